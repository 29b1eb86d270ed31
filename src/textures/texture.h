/* Textures: an RGB value as a function of a surface's texture coordinates (u, v), for any
 * material colour or roughness and for area-light emission. A tagged union of constants,
 * checkerboards (of two other textures) and images (bilinear, repeat or clamp). Textures
 * live in the scene's array and refer to each other by index; evaluation allocates nothing.
 * Images: v = 0 is the bottom row (the OpenGL / OBJ convention assimp passes through), u = 0
 * the left column; texel centres sit at half-integer positions. Each texture may map the
 * coordinates it is given by (u, v) -> (su u + du, sv v + dv) first, as pbrt's UVMapping
 * does; a checkerboard passes the coordinates it was given, unmapped, to its two textures. */
#ifndef CST_TEXTURES_TEXTURE_H
#define CST_TEXTURES_TEXTURE_H

#include <stdbool.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"

typedef enum TextureType {
    TEXTURE_CONSTANT,
    TEXTURE_CHECKERBOARD,
    TEXTURE_IMAGE
} TextureType;

typedef enum TextureWrap {
    TEXTURE_WRAP_REPEAT, /* the image tiles the uv plane */
    TEXTURE_WRAP_CLAMP   /* uv outside [0, 1] sees the border texels */
} TextureWrap;

typedef struct TextureChecker {
    int even, odd; /* texture indices, both lower than this texture's own (no cycles) */
    float scale;   /* squares per unit of u and of v */
} TextureChecker;

typedef struct TextureImage {
    float *rgb; /* width * height * 3 linear floats, row 0 = top; owned */
    int width, height;
    TextureWrap wrap;
} TextureImage;

typedef struct Texture {
    TextureType type;
    Color average; /* mean over the uv plane (images: over their texels): light selection */
    Color max;     /* largest value of each channel: validation (an albedo must stay <= 1) */
    Vec2 uv_scale, uv_offset; /* (1, 1) and (0, 0) unless texture_set_uv_transform */
    union {
        Color value; /* constant */
        TextureChecker checker;
        TextureImage image;
    };
} Texture;

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
void texture_free(Texture *t);
/* After construction: evaluate t at (scale.x u + offset.x, scale.y v + offset.y). */
void texture_set_uv_transform(Texture *t, Vec2 scale, Vec2 offset);

/* The value at uv of texture id in textures. */
Color texture_eval(const Texture *textures, int id, Vec2 uv);
/* A scalar texture (roughness): the mean of the three channels. */
static inline float texture_eval_scalar(const Texture *textures, int id, Vec2 uv)
{
    Color c = texture_eval(textures, id, uv);
    return (c.c[0] + c.c[1] + c.c[2]) * (1.0f / 3.0f);
}

#endif
