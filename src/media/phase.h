/* The Henyey–Greenstein phase function (Henyey & Greenstein 1941): eval, sample, pdf.
 * Conventions (pbrt-v4's HGPhaseFunction): wo and wi both point away from the scattering
 * point (wo toward where the light goes, i.e. back along the path, as for BSDFs); g in
 * (-1, 1) is the mean cosine between the propagation directions -wo and wi, so g > 0
 * scatters forward (wi near -wo). p(wo, wi) is per unit solid angle and integrates to 1,
 * so eval = pdf (HG is sampled exactly). */
#ifndef CST_MEDIA_PHASE_H
#define CST_MEDIA_PHASE_H

#include <math.h>

#include "math/frame.h"
#include "math/vec3.h"

#define PHASE_INV_4PI 0.0795774715459476679f

/* HG in terms of cos_theta = dot(wo, wi) (pbrt-v4's argument): 1/(4 pi) (1 - g^2) /
 * (1 + g^2 + 2 g cos_theta)^(3/2); per steradian. */
static inline float phase_hg(float cos_theta, float g)
{
    float denom = 1.0f + g * g + 2.0f * g * cos_theta;
    if (!(denom > 0.0f)) return 0.0f;
    return PHASE_INV_4PI * (1.0f - g * g) / (denom * sqrtf(denom));
}

/* p(wo, wi), per steradian; also the pdf of phase_hg_sample. */
static inline float phase_hg_eval(Vec3 wo, Vec3 wi, float g) { return phase_hg(v3_dot(wo, wi), g); }
static inline float phase_hg_pdf(Vec3 wo, Vec3 wi, float g) { return phase_hg(v3_dot(wo, wi), g); }

/* wi distributed as p(wo, .) from u in [0,1)^2; *pdf_w = p(wo, wi). Inverts the CDF of
 * mu = cos(-wo, wi): mu = (1 + g^2 - ((1 - g^2) / (1 - g + 2 g u))^2) / (2 g) (the HG
 * CDF solved for mu; isotropic below |g| = 1e-3, where that form loses precision). */
static inline Vec3 phase_hg_sample(Vec3 wo, float g, float u0, float u1, float *pdf_w)
{
    float mu;
    if (fabsf(g) < 1e-3f) {
        mu = 1.0f - 2.0f * u0;
    } else {
        float q = (1.0f - g * g) / (1.0f - g + 2.0f * g * u0);
        mu = (1.0f + g * g - q * q) / (2.0f * g);
    }
    mu = fminf(fmaxf(mu, -1.0f), 1.0f);
    float sin_t = sqrtf(fmaxf(0.0f, 1.0f - mu * mu));
    float phi = 6.28318530717958648f * u1;
    Frame f = frame_from_normal(v3_neg(wo)); /* z = the propagation direction */
    Vec3 wi = frame_to_world(&f, v3(sin_t * cosf(phi), sin_t * sinf(phi), mu));
    *pdf_w = phase_hg(-mu, g);
    return wi;
}

#endif
