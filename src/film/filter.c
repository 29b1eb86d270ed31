/* The reconstruction filters' shapes, normalisation and importance sampling. */
#include "film/filter.h"

#include <string.h>

#include "sampling/warp.h"

/* Unnormalised 1D shapes. Gaussian as pbrt-v4 has it: sigma 0.5 pixel, radius 1.5, minus
 * its value at the radius so it reaches 0 there. Mitchell-Netravali with B = C = 1/3
 * (Mitchell & Netravali, "Reconstruction Filters in Computer Graphics", 1988, eq. 8), on
 * a radius of 2 pixels; it has negative lobes for 1 < |x| < 2. */
static double shape(CstFilter type, double x)
{
    x = fabs(x);
    switch (type) {
    case CST_FILTER_GAUSSIAN: {
        const double s = 0.5, r = 1.5;
        if (x >= r) return 0.0;
        return exp(-x * x / (2.0 * s * s)) - exp(-r * r / (2.0 * s * s));
    }
    case CST_FILTER_MITCHELL: {
        const double B = 1.0 / 3.0, C = 1.0 / 3.0;
        if (x >= 2.0) return 0.0;
        if (x < 1.0)
            return ((12 - 9 * B - 6 * C) * x * x * x + (-18 + 12 * B + 6 * C) * x * x + (6 - 2 * B)) / 6.0;
        return ((-B - 6 * C) * x * x * x + (6 * B + 30 * C) * x * x + (-12 * B - 48 * C) * x + (8 * B + 24 * C)) / 6.0;
    }
    case CST_FILTER_TENT: return x < 1.0 ? 1.0 - x : 0.0;
    default: return x <= 0.5 ? 1.0 : 0.0;
    }
}

void filter_init(Filter *f, CstFilter type)
{
    memset(f, 0, sizeof *f);
    f->type = type == CST_FILTER_DEFAULT ? CST_FILTER_BOX : type;
    f->radius = f->type == CST_FILTER_GAUSSIAN ? 1.5f : f->type == CST_FILTER_MITCHELL ? 2.0f
              : f->type == CST_FILTER_TENT ? 1.0f : 0.5f;
    /* The integral and the per-bin means of |h1| by a fine midpoint rule (in double), which
     * is exact enough that the normalisation error is far below any test's noise. */
    const int sub = 256;
    double total = 0.0, cum = 0.0;
    const double dx = (double)f->radius / FILTER_TABLE;
    f->cdf[0] = 0.0f;
    double abs_sum[FILTER_TABLE];
    for (int b = 0; b < FILTER_TABLE; b++) {
        double s = 0.0, sa = 0.0;
        for (int k = 0; k < sub; k++) {
            double v = shape(f->type, (b + (k + 0.5) / sub) * dx);
            s += v;
            sa += fabs(v);
        }
        total += s * dx / sub;
        abs_sum[b] = sa * dx / sub;
        f->bin_abs[b] = (float)(sa / sub);
    }
    for (int b = 0; b < FILTER_TABLE; b++) {
        cum += abs_sum[b];
        f->cdf[b + 1] = (float)cum;
    }
    for (int b = 1; b <= FILTER_TABLE; b++) f->cdf[b] /= (float)cum;
    f->cdf[FILTER_TABLE] = 1.0f;
    f->norm = (float)(2.0 * total);
}

/* The integrals of the shapes over their support, in closed form, so a splat can weigh
 * without a Filter: box 1, tent 1, Mitchell 1 (it is normalised by construction),
 * Gaussian sqrt(pi/2) erf(1.5 sqrt 2) - 3 exp(-4.5) (sigma 0.5, radius 1.5). filter_init's
 * numeric integral is checked against these (test_filter.c). */
static double shape_integral(CstFilter type)
{
    return type == CST_FILTER_GAUSSIAN ? 1.2166034551268203 : 1.0;
}

float filter_weight1(CstFilter type, float x)
{
    return (float)(shape(type, (double)x) / shape_integral(type));
}

float filter_eval1(const Filter *f, float x)
{
    return filter_weight1(f->type, x);
}

/* One axis of the tabulated sampling: a sign, a bin by the CDF, a uniform point in it.
 * Returns the offset and its density (|h1| binned, normalised over [-radius, radius]). */
static float sample_axis(const Filter *f, float u, float *pdf)
{
    float sign = 1.0f;
    if (u < 0.5f) { sign = -1.0f; u = 2.0f * u; }
    else u = 2.0f * u - 1.0f;
    int lo = 0, hi = FILTER_TABLE; /* the bin b with cdf[b] <= u < cdf[b + 1] */
    while (hi - lo > 1) {
        int mid = (lo + hi) / 2;
        if (f->cdf[mid] <= u) lo = mid;
        else hi = mid;
    }
    float width = f->cdf[lo + 1] - f->cdf[lo];
    float t = width > 0.0f ? (u - f->cdf[lo]) / width : 0.5f;
    if (!(t < 1.0f)) t = 0x1.fffffep-1f;
    const float dx = f->radius / FILTER_TABLE;
    /* Each half holds probability 1/2; within it the bin's share is width, spread over dx. */
    *pdf = 0.5f * width / dx;
    return sign * ((float)lo + t) * dx;
}

Vec2 filter_sample(const Filter *f, Vec2 u, float *weight)
{
    switch (f->type) {
    case CST_FILTER_TENT:
        *weight = 1.0f;
        return v2(warp_tent(u.x), warp_tent(u.y));
    case CST_FILTER_GAUSSIAN:
    case CST_FILTER_MITCHELL: {
        float px, py;
        float x = sample_axis(f, u.x, &px), y = sample_axis(f, u.y, &py);
        *weight = filter_eval1(f, x) * filter_eval1(f, y) / (px * py);
        return v2(x, y);
    }
    default:
        *weight = 1.0f;
        return v2(u.x - 0.5f, u.y - 0.5f);
    }
}

/* The public name table (caustic.h): the filter module owns its names. */
CstFilter cst_filter_from_name(const char *name)
{
    if (strcmp(name, "box") == 0) return CST_FILTER_BOX;
    if (strcmp(name, "tent") == 0) return CST_FILTER_TENT;
    if (strcmp(name, "gaussian") == 0) return CST_FILTER_GAUSSIAN;
    if (strcmp(name, "mitchell") == 0) return CST_FILTER_MITCHELL;
    return CST_FILTER_DEFAULT;
}

const char *cst_filter_name(CstFilter filter)
{
    switch (filter) {
    case CST_FILTER_BOX: return "box";
    case CST_FILTER_TENT: return "tent";
    case CST_FILTER_GAUSSIAN: return "gaussian";
    case CST_FILTER_MITCHELL: return "mitchell";
    case CST_FILTER_DEFAULT: break;
    }
    return "default";
}
