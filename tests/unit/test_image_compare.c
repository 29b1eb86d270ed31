/* The metrics of `caustic compare` (film/film_compare.c compare_images, film/flip.c): closed
 * forms for identical images, constant offsets (RMSE, relMSE, block z-scores), FLIP of
 * uniform images (where the feature term vanishes and FLIP is the colour metric alone,
 * computed here from the paper's formulas by hand), FLIP's zero on identical images and its
 * growth with the difference, HDR-FLIP's exposure range, and the variance layer reader. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/rng.h"
#include "film/film_compare.h"
#include "film/flip.h"
#include "io/image_io.h"
#include "unit/scratch_dir.h"

enum { W = 40, H = 24, N = W * H };

static float *image_fill(float r, float g, float b)
{
    float *p = malloc(3 * N * sizeof *p);
    assert_non_null(p);
    for (int i = 0; i < N; i++) {
        p[3 * i] = r;
        p[3 * i + 1] = g;
        p[3 * i + 2] = b;
    }
    return p;
}

/* A textured image: smooth gradients and a few edges, values in [0, 1]. */
static float *image_pattern(uint64_t seed)
{
    float *p = malloc(3 * N * sizeof *p);
    assert_non_null(p);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 1);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++)
            for (int c = 0; c < 3; c++) {
                float v = 0.2f + 0.6f * (float)x / W * (float)(c + 1) / 3.0f + ((x / 8 + y / 6) % 2 ? 0.1f : 0.0f);
                p[3 * (y * W + x) + c] = v + 0.05f * pcg32_float(&rng);
            }
    return p;
}

static void assert_near(double got, double want, double tol)
{
    if (!(fabs(got - want) <= tol)) fail_msg("got %.10g, expected %.10g (tolerance %.3g)", got, want, tol);
}

/* ------------------------------------------------------------------ means, RMSE, relMSE */

static void test_identical_images(void **state)
{
    (void)state;
    float *a = image_pattern(1);
    ImageComparison r;
    CstError err = {0};
    assert_int_equal(compare_images(a, a, W, H, NULL, NULL, 8, &r, NULL, &err), CST_OK);
    for (int c = 0; c < 3; c++) {
        assert_true(r.mean_a[c] == r.mean_b[c]);
        assert_true(r.diff[c] == 0.0 && r.rel_diff[c] == 0.0);
        assert_true(r.rmse[c] == 0.0 && r.relmse[c] == 0.0);
    }
    assert_true(r.rmse_all == 0.0 && r.relmse_all == 0.0);
    assert_int_equal(r.has_z, 0);
    free(a);
}

/* a = b + d everywhere, b constant per channel: RMSE = d, relMSE = d^2 / (b^2 + eps), the
 * mean difference d and relative difference d / b, exactly up to float rounding of a. */
static void test_constant_offset(void **state)
{
    (void)state;
    const float b0[3] = {0.25f, 0.5f, 2.0f}, d = 0.125f; /* exact in binary */
    float *b = image_fill(b0[0], b0[1], b0[2]), *a = image_fill(b0[0] + d, b0[1] + d, b0[2] + d);
    ImageComparison r;
    CstError err = {0};
    assert_int_equal(compare_images(a, b, W, H, NULL, NULL, 8, &r, NULL, &err), CST_OK);
    double rel_all = 0.0;
    for (int c = 0; c < 3; c++) {
        double want_rel = (double)d * (double)d / ((double)b0[c] * (double)b0[c] + CST_RELMSE_EPS);
        assert_near(r.mean_a[c], (double)(b0[c] + d), 1e-12);
        assert_near(r.mean_b[c], (double)b0[c], 1e-12);
        assert_near(r.diff[c], (double)d, 1e-12);
        assert_near(r.rel_diff[c], (double)d / (double)b0[c], 1e-12);
        assert_near(r.rmse[c], (double)d, 1e-12);
        assert_near(r.relmse[c], want_rel, 1e-12);
        rel_all += want_rel / 3.0;
    }
    assert_near(r.rmse_all, (double)d, 1e-12);
    assert_near(r.relmse_all, rel_all, 1e-12);
    free(a);
    free(b);
}

/* NaN and infinite values are left out and counted, not propagated. */
static void test_nonfinite_left_out(void **state)
{
    (void)state;
    float *a = image_fill(1.0f, 1.0f, 1.0f), *b = image_fill(1.0f, 1.0f, 1.0f);
    a[0] = NAN;
    b[4] = INFINITY;
    ImageComparison r;
    CstError err = {0};
    assert_int_equal(compare_images(a, b, W, H, NULL, NULL, 8, &r, NULL, &err), CST_OK);
    assert_int_equal(r.nonfinite, 2);
    for (int c = 0; c < 3; c++) assert_true(r.mean_a[c] == 1.0 && r.rmse[c] == 0.0);
    free(a);
    free(b);
}

/* ------------------------------------------------------------------ block z-scores */

/* a = 1 + delta, b = 1, per-pixel variance v in both: a block of n pixels has
 * z = delta / sqrt(2 v / n) = delta sqrt(n / (2 v)); with v only in a, sqrt(n / v). Partial
 * edge blocks (W = 40 with blocks of 16: 16, 16, 8 wide) have their own n. */
static void test_block_z_closed_form(void **state)
{
    (void)state;
    const double delta = 0.01, v = 0.002;
    float *a = image_fill(1.0f + (float)delta, 1.0f + (float)delta, 1.0f + (float)delta);
    float *b = image_fill(1.0f, 1.0f, 1.0f), *var = image_fill((float)v, (float)v, (float)v);
    double da = (double)(1.0f + (float)delta) - 1.0; /* delta as stored */
    ImageComparison r;
    CstError err = {0};
    double bz[6];
    assert_int_equal(compare_images(a, b, W, H, var, var, 16, &r, bz, &err), CST_OK);
    assert_int_equal(r.has_z, 1);
    assert_int_equal(r.blocks, 3 * 2);
    double vf = (double)(float)v;
    double z_full = da * sqrt(256.0 / (2.0 * vf)), z_8x8 = da * sqrt(64.0 / (2.0 * vf));
    assert_near(bz[0], z_full, 1e-6 * z_full);  /* 16x16 */
    assert_near(bz[2], da * sqrt(128.0 / (2.0 * vf)), 1e-6 * z_full); /* 8 x 16 */
    assert_near(bz[5], z_8x8, 1e-6 * z_full);  /* 8 x 8 */
    assert_near(r.max_abs_z, z_full, 1e-6 * z_full);
    assert_true(r.worst_z > 0.0);
    assert_near(r.z_mean[1], da * sqrt((double)N / (2.0 * vf)), 1e-6 * z_full);
    /* z_full = 2.5, the 8 x 16 blocks 1.77, 8 x 8 1.25: none above 4 */
    assert_int_equal(r.above, 0);
    /* Variances in a only: z grows by sqrt 2; four times the offset: every block above 4
     * but the 8 x 8 one (2 x 1.25 x 2 x 1.41 = 7.1 > 4 too), so all of them. */
    float *a4 = image_fill(1.0f + 4.0f * (float)delta, 1.0f + 4.0f * (float)delta, 1.0f + 4.0f * (float)delta);
    assert_int_equal(compare_images(a4, b, W, H, var, NULL, 16, &r, bz, &err), CST_OK);
    double da4 = (double)(1.0f + 4.0f * (float)delta) - 1.0;
    assert_near(bz[0], da4 * sqrt(256.0 / vf), 1e-6 * bz[0]);
    assert_int_equal(r.above, 3 * 6);
    assert_near(r.frac_above, 1.0, 0.0);
    free(a);
    free(a4);
    free(b);
    free(var);
}

/* Two independent noisy images of the same mean with their true variances: the block z
 * are standard normal, so |z| > 4 (p = 6.3e-5) in none of 36 tests but with probability
 * ~0.2%; fixed seed. */
static void test_block_z_agreement(void **state)
{
    (void)state;
    const double sigma = 0.1;
    float *a = image_fill(0, 0, 0), *b = image_fill(0, 0, 0), *var = image_fill(0, 0, 0);
    Pcg32 rng;
    pcg32_seed(&rng, 7, 3);
    for (int i = 0; i < 3 * N; i++) {
        /* uniform noise of variance sigma^2: width sigma sqrt 12 */
        a[i] = (float)(0.5 + sigma * sqrt(12.0) * ((double)pcg32_float(&rng) - 0.5));
        b[i] = (float)(0.5 + sigma * sqrt(12.0) * ((double)pcg32_float(&rng) - 0.5));
        var[i] = (float)(sigma * sigma);
    }
    ImageComparison r;
    CstError err = {0};
    assert_int_equal(compare_images(a, b, W, H, var, var, 8, &r, NULL, &err), CST_OK);
    assert_int_equal(r.blocks, 15);
    assert_int_equal(r.above, 0);
    assert_true(r.max_abs_z < 4.0);
    free(a);
    free(b);
    free(var);
}

/* ------------------------------------------------------------------ FLIP */

static double flip_mean(const float *ref, const float *test, CstFlipKind kind)
{
    CstFlipOptions o = {0};
    o.kind = kind;
    CstFlipResult f;
    CstError err = {0};
    assert_int_equal(cst_image_flip(test, ref, W, H, &o, NULL, &f, &err), CST_OK);
    assert_true(f.mean >= 0.0 && f.mean <= 1.0 && f.max <= 1.0);
    return f.mean;
}

static void test_flip_identical_is_zero(void **state)
{
    (void)state;
    float *a = image_pattern(3);
    assert_true(flip_mean(a, a, CST_FLIP_LDR) == 0.0);
    for (int i = 0; i < 3 * N; i++) a[i] *= 40.0f; /* HDR values */
    assert_true(flip_mean(a, a, CST_FLIP_HDR) == 0.0);
    free(a);
}

/* Uniform images: the edge and point detectors sum to zero, so FLIP is the colour term:
 * c_max = HyAB(green, blue)^0.7 in Hunt-adjusted L*a*b* = 41.2761; black against white:
 * HyAB = 100 (L* 0 and 100, a* = b* = 0), 100^0.7 = 25.1189 >= 0.4 c_max, so FLIP =
 * 0.95 + (25.1189 - 0.4 c_max) / (0.6 c_max) 0.05 = 0.967380. Grey 0.5 against 0.6 (linear):
 * HyAB^0.7 = 3.41010 < 0.4 c_max, FLIP = 0.95 / (0.4 c_max) 3.41010 = 0.196215. (Values
 * from the paper's formulas evaluated in double precision by hand, outside this code.) */
static void test_flip_uniform_closed_form(void **state)
{
    (void)state;
    float *black = image_fill(0, 0, 0), *white = image_fill(1, 1, 1);
    float *g5 = image_fill(0.5f, 0.5f, 0.5f), *g6 = image_fill(0.6f, 0.6f, 0.6f);
    assert_near(flip_mean(white, black, CST_FLIP_LDR), 0.9673797615, 2e-5);
    assert_near(flip_mean(black, white, CST_FLIP_LDR), 0.9673797615, 2e-5);
    assert_near(flip_mean(g5, g6, CST_FLIP_LDR), 0.1962147115, 2e-5);
    free(black);
    free(white);
    free(g5);
    free(g6);
}

/* A patch of the test image brightened by t: the mean FLIP grows with t (LDR and HDR). */
static void test_flip_monotone(void **state)
{
    (void)state;
    float *ref = image_pattern(5), *test = malloc(3 * N * sizeof *test);
    assert_non_null(test);
    for (int kind = CST_FLIP_LDR; kind <= CST_FLIP_HDR; kind++) {
        double last = 0.0;
        for (int k = 1; k <= 6; k++) {
            float t = 0.03f * (float)k;
            memcpy(test, ref, 3 * N * sizeof *test);
            for (int y = 6; y < 18; y++)
                for (int x = 10; x < 30; x++)
                    for (int c = 0; c < 3; c++) test[3 * (y * W + x) + c] += t;
            double m = flip_mean(ref, test, (CstFlipKind)kind);
            if (!(m > last)) fail_msg("kind %d: FLIP %.6g at offset %.2f not above %.6g", kind, m, (double)t, last);
            last = m;
        }
    }
    free(ref);
    free(test);
}

/* HDR-FLIP's exposures (the 2021 paper): the brightest reference luminance maps to 0.85 at
 * the start, the median at the stop. A reference of luminance 1 in a quarter of the pixels,
 * 1/64 elsewhere: start = log2(x / 1), stop = log2(x / (1/64)) = start + 6, 6 exposures;
 * tone_map(y 2^start) = 0.85 for the brightest. */
static void test_flip_exposure_range(void **state)
{
    (void)state;
    float *ref = image_fill(1.0f / 64.0f, 1.0f / 64.0f, 1.0f / 64.0f);
    for (int i = 0; i < N / 4; i++) ref[3 * i] = ref[3 * i + 1] = ref[3 * i + 2] = 1.0f;
    double start, stop;
    int count;
    flip_exposure_range(ref, W, H, &start, &stop, &count);
    assert_near(flip_tone_map(1.0, start), 0.85, 1e-9);
    assert_near(stop - start, 6.0, 1e-5);
    assert_int_equal(count, 6);
    /* black everywhere: no range */
    float *black = image_fill(0, 0, 0);
    flip_exposure_range(black, W, H, &start, &stop, &count);
    assert_true(start == 0.0 && stop == 0.0 && count == 1);
    /* mostly black: the median of the lit pixels (1 here) */
    for (int i = 0; i < N / 4; i++) black[3 * i] = black[3 * i + 1] = black[3 * i + 2] = 1.0f;
    flip_exposure_range(black, W, H, &start, &stop, &count);
    assert_near(stop, start, 1e-9);
    free(ref);
    free(black);
}

/* ------------------------------------------------------------------ variance layer */

static void test_read_variance_layer(void **state)
{
    (void)state;
    char path[512];
    assert_int_equal(scratch_dir_make("/tmp/cst_image_compare.XXXXXX"), 0);
    tpath(path, sizeof path, "layers.exr");
    float *rgb = image_pattern(9), *var = image_pattern(10);
    static const char *const names[3] = {"variance.R", "variance.G", "variance.B"};
    ImageWriteOptions opt = {0};
    opt.extra_channels = 3;
    opt.extra_names = names;
    opt.extra = var;
    CstError err = {0};
    assert_int_equal(image_write_opt(path, rgb, W, H, &opt, &err), CST_OK);
    float *got = NULL;
    int w = 0, h = 0;
    assert_int_equal(image_read_layer(path, "variance", &got, &w, &h, &err), CST_OK);
    assert_int_equal(w, W);
    assert_int_equal(h, H);
    assert_memory_equal(got, var, 3 * N * sizeof *got);
    free(got);
    assert_int_equal(image_read_layer(path, "albedo", &got, &w, &h, &err), CST_ERR_UNSUPPORTED);
    assert_null(got);
    /* the RGB read is unchanged by the layer reader */
    assert_int_equal(image_read(path, &got, &w, &h, &err), CST_OK);
    assert_memory_equal(got, rgb, 3 * N * sizeof *got);
    free(got);
    scratch_dir_remove();
    free(rgb);
    free(var);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_identical_images),
        cmocka_unit_test(test_constant_offset),
        cmocka_unit_test(test_nonfinite_left_out),
        cmocka_unit_test(test_block_z_closed_form),
        cmocka_unit_test(test_block_z_agreement),
        cmocka_unit_test(test_flip_identical_is_zero),
        cmocka_unit_test(test_flip_uniform_closed_form),
        cmocka_unit_test(test_flip_monotone),
        cmocka_unit_test(test_flip_exposure_range),
        cmocka_unit_test(test_read_variance_layer),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
