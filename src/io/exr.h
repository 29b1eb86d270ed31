/* OpenEXR images through OpenEXR's C API (OpenEXRCore): what image_io.c dispatches to for
 * .exr files, reading and writing through an open FILE (image_io.c owns the atomic write). */
#ifndef CST_IO_EXR_H
#define CST_IO_EXR_H

#include "caustic/caustic.h"
#include "io/image_io.h"

#include <stdio.h>

/* Writes rgb (w x h x 3 linear floats, row 0 the top) and opt's extra channels and
 * metadata as a ZIP-compressed float scanline EXR to fp; path names it in errors. */
CstStatus exr_write(FILE *fp, const char *path, const float *rgb, int w, int h, const ImageWriteOptions *opt,
                    CstError *err);

/* Reads the EXR open in fp: R, G, B (or Y, replicated) when layer is NULL or empty, else
 * the channels layer.R, layer.G, layer.B (CST_ERR_UNSUPPORTED without them). *out is
 * malloc'd w x h x 3 floats. */
CstStatus exr_read(FILE *fp, const char *path, const char *layer, float **out, int *w, int *h, CstError *err);

#endif
