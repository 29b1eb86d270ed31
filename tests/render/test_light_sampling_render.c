/* NEE's sampling changes noise, never the image: a floor under a large, close triangle light
 * rendered with solid-angle and with area sampling of the light, and a room lit through a
 * window by an environment map with and without a portal on the window, agree block by
 * block within Z_LIMIT standard errors (path tracer, with MIS and NEE only); each prints the
 * standard-error ratio at equal spp (the noise gain). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "lights/envmap.h"
#include "render/blocks.h"
#include "render/render_util.h"
#include "scene/scene.h"

/* ------------------------------------------------------------------ solid angle vs area */

/* A floor under a one-sided triangle light 0.5 above it, 4 x 4 wide: from the floor below
 * it subtends up to ~5 sr, where area sampling's 1 / r^2 is at its worst. */
static Scene *close_triangle(void)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.6f, 0.6f, 0.6f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    Vec3 floor[4] = {{-5, 0, -5}, {-5, 0, 5}, {5, 0, 5}, {5, 0, -5}};
    assert_int_equal(scene_add_quad(s, floor, white, NULL, &err), CST_OK);
    /* (v1 - v0) x (v2 - v0) = (0, -16, 0): facing the floor */
    SceneMesh mesh;
    memset(&mesh, 0, sizeof mesh);
    Vec3 v[3] = {{-2.0f, 0.5f, -2.0f}, {2.0f, 0.5f, -2.0f}, {0.0f, 0.5f, 2.0f}};
    int idx[3] = {0, 1, 2};
    Emission e = {{{4.0f, 3.0f, 2.0f}}, 0, 0};
    mesh.positions = v;
    mesh.num_vertices = 3;
    mesh.indices = idx;
    mesh.num_triangles = 1;
    mesh.material = black;
    mesh.emission = &e;
    assert_int_equal(scene_add_mesh_ex(s, &mesh, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 4, -8}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static void run_solid_angle(CstIntegrator integ)
{
    Scene *s = close_triangle();
    CstError err;
    RegionStat a[R], b[R];
    assert_int_equal(cst_scene_set_light_sampling(s, "solid_angle", &err), CST_OK);
    render_blocks(s, integ, 256, 301u, a);
    assert_int_equal(cst_scene_set_light_sampling(s, "area", &err), CST_OK);
    render_blocks(s, integ, 256, 302u, b);
    char what[64];
    snprintf(what, sizeof what, "%s solid angle vs area", cst_integrator_name(integ));
    double ratio = compare_blocks(what, a, b);
    /* the point of it: less noise than area sampling at equal spp */
    assert_true(ratio > 1.0);
    scene_destroy(s);
}

static void test_solid_angle_path(void **state) { (void)state; run_solid_angle(CST_INTEGRATOR_PATH); }
static void test_solid_angle_path_nee(void **state) { (void)state; run_solid_angle(CST_INTEGRATOR_PATH_NEE); }

/* ------------------------------------------------------------------ portal */

/* A 6 x 3 x 6 room, closed but for a 2 x 1 window in the wall z = 3, under a sky map (64 x
 * 32: a gradient and a sun 14 degrees across, in the window's view); with_portal puts the
 * portal on the window, az = +z pointing out. */
static Scene *window_room(bool with_portal)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.6f, 0.6f, 0.6f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    const Vec3 q[][4] = {
        {{-3, 0, -3}, {-3, 0, 3}, {3, 0, 3}, {3, 0, -3}},   /* floor */
        {{-3, 3, -3}, {3, 3, -3}, {3, 3, 3}, {-3, 3, 3}},   /* ceiling */
        {{-3, 0, -3}, {3, 0, -3}, {3, 3, -3}, {-3, 3, -3}}, /* back wall */
        {{-3, 0, -3}, {-3, 3, -3}, {-3, 3, 3}, {-3, 0, 3}}, /* left */
        {{3, 0, -3}, {3, 0, 3}, {3, 3, 3}, {3, 3, -3}},     /* right */
        /* the window wall z = 3 around the hole [-1, 1] x [1, 2] */
        {{-3, 0, 3}, {-3, 3, 3}, {-1, 3, 3}, {-1, 0, 3}},
        {{1, 0, 3}, {1, 3, 3}, {3, 3, 3}, {3, 0, 3}},
        {{-1, 0, 3}, {-1, 1, 3}, {1, 1, 3}, {1, 0, 3}},
        {{-1, 2, 3}, {-1, 3, 3}, {1, 3, 3}, {1, 2, 3}},
    };
    for (size_t i = 0; i < sizeof q / sizeof q[0]; i++) assert_int_equal(scene_add_quad(s, q[i], white, NULL, &err), CST_OK);
    const int ew = 64, eh = 32;
    float *rgb = malloc(3u * (size_t)ew * (size_t)eh * sizeof *rgb);
    assert_non_null(rgb);
    Vec3 sun = v3_normalize(v3(0.3f, 0.35f, 1.0f));
    for (int y = 0; y < eh; y++)
        for (int x = 0; x < ew; x++) {
            float th = CST_PI * ((float)y + 0.5f) / (float)eh, ph = 2.0f * CST_PI * ((float)x + 0.5f) / (float)ew;
            Vec3 w = v3(sinf(th) * cosf(ph), cosf(th), sinf(th) * sinf(ph));
            float sky = 0.4f + 0.8f * fmaxf(w.y, 0.0f), b = v3_dot(w, sun) > 0.97f ? 30.0f : 0.0f;
            float *p = &rgb[3 * ((size_t)y * (size_t)ew + (size_t)x)];
            p[0] = 0.5f * sky + b;
            p[1] = 0.7f * sky + b;
            p[2] = sky + 0.8f * b;
        }
    EnvMap env;
    assert_int_equal(envmap_init_image(&env, rgb, ew, eh, color_s(1.0f), &err), CST_OK);
    assert_int_equal(scene_set_environment(s, &env, &err), CST_OK);
    if (with_portal) {
        /* p0, p1 = p0 + y, p2, p3 = p0 + x: ax = +x, ay = +y, az = +z (out of the room) */
        const float c[12] = {-1, 1, 3, -1, 2, 3, 1, 2, 3, 1, 1, 3};
        assert_int_equal(cst_scene_set_environment_portal(s, c, &err), CST_OK);
    }
    CameraDesc cam = {{0, 1.6f, -2.8f}, {0, 1.0f, 0}, {0, 1, 0}, 70.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    assert_true(!with_portal || s->env->portal != NULL);
    return s;
}

static void run_portal(CstIntegrator integ)
{
    Scene *p = window_room(true), *n = window_room(false);
    RegionStat a[R], b[R];
    render_blocks(p, integ, 512, 401u, a);
    render_blocks(n, integ, 512, 402u, b);
    char what[64];
    snprintf(what, sizeof what, "%s portal vs none", cst_integrator_name(integ));
    double ratio = compare_blocks(what, a, b);
    assert_true(ratio > 1.0);
    scene_destroy(p);
    scene_destroy(n);
}

static void test_portal_path(void **state) { (void)state; run_portal(CST_INTEGRATOR_PATH); }
static void test_portal_path_nee(void **state) { (void)state; run_portal(CST_INTEGRATOR_PATH_NEE); }

/* Bad portals are located errors, not a crash: three points in a line, a parallelogram. */
static void test_portal_rejects_non_rectangles(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    const float line[12] = {0, 0, 0, 0, 1, 0, 0, 2, 0, 0, 3, 0};
    const float skew[12] = {0, 0, 0, 0, 1, 0, 1, 1.5f, 0, 1, 0.5f, 0};
    assert_int_equal(cst_scene_set_environment_portal(s, line, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_set_environment_portal(s, skew, &err), CST_ERR_INVALID_ARG);
    assert_false(s->has_env_portal);
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solid_angle_path),
        cmocka_unit_test(test_solid_angle_path_nee),
        cmocka_unit_test(test_portal_path),
        cmocka_unit_test(test_portal_path_nee),
        cmocka_unit_test(test_portal_rejects_non_rectangles),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
