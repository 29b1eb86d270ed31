/* Axis-aligned bounding boxes and the slab test. An empty box has min = +inf, max = -inf. */
#ifndef CST_MATH_BBOX_H
#define CST_MATH_BBOX_H

#include <float.h>
#include <stdbool.h>
#include <xmmintrin.h>

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

/* Reciprocal direction for the BVH's SIMD slab test, in lanes 0-2 of an SSE vector (lane
 * 3 is whatever 1 / d[3] is). A component smaller than 1e-20 in magnitude becomes +-1e20
 * instead of up to inf, with the sign of the component (also of a zero), so (bound -
 * origin) * inv is finite or 0, never NaN (Embree's rcp_safe does the same). A ray lying
 * exactly in a face plane would then leave the slab at t = 0; the BVH widens its boxes so
 * that case cannot arise (see bvh.c, widen()). One correctly rounded division for the
 * three lanes and no branch: it is part of every ray's set-up. */
static inline __m128 ray_inv_dir4(__m128 d)
{
    const __m128 sign = _mm_set1_ps(-0.0f), tiny = _mm_set1_ps(1e-20f);
    const __m128 small = _mm_cmplt_ps(_mm_andnot_ps(sign, d), tiny);
    const __m128 s = _mm_or_ps(_mm_and_ps(small, _mm_or_ps(_mm_and_ps(d, sign), tiny)), _mm_andnot_ps(small, d));
    return _mm_div_ps(_mm_set1_ps(1.0f), s);
}

/* The factor on a slab test's exit distance that keeps rounding from making a grazed box
 * look missed (Ize, "Robust BVH Ray Traversal", JCGT 2013; pbrt-v4 section 6.8.2), for
 * t_min >= 0. With u = 2^-24, an entry distance (plane - o) * fl(1 / d) is computed with
 * three roundings, so at most (1 + u)^3 times the exact one; an exit distance with the
 * factor folded into the reciprocal, fl(fl(1 / d) * w), has four, at least (1 - u)^4 times
 * w times the exact one, and t_max * w rounds once. Entry <= exit then needs w >= (1 + u)^3
 * / (1 - u)^4, about 1 + 7u: 1 + 8u, the next float. (pbrt's 1 + 2 gamma(3) written as
 * the literal 1.00000024f is 1 + 4u, too little.) */
#define BBOX_EXIT_WIDEN 0x1.000008p0f

/* Slab test (Kay & Kajiya 1986) with exact handling of zero direction components: such
 * an axis constrains nothing if the origin lies within the slab (boundary included) and
 * rejects otherwise. t_far is scaled by BBOX_EXIT_WIDEN. Origins inside the box give
 * t_enter = t_min. The BVH uses a branch-free SIMD form of the same test. */
static inline bool bbox_intersect(BBox b, Vec3 o, Vec3 d, float t_min, float t_max, float *t_enter)
{
    float tn = t_min, tf = t_max;
    for (int axis = 0; axis < 3; axis++) {
        float oa = v3_get(o, axis), da = v3_get(d, axis);
        float lo = v3_get(b.min, axis), hi = v3_get(b.max, axis);
        if (da == 0.0f) {
            if (oa < lo || oa > hi) return false;
            continue;
        }
        float inv = 1.0f / da;
        float t0 = (lo - oa) * inv, t1 = (hi - oa) * inv;
        if (t0 > t1) { float t = t0; t0 = t1; t1 = t; }
        tn = t0 > tn ? t0 : tn;
        tf = t1 < tf ? t1 : tf;
    }
    *t_enter = tn;
    return tn <= tf * BBOX_EXIT_WIDEN;
}

#endif
