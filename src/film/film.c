/* Film storage, resolution to pixel means and variances, and output. */
#include "film/film.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/filter.h"
#include "film/image_io.h"

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
    c->aovs = f->aovs;
    c->exposure_scale = f->exposure_scale;
    c->png_linear = f->png_linear;
    if (f->aov) {
        c->aov = malloc((size_t)w * (size_t)h * FILM_AOV_STRIDE * sizeof *c->aov);
        if (!c->aov) { film_destroy(c); return NULL; }
    }
    for (int y = 0; y < h; y++) {
        size_t from = (size_t)(y0 + y) * (size_t)f->width + (size_t)x0, to = (size_t)y * (size_t)w;
        memcpy(&c->sum[3 * to], &f->sum[3 * from], 3 * (size_t)w * sizeof *c->sum);
        memcpy(&c->sum_sq[3 * to], &f->sum_sq[3 * from], 3 * (size_t)w * sizeof *c->sum_sq);
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
    free(f->aov);
    free(f);
}

void cst_film_destroy(CstFilm *film) { film_destroy(film); }
int cst_film_width(const CstFilm *f) { return f->width; }
int cst_film_height(const CstFilm *f) { return f->height; }
int cst_film_spp(const CstFilm *f) { return f->spp; }

void cst_film_pixel(const CstFilm *f, int x, int y, double rgb_out[3])
{
    const double *s = &f->sum[3 * ((size_t)y * (size_t)f->width + (size_t)x)];
    double inv = f->spp > 0 ? 1.0 / f->spp : 0.0;
    for (int c = 0; c < 3; c++) rgb_out[c] = s[c] * inv;
}

void cst_film_pixel_variance(const CstFilm *f, int x, int y, double var[3])
{
    size_t i = 3 * ((size_t)y * (size_t)f->width + (size_t)x);
    double n = (double)f->spp;
    for (int c = 0; c < 3; c++) {
        if (f->spp < 2) { var[c] = 0.0; continue; }
        double mean = f->sum[i + c] / n;
        /* Unbiased sample variance, divided by n for the variance of the mean. */
        double v = (f->sum_sq[i + c] - n * mean * mean) / (n - 1.0);
        var[c] = (v > 0.0 ? v : 0.0) / n;
    }
}

void film_resolve(const Film *f, float *rgb_out)
{
    double inv = f->spp > 0 ? 1.0 / f->spp : 0.0;
    size_t n = (size_t)f->width * (size_t)f->height * 3u;
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
    double inv = f->spp > 0 ? 1.0 / f->spp : 0.0;
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
    film_resolve(f, rgb);
    if (f->exposure_scale != 1.0)
        for (size_t i = 0; i < 3 * pixels; i++) rgb[i] = (float)((double)rgb[i] * f->exposure_scale);
    for (size_t i = 0; extra > 0 && i < pixels; i++) film_aov_pixel(f, i, aux + i * (size_t)extra);
    ImageWriteOptions opt = {f->png_linear != 0, extra, names, aux};
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

static void splat_push(SplatList *l, int pixel, Rgb c)
{
    if (l->n == l->cap) {
        size_t cap = l->cap ? 2 * l->cap : 1024;
        FilmSplat *v = realloc(l->v, cap * sizeof *v);
        if (!v) { l->oom = 1; return; }
        l->v = v;
        l->cap = cap;
    }
    FilmSplat *s = &l->v[l->n++];
    s->pixel = pixel;
    s->r = c.r; s->g = c.g; s->b = c.b;
}

void film_splat(SplatList *l, int width, int height, CstFilter filter, float x, float y, Rgb c)
{
    if (!rgb_is_finite(c)) {
        l->nonfinite++;
        return;
    }
    if (filter == CST_FILTER_BOX || filter == CST_FILTER_DEFAULT) {
        int px = (int)floorf(x), py = (int)floorf(y);
        if (px < 0 || px >= width || py < 0 || py >= height) return;
        splat_push(l, py * width + px, c);
        return;
    }
    if (filter == CST_FILTER_GAUSSIAN || filter == CST_FILTER_MITCHELL) {
        /* Every pixel whose centre lies within the radius gets h(centre - (x, y)) c: the
         * same normalised h the camera samples are weighted with (filter.c). */
        const float r = filter_radius(filter);
        int x0 = (int)ceilf(x - 0.5f - r), x1 = (int)floorf(x - 0.5f + r);
        int y0 = (int)ceilf(y - 0.5f - r), y1 = (int)floorf(y - 0.5f + r);
        if (x0 < 0) x0 = 0;
        if (y0 < 0) y0 = 0;
        if (x1 > width - 1) x1 = width - 1;
        if (y1 > height - 1) y1 = height - 1;
        for (int py = y0; py <= y1; py++) {
            float wy = filter_weight1(filter, (float)py + 0.5f - y);
            if (wy == 0.0f) continue;
            for (int px = x0; px <= x1; px++) {
                float wx = filter_weight1(filter, (float)px + 0.5f - x);
                if (wx != 0.0f) splat_push(l, py * width + px, rgb_scale(c, wx * wy));
            }
        }
        return;
    }
    /* Pixel centres sit at k + 1/2; the tent 1 - |t| of the two nearest in each axis
     * sums to 1, the partition of unity that makes filter importance sampling (each
     * camera sample in one pixel, weight 1) and splatting estimate the same pixel. */
    float tx = x - 0.5f, ty = y - 0.5f;
    float fx0 = floorf(tx), fy0 = floorf(ty);
    float ax = tx - fx0, ay = ty - fy0;
    int x0 = (int)fx0, y0 = (int)fy0;
    const float wx[2] = {1.0f - ax, ax}, wy[2] = {1.0f - ay, ay};
    for (int j = 0; j < 2; j++) {
        int py = y0 + j;
        if (py < 0 || py >= height || wy[j] == 0.0f) continue;
        for (int i = 0; i < 2; i++) {
            int px = x0 + i;
            if (px < 0 || px >= width || wx[i] == 0.0f) continue;
            splat_push(l, py * width + px, rgb_scale(c, wx[i] * wy[j]));
        }
    }
}

int splat_list_bin(SplatList *l, int bands)
{
    if (l->bands != bands) {
        uint32_t *bs = realloc(l->band_start, ((size_t)bands + 1) * sizeof *bs);
        if (!bs) { l->oom = 1; return 0; }
        l->band_start = bs;
        l->bands = bands;
    }
    if (l->binned_cap < l->n) {
        FilmSplat *b = realloc(l->binned, l->cap * sizeof *b);
        if (!b) { l->oom = 1; return 0; }
        l->binned = b;
        l->binned_cap = l->cap;
    }
    uint32_t *start = l->band_start;
    memset(start, 0, ((size_t)bands + 1) * sizeof *start);
    for (size_t i = 0; i < l->n; i++) start[l->v[i].pixel / FILM_SPLAT_BAND + 1]++;
    for (int b = 0; b < bands; b++) start[b + 1] += start[b];
    /* Placing through a running cursor per band keeps list order inside each band; the
     * cursors end where the next band starts, so one pass rebuilds band_start after. */
    for (size_t i = 0; i < l->n; i++) l->binned[start[l->v[i].pixel / FILM_SPLAT_BAND]++] = l->v[i];
    for (int b = bands; b > 0; b--) start[b] = start[b - 1];
    start[0] = 0;
    return 1;
}

void film_add_splats_band(const SplatList *l, double *rgb, double scale, int band)
{
    for (uint32_t i = l->band_start[band]; i < l->band_start[band + 1]; i++) {
        const FilmSplat *s = &l->binned[i];
        double *p = &rgb[3 * (size_t)s->pixel];
        p[0] += scale * (double)s->r;
        p[1] += scale * (double)s->g;
        p[2] += scale * (double)s->b;
    }
}

void film_add_splats(const SplatList *l, double *rgb, double scale)
{
    for (size_t i = 0; i < l->n; i++) {
        const FilmSplat *s = &l->v[i];
        double *p = &rgb[3 * (size_t)s->pixel];
        p[0] += scale * (double)s->r;
        p[1] += scale * (double)s->g;
        p[2] += scale * (double)s->b;
    }
}
