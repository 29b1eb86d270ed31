/* Participating media (src/media): chi-square of Henyey–Greenstein sampling against its
 * pdf for g in {-0.7, 0, 0.3, 0.9}, the phase function's normalisation, distance sampling
 * against its mixture pdf (chi-square) and as an estimator of the transmittance
 * e^{-sigma_t d}, and the scene's transmittance through a slab bounded by boundary shapes
 * (exact), blocked by an ordinary surface. Fixed seeds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "media/medium.h"
#include "media/phase.h"
#include "scene/scene.h"
#include "unit/chi2.h"

#define PI_D 3.14159265358979323846

enum { MU_BINS = 40, PHI_BINS = 20, HG_SAMPLES = 1000000 };

/* p = 0.01 per test: with four values of g a chance failure is rare, and a real bias in
 * the sampler or the pdf gives p far below it at a million samples. */
static const double P_MIN = 0.01;

static void check_hg(float g, uint64_t seed)
{
    Pcg32 r;
    pcg32_seed_sample(&r, seed, 0, 0);
    Vec3 wo = v3_normalize(v3(0.3f, -0.5f, 0.8f));
    Frame f = frame_from_normal(v3_neg(wo));
    static double obs[MU_BINS * PHI_BINS], expd[MU_BINS * PHI_BINS];
    memset(obs, 0, sizeof obs);
    for (int i = 0; i < HG_SAMPLES; i++) {
        float pdf;
        float u0 = pcg32_float(&r), u1 = pcg32_float(&r);
        Vec3 wi = phase_hg_sample(wo, g, u0, u1, &pdf);
        assert_true(fabsf(v3_length(wi) - 1.0f) < 1e-4f);
        float p_eval = phase_hg_pdf(wo, wi, g);
        assert_true(fabsf(pdf - p_eval) <= 1e-3f * p_eval + 1e-6f);
        assert_true(phase_hg_eval(wo, wi, g) == p_eval);
        Vec3 l = frame_to_local(&f, wi);
        double mu = fmin(fmax((double)l.z, -1.0), 1.0);
        double phi = atan2((double)l.y, (double)l.x);
        if (phi < 0.0) phi += 2.0 * PI_D;
        int a = (int)((mu + 1.0) * 0.5 * MU_BINS), b = (int)(phi / (2.0 * PI_D) * PHI_BINS);
        if (a >= MU_BINS) a = MU_BINS - 1;
        if (b >= PHI_BINS) b = PHI_BINS - 1;
        obs[a * PHI_BINS + b] += 1.0;
    }
    /* Expected counts: the pdf integrated over each cell by Simpson's rule in mu (dw =
     * dmu dphi), in double, from the formula rather than the sampler's inversion. */
    double total = 0.0;
    for (int a = 0; a < MU_BINS; a++) {
        double m0 = -1.0 + 2.0 * a / MU_BINS, m1 = m0 + 2.0 / MU_BINS, integral = 0.0;
        const int K = 64;
        for (int k = 0; k <= K; k++) {
            double mu = m0 + (m1 - m0) * k / K;
            double w = (k == 0 || k == K) ? 1.0 : (k % 2 ? 4.0 : 2.0);
            double gg = (double)g, den = 1.0 + gg * gg - 2.0 * gg * mu;
            integral += w * (1.0 - gg * gg) / (4.0 * PI_D * den * sqrt(den));
        }
        integral *= (m1 - m0) / (3.0 * K);
        for (int b = 0; b < PHI_BINS; b++) {
            expd[a * PHI_BINS + b] = HG_SAMPLES * integral * (2.0 * PI_D / PHI_BINS);
            total += integral * (2.0 * PI_D / PHI_BINS);
        }
    }
    assert_true(fabs(total - 1.0) < 1e-4); /* normalised over the sphere */
    int dof;
    double stat, outside;
    double p = chi2_pvalue(obs, expd, MU_BINS * PHI_BINS, &dof, &stat, &outside);
    print_message("HG g = %+.1f: chi2 %.1f, dof %d, p = %.3f\n", (double)g, stat, dof, p);
    assert_true(outside == 0.0);
    if (!(p > P_MIN)) fail_msg("HG g = %g: chi-square p = %g (stat %g, dof %d)", (double)g, p, stat, dof);
}

static void test_hg_chi2(void **state)
{
    (void)state;
    const float gs[4] = {-0.7f, 0.0f, 0.3f, 0.9f};
    for (int i = 0; i < 4; i++) check_hg(gs[i], 11u + (uint64_t)i);
}

/* pbrt-v4's convention: g > 0 scatters forward, toward -wo. */
static void test_hg_forward(void **state)
{
    (void)state;
    Vec3 wo = v3(0.0f, 0.0f, 1.0f);
    assert_true(phase_hg_eval(wo, v3(0.0f, 0.0f, -1.0f), 0.8f) > phase_hg_eval(wo, wo, 0.8f));
    assert_true(fabsf(phase_hg_eval(wo, wo, 0.0f) - PHASE_INV_4PI) < 1e-7f);
}

static MediumCoeffs coeffs(float a0, float a1, float a2, float s0, float s1, float s2)
{
    Medium m = {.type = MEDIUM_HOMOGENEOUS, .g = 0.0f};
    m.u.homog.sigma_a = color_rgb(a0, a1, a2);
    m.u.homog.sigma_s = color_rgb(s0, s1, s2);
    m.u.homog.le = color_s(0.0f);
    return medium_coeffs(&m, NULL);
}

static void test_transmittance_closed_form(void **state)
{
    (void)state;
    MediumCoeffs m = coeffs(0.5f, 0.0f, 2.0f, 0.5f, 0.0f, 1.0f);
    Color tr = medium_transmittance(&m, 0.75f);
    assert_true(fabsf(tr.c[0] - expf(-0.75f)) < 1e-6f);
    assert_true(tr.c[1] == 1.0f);
    assert_true(fabsf(tr.c[2] - expf(-2.25f)) < 1e-6f);
    assert_true(medium_transmittance(&m, INFINITY).c[1] == 1.0f); /* sigma_t 0: no NaN */
}

/* Distance sampling: chi-square of t against the mixture pdf on [0, t_max) in bins plus
 * the pass cell; and the pass weight as an estimator of e^{-sigma_t d} per channel (a
 * slab of thickness d), within 4 standard errors. One lane has sigma_t = 0. */
static void test_distance_sampling(void **state)
{
    (void)state;
    enum { BINS = 50, N = 1000000 };
    const float d = 1.3f;
    MediumCoeffs m = coeffs(0.2f, 0.0f, 1.5f, 0.6f, 0.0f, 0.5f);
    Pcg32 r;
    pcg32_seed_sample(&r, 77, 0, 0);
    static double obs[BINS + 1], expd[BINS + 1];
    double sum[4] = {0}, sum2[4] = {0};
    for (int i = 0; i < N; i++) {
        MediumSample ms;
        float uc = pcg32_float(&r), u = pcg32_float(&r);
        medium_sample_distance(&m, d, uc, u, &ms);
        if (ms.scattered) {
            assert_true(ms.t >= 0.0f && ms.t < d);
            int b = (int)(ms.t / d * BINS);
            obs[b < BINS ? b : BINS - 1] += 1.0;
        } else {
            assert_true(ms.t == d);
            obs[BINS] += 1.0;
        }
        for (int c = 0; c < 4; c++) {
            double x = ms.scattered ? 0.0 : (double)ms.weight.c[c];
            sum[c] += x;
            sum2[c] += x * x;
        }
    }
    for (int b = 0; b < BINS; b++) { /* pdf integrated exactly: sum of sigma e^{-sigma t} terms */
        double t0 = (double)d * b / BINS, t1 = (double)d * (b + 1) / BINS, p = 0.0;
        for (int c = 0; c < 4; c++) p += exp(-(double)m.sigma_t.c[c] * t0) - exp(-(double)m.sigma_t.c[c] * t1);
        expd[b] = N * p / 4.0;
    }
    expd[BINS] = N * (double)medium_pass_prob(&m, d);
    int dof;
    double stat, outside;
    double p = chi2_pvalue(obs, expd, BINS + 1, &dof, &stat, &outside);
    print_message("distance sampling: chi2 %.1f, dof %d, p = %.3f\n", stat, dof, p);
    if (!(p > P_MIN)) fail_msg("distance sampling chi-square p = %g", p);
    for (int c = 0; c < 4; c++) {
        double mean = sum[c] / N, var = sum2[c] / N - mean * mean, se = sqrt(var / N);
        double expect = exp(-(double)m.sigma_t.c[c] * (double)d);
        print_message("slab transmittance lane %d: %.5f (se %.1e), e^{-sigma_t d} = %.5f\n", c, mean, se, expect);
        if (!(fabs(mean - expect) <= 4.0 * se + 1e-6)) fail_msg("lane %d: %g vs %g (se %g)", c, mean, expect, se);
    }
    /* The pdf function against the bins' exact integrals, at a point. */
    float t = 0.4f;
    double pdf = 0.0;
    for (int c = 0; c < 4; c++) pdf += (double)m.sigma_t.c[c] * exp(-(double)m.sigma_t.c[c] * (double)t) / 4.0;
    assert_true(fabs((double)medium_distance_pdf(&m, t) - pdf) < 1e-6);
}

/* A slab 0 < z < 2 bounded by two boundary quads (medium inside, vacuum outside), then an
 * opaque quad at z = 3: scene_transmittance across the slab is e^{-sigma_t 2}, and black
 * through the opaque quad. */
static void test_scene_transmittance(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat, med;
    Material dm = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &dm, &mat, &err), CST_OK);
    Medium m = {.type = MEDIUM_HOMOGENEOUS, .g = 0.3f};
    m.u.homog.sigma_a = color_rgb(0.1f, 0.2f, 0.3f);
    m.u.homog.sigma_s = color_rgb(0.4f, 0.0f, 0.1f);
    assert_int_equal(scene_add_medium(s, &m, &med, &err), CST_OK);
    /* Normals: the z = 0 quad faces -z (outside below), the z = 2 quad faces +z. */
    Vec3 q0[4] = {{-5, -5, 0}, {-5, 5, 0}, {5, 5, 0}, {5, -5, 0}};
    Vec3 q1[4] = {{-5, -5, 2}, {5, -5, 2}, {5, 5, 2}, {-5, 5, 2}};
    Vec3 q2[4] = {{-5, -5, 3}, {5, -5, 3}, {5, 5, 3}, {-5, 5, 3}};
    assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, q0, mat, NULL, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, q1, mat, NULL, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, -1, -1, 0, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, q2, mat, NULL, &err), CST_OK);
    assert_true(s->tri_info[0].medium != 0 && s->tri_info[4].medium == 0);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    uint64_t rays = 0;
    Color tr = scene_transmittance(s, v3(0.1f, 0.2f, -1.0f), v3s(0.0f), v3(0.1f, 0.2f, 2.5f), v3s(0.0f), -1, NULL, &rays);
    for (int c = 0; c < 3; c++) {
        float st = m.u.homog.sigma_a.c[c] + m.u.homog.sigma_s.c[c];
        assert_true(fabsf(tr.c[c] - expf(-2.0f * st)) < 1e-5f);
    }
    assert_int_equal((int)rays, 3);
    /* Starting inside the medium, half-way. */
    tr = scene_transmittance(s, v3(0.0f, 0.0f, 1.0f), v3s(0.0f), v3(0.0f, 0.0f, -1.0f), v3s(0.0f), med, NULL, &rays);
    assert_true(fabsf(tr.c[0] - expf(-0.5f)) < 1e-5f);
    tr = scene_transmittance(s, v3(0.0f, 0.0f, -1.0f), v3s(0.0f), v3(0.0f, 0.0f, 4.0f), v3s(0.0f), -1, NULL, &rays);
    assert_true(color_is_black(tr));
    CstError e2;
    assert_int_equal(scene_set_medium_interface(s, 3, -1, 0, &e2), CST_ERR_INVALID_ARG);
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_hg_chi2),
        cmocka_unit_test(test_hg_forward),
        cmocka_unit_test(test_transmittance_closed_form),
        cmocka_unit_test(test_distance_sampling),
        cmocka_unit_test(test_scene_transmittance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
