/* FLIP and HDR-FLIP, implemented from the papers (Andersson et al., HPG 2020 and EG 2021):
 * the colour pipeline (contrast sensitivity filters in YyCxCz, then Hunt-adjusted L*a*b* and
 * the HyAB distance), the feature pipeline (edge and point detectors on luminance), and the
 * exposure bracket of HDR-FLIP. Every filter is separable and is applied as two 1D passes. */
#include "film/flip.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

#define FLIP_PI 3.14159265358979323846

/* ------------------------------------------------------------ colour spaces */

/* Linear sRGB to CIE XYZ (IEC 61966-2-1 primaries, D65 white), as exact rationals so that
 * RGB (1, 1, 1) maps to the white point to the last bit; the papers use the same matrix. */
static const double FLIP_RGB2XYZ[3][3] = {
    {10135552.0 / 24577794.0, 8788810.0 / 24577794.0, 4435075.0 / 24577794.0},
    {2613072.0 / 12288897.0, 8788810.0 / 12288897.0, 887015.0 / 12288897.0},
    {1425312.0 / 73733382.0, 8788810.0 / 73733382.0, 70074185.0 / 73733382.0},
};

/* The constants every conversion needs, computed once per call: the inverse matrix, the
 * white point (XYZ of RGB white: the matrix's row sums), and c_max of the colour metric. */
typedef struct FlipSpace {
    double xyz2rgb[3][3];
    double white[3];
    double cmax; /* HyAB(green, blue)^q_c in Hunt-adjusted L*a*b*: the largest colour error */
} FlipSpace;

static void flip_mat_apply(const double m[3][3], const double in[3], double out[3])
{
    for (int i = 0; i < 3; i++) out[i] = m[i][0] * in[0] + m[i][1] * in[1] + m[i][2] * in[2];
}

/* CIE L*a*b* of linear RGB (CIE 15:2004 with delta = 6/29), then the Hunt adjustment of
 * the FLIP paper (colour pipeline): a and b scaled by 0.01 L, since chroma is seen less at low
 * luminance. */
static void flip_rgb_to_hunt_lab(const FlipSpace *s, const double rgb[3], double lab[3])
{
    const double delta = 6.0 / 29.0, d3 = delta * delta * delta, k = 1.0 / (3.0 * delta * delta);
    double xyz[3], f[3];
    flip_mat_apply(FLIP_RGB2XYZ, rgb, xyz);
    for (int c = 0; c < 3; c++) {
        double t = xyz[c] / s->white[c];
        f[c] = t > d3 ? cbrt(t) : k * t + 4.0 / 29.0;
    }
    double l = 116.0 * f[1] - 16.0;
    lab[0] = l;
    lab[1] = 0.01 * l * 500.0 * (f[0] - f[1]);
    lab[2] = 0.01 * l * 200.0 * (f[1] - f[2]);
}

/* HyAB (Abasi et al. 2020): |dL| + the Euclidean distance in the a-b plane. */
static double flip_hyab(const double p[3], const double q[3])
{
    return fabs(p[0] - q[0]) + hypot(p[1] - q[1], p[2] - q[2]);
}

static void flip_space_init(FlipSpace *s)
{
    const double (*m)[3] = FLIP_RGB2XYZ;
    for (int i = 0; i < 3; i++) s->white[i] = m[i][0] + m[i][1] + m[i][2];
    /* inverse by cofactors (the matrix is well conditioned) */
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                 m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            s->xyz2rgb[i][j] = (m[r0][c0] * m[r1][c1] - m[r0][c1] * m[r1][c0]) / det;
        }
    double green[3] = {0.0, 1.0, 0.0}, blue[3] = {0.0, 0.0, 1.0}, lg[3], lb[3];
    flip_rgb_to_hunt_lab(s, green, lg);
    flip_rgb_to_hunt_lab(s, blue, lb);
    s->cmax = pow(flip_hyab(lg, lb), 0.7);
}

/* ------------------------------------------------------------ separable filtering */

/* One 1D pass along rows (dx = 1) or columns (dx = 0) of a w x h plane with a kernel of
 * 2r + 1 taps, the border replicated (the reference implementation's choice). */
static void flip_pass(const float *src, float *dst, int w, int h, const double *k, int r, int along_rows)
{
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double acc = 0.0;
            for (int t = -r; t <= r; t++) {
                int xx = x, yy = y;
                if (along_rows) xx = x + t < 0 ? 0 : x + t >= w ? w - 1 : x + t;
                else yy = y + t < 0 ? 0 : y + t >= h ? h - 1 : y + t;
                acc += k[t + r] * (double)src[(size_t)yy * (size_t)w + (size_t)xx];
            }
            dst[(size_t)y * (size_t)w + (size_t)x] = (float)acc;
        }
}

/* dst = src filtered by kx(x) ky(y); tmp holds the intermediate. */
static void flip_filter2(const float *src, float *dst, float *tmp, int w, int h, const double *kx,
                         const double *ky, int r)
{
    flip_pass(src, tmp, w, h, kx, r, 1);
    flip_pass(tmp, dst, w, h, ky, r, 0);
}

/* ------------------------------------------------------------ the kernels */

/* The paper's contrast sensitivity functions (FLIP paper, colour pipeline; the parameters of its table) are
 * sums of Gaussians in visual degrees, S(x) = sum_i a_i sqrt(pi / b_i) exp(-pi^2 x^2 / b_i),
 * normalised to sum 1 over the kernel: achromatic a1 = 1, b1 = 0.0047; red-green a1 = 1,
 * b1 = 0.0053; blue-yellow a1 = 34.1, b1 = 0.04, a2 = 13.5, b2 = 0.025. The radius covers
 * 3 standard deviations of the widest (b = 0.04). A 2D Gaussian is the product of two 1D
 * ones, so each term is one normalised 1D kernel g_i and a weight w_i (its share of the 2D
 * sum). */
typedef struct FlipCsf {
    int r;
    double *g[4];  /* normalised 1D kernels: A, RG, BY term 1, BY term 2 */
    double w_by[2]; /* the blue-yellow terms' weights, summing to 1 */
} FlipCsf;

typedef struct FlipFeature {
    int r;
    double *gauss, *edge, *point; /* normalised 1D kernels */
} FlipFeature;

static double flip_gauss_1d(double *k, int r, double ppd, double b)
{
    double sum = 0.0;
    for (int i = -r; i <= r; i++) {
        double x = i / ppd; /* degrees */
        k[i + r] = exp(-FLIP_PI * FLIP_PI * x * x / b);
        sum += k[i + r];
    }
    for (int i = 0; i <= 2 * r; i++) k[i] /= sum;
    return sum;
}

/* k normalised so that its positive taps sum to 1 and its negative ones to -1 (FLIP paper,
 * feature pipeline: the detectors respond alike to every contrast polarity). */
static void flip_balance(double *k, int n)
{
    double pos = 0.0, neg = 0.0;
    for (int i = 0; i < n; i++) {
        if (k[i] > 0.0) pos += k[i];
        else neg -= k[i];
    }
    for (int i = 0; i < n; i++) k[i] /= k[i] > 0.0 ? pos : neg > 0.0 ? neg : 1.0;
}

static double *flip_kernels_alloc(int r, int count)
{
    return malloc((size_t)count * (size_t)(2 * r + 1) * sizeof(double));
}

static double *flip_csf_init(FlipCsf *c, double ppd)
{
    c->r = (int)ceil(3.0 * sqrt(0.04 / (2.0 * FLIP_PI * FLIP_PI)) * ppd);
    int n = 2 * c->r + 1;
    double *mem = flip_kernels_alloc(c->r, 4);
    if (!mem) return NULL;
    for (int i = 0; i < 4; i++) c->g[i] = mem + (size_t)i * (size_t)n;
    flip_gauss_1d(c->g[0], c->r, ppd, 0.0047);
    flip_gauss_1d(c->g[1], c->r, ppd, 0.0053);
    double s1 = flip_gauss_1d(c->g[2], c->r, ppd, 0.04), s2 = flip_gauss_1d(c->g[3], c->r, ppd, 0.025);
    /* 2D sums of the two terms before normalisation: a sqrt(pi/b) (sum of the 1D kernel)^2 */
    double t1 = 34.1 * sqrt(FLIP_PI / 0.04) * s1 * s1, t2 = 13.5 * sqrt(FLIP_PI / 0.025) * s2 * s2;
    c->w_by[0] = t1 / (t1 + t2);
    c->w_by[1] = t2 / (t1 + t2);
    return mem;
}

/* The edge and point detectors (FLIP paper, feature pipeline): the first and second x-derivatives of a
 * Gaussian of standard deviation 0.5 w ppd, w = 0.082 degrees (peak to trough of the
 * human edge detector), radius 3 sd; both factor as (1D derivative kernel)(1D Gaussian). */
static double *flip_feature_init(FlipFeature *f, double ppd)
{
    double sd = 0.5 * 0.082 * ppd;
    f->r = (int)ceil(3.0 * sd);
    int n = 2 * f->r + 1;
    double *mem = flip_kernels_alloc(f->r, 3);
    if (!mem) return NULL;
    f->gauss = mem;
    f->edge = mem + n;
    f->point = mem + 2 * n;
    double sum = 0.0;
    for (int i = -f->r; i <= f->r; i++) {
        double g = exp(-(double)i * i / (2.0 * sd * sd));
        f->gauss[i + f->r] = g;
        f->edge[i + f->r] = -i * g;
        f->point[i + f->r] = ((double)i * i / (sd * sd) - 1.0) * g;
        sum += g;
    }
    for (int i = 0; i < n; i++) f->gauss[i] /= sum;
    /* Balancing the 1D factor balances the 2D kernel: the Gaussian factor is positive. */
    flip_balance(f->edge, n);
    flip_balance(f->point, n);
    return mem;
}

/* ------------------------------------------------------------ LDR-FLIP */

/* Per image: YyCxCz planes of the clamped linear input (the FLIP paper's opponent space, relative to the white point),
 * and the luminance plane y / y_white the feature pipeline reads. */
static void flip_to_ycxcz(const FlipSpace *s, const float *rgb, size_t n, float *planes, float *lum)
{
    for (size_t i = 0; i < n; i++) {
        double v[3], xyz[3];
        for (int c = 0; c < 3; c++) v[c] = fmin(fmax((double)rgb[3 * i + (size_t)c], 0.0), 1.0);
        flip_mat_apply(FLIP_RGB2XYZ, v, xyz);
        for (int c = 0; c < 3; c++) xyz[c] /= s->white[c];
        planes[i] = (float)(116.0 * xyz[1] - 16.0);
        planes[n + i] = (float)(500.0 * (xyz[0] - xyz[1]));
        planes[2 * n + i] = (float)(200.0 * (xyz[1] - xyz[2]));
        lum[i] = (float)xyz[1];
    }
}

/* The CSF-filtered image (planes replaced), tmp and tmp2: n floats each. */
static void flip_csf_filter(const FlipCsf *c, float *planes, float *tmp, float *tmp2, int w, int h)
{
    size_t n = (size_t)w * (size_t)h;
    flip_filter2(planes, tmp2, tmp, w, h, c->g[0], c->g[0], c->r);
    memcpy(planes, tmp2, n * sizeof *planes);
    flip_filter2(planes + n, tmp2, tmp, w, h, c->g[1], c->g[1], c->r);
    memcpy(planes + n, tmp2, n * sizeof *planes);
    float *by = planes + 2 * n;
    flip_filter2(by, tmp2, tmp, w, h, c->g[2], c->g[2], c->r);
    for (size_t i = 0; i < n; i++) tmp2[i] = (float)(c->w_by[0] * (double)tmp2[i]);
    /* second term into tmp via by itself: tmp2 keeps the first term's share */
    float *second = tmp;
    flip_pass(by, second, w, h, c->g[3], c->r, 1);
    flip_pass(second, by, w, h, c->g[3], c->r, 0);
    for (size_t i = 0; i < n; i++) by[i] = (float)((double)tmp2[i] + c->w_by[1] * (double)by[i]);
}

/* Hunt-adjusted L*a*b* of the filtered YyCxCz, after clamping to the RGB cube in linear
 * RGB (FLIP paper: the filtered colour may leave the gamut). In place. */
static void flip_filtered_to_lab(const FlipSpace *s, float *planes, size_t n)
{
    for (size_t i = 0; i < n; i++) {
        double yy = ((double)planes[i] + 16.0) / 116.0;
        double xyz[3] = {(yy + (double)planes[n + i] / 500.0) * s->white[0], yy * s->white[1],
                         (yy - (double)planes[2 * n + i] / 200.0) * s->white[2]};
        double rgb[3], lab[3];
        flip_mat_apply(s->xyz2rgb, xyz, rgb);
        for (int c = 0; c < 3; c++) rgb[c] = fmin(fmax(rgb[c], 0.0), 1.0);
        flip_rgb_to_hunt_lab(s, rgb, lab);
        for (int c = 0; c < 3; c++) planes[(size_t)c * n + i] = (float)lab[c];
    }
}

/* Edge and point magnitudes of a luminance plane into edge[] and point[]. */
static void flip_features(const FlipFeature *f, const float *lum, float *edge, float *point, float *tmp,
                          float *tmp2, int w, int h)
{
    size_t n = (size_t)w * (size_t)h;
    flip_filter2(lum, tmp2, tmp, w, h, f->edge, f->gauss, f->r);  /* d/dx */
    flip_filter2(lum, edge, tmp, w, h, f->gauss, f->edge, f->r);  /* d/dy */
    for (size_t i = 0; i < n; i++) edge[i] = (float)hypot((double)tmp2[i], (double)edge[i]);
    flip_filter2(lum, tmp2, tmp, w, h, f->point, f->gauss, f->r);
    flip_filter2(lum, point, tmp, w, h, f->gauss, f->point, f->r);
    for (size_t i = 0; i < n; i++) point[i] = (float)hypot((double)tmp2[i], (double)point[i]);
}

CstStatus flip_ldr(const float *reference, const float *test, int w, int h, double ppd, float *err,
                   CstError *error)
{
    if (w < 1 || h < 1 || !(ppd > 0.0) || !isfinite(ppd))
        return cst_fail(error, CST_ERR_INVALID_ARG, "FLIP: invalid image size %dx%d or pixels per degree %g",
                        w, h, ppd);
    size_t n = (size_t)w * (size_t)h;
    FlipSpace s;
    flip_space_init(&s);
    FlipCsf csf = {0};
    FlipFeature feat = {0};
    double *kc = flip_csf_init(&csf, ppd), *kf = flip_feature_init(&feat, ppd);
    /* per image: 3 colour planes, luminance, edges, points; plus two scratch planes */
    float *mem = malloc(14 * n * sizeof *mem);
    if (!kc || !kf || !mem) {
        free(kc);
        free(kf);
        free(mem);
        return cst_fail(error, CST_ERR_OOM, "FLIP: out of memory for a %dx%d image", w, h);
    }
    float *col[2] = {mem, mem + 3 * n}, *lum[2] = {mem + 6 * n, mem + 7 * n};
    float *edge[2] = {mem + 8 * n, mem + 9 * n}, *point[2] = {mem + 10 * n, mem + 11 * n};
    float *tmp = mem + 12 * n, *tmp2 = mem + 13 * n;
    const float *in[2] = {reference, test};
    for (int k = 0; k < 2; k++) {
        flip_to_ycxcz(&s, in[k], n, col[k], lum[k]);
        flip_csf_filter(&csf, col[k], tmp, tmp2, w, h);
        flip_filtered_to_lab(&s, col[k], n);
        flip_features(&feat, lum[k], edge[k], point[k], tmp, tmp2, w, h);
    }
    /* Colour error: HyAB^q_c, q_c = 0.7, mapped as in the FLIP paper so that errors up to
     * p_c c_max (p_c = 0.4) take [0, p_t] (p_t = 0.95) and the rest (p_t, 1]. Feature
     * error: the larger difference of edge or point magnitudes over sqrt 2, to the power
     * q_f = 0.5. FLIP = colour^(1 - feature): a feature difference
     * raises the error towards 1. */
    const double qc = 0.7, pc = 0.4, pt = 0.95, qf = 0.5;
    double pccmax = pc * s.cmax;
    for (size_t i = 0; i < n; i++) {
        double p[3] = {(double)col[0][i], (double)col[0][n + i], (double)col[0][2 * n + i]};
        double q[3] = {(double)col[1][i], (double)col[1][n + i], (double)col[1][2 * n + i]};
        double e = pow(flip_hyab(p, q), qc);
        double dc = e < pccmax ? pt / pccmax * e : pt + (e - pccmax) / (s.cmax - pccmax) * (1.0 - pt);
        double df = fmax(fabs((double)edge[0][i] - (double)edge[1][i]), fabs((double)point[0][i] - (double)point[1][i]));
        df = pow(df / sqrt(2.0), qf);
        err[i] = (float)pow(dc, 1.0 - df);
    }
    free(kc);
    free(kf);
    free(mem);
    return CST_OK;
}

/* ------------------------------------------------------------ HDR-FLIP */

/* Krzysztof Narkowicz's fit of the ACES filmic curve, (x (a x + b)) / (x (c x + d) + e) with
 * a = 2.51, b = 0.03, c = 2.43, d = 0.59, e = 0.14, of x = 0.6 v (his pre-exposure), written
 * as the rational polynomial in v of the HDR-FLIP paper. */
static const double FLIP_ACES[6] = {0.6 * 0.6 * 2.51, 0.6 * 0.03, 0.0, 0.6 * 0.6 * 2.43, 0.6 * 0.59, 0.14};

double flip_tone_map(double v, double exposure)
{
    const double *k = FLIP_ACES;
    double x = exp2(exposure) * fmax(v, 0.0); /* fmax also turns NaN into 0 */
    if (isinf(x)) return 1.0;
    double y = (k[0] * x * x + k[1] * x + k[2]) / (k[3] * x * x + k[4] * x + k[5]);
    return isfinite(y) ? fmin(fmax(y, 0.0), 1.0) : 1.0;
}

static int flip_cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

void flip_exposure_range(const float *reference, int w, int h, double *start, double *stop, int *count)
{
    *start = *stop = 0.0;
    *count = 1;
    size_t n = (size_t)w * (size_t)h, pos = 0;
    float *lum = n ? malloc(n * sizeof *lum) : NULL;
    if (!lum) return;
    double y_max = 0.0;
    for (size_t i = 0; i < n; i++) {
        double y = 0.2126 * (double)reference[3 * i] + 0.7152 * (double)reference[3 * i + 1] +
                   0.0722 * (double)reference[3 * i + 2];
        if (!(y > 0.0)) y = 0.0; /* negative and NaN: black */
        if (isinf(y)) y = 0.0;
        lum[i] = (float)y;
        if (y > y_max) y_max = y;
        pos += y > 0.0;
    }
    if (y_max > 0.0) {
        /* x with tone_map(x) = t: the positive root of (k0 - t k3) x^2 + (k1 - t k4) x +
         * (k2 - t k5) = 0 (HDR-FLIP paper), t = 0.85 for both ends as in the paper. */
        const double *k = FLIP_ACES, t = 0.85;
        double c0 = (k[1] - k[4] * t) / (k[0] - k[3] * t), c1 = (k[2] - k[5] * t) / (k[0] - k[3] * t);
        double x = -0.5 * c0 + sqrt(0.25 * c0 * c0 - c1);
        qsort(lum, n, sizeof *lum, flip_cmp_float);
        /* the median (linear interpolation between the middle two, as numpy's percentile),
         * of the non-black pixels when black is the majority */
        const float *v = pos * 2 > n ? lum : lum + (n - pos);
        size_t m = pos * 2 > n ? n : pos;
        double mid = 0.5 * (double)(m - 1), lo = floor(mid);
        double median = (double)v[(size_t)lo] + (mid - lo) * ((double)v[(size_t)ceil(mid)] - (double)v[(size_t)lo]);
        *start = log2(x / y_max);
        *stop = log2(x / median);
        double span = *stop - *start;
        *count = span > 0.0 ? (int)fmax(2.0, ceil(span)) : 1;
    }
    free(lum);
}

CstStatus flip_hdr(const float *reference, const float *test, int w, int h, double ppd, double start,
                   double stop, int count, float *err, CstError *error)
{
    if (w < 1 || h < 1 || count < 1 || !isfinite(start) || !isfinite(stop))
        return cst_fail(error, CST_ERR_INVALID_ARG, "HDR-FLIP: invalid size %dx%d or exposures %g..%g (%d)",
                        w, h, start, stop, count);
    size_t n = (size_t)w * (size_t)h;
    float *mem = malloc(7 * n * sizeof *mem);
    if (!mem) return cst_fail(error, CST_ERR_OOM, "HDR-FLIP: out of memory for a %dx%d image", w, h);
    float *ref = mem, *tst = mem + 3 * n, *e = mem + 6 * n;
    for (size_t i = 0; i < n; i++) err[i] = 0.0f;
    double step = count > 1 ? (stop - start) / (count - 1) : 0.0;
    CstStatus st = CST_OK;
    for (int k = 0; k < count && st == CST_OK; k++) {
        double exposure = start + k * step;
        for (size_t i = 0; i < 3 * n; i++) {
            ref[i] = (float)flip_tone_map((double)reference[i], exposure);
            tst[i] = (float)flip_tone_map((double)test[i], exposure);
        }
        st = flip_ldr(ref, tst, w, h, ppd, e, error);
        for (size_t i = 0; st == CST_OK && i < n; i++)
            if (e[i] > err[i]) err[i] = e[i];
    }
    free(mem);
    return st;
}

/* ------------------------------------------------------------ public names */

CstStatus cst_image_flip(const float *test, const float *reference, int width, int height,
                         const CstFlipOptions *options, float *map, CstFlipResult *out, CstError *err)
{
    CstFlipOptions o = {0};
    if (options) o = *options;
    if (o.kind != 0 && o.kind != CST_FLIP_LDR && o.kind != CST_FLIP_HDR)
        return cst_fail(err, CST_ERR_INVALID_ARG, "FLIP: unknown kind %d", (int)o.kind);
    memset(out, 0, sizeof *out);
    out->kind = o.kind ? o.kind : CST_FLIP_HDR;
    out->pixels_per_degree = o.pixels_per_degree > 0.0 ? o.pixels_per_degree : FLIP_DEFAULT_PPD;
    if (width < 1 || height < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "FLIP: empty image (%dx%d)", width, height);
    size_t n = (size_t)width * (size_t)height;
    float *e = map ? map : malloc(n * sizeof *e);
    if (!e) return cst_fail(err, CST_ERR_OOM, "FLIP: out of memory for a %dx%d map", width, height);
    CstStatus st;
    if (out->kind == CST_FLIP_LDR) {
        st = flip_ldr(reference, test, width, height, out->pixels_per_degree, e, err);
    } else {
        if (o.exposures > 0) {
            out->start_exposure = o.start_exposure;
            out->stop_exposure = o.stop_exposure;
            out->exposures = o.exposures;
        } else {
            flip_exposure_range(reference, width, height, &out->start_exposure, &out->stop_exposure,
                                &out->exposures);
        }
        st = flip_hdr(reference, test, width, height, out->pixels_per_degree, out->start_exposure,
                      out->stop_exposure, out->exposures, e, err);
    }
    if (st == CST_OK) {
        double sum = 0.0, mx = 0.0;
        for (size_t i = 0; i < n; i++) {
            sum += (double)e[i];
            if ((double)e[i] > mx) mx = (double)e[i];
        }
        out->mean = sum / (double)n;
        out->max = mx;
    }
    if (!map) free(e);
    return st;
}
