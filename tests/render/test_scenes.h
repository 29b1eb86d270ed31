/* Scenes several statistical render tests share, built and committed through the scene
 * API: the emitting furnace sphere and the floor under a glass interface. */
#ifndef CST_TESTS_RENDER_TEST_SCENES_H
#define CST_TESTS_RENDER_TEST_SCENES_H

#include "math/spectrum.h"
#include "scene/scene.h"

/* Inside a closed sphere of albedo rho whose surface also emits L_e = (1, 0.5, 0.25) on
 * both sides, the radiance is L_e / (1 - rho) in every direction (written to expect):
 * long paths, Russian roulette, channels kept apart. The camera looks from inside. */
static inline Scene *test_scene_emitting_sphere(float rho, double expect[3])
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int grey;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{rho, rho, rho}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &grey, &err), CST_OK);
    Emission em = {{{1.0f, 0.5f, 0.25f}}, 1, 0};
    assert_int_equal(scene_add_sphere(s, v3(0, 0, 0), 1.0f, grey, &em, &err), CST_OK);
    CameraDesc cam = {{0.1f, 0.2f, 0.3f}, {0, 0, -1}, {0, 1, 0}, 90.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    const double rd = (double)rho;
    expect[0] = 1.0 / (1.0 - rd);
    expect[1] = 0.5 / (1.0 - rd);
    expect[2] = 0.25 / (1.0 - rd);
    return s;
}

/* The emitting sphere's expectation in spectral mode, written to expect: the film's RGB of
 * the emission's illuminant spectrum (math/spectrum.h), over 1 - rho (a grey albedo is a
 * constant spectrum). RGB -> spectrum -> RGB is not the identity: for (1, 0.5, 0.25) it
 * gives (0.99988, 0.49963, 0.24967), 0.08% low in green, which BDPT's whole-image mean (se
 * 0.04%) saw as z = -1.7 on average over 40 seeds (both samplers). The integral over
 * 360-830 nm by the midpoint rule at 0.1 nm, each step through spectrum_to_rgb with all
 * four lanes at one wavelength of pdf 1 / 470 (converged to 1e-6: the CIE curves are
 * linear between 5 nm samples). */
static inline void test_emitting_sphere_expect_spectral(float rho, double expect[3])
{
    const int n = 4700;
    const Color le = color_rgb(1.0f, 0.5f, 0.25f);
    double acc[3] = {0.0, 0.0, 0.0};
    for (int k = 0; k < n; k++) {
        Wavelengths wl;
        float lambda = (float)SPECTRUM_LAMBDA_MIN +
                       ((float)k + 0.5f) * ((float)(SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN) / (float)n);
        for (int i = 0; i < COLOR_LANES; i++) {
            wl.lambda[i] = lambda;
            wl.pdf[i] = 1.0f / (float)(SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN);
        }
        Color rgb = spectrum_to_rgb(spectrum_illuminant(le, &wl), &wl);
        for (int c = 0; c < 3; c++) acc[c] += (double)rgb.c[c];
    }
    for (int c = 0; c < 3; c++) expect[c] = acc[c] / (double)n / (1.0 - (double)rho);
}

/* A diffuse floor under a flat glass interface (IOR 1.5, the outside above), lit from
 * above through it by a quad emitter, seen by a camera under the interface looking
 * straight down at the floor. Windings give the normals: floor and interface +y, emitter
 * -y. No delta surface is directly visible. */
static inline Scene *test_scene_glass_interface(void)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int floor_mat, glass_mat, light_mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.5f, 0.3f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &floor_mat, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &light_mat, &err), CST_OK);
    Material glass = {.type = MATERIAL_GLASS, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = 1.5f};
    assert_int_equal(scene_add_material(s, &glass, &glass_mat, &err), CST_OK);
    Vec3 floor_q[4] = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    Vec3 glass_q[4] = {{-3, 1, -3}, {-3, 1, 3}, {3, 1, 3}, {3, 1, -3}};
    Vec3 light_q[4] = {{-1.5f, 2, -1.5f}, {1.5f, 2, -1.5f}, {1.5f, 2, 1.5f}, {-1.5f, 2, 1.5f}};
    Emission em = {{{4.0f, 4.0f, 4.0f}}, 0, 0};
    assert_int_equal(scene_add_quad(s, floor_q, floor_mat, NULL, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, glass_q, glass_mat, NULL, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, light_q, light_mat, &em, &err), CST_OK);
    CameraDesc cam = {{0, 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 90.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

#endif
