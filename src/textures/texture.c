/* Texture construction (constants, checkerboards, images from memory or files) and
 * evaluation: bilinear filtering with repeat or clamp wrapping. */
#include "textures/texture.h"

#include <errno.h>
#include <limits.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "io/image_io.h"
#include "io/image_precheck.h"
#include "io/image_stb.h"

static Color rgb_max3(Color a, Color b) { return color_rgb(maxf(a.c[0], b.c[0]), maxf(a.c[1], b.c[1]), maxf(a.c[2], b.c[2])); }

void texture_constant(Texture *t, Color value)
{
    memset(t, 0, sizeof *t);
    t->type = TEXTURE_CONSTANT;
    t->uv_scale = v2(1.0f, 1.0f);
    t->value = value;
    t->average = t->max = value;
}

void texture_checkerboard(Texture *t, const Texture *textures, int even, int odd, float scale)
{
    memset(t, 0, sizeof *t);
    t->type = TEXTURE_CHECKERBOARD;
    t->uv_scale = v2(1.0f, 1.0f);
    t->checker.even = even;
    t->checker.odd = odd;
    t->checker.scale = scale;
    /* The two kinds of square cover equal areas of the uv plane. */
    t->average = color_scale(color_add(textures[even].average, textures[odd].average), 0.5f);
    t->max = rgb_max3(textures[even].max, textures[odd].max);
}

CstStatus texture_image(Texture *t, float *rgb_data, int width, int height, TextureWrap wrap, CstError *err)
{
    memset(t, 0, sizeof *t);
    if (!rgb_data || width <= 0 || height <= 0) {
        free(rgb_data);
        return cst_fail(err, CST_ERR_INVALID_ARG, "texture image of %d x %d pixels%s", width, height,
                        rgb_data ? "" : " without pixels");
    }
    size_t n = (size_t)width * (size_t)height;
    /* The rule of every image input (io/image_io.h); the message reads the pixel, so the
     * image is freed after it is written. */
    CstStatus bad = image_check_radiance(rgb_data, width, height, "texture image", err);
    if (bad != CST_OK) {
        free(rgb_data);
        return bad;
    }
    double sum[3] = {0.0, 0.0, 0.0};
    Color mx = color_s(0.0f);
    for (size_t i = 0; i < n; i++) {
        const float *p = &rgb_data[3 * i];
        for (int c = 0; c < 3; c++) sum[c] += (double)p[c];
        mx = rgb_max3(mx, color_rgb(p[0], p[1], p[2]));
    }
    t->type = TEXTURE_IMAGE;
    t->uv_scale = v2(1.0f, 1.0f);
    t->image.rgb = rgb_data;
    t->image.width = width;
    t->image.height = height;
    t->image.wrap = wrap;
    t->average = color_rgb((float)(sum[0] / (double)n), (float)(sum[1] / (double)n), (float)(sum[2] / (double)n));
    t->max = mx;
    return CST_OK;
}

/* An sRGB-encoded (or linear) integer image of 3 channels, maxval 255 or 65535, as floats. */
static float *texture_decode_ints(const void *px, bool sixteen, size_t n, bool linear)
{
    float *out = malloc(n * 3 * sizeof *out);
    if (!out) return NULL;
    if (!sixteen) {
        float lut[256];
        for (int i = 0; i < 256; i++) lut[i] = linear ? (float)i / 255.0f : image_srgb_to_linear(i / 255.0);
        const unsigned char *b = px;
        for (size_t i = 0; i < 3 * n; i++) out[i] = lut[b[i]];
    } else {
        const uint16_t *w = px;
        for (size_t i = 0; i < 3 * n; i++)
            out[i] = linear ? (float)w[i] / 65535.0f : image_srgb_to_linear(w[i] / 65535.0);
    }
    return out;
}

/* PNG, JPEG, BMP, TGA or Radiance HDR bytes through stb_image (io/image_stb.h), after the
 * checks stb lacks (io/image_precheck.h). */
static CstStatus texture_decode_stb(const char *path, const unsigned char *data, size_t size, bool linear,
                                    float **out, int *width, int *height, CstError *err)
{
    int dw = 0, dh = 0;
    CstStatus st = image_precheck_stb(path, data, size, &dw, &dh, err);
    if (st != CST_OK) return st;
    int len = (int)size; /* image_precheck_stb: size <= INT_MAX */
    int w = 0, h = 0;
    float *px = NULL;
    bool oom = false;
    if (image_stb_is_hdr(data, len)) {
        /* Radiance HDR: linear floats, taken as they are (stbi_loadf would gamma-decode
         * an 8-bit image with its own 2.2 curve, so it is used for HDR files only). stb's
         * buffer is malloc'd (io/image_stb.c), so it is kept. */
        px = image_stb_load(data, len, 32, &w, &h);
    } else {
        bool sixteen = image_stb_is_16_bit(data, len);
        void *ints = image_stb_load(data, len, sixteen ? 16 : 8, &w, &h);
        if (ints) {
            if (!(px = texture_decode_ints(ints, sixteen, (size_t)w * (size_t)h, linear))) oom = true;
            free(ints);
        }
    }
    if (oom) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d texture", path, w, h);
    if (!px)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: cannot decode the image (%s); expected a PNG, JPEG, BMP, TGA, HDR, EXR or PFM file",
                        path, image_stb_failure_reason());
    if (w != dw || h != dh) { /* the header read twice by stb: cannot differ */
        free(px);
        return cst_fail(err, CST_ERR_INTERNAL, "%s: decoded %d x %d pixels, the header declares %d x %d", path,
                        w, h, dw, dh);
    }
    *out = px;
    *width = w;
    *height = h;
    return CST_OK;
}

CstStatus texture_image_load(Texture *t, const char *path, bool linear, TextureWrap wrap, CstError *err)
{
    memset(t, 0, sizeof *t);
    char *bytes = NULL;
    size_t size = 0;
    CstStatus st = file_read_all(path, &bytes, &size, err); /* regular files only */
    if (st != CST_OK) return st;
    const unsigned char *magic = (const unsigned char *)bytes;
    bool exr = size >= 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
    bool pfm = size >= 2 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f');
    float *px = NULL;
    int w = 0, h = 0;
    if (exr || pfm) {
        /* Float formats through the film's readers (OpenEXR's C API, our PFM parser). */
        free(bytes);
        st = image_read_radiance(path, &px, &w, &h, err);
        if (st != CST_OK) return st;
        return texture_image(t, px, w, h, wrap, err);
    }
    st = texture_decode_stb(path, magic, size, linear, &px, &w, &h, err);
    free(bytes);
    if (st != CST_OK) return st;
    st = image_check_radiance(px, w, h, path, err); /* HDR files: NaN, Inf, < 0 */
    if (st != CST_OK) {
        free(px);
        return st;
    }
    st = texture_image(t, px, w, h, wrap, err);
    if (st != CST_OK) {
        char msg[sizeof err->msg];
        memcpy(msg, err->msg, sizeof msg);
        msg[sizeof msg - 1] = '\0';
        return cst_fail(err, st, "%s: %s", path, msg);
    }
    return CST_OK;
}

void texture_free(Texture *t)
{
    if (t && t->type == TEXTURE_IMAGE) free(t->image.rgb);
}

void texture_set_uv_transform(Texture *t, Vec2 scale, Vec2 offset)
{
    t->uv_scale = scale;
    t->uv_offset = offset;
}

/* A texel index along an axis of n texels. */
static inline int texture_wrap(int i, int n, TextureWrap wrap)
{
    if (wrap == TEXTURE_WRAP_CLAMP) return i < 0 ? 0 : i >= n ? n - 1 : i;
    return i < 0 ? i + n : i >= n ? i - n : i; /* i is within one period (see below) */
}

/* Bilinear interpolation between the four texel centres around uv. */
static Color texture_image_eval(const TextureImage *im, Vec2 uv)
{
    float u = uv.x, v = uv.y;
    if (!isfinite(u)) u = 0.0f;
    if (!isfinite(v)) v = 0.0f;
    /* Reduce to one period first (repeat) or to the unit square (clamp), so the texel
     * coordinates below are small and their conversion to int cannot overflow. */
    if (im->wrap == TEXTURE_WRAP_REPEAT) {
        u -= floorf(u);
        v -= floorf(v);
    } else {
        u = clampf(u, 0.0f, 1.0f);
        v = clampf(v, 0.0f, 1.0f);
    }
    float x = u * (float)im->width - 0.5f, y = (1.0f - v) * (float)im->height - 0.5f;
    float fx0 = floorf(x), fy0 = floorf(y);
    float dx = x - fx0, dy = y - fy0;
    int x0 = (int)fx0, y0 = (int)fy0;
    int xa = texture_wrap(x0, im->width, im->wrap), xb = texture_wrap(x0 + 1, im->width, im->wrap);
    int ya = texture_wrap(y0, im->height, im->wrap), yb = texture_wrap(y0 + 1, im->height, im->wrap);
    const float *p00 = &im->rgb[3 * ((size_t)ya * (size_t)im->width + (size_t)xa)];
    const float *p10 = &im->rgb[3 * ((size_t)ya * (size_t)im->width + (size_t)xb)];
    const float *p01 = &im->rgb[3 * ((size_t)yb * (size_t)im->width + (size_t)xa)];
    const float *p11 = &im->rgb[3 * ((size_t)yb * (size_t)im->width + (size_t)xb)];
    float w00 = (1.0f - dx) * (1.0f - dy), w10 = dx * (1.0f - dy), w01 = (1.0f - dx) * dy, w11 = dx * dy;
    return color_rgb(w00 * p00[0] + w10 * p10[0] + w01 * p01[0] + w11 * p11[0],
               w00 * p00[1] + w10 * p10[1] + w01 * p01[1] + w11 * p11[1],
               w00 * p00[2] + w10 * p10[2] + w01 * p01[2] + w11 * p11[2]);
}

Color texture_eval(const Texture *textures, int id, Vec2 uv)
{
    /* Checkerboards only select another texture, so nesting is a loop; children have
     * lower indices, so it ends. */
    for (;;) {
        const Texture *t = &textures[id];
        /* Exact for the identity (x * 1 + 0 == x), so untransformed textures are unchanged. */
        Vec2 st = v2(uv.x * t->uv_scale.x + t->uv_offset.x, uv.y * t->uv_scale.y + t->uv_offset.y);
        switch (t->type) {
        case TEXTURE_CONSTANT: return t->value;
        case TEXTURE_IMAGE: return texture_image_eval(&t->image, st);
        case TEXTURE_CHECKERBOARD: {
            float su = floorf(st.x * t->checker.scale), sv = floorf(st.y * t->checker.scale);
            /* fmodf is exact; beyond 2^24 every float is even, and NaN counts as even. */
            float parity = fmodf(su + sv, 2.0f);
            id = parity == 1.0f || parity == -1.0f ? t->checker.odd : t->checker.even;
            break;
        }
        }
    }
}
