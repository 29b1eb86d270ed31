/* Axis-aligned bounding boxes and the slab test. An empty box has min = +inf, max = -inf. */
#ifndef CST_MATH_BBOX_H
#define CST_MATH_BBOX_H

#include <float.h>
#include <stdbool.h>

#include "math/vec3.h"

typedef struct BBox { Vec3 min, max; } BBox;

static inline BBox bbox_empty(void)
{
    BBox b = {v3s(FLT_MAX), v3s(-FLT_MAX)};
    return b;
}
static inline BBox bbox_union(BBox a, BBox b) { BBox r = {v3_min(a.min, b.min), v3_max(a.max, b.max)}; return r; }
static inline BBox bbox_add(BBox a, Vec3 p) { BBox r = {v3_min(a.min, p), v3_max(a.max, p)}; return r; }
static inline Vec3 bbox_center(BBox b) { return v3_scale(v3_add(b.min, b.max), 0.5f); }
static inline float bbox_area(BBox b)
{
    Vec3 d = v3_sub(b.max, b.min);
    if (d.x < 0.0f || d.y < 0.0f || d.z < 0.0f) return 0.0f;
    return 2.0f * (d.x * d.y + d.y * d.z + d.z * d.x);
}

/* Reciprocal direction for slab tests. A zero component becomes +-1e20-ish instead of
 * inf, so (bound - origin) * inv is 0 (not NaN) for an origin on a slab plane: a ray in
 * that plane then counts as inside the slab (Embree's rcp_safe does the same). */
static inline Vec3 ray_inv_dir(Vec3 d)
{
    const float tiny = 1e-20f;
    Vec3 s = v3(fabsf(d.x) < tiny ? copysignf(tiny, d.x) : d.x,
                fabsf(d.y) < tiny ? copysignf(tiny, d.y) : d.y,
                fabsf(d.z) < tiny ? copysignf(tiny, d.z) : d.z);
    return v3(1.0f / s.x, 1.0f / s.y, 1.0f / s.z);
}

/* Robust slab test: t_far is scaled by 1 + 2*gamma(3) so rounding can never make a
 * box that the ray grazes look missed (Ize, "Robust BVH Ray Traversal", JCGT 2013).
 * Works for origins inside the box (t_near clamps to t_min). */
static inline bool bbox_intersect(BBox b, Vec3 o, Vec3 inv_d, float t_min, float t_max,
                                  float *t_enter)
{
    float tx0 = (b.min.x - o.x) * inv_d.x, tx1 = (b.max.x - o.x) * inv_d.x;
    float ty0 = (b.min.y - o.y) * inv_d.y, ty1 = (b.max.y - o.y) * inv_d.y;
    float tz0 = (b.min.z - o.z) * inv_d.z, tz1 = (b.max.z - o.z) * inv_d.z;
    float tn = maxf(maxf(minf(tx0, tx1), minf(ty0, ty1)), maxf(minf(tz0, tz1), t_min));
    float tf = minf(minf(maxf(tx0, tx1), maxf(ty0, ty1)), minf(maxf(tz0, tz1), t_max));
    tf *= 1.00000024f; /* 1 + 2 * gamma(3), gamma(n) = n eps / (1 - n eps), eps = 2^-24 */
    *t_enter = tn;
    return tn <= tf;
}

#endif
