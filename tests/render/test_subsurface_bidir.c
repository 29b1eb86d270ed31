/* Subsurface materials in the light tracer, BDPT, VCM and MMLT (integrators/sss_walk.c: the
 * material's medium random-walked by subpath_media.c under its dielectric surface): they
 * agree with the path tracer on the same scene written with an explicit medium behind a
 * dielectric (volpath.c's random walk, the estimand they share; the path tracer on the
 * subsurface material itself takes pbrt-v4's BSSRDF, a diffusion approximation, and is
 * not compared), a furnace, and the integrators that still refuse such scenes.
 * Fixed seeds; the standard errors of the light tracer and BDPT from independent renders;
 * 4 standard errors. `test_subsurface_bidir --spectral` runs the same in spectral mode. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/box_scene.h"
#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

static CstColorMode g_color_mode = CST_COLOR_RGB;

/* The medium of the test's subsurface sphere. */
static const float SSS_IOR = 1.33f, SSS_G = 0.3f;
static Color sss_sigma_a(void) { return color_rgb(0.1f, 0.3f, 0.6f); }
static Color sss_sigma_s(void) { return color_rgb(4.0f, 2.5f, 1.0f); }

/* A subsurface material (explicit: a plain dielectric, its medium added to the scene and
 * made the interface of the shapes added next). roughness: the surface's, perceptual. */
static int add_sss(Scene *s, float roughness, Color sigma_a, Color sigma_s, bool explicit_medium)
{
    CstError err;
    Material m = {.type = MATERIAL_DIELECTRIC, .albedo = {{1, 1, 1, 1}}, .ior = SSS_IOR, .roughness = roughness,
                  .g = SSS_G};
    if (explicit_medium) {
        Medium med = {.type = MEDIUM_HOMOGENEOUS, .g = SSS_G};
        med.u.homog.sigma_a = sigma_a;
        med.u.homog.sigma_s = sigma_s;
        int id;
        assert_int_equal(scene_add_medium(s, &med, &id, &err), CST_OK);
        assert_int_equal(scene_set_medium_interface(s, id, -1, 0, &err), CST_OK);
    } else {
        m.subsurface = true;
        m.sss_sigma_a = sigma_a;
        m.sss_sigma_s = sigma_s;
        m.sss_mfp = color_s(1.0f);
    }
    int id;
    assert_int_equal(scene_add_material(s, &m, &id, &err), CST_OK);
    return id;
}

/* An open box of diffuse walls lit by a small quad light, a subsurface sphere and a
 * subsurface cube (triangles) on a diffuse floor (their surface rough, so that the light
 * tracer's connections see inside) and a diffuse sphere beside them. */
static Scene *sss_box(bool explicit_medium)
{
    CstError err;
    Scene *s = scene_create();
    int wall, lightm;
    open_box_add(s, &wall, &lightm);
    const int sss = add_sss(s, 0.3f, sss_sigma_a(), sss_sigma_s(), explicit_medium);
    assert_int_equal(scene_add_sphere(s, v3(-0.25f, -0.45f, 0.0f), 0.55f, sss, NULL, &err), CST_OK);
    /* A subsurface cube of triangles too (faces wound so that ng points out: the medium
     * lies behind ng), [0.4, 0.8] x [-0.99, -0.6] x [-0.6, -0.25]. */
    const float x0 = 0.4f, x1 = 0.8f, y0 = -0.99f, y1 = -0.6f, z0 = -0.6f, z1 = -0.25f;
    const Vec3 cube[6][4] = {
        {{x0, y0, z0}, {x1, y0, z0}, {x1, y0, z1}, {x0, y0, z1}}, /* -y */
        {{x0, y1, z0}, {x0, y1, z1}, {x1, y1, z1}, {x1, y1, z0}}, /* +y */
        {{x0, y0, z0}, {x0, y1, z0}, {x1, y1, z0}, {x1, y0, z0}}, /* -z */
        {{x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}}, /* +z */
        {{x0, y0, z0}, {x0, y0, z1}, {x0, y1, z1}, {x0, y1, z0}}, /* -x */
        {{x1, y0, z0}, {x1, y1, z0}, {x1, y1, z1}, {x1, y0, z1}}, /* +x */
    };
    for (int i = 0; i < 6; i++) assert_int_equal(scene_add_quad(s, cube[i], sss, NULL, &err), CST_OK);
    assert_int_equal(scene_set_medium_interface(s, -1, -1, 0, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0.55f, -0.7f, 0.3f), 0.3f, wall, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0, 3.8f}, {0, 0, 0}, {0, 1, 0}, 40.0f, 0.0f, 3.8f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* path on the explicit-medium box (the reference: independent pixels), light, bdpt and
 * vcm on the subsurface box: the whole image and its four 16 x 16 blocks within 4
 * standard errors (path with subsurface_walk on the subsurface box is this reference
 * pixel for pixel: test_sss_view_exact). The light tracer and BDPT from 96 renders: in
 * spectral mode their medium walks' noise is heavy-tailed enough that 24 renders misjudged
 * a block's standard error (light vs bdpt z = -4.3 at 24 renders, 2.8 at 96 with the same
 * first seeds: noise, a bias would have doubled). */
static void test_sss_agreement(void **state)
{
    (void)state;
    Scene *ref = sss_box(true), *s = sss_box(false);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.subsurface_walk = 1; /* light, bdpt, vcm and mmlt refuse subsurface materials without it */
    st.width = st.height = 32;
    st.color_mode = g_color_mode;
    st.max_depth = 8;
    Regions path = regions(32, 16), light = regions(32, 16), bdpt = regions(32, 16), vcm = regions(32, 16);
    camera_regions(ref, &st, CST_INTEGRATOR_PATH, 64, 100, &path);
    st.spp = 2;
    /* The light tracer's block means are heavy-tailed here (block 3 red over 1536 renders:
     * skewness 10 in spectral mode, 5.6 in RGB, before and after lt-rr's roulette change),
     * so 96 renders gave |z| > 4 against their own grand mean for 1 seed group in 16 (z =
     * -5.9 at seeds 1160-1255); 16 groups of 384 stay within |z| <= 2.9. 384, which costs
     * about 1.6 s more. */
    split_regions(s, &st, CST_INTEGRATOR_LIGHT, 384, 200, &light);
    split_regions(s, &st, CST_INTEGRATOR_BDPT, 96, 300, &bdpt);
    split_regions(s, &st, CST_INTEGRATOR_VCM, 24, 400, &vcm);
    compare(&path, &light, "path (explicit medium)", "light (subsurface)");
    compare(&path, &bdpt, "path (explicit medium)", "bdpt (subsurface)");
    compare(&path, &vcm, "path (explicit medium)", "vcm (subsurface)");
    compare(&light, &bdpt, "light (subsurface)", "bdpt (subsurface)");
    compare(&bdpt, &vcm, "bdpt (subsurface)", "vcm (subsurface)");
    scene_destroy(ref);
    scene_destroy(s);
}

/* The view is the explicit medium: path (with subsurface_walk), light, bdpt and vcm
 * render the subsurface box pixel for pixel as they render the explicit-medium box (the
 * same random numbers meet the same media); path without subsurface_walk does not (the
 * BSSRDF). 16 x 16, 2 samples. */
static void test_sss_view_exact(void **state)
{
    (void)state;
    Scene *ref = sss_box(true), *s = sss_box(false);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.subsurface_walk = 1; /* light, bdpt, vcm and mmlt refuse subsurface materials without it */
    st.width = st.height = 16;
    st.color_mode = g_color_mode;
    st.max_depth = 8;
    st.subsurface_walk = 1;
    const CstIntegrator integ[5] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_LIGHT, CST_INTEGRATOR_BDPT,
                                    CST_INTEGRATOR_VCM, CST_INTEGRATOR_PATH};
    float a[16 * 16 * 3], b[16 * 16 * 3];
    for (int k = 0; k < 5; k++) {
        if (k == 4) st.subsurface_walk = 0;
        CstFilm *fa = render_film(s, &st, integ[k], 2, 900), *fb = render_film(ref, &st, integ[k], 2, 900);
        cst_film_pixels(fa, a);
        cst_film_pixels(fb, b);
        const bool same = memcmp(a, b, sizeof a) == 0;
        print_message("%s%s: subsurface box %s the explicit-medium box\n", cst_integrator_name(integ[k]),
                      k == 4 ? " (bssrdf)" : "", same ? "renders as" : "differs from");
        assert_true(same == (k < 4));
        cst_film_destroy(fa);
        cst_film_destroy(fb);
    }
    scene_destroy(ref);
    scene_destroy(s);
}

/* mmlt against bdpt on the subsurface box (test_media_bidir.c's mmlt settings). */
static void test_sss_mmlt(void **state)
{
    (void)state;
    Scene *s = sss_box(false);
    CstRenderSettings sm;
    cst_render_settings_init(&sm);
    sm.subsurface_walk = 1;
    sm.color_mode = g_color_mode;
    sm.width = sm.height = 24;
    sm.filter = CST_FILTER_BOX;
    sm.max_depth = 6;
    sm.spp = 8;
    sm.mlt_chains = 64;
    sm.mlt_bootstrap = 1024;
    Regions rb = regions(24, 12), rm = regions(24, 12);
    split_regions(s, &sm, CST_INTEGRATOR_BDPT, 24, 500, &rb);
    split_regions(s, &sm, CST_INTEGRATOR_MMLT, 24, 600, &rm);
    compare(&rb, &rm, "bdpt (subsurface, 24)", "mmlt (subsurface, 24)");
    scene_destroy(s);
}

/* A smooth subsurface ball of scattering-only medium (radius 2) in a black two-sided
 * enclosure emitting L (radius 4): L everywhere. BDPT (the camera walk through the smooth
 * boundary) and VCM (its volume merges inside); not the light tracer, whose connections
 * to the lens cannot cross the smooth surface. */
static void test_sss_furnace(void **state)
{
    (void)state;
    CstError err;
    const Color L = color_rgb(1.0f, 0.5f, 0.25f);
    Scene *s = scene_create();
    int black;
    Material mb = {.type = MATERIAL_DIFFUSE, .albedo = {{0.0f, 0.0f, 0.0f, 0.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &mb, &black, &err), CST_OK);
    Emission em = {L, 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 4.0f, black, &em, &err), CST_OK);
    const int sss = add_sss(s, 0.0f, color_s(0.0f), color_rgb(0.5f, 1.0f, 0.25f), false);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 2.0f, sss, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 0.5f, 3.5f}, {0, 0, 0}, {0, 1, 0}, 50.0f, 0.0f, 3.5f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    const CstIntegrator integ[2] = {CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (int k = 0; k < 2; k++) {
        CstRenderSettings st;
        cst_render_settings_init(&st);
    st.subsurface_walk = 1; /* light, bdpt, vcm and mmlt refuse subsurface materials without it */
        st.width = st.height = 16;
        st.spp = 2;
        st.color_mode = g_color_mode;
        st.photon_radius = integ[k] == CST_INTEGRATOR_VCM ? 0.25 : 0.0;
        Regions r = regions(16, 8);
        split_regions(s, &st, integ[k], 24, 700 + (uint64_t)k, &r);
        for (int i = 0; i < r.count; i++)
            for (int c = 0; c < 3; c++) {
                double dev = fabs(r.stat[i].mean[c] - (double)L.c[c]);
                if (!(dev <= Z_LIMIT * r.stat[i].se[c] + 1e-5 * (double)L.c[c]))
                    fail_msg("subsurface furnace, %s: block %d channel %d: %.6f, expected %.6f (z = %.2f)",
                             cst_integrator_name(integ[k]), i - 1, c, r.stat[i].mean[c], (double)L.c[c],
                             (r.stat[i].mean[c] - (double)L.c[c]) / r.stat[i].se[c]);
            }
        print_message("subsurface furnace, %s: whole image %.5f %.5f %.5f (se %.1e), expected %.5f %.5f %.5f\n",
                      cst_integrator_name(integ[k]), r.stat[0].mean[0], r.stat[0].mean[1], r.stat[0].mean[2],
                      r.stat[0].se[0], (double)L.c[0], (double)L.c[1], (double)L.c[2]);
    }
    scene_destroy(s);
}

/* Whitted, photon, sppm and pssmlt still refuse subsurface materials; light, bdpt, vcm
 * and mmlt refuse one whose reflectance is a texture (not a homogeneous medium) or an
 * instanced one. */
static void test_sss_refusals(void **state)
{
    (void)state;
    Scene *s = sss_box(false);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.subsurface_walk = 1; /* light, bdpt, vcm and mmlt refuse subsurface materials without it */
    st.width = st.height = 8;
    st.spp = 1;
    const CstIntegrator refused[4] = {CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM,
                                      CST_INTEGRATOR_PSSMLT};
    for (int i = 0; i < 4; i++) {
        CstError err;
        CstFilm *f = NULL;
        st.integrator = refused[i];
        assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
        assert_non_null(strstr(err.msg, "subsurface"));
        cst_film_destroy(f);
    }
    /* Without subsurface_walk the path tracers take the BSSRDF, another estimand: the
     * light-path integrators refuse rather than render another image. */
    const CstIntegrator walkers[4] = {CST_INTEGRATOR_LIGHT, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM,
                                      CST_INTEGRATOR_MMLT};
    st.subsurface_walk = 0;
    for (int i = 0; i < 4; i++) {
        CstError err;
        CstFilm *f = NULL;
        st.integrator = walkers[i];
        assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
        assert_non_null(strstr(err.msg, "--subsurface walk"));
        cst_film_destroy(f);
    }
    st.subsurface_walk = 1;
    scene_destroy(s);
    CstError err;
    s = scene_create();
    CstTextureDesc td = {0};
    td.type = CST_TEXTURE_CONSTANT;
    td.value[0] = td.value[1] = td.value[2] = 0.5f;
    int tex = 0; /* public ids are 1 + the index, as Material.sss_reflectance_texture */
    assert_int_equal(cst_scene_add_texture(s, &td, &tex, &err), CST_OK);
    Material m = {.type = MATERIAL_DIELECTRIC, .albedo = {{1, 1, 1, 1}}, .ior = SSS_IOR, .subsurface = true,
                  .sss_from_reflectance = true, .sss_reflectance_texture = tex};
    m.sss_reflectance = color_s(0.5f);
    m.sss_mfp = color_s(1.0f);
    int id;
    assert_int_equal(scene_add_material(s, &m, &id, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.0f, id, NULL, &err), CST_OK);
    Emission em = {color_s(1.0f), 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 4.0f, id, &em, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    st.integrator = CST_INTEGRATOR_BDPT;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "texture"));
    cst_film_destroy(f);
    scene_destroy(s);
    /* An instanced triangle of a subsurface material: refused by the walk (instances carry
     * no medium interface), rendered by path's BSSRDF. */
    s = scene_create();
    const int sss = add_sss(s, 0.3f, sss_sigma_a(), sss_sigma_s(), false);
    const Vec3 tri[3] = {{-1, -1, 0}, {1, -1, 0}, {0, 1, 0}};
    const int idx[3] = {0, 1, 2}, mat[1] = {sss};
    int proto;
    assert_int_equal(scene_add_instance_proto(s, tri, NULL, 3, idx, mat, 1, &proto, &err), CST_OK);
    const Transform ident = transform_identity();
    assert_int_equal(scene_add_instance(s, proto, &ident, &err), CST_OK);
    Emission em1 = {color_s(1.0f), 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 4.0f, sss, &em1, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    for (int k = 0; k < 2; k++) {
        st.integrator = k ? CST_INTEGRATOR_PATH : CST_INTEGRATOR_VCM;
        st.subsurface_walk = !k; /* path: its BSSRDF */
        f = NULL;
        assert_int_equal(cst_render(s, &st, &f, NULL, &err), k ? CST_OK : CST_ERR_UNSUPPORTED);
        if (!k) assert_non_null(strstr(err.msg, "instance"));
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    for (int i = 1; i + 1 < argc; i++)
        if (strcmp(argv[i], "--only") == 0) cmocka_set_test_filter(argv[i + 1]);
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sss_agreement),
        cmocka_unit_test(test_sss_view_exact),
        cmocka_unit_test(test_sss_mmlt),
        cmocka_unit_test(test_sss_furnace),
        cmocka_unit_test(test_sss_refusals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
