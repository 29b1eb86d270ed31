/* Environment maps: lookup and importance sampling over the sphere. */
#include "lights/envmap.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "sampling/warp.h"

CstStatus envmap_init_constant(EnvMap *m, Color radiance, CstError *err)
{
    (void)err;
    memset(m, 0, sizeof *m);
    m->scale = radiance;
    m->power = 4.0f * CST_PI * color_luminance(radiance);
    return CST_OK;
}

static void portal_free(EnvPortal *pt)
{
    if (!pt) return;
    free(pt->f);
    free(pt->sat);
    free(pt);
}

void envmap_free(EnvMap *m)
{
    portal_free(m->portal);
    if (m->rows)
        for (int r = 0; r < m->height; r++) distrib1d_free(&m->rows[r]);
    free(m->rows);
    distrib1d_free(&m->marginal);
    free(m->rgb);
    memset(m, 0, sizeof *m);
}

/* A pixel's sampling weight: its luminance, floored so that a pixel with any radiance can
 * be sampled (a pure-blue pixel has luminance 0.07 of its value, never 0 unless black). */
static float pixel_weight(const float *p)
{
    float y = 0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2];
    float mx = fmaxf(p[0], fmaxf(p[1], p[2]));
    return fmaxf(y, 1e-4f * mx);
}

CstStatus envmap_init_image(EnvMap *m, float *rgb, int width, int height, Color scale, CstError *err)
{
    memset(m, 0, sizeof *m);
    /* NaN, Inf or negative radiance is an error, as for every image input (it used to be
     * zeroed here, silently: a black sky). The loaders have checked their files already
     * with the file's name; this keeps the rule for every other caller. */
    CstStatus bad = image_check_radiance(rgb, width, height, "environment map", err);
    if (bad != CST_OK) {
        free(rgb);
        return bad;
    }
    m->rgb = rgb;
    m->width = width;
    m->height = height;
    m->scale = scale;
    m->rows = calloc((size_t)height, sizeof *m->rows);
    float *w = malloc((size_t)(width > height ? width : height) * sizeof *w);
    float *row_w = malloc((size_t)height * sizeof *row_w);
    if (!m->rows || !w || !row_w) {
        free(w);
        free(row_w);
        envmap_free(m);
        return cst_fail(err, CST_ERR_OOM, "out of memory for a %dx%d environment map", width, height);
    }
    double power = 0.0;
    const float ys = color_luminance(scale);
    for (int r = 0; r < height; r++) {
        double sum = 0.0, lum = 0.0;
        for (int c = 0; c < width; c++) {
            const float *p = &rgb[3 * ((size_t)r * (size_t)width + (size_t)c)];
            w[c] = pixel_weight(p);
            sum += (double)w[c];
            lum += (double)(0.2126f * p[0] + 0.7152f * p[1] + 0.0722f * p[2]);
        }
        /* Rows of pure black still need a (zero-weight) distribution to exist. */
        if (!(sum > 0.0)) for (int c = 0; c < width; c++) w[c] = 1.0f;
        CstStatus st = distrib1d_init(&m->rows[r], w, width, err);
        if (st != CST_OK) {
            free(w);
            free(row_w);
            envmap_free(m);
            return st;
        }
        float sin_t = sinf(CST_PI * ((float)r + 0.5f) / (float)height);
        row_w[r] = (float)sum * sin_t;
        /* d omega of a pixel = (2 pi / W) (pi / H) sin theta. */
        power += lum * (double)sin_t * (2.0 * (double)CST_PI / width) * ((double)CST_PI / height);
    }
    double total = 0.0;
    for (int r = 0; r < height; r++) total += (double)row_w[r];
    if (!(total > 0.0)) for (int r = 0; r < height; r++) row_w[r] = 1.0f;
    CstStatus st = distrib1d_init(&m->marginal, row_w, height, err);
    free(w);
    free(row_w);
    if (st != CST_OK) {
        envmap_free(m);
        return st;
    }
    m->power = (float)power * ys;
    return CST_OK;
}

static inline void dir_to_uv(Vec3 w, float *u, float *v)
{
    float theta = acosf(clampf(w.y, -1.0f, 1.0f));
    float phi = atan2f(w.z, w.x);
    if (phi < 0.0f) phi += 2.0f * CST_PI;
    *u = phi * CST_INV_2PI;
    *v = theta * CST_INV_PI;
}

static inline int clamp_index(float x, int n)
{
    int i = (int)x;
    return i < 0 ? 0 : i >= n ? n - 1 : i;
}

Color envmap_eval(const EnvMap *m, Vec3 w)
{
    if (!m->rgb) return m->scale;
    float u, v;
    dir_to_uv(w, &u, &v);
    int c = clamp_index(u * (float)m->width, m->width), r = clamp_index(v * (float)m->height, m->height);
    const float *p = &m->rgb[3 * ((size_t)r * (size_t)m->width + (size_t)c)];
    return color_rgb(p[0] * m->scale.c[0], p[1] * m->scale.c[1], p[2] * m->scale.c[2]);
}

/* The bin that distrib1d_sample picked, with u remapped to a uniform position inside it. */
static int sample_remap(const Distrib1D *d, float u, float *t)
{
    int i = distrib1d_sample(d, u);
    float lo = d->cdf[i], hi = d->cdf[i + 1];
    float x = hi > lo ? (u - lo) / (hi - lo) : 0.5f;
    *t = x < 0.0f ? 0.0f : x < 1.0f ? x : 0x1.fffffep-1f;
    return i;
}

Vec3 envmap_sample(const EnvMap *m, Vec2 u, float *pdf)
{
    if (!m->rgb) {
        *pdf = CST_INV_4PI;
        return warp_uniform_sphere(u);
    }
    float tv, tu;
    int r = sample_remap(&m->marginal, u.y, &tv);
    int c = sample_remap(&m->rows[r], u.x, &tu);
    float v = ((float)r + tv) / (float)m->height, uu = ((float)c + tu) / (float)m->width;
    float theta = v * CST_PI, phi = uu * 2.0f * CST_PI;
    float st = sinf(theta);
    Vec3 w = v3(st * cosf(phi), cosf(theta), st * sinf(phi));
    /* The density as envmap_pdf gives it for w: p(u, v) = pmf_row pmf_col W H on the cell,
     * d omega = 2 pi^2 sin theta du dv. Taking it from w, not from (r, c), keeps NEE and
     * the MIS weights of BSDF-sampled hits on one function even for a sample that rounds
     * into the neighbouring cell. */
    *pdf = envmap_pdf(m, w);
    return w;
}

float envmap_pdf(const EnvMap *m, Vec3 w)
{
    if (!m->rgb) return CST_INV_4PI;
    float u, v;
    dir_to_uv(w, &u, &v);
    int c = clamp_index(u * (float)m->width, m->width), r = clamp_index(v * (float)m->height, m->height);
    float st = sinf(v * CST_PI);
    float puv = m->marginal.pmf[r] * m->rows[r].pmf[c] * (float)m->width * (float)m->height;
    return st > 0.0f ? puv / (2.0f * CST_PI * CST_PI * st) : 0.0f;
}

/* ------------------------------------------------------------------ portal */

/* The portal's resolution over (u, v): 256 x 256 cells, each 0.7 degrees across at the
 * window's centre, finer than any map's pixels seen through a window from a room. */
enum { PORTAL_RES = 256, PORTAL_SUPER = 4 };

/* Rectified (u, v) of a local direction d (d.z > 0) and back (pbrt-v4
 * PortalImageInfiniteLight::ImageFromRender / RenderFromImage). */
static inline Vec2 portal_uv(Vec3 d)
{
    return v2((atan2f(d.x, d.z) + 0.5f * CST_PI) * CST_INV_PI, (atan2f(d.y, d.z) + 0.5f * CST_PI) * CST_INV_PI);
}
static inline Vec3 portal_dir_local(double u, double v)
{
    double x = tan(((double)CST_PI) * (u - 0.5)), y = tan(((double)CST_PI) * (v - 0.5));
    double r = sqrt(x * x + y * y + 1.0);
    return v3((float)(x / r), (float)(y / r), (float)(1.0 / r));
}
/* d omega / du dv at local direction d = pi^2 (1 + x^2)(1 + y^2) / r^3 for d = (x, y, 1) / r,
 * written with d's components. */
static inline float portal_jacobian(Vec3 d)
{
    return CST_PI * CST_PI * (1.0f - d.x * d.x) * (1.0f - d.y * d.y) / d.z;
}
static inline Vec3 portal_to_local(const EnvPortal *pt, Vec3 w)
{
    return v3(v3_dot(w, pt->ax), v3_dot(w, pt->ay), v3_dot(w, pt->az));
}

CstStatus envmap_set_portal(EnvMap *m, const Vec3 p[4], CstError *err)
{
    Vec3 e01 = v3_sub(p[1], p[0]), e03 = v3_sub(p[3], p[0]);
    float l01 = v3_length(e01), l03 = v3_length(e03);
    if (!(l01 > 0.0f) || !(l03 > 0.0f) || !isfinite(l01 + l03))
        return cst_fail(err, CST_ERR_INVALID_ARG, "portal: two corners coincide; expected four corners of a rectangle");
    /* a rectangle: opposite edges equal, adjacent ones perpendicular (pbrt-v4 checks the same) */
    Vec3 e32 = v3_sub(p[2], p[3]);
    float scale = fmaxf(l01, l03);
    if (v3_length(v3_sub(e32, e01)) > 1e-3f * scale || fabsf(v3_dot(e01, e03)) > 1e-3f * l01 * l03)
        return cst_fail(err, CST_ERR_INVALID_ARG, "portal: the four points are not a rectangle (corners in order, "
                        "opposite edges equal, right angles)");
    EnvPortal *pt = calloc(1, sizeof *pt);
    if (!pt) return cst_fail(err, CST_ERR_OOM, "out of memory for a portal");
    const int n = PORTAL_RES;
    pt->n = n;
    pt->p0 = p[0];
    pt->p2 = p[2];
    pt->ax = v3_scale(e03, 1.0f / l03);
    pt->ay = v3_scale(e01, 1.0f / l01);
    pt->az = v3_normalize(v3_cross(pt->ax, pt->ay));
    pt->f = malloc((size_t)n * (size_t)n * sizeof *pt->f);
    pt->sat = calloc((size_t)(n + 1) * (size_t)(n + 1), sizeof *pt->sat);
    if (!pt->f || !pt->sat) {
        portal_free(pt);
        return cst_fail(err, CST_ERR_OOM, "out of memory for a portal");
    }
    /* Each cell: the luminance averaged over PORTAL_SUPER^2 directions in it, floored at
     * 1e-3 of the mean (a cell whose sample points miss a bright pixel must still be
     * sampled: its density may not be 0 where the radiance is not), times d omega / du dv
     * at its centre, so that the density per solid angle follows the radiance. */
    double mean = 0.0;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            double acc = 0.0;
            for (int b = 0; b < PORTAL_SUPER; b++)
                for (int a = 0; a < PORTAL_SUPER; a++) {
                    Vec3 d = portal_dir_local((i + (a + 0.5) / PORTAL_SUPER) / n, (j + (b + 0.5) / PORTAL_SUPER) / n);
                    Vec3 w = v3_add(v3_add(v3_scale(pt->ax, d.x), v3_scale(pt->ay, d.y)), v3_scale(pt->az, d.z));
                    acc += (double)color_luminance(envmap_eval(m, w));
                }
            pt->f[(size_t)j * (size_t)n + (size_t)i] = (float)(acc / (PORTAL_SUPER * PORTAL_SUPER));
            mean += acc / (PORTAL_SUPER * PORTAL_SUPER);
        }
    mean /= (double)n * (double)n;
    const float floor_l = mean > 0.0 ? (float)(1e-3 * mean) : 1.0f;
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++) {
            float *f = &pt->f[(size_t)j * (size_t)n + (size_t)i];
            *f = fmaxf(*f, floor_l) * portal_jacobian(portal_dir_local((i + 0.5) / n, (j + 0.5) / n));
        }
    const double cell = 1.0 / ((double)n * (double)n);
    for (int j = 0; j < n; j++)
        for (int i = 0; i < n; i++)
            pt->sat[(size_t)(j + 1) * (size_t)(n + 1) + (size_t)(i + 1)] =
                (double)pt->f[(size_t)j * (size_t)n + (size_t)i] * cell + pt->sat[(size_t)j * (size_t)(n + 1) + (size_t)(i + 1)] +
                pt->sat[(size_t)(j + 1) * (size_t)(n + 1) + (size_t)i] - pt->sat[(size_t)j * (size_t)(n + 1) + (size_t)i];
    portal_free(m->portal);
    m->portal = pt;
    return CST_OK;
}

/* The integral of f over [0, u] x [0, v]: bilinear in the summed-area table, exact for a
 * piecewise-constant f. */
static double portal_integral_to(const EnvPortal *pt, double u, double v)
{
    const int n = pt->n;
    double x = u * n, y = v * n;
    int i = (int)x, j = (int)y;
    i = i < 0 ? 0 : i > n - 1 ? n - 1 : i;
    j = j < 0 ? 0 : j > n - 1 ? n - 1 : j;
    double fx = x - i, fy = y - j;
    const double *r0 = &pt->sat[(size_t)j * (size_t)(n + 1)], *r1 = r0 + (n + 1);
    double a = r0[i] + fx * (r0[i + 1] - r0[i]), b = r1[i] + fx * (r1[i + 1] - r1[i]);
    return a + fy * (b - a);
}

static double portal_integral(const EnvPortal *pt, double u0, double u1, double v0, double v1)
{
    return portal_integral_to(pt, u1, v1) - portal_integral_to(pt, u0, v1) - portal_integral_to(pt, u1, v0) +
           portal_integral_to(pt, u0, v0);
}

/* The window of directions from x through the portal, as a rectangle of (u, v). */
static bool portal_window(const EnvPortal *pt, Vec3 x, double *u0, double *u1, double *v0, double *v1)
{
    Vec3 a = portal_to_local(pt, v3_sub(pt->p0, x)), b = portal_to_local(pt, v3_sub(pt->p2, x));
    if (!(a.z > 0.0f) || !(b.z > 0.0f)) return false;
    Vec2 ua = portal_uv(a), ub = portal_uv(b);
    *u0 = (double)fminf(ua.x, ub.x);
    *u1 = (double)fmaxf(ua.x, ub.x);
    *v0 = (double)fminf(ua.y, ub.y);
    *v1 = (double)fmaxf(ua.y, ub.y);
    return *u1 > *u0 && *v1 > *v0;
}

float envmap_portal_pdf(const EnvMap *m, Vec3 x, Vec3 w)
{
    const EnvPortal *pt = m->portal;
    double u0, u1, v0, v1;
    if (!pt || !portal_window(pt, x, &u0, &u1, &v0, &v1)) return 0.0f;
    Vec3 d = portal_to_local(pt, w);
    if (!(d.z > 0.0f)) return 0.0f;
    Vec2 uv = portal_uv(d);
    if (!((double)uv.x >= u0 && (double)uv.x <= u1 && (double)uv.y >= v0 && (double)uv.y <= v1)) return 0.0f;
    double total = portal_integral(pt, u0, u1, v0, v1);
    float jac = portal_jacobian(d);
    if (!(total > 0.0) || !(jac > 0.0f)) return 0.0f;
    const int n = pt->n;
    int i = (int)(uv.x * (float)n), j = (int)(uv.y * (float)n);
    i = i < 0 ? 0 : i > n - 1 ? n - 1 : i;
    j = j < 0 ? 0 : j > n - 1 ? n - 1 : j;
    return (float)((double)pt->f[(size_t)j * (size_t)n + (size_t)i] / total) / jac;
}

bool envmap_portal_sample(const EnvMap *m, Vec3 x, Vec2 u, Vec3 *w, float *pdf)
{
    const EnvPortal *pt = m->portal;
    double u0, u1, v0, v1;
    *pdf = 0.0f;
    if (!pt || !portal_window(pt, x, &u0, &u1, &v0, &v1)) return false;
    const int n = pt->n;
    double total = portal_integral(pt, u0, u1, v0, v1);
    if (!(total > 0.0)) return false;
    /* v by the window's marginal: the rows' masses between u0 and u1, a binary search on the
     * cumulative mass at row boundaries, then linear inside the row. */
    double target = (double)u.y * total;
    int jlo = (int)(v0 * n), jhi = (int)(v1 * n);
    jlo = jlo < 0 ? 0 : jlo > n - 1 ? n - 1 : jlo;
    jhi = jhi < jlo ? jlo : jhi > n - 1 ? n - 1 : jhi;
    int a = jlo, b = jhi; /* the row j with C(start of j) <= target < C(end of j) */
    while (a < b) {
        int mid = (a + b) / 2;
        double end = fmin(v1, (double)(mid + 1) / n);
        if (portal_integral(pt, u0, u1, v0, end) <= target) a = mid + 1;
        else b = mid;
    }
    const int j = a;
    double vs = fmax(v0, (double)j / n), ve = fmin(v1, (double)(j + 1) / n);
    double c0 = portal_integral(pt, u0, u1, v0, vs), row = portal_integral(pt, u0, u1, vs, ve);
    double t = row > 0.0 ? (target - c0) / row : 0.5;
    t = t < 0.0 ? 0.0 : t > 1.0 ? 1.0 : t;
    double v = vs + t * (ve - vs);
    /* u in row j: the row's cumulative mass from the table (exact, piecewise linear in u),
     * a binary search over its cells between u0 and u1, then linear inside the cell */
    const double rv0 = (double)j / n, rv1 = (double)(j + 1) / n;
    const double base = portal_integral(pt, 0.0, u0, rv0, rv1);
    const double rtarget = base + (double)u.x * portal_integral(pt, u0, u1, rv0, rv1);
    int ilo = (int)(u0 * n), ihi = (int)(u1 * n);
    ilo = ilo < 0 ? 0 : ilo > n - 1 ? n - 1 : ilo;
    ihi = ihi < ilo ? ilo : ihi > n - 1 ? n - 1 : ihi;
    a = ilo;
    b = ihi;
    while (a < b) {
        int mid = (a + b) / 2;
        if (portal_integral(pt, 0.0, fmin(u1, (double)(mid + 1) / n), rv0, rv1) <= rtarget) a = mid + 1;
        else b = mid;
    }
    const int i = a;
    double us = fmax(u0, (double)i / n), ue = fmin(u1, (double)(i + 1) / n);
    double cs = portal_integral(pt, 0.0, us, rv0, rv1), mass = portal_integral(pt, us, ue, rv0, rv1);
    double tt = mass > 0.0 ? (rtarget - cs) / mass : 0.5;
    tt = tt < 0.0 ? 0.0 : tt > 1.0 ? 1.0 : tt;
    double uu = us + tt * (ue - us);
    Vec3 d = portal_dir_local(uu, v);
    *w = v3_normalize(v3_add(v3_add(v3_scale(pt->ax, d.x), v3_scale(pt->ay, d.y)), v3_scale(pt->az, d.z)));
    /* the density as envmap_portal_pdf gives it for w, as envmap_sample does: NEE and the
     * MIS weight of a BSDF-sampled ray see one function */
    *pdf = envmap_portal_pdf(m, x, *w);
    return *pdf > 0.0f;
}
