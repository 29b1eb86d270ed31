/* MIP pyramids of texture images and their filtered lookups (pbrt-v4 MIPMap, described in
 * Pharr, Jakob, Humphreys, "Physically Based Rendering", 4th ed., sec. 10.4.3-10.4.5;
 * EWA after Heckbert 1989, "Fundamentals of Texture Mapping and Image Warping", sec. 3.5). */
#include "textures/mipmap.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "math/half.h"

/* ------------------------------------------------------------------ texels */

static inline float decode16(const TexImage *im, uint16_t w)
{
    /* The expressions of the historical decoder, so 16-bit images stay bit-identical. */
    switch (im->encoding) {
    case TEXEL_LINEAR: return (float)w / 65535.0f;
    case TEXEL_SRGB: return image_srgb_to_linear(w / 65535.0);
    case TEXEL_GAMMA: return powf((float)w / 65535.0f, im->gamma);
    }
    return 0.0f;
}

/* Element k (texel * channels + channel) of level lv, decoded. */
static inline float element_at(const TexImage *im, const TexLevel *lv, size_t k)
{
    switch (im->format) {
    case TEXEL_U8: return im->lut[((const uint8_t *)lv->texels)[k]];
    case TEXEL_U16: return decode16(im, ((const uint16_t *)lv->texels)[k]);
    case TEXEL_F16: return half_to_float(((const uint16_t *)lv->texels)[k]);
    default: return ((const float *)lv->texels)[k];
    }
}

/* Texel index i (already wrapped) of level lv, decoded: RGB (alpha, if kept, not read). */
static inline Color texel_at(const TexImage *im, const TexLevel *lv, size_t i)
{
    if (im->channels == 1) {
        float v;
        switch (im->format) {
        case TEXEL_U8: v = im->lut[((const uint8_t *)lv->texels)[i]]; break;
        case TEXEL_U16: v = decode16(im, ((const uint16_t *)lv->texels)[i]); break;
        case TEXEL_F16: v = half_to_float(((const uint16_t *)lv->texels)[i]); break;
        default: v = ((const float *)lv->texels)[i]; break;
        }
        return color_s(v);
    }
    const size_t o = (size_t)im->channels * i;
    switch (im->format) {
    case TEXEL_U8: {
        const uint8_t *p = (const uint8_t *)lv->texels + o;
        return color_rgb(im->lut[p[0]], im->lut[p[1]], im->lut[p[2]]);
    }
    case TEXEL_U16: {
        const uint16_t *p = (const uint16_t *)lv->texels + o;
        return color_rgb(decode16(im, p[0]), decode16(im, p[1]), decode16(im, p[2]));
    }
    case TEXEL_F16: {
        const uint16_t *p = (const uint16_t *)lv->texels + o;
        return color_rgb(half_to_float(p[0]), half_to_float(p[1]), half_to_float(p[2]));
    }
    default: {
        const float *p = (const float *)lv->texels + o;
        return color_rgb(p[0], p[1], p[2]);
    }
    }
}

/* Any integer index wrapped onto [0, n). */
static inline int wrap_any(int i, int n, TextureWrap wrap)
{
    if (wrap == TEXTURE_WRAP_CLAMP) return i < 0 ? 0 : i >= n ? n - 1 : i;
    int r = i % n;
    return r < 0 ? r + n : r;
}

Color mipmap_texel(const TexImage *im, int level, int x, int y, TextureWrap wrap)
{
    const TexLevel *lv = &im->level[level];
    x = wrap_any(x, lv->width, wrap);
    y = wrap_any(y, lv->height, wrap);
    return texel_at(im, lv, (size_t)y * (size_t)lv->width + (size_t)x);
}

/* A texel index along an axis of n texels, i within one period of [0, n). */
static inline int wrap_near(int i, int n, TextureWrap wrap)
{
    if (wrap == TEXTURE_WRAP_CLAMP) return i < 0 ? 0 : i >= n ? n - 1 : i;
    return i < 0 ? i + n : i >= n ? i - n : i;
}

/* Reduces st to one period (repeat) or the unit square (clamp), so the texel coordinates
 * made from it are small and their conversion to int cannot overflow. */
static inline Vec2 reduce_st(Vec2 st, TextureWrap wrap)
{
    float u = st.x, v = st.y;
    if (!isfinite(u)) u = 0.0f;
    if (!isfinite(v)) v = 0.0f;
    if (wrap == TEXTURE_WRAP_REPEAT) {
        u -= floorf(u);
        v -= floorf(v);
    } else {
        u = clampf(u, 0.0f, 1.0f);
        v = clampf(v, 0.0f, 1.0f);
    }
    return v2(u, v);
}

/* The four texels around st on lv and their bilinear weights, in the order 00, 10, 01, 11
 * (x then y, y = 0 the top row). */
static inline void bilerp_taps(const TexLevel *lv, TextureWrap wrap, Vec2 st, size_t idx[4], float wt[4])
{
    Vec2 r = reduce_st(st, wrap);
    float x = r.x * (float)lv->width - 0.5f, y = (1.0f - r.y) * (float)lv->height - 0.5f;
    float fx0 = floorf(x), fy0 = floorf(y);
    float dx = x - fx0, dy = y - fy0;
    int x0 = (int)fx0, y0 = (int)fy0;
    size_t w = (size_t)lv->width;
    size_t xa = (size_t)wrap_near(x0, lv->width, wrap), xb = (size_t)wrap_near(x0 + 1, lv->width, wrap);
    size_t ya = (size_t)wrap_near(y0, lv->height, wrap), yb = (size_t)wrap_near(y0 + 1, lv->height, wrap);
    idx[0] = ya * w + xa, idx[1] = ya * w + xb, idx[2] = yb * w + xa, idx[3] = yb * w + xb;
    wt[0] = (1.0f - dx) * (1.0f - dy), wt[1] = dx * (1.0f - dy), wt[2] = (1.0f - dx) * dy, wt[3] = dx * dy;
}

Color mipmap_bilerp(const TexImage *im, int level, TextureWrap wrap, Vec2 st)
{
    const TexLevel *lv = &im->level[level];
    size_t i[4];
    float w[4];
    bilerp_taps(lv, wrap, st, i, w);
    Color p00 = texel_at(im, lv, i[0]), p10 = texel_at(im, lv, i[1]);
    Color p01 = texel_at(im, lv, i[2]), p11 = texel_at(im, lv, i[3]);
    return color_rgb(w[0] * p00.c[0] + w[1] * p10.c[0] + w[2] * p01.c[0] + w[3] * p11.c[0],
                     w[0] * p00.c[1] + w[1] * p10.c[1] + w[2] * p01.c[1] + w[3] * p11.c[1],
                     w[0] * p00.c[2] + w[1] * p10.c[2] + w[2] * p01.c[2] + w[3] * p11.c[2]);
}

/* Channel c of the texels i[0..3] of lv, weighted (pbrt-v4 Image::BilerpChannel). */
static inline float bilerp_channel(const TexImage *im, const TexLevel *lv, const size_t i[4], const float w[4], int c)
{
    size_t n = (size_t)im->channels, k = (size_t)c;
    return w[0] * element_at(im, lv, n * i[0] + k) + w[1] * element_at(im, lv, n * i[1] + k) +
           w[2] * element_at(im, lv, n * i[2] + k) + w[3] * element_at(im, lv, n * i[3] + k);
}

float mipmap_bilerp_float(const TexImage *im, int level, TextureWrap wrap, Vec2 st)
{
    const TexLevel *lv = &im->level[level];
    size_t i[4];
    float w[4];
    bilerp_taps(lv, wrap, st, i, w);
    switch (im->channels) {
    case 3: /* Image::Bilerp(...).Average(): each channel interpolated, then their mean */
        return (bilerp_channel(im, lv, i, w, 0) + bilerp_channel(im, lv, i, w, 1) + bilerp_channel(im, lv, i, w, 2)) /
               3.0f;
    case 4: return bilerp_channel(im, lv, i, w, 3); /* alpha */
    default: return bilerp_channel(im, lv, i, w, 0);
    }
}

float mipmap_texel_float(const TexImage *im, int level, int x, int y, TextureWrap wrap)
{
    const TexLevel *lv = &im->level[level];
    x = wrap_any(x, lv->width, wrap);
    y = wrap_any(y, lv->height, wrap);
    return element_at(im, lv, (size_t)im->channels * ((size_t)y * (size_t)lv->width + (size_t)x));
}

float mipmap_centre_float(const TexImage *im, int x, int y)
{
    const TexLevel *lv = &im->level[0];
    size_t n = (size_t)im->channels, i = n * ((size_t)y * (size_t)lv->width + (size_t)x);
    switch (im->channels) {
    case 3: return (element_at(im, lv, i) + element_at(im, lv, i + 1) + element_at(im, lv, i + 2)) / 3.0f;
    case 4: return element_at(im, lv, i + 3);
    default: return element_at(im, lv, i);
    }
}

/* ------------------------------------------------------------------ filters */

/* The two lookups pbrt-v4's MIPMap::Filter<T> is made of, for T = RGB (scalar false) or
 * T = Float (scalar true: the value in all three channels). pbrt-v4 reads one texel as
 * Texel<Float>, channel 0 (R of an RGB image) whatever the channels, but interpolates as
 * Bilerp<Float>, which depends on them (mipmap_bilerp_float): so a float texture's point,
 * EWA and coarsest-level values use R, its bilinear and trilinear ones the mean or alpha. */
static inline Color texel_t(const TexImage *im, int level, int x, int y, TextureWrap wrap, bool scalar)
{
    return scalar ? color_s(mipmap_texel_float(im, level, x, y, wrap)) : mipmap_texel(im, level, x, y, wrap);
}

static inline Color bilerp_t(const TexImage *im, int level, TextureWrap wrap, Vec2 st, bool scalar)
{
    return scalar ? color_s(mipmap_bilerp_float(im, level, wrap, st)) : mipmap_bilerp(im, level, wrap, st);
}

static inline Color color_lerp(float t, Color a, Color b)
{
    return color_add(color_scale(a, 1.0f - t), color_scale(b, t));
}

/* EWA on one level (PBR 4th ed. sec. 10.4.5): the footprint's ellipse in texel units, each
 * texel inside it weighted by a Gaussian of its ellipse radius, exp(-2 r^2) - exp(-2),
 * which falls to 0 at the ellipse's edge. st and the derivatives have t pointing down
 * (row 0 at t = 0), as the texels are stored. */
static Color ewa_level(const TexImage *im, int level, TextureWrap wrap, Vec2 st, Vec2 dst0, Vec2 dst1, bool scalar)
{
    if (level >= im->num_levels) return texel_t(im, im->num_levels - 1, 0, 0, wrap, scalar);
    const TexLevel *lv = &im->level[level];
    float w = (float)lv->width, h = (float)lv->height;
    float s = st.x * w - 0.5f, t = st.y * h - 0.5f;
    float d0s = dst0.x * w, d0t = dst0.y * h, d1s = dst1.x * w, d1t = dst1.y * h;
    /* The implicit ellipse A s^2 + B s t + C t^2 = F of the two axes, widened by one texel
     * in each direction so that it always covers a texel centre (Heckbert 1989). */
    float a = d0t * d0t + d1t * d1t + 1.0f;
    float b = -2.0f * (d0s * d0t + d1s * d1t);
    float c = d0s * d0s + d1s * d1s + 1.0f;
    float inv_f = 1.0f / (a * c - b * b * 0.25f);
    a *= inv_f, b *= inv_f, c *= inv_f;
    /* Its bounding box. */
    float det = -b * b + 4.0f * a * c, inv_det = 1.0f / det;
    float us = sqrtf(det * c), vs = sqrtf(a * det);
    float s0f = ceilf(s - 2.0f * inv_det * us), s1f = floorf(s + 2.0f * inv_det * us);
    float t0f = ceilf(t - 2.0f * inv_det * vs), t1f = floorf(t + 2.0f * inv_det * vs);
    if (!(s1f - s0f < 4096.0f && t1f - t0f < 4096.0f)) /* NaN or absurd: no footprint */
        return bilerp_t(im, level, wrap, v2(st.x, 1.0f - st.y), scalar);
    int s0 = (int)s0f, s1 = (int)s1f, t0 = (int)t0f, t1 = (int)t1f;
    const float e2 = expf(-2.0f);
    Color sum = color_s(0.0f);
    float wsum = 0.0f;
    for (int it = t0; it <= t1; it++) {
        float tt = (float)it - t;
        for (int is = s0; is <= s1; is++) {
            float ss = (float)is - s;
            float r2 = a * ss * ss + b * ss * tt + c * tt * tt;
            if (r2 < 1.0f) {
                float wt = expf(-2.0f * r2) - e2;
                sum = color_add(sum, color_scale(texel_t(im, level, is, it, wrap, scalar), wt));
                wsum += wt;
            }
        }
    }
    if (!(wsum > 0.0f)) return bilerp_t(im, level, wrap, v2(st.x, 1.0f - st.y), scalar);
    return color_scale(sum, 1.0f / wsum);
}

static inline float v2_len2(Vec2 a) { return a.x * a.x + a.y * a.y; }

static Color filter_t(const TexImage *im, TextureWrap wrap, TextureFilter filter, float max_aniso, Vec2 st,
                      Vec2 dst0, Vec2 dst1, bool scalar)
{
    int nl = im->num_levels;
    if (filter != TEXTURE_FILTER_EWA) {
        /* A square footprint as wide as the largest derivative, on the level whose texels
         * are that wide: level = nLevels - 1 + log2(width) (PBR 4th ed. eq. 10.15). */
        float width = 2.0f * maxf(maxf(fabsf(dst0.x), fabsf(dst0.y)), maxf(fabsf(dst1.x), fabsf(dst1.y)));
        float level = (float)(nl - 1) + log2f(maxf(width, 1e-8f));
        if (!(level < (float)(nl - 1))) return texel_t(im, nl - 1, 0, 0, wrap, scalar); /* NaN too */
        int il = level > 0.0f ? (int)floorf(level) : 0;
        if (filter == TEXTURE_FILTER_POINT) {
            const TexLevel *lv = &im->level[il];
            Vec2 r = reduce_st(st, wrap);
            int x = (int)floorf(r.x * (float)lv->width - 0.5f + 0.5f);
            int y = (int)floorf((1.0f - r.y) * (float)lv->height - 0.5f + 0.5f);
            return texel_t(im, il, x, y, wrap, scalar);
        }
        if (filter == TEXTURE_FILTER_BILINEAR || il == 0) return bilerp_t(im, il, wrap, st, scalar);
        float delta = level - (float)il; /* trilinear: il + 1 <= nl - 1 here */
        return color_lerp(delta, bilerp_t(im, il, wrap, st, scalar), bilerp_t(im, il + 1, wrap, st, scalar));
    }
    /* EWA: t flipped to the stored orientation (row 0 at the top). */
    Vec2 r = reduce_st(st, wrap);
    Vec2 p = v2(r.x, 1.0f - r.y);
    Vec2 a0 = v2(dst0.x, -dst0.y), a1 = v2(dst1.x, -dst1.y);
    if (v2_len2(a0) < v2_len2(a1)) { /* a0 the major axis */
        Vec2 tmp = a0;
        a0 = a1;
        a1 = tmp;
    }
    float longer = sqrtf(v2_len2(a0)), shorter = sqrtf(v2_len2(a1));
    /* Clamp the eccentricity: lengthen the minor axis, which blurs rather than alias and
     * bounds the texels visited (PBR 4th ed. sec. 10.4.5). */
    if (shorter * max_aniso < longer && shorter > 0.0f) {
        float sc = longer / (shorter * max_aniso);
        a1 = v2(a1.x * sc, a1.y * sc);
        shorter *= sc;
    }
    if (!(shorter > 0.0f) || !isfinite(longer)) return bilerp_t(im, 0, wrap, st, scalar);
    float lod = maxf(0.0f, (float)(nl - 1) + log2f(shorter));
    int il = (int)floorf(lod);
    return color_lerp(lod - (float)il, ewa_level(im, il, wrap, p, a0, a1, scalar),
                      ewa_level(im, il + 1, wrap, p, a0, a1, scalar));
}

Color mipmap_filter(const TexImage *im, TextureWrap wrap, TextureFilter filter, float max_aniso, Vec2 st,
                    Vec2 dst0, Vec2 dst1)
{
    return filter_t(im, wrap, filter, max_aniso, st, dst0, dst1, false);
}

float mipmap_filter_float(const TexImage *im, TextureWrap wrap, TextureFilter filter, float max_aniso, Vec2 st,
                          Vec2 dst0, Vec2 dst1)
{
    return filter_t(im, wrap, filter, max_aniso, st, dst0, dst1, true).c[0];
}

/* ------------------------------------------------------------------ pyramid */

/* A linear value back to the image's format: the nearest code (8-bit: by bisection of the
 * decoding table, which every encoding makes non-decreasing). */
static void encode_value(const TexImage *im, float v, void *texels, size_t i)
{
    if (!(v > 0.0f)) v = 0.0f;
    switch (im->format) {
    case TEXEL_U8: {
        int lo = 0, hi = 255;
        while (lo < hi) { /* the first code with lut >= v */
            int mid = (lo + hi) / 2;
            if (im->lut[mid] < v) lo = mid + 1;
            else hi = mid;
        }
        if (lo > 0 && v - im->lut[lo - 1] < im->lut[lo] - v) lo--;
        ((uint8_t *)texels)[i] = (uint8_t)lo;
        break;
    }
    case TEXEL_U16: {
        float c = minf(v, 1.0f);
        if (im->encoding == TEXEL_SRGB) c = image_linear_to_srgb(c);
        else if (im->encoding == TEXEL_GAMMA) c = powf(c, 1.0f / im->gamma);
        ((uint16_t *)texels)[i] = (uint16_t)(c * 65535.0f + 0.5f);
        break;
    }
    case TEXEL_F32: ((float *)texels)[i] = v; break;
    case TEXEL_F16: ((uint16_t *)texels)[i] = float_to_half(v); break;
    }
}

/* The source texels [a, b) of an axis of n texels that output j of m covers (area-weighted
 * box: output j covers source [j n/m, (j+1) n/m)), with their overlap weights; at most 3
 * texels as m >= n/2. */
static int box_taps(int j, int n, int m, int idx[3], double wt[3])
{
    double ratio = (double)n / (double)m, a = j * ratio, b = (j + 1) * ratio;
    int k = 0;
    for (int i = (int)floor(a); i < n && (double)i < b && k < 3; i++) {
        double w = fmin(b, i + 1.0) - fmax(a, (double)i);
        if (w <= 0.0) continue;
        idx[k] = i;
        wt[k++] = w / ratio;
    }
    return k;
}

CstStatus mipmap_build(TexImage *im, CstError *err)
{
    if (im->num_levels > 1) return CST_OK;
    int ch = im->channels;
    size_t esize = texel_format_size(im->format);
    TexLevel made[TEXTURE_MAX_LEVELS];
    made[0] = im->level[0];
    int nl = 1;
    /* Each level from the previous one as stored (quantised, as a reader sees it), texels
     * decoded on the fly: no float copy of a level is ever held. */
    while ((made[nl - 1].width > 1 || made[nl - 1].height > 1) && nl < TEXTURE_MAX_LEVELS) {
        const TexLevel *src = &made[nl - 1];
        int w = src->width, h = src->height;
        int w2 = w > 1 ? (w + 1) / 2 : 1, h2 = h > 1 ? (h + 1) / 2 : 1;
        TexLevel *lv = &made[nl];
        lv->width = w2, lv->height = h2;
        if (!(lv->texels = malloc((size_t)w2 * (size_t)h2 * (size_t)ch * esize))) goto oom;
        nl++;
        for (int y = 0; y < h2; y++) {
            int iy[3], ix[3];
            double wy[3], wx[3];
            int ny = box_taps(y, h, h2, iy, wy);
            for (int x = 0; x < w2; x++) {
                int nx = box_taps(x, w, w2, ix, wx);
                double acc[4] = {0.0, 0.0, 0.0, 0.0};
                for (int a = 0; a < ny; a++)
                    for (int b = 0; b < nx; b++) {
                        size_t e = (size_t)ch * ((size_t)iy[a] * (size_t)w + (size_t)ix[b]);
                        for (int k = 0; k < ch; k++)
                            acc[k] += wy[a] * wx[b] * (double)element_at(im, src, e + (size_t)k);
                    }
                size_t o = ((size_t)y * (size_t)w2 + (size_t)x) * (size_t)ch;
                for (int k = 0; k < ch; k++) encode_value(im, (float)acc[k], lv->texels, o + (size_t)k);
            }
        }
    }
    for (int l = 1; l < nl; l++) im->level[l] = made[l];
    im->num_levels = nl;
    return CST_OK;
oom:
    for (int l = 1; l < nl; l++) free(made[l].texels);
    return cst_fail(err, CST_ERR_OOM, "out of memory for the MIP map of a %d x %d texture", im->level[0].width,
                    im->level[0].height);
}
