/* Rays: origin, normalised direction and a parametric interval [t_min, t_max]. */
#ifndef CST_GEOMETRY_RAY_H
#define CST_GEOMETRY_RAY_H

#include <stdint.h>

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

/* Moves a surface point off its surface along n (oriented to the side the new ray
 * leaves on) far enough that the new ray cannot re-hit the surface, by a fixed number of
 * ulps of each coordinate, so the offset scales with the point's own float precision
 * rather than with the scene: Waechter & Binder, "A Fast and Robust Method for Avoiding
 * Self-Intersection", Ray Tracing Gems ch. 6, 2019. Near the origin, where ulps vanish,
 * a small absolute offset takes over. Hit points must be accurate to a few ulps for this
 * to hold: they are computed from barycentrics (triangles) or reprojected (spheres). */
static inline float ray_offset_coord(float p, float n)
{
    const float ORIGIN = 1.0f / 32.0f, FLOAT_SCALE = 1.0f / 65536.0f, INT_SCALE = 256.0f;
    if (fabsf(p) < ORIGIN) return p + FLOAT_SCALE * n;
    union { float f; int32_t i; } u = {p};
    int32_t of = (int32_t)(INT_SCALE * n);
    u.i += (p < 0.0f) ? -of : of;
    return u.f;
}

static inline Vec3 ray_offset_origin(Vec3 p, Vec3 n)
{
    return v3(ray_offset_coord(p.x, n.x), ray_offset_coord(p.y, n.y), ray_offset_coord(p.z, n.z));
}

#endif
