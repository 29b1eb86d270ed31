/* Named conductor presets and the derived data of materials (the rough plastic's coat
 * albedo table). */
#include "materials/material.h"

#include <string.h>

#include "materials/fresnel.h"
#include "materials/microfacet.h"

/* Complex IOR (n, k) sampled at about 650, 550 and 450 nm for the R, G and B channels: a
 * point sample per channel, not an integral against the sRGB matching functions, which is
 * the usual RGB-renderer simplification (the hue is right, saturation can differ a bit).
 * Sources, as tabulated on refractiveindex.info:
 *   gold, silver: P. B. Johnson & R. W. Christy, Phys. Rev. B 6, 4370 (1972), the table's
 *     photon energies 1.88, 2.26 and 2.75 eV (659, 549, 451 nm);
 *   copper: H.-J. Hagemann, W. Gudat & C. Kunz, DESY report SR-74/7 (1974), table 3, at
 *     652.5 nm, 550 nm (linear between 539.1 and 563.6 nm) and 442.8 nm;
 *   aluminium: A. D. Rakic, Appl. Opt. 34, 4755 (1995), at 650, 550 and 450 nm.
 * Checked against the tables (2026-11-22): gold and silver are the Johnson & Christy rows at
 * 659.5, 548.6 and 450.9 nm exactly, copper Hagemann's rows; aluminium agrees within 4% with
 * the Drude-Lorentz fit of Rakic et al., Appl. Opt. 37, 5271 (1998), at those wavelengths.
 * Normal-incidence reflectance ((n-1)^2 + k^2) / ((n+1)^2 + k^2) gives gold (0.96, 0.79,
 * 0.41), silver (0.99, 0.98, 0.98), copper (0.94, 0.64, 0.55), aluminium (0.91, 0.92, 0.93). */
typedef struct MetalPreset { const char *name; Color eta, k; } MetalPreset;
static const MetalPreset METALS[] = {
    {"gold", {{0.14f, 0.43f, 1.38f}}, {{3.697f, 2.455f, 1.914f}}},
    {"silver", {{0.05f, 0.06f, 0.04f}}, {{4.483f, 3.586f, 2.657f}}},
    {"copper", {{0.214f, 0.943f, 1.169f}}, {{3.67f, 2.594f, 2.36f}}},
    {"aluminium", {{1.47f, 0.958f, 0.618f}}, {{7.79f, 6.69f, 5.47f}}},
};
const char *const material_metal_names[] = {"gold", "silver", "copper", "aluminium", NULL};

bool material_metal(const char *name, Color *eta, Color *k)
{
    for (size_t i = 0; i < sizeof METALS / sizeof METALS[0]; i++)
        if (strcmp(name, METALS[i].name) == 0) {
            *eta = METALS[i].eta;
            *k = METALS[i].k;
            return true;
        }
    return false;
}

/* Directional albedo of the GGX dielectric coat's reflection at cos_o = mu:
 *   E(mu) = int f_coat(wo, wi) cos_i dwi = E_{m ~ D_wo}[F(wo.m) G2(wo, wi) / G1(wo)]
 * (visible-normal sampling makes the integrand D-free), by a midpoint rule on an n x n
 * grid of the sampler's unit square: deterministic, and smooth enough in u that 64^2
 * points give ~1e-4 (test_bsdf.c measures the table against Monte Carlo). */
static float coat_albedo_quadrature(float mu, float alpha, float eta, int n)
{
    Vec3 wo = v3(safe_sqrtf(1.0f - mu * mu), 0.0f, mu);
    double sum = 0.0;
    float g1 = ggx_g1(wo, alpha);
    for (int i = 0; i < n; i++)
        for (int j = 0; j < n; j++) {
            Vec2 u = v2(((float)i + 0.5f) / (float)n, ((float)j + 0.5f) / (float)n);
            Vec3 m = ggx_sample_visible(wo, alpha, u);
            Vec3 wi = reflect_about(wo, m);
            if (wi.z <= 0.0f) continue;
            sum += (double)(fresnel_dielectric(v3_dot(wo, m), eta) * ggx_g2(wo, wi, alpha) / g1);
        }
    return (float)(sum / ((double)n * (double)n));
}

void material_prepare(Material *m)
{
    m->prepared = true;
    m->coat_e_avg = 0.0f;
    float alpha = material_alpha(m->roughness);
    if (m->type != MATERIAL_PLASTIC || alpha < MATERIAL_SMOOTH_ALPHA) return;
    const int N = MATERIAL_COAT_TABLE;
    for (int j = 0; j < N; j++) {
        /* Nodes at mu = x^2, x uniform: E changes fastest at grazing. mu = 0 is a limit
         * (G1 = 0); sample just above it. */
        float x = (float)j / (float)(N - 1);
        m->coat_e[j] = coat_albedo_quadrature(maxf(x * x, 1e-4f), alpha, m->ior, 64);
    }
    /* E_avg = 2 int_0^1 E(mu) mu dmu = 4 int_0^1 E(x) x^3 dx of the piecewise-linear E(x)
     * that bsdf.c evaluates, exactly (3-point Gauss-Legendre is exact for the degree-4
     * integrand on each piece), so the diffuse normalisation matches the table and the
     * albedo identity E + rho (1 - E) holds. */
    static const double GX[3] = {-0.7745966692414834, 0.0, 0.7745966692414834};
    static const double GW[3] = {5.0 / 9.0, 8.0 / 9.0, 5.0 / 9.0};
    double avg = 0.0, h = 1.0 / (double)(N - 1);
    for (int j = 0; j + 1 < N; j++) {
        double e0 = (double)m->coat_e[j], e1 = (double)m->coat_e[j + 1];
        for (int q = 0; q < 3; q++) {
            double t = 0.5 * (1.0 + GX[q]), x = ((double)j + t) * h;
            avg += 0.5 * h * GW[q] * 4.0 * (e0 + t * (e1 - e0)) * x * x * x;
        }
    }
    m->coat_e_avg = (float)avg;
}
