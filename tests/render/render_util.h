/* Helpers for the statistical render tests: region means with standard errors from the
 * film's per-pixel variance or, for light tracing, from independent renders; z-scores
 * between two independent renders. */
#ifndef CST_TESTS_RENDER_UTIL_H
#define CST_TESTS_RENDER_UTIL_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"

/* Tests reject at |z| > 4: two-sided p = 6.3e-5 per comparison, so a suite of a few
 * hundred comparisons fails by chance with probability ~1e-2 at most; the seeds are
 * fixed, so a pass is a pass forever and a failure is a bias to find, not a flake. */
#define Z_LIMIT 4.0

typedef struct RegionStat {
    double mean[3];
    double se[3]; /* standard error of mean[] */
} RegionStat;

/* Mean over the pixels [x0,x1) x [y0,y1); the pixel estimates are independent (each has
 * its own random streams), so the variance of the average is sum(var) / n^2. */
static inline RegionStat region_stat(const CstFilm *f, int x0, int y0, int x1, int y1)
{
    RegionStat r = {{0, 0, 0}, {0, 0, 0}};
    double var[3] = {0, 0, 0};
    double n = (double)(x1 - x0) * (double)(y1 - y0);
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double m[3], v[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, v);
            for (int c = 0; c < 3; c++) { r.mean[c] += m[c]; var[c] += v[c]; }
        }
    for (int c = 0; c < 3; c++) {
        r.mean[c] /= n;
        r.se[c] = sqrt(var[c]) / n;
    }
    return r;
}

static inline double z_score(double a, double se_a, double b, double se_b)
{
    double se = sqrt(se_a * se_a + se_b * se_b);
    if (se == 0.0) return a == b ? 0.0 : (double)INFINITY;
    return (a - b) / se;
}

/* Region statistics of an estimator whose pixel estimates are correlated within a sample,
 * as the light tracer's are (a light path splats into several pixels, and the number of
 * paths is fixed): region_stat would sum per-pixel variances and miss the covariances.
 * Instead: `renders` independent renders of base->spp samples per pixel (1 if unset;
 * seeds seed, seed + 1, ...), and for each of the `count` regions rect[i] = {x0, y0, x1, y1} the mean of its
 * per-render means, with the standard error from their sample variance (normal to the
 * precision Z_LIMIT needs when renders is in the hundreds). If naive_se is not NULL it
 * receives, per region, what region_stat would have given for channel 0, for
 * comparison. Also right for estimators whose maps are shared by all pixels (photon
 * mapping). Returns cst_render's status on failure, and fails on NaN/Inf samples. */
static inline CstStatus region_stats_by_render(const CstScene *scene, const CstRenderSettings *base,
                                               int renders, uint64_t seed, int count,
                                               const int (*rect)[4], RegionStat *out,
                                               double *naive_se, CstError *err)
{
    const int w = base->width, h = base->height;
    double *acc = (double *)calloc((size_t)count * 6u, sizeof *acc); /* sum, sum_sq per channel */
    double *pix = (double *)calloc((size_t)w * (size_t)h * 2u, sizeof *pix); /* channel 0 */
    CstStatus st = acc && pix ? CST_OK : CST_ERR_OOM;
    if (st != CST_OK) {
        err->status = st;
        memcpy(err->msg, "out of memory", sizeof "out of memory");
    }
    for (int k = 0; k < renders && st == CST_OK; k++) {
        CstRenderSettings rs = *base;
        rs.spp = base->spp > 0 ? base->spp : 1;
        rs.seed = seed + (uint64_t)k;
        rs.seed_set = 1;
        CstFilm *f = NULL;
        CstRenderStats stats;
        if ((st = cst_render(scene, &rs, &f, &stats, err)) != CST_OK) break;
        if (stats.nonfinite > 0) {
            cst_film_destroy(f);
            st = err->status = CST_ERR_INTERNAL;
            snprintf(err->msg, sizeof err->msg, "%llu NaN/Inf samples", (unsigned long long)stats.nonfinite);
            break;
        }
        for (int i = 0; i < count; i++) {
            RegionStat one = region_stat(f, rect[i][0], rect[i][1], rect[i][2], rect[i][3]);
            for (int c = 0; c < 3; c++) {
                acc[6 * i + 2 * c] += one.mean[c];
                acc[6 * i + 2 * c + 1] += one.mean[c] * one.mean[c];
            }
        }
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double m[3];
                cst_film_pixel(f, x, y, m);
                size_t p = 2u * ((size_t)y * (size_t)w + (size_t)x);
                pix[p] += m[0];
                pix[p + 1] += m[0] * m[0];
            }
        cst_film_destroy(f);
    }
    if (st == CST_OK) {
        const double n = (double)renders;
        for (int i = 0; i < count; i++) {
            for (int c = 0; c < 3; c++) {
                double mean = acc[6 * i + 2 * c] / n;
                double var = (acc[6 * i + 2 * c + 1] - n * mean * mean) / (n - 1.0);
                out[i].mean[c] = mean;
                out[i].se[c] = sqrt(var > 0.0 ? var : 0.0) / sqrt(n);
            }
            if (naive_se) {
                double v = 0.0;
                for (int y = rect[i][1]; y < rect[i][3]; y++)
                    for (int x = rect[i][0]; x < rect[i][2]; x++) {
                        size_t p = 2u * ((size_t)y * (size_t)w + (size_t)x);
                        double mean = pix[p] / n;
                        v += (pix[p + 1] - n * mean * mean) / (n - 1.0) / n;
                    }
                double pixels = (double)(rect[i][2] - rect[i][0]) * (double)(rect[i][3] - rect[i][1]);
                naive_se[i] = sqrt(v > 0.0 ? v : 0.0) / pixels;
            }
        }
    }
    free(acc);
    free(pix);
    return st;
}

#endif
