/* Warps from [0,1)^2 to common domains. Every warp_X has its warp_X_pdf beside it, with
 * the measure stated; tests/unit/test_warp.c checks each pair with a chi-square test. */
#ifndef CST_SAMPLING_WARP_H
#define CST_SAMPLING_WARP_H

#include <stdbool.h>

#include "math/vec3.h"

/* cos and sin of |x| <= pi/4 by their Taylor polynomials to x^8 and x^9: the first terms
 * left out are below 3e-8 there, under float's half-ulp of 1, and the polynomials cost a
 * fraction of libm's sincosf with its range reduction (perf: 5% of the light tracer). */
static inline void warp_sincos_quarter(float x, float *s, float *c)
{
    float x2 = x * x;
    *s = x * (1.0f + x2 * (-1.0f / 6.0f + x2 * (1.0f / 120.0f + x2 * (-1.0f / 5040.0f + x2 * (1.0f / 362880.0f)))));
    *c = 1.0f + x2 * (-0.5f + x2 * (1.0f / 24.0f + x2 * (-1.0f / 720.0f + x2 * (1.0f / 40320.0f))));
}

/* Shirley & Chiu's concentric map, unit disk; pdf w.r.t. area = 1/pi. The angle of each
 * wedge is pi/4 times a ratio in [-1, 1]; the second pair of wedges, at pi/2 - phi, swaps
 * sine and cosine, so only angles within pi/4 of zero are ever evaluated. */
static inline Vec2 warp_concentric_disk(Vec2 u)
{
    float ox = 2.0f * u.x - 1.0f, oy = 2.0f * u.y - 1.0f;
    if (ox == 0.0f && oy == 0.0f) return v2(0.0f, 0.0f);
    /* The wedge by selects, not a branch: which of |ox|, |oy| is larger is a coin flip
     * for every sample, and the mispredictions showed in the light tracer's profile.
     * The same operations as the two branches, so the same bits. */
    const bool x_wedge = fabsf(ox) > fabsf(oy);
    const float r = x_wedge ? ox : oy, q = x_wedge ? oy : ox;
    float s, c;
    warp_sincos_quarter((CST_PI / 4.0f) * (q / r), &s, &c);
    return x_wedge ? v2(r * c, r * s) : v2(r * s, r * c);
}
static inline float warp_concentric_disk_pdf(Vec2 p) { return (p.x * p.x + p.y * p.y <= 1.0f) ? CST_INV_PI : 0.0f; }

/* Cosine-weighted hemisphere around +z (Malley's method); pdf w.r.t. solid angle = cos/pi. */
static inline Vec3 warp_cosine_hemisphere(Vec2 u)
{
    Vec2 d = warp_concentric_disk(u);
    float z = safe_sqrtf(1.0f - d.x * d.x - d.y * d.y);
    return v3(d.x, d.y, z);
}
static inline float warp_cosine_hemisphere_pdf(Vec3 w) { return w.z > 0.0f ? w.z * CST_INV_PI : 0.0f; }

/* Uniform hemisphere around +z; pdf w.r.t. solid angle = 1/(2 pi). */
static inline Vec3 warp_uniform_hemisphere(Vec2 u)
{
    float z = u.x;
    float r = safe_sqrtf(1.0f - z * z);
    float phi = 2.0f * CST_PI * u.y;
    return v3(r * cosf(phi), r * sinf(phi), z);
}
static inline float warp_uniform_hemisphere_pdf(Vec3 w) { return w.z >= 0.0f ? CST_INV_2PI : 0.0f; }

/* Uniform unit sphere; pdf w.r.t. solid angle = 1/(4 pi). */
static inline Vec3 warp_uniform_sphere(Vec2 u)
{
    float z = 1.0f - 2.0f * u.x;
    float r = safe_sqrtf(1.0f - z * z);
    float phi = 2.0f * CST_PI * u.y;
    return v3(r * cosf(phi), r * sinf(phi), z);
}
static inline float warp_uniform_sphere_pdf(Vec3 w) { (void)w; return CST_INV_4PI; }

/* Uniform direction in the cone of directions within angle acos(cos_max) of +z (pbrt-v4
 * SampleUniformCone): cos theta uniform in [cos_max, 1]. */
static inline Vec3 warp_uniform_cone(Vec2 u, float cos_max)
{
    float c = (1.0f - u.x) + u.x * cos_max;
    float s = sqrtf(fmaxf(0.0f, 1.0f - c * c));
    float phi = 2.0f * CST_PI * u.y;
    return v3(cosf(phi) * s, sinf(phi) * s, c);
}
static inline float warp_uniform_cone_pdf(float cos_max) { return 1.0f / (2.0f * CST_PI * (1.0f - cos_max)); }

/* Uniform point on a triangle as barycentrics (b1, b2) with b0 = 1 - b1 - b2
 * (the square-root parameterisation of Osada et al., "Shape Distributions", 2002, sec. 4.2).
 * pdf w.r.t. the barycentric domain's area = 2. */
static inline Vec2 warp_uniform_triangle(Vec2 u)
{
    float su = sqrtf(u.x);
    return v2(1.0f - su, u.y * su);
}
static inline float warp_uniform_triangle_pdf(Vec2 b) { return (b.x >= 0.0f && b.y >= 0.0f && b.x + b.y <= 1.0f) ? 2.0f : 0.0f; }

/* Tent on [-1, 1] by inverting its CDF; pdf(x) = 1 - |x|. */
static inline float warp_tent(float u)
{
    if (u < 0.5f) return sqrtf(2.0f * u) - 1.0f;
    return 1.0f - sqrtf(2.0f - 2.0f * u);
}
static inline float warp_tent_pdf(float x) { return fabsf(x) <= 1.0f ? 1.0f - fabsf(x) : 0.0f; }

#endif
