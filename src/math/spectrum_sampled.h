/* Spectra kept as spectra (pbrt-v4's PiecewiseLinearSpectrum, BlackbodySpectrum and named
 * spectra): a value per nm over the visible range, evaluated at a path's wavelengths in
 * spectral mode and reduced to RGB (or to one number, for an index of refraction) in RGB
 * mode. The named spectra's data are in spectrum_data.c.
 * Units: wavelengths in nm; values as given (an IOR, a k, a relative power). */
#ifndef CST_MATH_SPECTRUM_SAMPLED_H
#define CST_MATH_SPECTRUM_SAMPLED_H

#include <stdbool.h>

#include "math/color.h"
#include "math/spectrum.h"

enum { SAMPLED_SPECTRUM_N = SPECTRUM_LAMBDA_MAX - SPECTRUM_LAMBDA_MIN + 1 }; /* 1 nm nodes */

/* A spectrum stored at every nm of [360, 830] (pbrt-v4's DenselySampledSpectrum), linear
 * between the nodes; 0 outside. 1.9 KB, so a lookup is one interpolation whatever the
 * source's number of samples. */
typedef struct SampledSpectrum {
    float v[SAMPLED_SPECTRUM_N]; /* v[i]: the value at 360 + i nm */
    bool constant;               /* the same value at every node: no dispersion */
    /* 1 / (integral of v times y-bar, per nm), 0 when that is not positive: scales an
     * emitted spectrum to luminance 1 (set by the scene, scene_add_spectrum). */
    float inv_y;
} SampledSpectrum;

static inline float sampled_spectrum_at(const SampledSpectrum *s, float lambda)
{
    float x = lambda - (float)SPECTRUM_LAMBDA_MIN;
    if (!(x >= 0.0f && x <= (float)(SAMPLED_SPECTRUM_N - 1))) return 0.0f;
    int i = (int)x;
    if (i > SAMPLED_SPECTRUM_N - 2) i = SAMPLED_SPECTRUM_N - 2;
    float f = x - (float)i;
    return (1.0f - f) * s->v[i] + f * s->v[i + 1];
}

static inline Color sampled_spectrum_eval(const SampledSpectrum *s, const Wavelengths *wl)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = sampled_spectrum_at(s, wl->lambda[i]);
    return o;
}

/* From n (lambda, value) pairs, lambda strictly increasing (the caller checked): linear
 * between them and 0 outside [lambda[0], lambda[n-1]], as pbrt-v4's PiecewiseLinearSpectrum;
 * one pair is a constant. */
void sampled_spectrum_from_pairs(const float *lambda, const float *value, int n, SampledSpectrum *out);
/* Planck's law at temperature T (K) normalised to peak 1 (pbrt-v4 BlackbodySpectrum). */
void sampled_spectrum_blackbody(float T, SampledSpectrum *out);
/* A constant. */
void sampled_spectrum_constant(float c, SampledSpectrum *out);

/* Reductions for RGB mode, integrated against the CIE 1931 curves at 1 nm (math/cie_data.h):
 * - a reflectance or unbounded value (a conductor's eta, k): the linear sRGB of the spectrum
 *   under D65, per channel over that of the constant 1, so a constant c gives (c, c, c);
 * - an illuminant: the linear sRGB of the spectrum itself at luminance Y = 1 (pbrt-v4 scales
 *   a light's spectrum by 1 / its photometric value), black if Y <= 0;
 * - a scalar (a dielectric's IOR): the mean weighted by y-bar times D65, the value the eye
 *   sees most; a constant gives itself. */
Color sampled_spectrum_rgb_unbounded(const SampledSpectrum *s);
Color sampled_spectrum_rgb_illuminant(const SampledSpectrum *s);
float sampled_spectrum_mean_y(const SampledSpectrum *s);
/* The integral of s times y-bar over 360-830 nm (1 nm steps), nm. */
double sampled_spectrum_y(const SampledSpectrum *s);

/* pbrt-v4's named spectra (spectrum_data.c): "metal-{Ag,Al,Au,Cu,CuZn,MgO,TiO2}-{eta,k}",
 * "glass-{BK7,BAF10,FK51A,LASF9,F5,F10,F11,SF5,SF10,SF11}", "stdillum-A", "stdillum-D50",
 * "stdillum-D65", "stdillum-F1" ... "stdillum-F12", "illum-acesD60".
 * "glass-F5/F10/F11" are pbrt-v4's names for SCHOTT SF5/SF10/SF11, the same spectra as
 * "glass-SF5/SF10/SF11". Fills *out and returns true; false for an unknown name. */
bool spectrum_named(const char *name, SampledSpectrum *out);
/* The names spectrum_named knows, NULL-terminated. */
extern const char *const spectrum_named_list[];

#endif
