/* Chi-square goodness-of-fit of the solid-angle samplers of sampling/spherical.h (spherical
 * triangles and rectangles) against their densities, 1 / solid angle per unit solid angle,
 * and their solid angles against a closed form. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "core/rng.h"
#include "sampling/spherical.h"
#include "unit/chi2.h"

#define PI_D 3.14159265358979323846

enum {
    SAMPLE_COUNT = 1000000, /* per chi-square test */
    GRID = 30,              /* cells per side */
    SUBCELLS = 8,           /* midpoint sub-samples per cell side for the expected counts */
    CHI2_TESTS = 7          /* the number of p-values corrected for */
};
static const double ALPHA = 0.01;
static double sidak_threshold(void) { return 1.0 - pow(1.0 - ALPHA, 1.0 / (double)CHI2_TESTS); }

/* A polygon seen from x: a triangle (p0, p1, p2) or a rectangle (corner p0, edges e1, e2).
 * The histogram is over the polygon itself, parameterised so that its edges are grid
 * lines: the rectangle by (s, t) in [0, 1]^2; the triangle by the Duffy square, b1 = gx,
 * b2 = gy (1 - gx). The density there is pdf_w d omega / dA dA / dgrid, with d omega / dA
 * = cos theta_l / d^2: smooth inside each cell, so the midpoint rule converges. */
typedef struct Poly {
    const char *name;
    bool rect;
    Vec3 x, p0, e1, e2; /* triangle: p1 = p0 + e1, p2 = p0 + e2 */
} Poly;

static const Poly POLYS[] = {
    /* large and close: about 1.4 sr */
    {"triangle near", false, {0.1f, 0.2f, 0.0f}, {-1.0f, -0.8f, 1.0f}, {2.2f, 0.3f, 0.1f}, {0.6f, 1.9f, -0.2f}},
    /* small, oblique: about 0.01 sr */
    {"triangle far", false, {0.0f, 0.0f, 0.0f}, {3.0f, 1.0f, 4.0f}, {0.5f, 0.0f, -0.4f}, {0.1f, 0.6f, 0.0f}},
    /* most of a hemisphere */
    {"triangle huge", false, {0.0f, 0.0f, 0.5f}, {-4.0f, -3.0f, 0.0f}, {9.0f, 0.0f, 0.0f}, {0.0f, 9.0f, 0.0f}},
    {"rectangle near", true, {0.3f, -0.2f, 0.5f}, {-1.0f, -1.5f, 1.2f}, {2.0f, 0.0f, 0.0f}, {0.0f, 1.0f, 1.0f}},
    {"rectangle far", true, {0.0f, 0.0f, 0.0f}, {2.0f, 3.0f, -5.0f}, {0.0f, 0.7f, 0.0f}, {0.0f, 0.0f, 0.4f}},
    /* tiny: about 5e-4 sr, just above NEE's switch to area sampling (SPH_MIN_SOLID_ANGLE),
     * where the warp's area A_hat = u.x A and its trigonometry are smallest */
    {"triangle tiny", false, {0.0f, 0.0f, 0.0f}, {3.0f, 1.0f, 4.0f}, {0.135f, 0.0f, -0.108f}, {0.027f, 0.162f, 0.0f}},
    /* near-grazing: x 0.05 above the triangle's plane, most directions a few degrees from it */
    {"triangle grazing", false, {0.0f, 0.0f, 0.05f}, {0.5f, -0.5f, 0.0f}, {1.5f, 0.0f, 0.0f}, {0.0f, 1.5f, 0.0f}},
};

static double poly_solid_angle(const Poly *pg, SphRect *r)
{
    if (pg->rect) {
        assert_true(sph_rect_init(r, pg->x, pg->p0, pg->e1, pg->e2));
        return r->solid_angle;
    }
    return (double)sph_triangle_solid_angle(pg->x, pg->p0, v3_add(pg->p0, pg->e1), v3_add(pg->p0, pg->e2));
}

static void dv(Vec3 v, double out[3])
{
    out[0] = (double)v.x;
    out[1] = (double)v.y;
    out[2] = (double)v.z;
}

/* Where direction w from x meets the polygon's plane, in the grid's coordinates. */
static bool to_grid(const Poly *pg, Vec3 w, double *gx, double *gy)
{
    double e1[3], e2[3], d[3], o[3];
    dv(pg->e1, e1);
    dv(pg->e2, e2);
    dv(w, d);
    dv(v3_sub(pg->x, pg->p0), o);
    /* solve o + t d = a e1 + b e2 by Cramer's rule on [e1 e2 -d] (a, b, t) = o */
    double m[3][3] = {{e1[0], e2[0], -d[0]}, {e1[1], e2[1], -d[1]}, {e1[2], e2[2], -d[2]}};
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (det == 0.0) return false;
    double sol[3];
    for (int k = 0; k < 3; k++) {
        double mk[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) mk[i][j] = j == k ? o[i] : m[i][j];
        sol[k] = (mk[0][0] * (mk[1][1] * mk[2][2] - mk[1][2] * mk[2][1]) -
                  mk[0][1] * (mk[1][0] * mk[2][2] - mk[1][2] * mk[2][0]) +
                  mk[0][2] * (mk[1][0] * mk[2][1] - mk[1][1] * mk[2][0])) / det;
    }
    double a = sol[0], b = sol[1], t = sol[2];
    const double eps = 1e-4;
    if (t <= 0.0) return false;
    if (pg->rect) {
        *gx = a;
        *gy = b;
        return a >= -eps && b >= -eps && a <= 1.0 + eps && b <= 1.0 + eps;
    }
    if (a < -eps || b < -eps || a + b > 1.0 + eps) return false;
    *gx = a;
    *gy = a < 1.0 ? b / (1.0 - a) : 0.0;
    return true;
}

/* The grid density of a direction uniform over solid angle omega. */
static double grid_density(const Poly *pg, double omega, double gx, double gy)
{
    double a = gx, b = pg->rect ? gy : gy * (1.0 - gx);
    double p0[3], e1[3], e2[3], x[3], p[3], v[3];
    dv(pg->p0, p0);
    dv(pg->e1, e1);
    dv(pg->e2, e2);
    dv(pg->x, x);
    for (int i = 0; i < 3; i++) {
        p[i] = p0[i] + a * e1[i] + b * e2[i];
        v[i] = p[i] - x[i];
    }
    double d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2];
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double nl = sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]); /* |e1 x e2| = dA / da db */
    double cos_l = fabs(n[0] * v[0] + n[1] * v[1] + n[2] * v[2]) / (nl * sqrt(d2));
    double jac = nl * (pg->rect ? 1.0 : 1.0 - gx);
    return cos_l / d2 * jac / omega;
}

static void run_chi2(const Poly *pg, uint64_t seed)
{
    SphRect r;
    double omega = poly_solid_angle(pg, &r);
    double *obs = calloc(GRID * GRID, sizeof *obs), *expd = calloc(GRID * GRID, sizeof *expd);
    assert_non_null(obs);
    assert_non_null(expd);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 54u);
    long off = 0;
    Vec3 p1 = v3_add(pg->p0, pg->e1), p2 = v3_add(pg->p0, pg->e2);
    for (int s = 0; s < SAMPLE_COUNT; s++) {
        float ux = pcg32_float(&rng), uy = pcg32_float(&rng);
        Vec3 w, p;
        if (pg->rect) w = sph_rect_sample(&r, v2(ux, uy), &p);
        else if (!sph_triangle_sample(pg->x, pg->p0, p1, p2, v2(ux, uy), &w)) { off++; continue; }
        double gx, gy;
        if (!to_grid(pg, w, &gx, &gy)) { off++; continue; }
        int ix = (int)(gx * GRID), iy = (int)(gy * GRID);
        ix = ix < 0 ? 0 : ix >= GRID ? GRID - 1 : ix;
        iy = iy < 0 ? 0 : iy >= GRID ? GRID - 1 : iy;
        obs[iy * GRID + ix] += 1.0;
    }
    double total = 0.0;
    for (int iy = 0; iy < GRID; iy++)
        for (int ix = 0; ix < GRID; ix++) {
            double acc = 0.0;
            for (int sy = 0; sy < SUBCELLS; sy++)
                for (int sx = 0; sx < SUBCELLS; sx++)
                    acc += grid_density(pg, omega, (ix + (sx + 0.5) / SUBCELLS) / GRID, (iy + (sy + 0.5) / SUBCELLS) / GRID);
            double cell = acc / (SUBCELLS * SUBCELLS) / (GRID * GRID);
            expd[iy * GRID + ix] = cell * SAMPLE_COUNT;
            total += cell;
        }
    int dof = 0;
    double stat = 0.0, outside = 0.0;
    double p = chi2_pvalue(obs, expd, GRID * GRID, &dof, &stat, &outside);
    print_message("  %-15s omega = %.5f sr  chi2 = %9.2f  dof = %4d  p = %.4f  (threshold %.5f)  off %ld  integral %.6f\n",
                  pg->name, omega, stat, dof, p, sidak_threshold(), off, total);
    free(obs);
    free(expd);
    /* the density integrates to 1 over the polygon: the solid angle is the right one */
    assert_true(fabs(total - 1.0) < 2e-3);
    assert_true(off == 0 && outside == 0.0);
    assert_true(p > sidak_threshold());
}

static void test_chi2_triangle_near(void **state) { (void)state; run_chi2(&POLYS[0], 11u); }
static void test_chi2_triangle_far(void **state) { (void)state; run_chi2(&POLYS[1], 12u); }
static void test_chi2_triangle_huge(void **state) { (void)state; run_chi2(&POLYS[2], 13u); }
static void test_chi2_rect_near(void **state) { (void)state; run_chi2(&POLYS[3], 14u); }
static void test_chi2_rect_far(void **state) { (void)state; run_chi2(&POLYS[4], 15u); }
static void test_chi2_triangle_tiny(void **state) { (void)state; run_chi2(&POLYS[5], 16u); }
static void test_chi2_triangle_grazing(void **state) { (void)state; run_chi2(&POLYS[6], 17u); }

/* Closed forms: the octant triangle (1,0,0), (0,1,0), (0,0,1) from the origin is pi/2; a
 * cube's face from its centre, 4 pi / 6. A rectangle and the two triangles that split it
 * agree. */
static void test_solid_angles(void **state)
{
    (void)state;
    float o = sph_triangle_solid_angle(v3s(0.0f), v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1));
    assert_true(fabs((double)o - PI_D / 2.0) < 1e-6);
    SphRect r;
    assert_true(sph_rect_init(&r, v3s(0.0f), v3(-1, -1, 1), v3(2, 0, 0), v3(0, 2, 0)));
    assert_true(fabs(r.solid_angle - 4.0 * PI_D / 6.0) < 1e-9);
    Vec3 x = v3(0.3f, -0.2f, 0.5f), s = v3(-1.0f, -1.5f, 1.2f), ex = v3(2, 0, 0), ey = v3(0, 1, 1);
    assert_true(sph_rect_init(&r, x, s, ex, ey));
    double two = (double)sph_triangle_solid_angle(x, s, v3_add(s, ex), v3_add(s, ey)) +
                 (double)sph_triangle_solid_angle(x, v3_add(s, ex), v3_add(v3_add(s, ex), ey), v3_add(s, ey));
    assert_true(fabs(r.solid_angle - two) < 1e-5 * two);
    /* in the plane: nothing */
    assert_false(sph_rect_init(&r, v3(0, 0, 1), v3(-1, -1, 1), v3(2, 0, 0), v3(0, 2, 0)));
    assert_true(sph_triangle_solid_angle(v3(2.0f, 2.0f, 0.0f), v3(0, 0, 0), v3(1, 0, 0), v3(0, 1, 0)) < 1e-6f);
    /* the set-up form NEE uses (light.c): the same solid angle; a vertex at x is refused
     * with solid angle 0, which NEE's range check then sends to area sampling */
    SphTri t;
    assert_true(sph_tri_init(&t, v3s(0.0f), v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)));
    assert_true(t.solid_angle == o);
    t.solid_angle = 1.0f;
    assert_false(sph_tri_init(&t, v3(1, 0, 0), v3(1, 0, 0), v3(0, 1, 0), v3(0, 0, 1)));
    assert_true(t.solid_angle == 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_solid_angles),
        cmocka_unit_test(test_chi2_triangle_near),
        cmocka_unit_test(test_chi2_triangle_far),
        cmocka_unit_test(test_chi2_triangle_huge),
        cmocka_unit_test(test_chi2_rect_near),
        cmocka_unit_test(test_chi2_rect_far),
        cmocka_unit_test(test_chi2_triangle_tiny),
        cmocka_unit_test(test_chi2_triangle_grazing),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
