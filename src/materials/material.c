/* Named conductor presets and the derived data of materials (the rough plastic's coat
 * albedo table). */
#include "materials/material.h"

#include <immintrin.h>
#include <math.h>
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
/* Lane 3 repeats green, as color_rgb() makes it (math/color.h). */
typedef struct MetalPreset { const char *name; Color eta, k; } MetalPreset;
static const MetalPreset METALS[] = {
    {"gold", {{0.14f, 0.43f, 1.38f, 0.43f}}, {{3.697f, 2.455f, 1.914f, 2.455f}}},
    {"silver", {{0.05f, 0.06f, 0.04f, 0.06f}}, {{4.483f, 3.586f, 2.657f, 3.586f}}},
    {"copper", {{0.214f, 0.943f, 1.169f, 0.943f}}, {{3.67f, 2.594f, 2.36f, 2.594f}}},
    {"aluminium", {{1.47f, 0.958f, 0.618f, 0.958f}}, {{7.79f, 6.69f, 5.47f, 6.69f}}},
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
 * points give ~1e-4 (test_bsdf.c measures the table against Monte Carlo).
 *
 * Speed (issue 25: a scene of 1,000 rough plastics spent 13 s of CPU here): the grid's
 * disk points (p1, p2) = sqrt(u.x) (cos, sin)(2 pi u.y) do not depend on the material, so
 * the 64 cosines and sines are taken once per call instead of once per point, and the
 * points are evaluated COAT_LANES at a time with SSE/AVX. Every lane performs exactly the
 * float operations of ggx_sample_visible(), reflect_about(), fresnel_dielectric() and
 * ggx_g2() in the same order (+, -, *, / and sqrt are correctly rounded in SIMD as in
 * scalar code; -ffp-contract=off keeps them unfused; selects reproduce the branches), and
 * the terms are summed in double in the original order, so the table is bit-identical to
 * the scalar loop it replaces (tests/unit/test_coat_quadrature.c compares it with a copy
 * of that loop; the render hashes are unchanged). */
#define COAT_N 64
#ifdef __AVX__
#define COAT_LANES 8
typedef __m256 CoatLanes;
static inline CoatLanes cl_set(float x) { return _mm256_set1_ps(x); }
static inline CoatLanes cl_load(const float *p) { return _mm256_loadu_ps(p); }
static inline void cl_store(float *p, CoatLanes a) { _mm256_storeu_ps(p, a); }
static inline CoatLanes cl_add(CoatLanes a, CoatLanes b) { return _mm256_add_ps(a, b); }
static inline CoatLanes cl_sub(CoatLanes a, CoatLanes b) { return _mm256_sub_ps(a, b); }
static inline CoatLanes cl_mul(CoatLanes a, CoatLanes b) { return _mm256_mul_ps(a, b); }
static inline CoatLanes cl_div(CoatLanes a, CoatLanes b) { return _mm256_div_ps(a, b); }
static inline CoatLanes cl_sqrt(CoatLanes a) { return _mm256_sqrt_ps(a); }
static inline CoatLanes cl_max(CoatLanes a, CoatLanes b) { return _mm256_max_ps(a, b); } /* a > b ? a : b */
static inline CoatLanes cl_lt(CoatLanes a, CoatLanes b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline CoatLanes cl_gt(CoatLanes a, CoatLanes b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline CoatLanes cl_ge(CoatLanes a, CoatLanes b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
static inline CoatLanes cl_eq(CoatLanes a, CoatLanes b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }
static inline CoatLanes cl_sel(CoatLanes m, CoatLanes a, CoatLanes b) { return _mm256_blendv_ps(b, a, m); }
static inline int cl_mask(CoatLanes a) { return _mm256_movemask_ps(a); }
#else
#define COAT_LANES 4
typedef __m128 CoatLanes;
static inline CoatLanes cl_set(float x) { return _mm_set1_ps(x); }
static inline CoatLanes cl_load(const float *p) { return _mm_loadu_ps(p); }
static inline void cl_store(float *p, CoatLanes a) { _mm_storeu_ps(p, a); }
static inline CoatLanes cl_add(CoatLanes a, CoatLanes b) { return _mm_add_ps(a, b); }
static inline CoatLanes cl_sub(CoatLanes a, CoatLanes b) { return _mm_sub_ps(a, b); }
static inline CoatLanes cl_mul(CoatLanes a, CoatLanes b) { return _mm_mul_ps(a, b); }
static inline CoatLanes cl_div(CoatLanes a, CoatLanes b) { return _mm_div_ps(a, b); }
static inline CoatLanes cl_sqrt(CoatLanes a) { return _mm_sqrt_ps(a); }
static inline CoatLanes cl_max(CoatLanes a, CoatLanes b) { return _mm_max_ps(a, b); } /* a > b ? a : b */
static inline CoatLanes cl_lt(CoatLanes a, CoatLanes b) { return _mm_cmplt_ps(a, b); }
static inline CoatLanes cl_gt(CoatLanes a, CoatLanes b) { return _mm_cmpgt_ps(a, b); }
static inline CoatLanes cl_ge(CoatLanes a, CoatLanes b) { return _mm_cmpge_ps(a, b); }
static inline CoatLanes cl_eq(CoatLanes a, CoatLanes b) { return _mm_cmpeq_ps(a, b); }
static inline CoatLanes cl_sel(CoatLanes m, CoatLanes a, CoatLanes b)
{
    return _mm_or_ps(_mm_and_ps(m, a), _mm_andnot_ps(m, b));
}
static inline int cl_mask(CoatLanes a) { return _mm_movemask_ps(a); }
#endif
_Static_assert(COAT_N % COAT_LANES == 0, "whole vectors per row of the grid");

/* safe_sqrtf, lane-wise. */
static inline CoatLanes cl_safe_sqrt(CoatLanes a) { return cl_sqrt(cl_max(a, cl_set(0.0f))); }

/* The cosines and sines of the grid's angles phi_j = 2 pi (j + 1/2) / n. */
typedef struct CoatGrid { float cos_phi[COAT_N], sin_phi[COAT_N]; } CoatGrid;

static void coat_grid_init(CoatGrid *g)
{
    for (int j = 0; j < COAT_N; j++) {
        float uy = ((float)j + 0.5f) / (float)COAT_N, phi = 2.0f * CST_PI * uy;
        g->cos_phi[j] = cosf(phi);
        g->sin_phi[j] = sinf(phi);
    }
}

/* ggx_lambda(wi) lane-wise (wi.z^2 == 0: infinity). */
static inline CoatLanes cl_lambda(CoatLanes x, CoatLanes y, CoatLanes z, float alpha)
{
    CoatLanes z2 = cl_mul(z, z);
    CoatLanes a2_tan2 = cl_div(cl_mul(cl_set(alpha * alpha), cl_add(cl_mul(x, x), cl_mul(y, y))), z2);
    CoatLanes lam = cl_mul(cl_set(0.5f), cl_sub(cl_sqrt(cl_add(cl_set(1.0f), a2_tan2)), cl_set(1.0f)));
    return cl_sel(cl_eq(z2, cl_set(0.0f)), cl_set(INFINITY), lam);
}

/* fresnel_dielectric(cos_i, eta) lane-wise. */
static inline CoatLanes cl_fresnel(CoatLanes cos_i, float eta_f)
{
    cos_i = cl_sel(cl_lt(cos_i, cl_set(-1.0f)), cl_set(-1.0f), cl_sel(cl_gt(cos_i, cl_set(1.0f)), cl_set(1.0f), cos_i));
    CoatLanes back = cl_lt(cos_i, cl_set(0.0f));
    CoatLanes eta = cl_sel(back, cl_set(1.0f / eta_f), cl_set(eta_f));
    cos_i = cl_sel(back, cl_sub(cl_set(0.0f), cos_i), cos_i); /* -x: the sign flipped, as in C */
    CoatLanes sin2_i = cl_sub(cl_set(1.0f), cl_mul(cos_i, cos_i));
    CoatLanes sin2_t = cl_div(sin2_i, cl_mul(eta, eta));
    CoatLanes cos_t = cl_safe_sqrt(cl_sub(cl_set(1.0f), sin2_t));
    CoatLanes ec = cl_mul(eta, cos_i), et = cl_mul(eta, cos_t);
    CoatLanes r_par = cl_div(cl_sub(ec, cos_t), cl_add(ec, cos_t));
    CoatLanes r_perp = cl_div(cl_sub(cos_i, et), cl_add(cos_i, et));
    CoatLanes f = cl_mul(cl_set(0.5f), cl_add(cl_mul(r_par, r_par), cl_mul(r_perp, r_perp)));
    return cl_sel(cl_ge(sin2_t, cl_set(1.0f)), cl_set(1.0f), f);
}

static float coat_albedo_quadrature(const CoatGrid *g, float mu, float alpha, float eta)
{
    const int n = COAT_N;
    Vec3 wo = v3(safe_sqrtf(1.0f - mu * mu), 0.0f, mu);
    double sum = 0.0;
    float g1 = ggx_g1(wo, alpha, alpha), lambda_o = ggx_lambda(wo, alpha, alpha);
    /* ggx_sample_visible's quantities that depend on wo alone. */
    Vec3 vh = v3_normalize(v3(alpha * wo.x, alpha * wo.y, wo.z));
    float len2 = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = len2 > 0.0f ? v3_scale(v3(-vh.y, vh.x, 0.0f), 1.0f / sqrtf(len2)) : v3(1.0f, 0.0f, 0.0f);
    Vec3 t2 = v3_cross(vh, t1);
    float s = 0.5f * (1.0f + vh.z);
    const CoatLanes one = cl_set(1.0f), zero = cl_set(0.0f), va = cl_set(alpha), vs = cl_set(s),
                    v1s = cl_set(1.0f - s);
    for (int i = 0; i < n; i++) {
        const CoatLanes r = cl_set(sqrtf(((float)i + 0.5f) / (float)n));
        for (int j0 = 0; j0 < n; j0 += COAT_LANES) {
            CoatLanes p1 = cl_mul(r, cl_load(g->cos_phi + j0)), p2 = cl_mul(r, cl_load(g->sin_phi + j0));
            CoatLanes p1p1 = cl_mul(p1, p1);
            p2 = cl_add(cl_mul(v1s, cl_safe_sqrt(cl_sub(one, p1p1))), cl_mul(vs, p2));
            CoatLanes q = cl_safe_sqrt(cl_sub(cl_sub(one, p1p1), cl_mul(p2, p2)));
            CoatLanes nx = cl_add(cl_add(cl_mul(cl_set(t1.x), p1), cl_mul(cl_set(t2.x), p2)), cl_mul(cl_set(vh.x), q));
            CoatLanes ny = cl_add(cl_add(cl_mul(cl_set(t1.y), p1), cl_mul(cl_set(t2.y), p2)), cl_mul(cl_set(vh.y), q));
            CoatLanes nz = cl_add(cl_add(cl_mul(cl_set(t1.z), p1), cl_mul(cl_set(t2.z), p2)), cl_mul(cl_set(vh.z), q));
            /* m = v3_normalize(alpha nh.x, alpha nh.y, maxf(nh.z, 0)) */
            CoatLanes mx = cl_mul(va, nx), my = cl_mul(va, ny), mz = cl_max(nz, zero);
            CoatLanes inv = cl_div(one, cl_sqrt(cl_add(cl_add(cl_mul(mx, mx), cl_mul(my, my)), cl_mul(mz, mz))));
            mx = cl_mul(mx, inv);
            my = cl_mul(my, inv);
            mz = cl_mul(mz, inv);
            /* wi = reflect_about(wo, m) */
            CoatLanes d = cl_add(cl_add(cl_mul(cl_set(wo.x), mx), cl_mul(cl_set(wo.y), my)), cl_mul(cl_set(wo.z), mz));
            CoatLanes k = cl_mul(cl_set(2.0f), d);
            CoatLanes wx = cl_sub(cl_mul(mx, k), cl_set(wo.x)), wy = cl_sub(cl_mul(my, k), cl_set(wo.y)),
                      wz = cl_sub(cl_mul(mz, k), cl_set(wo.z));
            /* F(wo.m) G2(wo, wi) / G1(wo) */
            CoatLanes g2 = cl_div(one, cl_add(cl_add(one, cl_set(lambda_o)), cl_lambda(wx, wy, wz, alpha)));
            CoatLanes term = cl_div(cl_mul(cl_fresnel(d, eta), g2), cl_set(g1));
            float t[COAT_LANES];
            cl_store(t, term);
            int valid = cl_mask(cl_gt(wz, zero));
            for (int l = 0; l < COAT_LANES; l++)
                if (valid & (1 << l)) sum += (double)t[l];
        }
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
    CoatGrid grid;
    coat_grid_init(&grid);
    for (int j = 0; j < N; j++) {
        /* Nodes at mu = x^2, x uniform: E changes fastest at grazing. mu = 0 is a limit
         * (G1 = 0); sample just above it. */
        float x = (float)j / (float)(N - 1);
        m->coat_e[j] = coat_albedo_quadrature(&grid, maxf(x * x, 1e-4f), alpha, m->ior);
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
