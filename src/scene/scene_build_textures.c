/* The public scene builder's textures (cst_scene_add_texture, cst_scene_texture_info):
 * validates a CstTextureDesc and converts it to the scene's Texture, or back for info. */
#include <float.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

/* ------------------------------------------------------------------ textures */

static CstStatus check_ops(const CstTextureDesc *d, CstError *err)
{
    static const char fn[] = "cst_scene_add_texture";
    if (d->num_ops < 0 || d->num_ops > CST_TEXTURE_MAX_OPS)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d ops; expected 0 to %d", fn, d->num_ops, CST_TEXTURE_MAX_OPS);
    for (int i = 0; i < d->num_ops; i++) {
        const CstTextureOp *op = &d->ops[i];
        if (op->type < CST_TEXTURE_OP_AFFINE || op->type > CST_TEXTURE_OP_RED)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: ops[%d] has unknown type %d", fn, i, (int)op->type);
        for (int k = 0; k < 3; k++)
            if (!isfinite(op->a[k]) || !isfinite(op->b[k]))
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: ops[%d] has a value that is not finite", fn, i);
    }
    return CST_OK;
}

/* The description's value maps on t (checked by check_ops; at most TEXTURE_MAX_OPS). */
static void add_ops(const CstTextureDesc *d, Texture *t)
{
    static const TextureOpType types[] = {TEXTURE_OP_AFFINE, TEXTURE_OP_AFFINE, TEXTURE_OP_MIN1, TEXTURE_OP_POW,
                                          TEXTURE_OP_RED};
    for (int i = 0; i < d->num_ops; i++) {
        const CstTextureOp *op = &d->ops[i];
        texture_add_op(t, types[op->type], color_rgb(op->a[0], op->a[1], op->a[2]),
                       color_rgb(op->b[0], op->b[1], op->b[2]));
    }
}

/* The pixels of an image description: shared with a source texture, loaded or copied. */
static CstStatus image_pixels(Scene *s, const CstTextureDesc *d, TextureWrap wrap, Texture *t, CstError *err)
{
    static const char fn[] = "cst_scene_add_texture";
    if (d->source) {
        CstStatus st = check_texture_id(s, d->source, 0, fn, "source", err);
        if (st != CST_OK) return st;
        const Texture *src = &s->textures[d->source - 1];
        if (src->type != TEXTURE_IMAGE)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: source %d is not an image texture", fn, d->source);
        texture_share(t, src);
        t->num_ops = 0;
        t->uv_scale = v2(1.0f, 1.0f), t->uv_offset = v2(0.0f, 0.0f);
        t->image.wrap = wrap;
        t->image.filter = TEXTURE_FILTER_NONE;
        return CST_OK;
    }
    if (!d->path == !d->pixels)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: an image texture needs exactly one of path and pixels "
                        "(or a source)", fn);
    if (d->path) {
        TexelEncoding enc = d->linear ? TEXEL_LINEAR : TEXEL_SRGB;
        float gamma = 1.0f;
        switch (d->encoding) {
        case CST_TEXTURE_ENCODING_DEFAULT: break;
        case CST_TEXTURE_ENCODING_SRGB: enc = TEXEL_SRGB; break;
        case CST_TEXTURE_ENCODING_LINEAR: enc = TEXEL_LINEAR; break;
        case CST_TEXTURE_ENCODING_GAMMA:
            if (!(d->gamma > 0.0f && d->gamma <= 1e6f))
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: gamma %g; expected a number > 0", fn, (double)d->gamma);
            enc = TEXEL_GAMMA, gamma = d->gamma;
            break;
        default:
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown encoding %d; expected a CST_TEXTURE_ENCODING_*",
                            fn, (int)d->encoding);
        }
        return texture_image_load_encoded(t, d->path, enc, gamma, wrap, err);
    }
    if (d->width <= 0 || d->height <= 0 || d->width > 65536 || d->height > 65536)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: image of %d x %d pixels; expected 1 to 65536 on each side",
                        fn, d->width, d->height);
    size_t n = (size_t)d->width * (size_t)d->height * 3;
    float *rgb = malloc(n * sizeof *rgb);
    if (!rgb) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d image", fn, d->width, d->height);
    memcpy(rgb, d->pixels, n * sizeof *rgb);
    return texture_image(t, rgb, d->width, d->height, wrap, err); /* validates the pixels */
}

static CstStatus image_texture(Scene *s, const CstTextureDesc *d, Texture *t, CstError *err)
{
    static const char fn[] = "cst_scene_add_texture";
    TextureWrap wrap = d->wrap == CST_TEXTURE_WRAP_CLAMP ? TEXTURE_WRAP_CLAMP : TEXTURE_WRAP_REPEAT;
    if (d->wrap != CST_TEXTURE_WRAP_REPEAT && d->wrap != CST_TEXTURE_WRAP_CLAMP)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown wrap mode %d; expected CST_TEXTURE_WRAP_REPEAT "
                        "or CST_TEXTURE_WRAP_CLAMP", fn, (int)d->wrap);
    if ((unsigned)d->filter > (unsigned)CST_TEXTURE_FILTER_EWA)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown filter %d; expected a CST_TEXTURE_FILTER_*", fn,
                        (int)d->filter);
    if (!(d->max_anisotropy >= 0.0f && d->max_anisotropy <= 1e6f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: max_anisotropy %g; expected >= 1 (0 = 8)", fn,
                        (double)d->max_anisotropy);
    CstStatus st = check_ops(d, err);
    if (st != CST_OK) return st;
    if (d->pbrt_float != 0 && d->pbrt_float != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: pbrt_float %d; expected 0 or 1", fn, d->pbrt_float);
    if ((st = image_pixels(s, d, wrap, t, err)) != CST_OK) return st;
    texture_set_scalar(t, d->pbrt_float != 0); /* before the ops, which map its values */
    add_ops(d, t);
    static const TextureFilter filters[] = {TEXTURE_FILTER_NONE, TEXTURE_FILTER_POINT, TEXTURE_FILTER_BILINEAR,
                                            TEXTURE_FILTER_TRILINEAR, TEXTURE_FILTER_EWA};
    if ((st = texture_set_filter(t, filters[d->filter], d->max_anisotropy, err)) != CST_OK) {
        texture_free(t);
        return st;
    }
    return CST_OK;
}

/* The procedural and combining textures: operands checked (ids of textures already in the
 * scene, the ones each type needs), parameters defaulted and range-checked. */
static CstStatus procedural_texture(Scene *s, const CstTextureDesc *d, Texture *t, CstError *err)
{
    static const char fn[] = "cst_scene_add_texture";
    static const TextureType types[] = {TEXTURE_MIX, TEXTURE_DIRECTIONMIX, TEXTURE_SCALE, TEXTURE_BILERP,
                                        TEXTURE_CHECKER3D, TEXTURE_DOTS, TEXTURE_FBM, TEXTURE_WRINKLED,
                                        TEXTURE_WINDY, TEXTURE_MARBLE};
    TextureType type = types[d->type - CST_TEXTURE_MIX];
    bool two = d->type == CST_TEXTURE_MIX || d->type == CST_TEXTURE_DIRECTIONMIX || d->type == CST_TEXTURE_DOTS ||
               d->type == CST_TEXTURE_CHECKERBOARD_3D;
    CstStatus st;
    TextureProc pr;
    memset(&pr, 0, sizeof pr);
    pr.tex1 = pr.tex2 = pr.amount = -1;
    if (two || d->type == CST_TEXTURE_SCALE) {
        if ((st = check_texture_id(s, d->tex1, 0, fn, "tex1", err)) != CST_OK) return st;
        pr.tex1 = d->tex1 - 1;
    }
    if (two) {
        if ((st = check_texture_id(s, d->tex2, 0, fn, "tex2", err)) != CST_OK) return st;
        pr.tex2 = d->tex2 - 1;
    }
    if (d->type == CST_TEXTURE_SCALE || (d->type == CST_TEXTURE_MIX && d->amount)) {
        if ((st = check_texture_id(s, d->amount, 0, fn, "amount", err)) != CST_OK) return st;
        pr.amount = d->amount - 1;
    }
    if (!isfinite(d->amount_value))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: amount_value is not finite", fn);
    pr.amount_value = d->amount_value;
    if (d->type == CST_TEXTURE_DIRECTIONMIX) {
        Vec3 dir = v3(d->dir[0], d->dir[1], d->dir[2]);
        float len = v3_length(dir);
        if (!(len > 0.0f) || !isfinite(len))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: dir (%g, %g, %g); expected a nonzero finite direction", fn,
                            (double)d->dir[0], (double)d->dir[1], (double)d->dir[2]);
        pr.dir = v3_scale(dir, 1.0f / len);
    }
    for (int i = 0; i < 12; i++) {
        if (!isfinite(d->texture_from_world[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: texture_from_world has a value that is not finite", fn);
        pr.xf[i] = d->texture_from_world[i];
    }
    for (int i = 0; i < 4; i++)
        if ((st = read_rgb(d->corners[i], 0, fn, "corners", &pr.corner[i], err)) != CST_OK) return st;
    pr.octaves = d->octaves ? d->octaves : 8;
    pr.omega = d->roughness != 0.0f ? d->roughness : 0.5f;
    pr.scale = d->noise_scale != 0.0f ? d->noise_scale : 1.0f;
    pr.variation = d->variation != 0.0f ? d->variation : 0.2f;
    if (pr.octaves < 1 || pr.octaves > 32 || !(pr.omega > 0.0f && pr.omega < 1e3f) || !isfinite(pr.scale) ||
        !isfinite(pr.variation))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: octaves %d (expected 1 to 32), roughness %g (expected > 0), "
                        "noise_scale %g, variation %g (expected finite)", fn, pr.octaves, (double)pr.omega,
                        (double)pr.scale, (double)pr.variation);
    if ((st = check_ops(d, err)) != CST_OK) return st;
    if (!texture_procedural(t, type, &pr, s->textures))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: textures nested more than %d deep", fn, TEXTURE_MAX_DEPTH);
    add_ops(d, t);
    return CST_OK;
}

/* The description's mapping onto t (after its uv transform: planar replaces it). */
static CstStatus texture_mapping(const CstTextureDesc *d, const char *fn, Texture *t, CstError *err)
{
    if (d->mapping == CST_TEXTURE_MAPPING_UV) {
        t->mapping = TEXTURE_MAP_UV;
        return CST_OK;
    }
    if ((unsigned)d->mapping > CST_TEXTURE_MAPPING_PLANAR)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mapping %d; expected CST_TEXTURE_MAPPING_UV, _SPHERICAL, "
                        "_CYLINDRICAL or _PLANAR", fn, (int)d->mapping);
    for (int i = 0; i < 12; i++)
        if (!isfinite(d->mapping_from_world[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mapping_from_world[%d] is not finite", fn, i);
    Vec3 vs = v3(d->planar_v1[0], d->planar_v1[1], d->planar_v1[2]);
    Vec3 vt = v3(d->planar_v2[0], d->planar_v2[1], d->planar_v2[2]);
    if (!v3_is_finite(vs) || !v3_is_finite(vt))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: planar_v1 or planar_v2 is not finite", fn);
    if (v3_length2(vs) == 0.0f && v3_length2(vt) == 0.0f) vs = v3(1.0f, 0.0f, 0.0f), vt = v3(0.0f, 1.0f, 0.0f);
    texture_set_mapping(t, (TextureMapping)d->mapping, d->mapping_from_world, vs, vt,
                        v2(d->uv_offset[0], d->uv_offset[1]));
    return CST_OK;
}

CstStatus cst_scene_add_texture(CstScene *scene, const CstTextureDesc *d, int *out_id, CstError *err)
{
    static const char fn[] = "cst_scene_add_texture";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d || !out_id) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc and out_id must not be NULL", fn);
    float su = d->uv_scale[0], sv = d->uv_scale[1];
    if (su == 0.0f && sv == 0.0f) su = sv = 1.0f;
    if (!isfinite(su) || !isfinite(sv) || !isfinite(d->uv_offset[0]) || !isfinite(d->uv_offset[1]))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: uv_scale (%g, %g) or uv_offset (%g, %g) is not finite",
                        fn, (double)su, (double)sv, (double)d->uv_offset[0], (double)d->uv_offset[1]);
    Texture t;
    switch (d->type) {
    case CST_TEXTURE_CONSTANT: {
        Color c;
        if ((st = read_rgb(d->value, 0, fn, "value", &c, err)) != CST_OK) return st;
        texture_constant(&t, c);
        break;
    }
    case CST_TEXTURE_CHECKERBOARD: {
        float scale = d->scale == 0.0f ? 1.0f : d->scale;
        if (!(scale > 0.0f && scale <= FLT_MAX))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scale %g; expected squares per unit of u and v, > 0",
                            fn, (double)d->scale);
        if ((st = check_texture_id(scene, d->even, 0, fn, "even", err)) != CST_OK ||
            (st = check_texture_id(scene, d->odd, 0, fn, "odd", err)) != CST_OK)
            return st;
        texture_checkerboard(&t, scene->textures, d->even - 1, d->odd - 1, scale);
        break;
    }
    case CST_TEXTURE_IMAGE:
        if ((st = image_texture(scene, d, &t, err)) != CST_OK) return st;
        break;
    case CST_TEXTURE_MIX: case CST_TEXTURE_DIRECTIONMIX: case CST_TEXTURE_SCALE: case CST_TEXTURE_BILERP:
    case CST_TEXTURE_CHECKERBOARD_3D: case CST_TEXTURE_DOTS: case CST_TEXTURE_FBM: case CST_TEXTURE_WRINKLED:
    case CST_TEXTURE_WINDY: case CST_TEXTURE_MARBLE:
        if ((st = procedural_texture(scene, d, &t, err)) != CST_OK) return st;
        break;
    default:
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown texture type %d; expected CST_TEXTURE_CONSTANT, "
                        "_CHECKERBOARD or _IMAGE", fn, (int)d->type);
    }
    if (su != 1.0f || sv != 1.0f || d->uv_offset[0] != 0.0f || d->uv_offset[1] != 0.0f)
        texture_set_uv_transform(&t, v2(su, sv), v2(d->uv_offset[0], d->uv_offset[1]));
    if ((st = texture_mapping(d, fn, &t, err)) != CST_OK) {
        texture_free(&t);
        return st;
    }
    int id = 0;
    if ((st = scene_add_texture(scene, &t, &id, err)) != CST_OK) return st;
    *out_id = id + 1;
    return CST_OK;
}

static void color_floats(Color c, float out[3])
{
    for (int k = 0; k < 3; k++) out[k] = color_channel(c, k);
}

static void info_ops(const Texture *t, CstTextureDesc *d)
{
    static const CstTextureOpType types[] = {CST_TEXTURE_OP_AFFINE, CST_TEXTURE_OP_MIN1, CST_TEXTURE_OP_POW,
                                             CST_TEXTURE_OP_RED};
    d->num_ops = t->num_ops;
    for (int i = 0; i < t->num_ops; i++) {
        d->ops[i].type = types[t->ops[i].type];
        color_floats(t->ops[i].a, d->ops[i].a);
        color_floats(t->ops[i].b, d->ops[i].b);
    }
}

CstStatus cst_scene_texture_info(const CstScene *scene, int id, CstTextureInfo *info, CstError *err)
{
    static const char fn[] = "cst_scene_texture_info";
    cst_error_clear(err);
    if (!scene || !info) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene and info must not be NULL", fn);
    CstStatus st = check_texture_id(scene, id, 0, fn, "id", err);
    if (st != CST_OK) return st;
    const Texture *t = &scene->textures[id - 1];
    memset(info, 0, sizeof *info);
    CstTextureDesc *d = &info->desc;
    switch (t->type) {
    case TEXTURE_CONSTANT:
        d->type = CST_TEXTURE_CONSTANT;
        color_floats(t->value, d->value);
        break;
    case TEXTURE_CHECKERBOARD:
        d->type = CST_TEXTURE_CHECKERBOARD;
        d->even = t->checker.even + 1;
        d->odd = t->checker.odd + 1;
        d->scale = t->checker.scale;
        break;
    case TEXTURE_MIX: case TEXTURE_DIRECTIONMIX: case TEXTURE_SCALE: case TEXTURE_BILERP: case TEXTURE_CHECKER3D:
    case TEXTURE_DOTS: case TEXTURE_FBM: case TEXTURE_WRINKLED: case TEXTURE_WINDY: case TEXTURE_MARBLE: {
        static const CstTextureType types[] = {CST_TEXTURE_MIX, CST_TEXTURE_DIRECTIONMIX, CST_TEXTURE_SCALE,
                                               CST_TEXTURE_BILERP, CST_TEXTURE_CHECKERBOARD_3D, CST_TEXTURE_DOTS,
                                               CST_TEXTURE_FBM, CST_TEXTURE_WRINKLED, CST_TEXTURE_WINDY,
                                               CST_TEXTURE_MARBLE};
        const TextureProc *pr = &t->proc;
        d->type = types[t->type - TEXTURE_MIX];
        d->tex1 = pr->tex1 + 1, d->tex2 = pr->tex2 + 1, d->amount = pr->amount + 1;
        d->amount_value = pr->amount_value;
        d->dir[0] = pr->dir.x, d->dir[1] = pr->dir.y, d->dir[2] = pr->dir.z;
        memcpy(d->texture_from_world, pr->xf, sizeof pr->xf);
        d->octaves = pr->octaves, d->roughness = pr->omega, d->noise_scale = pr->scale, d->variation = pr->variation;
        for (int i = 0; i < 4; i++) color_floats(pr->corner[i], d->corners[i]);
        info_ops(t, d);
        break;
    }
    case TEXTURE_IMAGE:
        d->type = CST_TEXTURE_IMAGE;
        /* Images stored as 3-channel floats only (files keep their compact formats). */
        d->pixels = t->image.im->format == TEXEL_F32 && t->image.im->channels == 3
                        ? (const float *)t->image.im->level[0].texels : NULL;
        d->source = id;
        d->filter = (CstTextureFilter)t->image.filter; /* the enums agree */
        d->max_anisotropy = t->image.max_aniso;
        d->pbrt_float = t->image.scalar;
        info_ops(t, d);
        d->width = t->image.width;
        d->height = t->image.height;
        d->wrap = t->image.wrap == TEXTURE_WRAP_CLAMP ? CST_TEXTURE_WRAP_CLAMP : CST_TEXTURE_WRAP_REPEAT;
        break;
    }
    d->uv_scale[0] = t->uv_scale.x, d->uv_scale[1] = t->uv_scale.y;
    d->uv_offset[0] = t->uv_offset.x, d->uv_offset[1] = t->uv_offset.y;
    d->mapping = (CstTextureMapping)t->mapping; /* the enums agree */
    if (t->mapping != TEXTURE_MAP_UV) {
        memcpy(d->mapping_from_world, t->map_xf, sizeof d->mapping_from_world);
        d->planar_v1[0] = t->map_vs.x, d->planar_v1[1] = t->map_vs.y, d->planar_v1[2] = t->map_vs.z;
        d->planar_v2[0] = t->map_vt.x, d->planar_v2[1] = t->map_vt.y, d->planar_v2[2] = t->map_vt.z;
    }
    color_floats(t->average, info->average);
    color_floats(t->max, info->max);
    return CST_OK;
}

CstStatus scene_build_alpha(Scene *s, const CstAlpha *a, const char *fn, int *out, CstError *err)
{
    *out = 0;
    if (!a || !a->enabled) return CST_OK;
    if (a->enabled != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: alpha.enabled %d; expected 0 or 1", fn, a->enabled);
    CstStatus st = check_texture_id(s, a->texture, 1, fn, "alpha texture", err);
    if (st != CST_OK) return st;
    if (!a->texture && !(a->value >= 0.0f && a->value <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: alpha %g; expected a value from 0 to 1", fn, (double)a->value);
    if (!a->texture && a->value == 1.0f) return CST_OK;
    return scene_add_alpha(s, a->texture ? 1.0f : a->value, a->texture, out, err);
}

CstStatus scene_build_triangle_alphas(Scene *s, const CstMeshDesc *d, const char *fn, int **out, CstError *err)
{
    *out = NULL;
    if (!d->triangle_alphas) return CST_OK;
    int *ids = malloc((size_t)d->num_triangles * sizeof *ids);
    if (!ids) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for %d triangles' cut-outs", fn, d->num_triangles);
    for (int t = 0; t < d->num_triangles; t++) {
        const CstAlpha *a = &d->triangle_alphas[t], *prev = t > 0 ? &d->triangle_alphas[t - 1] : NULL;
        if (prev && a->enabled == prev->enabled && a->texture == prev->texture &&
            (a->value == prev->value || !a->enabled)) {
            ids[t] = ids[t - 1]; /* one id per run: a leaf mesh's cut-out is stored once */
            continue;
        }
        char what[96];
        snprintf(what, sizeof what, "%s (triangle_alphas[%d])", fn, t);
        CstStatus st = scene_build_alpha(s, a, what, &ids[t], err);
        if (st != CST_OK) {
            free(ids);
            return st;
        }
    }
    *out = ids;
    return CST_OK;
}
