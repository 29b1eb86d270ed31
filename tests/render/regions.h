/* The image regions the render tests compare between estimators (the whole image, then
 * square blocks), their statistics from a film or from independent renders, and the
 * comparison at Z_LIMIT standard errors. Include after cmocka.h. */
#ifndef CST_TESTS_REGIONS_H
#define CST_TESTS_REGIONS_H

#include <math.h>
#include <string.h>

#include "render/render_util.h"

enum { REGIONS_MAX = 1 + 16 };

typedef struct Regions {
    int count;
    int rect[REGIONS_MAX][4]; /* x0, y0, x1, y1 */
    RegionStat stat[REGIONS_MAX];
} Regions;

/* Region 0 is the whole size x size image, then its (size / block)^2 blocks in row order;
 * messages number them from -1 = whole image. */
static inline Regions regions(int size, int block)
{
    Regions r;
    memset(&r, 0, sizeof r);
    int n = size / block;
    r.rect[0][2] = r.rect[0][3] = size;
    r.count = 1;
    for (int b = 0; b < n * n; b++, r.count++) {
        r.rect[r.count][0] = (b % n) * block;
        r.rect[r.count][1] = (b / n) * block;
        r.rect[r.count][2] = r.rect[r.count][0] + block;
        r.rect[r.count][3] = r.rect[r.count][1] + block;
    }
    assert_true(r.count <= REGIONS_MAX);
    return r;
}

/* Standard errors from the film's per-pixel variances: right for camera integrators,
 * whose pixel estimates are independent. */
static inline void film_regions(const CstFilm *f, Regions *r)
{
    for (int i = 0; i < r->count; i++)
        r->stat[i] = region_stat(f, r->rect[i][0], r->rect[i][1], r->rect[i][2], r->rect[i][3]);
}

/* Renders `base` with `integ`, spp samples and seed; fails on an error or on NaN/Inf. */
static inline CstFilm *render_film(const CstScene *s, const CstRenderSettings *base, CstIntegrator integ, int spp,
                                   uint64_t seed)
{
    CstRenderSettings st = *base;
    st.integrator = integ;
    st.spp = spp;
    st.seed = seed;
    st.seed_set = 1;
    /* The standard errors come from the film's per-pixel variances, which assume
     * independent samples (and pixels): pinned to the independent sampler, not the default
     * zsobol, whose stratified samples and blue-noise pixels those variances misjudge. */
    if (st.sampler == CST_SAMPLER_DEFAULT) st.sampler = CST_SAMPLER_INDEPENDENT;
    CstFilm *f = NULL;
    CstRenderStats stats;
    CstError err;
    if (cst_render(s, &st, &f, &stats, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(stats.nonfinite, 0);
    return f;
}

/* A pbrt-v4 test scene (`file`, under CST_SOURCE_DIR) rendered by caustic's path tracer in
 * spectral mode at 32 x 32 pixels, spp samples: its whole-image mean per channel within 1%
 * of pbrt-v4's (`pbrt_mean`, from the README beside the scene) plus Z_LIMIT standard
 * errors of caustic's. With the box filter the whole-image mean does not depend on the
 * resolution, so pbrt-v4's larger reference render stands for this one. */
static inline void pbrt_mean_check(const char *file, const double pbrt_mean[3], int spp, uint64_t seed,
                                   const char *what)
{
    CstScene *s = NULL;
    CstError err;
    CstLoadOptions opt = {0};
    if (cst_scene_load_pbrt(file, &opt, &s, &err) != CST_OK) fail_msg("%s", err.msg);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = 32;
    st.color_mode = CST_COLOR_SPECTRAL;
    CstFilm *f = render_film(s, &st, CST_INTEGRATOR_PATH, spp, seed);
    RegionStat r = region_stat(f, 0, 0, 32, 32);
    for (int c = 0; c < 3; c++) {
        double rel = (r.mean[c] - pbrt_mean[c]) / pbrt_mean[c];
        print_message("%s channel %d: caustic %.6f (se %.1e), pbrt-v4 %.6f: %+.2f%%\n", what, c, r.mean[c], r.se[c],
                      pbrt_mean[c], 100.0 * rel);
        if (!(fabs(r.mean[c] - pbrt_mean[c]) <= 0.01 * pbrt_mean[c] + Z_LIMIT * r.se[c]))
            fail_msg("%s channel %d: caustic %.6f vs pbrt-v4 %.6f (%+.2f%%, se %.1e)", what, c, r.mean[c],
                     pbrt_mean[c], 100.0 * rel, r.se[c]);
    }
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

/* Renders with a camera integrator and takes the film's statistics. */
static inline void camera_regions(const CstScene *s, const CstRenderSettings *base, CstIntegrator integ, int spp,
                                  uint64_t seed, Regions *r)
{
    CstFilm *f = render_film(s, base, integ, spp, seed);
    film_regions(f, r);
    cst_film_destroy(f);
}

/* Splatting integrators: their pixels are correlated within an iteration, so the errors
 * come from `renders` independent renders (region_stats_by_render). */
static inline void split_regions(const CstScene *s, const CstRenderSettings *base, CstIntegrator integ,
                                 int renders, uint64_t seed, Regions *r)
{
    CstRenderSettings st = *base;
    st.integrator = integ;
    CstError err;
    if (region_stats_by_render(s, &st, renders, seed, r->count, (const int (*)[4])r->rect, r->stat, NULL,
                               &err) != CST_OK)
        fail_msg("%s", err.msg);
}

/* Renders st (integrator, seed and size set by the caller) of scene s with 1 and with 2
 * threads: the films must be equal bit for bit, and not black. */
static inline void assert_threads_bit_identical(const CstScene *s, CstRenderSettings st)
{
    CstFilm *f[2] = {NULL, NULL};
    CstError err;
    for (int k = 0; k < 2; k++) {
        st.threads = k + 1;
        CstRenderStats stats;
        if (cst_render(s, &st, &f[k], &stats, &err) != CST_OK) fail_msg("%s", err.msg);
    }
    double sum = 0.0;
    for (int y = 0; y < st.height; y++)
        for (int x = 0; x < st.width; x++) {
            double a[3], b[3];
            cst_film_pixel(f[0], x, y, a);
            cst_film_pixel(f[1], x, y, b);
            assert_memory_equal(a, b, sizeof a);
            sum += a[0];
        }
    assert_true(sum > 0.0);
    cst_film_destroy(f[0]);
    cst_film_destroy(f[1]);
}

/* The start of a JSON scene (film, camera, one diffuse emitting sphere) to which a test
 * appends its "integrator" section and the closing brace. */
#define TEST_JSON_EMITTER_HEAD                                                                                \
    "{\"film\": {\"width\": 8, \"height\": 8}, \"camera\": {\"type\": \"pinhole\", "                        \
    "\"position\": [0, 0, 0], \"look_at\": [0, 0, -1], \"up\": [0, 1, 0], \"fov\": 45}, "                       \
    "\"materials\": {\"w\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}}, "                        \
    "\"shapes\": [{\"type\": \"sphere\", \"material\": \"w\", \"center\": [0, 0, -3], "                       \
    "\"radius\": 1, \"emission\": {\"radiance\": [1, 1, 1]}}], "

/* Fails at |z| > Z_LIMIT on any region and channel; prints the whole image's red means
 * and z, and the largest |z|. */
static inline void compare(const Regions *a, const Regions *b, const char *na, const char *nb)
{
    assert_int_equal(a->count, b->count);
    double worst = 0.0;
    int worst_block = -2, worst_c = 0;
    for (int i = 0; i < a->count; i++)
        for (int c = 0; c < 3; c++) {
            double z = z_score(a->stat[i].mean[c], a->stat[i].se[c], b->stat[i].mean[c], b->stat[i].se[c]);
            if (fabs(z) > fabs(worst)) { worst = z; worst_block = i - 1; worst_c = c; }
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("%s vs %s: block %d (-1 = whole image) channel %d: %.6f vs %.6f, z = %.2f", na, nb, i - 1,
                         c, a->stat[i].mean[c], b->stat[i].mean[c], z);
        }
    double z0 = z_score(a->stat[0].mean[0], a->stat[0].se[0], b->stat[0].mean[0], b->stat[0].se[0]);
    print_message("%s vs %s: whole image (r) %.5f vs %.5f (z = %.2f), largest |z| = %.2f (block %d, channel %d)\n",
                  na, nb, a->stat[0].mean[0], b->stat[0].mean[0], z0, fabs(worst), worst_block, worst_c);
}

#endif
