/* Piecewise-constant 1D distribution over n discrete items (a CDF with binary search). */
#ifndef CST_SAMPLING_DISTRIB1D_H
#define CST_SAMPLING_DISTRIB1D_H

#include "caustic/caustic.h"

typedef struct Distrib1D {
    float *cdf;  /* n + 1 entries, cdf[0] = 0, cdf[n] = 1 */
    float *pmf;  /* n entries */
    int n;
    double total; /* sum of the input weights */
} Distrib1D;

/* Weights must be >= 0 with a positive sum. */
CstStatus distrib1d_init(Distrib1D *d, const float *weights, int n, CstError *err);
void distrib1d_free(Distrib1D *d);
/* Picks an item with probability pmf[i]; u in [0, 1). */
int distrib1d_sample(const Distrib1D *d, float u);

#endif
