/* Spectra as linear sRGB: CIE 1931 matching functions, blackbodies, sampled and named
 * spectra (metals, glasses), and spectrum-valued parameters. */
#include "scene/pbrt/pbrt_spectrum.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/spd.h"
#include "math/spectrum_sampled.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_texture.h"

/* CIE 1931 colour matching functions by the multi-lobe Gaussian fit of Wyman, Sloan and
 * Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching Functions"
 * (JCGT 2013), eq. 2: close enough for turning a spectrum into three numbers. */
static double cmf_g(double x, double mu, double s1, double s2)
{
    double t = (x - mu) / (x < mu ? s1 : s2);
    return exp(-0.5 * t * t);
}

static void cmf(double l, double xyz[3])
{
    xyz[0] = 1.056 * cmf_g(l, 599.8, 37.9, 31.0) + 0.362 * cmf_g(l, 442.0, 16.0, 26.7) -
             0.065 * cmf_g(l, 501.1, 20.4, 26.2);
    xyz[1] = 0.821 * cmf_g(l, 568.8, 46.9, 40.5) + 0.286 * cmf_g(l, 530.9, 16.3, 31.1);
    xyz[2] = 1.217 * cmf_g(l, 437.0, 11.8, 36.0) + 0.681 * cmf_g(l, 459.0, 26.0, 13.8);
}

/* XYZ to linear sRGB (IEC 61966-2-1, D65 white). */
static void xyz_to_rgb(const double x[3], double out[3])
{
    out[0] = 3.2404542 * x[0] - 1.5371385 * x[1] - 0.4985314 * x[2];
    out[1] = -0.9692660 * x[0] + 1.8760108 * x[1] + 0.0415560 * x[2];
    out[2] = 0.0556434 * x[0] - 0.2040259 * x[1] + 1.0572252 * x[2];
}

static Color rgb_from_d(const double c[3]) { return color_rgb((float)c[0], (float)c[1], (float)c[2]); }

Color pbrt_blackbody_rgb(double kelvin)
{
    if (!(kelvin > 0.0))
        return color_s(0.0f);
    /* Planck's law up to a constant factor, which the luminance normalisation removes. */
    const double c2 = 1.4387769e7; /* h c / k_B in nm K */
    double xyz[3] = {0, 0, 0};
    for (double l = 360.0; l <= 830.0; l += 1.0) {
        double b = 1.0 / (pow(l * 1e-3, 5.0) * (exp(c2 / (l * kelvin)) - 1.0)), w[3];
        if (!isfinite(b)) continue;
        cmf(l, w);
        for (int k = 0; k < 3; k++) xyz[k] += b * w[k];
    }
    if (!(xyz[1] > 0.0))
        return color_s(0.0f);
    double y = xyz[1];
    for (int k = 0; k < 3; k++) xyz[k] /= y;
    double c[3];
    xyz_to_rgb(xyz, c);
    for (int k = 0; k < 3; k++) c[k] = c[k] > 0.0 ? c[k] : 0.0; /* outside the gamut: clip */
    return rgb_from_d(c);
}

static double spectrum_at(const double *pairs, int n, double l)
{
    if (n == 0 || l < pairs[0] || l > pairs[2 * (n - 1)]) return 0.0;
    for (int i = 0; i + 1 < n; i++) {
        double l0 = pairs[2 * i], l1 = pairs[2 * i + 2];
        if (l >= l0 && l <= l1)
            return l1 > l0 ? pairs[2 * i + 1] + (pairs[2 * i + 3] - pairs[2 * i + 1]) * (l - l0) / (l1 - l0)
                           : pairs[2 * i + 1];
    }
    return pairs[2 * n - 1];
}

Color pbrt_spectrum_rgb(const double *pairs, int num_pairs, bool illuminant)
{
    double xyz[3] = {0, 0, 0}, white[3] = {0, 0, 0};
    if (num_pairs == 1) /* a single sample: a constant spectrum */
        return illuminant ? color_s(1.0f) : color_s((float)pairs[1]);
    for (double l = 360.0; l <= 830.0; l += 1.0) {
        double w[3], s = spectrum_at(pairs, num_pairs, l);
        cmf(l, w);
        for (int k = 0; k < 3; k++) {
            xyz[k] += s * w[k];
            white[k] += w[k];
        }
    }
    double c[3], cw[3];
    if (illuminant) {
        double y = xyz[1];
        if (!(y > 0.0)) return color_s(0.0f);
        for (int k = 0; k < 3; k++) xyz[k] /= y;
        xyz_to_rgb(xyz, c);
    } else {
        /* Per-channel normalisation by the flat spectrum: a constant reflectance c maps to
         * exactly (c, c, c) despite the equal-energy white not being sRGB's D65. */
        xyz_to_rgb(xyz, c);
        xyz_to_rgb(white, cw);
        for (int k = 0; k < 3; k++) c[k] /= cw[k];
    }
    for (int k = 0; k < 3; k++) c[k] = c[k] > 0.0 ? c[k] : 0.0;
    return rgb_from_d(c);
}

/* pbrt-v4's named metals "metal-<X>-eta" / "-k". Gold, silver, copper and aluminium are
 * caustic's cited presets (material_metal, materials/material.c). The other three are RGB
 * readings at about 650, 550 and 450 nm of the sampled data pbrt ships (CuZn: brass; MgO
 * and TiO2 are dielectrics, k = 0; MgO's n agrees with Stephens & Malitson, J. Res. NBS
 * 49, 249 (1952), n = 1.7355 at 589 nm); get_spectrum reports them as approximated. */
static const struct { const char *name, *preset; float eta[3], k[3]; } PBRT_METALS[] = {
    {"Ag", "silver", {0}, {0}},
    {"Al", "aluminium", {0}, {0}},
    {"Au", "gold", {0}, {0}},
    {"Cu", "copper", {0}, {0}},
    {"CuZn", NULL, {0.444f, 0.527f, 1.094f}, {3.695f, 2.765f, 1.829f}},
    {"MgO", NULL, {1.732f, 1.738f, 1.750f}, {0.0f, 0.0f, 0.0f}},
    {"TiO2", NULL, {2.58f, 2.66f, 2.87f}, {0.0f, 0.0f, 0.0f}},
};

/* The table entry of a named metal spectrum, with is_k set for "-k"; -1 if unknown. */
static int named_metal_index(const char *name, int *is_k)
{
    if (strncmp(name, "metal-", 6) != 0) return -1;
    const char *m = name + 6;
    for (int i = 0; i < (int)(sizeof PBRT_METALS / sizeof PBRT_METALS[0]); i++) {
        size_t n = strlen(PBRT_METALS[i].name);
        if (strncmp(m, PBRT_METALS[i].name, n) == 0 && m[n] == '-') {
            if (strcmp(m + n, "-eta") == 0) *is_k = 0;
            else if (strcmp(m + n, "-k") == 0) *is_k = 1;
            else return -1;
            return i;
        }
    }
    return -1;
}

bool pbrt_named_metal(const char *name, Color *out)
{
    int is_k = 0, i = named_metal_index(name, &is_k);
    if (i < 0) return false;
    if (PBRT_METALS[i].preset) {
        Color eta, k;
        material_metal(PBRT_METALS[i].preset, &eta, &k);
        *out = is_k ? k : eta;
        return true;
    }
    const float *v = is_k ? PBRT_METALS[i].k : PBRT_METALS[i].eta;
    *out = color_rgb(v[0], v[1], v[2]);
    return true;
}

static float r0_channel(float n, float k)
{
    return ((n - 1.0f) * (n - 1.0f) + k * k) / ((n + 1.0f) * (n + 1.0f) + k * k);
}

Color pbrt_conductor_r0(Color eta, Color k)
{
    return color_rgb(r0_channel(eta.c[0], k.c[0]), r0_channel(eta.c[1], k.c[1]), r0_channel(eta.c[2], k.c[2]));
}

/* n_d (587.6 nm) of pbrt-v4's named glasses (Schott catalogue); pbrt-v4's F5/F10/F11 are the
 * dense flints SF5/SF10/SF11 (spectrum_data.c). */
static int named_glass(const char *name, float *eta)
{
    static const struct { const char *name; float eta; } g[] = {
        {"glass-BK7", 1.5168f}, {"glass-BAF10", 1.6700f}, {"glass-FK51A", 1.4866f},
        {"glass-LASF9", 1.8503f}, {"glass-F5", 1.6727f}, {"glass-F10", 1.7283f},
        {"glass-F11", 1.7847f}, {"glass-SF5", 1.6727f}, {"glass-SF10", 1.7283f},
        {"glass-SF11", 1.7847f}};
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
        if (strcmp(name, g[i].name) == 0) {
            *eta = g[i].eta;
            return 1;
        }
    return 0;
}

/* A sampled spectrum handed to the scene (cst_scene_add_spectrum) at its 1 nm nodes. */
static CstStatus add_sampled(Loader *ld, const SampledSpectrum *sp, int *id)
{
    float l[SAMPLED_SPECTRUM_N];
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) l[i] = (float)(SPECTRUM_LAMBDA_MIN + i);
    return cst_scene_add_spectrum(ld->scene, l, sp->v, SAMPLED_SPECTRUM_N, id, ld->err);
}

/* The RGB a sampled spectrum stands for as a parameter of this kind. */
static Color sampled_rgb(const SampledSpectrum *sp, SpecKind kind)
{
    return kind == SPEC_ILLUMINANT ? sampled_spectrum_rgb_illuminant(sp) : sampled_spectrum_rgb_unbounded(sp);
}

/* A .spd file named by a "spectrum" parameter (pbrt-v4 reads a string that is not a named
 * spectrum as a file): its RGB as this kind, and with spectrum_id the scene's spectrum. */
static CstStatus spd_param(Loader *ld, const Param *p, const char *d, SpecKind kind, Color *c, int *spectrum_id)
{
    char nm[72];
    TRY(pbrt_check_file_access(ld, p->loc, d));
    char *path = pbrt_resolve_path(ld, p->strs[0]);
    if (!path) return pbrt_oom(ld);
    float *l = NULL, *v = NULL;
    int n = 0;
    CstError e;
    e.status = CST_OK, e.msg[0] = '\0';
    CstStatus st = spd_read_file(path, &l, &v, &n, &e);
    free(path);
    if (st != CST_OK)
        return pbrt_fail_at(ld, st, p->loc, "%s: \"%s\": %s (expected a named spectrum or a .spd file of "
                            "wavelength-value pairs)", d, pbrt_clip(p->decl, nm), e.msg);
    SampledSpectrum *sp = malloc(sizeof *sp);
    if (!sp) {
        free(l), free(v);
        return pbrt_oom(ld);
    }
    sampled_spectrum_from_pairs(l, v, n, sp);
    free(l), free(v);
    *c = sampled_rgb(sp, kind);
    st = spectrum_id ? add_sampled(ld, sp, spectrum_id) : CST_OK;
    free(sp);
    return st;
}

CstStatus pbrt_get_spectrum(Loader *ld, Params *ps, const char *d, const char *name,
                            SpecKind kind, int allow_tex, Color *out, int *found)
{
    return pbrt_get_spectrum_id(ld, ps, d, name, kind, allow_tex, out, found, NULL);
}

CstStatus pbrt_get_spectrum_id(Loader *ld, Params *ps, const char *d, const char *name, SpecKind kind,
                               int allow_tex, Color *out, int *found, int *spectrum_id)
{
    Param *p;
    char nm[72];
    if (spectrum_id) *spectrum_id = 0;
    unsigned allowed = PT_MASK(PT_RGB) | PT_MASK(PT_SPECTRUM) | PT_MASK(PT_BLACKBODY) | PT_MASK(PT_XYZ) |
                       (allow_tex ? PT_MASK(PT_TEXTURE) : 0u);
    if (found) *found = 0;
    TRY(pbrt_lookup(ld, ps, d, name, allowed,
                    allow_tex ? "rgb, spectrum, blackbody or texture" : "rgb, spectrum or blackbody", &p));
    if (!p) return CST_OK;
    Color c = *out;
    switch (p->type) {
    case PT_TEXTURE: TRY(pbrt_texture_ref(ld, p, d, 0, &c)); break;
    case PT_RGB: c = color_rgb((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]); break;
    case PT_XYZ: {
        double x[3] = {p->nums[0], p->nums[1], p->nums[2]}, r[3];
        xyz_to_rgb(x, r);
        c = rgb_from_d(r);
        break;
    }
    case PT_BLACKBODY:
        c = pbrt_blackbody_rgb(p->nums[0]);
        if (p->num_nums == 2) c = color_scale(c, (float)p->nums[1]);
        if (spectrum_id && p->nums[0] > 0.0 && p->nums[0] < 1e6) {
            /* pbrt-v4's BlackbodySpectrum (peak 1); the RGB above sets the luminance. */
            SampledSpectrum *sp = malloc(sizeof *sp);
            if (!sp) return pbrt_oom(ld);
            sampled_spectrum_blackbody((float)p->nums[0], sp);
            CstStatus st = add_sampled(ld, sp, spectrum_id);
            free(sp);
            TRY(st);
        }
        break;
    case PT_SPECTRUM:
        if (p->num_strs) {
            const char *s = p->strs[0];
            float eta = 0.0f;
            int is_k = 0, mi = named_metal_index(s, &is_k);
            SampledSpectrum *sp = spectrum_id ? malloc(sizeof *sp) : NULL;
            if (spectrum_id && !sp) return pbrt_oom(ld);
            bool named = sp && spectrum_named(s, sp);
            if (named) {
                /* Kept as a spectrum for spectral mode; its RGB for RGB mode. */
                CstStatus st = add_sampled(ld, sp, spectrum_id);
                c = strncmp(s, "glass-", 6) == 0 ? color_s(sampled_spectrum_mean_y(sp)) : sampled_rgb(sp, kind);
                free(sp);
                TRY(st);
            }
            free(named ? NULL : sp);
            if (named) {
                /* kept above */
            } else if (mi >= 0) {
                pbrt_named_metal(s, &c);
                if (!PBRT_METALS[mi].preset)
                    pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                            "%s: \"%s\" taken as the RGB (%g, %g, %g) of its spectrum at about "
                                 "650, 550 and 450 nm", d, pbrt_clip(s, nm), (double)c.c[0], (double)c.c[1], (double)c.c[2]);
            } else if (named_glass(s, &eta)) {
                c = color_s(eta);
                pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                             "%s: \"%s\" \"%s\" taken as the constant %g (n_d): no dispersion", d,
                             pbrt_clip(p->decl, nm), s, (double)eta);
            } else if (strcmp(s, "stdillum-D65") == 0 || strcmp(s, "illum-D65") == 0) {
                c = color_s(1.0f); /* sRGB's white point */
            } else if (strcmp(s, "stdillum-A") == 0 || strcmp(s, "illum-A") == 0) {
                c = pbrt_blackbody_rgb(2856.0);
            } else if (strncmp(s, "stdillum-", 9) == 0 || strncmp(s, "illum-", 6) == 0) {
                c = color_s(1.0f);
                pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: illuminant \"%s\" taken as white (D65)",
                             d, pbrt_clip(s, nm));
            } else {
                TRY(spd_param(ld, p, d, kind, &c, spectrum_id));
            }
        } else {
            for (int i = 1; i < p->num_nums / 2; i++)
                if (!(p->nums[2 * i] > p->nums[2 * i - 2]))
                    return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                                   "%s: \"%s\": wavelength %g does not increase; expected "
                                        "(wavelength, value) pairs in increasing wavelength", d,
                                        pbrt_clip(p->decl, nm), p->nums[2 * i]);
            c = pbrt_spectrum_rgb(p->nums, p->num_nums / 2, kind == SPEC_ILLUMINANT);
            if (spectrum_id) {
                int np = p->num_nums / 2;
                float *l = malloc((size_t)(np > 0 ? np : 1) * 2 * sizeof *l);
                if (!l) return pbrt_oom(ld);
                for (int i = 0; i < np; i++) l[i] = (float)p->nums[2 * i], l[np + i] = (float)p->nums[2 * i + 1];
                CstStatus st = np > 0 ? cst_scene_add_spectrum(ld->scene, l, l + np, np, spectrum_id, ld->err) : CST_OK;
                free(l);
                if (st != CST_OK) {
                    char msg[sizeof ld->err->msg];
                    snprintf(msg, sizeof msg, "%s", ld->err->msg);
                    return pbrt_fail_at(ld, st, p->loc, "%s: \"%s\": %s", d, pbrt_clip(p->decl, nm), msg);
                }
            }
        }
        break;
    default: break;
    }
    if (!color_is_finite(c))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" is not finite as a 32-bit RGB",
                            d, pbrt_clip(p->decl, nm));
    if (c.c[0] < 0.0f || c.c[1] < 0.0f || c.c[2] < 0.0f || (kind == SPEC_REFLECTANCE && color_max(c) > 1.0f)) {
        Color k = color_rgb(clampf(c.c[0], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX),
                    clampf(c.c[1], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX),
                    clampf(c.c[2], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX));
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                     "%s: \"%s\" (%g, %g, %g) clamped to (%g, %g, %g)%s", d, pbrt_clip(p->decl, nm),
                     (double)c.c[0], (double)c.c[1], (double)c.c[2], (double)k.c[0], (double)k.c[1], (double)k.c[2],
                     kind == SPEC_REFLECTANCE ? ": a reflectance lies in [0, 1]" : "");
        c = k;
    }
    *out = c;
    if (found) *found = 1;
    return CST_OK;
}
