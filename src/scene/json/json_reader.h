/* The JSON scene loader's reader core: the Loader state, the path of the value being read
 * and its file:line:column in messages (found again by json_locate, since jansson keeps no
 * positions), and the typed readers that check every value. */
#ifndef CST_SCENE_JSON_JSON_READER_H
#define CST_SCENE_JSON_JSON_READER_H

#include <jansson.h>
#include <limits.h>
#include <stdbool.h>
#include <stddef.h>

#include "caustic/caustic.h"
#include "scene/json/json_locate.h"
#include "scene/scene.h"

/* Deepest path the format has: an "sdf" shape's tree, shapes[i].root then 2 steps per level
 * (children[j]) for up to SDF_MAX_DEPTH (24) levels, then a node's transform.rotate[j].axis[k]:
 * 2 + 2 x 24 + 4 = 54; the rest is headroom. */
#define LOADER_MAX_DEPTH 64

/* Bound on scene-space coordinates and lengths. Intersection tests work with squared
 * distances in float; with every coordinate within 1e18 those stay finite,
 * 3 * (2e18)^2 = 1.2e37 < FLT_MAX = 3.4e38, and so do triangle and sphere areas. */
#define LOADER_MAX_LENGTH 1e18

/* read_int's "no upper bound"; jansson integers are long long (JSON_INTEGER_IS_LONG_LONG). */
#define LOADER_NO_MAX ((json_int_t)LLONG_MAX)

#define LOADER_TRY(expr)                    \
    do {                                    \
        CstStatus loader_st_ = (expr);      \
        if (loader_st_ != CST_OK)           \
            return loader_st_;              \
    } while (0)

typedef struct Loader {
    const char *text;
    size_t len;
    const char *name; /* the file name in messages */
    /* Path of the value being read. Every error returns at once, so a failing reader
     * never needs to pop what it pushed. */
    JsonPathStep path[LOADER_MAX_DEPTH];
    int depth;
    Scene *scene;
    CstError *err; /* never NULL: the entry points substitute a local one */
    const CstLoadOptions *opt; /* the caller's warning callback, or NULL */
    /* Material names (keys owned by the jansson root) and their scene ids, in file order. */
    const char **mat_names;
    int *mat_ids;
    int num_materials;
    /* The "textures" object and, per member in iteration order, its name, state (0 not
     * read, 1 being read: a checkerboard cycle, 2 read) and scene id. Read on first use,
     * so checkerboards may name textures listed after them. */
    const json_t *tex_obj;
    const char **tex_names;
    int *tex_state, *tex_ids;
    int *tex_sorted; /* indices into tex_names in strcmp order: lookups by binary search */
    int num_textures;
    /* Medium names (keys owned by the jansson root), in file order: a medium's scene id is
     * its index. boundary_material: the material given to boundary shapes without one
     * (made on first use), or -1. */
    const char **med_names;
    int num_media;
    int boundary_material;
    /* What the film, integrator and sampler sections ask for, handed to the scene with
     * cst_scene_set_render_settings before commit. Starts as a new scene's settings: unset,
     * with 0 for the fields where 0 reads as unset (and aovs, which sections OR into). */
    CstRenderSettings settings;
} Loader;

/* The path of the value being read (for messages): push an object member, an array element;
 * pop. Pushes beyond LOADER_MAX_DEPTH are counted, not stored. */
void json_path_push_key(Loader *ld, const char *key);

void json_path_push_index(Loader *ld, size_t index);

void json_path_pop(Loader *ld);

/* Copies src into buf[*pos, cap) as far as it fits, always terminating. Control bytes
 * (decoded from escapes in the file) become '?' so a message stays on one line. */
void json_buf_append(char *buf, size_t cap, size_t *pos, const char *src);

/* A name from the file, made safe and short enough to quote in a message. */
const char *json_clip_name(const char *s, char buf[72]);

/* "a, b, c" */
void json_join_names(const char *const *names, int n, char *buf, size_t cap);

/* Fails with `status` at the value of the current path: "file:line:column: path: message". */
CstStatus json_fail_at(Loader *ld, CstStatus status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

/* A semantic error in the value at the current path. */
CstStatus json_fail_here(Loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A semantic error in the key that ends the current path. */
CstStatus json_fail_key(Loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));

/* A builder call failed: keep its status and text, add where in the file it came from. */
CstStatus json_fail_builder(Loader *ld, CstStatus status);
/* A colour the loader read, as the three floats the public builder takes (exact). */
static inline void json_color_floats(Color c, float out[3])
{
    for (int k = 0; k < 3; k++) out[k] = color_channel(c, k);
}
static inline void json_vec3_floats(Vec3 v, float out[3])
{
    out[0] = v.x;
    out[1] = v.y;
    out[2] = v.z;
}

/* Each reads the value at the current path and fails there with what it expected. */

/* What v is, for "got ..." in messages ("an array of 2 elements", "a string"...). */
const char *json_describe(const json_t *v, char buf[48]);

/* A number of magnitude at most max_abs: FLT_MAX for plain values, LOADER_MAX_LENGTH for
 * scene-space coordinates and lengths. */
CstStatus json_read_float(Loader *ld, const json_t *v, double max_abs, float *out);

/* An array of 3 numbers of magnitude at most max_abs. */
CstStatus json_read_vec3(Loader *ld, const json_t *v, double max_abs, Vec3 *out);

/* An RGB triple of numbers, each >= 0 and, when max_one, <= 1. */
CstStatus json_read_rgb(Loader *ld, const json_t *v, int max_one, Color *out);

/* An integer in [lo, hi]. */
CstStatus json_read_int(Loader *ld, const json_t *v, json_int_t lo, json_int_t hi, json_int_t *out);

/* A string; *out points into the jansson value. */
CstStatus json_read_string(Loader *ld, const json_t *v, const char **out);

/* true or false. */
CstStatus json_read_bool(Loader *ld, const json_t *v, int *out);

/* A located error unless v is an object; `what` describes the expected object. */
CstStatus json_expect_object(Loader *ld, const json_t *v, const char *what);

/* Rejects keys not in allowed: a misspelt optional key must not silently mean "default". */
CstStatus json_check_keys(Loader *ld, const json_t *obj, const char *const *allowed, int n);

/* *out = obj[key], which must exist; the error points at obj. */
CstStatus json_member_required(Loader *ld, const json_t *obj, const char *key,
                               const char *expected, json_t **out);

/* obj["type"] as an index into names; a missing type gives default_index, or an error
 * if that is -1. */
CstStatus json_read_type(Loader *ld, const json_t *obj, const char *what,
                         const char *const *names, int n, int default_index, int *out);

#endif
