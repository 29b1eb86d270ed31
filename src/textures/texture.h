/* Textures: an RGB value as a function of a surface's texture coordinates (u, v), for any
 * material colour or roughness and for area-light emission. A tagged union of constants,
 * checkerboards (of two other textures) and images. Textures live in the scene's array and
 * refer to each other by index; evaluation allocates nothing.
 * Images keep their file's storage (8-bit texels decoded through a 256-entry table at
 * lookup, 16-bit ones decoded at lookup, floats as floats; grey images one channel, RGBA
 * PNGs with some alpha below 1 four) and are
 * shared, reference-counted, between the textures that derive from one file (a scaled copy
 * is a new Texture with one more value op, not a new image). They may carry a MIP pyramid
 * (textures/mipmap.h) filtered as pbrt-v4's MIPMap: point, bilinear, trilinear or EWA.
 * Images: v = 0 is the bottom row (the OpenGL / OBJ convention assimp passes through), u = 0
 * the left column; texel centres sit at half-integer positions. Each texture may map the
 * coordinates it is given by (u, v) -> (su u + du, sv v + dv) first, as pbrt's UVMapping
 * does; a checkerboard passes the coordinates it was given, unmapped, to its two textures. */
#ifndef CST_TEXTURES_TEXTURE_H
#define CST_TEXTURES_TEXTURE_H

#include <stdbool.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"

typedef enum TextureType {
    TEXTURE_CONSTANT,
    TEXTURE_CHECKERBOARD,
    TEXTURE_IMAGE,
    /* pbrt-v4's procedural and combining textures (TextureProc): */
    TEXTURE_MIX,          /* (1 - amount) tex1 + amount tex2 */
    TEXTURE_DIRECTIONMIX, /* |n . dir| tex1 + (1 - |n . dir|) tex2 */
    TEXTURE_SCALE,        /* tex1 times the scalar texture `amount` */
    TEXTURE_BILERP,       /* bilinear between four corner values over (s, t) */
    TEXTURE_CHECKER3D,    /* tex1 where floor(x) + floor(y) + floor(z) is even, else tex2 */
    TEXTURE_DOTS,         /* tex1 in randomly placed dots of radius 0.35 per unit cell, else tex2 */
    TEXTURE_FBM,          /* fractional Brownian motion of Perlin noise */
    TEXTURE_WRINKLED,     /* turbulence */
    TEXTURE_WINDY,        /* |fbm(0.1 p, 3 octaves)| fbm(p, 6 octaves): waves */
    TEXTURE_MARBLE        /* a colour spline at sin(y + variation fbm) */
} TextureType;

/* The most textures nested in one (a mix of mixes ...): evaluation recurses that deep. */
#define TEXTURE_MAX_DEPTH 64

typedef enum TextureWrap {
    TEXTURE_WRAP_REPEAT, /* the image tiles the uv plane */
    TEXTURE_WRAP_CLAMP   /* uv outside [0, 1] sees the border texels */
} TextureWrap;

/* How an image texture turns a footprint into a value (pbrt-v4's FilterFunction, plus
 * caustic's historical default). */
typedef enum TextureFilter {
    TEXTURE_FILTER_NONE,      /* bilinear on the full-resolution image, footprint ignored */
    TEXTURE_FILTER_POINT,     /* nearest texel of the MIP level the footprint selects */
    TEXTURE_FILTER_BILINEAR,  /* bilinear on that level (pbrt-v4's default) */
    TEXTURE_FILTER_TRILINEAR, /* bilinear on the two levels around it, blended */
    TEXTURE_FILTER_EWA        /* Heckbert's elliptical weighted average (Heckbert 1989) */
} TextureFilter;

/* How integer texels encode linear values. */
typedef enum TexelEncoding {
    TEXEL_LINEAR, /* code / max */
    TEXEL_SRGB,   /* the sRGB curve (IEC 61966-2-1) */
    TEXEL_GAMMA   /* (code / max)^gamma: pbrt-v4's "gamma g" encoding */
} TexelEncoding;

typedef enum TexelFormat {
    TEXEL_U8,  /* bytes, decoded through TexImage.lut */
    TEXEL_U16, /* 16-bit codes, decoded at lookup */
    TEXEL_F32, /* linear floats */
    TEXEL_F16  /* linear IEEE halves (math/half.h): half-float EXR files, as pbrt-v4 keeps them */
} TexelFormat;

/* Bytes per stored value. */
static inline size_t texel_format_size(TexelFormat f)
{
    return f == TEXEL_U8 ? 1 : f == TEXEL_U16 || f == TEXEL_F16 ? 2 : 4;
}

#define TEXTURE_MAX_LEVELS 32

typedef struct TexLevel {
    int width, height;
    void *texels; /* width * height * channels values of the image's format, row 0 = top */
} TexLevel;

/* Pixel storage shared by the textures made from one image. */
typedef struct TexImage {
    int refs; /* textures holding it; freed by the last texture_free (scene build is single-threaded) */
    TexelFormat format;
    int channels; /* 1 (grey: the value in all three channels of a lookup), 3 (RGB) or 4 (RGBA,
                   * from an RGBA PNG or EXR whose alpha is not all 1; RGB lookups ignore alpha) */
    TexelEncoding encoding;
    float gamma;    /* TEXEL_GAMMA */
    float lut[256]; /* TEXEL_U8: the linear value of each code */
    int num_levels; /* 1 until texture_set_filter builds the pyramid */
    TexLevel level[TEXTURE_MAX_LEVELS];
} TexImage;

typedef struct TextureChecker {
    int even, odd; /* texture indices, both lower than this texture's own (no cycles) */
    float scale;   /* squares per unit of u and of v */
} TextureChecker;

/* The procedural and combining textures' parameters. Child textures are indices lower
 * than the texture's own, -1 for none. Solid textures (checker3d, noise, marble) take
 * p through texture_from_world (pbrt-v4: the inverse of the CTM at the definition). */
typedef struct TextureProc {
    int tex1, tex2;
    int amount;         /* mix: a scalar texture, or -1 for amount_value; scale: the factor */
    float amount_value;
    Vec3 dir;           /* directionmix: unit, world space */
    float xf[12];       /* texture_from_world, row-major 3 x 4 */
    int octaves;
    float omega, scale, variation; /* noise: roughness (omega); marble: scale, variation */
    Color corner[4];    /* bilerp: v00, v01, v10, v11 */
} TextureProc;

typedef struct TextureImage {
    TexImage *im; /* shared; see TexImage.refs */
    int width, height; /* of level 0 */
    TextureWrap wrap;
    TextureFilter filter;
    float max_aniso; /* EWA: the longest ellipse axis over the shortest (pbrt-v4's maxanisotropy) */
    bool scalar;     /* pbrt-v4's float image texture: one value by its channel rule
                      * (mipmap_filter_float), in all three channels */
} TextureImage;

/* A map applied to a texture's value after its lookup and filtering, in the order added
 * (pbrt-v4 applies its scale, invert and its materials' clamps after the MIP filter). */
typedef enum TextureOpType {
    TEXTURE_OP_AFFINE, /* max(0, a v + b) per channel */
    TEXTURE_OP_MIN1,   /* min(v, 1) */
    TEXTURE_OP_POW,    /* max(v, 0)^a.c[0] */
    TEXTURE_OP_RED     /* the first channel in all three (pbrt's float image textures) */
} TextureOpType;

#define TEXTURE_MAX_OPS 6

typedef struct TextureOp {
    TextureOpType type;
    Color a, b;
} TextureOp;

/* Where a 2D texture's (s, t) come from (pbrt-v4's TextureMapping2D, PBR 4th ed. sec.
 * 10.2.1-10.2.4): the surface's (u, v) scaled and offset, or the hit point p taken to
 * texture space by map_xf (pbrt-v4: the inverse of the CTM at the texture's definition)
 * and projected: spherical s = theta / pi, t = phi / 2pi (theta from +z, phi = atan2(y, x)
 * in [0, 2pi)); cylindrical s = (pi + atan2(y, x)) / 2pi, t = z; planar s = du + p.vs,
 * t = dv + p.vt. */
typedef enum TextureMapping {
    TEXTURE_MAP_UV = 0,
    TEXTURE_MAP_SPHERICAL,
    TEXTURE_MAP_CYLINDRICAL,
    TEXTURE_MAP_PLANAR
} TextureMapping;

typedef struct Texture {
    TextureType type;
    Color average; /* mean over the uv plane (images: over their texels): light selection */
    Color max;     /* largest value of each channel: validation (an albedo must stay <= 1) */
    Vec2 uv_scale, uv_offset; /* (1, 1) and (0, 0) unless texture_set_uv_transform */
    TextureMapping mapping;   /* TEXTURE_MAP_UV unless texture_set_mapping */
    float map_xf[12];         /* other mappings: texture_from_world, row-major 3 x 4 */
    Vec3 map_vs, map_vt;      /* planar: the s and t axes; (du, dv) is uv_offset */
    int num_ops; /* value maps (images and constants; never on checkerboards) */
    int depth;   /* 1 + the deepest child's depth; at most TEXTURE_MAX_DEPTH */
    TextureOp ops[TEXTURE_MAX_OPS];
    union {
        Color value; /* constant */
        TextureChecker checker;
        TextureImage image;
        TextureProc proc;
    };
} Texture;

/* Where a texture is looked up: texture coordinates and their screen-space derivatives
 * (pbrt-v4's TextureEvalContext, uv part). Zero derivatives ask for the finest level. */
typedef struct TexCtx {
    Vec2 uv;
    float dudx, dudy, dvdx, dvdy; /* per pixel step in x and y */
    Vec3 p, n;         /* world-space point and unit geometric normal (solid textures, directionmix) */
    Vec3 dpdx, dpdy;   /* change of p per pixel step (noise octaves); zero: all octaves */
} TexCtx;

void texture_constant(Texture *t, Color value);
/* even, odd: indices into textures (the array the texture will be added to). */
void texture_checkerboard(Texture *t, const Texture *textures, int even, int odd, float scale);
/* Takes ownership of rgb (width * height * 3 linear floats, row 0 = top), also on failure. */
CstStatus texture_image(Texture *t, float *rgb, int width, int height, TextureWrap wrap, CstError *err);
/* Loads an image file: PNG, JPEG, BMP, TGA and Radiance HDR through stb_image, OpenEXR and
 * PFM through image_read (io/image_io.c). 8- and 16-bit images are sRGB-encoded and
 * decoded to linear unless `linear` (data such as roughness maps); float images (HDR, EXR,
 * PFM) are linear already and taken as they are. */
CstStatus texture_image_load(Texture *t, const char *path, bool linear, TextureWrap wrap, CstError *err);
/* texture_image_load with any encoding of integer texels (gamma for TEXEL_GAMMA). */
CstStatus texture_image_load_encoded(Texture *t, const char *path, TexelEncoding enc, float gamma,
                                     TextureWrap wrap, CstError *err);
/* dst becomes a copy of image texture src sharing its pixels (one more reference). */
void texture_share(Texture *dst, const Texture *src);
/* A procedural or combining texture of type `type` (TEXTURE_MIX and after) with parameters
 * pr, whose child indices must be in textures (the array it will be added to); average
 * and max are estimated from the children's and the type's range. Identity xf when all
 * zero. False when the nesting would exceed TEXTURE_MAX_DEPTH. */
bool texture_procedural(Texture *t, TextureType type, const TextureProc *pr, const Texture *textures);
/* Appends a value map to an image, constant or procedural texture (constants fold it into
 * their value) and updates average and max (images: one pass over the level-0 texels;
 * procedural: the map of each). False when the texture is a checkerboard or already holds
 * TEXTURE_MAX_OPS maps. */
bool texture_add_op(Texture *t, TextureOpType type, Color a, Color b);
/* Chooses an image texture's filter, building the MIP pyramid (shared by every texture of
 * the image) for the filters that need one. max_aniso <= 0 means pbrt-v4's 8. */
CstStatus texture_set_filter(Texture *t, TextureFilter filter, float max_aniso, CstError *err);
/* Makes an image texture a pbrt-v4 float texture (TextureImage.scalar) or an RGB one again,
 * and recomputes its average and max; other types are left alone. Call before value maps
 * are added, which apply after the lookup. */
void texture_set_scalar(Texture *t, bool scalar);
/* Bytes of texel storage of an image texture's pixels (all levels); 0 for other types. */
size_t texture_image_bytes(const Texture *t);
void texture_free(Texture *t);
/* After construction: evaluate t at (scale.x u + offset.x, scale.y v + offset.y). */
void texture_set_uv_transform(Texture *t, Vec2 scale, Vec2 offset);
/* After construction: a spherical, cylindrical or planar mapping with texture_from_world
 * xf (row-major 3 x 4; NULL or all zero: the identity), planar axes vs, vt and offset
 * (du, dv) in uv_offset (planar only). TEXTURE_MAP_UV restores the uv mapping. */
void texture_set_mapping(Texture *t, TextureMapping m, const float *xf, Vec3 vs, Vec3 vt, Vec2 offset);
/* (s, t) of texture t at c, and their screen derivatives ds/dx, dt/dx (*d0) and ds/dy,
 * dt/dy (*d1) as pbrt-v4's mappings compute them (zero when c has none). */
Vec2 texture_map_st(const Texture *t, const TexCtx *c, Vec2 *d0, Vec2 *d1);

/* The raw (decoded, unmapped) texel (x, y) of level `level` of an image texture, y = 0 the
 * top row; indices wrap as the texture does. */
Color texture_texel(const Texture *t, int level, int x, int y);

/* The value of texture id in textures at ctx (its footprint chooses the MIP level). */
Color texture_eval_ctx(const Texture *textures, int id, const TexCtx *ctx);
/* The value at uv with no footprint: the finest level. */
static inline Color texture_eval(const Texture *textures, int id, Vec2 uv)
{
    TexCtx c = {.uv = uv};
    return texture_eval_ctx(textures, id, &c);
}
/* A scalar texture (roughness): the mean of the three channels. */
static inline float texture_eval_scalar(const Texture *textures, int id, Vec2 uv)
{
    Color c = texture_eval(textures, id, uv);
    return (c.c[0] + c.c[1] + c.c[2]) * (1.0f / 3.0f);
}
static inline float texture_eval_scalar_ctx(const Texture *textures, int id, const TexCtx *ctx)
{
    Color c = texture_eval_ctx(textures, id, ctx);
    return (c.c[0] + c.c[1] + c.c[2]) * (1.0f / 3.0f);
}
/* Whether any of the textures filters with a footprint (a MIP filter): hits then need
 * screen-space derivatives. */
bool texture_needs_footprint(const Texture *t);

#endif
