/* The camera sensor's white balance (pbrt-v4's "cie1931" sensor with Film "whitebalance"):
 * a von Kries adaptation in the Bradford cone space from the white of an illuminant of a
 * given colour temperature to the output colour space's white (sRGB's D65), as one 3x3
 * matrix on linear sRGB. */
#ifndef CST_FILM_SENSOR_H
#define CST_FILM_SENSOR_H

/* The chromaticity (x, y) of pbrt-v4's white-balance illuminant at kelvin: the CIE
 * daylight locus (CIE 15:2004 eq. 3.3-3.4, at the temperature corrected for the change of
 * c2 from 1.4380e-2 to 1.4388e-2 m K, as pbrt-v4's Spectra::D) from 4000 K, a blackbody
 * below (its chromaticity through the CIE 1931 curves). kelvin > 0. */
void sensor_illuminant_xy(double kelvin, double xy[2]);

/* The matrix M with rgb_out = M rgb_in (linear sRGB) that maps the white of the illuminant
 * at kelvin to the output's white, every colour by the same scaling of the Bradford cone
 * responses (von Kries; Lam 1985's matrix): M = XYZ->sRGB . B^-1 diag(lms_d65 / lms_src)
 * B . sRGB->XYZ. kelvin <= 0: the identity. */
void sensor_white_balance(double kelvin, double m[3][3]);

#endif
