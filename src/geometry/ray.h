/* Rays: origin, normalised direction, a parametric interval [t_min, t_max] and the time of
 * the ray within the shutter interval (motion blur). */
#ifndef CST_GEOMETRY_RAY_H
#define CST_GEOMETRY_RAY_H

#include <emmintrin.h>
#include <stdint.h>

#include "math/vec3.h"

typedef struct Ray {
    Vec3 o;
    float t_min;
    Vec3 d;
    float t_max;
    /* The ray's time in [0, 1): 0 at shutter open, 1 at close. Every ray of a path carries
     * its path's time (moving instances are placed at it, accel/instances.c); 0 in scenes
     * without motion, which never read it. Last, so the 32 bytes the traversals read come
     * first (sizeof(Ray) is 36). */
    float time;
} Ray;

static inline Ray ray_make(Vec3 o, Vec3 d, float t_min, float t_max)
{
    Ray r;
    r.o = o; r.d = d; r.t_min = t_min; r.t_max = t_max; r.time = 0.0f;
    return r;
}

/* ray_make at a path's time. */
static inline Ray ray_make_at(Vec3 o, Vec3 d, float t_min, float t_max, float time)
{
    Ray r = ray_make(o, d, t_min, t_max);
    r.time = time;
    return r;
}

static inline Vec3 ray_at(const Ray *r, float t) { return v3_madd(r->o, r->d, t); }

/* The absolute offset near the origin of Ray Tracing Gems (below): the smallest
 * ray_offset_origin uses. Scenes pass a larger one when their size calls for it
 * (scene.h: Scene.offset_near). */
#define RAY_OFFSET_NEAR_MIN (1.0f / 65536.0f)

/* Moves a surface point off its surface along n (oriented to the side the new ray
 * leaves on) far enough that the new ray cannot re-hit the surface, by a fixed number of
 * ulps of each coordinate, so the offset scales with the point's own float precision
 * rather than with the scene: Waechter & Binder, "A Fast and Robust Method for Avoiding
 * Self-Intersection", Ray Tracing Gems ch. 6, 2019. Near the origin, where ulps vanish,
 * an absolute offset `near` takes over, below |p| < 2048 near (their 2^-16 and 1/32 for
 * near = RAY_OFFSET_NEAR_MIN). Hit points must be accurate to a few ulps for this to hold:
 * they are computed from barycentrics (triangles) or reprojected (spheres). */
static inline float ray_offset_coord(float p, float n, float near)
{
    const float INT_SCALE = 256.0f;
    if (fabsf(p) < 2048.0f * near) return p + near * n;
    union { float f; int32_t i; } u = {p};
    int32_t of = (int32_t)(INT_SCALE * n);
    u.i += (p < 0.0f) ? -of : of;
    return u.f;
}

/* ray_offset_coord on the three coordinates at once (SSE2), the same operations lane by
 * lane, so the same bits: every shadow ray and every bounce offsets one or two points,
 * and the scalar version's three data-dependent branches were a visible part of the
 * bidirectional integrators' instructions (docs/benchmarks.md). */
static inline Vec3 ray_offset_origin(Vec3 p, Vec3 n, float near)
{
    const __m128 P = _mm_set_ps(0.0f, p.z, p.y, p.x), N = _mm_set_ps(0.0f, n.z, n.y, n.x);
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 near_origin = _mm_cmplt_ps(_mm_and_ps(P, abs_mask), _mm_set1_ps(2048.0f * near));
    const __m128 by_float = _mm_add_ps(P, _mm_mul_ps(_mm_set1_ps(near), N));
    const __m128i of = _mm_cvttps_epi32(_mm_mul_ps(_mm_set1_ps(256.0f), N));
    const __m128i neg = _mm_castps_si128(_mm_cmplt_ps(P, _mm_setzero_ps()));
    const __m128i signed_of = _mm_sub_epi32(_mm_xor_si128(of, neg), neg); /* -of where p < 0 */
    const __m128 by_int = _mm_castsi128_ps(_mm_add_epi32(_mm_castps_si128(P), signed_of));
    const __m128 r = _mm_or_ps(_mm_and_ps(near_origin, by_float), _mm_andnot_ps(near_origin, by_int));
    float out[4];
    _mm_storeu_ps(out, r);
    return v3(out[0], out[1], out[2]);
}

#endif
