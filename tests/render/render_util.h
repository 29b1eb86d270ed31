/* Helpers for the statistical render tests: region means with standard errors from the
 * film's per-pixel variance, and z-scores between two independent renders. */
#ifndef CST_TESTS_RENDER_UTIL_H
#define CST_TESTS_RENDER_UTIL_H

#include <math.h>

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

#endif
