/* Heterogeneous media in the path tracer (integrators/volpath.c, media/hetero_medium.c):
 * furnaces whose radiance is known exactly for any density field (a scattering-only grid,
 * an absorbing grid that emits what it absorbs, the camera inside a grid medium, the
 * procedural cloud), and a grid of constant density rendering the same image as the
 * homogeneous medium (block means within 4 standard errors). `test_grid_media --spectral`
 * runs the same in spectral mode. Fixed seeds. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

static CstColorMode g_color_mode = CST_COLOR_RGB;

/* pbrt-v4's whole-image means of tests/render/media/cornell-grid.pbrt (see
 * test_pbrt_grid_cornell). */
#define PBRT_GRID_R 0.201369
#define PBRT_GRID_G 0.128219
#define PBRT_GRID_B 0.0362208

static const CstIntegrator VARIANTS[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_BSDF, CST_INTEGRATOR_PATH_NEE};

/* Every block's mean within Z_LIMIT standard errors of expect[c]. */
static void check_value(const CstFilm *f, const double expect[3], const char *what)
{
    Regions r = regions(cst_film_width(f), cst_film_width(f) / 4);
    film_regions(f, &r);
    for (int i = 0; i < r.count; i++)
        for (int c = 0; c < 3; c++) {
            double dev = fabs(r.stat[i].mean[c] - expect[c]);
            if (!(dev <= Z_LIMIT * r.stat[i].se[c] + 1e-5 * expect[c]))
                fail_msg("%s: block %d channel %d: %.6f, expected %.6f (z = %.2f)", what, i - 1, c,
                         r.stat[i].mean[c], expect[c], (r.stat[i].mean[c] - expect[c]) / r.stat[i].se[c]);
        }
    print_message("%s: whole image %.5f %.5f %.5f (se %.1e), expected %.5f %.5f %.5f\n", what, r.stat[0].mean[0],
                  r.stat[0].mean[1], r.stat[0].mean[2], r.stat[0].se[0], expect[0], expect[1], expect[2]);
}

/* A grid medium over the box [-h, h]^3 with n^3 densities from f (or random in [0, 3)
 * when f is NULL, seeded). */
static int add_grid(Scene *s, float h, int n, float (*f)(Vec3), uint64_t seed, Color sigma_a, Color sigma_s,
                    Color le, float g)
{
    CstError err;
    Medium m = {.type = MEDIUM_GRID, .g = g};
    HeteroMedium *hm = &m.u.het;
    hm->sigma_a = sigma_a;
    hm->sigma_s = sigma_s;
    hm->le = le;
    hm->le_scale_1 = 1.0f;
    hm->medium_from_world = transform_identity();
    hm->p0 = v3s(-h);
    hm->p1 = v3s(h);
    hm->n[0] = hm->n[1] = hm->n[2] = n;
    hm->density = malloc((size_t)n * (size_t)n * (size_t)n * sizeof(float));
    Pcg32 r;
    pcg32_seed_sample(&r, seed, 0, 0);
    for (int z = 0; z < n; z++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                Vec3 p = v3(h * (-1.0f + 2.0f * ((float)x + 0.5f) / (float)n),
                            h * (-1.0f + 2.0f * ((float)y + 0.5f) / (float)n),
                            h * (-1.0f + 2.0f * ((float)z + 0.5f) / (float)n));
                hm->density[(z * n + y) * n + x] = f ? f(p) : 3.0f * pcg32_float(&r);
            }
    int id;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_OK);
    free(hm->density);
    return id;
}

static int add_cloud(Scene *s, Color sigma_a, Color sigma_s, float g)
{
    CstError err;
    Medium m = {.type = MEDIUM_CLOUD, .g = g};
    HeteroMedium *hm = &m.u.het;
    hm->cloud = true;
    hm->sigma_a = sigma_a;
    hm->sigma_s = sigma_s;
    hm->medium_from_world = transform_translate(v3s(1.0f)); /* the box [-1, 1]^3 from [0, 2]^3 */
    hm->p1 = v3s(2.0f);
    hm->cloud_density = 2.0f;
    hm->wispiness = 1.0f;
    hm->frequency = 5.0f;
    int id;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_OK);
    return id;
}

/* A black enclosure (radius 10) emitting L, in it a boundary ball (radius 1.5) of medium
 * med, or (in_medium) med filling the enclosure with the camera in it. */
static Scene *furnace_scene(Scene *s, int med, bool in_medium, Color L)
{
    CstError err;
    int black;
    Material mat = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &mat, &black, &err), CST_OK);
    Emission em = {L, 1, 0};
    if (in_medium) {
        assert_int_equal(scene_set_medium_interface(s, med, -1, 0, &err), CST_OK);
        assert_int_equal(scene_set_camera_medium(s, med, &err), CST_OK);
    }
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 10.0f, black, &em, &err), CST_OK);
    if (!in_medium) {
        assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
        assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.5f, black, NULL, &err), CST_OK);
    }
    CameraDesc cam = {{0, 0.5f, 4}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, 4.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static void run_furnace(Scene *s, Color L, int spp, uint64_t seed, int variants, const char *what)
{
    const double expect[3] = {(double)L.c[0], (double)L.c[1], (double)L.c[2]};
    for (int i = 0; i < variants; i++) {
        char name[128];
        snprintf(name, sizeof name, "%s, %s", what, cst_integrator_name(VARIANTS[i]));
        CstRenderSettings st = {.width = 32, .height = 32, .color_mode = g_color_mode};
        CstFilm *f = render_film(s, &st, VARIANTS[i], spp, seed + (uint64_t)i);
        check_value(f, expect, name);
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

/* A random density grid, scattering only (chromatic, forward HG): radiance L. */
static void test_grid_furnace_scattering(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = scene_create();
    int med = add_grid(s, 1.5f, 6, NULL, 1, color_s(0.0f), color_rgb(1.0f, 2.0f, 0.5f), color_s(0.0f), 0.6f);
    run_furnace(furnace_scene(s, med, false, L), L, 64, 10, 3, "scattering grid");
}

/* Absorbing and scattering with Le = L: what the medium absorbs it emits again, whatever
 * the density. */
static void test_grid_furnace_emission(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = scene_create();
    int med = add_grid(s, 1.5f, 5, NULL, 2, color_rgb(0.5f, 1.0f, 0.3f), color_rgb(0.5f, 0.2f, 1.0f), L, -0.3f);
    run_furnace(furnace_scene(s, med, false, L), L, 64, 20, 3, "emitting grid");
}

/* The camera inside a grid medium that fills the enclosure (MIS and phase sampling, as
 * test_media's camera-medium furnace). */
static void test_grid_furnace_camera_medium(void **state)
{
    (void)state;
    const Color L = color_rgb(0.3f, 0.6f, 0.9f);
    Scene *s = scene_create();
    int med = add_grid(s, 10.0f, 8, NULL, 3, color_s(0.0f), color_rgb(0.2f, 0.3f, 0.1f), color_s(0.0f), 0.8f);
    run_furnace(furnace_scene(s, med, true, L), L, 64, 30, 2, "camera in grid");
}

/* pbrt-v4's procedural cloud, scattering only: radiance L. */
static void test_cloud_furnace(void **state)
{
    (void)state;
    const Color L = color_rgb(0.8f, 0.6f, 0.4f);
    Scene *s = scene_create();
    int med = add_cloud(s, color_s(0.0f), color_rgb(4.0f, 6.0f, 3.0f), 0.7f);
    run_furnace(furnace_scene(s, med, false, L), L, 32, 40, 3, "cloud");
}

static float half_density(Vec3 p) { (void)p; return 0.5f; }

/* The open box of test_media's fog test (diffuse walls, a quad light, a diffuse sphere),
 * with a ball of the given medium. */
static Scene *fog_box(bool grid)
{
    CstError err;
    Scene *s = scene_create();
    int wall, lightm;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.6f, 0.5f, 0.6f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &wall, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &lightm, &err), CST_OK);
    const Vec3 walls[5][4] = {
        {{-1, -1, -1}, {1, -1, -1}, {1, -1, 1}, {-1, -1, 1}}, {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}},
        {{-1, -1, -1}, {-1, 1, -1}, {1, 1, -1}, {1, -1, -1}}, {{-1, -1, -1}, {-1, -1, 1}, {-1, 1, 1}, {-1, 1, -1}},
        {{1, -1, -1}, {1, 1, -1}, {1, 1, 1}, {1, -1, 1}},
    };
    for (int i = 0; i < 5; i++) assert_int_equal(scene_add_quad(s, walls[i], wall, NULL, &err), CST_OK);
    const Vec3 light[4] = {{-0.3f, 0.99f, -0.3f}, {0.3f, 0.99f, -0.3f}, {0.3f, 0.99f, 0.3f}, {-0.3f, 0.99f, 0.3f}};
    Emission em = {color_rgb(8.0f, 8.0f, 6.0f), 0, 0};
    assert_int_equal(scene_add_quad(s, light, lightm, &em, &err), CST_OK);
    const Color sa = color_s(0.4f), ss = color_rgb(3.0f, 2.0f, 1.0f), le = color_rgb(0.3f, 0.2f, 0.1f);
    int med;
    if (grid) {
        /* Density 0.5 on 4^3 samples over [-2, 2]^3: constant within 1.5 of the centre
         * (the ball reaches 0.9), at half the homogeneous medium's coefficients x 2. */
        med = add_grid(s, 2.0f, 4, half_density, 0, color_scale(sa, 2.0f), color_scale(ss, 2.0f), le, 0.5f);
    } else {
        Medium mh = {.type = MEDIUM_HOMOGENEOUS, .g = 0.5f};
        mh.u.homog.sigma_a = sa;
        mh.u.homog.sigma_s = ss;
        mh.u.homog.le = le;
        assert_int_equal(scene_add_medium(s, &mh, &med, &err), CST_OK);
    }
    assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-0.2f, -0.3f, 0.0f), 0.6f, lightm, NULL, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, -1, -1, 0, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0.45f, -0.6f, 0.2f), 0.35f, wall, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0, 3.8f}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 3.8f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* A constant-density grid renders what the homogeneous medium does (path with MIS and
 * path-nee; block means within 4 standard errors). */
static void test_constant_grid_is_homogeneous(void **state)
{
    (void)state;
    Scene *h = fog_box(false), *g = fog_box(true);
    CstRenderSettings st = {.width = 32, .height = 32, .color_mode = g_color_mode};
    const CstIntegrator integ[2] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE};
    for (int i = 0; i < 2; i++) {
        Regions rh = regions(32, 8), rg = regions(32, 8);
        camera_regions(h, &st, integ[i], 256, 60 + (uint64_t)i, &rh);
        camera_regions(g, &st, integ[i], 256, 70 + (uint64_t)i, &rg);
        compare(&rh, &rg, "homogeneous", "constant grid");
    }
    scene_destroy(h);
    scene_destroy(g);
}


/* tests/render/media/cornell-grid.pbrt (a uniformgrid and a cloud in the Cornell box)
 * against pbrt-v4's volpath (spectral, maxdepth 5): its whole-image means at 64 x 64,
 * 1024 spp (tests/render/media/README.md), and caustic's at 32 x 32 (the box filter's
 * whole-image mean does not depend on the resolution). Each channel within 1% of pbrt-v4
 * plus 4 standard errors of caustic's. Spectral mode only: pbrt-v4 is spectral. */
static void test_pbrt_grid_cornell(void **state)
{
    (void)state;
    if (g_color_mode != CST_COLOR_SPECTRAL) {
        print_message("spectral mode only (run as test_grid_media --spectral)\n");
        return;
    }
    static const double PBRT_MEAN[3] = {PBRT_GRID_R, PBRT_GRID_G, PBRT_GRID_B};
    pbrt_mean_check(CST_SOURCE_DIR "/tests/render/media/cornell-grid.pbrt", PBRT_MEAN, 512, 80, "grid Cornell");
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_furnace_scattering),
        cmocka_unit_test(test_grid_furnace_emission),
        cmocka_unit_test(test_grid_furnace_camera_medium),
        cmocka_unit_test(test_cloud_furnace),
        cmocka_unit_test(test_constant_grid_is_homogeneous),
        cmocka_unit_test(test_pbrt_grid_cornell),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
