/* --noise (render/adaptive.h): the estimated block errors agree with the errors measured
 * against a longer reference render; the target is met; the rounds are the same for 1 and
 * 2 threads and through a state file; a block of n samples holds exactly a uniform n-spp
 * render's sums; bad targets and integrators without variances are refused. */
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
#include "film/film_state.h"
#include "render/adaptive.h"
#include "scene/scene.h"
#include "unit/scratch_dir.h"

static CstScene *g_box;

static CstRenderSettings settings(int w, int h, double target, int spp, int threads, uint64_t seed)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = w;
    st.height = h;
    st.noise_target = target;
    st.spp = spp > 0 ? spp : CST_SPP_UNLIMITED; /* not the built-in box's 64 */
    st.threads = threads;
    st.seed = seed;
    st.seed_set = 1;
    return st;
}

static Film *render(const CstRenderSettings *st, CstRenderStats *stats)
{
    CstFilm *f = NULL;
    CstError err;
    CstStatus s = cst_render(g_box, st, &f, stats, &err);
    if (s != CST_OK) fail_msg("cst_render: %s", err.msg);
    return f;
}

static int films_identical(const Film *a, const Film *b)
{
    const size_t n = (size_t)a->width * (size_t)a->height;
    return a->width == b->width && a->height == b->height && a->spp == b->spp && !a->pixel_spp == !b->pixel_spp &&
           memcmp(a->sum, b->sum, 3 * n * sizeof *a->sum) == 0 &&
           memcmp(a->sum_sq, b->sum_sq, 3 * n * sizeof *a->sum_sq) == 0 &&
           (!a->pixel_spp || memcmp(a->pixel_spp, b->pixel_spp, n * sizeof *a->pixel_spp) == 0);
}

/* Block t's mean luminance (adaptive.c's weights) and its estimated standard error. */
static void block_mean(const Film *f, const AdaptiveGrid *g, int t, double *mean, double *se)
{
    int x0, y0, x1, y1;
    adaptive_tile_rect(g, t, &x0, &y0, &x1, &y1);
    double sum = 0.0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double rgb[3];
            cst_film_pixel(f, x, y, rgb);
            sum += 0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2];
        }
    *mean = sum / ((x1 - x0) * (y1 - y0));
    *se = adaptive_block_noise(f, x0, y0, x1, y1).rel * *mean;
}

/* The statistical test: each block's mean of a --noise render against a uniform render of
 * twice its most samples (another seed), the difference over the two estimated errors in
 * quadrature: with correct estimates the sum of the B squares is chi-square with B dof,
 * mean B, sd sqrt(2B). Accepted within 4 sd; the luminance bound (adaptive.c) may only
 * make the estimates larger, and optional stopping (a block stops when its estimate is
 * low) smaller. Measured at the commit: see the printed line. */
static void test_estimate_matches_reference(void **state)
{
    (void)state;
    const double target = 0.03;
    CstRenderSettings st = settings(96, 96, target, 0, 2, 1);
    CstRenderStats stats;
    Film *f = render(&st, &stats);
    assert_true(stats.noise_max <= target);
    assert_int_equal(stats.noise_blocks_over, 0);
    assert_true(stats.spp_min >= ADAPTIVE_MIN_SPP && stats.spp_min < stats.spp); /* adaptive */
    CstRenderSettings rs = settings(96, 96, 0.0, 2 * stats.spp, 2, 2);
    Film *ref = render(&rs, NULL);
    const int crop[4] = {0, 96, 0, 96};
    const AdaptiveGrid g = adaptive_grid(crop);
    double chi2 = 0.0, measured2 = 0.0;
    for (int t = 0; t < g.tiles; t++) {
        double m, se, mr, ser;
        block_mean(f, &g, t, &m, &se);
        block_mean(ref, &g, t, &mr, &ser);
        chi2 += (m - mr) * (m - mr) / (se * se + ser * ser);
        measured2 += (m - mr) * (m - mr) / (mr * mr);
    }
    const double B = g.tiles, lo = B - 4.0 * sqrt(2.0 * B), hi = B + 4.0 * sqrt(2.0 * B);
    print_message("noise %.3g: %d blocks, %d-%d spp; chi2 %.1f (accepted [%.1f, %.1f]); estimated rms %.4g "
                  "(95%% CI %.4g-%.4g), measured rms %.4g against the reference (its own error included)\n",
                  target, g.tiles, stats.spp_min, stats.spp, chi2, lo, hi, stats.noise_rms, stats.noise_rms_lo,
                  stats.noise_rms_hi, sqrt(measured2 / B));
    assert_true(chi2 >= lo && chi2 <= hi);
    film_destroy(f);
    film_destroy(ref);
}

/* A loose target: met by the first round, every block with the minimum samples. */
static void test_loose_target_stops(void **state)
{
    (void)state;
    CstRenderSettings st = settings(64, 64, 0.05, 0, 2, 1);
    CstRenderStats stats;
    Film *f = render(&st, &stats);
    assert_true(stats.noise_max <= 0.05 && stats.noise_max > 0.0);
    assert_int_equal(stats.spp, ADAPTIVE_MIN_SPP);
    assert_int_equal(stats.spp_min, ADAPTIVE_MIN_SPP);
    assert_true(stats.noise_rms_lo <= stats.noise_rms && stats.noise_rms <= stats.noise_rms_hi);
    film_destroy(f);
}

/* 1 and 2 threads, partial tiles (72 x 40), and a block of n samples equal to the same
 * pixels of a uniform n-spp render. */
static void test_determinism(void **state)
{
    (void)state;
    CstRenderSettings st = settings(72, 40, 0.02, 0, 1, 3);
    Film *one = render(&st, NULL);
    st.threads = 2;
    Film *two = render(&st, NULL);
    assert_true(films_identical(one, two));
    const int n = one->pixel_spp[0]; /* block 0 */
    CstRenderSettings us = settings(72, 40, 0.0, n, 2, 3);
    Film *uni = render(&us, NULL);
    for (int y = 0; y < 16; y++)
        assert_memory_equal(&one->sum[3 * (size_t)y * 72], &uni->sum[3 * (size_t)y * 72], 3 * 16 * sizeof(double));
    film_destroy(one);
    film_destroy(two);
    film_destroy(uni);
}

/* pass_done: stops the render after its first round. */
static int stop_after_one(void *user, const CstFilm *film, const CstPassInfo *info)
{
    (void)film;
    (void)info;
    return ++*(int *)user >= 1;
}

/* Stopped after the first round (as Ctrl-C stops it), written to a state file (format
 * version 2: the per-pixel counts), read back and resumed with the same settings: bit for
 * bit the uninterrupted render. */
static void test_resume(void **state)
{
    (void)state;
    char path[300];
    tpath(path, sizeof path, "noise.state");
    CstRenderSettings st = settings(64, 48, 0.015, 0, 2, 4);
    int calls = 0;
    st.pass_done = stop_after_one;
    st.pass_user = &calls;
    CstError err;
    CstRenderStats stats;
    Film *part = render(&st, &stats);
    assert_int_equal(stats.stopped, 1);
    assert_int_equal(part->spp, ADAPTIVE_MIN_SPP);
    assert_int_equal(cst_film_state_write(path, part, g_box, &st, "builtin:cornell-box", NULL, &err), CST_OK);
    CstRenderSettings full = settings(64, 48, 0.015, 0, 2, 4);
    CstFilm *resume = NULL;
    if (cst_film_state_read(path, g_box, &full, "builtin:cornell-box", &resume, &err) != CST_OK)
        fail_msg("cst_film_state_read: %s", err.msg);
    assert_true(films_identical(part, resume));
    full.resume = resume;
    Film *resumed = render(&full, NULL);
    full.resume = NULL;
    Film *whole = render(&full, NULL);
    assert_true(whole->spp > 2 * ADAPTIVE_MIN_SPP);
    assert_true(films_identical(resumed, whole));
    /* Another target is another render: refused by the key. */
    CstRenderSettings other = settings(64, 48, 0.02, 0, 2, 4);
    CstFilm *no = NULL;
    assert_int_equal(cst_film_state_read(path, g_box, &other, "builtin:cornell-box", &no, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "noise"));
    film_destroy(part);
    film_destroy(resume);
    film_destroy(resumed);
    film_destroy(whole);
}

/* A state of version 2 (per-pixel counts): every prefix, and a changed count, refused. */
static void test_state_v2_checked(void **state)
{
    (void)state;
    char path[300];
    tpath(path, sizeof path, "v2.state");
    CstRenderSettings st = settings(20, 18, 0.05, 0, 1, 6);
    CstError err;
    Film *f = render(&st, NULL);
    assert_int_equal(cst_film_state_write(path, f, g_box, &st, "builtin:cornell-box", NULL, &err), CST_OK);
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    static unsigned char bytes[1 << 16];
    const size_t len = fread(bytes, 1, sizeof bytes, fp);
    fclose(fp);
    assert_true(len > 20 * 18 * 4 && len < sizeof bytes);
    assert_int_equal(bytes[8], FILM_STATE_VERSION_PIXEL_SPP);
    StateKey *keys = calloc(STATE_KEYS_MAX, sizeof *keys);
    int nkeys;
    Film *back = NULL;
    assert_int_equal(film_state_read_mem("v2", bytes, len, &back, keys, &nkeys, &err), CST_OK);
    assert_true(films_identical(f, back));
    film_destroy(back);
    for (size_t n = 0; n < len; n++) {
        Film *g = NULL;
        if (film_state_read_mem("v2", bytes, n, &g, keys, &nkeys, &err) != CST_ERR_PARSE) fail_msg("prefix %zu read", n);
    }
    bytes[len - 4 - 4 * 7] ^= 1; /* a pixel's count */
    Film *g = NULL;
    assert_int_equal(film_state_read_mem("v2", bytes, len, &g, keys, &nkeys, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "CRC-32"));
    free(keys);
    film_destroy(f);
}

/* Light, bdpt, vcm: whole-image rounds, every pixel the same count. */
static void test_whole_image(void **state)
{
    (void)state;
    CstRenderSettings st = settings(32, 32, 0.05, 64, 2, 5);
    st.integrator = CST_INTEGRATOR_BDPT;
    CstRenderStats stats;
    Film *f = render(&st, &stats);
    assert_null(f->pixel_spp);
    assert_true(stats.noise_max <= 0.05 || stats.spp == 64);
    assert_int_equal(stats.spp_min, stats.spp);
    film_destroy(f);
}

static void test_refused(void **state)
{
    (void)state;
    const double bad[] = {-0.01, (double)NAN, (double)INFINITY};
    for (int k = 0; k < 3; k++) {
        CstRenderSettings st = settings(16, 16, bad[k], 0, 1, 1);
        CstFilm *f = NULL;
        CstError err;
        assert_int_equal(cst_render(g_box, &st, &f, NULL, &err), CST_ERR_INVALID_ARG);
        assert_null(f);
    }
    const CstIntegrator no[] = {CST_INTEGRATOR_SPPM, CST_INTEGRATOR_PSSMLT};
    for (int k = 0; k < 2; k++) {
        CstRenderSettings st = settings(16, 16, 0.05, 0, 1, 1);
        st.integrator = no[k];
        CstFilm *f = NULL;
        CstError err;
        assert_int_equal(cst_render(g_box, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
    }
    CstRenderSettings st = settings(16, 16, 0.05, 0, 1, 1);
    st.sample_block = 4;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(g_box, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
}

static int setup(void **state)
{
    (void)state;
    CstError err;
    if (cst_scene_create_cornell_box(&g_box, &err) != CST_OK) return -1;
    return scratch_dir_make("/tmp/caustic-test-noise-XXXXXX");
}

static int teardown(void **state)
{
    (void)state;
    cst_scene_destroy(g_box);
    return scratch_dir_remove();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_estimate_matches_reference),
        cmocka_unit_test(test_loose_target_stops),
        cmocka_unit_test(test_determinism),
        cmocka_unit_test(test_resume),
        cmocka_unit_test(test_state_v2_checked),
        cmocka_unit_test(test_whole_image),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
