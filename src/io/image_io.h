/* Image files: writers for PNG (8-bit sRGB), OpenEXR (float, linear) and PFM (float,
 * linear), chosen by the file extension, always written atomically (temporary file in
 * the same directory, then rename). Readers for the same formats serve tests and tools. */
#ifndef CST_IO_IMAGE_IO_H
#define CST_IO_IMAGE_IO_H

#include "caustic/caustic.h"

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

enum { IMAGE_MAX_EXTRA = 16 };

/* Encoders and decoders address rows with int32 byte strides (OpenEXR), 12 bytes a pixel. */
#define IMAGE_MAX_WIDTH (INT32_MAX / 12)

/* Zero-initialised: plain RGB, PNG in sRGB. */
typedef struct ImageWriteOptions {
    bool png_linear;          /* PNG bytes are linear (tagged gAMA 1.0), not sRGB-encoded */
    int extra_channels;       /* EXR only: channels after R, G, B (0..IMAGE_MAX_EXTRA) */
    const char *const *extra_names; /* their EXR names, e.g. "albedo.R", "Z" */
    const float *extra;       /* width * height * extra_channels floats, interleaved per pixel */
    /* The caller's metadata (PNG text chunks, EXR string attributes; PFM has none) and
     * temporary-file callback; NULL = neither. Keys and values are checked as the public
     * header states (image_write_opt fails with CST_ERR_INVALID_ARG otherwise). */
    const CstImageWriteOptions *out;
} ImageWriteOptions;

/* rgb: width * height * 3 linear floats, row 0 = the top row of the image. */
CstStatus image_write(const char *path, const float *rgb, int width, int height, CstError *err);
/* The same with options; extra channels with a non-EXR path fail with CST_ERR_INVALID_ARG. */
CstStatus image_write_opt(const char *path, const float *rgb, int width, int height,
                          const ImageWriteOptions *opt, CstError *err);
/* What image_write_opt checks before it writes, so that a render is refused before it
 * starts rather than thrown away at the end: a writable format, a path that is not a
 * directory and whose name is not too long, and the temporary file the write will use
 * (same name rule, io/path.h), created and removed. */
CstStatus image_write_check(const char *path, CstError *err);
/* Image file formats caustic reads (textures) or writes (renders). */
typedef enum ImageFileFormat {
    IMAGE_FILE_NONE, /* no extension, or one that names no image format below */
    IMAGE_FILE_PNG, IMAGE_FILE_JPEG, IMAGE_FILE_BMP, IMAGE_FILE_TGA, /* 8/16-bit, sRGB */
    IMAGE_FILE_HDR, IMAGE_FILE_EXR, IMAGE_FILE_PFM                   /* float, linear */
} ImageFileFormat;

/* The one rule for "which image format does this file name name": the extension of the
 * last path component (after its last '.', nonempty), compared ASCII case-insensitively
 * (the locale must not change the answer). "a.png", "A.PNG" and "dir/.png" are PNG;
 * "dir.png/a" and "png" are IMAGE_FILE_NONE. The scene loaders and the CLI use it to
 * reject names that image_write would refuse before rendering. */
ImageFileFormat image_format_from_path(const char *path);
/* The index-th (from 0) extension image_write writes ("png", "exr", "pfm"), else NULL. */
const char *image_writable_extension(int index);
/* True for the formats image_write can produce: PNG, EXR and PFM. */
bool image_format_is_writable(ImageFileFormat f);
/* An output name a scene file may give: a writable format and something before the '.' of
 * the extension ("a.png", "dir/.png"; not ".png"), as both scene loaders have checked it. */
bool image_path_is_scene_output(const char *path);
/* True for the formats holding linear floats (HDR, EXR, PFM): no sRGB decoding. */
bool image_format_is_float(ImageFileFormat f);
/* True when the path's extension is .exr (any case). */
bool image_path_is_exr(const char *path);
/* Readers refuse images above this many pixels (16384 x 16384) so that a corrupt header
 * cannot make us allocate tens of gigabytes before the data turns out to be missing. */
#define IMAGE_MAX_PIXELS ((uint64_t)1 << 28)
/* The size every image reader accepts (image_read, and textures decoded by stb_image):
 * both sides positive, at most IMAGE_MAX_PIXELS pixels, and a width whose float rows
 * OpenEXR can address. */
bool image_size_ok(uint64_t width, uint64_t height);

/* strerror's text for errno e in buf (reentrant: checkpoints are written while render
 * threads run), returned. */
const char *image_strerror(int e, char *buf, size_t n);
/* Reads a PNG (decoded to linear), EXR, PFM or Radiance HDR into a new malloc'd buffer in the same layout.
 * Caller frees *rgb. */
CstStatus image_read(const char *path, float **rgb, int *width, int *height, CstError *err);
/* The EXR channels "<layer>.R/G/B" of path as image_read's RGB (layer NULL or "": image_read).
 * CST_ERR_UNSUPPORTED when path is no EXR or lacks them. */
CstStatus image_read_layer(const char *path, const char *layer, float **rgb, int *width, int *height,
                           CstError *err);
/* The one rule for images that become light or reflectance (textures, environment maps,
 * both loaders and the builder): every value finite and >= 0. Fails with
 * CST_ERR_INVALID_ARG naming `what` (a path, or NULL for "image") and the first offending
 * pixel's x, y (row 0 at the top) and channel. */
CstStatus image_check_radiance(const float *rgb, int width, int height, const char *what, CstError *err);
/* image_read, then image_check_radiance; on failure *rgb is freed and NULL. */
CstStatus image_read_radiance(const char *path, float **rgb, int *width, int *height, CstError *err);
/* sRGB OETF (IEC 61966-2-1) of a linear value, clamped to [0, 1]. */
float image_linear_to_srgb(float v);
/* Its inverse, the sRGB EOTF, of an encoded value s in [0, 1]. */
float image_srgb_to_linear(double s);

#endif
