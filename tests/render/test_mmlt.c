/* Multiplexed MLT (mmlt, integrators/mlt.c over subpath.c's single strategies) against
 * BDPT: the same estimator in expectation (each strategy (d + 2) times its BDPT weight,
 * picked uniformly), so image means and block means agree within noise on the Cornell box,
 * on the spheres scene (mirror and glass: strategies through delta vertices) and in the
 * fog-filled box (participating media), and through a door's gap, where the bootstrap
 * finds light on few paths of each length; 1 and 2 threads give the same image bit for bit;
 * the settings and refusals. MLT's pixels are
 * correlated, so standard errors come from independent renders. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

/* `test_mmlt --spectral`: every render in spectral mode. */
static CstColorMode g_color_mode = CST_COLOR_RGB;

/* Small chains and bootstraps keep each render cheap; they change the noise, not the
 * expectation. max_depth 4: five chains' lengths. */
static CstRenderSettings mmlt_settings(int size, int mpp)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = size;
    st.filter = CST_FILTER_BOX;
    st.color_mode = g_color_mode;
    st.spp = mpp;
    st.max_depth = 4;
    st.mlt_chains = 64;
    st.mlt_bootstrap = 4096;
    return st;
}

static void bdpt_vs_mmlt(const CstScene *s, const CstRenderSettings *st, int size, int block, int bdpt_spp,
                         int renders, uint64_t seed, const char *label)
{
    Regions rb = regions(size, block), rm = rb;
    CstRenderSettings sb = *st;
    sb.spp = bdpt_spp;
    split_regions(s, &sb, CST_INTEGRATOR_BDPT, renders, seed, &rb);
    split_regions(s, st, CST_INTEGRATOR_MMLT, renders, seed + 1000, &rm);
    char a[96], b[96];
    snprintf(a, sizeof a, "bdpt (%s)", label);
    snprintf(b, sizeof b, "mmlt (%s)", label);
    compare(&rb, &rm, a, b);
}

static void test_cornell_box(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = mmlt_settings(32, 8);
    bdpt_vs_mmlt(s, &st, 32, 16, 8, 24, 11, "cornell");
    cst_scene_destroy(s);
}

/* Mirror and glass spheres: paths through delta vertices, which only some strategies
 * (s = 0, and connections at the diffuse ends) can sample. */
static void test_cornell_spheres(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-spheres.json", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings st = mmlt_settings(32, 8);
    bdpt_vs_mmlt(s, &st, 32, 16, 8, 24, 21, "spheres");
    cst_scene_destroy(s);
}

/* Participating media: the fog-filled Cornell box of test_media, whose strategies cross
 * the fog (volume vertices on both subpaths, transmittance on every connection) through
 * subpath_media.c's single strategies, against BDPT's walks there. */
static void test_fog_cornell(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    CstLoadOptions opt = {0};
    if (cst_scene_load_pbrt(CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt", &opt, &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    /* 24 x 24 and a bootstrap of 1024 per length: the CI budget (the bootstrap changes
     * only the noise of b, which the independent renders' spread includes). */
    CstRenderSettings st = mmlt_settings(24, 8);
    st.mlt_bootstrap = 1024;
    bdpt_vs_mmlt(s, &st, 24, 12, 8, 24, 31, "fog");
    cst_scene_destroy(s);
}

/* Light through a door's gap (scenes/door.json), path lengths 0-3: none reaches the camera
 * directly, and a bootstrap path of length 1, 2 or 3 carries light about once in 200, 130
 * and 120 (issue 31: mmlt's door renders were dark). mmlt's image mean is b's bootstrap
 * estimate exactly (each mutation splats a total importance a + (1 - a) = 1), b is the sum
 * of the lengths' bootstrap means, and each length gets chains in proportion to its share:
 * a length the bootstrap under- or over-weights, a length whose chains are dropped or get
 * a share not in proportion to its b, or a strategy that loses light moves the whole
 * image. 16,384 bootstrap paths per length (some 80 carrying light at length 1) make b's
 * estimate close to normal, so 24 renders' spread is its standard error (about 2.5% of
 * the difference: 4 standard errors are a 10% shift). */
static void test_door_rare_lengths(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/door.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    CstRenderSettings st = mmlt_settings(16, 2);
    st.max_depth = 3;
    st.mlt_bootstrap = 16384;
    st.mlt_chains = 32;
    bdpt_vs_mmlt(s, &st, 16, 8, 32, 24, 41, "door");
    cst_scene_destroy(s);
}

/* The image is a function of the seed and the settings: 1 and 2 threads, bit for bit. */
static void test_threads_deterministic(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = mmlt_settings(24, 4);
    st.integrator = CST_INTEGRATOR_MMLT;
    st.seed = 7;
    st.seed_set = 1;
    assert_threads_bit_identical(s, st);
    cst_scene_destroy(s);
}

/* The JSON type and keys reach the settings; mmlt is resumable (test_checkpoint); a
 * bootstrap too large for its path lengths is refused. */
static void test_settings_and_refusals(void **state)
{
    (void)state;
    static const char head[] = TEST_JSON_EMITTER_HEAD;
    char text[1024];
    CstScene *s = NULL;
    CstError err;
    snprintf(text, sizeof text, "%s\"integrator\": {\"type\": \"mmlt\", \"mutations_per_pixel\": 5, "
             "\"max_depth\": 3, \"bootstrap_samples\": 300, \"chains\": 7}}", head);
    if (cst_scene_load_json_string(text, strlen(text), "mmlt.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    CstRenderSettings r;
    cst_render_settings_resolve(s, NULL, &r);
    assert_int_equal(r.integrator, CST_INTEGRATOR_MMLT);
    assert_int_equal(r.spp, 5);
    assert_int_equal(r.mlt_bootstrap, 300);
    assert_int_equal(r.mlt_chains, 7);
    assert_int_equal(cst_integrator_resumable(CST_INTEGRATOR_MMLT), 1);
    assert_int_equal(cst_integrator_from_name("mmlt"), CST_INTEGRATOR_MMLT);
    assert_string_equal(cst_integrator_name(CST_INTEGRATOR_MMLT), "mmlt");
    CstRenderSettings st = r;
    st.first_sample = 1;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
    st = r;
    st.max_depth = 1 << 12;
    st.mlt_bootstrap = 1 << 20;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "bootstrap"));
    /* max_depth 0 (unbounded) renders with MMLT_DEFAULT_DEPTH. */
    st = r;
    st.max_depth = 0;
    st.threads = 1;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) {
        /* Spectral mode: the glass and mirror scene alone (the CI budget); the rest does not
         * depend on the colour mode. */
        g_color_mode = CST_COLOR_SPECTRAL;
        const struct CMUnitTest spectral[] = {cmocka_unit_test(test_cornell_spheres)};
        return cmocka_run_group_tests(spectral, NULL, NULL);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_spheres),
        cmocka_unit_test(test_fog_cornell),
        cmocka_unit_test(test_door_rare_lengths),
        cmocka_unit_test(test_threads_deterministic),
        cmocka_unit_test(test_settings_and_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
