/* Spectra for the spectral mode: the four wavelengths a path carries (Wavelengths; pbrt-v4's
 * SampledWavelengths), their importance sampling over the visible range, RGB -> spectrum
 * upsampling (Jakob & Hanika 2019) for reflectances, unbounded values and illuminants, the
 * film's conversion of a path's four values to linear sRGB through the CIE 1931
 * colour-matching functions, and blackbody emission. In spectral mode lane i of a Color is
 * the spectral value at lambda[i]; RGB mode never calls this module.
 * Units: wavelengths in nm; pdfs per nm; illuminant spectra scaled so that an RGB value
 * (r, g, b) emits what the RGB mode calls (r, g, b) (luminance Y = 1 for white). */
#ifndef CST_MATH_SPECTRUM_H
#define CST_MATH_SPECTRUM_H

#include <math.h>
#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "math/color.h"

enum {
    SPECTRUM_LAMBDA_MIN = 360, /* nm: the visible range wavelengths are drawn from */
    SPECTRUM_LAMBDA_MAX = 830,
    SPECTRUM_TABLE_RES = 64    /* the RGB -> spectrum table's grid, per axis */
};
/* The table (tools/spectrum_table_gen.c writes it, spectrum.c embeds it): RES brightness
 * nodes, then coefficients [3 largest channel][RES brightness][RES][RES][3]. */
#define SPECTRUM_TABLE_FLOATS \
    ((size_t)SPECTRUM_TABLE_RES + 9u * (size_t)SPECTRUM_TABLE_RES * SPECTRUM_TABLE_RES * SPECTRUM_TABLE_RES)

/* The wavelengths of one path: lambda[0] the hero, the others rotated from it by quarters of
 * the sampling distribution (Wilkie et al. 2014, "Hero Wavelength Spectral Sampling"; the
 * stratification pbrt-v4's SampledWavelengths::SampleVisible uses). pdf[i] per nm; 0 for a
 * wavelength terminated at a dispersive refraction. */
typedef struct Wavelengths {
    float lambda[COLOR_LANES];
    float pdf[COLOR_LANES];
} Wavelengths;

/* Density of wavelengths_visible_sample per nm: 1 / cosh^2 fitted to the CIE y-bar and
 * the spectral locus (pbrt-v4 VisibleWavelengthsPDF, 4th edition sec. 5.4.1), normalised
 * over [360, 830] nm; 0 outside. */
static inline float wavelengths_visible_pdf(float lambda)
{
    if (lambda < (float)SPECTRUM_LAMBDA_MIN || lambda > (float)SPECTRUM_LAMBDA_MAX) return 0.0f;
    float c = coshf(0.0072f * (lambda - 538.0f));
    return 0.0039398042f / (c * c);
}
/* The inverse of that density's CDF at u in [0, 1). */
static inline float wavelengths_visible_sample(float u)
{
    return 538.0f - 138.888889f * atanhf(0.85691062f - 1.82750197f * u);
}
/* Four wavelengths from one uniform number: u, u + 1/4, u + 1/2, u + 3/4 (mod 1), each
 * through the visible-range warp. Each lane alone has density wavelengths_visible_pdf,
 * evaluated here without cosh: 0.0072 * 138.888889 = 1, so with x = 0.85691062 -
 * 1.82750197 u the lane's cosh^2(0.0072 (lambda - 538)) is cosh^2(atanh x) = 1 / (1 - x^2),
 * and atanh x = log((1 + x) / (1 - x)) / 2: one logf per lane. */
static inline Wavelengths wavelengths_sample(float u)
{
    Wavelengths wl;
    for (int i = 0; i < COLOR_LANES; i++) {
        float up = u + (float)i * (1.0f / (float)COLOR_LANES);
        if (up >= 1.0f) up -= 1.0f;
        float x = 0.85691062f - 1.82750197f * up;
        wl.lambda[i] = 538.0f - 138.888889f * 0.5f * logf((1.0f + x) / (1.0f - x));
        wl.pdf[i] = 0.0039398042f * (1.0f - x * x);
    }
    return wl;
}
/* The wavelength sample of pass `pass` when a whole pass shares one set (VCM, SPPM): the
 * van der Corput point of pass (base 2) shifted by `offset` mod 1 (Cranley-Patterson
 * rotation, a per-render random offset), so each pass's u is uniform (an unbiased pass)
 * and the passes together stratify [0, 1): the colour error of the average falls about as
 * 1/passes instead of 1/sqrt(passes). Then wavelengths_sample(u). */
static inline float wavelengths_pass_u(uint32_t pass, uint32_t offset)
{
    uint32_t b = pass;
    b = (b << 16) | (b >> 16);
    b = ((b & 0x00ff00ffu) << 8) | ((b & 0xff00ff00u) >> 8);
    b = ((b & 0x0f0f0f0fu) << 4) | ((b & 0xf0f0f0f0u) >> 4);
    b = ((b & 0x33333333u) << 2) | ((b & 0xccccccccu) >> 2);
    b = ((b & 0x55555555u) << 1) | ((b & 0xaaaaaaaau) >> 1);
    uint32_t v = (b + offset) >> 8; /* 24 bits: exactly representable, below 1 */
    return (float)v * 0x1p-24f;
}

static inline bool wavelengths_secondary_terminated(const Wavelengths *wl)
{
    for (int i = 1; i < COLOR_LANES; i++)
        if (wl->pdf[i] != 0.0f) return false;
    return true;
}
/* After a wavelength-dependent refraction only the hero's direction is right: the others'
 * pdfs go to 0 (they no longer contribute) and the hero's is divided by 4, so that the
 * film's average over 4 lanes of value / pdf still counts the hero once (pbrt-v4
 * SampledWavelengths::TerminateSecondary). */
static inline void wavelengths_terminate_secondary(Wavelengths *wl)
{
    if (wavelengths_secondary_terminated(wl)) return;
    for (int i = 1; i < COLOR_LANES; i++) wl->pdf[i] = 0.0f;
    wl->pdf[0] /= (float)COLOR_LANES;
}

/* A smooth spectrum s(c0 t^2 + c1 t + c2), t = (lambda - 360) / 470, s(x) = 1/2 + x /
 * (2 sqrt(1 + x^2)): values in [0, 1] (Jakob & Hanika 2019, eq. 3 and 5). */
typedef struct SigmoidPoly {
    float c[3];
} SigmoidPoly;

static inline float sigmoid_poly_eval(SigmoidPoly p, float lambda)
{
    float t = (lambda - (float)SPECTRUM_LAMBDA_MIN) * (1.0f / (float)(SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN));
    float x = (p.c[0] * t + p.c[1]) * t + p.c[2];
    if (isinf(x)) return x > 0.0f ? 1.0f : 0.0f;
    return 0.5f + x / (2.0f * sqrtf(1.0f + x * x));
}

/* The smooth reflectance whose colour under D65 is rgb (linear sRGB, each clamped to
 * [0, 1]): the table's trilinear interpolation; exact constants for greys. */
SigmoidPoly spectrum_rgb_sigmoid(Color rgb);

/* An RGB value's spectrum looked up once (the table lookup is most of a conversion's
 * cost): scale times the sigmoid polynomial. Scenes keep one per constant material colour
 * and emitter (scene.h), so hits and light samples only evaluate it. */
typedef struct SpectrumRgb {
    SigmoidPoly poly;
    float scale;
} SpectrumRgb;
SpectrumRgb spectrum_rgb_albedo(Color rgb);    /* as spectrum_albedo */
SpectrumRgb spectrum_rgb_unbounded(Color rgb); /* as spectrum_unbounded and _illuminant */
static inline Color spectrum_rgb_eval(const SpectrumRgb *s, const Wavelengths *wl)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = s->scale * sigmoid_poly_eval(s->poly, wl->lambda[i]);
    return o;
}
/* The same times D65 at luminance 1 (spectrum_illuminant). */
Color spectrum_rgb_eval_illuminant(const SpectrumRgb *s, const Wavelengths *wl);

/* RGB inputs at the path's wavelengths, the three kinds pbrt-v4 distinguishes:
 * a reflectance in [0, 1] (RGBAlbedoSpectrum); an unbounded non-negative value such as a
 * conductor's eta and k or a scale (RGBUnboundedSpectrum: 2 max(rgb) times the sigmoid of
 * rgb / (2 max)); an emitted radiance or intensity (RGBIlluminantSpectrum: the unbounded
 * spectrum times D65 at luminance 1, so white (1, 1, 1) is D65 with Y = 1). */
Color spectrum_albedo(Color rgb, const Wavelengths *wl);
Color spectrum_unbounded(Color rgb, const Wavelengths *wl);
Color spectrum_illuminant(Color rgb, const Wavelengths *wl);

/* CIE 1931 x-bar, y-bar, z-bar at lambda (nm), linear between the 5 nm samples; 0 outside
 * [360, 830]. */
void spectrum_cie_xyz(float lambda, float xyz[3]);
/* D65 at lambda scaled to luminance 1: its integral against y-bar is 1 (per nm). */
float spectrum_d65(float lambda);
/* Planck's law at lambda (nm) for temperature T (K), divided by its value at the peak
 * wavelength (Wien's law), so its maximum is 1 (pbrt-v4 BlackbodySpectrum). 0 for T <= 0. */
float spectrum_blackbody(float lambda, float T);

/* A camera sample's four values -> linear sRGB, the film's sensor (pbrt-v4
 * PixelSensor::ToSensorRGB for the "cie1931" sensor, then RGBFilm's XYZ -> output
 * matrix): XYZ = mean over lanes of cmf(lambda_i) L_i / pdf_i (lanes with pdf 0 skipped),
 * the Monte Carlo estimate of the integral of cmf times L; then XYZ -> sRGB. */
Color spectrum_to_rgb(Color L, const Wavelengths *wl);

#endif
