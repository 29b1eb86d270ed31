/* Fresnel equations: dielectric, complex-IOR conductor, and the diffuse (hemispherical)
 * average of the dielectric reflectance. */
#include "materials/fresnel.h"

#include "math/vec3.h"

/* Exact Fresnel equations for unpolarised light (pbrt-v4 eq. 9.4-9.5, averaged). */
float fresnel_dielectric(float cos_i, float eta)
{
    cos_i = clampf(cos_i, -1.0f, 1.0f);
    if (cos_i < 0.0f) { eta = 1.0f / eta; cos_i = -cos_i; }
    float sin2_i = 1.0f - cos_i * cos_i;
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f; /* total internal reflection */
    float cos_t = safe_sqrtf(1.0f - sin2_t);
    float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_par * r_par + r_perp * r_perp);
}

/* The Fresnel equations with a complex refracted angle, written in real arithmetic (Born &
 * Wolf, Principles of Optics, sec. 14.2; the form of S. Lagarde, "Memo on Fresnel
 * equations", 2013): with a^2 + b^2 = sqrt((n^2 - k^2 - sin^2)^2 + 4 n^2 k^2) and
 * a^2 = (a^2 + b^2 + n^2 - k^2 - sin^2) / 2,
 *   R_s = (a^2 + b^2 - 2 a cos + cos^2) / (a^2 + b^2 + 2 a cos + cos^2)
 *   R_p = R_s (cos^2 (a^2 + b^2) - 2 a cos sin^2 + sin^4) / (cos^2 (a^2 + b^2) + 2 a cos sin^2 + sin^4)
 * and R = (R_s + R_p) / 2. tests/unit/test_bsdf.c checks it against complex arithmetic. */
float fresnel_conductor(float cos_i, float eta, float k)
{
    float c = clampf(fabsf(cos_i), 0.0f, 1.0f);
    float c2 = c * c, s2 = 1.0f - c2;
    float t0 = eta * eta - k * k - s2;
    float a2b2 = sqrtf(t0 * t0 + 4.0f * eta * eta * k * k);
    float a = safe_sqrtf(0.5f * (a2b2 + t0));
    float rs = (a2b2 - 2.0f * a * c + c2) / (a2b2 + 2.0f * a * c + c2);
    float t1 = c2 * a2b2 + s2 * s2, t2 = 2.0f * a * c * s2;
    float rp = rs * (t1 - t2) / (t1 + t2);
    float r = 0.5f * (rs + rp);
    return r == r ? r : 1.0f; /* 0/0 only at grazing incidence on k = 0, where R = 1 */
}

Color fresnel_conductor_rgb(float cos_i, Color eta, Color k)
{
    /* Every lane: in spectral mode lane 3 is a fourth wavelength (color.h). */
    Color r;
    for (int i = 0; i < COLOR_LANES; i++) r.c[i] = fresnel_conductor(cos_i, eta.c[i], k.c[i]);
    return r;
}

/* 2 int_0^1 F(mu) mu dmu for unpolarised light entering a medium of relative IOR n > 1:
 * the Fresnel equations integrate in elementary functions; this is the classical result
 * (it goes back to Stokes' work on piles of plates). Rather than trust a transcription,
 * test_bsdf.c checks it against quadrature to 1e-6 for n from 1.01 to 4. In double: the
 * terms cancel heavily as n -> 1. */
float fresnel_diffuse_reflectance(float eta_f)
{
    double n = (double)eta_f;
    if (!(n > 1.0 + 1e-6)) return 0.0f; /* no interface, no reflection */
    double n2 = n * n, n4 = n2 * n2;
    double r = 0.5 + (n - 1.0) * (3.0 * n + 1.0) / (6.0 * (n + 1.0) * (n + 1.0)) +
               n2 * (n2 - 1.0) * (n2 - 1.0) / ((n2 + 1.0) * (n2 + 1.0) * (n2 + 1.0)) * log((n - 1.0) / (n + 1.0)) -
               2.0 * n * n2 * (n2 + 2.0 * n - 1.0) / ((n2 + 1.0) * (n4 - 1.0)) +
               8.0 * n4 * (n4 + 1.0) / ((n2 + 1.0) * (n4 - 1.0) * (n4 - 1.0)) * log(n);
    return (float)r;
}
