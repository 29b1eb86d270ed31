/* Numeric limits of the public API (issue 25, items 5 and 6): products of values that each
 * pass validation but overflow float together are refused by the builder or at commit; a
 * photon, SPPM or VCM radius too small for the scene (r^2 underflows, 0 x inf = NaN) or
 * too large is refused by cst_render. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <string.h>

#include "caustic/caustic.h"

/* A scene with one diffuse material (id 0) and, if `sphere`, a sphere of radius 1. */
static CstScene *scene_with_material(int sphere)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    CstMaterialDesc m;
    cst_material_desc_init(&m, CST_MATERIAL_DIFFUSE);
    int id = -1;
    assert_int_equal(cst_scene_add_material(s, &m, &id, &err), CST_OK);
    if (sphere) assert_int_equal(cst_scene_add_sphere(s, (const float[3]){0, 0, 0}, 1.0f, id, NULL, &err), CST_OK);
    return s;
}

static void expect_overflow(CstStatus st, const CstError *err, const char *what)
{
    assert_int_equal(st, CST_ERR_INVALID_ARG);
    if (!strstr(err->msg, "overflows a float") || !strstr(err->msg, what))
        fail_msg("message does not name \"%s\" and the overflow: %s", what, err->msg);
}

static void test_light_products(void **state)
{
    (void)state;
    CstScene *s = scene_with_material(0);
    CstError err;
    CstLightDesc l = {.type = CST_LIGHT_POINT, .intensity = {3e38f, 3e38f, 3e38f}};
    expect_overflow(cst_scene_add_light(s, &l, &err), &err, "4 pi x intensity");
    l.intensity[0] = l.intensity[1] = l.intensity[2] = 1e37f; /* power 1.3e38: finite */
    assert_int_equal(cst_scene_add_light(s, &l, &err), CST_OK);
    expect_overflow(cst_scene_set_environment_constant(s, (const float[3]){3e38f, 0, 0}, &err), &err, "4 pi x radiance");
    /* Emission: radiance x texture maximum, and the power of a sphere. */
    CstTextureDesc t = {.type = CST_TEXTURE_CONSTANT, .value = {1e30f, 1e30f, 1e30f}};
    int tex = 0;
    assert_int_equal(cst_scene_add_texture(s, &t, &tex, &err), CST_OK);
    CstEmission e = {{1e30f, 1e30f, 1e30f}, tex, 0, 0};
    expect_overflow(cst_scene_add_sphere(s, (const float[3]){0, 0, 0}, 1.0f, 0, &e, &err), &err, "texture");
    CstEmission big = {{1e37f, 1e37f, 1e37f}, 0, 0, 0};
    expect_overflow(cst_scene_add_sphere(s, (const float[3]){0, 0, 0}, 100.0f, 0, &big, &err), &err, "power");
    assert_int_equal(cst_scene_add_sphere(s, (const float[3]){0, 0, 0}, 1e-3f, 0, &big, &err), CST_OK);
    cst_scene_destroy(s);
}

/* A directional light's power is pi R^2 E with R the scene's bounding radius: known at commit. */
static void test_commit_checks_scene_sized_power(void **state)
{
    (void)state;
    CstScene *s = scene_with_material(0);
    CstError err;
    assert_int_equal(cst_scene_add_sphere(s, (const float[3]){0, 0, 0}, 1e6f, 0, NULL, &err), CST_OK);
    CstLightDesc l = {.type = CST_LIGHT_DIRECTIONAL, .direction = {0, -1, 0}, .intensity = {1e27f, 1e27f, 1e27f}};
    assert_int_equal(cst_scene_add_light(s, &l, &err), CST_OK);
    expect_overflow(cst_scene_commit(s, &err), &err, "directional light");
    cst_scene_destroy(s);
}

static void test_radius_against_scene(void **state)
{
    (void)state;
    CstScene *s = scene_with_material(1); /* diagonal 2 sqrt(3) = 3.46 */
    CstError err;
    CstLightDesc l = {.type = CST_LIGHT_POINT, .position = {0, 3, 0}, .intensity = {10, 10, 10}};
    assert_int_equal(cst_scene_add_light(s, &l, &err), CST_OK);
    assert_int_equal(cst_scene_commit(s, &err), CST_OK);
    static const CstIntegrator integ[] = {CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM, CST_INTEGRATOR_VCM};
    for (int k = 0; k < 3; k++) {
        CstRenderSettings rs;
        cst_render_settings_init(&rs);
        rs.width = rs.height = 8;
        rs.spp = 1;
        rs.threads = 1;
        rs.photons = 1000;
        rs.integrator = integ[k];
        static const double bad[] = {1e-30, 1e-8, 3e-6, 1e19, 1e30};
        for (int b = 0; b < 5; b++) {
            CstFilm *f = NULL;
            rs.photon_radius = bad[b];
            assert_int_equal(cst_render(s, &rs, &f, NULL, &err), CST_ERR_INVALID_ARG);
            assert_null(f);
            if (!strstr(err.msg, "radius")) fail_msg("%s", err.msg);
        }
        CstFilm *f = NULL;
        CstRenderStats st;
        rs.photon_radius = 4e-6; /* just above 1e-6 of the diagonal */
        assert_int_equal(cst_render(s, &rs, &f, &st, &err), CST_OK);
        assert_int_equal((int)st.nonfinite, 0);
        cst_film_destroy(f);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_light_products),
        cmocka_unit_test(test_commit_checks_scene_sized_power),
        cmocka_unit_test(test_radius_against_scene),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
