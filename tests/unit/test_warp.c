/* Chi-square goodness-of-fit of every warp in sampling/warp.h against its own pdf (the
 * test pbrt-v4 and Mitsuba 3 run on their samplers), the pdfs' normalisation, the
 * discrete distribution of sampling/distrib1d.c and the PCG32 reference sequence. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "sampling/distrib1d.h"
#include "unit/chi2.h"
#include "sampling/warp.h"

#define PI_D 3.14159265358979323846

enum {
    SAMPLE_COUNT = 1000000, /* per chi-square test */
    SUBCELLS = 8,           /* midpoint sub-samples per cell side for the expected counts */
    CHI2_TESTS = 8          /* 7 warps + distrib1d: the number of p-values corrected for */
};
/* Significance level of the whole file. Each test compares its p-value against the Sidak
 * threshold 1 - (1 - ALPHA)^(1 / CHI2_TESTS) ~ 0.00144, so that with correct samplers
 * the file as a whole fails with probability ALPHA (as Mitsuba's ChiSquareTest does). */
static const double ALPHA = 0.01;

static double sidak_threshold(void) { return 1.0 - pow(1.0 - ALPHA, 1.0 / (double)CHI2_TESTS); }

/* ------------------------------------------------------------------ chi-square statistics */

static void test_chi2_distribution_function(void **state)
{
    (void)state;
    /* Tabulated 5% critical values, and closed forms for dof 2 (e^{-x/2}) and dof 1. */
    assert_true(fabs(chi2_sf(3.841459, 1) - 0.05) < 1e-6);
    assert_true(fabs(chi2_sf(18.307038, 10) - 0.05) < 1e-6);
    assert_true(fabs(chi2_sf(124.342113, 100) - 0.05) < 1e-6);
    assert_true(fabs(chi2_sf(1074.679, 1000) - 0.05) < 1e-4);
    assert_true(fabs(chi2_sf(3.0, 2) - exp(-1.5)) < 1e-12);
    assert_true(fabs(chi2_sf(2.0, 1) - erfc(1.0)) < 1e-12);
    assert_true(chi2_sf(0.0, 5) == 1.0);
    assert_true(chi2_sf(1e4, 10) < 1e-200);
}

/* ------------------------------------------------------------------ warps on grids */

/* Each warp is histogrammed on a grid over [0,1)^2 in coordinates (gx, gy) chosen so
 * the support's boundary falls on cell edges; density() is the warp's own pdf expressed
 * in those coordinates, i.e. times the Jacobian of the map to the warp's measure. */
typedef struct WarpCase {
    const char *name;
    int nx, ny;
    /* Draws the warp at u; returns false if the sample lies outside the grid's domain. */
    bool (*to_grid)(Vec2 u, double *gx, double *gy);
    double (*density)(double gx, double gy);
} WarpCase;

static double phi_of(double x, double y)
{
    double phi = atan2(y, x);
    return phi < 0.0 ? phi + 2.0 * PI_D : phi;
}

/* Directions on (z, phi): gx = (z + 1) / 2 covers the whole sphere so hemisphere warps
 * must leave the lower half empty; d omega = dz dphi = 4 pi dgx dgy. */
static bool dir_to_grid(Vec3 w, double *gx, double *gy)
{
    *gx = 0.5 * ((double)w.z + 1.0);
    *gy = phi_of((double)w.x, (double)w.y) / (2.0 * PI_D);
    return isfinite(*gx) && *gx >= 0.0 && *gx <= 1.0;
}
static Vec3 dir_of_grid(double gx, double gy)
{
    double z = 2.0 * gx - 1.0, r = sqrt(fmax(0.0, 1.0 - z * z)), phi = 2.0 * PI_D * gy;
    return v3((float)(r * cos(phi)), (float)(r * sin(phi)), (float)z);
}

static bool disk_to_grid(Vec2 u, double *gx, double *gy)
{
    Vec2 p = warp_concentric_disk(u);
    /* (r^2, phi): d area = r dr dphi = (1/2) d(r^2) dphi = pi dgx dgy. */
    *gx = (double)p.x * (double)p.x + (double)p.y * (double)p.y;
    *gy = phi_of((double)p.x, (double)p.y) / (2.0 * PI_D);
    return *gx <= 1.0;
}
static double disk_density(double gx, double gy)
{
    double r = sqrt(gx), phi = 2.0 * PI_D * gy;
    return PI_D * (double)warp_concentric_disk_pdf(v2((float)(r * cos(phi)), (float)(r * sin(phi))));
}

static bool cosine_to_grid(Vec2 u, double *gx, double *gy) { return dir_to_grid(warp_cosine_hemisphere(u), gx, gy); }
static double cosine_density(double gx, double gy)
{
    return 4.0 * PI_D * (double)warp_cosine_hemisphere_pdf(dir_of_grid(gx, gy));
}

static bool uhemi_to_grid(Vec2 u, double *gx, double *gy) { return dir_to_grid(warp_uniform_hemisphere(u), gx, gy); }
static double uhemi_density(double gx, double gy)
{
    return 4.0 * PI_D * (double)warp_uniform_hemisphere_pdf(dir_of_grid(gx, gy));
}

static bool sphere_to_grid(Vec2 u, double *gx, double *gy) { return dir_to_grid(warp_uniform_sphere(u), gx, gy); }
static double sphere_density(double gx, double gy)
{
    return 4.0 * PI_D * (double)warp_uniform_sphere_pdf(dir_of_grid(gx, gy));
}

/* The cone of spot lights, cos_max = 0.85: its edge z = 0.85 is the grid line gx = 37/40,
 * so no cell straddles it. */
static const float CONE_COS = 0.85f;
static bool cone_to_grid(Vec2 u, double *gx, double *gy) { return dir_to_grid(warp_uniform_cone(u, CONE_COS), gx, gy); }
static double cone_density(double gx, double gy)
{
    Vec3 w = dir_of_grid(gx, gy);
    return w.z >= CONE_COS ? 4.0 * PI_D * (double)warp_uniform_cone_pdf(CONE_COS) : 0.0;
}

/* Barycentrics on the Duffy square: b1 = gx, b2 = gy (1 - gx), Jacobian 1 - gx. The
 * triangle's hypotenuse is the edge gy = 1, so no cell straddles it (and the grid is not
 * the sampler's own parameterisation, which is b1 + b2 = sqrt(u.x)). */
static bool triangle_to_grid(Vec2 u, double *gx, double *gy)
{
    Vec2 b = warp_uniform_triangle(u);
    double b1 = (double)b.x, b2 = (double)b.y;
    if (b1 < 0.0 || b2 < 0.0 || b1 + b2 > 1.0) return false;
    *gx = b1;
    *gy = b1 < 1.0 ? b2 / (1.0 - b1) : 0.0;
    return true;
}
static double triangle_density(double gx, double gy)
{
    return (double)warp_uniform_triangle_pdf(v2((float)gx, (float)(gy * (1.0 - gx)))) * (1.0 - gx);
}

/* Tent on [-1, 1]: gx = (x + 1) / 2, one row. */
static bool tent_to_grid(Vec2 u, double *gx, double *gy)
{
    double x = (double)warp_tent(u.x);
    *gx = 0.5 * (x + 1.0);
    *gy = 0.5;
    return x >= -1.0 && x <= 1.0;
}
static double tent_density(double gx, double gy)
{
    (void)gy;
    return 2.0 * (double)warp_tent_pdf((float)(2.0 * gx - 1.0));
}

static const WarpCase WARPS[] = {
    {"concentric disk", 20, 40, disk_to_grid, disk_density},
    {"cosine hemisphere", 40, 40, cosine_to_grid, cosine_density},
    {"uniform hemisphere", 40, 40, uhemi_to_grid, uhemi_density},
    {"uniform sphere", 40, 40, sphere_to_grid, sphere_density},
    {"uniform triangle", 30, 30, triangle_to_grid, triangle_density},
    {"tent", 100, 1, tent_to_grid, tent_density},
    {"uniform cone", 40, 40, cone_to_grid, cone_density},
};

static Vec2 next_u(Pcg32 *rng)
{
    float a = pcg32_float(rng);
    float b = pcg32_float(rng);
    return v2(a, b);
}

/* Histograms SAMPLE_COUNT samples of wc and returns the chi-square p-value against
 * wc->density; *outside counts samples off the support, *total the density's integral. */
static double warp_chi2(const WarpCase *wc, uint64_t seed, bool verbose, double *outside_out, double *total_out)
{
    int n = wc->nx * wc->ny;
    double *obs = calloc((size_t)n, sizeof *obs), *expd = calloc((size_t)n, sizeof *expd);
    assert_non_null(obs);
    assert_non_null(expd);

    Pcg32 rng;
    pcg32_seed(&rng, seed, 54u);
    long outside_grid = 0;
    for (int s = 0; s < SAMPLE_COUNT; s++) {
        double gx = 0.0, gy = 0.0;
        if (!wc->to_grid(next_u(&rng), &gx, &gy)) { outside_grid++; continue; }
        int ix = (int)(gx * wc->nx), iy = (int)(gy * wc->ny);
        ix = ix < 0 ? 0 : (ix >= wc->nx ? wc->nx - 1 : ix);
        iy = iy < 0 ? 0 : (iy >= wc->ny ? wc->ny - 1 : iy);
        obs[iy * wc->nx + ix] += 1.0;
    }

    /* Expected counts: composite midpoint rule on SUBCELLS^2 points per cell, in double.
     * Every density here is constant or linear in (gx, gy) inside a cell, where the
     * midpoint rule is exact; the supports' edges are cell edges. */
    double total = 0.0;
    for (int iy = 0; iy < wc->ny; iy++)
        for (int ix = 0; ix < wc->nx; ix++) {
            double acc = 0.0;
            for (int sy = 0; sy < SUBCELLS; sy++)
                for (int sx = 0; sx < SUBCELLS; sx++) {
                    double gx = ((double)ix + ((double)sx + 0.5) / SUBCELLS) / wc->nx;
                    double gy = ((double)iy + ((double)sy + 0.5) / SUBCELLS) / wc->ny;
                    acc += wc->density(gx, gy);
                }
            double cell = acc / (SUBCELLS * SUBCELLS) / ((double)wc->nx * wc->ny);
            expd[iy * wc->nx + ix] = cell * SAMPLE_COUNT;
            total += cell;
        }

    int dof = 0;
    double stat = 0.0, outside = 0.0;
    double p = chi2_pvalue(obs, expd, n, &dof, &stat, &outside);
    if (verbose)
        print_message("  %-19s chi2 = %9.2f  dof = %4d  p = %.4f  (threshold %.5f)\n", wc->name, stat, dof, p,
                      sidak_threshold());
    *outside_out = outside + (double)outside_grid;
    *total_out = total;
    free(obs);
    free(expd);
    return p;
}

static void run_warp_chi2(const WarpCase *wc, uint64_t seed)
{
    double outside = 0.0, total = 0.0;
    double p = warp_chi2(wc, seed, true, &outside, &total);
    if (outside > 0.0) fail_msg("%s: %.0f samples outside the support", wc->name, outside);
    if (fabs(total - 1.0) > 1e-3) fail_msg("%s: density integrates to %.6f over the grid", wc->name, total);
    if (!(p > sidak_threshold())) fail_msg("%s: chi-square p = %.3g rejects the pdf", wc->name, p);
}

static void test_chi2_concentric_disk(void **state) { (void)state; run_warp_chi2(&WARPS[0], 1u); }
static void test_chi2_cosine_hemisphere(void **state) { (void)state; run_warp_chi2(&WARPS[1], 2u); }
static void test_chi2_uniform_hemisphere(void **state) { (void)state; run_warp_chi2(&WARPS[2], 3u); }
static void test_chi2_uniform_sphere(void **state) { (void)state; run_warp_chi2(&WARPS[3], 4u); }
static void test_chi2_uniform_triangle(void **state) { (void)state; run_warp_chi2(&WARPS[4], 5u); }
static void test_chi2_tent(void **state) { (void)state; run_warp_chi2(&WARPS[5], 6u); }
static void test_chi2_uniform_cone(void **state) { (void)state; run_warp_chi2(&WARPS[6], 8u); }

/* Negative controls, not counted in CHI2_TESTS: the machinery must reject a sampler
 * that does not match the pdf it is tested against, including a subtle mismatch. */
static bool naive_disk_to_grid(Vec2 u, double *gx, double *gy)
{
    /* Polar map with r = u.x instead of sqrt(u.x): area density 1 / (2 pi r), not 1/pi. */
    *gx = (double)u.x * (double)u.x;
    *gy = (double)u.y;
    return true;
}
static bool skewed_tent_to_grid(Vec2 u, double *gx, double *gy)
{
    /* The tent evaluated at u^1.02: a 2% distortion of the CDF. */
    Vec2 v = v2(powf(u.x, 1.02f), u.y);
    return tent_to_grid(v, gx, gy);
}

static void test_chi2_rejects_wrong_pdfs(void **state)
{
    (void)state;
    const WarpCase wrong[] = {
        {"uniform vs cosine", 40, 40, uhemi_to_grid, cosine_density},
        {"cosine vs uniform", 40, 40, cosine_to_grid, uhemi_density},
        {"naive polar disk", 20, 40, naive_disk_to_grid, disk_density},
        {"skewed tent", 100, 1, skewed_tent_to_grid, tent_density},
    };
    for (size_t i = 0; i < sizeof wrong / sizeof wrong[0]; i++) {
        double outside = 0.0, total = 0.0;
        double p = warp_chi2(&wrong[i], 100u + i, false, &outside, &total);
        print_message("  control %-19s p = %.3g\n", wrong[i].name, p);
        if (!(p < 1e-6)) fail_msg("%s: p = %.3g, the test failed to reject it", wrong[i].name, p);
    }
}

/* ------------------------------------------------------------------ normalisation */

/* Each pdf integrated over a box a little larger than its support, in coordinates other
 * than the chi-square grid's, by the midpoint rule; cell edges avoid the supports'
 * boundaries, so the pdf's own indicator decides what is inside. */
static void test_pdfs_integrate_to_one(void **state)
{
    (void)state;
    const int n = 2000;
    double disk = 0.0, tri = 0.0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double x = -1.01 + 2.02 * ((double)i + 0.5) / n, y = -1.01 + 2.02 * ((double)j + 0.5) / n;
            disk += (double)warp_concentric_disk_pdf(v2((float)x, (float)y));
            double b1 = -0.01 + 1.02 * ((double)i + 0.5) / n, b2 = -0.01 + 1.02 * ((double)j + 0.5) / n;
            tri += (double)warp_uniform_triangle_pdf(v2((float)b1, (float)b2));
        }
    disk *= (2.02 / n) * (2.02 / n);
    tri *= (1.02 / n) * (1.02 / n);

    /* Directions in (theta, phi), d omega = sin(theta) dtheta dphi; an even theta count
     * puts a cell edge on the equator. */
    const int nt = 1000, np = 2000;
    double cosine = 0.0, uhemi = 0.0, sphere = 0.0;
    for (int j = 0; j < nt; j++) {
        double theta = PI_D * ((double)j + 0.5) / nt, st = sin(theta);
        for (int i = 0; i < np; i++) {
            double phi = 2.0 * PI_D * ((double)i + 0.5) / np;
            Vec3 w = v3((float)(st * cos(phi)), (float)(st * sin(phi)), (float)cos(theta));
            cosine += (double)warp_cosine_hemisphere_pdf(w) * st;
            uhemi += (double)warp_uniform_hemisphere_pdf(w) * st;
            sphere += (double)warp_uniform_sphere_pdf(w) * st;
        }
    }
    double dw = (PI_D / nt) * (2.0 * PI_D / np);
    cosine *= dw; uhemi *= dw; sphere *= dw;

    const int nx = 300000;
    double tent = 0.0;
    for (int i = 0; i < nx; i++) tent += (double)warp_tent_pdf((float)(-1.5 + 3.0 * ((double)i + 0.5) / nx));
    tent *= 3.0 / nx;

    print_message("  integrals: disk %.6f cosine %.6f hemisphere %.6f sphere %.6f triangle %.6f tent %.6f\n",
                  disk, cosine, uhemi, sphere, tri, tent);
    assert_true(fabs(disk - 1.0) < 1e-3);
    assert_true(fabs(cosine - 1.0) < 1e-3);
    assert_true(fabs(uhemi - 1.0) < 1e-3);
    assert_true(fabs(sphere - 1.0) < 1e-3);
    assert_true(fabs(tri - 1.0) < 1e-3);
    assert_true(fabs(tent - 1.0) < 1e-3);
}

/* ------------------------------------------------------------------ domains */

static void check_direction(const char *name, Vec3 w, float pdf, bool upper, int s)
{
    if (!v3_is_finite(w) || fabsf(v3_length(w) - 1.0f) > 1e-5f)
        fail_msg("%s sample %d: (%g, %g, %g) not a unit vector", name, s, (double)w.x, (double)w.y, (double)w.z);
    if (upper && !(w.z >= 0.0f)) fail_msg("%s sample %d: z = %g below the horizon", name, s, (double)w.z);
    if (!(pdf > 0.0f) || !isfinite(pdf)) fail_msg("%s sample %d: pdf %g", name, s, (double)pdf);
}

/* Every sample of 10^6 (fixed seed) lies in its warp's domain where its pdf is > 0. */
static void test_samples_in_domain(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 99u, 7u);
    for (int s = 0; s < SAMPLE_COUNT; s++) {
        Vec2 u = next_u(&rng);
        Vec2 p = warp_concentric_disk(u);
        if (!(p.x * p.x + p.y * p.y <= 1.0f) || !(warp_concentric_disk_pdf(p) > 0.0f))
            fail_msg("disk sample %d: (%g, %g) outside or pdf 0", s, (double)p.x, (double)p.y);
        Vec3 w = warp_cosine_hemisphere(u);
        check_direction("cosine hemisphere", w, warp_cosine_hemisphere_pdf(w), true, s);
        w = warp_uniform_hemisphere(u);
        check_direction("uniform hemisphere", w, warp_uniform_hemisphere_pdf(w), true, s);
        w = warp_uniform_sphere(u);
        check_direction("uniform sphere", w, warp_uniform_sphere_pdf(w), false, s);
        Vec2 b = warp_uniform_triangle(u);
        if (!(b.x >= 0.0f && b.y >= 0.0f && b.x + b.y <= 1.0f) || !(warp_uniform_triangle_pdf(b) > 0.0f))
            fail_msg("triangle sample %d: (%g, %g)", s, (double)b.x, (double)b.y);
        float x = warp_tent(u.x);
        if (!(x >= -1.0f && x <= 1.0f) || !(warp_tent_pdf(x) > 0.0f))
            fail_msg("tent sample %d: %g, pdf %g", s, (double)x, (double)warp_tent_pdf(x));
    }
}

/* The extreme inputs 0 and 1 - 2^-24 (pcg32_float's range) map into the closed domain.
 * Documented edge behaviour: u.x = 0 or u.y = 0 is the concentric map's square boundary,
 * which lands on the unit circle, so the cosine hemisphere returns z = 0 with pdf 0
 * there (bsdf_sample rejects wi.z == 0), and warp_tent(0) = -1 with pdf 0. These inputs
 * have probability 2^-24 each per coordinate. */
static void test_warp_extreme_inputs(void **state)
{
    (void)state;
    const float us[] = {0.0f, 0x1p-24f, 0.5f, 1.0f - 0x1p-24f};
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++) {
            Vec2 u = v2(us[i], us[j]);
            Vec2 p = warp_concentric_disk(u);
            assert_true(isfinite(p.x) && isfinite(p.y));
            assert_true((double)p.x * (double)p.x + (double)p.y * (double)p.y <= 1.0 + 1e-6);
            Vec3 w = warp_cosine_hemisphere(u);
            assert_true(v3_is_finite(w) && w.z >= 0.0f && fabsf(v3_length(w) - 1.0f) < 1e-5f);
            if (i > 0 && j > 0) assert_true(warp_cosine_hemisphere_pdf(w) > 0.0f);
            w = warp_uniform_hemisphere(u);
            assert_true(v3_is_finite(w) && w.z >= 0.0f && warp_uniform_hemisphere_pdf(w) > 0.0f);
            w = warp_uniform_sphere(u);
            assert_true(v3_is_finite(w) && fabsf(v3_length(w) - 1.0f) < 1e-5f);
            Vec2 b = warp_uniform_triangle(u);
            assert_true(warp_uniform_triangle_pdf(b) > 0.0f);
        }
    assert_true(warp_tent(0.0f) == -1.0f && warp_tent_pdf(-1.0f) == 0.0f);
    assert_true(warp_tent(0x1p-24f) > -1.0f && warp_tent_pdf(warp_tent(0x1p-24f)) > 0.0f);
    assert_true(warp_tent(1.0f - 0x1p-24f) < 1.0f && warp_tent_pdf(warp_tent(1.0f - 0x1p-24f)) > 0.0f);
    assert_true(warp_tent(0.5f) == 0.0f);
}

/* ------------------------------------------------------------------ distrib1d */

static const float DWEIGHTS[] = {0.0f, 1.0f, 3.0f, 0.0f, 0.5f, 2.0f, 0.0f, 7.0f, 1e-3f, 0.0f, 0.0f};
enum { DN = (int)(sizeof DWEIGHTS / sizeof DWEIGHTS[0]) };

static void test_distrib1d_pmf_and_cdf(void **state)
{
    (void)state;
    Distrib1D d;
    CstError err = {0};
    assert_int_equal(distrib1d_init(&d, DWEIGHTS, DN, &err), CST_OK);
    double total = 0.0;
    for (int i = 0; i < DN; i++) total += (double)DWEIGHTS[i];
    assert_true(fabs(d.total - total) < 1e-12);
    assert_true(d.cdf[0] == 0.0f && d.cdf[DN] == 1.0f);
    for (int i = 0; i < DN; i++) {
        assert_true(fabs((double)d.pmf[i] - (double)DWEIGHTS[i] / total) <= 1e-7 * (double)DWEIGHTS[i] / total);
        assert_true(d.cdf[i + 1] >= d.cdf[i]);
    }
    distrib1d_free(&d);

    /* Invalid inputs report an error and leave nothing to free. */
    const float zeros[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(distrib1d_init(&d, zeros, 3, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(distrib1d_init(&d, DWEIGHTS, 0, &err), CST_ERR_INVALID_ARG);
    distrib1d_free(&d);
}

/* Every float pcg32_float can return (k 2^-24, k < 2^24) is fed through
 * distrib1d_sample: zero-weight items are never chosen and each item's share of the
 * 2^24 inputs equals its pmf up to the CDF's float rounding. */
static void test_distrib1d_exhaustive(void **state)
{
    (void)state;
    Distrib1D d;
    CstError err = {0};
    assert_int_equal(distrib1d_init(&d, DWEIGHTS, DN, &err), CST_OK);
    long counts[DN] = {0};
    int prev = 0;
    for (uint32_t k = 0; k < (1u << 24); k++) {
        int i = distrib1d_sample(&d, (float)k * 0x1p-24f);
        assert_true(i >= 0 && i < DN);
        if (i < prev) fail_msg("not monotone in u at k = %u", k);
        prev = i;
        counts[i]++;
    }
    for (int i = 0; i < DN; i++) {
        if (DWEIGHTS[i] == 0.0f && counts[i] != 0) fail_msg("zero-weight item %d chosen %ld times", i, counts[i]);
        double share = (double)counts[i] * 0x1p-24;
        if (fabs(share - (double)d.pmf[i]) > 2e-7) fail_msg("item %d: share %.9f, pmf %.9f", i, share, (double)d.pmf[i]);
    }
    /* Edge cases: leading, trailing and single non-zero weights. */
    const float lead[] = {0.0f, 0.0f, 2.0f}, trail[] = {2.0f, 0.0f, 0.0f}, mid[] = {0.0f, 1.0f, 0.0f};
    Distrib1D e;
    assert_int_equal(distrib1d_init(&e, lead, 3, &err), CST_OK);
    assert_int_equal(distrib1d_sample(&e, 0.0f), 2);
    assert_int_equal(distrib1d_sample(&e, 1.0f - 0x1p-24f), 2);
    distrib1d_free(&e);
    assert_int_equal(distrib1d_init(&e, trail, 3, &err), CST_OK);
    assert_int_equal(distrib1d_sample(&e, 0.0f), 0);
    assert_int_equal(distrib1d_sample(&e, 1.0f - 0x1p-24f), 0);
    distrib1d_free(&e);
    assert_int_equal(distrib1d_init(&e, mid, 3, &err), CST_OK);
    assert_int_equal(distrib1d_sample(&e, 0.0f), 1);
    assert_int_equal(distrib1d_sample(&e, 0.5f), 1);
    assert_int_equal(distrib1d_sample(&e, 1.0f - 0x1p-24f), 1);
    distrib1d_free(&e);
    distrib1d_free(&d);
}

static void test_chi2_distrib1d(void **state)
{
    (void)state;
    Distrib1D d;
    CstError err = {0};
    assert_int_equal(distrib1d_init(&d, DWEIGHTS, DN, &err), CST_OK);
    double obs[DN] = {0}, expd[DN];
    Pcg32 rng;
    pcg32_seed(&rng, 7u, 54u);
    for (int s = 0; s < SAMPLE_COUNT; s++) obs[distrib1d_sample(&d, pcg32_float(&rng))] += 1.0;
    double total = 0.0;
    for (int i = 0; i < DN; i++) total += (double)DWEIGHTS[i];
    for (int i = 0; i < DN; i++) expd[i] = (double)DWEIGHTS[i] / total * SAMPLE_COUNT;
    int dof = 0;
    double stat = 0.0, outside = 0.0;
    double p = chi2_pvalue(obs, expd, DN, &dof, &stat, &outside);
    print_message("  %-19s chi2 = %9.2f  dof = %4d  p = %.4f  (threshold %.5f)\n", "distrib1d", stat, dof, p,
                  sidak_threshold());
    if (outside > 0.0) fail_msg("zero-weight items chosen %.0f times", outside);
    if (!(p > sidak_threshold())) fail_msg("distrib1d: chi-square p = %.3g", p);
    distrib1d_free(&d);
}

/* ------------------------------------------------------------------ PCG32 */

static void test_pcg32_reference_sequence(void **state)
{
    (void)state;
    /* pcg32-demo of the reference C implementation: pcg32_srandom_r(&rng, 42u, 54u). */
    const uint32_t want[6] = {0xa15c02b7u, 0x7b47f409u, 0xba1d3330u, 0x83d2f293u, 0xbfa4784bu, 0xcbed606eu};
    Pcg32 rng;
    pcg32_seed(&rng, 42u, 54u);
    for (int i = 0; i < 6; i++) {
        uint32_t got = pcg32_next(&rng);
        if (got != want[i]) fail_msg("output %d: 0x%08x, expected 0x%08x", i, got, want[i]);
    }
    /* pcg32_float stays in [0, 1): the largest output maps below 1. */
    for (int i = 0; i < 100000; i++) {
        float f = pcg32_float(&rng);
        assert_true(f >= 0.0f && f < 1.0f);
    }
    assert_true((float)(0xffffffffu >> 8) * 0x1p-24f < 1.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_distribution_function),
        cmocka_unit_test(test_pcg32_reference_sequence),
        cmocka_unit_test(test_chi2_concentric_disk),
        cmocka_unit_test(test_chi2_cosine_hemisphere),
        cmocka_unit_test(test_chi2_uniform_hemisphere),
        cmocka_unit_test(test_chi2_uniform_sphere),
        cmocka_unit_test(test_chi2_uniform_triangle),
        cmocka_unit_test(test_chi2_tent),
        cmocka_unit_test(test_chi2_uniform_cone),
        cmocka_unit_test(test_chi2_rejects_wrong_pdfs),
        cmocka_unit_test(test_pdfs_integrate_to_one),
        cmocka_unit_test(test_samples_in_domain),
        cmocka_unit_test(test_warp_extreme_inputs),
        cmocka_unit_test(test_distrib1d_pmf_and_cdf),
        cmocka_unit_test(test_distrib1d_exhaustive),
        cmocka_unit_test(test_chi2_distrib1d),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
