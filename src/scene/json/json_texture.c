/* The "textures" section: constants, checkerboards and image files, read on first use so
 * that checkerboards may name textures listed after them. */
#include "scene/json/json_texture.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/path.h"

/* Adds the texture through the public builder; *out gets the loader's 0-based id (the
 * public id - 1), the index into the scene's textures it reads back. */
static CstStatus add_texture(Loader *ld, const CstTextureDesc *t, int *out)
{
    int id = 0;
    CstStatus st = cst_scene_add_texture(ld->scene, t, &id, ld->err);
    if (st != CST_OK) return json_fail_builder(ld, st);
    *out = id - 1;
    return CST_OK;
}

/* A checkerboard's "even" or "odd": a colour (a new constant texture) or a texture name. */
static CstStatus read_texture_operand(Loader *ld, const json_t *obj, const char *key, int *out)
{
    json_t *v;
    LOADER_TRY(json_member_required(ld, obj, key, "an RGB triple or a texture name", &v));
    json_path_push_key(ld, key);
    if (json_is_string(v)) {
        LOADER_TRY(json_read_texture_name(ld, json_string_value(v), out));
    } else {
        Color c;
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
        CstTextureDesc t = {0};
        t.type = CST_TEXTURE_CONSTANT;
        json_color_floats(c, t.value);
        LOADER_TRY(add_texture(ld, &t, out));
    }
    json_path_pop(ld);
    return CST_OK;
}

/* An image's "filter" (pbrt-v4's image filters; "none", the default, is bilinear on the
 * full image without a MIP map) and "max_anisotropy" (EWA's longest ellipse axis over the
 * shortest, > 0; pbrt-v4's 8 when absent; only with "ewa"). */
static CstStatus read_image_filter(Loader *ld, const json_t *obj, CstTextureDesc *t)
{
    static const char *const filters[] = {"none", "point", "bilinear", "trilinear", "ewa"};
    json_t *v;
    if ((v = json_object_get(obj, "filter"))) {
        const char *f = NULL;
        json_path_push_key(ld, "filter");
        LOADER_TRY(json_read_string(ld, v, &f));
        int k = 0;
        while (k < 5 && strcmp(f, filters[k]) != 0) k++;
        if (k == 5) {
            char name[72];
            return json_fail_here(ld, "unknown filter \"%s\"; expected one of: none, point, bilinear, trilinear, ewa",
                                  json_clip_name(f, name));
        }
        t->filter = (CstTextureFilter)k; /* the names are in the enum's order */
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "max_anisotropy"))) {
        json_path_push_key(ld, "max_anisotropy");
        if (t->filter != CST_TEXTURE_FILTER_EWA)
            return json_fail_here(ld, "max_anisotropy is for the \"ewa\" filter only; expected \"filter\": \"ewa\" "
                                      "or no max_anisotropy");
        LOADER_TRY(json_read_float(ld, v, 1e6, &t->max_anisotropy));
        if (!(t->max_anisotropy >= 1.0f))
            return json_fail_here(ld, "max_anisotropy %g; expected a number >= 1", (double)t->max_anisotropy);
        json_path_pop(ld);
    }
    return CST_OK;
}

/* The texture object at the current path (textures.<name>). */
static CstStatus parse_texture(Loader *ld, const json_t *obj, int *out)
{
    static const char *const types[] = {"constant", "checkerboard", "image"};
    static const char *const keys_constant[] = {"type", "value"};
    static const char *const keys_checker[] = {"type", "even", "odd", "scale"};
    static const char *const keys_image[] = {"type", "file", "linear", "wrap", "filter", "max_anisotropy"};
    int type = 0;
    json_t *v;
    CstTextureDesc t = {0};
    LOADER_TRY(json_expect_object(ld, obj, "a texture object"));
    LOADER_TRY(json_read_type(ld, obj, "texture type", types, 3, -1, &type));
    if (type == TEXTURE_CONSTANT) {
        Color c;
        LOADER_TRY(json_check_keys(ld, obj, keys_constant, 2));
        LOADER_TRY(json_member_required(ld, obj, "value", "an array of 3 numbers >= 0", &v));
        json_path_push_key(ld, "value");
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
        json_path_pop(ld);
        t.type = CST_TEXTURE_CONSTANT;
        json_color_floats(c, t.value);
    } else if (type == TEXTURE_CHECKERBOARD) {
        int even = 0, odd = 0;
        float scale = 1.0f;
        LOADER_TRY(json_check_keys(ld, obj, keys_checker, 4));
        if ((v = json_object_get(obj, "scale"))) {
            json_path_push_key(ld, "scale");
            LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &scale));
            if (!(scale > 0.0f))
                return json_fail_here(ld, "scale %g is not positive; expected the number of squares per "
                                          "unit of u and v, > 0", (double)scale);
            json_path_pop(ld);
        }
        LOADER_TRY(read_texture_operand(ld, obj, "even", &even));
        LOADER_TRY(read_texture_operand(ld, obj, "odd", &odd));
        t.type = CST_TEXTURE_CHECKERBOARD;
        t.even = even + 1;
        t.odd = odd + 1;
        t.scale = scale;
    } else {
        static const char *const wraps[] = {"repeat", "clamp"};
        const char *file = NULL;
        int linear = 0;
        CstTextureWrap wrap = CST_TEXTURE_WRAP_REPEAT;
        LOADER_TRY(json_check_keys(ld, obj, keys_image, 6));
        LOADER_TRY(read_image_filter(ld, obj, &t));
        if ((v = json_object_get(obj, "linear"))) {
            json_path_push_key(ld, "linear");
            LOADER_TRY(json_read_bool(ld, v, &linear));
            json_path_pop(ld);
        }
        if ((v = json_object_get(obj, "wrap"))) {
            const char *w = NULL;
            json_path_push_key(ld, "wrap");
            LOADER_TRY(json_read_string(ld, v, &w));
            if (strcmp(w, wraps[0]) == 0) wrap = CST_TEXTURE_WRAP_REPEAT;
            else if (strcmp(w, wraps[1]) == 0) wrap = CST_TEXTURE_WRAP_CLAMP;
            else {
                char name[72];
                return json_fail_here(ld, "unknown wrap mode \"%s\"; expected one of: repeat, clamp",
                                      json_clip_name(w, name));
            }
            json_path_pop(ld);
        }
        LOADER_TRY(json_member_required(ld, obj, "file", "the path of an image file", &v));
        json_path_push_key(ld, "file");
        LOADER_TRY(json_read_string(ld, v, &file));
        if (!file[0]) return json_fail_here(ld, "the file name is empty; expected the path of an image");
        char *path = path_resolve(ld->name, file);
        if (!path) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
        t.type = CST_TEXTURE_IMAGE;
        t.path = path;
        t.linear = linear;
        t.wrap = wrap;
        CstStatus st = add_texture(ld, &t, out); /* at "file": the image's own errors */
        free(path);
        if (st != CST_OK) return st;
        json_path_pop(ld);
        return CST_OK;
    }
    return add_texture(ld, &t, out);
}

/* Index of the texture called `name` in ld->tex_names, or -1. */
static int texture_index(const Loader *ld, const char *name)
{
    int lo = 0, hi = ld->num_textures;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2, c = strcmp(ld->tex_names[ld->tex_sorted[mid]], name);
        if (c == 0) return ld->tex_sorted[mid];
        if (c < 0) lo = mid + 1;
        else hi = mid;
    }
    return -1;
}

/* A texture that texture i's checkerboard operands name and that has not been read yet,
 * or -1. Anything malformed is left for parse_texture to report at its place. */
static int texture_pending_operand(const Loader *ld, int i)
{
    const json_t *obj = json_object_get(ld->tex_obj, ld->tex_names[i]);
    const json_t *type = json_object_get(obj, "type");
    if (!json_is_string(type) || strcmp(json_string_value(type), "checkerboard") != 0) return -1;
    static const char *const keys[] = {"even", "odd"};
    for (int k = 0; k < 2; k++) {
        const json_t *v = json_object_get(obj, keys[k]);
        int j = json_is_string(v) ? texture_index(ld, json_string_value(v)) : -1;
        if (j >= 0 && ld->tex_state[j] == 0) return j;
    }
    return -1;
}

/* Reads texture `root` and, first, every unread texture its checkerboards reach. Chains of
 * checkerboards are as long as the file makes them (a chain of 100,000 overflowed the stack
 * when this recursed), so the walk keeps its own stack: a texture is pushed once (state 1)
 * and parsed when the textures it names are read, so parse_texture finds them read and
 * never descends. A texture naming one still on the stack is a cycle, reported by
 * read_texture_operand at the name that closes it. */
static CstStatus read_texture_tree(Loader *ld, int root)
{
    int *stack = malloc((size_t)ld->num_textures * sizeof *stack), top = 0;
    if (!stack) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    JsonPathStep saved[LOADER_MAX_DEPTH];
    int saved_depth = ld->depth;
    memcpy(saved, ld->path, sizeof saved);
    stack[top++] = root;
    ld->tex_state[root] = 1;
    CstStatus st = CST_OK;
    while (top > 0 && st == CST_OK) {
        int i = stack[top - 1], dep = texture_pending_operand(ld, i);
        if (dep >= 0) {
            ld->tex_state[dep] = 1;
            stack[top++] = dep;
            continue;
        }
        /* Read it at its own path. */
        ld->depth = 0;
        json_path_push_key(ld, "textures");
        json_path_push_key(ld, ld->tex_names[i]);
        st = parse_texture(ld, json_object_get(ld->tex_obj, ld->tex_names[i]), &ld->tex_ids[i]);
        ld->tex_state[i] = 2;
        top--;
    }
    free(stack);
    if (st != CST_OK) return st; /* the path stays at the error */
    memcpy(ld->path, saved, sizeof saved);
    ld->depth = saved_depth;
    return CST_OK;
}

/* Scene id of the texture called `name`, read now if it has not been. The error points at
 * the current path (the value naming it). */
CstStatus json_read_texture_name(Loader *ld, const char *name, int *out)
{
    char clipped[72];
    int i = texture_index(ld, name);
    if (i >= 0) {
        if (ld->tex_state[i] == 1)
            return json_fail_here(ld, "texture \"%s\" contains itself through checkerboards; expected "
                                      "no cycles", json_clip_name(name, clipped));
        if (ld->tex_state[i] == 0) LOADER_TRY(read_texture_tree(ld, i));
        *out = ld->tex_ids[i];
        return CST_OK;
    }
    if (ld->num_textures == 0)
        return json_fail_here(ld, "texture \"%s\" is not defined (no textures are); expected a name "
                                  "defined under \"textures\"", json_clip_name(name, clipped));
    char list[512];
    json_join_names(ld->tex_names, ld->num_textures, list, sizeof list);
    return json_fail_here(ld, "texture \"%s\" is not defined; expected one of: %s", json_clip_name(name, clipped), list);
}

typedef struct TexKey {
    const char *name;
    int index;
} TexKey;

static int tex_key_cmp(const void *a, const void *b)
{
    return strcmp(((const TexKey *)a)->name, ((const TexKey *)b)->name);
}

CstStatus json_parse_textures(Loader *ld, const json_t *texs)
{
    LOADER_TRY(json_expect_object(ld, texs, "an object mapping texture names to textures"));
    size_t n = json_object_size(texs);
    if (n > (size_t)INT_MAX / 2)
        return json_fail_here(ld, "too many textures");
    ld->tex_obj = texs;
    ld->tex_names = malloc((n ? n : 1) * sizeof *ld->tex_names);
    ld->tex_state = calloc(n ? n : 1, sizeof *ld->tex_state);
    ld->tex_ids = calloc(n ? n : 1, sizeof *ld->tex_ids);
    ld->tex_sorted = malloc((n ? n : 1) * sizeof *ld->tex_sorted);
    TexKey *keys = malloc((n ? n : 1) * sizeof *keys);
    if (!ld->tex_names || !ld->tex_state || !ld->tex_ids || !ld->tex_sorted || !keys) {
        free(keys);
        return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    }
    const char *name;
    json_t *v;
    json_object_foreach((json_t *)texs, name, v) {
        keys[ld->num_textures] = (TexKey){name, ld->num_textures};
        ld->tex_names[ld->num_textures++] = name;
    }
    qsort(keys, n, sizeof *keys, tex_key_cmp);
    for (size_t i = 0; i < n; i++) ld->tex_sorted[i] = keys[i].index;
    free(keys);
    /* Every texture is read (and so checked) even when nothing uses it. */
    for (int i = 0; i < ld->num_textures; i++) {
        int id;
        LOADER_TRY(json_read_texture_name(ld, ld->tex_names[i], &id));
    }
    return CST_OK;
}

/* A material parameter given as a texture name: its id + 1 (Material's convention), after
 * checking the texture's values fit the parameter (at most 1 for reflectances and
 * roughness). The current path is the parameter's value. */
CstStatus json_read_param_texture(Loader *ld, const json_t *v, const char *what, int *out)
{
    int id = 0;
    LOADER_TRY(json_read_texture_name(ld, json_string_value(v), &id));
    CstTextureInfo info;
    LOADER_TRY(cst_scene_texture_info(ld->scene, id + 1, &info, ld->err));
    float mx = fmaxf(info.max[0], fmaxf(info.max[1], info.max[2]));
    if (mx > 1.0f) {
        char clipped[72];
        return json_fail_here(ld, "texture \"%s\" has values up to %g; expected %s, at most 1",
                              json_clip_name(json_string_value(v), clipped), (double)mx, what);
    }
    *out = id + 1;
    return CST_OK;
}
