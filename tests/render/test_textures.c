/* Textures in light transport: a checkerboard-textured diffuse plane under a constant
 * environment against its closed form, and a scene with textured albedo, roughness and
 * emission (quad and sphere emitters) on which every estimator must agree: MIS, NEE-only
 * and BSDF-only path tracing (NEE's point on a light and a hit on it see one radiance),
 * light tracing (emission sampled at a uv), BDPT and VCM (light vertices keep their uv). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

static int add_texture(Scene *s, const Texture *t)
{
    int id;
    CstError err;
    assert_int_equal(scene_add_texture(s, t, &id, &err), CST_OK);
    return id;
}

/* A checkerboard of two colours; returns its id. */
static int add_checker(Scene *s, Color even, Color odd, float scale)
{
    Texture t;
    texture_constant(&t, even);
    int e = add_texture(s, &t);
    texture_constant(&t, odd);
    int o = add_texture(s, &t);
    texture_checkerboard(&t, s->textures, e, o, scale);
    return add_texture(s, &t);
}

/* ------------------------------------------------------------------ closed form */

/* A 1 x 1 diffuse quad (normal +y) with a 4 x 4 checkerboard of albedos A and B, under a
 * constant environment of radiance 1, seen straight down by an orthographic camera that
 * frames exactly the quad: every point sees the whole upper hemisphere, so L(x) = rho(x),
 * and each 8 x 8 block of the 32 x 32 image covers exactly one square. The whole image
 * and each quadrant must average (A + B) / 2; each block must be A or B, alternating. */
static void test_checker_plane_closed_form(void **state)
{
    (void)state;
    enum { SIZE = 32, SQUARE = 8 };
    const Color A = {{0.9f, 0.2f, 0.5f}}, B = {{0.1f, 0.6f, 0.5f}};
    CstError err;
    Scene *s = scene_create();
    int board = add_checker(s, A, B, 4.0f), mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo_texture = board + 1, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Vec3 q[4] = {{-0.5f, 0, -0.5f}, {-0.5f, 0, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 0, -0.5f}};
    assert_int_equal(scene_add_quad(s, q, mat, NULL, &err), CST_OK);
    EnvMap env;
    assert_int_equal(envmap_init_constant(&env, color_s(1.0f), &err), CST_OK);
    assert_int_equal(scene_set_environment(s, &env, &err), CST_OK);
    CameraDesc cam = {{0, 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 0.0f, 0.0f, 1.0f, 1.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);

    /* (BSDF-only sampling would be exact here: every sample is rho(x) times 1.) */
    const CstIntegrator integs[2] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE};
    for (int k = 0; k < 2; k++) {
        CstRenderSettings st = {0};
        st.width = st.height = SIZE;
        st.spp = 64;
        st.integrator = integs[k];
        st.seed = 300 + (uint64_t)k;
        st.seed_set = 1;
        st.threads = 2;
        st.filter = CST_FILTER_BOX;
        CstFilm *f = NULL;
        CstRenderStats stats;
        st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
        assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
        assert_int_equal(stats.nonfinite, 0);
        const double half[3] = {0.5 * ((double)A.c[0] + (double)B.c[0]), 0.5 * ((double)A.c[1] + (double)B.c[1]),
                                0.5 * ((double)A.c[2] + (double)B.c[2])};
        double worst = 0.0;
        Regions quads = regions(SIZE, SIZE / 2);
        for (int i = 0; i < quads.count; i++) {
            RegionStat r = region_stat(f, quads.rect[i][0], quads.rect[i][1], quads.rect[i][2], quads.rect[i][3]);
            for (int c = 0; c < 3; c++) {
                double z = (r.mean[c] - half[c]) / r.se[c];
                if (fabs(z) > worst) worst = fabs(z);
                if (!(fabs(z) <= Z_LIMIT))
                    fail_msg("%s: region %d channel %d: %.6f, closed form %.6f (z = %.2f)",
                             cst_integrator_name(integs[k]), i - 1, c, r.mean[c], half[c], z);
            }
        }
        /* blocks: the red channel tells A (0.9) from B (0.1) at any noise level here */
        for (int by = 0; by < SIZE / SQUARE; by++)
            for (int bx = 0; bx < SIZE / SQUARE; bx++) {
                RegionStat r = region_stat(f, bx * SQUARE, by * SQUARE, (bx + 1) * SQUARE, (by + 1) * SQUARE);
                int is_a = r.mean[0] > 0.5;
                RegionStat r0 = region_stat(f, 0, 0, SQUARE, SQUARE);
                assert_int_equal(is_a, (r0.mean[0] > 0.5) ^ ((bx + by) & 1));
                Color want = is_a ? A : B;
                const double w[3] = {(double)want.c[0], (double)want.c[1], (double)want.c[2]};
                for (int c = 0; c < 3; c++) {
                    double z = (r.mean[c] - w[c]) / r.se[c];
                    if (fabs(z) > worst) worst = fabs(z);
                    if (!(fabs(z) <= Z_LIMIT))
                        fail_msg("%s: square (%d, %d) channel %d: %.6f, albedo %.6f (z = %.2f)",
                                 cst_integrator_name(integs[k]), bx, by, c, r.mean[c], w[c], z);
                }
            }
        print_message("%s: textured plane, whole image (r) %.5f vs %.5f, largest |z| = %.2f\n",
                      cst_integrator_name(integs[k]), region_stat(f, 0, 0, SIZE, SIZE).mean[0], half[0], worst);
        cst_film_destroy(f);
    }
    scene_destroy(s);
}

/* ------------------------------------------------------------------ consistency */

/* A floor with a checkerboard albedo, an image-textured diffuse sphere, a rough metal
 * sphere with a checkerboard roughness, lit by a one-sided quad with a checkerboard
 * radiance and a small two-sided emitting sphere with a checkerboard in its spherical
 * uvs. Nothing the camera sees is a delta surface. */
static Scene *textured_scene(void)
{
    CstError err;
    Scene *s = scene_create();
    int floor_tex = add_checker(s, color_rgb(0.8f, 0.3f, 0.2f), color_rgb(0.2f, 0.5f, 0.8f), 4.0f);
    int rough_tex = add_checker(s, color_s(0.3f), color_s(0.65f), 3.0f);
    int quad_le = add_checker(s, color_rgb(6.0f, 5.0f, 4.0f), color_rgb(0.5f, 1.0f, 2.0f), 3.0f);
    int ball_le = add_checker(s, color_rgb(8.0f, 2.0f, 1.0f), color_rgb(1.0f, 3.0f, 6.0f), 4.0f);
    /* an 8 x 4 image of smooth colours */
    float *px = malloc(8 * 4 * 3 * sizeof *px);
    assert_non_null(px);
    for (int y = 0; y < 4; y++)
        for (int x = 0; x < 8; x++) {
            float *p = &px[3 * (y * 8 + x)];
            p[0] = 0.1f + 0.1f * (float)x;
            p[1] = 0.2f + 0.2f * (float)y;
            p[2] = (x + y) % 2 ? 0.9f : 0.1f;
        }
    Texture img;
    assert_int_equal(texture_image(&img, px, 8, 4, TEXTURE_WRAP_REPEAT, &err), CST_OK);
    int img_tex = add_texture(s, &img);

    int floor_mat, ball_mat, metal_mat, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo_texture = floor_tex + 1, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &floor_mat, &err), CST_OK);
    m.albedo_texture = img_tex + 1;
    assert_int_equal(scene_add_material(s, &m, &ball_mat, &err), CST_OK);
    Material metal = {.type = MATERIAL_CONDUCTOR, .roughness_texture = rough_tex + 1, .ior = 1.0f};
    assert_true(material_metal("copper", &metal.eta, &metal.k));
    assert_int_equal(scene_add_material(s, &metal, &metal_mat, &err), CST_OK);
    Material dark = {.type = MATERIAL_DIFFUSE, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &dark, &black, &err), CST_OK);

    Vec3 floor_q[4] = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    assert_int_equal(scene_add_quad(s, floor_q, floor_mat, NULL, &err), CST_OK);
    Vec3 light_q[4] = {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}}; /* normal -y */
    Emission quad_em = {{{1.0f, 1.0f, 1.0f}}, 0, quad_le + 1};
    assert_int_equal(scene_add_quad(s, light_q, black, &quad_em, &err), CST_OK);
    Emission ball_em = {{{1.0f, 1.0f, 1.0f}}, 1, ball_le + 1};
    assert_int_equal(scene_add_sphere(s, v3(0.9f, 0.9f, 0.6f), 0.25f, black, &ball_em, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-0.6f, 0.5f, 0.3f), 0.5f, ball_mat, NULL, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0.5f, 0.35f, -0.4f), 0.35f, metal_mat, NULL, &err), CST_OK);
    CameraDesc cam = {{0, 1.4f, -3.2f}, {0, 0.4f, 0}, {0, 1, 0}, 55.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

enum { CSIZE = 48, CBLOCK = 12 };

static void path_regions(const Scene *s, CstIntegrator integ, int spp, uint64_t seed, Regions *r)
{
    CstRenderSettings st = {0};
    st.width = st.height = CSIZE;
    st.filter = CST_FILTER_BOX;
    camera_regions(s, &st, integ, spp, seed, r);
}

/* Splatting and bidirectional estimators: standard errors from independent renders. */
static void render_regions(const Scene *s, CstIntegrator integ, int renders, uint64_t seed, Regions *r)
{
    CstRenderSettings st = {0};
    st.width = st.height = CSIZE;
    st.filter = CST_FILTER_BOX;
    split_regions(s, &st, integ, renders, seed, r);
}

static void test_textured_estimators_agree(void **state)
{
    (void)state;
    Scene *s = textured_scene();
    Regions rp = regions(CSIZE, CBLOCK), rn = rp, rb = rp, rl = rp, rd = rp, rv = rp;
    path_regions(s, CST_INTEGRATOR_PATH, 512, 11, &rp);
    path_regions(s, CST_INTEGRATOR_PATH_NEE, 512, 12, &rn);
    path_regions(s, CST_INTEGRATOR_PATH_BSDF, 1024, 13, &rb);
    render_regions(s, CST_INTEGRATOR_LIGHT, 256, 14000, &rl);
    render_regions(s, CST_INTEGRATOR_BDPT, 64, 15000, &rd);
    render_regions(s, CST_INTEGRATOR_VCM, 64, 16000, &rv);
    compare(&rp, &rn, "path", "path-nee");
    compare(&rp, &rb, "path", "path-bsdf");
    compare(&rp, &rl, "path", "light");
    compare(&rp, &rd, "path", "bdpt");
    compare(&rp, &rv, "path", "vcm");
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_checker_plane_closed_form),
        cmocka_unit_test(test_textured_estimators_agree),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
