/* Unit tests for io/image_io: PFM/EXR/PNG round trips, the sRGB curve, atomic writes
 * and failure paths, and malformed or hand-built files that exercise the readers. */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"
#include "unit/exr_build.h"

#include <dirent.h>
#include <math.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <unistd.h>

#include <png.h>

#include "io/image_io.h"

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_image_io.XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static int count_temp_files(void)
{
    DIR *d = opendir(g_dir);
    assert_non_null(d);
    int n = 0;
    struct dirent *e;
    while ((e = readdir(d))) n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

static bool file_exists(const char *p)
{
    struct stat sb;
    return stat(p, &sb) == 0;
}

/* Whole file into a malloc'd buffer. */
static uint8_t *slurp(const char *p, size_t *n)
{
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    long len = ftell(f);
    fseek(f, 0, SEEK_SET);
    uint8_t *b = malloc((size_t)len + 1);
    assert_non_null(b);
    assert_int_equal(fread(b, 1, (size_t)len, f), (size_t)len);
    fclose(f);
    *n = (size_t)len;
    return b;
}

static void spit(const char *p, const void *data, size_t n)
{
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

static float le_f32(const uint8_t *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static bool same_bits(float a, float b)
{
    return memcmp(&a, &b, sizeof a) == 0;
}

/* A test image whose every sample differs, with distinct top and bottom rows, negative,
 * tiny (denormal), huge and non-finite values: bit exactness must survive all of them. */
static float *make_hdr_image(int w, int h)
{
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    assert_non_null(rgb);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                rgb[((size_t)y * w + x) * 3 + c] = (float)(y * 1000 + x * 10 + c) * 0.37f + 0.001f * (float)c;
    rgb[0] = -2.5f;
    rgb[1] = 1.0e-40f;
    rgb[2] = 3.0e38f;
    rgb[3] = INFINITY;
    rgb[4] = -INFINITY;
    rgb[5] = NAN;
    return rgb;
}

/* ---------------------------------------------------------------- sRGB curve */

static void test_srgb_curve(void **state)
{
    (void)state;
    assert_true(image_linear_to_srgb(0.0f) == 0.0f);
    assert_true(image_linear_to_srgb(1.0f) == 1.0f);
    assert_true(image_linear_to_srgb(-1.0f) == 0.0f);
    assert_true(image_linear_to_srgb(7.0f) == 1.0f);
    assert_true(image_linear_to_srgb(NAN) == 0.0f);
    assert_true(image_linear_to_srgb(INFINITY) == 1.0f);
    assert_true(image_linear_to_srgb(-INFINITY) == 0.0f);
    /* 1.055 * 0.5^(1/2.4) - 0.055 = 0.735357 */
    assert_float_equal(image_linear_to_srgb(0.5f), 0.735357f, 1e-5f);
    assert_float_equal(image_linear_to_srgb(0.18f), 0.461356f, 1e-5f);
    /* the linear toe: 12.92 v */
    assert_float_equal(image_linear_to_srgb(0.001f), 0.01292f, 1e-7f);
    /* the two pieces meet at the knee 0.0031308 (value 0.0404500) */
    float k = 0.0031308f;
    float below = image_linear_to_srgb(nextafterf(k, 0.0f));
    float at = image_linear_to_srgb(k);
    float above = image_linear_to_srgb(nextafterf(k, 1.0f));
    assert_float_equal(at, 0.04045f, 1e-6f);
    assert_true(fabsf(above - below) < 1e-6f);
    /* monotone over [0, 1] */
    float prev = -1.0f;
    for (int i = 0; i <= 10000; ++i) {
        float s = image_linear_to_srgb((float)i / 10000.0f);
        assert_true(s >= prev);
        assert_true(s >= 0.0f && s <= 1.0f);
        prev = s;
    }
}

/* ---------------------------------------------------------------- PFM */

static void test_pfm_roundtrip_row_order(void **state)
{
    (void)state;
    const int w = 5, h = 3;
    float *rgb = make_hdr_image(w, h);
    char p[512];
    tpath(p, sizeof p, "round.pfm");
    CstError err = {0};
    assert_int_equal(image_write(p, rgb, w, h, &err), CST_OK);
    assert_int_equal(count_temp_files(), 0);

    /* The raw file: exact header, then the image's BOTTOM row first, little endian. */
    size_t n;
    uint8_t *raw = slurp(p, &n);
    const char *hdr = "PF\n5 3\n-1.0\n";
    size_t hl = strlen(hdr);
    assert_int_equal(n, hl + (size_t)w * h * 12);
    assert_memory_equal(raw, hdr, hl);
    for (int y = 0; y < h; ++y) {
        const float *img_row = rgb + (size_t)(h - 1 - y) * w * 3;
        for (int i = 0; i < w * 3; ++i)
            assert_true(same_bits(le_f32(raw + hl + ((size_t)y * w * 3 + i) * 4), img_row[i]));
    }
    free(raw);

    float *back = NULL;
    int bw = 0, bh = 0;
    assert_int_equal(image_read(p, &back, &bw, &bh, &err), CST_OK);
    assert_int_equal(bw, w);
    assert_int_equal(bh, h);
    assert_memory_equal(back, rgb, (size_t)w * h * 3 * sizeof(float));
    free(back);
    free(rgb);
}

/* "Pf" greyscale and big-endian "PF" written by hand: byte order from the scale's sign,
 * rows bottom to top, grey replicated into R, G, B. */
static void test_pfm_read_variants(void **state)
{
    (void)state;
    char p[512];
    tpath(p, sizeof p, "grey_be.pfm");
    /* 2 x 2 grey, big endian (positive scale 1.5, ignored), file rows: bottom then top */
    const float vals[4] = {1.0f, 2.0f, 3.0f, 4.0f};
    uint8_t buf[64];
    size_t hl = (size_t)sprintf((char *)buf, "Pf\n2 2\n1.5\n");
    for (int i = 0; i < 4; ++i) {
        uint32_t u;
        memcpy(&u, &vals[i], 4);
        buf[hl + 4 * i + 0] = (uint8_t)(u >> 24);
        buf[hl + 4 * i + 1] = (uint8_t)(u >> 16);
        buf[hl + 4 * i + 2] = (uint8_t)(u >> 8);
        buf[hl + 4 * i + 3] = (uint8_t)u;
    }
    spit(p, buf, hl + 16);
    float *rgb = NULL;
    int w = 0, h = 0;
    CstError err = {0};
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_OK);
    assert_int_equal(w, 2);
    assert_int_equal(h, 2);
    const float want[4] = {3.0f, 4.0f, 1.0f, 2.0f}; /* top row first */
    for (int i = 0; i < 4; ++i)
        for (int c = 0; c < 3; ++c) assert_true(rgb[3 * i + c] == want[i]);
    free(rgb);

    /* little endian colour with spaces instead of newlines and an exponent in the scale */
    tpath(p, sizeof p, "spaced.pfm");
    hl = (size_t)sprintf((char *)buf, "PF 1  1 -1e0 ");
    const float px[3] = {0.25f, -0.5f, 8.0f};
    for (int i = 0; i < 3; ++i) {
        uint32_t u;
        memcpy(&u, &px[i], 4);
        for (int b = 0; b < 4; ++b) buf[hl + 4 * i + b] = (uint8_t)(u >> (8 * b));
    }
    spit(p, buf, hl + 12);
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_OK);
    assert_int_equal(w, 1);
    assert_int_equal(h, 1);
    assert_memory_equal(rgb, px, sizeof px);
    free(rgb);
}

static void expect_read_error(const char *name, const void *data, size_t n, CstStatus want)
{
    char p[512];
    tpath(p, sizeof p, name);
    spit(p, data, n);
    float *rgb = (float *)(uintptr_t)1; /* must be reset to NULL on failure */
    int w = 7, h = 7;
    CstError err = {0};
    CstStatus st = image_read(p, &rgb, &w, &h, &err);
    if (st != want) print_error("%s: got %d (%s), want %d\n", name, st, err.msg, want);
    assert_int_equal(st, want);
    assert_null(rgb);
    assert_int_equal(w, 0);
    assert_int_equal(h, 0);
    assert_non_null(strstr(err.msg, p)); /* messages name the file */
}

static void test_pfm_malformed(void **state)
{
    (void)state;
    /* truncated pixel data: 4 x 4 RGB needs 192 bytes */
    char t[64];
    size_t hl = (size_t)sprintf(t, "PF\n4 4\n-1.0\n");
    memset(t + hl, 0x42, 10);
    expect_read_error("trunc.pfm", t, hl + 10, CST_ERR_PARSE);
    /* a header that claims a huge image must fail on size, not try to allocate it */
    expect_read_error("huge.pfm", "PF\n100000 100000\n-1.0\n\0\0\0\0", 27, CST_ERR_PARSE);
    expect_read_error("huge2.pfm", "PF\n16384 16384\n-1.0\n\0\0\0\0", 25, CST_ERR_PARSE);
    const char *bad[] = {
        "PF\nabc 3\n-1.0\n", "PF\n2 2\n0.0\n", "PF\n2 2\nxyz\n", "PF\n2\n",
        "PF\n-2 2\n-1.0\n", "PF\n0 2\n-1.0\n", "PF\n9999999999 1\n-1.0\n", "PF\n2 2\n-1.0",
        "PF2 2 -1.0\n", "PF\n2 2\n-.\n", "PF\n2 2\n-1e\n", "PF", "Pf\n\n\n\n",
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; ++i) {
        char name[32];
        snprintf(name, sizeof name, "bad%zu.pfm", i);
        expect_read_error(name, bad[i], strlen(bad[i]), CST_ERR_PARSE);
    }
    /* a 200-byte run of spaces: the header never ends inside the bytes we look at */
    char spaces[220];
    memcpy(spaces, "PF", 2);
    memset(spaces + 2, ' ', sizeof spaces - 2);
    expect_read_error("spaces.pfm", spaces, sizeof spaces, CST_ERR_PARSE);
    /* not any known format, and empty */
    expect_read_error("garbage.pfm", "GARBAGE!GARBAGE!", 16, CST_ERR_UNSUPPORTED);
    expect_read_error("empty.pfm", "", 0, CST_ERR_PARSE);
}

/* ---------------------------------------------------------------- OpenEXR */

static void test_exr_roundtrip(void **state)
{
    (void)state;
    /* 37 x 23: not a multiple of the 16-line ZIP chunk, so the short last chunk is used */
    const int w = 37, h = 23;
    float *rgb = make_hdr_image(w, h);
    char p[512];
    tpath(p, sizeof p, "round.EXR"); /* extension matching ignores case */
    CstError err = {0};
    assert_int_equal(image_write(p, rgb, w, h, &err), CST_OK);
    assert_int_equal(count_temp_files(), 0);
    size_t n;
    uint8_t *raw = slurp(p, &n);
    assert_true(n > 4 && raw[0] == 0x76 && raw[1] == 0x2f && raw[2] == 0x31 && raw[3] == 0x01);
    free(raw);

    float *back = NULL;
    int bw = 0, bh = 0;
    assert_int_equal(image_read(p, &back, &bw, &bh, &err), CST_OK);
    assert_int_equal(bw, w);
    assert_int_equal(bh, h);
    assert_memory_equal(back, rgb, (size_t)w * h * 3 * sizeof(float));
    free(back);
    free(rgb);
}

/* OpenEXR 3.1.5 stored a ZIP chunk's deflated bytes when they were exactly as many as its
 * pixels' bytes, which readers take for an uncompressed chunk (image_io.c,
 * image_exr_compress). Chunks of noise made a little compressible by zeroing a varying share
 * of the values sweep the deflated size across the packed size (64 x 16 x 3 floats = 12,288
 * bytes) in steps of a few bytes, so some land on it exactly; every one must read back bit
 * for bit. Without the guard, image 267 is the first to read back as garbage. */
static void test_exr_incompressible_chunks(void **state)
{
    (void)state;
    enum { W = 64, H = 16, TRIALS = 600 };
    float *rgb = malloc(sizeof(float) * W * H * 3);
    assert_non_null(rgb);
    uint64_t x = 0x9e3779b97f4a7c15ULL;
    char p[512];
    tpath(p, sizeof p, "noise.exr");
    int raw_sized = 0;
    for (int t = 0; t < TRIALS; t++) {
        const uint32_t zero_below = (uint32_t)t * 7u; /* of 2^16: 0 to 6.4 % of the values zero */
        for (int i = 0; i < W * H * 3; i++) {
            x ^= x << 13, x ^= x >> 7, x ^= x << 17; /* xorshift64 */
            uint32_t u = (uint32_t)(x >> 32);
            rgb[i] = (u & 0xffffu) < zero_below ? 0.0f : (float)(u >> 8) * 0x1p-24f;
        }
        CstError err = {0};
        assert_int_equal(image_write(p, rgb, W, H, &err), CST_OK);
        size_t n;
        uint8_t *raw = slurp(p, &n);
        /* the one chunk is the file's last bytes: y, size, data */
        if (n > 12288 + 8) {
            int32_t stored;
            memcpy(&stored, raw + n - 12288 - 4, 4);
            raw_sized += stored == 12288;
        }
        free(raw);
        float *back = NULL;
        int bw = 0, bh = 0;
        assert_int_equal(image_read(p, &back, &bw, &bh, &err), CST_OK);
        if (memcmp(back, rgb, sizeof(float) * W * H * 3) != 0)
            fail_msg("image %d (%u of 65536 values zero) did not read back bit for bit", t, zero_below);
        free(back);
    }
    print_message("exr: %d of %d noise chunks stored at their packed size, all read back\n", raw_sized, TRIALS);
    free(rgb);
}

/* The hand-made EXRs (unit/exr_build.h) check half -> float, the B, G, R storage order
 * and channels the reader must skip. */
static void test_exr_read_handmade(void **state)
{
    (void)state;
    /* half bit patterns and their exact float values */
    const uint32_t hb[6] = {0x3C00, 0x3800, 0x4000, 0xBC00, 0x0001, 0x7BFF};
    const float hv[6] = {1.0f, 0.5f, 2.0f, -1.0f, 5.9604644775390625e-8f, 65504.0f};
    /* R = hv[i], G = hv[(i+2)%6], B = hv[(i+4)%6]; plus a float alpha to be skipped */
    ExrChan ch[4] = {{"A", 2, {0}}, {"B", 1, {0}}, {"G", 1, {0}}, {"R", 1, {0}}};
    for (int i = 0; i < 6; ++i) {
        ch[0].bits[i] = fbits(0.125f);
        ch[1].bits[i] = hb[(i + 4) % 6];
        ch[2].bits[i] = hb[(i + 2) % 6];
        ch[3].bits[i] = hb[i];
    }
    ExrBuf *b = malloc(sizeof *b);
    assert_non_null(b);
    build_exr(b, ch, 4);
    char p[512];
    tpath(p, sizeof p, "handmade_half.exr");
    spit(p, b->d, b->n);
    float *rgb = NULL;
    int w = 0, h = 0;
    CstError err = {0};
    CstStatus st = image_read(p, &rgb, &w, &h, &err);
    if (st != CST_OK) print_error("%s\n", err.msg);
    assert_int_equal(st, CST_OK);
    assert_int_equal(w, 3);
    assert_int_equal(h, 2);
    for (int i = 0; i < 6; ++i) {
        assert_true(rgb[3 * i + 0] == hv[i]);
        assert_true(rgb[3 * i + 1] == hv[(i + 2) % 6]);
        assert_true(rgb[3 * i + 2] == hv[(i + 4) % 6]);
    }
    free(rgb);

    /* greyscale: a lone float Y channel is replicated */
    ExrChan y[1] = {{"Y", 2, {0}}};
    for (int i = 0; i < 6; ++i) y[0].bits[i] = fbits((float)i * 0.75f - 1.0f);
    build_exr(b, y, 1);
    tpath(p, sizeof p, "handmade_y.exr");
    spit(p, b->d, b->n);
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_OK);
    for (int i = 0; i < 6; ++i)
        for (int c = 0; c < 3; ++c) assert_true(rgb[3 * i + c] == (float)i * 0.75f - 1.0f);
    free(rgb);

    /* no colour channels at all */
    ExrChan z[1] = {{"Z", 2, {0}}};
    build_exr(b, z, 1);
    expect_read_error("handmade_z.exr", b->d, b->n, CST_ERR_UNSUPPORTED);
    free(b);
}

/* Truncated and corrupted EXR files: an error or a sane image, never a crash. */
static void test_exr_malformed(void **state)
{
    (void)state;
    const int w = 40, h = 40;
    float *rgb = make_hdr_image(w, h);
    char p[512];
    tpath(p, sizeof p, "src.exr");
    CstError err = {0};
    assert_int_equal(image_write(p, rgb, w, h, &err), CST_OK);
    size_t n;
    uint8_t *raw = slurp(p, &n);

    /* header cut short */
    expect_read_error("cut_header.exr", raw, 40, CST_ERR_PARSE);
    /* magic followed by garbage */
    uint8_t junk[64];
    memcpy(junk, raw, 8);
    for (size_t i = 8; i < sizeof junk; ++i) junk[i] = (uint8_t)(i * 37 + 11);
    expect_read_error("junk.exr", junk, sizeof junk, CST_ERR_PARSE);

    /* truncated pixel data, and bytes flipped all over the file */
    char q[512];
    for (int k = 0; k < 40; ++k) {
        uint8_t *copy = malloc(n);
        assert_non_null(copy);
        memcpy(copy, raw, n);
        size_t len = n;
        if (k < 10) {
            len = n * (size_t)(k + 1) / 11;
        } else {
            for (size_t i = (size_t)k * 7; i < n; i += 97 + (size_t)k) copy[i] ^= (uint8_t)(0x5a + k);
        }
        tpath(q, sizeof q, "mangled.exr");
        spit(q, copy, len);
        float *back = NULL;
        int bw = 0, bh = 0;
        CstStatus st = image_read(q, &back, &bw, &bh, &err);
        if (st == CST_OK) {
            assert_non_null(back);
            assert_true(bw > 0 && bh > 0);
        } else {
            assert_null(back);
        }
        free(back);
        free(copy);
    }
    free(raw);
    free(rgb);
}

/* ---------------------------------------------------------------- PNG */

static void test_png_roundtrip(void **state)
{
    (void)state;
    const int w = 64, h = 8;
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    assert_non_null(rgb);
    for (int i = 0; i < w * h * 3; ++i) rgb[i] = (float)((i * 7919) % 1000) / 999.0f; /* [0, 1] */
    /* out-of-range and non-finite values clamp: NaN and -inf -> 0, +inf and 5 -> 1 */
    rgb[0] = NAN;
    rgb[1] = INFINITY;
    rgb[2] = -INFINITY;
    rgb[3] = -3.0f;
    rgb[4] = 5.0f;
    char p[512];
    tpath(p, sizeof p, "round.Png");
    CstError err = {0};
    assert_int_equal(image_write(p, rgb, w, h, &err), CST_OK);
    assert_int_equal(count_temp_files(), 0);

    size_t n;
    uint8_t *raw = slurp(p, &n);
    assert_int_equal(png_sig_cmp(raw, 0, 8), 0);
    bool has_srgb = false;
    for (size_t i = 8; i + 4 <= n; ++i) has_srgb |= memcmp(raw + i, "sRGB", 4) == 0;
    assert_true(has_srgb);
    free(raw);

    float *back = NULL;
    int bw = 0, bh = 0;
    assert_int_equal(image_read(p, &back, &bw, &bh, &err), CST_OK);
    assert_int_equal(bw, w);
    assert_int_equal(bh, h);
    /* in the encoded domain the only loss is 8-bit rounding: at most half a step */
    for (int i = 0; i < w * h * 3; ++i) {
        float a = image_linear_to_srgb(rgb[i]), b = image_linear_to_srgb(back[i]);
        assert_true(fabsf(a - b) <= 0.5f / 255.0f + 1e-5f);
    }
    assert_true(back[0] == 0.0f);
    assert_true(back[1] == 1.0f);
    assert_true(back[2] == 0.0f);
    assert_true(back[3] == 0.0f);
    assert_true(back[4] == 1.0f);
    free(back);

    /* The stored bytes themselves, decoded by libpng's simplified API: round(255 s + 0.5)
     * of the sRGB-encoded value, e.g. 0.5 -> 0.735357 -> 188, 0.0031308 -> 0.04045 -> 10. */
    const float probe[6] = {0.5f, 0.0031308f, 0.18f, 1.0f, 0.0f, 0.9f};
    const uint8_t want[6] = {188, 10, 118, 255, 0, 243};
    tpath(p, sizeof p, "bytes.png");
    assert_int_equal(image_write(p, probe, 2, 1, &err), CST_OK);
    png_image img;
    memset(&img, 0, sizeof img);
    img.version = PNG_IMAGE_VERSION;
    assert_true(png_image_begin_read_from_file(&img, p));
    img.format = PNG_FORMAT_RGB;
    uint8_t got[6] = {0};
    assert_int_equal(PNG_IMAGE_SIZE(img), sizeof got);
    assert_true(png_image_finish_read(&img, NULL, got, 0, NULL));
    assert_memory_equal(got, want, sizeof want);
    free(rgb);
}

/* Writes a PNG of any layout with libpng directly; rows are given raw. */
static void write_png_raw(const char *p, int w, int h, int depth, int color,
                          const uint8_t *data, size_t rowbytes, const png_color *pal, int npal)
{
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png))) fail();
    png_init_io(png, f);
    png_set_IHDR(png, info, (png_uint_32)w, (png_uint_32)h, depth, color, PNG_INTERLACE_ADAM7,
                 PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
    if (pal) png_set_PLTE(png, info, pal, npal);
    png_write_info(png, info);
    for (int pass = png_set_interlace_handling(png); pass > 0; --pass)
        for (int y = 0; y < h; ++y) png_write_row(png, data + (size_t)y * rowbytes);
    png_write_end(png, NULL);
    png_destroy_write_struct(&png, &info);
    fclose(f);
}

static float srgb_decode(double s)
{
    return (float)(s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4));
}

static void read_and_expect(const char *p, const float *want, int w, int h, float tol)
{
    float *rgb = NULL;
    int bw = 0, bh = 0;
    CstError err = {0};
    CstStatus st = image_read(p, &rgb, &bw, &bh, &err);
    if (st != CST_OK) print_error("%s\n", err.msg);
    assert_int_equal(st, CST_OK);
    assert_int_equal(bw, w);
    assert_int_equal(bh, h);
    for (int i = 0; i < w * h * 3; ++i) assert_float_equal(rgb[i], want[i], tol);
    free(rgb);
}

/* Grey, grey+alpha, RGBA, palette, 1-bit and 16-bit PNGs (interlaced) decode to linear RGB. */
static void test_png_read_layouts(void **state)
{
    (void)state;
    enum { W = 3, H = 2 };
    char p[512];
    float want[W * H * 3];

    /* 8-bit grey */
    const uint8_t grey[W * H] = {0, 64, 128, 192, 255, 10};
    for (int i = 0; i < W * H; ++i)
        want[3 * i] = want[3 * i + 1] = want[3 * i + 2] = srgb_decode(grey[i] / 255.0);
    tpath(p, sizeof p, "grey8.png");
    write_png_raw(p, W, H, 8, PNG_COLOR_TYPE_GRAY, grey, W, NULL, 0);
    read_and_expect(p, want, W, H, 1e-7f);

    /* grey + alpha: alpha dropped */
    uint8_t ga[W * H * 2];
    for (int i = 0; i < W * H; ++i) { ga[2 * i] = grey[i]; ga[2 * i + 1] = (uint8_t)(i * 40); }
    tpath(p, sizeof p, "greya8.png");
    write_png_raw(p, W, H, 8, PNG_COLOR_TYPE_GRAY_ALPHA, ga, W * 2, NULL, 0);
    read_and_expect(p, want, W, H, 1e-7f);

    /* RGBA */
    uint8_t rgba[W * H * 4];
    for (int i = 0; i < W * H; ++i) {
        for (int c = 0; c < 3; ++c) {
            rgba[4 * i + c] = (uint8_t)(i * 50 + c * 17);
            want[3 * i + c] = srgb_decode(rgba[4 * i + c] / 255.0);
        }
        rgba[4 * i + 3] = 7;
    }
    tpath(p, sizeof p, "rgba8.png");
    write_png_raw(p, W, H, 8, PNG_COLOR_TYPE_RGB_ALPHA, rgba, W * 4, NULL, 0);
    read_and_expect(p, want, W, H, 1e-7f);

    /* palette */
    const png_color pal[3] = {{255, 0, 0}, {0, 128, 0}, {10, 20, 30}};
    const uint8_t idx[W * H] = {0, 1, 2, 2, 1, 0};
    for (int i = 0; i < W * H; ++i) {
        want[3 * i + 0] = srgb_decode(pal[idx[i]].red / 255.0);
        want[3 * i + 1] = srgb_decode(pal[idx[i]].green / 255.0);
        want[3 * i + 2] = srgb_decode(pal[idx[i]].blue / 255.0);
    }
    tpath(p, sizeof p, "pal8.png");
    write_png_raw(p, W, H, 8, PNG_COLOR_TYPE_PALETTE, idx, W, pal, 3);
    read_and_expect(p, want, W, H, 1e-7f);

    /* 1-bit grey: rows are bit-packed, MSB first: 101, 010 */
    const uint8_t bits[2] = {0xA0, 0x40};
    for (int i = 0; i < W * H; ++i) {
        float v = ((i == 0 || i == 2 || i == 4) ? 1.0f : 0.0f);
        want[3 * i] = want[3 * i + 1] = want[3 * i + 2] = v;
    }
    tpath(p, sizeof p, "grey1.png");
    write_png_raw(p, W, H, 1, PNG_COLOR_TYPE_GRAY, bits, 1, NULL, 0);
    read_and_expect(p, want, W, H, 1e-7f);

    /* 16-bit RGB, big-endian samples */
    uint8_t rgb16[W * H * 6];
    for (int i = 0; i < W * H * 3; ++i) {
        unsigned v = (unsigned)(i * 3851 + 17) & 0xFFFF;
        rgb16[2 * i] = (uint8_t)(v >> 8);
        rgb16[2 * i + 1] = (uint8_t)v;
        want[i] = srgb_decode(v / 65535.0);
    }
    tpath(p, sizeof p, "rgb16.png");
    write_png_raw(p, W, H, 16, PNG_COLOR_TYPE_RGB, rgb16, W * 6, NULL, 0);
    read_and_expect(p, want, W, H, 1e-6f);
}

static void test_png_malformed(void **state)
{
    (void)state;
    const int w = 50, h = 50;
    float *rgb = malloc((size_t)w * h * 3 * sizeof *rgb);
    assert_non_null(rgb);
    for (int i = 0; i < w * h * 3; ++i) rgb[i] = (float)((i * 31) % 101) / 100.0f;
    char p[512];
    tpath(p, sizeof p, "src.png");
    CstError err = {0};
    assert_int_equal(image_write(p, rgb, w, h, &err), CST_OK);
    size_t n;
    uint8_t *raw = slurp(p, &n);
    expect_read_error("cut.png", raw, n / 2, CST_ERR_PARSE);
    expect_read_error("sigonly.png", raw, 8, CST_ERR_PARSE);
    raw[n / 2] ^= 0xFF; /* CRC mismatch in the image data */
    expect_read_error("crc.png", raw, n, CST_ERR_PARSE);
    free(raw);
    free(rgb);
}

/* ---------------------------------------------------------------- writing: errors, atomicity */

static void test_unknown_extension(void **state)
{
    (void)state;
    float px[3] = {0.5f, 0.5f, 0.5f};
    char p[512];
    CstError err = {0};
    tpath(p, sizeof p, "out.bmp");
    assert_int_equal(image_write(p, px, 1, 1, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, p));
    assert_non_null(strstr(err.msg, ".png"));
    assert_non_null(strstr(err.msg, ".exr"));
    assert_non_null(strstr(err.msg, ".pfm"));
    assert_false(file_exists(p));
    tpath(p, sizeof p, "no_extension");
    assert_int_equal(image_write(p, px, 1, 1, &err), CST_ERR_INVALID_ARG);
    assert_false(file_exists(p));
    tpath(p, sizeof p, "dir.png/noext");
    assert_int_equal(image_write(p, px, 1, 1, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(count_temp_files(), 0);
}

/* The one extension rule (image_format_from_path) that the writer, both scene loaders and
 * the CLI share. */
static void test_format_from_path(void **state)
{
    (void)state;
    assert_int_equal(image_format_from_path("a.png"), IMAGE_FILE_PNG);
    assert_int_equal(image_format_from_path("dir/A.PnG"), IMAGE_FILE_PNG);
    assert_int_equal(image_format_from_path("x.jpeg"), IMAGE_FILE_JPEG);
    assert_int_equal(image_format_from_path("x.JPG"), IMAGE_FILE_JPEG);
    assert_int_equal(image_format_from_path("x.bmp"), IMAGE_FILE_BMP);
    assert_int_equal(image_format_from_path("x.tga"), IMAGE_FILE_TGA);
    assert_int_equal(image_format_from_path("x.hdr"), IMAGE_FILE_HDR);
    assert_int_equal(image_format_from_path("x.tar.exr"), IMAGE_FILE_EXR);
    assert_int_equal(image_format_from_path("x.pfm"), IMAGE_FILE_PFM);
    assert_int_equal(image_format_from_path("dir.png/noext"), IMAGE_FILE_NONE);
    assert_int_equal(image_format_from_path("png"), IMAGE_FILE_NONE);
    assert_int_equal(image_format_from_path("x."), IMAGE_FILE_NONE);
    assert_int_equal(image_format_from_path("x.pngx"), IMAGE_FILE_NONE);
    assert_int_equal(image_format_from_path(""), IMAGE_FILE_NONE);
    assert_true(image_format_is_writable(IMAGE_FILE_EXR));
    assert_false(image_format_is_writable(IMAGE_FILE_JPEG));
    assert_true(image_format_is_float(IMAGE_FILE_HDR));
    assert_false(image_format_is_float(IMAGE_FILE_PNG));
    assert_true(image_path_is_exr("a.EXR"));
    assert_true(image_path_is_scene_output("a.png"));
    assert_true(image_path_is_scene_output("dir/.pfm"));
    assert_false(image_path_is_scene_output(".png"));
    assert_false(image_path_is_scene_output("a.jpg"));
}

static void test_invalid_args(void **state)
{
    (void)state;
    float px[3] = {0};
    char p[512];
    CstError err = {0};
    tpath(p, sizeof p, "bad.pfm");
    assert_int_equal(image_write(p, NULL, 1, 1, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(image_write(p, px, 0, 1, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(image_write(p, px, 1, -3, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(image_write(NULL, px, 1, 1, &err), CST_ERR_INVALID_ARG);
    assert_false(file_exists(p));
    float *rgb = NULL;
    int w, h;
    assert_int_equal(image_read(p, NULL, &w, &h, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_ERR_IO); /* does not exist */
    assert_null(rgb);
    assert_int_equal(image_read(g_dir, &rgb, &w, &h, &err), CST_ERR_IO); /* a directory */
    assert_null(rgb);
}

static void test_missing_directory(void **state)
{
    (void)state;
    float px[6] = {0.1f, 0.2f, 0.3f, 0.4f, 0.5f, 0.6f};
    const char *names[3] = {"nope/out.png", "nope/out.exr", "nope/deeper/out.pfm"};
    for (int i = 0; i < 3; ++i) {
        char p[512];
        tpath(p, sizeof p, names[i]);
        CstError err = {0};
        assert_int_equal(image_write(p, px, 2, 1, &err), CST_ERR_IO);
        assert_non_null(strstr(err.msg, p));
        assert_non_null(strstr(err.msg, "does not exist"));
        assert_false(file_exists(p));
    }
    assert_int_equal(count_temp_files(), 0);
}

/* Overwriting replaces the file whole, with the permissions a plain fopen would give. */
static void test_overwrite_and_mode(void **state)
{
    (void)state;
    float a[3] = {1.0f, 2.0f, 3.0f}, b[6] = {4.0f, 5.0f, 6.0f, 7.0f, 8.0f, 9.0f};
    char p[512];
    tpath(p, sizeof p, "over.pfm");
    CstError err = {0};
    assert_int_equal(image_write(p, a, 1, 1, &err), CST_OK);
    assert_int_equal(image_write(p, b, 2, 1, &err), CST_OK);
    float *rgb = NULL;
    int w = 0, h = 0;
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_OK);
    assert_int_equal(w, 2);
    assert_memory_equal(rgb, b, sizeof b);
    free(rgb);
    mode_t mask = umask(0);
    umask(mask);
    struct stat sb;
    assert_int_equal(stat(p, &sb), 0);
    assert_int_equal(sb.st_mode & 0777, 0666 & ~mask);
}

/* A write that fails half way (file size limit -> EFBIG) reports CST_ERR_IO, leaves the
 * existing target untouched and removes its temporary file, for every format. */
static void test_failed_write_keeps_target(void **state)
{
    (void)state;
    const int w = 128, h = 128; /* incompressible noise: far above the limit in any format */
    float *big = malloc((size_t)w * h * 3 * sizeof *big);
    assert_non_null(big);
    uint32_t s = 12345;
    for (int i = 0; i < w * h * 3; ++i) {
        s = s * 1664525u + 1013904223u;
        big[i] = (float)(s >> 8) / 16777216.0f;
    }
    float small[3] = {0.25f, 0.5f, 0.75f};
    const char *names[3] = {"keep.pfm", "keep.exr", "keep.png"};

    struct rlimit old;
    assert_int_equal(getrlimit(RLIMIT_FSIZE, &old), 0);
    void (*old_handler)(int) = signal(SIGXFSZ, SIG_IGN);
    for (int i = 0; i < 3; ++i) {
        char p[512];
        tpath(p, sizeof p, names[i]);
        CstError err = {0};
        assert_int_equal(image_write(p, small, 1, 1, &err), CST_OK);
        size_t n0;
        uint8_t *before = slurp(p, &n0);
        assert_true(n0 < 2048);

        struct rlimit lim = old;
        lim.rlim_cur = 4096;
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &lim), 0);
        CstStatus st = image_write(p, big, w, h, &err);
        assert_int_equal(setrlimit(RLIMIT_FSIZE, &old), 0);
        if (st != CST_ERR_IO) print_error("%s: %d %s\n", names[i], st, err.msg);
        assert_int_equal(st, CST_ERR_IO);
        assert_non_null(strstr(err.msg, p));

        size_t n1;
        uint8_t *after = slurp(p, &n1);
        assert_int_equal(n0, n1);
        assert_memory_equal(before, after, n0);
        free(before);
        free(after);
        assert_int_equal(count_temp_files(), 0);
    }
    signal(SIGXFSZ, old_handler);
    free(big);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_srgb_curve),
        cmocka_unit_test(test_pfm_roundtrip_row_order),
        cmocka_unit_test(test_pfm_read_variants),
        cmocka_unit_test(test_pfm_malformed),
        cmocka_unit_test(test_exr_roundtrip),
        cmocka_unit_test(test_exr_incompressible_chunks),
        cmocka_unit_test(test_exr_read_handmade),
        cmocka_unit_test(test_exr_malformed),
        cmocka_unit_test(test_png_roundtrip),
        cmocka_unit_test(test_png_read_layouts),
        cmocka_unit_test(test_png_malformed),
        cmocka_unit_test(test_unknown_extension),
        cmocka_unit_test(test_format_from_path),
        cmocka_unit_test(test_invalid_args),
        cmocka_unit_test(test_missing_directory),
        cmocka_unit_test(test_overwrite_and_mode),
        cmocka_unit_test(test_failed_write_keeps_target),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
