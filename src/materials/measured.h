/* pbrt-v4's "measured" material data: an RGL tabulated BSDF (Dupuy & Jakob 2018, "An
 * Adaptive Parameterization for Efficient Material Acquisition and Rendering"), read from
 * its .bsdf tensor file (io/tensor.h) and validated field by field the way pbrt-v4's
 * MeasuredBRDF::Create checks the structure, plus the values (finite, non-negative
 * densities, increasing grids). The evaluation and sampling (piecewise-linear 2D warps)
 * are not implemented yet: this module loads and checks the tables. */
#ifndef CST_MATERIALS_MEASURED_H
#define CST_MATERIALS_MEASURED_H

#include <stdbool.h>
#include <stddef.h>

#include "caustic/caustic.h"

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

#endif
