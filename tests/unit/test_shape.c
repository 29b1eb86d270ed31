/* Analytic shapes (geometry/shape.h): hits, uv and normals against closed forms for the
 * cylinder, the disk with a hole and the partial sphere; clipping in z and phi; transforms
 * (scale, mirror, reverse orientation); dp/du and dp/dv against finite differences of the
 * parameterisation; spawned rays never re-hit their shape near the start; area sampling
 * uniform by area (the disk's annulus split in two by area, within 4 standard errors); the
 * JSON loader's "cylinder", "disk" and partial spheres. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>

#include <string.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "scene/scene.h"
#include "geometry/shape.h"
#include "math/transform.h"

static AnalyticShape make(ShapeTag type, float r, float z0, float z1, float h, float ri, float phi_max, bool rev,
                          Transform m)
{
    ShapeParams p = {type, r, z0, z1, h, ri, phi_max, rev, 0.0f};
    AnalyticShape s;
    assert_true(shape_init(&s, &p, &m));
    return s;
}

static bool hit(const AnalyticShape *s, Vec3 o, Vec3 d, float *t, float *u, float *v)
{
    Ray r = ray_make(o, d, 0.0f, INFINITY);
    return shape_intersect(s, &r, t, u, v);
}

static void near3(Vec3 a, Vec3 b, float eps)
{
    if (!(fabsf(a.x - b.x) <= eps && fabsf(a.y - b.y) <= eps && fabsf(a.z - b.z) <= eps))
        fail_msg("(%g %g %g) != (%g %g %g)", (double)a.x, (double)a.y, (double)a.z, (double)b.x, (double)b.y,
                 (double)b.z);
}

static void test_cylinder(void **state)
{
    (void)state;
    const float PI = CST_PI;
    AnalyticShape c = make(SHAPE_TAG_CYLINDER, 2.0f, -1.0f, 3.0f, 0.0f, 0.0f, 2.0f * PI, false, transform_identity());
    float t, u, v;
    assert_true(hit(&c, v3(5.0f, 0.0f, 1.0f), v3(-1.0f, 0.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 3.0f, 1e-6f);
    assert_float_equal(u, 0.0f, 1e-6f);
    assert_float_equal(v, 0.5f, 1e-6f);
    Ray r = ray_make(v3(5.0f, 0.0f, 1.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    ShapeSurface sf;
    shape_surface(&c, &r, t, &sf);
    near3(sf.p, v3(2.0f, 0.0f, 1.0f), 1e-6f);
    near3(sf.n, v3(1.0f, 0.0f, 0.0f), 1e-6f);
    near3(sf.dpdu, v3(0.0f, 2.0f * 2.0f * PI, 0.0f), 1e-4f); /* (-phi_max y, phi_max x, 0) */
    near3(sf.dpdv, v3(0.0f, 0.0f, 4.0f), 1e-6f);
    /* From inside: the far wall; along the axis: nothing; above the top: nothing. */
    assert_true(hit(&c, v3(0.0f, 0.0f, 1.0f), v3(0.0f, 1.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 2.0f, 1e-6f);
    assert_float_equal(u, 0.25f, 1e-6f);
    assert_false(hit(&c, v3(0.0f, 0.0f, -5.0f), v3(0.0f, 0.0f, 1.0f), &t, &u, &v));
    assert_false(hit(&c, v3(5.0f, 0.0f, 3.5f), v3(-1.0f, 0.0f, 0.0f), &t, &u, &v));
    /* phi_max = pi/2: the near wall at phi ~ pi is cut away, the far one at phi ~ 0.05 stays. */
    AnalyticShape q = make(SHAPE_TAG_CYLINDER, 2.0f, -1.0f, 3.0f, 0.0f, 0.0f, 0.5f * PI, false, transform_identity());
    assert_true(hit(&q, v3(-5.0f, 0.1f, 1.0f), v3(1.0f, 0.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 5.0f + sqrtf(4.0f - 0.01f), 1e-5f);
    /* Uniform scale 3 and a translation: t scales, the normal does not. */
    Transform m = transform_compose(transform_translate(v3(10.0f, 0.0f, 0.0f)), transform_scale(v3s(3.0f)));
    AnalyticShape cs = make(SHAPE_TAG_CYLINDER, 2.0f, -1.0f, 3.0f, 0.0f, 0.0f, 2.0f * PI, false, m);
    assert_true(hit(&cs, v3(30.0f, 0.0f, 3.0f), v3(-1.0f, 0.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 14.0f, 1e-5f);
    assert_float_equal(shape_area(&cs), 9.0f * 2.0f * PI * 2.0f * 4.0f, 1e-2f);
    /* Mirrored: pbrt-v4 flips n for a handedness swap; reverse orientation flips it back. */
    Transform mir = transform_scale(v3(1.0f, 1.0f, -1.0f));
    AnalyticShape cm = make(SHAPE_TAG_CYLINDER, 2.0f, -1.0f, 3.0f, 0.0f, 0.0f, 2.0f * PI, false, mir);
    AnalyticShape cr = make(SHAPE_TAG_CYLINDER, 2.0f, -1.0f, 3.0f, 0.0f, 0.0f, 2.0f * PI, true, mir);
    r = ray_make(v3(5.0f, 0.0f, -1.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    assert_true(shape_intersect(&cm, &r, &t, &u, &v));
    shape_surface(&cm, &r, t, &sf);
    near3(sf.n, v3(-1.0f, 0.0f, 0.0f), 1e-6f);
    shape_surface(&cr, &r, t, &sf);
    near3(sf.n, v3(1.0f, 0.0f, 0.0f), 1e-6f);
}

static void test_disk(void **state)
{
    (void)state;
    AnalyticShape d = make(SHAPE_TAG_DISK, 2.0f, 0.0f, 0.0f, 1.0f, 0.5f, 2.0f * CST_PI, false, transform_identity());
    float t, u, v;
    assert_true(hit(&d, v3(1.0f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), &t, &u, &v));
    assert_float_equal(t, 4.0f, 1e-6f);
    assert_float_equal(v, 2.0f / 3.0f, 1e-6f); /* (r - rho) / (r - ri) */
    assert_false(hit(&d, v3(0.2f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), &t, &u, &v)); /* the hole */
    assert_false(hit(&d, v3(2.1f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), &t, &u, &v));
    assert_false(hit(&d, v3(1.0f, 0.0f, 5.0f), v3(1.0f, 0.0f, 0.0f), &t, &u, &v)); /* parallel */
    Ray r = ray_make(v3(0.0f, 1.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(shape_intersect(&d, &r, &t, &u, &v));
    assert_float_equal(u, 0.25f, 1e-6f);
    ShapeSurface sf;
    shape_surface(&d, &r, t, &sf);
    near3(sf.p, v3(0.0f, 1.0f, 1.0f), 1e-6f);
    near3(sf.n, v3(0.0f, 0.0f, 1.0f), 0.0f);
    AnalyticShape dr = make(SHAPE_TAG_DISK, 2.0f, 0.0f, 0.0f, 1.0f, 0.5f, 2.0f * CST_PI, true, transform_identity());
    shape_surface(&dr, &r, t, &sf);
    near3(sf.n, v3(0.0f, 0.0f, -1.0f), 0.0f);
    assert_float_equal(shape_area(&d), CST_PI * (4.0f - 0.25f), 1e-5f);
    /* Uniform by area: the share of samples inside rho^2 < (r^2 + ri^2) / 2 is one half. */
    Pcg32 rng;
    pcg32_seed(&rng, 7u, 1u);
    const int N = 200000;
    int inner = 0;
    for (int i = 0; i < N; i++) {
        float u0 = pcg32_float(&rng), u1 = pcg32_float(&rng), pdf;
        shape_sample_area(&d, v2(u0, u1), &sf, &pdf);
        assert_float_equal(pdf, 1.0f / shape_area(&d), 1e-6f);
        assert_float_equal(sf.p.z, 1.0f, 0.0f);
        float rho2 = sf.p.x * sf.p.x + sf.p.y * sf.p.y;
        assert_true(rho2 >= 0.25f * (1.0f - 1e-6f) && rho2 <= 4.0f * (1.0f + 1e-6f));
        inner += rho2 < 0.5f * (4.0f + 0.25f);
    }
    double se = sqrt(0.25 / N);
    assert_true(fabs((double)inner / N - 0.5) < 4.0 * se);
}

static void test_partial_sphere(void **state)
{
    (void)state;
    AnalyticShape s = make(SHAPE_TAG_SPHERE, 1.0f, -0.5f, 0.5f, 0.0f, 0.0f, 2.0f * CST_PI, false, transform_identity());
    float t, u, v;
    assert_false(hit(&s, v3(0.0f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), &t, &u, &v)); /* both poles cut */
    assert_true(hit(&s, v3(5.0f, 0.0f, 0.0f), v3(-1.0f, 0.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 4.0f, 1e-6f);
    assert_float_equal(v, 0.5f, 1e-6f);
    /* A ray through the cut top enters and meets the inside of the band. */
    Vec3 o = v3(0.0f, 0.0f, 5.0f), d = v3_normalize(v3(0.9f, 0.0f, -5.0f));
    assert_true(hit(&s, o, d, &t, &u, &v));
    Vec3 p = v3_madd(o, d, t);
    assert_true(p.z <= 0.5f && p.z >= -0.5f);
    assert_float_equal(v3_length(p), 1.0f, 1e-5f);
    assert_float_equal(shape_area(&s), 2.0f * CST_PI * 1.0f, 1e-5f); /* Archimedes: 2 pi r (z1 - z0) */
    /* phi_max = pi: the half with y >= 0. */
    AnalyticShape h = make(SHAPE_TAG_SPHERE, 1.0f, -1.0f, 1.0f, 0.0f, 0.0f, CST_PI, false, transform_identity());
    assert_true(hit(&h, v3(0.0f, 5.0f, 0.0f), v3(0.0f, -1.0f, 0.0f), &t, &u, &v));
    assert_float_equal(t, 4.0f, 1e-6f);
    assert_true(hit(&h, v3(0.0f, -5.0f, 0.0f), v3(0.0f, 1.0f, 0.0f), &t, &u, &v)); /* the inside of y > 0 */
    assert_float_equal(t, 6.0f, 1e-6f);
}

/* Every shape kind under a random rotation, translation and (sometimes non-uniform) scale:
 * points shape_surface_at gives are found by rays aimed at them, where shape_surface gives
 * the same point, uv, normal and derivatives; dp/du and dp/dv match central differences;
 * a ray leaving the point by the spawn offset never meets the shape within 1e-4 of the
 * shape's size. */
static void test_random_transforms(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 99u, 3u);
    long spawned = 0, rehits = 0, dn_checked = 0;
    for (int k = 0; k < 300; k++) {
        ShapeTag type = (ShapeTag)(k % 3);
        float phi_max = (k / 3) % 2 ? 2.0f * CST_PI : 1.0f + 4.0f * pcg32_float(&rng);
        float ri = type == SHAPE_TAG_DISK && (k / 6) % 2 ? 0.3f : 0.0f;
        AnalyticShape s;
        ShapeParams p = {type, 1.0f, -0.6f, 0.7f, 0.2f, ri, phi_max, (k / 12) % 2 == 1, 0.0f};
        float ax = pcg32_float(&rng), ay = pcg32_float(&rng), az = pcg32_float(&rng), ang = 6.0f * pcg32_float(&rng);
        Transform m = transform_rotate(v3(ax - 0.5f, ay - 0.5f, az - 0.5f + 1e-3f), ang);
        if (k % 4 == 0) m = transform_compose(m, transform_scale(v3(0.5f, 2.0f, 1.5f)));
        if (k % 5 == 0) m = transform_compose(m, transform_scale(v3(-1.0f, 1.0f, 1.0f)));
        m = transform_compose(transform_translate(v3(3.0f, -2.0f, 7.0f)), m);
        assert_true(shape_init(&s, &p, &m));
        for (int i = 0; i < 50; i++) {
            Vec2 uv = v2(0.02f + 0.96f * pcg32_float(&rng), 0.02f + 0.96f * pcg32_float(&rng));
            ShapeSurface a, b;
            shape_surface_at(&s, uv, &a);
            float h = 1e-3f;
            ShapeSurface up, um, vp, vm;
            shape_surface_at(&s, v2(uv.x + h, uv.y), &up);
            shape_surface_at(&s, v2(uv.x - h, uv.y), &um);
            shape_surface_at(&s, v2(uv.x, uv.y + h), &vp);
            shape_surface_at(&s, v2(uv.x, uv.y - h), &vm);
            float scale = 1e-2f * (1.0f + v3_length(a.dpdu) + v3_length(a.dpdv));
            near3(v3_scale(v3_sub(up.p, um.p), 0.5f / h), a.dpdu, scale);
            near3(v3_scale(v3_sub(vp.p, vm.p), 0.5f / h), a.dpdv, scale);
            /* n is cross(dp/du, dp/dv) up to pbrt's flips. */
            Vec3 c = v3_normalize(v3_cross(a.dpdu, a.dpdv));
            bool flip = s.flip_normal != (transform_det(&m) < 0.0);
            near3(flip ? v3_neg(c) : c, a.n, 1e-3f);
            /* dn/du, dn/dv of the outward normal (pbrt-v4's, unflipped) against central
             * differences; under a non-uniform scale pbrt-v4's (the object's, mapped as a
             * normal) is not the world normal's derivative, so only rigid maps here. */
            if (k % 4 != 0) {
                Vec3 dndu, dndv;
                assert_true(shape_dnduv(&s, uv, &dndu, &dndv));
                float sg = s.flip_normal ? -1.0f : 1.0f;
                float nscale = 1e-2f * (1.0f + v3_length(dndu) + v3_length(dndv));
                near3(v3_scale(v3_sub(up.n, um.n), 0.5f * sg / h), dndu, nscale);
                near3(v3_scale(v3_sub(vp.n, vm.n), 0.5f * sg / h), dndv, nscale);
                dn_checked++;
            }
            /* A ray from outside aimed at the point. */
            Vec3 dir = v3_normalize(v3_add(v3_neg(a.n), v3_scale(v3(pcg32_float(&rng), pcg32_float(&rng), 0.3f), 0.5f)));
            if (v3_dot(dir, a.n) > 0.0f) dir = v3_neg(dir);
            Ray r = ray_make(v3_madd(a.p, dir, -5.0f), dir, 0.0f, INFINITY);
            float t, u, v;
            assert_true(shape_intersect(&s, &r, &t, &u, &v));
            if (t > 5.0f - 1e-3f) { /* nothing in front of the aimed point: it is the hit */
                shape_surface(&s, &r, t, &b);
                near3(b.p, a.p, 1e-4f);
                assert_float_equal(b.uv.x, uv.x, 1e-3f);
                assert_float_equal(b.uv.y, uv.y, 1e-3f);
                near3(b.n, a.n, 1e-3f);
                /* Spawn to both sides, random directions. */
                for (int j = 0; j < 20; j++) {
                    Vec3 w = v3_normalize(v3(pcg32_float(&rng) - 0.5f, pcg32_float(&rng) - 0.5f, pcg32_float(&rng) - 0.5f));
                    Vec3 n = v3_dot(w, b.n) >= 0.0f ? b.n : v3_neg(b.n);
                    Ray sr = ray_make(ray_offset_origin(b.p, n, RAY_OFFSET_NEAR_MIN), w, 0.0f, 1e-4f);
                    spawned++;
                    rehits += shape_intersect(&s, &sr, &t, &u, &v);
                }
            }
        }
    }
    print_message("  spawned %ld rays off shapes, %ld re-hit within 1e-4\n", spawned, rehits);
    assert_true(dn_checked > 10000);
    assert_true(spawned > 100000);
    assert_int_equal(rehits, 0);
}

/* The torus's dn/du, dn/dv (shape_dnduv) against central differences of its normal, under
 * a rotation and translation. */
static void test_torus_dndu(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 7u, 1u);
    ShapeParams p = {SHAPE_TAG_TORUS, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 2.0f * CST_PI, false, 0.3f};
    Transform m = transform_compose(transform_translate(v3(1.0f, 2.0f, -3.0f)), transform_rotate(v3(1.0f, 0.5f, 0.2f), 1.1f));
    AnalyticShape s;
    assert_true(shape_init(&s, &p, &m));
    for (int i = 0; i < 200; i++) {
        Vec2 uv = v2(0.02f + 0.96f * pcg32_float(&rng), 0.02f + 0.96f * pcg32_float(&rng));
        const float h = 1e-3f;
        ShapeSurface up, um, vp, vm;
        shape_surface_at(&s, v2(uv.x + h, uv.y), &up);
        shape_surface_at(&s, v2(uv.x - h, uv.y), &um);
        shape_surface_at(&s, v2(uv.x, uv.y + h), &vp);
        shape_surface_at(&s, v2(uv.x, uv.y - h), &vm);
        Vec3 dndu, dndv;
        assert_true(shape_dnduv(&s, uv, &dndu, &dndv));
        float nscale = 1e-2f * (1.0f + v3_length(dndu) + v3_length(dndv));
        near3(v3_scale(v3_sub(up.n, um.n), 0.5f / h), dndu, nscale);
        near3(v3_scale(v3_sub(vp.n, vm.n), 0.5f / h), dndv, nscale);
    }
}

/* The JSON loader: "cylinder", "disk" and a "sphere" with "z_min"/"z_max"/"phi_max" are
 * analytic shapes; an emitting one is a located error (not supported yet), as is a key of
 * the other kind. */
#define JSON_SCENE(shapes) "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}, " \
    "\"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}}, \"shapes\": [" shapes "]}"
static CstStatus load_json(const char *text, CstScene **out, CstError *err)
{
    return cst_scene_load_json_string(text, strlen(text), "t.json", out, err);
}

static void test_json_shapes(void **state)
{
    (void)state;
    CstScene *scene = NULL;
    CstError err = {0};
    if (load_json(JSON_SCENE(
            "{\"type\": \"cylinder\", \"material\": \"white\", \"radius\": 0.5, \"z_min\": 0, \"z_max\": 2, "
            "\"phi_max\": 270, \"transform\": {\"translate\": [1, 0, 0]}}, "
            "{\"type\": \"disk\", \"material\": \"white\", \"radius\": 2, \"inner_radius\": 0.5, \"height\": 1, "
            "\"reverse_orientation\": true}, "
            "{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 3, 0], \"radius\": 1, \"z_max\": 0.5}"),
                  &scene, &err) != CST_OK)
        fail_msg("%s", err.msg);
    const Scene *s = scene;
    assert_int_equal(s->num_shapes, 3);
    assert_int_equal(s->shapes[0].p.type, SHAPE_TAG_CYLINDER);
    assert_true(s->shapes[0].p.z_max == 2.0f && s->shapes[0].bounds.min.x > 0.4f);
    assert_int_equal(s->shapes[1].p.type, SHAPE_TAG_DISK);
    assert_true(s->shapes[1].p.inner_radius == 0.5f && s->shapes[1].flip_normal);
    assert_int_equal(s->shapes[2].p.type, SHAPE_TAG_SPHERE);
    assert_true(s->shapes[2].p.z_min == -1.0f && s->shapes[2].p.z_max == 0.5f && s->shapes[2].bounds.min.y > 1.9f);
    CstSceneInfo info;
    cst_scene_info(scene, &info);
    assert_int_equal(info.shapes, 3);
    cst_scene_destroy(scene);
    scene = NULL;
    /* an emitting disk is an area light of its own area; a non-uniform scale is refused */
    if (load_json(JSON_SCENE("{\"type\": \"disk\", \"material\": \"white\", \"radius\": 1, "
                             "\"emission\": {\"radiance\": [1, 1, 1]}}"), &scene, &err) != CST_OK)
        fail_msg("%s", err.msg);
    assert_int_equal(((const Scene *)scene)->num_emitters, 1);
    assert_float_equal(((const Scene *)scene)->emitters[0].area, CST_PI, 1e-6f);
    cst_scene_destroy(scene);
    scene = NULL;
    assert_int_equal(load_json(JSON_SCENE("{\"type\": \"disk\", \"material\": \"white\", \"radius\": 1, "
                                          "\"transform\": {\"scale\": [1, 2, 1]}, "
                                          "\"emission\": {\"radiance\": [1, 1, 1]}}"), &scene, &err), CST_ERR_UNSUPPORTED);
    assert_null(scene);
    if (!strstr(err.msg, "t.json:1:") || !strstr(err.msg, "similarity")) fail_msg("%s", err.msg);
    assert_int_equal(load_json(JSON_SCENE("{\"type\": \"cylinder\", \"material\": \"white\", \"radius\": 1, "
                                          "\"height\": 1}"), &scene, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "\"height\"")) fail_msg("%s", err.msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cylinder),
        cmocka_unit_test(test_disk),
        cmocka_unit_test(test_partial_sphere),
        cmocka_unit_test(test_random_transforms),
        cmocka_unit_test(test_torus_dndu),
        cmocka_unit_test(test_json_shapes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
