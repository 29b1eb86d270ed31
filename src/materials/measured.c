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
#include "materials/microfacet.h"
#include "math/cie_data.h"
#include "math/spectrum.h"

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

/* ------------------------------------------------------------------ the tabulated BRDF */

/* pbrt-v4's unit-square coordinates of spherical angles (Dupuy & Jakob 2018 sec. 4.3: the
 * square root puts more nodes near the pole). */
static inline float theta2u(float theta) { return sqrtf(theta * (2.0f / CST_PI)); }
static inline float phi2u(float phi) { return (phi + CST_PI) * (0.5f * CST_INV_PI); }
static inline float u2theta(float u) { return sqrf(u) * (0.5f * CST_PI); }
static inline float u2phi(float u) { return (2.0f * u - 1.0f) * CST_PI; }

static inline float sph_theta(Vec3 w) { return acosf(clampf(w.z, -1.0f, 1.0f)); }

/* A spectral reflectance table as linear sRGB: per (incident angle, node), R(lambda)
 * piecewise linear between the file's wavelengths (constant beyond), against the CIE 1931
 * matching functions under D65 at 1 nm from 360 to 830 nm, normalised so that R = 1 is
 * white (Y = 1), then XYZ to sRGB (math/cie_data.c). */
static CstStatus spectra_to_rgb(const MeasuredData *m, float **out, CstError *err)
{
    const size_t plane = (size_t)m->res * (size_t)m->res, slices = (size_t)m->n_phi * (size_t)m->n_theta;
    const int nl = m->n_lambda;
    /* Each wavelength's weight (the hat functions of the file's nodes) in X, Y, Z. */
    double *w = calloc((size_t)nl * 3, sizeof *w);
    float *rgb = malloc(slices * 3 * plane * sizeof *rgb);
    if (!w || !rgb) {
        free(w);
        free(rgb);
        return cst_fail(err, CST_ERR_OOM, "measured: out of memory converting spectra to RGB");
    }
    double ysum = 0.0;
    for (int l = 360; l <= 830; l++) {
        float xyz[3], lam = (float)l, d65 = spectrum_d65(lam);
        spectrum_cie_xyz(lam, xyz);
        ysum += (double)(xyz[1] * d65);
        int k = 0;
        while (k + 1 < nl && m->wavelengths[k + 1] <= lam) k++;
        float t = k + 1 < nl && lam > m->wavelengths[k] ? (lam - m->wavelengths[k]) / (m->wavelengths[k + 1] - m->wavelengths[k]) : 0.0f;
        for (int c = 0; c < 3; c++) {
            w[k * 3 + c] += (double)((1.0f - t) * xyz[c] * d65);
            if (t > 0.0f) w[(k + 1) * 3 + c] += (double)(t * xyz[c] * d65);
        }
    }
    for (size_t s = 0; s < slices; s++)
        for (size_t i = 0; i < plane; i++) {
            double xyz[3] = {0, 0, 0};
            for (int l = 0; l < nl; l++)
                for (int c = 0; c < 3; c++) xyz[c] += w[l * 3 + c] * (double)m->spectra[(s * (size_t)nl + (size_t)l) * plane + i];
            for (int c = 0; c < 3; c++) {
                double v = 0.0;
                for (int k = 0; k < 3; k++) v += (double)cie_xyz_to_srgb[c][k] * xyz[k] / ysum;
                rgb[(s * 3 + (size_t)c) * plane + i] = (float)v;
            }
        }
    free(w);
    *out = rgb;
    return CST_OK;
}

CstStatus measured_bsdf_init(MeasuredBsdf *b, const MeasuredData *m, CstError *err)
{
    memset(b, 0, sizeof *b);
    b->isotropic = m->isotropic;
    const int inc[2] = {m->n_phi, m->n_theta};
    const float *inc_v[2] = {m->phi_i, m->theta_i};
    static const float channels[3] = {0.0f, 1.0f, 2.0f};
    float *table = m->rgb;
    CstStatus st = CST_OK;
    b->spectral = m->n_lambda > 0;
    if (b->spectral && (st = spectra_to_rgb(m, &table, err)) != CST_OK) return st;
    const int rgb_n[3] = {m->n_phi, m->n_theta, 3}, spec_n[3] = {m->n_phi, m->n_theta, m->n_lambda};
    const float *rgb_v[3] = {m->phi_i, m->theta_i, channels}, *spec_v[3] = {m->phi_i, m->theta_i, m->wavelengths};
    if ((st = pl2d_init(&b->ndf, m->ndf, m->ndf_w, m->ndf_h, 0, NULL, NULL, false, err)) != CST_OK ||
        (st = pl2d_init(&b->sigma, m->sigma, m->sigma_w, m->sigma_h, 0, NULL, NULL, false, err)) != CST_OK ||
        (st = pl2d_init(&b->vndf, m->vndf, m->res, m->res, 2, inc, inc_v, true, err)) != CST_OK ||
        (st = pl2d_init(&b->luminance, m->luminance, m->res, m->res, 2, inc, inc_v, true, err)) != CST_OK ||
        (st = pl2d_init(&b->refl_rgb, table, m->res, m->res, 3, rgb_n, rgb_v, false, err)) != CST_OK ||
        (b->spectral && (st = pl2d_init(&b->refl_spec, m->spectra, m->res, m->res, 3, spec_n, spec_v, false, err)) != CST_OK))
        measured_bsdf_free(b);
    if (table != m->rgb) free(table);
    if (st != CST_OK) return st;
    /* The albedo AOV: the directional albedo at normal incidence, 16 x 16 stratified. */
    Color sum = color_s(0.0f);
    for (int i = 0; i < 256; i++) {
        Vec3 wi;
        Color w;
        float pdf;
        Vec2 u = v2(((float)(i % 16) + 0.5f) / 16.0f, ((float)(i / 16) + 0.5f) / 16.0f);
        if (measured_sample(b, v3(0.0f, 0.0f, 1.0f), u, NULL, &wi, &w, &pdf) && color_is_finite(w)) sum = color_add(sum, w);
    }
    b->albedo = color_scale(sum, 1.0f / 256.0f);
    return CST_OK;
}

CstStatus measured_bsdf_read_file(MeasuredBsdf *b, const char *path, CstError *err)
{
    memset(b, 0, sizeof *b);
    MeasuredData m;
    CstStatus st = measured_read_file(path, &m, err);
    if (st != CST_OK) return st;
    st = measured_bsdf_init(b, &m, err);
    measured_free(&m);
    if (st != CST_OK) return st;
    size_t n = strlen(path) + 1;
    if (!(b->path = malloc(n))) {
        measured_bsdf_free(b);
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory", path);
    }
    memcpy(b->path, path, n);
    return CST_OK;
}

void measured_bsdf_free(MeasuredBsdf *b)
{
    if (!b) return;
    pl2d_free(&b->ndf);
    pl2d_free(&b->sigma);
    pl2d_free(&b->vndf);
    pl2d_free(&b->luminance);
    pl2d_free(&b->refl_rgb);
    pl2d_free(&b->refl_spec);
    free(b->path);
    b->path = NULL;
}

/* R at the warp's sample s for incident params, per channel or at the 4 wavelengths. */
static Color refl_at(const MeasuredBsdf *b, Vec2 s, float phi_o, float theta_o, const float *lambda)
{
    float v[4];
    const bool spec = lambda && b->spectral;
    for (int c = 0; c < 4; c++) {
        float p[3] = {phi_o, theta_o, spec ? lambda[c] : (float)(c < 3 ? c : 1)}; /* lane 3: green */
        v[c] = maxf(pl2d_eval(spec ? &b->refl_spec : &b->refl_rgb, s, p), 0.0f); /* pbrt-v4 clamps at 0 */
    }
    /* an RGB file in spectral mode: the channels' mean (grey), a rough stand-in */
    if (lambda && !b->spectral) v[0] = v[1] = v[2] = v[3] = (v[0] + v[1] + v[2]) * (1.0f / 3.0f);
    Color c;
    for (int k = 0; k < 4; k++) c.c[k] = v[k];
    return c;
}

/* The half vector's unit-square coordinates, relative to wo's azimuth when isotropic. */
static Vec2 half_coords(const MeasuredBsdf *b, Vec3 wm, float phi_o)
{
    float phi_m = atan2f(wm.y, wm.x);
    float uy = phi2u(b->isotropic ? phi_m - phi_o : phi_m);
    return v2(theta2u(sph_theta(wm)), uy - floorf(uy));
}

/* The solid-angle Jacobian of u_m -> wm (d omega = 2 pi^2 u sin theta du, pbrt-v4's floor
 * of 1e-6) times the reflection's 4 (wo.wm). */
static inline float half_jacobian(Vec3 wo, Vec3 wm, float ux)
{
    float sin_m = sqrtf(wm.x * wm.x + wm.y * wm.y);
    return 4.0f * v3_dot(wo, wm) * maxf(2.0f * CST_PI * CST_PI * ux * sin_m, 1e-6f);
}

Color measured_eval(const MeasuredBsdf *b, Vec3 wo, Vec3 wi, const float *lambda)
{
    if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return color_s(0.0f);
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return color_s(0.0f);
    Vec3 wm = v3_normalize(h);
    float theta_o = sph_theta(wo), phi_o = atan2f(wo.y, wo.x);
    float params[2] = {phi_o, theta_o};
    Vec2 um = half_coords(b, wm, phi_o);
    float vpdf;
    Vec2 s = pl2d_invert(&b->vndf, um, params, &vpdf);
    float uo_y = phi2u(phi_o);
    float scale = pl2d_eval(&b->ndf, um, NULL) / (4.0f * pl2d_eval(&b->sigma, v2(theta2u(theta_o), uo_y - floorf(uo_y)), NULL));
    if (!(scale > 0.0f) || !isfinite(scale)) return color_s(0.0f);
    return color_scale(refl_at(b, s, phi_o, theta_o, lambda), scale);
}

float measured_pdf(const MeasuredBsdf *b, Vec3 wo, Vec3 wi)
{
    if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return 0.0f;
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return 0.0f;
    Vec3 wm = v3_normalize(h);
    float params[2] = {atan2f(wo.y, wo.x), sph_theta(wo)};
    Vec2 um = half_coords(b, wm, params[0]);
    float vpdf;
    Vec2 s = pl2d_invert(&b->vndf, um, params, &vpdf);
    return vpdf * pl2d_eval(&b->luminance, s, params) / half_jacobian(wo, wm, um.x);
}

bool measured_sample(const MeasuredBsdf *b, Vec3 wo, Vec2 u, const float *lambda, Vec3 *wi, Color *weight, float *pdf)
{
    if (!(wo.z > 0.0f)) return false;
    float theta_o = sph_theta(wo), phi_o = atan2f(wo.y, wo.x);
    float params[2] = {phi_o, theta_o}, lpdf, vpdf;
    Vec2 s = pl2d_sample(&b->luminance, v2(u.y, u.x), params, &lpdf);
    Vec2 um = pl2d_sample(&b->vndf, s, params, &vpdf);
    float phi_m = u2phi(um.y) + (b->isotropic ? phi_o : 0.0f), theta_m = u2theta(um.x);
    Vec3 wm = v3(sinf(theta_m) * cosf(phi_m), sinf(theta_m) * sinf(phi_m), cosf(theta_m));
    Vec3 w = reflect_about(wo, wm);
    if (!(w.z > 0.0f)) return false;
    /* The density and value as measured_pdf and measured_eval compute them from (wo, w),
     * so that a sample and a later query of the same pair agree. */
    *wi = w;
    *pdf = measured_pdf(b, wo, w);
    Color f = measured_eval(b, wo, w, lambda);
    if (!(*pdf > 0.0f)) return false;
    *weight = color_scale(f, 1.0f / *pdf);
    return true;
}
