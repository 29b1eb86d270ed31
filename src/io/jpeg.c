/* JPEG decoding through libjpeg-turbo (docs/fuzzing.md: stb_image 2.27's JPEG reader shifted
 * by more than 31 bits on a corrupt scan). libjpeg reports errors through error_exit, which
 * must not return; here it longjmps back to the call, which turns the message into a
 * CstError, so no input reaches libjpeg's default exit(). */
#include "io/jpeg.h"

#include <setjmp.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h> /* jpeglib.h needs FILE and size_t declared first */
#include <stdlib.h>
#include <string.h>

#include <jpeglib.h>
#include <jerror.h> /* after jpeglib.h: its message list depends on jconfig.h */

#include "core/error.h"

/* libjpeg's error manager, extended with the way back and the first message. */
typedef struct JpegFail {
    struct jpeg_error_mgr pub; /* first: libjpeg passes &pub as cinfo->err */
    jmp_buf back;
    char msg[JMSG_LENGTH_MAX];
    size_t at; /* the failure is at or after this byte (jpeg_offset) */
} JpegFail;

/* A JpegFail, the decoder and the bytes it reads: one decode's state. */
typedef struct JpegRead {
    struct jpeg_decompress_struct cinfo;
    JpegFail fail;
    struct jpeg_progress_mgr progress;
    const unsigned char *data;
    size_t size;
} JpegRead;

/* How far into the file libjpeg's source stands: jpeg_mem_src points into our bytes until
 * they run out, then at a fake EOI of its own (so only equality with our buffer is tested).
 * The entropy decoder reads ahead on a copy and writes its position back after each MCU, so
 * inside a scan the fault is at or after this byte (the file's size at its end). */
static size_t jpeg_offset(const JpegRead *r)
{
    const struct jpeg_source_mgr *src = r->cinfo.src;
    if (!src || src->bytes_in_buffer > r->size) return r->size;
    size_t at = r->size - src->bytes_in_buffer;
    return src->next_input_byte == r->data + at ? at : r->size;
}

static void jpeg_leave(j_common_ptr cinfo)
{
    JpegFail *f = (JpegFail *)cinfo->err;
    JpegRead *r = (JpegRead *)(void *)((char *)f - offsetof(JpegRead, fail));
    (*cinfo->err->format_message)(cinfo, f->msg);
    f->at = jpeg_offset(r);
    longjmp(f->back, 1);
}

/* Replaces error_exit (whose default prints and calls exit()). */
static void jpeg_error_exit(j_common_ptr cinfo) { jpeg_leave(cinfo); }

/* Warnings (level -1) that mean the data is corrupt end the decode: libjpeg would go on and
 * fill what it cannot read with grey or with a guess. The others (an unknown JFIF version or
 * Adobe transform code, messages meant for encoders) are ignored, as are trace messages. */
static void jpeg_emit_message(j_common_ptr cinfo, int level)
{
    if (level >= 0) return;
    switch (cinfo->err->msg_code) {
    case JWRN_ARITH_BAD_CODE:
    case JWRN_BOGUS_PROGRESSION:
    case JWRN_EXTRANEOUS_DATA:
    case JWRN_HIT_MARKER:
    case JWRN_HUFF_BAD_CODE:
    case JWRN_JPEG_EOF:
    case JWRN_MUST_RESYNC:
    case JWRN_NOT_SEQUENTIAL: jpeg_leave(cinfo); break;
    default: break;
    }
}

/* Called by libjpeg between scans and row groups: refuses the JPEG_MAX_SCANS + 1-th scan. */
static void jpeg_progress(j_common_ptr cinfo)
{
    j_decompress_ptr d = (j_decompress_ptr)cinfo;
    if (d->progressive_mode && d->input_scan_number > JPEG_MAX_SCANS) {
        JpegFail *f = (JpegFail *)cinfo->err;
        JpegRead *r = (JpegRead *)(void *)((char *)f - offsetof(JpegRead, fail));
        snprintf(f->msg, sizeof f->msg, "a progressive JPEG of more than %d scans", JPEG_MAX_SCANS);
        f->at = jpeg_offset(r);
        longjmp(f->back, 1);
    }
}

/* Sets up r to read data (the caller setjmps before anything can fail). */
static void jpeg_begin(JpegRead *r, const unsigned char *data, size_t size)
{
    memset(r, 0, sizeof *r);
    r->data = data;
    r->size = size;
    r->cinfo.err = jpeg_std_error(&r->fail.pub);
    r->fail.pub.error_exit = jpeg_error_exit;
    r->fail.pub.emit_message = jpeg_emit_message;
    r->progress.progress_monitor = jpeg_progress;
}

static CstStatus jpeg_failed(JpegRead *r, const char *path, CstError *err)
{
    jpeg_destroy_decompress(&r->cinfo);
    return cst_fail(err, CST_ERR_PARSE, "%s: cannot decode the JPEG (libjpeg-turbo, at or after byte %zu): %s", path,
                    r->fail.at, r->fail.msg);
}

CstStatus jpeg_info(const char *path, const unsigned char *data, size_t size, int *width, int *height,
                    CstError *err)
{
    JpegRead r;
    jpeg_begin(&r, data, size);
    if (setjmp(r.fail.back)) return jpeg_failed(&r, path, err);
    jpeg_create_decompress(&r.cinfo);
    r.cinfo.progress = &r.progress;
    jpeg_mem_src(&r.cinfo, data, (unsigned long)size);
    jpeg_read_header(&r.cinfo, TRUE);
    *width = (int)r.cinfo.image_width;
    *height = (int)r.cinfo.image_height;
    jpeg_destroy_decompress(&r.cinfo);
    return CST_OK;
}

/* One row of 4-channel CMYK as libjpeg gives it (Adobe's inverted values; YCCK already
 * converted to that form) to RGB: R = C K / 255, rounded as stb_image rounds (its
 * stbi__blinn_8x8: t = a b + 128, (t + t / 256) / 256), so such files decode as before. */
static void jpeg_cmyk_row(const unsigned char *cmyk, unsigned char *rgb, unsigned width)
{
    for (unsigned x = 0; x < width; x++, cmyk += 4, rgb += 3) {
        for (int c = 0; c < 3; c++) {
            unsigned t = (unsigned)cmyk[c] * cmyk[3] + 128u;
            rgb[c] = (unsigned char)((t + (t >> 8)) >> 8);
        }
    }
}

CstStatus jpeg_decode(const char *path, const unsigned char *data, size_t size, unsigned char **pixels,
                      int *width, int *height, int *channels, CstError *err)
{
    *pixels = NULL;
    JpegRead r;
    /* Changed between setjmp and a longjmp, so volatile (C17 7.13.2.1). */
    unsigned char *volatile out = NULL, *volatile row4 = NULL;
    jpeg_begin(&r, data, size);
    if (setjmp(r.fail.back)) {
        free(out);
        free(row4);
        return jpeg_failed(&r, path, err);
    }
    jpeg_create_decompress(&r.cinfo);
    r.cinfo.progress = &r.progress;
    jpeg_mem_src(&r.cinfo, data, (unsigned long)size);
    jpeg_read_header(&r.cinfo, TRUE);
    J_COLOR_SPACE in = r.cinfo.jpeg_color_space;
    bool cmyk = in == JCS_CMYK || in == JCS_YCCK;
    int ch = in == JCS_GRAYSCALE ? 1 : 3;
    r.cinfo.out_color_space = ch == 1 ? JCS_GRAYSCALE : cmyk ? JCS_CMYK : JCS_RGB;
    jpeg_start_decompress(&r.cinfo);
    unsigned w = r.cinfo.output_width, h = r.cinfo.output_height;
    size_t stride = (size_t)w * (size_t)ch;
    out = malloc(stride * h);
    if (cmyk) row4 = malloc((size_t)w * 4);
    if (!out || (cmyk && !row4)) {
        free(out);
        free(row4);
        jpeg_destroy_decompress(&r.cinfo);
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %u x %u JPEG", path, w, h);
    }
    while (r.cinfo.output_scanline < h) {
        unsigned y = r.cinfo.output_scanline;
        JSAMPROW row = cmyk ? row4 : out + stride * y;
        if (jpeg_read_scanlines(&r.cinfo, &row, 1) != 1) { /* cannot happen with jpeg_mem_src */
            snprintf(r.fail.msg, sizeof r.fail.msg, "no data for row %u of %u", y, h);
            r.fail.at = jpeg_offset(&r);
            free(out);
            free(row4);
            return jpeg_failed(&r, path, err);
        }
        if (cmyk) jpeg_cmyk_row(row4, out + stride * y, w);
    }
    jpeg_finish_decompress(&r.cinfo); /* reads to EOI: a corrupt tail is an error too */
    jpeg_destroy_decompress(&r.cinfo);
    free(row4);
    *pixels = out;
    *width = (int)w;
    *height = (int)h;
    *channels = ch;
    return CST_OK;
}
