/* The piecewise-bilinear 2D distribution (formulas and conventions in plinear2d.h): the
 * marginal cdf over rows and the conditional cdfs within rows are integrals of the
 * bilinear interpolant, so sampling inverts quadratics (the trapezoid's cdf) exactly. */
#include "sampling/plinear2d.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

void pl2d_free(PLinear2D *d)
{
    if (!d) return;
    for (int i = 0; i < PL2D_MAX_PARAMS; i++) free(d->param_values[i]);
    free(d->data);
    free(d->marginal_cdf);
    free(d->conditional_cdf);
    memset(d, 0, sizeof *d);
}

CstStatus pl2d_init(PLinear2D *d, const float *data, int nx, int ny, int nparams, const int *param_size,
                    const float *const *param_values, bool cdf, CstError *err)
{
    memset(d, 0, sizeof *d);
    if (nx < 2 || ny < 2 || nx > 65536 || ny > 65536 || nparams < 0 || nparams > PL2D_MAX_PARAMS)
        return cst_fail(err, CST_ERR_INVALID_ARG, "pl2d_init: %d x %d nodes, %d parameters; expected 2 to 65536 "
                        "nodes each way and at most %d parameters", nx, ny, nparams, PL2D_MAX_PARAMS);
    d->nx = nx, d->ny = ny, d->nparams = nparams;
    d->inv_patch_x = (float)(nx - 1), d->inv_patch_y = (float)(ny - 1);
    size_t slices = 1;
    for (int i = nparams - 1; i >= 0; i--) {
        if (param_size[i] < 1 || param_size[i] > 65536 || slices * (size_t)param_size[i] > (1u << 24))
            return cst_fail(err, CST_ERR_INVALID_ARG, "pl2d_init: parameter %d has %d nodes; expected 1 to 65536", i,
                            param_size[i]);
        d->param_size[i] = param_size[i];
        d->param_stride[i] = param_size[i] > 1 ? (uint32_t)slices : 0u;
        slices *= (size_t)param_size[i];
        d->param_values[i] = malloc((size_t)param_size[i] * sizeof(float));
        if (!d->param_values[i]) goto oom;
        memcpy(d->param_values[i], param_values[i], (size_t)param_size[i] * sizeof(float));
    }
    const size_t n = (size_t)nx * (size_t)ny;
    d->data = malloc(slices * n * sizeof(float));
    if (!d->data) goto oom;
    if (!cdf) {
        memcpy(d->data, data, slices * n * sizeof(float));
        return CST_OK;
    }
    d->marginal_cdf = malloc(slices * (size_t)ny * sizeof(float));
    d->conditional_cdf = malloc(slices * n * sizeof(float));
    if (!d->marginal_cdf || !d->conditional_cdf) goto oom;
    for (size_t s = 0; s < slices; s++) {
        const float *in = data + s * n;
        float *cond = d->conditional_cdf + s * n, *marg = d->marginal_cdf + s * (size_t)ny, *out = d->data + s * n;
        /* Per row, the integral of the linear interpolant from x = 0 (in node spacings). */
        for (int y = 0; y < ny; y++) {
            double sum = 0.0;
            size_t i = (size_t)y * (size_t)nx;
            cond[i] = 0.0f;
            for (int x = 0; x < nx - 1; x++, i++) {
                sum += 0.5 * ((double)in[i] + (double)in[i + 1]);
                cond[i + 1] = (float)sum;
            }
        }
        /* Over rows, the integral of the rows' totals, linear between rows. */
        double sum = 0.0;
        marg[0] = 0.0f;
        for (int y = 0; y < ny - 1; y++) {
            sum += 0.5 * ((double)cond[(size_t)(y + 1) * (size_t)nx - 1] + (double)cond[(size_t)(y + 2) * (size_t)nx - 1]);
            marg[y + 1] = (float)sum;
        }
        if (!(sum > 0.0) || !isfinite(sum)) {
            pl2d_free(d);
            return cst_fail(err, CST_ERR_INVALID_ARG, "pl2d_init: slice %zu has no mass (total %g); expected a density "
                            "with a positive integral", s, sum);
        }
        /* Normalised to a density on the unit square: the cdfs to 1, the values by the same
         * factor (their integral in node units is sum; the square has (nx-1)(ny-1) of them). */
        const float norm = (float)(1.0 / sum);
        for (size_t k = 0; k < n; k++) cond[k] *= norm, out[k] = in[k] * norm;
        for (int y = 0; y < ny; y++) marg[y] *= norm;
    }
    return CST_OK;
oom:
    pl2d_free(d);
    return cst_fail(err, CST_ERR_OOM, "pl2d_init: out of memory for %d x %d nodes", nx, ny);
}

/* The multilinear blend over the parameters of a table's entry i0 of slice size `size`
 * (pbrt-v4's lookup<Dimension>): the last parameter innermost. */
static float lookup(const PLinear2D *d, const float *t, uint32_t i0, uint32_t size, const float *w, int dim)
{
    if (dim == 0) return t[i0];
    uint32_t i1 = i0 + d->param_stride[dim - 1] * size;
    float v0 = lookup(d, t, i0, size, w, dim - 1), v1 = lookup(d, t, i1, size, w, dim - 1);
    return fmaf(v0, w[2 * dim - 2], v1 * w[2 * dim - 1]);
}

/* The largest index i in [0, n - 2] with pred(i) true (pbrt-v4's FindInterval). */
#define FIND_INTERVAL(n, pred_i, out)                                   \
    do {                                                                \
        int lo_ = 1, len_ = (n) - 2;                                    \
        while (len_ > 0) {                                              \
            int half_ = len_ >> 1, i = lo_ + half_;                     \
            if (pred_i) { lo_ = i + 1; len_ -= half_ + 1; }             \
            else len_ = half_;                                          \
        }                                                               \
        (out) = (uint32_t)(lo_ - 1 < 0 ? 0 : lo_ - 1 > (n) - 2 ? (n) - 2 : lo_ - 1); \
    } while (0)

/* Each parameter's interpolation weights and the offset of its lower node's slice. */
static uint32_t param_weights(const PLinear2D *d, const float *params, float *w)
{
    uint32_t slice = 0;
    for (int k = 0; k < d->nparams; k++) {
        if (d->param_size[k] == 1) {
            w[2 * k] = 1.0f, w[2 * k + 1] = 0.0f;
            continue;
        }
        const float *v = d->param_values[k], x = params[k];
        uint32_t idx;
        FIND_INTERVAL(d->param_size[k], v[i] <= x, idx);
        float t = (x - v[idx]) / (v[idx + 1] - v[idx]);
        t = t > 0.0f ? (t < 1.0f ? t : 1.0f) : 0.0f;
        w[2 * k + 1] = t, w[2 * k] = 1.0f - t;
        slice += d->param_stride[k] * idx;
    }
    return slice;
}

float pl2d_eval(const PLinear2D *d, Vec2 pos, const float *params)
{
    float w[2 * PL2D_MAX_PARAMS];
    const uint32_t size = (uint32_t)(d->nx * d->ny), slice = param_weights(d, params, w);
    float px = pos.x * d->inv_patch_x, py = pos.y * d->inv_patch_y;
    int ox = (int)px, oy = (int)py;
    if (ox > d->nx - 2) ox = d->nx - 2;
    if (oy > d->ny - 2) oy = d->ny - 2;
    if (ox < 0) ox = 0;
    if (oy < 0) oy = 0;
    float w1x = px - (float)ox, w1y = py - (float)oy, w0x = 1.0f - w1x, w0y = 1.0f - w1y;
    uint32_t i = (uint32_t)ox + (uint32_t)oy * (uint32_t)d->nx + slice * size;
    float v00 = lookup(d, d->data, i, size, w, d->nparams), v10 = lookup(d, d->data + 1, i, size, w, d->nparams),
          v01 = lookup(d, d->data + d->nx, i, size, w, d->nparams),
          v11 = lookup(d, d->data + d->nx + 1, i, size, w, d->nparams);
    float v = fmaf(w0y, fmaf(w0x, v00, w1x * v10), w1y * fmaf(w0x, v01, w1x * v11));
    /* a density per unit square; raw tables are returned as interpolated */
    return d->marginal_cdf ? v * d->inv_patch_x * d->inv_patch_y : v;
}

/* Inverts the cdf of a linear density from c0 to c1 on [0, 1] at mass s (pbrt-v4's
 * trapezoid inversion, with the constant case apart). */
static float invert_linear(float c0, float c1, float s)
{
    const bool flat = fabsf(c0 - c1) < 1e-4f * (c0 + c1);
    float t = flat ? 2.0f * s : c0 - sqrtf(fmaxf(c0 * c0 - 2.0f * s * (c0 - c1), 0.0f));
    return t / (flat ? c0 + c1 : c0 - c1);
}

Vec2 pl2d_sample(const PLinear2D *d, Vec2 u, const float *params, float *pdf)
{
    const float lo = 0x1p-24f, hi = 1.0f - 0x1p-24f; /* away from the extrema */
    u.x = u.x < lo ? lo : u.x > hi ? hi : u.x;
    u.y = u.y < lo ? lo : u.y > hi ? hi : u.y;
    float w[2 * PL2D_MAX_PARAMS];
    const int np = d->nparams, nx = d->nx, ny = d->ny;
    const uint32_t size = (uint32_t)(nx * ny), slice = param_weights(d, params, w);
    /* The row, from the marginal cdf. */
    const uint32_t moff = slice * (uint32_t)ny;
    uint32_t row;
    FIND_INTERVAL(ny, lookup(d, d->marginal_cdf, moff + (uint32_t)i, (uint32_t)ny, w, np) < u.y, row);
    u.y -= lookup(d, d->marginal_cdf, moff + row, (uint32_t)ny, w, np);
    uint32_t off = row * (uint32_t)nx + slice * size;
    float r0 = lookup(d, d->conditional_cdf, off + (uint32_t)nx - 1, size, w, np),
          r1 = lookup(d, d->conditional_cdf, off + (uint32_t)nx * 2 - 1, size, w, np);
    u.y = invert_linear(r0, r1, u.y);
    /* The column, from the conditional cdf interpolated between the two rows. */
    u.x *= (1.0f - u.y) * r0 + u.y * r1;
    const float *cc = d->conditional_cdf;
    uint32_t col;
    FIND_INTERVAL(nx,
                  (1.0f - u.y) * lookup(d, cc, off + (uint32_t)i, size, w, np) +
                          u.y * lookup(d, cc + nx, off + (uint32_t)i, size, w, np) < u.x,
                  col);
    u.x -= (1.0f - u.y) * lookup(d, cc, off + col, size, w, np) + u.y * lookup(d, cc + nx, off + col, size, w, np);
    off += col;
    float v00 = lookup(d, d->data, off, size, w, np), v10 = lookup(d, d->data + 1, off, size, w, np),
          v01 = lookup(d, d->data + nx, off, size, w, np), v11 = lookup(d, d->data + nx + 1, off, size, w, np);
    float c0 = fmaf(1.0f - u.y, v00, u.y * v01), c1 = fmaf(1.0f - u.y, v10, u.y * v11);
    u.x = invert_linear(c0, c1, u.x);
    *pdf = ((1.0f - u.x) * c0 + u.x * c1) * d->inv_patch_x * d->inv_patch_y;
    return v2(((float)col + u.x) / d->inv_patch_x, ((float)row + u.y) / d->inv_patch_y);
}

Vec2 pl2d_invert(const PLinear2D *d, Vec2 p, const float *params, float *pdf)
{
    float w[2 * PL2D_MAX_PARAMS];
    const int np = d->nparams, nx = d->nx, ny = d->ny;
    const uint32_t size = (uint32_t)(nx * ny), slice = param_weights(d, params, w);
    float sx = p.x * d->inv_patch_x, sy = p.y * d->inv_patch_y;
    int px = (int)sx, py = (int)sy;
    if (px > nx - 2) px = nx - 2;
    if (py > ny - 2) py = ny - 2;
    if (px < 0) px = 0;
    if (py < 0) py = 0;
    sx -= (float)px, sy -= (float)py;
    uint32_t off = (uint32_t)px + (uint32_t)py * (uint32_t)nx + slice * size;
    float v00 = lookup(d, d->data, off, size, w, np), v10 = lookup(d, d->data + 1, off, size, w, np),
          v01 = lookup(d, d->data + nx, off, size, w, np), v11 = lookup(d, d->data + nx + 1, off, size, w, np);
    float c0 = fmaf(1.0f - sy, v00, sy * v01), c1 = fmaf(1.0f - sy, v10, sy * v11);
    float dens = fmaf(1.0f - sx, c0, sx * c1);
    /* x: the mass of the row-interpolated density left of p, over the row's total */
    sx *= c0 + 0.5f * sx * (c1 - c0);
    const float *cc = d->conditional_cdf;
    sx += (1.0f - sy) * lookup(d, cc, off, size, w, np) + sy * lookup(d, cc + nx, off, size, w, np);
    uint32_t roff = (uint32_t)py * (uint32_t)nx + slice * size;
    float r0 = lookup(d, cc, roff + (uint32_t)nx - 1, size, w, np), r1 = lookup(d, cc, roff + (uint32_t)nx * 2 - 1, size, w, np);
    sx /= (1.0f - sy) * r0 + sy * r1;
    /* y: the marginal mass below p */
    sy *= r0 + 0.5f * sy * (r1 - r0);
    sy += lookup(d, d->marginal_cdf, (uint32_t)py + slice * (uint32_t)ny, (uint32_t)ny, w, np);
    *pdf = dens * d->inv_patch_x * d->inv_patch_y;
    return v2(sx, sy);
}
