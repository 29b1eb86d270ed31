/* The photon integrator in participating media (photon.c's volume photon map, Jensen &
 * Christensen 1998): a furnace (a scattering-only medium, homogeneous or a random grid, in
 * a uniform emitter renders the emitter's radiance), photon against the path tracer on
 * the fog box (media_scenes.h) at two radii (within 4 standard errors at both: the large
 * one's bias was resolved before the ball's boundary correction, issue 27), the edge of a
 * scattering ball in a furnace (that correction) and its ball fraction against the exact
 * lens volume, and the same image for 1 and 2 threads (emitting media: test_photon_emit.c).
 * Standard errors of photon images come from independent renders (one render's pixels
 * share its maps). `--spectral` runs it all in
 * spectral mode. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "integrators/volume_ball.h"
#include "sampling/warp.h"
#include "render/media_scenes.h"

static CstColorMode g_color_mode = CST_COLOR_RGB;

/* test_sppm_media.c's furnace: a black two-sided emitting sphere (radius 4, radiance L)
 * filled with a scattering-only medium, the camera inside: L everywhere. */
static Scene *furnace(bool grid, Color L)
{
    Scene *s = scene_create();
    const Color ss = color_rgb(0.2f, 0.3f, 0.1f);
    const int med = grid ? media_add_random_grid(s, v3s(-4.0f), v3s(4.0f), 0.8f, color_s(0.0f), ss, color_s(0.0f), 0.3f)
                         : media_add_homogeneous(s, color_s(0.0f), ss, color_s(0.0f), 0.6f);
    return media_furnace(s, med, 4.0f, 0.0f, 3.5f, L);
}

/* The furnace: every 8 x 8 block and the whole image within 4 standard errors of L. The
 * radiance field is constant, so the ball's only bias is where it reaches outside the
 * medium (no photons there), rare in this thin medium at FURNACE_R. The balls hold about
 * one volume photon each (a spectral set, 1/16 of them): the per-render means are skewed,
 * so 32 renders estimate their spread. Measured whole image (RGB, blue; L = 0.25):
 * homogeneous 0.2427 +- 0.0026 at these seeds, 0.2478 +- 0.0026 and 0.2515 +- 0.0044 at
 * two other seed ranges (r = 0.15, 16000 photons, 64 renders); grid 0.2491 +- 0.0013. */
#define FURNACE_R 0.25
enum { FURNACE_PHOTONS = 16000, FURNACE_RENDERS = 32 };
static void check_furnace(Scene *s, Color L, uint64_t seed, const char *what)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.spp = 4;
    st.photon_radius = FURNACE_R;
    st.photons = FURNACE_PHOTONS;
    st.color_mode = g_color_mode;
    media_furnace_check(s, st, CST_INTEGRATOR_PHOTON, FURNACE_RENDERS, seed, L, 0.0, what);
}

static void test_furnace(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = furnace(false, L);
    check_furnace(s, L, 100, "scattering ball");
    scene_destroy(s);
    s = furnace(true, L);
    check_furnace(s, L, 200, "grid ball");
    scene_destroy(s);
}

/* volume_ball_fraction() against the exact volume of the lens B(p, r) ∩ S(0, R) (two balls
 * whose centres are c apart, R - r < c < R + r): V = pi (R + r - c)^2 (c^2 + 2 c r - 3 r^2
 * + 2 c R + 6 r R - 3 R^2) / (12 c). The mean of the rotated quadrature over 512 points at
 * each distance c from the centre (random directions, so random rotations) must agree
 * within 4 standard errors (its spread estimated from the same points): it is unbiased. */
static void test_ball_fraction(void **state)
{
    (void)state;
    Scene *s = scene_create();
    CstError err;
    int black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.0f, black, NULL, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    const double R = 1.0, r = 0.25;
    const double cs[] = {0.5, 0.8, 0.9, 0.97, 0.999};
    Pcg32 rng;
    pcg32_seed(&rng, 27, 1);
    for (size_t k = 0; k < sizeof cs / sizeof cs[0]; k++) {
        const double c = cs[k];
        double exact = 1.0;
        if (c > R - r) {
            const double lens = (c * c + 2 * c * r - 3 * r * r + 2 * c * R + 6 * r * R - 3 * R * R);
            const double v = (double)CST_PI * (R + r - c) * (R + r - c) * lens / (12.0 * c);
            exact = v / (4.0 / 3.0 * (double)CST_PI * r * r * r);
        }
        const int n = 512;
        double sum = 0.0, sum2 = 0.0;
        uint64_t rays = 0;
        for (int i = 0; i < n; i++) {
            const Vec3 d = warp_uniform_sphere(pcg32_v2(&rng));
            const double f = (double)volume_ball_fraction(s, v3_scale(d, (float)c), (float)r, 0.0f, &rays);
            sum += f;
            sum2 += f * f;
        }
        const double mean = sum / n, se = sqrt(fmax(sum2 / n - mean * mean, 0.0) / (n - 1));
        const double z = se > 0.0 ? (mean - exact) / se : (fabs(mean - exact) < 1e-6 ? 0.0 : (double)INFINITY);
        print_message("ball fraction at c = %.3f: %.5f +- %.5f, exact %.5f (z = %.2f)\n", c, mean, se, exact, z);
        assert_int_equal(rays, (uint64_t)n * VOLUME_BALL_DIRS);
        if (!(fabs(z) <= Z_LIMIT)) fail_msg("ball fraction at c = %.3f: %.5f, exact %.5f (z = %.2f)", c, mean, exact, z);
    }
    scene_destroy(s);
}

/* Issue 27, the ball estimate at a medium's boundary (media_edge_furnace_check): a scattering-only
 * ball (radius 1, an interface sphere, optical radius 2) in vacuum inside the furnace's emitting
 * sphere, the camera outside the ball: still L everywhere. The camera's medium vertices lie
 * mostly within EDGE_R of the ball's surface, where the ball of the volume estimate reaches
 * into the vacuum, which holds no photons: without volume_ball.c's correction (dividing by
 * the part of the ball inside the medium) the image is resolved low, every block that
 * shows the ball (measured in the commit that added this test, red, whole image). */
#define EDGE_R 0.25
enum { EDGE_PHOTONS = 16000, EDGE_RENDERS = 16 };
static void test_edge_furnace(void **state)
{
    (void)state;
    media_edge_furnace_check(CST_INTEGRATOR_PHOTON, 4, EDGE_R, EDGE_PHOTONS, EDGE_RENDERS, g_color_mode);
}

/* Two touching media (issue 27): a thin scattering medium A (sigma_s 0.3) fills the
 * furnace's emitter, and a ball of a dense one B (sigma_s 3, radius 1.5, an interface
 * sphere) sits in it, the camera in A: L everywhere. A ball of the volume estimate near the
 * sphere reaches into the other medium, whose photons have another density per volume and
 * carry another sigma_s: the estimate gathers only the photons of x's medium (Photon.inst of
 * a volume photon), whose part of the ball volume_ball.c measures. */
enum { TWO_PHOTONS = 32000, TWO_RENDERS = 24 };
#define TWO_R 0.25
static void test_two_media(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = scene_create();
    CstError err;
    const int a = media_add_homogeneous(s, color_s(0.0f), color_s(0.3f), color_s(0.0f), 0.3f);
    const int b = media_add_homogeneous(s, color_s(0.0f), color_s(3.0f), color_s(0.0f), 0.3f);
    int black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    Emission em = {L, 1, 0};
    assert_int_equal(scene_set_medium_interface(s, a, -1, 0, &err), CST_OK);
    assert_int_equal(scene_set_camera_medium(s, a, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 4.0f, black, &em, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, b, a, 1, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.5f, black, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0.5f, 3.5f}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, 3.5f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.spp = 2;
    st.photon_radius = TWO_R;
    st.photons = TWO_PHOTONS;
    st.color_mode = g_color_mode;
    media_furnace_check(s, st, CST_INTEGRATOR_PHOTON, TWO_RENDERS, 800, L, 0.0, "two touching media");
    scene_destroy(s);
}

/* The fog box's settings. FOG_R_SMALL (2.5% of the box's width) holds a few volume photons
 * per ball at FOG_PHOTONS; at FOG_R_LARGE the balls reach far outside the fog (through the
 * box's walls) and the surfaces' discs across their edges. Measured (RGB, red, whole image):
 * path 0.24937 +- 0.00102; photon r = 0.30 0.23746 +- 0.00189 (z = -5.6) before the ball's
 * boundary correction (issue 27, volume_ball.c), 0.24658 +- 0.00198 (z = -1.25) with it;
 * r = 0.25 0.23992 +- 0.00189 (z = -4.4) before; r = 0.05 0.24704 +- 0.00216 (z = -1.0)
 * before, 0.24869 +- 0.00218 (z = -0.3) with it. */
enum { FOG_PHOTONS = 20000, FOG_SPP = 2 };
#define FOG_R_SMALL 0.05
#define FOG_R_LARGE 0.3

/* path (the reference: independent pixels) and photon at FOG_R_SMALL: the whole image and
 * its four 16 x 16 blocks within 4 standard errors. With `large`, photon at FOG_R_LARGE
 * too, whose whole image (red) must agree as well: most of the bias at that radius was the
 * balls' reaching through the walls, which volume_ball.c corrects (without it, z = -5.6). */
static void fog_agreement(FogKind kind, bool large, int path_spp, int renders, uint64_t seed, const char *what)
{
    Scene *s = fog_box(kind);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = 32;
    st.color_mode = g_color_mode;
    /* Unbounded depth: photon's max_depth counts the photon path's bounces alone (the camera
     * side adds up to two vertices), so a finite one is not path's. */
    st.max_depth = 0;
    Regions path = regions(32, 16), small = regions(32, 16), big = regions(32, 16);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, path_spp, seed, &path);
    st.spp = FOG_SPP;
    st.photons = FOG_PHOTONS;
    st.photon_radius = FOG_R_SMALL;
    split_regions(s, &st, CST_INTEGRATOR_PHOTON, renders, seed + 1000, &small);
    char name[64];
    snprintf(name, sizeof name, "photon r = %.2f (%s)", FOG_R_SMALL, what);
    compare(&path, &small, "path", name);
    if (large) {
        st.photon_radius = FOG_R_LARGE;
        split_regions(s, &st, CST_INTEGRATOR_PHOTON, renders, seed + 10, &big);
        const RegionStat *p = &path.stat[0], *a = &small.stat[0], *b = &big.stat[0];
        const double zb = z_score(b->mean[0], b->se[0], p->mean[0], p->se[0]);
        const double zs = z_score(a->mean[0], a->se[0], p->mean[0], p->se[0]);
        print_message("%s, red: path %.5f +- %.5f; photon r = %.2f %.5f +- %.5f (z = %.2f), r = %.2f %.5f +- %.5f "
                      "(z = %.2f)\n", what, p->mean[0], p->se[0], FOG_R_LARGE, b->mean[0], b->se[0], zb, FOG_R_SMALL,
                      a->mean[0], a->se[0], zs);
        if (!(fabs(zb) <= Z_LIMIT))
            fail_msg("%s: photon at r = %.2f disagrees with path (red, z = %.2f): the balls' boundary bias", what,
                     FOG_R_LARGE, zb);
    }
    scene_destroy(s);
}

static void test_fog_agreement(void **state)
{
    (void)state;
    fog_agreement(FOG_HOMOGENEOUS, true, 256, 24, 700, "homogeneous");
}

static void test_grid_agreement(void **state)
{
    (void)state;
    fog_agreement(FOG_GRID, false, 128, 16, 900, "grid");
}

/* The same image bit for bit for 1 and 2 threads (the maps are built single-threaded,
 * each camera sample from its own stream). */
static void test_threads(void **state)
{
    (void)state;
    Scene *s = fog_box(FOG_GRID);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = 16;
    st.spp = 2;
    st.integrator = CST_INTEGRATOR_PHOTON;
    st.photon_radius = FOG_R_SMALL;
    st.photons = 2000;
    st.color_mode = g_color_mode;
    st.seed = 5;
    st.seed_set = 1;
    assert_threads_bit_identical(s, st);
    scene_destroy(s);
}

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        if (strcmp(argv[i], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
        if (strcmp(argv[i], "--only") == 0 && i + 1 < argc) cmocka_set_test_filter(argv[i + 1]);
    }
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_furnace),
        cmocka_unit_test(test_ball_fraction),
        cmocka_unit_test(test_edge_furnace),
        cmocka_unit_test(test_two_media),
        cmocka_unit_test(test_fog_agreement),
        cmocka_unit_test(test_grid_agreement),
        cmocka_unit_test(test_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
