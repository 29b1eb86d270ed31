/* The spectrum module (math/spectrum.h): the wavelength sampler against its pdf (chi-square),
 * the RGB -> spectrum round trip through the film's conversion for every kind, white
 * illuminant -> RGB (1, 1, 1), dispersion's pdf bookkeeping, blackbody normalisation. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <cmocka.h>

#include "math/cie_data.h"
#include "math/spectrum.h"
#include "unit/chi2.h"

/* Each lane of wavelengths_sample against wavelengths_visible_pdf: 94 bins of 5 nm,
 * expected counts by integrating the pdf (Simpson, 20 steps a bin). Fixed sample points
 * (a stratified-free hash sequence), p-value above 1e-4. */
static void test_wavelength_chi2(void **state)
{
    (void)state;
    enum { BINS = 94, N = 400000 };
    for (int lane = 0; lane < COLOR_LANES; lane++) {
        double obs[BINS] = {0}, expd[BINS];
        uint32_t x = 12345u + (uint32_t)lane;
        for (int i = 0; i < N; i++) {
            x = x * 1664525u + 1013904223u;
            float u = (float)(x >> 8) * 0x1p-24f;
            Wavelengths wl = wavelengths_sample(u);
            float l = wl.lambda[lane];
            assert_true(l >= 360.0f && l <= 830.0f);
            /* the pdf the sampler reports is the density's value at the sample */
            assert_true(fabsf(wl.pdf[lane] - wavelengths_visible_pdf(l)) <= 2e-3f * wl.pdf[lane] + 1e-7f);
            int b = (int)((l - 360.0f) / 5.0f);
            if (b >= BINS) b = BINS - 1;
            obs[b] += 1.0;
        }
        double total = 0.0;
        for (int b = 0; b < BINS; b++) {
            double a = 360.0 + 5.0 * b, h = 5.0 / 20.0, s = 0.0;
            for (int k = 0; k <= 20; k++) {
                double w = (k == 0 || k == 20) ? 1.0 : (k % 2 ? 4.0 : 2.0);
                s += w * (double)wavelengths_visible_pdf((float)(a + k * h));
            }
            expd[b] = s * h / 3.0;
            total += expd[b];
        }
        assert_true(fabs(total - 1.0) < 1e-3); /* normalised over [360, 830] */
        for (int b = 0; b < BINS; b++) expd[b] *= N / total;
        int dof;
        double stat, outside;
        double p = chi2_pvalue(obs, expd, BINS, &dof, &stat, &outside);
        if (!(p > 1e-4)) fail_msg("lane %d: chi-square p = %g (dof %d)", lane, p, dof);
    }
}

/* The film's estimate of an RGB input's colour, averaged over stratified wavelength sets:
 * exact up to the table's interpolation and the 5 nm curves (0.5%). */
static Color film_mean(Color rgb, int kind)
{
    enum { N = 20000 };
    double acc[3] = {0, 0, 0};
    Color white_d65 = color_s(1.0f);
    for (int i = 0; i < N; i++) {
        Wavelengths wl = wavelengths_sample(((float)i + 0.5f) / (float)N);
        Color v = kind == 0 ? color_mul(spectrum_albedo(rgb, &wl), spectrum_illuminant(white_d65, &wl))
                : kind == 1 ? color_mul(spectrum_unbounded(rgb, &wl), spectrum_illuminant(white_d65, &wl))
                            : spectrum_illuminant(rgb, &wl);
        Color o = spectrum_to_rgb(v, &wl);
        for (int c = 0; c < 3; c++) acc[c] += (double)o.c[c];
    }
    return color_rgb((float)(acc[0] / N), (float)(acc[1] / N), (float)(acc[2] / N));
}

static void test_round_trip(void **state)
{
    (void)state;
    const Color in[] = {color_rgb(1.0f, 1.0f, 1.0f), color_rgb(0.725f, 0.71f, 0.68f), color_rgb(0.63f, 0.065f, 0.05f),
                        color_rgb(0.14f, 0.45f, 0.091f), color_rgb(0.1f, 0.2f, 0.9f), color_rgb(0.0f, 0.0f, 0.0f),
                        color_rgb(0.5f, 0.5f, 0.5f)};
    for (size_t i = 0; i < sizeof in / sizeof in[0]; i++)
        for (int kind = 0; kind < 3; kind++) {
            float s = kind == 0 ? 1.0f : 17.0f;
            Color x = color_scale(in[i], s);
            Color o = film_mean(x, kind);
            for (int c = 0; c < 3; c++)
                if (!(fabsf(o.c[c] - x.c[c]) <= 5e-3f * s * fmaxf(x.c[c], 0.05f)))
                    fail_msg("kind %d, rgb (%g %g %g): channel %d gives %g", kind, (double)x.c[0], (double)x.c[1],
                             (double)x.c[2], c, (double)o.c[c]);
        }
}

/* A reflectance spectrum stays within [0, 1] at every wavelength. */
static void test_albedo_bounded(void **state)
{
    (void)state;
    for (int r = 0; r <= 10; r++)
        for (int g = 0; g <= 10; g++)
            for (int b = 0; b <= 10; b++) {
                SigmoidPoly p = spectrum_rgb_sigmoid(color_rgb(0.1f * (float)r, 0.1f * (float)g, 0.1f * (float)b));
                for (float l = 360.0f; l <= 830.0f; l += 10.0f) {
                    float v = sigmoid_poly_eval(p, l);
                    assert_true(v >= 0.0f && v <= 1.0f);
                }
            }
}

/* Terminating the secondary wavelengths keeps the hero's weight: the film counts it once. */
static void test_terminate_secondary(void **state)
{
    (void)state;
    Wavelengths wl = wavelengths_sample(0.3f);
    float pdf0 = wl.pdf[0];
    Color L = color_s(1.0f);
    Color full = spectrum_to_rgb(L, &wl);
    wavelengths_terminate_secondary(&wl);
    assert_true(wavelengths_secondary_terminated(&wl));
    assert_true(wl.pdf[0] == pdf0 / 4.0f && wl.pdf[1] == 0.0f && wl.pdf[3] == 0.0f);
    wavelengths_terminate_secondary(&wl); /* idempotent */
    assert_true(wl.pdf[0] == pdf0 / 4.0f);
    Color hero = spectrum_to_rgb(L, &wl);
    assert_true(isfinite(hero.c[0]) && isfinite(full.c[0]));
}

static void test_blackbody(void **state)
{
    (void)state;
    /* normalised to 1 at the peak (Wien: 2897.77 um K / T) */
    assert_true(fabsf(spectrum_blackbody(2897.7721f / 6.5f, 6500.0f) - 1.0f) < 1e-4f);
    assert_true(spectrum_blackbody(500.0f, 6500.0f) < 1.0f && spectrum_blackbody(500.0f, 6500.0f) > 0.9f);
    assert_true(spectrum_blackbody(500.0f, 0.0f) == 0.0f);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_wavelength_chi2),   cmocka_unit_test(test_round_trip),
        cmocka_unit_test(test_albedo_bounded),    cmocka_unit_test(test_terminate_secondary),
        cmocka_unit_test(test_blackbody),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
