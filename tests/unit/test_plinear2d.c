/* The piecewise-bilinear 2D distribution (sampling/plinear2d.c) against its own density:
 * chi-square of pl2d_sample, the sample's pdf against pl2d_eval, pl2d_invert as
 * pl2d_sample's inverse, the density's integral over the unit square with parameters
 * between their nodes, and the raw (no cdf) table's interpolation at its nodes. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>

#include "core/rng.h"
#include "sampling/plinear2d.h"
#include "unit/chi2.h"

enum { NX = 5, NY = 4, P0 = 3, P1 = 2 };
static const float PV0[P0] = {0.0f, 0.5f, 2.0f}, PV1[P1] = {-1.0f, 1.0f};

/* A positive table with structure: a bump whose place moves with the parameters, and
 * some nodes near zero. */
static void make_table(float *t)
{
    for (int a = 0; a < P0; a++)
        for (int b = 0; b < P1; b++)
            for (int y = 0; y < NY; y++)
                for (int x = 0; x < NX; x++) {
                    float cx = 0.2f + 0.3f * (float)a, cy = b ? 0.8f : 0.3f;
                    float dx = (float)x / (NX - 1) - cx, dy = (float)y / (NY - 1) - cy;
                    t[((a * P1 + b) * NY + y) * NX + x] = 0.02f + expf(-8.0f * (dx * dx + dy * dy)) * (1.0f + (float)a);
                }
}

static PLinear2D make(bool cdf)
{
    static float t[P0 * P1 * NY * NX];
    make_table(t);
    const int sizes[2] = {P0, P1};
    const float *const values[2] = {PV0, PV1};
    PLinear2D d;
    CstError err = {0};
    if (pl2d_init(&d, t, NX, NY, 2, sizes, values, cdf, &err) != CST_OK) fail_msg("%s", err.msg);
    return d;
}

static const float PARAMS[][2] = {{0.25f, 0.3f}, {1.2f, -0.7f}, {0.0f, 1.0f}, {5.0f, 0.0f}};

static void test_chi2(void **state)
{
    (void)state;
    enum { N = 200000, H = 16, SUBS = 8 };
    PLinear2D d = make(true);
    double worst_p = 1.0, worst_rel = 0.0;
    for (int c = 0; c < 4; c++) {
        const float *pr = PARAMS[c];
        static double obs[H * H], expd[H * H];
        for (int i = 0; i < H * H; i++) obs[i] = expd[i] = 0.0;
        Pcg32 r;
        pcg32_seed(&r, 700u + (uint64_t)c, 1u);
        for (int s = 0; s < N; s++) {
            float pdf;
            Vec2 p = pl2d_sample(&d, pcg32_v2(&r), pr, &pdf);
            assert_true(p.x >= 0.0f && p.x <= 1.0f && p.y >= 0.0f && p.y <= 1.0f);
            double e = (double)pl2d_eval(&d, p, pr);
            worst_rel = fmax(worst_rel, fabs((double)pdf - e) / e);
            int ix = (int)(p.x * H), iy = (int)(p.y * H);
            obs[(iy < H ? iy : H - 1) * H + (ix < H ? ix : H - 1)] += 1.0;
        }
        for (int iy = 0; iy < H; iy++)
            for (int ix = 0; ix < H; ix++) {
                double sum = 0.0;
                for (int a = 0; a < SUBS; a++)
                    for (int b = 0; b < SUBS; b++)
                        sum += (double)pl2d_eval(&d, v2(((float)ix + ((float)a + 0.5f) / SUBS) / H,
                                                        ((float)iy + ((float)b + 0.5f) / SUBS) / H), pr);
                expd[iy * H + ix] = sum / (SUBS * SUBS) / (H * H) * N;
            }
        int dof;
        double stat, outside;
        double p = chi2_pvalue(obs, expd, H * H, &dof, &stat, &outside);
        print_message("params (%.2f, %.2f): chi2 %.1f, dof %d, p %.3g\n", (double)pr[0], (double)pr[1], stat, dof, p);
        worst_p = fmin(worst_p, p);
        assert_true(outside == 0.0);
        /* 4 cases at a file significance of 1e-3 */
        if (!(p > 1e-3 / 4)) fail_msg("params (%g, %g): p = %.3g", (double)pr[0], (double)pr[1], p);
    }
    print_message("pl2d chi-square: worst p %.3g; sample pdf vs eval max relative %.2g\n", worst_p, worst_rel);
    assert_true(worst_rel < 1e-4);
    pl2d_free(&d);
}

static void test_invert_and_integral(void **state)
{
    (void)state;
    PLinear2D d = make(true);
    Pcg32 r;
    pcg32_seed(&r, 9u, 1u);
    double worst = 0.0;
    for (int c = 0; c < 4; c++)
        for (int s = 0; s < 20000; s++) {
            Vec2 u = pcg32_v2(&r);
            float pdf, pdf2;
            Vec2 p = pl2d_sample(&d, u, PARAMS[c], &pdf);
            Vec2 back = pl2d_invert(&d, p, PARAMS[c], &pdf2);
            worst = fmax(worst, fmax(fabs((double)back.x - (double)u.x), fabs((double)back.y - (double)u.y)));
            assert_true(fabsf(pdf - pdf2) <= 1e-4f * pdf);
        }
    print_message("invert(sample(u)) - u: max %.2g\n", worst);
    assert_true(worst < 2e-4);
    for (int c = 0; c < 4; c++) {
        double sum = 0.0;
        const int M = 400;
        for (int i = 0; i < M; i++)
            for (int j = 0; j < M; j++) sum += (double)pl2d_eval(&d, v2((i + 0.5f) / M, (j + 0.5f) / M), PARAMS[c]);
        sum /= (double)M * M;
        if (!(fabs(sum - 1.0) < 1e-4)) fail_msg("params %d: integral %.6f", c, sum);
    }
    pl2d_free(&d);
}

static void test_raw_table(void **state)
{
    (void)state;
    float t[P0 * P1 * NY * NX];
    make_table(t);
    PLinear2D d = make(false);
    for (int a = 0; a < P0; a++)
        for (int b = 0; b < P1; b++)
            for (int y = 0; y < NY; y++)
                for (int x = 0; x < NX; x++) {
                    float pr[2] = {PV0[a], PV1[b]};
                    float v = pl2d_eval(&d, v2((float)x / (NX - 1), (float)y / (NY - 1)), pr);
                    assert_true(fabsf(v - t[((a * P1 + b) * NY + y) * NX + x]) < 1e-6f);
                }
    pl2d_free(&d);
    /* sizes out of range, a table without mass */
    PLinear2D e;
    CstError err = {0};
    float zero[4] = {0, 0, 0, 0};
    assert_int_equal(pl2d_init(&e, zero, 1, 4, 0, NULL, NULL, false, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(pl2d_init(&e, zero, 2, 2, 0, NULL, NULL, true, &err), CST_ERR_INVALID_ARG);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2),
        cmocka_unit_test(test_invert_and_integral),
        cmocka_unit_test(test_raw_table),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
