/* The environment portal's sampler (lights/envmap.h EnvPortal): chi-square of its directions
 * against its own density, every sample through the window, and its estimate of the
 * radiance integrated over the window against uniform solid-angle sampling of the same
 * rectangle (sampling/spherical.h). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>

#include "core/rng.h"
#include "lights/envmap.h"
#include "sampling/spherical.h"
#include "unit/chi2.h"

#define PI_D 3.14159265358979323846

enum {
    SAMPLE_COUNT = 1000000,
    GRID = 30,
    SUBCELLS = 16,
    CHI2_TESTS = 2
};
static const double ALPHA = 0.01;
static double sidak_threshold(void) { return 1.0 - pow(1.0 - ALPHA, 1.0 / (double)CHI2_TESTS); }

/* A 256 x 128 sky: a gradient, a bright sun with a smooth falloff and a dark band, so that
 * the density varies by two orders of magnitude, but by little from one pixel to the next:
 * the expected counts come from the midpoint rule, which a step between two of the portal's
 * cells inside a histogram cell would bias (a sun with a hard edge put the integral 0.7 %
 * off). */
static void make_env(EnvMap *env)
{
    const int w = 256, h = 128;
    float *rgb = malloc(3u * (size_t)w * (size_t)h * sizeof *rgb);
    assert_non_null(rgb);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double th = PI_D * (y + 0.5) / h, ph = 2.0 * PI_D * (x + 0.5) / w;
            double d[3] = {sin(th) * cos(ph), cos(th), sin(th) * sin(ph)};
            double sun = 0.3 * d[0] + 0.4 * d[1] + 0.866 * d[2];
            float v = (float)(0.3 + 0.7 * fmax(d[1], 0.0) + 20.0 * exp(-30.0 * (1.0 - sun)) -
                              0.2 * exp(-0.5 * pow((ph - 4.0) / 0.3, 2.0)));
            float *p = &rgb[3 * ((size_t)y * (size_t)w + (size_t)x)];
            p[0] = v;
            p[1] = 0.8f * v;
            p[2] = 0.6f * v;
        }
    CstError err;
    assert_int_equal(envmap_init_image(env, rgb, w, h, color_s(1.0f), &err), CST_OK);
}

/* A window 2 x 1 in the plane z = 3, looking out along +z (p3 - p0 = +x, p1 - p0 = +y). */
static const Vec3 PORTAL[4] = {{-1, 1, 3}, {-1, 2, 3}, {1, 2, 3}, {1, 1, 3}};

/* (u, v) of a direction in the portal's frame, in double (the test's own, not envmap.c's) */
static void uv_of(Vec3 w, double *u, double *v)
{
    *u = (atan2((double)w.x, (double)w.z) + PI_D / 2.0) / PI_D;
    *v = (atan2((double)w.y, (double)w.z) + PI_D / 2.0) / PI_D;
}
static Vec3 dir_of(double u, double v)
{
    double x = tan(PI_D * (u - 0.5)), y = tan(PI_D * (v - 0.5)), r = sqrt(x * x + y * y + 1.0);
    return v3((float)(x / r), (float)(y / r), (float)(1.0 / r));
}
/* d omega / du dv = pi^2 (1 + x^2)(1 + y^2) / r^3 */
static double jacobian(double u, double v)
{
    double x = tan(PI_D * (u - 0.5)), y = tan(PI_D * (v - 0.5)), r = sqrt(x * x + y * y + 1.0);
    return PI_D * PI_D * (1.0 + x * x) * (1.0 + y * y) / (r * r * r);
}

static void run_chi2(Vec3 x, uint64_t seed)
{
    EnvMap env;
    make_env(&env);
    CstError err;
    assert_int_equal(envmap_set_portal(&env, PORTAL, &err), CST_OK);
    /* the window from x, in (u, v) */
    double u0, u1, v0, v1, ua, va, ub, vb;
    uv_of(v3_sub(PORTAL[0], x), &ua, &va);
    uv_of(v3_sub(PORTAL[2], x), &ub, &vb);
    u0 = fmin(ua, ub), u1 = fmax(ua, ub), v0 = fmin(va, vb), v1 = fmax(va, vb);
    double *obs = calloc(GRID * GRID, sizeof *obs), *expd = calloc(GRID * GRID, sizeof *expd);
    assert_non_null(obs);
    assert_non_null(expd);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 7u);
    long missed = 0;
    for (int s = 0; s < SAMPLE_COUNT; s++) {
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        Vec3 w;
        float pdf;
        if (!envmap_portal_sample(&env, x, u, &w, &pdf)) { missed++; continue; }
        /* through the window: the ray x + t w meets z = 3 inside [-1, 1] x [1, 2] */
        double t = (3.0 - (double)x.z) / (double)w.z;
        double hx = (double)x.x + t * (double)w.x, hy = (double)x.y + t * (double)w.y;
        if (!(t > 0.0 && hx >= -1.0 - 1e-4 && hx <= 1.0 + 1e-4 && hy >= 1.0 - 1e-4 && hy <= 2.0 + 1e-4)) { missed++; continue; }
        assert_true(fabs((double)pdf / (double)envmap_portal_pdf(&env, x, w) - 1.0) < 1e-6);
        double u_, v_;
        uv_of(w, &u_, &v_);
        int ix = (int)((u_ - u0) / (u1 - u0) * GRID), iy = (int)((v_ - v0) / (v1 - v0) * GRID);
        ix = ix < 0 ? 0 : ix >= GRID ? GRID - 1 : ix;
        iy = iy < 0 ? 0 : iy >= GRID ? GRID - 1 : iy;
        obs[iy * GRID + ix] += 1.0;
    }
    /* expected: pdf_w d omega / du dv du dv, the midpoint rule on SUBCELLS^2 points a cell */
    double total = 0.0;
    for (int iy = 0; iy < GRID; iy++)
        for (int ix = 0; ix < GRID; ix++) {
            double acc = 0.0;
            for (int sy = 0; sy < SUBCELLS; sy++)
                for (int sx = 0; sx < SUBCELLS; sx++) {
                    double u = u0 + (u1 - u0) * (ix + (sx + 0.5) / SUBCELLS) / GRID;
                    double v = v0 + (v1 - v0) * (iy + (sy + 0.5) / SUBCELLS) / GRID;
                    acc += (double)envmap_portal_pdf(&env, x, dir_of(u, v)) * jacobian(u, v);
                }
            double cell = acc / (SUBCELLS * SUBCELLS) * (u1 - u0) * (v1 - v0) / (GRID * GRID);
            expd[iy * GRID + ix] = cell * SAMPLE_COUNT;
            total += cell;
        }
    int dof = 0;
    double stat = 0.0, outside = 0.0;
    double p = chi2_pvalue(obs, expd, GRID * GRID, &dof, &stat, &outside);
    print_message("  portal from (%.1f, %.1f, %.1f): chi2 = %9.2f  dof = %4d  p = %.4f  (threshold %.5f)  "
                  "missed %ld  integral %.6f\n", (double)x.x, (double)x.y, (double)x.z, stat, dof, p,
                  sidak_threshold(), missed, total);
    free(obs);
    free(expd);
    envmap_free(&env);
    assert_true(missed == 0 && outside == 0.0);
    assert_true(fabs(total - 1.0) < 2e-3);
    assert_true(p > sidak_threshold());
}

static void test_chi2_portal_centre(void **state) { (void)state; run_chi2(v3(0.0f, 1.2f, -1.0f), 21u); }
static void test_chi2_portal_oblique(void **state) { (void)state; run_chi2(v3(2.5f, 0.3f, 2.2f), 22u); }

/* The integral of luminance over the window's directions from x, estimated with portal
 * samples (L / pdf) and with uniform solid-angle samples of the window rectangle (L S): the
 * same expectation, within 4 standard errors. */
static void test_portal_estimate_unbiased(void **state)
{
    (void)state;
    EnvMap env;
    make_env(&env);
    CstError err;
    assert_int_equal(envmap_set_portal(&env, PORTAL, &err), CST_OK);
    const Vec3 x = v3(0.5f, 0.8f, 0.5f);
    SphRect r;
    assert_true(sph_rect_init(&r, x, PORTAL[0], v3_sub(PORTAL[3], PORTAL[0]), v3_sub(PORTAL[1], PORTAL[0])));
    Pcg32 rng;
    pcg32_seed(&rng, 99u, 3u);
    const int n = 400000;
    double s1 = 0, q1 = 0, s2 = 0, q2 = 0;
    for (int i = 0; i < n; i++) {
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        Vec3 w;
        float pdf;
        double f1 = 0.0;
        if (envmap_portal_sample(&env, x, u, &w, &pdf)) f1 = (double)color_luminance(envmap_eval(&env, w)) / (double)pdf;
        s1 += f1;
        q1 += f1 * f1;
        Vec3 p;
        Vec3 w2 = sph_rect_sample(&r, v2(pcg32_float(&rng), pcg32_float(&rng)), &p);
        double f2 = (double)color_luminance(envmap_eval(&env, w2)) * r.solid_angle;
        s2 += f2;
        q2 += f2 * f2;
    }
    double m1 = s1 / n, m2 = s2 / n;
    double se1 = sqrt(fmax(q1 / n - m1 * m1, 0.0) / n), se2 = sqrt(fmax(q2 / n - m2 * m2, 0.0) / n);
    double z = (m1 - m2) / sqrt(se1 * se1 + se2 * se2);
    print_message("  integral over the window: portal %.6f +- %.6f, uniform %.6f +- %.6f, z = %.2f; "
                  "variance ratio uniform / portal %.1f\n", m1, se1, m2, se2, z, se2 * se2 / (se1 * se1));
    assert_true(fabs(z) <= 4.0);
    envmap_free(&env);
}

/* Behind the window (or in its plane) there is nothing to sample. */
static void test_portal_behind(void **state)
{
    (void)state;
    EnvMap env;
    make_env(&env);
    CstError err;
    assert_int_equal(envmap_set_portal(&env, PORTAL, &err), CST_OK);
    Vec3 w;
    float pdf;
    assert_false(envmap_portal_sample(&env, v3(0.0f, 1.5f, 4.0f), v2(0.5f, 0.5f), &w, &pdf));
    assert_false(envmap_portal_sample(&env, v3(0.0f, 1.5f, 3.0f), v2(0.5f, 0.5f), &w, &pdf));
    assert_true(envmap_portal_pdf(&env, v3(0.0f, 1.5f, 4.0f), v3(0, 0, 1)) == 0.0f);
    /* from the room, a direction away from the window has no density */
    assert_true(envmap_portal_pdf(&env, v3(0.0f, 1.5f, 0.0f), v3(0, 0, -1)) == 0.0f);
    assert_true(envmap_portal_pdf(&env, v3(0.0f, 1.5f, 0.0f), v3(0, 0, 1)) > 0.0f);
    envmap_free(&env);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_portal_centre),
        cmocka_unit_test(test_chi2_portal_oblique),
        cmocka_unit_test(test_portal_estimate_unbiased),
        cmocka_unit_test(test_portal_behind),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
