/* Statistical comparison of renders of one scene, for `caustic verify`: z-scores of the
 * difference of the image means and of the block means, per channel, judged at a
 * family-wise significance with the Sidak correction; the false-colour map of them; and the
 * convergence check of consistent but biased integrators against an unbiased reference. */
#ifndef CST_FILM_FILM_COMPARE_H
#define CST_FILM_FILM_COMPARE_H

#include <stdbool.h>
#include <stdint.h>

#include "caustic/caustic.h"

/* Two deterministic region sums (zero variance in both films) closer than this, relative
 * to the larger, count as equal: integrators may compute the same deterministic radiance
 * with float operations in a different order, a few float ulps (~1e-7) apart. */
#define COMPARE_EQUAL_REL 1e-5

/* Inverse of the standard normal CDF: the x with Phi(x) = p. -INFINITY at p = 0, INFINITY
 * at p = 1, NaN outside [0, 1]. Relative error under 3e-16 (see film_compare.c). */
double compare_normal_quantile(double p);

/* Per-test significance of m tests with family-wise significance alpha (Sidak):
 * 1 - (1 - alpha)^(1/m). alpha in (0, 1), m >= 1; NaN otherwise. */
double compare_sidak_alpha(double alpha, double m);

/* The two-sided critical |z| of one test among m at family-wise significance alpha: the
 * standard normal quantile at 1 - alpha_1/2, alpha_1 = compare_sidak_alpha(alpha, m).
 * NaN for invalid arguments. */
double compare_z_critical(double alpha, double m);

/* Non-overlapping block x block cells covering a width x height image; the last column
 * and row hold partial blocks. 0 for invalid arguments. */
int compare_blocks_x(int width, int block);
int compare_blocks_y(int height, int block);

/* Tests one pair of films contributes: 3 channels x (the image mean + every block). */
int64_t compare_tests_per_pair(int width, int height, int block);

/* The public CstFilmComparison (caustic.h documents its fields). */
typedef CstFilmComparison CompareResult;

/* Compares films a and b (same size, at least 2 samples per pixel each: the variance of a
 * pixel mean is estimated from its samples) over block x block blocks, failing tests with
 * |z| > z_crit. Pixel means are independent (each pixel has its own random streams), so the
 * variance of a region's mean is the sum of its pixels' variances over n^2. If block_abs_z
 * is not NULL it receives, per block (row-major, compare_blocks_x * compare_blocks_y
 * entries), the largest |z| over the channels. Returns CST_ERR_INVALID_ARG for films of
 * different sizes, fewer than 2 spp, block < 1 or z_crit not > 0; never allocates. */
CstStatus compare_films(const CstFilm *a, const CstFilm *b, int block, double z_crit,
                        CompareResult *out, double *block_abs_z, CstError *err);

/* ------------------------------------------------------------ convergence */

/* One level of the convergence check of a consistent but biased integrator X (photon
 * mapping, SPPM): two independent renders x1, x2 of X at the same work, against a render r
 * of an unbiased reference with per-pixel variances. Per block b and channel c, with block
 * means,
 *   d = (x1 + x2) / 2 - r,   s2 = (x1 - x2)^2 / 4 + var(r),
 *   t_b = sum_c (d^2 - s2).
 * (x1 - x2)^2 / 4 estimates the variance of (x1 + x2) / 2 without bias whatever X's
 * correlations between pixels (the photons are shared by the whole image, so X's per-pixel
 * variances, when it has any, understate it; the two renders are independent), so t_b
 * estimates the block's squared bias, summed over channels, without bias. */
/* The public CstConvergenceLevel (caustic.h documents its fields). */
typedef CstConvergenceLevel ConvergenceLevel;

/* Fills *out and terms[b] = t_b (compare_blocks_x * compare_blocks_y entries, row-major).
 * CST_ERR_INVALID_ARG for films of different sizes, a reference with fewer than 2 spp,
 * block < 1 or fewer than 2 blocks (no spread to estimate the standard error from). */
CstStatus compare_convergence_level(const CstFilm *ref, const CstFilm *x1, const CstFilm *x2, int block,
                                    double *terms, ConvergenceLevel *out, CstError *err);

/* The paired difference D_a - D_b of two levels over the same blocks (terms from
 * compare_convergence_level) and its standard error, from the spread of the per-block
 * differences: the reference render is shared by the levels, so D_a and D_b are correlated
 * and their own standard errors cannot be combined in quadrature. se is NaN for blocks < 2. */
void compare_convergence_step(const double *terms_a, const double *terms_b, int blocks, double *diff,
                              double *se);

/* The public CstConvergenceVerdict under the module's own names. */
typedef CstConvergenceVerdict ConvergenceVerdict;
#define CONVERGENCE_WITHIN_NOISE CST_CONVERGENCE_WITHIN_NOISE
#define CONVERGENCE_SHRINKS CST_CONVERGENCE_SHRINKS
#define CONVERGENCE_FAILS CST_CONVERGENCE_FAILS

/* The rule of `caustic verify` for `levels` >= 2 levels of growing work (step k compares
 * level k with k + 1, step_diff[k] = D_k - D_k+1): within noise if at the last level
 * D <= z * se and every |mean_z| <= z_mean; else shrinks if step_diff[k] > z * step_se[k]
 * for every step; else fails. z is a one-sided critical value, z_mean a two-sided one; NaN
 * anywhere counts against the integrator. */
ConvergenceVerdict compare_convergence_judge(const ConvergenceLevel *lv, const double *step_diff,
                                             const double *step_se, int levels, double z, double z_mean);

/* The map colour of a block's |z|, as linear RGB (for image_write, which encodes PNG as
 * sRGB): black at 0 ramping to blue at z_crit/2, blue ramping to yellow at z_crit (both
 * ramps linear in sRGB), red above z_crit (and for NaN). */
void compare_map_colour(double abs_z, double z_crit, float rgb[3]);

/* Fills rgb (width * height * 3 linear floats, row 0 = top) with every pixel's block colour:
 * the map at the image's size, one flat cell per block. */
void compare_map_image(const double *block_abs_z, int width, int height, int block,
                       double z_crit, float *rgb);

/* ------------------------------------------------------------ images */

/* The public CstImageComparison (caustic.h documents its fields). */
typedef CstImageComparison ImageComparison;

/* `caustic compare`: a against the reference b (w x h x 3 linear floats): means, RMSE and
 * relMSE (epsilon CST_RELMSE_EPS) per channel over the values finite in both; with
 * variances of the pixel values (var_a and/or var_b; NULL counts as zero), the z-score of
 * the image mean and of every block x block block mean per channel, the same statistic as
 * compare_films but from variance images instead of films. Allocates nothing. */
CstStatus compare_images(const float *a, const float *b, int w, int h, const float *var_a, const float *var_b,
                         int block, ImageComparison *out, double *block_abs_z, CstError *err);

#endif
