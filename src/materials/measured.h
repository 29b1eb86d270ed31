/* pbrt-v4's "measured" material data: an RGL tabulated BSDF (Dupuy & Jakob 2018, "An
 * Adaptive Parameterization for Efficient Material Acquisition and Rendering"), read from
 * its .bsdf tensor file (io/tensor.h) and validated field by field the way pbrt-v4's
 * MeasuredBRDF::Create checks the structure, plus the values (finite, non-negative
 * densities, increasing grids); and the BRDF they tabulate (MeasuredBsdf): evaluation,
 * density and sampling through piecewise-bilinear warps (sampling/plinear2d.h), which
 * bsdf.c's MATERIAL_MEASURED lobe calls; the scene owns one per file. */
#ifndef CST_MATERIALS_MEASURED_H
#define CST_MATERIALS_MEASURED_H

#include <stdbool.h>
#include <stddef.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "sampling/plinear2d.h"

typedef struct MeasuredData {
    int n_phi, n_theta;   /* the incident directions' grid: phi_i, theta_i (radians, increasing) */
    float *phi_i, *theta_i;
    int ndf_w, ndf_h;     /* ndf and sigma: [h][w] over the unit square of the half vector's
                           * (theta, phi) and of the incident direction's */
    float *ndf, *sigma;
    int sigma_w, sigma_h;
    int res;              /* vndf, luminance and the reflectance tables: [n_phi][n_theta][res][res] */
    float *vndf, *luminance;
    int n_lambda;         /* spectra: [n_phi][n_theta][n_lambda][res][res] at wavelengths (nm,
                           * increasing); 0 for an RGB file, whose rgb is [..][3][res][res] */
    float *wavelengths, *spectra;
    float *rgb;
    bool isotropic;       /* n_phi <= 2: the tables depend on phi_m - phi_i only */
    bool jacobian;        /* the file's jacobian flag */
    char description[256]; /* the file's description, clipped, NUL-terminated */
} MeasuredData;

/* Loads and checks the .bsdf held in data[0..len); `name` for messages. Errors say
 * "NAME: byte OFFSET: ..." for the file's structure (CST_ERR_PARSE: a field missing, of the
 * wrong type or shape, the file's size not matching its fields) and "NAME: field \"f\" ..."
 * for values. On success the caller frees *out with measured_free. */
CstStatus measured_read(const char *name, const void *data, size_t len, MeasuredData *out, CstError *err);
/* measured_read of a file (through the input-file gate, core/file.h). */
CstStatus measured_read_file(const char *path, MeasuredData *out, CstError *err);
void measured_free(MeasuredData *m);

/* The tabulated BRDF (Dupuy & Jakob 2018 eq. 19): with wo the table's incident direction,
 *   f(wo, wi) = R(s) D(u_m) / (4 sigma(wo) cos theta_i),  s = vndf^-1(u_m | wo),
 * where u_m are the unit-square coordinates of the half vector (theta2u = sqrt(2 theta /
 * pi), phi2u = (phi + pi) / (2 pi); isotropic tables use phi_m - phi_o), D the tabulated
 * NDF, sigma the projected area, R the reflectance tabulated over the VNDF warp's sample
 * space, all interpolated (bilinearly, and linearly between incident angles and
 * wavelengths). Sampling draws s from the luminance table, then u_m from the VNDF warp
 * (pbrt-v4 MeasuredBxDF::Sample_f). pbrt-v4's f() takes wi as the table's incident
 * direction and its Sample_f wo; here wo is in all three, so that eval, pdf and sample
 * describe one function and one density. Local frame, reflection only, wo.z > 0. */
typedef struct MeasuredBsdf {
    PLinear2D ndf, sigma;       /* raw tables */
    PLinear2D vndf, luminance;  /* densities over their unit squares, params (phi_i, theta_i) */
    PLinear2D refl_rgb;         /* R: params (phi_i, theta_i, channel 0, 1, 2), linear sRGB */
    PLinear2D refl_spec;        /* R: params (phi_i, theta_i, wavelength in nm); spectral files */
    bool isotropic;
    bool spectral;              /* refl_spec is there */
    Color albedo;               /* directional albedo at normal incidence (the albedo AOV) */
    char *path;                 /* the file's path (measured_bsdf_read_file), or NULL */
} MeasuredBsdf;

/* The BRDF of loaded tables: R as RGB for RGB rendering (a spectral table converted at load
 * against the CIE 1931 matching functions under D65, as a reflectance's colour) and, for a
 * spectral file, also as spectra for evaluation at a path's wavelengths. */
CstStatus measured_bsdf_init(MeasuredBsdf *b, const MeasuredData *m, CstError *err);
/* measured_read_file then measured_bsdf_init; b->path is a copy of path. */
CstStatus measured_bsdf_read_file(MeasuredBsdf *b, const char *path, CstError *err);
void measured_bsdf_free(MeasuredBsdf *b);
/* f(wo, wi) |cos theta_i| per channel: RGB, or with lambda (4 wavelengths, nm) the values
 * there (a spectral table; an RGB table gives its channels' mean). 0 for wi below. */
Color measured_eval(const MeasuredBsdf *b, Vec3 wo, Vec3 wi, const float *lambda);
/* The density of measured_sample's directions, per unit solid angle. */
float measured_pdf(const MeasuredBsdf *b, Vec3 wo, Vec3 wi);
/* wi from u; *weight = f |cos_i| / pdf, *pdf. False for a direction below the surface. */
bool measured_sample(const MeasuredBsdf *b, Vec3 wo, Vec2 u, const float *lambda, Vec3 *wi, Color *weight, float *pdf);

#endif
