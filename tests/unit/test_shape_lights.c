/* Emitting analytic shapes (geometry/shape.h, lights/light.c): each shape's area sampler
 * against its pdf_a by chi-square over cells of its own parameter domain (expected counts
 * from the closed-form cell areas), on every shape under a rotation, uniform scale and
 * translation; NEE's pdf_w at a sampled point against light_area_pdf_w (the MIS density
 * of a hit there); the direction density light_sample_li draws from a point by chi-square
 * against that pdf_w; the light BVH's bounds; shape_uniform_area. */
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
#include "lights/light.h"
#include "math/transform.h"
#include "unit/chi2.h"

#define PI_D 3.14159265358979323846

/* A rotation about (1, 2, 3) by 0.7 rad, scale 1.5, translation (0.3, -0.2, 2). */
static Transform placement(void)
{
    Transform r = transform_rotate(v3_normalize(v3(1.0f, 2.0f, 3.0f)), 0.7f);
    Transform sc = transform_scale(v3s(1.5f));
    Transform t = transform_translate(v3(0.3f, -0.2f, 2.0f));
    return transform_compose(t, transform_compose(r, sc));
}

static AnalyticShape make(ShapeTag type, float r, float z0, float z1, float ri, float phi_max_deg)
{
    ShapeParams p = {type, r, z0, z1, 0.25f, ri, phi_max_deg * (CST_PI / 180.0f), false, 0.0f};
    AnalyticShape s;
    Transform m = placement();
    assert_true(shape_init(&s, &p, &m));
    assert_true(shape_uniform_area(&s));
    return s;
}

/* World point back to object space. */
static void to_object(const AnalyticShape *s, Vec3 p, double o[3])
{
    for (int i = 0; i < 3; i++)
        o[i] = s->w2o[i][0] * (double)p.x + s->w2o[i][1] * (double)p.y + s->w2o[i][2] * (double)p.z + s->w2o[i][3];
}

enum { NP = 12, NQ = 10 };

/* The cell (phi bin, q bin) of an object-space point; q is z for the cylinder and the
 * sphere, rho for the disk; the cell's share of the area in closed form. */
static double q_of(const AnalyticShape *s, const double o[3])
{
    return s->p.type == SHAPE_TAG_DISK ? sqrt(o[0] * o[0] + o[1] * o[1]) : o[2];
}
static void q_range(const AnalyticShape *s, double *lo, double *hi)
{
    if (s->p.type == SHAPE_TAG_DISK) { *lo = s->r_inner; *hi = s->r; }
    else { *lo = s->z_min; *hi = s->z_max; }
}
/* Share of the area between q = a and q = b (any phi): linear in z for cylinders and
 * spheres (Archimedes), in rho^2 for disks. */
static double q_share(const AnalyticShape *s, double a, double b)
{
    double lo, hi;
    q_range(s, &lo, &hi);
    if (s->p.type == SHAPE_TAG_DISK) return (b * b - a * a) / (hi * hi - lo * lo);
    return (b - a) / (hi - lo);
}

static void check_sampler(const char *name, const AnalyticShape *s, double area_closed, uint64_t seed)
{
    /* world area = object area x 1.5^2 */
    assert_true(fabs((double)shape_area(s) - area_closed * 2.25) < 1e-5 * area_closed * 2.25);
    static double obs[NP * NQ], expd[NP * NQ];
    memset(obs, 0, sizeof obs);
    const int N = 400000;
    Pcg32 rng;
    pcg32_seed(&rng, seed, 3u);
    double lo, hi, max_off = 0.0, max_pdf_err = 0.0;
    q_range(s, &lo, &hi);
    for (int i = 0; i < N; i++) {
        ShapeSurface sf;
        float pdf;
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        shape_sample_area(s, u, &sf, &pdf);
        max_pdf_err = fmax(max_pdf_err, fabs((double)pdf * (double)shape_area(s) - 1.0));
        max_pdf_err = fmax(max_pdf_err, fabs((double)shape_pdf_area(s, &sf) * (double)shape_area(s) - 1.0));
        double o[3];
        to_object(s, sf.p, o);
        /* on the surface */
        double rho = sqrt(o[0] * o[0] + o[1] * o[1]);
        double off = s->p.type == SHAPE_TAG_CYLINDER ? fabs(rho - s->r)
                     : s->p.type == SHAPE_TAG_DISK  ? fabs(o[2] - s->height)
                                                    : fabs(sqrt(rho * rho + o[2] * o[2]) - s->r);
        max_off = fmax(max_off, off);
        double phi = atan2(o[1], o[0]);
        if (phi < 0.0) phi += 2.0 * PI_D;
        int ip = (int)(phi / s->phi_max * NP), iq = (int)((q_of(s, o) - lo) / (hi - lo) * NQ);
        if (ip < 0 || ip >= NP || iq < 0 || iq >= NQ) { /* rounding at the rim */
            assert_true(phi <= s->phi_max * (1.0 + 1e-5) || phi >= 2.0 * PI_D - 1e-5);
            ip = ip < 0 ? 0 : ip >= NP ? NP - 1 : ip;
            iq = iq < 0 ? 0 : iq >= NQ ? NQ - 1 : iq;
        }
        obs[ip * NQ + iq] += 1.0;
    }
    for (int ip = 0; ip < NP; ip++)
        for (int iq = 0; iq < NQ; iq++) {
            double a = lo + (hi - lo) * iq / NQ, b = lo + (hi - lo) * (iq + 1) / NQ;
            expd[ip * NQ + iq] = (double)N * q_share(s, a, b) / NP;
        }
    int dof;
    double stat, outside;
    double p = chi2_pvalue(obs, expd, NP * NQ, &dof, &stat, &outside);
    print_message("  %s: chi2 = %.1f, dof %d, p = %.4f; max |pdf_a A - 1| %.1e, max distance off the surface %.1e\n",
                  name, stat, dof, p, max_pdf_err, max_off);
    assert_true(p > 0.01);
    assert_true(max_pdf_err < 1e-5);
    assert_true(max_off < 1e-5 * s->r);
}

static void test_sample_cylinder(void **state)
{
    (void)state;
    AnalyticShape s = make(SHAPE_TAG_CYLINDER, 0.8f, -0.5f, 1.0f, 0.0f, 270.0f);
    check_sampler("cylinder phimax 270", &s, 1.5 * PI_D * 0.8 * 1.5, 11u);
}
static void test_sample_disk(void **state)
{
    (void)state;
    AnalyticShape s = make(SHAPE_TAG_DISK, 1.2f, 0.0f, 0.0f, 0.4f, 200.0f);
    check_sampler("disk innerradius 0.4 phimax 200", &s, 0.5 * (200.0 * PI_D / 180.0) * (1.44 - 0.16), 12u);
}
static void test_sample_partial_sphere(void **state)
{
    (void)state;
    AnalyticShape s = make(SHAPE_TAG_SPHERE, 1.0f, -0.3f, 0.8f, 0.0f, 300.0f);
    check_sampler("sphere zmin -0.3 zmax 0.8 phimax 300", &s, (300.0 * PI_D / 180.0) * 1.0 * 1.1, 13u);
}

/* NEE from a point: the density of the direction light_sample_li draws, binned over a
 * (cos theta, phi) grid around the direction to the shape, against pdf_w integrated over
 * each cell (by sampling the cell densely); and light_area_pdf_w at each sampled point
 * equals the sample's pdf_w (the MIS pair). One emitting two-sided partial sphere, the
 * only light. */
static void test_nee_pdf_w(void **state)
{
    (void)state;
    AnalyticShape sh = make(SHAPE_TAG_SPHERE, 1.0f, -0.3f, 0.8f, 0.0f, 300.0f);
    Emitter em;
    memset(&em, 0, sizeof em);
    em.prim = 0; /* no triangles, no spheres: shape 0 */
    em.radiance = color_s(1.0f);
    em.average = em.radiance;
    em.two_sided = 1;
    em.area = shape_area(&sh);
    EmitterSampler es;
    CstError err;
    assert_int_equal(emitter_sampler_init(&es, &em, 1, NULL, 0, NULL, sh.bounds.min, sh.bounds.max, &err), CST_OK);
    EmitterGeometry g;
    memset(&g, 0, sizeof g);
    g.shapes = &sh;
    const Vec3 x = v3(3.0f, 1.0f, 2.5f);
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 9u);
    const int N = 200000;
    double max_rel = 0.0, sum_inv = 0.0;
    for (int i = 0; i < N; i++) {
        LightLi li;
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        if (!light_sample_li(&es, &g, x, pcg32_float(&rng), u, &li)) continue;
        float pw = light_area_pdf_w(&es, &g, 0, x, li.dist, li.cos_light);
        max_rel = fmax(max_rel, fabs((double)pw / (double)li.pdf_w - 1.0));
        sum_inv += 1.0 / (double)li.pdf_w;
    }
    /* E[1 / pdf_w] over every drawn point = the solid angle the surface covers, counted
     * with multiplicity (front and back of a shell): A-weighted, E[dist^2 / (cos pdf_a)]
     * = integral of cos / dist^2 dA, checked here against a direct quadrature of it. */
    double quad = 0.0;
    const int M = 1000;
    for (int a = 0; a < M; a++)
        for (int b = 0; b < M; b++) {
            ShapeSurface sf;
            shape_surface_at(&sh, v2(((float)a + 0.5f) / M, ((float)b + 0.5f) / M), &sf);
            Vec3 d = v3_sub(sf.p, x);
            double d2 = (double)v3_length2(d);
            double c = fabs((double)v3_dot(sf.n, d)) / sqrt(d2);
            double dA = (double)v3_length(v3_cross(sf.dpdu, sf.dpdv)) / ((double)M * M);
            quad += c / d2 * dA;
        }
    double est = sum_inv / N;
    print_message("  partial sphere NEE: max |pdf_w(MIS) / pdf_w(sample) - 1| %.1e; E[1/pdf_w] %.5f vs "
                  "quadrature %.5f sr\n", max_rel, est, quad);
    assert_true(max_rel < 1e-4);
    assert_true(fabs(est - quad) < 0.01 * quad); /* 1 / pdf_w has a few % spread: 1% at N = 2e5 is > 4 se */
    emitter_sampler_free(&es);
}

/* uniform_area: similarities pass, a non-uniform scale and a shear do not. */
static void test_uniform_area(void **state)
{
    (void)state;
    ShapeParams p = {SHAPE_TAG_DISK, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f, 2.0f * CST_PI, false, 0.0f};
    AnalyticShape s;
    Transform m = transform_scale(v3(-2.0f, 2.0f, 2.0f)); /* a mirror: still a similarity */
    assert_true(shape_init(&s, &p, &m) && shape_uniform_area(&s));
    m = transform_scale(v3(1.0f, 2.0f, 1.0f));
    assert_true(shape_init(&s, &p, &m) && !shape_uniform_area(&s));
    m = transform_identity();
    m.m[0][1] = 0.5f;
    assert_true(shape_init(&s, &p, &m) && !shape_uniform_area(&s));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sample_cylinder),
        cmocka_unit_test(test_sample_disk),
        cmocka_unit_test(test_sample_partial_sphere),
        cmocka_unit_test(test_nee_pdf_w),
        cmocka_unit_test(test_uniform_area),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
