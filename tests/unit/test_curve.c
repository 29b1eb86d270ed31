/* Curves (geometry/curve.c, SHAPE_TAG_CURVE): flat and cylinder curves against a densely
 * tessellated reference ribbon (the ribbon facing the ray: for parallel rays a fixed
 * surface), the bounds holding every hit, every accel back end returning the list's hits
 * bit for bit, the surface (normals, v, dp/du), B-spline and quadratic conversion, and the
 * pbrt loader's "curve" with its errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel.h"
#include "caustic/caustic.h"
#include "core/rng.h"
#include "geometry/shape.h"
#include "scene/scene.h"

static float rndf(Pcg32 *r, float lo, float hi) { return lo + (hi - lo) * pcg32_float(r); }
static Vec3 rnd_v3(Pcg32 *r, float lo, float hi) { return v3(rndf(r, lo, hi), rndf(r, lo, hi), rndf(r, lo, hi)); }

/* Moller-Trumbore in double; t > 0. */
static bool tri_hit(Vec3 a, Vec3 b, Vec3 c, Vec3 o, Vec3 d, double *t)
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
    return u >= 0.0 && v >= 0.0 && u + v <= 1.0 && *t > 0.0;
}

enum { TESS = 512 };

/* The ribbon of the curve cp (widths w0, w1) facing direction d, scaled across by k:
 * c(u) +- k w(u) / 2 normalize(d x c'(u)), TESS quads along u; closest hit of ray (o, d). */
static float g_ref_u;
static bool ribbon_hit(const Vec3 cp[4], float w0, float w1, float k, Vec3 o, Vec3 d, double *t_out)
{
    bool hit = false;
    double best = INFINITY;
    Vec3 prev_a = v3s(0.0f), prev_b = v3s(0.0f);
    for (int i = 0; i <= TESS; i++) {
        float u = (float)i / (float)TESS;
        Vec3 dc;
        Vec3 c = curve_eval(cp, u, &dc);
        Vec3 side = v3_normalize(v3_cross(d, dc));
        float hw = 0.5f * k * ((1.0f - u) * w0 + u * w1);
        Vec3 a = v3_madd(c, side, hw), b = v3_madd(c, side, -hw);
        if (i > 0) {
            double t;
            if (tri_hit(prev_a, prev_b, b, o, d, &t) && t < best) best = t, hit = true, g_ref_u = u;
            if (tri_hit(prev_a, b, a, o, d, &t) && t < best) best = t, hit = true, g_ref_u = u;
        }
        prev_a = a;
        prev_b = b;
    }
    *t_out = best;
    return hit;
}

/* A random smooth curve about the origin, its chord about 2 long, width about 0.1. */
static void random_curve(Pcg32 *rng, Vec3 cp[4], float *w0, float *w1)
{
    Vec3 a = rnd_v3(rng, -1.0f, 1.0f), b = rnd_v3(rng, -1.0f, 1.0f);
    if (v3_length(v3_sub(b, a)) < 1.0f) b = v3_add(a, v3(1.5f, 0.3f, -0.2f));
    cp[0] = a;
    cp[3] = b;
    cp[1] = v3_add(v3_scale(v3_add(v3_scale(a, 2.0f), b), 1.0f / 3.0f), rnd_v3(rng, -0.4f, 0.4f));
    cp[2] = v3_add(v3_scale(v3_add(a, v3_scale(b, 2.0f)), 1.0f / 3.0f), rnd_v3(rng, -0.4f, 0.4f));
    *w0 = rndf(rng, 0.05f, 0.15f);
    *w1 = rndf(rng, 0.02f, 0.15f);
}

/* Flat and cylinder curves, split into 1 or 4 segments, against the tessellated ribbon:
 * rays that hit the ribbon narrowed to 80 % hit the curve at t within 0.3 widths (the
 * subdivision's 5 % chord tolerance, with slanted tangents); rays that miss the ribbon
 * widened to 125 % miss it; every hit point inside the segment's bounds. Ray bundles are
 * parallel (one direction per bundle), the ribbon a fixed surface for them. */
static void test_against_tessellation(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 28u, 1u);
    int hits = 0, misses = 0, skipped = 0;
    for (int k = 0; k < 24; k++) {
        Vec3 cp[4];
        float w0, w1;
        random_curve(&rng, cp, &w0, &w1);
        const int nseg = k % 2 ? 4 : 1;
        AnalyticShape seg[4];
        for (int s = 0; s < nseg; s++)
            assert_true(shape_init_curve(&seg[s], cp, (float)s / (float)nseg, (float)(s + 1) / (float)nseg, w0, w1,
                                         k % 3 == 0 ? CURVE_CYLINDER : CURVE_FLAT, NULL, false));
        for (int bundle = 0; bundle < 4; bundle++) {
            Vec3 d = v3_normalize(rnd_v3(&rng, -1.0f, 1.0f));
            for (int i = 0; i < 60; i++) {
                /* aim at a point near the curve */
                Vec3 target = v3_add(curve_eval(cp, rndf(&rng, -0.05f, 1.05f), NULL), rnd_v3(&rng, -0.12f, 0.12f));
                Vec3 o = v3_madd(target, d, -8.0f);
                Ray r = ray_make(o, d, 0.0f, INFINITY);
                float t = INFINITY, u = 0.0f, v;
                bool h = false;
                for (int s = 0; s < nseg; s++) {
                    float ts, us, vs;
                    if (shape_intersect(&seg[s], &r, &ts, &us, &vs) && ts < t) {
                        t = ts, u = us, v = vs, h = true;
                        Vec3 p = ray_at(&r, ts);
                        const BBox *b = &seg[s].bounds;
                        assert_true(p.x >= b->min.x && p.y >= b->min.y && p.z >= b->min.z && p.x <= b->max.x &&
                                    p.y <= b->max.y && p.z <= b->max.z);
                        assert_true(us >= seg[s].cv.u0 && us <= seg[s].cv.u1 && vs >= 0.0f && vs <= 1.0f);
                    }
                }
                (void)v;
                double t_in, t_out;
                bool in = ribbon_hit(cp, w0, w1, 0.8f, o, d, &t_in);
                const float ref_u = g_ref_u;
                bool out = ribbon_hit(cp, w0, w1, 1.25f, o, d, &t_out);
                /* pbrt-v4's test (the pieces' end perpendiculars and chords in the ray's
                 * plane) is not exact where the fibre runs within ~27 degrees of the ray
                 * (|d.c'| > 2 |d x c'|): such views are left out */
                Vec3 dc_ref, dc_hit;
                (void)curve_eval(cp, ref_u, &dc_ref);
                (void)curve_eval(cp, u, &dc_hit);
                const bool steep = (in && fabsf(v3_dot(d, dc_ref)) > 2.0f * v3_length(v3_cross(d, dc_ref))) ||
                                   (h && fabsf(v3_dot(d, dc_hit)) > 2.0f * v3_length(v3_cross(d, dc_hit)));
                if (steep) {
                    skipped++;
                } else if (in) {
                    /* the reference's depth is only as good as its own 1/TESS steps along slanted tangents */
                    if (!h) fail_msg("curve %d ray %d: the ribbon is hit at t %g, the curve is not", k, i, t_in);
                    /* depth errors grow with the tangent's slope along the ray: |d.c'| / |d x c'| */
                    Vec3 dc;
                    (void)curve_eval(cp, u, &dc);
                    const double wmax = (double)fmaxf(w0, w1);
                    const double slope = fmax(1.0, (double)(fabsf(v3_dot(d, dc)) / v3_length(v3_cross(d, dc))));
                    if (fabs((double)t - t_in) > 0.3 * wmax * slope + 2e-3)
                        fail_msg("curve %d ray %d: t %g, the ribbon's %g (ref u %g, u %g slope %g depth %d nseg %d w %g %g)", k, i, (double)t, t_in, (double)ref_u, (double)u, slope, seg[0].cv.depth, nseg, (double)w0, (double)w1);
                    hits++;
                } else if (!out) {
                    if (h) fail_msg("curve %d ray %d: the curve is hit at t %g, the widened ribbon is not", k, i, (double)t);
                    misses++;
                } else {
                    skipped++;
                }
            }
        }
    }
    print_message("  curves vs tessellated ribbons: %d hits, %d misses agree (%d near the edges or seen nearly end-on left out)\n", hits,
                  misses, skipped);
    assert_true(hits > 1500 && misses > 1500);
}

/* A ribbon in the plane z = 0 with normals +z seen along -z: the tessellated ribbon with
 * side vectors n x c' (exact for this view); narrowed ribbon hits are curve hits. */
static void test_ribbon(void **state)
{
    (void)state;
    const Vec3 cp[4] = {{-1, 0, 0}, {-0.3f, 0.6f, 0}, {0.3f, -0.6f, 0}, {1, 0, 0}};
    const Vec3 n[2] = {{0, 0, 1}, {0, 0, 2}};
    AnalyticShape s;
    assert_true(shape_init_curve(&s, cp, 0.0f, 1.0f, 0.2f, 0.1f, CURVE_RIBBON, n, false));
    Pcg32 rng;
    pcg32_seed(&rng, 28u, 2u);
    int hits = 0, misses = 0;
    const Vec3 d = v3(0.0f, 0.0f, -1.0f);
    for (int i = 0; i < 2000; i++) {
        Vec3 o = v3(rndf(&rng, -1.2f, 1.2f), rndf(&rng, -0.35f, 0.35f), 3.0f);
        Ray r = ray_make(o, d, 0.0f, INFINITY);
        float t, u, v;
        bool h = shape_intersect(&s, &r, &t, &u, &v);
        double tr;
        if (ribbon_hit(cp, 0.2f, 0.1f, 0.8f, o, d, &tr)) {
            assert_true(h);
            assert_true(fabs((double)t - 3.0) < 1e-5);
            ShapeSurface sf;
            shape_surface(&s, &r, t, &sf);
            assert_true(fabsf(sf.n.z) > 0.9999f); /* the ribbon's own normal */
            hits++;
        } else if (!ribbon_hit(cp, 0.2f, 0.1f, 1.25f, o, d, &tr)) {
            assert_false(h);
            misses++;
        }
    }
    /* edge-on, a ribbon has no width */
    Ray r = ray_make(v3(0.0f, -3.0f, 0.0f), v3(0.0f, 1.0f, 0.0f), 0.0f, INFINITY);
    float t, u, v;
    assert_false(shape_intersect(&s, &r, &t, &u, &v));
    print_message("  ribbon: %d hits, %d misses agree\n", hits, misses);
    assert_true(hits > 300 && misses > 300);
}

/* The surface of a straight flat curve along x seen along -z: n = +-z (dp/du x dp/dv
 * faces along the ray), v from 0 to 1 across y, dp/du = the chord; a cylinder curve's
 * normal turns from -y through the flat one to +y (sideways at the edges), and a ray
 * leaving the fibre does not hit it again. */
static void test_surface(void **state)
{
    (void)state;
    const Vec3 cp[4] = {{0, 0, 0}, {1, 0, 0}, {2, 0, 0}, {3, 0, 0}};
    AnalyticShape flat, cyl;
    assert_true(shape_init_curve(&flat, cp, 0.0f, 1.0f, 0.2f, 0.2f, CURVE_FLAT, NULL, false));
    assert_true(shape_init_curve(&cyl, cp, 0.0f, 1.0f, 0.2f, 0.2f, CURVE_CYLINDER, NULL, false));
    for (int j = -4; j <= 4; j++) {
        const float y = 0.0249f * (float)j;
        Ray r = ray_make(v3(1.5f, y, 5.0f), v3(0.0f, 0.0f, -2.0f), 0.0f, INFINITY);
        float t, u, v;
        assert_true(shape_intersect(&flat, &r, &t, &u, &v));
        assert_float_equal(t, 2.5f, 1e-5f); /* world t of the unnormalised direction */
        assert_float_equal(u, 0.5f, 1e-5f);
        ShapeSurface sf, sc;
        shape_surface(&flat, &r, t, &sf);
        assert_float_equal(fabsf(sf.uv.y - 0.5f), fabsf(y) / 0.2f, 1e-4f);
        assert_true(fabsf(sf.n.z) > 0.99999f);
        assert_float_equal(sf.dpdu.x, 3.0f, 1e-5f);
        assert_float_equal(v3_length(sf.dpdv), 0.2f, 1e-5f);
        shape_surface(&cyl, &r, t, &sc);
        /* rotated about x by (v - 1/2) pi away from the flat normal: the side turns to y */
        const float ang = (sc.uv.y - 0.5f) * CST_PI;
        assert_float_equal(fabsf(sc.n.y), fabsf(sinf(ang)), 1e-4f);
        assert_float_equal(fabsf(sc.n.z), cosf(ang), 1e-4f);
        /* a bounce from the hit, any direction: no hit on the same fibre */
        for (int k = 0; k < 6; k++) {
            Vec3 dir = v3_normalize(v3((float)(k - 3), 1.0f - 0.3f * (float)k, k % 2 ? 1.0f : -1.0f));
            Ray b = ray_make(sf.p, dir, 0.0f, INFINITY);
            assert_false(shape_intersect(&flat, &b, &t, &u, &v));
        }
    }
    /* a ray from beside the fibre, more than a width away, still hits it */
    Ray side = ray_make(v3(1.5f, -0.5f, 0.0f), v3(0.0f, 1.0f, 0.0f), 0.0f, INFINITY);
    float t, u, v;
    assert_true(shape_intersect(&flat, &side, &t, &u, &v));
    assert_float_equal(t, 0.5f, 1e-4f);
}

/* Bases: a B-spline's cubic segments join with matching points and tangents; a quadratic
 * Bezier elevated to cubic keeps its points. */
static void test_bases(void **state)
{
    (void)state;
    const Vec3 p[6] = {{0, 0, 0}, {1, 2, 0}, {2, -1, 1}, {3, 0, 2}, {4, 1, 0}, {5, 0, 0}};
    for (int deg = 2; deg <= 3; deg++) {
        for (int seg = 0; seg + deg + 1 < 6; seg++) {
            Vec3 a[4], b[4], da, db;
            curve_bezier_segment(p, deg, true, seg, a);
            curve_bezier_segment(p, deg, true, seg + 1, b);
            Vec3 ea = curve_eval(a, 1.0f, &da), eb = curve_eval(b, 0.0f, &db);
            assert_true(v3_length(v3_sub(ea, eb)) < 1e-5f);
            assert_true(v3_length(v3_sub(da, db)) < 1e-4f);
        }
    }
    Vec3 c[4];
    curve_bezier_segment(p, 2, false, 1, c); /* points 2, 3, 4 */
    for (int i = 0; i <= 8; i++) {
        float t = (float)i / 8.0f, s = 1.0f - t;
        Vec3 q = v3_add(v3_add(v3_scale(p[2], s * s), v3_scale(p[3], 2.0f * s * t)), v3_scale(p[4], t * t));
        assert_true(v3_length(v3_sub(curve_eval(c, t, NULL), q)) < 1e-5f);
    }
}

/* Every back end over 600 curve segments (150 curves split in 4) returns the list's hits
 * bit for bit (t, u, v, primitive). Spheres among them (first, and one between every
 * tenth curve's segments) make the BVH mix its compact curve records (bvh.h) with
 * shapes tested on their AnalyticShape, and ribbons (every third curve) have no record. */
static void test_backends_agree(void **state)
{
    (void)state;
    enum { NC = 150, NS = 4, NQ = 4 + NC / 10 };
    AnalyticShape *shapes = malloc((NC * NS + NQ) * sizeof *shapes);
    assert_non_null(shapes);
    Pcg32 rng;
    pcg32_seed(&rng, 28u, 3u);
    int n = 0;
    const ShapeParams sphere = {.type = SHAPE_TAG_SPHERE, .radius = 0.4f, .z_min = -0.4f, .z_max = 0.4f,
                                .phi_max = 2.0f * CST_PI};
    for (int q = 0; q < 4; q++) { /* drawn from their own stream: the curves and rays stay as they were */
        const Transform m = transform_translate(v3(2.5f * (float)(q % 2) - 1.25f, 2.5f * (float)(q / 2) - 1.25f, 0.5f));
        assert_true(shape_init(&shapes[n++], &sphere, &m));
    }
    for (int c = 0; c < NC; c++) {
        Vec3 cp[4];
        float w0, w1;
        random_curve(&rng, cp, &w0, &w1);
        if (c % 2) w0 *= 0.25f, w1 *= 0.25f; /* thin: the BVH bounds these by pieces */
        Vec3 off = rnd_v3(&rng, -3.0f, 3.0f);
        for (int i = 0; i < 4; i++) cp[i] = v3_add(cp[i], off);
        for (int s = 0; s < NS; s++) {
            if (c % 10 == 5 && s == 2) { /* a sphere splitting the run of segments that share widths */
                const Transform m = transform_translate(v3_scale(v3_add(cp[0], cp[3]), 0.5f));
                assert_true(shape_init(&shapes[n++], &(ShapeParams){.type = SHAPE_TAG_SPHERE, .radius = 0.1f,
                                                                    .z_min = -0.1f, .z_max = 0.1f,
                                                                    .phi_max = 2.0f * CST_PI},
                                       &m));
            }
            assert_true(shape_init_curve(&shapes[n++], cp, (float)s / NS, (float)(s + 1) / NS, w0, w1,
                                         (CurveType)(c % 3), c % 3 == 2 ? (Vec3[2]){cp[1], cp[2]} : NULL, false));
        }
    }
    assert_int_equal(n, NC * NS + NQ);
    AccelGeometry g = {0};
    g.shapes = shapes;
    g.num_shapes = n;
    Accel a[ACCEL_TYPE_COUNT];
    int na = 0, list = -1;
    for (int t = 0; t < ACCEL_TYPE_COUNT; t++) {
        if (!accel_type_available((AccelType)t)) continue;
        CstError err = {0};
        if (accel_build(&a[na], (AccelType)t, &g, &err) != CST_OK) fail_msg("%s: %s", accel_type_name((AccelType)t), err.msg);
        if (t == ACCEL_LIST) list = na;
        na++;
    }
    assert_true(list >= 0 && na >= 4);
    int hits = 0;
    for (int i = 0; i < 3000; i++) {
        Vec3 o = rnd_v3(&rng, -6.0f, 6.0f), d = v3_normalize(v3_sub(rnd_v3(&rng, -3.0f, 3.0f), o));
        Ray r = ray_make(o, d, 0.0f, INFINITY);
        Hit ref = {0};
        bool hr = accel_intersect(&a[list], &r, &ref);
        hits += hr;
        for (int k = 0; k < na; k++) {
            Hit h = {0};
            bool hk = accel_intersect(&a[k], &r, &h);
            if (hk != hr || (hr && (h.t != ref.t || h.prim != ref.prim || h.u != ref.u || h.v != ref.v)))
                fail_msg("ray %d: %s differs from the list (%d %g %u vs %d %g %u)", i, accel_type_name(a[k].type),
                         hk, (double)h.t, h.prim, hr, (double)ref.t, ref.prim);
            assert_int_equal(accel_occluded(&a[k], &r), hr);
        }
    }
    print_message("  %d back ends agree on 3000 rays (%d hits)\n", na, hits);
    assert_true(hits > 300);
    for (int k = 0; k < na; k++) accel_free(&a[k]);
    free(shapes);
}

/* curve_piece_bounds: long segments are cut (k > 1), short ones not; every hit of rays
 * aimed at points of the fibre (within its width, from every side) lies in the box of
 * the piece holding the hit's u, and the pieces lie in the segment's box. */
static bool box_holds(BBox b, Vec3 p)
{
    return p.x >= b.min.x && p.y >= b.min.y && p.z >= b.min.z && p.x <= b.max.x && p.y <= b.max.y && p.z <= b.max.z;
}

static void test_piece_bounds(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 28u, 7u);
    int hits = 0, cut = 0;
    for (int c = 0; c < 120; c++) {
        Vec3 cp[4];
        float w0, w1;
        random_curve(&rng, cp, &w0, &w1);
        w0 *= 0.25f; /* hair-like: segments 10 to 40 widths long, cut into 2 to 8 pieces */
        w1 *= 0.25f;
        const float u0 = (float)(c % 4) / 4.0f, u1 = u0 + 0.25f;
        AnalyticShape sh;
        assert_true(shape_init_curve(&sh, cp, u0, u1, w0, w1, (CurveType)(c % 3),
                                     c % 3 == 2 ? (Vec3[2]){cp[1], cp[2]} : NULL, false));
        BBox box[CURVE_MAX_PIECES];
        const int k = shape_piece_bounds(&sh, box);
        assert_true(k >= 1 && k <= CURVE_MAX_PIECES && (k & (k - 1)) == 0);
        cut += k > 1;
        for (int j = 0; j < k; j++)
            for (int a = 0; a < 3; a++)
                assert_true(v3_get(box[j].min, a) >= v3_get(sh.bounds.min, a) &&
                            v3_get(box[j].max, a) <= v3_get(sh.bounds.max, a));
        for (int i = 0; i < 400; i++) {
            const float w = pcg32_float(&rng);
            const Vec3 target = v3_add(curve_eval(sh.cv.cp, w, NULL), rnd_v3(&rng, -0.6f * w0, 0.6f * w0));
            const Vec3 d = v3_normalize(rnd_v3(&rng, -1.0f, 1.0f));
            const Ray r = ray_make(v3_madd(target, d, -4.0f), d, 0.0f, INFINITY);
            float t, u, v;
            if (!shape_intersect(&sh, &r, &t, &u, &v)) continue;
            hits++;
            int j = (int)((u - u0) / (u1 - u0) * (float)k);
            j = j < 0 ? 0 : j >= k ? k - 1 : j;
            const Vec3 p = ray_at(&r, t);
            /* on a boundary between pieces u may round either way: either box will do */
            bool in = false;
            for (int jj = j - 1; jj <= j + 1; jj++) {
                if (jj < 0 || jj >= k) continue;
                const float uj0 = u0 + (u1 - u0) * (float)jj / (float)k, uj1 = u0 + (u1 - u0) * (float)(jj + 1) / (float)k;
                if ((jj != j && fabsf(u - (jj < j ? uj1 : uj0)) > 1e-5f)) continue;
                in |= box_holds(box[jj], p);
            }
            if (!in)
                fail_msg("curve %d ray %d: hit at u %g outside piece %d of %d", c, i, (double)u, j, k);
        }
    }
    print_message("  %d hits inside their pieces' boxes; %d of 120 segments cut\n", hits, cut);
    assert_true(hits > 5000 && cut > 90);
    /* a short segment (its length below 8 widths) is one piece */
    AnalyticShape sh;
    const Vec3 cp[4] = {v3(0, 0, 0), v3(0.1f, 0, 0), v3(0.2f, 0, 0), v3(0.3f, 0, 0)};
    assert_true(shape_init_curve(&sh, cp, 0.0f, 1.0f, 0.1f, 0.1f, CURVE_FLAT, NULL, false));
    BBox box[CURVE_MAX_PIECES];
    assert_int_equal(shape_piece_bounds(&sh, box), 1);
}

static Scene *load_pbrt(const char *text, CstStatus want, CstError *err)
{
    CstScene *s = NULL;
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), "t.pbrt", NULL, &s, err);
    if (st != want) fail_msg("status %d: %s", (int)st, err->msg);
    return s;
}

#define WORLD(x) "LookAt 0 0 5 0 0 0 0 1 0\nCamera \"perspective\"\nWorldBegin\nMaterial \"hair\"\n" x

/* The loader: segments x 2^splitdepth shapes, widths scaled by the CTM, the hair material
 * on a curve gets the hit's v; errors located. */
static void test_pbrt_curve(void **state)
{
    (void)state;
    CstError err;
    Scene *s = load_pbrt(WORLD("Scale 2 2 2\nShape \"curve\" \"point3 P\" [-1 0 0 -0.3 0 0 0.3 0 0 1 0 0 1.5 0 0 2 0 0 2.5 0 0] "
                               "\"float width0\" 0.1 \"float width1\" 0.05 \"integer splitdepth\" 1\n"
                               "Shape \"curve\" \"string basis\" \"bspline\" \"point3 P\" [0 0 0 1 1 0 2 0 0 3 1 0 4 0 0] "
                               "\"float width\" 0.1 \"string type\" \"cylinder\"\n"),
                         CST_OK, &err);
    assert_int_equal(s->num_shapes, 2 * 2 + 2 * 8);
    assert_int_equal(s->shapes[0].p.type, SHAPE_TAG_CURVE);
    assert_float_equal(s->shapes[0].cv.w0, 0.2f, 1e-6f);   /* 2 x 0.1 */
    assert_float_equal(s->shapes[0].cv.w1, 0.15f, 1e-6f);  /* 2 x (0.1 + 0.5 (0.05 - 0.1)) */
    assert_float_equal(s->shapes[3].cv.cp[3].x, 5.0f, 1e-5f);
    assert_int_equal(s->shapes[4].cv.type, CURVE_CYLINDER);
    SurfaceHit sh;
    Ray r = ray_make(v3(-1.0f, 0.05f, 4.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    assert_true(fabsf(sh.uv.y - 0.5f) > 0.2f && fabsf(sh.uv.y - 0.5f) < 0.4f); /* 0.05 off a width 0.2 to 0.15 */
    cst_scene_destroy(s);
    /* errors: count, ribbon without normals, bad basis */
    s = load_pbrt(WORLD("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0 4 0 0]\n"), CST_ERR_INVALID_ARG, &err);
    if (!strstr(err.msg, "t.pbrt:5:") || !strstr(err.msg, "3n + 1")) fail_msg("%s", err.msg);
    s = load_pbrt(WORLD("Shape \"curve\" \"string type\" \"ribbon\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n"),
                  CST_ERR_INVALID_ARG, &err);
    if (!strstr(err.msg, "t.pbrt:5:") || !strstr(err.msg, "normal")) fail_msg("%s", err.msg);
    s = load_pbrt(WORLD("Shape \"curve\" \"string basis\" \"nurbs\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0]\n"),
                  CST_ERR_INVALID_ARG, &err);
    if (!strstr(err.msg, "bspline")) fail_msg("%s", err.msg);
    s = load_pbrt(WORLD("Shape \"curve\" \"point3 P\" [0 0 0 1 0 0 2 0 0 3 0 0] \"float width\" 0\n"),
                  CST_ERR_INVALID_ARG, &err);
    (void)s;
}

/* The JSON "curve" shape gives the same primitives as the pbrt loader's "curve" (both go
 * through cst_scene_add_curves), and its errors are located. */
static CstStatus load_json(const char *shapes, CstScene **out, CstError *err)
{
    char text[4096];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
             " \"materials\": {\"h\": {\"type\": \"hair\"}},\n"
             " \"shapes\": [\n%s]}\n", shapes);
    return cst_scene_load_json_string(text, strlen(text), "c.json", out, err);
}

static void test_json_curve(void **state)
{
    (void)state;
    CstError err;
    Scene *p = load_pbrt(WORLD("Scale 2 2 2\nShape \"curve\" \"point3 P\" [-1 0 0 -0.3 0 0 0.3 0 0 1 0 0 1.5 0 0 2 0 0 2.5 0 0] "
                               "\"float width0\" 0.1 \"float width1\" 0.05 \"integer splitdepth\" 1\n"
                               "Shape \"curve\" \"string basis\" \"bspline\" \"string type\" \"ribbon\" "
                               "\"point3 P\" [0 0 0 1 1 0 2 0 0 3 1 0 4 0 0] \"normal N\" [0 0 1 0 1 1 1 0 1] "
                               "\"float width\" 0.1 \"integer degree\" 3\n"),
                         CST_OK, &err);
    CstScene *j = NULL;
    if (load_json("{\"type\": \"curve\", \"material\": \"h\", \"transform\": {\"scale\": [2, 2, 2]}, \"split_depth\": 1,\n"
                  "  \"points\": [[-1,0,0], [-0.3,0,0], [0.3,0,0], [1,0,0], [1.5,0,0], [2,0,0], [2.5,0,0]],\n"
                  "  \"width0\": 0.1, \"width1\": 0.05},\n"
                  " {\"type\": \"curve\", \"material\": \"h\", \"basis\": \"bspline\", \"curve_type\": \"ribbon\", \"width\": 0.1,\n"
                  "  \"transform\": {\"scale\": [2, 2, 2]},\n"
                  "  \"points\": [[0,0,0], [1,1,0], [2,0,0], [3,1,0], [4,0,0]], \"normals\": [[0,0,1], [0,1,1], [1,0,1]]}\n",
                  &j, &err) != CST_OK)
        fail_msg("%s", err.msg);
    assert_int_equal(j->num_shapes, p->num_shapes);
    assert_int_equal(j->num_shapes, 2 * 2 + 2 * 8);
    assert_memory_equal(j->shapes, p->shapes, (size_t)p->num_shapes * sizeof *p->shapes);
    cst_scene_destroy(j);
    cst_scene_destroy(p);
    /* errors, each located at its shape's line (the shapes start on line 4) */
    static const struct { const char *shape, *what; } bad[] = {
        {"{\"type\": \"curve\", \"material\": \"h\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0],[4,0,0]]}", "3n + 1"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"curve_type\": \"ribbon\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}", "normal"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"curve_type\": \"ribbon\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]], "
         "\"normals\": [[0,0,1]]}", "1 normals; expected one per segment end (2)"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"basis\": \"nurbs\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}", "bspline"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"width\": 0, \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}", "not both 0"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"degree\": 4, \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}", "degree"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]], \"normals\": [[0,0,1],[0,0,1]]}",
         "ribbon"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"emission\": [1,1,1], \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,0]]}",
         "emission"},
        {"{\"type\": \"curve\", \"material\": \"h\", \"points\": [[0,0,0],[1,0,0],[2,0,0],[3,0,\"x\"]]}", "points[3]"},
    };
    for (size_t k = 0; k < sizeof bad / sizeof bad[0]; k++) {
        CstScene *s = NULL;
        err.msg[0] = '\0';
        if (load_json(bad[k].shape, &s, &err) == CST_OK) fail_msg("loaded: %s", bad[k].shape);
        assert_null(s);
        if (!strstr(err.msg, "c.json:4:") || !strstr(err.msg, bad[k].what))
            fail_msg("case %zu: %s (expected c.json:4: and \"%s\")", k, err.msg, bad[k].what);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_against_tessellation),
        cmocka_unit_test(test_ribbon),
        cmocka_unit_test(test_surface),
        cmocka_unit_test(test_bases),
        cmocka_unit_test(test_backends_agree),
        cmocka_unit_test(test_piece_bounds),
        cmocka_unit_test(test_pbrt_curve),
        cmocka_unit_test(test_json_curve),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
