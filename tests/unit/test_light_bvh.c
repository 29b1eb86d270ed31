/* The light BVH (lights/light_bvh.c): its choice of light at a shading point against
 * light_bvh_pmf() by a chi-square test over every light (the "no light" outcome a cell of
 * its own), pmf() equal to the probability the sample reports, the pmfs summing to the
 * probability of a choice; the selection rule and the uniform sampler. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "lights/light_bvh.h"
#include "scene/scene.h"
#include "unit/chi2.h"

/* 150 small triangles of random orientation (a third two-sided) and random radiance, 8
 * spheres, 4 point and 4 spot lights and a directional light, in a box of side 10. */
static Scene *many_lights_scene(uint64_t seed)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 1u);
    for (int i = 0; i < 150; i++) {
        Vec3 c = v3(10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng));
        Vec3 v[3];
        for (int k = 0; k < 3; k++)
            v[k] = v3_add(c, v3(0.4f * pcg32_float(&rng) - 0.2f, 0.4f * pcg32_float(&rng) - 0.2f,
                                0.4f * pcg32_float(&rng) - 0.2f));
        int idx[3] = {0, 1, 2};
        float a = 0.1f + 5.0f * pcg32_float(&rng);
        Emission e = {{{a, a * pcg32_float(&rng), a * pcg32_float(&rng)}}, i % 3 == 0, 0};
        assert_int_equal(scene_add_mesh(s, v, 3, idx, 1, mat, &e, &err), CST_OK);
    }
    for (int i = 0; i < 8; i++) {
        Vec3 c = v3(10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng));
        Emission e = {{{2.0f, 1.0f, 0.5f}}, 0, 0};
        assert_int_equal(scene_add_sphere(s, c, 0.05f + 0.3f * pcg32_float(&rng), mat, &e, &err), CST_OK);
    }
    for (int i = 0; i < 8; i++) {
        DeltaLight d;
        memset(&d, 0, sizeof d);
        d.type = i < 4 ? DELTA_POINT : DELTA_SPOT;
        d.p = v3(10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng), 10.0f * pcg32_float(&rng));
        d.dir = v3_normalize(v3(pcg32_float(&rng) - 0.5f, -1.0f, pcg32_float(&rng) - 0.5f));
        d.intensity = color_s(1.0f + 10.0f * pcg32_float(&rng));
        d.cos_inner = 0.95f;
        d.cos_outer = 0.8f;
        assert_int_equal(scene_add_delta_light(s, &d, &err), CST_OK);
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
    DeltaLight dl = {DELTA_DIRECTIONAL, {0, 0, 0}, {0, -1, 0}, {{0.5f, 0.5f, 0.5f}}, 0, 0, {0}, {0}};
    assert_int_equal(scene_add_delta_light(s, &dl, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    EmitterGeometry g = scene_emitter_geometry(s);
    assert_int_equal(emitter_sampler_set_nee(&s->emitter_sampler, &g, LIGHT_SELECT_BVH, &err), CST_OK);
    return s;
}

/* One shading point: 10^6 choices against N pmf per light, plus a cell for "none"
 * (probability 1 - sum pmf). */
static void choice_case(const Scene *s, Vec3 x, Vec3 n, uint64_t seed)
{
    const EmitterSampler *es = &s->emitter_sampler;
    const LightBvh *bvh = es->bvh;
    const int L = es->lights;
    enum { N = 1000000 };
    double *obs = calloc((size_t)L + 1, sizeof *obs), *expd = calloc((size_t)L + 1, sizeof *expd);
    assert_non_null(obs);
    assert_non_null(expd);
    double sum = 0.0;
    for (int i = 0; i < L; i++) {
        expd[i] = (double)light_bvh_pmf(bvh, x, n, i);
        assert_true(expd[i] >= 0.0 && expd[i] <= 1.0);
        sum += expd[i];
    }
    assert_true(sum <= 1.0 + 1e-5);
    expd[L] = fmax(0.0, 1.0 - sum);
    for (int i = 0; i <= L; i++) expd[i] *= N;
    Pcg32 rng;
    pcg32_seed(&rng, seed, 7u);
    for (int k = 0; k < N; k++) {
        float pmf;
        int i = light_bvh_sample(bvh, x, n, pcg32_float(&rng), &pmf);
        if (i < 0) {
            obs[L] += 1.0;
            continue;
        }
        obs[i] += 1.0;
        /* the sample's probability is pmf()'s (products taken in another order) */
        float q = light_bvh_pmf(bvh, x, n, i);
        assert_true(fabsf(pmf - q) <= 1e-5f * q);
        /* and light_nee_pmf()'s, which the path tracer's MIS uses */
        assert_true(light_nee_pmf(es, x, n, i) == q);
    }
    int dof;
    double stat, outside;
    double p = chi2_pvalue(obs, expd, L + 1, &dof, &stat, &outside);
    print_message("  x (%.2f %.2f %.2f) n (%.2f %.2f %.2f): sum pmf %.6f, chi2 %.1f, dof %d, p %.4f\n",
                  (double)x.x, (double)x.y, (double)x.z, (double)n.x, (double)n.y, (double)n.z, sum, stat, dof, p);
    assert_true(outside == 0.0);
    assert_true(p > 1e-4);
    free(obs);
    free(expd);
}

static void test_bvh_choice_chi2(void **state)
{
    (void)state;
    Scene *s = many_lights_scene(3u);
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_BVH);
    const LightBvh *bvh = s->emitter_sampler.bvh;
    assert_int_equal(bvh->num_infinite, 1);
    assert_true(bvh->num_nodes == 2 * (s->emitter_sampler.lights - 1) - 1);
    /* points inside the cluster, at its edge and far away; normals of every kind */
    choice_case(s, v3(5.0f, 5.0f, 5.0f), v3(0.0f, 1.0f, 0.0f), 11u);
    choice_case(s, v3(1.0f, 9.0f, 3.0f), v3_normalize(v3(1.0f, -1.0f, 0.5f)), 12u);
    choice_case(s, v3(-3.0f, 5.0f, 5.0f), v3(-1.0f, 0.0f, 0.0f), 13u); /* facing away: only |cos| bounds */
    choice_case(s, v3(40.0f, 30.0f, -20.0f), v3(0.0f, 0.0f, 0.0f), 14u); /* far, no normal (a medium) */
    choice_case(s, v3(5.0f, -0.5f, 5.0f), v3(0.0f, 1.0f, 0.0f), 15u);
    scene_destroy(s);
}

/* NEE through the scene's sampler: light_sample_nee's pdf_w includes the BVH's pmf, and the
 * MIS density of a BSDF-sampled ray that hits the same point equals it. */
static void test_bvh_nee_densities(void **state)
{
    (void)state;
    Scene *s = many_lights_scene(5u);
    const EmitterSampler *es = &s->emitter_sampler;
    EmitterGeometry g = scene_emitter_geometry(s);
    Pcg32 rng;
    pcg32_seed(&rng, 21u, 2u);
    Vec3 x = v3(4.0f, 6.0f, 5.0f), n = v3_normalize(v3(0.2f, 1.0f, -0.3f));
    int area = 0, delta = 0;
    for (int k = 0; k < 20000; k++) {
        LightLi ls;
        float u_sel = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        if (!light_sample_nee(es, &g, x, n, u_sel, u, &ls)) continue;
        float pmf = light_nee_pmf(es, x, n, ls.light);
        if (ls.delta) {
            assert_true(fabsf(ls.pmf - pmf) <= 1e-5f * pmf);
            delta++;
            continue;
        }
        float pdf = light_area_nee_pdf_w(es, &g, ls.light, x, n, ls.dist, ls.cos_light);
        assert_true(fabsf(ls.pdf_w - pdf) <= 2e-4f * pdf);
        area++;
    }
    print_message("  %d area and %d delta samples checked\n", area, delta);
    assert_true(area > 1000 && delta > 100);
    scene_destroy(s);
}

/* Few lights keep power selection (today's images); many get the BVH; "uniform" picks
 * each light with 1 / lights. */
static void test_selection_rule(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Emission e = {{{1.0f, 1.0f, 1.0f}}, 0, 0};
    for (int i = 0; i < LIGHT_SELECT_BVH_ABOVE; i++)
        assert_int_equal(scene_add_sphere(s, v3((float)i, 0.0f, 0.0f), 0.25f, mat, &e, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_POWER);
    assert_null(s->emitter_sampler.bvh);
    scene_destroy(s);

    s = scene_create();
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    for (int i = 0; i <= LIGHT_SELECT_BVH_ABOVE; i++)
        assert_int_equal(scene_add_sphere(s, v3((float)i, 0.0f, 0.0f), 0.25f, mat, &e, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_BVH);
    assert_int_equal(cst_scene_set_light_sampler(s, "uniform", &err), CST_OK);
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_UNIFORM);
    assert_int_equal(cst_scene_set_light_sampler(s, "exhaustive", &err), CST_ERR_INVALID_ARG);
    assert_int_equal(s->emitter_sampler.nee, LIGHT_SELECT_UNIFORM);
    const EmitterSampler *es = &s->emitter_sampler;
    EmitterGeometry g = scene_emitter_geometry(s);
    int seen = 0;
    for (int k = 0; k < 1000; k++) {
        LightLi ls;
        if (!light_sample_nee(es, &g, v3(3.0f, 2.0f, 1.0f), v3(0, 1, 0), ((float)k + 0.5f) / 1000.0f,
                              v2(0.5f, 0.5f), &ls))
            continue;
        assert_int_equal(ls.light, (int)(((float)k + 0.5f) / 1000.0f * (float)es->lights));
        assert_true(light_nee_pmf(es, v3(3.0f, 2.0f, 1.0f), v3(0, 1, 0), ls.light) == 1.0f / (float)es->lights);
        seen++;
    }
    assert_true(seen > 900);
    scene_destroy(s);
}

/* The scene files' setting: pbrt-v4's Integrator "lightsampler" and JSON's
 * integrator.light_sampler, with located errors for unknown names. */
static void test_scene_file_setting(void **state)
{
    (void)state;
    static const char pbrt[] = "Integrator \"path\" \"string lightsampler\" \"%s\"\n"
                               "WorldBegin\nLightSource \"point\" \"rgb I\" [1 1 1]\n"
                               "Shape \"sphere\" \"float radius\" 0.5\n";
    static const char json[] = "{\"camera\": {\"position\": [0, 0, -5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                               " \"integrator\": {\"type\": \"path\", \"light_sampler\": \"%s\"},\n"
                               " \"lights\": [{\"type\": \"point\", \"position\": [0, 1, 0], "
                               "\"intensity\": [1, 1, 1]}],\n"
                               " \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"
                               " \"shapes\": [{\"type\": \"sphere\", \"material\": \"m\", \"center\": [0, 0, 0], "
                               "\"radius\": 0.5}]}";
    const char *names[] = {"uniform", "bvh", "power"};
    const LightSelect sel[] = {LIGHT_SELECT_UNIFORM, LIGHT_SELECT_BVH, LIGHT_SELECT_POWER};
    char text[512];
    for (int k = 0; k < 3; k++) {
        CstError err;
        CstScene *sc = NULL;
        snprintf(text, sizeof text, pbrt, names[k]);
        if (cst_scene_load_pbrt_string(text, strlen(text), "t.pbrt", NULL, &sc, &err) != CST_OK) fail_msg("%s", err.msg);
        assert_int_equal(((Scene *)sc)->emitter_sampler.nee, sel[k]);
        CstSceneInfo in;
        cst_scene_info(sc, &in);
        assert_string_equal(in.light_sampler, names[k]);
        cst_scene_destroy(sc);
        snprintf(text, sizeof text, json, names[k]);
        CstStatus st = cst_scene_load_json_string(text, strlen(text), "t.json", &sc, &err);
        if (st != CST_OK) fail_msg("%s", err.msg);
        assert_int_equal(((Scene *)sc)->emitter_sampler.nee, sel[k]);
        cst_scene_destroy(sc);
    }
    CstError err;
    CstScene *sc = NULL;
    snprintf(text, sizeof text, pbrt, "bogus");
    assert_int_equal(cst_scene_load_pbrt_string(text, strlen(text), "t.pbrt", NULL, &sc, &err), CST_ERR_INVALID_ARG);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "t.pbrt:1:"));
    assert_non_null(strstr(err.msg, "lightsampler"));
    snprintf(text, sizeof text, json, "bogus");
    assert_int_not_equal(cst_scene_load_json_string(text, strlen(text), "t.json", &sc, &err), CST_OK);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "t.json:2:"));
    assert_non_null(strstr(err.msg, "light sampler"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bvh_choice_chi2),
        cmocka_unit_test(test_bvh_nee_densities),
        cmocka_unit_test(test_selection_rule),
        cmocka_unit_test(test_scene_file_setting),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
