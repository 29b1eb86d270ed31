/* The film: per-pixel accumulation of linear radiance samples. Each pixel keeps the sum
 * and the sum of squares (in double) so tests and tools get a variance estimate for
 * every pixel mean. Samples are added by exactly one thread per pixel, in sample order,
 * which makes the result independent of the thread count. */
#ifndef CST_FILM_FILM_H
#define CST_FILM_FILM_H

#include "caustic/caustic.h"
#include "math/color.h"

/* The AOVs traced from each camera sample's first hit (render.c), and the per-pixel sums
 * they keep: albedo r, g, b, normal x, y, z, depth, and the number of samples that hit
 * something. Albedo and normal are means over all the pixel's samples (a miss adds 0);
 * depth is the mean over the samples that hit (+inf when none did). */
enum { FILM_AOV_FIRST_HIT = CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH, FILM_AOV_STRIDE = 8 };
/* Values per pixel of Film.progressive (SPPM's Ld sums, tau, N, r, and tau, N, r of its
 * visible points in media: sppm.c). */
enum { FILM_PROGRESSIVE_STRIDE = 13 };

struct CstFilm {
    int width, height;
    int spp;        /* samples accumulated in every pixel (with pixel_spp: the most any holds) */
    double *sum;    /* 3 per pixel */
    double *sum_sq; /* 3 per pixel */
    /* NULL: every pixel holds spp samples. Else each pixel's own count (--noise's adaptive
     * sampling, render/adaptive.h: pixels of one 16x16 block share a count). */
    int *pixel_spp;
    /* Output settings, applied by cst_film_write only */
    int aovs;               /* CST_AOV_* bits */
    double *aov;            /* FILM_AOV_STRIDE per pixel when aovs & FILM_AOV_FIRST_HIT, else NULL */
    /* A progressive integrator's per-pixel state, whose sums the film does not hold (SPPM:
     * FILM_PROGRESSIVE_STRIDE values per pixel, sppm_export), for checkpoints; else NULL. */
    double *progressive;
    /* An MLT render's chains (integrators/mlt.c's bytes, mlt_state_write), for checkpoints;
     * else NULL. Opaque here: the film only stores and frees them. */
    unsigned char *chains;
    size_t chains_len;
    double exposure_scale;  /* 2^exposure */
    int png_linear;
    int white_balanced;        /* white_balance applies (sensor.h) */
    double white_balance[3][3]; /* rgb_out = M rgb, after the exposure */
};
typedef struct CstFilm Film;

/* Returns NULL on OOM. */
Film *film_create(int width, int height);
/* Sets the output settings (caustic.h) and allocates the AOV sums if needed. Returns 0 on
 * OOM. */
int film_set_output(Film *film, int aovs, double exposure, int png_linear);
/* The sensor's white balance for an illuminant at kelvin (sensor.h; <= 0: none), applied
 * by cst_film_write with the exposure. */
void film_set_white_balance(Film *film, double kelvin);
void film_destroy(Film *film);
/* A new film holding the w x h pixels of f from (x0, y0) (sums, AOV sums, spp and output
 * settings); NULL on OOM. */
Film *film_crop(const Film *f, int x0, int y0, int w, int h);

/* The samples pixel i (row-major index) holds. */
static inline int film_pixel_spp(const Film *f, size_t i) { return f->pixel_spp ? f->pixel_spp[i] : f->spp; }
/* Gives f per-pixel counts, all f->spp; returns 0 on OOM. */
int film_enable_pixel_spp(Film *f);

/* dst's sums plus src's, value by value (sums, sums of squares, AOV sums when both have
 * them; not spp): how the sums of blocks of samples combine (render.c, cst_film_add). */
void film_add(Film *dst, const Film *src);

static inline void film_accumulate(Film *f, int pixel, double r, double g, double b)
{
    double *s = &f->sum[3 * pixel], *q = &f->sum_sq[3 * pixel];
    s[0] += r; s[1] += g; s[2] += b;
    q[0] += r * r; q[1] += g * g; q[2] += b * b;
}

/* Means as float RGB, row 0 = top, into a caller buffer of width*height*3. */
void film_resolve(const Film *f, float *rgb_out);

/* Light tracing's contributions ("splats") land on arbitrary pixels, so they cannot be
 * accumulated by the thread that owns a pixel. Each work unit records its splats in its
 * own list, one entry per contribution (its film position and colour: the filter spreads
 * it over pixels only when the lists are merged); the render driver adds the lists in a
 * fixed order (render.c). */
typedef struct FilmSplat {
    float x, y;         /* film position, camera_generate_ray's convention */
    float r, g, b;
    uint16_t row0, row1; /* the first and last film rows the filter reaches (clipped) */
} FilmSplat;

/* The film geometry splats are made for: the filter and the size, and the rows of the
 * merge bands. */
typedef struct SplatFrame {
    int width, height;
    CstFilter filter;
    int band_shift; /* rows per band of splat_list_bin: 1 << band_shift */
    int band_rows;
    int bands;      /* ceil(height / band_rows) */
    float clamp;    /* > 0: each splat through color_clamp_xyz_max with this limit; 0 = none */
} SplatFrame;

/* Bands of about 16384 pixels: the part of a double RGB image a band's merge writes (384
 * KiB) stays in the L2 cache (1 MiB per core here), whatever the image width. Taller bands
 * mean fewer tent splats that straddle two bands, each binned and spread twice (1 in 32
 * at 512 pixels wide, against 1 in 4 with bands of 2048 pixels: light tracing 5% faster,
 * docs/benchmarks.md). The sums do not depend on it: every pixel gets its splats in
 * chunk order whatever band it is in. */
enum { FILM_SPLAT_BAND = 16384 };
SplatFrame splat_frame(int width, int height, CstFilter filter);

typedef struct SplatList {
    FilmSplat *v;
    size_t n, cap;
    uint64_t nonfinite; /* NaN/Inf contributions dropped (never cleared) */
    int oom;            /* a splat was lost for lack of memory */
    /* splat_list_bin's output: the entries stably sorted by band into `binned`, band b at
     * [band_start[b], band_start[b + 1]); an entry whose filter footprint spans two bands
     * is in both. */
    FilmSplat *binned;
    size_t binned_cap;
    uint32_t *band_start;
    int bands;
} SplatList;

/* Reserves room for cap splats; returns 0 on OOM. Free with splat_list_free (accepts a
 * zeroed list). */
int splat_list_init(SplatList *l, size_t cap);
/* Adds scale times one entry, spread by the filter, to the pixels of rgb (width x height x
 * 3) in rows [row_lo, row_hi), with film_add_splats_band's arithmetic (`caustic explain`). */
void film_add_splat_rows(const FilmSplat *s, const SplatFrame *fr, double *rgb, double scale, int row_lo, int row_hi);
void splat_list_free(SplatList *l);
/* Records contribution c at film position (x, y), to be spread with the frame's filter so
 * that splats estimate the same pixel values as camera samples: box: all of c to the pixel
 * containing (x, y); tent (radius 1 pixel, normalised, as render.c samples it): c times
 * the tent of each of the up to four pixel centres within one pixel in x and y, i.e.
 * bilinear weights; Gaussian and Mitchell: c times h of every pixel centre within the
 * radius. Entries that reach no pixel are dropped; NaN/Inf contributions are counted and
 * dropped. Grows the list (sets l->oom if it cannot). */
void film_splat(SplatList *l, const SplatFrame *fr, float x, float y, Color c);
/* Adds scale times every splat, spread by the filter, to rgb (width*height*3 doubles), in
 * the list's order (tests and single-threaded callers). */
void film_add_splats(const SplatList *l, const SplatFrame *fr, double *rgb, double scale);
/* Counting sort of the list by band into l->binned, stable, so each pixel's splats keep
 * their order. Done by the thread that filled the list, while it is in cache. Returns 0
 * on OOM (sets l->oom). */
int splat_list_bin(SplatList *l, const SplatFrame *fr);
/* Adds scale times the binned splats of one band, spread by the filter, to the band's
 * rows of rgb, in list order: threads that own different bands can merge the same lists
 * at once, each pixel's sum in list order. */
void film_add_splats_band(const SplatList *l, const SplatFrame *fr, double *rgb, double scale, int band);

#endif
