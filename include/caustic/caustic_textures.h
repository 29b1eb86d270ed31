/* Part of caustic's public API, included by caustic/caustic.h (include that, not this):
 * textures (constants, procedural, images; their mappings and operators),
 * cst_scene_add_texture and cst_scene_texture_info. Kept apart only to keep each header
 * readable. */
#ifndef CAUSTIC_CAUSTIC_TEXTURES_H
#define CAUSTIC_CAUSTIC_TEXTURES_H

#ifndef CAUSTIC_CAUSTIC_H
#error "include caustic/caustic.h, which includes this header"
#endif

typedef enum CstTextureType {
    CST_TEXTURE_CONSTANT = 1, /* one RGB value */
    CST_TEXTURE_CHECKERBOARD, /* squares alternating between two other textures */
    CST_TEXTURE_IMAGE,        /* an image file or caller's pixels, bilinear */
    /* pbrt-v4's procedural and combining textures (tex1, tex2, amount: texture ids): */
    CST_TEXTURE_MIX,          /* (1 - a) tex1 + a tex2, a = amount's channel mean or amount_value */
    CST_TEXTURE_DIRECTIONMIX, /* |n . dir| tex1 + (1 - |n . dir|) tex2, n the geometric normal */
    CST_TEXTURE_SCALE,        /* tex1 times the channel mean of texture amount */
    CST_TEXTURE_BILERP,       /* corners[0..3] = v00, v01, v10, v11 bilinear over (u, v) */
    CST_TEXTURE_CHECKERBOARD_3D, /* tex1 where floor(x)+floor(y)+floor(z) of the mapped point is even */
    CST_TEXTURE_DOTS,         /* tex1 inside pbrt's noise-placed dots, tex2 outside, over (u, v) */
    CST_TEXTURE_FBM,          /* fBm of Perlin noise at the mapped point (octaves, roughness) */
    CST_TEXTURE_WRINKLED,     /* turbulence (octaves, roughness) */
    CST_TEXTURE_WINDY,        /* pbrt's waves */
    CST_TEXTURE_MARBLE        /* pbrt's marble (octaves, roughness, noise_scale, variation) */
} CstTextureType;

typedef enum CstTextureWrap {
    CST_TEXTURE_WRAP_REPEAT = 0, /* the image tiles the uv plane */
    CST_TEXTURE_WRAP_CLAMP       /* uv outside [0, 1] sees the border texels */
} CstTextureWrap;

/* An image's filter (pbrt-v4's): none = bilinear on the full image without a MIP map
 * (the default); the others build a MIP map and filter over each hit's footprint. */
typedef enum CstTextureFilter {
    CST_TEXTURE_FILTER_NONE = 0,
    CST_TEXTURE_FILTER_POINT,
    CST_TEXTURE_FILTER_BILINEAR,
    CST_TEXTURE_FILTER_TRILINEAR,
    CST_TEXTURE_FILTER_EWA
} CstTextureFilter;

/* How an image file's 8- and 16-bit values encode linear ones. */
typedef enum CstTextureEncoding {
    CST_TEXTURE_ENCODING_DEFAULT = 0, /* sRGB, or linear when `linear` is set */
    CST_TEXTURE_ENCODING_SRGB,
    CST_TEXTURE_ENCODING_LINEAR,
    CST_TEXTURE_ENCODING_GAMMA /* (code / max)^gamma */
} CstTextureEncoding;

/* A map of an image texture's values after its lookup, applied in order. */
typedef enum CstTextureOpType {
    CST_TEXTURE_OP_AFFINE = 1, /* max(0, a v + b) per channel */
    CST_TEXTURE_OP_MIN1,       /* min(v, 1) */
    CST_TEXTURE_OP_POW,        /* max(v, 0)^a[0] */
    CST_TEXTURE_OP_RED         /* the first channel in all three */
} CstTextureOpType;

typedef struct CstTextureOp {
    CstTextureOpType type;
    float a[3], b[3];
} CstTextureOp;

#define CST_TEXTURE_MAX_OPS 6

/* Zero-initialise, then set the type and its fields. Images: v = 0 is the bottom row,
 * u = 0 the left column (OBJ and glTF meshes' convention). */
/* Where a 2D texture's (s, t) come from (pbrt-v4's TextureMapping2D). */
typedef enum CstTextureMapping {
    CST_TEXTURE_MAPPING_UV = 0,    /* the surface's (u, v), through uv_scale and uv_offset */
    CST_TEXTURE_MAPPING_SPHERICAL, /* p' = mapping_from_world p: s = theta / pi (from +z),
                                    * t = phi / 2pi, phi = atan2(y, x) in [0, 2pi) */
    CST_TEXTURE_MAPPING_CYLINDRICAL, /* s = (pi + atan2(y', x')) / 2pi, t = z' */
    CST_TEXTURE_MAPPING_PLANAR     /* s = uv_offset[0] + p'.planar_v1, t = uv_offset[1] + p'.planar_v2 */
} CstTextureMapping;

typedef struct CstTextureDesc {
    CstTextureType type;
    float value[3];       /* constant: linear RGB, >= 0 */
    int even, odd;        /* checkerboard: ids of textures already in the scene */
    float scale;          /* checkerboard: squares per unit of u and v, > 0 (0 = 1) */
    const char *path;     /* image: PNG, JPEG, BMP, TGA, HDR, EXR or PFM file, or NULL and */
    const float *pixels;  /* image: width * height * 3 linear floats, row 0 = top (copied) */
    int width, height;    /* image: the size of `pixels` */
    int linear;           /* image file: 1 = 8/16-bit values are data (roughness maps), not sRGB */
    CstTextureWrap wrap;  /* image */
    /* image: 1 + an image texture already in the scene whose pixels (and MIP map) this one
     * shares, taking precedence over path and pixels; 0 = none */
    int source;
    CstTextureEncoding encoding; /* image file */
    float gamma;                 /* CST_TEXTURE_ENCODING_GAMMA: > 0 */
    CstTextureFilter filter;     /* image */
    float max_anisotropy;        /* CST_TEXTURE_FILTER_EWA: 0 = 8 */
    int num_ops;                 /* image: value maps (ops) after the lookup */
    CstTextureOp ops[CST_TEXTURE_MAX_OPS];
    int tex1, tex2, amount;      /* procedural: ids of operand textures (0 = none) */
    float amount_value;          /* mix without an amount texture */
    float dir[3];                /* directionmix: world-space direction (normalised here) */
    /* Solid textures (checkerboard 3D, fbm, wrinkled, windy, marble): the texture-space
     * point is texture_from_world times the world point (row-major 3 x 4; all 0 = identity). */
    float texture_from_world[12];
    int octaves;                 /* noise: 0 = 8 */
    float roughness;             /* noise: the octaves' weight ratio (pbrt's omega); 0 = 0.5 */
    float noise_scale, variation; /* marble: 0 = 1 and 0 = 0.2 */
    float corners[4][3];         /* bilerp */
    /* Every type: evaluate at (uv_scale u + uv_offset[0], uv_scale v + uv_offset[1]);
     * uv_scale {0, 0} = {1, 1}. */
    float uv_scale[2], uv_offset[2];
    /* Images, checkerboards, bilerp and dots: how (s, t) are made (0 = uv); the other
     * mappings take the hit point through mapping_from_world (row-major 3 x 4; all 0 =
     * identity; pbrt-v4: the inverse of the CTM where the texture is defined). */
    CstTextureMapping mapping;
    float mapping_from_world[12];
    float planar_v1[3], planar_v2[3]; /* planar: both all 0 = (1, 0, 0) and (0, 1, 0) */
    /* image: how a lookup becomes a value, before the ops. 0 = RGB (a grey image's value in
     * all three channels; an image file's alpha is not read). 1 = pbrt-v4's float image
     * texture, one value in all three channels (pbrt-v4 MIPMap::Filter<Float>): every
     * interpolated lookup (filters none, bilinear, trilinear) gives a grey image's value,
     * an RGB image's mean of R, G and B, an RGBA PNG's alpha (if not all 1; 8-bit alpha
     * decoded by the encoding, as pbrt-v4 does); single-texel lookups (point, EWA, a
     * footprint wider than the image) give the first channel (R) whatever the image. */
    int pbrt_float;
} CstTextureDesc;

/* *out_id (>= 1) names the texture in later descriptions. */
CST_API CstStatus cst_scene_add_texture(CstScene *scene, const CstTextureDesc *desc, int *out_id,
                                CstError *err);

/* What the scene holds for a texture, so that a caller (a loader deriving one texture from
 * another: pbrt's scale, clamps and roughness remapping) can read it back. */
typedef struct CstTextureInfo {
    /* The description that adds this texture again: type, value, even/odd, scale, wrap and
     * the uv transform as stored; for an image given as floats, pixels points to the scene's
     * own copy (width * height * 3 floats, valid until cst_scene_destroy); an image read
     * from a file keeps the file's compact storage (8-bit, 16-bit, grey), and pixels is
     * NULL; path is NULL; source is the texture's own id, so the description shares the
     * pixels when added again. */
    CstTextureDesc desc;
    float average[3]; /* mean over the uv plane (an image: over its texels) */
    float max[3];     /* largest value of each channel */
} CstTextureInfo;

/* Fills *info for texture `id` (>= 1); also after cst_scene_commit. */
CST_API CstStatus cst_scene_texture_info(const CstScene *scene, int id, CstTextureInfo *info,
                                         CstError *err);

#endif
