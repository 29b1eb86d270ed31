/* Texture directives (imagemap, checkerboard, scale, mix, ...) and texture references in
 * parameters, mapped onto the scene's textures. */
#ifndef CST_SCENE_PBRT_PBRT_TEXTURE_H
#define CST_SCENE_PBRT_PBRT_TEXTURE_H

#include "scene/pbrt/pbrt_loader.h"

/* A texture where caustic takes one value: its average, with a warning unless it is constant. */
CstStatus pbrt_texture_ref(Loader *ld, const Param *p, const char *d, int is_float, Color *out);

/* A float parameter that may also name a float texture. */
CstStatus pbrt_get_float_tex(Loader *ld, Params *ps, const char *d, const char *name, float def,
                             float *out, int *found);

/* Per-value maps that pbrt applies after its lookups: folded into constants, appended to an
 * image texture's value maps (applied after its lookup and filtering, as pbrt does, over
 * pixels shared with the unmapped texture), and applied to a checkerboard's two textures. */
typedef enum TexOp {
    TEXOP_AFFINE, /* max(0, a v + b): pbrt's scale, invert and ScaleTexture */
    TEXOP_MIN1,   /* min(v, 1): the reflectance clamp of pbrt's materials */
    TEXOP_POW     /* max(v, 0)^a.r: gamma decoding, roughness to caustic's roughness */
} TexOp;

/* A new scene texture: texture `id` with op applied to its values, or id itself when op
 * changes nothing. A checkerboard's textures are mapped too, each once however often it
 * is shared (nested checkerboards may share children), without recursion: children have
 * lower indices, so one downward pass marks what is reachable and one upward pass copies. */
CstStatus pbrt_tex_map(Loader *ld, int id, TexOp op, Color a, Color b, Loc loc, const char *d, int *out);

/* The scene texture for a "texture" parameter of a material (its albedo or roughness):
 * 0 when the file gives a value or names a constant texture (*val then holds it), else
 * 1 + the scene texture's index, as Material stores it. */
CstStatus pbrt_tex_param(Loader *ld, Params *ps, const char *d, const char *name, int is_float,
                         int *tex, Color *val, int *entry);

/* A material's shading-normal parameters (every pbrt-v4 material takes them): "texture
 * displacement" (a float texture; a constant displacement bends nothing) and "string
 * normalmap" (an image file read linear, as pbrt-v4 reads it), into m's texture slots. */
CstStatus pbrt_material_normal_textures(Loader *ld, Params *ps, const char *d, Material *m);

/* The scene's texture `id` (public id - 1, as TexEntry.id) read back through the builder. */
CstStatus pbrt_texture_info(Loader *ld, int id, CstTextureInfo *info);

/* Directive handler, called through the table in pbrt_scene.c. */
CstStatus pbrt_texture_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
