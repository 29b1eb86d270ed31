/* Real roots of polynomials of degree at most 4 in an interval, in double: isolated by the
 * roots of the derivatives, each refined by Newton's method kept inside its bracket. */
#ifndef CST_MATH_POLYNOMIAL_H
#define CST_MATH_POLYNOMIAL_H

enum { POLY_MAX_DEGREE = 4 };

/* p(x) = c[0] + c[1] x + ... + c[degree] x^degree (degree <= POLY_MAX_DEGREE; leading zero
 * coefficients lower it). Writes the roots in [lo, hi] to roots[] in increasing order and
 * returns their number (at most degree). Only roots where p changes sign, or is exactly 0
 * at an end of a monotone piece, are found: a double root where p touches 0 without
 * crossing (a ray grazing a surface) may be missed. */
int poly_roots(const double *c, int degree, double lo, double hi, double *roots);

/* p(x) by Horner's rule. */
double poly_eval(const double *c, int degree, double x);

#endif
