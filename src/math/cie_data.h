/* Tabulated colorimetric data: the CIE 1931 2-degree colour-matching functions and the CIE
 * standard illuminant D65, 360-830 nm every 5 nm (95 samples). Shared by the spectrum
 * module (math/spectrum.c) and the build-time generator of the RGB->spectrum table
 * (tools/spectrum_table_gen.c), so both integrate against the same curves. */
#ifndef CST_MATH_CIE_DATA_H
#define CST_MATH_CIE_DATA_H

enum {
    CIE_LAMBDA_MIN = 360, /* nm */
    CIE_LAMBDA_MAX = 830, /* nm */
    CIE_STEP = 5,         /* nm */
    CIE_SAMPLES = 95      /* (830 - 360) / 5 + 1 */
};

/* x-bar, y-bar, z-bar (dimensionless, y-bar peaks at 1 at 555 nm). */
extern const float cie_x[CIE_SAMPLES], cie_y[CIE_SAMPLES], cie_z[CIE_SAMPLES];
/* D65 relative spectral power, 100 at 560 nm (CIE's own scale). */
extern const float cie_d65[CIE_SAMPLES];

/* Linear sRGB (ITU-R BT.709 primaries) <-> CIE XYZ, with the white point of the D65 table
 * above integrated against the colour-matching functions above (X, Z = 0.950471, 1.088665
 * at Y = 1; pbrt-v4 also derives its matrices from the illuminant's spectrum), so D65 at
 * luminance 1 maps to RGB (1, 1, 1) to float precision. */
extern const float cie_xyz_to_srgb[3][3], cie_srgb_to_xyz[3][3];
/* Integral of D65 (as tabulated) times y-bar over 360-830 nm, both linearly interpolated
 * between the 5 nm samples (computed at 0.01 nm steps), nm. */
#define CIE_D65_Y_INTEGRAL 10566.864f

/* Integral of y-bar over 360-830 nm with 1 nm steps of the official 1 nm table, nm
 * (the value pbrt-v4 calls CIE_Y_integral). */
#define CIE_Y_INTEGRAL 106.856895f

#endif
