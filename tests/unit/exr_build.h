/* A minimal uncompressed scanline EXR (3 x 2 pixels) built byte by byte from the OpenEXR
 * file layout document, independent of the library's writer; for the EXR reader's tests
 * (test_image_io, test_texture_exr). Include after cmocka.h. */
#ifndef CST_TEST_EXR_BUILD_H
#define CST_TEST_EXR_BUILD_H

#include <stdint.h>
#include <string.h>

typedef struct ExrBuf {
    uint8_t d[8192];
    size_t n;
} ExrBuf;

static void eb_put(ExrBuf *b, const void *p, size_t n)
{
    assert_true(b->n + n <= sizeof b->d);
    memcpy(b->d + b->n, p, n);
    b->n += n;
}
static void eb_u8(ExrBuf *b, uint8_t v) { eb_put(b, &v, 1); }
static void eb_str(ExrBuf *b, const char *s) { eb_put(b, s, strlen(s) + 1); }
static void eb_i32(ExrBuf *b, uint32_t v)
{
    uint8_t x[4] = {(uint8_t)v, (uint8_t)(v >> 8), (uint8_t)(v >> 16), (uint8_t)(v >> 24)};
    eb_put(b, x, 4);
}
static void eb_u64(ExrBuf *b, uint64_t v)
{
    eb_i32(b, (uint32_t)v);
    eb_i32(b, (uint32_t)(v >> 32));
}
static void eb_f32(ExrBuf *b, float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    eb_i32(b, u);
}
static void eb_attr(ExrBuf *b, const char *name, const char *type, uint32_t size)
{
    eb_str(b, name);
    eb_str(b, type);
    eb_i32(b, size);
}

typedef struct ExrChan {
    const char *name; /* must be listed in alphabetical order */
    int type;         /* 1 = half, 2 = float */
    /* raw sample bits at pixel i (row-major) */
    uint32_t bits[6];
} ExrChan;

/* 3 x 2 image, one scanline per chunk, no compression. */
static void build_exr(ExrBuf *b, const ExrChan *ch, int nch)
{
    const int w = 3, h = 2;
    b->n = 0;
    eb_i32(b, 20000630u); /* magic 0x01312f76 */
    eb_i32(b, 2u);        /* version 2, single-part scanline */
    uint32_t chsize = 1;
    for (int c = 0; c < nch; ++c) chsize += (uint32_t)strlen(ch[c].name) + 1 + 16;
    eb_attr(b, "channels", "chlist", chsize);
    for (int c = 0; c < nch; ++c) {
        eb_str(b, ch[c].name);
        eb_i32(b, (uint32_t)ch[c].type);
        eb_i32(b, 0); /* pLinear + reserved */
        eb_i32(b, 1);
        eb_i32(b, 1);
    }
    eb_u8(b, 0);
    eb_attr(b, "compression", "compression", 1);
    eb_u8(b, 0);
    eb_attr(b, "dataWindow", "box2i", 16);
    eb_i32(b, 0); eb_i32(b, 0); eb_i32(b, (uint32_t)(w - 1)); eb_i32(b, (uint32_t)(h - 1));
    eb_attr(b, "displayWindow", "box2i", 16);
    eb_i32(b, 0); eb_i32(b, 0); eb_i32(b, (uint32_t)(w - 1)); eb_i32(b, (uint32_t)(h - 1));
    eb_attr(b, "lineOrder", "lineOrder", 1);
    eb_u8(b, 0);
    eb_attr(b, "pixelAspectRatio", "float", 4);
    eb_f32(b, 1.0f);
    eb_attr(b, "screenWindowCenter", "v2f", 8);
    eb_f32(b, 0.0f);
    eb_f32(b, 0.0f);
    eb_attr(b, "screenWindowWidth", "float", 4);
    eb_f32(b, 1.0f);
    eb_u8(b, 0); /* end of header */

    uint32_t line_bytes = 0;
    for (int c = 0; c < nch; ++c) line_bytes += (uint32_t)(w * (ch[c].type == 1 ? 2 : 4));
    uint64_t first = b->n + 8u * (uint64_t)h;
    for (int y = 0; y < h; ++y) eb_u64(b, first + (uint64_t)y * (8 + line_bytes));
    for (int y = 0; y < h; ++y) {
        eb_i32(b, (uint32_t)y);
        eb_i32(b, line_bytes);
        for (int c = 0; c < nch; ++c) {
            for (int x = 0; x < w; ++x) {
                uint32_t v = ch[c].bits[y * w + x];
                if (ch[c].type == 1) {
                    eb_u8(b, (uint8_t)v);
                    eb_u8(b, (uint8_t)(v >> 8));
                } else {
                    eb_i32(b, v);
                }
            }
        }
    }
}

static uint32_t fbits(float f)
{
    uint32_t u;
    memcpy(&u, &f, 4);
    return u;
}

#endif
