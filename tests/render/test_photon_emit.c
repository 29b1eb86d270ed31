/* The photon integrator in emitting participating media (issue 27): photons that start in
 * the media, the emission the camera walk and the final gather pass (photon.c,
 * photon_li_media). A furnace with every estimator in play, the head-on closed form of an
 * emitting absorber, and photon against the path tracer on the emitting fog box. Standard
 * errors of photon images come from independent renders. `--spectral` runs it all in
 * spectral mode. */
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

/* The emitting furnace: a black two-sided sphere of radius 4 emitting L, filled with an
 * absorbing and scattering medium that emits L (sigma_a L per unit length), the camera in
 * it, and inside a grey diffuse sphere (albedo RHO) that emits (1 - RHO) L. Radiance is L
 * everywhere (every emitter emits what it absorbs), and every estimator of photon
 * contributes: the camera walk's medium emission, NEE to both emitting spheres, the volume
 * map (photons from the spheres and from the medium, the latter from their first vertex),
 * and at the grey sphere the final gather with the medium emission on its way and the
 * global map's estimate at its end. */
#define RHO 0.5f
static Scene *emitting_furnace(Color L)
{
    Scene *s = scene_create();
    CstError err;
    const int med = media_add_homogeneous(s, color_s(0.1f), color_s(0.15f), L, 0.3f);
    int black, grey, mirror;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    m.albedo = color_s(RHO);
    assert_int_equal(scene_add_material(s, &m, &grey, &err), CST_OK);
    m = (Material){.type = MATERIAL_MIRROR, .albedo = {{1.0f, 1.0f, 1.0f, 1.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mirror, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, med, -1, 0, &err), CST_OK);
    assert_int_equal(scene_set_camera_medium(s, med, &err), CST_OK);
    Emission wall = {L, 1, 0}, inner = {color_scale(L, 1.0f - RHO), 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 4.0f, black, &wall, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, med, med, 0, &err), CST_OK); /* opaque, in the medium */
    assert_int_equal(scene_add_sphere(s, v3(0.3f, 0.0f, 0.0f), 1.2f, grey, &inner, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-1.5f, 0.8f, 0.5f), 0.7f, mirror, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0.5f, 3.5f}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, 3.5f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* Every 8 x 8 block and the whole image of 16 x 16 renders within 4 standard errors of L. */
enum { FURNACE_PHOTONS = 32000, FURNACE_RENDERS = 24 };
#define FURNACE_R 0.4
static void test_furnace(void **state)
{
    (void)state;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = emitting_furnace(L);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.spp = 2;
    st.photon_radius = FURNACE_R;
    st.photons = FURNACE_PHOTONS;
    st.color_mode = g_color_mode;
    media_furnace_check(s, st, CST_INTEGRATOR_PHOTON, FURNACE_RENDERS, 400, L, 0.0, "emitting furnace");
    scene_destroy(s);
}

/* An absorbing-only emitting slab (sigma_a SLAB_SA, thickness SLAB_D, radiance Le) seen
 * head-on by an orthographic camera from vacuum, nothing behind it: L = Le (1 - exp(-sigma_a
 * d)) at every pixel, all of it the camera walk's collision estimate of the emission (no
 * photon scatters: sigma_s = 0). The slab is a box of boundary triangles, normals outward.
 * 32 renders: in spectral mode each render's pixels share its 64 wavelengths, and 8 renders
 * estimated the spread too poorly for a 4-sigma normal test (a block at z = -4.2, the whole
 * image 0.1 standard errors off at 64 renders). */
#define SLAB_SA 0.7f
#define SLAB_D 1.5f
static void test_slab(void **state)
{
    (void)state;
    const Color le = color_rgb(0.8f, 0.4f, 0.2f);
    Scene *s = scene_create();
    CstError err;
    const int med = media_add_homogeneous(s, color_s(SLAB_SA), color_s(0.0f), le, 0.0f);
    int black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
    const float h = 2.0f; /* 4 x 4 x SLAB_D, its near face at z = 0 */
    const Vec3 p[8] = {{-h, -h, -SLAB_D}, {h, -h, -SLAB_D}, {h, h, -SLAB_D}, {-h, h, -SLAB_D},
                       {-h, -h, 0.0f},    {h, -h, 0.0f},    {h, h, 0.0f},    {-h, h, 0.0f}};
    const int idx[36] = {0, 2, 1, 0, 3, 2, 4, 5, 6, 4, 6, 7, 0, 1, 5, 0, 5, 4,
                         3, 7, 6, 3, 6, 2, 0, 4, 7, 0, 7, 3, 1, 2, 6, 1, 6, 5};
    assert_int_equal(scene_add_mesh(s, p, 8, idx, 12, black, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0, 3.0f}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 3.0f, 1.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.spp = 8;
    st.photon_radius = 0.1;
    st.photons = 1000;
    st.color_mode = g_color_mode;
    const Color L = color_scale(le, 1.0f - expf(-SLAB_SA * SLAB_D));
    media_furnace_check(s, st, CST_INTEGRATOR_PHOTON, 32, 500, L, 0.0, "emitting slab");
    scene_destroy(s);
}

/* The caustic map keeps out the photons that started in a medium: a diffuse floor lit
 * by an emitting ball of fog (the only light), directly and through a mirror wall. The
 * mirrored light (z0 S D) reaches a floor point x by the final gather from x (the emission
 * it passes after the mirror), so such photons in the caustic map would count it twice.
 * photon against path, the whole image and four blocks within 4 standard errors. */
enum { MIRROR_PHOTONS = 16000, MIRROR_RENDERS = 48, MIRROR_PATH_SPP = 512 };
static void test_mirror(void **state)
{
    (void)state;
    Scene *s = scene_create();
    CstError err;
    const int med = media_add_homogeneous(s, color_s(0.6f), color_s(0.4f), color_rgb(3.0f, 2.0f, 1.0f), 0.0f);
    int floor, mirror, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.7f, 0.7f, 0.7f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &floor, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    m = (Material){.type = MATERIAL_MIRROR, .albedo = {{1.0f, 1.0f, 1.0f, 1.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mirror, &err), CST_OK);
    const Vec3 fl[4] = {{-1.2f, -1, 2}, {2, -1, 2}, {2, -1, -2}, {-1.2f, -1, -2}};
    const Vec3 mi[4] = {{-1.2f, -1, -2}, {-1.2f, 1.5f, -2}, {-1.2f, 1.5f, 2}, {-1.2f, -1, 2}};
    assert_int_equal(scene_add_quad(s, fl, floor, NULL, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, mi, mirror, NULL, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, med, -1, 1, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-0.4f, -0.3f, 0.0f), 0.4f, black, NULL, &err), CST_OK);
    CameraDesc cam = {{1.8f, 1.2f, 3.2f}, {-0.4f, -0.8f, 0.0f}, {0, 1, 0}, 45.0f, 0.0f, 3.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = 32;
    st.color_mode = g_color_mode;
    st.max_depth = 0;
    Regions path = regions(32, 16), photon = regions(32, 16);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, MIRROR_PATH_SPP, 1700, &path);
    st.spp = 2;
    st.photons = MIRROR_PHOTONS;
    st.photon_radius = 0.05;
    split_regions(s, &st, CST_INTEGRATOR_PHOTON, MIRROR_RENDERS, 1800, &photon);
    compare(&path, &photon, "path", "photon (mirrored fog)");
    scene_destroy(s);
}

/* The emitting fog box (media_scenes.h): photon against path, the whole image and its four
 * 16 x 16 blocks within 4 standard errors. */
enum { FOG_PHOTONS = 16000, FOG_RENDERS = 32, FOG_PATH_SPP = 512 };
#define FOG_R 0.05
static void test_fog_agreement(void **state)
{
    (void)state;
    Scene *s = fog_box(FOG_HOMOGENEOUS_EMISSIVE);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = st.height = 32;
    st.color_mode = g_color_mode;
    st.max_depth = 0; /* photon's max_depth counts the photon path's bounces alone */
    Regions path = regions(32, 16), photon = regions(32, 16);
    camera_regions(s, &st, CST_INTEGRATOR_PATH, FOG_PATH_SPP, 1500, &path);
    st.spp = 2;
    st.photons = FOG_PHOTONS;
    st.photon_radius = FOG_R;
    split_regions(s, &st, CST_INTEGRATOR_PHOTON, FOG_RENDERS, 1600, &photon);
    compare(&path, &photon, "path", "photon (emitting fog)");
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
        cmocka_unit_test(test_slab),
        cmocka_unit_test(test_mirror),
        cmocka_unit_test(test_fog_agreement),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
