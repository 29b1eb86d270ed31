/* Unit tests for textures (textures/texture.c) and texture coordinates: exact bilinear
 * lookups and wrapping on a tiny image, sRGB decoding of 8-bit files, float formats taken
 * as they are, checkerboards, uvs at triangle, quad, sphere and instance hits and at
 * sampled emitter points, and the JSON "textures" section with its errors. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <jpeglib.h> /* after stdio.h, which it needs */
#include <stb_image_write.h>

#include "io/image_io.h"
#include "scene/scene.h"
#include "textures/mipmap.h"
#include "textures/noise.h"
#include "textures/texture.h"

/* Writes w x h RGB pixels as a quality-100 JPEG through libjpeg-turbo (stb_image_write's
 * JPEG writer shifts into the sign bit, which UBSan reports). */
static void write_jpeg(const char *path, int w, int h, const unsigned char *rgb)
{
    FILE *fp = fopen(path, "wb");
    assert_non_null(fp);
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr e;
    c.err = jpeg_std_error(&e);
    jpeg_create_compress(&c);
    jpeg_stdio_dest(&c, fp);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = 3;
    c.in_color_space = JCS_RGB;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 100, TRUE);
    jpeg_start_compress(&c, TRUE);
    for (int y = 0; y < h; y++) {
        JSAMPROW row = (JSAMPROW)(uintptr_t)(rgb + (size_t)y * (size_t)w * 3);
        jpeg_write_scanlines(&c, &row, 1);
    }
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    assert_int_equal(fclose(fp), 0);
}

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_texture.XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static void assert_rgb_near(Color got, double r, double g, double b, double tol)
{
    if (!(fabs((double)got.c[0] - r) <= tol && fabs((double)got.c[1] - g) <= tol && fabs((double)got.c[2] - b) <= tol))
        fail_msg("got (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g) within %g", (double)got.c[0], (double)got.c[1],
                 (double)got.c[2], r, g, b, tol);
}

/* The sRGB EOTF (IEC 61966-2-1), written out independently of image_io.c. */
static double srgb_eotf(double s) { return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4); }

/* ------------------------------------------------------------------ images */

enum { IW = 3, IH = 2 };
/* Texel (x, y) of the 3 x 2 test image, y = 0 the top row: dyadic values, so bilinear
 * weights of 1/2 and 1/4 give exact results. */
static void texel(int x, int y, float out[3])
{
    out[0] = (float)x + 4.0f * (float)y;
    out[1] = 0.25f * (float)x;
    out[2] = 0.5f + 0.5f * (float)y;
}

static Texture tiny_image(TextureWrap wrap)
{
    float *px = malloc(IW * IH * 3 * sizeof *px);
    assert_non_null(px);
    for (int y = 0; y < IH; y++)
        for (int x = 0; x < IW; x++) texel(x, y, &px[3 * (y * IW + x)]);
    Texture t;
    CstError err;
    assert_int_equal(texture_image(&t, px, IW, IH, wrap, &err), CST_OK);
    return t;
}

/* A negative or non-finite texel is rejected with its place and value in the message
 * (texture_image takes the pixels and frees them on failure too; ASan checks that the
 * message is written before). */
static void test_image_rejects_bad_texels(void **state)
{
    (void)state;
    float *px = calloc(IW * IH * 3, sizeof *px);
    assert_non_null(px);
    px[3 * (1 * IW + 2) + 1] = -0.5f;
    Texture t;
    CstError err = {0};
    assert_int_equal(texture_image(&t, px, IW, IH, TEXTURE_WRAP_REPEAT, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "pixel (2, 1) channel G is -0.5; expected a finite value >= 0"));
}

/* uv of the centre of texel (x, y) (v = 0 is the bottom row). */
static Vec2 centre(double x, double y) { return v2((float)((x + 0.5) / IW), (float)(1.0 - (y + 0.5) / IH)); }

static void expect_mix(const Texture *t, Vec2 uv, const int (*xy)[2], int n)
{
    double want[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        float c[3];
        texel(xy[i][0], xy[i][1], c);
        for (int k = 0; k < 3; k++) want[k] += (double)c[k] / n;
    }
    assert_rgb_near(texture_eval(t, 0, uv), want[0], want[1], want[2], 1e-5);
}

static void test_bilinear_exact(void **state)
{
    (void)state;
    for (int w = 0; w < 2; w++) {
        Texture t = tiny_image(w ? TEXTURE_WRAP_CLAMP : TEXTURE_WRAP_REPEAT);
        /* texel centres give the texels */
        for (int y = 0; y < IH; y++)
            for (int x = 0; x < IW; x++) {
                int one[1][2] = {{x, y}};
                expect_mix(&t, centre(x, y), one, 1);
            }
        /* half way between two texel centres, and the middle of four */
        int pair[2][2] = {{0, 0}, {1, 0}};
        expect_mix(&t, centre(0.5, 0), pair, 2);
        int four[4][2] = {{1, 0}, {2, 0}, {1, 1}, {2, 1}};
        expect_mix(&t, centre(1.5, 0.5), four, 4);
        /* a quarter of the way from (0, 1) to (1, 1): weights 3/4, 1/4 */
        float a[3], b[3];
        texel(0, 1, a);
        texel(1, 1, b);
        assert_rgb_near(texture_eval(&t, 0, centre(0.25, 1)), 0.75 * (double)a[0] + 0.25 * (double)b[0],
                        0.75 * (double)a[1] + 0.25 * (double)b[1], 0.75 * (double)a[2] + 0.25 * (double)b[2], 1e-5);
        /* average and max over the texels */
        assert_rgb_near(t.average, (0 + 1 + 2 + 4 + 5 + 6) / 6.0, 0.25, 0.75, 1e-6);
        assert_rgb_near(t.max, 6.0, 0.5, 1.0, 0.0);
        texture_free(&t);
    }
    /* At the left edge (u = 0, the first centre is half a texel in): repeat mixes the last
     * and first columns equally, clamp sees the first column; a whole period away is the
     * same point under repeat. */
    Texture rep = tiny_image(TEXTURE_WRAP_REPEAT), cl = tiny_image(TEXTURE_WRAP_CLAMP);
    int wrapped[2][2] = {{2, 0}, {0, 0}}, first[1][2] = {{0, 0}};
    Vec2 edge = v2(0.0f, centre(0, 0).y);
    expect_mix(&rep, edge, wrapped, 2);
    expect_mix(&cl, edge, first, 1);
    int one[1][2] = {{1, 1}};
    expect_mix(&rep, v2(centre(1, 1).x + 3.0f, centre(1, 1).y - 2.0f), one, 1);
    /* clamp: far outside is the corner texel; non-finite uv counts as 0 */
    int corner[1][2] = {{2, 0}};
    expect_mix(&cl, v2(50.0f, 50.0f), corner, 1);
    Color nan_uv = texture_eval(&cl, 0, v2(NAN, INFINITY));
    assert_true(color_is_finite(nan_uv));
    texture_free(&rep);
    texture_free(&cl);
}

static void test_srgb_decode(void **state)
{
    (void)state;
    /* A 4 x 1 PNG with the bytes 0, 10, 128, 255 in every channel: image_write encodes
     * linear values, so give it the linear values of those bytes. */
    static const int bytes[4] = {0, 10, 128, 255};
    float px[12];
    for (int i = 0; i < 4; i++) px[3 * i] = px[3 * i + 1] = px[3 * i + 2] = (float)srgb_eotf(bytes[i] / 255.0);
    char path[512];
    tpath(path, sizeof path, "ramp.png");
    CstError err;
    assert_int_equal(image_write(path, px, 4, 1, &err), CST_OK);
    for (int linear = 0; linear < 2; linear++) {
        Texture t;
        assert_int_equal(texture_image_load(&t, path, linear, TEXTURE_WRAP_CLAMP, &err), CST_OK);
        assert_int_equal(t.image.width, 4);
        assert_int_equal(t.image.height, 1);
        for (int i = 0; i < 4; i++) {
            double s = bytes[i] / 255.0, want = linear ? s : srgb_eotf(s);
            Color got = texture_eval(&t, 0, v2((float)((i + 0.5) / 4.0), 0.5f));
            assert_rgb_near(got, want, want, want, 1e-6);
        }
        texture_free(&t);
    }
    /* Known values of the curve: byte 128 is 0.2158605 linear, byte 10 is 10/255/12.92. */
    assert_true(fabs(srgb_eotf(128 / 255.0) - 0.21586050011389923) < 1e-12);
    assert_true(fabs(srgb_eotf(10 / 255.0) - 0.0030352698354883752) < 1e-12);
}

/* 8-bit files stay 8-bit (one byte per channel, grey files one channel) and decode at
 * lookup to exactly the floats of the sRGB curve's table; a gamma encoding decodes to
 * (code / 255)^g. */
static void test_compact_storage(void **state)
{
    (void)state;
    enum { W = 5, H = 3 };
    unsigned char rgb[W * H * 3], grey[W * H];
    for (int i = 0; i < W * H * 3; i++) rgb[i] = (unsigned char)(17 * i + 3);
    for (int i = 0; i < W * H; i++) grey[i] = (unsigned char)(29 * i + 1);
    char prgb[512], pgrey[512];
    tpath(prgb, sizeof prgb, "compact_rgb.png");
    tpath(pgrey, sizeof pgrey, "compact_grey.png");
    assert_true(stbi_write_png(prgb, W, H, 3, rgb, W * 3));
    assert_true(stbi_write_png(pgrey, W, H, 1, grey, W));
    CstError err;
    Texture t, g, gam;
    assert_int_equal(texture_image_load(&t, prgb, false, TEXTURE_WRAP_CLAMP, &err), CST_OK);
    assert_int_equal(texture_image_load(&g, pgrey, false, TEXTURE_WRAP_CLAMP, &err), CST_OK);
    assert_int_equal(texture_image_load_encoded(&gam, pgrey, TEXEL_GAMMA, 2.2f, TEXTURE_WRAP_CLAMP, &err), CST_OK);
    assert_int_equal(t.image.im->format, TEXEL_U8);
    assert_int_equal(t.image.im->channels, 3);
    assert_int_equal(g.image.im->channels, 1);
    assert_int_equal(texture_image_bytes(&t), W * H * 3);
    assert_int_equal(texture_image_bytes(&g), W * H);
    for (int y = 0; y < H; y++)
        for (int x = 0; x < W; x++) {
            Color c = texture_texel(&t, 0, x, y), cg = texture_texel(&g, 0, x, y), cm = texture_texel(&gam, 0, x, y);
            for (int k = 0; k < 3; k++) {
                assert_true(c.c[k] == image_srgb_to_linear(rgb[(y * W + x) * 3 + k] / 255.0));
                if (cg.c[k] != image_srgb_to_linear(grey[y * W + x] / 255.0))
                    fail_msg("grey texel (%d, %d): %.9g, code %d", x, y, (double)cg.c[k], grey[y * W + x]);
                assert_true(fabsf(cm.c[k] - powf(grey[y * W + x] / 255.0f, 2.2f)) <= 1e-7f);
            }
        }
    /* A shared copy with a value map: no new pixels, the map applied after the lookup. */
    Texture s2;
    texture_share(&s2, &t);
    assert_true(texture_add_op(&s2, TEXTURE_OP_AFFINE, color_s(-0.5f), color_s(1.0f)));
    assert_true(s2.image.im == t.image.im && t.image.im->refs == 2);
    Color a = texture_eval(&t, 0, v2(0.3f, 0.3f)), b = texture_eval(&s2, 0, v2(0.3f, 0.3f));
    for (int k = 0; k < 3; k++) assert_true(b.c[k] == maxf(0.0f, -0.5f * a.c[k] + 1.0f));
    texture_free(&s2);
    assert_int_equal(t.image.im->refs, 1);
    texture_free(&t);
    texture_free(&g);
    texture_free(&gam);
}

/* A float image of w x h texels from f(x, y, channel). */
static Texture float_image(int w, int h, float (*f)(int, int, int))
{
    float *px = malloc((size_t)w * (size_t)h * 3 * sizeof *px);
    assert_non_null(px);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int k = 0; k < 3; k++) px[(y * w + x) * 3 + k] = f(x, y, k);
    Texture t;
    CstError err;
    assert_int_equal(texture_image(&t, px, w, h, TEXTURE_WRAP_REPEAT, &err), CST_OK);
    return t;
}

static float f_const(int x, int y, int k) { (void)x, (void)y; return 0.25f + 0.25f * (float)k; }
static float f_hash(int x, int y, int k)
{
    uint32_t v = (uint32_t)x * 73856093u ^ (uint32_t)y * 19349663u ^ (uint32_t)k * 83492791u;
    v ^= v >> 13, v *= 0x5bd1e995u, v ^= v >> 15;
    return (float)(v & 0xffff) / 65535.0f;
}
static float f_checker(int x, int y, int k) { (void)k; return (float)((x + y) & 1); }

/* The mean of level l's texels, channel k. */
static double level_mean(const Texture *t, int l, int k)
{
    const TexLevel *lv = &t->image.im->level[l];
    double sum = 0.0;
    for (int y = 0; y < lv->height; y++)
        for (int x = 0; x < lv->width; x++) sum += (double)texture_texel(t, l, x, y).c[k];
    return sum / ((double)lv->width * (double)lv->height);
}

/* MIP pyramids: levels halve (rounded up) down to 1 x 1; an area-weighted box filter keeps
 * every level's mean equal to level 0's (odd sizes included); a constant image stays that
 * constant on every level and through every filter and footprint. */
static void test_mipmap_levels(void **state)
{
    (void)state;
    CstError err;
    static const int sizes[3][2] = {{64, 48}, {37, 21}, {1, 9}};
    for (int si = 0; si < 3; si++) {
        int w = sizes[si][0], h = sizes[si][1];
        Texture t = float_image(w, h, f_hash);
        assert_int_equal(texture_set_filter(&t, TEXTURE_FILTER_TRILINEAR, 0.0f, &err), CST_OK);
        const TexImage *im = t.image.im;
        int lw = w, lh = h, l = 0;
        for (; l < im->num_levels; l++) {
            assert_int_equal(im->level[l].width, lw);
            assert_int_equal(im->level[l].height, lh);
            for (int k = 0; k < 3; k++) {
                double m0 = level_mean(&t, 0, k), ml = level_mean(&t, l, k);
                if (fabs(ml - m0) > 1e-6) fail_msg("%dx%d level %d channel %d: mean %.9f, level 0 %.9f", w, h, l, k, ml, m0);
            }
            lw = lw > 1 ? (lw + 1) / 2 : 1, lh = lh > 1 ? (lh + 1) / 2 : 1;
        }
        assert_int_equal(im->level[im->num_levels - 1].width * im->level[im->num_levels - 1].height, 1);
        texture_free(&t);
    }
    Texture c = float_image(37, 21, f_const);
    assert_int_equal(texture_set_filter(&c, TEXTURE_FILTER_EWA, 0.0f, &err), CST_OK);
    for (int l = 0; l < c.image.im->num_levels; l++)
        for (int k = 0; k < 3; k++) assert_true(fabs(level_mean(&c, l, k) - (double)f_const(0, 0, k)) < 1e-7);
    static const TextureFilter filters[4] = {TEXTURE_FILTER_POINT, TEXTURE_FILTER_BILINEAR, TEXTURE_FILTER_TRILINEAR,
                                             TEXTURE_FILTER_EWA};
    for (int fi = 0; fi < 4; fi++)
        for (int i = 0; i < 200; i++) {
            float d = ldexpf(1.0f, -(i % 12)) * (float)(1 + i % 3);
            Vec2 st = v2(f_hash(i, 1, 0) * 3.0f - 1.0f, f_hash(i, 2, 0) * 3.0f - 1.0f);
            Color v = mipmap_filter(c.image.im, TEXTURE_WRAP_REPEAT, filters[fi], 8.0f, st, v2(d, 0.3f * d),
                                    v2(-0.1f * d, 0.5f * d));
            assert_rgb_near(v, 0.25, 0.5, 0.75, 2e-6);
        }
    texture_free(&c);
}

/* Level selection (pbrt-v4 MIPMap::Filter): a checkerboard of single texels is 0 or 1 on
 * level 0 and 0.5 on every coarser level, so the footprint decides which one is seen. */
static void test_mipmap_filters(void **state)
{
    (void)state;
    CstError err;
    Texture t = float_image(64, 64, f_checker);
    assert_int_equal(texture_set_filter(&t, TEXTURE_FILTER_BILINEAR, 0.0f, &err), CST_OK);
    const TexImage *im = t.image.im;
    assert_int_equal(im->num_levels, 7);
    Vec2 centre = v2(10.5f / 64.0f, 1.0f - 20.5f / 64.0f); /* texel (10, 20): even, 0 */
    Vec2 z = v2(0.0f, 0.0f);
    /* No footprint: level 0. A footprint of 2 texels (width = 2 max|d| = 2/64): level 1. */
    for (int fi = TEXTURE_FILTER_POINT; fi <= TEXTURE_FILTER_EWA; fi++) {
        Color v0 = mipmap_filter(im, TEXTURE_WRAP_REPEAT, (TextureFilter)fi, 8.0f, centre, z, z);
        if (fi == TEXTURE_FILTER_EWA) assert_true(v0.c[0] == 0.0f); /* falls back to level 0's bilinear */
        else assert_rgb_near(v0, 0.0, 0.0, 0.0, 0.0);
    }
    Vec2 d1 = v2(1.0f / 64.0f, 0.0f), d2 = v2(0.0f, 1.0f / 64.0f);
    assert_rgb_near(mipmap_filter(im, TEXTURE_WRAP_REPEAT, TEXTURE_FILTER_BILINEAR, 8.0f, centre, d1, d2), 0.5, 0.5, 0.5, 0.0);
    assert_rgb_near(mipmap_filter(im, TEXTURE_WRAP_REPEAT, TEXTURE_FILTER_POINT, 8.0f, centre, d1, d2), 0.5, 0.5, 0.5, 0.0);
    /* Half a texel: level 0 (log2(1/64) = -6 below the top of 6). */
    Vec2 h1 = v2(0.5f / 64.0f, 0.0f), h2 = v2(0.0f, 0.5f / 64.0f);
    assert_rgb_near(mipmap_filter(im, TEXTURE_WRAP_REPEAT, TEXTURE_FILTER_BILINEAR, 8.0f, centre, h1, h2), 0.0, 0.0, 0.0, 0.0);
    /* Trilinear between level 0 (0) and 1 (0.5) is pbrt-v4's level-0 bilinear below level
     * 1; between levels 1 and 2 both are 0.5. */
    Vec2 t1 = v2(1.5f / 64.0f, 0.0f);
    assert_rgb_near(mipmap_filter(im, TEXTURE_WRAP_REPEAT, TEXTURE_FILTER_TRILINEAR, 8.0f, centre, t1, d2), 0.5, 0.5, 0.5, 1e-7);
    /* EWA over a footprint of several texels averages the checker to about 0.5. */
    Vec2 e1 = v2(4.0f / 64.0f, 1.0f / 64.0f), e2 = v2(-1.0f / 64.0f, 3.0f / 64.0f);
    Color e = mipmap_filter(im, TEXTURE_WRAP_REPEAT, TEXTURE_FILTER_EWA, 8.0f, centre, e1, e2);
    assert_rgb_near(e, 0.5, 0.5, 0.5, 0.02);
    /* Huge footprints: the 1 x 1 top level, the image's mean. */
    Vec2 b1 = v2(4.0f, 0.0f), b2 = v2(0.0f, 4.0f);
    for (int fi = TEXTURE_FILTER_POINT; fi <= TEXTURE_FILTER_EWA; fi++)
        assert_rgb_near(mipmap_filter(im, TEXTURE_WRAP_REPEAT, (TextureFilter)fi, 8.0f, centre, b1, b2), 0.5, 0.5, 0.5, 1e-6);
    /* Through texture_eval_ctx: the footprint is scaled by the texture's uv map. */
    texture_set_uv_transform(&t, v2(2.0f, 2.0f), v2(0.0f, 0.0f));
    TexCtx ctx = {.uv = v2(centre.x * 0.5f, centre.y * 0.5f), .dudx = 0.5f / 64.0f, .dvdy = 0.5f / 64.0f};
    assert_rgb_near(texture_eval_ctx(&t, 0, &ctx), 0.5, 0.5, 0.5, 0.0);
    texture_free(&t);
}

/* Footprints (scene/footprint.c): an orthographic camera's pixel is 2 h aspect / W wide,
 * scaled by pbrt-v4's max(1/8, 1/sqrt(spp)); on a quad facing it whose u spans 4 units,
 * du/dx is that over 4. A 90-degree pinhole's smallest per-pixel change of direction is
 * at the film's corner, |d normalize(v) / d sx| = sqrt(6) / 3 / sqrt(3) at v = (1, 1, 1),
 * times the step 2 / H, and the footprint at distance L on a facing plane is L times it. */
static void test_footprint(void **state)
{
    (void)state;
    CameraDesc o = {0};
    o.position = v3(0, 0, -5), o.look_at = v3(0, 0, 0), o.up = v3(0, 1, 0);
    o.vfov_deg = 40.0f, o.focus_distance = 1.0f, o.ortho_height = 2.0f;
    Footprint fp;
    footprint_init(&fp, &o, false, 100, 50, 16);
    assert_true(fabsf(fp.spp_scale - 0.25f) < 1e-7f);
    TexCtx c = footprint_tex_ctx(&fp, v3(0.3f, -0.2f, 0.0f), v3(0, 0, -1), v2(0.5f, 0.5f), v3(4, 0, 0), v3(0, 4, 0));
    double px = 2.0 * 1.0 * 2.0 / 100.0 * 0.25;
    if (fabs(fabs((double)c.dudx) - px / 4.0) > 1e-6 || fabs((double)c.dvdx) > 1e-6 ||
        fabs((double)c.dudy) > 1e-6 || fabs(fabs((double)c.dvdy) - px / 4.0) > 1e-6)
        fail_msg("orthographic: du/dx %g dv/dx %g du/dy %g dv/dy %g, expected +-%g on the diagonal", (double)c.dudx,
                 (double)c.dvdx, (double)c.dudy, (double)c.dvdy, px / 4.0);
    /* Tilted 60 degrees about x: the y footprint stretches by 1 / cos 60 = 2 on the plane. */
    Vec3 n = v3(0.0f, sinf(CST_PI / 3.0f), -cosf(CST_PI / 3.0f));
    Vec3 dpdx, dpdy;
    footprint_dp_dxy(&fp, v3(0, 0, 0), n, &dpdx, &dpdy);
    assert_true(fabs((double)v3_length(dpdx) - px) < 1e-6 && fabs((double)v3_length(dpdy) - 2.0 * px) < 1e-5);
    CameraDesc pc = {0};
    pc.position = v3(0, 0, 0), pc.look_at = v3(0, 0, 1), pc.up = v3(0, 1, 0);
    pc.vfov_deg = 90.0f, pc.focus_distance = 1.0f;
    footprint_init(&fp, &pc, false, 64, 64, 1);
    double want = sqrt(6.0) / 3.0 / sqrt(3.0) * 2.0 / 64.0;
    if (fabs((double)fp.dir_dx - want) > 0.03 * want) fail_msg("pinhole: dir_dx %g, expected %g", (double)fp.dir_dx, want);
    footprint_dp_dxy(&fp, v3(0, 0, 7), v3(0, 0, -1), &dpdx, &dpdy);
    assert_true(fabs((double)v3_length(dpdx) - 7.0 * (double)fp.dir_dx) < 1e-5);
    assert_true(fabs((double)v3_length(dpdy) - 7.0 * (double)fp.dir_dy) < 1e-5);
}

/* Perlin noise: 0 on the integer lattice, period 256, within [-1, 1], continuous. Octave
 * sums: a footprint of one unit resolves no octave (n = -1 - log2(1) / 2 < 0), so fBm is 0
 * and turbulence is 0.2 sum omega^i over the octaves, exactly. */
static void test_noise(void **state)
{
    (void)state;
    for (int i = -5; i <= 5; i++) assert_true(noise3(v3((float)i, (float)(2 * i), (float)(300 - i))) == 0.0f);
    float lo = 0.0f, hi = 0.0f;
    for (int i = 0; i < 20000; i++) {
        Vec3 p = v3(f_hash(i, 0, 0) * 40.0f - 20.0f, f_hash(i, 1, 0) * 40.0f - 20.0f, f_hash(i, 2, 0) * 40.0f - 20.0f);
        float n = noise3(p);
        lo = minf(lo, n), hi = maxf(hi, n);
        assert_true(fabsf(noise3(v3(p.x + 256.0f, p.y, p.z - 256.0f)) - n) < 1e-4f); /* period */
        assert_true(fabsf(noise3(v3(p.x + 1e-3f, p.y, p.z)) - n) < 1e-2f);         /* continuity */
    }
    assert_true(lo >= -1.0f && hi <= 1.0f && lo < -0.5f && hi > 0.5f);
    Vec3 one = v3(1.0f, 0.0f, 0.0f), z = v3(0.0f, 0.0f, 0.0f);
    assert_true(noise_fbm(v3(0.3f, 0.7f, 0.1f), one, z, 0.5f, 8) == 0.0f);
    /* pbrt-v4's Turbulence: the partly resolved octave (here none of it) blends toward 0.2,
     * then each octave from it on adds 0.2 omega^i, the first at the same weight. */
    float want = 0.2f, o = 1.0f;
    for (int i = 0; i < 8; i++, o *= 0.5f) want += 0.2f * o;
    assert_true(fabsf(noise_turbulence(v3(0.3f, 0.7f, 0.1f), one, z, 0.5f, 8) - want) < 1e-6f);
    /* No footprint: all octaves, the sum of the scaled lookups. */
    Vec3 p = v3(0.3f, 0.7f, 0.1f);
    float sum = 0.0f, lambda = 1.0f;
    o = 1.0f;
    for (int i = 0; i < 3; i++, lambda *= 1.99f, o *= 0.6f) sum += o * noise3(v3_scale(p, lambda));
    assert_true(fabsf(noise_fbm(p, z, z, 0.6f, 3) - sum) < 1e-6f);
}

/* Procedural and combining textures against closed forms: mix, scale and bilerp values,
 * directionmix at |n . dir| = 1, 0 and 0.6, the 3D checkerboard's mean over a cube of
 * whole cells (exactly 1/2 at cell centres), its texture_from_world map, the dots' area
 * fraction near pi 0.35^2 / 2, the marble spline's range. */
static void test_procedural(void **state)
{
    (void)state;
    Texture tex[12];
    texture_constant(&tex[0], color_rgb(0.2f, 0.4f, 0.6f));
    texture_constant(&tex[1], color_rgb(1.0f, 0.5f, 0.0f));
    texture_constant(&tex[2], color_s(0.25f));
    TextureProc pr;
    memset(&pr, 0, sizeof pr);
    pr.tex1 = 0, pr.tex2 = 1, pr.amount = 2;
    assert_true(texture_procedural(&tex[3], TEXTURE_MIX, &pr, tex));
    pr.amount = -1, pr.dir = v3(0.0f, 0.0f, 1.0f);
    assert_true(texture_procedural(&tex[4], TEXTURE_DIRECTIONMIX, &pr, tex));
    pr.tex2 = -1, pr.amount = 2;
    assert_true(texture_procedural(&tex[5], TEXTURE_SCALE, &pr, tex));
    memset(&pr, 0, sizeof pr);
    pr.tex1 = pr.tex2 = pr.amount = -1;
    pr.corner[0] = color_s(0.0f), pr.corner[1] = color_s(1.0f), pr.corner[2] = color_s(2.0f), pr.corner[3] = color_s(4.0f);
    assert_true(texture_procedural(&tex[6], TEXTURE_BILERP, &pr, tex));
    pr.tex1 = 0, pr.tex2 = 1;
    assert_true(texture_procedural(&tex[7], TEXTURE_CHECKER3D, &pr, tex));
    pr.xf[0] = 2.0f, pr.xf[5] = 1.0f, pr.xf[10] = 1.0f, pr.xf[3] = 0.5f; /* x' = 2x + 0.5 */
    assert_true(texture_procedural(&tex[8], TEXTURE_CHECKER3D, &pr, tex));
    memset(pr.xf, 0, sizeof pr.xf);
    assert_true(texture_procedural(&tex[9], TEXTURE_DOTS, &pr, tex));
    pr.tex1 = pr.tex2 = -1, pr.octaves = 8, pr.omega = 0.5f, pr.scale = 1.0f, pr.variation = 0.2f;
    assert_true(texture_procedural(&tex[10], TEXTURE_MARBLE, &pr, tex));
    TexCtx c = {.uv = v2(0.25f, 0.75f), .n = v3(0.0f, 0.0f, 1.0f)};
    assert_rgb_near(texture_eval_ctx(tex, 3, &c), 0.75 * 0.2 + 0.25, 0.75 * 0.4 + 0.125, 0.75 * 0.6, 1e-6);
    assert_rgb_near(texture_eval_ctx(tex, 4, &c), 0.2, 0.4, 0.6, 1e-7);
    c.n = v3(1.0f, 0.0f, 0.0f);
    assert_rgb_near(texture_eval_ctx(tex, 4, &c), 1.0, 0.5, 0.0, 1e-7);
    c.n = v3(0.8f, 0.0f, -0.6f);
    assert_rgb_near(texture_eval_ctx(tex, 4, &c), 0.6 * 0.2 + 0.4, 0.6 * 0.4 + 0.2, 0.6 * 0.6, 1e-6);
    assert_rgb_near(texture_eval_ctx(tex, 5, &c), 0.05, 0.1, 0.15, 1e-7);
    /* bilerp (1-s)(1-t) v00 + (1-s) t v01 + s (1-t) v10 + s t v11 at (0.25, 0.75) */
    double b = 0.75 * 0.25 * 0 + 0.75 * 0.75 * 1 + 0.25 * 0.25 * 2 + 0.25 * 0.75 * 4;
    assert_rgb_near(texture_eval_ctx(tex, 6, &c), b, b, b, 1e-6);
    assert_rgb_near(tex[6].average, 1.75, 1.75, 1.75, 1e-6);
    /* 3D checker: the mean over the 4 x 4 x 4 cells' centres is exactly half of each. */
    double sum[2] = {0.0, 0.0};
    for (int i = 0; i < 64; i++) {
        c.p = v3((float)(i % 4) - 1.5f, (float)(i / 4 % 4) - 1.5f, (float)(i / 16) - 1.5f);
        sum[0] += (double)texture_eval_ctx(tex, 7, &c).c[0];
        sum[1] += (double)texture_eval_ctx(tex, 8, &c).c[0];
    }
    assert_true(fabs(sum[0] / 64.0 - 0.6) < 1e-6 && fabs(sum[1] / 64.0 - 0.6) < 1e-6);
    c.p = v3(0.3f, 0.5f, 0.5f); /* x' = 1.1: odd */
    assert_rgb_near(texture_eval_ctx(tex, 8, &c), 1.0, 0.5, 0.0, 1e-7);
    c.p = v3(0.2f, 0.5f, 0.5f); /* x' = 0.9: even */
    assert_rgb_near(texture_eval_ctx(tex, 8, &c), 0.2, 0.4, 0.6, 1e-7);
    /* dots: the inside fraction over 40 x 40 cells, 16 x 16 points each */
    long inside = 0, total = 0;
    for (int y = 0; y < 640; y++)
        for (int x = 0; x < 640; x++, total++) {
            c.uv = v2(((float)x + 0.5f) / 16.0f, ((float)y + 0.5f) / 16.0f);
            inside += texture_eval_ctx(tex, 9, &c).c[0] == 0.2f;
        }
    double frac = (double)inside / (double)total;
    if (!(frac > 0.12 && frac < 0.27)) fail_msg("dots cover %.3f of the plane, expected about 0.19", frac);
    for (int i = 0; i < 500; i++) {
        c.p = v3(f_hash(i, 5, 0) * 10.0f, f_hash(i, 6, 0) * 10.0f, f_hash(i, 7, 0) * 10.0f);
        Color m = texture_eval_ctx(tex, 10, &c);
        assert_true(m.c[0] >= 1.5f * 0.2f - 1e-6f && m.c[0] <= 1.5f * 0.6f + 1e-6f);
    }
    /* nesting depth is bounded */
    Texture deep[TEXTURE_MAX_DEPTH + 2];
    texture_constant(&deep[0], color_s(1.0f));
    memset(&pr, 0, sizeof pr);
    pr.tex2 = -1, pr.amount = -1, pr.amount_value = 0.5f;
    bool ok = true;
    for (int i = 1; i < TEXTURE_MAX_DEPTH + 2 && ok; i++) {
        pr.tex1 = pr.tex2 = i - 1;
        ok = texture_procedural(&deep[i], TEXTURE_MIX, &pr, deep);
        if (!ok) assert_int_equal(i, TEXTURE_MAX_DEPTH);
    }
    assert_false(ok);
}

/* The hit of a ray straight down (-z) at (x, y) on a scene's quad. */
static SurfaceHit hit_at(const Scene *s, float x, float y)
{
    Ray r = ray_make(v3(x, y, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, 10.0f);
    SurfaceHit sh;
    assert_true(scene_intersect(s, &r, &sh));
    return sh;
}

/* Bump mapping of a known height field: on the unit quad z = 0 with (u, v) = (x, y), the
 * displacement h = a u + b v (a bilerp texture) moves the surface to (u, v, h), whose
 * normal is normalize(-a, -b, 1); forward differences are exact on a plane. A normal map
 * of one tangent-space normal t (float texels 0.5 + 0.5 t) gives t in the frame (dp/du,
 * n x dp/du, n) = (x, y, z). */
static void test_bump_and_normal_map(void **state)
{
    (void)state;
    CstError err;
    for (int kind = 0; kind < 2; kind++) {
        CstScene *cs = NULL;
        assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
        const float a = 0.3f, b = 0.15f;
        Vec3 want;
        int tid = 0;
        CstTextureDesc t = {0};
        if (kind == 0) {
            t.type = CST_TEXTURE_BILERP;
            float c[4] = {0.0f, b, a, a + b}; /* v00, v01, v10, v11 */
            for (int i = 0; i < 4; i++) t.corners[i][0] = t.corners[i][1] = t.corners[i][2] = c[i];
            want = v3_normalize(v3(-a, -b, 1.0f));
        } else {
            Vec3 tn = v3_normalize(v3(0.3f, -0.2f, 1.0f));
            static float px[4 * 3];
            for (int i = 0; i < 4; i++)
                px[3 * i] = 0.5f + 0.5f * tn.x, px[3 * i + 1] = 0.5f + 0.5f * tn.y, px[3 * i + 2] = 0.5f + 0.5f * tn.z;
            t.type = CST_TEXTURE_IMAGE;
            t.pixels = px, t.width = 2, t.height = 2;
            want = tn;
        }
        assert_int_equal(cst_scene_add_texture(cs, &t, &tid, &err), CST_OK);
        CstMaterialDesc md;
        cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
        if (kind == 0) md.displacement_texture = tid;
        else md.normal_map_texture = tid;
        int mid = 0;
        assert_int_equal(cst_scene_add_material(cs, &md, &mid, &err), CST_OK);
        Scene *s = cs;
        const Vec3 q[4] = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), v3(0, 1, 0)};
        if (scene_add_quad(s, q, mid, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
        assert_int_equal(scene_commit(s, &err), CST_OK);
        for (int i = 0; i < 5; i++) {
            SurfaceHit sh = hit_at(s, 0.1f + 0.17f * (float)i, 0.8f - 0.13f * (float)i);
            Vec3 n = scene_bump(s, &s->materials[sh.material], &sh);
            /* Forward differences over du = 0.0005 of float heights up to 0.45 round the
             * slope by up to 2 ulp(0.45) / 0.0005 = 1.2e-4; the normal map is exact. */
            if (v3_length(v3_sub(n, want)) > (kind == 0 ? 2e-4f : 1e-6f))
                fail_msg("%s at hit %d: (%g, %g, %g), expected (%g, %g, %g)", kind ? "normal map" : "bump", i,
                         (double)n.x, (double)n.y, (double)n.z, (double)want.x, (double)want.y, (double)want.z);
            Bsdf bs;
            scene_bsdf(s, &sh, NULL, &bs);
        }
        cst_scene_destroy(cs);
    }
}

/* Float files are linear: EXR and PFM (through image_read) and Radiance HDR (stb_image)
 * come back as written; an 8-bit JPEG decodes through the sRGB curve. */
static void test_float_and_jpeg(void **state)
{
    (void)state;
    /* RGBE stores a shared exponent: (4, 2, 0.5) and (1, 0.25, 0.125) are exact in it. */
    float px[6] = {4.0f, 2.0f, 0.5f, 1.0f, 0.25f, 0.125f};
    static const char *const names[3] = {"f.exr", "f.pfm", "f.hdr"};
    CstError err;
    for (int k = 0; k < 3; k++) {
        char path[512];
        tpath(path, sizeof path, names[k]);
        if (k < 2) assert_int_equal(image_write(path, px, 2, 1, &err), CST_OK);
        else assert_true(stbi_write_hdr(path, 2, 1, 3, px) != 0);
        Texture t;
        /* linear = false must not touch float data */
        assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_CLAMP, &err), CST_OK);
        assert_rgb_near(texture_eval(&t, 0, v2(0.25f, 0.5f)), 4.0, 2.0, 0.5, 0.0);
        assert_rgb_near(texture_eval(&t, 0, v2(0.75f, 0.5f)), 1.0, 0.25, 0.125, 0.0);
        texture_free(&t);
    }
    /* A uniform JPEG block is its DC term: byte 200 comes back within one step. */
    unsigned char grey[8 * 8 * 3];
    memset(grey, 200, sizeof grey);
    char path[512];
    tpath(path, sizeof path, "g.jpg");
    write_jpeg(path, 8, 8, grey);
    Texture t;
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_OK);
    Color c = texture_eval(&t, 0, v2(0.5f, 0.5f));
    assert_true(fabs((double)c.c[0] - srgb_eotf(200 / 255.0)) < srgb_eotf(201 / 255.0) - srgb_eotf(200 / 255.0));
    texture_free(&t);
    /* failures: a missing file (I/O), a file that is no image (parse) */
    tpath(path, sizeof path, "missing.png");
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "missing.png"));
    tpath(path, sizeof path, "text.png");
    FILE *fp = fopen(path, "w");
    assert_non_null(fp);
    fputs("not an image at all\n", fp);
    fclose(fp);
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "text.png"));
}

static void test_checkerboard(void **state)
{
    (void)state;
    Texture tex[4];
    texture_constant(&tex[0], color_rgb(0.1f, 0.2f, 0.3f));
    texture_constant(&tex[1], color_rgb(0.9f, 0.8f, 0.7f));
    texture_checkerboard(&tex[2], tex, 0, 1, 2.0f); /* squares of 1/2 */
    /* (floor(2u) + floor(2v)) even -> texture 0 */
    assert_rgb_near(texture_eval(tex, 2, v2(0.1f, 0.1f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.6f, 0.1f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.1f, 0.6f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.6f, 0.6f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(-0.1f, 0.1f)), 0.9, 0.8, 0.7, 1e-7); /* floor(-0.2) = -1 */
    assert_rgb_near(texture_eval(tex, 2, v2(-0.1f, -0.1f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(1e30f, NAN)), 0.1, 0.2, 0.3, 1e-7); /* no overflow */
    assert_rgb_near(tex[2].average, 0.5, 0.5, 0.5, 1e-7);
    assert_rgb_near(tex[2].max, 0.9, 0.8, 0.7, 1e-7);
    /* nested: the odd squares of a coarse board are a finer board */
    texture_checkerboard(&tex[3], tex, 1, 2, 1.0f);
    assert_rgb_near(texture_eval(tex, 3, v2(0.3f, 0.3f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 3, v2(1.3f, 0.3f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 3, v2(1.3f, 0.8f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(tex[3].average, 0.7, 0.65, 0.6, 1e-6);
}

/* texture_set_uv_transform: an image looked up at (su u + du, sv v + dv); a checkerboard's
 * squares on its mapped coordinates while its textures see the coordinates unmapped. */
static void test_uv_transform(void **state)
{
    (void)state;
    Texture tex[4];
    tex[0] = tiny_image(TEXTURE_WRAP_REPEAT);
    float c[3];
    /* (0.5 u + 0.25, 2 v - 0.5): texel (1, 0)'s centre from the uv below */
    texture_set_uv_transform(&tex[0], v2(0.5f, 2.0f), v2(0.25f, -0.5f));
    Vec2 at = centre(1, 0);
    texel(1, 0, c);
    assert_rgb_near(texture_eval(tex, 0, v2((at.x - 0.25f) / 0.5f, (at.y + 0.5f) / 2.0f)), (double)c[0], (double)c[1],
                    (double)c[2], 1e-6);
    texture_constant(&tex[1], color_rgb(0.1f, 0.2f, 0.3f));
    texture_constant(&tex[2], color_rgb(0.9f, 0.8f, 0.7f));
    texture_checkerboard(&tex[3], tex, 0, 1, 1.0f);
    texture_set_uv_transform(&tex[3], v2(2.0f, 1.0f), v2(-0.5f, 0.0f));
    /* uv = (0.5, 0.625) -> (s, t) = (0.5, 0.625), even: the image, at the unmapped uv */
    Vec2 uv = v2((at.x - 0.25f) / 0.5f, (at.y + 0.5f) / 2.0f);
    assert_rgb_near(texture_eval(tex, 3, uv), (double)c[0], (double)c[1], (double)c[2], 1e-6);
    assert_rgb_near(texture_eval(tex, 3, v2(0.8f, 0.5f)), 0.1, 0.2, 0.3, 1e-7); /* s = 1.1: odd */
    texture_free(&tex[0]);
}

/* ------------------------------------------------------------------ uvs at hits */

/* The closest hit of a ray from o toward target. */
static SurfaceHit hit_toward(const Scene *s, Vec3 o, Vec3 target)
{
    SurfaceHit sh;
    Ray r = ray_make(o, v3_normalize(v3_sub(target, o)), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    return sh;
}

static Vec3 bary(Vec3 a, Vec3 b, Vec3 c, float b1, float b2)
{
    return v3_add(v3_add(v3_scale(a, 1.0f - b1 - b2), v3_scale(b, b1)), v3_scale(c, b2));
}

static void assert_uv(Vec2 got, double u, double v)
{
    if (!(fabs((double)got.x - u) < 1e-5 && fabs((double)got.y - v) < 1e-5))
        fail_msg("uv (%.7f, %.7f), expected (%.7f, %.7f)", (double)got.x, (double)got.y, u, v);
}

/* pbrt-v4's spherical, cylindrical and planar mappings (TextureMapping2D) against closed
 * forms of (s, t), their derivatives against finite differences, a texture_from_world, and
 * a checkerboard evaluated through a planar mapping. */
static Vec2 map_at(const Texture *t, Vec3 p, Vec3 dpdx, Vec2 *d0)
{
    TexCtx c = {.p = p, .dpdx = dpdx};
    Vec2 d1;
    return texture_map_st(t, &c, d0, &d1);
}

static void expect_st(const Texture *t, Vec3 p, float s, float tt)
{
    Vec2 d0, st = map_at(t, p, v3s(0.0f), &d0);
    if (!(fabsf(st.x - s) < 1e-6f && fabsf(st.y - tt) < 1e-6f))
        fail_msg("mapping %d at (%g, %g, %g): (%.7f, %.7f), closed form (%.7f, %.7f)", (int)t->mapping,
                 (double)p.x, (double)p.y, (double)p.z, (double)st.x, (double)st.y, (double)s, (double)tt);
    assert_true(d0.x == 0.0f && d0.y == 0.0f); /* no footprint: none */
}

/* d0 against central differences of (s, t) along dpdx (h = 1e-3 of it). */
static void expect_derivs(const Texture *t, Vec3 p, Vec3 dpdx, int swap)
{
    Vec2 d0, unused;
    map_at(t, p, dpdx, &d0);
    const float h = 1e-3f;
    Vec2 a = map_at(t, v3_madd(p, dpdx, h), v3s(0.0f), &unused), b = map_at(t, v3_madd(p, dpdx, -h), v3s(0.0f), &unused);
    Vec2 fd = v2((a.x - b.x) / (2.0f * h), (a.y - b.y) / (2.0f * h));
    if (swap) fd = v2(fd.y, fd.x); /* pbrt-v4's spherical mapping: see texture_map_st */
    if (!(fabsf(d0.x - fd.x) < 2e-3f * (1.0f + fabsf(fd.x)) && fabsf(d0.y - fd.y) < 2e-3f * (1.0f + fabsf(fd.y))))
        fail_msg("mapping %d: derivatives (%.6f, %.6f), differences (%.6f, %.6f)", (int)t->mapping, (double)d0.x,
                 (double)d0.y, (double)fd.x, (double)fd.y);
}

static void test_texture_mappings(void **state)
{
    (void)state;
    Texture t;
    texture_constant(&t, color_s(1.0f));
    texture_set_mapping(&t, TEXTURE_MAP_SPHERICAL, NULL, v3s(0.0f), v3s(0.0f), v2(0.0f, 0.0f));
    expect_st(&t, v3(0, 0, 2), 0.0f, 0.0f);         /* theta 0 */
    expect_st(&t, v3(3, 0, 0), 0.5f, 0.0f);         /* theta pi/2, phi 0 */
    expect_st(&t, v3(0, 1, 0), 0.5f, 0.25f);        /* phi pi/2 */
    expect_st(&t, v3(0, -1, 0), 0.5f, 0.75f);       /* phi 3pi/2: [0, 2pi) */
    expect_st(&t, v3(-1, 0, -1), 0.75f, 0.5f);      /* theta 3pi/4, phi pi */
    expect_derivs(&t, v3(0.3f, 0.5f, 0.4f), v3(0.02f, -0.01f, 0.03f), 1);
    /* texture_from_world: a translation by (-1, 0, 0) centres the sphere at x = 1 */
    const float xf[12] = {1, 0, 0, -1, 0, 1, 0, 0, 0, 0, 1, 0};
    texture_set_mapping(&t, TEXTURE_MAP_SPHERICAL, xf, v3s(0.0f), v3s(0.0f), v2(0.0f, 0.0f));
    expect_st(&t, v3(1, 1, 0), 0.5f, 0.25f);
    texture_set_mapping(&t, TEXTURE_MAP_CYLINDRICAL, NULL, v3s(0.0f), v3s(0.0f), v2(0.0f, 0.0f));
    expect_st(&t, v3(1, 0, 3), 0.5f, 3.0f);         /* (pi + 0) / 2pi */
    expect_st(&t, v3(0, 2, -2), 0.75f, -2.0f);      /* (pi + pi/2) / 2pi */
    expect_st(&t, v3(-1, -1e-7f, 0), 0.0f, 0.0f);   /* atan2 -> -pi: s = 0 */
    expect_derivs(&t, v3(0.7f, -0.4f, 1.0f), v3(0.01f, 0.02f, -0.05f), 0);
    /* planar: s = 0.1 + p.v1, t = 0.2 + p.v2 */
    texture_set_mapping(&t, TEXTURE_MAP_PLANAR, NULL, v3(1, 0, 0), v3(0, 0.5f, 1), v2(0.1f, 0.2f));
    expect_st(&t, v3(2, 5, 3), 2.1f, 5.7f);
    expect_derivs(&t, v3(2, 5, 3), v3(0.25f, -0.5f, 1.0f), 0);
    Vec2 d0, st = map_at(&t, v3(0, 0, 0), v3(0.25f, -0.5f, 1.0f), &d0);
    assert_true(st.x == 0.1f && st.y == 0.2f && d0.x == 0.25f && d0.y == 0.75f);
    /* a checkerboard (scale 1) through the planar mapping: parity of floor(s) + floor(t) */
    Texture tex[3];
    texture_constant(&tex[0], color_s(0.25f));
    texture_constant(&tex[1], color_s(0.75f));
    texture_checkerboard(&tex[2], tex, 0, 1, 1.0f);
    texture_set_mapping(&tex[2], TEXTURE_MAP_PLANAR, NULL, v3(1, 0, 0), v3(0, 0, 1), v2(0.0f, 0.0f));
    TexCtx c = {.uv = v2(0.9f, 0.9f), .p = v3(0.5f, 7.0f, 0.5f)};
    assert_true(texture_eval_ctx(tex, 2, &c).c[0] == 0.25f); /* (0, 0): even; the uv would be too */
    c.p = v3(1.5f, 7.0f, 0.5f);
    assert_true(texture_eval_ctx(tex, 2, &c).c[0] == 0.75f); /* (1, 0): odd, whatever the uv */
    c.p = v3(1.5f, -3.0f, -0.5f);
    assert_true(texture_eval_ctx(tex, 2, &c).c[0] == 0.25f); /* (1, -1): even */
}

static void test_uv_at_hits(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    /* uvs are computed in scenes with textures only */
    Texture tc;
    texture_constant(&tc, color_s(1.0f));
    int tid;
    assert_int_equal(scene_add_texture(s, &tc, &tid, &err), CST_OK);
    /* a triangle without uvs at z = 0 (added first: before the scene has a uv array) */
    Vec3 t0[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const int tri[3] = {0, 1, 2};
    assert_int_equal(scene_add_mesh(s, t0, 3, tri, 1, mat, NULL, &err), CST_OK);
    /* a triangle with uvs at z = 1 */
    Vec3 t1[3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    Vec2 uv1[3] = {{0.2f, 0.3f}, {0.8f, 0.1f}, {0.4f, 0.9f}};
    SceneMesh sm = {0};
    sm.positions = t1;
    sm.num_vertices = 3;
    sm.uvs = uv1;
    sm.indices = tri;
    sm.num_triangles = 1;
    sm.material = mat;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
    /* a quad at z = 2 (after a mesh with uvs) and a triangle without uvs at z = 3 */
    Vec3 q[4] = {{0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {0, 2, 2}};
    assert_int_equal(scene_add_quad(s, q, mat, NULL, &err), CST_OK);
    Vec3 t3[3] = {{0, 0, 3}, {1, 0, 3}, {0, 1, 3}};
    assert_int_equal(scene_add_mesh(s, t3, 3, tri, 1, mat, NULL, &err), CST_OK);
    /* a sphere at (10, 0, 0) */
    assert_int_equal(scene_add_sphere(s, v3(10, 0, 0), 1.0f, mat, NULL, &err), CST_OK);
    /* an instanced triangle at z = 5 (object space z = 0, translated) */
    int proto, pmat[1] = {mat};
    assert_int_equal(scene_add_instance_proto(s, t0, NULL, 3, tri, pmat, 1, &proto, &err), CST_OK);
    Transform tr = transform_translate(v3(20, 0, 5));
    assert_int_equal(scene_add_instance(s, proto, &tr, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);

    const float bs[3][2] = {{0.25f, 0.5f}, {0.1f, 0.1f}, {0.6f, 0.3f}};
    for (int i = 0; i < 3; i++) {
        float b1 = bs[i][0], b2 = bs[i][1], b0 = 1.0f - b1 - b2;
        /* the default mapping: (b1, b2) */
        Vec3 p = bary(t0[0], t0[1], t0[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, -1), p).uv, (double)b1, (double)b2);
        p = bary(t3[0], t3[1], t3[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, 3.5f), p).uv, (double)b1, (double)b2);
        /* interpolated */
        p = bary(t1[0], t1[1], t1[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, 0.5f), p).uv, (double)(0.2f * b0 + 0.8f * b1 + 0.4f * b2),
                  (double)(0.3f * b0 + 0.1f * b1 + 0.9f * b2));
        /* instances have no uvs: the default */
        p = bary(t0[0], t0[1], t0[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x + 20, p.y, 4), v3(p.x + 20, p.y, 5)).uv, (double)b1, (double)b2);
    }
    /* the quad: (0,0), (1,0), (1,1), (0,1) at its corners, linear across it */
    const float qp[4][2] = {{0.5f, 0.5f}, {1.5f, 0.3f}, {0.2f, 1.7f}, {1.9f, 1.9f}};
    for (int i = 0; i < 4; i++)
        assert_uv(hit_toward(s, v3(qp[i][0], qp[i][1], 2.5f), v3(qp[i][0], qp[i][1], 2)).uv,
                  (double)qp[i][0] / 2.0, (double)qp[i][1] / 2.0);
    /* the sphere: u = phi / 2pi about +y from +z toward +x, v = theta / pi from -y */
    assert_uv(hit_toward(s, v3(13, 0, 0), v3(10, 0, 0)).uv, 0.25, 0.5);   /* +x */
    assert_uv(hit_toward(s, v3(10, 0, -3), v3(10, 0, 0)).uv, 0.5, 0.5);  /* -z */
    assert_uv(hit_toward(s, v3(7, 0, 0), v3(10, 0, 0)).uv, 0.75, 0.5);   /* -x */
    assert_true(hit_toward(s, v3(10, 3, 0.001f), v3(10, 0, 0.001f)).uv.y > 0.999f); /* top: v = 1 */
    Vec3 d = v3_normalize(v3(1, 1, 1)); /* phi = 45 deg, theta = pi - acos(1/sqrt 3) */
    assert_uv(hit_toward(s, v3_add(v3(10, 0, 0), v3_scale(d, 3)), v3(10, 0, 0)).uv, 0.125,
              (3.14159265358979 - acos(1.0 / sqrt(3.0))) / 3.14159265358979);
    scene_destroy(s);
}

/* Points sampled on textured emitters carry the uv of where they are: a quad's position
 * maps linearly to its uv, a sphere point's direction to sphere_uv. */
static void test_emitter_sample_uv(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat, tid;
    Material m = {.type = MATERIAL_DIFFUSE, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Texture tex[3];
    texture_constant(&tex[0], color_rgb(1.0f, 0.5f, 0.25f));
    texture_constant(&tex[1], color_rgb(0.0f, 2.0f, 4.0f));
    for (int i = 0; i < 2; i++) assert_int_equal(scene_add_texture(s, &tex[i], &tid, &err), CST_OK);
    texture_checkerboard(&tex[2], s->textures, 0, 1, 4.0f);
    assert_int_equal(scene_add_texture(s, &tex[2], &tid, &err), CST_OK);
    Emission em = {{{2.0f, 2.0f, 2.0f}}, 1, tid + 1};
    Vec3 q[4] = {{0, 0, 0}, {4, 0, 0}, {4, 0, 4}, {0, 0, 4}}; /* u along x, v along z */
    assert_int_equal(scene_add_quad(s, q, mat, &em, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 10, 0), 1.0f, mat, &em, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    /* the emitters' selection weights use the texture's average: (0.5, 1.25, 2.125) * 2 */
    for (int i = 0; i < s->num_emitters; i++) assert_rgb_near(s->emitters[i].average, 1.0, 2.5, 4.25, 1e-6);
    EmitterGeometry g = scene_emitter_geometry(s);
    int checked = 0;
    for (int i = 0; i < 256; i++) {
        Vec2 u = v2((float)((i * 37) % 256) / 256.0f + 1e-3f, (float)i / 256.0f + 1e-3f);
        for (int e = 0; e < s->num_emitters; e++) {
            Vec3 p, n;
            Vec2 uv;
            emitter_sample_point(&s->emitters[e], &g, u, &p, &n, &uv);
            if ((int)s->emitters[e].prim < s->num_triangles) assert_uv(uv, (double)p.x / 4.0, (double)p.z / 4.0);
            else assert_uv(uv, (double)sphere_uv(v3_sub(p, v3(0, 10, 0))).x, (double)sphere_uv(v3_sub(p, v3(0, 10, 0))).y);
            /* the radiance there is the texture's, scaled */
            Color want = color_scale(texture_eval(s->textures, tid, uv), 2.0f);
            Color got = emitter_radiance(&s->emitters[e], s->textures, n, uv, n);
            assert_rgb_near(got, (double)want.c[0], (double)want.c[1], (double)want.c[2], 0.0);
            checked++;
        }
    }
    assert_int_equal(checked, 3 * 256); /* the quad is two emitters */
    /* light_sample_li returns the radiance at the point it picked */
    for (int i = 0; i < 64; i++) {
        LightLi ls;
        Vec3 x = v3(2, 3, 2);
        if (!light_sample_li(&s->emitter_sampler, &g, x, (float)i / 64.0f,
                             v2((float)((i * 29) % 64) / 64.0f + 0.01f, (float)i / 64.0f + 0.005f), &ls))
            continue;
        Vec2 uv = ls.light == 0 || ls.light == 1 ? v2(ls.p.x / 4.0f, ls.p.z / 4.0f)
                                                  : sphere_uv(v3_normalize(v3_sub(ls.p, v3(0, 10, 0))));
        Color want = color_scale(texture_eval(s->textures, tid, uv), 2.0f);
        assert_rgb_near(ls.li, (double)want.c[0], (double)want.c[1], (double)want.c[2], 1e-6);
    }
    scene_destroy(s);
}

/* ------------------------------------------------------------------ JSON */

#define NAME "t.json"

static const char *json_head =
    "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n";

/* Loads head + body; expects status and, when not OK, "t.json:<line>:<col>:" at the
 * nth occurrence of needle and `what` in the message. */
static CstScene *load_json(const char *body, CstStatus status, const char *needle, int nth, const char *what)
{
    char text[4096];
    snprintf(text, sizeof text, "%s%s", json_head, body);
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus st = cst_scene_load_json_string(text, strlen(text), NAME, &scene, &err);
    if (st != status) fail_msg("status %s, expected %s: %s", cst_status_name(st), cst_status_name(status), err.msg);
    if (st == CST_OK) return scene;
    const char *at = text;
    for (int i = 0; i <= nth; i++) {
        at = strstr(i ? at + 1 : at, needle);
        if (!at) fail_msg("needle %s not found", needle);
    }
    int line = 1, col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') { line++; col = 1; } else { col++; }
    }
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0) fail_msg("message \"%s\" does not start with \"%s\"", err.msg, prefix);
    if (what && !strstr(err.msg, what)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
    return NULL;
}

static void test_json_textures(void **state)
{
    (void)state;
    char png[512], body[3072];
    tpath(png, sizeof png, "j.png");
    float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(png, px, 2, 2, &err), CST_OK);
    /* names may be used before they are listed; colours or names in a checkerboard */
    snprintf(body, sizeof body,
             "\"textures\": {\"board\": {\"type\": \"checkerboard\", \"even\": \"img\", \"odd\": [0.1, 0.2, 0.3], \"scale\": 4},\n"
             " \"img\": {\"type\": \"image\", \"file\": \"%s\", \"wrap\": \"clamp\"},\n"
             " \"rough\": {\"type\": \"constant\", \"value\": [0.5, 0.5, 0.5]},\n"
             " \"hot\": {\"type\": \"constant\", \"value\": [3, 2, 1]}},\n"
             "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"board\"},\n"
             " \"b\": {\"type\": \"conductor\", \"metal\": \"gold\", \"roughness\": \"rough\"}},\n"
             "\"shapes\": [{\"type\": \"mesh\", \"material\": \"a\", \"vertices\": [[0,0,0],[1,0,0],[0,1,0]],\n"
             "  \"indices\": [[0,1,2]], \"uvs\": [[0,0],[0.5,0],[0,0.5]]},\n"
             " {\"type\": \"sphere\", \"material\": \"b\", \"center\": [0,0,-3], \"radius\": 1,\n"
             "  \"emission\": {\"radiance\": \"hot\", \"scale\": 2}}]}",
             png);
    CstScene *s = load_json(body, CST_OK, NULL, 0, NULL);
    assert_int_equal(s->num_textures, 5); /* img, the odd colour, board, rough, hot */
    const Material *ma = &s->materials[0], *mb = &s->materials[1];
    assert_true(ma->albedo_texture > 0 && s->textures[ma->albedo_texture - 1].type == TEXTURE_CHECKERBOARD);
    assert_true(mb->roughness_texture > 0);
    assert_int_equal(s->num_emitters, 1);
    Color le = emitter_radiance(&s->emitters[0], s->textures, v3(0, 0, 1), v2(0.3f, 0.3f), v3(0, 0, 1));
    assert_rgb_near(le, 6.0, 4.0, 2.0, 0.0);
    assert_true(s->tri_has_uv && s->tri_has_uv[0]);
    /* a hit on the mesh: uv from its uvs, albedo from the board (odd square at uv (0.3, 0.05)) */
    SurfaceHit sh = hit_toward(s, v3(0.6f, 0.1f, 1), v3(0.6f, 0.1f, 0));
    assert_uv(sh.uv, 0.3, 0.05);
    Bsdf b;
    scene_bsdf(s, &sh, NULL, &b);
    assert_rgb_near(bsdf_albedo(&b), 0.1, 0.2, 0.3, 1e-7);
    cst_scene_destroy(s);

    /* errors, each at the value that causes it */
    load_json("\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"nope\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"nope\"", 0, "texture \"nope\" is not defined (no textures are)");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [1, 1, 1]}},\n"
              "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"tt\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"tt\"", 0, "expected one of: t");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"/nonexistent/dir/x.png\"}},\n\"shapes\": []}",
              CST_ERR_IO, "\"/nonexistent", 0, "cannot open");
    load_json("\"textures\": {\"a\": {\"type\": \"checkerboard\", \"even\": \"b\", \"odd\": [0,0,0]},\n"
              " \"b\": {\"type\": \"checkerboard\", \"even\": [0,0,0], \"odd\": \"a\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"a\"", 1, "contains itself");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [0.5, 1.5, 0]}},\n"
              "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"t\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"t\"}", 0, "values up to 1.5");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [0.5, 0.5, 0.5]}},\n"
              "\"materials\": {\"a\": {\"type\": \"plastic\", \"roughness\": \"t\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"t\"}", 0, "plastic's roughness cannot be a texture");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"x.png\", \"wrap\": \"mirror\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"mirror\"", 0, "expected one of: repeat, clamp");
    load_json("\"textures\": {\"t\": {\"type\": \"checkerboard\", \"even\": [0,0,0], \"odd\": [1,1,1], \"scale\": 0}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "0}}", 0, "scale 0 is not positive");
    load_json("\"textures\": {\"t\": {\"type\": \"marble\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"marble\"", 0, "unknown texture type");
    load_json("\"shapes\": [{\"type\": \"mesh\", \"material\": \"m\", \"vertices\": [[0,0,0],[1,0,0],[0,1,0]],\n"
              " \"indices\": [[0,1,2]], \"uvs\": [[0,0],[1,0]]}],\n\"materials\": {\"m\": {\"type\": \"diffuse\"}}}",
              CST_ERR_INVALID_ARG, "[[0,0],[1,0]]", 0, "one [u, v] per vertex");
}

/* The example scene loads (its image texture found next to it) with its textures in use. */
/* An image's "filter" and "max_anisotropy" in JSON: pbrt-v4's filters with a MIP map (and
 * the footprint machinery on), the default none without one; errors at their values. */
static void test_json_texture_filter(void **state)
{
    (void)state;
    char png[512], body[3072];
    tpath(png, sizeof png, "jf.png");
    float px[48];
    for (int i = 0; i < 48; i++) px[i] = (float)(i % 7) / 7.0f;
    CstError err;
    assert_int_equal(image_write(png, px, 4, 4, &err), CST_OK);
    snprintf(body, sizeof body,
             "\"textures\": {\"e\": {\"type\": \"image\", \"file\": \"%s\", \"filter\": \"ewa\", \"max_anisotropy\": 4},\n"
             " \"t\": {\"type\": \"image\", \"file\": \"%s\", \"filter\": \"trilinear\"},\n"
             " \"p\": {\"type\": \"image\", \"file\": \"%s\", \"filter\": \"point\"},\n"
             " \"n\": {\"type\": \"image\", \"file\": \"%s\"}},\n"
             "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"e\"}},\n"
             "\"shapes\": [{\"type\": \"sphere\", \"material\": \"a\", \"center\": [0,0,-3], \"radius\": 1}]}",
             png, png, png, png);
    CstScene *s = load_json(body, CST_OK, NULL, 0, NULL);
    assert_int_equal(s->num_textures, 4);
    const TextureFilter want[4] = {TEXTURE_FILTER_EWA, TEXTURE_FILTER_TRILINEAR, TEXTURE_FILTER_POINT, TEXTURE_FILTER_NONE};
    for (int i = 0; i < 4; i++) {
        /* the four share one file but are read separately, in the order listed */
        const Texture *t = &s->textures[i];
        assert_int_equal(t->type, TEXTURE_IMAGE);
        assert_int_equal(t->image.filter, want[i]);
        assert_int_equal(t->image.im->num_levels, want[i] == TEXTURE_FILTER_NONE ? 1 : 3); /* 4x4, 2x2, 1x1 */
    }
    assert_true(s->textures[0].image.max_aniso == 4.0f);
    assert_true(s->textures[1].image.max_aniso == 8.0f); /* pbrt-v4's default */
    assert_true(s->footprint.enabled); /* hits get screen-space footprints */
    cst_scene_destroy(s);
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"x.png\", \"filter\": \"gaussian\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"gaussian\"", 0, "expected one of: none, point, bilinear, trilinear, ewa");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"x.png\", \"max_anisotropy\": 4}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "4}}", 0, "max_anisotropy is for the \"ewa\" filter only");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"x.png\", \"filter\": \"ewa\", "
              "\"max_anisotropy\": 0.5}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "0.5}}", 0, "expected a number >= 1");
}

static void test_example_scene(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/textured.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    int images = 0, textured = 0;
    for (int i = 0; i < s->num_textures; i++)
        if (s->textures[i].type == TEXTURE_IMAGE) {
            images++;
            assert_int_equal(s->textures[i].image.width, 256);
            assert_int_equal(s->textures[i].image.height, 256);
        }
    for (int i = 0; i < s->num_materials; i++)
        textured += s->materials[i].albedo_texture > 0 || s->materials[i].roughness_texture > 0;
    assert_int_equal(images, 1);
    assert_true(textured >= 3);
    int lit = 0;
    for (int i = 0; i < s->num_emitters; i++) lit += s->emitters[i].texture > 0;
    assert_true(lit > 0);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bilinear_exact),
        cmocka_unit_test(test_image_rejects_bad_texels),
        cmocka_unit_test(test_srgb_decode),
        cmocka_unit_test(test_float_and_jpeg),
        cmocka_unit_test(test_compact_storage),
        cmocka_unit_test(test_mipmap_levels),
        cmocka_unit_test(test_mipmap_filters),
        cmocka_unit_test(test_footprint),
        cmocka_unit_test(test_noise),
        cmocka_unit_test(test_procedural),
        cmocka_unit_test(test_bump_and_normal_map),
        cmocka_unit_test(test_checkerboard),
        cmocka_unit_test(test_uv_transform),
        cmocka_unit_test(test_texture_mappings),
        cmocka_unit_test(test_json_texture_filter),
        cmocka_unit_test(test_uv_at_hits),
        cmocka_unit_test(test_emitter_sample_uv),
        cmocka_unit_test(test_json_textures),
        cmocka_unit_test(test_example_scene),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
