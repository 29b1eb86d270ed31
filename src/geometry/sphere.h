/* Spheres and a numerically robust ray-sphere test (Haines et al., "Precision
 * Improvements for Ray/Sphere Intersection", Ray Tracing Gems, ch. 7, 2019). */
#ifndef CST_GEOMETRY_SPHERE_H
#define CST_GEOMETRY_SPHERE_H

#include <stdbool.h>

#include "geometry/ray.h"

typedef struct Sphere {
    Vec3 center;
    float radius;
} Sphere;

/* Nearest root in (t_min, t_max); the ray direction must be normalised. Origins inside
 * the sphere hit the far side. The discriminant is computed as r^2 - |f - (f.d) d|^2
 * (RTG eq. 7.5), which stays accurate for spheres small relative to their distance,
 * and the roots use the stable form q = -b - sign(b) sqrt(disc) (eq. 7.6). */
static inline bool sphere_intersect(Vec3 center, float radius, const Ray *r, float *t_out)
{
    Vec3 f = v3_sub(r->o, center);
    float b = v3_dot(f, r->d); /* half of the usual b, with a = 1 */
    Vec3 perp = v3_madd(f, r->d, -b);
    float r2 = radius * radius;
    float disc = r2 - v3_dot(perp, perp);
    if (disc < 0.0f) return false;
    float c = v3_dot(f, f) - r2;
    float q = -b - copysignf(sqrtf(disc), b);
    float t0, t1;
    if (q == 0.0f) { t0 = t1 = 0.0f; }
    else { t0 = c / q; t1 = q; }
    if (t0 > t1) { float tmp = t0; t0 = t1; t1 = tmp; }
    if (t0 > r->t_min && t0 < r->t_max) { *t_out = t0; return true; }
    if (t1 > r->t_min && t1 < r->t_max) { *t_out = t1; return true; }
    return false;
}

/* Texture coordinates of the point in unit direction d from a sphere's centre: u = phi / 2pi
 * with phi the angle about +y from +z toward +x, v = theta / pi with theta the angle from
 * -y, so v runs from 0 at the bottom pole to 1 at the top (an equirectangular image with
 * its top row at +y, as image textures put v = 1 at the top row). */
static inline Vec2 sphere_uv(Vec3 d)
{
    float phi = atan2f(d.x, d.z);
    if (phi < 0.0f) phi += 2.0f * CST_PI;
    float theta = acosf(clampf(-d.y, -1.0f, 1.0f));
    return v2(phi * (0.5f * CST_INV_PI), theta * CST_INV_PI);
}

#endif
