/* Bilinear patches (geometry/shape.c, SHAPE_TAG_BILINEAR): planar patches hit where their
 * two triangles are hit (same t, same normal) away from the edges; the saddle
 * p(u, v) = (u, v, uv) against its closed form (hit points on z = xy, (u, v) = (x, y),
 * normal (-v, -u, 1) / |.|, t of oblique rays from the quadratic, area against the
 * integral of sqrt(1 + x^2 + y^2)); area sampling's density; the pbrt loader's
 * "bilinearmesh" (patches, N and uv, degenerate patches left out, emitting ones still
 * triangles) and the builder's errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "geometry/shape.h"
#include "geometry/triangle.h"
#include "scene/scene.h"

static double rnd(Pcg32 *r, double lo, double hi) { return lo + (hi - lo) * (double)pcg32_float(r); }
static Vec3 rnd_v3(Pcg32 *r, double lo, double hi)
{
    return v3((float)rnd(r, lo, hi), (float)rnd(r, lo, hi), (float)rnd(r, lo, hi));
}

/* Moller-Trumbore in double: the reference for the two triangles. */
static bool tri_hit(Vec3 a, Vec3 b, Vec3 c, Vec3 o, Vec3 d, double *t, double *bu, double *bv)
{
    double e1[3] = {(double)b.x - (double)a.x, (double)b.y - (double)a.y, (double)b.z - (double)a.z};
    double e2[3] = {(double)c.x - (double)a.x, (double)c.y - (double)a.y, (double)c.z - (double)a.z};
    double dd[3] = {(double)d.x, (double)d.y, (double)d.z};
    double s[3] = {(double)o.x - (double)a.x, (double)o.y - (double)a.y, (double)o.z - (double)a.z};
    double p[3] = {dd[1] * e2[2] - dd[2] * e2[1], dd[2] * e2[0] - dd[0] * e2[2], dd[0] * e2[1] - dd[1] * e2[0]};
    double det = e1[0] * p[0] + e1[1] * p[1] + e1[2] * p[2];
    if (fabs(det) < 1e-300) return false;
    double u = (s[0] * p[0] + s[1] * p[1] + s[2] * p[2]) / det;
    double q[3] = {s[1] * e1[2] - s[2] * e1[1], s[2] * e1[0] - s[0] * e1[2], s[0] * e1[1] - s[1] * e1[0]};
    double v = (dd[0] * q[0] + dd[1] * q[1] + dd[2] * q[2]) / det;
    *t = (e2[0] * q[0] + e2[1] * q[1] + e2[2] * q[2]) / det;
    *bu = u;
    *bv = v;
    return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && *t > 0.0;
}

/* Random convex planar quads (parallelograms and general ones) under random rays: where
 * the triangles are hit at least 1e-4 (in barycentric terms) inside, the patch is hit at
 * the same t (relative 1e-5) with the same normal; where they are missed by that margin,
 * the patch is missed. */
static void test_planar_vs_triangles(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 21u, 5u);
    int hits = 0, misses = 0;
    for (int k = 0; k < 200; k++) {
        Vec3 c = rnd_v3(&rng, -5.0, 5.0), e1 = rnd_v3(&rng, -2.0, 2.0), e2 = rnd_v3(&rng, -2.0, 2.0);
        if (v3_length(v3_cross(e1, e2)) < 0.2f) continue;
        /* p11 = p00 + a e1 + b e2 with a, b > 0.5 keeps the quad convex */
        float a = k % 2 ? 1.0f : (float)rnd(&rng, 0.6, 1.6), b = k % 2 ? 1.0f : (float)rnd(&rng, 0.6, 1.6);
        Vec3 p[4] = {c, v3_add(c, e1), v3_add(c, e2), v3_add(c, v3_add(v3_scale(e1, a), v3_scale(e2, b)))};
        AnalyticShape s;
        assert_true(shape_init_bilinear(&s, p, NULL, NULL, false));
        Vec3 ng = v3_normalize(v3_cross(e1, e2));
        for (int i = 0; i < 200; i++) {
            Vec3 target = v3_add(p[0], v3_add(v3_scale(e1, (float)rnd(&rng, -0.3, 1.8)),
                                               v3_scale(e2, (float)rnd(&rng, -0.3, 1.8))));
            Vec3 o = v3_add(target, v3_scale(v3_normalize(rnd_v3(&rng, -1.0, 1.0)), 6.0f));
            Vec3 d = v3_normalize(v3_sub(target, o));
            if (fabsf(v3_dot(d, ng)) < 0.05f) continue; /* grazing: edges ambiguous */
            double t1, t2, u1, v1, u2, v2;
            bool h1 = tri_hit(p[0], p[1], p[3], o, d, &t1, &u1, &v1);
            bool h2 = tri_hit(p[0], p[3], p[2], o, d, &t2, &u2, &v2);
            const double m = 1e-4;
            bool in1 = h1 && u1 > m && v1 > m && u1 + v1 < 1.0 - m, in2 = h2 && u2 > m && v2 > m && u2 + v2 < 1.0 - m;
            bool out1 = !(u1 >= -m && v1 >= -m && u1 + v1 <= 1.0 + m), out2 = !(u2 >= -m && v2 >= -m && u2 + v2 <= 1.0 + m);
            Ray r = ray_make(o, d, 0.0f, INFINITY);
            float t, u, v;
            bool hp = shape_intersect(&s, &r, &t, &u, &v);
            if (in1 || in2) {
                if (!hp) fail_msg("quad %d ray %d: the triangles are hit, the patch is not", k, i);
                double tr = in1 ? t1 : t2;
                assert_true(fabs((double)t - tr) <= 1e-5 * tr);
                ShapeSurface sf;
                shape_surface(&s, &r, t, &sf);
                assert_true(v3_dot(sf.n, ng) > 0.99999f); /* dp/du x dp/dv = e1 x e2 side */
                assert_true(v3_length(v3_sub(sf.p, ray_at(&r, t))) < 1e-5f * (1.0f + v3_length(sf.p)));
                hits++;
            } else if (out1 && out2) {
                if (hp) fail_msg("quad %d ray %d: the patch is hit at t %g, the triangles are not", k, i, (double)t);
                misses++;
            }
        }
    }
    print_message("  planar patches vs two triangles: %d hits, %d misses agree\n", hits, misses);
    assert_true(hits > 5000 && misses > 5000);
}

/* The saddle p(u, v) = (u, v, uv). */
static AnalyticShape saddle(void)
{
    Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
    AnalyticShape s;
    assert_true(shape_init_bilinear(&s, p, NULL, NULL, false));
    return s;
}

static void test_saddle_closed_form(void **state)
{
    (void)state;
    AnalyticShape s = saddle();
    Pcg32 rng;
    pcg32_seed(&rng, 3u, 8u);
    double max_err = 0.0;
    for (int i = 0; i < 20000; i++) {
        double x = rnd(&rng, 0.001, 0.999), y = rnd(&rng, 0.001, 0.999);
        /* an oblique ray through the surface point (x, y, xy) from above */
        Vec3 q = v3((float)x, (float)y, (float)(x * y));
        Vec3 d = v3_normalize(v3((float)rnd(&rng, -0.5, 0.5), (float)rnd(&rng, -0.5, 0.5), -1.0f));
        Vec3 o = v3_sub(q, v3_scale(d, 3.0f));
        Ray r = ray_make(o, d, 0.0f, INFINITY);
        float t, u, v;
        if (!shape_intersect(&s, &r, &t, &u, &v)) fail_msg("ray %d through (%g, %g) missed", i, x, y);
        /* closed form: o + t d on z = x y: (oz + t dz) = (ox + t dx)(oy + t dy), the root
         * nearest 3 (the ray starts 3 above the point, so that root is the surface point
         * unless the ray met the saddle before: then t < 3 and it is the other root) */
        double ox = (double)o.x, oy = (double)o.y, oz = (double)o.z, dx = (double)d.x, dy = (double)d.y, dz = (double)d.z;
        double A = dx * dy, B = ox * dy + oy * dx - dz, C = ox * oy - oz;
        double tr;
        if (fabs(A) < 1e-12) tr = -C / B;
        else {
            double disc = sqrt(fmax(0.0, B * B - 4.0 * A * C));
            double r1 = (-B - disc) / (2.0 * A), r2 = (-B + disc) / (2.0 * A);
            double lo = fmin(r1, r2), hi = fmax(r1, r2);
            /* the nearest root in (0, inf) whose point lies on the unit square */
            double px = ox + lo * dx, py = oy + lo * dy;
            tr = (lo > 0.0 && px >= 0.0 && px <= 1.0 && py >= 0.0 && py <= 1.0) ? lo : hi;
        }
        max_err = fmax(max_err, fabs((double)t - tr));
        assert_true(fabs((double)t - tr) < 2e-5);
        ShapeSurface sf;
        shape_surface(&s, &r, t, &sf);
        Vec3 ref_n = v3_normalize(v3(-sf.uv.y, -sf.uv.x, 1.0f)); /* no uvs: uv = (u, v) */
        assert_true(v3_dot(sf.n, ref_n) > 0.999999f);
        assert_float_equal(sf.uv.x, sf.p.x, 2e-5f); /* u = x, v = y */
        assert_float_equal(sf.uv.y, sf.p.y, 2e-5f);
        assert_float_equal(sf.p.z, sf.p.x * sf.p.y, 2e-5f);
    }
    /* area: the integral of sqrt(1 + x^2 + y^2) over the unit square, 1.2807892752734
     * (mpmath.quad, 15 digits) */
    double area = (double)shape_area(&s);
    print_message("  saddle: max |t - t_closed| %.2e; area %.9f vs 1.2807892752734\n", max_err, area);
    assert_true(fabs(area - 1.2807892752734) < 1e-6);
    /* area sampling: uniform in (u, v), pdf_a = 1 / |dp/du x dp/dv| = 1 / sqrt(1 + u^2 + v^2);
     * E[1 / pdf_a] = the area */
    double sum = 0.0;
    const int N = 200000;
    for (int i = 0; i < N; i++) {
        ShapeSurface sf;
        float pdf;
        shape_sample_area(&s, v2(pcg32_float(&rng), pcg32_float(&rng)), &sf, &pdf);
        assert_float_equal(pdf, 1.0f / sqrtf(1.0f + sf.p.x * sf.p.x + sf.p.y * sf.p.y), 1e-5f);
        sum += 1.0 / (double)pdf;
    }
    /* 1 / pdf has a standard deviation below 0.2: 4 standard errors are under 2e-3 */
    assert_true(fabs(sum / N - 1.2807892752734) < 2e-3);
    assert_false(shape_uniform_area(&s));
}

/* Normals and uvs: the shading normal interpolated, the geometric one facing it; uvs
 * interpolated; reverse orientation without normals flips n. Degenerate patches refused. */
static void test_normals_uvs(void **state)
{
    (void)state;
    Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}};
    Vec3 n[4] = {{0, 0, -1}, {0, 0, -1}, {0, 0, -1}, {0, 0, -1}};
    Vec2 uv[4] = {{0, 0}, {2, 0}, {0, 4}, {2, 4}};
    AnalyticShape s;
    assert_true(shape_init_bilinear(&s, p, n, uv, false));
    Ray r = ray_make(v3(0.25f, 0.5f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    float t, u, v;
    assert_true(shape_intersect(&s, &r, &t, &u, &v));
    ShapeSurface sf;
    shape_surface(&s, &r, t, &sf);
    assert_float_equal(sf.n.z, -1.0f, 1e-6f); /* turned to face N */
    assert_float_equal(sf.ns.z, -1.0f, 1e-6f);
    assert_float_equal(sf.uv.x, 0.5f, 1e-6f);
    assert_float_equal(sf.uv.y, 2.0f, 1e-6f);
    assert_true(shape_init_bilinear(&s, p, NULL, NULL, true));
    shape_surface(&s, &r, t, &sf);
    assert_float_equal(sf.n.z, -1.0f, 1e-6f); /* flipped */
    Vec3 line[4] = {{0, 0, 0}, {1, 1, 1}, {2, 2, 2}, {3, 3, 3}};
    assert_false(shape_init_bilinear(&s, line, NULL, NULL, false));
}

static Scene *load_pbrt(const char *text, CstStatus want, CstError *err)
{
    CstScene *s = NULL;
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), "t.pbrt", NULL, &s, err);
    if (st != want) fail_msg("status %d: %s", (int)st, err->msg);
    return s;
}

#define WORLD(x) "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\n" x

/* "bilinearmesh": exact patches with N and uv; a degenerate patch left out; emitting ones
 * two triangles each, as before. */
static void test_pbrt_bilinearmesh(void **state)
{
    (void)state;
    CstError err;
    Scene *s = load_pbrt(WORLD("Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1  5 5 5 5 5 5 5 5 5 5 5 5] "
                               "\"integer indices\" [0 1 2 3 4 5 6 7] \"point2 uv\" [0 0 1 0 0 1 1 1 0 0 0 0 0 0 0 0]\n"
                               "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1]\n"
                               "Shape \"bilinearmesh\" \"point3 P\" [0 0 3 1 0 3 0 1 3 1 1 3]\nAttributeEnd\n"),
                         CST_OK, &err);
    assert_int_equal(s->num_shapes, 1);
    assert_int_equal(s->shapes[0].p.type, SHAPE_TAG_BILINEAR);
    assert_true(s->shapes[0].bl.has_uv && !s->shapes[0].bl.has_n);
    assert_int_equal(s->num_triangles, 2); /* the emitting patch */
    assert_int_equal(s->num_emitters, 2);  /* its two triangles */
    /* the camera's central ray meets the saddle at (0.5, 0.5, 0.25) */
    SurfaceHit sh;
    Ray r = ray_make(v3(0.5f, 0.5f, 2.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    assert_float_equal(sh.p.z, 0.25f, 1e-6f);
    assert_float_equal(sh.uv.x, 0.5f, 1e-6f);
    cst_scene_destroy(s);
    /* a bad index is still a located error */
    s = load_pbrt(WORLD("Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 1] \"integer indices\" [0 1 2 9]\n"),
                  CST_ERR_INVALID_ARG, &err);
    assert_null(s);
    if (!strstr(err.msg, "t.pbrt:4:")) fail_msg("%s", err.msg);
}

/* The builder: an emitting patch is refused (CST_ERR_UNSUPPORTED), so is one without area. */
static void test_builder(void **state)
{
    (void)state;
    CstScene *scene = NULL;
    CstError err;
    assert_int_equal(cst_scene_create(&scene, &err), CST_OK);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    int mat = -1;
    assert_int_equal(cst_scene_add_material(scene, &md, &mat, &err), CST_OK);
    CstShapeDesc d;
    memset(&d, 0, sizeof d);
    d.type = CST_SHAPE_BILINEAR;
    d.material = mat;
    const float q[4][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 1}};
    memcpy(d.patch, q, sizeof q);
    assert_int_equal(cst_scene_add_shape(scene, &d, &err), CST_OK);
    d.emission.radiance[0] = 1.0f;
    assert_int_equal(cst_scene_add_shape(scene, &d, &err), CST_ERR_UNSUPPORTED);
    d.emission.radiance[0] = 0.0f;
    memset(d.patch, 0, sizeof d.patch);
    assert_int_equal(cst_scene_add_shape(scene, &d, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "no area")) fail_msg("%s", err.msg);
    cst_scene_destroy(scene);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_planar_vs_triangles),
        cmocka_unit_test(test_saddle_closed_form),
        cmocka_unit_test(test_normals_uvs),
        cmocka_unit_test(test_pbrt_bilinearmesh),
        cmocka_unit_test(test_builder),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
