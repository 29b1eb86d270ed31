/* OpenEXR images through OpenEXR's C API (OpenEXRCore): what image_io.c dispatches to for
 * .exr files, reading and writing through an open FILE (image_io.c owns the atomic write). */
#ifndef CST_IO_EXR_H
#define CST_IO_EXR_H

#include "caustic/caustic.h"
#include "io/image_io.h"

#include <stdbool.h>
#include <stdio.h>

/* Writes rgb (w x h x 3 linear floats, row 0 the top) and opt's extra channels and
 * metadata as a ZIP-compressed float scanline EXR to fp; path names it in errors. */
CstStatus exr_write(FILE *fp, const char *path, const float *rgb, int w, int h, const ImageWriteOptions *opt,
                    CstError *err);

/* Reads the EXR open in fp: R, G, B (or Y, replicated) when layer is NULL or empty, else
 * the channels layer.R, layer.G, layer.B (CST_ERR_UNSUPPORTED without them). *out is
 * malloc'd w x h x 3 floats. */
CstStatus exr_read(FILE *fp, const char *path, const char *layer, float **out, int *w, int *h, CstError *err);

/* An EXR image as a texture keeps it (exr_read_texels): w x h texels of `channels`
 * interleaved values, row 0 the top: 1 (Y), 3 (R, G, B) or 4 (R, G, B, A: a full-
 * resolution A beside them), as IEEE halves (uint16_t) when every kept channel is half,
 * else as floats. px is malloc'd. */
typedef struct ExrImage {
    void *px;
    int width, height, channels;
    bool half;
} ExrImage;

/* Reads the EXR open in fp as a texture keeps it (pbrt-v4 Image::Read and
 * MIPMap::CreateFromFile keep the file's pixel format and R, G, B, A or Y). No value is
 * checked here. */
CstStatus exr_read_texels(FILE *fp, const char *path, ExrImage *out, CstError *err);

#endif
