/* The comparison statistics of `caustic verify` (film/film_compare.c): the inverse normal
 * CDF against high-precision quantiles, the Sidak arithmetic, and z-scores of synthetic
 * films with known pixel means and variances: agreement, offsets of a known z in one
 * block (partial blocks included), zero-variance pixels, the false-alarm rate, map colours;
 * the convergence check's level statistics, step test and rule, and their error rates. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "film/film.h"
#include "film/film_compare.h"
#include "io/image_io.h"

static void assert_rel(double got, double want, double rel)
{
    if (!(fabs(got - want) <= rel * fabs(want)))
        fail_msg("got %.17g, expected %.17g (relative error %.3g > %.3g)", got, want,
                 fabs(got - want) / fabs(want), rel);
}

/* ------------------------------------------------------------------ inverse normal CDF */

static void test_quantile_known_values(void **state)
{
    (void)state;
    /* Reference values: mpmath at 50 digits, the root of log Phi(x) = log p for the double
     * nearest each p (near p = 1/2 that differs from the decimal p's quantile by 1e-12). */
    assert_rel(compare_normal_quantile(0.975), 1.959963984540054211779584, 1e-14);
    assert_rel(compare_normal_quantile(0.995), 2.575829303548900753780426, 1e-14);
    /* 1 - 1e-9 as a double is 0.99999999900000002828...; its quantile: */
    assert_rel(compare_normal_quantile(1.0 - 1e-9), 5.997807019601637426423078, 1e-14);
    /* The exact tail 1e-9 (what 1 - 1e-9 means in real numbers), within 1e-7: */
    assert_rel(-compare_normal_quantile(1e-9), 5.997807015007686871562310, 1e-14);
    assert_rel(compare_normal_quantile(1.0 - 1e-9), 5.997807015007686871562310, 1e-7);
    assert_rel(compare_normal_quantile(1e-300), -37.04709629936119923654704, 1e-14);
    assert_rel(compare_normal_quantile(1e-20), -9.262340089798407579572095, 1e-14);
    /* Both sides of Acklam's region boundary (p_low = 0.02425). */
    assert_rel(compare_normal_quantile(0.02425), -1.972961051311884837602748, 1e-14);
    assert_rel(compare_normal_quantile(0.3), -0.5244005127080408159694544, 1e-14);
    assert_rel(compare_normal_quantile(0.49999), -2.506628274896000852684996e-5, 1e-14);
    assert_true(compare_normal_quantile(0.5) == 0.0);
}

static void test_quantile_domain_and_round_trip(void **state)
{
    (void)state;
    assert_true(compare_normal_quantile(0.0) == -HUGE_VAL);
    assert_true(compare_normal_quantile(1.0) == HUGE_VAL);
    assert_true(isnan(compare_normal_quantile(-0.1)));
    assert_true(isnan(compare_normal_quantile(1.5)));
    assert_true(isnan(compare_normal_quantile((double)NAN)));
    /* Phi(Phi^-1(p)) = p and symmetry, over p from 1e-300 to 0.5. */
    for (double p = 1e-300; p < 0.5; p *= 1.7) {
        double x = compare_normal_quantile(p);
        assert_rel(0.5 * erfc(-x / sqrt(2.0)), p, 1e-12);
        if (p > 1e-16) /* below, 1 - p rounds to 1 */
            assert_rel(compare_normal_quantile(1.0 - p), -x, 1e-15 / p + 1e-12);
    }
}

/* ------------------------------------------------------------------ Sidak */

static void test_sidak(void **state)
{
    (void)state;
    assert_rel(compare_sidak_alpha(0.01, 1.0), 0.01, 1e-14);
    assert_rel(compare_sidak_alpha(0.01, 2.0), 0.005012562893380045370127941, 1e-12);
    assert_rel(compare_sidak_alpha(0.01, 9225.0), 1.089466707723283510675479e-6, 1e-12);
    assert_rel(compare_sidak_alpha(0.01, 1e6), 1.005033580299681617892621e-8, 1e-12);
    /* m tests at alpha_1 have family-wise error 1 - (1 - alpha_1)^m = alpha. */
    double a1 = compare_sidak_alpha(0.05, 51.0);
    assert_rel(-expm1(51.0 * log1p(-a1)), 0.05, 1e-13);

    assert_rel(compare_z_critical(0.01, 1.0), 2.575829303548900760978577, 1e-12);
    assert_rel(compare_z_critical(0.05, 1.0), 1.959963984540054235524594, 1e-12);
    assert_rel(compare_z_critical(0.01, 21.0), 3.492527169938902781797709, 1e-12);
    assert_rel(compare_z_critical(0.01, 9225.0), 4.874749393824968422625913, 1e-12);
    assert_rel(compare_z_critical(0.01, 1e6), 5.729877212047103695318281, 1e-12);

    assert_true(isnan(compare_sidak_alpha(0.0, 3.0)));
    assert_true(isnan(compare_sidak_alpha(1.0, 3.0)));
    assert_true(isnan(compare_sidak_alpha(0.01, 0.0)));
    assert_true(isnan(compare_z_critical(0.01, HUGE_VAL)));

    assert_int_equal(compare_blocks_x(20, 8), 3);
    assert_int_equal(compare_blocks_x(16, 8), 2);
    assert_int_equal(compare_blocks_y(12, 8), 2);
    assert_int_equal(compare_blocks_x(5, 16), 1);
    assert_int_equal(compare_blocks_x(5, 0), 0);
    assert_int_equal(compare_tests_per_pair(20, 12, 8), 3 * (1 + 6));
    assert_int_equal(compare_tests_per_pair(512, 512, 16), 3 * (1 + 1024));
}

/* ------------------------------------------------------------------ synthetic films */

/* A film of 2 samples per pixel where pixel (x, y) has, per channel, mean m and a pixel
 * mean variance of s^2: samples m + s and m - s have sample variance 2 s^2, over 2. */
static Film *make_film(int w, int h)
{
    Film *f = film_create(w, h);
    assert_non_null(f);
    f->spp = 2;
    return f;
}

static void put(Film *f, int x, int y, const double m[3], const double s[3])
{
    int p = y * f->width + x;
    for (int c = 0; c < 3; c++) f->sum[3 * p + c] = f->sum_sq[3 * p + c] = 0.0;
    film_accumulate(f, p, m[0] + s[0], m[1] + s[1], m[2] + s[2]);
    film_accumulate(f, p, m[0] - s[0], m[1] - s[1], m[2] - s[2]);
}

/* Every pixel: mean (0.5, 0.25, 0.125) plus `shift`, standard error s in each channel. */
static void fill(Film *f, double s, const double shift[3])
{
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            double m[3] = {0.5 + shift[0], 0.25 + shift[1], 0.125 + shift[2]};
            double se[3] = {s, s, s};
            put(f, x, y, m, se);
        }
}

/* Shifts channel c of every pixel of block (bx, by) of f so that the block's z against
 * an unshifted twin (both with standard error s per pixel) is exactly -z: the block of n
 * pixels has sum variance 2 n s^2. */
static int shift_block(Film *f, int block, int bx, int by, int c, double s, double z)
{
    int x1 = (bx + 1) * block < f->width ? (bx + 1) * block : f->width;
    int y1 = (by + 1) * block < f->height ? (by + 1) * block : f->height;
    int n = (x1 - bx * block) * (y1 - by * block);
    double delta = z * sqrt(2.0 * n) * s / n;
    for (int y = by * block; y < y1; y++)
        for (int x = bx * block; x < x1; x++) {
            double m[3], var[3], se[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, var);
            for (int k = 0; k < 3; k++) se[k] = sqrt(var[k]);
            m[c] += delta;
            put(f, x, y, m, se);
        }
    return n;
}

static void test_identical_films_agree(void **state)
{
    (void)state;
    static const double zero[3] = {0, 0, 0};
    Film *a = make_film(40, 24), *b = make_film(40, 24);
    fill(a, 0.1, zero);
    fill(b, 0.1, zero);
    CompareResult r;
    CstError err = {0};
    double bz[6];
    assert_int_equal(compare_films(a, b, 16, 3.0, &r, bz, &err), CST_OK);
    assert_true(r.pass);
    assert_int_equal(r.blocks, 6); /* 3 x 2, the last column 8 wide and the last row 8 tall */
    assert_int_equal(r.blocks_failing, 0);
    assert_int_equal(r.zero_variance_disagreements, 0);
    for (int c = 0; c < 3; c++) assert_true(fabs(r.z_mean[c]) < 1e-9);
    assert_true(r.max_abs_block_z < 1e-9);
    for (int i = 0; i < 6; i++) assert_true(bz[i] < 1e-9);
    film_destroy(a);
    film_destroy(b);
}

static void test_offset_block_flagged(void **state)
{
    (void)state;
    static const double zero[3] = {0, 0, 0};
    enum { W = 40, H = 24, B = 16 };
    double zc = compare_z_critical(0.01, (double)compare_tests_per_pair(W, H, B)); /* 3.49 */
    Film *a = make_film(W, H), *b = make_film(W, H);
    fill(a, 0.1, zero);
    fill(b, 0.1, zero);
    /* Block (1, 0), green: 5 sigma of the block mean is far beyond z_crit ... */
    int n = shift_block(b, B, 1, 0, 1, 0.1, 5.0);
    CompareResult r;
    CstError err = {0};
    double bz[6];
    assert_int_equal(compare_films(a, b, B, zc, &r, bz, &err), CST_OK);
    assert_false(r.pass);
    assert_int_equal(r.blocks_failing, 1);
    assert_int_equal(r.worst_bx, 1);
    assert_int_equal(r.worst_by, 0);
    assert_int_equal(r.worst_channel, 1);
    assert_rel(r.max_abs_block_z, 5.0, 1e-9);
    assert_rel(bz[1], 5.0, 1e-9);
    assert_true(bz[0] < 1e-9 && bz[2] < 1e-9 && bz[3] < 1e-9);
    /* ... and dilutes in the image mean: n pixels shifted of W*H, z = -5 sqrt(n / (W H)). */
    assert_rel(r.z_mean[1], -5.0 * sqrt((double)n / (W * H)), 1e-9);
    assert_true(fabs(r.z_mean[0]) < 1e-9 && fabs(r.z_mean[2]) < 1e-9);

    /* 3 sigma in one block: not enough against 21 tests (z_crit 3.49), flagged by a single
     * test at the same alpha (z_crit 2.58). The correction costs power, as it must. */
    fill(b, 0.1, zero);
    shift_block(b, B, 2, 1, 0, 0.1, 3.0); /* the 8x8 corner block */
    assert_int_equal(compare_films(a, b, B, zc, &r, bz, &err), CST_OK);
    assert_true(r.pass);
    assert_rel(r.max_abs_block_z, 3.0, 1e-9);
    assert_int_equal(compare_films(a, b, B, compare_z_critical(0.01, 1.0), &r, bz, &err), CST_OK);
    assert_false(r.pass);
    assert_int_equal(r.blocks_failing, 1);
    assert_int_equal(r.worst_bx, 2);
    assert_int_equal(r.worst_by, 1);
    assert_int_equal(r.worst_channel, 0);
    assert_rel(bz[5], 3.0, 1e-9);
    film_destroy(a);
    film_destroy(b);
}

/* A partial block is tested with its own pixel count: 20x12 in blocks of 8 leaves a 4x4
 * corner; a shift giving z = 5 over 16 pixels must read 5, not 5 * 16/64 or similar. */
static void test_partial_block_uses_its_pixel_count(void **state)
{
    (void)state;
    static const double zero[3] = {0, 0, 0};
    Film *a = make_film(20, 12), *b = make_film(20, 12);
    fill(a, 0.05, zero);
    fill(b, 0.05, zero);
    assert_int_equal(shift_block(b, 8, 2, 1, 2, 0.05, -5.0), 16);
    CompareResult r;
    CstError err = {0};
    double bz[6];
    assert_int_equal(compare_films(a, b, 8, 4.0, &r, bz, &err), CST_OK);
    assert_rel(r.max_abs_block_z, 5.0, 1e-9);
    assert_int_equal(r.worst_bx, 2);
    assert_int_equal(r.worst_by, 1);
    assert_int_equal(r.worst_channel, 2);
    assert_int_equal(r.blocks_failing, 1);
    assert_rel(r.z_mean[2], 5.0 * sqrt(16.0 / 240.0), 1e-9);
    film_destroy(a);
    film_destroy(b);
}

static void test_zero_variance(void **state)
{
    (void)state;
    static const double zero[3] = {0, 0, 0};
    Film *a = make_film(16, 16), *b = make_film(16, 16);
    CompareResult r;
    CstError err = {0};
    double bz[4];

    /* Deterministic pixels, equal means: agreement, no division by zero. */
    fill(a, 0.0, zero);
    fill(b, 0.0, zero);
    assert_int_equal(compare_films(a, b, 8, 3.0, &r, bz, &err), CST_OK);
    assert_true(r.pass);
    assert_int_equal(r.zero_variance_disagreements, 0);
    assert_true(r.max_abs_block_z == 0.0);

    /* Equal up to float rounding of the same value (1e-7 relative): still equal. */
    double tiny[3] = {0.5 * 1e-7, 0.0, 0.0};
    fill(b, 0.0, tiny);
    assert_int_equal(compare_films(a, b, 8, 3.0, &r, bz, &err), CST_OK);
    assert_true(r.pass);

    /* One deterministic pixel differs in red: its block and the image mean disagree
     * outright (infinite z), counted, and fail whatever z_crit is. */
    fill(b, 0.0, zero);
    double m[3] = {0.6, 0.25, 0.125}, s0[3] = {0, 0, 0};
    put(b, 12, 3, m, s0); /* block (1, 0) */
    assert_int_equal(compare_films(a, b, 8, 1e300, &r, bz, &err), CST_OK);
    assert_false(r.pass);
    assert_int_equal(r.blocks_failing, 1);
    assert_int_equal(r.zero_variance_disagreements, 2); /* the block's red, the image's red */
    assert_true(r.z_mean[0] == -HUGE_VAL);
    assert_true(r.z_mean[1] == 0.0 && r.z_mean[2] == 0.0);
    assert_true(isinf(r.max_abs_block_z));
    assert_int_equal(r.worst_bx, 1);
    assert_int_equal(r.worst_by, 0);
    assert_true(isinf(bz[1]) && bz[0] == 0.0);

    /* Zero variance on one side only is an ordinary test: the other side's variance
     * carries it. a: deterministic 0.5; b: mean 0.5 + 2 s_b in one pixel, s_b = 0.1. */
    fill(b, 0.0, zero);
    double mb[3] = {0.7, 0.25, 0.125}, sb[3] = {0.1, 0.0, 0.0};
    put(b, 0, 0, mb, sb);
    assert_int_equal(compare_films(a, b, 8, 3.0, &r, bz, &err), CST_OK);
    assert_int_equal(r.zero_variance_disagreements, 0);
    assert_rel(bz[0], 2.0, 1e-9);
    assert_rel(r.z_mean[0], -2.0, 1e-9);
    assert_true(r.pass);
    film_destroy(a);
    film_destroy(b);
}

/* The false-alarm rate: pairs of films whose pixel means are independent draws around the
 * same truth, with the stated variances, fail at most alpha of the time (Sidak is exact for
 * independent tests, conservative for the correlated image mean and blocks here). */
static void test_false_alarm_rate(void **state)
{
    (void)state;
    enum { W = 32, H = 32, B = 8, TRIALS = 400 };
    const double alpha = 0.05, s = 0.1;
    double zc = compare_z_critical(alpha, (double)compare_tests_per_pair(W, H, B)); /* 51 tests */
    Film *f[2] = {make_film(W, H), make_film(W, H)};
    Pcg32 rng;
    pcg32_seed(&rng, 20240607u, 11u);
    int failures = 0;
    for (int t = 0; t < TRIALS; t++) {
        for (int k = 0; k < 2; k++)
            for (int y = 0; y < H; y++)
                for (int x = 0; x < W; x++) {
                    double m[3], se[3] = {s, s, s};
                    for (int c = 0; c < 3; c++) {
                        /* Box-Muller; u1 in (0, 1]. */
                        double u1 = 1.0 - (double)pcg32_float(&rng), u2 = (double)pcg32_float(&rng);
                        m[c] = 0.3 * (c + 1) + s * sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
                    }
                    put(f[k], x, y, m, se);
                }
        CompareResult r;
        CstError err = {0};
        assert_int_equal(compare_films(f[0], f[1], B, zc, &r, NULL, &err), CST_OK);
        failures += !r.pass;
    }
    print_message("false alarms: %d of %d at alpha %.2f (z_crit %.3f)\n", failures, TRIALS, alpha, zc);
    /* Binomial(400, <= 0.05): mean <= 20, sd 4.4. Too few would mean z is deflated. */
    assert_true(failures <= 36);
    assert_true(failures >= 6);
    film_destroy(f[0]);
    film_destroy(f[1]);
}

/* ------------------------------------------------------------------ convergence */

/* Fills f (2 spp) with the per-channel means base[c] + off[c] in every pixel, and a pixel
 * mean standard error s. */
static void fill_const(Film *f, const double base[3], const double off[3], double s)
{
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            double m[3] = {base[0] + off[0], base[1] + off[1], base[2] + off[2]}, se[3] = {s, s, s};
            put(f, x, y, m, se);
        }
}

/* Known answer: X's two renders are truth + bias +- e in every pixel (so their half
 * difference is e), the reference is the truth with pixel standard error s; on 8x8 blocks
 * t_b = 3 (bias^2 - e^2 - s^2 / 64) exactly, in every block. X's own film variances (here
 * 0.3) must not enter. */
static void test_convergence_level_known(void **state)
{
    (void)state;
    static const double truth[3] = {0.5, 0.25, 0.125}, zero[3] = {0, 0, 0};
    const double bias = 0.02, e = 0.005, s = 0.04;
    Film *r = make_film(24, 16), *x1 = make_film(24, 16), *x2 = make_film(24, 16);
    fill_const(r, truth, zero, s);
    double up[3] = {bias + e, bias + e, bias + e}, down[3] = {bias - e, bias - e, bias - e};
    fill_const(x1, truth, up, 0.3);
    fill_const(x2, truth, down, 0.3);
    double terms[6];
    ConvergenceLevel lv;
    CstError err = {0};
    assert_int_equal(compare_convergence_level(r, x1, x2, 8, terms, &lv, &err), CST_OK);
    assert_int_equal(lv.blocks, 6);
    double want = 3.0 * (bias * bias - e * e - s * s / 64.0);
    for (int b = 0; b < 6; b++) assert_rel(terms[b], want, 1e-9);
    assert_rel(lv.d2, want, 1e-9);
    assert_true(lv.d2_se < 1e-12); /* every block the same */
    for (int c = 0; c < 3; c++) assert_rel(lv.mean_diff[c], bias, 1e-9);
    /* Image-mean z: the sum's variance is 6 blocks x (64 e)^2 from X plus 384 s^2 from r. */
    for (int c = 0; c < 3; c++)
        assert_rel(lv.mean_z[c], 384.0 * bias / sqrt(6.0 * 64.0 * 64.0 * e * e + 384.0 * s * s), 1e-9);
    /* The arguments it refuses. */
    Film *small = make_film(8, 8), *one = make_film(24, 16);
    one->spp = 1;
    assert_int_equal(compare_convergence_level(r, x1, small, 8, terms, &lv, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(compare_convergence_level(one, x1, x2, 8, terms, &lv, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(compare_convergence_level(r, x1, x2, 0, terms, &lv, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(compare_convergence_level(r, x1, x2, 24, terms, &lv, &err), CST_ERR_INVALID_ARG);
    film_destroy(small);
    film_destroy(one);
    film_destroy(r);
    film_destroy(x1);
    film_destroy(x2);
}

static void test_convergence_step_and_judge(void **state)
{
    (void)state;
    const double a[4] = {4, 5, 6, 5}, b[4] = {1, 3, 2, 2};
    double diff, se;
    compare_convergence_step(a, b, 4, &diff, &se);
    assert_rel(diff, 3.0, 1e-12);                        /* differences 3, 2, 4, 3 */
    assert_rel(se, sqrt(2.0 / 3.0 / 4.0), 1e-12);        /* their sample variance 2/3, over 4 */
    compare_convergence_step(a, b, 1, &diff, &se);
    assert_true(isnan(se));

    ConvergenceLevel lv[3] = {{.d2 = 9.0, .d2_se = 1.0}, {.d2 = 5.0, .d2_se = 1.0}, {.d2 = 1.5, .d2_se = 1.0}};
    double sd[2] = {4.0, 3.5}, sse[2] = {1.0, 1.0};
    /* D_last = 1.5 <= 2 se: within noise, whatever the steps... */
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 2.0, 3.0), CONVERGENCE_WITHIN_NOISE);
    /* ...unless the image mean is off (here the steps then decide: they fall). */
    lv[2].mean_z[1] = -3.5;
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 2.0, 3.0), CONVERGENCE_SHRINKS);
    sd[0] = 1.0;
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 2.0, 3.0), CONVERGENCE_FAILS);
    sd[0] = 4.0;
    lv[2].mean_z[1] = 0.0;
    /* z = 1: D_last is significant, every step falls by more than 1 se. */
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 1.0, 3.0), CONVERGENCE_SHRINKS);
    /* A step that does not fall significantly (a bias floor). */
    sd[1] = 0.5;
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 1.0, 3.0), CONVERGENCE_FAILS);
    sd[1] = (double)NAN;
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 1.0, 3.0), CONVERGENCE_FAILS);
    lv[2].d2 = (double)NAN;
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 3, 2.0, 3.0), CONVERGENCE_FAILS);
    assert_int_equal(compare_convergence_judge(lv, sd, sse, 1, 2.0, 3.0), CONVERGENCE_FAILS);
}

/* One Gaussian draw (Box-Muller; u1 in (0, 1]). */
static double gauss(Pcg32 *rng)
{
    double u1 = 1.0 - (double)pcg32_float(rng), u2 = (double)pcg32_float(rng);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* Pixel means truth + bias(x, y) + noise of standard deviation s; the film claims
 * variance vs^2 (X's claim is not used; the reference's is). */
static void fill_noisy(Film *f, Pcg32 *rng, double s, double vs, double bias, bool bias_in_blocks)
{
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            /* A block-level bias pattern of zero image mean: +bias and -bias in a
             * checkerboard of 8x8 blocks (as edges darken and caustics brighten). */
            double b = bias_in_blocks ? ((x / 8 + y / 8) % 2 ? bias : -bias) : bias;
            double m[3], se[3] = {vs, vs, vs};
            for (int c = 0; c < 3; c++) m[c] = 0.3 * (c + 1) + b + s * gauss(rng);
            put(f, x, y, m, se);
        }
}

/* The statistics of the rule on synthetic renders (64 blocks of 8x8 pixels): an unbiased
 * X is called "within noise" about 1 - alpha of the time; a biased one whose bias halves
 * per level passes by shrinking; one whose bias stays (a bug) fails. */
static void test_convergence_rates(void **state)
{
    (void)state;
    enum { W = 64, H = 64, B = 8, K = 3, TRIALS = 200 };
    const double alpha = 0.05, s = 0.1;
    /* Sidak over the 4 tests of "within noise": D one-sided, the image mean two-sided. */
    const double a1 = compare_sidak_alpha(alpha, 4.0);
    const double z = -compare_normal_quantile(a1), z_mean = -compare_normal_quantile(0.5 * a1);
    Film *r = make_film(W, H), *x[2] = {make_film(W, H), make_film(W, H)};
    Pcg32 rng;
    pcg32_seed(&rng, 20261122u, 3u);
    double terms[K][64];
    int outcomes[3][3] = {{0}}; /* [case][verdict] */
    for (int t = 0; t < TRIALS; t++)
        for (int kase = 0; kase < 3; kase++) {
            ConvergenceLevel lv[K];
            double sd[K - 1], sse[K - 1];
            for (int l = 0; l < K; l++) {
                fill_noisy(r, &rng, s, s, 0.0, false);
                /* case 0 unbiased; 1 block bias 0.08, 0.04, 0.02 (its noise: 0.1/8 per
                 * block mean, 0.0125); 2 a bias that stays at 0.04. */
                double bias = kase == 0 ? 0.0 : kase == 1 ? 0.08 / (1 << l) : 0.04;
                for (int k = 0; k < 2; k++) fill_noisy(x[k], &rng, s, 0.0, bias, true);
                CstError err = {0};
                assert_int_equal(compare_convergence_level(r, x[0], x[1], B, terms[l], &lv[l], &err), CST_OK);
            }
            for (int l = 0; l + 1 < K; l++) compare_convergence_step(terms[l], terms[l + 1], 64, &sd[l], &sse[l]);
            outcomes[kase][compare_convergence_judge(lv, sd, sse, K, z, z_mean)]++;
        }
    print_message("unbiased: %d within noise, %d shrinks, %d fails; halving bias: %d %d %d; "
                  "constant bias: %d %d %d (of %d)\n", outcomes[0][0], outcomes[0][1], outcomes[0][2],
                  outcomes[1][0], outcomes[1][1], outcomes[1][2], outcomes[2][0], outcomes[2][1],
                  outcomes[2][2], TRIALS);
    /* Unbiased: D_last > z se about alpha of the time (Binomial(200, 0.05): mean 10, sd 3.1),
     * and then it fails unless both steps happen to fall significantly. */
    assert_true(outcomes[0][2] <= 22);
    assert_true(outcomes[0][0] >= 170);
    /* Halving: bias 0.02 at the last level is 1.6 block standard errors, so D_last is
     * often significant; then both steps must be: 0.0064 - 0.0016 and 0.0016 - 0.0004
     * per channel, many standard errors each. */
    assert_int_equal(outcomes[1][2], 0);
    /* Constant: D_last ~ 3 x 0.0016 with se ~ 3e-4: always significant, never shrinking. */
    assert_int_equal(outcomes[2][2], TRIALS);
    film_destroy(r);
    film_destroy(x[0]);
    film_destroy(x[1]);
}

static void test_errors(void **state)
{
    (void)state;
    static const double zero[3] = {0, 0, 0};
    Film *a = make_film(8, 8), *b = make_film(8, 4);
    fill(a, 0.1, zero);
    fill(b, 0.1, zero);
    CompareResult r;
    CstError err = {0};
    assert_int_equal(compare_films(a, b, 4, 3.0, &r, NULL, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "8x8"));
    film_destroy(b);
    b = make_film(8, 8);
    fill(b, 0.1, zero);
    err.msg[0] = '\0';
    assert_int_equal(compare_films(a, b, 0, 3.0, &r, NULL, &err), CST_ERR_INVALID_ARG);
    assert_true(err.msg[0] != '\0');
    assert_int_equal(compare_films(a, b, 4, 0.0, &r, NULL, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(compare_films(a, b, 4, (double)NAN, &r, NULL, &err), CST_ERR_INVALID_ARG);
    b->spp = 1; /* no variance estimate */
    assert_int_equal(compare_films(a, b, 4, 3.0, &r, NULL, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "2 samples"));
    film_destroy(a);
    film_destroy(b);
}

/* ------------------------------------------------------------------ the map */

static void test_map_colours(void **state)
{
    (void)state;
    float c[3];
    const double zc = 4.0;
    compare_map_colour(0.0, zc, c);
    assert_true(c[0] == 0.0f && c[1] == 0.0f && c[2] == 0.0f);
    compare_map_colour(1.0, zc, c); /* a quarter of z_crit: half-way to blue */
    assert_true(c[0] == 0.0f && c[1] == 0.0f);
    assert_float_equal(image_linear_to_srgb(c[2]), 0.5f, 1e-5f);
    compare_map_colour(2.0, zc, c); /* z_crit / 2: blue */
    assert_true(c[0] == 0.0f && c[1] == 0.0f && c[2] == 1.0f);
    compare_map_colour(3.0, zc, c); /* half-way from blue to yellow: sRGB grey 0.5 */
    for (int k = 0; k < 3; k++) assert_float_equal(image_linear_to_srgb(c[k]), 0.5f, 1e-5f);
    compare_map_colour(4.0, zc, c); /* at z_crit (still passing): yellow */
    assert_true(c[0] == 1.0f && c[1] == 1.0f && c[2] == 0.0f);
    compare_map_colour(4.001, zc, c); /* failing: red */
    assert_true(c[0] == 1.0f && c[1] == 0.0f && c[2] == 0.0f);
    compare_map_colour(HUGE_VAL, zc, c);
    assert_true(c[0] == 1.0f && c[1] == 0.0f && c[2] == 0.0f);
    compare_map_colour((double)NAN, zc, c);
    assert_true(c[0] == 1.0f && c[1] == 0.0f && c[2] == 0.0f);

    /* At image size, each pixel shows its block: 20x12 in blocks of 8 is 3x2 blocks. */
    double bz[6] = {0.0, 2.0, 4.0, 0.0, 0.0, 9.0};
    float *rgb = malloc(20 * 12 * 3 * sizeof *rgb);
    assert_non_null(rgb);
    compare_map_image(bz, 20, 12, 8, zc, rgb);
    const float *p = &rgb[3 * (11 * 20 + 19)]; /* bottom-right pixel: block (2, 1) -> red */
    assert_true(p[0] == 1.0f && p[1] == 0.0f && p[2] == 0.0f);
    p = &rgb[3 * (7 * 20 + 15)]; /* block (1, 0) -> blue */
    assert_true(p[0] == 0.0f && p[2] == 1.0f);
    p = &rgb[3 * (8 * 20 + 15)]; /* block (1, 1) -> black */
    assert_true(p[0] == 0.0f && p[1] == 0.0f && p[2] == 0.0f);
    p = &rgb[3 * (0 * 20 + 16)]; /* block (2, 0) -> yellow */
    assert_true(p[0] == 1.0f && p[1] == 1.0f && p[2] == 0.0f);
    free(rgb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_quantile_known_values),
        cmocka_unit_test(test_quantile_domain_and_round_trip),
        cmocka_unit_test(test_sidak),
        cmocka_unit_test(test_identical_films_agree),
        cmocka_unit_test(test_offset_block_flagged),
        cmocka_unit_test(test_partial_block_uses_its_pixel_count),
        cmocka_unit_test(test_zero_variance),
        cmocka_unit_test(test_false_alarm_rate),
        cmocka_unit_test(test_convergence_level_known),
        cmocka_unit_test(test_convergence_step_and_judge),
        cmocka_unit_test(test_convergence_rates),
        cmocka_unit_test(test_errors),
        cmocka_unit_test(test_map_colours),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
