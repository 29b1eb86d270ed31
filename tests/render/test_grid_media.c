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

#include "render/media_scenes.h"

static CstColorMode g_color_mode = CST_COLOR_RGB;

/* pbrt-v4's whole-image means of tests/render/media/cornell-grid.pbrt (see
 * test_pbrt_grid_cornell). */
#define PBRT_GRID_R 0.201369
#define PBRT_GRID_G 0.128219
#define PBRT_GRID_B 0.0362208

/* A grid medium over the box [-h, h]^3 with n^3 densities from f (or random in [0, 3)
 * when f is NULL, seeded). */
static int add_grid(Scene *s, float h, int n, float (*f)(Vec3), uint64_t seed, Color sigma_a, Color sigma_s,
                    Color le, float g)
{
    CstError err;
    Medium m = media_grid_desc(v3s(-h), v3s(h), n, sigma_a, sigma_s, le, g);
    HeteroMedium *hm = &m.u.het;
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
    return media_furnace(s, med, 10.0f, in_medium ? 0.0f : 1.5f, 4.0f, L);
}

static void run_furnace(Scene *s, Color L, int spp, uint64_t seed, int variants, const char *what)
{
    media_path_furnace(s, L, spp, seed, variants, g_color_mode, what);
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

/* The fog box of media_scenes.h (diffuse walls, a quad light, a diffuse sphere), with a
 * ball of a medium of its own. */
static Scene *grid_fog_box(bool grid)
{
    Scene *s = scene_create();
    int wall, lightm;
    open_box_add(s, &wall, &lightm);
    const Color sa = color_s(0.4f), ss = color_rgb(3.0f, 2.0f, 1.0f), le = color_rgb(0.3f, 0.2f, 0.1f);
    /* Density 0.5 on 4^3 samples over [-2, 2]^3: constant within 1.5 of the centre (the ball
     * reaches 0.9), at half the homogeneous medium's coefficients x 2. */
    const int med = grid ? add_grid(s, 2.0f, 4, half_density, 0, color_scale(sa, 2.0f), color_scale(ss, 2.0f), le, 0.5f)
                         : media_add_homogeneous(s, sa, ss, le, 0.5f);
    fog_box_add_ball(s, med, wall, lightm);
    fog_box_commit(s);
    return s;
}

/* A constant-density grid renders what the homogeneous medium does (path with MIS and
 * path-nee; block means within 4 standard errors). */
static void test_constant_grid_is_homogeneous(void **state)
{
    (void)state;
    Scene *h = grid_fog_box(false), *g = grid_fog_box(true);
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
