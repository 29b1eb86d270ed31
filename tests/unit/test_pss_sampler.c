/* The primary-sample-space sampler of MLT (sampling/pss_sampler.c): chi-square of its
 * small-step (wrapped normal, lazily accumulated) and large-step (uniform) proposals
 * against their densities, restore on reject, and stationarity of a Metropolis chain
 * it drives on a target with a known density (detailed balance). Fixed seeds; each
 * p-value is compared with 6.3e-5, the two-sided tail beyond 4 standard errors. */
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
#include "sampling/pss_sampler.h"
#include "unit/chi2.h"

static const double P_MIN = 6.3e-5;
enum { BINS = 100 };

static void check_chi2(const double *obs, const double *expd, int n, const char *what)
{
    int dof;
    double stat, outside;
    double p = chi2_pvalue(obs, expd, n, &dof, &stat, &outside);
    print_message("%s: chi2 %.1f, dof %d, p %.4g\n", what, stat, dof, p);
    assert_true(outside == 0.0);
    assert_true(p >= P_MIN);
}

/* Expected counts of `n` draws of the wrapped normal of width w around 0, per bin, by
 * midpoint integration on 64 sub-cells. */
static void small_step_expected(double *expd, double w, double n)
{
    for (int b = 0; b < BINS; b++) {
        double sum = 0.0;
        for (int k = 0; k < 64; k++) sum += pss_small_step_pdf(0.0, ((double)b + ((double)k + 0.5) / 64.0) / BINS, w);
        expd[b] = n * sum / 64.0 / BINS;
    }
}

/* A small step read every iteration: the offset y - x (wrapped) follows the wrapped
 * normal of width sigma. sigma = 0.3 so that the wrap matters. Each proposal is
 * rejected, so all start from the same state: also checks the restore. */
static void test_small_step_density(void **state)
{
    (void)state;
    const int N = 400000;
    const double sigma = 0.3;
    PssSampler s;
    Pcg32 r;
    pcg32_seed(&r, 11, 3);
    pss_init(&s, r, sigma, 0.0f, 1);
    pss_start_iteration(&s);
    double x0 = (double)pss_next(&s);
    pss_accept(&s);
    double *obs = calloc(2 * BINS, sizeof *obs), *expd = obs + BINS;
    for (int i = 0; i < N; i++) {
        pss_start_iteration(&s);
        double y = (double)pss_next(&s);
        pss_reject(&s);
        double d = y - x0;
        d -= floor(d);
        int b = (int)(d * BINS);
        obs[b < BINS ? b : BINS - 1] += 1.0;
    }
    /* The restored state is the original one. */
    pss_start_iteration(&s);
    s.large_step = false;
    assert_int_equal(s.x[0].modified, 1);
    assert_true((float)s.x[0].value == (float)x0);
    small_step_expected(expd, sigma, N);
    check_chi2(obs, expd, BINS, "small step");
    free(obs);
    pss_free(&s);
}

/* A coordinate not read for k iterations gets the k missed small steps at once: width
 * sigma sqrt(k) (Kelemen et al. 2002 sec. 4.2). Stream 1 is read only at the end while
 * stream 0 is read and accepted in every iteration. */
static void test_lazy_small_steps(void **state)
{
    (void)state;
    const int N = 100000, K = 6;
    const double sigma = 0.07;
    double *obs = calloc(2 * BINS, sizeof *obs), *expd = obs + BINS;
    for (int t = 0; t < N; t++) {
        PssSampler s;
        Pcg32 r;
        pcg32_seed(&r, 1000 + (uint64_t)t, 7);
        pss_init(&s, r, sigma, 0.0f, 2);
        pss_start_iteration(&s);
        (void)pss_next(&s);
        pss_start_stream(&s, 1);
        double x1 = (double)pss_next(&s);
        pss_accept(&s);
        for (int k = 0; k < K; k++) {
            pss_start_iteration(&s);
            (void)pss_next(&s);
            pss_accept(&s);
        }
        /* Read at iteration K + 2: K + 1 small steps since its value was set. */
        pss_start_iteration(&s);
        pss_start_stream(&s, 1);
        double d = (double)pss_next(&s) - x1;
        d -= floor(d);
        int b = (int)(d * BINS);
        obs[b < BINS ? b : BINS - 1] += 1.0;
        pss_free(&s);
    }
    small_step_expected(expd, sigma * sqrt((double)(K + 1)), N);
    check_chi2(obs, expd, BINS, "lazy small steps");
    free(obs);
}

/* Large steps: every value uniform, and independent of the previous one (2-D histogram
 * of (previous, proposed) on 20 x 20 cells). */
static void test_large_step_density(void **state)
{
    (void)state;
    const int N = 400000, C = 20;
    PssSampler s;
    Pcg32 r;
    pcg32_seed(&r, 5, 9);
    pss_init(&s, r, 0.01, 1.0f, 3);
    double *obs = calloc(2 * (size_t)(C * C), sizeof *obs), *expd = obs + C * C;
    pss_start_iteration(&s);
    pss_start_stream(&s, 2);
    double prev = (double)pss_next(&s);
    pss_accept(&s);
    for (int i = 0; i < N; i++) {
        pss_start_iteration(&s);
        pss_start_stream(&s, 2);
        double y = (double)pss_next(&s);
        assert_true(y >= 0.0 && y < 1.0);
        pss_accept(&s);
        obs[(int)(prev * C) * C + (int)(y * C)] += 1.0;
        prev = y;
    }
    for (int c = 0; c < C * C; c++) expd[c] = (double)N / (C * C);
    check_chi2(obs, expd, C * C, "large step");
    free(obs);
    pss_free(&s);
}

/* Target density on [0,1)^2: f(x, y) = (x^2 + 0.1)(1.5 - y), normalised by its integral
 * (1/3 + 0.1) * 1. Not periodic, so the wrap at 0 and 1 is exercised. */
static double target(double x, double y) { return (x * x + 0.1) * (1.5 - y); }
static double target_x_cdf(double x) { return (x * x * x / 3.0 + 0.1 * x) / (1.0 / 3.0 + 0.1); }
static double target_y_cdf(double y) { return (1.5 * y - 0.5 * y * y) / 1.0; }

/* Stationarity: chains started from exact samples of the target (rejection sampling),
 * run M Metropolis steps with the sampler's proposals (large step probability 0.3,
 * sigma 0.1) and acceptance min(1, f(y)/f(x)); the final states are independent draws,
 * which follow the target iff the kernel satisfies detailed balance. Both marginals are
 * tested. */
static void test_metropolis_stationary(void **state)
{
    (void)state;
    const int N = 100000, M = 20;
    double *obs = calloc(4 * BINS, sizeof *obs), *expd = obs + BINS, *obs_y = obs + 2 * BINS,
           *expd_y = obs + 3 * BINS;
    Pcg32 acc;
    pcg32_seed(&acc, 77, 1);
    for (int t = 0; t < N; t++) {
        PssSampler s;
        Pcg32 r;
        pcg32_seed(&r, 5000 + (uint64_t)t, 11);
        pss_init(&s, r, 0.1, 0.3f, 1);
        double x, y;
        do {
            x = (double)pcg32_float(&acc);
            y = (double)pcg32_float(&acc);
        } while ((double)pcg32_float(&acc) * 1.5 * 1.1 >= target(x, y));
        /* Put the exact sample in as the chain's state. */
        pss_start_iteration(&s);
        (void)pss_next(&s);
        (void)pss_next(&s);
        s.x[0].value = x;
        s.x[1].value = y;
        pss_accept(&s);
        double fx = target(x, y);
        for (int m = 0; m < M; m++) {
            pss_start_iteration(&s);
            double px = (double)pss_next(&s);
            double py = (double)pss_next(&s);
            double fy = target(px, py);
            if ((double)pcg32_float(&acc) * fx < fy) {
                pss_accept(&s);
                x = px; y = py; fx = fy;
            } else {
                pss_reject(&s);
            }
        }
        obs[(int)(x * BINS)] += 1.0;
        obs_y[(int)(y * BINS)] += 1.0;
        pss_free(&s);
    }
    for (int b = 0; b < BINS; b++) {
        expd[b] = N * (target_x_cdf((b + 1.0) / BINS) - target_x_cdf((double)b / BINS));
        expd_y[b] = N * (target_y_cdf((b + 1.0) / BINS) - target_y_cdf((double)b / BINS));
    }
    check_chi2(obs, expd, BINS, "stationary x");
    check_chi2(obs_y, expd_y, BINS, "stationary y");
    free(obs);
}

/* A proposal rejected leaves values read only by it undone too: a new coordinate read
 * by a rejected proposal keeps its uniform start, not the mutated value. */
static void test_reject_restores(void **state)
{
    (void)state;
    PssSampler s;
    Pcg32 r;
    pcg32_seed(&r, 3, 3);
    pss_init(&s, r, 0.01, 0.0f, 1);
    pss_start_iteration(&s);
    float a = pss_next(&s);
    pss_accept(&s);
    pss_start_iteration(&s);
    float a2 = pss_next(&s);
    assert_true(a2 != a);
    pss_reject(&s);
    assert_true((float)s.x[0].value == a);
    assert_int_equal(s.iteration, 1);
    pss_free(&s);
}

/* explain's replay (pss_replay_init): a chain's proposal values and its current state's (the
 * backups of what the proposal changed) read back as the chain read them, over three
 * interleaved streams, with a value of exactly 1 (a wrap's rounding) read as the chain
 * would (the float below 1). Broken (the values dated before the iteration, so that a small
 * step of sigma 0.05 moves them; or a value of 1 wrapped to 0): differs. */
static void test_replay(void **state)
{
    (void)state;
    PssSampler s;
    Pcg32 r;
    pcg32_seed(&r, 11, 5);
    pss_init(&s, r, 0.05, 0.3f, 3);
    enum { N = 7, STEPS = 40 };
    float cur[3][N];
    for (int k = 0; k < STEPS; k++) {
        pss_start_iteration(&s);
        float got[3][N];
        for (int st = 2; st >= 0; st--) { /* streams in any order */
            pss_start_stream(&s, st);
            for (int i = 0; i < N; i++) got[st][i] = pss_next(&s);
        }
        double prop[3 * N], old[3 * N];
        for (size_t i = 0; i < s.n; i++) {
            prop[i] = s.x[i].value;
            old[i] = s.x[i].modified == s.iteration ? s.x[i].backup : s.x[i].value;
        }
        for (int which = 0; which < (k > 0 ? 2 : 1); which++) {
            PssSampler q;
            assert_true(pss_replay_init(&q, which ? old : prop, s.n, 3));
            for (int st = 0; st < 3; st++) {
                pss_start_stream(&q, st);
                for (int i = 0; i < N; i++) {
                    const float want = which ? cur[st][i] : got[st][i];
                    assert_memory_equal(&(float){pss_next(&q)}, &want, sizeof want);
                }
            }
            pss_free(&q);
        }
        if (k % 3 != 2) {
            pss_accept(&s);
            memcpy(cur, got, sizeof cur);
        } else {
            pss_reject(&s);
        }
    }
    pss_free(&s);
    /* A stored 1.0 reads as the largest float below 1, as to_unit_float gives it. */
    const double edge[2] = {1.0, 0.25};
    PssSampler q;
    assert_true(pss_replay_init(&q, edge, 2, 1));
    assert_true(pss_next(&q) == 0x1.fffffep-1f);
    assert_true(pss_next(&q) == 0.25f);
    pss_free(&q);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_small_step_density),
        cmocka_unit_test(test_lazy_small_steps),
        cmocka_unit_test(test_large_step_density),
        cmocka_unit_test(test_metropolis_stationary),
        cmocka_unit_test(test_reject_restores),
        cmocka_unit_test(test_replay),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
