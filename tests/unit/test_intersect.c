/* Unit tests of the ray-primitive tests: the robust ray-sphere quadratic (sphere.h),
 * Moller-Trumbore ray-triangle (triangle.h), the slab test with exact zero-direction
 * handling and the BVH's safe reciprocal (bbox.h). References are computed in double. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "core/rng.h"
#include "geometry/ray.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"
#include "math/bbox.h"
#include "scene/scene.h"

/* |got - want| <= tol * max(|want|, 1e-30), with both values in the failure message. */
#define assert_rel(got, want, tol)                                                        \
    do {                                                                                  \
        double g_ = (double)(got), w_ = (double)(want);                                   \
        if (!(fabs(g_ - w_) <= (double)(tol) * fmax(fabs(w_), 1e-30)))                    \
            fail_msg("%s = %.9g, expected %.9g (rel tol %g)", #got, g_, w_, (double)(tol)); \
    } while (0)
#define assert_abs(got, want, tol)                                                        \
    do {                                                                                  \
        double g_ = (double)(got), w_ = (double)(want);                                   \
        if (!(fabs(g_ - w_) <= (double)(tol)))                                            \
            fail_msg("%s = %.9g, expected %.9g (abs tol %g)", #got, g_, w_, (double)(tol)); \
    } while (0)

static Ray ray_to(Vec3 o, Vec3 d, float t_min, float t_max)
{
    return ray_make(o, v3_normalize(d), t_min, t_max);
}

static double rnd(Pcg32 *rng, double lo, double hi) { return lo + (hi - lo) * (double)pcg32_float(rng); }
/* Three draws for one vector, z first: the order GCC gave the v3(rnd(), rnd(), rnd()) this
 * replaces (C leaves the order of arguments unspecified; Clang went x first), so the tests
 * keep the values they had. */
static Vec3 rnd_v3_zyx(Pcg32 *rng, double lo, double hi)
{
    float z = (float)rnd(rng, lo, hi), y = (float)rnd(rng, lo, hi), x = (float)rnd(rng, lo, hi);
    return v3(x, y, z);
}

/* ------------------------------------------------------------------ sphere */

static void test_sphere_outside_nearest_root(void **state)
{
    (void)state;
    Vec3 c = v3(0.0f, 0.0f, 5.0f);
    float t = -1.0f;
    Ray r = ray_to(v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(c, 1.0f, &r, &t));
    assert_rel(t, 4.0, 1e-6); /* near root; the far root is 6 */
    /* Both roots exist: with the near one excluded by t_min the far one is returned. */
    r.t_min = 4.5f;
    assert_true(sphere_intersect(c, 1.0f, &r, &t));
    assert_rel(t, 6.0, 1e-6);

    /* Off-axis hit at impact parameter 0.6: t = 5 - sqrt(1 - 0.36) = 4.2. */
    r = ray_to(v3(0.6f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(c, 1.0f, &r, &t));
    assert_rel(t, 4.2, 1e-6);

    /* Random rays aimed at random points on random spheres: nearest root vs double. */
    Pcg32 rng;
    pcg32_seed(&rng, 1u, 2u);
    for (int i = 0; i < 10000; i++) {
        Vec3 cc = rnd_v3_zyx(&rng, -10, 10);
        float rad = (float)exp(rnd(&rng, log(0.01), log(5.0)));
        Vec3 o = rnd_v3_zyx(&rng, -30, 30);
        if (v3_length(v3_sub(o, cc)) < 1.5f * rad) continue;
        /* Aim at a point within 0.9 radius of the centre so the ray clearly hits. */
        Vec3 off = rnd_v3_zyx(&rng, -0.5, 0.5);
        Vec3 aim = v3_add(cc, v3(off.x * rad, off.y * rad, off.z * rad));
        Ray rr = ray_to(o, v3_sub(aim, o), 0.0f, INFINITY);
        double fx = (double)o.x - (double)cc.x, fy = (double)o.y - (double)cc.y, fz = (double)o.z - (double)cc.z;
        double dx = (double)rr.d.x, dy = (double)rr.d.y, dz = (double)rr.d.z;
        double b = fx * dx + fy * dy + fz * dz;
        double dd = dx * dx + dy * dy + dz * dz;
        double cq = fx * fx + fy * fy + fz * fz - (double)rad * (double)rad;
        double disc = b * b - dd * cq;
        assert_true(disc > 0.0);
        double t_ref = (-b - sqrt(disc)) / dd;
        float tt = -1.0f;
        if (!sphere_intersect(cc, rad, &rr, &tt)) fail_msg("ray %d missed a sphere it aims into", i);
        assert_rel(tt, t_ref, 1e-5);
    }
}

static void test_sphere_origin_inside(void **state)
{
    (void)state;
    Vec3 c = v3(0.0f, 0.0f, 0.0f);
    float t = -1.0f;
    Ray r = ray_to(v3(0.5f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(c, 2.0f, &r, &t));
    assert_rel(t, 1.5, 1e-6); /* the root at -2.5 is behind: far root */
    r = ray_to(v3(0.5f, 0.0f, 0.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(c, 2.0f, &r, &t));
    assert_rel(t, 2.5, 1e-6);
    /* From the exact centre, every direction exits at the radius. */
    r = ray_to(c, v3(1.0f, -2.0f, 3.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(c, 2.0f, &r, &t));
    assert_rel(t, 2.0, 1e-6);
}

static void test_sphere_behind_misses(void **state)
{
    (void)state;
    float t = -1.0f;
    Ray r = ray_to(v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    assert_false(sphere_intersect(v3(0.0f, 0.0f, -5.0f), 1.0f, &r, &t));
    /* A sphere beside the ray misses too. */
    assert_false(sphere_intersect(v3(3.0f, 0.0f, 5.0f), 1.0f, &r, &t));
    /* With t_min = 0 and negative t_min alike, roots at -6 and -4 are never returned
     * unless t_min admits them. */
    r.t_min = -10.0f;
    assert_true(sphere_intersect(v3(0.0f, 0.0f, -5.0f), 1.0f, &r, &t));
    assert_rel(t, -6.0, 1e-6);
}

static void test_sphere_tangent_consistent(void **state)
{
    (void)state;
    float t = -1.0f;
    /* Exactly tangent: discriminant 0, one double root at t = 5. */
    Ray r = ray_to(v3(1.0f, 0.0f, -5.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    bool hit = sphere_intersect(v3(0.0f, 0.0f, 0.0f), 1.0f, &r, &t);
    if (hit) { assert_true(isfinite(t)); assert_rel(t, 5.0, 1e-6); }

    /* Sweep the impact parameter across the radius: no NaN, a hit only when the ray
     * comes within the radius (up to rounding), a miss only when it does not, and every
     * reported hit point lies on the sphere. */
    int hits = 0, misses = 0;
    for (int i = -2000; i <= 2000; i++) {
        float off = 1.0f + (float)i * 1e-7f;
        Ray s = ray_to(v3(off, 0.0f, -5.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
        float ts = NAN;
        if (sphere_intersect(v3(0.0f, 0.0f, 0.0f), 1.0f, &s, &ts)) {
            hits++;
            assert_true(isfinite(ts));
            if (!((double)off <= 1.0 + 1e-6)) fail_msg("offset %.9g > radius hit", (double)off);
            /* disc = 1 - off^2 carries ~1e-7 of rounding, so sqrt(disc) ~3e-4. */
            assert_abs(ts, 5.0 - sqrt(fmax(0.0, 1.0 - (double)off * (double)off)), 1e-3);
        } else {
            misses++;
            if (!((double)off >= 1.0 - 1e-6)) fail_msg("offset %.9g < radius missed", (double)off);
        }
    }
    assert_true(hits > 0 && misses > 0);

    /* Grazing rays in random directions tangent to random spheres: finite or a miss. */
    Pcg32 rng;
    pcg32_seed(&rng, 7u, 9u);
    for (int i = 0; i < 20000; i++) {
        Vec3 d = v3_normalize(rnd_v3_zyx(&rng, -1, 1));
        Vec3 n = v3_normalize(v3_cross(d, v3(0.3f, 0.5f, 0.7f)));
        Vec3 cc = rnd_v3_zyx(&rng, -5, 5);
        float rad = (float)rnd(&rng, 0.1, 3.0);
        Vec3 o = v3_madd(v3_madd(cc, n, rad), d, -10.0f);
        Ray g = ray_make(o, d, 0.0f, INFINITY);
        float tg = NAN;
        if (sphere_intersect(cc, rad, &g, &tg)) {
            assert_true(isfinite(tg));
            assert_abs(tg, 10.0, 0.05 * (double)rad + 1e-2);
        }
    }
}

static void test_sphere_far_precision(void **state)
{
    (void)state;
    /* A unit sphere 1e5 away: the naive b^2 - c discriminant loses all of its digits
     * (b^2 ~ 1e10 in float), RTG eq. 7.5 keeps them. */
    float t = -1.0f;
    Ray r = ray_to(v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    assert_true(sphere_intersect(v3(0.0f, 0.0f, 1e5f), 1.0f, &r, &t));
    assert_rel(t, 1e5 - 1.0, 1e-4);
    assert_rel(t, 1e5 - 1.0, 1e-6); /* in fact close to float precision */

    /* Off-centre hits on far spheres in random directions, against double. */
    Pcg32 rng;
    pcg32_seed(&rng, 3u, 4u);
    for (int i = 0; i < 2000; i++) {
        Vec3 dir = v3_normalize(rnd_v3_zyx(&rng, -1, 1));
        Vec3 cc = v3_scale(dir, 1e5f);
        /* Aim at a point up to 0.9 off the centre, perpendicular to dir. */
        Vec3 side = v3_normalize(v3_cross(dir, v3(0.0f, 0.6f, 0.8f)));
        Vec3 aim = v3_madd(cc, side, (float)rnd(&rng, -0.9, 0.9));
        Ray rr = ray_to(v3(0.0f, 0.0f, 0.0f), aim, 0.0f, INFINITY);
        double fx = -(double)cc.x, fy = -(double)cc.y, fz = -(double)cc.z;
        double dx = (double)rr.d.x, dy = (double)rr.d.y, dz = (double)rr.d.z;
        double dd = dx * dx + dy * dy + dz * dz;
        double b = fx * dx + fy * dy + fz * dz;
        double px = fx - b / dd * dx, py = fy - b / dd * dy, pz = fz - b / dd * dz;
        double disc = 1.0 - (px * px + py * py + pz * pz);
        if (disc < 1e-3) continue; /* too close to tangent for a clean reference */
        double t_ref = (-b / dd - sqrt(disc / dd));
        float tt = -1.0f;
        if (!sphere_intersect(cc, 1.0f, &rr, &tt)) fail_msg("far ray %d missed", i);
        assert_rel(tt, t_ref, 1e-4);
    }
}

static void test_sphere_interval_clipping(void **state)
{
    (void)state;
    Vec3 c = v3(0.0f, 0.0f, 5.0f);
    float t = -1.0f;
    Ray r = ray_to(v3(0.0f, 0.0f, 0.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, 3.9f);
    assert_false(sphere_intersect(c, 1.0f, &r, &t)); /* both roots beyond t_max */
    r.t_max = 4.5f;
    assert_true(sphere_intersect(c, 1.0f, &r, &t));
    assert_rel(t, 4.0, 1e-6);
    r.t_min = 4.5f; r.t_max = 5.9f;
    assert_false(sphere_intersect(c, 1.0f, &r, &t)); /* between the roots */
    r.t_max = 7.0f;
    assert_true(sphere_intersect(c, 1.0f, &r, &t));
    assert_rel(t, 6.0, 1e-6);
    r.t_min = 6.5f;
    assert_false(sphere_intersect(c, 1.0f, &r, &t)); /* past both roots */
    /* The interval is open: a root exactly at t_max or t_min is not a hit. */
    r.t_min = 0.0f; r.t_max = 4.0f;
    assert_false(sphere_intersect(c, 1.0f, &r, &t));
    r.t_min = 4.0f; r.t_max = 5.0f;
    assert_false(sphere_intersect(c, 1.0f, &r, &t));
}

/* ------------------------------------------------------------------ triangle */

static const Vec3 TV0 = {0.0f, 0.0f, 0.0f}, TV1 = {1.0f, 0.0f, 0.0f}, TV2 = {0.0f, 1.0f, 0.0f};

static bool tri_hit(Vec3 o, Vec3 d, float t_min, float t_max, float *t, float *u, float *v)
{
    Ray r = ray_make(o, d, t_min, t_max);
    return triangle_intersect_mt(TV0, v3_sub(TV1, TV0), v3_sub(TV2, TV0), &r, t, u, v);
}

static void test_triangle_center_hit(void **state)
{
    (void)state;
    float t = 0.0f, u = 0.0f, v = 0.0f;
    assert_true(tri_hit(v3(1.0f / 3.0f, 1.0f / 3.0f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_rel(t, 1.0, 1e-6);
    assert_rel(u, 1.0 / 3.0, 1e-6);
    assert_rel(v, 1.0 / 3.0, 1e-6);
    assert_true(tri_hit(v3(0.25f, 0.5f, 2.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_rel(t, 2.0, 1e-6);
    assert_rel(u, 0.25, 1e-6); /* u weights v1 = (1,0,0): u = x */
    assert_rel(v, 0.5, 1e-6);  /* v weights v2 = (0,1,0): v = y */

    /* Random triangles, random interior points, random directions: t, u, v vs exact. */
    Pcg32 rng;
    pcg32_seed(&rng, 11u, 12u);
    for (int i = 0; i < 20000; i++) {
        Vec3 a = rnd_v3_zyx(&rng, -5, 5);
        Vec3 e1 = rnd_v3_zyx(&rng, -2, 2);
        Vec3 e2 = rnd_v3_zyx(&rng, -2, 2);
        Vec3 n = v3_cross(e1, e2);
        if (v3_length(n) < 0.1f) continue;
        double bu = rnd(&rng, 0.02, 0.96), bv = rnd(&rng, 0.02, 0.98 - bu);
        Vec3 p = v3_add(a, v3_add(v3_scale(e1, (float)bu), v3_scale(e2, (float)bv)));
        Vec3 d = v3_normalize(rnd_v3_zyx(&rng, -1, 1));
        if (fabsf(v3_dot(d, v3_normalize(n))) < 0.05f) continue; /* keep away from grazing */
        float t_ref = (float)rnd(&rng, 0.1, 20.0);
        Ray r = ray_make(v3_madd(p, d, -t_ref), d, 0.0f, INFINITY);
        float tr = 0.0f, ur = 0.0f, vr = 0.0f;
        if (!triangle_intersect_mt(a, e1, e2, &r, &tr, &ur, &vr)) fail_msg("random ray %d missed", i);
        assert_abs(tr, t_ref, 1e-4 * (double)t_ref + 1e-4);
        assert_abs(ur, bu, 2e-4);
        assert_abs(vr, bv, 2e-4);
    }
}

static void test_triangle_behind_rejected(void **state)
{
    (void)state;
    float t = 0.0f, u = 0.0f, v = 0.0f;
    /* The plane is at t = -1. */
    assert_false(tri_hit(v3(0.25f, 0.25f, -1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_false(tri_hit(v3(0.25f, 0.25f, 1.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY, &t, &u, &v));
    /* ... unless t_min admits negative t. */
    assert_true(tri_hit(v3(0.25f, 0.25f, 1.0f), v3(0.0f, 0.0f, 1.0f), -2.0f, INFINITY, &t, &u, &v));
    assert_rel(t, -1.0, 1e-6);
    /* Outside the triangle's extent in front of the ray. */
    assert_false(tri_hit(v3(0.75f, 0.75f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_false(tri_hit(v3(-0.1f, 0.5f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
}

static void test_triangle_parallel_misses(void **state)
{
    (void)state;
    float t = 0.0f, u = 0.0f, v = 0.0f;
    /* Parallel, above the plane. */
    assert_false(tri_hit(v3(-1.0f, 0.2f, 1.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &t, &u, &v));
    /* Parallel and in the plane, crossing the triangle: det == 0, documented as a miss
     * (no well-defined t; the neighbours sharing the edges take such rays). */
    assert_false(tri_hit(v3(-1.0f, 0.2f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_false(tri_hit(v3(-1.0f, -1.0f, 0.0f), v3_normalize(v3(1.0f, 1.0f, 0.0f)), 0.0f, INFINITY, &t, &u, &v));
    /* In the plane, along an edge. */
    assert_false(tri_hit(v3(-1.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &t, &u, &v));
}

static void test_triangle_edges_and_vertices(void **state)
{
    (void)state;
    /* With exactly representable geometry the barycentrics come out exact and the
     * closed intervals u, v >= 0, u + v <= 1 make every edge and vertex a hit. With
     * rounding this is NOT guaranteed (Moller-Trumbore is not watertight); test_accel_conformance's
     * closed-mesh test covers shared edges under rounding. */
    const struct { float x, y; float u, v; const char *what; } pts[] = {
        {0.0f, 0.0f, 0.0f, 0.0f, "vertex v0"},
        {1.0f, 0.0f, 1.0f, 0.0f, "vertex v1"},
        {0.0f, 1.0f, 0.0f, 1.0f, "vertex v2"},
        {0.5f, 0.0f, 0.5f, 0.0f, "edge v0v1 (v = 0)"},
        {0.0f, 0.5f, 0.0f, 0.5f, "edge v0v2 (u = 0)"},
        {0.5f, 0.5f, 0.5f, 0.5f, "edge v1v2 (u + v = 1)"},
        {0.25f, 0.75f, 0.25f, 0.75f, "edge v1v2 (u + v = 1)"},
    };
    for (size_t i = 0; i < sizeof pts / sizeof pts[0]; i++) {
        float ti = 0.0f, ui = 0.0f, vi = 0.0f;
        for (int side = 0; side < 2; side++) {
            float z = side ? -1.0f : 1.0f;
            if (!tri_hit(v3(pts[i].x, pts[i].y, z), v3(0.0f, 0.0f, -z), 0.0f, INFINITY, &ti, &ui, &vi))
                fail_msg("%s missed from %s", pts[i].what, side ? "below" : "above");
            assert_rel(ti, 1.0, 0.0);
            assert_abs(ui, pts[i].u, 0.0);
            assert_abs(vi, pts[i].v, 0.0);
        }
    }
    /* Just outside each edge: a miss. */
    float t = 0.0f, u = 0.0f, v = 0.0f;
    assert_false(tri_hit(v3(0.5f, -1e-6f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_false(tri_hit(v3(-1e-6f, 0.5f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
    assert_false(tri_hit(v3(0.5f, 0.5f + 1e-6f, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t, &u, &v));
}

static void test_triangle_two_sided(void **state)
{
    (void)state;
    float t1 = 0.0f, u1 = 0.0f, v1 = 0.0f, t2 = 0.0f, u2 = 0.0f, v2 = 0.0f;
    assert_true(tri_hit(v3(0.2f, 0.3f, 2.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY, &t1, &u1, &v1));
    assert_true(tri_hit(v3(0.2f, 0.3f, -2.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY, &t2, &u2, &v2));
    assert_rel(t1, 2.0, 1e-6);
    assert_rel(t2, 2.0, 1e-6);
    assert_rel(u1, u2, 1e-6);
    assert_rel(v1, v2, 1e-6);
    /* The reversed winding (v0, v2, v1) is hit from both sides as well, u and v swap. */
    Ray r = ray_make(v3(0.2f, 0.3f, 2.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(triangle_intersect_mt(TV0, v3_sub(TV2, TV0), v3_sub(TV1, TV0), &r, &t1, &u1, &v1));
    assert_rel(u1, 0.3, 1e-6);
    assert_rel(v1, 0.2, 1e-6);
    r = ray_make(v3(0.2f, 0.3f, -2.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, INFINITY);
    assert_true(triangle_intersect_mt(TV0, v3_sub(TV2, TV0), v3_sub(TV1, TV0), &r, &t1, &u1, &v1));
}

static void test_triangle_interval_clipping(void **state)
{
    (void)state;
    float t = 0.0f, u = 0.0f, v = 0.0f;
    Vec3 o = v3(0.25f, 0.25f, 1.0f), d = v3(0.0f, 0.0f, -1.0f);
    assert_false(tri_hit(o, d, 0.0f, 0.5f, &t, &u, &v));
    assert_false(tri_hit(o, d, 0.0f, 1.0f, &t, &u, &v)); /* open interval: t == t_max misses */
    assert_true(tri_hit(o, d, 0.0f, 1.0001f, &t, &u, &v));
    assert_false(tri_hit(o, d, 1.0f, 2.0f, &t, &u, &v)); /* t == t_min misses */
    assert_true(tri_hit(o, d, 0.9999f, 2.0f, &t, &u, &v));
    assert_false(tri_hit(o, d, 1.5f, 2.0f, &t, &u, &v));
}

/* ------------------------------------------------------------------ slab test */

static const BBox BOX = {{-1.0f, -1.0f, -1.0f}, {1.0f, 1.0f, 1.0f}};

static bool slab(Vec3 o, Vec3 d, float t_min, float t_max, float *t_enter)
{
    return bbox_intersect(BOX, o, d, t_min, t_max, t_enter);
}

/* ray_inv_dir4 (the BVH's reciprocal): exact where 1/d is finite and the components
 * below 1e-20 (zeros too) mapped to +-1e20 with the component's sign, never inf or NaN. */
static Vec3 inv_dir(Vec3 d)
{
    float r[4];
    _mm_storeu_ps(r, ray_inv_dir4(_mm_setr_ps(d.x, d.y, d.z, 1.0f)));
    return v3(r[0], r[1], r[2]);
}

static void test_ray_inv_dir(void **state)
{
    (void)state;
    Vec3 inv = inv_dir(v3(2.0f, -0.5f, 3.0f));
    assert_true(inv.x == 0.5f && inv.y == -2.0f && inv.z == 1.0f / 3.0f);
    const float big = 1.0f / 1e-20f;
    inv = inv_dir(v3(0.0f, -0.0f, 1.0f));
    assert_true(inv.x == big && inv.y == -big && inv.z == 1.0f);
    inv = inv_dir(v3(1e-30f, -1e-30f, 1e-45f)); /* tiny and denormal components too */
    assert_true(inv.x == big && inv.y == -big && inv.z == big);
    inv = inv_dir(v3(1e-20f, -2e-20f, 3.0e-7f)); /* at and above the threshold: exact */
    assert_true(inv.x == 1.0f / 1e-20f && inv.y == 1.0f / -2e-20f && inv.z == 1.0f / 3.0e-7f);
    /* (bound - o) * inv is never NaN, also for an origin on the bound. */
    float zero = 1.0f - 1.0f;
    assert_false(isnan(zero * inv.x));
}

static void test_slab_zero_direction_components(void **state)
{
    (void)state;
    float te;
    for (int s = 0; s < 2; s++) {
        float z0 = s ? -0.0f : 0.0f; /* both signs of zero */
        /* Axis-parallel ray, origin inside the x and y slabs. */
        assert_true(slab(v3(0.5f, -0.5f, -5.0f), v3(z0, z0, 1.0f), 0.0f, INFINITY, &te));
        assert_rel(te, 4.0, 1e-6);
        assert_true(slab(v3(0.5f, -0.5f, 5.0f), v3(z0, z0, -1.0f), 0.0f, INFINITY, &te));
        assert_rel(te, 4.0, 1e-6);
        /* Origin outside the x slab with d.x = 0: never enters, however long the ray. */
        assert_false(slab(v3(1.5f, 0.0f, -5.0f), v3(z0, z0, 1.0f), 0.0f, INFINITY, &te));
        assert_false(slab(v3(-1.0001f, 0.0f, -5.0f), v3(z0, z0, 1.0f), 0.0f, INFINITY, &te));
        assert_false(slab(v3(0.0f, 1e6f, -5.0f), v3(z0, z0, 1.0f), 0.0f, INFINITY, &te));
        /* One zero component, the other two not. */
        assert_true(slab(v3(0.3f, -5.0f, -5.0f), v3_normalize(v3(z0, 1.0f, 1.0f)), 0.0f, INFINITY, &te));
        assert_rel(te, 4.0 * sqrt(2.0), 1e-6);
        assert_false(slab(v3(3.0f, -5.0f, -5.0f), v3_normalize(v3(z0, 1.0f, 1.0f)), 0.0f, INFINITY, &te));
    }
}

static void test_slab_origin_on_plane_zero_direction(void **state)
{
    (void)state;
    /* bbox_intersect promises that a zero direction component constrains nothing when
     * the origin lies in the slab, boundary included: a ray lying in a face plane is
     * inside, for either bounding plane and either sign of zero (the box is closed). */
    float te;
    for (int s = 0; s < 2; s++) {
        float z0 = s ? -0.0f : 0.0f;
        for (int pl = 0; pl < 2; pl++) {
            float x = pl ? 1.0f : -1.0f;
            const char *plane = pl ? "max" : "min";
            /* Origin outside along z, entering later: t_enter = 4. */
            if (!slab(v3(x, 0.0f, -5.0f), v3(z0, 0.0f, 1.0f), 0.0f, INFINITY, &te))
                fail_msg("ray in the x = %s plane, d.x = %s0, missed", plane, s ? "-" : "+");
            assert_rel(te, 4.0, 1e-6);
            /* Origin inside along y and z, t_min > 0. */
            if (!slab(v3(x, 0.0f, 0.0f), v3(z0, 0.0f, 1.0f), 0.1f, INFINITY, &te))
                fail_msg("ray from the x = %s face, d.x = %s0, t_min > 0, missed", plane, s ? "-" : "+");
            assert_rel(te, 0.1f, 0.0);
            /* Along an edge: in the x = +-1 and y = +-1 planes at once. */
            if (!slab(v3(x, x, -5.0f), v3(z0, z0, 1.0f), 0.0f, INFINITY, &te))
                fail_msg("ray along the (%s, %s) edge missed", plane, plane);
            assert_rel(te, 4.0, 1e-6);
        }
    }
}

static void test_slab_origin_inside(void **state)
{
    (void)state;
    float te = -1.0f;
    assert_true(slab(v3(0.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));
    assert_rel(te, 0.0, 0.0);
    assert_true(slab(v3(0.2f, -0.3f, 0.4f), v3_normalize(v3(1.0f, 2.0f, -3.0f)), 0.25f, INFINITY, &te));
    assert_rel(te, 0.25, 0.0); /* t_enter clamps to t_min */
    /* Inside but with the whole interval past the exit (x exits at t = 1). */
    assert_false(slab(v3(0.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 1.5f, INFINITY, &te));
}

static void test_slab_negative_directions_and_behind(void **state)
{
    (void)state;
    float te;
    assert_true(slab(v3(5.0f, 0.0f, 0.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));
    assert_rel(te, 4.0, 1e-6);
    assert_true(slab(v3(3.0f, 3.0f, 3.0f), v3_normalize(v3(-1.0f, -1.0f, -1.0f)), 0.0f, INFINITY, &te));
    assert_rel(te, 2.0 * sqrt(3.0), 1e-6);
    assert_true(slab(v3(3.0f, -3.0f, 0.5f), v3_normalize(v3(-1.0f, 1.0f, 0.0f)), 0.0f, INFINITY, &te));
    assert_rel(te, 2.0 * sqrt(2.0), 1e-6);
    /* Box behind the ray. */
    assert_false(slab(v3(5.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));
    assert_false(slab(v3(-3.0f, -3.0f, -3.0f), v3_normalize(v3(-1.0f, -1.0f, -1.0f)), 0.0f, INFINITY, &te));
    /* Box beyond t_max, then just within it. */
    assert_false(slab(v3(5.0f, 0.0f, 0.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, 3.9f, &te));
    assert_true(slab(v3(5.0f, 0.0f, 0.0f), v3(-1.0f, 0.0f, 0.0f), 0.0f, 4.0f, &te));
    /* A line that passes beside the box. */
    assert_false(slab(v3(3.0f, -3.0f, 0.5f), v3_normalize(v3(-1.0f, 3.0f, 0.0f)), 0.0f, INFINITY, &te));
}

static void test_slab_grazing(void **state)
{
    (void)state;
    float te;
    /* Along the y = +1 face (d.y = 0 exactly), diagonally within the face plane, and
     * through an edge and a corner exactly: the box is closed, all are hits. */
    assert_true(slab(v3(-5.0f, 1.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));
    assert_rel(te, 4.0, 1e-6);
    assert_true(slab(v3(-5.0f, -1.0f, 0.5f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));
    assert_true(slab(v3(-3.0f, 1.0f, -2.5f), v3_normalize(v3(1.0f, 0.0f, 1.0f)), 0.0f, INFINITY, &te));
    assert_true(slab(v3(-1.0f, -3.0f, 0.0f), v3_normalize(v3(1.0f, 1.0f, 0.0f)), 0.0f, INFINITY, &te));
    assert_rel(te, 2.0 * sqrt(2.0), 1e-6); /* touches the edge x = 1, y = -1 only */
    assert_true(slab(v3(-1.0f, -3.0f, -3.0f), v3_normalize(v3(1.0f, 1.0f, 1.0f)), 0.0f, INFINITY, &te));
    /* Just beside the face: a miss. */
    assert_false(slab(v3(-5.0f, 1.0001f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY, &te));

    /* Rays from random origins toward random points on the box surface, up to 1e-4
     * inside, always hit (Ize's conservative t_far). Rays parallel to a face 1e-3
     * outside it (a zero direction component), or leaving that face's half-space,
     * never hit. */
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 6u);
    for (int i = 0; i < 100000; i++) {
        int axis = (int)(pcg32_next(&rng) % 3u);
        float side = (pcg32_next(&rng) & 1u) ? 1.0f : -1.0f;
        float p[3]; /* in sequence, x first (an initializer list's order is not specified either) */
        for (int a = 0; a < 3; a++) p[a] = (float)rnd(&rng, -1, 1);
        p[axis] = side * (1.0f - 1e-4f);
        Vec3 o = rnd_v3_zyx(&rng, -20, 20);
        Vec3 d = v3_normalize(v3_sub(v3(p[0], p[1], p[2]), o));
        if (!slab(o, d, 0.0f, INFINITY, &te)) fail_msg("ray %d toward a surface point missed", i);

        float oc[3], dc[3];
        for (int a = 0; a < 3; a++) oc[a] = (float)rnd(&rng, -20, 20);
        for (int a = 0; a < 3; a++) dc[a] = (float)rnd(&rng, -1, 1);
        oc[axis] = side * 1.001f;
        dc[axis] = 0.0f;
        if (slab(v3(oc[0], oc[1], oc[2]), v3(dc[0], dc[1], dc[2]), 0.0f, INFINITY, &te))
            fail_msg("ray %d parallel to a face, 1e-3 outside it, hit", i);
        dc[axis] = side * (float)rnd(&rng, 1e-3, 1.0);
        if (slab(v3(oc[0], oc[1], oc[2]), v3_normalize(v3(dc[0], dc[1], dc[2])), 0.0f, INFINITY, &te))
            fail_msg("ray %d leaving a face's half-space hit", i);
    }
}

/* ------------------------------------------------------------------ ray offsets */

/* ray_offset_origin (three lanes at once) is ray_offset_coord on each coordinate, bit for
 * bit: both regimes (ulps away from the origin, a fixed step near it), the boundary at
 * 2048 near, negative coordinates, signed zeros, and normals of either sign, for the
 * smallest near and for larger scenes' ones. */
static void test_offset_origin_matches_scalar(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 83u, 1u);
    const float nears[3] = {RAY_OFFSET_NEAR_MIN, 2.2239e-4f, 1e-3f};
    for (int ni = 0; ni < 3; ni++) {
        const float near = nears[ni], edge = 2048.0f * near;
        const float special[] = {0.0f, -0.0f, edge, -edge, nextafterf(edge, 0.0f), nextafterf(-edge, 0.0f),
                                 1e-30f, 548.8f};
        for (int i = 0; i < 100000; i++) {
            float pc[3], nc[3];
            for (int a = 0; a < 3; a++) {
                int kind = (int)(pcg32_next(&rng) % 4u);
                pc[a] = kind == 0   ? special[pcg32_next(&rng) % 8u]
                        : kind == 1 ? (float)rnd(&rng, -2.0 * (double)edge, 2.0 * (double)edge)
                                    : (float)rnd(&rng, -600.0, 600.0);
                nc[a] = (float)rnd(&rng, -1.0, 1.0);
            }
            Vec3 p = v3(pc[0], pc[1], pc[2]), n = v3(nc[0], nc[1], nc[2]);
            Vec3 got = ray_offset_origin(p, n, near);
            Vec3 want = v3(ray_offset_coord(p.x, n.x, near), ray_offset_coord(p.y, n.y, near),
                           ray_offset_coord(p.z, n.z, near));
            if (memcmp(&got, &want, sizeof got) != 0)
                fail_msg("near %g, p (%.9g, %.9g, %.9g), n (%g, %g, %g): (%.9g, %.9g, %.9g) against (%.9g, %.9g, %.9g)",
                         (double)near, (double)p.x, (double)p.y, (double)p.z, (double)n.x, (double)n.y, (double)n.z,
                         (double)got.x, (double)got.y, (double)got.z, (double)want.x, (double)want.y, (double)want.z);
        }
    }
}

/* A scene's offset near the origin grows with its size: a ray leaving a 1000-unit floor
 * at y = 0 starts above that floor's BVH box (widened by 1e-7 of the largest coordinate,
 * bvh.c) instead of inside it, and does not hit the floor; a unit-sized scene keeps Ray
 * Tracing Gems' 2^-16. */
static void test_scene_offset_near_scales(void **state)
{
    (void)state;
    CstError err;
    for (int big = 0; big < 2; big++) {
        const double h = big ? 500.0 : 0.5;
        Scene *s = scene_create();
        assert_non_null(s);
        int mat;
        Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
        assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
        const float hf = (float)h;
        const Vec3 floor[4] = {{-hf, 0, -hf}, {-hf, 0, hf}, {hf, 0, hf}, {hf, 0, -hf}};
        assert_int_equal(scene_add_quad(s, floor, mat, NULL, &err), CST_OK);
        assert_int_equal(scene_add_sphere(s, v3(0, 0.5f * hf, 0), 0.1f * hf, mat, NULL, &err), CST_OK);
        assert_int_equal(scene_commit(s, &err), CST_OK);
        if (!big) {
            assert_true(s->offset_near == RAY_OFFSET_NEAR_MIN);
        } else {
            assert_rel(s->offset_near, 4e-7 * 500.0, 1e-6);
            Pcg32 rng;
            pcg32_seed(&rng, 84u, 1u);
            for (int i = 0; i < 1000; i++) {
                float pz = (float)rnd(&rng, -0.9 * h, 0.9 * h), px = (float)rnd(&rng, -0.9 * h, 0.9 * h);
                Vec3 p = v3(px, 0.0f, pz);
                float dz = (float)rnd(&rng, -1, 1), dy = (float)rnd(&rng, 0.01, 1), dx = (float)rnd(&rng, -1, 1);
                Vec3 d = v3_normalize(v3(dx, dy, dz));
                Vec3 o = scene_offset(s, p, v3(0, 1, 0), d);
                if (!(o.y > 1e-7f * 500.0f)) fail_msg("offset point %g above the floor, inside its box", (double)o.y);
                SurfaceHit sh;
                Ray r = ray_make(o, d, 0.0f, INFINITY);
                if (scene_intersect(s, &r, &sh) && sh.prim < 2)
                    fail_msg("ray %d re-hit the floor at t = %g", i, (double)sh.t);
            }
        }
        scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_outside_nearest_root),
        cmocka_unit_test(test_sphere_origin_inside),
        cmocka_unit_test(test_sphere_behind_misses),
        cmocka_unit_test(test_sphere_tangent_consistent),
        cmocka_unit_test(test_sphere_far_precision),
        cmocka_unit_test(test_sphere_interval_clipping),
        cmocka_unit_test(test_triangle_center_hit),
        cmocka_unit_test(test_triangle_behind_rejected),
        cmocka_unit_test(test_triangle_parallel_misses),
        cmocka_unit_test(test_triangle_edges_and_vertices),
        cmocka_unit_test(test_triangle_two_sided),
        cmocka_unit_test(test_triangle_interval_clipping),
        cmocka_unit_test(test_ray_inv_dir),
        cmocka_unit_test(test_slab_zero_direction_components),
        cmocka_unit_test(test_slab_origin_on_plane_zero_direction),
        cmocka_unit_test(test_slab_origin_inside),
        cmocka_unit_test(test_slab_negative_directions_and_behind),
        cmocka_unit_test(test_slab_grazing),
        cmocka_unit_test(test_offset_origin_matches_scalar),
        cmocka_unit_test(test_scene_offset_near_scales),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
