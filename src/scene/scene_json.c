/* The JSON scene loader (format: docs/scene-format.md). jansson parses; this file validates
 * every value, names its file:line:column on error (found again by json_locate, since
 * jansson keeps no positions), and builds the scene through the scene_add_* builder only. */
#include <errno.h>
#include <float.h>
#include <jansson.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "io/image_io.h"
#include "io/path.h"
#include "math/transform.h"
#include "scene/json_locate.h"
#include "scene/mesh_import.h"
#include "scene/scene.h"

/* Deepest path the format has is 6 (shapes[i].transform.rotate[j].axis[k]); the rest is
 * headroom. */
#define LOADER_MAX_DEPTH 8
#define LOADER_MAX_FILM_SIZE 65536
/* A quad's fourth vertex may lie this fraction of the quad's longer diagonal off the plane
 * of the other three. The measured Cornell box data is off by 0.41% (the left wall: the
 * room was surveyed, not modelled), so 1% passes it while a visibly bent quad fails. */
#define LOADER_QUAD_PLANARITY_TOL 0.01
/* Bound on scene-space coordinates and lengths. Intersection tests work with squared
 * distances in float; with every coordinate within 1e18 those stay finite,
 * 3 * (2e18)^2 = 1.2e37 < FLT_MAX = 3.4e38, and so do triangle and sphere areas. */
#define LOADER_MAX_LENGTH 1e18
/* A sphere's area 4 pi r^2 must not underflow to 0 in float: an emitter of area 0 cannot
 * be sampled. 1e-18 keeps r^2 a normal float. */
#define LOADER_MIN_RADIUS 1e-18
/* read_int's "no upper bound"; jansson integers are long long (JSON_INTEGER_IS_LONG_LONG). */
#define LOADER_NO_MAX ((json_int_t)LLONG_MAX)
_Static_assert(sizeof(json_int_t) == sizeof(long long), "jansson integers are long long");

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
    int num_textures;
} Loader;

/* ------------------------------------------------------------------ paths and messages */

static void path_push_key(Loader *ld, const char *key)
{
    if (ld->depth < LOADER_MAX_DEPTH)
        ld->path[ld->depth] = (JsonPathStep){key, 0};
    ld->depth++;
}

static void path_push_index(Loader *ld, size_t index)
{
    if (ld->depth < LOADER_MAX_DEPTH)
        ld->path[ld->depth] = (JsonPathStep){NULL, index};
    ld->depth++;
}

static void path_pop(Loader *ld) { ld->depth--; }

/* Copies src into buf[*pos, cap) as far as it fits, always terminating. Control bytes
 * (decoded from escapes in the file) become '?' so a message stays on one line. */
static void buf_append(char *buf, size_t cap, size_t *pos, const char *src)
{
    for (; *src && *pos + 1 < cap; src++)
        buf[(*pos)++] = ((unsigned char)*src < 0x20) ? '?' : *src;
    buf[*pos] = '\0';
}

/* A name from the file, made safe and short enough to quote in a message. */
static const char *clip_name(const char *s, char buf[72])
{
    size_t pos = 0;
    buf[0] = '\0';
    buf_append(buf, 64, &pos, s);
    if (strlen(s) > pos)
        buf_append(buf, 72, &pos, "...");
    return buf;
}

/* "a, b, c" */
static void join_names(const char *const *names, int n, char *buf, size_t cap)
{
    size_t pos = 0;
    buf[0] = '\0';
    for (int i = 0; i < n; i++) {
        if (i > 0)
            buf_append(buf, cap, &pos, ", ");
        buf_append(buf, cap, &pos, names[i]);
    }
}

static int is_plain_key(const char *k)
{
    if (!*k)
        return 0;
    for (; *k; k++)
        if (!((*k >= 'a' && *k <= 'z') || (*k >= 'A' && *k <= 'Z') || (*k >= '0' && *k <= '9') ||
              *k == '_' || *k == '-'))
            return 0;
    return 1;
}

/* shapes[3].vertices[2], or materials["my glass"].ior for keys that are not identifiers. */
static void path_format(const JsonPathStep *path, int depth, char *buf, size_t cap)
{
    size_t pos = 0;
    buf[0] = '\0';
    for (int d = 0; d < depth; d++) {
        if (path[d].key && is_plain_key(path[d].key)) {
            if (d > 0)
                buf_append(buf, cap, &pos, ".");
            buf_append(buf, cap, &pos, path[d].key);
        } else if (path[d].key) {
            char name[72];
            buf_append(buf, cap, &pos, "[\"");
            buf_append(buf, cap, &pos, clip_name(path[d].key, name));
            buf_append(buf, cap, &pos, "\"]");
        } else {
            char idx[32];
            snprintf(idx, sizeof idx, "[%zu]", path[d].index);
            buf_append(buf, cap, &pos, idx);
        }
    }
}

/* Fails with "<file>:<line>:<col>: <json path>: <what>". The position is that of the value
 * at the current path or, for JSON_LOCATE_KEY, of the key ending it; the json path printed
 * is then the object holding the key, as the message names the key itself. */
static CstStatus fail_v(Loader *ld, CstStatus status, JsonLocateTarget target, const char *fmt,
                        va_list ap)
{
    char what[640], where[256];
    int depth = ld->depth < LOADER_MAX_DEPTH ? ld->depth : LOADER_MAX_DEPTH;
    vsnprintf(what, sizeof what, fmt, ap);
    path_format(ld->path, target == JSON_LOCATE_KEY ? depth - 1 : depth, where, sizeof where);
    const char *sep = where[0] ? ": " : "";
    JsonLocation loc;
    if (json_locate(ld->text, ld->len, ld->path, depth, target, &loc))
        cst_fail(ld->err, status, "%.200s:%d:%d: %s%s%s", ld->name, loc.line, loc.column, where,
                 sep, what);
    else /* unreachable for text jansson accepted; still say what we know */
        cst_fail(ld->err, status, "%.200s: %s%s%s", ld->name, where, sep, what);
    return status; /* visibly nonzero, so callers' outputs are known set on CST_OK */
}

static CstStatus fail_at(Loader *ld, CstStatus status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static CstStatus fail_at(Loader *ld, CstStatus status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, status, JSON_LOCATE_VALUE, fmt, ap);
    va_end(ap);
    return st;
}

/* A semantic error in the value at the current path. */
static CstStatus fail_here(Loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static CstStatus fail_here(Loader *ld, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, CST_ERR_INVALID_ARG, JSON_LOCATE_VALUE, fmt, ap);
    va_end(ap);
    return st;
}

/* A semantic error in the key that ends the current path. */
static CstStatus fail_key(Loader *ld, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static CstStatus fail_key(Loader *ld, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, CST_ERR_INVALID_ARG, JSON_LOCATE_KEY, fmt, ap);
    va_end(ap);
    return st;
}

/* A builder call failed: keep its status and text, add where in the file it came from. */
static CstStatus fail_builder(Loader *ld, CstStatus status)
{
    char msg[sizeof ld->err->msg];
    memcpy(msg, ld->err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    return fail_at(ld, status, "%.600s", msg);
}

/* ------------------------------------------------------------------ typed readers */
/* Each reads the value at the current path and fails there with what it expected. */

static const char *describe(const json_t *v, char buf[48])
{
    switch (json_typeof(v)) {
    case JSON_OBJECT: return "an object";
    case JSON_ARRAY:
        snprintf(buf, 48, "an array of %zu element%s", json_array_size(v),
                 json_array_size(v) == 1 ? "" : "s");
        return buf;
    case JSON_STRING: return "a string";
    case JSON_INTEGER: return "an integer";
    case JSON_REAL: return "a number";
    case JSON_TRUE: return "true";
    case JSON_FALSE: return "false";
    case JSON_NULL: return "null";
    }
    return "an unknown value";
}

/* A number of magnitude at most max_abs: FLT_MAX for plain values, LOADER_MAX_LENGTH for
 * scene-space coordinates and lengths. */
static CstStatus read_float(Loader *ld, const json_t *v, double max_abs, float *out)
{
    char kind[48];
    if (!json_is_number(v))
        return fail_here(ld, "got %s; expected a number", describe(v, kind));
    double d = json_number_value(v);
    /* jansson already rejects NaN, Infinity and 1e999; this catches finite doubles that
     * would become infinite as floats, and coordinates beyond LOADER_MAX_LENGTH. */
    if (!(fabs(d) <= (double)FLT_MAX))
        return fail_here(ld, "%g does not fit a 32-bit float; expected a magnitude below 3.4e38",
                         d);
    if (!(fabs(d) <= max_abs))
        return fail_here(ld, "%g is too large for a scene coordinate or length; expected a "
                             "magnitude of at most %g",
                         d, max_abs);
    *out = (float)d;
    return CST_OK;
}

static CstStatus read_vec3(Loader *ld, const json_t *v, double max_abs, Vec3 *out)
{
    char kind[48];
    if (!json_is_array(v) || json_array_size(v) != 3)
        return fail_here(ld, "got %s; expected an array of 3 numbers", describe(v, kind));
    float c[3] = {0};
    for (size_t k = 0; k < 3; k++) {
        path_push_index(ld, k);
        LOADER_TRY(read_float(ld, json_array_get(v, k), max_abs, &c[k]));
        path_pop(ld);
    }
    *out = v3(c[0], c[1], c[2]);
    return CST_OK;
}

/* An RGB triple of numbers, each >= 0 and, when max_one, <= 1. */
static CstStatus read_rgb(Loader *ld, const json_t *v, int max_one, Color *out)
{
    static const char *const channel[3] = {"red", "green", "blue"};
    Vec3 c = {0};
    LOADER_TRY(read_vec3(ld, v, (double)FLT_MAX, &c));
    for (int k = 0; k < 3; k++) {
        float x = v3_get(c, k);
        if (x < 0.0f || (max_one && x > 1.0f)) {
            path_push_index(ld, (size_t)k);
            if (max_one)
                return fail_here(ld, "%s %g is outside [0, 1] (more than 1 would create energy); "
                                     "expected a reflectance from 0 to 1",
                                 channel[k], (double)x);
            return fail_here(ld, "%s %g is negative; expected a number >= 0", channel[k], (double)x);
        }
    }
    *out = color_rgb(c.x, c.y, c.z);
    return CST_OK;
}

static CstStatus read_int(Loader *ld, const json_t *v, json_int_t lo, json_int_t hi, json_int_t *out)
{
    char kind[48];
    if (!json_is_integer(v)) {
        if (hi == LOADER_NO_MAX)
            return fail_here(ld, "got %s; expected an integer >= %" JSON_INTEGER_FORMAT,
                             describe(v, kind), lo);
        return fail_here(ld, "got %s; expected an integer from %" JSON_INTEGER_FORMAT
                             " to %" JSON_INTEGER_FORMAT,
                         describe(v, kind), lo, hi);
    }
    json_int_t i = json_integer_value(v);
    if (i < lo || i > hi) {
        if (hi == LOADER_NO_MAX)
            return fail_here(ld, "%" JSON_INTEGER_FORMAT " is out of range; expected an integer >= %"
                                 JSON_INTEGER_FORMAT, i, lo);
        return fail_here(ld, "%" JSON_INTEGER_FORMAT " is out of range; expected an integer from %"
                             JSON_INTEGER_FORMAT " to %" JSON_INTEGER_FORMAT, i, lo, hi);
    }
    *out = i;
    return CST_OK;
}

static CstStatus read_string(Loader *ld, const json_t *v, const char **out)
{
    char kind[48];
    if (!json_is_string(v))
        return fail_here(ld, "got %s; expected a string", describe(v, kind));
    *out = json_string_value(v);
    return CST_OK;
}

static CstStatus read_bool(Loader *ld, const json_t *v, int *out)
{
    char kind[48];
    if (!json_is_boolean(v))
        return fail_here(ld, "got %s; expected true or false", describe(v, kind));
    *out = json_is_true(v);
    return CST_OK;
}

static CstStatus expect_object(Loader *ld, const json_t *v, const char *what)
{
    char kind[48];
    if (!json_is_object(v))
        return fail_here(ld, "got %s; expected %s", describe(v, kind), what);
    return CST_OK;
}

/* Rejects keys not in allowed: a misspelt optional key must not silently mean "default". */
static CstStatus check_keys(Loader *ld, const json_t *obj, const char *const *allowed, int n)
{
    const char *key;
    json_t *val;
    json_object_foreach((json_t *)obj, key, val) {
        int known = 0;
        for (int i = 0; i < n && !known; i++)
            known = strcmp(key, allowed[i]) == 0;
        if (!known) {
            char list[512], name[72];
            join_names(allowed, n, list, sizeof list);
            path_push_key(ld, key);
            return fail_key(ld, "unknown key \"%s\"; expected one of: %s", clip_name(key, name),
                            list);
        }
    }
    return CST_OK;
}

/* *out = obj[key], which must exist; the error points at obj. */
static CstStatus member_required(Loader *ld, const json_t *obj, const char *key,
                                 const char *expected, json_t **out)
{
    *out = json_object_get(obj, key);
    if (!*out)
        return fail_here(ld, "missing key \"%s\"; expected %s", key, expected);
    return CST_OK;
}

/* obj["type"] as an index into names; a missing type gives default_index, or an error
 * if that is -1. */
static CstStatus read_type(Loader *ld, const json_t *obj, const char *what,
                           const char *const *names, int n, int default_index, int *out)
{
    char list[256];
    join_names(names, n, list, sizeof list);
    json_t *v = json_object_get(obj, "type");
    if (!v) {
        if (default_index >= 0) {
            *out = default_index;
            return CST_OK;
        }
        return fail_here(ld, "missing key \"type\"; expected a %s: %s", what, list);
    }
    const char *s = NULL;
    path_push_key(ld, "type");
    LOADER_TRY(read_string(ld, v, &s));
    for (int i = 0; i < n; i++)
        if (strcmp(s, names[i]) == 0) {
            path_pop(ld);
            *out = i;
            return CST_OK;
        }
    char name[72];
    return fail_here(ld, "unknown %s \"%s\"; expected one of: %s", what, clip_name(s, name), list);
}

/* ------------------------------------------------------------------ sections */

static CstStatus parse_film(Loader *ld, const json_t *film)
{
    static const char *const keys[] = {"width", "height", "filter", "output", "exposure", "png_encoding",
                                       "aovs", "crop"};
    CstRenderSettings *rs = &ld->scene->settings;
    LOADER_TRY(expect_object(ld, film,
                             "an object with width, height, filter, output, exposure, png_encoding, aovs, crop"));
    LOADER_TRY(check_keys(ld, film, keys, 8));
    json_t *v;
    json_int_t i = 0;
    if ((v = json_object_get(film, "width"))) {
        path_push_key(ld, "width");
        LOADER_TRY(read_int(ld, v, 1, LOADER_MAX_FILM_SIZE, &i));
        rs->width = (int)i;
        path_pop(ld);
    }
    if ((v = json_object_get(film, "height"))) {
        path_push_key(ld, "height");
        LOADER_TRY(read_int(ld, v, 1, LOADER_MAX_FILM_SIZE, &i));
        rs->height = (int)i;
        path_pop(ld);
    }
    if ((v = json_object_get(film, "filter"))) {
        const char *s = NULL;
        path_push_key(ld, "filter");
        LOADER_TRY(read_string(ld, v, &s));
        CstFilter f = cst_filter_from_name(s);
        if (f == CST_FILTER_DEFAULT) {
            char name[72];
            return fail_here(ld, "unknown filter \"%s\"; expected one of: box, tent, gaussian, mitchell",
                             clip_name(s, name));
        }
        rs->filter = f;
        path_pop(ld);
    }
    if ((v = json_object_get(film, "output"))) {
        const char *s = NULL;
        path_push_key(ld, "output");
        LOADER_TRY(read_string(ld, v, &s));
        /* Checked now, not when the image is written hours later: the writer picks the
         * format from the extension. */
        if (!image_path_is_scene_output(s)) {
            char name[72];
            return fail_here(ld, "output \"%s\" has no supported extension; expected a file "
                                 "name ending in .png, .exr or .pfm",
                             clip_name(s, name));
        }
        CstStatus st = scene_set_output_path(ld->scene, s, ld->err);
        if (st != CST_OK)
            return fail_builder(ld, st);
        path_pop(ld);
    }
    if ((v = json_object_get(film, "exposure"))) {
        float ev = 0.0f;
        path_push_key(ld, "exposure");
        LOADER_TRY(read_float(ld, v, 64.0, &ev));
        rs->exposure = (double)ev;
        rs->exposure_set = 1;
        path_pop(ld);
    }
    if ((v = json_object_get(film, "png_encoding"))) {
        const char *s = NULL;
        path_push_key(ld, "png_encoding");
        LOADER_TRY(read_string(ld, v, &s));
        if (strcmp(s, "srgb") != 0 && strcmp(s, "linear") != 0) {
            char name[72];
            return fail_here(ld, "unknown PNG encoding \"%s\"; expected \"srgb\" or \"linear\"", clip_name(s, name));
        }
        rs->png_linear = strcmp(s, "linear") == 0;
        path_pop(ld);
    }
    if ((v = json_object_get(film, "aovs"))) {
        path_push_key(ld, "aovs");
        if (!json_is_array(v))
            return fail_here(ld, "expected an array of AOV names (albedo, normal, depth, variance)");
        for (size_t k = 0; k < json_array_size(v); k++) {
            const char *s = NULL;
            path_push_index(ld, k);
            LOADER_TRY(read_string(ld, json_array_get(v, k), &s));
            int bit = cst_aov_from_name(s);
            if (!bit) {
                char name[72];
                return fail_here(ld, "unknown AOV \"%s\"; expected one of: albedo, normal, depth, variance",
                                 clip_name(s, name));
            }
            rs->aovs |= bit;
            path_pop(ld);
        }
        path_pop(ld);
    }
    if ((v = json_object_get(film, "crop"))) {
        /* Checked against the image size here only when the file gives both; cst_render
         * checks the final size (the command line may change it). */
        path_push_key(ld, "crop");
        if (!json_is_array(v) || json_array_size(v) != 4)
            return fail_here(ld, "expected [x0, x1, y0, y1]: the pixel bounds x0 <= x < x1, y0 <= y < y1 to render");
        for (size_t k = 0; k < 4; k++) {
            path_push_index(ld, k);
            LOADER_TRY(read_int(ld, json_array_get(v, k), 0, LOADER_MAX_FILM_SIZE, &i));
            rs->crop[k] = (int)i;
            path_pop(ld);
        }
        if (!(rs->crop[0] < rs->crop[1] && rs->crop[2] < rs->crop[3]))
            return fail_here(ld, "crop [%d, %d, %d, %d]: expected x0 < x1 and y0 < y1", rs->crop[0], rs->crop[1],
                             rs->crop[2], rs->crop[3]);
        if ((rs->width && rs->crop[1] > rs->width) || (rs->height && rs->crop[3] > rs->height))
            return fail_here(ld, "crop [%d, %d, %d, %d]: expected x1 <= width (%d) and y1 <= height (%d)", rs->crop[0],
                             rs->crop[1], rs->crop[2], rs->crop[3], rs->width, rs->height);
        path_pop(ld);
    }
    return CST_OK;
}

enum { CAMERA_PINHOLE, CAMERA_THINLENS, CAMERA_ORTHOGRAPHIC };

static CstStatus parse_camera(Loader *ld, const json_t *cam)
{
    static const char *const types[] = {"pinhole", "thinlens", "orthographic"};
    static const char *const keys[] = {"type", "position", "look_at", "up", "fov",
                                       "aperture_radius", "focus_distance"};
    static const char *const ortho_keys[] = {"type", "position", "look_at", "up", "height"};
    int type = 0;
    json_t *v;
    LOADER_TRY(expect_object(ld, cam, "a camera object"));
    LOADER_TRY(read_type(ld, cam, "camera type", types, 3, CAMERA_PINHOLE, &type));
    /* The lens keys mean nothing to a pinhole: reject rather than ignore them. */
    if (type == CAMERA_ORTHOGRAPHIC) LOADER_TRY(check_keys(ld, cam, ortho_keys, 5));
    else LOADER_TRY(check_keys(ld, cam, keys, type == CAMERA_THINLENS ? 7 : 5));

    CameraDesc desc = {0};
    desc.up = v3(0.0f, 1.0f, 0.0f);
    LOADER_TRY(member_required(ld, cam, "position", "the eye point, an array of 3 numbers", &v));
    path_push_key(ld, "position");
    LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.position));
    path_pop(ld);

    LOADER_TRY(member_required(ld, cam, "look_at", "the point looked at, an array of 3 numbers",
                               &v));
    path_push_key(ld, "look_at");
    LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.look_at));
    Vec3 forward = v3_sub(desc.look_at, desc.position);
    float dist = v3_length(forward);
    if (!(dist > 0.0f) || !isfinite(dist))
        return fail_here(ld, "look_at equals position, so there is no view direction; expected "
                             "a point other than position");
    path_pop(ld);

    if ((v = json_object_get(cam, "up"))) {
        path_push_key(ld, "up");
        LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.up));
        path_pop(ld);
    }
    /* right = normalize(forward x up) must exist: up must not be zero or along forward.
     * sin(angle) below 1e-4 (0.006 degrees) leaves the frame to rounding. */
    float ul = v3_length(desc.up);
    Vec3 c = v3_cross(v3_scale(forward, 1.0f / dist), desc.up);
    if (!(ul > 0.0f) || !isfinite(ul) || !(v3_length(c) > 1e-4f * ul)) {
        if (json_object_get(cam, "up"))
            path_push_key(ld, "up");
        return fail_here(ld, "up (%g, %g, %g) is zero or parallel to the view direction; "
                             "expected a vector not parallel to look_at - position",
                         (double)desc.up.x, (double)desc.up.y, (double)desc.up.z);
    }

    if (type == CAMERA_ORTHOGRAPHIC) {
        LOADER_TRY(member_required(ld, cam, "height", "the view's height in scene units, > 0", &v));
        path_push_key(ld, "height");
        LOADER_TRY(read_float(ld, v, LOADER_MAX_LENGTH, &desc.ortho_height));
        if (!(desc.ortho_height > 0.0f))
            return fail_here(ld, "height %g is not positive; expected the view's height in scene units, > 0",
                             (double)desc.ortho_height);
        path_pop(ld);
        desc.vfov_deg = 0.0f;
        desc.focus_distance = dist;
        scene_set_camera(ld->scene, &desc);
        return CST_OK;
    }
    LOADER_TRY(member_required(ld, cam, "fov",
                               "the vertical field of view in degrees, in (0, 180)", &v));
    path_push_key(ld, "fov");
    LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &desc.vfov_deg));
    if (!(desc.vfov_deg > 0.0f && desc.vfov_deg < 180.0f))
        return fail_here(ld, "fov %g is out of range; expected the vertical field of view in "
                             "degrees, greater than 0 and less than 180",
                         (double)desc.vfov_deg);
    path_pop(ld);

    desc.aperture_radius = 0.0f;
    desc.focus_distance = dist;
    if (type == CAMERA_THINLENS) {
        LOADER_TRY(member_required(ld, cam, "aperture_radius",
                                   "the lens radius in scene units, >= 0", &v));
        path_push_key(ld, "aperture_radius");
        LOADER_TRY(read_float(ld, v, LOADER_MAX_LENGTH, &desc.aperture_radius));
        if (desc.aperture_radius < 0.0f)
            return fail_here(ld, "aperture_radius %g is negative; expected a lens radius >= 0",
                             (double)desc.aperture_radius);
        path_pop(ld);
        if ((v = json_object_get(cam, "focus_distance"))) {
            path_push_key(ld, "focus_distance");
            LOADER_TRY(read_float(ld, v, LOADER_MAX_LENGTH, &desc.focus_distance));
            if (!(desc.focus_distance > 0.0f))
                return fail_here(ld, "focus_distance %g is not positive; expected a distance > 0",
                                 (double)desc.focus_distance);
            path_pop(ld);
        }
    }
    scene_set_camera(ld->scene, &desc);
    return CST_OK;
}

static CstStatus parse_integrator(Loader *ld, const json_t *integ)
{
    static const char *const keys[] = {"type", "max_depth", "rr_depth", "photons", "radius"};
    CstRenderSettings *rs = &ld->scene->settings;
    json_t *v;
    json_int_t i = 0;
    LOADER_TRY(expect_object(ld, integ, "an object with type, max_depth, rr_depth, photons, radius"));
    LOADER_TRY(check_keys(ld, integ, keys, 5));
    if ((v = json_object_get(integ, "type"))) {
        const char *s = NULL;
        path_push_key(ld, "type");
        LOADER_TRY(read_string(ld, v, &s));
        CstIntegrator t = cst_integrator_from_name(s);
        if (t == CST_INTEGRATOR_DEFAULT) {
            char name[72];
            return fail_here(ld, "unknown integrator \"%s\"; expected one of: path, path-nee, "
                                 "path-bsdf, light, whitted, photon, sppm, bdpt, vcm",
                             clip_name(s, name));
        }
        rs->integrator = t;
        path_pop(ld);
    }
    if ((v = json_object_get(integ, "max_depth"))) {
        path_push_key(ld, "max_depth");
        LOADER_TRY(read_int(ld, v, 0, INT_MAX, &i)); /* 0 = unbounded */
        rs->max_depth = (int)i;
        path_pop(ld);
    }
    if ((v = json_object_get(integ, "rr_depth"))) {
        /* From 1: the settings struct reads 0 as "default", which a file should not say. */
        path_push_key(ld, "rr_depth");
        LOADER_TRY(read_int(ld, v, 1, INT_MAX, &i));
        rs->rr_depth = (int)i;
        path_pop(ld);
    }
    /* Photon mapping only (ignored by the other integrators). At most 2^28 photon paths:
     * the stored photons (several per path) must stay within the photon map's 2^30. */
    if ((v = json_object_get(integ, "photons"))) {
        path_push_key(ld, "photons");
        LOADER_TRY(read_int(ld, v, 1, (json_int_t)1 << 28, &i));
        rs->photons = (int)i;
        path_pop(ld);
    }
    if ((v = json_object_get(integ, "radius"))) {
        float r = 0.0f;
        path_push_key(ld, "radius");
        LOADER_TRY(read_float(ld, v, LOADER_MAX_LENGTH, &r));
        if (!(r > 0.0f))
            return fail_here(ld, "radius %g is not positive; expected a gather radius > 0 (omit it for "
                                 "the automatic radius)",
                             (double)r);
        rs->photon_radius = (double)r;
        path_pop(ld);
    }
    return CST_OK;
}

static CstStatus parse_sampler(Loader *ld, const json_t *sampler)
{
    static const char *const keys[] = {"spp", "seed", "type"};
    CstRenderSettings *rs = &ld->scene->settings;
    json_t *v;
    json_int_t i = 0;
    LOADER_TRY(expect_object(ld, sampler, "an object with spp, seed, type"));
    LOADER_TRY(check_keys(ld, sampler, keys, 3));
    if ((v = json_object_get(sampler, "type"))) {
        const char *s = NULL;
        path_push_key(ld, "type");
        LOADER_TRY(read_string(ld, v, &s));
        rs->sampler = cst_sampler_from_name(s);
        if (rs->sampler == CST_SAMPLER_DEFAULT) {
            char name[72];
            return fail_here(ld, "unknown sampler \"%s\"; expected one of: independent, stratified, sobol",
                             clip_name(s, name));
        }
        path_pop(ld);
    }
    if ((v = json_object_get(sampler, "spp"))) {
        path_push_key(ld, "spp");
        LOADER_TRY(read_int(ld, v, 1, INT_MAX, &i));
        rs->spp = (int)i;
        path_pop(ld);
    }
    if ((v = json_object_get(sampler, "seed"))) {
        path_push_key(ld, "seed");
        LOADER_TRY(read_int(ld, v, 0, LOADER_NO_MAX, &i));
        rs->seed = (uint64_t)i;
        rs->seed_set = 1;
        path_pop(ld);
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ textures */

static CstStatus read_texture_name(Loader *ld, const char *name, int *out);

/* A checkerboard's "even" or "odd": a colour (a new constant texture) or a texture name. */
static CstStatus read_texture_operand(Loader *ld, const json_t *obj, const char *key, int *out)
{
    json_t *v;
    LOADER_TRY(member_required(ld, obj, key, "an RGB triple or a texture name", &v));
    path_push_key(ld, key);
    if (json_is_string(v)) {
        LOADER_TRY(read_texture_name(ld, json_string_value(v), out));
    } else {
        Color c;
        Texture t;
        LOADER_TRY(read_rgb(ld, v, 0, &c));
        texture_constant(&t, c);
        CstStatus st = scene_add_texture(ld->scene, &t, out, ld->err);
        if (st != CST_OK) return fail_builder(ld, st);
    }
    path_pop(ld);
    return CST_OK;
}

/* The texture object at the current path (textures.<name>). */
static CstStatus parse_texture(Loader *ld, const json_t *obj, int *out)
{
    static const char *const types[] = {"constant", "checkerboard", "image"};
    static const char *const keys_constant[] = {"type", "value"};
    static const char *const keys_checker[] = {"type", "even", "odd", "scale"};
    static const char *const keys_image[] = {"type", "file", "linear", "wrap"};
    int type = 0;
    json_t *v;
    Texture t;
    CstStatus st;
    LOADER_TRY(expect_object(ld, obj, "a texture object"));
    LOADER_TRY(read_type(ld, obj, "texture type", types, 3, -1, &type));
    if (type == TEXTURE_CONSTANT) {
        Color c;
        LOADER_TRY(check_keys(ld, obj, keys_constant, 2));
        LOADER_TRY(member_required(ld, obj, "value", "an array of 3 numbers >= 0", &v));
        path_push_key(ld, "value");
        LOADER_TRY(read_rgb(ld, v, 0, &c));
        path_pop(ld);
        texture_constant(&t, c);
    } else if (type == TEXTURE_CHECKERBOARD) {
        int even = 0, odd = 0;
        float scale = 1.0f;
        LOADER_TRY(check_keys(ld, obj, keys_checker, 4));
        if ((v = json_object_get(obj, "scale"))) {
            path_push_key(ld, "scale");
            LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &scale));
            if (!(scale > 0.0f))
                return fail_here(ld, "scale %g is not positive; expected the number of squares per "
                                     "unit of u and v, > 0", (double)scale);
            path_pop(ld);
        }
        LOADER_TRY(read_texture_operand(ld, obj, "even", &even));
        LOADER_TRY(read_texture_operand(ld, obj, "odd", &odd));
        texture_checkerboard(&t, ld->scene->textures, even, odd, scale);
    } else {
        static const char *const wraps[] = {"repeat", "clamp"};
        const char *file = NULL;
        int linear = 0;
        TextureWrap wrap = TEXTURE_WRAP_REPEAT;
        LOADER_TRY(check_keys(ld, obj, keys_image, 4));
        if ((v = json_object_get(obj, "linear"))) {
            path_push_key(ld, "linear");
            LOADER_TRY(read_bool(ld, v, &linear));
            path_pop(ld);
        }
        if ((v = json_object_get(obj, "wrap"))) {
            const char *w = NULL;
            path_push_key(ld, "wrap");
            LOADER_TRY(read_string(ld, v, &w));
            if (strcmp(w, wraps[0]) == 0) wrap = TEXTURE_WRAP_REPEAT;
            else if (strcmp(w, wraps[1]) == 0) wrap = TEXTURE_WRAP_CLAMP;
            else {
                char name[72];
                return fail_here(ld, "unknown wrap mode \"%s\"; expected one of: repeat, clamp",
                                 clip_name(w, name));
            }
            path_pop(ld);
        }
        LOADER_TRY(member_required(ld, obj, "file", "the path of an image file", &v));
        path_push_key(ld, "file");
        LOADER_TRY(read_string(ld, v, &file));
        if (!file[0]) return fail_here(ld, "the file name is empty; expected the path of an image");
        char *path = path_resolve(ld->name, file);
        if (!path) return fail_at(ld, CST_ERR_OOM, "out of memory");
        st = texture_image_load(&t, path, linear, wrap, ld->err);
        free(path);
        if (st != CST_OK) return fail_builder(ld, st);
        path_pop(ld);
    }
    st = scene_add_texture(ld->scene, &t, out, ld->err);
    if (st != CST_OK) return fail_builder(ld, st);
    return CST_OK;
}

/* Scene id of the texture called `name`, read now if it has not been. The error points at
 * the current path (the value naming it). */
static CstStatus read_texture_name(Loader *ld, const char *name, int *out)
{
    char clipped[72];
    for (int i = 0; i < ld->num_textures; i++) {
        if (strcmp(ld->tex_names[i], name) != 0) continue;
        if (ld->tex_state[i] == 2) {
            *out = ld->tex_ids[i];
            return CST_OK;
        }
        if (ld->tex_state[i] == 1)
            return fail_here(ld, "texture \"%s\" contains itself through checkerboards; expected "
                                 "no cycles", clip_name(name, clipped));
        /* Read it at its own path, then come back. */
        JsonPathStep saved[LOADER_MAX_DEPTH];
        int saved_depth = ld->depth;
        memcpy(saved, ld->path, sizeof saved);
        ld->depth = 0;
        path_push_key(ld, "textures");
        path_push_key(ld, ld->tex_names[i]);
        ld->tex_state[i] = 1;
        LOADER_TRY(parse_texture(ld, json_object_get(ld->tex_obj, ld->tex_names[i]), &ld->tex_ids[i]));
        ld->tex_state[i] = 2;
        memcpy(ld->path, saved, sizeof saved);
        ld->depth = saved_depth;
        *out = ld->tex_ids[i];
        return CST_OK;
    }
    if (ld->num_textures == 0)
        return fail_here(ld, "texture \"%s\" is not defined (no textures are); expected a name "
                             "defined under \"textures\"", clip_name(name, clipped));
    char list[512];
    join_names(ld->tex_names, ld->num_textures, list, sizeof list);
    return fail_here(ld, "texture \"%s\" is not defined; expected one of: %s", clip_name(name, clipped), list);
}

static CstStatus parse_textures(Loader *ld, const json_t *texs)
{
    LOADER_TRY(expect_object(ld, texs, "an object mapping texture names to textures"));
    size_t n = json_object_size(texs);
    if (n > (size_t)INT_MAX / 2)
        return fail_here(ld, "too many textures");
    ld->tex_obj = texs;
    ld->tex_names = malloc((n ? n : 1) * sizeof *ld->tex_names);
    ld->tex_state = calloc(n ? n : 1, sizeof *ld->tex_state);
    ld->tex_ids = calloc(n ? n : 1, sizeof *ld->tex_ids);
    if (!ld->tex_names || !ld->tex_state || !ld->tex_ids)
        return fail_at(ld, CST_ERR_OOM, "out of memory");
    const char *name;
    json_t *v;
    json_object_foreach((json_t *)texs, name, v) ld->tex_names[ld->num_textures++] = name;
    /* Every texture is read (and so checked) even when nothing uses it. */
    for (int i = 0; i < ld->num_textures; i++) {
        int id;
        LOADER_TRY(read_texture_name(ld, ld->tex_names[i], &id));
    }
    return CST_OK;
}

/* A material parameter given as a texture name: its id + 1 (Material's convention), after
 * checking the texture's values fit the parameter (at most 1 for reflectances and
 * roughness). The current path is the parameter's value. */
static CstStatus read_param_texture(Loader *ld, const json_t *v, const char *what, int *out)
{
    int id = 0;
    LOADER_TRY(read_texture_name(ld, json_string_value(v), &id));
    Color mx = ld->scene->textures[id].max;
    if (color_max(mx) > 1.0f) {
        char clipped[72];
        return fail_here(ld, "texture \"%s\" has values up to %g; expected %s, at most 1",
                         clip_name(json_string_value(v), clipped), (double)color_max(mx), what);
    }
    *out = id + 1;
    return CST_OK;
}

enum { MAT_DIFFUSE, MAT_MIRROR, MAT_GLASS, MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_PLASTIC, MAT_COUNT };

/* "roughness": perceptual, in [0, 1] (material.h: alpha = roughness^2). */
static CstStatus read_roughness(Loader *ld, const json_t *v, float *out)
{
    path_push_key(ld, "roughness");
    LOADER_TRY(read_float(ld, v, (double)FLT_MAX, out));
    if (!(*out >= 0.0f && *out <= 1.0f))
        return fail_here(ld, "roughness %g is outside [0, 1]; expected 0 (smooth) to 1 (roughest)",
                         (double)*out);
    path_pop(ld);
    return CST_OK;
}

static CstStatus parse_material(Loader *ld, const json_t *obj, Material *m)
{
    static const char *const types[] = {"diffuse", "mirror", "glass", "conductor", "dielectric", "plastic"};
    static const MaterialType mtype[] = {MATERIAL_DIFFUSE, MATERIAL_MIRROR, MATERIAL_GLASS,
                                         MATERIAL_CONDUCTOR, MATERIAL_DIELECTRIC, MATERIAL_PLASTIC};
    /* The keys each type accepts, "type" first. */
    static const char *const keys_diffuse[] = {"type", "albedo", "two_sided"};
    static const char *const keys_glass[] = {"type", "albedo", "ior"};
    static const char *const keys_conductor[] = {"type", "metal", "eta", "k", "roughness", "two_sided"};
    static const char *const keys_dielectric[] = {"type", "albedo", "ior", "roughness"};
    static const char *const keys_plastic[] = {"type", "albedo", "ior", "roughness", "two_sided"};
    static const char *const *const keys[] = {keys_diffuse, keys_diffuse, keys_glass,
                                              keys_conductor, keys_dielectric, keys_plastic};
    static const int nkeys[] = {3, 3, 3, 6, 4, 5};
    int type = 0;
    json_t *v;
    LOADER_TRY(expect_object(ld, obj, "a material object"));
    LOADER_TRY(read_type(ld, obj, "material type", types, MAT_COUNT, -1, &type));
    LOADER_TRY(check_keys(ld, obj, keys[type], nkeys[type]));
    m->type = mtype[type];
    m->albedo = type == MAT_DIFFUSE ? color_s(0.5f) : type == MAT_PLASTIC ? color_s(0.5f) : color_s(1.0f);
    m->ior = type == MAT_GLASS || type == MAT_DIELECTRIC || type == MAT_PLASTIC ? 1.5f : 1.0f;
    m->roughness = 0.0f;
    if ((v = json_object_get(obj, "albedo"))) {
        /* A reflectance above 1 would make any of these create energy. */
        path_push_key(ld, "albedo");
        if (json_is_string(v))
            LOADER_TRY(read_param_texture(ld, v, "a reflectance", &m->albedo_texture));
        else
            LOADER_TRY(read_rgb(ld, v, 1, &m->albedo));
        path_pop(ld);
    }
    if ((v = json_object_get(obj, "ior"))) {
        path_push_key(ld, "ior");
        LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &m->ior));
        if (!(m->ior > 0.0f))
            return fail_here(ld, "ior %g is not positive; expected an index of refraction > 0 "
                                 "(glass is about 1.5)",
                             (double)m->ior);
        /* The coat model (bsdf.c) needs light to enter a denser layer. */
        if (type == MAT_PLASTIC && !(m->ior >= 1.0f))
            return fail_here(ld, "ior %g is below 1; expected the coat's index of refraction >= 1 "
                                 "(plastics are about 1.5)",
                             (double)m->ior);
        path_pop(ld);
    }
    if ((v = json_object_get(obj, "roughness"))) {
        if (json_is_string(v)) {
            path_push_key(ld, "roughness");
            if (type == MAT_PLASTIC)
                return fail_here(ld, "a plastic's roughness cannot be a texture (its coat albedo "
                                     "table is made for one roughness); expected a number from 0 to 1");
            LOADER_TRY(read_param_texture(ld, v, "a roughness", &m->roughness_texture));
            path_pop(ld);
        } else {
            LOADER_TRY(read_roughness(ld, v, &m->roughness));
        }
    }
    if ((v = json_object_get(obj, "two_sided"))) {
        int two = 1;
        path_push_key(ld, "two_sided");
        LOADER_TRY(read_bool(ld, v, &two));
        m->one_sided = !two;
        path_pop(ld);
    }
    if (type == MAT_CONDUCTOR) {
        json_t *metal = json_object_get(obj, "metal"), *eta = json_object_get(obj, "eta"),
               *k = json_object_get(obj, "k");
        char list[128];
        join_names(material_metal_names, 4, list, sizeof list);
        if (metal && (eta || k))
            return fail_here(ld, "both \"metal\" and \"eta\"/\"k\"; expected either a named metal "
                                 "(%s) or \"eta\" and \"k\"",
                             list);
        if (metal) {
            const char *name = NULL;
            path_push_key(ld, "metal");
            LOADER_TRY(read_string(ld, metal, &name));
            if (!material_metal(name, &m->eta, &m->k)) {
                char clipped[72];
                return fail_here(ld, "unknown metal \"%s\"; expected one of: %s", clip_name(name, clipped), list);
            }
            path_pop(ld);
        } else if (eta && k) {
            /* A complex IOR: eta >= 0 and k >= 0 per channel. */
            path_push_key(ld, "eta");
            LOADER_TRY(read_rgb(ld, eta, 0, &m->eta));
            path_pop(ld);
            path_push_key(ld, "k");
            LOADER_TRY(read_rgb(ld, k, 0, &m->k));
            path_pop(ld);
        } else {
            return fail_here(ld, "missing key \"%s\"; expected a named metal (\"metal\": one of %s) or "
                                 "a complex IOR (\"eta\" and \"k\", RGB triples)",
                             eta ? "k" : k ? "eta" : "metal", list);
        }
    }
    return CST_OK;
}

static CstStatus parse_materials(Loader *ld, const json_t *mats)
{
    LOADER_TRY(expect_object(ld, mats, "an object mapping material names to materials"));
    size_t n = json_object_size(mats);
    if (n > (size_t)INT_MAX)
        return fail_here(ld, "too many materials");
    ld->mat_names = malloc((n ? n : 1) * sizeof *ld->mat_names);
    ld->mat_ids = malloc((n ? n : 1) * sizeof *ld->mat_ids);
    if (!ld->mat_names || !ld->mat_ids)
        return fail_at(ld, CST_ERR_OOM, "out of memory");
    const char *name;
    json_t *v;
    json_object_foreach((json_t *)mats, name, v) {
        Material m = {0};
        int id = 0;
        path_push_key(ld, name);
        LOADER_TRY(parse_material(ld, v, &m));
        CstStatus st = scene_add_material(ld->scene, &m, &id, ld->err);
        if (st != CST_OK)
            return fail_builder(ld, st);
        path_pop(ld);
        ld->mat_names[ld->num_materials] = name;
        ld->mat_ids[ld->num_materials] = id;
        ld->num_materials++;
    }
    return CST_OK;
}

/* shape["material"] -> scene material id. */
static CstStatus read_material_ref(Loader *ld, const json_t *shape, int *out)
{
    json_t *v;
    const char *s = NULL;
    LOADER_TRY(member_required(ld, shape, "material", "the name of a material", &v));
    path_push_key(ld, "material");
    LOADER_TRY(read_string(ld, v, &s));
    for (int i = 0; i < ld->num_materials; i++)
        if (strcmp(ld->mat_names[i], s) == 0) {
            *out = ld->mat_ids[i];
            path_pop(ld);
            return CST_OK;
        }
    char name[72];
    if (ld->num_materials == 0)
        return fail_here(ld, "material \"%s\" is not defined (no materials are); expected a name "
                             "defined under \"materials\"",
                         clip_name(s, name));
    char list[512];
    join_names(ld->mat_names, ld->num_materials, list, sizeof list);
    return fail_here(ld, "material \"%s\" is not defined; expected one of: %s", clip_name(s, name),
                     list);
}

static CstStatus read_emission(Loader *ld, const json_t *shape, Emission *em)
{
    static const char *const keys[] = {"radiance", "two_sided", "scale"};
    json_t *obj = json_object_get(shape, "emission"), *v;
    em->radiance = color_s(0.0f);
    em->two_sided = 0;
    em->texture = 0;
    if (!obj)
        return CST_OK;
    path_push_key(ld, "emission");
    LOADER_TRY(expect_object(ld, obj, "an object with radiance, two_sided, scale"));
    LOADER_TRY(check_keys(ld, obj, keys, 3));
    LOADER_TRY(member_required(ld, obj, "radiance", "an array of 3 numbers >= 0 or a texture name", &v));
    path_push_key(ld, "radiance");
    if (json_is_string(v)) {
        int id = 0;
        LOADER_TRY(read_texture_name(ld, json_string_value(v), &id));
        em->texture = id + 1;
        em->radiance = color_s(1.0f);
    } else {
        LOADER_TRY(read_rgb(ld, v, 0, &em->radiance));
    }
    path_pop(ld);
    if ((v = json_object_get(obj, "scale"))) {
        float k = 1.0f;
        path_push_key(ld, "scale");
        LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &k));
        if (!(k >= 0.0f)) return fail_here(ld, "scale %g is negative; expected a number >= 0", (double)k);
        em->radiance = color_scale(em->radiance, k);
        path_pop(ld);
    }
    if ((v = json_object_get(obj, "two_sided"))) {
        path_push_key(ld, "two_sided");
        LOADER_TRY(read_bool(ld, v, &em->two_sided));
        path_pop(ld);
    }
    path_pop(ld);
    return CST_OK;
}

/* Triangle (a, b, c) has an area > 0, the same test the builder applies. */
static int triangle_ok(Vec3 a, Vec3 b, Vec3 c)
{
    float area = triangle_area(a, b, c);
    return area > 0.0f && isfinite(area);
}

static CstStatus parse_quad(Loader *ld, const json_t *shape, int material, const Emission *em)
{
    json_t *arr;
    Vec3 v[4] = {{0}};
    char kind[48];
    LOADER_TRY(member_required(ld, shape, "vertices", "4 vertices, each an array of 3 numbers",
                               &arr));
    path_push_key(ld, "vertices");
    if (!json_is_array(arr) || json_array_size(arr) != 4)
        return fail_here(ld, "got %s; expected 4 vertices, each an array of 3 numbers",
                         describe(arr, kind));
    for (size_t k = 0; k < 4; k++) {
        path_push_index(ld, k);
        LOADER_TRY(read_vec3(ld, json_array_get(arr, k), LOADER_MAX_LENGTH, &v[k]));
        path_pop(ld);
    }
    /* The builder splits the quad along v0-v2 into (v0, v1, v2) and (v0, v2, v3). */
    if (!triangle_ok(v[0], v[1], v[2]))
        return fail_here(ld, "triangle 0 of the quad (v0, v1, v2) is degenerate (zero area); "
                             "expected 4 vertices in order around a quad of nonzero area");
    if (!triangle_ok(v[0], v[2], v[3]))
        return fail_here(ld, "triangle 1 of the quad (v0, v2, v3) is degenerate (zero area); "
                             "expected 4 vertices in order around a quad of nonzero area");
    /* Checked in double: the cancellation in these differences is what we measure. */
    double e1[3], e2[3], e3[3], n0[3], n1[3], d13[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)v3_get(v[1], k) - (double)v3_get(v[0], k);
        e2[k] = (double)v3_get(v[2], k) - (double)v3_get(v[0], k);
        e3[k] = (double)v3_get(v[3], k) - (double)v3_get(v[0], k);
        d13[k] = (double)v3_get(v[3], k) - (double)v3_get(v[1], k);
    }
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        n0[k] = e1[a] * e2[b] - e1[b] * e2[a]; /* (v1 - v0) x (v2 - v0) */
        n1[k] = e2[a] * e3[b] - e2[b] * e3[a]; /* (v2 - v0) x (v3 - v0) */
    }
    double dot01 = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2];
    if (!(dot01 > 0.0))
        return fail_here(ld, "the quad's triangles (v0, v1, v2) and (v0, v2, v3) face opposite "
                             "ways; expected vertices in order around the quad (not crossing)");
    double n0_len = sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]);
    double off = fabs(e3[0] * n0[0] + e3[1] * n0[1] + e3[2] * n0[2]) / n0_len;
    double diag = fmax(sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]),
                       sqrt(d13[0] * d13[0] + d13[1] * d13[1] + d13[2] * d13[2]));
    double tol = LOADER_QUAD_PLANARITY_TOL * diag;
    if (off > tol)
        return fail_here(ld, "the quad is not planar: v3 is %g off the plane of v0, v1, v2 (more "
                             "than %g, 1%% of its longer diagonal); expected 4 coplanar vertices",
                         off, tol);
    path_pop(ld);
    CstStatus st = scene_add_quad(ld->scene, v, material, em, ld->err);
    return st == CST_OK ? CST_OK : fail_builder(ld, st);
}

static CstStatus read_mesh_indices(Loader *ld, const json_t *arr, int num_vertices, Vec3 *pos,
                                   int *idx)
{
    char kind[48];
    size_t t;
    json_t *tri;
    json_array_foreach(arr, t, tri) {
        path_push_index(ld, t);
        if (!json_is_array(tri) || json_array_size(tri) != 3)
            return fail_here(ld, "got %s; expected a triangle, an array of 3 vertex indices",
                             describe(tri, kind));
        for (size_t k = 0; k < 3; k++) {
            json_t *iv = json_array_get(tri, k);
            path_push_index(ld, k);
            if (!json_is_integer(iv))
                return fail_here(ld, "got %s; expected a vertex index, an integer from 0 to %d",
                                 describe(iv, kind), num_vertices - 1);
            json_int_t i = json_integer_value(iv);
            if (i < 0 || i >= num_vertices)
                return fail_here(ld, "vertex index %" JSON_INTEGER_FORMAT " is out of range; "
                                     "expected 0 to %d (the mesh has %d vertices)",
                                 i, num_vertices - 1, num_vertices);
            idx[3 * t + k] = (int)i;
            path_pop(ld);
        }
        if (!triangle_ok(pos[idx[3 * t]], pos[idx[3 * t + 1]], pos[idx[3 * t + 2]]))
            return fail_here(ld, "triangle %zu is degenerate (zero area); expected 3 distinct, "
                                 "non-collinear vertices",
                             t);
        path_pop(ld);
    }
    return CST_OK;
}

/* An inline mesh's "normals": one nonzero vector per vertex, stored normalised. */
static CstStatus read_mesh_normals(Loader *ld, const json_t *narr, size_t nv, Vec3 **out)
{
    char kind[48];
    path_push_key(ld, "normals");
    if (!json_is_array(narr) || json_array_size(narr) != nv)
        return fail_here(ld, "got %s; expected an array of %zu normals (one per vertex), each an "
                             "array of 3 numbers",
                         describe(narr, kind), nv);
    Vec3 *n = malloc(nv * sizeof *n);
    if (!n) return fail_at(ld, CST_ERR_OOM, "out of memory for %zu normals", nv);
    for (size_t k = 0; k < nv; k++) {
        path_push_index(ld, k);
        CstStatus st = read_vec3(ld, json_array_get(narr, k), LOADER_MAX_LENGTH, &n[k]);
        if (st == CST_OK && !(v3_max_abs(n[k]) > 0.0f))
            st = fail_here(ld, "the normal is zero; expected a nonzero vector");
        if (st != CST_OK) {
            free(n);
            return st;
        }
        /* Scaled first, so tiny or huge normals normalise without under- or overflow. */
        n[k] = v3_normalize(v3_scale(n[k], 1.0f / v3_max_abs(n[k])));
        path_pop(ld);
    }
    path_pop(ld);
    *out = n;
    return CST_OK;
}

/* A mesh's "shading": "smooth" (default) makes its vertex normals shading normals; "flat"
 * drops them, so the mesh shades with its geometric normals. */
static CstStatus read_shading(Loader *ld, const json_t *shape, bool *flat)
{
    json_t *v = json_object_get(shape, "shading");
    *flat = false;
    if (!v) return CST_OK;
    const char *sv = NULL;
    path_push_key(ld, "shading");
    LOADER_TRY(read_string(ld, v, &sv));
    if (strcmp(sv, "flat") == 0) {
        *flat = true;
    } else if (strcmp(sv, "smooth") != 0) {
        char name[72];
        return fail_here(ld, "unknown shading \"%s\"; expected one of: smooth, flat", clip_name(sv, name));
    }
    path_pop(ld);
    return CST_OK;
}

static CstStatus parse_mesh(Loader *ld, const json_t *shape, int material, const Emission *em)
{
    json_t *varr, *iarr;
    char kind[48];
    LOADER_TRY(member_required(ld, shape, "vertices",
                               "an array of vertices, each an array of 3 numbers", &varr));
    LOADER_TRY(member_required(ld, shape, "indices",
                               "an array of triangles, each an array of 3 vertex indices", &iarr));
    path_push_key(ld, "vertices");
    if (!json_is_array(varr) || json_array_size(varr) < 3)
        return fail_here(ld, "got %s; expected at least 3 vertices, each an array of 3 numbers",
                         describe(varr, kind));
    path_pop(ld);
    path_push_key(ld, "indices");
    if (!json_is_array(iarr) || json_array_size(iarr) == 0)
        return fail_here(ld, "got %s; expected at least 1 triangle, each an array of 3 vertex "
                             "indices",
                         describe(iarr, kind));
    path_pop(ld);
    size_t nv = json_array_size(varr), nt = json_array_size(iarr);
    /* The builder counts in int, 3 indices per triangle. */
    if (nv > (size_t)INT_MAX || nt > (size_t)(INT_MAX / 3))
        return fail_here(ld, "the mesh is too large; expected fewer than %d triangles", INT_MAX / 3);

    CstStatus st = CST_OK;
    json_t *uarr = json_object_get(shape, "uvs");
    Vec3 *pos = malloc(nv * sizeof *pos), *nrm = NULL;
    int *idx = malloc(nt * 3 * sizeof *idx);
    Vec2 *uvs = uarr ? malloc(nv * sizeof *uvs) : NULL;
    if (!pos || !idx || (uarr && !uvs)) {
        st = fail_at(ld, CST_ERR_OOM, "out of memory for %zu vertices and %zu triangles", nv, nt);
        goto done;
    }
    path_push_key(ld, "vertices");
    for (size_t k = 0; k < nv; k++) {
        path_push_index(ld, k);
        st = read_vec3(ld, json_array_get(varr, k), LOADER_MAX_LENGTH, &pos[k]);
        if (st != CST_OK)
            goto done;
        path_pop(ld);
    }
    path_pop(ld);
    path_push_key(ld, "indices");
    st = read_mesh_indices(ld, iarr, (int)nv, pos, idx);
    if (st != CST_OK)
        goto done;
    path_pop(ld);
    if (uarr) {
        /* Texture coordinates, one [u, v] per vertex. */
        path_push_key(ld, "uvs");
        if (!json_is_array(uarr) || json_array_size(uarr) != nv) {
            st = fail_here(ld, "got %s; expected one [u, v] per vertex (%zu)", describe(uarr, kind), nv);
            goto done;
        }
        for (size_t k = 0; k < nv; k++) {
            json_t *e = json_array_get(uarr, k);
            float c[2] = {0.0f, 0.0f};
            path_push_index(ld, k);
            if (!json_is_array(e) || json_array_size(e) != 2) {
                st = fail_here(ld, "got %s; expected an array of 2 numbers", describe(e, kind));
                goto done;
            }
            for (size_t j = 0; j < 2; j++) {
                path_push_index(ld, j);
                st = read_float(ld, json_array_get(e, j), (double)FLT_MAX, &c[j]);
                if (st != CST_OK)
                    goto done;
                path_pop(ld);
            }
            uvs[k] = v2(c[0], c[1]);
            path_pop(ld);
        }
        path_pop(ld);
    }
    bool flat = false;
    if ((st = read_shading(ld, shape, &flat)) != CST_OK)
        goto done;
    json_t *narr = json_object_get(shape, "normals");
    if (narr && (st = read_mesh_normals(ld, narr, nv, &nrm)) != CST_OK)
        goto done;
    SceneMesh sm = {0};
    sm.positions = pos;
    sm.num_vertices = (int)nv;
    sm.uvs = uvs;
    sm.normals = flat ? NULL : nrm;
    sm.indices = idx;
    sm.num_triangles = (int)nt;
    sm.material = material;
    sm.emission = em;
    st = scene_add_mesh_ex(ld->scene, &sm, NULL, ld->err);
    if (st != CST_OK)
        st = fail_builder(ld, st);
done:
    free(pos);
    free(idx);
    free(uvs);
    free(nrm);
    return st;
}

static CstStatus parse_sphere(Loader *ld, const json_t *shape, int material, const Emission *em)
{
    json_t *v;
    Vec3 center = {0};
    float radius = 0.0f;
    LOADER_TRY(member_required(ld, shape, "center", "an array of 3 numbers", &v));
    path_push_key(ld, "center");
    LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &center));
    path_pop(ld);
    LOADER_TRY(member_required(ld, shape, "radius", "a number > 0", &v));
    path_push_key(ld, "radius");
    LOADER_TRY(read_float(ld, v, LOADER_MAX_LENGTH, &radius));
    if (!(radius > 0.0f))
        return fail_here(ld, "radius %g is not positive; expected a number > 0", (double)radius);
    if (!(radius >= (float)LOADER_MIN_RADIUS))
        return fail_here(ld, "radius %g is too small (its area would underflow a 32-bit float); "
                             "expected a radius of at least %g",
                         (double)radius, LOADER_MIN_RADIUS);
    path_pop(ld);
    CstStatus st = scene_add_sphere(ld->scene, center, radius, material, em, ld->err);
    return st == CST_OK ? CST_OK : fail_builder(ld, st);
}

/* One rotation {"axis": [x, y, z], "angle": degrees}. */
static CstStatus read_rotation(Loader *ld, const json_t *obj, Transform *out)
{
    static const char *const keys[] = {"axis", "angle"};
    json_t *v;
    Vec3 axis = {0};
    float angle = 0.0f;
    LOADER_TRY(expect_object(ld, obj, "a rotation, an object with axis and angle"));
    LOADER_TRY(check_keys(ld, obj, keys, 2));
    LOADER_TRY(member_required(ld, obj, "axis", "the rotation axis, an array of 3 numbers", &v));
    path_push_key(ld, "axis");
    LOADER_TRY(read_vec3(ld, v, (double)FLT_MAX, &axis));
    if (!(v3_max_abs(axis) > 0.0f))
        return fail_here(ld, "the axis is zero; expected a nonzero vector");
    path_pop(ld);
    LOADER_TRY(member_required(ld, obj, "angle", "the rotation angle in degrees", &v));
    path_push_key(ld, "angle");
    LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &angle));
    path_pop(ld);
    *out = transform_rotate_degrees(axis, (double)angle);
    return CST_OK;
}

/* "transform": {"scale", "rotate", "translate"} applied in that order, or {"matrix"}. */
static CstStatus parse_transform(Loader *ld, const json_t *obj, Transform *out)
{
    static const char *const keys[] = {"translate", "rotate", "scale", "matrix"};
    char kind[48];
    json_t *v;
    LOADER_TRY(expect_object(ld, obj,
                             "an object with translate, rotate and scale, or with matrix"));
    LOADER_TRY(check_keys(ld, obj, keys, 4));
    Transform t = transform_identity();
    if ((v = json_object_get(obj, "matrix"))) {
        for (int k = 0; k < 3; k++)
            if (json_object_get(obj, keys[k])) {
                path_push_key(ld, keys[k]);
                return fail_key(ld, "\"%s\" cannot be combined with \"matrix\"; expected either "
                                    "a matrix or translate, rotate and scale", keys[k]);
            }
        path_push_key(ld, "matrix");
        if (!json_is_array(v) || json_array_size(v) != 16)
            return fail_here(ld, "got %s; expected 16 numbers, a 4x4 matrix row by row",
                             describe(v, kind));
        float rows[16];
        for (size_t k = 0; k < 16; k++) {
            path_push_index(ld, k);
            LOADER_TRY(read_float(ld, json_array_get(v, k), (double)FLT_MAX, &rows[k]));
            path_pop(ld);
        }
        static const float bottom[4] = {0.0f, 0.0f, 0.0f, 1.0f};
        for (size_t k = 12; k < 16; k++)
            if (rows[k] != bottom[k - 12]) {
                path_push_index(ld, k);
                return fail_here(ld, "element %g of the bottom row is not %g; expected an affine "
                                     "matrix, bottom row 0, 0, 0, 1",
                                 (double)rows[k], (double)bottom[k - 12]);
            }
        t = transform_from_rows(rows);
        path_pop(ld);
    } else {
        if ((v = json_object_get(obj, "scale"))) {
            Vec3 sc = {0};
            path_push_key(ld, "scale");
            if (json_is_number(v)) {
                float f = 0.0f;
                LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &f));
                sc = v3s(f);
            } else if (json_is_array(v)) {
                LOADER_TRY(read_vec3(ld, v, (double)FLT_MAX, &sc));
            } else {
                return fail_here(ld, "got %s; expected a number or an array of 3 numbers",
                                 describe(v, kind));
            }
            for (int k = 0; k < 3; k++)
                if (v3_get(sc, k) == 0.0f) {
                    if (json_is_array(v))
                        path_push_index(ld, (size_t)k);
                    return fail_here(ld, "scale 0 flattens the mesh; expected a nonzero number "
                                         "(a negative one mirrors)");
                }
            t = transform_scale(sc);
            path_pop(ld);
        }
        if ((v = json_object_get(obj, "rotate"))) {
            Transform r = transform_identity();
            path_push_key(ld, "rotate");
            if (json_is_array(v)) {
                if (json_array_size(v) == 0)
                    return fail_here(ld, "got an empty array; expected a rotation or an array "
                                         "of rotations, each an object with axis and angle");
                size_t i;
                json_t *rv;
                json_array_foreach(v, i, rv) {
                    path_push_index(ld, i);
                    LOADER_TRY(read_rotation(ld, rv, &r));
                    t = transform_compose(r, t); /* the list in order: first applied first */
                    path_pop(ld);
                }
            } else {
                LOADER_TRY(read_rotation(ld, v, &r));
                t = transform_compose(r, t);
            }
            path_pop(ld);
        }
        if ((v = json_object_get(obj, "translate"))) {
            Vec3 d = {0};
            path_push_key(ld, "translate");
            LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &d));
            t = transform_compose(transform_translate(d), t);
            path_pop(ld);
        }
    }
    Transform nm;
    if (!transform_normal_matrix(&t, &nm))
        return fail_here(ld, "the transform is singular (determinant %g) or not invertible in "
                             "32-bit floats, so it flattens the mesh; expected an invertible "
                             "transform",
                         transform_det(&t));
    *out = t;
    return CST_OK;
}

/* Applies the shape's transform to the imported mesh in place; a mirroring transform gets
 * the triangles' winding swapped back so that outside stays outside (the geometric normal
 * is (b - a) x (c - a)). */
static void transform_mesh(ImportedMesh *im, const Transform *t)
{
    Transform nm = transform_identity();
    transform_normal_matrix(t, &nm); /* checked invertible by parse_transform */
    for (int i = 0; i < im->num_vertices; i++)
        im->positions[i] = transform_point(t, im->positions[i]);
    for (int i = 0; im->normals && i < im->num_vertices; i++)
        im->normals[i] = transform_normal(&nm, im->normals[i]);
    if (transform_det(t) < 0.0)
        for (int i = 0; i < im->num_triangles; i++) {
            int32_t tmp = im->indices[3 * i + 1];
            im->indices[3 * i + 1] = im->indices[3 * i + 2];
            im->indices[3 * i + 2] = tmp;
        }
}

/* Scene material ids for the file's materials, added to the scene on first use. Fails
 * at the shape when a triangle has only assimp's stand-in material. */
static CstStatus file_materials(Loader *ld, const ImportedMesh *im, int *tri_ids)
{
    int *ids = malloc((size_t)(im->num_materials > 0 ? im->num_materials : 1) * sizeof *ids);
    if (!ids)
        return fail_at(ld, CST_ERR_OOM, "out of memory");
    for (int i = 0; i < im->num_materials; i++)
        ids[i] = -1;
    CstStatus st = CST_OK;
    for (int t = 0; t < im->num_triangles && st == CST_OK; t++) {
        const ImportedMaterial *fm = &im->materials[im->tri_material[t]];
        int *id = &ids[im->tri_material[t]];
        if (*id < 0 && !fm->from_file) {
            st = fail_here(ld, "missing key \"material\": the mesh file names no material for "
                               "its triangle %d; expected the name of a material for the whole "
                               "mesh",
                           t);
        } else if (*id < 0) {
            Material m = {0};
            m.type = (MaterialType)fm->type;
            m.albedo = fm->albedo;
            m.ior = fm->ior;
            st = scene_add_material(ld->scene, &m, id, ld->err);
            if (st != CST_OK)
                st = fail_builder(ld, st);
        }
        tri_ids[t] = *id;
    }
    free(ids);
    return st;
}

static CstStatus parse_meshfile(Loader *ld, const json_t *shape, int material, const Emission *em)
{
    json_t *fv, *v;
    const char *file = NULL;
    Transform xf = transform_identity();
    LOADER_TRY(member_required(ld, shape, "file",
                               "the path of a mesh file (OBJ, PLY, glTF, ...), relative to the "
                               "scene file",
                               &fv));
    if ((v = json_object_get(shape, "transform"))) {
        path_push_key(ld, "transform");
        LOADER_TRY(parse_transform(ld, v, &xf));
        path_pop(ld);
    }
    bool flat = false;
    LOADER_TRY(read_shading(ld, shape, &flat));
    path_push_key(ld, "file");
    LOADER_TRY(read_string(ld, fv, &file));
    if (!file[0])
        return fail_here(ld, "the file name is empty; expected the path of a mesh file");
    char *path = path_resolve(ld->name, file);
    if (!path)
        return fail_at(ld, CST_ERR_OOM, "out of memory");
    ImportedMesh im = {0};
    int *tri_ids = NULL;
    CstStatus st = mesh_import(path, &im, ld->err);
    if (st != CST_OK) {
        st = fail_builder(ld, st); /* "<json>:l:c: shapes[i].file: <resolved path>: ..." */
        goto done;
    }
    if (!transform_is_identity(&xf))
        transform_mesh(&im, &xf);
    for (int i = 0; i < im.num_vertices; i++) {
        Vec3 p = im.positions[i];
        if (!v3_is_finite(p) || !((double)v3_max_abs(p) <= LOADER_MAX_LENGTH)) {
            st = fail_here(ld, "vertex %d of the mesh is at (%g, %g, %g)%s, beyond the scene "
                               "limit; expected coordinates of magnitude at most %g",
                           i, (double)p.x, (double)p.y, (double)p.z,
                           json_object_get(shape, "transform") ? " after the transform" : "",
                           LOADER_MAX_LENGTH);
            goto done;
        }
    }
    if (material < 0) {
        tri_ids = malloc((size_t)im.num_triangles * sizeof *tri_ids);
        if (!tri_ids) {
            st = fail_at(ld, CST_ERR_OOM, "out of memory");
            goto done;
        }
        path_pop(ld); /* a missing material is the shape's error, not the file's */
        st = file_materials(ld, &im, tri_ids);
        path_push_key(ld, "file");
        if (st != CST_OK)
            goto done;
    }
    SceneMesh sm = {0};
    sm.positions = im.positions;
    sm.num_vertices = im.num_vertices;
    sm.normals = flat ? NULL : im.normals;
    sm.uvs = im.uvs;
    sm.normals_partial = !flat && im.normals_partial;
    sm.uvs_partial = im.uvs_partial;
    sm.indices = im.indices;
    sm.num_triangles = im.num_triangles;
    sm.material = material;
    sm.tri_material = tri_ids;
    sm.emission = em;
    sm.skip_degenerate = 1; /* scanned meshes have some; documented in scene-format.md */
    int dropped = 0;
    st = scene_add_mesh_ex(ld->scene, &sm, &dropped, ld->err);
    if (st != CST_OK) {
        st = fail_builder(ld, st);
    } else if (dropped == im.num_triangles) {
        st = fail_here(ld, "all %d triangles of the mesh are degenerate (zero area)%s; expected "
                           "a mesh with some area",
                       dropped, json_object_get(shape, "transform") ? " after the transform" : "");
    } else {
        path_pop(ld);
    }
done:
    free(tri_ids);
    mesh_import_free(&im);
    free(path);
    return st;
}

enum { SHAPE_QUAD, SHAPE_MESH, SHAPE_SPHERE, SHAPE_MESHFILE };

static CstStatus parse_shape(Loader *ld, const json_t *shape)
{
    static const char *const types[] = {"quad", "mesh", "sphere", "meshfile"};
    static const char *const quad_keys[] = {"type", "vertices", "material", "emission"};
    static const char *const mesh_keys[] = {"type", "vertices", "indices", "uvs", "material", "emission",
                                            "normals", "shading"};
    static const char *const sphere_keys[] = {"type", "center", "radius", "material", "emission"};
    static const char *const meshfile_keys[] = {"type", "file", "material", "emission",
                                                "transform", "shading"};
    int type = 0, material = -1;
    Emission em = {0};
    LOADER_TRY(expect_object(ld, shape, "a shape object"));
    LOADER_TRY(read_type(ld, shape, "shape type", types, 4, -1, &type));
    switch (type) {
    case SHAPE_QUAD: LOADER_TRY(check_keys(ld, shape, quad_keys, 4)); break;
    case SHAPE_MESH: LOADER_TRY(check_keys(ld, shape, mesh_keys, 8)); break;
    case SHAPE_MESHFILE: LOADER_TRY(check_keys(ld, shape, meshfile_keys, 6)); break;
    default: LOADER_TRY(check_keys(ld, shape, sphere_keys, 5)); break;
    }
    /* A mesh file may bring its own materials: then "material" is optional (-1 = none). */
    if (type != SHAPE_MESHFILE || json_object_get(shape, "material"))
        LOADER_TRY(read_material_ref(ld, shape, &material));
    LOADER_TRY(read_emission(ld, shape, &em));
    switch (type) {
    case SHAPE_QUAD: return parse_quad(ld, shape, material, &em);
    case SHAPE_MESH: return parse_mesh(ld, shape, material, &em);
    case SHAPE_MESHFILE: return parse_meshfile(ld, shape, material, &em);
    default: return parse_sphere(ld, shape, material, &em);
    }
}

static CstStatus parse_shapes(Loader *ld, const json_t *shapes)
{
    char kind[48];
    if (!json_is_array(shapes) || json_array_size(shapes) == 0)
        return fail_here(ld, "got %s; expected an array of at least one shape",
                         describe(shapes, kind));
    size_t i;
    json_t *shape;
    json_array_foreach(shapes, i, shape) {
        path_push_index(ld, i);
        LOADER_TRY(parse_shape(ld, shape));
        path_pop(ld);
    }
    return CST_OK;
}

/* A unit direction from a vector that must not be zero. */
static CstStatus read_direction(Loader *ld, const json_t *v, Vec3 *out)
{
    Vec3 d;
    LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &d));
    float len = v3_length(d);
    if (!(len > 0.0f) || !isfinite(len))
        return fail_here(ld, "direction [%g, %g, %g] has no length; expected a nonzero vector",
                         (double)d.x, (double)d.y, (double)d.z);
    *out = v3_scale(d, 1.0f / len);
    return CST_OK;
}

static CstStatus read_angle(Loader *ld, const json_t *obj, const char *key, float dflt, float lo,
                            float hi, float *out)
{
    json_t *v = json_object_get(obj, key);
    *out = dflt;
    if (!v) return CST_OK;
    path_push_key(ld, key);
    LOADER_TRY(read_float(ld, v, (double)FLT_MAX, out));
    if (!(*out >= lo && *out <= hi))
        return fail_here(ld, "%s %g is out of range; expected degrees from %g to %g", key, (double)*out,
                         (double)lo, (double)hi);
    path_pop(ld);
    return CST_OK;
}

/* "lights": point, spot and directional lights (area lights are shapes with "emission"). */
static CstStatus parse_light(Loader *ld, const json_t *obj)
{
    static const char *const types[] = {"point", "spot", "directional"};
    static const char *const point_keys[] = {"type", "position", "intensity"};
    static const char *const spot_keys[] = {"type", "position", "look_at", "intensity", "cone_angle",
                                            "cone_delta"};
    static const char *const dir_keys[] = {"type", "direction", "irradiance"};
    int type = 0;
    json_t *v;
    DeltaLight l;
    memset(&l, 0, sizeof l);
    LOADER_TRY(expect_object(ld, obj, "a light object"));
    LOADER_TRY(read_type(ld, obj, "light type", types, 3, -1, &type));
    if (type == 2) {
        LOADER_TRY(check_keys(ld, obj, dir_keys, 3));
        l.type = DELTA_DIRECTIONAL;
        LOADER_TRY(member_required(ld, obj, "direction", "the direction the light travels, 3 numbers", &v));
        path_push_key(ld, "direction");
        LOADER_TRY(read_direction(ld, v, &l.dir));
        path_pop(ld);
        LOADER_TRY(member_required(ld, obj, "irradiance", "an array of 3 numbers >= 0", &v));
        path_push_key(ld, "irradiance");
        LOADER_TRY(read_rgb(ld, v, 0, &l.intensity));
        path_pop(ld);
    } else {
        LOADER_TRY(check_keys(ld, obj, type == 0 ? point_keys : spot_keys, type == 0 ? 3 : 6));
        l.type = type == 0 ? DELTA_POINT : DELTA_SPOT;
        LOADER_TRY(member_required(ld, obj, "position", "the light's position, 3 numbers", &v));
        path_push_key(ld, "position");
        LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &l.p));
        path_pop(ld);
        LOADER_TRY(member_required(ld, obj, "intensity", "an array of 3 numbers >= 0 (W/sr)", &v));
        path_push_key(ld, "intensity");
        LOADER_TRY(read_rgb(ld, v, 0, &l.intensity));
        path_pop(ld);
        if (type == 1) {
            Vec3 at;
            LOADER_TRY(member_required(ld, obj, "look_at", "the point the spot's axis goes through", &v));
            path_push_key(ld, "look_at");
            LOADER_TRY(read_vec3(ld, v, LOADER_MAX_LENGTH, &at));
            Vec3 d = v3_sub(at, l.p);
            float len = v3_length(d);
            if (!(len > 0.0f) || !isfinite(len))
                return fail_here(ld, "look_at equals position; expected a point away from the light");
            l.dir = v3_scale(d, 1.0f / len);
            path_pop(ld);
            /* pbrt-v4's parameters: the cone's half-angle, and how much of it the falloff
             * takes at its edge. */
            float cone, delta;
            LOADER_TRY(read_angle(ld, obj, "cone_angle", 30.0f, 0.001f, 90.0f, &cone));
            LOADER_TRY(read_angle(ld, obj, "cone_delta", 5.0f, 0.0f, cone, &delta));
            l.cos_outer = cosf(cone * (CST_PI / 180.0f));
            l.cos_inner = cosf((cone - delta) * (CST_PI / 180.0f));
        }
    }
    return scene_add_delta_light(ld->scene, &l, ld->err);
}

static CstStatus parse_lights(Loader *ld, const json_t *lights)
{
    char kind[48];
    if (!json_is_array(lights))
        return fail_here(ld, "got %s; expected an array of lights", describe(lights, kind));
    size_t i;
    json_t *light;
    json_array_foreach(lights, i, light) {
        path_push_index(ld, i);
        LOADER_TRY(parse_light(ld, light));
        path_pop(ld);
    }
    return CST_OK;
}

/* "environment": a constant radiance, or an equirectangular image (EXR, PFM or PNG,
 * relative to the scene file) times a scale. */
static CstStatus parse_environment(Loader *ld, const json_t *obj)
{
    static const char *const keys[] = {"radiance", "file", "scale"};
    json_t *v;
    LOADER_TRY(expect_object(ld, obj, "an object with radiance, or file and scale"));
    LOADER_TRY(check_keys(ld, obj, keys, 3));
    json_t *rad = json_object_get(obj, "radiance"), *file = json_object_get(obj, "file");
    if (!rad == !file)
        return fail_here(ld, "expected exactly one of radiance (a constant environment) and file "
                             "(an equirectangular image)");
    EnvMap env;
    if (rad) {
        if (json_object_get(obj, "scale")) {
            path_push_key(ld, "scale");
            return fail_here(ld, "scale goes with file; a constant environment is just its radiance");
        }
        Color L;
        path_push_key(ld, "radiance");
        LOADER_TRY(read_rgb(ld, rad, 0, &L));
        path_pop(ld);
        LOADER_TRY(envmap_init_constant(&env, L, ld->err));
        return scene_set_environment(ld->scene, &env, ld->err);
    }
    Color scale = color_s(1.0f);
    if ((v = json_object_get(obj, "scale"))) {
        path_push_key(ld, "scale");
        if (json_is_number(v)) {
            float k;
            LOADER_TRY(read_float(ld, v, (double)FLT_MAX, &k));
            if (!(k >= 0.0f)) return fail_here(ld, "scale %g is negative; expected a number >= 0", (double)k);
            scale = color_s(k);
        } else {
            LOADER_TRY(read_rgb(ld, v, 0, &scale));
        }
        path_pop(ld);
    }
    const char *name = NULL;
    path_push_key(ld, "file");
    LOADER_TRY(read_string(ld, file, &name));
    if (!name[0]) return fail_here(ld, "the file name is empty; expected the path of an image");
    char *path = path_resolve(ld->name, name);
    if (!path) return fail_at(ld, CST_ERR_OOM, "out of memory");
    float *rgb = NULL;
    int w = 0, h = 0;
    CstStatus st = image_read(path, &rgb, &w, &h, ld->err);
    free(path);
    if (st != CST_OK) return fail_builder(ld, st);
    st = envmap_init_image(&env, rgb, w, h, scale, ld->err);
    if (st != CST_OK) return fail_builder(ld, st);
    path_pop(ld);
    return scene_set_environment(ld->scene, &env, ld->err);
}

/* Sections are read in dependency order (materials before the shapes naming them), not
 * file order, so a file may list them in any order. */
static CstStatus parse_root(Loader *ld, const json_t *root)
{
    static const char *const keys[] = {"film", "camera", "integrator", "sampler", "materials",
                                       "shapes", "lights", "environment", "accel", "textures"};
    json_t *v;
    LOADER_TRY(expect_object(ld, root, "an object with the scene sections"));
    LOADER_TRY(check_keys(ld, root, keys, 10));
    if ((v = json_object_get(root, "accel"))) {
        path_push_key(ld, "accel");
        const char *name = NULL;
        AccelType type = ACCEL_BVH;
        LOADER_TRY(read_string(ld, v, &name));
        if (!accel_type_from_name(name, &type))
            return fail_here(ld, "unknown acceleration structure \"%s\"; expected one of: bvh, "
                                 "kdtree, grid, list, embree", name);
        if (!accel_type_available(type))
            return fail_here(ld, "acceleration structure \"%s\" is not available in this build; "
                                 "expected one of: bvh, kdtree, grid, list", name);
        ld->scene->accel_type = type;
        path_pop(ld);
    }
    if ((v = json_object_get(root, "film"))) {
        path_push_key(ld, "film");
        LOADER_TRY(parse_film(ld, v));
        path_pop(ld);
    }
    LOADER_TRY(member_required(ld, root, "camera", "a camera object", &v));
    path_push_key(ld, "camera");
    LOADER_TRY(parse_camera(ld, v));
    path_pop(ld);
    if ((v = json_object_get(root, "integrator"))) {
        path_push_key(ld, "integrator");
        LOADER_TRY(parse_integrator(ld, v));
        path_pop(ld);
    }
    if ((v = json_object_get(root, "sampler"))) {
        path_push_key(ld, "sampler");
        LOADER_TRY(parse_sampler(ld, v));
        path_pop(ld);
    }
    if ((v = json_object_get(root, "textures"))) {
        path_push_key(ld, "textures");
        LOADER_TRY(parse_textures(ld, v));
        path_pop(ld);
    }
    if ((v = json_object_get(root, "materials"))) {
        path_push_key(ld, "materials");
        LOADER_TRY(parse_materials(ld, v));
        path_pop(ld);
    }
    LOADER_TRY(member_required(ld, root, "shapes", "an array of at least one shape", &v));
    path_push_key(ld, "shapes");
    LOADER_TRY(parse_shapes(ld, v));
    path_pop(ld);
    if ((v = json_object_get(root, "lights"))) {
        path_push_key(ld, "lights");
        LOADER_TRY(parse_lights(ld, v));
        path_pop(ld);
    }
    if ((v = json_object_get(root, "environment"))) {
        path_push_key(ld, "environment");
        LOADER_TRY(parse_environment(ld, v));
        path_pop(ld);
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ entry points */

CstStatus cst_scene_load_json_string(const char *text, size_t len, const char *name,
                                     CstScene **out, CstError *err)
{
    CstError local;
    if (!err)
        err = &local;
    cst_error_clear(err);
    if (!name)
        name = "<string>";
    if (!out)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%.200s: no place for the scene (out is NULL)",
                        name);
    *out = NULL;
    if (!text && len > 0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%.200s: text is NULL", name);

    /* JSON text never holds a raw NUL, but jansson drops one that directly follows a number
     * or literal ("51\0," parses as "51,"): its one-character push-back cannot tell a NUL
     * from an empty buffer. Reject it here so the text json_locate walks is what jansson
     * saw. */
    const char *nul = len ? memchr(text, '\0', len) : NULL;
    if (nul) {
        JsonLocation at = json_offset_location(text, len, (size_t)(nul - text));
        return cst_fail(err, CST_ERR_PARSE,
                        "%.200s:%d:%d: NUL byte in the text; expected JSON text, which has none",
                        name, at.line, at.column);
    }

    json_error_t jerr;
    json_t *root = json_loadb(text ? text : "", len, JSON_REJECT_DUPLICATES, &jerr);
    if (!root) {
        if (json_error_code(&jerr) == json_error_out_of_memory)
            return cst_fail(err, CST_ERR_OOM, "%.200s: out of memory parsing JSON", name);
        /* jansson's column is that of the token's last character; 0 means "before the first"
         * (an empty file), shown as 1 so positions stay 1-based. */
        int line = jerr.line > 0 ? jerr.line : 1, col = jerr.column > 0 ? jerr.column : 1;
        char text_safe[JSON_ERROR_TEXT_LENGTH]; /* "near '<raw bytes>'" may hold a newline */
        size_t pos = 0;
        buf_append(text_safe, sizeof text_safe, &pos, jerr.text);
        return cst_fail(err, CST_ERR_PARSE, "%.200s:%d:%d: %s", name, line, col, text_safe);
    }

    Loader ld = {0};
    ld.text = text ? text : "";
    ld.len = len;
    ld.name = name;
    ld.err = err;
    ld.scene = scene_create();
    CstStatus st;
    if (!ld.scene) {
        st = cst_fail(err, CST_ERR_OOM, "%.200s: out of memory creating the scene", name);
    } else {
        st = parse_root(&ld, root);
        if (st == CST_OK) {
            st = scene_commit(ld.scene, err);
            if (st != CST_OK) {
                char msg[sizeof err->msg];
                memcpy(msg, err->msg, sizeof msg);
                msg[sizeof msg - 1] = '\0';
                cst_fail(err, st, "%.200s: %.800s", name, msg);
            }
        }
    }
    free(ld.mat_names);
    free(ld.mat_ids);
    free(ld.tex_names);
    free(ld.tex_state);
    free(ld.tex_ids);
    json_decref(root);
    if (st != CST_OK) {
        scene_destroy(ld.scene);
        return st;
    }
    *out = ld.scene;
    return CST_OK;
}

CstStatus cst_scene_load_json(const char *path, CstScene **out, CstError *err)
{
    CstError local;
    if (!err)
        err = &local;
    if (!out || !path)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_load_json: path and out must not "
                                                  "be NULL");
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    CstStatus st = file_read_all(path, &text, &len, err);
    if (st != CST_OK)
        return st;
    st = cst_scene_load_json_string(text, len, path, out, err);
    free(text);
    return st;
}
