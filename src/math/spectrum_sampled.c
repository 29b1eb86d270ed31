/* Densely sampled spectra (spectrum_sampled.h): construction from pairs, blackbodies and
 * constants, and their reductions to RGB or to one number for RGB mode. */
#include "math/spectrum_sampled.h"

#include "math/cie_data.h"

static void mark_constant(SampledSpectrum *s)
{
    s->constant = true;
    for (int i = 1; i < SAMPLED_SPECTRUM_N; i++)
        if (s->v[i] != s->v[0]) {
            s->constant = false;
            return;
        }
}

void sampled_spectrum_constant(float c, SampledSpectrum *out)
{
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) out->v[i] = c;
    out->constant = true;
}

void sampled_spectrum_from_pairs(const float *lambda, const float *value, int n, SampledSpectrum *out)
{
    if (n == 1) {
        sampled_spectrum_constant(value[0], out);
        return;
    }
    int j = 0; /* the segment [lambda[j], lambda[j + 1]] holding the node, walked forward */
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
        float l = (float)(SPECTRUM_LAMBDA_MIN + i);
        if (n < 1 || l < lambda[0] || l > lambda[n - 1]) {
            out->v[i] = 0.0f;
            continue;
        }
        while (j < n - 2 && l > lambda[j + 1]) j++;
        float t = (l - lambda[j]) / (lambda[j + 1] - lambda[j]);
        out->v[i] = (1.0f - t) * value[j] + t * value[j + 1];
    }
    mark_constant(out);
}

void sampled_spectrum_blackbody(float T, SampledSpectrum *out)
{
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++)
        out->v[i] = spectrum_blackbody((float)(SPECTRUM_LAMBDA_MIN + i), T);
    mark_constant(out);
}

/* Sum over the 1 nm nodes of s(lambda) times the CIE curves, weighted by D65 or not. */
static void integrate_xyz(const SampledSpectrum *s, bool d65, double xyz[3])
{
    xyz[0] = xyz[1] = xyz[2] = 0.0;
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
        float l = (float)(SPECTRUM_LAMBDA_MIN + i), c[3];
        spectrum_cie_xyz(l, c);
        double w = (double)(s ? s->v[i] : 1.0f) * (d65 ? (double)spectrum_d65(l) : 1.0);
        for (int k = 0; k < 3; k++) xyz[k] += w * (double)c[k];
    }
}

static void xyz_to_srgb(const double xyz[3], double rgb[3])
{
    for (int r = 0; r < 3; r++)
        rgb[r] = (double)cie_xyz_to_srgb[r][0] * xyz[0] + (double)cie_xyz_to_srgb[r][1] * xyz[1] +
                 (double)cie_xyz_to_srgb[r][2] * xyz[2];
}

Color sampled_spectrum_rgb_unbounded(const SampledSpectrum *s)
{
    if (s->constant) return color_s(s->v[0]);
    double xyz[3], w[3], rgb[3], rgb_w[3];
    integrate_xyz(s, true, xyz);
    integrate_xyz(NULL, true, w);
    xyz_to_srgb(xyz, rgb);
    xyz_to_srgb(w, rgb_w);
    float c[3];
    for (int k = 0; k < 3; k++) {
        double v = rgb[k] / rgb_w[k];
        c[k] = v > 0.0 ? (float)v : 0.0f; /* outside the gamut: clipped */
    }
    return color_rgb(c[0], c[1], c[2]);
}

Color sampled_spectrum_rgb_illuminant(const SampledSpectrum *s)
{
    double xyz[3], rgb[3];
    integrate_xyz(s, false, xyz);
    if (!(xyz[1] > 0.0)) return color_s(0.0f);
    double y = xyz[1];
    for (int k = 0; k < 3; k++) xyz[k] /= y;
    xyz_to_srgb(xyz, rgb);
    float c[3];
    for (int k = 0; k < 3; k++) c[k] = rgb[k] > 0.0 ? (float)rgb[k] : 0.0f;
    return color_rgb(c[0], c[1], c[2]);
}

double sampled_spectrum_y(const SampledSpectrum *s)
{
    double xyz[3];
    integrate_xyz(s, false, xyz);
    return xyz[1];
}

float sampled_spectrum_mean_y(const SampledSpectrum *s)
{
    if (s->constant) return s->v[0];
    double num = 0.0, den = 0.0;
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
        float l = (float)(SPECTRUM_LAMBDA_MIN + i), c[3];
        spectrum_cie_xyz(l, c);
        double w = (double)c[1] * (double)spectrum_d65(l);
        num += w * (double)s->v[i];
        den += w;
    }
    return (float)(num / den);
}
