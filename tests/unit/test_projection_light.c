/* Projection lights (pbrt-v4 ProjectionLight): with a constant image, a spot-like closed
 * form: NEE gives I / d^2 inside the window and nothing outside, the flux is I times the
 * window's solid angle 4 asin(X Y / sqrt((1 + X^2)(1 + Y^2))) (X, Y its half-extents on the
 * plane at distance 1), emission samples carry it on average (their density against that
 * closed form); the pbrt loader's "power" normalisation; the path tracer, the light tracer
 * and BDPT (emission sampling) render the same floor. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "io/image_io.h"
#include "render/render_util.h"
#include "scene/scene.h"
#include "unit/scratch_dir.h"

#define PI_D 3.14159265358979323846
#define IW 64
#define IH 32
#define FOV 40.0f

static int setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/caustic-projection-XXXXXX");
}
static int teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

/* A floor y = 0 (albedo 0.5) under a projection light at (0, 3, 0) looking down (light +z
 * = world -y), constant image 1, intensity (2, 1, 0.5), 64 x 32 pixels: the window is
 * X = 2 tan 20 deg wide along world x, Y = tan 20 deg along world z. */
static Scene *proj_scene(void)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Vec3 q[4] = {{-6, 0, -6}, {-6, 0, 6}, {6, 0, 6}, {6, 0, -6}};
    assert_int_equal(scene_add_quad(s, q, mat, NULL, &err), CST_OK);
    static float img[IW * IH * 3];
    for (int i = 0; i < IW * IH * 3; i++) img[i] = 1.0f;
    CstLightDesc l;
    memset(&l, 0, sizeof l);
    l.type = CST_LIGHT_PROJECTION;
    l.position[1] = 3.0f;
    l.intensity[0] = 2.0f, l.intensity[1] = 1.0f, l.intensity[2] = 0.5f;
    l.image = img;
    l.image_width = IW;
    l.image_height = IH;
    l.fov = FOV;
    const float lfw[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0}; /* rows: light x, y, z in world */
    memcpy(l.light_from_world, lfw, sizeof lfw);
    assert_int_equal(cst_scene_add_light(s, &l, &err), CST_OK);
    CameraDesc cam = {{0, 8, -0.001f}, {0, 0, 0}, {0, 0, 1}, 60.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static double window_solid_angle(void)
{
    double t = tan(0.5 * (double)FOV * PI_D / 180.0), X = 2.0 * t, Y = t;
    return 4.0 * asin(X * Y / sqrt((1.0 + X * X) * (1.0 + Y * Y)));
}

static void test_constant_image_closed_form(void **state)
{
    (void)state;
    Scene *s = proj_scene();
    const EmitterSampler *es = &s->emitter_sampler;
    assert_int_equal(es->lights, 1);
    const Light *l = &es->light[0];
    assert_int_equal(l->type, LIGHT_PROJECTION);
    const double omega = window_solid_angle();
    /* the image's integral (midpoint rule over 64 x 32 pixels) against the closed form */
    double integral = (double)color_channel(l->u.proj.image.integral, 0);
    print_message("  solid angle: closed form %.6f, pixel sum %.6f\n", omega, integral);
    assert_true(fabs(integral - omega) <= 1e-3 * omega);

    /* NEE: I / d^2 inside, nothing outside (a spot with a rectangular cone) */
    EmitterGeometry g = scene_emitter_geometry(s);
    const double t = tan(0.5 * (double)FOV * PI_D / 180.0);
    const float xs[4] = {0.0f, (float)(3.0 * 2.0 * t * 0.99), (float)(3.0 * 2.0 * t * 1.01), 0.5f};
    const float zs[4] = {0.0f, 0.0f, 0.0f, (float)(3.0 * t * 1.01)};
    for (int k = 0; k < 4; k++) {
        LightLi ls;
        Vec3 x = v3(xs[k], 0.0f, zs[k]);
        bool ok = light_sample_li(es, &g, x, 0.5f, v2(0.5f, 0.5f), &ls);
        bool inside = k < 2;
        assert_true(ok == inside);
        if (!inside) continue;
        double d2 = (double)v3_length2(v3_sub(v3(0, 3, 0), x));
        for (int c = 0; c < 3; c++) {
            double expect = (c == 0 ? 2.0 : c == 1 ? 1.0 : 0.5) / d2;
            assert_true(fabs((double)color_channel(ls.li, c) - expect) <= 1e-5 * expect);
        }
        assert_true(ls.delta && ls.pmf == 1.0f);
    }

    /* Emission: E[beta] = I Omega (flux), beta = I A cos^3 theta / pmf; every direction in
     * the window and pdf_w equal to proj_factor's */
    enum { N = 1000000 };
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 1u);
    double sum = 0.0, sum2 = 0.0;
    for (int n = 0; n < N; n++) {
        EmissionSample e;
        float u_sel = pcg32_float(&rng);
        Vec2 a = pcg32_v2(&rng), b = pcg32_v2(&rng);
        emitter_sample_emission(es, &g, u_sel, a, b, &e);
        assert_true(e.delta && e.pdf_w > 0.0f);
        float pdf;
        Color f = proj_factor(&l->u.proj.image, e.w, &pdf);
        assert_true(color_channel(f, 0) == 1.0f);
        assert_true(fabsf(pdf - e.pdf_w) <= 1e-5f * pdf);
        double v = (double)color_channel(e.beta, 0) / 2.0;
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / N, se = sqrt((sum2 / N - mean * mean) / N);
    double z = (mean - omega) / se;
    print_message("  emission: E[beta] / I = %.6f +- %.6f, closed form %.6f (z = %.2f)\n", mean, se, omega, z);
    assert_true(fabs(z) <= 4.0);
    assert_true(fabs((double)light_power(l, es->radius) -
                     omega * (0.2126 * 2.0 + 0.7152 * 1.0 + 0.0722 * 0.5)) <= 1e-3 * omega);
    scene_destroy(s);
}

/* The floor's image by the path tracer (NEE), the light tracer and BDPT (the last two
 * start paths by emission sampling): the same means within Z_LIMIT. */
static void test_integrators_agree(void **state)
{
    (void)state;
    Scene *s = proj_scene();
    const int rect[5][4] = {{0, 0, 16, 16}, {0, 0, 8, 8}, {8, 0, 16, 8}, {0, 8, 8, 16}, {8, 8, 16, 16}};
    const CstIntegrator integ[3] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_LIGHT, CST_INTEGRATOR_BDPT};
    RegionStat r[3][5];
    for (int k = 0; k < 3; k++) {
        CstRenderSettings st = {0};
        st.width = st.height = 16;
        st.spp = 4;
        st.integrator = integ[k];
        st.max_depth = 1;
        st.threads = 2;
        CstError err;
        if (region_stats_by_render(s, &st, 64, 1000u * (uint64_t)(k + 1), 5, rect, r[k], NULL, &err) != CST_OK)
            fail_msg("%s", err.msg);
    }
    double zmax = 0.0;
    for (int k = 1; k < 3; k++)
        for (int i = 0; i < 5; i++)
            for (int c = 0; c < 3; c++) {
                double z = z_score(r[k][i].mean[c], r[k][i].se[c], r[0][i].mean[c], r[0][i].se[c]);
                zmax = fmax(zmax, fabs(z));
                assert_true(fabs(z) <= Z_LIMIT);
            }
    print_message("  image mean (red): path %.5f, light %.5f, bdpt %.5f; max |z| %.2f over 30 comparisons\n",
                  r[0][0].mean[0], r[1][0].mean[0], r[2][0].mean[0], zmax);
    assert_true(r[0][0].mean[0] > 0.0);
    scene_destroy(s);
}

/* pbrt-v4's "projection": the image from its file, fov, and "power" as the light's flux. */
static void test_pbrt_projection(void **state)
{
    (void)state;
    float px[4 * 2 * 3];
    for (int i = 0; i < 8; i++) px[3 * i] = 0.1f * (float)(i + 1), px[3 * i + 1] = 0.5f, px[3 * i + 2] = 0.05f * (float)i;
    char p[512];
    CstError err;
    tpath(p, sizeof p, "proj.pfm");
    assert_int_equal(image_write(p, px, 4, 2, &err), CST_OK);
    const char *fmt = "LookAt 0 5 -5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                      "AttributeBegin\nTranslate 0 2 0\nRotate 90 1 0 0\n"
                      "LightSource \"projection\" \"string filename\" \"proj.pfm\" \"float fov\" 30 %s\n"
                      "AttributeEnd\nShape \"sphere\" \"float radius\" 1\n";
    char text[1024], name[512];
    tpath(name, sizeof name, "t.pbrt");
    snprintf(text, sizeof text, fmt, "\"float power\" 100");
    CstScene *sc = NULL;
    if (cst_scene_load_pbrt_string(text, strlen(text), name, NULL, &sc, &err) != CST_OK) fail_msg("%s", err.msg);
    const Scene *s = (const Scene *)sc;
    assert_int_equal(s->num_delta_lights, 1);
    const DeltaLight *dl = &s->delta_lights[0];
    assert_int_equal(dl->type, DELTA_PROJECTION);
    assert_int_equal(dl->proj.w, 4);
    assert_int_equal(dl->proj.h, 2);
    assert_true(fabsf(dl->proj.tan_half - tanf(15.0f * CST_PI / 180.0f)) <= 1e-6f);
    /* Rotate 90 about x takes light +z to world -y: the axis points down */
    assert_true(fabsf(dl->proj.light_from_world[7] + 1.0f) <= 1e-6f);
    double phi = (double)light_power(&s->emitter_sampler.light[0], s->emitter_sampler.radius);
    print_message("  power 100: the light's flux %.4f\n", phi);
    assert_true(fabs(phi - 100.0) <= 1e-3 * 100.0);
    cst_scene_destroy(sc);
    snprintf(text, sizeof text, fmt, "\"float fov\" 180");
    assert_int_equal(cst_scene_load_pbrt_string(text, strlen(text), name, NULL, &sc, &err), CST_ERR_INVALID_ARG);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "fov"));
    cst_scene_destroy(sc);
}

/* The JSON scene's "projection" light: its frame from position, look_at and up, the image
 * from "file", and located errors. */
static void test_json_projection(void **state)
{
    (void)state;
    float px[3 * 2 * 3];
    for (int i = 0; i < 18; i++) px[i] = 0.5f;
    char p[512], name[512], text[1024];
    CstError err;
    tpath(p, sizeof p, "j.pfm");
    assert_int_equal(image_write(p, px, 3, 2, &err), CST_OK);
    tpath(name, sizeof name, "t.json");
    const char *fmt = "{\"camera\": {\"position\": [0, 2, -5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                      " \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"
                      " \"shapes\": [{\"type\": \"sphere\", \"material\": \"m\", \"center\": [0, 0, 0], "
                      "\"radius\": 1}],\n"
                      " \"lights\": [{\"type\": \"projection\", \"position\": [0, 4, 0], \"look_at\": [0, 0, 0], "
                      "%s \"file\": \"j.pfm\", \"fov\": 50, \"intensity\": [3, 3, 3]}]}";
    snprintf(text, sizeof text, fmt, "\"up\": [0, 0, 1],");
    CstScene *sc = NULL;
    if (cst_scene_load_json_string(text, strlen(text), name, &sc, &err) != CST_OK) fail_msg("%s", err.msg);
    const Scene *s = (const Scene *)sc;
    assert_int_equal(s->num_delta_lights, 1);
    const ProjImage *g = &s->delta_lights[0].proj;
    assert_int_equal(g->w, 3);
    assert_int_equal(g->h, 2);
    const float expect[9] = {1, 0, 0, 0, 0, 1, 0, -1, 0}; /* x = y cross z, y = up, z = down */
    for (int k = 0; k < 9; k++) assert_true(fabsf(g->light_from_world[k] - expect[k]) <= 1e-6f);
    assert_true(fabsf(g->tan_half - tanf(25.0f * CST_PI / 180.0f)) <= 1e-6f);
    cst_scene_destroy(sc);
    snprintf(text, sizeof text, fmt, "\"up\": [0, 1, 0],");
    assert_int_not_equal(cst_scene_load_json_string(text, strlen(text), name, &sc, &err), CST_OK);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "t.json:4:87:"));
    assert_non_null(strstr(err.msg, "up is parallel"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_image_closed_form),
        cmocka_unit_test(test_integrators_agree),
        cmocka_unit_test(test_pbrt_projection),
        cmocka_unit_test(test_json_projection),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
