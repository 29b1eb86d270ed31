/* White balance of the sensor (sensor.h). */
#include "film/sensor.h"

#include <math.h>

#include "math/cie_data.h"
#include "math/spectrum.h"

void sensor_illuminant_xy(double kelvin, double xy[2])
{
    double t = kelvin * 1.4388 / 1.4380; /* CCT on the ITS-90 c2 */
    if (t < 4000.0) {
        /* The daylight locus is not defined below 4000 K: a blackbody, integrated at 1 nm. */
        double X = 0.0, Y = 0.0, Z = 0.0;
        for (int l = SPECTRUM_LAMBDA_MIN; l <= SPECTRUM_LAMBDA_MAX; l++) {
            float c[3];
            spectrum_cie_xyz((float)l, c);
            double b = (double)spectrum_blackbody((float)l, (float)t);
            X += b * (double)c[0], Y += b * (double)c[1], Z += b * (double)c[2];
        }
        double s = X + Y + Z;
        xy[0] = X / s, xy[1] = Y / s;
        return;
    }
    double x = t <= 7000.0 ? -4.6070e9 / (t * t * t) + 2.9678e6 / (t * t) + 0.09911e3 / t + 0.244063
                           : -2.0064e9 / (t * t * t) + 1.9018e6 / (t * t) + 0.24748e3 / t + 0.237040;
    xy[0] = x;
    xy[1] = -3.0 * x * x + 2.870 * x - 0.275;
}

static void mul3(const double a[3][3], const double b[3][3], double out[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) out[i][j] = a[i][0] * b[0][j] + a[i][1] * b[1][j] + a[i][2] * b[2][j];
}

/* The inverse by cofactors (B is well conditioned: det 0.95). */
static void inverse3(const double a[3][3], double out[3][3])
{
    double det = a[0][0] * (a[1][1] * a[2][2] - a[1][2] * a[2][1]) - a[0][1] * (a[1][0] * a[2][2] - a[1][2] * a[2][0]) +
                 a[0][2] * (a[1][0] * a[2][1] - a[1][1] * a[2][0]);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            int r0 = (j + 1) % 3, r1 = (j + 2) % 3, c0 = (i + 1) % 3, c1 = (i + 2) % 3;
            out[i][j] = (a[r0][c0] * a[r1][c1] - a[r0][c1] * a[r1][c0]) / det;
        }
}

void sensor_white_balance(double kelvin, double m[3][3])
{
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) m[i][j] = i == j ? 1.0 : 0.0;
    if (!(kelvin > 0.0) || !isfinite(kelvin)) return;
    /* Bradford's XYZ -> cone response (Lam 1985) and its inverse. */
    static const double B[3][3] = {{0.8951, 0.2664, -0.1614}, {-0.7502, 1.7135, 0.0367}, {0.0389, -0.0685, 1.0296}};
    double BI[3][3];
    inverse3(B, BI);
    double xy[2];
    sensor_illuminant_xy(kelvin, xy);
    const double src[3] = {xy[0] / xy[1], 1.0, (1.0 - xy[0] - xy[1]) / xy[1]};
    /* The output's white: D65 as the film's XYZ -> sRGB matrix has it (cie_data.h). */
    const double dst[3] = {0.950471, 1.0, 1.088665};
    double d[3][3] = {{0}};
    for (int i = 0; i < 3; i++) {
        double ls = B[i][0] * src[0] + B[i][1] * src[1] + B[i][2] * src[2];
        double ld = B[i][0] * dst[0] + B[i][1] * dst[1] + B[i][2] * dst[2];
        d[i][i] = ld / ls;
    }
    double to_xyz[3][3], to_rgb[3][3], t1[3][3], t2[3][3], t3[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) {
            to_xyz[i][j] = (double)cie_srgb_to_xyz[i][j];
            to_rgb[i][j] = (double)cie_xyz_to_srgb[i][j];
        }
    mul3(d, B, t1);      /* diag . B */
    mul3(BI, t1, t2);    /* B^-1 . diag . B: the adaptation in XYZ */
    mul3(t2, to_xyz, t3);
    mul3(to_rgb, t3, m);
}
