/* The measured material's tables: the .bsdf fields pbrt-v4 reads, each checked for its
 * type, its shape against the others, and its values, then copied into float arrays. */
#include "materials/measured.h"

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "io/tensor.h"

/* A field of the given type and dimension count (ndim < 0: any), or a located error. */
static CstStatus need(const char *name, const TensorFile *t, const char *field, TensorDtype dtype, int ndim,
                      const TensorField **out, CstError *err)
{
    const TensorField *f = tensor_field(t, field);
    if (!f) return cst_fail(err, CST_ERR_PARSE, "%s: no field \"%s\"; expected a measured BSDF with fields theta_i, "
                            "phi_i, ndf, sigma, vndf, luminance, description, jacobian and spectra with "
                            "wavelengths (or rgb)", name, field);
    if (f->dtype != dtype || (ndim >= 0 && f->ndim != ndim))
        return cst_fail(err, CST_ERR_PARSE, "%s: byte %llu: field \"%s\" is %d-dimensional %s; expected %d-dimensional %s",
                        name, (unsigned long long)f->offset, field, f->ndim, tensor_dtype_name(f->dtype), ndim,
                        tensor_dtype_name(dtype));
    *out = f;
    return CST_OK;
}

/* The shape of f must be `want` (n entries). */
static CstStatus shape_is(const char *name, const TensorField *f, const uint64_t *want, int n, CstError *err)
{
    for (int d = 0; d < n; d++)
        if (f->shape[d] != want[d])
            return cst_fail(err, CST_ERR_PARSE, "%s: byte %llu: field \"%s\" has size %llu along dimension %d; expected "
                            "%llu to match the other fields", name, (unsigned long long)f->offset, f->name,
                            (unsigned long long)f->shape[d], d, (unsigned long long)want[d]);
    return CST_OK;
}

/* A float32 field's values copied out, each finite and (nonneg) >= 0, (increasing)
 * strictly increasing. */
static CstStatus copy(const char *name, const TensorField *f, bool nonneg, bool increasing, float **out, CstError *err)
{
    if (f->count == 0) return cst_fail(err, CST_ERR_PARSE, "%s: field \"%s\" is empty; expected values", name, f->name);
    float *v = malloc((size_t)f->count * sizeof *v);
    if (!v) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for field \"%s\"", name, f->name);
    for (uint64_t i = 0; i < f->count; i++) {
        v[i] = (float)tensor_value(f, i);
        const char *bad = !isfinite(v[i]) ? "not finite" : nonneg && v[i] < 0.0f ? "negative"
                          : increasing && i > 0 && !(v[i] > v[i - 1]) ? "not above the one before" : NULL;
        if (bad) {
            float x = v[i];
            free(v);
            return cst_fail(err, CST_ERR_PARSE, "%s: field \"%s\" value %llu (%g) is %s; expected %s", name, f->name,
                            (unsigned long long)i, (double)x, bad,
                            increasing ? "finite increasing values" : nonneg ? "finite values >= 0" : "finite values");
        }
    }
    *out = v;
    return CST_OK;
}

/* measured_read's steps: the status in st, to the clean-up on failure. */
#define TRY(x)                                  \
    do {                                        \
        st = (x);                               \
        if (st != CST_OK) goto fail;            \
    } while (0)

CstStatus measured_read(const char *name, const void *data, size_t len, MeasuredData *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    TensorFile t;
    CstStatus st = tensor_read(name, data, len, &t, err);
    if (st != CST_OK) return st;
    const TensorField *theta, *phi, *ndf, *sigma, *vndf, *lum, *desc, *jac, *spec = NULL, *wl = NULL, *rgb = NULL;
    TRY(need(name, &t, "theta_i", TENSOR_F32, 1, &theta, err));
    TRY(need(name, &t, "phi_i", TENSOR_F32, 1, &phi, err));
    TRY(need(name, &t, "ndf", TENSOR_F32, 2, &ndf, err));
    TRY(need(name, &t, "sigma", TENSOR_F32, 2, &sigma, err));
    TRY(need(name, &t, "vndf", TENSOR_F32, 4, &vndf, err));
    TRY(need(name, &t, "luminance", TENSOR_F32, 4, &lum, err));
    TRY(need(name, &t, "description", TENSOR_U8, 1, &desc, err));
    TRY(need(name, &t, "jacobian", TENSOR_U8, 1, &jac, err));
    if (tensor_field(&t, "spectra") || !tensor_field(&t, "rgb")) {
        TRY(need(name, &t, "spectra", TENSOR_F32, 5, &spec, err));
        TRY(need(name, &t, "wavelengths", TENSOR_F32, 1, &wl, err));
    } else {
        TRY(need(name, &t, "rgb", TENSOR_F32, 5, &rgb, err));
    }
    const uint64_t np = phi->shape[0], nt = theta->shape[0], res = lum->shape[2];
    /* Interpolation needs two nodes along every axis; the sizes stay far below INT_MAX. */
    const TensorField *grids[] = {theta, phi, ndf, sigma, lum};
    for (int i = 0; i < 5; i++)
        for (int d = 0; d < grids[i]->ndim; d++)
            if (grids[i]->shape[d] < 2 || grids[i]->shape[d] > 4096) {
                st = cst_fail(err, CST_ERR_PARSE, "%s: byte %llu: field \"%s\" has size %llu along dimension %d; "
                              "expected 2 to 4096", name, (unsigned long long)grids[i]->offset, grids[i]->name,
                              (unsigned long long)grids[i]->shape[d], d);
                goto fail;
            }
    const uint64_t grid4[] = {np, nt, res, res};
    TRY(shape_is(name, lum, grid4, 4, err));
    TRY(shape_is(name, vndf, grid4, 4, err));
    const uint64_t grid5[] = {np, nt, wl ? wl->shape[0] : 3, res, res};
    TRY(shape_is(name, spec ? spec : rgb, grid5, 5, err));
    const uint64_t one[] = {1};
    TRY(shape_is(name, jac, one, 1, err));
    if (wl && (wl->shape[0] < 1 || wl->shape[0] > 1024)) {
        st = cst_fail(err, CST_ERR_PARSE, "%s: field \"wavelengths\" has %llu values; expected 1 to 1024", name,
                      (unsigned long long)wl->shape[0]);
        goto fail;
    }
    out->n_phi = (int)np;
    out->n_theta = (int)nt;
    out->res = (int)res;
    out->ndf_h = (int)ndf->shape[0], out->ndf_w = (int)ndf->shape[1];
    out->sigma_h = (int)sigma->shape[0], out->sigma_w = (int)sigma->shape[1];
    out->n_lambda = wl ? (int)wl->shape[0] : 0;
    out->isotropic = np <= 2;
    out->jacobian = tensor_value(jac, 0) != 0.0;
    size_t nd = desc->count < sizeof out->description ? (size_t)desc->count : sizeof out->description - 1;
    memcpy(out->description, desc->data, nd);
    TRY(copy(name, theta, true, true, &out->theta_i, err));
    TRY(copy(name, phi, false, true, &out->phi_i, err));
    if (out->theta_i[nt - 1] > 1.5707964f) {
        st = cst_fail(err, CST_ERR_PARSE, "%s: field \"theta_i\" ends at %g; expected incident angles from 0 to pi/2",
                      name, (double)out->theta_i[nt - 1]);
        goto fail;
    }
    TRY(copy(name, ndf, true, false, &out->ndf, err));
    TRY(copy(name, sigma, true, false, &out->sigma, err));
    TRY(copy(name, vndf, true, false, &out->vndf, err));
    TRY(copy(name, lum, true, false, &out->luminance, err));
    if (wl) {
        TRY(copy(name, wl, true, true, &out->wavelengths, err));
        TRY(copy(name, spec, false, false, &out->spectra, err)); /* pbrt-v4 clamps negative lookups to 0 */
    } else {
        TRY(copy(name, rgb, false, false, &out->rgb, err));
    }
    /* pbrt-v4 takes an anisotropic table's phi_i to span 2 pi / reduction and supports
     * reduction 1 only. */
    if (!out->isotropic && (int)lrint(2.0 * 3.14159265358979 / ((double)out->phi_i[np - 1] - (double)out->phi_i[0])) != 1) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%s: field \"phi_i\" spans %g radians; expected 2 pi (pbrt-v4 supports "
                      "no symmetry reduction of anisotropic tables)", name,
                      (double)(out->phi_i[np - 1] - out->phi_i[0]));
        goto fail;
    }
    tensor_free(&t);
    return CST_OK;
fail:
    tensor_free(&t);
    measured_free(out);
    return st;
}

CstStatus measured_read_file(const char *path, MeasuredData *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    char *data = NULL;
    size_t len = 0;
    CstStatus st = file_read_all(path, &data, &len, err);
    if (st == CST_OK) st = measured_read(path, data, len, out, err);
    free(data);
    return st;
}

void measured_free(MeasuredData *m)
{
    if (!m) return;
    free(m->phi_i);
    free(m->theta_i);
    free(m->ndf);
    free(m->sigma);
    free(m->vndf);
    free(m->luminance);
    free(m->wavelengths);
    free(m->spectra);
    free(m->rgb);
    memset(m, 0, sizeof *m);
}
