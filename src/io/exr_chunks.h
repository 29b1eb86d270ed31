/* A check of an OpenEXR file's chunk headers before its pixels are allocated: each chunk
 * inside the data window, and its stored bytes enough for its pixels under its compression. */
#ifndef CST_IO_EXR_CHUNKS_H
#define CST_IO_EXR_CHUNKS_H

#include <stdbool.h>

#include <openexr.h>

#include "caustic/caustic.h"

/* Reads the header of every chunk of part 0 (scanline blocks, or level-0 tiles when tiled)
 * of a window of w x h pixels. Returns EXR_ERR_SUCCESS; OpenEXR's error (err untouched);
 * EXR_ERR_CORRUPT_CHUNK for a chunk outside the window (err untouched); or
 * EXR_ERR_CORRUPT_CHUNK with *short_chunk set and err filled (CST_ERR_PARSE, "path: ...")
 * for a chunk whose stored bytes cannot expand to its pixels (docs/fuzzing.md, fixed
 * finding 9: a 285-byte file declaring 2.4 GB of floats). */
exr_result_t exr_chunks_check(exr_context_t ctx, const char *path, bool tiled, const exr_attr_box2i_t *dw, int w,
                              int h, bool *short_chunk, CstError *err);

#endif
