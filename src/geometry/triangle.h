/* Ray-triangle intersection (Moller & Trumbore, "Fast, Minimum Storage Ray/Triangle
 * Intersection", JGT 1997) on precomputed (v0, e1 = v1 - v0, e2 = v2 - v0). */
#ifndef CST_GEOMETRY_TRIANGLE_H
#define CST_GEOMETRY_TRIANGLE_H

#include <stdbool.h>

#include "geometry/ray.h"

/* Two-sided test. On a hit in (t_min, t_max) writes t and the barycentrics (u, v) of v1
 * and v2. A ray parallel to the plane (det == 0) never hits, including rays lying in the
 * plane: such grazing hits have no well-defined t and are left to the neighbours. */
static inline bool triangle_intersect(Vec3 v0, Vec3 e1, Vec3 e2, const Ray *r,
                                      float *t_out, float *u_out, float *v_out)
{
    Vec3 p = v3_cross(r->d, e2);
    float det = v3_dot(e1, p);
    if (det == 0.0f) return false;
    float inv_det = 1.0f / det;
    Vec3 s = v3_sub(r->o, v0);
    float u = v3_dot(s, p) * inv_det;
    if (u < 0.0f || u > 1.0f) return false;
    Vec3 q = v3_cross(s, e1);
    float v = v3_dot(r->d, q) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return false;
    float t = v3_dot(e2, q) * inv_det;
    if (!(t > r->t_min && t < r->t_max)) return false;
    *t_out = t; *u_out = u; *v_out = v;
    return true;
}

#endif
