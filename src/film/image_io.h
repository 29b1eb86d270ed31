/* Image files: writers for PNG (8-bit sRGB), OpenEXR (float, linear) and PFM (float,
 * linear), chosen by the file extension, always written atomically (temporary file in
 * the same directory, then rename). Readers for the same formats serve tests and tools. */
#ifndef CST_FILM_IMAGE_IO_H
#define CST_FILM_IMAGE_IO_H

#include "caustic/caustic.h"

#include <stdbool.h>

enum { IMAGE_MAX_EXTRA = 16 };

/* Zero-initialised: plain RGB, PNG in sRGB. */
typedef struct ImageWriteOptions {
    bool png_linear;          /* PNG bytes are linear (tagged gAMA 1.0), not sRGB-encoded */
    int extra_channels;       /* EXR only: channels after R, G, B (0..IMAGE_MAX_EXTRA) */
    const char *const *extra_names; /* their EXR names, e.g. "albedo.R", "Z" */
    const float *extra;       /* width * height * extra_channels floats, interleaved per pixel */
} ImageWriteOptions;

/* rgb: width * height * 3 linear floats, row 0 = the top row of the image. */
CstStatus image_write(const char *path, const float *rgb, int width, int height, CstError *err);
/* The same with options; extra channels with a non-EXR path fail with CST_ERR_INVALID_ARG. */
CstStatus image_write_opt(const char *path, const float *rgb, int width, int height,
                          const ImageWriteOptions *opt, CstError *err);
/* True when the path's extension is .exr (any case). */
bool image_path_is_exr(const char *path);
/* Reads a PNG (decoded to linear), EXR or PFM into a new malloc'd buffer in the same layout.
 * Caller frees *rgb. */
CstStatus image_read(const char *path, float **rgb, int *width, int *height, CstError *err);
/* sRGB OETF (IEC 61966-2-1) of a linear value, clamped to [0, 1]. */
float image_linear_to_srgb(float v);
/* Its inverse, the sRGB EOTF, of an encoded value s in [0, 1]. */
float image_srgb_to_linear(double s);

#endif
