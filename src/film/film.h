/* The film: per-pixel accumulation of linear radiance samples. Each pixel keeps the sum
 * and the sum of squares (in double) so tests and tools get a variance estimate for
 * every pixel mean. Samples are added by exactly one thread per pixel, in sample order,
 * which makes the result independent of the thread count. */
#ifndef CST_FILM_FILM_H
#define CST_FILM_FILM_H

#include "caustic/caustic.h"
#include "math/rgb.h"

struct CstFilm {
    int width, height;
    int spp;        /* samples accumulated in every pixel */
    double *sum;    /* 3 per pixel */
    double *sum_sq; /* 3 per pixel */
};
typedef struct CstFilm Film;

/* Returns NULL on OOM. */
Film *film_create(int width, int height);
void film_destroy(Film *film);

static inline void film_accumulate(Film *f, int pixel, double r, double g, double b)
{
    double *s = &f->sum[3 * pixel], *q = &f->sum_sq[3 * pixel];
    s[0] += r; s[1] += g; s[2] += b;
    q[0] += r * r; q[1] += g * g; q[2] += b * b;
}

/* Means as float RGB, row 0 = top, into a caller buffer of width*height*3. */
void film_resolve(const Film *f, float *rgb_out);

#endif
