/* Moving analytic shapes (a sphere, disk or cylinder in an object of its own, placed by a
 * moving instance: cst_scene_add_object_shape, pbrt-v4's AnimatedPrimitive): each renders
 * the closed-form time average of its coverage per column, from pbrt (ActiveTransform) and
 * from JSON ("motion"); path and BDPT agree on a lit scene with a moving sphere and disk;
 * and SPPM in fog with a moving sphere between the light and the fog agrees with path (its
 * photons and visible points in media at the iteration's instant). 4 standard errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"
#include "render/media_scenes.h"
#include "scene/scene.h"

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s", e->msg);
}

/* ------------------------------------------------------------------ coverage */

/* An orthographic view 8 units wide (x in [-4, 4]) and 1 high (y in [-0.5, 0.5]), W x H
 * pixels; the shape's centre moves from X0 to X1 over the shutter. */
enum { W = 32, H = 4, SPP = 64 };
static const double X0 = -1.5, X1 = 1.5;

/* The sky's share of column px (1 minus the coverage averaged over the column's area and
 * the shutter). At (x, y) the shape covers while |x - c(t)| < w(y), c(t) = X0 + (X1 - X0) t:
 * a t interval, exact; w(y) = sqrt(r^2 - y^2) for a disk (a sphere's or a facing disk's
 * silhouette; 0 where |y| >= r), r for a band (a cylinder along y). The area integral by
 * the midpoint rule on 400 x 64 points (error far below the 4-sigma margins). */
static double expected_sky(int px, double r, int band)
{
    const double a = -4.0 + 8.0 * px / W, b = -4.0 + 8.0 * (px + 1) / W, v = X1 - X0;
    const int nx = 400, ny = 64;
    double sum = 0.0;
    for (int j = 0; j < ny; j++) {
        const double y = -0.5 + (j + 0.5) / ny;
        const double w = band ? r : (fabs(y) < r ? sqrt(r * r - y * y) : 0.0);
        for (int i = 0; i < nx; i++) {
            const double x = a + (b - a) * (i + 0.5) / nx;
            double lo = (x - w - X0) / v, hi = (x + w - X0) / v;
            lo = lo < 0.0 ? 0.0 : lo;
            hi = hi > 1.0 ? 1.0 : hi;
            sum += hi > lo ? hi - lo : 0.0;
        }
    }
    return 1.0 - sum / (nx * ny);
}

static CstFilm *render_cov(const CstScene *s)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = W, rs.height = H, rs.spp = SPP, rs.threads = 2, rs.seed = 5, rs.seed_set = 1;
    rs.filter = CST_FILTER_BOX;
    rs.integrator = CST_INTEGRATOR_PATH;
    rs.color_mode = CST_COLOR_RGB;
    rs.max_depth = 1;
    rs.sampler = CST_SAMPLER_INDEPENDENT; /* the film's per-pixel variances are the errors */
    CstFilm *f = NULL;
    CstRenderStats stats;
    CstError e;
    ok(cst_render(s, &rs, &f, &stats, &e), &e);
    return f;
}

/* Every column's sky share (relative to column 0's, which nothing covers) against
 * expected_sky within 4 standard errors; at least 8 columns partly covered. */
static void check_coverage(const CstScene *s, const char *what, double r, int band)
{
    CstFilm *f = render_cov(s);
    double sky[3], sky_var[3];
    cst_film_pixel(f, 0, 0, sky);
    cst_film_pixel_variance(f, 0, 0, sky_var);
    assert_true(sky[0] > 0.0 && sky_var[0] == 0.0);
    int blurred = 0;
    double worst = 0.0;
    for (int x = 0; x < W; x++) {
        double mean = 0.0, var = 0.0;
        for (int y = 0; y < H; y++) {
            double m[3], v[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, v);
            mean += m[0] / (H * sky[0]);
            var += v[0] / (H * H * sky[0] * sky[0]);
        }
        const double want = expected_sky(x, r, band), se = sqrt(var > 0.0 ? var : 0.0) + 1e-9;
        if (want > 0.05 && want < 0.95) blurred++;
        if (fabs(mean - want) / se > worst && fabs(mean - want) > 1e-6) worst = fabs(mean - want) / se;
        if (fabs(mean - want) > 4.0 * se + 1e-6)
            fail_msg("%s: column %d: sky %.5f, expected %.5f (4 sigma = %.5f)", what, x, mean, want, 4.0 * se);
    }
    print_message("%s: largest |z| over the columns %.2f\n", what, worst);
    assert_true(blurred >= 8);
    cst_film_destroy(f);
}

static void count_static(void *user, CstWarningCode code, const char *message)
{
    (void)code;
    if (strstr(message, "rendered static") || strstr(message, "skipped") || strstr(message, "tessellated"))
        ++*(int *)user;
}

/* pbrt: a black sphere (radius 1), a facing disk (radius 1) and a cylinder along y (radius
 * 0.5) under ActiveTransform, each one moving instance of an object holding the analytic
 * shape, without a warning. */
static void test_pbrt_moving_shapes(void **state)
{
    (void)state;
    static const struct { const char *shape; double r; int band; } cases[] = {
        {"Shape \"sphere\" \"float radius\" 1", 1.0, 0},
        {"Shape \"disk\" \"float radius\" 1", 1.0, 0},
        {"Rotate 90 1 0 0\n  Shape \"cylinder\" \"float radius\" 0.5 \"float zmin\" -3 \"float zmax\" 3", 0.5, 1},
    };
    for (size_t k = 0; k < sizeof cases / sizeof *cases; k++) {
        char text[1024];
        snprintf(text, sizeof text,
                 "Scale -1 1 1\nLookAt 0 0 5  0 0 0  0 1 0\n"
                 "Camera \"orthographic\" \"float screenwindow\" [-4 4 -0.5 0.5]\n"
                 "WorldBegin\n"
                 "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
                 "AttributeBegin\n"
                 "  ActiveTransform StartTime\n  Translate %g 0 0\n"
                 "  ActiveTransform EndTime\n  Translate %g 0 0\n  ActiveTransform All\n"
                 "  Material \"diffuse\" \"rgb reflectance\" [0 0 0]\n"
                 "  %s\n"
                 "AttributeEnd\n",
                 X0, X1, cases[k].shape);
        CstScene *s = NULL;
        CstError e;
        int warnings = 0;
        CstLoadOptions opt = {0};
        opt.warning = count_static;
        opt.warning_user = &warnings;
        ok(cst_scene_load_pbrt_string(text, strlen(text), "t.pbrt", &opt, &s, &e), &e);
        assert_int_equal(warnings, 0);
        assert_non_null(s->instances);
        assert_int_equal(s->instances->num_motions, 1);
        assert_int_equal(s->instances->protos[0].num_shapes, 1);
        assert_int_equal(s->num_shapes + s->num_spheres + s->num_triangles, 0);
        check_coverage(s, cases[k].shape, cases[k].r, cases[k].band);
        cst_scene_destroy(s);
    }
}

/* JSON: a black sphere (radius 1) with "motion", the same closed form; a moving sphere
 * cannot emit (a located error). */
static void test_json_moving_sphere(void **state)
{
    (void)state;
    static const char head[] =
        "{\"film\": {\"width\": 32, \"height\": 4},\n"
        " \"camera\": {\"type\": \"orthographic\", \"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"height\": 1},\n"
        " \"environment\": {\"radiance\": [1, 1, 1]},\n"
        " \"materials\": {\"black\": {\"type\": \"diffuse\", \"albedo\": [0, 0, 0]}},\n"
        " \"shapes\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"black\",%s\n"
        "   \"motion\": {\"transform\": {\"translate\": [%g, 0, 0]}, \"transform_end\": {\"translate\": [%g, 0, 0]}}}]}\n";
    char text[1024];
    snprintf(text, sizeof text, head, "", X0, X1);
    CstScene *s = NULL;
    CstError e;
    ok(cst_scene_load_json_string(text, strlen(text), "m.json", &s, &e), &e);
    assert_non_null(s->instances);
    assert_int_equal(s->instances->num_motions, 1);
    assert_int_equal(s->num_spheres + s->num_shapes, 0);
    check_coverage(s, "json sphere", 1.0, 0);
    cst_scene_destroy(s);
    s = NULL;
    snprintf(text, sizeof text, head, " \"emission\": {\"radiance\": [1, 1, 1]},", X0, X1);
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), "m.json", &s, &e), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(e.msg, "m.json:6:"));
    assert_non_null(strstr(e.msg, "emission"));
    assert_null(s);
}

/* ------------------------------------------------------------------ path vs bdpt */

enum { MS = 16, MBLOCK = 8 };

/* A grey floor and back wall, a point light, and, moving across in front of the wall, a grey
 * sphere (its shadow sweeps the wall) and a grey disk turning about its diameter. */
static CstScene *lit_sphere_scene(void)
{
    CstError e;
    CstScene *s = NULL;
    ok(cst_scene_create(&s, &e), &e);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    int grey = -1, obj = -1, disk = -1;
    ok(cst_scene_add_material(s, &md, &grey, &e), &e);
    const uint32_t idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
    const float wall[4][3] = {{-4, -3, -2}, {4, -3, -2}, {4, 3, -2}, {-4, 3, -2}};
    const float floor_pos[4][3] = {{-4, -1.5f, -2}, {-4, -1.5f, 4}, {4, -1.5f, 4}, {4, -1.5f, -2}};
    CstMeshDesc m = {0};
    m.positions = wall;
    m.num_vertices = 4;
    m.indices = idx;
    m.num_triangles = 2;
    m.material = grey;
    ok(cst_scene_add_mesh(s, &m, NULL, &e), &e);
    m.positions = floor_pos;
    ok(cst_scene_add_mesh(s, &m, NULL, &e), &e);
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_SPHERE;
    sd.radius = 0.5f;
    sd.material = grey;
    ok(cst_scene_add_object_shape(s, -1, &sd, &obj, &e), &e);
    const float t0[12] = {1, 0, 0, -1.2f, 0, 1, 0, 0.2f, 0, 0, 1, 0};
    const float t1[12] = {1, 0, 0, 1.2f, 0, 1, 0, 0.2f, 0, 0, 1, 0};
    ok(cst_scene_add_instance_motion(s, obj, t0, t1, &e), &e);
    sd.type = CST_SHAPE_DISK;
    sd.radius = 0.4f;
    ok(cst_scene_add_object_shape(s, -1, &sd, &disk, &e), &e);
    const float d0[12] = {1, 0, 0, 1.0f, 0, 1, 0, -0.8f, 0, 0, 1, 0};
    const float d1[12] = {1, 0, 0, -1.0f, 0, 0, -1, -0.8f, 0, 1, 0, 0}; /* turned 90 degrees about x */
    ok(cst_scene_add_instance_motion(s, disk, d0, d1, &e), &e);
    CstLightDesc l = {0};
    l.type = CST_LIGHT_POINT;
    l.position[0] = 0.3f;
    l.position[1] = 1.0f;
    l.position[2] = 1.5f;
    l.intensity[0] = l.intensity[1] = l.intensity[2] = 6.0f;
    ok(cst_scene_add_light(s, &l, &e), &e);
    CstCameraDesc cam = {0};
    cam.type = CST_CAMERA_PERSPECTIVE;
    cam.position[2] = 5.0f;
    cam.fov = 40.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

static CstRenderSettings lit_settings(void)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = MS;
    st.filter = CST_FILTER_BOX;
    st.color_mode = CST_COLOR_RGB;
    st.threads = 2;
    st.max_depth = 4;
    return st;
}

/* BDPT's light subpaths at their camera path's time meet the sphere and disk where that
 * instant places them (their shadows on the wall and floor move with them). */
static void test_lit_sphere_bdpt_agrees(void **state)
{
    (void)state;
    CstScene *s = lit_sphere_scene();
    CstRenderSettings st = lit_settings();
    Regions ref = regions(MS, MBLOCK), r = regions(MS, MBLOCK);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 512, 3, &ref);
    st.spp = 32;
    split_regions(s, &st, CST_INTEGRATOR_BDPT, 16, 101, &r);
    compare(&ref, &r, "path", "bdpt (moving sphere and disk)");
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ sppm in fog */

/* The fog box of media_scenes.h (an open box lit by a quad under the ceiling, a ball of
 * homogeneous fog and a diffuse sphere), with a grey sphere moving between the light and
 * the fog: its shadow sweeps through the fog over the shutter, so photons traced at another
 * instant than the iteration's visible points would light the fog where it is not. */
static Scene *fog_motion_box(void)
{
    CstError err;
    int wall, lightm, obj = -1;
    Scene *s = fog_box_uncommitted(FOG_HOMOGENEOUS, &wall, &lightm);
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_SPHERE;
    sd.radius = 0.3f;
    sd.material = wall;
    ok(cst_scene_add_object_shape(s, -1, &sd, &obj, &err), &err);
    /* Under the light at the start (the fog in its shadow), out of the open box at the end. */
    const float t0[12] = {1, 0, 0, 0.0f, 0, 1, 0, 0.65f, 0, 0, 1, 0};
    const float t1[12] = {1, 0, 0, 0.0f, 0, 1, 0, 0.65f, 0, 0, 1, 1.2f};
    ok(cst_scene_add_instance_motion(s, obj, t0, t1, &err), &err);
    fog_box_commit(s);
    return s;
}

/* path (independent pixels) and SPPM (16 independent renders of 16 iterations; the initial
 * radius test_sppm_media's FOG_R0, whose bias there is below a quarter of this comparison's
 * standard error) on the whole 16 x 16 image and its four 8 x 8 blocks. */
static void test_sppm_fog_motion(void **state)
{
    (void)state;
    Scene *s = fog_motion_box();
    CstRenderSettings st = lit_settings();
    st.max_depth = 5;
    st.photon_radius = 0.05;
    Regions path = regions(MS, MBLOCK), sppm = regions(MS, MBLOCK);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 2048, 7, &path);
    st.spp = 16;
    split_regions(s, &st, CST_INTEGRATOR_SPPM, 32, 17, &sppm);
    compare(&path, &sppm, "path (fog, moving sphere)", "sppm");
    scene_destroy(s);
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++)
        if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) cmocka_set_test_filter(argv[i + 1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pbrt_moving_shapes),
        cmocka_unit_test(test_json_moving_sphere),
        cmocka_unit_test(test_lit_sphere_bdpt_agrees),
        cmocka_unit_test(test_sppm_fog_motion),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
