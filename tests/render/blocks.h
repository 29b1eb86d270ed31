/* Block-by-block comparison of two camera-integrator renders of a 32 x 24 image in 8 x 6
 * blocks (the tests of light sampling and emitting shapes): the renders, each block's and
 * the whole image's statistics, and the check at Z_LIMIT. Include after cmocka.h. */
#ifndef CST_TESTS_BLOCKS_H
#define CST_TESTS_BLOCKS_H

#include "render/render_util.h"
#include "scene/scene.h"

#define W 32
#define H 24
#define BX 8
#define BY 6
enum { R = (W / BX) * (H / BY) + 1 }; /* the blocks and the whole image */

/* Renders s (max_depth 3, 2 threads) and writes the blocks' statistics, then the whole
 * image's, to out[R]. */
static void render_blocks(Scene *s, CstIntegrator integ, int spp, uint64_t seed, RegionStat *out)
{
    CstError err;
    CstRenderSettings st = {0};
    st.width = W;
    st.height = H;
    st.spp = spp;
    st.integrator = integ;
    st.max_depth = 3;
    st.seed = seed;
    st.seed_set = 1;
    st.threads = 2;
    /* The standard errors come from the film's per-pixel variances, which assume
     * independent samples (and pixels): pinned to the independent sampler, not the default
     * zsobol, whose stratified samples and blue-noise pixels those variances misjudge. */
    st.sampler = CST_SAMPLER_INDEPENDENT;
    CstFilm *f = NULL;
    CstRenderStats stats;
    assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
    assert_int_equal(stats.nonfinite, 0);
    int k = 0;
    for (int by = 0; by < H; by += BY)
        for (int bx = 0; bx < W; bx += BX) out[k++] = region_stat(f, bx, by, bx + BX, by + BY);
    out[k] = region_stat(f, 0, 0, W, H);
    cst_film_destroy(f);
}

/* Every block of a and b within Z_LIMIT; returns the whole image's standard error b / a
 * (the mean over channels). */
static double compare_blocks(const char *what, const RegionStat *a, const RegionStat *b)
{
    double zmax = 0.0, ratio = 0.0;
    for (int i = 0; i < R; i++)
        for (int c = 0; c < 3; c++) {
            double z = z_score(a[i].mean[c], a[i].se[c], b[i].mean[c], b[i].se[c]);
            zmax = fmax(zmax, fabs(z));
            if (fabs(z) > Z_LIMIT)
                print_message("  %s block %d channel %d: %.5f +- %.5f vs %.5f +- %.5f, z = %.2f\n", what, i, c,
                              a[i].mean[c], a[i].se[c], b[i].mean[c], b[i].se[c], z);
            assert_true(fabs(z) <= Z_LIMIT);
        }
    for (int c = 0; c < 3; c++) ratio += b[R - 1].se[c] / a[R - 1].se[c] / 3.0;
    print_message("  %s: image mean %.5f +- %.5f vs %.5f +- %.5f (green), max |z| %.2f over %d comparisons; "
                  "standard error ratio %.2f at equal spp\n", what, a[R - 1].mean[1], a[R - 1].se[1],
                  b[R - 1].mean[1], b[R - 1].se[1], zmax, 3 * R, ratio);
    return ratio;
}

#endif
