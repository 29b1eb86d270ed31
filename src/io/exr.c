/* OpenEXR images through OpenEXR's C API (OpenEXRCore): the float RGB writer with extra
 * channels and string attributes, and the reader of RGB, Y or a named layer's channels. */
#include "io/exr.h"

#include "core/error.h"
#include "io/exr_chunks.h"

#include <errno.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <openexr.h>

/* Our side of an OpenEXR context: the file descriptor behind the custom read/write
 * callbacks, the errno of a failed system call and the library's first error message. */
typedef struct ExrIo {
    int fd;
    int io_errno;
    char msg[256];
} ExrIo;

/* OpenEXR reports errors through a callback (it would print to stderr without one). The
 * callback can fire while the context's write lock is held, so it must not call back into
 * the library (exr_get_user_data locks too); a thread-local pointer finds our ExrIo. */
static _Thread_local ExrIo *image_exr_sink;

static void image_exr_on_error(exr_const_context_t ctxt, exr_result_t code, const char *msg)
{
    (void)ctxt;
    ExrIo *io = image_exr_sink;
    if (io && !io->msg[0])
        snprintf(io->msg, sizeof io->msg, "%s", msg ? msg : exr_get_default_error_message(code));
}

static int64_t image_exr_read_fn(exr_const_context_t ctxt, void *user, void *buffer, uint64_t sz,
                                 uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    ExrIo *io = user;
    uint8_t *dst = buffer;
    uint64_t done = 0;
    if (offset > (uint64_t)INT64_MAX - sz) return -1;
    while (done < sz) {
        size_t chunk = sz - done > ((size_t)1 << 30) ? (size_t)1 << 30 : (size_t)(sz - done);
        ssize_t n = pread(io->fd, dst + done, chunk, (off_t)(offset + done));
        if (n < 0) {
            if (errno == EINTR) continue;
            io->io_errno = errno;
            return -1;
        }
        if (n == 0) break; /* end of file: the library reports the short read */
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

static int64_t image_exr_size_fn(exr_const_context_t ctxt, void *user)
{
    (void)ctxt;
    ExrIo *io = user;
    struct stat sb;
    return fstat(io->fd, &sb) == 0 ? (int64_t)sb.st_size : -1;
}

static int64_t image_exr_write_fn(exr_const_context_t ctxt, void *user, const void *buffer,
                                  uint64_t sz, uint64_t offset, exr_stream_error_func_ptr_t error_cb)
{
    (void)ctxt;
    (void)error_cb;
    ExrIo *io = user;
    const uint8_t *src = buffer;
    uint64_t done = 0;
    if (offset > (uint64_t)INT64_MAX - sz) return -1;
    while (done < sz) {
        size_t chunk = sz - done > ((size_t)1 << 30) ? (size_t)1 << 30 : (size_t)(sz - done);
        ssize_t n = pwrite(io->fd, src + done, chunk, (off_t)(offset + done));
        if (n < 0) {
            if (errno == EINTR) continue;
            io->io_errno = errno;
            return -1;
        }
        done += (uint64_t)n;
    }
    return (int64_t)done;
}

/* The layer image_read_exr reads on this thread: NULL for R, G, B (or Y); "variance" for
 * variance.R/G/B (image_read_layer). Thread-local like image_exr_sink, so the slot rule
 * keeps its signature for the writer too. */
static _Thread_local const char *image_exr_layer;

/* Interleaved slot (0 = R, 1 = G, 2 = B) of a channel, or -1. The file keeps channels
 * sorted by name (B, G, R), so slots go by name, never by position. When the file is
 * greyscale, "Y" lands in slot 0 (and the film's reader replicates it afterwards). */
static int image_exr_slot(const char *name, bool grey)
{
    if (!name) return -1;
    if (image_exr_layer) { /* "<layer>.R" ... */
        size_t n = strlen(image_exr_layer);
        if (grey || strncmp(name, image_exr_layer, n) != 0 || name[n] != '.') return -1;
        name += n + 1;
    }
    if (grey) return strcmp(name, "Y") == 0 ? 0 : -1;
    if (strcmp(name, "R") == 0) return 0;
    if (strcmp(name, "G") == 0) return 1;
    if (strcmp(name, "B") == 0) return 2;
    return -1;
}

static CstStatus image_exr_status(CstError *err, const char *path, const ExrIo *io,
                                  exr_result_t rv, const char *doing)
{
    char buf[128];
    if (io->io_errno)
        return cst_fail(err, CST_ERR_IO, "%s: %s: %s", path, doing,
                        image_strerror(io->io_errno, buf, sizeof buf));
    if (rv == EXR_ERR_OUT_OF_MEMORY) return cst_fail(err, CST_ERR_OOM, "%s: %s: out of memory", path, doing);
    /* OpenEXRCore 3.1 cannot decode DWAA/DWAB yet: a valid file this build cannot read. */
    if (rv == EXR_ERR_FEATURE_NOT_IMPLEMENTED)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: %s: %s", path, doing,
                        io->msg[0] ? io->msg : exr_get_default_error_message(rv));
    return cst_fail(err, CST_ERR_PARSE, "%s: %s: %s", path, doing,
                    io->msg[0] ? io->msg : exr_get_default_error_message(rv));
}

/* The extra channel called `name`, or -1. */
static int image_exr_extra(const ImageWriteOptions *opt, const char *name)
{
    for (int i = 0; name && i < opt->extra_channels; ++i)
        if (strcmp(opt->extra_names[i], name) == 0) return i;
    return -1;
}

/* The library's own compressor, which image_exr_compress wraps (a struct: a function pointer
 * does not travel through encoding_user_data's void * in C17). */
typedef struct ExrCompressor {
    exr_result_t (*fn)(exr_encode_pipeline_t *);
} ExrCompressor;

/* OpenEXR 3.1.5's ZIP compressor (Debian 12) keeps the deflated bytes when they are exactly as
 * many as the packed pixels, and every reader, OpenEXR's included, takes a chunk whose stored
 * size equals its pixels' size for uncompressed: the chunk reads back as garbage (OpenEXR issue
 * #2306, fixed upstream in 2026 by storing the packed bytes when deflate does not shrink
 * them). A noisy 64 x 16 float chunk hits it about once in a few hundred. The same rule here:
 * a chunk that did not shrink is stored as its packed bytes, which the compression buffer,
 * at least as large as them, holds. */
static exr_result_t image_exr_compress(exr_encode_pipeline_t *enc)
{
    const ExrCompressor *c = enc->encoding_user_data;
    exr_result_t rv = c->fn(enc);
    if (rv == EXR_ERR_SUCCESS && enc->compressed_buffer && enc->compressed_buffer != enc->packed_buffer &&
        enc->compressed_bytes == enc->packed_bytes && enc->compressed_alloc_size >= enc->packed_bytes)
        memcpy(enc->compressed_buffer, enc->packed_buffer, (size_t)enc->packed_bytes);
    return rv;
}

static exr_result_t image_exr_encode(exr_context_t ctx, int part, const float *rgb, int w, int h,
                                     const ImageWriteOptions *opt)
{
    ExrCompressor library = {NULL};
    const int ne = opt->extra_channels;
    exr_encode_pipeline_t enc = EXR_ENCODE_PIPELINE_INITIALIZER;
    bool live = false;
    int32_t lines = 0;
    exr_result_t rv = exr_get_scanlines_per_chunk(ctx, part, &lines);
    if (rv == EXR_ERR_SUCCESS && lines <= 0) rv = EXR_ERR_UNKNOWN;
    for (int y = 0; rv == EXR_ERR_SUCCESS && y < h; y += lines) {
        exr_chunk_info_t ci;
        rv = exr_write_scanline_chunk_info(ctx, part, y, &ci);
        if (rv != EXR_ERR_SUCCESS) break;
        rv = live ? exr_encoding_update(ctx, part, &ci, &enc)
                  : exr_encoding_initialize(ctx, part, &ci, &enc);
        if (rv != EXR_ERR_SUCCESS) break;
        live = true;
        const float *first = rgb + (size_t)(ci.start_y) * (size_t)w * 3;
        for (int c = 0; c < enc.channel_count; ++c) {
            exr_coding_channel_info_t *ch = &enc.channels[c];
            int slot = image_exr_slot(ch->channel_name, false), stride = 3;
            const float *at = first + slot;
            if (slot < 0) {
                slot = image_exr_extra(opt, ch->channel_name);
                if (slot < 0) return EXR_ERR_UNKNOWN; /* we declared only these */
                stride = ne;
                at = opt->extra + (size_t)(ci.start_y) * (size_t)w * (size_t)ne + slot;
            }
            ch->encode_from_ptr = (const uint8_t *)at;
            ch->user_pixel_stride = stride * (int32_t)sizeof(float);
            ch->user_line_stride = w * stride * (int32_t)sizeof(float);
            ch->user_bytes_per_element = (int16_t)sizeof(float);
            ch->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (!enc.convert_and_pack_fn) rv = exr_encoding_choose_default_routines(ctx, part, &enc);
        if (rv == EXR_ERR_SUCCESS && enc.compress_fn && enc.compress_fn != image_exr_compress) {
            library.fn = enc.compress_fn;
            enc.compress_fn = image_exr_compress;
            enc.encoding_user_data = &library;
        }
        if (rv == EXR_ERR_SUCCESS) rv = exr_encoding_run(ctx, part, &enc);
    }
    if (live) exr_encoding_destroy(ctx, &enc);
    return rv;
}

CstStatus exr_write(FILE *fp, const char *path, const float *rgb, int w, int h, const ImageWriteOptions *opt,
                    CstError *err)
{
    if (w > IMAGE_MAX_WIDTH / (opt->extra_channels > 3 ? opt->extra_channels : 3) * 3)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: %d pixels is too wide for the EXR writer", path, w);
    ExrIo io = {fileno(fp), 0, {0}};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = image_exr_on_error;
    init.user_data = &io;
    init.write_fn = image_exr_write_fn; /* our temporary file, not the library's */

    ExrIo *outer = image_exr_sink;
    image_exr_sink = &io;
    exr_context_t ctx = NULL;
    int part = 0;
    static const char *const names[3] = {"R", "G", "B"};
    exr_result_t rv = exr_start_write(&ctx, path, EXR_WRITE_FILE_DIRECTLY, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_add_part(ctx, NULL, EXR_STORAGE_SCANLINE, &part);
    /* ZIP: lossless, 16 scanlines a chunk, readable by every EXR reader. */
    if (rv == EXR_ERR_SUCCESS) rv = exr_initialize_required_attr_simple(ctx, part, w, h, EXR_COMPRESSION_ZIP);
    for (int c = 0; c < 3 && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctx, part, names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LOGARITHMIC, 1, 1);
    for (int c = 0; c < opt->extra_channels && rv == EXR_ERR_SUCCESS; ++c)
        rv = exr_add_channel(ctx, part, opt->extra_names[c], EXR_PIXEL_FLOAT, EXR_PERCEPTUALLY_LINEAR, 1, 1);
    for (int i = 0; opt->out && i < opt->out->metadata_count && rv == EXR_ERR_SUCCESS; ++i)
        rv = exr_attr_set_string(ctx, part, opt->out->metadata[i].key, opt->out->metadata[i].value);
    if (rv == EXR_ERR_SUCCESS) rv = exr_write_header(ctx);
    if (rv == EXR_ERR_SUCCESS) rv = image_exr_encode(ctx, part, rgb, w, h, opt);
    if (ctx) {
        /* exr_finish also writes the chunk offset table, so its failure is a failed write. */
        exr_result_t rf = exr_finish(&ctx);
        if (rv == EXR_ERR_SUCCESS) rv = rf;
    }
    image_exr_sink = outer;
    if (rv == EXR_ERR_SUCCESS) return CST_OK;
    char buf[128];
    if (io.io_errno)
        return cst_fail(err, CST_ERR_IO, "%s: write failed: %s", path,
                        image_strerror(io.io_errno, buf, sizeof buf));
    if (rv == EXR_ERR_OUT_OF_MEMORY) return cst_fail(err, CST_ERR_OOM, "%s: out of memory writing EXR", path);
    return cst_fail(err, CST_ERR_INTERNAL, "%s: OpenEXR: %s", path,
                    io.msg[0] ? io.msg : exr_get_default_error_message(rv));
}

/* Where decoded pixels go: w x h texels of nch interleaved channels (R, G, B, or Y; A in
 * slot 3 when nch is 4), as floats or as halves. */
typedef struct ExrTarget {
    void *px;
    int nch;
    bool half, grey;
} ExrTarget;

/* The target slot of a channel: image_exr_slot's, and A in slot 3 of a four-channel one. */
static int image_exr_target_slot(const ExrTarget *t, const char *name)
{
    if (t->nch == 4 && name && strcmp(name, "A") == 0) return 3;
    return image_exr_slot(name, t->grey);
}

/* Decodes part 0 of an open context into the target, chunk by chunk: scanline blocks, or
 * level-0 tiles of a tiled file. */
static exr_result_t image_exr_decode(exr_context_t ctx, bool tiled, const exr_attr_box2i_t *dw,
                                     const ExrTarget *t, int w, int h)
{
    const int32_t esize = t->half ? 2 : (int32_t)sizeof(float);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    bool live = false;
    exr_result_t rv = EXR_ERR_SUCCESS;
    int32_t nx = 1, ny = 0, step_x = w, step_y = 0;
    if (tiled) {
        rv = exr_get_tile_sizes(ctx, 0, 0, 0, &step_x, &step_y);
        if (rv == EXR_ERR_SUCCESS && (step_x <= 0 || step_y <= 0)) rv = EXR_ERR_INVALID_ATTR;
        if (rv == EXR_ERR_SUCCESS) {
            nx = (int32_t)(((int64_t)w + step_x - 1) / step_x);
            ny = (int32_t)(((int64_t)h + step_y - 1) / step_y);
        }
    } else {
        rv = exr_get_scanlines_per_chunk(ctx, 0, &step_y);
        if (rv == EXR_ERR_SUCCESS && step_y <= 0) rv = EXR_ERR_INVALID_ATTR;
        if (rv == EXR_ERR_SUCCESS) ny = (int32_t)(((int64_t)h + step_y - 1) / step_y);
    }
    for (int32_t ty = 0; rv == EXR_ERR_SUCCESS && ty < ny; ++ty) {
        for (int32_t tx = 0; rv == EXR_ERR_SUCCESS && tx < nx; ++tx) {
            exr_chunk_info_t ci;
            int64_t x0, y0;
            if (tiled) {
                rv = exr_read_tile_chunk_info(ctx, 0, tx, ty, 0, 0, &ci);
                /* for tiles start_x/start_y are tile indices, not pixels */
                x0 = (int64_t)tx * step_x;
                y0 = (int64_t)ty * step_y;
            } else {
                rv = exr_read_scanline_chunk_info(ctx, 0, (int)(dw->min.y + (int64_t)ty * step_y), &ci);
                x0 = 0;
                y0 = (int64_t)ci.start_y - dw->min.y;
            }
            if (rv != EXR_ERR_SUCCESS) break;
            /* Never trust a chunk to stay inside the buffer. */
            if (x0 < 0 || y0 < 0 || ci.width < 0 || ci.height < 0 || x0 + ci.width > w ||
                y0 + ci.height > h) {
                rv = EXR_ERR_CORRUPT_CHUNK;
                break;
            }
            rv = live ? exr_decoding_update(ctx, 0, &ci, &dec) : exr_decoding_initialize(ctx, 0, &ci, &dec);
            if (rv != EXR_ERR_SUCCESS) break;
            live = true;
            uint8_t *first = (uint8_t *)t->px + ((size_t)y0 * (size_t)w + (size_t)x0) * (size_t)t->nch * (size_t)esize;
            for (int c = 0; c < dec.channel_count; ++c) {
                exr_coding_channel_info_t *ch = &dec.channels[c];
                int slot = image_exr_target_slot(t, ch->channel_name);
                if (slot < 0 || ch->x_samples != 1 || ch->y_samples != 1) {
                    ch->decode_to_ptr = NULL; /* skipped: alpha, depth, subsampled, ... */
                    continue;
                }
                ch->decode_to_ptr = first + (size_t)slot * (size_t)esize;
                ch->user_pixel_stride = t->nch * esize;
                ch->user_line_stride = w * t->nch * esize;
                ch->user_bytes_per_element = (int16_t)esize;
                /* to float: half and uint convert on unpack; to half: only half channels */
                ch->user_data_type = t->half ? EXR_PIXEL_HALF : EXR_PIXEL_FLOAT;
            }
            if (!dec.unpack_and_convert_fn) rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
            if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
        }
    }
    if (live) exr_decoding_destroy(ctx, &dec);
    return rv;
}

/* The reading itself, for the layer image_exr_layer names: the film's RGB floats (Y
 * replicated), or (texels) the file's own channels and storage as exr.h says. */
static CstStatus exr_read_current(FILE *fp, const char *path, bool texels, ExrImage *out, CstError *err)
{
    ExrIo io = {fileno(fp), 0, {0}};
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.error_handler_fn = image_exr_on_error;
    init.user_data = &io;
    init.read_fn = image_exr_read_fn;
    init.size_fn = image_exr_size_fn;
    init.flags = EXR_CONTEXT_FLAG_SILENT_HEADER_PARSE;

    ExrIo *outer = image_exr_sink;
    image_exr_sink = &io;
    exr_context_t ctx = NULL;
    void *px = NULL;
    CstStatus st = CST_OK;
    exr_storage_t storage = EXR_STORAGE_SCANLINE;
    exr_attr_box2i_t dw;
    memset(&dw, 0, sizeof dw);
    const exr_attr_chlist_t *chans = NULL;
    exr_result_t rv = exr_start_read(&ctx, path, &init);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_storage(ctx, 0, &storage);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_data_window(ctx, 0, &dw);
    if (rv == EXR_ERR_SUCCESS) rv = exr_get_channels(ctx, 0, &chans);
    if (rv != EXR_ERR_SUCCESS) {
        st = image_exr_status(err, path, &io, rv, "reading the OpenEXR header");
        goto done;
    }
    if (storage != EXR_STORAGE_SCANLINE && storage != EXR_STORAGE_TILED) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%s: deep OpenEXR images are not supported", path);
        goto done;
    }

    /* R, G and B at full resolution, or else a full-resolution Y for greyscale; texels
     * also keep a full-resolution A beside R, G, B, and stay halves if all they keep are. */
    int found = 0, found_y = 0, found_a = 0, half_rgb = 0, half_y = 0, half_a = 0;
    for (int i = 0; i < chans->num_channels; ++i) {
        const exr_attr_chlist_entry_t *e = &chans->entries[i];
        bool full = e->x_sampling == 1 && e->y_sampling == 1, half = e->pixel_type == EXR_PIXEL_HALF;
        bool rgb = full && image_exr_slot(e->name.str, false) >= 0, y = full && image_exr_slot(e->name.str, true) >= 0;
        bool a = full && !image_exr_layer && e->name.str && strcmp(e->name.str, "A") == 0;
        found += rgb, half_rgb += rgb && half;
        found_y += y, half_y += y && half;
        found_a += a, half_a += a && half;
    }
    bool grey = found < 3 && found_y == 1;
    if (found < 3 && !grey) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED,
                      "%s: OpenEXR image has no full-resolution R, G, B (or Y) channels", path);
        goto done;
    }

    int64_t w = (int64_t)dw.max.x - dw.min.x + 1, h = (int64_t)dw.max.y - dw.min.y + 1;
    if (w <= 0 || h <= 0 || !image_size_ok((uint64_t)w, (uint64_t)h)) {
        st = cst_fail(err, CST_ERR_PARSE, "%s: OpenEXR data window %lld x %lld is empty or too large",
                      path, (long long)w, (long long)h);
        goto done;
    }
    bool short_chunk = false; /* every chunk's header before the allocation (io/exr_chunks.h) */
    rv = exr_chunks_check(ctx, path, storage == EXR_STORAGE_TILED, &dw, (int)w, (int)h, &short_chunk, err);
    if (rv != EXR_ERR_SUCCESS) {
        st = short_chunk ? CST_ERR_PARSE : image_exr_status(err, path, &io, rv, "decoding OpenEXR pixels");
        goto done;
    }
    ExrTarget t = {NULL, 3, false, grey};
    if (texels) {
        t.nch = grey ? 1 : found_a == 1 ? 4 : 3;
        t.half = grey ? half_y == 1 : half_rgb == 3 && (t.nch == 3 || half_a == 1);
    }
    /* calloc: regions a lenient decoder skips read as black, not as heap garbage */
    px = t.px = calloc((size_t)(w * h) * (size_t)t.nch, t.half ? 2 : sizeof(float));
    if (!px) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %lld x %lld image", path,
                      (long long)w, (long long)h);
        goto done;
    }
    rv = image_exr_decode(ctx, storage == EXR_STORAGE_TILED, &dw, &t, (int)w, (int)h);
    if (rv != EXR_ERR_SUCCESS) {
        st = image_exr_status(err, path, &io, rv, "decoding OpenEXR pixels");
        goto done;
    }
    if (grey && !texels) {
        float *rgb = px;
        for (size_t i = 0; i < (size_t)(w * h); ++i) rgb[3 * i + 1] = rgb[3 * i + 2] = rgb[3 * i];
    }
    out->px = px;
    px = NULL;
    out->width = (int)w;
    out->height = (int)h;
    out->channels = t.nch;
    out->half = t.half;
done:
    if (ctx) exr_finish(&ctx);
    image_exr_sink = outer;
    free(px);
    return st;
}

CstStatus exr_read(FILE *fp, const char *path, const char *layer, float **out, int *w, int *h, CstError *err)
{
    const char *outer = image_exr_layer;
    image_exr_layer = layer && layer[0] ? layer : NULL;
    ExrImage im = {NULL, 0, 0, 0, false};
    CstStatus st = exr_read_current(fp, path, false, &im, err);
    image_exr_layer = outer;
    *out = im.px;
    *w = im.width;
    *h = im.height;
    return st;
}

CstStatus exr_read_texels(FILE *fp, const char *path, ExrImage *out, CstError *err)
{
    const char *outer = image_exr_layer;
    image_exr_layer = NULL;
    memset(out, 0, sizeof *out);
    CstStatus st = exr_read_current(fp, path, true, out, err);
    image_exr_layer = outer;
    return st;
}
