/* Photon mapping on the Cornell box: its fixed-radius density estimates are biased (the
 * disc of radius r reaches past edges and corners, where photons are missing or rejected
 * by the normal test), but consistent. The test checks both halves of that claim against
 * the MIS path tracer on the whole-image mean, per channel:
 *   convergence: the bias at (4N photons, r/2) is smaller than at (N, r);
 *   the bias is first order in r (a boundary layer of width ~r; measured differences in
 *   red: -0.0042, -0.0023, -0.0013 at r = 40, 20, 10 mm with N r^2 fixed, 10k photons at
 *   40 mm, each +- 0.0007), so the
 *   Richardson extrapolation 2 m(r/2) - m(r) removes it and must agree with the path
 *   tracer within Z_LIMIT standard errors, with no separate bias allowance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "render/render_util.h"

enum { SIZE = 64, RENDERS = 64, PHOTON_SPP = 4, PATH_SPP = 1024 };

static CstScene *cornell(void)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    return s;
}

/* The photon image mean over RENDERS independent renders (seeds seed, seed + 1, ...): each
 * render builds its own maps, so the spread of the per-render means holds the photon
 * maps' noise as well as the gather noise, which per-pixel variances would miss (one map
 * serves every pixel). */
static RegionStat photon_mean(const CstScene *s, int photons, double radius, uint64_t seed)
{
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = PHOTON_SPP;
    st.integrator = CST_INTEGRATOR_PHOTON;
    st.photons = photons;
    st.photon_radius = radius;
    const int whole[1][4] = {{0, 0, SIZE, SIZE}};
    RegionStat r;
    CstError err;
    if (region_stats_by_render(s, &st, RENDERS, seed, 1, whole, &r, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    return r;
}

static void test_photon_converges_to_path(void **state)
{
    (void)state;
    CstScene *s = cornell();
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = PATH_SPP;
    st.integrator = CST_INTEGRATOR_PATH;
    st.seed = 1;
    st.seed_set = 1;
    CstFilm *f = NULL;
    CstError err;
    st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    RegionStat ref = region_stat(f, 0, 0, SIZE, SIZE);
    cst_film_destroy(f);

    /* The box is 550 mm wide: r = 40 mm holds about as many photons of 10000 as the
     * automatic radius does of the default 200000. */
    RegionStat coarse = photon_mean(s, 10000, 40.0, 1000);
    RegionStat fine = photon_mean(s, 40000, 20.0, 2000);
    for (int c = 0; c < 3; c++) {
        double d_coarse = coarse.mean[c] - ref.mean[c], d_fine = fine.mean[c] - ref.mean[c];
        double rich = 2.0 * fine.mean[c] - coarse.mean[c];
        double rich_se = sqrt(4.0 * fine.se[c] * fine.se[c] + coarse.se[c] * coarse.se[c]);
        double z = z_score(rich, rich_se, ref.mean[c], ref.se[c]);
        print_message("channel %d: path %.6f +- %.6f; photon (10k, 40) %+.6f +- %.6f, "
                      "(40k, 20) %+.6f +- %.6f; extrapolated %.6f, z = %.2f\n",
                      c, ref.mean[c], ref.se[c], d_coarse, coarse.se[c], d_fine, fine.se[c], rich, z);
        if (!(fabs(d_fine) < fabs(d_coarse)))
            fail_msg("channel %d: the bias did not shrink: %+.6f at (10k, r = 40), %+.6f at (40k, r = 20)",
                     c, d_coarse, d_fine);
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("channel %d: extrapolated photon mean %.6f vs path %.6f, z = %.2f", c, rich,
                     ref.mean[c], z);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_photon_converges_to_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
