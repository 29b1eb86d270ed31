/* Texture directives (imagemap, checkerboard, scale, mix, ...) and texture references in
 * parameters, mapped onto the scene's textures. */
#include "scene/pbrt/pbrt_texture.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/image_io.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_spectrum.h"
#include "textures/texture.h"

static int find_texture(Loader *ld, const char *name, int is_float)
{
    for (int i = ld->num_texs - 1; i >= 0; i--)
        if (ld->texs[i].is_float == is_float && strcmp(ld->texs[i].name, name) == 0)
            return i;
    return -1;
}

/* The texture a "texture" parameter names, as an index into ld->texs; a located error if
 * there is none of that type (pbrt-v4 looks float and spectrum textures up apart, and
 * stops at a missing one). */
static CstStatus texture_find_ref(Loader *ld, const Param *p, const char *d, int is_float, int *out)
{
    char nm[72];
    TRY(pbrt_one_value(ld, p, d));
    int i = find_texture(ld, p->strs[0], is_float);
    if (i >= 0) {
        *out = i;
        return CST_OK;
    }
    if (find_texture(ld, p->strs[0], !is_float) >= 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                            "%s: texture \"%s\" is a %s texture; expected a %s texture here", d,
                            pbrt_clip(p->strs[0], nm), is_float ? "spectrum" : "float", is_float ? "float" : "spectrum");
    return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                   "%s: %s texture \"%s\" is not defined; expected the name of a Texture "
                        "declared earlier as \"%s\"", d, is_float ? "float" : "spectrum",
                        pbrt_clip(p->strs[0], nm), is_float ? "float" : "spectrum");
}

/* Constants live in the loader alone (TexEntry.id < 0) until a checkerboard needs one. */
static int texture_is_constant(const Loader *ld, int entry) { return ld->texs[entry].id < 0; }

CstStatus pbrt_texture_info(Loader *ld, int id, CstTextureInfo *info)
{
    return cst_scene_texture_info(ld->scene, id + 1, info, ld->err);
}

static Color color_of(const float v[3]) { return color_rgb(v[0], v[1], v[2]); }

/* A texture where caustic takes one value: its average, with a warning unless it is constant. */
CstStatus pbrt_texture_ref(Loader *ld, const Param *p, const char *d, int is_float, Color *out)
{
    int i = 0;
    char nm[72], nm2[72];
    TRY(texture_find_ref(ld, p, d, is_float, &i));
    *out = ld->texs[i].value;
    if (!texture_is_constant(ld, i))
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: \"%s\" cannot be textured in caustic; "
                     "texture \"%s\" is taken as its average (%g, %g, %g)", d, pbrt_clip(p->decl, nm),
                     pbrt_clip(p->strs[0], nm2), (double)out->c[0], (double)out->c[1], (double)out->c[2]);
    return CST_OK;
}

/* A float parameter that may also name a float texture. */
CstStatus pbrt_get_float_tex(Loader *ld, Params *ps, const char *d, const char *name, float def,
                             float *out, int *found)
{
    Param *p;
    *out = def;
    if (found) *found = 0;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_FLOAT) | PT_MASK(PT_TEXTURE), "float or texture", &p));
    if (!p) return CST_OK;
    if (p->type == PT_TEXTURE) {
        Color c;
        TRY(pbrt_texture_ref(ld, p, d, 1, &c));
        *out = c.c[0];
    } else {
        TRY(pbrt_one_value(ld, p, d));
        *out = (float)p->nums[0];
    }
    if (!isfinite(*out)) {
        char nm[72];
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" does not fit a 32-bit float", d,
                            pbrt_clip(p->decl, nm));
    }
    if (found) *found = 1;
    return CST_OK;
}

/* Adds desc to the scene (which copies any pixels), failures located at loc; *id is the
 * public id - 1. */
static CstStatus tex_add(Loader *ld, const CstTextureDesc *desc, Loc loc, const char *d, int *id)
{
    int pid = 0;
    CstStatus st = cst_scene_add_texture(ld->scene, desc, &pid, ld->err);
    if (st) return pbrt_fail_wrap(ld, st, loc, d);
    *id = pid - 1;
    return CST_OK;
}

/* A constant as a scene texture (a checkerboard's square). The builder takes values >= 0;
 * a negative float constant (nothing pbrt renders meaningfully) becomes 0. */
static CstStatus tex_const(Loader *ld, Color c, Loc loc, const char *d, int *id)
{
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_CONSTANT;
    pbrt_color_floats(c, t.value);
    if (t.value[0] < 0.0f || t.value[1] < 0.0f || t.value[2] < 0.0f) {
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: the negative value (%g, %g, %g) is clamped to 0",
                     d, (double)t.value[0], (double)t.value[1], (double)t.value[2]);
        for (int k = 0; k < 3; k++) t.value[k] = maxf(t.value[k], 0.0f);
    }
    return tex_add(ld, &t, loc, d, id);
}

static Color texop_apply(TexOp op, Color a, Color b, Color v)
{
    switch (op) {
    case TEXOP_AFFINE:
        return color_rgb(maxf(0.0f, a.c[0] * v.c[0] + b.c[0]), maxf(0.0f, a.c[1] * v.c[1] + b.c[1]), maxf(0.0f, a.c[2] * v.c[2] + b.c[2]));
    case TEXOP_MIN1: return color_rgb(minf(v.c[0], 1.0f), minf(v.c[1], 1.0f), minf(v.c[2], 1.0f));
    case TEXOP_POW:
        return color_rgb(powf(maxf(v.c[0], 0.0f), a.c[0]), powf(maxf(v.c[1], 0.0f), a.c[0]), powf(maxf(v.c[2], 0.0f), a.c[0]));
    }
    return v;
}

/* The builder's value map for a TexOp. */
static CstTextureOpType texop_type(TexOp op)
{
    switch (op) {
    case TEXOP_AFFINE: return CST_TEXTURE_OP_AFFINE;
    case TEXOP_MIN1: return CST_TEXTURE_OP_MIN1;
    case TEXOP_POW: return CST_TEXTURE_OP_POW;
    }
    return CST_TEXTURE_OP_AFFINE;
}

/* An image description with op appended to its value maps (the image's pixels are shared,
 * never copied). Two pure scales (b = 0, a >= 0) in a row fold into one, exactly, as image
 * values are >= 0. A located error when the chain is full. */
static CstStatus desc_append_op(Loader *ld, CstTextureDesc *t, TexOp op, Color a, Color b, Loc loc, const char *d)
{
    if (op == TEXOP_AFFINE && t->num_ops > 0 && color_is_black(b)) {
        CstTextureOp *last = &t->ops[t->num_ops - 1];
        int pure = last->type == CST_TEXTURE_OP_AFFINE;
        for (int k = 0; k < 3; k++) pure &= last->b[k] == 0.0f && last->a[k] >= 0.0f && a.c[k] >= 0.0f;
        if (pure) {
            for (int k = 0; k < 3; k++) last->a[k] *= a.c[k];
            return CST_OK;
        }
    }
    if (t->num_ops >= CST_TEXTURE_MAX_OPS)
        return pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: more than %d scales, clamps and remappings "
                            "applied to one image texture", d, CST_TEXTURE_MAX_OPS);
    CstTextureOp *o = &t->ops[t->num_ops++];
    o->type = texop_type(op);
    pbrt_color_floats(a, o->a);
    pbrt_color_floats(b, o->b);
    return CST_OK;
}

/* A new scene texture: texture `id` with op applied to its values, or id itself when op
 * changes nothing. Constants take the op in their value, images one more value map over
 * their shared pixels; a checkerboard's textures are mapped too, each once however often
 * it is shared (nested checkerboards may share children), without recursion: children have
 * lower indices, so one downward pass marks what is reachable and one upward pass copies. */
CstStatus pbrt_tex_map(Loader *ld, int id, TexOp op, Color a, Color b, Loc loc, const char *d, int *out)
{
    *out = id;
    /* Spectrum and image values are >= 0 already (get_spectrum, texture_image), so the
     * identity's max(0, v) could only change a negative float constant: left as it is. */
    if (op == TEXOP_AFFINE && a.c[0] == 1.0f && a.c[1] == 1.0f && a.c[2] == 1.0f && color_is_black(b)) return CST_OK;
    int n = id + 1, *memo = malloc((size_t)n * sizeof *memo);
    if (!memo) return pbrt_oom(ld);
    for (int i = 0; i < n; i++) memo[i] = -1;
    memo[id] = 0; /* reachable */
    CstStatus st = CST_OK;
    CstTextureInfo info;
    for (int i = id; i >= 0 && !st; i--) {
        if (memo[i] < 0 || (st = pbrt_texture_info(ld, i, &info))) continue;
        if (info.desc.type == CST_TEXTURE_CHECKERBOARD) memo[info.desc.even - 1] = memo[info.desc.odd - 1] = 0;
    }
    for (int i = 0; i < n && !st; i++) {
        if (memo[i] < 0 || (st = pbrt_texture_info(ld, i, &info))) continue;
        CstTextureDesc t = info.desc; /* uv transform, wrap, filter and the image's source as they are */
        if (t.type == CST_TEXTURE_CONSTANT) {
            pbrt_color_floats(texop_apply(op, a, b, color_of(t.value)), t.value);
        } else if (t.type == CST_TEXTURE_CHECKERBOARD) {
            t.even = memo[t.even - 1] + 1;
            t.odd = memo[t.odd - 1] + 1;
        } else if ((st = desc_append_op(ld, &t, op, a, b, loc, d))) {
            break;
        }
        st = tex_add(ld, &t, loc, d, &memo[i]);
    }
    if (!st) *out = memo[id];
    free(memo);
    return st;
}

/* The scene texture for a "texture" parameter of a material (its albedo or roughness):
 * 0 when the file gives a value or names a constant texture (*val then holds it), else
 * 1 + the scene texture's index, as Material stores it. */
CstStatus pbrt_tex_param(Loader *ld, Params *ps, const char *d, const char *name, int is_float,
                         int *tex, Color *val, int *entry)
{
    Param *p = pbrt_find_param(ps, name);
    *tex = 0;
    if (!p || p->type != PT_TEXTURE) return CST_OK;
    int i = 0;
    p->used = 1;
    TRY(texture_find_ref(ld, p, d, is_float, &i));
    *val = ld->texs[i].value;
    if (entry) *entry = i;
    if (!texture_is_constant(ld, i)) *tex = 1 + ld->texs[i].id;
    return CST_OK;
}

/* A 2D texture's mapping as pbrt-v4 reads it (TextureMapping2D::Create): "uv" with
 * "uscale", "vscale", "udelta", "vdelta" ((s, t) = (su u + du, sv v + dv)); "spherical" and
 * "cylindrical" through the inverse of the CTM at the definition; "planar" through it too,
 * with the axes "v1", "v2" and offsets "udelta", "vdelta". */
typedef struct TexMapping {
    CstTextureMapping type;
    Vec2 scale, offset;
    float xf[12]; /* texture_from_world; all 0 = identity */
    Vec3 v1, v2;
} TexMapping;

static CstStatus tex_vector3(Loader *ld, Params *ps, const char *d, const char *name, Vec3 def, Vec3 *out)
{
    Param *p;
    *out = def;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_VECTOR3), "vector3", &p));
    if (!p) return CST_OK;
    if (p->num_nums != 3)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" has %d values; expected 3", d, name,
                            p->num_nums);
    *out = v3((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]);
    if (!v3_is_finite(*out))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" is not finite", d, name);
    return CST_OK;
}

static CstStatus tex_uv_mapping(Loader *ld, Params *ps, const char *d, TexMapping *m)
{
    const char *mapping = NULL;
    Loc ml;
    char nm[72];
    float su = 1.0f, sv = 1.0f, du = 0.0f, dv = 0.0f;
    memset(m, 0, sizeof *m);
    TRY(pbrt_get_string(ld, ps, d, "mapping", &mapping, &ml));
    if (mapping && strcmp(mapping, "uv") != 0) {
        if (strcmp(mapping, "spherical") == 0) m->type = CST_TEXTURE_MAPPING_SPHERICAL;
        else if (strcmp(mapping, "cylindrical") == 0) m->type = CST_TEXTURE_MAPPING_CYLINDRICAL;
        else if (strcmp(mapping, "planar") == 0) m->type = CST_TEXTURE_MAPPING_PLANAR;
        else
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, ml, "%s: unknown mapping \"%s\"; expected one of: uv, "
                                "spherical, cylindrical, planar", d, pbrt_clip(mapping, nm));
        if (ld->gs.ctm.inv_ok)
            for (int r = 0; r < 3; r++)
                for (int c = 0; c < 4; c++) m->xf[4 * r + c] = ld->gs.ctm.inv.m[r][c];
        if (m->type == CST_TEXTURE_MAPPING_PLANAR) {
            TRY(tex_vector3(ld, ps, d, "v1", v3(1.0f, 0.0f, 0.0f), &m->v1));
            TRY(tex_vector3(ld, ps, d, "v2", v3(0.0f, 1.0f, 0.0f), &m->v2));
            TRY(pbrt_get_float(ld, ps, d, "udelta", 0.0f, &du, NULL));
            TRY(pbrt_get_float(ld, ps, d, "vdelta", 0.0f, &dv, NULL));
        }
        m->scale = v2(1.0f, 1.0f);
        m->offset = v2(du, dv);
        return CST_OK;
    }
    TRY(pbrt_get_float(ld, ps, d, "uscale", 1.0f, &su, NULL));
    TRY(pbrt_get_float(ld, ps, d, "vscale", 1.0f, &sv, NULL));
    TRY(pbrt_get_float(ld, ps, d, "udelta", 0.0f, &du, NULL));
    TRY(pbrt_get_float(ld, ps, d, "vdelta", 0.0f, &dv, NULL));
    if (su == 0.0f && sv == 0.0f) {
        /* The builder reads a zero uv_scale as "unset" (1, 1). */
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, ml, "%s: uscale and vscale 0 (the texture squeezed to one "
                     "point) are read as 1", d);
        su = sv = 1.0f;
    }
    m->scale = v2(su, sv);
    m->offset = v2(du, dv);
    return CST_OK;
}

static void desc_uv(CstTextureDesc *t, const TexMapping *m)
{
    t->uv_scale[0] = m->scale.x, t->uv_scale[1] = m->scale.y;
    t->uv_offset[0] = m->offset.x, t->uv_offset[1] = m->offset.y;
    t->mapping = m->type;
    if (m->type == CST_TEXTURE_MAPPING_UV) return;
    memcpy(t->mapping_from_world, m->xf, sizeof m->xf);
    t->planar_v1[0] = m->v1.x, t->planar_v1[1] = m->v1.y, t->planar_v1[2] = m->v1.z;
    t->planar_v2[0] = m->v2.x, t->planar_v2[1] = m->v2.y, t->planar_v2[2] = m->v2.z;
}

/* A texture-valued parameter of a Texture: another non-constant texture (*id >= 0), or a
 * value (*id = -1, *val: given, a constant texture's, or def). */
static CstStatus tex_operand(Loader *ld, Params *ps, const char *d, const char *name, int is_float,
                             float def, int *id, Color *val)
{
    int tex = 0;
    *id = -1;
    *val = color_s(def);
    TRY(pbrt_tex_param(ld, ps, d, name, is_float, &tex, val, NULL));
    if (tex) {
        *id = tex - 1;
        return CST_OK;
    }
    Param *p = pbrt_find_param(ps, name);
    if (p && p->type == PT_TEXTURE) return CST_OK;
    if (is_float) {
        float f = def;
        TRY(pbrt_get_float_tex(ld, ps, d, name, def, &f, NULL));
        *val = color_s(f);
        return CST_OK;
    }
    return pbrt_get_spectrum(ld, ps, d, name, SPEC_UNBOUNDED, 1, val, NULL);
}

/* pbrt-v4's "imagemap" as an image texture (docs/pbrt-compat.md): the image file, its
 * decoding, pbrt's per-value scale and invert, and the uv mapping. *id < 0 (and *v set)
 * when the file's format cannot be read. */
static CstStatus texture_imagemap(Loader *ld, Params *ps, const char *d, Loc loc, int is_float, int *id, Color *v)
{
    const char *file = NULL, *filter = NULL, *wrap = NULL, *enc = NULL;
    Loc fl = loc, wl = loc, el = loc, il = loc;
    float scale = 1.0f, aniso = 8.0f, gamma = 0.0f;
    int invert = 0;
    char nm[72];
    TexMapping map;
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    TRY(pbrt_get_string(ld, ps, d, "filter", &filter, &il));
    TRY(pbrt_get_string(ld, ps, d, "wrap", &wrap, &wl));
    TRY(pbrt_get_string(ld, ps, d, "encoding", &enc, &el));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "maxanisotropy", 8.0f, &aniso, NULL)); /* for EWA only */
    TRY(pbrt_get_bool(ld, ps, d, "invert", 0, &invert));
    TRY(tex_uv_mapping(ld, ps, d, &map));
    *id = -1;
    if (!file)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the image file", d);
    CstTextureWrap tw = CST_TEXTURE_WRAP_REPEAT;
    if (wrap && strcmp(wrap, "clamp") == 0) {
        tw = CST_TEXTURE_WRAP_CLAMP;
    } else if (wrap && (strcmp(wrap, "black") == 0 || strcmp(wrap, "octahedralsphere") == 0)) {
        tw = CST_TEXTURE_WRAP_CLAMP;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, wl, "%s: wrap \"%s\" approximated by \"clamp\"", d, wrap);
    } else if (wrap && strcmp(wrap, "repeat") != 0) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, wl, "%s: wrap \"%s\" is not known; expected \"repeat\", "
                            "\"clamp\", \"black\" or \"octahedralsphere\"", d, pbrt_clip(wrap, nm));
    }
    CstTextureFilter tf = CST_TEXTURE_FILTER_BILINEAR; /* pbrt-v4's default */
    if (filter) {
        if (strcmp(filter, "point") == 0) tf = CST_TEXTURE_FILTER_POINT;
        else if (strcmp(filter, "trilinear") == 0) tf = CST_TEXTURE_FILTER_TRILINEAR;
        else if (strcmp(filter, "ewa") == 0 || strcmp(filter, "EWA") == 0) tf = CST_TEXTURE_FILTER_EWA;
        else if (strcmp(filter, "bilinear") != 0)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, il, "%s: filter \"%s\" is not known; expected \"point\", "
                                "\"bilinear\", \"trilinear\" or \"ewa\"", d, pbrt_clip(filter, nm));
    }
    /* pbrt-v4's default: sRGB for PNG files, linear for every other file (JPEG, TGA, ...). */
    size_t fn_len = strlen(file);
    int linear = !(fn_len >= 4 && strcasecmp(file + fn_len - 4, ".png") == 0);
    if (enc) {
        if (strcmp(enc, "linear") == 0) {
            linear = 1;
        } else if (strncmp(enc, "gamma ", 6) == 0) {
            char *e = NULL;
            gamma = strtof(enc + 6, &e);
            if (!(gamma > 0.0f) || !isfinite(gamma) || *e)
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, el, "%s: encoding \"%s\"; expected \"gamma\" and "
                                    "a number > 0, as in \"gamma 2.2\"", d, pbrt_clip(enc, nm));
            linear = 1;
        } else if (strcmp(enc, "sRGB") != 0) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, el, "%s: encoding \"%s\" is not known; expected "
                                "\"sRGB\", \"linear\" or \"gamma\" and a number", d, pbrt_clip(enc, nm));
        }
    }
    ImageFileFormat format = image_format_from_path(file);
    int readable = format != IMAGE_FILE_NONE;
    if (!readable) {
        *v = color_s(0.5f);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, fl, "%s: image \"%s\" is not PNG, JPEG, BMP, TGA, HDR, EXR or "
                     "PFM; the constant 0.5 is used instead", d, pbrt_clip(file, nm));
        Color a = color_s(invert ? -scale : scale), b = color_s(invert ? 1.0f : 0.0f);
        *v = texop_apply(TEXOP_AFFINE, a, b, *v);
        return CST_OK;
    }
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    /* The image in its file's storage; pbrt's order after the lookup and filtering: a float
     * texture's value by pbrt-v4's channel rule (CstTextureDesc.pbrt_float: MIPMap::
     * Filter<Float>), then scale, then invert (pbrt-v4 FloatImageTexture). */
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_IMAGE;
    t.path = path;
    t.encoding = gamma > 0.0f ? CST_TEXTURE_ENCODING_GAMMA : linear ? CST_TEXTURE_ENCODING_LINEAR
                                                                  : CST_TEXTURE_ENCODING_SRGB;
    t.gamma = gamma;
    t.wrap = tw;
    t.filter = tf;
    t.max_anisotropy = aniso >= 1.0f && aniso <= 1e6f ? aniso : 8.0f;
    desc_uv(&t, &map);
    CstStatus st = CST_OK;
    t.pbrt_float = is_float;
    if (scale != 1.0f || invert)
        st = desc_append_op(ld, &t, TEXOP_AFFINE, color_s(invert ? -scale : scale), color_s(invert ? 1.0f : 0.0f),
                            loc, d);
    if (!st) st = tex_add(ld, &t, fl, d, id);
    free(path);
    return st;
}

/* pbrt-v4's "checkerboard": a 2D checkerboard of tex1 (where floor(s) + floor(t) is even)
 * and tex2, on the uv mapping. */
static CstStatus texture_checker(Loader *ld, Params *ps, const char *d, Loc loc, int is_float, int *id)
{
    int a = -1, b = -1;
    Color va, vb;
    TexMapping map;
    TRY(tex_operand(ld, ps, d, "tex1", is_float, 1.0f, &a, &va));
    TRY(tex_operand(ld, ps, d, "tex2", is_float, 0.0f, &b, &vb));
    TRY(tex_uv_mapping(ld, ps, d, &map));
    if (a < 0) TRY(tex_const(ld, va, loc, d, &a));
    if (b < 0) TRY(tex_const(ld, vb, loc, d, &b));
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_CHECKERBOARD;
    t.even = a + 1;
    t.odd = b + 1;
    t.scale = 1.0f;
    desc_uv(&t, &map);
    return tex_add(ld, &t, loc, d, id);
}

/* A texture operand as a scene texture id (public id - 1): the named texture, or a constant
 * texture made of the given or default value. */
static CstStatus tex_operand_id(Loader *ld, Params *ps, const char *d, const char *name, int is_float, float def,
                                Loc loc, int *id)
{
    Color v;
    TRY(tex_operand(ld, ps, d, name, is_float, def, id, &v));
    if (*id < 0) TRY(tex_const(ld, v, loc, d, id));
    return CST_OK;
}

/* texture_from_world of a solid texture: the inverse of the CTM at its definition
 * (pbrt-v4 TextureMapping3D: renderFromTexture is the CTM). */
static void desc_solid_xf(Loader *ld, CstTextureDesc *t)
{
    if (!ld->gs.ctm.inv_ok) return; /* identity */
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) t->texture_from_world[4 * r + c] = ld->gs.ctm.inv.m[r][c];
}

/* Whether a mix's operands are all values or constant textures (amount too, for "mix"). */
static int mix_is_constant(Loader *ld, Params *ps, int is_float)
{
    static const char *const names[3] = {"tex1", "tex2", "amount"};
    for (int i = 0; i < 3; i++) {
        Param *p = pbrt_find_param(ps, names[i]);
        if (!p || p->type != PT_TEXTURE || p->num_strs < 1) continue;
        int k = find_texture(ld, p->strs[0], i == 2 ? 1 : is_float);
        if (k >= 0 && !texture_is_constant(ld, k)) return 0;
    }
    return 1;
}

/* pbrt-v4's procedural and combining textures through the builder (docs/pbrt-compat.md). */
static CstStatus texture_procedural_class(Loader *ld, Params *ps, const char *d, Loc loc, const char *cls,
                                          int is_float, int *id)
{
    CstTextureDesc t = {0};
    TexMapping map = {.scale = {1.0f, 1.0f}};
    int a = -1, b = -1;
    if (strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0) {
        TRY(tex_operand_id(ld, ps, d, "tex1", is_float, 0.0f, loc, &a));
        TRY(tex_operand_id(ld, ps, d, "tex2", is_float, 1.0f, loc, &b));
        t.tex1 = a + 1, t.tex2 = b + 1;
        if (cls[0] == 'm') {
            int am = -1;
            Color av;
            TRY(tex_operand(ld, ps, d, "amount", 1, 0.5f, &am, &av));
            t.type = CST_TEXTURE_MIX;
            t.amount = am + 1;
            t.amount_value = av.c[0];
        } else {
            Param *p;
            t.type = CST_TEXTURE_DIRECTIONMIX;
            Vec3 dir = v3(0.0f, 1.0f, 0.0f);
            TRY(pbrt_lookup(ld, ps, d, "dir", PT_MASK(PT_VECTOR3), "vector3", &p));
            if (p) {
                if (p->num_nums != 3)
                    return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"dir\" has %d values; expected 3", d,
                                        p->num_nums);
                dir = v3((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]);
            }
            /* pbrt-v4 carries dir by the CTM at the definition. */
            dir = transform_vector(&ld->gs.ctm.m, dir);
            t.dir[0] = dir.x, t.dir[1] = dir.y, t.dir[2] = dir.z;
        }
    } else if (strcmp(cls, "checkerboard") == 0) { /* dimension 3 */
        TRY(tex_operand_id(ld, ps, d, "tex1", is_float, 1.0f, loc, &a));
        TRY(tex_operand_id(ld, ps, d, "tex2", is_float, 0.0f, loc, &b));
        t.type = CST_TEXTURE_CHECKERBOARD_3D;
        t.tex1 = a + 1, t.tex2 = b + 1;
        desc_solid_xf(ld, &t);
    } else if (strcmp(cls, "dots") == 0) {
        TRY(tex_operand_id(ld, ps, d, "inside", is_float, 1.0f, loc, &a));
        TRY(tex_operand_id(ld, ps, d, "outside", is_float, 0.0f, loc, &b));
        TRY(tex_uv_mapping(ld, ps, d, &map));
        t.type = CST_TEXTURE_DOTS;
        /* pbrt-v4 (DotsTexture::Create) hands "inside" to the constructor's outsideDot and
         * "outside" to its insideDot, so its dots show "outside": rendered as pbrt does. */
        t.tex1 = b + 1, t.tex2 = a + 1;
    } else if (strcmp(cls, "bilerp") == 0) {
        static const char *const names[4] = {"v00", "v01", "v10", "v11"};
        static const float defs[4] = {0.0f, 1.0f, 0.0f, 1.0f};
        for (int i = 0; i < 4; i++) {
            Color c = color_s(defs[i]);
            if (is_float) {
                float f = defs[i];
                TRY(pbrt_get_float(ld, ps, d, names[i], defs[i], &f, NULL));
                c = color_s(maxf(f, 0.0f));
            } else {
                TRY(pbrt_get_spectrum(ld, ps, d, names[i], SPEC_UNBOUNDED, 1, &c, NULL));
            }
            pbrt_color_floats(c, t.corners[i]);
        }
        TRY(tex_uv_mapping(ld, ps, d, &map));
        t.type = CST_TEXTURE_BILERP;
    } else { /* fbm, wrinkled, windy, marble */
        float rough = 0.5f, sc = 1.0f, var = 0.2f;
        int oct = 8;
        t.type = strcmp(cls, "fbm") == 0 ? CST_TEXTURE_FBM : strcmp(cls, "wrinkled") == 0 ? CST_TEXTURE_WRINKLED
                 : strcmp(cls, "windy") == 0 ? CST_TEXTURE_WINDY : CST_TEXTURE_MARBLE;
        if (t.type != CST_TEXTURE_WINDY) {
            TRY(pbrt_get_int(ld, ps, d, "octaves", 8, &oct));
            TRY(pbrt_get_float(ld, ps, d, "roughness", 0.5f, &rough, NULL));
            if (oct < 1 || oct > 32 || !(rough > 0.0f))
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: octaves %d and roughness %g; expected 1 to 32 "
                                    "octaves and a roughness > 0", d, oct, (double)rough);
        }
        if (t.type == CST_TEXTURE_MARBLE) {
            TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &sc, NULL));
            TRY(pbrt_get_float(ld, ps, d, "variation", 0.2f, &var, NULL));
            if (sc == 0.0f) sc = 1e-30f; /* the builder reads 0 as "unset" (1) */
            if (var == 0.0f) var = 1e-30f;
        }
        t.octaves = oct, t.roughness = rough, t.noise_scale = sc, t.variation = var;
        desc_solid_xf(ld, &t);
    }
    desc_uv(&t, &map);
    return tex_add(ld, &t, loc, d, id);
}

CstStatus pbrt_material_normal_textures(Loader *ld, Params *ps, const char *d, Material *m)
{
    Param *p = pbrt_find_param(ps, "displacement");
    if (p && p->type == PT_TEXTURE) {
        int tex = 0;
        Color val;
        TRY(pbrt_tex_param(ld, ps, d, "displacement", 1, &tex, &val, NULL));
        m->displacement_texture = tex; /* 0 for a constant texture: no bending */
    } else if (p) {
        float f = 0.0f;
        TRY(pbrt_get_float(ld, ps, d, "displacement", 0.0f, &f, NULL)); /* a constant: no bending */
    }
    const char *file = NULL;
    Loc fl;
    TRY(pbrt_get_string(ld, ps, d, "normalmap", &file, &fl));
    if (!file) return CST_OK;
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_IMAGE;
    t.path = path;
    t.encoding = CST_TEXTURE_ENCODING_LINEAR;
    int id = 0;
    CstStatus st = tex_add(ld, &t, fl, d, &id);
    free(path);
    if (st) return st;
    m->normal_map_texture = id + 1;
    return CST_OK;
}

CstStatus pbrt_texture_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *name = NULL, *ttype = NULL, *cls = NULL, nm[72], nm2[72];
    Params ps = {0};
    Loc tl;
    CstStatus st = pbrt_expect_string(ld, lx, "Texture", "the texture's name", &name, NULL);
    if (!st) st = pbrt_expect_string(ld, lx, "Texture", "its type, \"spectrum\" or \"float\"", &ttype, &tl);
    if (!st) st = pbrt_expect_string(ld, lx, "Texture", "its class, as in \"imagemap\"", &cls, NULL);
    if (!st) st = pbrt_parse_params(ld, lx, &ps);
    if (st) goto done;
    if (!ld->in_world) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "Texture before WorldBegin; expected textures "
                          "in the world block");
        goto done;
    }
    int is_float = strcmp(ttype, "float") == 0;
    if (!is_float && strcmp(ttype, "spectrum") != 0 && strcmp(ttype, "color") != 0) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "Texture \"%s\": type \"%s\"; expected \"spectrum\" "
                          "or \"float\"", pbrt_clip(name, nm), pbrt_clip(ttype, nm2));
        goto done;
    }
    char d[160];
    snprintf(d, sizeof d, "Texture \"%s\" \"%s\"", pbrt_clip(name, nm), pbrt_clip(cls, nm2));
    Color v = color_s(1.0f); /* the value of a constant (id < 0) */
    int id = -1;         /* the scene texture, when not a constant */
    SpecKind sk = SPEC_UNBOUNDED;
/* A texture-valued parameter of this texture taken as one value (its average). */
#define TEXPARAM(pname, def, outv)                                                        \
    do {                                                                                  \
        (outv) = color_s(def);                                                              \
        if (is_float) {                                                                   \
            float f_ = (def);                                                             \
            st = pbrt_get_float_tex(ld, &ps, d, (pname), (def), &f_, NULL);                    \
            (outv) = color_s(f_);                                                           \
        } else {                                                                          \
            st = pbrt_get_spectrum(ld, &ps, d, (pname), sk, 1, &(outv), NULL);                 \
        }                                                                                 \
        if (st) goto done;                                                                \
    } while (0)
    if (strcmp(cls, "constant") == 0) {
        TEXPARAM("value", 1.0f, v);
    } else if (strcmp(cls, "scale") == 0) {
        /* tex times scale (a float texture): a constant, or a textured operand with the
         * other folded into its values. */
        int ta = -1, tb = -1;
        Color a, b;
        if ((st = tex_operand(ld, &ps, d, "tex", is_float, 1.0f, &ta, &a))) goto done;
        if ((st = tex_operand(ld, &ps, d, "scale", 1, 1.0f, &tb, &b))) goto done;
        if (ta < 0 && tb < 0) {
            v = color_mul(a, b);
        } else if (ta >= 0 && tb >= 0) {
            CstTextureDesc t = {0};
            t.type = CST_TEXTURE_SCALE;
            t.tex1 = ta + 1, t.amount = tb + 1;
            st = tex_add(ld, &t, loc, d, &id);
        } else {
            st = pbrt_tex_map(ld, ta >= 0 ? ta : tb, TEXOP_AFFINE, ta >= 0 ? b : a, color_s(0.0f), loc, d, &id);
        }
        if (st) goto done;
    } else if ((strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0) && mix_is_constant(ld, &ps, is_float)) {
        /* Constant operands: the loader keeps the value. */
        Color a, b;
        float amount = 0.5f;
        TEXPARAM("tex1", 0.0f, a);
        TEXPARAM("tex2", 1.0f, b);
        if (cls[0] == 'm') {
            st = pbrt_get_float_tex(ld, &ps, d, "amount", 0.5f, &amount, NULL);
            if (st) goto done;
            v = color_add(color_scale(a, 1.0f - amount), color_scale(b, amount));
        } else if ((st = texture_procedural_class(ld, &ps, d, loc, cls, is_float, &id))) {
            goto done;
        }
    } else if (strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0 || strcmp(cls, "dots") == 0 ||
               strcmp(cls, "bilerp") == 0 || strcmp(cls, "fbm") == 0 || strcmp(cls, "wrinkled") == 0 ||
               strcmp(cls, "windy") == 0 || strcmp(cls, "marble") == 0) {
        if ((st = texture_procedural_class(ld, &ps, d, loc, cls, is_float, &id))) goto done;
    } else if (strcmp(cls, "checkerboard") == 0) {
        int dim = 2;
        if ((st = pbrt_get_int(ld, &ps, d, "dimension", 2, &dim))) goto done;
        if (dim == 3) {
            if ((st = texture_procedural_class(ld, &ps, d, loc, cls, is_float, &id))) goto done;
        } else if (dim == 2) {
            if ((st = texture_checker(ld, &ps, d, loc, is_float, &id))) goto done;
        } else {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pbrt_find_param(&ps, "dimension")->loc, "%s: dimension %d; "
                              "expected 2 or 3", d, dim);
            goto done;
        }
    } else if (strcmp(cls, "imagemap") == 0) {
        if ((st = texture_imagemap(ld, &ps, d, loc, is_float, &id, &v))) goto done;
    } else {
        v = color_s(0.5f);
        pbrt_params_mark_all_used(&ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: texture class not supported; the constant 0.5 "
                     "is used instead", d);
    }
#undef TEXPARAM
    pbrt_params_warn_unused(ld, &ps, d);
    if (id >= 0) { /* else a constant: v, kept by the loader */
        CstTextureInfo info;
        if ((st = pbrt_texture_info(ld, id, &info))) goto done;
        v = color_of(info.average);
    }
    if (!GROW(ld->texs, ld->cap_texs, ld->num_texs + 1)) { st = pbrt_oom(ld); goto done; }
    ld->texs[ld->num_texs].name = name;
    ld->texs[ld->num_texs].is_float = is_float;
    ld->texs[ld->num_texs].id = id;
    ld->texs[ld->num_texs].value = v;
    ld->texs[ld->num_texs].clamped = ld->texs[ld->num_texs].rough[0] = ld->texs[ld->num_texs].rough[1] = -1;
    ld->num_texs++;
    name = NULL;
done:
    free(name);
    free(ttype);
    free(cls);
    pbrt_params_free(&ps);
    return st;
}
