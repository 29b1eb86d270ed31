/* Texture construction (constants, checkerboards, images from memory or files, kept in their
 * files' compact formats and shared between derived textures) and evaluation (lookups in
 * textures/mipmap.c, then the value maps). */
#include "textures/texture.h"

#include <errno.h>
#include <limits.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "io/exr.h"
#include "io/image_io.h"
#include "io/image_precheck.h"
#include "io/image_stb.h"
#include "io/jpeg.h"
#include "math/half.h"
#include "textures/mipmap.h"
#include "textures/noise.h"

static Color rgb_max3(Color a, Color b) { return color_rgb(maxf(a.c[0], b.c[0]), maxf(a.c[1], b.c[1]), maxf(a.c[2], b.c[2])); }

void texture_constant(Texture *t, Color value)
{
    memset(t, 0, sizeof *t);
    t->type = TEXTURE_CONSTANT;
    t->depth = 1;
    t->uv_scale = v2(1.0f, 1.0f);
    t->value = value;
    t->average = t->max = value;
}

void texture_checkerboard(Texture *t, const Texture *textures, int even, int odd, float scale)
{
    memset(t, 0, sizeof *t);
    t->type = TEXTURE_CHECKERBOARD;
    t->depth = 1 + (textures[even].depth > textures[odd].depth ? textures[even].depth : textures[odd].depth);
    t->uv_scale = v2(1.0f, 1.0f);
    t->checker.even = even;
    t->checker.odd = odd;
    t->checker.scale = scale;
    /* The two kinds of square cover equal areas of the uv plane. */
    t->average = color_scale(color_add(textures[even].average, textures[odd].average), 0.5f);
    t->max = rgb_max3(textures[even].max, textures[odd].max);
}

/* A new TexImage of one level holding texels (taken over), or NULL on OOM (texels freed). */
static TexImage *teximage_new(void *texels, int width, int height, TexelFormat format, int channels,
                              TexelEncoding enc, float gamma)
{
    TexImage *im = calloc(1, sizeof *im);
    if (!im) {
        free(texels);
        return NULL;
    }
    im->refs = 1;
    im->format = format;
    im->channels = channels;
    im->encoding = enc;
    im->gamma = gamma;
    /* The historical decoders' expressions, so 8-bit images decode to the same floats. */
    for (int i = 0; i < 256; i++)
        im->lut[i] = enc == TEXEL_LINEAR ? (float)i / 255.0f
                   : enc == TEXEL_SRGB  ? image_srgb_to_linear(i / 255.0)
                                        : powf((float)i / 255.0f, gamma);
    im->num_levels = 1;
    im->level[0].width = width;
    im->level[0].height = height;
    im->level[0].texels = texels;
    return im;
}

static Color texture_apply_ops(const Texture *t, Color v);

/* average and max of an image texture: its level-0 texels through its value maps (double
 * sums, as before compact storage, so unmapped images keep their exact averages). */
static void texture_image_stats(Texture *t)
{
    const TexImage *im = t->image.im;
    size_t n = (size_t)t->image.width * (size_t)t->image.height;
    double sum[3] = {0.0, 0.0, 0.0};
    Color mx = color_s(0.0f);
    for (size_t i = 0; i < n; i++) {
        int x = (int)(i % (size_t)t->image.width), y = (int)(i / (size_t)t->image.width);
        Color c = t->image.scalar ? color_s(mipmap_centre_float(im, x, y)) : mipmap_texel(im, 0, x, y, TEXTURE_WRAP_CLAMP);
        if (t->num_ops) c = texture_apply_ops(t, c);
        for (int k = 0; k < 3; k++) sum[k] += (double)c.c[k];
        mx = rgb_max3(mx, c);
    }
    t->average = color_rgb((float)(sum[0] / (double)n), (float)(sum[1] / (double)n), (float)(sum[2] / (double)n));
    t->max = mx;
}

/* An image texture over im (its one reference moves to t). */
static void texture_over(Texture *t, TexImage *im, TextureWrap wrap)
{
    memset(t, 0, sizeof *t);
    t->type = TEXTURE_IMAGE;
    t->depth = 1;
    t->uv_scale = v2(1.0f, 1.0f);
    t->image.im = im;
    t->image.width = im->level[0].width;
    t->image.height = im->level[0].height;
    t->image.wrap = wrap;
    t->image.filter = TEXTURE_FILTER_NONE;
    t->image.max_aniso = 8.0f;
    texture_image_stats(t);
}

CstStatus texture_image(Texture *t, float *rgb_data, int width, int height, TextureWrap wrap, CstError *err)
{
    memset(t, 0, sizeof *t);
    if (!rgb_data || width <= 0 || height <= 0) {
        free(rgb_data);
        return cst_fail(err, CST_ERR_INVALID_ARG, "texture image of %d x %d pixels%s", width, height,
                        rgb_data ? "" : " without pixels");
    }
    /* The rule of every image input (io/image_io.h); the message reads the pixel, so the
     * image is freed after it is written. */
    CstStatus bad = image_check_radiance(rgb_data, width, height, "texture image", err);
    if (bad != CST_OK) {
        free(rgb_data);
        return bad;
    }
    TexImage *im = teximage_new(rgb_data, width, height, TEXEL_F32, 3, TEXEL_LINEAR, 1.0f);
    if (!im) return cst_fail(err, CST_ERR_OOM, "out of memory for a %d x %d texture", width, height);
    texture_over(t, im, wrap);
    return CST_OK;
}

/* A PNG whose header declares colour type 6, RGB with alpha (PNG spec. sec. 11.2.2, IHDR:
 * the colour type is byte 25 of the file). */
static bool png_is_rgba(const unsigned char *data, size_t size)
{
    return image_precheck_format(data, size) == IMAGE_STB_PNG && size > 25 && memcmp(data + 12, "IHDR", 4) == 0 &&
           data[25] == 6;
}

/* Whether every alpha of n RGBA texels (bytes, or 16-bit codes) is the largest code, which
 * every encoding decodes to exactly 1. If so, the texels are packed to RGB in place. */
static bool alpha_all_one(void *px, size_t n, bool sixteen)
{
    for (size_t i = 0; i < n; i++)
        if (sixteen ? ((const uint16_t *)px)[4 * i + 3] != 65535 : ((const uint8_t *)px)[4 * i + 3] != 255)
            return false;
    for (size_t i = 0; i < n; i++)
        for (size_t k = 0; k < 3; k++) {
            if (sixteen) ((uint16_t *)px)[3 * i + k] = ((const uint16_t *)px)[4 * i + k];
            else ((uint8_t *)px)[3 * i + k] = ((const uint8_t *)px)[4 * i + k];
        }
    return true;
}

/* PNG, BMP, TGA or Radiance HDR bytes through stb_image (io/image_stb.h), JPEG through
 * libjpeg-turbo (io/jpeg.h), after the checks stb lacks (io/image_precheck.h): a TexImage
 * in the file's own storage (8-bit, 16-bit or float; grey files one channel). */
static CstStatus texture_decode_stb(const char *path, const unsigned char *data, size_t size, TexelEncoding enc,
                                    float gamma, TexImage **out, CstError *err)
{
    int dw = 0, dh = 0;
    CstStatus st = image_precheck_stb(path, data, size, &dw, &dh, err);
    if (st != CST_OK) return st;
    int len = (int)size; /* image_precheck_stb: size <= INT_MAX */
    int w = 0, h = 0, ch = 3;
    void *px = NULL;
    TexelFormat format = TEXEL_F32;
    if (image_precheck_format(data, size) == IMAGE_STB_JPEG) {
        /* libjpeg-turbo (io/jpeg.h): 8-bit, grey files one channel, its located errors. */
        unsigned char *bytes = NULL;
        st = jpeg_decode(path, data, size, &bytes, &w, &h, &ch, err);
        if (st != CST_OK) return st;
        px = bytes;
        format = TEXEL_U8;
    } else if (image_stb_is_hdr(data, len)) {
        /* Radiance HDR: linear floats, taken as they are (stbi_loadf would gamma-decode
         * an 8-bit image with its own 2.2 curve, so it is used for HDR files only). stb's
         * buffer is malloc'd (io/image_stb.c), so it is kept. */
        px = image_stb_load(data, len, 32, &w, &h);
        if (px) {
            st = image_check_radiance(px, w, h, path, err); /* NaN, Inf, < 0 */
            if (st != CST_OK) {
                free(px);
                return st;
            }
        }
        enc = TEXEL_LINEAR;
    } else {
        bool sixteen = image_stb_is_16_bit(data, len);
        format = sixteen ? TEXEL_U16 : TEXEL_U8;
        if (png_is_rgba(data, size)) {
            /* pbrt-v4 keeps the alpha of an RGBA PNG (colour type 6; not a palette's or a
             * tRNS key's) when it is not all 1 (MIPMap::CreateFromFile), and its float
             * textures read it (mipmap_bilerp_float); an opaque one is stored as RGB. */
            ch = 4;
            px = image_stb_load_n(data, len, sixteen ? 16 : 8, 4, &w, &h);
            if (px && alpha_all_one(px, (size_t)w * (size_t)h, sixteen)) {
                ch = 3;
                void *packed = realloc(px, (size_t)w * (size_t)h * 3 * (sixteen ? 2 : 1));
                if (packed) px = packed; /* a shrink: the larger block serves if it fails */
            }
        } else {
            px = image_stb_load_channels(data, len, sixteen ? 16 : 8, &w, &h, &ch);
        }
    }
    if (!px)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: cannot decode the image (%s); expected a PNG, JPEG, BMP, TGA, HDR, EXR or PFM file",
                        path, image_stb_failure_reason());
    if (w != dw || h != dh) { /* the header read twice by the same decoder: cannot differ */
        free(px);
        return cst_fail(err, CST_ERR_INTERNAL, "%s: decoded %d x %d pixels, the header declares %d x %d", path,
                        w, h, dw, dh);
    }
    if (!(*out = teximage_new(px, w, h, format, ch, enc, gamma)))
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d texture", path, w, h);
    return CST_OK;
}

/* Value k of n EXR texels as a float (halves widened exactly). */
static inline float exr_value(const ExrImage *e, size_t k)
{
    return e->half ? half_to_float(((const uint16_t *)e->px)[k]) : ((const float *)e->px)[k];
}

/* An OpenEXR file in its own storage (io/exr.h: halves stay halves, as pbrt-v4's
 * PixelFormat::Half), Y as one channel, R, G, B, and A when it is not all 1 (pbrt-v4
 * MIPMap::CreateFromFile, as for PNGs above). Every value is checked as every image input
 * is (finite, >= 0; image_check_radiance's message), alpha included. */
static CstStatus texture_decode_exr(const char *path, TexImage **out, CstError *err)
{
    FILE *fp = NULL;
    CstStatus st = file_open_input(path, &fp, NULL, err); /* regular files only, bounded */
    if (st != CST_OK) return st;
    ExrImage e;
    st = exr_read_texels(fp, path, &e, err);
    fclose(fp);
    if (st != CST_OK) return st;
    static const char names[4][4] = {"R", "G", "B", "A"};
    const size_t n = (size_t)e.width * (size_t)e.height, ch = (size_t)e.channels;
    bool opaque = ch == 4;
    for (size_t k = 0; k < n * ch; k++) {
        float v = exr_value(&e, k);
        if (ch == 4 && k % 4 == 3 && v != 1.0f) opaque = false;
        if (isfinite(v) && v >= 0.0f) continue;
        size_t px = k / ch;
        free(e.px);
        return cst_fail(err, CST_ERR_INVALID_ARG, "%.300s: pixel (%zu, %zu) channel %s is %g; expected a finite "
                        "value >= 0 (x from the left, y from the top row)", path, px % (size_t)e.width,
                        px / (size_t)e.width, ch == 1 ? "Y" : names[k % ch], (double)v);
    }
    if (opaque) { /* RGB in place, as alpha_all_one packs a PNG's */
        const size_t es = e.half ? 2 : 4;
        for (size_t i = 0; i < n; i++) memmove((char *)e.px + 3 * es * i, (char *)e.px + 4 * es * i, 3 * es);
        void *packed = realloc(e.px, n * 3 * es);
        if (packed) e.px = packed; /* a shrink: the larger block serves if it fails */
        e.channels = 3;
    }
    if (!(*out = teximage_new(e.px, e.width, e.height, e.half ? TEXEL_F16 : TEXEL_F32, e.channels, TEXEL_LINEAR,
                              1.0f)))
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d texture", path, e.width, e.height);
    return CST_OK;
}

CstStatus texture_image_load_encoded(Texture *t, const char *path, TexelEncoding enc, float gamma,
                                     TextureWrap wrap, CstError *err)
{
    memset(t, 0, sizeof *t);
    char *bytes = NULL;
    size_t size = 0;
    CstStatus st = file_read_all(path, &bytes, &size, err); /* regular files only */
    if (st != CST_OK) return st;
    const unsigned char *magic = (const unsigned char *)bytes;
    bool exr = size >= 4 && magic[0] == 0x76 && magic[1] == 0x2f && magic[2] == 0x31 && magic[3] == 0x01;
    bool pfm = size >= 2 && magic[0] == 'P' && (magic[1] == 'F' || magic[1] == 'f');
    if (exr) {
        free(bytes);
        TexImage *im = NULL;
        st = texture_decode_exr(path, &im, err);
        if (st != CST_OK) return st;
        texture_over(t, im, wrap);
        return CST_OK;
    }
    if (pfm) {
        /* PFM through the film's reader (our parser): 32-bit floats. */
        float *px = NULL;
        int w = 0, h = 0;
        free(bytes);
        st = image_read_radiance(path, &px, &w, &h, err);
        if (st != CST_OK) return st;
        return texture_image(t, px, w, h, wrap, err);
    }
    TexImage *im = NULL;
    st = texture_decode_stb(path, magic, size, enc, gamma, &im, err);
    free(bytes);
    if (st != CST_OK) return st;
    texture_over(t, im, wrap);
    return CST_OK;
}

CstStatus texture_image_load(Texture *t, const char *path, bool linear, TextureWrap wrap, CstError *err)
{
    return texture_image_load_encoded(t, path, linear ? TEXEL_LINEAR : TEXEL_SRGB, 1.0f, wrap, err);
}

void texture_share(Texture *dst, const Texture *src)
{
    *dst = *src;
    if (src->type == TEXTURE_IMAGE) src->image.im->refs++;
}

static Color texture_op(const TextureOp *op, Color v)
{
    Color a = op->a, b = op->b;
    switch (op->type) {
    case TEXTURE_OP_AFFINE:
        return color_rgb(maxf(0.0f, a.c[0] * v.c[0] + b.c[0]), maxf(0.0f, a.c[1] * v.c[1] + b.c[1]),
                         maxf(0.0f, a.c[2] * v.c[2] + b.c[2]));
    case TEXTURE_OP_MIN1: return color_rgb(minf(v.c[0], 1.0f), minf(v.c[1], 1.0f), minf(v.c[2], 1.0f));
    case TEXTURE_OP_POW:
        return color_rgb(powf(maxf(v.c[0], 0.0f), a.c[0]), powf(maxf(v.c[1], 0.0f), a.c[0]),
                         powf(maxf(v.c[2], 0.0f), a.c[0]));
    case TEXTURE_OP_RED: return color_s(v.c[0]);
    }
    return v;
}

static Color texture_apply_ops(const Texture *t, Color v)
{
    for (int i = 0; i < t->num_ops; i++) v = texture_op(&t->ops[i], v);
    return v;
}

bool texture_add_op(Texture *t, TextureOpType type, Color a, Color b)
{
    TextureOp op = {type, a, b};
    if (t->type == TEXTURE_CONSTANT) {
        t->value = texture_op(&op, t->value);
        t->average = t->max = t->value;
        return true;
    }
    if (t->type == TEXTURE_CHECKERBOARD || t->num_ops >= TEXTURE_MAX_OPS) return false;
    t->ops[t->num_ops++] = op;
    if (t->type == TEXTURE_IMAGE) {
        texture_image_stats(t);
    } else { /* procedural: the maps are monotone, so they bound max; the average is estimated */
        t->average = texture_op(&op, t->average);
        t->max = texture_op(&op, t->max);
    }
    return true;
}

CstStatus texture_set_filter(Texture *t, TextureFilter filter, float max_aniso, CstError *err)
{
    if (t->type != TEXTURE_IMAGE) return CST_OK;
    if (filter != TEXTURE_FILTER_NONE) {
        CstStatus st = mipmap_build(t->image.im, err);
        if (st != CST_OK) return st;
    }
    t->image.filter = filter;
    t->image.max_aniso = max_aniso > 0.0f ? max_aniso : 8.0f;
    return CST_OK;
}

void texture_set_scalar(Texture *t, bool scalar)
{
    if (t->type != TEXTURE_IMAGE || t->image.scalar == scalar) return;
    t->image.scalar = scalar;
    texture_image_stats(t);
}

size_t texture_image_bytes(const Texture *t)
{
    if (t->type != TEXTURE_IMAGE) return 0;
    const TexImage *im = t->image.im;
    size_t esize = texel_format_size(im->format), n = 0;
    for (int l = 0; l < im->num_levels; l++)
        n += (size_t)im->level[l].width * (size_t)im->level[l].height * (size_t)im->channels * esize;
    return n;
}

void texture_free(Texture *t)
{
    if (!t || t->type != TEXTURE_IMAGE || !t->image.im) return;
    TexImage *im = t->image.im;
    t->image.im = NULL;
    if (--im->refs > 0) return;
    for (int l = 0; l < im->num_levels; l++) free(im->level[l].texels);
    free(im);
}

void texture_set_uv_transform(Texture *t, Vec2 scale, Vec2 offset)
{
    t->uv_scale = scale;
    t->uv_offset = offset;
}

void texture_set_mapping(Texture *t, TextureMapping m, const float *xf, Vec3 vs, Vec3 vt, Vec2 offset)
{
    t->mapping = m;
    memset(t->map_xf, 0, sizeof t->map_xf);
    bool zero = true;
    for (int i = 0; xf && i < 12; i++) zero &= xf[i] == 0.0f;
    if (zero) t->map_xf[0] = t->map_xf[5] = t->map_xf[10] = 1.0f;
    else memcpy(t->map_xf, xf, sizeof t->map_xf);
    t->map_vs = vs;
    t->map_vt = vt;
    if (m == TEXTURE_MAP_PLANAR) t->uv_offset = offset, t->uv_scale = v2(1.0f, 1.0f);
}

Color texture_texel(const Texture *t, int level, int x, int y)
{
    return mipmap_texel(t->image.im, level, x, y, t->image.wrap);
}

bool texture_needs_footprint(const Texture *t)
{
    switch (t->type) {
    case TEXTURE_IMAGE: return t->image.filter != TEXTURE_FILTER_NONE;
    case TEXTURE_FBM: case TEXTURE_WRINKLED: case TEXTURE_WINDY: case TEXTURE_MARBLE: return true;
    default: return false;
    }
}

static float color_mean(Color c) { return (c.c[0] + c.c[1] + c.c[2]) * (1.0f / 3.0f); }

/* The largest |sum| of octaves of weight omega^i, noise within [-1, 1]. */
static float octave_bound(float omega, int octaves)
{
    float sum = 0.0f, o = 1.0f;
    for (int i = 0; i <= octaves; i++, o *= omega) sum += o;
    return sum;
}

bool texture_procedural(Texture *t, TextureType type, const TextureProc *pr, const Texture *textures)
{
    memset(t, 0, sizeof *t);
    t->type = type;
    t->uv_scale = v2(1.0f, 1.0f);
    t->proc = *pr;
    bool zero = true;
    for (int i = 0; i < 12; i++) zero &= pr->xf[i] == 0.0f;
    if (zero) t->proc.xf[0] = t->proc.xf[5] = t->proc.xf[10] = 1.0f;
    int depth = 0;
    const int kids[3] = {pr->tex1, pr->tex2, pr->amount};
    for (int k = 0; k < 3; k++)
        if (kids[k] >= 0 && textures[kids[k]].depth > depth) depth = textures[kids[k]].depth;
    t->depth = depth + 1;
    Color a1 = pr->tex1 >= 0 ? textures[pr->tex1].average : color_s(0.0f);
    Color a2 = pr->tex2 >= 0 ? textures[pr->tex2].average : color_s(0.0f);
    Color m1 = pr->tex1 >= 0 ? textures[pr->tex1].max : color_s(0.0f);
    Color m2 = pr->tex2 >= 0 ? textures[pr->tex2].max : color_s(0.0f);
    float bound = octave_bound(pr->omega, pr->octaves);
    switch (type) {
    case TEXTURE_MIX: {
        float a = pr->amount >= 0 ? color_mean(textures[pr->amount].average) : pr->amount_value;
        t->average = color_add(color_scale(a1, 1.0f - a), color_scale(a2, a));
        t->max = rgb_max3(m1, m2);
        break;
    }
    case TEXTURE_DIRECTIONMIX: /* |n . dir| averages 1/2 over directions */
    case TEXTURE_CHECKER3D:    /* equal volumes */
        t->average = color_scale(color_add(a1, a2), 0.5f);
        t->max = rgb_max3(m1, m2);
        break;
    case TEXTURE_DOTS: { /* a dot in half the cells (noise > 0), of area pi 0.35^2 */
        float f = 0.5f * CST_PI * 0.35f * 0.35f;
        t->average = color_add(color_scale(a1, f), color_scale(a2, 1.0f - f));
        t->max = rgb_max3(m1, m2);
        break;
    }
    case TEXTURE_SCALE:
        t->average = color_scale(a1, color_mean(textures[pr->amount].average));
        t->max = color_scale(m1, color_max(textures[pr->amount].max));
        break;
    case TEXTURE_BILERP:
        t->average = color_scale(color_add(color_add(pr->corner[0], pr->corner[1]), color_add(pr->corner[2], pr->corner[3])), 0.25f);
        t->max = rgb_max3(rgb_max3(pr->corner[0], pr->corner[1]), rgb_max3(pr->corner[2], pr->corner[3]));
        break;
    case TEXTURE_FBM: t->average = color_s(0.0f), t->max = color_s(bound); break;
    case TEXTURE_WRINKLED: t->average = color_s(0.2f * bound), t->max = color_s(bound); break;
    case TEXTURE_WINDY: t->average = color_s(0.0f), t->max = color_s(octave_bound(0.5f, 3) * octave_bound(0.5f, 6)); break;
    case TEXTURE_MARBLE: t->average = color_rgb(0.84f, 0.83f, 0.86f), t->max = color_rgb(0.9f, 0.9f, 0.9f); break;
    default: break;
    }
    return t->depth <= TEXTURE_MAX_DEPTH;
}

/* p through a solid texture's texture_from_world (points), and a vector (no translation). */
static inline Vec3 xf_point(const float *m, Vec3 p)
{
    return v3(m[0] * p.x + m[1] * p.y + m[2] * p.z + m[3], m[4] * p.x + m[5] * p.y + m[6] * p.z + m[7],
              m[8] * p.x + m[9] * p.y + m[10] * p.z + m[11]);
}
static inline Vec3 xf_vector(const float *m, Vec3 v)
{
    return v3(m[0] * v.x + m[1] * v.y + m[2] * v.z, m[4] * v.x + m[5] * v.y + m[6] * v.z,
              m[8] * v.x + m[9] * v.y + m[10] * v.z);
}

/* The mappings of pbrt-v4's TextureMapping2D::Map. The derivatives are the gradients of
 * (s, t) with respect to the texture-space point, dotted with the point's screen
 * derivatives (PBR 4th ed. eqs. 10.9-10.11): spherical ds/dp = (-y, x, 0) / (2 pi (x^2 +
 * y^2)) for phi, and dt/dp = (x z / r, y z / r, -r) / (pi |p|^2), r = sqrt(x^2 + y^2), for
 * theta, which pbrt-v4 assigns to s and t the other way round (its s is theta / pi, its
 * derivatives' s is phi's): kept as pbrt-v4 has it, so footprints match its MIP levels. */
Vec2 texture_map_st(const Texture *t, const TexCtx *c, Vec2 *d0, Vec2 *d1)
{
    if (t->mapping == TEXTURE_MAP_UV) {
        *d0 = v2(t->uv_scale.x * c->dudx, t->uv_scale.y * c->dvdx);
        *d1 = v2(t->uv_scale.x * c->dudy, t->uv_scale.y * c->dvdy);
        return v2(c->uv.x * t->uv_scale.x + t->uv_offset.x, c->uv.y * t->uv_scale.y + t->uv_offset.y);
    }
    Vec3 p = xf_point(t->map_xf, c->p);
    Vec3 dx = xf_vector(t->map_xf, c->dpdx), dy = xf_vector(t->map_xf, c->dpdy);
    Vec3 dsdp, dtdp;
    Vec2 st;
    const float inv_2pi = 1.0f / (2.0f * CST_PI);
    float x2y2 = p.x * p.x + p.y * p.y;
    switch (t->mapping) {
    case TEXTURE_MAP_SPHERICAL: {
        float r = sqrtf(x2y2), l2 = x2y2 + p.z * p.z;
        dsdp = x2y2 > 0.0f ? v3_scale(v3(-p.y, p.x, 0.0f), inv_2pi / x2y2) : v3s(0.0f);
        dtdp = r > 0.0f ? v3_scale(v3(p.x * p.z / r, p.y * p.z / r, -r), 1.0f / (CST_PI * l2)) : v3s(0.0f);
        float len = sqrtf(l2);
        float cz = len > 0.0f ? clampf(p.z / len, -1.0f, 1.0f) : 1.0f;
        float phi = atan2f(p.y, p.x);
        if (phi < 0.0f) phi += 2.0f * CST_PI;
        st = v2(acosf(cz) * (1.0f / CST_PI), phi * inv_2pi);
        break;
    }
    case TEXTURE_MAP_CYLINDRICAL:
        dsdp = x2y2 > 0.0f ? v3_scale(v3(-p.y, p.x, 0.0f), inv_2pi / x2y2) : v3s(0.0f);
        dtdp = v3(0.0f, 0.0f, 1.0f);
        st = v2((CST_PI + atan2f(p.y, p.x)) * inv_2pi, p.z);
        break;
    default: /* planar */
        dsdp = t->map_vs;
        dtdp = t->map_vt;
        st = v2(t->uv_offset.x + v3_dot(p, t->map_vs), t->uv_offset.y + v3_dot(p, t->map_vt));
        break;
    }
    *d0 = v2(v3_dot(dsdp, dx), v3_dot(dtdp, dx));
    *d1 = v2(v3_dot(dsdp, dy), v3_dot(dtdp, dy));
    return st;
}

/* An image texture at st (already mapped) with its footprint d0, d1. */
static Color texture_image_eval(const Texture *t, Vec2 st, Vec2 d0, Vec2 d1)
{
    const TextureImage *ti = &t->image;
    if (ti->scalar)
        return color_s(ti->filter == TEXTURE_FILTER_NONE
                           ? mipmap_bilerp_float(ti->im, 0, ti->wrap, st)
                           : mipmap_filter_float(ti->im, ti->wrap, ti->filter, ti->max_aniso, st, d0, d1));
    if (ti->filter == TEXTURE_FILTER_NONE) return mipmap_bilerp(ti->im, 0, ti->wrap, st);
    return mipmap_filter(ti->im, ti->wrap, ti->filter, ti->max_aniso, st, d0, d1);
}

static inline Color lerp_color(float t, Color a, Color b) { return color_add(color_scale(a, 1.0f - t), color_scale(b, t)); }

/* pbrt-v4's marble colours (MarbleTexture), a cubic Bezier spline through 9 RGB points. */
static Color marble_colour(float t)
{
    static const float c[9][3] = {{0.58f, 0.58f, 0.6f}, {0.58f, 0.58f, 0.6f}, {0.58f, 0.58f, 0.6f},
                                  {0.5f, 0.5f, 0.5f},   {0.6f, 0.59f, 0.58f}, {0.58f, 0.58f, 0.6f},
                                  {0.58f, 0.58f, 0.6f}, {0.2f, 0.2f, 0.33f},  {0.58f, 0.58f, 0.6f}};
    enum { NSEG = 9 - 3 };
    t = clampf(t, 0.0f, 1.0f);
    int first = (int)floorf(t * NSEG);
    if (first > NSEG - 1) first = NSEG - 1;
    t = t * NSEG - (float)first;
    Color p[4];
    for (int i = 0; i < 4; i++) p[i] = color_rgb(c[first + i][0], c[first + i][1], c[first + i][2]);
    /* de Casteljau */
    Color s0 = lerp_color(t, p[0], p[1]), s1 = lerp_color(t, p[1], p[2]), s2 = lerp_color(t, p[2], p[3]);
    s0 = lerp_color(t, s0, s1), s1 = lerp_color(t, s1, s2);
    return color_scale(lerp_color(t, s0, s1), 1.5f); /* pbrt's extra 1.5 for more variation */
}

static Color eval_rec(const Texture *textures, int id, const TexCtx *c);

/* A procedural or combining texture (depth-bounded recursion, TEXTURE_MAX_DEPTH). */
static Color eval_proc(const Texture *textures, const Texture *t, Vec2 st, const TexCtx *c)
{
    const TextureProc *pr = &t->proc;
    switch (t->type) {
    case TEXTURE_MIX: {
        float a = pr->amount >= 0 ? color_mean(eval_rec(textures, pr->amount, c)) : pr->amount_value;
        Color t1 = a != 1.0f ? eval_rec(textures, pr->tex1, c) : color_s(0.0f);
        Color t2 = a != 0.0f ? eval_rec(textures, pr->tex2, c) : color_s(0.0f);
        return color_add(color_scale(t1, 1.0f - a), color_scale(t2, a));
    }
    case TEXTURE_DIRECTIONMIX: {
        float a = fabsf(v3_dot(c->n, pr->dir));
        Color t1 = a != 0.0f ? eval_rec(textures, pr->tex1, c) : color_s(0.0f);
        Color t2 = a != 1.0f ? eval_rec(textures, pr->tex2, c) : color_s(0.0f);
        return color_add(color_scale(t1, a), color_scale(t2, 1.0f - a));
    }
    case TEXTURE_SCALE: {
        float k = color_mean(eval_rec(textures, pr->amount, c));
        return k == 0.0f ? color_s(0.0f) : color_scale(eval_rec(textures, pr->tex1, c), k);
    }
    case TEXTURE_BILERP: {
        float s = st.x, u = st.y;
        return color_add(color_add(color_scale(pr->corner[0], (1.0f - s) * (1.0f - u)), color_scale(pr->corner[1], (1.0f - s) * u)),
                         color_add(color_scale(pr->corner[2], s * (1.0f - u)), color_scale(pr->corner[3], s * u)));
    }
    case TEXTURE_DOTS: {
        /* One candidate dot per unit cell around integer (s, t), present where the noise
         * at the cell is positive, its centre jittered by two more noise lookups. */
        float sc = floorf(st.x + 0.5f), tc = floorf(st.y + 0.5f);
        if (noise3(v3(sc + 0.5f, tc + 0.5f, 0.5f)) > 0.0f) {
            const float radius = 0.35f, shift = 0.5f - radius;
            float cs = sc + shift * noise3(v3(sc + 1.5f, tc + 2.8f, 0.5f));
            float ct = tc + shift * noise3(v3(sc + 4.5f, tc + 9.8f, 0.5f));
            float ds = st.x - cs, dt = st.y - ct;
            if (ds * ds + dt * dt < radius * radius) return eval_rec(textures, pr->tex1, c);
        }
        return eval_rec(textures, pr->tex2, c);
    }
    default: break;
    }
    /* Solid textures: p and its footprint in texture space. */
    Vec3 p = xf_point(pr->xf, c->p), dx = xf_vector(pr->xf, c->dpdx), dy = xf_vector(pr->xf, c->dpdy);
    switch (t->type) {
    case TEXTURE_CHECKER3D: {
        float sum = floorf(p.x) + floorf(p.y) + floorf(p.z);
        float parity = fmodf(sum, 2.0f); /* exact; NaN counts as even */
        return eval_rec(textures, parity == 1.0f || parity == -1.0f ? pr->tex2 : pr->tex1, c);
    }
    case TEXTURE_FBM: return color_s(noise_fbm(p, dx, dy, pr->omega, pr->octaves));
    case TEXTURE_WRINKLED: return color_s(noise_turbulence(p, dx, dy, pr->omega, pr->octaves));
    case TEXTURE_WINDY: {
        float wind = noise_fbm(v3_scale(p, 0.1f), v3_scale(dx, 0.1f), v3_scale(dy, 0.1f), 0.5f, 3);
        float wave = noise_fbm(p, dx, dy, 0.5f, 6);
        return color_s(fabsf(wind) * wave);
    }
    case TEXTURE_MARBLE: {
        p = v3_scale(p, pr->scale);
        float m = p.y + pr->variation * noise_fbm(p, v3_scale(dx, pr->scale), v3_scale(dy, pr->scale), pr->omega, pr->octaves);
        return marble_colour(0.5f + 0.5f * sinf(m));
    }
    default: return color_s(0.0f);
    }
}

static Color eval_rec(const Texture *textures, int id, const TexCtx *c)
{
    /* Checkerboards only select another texture, so their nesting is a loop; children have
     * lower indices, so it ends. */
    Vec2 uv = c->uv;
    for (;;) {
        const Texture *t = &textures[id];
        /* Exact for the identity (x * 1 + 0 == x), so untransformed textures are unchanged. */
        Vec2 st = v2(uv.x * t->uv_scale.x + t->uv_offset.x, uv.y * t->uv_scale.y + t->uv_offset.y);
        Vec2 d0 = v2(0.0f, 0.0f), d1 = d0;
        if (t->mapping != TEXTURE_MAP_UV) st = texture_map_st(t, c, &d0, &d1);
        switch (t->type) {
        case TEXTURE_CONSTANT: return t->value; /* its maps are folded in */
        case TEXTURE_IMAGE: {
            if (t->mapping == TEXTURE_MAP_UV) {
                d0 = v2(t->uv_scale.x * c->dudx, t->uv_scale.y * c->dvdx);
                d1 = v2(t->uv_scale.x * c->dudy, t->uv_scale.y * c->dvdy);
            }
            Color v = texture_image_eval(t, st, d0, d1);
            return t->num_ops ? texture_apply_ops(t, v) : v;
        }
        case TEXTURE_CHECKERBOARD: {
            float su = floorf(st.x * t->checker.scale), sv = floorf(st.y * t->checker.scale);
            /* fmodf is exact; beyond 2^24 every float is even, and NaN counts as even. */
            float parity = fmodf(su + sv, 2.0f);
            id = parity == 1.0f || parity == -1.0f ? t->checker.odd : t->checker.even;
            break;
        }
        default: {
            Color v = eval_proc(textures, t, st, c);
            return t->num_ops ? texture_apply_ops(t, v) : v;
        }
        }
    }
}

Color texture_eval_ctx(const Texture *textures, int id, const TexCtx *c) { return eval_rec(textures, id, c); }
