/* Film storage, resolution to pixel means and variances, and output. */
#include "film/film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "film/filter.h"
#include "film/sensor.h"
#include "io/image_io.h"

Film *film_create(int width, int height)
{
    Film *f = calloc(1, sizeof *f);
    if (!f) return NULL;
    size_t n = (size_t)width * (size_t)height * 3u;
    f->sum = calloc(n, sizeof *f->sum);
    f->sum_sq = calloc(n, sizeof *f->sum_sq);
    if (!f->sum || !f->sum_sq) { film_destroy(f); return NULL; }
    f->width = width;
    f->height = height;
    f->exposure_scale = 1.0;
    return f;
}

void film_set_white_balance(Film *f, double kelvin)
{
    f->white_balanced = kelvin > 0.0 && isfinite(kelvin);
    sensor_white_balance(kelvin, f->white_balance);
}

int film_set_output(Film *f, int aovs, double exposure, int png_linear)
{
    f->aovs = aovs;
    f->exposure_scale = exp2(exposure);
    f->png_linear = png_linear;
    if ((aovs & FILM_AOV_FIRST_HIT) && !f->aov) {
        f->aov = calloc((size_t)f->width * (size_t)f->height * FILM_AOV_STRIDE, sizeof *f->aov);
        if (!f->aov) return 0;
    }
    return 1;
}

Film *film_crop(const Film *f, int x0, int y0, int w, int h)
{
    Film *c = film_create(w, h);
    if (!c) return NULL;
    c->spp = f->spp;
    if (f->pixel_spp && !(c->pixel_spp = malloc((size_t)w * (size_t)h * sizeof *c->pixel_spp))) {
        film_destroy(c);
        return NULL;
    }
    c->aovs = f->aovs;
    c->exposure_scale = f->exposure_scale;
    c->png_linear = f->png_linear;
    c->white_balanced = f->white_balanced;
    memcpy(c->white_balance, f->white_balance, sizeof c->white_balance);
    if (f->aov) {
        c->aov = malloc((size_t)w * (size_t)h * FILM_AOV_STRIDE * sizeof *c->aov);
        if (!c->aov) { film_destroy(c); return NULL; }
    }
    for (int y = 0; y < h; y++) {
        size_t from = (size_t)(y0 + y) * (size_t)f->width + (size_t)x0, to = (size_t)y * (size_t)w;
        memcpy(&c->sum[3 * to], &f->sum[3 * from], 3 * (size_t)w * sizeof *c->sum);
        memcpy(&c->sum_sq[3 * to], &f->sum_sq[3 * from], 3 * (size_t)w * sizeof *c->sum_sq);
        if (f->pixel_spp) memcpy(&c->pixel_spp[to], &f->pixel_spp[from], (size_t)w * sizeof *c->pixel_spp);
        if (f->aov)
            memcpy(&c->aov[FILM_AOV_STRIDE * to], &f->aov[FILM_AOV_STRIDE * from],
                   FILM_AOV_STRIDE * (size_t)w * sizeof *c->aov);
    }
    return c;
}

void film_destroy(Film *f)
{
    if (!f) return;
    free(f->sum);
    free(f->sum_sq);
    free(f->pixel_spp);
    free(f->aov);
    free(f->progressive);
    free(f->chains);
    free(f);
}

int film_enable_pixel_spp(Film *f)
{
    const size_t n = (size_t)f->width * (size_t)f->height;
    if (!f->pixel_spp && !(f->pixel_spp = malloc(n * sizeof *f->pixel_spp))) return 0;
    for (size_t i = 0; i < n; i++) f->pixel_spp[i] = f->spp;
    return 1;
}

void film_add(Film *dst, const Film *src)
{
    const size_t n = 3 * (size_t)dst->width * (size_t)dst->height;
    for (size_t i = 0; i < n; i++) dst->sum[i] += src->sum[i];
    for (size_t i = 0; i < n; i++) dst->sum_sq[i] += src->sum_sq[i];
    if (dst->aov && src->aov)
        for (size_t i = 0; i < n / 3 * FILM_AOV_STRIDE; i++) dst->aov[i] += src->aov[i];
}

CstStatus cst_film_add(CstFilm *dst, const CstFilm *src, CstError *err)
{
    if (dst->progressive || src->progressive)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "cst_film_add: a film with a progressive integrator's state "
                        "(SPPM): its iterations are not sums of samples that add up; expected films of sums");
    if (dst->chains || src->chains)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "cst_film_add: a film with MLT's chains: its iterations "
                        "continue the same chains and do not add up; expected films of independent sums");
    if (dst->width != src->width || dst->height != src->height || (!dst->aov) != (!src->aov))
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_add: a %dx%d film%s and a %dx%d film%s; expected the "
                        "same size and AOV sums", dst->width, dst->height, dst->aov ? " with AOV sums" : "",
                        src->width, src->height, src->aov ? " with AOV sums" : "");
    if (dst->pixel_spp || src->pixel_spp)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "cst_film_add: a film of adaptive sampling (--noise: sample "
                        "counts per block); expected films of the same samples in every pixel");
    film_add(dst, src);
    dst->spp += src->spp;
    return CST_OK;
}

void cst_film_sums(CstFilm *f, CstFilmSums *out)
{
    out->sum = f->sum;
    out->sum_sq = f->sum_sq;
    out->aov = f->aov;
    out->pixels = (size_t)f->width * (size_t)f->height;
    out->spp = &f->spp;
}

void cst_film_destroy(CstFilm *film) { film_destroy(film); }
int cst_film_width(const CstFilm *f) { return f->width; }
int cst_film_height(const CstFilm *f) { return f->height; }
int cst_film_spp(const CstFilm *f) { return f->spp; }

void cst_film_pixel(const CstFilm *f, int x, int y, double rgb_out[3])
{
    const size_t i = (size_t)y * (size_t)f->width + (size_t)x;
    const double *s = &f->sum[3 * i];
    const int spp = film_pixel_spp(f, i);
    double inv = spp > 0 ? 1.0 / spp : 0.0;
    for (int c = 0; c < 3; c++) rgb_out[c] = s[c] * inv;
}

void cst_film_pixel_variance(const CstFilm *f, int x, int y, double var[3])
{
    const size_t p = (size_t)y * (size_t)f->width + (size_t)x, i = 3 * p;
    const int spp = film_pixel_spp(f, p);
    double n = (double)spp;
    for (int c = 0; c < 3; c++) {
        if (spp < 2) { var[c] = 0.0; continue; }
        double mean = f->sum[i + c] / n;
        /* Unbiased sample variance, divided by n for the variance of the mean. */
        double v = (f->sum_sq[i + c] - n * mean * mean) / (n - 1.0);
        var[c] = (v > 0.0 ? v : 0.0) / n;
    }
}

void cst_film_pixels(const CstFilm *f, float *rgb_out)
{
    film_resolve(f, rgb_out); /* the means cst_film_pixel gives, rounded to float */
}

void cst_film_variances(const CstFilm *f, float *var_out)
{
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            double var[3];
            cst_film_pixel_variance(f, x, y, var);
            float *o = &var_out[3 * ((size_t)y * (size_t)f->width + (size_t)x)];
            for (int c = 0; c < 3; c++) o[c] = (float)var[c];
        }
}

CstStatus cst_film_aov_pixels(const CstFilm *f, int aov, float *out, CstError *err)
{
    if ((aov != CST_AOV_ALBEDO && aov != CST_AOV_NORMAL && aov != CST_AOV_DEPTH) || !(f->aovs & aov) || !f->aov)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_aov_pixels: aov %d; expected one of CST_AOV_ALBEDO, "
                        "CST_AOV_NORMAL, CST_AOV_DEPTH that the film was rendered with (aovs %d)", aov, f->aovs);
    size_t pixels = (size_t)f->width * (size_t)f->height;
    for (size_t i = 0; i < pixels; i++) {
        const double *a = &f->aov[FILM_AOV_STRIDE * i];
        const int spp = film_pixel_spp(f, i);
        const double inv = spp > 0 ? 1.0 / spp : 0.0;
        if (aov == CST_AOV_ALBEDO) {
            for (int c = 0; c < 3; c++) out[3 * i + (size_t)c] = (float)(a[c] * inv);
        } else if (aov == CST_AOV_NORMAL) { /* renormalised as the EXR's N channels */
            double len = sqrt(a[3] * a[3] + a[4] * a[4] + a[5] * a[5]);
            for (int c = 0; c < 3; c++) out[3 * i + (size_t)c] = len > 0.0 ? (float)(a[3 + c] / len) : 0.0f;
        } else {
            out[i] = a[7] > 0.0 ? (float)(a[6] / a[7]) : INFINITY;
        }
    }
    return CST_OK;
}

CstStatus cst_image_read(const char *path, float **rgb, int *width, int *height, CstError *err)
{
    return image_read(path, rgb, width, height, err);
}

CstStatus cst_image_write(const char *path, const float *rgb, int width, int height, CstError *err)
{
    return image_write(path, rgb, width, height, err);
}

CstStatus cst_image_write_opt(const char *path, const float *rgb, int width, int height,
                              const CstImageWriteOptions *options, CstError *err)
{
    ImageWriteOptions opt = {.out = options};
    return image_write_opt(path, rgb, width, height, &opt, err);
}

CstStatus cst_image_write_check(const char *path, CstError *err) { return image_write_check(path, err); }

int cst_image_path_writable(const char *path) { return image_format_is_writable(image_format_from_path(path)); }
int cst_image_path_is_exr(const char *path) { return image_path_is_exr(path); }

void film_resolve(const Film *f, float *rgb_out)
{
    size_t n = (size_t)f->width * (size_t)f->height * 3u;
    if (f->pixel_spp) {
        for (size_t i = 0; i < n; i++) {
            const int spp = f->pixel_spp[i / 3];
            rgb_out[i] = (float)(f->sum[i] * (spp > 0 ? 1.0 / spp : 0.0));
        }
        return;
    }
    double inv = f->spp > 0 ? 1.0 / f->spp : 0.0;
    for (size_t i = 0; i < n; i++) rgb_out[i] = (float)(f->sum[i] * inv);
}

/* The extra channels of the AOVs in f->aovs, interleaved per pixel in this order (the
 * EXR writer keys channels by name, so the order is ours). */
static int film_aov_channels(int aovs, const char **names)
{
    static const struct { int bit; const char *names[3]; int n; } AOVS[] = {
        {CST_AOV_ALBEDO, {"albedo.R", "albedo.G", "albedo.B"}, 3},
        {CST_AOV_NORMAL, {"N.X", "N.Y", "N.Z"}, 3},
        {CST_AOV_DEPTH, {"Z", NULL, NULL}, 1},
        {CST_AOV_VARIANCE, {"variance.R", "variance.G", "variance.B"}, 3},
    };
    int n = 0;
    for (size_t a = 0; a < sizeof AOVS / sizeof AOVS[0]; a++)
        if (aovs & AOVS[a].bit)
            for (int c = 0; c < AOVS[a].n; c++) names[n++] = AOVS[a].names[c];
    return n;
}

/* Pixel i's extra channels, as film_aov_channels lists them. Variance is that of the
 * written (exposed) mean, so it scales with the square of the exposure. */
static void film_aov_pixel(const Film *f, size_t i, float *out)
{
    int n = 0;
    const double *a = f->aov ? &f->aov[FILM_AOV_STRIDE * i] : NULL;
    const int spp = film_pixel_spp(f, i);
    double inv = spp > 0 ? 1.0 / spp : 0.0;
    if (f->aovs & CST_AOV_ALBEDO)
        for (int c = 0; c < 3; c++) out[n++] = (float)(a[c] * inv);
    if (f->aovs & CST_AOV_NORMAL) {
        /* The mean of unit normals, renormalised: a pixel across an edge gets the average
         * direction, one on a flat surface the surface's normal. */
        double len = sqrt(a[3] * a[3] + a[4] * a[4] + a[5] * a[5]);
        for (int c = 0; c < 3; c++) out[n++] = len > 0.0 ? (float)(a[3 + c] / len) : 0.0f;
    }
    if (f->aovs & CST_AOV_DEPTH) out[n++] = a[7] > 0.0 ? (float)(a[6] / a[7]) : INFINITY;
    if (f->aovs & CST_AOV_VARIANCE) {
        double var[3];
        cst_film_pixel_variance(f, (int)(i % (size_t)f->width), (int)(i / (size_t)f->width), var);
        for (int c = 0; c < 3; c++) out[n++] = (float)(var[c] * f->exposure_scale * f->exposure_scale);
    }
}

CstStatus cst_film_write(const CstFilm *f, const char *path, CstError *err)
{
    return cst_film_write_opt(f, path, NULL, err);
}

void cst_film_output_pixels(const CstFilm *f, float *rgb_out)
{
    size_t pixels = (size_t)f->width * (size_t)f->height;
    film_resolve(f, rgb_out);
    if (f->exposure_scale != 1.0)
        for (size_t i = 0; i < 3 * pixels; i++) rgb_out[i] = (float)((double)rgb_out[i] * f->exposure_scale);
    if (f->white_balanced)
        for (size_t i = 0; i < pixels; i++) {
            const double (*m)[3] = f->white_balance;
            double r = (double)rgb_out[3 * i], g = (double)rgb_out[3 * i + 1], b = (double)rgb_out[3 * i + 2];
            for (int c = 0; c < 3; c++) rgb_out[3 * i + c] = (float)(m[c][0] * r + m[c][1] * g + m[c][2] * b);
        }
}

CstStatus cst_film_write_opt(const CstFilm *f, const char *path, const CstImageWriteOptions *options,
                             CstError *err)
{
    size_t pixels = (size_t)f->width * (size_t)f->height;
    const char *names[IMAGE_MAX_EXTRA];
    int extra = film_aov_channels(f->aovs, names);
    if (extra > 0 && !image_path_is_exr(path))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "%s: AOVs are written as extra EXR channels; expected an output ending in .exr",
                        path);
    float *rgb = malloc(pixels * 3u * sizeof *rgb);
    float *aux = extra > 0 ? malloc(pixels * (size_t)extra * sizeof *aux) : NULL;
    if (!rgb || (extra > 0 && !aux)) {
        free(rgb);
        free(aux);
        return cst_fail(err, CST_ERR_OOM, "out of memory resolving the film");
    }
    cst_film_output_pixels(f, rgb);
    for (size_t i = 0; extra > 0 && i < pixels; i++) film_aov_pixel(f, i, aux + i * (size_t)extra);
    ImageWriteOptions opt = {f->png_linear != 0, extra, names, aux, options};
    CstStatus st = image_write_opt(path, rgb, f->width, f->height, &opt, err);
    free(rgb);
    free(aux);
    return st;
}

int splat_list_init(SplatList *l, size_t cap)
{
    memset(l, 0, sizeof *l);
    l->v = malloc(cap * sizeof *l->v);
    if (!l->v) return 0;
    l->cap = cap;
    return 1;
}

void splat_list_free(SplatList *l)
{
    free(l->v);
    free(l->binned);
    free(l->band_start);
    memset(l, 0, sizeof *l);
}

SplatFrame splat_frame(int width, int height, CstFilter filter)
{
    SplatFrame fr = {width, height, filter, 0, 1, height, 0.0f};
    /* A power of two of rows, so binning shifts instead of dividing. */
    while ((2 << fr.band_shift) * width <= FILM_SPLAT_BAND) fr.band_shift++;
    fr.band_rows = 1 << fr.band_shift;
    fr.bands = (height + fr.band_rows - 1) / fr.band_rows;
    return fr;
}

/* The pixels an entry at (x, y) reaches: columns [*x0, *x1] and rows [*y0, *y1], clipped
 * to the film; false when none. Pixel centres sit at k + 1/2. */
static inline bool splat_footprint(const SplatFrame *fr, float x, float y, int *x0, int *x1, int *y0, int *y1)
{
    switch (fr->filter) {
    case CST_FILTER_TENT: {
        /* The tent 1 - |t| of the two nearest centres in each axis. */
        *x0 = (int)floorf(x - 0.5f); *x1 = *x0 + 1;
        *y0 = (int)floorf(y - 0.5f); *y1 = *y0 + 1;
        break;
    }
    case CST_FILTER_GAUSSIAN:
    case CST_FILTER_MITCHELL: {
        const float r = filter_radius(fr->filter);
        *x0 = (int)ceilf(x - 0.5f - r); *x1 = (int)floorf(x - 0.5f + r);
        *y0 = (int)ceilf(y - 0.5f - r); *y1 = (int)floorf(y - 0.5f + r);
        break;
    }
    default:
        *x0 = *x1 = (int)floorf(x);
        *y0 = *y1 = (int)floorf(y);
        break;
    }
    if (*x0 < 0) *x0 = 0;
    if (*y0 < 0) *y0 = 0;
    if (*x1 > fr->width - 1) *x1 = fr->width - 1;
    if (*y1 > fr->height - 1) *y1 = fr->height - 1;
    return *x0 <= *x1 && *y0 <= *y1;
}

void film_splat(SplatList *l, const SplatFrame *fr, float x, float y, Color c)
{
    if (!color_is_finite(c)) {
        l->nonfinite++;
        return;
    }
    if (fr->clamp > 0.0f) c = color_clamp_xyz_max(c, fr->clamp);
    int x0, x1, y0, y1;
    /* (also drops positions so far off that the integer conversion would overflow) */
    if (!(fabsf(x) < 1e9f && fabsf(y) < 1e9f) || !splat_footprint(fr, x, y, &x0, &x1, &y0, &y1)) return;
    if (!array_push(l, ((FilmSplat){x, y, c.c[0], c.c[1], c.c[2], (uint16_t)y0, (uint16_t)y1}))) l->oom = 1;
}

/* splat_spread for the tent, the light tracers' default filter: the two nearest pixel
 * centres per axis with bilinear weights (1 - a, a), each kept if on the film (and the
 * rows within [row_lo, row_hi)). Zero weights are added rather than tested for: the sums
 * start at +0, and adding a zero of either sign to them changes no bit. */
static inline void splat_spread_tent(const FilmSplat *s, int width, double *rgb, double scale, int row_lo,
                                     int row_hi)
{
    const float tx = s->x - 0.5f, ty = s->y - 0.5f;
    const float fx0 = floorf(tx), fy0 = floorf(ty);
    const float ax = tx - fx0, ay = ty - fy0;
    const int cx = (int)fx0, cy = (int)fy0;
    const float wx0 = 1.0f - ax, wy[2] = {1.0f - ay, ay};
    const bool x0_in = (unsigned)cx < (unsigned)width, x1_in = (unsigned)(cx + 1) < (unsigned)width;
    const double r = scale * (double)s->r, g = scale * (double)s->g, b = scale * (double)s->b;
    const int lo = s->row0 > row_lo ? s->row0 : row_lo, hi = s->row1 < row_hi - 1 ? s->row1 : row_hi - 1;
    for (int j = 0; j < 2; j++) {
        const int py = cy + j;
        if (py < lo || py > hi) continue;
        double *row = &rgb[3 * (size_t)py * (size_t)width];
        if (x0_in) {
            double *p = &row[3 * cx];
            const double w = (double)(wx0 * wy[j]);
            p[0] += r * w; p[1] += g * w; p[2] += b * w;
        }
        if (x1_in) {
            double *p = &row[3 * (cx + 1)];
            const double w = (double)(ax * wy[j]);
            p[0] += r * w; p[1] += g * w; p[2] += b * w;
        }
    }
}

/* Adds scale times entry s, spread by the filter, to the pixels of its footprint in rows
 * [row_lo, row_hi). The weights: the tent's bilinear (1 - a, a) pairs, the wide filters'
 * h(centre - position) from filter_weight1, the same h camera samples are weighted with. */
static inline void splat_spread(const FilmSplat *s, const SplatFrame *fr, double *rgb, double scale, int row_lo,
                                int row_hi)
{
    if (fr->filter == CST_FILTER_TENT) {
        splat_spread_tent(s, fr->width, rgb, scale, row_lo, row_hi);
        return;
    }
    /* Rows from the entry (film_splat's footprint), columns as film_splat found them. */
    int y0 = s->row0 > row_lo ? s->row0 : row_lo, y1 = s->row1 < row_hi - 1 ? s->row1 : row_hi - 1;
    int x0, x1;
    switch (fr->filter) {
    case CST_FILTER_GAUSSIAN:
    case CST_FILTER_MITCHELL: {
        const float rad = filter_radius(fr->filter);
        x0 = (int)ceilf(s->x - 0.5f - rad);
        x1 = (int)floorf(s->x - 0.5f + rad);
        break;
    }
    default: x0 = x1 = (int)floorf(s->x); break;
    }
    if (x0 < 0) x0 = 0;
    if (x1 > fr->width - 1) x1 = fr->width - 1;
    const double r = scale * (double)s->r, g = scale * (double)s->g, b = scale * (double)s->b;
    if (fr->filter == CST_FILTER_GAUSSIAN || fr->filter == CST_FILTER_MITCHELL) {
        for (int py = y0; py <= y1; py++) {
            float wy = filter_weight1(fr->filter, (float)py + 0.5f - s->y);
            if (wy == 0.0f) continue;
            for (int px = x0; px <= x1; px++) {
                float wx = filter_weight1(fr->filter, (float)px + 0.5f - s->x);
                if (wx == 0.0f) continue;
                double w = (double)(wx * wy);
                double *p = &rgb[3 * ((size_t)py * (size_t)fr->width + (size_t)px)];
                p[0] += r * w; p[1] += g * w; p[2] += b * w;
            }
        }
    } else if (y0 <= y1) {
        double *p = &rgb[3 * ((size_t)y0 * (size_t)fr->width + (size_t)x0)];
        p[0] += r; p[1] += g; p[2] += b;
    }
}

void film_add_splat_rows(const FilmSplat *s, const SplatFrame *fr, double *rgb, double scale, int row_lo, int row_hi)
{
    splat_spread(s, fr, rgb, scale, row_lo, row_hi);
}

int splat_list_bin(SplatList *l, const SplatFrame *fr)
{
    const int bands = fr->bands;
    if (l->bands != bands) {
        uint32_t *bs = realloc(l->band_start, ((size_t)bands + 1) * sizeof *bs);
        if (!bs) { l->oom = 1; return 0; }
        l->band_start = bs;
        l->bands = bands;
    }
    uint32_t *start = l->band_start;
    memset(start, 0, ((size_t)bands + 1) * sizeof *start);
    /* Each entry goes to the bands of its first and last footprint rows (a footprint is
     * at most 4 rows, a band at least 1: wider spans are counted band by band). */
    size_t total = 0;
    for (size_t i = 0; i < l->n; i++)
        for (int b = l->v[i].row0 >> fr->band_shift; b <= l->v[i].row1 >> fr->band_shift; b++) { start[b + 1]++; total++; }
    if (!array_grow(&l->binned, &l->binned_cap, total, sizeof *l->binned)) {
        l->oom = 1;
        return 0;
    }
    for (int b = 0; b < bands; b++) start[b + 1] += start[b];
    /* Placing through a running cursor per band keeps list order inside each band; the
     * cursors end where the next band starts, so one pass rebuilds band_start after. */
    for (size_t i = 0; i < l->n; i++)
        for (int b = l->v[i].row0 >> fr->band_shift; b <= l->v[i].row1 >> fr->band_shift; b++) l->binned[start[b]++] = l->v[i];
    for (int b = bands; b > 0; b--) start[b] = start[b - 1];
    start[0] = 0;
    return 1;
}

void film_add_splats_band(const SplatList *l, const SplatFrame *fr, double *rgb, double scale, int band)
{
    const int row_lo = band * fr->band_rows;
    const int row_hi = row_lo + fr->band_rows < fr->height ? row_lo + fr->band_rows : fr->height;
    for (uint32_t i = l->band_start[band]; i < l->band_start[band + 1]; i++)
        splat_spread(&l->binned[i], fr, rgb, scale, row_lo, row_hi);
}

void film_add_splats(const SplatList *l, const SplatFrame *fr, double *rgb, double scale)
{
    for (size_t i = 0; i < l->n; i++) splat_spread(&l->v[i], fr, rgb, scale, 0, fr->height);
}

/* The public AOV names (caustic.h). */
int cst_aov_from_name(const char *name)
{
    if (strcmp(name, "albedo") == 0) return CST_AOV_ALBEDO;
    if (strcmp(name, "normal") == 0) return CST_AOV_NORMAL;
    if (strcmp(name, "depth") == 0) return CST_AOV_DEPTH;
    if (strcmp(name, "variance") == 0) return CST_AOV_VARIANCE;
    return 0;
}
