/* Unit tests for the JSON scene loader (scene/json/) and the JSON locator
 * (scene/json/json_locate.c): every validation error gives its status and file:line:column,
 * the example scenes load, and the locator stays in bounds on hostile text. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "caustic/caustic.h"
#include "scene/json/json_locate.h"
#include "scene/scene.h"

#define NAME "t.json"

/* ------------------------------------------------------------------ helpers */

/* 1-based line and code-point column of the nth (0-based) occurrence of needle: an
 * independent count to check the locator against. */
static void pos_of(const char *text, const char *needle, int nth, int *line, int *col)
{
    const char *at = text;
    for (int i = 0;; i++) {
        at = strstr(at, needle);
        if (!at)
            fail_msg("needle \"%s\" #%d not in the test text", needle, nth);
        if (i == nth)
            break;
        at++;
    }
    *line = 1;
    *col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') {
            (*line)++;
            *col = 1;
        } else if (((unsigned char)*p & 0xC0) != 0x80) {
            (*col)++;
        }
    }
}

static CstStatus load(const char *text, CstScene **out, CstError *err)
{
    return cst_scene_load_json_string(text, strlen(text), NAME, out, err);
}

/* Loads text expecting failure with `status`, the position of needle #nth, and (when not
 * NULL) `what` somewhere in the message. */
static void expect_error(const char *text, CstStatus status, const char *needle, int nth,
                         const char *what)
{
    CstScene *scene = (CstScene *)(uintptr_t)1; /* must be reset to NULL */
    CstError err = {0};
    CstStatus st = load(text, &scene, &err);
    if (st != status)
        fail_msg("status %s, expected %s; message: %s\ntext: %s", cst_status_name(st),
                 cst_status_name(status), err.msg, text);
    assert_null(scene);
    assert_int_equal(err.status, status);
    int line, col;
    pos_of(text, needle, nth, &line, &col);
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("message \"%s\" does not start with \"%s\"\ntext: %s", err.msg, prefix, text);
    if (what && !strstr(err.msg, what))
        fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
}

/* The same with the exact whole message. */
static void expect_message(const char *text, CstStatus status, const char *msg)
{
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus st = load(text, &scene, &err);
    assert_null(scene);
    if (st != status || strcmp(err.msg, msg) != 0)
        fail_msg("got %s \"%s\"\nexpected %s \"%s\"", cst_status_name(st), err.msg,
                 cst_status_name(status), msg);
}

static CstScene *expect_ok(const char *text)
{
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus st = load(text, &scene, &err);
    if (st != CST_OK)
        fail_msg("%s: %s\ntext: %s", cst_status_name(st), err.msg, text);
    assert_non_null(scene);
    return scene;
}

/* Pieces of a valid scene that the cases below vary one at a time. */
#define CAM "\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}"
#define MATS "\"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}}"
#define QUAD_V "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]"
#define QUAD "{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " QUAD_V "}"
#define SHAPES "\"shapes\": [" QUAD "]"
/* A scene with the given camera, materials and shapes members. */
#define SCENE3(cam, mats, shapes) "{" cam ", " mats ", " shapes "}"
#define WITH_SHAPE(shape) SCENE3(CAM, MATS, "\"shapes\": [" shape "]")
#define WITH_CAM(cam) SCENE3("\"camera\": " cam, MATS, SHAPES)
#define WITH_SECTION(sec) "{" sec ", " CAM ", " MATS ", " SHAPES "}"

/* ------------------------------------------------------------------ locator */

static void locate_ok(const char *text, const JsonPathStep *path, int depth,
                      JsonLocateTarget target, int line, int col)
{
    JsonLocation loc = {0, 0};
    assert_true(json_locate(text, strlen(text), path, depth, target, &loc));
    if (loc.line != line || loc.column != col)
        fail_msg("located %d:%d, expected %d:%d in %s", loc.line, loc.column, line, col, text);
}

static void test_locate_basic(void **state)
{
    (void)state;
    const char *t = "{\"a\": 1,\n \"b\": [10, 20, {\"c\": true}],\n \"d\": \"x\"}";
    JsonPathStep p[3] = {{"b", 0}, {NULL, 2}, {"c", 0}};
    locate_ok(t, NULL, 0, JSON_LOCATE_VALUE, 1, 1);
    locate_ok(t, (JsonPathStep[]){{"a", 0}}, 1, JSON_LOCATE_VALUE, 1, 7);
    locate_ok(t, p, 1, JSON_LOCATE_VALUE, 2, 7);
    locate_ok(t, p, 2, JSON_LOCATE_VALUE, 2, 16);
    locate_ok(t, p, 3, JSON_LOCATE_VALUE, 2, 22);
    locate_ok(t, p, 3, JSON_LOCATE_KEY, 2, 17);
    locate_ok(t, (JsonPathStep[]){{"d", 0}}, 1, JSON_LOCATE_KEY, 3, 2);
    locate_ok(t, (JsonPathStep[]){{"d", 0}}, 1, JSON_LOCATE_VALUE, 3, 7);
}

static void test_locate_not_found(void **state)
{
    (void)state;
    const char *t = "{\"a\": [1, 2], \"b\": {\"c\": 3}}";
    JsonLocation loc;
    size_t n = strlen(t);
    assert_false(json_locate(t, n, (JsonPathStep[]){{"x", 0}}, 1, JSON_LOCATE_VALUE, &loc));
    assert_false(json_locate(t, n, (JsonPathStep[]){{"a", 0}, {NULL, 2}}, 2, JSON_LOCATE_VALUE, &loc));
    /* a key step into an array, an index step into an object, a step into a scalar */
    assert_false(json_locate(t, n, (JsonPathStep[]){{"a", 0}, {"c", 0}}, 2, JSON_LOCATE_VALUE, &loc));
    assert_false(json_locate(t, n, (JsonPathStep[]){{"b", 0}, {NULL, 0}}, 2, JSON_LOCATE_VALUE, &loc));
    assert_false(json_locate(t, n, (JsonPathStep[]){{"a", 0}, {NULL, 0}, {NULL, 0}}, 3,
                             JSON_LOCATE_VALUE, &loc));
    /* a key target needs a key step */
    assert_false(json_locate(t, n, (JsonPathStep[]){{"a", 0}, {NULL, 0}}, 2, JSON_LOCATE_KEY, &loc));
    assert_false(json_locate(t, n, NULL, 0, JSON_LOCATE_KEY, &loc));
    assert_false(json_locate("", 0, NULL, 0, JSON_LOCATE_VALUE, &loc));
    assert_false(json_locate("   ", 3, NULL, 0, JSON_LOCATE_VALUE, &loc));
    /* a key that is a prefix of another must not match it, nor the other way round */
    assert_false(json_locate("{\"ab\": 1}", 9, (JsonPathStep[]){{"a", 0}}, 1, JSON_LOCATE_VALUE, &loc));
    assert_false(json_locate("{\"a\": 1}", 8, (JsonPathStep[]){{"ab", 0}}, 1, JSON_LOCATE_VALUE, &loc));
}

/* Strings holding quotes, backslashes and brackets must not confuse the skipping. */
static void test_locate_escapes(void **state)
{
    (void)state;
    const char *t = "{\"k\\\"]}\": \"v\\\\\", \"s\": \"[{\\\"}\\\\\", \"x\\u005d\": [\"]\", \"\\\"\", 7]}";
    /* {"k\"]}": "v\\", "s": "[{\"}\\", "x\u005d": ["]", "\"", 7]} */
    locate_ok(t, (JsonPathStep[]){{"k\"]}", 0}}, 1, JSON_LOCATE_VALUE, 1, 11);
    locate_ok(t, (JsonPathStep[]){{"s", 0}}, 1, JSON_LOCATE_KEY, 1, 18);
    locate_ok(t, (JsonPathStep[]){{"x]", 0}, {NULL, 2}}, 2, JSON_LOCATE_VALUE, 1, 57);
    /* every escape decodes before comparing: \/ \b \f \n \r \t \\ \" */
    const char *e = "{\"\\/\\b\\f\\n\\r\\t\\\\\\\"\": 1}";
    locate_ok(e, (JsonPathStep[]){{"/\b\f\n\r\t\\\"", 0}}, 1, JSON_LOCATE_VALUE, 1, 22);
}

static void test_locate_nested(void **state)
{
    (void)state;
    const char *t = "[[1, [2, [3, [4]]]], [[]], {\"a\": [[5], {\"b\": [6, [7]]}]}]";
    locate_ok(t, (JsonPathStep[]){{NULL, 0}, {NULL, 1}, {NULL, 1}, {NULL, 1}, {NULL, 0}}, 5,
              JSON_LOCATE_VALUE, 1, 15);
    locate_ok(t, (JsonPathStep[]){{NULL, 1}, {NULL, 0}}, 2, JSON_LOCATE_VALUE, 1, 23);
    locate_ok(t, (JsonPathStep[]){{NULL, 2}, {"a", 0}, {NULL, 1}, {"b", 0}, {NULL, 1}, {NULL, 0}},
              6, JSON_LOCATE_VALUE, 1, 51);
    JsonLocation loc;
    assert_false(json_locate(t, strlen(t), (JsonPathStep[]){{NULL, 1}, {NULL, 0}, {NULL, 0}}, 3,
                             JSON_LOCATE_VALUE, &loc));
}

/* Columns count code points; keys match whether spelt raw or as \u escapes, including a
 * surrogate pair for a character outside the BMP. */
static void test_locate_unicode(void **state)
{
    (void)state;
    const char *t = "{\"\xc3\xa9t\xc3\xa9\": \"\xe2\x82\xac\xf0\x9f\x98\x80\", \"\\u00e9\\ud83d\\ude00\": 1,\n"
                    " \"n\\u00e9\": [\"\xf0\x9f\x98\x80\", 2]}";
    /* {"été": "€😀", "\u00e9\ud83d\ude00": 1,
     *  "n\u00e9": ["😀", 2]} */
    locate_ok(t, (JsonPathStep[]){{"\xc3\xa9t\xc3\xa9", 0}}, 1, JSON_LOCATE_VALUE, 1, 9);
    locate_ok(t, (JsonPathStep[]){{"\xc3\xa9\xf0\x9f\x98\x80", 0}}, 1, JSON_LOCATE_KEY, 1, 15);
    locate_ok(t, (JsonPathStep[]){{"\xc3\xa9\xf0\x9f\x98\x80", 0}}, 1, JSON_LOCATE_VALUE, 1, 37);
    locate_ok(t, (JsonPathStep[]){{"n\xc3\xa9", 0}, {NULL, 1}}, 2, JSON_LOCATE_VALUE, 2, 19);
    JsonLocation loc;
    /* half a code point is not the key */
    assert_false(json_locate(t, strlen(t), (JsonPathStep[]){{"\xc3", 0}}, 1, JSON_LOCATE_VALUE, &loc));
}

/* Every prefix of a document and hostile bytes: answers or false, never out of bounds
 * (ASan/valgrind check the "never"); the copy to an exact-size heap block makes any
 * overrun visible. */
static void test_locate_truncated_and_garbage(void **state)
{
    (void)state;
    const char *doc = "{\"a\\\"\": [1, \"x\\u00e9\\\\\", {\"b\": [true, null, -1.5e3]}], \"c\": \"\xe2\x82\xac\"}";
    JsonPathStep paths[][3] = {
        {{"a\"", 0}, {NULL, 2}, {"b", 0}}, {{"c", 0}, {NULL, 0}, {NULL, 0}}, {{NULL, 0}, {NULL, 0}, {NULL, 0}}};
    int depths[] = {3, 1, 2};
    size_t n = strlen(doc);
    for (size_t len = 0; len <= n; len++) {
        char *copy = malloc(len ? len : 1);
        assert_non_null(copy);
        memcpy(copy, doc, len);
        for (int p = 0; p < 3; p++) {
            JsonLocation loc;
            bool found = json_locate(copy, len, paths[p], depths[p], JSON_LOCATE_VALUE, &loc);
            if (found) {
                assert_true(loc.line >= 1 && loc.column >= 1);
            }
            json_locate(copy, len, paths[p], depths[p], JSON_LOCATE_KEY, &loc);
        }
        free(copy);
    }
    const char *garbage[] = {"\"", "\\", "{\"", "{\"a\\", "{\"a\\u00", "{\"a\\ud83d\\u", "[\"\\", "{\"a\":",
                             "{\"a\" 1}", "{\"a\": }", "[,]", "{{{{", "]]]]", "{\"a\": 1 \"b\": 2}",
                             "\xff\xfe{", "{\"a\": 1,}", "[1 2 3]"};
    for (size_t g = 0; g < sizeof garbage / sizeof garbage[0]; g++) {
        size_t len = strlen(garbage[g]);
        char *copy = malloc(len ? len : 1);
        assert_non_null(copy);
        memcpy(copy, garbage[g], len);
        JsonLocation loc;
        json_locate(copy, len, (JsonPathStep[]){{"a", 0}, {NULL, 1}}, 2, JSON_LOCATE_VALUE, &loc);
        json_locate(copy, len, (JsonPathStep[]){{"b", 0}}, 1, JSON_LOCATE_KEY, &loc);
        json_locate(copy, len, (JsonPathStep[]){{NULL, 2}}, 1, JSON_LOCATE_VALUE, &loc);
        free(copy);
    }
}

/* Deep nesting costs neither recursion nor stack. */
static void test_locate_deep(void **state)
{
    (void)state;
    size_t n = 1000000;
    char *t = malloc(2 * n + 16);
    assert_non_null(t);
    size_t k = 0;
    t[k++] = '{';
    memcpy(t + k, "\"a\": ", 5);
    k += 5;
    for (size_t i = 0; i < n; i++) t[k++] = '[';
    for (size_t i = 0; i < n; i++) t[k++] = ']';
    memcpy(t + k, ", \"b\": 2}", 9);
    k += 9;
    t[k] = '\0';
    locate_ok(t, (JsonPathStep[]){{"b", 0}}, 1, JSON_LOCATE_VALUE, 1, (int)(2 * n + 14));
    JsonLocation loc;
    assert_false(json_locate(t, k - 9, (JsonPathStep[]){{"b", 0}}, 1, JSON_LOCATE_VALUE, &loc));
    free(t);
}

/* Byte offset of a 1-based line and code-point column: the inverse of the locator's
 * convention, so located text can be parsed again. */
static size_t offset_of(const char *text, size_t len, JsonLocation loc)
{
    int line = 1, col = 1;
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)text[i];
        if ((c & 0xC0) == 0x80)
            continue; /* continuation bytes belong to the code point before */
        if (line == loc.line && col == loc.column)
            return i;
        if (c == '\n') {
            line++;
            col = 1;
        } else {
            col++;
        }
    }
    return len;
}

/* Differential check against jansson: every value in the parsed tree, located by path,
 * must parse again (from that offset) to an equal value, and every key must be found at
 * its quote. */
static void check_subtree(const char *text, size_t len, json_t *v, JsonPathStep *path, int depth)
{
    JsonLocation loc;
    assert_true(depth < 16);
    if (!json_locate(text, len, path, depth, JSON_LOCATE_VALUE, &loc))
        fail_msg("value at depth %d not located", depth);
    size_t off = offset_of(text, len, loc);
    json_error_t jerr;
    json_t *again = json_loadb(text + off, len - off, JSON_DECODE_ANY | JSON_DISABLE_EOF_CHECK, &jerr);
    if (!again || !json_equal(again, v))
        fail_msg("value located at %d:%d (offset %zu) does not match the tree: found %s, expected %s",
                 loc.line, loc.column, off, again ? json_dumps(again, JSON_ENCODE_ANY) : jerr.text,
                 json_dumps(v, JSON_ENCODE_ANY));
    json_decref(again);
    if (depth > 0 && path[depth - 1].key) {
        assert_true(json_locate(text, len, path, depth, JSON_LOCATE_KEY, &loc));
        off = offset_of(text, len, loc);
        assert_true(off < len && text[off] == '"');
        json_t *key = json_loadb(text + off, len - off, JSON_DECODE_ANY | JSON_DISABLE_EOF_CHECK, &jerr);
        assert_non_null(key);
        assert_string_equal(json_string_value(key), path[depth - 1].key);
        json_decref(key);
    }
    if (json_is_object(v)) {
        const char *k;
        json_t *child;
        json_object_foreach(v, k, child) {
            path[depth] = (JsonPathStep){k, 0};
            check_subtree(text, len, child, path, depth + 1);
        }
    } else if (json_is_array(v)) {
        size_t i;
        json_t *child;
        json_array_foreach(v, i, child) {
            path[depth] = (JsonPathStep){NULL, i};
            check_subtree(text, len, child, path, depth + 1);
        }
    }
}

static char *read_whole(const char *path, size_t *len);

static void check_document(const char *text, size_t len)
{
    json_error_t jerr;
    /* Keys are unique (as the loader demands), so the first match is the only one. */
    json_t *root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!root)
        fail_msg("test document does not parse: %d:%d: %s", jerr.line, jerr.column, jerr.text);
    JsonPathStep path[16];
    check_subtree(text, len, root, path, 0);
    json_decref(root);
}

static void test_locate_matches_jansson(void **state)
{
    (void)state;
    const char *files[] = {CST_SOURCE_DIR "/scenes/cornell-box.json", CST_SOURCE_DIR "/scenes/cornell-spheres.json"};
    for (int f = 0; f < 2; f++) {
        size_t len;
        char *text = read_whole(files[f], &len);
        check_document(text, len);
        free(text);
    }
    const char *tricky =
        "\r\n\t[ {\"\\u00e9\\ud83d\\ude00\": [\"]}\\\"\\\\\", -0.5e-3, [[], {}], {\"\": null}],\n"
        "  \"\xc3\xbc\xf0\x9f\x98\x80\": true, \"\xc3\xa9\": 2, \"a/b\": \"\\/\"}, 1E+2, \"\xe2\x82\xac\", false ,[ [ [ 0 ] ] ] ]";
    check_document(tricky, strlen(tricky));
}

static void test_offset_location(void **state)
{
    (void)state;
    const char *t = "ab\n\xc3\xa9x\n";
    JsonLocation l = json_offset_location(t, strlen(t), 0);
    assert_int_equal(l.line, 1); assert_int_equal(l.column, 1);
    l = json_offset_location(t, strlen(t), 5); /* 'x' after a 2-byte é */
    assert_int_equal(l.line, 2); assert_int_equal(l.column, 2);
    l = json_offset_location(t, strlen(t), 1000); /* clamped to the end */
    assert_int_equal(l.line, 3); assert_int_equal(l.column, 1);
}

/* ------------------------------------------------------------------ syntax errors */

static void test_syntax_errors(void **state)
{
    (void)state;
    /* jansson reports the column of the offending token's last character. */
    expect_message("", CST_ERR_PARSE, NAME ":1:1: '[' or '{' expected near end of file");
    expect_message("{\n  \"camera\": {\"fov\": NaN}\n}", CST_ERR_PARSE,
                   NAME ":2:23: invalid token near 'NaN'");
    expect_message("{\"shapes\": [],\n \"camera\": {\"fov\":\n    1e999}}", CST_ERR_PARSE,
                   NAME ":3:9: real number overflow near '1e999'");
    expect_message("{\"sampler\": {\"seed\": 99999999999999999999}}", CST_ERR_PARSE,
                   NAME ":1:41: too big integer near '99999999999999999999'");
    expect_message("{\"film\": {\"width\": 1, \"width\": 2}}", CST_ERR_PARSE,
                   NAME ":1:29: duplicate object key near '\"width\"'");
    /* an escaped spelling of a key duplicates the plain one */
    expect_message("{\"film\": {}, \"\\u0066ilm\": {}}", CST_ERR_PARSE,
                   NAME ":1:24: duplicate object key near '\"\\u0066ilm\"'");
    expect_message("{\"film\": {\"width\": 1,}}", CST_ERR_PARSE,
                   NAME ":1:22: string or '}' expected near '}'");
    expect_message("{\"camera\": {\"fov\": Infinity}}", CST_ERR_PARSE,
                   NAME ":1:27: invalid token near 'Infinity'");
    /* A raw NUL is never JSON; jansson would silently drop one right after a number
     * ("51\0," reads as "51,") and leave the locator walking different text, so it is
     * rejected up front, wherever it is. */
    CstScene *scene = NULL;
    CstError err;
    assert_int_equal(cst_scene_load_json_string("{}\0{}", 5, NAME, &scene, &err), CST_ERR_PARSE);
    assert_null(scene);
    assert_string_equal(err.msg, NAME ":1:3: NUL byte in the text; expected JSON text, which has none");
    static const char nul_after_number[] = "{\n \"film\": {\"width\": 51\0, \"\": 0}}";
    assert_int_equal(cst_scene_load_json_string(nul_after_number, sizeof nul_after_number - 1, NAME,
                                                &scene, &err),
                     CST_ERR_PARSE);
    assert_string_equal(err.msg, NAME ":2:22: NUL byte in the text; expected JSON text, which has none");
    /* Top level must be an object (jansson alone would take an array). */
    expect_message("[1, 2]", CST_ERR_INVALID_ARG,
                   NAME ":1:1: got an array of 2 elements; expected an object with the scene sections");
}

/* ------------------------------------------------------------------ semantic errors */

static void test_unknown_keys(void **state)
{
    (void)state;
    expect_error("{" CAM ", " MATS ", " SHAPES ", \"bogus\": 1}", CST_ERR_INVALID_ARG, "\"bogus\"", 0,
                 "unknown key \"bogus\"; expected one of: film, camera, integrator, sampler, "
                 "materials, shapes");
    expect_error(WITH_SECTION("\"film\": {\"widht\": 10}"), CST_ERR_INVALID_ARG, "\"widht\"", 0,
                 "film: unknown key \"widht\"; expected one of: width, height, filter, output");
    expect_error(WITH_SECTION("\"integrator\": {\"kind\": \"path\"}"), CST_ERR_INVALID_ARG, "\"kind\"", 0,
                 "integrator: unknown key \"kind\"; expected one of: type, max_depth, rr_depth");
    expect_error(WITH_SECTION("\"sampler\": {\"samples\": 4}"), CST_ERR_INVALID_ARG, "\"samples\"", 0,
                 "sampler: unknown key \"samples\"; expected one of: spp, seed");
    /* lens keys on a pinhole are an error, not silently ignored */
    expect_error(WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40, "
                          "\"aperture_radius\": 1}"),
                 CST_ERR_INVALID_ARG, "\"aperture_radius\"", 0,
                 "camera: unknown key \"aperture_radius\"; expected one of: type, position, look_at, up, fov");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"diffuse\", \"ior\": 1.5}}", SHAPES),
                 CST_ERR_INVALID_ARG, "\"ior\"", 0,
                 "materials.white: unknown key \"ior\"; expected one of: type, albedo");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"radius\": 1, \"vertices\": " QUAD_V "}"),
                 CST_ERR_INVALID_ARG, "\"radius\"", 0,
                 "shapes[0]: unknown key \"radius\"; expected one of: type, vertices, material, emission");
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], "
                            "\"radius\": 1, \"emission\": {\"radiance\": [1, 1, 1], \"power\": 2}}"),
                 CST_ERR_INVALID_ARG, "\"power\"", 0,
                 "shapes[0].emission: unknown key \"power\"; expected one of: radiance, two_sided");
    /* a key spelt with escapes is still the key it decodes to */
    expect_error("{\"\\u0066ilm\": {\"width\": -1}, " CAM ", " MATS ", " SHAPES "}", CST_ERR_INVALID_ARG,
                 "-1", 0, "film.width: -1 is out of range; expected an integer from 1 to 65536");
}

static void test_missing_keys(void **state)
{
    (void)state;
    expect_error("{" MATS ", " SHAPES "}", CST_ERR_INVALID_ARG, "{", 0,
                 "missing key \"camera\"; expected a camera object");
    expect_error("{" CAM ", " MATS "}", CST_ERR_INVALID_ARG, "{", 0,
                 "missing key \"shapes\"; expected an array of shapes");
    expect_error(WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0]}"), CST_ERR_INVALID_ARG,
                 "{\"position\"", 0, "camera: missing key \"fov\"");
    expect_error(WITH_CAM("{\"look_at\": [0, 0, 0], \"fov\": 40}"), CST_ERR_INVALID_ARG, "{\"look_at\"", 0,
                 "camera: missing key \"position\"");
    expect_error(WITH_CAM("{\"type\": \"thinlens\", \"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "{\"type\"", 0, "camera: missing key \"aperture_radius\"");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"vertices\": " QUAD_V "}"), CST_ERR_INVALID_ARG,
                 "{\"type\": \"quad\"", 0,
                 "shapes[0]: missing key \"material\"; expected the name of a material");
    expect_error(WITH_SHAPE("{\"material\": \"white\"}"), CST_ERR_INVALID_ARG, "{\"material\"", 0,
                 "shapes[0]: missing key \"type\"; expected a shape type: quad, mesh, sphere");
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0]}"),
                 CST_ERR_INVALID_ARG, "{\"type\": \"sphere\"", 0, "shapes[0]: missing key \"radius\"");
    expect_error(WITH_SHAPE("{\"type\": \"mesh\", \"material\": \"white\", \"vertices\": " QUAD_V "}"),
                 CST_ERR_INVALID_ARG, "{\"type\": \"mesh\"", 0, "shapes[0]: missing key \"indices\"");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " QUAD_V
                            ", \"emission\": {\"two_sided\": true}}"),
                 CST_ERR_INVALID_ARG, "{\"two_sided\"", 0, "shapes[0].emission: missing key \"radiance\"");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"albedo\": [1, 1, 1]}}", SHAPES),
                 CST_ERR_INVALID_ARG, "{\"albedo\"", 0,
                 "materials.white: missing key \"type\"; expected a material type: diffuse, mirror, glass");
}

static void test_wrong_types(void **state)
{
    (void)state;
    expect_error(WITH_CAM("{\"position\": \"abc\", \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "\"abc\"", 0,
                 "camera.position: got a string; expected an array of 3 numbers");
    expect_error(WITH_CAM("{\"position\": [0, 0], \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "[0, 0]", 0,
                 "camera.position: got an array of 2 elements; expected an array of 3 numbers");
    expect_error(WITH_CAM("{\"position\": [0, \"y\", 5], \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "\"y\"", 0, "camera.position[1]: got a string; expected a number");
    expect_error(WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": null}"),
                 CST_ERR_INVALID_ARG, "null", 0, "camera.fov: got null; expected a number");
    expect_error(WITH_SECTION("\"film\": {\"width\": 1.5}"), CST_ERR_INVALID_ARG, "1.5", 0,
                 "film.width: got a number; expected an integer from 1 to 65536");
    expect_error(WITH_SECTION("\"film\": [512, 512]"), CST_ERR_INVALID_ARG, "[512", 0,
                 "film: got an array of 2 elements; expected an object");
    expect_error(WITH_SECTION("\"film\": {\"filter\": 1}"), CST_ERR_INVALID_ARG, "1}", 0,
                 "film.filter: got an integer; expected a string");
    expect_error(WITH_SHAPE("5"), CST_ERR_INVALID_ARG, "5]}", 1,
                 "shapes[0]: got an integer; expected a shape object");
    expect_error(SCENE3(CAM, MATS, "\"shapes\": {\"a\": 1}"), CST_ERR_INVALID_ARG, "{\"a\"", 0,
                 "shapes: got an object; expected an array of shapes");
    expect_error(SCENE3(CAM, "\"materials\": [1]", SHAPES), CST_ERR_INVALID_ARG, "[1]", 0,
                 "materials: got an array of 1 element; expected an object mapping material names");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " QUAD_V
                            ", \"emission\": {\"radiance\": [1, 1, 1], \"two_sided\": \"yes\"}}"),
                 CST_ERR_INVALID_ARG, "\"yes\"", 0,
                 "shapes[0].emission.two_sided: got a string; expected true or false");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": 3, \"vertices\": " QUAD_V "}"),
                 CST_ERR_INVALID_ARG, "3,", 0, "shapes[0].material: got an integer; expected a string");
}

static void test_ranges(void **state)
{
    (void)state;
    expect_error(WITH_SECTION("\"film\": {\"width\": 0, \"height\": 10}"), CST_ERR_INVALID_ARG, "0, \"h", 0,
                 "film.width: 0 is out of range; expected an integer from 1 to 65536");
    expect_error(WITH_SECTION("\"film\": {\"width\": 70000}"), CST_ERR_INVALID_ARG, "70000", 0,
                 "film.width: 70000 is out of range; expected an integer from 1 to 65536");
    expect_error(WITH_SECTION("\"film\": {\"height\": -3}"), CST_ERR_INVALID_ARG, "-3", 0,
                 "film.height: -3 is out of range");
    expect_error(WITH_SECTION("\"sampler\": {\"spp\": 0}"), CST_ERR_INVALID_ARG, "0}", 0,
                 "sampler.spp: 0 is out of range; expected an integer from 1 to");
    expect_error(WITH_SECTION("\"sampler\": {\"spp\": -4}"), CST_ERR_INVALID_ARG, "-4", 0, "sampler.spp");
    expect_error(WITH_SECTION("\"sampler\": {\"seed\": -1}"), CST_ERR_INVALID_ARG, "-1", 0,
                 "sampler.seed: -1 is out of range; expected an integer >= 0");
    expect_error(WITH_SECTION("\"integrator\": {\"max_depth\": -1}"), CST_ERR_INVALID_ARG, "-1", 0,
                 "integrator.max_depth: -1 is out of range");
    expect_error(WITH_SECTION("\"integrator\": {\"rr_depth\": 0}"), CST_ERR_INVALID_ARG, "0}", 0,
                 "integrator.rr_depth: 0 is out of range");
    expect_error(WITH_SECTION("\"integrator\": {\"light_rr_depth\": 0}"), CST_ERR_INVALID_ARG, "0}", 0,
                 "integrator.light_rr_depth: 0 is out of range");
    expect_error(WITH_SECTION("\"integrator\": {\"photons\": 0}"), CST_ERR_INVALID_ARG, "0}", 0,
                 "integrator.photons: 0 is out of range");
    expect_error(WITH_SECTION("\"integrator\": {\"radius\": -2}"), CST_ERR_INVALID_ARG, "-2", 0,
                 "integrator.radius: radius -2 is not positive");
    expect_error(WITH_SECTION("\"integrator\": {\"radius\": 0}"), CST_ERR_INVALID_ARG, "0}", 0,
                 "integrator.radius: radius 0 is not positive");
    const char *fovs[] = {"0", "180", "-5", "200.5"};
    for (int i = 0; i < 4; i++) {
        char text[512];
        snprintf(text, sizeof text,
                 WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": %s}"), fovs[i]);
        char needle[16];
        snprintf(needle, sizeof needle, "%s}", fovs[i]);
        expect_error(text, CST_ERR_INVALID_ARG, needle, 0,
                     "camera.fov: fov"); /* "... is out of range; expected ... degrees" */
        expect_error(text, CST_ERR_INVALID_ARG, needle, 0, "less than 180");
    }
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], \"radius\": 0}"),
                 CST_ERR_INVALID_ARG, "0}]", 0,
                 "shapes[0].radius: radius 0 is not positive; expected a number > 0");
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], \"radius\": -1.5}"),
                 CST_ERR_INVALID_ARG, "-1.5", 0, "radius -1.5 is not positive");
    /* finite as a double, infinite as a float */
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 1e39, 0], \"radius\": 1}"),
                 CST_ERR_INVALID_ARG, "1e39", 0,
                 "shapes[0].center[1]: 1e+39 does not fit a 32-bit float");
    /* coordinates and lengths stay within 1e18 so squared distances and areas are finite */
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": "
                            "[[-3e38, 0, 0], [3e38, 0, 0], [3e38, 3e38, 0], [-3e38, 3e38, 0]]}"),
                 CST_ERR_INVALID_ARG, "-3e38", 0,
                 "shapes[0].vertices[0][0]: -3e+38 is too large for a scene coordinate or length; "
                 "expected a magnitude of at most 1e+18");
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], \"radius\": 2e18}"),
                 CST_ERR_INVALID_ARG, "2e18", 0, "shapes[0].radius: 2e+18 is too large");
    expect_error(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], "
                            "\"radius\": 1e-30, \"emission\": {\"radiance\": [1, 1, 1]}}"),
                 CST_ERR_INVALID_ARG, "1e-30", 0,
                 "shapes[0].radius: radius 1e-30 is too small (its area would underflow a 32-bit float)");
    expect_error(WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 1e30, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "1e30", 0, "camera.up[1]: 1e+30 is too large");
    CstScene *s = expect_ok(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, -1e18], "
                                       "\"radius\": 1e-18, \"emission\": {\"radiance\": [1e30, 0, 0]}}"));
    cst_scene_destroy(s);
    expect_error(WITH_CAM("{\"type\": \"thinlens\", \"position\": [0, 0, 5], \"look_at\": [0, 0, 0], "
                          "\"fov\": 40, \"aperture_radius\": -1}"),
                 CST_ERR_INVALID_ARG, "-1", 0, "camera.aperture_radius: aperture_radius -1 is negative");
    expect_error(WITH_CAM("{\"type\": \"thinlens\", \"position\": [0, 0, 5], \"look_at\": [0, 0, 0], "
                          "\"fov\": 40, \"aperture_radius\": 1, \"focus_distance\": 0}"),
                 CST_ERR_INVALID_ARG, "0}", 0, "camera.focus_distance: focus_distance 0 is not positive");
    expect_error(WITH_CAM("{\"position\": [1, 2, 3], \"look_at\": [1, 2, 3], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "[1, 2, 3]", 1, "camera.look_at: look_at equals position");
    expect_error(WITH_CAM("{\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"up\": [0, 0, 2], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "[0, 0, 2]", 0, "camera.up: up (0, 0, 2) is zero or parallel");
    /* the default up is parallel when looking straight down: the error points at camera */
    expect_error(WITH_CAM("{\"position\": [0, 5, 0], \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "{\"position\": [0, 5", 0, "camera: up (0, 1, 0)");
    expect_error(WITH_SECTION("\"film\": {\"output\": \"image.jpg\"}"), CST_ERR_INVALID_ARG, "\"image.jpg\"", 0,
                 "film.output: output \"image.jpg\" has no supported extension; expected a file name "
                 "ending in .png, .exr or .pfm");
    expect_error(WITH_SECTION("\"film\": {\"output\": \".png\"}"), CST_ERR_INVALID_ARG, "\".png\"", 0,
                 "film.output: output \".png\" has no supported extension");
}

static void test_materials(void **state)
{
    (void)state;
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.5, -0.1, 0.5]}}",
                        SHAPES),
                 CST_ERR_INVALID_ARG, "-0.1", 0,
                 "materials.white.albedo[1]: green -0.1 is outside [0, 1]");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 1.2]}}",
                        SHAPES),
                 CST_ERR_INVALID_ARG, "1.2", 0,
                 "materials.white.albedo[2]: blue 1.2 is outside [0, 1] (more than 1 would create energy); "
                 "expected a reflectance from 0 to 1");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"glass\", \"ior\": 0}}", SHAPES),
                 CST_ERR_INVALID_ARG, "0}}", 0,
                 "materials.white.ior: ior 0 is not positive; expected an index of refraction > 0");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"glass\", \"ior\": -1.3}}", SHAPES),
                 CST_ERR_INVALID_ARG, "-1.3", 0, "ior -1.3 is not positive");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"metal\"}}", SHAPES), CST_ERR_INVALID_ARG,
                 "\"metal\"", 0,
                 "materials.white.type: unknown material type \"metal\"; expected one of: diffuse, mirror, glass");
    expect_error(SCENE3(CAM, "\"materials\": {\"my white\": {\"type\": 7}}", SHAPES), CST_ERR_INVALID_ARG,
                 "7", 0, "materials[\"my white\"].type: got an integer; expected a string");
    /* unknown names list the known ones, in file order */
    expect_error(SCENE3(CAM,
                        "\"materials\": {\"white\": {\"type\": \"diffuse\"}, \"red\": {\"type\": \"mirror\"}}",
                        "\"shapes\": [{\"type\": \"quad\", \"material\": \"whte\", \"vertices\": " QUAD_V "}]"),
                 CST_ERR_INVALID_ARG, "\"whte\"", 0,
                 "shapes[0].material: material \"whte\" is not defined; expected one of: white, red");
    expect_error("{" CAM ", " SHAPES "}", CST_ERR_INVALID_ARG, "\"white\"", 0,
                 "material \"white\" is not defined (no materials are)");
}

static void test_type_names(void **state)
{
    (void)state;
    expect_error(WITH_SHAPE("{\"type\": \"cone\", \"material\": \"white\"}"), CST_ERR_INVALID_ARG, "\"cone\"", 0,
                 "shapes[0].type: unknown shape type \"cone\"; expected one of: quad, mesh, sphere");
    expect_error(WITH_CAM("{\"type\": \"fisheye\", \"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}"),
                 CST_ERR_INVALID_ARG, "\"fisheye\"", 0,
                 "camera.type: unknown camera type \"fisheye\"; expected one of: pinhole, thinlens");
    expect_error(WITH_SECTION("\"integrator\": {\"type\": \"bpt\"}"), CST_ERR_INVALID_ARG, "\"bpt\"", 0,
                 "integrator.type: unknown integrator \"bpt\"; expected one of: path, path-nee, path-bsdf, light");
    expect_error(WITH_SECTION("\"film\": {\"filter\": \"gauss\"}"), CST_ERR_INVALID_ARG, "\"gauss\"", 0,
                 "film.filter: unknown filter \"gauss\"; expected one of: box, tent");
}

/* sampler.type and the film's output keys (exposure, png_encoding, aovs). */
static void test_sampler_and_output_keys(void **state)
{
    (void)state;
    CstScene *s = expect_ok(WITH_SECTION("\"sampler\": {\"type\": \"sobol\", \"spp\": 4}, "
                                         "\"film\": {\"exposure\": -1.5, \"png_encoding\": \"linear\", "
                                         "\"aovs\": [\"depth\", \"normal\"], \"output\": \"a.exr\"}"));
    assert_int_equal(s->settings.sampler, CST_SAMPLER_SOBOL);
    assert_int_equal(cst_sampler_from_name("zsobol"), CST_SAMPLER_ZSOBOL);
    assert_string_equal(cst_sampler_name(CST_SAMPLER_ZSOBOL), "zsobol");
    assert_true(s->settings.exposure == -1.5 && s->settings.exposure_set);
    assert_int_equal(s->settings.png_linear, 1);
    assert_int_equal(s->settings.aovs, CST_AOV_DEPTH | CST_AOV_NORMAL);
    cst_scene_destroy(s);
    expect_error(WITH_SECTION("\"sampler\": {\"type\": \"halton\"}"), CST_ERR_INVALID_ARG, "\"halton\"", 0,
                 "sampler.type: unknown sampler \"halton\"; expected one of: independent, stratified, sobol");
    expect_error(WITH_SECTION("\"film\": {\"aovs\": [\"depth\", \"uv\"]}"), CST_ERR_INVALID_ARG, "\"uv\"", 0,
                 "unknown AOV \"uv\"; expected one of: albedo, normal, depth, variance");
    expect_error(WITH_SECTION("\"film\": {\"aovs\": \"depth\"}"), CST_ERR_INVALID_ARG, "\"depth\"", 0,
                 "expected an array of AOV names");
    expect_error(WITH_SECTION("\"film\": {\"png_encoding\": \"gamma\"}"), CST_ERR_INVALID_ARG, "\"gamma\"", 0,
                 "unknown PNG encoding \"gamma\"");
    expect_error(WITH_SECTION("\"film\": {\"exposure\": 65}"), CST_ERR_INVALID_ARG, "65", 0, "exposure");
    /* crop: pixel bounds x0, x1, y0, y1 */
    s = expect_ok(WITH_SECTION("\"film\": {\"width\": 64, \"height\": 48, \"crop\": [8, 40, 0, 48]}"));
    assert_int_equal(s->settings.crop[0], 8);
    assert_int_equal(s->settings.crop[1], 40);
    assert_int_equal(s->settings.crop[2], 0);
    assert_int_equal(s->settings.crop[3], 48);
    cst_scene_destroy(s);
    expect_error(WITH_SECTION("\"film\": {\"crop\": [8, 40, 0]}"), CST_ERR_INVALID_ARG, "[8", 0,
                 "film.crop: expected [x0, x1, y0, y1]");
    expect_error(WITH_SECTION("\"film\": {\"crop\": [40, 8, 0, 10]}"), CST_ERR_INVALID_ARG, "[40", 0,
                 "expected x0 < x1 and y0 < y1");
    expect_error(WITH_SECTION("\"film\": {\"width\": 32, \"crop\": [0, 40, 0, 10]}"), CST_ERR_INVALID_ARG, "[0, 40", 0,
                 "expected x1 <= width (32)");
    expect_error(WITH_SECTION("\"film\": {\"crop\": [0, 4, -1, 10]}"), CST_ERR_INVALID_ARG, "-1", 0, "film.crop[2]");
}

static void test_shapes(void **state)
{
    (void)state;
    /* "shapes": [] is an empty world (test_empty_world); a non-array is an error */
    expect_error(SCENE3(CAM, MATS, "\"shapes\": \"none\""), CST_ERR_INVALID_ARG, "\"none\"", 0,
                 "shapes: got a string; expected an array of shapes");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0,
                 "shapes[0].vertices: got an array of 3 elements; expected 4 vertices");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1], [0, 1, 0]]}"),
                 CST_ERR_INVALID_ARG, "[1, 1]", 0,
                 "shapes[0].vertices[2]: got an array of 2 elements; expected an array of 3 numbers");
    /* degenerate quads name the triangle */
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0,
                 "shapes[0].vertices: triangle 0 of the quad (v0, v1, v2) is degenerate (zero area)");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [2, 2, 0]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0,
                 "shapes[0].vertices: triangle 1 of the quad (v0, v2, v3) is degenerate (zero area)");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[5, 5, 5], [5, 5, 5], [5, 5, 5], [5, 5, 5]]}"),
                 CST_ERR_INVALID_ARG, "[[5", 0, "triangle 0 of the quad");
    /* v3 lifted by half the size: not planar; crossed (bow-tie) order: folded */
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0.5]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0,
                 "shapes[0].vertices: the quad is not planar: v3 is 0.5 off the plane of v0, v1, v2");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": [[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0, "face opposite ways");
    /* within 1% of the diagonal is accepted; just beyond is not */
    CstScene *s = expect_ok(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": "
                                       "[[0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 1.4]]}"));
    cst_scene_destroy(s);
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": "
                            "[[0, 0, 0], [100, 0, 0], [100, 100, 0], [0, 100, 1.5]]}"),
                 CST_ERR_INVALID_ARG, "[[0", 0, "not planar");
    /* emission */
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " QUAD_V
                            ", \"emission\": {\"radiance\": [1, -1, 1]}}"),
                 CST_ERR_INVALID_ARG, "-1", 0,
                 "shapes[0].emission.radiance[1]: green -1 is negative; expected a number >= 0");
    expect_error(WITH_SHAPE("{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " QUAD_V
                            ", \"emission\": [17, 12, 4]}"),
                 CST_ERR_INVALID_ARG, "[17", 0, "shapes[0].emission: got an array of 3 elements; expected an object");
    /* the second shape is named by its index */
    expect_error(SCENE3(CAM, MATS, "\"shapes\": [" QUAD ", {\"type\": \"sphere\", \"material\": \"white\", "
                                   "\"center\": [0, 0, 0], \"radius\": -2}]"),
                 CST_ERR_INVALID_ARG, "-2", 0, "shapes[1].radius");
}

#define MESH(verts, idx) \
    WITH_SHAPE("{\"type\": \"mesh\", \"material\": \"white\", \"vertices\": " verts ", \"indices\": " idx "}")
#define TETRA_V "[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]]"

static void test_meshes(void **state)
{
    (void)state;
    CstScene *s = expect_ok(MESH(TETRA_V, "[[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]]"));
    assert_int_equal(s->num_triangles, 4);
    assert_int_equal(s->num_positions, 4);
    cst_scene_destroy(s);
    expect_error(MESH(TETRA_V, "[[0, 2, 1], [0, 1, 7]]"), CST_ERR_INVALID_ARG, "7]", 0,
                 "shapes[0].indices[1][2]: vertex index 7 is out of range; expected 0 to 3 (the mesh has 4 vertices)");
    expect_error(MESH(TETRA_V, "[[0, -1, 1]]"), CST_ERR_INVALID_ARG, "-1", 0,
                 "shapes[0].indices[0][1]: vertex index -1 is out of range");
    expect_error(MESH(TETRA_V, "[[0, 1.0, 2]]"), CST_ERR_INVALID_ARG, "1.0", 0,
                 "shapes[0].indices[0][1]: got a number; expected a vertex index, an integer from 0 to 3");
    expect_error(MESH(TETRA_V, "[[0, 2, 1], [0, 1]]"), CST_ERR_INVALID_ARG, "[0, 1]", 0,
                 "shapes[0].indices[1]: got an array of 2 elements; expected a triangle");
    /* triangle 2 repeats a vertex; triangle 1 of the second case is collinear */
    expect_error(MESH(TETRA_V, "[[0, 2, 1], [0, 1, 3], [3, 3, 2]]"), CST_ERR_INVALID_ARG, "[3, 3, 2]", 0,
                 "shapes[0].indices[2]: triangle 2 is degenerate (zero area); expected 3 distinct, non-collinear vertices");
    expect_error(MESH("[[0, 0, 0], [1, 1, 1], [2, 2, 2], [0, 1, 0]]", "[[0, 1, 3], [0, 1, 2]]"), CST_ERR_INVALID_ARG,
                 "[0, 1, 2]", 0, "triangle 1 is degenerate");
    expect_error(MESH("[[0, 0, 0], [1, 0, 0]]", "[[0, 1, 0]]"), CST_ERR_INVALID_ARG, "[[0, 0, 0], [1, 0, 0]]", 0,
                 "shapes[0].vertices: got an array of 2 elements; expected at least 3 vertices");
    expect_error(MESH(TETRA_V, "[]"), CST_ERR_INVALID_ARG, "[]", 0,
                 "shapes[0].indices: got an array of 0 elements; expected at least 1 triangle");
    expect_error(MESH("[[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, true]]", "[[0, 1, 2]]"), CST_ERR_INVALID_ARG,
                 "true", 0, "shapes[0].vertices[3][2]: got true; expected a number");
}

/* Hand-counted positions: the message is the contract, so these compare it whole. */
static void test_exact_positions(void **state)
{
    (void)state;
    expect_message("{\n"
                   "  \"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                   "  \"materials\": {\"white\": {\"type\": \"diffuse\"}},\n"
                   "  \"shapes\": [\n"
                   "    {\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], \"radius\": -2}\n"
                   "  ]\n"
                   "}\n",
                   CST_ERR_INVALID_ARG,
                   NAME ":5:76: shapes[0].radius: radius -2 is not positive; expected a number > 0");
    expect_message("{\n"
                   "  \"film\": {\"width\": 64, \"hieght\": 64},\n"
                   "  \"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}\n"
                   "}",
                   CST_ERR_INVALID_ARG,
                   NAME ":2:25: film: unknown key \"hieght\"; expected one of: width, height, filter, output, exposure, "
                   "png_encoding, aovs, crop, max_component");
    /* columns count code points: é (2 bytes), € (3), 😀 (4) are one column each */
    expect_message("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                   "\t\"materials\": {\"\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\": {\"type\": \"diffuse\", "
                   "\"albedo\": [0.5, 2, 0.5]}}, \"shapes\": []}",
                   CST_ERR_INVALID_ARG,
                   NAME ":2:59: materials[\"\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80\"].albedo[1]: green 2 is "
                   "outside [0, 1] (more than 1 would create energy); expected a reflectance from 0 to 1");
    expect_message("{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
                   " \"materials\": {\"m\": {\"type\": \"diffuse\"}},\n"
                   " \"shapes\": [\n"
                   "  {\"type\": \"mesh\", \"material\": \"m\",\n"
                   "   \"vertices\": [[0, 0, 0], [1, 0, 0], [0, 1, 0]],\n"
                   "   \"indices\": [[0, 1, 2],\n"
                   "               [2, 1, 3]]}]}",
                   CST_ERR_INVALID_ARG,
                   NAME ":7:23: shapes[0].indices[1][2]: vertex index 3 is out of range; expected 0 to 2 "
                   "(the mesh has 3 vertices)");
    /* CRLF line ends: '\r' is one more column at the end of a line, never a line break */
    expect_message("{\r\n  \"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 400}\r\n}",
                   CST_ERR_INVALID_ARG,
                   NAME ":2:66: camera.fov: fov 400 is out of range; expected the vertical field of view in "
                   "degrees, greater than 0 and less than 180");
}

static void test_io_errors(void **state)
{
    (void)state;
    CstScene *scene = (CstScene *)(uintptr_t)1;
    CstError err;
    const char *path = CST_SOURCE_DIR "/scenes/does-not-exist.json";
    assert_int_equal(cst_scene_load_json(path, &scene, &err), CST_ERR_IO);
    assert_null(scene);
    char want[512];
    snprintf(want, sizeof want, "%s: cannot open: No such file or directory", path);
    assert_string_equal(err.msg, want);
    assert_int_equal(err.status, CST_ERR_IO);
    /* a directory is refused before anything is read */
    assert_int_equal(cst_scene_load_json(CST_SOURCE_DIR "/scenes", &scene, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "is not a regular file (a directory)"));
    /* bad arguments and a NULL error sink */
    assert_int_equal(cst_scene_load_json(path, &scene, NULL), CST_ERR_IO);
    assert_int_equal(cst_scene_load_json_string(NULL, 5, NULL, &scene, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_load_json_string("{}", 2, NULL, NULL, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_load_json_string("{}", 2, NULL, &scene, NULL), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_load_json_string("{}", 2, NULL, &scene, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "<string>:1:1: missing key \"camera\""));
}

/* ------------------------------------------------------------------ successful loads */

static CstScene *load_file(const char *path)
{
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus st = cst_scene_load_json(path, &scene, &err);
    if (st != CST_OK)
        fail_msg("%s: %s", cst_status_name(st), err.msg);
    return scene;
}

static void test_defaults(void **state)
{
    (void)state;
    /* sections in any order; everything optional left at its default */
    CstScene *s = expect_ok("{\"shapes\": [{\"type\": \"sphere\", \"material\": \"m\", \"center\": [1, 2, 3], "
                            "\"radius\": 0.5}], \"materials\": {\"m\": {\"type\": \"diffuse\"}, "
                            "\"g\": {\"type\": \"glass\"}, \"r\": {\"type\": \"mirror\"}}, "
                            "\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 1], \"fov\": 30}}");
    assert_int_equal(s->settings.width, 0);
    assert_int_equal(s->settings.spp, 0);
    assert_int_equal(s->settings.seed_set, 0);
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_DEFAULT);
    assert_int_equal(s->settings.filter, CST_FILTER_DEFAULT);
    assert_null(cst_scene_output_path(s));
    assert_int_equal(s->num_materials, 3);
    assert_int_equal(s->materials[0].type, MATERIAL_DIFFUSE);
    assert_true(s->materials[0].albedo.c[1] == 0.5f);
    assert_int_equal(s->materials[1].type, MATERIAL_GLASS);
    assert_true(s->materials[1].ior == 1.5f && s->materials[1].albedo.c[0] == 1.0f);
    assert_int_equal(s->materials[2].type, MATERIAL_MIRROR);
    assert_true(s->materials[2].albedo.c[2] == 1.0f);
    assert_int_equal(s->num_spheres, 1);
    assert_int_equal(s->num_emitters, 0);
    assert_true(s->camera.up.y == 1.0f && s->camera.aperture_radius == 0.0f);
    assert_true(s->camera.focus_distance == 4.0f);
    assert_true(s->committed);
    cst_scene_destroy(s);
    /* integrator aliases and the other names */
    s = expect_ok(WITH_SECTION("\"integrator\": {\"type\": \"nee\", \"max_depth\": 5, \"rr_depth\": 1}, "
                               "\"film\": {\"filter\": \"tent\", \"output\": \"out/A.EXR\"}"));
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_PATH_NEE);
    assert_int_equal(s->settings.max_depth, 5);
    assert_int_equal(s->settings.rr_depth, 1);
    assert_int_equal(s->settings.filter, CST_FILTER_TENT);
    assert_string_equal(cst_scene_output_path(s), "out/A.EXR");
    /* light_rr_depth unset: a render resolves it to rr_depth */
    CstRenderSettings rs;
    cst_render_settings_resolve(s, NULL, &rs);
    assert_int_equal(rs.rr_depth, 1);
    assert_int_equal(rs.light_rr_depth, 1);
    cst_scene_destroy(s);
    s = expect_ok(WITH_SECTION("\"integrator\": {\"type\": \"bdpt\", \"light_rr_depth\": 2}"));
    cst_render_settings_resolve(s, NULL, &rs);
    assert_int_equal(rs.rr_depth, 3);
    assert_int_equal(rs.light_rr_depth, 2);
    cst_scene_destroy(s);
    s = expect_ok(WITH_SECTION("\"integrator\": {\"type\": \"light\"}"));
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_LIGHT);
    cst_scene_destroy(s);
    /* regularize (pbrt-v4's option) and the film's max_component clamp */
    s = expect_ok(WITH_SECTION("\"integrator\": {\"regularize\": true}, \"film\": {\"max_component\": 7.5}"));
    assert_int_equal(s->settings.regularize, 1);
    assert_true(s->settings.max_component == 7.5);
    cst_scene_destroy(s);
    s = expect_ok(WITH_SECTION("\"integrator\": {\"type\": \"lighttracing\"}"));
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_LIGHT);
    cst_scene_destroy(s);
    s = expect_ok(WITH_SECTION("\"integrator\": {\"type\": \"photon\", \"photons\": 5000, \"radius\": 12.5}"));
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_PHOTON);
    assert_int_equal(s->settings.photons, 5000);
    assert_true(s->settings.photon_radius == 12.5);
    cst_scene_destroy(s);
    /* two-sided emission on a sphere */
    s = expect_ok(WITH_SHAPE("{\"type\": \"sphere\", \"material\": \"white\", \"center\": [0, 0, 0], \"radius\": 2, "
                             "\"emission\": {\"radiance\": [1, 2, 3], \"two_sided\": true}}"));
    assert_int_equal(s->num_emitters, 1);
    assert_true(s->emitters[0].two_sided);
    assert_true(s->emitters[0].radiance.c[2] == 3.0f);
    cst_scene_destroy(s);
}

static void test_cornell_box_file(void **state)
{
    (void)state;
    CstScene *s = load_file(CST_SOURCE_DIR "/scenes/cornell-box.json");
    assert_int_equal(s->num_triangles, 32);
    assert_int_equal(s->num_spheres, 0);
    assert_int_equal(s->num_materials, 4);
    assert_int_equal(s->num_emitters, 2); /* the light quad's two triangles */
    assert_int_equal(s->settings.width, 512);
    assert_int_equal(s->settings.height, 512);
    assert_int_equal(s->settings.spp, 64);
    assert_int_equal(s->settings.seed_set, 1);
    assert_int_equal(s->settings.seed, 0);
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_PATH);
    assert_int_equal(s->settings.filter, CST_FILTER_BOX);
    assert_string_equal(cst_scene_output_path(s), "cornell-box.png");
    assert_true(s->camera.vfov_deg == (float)39.3077);
    assert_true(s->emitters[0].radiance.c[0] == 17.0f && s->emitters[0].two_sided == 0);
    cst_scene_destroy(s);
}

/* The file and the built-in scene must hold bit-identical geometry, materials, emitters
 * and camera, or renders of the two could not match bit for bit. */
static void test_cornell_box_matches_builtin(void **state)
{
    (void)state;
    CstScene *a = load_file(CST_SOURCE_DIR "/scenes/cornell-box.json");
    CstScene *b = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&b, &err), CST_OK);
    assert_int_equal(a->num_positions, b->num_positions);
    assert_memory_equal(a->positions, b->positions, (size_t)a->num_positions * sizeof *a->positions);
    assert_int_equal(a->num_triangles, b->num_triangles);
    assert_memory_equal(a->tri_indices, b->tri_indices, (size_t)a->num_triangles * 3 * sizeof *a->tri_indices);
    assert_memory_equal(a->tri_info, b->tri_info, (size_t)a->num_triangles * sizeof *a->tri_info);
    assert_int_equal(a->num_materials, b->num_materials);
    for (int i = 0; i < a->num_materials; i++) {
        assert_int_equal(a->materials[i].type, b->materials[i].type);
        assert_memory_equal(&a->materials[i].albedo, &b->materials[i].albedo, sizeof(Color));
        assert_true(a->materials[i].ior == b->materials[i].ior);
    }
    assert_int_equal(a->num_emitters, b->num_emitters);
    for (int i = 0; i < a->num_emitters; i++) {
        assert_int_equal(a->emitters[i].prim, b->emitters[i].prim);
        assert_memory_equal(&a->emitters[i].radiance, &b->emitters[i].radiance, sizeof(Color));
        assert_int_equal(a->emitters[i].two_sided, b->emitters[i].two_sided);
        assert_true(a->emitters[i].area == b->emitters[i].area);
    }
    assert_memory_equal(&a->camera.position, &b->camera.position, sizeof(Vec3));
    assert_memory_equal(&a->camera.look_at, &b->camera.look_at, sizeof(Vec3));
    assert_memory_equal(&a->camera.up, &b->camera.up, sizeof(Vec3));
    assert_true(a->camera.vfov_deg == b->camera.vfov_deg);
    assert_true(a->camera.aperture_radius == b->camera.aperture_radius);
    assert_true(a->camera.focus_distance == b->camera.focus_distance);
    assert_string_equal(cst_scene_output_path(a), cst_scene_output_path(b));
    assert_int_equal(a->settings.width, b->settings.width);
    assert_int_equal(a->settings.height, b->settings.height);
    cst_scene_destroy(a);
    cst_scene_destroy(b);
}

static void test_cornell_spheres_file(void **state)
{
    (void)state;
    CstScene *s = load_file(CST_SOURCE_DIR "/scenes/cornell-spheres.json");
    assert_int_equal(s->num_spheres, 2);
    assert_int_equal(s->num_triangles, 6 * 2 + 4);
    assert_int_equal(s->num_materials, 7);
    assert_true(s->camera.aperture_radius == 8.0f);
    assert_true(s->camera.focus_distance == 1000.0f);
    assert_int_equal(s->settings.filter, CST_FILTER_TENT);
    int mirror = s->sphere_info[0].material, glass = s->sphere_info[1].material;
    assert_int_equal(s->materials[mirror].type, MATERIAL_MIRROR);
    assert_int_equal(s->materials[glass].type, MATERIAL_GLASS);
    assert_true(s->materials[glass].ior == 1.5f);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ robustness */

static char *read_whole(const char *path, size_t *len)
{
    FILE *f = fopen(path, "rb");
    assert_non_null(f);
    char *buf = malloc(1 << 16);
    assert_non_null(buf);
    *len = fread(buf, 1, 1 << 16, f);
    fclose(f);
    return buf;
}

/* Every byte of a real scene replaced by a few troublemakers, and every prefix: each load
 * either succeeds or fails with a located message, and nothing leaks (under valgrind or
 * ASan). A semantic error without a position would mean the locator lost its way. */
static void test_mutations(void **state)
{
    (void)state;
    size_t len;
    char *text = read_whole(CST_SOURCE_DIR "/scenes/cornell-spheres.json", &len);
    static const char subst[] = {'"', '}', ']', ',', '0', '-', 'x', '\\', '[', '{'};
    char prefix[32];
    snprintf(prefix, sizeof prefix, "%s:", NAME);
    int ok = 0, failed = 0;
    for (size_t i = 0; i < len; i += 3) { /* every third byte keeps valgrind runs short */
        for (size_t k = 0; k < sizeof subst; k++) {
            char *copy = malloc(len);
            assert_non_null(copy);
            memcpy(copy, text, len);
            copy[i] = subst[k];
            CstScene *s = NULL;
            CstError err = {0};
            CstStatus st = cst_scene_load_json_string(copy, len, NAME, &s, &err);
            if (st == CST_OK) {
                assert_non_null(s);
                ok++;
            } else {
                int line = 0, col = 0;
                assert_null(s);
                if (sscanf(err.msg, NAME ":%d:%d: ", &line, &col) != 2 || line < 1 || col < 1)
                    fail_msg("unlocated error after replacing byte %zu with '%c': %s", i, subst[k], err.msg);
                failed++;
            }
            cst_scene_destroy(s);
            free(copy);
        }
    }
    for (size_t n = 0; n < len; n += 7) {
        CstScene *s = NULL;
        CstError err;
        assert_int_equal(cst_scene_load_json_string(text, n, NAME, &s, &err), CST_ERR_PARSE);
        assert_null(s);
    }
    assert_true(ok > 0 && failed > 0);
    free(text);
}

/* The materials of issue #5: conductor (named or complex IOR), rough dielectric, plastic,
 * roughness and two_sided, with their errors. */
static void test_new_materials(void **state)
{
    (void)state;
    CstScene *s = expect_ok(SCENE3(CAM,
        "\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"gold\", \"roughness\": 0.2}, "
        "\"c\": {\"type\": \"conductor\", \"eta\": [0.2, 0.9, 1.1], \"k\": [3.9, 2.4, 2.1], \"two_sided\": false}, "
        "\"d\": {\"type\": \"dielectric\", \"ior\": 1.33, \"roughness\": 0.1}, "
        "\"p\": {\"type\": \"plastic\", \"albedo\": [0.8, 0.1, 0.1], \"roughness\": 0.3}}",
        SHAPES));
    assert_int_equal(s->num_materials, 4);
    assert_int_equal(s->materials[0].type, MATERIAL_CONDUCTOR);
    assert_true(s->materials[0].roughness == 0.2f && s->materials[0].k.c[0] > 3.0f && !s->materials[0].one_sided);
    assert_int_equal(s->materials[1].type, MATERIAL_CONDUCTOR);
    assert_true(s->materials[1].eta.c[1] == 0.9f && s->materials[1].k.c[2] == 2.1f && s->materials[1].one_sided);
    assert_int_equal(s->materials[2].type, MATERIAL_DIELECTRIC);
    assert_true(s->materials[2].ior == 1.33f && s->materials[2].roughness == 0.1f);
    assert_int_equal(s->materials[3].type, MATERIAL_PLASTIC);
    assert_true(s->materials[3].ior == 1.5f && s->materials[3].prepared && s->materials[3].coat_e_avg > 0.0f);
    cst_scene_destroy(s);

    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"brass\"}}", SHAPES),
                 CST_ERR_INVALID_ARG, "\"brass\"", 0,
                 "materials.white.metal: unknown metal \"brass\"; expected one of: gold, silver, copper, aluminium");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"conductor\"}}", SHAPES),
                 CST_ERR_INVALID_ARG, "{\"type\": \"conductor\"", 0,
                 "materials.white: missing key \"metal\"; expected a named metal");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"conductor\", \"eta\": [1, 1, 1]}}", SHAPES),
                 CST_ERR_INVALID_ARG, "{\"type\": \"conductor\"", 0, "missing key \"k\"");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"dielectric\", \"roughness\": 1.5}}", SHAPES),
                 CST_ERR_INVALID_ARG, "1.5", 0,
                 "materials.white.roughness: roughness 1.5 is outside [0, 1]; expected 0 (smooth) to 1 (roughest)");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"plastic\", \"ior\": 0.8}}", SHAPES),
                 CST_ERR_INVALID_ARG, "0.8", 0, "ior 0.8 is below 1");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"diffuse\", \"two_sided\": 1}}", SHAPES),
                 CST_ERR_INVALID_ARG, "1}", 0, "materials.white.two_sided: got");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"glass\", \"roughness\": 0.1}}", SHAPES),
                 CST_ERR_INVALID_ARG, "\"roughness\"", 0,
                 "unknown key \"roughness\"; expected one of: type, albedo, ior");
}

/* The coated materials (pbrt-v4's coateddiffuse and coatedconductor): their keys, pbrt-v4's
 * layer defaults, and the layer's errors. */
static void test_coated_materials(void **state)
{
    (void)state;
    CstScene *s = expect_ok(SCENE3(CAM,
        "\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"albedo\": [0.8, 0.1, 0.1], \"roughness\": 0.3}, "
        "\"c\": {\"type\": \"coated_conductor\", \"metal\": \"gold\", \"base_roughness\": 0.4, \"ior\": 1.3, "
        "\"thickness\": 0.2, \"layer_albedo\": [0.5, 0.5, 0.5], \"g\": -0.3, \"max_depth\": 20, \"nsamples\": 2}}",
        SHAPES));
    assert_int_equal(s->num_materials, 2);
    const Material *m = &s->materials[0];
    assert_int_equal(m->type, MATERIAL_COATED_DIFFUSE);
    assert_true(m->roughness == 0.3f && m->ior == 1.5f && m->albedo.c[1] == 0.1f);
    assert_true(m->thickness == 0.01f && m->max_depth == 10 && m->nsamples == 1 && m->g == 0.0f);
    m = &s->materials[1];
    assert_int_equal(m->type, MATERIAL_COATED_CONDUCTOR);
    assert_true(m->base_roughness == 0.4f && m->ior == 1.3f && m->k.c[0] > 3.0f);
    assert_true(m->thickness == 0.2f && m->layer_albedo.c[2] == 0.5f && m->g == -0.3f);
    assert_true(m->max_depth == 20 && m->nsamples == 2);
    cst_scene_destroy(s);
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"g\": 1}}", SHAPES),
                 CST_ERR_INVALID_ARG, "1}", 0, "materials.white.g: g 1 is outside (-1, 1)");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"thickness\": -1}}", SHAPES),
                 CST_ERR_INVALID_ARG, "-1}", 0, "materials.white.thickness: thickness -1 is negative");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"metal\": \"gold\"}}", SHAPES),
                 CST_ERR_INVALID_ARG, "\"metal\"", 0, "unknown key \"metal\"");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"coated_conductor\"}}", SHAPES),
                 CST_ERR_INVALID_ARG, "{\"type\": \"coated_conductor\"", 0, "missing key \"metal\"");
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"max_depth\": 0}}", SHAPES),
                 CST_ERR_INVALID_ARG, "0}}", 0, "materials.white.max_depth");
}

/* diffuse_transmission (pbrt-v4's defaults 0.25 and 0.25) and thin_dielectric. */
static void test_transmitter_materials(void **state)
{
    (void)state;
    CstScene *s = expect_ok(SCENE3(CAM,
        "\"materials\": {\"white\": {\"type\": \"diffuse_transmission\", \"transmittance\": [0.5, 0.6, 0.7]}, "
        "\"t\": {\"type\": \"thin_dielectric\", \"ior\": 1.33}, \"d\": {\"type\": \"diffuse_transmission\"}}",
        SHAPES));
    assert_int_equal(s->materials[0].type, MATERIAL_DIFFUSE_TRANSMISSION);
    assert_true(s->materials[0].albedo.c[0] == 0.25f && s->materials[0].transmittance.c[2] == 0.7f);
    assert_true(s->materials[1].type == MATERIAL_THIN_DIELECTRIC && s->materials[1].ior == 1.33f);
    assert_true(s->materials[2].transmittance.c[1] == 0.25f);
    cst_scene_destroy(s);
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"diffuse_transmission\", \"transmittance\": "
                             "[2, 0, 0]}}", SHAPES),
                 CST_ERR_INVALID_ARG, "2, 0, 0]}", 0, "materials.white.transmittance[0]: red 2 is outside [0, 1]");
}

/* The mix material: names resolved among the materials above it, amount, and errors. */
static void test_mix_material(void **state)
{
    (void)state;
    CstScene *s = expect_ok(SCENE3(CAM,
        "\"materials\": {\"a\": {\"type\": \"diffuse\"}, \"b\": {\"type\": \"glass\"}, "
        "\"white\": {\"type\": \"mix\", \"materials\": [\"a\", \"b\"], \"amount\": 0.25}}",
        SHAPES));
    assert_int_equal(s->num_materials, 3);
    const Material *m = &s->materials[2];
    assert_int_equal(m->type, MATERIAL_MIX);
    assert_true(m->mix[0] == 0 && m->mix[1] == 1 && m->amount == 0.25f);
    cst_scene_destroy(s);
    expect_error(SCENE3(CAM, "\"materials\": {\"white\": {\"type\": \"mix\", \"materials\": [\"white\", \"x\"]}}", SHAPES),
                 CST_ERR_INVALID_ARG, "\"white\", \"x\"", 0,
                 "materials.white.materials[0]: material \"white\" is not defined before the mix");
    expect_error(SCENE3(CAM, "\"materials\": {\"a\": {\"type\": \"diffuse\"}, \"white\": {\"type\": \"mix\", "
                             "\"materials\": [\"a\"]}}", SHAPES),
                 CST_ERR_INVALID_ARG, "[\"a\"]", 0, "materials.white.materials: expected an array of the names of two");
    expect_error(SCENE3(CAM, "\"materials\": {\"a\": {\"type\": \"diffuse\"}, \"white\": {\"type\": \"mix\", "
                             "\"materials\": [\"a\", \"a\"], \"amount\": 2}}", SHAPES),
                 CST_ERR_INVALID_ARG, "2}}", 0, "materials.white.amount: amount 2 is outside [0, 1]");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_locate_basic),
        cmocka_unit_test(test_locate_not_found),
        cmocka_unit_test(test_locate_escapes),
        cmocka_unit_test(test_locate_nested),
        cmocka_unit_test(test_locate_unicode),
        cmocka_unit_test(test_locate_truncated_and_garbage),
        cmocka_unit_test(test_locate_deep),
        cmocka_unit_test(test_locate_matches_jansson),
        cmocka_unit_test(test_offset_location),
        cmocka_unit_test(test_syntax_errors),
        cmocka_unit_test(test_unknown_keys),
        cmocka_unit_test(test_missing_keys),
        cmocka_unit_test(test_wrong_types),
        cmocka_unit_test(test_ranges),
        cmocka_unit_test(test_materials),
        cmocka_unit_test(test_type_names),
        cmocka_unit_test(test_sampler_and_output_keys),
        cmocka_unit_test(test_shapes),
        cmocka_unit_test(test_meshes),
        cmocka_unit_test(test_exact_positions),
        cmocka_unit_test(test_io_errors),
        cmocka_unit_test(test_defaults),
        cmocka_unit_test(test_cornell_box_file),
        cmocka_unit_test(test_cornell_box_matches_builtin),
        cmocka_unit_test(test_cornell_spheres_file),
        cmocka_unit_test(test_mutations),
        cmocka_unit_test(test_new_materials),
        cmocka_unit_test(test_coated_materials),
        cmocka_unit_test(test_mix_material),
        cmocka_unit_test(test_transmitter_materials),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
