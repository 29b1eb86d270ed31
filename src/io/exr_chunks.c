/* The OpenEXR chunk check of io/exr_chunks.h: a first pass over the chunk headers, as
 * io/image_io.c's decoder walks them, before the image is allocated. */
#include "io/exr_chunks.h"

#include <stdint.h>

#include "core/error.h"

/* The most a chunk's pixels can expand from its stored bytes in each compression, a bound
 * no valid file exceeds; 0 where none is known (PIZ, DWAA, DWAB: not checked). RLE: runs
 * of at most 128 bytes in 2; ZIP(S): deflate's 1032:1; PXR24: deflate of at least 3
 * bytes for every 4 (floats cut to 24 bits); B44(A): at least 3 bytes a 4 x 4 block of 32. */
static uint64_t exr_chunks_max_ratio(exr_compression_t c)
{
    switch (c) {
    case EXR_COMPRESSION_NONE: return 1;
    case EXR_COMPRESSION_RLE: return 64;
    case EXR_COMPRESSION_ZIPS:
    case EXR_COMPRESSION_ZIP: return 1032;
    case EXR_COMPRESSION_PXR24: return 1376;
    case EXR_COMPRESSION_B44:
    case EXR_COMPRESSION_B44A: return 11;
    default: return 0;
    }
}

exr_result_t exr_chunks_check(exr_context_t ctx, const char *path, bool tiled, const exr_attr_box2i_t *dw, int w,
                              int h, bool *short_chunk, CstError *err)
{
    *short_chunk = false;
    exr_compression_t comp = EXR_COMPRESSION_NONE;
    exr_result_t rv = exr_get_compression(ctx, 0, &comp);
    uint64_t ratio = exr_chunks_max_ratio(comp);
    int32_t nx = 1, ny = 0, step_x = w, step_y = 0;
    if (rv == EXR_ERR_SUCCESS && tiled) {
        rv = exr_get_tile_sizes(ctx, 0, 0, 0, &step_x, &step_y);
        if (rv == EXR_ERR_SUCCESS && (step_x <= 0 || step_y <= 0)) rv = EXR_ERR_INVALID_ATTR;
        if (rv == EXR_ERR_SUCCESS) nx = (int32_t)(((int64_t)w + step_x - 1) / step_x);
    } else if (rv == EXR_ERR_SUCCESS) {
        rv = exr_get_scanlines_per_chunk(ctx, 0, &step_y);
        if (rv == EXR_ERR_SUCCESS && step_y <= 0) rv = EXR_ERR_INVALID_ATTR;
    }
    if (rv == EXR_ERR_SUCCESS) ny = (int32_t)(((int64_t)h + step_y - 1) / step_y);
    for (int32_t ty = 0; rv == EXR_ERR_SUCCESS && ty < ny; ++ty) {
        for (int32_t tx = 0; rv == EXR_ERR_SUCCESS && tx < nx; ++tx) {
            exr_chunk_info_t ci;
            int64_t x0 = 0, y0;
            if (tiled) {
                rv = exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &ci);
                x0 = (int64_t)tx * step_x; /* start_x/start_y are tile indices here */
                y0 = (int64_t)ty * step_y;
            } else {
                rv = exr_read_scanline_chunk_info(ctx, 0, (int)(dw->min.y + (int64_t)ty * step_y), &ci);
                y0 = (int64_t)ci.start_y - dw->min.y;
            }
            if (rv != EXR_ERR_SUCCESS) break;
            if (x0 < 0 || y0 < 0 || ci.width < 0 || ci.height < 0 || x0 + ci.width > w || y0 + ci.height > h)
                return EXR_ERR_CORRUPT_CHUNK;
            if (ratio && ci.packed_size * ratio < ci.unpacked_size) {
                *short_chunk = true;
                cst_fail(err, CST_ERR_PARSE,
                         "%s: truncated or corrupt OpenEXR: the chunk at line %lld stores %llu bytes for %llu "
                         "bytes of pixels, more than its compression can expand", path, (long long)y0,
                         (unsigned long long)ci.packed_size, (unsigned long long)ci.unpacked_size);
                return EXR_ERR_CORRUPT_CHUNK;
            }
        }
    }
    return rv;
}
