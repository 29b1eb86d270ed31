/* Image files: PNG (8-bit sRGB), OpenEXR and PFM (float, linear) writers chosen by extension
 * and committed atomically (temporary file, then rename); readers that sniff the format. */
#define _POSIX_C_SOURCE 200809L

#include "io/image_io.h"

#include "core/error.h"
#include "io/path.h"
#include "core/file.h"
#include "io/image_precheck.h"
#include "io/exr.h"
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

#include <png.h>

/* ---------------------------------------------------------------- small helpers */

/* strerror() may share one static buffer between threads; checkpoints are written while
 * render threads run, so use the reentrant (XSI) form. */
const char *image_strerror(int e, char *buf, size_t n)
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

/* ---------------------------------------------------------------- dispatch */

typedef CstStatus (*ImageWriteFn)(FILE *fp, const char *path, const float *rgb, int w, int h,
                                  const ImageWriteOptions *opt, CstError *err);

typedef struct ImageWriter {
    ImageFileFormat format;
    ImageWriteFn write;
} ImageWriter;

static const ImageWriter image_writers[] = {
    {IMAGE_FILE_PNG, image_write_png},
    {IMAGE_FILE_EXR, exr_write},
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
    if (opt->extra_channels > 0 && fmt->write != exr_write)
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
        st = exr_read(fp, path, NULL, rgb, width, height, err);
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
    st = exr_read(fp, path, layer, rgb, width, height, err);
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
