/* Chi-square goodness-of-fit helpers shared by the sampling tests (warps, BSDFs, lights):
 * the chi-square survival function and Pearson's statistic with pooling of
 * low-expectation cells. */
#ifndef CST_TESTS_UNIT_CHI2_H
#define CST_TESTS_UNIT_CHI2_H

#include <math.h>
#include <stdlib.h>

/* Cells expecting fewer samples than this are pooled. */
static const double MIN_EXPECTED = 5.0;

/* Regularized incomplete gamma functions by the series (x < a + 1) and by Lentz's
 * continued fraction otherwise (Numerical Recipes, 3rd ed., sec. 6.2). */
static double gamma_p_series(double a, double x)
{
    double ap = a, del = 1.0 / a, sum = del;
    for (int n = 0; n < 100000; n++) {
        ap += 1.0;
        del *= x / ap;
        sum += del;
        if (fabs(del) < fabs(sum) * 1e-16) break;
    }
    return sum * exp(-x + a * log(x) - lgamma(a));
}

static double gamma_q_fraction(double a, double x)
{
    const double tiny = 1e-300;
    double b = x + 1.0 - a, c = 1.0 / tiny, d = 1.0 / b, h = d;
    for (int i = 1; i < 100000; i++) {
        double an = -(double)i * ((double)i - a);
        b += 2.0;
        d = an * d + b;
        if (fabs(d) < tiny) d = tiny;
        c = b + an / c;
        if (fabs(c) < tiny) c = tiny;
        d = 1.0 / d;
        double del = d * c;
        h *= del;
        if (fabs(del - 1.0) < 1e-16) break;
    }
    return exp(-x + a * log(x) - lgamma(a)) * h;
}

/* Q(a, x) = Gamma(a, x) / Gamma(a). */
static double gamma_q(double a, double x)
{
    if (x <= 0.0) return 1.0;
    return x < a + 1.0 ? 1.0 - gamma_p_series(a, x) : gamma_q_fraction(a, x);
}

/* P(X >= stat) for X ~ chi-square with dof degrees of freedom. */
static double chi2_sf(double stat, int dof) { return gamma_q(0.5 * (double)dof, 0.5 * stat); }

static const double *g_sort_key;
static int cmp_by_key(const void *a, const void *b)
{
    double ka = g_sort_key[*(const int *)a], kb = g_sort_key[*(const int *)b];
    return (ka > kb) - (ka < kb);
}

/* Pearson's statistic over n cells. Cells expecting fewer than MIN_EXPECTED samples are
 * pooled, smallest first, into one cell (Mitsuba's ChiSquareTest does the same). A cell
 * with zero expectation must be empty: *outside counts the samples that break this.
 * Returns the p-value; *dof_out gets the degrees of freedom. */
static double chi2_pvalue(const double *obs, const double *expd, int n, int *dof_out,
                          double *stat_out, double *outside)
{
    int *order = malloc((size_t)n * sizeof *order);
    if (!order) abort();
    for (int i = 0; i < n; i++) order[i] = i;
    g_sort_key = expd;
    qsort(order, (size_t)n, sizeof *order, cmp_by_key);
    double stat = 0.0, pool_obs = 0.0, pool_exp = 0.0;
    int cells = 0;
    *outside = 0.0;
    for (int k = 0; k < n; k++) {
        int i = order[k];
        if (expd[i] <= 0.0) { *outside += obs[i]; continue; }
        if (expd[i] < MIN_EXPECTED || (pool_exp > 0.0 && pool_exp < MIN_EXPECTED)) {
            pool_obs += obs[i];
            pool_exp += expd[i];
            continue;
        }
        stat += (obs[i] - expd[i]) * (obs[i] - expd[i]) / expd[i];
        cells++;
    }
    if (pool_exp > 0.0) {
        stat += (pool_obs - pool_exp) * (pool_obs - pool_exp) / pool_exp;
        cells++;
    }
    free(order);
    *dof_out = cells - 1;
    *stat_out = stat;
    return chi2_sf(stat, cells - 1);
}

#endif
