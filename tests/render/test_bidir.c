/* Bidirectional estimators: BDPT is unbiased and VCM consistent, so both must agree with
 * the MIS path tracer within noise per channel on the image mean and every block: on
 * the Cornell box, on the Cornell box with a mirror and a glass sphere (caustics, paths
 * through delta vertices), with a bounce limit and the tent filter, through a glass
 * interface (the eta^2 of radiance vs importance), and in an emitting furnace with a
 * closed form. Their pixel estimates are correlated within an iteration (splats, shared
 * light vertices), so their standard errors come from independent renders. */
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

/* The colour mode of every render (`test_bidir --spectral`: spectral mode, where BDPT's
 * light and camera subpaths share per-path wavelengths and VCM's iterations one set). */
static CstColorMode g_color_mode = CST_COLOR_RGB;

static CstRenderSettings sized(int size, CstFilter filter)
{
    CstRenderSettings st = {0};
    st.width = st.height = size;
    st.filter = filter;
    st.color_mode = g_color_mode;
    return st;
}

/* path vs bdpt vs vcm on one scene and settings. */
static void three_way(const CstScene *s, const CstRenderSettings *st, int size, int block, int path_spp,
                      int renders, uint64_t seed, const char *label)
{
    Regions rp = regions(size, block), rb = rp, rv = rp;
    camera_regions(s, st, CST_INTEGRATOR_PATH, path_spp, seed, &rp);
    split_regions(s, st, CST_INTEGRATOR_BDPT, renders, seed + 1000, &rb);
    split_regions(s, st, CST_INTEGRATOR_VCM, renders, seed + 5000, &rv);
    char a[96], b[96], c[96];
    snprintf(a, sizeof a, "path (%s)", label);
    snprintf(b, sizeof b, "bdpt (%s)", label);
    snprintf(c, sizeof c, "vcm (%s)", label);
    compare(&rp, &rb, a, b);
    compare(&rp, &rv, a, c);
    compare(&rb, &rv, b, c);
}

static void test_cornell_box(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = sized(64, CST_FILTER_BOX);
    three_way(s, &st, 64, 16, 1024, 256, 11, "cornell");
    cst_scene_destroy(s);
}

/* Mirror and glass spheres: caustics on the floor (light -> glass -> floor -> camera,
 * where connections through the delta vertices are impossible and the weights must fall
 * to the strategies that can), the mirror's reflections seen by the camera. */
static void test_cornell_spheres(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-spheres.json", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings st = sized(48, CST_FILTER_BOX);
    three_way(s, &st, 48, 12, 2048, 512, 21, "spheres");
    cst_scene_destroy(s);
}

/* A bounce limit means the same for all three (an off-by-one drops or adds a bounce of
 * light, tens of percent), and the tent filter splats as camera samples are filtered. */
static void test_max_depth_and_tent(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = sized(48, CST_FILTER_TENT);
    st.max_depth = 2;
    three_way(s, &st, 48, 12, 1024, 256, 31, "max_depth 2, tent");
    cst_scene_destroy(s);
}

/* test_consistency.c's glass interface: a floor lit through a flat glass interface, seen
 * from under it. A light subpath that used the radiance BTDF would be 1/eta^2 too dark in
 * every strategy that crosses the interface on the light side. */
static void test_through_glass(void **state)
{
    (void)state;
    Scene *s = test_scene_glass_interface();
    CstRenderSettings st = sized(32, CST_FILTER_BOX);
    three_way(s, &st, 32, 8, 512, 256, 41, "glass");
    scene_destroy(s);
}

/* A diffuse sphere of albedo rho emitting L_e on both sides, seen from inside: every
 * pixel sees L_e / (1 - rho) (the emitting furnace of test_furnace.c; spectral mode: the
 * film's RGB of L_e's spectrum, test_emitting_sphere_expect_spectral). Long paths,
 * Russian roulette on both subpaths, two-sided emission. */
static void test_emitting_furnace(void **state)
{
    (void)state;
    const float rho = 0.5f;
    double expect[3];
    Scene *s = test_scene_emitting_sphere(rho, expect);
    if (g_color_mode == CST_COLOR_SPECTRAL) test_emitting_sphere_expect_spectral(rho, expect);
    const CstIntegrator integ[2] = {CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (int k = 0; k < 2; k++) {
        CstRenderSettings st = sized(32, CST_FILTER_BOX);
        Regions r = regions(32, 8);
        split_regions(s, &st, integ[k], 256, 300 + 1000 * (uint64_t)k, &r);
        double worst = 0.0;
        for (int i = 0; i < r.count; i++)
            for (int c = 0; c < 3; c++) {
                double z = (r.stat[i].mean[c] - expect[c]) / r.stat[i].se[c];
                if (fabs(z) > fabs(worst)) worst = z;
                if (!(fabs(z) <= Z_LIMIT))
                    fail_msg("%s: block %d channel %d: mean %.6f, expected %.6f (z = %.2f)",
                             cst_integrator_name(integ[k]), i - 1, c, r.stat[i].mean[c], expect[c], z);
            }
        print_message("%s furnace: whole image %.5f (se %.1e), expected %.5f; largest |z| = %.2f\n",
                      cst_integrator_name(integ[k]), r.stat[0].mean[0], r.stat[0].se[0], expect[0],
                      fabs(worst));
    }
    scene_destroy(s);
}

/* The Cornell box with a point light and a spot added to its area light: delta lights in
 * every strategy (never hit, never connected to as a surface, NEE and light paths only),
 * light selection by power over three kinds of light. The light tracer joins: the box is
 * all diffuse. */
static void test_delta_lights_cornell(void **state)
{
    (void)state;
    FILE *fp = fopen(CST_SOURCE_DIR "/scenes/cornell-box.json", "rb");
    assert_non_null(fp);
    static char text[1 << 16];
    size_t n = fread(text, 1, sizeof text - 512, fp);
    fclose(fp);
    while (n > 0 && text[n - 1] != '}') n--;
    assert_true(n > 0);
    const char *lights = ",\n\"lights\": [{\"type\": \"point\", \"position\": [150, 400, 200], "
                         "\"intensity\": [30000, 30000, 20000]}, {\"type\": \"spot\", \"position\": [450, 500, 100], "
                         "\"look_at\": [350, 0, 400], \"intensity\": [60000, 40000, 40000], \"cone_angle\": 25, "
                         "\"cone_delta\": 10}]}";
    memcpy(text + n - 1, lights, strlen(lights) + 1);
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_string(text, strlen(text), "cornell+delta", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    CstRenderSettings st = sized(48, CST_FILTER_BOX);
    three_way(s, &st, 48, 12, 1024, 256, 51, "delta lights");
    Regions rp = regions(48, 12), rl = rp;
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 1024, 61, &rp);
    split_regions(s, &st, CST_INTEGRATOR_LIGHT, 256, 7000, &rl);
    compare(&rp, &rl, "path (delta lights)", "light (delta lights)");
    cst_scene_destroy(s);
}

/* An environment map lighting a plane and a box, seen from above (the camera sees no sky,
 * which light paths could not render): light paths start on the disk of the bounding
 * sphere with directions from the map's distribution; camera paths escape into it; NEE
 * samples it. The light tracer must agree too. */
static void test_environment_scene(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white, red;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.7f, 0.7f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_rgb(0.7f, 0.2f, 0.1f);
    assert_int_equal(scene_add_material(s, &m, &red, &err), CST_OK);
    /* Small, so that the light paths' disk (the bounding sphere's) is not much wider
     * than what the camera sees, or the light tracer would have no power here. */
    Vec3 plane[4] = {{-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}};
    assert_int_equal(scene_add_quad(s, plane, white, NULL, &err), CST_OK);
    /* A unit box on the plane, faces outward. */
    const Vec3 b0 = {-0.5f, 0.0f, -0.5f}, b1 = {0.5f, 1.0f, 0.5f};
    Vec3 faces[5][4] = {
        {{b0.x, b1.y, b0.z}, {b0.x, b1.y, b1.z}, {b1.x, b1.y, b1.z}, {b1.x, b1.y, b0.z}}, /* top, +y */
        {{b0.x, b0.y, b0.z}, {b0.x, b1.y, b0.z}, {b1.x, b1.y, b0.z}, {b1.x, b0.y, b0.z}}, /* -z */
        {{b0.x, b0.y, b1.z}, {b1.x, b0.y, b1.z}, {b1.x, b1.y, b1.z}, {b0.x, b1.y, b1.z}}, /* +z */
        {{b0.x, b0.y, b0.z}, {b0.x, b0.y, b1.z}, {b0.x, b1.y, b1.z}, {b0.x, b1.y, b0.z}}, /* -x */
        {{b1.x, b0.y, b0.z}, {b1.x, b1.y, b0.z}, {b1.x, b1.y, b1.z}, {b1.x, b0.y, b1.z}}, /* +x */
    };
    for (int k = 0; k < 5; k++) assert_int_equal(scene_add_quad(s, faces[k], red, NULL, &err), CST_OK);
    enum { W = 32, H = 16 };
    float *rgb = malloc(W * H * 3 * sizeof *rgb);
    assert_non_null(rgb);
    for (int r = 0; r < H; r++)
        for (int c = 0; c < W; c++) {
            float *p = &rgb[3 * (r * W + c)];
            float sky = 0.3f + 0.7f * (float)(H - r) / H;
            p[0] = 0.5f * sky; p[1] = 0.6f * sky; p[2] = sky;
            if (r == 3 && c == 5) { p[0] = 80.0f; p[1] = 70.0f; p[2] = 50.0f; }
        }
    EnvMap env;
    assert_int_equal(envmap_init_image(&env, rgb, W, H, color_s(1.0f), &err), CST_OK);
    assert_int_equal(scene_set_environment(s, &env, &err), CST_OK);
    CameraDesc cam = {{0.3f, 4.0f, -0.2f}, {0, 0, 0}, {0, 0, 1}, 50.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st = sized(32, CST_FILTER_BOX);
    three_way(s, &st, 32, 8, 1024, 256, 71, "environment");
    Regions rp = regions(32, 8), rl = rp;
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 1024, 81, &rp);
    split_regions(s, &st, CST_INTEGRATOR_LIGHT, 256, 9000, &rl);
    compare(&rp, &rl, "path (environment)", "light (environment)");
    scene_destroy(s);
}

/* Dispersion (test_bidir --spectral): scenes/prism.pbrt without its floor, a white slit
 * seen through an SF11 prism, so every path is camera -> glass -> glass -> slit. BDPT
 * and VCM share each path's wavelengths between their subpaths; the refraction at the
 * dispersive glass keeps the hero wavelength alone (pbrt-v4's TerminateSecondary) as the
 * path tracer does, so all three see the slit spread into its spectrum: compared on the
 * image and on 16 one-pixel columns across the spectrum. Before, BDPT and VCM refracted
 * every wavelength at the ior's mean and saw the slit undispersed (column 31, blue:
 * path 0.174, bdpt 0.0027, z = 4.1). RGB mode: undispersed in all three. */
static void test_dispersion(void **state)
{
    (void)state;
    static const char text[] =
        "LookAt -3.08035 0.6 5.16444  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [ 30 ]\n"
        "Film \"rgb\" \"integer xresolution\" [ 64 ] \"integer yresolution\" [ 64 ]\n"
        "Integrator \"path\" \"integer maxdepth\" [ 16 ]\nWorldBegin\n"
        "AttributeBegin\nMaterial \"dielectric\" \"spectrum eta\" \"glass-SF11\"\n"
        "Shape \"trianglemesh\" \"integer indices\" [ 0 1 2 3 5 4 0 4 1 0 3 4 1 5 2 1 4 5 2 3 0 2 5 3 ] "
        "\"point3 P\" [ 0.92376 -1 0  -0.46188 -1 0.8  -0.46188 -1 -0.8  0.92376 1 0  -0.46188 1 0.8  "
        "-0.46188 1 -0.8 ]\nAttributeEnd\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [ 30 30 30 ] \"bool twosided\" true\n"
        "Material \"diffuse\" \"rgb reflectance\" [ 0 0 0 ]\n"
        "Shape \"trianglemesh\" \"integer indices\" [ 0 1 2 0 2 3 ] \"point3 P\" [ 5.24394 -1 -0.04687  "
        "5.2403 -1 0.003  5.2403 1.6 0.003  5.24394 1.6 -0.04687 ]\nAttributeEnd\n";
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt_string(text, strlen(text), "prism.pbrt", NULL, &s, &err) != CST_OK) fail_msg("%s", err.msg);
    /* The spectrum spreads over columns 36-43 of 64: the image and 16 one-pixel columns
     * across it, so that each compares one band of colour. */
    CstRenderSettings st = sized(64, CST_FILTER_BOX);
    Regions rp = regions(64, 64);
    rp.count = 1; /* the whole image; then the columns */
    for (int i = 0; i < 16; i++, rp.count++) {
        int *r = rp.rect[rp.count];
        r[0] = 30 + i, r[1] = 0, r[2] = 31 + i, r[3] = 64;
    }
    Regions rb = rp, rv = rp;
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 1024, 91, &rp);
    split_regions(s, &st, CST_INTEGRATOR_BDPT, 256, 1091, &rb);
    split_regions(s, &st, CST_INTEGRATOR_VCM, 256, 5091, &rv);
    compare(&rp, &rb, "path (prism)", "bdpt (prism)");
    compare(&rp, &rv, "path (prism)", "vcm (prism)");
    compare(&rb, &rv, "bdpt (prism)", "vcm (prism)");
    cst_scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_spheres),
        cmocka_unit_test(test_max_depth_and_tent),
        cmocka_unit_test(test_through_glass),
        cmocka_unit_test(test_emitting_furnace),
        cmocka_unit_test(test_delta_lights_cornell),
        cmocka_unit_test(test_environment_scene),
        cmocka_unit_test(test_dispersion),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
