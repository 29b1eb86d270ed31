/* The photon integrator in spectral mode (photon.c's photon sets: PHOTON_SPECTRAL_SETS sets
 * of photon paths, each at wavelengths of its own; a camera sample traces at the
 * wavelengths of the set it picks). On the Cornell box, against the spectral path tracer,
 * whole-image mean per channel, as test_photon.c checks RGB mode: the fixed radius's bias
 * is first order in r, so the bias at (4N, r/2) must be smaller than at (N, r) and the
 * Richardson extrapolation 2 m(r/2) - m(r) must agree with path within Z_LIMIT standard
 * errors. Each render's wavelength sets are its own draw, so the spread of the per-render
 * means holds their colour noise too. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "render/render_util.h"

enum { SIZE = 32, RENDERS = 32, PHOTON_SPP = 2, PATH_SPP = 512 };

static RegionStat photon_mean(const CstScene *s, int photons, double radius, uint64_t seed)
{
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = PHOTON_SPP;
    st.integrator = CST_INTEGRATOR_PHOTON;
    st.color_mode = CST_COLOR_SPECTRAL;
    st.photons = photons;
    st.photon_radius = radius;
    const int whole[1][4] = {{0, 0, SIZE, SIZE}};
    RegionStat r;
    CstError err;
    if (region_stats_by_render(s, &st, RENDERS, seed, 1, whole, &r, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    return r;
}

static void test_spectral_photon_converges_to_path(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = PATH_SPP;
    st.integrator = CST_INTEGRATOR_PATH;
    st.color_mode = CST_COLOR_SPECTRAL;
    st.seed = 1;
    st.seed_set = 1;
    st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
    CstFilm *f = NULL;
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    RegionStat ref = region_stat(f, 0, 0, SIZE, SIZE);
    cst_film_destroy(f);
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
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("channel %d: extrapolated spectral photon mean %.6f vs path %.6f, z = %.2f", c, rich,
                     ref.mean[c], z);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spectral_photon_converges_to_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
