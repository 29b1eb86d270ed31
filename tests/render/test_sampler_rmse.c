/* Low-discrepancy samplers reach the independent sampler's RMSE on the Cornell box (path
 * tracer, 32 x 32) with fewer samples: Sobol' at N/2 and stratified at 3N/4 samples per
 * pixel beat independent at N = 64, each by at least 4 standard errors.
 *
 * No reference image is needed. Every sampler is unbiased, so a render's MSE is its
 * variance. Independent sampling's MSE at N spp is exactly sigma^2 / N, with sigma^2 the
 * per-sample variance, measured from the films' sums of squares (8 renders of 128 spp;
 * the spread of the 8 gives its standard error). The other samplers' variance is measured
 * across 16 renders with different seeds (per pixel, averaged over pixels and channels;
 * standard error by the jackknife over the renders). The ratio sigma^2 / (M MSE(M)) is
 * how many more samples independent sampling needs for the same RMSE.
 *
 * Measured here (seeds as below): sobol at 32 spp: 6.7x, z = 14.1; stratified at 48 spp:
 * 3.0x, z = 9.7. Independent's RMSE at 64 spp is reached by sobol at about 18 spp (ratio
 * 3.6) and by stratified at about 27 (2.4): docs/benchmarks.md.
 * Most of the gain is at the light's edges, where the film position decides the sample
 * (antialiasing converges faster than 1/N with stratified positions). */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "film/film.h"
#include "scene/scene.h"

enum { SIZE = 32, N_INDEPENDENT = 64, GROUPS = 8, GROUP_SPP = 128, REPLICAS = 16 };

static Film *render(const CstScene *s, CstSampler sampler, int spp, uint64_t seed)
{
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = spp;
    st.threads = 2;
    st.seed = seed;
    st.seed_set = 1;
    st.sampler = sampler;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    return f;
}

/* Per-sample variance of independent sampling, averaged over pixels and channels. */
static void independent_sigma2(const CstScene *s, double *mean, double *se)
{
    double g[GROUPS], a = 0.0, b = 0.0;
    for (int k = 0; k < GROUPS; k++) {
        Film *f = render(s, CST_SAMPLER_INDEPENDENT, GROUP_SPP, 500 + (uint64_t)k);
        double t = 0.0, v[3];
        for (int y = 0; y < SIZE; y++)
            for (int x = 0; x < SIZE; x++) {
                cst_film_pixel_variance(f, x, y, v); /* of the mean: times spp per sample */
                t += v[0] + v[1] + v[2];
            }
        g[k] = t / (3.0 * SIZE * SIZE) * GROUP_SPP;
        a += g[k];
        b += g[k] * g[k];
        film_destroy(f);
    }
    *mean = a / GROUPS;
    *se = sqrt((b - GROUPS * *mean * *mean) / (GROUPS - 1) / GROUPS);
}

/* Variance across replicas of pixel means, averaged over pixels and channels, leaving
 * replica `skip` out (-1: none). */
static double replica_variance(double (*x)[SIZE * SIZE * 3], int skip)
{
    int k2 = REPLICAS - (skip >= 0);
    double tot = 0.0;
    for (size_t i = 0; i < SIZE * SIZE * 3; i++) {
        double s = 0.0, q = 0.0;
        for (int k = 0; k < REPLICAS; k++) {
            if (k == skip) continue;
            s += x[k][i];
            q += x[k][i] * x[k][i];
        }
        double m = s / k2;
        tot += (q - k2 * m * m) / (k2 - 1);
    }
    return tot / (SIZE * SIZE * 3);
}

static void sampler_mse(const CstScene *s, CstSampler sampler, int spp, double *mse, double *se)
{
    double (*x)[SIZE * SIZE * 3] = malloc(REPLICAS * sizeof *x);
    assert_non_null(x);
    for (int k = 0; k < REPLICAS; k++) {
        Film *f = render(s, sampler, spp, 1000 + (uint64_t)k);
        for (size_t i = 0; i < SIZE * SIZE * 3; i++) x[k][i] = f->sum[i] / spp;
        film_destroy(f);
    }
    *mse = replica_variance(x, -1);
    double a = 0.0, b = 0.0; /* jackknife (Efron & Tibshirani 1993, eq. 11.5) */
    for (int k = 0; k < REPLICAS; k++) {
        double j = replica_variance(x, k);
        a += j;
        b += j * j;
    }
    a /= REPLICAS;
    *se = sqrt((REPLICAS - 1.0) / REPLICAS * (b - REPLICAS * a * a));
    free(x);
}

static void test_fewer_samples_for_equal_rmse(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    double sigma2, sigma2_se;
    independent_sigma2(s, &sigma2, &sigma2_se);
    const double target = sigma2 / N_INDEPENDENT, target_se = sigma2_se / N_INDEPENDENT;
    const struct { CstSampler sampler; int spp; } cases[] = {
        {CST_SAMPLER_SOBOL, N_INDEPENDENT / 2},
        {CST_SAMPLER_STRATIFIED, 3 * N_INDEPENDENT / 4},
    };
    for (size_t c = 0; c < sizeof cases / sizeof cases[0]; c++) {
        double mse, se;
        sampler_mse(s, cases[c].sampler, cases[c].spp, &mse, &se);
        double z = (target - mse) / sqrt(target_se * target_se + se * se);
        printf("%s at %d spp: MSE %.3g +- %.2g; independent at %d spp: %.3g +- %.2g; z = %.1f; "
               "independent needs %.2fx the samples for this RMSE\n",
               cst_sampler_name(cases[c].sampler), cases[c].spp, mse, se, N_INDEPENDENT, target,
               target_se, z, sigma2 / (cases[c].spp * mse));
        if (!(z >= 4.0))
            fail_msg("%s at %d spp does not reach the RMSE of independent at %d spp (z = %.2f)",
                     cst_sampler_name(cases[c].sampler), cases[c].spp, N_INDEPENDENT, z);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_fewer_samples_for_equal_rmse),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
