/* pbrt-v4's float image textures (CstTextureDesc.pbrt_float, textures/mipmap.c's *_float
 * lookups): small PNGs written here (RGB, RGBA with partial alpha, opaque RGBA, grey, grey
 * with alpha) looked up per filter against the closed form of pbrt-v4's rule
 * (MIPMap::Bilerp<Float>: grey value, mean of R, G, B, or alpha; MIPMap::Texel<Float>: the
 * first channel), the alpha of an RGBA PNG decoded by the encoding, RGB lookups of the same
 * files unchanged, and a pbrt file's float "imagemap" used as an alpha cut-out. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include <stb_image_write.h>

#include "caustic/caustic.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "textures/mipmap.h"
#include "textures/texture.h"

enum { W = 4, H = 2, N = W * H };

/* Red is 200 in every texel of the colour images, so a lookup reading the first channel
 * gives 200/255 wherever it looks, far from the mean of R, G, B or the alpha. */
static unsigned char g_rgba[N * 4], g_grey_alpha[N * 2], g_grey[N], g_opaque[N * 4];

static void make_pixels(void)
{
    for (int i = 0; i < N; i++) {
        g_rgba[4 * i + 0] = 200;
        g_rgba[4 * i + 1] = (unsigned char)(17 + 29 * i);
        g_rgba[4 * i + 2] = (unsigned char)(240 - 23 * i);
        g_rgba[4 * i + 3] = (unsigned char)(i == 5 ? 255 : 9 + 31 * i); /* partial, one 1 */
        memcpy(&g_opaque[4 * i], &g_rgba[4 * i], 3);
        g_opaque[4 * i + 3] = 255;
        g_grey[i] = (unsigned char)(5 + 33 * i);
        g_grey_alpha[2 * i] = g_grey[i];
        g_grey_alpha[2 * i + 1] = (unsigned char)(100 + i);
    }
}

static int group_setup(void **state)
{
    (void)state;
    make_pixels();
    if (scratch_dir_make("/tmp/cst_texfloat.XXXXXX") != 0) return -1;
    char p[512];
    int ok = 1;
    tpath(p, sizeof p, "rgba.png"), ok &= stbi_write_png(p, W, H, 4, g_rgba, W * 4) != 0;
    tpath(p, sizeof p, "opaque.png"), ok &= stbi_write_png(p, W, H, 4, g_opaque, W * 4) != 0;
    unsigned char rgb[N * 3];
    for (int i = 0; i < N; i++) memcpy(&rgb[3 * i], &g_rgba[4 * i], 3);
    tpath(p, sizeof p, "rgb.png"), ok &= stbi_write_png(p, W, H, 3, rgb, W * 3) != 0;
    tpath(p, sizeof p, "grey.png"), ok &= stbi_write_png(p, W, H, 1, g_grey, W) != 0;
    tpath(p, sizeof p, "greya.png"), ok &= stbi_write_png(p, W, H, 2, g_grey_alpha, W * 2) != 0;
    return ok ? 0 : -1;
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static void ok_st(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s", e->msg);
}

typedef enum Kind { K_RGB, K_RGBA, K_OPAQUE, K_GREY, K_GREYA } Kind;
static const char *const k_file[] = {"rgb.png", "rgba.png", "opaque.png", "grey.png", "greya.png"};
static const int k_channels[] = {3, 4, 3, 1, 1};

/* Linear value of code c: code / 255 (linear encoding) or the sRGB curve. */
static double dec(int c, int srgb) { return srgb ? (double)image_srgb_to_linear(c / 255.0) : c / 255.0; }

/* pbrt-v4's Bilerp<Float> at texel i's centre: the rule's closed form. */
static double rule_value(Kind k, int i, int srgb)
{
    switch (k) {
    case K_RGB: case K_OPAQUE:
        return (dec(g_rgba[4 * i], srgb) + dec(g_rgba[4 * i + 1], srgb) + dec(g_rgba[4 * i + 2], srgb)) / 3.0;
    case K_RGBA: return dec(g_rgba[4 * i + 3], srgb); /* alpha, through the encoding as pbrt-v4 */
    default: return dec(g_grey[i], srgb);
    }
}

/* pbrt-v4's Texel<Float>: channel 0. */
static double first_channel(Kind k, int i, int srgb)
{
    return dec(k == K_GREY || k == K_GREYA ? g_grey[i] : g_rgba[4 * i], srgb);
}

/* A scene holding one texture of file k as a pbrt float texture with `filter`. */
static CstScene *texture_scene(Kind k, CstTextureFilter filter, int srgb, int pbrt_float, int *id)
{
    CstError e;
    CstScene *s = NULL;
    ok_st(cst_scene_create(&s, &e), &e);
    char p[512];
    tpath(p, sizeof p, k_file[k]);
    CstTextureDesc d = {0};
    d.type = CST_TEXTURE_IMAGE;
    d.path = p;
    d.encoding = srgb ? CST_TEXTURE_ENCODING_SRGB : CST_TEXTURE_ENCODING_LINEAR;
    d.filter = filter;
    d.pbrt_float = pbrt_float;
    ok_st(cst_scene_add_texture(s, &d, id, &e), &e);
    return s;
}

/* The value at texel (x, y)'s centre plus (ox, oy) texels, with footprint derivatives
 * du (= dudx = dvdy, in uv units; 0: none). */
static Color lookup(const Scene *s, int id, double x, double y, float du)
{
    TexCtx c = {.uv = v2((float)((x + 0.5) / W), (float)(1.0 - (y + 0.5) / H)), .dudx = du, .dvdy = du};
    return texture_eval_ctx(s->textures, id - 1, &c);
}

static void expect_grey(Color c, double want, double tol, const char *what, Kind k, int i)
{
    for (int ch = 0; ch < 3; ch++)
        if (!(fabs((double)c.c[ch] - want) <= tol))
            fail_msg("%s, %s, texel %d: channel %d is %.9g, expected %.9g", what, k_file[k], i, ch, (double)c.c[ch],
                     want);
}

/* Every kind of file under every filter, linear and sRGB: interpolating filters follow
 * Bilerp<Float>, single-texel reads Texel<Float>. */
static void test_channel_rule_per_filter(void **state)
{
    (void)state;
    for (int srgb = 0; srgb < 2; srgb++)
        for (int k = K_RGB; k <= K_GREYA; k++)
            for (int f = CST_TEXTURE_FILTER_NONE; f <= CST_TEXTURE_FILTER_EWA; f++) {
                int id = 0;
                CstScene *s = texture_scene((Kind)k, (CstTextureFilter)f, srgb, 1, &id);
                const Texture *t = &s->textures[id - 1];
                assert_int_equal(t->image.im->channels, k_channels[k]);
                assert_true(t->image.scalar);
                char what[64];
                snprintf(what, sizeof what, "filter %d, %s", f, srgb ? "sRGB" : "linear");
                /* No footprint: the finest level. Point reads one texel (the first channel);
                 * the others interpolate, which at a texel's centre is its rule value and
                 * halfway to the next texel the mean of the two. */
                for (int i = 0; i < N; i++) {
                    int x = i % W, y = i / W;
                    double want = f == CST_TEXTURE_FILTER_POINT ? first_channel((Kind)k, i, srgb)
                                                                : rule_value((Kind)k, i, srgb);
                    expect_grey(lookup(s, id, x, y, 0.0f), want, 1e-6, what, (Kind)k, i);
                    if (x + 1 < W && f != CST_TEXTURE_FILTER_POINT) {
                        double mid = 0.5 * (rule_value((Kind)k, i, srgb) + rule_value((Kind)k, i + 1, srgb));
                        TexCtx c = {.uv = v2((float)(x + 1.0) / W, (float)(1.0 - (y + 0.5) / H))};
                        expect_grey(texture_eval_ctx(s->textures, id - 1, &c), mid, 1e-6, what, (Kind)k, i);
                    }
                }
                /* A footprint wider than the image: the 1 x 1 level read as one texel
                 * (Texel<Float>) by every filter but EWA; EWA over a small footprint weighs
                 * texels read one by one. In the colour images red is 200 everywhere. */
                if (k != K_GREY && k != K_GREYA && f != CST_TEXTURE_FILTER_NONE) {
                    double red = dec(200, srgb);
                    Color wide = lookup(s, id, 1, 0, 4.0f);
                    if (f != CST_TEXTURE_FILTER_EWA) expect_grey(wide, red, 1e-6, "wide footprint", (Kind)k, 1);
                    Color ewa = lookup(s, id, 1.3, 0.6, 0.3f);
                    if (f == CST_TEXTURE_FILTER_EWA) expect_grey(ewa, red, 1e-6, "EWA footprint", (Kind)k, 1);
                }
                cst_scene_destroy(s);
            }
}

/* The texture's average (light selection, mix estimates) is the rule's mean over texels;
 * the RGB lookup of an RGBA file is the RGB file's, alpha unread; opaque RGBA is stored as
 * RGB. */
static void test_average_and_rgb_lookups(void **state)
{
    (void)state;
    CstError e;
    for (int k = K_RGB; k <= K_GREYA; k++) {
        int id = 0;
        CstScene *s = texture_scene((Kind)k, CST_TEXTURE_FILTER_BILINEAR, 0, 1, &id);
        CstTextureInfo info;
        ok_st(cst_scene_texture_info(s, id, &info, &e), &e);
        assert_int_equal(info.desc.pbrt_float, 1);
        double mean = 0.0;
        for (int i = 0; i < N; i++) mean += rule_value((Kind)k, i, 0) / N;
        for (int ch = 0; ch < 3; ch++)
            if (fabs((double)info.average[ch] - mean) > 1e-6)
                fail_msg("%s: average %.9g, expected %.9g", k_file[k], (double)info.average[ch], mean);
        cst_scene_destroy(s);
    }
    int a = 0, b = 0;
    CstScene *sa = texture_scene(K_RGBA, CST_TEXTURE_FILTER_NONE, 1, 0, &a);
    CstScene *sb = texture_scene(K_RGB, CST_TEXTURE_FILTER_NONE, 1, 0, &b);
    for (int i = 0; i < N; i++) {
        Color ca = lookup(sa, a, i % W + 0.3, i / W + 0.2, 0.0f), cb = lookup(sb, b, i % W + 0.3, i / W + 0.2, 0.0f);
        for (int ch = 0; ch < 3; ch++) assert_true(ca.c[ch] == cb.c[ch]);
    }
    assert_int_equal(texture_image_bytes(&sa->textures[a - 1]), N * 4);
    cst_scene_destroy(sa);
    cst_scene_destroy(sb);
    CstScene *so = texture_scene(K_OPAQUE, CST_TEXTURE_FILTER_NONE, 1, 0, &a);
    assert_int_equal(texture_image_bytes(&so->textures[a - 1]), N * 3);
    cst_scene_destroy(so);
}

/* A pbrt float "imagemap" of the RGBA file as a shape's alpha: the scene's cut-out reads
 * the alpha channel (sRGB-decoded, pbrt-v4's default encoding for PNG files); the RGB
 * file's reads the mean of R, G, B. */
static void test_pbrt_alpha_texture(void **state)
{
    (void)state;
    for (int k = 0; k < 2; k++) {
        Kind kind = k ? K_RGB : K_RGBA;
        char text[1024], name[512];
        snprintf(text, sizeof text,
                 "LookAt 0 0 5  0 0 0  0 1 0\nCamera \"perspective\"\nWorldBegin\n"
                 "Texture \"a\" \"float\" \"imagemap\" \"string filename\" \"%s\"\n"
                 "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  1 1 0  0 1 0] \"integer indices\" [0 1 2 0 2 3]\n"
                 "  \"point2 uv\" [0 0  1 0  1 1  0 1] \"texture alpha\" \"a\"\n",
                 k_file[kind]);
        tpath(name, sizeof name, "t.pbrt");
        CstScene *s = NULL;
        CstError e;
        ok_st(cst_scene_load_pbrt_string(text, strlen(text), name, NULL, &s, &e), &e);
        assert_int_equal(s->num_alphas, 1);
        int id = s->alphas[0].texture;
        assert_true(id > 0);
        for (int i = 0; i < N; i++)
            expect_grey(lookup(s, id, i % W, i / W, 0.0f), rule_value(kind, i, 1), 1e-6, "pbrt alpha", kind, i);
        cst_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_channel_rule_per_filter),
        cmocka_unit_test(test_average_and_rgb_lookups),
        cmocka_unit_test(test_pbrt_alpha_texture),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
