/* Direct light by one light sample: the next-event estimate of the path tracer (with MIS)
 * and of the Whitted, photon-mapping and SPPM integrators (without). */
#ifndef CST_INTEGRATORS_DIRECT_H
#define CST_INTEGRATORS_DIRECT_H

#include <stdint.h>

#include "materials/bsdf.h"
#include "scene/scene.h"

/* Veach's power heuristic, beta = 2 (thesis eq. 9.13). */
static inline float power_heuristic(float pdf_a, float pdf_b)
{
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a / (a + b);
}

/* f(wo, wi) L_i / pdf for one light picked by the scene's NEE sampler (light_sample_nee:
 * power, BVH or uniform; area point or delta light) with u_sel, the point on it with u,
 * and a shadow ray; black when the scene has no lights.
 * The caller draws the numbers (from its Sampler). wl: the path's wavelengths (spectral
 * mode) or NULL. */
Color direct_light(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel, Vec2 u,
                 const Wavelengths *wl, uint64_t *rays);
/* The same weighted by the power heuristic against BSDF sampling of the same direction
 * (path.c's MIS; a delta light keeps weight 1: BSDF sampling cannot reach it). */
Color direct_light_mis(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                     Vec2 u, const Wavelengths *wl, uint64_t *rays);

#endif
