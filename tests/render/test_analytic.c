/* Analytic test: radiance reflected by a diffuse plane under a rectangular emitter,
 * against the closed-form irradiance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "render/render_util.h"
#include "scene/scene.h"

/* Form factor from a differential area to a parallel rectangle a x b at height h whose
 * corner lies straight above it (Howell's catalogue of configuration factors, B-3):
 * F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))],
 * X = a/h, Y = b/h. Irradiance from a Lambertian emitter of radiance L is E = pi L F. */
static double corner_form_factor(double a, double b, double h)
{
    double X = a / h, Y = b / h;
    double sx = sqrt(1.0 + X * X), sy = sqrt(1.0 + Y * Y);
    return (X / sx * atan(Y / sx) + Y / sy * atan(X / sy)) / (2.0 * 3.14159265358979323846);
}

/* Radiance leaving a diffuse plane of albedo rho at the point below an a x b emitter's
 * centre: L_o = rho E / pi = rho L * 4 F(a/2, b/2, h). */
static void run_case(CstIntegrator integ, double a, double b, double h, uint64_t seed)
{
    CstError err;
    Scene *s = scene_create();
    int plane_mat, light_mat;
    const float rho = 0.8f, Le = 3.0f;
    Material m = {MATERIAL_DIFFUSE, {rho, rho, rho}, 1.0f};
    assert_int_equal(scene_add_material(s, &m, &plane_mat, &err), CST_OK);
    m.albedo = rgb_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &light_mat, &err), CST_OK);
    /* Plane y = 0 with normal +y; emitter at y = h, normal -y (winding gives the side). */
    Vec3 plane[4] = {{-50, 0, -50}, {-50, 0, 50}, {50, 0, 50}, {50, 0, -50}};
    assert_int_equal(scene_add_quad(s, plane, plane_mat, NULL, &err), CST_OK);
    float ha = (float)(a / 2), hb = (float)(b / 2), fh = (float)h;
    Vec3 light[4] = {{-ha, fh, -hb}, {ha, fh, -hb}, {ha, fh, hb}, {-ha, fh, hb}};
    Emission em = {{Le, Le, Le}, 0};
    assert_int_equal(scene_add_quad(s, light, light_mat, &em, &err), CST_OK);
    /* A pinhole (which blocks nothing) between the two, looking straight down with a
     * field of view so narrow that the pixel sees a single point of the plane. */
    CameraDesc cam = {{0, fh * 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 1e-3f, 0.0f, 1.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);

    CstRenderSettings st = {0};
    st.width = st.height = 1;
    st.spp = 1 << 20;
    st.integrator = integ;
    st.seed = seed;
    st.seed_set = 1;
    st.threads = 2;
    CstFilm *f = NULL;
    CstRenderStats stats;
    assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
    double expected = (double)rho * (double)Le * 4.0 * corner_form_factor(a / 2, b / 2, h);
    RegionStat r = region_stat(f, 0, 0, 1, 1);
    for (int c = 0; c < 3; c++) {
        double z = (r.mean[c] - expected) / r.se[c];
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("%s a=%g b=%g h=%g: L = %.6f, closed form %.6f (z = %.2f)",
                     cst_integrator_name(integ), a, b, h, r.mean[c], expected, z);
    }
    cst_film_destroy(f);
    scene_destroy(s);
}

static void test_rectangle_irradiance(void **state)
{
    (void)state;
    const CstIntegrator v[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_PATH_BSDF};
    for (int i = 0; i < 3; i++) {
        run_case(v[i], 1.0, 1.0, 1.0, 11 + i);  /* square, moderate solid angle */
        run_case(v[i], 4.0, 0.5, 0.7, 21 + i);  /* elongated, large solid angle */
        run_case(v[i], 0.2, 0.3, 2.0, 31 + i);  /* small and far: NEE's favourable case */
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rectangle_irradiance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
