/* OpenEXR textures kept as pbrt-v4 keeps them (issue 26): math/half.h's conversions (every
 * half exactly, rounding to nearest even), io/exr.h's exr_read_texels (halves stay halves,
 * A kept beside R, G, B, Y alone as one channel) on hand-made files, and the textures
 * made of them: TEXEL_F16 storage, alpha as the float lookup, an opaque alpha dropped, a
 * negative alpha refused with its pixel, a half MIP level rounded from its box average. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "unit/exr_build.h"
#include "unit/scratch_dir.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "core/file.h"
#include "io/exr.h"
#include "math/half.h"
#include "textures/mipmap.h"
#include "textures/texture.h"

static void spit(const char *p, const void *data, size_t n)
{
    FILE *f = fopen(p, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    fclose(f);
}

/* The value of half bits by the definition (IEEE 754-2008 binary16), apart from the code. */
static double half_reference(uint16_t h)
{
    int e = (h >> 10) & 0x1f, m = h & 0x3ff;
    double v = e == 0 ? ldexp((double)m, -24) : e == 31 ? (m ? (double)NAN : (double)INFINITY)
                                                        : ldexp((double)(m | 0x400), e - 25);
    return (h & 0x8000) ? -v : v;
}

/* Every one of the 65,536 halves decodes exactly and encodes back to itself (NaN to a NaN). */
static void test_half_every_value(void **state)
{
    (void)state;
    for (uint32_t h = 0; h < 65536u; h++) {
        float f = half_to_float((uint16_t)h);
        double r = half_reference((uint16_t)h);
        uint16_t back = float_to_half(f);
        if (isnan(r)) {
            assert_true(isnan(f));
            assert_true((back & 0x7c00u) == 0x7c00u && (back & 0x3ffu) != 0);
            continue;
        }
        if ((double)f != r) fail_msg("half 0x%04x: %.17g, expected %.17g", h, (double)f, r);
        if (back != h) fail_msg("half 0x%04x: encodes back to 0x%04x", h, back);
    }
}

/* Rounding to nearest, ties to even, on a million floats spread over every exponent the
 * halves reach (subnormals and overflow included): no half lies nearer than the one
 * chosen, and a tie picks the even one. */
static void test_half_rounding(void **state)
{
    (void)state;
    uint64_t s = 0x9E3779B97F4A7C15ull;
    int ties = 0;
    for (int i = 0; i < 1000000; i++) {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        uint32_t r = (uint32_t)(s >> 32);
        /* exponents 2^-27 .. 2^17; every fourth mantissa cut to 13 bits of ties */
        uint32_t bits = (r & 0x80000000u) | ((100u + (r >> 23) % 45u) << 23) | (s >> 9 & 0x7fffffu);
        if (i % 4 == 0) bits = (bits & ~0x1fffu) | 0x1000u;
        float f;
        memcpy(&f, &bits, sizeof f);
        uint16_t q = float_to_half(f);
        double fd = (double)f;
        if (fabs(fd) >= 65520.0) {
            assert_int_equal(q & 0x7fffu, 0x7c00u);
            continue;
        }
        double err = fabs(half_reference(q) - fd);
        uint16_t mag = q & 0x7fffu;
        for (int d = -1; d <= 1; d += 2) {
            if ((d < 0 && mag == 0) || (d > 0 && mag >= 0x7bffu)) continue;
            double other = fabs(half_reference((uint16_t)(q + d)) - fd);
            if (other < err) fail_msg("%.9g -> 0x%04x (off %.3g), 0x%04x is nearer (%.3g)", fd, q, err, q + d, other);
            if (other == err) {
                ties++;
                if (q & 1u) fail_msg("%.9g: a tie rounded to the odd 0x%04x", fd, q);
            }
        }
    }
    assert_true(ties > 1000); /* the tie cases were reached */
}

enum { W = 3, H = 2, N = W * H };

/* R, G, B of texel i as halves (exact values), alpha per the caller. */
static const float g_r[N] = {0.25f, 1.5f, 3.0f, 0.0f, 0.125f, 7.0f};
static const float g_g[N] = {0.5f, 0.75f, 2.0f, 1.0f, 0.0625f, 6.0f};
static const float g_b[N] = {1.0f, 0.375f, 4.0f, 2.0f, 0.03125f, 5.0f};

/* A hand-made RGBA EXR (RGB halves; A of the given type, or none when a_type is 0). */
static void write_rgba(const char *name, int a_type, const float a[N], char *path, size_t n)
{
    ExrChan ch[4] = {{"A", a_type, {0}}, {"B", 1, {0}}, {"G", 1, {0}}, {"R", 1, {0}}};
    for (int i = 0; i < N; i++) {
        if (a_type) ch[0].bits[i] = a_type == 1 ? float_to_half(a[i]) : fbits(a[i]);
        ch[1].bits[i] = float_to_half(g_b[i]);
        ch[2].bits[i] = float_to_half(g_g[i]);
        ch[3].bits[i] = float_to_half(g_r[i]);
    }
    ExrBuf *b = malloc(sizeof *b);
    assert_non_null(b);
    build_exr(b, a_type ? ch : ch + 1, a_type ? 4 : 3);
    tpath(path, n, name);
    spit(path, b->d, b->n);
    free(b);
}

static ExrImage read_texels(const char *path)
{
    FILE *fp = NULL;
    CstError err = {0};
    assert_int_equal(file_open_input(path, &fp, NULL, &err), CST_OK);
    ExrImage e;
    CstStatus st = exr_read_texels(fp, path, &e, &err);
    fclose(fp);
    if (st != CST_OK) fail_msg("%s", err.msg);
    return e;
}

static const float g_alpha[N] = {1.0f, 0.5f, 0.0f, 0.25f, 1.0f, 0.75f};
static const float g_opaque[N] = {1.0f, 1.0f, 1.0f, 1.0f, 1.0f, 1.0f};

/* The channels and storage exr_read_texels keeps. */
static void test_exr_texels(void **state)
{
    (void)state;
    char p[512];
    write_rgba("rgba_half.exr", 1, g_alpha, p, sizeof p);
    ExrImage e = read_texels(p);
    assert_int_equal(e.width, W);
    assert_int_equal(e.height, H);
    assert_int_equal(e.channels, 4);
    assert_true(e.half);
    const uint16_t *hp = e.px;
    for (int i = 0; i < N; i++) {
        assert_true(half_to_float(hp[4 * i + 0]) == g_r[i] && half_to_float(hp[4 * i + 1]) == g_g[i]);
        assert_true(half_to_float(hp[4 * i + 2]) == g_b[i] && half_to_float(hp[4 * i + 3]) == g_alpha[i]);
    }
    free(e.px);

    write_rgba("rgba_float_a.exr", 2, g_alpha, p, sizeof p); /* a float A: floats for all */
    e = read_texels(p);
    assert_int_equal(e.channels, 4);
    assert_false(e.half);
    const float *fp = e.px;
    for (int i = 0; i < N; i++) assert_true(fp[4 * i + 0] == g_r[i] && fp[4 * i + 3] == g_alpha[i]);
    free(e.px);

    write_rgba("rgb_half.exr", 0, NULL, p, sizeof p);
    e = read_texels(p);
    assert_int_equal(e.channels, 3);
    assert_true(e.half);
    free(e.px);

    ExrChan y[1] = {{"Y", 1, {0}}};
    for (int i = 0; i < N; i++) y[0].bits[i] = float_to_half(g_g[i]);
    ExrBuf *b = malloc(sizeof *b);
    assert_non_null(b);
    build_exr(b, y, 1);
    tpath(p, sizeof p, "y_half.exr");
    spit(p, b->d, b->n);
    free(b);
    e = read_texels(p);
    assert_int_equal(e.channels, 1);
    assert_true(e.half);
    for (int i = 0; i < N; i++) assert_true(half_to_float(((const uint16_t *)e.px)[i]) == g_g[i]);
    free(e.px);
}

static Vec2 centre(int x, int y) { return v2(((float)x + 0.5f) / W, 1.0f - ((float)y + 0.5f) / H); }

/* Textures of those files: halves stored as halves, alpha the float lookup, RGB lookups
 * the colour, an opaque alpha dropped, a negative alpha an error at its pixel. */
static void test_exr_textures(void **state)
{
    (void)state;
    char p[512];
    CstError err = {0};
    Texture t;
    write_rgba("tex_rgba.exr", 1, g_alpha, p, sizeof p);
    assert_int_equal(texture_image_load(&t, p, true, TEXTURE_WRAP_CLAMP, &err), CST_OK);
    const TexImage *im = t.image.im;
    assert_int_equal(im->format, TEXEL_F16);
    assert_int_equal(im->channels, 4);
    assert_int_equal(texture_image_bytes(&t), (size_t)N * 4 * 2);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            int i = y * W + x;
            assert_true(mipmap_bilerp_float(im, 0, TEXTURE_WRAP_CLAMP, centre(x, y)) == g_alpha[i]);
            Color c = mipmap_texel(im, 0, x, y, TEXTURE_WRAP_CLAMP);
            assert_true(c.c[0] == g_r[i] && c.c[1] == g_g[i] && c.c[2] == g_b[i]);
        }
    /* the pyramid stays half: level 1 (2 x 1) holds each box average rounded to a half */
    assert_int_equal(texture_set_filter(&t, TEXTURE_FILTER_TRILINEAR, 8.0f, &err), CST_OK);
    im = t.image.im;
    assert_true(im->num_levels >= 2 && im->level[1].width == 2 && im->level[1].height == 1);
    const double w0 = 1.0 / 1.5, w1 = 0.5 / 1.5; /* output 0 covers texel 0 and half of texel 1 */
    double a0 = 0.5 * (w0 * (double)g_alpha[0] + w1 * (double)g_alpha[1]) +
                0.5 * (w0 * (double)g_alpha[3] + w1 * (double)g_alpha[4]);
    float got = half_to_float(((const uint16_t *)im->level[1].texels)[3]);
    assert_true(got == half_to_float(float_to_half((float)a0)));
    texture_free(&t);

    write_rgba("tex_opaque.exr", 1, g_opaque, p, sizeof p);
    assert_int_equal(texture_image_load(&t, p, true, TEXTURE_WRAP_CLAMP, &err), CST_OK);
    assert_int_equal(t.image.im->channels, 3);
    assert_int_equal(t.image.im->format, TEXEL_F16);
    assert_true(mipmap_bilerp_float(t.image.im, 0, TEXTURE_WRAP_CLAMP, centre(1, 1)) ==
                (g_r[4] + g_g[4] + g_b[4]) / 3.0f); /* pbrt-v4's mean of R, G, B */
    texture_free(&t);

    float bad[N];
    memcpy(bad, g_alpha, sizeof bad);
    bad[4] = -0.5f; /* pixel (1, 1) */
    write_rgba("tex_negative.exr", 1, bad, p, sizeof p);
    assert_int_equal(texture_image_load(&t, p, true, TEXTURE_WRAP_CLAMP, &err), CST_ERR_INVALID_ARG);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "tex_negative.exr: pixel (1, 1) channel A is -0.5"));
}

static int setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_texexr.XXXXXX");
}

static int teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_half_every_value),
        cmocka_unit_test(test_half_rounding),
        cmocka_unit_test(test_exr_texels),
        cmocka_unit_test(test_exr_textures),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
