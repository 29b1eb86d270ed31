/* A 2D distribution over the unit square, piecewise bilinear between the nodes of a
 * regular grid, possibly conditioned on up to three parameters it is tabulated for and
 * interpolates multilinearly between (pbrt-v4's PiecewiseLinear2D, Mitsuba's Marginal2D;
 * Dupuy & Jakob 2018, sec. 5): sampling by a marginal over rows then a conditional over
 * columns, its exact inverse, and the density. Used by the measured BSDF (materials/
 * measured.c). Positions and samples are in [0, 1]^2; densities are per unit area of it. */
#ifndef CST_SAMPLING_PLINEAR2D_H
#define CST_SAMPLING_PLINEAR2D_H

#include <stdbool.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "math/vec3.h"

enum { PL2D_MAX_PARAMS = 3 };

typedef struct PLinear2D {
    int nx, ny;                           /* grid nodes along x (contiguous) and y, >= 2 */
    int nparams;
    int param_size[PL2D_MAX_PARAMS];      /* nodes per parameter, >= 1 */
    uint32_t param_stride[PL2D_MAX_PARAMS]; /* in slices; 0 for a 1-node parameter */
    float *param_values[PL2D_MAX_PARAMS]; /* increasing node values (owned copies) */
    float *data;                          /* slices x ny x nx values (normalised densities
                                           * when cdf, else the raw values) */
    float *marginal_cdf, *conditional_cdf; /* NULL without a cdf */
    float inv_patch_x, inv_patch_y;       /* nx - 1, ny - 1 */
} PLinear2D;

/* data: param_size[0] x ... x param_size[nparams-1] x ny x nx floats (>= 0 when cdf), the
 * first parameter outermost. cdf: normalise each slice to a density and build the
 * cumulative tables for sampling and inversion; without it only pl2d_eval works and gives
 * the bilinear interpolation of the raw values. CST_ERR_INVALID_ARG for sizes out of range
 * or a slice with no mass (cdf), CST_ERR_OOM. */
CstStatus pl2d_init(PLinear2D *d, const float *data, int nx, int ny, int nparams, const int *param_size,
                    const float *const *param_values, bool cdf, CstError *err);
void pl2d_free(PLinear2D *d);

/* The density (or interpolated value) at pos for the parameters params[0..nparams). */
float pl2d_eval(const PLinear2D *d, Vec2 pos, const float *params);
/* A position distributed as the density for params, from u uniform on [0, 1)^2; *pdf its
 * density. */
Vec2 pl2d_sample(const PLinear2D *d, Vec2 u, const float *params, float *pdf);
/* The inverse of pl2d_sample: the u that maps to pos; *pdf the density at pos. */
Vec2 pl2d_invert(const PLinear2D *d, Vec2 pos, const float *params, float *pdf);

#endif
