/* Consistency: BSDF-only, NEE-only and MIS path tracing estimate the same integral, so
 * their Cornell box images must agree within noise, per channel, on the image mean and
 * on every 32x32 block. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "render/render_util.h"

enum { SIZE = 128, BLOCK = 32 };

static CstFilm *render_cornell(CstIntegrator integ, int spp, uint64_t seed)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = spp;
    st.integrator = integ;
    st.seed = seed;
    st.seed_set = 1;
    CstFilm *f = NULL;
    CstRenderStats stats;
    assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
    assert_int_equal(stats.nonfinite, 0);
    cst_scene_destroy(s);
    return f;
}

static void compare(const CstFilm *a, const CstFilm *b, const char *na, const char *nb)
{
    int worst_block = -2, worst_c = 0;
    double worst = 0.0;
    for (int blk = -1; blk < (SIZE / BLOCK) * (SIZE / BLOCK); blk++) {
        int x0 = 0, y0 = 0, x1 = SIZE, y1 = SIZE;
        if (blk >= 0) {
            x0 = (blk % (SIZE / BLOCK)) * BLOCK; y0 = (blk / (SIZE / BLOCK)) * BLOCK;
            x1 = x0 + BLOCK; y1 = y0 + BLOCK;
        }
        RegionStat ra = region_stat(a, x0, y0, x1, y1), rb = region_stat(b, x0, y0, x1, y1);
        for (int c = 0; c < 3; c++) {
            double z = z_score(ra.mean[c], ra.se[c], rb.mean[c], rb.se[c]);
            if (fabs(z) > fabs(worst)) { worst = z; worst_block = blk; worst_c = c; }
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("%s vs %s: block %d (-1 = whole image) channel %d: %.6f vs %.6f, z = %.2f",
                         na, nb, blk, c, ra.mean[c], rb.mean[c], z);
        }
    }
    print_message("%s vs %s: largest |z| = %.2f (block %d, channel %d)\n", na, nb, fabs(worst),
                  worst_block, worst_c);
}

static void test_cornell_variants_agree(void **state)
{
    (void)state;
    /* BSDF-only sampling of a small light is the noisy one: give it more samples so the
     * test has power against biases of a fraction of a percent. */
    CstFilm *mis = render_cornell(CST_INTEGRATOR_PATH, 256, 1);
    CstFilm *nee = render_cornell(CST_INTEGRATOR_PATH_NEE, 256, 2);
    CstFilm *bsdf = render_cornell(CST_INTEGRATOR_PATH_BSDF, 1024, 3);
    compare(mis, nee, "path", "path-nee");
    compare(mis, bsdf, "path", "path-bsdf");
    compare(nee, bsdf, "path-nee", "path-bsdf");
    cst_film_destroy(mis);
    cst_film_destroy(nee);
    cst_film_destroy(bsdf);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_variants_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
