/* Root isolation by derivative cascade: between consecutive roots of p' the polynomial is
 * monotone, so each piece holds at most one root, bracketed by a sign change; the roots of
 * p' come from the same procedure one degree down, down to a linear p (Rolle's theorem; the
 * approach of e.g. Press et al., Numerical Recipes 3rd ed. §9.4 safeguarded Newton, applied
 * to each monotone piece). Deterministic: no iteration depends on anything but c, lo, hi. */
#include "math/polynomial.h"

#include <float.h>
#include <math.h>

double poly_eval(const double *c, int degree, double x)
{
    double v = c[degree];
    for (int k = degree - 1; k >= 0; k--) v = v * x + c[k];
    return v;
}

static double poly_deriv_eval(const double *c, int degree, double x)
{
    double v = degree * c[degree];
    for (int k = degree - 1; k >= 1; k--) v = v * x + k * c[k];
    return v;
}

/* The root of the monotone p in [a, b] where p(a), p(b) have opposite signs: Newton steps,
 * replaced by bisection when they leave the bracket; the bracket shrinks every step. */
static double bracketed_root(const double *c, int degree, double a, double b, double fa)
{
    double x = 0.5 * (a + b);
    for (int it = 0; it < 100; it++) {
        const double f = poly_eval(c, degree, x);
        if (f == 0.0) return x;
        if ((f < 0.0) == (fa < 0.0)) a = x, fa = f;
        else b = x;
        const double df = poly_deriv_eval(c, degree, x);
        double xn = df != 0.0 ? x - f / df : 0.5 * (a + b);
        if (!(xn > a && xn < b)) xn = 0.5 * (a + b);
        if (xn == x || !(b - a > 0.0) || xn <= a || xn >= b) return xn;
        /* converged: the Newton step below a few ulps of the bracket's magnitude */
        if (fabs(xn - x) <= 4.0 * DBL_EPSILON * fmax(fabs(a), fabs(b))) return xn;
        x = xn;
    }
    return x;
}

int poly_roots(const double *c_in, int degree, double lo, double hi, double *roots)
{
    while (degree > 0 && c_in[degree] == 0.0) degree--;
    if (degree <= 0 || !(lo <= hi)) return 0;
    double c[POLY_MAX_DEGREE + 1];
    for (int k = 0; k <= degree; k++) c[k] = c_in[k];
    if (degree == 1) {
        const double x = -c[0] / c[1];
        if (x >= lo && x <= hi) { roots[0] = x; return 1; }
        return 0;
    }
    double dc[POLY_MAX_DEGREE], crit[POLY_MAX_DEGREE + 1];
    for (int k = 1; k <= degree; k++) dc[k - 1] = k * c[k];
    const int nc = poly_roots(dc, degree - 1, lo, hi, crit);
    /* the ends of the monotone pieces: lo, the critical points, hi */
    double ends[POLY_MAX_DEGREE + 2];
    int ne = 0;
    ends[ne++] = lo;
    for (int i = 0; i < nc; i++)
        if (crit[i] > ends[ne - 1]) ends[ne++] = crit[i];
    if (hi > ends[ne - 1]) ends[ne++] = hi;
    int n = 0;
    double fa = poly_eval(c, degree, ends[0]);
    if (fa == 0.0) roots[n++] = ends[0];
    for (int i = 0; i + 1 < ne; i++) {
        const double fb = poly_eval(c, degree, ends[i + 1]);
        if (fb == 0.0) {
            if (n < degree) roots[n++] = ends[i + 1];
        } else if (fa != 0.0 && (fa < 0.0) != (fb < 0.0)) {
            if (n < degree) roots[n++] = bracketed_root(c, degree, ends[i], ends[i + 1], fa);
        }
        fa = fb;
    }
    return n;
}
