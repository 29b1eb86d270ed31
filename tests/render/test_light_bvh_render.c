/* The light BVH renders the same image as power selection: a floor and a wall under 200
 * small one-sided quad lights, 20 small emitting spheres of random colours and a projection
 * light, rendered by
 * the path tracer (MIS and NEE only) and the Whitted integrator with each light sampler;
 * every 8 x 6 block's mean agrees within Z_LIMIT standard errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "render/render_util.h"
#include "scene/scene.h"

#define W 32
#define H 24
#define BX 8
#define BY 6

static Scene *many_lights(void)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.7f, 0.7f, 0.7f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    Vec3 floor[4] = {{-10, 0, -10}, {-10, 0, 10}, {10, 0, 10}, {10, 0, -10}};
    Vec3 wall[4] = {{-10, 0, 10}, {-10, 10, 10}, {10, 10, 10}, {10, 0, 10}};
    assert_int_equal(scene_add_quad(s, floor, white, NULL, &err), CST_OK);
    assert_int_equal(scene_add_quad(s, wall, white, NULL, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(-2.0f, 1.0f, 2.0f), 1.0f, white, NULL, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(3.0f, 1.5f, 4.0f), 1.5f, white, NULL, &err), CST_OK);
    Pcg32 rng;
    pcg32_seed(&rng, 2018u, 5u);
    for (int i = 0; i < 200; i++) {
        float x = 16.0f * pcg32_float(&rng) - 8.0f, z = 16.0f * pcg32_float(&rng) - 8.0f;
        float h = 0.5f + 4.0f * pcg32_float(&rng), q = 0.1f + 0.2f * pcg32_float(&rng);
        /* (v1 - v0) x (v2 - v0) points down: the light faces the floor */
        Vec3 v[4] = {{x, h, z}, {x + q, h, z}, {x + q, h, z + q}, {x, h, z + q}};
        float a = 20.0f + 80.0f * pcg32_float(&rng);
        Emission e = {{{a * pcg32_float(&rng), a * pcg32_float(&rng), a * pcg32_float(&rng)}}, 0, 0};
        assert_int_equal(scene_add_quad(s, v, black, &e, &err), CST_OK);
    }
    for (int i = 0; i < 20; i++) {
        Vec3 c = v3(16.0f * pcg32_float(&rng) - 8.0f, 0.5f + 5.0f * pcg32_float(&rng), 16.0f * pcg32_float(&rng) - 8.0f);
        Emission e = {{{10.0f, 8.0f, 6.0f}}, 0, 0};
        assert_int_equal(scene_add_sphere(s, c, 0.05f + 0.1f * pcg32_float(&rng), black, &e, &err), CST_OK);
    }
    {
        /* a projection light (a frustum of a 2 x 1 image) looking down and to the side */
        static const float img[2 * 1 * 3] = {4.0f, 2.0f, 1.0f, 1.0f, 2.0f, 4.0f};
        CstLightDesc pl;
        memset(&pl, 0, sizeof pl);
        pl.type = CST_LIGHT_PROJECTION;
        pl.position[0] = 2.0f, pl.position[1] = 5.0f, pl.position[2] = 1.0f;
        pl.intensity[0] = pl.intensity[1] = pl.intensity[2] = 3.0f;
        pl.image = img;
        pl.image_width = 2;
        pl.image_height = 1;
        pl.fov = 35.0f;
        const float lfw[9] = {1, 0, 0, 0, 0.8f, 0.6f, 0, -0.6f, 0.8f}; /* axis (0, -0.6, 0.8) */
        memcpy(pl.light_from_world, lfw, sizeof lfw);
        assert_int_equal(cst_scene_add_light(s, &pl, &err), CST_OK);
    }
    CameraDesc cam = {{0, 6, -14}, {0, 1, 2}, {0, 1, 0}, 55.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static void render_blocks(Scene *s, const char *sampler, CstIntegrator integ, int spp, RegionStat *out)
{
    CstError err;
    assert_int_equal(cst_scene_set_light_sampler(s, sampler, &err), CST_OK);
    CstRenderSettings st = {0};
    st.width = W;
    st.height = H;
    st.spp = spp;
    st.integrator = integ;
    st.max_depth = 3;
    st.seed = strcmp(sampler, "bvh") == 0 ? 101u : 202u; /* independent renders */
    st.seed_set = 1;
    st.threads = 2;
    CstFilm *f = NULL;
    CstRenderStats stats;
    st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
    assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
    assert_int_equal(stats.nonfinite, 0);
    int k = 0;
    for (int by = 0; by < H; by += BY)
        for (int bx = 0; bx < W; bx += BX) out[k++] = region_stat(f, bx, by, bx + BX, by + BY);
    out[k] = region_stat(f, 0, 0, W, H);
    cst_film_destroy(f);
}

static void compare(CstIntegrator integ, int spp)
{
    Scene *s = many_lights();
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_BVH); /* 421 lights: the rule's choice */
    enum { R = (W / BX) * (H / BY) + 1 };
    RegionStat a[R], b[R];
    render_blocks(s, "bvh", integ, spp, a);
    render_blocks(s, "power", integ, spp, b);
    double zmax = 0.0, se_ratio = 0.0;
    for (int i = 0; i < R; i++)
        for (int c = 0; c < 3; c++) {
            double z = z_score(a[i].mean[c], a[i].se[c], b[i].mean[c], b[i].se[c]);
            zmax = fmax(zmax, fabs(z));
            if (fabs(z) > Z_LIMIT)
                print_message("  block %d channel %d: bvh %.5f +- %.5f, power %.5f +- %.5f, z = %.2f\n", i, c,
                              a[i].mean[c], a[i].se[c], b[i].mean[c], b[i].se[c], z);
            assert_true(fabs(z) <= Z_LIMIT);
        }
    for (int c = 0; c < 3; c++) se_ratio += b[R - 1].se[c] / a[R - 1].se[c] / 3.0;
    print_message("  %s: image mean bvh %.5f power %.5f (green), max |z| %.2f over %d comparisons; "
                  "standard error power / bvh = %.2f at equal spp\n",
                  cst_integrator_name(integ), a[R - 1].mean[1], b[R - 1].mean[1], zmax, 3 * R, se_ratio);
    scene_destroy(s);
}

/* 2048 spp: with power selection over 421 small lights the per-pixel variance estimates
 * of a few hundred samples miss the rare bright samples (at 512 spp one path-nee block gave
 * z = 4.3, the same block at 8192 spp |z| < 2.3: heavy tails, not a bias). */
static void test_path_mis(void **state) { (void)state; compare(CST_INTEGRATOR_PATH, 2048); }
static void test_path_nee(void **state) { (void)state; compare(CST_INTEGRATOR_PATH_NEE, 2048); }
static void test_whitted(void **state) { (void)state; compare(CST_INTEGRATOR_WHITTED, 2048); }

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_mis),
        cmocka_unit_test(test_path_nee),
        cmocka_unit_test(test_whitted),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
