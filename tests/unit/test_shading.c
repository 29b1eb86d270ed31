/* Shading normals: their interpolation at hits (scene.h), smooth vs flat meshes from the
 * JSON loader, and the BSDF's convention with a shading normal (bsdf_init_shading): the
 * geometric side test, the adjoint correction (Veach thesis eq. 5.19) and the agreement of
 * sample, eval and pdf in both transports. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <string.h>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "scene/scene.h"

static void assert_vec_near(Vec3 a, Vec3 b, float tol)
{
    if (!(fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol))
        fail_msg("(%.7f, %.7f, %.7f) vs (%.7f, %.7f, %.7f)", (double)a.x, (double)a.y, (double)a.z, (double)b.x,
                 (double)b.y, (double)b.z);
}

static bool vec_equal(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* The triangle (0,0,0), (1,0,0), (0,1,0) (ng = +z) with vertex normals n (or none), and a
 * sphere beside it; committed. */
static Scene *one_triangle(const Vec3 *n)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Vec3 pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    int idx[3] = {0, 1, 2};
    SceneMesh sm = {0};
    sm.positions = pos;
    sm.num_vertices = 3;
    sm.normals = n;
    sm.indices = idx;
    sm.num_triangles = 1;
    sm.material = mat;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(5, 0, 0), 1.0f, mat, NULL, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* The hit of the ray down the z axis through (x, y). */
static SurfaceHit hit_at(const Scene *s, float x, float y)
{
    SurfaceHit sh;
    Ray r = ray_make(v3(x, y, 1.0f), v3(0, 0, -1), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    return sh;
}

/* At barycentrics (u, v) = (0.2, 0.3) of v1 and v2 the shading normal is the normalised
 * 0.5 n0 + 0.2 n1 + 0.3 n2 (Phong), and at a vertex that vertex's normal. */
static void test_interpolation(void **state)
{
    (void)state;
    Vec3 n[3] = {v3(0, 0, 1), v3_normalize(v3(1, 0, 1)), v3_normalize(v3(0, 1, 2))};
    Scene *s = one_triangle(n);
    SurfaceHit sh = hit_at(s, 0.2f, 0.3f);
    assert_vec_near(sh.ng, v3(0, 0, 1), 0.0f);
    Vec3 expect = v3_normalize(v3_add(v3_add(v3_scale(n[0], 0.5f), v3_scale(n[1], 0.2f)), v3_scale(n[2], 0.3f)));
    assert_vec_near(sh.ns, expect, 1e-6f);
    assert_vec_near(hit_at(s, 1e-6f, 1e-6f).ns, n[0], 1e-5f);
    assert_vec_near(hit_at(s, 0.999998f, 1e-6f).ns, n[1], 1e-5f);
    /* The sphere has no vertex normals: ns = ng. */
    SurfaceHit sp;
    Ray r = ray_make(v3(5.3f, 0.2f, 5.0f), v3(0, 0, -1), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sp));
    assert_true(vec_equal(sp.ns, sp.ng));
    /* The BSDF's frame is the shading normal's, its ng the geometric one. */
    Bsdf b;
    scene_bsdf(s, &sh, NULL, &b);
    assert_true(vec_equal(b.frame.n, sh.ns) && vec_equal(b.ng, sh.ng) && b.shading);
    scene_destroy(s);
}

/* Vertex normals pointing away from ng (a mesh wound against its normals) are turned to
 * ng's side; ng is kept. */
static void test_orientation(void **state)
{
    (void)state;
    Vec3 a = v3_normalize(v3(0.3f, 0.0f, -1.0f));
    Vec3 n[3] = {a, a, a};
    Scene *s = one_triangle(n);
    SurfaceHit sh = hit_at(s, 0.25f, 0.25f);
    assert_vec_near(sh.ng, v3(0, 0, 1), 0.0f);
    assert_vec_near(sh.ns, v3_neg(a), 1e-6f);
    scene_destroy(s);
}

/* No normals, or a vertex without one (a zero fill): flat, ns = ng exactly. */
static void test_flat(void **state)
{
    (void)state;
    Scene *s = one_triangle(NULL);
    SurfaceHit sh = hit_at(s, 0.2f, 0.3f);
    assert_true(vec_equal(sh.ns, sh.ng));
    Bsdf b;
    scene_bsdf(s, &sh, NULL, &b);
    assert_false(b.shading);
    scene_destroy(s);
    Vec3 n[3] = {v3(0, 0, 1), v3(0, 0, 0), v3_normalize(v3(0, 1, 2))};
    s = one_triangle(n);
    sh = hit_at(s, 0.2f, 0.3f);
    assert_true(vec_equal(sh.ns, sh.ng));
    scene_destroy(s);
}

/* An instanced triangle with vertex normals under a non-uniform scale: ns is the
 * object-space interpolation carried by the normal matrix (the inverse transpose), not by
 * the transform itself; without normals ns = ng. */
static void test_instance(void **state)
{
    (void)state;
    for (int with = 0; with < 2; with++) {
        CstError err;
        Scene *s = scene_create();
        assert_non_null(s);
        int mat, proto;
        Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
        assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
        Vec3 pos[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
        Vec3 n[3] = {v3(0, 0, 1), v3_normalize(v3(1, 0, 1)), v3_normalize(v3(0, 1, 2))};
        int idx[3] = {0, 1, 2}, tm[1] = {mat};
        assert_int_equal(scene_add_instance_proto(s, pos, with ? n : NULL, 3, idx, tm, 1, &proto, &err), CST_OK);
        Transform xf = transform_compose(transform_translate(v3(0, 0, -2)), transform_scale(v3(3, 1, 1)));
        assert_int_equal(scene_add_instance(s, proto, &xf, &err), CST_OK);
        assert_int_equal(scene_commit(s, &err), CST_OK);
        /* object point (0.2, 0.3, 0) is world (0.6, 0.3, -2) */
        SurfaceHit sh;
        Ray r = ray_make(v3(0.6f, 0.3f, 1.0f), v3(0, 0, -1), 0.0f, INFINITY);
        assert_true(scene_intersect(s, &r, &sh));
        assert_vec_near(sh.p, v3(0.6f, 0.3f, -2.0f), 1e-5f);
        if (!with) {
            assert_true(vec_equal(sh.ns, sh.ng));
        } else {
            Vec3 o = v3_add(v3_add(v3_scale(n[0], 0.5f), v3_scale(n[1], 0.2f)), v3_scale(n[2], 0.3f));
            Vec3 expect = v3_normalize(v3(o.x / 3.0f, o.y, o.z)); /* inverse transpose of diag(3, 1, 1) */
            assert_vec_near(sh.ns, expect, 1e-5f);
        }
        scene_destroy(s);
    }
}

static const char *mesh_json(const char *extra, char *buf, size_t size)
{
    snprintf(buf, size,
             "{\"camera\": {\"position\": [0.2, 0.3, 3], \"look_at\": [0.2, 0.3, 0], \"fov\": 30},\n"
             " \"materials\": {\"m\": {\"type\": \"diffuse\"}},\n"
             " \"shapes\": [{\"type\": \"mesh\", \"material\": \"m\",\n"
             "   \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"indices\": [[0, 1, 2]]%s}]}",
             extra);
    return buf;
}

/* "normals" on an inline mesh shade smoothly unless "shading" is "flat". */
static void test_json_smooth_and_flat(void **state)
{
    (void)state;
    char text[1024];
    const char *normals = ",\n   \"normals\": [[0, 0, 1], [2, 0, 2], [0, 0.1, 0.2]]";
    CstError err;
    const char *variants[3] = {"", ", \"shading\": \"smooth\"", ", \"shading\": \"flat\""};
    for (int k = 0; k < 3; k++) {
        char extra[256];
        snprintf(extra, sizeof extra, "%s%s", normals, variants[k]);
        mesh_json(extra, text, sizeof text);
        CstScene *s = NULL;
        if (cst_scene_load_json_string(text, strlen(text), "mesh.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
        SurfaceHit sh = hit_at(s, 0.2f, 0.3f);
        if (k < 2) {
            Vec3 expect = v3_normalize(v3_add(v3_add(v3_scale(v3(0, 0, 1), 0.5f), v3_scale(v3_normalize(v3(1, 0, 1)), 0.2f)),
                                              v3_scale(v3_normalize(v3(0, 1, 2)), 0.3f)));
            assert_vec_near(sh.ns, expect, 1e-6f);
        } else {
            assert_true(vec_equal(sh.ns, sh.ng));
        }
        cst_scene_destroy(s);
    }
}

static void expect_error(const char *extra, const char *where, const char *what)
{
    char text[1024];
    mesh_json(extra, text, sizeof text);
    CstScene *s = NULL;
    CstError err;
    CstStatus st = cst_scene_load_json_string(text, strlen(text), "mesh.json", &s, &err);
    if (st == CST_OK) fail_msg("accepted: %s", text);
    if (!strstr(err.msg, where) || !strstr(err.msg, what))
        fail_msg("message \"%s\" lacks \"%s\" or \"%s\"", err.msg, where, what);
}

static void test_json_errors(void **state)
{
    (void)state;
    expect_error(", \"shading\": \"phong\"", "mesh.json:4:", "expected one of: smooth, flat");
    expect_error(", \"shading\": 1", "mesh.json:4:", "shading");
    expect_error(", \"normals\": [[0, 0, 1], [0, 0, 1]]", "mesh.json:4:", "3 normals");
    expect_error(", \"normals\": [[0, 0, 1], [0, 0, 0], [0, 0, 1]]", "shapes[0].normals[1]", "zero");
}

/* ------------------------------------------------------------------ the BSDF */

static Vec3 random_dir(Pcg32 *rng)
{
    float z = 1.0f - 2.0f * pcg32_float(rng), phi = 2.0f * CST_PI * pcg32_float(rng);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(r * cosf(phi), r * sinf(phi), z);
}

static Material material(MaterialType t, float roughness)
{
    Material m = {.type = t, .albedo = {{0.8f, 0.6f, 0.4f}}, .ior = 1.5f, .roughness = roughness};
    if (t == MATERIAL_CONDUCTOR) assert_true(material_metal("gold", &m.eta, &m.k));
    material_prepare(&m);
    return m;
}

#define NMAT 6
static Material test_material(int i)
{
    static const MaterialType type[NMAT] = {MATERIAL_DIFFUSE, MATERIAL_CONDUCTOR, MATERIAL_DIELECTRIC,
                                           MATERIAL_PLASTIC, MATERIAL_GLASS, MATERIAL_MIRROR};
    static const float rough[NMAT] = {0.0f, 0.4f, 0.4f, 0.3f, 0.0f, 0.0f};
    return material(type[i], rough[i]);
}

static bool rgb_near(Color a, Color b, float rel)
{
    float s = fmaxf(color_max(a), color_max(b));
    return fabsf(a.c[0] - b.c[0]) <= rel * s && fabsf(a.c[1] - b.c[1]) <= rel * s && fabsf(a.c[2] - b.c[2]) <= rel * s;
}

/* With ns = ng the factor is 1 and bsdf_init_shading is bsdf_init, bit for bit. */
static void test_adjoint_is_one_without_shading(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed_sample(&rng, 1, 0, 0);
    for (int i = 0; i < NMAT; i++) {
        Material m = test_material(i);
        for (int k = 0; k < 200; k++) {
            Vec3 n = random_dir(&rng), wo = random_dir(&rng), wi = random_dir(&rng);
            Bsdf a, b;
            bsdf_init(&a, &m, n);
            bsdf_init_shading(&b, &m, n, n);
            assert_false(b.shading);
            float f = bsdf_shading_adjoint(&b, wo, wi);
            if (!(fabsf(f - 1.0f) <= 1e-6f)) fail_msg("adjoint factor %.9f with ns = ng", (double)f);
            for (int mode = 0; mode < 2; mode++) {
                Color fa = bsdf_eval_transport(&a, wo, wi, (BsdfTransport)mode);
                Color fb = bsdf_eval_transport(&b, wo, wi, (BsdfTransport)mode);
                assert_true(fa.c[0] == fb.c[0] && fa.c[1] == fb.c[1] && fa.c[2] == fb.c[2]);
            }
            assert_true(bsdf_pdf(&a, wo, wi) == bsdf_pdf(&b, wo, wi));
        }
    }
}

/* The factor's value: |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|). */
static void test_adjoint_value(void **state)
{
    (void)state;
    Material m = test_material(0);
    Bsdf b;
    Vec3 ng = v3(0, 0, 1), ns = v3_normalize(v3(0.5f, 0.0f, 1.0f));
    bsdf_init_shading(&b, &m, ns, ng);
    Vec3 wo = v3_normalize(v3(1, 0, 1)), wi = v3_normalize(v3(-1, 0.5f, 2));
    double expect = fabs((double)v3_dot(wo, ns) * (double)v3_dot(wi, ng)) /
                    fabs((double)v3_dot(wo, ng) * (double)v3_dot(wi, ns));
    assert_true(fabs((double)bsdf_shading_adjoint(&b, wo, wi) - expect) <= 1e-6 * expect);
    /* wo in ng's tangent plane: no value rather than an infinity. */
    assert_true(bsdf_shading_adjoint(&b, v3(0, 1, 0), wi) == 0.0f);
}

/* With a leaning shading normal: (1) no pair on which ng and the shading frame disagree
 * (reflection vs transmission) has a value, so nothing leaks through; (2) the importance
 * BSDF is the radiance one swapped, with geometric cosines: f_imp(wo, wi) =
 * f_rad(wi, wo) |wi.ng| / |wo.ng| (the adjoint of Veach's eq. 5.17 BSDF); (3) every sample
 * lies on an allowed side, with pdf = bsdf_pdf and, for non-delta lobes, weight =
 * eval / pdf in its transport. */
static void test_convention(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed_sample(&rng, 2, 0, 0);
    const Vec3 ng = v3_normalize(v3(0.2f, -0.3f, 1.0f));
    int leaks_checked = 0, samples = 0;
    for (int i = 0; i < NMAT; i++) {
        Material m = test_material(i);
        const bool transmits = m.type == MATERIAL_DIELECTRIC || m.type == MATERIAL_GLASS;
        for (int k = 0; k < 400; k++) {
            /* ns within 35 degrees of ng */
            Vec3 ns;
            do ns = v3_normalize(v3_add(ng, v3_scale(random_dir(&rng), 0.6f)));
            while (!(v3_dot(ns, ng) > cosf(35.0f * CST_PI / 180.0f)));
            Bsdf b;
            bsdf_init_shading(&b, &m, ns, ng);
            assert_true(b.shading);
            Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
            float go = v3_dot(wo, ng), gi = v3_dot(wi, ng), so = v3_dot(wo, ns), si = v3_dot(wi, ns);
            Color fr = bsdf_eval_transport(&b, wo, wi, BSDF_RADIANCE);
            Color fi = bsdf_eval_transport(&b, wo, wi, BSDF_IMPORTANCE);
            if ((go * gi > 0.0f) != (so * si > 0.0f)) {
                leaks_checked++;
                assert_true(color_is_black(fr) && color_is_black(fi) && bsdf_pdf(&b, wo, wi) == 0.0f);
            }
            if (!transmits && go * gi < 0.0f) assert_true(color_is_black(fr) && color_is_black(fi));
            Color swapped = color_scale(bsdf_eval_transport(&b, wi, wo, BSDF_RADIANCE), fabsf(gi) / fabsf(go));
            if (!rgb_near(fi, swapped, 1e-4f))
                fail_msg("material %d: importance (%g) vs swapped radiance (%g)", i, (double)fi.c[0], (double)swapped.c[0]);
            for (int mode = 0; mode < 2; mode++) {
                BsdfSample bs;
                float uc = pcg32_float(&rng);
                Vec2 u = pcg32_v2(&rng);
                if (!bsdf_sample_transport(&b, wo, uc, u, (BsdfTransport)mode, &bs)) continue;
                samples++;
                float gs = v3_dot(bs.wi, ng), ss = v3_dot(bs.wi, ns);
                assert_true((go * gs > 0.0f) == (so * ss > 0.0f));
                if (!transmits) assert_true(go * gs > 0.0f);
                if (bs.delta) continue;
                float pdf = bsdf_pdf(&b, wo, bs.wi);
                if (!(fabsf(pdf - bs.pdf_w) <= 1e-3f * pdf)) fail_msg("material %d: pdf %g vs %g", i, (double)bs.pdf_w, (double)pdf);
                Color f = color_scale(bsdf_eval_transport(&b, wo, bs.wi, (BsdfTransport)mode), 1.0f / bs.pdf_w);
                if (!rgb_near(f, bs.weight, 2e-3f))
                    fail_msg("material %d mode %d: weight %g vs eval/pdf %g", i, mode, (double)bs.weight.c[0], (double)f.c[0]);
            }
        }
    }
    print_message("%d disagreeing pairs checked, %d samples\n", leaks_checked, samples);
    assert_true(leaks_checked > 100 && samples > 2000);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_interpolation),
        cmocka_unit_test(test_orientation),
        cmocka_unit_test(test_flat),
        cmocka_unit_test(test_instance),
        cmocka_unit_test(test_json_smooth_and_flat),
        cmocka_unit_test(test_json_errors),
        cmocka_unit_test(test_adjoint_is_one_without_shading),
        cmocka_unit_test(test_adjoint_value),
        cmocka_unit_test(test_convention),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
