/* Metropolis light transport (pssmlt, integrators/mlt.c) against the path tracer: its
 * estimate (bootstrap b times the chains' splats) is unbiased for any chain length,
 * because b and the chains' starts come from one bootstrap (see docs/integrators.md), so
 * image means and block means must agree with path within noise on the Cornell box, on
 * the spheres scene (caustics through glass), in a fog-filled box (media) and in the
 * emitting furnace with its closed form; two sets of seeds agree with each other; and 1 and 2 threads give the same image
 * bit for bit. MLT's pixels are correlated (chains cross pixels, iterations continue the
 * chains), so standard errors come from independent renders. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "render/test_scenes.h"
#include "scene/scene.h"

/* `test_mlt --spectral`: every render in spectral mode (the PSS sampler also draws the
 * wavelengths). */
static CstColorMode g_color_mode = CST_COLOR_RGB;

/* Small chains and bootstraps keep each render cheap; they change the noise, not the
 * expectation. */
static CstRenderSettings mlt_settings(int size, int mpp)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = size;
    st.filter = CST_FILTER_BOX;
    st.color_mode = g_color_mode;
    st.spp = mpp;
    st.mlt_chains = 64;
    st.mlt_bootstrap = 4096;
    return st;
}

static void path_vs_mlt(const CstScene *s, const CstRenderSettings *st, int size, int block, int path_spp,
                        int renders, uint64_t seed, const char *label)
{
    Regions rp = regions(size, block), rm = rp;
    camera_regions(s, st, CST_INTEGRATOR_PATH, path_spp, seed, &rp);
    split_regions(s, st, CST_INTEGRATOR_PSSMLT, renders, seed + 1000, &rm);
    char a[96], b[96];
    snprintf(a, sizeof a, "path (%s)", label);
    snprintf(b, sizeof b, "pssmlt (%s)", label);
    compare(&rp, &rm, a, b);
}

static void test_cornell_box(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = mlt_settings(64, 8);
    path_vs_mlt(s, &st, 64, 16, 512, 64, 11, "cornell");
    cst_scene_destroy(s);
}

/* Mirror and glass spheres: caustics, where small steps keep the chains on the few paths
 * through the glass that reach the light. */
static void test_cornell_spheres(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-spheres.json", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings st = mlt_settings(48, 8);
    path_vs_mlt(s, &st, 48, 12, 512, 64, 21, "spheres");
    cst_scene_destroy(s);
}

/* Participating media: the target is path_li's estimate, whose volumetric loop
 * (volpath.c) reads the same Sampler: the fog-filled Cornell box of test_media. */
static void test_fog_cornell(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    CstLoadOptions opt = {0};
    if (cst_scene_load_pbrt(CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt", &opt, &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings st = mlt_settings(32, 8);
    path_vs_mlt(s, &st, 32, 16, 512, 48, 61, "fog");
    cst_scene_destroy(s);
}

/* Two independent sets of renders (seeds 100.. and 9100..) of the same settings agree:
 * pbrt-v4's reports of MLT images that depend on the seed. Large steps rare and a wide
 * sigma, so the chains mostly walk. */
static void test_seeds_agree(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = mlt_settings(32, 8);
    st.mlt_large_step = 0.05;
    st.mlt_sigma = 0.05;
    Regions a = regions(32, 8), b = a;
    split_regions(s, &st, CST_INTEGRATOR_PSSMLT, 48, 100, &a);
    split_regions(s, &st, CST_INTEGRATOR_PSSMLT, 48, 9100, &b);
    compare(&a, &b, "pssmlt (seeds 100..)", "pssmlt (seeds 9100..)");
    cst_scene_destroy(s);
}

/* The emitting furnace: every pixel sees L_e / (1 - rho) (in spectral mode the film's RGB
 * of L_e's spectrum, test_emitting_sphere_expect_spectral). */
static void test_emitting_furnace(void **state)
{
    (void)state;
    double expect[3];
    Scene *s = test_scene_emitting_sphere(0.5f, expect);
    if (g_color_mode == CST_COLOR_SPECTRAL) test_emitting_sphere_expect_spectral(0.5f, expect);
    CstRenderSettings st = mlt_settings(32, 8);
    Regions r = regions(32, 8);
    split_regions(s, &st, CST_INTEGRATOR_PSSMLT, 48, 300, &r);
    double worst = 0.0;
    for (int i = 0; i < r.count; i++)
        for (int c = 0; c < 3; c++) {
            double z = (r.stat[i].mean[c] - expect[c]) / r.stat[i].se[c];
            if (fabs(z) > fabs(worst)) worst = z;
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("pssmlt furnace: block %d channel %d: mean %.6f, expected %.6f (z = %.2f)", i - 1, c,
                         r.stat[i].mean[c], expect[c], z);
        }
    print_message("pssmlt furnace: whole image %.5f (se %.1e), expected %.5f; largest |z| = %.2f\n",
                  r.stat[0].mean[0], r.stat[0].se[0], expect[0], fabs(worst));
    scene_destroy(s);
}

/* The image is a function of the seed and the settings: 1 and 2 threads, bit for bit,
 * and a render cut into passes of one sample is the render in one pass. */
static void test_threads_deterministic(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = mlt_settings(40, 4);
    st.integrator = CST_INTEGRATOR_PSSMLT;
    st.seed = 7;
    st.seed_set = 1;
    assert_threads_bit_identical(s, st);
    cst_scene_destroy(s);
}

/* The JSON keys reach the settings; mutations_per_pixel with another integrator, and
 * out-of-range values, are located errors; first_sample > 0 and AOVs are refused. */
static void test_settings_and_refusals(void **state)
{
    (void)state;
    static const char head[] = TEST_JSON_EMITTER_HEAD;
    char text[1024];
    CstScene *s = NULL;
    CstError err;
    snprintf(text, sizeof text, "%s\"integrator\": {\"type\": \"pssmlt\", \"mutations_per_pixel\": 5, "
             "\"large_step_probability\": 0.5, \"sigma\": 0.02, \"bootstrap_samples\": 300, \"chains\": 7}}", head);
    if (cst_scene_load_json_string(text, strlen(text), "mlt.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    CstRenderSettings r;
    cst_render_settings_resolve(s, NULL, &r);
    assert_int_equal(r.integrator, CST_INTEGRATOR_PSSMLT);
    assert_int_equal(r.spp, 5);
    assert_true(r.mlt_large_step == 0.5 && fabs(r.mlt_sigma - 0.02) < 1e-7);
    assert_int_equal(r.mlt_bootstrap, 300);
    assert_int_equal(r.mlt_chains, 7);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.first_sample = 1;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
    cst_render_settings_init(&st);
    st.aovs = CST_AOV_ALBEDO;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
    assert_int_equal(cst_integrator_resumable(CST_INTEGRATOR_PSSMLT), 1);
    cst_scene_destroy(s);
    s = NULL;

    snprintf(text, sizeof text, "%s\"integrator\": {\"type\": \"path\", \"mutations_per_pixel\": 5}}", head);
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), "mlt.json", &s, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "mlt.json:1:"));
    snprintf(text, sizeof text, "%s\"integrator\": {\"type\": \"pssmlt\", \"sigma\": 1.5}}", head);
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), "mlt.json", &s, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "sigma"));
    assert_null(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_spheres),
        cmocka_unit_test(test_fog_cornell),
        cmocka_unit_test(test_seeds_agree),
        cmocka_unit_test(test_emitting_furnace),
        cmocka_unit_test(test_threads_deterministic),
        cmocka_unit_test(test_settings_and_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
