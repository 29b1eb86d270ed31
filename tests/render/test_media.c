/* Participating media in the path tracer (integrators/volpath.c): furnaces whose radiance
 * is known exactly (a scattering-only medium, an absorbing medium that emits what it
 * absorbs, the camera inside a medium), the three path variants (MIS, NEE only, phase /
 * BSDF sampling only) agreeing on a lit fog, and the refusal of other integrators.
 * `test_media --spectral` runs the same in spectral mode. Fixed seeds, 4 standard errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/media_scenes.h"

static CstColorMode g_color_mode = CST_COLOR_RGB;

/* pbrt-v4's whole-image means of tests/render/media/cornell-fog.pbrt (see
 * test_pbrt_fog_cornell). */
#define PBRT_FOG_R 0.0378617
#define PBRT_FOG_G 0.0208463
#define PBRT_FOG_B 0.00466914

/* A black enclosure (radius 10) emitting L two-sided, and in it a ball of medium (radius
 * 2, a boundary sphere) with the given coefficients; camera outside the ball, or (in_medium)
 * the medium fills the enclosure, whose sphere is then its non-boundary interface, and the
 * camera sits in it. Radiance is L everywhere when the medium conserves (no absorption) or
 * emits L where it absorbs. */
static Scene *furnace(Color sigma_a, Color sigma_s, Color le, float g, bool in_medium, const Color L)
{
    Scene *s = scene_create();
    const int med = media_add_homogeneous(s, sigma_a, sigma_s, le, g);
    return media_furnace(s, med, 10.0f, in_medium ? 0.0f : 2.0f, 5.0f, L);
}

static void run_furnace(Scene *s, Color L, int spp, uint64_t seed, int variants, const char *what)
{
    media_path_furnace(s, L, spp, seed, variants, g_color_mode, what);
}

/* Scattering only (albedo 1, sigma_s different per channel, forward HG): radiance L. */
static void test_furnace_scattering(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = furnace(color_s(0.0f), color_rgb(1.0f, 2.0f, 0.5f), color_s(0.0f), 0.6f, false, L);
    run_furnace(s, L, 64, 10, 3, "scattering ball");
}

/* Absorbing and scattering, emitting Le = L: what the medium absorbs it emits again. */
static void test_furnace_emission(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = furnace(color_rgb(0.5f, 1.0f, 0.3f), color_rgb(0.5f, 0.2f, 1.0f), L, -0.3f, false, L);
    run_furnace(s, L, 64, 20, 3, "emitting ball");
}

/* The camera inside the medium that fills the enclosure (camera medium, non-boundary
 * interface on the emitter). MIS and phase sampling only: NEE alone samples the emitter
 * sphere by area from inside it (light.c), so its estimate Le cos A / d^2 has an infinite
 * second moment at medium vertices near the wall (the integral of d^-4 over the area
 * diverges) and its standard errors mean nothing; MIS bounds it by the phase pdf. */
static void test_furnace_camera_medium(void **state)
{
    (void)state;
    const Color L = color_rgb(0.3f, 0.6f, 0.9f);
    Scene *s = furnace(color_s(0.0f), color_rgb(0.2f, 0.3f, 0.1f), color_s(0.0f), 0.8f, true, L);
    run_furnace(s, L, 64, 30, 2, "camera in medium");
}

/* The fog box (media_scenes.h: an open box lit by a small quad light, a ball of fog and a
 * diffuse sphere half inside it): MIS, NEE only and phase/BSDF sampling only estimate the
 * same image. */
static void test_fog_variants_agree(void **state)
{
    (void)state;
    Scene *s = fog_box(FOG_HOMOGENEOUS);
    CstRenderSettings st = {.width = 32, .height = 32, .color_mode = g_color_mode};
    Regions mis = regions(32, 8), nee = regions(32, 8), bsdf = regions(32, 8);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 256, 40, &mis);
    camera_regions(s, &st, CST_INTEGRATOR_PATH_NEE, 256, 41, &nee);
    camera_regions(s, &st, CST_INTEGRATOR_PATH_BSDF, 1024, 42, &bsdf);
    compare(&mis, &nee, "path", "path-nee");
    compare(&mis, &bsdf, "path", "path-bsdf");
    compare(&nee, &bsdf, "path-nee", "path-bsdf");
    scene_destroy(s);
}

/* The fog-filled Cornell box of tests/render/media/cornell-fog.pbrt against pbrt-v4's
 * volpath (spectral, maxdepth 5): the whole-image means of pbrt-v4 renders of 128 x
 * 128 pixels at 1024 + 256 spp (tests/render/media/README.md), and caustic's at a
 * fraction of the paths (the whole-image mean does not depend on the resolution with the
 * box filter). Passes when each channel is within 1% of pbrt-v4's mean plus 4 standard
 * errors of caustic's (the reference's own standard error, about 0.5% in blue, is
 * inside the 1%).
 * Spectral mode only: pbrt-v4 is spectral. */
static void test_pbrt_fog_cornell(void **state)
{
    (void)state;
    if (g_color_mode != CST_COLOR_SPECTRAL) {
        print_message("spectral mode only (run as test_media --spectral)\n");
        return;
    }
    static const double PBRT_MEAN[3] = {PBRT_FOG_R, PBRT_FOG_G, PBRT_FOG_B};
    pbrt_mean_check(CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt", PBRT_MEAN, 512, 50, "fog Cornell");
}

/* Integrators without media support fail with a clear error instead of ignoring them
 * (vcm renders media now: test_media_bidir; sppm too: test_sppm_media; photon:
 * test_photon_media). */
static void test_other_integrators_refuse(void **state)
{
    (void)state;
    Scene *s = fog_box(FOG_HOMOGENEOUS);
    const CstIntegrator others[] = {CST_INTEGRATOR_WHITTED};
    for (size_t i = 0; i < sizeof others / sizeof *others; i++) {
        CstRenderSettings st;
        cst_render_settings_init(&st);
        st.width = st.height = 8;
        st.spp = 1;
        st.integrator = others[i];
        CstFilm *f = NULL;
        CstError err;
        assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
        assert_non_null(strstr(err.msg, "participating media"));
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace_scattering),
        cmocka_unit_test(test_furnace_emission),
        cmocka_unit_test(test_furnace_camera_medium),
        cmocka_unit_test(test_fog_variants_agree),
        cmocka_unit_test(test_other_integrators_refuse),
        cmocka_unit_test(test_pbrt_fog_cornell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
