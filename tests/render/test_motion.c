/* Motion blur: the decomposed interpolation of motion transforms (math/motion.c), the bound
 * of a moving instance over the shutter, moving instances' hits against static instances
 * placed at the same time, a square moving across the image against the closed-form time
 * average of its coverage, the same image from every acceleration back end, the JSON
 * "motion" key and the integrators that refuse motion. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <math.h>
#include <string.h>
#include <cmocka.h>

#include "accel/instances.h"
#include "caustic/caustic.h"
#include "core/rng.h"
#include "math/motion.h"

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s", e->msg);
}

/* ------------------------------------------------------------------ interpolation */

static void test_motion_interpolation(void **state)
{
    (void)state;
    /* start: identity; end: rotated 90 degrees about z, scaled 3, moved by (4, 0, 0). */
    Transform a = transform_identity();
    Transform b = transform_compose(transform_translate(v3(4.0f, 0.0f, 0.0f)),
                                    transform_compose(transform_rotate_degrees(v3(0, 0, 1), 90.0),
                                                      transform_scale(v3s(3.0f))));
    MotionTransform mt;
    assert_true(motion_init(&mt, &a, &b));
    Transform t0 = motion_at(&mt, 0.0f), t1 = motion_at(&mt, 1.0f);
    assert_memory_equal(&t0, &a, sizeof a);
    assert_memory_equal(&t1, &b, sizeof b);
    /* Halfway: rotated 45 degrees (slerp; the matrices' linear blend would also shrink the
     * rotation part to cos 45), scaled 2, moved by 2. */
    Transform h = motion_at(&mt, 0.5f);
    Vec3 x = transform_vector(&h, v3(1, 0, 0)), o = transform_point(&h, v3s(0.0f));
    const float c45 = 2.0f * sqrtf(0.5f);
    assert_float_equal(x.x, c45, 1e-5);
    assert_float_equal(x.y, c45, 1e-5);
    assert_float_equal(x.z, 0.0f, 1e-6);
    assert_float_equal(o.x, 2.0f, 1e-6);
    /* A quarter: 22.5 degrees, scale 1.5. */
    Transform q = motion_at(&mt, 0.25f);
    x = transform_vector(&q, v3(1, 0, 0));
    assert_true(fabs((double)x.x - 1.5 * cos(3.14159265358979 / 8.0)) < 1e-5);
    assert_true(fabs((double)x.y - 1.5 * sin(3.14159265358979 / 8.0)) < 1e-5);
    /* Mirroring ends (det < 0): the reflection stays in the stretch at every time. */
    Transform m0 = transform_scale(v3(-1.0f, 1.0f, 1.0f));
    Transform m1 = transform_compose(transform_rotate_degrees(v3(0, 1, 0), 60.0), m0);
    assert_true(motion_init(&mt, &m0, &m1));
    for (int k = 0; k <= 8; k++) {
        Transform t = motion_at(&mt, (float)k / 8.0f);
        assert_true(transform_det(&t) < -0.999 && transform_det(&t) > -1.001);
    }
    Transform sing = transform_scale(v3(1.0f, 0.0f, 1.0f));
    assert_false(motion_init(&mt, &a, &sing));
}

/* Points of a box moved at random times stay inside motion_bounds of the box. */
static void test_motion_bounds(void **state)
{
    (void)state;
    Transform a = transform_compose(transform_translate(v3(-2.0f, 1.0f, 0.0f)),
                                    transform_rotate_degrees(v3(1, 1, 0), 10.0));
    Transform b = transform_compose(transform_translate(v3(3.0f, -1.0f, 2.0f)),
                                    transform_compose(transform_rotate_degrees(v3(0, 1, 1), 170.0),
                                                      transform_scale(v3(0.5f, 2.0f, 1.0f))));
    MotionTransform mt;
    assert_true(motion_init(&mt, &a, &b));
    BBox box = {v3(-1.0f, -0.5f, -2.0f), v3(1.0f, 0.5f, 2.0f)};
    BBox mb = motion_bounds(&mt, box);
    Pcg32 rng;
    pcg32_seed(&rng, 7, 1);
    for (int i = 0; i < 20000; i++) {
        float t = pcg32_float(&rng);
        Vec3 p = v3(box.min.x + (box.max.x - box.min.x) * pcg32_float(&rng),
                    box.min.y + (box.max.y - box.min.y) * pcg32_float(&rng),
                    box.min.z + (box.max.z - box.min.z) * pcg32_float(&rng));
        Transform xf = motion_at(&mt, t);
        Vec3 w = transform_point(&xf, p);
        assert_true(w.x >= mb.min.x && w.y >= mb.min.y && w.z >= mb.min.z);
        assert_true(w.x <= mb.max.x && w.y <= mb.max.y && w.z <= mb.max.z);
    }
}

/* ------------------------------------------------------------------ instance hits */

static const Vec3 CUBE_POS[8] = {{-1, -1, -1}, {1, -1, -1}, {1, 1, -1}, {-1, 1, -1},
                                 {-1, -1, 1},  {1, -1, 1},  {1, 1, 1},  {-1, 1, 1}};
static const int CUBE_IDX[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                                 2, 3, 7, 2, 7, 6, 1, 2, 6, 1, 6, 5, 0, 4, 7, 0, 7, 3};

/* A moving instance hit at time t is hit where a static instance placed at motion_at(t)
 * is: same triangle, same t to float rounding. */
static void test_moving_instance_hits(void **state)
{
    (void)state;
    CstError e;
    Transform a = transform_translate(v3(-2.0f, 0.0f, 0.0f));
    Transform b = transform_compose(transform_translate(v3(2.0f, 0.5f, 0.0f)),
                                    transform_rotate_degrees(v3(0, 0, 1), 120.0));
    int mat[12] = {0};
    InstanceSet moving = {0};
    int proto;
    ok(instances_add_proto(&moving, CUBE_POS, NULL, 8, CUBE_IDX, mat, 12, &proto, &e), &e);
    ok(instances_add_moving(&moving, proto, &a, &b, &e), &e);
    ok(instances_build(&moving, &e), &e);
    assert_int_equal(moving.num_motions, 1);
    Pcg32 rng;
    pcg32_seed(&rng, 11, 3);
    int hits = 0;
    for (int i = 0; i < 400; i++) {
        float time = pcg32_float(&rng);
        Ray r = ray_make_at(v3(-4.0f + 8.0f * pcg32_float(&rng), -1.5f + 3.0f * pcg32_float(&rng), 10.0f),
                            v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, time);
        Transform at = motion_at(&moving.motions[0], time);
        InstanceSet fixed = {0};
        ok(instances_add_proto(&fixed, CUBE_POS, NULL, 8, CUBE_IDX, mat, 12, &proto, &e), &e);
        ok(instances_add(&fixed, proto, &at, &e), &e);
        ok(instances_build(&fixed, &e), &e);
        InstHit hm, hf;
        bool a_hit = instances_intersect(&moving, &r, &hm), f_hit = instances_intersect(&fixed, &r, &hf);
        assert_int_equal(a_hit, f_hit);
        assert_int_equal(instances_occluded(&moving, &r), f_hit);
        if (a_hit) {
            hits++;
            assert_int_equal(hm.prim, hf.prim);
            assert_float_equal(hm.t, hf.t, 1e-5 * hf.t);
        }
        instances_free(&fixed);
    }
    assert_true(hits > 50 && hits < 350); /* the cube is missed and hit */
    instances_free(&moving);
}

/* ------------------------------------------------------------------ moving square */

enum { W = 32, H = 4, SPP = 64 };
static const float HALF = 0.5f, X0 = -1.5f, X1 = 1.5f;

/* A black square (albedo 0) of half-width HALF, taller than the view, moving from x = X0 to
 * X1 over the shutter in front of a white sky, seen by an orthographic camera 8 units wide
 * (W pixels): only the sky contributes (1 per escaping camera ray). */
static CstScene *square_scene(const char *accel, int moving, int perspective)
{
    CstError e;
    CstScene *s = NULL;
    ok(cst_scene_create(&s, &e), &e);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.albedo[0] = md.albedo[1] = md.albedo[2] = 0.0f;
    int mat = -1, obj = -1;
    ok(cst_scene_add_material(s, &md, &mat, &e), &e);
    const float pos[4][3] = {{-HALF, -3, 0}, {HALF, -3, 0}, {HALF, 3, 0}, {-HALF, 3, 0}};
    const uint32_t idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
    CstMeshDesc m = {0};
    m.positions = pos;
    m.num_vertices = 4;
    m.indices = idx;
    m.num_triangles = 2;
    m.material = mat;
    ok(cst_scene_add_object(s, &m, &obj, NULL, &e), &e);
    const float t0[12] = {1, 0, 0, X0, 0, 1, 0, 0, 0, 0, 1, 0};
    const float t1[12] = {1, 0, 0, X1, 0, 1, 0, 0, 0, 0, 1, 0};
    ok(cst_scene_add_instance_motion(s, obj, t0, moving ? t1 : t0, &e), &e);
    /* A static black quad out of view, so every flat back end has a tree to traverse. */
    const float side_pos[4][3] = {{-9, 5, -5}, {9, 5, -5}, {9, 6, -5}, {-9, 6, -5}};
    CstMeshDesc f = m;
    f.positions = side_pos;
    ok(cst_scene_add_mesh(s, &f, NULL, &e), &e);
    CstCameraDesc cam = {0};
    cam.type = perspective ? CST_CAMERA_PERSPECTIVE : CST_CAMERA_ORTHOGRAPHIC;
    cam.fov = 30.0f;
    cam.position[2] = 5.0f;
    cam.height = 1.0f; /* W / H = 8: the view is 8 units wide, 1 high */
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    ok(cst_scene_set_environment_constant(s, (const float[3]){1, 1, 1}, &e), &e);
    if (accel) ok(cst_scene_set_accel(s, accel, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

static CstFilm *render(const CstScene *s, CstIntegrator integ, CstStatus expect, CstError *e)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = W, rs.height = H, rs.spp = SPP, rs.threads = 2, rs.seed = 5, rs.seed_set = 1;
    rs.filter = CST_FILTER_BOX;
    rs.integrator = integ;
    rs.color_mode = CST_COLOR_RGB;
    rs.sampler = CST_SAMPLER_INDEPENDENT; /* the checks' errors are the film's per-pixel variances:
                                           * independent samples and pixels, not zsobol's */
    CstFilm *f = NULL;
    CstRenderStats stats;
    CstStatus st = cst_render(s, &rs, &f, &stats, e);
    if (expect == CST_OK) ok(st, e);
    else if (st != expect) fail_msg("status %d, expected %d: %s", (int)st, (int)expect, e->msg);
    return f;
}

/* The sky's share of pixel column px: 1 minus the square's coverage averaged over the
 * pixel's x range and the shutter. At x, the square covers it while |x - c(t)| < HALF with
 * c(t) = X0 + (X1 - X0) t: a t interval, clipped to [0, 1] (exact); its length is piecewise
 * linear in x, integrated by the midpoint rule on 4000 steps (error ~1e-8). */
static double expected_sky(int px)
{
    const double a = -4.0 + 8.0 * px / W, b = -4.0 + 8.0 * (px + 1) / W, v = (double)(X1 - X0);
    const double half = (double)HALF, x0 = (double)X0;
    double sum = 0.0;
    const int n = 4000;
    for (int i = 0; i < n; i++) {
        double x = a + (b - a) * (i + 0.5) / n;
        double lo = (x - half - x0) / v, hi = (x + half - x0) / v;
        lo = lo < 0.0 ? 0.0 : lo;
        hi = hi > 1.0 ? 1.0 : hi;
        sum += hi > lo ? hi - lo : 0.0;
    }
    return 1.0 - sum / n;
}

/* Column means of the image (H rows, SPP samples each pixel) against expected_sky, within 4
 * standard errors from the film's variances (a column's pixels are independent). */
static void check_columns(const CstFilm *f, const char *what)
{
    int blurred = 0;
    for (int x = 0; x < W; x++) {
        double mean = 0.0, var = 0.0;
        for (int y = 0; y < H; y++) {
            double m[3], v[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, v);
            mean += m[0] / H;
            var += v[0] / (H * H);
        }
        double want = expected_sky(x);
        /* The standard error of a column with no variance (all sky or all square) is 0: its
         * mean must be exact; a binomial floor keeps 4 sigma meaningful near 0 and 1. */
        double se = sqrt(var > 0.0 ? var : 0.0) + 1e-9;
        if (want > 0.05 && want < 0.95) blurred++;
        if (fabs(mean - want) > 4.0 * se + 1e-6)
            fail_msg("%s: column %d: sky %.5f, expected %.5f (4 sigma = %.5f)", what, x, mean, want, 4.0 * se);
    }
    assert_true(blurred >= 8); /* the blur spans 16 columns, partly covered */
}

static void test_moving_square_coverage(void **state)
{
    (void)state;
    CstError e;
    CstScene *s = square_scene(NULL, 1, 0);
    CstFilm *f = render(s, CST_INTEGRATOR_PATH, CST_OK, &e);
    check_columns(f, "path");
    cst_film_destroy(f);
    f = render(s, CST_INTEGRATOR_WHITTED, CST_OK, &e);
    check_columns(f, "whitted");
    cst_film_destroy(f);
    /* Integrators whose light paths do not carry a time yet refuse the scene. */
    const CstIntegrator refused[] = {CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM,
                                     CST_INTEGRATOR_SPPM, CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_PSSMLT};
    cst_scene_destroy(s);
    s = square_scene(NULL, 1, 1); /* bdpt and vcm refuse orthographic cameras first */
    for (size_t i = 0; i < sizeof refused / sizeof *refused; i++) {
        f = render(s, refused[i], CST_ERR_UNSUPPORTED, &e);
        assert_non_null(strstr(e.msg, "motion blur"));
        cst_film_destroy(f);
    }
    cst_scene_destroy(s);
    /* Equal ends: a static instance, no time drawn: the square sharp at X0. */
    s = square_scene(NULL, 0, 0);
    f = render(s, CST_INTEGRATOR_PATH, CST_OK, &e);
    double m[3];
    cst_film_pixel(f, 8, 1, m); /* x in [-2, -1.75]: inside the square at X0 */
    assert_true(m[0] == 0.0);
    cst_film_pixel(f, 16, 1, m); /* x in [0, 0.25]: sky */
    assert_true(m[0] == 1.0);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

/* Every acceleration back end of this build renders the moving scene bit for bit alike
 * (instances sit beside the flat back end, in their own two-level tree). */
static void test_backends_agree(void **state)
{
    (void)state;
    CstError e;
    CstScene *ref_scene = square_scene("bvh", 1, 0);
    CstFilm *ref = render(ref_scene, CST_INTEGRATOR_PATH, CST_OK, &e);
    float *a = malloc(sizeof(float) * 3 * W * H), *b = malloc(sizeof(float) * 3 * W * H);
    assert_non_null(a);
    assert_non_null(b);
    cst_film_pixels(ref, a);
    for (int i = 0;; i++) {
        const char *name = cst_list_names(CST_NAMES_ACCEL, i);
        if (!name) break;
        CstScene *s = square_scene(name, 1, 0);
        CstFilm *f = render(s, CST_INTEGRATOR_PATH, CST_OK, &e);
        cst_film_pixels(f, b);
        if (memcmp(a, b, sizeof(float) * 3 * W * H) != 0) fail_msg("accel %s renders another image", name);
        cst_film_destroy(f);
        cst_scene_destroy(s);
    }
    free(a);
    free(b);
    cst_film_destroy(ref);
    cst_scene_destroy(ref_scene);
}

/* ------------------------------------------------------------------ light vs path */

/* A grey square (albedo 0.5) moving and turning in front of an emitting wall, lit by a point
 * light beside the camera, seen through a pinhole: the light tracer (its own time per light
 * path, the time carried to its camera connections) and the path tracer (the camera path's)
 * estimate the same time-averaged image. */
static CstScene *lit_scene(void)
{
    CstError e;
    CstScene *s = NULL;
    ok(cst_scene_create(&s, &e), &e);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    int grey = -1, obj = -1;
    ok(cst_scene_add_material(s, &md, &grey, &e), &e);
    const float pos[4][3] = {{-0.6f, -0.6f, 0}, {0.6f, -0.6f, 0}, {0.6f, 0.6f, 0}, {-0.6f, 0.6f, 0}};
    const uint32_t idx[2][3] = {{0, 1, 2}, {0, 2, 3}};
    CstMeshDesc m = {0};
    m.positions = pos;
    m.num_vertices = 4;
    m.indices = idx;
    m.num_triangles = 2;
    m.material = grey;
    ok(cst_scene_add_object(s, &m, &obj, NULL, &e), &e);
    const float t0[12] = {1, 0, 0, -1.2f, 0, 1, 0, 0, 0, 0, 1, 0};
    const float t1[12] = {0, -1, 0, 1.2f, 1, 0, 0, 0.3f, 0, 0, 1, 0}; /* turned 90 degrees about z */
    ok(cst_scene_add_instance_motion(s, obj, t0, t1, &e), &e);
    const float wall[4][3] = {{-4, -3, -2}, {4, -3, -2}, {4, 3, -2}, {-4, 3, -2}};
    CstMeshDesc w = m;
    w.positions = wall;
    w.emission.radiance[0] = w.emission.radiance[1] = w.emission.radiance[2] = 0.2f;
    ok(cst_scene_add_mesh(s, &w, NULL, &e), &e);
    CstLightDesc l = {0};
    l.type = CST_LIGHT_POINT;
    l.position[0] = 1.0f;
    l.position[2] = 4.0f;
    l.intensity[0] = l.intensity[1] = l.intensity[2] = 50.0f;
    ok(cst_scene_add_light(s, &l, &e), &e);
    CstCameraDesc cam = {0};
    cam.type = CST_CAMERA_PERSPECTIVE;
    cam.position[2] = 5.0f;
    cam.fov = 40.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

enum { LW = 24, LH = 16, LSPP = 256, BLOCK = 4 };

static CstFilm *render_lit(const CstScene *s, CstIntegrator integ)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = LW, rs.height = LH, rs.spp = LSPP, rs.threads = 2, rs.seed = 9, rs.seed_set = 1;
    rs.filter = CST_FILTER_BOX;
    rs.integrator = integ;
    rs.color_mode = CST_COLOR_RGB;
    rs.sampler = CST_SAMPLER_INDEPENDENT; /* the checks' errors are the film's per-pixel variances:
                                           * independent samples and pixels, not zsobol's */
    CstFilm *f = NULL;
    CstRenderStats stats;
    CstError e;
    ok(cst_render(s, &rs, &f, &stats, &e), &e);
    return f;
}

static void test_light_agrees_with_path(void **state)
{
    (void)state;
    CstScene *s = lit_scene();
    CstFilm *a = render_lit(s, CST_INTEGRATOR_PATH), *b = render_lit(s, CST_INTEGRATOR_LIGHT);
    /* Block means (BLOCK x BLOCK pixels: independent pixels, variances add) within 4
     * standard errors of their difference. */
    int blocks = 0;
    for (int by = 0; by < LH; by += BLOCK)
        for (int bx = 0; bx < LW; bx += BLOCK) {
            double ma = 0.0, mb = 0.0, va = 0.0, vb = 0.0;
            for (int y = by; y < by + BLOCK; y++)
                for (int x = bx; x < bx + BLOCK; x++) {
                    double m[3], v[3];
                    cst_film_pixel(a, x, y, m);
                    cst_film_pixel_variance(a, x, y, v);
                    ma += m[1];
                    va += v[1];
                    cst_film_pixel(b, x, y, m);
                    cst_film_pixel_variance(b, x, y, v);
                    mb += m[1];
                    vb += v[1];
                }
            const double n = BLOCK * BLOCK;
            ma /= n, mb /= n, va /= n * n, vb /= n * n;
            double se = sqrt(va + vb);
            if (fabs(ma - mb) > 4.0 * se + 1e-6)
                fail_msg("block (%d, %d): path %.5f, light %.5f (4 sigma = %.5f)", bx, by, ma, mb, 4.0 * se);
            blocks++;
        }
    assert_int_equal(blocks, (LW / BLOCK) * (LH / BLOCK));
    cst_film_destroy(a);
    cst_film_destroy(b);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ JSON */

static const char *JSON_HEAD =
    "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
    " \"materials\": {\"m\": {\"type\": \"diffuse\"}},\n"
    " \"shapes\": [{\"type\": \"mesh\", \"material\": \"m\",\n"
    "   \"vertices\": [[-1, -1, 0], [1, -1, 0], [1, 1, 0]], \"indices\": [[0, 1, 2]],\n";

static CstStatus load(const char *tail, CstScene **s, CstError *e)
{
    char text[1024];
    snprintf(text, sizeof text, "%s%s", JSON_HEAD, tail);
    CstStatus st = cst_scene_load_json_string(text, strlen(text), "motion.json", s, e);
    return st;
}

static void test_json_motion(void **state)
{
    (void)state;
    CstError e;
    CstScene *s = NULL;
    ok(load("   \"motion\": {\"transform_end\": {\"translate\": [1, 0, 0]}}}]}", &s, &e), &e);
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.instances, 1);
    cst_scene_destroy(s);
    s = NULL;
    /* Bad input: a located error naming what was expected. */
    assert_int_not_equal(load("   \"motion\": {\"transform\": {}}}]}", &s, &e), CST_OK);
    assert_non_null(strstr(e.msg, "motion.json:5:"));
    assert_non_null(strstr(e.msg, "transform_end"));
    assert_int_not_equal(load("   \"emission\": {\"radiance\": [1, 1, 1]}, \"motion\": {\"transform_end\": {}}}]}", &s, &e),
                         CST_OK);
    assert_non_null(strstr(e.msg, "emission"));
    assert_int_not_equal(load("   \"motion\": {\"transform_end\": {\"scale\": [1, 0, 1]}}}]}", &s, &e), CST_OK);
    assert_non_null(strstr(e.msg, "motion.json:5:"));
    assert_null(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_motion_interpolation),
        cmocka_unit_test(test_motion_bounds),
        cmocka_unit_test(test_moving_instance_hits),
        cmocka_unit_test(test_moving_square_coverage),
        cmocka_unit_test(test_backends_agree),
        cmocka_unit_test(test_light_agrees_with_path),
        cmocka_unit_test(test_json_motion),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
