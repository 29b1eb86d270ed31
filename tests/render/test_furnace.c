/* White-furnace tests: closed scenes whose radiance is known exactly, rendered by every
 * path-tracing variant and by the light tracer. `test_furnace --spectral`: the same in
 * spectral mode (grey albedos are constant spectra and a white emitter is D65, whose film
 * value is white: the same expected images, no longer zero-variance). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "render/test_scenes.h"
#include "scene/scene.h"

/* The colour mode of every render: set once by main from the command line. */
static CstColorMode g_color_mode = CST_COLOR_RGB;

static const CstIntegrator VARIANTS[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE,
                                         CST_INTEGRATOR_PATH_BSDF};

/* Rounding slack for zero-variance estimators: a sample equal to 1 up to float rounding
 * of its MIS weights (a few ulps), averaged; far below any real bias we look for. */
static const double ROUNDING = 1e-5;

static void check_uniform(const CstFilm *film, double expected, const char *what)
{
    int w = cst_film_width(film), h = cst_film_height(film);
    /* The whole image and each of its 4x4 blocks. */
    for (int b = -1; b < 16; b++) {
        int x0 = 0, y0 = 0, x1 = w, y1 = h;
        if (b >= 0) { x0 = (b % 4) * w / 4; x1 = x0 + w / 4; y0 = (b / 4) * h / 4; y1 = y0 + h / 4; }
        RegionStat r = region_stat(film, x0, y0, x1, y1);
        for (int c = 0; c < 3; c++) {
            double dev = fabs(r.mean[c] - expected);
            if (dev > Z_LIMIT * r.se[c] + ROUNDING) {
                fail_msg("%s: block %d channel %d: mean %.6f, expected %.6f (z = %.2f, se %.2e)",
                         what, b, c, r.mean[c], expected, (r.mean[c] - expected) / r.se[c], r.se[c]);
            }
        }
    }
}

static CstFilm *render(const Scene *s, CstIntegrator integ, int size, int spp, uint64_t seed)
{
    CstRenderSettings st = {.width = size, .height = size, .color_mode = g_color_mode};
    return render_film(s, &st, integ, spp, seed);
}

/* An albedo-1 diffuse sphere inside a black enclosure that emits radiance 1 (two-sided):
 * every camera ray must see radiance exactly 1 (energy conservation of Lambert, and the
 * NEE/MIS estimators must add up to the same). */
static void test_white_furnace_albedo_one(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int white, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    Emission em = {{{1.0f, 1.0f, 1.0f}}, 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 10.0f, black, &em, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.0f, white, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 4.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    for (size_t i = 0; i < 3; i++) {
        CstFilm *f = render(s, VARIANTS[i], 32, 64, 7 + i);
        check_uniform(f, 1.0, cst_integrator_name(VARIANTS[i]));
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

/* Inside a closed sphere of albedo rho whose surface also emits L_e (two-sided), the
 * radiance is L_e (1 + rho + rho^2 + ...) = L_e / (1 - rho) in every direction: this
 * exercises long paths and Russian roulette. Different L_e per channel checks that
 * channels stay apart. */
static void test_furnace_emitting_sphere(void **state)
{
    (void)state;
    const float rho = 0.5f;
    double expect[3];
    Scene *s = test_scene_emitting_sphere(rho, expect);
    if (g_color_mode == CST_COLOR_SPECTRAL) test_emitting_sphere_expect_spectral(rho, expect);
    for (size_t i = 0; i < 3; i++) {
        CstFilm *f = render(s, VARIANTS[i], 32, 128, 100 + i);
        /* per-channel expectation: check each channel against its own value */
        int w = cst_film_width(f), h = cst_film_height(f);
        for (int b = -1; b < 16; b++) {
            int x0 = 0, y0 = 0, x1 = w, y1 = h;
            if (b >= 0) { x0 = (b % 4) * w / 4; x1 = x0 + w / 4; y0 = (b / 4) * h / 4; y1 = y0 + h / 4; }
            RegionStat r = region_stat(f, x0, y0, x1, y1);
            for (int c = 0; c < 3; c++) {
                double z = (r.mean[c] - expect[c]) / r.se[c];
                if (!(fabs(z) <= Z_LIMIT))
                    fail_msg("%s: block %d channel %d: mean %.6f, expected %.6f (z = %.2f)",
                             cst_integrator_name(VARIANTS[i]), b, c, r.mean[c], expect[c], z);
            }
        }
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

/* The emitting sphere for the light tracer: two-sided emission (half of the paths start
 * outward and only show their first vertex), long paths, Russian roulette. Light paths
 * splat into many pixels, so the standard errors come from independent one-iteration
 * renders (region_stats_by_render). */
static void test_light_furnace_emitting_sphere(void **state)
{
    (void)state;
    CstError err;
    const float rho = 0.5f;
    double expect[3];
    Scene *s = test_scene_emitting_sphere(rho, expect);
    if (g_color_mode == CST_COLOR_SPECTRAL) test_emitting_sphere_expect_spectral(rho, expect);
    CstRenderSettings st = {0};
    st.width = st.height = 32;
    st.integrator = CST_INTEGRATOR_LIGHT;
    st.color_mode = g_color_mode;
    int rect[17][4];
    for (int b = -1; b < 16; b++) {
        int *r = rect[b + 1];
        r[0] = 0; r[1] = 0; r[2] = 32; r[3] = 32;
        if (b >= 0) { r[0] = (b % 4) * 8; r[2] = r[0] + 8; r[1] = (b / 4) * 8; r[3] = r[1] + 8; }
    }
    RegionStat reg[17];
    if (region_stats_by_render(s, &st, 2048, 300, 17, (const int (*)[4])rect, reg, NULL, &err) != CST_OK)
        fail_msg("%s", err.msg);
    double worst = 0.0;
    for (int i = 0; i < 17; i++)
        for (int c = 0; c < 3; c++) {
            double z = (reg[i].mean[c] - expect[c]) / reg[i].se[c];
            if (fabs(z) > fabs(worst)) worst = z;
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("light: block %d channel %d: mean %.6f, expected %.6f (z = %.2f)", i - 1, c,
                         reg[i].mean[c], expect[c], z);
        }
    print_message("light: whole image %.5f (se %.1e), expected %.5f; largest |z| = %.2f\n",
                  reg[0].mean[0], reg[0].se[0], expect[0], fabs(worst));
    scene_destroy(s);
}

/* Dispersion in a furnace: inside a black enclosure emitting 1 (D65 in spectral mode), a
 * lossless glass sphere whose ior varies strongly with wavelength (1.9 at 360 nm to 1.3
 * at 830 nm, linear) and an albedo-1 diffuse sphere. Radiance is 1 everywhere whatever the
 * glass does, so the image is white with or without dispersion: the test of the
 * termination's bookkeeping (the hero's pdf / 4, the other lanes dropped from the film)
 * in the path tracer (the camera sees the glass) and the light tracer (light paths reach
 * the diffuse sphere through the glass behind the camera; the light tracer cannot see a
 * smooth surface directly). In spectral mode the test also checks that the paths did
 * disperse: the dispersive render's variance is larger than the non-dispersive one's. */
static Scene *dispersive_scene(bool dispersive, bool glass_behind)
{
    CstError err;
    Scene *s = scene_create();
    int white, black, glass, sp;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    SampledSpectrum *ior = malloc(sizeof *ior);
    assert_non_null(ior);
    const float l[2] = {360.0f, 830.0f}, n[2] = {1.9f, 1.3f};
    sampled_spectrum_from_pairs(l, n, 2, ior);
    assert_int_equal(scene_add_spectrum(s, ior, &sp, &err), CST_OK);
    Material g = {.type = MATERIAL_GLASS, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = sampled_spectrum_mean_y(ior)};
    if (dispersive) g.ior_spectrum = sp + 1, g.ior_dispersive = true;
    free(ior);
    assert_int_equal(scene_add_material(s, &g, &glass, &err), CST_OK);
    Emission em = {{{1.0f, 1.0f, 1.0f}}, 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 10.0f, black, &em, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(glass_behind ? 0.0f : -0.6f, 0, 0), glass_behind ? 1.0f : 0.5f,
                                      white, NULL, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, glass_behind ? v3(0, 0, 6.5f) : v3(0.6f, 0, 0), glass_behind ? 2.0f : 0.5f,
                                      glass, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 4.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static void test_dispersive_glass_furnace(void **state)
{
    (void)state;
    double var[2] = {0.0, 0.0};
    for (int disp = 0; disp < 2; disp++) {
        Scene *s = dispersive_scene(disp != 0, false);
        CstFilm *f = render(s, CST_INTEGRATOR_PATH, 32, 128, 300 + (uint64_t)disp);
        check_uniform(f, 1.0, disp ? "path, dispersive glass" : "path, glass");
        RegionStat r = region_stat(f, 16, 8, 32, 24); /* the glass sphere's side */
        var[disp] = r.se[0] * r.se[0] + r.se[1] * r.se[1] + r.se[2] * r.se[2];
        cst_film_destroy(f);
        scene_destroy(s);
    }
    print_message("path: variance of the glass block's mean %.3g (dispersive) vs %.3g\n", var[1], var[0]);
    if (g_color_mode == CST_COLOR_SPECTRAL && !(var[1] > 1.5 * var[0]))
        fail_msg("the dispersive glass did not add variance: termination not applied?");

    CstError err;
    Scene *s = dispersive_scene(true, true);
    CstRenderSettings st = {0};
    st.width = st.height = 32;
    st.integrator = CST_INTEGRATOR_LIGHT;
    st.color_mode = g_color_mode;
    st.spp = 16;
    int rect[17][4];
    for (int b = -1; b < 16; b++) {
        int *r = rect[b + 1];
        r[0] = 0; r[1] = 0; r[2] = 32; r[3] = 32;
        if (b >= 0) { r[0] = (b % 4) * 8; r[2] = r[0] + 8; r[1] = (b / 4) * 8; r[3] = r[1] + 8; }
    }
    RegionStat reg[17];
    if (region_stats_by_render(s, &st, 256, 400, 17, (const int (*)[4])rect, reg, NULL, &err) != CST_OK)
        fail_msg("%s", err.msg);
    for (int i = 0; i < 17; i++)
        for (int c = 0; c < 3; c++) {
            double z = (reg[i].mean[c] - 1.0) / reg[i].se[c];
            if (!(fabs(z) <= Z_LIMIT) && !(fabs(reg[i].mean[c] - 1.0) <= ROUNDING))
                fail_msg("light, dispersive glass: block %d channel %d: mean %.6f, expected 1 (z = %.2f)", i - 1, c,
                         reg[i].mean[c], z);
        }
    print_message("light, dispersive glass: whole image (%.5f, %.5f, %.5f) se %.1e, expected 1\n", reg[0].mean[0],
                  reg[0].mean[1], reg[0].mean[2], reg[0].se[0]);
    scene_destroy(s);
}

/* An emitter with a spectrum of its own (CstEmission.spectrum): a black enclosure emitting
 * a 3000 K blackbody at twice its luminance-1 RGB. Seen directly, every pixel's expected
 * value is that RGB in both modes (spectral: the spectrum at luminance Y(rgb), through the
 * CIE curves, is the RGB its reduction gave), so this checks the normalisation of emitted
 * spectra in the path tracer (emission and NEE) and the light tracer (light-path starts). */
static void test_emitter_spectrum_furnace(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int black, sp;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    SampledSpectrum *bb = malloc(sizeof *bb);
    assert_non_null(bb);
    sampled_spectrum_blackbody(3000.0f, bb);
    Color rgb = color_scale(sampled_spectrum_rgb_illuminant(bb), 2.0f);
    assert_int_equal(scene_add_spectrum(s, bb, &sp, &err), CST_OK);
    free(bb);
    Emission em = {rgb, 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 10.0f, black, &em, &err), CST_OK);
    assert_int_equal(scene_set_emitter_spectrum(s, 0, sp + 1, &err), CST_OK);
    CameraDesc cam = {{0, 0, 4}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 4.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstFilm *f = render(s, CST_INTEGRATOR_PATH, 32, 64, 500);
    RegionStat r = region_stat(f, 0, 0, 32, 32);
    for (int c = 0; c < 3; c++) {
        double z = (r.mean[c] - (double)rgb.c[c]) / r.se[c];
        if (!(fabs(z) <= Z_LIMIT) && !(fabs(r.mean[c] - (double)rgb.c[c]) <= 1e-5 * (double)rgb.c[c]))
            fail_msg("path: channel %d: mean %.6f, expected %.6f (z = %.2f)", c, r.mean[c], (double)rgb.c[c], z);
    }
    print_message("emitter spectrum, path: (%.5f, %.5f, %.5f), expected (%.5f, %.5f, %.5f)\n", r.mean[0], r.mean[1],
                  r.mean[2], (double)rgb.c[0], (double)rgb.c[1], (double)rgb.c[2]);
    cst_film_destroy(f);
    CstRenderSettings st = {0};
    st.width = st.height = 16;
    st.integrator = CST_INTEGRATOR_LIGHT;
    st.color_mode = g_color_mode;
    const int rect[1][4] = {{0, 0, 16, 16}};
    RegionStat reg;
    if (region_stats_by_render(s, &st, 1024, 600, 1, rect, &reg, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    for (int c = 0; c < 3; c++) {
        double z = (reg.mean[c] - (double)rgb.c[c]) / reg.se[c];
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("light: channel %d: mean %.6f, expected %.6f (z = %.2f)", c, reg.mean[c], (double)rgb.c[c], z);
    }
    print_message("emitter spectrum, light: (%.5f, %.5f, %.5f) se %.1e\n", reg.mean[0], reg.mean[1], reg.mean[2],
                  reg.se[0]);
    scene_destroy(s);
}

/* Russian roulette from the first bounce (rr_depth 1, SmallVCM's rule, which
 * scenes/smallvcm-box.json uses: issue 32): the emitting sphere of albedo 0.8, whose
 * L_e / (1 - rho) = 5 L_e needs long paths, every one of them decided by roulette from its
 * first scattering on. Unbiased in the path variants, the light tracer and BDPT (whose
 * throughputs and MIS pdfs both go through roulette()), each at Z_LIMIT standard errors
 * of the whole image and its four quadrants (light and bdpt: errors from independent
 * renders, since their splats correlate pixels). The last case, BDPT with roulette from
 * the first bounce on its light subpaths alone (rr_depth 3, light_rr_depth 1: what
 * bench/smallvcm.sh runs bdpt with), checks the light subpaths' roulette on its own. */
static void test_furnace_roulette_first_bounce(void **state)
{
    (void)state;
    CstError err;
    const float rho = 0.8f;
    double expect[3];
    Scene *s = test_scene_emitting_sphere(rho, expect);
    if (g_color_mode == CST_COLOR_SPECTRAL) test_emitting_sphere_expect_spectral(rho, expect);
    CstRenderSettings st = {.width = 16, .height = 16, .color_mode = g_color_mode, .rr_depth = 1};
    int rect[5][4];
    for (int b = -1; b < 4; b++) {
        int *r = rect[b + 1];
        r[0] = 0; r[1] = 0; r[2] = 16; r[3] = 16;
        if (b >= 0) { r[0] = (b % 2) * 8; r[2] = r[0] + 8; r[1] = (b / 2) * 8; r[3] = r[1] + 8; }
    }
    const CstIntegrator integ[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_PATH_BSDF,
                                   CST_INTEGRATOR_LIGHT, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_BDPT};
    const int rr[] = {1, 1, 1, 1, 1, 3}, light_rr[] = {0, 0, 0, 0, 0, 1}; /* 0: rr_depth's */
    for (size_t i = 0; i < sizeof integ / sizeof integ[0]; i++) {
        RegionStat reg[5];
        st.rr_depth = rr[i];
        st.light_rr_depth = light_rr[i];
        if (integ[i] == CST_INTEGRATOR_LIGHT || integ[i] == CST_INTEGRATOR_BDPT) {
            st.integrator = integ[i];
            if (region_stats_by_render(s, &st, integ[i] == CST_INTEGRATOR_BDPT ? 64 : 128, 700 + i, 5,
                                       (const int (*)[4])rect, reg, NULL, &err) != CST_OK)
                fail_msg("%s", err.msg);
        } else {
            CstFilm *f = render_film(s, &st, integ[i], 64, 700 + i);
            for (int k = 0; k < 5; k++) reg[k] = region_stat(f, rect[k][0], rect[k][1], rect[k][2], rect[k][3]);
            cst_film_destroy(f);
        }
        for (int k = 0; k < 5; k++)
            for (int c = 0; c < 3; c++) {
                double z = (reg[k].mean[c] - expect[c]) / reg[k].se[c];
                if (!(fabs(z) <= Z_LIMIT))
                    fail_msg("%s, rr_depth %d, light_rr_depth %d: region %d channel %d: mean %.6f, expected %.6f "
                             "(z = %.2f)", cst_integrator_name(integ[i]), rr[i], light_rr[i], k - 1, c, reg[k].mean[c],
                             expect[c], z);
            }
        print_message("%s, rr_depth %d, light_rr_depth %d: whole image %.5f (se %.1e), expected %.5f\n",
                      cst_integrator_name(integ[i]), rr[i], light_rr[i], reg[0].mean[0], reg[0].se[0], expect[0]);
    }
    scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_white_furnace_albedo_one),
        cmocka_unit_test(test_furnace_emitting_sphere),
        cmocka_unit_test(test_light_furnace_emitting_sphere),
        cmocka_unit_test(test_dispersive_glass_furnace),
        cmocka_unit_test(test_emitter_spectrum_furnace),
        cmocka_unit_test(test_furnace_roulette_first_bounce),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
