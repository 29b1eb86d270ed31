/* Film storage, resolution to pixel means and variances, and output. */
#include "film/film.h"

#include <stdlib.h>

#include "core/error.h"
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
    return f;
}

void film_destroy(Film *f)
{
    if (!f) return;
    free(f->sum);
    free(f->sum_sq);
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

CstStatus cst_film_write(const CstFilm *f, const char *path, CstError *err)
{
    float *rgb = malloc((size_t)f->width * (size_t)f->height * 3u * sizeof *rgb);
    if (!rgb) return cst_fail(err, CST_ERR_OOM, "out of memory resolving the film");
    film_resolve(f, rgb);
    CstStatus st = image_write(path, rgb, f->width, f->height, err);
    free(rgb);
    return st;
}
