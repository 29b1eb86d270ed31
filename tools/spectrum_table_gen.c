/* Build-time generator of the RGB -> spectrum coefficient table of Jakob & Hanika 2019, "A
 * Low-Dimensional Function Space for Efficient Spectral Upsampling" (Computer Graphics
 * Forum 38(2)): for every linear sRGB colour of a grid, the sigmoid of a quadratic,
 * s(c0 t^2 + c1 t + c2) with t = (lambda - 360) / 470 and s(x) = 1/2 + x / (2 sqrt(1 + x^2)),
 * whose reflectance under D65 has that colour. Solved by Gauss-Newton on the CIELAB
 * difference (the paper's sec. 4.2), each solution starting from its grid neighbour's
 * (the paper's continuation along the brightness axis). Written once by CMake into the
 * build tree; math/spectrum.c embeds it (the binary layout is spectrum.h's).
 * Usage: spectrum_table_gen OUT.bin */
#include <math.h>
#include <pthread.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "math/cie_data.h"
#include "math/spectrum.h"

enum { FINE = (CIE_SAMPLES - 1) * 3 + 1 }; /* Simpson 3/8 nodes: 5/3 nm apart */

typedef struct Curves {
    double lambda_t[FINE];   /* normalised wavelength of each node, [0, 1] */
    double rgb_w[3][FINE];   /* weight of each node in R, G, B: (XYZ->sRGB) cmf D65 quadrature */
    double white[3];         /* XYZ of the illuminant (Y = 1) */
} Curves;

/* Linear interpolation in a 5 nm table. */
static double cie_lerp(const float *tab, double lambda)
{
    double x = (lambda - CIE_LAMBDA_MIN) / CIE_STEP;
    int i = (int)x;
    if (i < 0) i = 0;
    if (i > CIE_SAMPLES - 2) i = CIE_SAMPLES - 2;
    double f = x - i;
    return (1.0 - f) * (double)tab[i] + f * (double)tab[i + 1];
}

static void curves_init(Curves *cv)
{
    const double h = (double)(CIE_LAMBDA_MAX - CIE_LAMBDA_MIN) / (FINE - 1);
    double y_sum = 0.0;
    double w[FINE], xyz[FINE][3];
    for (int i = 0; i < FINE; i++) {
        double lambda = CIE_LAMBDA_MIN + i * h;
        /* Composite Simpson 3/8: 1 3 3 2 3 3 2 ... 3 3 1, times 3h/8. */
        double q = (i == 0 || i == FINE - 1) ? 1.0 : (i % 3 == 0 ? 2.0 : 3.0);
        double d65 = cie_lerp(cie_d65, lambda);
        w[i] = q * 3.0 * h / 8.0 * d65;
        xyz[i][0] = cie_lerp(cie_x, lambda);
        xyz[i][1] = cie_lerp(cie_y, lambda);
        xyz[i][2] = cie_lerp(cie_z, lambda);
        y_sum += w[i] * xyz[i][1];
        cv->lambda_t[i] = (lambda - CIE_LAMBDA_MIN) / (CIE_LAMBDA_MAX - CIE_LAMBDA_MIN);
    }
    memset(cv->white, 0, sizeof cv->white);
    for (int i = 0; i < FINE; i++) {
        w[i] /= y_sum; /* the illuminant at luminance 1 */
        for (int c = 0; c < 3; c++) {
            double v = 0.0;
            for (int k = 0; k < 3; k++) v += (double)cie_xyz_to_srgb[c][k] * xyz[i][k];
            cv->rgb_w[c][i] = v * w[i];
            cv->white[c] += xyz[i][c] * w[i];
        }
    }
}

static double lab_f(double t)
{
    const double d = 6.0 / 29.0;
    return t > d * d * d ? cbrt(t) : t / (3.0 * d * d) + 4.0 / 29.0;
}

/* Linear sRGB -> CIELAB relative to the illuminant's white. */
static void rgb_to_lab(const Curves *cv, const double rgb[3], double lab[3])
{
    double xyz[3];
    for (int c = 0; c < 3; c++) {
        xyz[c] = 0.0;
        for (int k = 0; k < 3; k++) xyz[c] += (double)cie_srgb_to_xyz[c][k] * rgb[k];
    }
    double fx = lab_f(xyz[0] / cv->white[0]), fy = lab_f(xyz[1] / cv->white[1]), fz = lab_f(xyz[2] / cv->white[2]);
    lab[0] = 116.0 * fy - 16.0;
    lab[1] = 500.0 * (fx - fy);
    lab[2] = 200.0 * (fy - fz);
}

static double sigmoid(double x) { return 0.5 + x / (2.0 * sqrt(1.0 + x * x)); }

/* Residual: the target's Lab minus the Lab of the coefficients' reflectance. */
static void residual(const Curves *cv, const double c[3], const double target_lab[3], double r[3])
{
    double rgb[3] = {0.0, 0.0, 0.0};
    for (int i = 0; i < FINE; i++) {
        double t = cv->lambda_t[i];
        double s = sigmoid((c[0] * t + c[1]) * t + c[2]);
        for (int k = 0; k < 3; k++) rgb[k] += cv->rgb_w[k][i] * s;
    }
    double lab[3];
    rgb_to_lab(cv, rgb, lab);
    for (int k = 0; k < 3; k++) r[k] = target_lab[k] - lab[k];
}

/* Solves A x = b (3x3) by Gaussian elimination with partial pivoting; 0 if singular. */
static int solve3(double A[3][3], double b[3], double x[3])
{
    for (int col = 0; col < 3; col++) {
        int p = col;
        for (int r = col + 1; r < 3; r++)
            if (fabs(A[r][col]) > fabs(A[p][col])) p = r;
        if (fabs(A[p][col]) < 1e-15) return 0;
        if (p != col) {
            for (int k = 0; k < 3; k++) { double t = A[col][k]; A[col][k] = A[p][k]; A[p][k] = t; }
            double t = b[col]; b[col] = b[p]; b[p] = t;
        }
        for (int r = col + 1; r < 3; r++) {
            double f = A[r][col] / A[col][col];
            for (int k = col; k < 3; k++) A[r][k] -= f * A[col][k];
            b[r] -= f * b[col];
        }
    }
    for (int r = 2; r >= 0; r--) {
        double v = b[r];
        for (int k = r + 1; k < 3; k++) v -= A[r][k] * x[k];
        x[r] = v / A[r][r];
    }
    return 1;
}

/* Gauss-Newton from the coefficients in c (updated in place); the Jacobian by central
 * differences. Coefficients are kept within +-200 (beyond, the sigmoid is a step to float
 * precision and the system is ill-conditioned). */
static void gauss_newton(const Curves *cv, const double rgb[3], double c[3])
{
    double target[3];
    rgb_to_lab(cv, rgb, target);
    for (int it = 0; it < 20; it++) {
        double r[3];
        residual(cv, c, target, r);
        double J[3][3];
        for (int j = 0; j < 3; j++) {
            double cp[3] = {c[0], c[1], c[2]}, cm[3] = {c[0], c[1], c[2]}, rp[3], rm[3];
            cp[j] += 1e-4;
            cm[j] -= 1e-4;
            residual(cv, cp, target, rp);
            residual(cv, cm, target, rm);
            for (int k = 0; k < 3; k++) J[k][j] = (rp[k] - rm[k]) / 2e-4;
        }
        double dx[3];
        if (!solve3(J, r, dx)) break;
        double m = 0.0;
        for (int k = 0; k < 3; k++) {
            c[k] -= dx[k];
            m = fmax(m, fabs(c[k]));
        }
        if (m > 200.0)
            for (int k = 0; k < 3; k++) c[k] *= 200.0 / m;
        if (r[0] * r[0] + r[1] * r[1] + r[2] * r[2] < 1e-12) break;
    }
}

typedef struct Job {
    const Curves *cv;
    const float *znodes;
    float *out; /* the coefficient part of the table */
    int first, step;
} Job;

static void solve_line(const Job *jb, int line)
{
    const int R = SPECTRUM_TABLE_RES;
    int l = line / (R * R), yi = (line / R) % R, xi = line % R;
    double x = (double)xi / (R - 1), y = (double)yi / (R - 1);
    /* From the middle of the brightness axis upward, then from there downward, each
     * solve starting from the previous one. */
    const int start = R / 5;
    for (int pass = 0; pass < 2; pass++) {
        double c[3] = {0.0, 0.0, 0.0};
        for (int zi = start; pass == 0 ? zi < R : zi >= 0; zi += pass == 0 ? 1 : -1) {
            double z = (double)jb->znodes[zi], rgb[3];
            rgb[l] = z;
            rgb[(l + 1) % 3] = x * z;
            rgb[(l + 2) % 3] = y * z;
            gauss_newton(jb->cv, rgb, c);
            float *o = &jb->out[3 * ((((size_t)l * R + zi) * R + yi) * R + xi)];
            for (int k = 0; k < 3; k++) o[k] = (float)c[k];
        }
    }
}

static void *worker(void *arg)
{
    const Job *jb = arg;
    for (int line = jb->first; line < 3 * SPECTRUM_TABLE_RES * SPECTRUM_TABLE_RES; line += jb->step) solve_line(jb, line);
    return NULL;
}

int main(int argc, char **argv)
{
    if (argc != 2) {
        fprintf(stderr, "usage: %s OUT.bin\n", argv[0]);
        return 2;
    }
    const int R = SPECTRUM_TABLE_RES;
    static Curves cv;
    curves_init(&cv);
    size_t n = SPECTRUM_TABLE_FLOATS;
    float *tab = calloc(n, sizeof *tab);
    if (!tab) return 1;
    /* Brightness nodes: denser near 0 and 1, where reflectances change fastest. */
    for (int k = 0; k < R; k++) {
        double t = (double)k / (R - 1);
        t = t * t * (3.0 - 2.0 * t);
        tab[k] = (float)(t * t * (3.0 - 2.0 * t));
    }
    enum { THREADS = 2 };
    pthread_t th[THREADS];
    Job jobs[THREADS];
    for (int i = 0; i < THREADS; i++) {
        jobs[i] = (Job){&cv, tab, tab + R, i, THREADS};
        if (pthread_create(&th[i], NULL, worker, &jobs[i])) return 1;
    }
    for (int i = 0; i < THREADS; i++) pthread_join(th[i], NULL);
    FILE *f = fopen(argv[1], "wb");
    if (!f || fwrite(tab, sizeof *tab, n, f) != n || fclose(f)) {
        fprintf(stderr, "%s: cannot write %s\n", argv[0], argv[1]);
        return 1;
    }
    free(tab);
    return 0;
}
