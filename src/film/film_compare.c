/* Comparison of two renders: region z-scores from the films' per-pixel means and
 * variances, the Sidak-corrected critical z (with the inverse normal CDF it needs), and
 * the colours of the z map. Pure functions over films; the CLI renders and prints. */
#include "film/film_compare.h"

#include <math.h>
#include <string.h>

#include "core/error.h"

#define COMPARE_SQRT2    1.41421356237309504880
#define COMPARE_SQRT2PI  2.50662827463100050242

/* ------------------------------------------------------------ inverse normal CDF */

/* Phi^-1(p) for p in (0, 0.5]. P. J. Acklam, "An algorithm for computing the inverse normal
 * cumulative distribution function" (2003, https://web.archive.org/web/20151030215612/
 * http://home.online.no/~pjacklam/notes/invnorm/): a rational approximation in the
 * central region and one in sqrt(-2 log p) in the tail, relative error below 1.15e-9.
 * One Halley step on Phi(x) - p = 0 (also from Acklam's note) brings it to about machine
 * precision (measured: under 3e-16 relative against 50-digit values); Phi comes from libm's
 * erfc, which keeps its relative accuracy deep in the lower tail, which is why only the
 * lower half is computed here. */
static double compare_quantile_lower(double p)
{
    static const double a[6] = {-3.969683028665376e+01, 2.209460984245205e+02,
                                -2.759285104469687e+02, 1.383577518672690e+02,
                                -3.066479806614716e+01, 2.506628277459239e+00};
    static const double b[5] = {-5.447609879822406e+01, 1.615858368580409e+02,
                                -1.556989798598866e+02, 6.680131188771972e+01,
                                -1.328068155288572e+01};
    static const double c[6] = {-7.784894002430293e-03, -3.223964580411365e-01,
                                -2.400758277161838e+00, -2.549732539343734e+00,
                                4.374664141464968e+00, 2.938163982698783e+00};
    static const double d[4] = {7.784695709041462e-03, 3.224671290700398e-01,
                                2.445134137142996e+00, 3.754408661907416e+00};
    double x;
    if (p < 0.02425) {
        double q = sqrt(-2.0 * log(p));
        x = (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
            ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
    } else {
        double q = p - 0.5, r = q * q;
        x = (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
            (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
    }
    /* Halley: u = (Phi(x) - p) / phi(x). Near p = 1/2, x is tiny and Phi(x) - p would
     * cancel to an absolute error of an ulp of 1/2, so the residual is taken as
     * erf(x/sqrt 2)/2 - (p - 1/2) there (p - 1/2 is exact for p >= 1/4, Sterbenz). Below
     * p ~ 1e-306 exp(x^2/2) overflows; the raw approximation is then kept (1e-9). */
    double e = p < 0.02425 ? 0.5 * erfc(-x / COMPARE_SQRT2) - p
                           : 0.5 * erf(x / COMPARE_SQRT2) - (p - 0.5);
    double u = e * COMPARE_SQRT2PI * exp(0.5 * x * x);
    if (isfinite(u))
        x -= u / (1.0 + 0.5 * x * u);
    return x;
}

double compare_normal_quantile(double p)
{
    if (isnan(p) || p < 0.0 || p > 1.0) return (double)NAN;
    if (p == 0.0) return -HUGE_VAL;
    if (p == 1.0) return HUGE_VAL;
    /* 1 - p is exact for p in [0.5, 1] (Sterbenz), so the upper half loses nothing by
     * symmetry beyond the rounding already in p. */
    return p <= 0.5 ? compare_quantile_lower(p) : -compare_quantile_lower(1.0 - p);
}

/* ------------------------------------------------------------ multiple testing */

/* Z. Sidak, "Rectangular confidence regions for the means of multivariate normal
 * distributions", JASA 62 (1967) 626-633: for jointly normal statistics, whatever their
 * correlations, P(all |Z_i| <= c_i) >= prod P(|Z_i| <= c_i). So testing each at
 * 1 - (1 - alpha)^(1/m) holds the family-wise error at or below alpha even though the
 * image mean, the blocks inside it, the channels and pairs sharing a render are correlated.
 * expm1/log1p keep alpha_1 accurate when it is ~1e-9 and 1 - alpha_1 would round. */
double compare_sidak_alpha(double alpha, double m)
{
    if (!(alpha > 0.0 && alpha < 1.0) || !(m >= 1.0) || isinf(m)) return (double)NAN;
    return -expm1(log1p(-alpha) / m);
}

double compare_z_critical(double alpha, double m)
{
    double a1 = compare_sidak_alpha(alpha, m);
    if (isnan(a1)) return (double)NAN;
    /* Two-sided: alpha_1 / 2 in each tail; the lower tail quantile avoids 1 - alpha_1/2. */
    return -compare_normal_quantile(0.5 * a1);
}

int compare_blocks_x(int width, int block)
{
    return width > 0 && block > 0 ? width / block + (width % block != 0) : 0;
}

int compare_blocks_y(int height, int block) { return compare_blocks_x(height, block); }

int64_t compare_tests_per_pair(int width, int height, int block)
{
    int64_t blocks = (int64_t)compare_blocks_x(width, block) * compare_blocks_y(height, block);
    return blocks > 0 ? 3 * (1 + blocks) : 0;
}

/* ------------------------------------------------------------ z-scores */

/* z of a region from the sums over its n pixels of the pixel means (s) and of their
 * variances (v): (s_a/n - s_b/n) / (sqrt(v_a + v_b)/n), the n cancels. Zero variance on
 * both sides leaves nothing to divide by: equal sums agree (z = 0), different ones are an
 * outright disagreement (z = +-inf, *outright set). */
static double compare_z(double s_a, double v_a, double s_b, double v_b, bool *outright)
{
    double diff = s_a - s_b, var = v_a + v_b;
    if (var > 0.0) return diff / sqrt(var);
    if (fabs(diff) <= COMPARE_EQUAL_REL * fmax(fabs(s_a), fabs(s_b))) return 0.0;
    *outright = true;
    return diff > 0.0 ? HUGE_VAL : diff < 0.0 ? -HUGE_VAL : (double)NAN;
}

/* Adds the pixel means and variances of [x0,x1) x [y0,y1) of f to s and v. */
static void compare_region_sums(const CstFilm *f, int x0, int y0, int x1, int y1, double s[3],
                                double v[3])
{
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            double m[3], var[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, var);
            for (int c = 0; c < 3; c++) {
                s[c] += m[c];
                v[c] += var[c];
            }
        }
}

CstStatus compare_films(const CstFilm *a, const CstFilm *b, int block, double z_crit,
                        CompareResult *out, double *block_abs_z, CstError *err)
{
    int w = cst_film_width(a), h = cst_film_height(a);
    if (w != cst_film_width(b) || h != cst_film_height(b))
        return cst_fail(err, CST_ERR_INVALID_ARG, "films of different sizes: %dx%d and %dx%d",
                        w, h, cst_film_width(b), cst_film_height(b));
    if (w < 1 || h < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "empty film (%dx%d)", w, h);
    /* With one sample the film reports zero variance: every difference would look like an
     * outright disagreement. */
    if (cst_film_spp(a) < 2 || cst_film_spp(b) < 2)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "comparing films needs at least 2 samples per pixel in each for a "
                        "variance estimate (got %d and %d)", cst_film_spp(a), cst_film_spp(b));
    if (block < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "block size must be >= 1 (got %d)", block);
    if (!(z_crit > 0.0))
        return cst_fail(err, CST_ERR_INVALID_ARG, "critical z must be > 0 (got %g)", z_crit);

    memset(out, 0, sizeof *out);
    int nbx = compare_blocks_x(w, block), nby = compare_blocks_y(h, block);
    double img_s[2][3] = {{0}}, img_v[2][3] = {{0}};
    out->max_abs_block_z = -1.0; /* so the first block is recorded as the worst so far */
    for (int by = 0; by < nby; by++)
        for (int bx = 0; bx < nbx; bx++) {
            int x0 = bx * block, y0 = by * block;
            int x1 = x0 + block < w ? x0 + block : w, y1 = y0 + block < h ? y0 + block : h;
            double s[2][3] = {{0}}, v[2][3] = {{0}};
            compare_region_sums(a, x0, y0, x1, y1, s[0], v[0]);
            compare_region_sums(b, x0, y0, x1, y1, s[1], v[1]);
            double worst = 0.0;
            bool fails = false;
            for (int c = 0; c < 3; c++) {
                bool zero_var = false;
                double z = compare_z(s[0][c], v[0][c], s[1][c], v[1][c], &zero_var);
                out->zero_variance_disagreements += zero_var;
                if (!(fabs(z) <= z_crit)) fails = true;
                double az = isnan(z) ? HUGE_VAL : fabs(z);
                if (az > worst) worst = az;
                if (az > out->max_abs_block_z) {
                    out->max_abs_block_z = az;
                    out->worst_z = z;
                    out->worst_bx = bx;
                    out->worst_by = by;
                    out->worst_channel = c;
                }
                img_s[0][c] += s[0][c]; img_v[0][c] += v[0][c];
                img_s[1][c] += s[1][c]; img_v[1][c] += v[1][c];
            }
            out->blocks_failing += fails;
            if (block_abs_z) block_abs_z[by * nbx + bx] = worst;
        }
    out->blocks = nbx * nby;

    out->pass = out->blocks_failing == 0;
    for (int c = 0; c < 3; c++) {
        bool zero_var = false;
        out->z_mean[c] = compare_z(img_s[0][c], img_v[0][c], img_s[1][c], img_v[1][c], &zero_var);
        out->zero_variance_disagreements += zero_var;
        if (!(fabs(out->z_mean[c]) <= z_crit)) out->pass = false;
    }
    return CST_OK;
}

/* ------------------------------------------------------------ convergence */

CstStatus compare_convergence_level(const CstFilm *ref, const CstFilm *x1, const CstFilm *x2, int block,
                                    double *terms, ConvergenceLevel *out, CstError *err)
{
    int w = cst_film_width(ref), h = cst_film_height(ref);
    if (w != cst_film_width(x1) || h != cst_film_height(x1) || w != cst_film_width(x2) ||
        h != cst_film_height(x2))
        return cst_fail(err, CST_ERR_INVALID_ARG, "films of different sizes: %dx%d, %dx%d and %dx%d", w, h,
                        cst_film_width(x1), cst_film_height(x1), cst_film_width(x2), cst_film_height(x2));
    if (cst_film_spp(ref) < 2)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "the reference needs at least 2 samples per pixel for a variance estimate (got %d)",
                        cst_film_spp(ref));
    if (block < 1) return cst_fail(err, CST_ERR_INVALID_ARG, "block size must be >= 1 (got %d)", block);
    int nbx = compare_blocks_x(w, block), nby = compare_blocks_y(h, block);
    if (nbx * nby < 2)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "a convergence check needs at least 2 blocks for a standard error (%dx%d "
                        "image, block %d)", w, h, block);
    memset(out, 0, sizeof *out);
    out->blocks = nbx * nby;
    /* image sums of (x1 + x2)/2 and of r, and the variances of those sums */
    double sum = 0.0, img[3][2] = {{0}}, img_var[3][2] = {{0}};
    for (int by = 0; by < nby; by++)
        for (int bx = 0; bx < nbx; bx++) {
            int x0 = bx * block, y0 = by * block;
            int xe = x0 + block < w ? x0 + block : w, ye = y0 + block < h ? y0 + block : h;
            double n = (double)(xe - x0) * (double)(ye - y0);
            double s1[3] = {0}, s2[3] = {0}, v1[3] = {0}, sr[3] = {0}, vr[3] = {0};
            /* The films' per-pixel variances of X are not used (see the header). */
            compare_region_sums(x1, x0, y0, xe, ye, s1, v1);
            compare_region_sums(x2, x0, y0, xe, ye, s2, v1);
            compare_region_sums(ref, x0, y0, xe, ye, sr, vr);
            double t = 0.0;
            for (int c = 0; c < 3; c++) {
                double m1 = s1[c] / n, m2 = s2[c] / n, mr = sr[c] / n;
                double d = 0.5 * (m1 + m2) - mr, half = 0.5 * (m1 - m2);
                t += d * d - half * half - vr[c] / (n * n);
                img[c][0] += 0.5 * (s1[c] + s2[c]);
                img[c][1] += sr[c];
                img_var[c][0] += n * n * half * half; /* the block sum's variance */
                img_var[c][1] += vr[c];
            }
            terms[by * nbx + bx] = t;
            sum += t;
        }
    out->d2 = sum / out->blocks;
    double ss = 0.0;
    for (int b = 0; b < out->blocks; b++) ss += (terms[b] - out->d2) * (terms[b] - out->d2);
    out->d2_se = sqrt(ss / (out->blocks - 1) / out->blocks);
    for (int c = 0; c < 3; c++) {
        out->mean_diff[c] = (img[c][0] - img[c][1]) / ((double)w * (double)h);
        bool outright = false;
        out->mean_z[c] = compare_z(img[c][0], img_var[c][0], img[c][1], img_var[c][1], &outright);
    }
    return CST_OK;
}

void compare_convergence_step(const double *terms_a, const double *terms_b, int blocks, double *diff,
                              double *se)
{
    double sum = 0.0, ss = 0.0;
    for (int b = 0; b < blocks; b++) sum += terms_a[b] - terms_b[b];
    double mean = blocks > 0 ? sum / blocks : (double)NAN;
    for (int b = 0; b < blocks; b++) {
        double e = terms_a[b] - terms_b[b] - mean;
        ss += e * e;
    }
    *diff = mean;
    *se = blocks >= 2 ? sqrt(ss / (blocks - 1) / blocks) : (double)NAN;
}

ConvergenceVerdict compare_convergence_judge(const ConvergenceLevel *lv, const double *step_diff,
                                             const double *step_se, int levels, double z, double z_mean)
{
    if (levels < 2 || !(z > 0.0) || !(z_mean > 0.0)) return CONVERGENCE_FAILS;
    const ConvergenceLevel *last = &lv[levels - 1];
    /* D alone misses a bias spread evenly over many blocks when the blocks differ much
     * (se comes from their spread); the image mean sees it at once. */
    bool within = last->d2 <= z * last->d2_se;
    for (int c = 0; c < 3; c++) within &= fabs(last->mean_z[c]) <= z_mean;
    if (within) return CONVERGENCE_WITHIN_NOISE;
    for (int k = 0; k + 1 < levels; k++)
        if (!(step_diff[k] > z * step_se[k])) return CONVERGENCE_FAILS;
    return CONVERGENCE_SHRINKS;
}

/* ------------------------------------------------------------ the map */

/* sRGB EOTF (IEC 61966-2-1): the map's colours are designed as display values and
 * image_write encodes linear values, so they are decoded here first. */
static float compare_srgb_to_linear(double s)
{
    return (float)(s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4));
}

void compare_map_colour(double abs_z, double z_crit, float rgb[3])
{
    double t = abs_z / z_crit, srgb[3];
    if (!(t <= 1.0)) {                      /* fails (or NaN): red */
        srgb[0] = 1.0; srgb[1] = 0.0; srgb[2] = 0.0;
    } else if (t <= 0.5) {                  /* well inside: black to blue */
        srgb[0] = 0.0; srgb[1] = 0.0; srgb[2] = t > 0.0 ? 2.0 * t : 0.0;
    } else {                                /* approaching z_crit: blue to yellow */
        double s = 2.0 * (t - 0.5);
        srgb[0] = s; srgb[1] = s; srgb[2] = 1.0 - s;
    }
    for (int c = 0; c < 3; c++) rgb[c] = compare_srgb_to_linear(srgb[c]);
}

void compare_map_image(const double *block_abs_z, int width, int height, int block,
                       double z_crit, float *rgb)
{
    int nbx = compare_blocks_x(width, block);
    for (int y = 0; y < height; y++)
        for (int x = 0; x < width; x++)
            compare_map_colour(block_abs_z[(y / block) * nbx + x / block], z_crit,
                               &rgb[3 * ((size_t)y * (size_t)width + (size_t)x)]);
}

/* ------------------------------------------------------------ images */

/* Sums over [x0,x1) x [y0,y1) of the values of a and b and of their variances (0 where
 * none is given), per channel, over the values finite in both images (and variances). */
static void compare_image_region(const float *a, const float *b, const float *va, const float *vb, int w,
                                 int x0, int y0, int x1, int y1, double s[2][3], double v[2][3], double n[3])
{
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            size_t i = 3 * ((size_t)y * (size_t)w + (size_t)x);
            for (int c = 0; c < 3; c++) {
                double pa = (double)a[i + (size_t)c], pb = (double)b[i + (size_t)c];
                double qa = va ? (double)va[i + (size_t)c] : 0.0, qb = vb ? (double)vb[i + (size_t)c] : 0.0;
                if (!isfinite(pa) || !isfinite(pb) || !isfinite(qa) || !isfinite(qb)) continue;
                s[0][c] += pa;
                s[1][c] += pb;
                v[0][c] += qa;
                v[1][c] += qb;
                n[c] += 1.0;
            }
        }
}

/* The z test of the region sums: the block mean difference over its standard error,
 * (s_a - s_b)/n / (sqrt(v_a + v_b)/n); the n cancel (compare_z). No values: z = 0. */
static double compare_image_z(const double s[2][3], const double v[2][3], const double n[3], int c)
{
    bool outright = false;
    return n[c] > 0.0 ? compare_z(s[0][c], v[0][c], s[1][c], v[1][c], &outright) : 0.0;
}

CstStatus compare_images(const float *a, const float *b, int w, int h, const float *var_a, const float *var_b,
                         int block, ImageComparison *out, double *block_abs_z, CstError *err)
{
    if (w < 1 || h < 1) return cst_fail(err, CST_ERR_INVALID_ARG, "empty image (%dx%d)", w, h);
    if (block < 1) return cst_fail(err, CST_ERR_INVALID_ARG, "block size must be >= 1 (got %d)", block);
    memset(out, 0, sizeof *out);
    /* Means, RMSE and relMSE: one pass, sums in double (an image of 2^28 pixels of values
     * ~1 keeps ~8 significant digits). */
    double sum[2][3] = {{0}}, se[3] = {0}, rel[3] = {0}, cnt[3] = {0};
    size_t n = (size_t)w * (size_t)h;
    for (size_t i = 0; i < n; i++)
        for (int c = 0; c < 3; c++) {
            double pa = (double)a[3 * i + (size_t)c], pb = (double)b[3 * i + (size_t)c];
            if (!isfinite(pa) || !isfinite(pb)) {
                out->nonfinite++;
                continue;
            }
            double d = pa - pb;
            sum[0][c] += pa;
            sum[1][c] += pb;
            se[c] += d * d;
            rel[c] += d * d / (pb * pb + CST_RELMSE_EPS);
            cnt[c] += 1.0;
        }
    double se_all = 0.0, rel_all = 0.0, cnt_all = 0.0;
    for (int c = 0; c < 3; c++) {
        double k = cnt[c] > 0.0 ? cnt[c] : (double)NAN;
        out->mean_a[c] = sum[0][c] / k;
        out->mean_b[c] = sum[1][c] / k;
        out->diff[c] = out->mean_a[c] - out->mean_b[c];
        out->rel_diff[c] = out->mean_b[c] != 0.0 ? out->diff[c] / fabs(out->mean_b[c]) : (double)NAN;
        out->rmse[c] = sqrt(se[c] / k);
        out->relmse[c] = rel[c] / k;
        se_all += se[c];
        rel_all += rel[c];
        cnt_all += cnt[c];
    }
    out->rmse_all = cnt_all > 0.0 ? sqrt(se_all / cnt_all) : (double)NAN;
    out->relmse_all = cnt_all > 0.0 ? rel_all / cnt_all : (double)NAN;
    if (!var_a && !var_b) return CST_OK;

    /* z-scores: the variances are those of the pixel values (the variance AOV: of each
     * pixel mean), pixels independent, so a block mean's variance is the sum over n^2. */
    out->has_z = 1;
    int nbx = compare_blocks_x(w, block), nby = compare_blocks_y(h, block);
    double img_s[2][3] = {{0}}, img_v[2][3] = {{0}}, img_n[3] = {0};
    out->max_abs_z = -1.0;
    for (int by = 0; by < nby; by++)
        for (int bx = 0; bx < nbx; bx++) {
            int x0 = bx * block, y0 = by * block;
            int x1 = x0 + block < w ? x0 + block : w, y1 = y0 + block < h ? y0 + block : h;
            double s[2][3] = {{0}}, v[2][3] = {{0}}, cn[3] = {0}, worst = 0.0;
            compare_image_region(a, b, var_a, var_b, w, x0, y0, x1, y1, s, v, cn);
            for (int c = 0; c < 3; c++) {
                double z = compare_image_z(s, v, cn, c);
                double az = isnan(z) ? HUGE_VAL : fabs(z);
                out->above += az > CST_COMPARE_Z_OUTLIER;
                if (az > worst) worst = az;
                if (az > out->max_abs_z) {
                    out->max_abs_z = az;
                    out->worst_z = z;
                    out->worst_bx = bx;
                    out->worst_by = by;
                    out->worst_channel = c;
                }
                for (int k = 0; k < 2; k++) {
                    img_s[k][c] += s[k][c];
                    img_v[k][c] += v[k][c];
                }
                img_n[c] += cn[c];
            }
            if (block_abs_z) block_abs_z[by * nbx + bx] = worst;
        }
    out->blocks = nbx * nby;
    out->frac_above = (double)out->above / (3.0 * out->blocks);
    for (int c = 0; c < 3; c++) out->z_mean[c] = compare_image_z(img_s, img_v, img_n, c);
    return CST_OK;
}

/* ------------------------------------------------------------ public names */

double cst_compare_normal_quantile(double p) { return compare_normal_quantile(p); }
double cst_compare_sidak_alpha(double alpha, double m) { return compare_sidak_alpha(alpha, m); }
double cst_compare_z_critical(double alpha, double m) { return compare_z_critical(alpha, m); }
int cst_compare_blocks_x(int width, int block) { return compare_blocks_x(width, block); }
int cst_compare_blocks_y(int height, int block) { return compare_blocks_y(height, block); }
int64_t cst_compare_tests_per_pair(int width, int height, int block)
{
    return compare_tests_per_pair(width, height, block);
}

CstStatus cst_film_compare(const CstFilm *a, const CstFilm *b, int block, double z_crit,
                           CstFilmComparison *out, double *block_abs_z, CstError *err)
{
    return compare_films(a, b, block, z_crit, out, block_abs_z, err);
}

CstStatus cst_compare_convergence_level(const CstFilm *ref, const CstFilm *x1, const CstFilm *x2, int block,
                                        double *terms, CstConvergenceLevel *out, CstError *err)
{
    return compare_convergence_level(ref, x1, x2, block, terms, out, err);
}

void cst_compare_convergence_step(const double *terms_a, const double *terms_b, int blocks, double *diff,
                                  double *se)
{
    compare_convergence_step(terms_a, terms_b, blocks, diff, se);
}

CstConvergenceVerdict cst_compare_convergence_judge(const CstConvergenceLevel *lv, const double *step_diff,
                                                    const double *step_se, int levels, double z, double z_mean)
{
    return compare_convergence_judge(lv, step_diff, step_se, levels, z, z_mean);
}

void cst_compare_map_image(const double *block_abs_z, int width, int height, int block, double z_crit,
                           float *rgb)
{
    compare_map_image(block_abs_z, width, height, block, z_crit, rgb);
}

CstStatus cst_image_compare(const float *a, const float *b, int width, int height, const float *var_a,
                            const float *var_b, int block, CstImageComparison *out, double *block_abs_z,
                            CstError *err)
{
    return compare_images(a, b, width, height, var_a, var_b, block, out, block_abs_z, err);
}
