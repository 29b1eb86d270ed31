/* Rays: origin, normalised direction and a parametric interval [t_min, t_max]. */
#ifndef CST_GEOMETRY_RAY_H
#define CST_GEOMETRY_RAY_H

#include "math/vec3.h"

typedef struct Ray {
    Vec3 o;
    float t_min;
    Vec3 d;
    float t_max;
} Ray;

static inline Ray ray_make(Vec3 o, Vec3 d, float t_min, float t_max)
{
    Ray r;
    r.o = o; r.d = d; r.t_min = t_min; r.t_max = t_max;
    return r;
}

static inline Vec3 ray_at(const Ray *r, float t) { return v3_madd(r->o, r->d, t); }

#endif
