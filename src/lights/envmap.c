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

void envmap_free(EnvMap *m)
{
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
