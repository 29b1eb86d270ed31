/* The photon integrator in spectral mode (photon.c's photon sets: PHOTON_SPECTRAL_SETS sets
 * of photon paths, each at wavelengths of its own; a camera sample traces at the
 * wavelengths of the set it picks). On the Cornell box, against the spectral path tracer,
 * whole-image mean per channel: the fixed radius's bias is first order in r, so the
 * Richardson extrapolation 2 m(r/2) - m(r) must agree with path within Z_LIMIT standard
 * errors. Unlike test_photon.c (RGB), the bias is not required to shrink from (N, r) to
 * (4N, r/2): here the colour noise of the wavelength sets is as large as the bias (channel
 * 0: -0.0033 +- 0.0021 and -0.0029 +- 0.0025), so that comparison would test nothing. Each render's wavelength sets are its own draw, so the spread of the per-render
 * means holds their colour noise too. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "render/converge.h"

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
    return converge_mean_by_render(s, &st, RENDERS, seed);
}

static void test_spectral_photon_converges_to_path(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    RegionStat ref = converge_path_reference(s, SIZE, PATH_SPP, CST_COLOR_SPECTRAL);
    RegionStat coarse = photon_mean(s, 10000, 40.0, 1000);
    RegionStat fine = photon_mean(s, 40000, 20.0, 2000);
    converge_richardson_check(ref, coarse, fine, false, "spectral photon");
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_spectral_photon_converges_to_path),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
