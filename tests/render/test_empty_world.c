/* Scenes with no shapes (pbrt-v4 renders them: every ray misses): every integrator and every
 * acceleration back end renders the environment seen directly, exactly, or black, with no
 * NaN; the pbrt and JSON loaders accept an empty world with a warning. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"

static const float ENV[3] = {0.25f, 0.5f, 1.0f};

/* Every camera ray escapes: the estimate of each sample is the environment's radiance with
 * MIS weight 1 (no other strategy can reach a light at infinity without a surface), so the
 * pixel means equal it up to float rounding. */
static const double ROUNDING = 1e-6;

static CstScene *empty_scene(int with_env, const CstLightDesc *light)
{
    CstError err;
    CstScene *s = NULL;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    CstCameraDesc cam = {0};
    cam.type = CST_CAMERA_PERSPECTIVE;
    cam.position[2] = 5.0f;
    cam.fov = 40.0f;
    assert_int_equal(cst_scene_set_camera(s, &cam, &err), CST_OK);
    if (with_env) assert_int_equal(cst_scene_set_environment_constant(s, ENV, &err), CST_OK);
    if (light && cst_scene_add_light(s, light, &err) != CST_OK) fail_msg("%s", err.msg);
    if (cst_scene_commit(s, &err) != CST_OK) fail_msg("%s", err.msg);
    return s;
}

/* Renders 16 x 16 pixels at 4 spp; every pixel must be `expected` (NULL: the
 * environment), and no sample may be NaN or infinite. */
static void check_render(const CstScene *s, CstIntegrator integ, const float *expected, const char *what)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = rs.height = 16;
    rs.spp = 4;
    rs.threads = 2;
    rs.integrator = integ;
    rs.photons = 1000;
    rs.color_mode = CST_COLOR_RGB;
    CstFilm *f = NULL;
    CstRenderStats stats;
    CstError err;
    CstStatus st = cst_render(s, &rs, &f, &stats, &err);
    if (st != CST_OK) fail_msg("%s (%s): %s", what, cst_integrator_name(integ), err.msg);
    if (stats.nonfinite != 0)
        fail_msg("%s (%s): %llu non-finite samples", what, cst_integrator_name(integ),
                 (unsigned long long)stats.nonfinite);
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++) {
            double m[3];
            cst_film_pixel(f, x, y, m);
            for (int c = 0; c < 3; c++)
                if (!(fabs(m[c] - (double)expected[c]) <= ROUNDING * (1.0 + (double)expected[c])))
                    fail_msg("%s (%s): pixel (%d, %d) channel %d = %.9g; expected %.9g", what,
                             cst_integrator_name(integ), x, y, c, m[c], (double)expected[c]);
        }
    cst_film_destroy(f);
}

static const CstIntegrator SEES_ENV[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_PATH_BSDF,
                                         CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM,
                                         CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
#define NUM_SEES_ENV ((int)(sizeof SEES_ENV / sizeof SEES_ENV[0]))

/* Empty world + constant environment: the environment's value in every pixel for each
 * integrator that sees escaping camera rays; the light tracer, which cannot see the
 * environment directly (docs/integrators.md), renders black. */
static void test_env_every_integrator(void **state)
{
    (void)state;
    CstScene *s = empty_scene(1, NULL);
    for (int i = 0; i < NUM_SEES_ENV; i++) check_render(s, SEES_ENV[i], ENV, "empty world + environment");
    const float black[3] = {0.0f, 0.0f, 0.0f};
    check_render(s, CST_INTEGRATOR_LIGHT, black, "empty world + environment");
    cst_scene_destroy(s);
}

/* The same through every acceleration back end this build has. */
static void test_env_every_accel(void **state)
{
    (void)state;
    CstScene *s = empty_scene(1, NULL);
    int n = 0;
    for (const char *name; (name = cst_list_names(CST_NAMES_ACCEL, n)) != NULL; n++) {
        CstError err;
        if (cst_scene_set_accel(s, name, &err) != CST_OK) fail_msg("accel %s: %s", name, err.msg);
        char what[64];
        snprintf(what, sizeof what, "empty world, accel %s", name);
        check_render(s, CST_INTEGRATOR_PATH, ENV, what);
        check_render(s, CST_INTEGRATOR_BDPT, ENV, what);
    }
    assert_true(n >= 4); /* bvh, kdtree, grid, list (+ embree) */
    cst_scene_destroy(s);
}

/* No environment; a point or a directional light (sampled over the scene's bounds, which
 * are empty): black in every integrator, no NaN. */
static void test_black_with_delta_lights(void **state)
{
    (void)state;
    const float black[3] = {0.0f, 0.0f, 0.0f};
    CstLightDesc lights[2] = {{0}, {0}};
    lights[0].type = CST_LIGHT_POINT;
    lights[0].intensity[0] = lights[0].intensity[1] = lights[0].intensity[2] = 10.0f;
    lights[1].type = CST_LIGHT_DIRECTIONAL;
    lights[1].direction[1] = -1.0f;
    lights[1].intensity[0] = lights[1].intensity[1] = lights[1].intensity[2] = 3.0f;
    for (int k = 0; k < 3; k++) {
        CstScene *s = empty_scene(0, k < 2 ? &lights[k] : NULL);
        for (int i = 0; i < NUM_SEES_ENV; i++) check_render(s, SEES_ENV[i], black, k < 2 ? "delta light" : "no light");
        check_render(s, CST_INTEGRATOR_LIGHT, black, "empty world, delta light");
        cst_scene_destroy(s);
    }
}

typedef struct Warnings {
    int count;
    char last[512];
} Warnings;

static void on_warning(void *user, CstWarningCode kind, const char *msg)
{
    (void)kind;
    Warnings *w = user;
    w->count++;
    snprintf(w->last, sizeof w->last, "%s", msg);
}

/* pbrt: a media-only world (as clouds.pbrt: a medium bounded by an "interface" sphere;
 * here a NanoVDB medium, which caustic reads as vacuum, so it leaves the sphere out) under an
 * infinite light loads with a located warning and renders the light's radiance. */
static void test_pbrt_media_only_world(void **state)
{
    (void)state;
    const char *text =
        "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n"
        "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\n"
        "WorldBegin\n"
        "LightSource \"infinite\" \"rgb L\" [0.25 0.5 1]\n"
        "MakeNamedMedium \"m\" \"string type\" \"nanovdb\"\n"
        "AttributeBegin\n  MediumInterface \"m\" \"\"\n  Material \"interface\"\n  Shape \"sphere\"\nAttributeEnd\n";
    Warnings w = {0};
    CstLoadOptions opt = {0};
    opt.warning = on_warning;
    opt.warning_user = &w;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt_string(text, strlen(text), "clouds-like.pbrt", &opt, &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    if (!strstr(w.last, "clouds-like.pbrt:12:1: the world has no shapes")) fail_msg("last warning: %s", w.last);
    /* The expected image: the same light in a world with a shape (a sphere behind the
     * camera, which loaded before empty worlds did), pixel for pixel (pbrt's Gaussian filter
     * weights samples by f / pdf, so pixels vary by a few percent around the light's value;
     * its "rgb L" is an illuminant spectrum the loader maps to RGB). */
    char with_shape[1024];
    snprintf(with_shape, sizeof with_shape, "%sTranslate 0 0 50\nShape \"sphere\"\n", text);
    CstScene *ref = NULL;
    if (cst_scene_load_pbrt_string(with_shape, strlen(with_shape), "ref.pbrt", NULL, &ref, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = rs.height = 16;
    rs.spp = 4;
    rs.integrator = CST_INTEGRATOR_PATH;
    rs.color_mode = CST_COLOR_RGB;
    CstFilm *fa = NULL, *fb = NULL;
    CstRenderStats stats;
    if (cst_render(ref, &rs, &fa, &stats, &err) != CST_OK) fail_msg("%s", err.msg);
    if (cst_render(s, &rs, &fb, &stats, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(stats.nonfinite, 0);
    double mean[3] = {0, 0, 0};
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++) {
            double a[3], b[3];
            cst_film_pixel(fa, x, y, a);
            cst_film_pixel(fb, x, y, b);
            for (int c = 0; c < 3; c++) {
                if (a[c] != b[c]) fail_msg("pixel (%d, %d) channel %d: %.9g; expected %.9g", x, y, c, b[c], a[c]);
                mean[c] += b[c] / 256.0;
            }
        }
    for (int c = 0; c < 3; c++)
        if (!(fabs(mean[c] - (double)ENV[c]) <= 0.02 * (double)ENV[c]))
            fail_msg("channel %d: image mean %.6g; expected %.6g within 2%%", c, mean[c], (double)ENV[c]);
    cst_film_destroy(fa);
    cst_film_destroy(fb);
    cst_scene_destroy(ref);
    cst_scene_destroy(s);
}

/* JSON: "shapes": [] loads, with a warning, and renders the environment. */
static void test_json_empty_shapes(void **state)
{
    (void)state;
    const char *text = "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                       " \"shapes\": [],\n \"environment\": {\"radiance\": [0.25, 0.5, 1]}}\n";
    Warnings w = {0};
    CstLoadOptions opt = {0};
    opt.warning = on_warning;
    opt.warning_user = &w;
    const char *path = CST_BINARY_DIR "/test_empty_world.json";
    FILE *fp = fopen(path, "w");
    assert_non_null(fp);
    fputs(text, fp);
    fclose(fp);
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_opt(path, &opt, &s, &err) != CST_OK) fail_msg("%s", err.msg);
    remove(path);
    if (w.count != 1 || !strstr(w.last, "test_empty_world.json: \"shapes\" is empty: the world has no shapes"))
        fail_msg("%d warnings, last: %s", w.count, w.last);
    check_render(s, CST_INTEGRATOR_PATH, ENV, "json empty world");
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_env_every_integrator),
        cmocka_unit_test(test_env_every_accel),
        cmocka_unit_test(test_black_with_delta_lights),
        cmocka_unit_test(test_pbrt_media_only_world),
        cmocka_unit_test(test_json_empty_shapes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
