/* Reconstruction filters: each normalised h integrates to 1, and filter importance
 * sampling with the weights h / pdf is unbiased: the weighted sample mean of test
 * functions g equals the integral of h g (within 4 standard errors, fixed seed). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "film/film.h"
#include "film/filter.h"
#include "render/render_util.h"

static const CstFilter TYPES[4] = {CST_FILTER_BOX, CST_FILTER_TENT, CST_FILTER_GAUSSIAN, CST_FILTER_MITCHELL};

static void test_normalised(void **state)
{
    (void)state;
    for (int k = 0; k < 4; k++) {
        Filter f;
        filter_init(&f, TYPES[k]);
        const int n = 200000;
        double sum = 0.0, r = (double)f.radius;
        for (int i = 0; i < n; i++) sum += (double)filter_eval1(&f, (float)(-r + 2.0 * r * (i + 0.5) / n));
        sum *= 2.0 * r / n;
        print_message("%s: integral of h1 %.6f (numeric norm %.6f)\n", cst_filter_name(TYPES[k]), sum, (double)f.norm);
        assert_true(fabs(sum - 1.0) < 2e-4);
        /* The closed-form normalisation filter_weight1 uses agrees with filter_init's. */
        if (TYPES[k] == CST_FILTER_GAUSSIAN || TYPES[k] == CST_FILTER_MITCHELL)
            assert_true(fabs((double)f.norm - (TYPES[k] == CST_FILTER_GAUSSIAN ? 1.2166034551268203 : 1.0)) < 1e-5);
    }
}

/* Test functions of the offset (x, y): constant, a quadratic that weighs the tails, and a
 * lopsided one. Their filtered values by a fine midpoint rule against the FIS estimate. */
static double g(int which, double x, double y)
{
    switch (which) {
    case 0: return 1.0;
    case 1: return x * x + 0.5 * y * y;
    default: return exp(0.7 * x) * (1.0 + 0.3 * y);
    }
}

static void test_importance_sampling_unbiased(void **state)
{
    (void)state;
    for (int k = 0; k < 4; k++) {
        Filter f;
        filter_init(&f, TYPES[k]);
        for (int which = 0; which < 3; which++) {
            const int m = 1200;
            double r = (double)f.radius, exact = 0.0, h = 2.0 * r / m;
            for (int j = 0; j < m; j++)
                for (int i = 0; i < m; i++) {
                    double x = -r + h * (i + 0.5), y = -r + h * (j + 0.5);
                    exact += (double)filter_eval1(&f, (float)x) * (double)filter_eval1(&f, (float)y) * g(which, x, y);
                }
            exact *= h * h;
            Pcg32 rng;
            pcg32_seed(&rng, 77u + (uint64_t)k, 5u + (uint64_t)which);
            const int n = 400000;
            double s = 0.0, s2 = 0.0;
            for (int i = 0; i < n; i++) {
                float w;
                Vec2 u = pcg32_v2(&rng);
                Vec2 d = filter_sample(&f, u, &w);
                assert_true(fabsf(d.x) <= f.radius && fabsf(d.y) <= f.radius);
                double v = (double)w * g(which, (double)d.x, (double)d.y);
                s += v;
                s2 += v * v;
            }
            double mean = s / n, se = sqrt((s2 / n - mean * mean) / n);
            double z = se > 0.0 ? (mean - exact) / se : (fabs(mean - exact) < 1e-9 ? 0.0 : (double)INFINITY);
            print_message("%s, g%d: FIS %.6f +- %.1e, quadrature %.6f, z = %.2f\n", cst_filter_name(TYPES[k]), which,
                          mean, se, exact, z);
            /* The quadrature's own error is ~1e-6; allow it next to 4 standard errors. */
            assert_true(fabs(mean - exact) <= Z_LIMIT * se + 1e-5 * fabs(exact) + 1e-6);
        }
    }
}

/* A splat reaches every pixel whose centre lies within the filter's radius, each with the
 * weight h(centre - position) the camera samples are weighted with, and no other pixel.
 * (A wide filter that splatted like the box would still agree with path tracing on the
 * smooth block means of the render tests; this sees it directly.) */
static void test_splat_weights(void **state)
{
    (void)state;
    enum { W = 16, H = 12 };
    Pcg32 rng;
    pcg32_seed(&rng, 4242u, 1u);
    for (int k = 0; k < 4; k++) {
        float r = filter_radius(TYPES[k]);
        SplatFrame fr = splat_frame(W, H, TYPES[k]);
        for (int trial = 0; trial < 200; trial++) {
            /* anywhere, including the margin outside the film and the borders */
            float x = -1.0f + (W + 2.0f) * pcg32_float(&rng), y = -1.0f + (H + 2.0f) * pcg32_float(&rng);
            SplatList l;
            assert_true(splat_list_init(&l, 16));
            film_splat(&l, &fr, x, y, color_s(1.0f));
            double expect[W * H] = {0}, got[3 * W * H] = {0};
            for (int py = 0; py < H; py++)
                for (int px = 0; px < W; px++) {
                    float dx = (float)px + 0.5f - x, dy = (float)py + 0.5f - y;
                    if (TYPES[k] == CST_FILTER_BOX)
                        expect[py * W + px] = (px == (int)floorf(x) && py == (int)floorf(y)) ? 1.0 : 0.0;
                    else if (fabsf(dx) <= r && fabsf(dy) <= r)
                        expect[py * W + px] = (double)filter_weight1(TYPES[k], dx) * (double)filter_weight1(TYPES[k], dy);
                }
            film_add_splats(&l, &fr, got, 1.0);
            for (int i = 0; i < W * H; i++) {
                if (fabs(got[3 * i] - expect[i]) > 1e-6) {
                    print_message("%s splat at (%.3f, %.3f): pixel %d got %.6f, expected %.6f\n",
                                  cst_filter_name(TYPES[k]), (double)x, (double)y, i, got[3 * i], expect[i]);
                    fail();
                }
            }
            splat_list_free(&l);
        }
    }
}

/* Merging band by band (rows of 1 and 2, so footprints straddle bands) gives every pixel
 * exactly the sum of adding the whole list in order: same additions, same order. */
static void test_splat_bands(void **state)
{
    (void)state;
    enum { W = 13, H = 11, N = 3000 };
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 3u);
    for (int k = 0; k < 4; k++) {
        SplatFrame fr = splat_frame(W, H, TYPES[k]);
        SplatList l;
        assert_true(splat_list_init(&l, 16));
        for (int i = 0; i < N; i++) {
            float x = -2.0f + (W + 4.0f) * pcg32_float(&rng), y = -2.0f + (H + 4.0f) * pcg32_float(&rng);
            float cb = 1.0f + pcg32_float(&rng), cg = pcg32_float(&rng), cr = pcg32_float(&rng);
            film_splat(&l, &fr, x, y, color_rgb(cr, cg, cb));
        }
        static double whole[3 * W * H], banded[3 * W * H];
        memset(whole, 0, sizeof whole);
        film_add_splats(&l, &fr, whole, 0.37);
        for (int rows = 1; rows <= 2; rows++) {
            SplatFrame fb = fr;
            fb.band_shift = rows - 1;
            fb.band_rows = 1 << fb.band_shift;
            fb.bands = (H + fb.band_rows - 1) / fb.band_rows;
            assert_true(splat_list_bin(&l, &fb));
            memset(banded, 0, sizeof banded);
            for (int b = fb.bands - 1; b >= 0; b--) film_add_splats_band(&l, &fb, banded, 0.37, b);
            assert_memory_equal(whole, banded, sizeof whole);
        }
        assert_int_equal(l.oom, 0);
        splat_list_free(&l);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_normalised),
        cmocka_unit_test(test_importance_sampling_unbiased),
        cmocka_unit_test(test_splat_weights),
        cmocka_unit_test(test_splat_bands),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
