/* Spectral upsampling, the CIE curves at a wavelength, blackbody emission and the film's
 * spectral -> sRGB conversion (spectrum.h). The RGB -> spectrum table is generated at
 * build time by tools/spectrum_table_gen.c (our Gauss-Newton solver of Jakob & Hanika
 * 2019) and embedded read-only here. */
#include "math/spectrum.h"

#include "math/cie_data.h"

#ifndef CST_SPECTRUM_TABLE_BIN
#error "CST_SPECTRUM_TABLE_BIN: the generated table's path (CMakeLists.txt defines it)"
#endif

/* The generated binary, embedded by the assembler: 9.4 MB would take the C compiler
 * minutes as an initialiser. Hidden: an internal symbol of the shared library. */
__asm__(".section .rodata\n"
        ".balign 64\n"
        ".globl cst_spectrum_table\n"
        ".hidden cst_spectrum_table\n"
        "cst_spectrum_table:\n"
        ".incbin \"" CST_SPECTRUM_TABLE_BIN "\"\n"
        ".previous\n");
extern const float cst_spectrum_table[SPECTRUM_TABLE_FLOATS];

static inline float lerpf(float t, float a, float b) { return (1.0f - t) * a + t * b; }

SigmoidPoly spectrum_rgb_sigmoid(Color rgb)
{
    const int R = SPECTRUM_TABLE_RES;
    float v[3];
    for (int i = 0; i < 3; i++) {
        float c = rgb.c[i];
        v[i] = c > 0.0f ? (c < 1.0f ? c : 1.0f) : 0.0f; /* also maps NaN to 0 */
    }
    SigmoidPoly p = {{0.0f, 0.0f, 0.0f}};
    if (v[0] == v[1] && v[1] == v[2]) {
        /* A grey: the constant spectrum, s(x) = v at x = (v - 1/2) / sqrt(v (1 - v))
         * (+-inf at 0 and 1, which sigmoid_poly_eval maps to 0 and 1). */
        p.c[2] = (v[0] - 0.5f) / sqrtf(v[0] * (1.0f - v[0]));
        return p;
    }
    int m = v[0] > v[1] ? (v[0] > v[2] ? 0 : 2) : (v[1] > v[2] ? 1 : 2);
    float z = v[m];
    float x = v[(m + 1) % 3] * (float)(R - 1) / z, y = v[(m + 2) % 3] * (float)(R - 1) / z;
    int xi = (int)x < R - 2 ? (int)x : R - 2, yi = (int)y < R - 2 ? (int)y : R - 2;
    const float *zn = cst_spectrum_table;
    /* The last node below z (binary search over the increasing brightness nodes). */
    int lo = 0, hi = R - 2;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (zn[mid] <= z) lo = mid;
        else hi = mid - 1;
    }
    int zi = lo;
    float dx = x - (float)xi, dy = y - (float)yi, dz = (z - zn[zi]) / (zn[zi + 1] - zn[zi]);
    const float *co = cst_spectrum_table + R;
#define CO(ddx, ddy, ddz, k) co[3 * ((((size_t)m * R + (size_t)(zi + (ddz))) * R + (size_t)(yi + (ddy))) * R + (size_t)(xi + (ddx))) + (k)]
    for (int k = 0; k < 3; k++) {
        p.c[k] = lerpf(dz, lerpf(dy, lerpf(dx, CO(0, 0, 0, k), CO(1, 0, 0, k)), lerpf(dx, CO(0, 1, 0, k), CO(1, 1, 0, k))),
                       lerpf(dy, lerpf(dx, CO(0, 0, 1, k), CO(1, 0, 1, k)), lerpf(dx, CO(0, 1, 1, k), CO(1, 1, 1, k))));
    }
#undef CO
    return p;
}

/* Linear interpolation in a 5 nm CIE table; the caller checked the range. */
static inline float cie_at(const float *tab, int i, float f) { return (1.0f - f) * tab[i] + f * tab[i + 1]; }

static inline int cie_index(float lambda, float *f)
{
    float x = (lambda - (float)CIE_LAMBDA_MIN) * (1.0f / (float)CIE_STEP);
    int i = (int)x;
    if (i > CIE_SAMPLES - 2) i = CIE_SAMPLES - 2;
    *f = x - (float)i;
    return i;
}

void spectrum_cie_xyz(float lambda, float xyz[3])
{
    if (!(lambda >= (float)CIE_LAMBDA_MIN && lambda <= (float)CIE_LAMBDA_MAX)) {
        xyz[0] = xyz[1] = xyz[2] = 0.0f;
        return;
    }
    float f;
    int i = cie_index(lambda, &f);
    xyz[0] = cie_at(cie_x, i, f);
    xyz[1] = cie_at(cie_y, i, f);
    xyz[2] = cie_at(cie_z, i, f);
}

float spectrum_d65(float lambda)
{
    if (!(lambda >= (float)CIE_LAMBDA_MIN && lambda <= (float)CIE_LAMBDA_MAX)) return 0.0f;
    float f;
    int i = cie_index(lambda, &f);
    return cie_at(cie_d65, i, f) * (1.0f / CIE_D65_Y_INTEGRAL);
}

SpectrumRgb spectrum_rgb_albedo(Color rgb)
{
    SpectrumRgb s = {spectrum_rgb_sigmoid(rgb), 1.0f};
    return s;
}

Color spectrum_rgb_eval_illuminant(const SpectrumRgb *s, const Wavelengths *wl)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++)
        o.c[i] = s->scale * sigmoid_poly_eval(s->poly, wl->lambda[i]) * spectrum_d65(wl->lambda[i]);
    return o;
}

Color spectrum_albedo(Color rgb, const Wavelengths *wl)
{
    SigmoidPoly p = spectrum_rgb_sigmoid(rgb);
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = sigmoid_poly_eval(p, wl->lambda[i]);
    return o;
}

/* pbrt-v4 RGBUnboundedSpectrum: scale 2 max(rgb), so the sigmoid's input has its largest
 * channel at 1/2, where the table is smooth. */
static SigmoidPoly unbounded_sigmoid(Color rgb, float *scale)
{
    float m = fmaxf(fmaxf(rgb.c[0], rgb.c[1]), rgb.c[2]);
    if (!(m > 0.0f)) {
        *scale = 0.0f;
        SigmoidPoly z = {{0.0f, 0.0f, 0.0f}};
        return z;
    }
    *scale = 2.0f * m;
    return spectrum_rgb_sigmoid(color_scale(rgb, 1.0f / *scale));
}

SpectrumRgb spectrum_rgb_unbounded(Color rgb)
{
    SpectrumRgb s;
    s.poly = unbounded_sigmoid(rgb, &s.scale);
    return s;
}

Color spectrum_unbounded(Color rgb, const Wavelengths *wl)
{
    float scale;
    SigmoidPoly p = unbounded_sigmoid(rgb, &scale);
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = scale * sigmoid_poly_eval(p, wl->lambda[i]);
    return o;
}

Color spectrum_illuminant(Color rgb, const Wavelengths *wl)
{
    float scale;
    SigmoidPoly p = unbounded_sigmoid(rgb, &scale);
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = scale * sigmoid_poly_eval(p, wl->lambda[i]) * spectrum_d65(wl->lambda[i]);
    return o;
}

float spectrum_blackbody(float lambda, float T)
{
    if (!(T > 0.0f)) return 0.0f;
    /* Planck: B(lambda, T) = 2 h c^2 / (lambda^5 (exp(h c / (lambda k T)) - 1)), lambda in m. */
    const double c = 299792458.0, h = 6.62606957e-34, kb = 1.3806488e-23;
    double lambda_max = 2.8977721e-3 / (double)T; /* Wien's displacement law, m */
    double l = (double)lambda * 1e-9;
    double b = 2.0 * h * c * c / (pow(l, 5.0) * (exp(h * c / (l * kb * (double)T)) - 1.0));
    double bm = 2.0 * h * c * c / (pow(lambda_max, 5.0) * (exp(h * c / (lambda_max * kb * (double)T)) - 1.0));
    return (float)(b / bm);
}

Color spectrum_to_rgb(Color L, const Wavelengths *wl)
{
    float X = 0.0f, Y = 0.0f, Z = 0.0f;
    for (int i = 0; i < COLOR_LANES; i++) {
        if (wl->pdf[i] == 0.0f) continue;
        float xyz[3];
        spectrum_cie_xyz(wl->lambda[i], xyz);
        float v = L.c[i] / wl->pdf[i];
        X += xyz[0] * v;
        Y += xyz[1] * v;
        Z += xyz[2] * v;
    }
    const float n = 1.0f / (float)COLOR_LANES;
    X *= n, Y *= n, Z *= n;
    const float (*M)[3] = cie_xyz_to_srgb;
    return color_rgb(M[0][0] * X + M[0][1] * Y + M[0][2] * Z, M[1][0] * X + M[1][1] * Y + M[1][2] * Z,
                     M[2][0] * X + M[2][1] * Y + M[2][2] * Z);
}
