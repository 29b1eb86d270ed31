/* Image pyramids of texture images (TexImage, textures/texture.h) and their lookups:
 * texel decoding of the compact formats, bilinear interpolation on one level, and
 * pbrt-v4's MIPMap filters (point, bilinear, trilinear, EWA) driven by a footprint in
 * texture space. Levels are stored in the image's own format, as pbrt-v4 stores them. */
#ifndef CST_TEXTURES_MIPMAP_H
#define CST_TEXTURES_MIPMAP_H

#include "textures/texture.h"

/* Builds levels 1.. of im from level 0: each level halves the previous one's size (rounded
 * up, down to 1 x 1) with an area-weighted box filter in linear values, so every level has
 * the mean of level 0 (up to re-quantisation to the image's format). pbrt-v4 first resamples
 * a non-power-of-two image up to a power of two with a windowed sinc; caustic filters the
 * odd sizes directly. Returns CST_ERR_OOM with err set on failure (im unchanged). */
CstStatus mipmap_build(TexImage *im, CstError *err);

/* Texel (x, y) of `level` decoded to linear RGB; x and y are wrapped (any int). */
Color mipmap_texel(const TexImage *im, int level, int x, int y, TextureWrap wrap);

/* Bilinear interpolation between the four texel centres around st on `level`; t = 0 is the
 * bottom row. Level 0's lookups are bit-identical to caustic's historical bilinear. */
Color mipmap_bilerp(const TexImage *im, int level, TextureWrap wrap, Vec2 st);

/* pbrt-v4's float image textures (MIPMap::Bilerp<Float>, mipmap.cpp): bilinear on `level`
 * of channel 0 of a grey image, of each of R, G, B then their mean for an RGB image, of
 * alpha for an image that kept it (RGBA, alpha not all 1: TexImage.channels 4). */
float mipmap_bilerp_float(const TexImage *im, int level, TextureWrap wrap, Vec2 st);
/* pbrt-v4's MIPMap::Texel<Float>: channel 0 of texel (x, y) of `level` (wrapped), whatever
 * the channels (R of an RGB or RGBA image). */
float mipmap_texel_float(const TexImage *im, int level, int x, int y, TextureWrap wrap);
/* mipmap_bilerp_float at the centre of level-0 texel (x, y) (in range): the texel's own
 * value by that rule (a texture's average and max). */
float mipmap_centre_float(const TexImage *im, int x, int y);

/* The filtered value at st for a footprint with derivatives dst0 = (ds/dx, dt/dx) and
 * dst1 = (ds/dy, dt/dy) (pbrt-v4 MIPMap::Filter). filter is not TEXTURE_FILTER_NONE. */
Color mipmap_filter(const TexImage *im, TextureWrap wrap, TextureFilter filter, float max_aniso, Vec2 st,
                    Vec2 dst0, Vec2 dst1);
/* mipmap_filter of a float texture (pbrt-v4 MIPMap::Filter<Float>): each texel read alone
 * (point, EWA, the coarsest level of a footprint wider than the image) is
 * mipmap_texel_float, each interpolation (bilinear, trilinear, EWA without a footprint)
 * mipmap_bilerp_float. */
float mipmap_filter_float(const TexImage *im, TextureWrap wrap, TextureFilter filter, float max_aniso, Vec2 st,
                          Vec2 dst0, Vec2 dst1);

#endif
