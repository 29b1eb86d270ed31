/* The JSON scene loader's reader core: the Loader state, the path of the value being read
 * and its file:line:column in messages (found again by json_locate, since jansson keeps no
 * positions), and the typed readers that check every value. */
#include "scene/json/json_reader.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "scene/json/json_locate.h"

_Static_assert(sizeof(json_int_t) == sizeof(long long), "jansson integers are long long");

void json_path_push_key(Loader *ld, const char *key)
{
    if (ld->depth < LOADER_MAX_DEPTH)
        ld->path[ld->depth] = (JsonPathStep){key, 0};
    ld->depth++;
}

void json_path_push_index(Loader *ld, size_t index)
{
    if (ld->depth < LOADER_MAX_DEPTH)
        ld->path[ld->depth] = (JsonPathStep){NULL, index};
    ld->depth++;
}

void json_path_pop(Loader *ld) { ld->depth--; }

/* Copies src into buf[*pos, cap) as far as it fits, always terminating. Control bytes
 * (decoded from escapes in the file) become '?' so a message stays on one line. */
void json_buf_append(char *buf, size_t cap, size_t *pos, const char *src)
{
    for (; *src && *pos + 1 < cap; src++)
        buf[(*pos)++] = ((unsigned char)*src < 0x20) ? '?' : *src;
    buf[*pos] = '\0';
}

/* A name from the file, made safe and short enough to quote in a message. */
const char *json_clip_name(const char *s, char buf[72])
{
    size_t pos = 0;
    buf[0] = '\0';
    json_buf_append(buf, 64, &pos, s);
    if (strlen(s) > pos)
        json_buf_append(buf, 72, &pos, "...");
    return buf;
}

/* "a, b, c" */
void json_join_names(const char *const *names, int n, char *buf, size_t cap)
{
    size_t pos = 0;
    buf[0] = '\0';
    for (int i = 0; i < n; i++) {
        if (i > 0)
            json_buf_append(buf, cap, &pos, ", ");
        json_buf_append(buf, cap, &pos, names[i]);
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
                json_buf_append(buf, cap, &pos, ".");
            json_buf_append(buf, cap, &pos, path[d].key);
        } else if (path[d].key) {
            char name[72];
            json_buf_append(buf, cap, &pos, "[\"");
            json_buf_append(buf, cap, &pos, json_clip_name(path[d].key, name));
            json_buf_append(buf, cap, &pos, "\"]");
        } else {
            char idx[32];
            snprintf(idx, sizeof idx, "[%zu]", path[d].index);
            json_buf_append(buf, cap, &pos, idx);
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

CstStatus json_fail_at(Loader *ld, CstStatus status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, status, JSON_LOCATE_VALUE, fmt, ap);
    va_end(ap);
    return st;
}

CstStatus json_fail_here(Loader *ld, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, CST_ERR_INVALID_ARG, JSON_LOCATE_VALUE, fmt, ap);
    va_end(ap);
    return st;
}

CstStatus json_fail_key(Loader *ld, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    CstStatus st = fail_v(ld, CST_ERR_INVALID_ARG, JSON_LOCATE_KEY, fmt, ap);
    va_end(ap);
    return st;
}

/* A builder call failed: keep its status and text, add where in the file it came from. */
CstStatus json_fail_builder(Loader *ld, CstStatus status)
{
    char msg[sizeof ld->err->msg];
    memcpy(msg, ld->err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    return json_fail_at(ld, status, "%.600s", msg);
}

/* Each reads the value at the current path and fails there with what it expected. */

const char *json_describe(const json_t *v, char buf[48])
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
CstStatus json_read_float(Loader *ld, const json_t *v, double max_abs, float *out)
{
    char kind[48];
    if (!json_is_number(v))
        return json_fail_here(ld, "got %s; expected a number", json_describe(v, kind));
    double d = json_number_value(v);
    /* jansson already rejects NaN, Infinity and 1e999; this catches finite doubles that
     * would become infinite as floats, and coordinates beyond LOADER_MAX_LENGTH. */
    if (!(fabs(d) <= (double)FLT_MAX))
        return json_fail_here(ld, "%g does not fit a 32-bit float; expected a magnitude below 3.4e38",
                              d);
    if (!(fabs(d) <= max_abs))
        return json_fail_here(ld, "%g is too large for a scene coordinate or length; expected a "
                                  "magnitude of at most %g",
                              d, max_abs);
    *out = (float)d;
    return CST_OK;
}

CstStatus json_read_vec3(Loader *ld, const json_t *v, double max_abs, Vec3 *out)
{
    char kind[48];
    if (!json_is_array(v) || json_array_size(v) != 3)
        return json_fail_here(ld, "got %s; expected an array of 3 numbers", json_describe(v, kind));
    float c[3] = {0};
    for (size_t k = 0; k < 3; k++) {
        json_path_push_index(ld, k);
        LOADER_TRY(json_read_float(ld, json_array_get(v, k), max_abs, &c[k]));
        json_path_pop(ld);
    }
    *out = v3(c[0], c[1], c[2]);
    return CST_OK;
}

/* An RGB triple of numbers, each >= 0 and, when max_one, <= 1. */
CstStatus json_read_rgb(Loader *ld, const json_t *v, int max_one, Color *out)
{
    static const char *const channel[3] = {"red", "green", "blue"};
    Vec3 c = {0};
    LOADER_TRY(json_read_vec3(ld, v, (double)FLT_MAX, &c));
    for (int k = 0; k < 3; k++) {
        float x = v3_get(c, k);
        if (x < 0.0f || (max_one && x > 1.0f)) {
            json_path_push_index(ld, (size_t)k);
            if (max_one)
                return json_fail_here(ld, "%s %g is outside [0, 1] (more than 1 would create energy); "
                                          "expected a reflectance from 0 to 1",
                                      channel[k], (double)x);
            return json_fail_here(ld, "%s %g is negative; expected a number >= 0", channel[k], (double)x);
        }
    }
    *out = color_rgb(c.x, c.y, c.z);
    return CST_OK;
}

CstStatus json_read_int(Loader *ld, const json_t *v, json_int_t lo, json_int_t hi, json_int_t *out)
{
    char kind[48];
    if (!json_is_integer(v)) {
        if (hi == LOADER_NO_MAX)
            return json_fail_here(ld, "got %s; expected an integer >= %" JSON_INTEGER_FORMAT,
                                  json_describe(v, kind), lo);
        return json_fail_here(ld, "got %s; expected an integer from %" JSON_INTEGER_FORMAT
                                  " to %" JSON_INTEGER_FORMAT,
                              json_describe(v, kind), lo, hi);
    }
    json_int_t i = json_integer_value(v);
    if (i < lo || i > hi) {
        if (hi == LOADER_NO_MAX)
            return json_fail_here(ld, "%" JSON_INTEGER_FORMAT " is out of range; expected an integer >= %"
                                      JSON_INTEGER_FORMAT, i, lo);
        return json_fail_here(ld, "%" JSON_INTEGER_FORMAT " is out of range; expected an integer from %"
                                  JSON_INTEGER_FORMAT " to %" JSON_INTEGER_FORMAT, i, lo, hi);
    }
    *out = i;
    return CST_OK;
}

CstStatus json_read_string(Loader *ld, const json_t *v, const char **out)
{
    char kind[48];
    if (!json_is_string(v))
        return json_fail_here(ld, "got %s; expected a string", json_describe(v, kind));
    *out = json_string_value(v);
    return CST_OK;
}

CstStatus json_read_bool(Loader *ld, const json_t *v, int *out)
{
    char kind[48];
    if (!json_is_boolean(v))
        return json_fail_here(ld, "got %s; expected true or false", json_describe(v, kind));
    *out = json_is_true(v);
    return CST_OK;
}

CstStatus json_expect_object(Loader *ld, const json_t *v, const char *what)
{
    char kind[48];
    if (!json_is_object(v))
        return json_fail_here(ld, "got %s; expected %s", json_describe(v, kind), what);
    return CST_OK;
}

/* Rejects keys not in allowed: a misspelt optional key must not silently mean "default". */
CstStatus json_check_keys(Loader *ld, const json_t *obj, const char *const *allowed, int n)
{
    const char *key;
    json_t *val;
    json_object_foreach((json_t *)obj, key, val) {
        int known = 0;
        for (int i = 0; i < n && !known; i++)
            known = strcmp(key, allowed[i]) == 0;
        if (!known) {
            char list[512], name[72];
            json_join_names(allowed, n, list, sizeof list);
            json_path_push_key(ld, key);
            return json_fail_key(ld, "unknown key \"%s\"; expected one of: %s", json_clip_name(key, name),
                                 list);
        }
    }
    return CST_OK;
}

/* *out = obj[key], which must exist; the error points at obj. */
CstStatus json_member_required(Loader *ld, const json_t *obj, const char *key,
                               const char *expected, json_t **out)
{
    *out = json_object_get(obj, key);
    if (!*out)
        return json_fail_here(ld, "missing key \"%s\"; expected %s", key, expected);
    return CST_OK;
}

/* obj["type"] as an index into names; a missing type gives default_index, or an error
 * if that is -1. */
CstStatus json_read_type(Loader *ld, const json_t *obj, const char *what,
                         const char *const *names, int n, int default_index, int *out)
{
    char list[256];
    json_join_names(names, n, list, sizeof list);
    json_t *v = json_object_get(obj, "type");
    if (!v) {
        if (default_index >= 0) {
            *out = default_index;
            return CST_OK;
        }
        return json_fail_here(ld, "missing key \"type\"; expected a %s: %s", what, list);
    }
    const char *s = NULL;
    json_path_push_key(ld, "type");
    LOADER_TRY(json_read_string(ld, v, &s));
    for (int i = 0; i < n; i++)
        if (strcmp(s, names[i]) == 0) {
            json_path_pop(ld);
            *out = i;
            return CST_OK;
        }
    char name[72];
    return json_fail_here(ld, "unknown %s \"%s\"; expected one of: %s", what, json_clip_name(s, name), list);
}
