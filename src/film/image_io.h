/* Image files: writers for PNG (8-bit sRGB), OpenEXR (float, linear) and PFM (float,
 * linear), chosen by the file extension, always written atomically (temporary file in
 * the same directory, then rename). Readers for the same formats serve tests and tools. */
#ifndef CST_FILM_IMAGE_IO_H
#define CST_FILM_IMAGE_IO_H

#include "caustic/caustic.h"

/* rgb: width * height * 3 linear floats, row 0 = the top row of the image. */
CstStatus image_write(const char *path, const float *rgb, int width, int height, CstError *err);
/* Reads a PNG (decoded to linear), EXR or PFM into a new malloc'd buffer in the same layout.
 * Caller frees *rgb. */
CstStatus image_read(const char *path, float **rgb, int *width, int *height, CstError *err);
/* sRGB OETF (IEC 61966-2-1) of a linear value, clamped to [0, 1]. */
float image_linear_to_srgb(float v);
/* Its inverse, the sRGB EOTF, of an encoded value s in [0, 1]. */
float image_srgb_to_linear(double s);

#endif
