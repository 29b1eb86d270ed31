/* pbrt-v4's named spectra as data: measured n and k of metals, the dispersion of Schott
 * glasses, the CIE standard illuminants A and D65 (spectrum_sampled.h, spectrum_named).
 * Tables are {wavelength nm, n, k}, read from the refractiveindex.info database (public
 * domain, CC0; M. N. Polyanskiy, Sci. Data 11, 94 (2024)), which cites the measurements:
 *   Ag, Au, Cu: P. B. Johnson and R. W. Christy, "Optical constants of the noble metals",
 *               Phys. Rev. B 6, 4370 (1972);
 *   Al:         A. D. Rakic, "Algorithm for the determination of intrinsic optical constants
 *               of metal films: application to aluminum", Appl. Opt. 34, 4755 (1995);
 *   CuZn:       M. R. Querry, "Optical constants", CRDC-CR-85034 (1985), 70% Cu 30% Zn brass.
 * Only the rows around the visible range are kept (first row below 360 nm, last above
 * 830 nm); pbrt-v4 ships its own resampling of similar data, so values differ slightly. */
#include <math.h>
#include <stddef.h>
#include <string.h>

#include "math/cie_data.h"
#include "math/spectrum_sampled.h"

static const float NK_AG[][3] = {
    {284.40f, 1.41f, 1.264f}, {292.40f, 1.39f, 1.161f}, {300.90f, 1.34f, 0.964f},
    {310.70f, 1.13f, 0.616f}, {320.40f, 0.81f, 0.392f}, {331.50f, 0.17f, 0.829f},
    {342.50f, 0.14f, 1.142f}, {354.20f, 0.1f, 1.419f}, {367.90f, 0.07f, 1.657f},
    {381.50f, 0.05f, 1.864f}, {397.40f, 0.05f, 2.07f}, {413.30f, 0.05f, 2.275f},
    {430.50f, 0.04f, 2.462f}, {450.90f, 0.04f, 2.657f}, {471.40f, 0.05f, 2.869f},
    {495.90f, 0.05f, 3.093f}, {520.90f, 0.05f, 3.324f}, {548.60f, 0.06f, 3.586f},
    {582.10f, 0.05f, 3.858f}, {616.80f, 0.06f, 4.152f}, {659.50f, 0.05f, 4.483f},
    {704.50f, 0.04f, 4.838f}, {756.0f, 0.03f, 5.242f}, {821.10f, 0.04f, 5.727f},
    {892.0f, 0.04f, 6.312f},
};
static const float NK_AL[][3] = {
    {247.97f, 0.18137f, 2.9029f}, {309.96f, 0.28003f, 3.7081f}, {326.28f, 0.31474f, 3.9165f},
    {364.66f, 0.39877f, 4.3957f}, {413.28f, 0.52135f, 5.0008f}, {442.80f, 0.6079f, 5.3676f},
    {476.87f, 0.7278f, 5.7781f}, {516.60f, 0.8734f, 6.2418f}, {563.57f, 1.0728f, 6.7839f},
    {619.93f, 1.366f, 7.4052f}, {652.25f, 1.5724f, 7.7354f}, {688.81f, 1.8301f, 8.0601f},
    {729.32f, 2.1606f, 8.3565f}, {774.91f, 2.6154f, 8.4914f}, {794.78f, 2.7675f, 8.3866f},
    {815.69f, 2.7668f, 8.2573f}, {837.74f, 2.6945f, 8.1878f}, {885.61f, 2.2802f, 8.1134f},
};
static const float NK_AU[][3] = {
    {284.40f, 1.47f, 1.869f}, {292.40f, 1.49f, 1.878f}, {300.90f, 1.53f, 1.889f},
    {310.70f, 1.53f, 1.893f}, {320.40f, 1.54f, 1.898f}, {331.50f, 1.48f, 1.883f},
    {342.50f, 1.48f, 1.871f}, {354.20f, 1.5f, 1.866f}, {367.90f, 1.48f, 1.895f},
    {381.50f, 1.46f, 1.933f}, {397.40f, 1.47f, 1.952f}, {413.30f, 1.46f, 1.958f},
    {430.50f, 1.45f, 1.948f}, {450.90f, 1.38f, 1.914f}, {471.40f, 1.31f, 1.849f},
    {495.90f, 1.04f, 1.833f}, {520.90f, 0.62f, 2.081f}, {548.60f, 0.43f, 2.455f},
    {582.10f, 0.29f, 2.863f}, {616.80f, 0.21f, 3.272f}, {659.50f, 0.14f, 3.697f},
    {704.50f, 0.13f, 4.103f}, {756.0f, 0.14f, 4.542f}, {821.10f, 0.16f, 5.083f},
    {892.0f, 0.17f, 5.663f},
};
static const float NK_CU[][3] = {
    {284.40f, 1.45f, 1.633f}, {292.40f, 1.42f, 1.633f}, {300.90f, 1.4f, 1.679f},
    {310.70f, 1.38f, 1.729f}, {320.40f, 1.38f, 1.783f}, {331.50f, 1.34f, 1.821f},
    {342.50f, 1.36f, 1.864f}, {354.20f, 1.37f, 1.916f}, {367.90f, 1.36f, 1.975f},
    {381.50f, 1.33f, 2.045f}, {397.40f, 1.32f, 2.116f}, {413.30f, 1.28f, 2.207f},
    {430.50f, 1.25f, 2.305f}, {450.90f, 1.24f, 2.397f}, {471.40f, 1.25f, 2.483f},
    {495.90f, 1.22f, 2.564f}, {520.90f, 1.18f, 2.608f}, {548.60f, 1.02f, 2.577f},
    {582.10f, 0.7f, 2.704f}, {616.80f, 0.3f, 3.205f}, {659.50f, 0.22f, 3.747f},
    {704.50f, 0.21f, 4.205f}, {756.0f, 0.24f, 4.665f}, {821.10f, 0.26f, 5.18f},
    {892.0f, 0.3f, 5.768f},
};
static const float NK_CUZN[][3] = {
    {300.0f, 1.388f, 1.731f}, {310.0f, 1.419f, 1.764f}, {320.0f, 1.446f, 1.789f},
    {330.0f, 1.473f, 1.807f}, {340.0f, 1.494f, 1.815f}, {350.0f, 1.504f, 1.815f},
    {360.0f, 1.503f, 1.815f}, {370.0f, 1.497f, 1.818f}, {380.0f, 1.487f, 1.818f},
    {390.0f, 1.471f, 1.813f}, {400.0f, 1.445f, 1.805f}, {410.0f, 1.405f, 1.794f},
    {420.0f, 1.35f, 1.786f}, {430.0f, 1.278f, 1.784f}, {440.0f, 1.191f, 1.797f},
    {450.0f, 1.094f, 1.829f}, {460.0f, 0.994f, 1.883f}, {470.0f, 0.9f, 1.957f},
    {480.0f, 0.816f, 2.046f}, {490.0f, 0.745f, 2.145f}, {500.0f, 0.686f, 2.25f},
    {510.0f, 0.639f, 2.358f}, {520.0f, 0.602f, 2.464f}, {530.0f, 0.573f, 2.568f},
    {540.0f, 0.549f, 2.668f}, {550.0f, 0.527f, 2.765f}, {560.0f, 0.505f, 2.86f},
    {570.0f, 0.484f, 2.958f}, {580.0f, 0.468f, 3.059f}, {590.0f, 0.46f, 3.159f},
    {600.0f, 0.45f, 3.253f}, {610.0f, 0.452f, 3.345f}, {620.0f, 0.449f, 3.434f},
    {630.0f, 0.445f, 3.522f}, {640.0f, 0.444f, 3.609f}, {650.0f, 0.444f, 3.695f},
    {660.0f, 0.445f, 3.778f}, {670.0f, 0.444f, 3.86f}, {680.0f, 0.444f, 3.943f},
    {690.0f, 0.445f, 4.025f}, {700.0f, 0.446f, 4.106f}, {710.0f, 0.448f, 4.186f},
    {720.0f, 0.45f, 4.266f}, {730.0f, 0.452f, 4.346f}, {740.0f, 0.455f, 4.424f},
    {750.0f, 0.457f, 4.501f}, {760.0f, 0.458f, 4.579f}, {770.0f, 0.46f, 4.657f},
    {780.0f, 0.464f, 4.737f}, {790.0f, 0.469f, 4.814f}, {800.0f, 0.473f, 4.89f},
    {810.0f, 0.478f, 4.965f}, {820.0f, 0.481f, 5.039f}, {830.0f, 0.483f, 5.115f},
    {840.0f, 0.486f, 5.192f},
};

/* Sellmeier coefficients B1, C1, B2, C2, B3, C3 (C in um^2) of the SCHOTT optical glass
 * catalogue (Zemax catalog 2017-01-20b, as given by refractiveindex.info):
 * n^2 - 1 = sum_i B_i lambda^2 / (lambda^2 - C_i), lambda in um. pbrt-v4's BK7, BAF10,
 * FK51A, LASF9 are SCHOTT's current N- glasses; F5, SF5, SF10, SF11 the lead glasses. */
static const struct { const char *name; double b[6]; } GLASSES[] = {
    {"BK7", {1.03961212, 0.00600069867, 0.231792344, 0.0200179144, 1.01046945, 103.560653}},
    {"BAF10", {1.5851495, 0.00926681282, 0.143559385, 0.0424489805, 1.08521269, 105.613573}},
    {"FK51A", {0.971247817, 0.00472301995, 0.216901417, 0.0153575612, 0.904651666, 168.68133}},
    {"LASF9", {2.00029547, 0.0121426017, 0.298926886, 0.0538736236, 1.80691843, 156.530829}},
    {"F5", {1.3104463, 0.00958633048, 0.19603426, 0.0457627627, 0.96612977, 115.011883}},
    {"SF5", {1.46141885, 0.0111826126, 0.247713019, 0.0508594669, 0.949995832, 112.041888}},
    {"SF10", {1.61625977, 0.0127534559, 0.259229334, 0.0581983954, 1.07762317, 116.60768}},
    {"SF11", {1.73848403, 0.0136068604, 0.311168974, 0.0615960463, 1.17490871, 121.922711}},
};
/* F10 and F11 are not in the current SCHOTT catalogue: their n_d (587.6 nm) as a constant,
 * reported as approximated (no dispersion). */
static const struct { const char *name; float nd; } GLASSES_ND[] = {{"F10", 1.6200f}, {"F11", 1.6259f}};

const char *const spectrum_named_list[] = {
    "metal-Ag-eta", "metal-Ag-k", "metal-Al-eta", "metal-Al-k", "metal-Au-eta", "metal-Au-k",
    "metal-Cu-eta", "metal-Cu-k", "metal-CuZn-eta", "metal-CuZn-k", "metal-MgO-eta", "metal-MgO-k",
    "metal-TiO2-eta", "metal-TiO2-k", "glass-BK7", "glass-BAF10", "glass-FK51A", "glass-LASF9",
    "glass-F5", "glass-F10", "glass-F11", "glass-SF5", "glass-SF10", "glass-SF11", "stdillum-A",
    "stdillum-D65", NULL};

static void from_nk(const float (*t)[3], int rows, int col, SampledSpectrum *out)
{
    float l[64], v[64];
    for (int i = 0; i < rows; i++) {
        l[i] = t[i][0];
        v[i] = t[i][col];
    }
    sampled_spectrum_from_pairs(l, v, rows, out);
}

/* n(lambda) from n^2(lambda um^2) by fn at every node. */
static void from_n2(double (*n2)(double l2, const double *c), const double *c, SampledSpectrum *out)
{
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
        double l = (double)(SPECTRUM_LAMBDA_MIN + i) * 1e-3;
        out->v[i] = (float)sqrt(n2(l * l, c));
    }
    out->constant = false;
}

static double sellmeier_n2(double l2, const double *b)
{
    return 1.0 + b[0] * l2 / (l2 - b[1]) + b[2] * l2 / (l2 - b[3]) + b[4] * l2 / (l2 - b[5]);
}
/* MgO: R. E. Stephens and I. H. Malitson, "Index of refraction of magnesium oxide", J. Res.
 * NBS 49, 249 (1952), their formula over 0.36-5.4 um. */
static double mgo_n2(double l2, const double *c)
{
    (void)c;
    return 2.956362 + 0.02195770 / (l2 - 0.01428322) - 0.01062387 * l2 - 0.0000204968 * l2 * l2;
}
/* TiO2 (rutile, ordinary ray): J. R. Devore, "Refractive indices of rutile and sphalerite",
 * J. Opt. Soc. Am. 41, 416 (1951), over 0.43-1.53 um (extrapolated below). */
static double tio2_n2(double l2, const double *c)
{
    (void)c;
    return 5.913 + 0.2441 / (l2 - 0.0803);
}

#define NK(t) t, (int)(sizeof t / sizeof t[0])
static bool named_metal(const char *m, SampledSpectrum *out)
{
    static const struct { const char *name; const float (*t)[3]; int rows; } T[] = {
        {"Ag", NK(NK_AG)}, {"Al", NK(NK_AL)}, {"Au", NK(NK_AU)}, {"Cu", NK(NK_CU)}, {"CuZn", NK(NK_CUZN)}};
    for (size_t i = 0; i < sizeof T / sizeof T[0]; i++) {
        size_t n = strlen(T[i].name);
        if (strncmp(m, T[i].name, n) != 0) continue;
        if (strcmp(m + n, "-eta") == 0) from_nk(T[i].t, T[i].rows, 1, out);
        else if (strcmp(m + n, "-k") == 0) from_nk(T[i].t, T[i].rows, 2, out);
        else continue;
        return true;
    }
    /* The two dielectrics pbrt-v4 files under metal-: k = 0 over the visible range. */
    bool mgo = strncmp(m, "MgO-", 4) == 0, tio2 = strncmp(m, "TiO2-", 5) == 0;
    if (!mgo && !tio2) return false;
    const char *part = m + (mgo ? 4 : 5);
    if (strcmp(part, "k") == 0) sampled_spectrum_constant(0.0f, out);
    else if (strcmp(part, "eta") == 0) from_n2(mgo ? mgo_n2 : tio2_n2, NULL, out);
    else return false;
    return true;
}

bool spectrum_named(const char *name, SampledSpectrum *out, bool *approx)
{
    *approx = false;
    if (strncmp(name, "metal-", 6) == 0) return named_metal(name + 6, out);
    if (strncmp(name, "glass-", 6) == 0) {
        for (size_t i = 0; i < sizeof GLASSES / sizeof GLASSES[0]; i++)
            if (strcmp(name + 6, GLASSES[i].name) == 0) {
                from_n2(sellmeier_n2, GLASSES[i].b, out);
                return true;
            }
        for (size_t i = 0; i < sizeof GLASSES_ND / sizeof GLASSES_ND[0]; i++)
            if (strcmp(name + 6, GLASSES_ND[i].name) == 0) {
                sampled_spectrum_constant(GLASSES_ND[i].nd, out);
                *approx = true;
                return true;
            }
        return false;
    }
    if (strcmp(name, "stdillum-D65") == 0) {
        /* The tabulated D65 on its CIE scale (100 at 560 nm). */
        for (int i = 0; i < SAMPLED_SPECTRUM_N; i++)
            out->v[i] = spectrum_d65((float)(SPECTRUM_LAMBDA_MIN + i)) * CIE_D65_Y_INTEGRAL;
        out->constant = false;
        return true;
    }
    if (strcmp(name, "stdillum-A") == 0) {
        /* CIE 15:2004 eq. 1: S_A = 100 (560 / lambda)^5 (e^(c2 / (2848 * 560)) - 1) /
         * (e^(c2 / (2848 lambda)) - 1), c2 = 1.435e7 nm K. */
        const double c2 = 1.435e7, T = 2848.0;
        for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
            double l = (double)(SPECTRUM_LAMBDA_MIN + i);
            out->v[i] = (float)(100.0 * pow(560.0 / l, 5.0) * (exp(c2 / (T * 560.0)) - 1.0) / (exp(c2 / (T * l)) - 1.0));
        }
        out->constant = false;
        return true;
    }
    return false;
}
