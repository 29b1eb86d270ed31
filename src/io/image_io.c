/* Image files: PNG (8-bit sRGB), OpenEXR and PFM (float, linear) writers chosen by extension
 * and committed atomically (temporary file, then rename); readers that sniff the format. */
#define _POSIX_C_SOURCE 200809L

#include "io/image_io.h"

#include "core/error.h"
#include "io/path.h"
#include "core/file.h"
#include "io/image_precheck.h"
#include "io/exr_chunks.h"
#include "io/image_stb.h"

#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <math.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

#include <openexr.h>
#include <png.h>

/* Encoders and decoders address rows with int32 byte strides (OpenEXR), 12 bytes a pixel. */
#define IMAGE_MAX_WIDTH (INT32_MAX / 12)

/* ---------------------------------------------------------------- small helpers */

/* strerror() may share one static buffer between threads; checkpoints are written while
 * render threads run, so use the reentrant (XSI) form. */
static const char *image_strerror(int e, char *buf, size_t n)
{
    if (strerror_r(e, buf, n) != 0) snprintf(buf, n, "error %d", e);
    return buf;
}

static CstStatus image_fail_errno(CstError *err, int e, const char *path, const char *what)
{
    char buf[128];
    return cst_fail(err, CST_ERR_IO, "%s: %s: %s", path, what, image_strerror(e, buf, sizeof buf));
}

bool image_size_ok(uint64_t w, uint64_t h)
{
    return w > 0 && h > 0 && w <= (uint64_t)IMAGE_MAX_WIDTH && w * h <= IMAGE_MAX_PIXELS;
}

/* Little-endian byte order written explicitly, so the files do not depend on the host. */
static void image_put_le32(uint8_t *p, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u);
    p[0] = (uint8_t)u;
    p[1] = (uint8_t)(u >> 8);
    p[2] = (uint8_t)(u >> 16);
    p[3] = (uint8_t)(u >> 24);
}

static float image_get_f32(const uint8_t *p, bool little_endian)
{
    uint32_t u = little_endian
        ? (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24
        : (uint32_t)p[3] | (uint32_t)p[2] << 8 | (uint32_t)p[1] << 16 | (uint32_t)p[0] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

/* ---------------------------------------------------------------- sRGB transfer curves */

float image_linear_to_srgb(float v)
{
    /* !(v > 0) also catches NaN, which must encode as black rather than reach the
     * quantiser; +inf falls into the v >= 1 branch. */
    if (!(v > 0.0f)) return 0.0f;
    if (v >= 1.0f) return 1.0f;
    /* IEC 61966-2-1: linear toe below 0.0031308, offset 1/2.4 power above. Evaluated in
     * double so 1.055 - 0.055 lands on exactly 1 and the two pieces meet at the knee. */
    double c = (double)v;
    double s = c <= 0.0031308 ? 12.92 * c : 1.055 * pow(c, 1.0 / 2.4) - 0.055;
    return (float)s;
}

float image_srgb_to_linear(double s)
{
    double c = s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4);
    return (float)c;
}

static uint8_t image_linear_byte(float v)
{
    float c = v > 0.0f ? (v < 1.0f ? v : 1.0f) : 0.0f; /* NaN -> 0 */
    return (uint8_t)(c * 255.0f + 0.5f);
}

static uint8_t image_srgb_byte(float v)
{
    return (uint8_t)(image_linear_to_srgb(v) * 255.0f + 0.5f);
}

/* ---------------------------------------------------------------- PFM */

/* Portable Float Map: "PF" (RGB) or "Pf" (grey), width, height, then a scale whose sign
 * gives the byte order (negative = little endian); rows are stored bottom to top. */
static CstStatus image_write_pfm(FILE *fp, const char *path, const float *rgb, int w, int h,
                                 const ImageWriteOptions *opt, CstError *err)
{
    (void)opt;
    size_t row_floats = (size_t)w * 3;
    uint8_t *row = malloc(row_floats * 4);
    if (!row) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d-pixel row", path, w);

    CstStatus st = CST_OK;
    if (fprintf(fp, "PF\n%d %d\n-1.0\n", w, h) < 0) st = image_fail_errno(err, errno, path, "write failed");
    for (int y = h - 1; st == CST_OK && y >= 0; --y) {
        const float *src = rgb + (size_t)y * row_floats;
        for (size_t i = 0; i < row_floats; ++i) image_put_le32(row + 4 * i, src[i]);
        if (fwrite(row, 4, row_floats, fp) != row_floats)
            st = image_fail_errno(err, errno, path, "write failed");
    }
    free(row);
    return st;
}

typedef struct PfmCursor {
    const uint8_t *p;
    size_t n, i;
} PfmCursor;

static bool pfm_is_space(uint8_t c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f';
}

/* Skips at least one whitespace character; false if there is none before the token. */
static bool pfm_skip_space(PfmCursor *c)
{
    size_t start = c->i;
    while (c->i < c->n && pfm_is_space(c->p[c->i])) c->i++;
    return c->i > start && c->i < c->n;
}

/* A positive decimal integer of at most 9 digits, ended by whitespace. */
static bool pfm_parse_dim(PfmCursor *c, uint64_t *out)
{
    uint64_t v = 0;
    size_t digits = 0;
    while (c->i < c->n && c->p[c->i] >= '0' && c->p[c->i] <= '9') {
        if (++digits > 9) return false;
        v = v * 10 + (uint64_t)(c->p[c->i++] - '0');
    }
    if (digits == 0 || c->i >= c->n || !pfm_is_space(c->p[c->i])) return false;
    *out = v;
    return true;
}

/* The scale: [+-]digits[.digits][(e|E)[+-]digits], non-zero, ended by whitespace. Only its
 * sign is used, so it is validated by hand rather than with the locale-dependent strtod. */
static bool pfm_parse_scale(PfmCursor *c, bool *negative)
{
    const uint8_t *p = c->p;
    size_t i = c->i;
    *negative = false;
    if (i < c->n && (p[i] == '+' || p[i] == '-')) *negative = p[i++] == '-';
    size_t mant = 0;
    bool nonzero = false, dot = false;
    for (; i < c->n && ((p[i] >= '0' && p[i] <= '9') || (p[i] == '.' && !dot)); ++i) {
        if (p[i] == '.') { dot = true; continue; }
        mant++;
        nonzero |= p[i] != '0';
    }
    if (mant == 0 || !nonzero) return false;
    if (i < c->n && (p[i] == 'e' || p[i] == 'E')) {
        ++i;
        if (i < c->n && (p[i] == '+' || p[i] == '-')) ++i;
        size_t exp_digits = 0;
        while (i < c->n && p[i] >= '0' && p[i] <= '9') { ++i; ++exp_digits; }
        if (exp_digits == 0) return false;
    }
    if (i >= c->n || !pfm_is_space(p[i])) return false;
    c->i = i;
    return true;
}

static CstStatus image_read_pfm(FILE *fp, const char *path, float **out, int *wout, int *hout,
                                CstError *err)
{
    /* "PF\n<w> <h>\n<scale>\n" is short; 128 bytes leave room for generous padding. */
    uint8_t hdr[128];
    if (fseek(fp, 0, SEEK_SET) != 0) return image_fail_errno(err, errno, path, "seek failed");
    size_t got = fread(hdr, 1, sizeof hdr, fp);
    if (ferror(fp)) return image_fail_errno(err, errno, path, "read failed");

    PfmCursor c = {hdr, got, 2};
    uint64_t w = 0, h = 0;
    bool negative = false;
    const char *what = NULL;
    if (got < 2 || hdr[0] != 'P' || (hdr[1] != 'F' && hdr[1] != 'f')) what = "missing \"PF\"/\"Pf\" magic";
    else if (!pfm_skip_space(&c) || !pfm_parse_dim(&c, &w)) what = "bad or missing width";
    else if (!pfm_skip_space(&c) || !pfm_parse_dim(&c, &h)) what = "bad or missing height";
    else if (!pfm_skip_space(&c) || !pfm_parse_scale(&c, &negative))
        what = "bad or missing scale (a non-zero number whose sign gives the byte order)";
    if (what) return cst_fail(err, CST_ERR_PARSE, "%s: malformed PFM header: %s", path, what);
    bool little = negative; /* a negative scale means little-endian floats */
    if (!image_size_ok(w, h))
        return cst_fail(err, CST_ERR_PARSE, "%s: PFM size %llu x %llu is zero or too large",
                        path, (unsigned long long)w, (unsigned long long)h);

    /* Exactly one whitespace character separates the header from the binary data, which
     * may itself start with bytes that look like whitespace. */
    size_t data_off = c.i + 1;
    size_t chans = hdr[1] == 'F' ? 3 : 1;
    size_t need = (size_t)(w * h) * chans * 4;

    struct stat sb;
    if (fstat(fileno(fp), &sb) != 0) return image_fail_errno(err, errno, path, "stat failed");
    uint64_t have = (uint64_t)sb.st_size > data_off ? (uint64_t)sb.st_size - data_off : 0;
    if (have < need)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: truncated PFM: %llu x %llu x %zu floats need %zu bytes of pixel data, "
                        "the file has %llu", path, (unsigned long long)w, (unsigned long long)h,
                        chans, need, (unsigned long long)have);

    uint8_t *data = malloc(need);
    float *rgb = malloc((size_t)(w * h) * 3 * sizeof *rgb);
    CstStatus st = CST_OK;
    if (!data || !rgb) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %llu x %llu image", path,
                      (unsigned long long)w, (unsigned long long)h);
    } else if (fseek(fp, (long)data_off, SEEK_SET) != 0) {
        st = image_fail_errno(err, errno, path, "seek failed");
    } else if (fread(data, 1, need, fp) != need) {
        st = ferror(fp) ? image_fail_errno(err, errno, path, "read failed")
                        : cst_fail(err, CST_ERR_PARSE, "%s: truncated PFM pixel data", path);
    }
    if (st != CST_OK) {
        free(data);
        free(rgb);
        return st;
    }

    /* File row r is image row h-1-r: PFM stores the bottom row first. */
    size_t row_in = (size_t)w * chans;
    for (size_t r = 0; r < h; ++r) {
        const uint8_t *src = data + r * row_in * 4;
        float *dst = rgb + (h - 1 - r) * (size_t)w * 3;
        for (size_t x = 0; x < w; ++x) {
            for (size_t k = 0; k < 3; ++k) {
                size_t ch = chans == 3 ? k : 0;
                dst[3 * x + k] = image_get_f32(src + 4 * (x * chans + ch), little);
            }
        }
    }
    free(data);
    *out = rgb;
    *wout = (int)w;
    *hout = (int)h;
    return CST_OK;
}

/* ---------------------------------------------------------------- PNG */

/* libpng reports errors by calling us and expecting a longjmp; the message is kept here. */
typedef struct PngIo {
    char msg[256];
    int saved_errno;
} PngIo;

static void image_png_on_error(png_structp png, png_const_charp msg)
{
    PngIo *io = png_get_error_ptr(png);
    io->saved_errno = errno;
    snprintf(io->msg, sizeof io->msg, "%s", msg ? msg : "unknown libpng error");
    png_longjmp(png, 1);
}

static void image_png_on_warning(png_structp png, png_const_charp msg)
{
    /* The library never prints; libpng warnings are about benign oddities. */
    (void)png;
    (void)msg;
}

typedef struct PngWriteJob {
    FILE *fp;
    const float *rgb;
    int w, h;
    uint8_t *row;
    bool linear; /* bytes are linear values, tagged gAMA 1.0, instead of sRGB */
    png_text *text; /* the metadata, one chunk each */
    int ntext;
} PngWriteJob;

/* setjmp lives in its own function: nothing the caller owns is modified after it, so
 * nothing is left indeterminate by the longjmp (C17 7.13.2.1). */
static bool image_png_write_body(png_structp png, png_infop info, const PngWriteJob *job)
{
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, job->fp);
    png_set_IHDR(png, info, (png_uint_32)job->w, (png_uint_32)job->h, 8, PNG_COLOR_TYPE_RGB,
                 PNG_INTERLACE_NONE, PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    /* The sRGB chunk tells viewers how the bytes were encoded; the gAMA and cHRM values
     * that go with it help decoders that predate sRGB (PNG spec 11.3.3.5). */
    if (job->linear) png_set_gAMA(png, info, 1.0);
    else png_set_sRGB_gAMA_and_cHRM(png, info, PNG_sRGB_INTENT_PERCEPTUAL);
    if (job->ntext > 0) png_set_text(png, info, job->text, job->ntext);
    png_write_info(png, info);
    size_t row_floats = (size_t)job->w * 3;
    for (int y = 0; y < job->h; ++y) {
        const float *src = job->rgb + (size_t)y * row_floats;
        for (size_t i = 0; i < row_floats; ++i)
            job->row[i] = job->linear ? image_linear_byte(src[i]) : image_srgb_byte(src[i]);
        png_write_row(png, job->row);
    }
    png_write_end(png, NULL);
    return true;
}

/* One metadata entry as a text chunk: tEXt (Latin-1, here printable ASCII and line feeds)
 * when the value allows it, else iTXt, which holds UTF-8 (PNG spec 11.3.4). libpng copies
 * the strings, so they are passed as they are. */
static void image_png_text(png_text *t, const CstImageMetadata *m)
{
    bool plain = true;
    for (const char *c = m->value; *c && plain; ++c)
        plain = (*c >= 0x20 && *c < 0x7f) || *c == '\n';
    t->compression = plain ? PNG_TEXT_COMPRESSION_NONE : PNG_ITXT_COMPRESSION_NONE;
    t->key = (png_charp)(uintptr_t)m->key;
    t->text = (png_charp)(uintptr_t)m->value;
    t->text_length = strlen(m->value);
}

static CstStatus image_write_png(FILE *fp, const char *path, const float *rgb, int w, int h,
                                 const ImageWriteOptions *opt, CstError *err)
{
    /* libpng's default limit; checked here so it reads as a limit, not an internal error */
    if (w > PNG_USER_WIDTH_MAX || h > PNG_USER_HEIGHT_MAX)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: %d x %d exceeds the PNG writer's limit of %d per side",
                        path, w, h, (int)PNG_USER_WIDTH_MAX);
    PngIo io = {{0}, 0};
    int ntext = opt->out ? opt->out->metadata_count : 0;
    PngWriteJob job = {fp, rgb, w, h, malloc((size_t)w * 3), opt->png_linear,
                       ntext > 0 ? calloc((size_t)ntext, sizeof(png_text)) : NULL, ntext};
    for (int i = 0; job.text && i < ntext; ++i) image_png_text(&job.text[i], &opt->out->metadata[i]);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, &io, image_png_on_error,
                                              image_png_on_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    CstStatus st = CST_OK;
    if (!job.row || !info || (ntext > 0 && !job.text)) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory starting the PNG encoder", path);
    } else if (!image_png_write_body(png, info, &job)) {
        char buf[128];
        st = ferror(fp) ? cst_fail(err, CST_ERR_IO, "%s: write failed: %s", path,
                                   image_strerror(io.saved_errno, buf, sizeof buf))
                        : cst_fail(err, CST_ERR_INTERNAL, "%s: libpng: %s", path, io.msg);
    }
    png_destroy_write_struct(&png, &info);
    free(job.row);
    free(job.text);
    return st;
}

typedef struct PngReadJob {
    FILE *fp;
    png_bytep raw;   /* decoded rows, 3 samples a pixel; freed by the caller */
    png_bytep *rows; /* pointers into raw; freed by the caller */
    uint32_t w, h;
    int depth;       /* 8 or 16 after the transforms */
    bool too_big, oom;
} PngReadJob;

static bool image_png_read_body(png_structp png, png_infop info, PngReadJob *job)
{
    if (setjmp(png_jmpbuf(png))) return false;
    png_init_io(png, job->fp);
    png_set_sig_bytes(png, 8);
    png_read_info(png, info);

    png_uint_32 w = 0, h = 0;
    int depth = 0, color = 0;
    png_get_IHDR(png, info, &w, &h, &depth, &color, NULL, NULL, NULL);
    if (!image_size_ok(w, h)) {
        job->w = w;
        job->h = h;
        job->too_big = true;
        return false;
    }
    /* Everything becomes 3 samples of 8 or 16 bits: palettes and low-depth grey expand,
     * grey replicates, alpha is dropped (a film has no coverage to composite against). */
    if (color == PNG_COLOR_TYPE_PALETTE) png_set_palette_to_rgb(png);
    if (color == PNG_COLOR_TYPE_GRAY && depth < 8) png_set_expand_gray_1_2_4_to_8(png);
    if (color & PNG_COLOR_MASK_ALPHA) png_set_strip_alpha(png);
    if (color == PNG_COLOR_TYPE_GRAY || color == PNG_COLOR_TYPE_GRAY_ALPHA) png_set_gray_to_rgb(png);
    png_set_interlace_handling(png);
    png_read_update_info(png, info);

    int out_depth = png_get_bit_depth(png, info);
    if (png_get_channels(png, info) != 3 || (out_depth != 8 && out_depth != 16))
        png_error(png, "unexpected pixel layout after conversion to RGB");
    size_t rowbytes = png_get_rowbytes(png, info);
    if (rowbytes < (size_t)w * 3 * (size_t)(out_depth / 8))
        png_error(png, "row size smaller than the image width");

    job->raw = malloc(rowbytes * h);
    job->rows = malloc(sizeof *job->rows * h);
    if (!job->raw || !job->rows) {
        job->oom = true;
        return false;
    }
    for (png_uint_32 y = 0; y < h; ++y) job->rows[y] = job->raw + (size_t)y * rowbytes;
    png_read_image(png, job->rows);
    png_read_end(png, NULL);
    job->w = w;
    job->h = h;
    job->depth = out_depth;
    return true;
}

static CstStatus image_read_png(FILE *fp, const char *path, float **out, int *wout, int *hout,
                                CstError *err)
{
    PngIo io = {{0}, 0};
    PngReadJob job = {0};
    job.fp = fp;
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, &io, image_png_on_error,
                                             image_png_on_warning);
    png_infop info = png ? png_create_info_struct(png) : NULL;
    float *rgb = NULL;
    CstStatus st = CST_OK;
    if (!info) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory starting the PNG decoder", path);
    } else if (fseek(fp, 8, SEEK_SET) != 0) {
        st = image_fail_errno(err, errno, path, "seek failed");
    } else if (!image_png_read_body(png, info, &job)) {
        char buf[128];
        if (job.too_big)
            st = cst_fail(err, CST_ERR_PARSE, "%s: PNG size %u x %u is zero or too large", path,
                          (unsigned)job.w, (unsigned)job.h);
        else if (job.oom)
            st = cst_fail(err, CST_ERR_OOM, "%s: out of memory decoding the PNG", path);
        else if (ferror(fp))
            st = cst_fail(err, CST_ERR_IO, "%s: read failed: %s", path,
                          image_strerror(io.saved_errno, buf, sizeof buf));
        else
            st = cst_fail(err, CST_ERR_PARSE, "%s: malformed PNG: %s", path, io.msg);
    } else if (!(rgb = malloc((size_t)job.w * job.h * 3 * sizeof *rgb))) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %u x %u image", path,
                      (unsigned)job.w, (unsigned)job.h);
    } else {
        /* The samples are sRGB-encoded; 8-bit values go through a 256-entry table. */
        float lut[256];
        for (int i = 0; i < 256; ++i) lut[i] = image_srgb_to_linear(i / 255.0);
        size_t n = (size_t)job.w * 3;
        for (uint32_t y = 0; y < job.h; ++y) {
            const png_byte *src = job.rows[y];
            float *dst = rgb + (size_t)y * n;
            if (job.depth == 8) {
                for (size_t i = 0; i < n; ++i) dst[i] = lut[src[i]];
            } else {
                for (size_t i = 0; i < n; ++i) /* PNG samples are big endian */
                    dst[i] = image_srgb_to_linear(((unsigned)src[2 * i] << 8 | src[2 * i + 1]) / 65535.0);
            }
        }
        *out = rgb;
        *wout = (int)job.w;
        *hout = (int)job.h;
    }
    png_destroy_read_struct(&png, &info, NULL);
    free(job.rows);
    free(job.raw);
    return st;
}

/* ---------------------------------------------------------------- OpenEXR */

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
 * greyscale, "Y" lands in slot 0 and is replicated afterwards. */
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

static CstStatus image_write_exr(FILE *fp, const char *path, const float *rgb, int w, int h,
                                 const ImageWriteOptions *opt, CstError *err)
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

/* Decodes part 0 of an open context into rgb (w x h, interleaved), chunk by chunk:
 * scanline blocks, or level-0 tiles of a tiled file. */
static exr_result_t image_exr_decode(exr_context_t ctx, bool tiled, bool grey,
                                     const exr_attr_box2i_t *dw, float *rgb, int w, int h)
{
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
            float *first = rgb + ((size_t)y0 * (size_t)w + (size_t)x0) * 3;
            for (int c = 0; c < dec.channel_count; ++c) {
                exr_coding_channel_info_t *ch = &dec.channels[c];
                int slot = image_exr_slot(ch->channel_name, grey);
                if (slot < 0 || ch->x_samples != 1 || ch->y_samples != 1) {
                    ch->decode_to_ptr = NULL; /* skipped: alpha, depth, subsampled, ... */
                    continue;
                }
                ch->decode_to_ptr = (uint8_t *)(first + slot);
                ch->user_pixel_stride = 3 * (int32_t)sizeof(float);
                ch->user_line_stride = w * 3 * (int32_t)sizeof(float);
                ch->user_bytes_per_element = (int16_t)sizeof(float);
                ch->user_data_type = EXR_PIXEL_FLOAT; /* half and uint convert on unpack */
            }
            if (!dec.unpack_and_convert_fn) rv = exr_decoding_choose_default_routines(ctx, 0, &dec);
            if (rv == EXR_ERR_SUCCESS) rv = exr_decoding_run(ctx, 0, &dec);
        }
    }
    if (live) exr_decoding_destroy(ctx, &dec);
    return rv;
}

static CstStatus image_read_exr(FILE *fp, const char *path, float **out, int *wout, int *hout,
                                CstError *err)
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
    float *rgb = NULL;
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

    /* R, G and B at full resolution, or else a full-resolution Y for greyscale. */
    int found = 0, found_y = 0;
    for (int i = 0; i < chans->num_channels; ++i) {
        const exr_attr_chlist_entry_t *e = &chans->entries[i];
        bool full = e->x_sampling == 1 && e->y_sampling == 1;
        found += full && image_exr_slot(e->name.str, false) >= 0;
        found_y += full && image_exr_slot(e->name.str, true) >= 0;
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
    /* calloc: regions a lenient decoder skips read as black, not as heap garbage */
    rgb = calloc((size_t)(w * h) * 3, sizeof *rgb);
    if (!rgb) {
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %lld x %lld image", path,
                      (long long)w, (long long)h);
        goto done;
    }
    rv = image_exr_decode(ctx, storage == EXR_STORAGE_TILED, grey, &dw, rgb, (int)w, (int)h);
    if (rv != EXR_ERR_SUCCESS) {
        st = image_exr_status(err, path, &io, rv, "decoding OpenEXR pixels");
        goto done;
    }
    if (grey) {
        for (size_t i = 0; i < (size_t)(w * h); ++i) rgb[3 * i + 1] = rgb[3 * i + 2] = rgb[3 * i];
    }
    *out = rgb;
    rgb = NULL;
    *wout = (int)w;
    *hout = (int)h;
done:
    if (ctx) exr_finish(&ctx);
    image_exr_sink = outer;
    free(rgb);
    return st;
}

/* ---------------------------------------------------------------- dispatch */

typedef CstStatus (*ImageWriteFn)(FILE *fp, const char *path, const float *rgb, int w, int h,
                                  const ImageWriteOptions *opt, CstError *err);

typedef struct ImageWriter {
    ImageFileFormat format;
    ImageWriteFn write;
} ImageWriter;

static const ImageWriter image_writers[] = {
    {IMAGE_FILE_PNG, image_write_png},
    {IMAGE_FILE_EXR, image_write_exr},
    {IMAGE_FILE_PFM, image_write_pfm},
};
#define IMAGE_SUPPORTED "supported: .png, .exr, .pfm"

/* ASCII case folding; the locale must not change which writer a path selects. */
static bool image_ext_equal(const char *ext, const char *lower)
{
    for (; *ext && *lower; ++ext, ++lower) {
        char c = *ext >= 'A' && *ext <= 'Z' ? (char)(*ext - 'A' + 'a') : *ext;
        if (c != *lower) return false;
    }
    return *ext == '\0' && *lower == '\0';
}

/* The extension of the last path component, without the dot, or NULL. */
static const char *image_path_ext(const char *path)
{
    const char *base = strrchr(path, '/');
    base = base ? base + 1 : path;
    const char *dot = strrchr(base, '.');
    return dot && dot[1] ? dot + 1 : NULL;
}

/* Every extension an image file may have, and its format. */
static const struct { const char *ext; ImageFileFormat format; } exts[] = {
    {"png", IMAGE_FILE_PNG}, {"jpg", IMAGE_FILE_JPEG}, {"jpeg", IMAGE_FILE_JPEG},
    {"bmp", IMAGE_FILE_BMP}, {"tga", IMAGE_FILE_TGA},  {"hdr", IMAGE_FILE_HDR},
    {"exr", IMAGE_FILE_EXR}, {"pfm", IMAGE_FILE_PFM}};

const char *image_writable_extension(int index)
{
    for (size_t i = 0; i < sizeof exts / sizeof exts[0]; ++i)
        if (image_format_is_writable(exts[i].format) && index-- == 0) return exts[i].ext;
    return NULL;
}

ImageFileFormat image_format_from_path(const char *path)
{
    const char *ext = path ? image_path_ext(path) : NULL;
    for (size_t i = 0; ext && i < sizeof exts / sizeof exts[0]; ++i)
        if (image_ext_equal(ext, exts[i].ext)) return exts[i].format;
    return IMAGE_FILE_NONE;
}

bool image_format_is_writable(ImageFileFormat f)
{
    return f == IMAGE_FILE_PNG || f == IMAGE_FILE_EXR || f == IMAGE_FILE_PFM;
}

bool image_path_is_scene_output(const char *path)
{
    const char *ext = image_path_ext(path);
    return image_format_is_writable(image_format_from_path(path)) && ext - 1 > path;
}

bool image_format_is_float(ImageFileFormat f)
{
    return f == IMAGE_FILE_HDR || f == IMAGE_FILE_EXR || f == IMAGE_FILE_PFM;
}

bool image_path_is_exr(const char *path)
{
    return image_format_from_path(path) == IMAGE_FILE_EXR;
}

/* ---------------------------------------------------------------- metadata */

/* Well-formed UTF-8 (RFC 3629: no overlong forms, no surrogates, at most U+10FFFF). */
static bool image_utf8_valid(const char *s)
{
    const uint8_t *p = (const uint8_t *)s;
    while (*p) {
        uint32_t c = *p++;
        int more = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2 : (c & 0xf8) == 0xf0 ? 3 : -1;
        if (more < 0) return false;
        c &= 0x7fu >> more;
        for (int i = 0; i < more; ++i, ++p) {
            if ((*p & 0xc0) != 0x80) return false;
            c = c << 6 | (*p & 0x3fu);
        }
        static const uint32_t least[4] = {0, 0x80, 0x800, 0x10000};
        if (c < least[more] || c > 0x10ffff || (c >= 0xd800 && c <= 0xdfff)) return false;
    }
    return true;
}

/* The public header's rules for metadata (caustic.h, CstImageMetadata). */
static CstStatus image_metadata_check(const char *path, const CstImageWriteOptions *o, CstError *err)
{
    /* EXR's own header attributes (OpenEXR file layout, "Header Attributes"). */
    static const char *const reserved[] = {
        "channels", "compression", "dataWindow", "displayWindow", "lineOrder", "pixelAspectRatio",
        "screenWindowCenter", "screenWindowWidth", "tiles", "type", "name", "version",
        "chunkCount", "view", "multiView"};
    if (!o) return CST_OK;
    if (o->metadata_count < 0 || o->metadata_count > 256 || (o->metadata_count > 0 && !o->metadata))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d metadata entries (expected 0 to 256 with a list)",
                        path, o->metadata_count);
    for (int i = 0; i < o->metadata_count; ++i) {
        const char *k = o->metadata[i].key, *v = o->metadata[i].value;
        size_t n = k ? strspn(k, "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789._-") : 0;
        if (!k || n == 0 || n > 31 || k[n])
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: metadata key \"%s\": expected 1 to 31 of "
                            "A-Z a-z 0-9 . _ -", path, k ? k : "(null)");
        for (size_t r = 0; r < sizeof reserved / sizeof reserved[0]; ++r)
            if (strcmp(k, reserved[r]) == 0)
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: metadata key \"%s\" is an EXR header "
                                "attribute of its own", path, k);
        for (int j = 0; j < i; ++j)
            if (strcmp(k, o->metadata[j].key) == 0)
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: metadata key \"%s\" given twice", path, k);
        if (!v || !image_utf8_valid(v))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: metadata \"%s\": the value is %s", path, k,
                            v ? "not valid UTF-8" : "NULL");
    }
    return CST_OK;
}

/* ---------------------------------------------------------------- writing */

/* The writer for `path`'s extension in *out, or the error. */
static CstStatus image_writer_for(const char *path, const ImageWriter **out, CstError *err)
{
    ImageFileFormat format = image_format_from_path(path);
    for (size_t i = 0; i < sizeof image_writers / sizeof image_writers[0]; ++i)
        if (image_writers[i].format == format) {
            *out = &image_writers[i];
            return CST_OK;
        }
    const char *ext = image_path_ext(path);
    if (!ext)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "%s: no file extension to choose an image format (" IMAGE_SUPPORTED ")", path);
    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown image extension \".%s\" (" IMAGE_SUPPORTED ")",
                    path, ext);
}

CstStatus image_write_check(const char *path, CstError *err)
{
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "image_write: empty path");
    const ImageWriter *fmt;
    CstStatus st = image_writer_for(path, &fmt, err);
    if (st != CST_OK) return st;
    struct stat sb;
    int r = stat(path, &sb);
    if (r == 0 && S_ISDIR(sb.st_mode)) return cst_fail(err, CST_ERR_IO, "%s: is a directory", path);
    if (r != 0 && errno == ENAMETOOLONG) return image_fail_errno(err, errno, path, "cannot write");
    /* The temporary file is where a name too long, a read-only or pseudo file system
     * (/proc, /sys) or a missing permission shows: make it exactly as the write will. */
    char *tmp = NULL;
    int fd = -1;
    st = path_temp_create(path, NULL, NULL, &tmp, &fd, err);
    if (st != CST_OK) return st;
    close(fd);
    unlink(tmp);
    free(tmp);
    return CST_OK;
}

CstStatus image_write(const char *path, const float *rgb, int width, int height, CstError *err)
{
    static const ImageWriteOptions plain;
    return image_write_opt(path, rgb, width, height, &plain, err);
}

/* Encodes into the open temporary file and moves it into place. */
static CstStatus image_write_temp(FILE *fp, const char *tmp, const char *path, const ImageWriter *fmt,
                                  const float *rgb, int width, int height,
                                  const ImageWriteOptions *opt, CstError *err)
{
    CstStatus st = fmt->write(fp, path, rgb, width, height, opt, err);
    if (st == CST_OK && fflush(fp) != 0) st = image_fail_errno(err, errno, path, "write failed");
    /* Data on disk before the rename: otherwise a crash right after it can leave an
     * empty file under the final name on some filesystems. */
    if (st == CST_OK && fsync(fileno(fp)) != 0 && errno != EINVAL)
        st = image_fail_errno(err, errno, path, "fsync failed");
    if (fclose(fp) != 0 && st == CST_OK) st = image_fail_errno(err, errno, path, "write failed");
    if (st == CST_OK && rename(tmp, path) != 0)
        st = image_fail_errno(err, errno, path, "cannot move the temporary file into place");
    return st;
}

CstStatus image_write_opt(const char *path, const float *rgb, int width, int height,
                          const ImageWriteOptions *opt, CstError *err)
{
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "image_write: empty path");
    if (!rgb || width <= 0 || height <= 0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: invalid image (%d x %d%s)", path, width,
                        height, rgb ? "" : ", no pixels");
    const ImageWriter *fmt;
    CstStatus st = image_writer_for(path, &fmt, err);
    if (st != CST_OK) return st;
    if (opt->extra_channels > 0 && fmt->write != image_write_exr)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: extra channels need an .exr output", path);
    if (opt->extra_channels < 0 || opt->extra_channels > IMAGE_MAX_EXTRA)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d extra channels (at most %d)", path,
                        opt->extra_channels, IMAGE_MAX_EXTRA);
    st = image_metadata_check(path, opt->out, err);
    if (st != CST_OK) return st;

    path_temp_remove_stale(path);
    CstTempFileFn told = opt->out ? opt->out->temp_file : NULL;
    void *user = opt->out ? opt->out->temp_file_user : NULL;
    char *tmp = NULL;
    int fd = -1;
    st = path_temp_create(path, told, user, &tmp, &fd, err);
    if (st != CST_OK) return st;
    FILE *fp = fdopen(fd, "wb");
    if (!fp) {
        st = image_fail_errno(err, errno, path, "cannot open temporary file");
        close(fd);
    } else {
        st = image_write_temp(fp, tmp, path, fmt, rgb, width, height, opt, err);
    }
    if (st != CST_OK) unlink(tmp);
    if (told) told(user, NULL);
    free(tmp);
    return st;
}

/* A Radiance HDR file through stb_image, after the pre-check (io/image_precheck.h): linear
 * floats as stored. */
static CstStatus image_read_rgbe(const char *path, float **out, int *wout, int *hout, CstError *err)
{
    char *bytes = NULL;
    size_t size = 0;
    CstStatus st = file_read_all(path, &bytes, &size, err);
    if (st != CST_OK) return st;
    int dw = 0, dh = 0, w = 0, h = 0;
    st = image_precheck_stb(path, (const unsigned char *)bytes, size, &dw, &dh, err);
    if (st == CST_OK) {
        float *px = image_stb_load((const unsigned char *)bytes, (int)size, 32, &w, &h);
        if (!px)
            st = cst_fail(err, CST_ERR_PARSE, "%s: cannot decode the Radiance HDR image (%s)", path,
                          image_stb_failure_reason());
        else {
            *out = px;
            *wout = w;
            *hout = h;
        }
    }
    free(bytes);
    return st;
}

CstStatus image_read(const char *path, float **rgb, int *width, int *height, CstError *err)
{
    if (!rgb || !width || !height)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image_read: NULL output argument");
    *rgb = NULL;
    *width = *height = 0;
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "image_read: empty path");

    FILE *fp = NULL;
    CstStatus st = file_open_input(path, &fp, NULL, err); /* regular files only, bounded */
    if (st != CST_OK) return st;
    uint8_t magic[8] = {0};
    size_t got = 0;
    if ((got = fread(magic, 1, sizeof magic, fp)) == 0 && ferror(fp))
        st = image_fail_errno(err, errno, path, "read failed");
    else if (got == 0) st = cst_fail(err, CST_ERR_PARSE, "%s: empty file", path);
    if (st != CST_OK) {
        fclose(fp);
        return st;
    }

    /* Formats are recognised by content, so a misnamed file still reads correctly. */
    if (got == 8 && png_sig_cmp(magic, 0, 8) == 0)
        st = image_read_png(fp, path, rgb, width, height, err);
    else if (got >= 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01)
        st = image_read_exr(fp, path, rgb, width, height, err);
    else if (got >= 2 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f'))
        st = image_read_pfm(fp, path, rgb, width, height, err);
    else if (got >= 2 && magic[0] == '#' && magic[1] == '?') /* #?RADIANCE, #?RGBE */
        st = image_read_rgbe(path, rgb, width, height, err);
    else
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%s: not a PNG, OpenEXR, PFM or Radiance HDR file", path);
    fclose(fp);
    return st;
}

CstStatus image_read_layer(const char *path, const char *layer, float **rgb, int *width, int *height,
                           CstError *err)
{
    if (!layer || !layer[0]) return image_read(path, rgb, width, height, err);
    if (!rgb || !width || !height || !path)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image_read_layer: NULL argument");
    *rgb = NULL;
    *width = *height = 0;
    FILE *fp = NULL;
    CstStatus st = file_open_input(path, &fp, NULL, err);
    if (st != CST_OK) return st;
    uint8_t magic[4] = {0};
    if (fread(magic, 1, sizeof magic, fp) != 4 || magic[0] != 0x76 || magic[1] != 0x2f || magic[2] != 0x31 ||
        magic[3] != 0x01) {
        fclose(fp);
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: not an OpenEXR file (only EXR images have a \"%s\" "
                        "layer)", path, layer);
    }
    const char *outer = image_exr_layer;
    image_exr_layer = layer;
    st = image_read_exr(fp, path, rgb, width, height, err);
    image_exr_layer = outer;
    fclose(fp);
    if (st == CST_ERR_UNSUPPORTED)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: no full-resolution %s.R, %s.G, %s.B channels", path,
                        layer, layer, layer);
    return st;
}

CstStatus cst_image_read_layer(const char *path, const char *layer, float **rgb, int *width, int *height,
                               CstError *err)
{
    return image_read_layer(path, layer, rgb, width, height, err);
}

/* ---------------------------------------------------------------- radiance inputs */

CstStatus image_check_radiance(const float *rgb, int width, int height, const char *what, CstError *err)
{
    static const char channel[3] = {'R', 'G', 'B'};
    size_t n = 3u * (size_t)(width > 0 ? width : 0) * (size_t)(height > 0 ? height : 0);
    for (size_t i = 0; i < n; i++) {
        float v = rgb[i];
        if (isfinite(v) && v >= 0.0f) continue;
        size_t px = i / 3, w = (size_t)width;
        return cst_fail(err, CST_ERR_INVALID_ARG, "%.300s: pixel (%zu, %zu) channel %c is %g; expected a "
                        "finite value >= 0 (x from the left, y from the top row)", what ? what : "image",
                        px % w, px / w, channel[i % 3], (double)v);
    }
    return CST_OK;
}

CstStatus image_read_radiance(const char *path, float **rgb, int *width, int *height, CstError *err)
{
    CstStatus st = image_read(path, rgb, width, height, err);
    if (st != CST_OK) return st;
    if ((st = image_check_radiance(*rgb, *width, *height, path, err)) != CST_OK) {
        free(*rgb);
        *rgb = NULL;
        *width = *height = 0;
    }
    return st;
}
