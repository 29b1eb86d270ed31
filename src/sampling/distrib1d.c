/* Discrete distribution by CDF inversion. */
#include "sampling/distrib1d.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"

CstStatus distrib1d_init(Distrib1D *d, const float *weights, int n, CstError *err)
{
    memset(d, 0, sizeof *d);
    if (n <= 0) return cst_fail(err, CST_ERR_INVALID_ARG, "empty distribution");
    d->cdf = malloc((size_t)(n + 1) * sizeof *d->cdf);
    d->pmf = malloc((size_t)n * sizeof *d->pmf);
    if (!d->cdf || !d->pmf) {
        distrib1d_free(d);
        return cst_fail(err, CST_ERR_OOM, "out of memory for a %d-entry distribution", n);
    }
    /* Accumulate in double so long lists of small weights keep their share. */
    double total = 0.0;
    for (int i = 0; i < n; i++) total += weights[i] > 0.0f ? (double)weights[i] : 0.0;
    if (!(total > 0.0)) {
        distrib1d_free(d);
        return cst_fail(err, CST_ERR_INVALID_ARG, "distribution weights sum to zero");
    }
    double acc = 0.0;
    d->cdf[0] = 0.0f;
    for (int i = 0; i < n; i++) {
        double w = weights[i] > 0.0f ? (double)weights[i] : 0.0;
        d->pmf[i] = (float)(w / total);
        acc += w;
        d->cdf[i + 1] = (float)(acc / total);
    }
    d->cdf[n] = 1.0f;
    d->n = n;
    d->total = total;
    return CST_OK;
}

void distrib1d_free(Distrib1D *d)
{
    free(d->cdf);
    free(d->pmf);
    memset(d, 0, sizeof *d);
}

int distrib1d_sample(const Distrib1D *d, float u)
{
    /* Largest i with cdf[i] <= u, skipping zero-probability items. */
    int lo = 0, hi = d->n - 1;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (d->cdf[mid] <= u) lo = mid;
        else hi = mid - 1;
    }
    while (lo < d->n - 1 && d->pmf[lo] == 0.0f) lo++;
    return lo;
}
