/* Unit tests for the pbrt-v4 loader (scene/pbrt_tokenizer.c, scene/scene_pbrt.c): tokens
 * and their locations, every directive and parameter type, the mapping of materials,
 * lights, shapes and the camera, the warnings (by code) for what is approximated or
 * skipped, malformed input (status and file:line:column), and the Cornell box in pbrt
 * format rendering bit for bit like the JSON one. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "caustic/caustic.h"
#include "camera/camera.h"
#include "film/film.h"
#include "film/image_io.h"
#include "scene/pbrt_tokenizer.h"
#include "scene/scene.h"
#include "scene/scene_pbrt.h"

#define NAME "t.pbrt"

/* ------------------------------------------------------------------ helpers */

typedef struct Warnings {
    int n;
    CstWarningCode code[64];
    char msg[64][256];
} Warnings;

static void collect(void *user, CstWarningCode code, const char *message)
{
    Warnings *w = user;
    if (w->n < 64) {
        w->code[w->n] = code;
        snprintf(w->msg[w->n], sizeof w->msg[0], "%s", message);
    }
    w->n++;
}

/* The first warning with `code` whose message contains `what`, or -1. */
static int find_warning(const Warnings *w, CstWarningCode code, const char *what)
{
    for (int i = 0; i < w->n && i < 64; i++)
        if (w->code[i] == code && strstr(w->msg[i], what)) return i;
    return -1;
}

static CstStatus load_w(const char *text, CstScene **out, CstError *err, Warnings *w)
{
    CstLoadOptions opt = {0};
    opt.warning = collect;
    opt.warning_user = w;
    opt.no_file_access = 1;
    return cst_scene_load_pbrt_string(text, strlen(text), NAME, &opt, out, err);
}

/* 1-based line and column of the nth occurrence of needle. */
static void pos_of(const char *text, const char *needle, int nth, int *line, int *col)
{
    const char *at = text;
    for (int i = 0;; i++) {
        at = strstr(at, needle);
        if (!at) fail_msg("needle \"%s\" #%d not in the test text", needle, nth);
        if (i == nth) break;
        at++;
    }
    *line = 1;
    *col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') { (*line)++; *col = 1; }
        else if (((unsigned char)*p & 0xC0) != 0x80) (*col)++;
    }
}

static void expect_error(const char *text, CstStatus status, const char *needle, int nth,
                         const char *what)
{
    CstScene *scene = (CstScene *)(uintptr_t)1;
    CstError err = {0};
    Warnings w = {0};
    CstStatus st = load_w(text, &scene, &err, &w);
    if (st != status)
        fail_msg("status %s, expected %s; message: %s\ntext: %s", cst_status_name(st),
                 cst_status_name(status), err.msg, text);
    assert_null(scene);
    int line, col;
    pos_of(text, needle, nth, &line, &col);
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("message \"%s\" does not start with \"%s\"\ntext: %s", err.msg, prefix, text);
    if (what && !strstr(err.msg, what)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
}

static Scene *expect_ok(const char *text, Warnings *w)
{
    CstScene *scene = NULL;
    CstError err = {0};
    Warnings local = {0};
    CstStatus st = load_w(text, &scene, &err, w ? w : &local);
    if (st != CST_OK) fail_msg("%s: %s\ntext: %s", cst_status_name(st), err.msg, text);
    assert_non_null(scene);
    return scene;
}

#define CAMERA "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
#define TRI "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2]\n"
#define WORLD(body) CAMERA "WorldBegin\n" body

static void assert_vec(Vec3 v, float x, float y, float z, float tol)
{
    if (!(fabsf(v.x - x) <= tol && fabsf(v.y - y) <= tol && fabsf(v.z - z) <= tol))
        fail_msg("(%g, %g, %g), expected (%g, %g, %g)", (double)v.x, (double)v.y, (double)v.z,
                 (double)x, (double)y, (double)z);
}

static Vec3 tri_vertex(const Scene *s, int t, int k) { return s->positions[s->tri_indices[3 * t + k]]; }

/* ------------------------------------------------------------------ tokenizer */

static void test_tokens(void **state)
{
    (void)state;
    const char *t = "# comment\nShape \"tri\\\"x\" [ -1.5e2 .5 ]\n  true";
    PbrtTokenizer tz;
    PbrtToken k;
    CstError err;
    pbrt_tokenizer_init(&tz, t, strlen(t), "f");
    static const struct { PbrtTokenKind kind; int line, col; } want[] = {
        {PBRT_TOK_WORD, 2, 1}, {PBRT_TOK_STRING, 2, 7}, {PBRT_TOK_LBRACKET, 2, 16},
        {PBRT_TOK_NUMBER, 2, 18}, {PBRT_TOK_NUMBER, 2, 25}, {PBRT_TOK_RBRACKET, 2, 28},
        {PBRT_TOK_WORD, 3, 3}, {PBRT_TOK_EOF, 3, 7}};
    for (size_t i = 0; i < sizeof want / sizeof want[0]; i++) {
        assert_int_equal(pbrt_next_token(&tz, &k, &err), CST_OK);
        if (k.kind != want[i].kind || k.line != want[i].line || k.column != want[i].col)
            fail_msg("token %zu: kind %d at %d:%d, expected kind %d at %d:%d", i, k.kind, k.line,
                     k.column, want[i].kind, want[i].line, want[i].col);
        if (i == 1) {
            char *s = pbrt_token_string(&k);
            assert_string_equal(s, "tri\"x");
            free(s);
        }
        if (i == 3) assert_true(k.number == -150.0);
        if (i == 4) assert_true(k.number == 0.5);
    }
}

static void expect_lex_error(const char *text, int line, int col, const char *what)
{
    PbrtTokenizer tz;
    PbrtToken k;
    CstError err = {0};
    pbrt_tokenizer_init(&tz, text, strlen(text), "f");
    CstStatus st;
    do st = pbrt_next_token(&tz, &k, &err);
    while (st == CST_OK && k.kind != PBRT_TOK_EOF);
    assert_int_equal(st, CST_ERR_PARSE);
    char prefix[32];
    snprintf(prefix, sizeof prefix, "f:%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0 || !strstr(err.msg, what))
        fail_msg("\"%s\": expected \"%s...%s\"", err.msg, prefix, what);
}

static void test_token_errors(void **state)
{
    (void)state;
    expect_lex_error("Shape \"sphere\n", 1, 7, "unterminated string");
    expect_lex_error("Shape \"sph", 1, 7, "unterminated string");
    expect_lex_error("\n  1.2.3", 2, 3, "malformed number");
    expect_lex_error("1e999", 1, 1, "out of range");
    expect_lex_error("Shape {", 1, 7, "unexpected character '{'");
    expect_lex_error("\"a\\q\"", 1, 3, "unknown escape");
    expect_lex_error("Shape\x01", 1, 6, "unexpected character after a word");
    const char nul[] = "Shape \0";
    PbrtTokenizer tz;
    PbrtToken k;
    CstError err;
    pbrt_tokenizer_init(&tz, nul, sizeof nul - 1, "f");
    assert_int_equal(pbrt_next_token(&tz, &k, &err), CST_OK);
    assert_int_equal(pbrt_next_token(&tz, &k, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "f:1:7: NUL"));
}

/* ------------------------------------------------------------------ syntax errors */

static void test_parse_errors(void **state)
{
    (void)state;
    /* unbalanced brackets: the directive word that follows is where ']' was expected */
    expect_error(WORLD("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0\nAttributeBegin\n"),
                 CST_ERR_PARSE, "AttributeBegin", 0, "expected ']' to close the '[' at 4:33");
}

static void test_parse_errors_located(void **state)
{
    (void)state;
    const char *eof = WORLD("Shape \"trianglemesh\" \"point3 P\" [0 0 0");
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    assert_int_equal(load_w(eof, &s, &err, &w), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "t.pbrt:4:"));
    assert_non_null(strstr(err.msg, "the end of the file"));
    expect_error(WORLD("Shape \"sphere\" ]\n"), CST_ERR_PARSE, "]", 0, "expected a directive");
    expect_error(WORLD("Sphere \"x\"\n"), CST_ERR_PARSE, "Sphere", 0, "unknown directive");
    expect_error(WORLD("\"float radius\" 3\n"), CST_ERR_PARSE, "\"float radius\"", 0,
                 "a parameter outside a directive");
    /* wrong parameter type, unknown type, malformed declaration, mixed values */
    expect_error("LookAt 0 0 -5 0 0 0 0 1 0\nCamera \"perspective\" \"integer fov\" 45\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"integer fov\"", 0, "has type integer; expected float");
    expect_error(WORLD("Shape \"sphere\" \"real radius\" 2\n"), CST_ERR_PARSE, "\"real radius\"", 0,
                 "unknown parameter type \"real\"");
    expect_error(WORLD("Shape \"sphere\" \"radius\" 2\n"), CST_ERR_PARSE, "\"radius\"", 0,
                 "expected \"type name\"");
    /* found by fuzz_pbrt: a type name longer than its buffer overran the stack */
    expect_error(WORLD("Shape \"sphere\" \"floatfloatfloatfloatfloatfloatfloatfloatfloatfloatfloatfloatfloatfloat r\" 2\n"),
                 CST_ERR_PARSE, "\"floatfloat", 0, "expected \"type name\"");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" [1 \"a\"]\n"), CST_ERR_PARSE,
                 "\"float radius\"", 0, "mixes numbers and strings");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" \"big\"\n"), CST_ERR_INVALID_ARG,
                 "\"float radius\"", 0, "expected numbers");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" []\n"), CST_ERR_INVALID_ARG,
                 "\"float radius\"", 0, "no values");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" [1 2]\n"), CST_ERR_INVALID_ARG,
                 "\"float radius\"", 0, "expected one");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" 1 \"float radius\" 2\n"),
                 CST_ERR_INVALID_ARG, "\"float radius\"", 1, "given twice");
    expect_error(WORLD("Shape \"sphere\" \"float radius\" Shape\n"), CST_ERR_PARSE, "Shape", 1,
                 "expected its value");
    expect_error(WORLD(TRI "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1] \"integer indices\" [0 1 2]\n"),
                 CST_ERR_INVALID_ARG, "\"point3 P\"", 1, "expected a multiple of 3");
    expect_error(WORLD("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1.5 2]\n"),
                 CST_ERR_INVALID_ARG, "\"integer indices\"", 0, "not an integer");
    expect_error(WORLD("Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 3]\n"),
                 CST_ERR_INVALID_ARG, "\"integer indices\"", 0, "out of range");
    expect_error(WORLD("Shape \"sphere\" \"bool x\" \"maybe\"\n"), CST_ERR_INVALID_ARG, "\"bool x\"", 0,
                 "expected true or false");
    expect_error(WORLD("Material \"diffuse\" \"rgb reflectance\" [1 1]\n" TRI), CST_ERR_INVALID_ARG,
                 "\"rgb reflectance\"", 0, "exactly 3");
    expect_error(WORLD("Material \"diffuse\" \"spectrum reflectance\" [400 1 500]\n" TRI),
                 CST_ERR_INVALID_ARG, "\"spectrum reflectance\"", 0, "pairs");
    expect_error(WORLD("Material \"diffuse\" \"spectrum reflectance\" [500 1 400 1]\n" TRI),
                 CST_ERR_INVALID_ARG, "\"spectrum reflectance\"", 0, "does not increase");
    expect_error(WORLD("Translate 1 2\nWorldEnd\n"), CST_ERR_PARSE, "WorldEnd", 0, "expected 3 numbers");
    expect_error(WORLD("ConcatTransform [1 0 0 0 0 1 0 0 0 0 1 0 0 0 0 1 1]\n"), CST_ERR_PARSE,
                 "1]", 0, "expected ']'");
    expect_error(WORLD("ActiveTransform Sometimes\n"), CST_ERR_PARSE, "Sometimes", 0, "StartTime");
}

static void test_semantic_errors(void **state)
{
    (void)state;
    expect_error(WORLD("NamedMaterial \"gold\"\n" TRI), CST_ERR_INVALID_ARG, "\"gold\"", 0,
                 "is not defined");
    expect_error(WORLD("Material \"velvet\"\n" TRI), CST_ERR_INVALID_ARG, "Material", 0,
                 "unknown material type \"velvet\"");
    expect_error(WORLD("Shape \"teapot\"\n"), CST_ERR_INVALID_ARG, "\"teapot\"", 0, "unknown shape");
    expect_error(WORLD("AttributeEnd\n" TRI), CST_ERR_INVALID_ARG, "AttributeEnd", 0,
                 "without a matching AttributeBegin");
    expect_error(WORLD("TransformBegin\nAttributeEnd\n" TRI), CST_ERR_INVALID_ARG, "AttributeEnd", 0,
                 "closes the TransformBegin at line 4");
    expect_error(WORLD("Camera \"perspective\"\n"), CST_ERR_INVALID_ARG, "Camera", 1,
                 "after WorldBegin");
    expect_error(TRI, CST_ERR_INVALID_ARG, "Shape", 0, "before WorldBegin");
    expect_error(WORLD("WorldBegin\n"), CST_ERR_INVALID_ARG, "WorldBegin", 1, "second time");
    expect_error("Camera \"realistic\"\nWorldBegin\n" TRI, CST_ERR_UNSUPPORTED, "\"realistic\"",
                 0, "not supported");
    expect_error(WORLD("ObjectInstance \"tree\"\n"), CST_ERR_INVALID_ARG, "\"tree\"", 0, "not defined");
    expect_error(WORLD("ObjectEnd\n"), CST_ERR_INVALID_ARG, "ObjectEnd", 0, "without ObjectBegin");
    expect_error(WORLD("CoordSysTransform \"lamp\"\n"), CST_ERR_INVALID_ARG, "\"lamp\"", 0, "not defined");
    expect_error(WORLD("Texture \"t\" \"spectrum\" \"constant\" \"rgb value\" [.5 .5 .5]\n"
                       "Material \"diffuse\" \"texture reflectance\" \"u\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"texture reflectance\"", 0, "texture \"u\" is not defined");
    expect_error(WORLD("Shape \"plymesh\" \"string filename\" \"none.ply\"\n"), CST_ERR_UNSUPPORTED,
                 "\"string filename\"", 0, "file access is disabled");
    expect_error(WORLD("Include \"other.pbrt\"\n"), CST_ERR_UNSUPPORTED, "\"other.pbrt\"", 0,
                 "file access is disabled");
    expect_error("LookAt 0 0 0  0 0 0  0 1 0\n", CST_ERR_INVALID_ARG, "LookAt", 0, "eye equals look");
    expect_error(WORLD("Rotate 30 0 0 0\n"), CST_ERR_INVALID_ARG, "Rotate", 0, "nonzero");
    expect_error(WORLD("Transform [1 0 0 1 0 1 0 0 0 0 1 0 0 0 0 1]\n"), CST_ERR_INVALID_ARG,
                 "Transform", 0, "affine");
    expect_error("Film \"rgb\" \"integer xresolution\" 0\n", CST_ERR_INVALID_ARG, "Film", 0,
                 "resolution 0 x 720");
    expect_error(WORLD("Material \"dielectric\" \"float eta\" -1\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float eta\"", 0, "not positive");
    /* no shapes: located at the end of the file */
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    assert_int_equal(load_w(WORLD("Shape \"cylinder\"\n"), &s, &err, &w), CST_ERR_INVALID_ARG);
    if (strncmp(err.msg, "t.pbrt:5:1: the scene has no shapes", 35) != 0) fail_msg("%s", err.msg);
}

/* Errors without file access disabled: a missing PLY (I/O, located at its file name)
 * and a missing Include. */
static void test_missing_files(void **state)
{
    (void)state;
    const char *text = WORLD("Shape \"plymesh\" \"string filename\" \"no-such-mesh.ply\"\n");
    CstScene *s = NULL;
    CstError err;
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", NULL, &s, &err);
    assert_int_equal(st, CST_ERR_IO);
    assert_null(s);
    if (!strstr(err.msg, "/t.pbrt:4:17: Shape \"plymesh\": ") || !strstr(err.msg, "no-such-mesh.ply"))
        fail_msg("%s", err.msg);
    text = WORLD("Include \"no-such-file.pbrt\"\n");
    st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", NULL, &s, &err);
    assert_int_equal(st, CST_ERR_IO);
    if (!strstr(err.msg, "/t.pbrt:4:9: Include: ") || !strstr(err.msg, "cannot open"))
        fail_msg("%s", err.msg);
}

/* ------------------------------------------------------------------ directives */

static void test_transforms(void **state)
{
    (void)state;
    Scene *s = expect_ok(WORLD(
        "AttributeBegin\n Translate 10 0 0\n" TRI "AttributeEnd\n"              /* tri 0 */
        "AttributeBegin\n Scale 2 3 4\n" TRI "AttributeEnd\n"                   /* tri 1 */
        "AttributeBegin\n Rotate 90 0 0 1\n" TRI "AttributeEnd\n"               /* tri 2 */
        "AttributeBegin\n ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 0  5 6 7 1]\n" TRI
        "AttributeEnd\n"                                                        /* tri 3 */
        "AttributeBegin\n Translate 1 0 0\n Transform [1 0 0 0  0 1 0 0  0 0 1 0  0 0 9 1]\n" TRI
        "AttributeEnd\n"                                                        /* tri 4 */
        "TransformBegin\n Translate 0 0 3\n CoordinateSystem \"lamp\"\nTransformEnd\n"
        "AttributeBegin\n CoordSysTransform \"lamp\"\n Translate 0 1 0\n" TRI "AttributeEnd\n" /* 5 */
        "AttributeBegin\n Translate 1 1 1\n Identity\n" TRI "AttributeEnd\n"    /* tri 6 */
        TRI                                                                     /* tri 7 */
        "AttributeBegin\n Translate 4 0 0\n ActiveTransform EndTime\n Translate 100 0 0\n"
        " ActiveTransform All\n" TRI "AttributeEnd\n"), NULL);                  /* tri 8 */
    assert_int_equal(s->num_triangles, 9);
    assert_vec(tri_vertex(s, 0, 1), 11, 0, 0, 0);
    assert_vec(tri_vertex(s, 1, 1), 2, 0, 0, 0);
    assert_vec(tri_vertex(s, 1, 2), 0, 3, 0, 0);
    assert_vec(tri_vertex(s, 2, 1), 0, 1, 0, 1e-6f); /* x -> y: counter-clockwise about z */
    assert_vec(tri_vertex(s, 3, 0), 5, 6, 7, 0);
    assert_vec(tri_vertex(s, 4, 0), 0, 0, 9, 0);
    assert_vec(tri_vertex(s, 5, 0), 0, 1, 3, 0);
    assert_vec(tri_vertex(s, 6, 0), 0, 0, 0, 0);
    assert_vec(tri_vertex(s, 7, 1), 1, 0, 0, 0);
    assert_vec(tri_vertex(s, 8, 0), 4, 0, 0, 0);
    cst_scene_destroy(s);
}

/* A mirroring transform keeps the outside: the winding is swapped so the geometric normal
 * (v1-v0) x (v2-v0) still points where the object-space one did; ReverseOrientation
 * flips it (pbrt's rule), and both together cancel. */
static void test_orientation(void **state)
{
    (void)state;
    Scene *s = expect_ok(WORLD(TRI
                               "AttributeBegin\n Scale -1 1 1\n" TRI "AttributeEnd\n"
                               "AttributeBegin\n ReverseOrientation\n" TRI "AttributeEnd\n"
                               "AttributeBegin\n ReverseOrientation\n Scale 1 1 -1\n" TRI "AttributeEnd\n"
                               "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] "
                               "\"integer indices\" [0 1 2] \"normal N\" [0 0 -1 0 0 -1 0 0 -1]\n"),
                         NULL);
    assert_int_equal(s->num_triangles, 5);
    const float want[5] = {1, 1, -1, 1, -1};
    for (int t = 0; t < 5; t++) {
        Vec3 n = s->tri_normals[t];
        if (fabsf(n.z - want[t]) > 1e-6f) fail_msg("triangle %d: normal z %g, expected %g", t, (double)n.z, (double)want[t]);
    }
    cst_scene_destroy(s);
}

static void test_attributes_scope(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("Material \"diffuse\" \"rgb reflectance\" [.2 .2 .2]\n"
                               "AttributeBegin\n Material \"diffuse\" \"rgb reflectance\" [.7 .7 .7]\n"
                               " AreaLightSource \"diffuse\" \"rgb L\" [1 2 3]\n" TRI "AttributeEnd\n" TRI
                               "AttributeBegin\n"),
                         &w);
    assert_int_equal(s->num_triangles, 2);
    assert_true(s->materials[s->tri_info[0].material].albedo.c[0] == 0.7f);
    assert_true(s->materials[s->tri_info[1].material].albedo.c[0] == 0.2f);
    assert_int_equal(s->tri_info[0].emitter, 0);
    assert_int_equal(s->tri_info[1].emitter, -1);
    assert_true(find_warning(&w, CST_WARN_GEOMETRY, "t.pbrt:11:1: AttributeBegin is never closed") >= 0);
    cst_scene_destroy(s);
}

static void test_include(void **state)
{
    (void)state;
    const char *dir = CST_BINARY_DIR "/pbrt_include";
    mkdir(dir, 0755);
    FILE *f = fopen(CST_BINARY_DIR "/pbrt_include/geometry.pbrt", "w");
    assert_non_null(f);
    fputs("# included\nTranslate 0 0 1\n" TRI "Shape \"sphere\" \"float radiu\" 1\n", f);
    fclose(f);
    f = fopen(CST_BINARY_DIR "/pbrt_include/bad.pbrt", "w");
    assert_non_null(f);
    fputs("\n  Shape \"sphere\" \"float radius\" [1\n", f);
    fclose(f);
    const char *text = WORLD("Include \"geometry.pbrt\"\nImport \"geometry.pbrt\"\n");
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    CstLoadOptions opt = {collect, &w, 0};
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/pbrt_include/main.pbrt",
                                              &opt, &s, &err);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->num_spheres, 2);
    assert_vec(tri_vertex(s, 1, 0), 0, 0, 2, 0); /* the CTM carries across includes */
    /* warnings name the included file and its line */
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "geometry.pbrt:4:16: Shape \"sphere\": "
                                                           "parameter \"float radiu\"") >= 0);
    cst_scene_destroy(s);
    text = WORLD("Include \"bad.pbrt\"\n");
    st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/pbrt_include/main.pbrt",
                                    NULL, &s, &err);
    assert_int_equal(st, CST_ERR_PARSE);
    if (!strstr(err.msg, "pbrt_include/bad.pbrt:3:1: ")) fail_msg("%s", err.msg);
}

/* ------------------------------------------------------------------ parameter types and colour */

static void test_parameter_types(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "Texture \"chk\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n"
        "Texture \"half\" \"float\" \"constant\" \"float value\" 0.5\n"
        "Texture \"sc\" \"spectrum\" \"scale\" \"texture tex\" \"chk\" \"texture scale\" \"half\"\n"
        "Material \"diffuse\" \"texture reflectance\" \"sc\"\n" TRI                       /* 0 */
        "Material \"diffuse\" \"spectrum reflectance\" [300 0.25 900 0.25]\n" TRI         /* 1 */
        "Material \"diffuse\" \"xyz reflectance\" [0.2 0.2 0.2]\n" TRI                    /* 2 */
        "Material \"matte\" \"color Kd\" [0.1 0.2 0.3]\n" TRI                            /* 3: v3 spelling */
        "AttributeBegin\nAreaLightSource \"diffuse\" \"blackbody L\" [6500] \"bool twosided\" true\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"point2 uv\" [0 0 1 0 0 1] "
        "\"normal N\" [0 0 1 0 0 1 0 0 1] \"string emission\" \"x\"\nAttributeEnd\n"),    /* 4 */
        &w);
    Color a = s->materials[s->tri_info[0].material].albedo;
    assert_true(fabsf(a.c[0] - 0.25f) < 1e-6f && a.c[1] == 0.0f && fabsf(a.c[2] - 0.25f) < 1e-6f);
    assert_int_equal(s->textures[s->materials[s->tri_info[0].material].albedo_texture - 1].type,
                     TEXTURE_CHECKERBOARD);
    Color b = s->materials[s->tri_info[1].material].albedo;
    assert_true(fabsf(b.c[0] - 0.25f) < 1e-5f && fabsf(b.c[1] - 0.25f) < 1e-5f && fabsf(b.c[2] - 0.25f) < 1e-5f);
    Color c = s->materials[s->tri_info[2].material].albedo;
    assert_true(c.c[0] > 0.0f && c.c[1] > 0.0f && c.c[2] > 0.0f);
    assert_true(s->materials[s->tri_info[3].material].albedo.c[2] == 0.3f);
    const Emitter *e = &s->emitters[s->tri_info[4].emitter];
    assert_true(e->two_sided);
    assert_true(fabsf(color_luminance(e->radiance) - 1.0f) < 0.03f); /* normalised to 1 nit */
    assert_true(e->radiance.c[0] > e->radiance.c[2] * 0.8f && e->radiance.c[2] > e->radiance.c[0] * 0.8f);
    assert_non_null(s->uvs);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"string emission\"") >= 0);
    cst_scene_destroy(s);
}

static void test_colour_conversions(void **state)
{
    (void)state;
    Color warm = pbrt_blackbody_rgb(2700.0), cool = pbrt_blackbody_rgb(10000.0);
    assert_true(warm.c[0] > warm.c[1] && warm.c[1] > warm.c[2]);
    assert_true(cool.c[2] > cool.c[0]);
    assert_true(fabsf(color_luminance(warm) - 1.0f) < 0.03f);
    double flat[] = {300, 0.6, 900, 0.6};
    Color f = pbrt_spectrum_rgb(flat, 2, false);
    assert_true(fabsf(f.c[0] - 0.6f) < 1e-5f && fabsf(f.c[1] - 0.6f) < 1e-5f && fabsf(f.c[2] - 0.6f) < 1e-5f);
    double red[] = {380, 0, 590, 0, 600, 1, 780, 1};
    Color r = pbrt_spectrum_rgb(red, 4, false);
    assert_true(r.c[0] > 0.5f && r.c[2] < 0.05f);
    Color eta, k;
    assert_true(pbrt_named_metal("metal-Au-eta", &eta));
    assert_true(pbrt_named_metal("metal-Au-k", &k));
    assert_false(pbrt_named_metal("metal-Xx-k", &k));
    assert_false(pbrt_named_metal("metal-Au-kk", &k));
    Color r0 = pbrt_conductor_r0(eta, k);
    assert_true(r0.c[0] > 0.9f && r0.c[1] > 0.7f && r0.c[1] < 0.85f && r0.c[2] < 0.45f); /* gold */
    Color peta, pk;
    assert_true(material_metal("gold", &peta, &pk)); /* the named spectrum is caustic's preset */
    assert_memory_equal(&eta, &peta, sizeof eta);
    assert_memory_equal(&k, &pk, sizeof k);
}

/* ------------------------------------------------------------------ materials */

static void test_materials(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"spectrum k\" \"metal-Au-k\"\n" TRI /* 0 */
        "Material \"conductor\" \"float roughness\" 0.0625\n" TRI                             /* 1 */
        "Material \"conductor\" \"float roughness\" 0.25 \"bool remaproughness\" false "
        "\"rgb reflectance\" [.9 .6 .3]\n" TRI                                                 /* 2 */
        "Material \"dielectric\" \"float eta\" 1.33\n" TRI                                     /* 3 */
        "Material \"dielectric\" \"spectrum eta\" \"glass-BK7\"\n" TRI                          /* 4 */
        "Material \"coateddiffuse\" \"rgb reflectance\" [.3 .4 .5] \"float roughness\" 0.0625 "
        "\"float eta\" 1.4\n" TRI                                                              /* 5 */
        "MakeNamedMaterial \"a\" \"string type\" \"diffuse\" \"rgb reflectance\" [.2 .2 .2]\n"
        "MakeNamedMaterial \"b\" \"string type\" \"diffuse\" \"rgb reflectance\" [.6 .6 .6]\n"
        "MakeNamedMaterial \"m\" \"string type\" \"mix\" \"string materials\" [\"a\" \"b\"] \"float amount\" 0.25\n"
        "NamedMaterial \"m\"\n" TRI                                                            /* 6 */
        "MakeNamedMaterial \"g\" \"string type\" \"dielectric\"\n"
        "MakeNamedMaterial \"m2\" \"string type\" \"mix\" \"string materials\" [\"a\" \"g\"] \"float amount\" 0.75\n"
        "NamedMaterial \"m2\"\n" TRI                                                           /* 7 */
        "Material \"interface\"\n" TRI                                                         /* 8 */
        "Material \"thindielectric\"\n" TRI                                                    /* 9 */
        "Material \"hair\"\n" TRI                                                              /* 10 */
        "Material \"diffuse\" \"rgb reflectance\" [2 0.5 -1]\n" TRI                            /* 11 */
        "Material \"matte\" \"rgb Kd\" [.1 .1 .1]\n" TRI                                       /* 12: v3 */
        "Material \"dielectric\" \"float roughness\" 0.01\n" TRI                               /* 13 */
        "Material \"conductor\" \"float uroughness\" 0.25 \"float vroughness\" 0.0625 "
        "\"bool remaproughness\" false\n" TRI                                                  /* 14 */
        "Material \"coatedconductor\" \"spectrum conductor.eta\" \"metal-Ag-eta\" \"spectrum conductor.k\" "
        "\"metal-Ag-k\" \"float conductor.roughness\" 0.0625 \"float interface.roughness\" 0.2 "
        "\"float thickness\" 0.1\n" TRI                                                        /* 15 */
        "Material \"conductor\" \"spectrum eta\" \"metal-CuZn-eta\" \"spectrum k\" \"metal-CuZn-k\"\n" TRI /* 16 */
        "Material \"coateddiffuse\"\n" TRI                                                     /* 17 */
        "Material \"conductor\" \"float roughness\" 4 \"bool remaproughness\" false\n" TRI     /* 18 */
        "MakeNamedMaterial \"c1\" \"string type\" \"conductor\"\n"
        "MakeNamedMaterial \"c2\" \"string type\" \"conductor\" \"rgb reflectance\" [.5 .5 .5]\n"
        "MakeNamedMaterial \"m3\" \"string type\" \"mix\" \"string materials\" [\"c1\" \"c2\"] \"float amount\" 0.3\n"
        "NamedMaterial \"m3\"\n" TRI),                                                         /* 19 */
        &w);
    enum { N = 20 };
    const Material *m[N];
    for (int i = 0; i < N; i++) m[i] = &s->materials[s->tri_info[i].material];
    Color eta, k;
    /* named spectra of the four preset metals are caustic's presets, exactly */
    assert_int_equal(m[0]->type, MATERIAL_CONDUCTOR);
    assert_true(material_metal("gold", &eta, &k));
    assert_memory_equal(&m[0]->eta, &eta, sizeof eta);
    assert_memory_equal(&m[0]->k, &k, sizeof k);
    assert_true(m[0]->roughness == 0.0f);
    /* remapped roughness 0.0625: pbrt alpha = sqrt(0.0625) = 0.25, ours r = sqrt(alpha) = 0.5 */
    assert_int_equal(m[1]->type, MATERIAL_CONDUCTOR);
    assert_true(m[1]->roughness == 0.5f);
    assert_true(material_metal("copper", &eta, &k)); /* pbrt's default conductor */
    assert_memory_equal(&m[1]->eta, &eta, sizeof eta);
    assert_memory_equal(&m[1]->k, &k, sizeof k);
    /* reflectance: eta 1, k = 2 sqrt(R) / sqrt(1 - R), whose R0 is R; alpha = 0.25 unremapped */
    assert_int_equal(m[2]->type, MATERIAL_CONDUCTOR);
    assert_true(m[2]->roughness == 0.5f);
    assert_true(m[2]->eta.c[0] == 1.0f && m[2]->eta.c[1] == 1.0f && m[2]->eta.c[2] == 1.0f);
    assert_true(m[2]->k.c[0] == 2.0f * sqrtf(0.9f) / sqrtf(1.0f - 0.9f));
    Color r0 = pbrt_conductor_r0(m[2]->eta, m[2]->k);
    assert_true(fabsf(r0.c[0] - 0.9f) < 1e-6f && fabsf(r0.c[1] - 0.6f) < 1e-6f && fabsf(r0.c[2] - 0.3f) < 1e-6f);
    assert_int_equal(m[3]->type, MATERIAL_GLASS);
    assert_true(m[3]->ior == 1.33f);
    assert_true(m[4]->ior == 1.5168f);
    /* coateddiffuse -> plastic: reflectance, eta, roughness (remapped as above) */
    assert_int_equal(m[5]->type, MATERIAL_PLASTIC);
    assert_true(m[5]->albedo.c[0] == 0.3f && m[5]->albedo.c[1] == 0.4f && m[5]->albedo.c[2] == 0.5f);
    assert_true(m[5]->ior == 1.4f && m[5]->roughness == 0.5f);
    assert_true(m[5]->prepared); /* scene_add_material prepared the rough coat's table */
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "material \"coateddiffuse\" approximated by caustic's plastic") >= 0);
    assert_true(fabsf(m[6]->albedo.c[0] - 0.3f) < 1e-6f); /* exact blend of two diffuse */
    assert_int_equal(m[7]->type, MATERIAL_GLASS);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "larger weight, \"g\"") >= 0);
    assert_true(m[8]->type == MATERIAL_GLASS && m[8]->ior == 1.0f);
    assert_int_equal(m[9]->type, MATERIAL_GLASS);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "material \"hair\" is not supported") >= 0);
    assert_true(m[11]->albedo.c[0] == 1.0f && m[11]->albedo.c[2] == 0.0f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "clamped") >= 0);
    assert_true(m[12]->albedo.c[1] == 0.1f);
    /* rough dielectric: alpha = sqrt(0.01) = 0.1, r = sqrt(0.1) */
    assert_int_equal(m[13]->type, MATERIAL_DIELECTRIC);
    assert_true(m[13]->roughness == sqrtf(sqrtf(0.01f)) && m[13]->ior == 1.5f);
    assert_true(m[13]->albedo.c[0] == 1.0f && m[13]->albedo.c[2] == 1.0f);
    /* anisotropic alphas 0.25 and 0.0625: geometric mean 0.125 */
    assert_true(m[14]->roughness == sqrtf(0.125f));
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "geometric mean, alpha 0.125") >= 0);
    /* coatedconductor: its conductor, the coat dropped; a non-default thickness reported */
    assert_int_equal(m[15]->type, MATERIAL_CONDUCTOR);
    assert_true(material_metal("silver", &eta, &k));
    assert_memory_equal(&m[15]->eta, &eta, sizeof eta);
    assert_true(m[15]->roughness == 0.5f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "material \"coatedconductor\" approximated as its conductor") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"thickness\" 0.1") >= 0);
    assert_int_equal(m[16]->type, MATERIAL_CONDUCTOR);
    assert_true(m[16]->eta.c[0] == 0.444f && m[16]->k.c[2] == 1.829f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "\"metal-CuZn-eta\" taken as the RGB") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "\"metal-Au-eta\"") < 0); /* a preset */
    assert_true(m[17]->type == MATERIAL_PLASTIC && m[17]->albedo.c[1] == 0.5f && m[17]->ior == 1.5f &&
                m[17]->roughness == 0.0f);
    assert_true(m[18]->roughness == 1.0f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "GGX alpha 4 is beyond") >= 0);
    /* two conductors are not blended: the larger weight, c1 */
    assert_true(m[19]->type == MATERIAL_CONDUCTOR && m[19]->eta.c[1] == m[1]->eta.c[1]);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "larger weight, \"c1\"") >= 0);
    /* pbrt's reflective materials reflect on both sides: caustic's two-sided default */
    for (int i = 0; i < N; i++) assert_false(m[i]->one_sided);
    for (int i = 0; i < 13; i++)
        if (i != 1 && i != 2 && i != 5) assert_true(m[i]->roughness == 0.0f);
    cst_scene_destroy(s);
    /* malformed variants, located */
    expect_error(WORLD("Material \"conductor\" \"spectrum eta\" \"metal-Au-eta\" \"rgb reflectance\" [.5 .5 .5]\n" TRI),
                 CST_ERR_INVALID_ARG, "\"rgb reflectance\"", 0, "either reflectance or eta and k");
    expect_error(WORLD("Material \"coateddiffuse\" \"float roughness\" -0.5\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float roughness\"", 0, "roughness -0.5 is negative");
    expect_error(WORLD("Material \"conductor\" \"float vroughness\" -1\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float vroughness\"", 0, "is negative");
    expect_error(WORLD("Material \"conductor\" \"float eta\" -2\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float eta\"", 0, "eta -2 is negative");
    expect_error(WORLD("Material \"coateddiffuse\" \"float eta\" 0\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float eta\"", 0, "not positive");
    expect_error(WORLD("Material \"conductor\" \"float roughness\" [0.1 0.2]\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float roughness\"", 0, NULL);
}

/* ------------------------------------------------------------------ lights */

static void test_lights(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "LightSource \"point\" \"rgb I\" [1 1 1]\n"
        "LightSource \"infinite\" \"rgb L\" [1 1 1]\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 2 3] \"float scale\" 2\n" TRI "AttributeEnd\n"
        /* power 10 W over a triangle of area 0.5, one-sided: L = 10 / (pi 0.5) */
        "AttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [1 1 1] \"float power\" 10\n" TRI "AttributeEnd\n"
        "AttributeBegin\nAreaLightSource \"diffuse\" \"float power\" 10 \"bool twosided\" true\n"
        "Shape \"sphere\" \"float radius\" 2\nAttributeEnd\n"
        "AttributeBegin\nAreaLightSource \"goniometric\"\n" TRI "AttributeEnd\n"),
        &w);
    assert_non_null(s->env); /* the infinite light: a constant environment */
    assert_null(s->env->rgb);
    assert_true(s->env->scale.c[0] == 1.0f && s->env->scale.c[1] == 1.0f && s->env->scale.c[2] == 1.0f);
    assert_int_equal(s->num_delta_lights, 1);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "AreaLightSource \"goniometric\"") >= 0);
    assert_int_equal(s->num_emitters, 3);
    Color l0 = s->emitters[s->tri_info[0].emitter].radiance;
    assert_true(l0.c[0] == 2.0f && l0.c[1] == 4.0f && l0.c[2] == 6.0f);
    assert_false(s->emitters[s->tri_info[0].emitter].two_sided);
    Color l1 = s->emitters[s->tri_info[1].emitter].radiance;
    assert_true(fabsf(l1.c[0] - 10.0f / (3.14159265f * 0.5f)) < 1e-4f);
    Color l2 = s->emitters[s->sphere_info[0].emitter].radiance;
    assert_true(fabsf(l2.c[1] - 10.0f / (2.0f * 3.14159265f * 4.0f * 3.14159265f * 4.0f)) < 1e-5f);
    assert_int_equal(s->tri_info[2].emitter, -1);
    cst_scene_destroy(s);
}

/* The equal-area octahedral map of pbrt-v4's environment images: its landmarks, and
 * square -> sphere -> square is the identity. */
static void test_equal_area_map(void **state)
{
    (void)state;
    double uv[2], d[3];
    const double axes[4][3] = {{0, 0, 1}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}};
    const double want[4][2] = {{0.5, 0.5}, {1.0, 0.5}, {0.5, 1.0}, {0.0, 0.5}};
    for (int i = 0; i < 4; i++) {
        pbrt_equal_area_sphere_to_square(axes[i], uv);
        assert_true(fabs(uv[0] - want[i][0]) < 1e-12 && fabs(uv[1] - want[i][1]) < 1e-12);
    }
    const double down[3] = {0, 0, -1};
    pbrt_equal_area_sphere_to_square(down, uv); /* -z: a corner */
    assert_true((uv[0] == 0.0 || uv[0] == 1.0) && (uv[1] == 0.0 || uv[1] == 1.0));
    for (int i = 0; i < 17; i++)
        for (int j = 0; j < 17; j++) {
            double p[2] = {(i + 0.37) / 17.0, (j + 0.61) / 17.0}, q[2];
            pbrt_equal_area_square_to_sphere(p, d);
            assert_true(fabs(d[0] * d[0] + d[1] * d[1] + d[2] * d[2] - 1.0) < 1e-12);
            pbrt_equal_area_sphere_to_square(d, q);
            if (!(fabs(q[0] - p[0]) < 1e-9 && fabs(q[1] - p[1]) < 1e-9))
                fail_msg("(%g, %g) -> (%g, %g, %g) -> (%g, %g)", p[0], p[1], d[0], d[1], d[2], q[0], q[1]);
        }
}

/* An image whose pixels say on which side of the light-space axes their centre direction
 * lies: red x > 0, green y > 0, blue z > 0. Square: pbrt-v4's equal-area layout; else
 * pbrt-v3's equirectangular one (+z up, phi = atan2(y, x) from the left column). */
static void write_sides_image(const char *path, int w, int h)
{
    float *px = malloc(3u * (size_t)w * (size_t)h * sizeof *px);
    assert_non_null(px);
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double d[3], uv[2] = {(x + 0.5) / w, (y + 0.5) / h};
            if (w == h) {
                pbrt_equal_area_square_to_sphere(uv, d);
            } else {
                double th = 3.14159265358979 * uv[1], ph = 2.0 * 3.14159265358979 * uv[0];
                d[0] = sin(th) * cos(ph);
                d[1] = sin(th) * sin(ph);
                d[2] = cos(th);
            }
            float *p = &px[3 * ((size_t)y * (size_t)w + (size_t)x)];
            p[0] = d[0] > 0.0 ? 1.0f : 0.0f;
            p[1] = d[1] > 0.0 ? 1.0f : 0.0f;
            p[2] = d[2] > 0.0 ? 1.0f : 0.0f;
        }
    CstError err;
    if (image_write(path, px, w, h, &err) != CST_OK) fail_msg("%s", err.msg);
    free(px);
}

static Scene *load_file_scene(const char *text, Warnings *w)
{
    CstScene *s = NULL;
    CstError err;
    CstLoadOptions opt = {collect, w, 0};
    if (cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", &opt, &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    return s;
}

/* Checks the environment at the 8 directions (+-0.6, +-0.6, +-0.53): away from every axis
 * plane by at least 30 degrees, far more than a pixel. `map` gives, per light axis, the
 * world component (0 x, 1 y, 2 z) and its sign. */
static void check_sides(const EnvMap *env, const int map[3][2], float k)
{
    for (int i = 0; i < 8; i++) {
        Vec3 wv = v3_normalize(v3(i & 1 ? 0.6f : -0.6f, i & 2 ? 0.6f : -0.6f, i & 4 ? 0.53f : -0.53f));
        float c[3] = {wv.x, wv.y, wv.z};
        Color got = envmap_eval(env, wv);
        float want[3];
        for (int a = 0; a < 3; a++) want[a] = (float)map[a][1] * c[map[a][0]] > 0.0f ? k : 0.0f;
        if (got.c[0] != want[0] || got.c[1] != want[1] || got.c[2] != want[2])
            fail_msg("direction (%g, %g, %g): (%g, %g, %g), expected (%g, %g, %g)", (double)wv.x,
                     (double)wv.y, (double)wv.z, (double)got.c[0], (double)got.c[1], (double)got.c[2],
                     (double)want[0], (double)want[1], (double)want[2]);
    }
}

/* LightSource "infinite": constant (L, scale, illuminance), images through the light's
 * transform, one environment only, malformed variants. */
static void test_infinite_lights(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("LightSource \"infinite\" \"rgb L\" [1 2 3] \"float scale\" 2\n"
                               "LightSource \"infinite\" \"rgb L\" [5 5 5]\n" TRI), &w);
    assert_non_null(s->env);
    assert_null(s->env->rgb);
    assert_true(s->env->scale.c[0] == 2.0f && s->env->scale.c[1] == 4.0f && s->env->scale.c[2] == 6.0f);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:5:1: LightSource \"infinite\": caustic has one environment") >= 0);
    cst_scene_destroy(s);
    /* illuminance E: a uniform sky of radiance L gives pi L on an upward patch, so L E / pi */
    s = expect_ok(WORLD("LightSource \"infinite\" \"float illuminance\" 10\n" TRI), NULL);
    assert_true(s->env->scale.c[1] == (float)(10.0 / 3.14159265358979323846));
    cst_scene_destroy(s);

    /* a square (equal-area) image under pbrt's usual "Rotate -90 1 0 0": light +z is world
     * +y, light +y is world -z */
    write_sides_image(CST_BINARY_DIR "/pbrt_env_sq.pfm", 64, 64);
    memset(&w, 0, sizeof w);
    s = load_file_scene(WORLD("AttributeBegin\nRotate -90 1 0 0\nLightSource \"infinite\" "
                              "\"string filename\" \"pbrt_env_sq.pfm\" \"float scale\" 2\nAttributeEnd\n" TRI), &w);
    assert_non_null(s->env->rgb);
    assert_int_equal(s->env->width, 128);
    assert_int_equal(s->env->height, 64);
    assert_int_equal(w.n, 0);
    static const int rot[3][2] = {{0, 1}, {2, -1}, {1, 1}};
    check_sides(s->env, rot, 2.0f);
    cst_scene_destroy(s);
    /* untransformed; "illuminance" 1 divides by pbrt-v4's measure of the map, sum of
     * L cos theta times 2 pi / N^2 over the upper pixels: half the illuminance, here
     * 0.5 pi (0.5 (0.2126 + 0.7152) + 0.0722) up to the pixels' discretisation */
    s = load_file_scene(WORLD("LightSource \"infinite\" \"string filename\" \"pbrt_env_sq.pfm\" "
                              "\"float illuminance\" 1\n" TRI), &w);
    const double half_e = 0.5 * 3.14159265358979 * (0.5 * (0.2126 + 0.7152) + 0.0722);
    float k = s->env->scale.c[0];
    if (!(fabs((double)k * half_e - 1.0) < 0.02)) fail_msg("illuminance scale %g, expected about %g", (double)k, 1.0 / half_e);
    static const int ident[3][2] = {{0, 1}, {1, 1}, {2, 1}};
    check_sides(s->env, ident, k);
    cst_scene_destroy(s);
    /* a non-square image: pbrt-v3's equirectangular layout, with a warning */
    write_sides_image(CST_BINARY_DIR "/pbrt_env_ll.pfm", 32, 16);
    memset(&w, 0, sizeof w);
    s = load_file_scene(WORLD("LightSource \"infinite\" \"string filename\" \"pbrt_env_ll.pfm\"\n" TRI), &w);
    assert_int_equal(s->env->width, 32);
    assert_int_equal(s->env->height, 16);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "is 32 x 16, not square") >= 0);
    check_sides(s->env, ident, 1.0f);
    cst_scene_destroy(s);

    expect_error(WORLD("LightSource \"infinite\" \"rgb L\" [1 1 1] \"string filename\" \"sky.exr\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"string filename\"", 0, "both \"L\" and \"filename\"");
    expect_error(WORLD("LightSource \"infinite\" \"string filename\" \"sky.exr\"\n" TRI),
                 CST_ERR_UNSUPPORTED, "\"string filename\"", 0, "file access is disabled");
    expect_error(WORLD("LightSource \"infinite\" \"float scale\" -1\n" TRI), CST_ERR_INVALID_ARG,
                 "LightSource", 0, "scale -1");
    expect_error(WORLD("LightSource \"infinite\" \"rgb L\" [1 1]\n" TRI), CST_ERR_INVALID_ARG,
                 "\"rgb L\"", 0, NULL);
}

/* ------------------------------------------------------------------ shapes */

/* point, spot and distant lights as delta lights, placed by the CTM, with pbrt's power and
 * illuminance normalisation. */
static void test_delta_lights(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "AttributeBegin\nTranslate 1 2 3\nLightSource \"point\" \"rgb I\" [1 2 3] \"float scale\" 2 "
        "\"point3 from\" [0 0 1]\nAttributeEnd\n"
        "LightSource \"point\" \"float power\" 100\n"
        "LightSource \"spot\" \"point3 from\" [0 5 0] \"point3 to\" [0 0 0] \"float coneangle\" 20 "
        "\"float conedelta\" 10 \"float power\" 50\n"
        "AttributeBegin\nRotate 90 0 0 1\nLightSource \"distant\" \"point3 from\" [0 0 0] \"point3 to\" [1 0 0] "
        "\"blackbody L\" 5500 \"float illuminance\" 3\nAttributeEnd\n"
        "LightSource \"goniometric\"\n" TRI), &w);
    assert_int_equal(s->num_delta_lights, 4);
    const DeltaLight *l = s->delta_lights;
    assert_int_equal(l[0].type, DELTA_POINT);
    assert_vec(l[0].p, 1, 2, 4, 0);
    assert_true(l[0].intensity.c[0] == 2.0f && l[0].intensity.c[2] == 6.0f);
    assert_true(fabsf(l[1].intensity.c[1] - 100.0f / (4.0f * 3.14159265f)) < 1e-4f);
    assert_int_equal(l[2].type, DELTA_SPOT);
    assert_vec(l[2].dir, 0, -1, 0, 1e-6f);
    assert_true(fabsf(l[2].cos_outer - cosf(20.0f * 3.14159265f / 180.0f)) < 1e-6f);
    assert_true(fabsf(l[2].cos_inner - cosf(10.0f * 3.14159265f / 180.0f)) < 1e-6f);
    float k_e = 2.0f * 3.14159265f * (1.0f - 0.5f * (l[2].cos_inner + l[2].cos_outer));
    assert_true(fabsf(l[2].intensity.c[0] - 50.0f / k_e) < 1e-3f * (50.0f / k_e));
    /* exactly pbrt-v4's k_e = 2 pi ((1 - cos_start) + (cos_start - cos_end) / 2), in double */
    const double pi = 3.14159265358979323846;
    double ci = (double)l[2].cos_inner, co = (double)l[2].cos_outer;
    assert_true(l[2].intensity.c[1] == (float)(50.0 / (2.0 * pi * ((1.0 - ci) + (ci - co) / 2.0))));
    assert_true(l[1].intensity.c[2] == (float)(100.0 / (4.0 * pi)));
    assert_int_equal(l[3].type, DELTA_DIRECTIONAL);
    assert_vec(l[3].dir, 0, 1, 0, 1e-6f); /* (1, 0, 0) turned 90 degrees about z */
    assert_true(fabsf(color_luminance(l[3].intensity) - 3.0f) < 0.01f);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "LightSource \"goniometric\" is not supported") >= 0);
    cst_scene_destroy(s);
    expect_error(WORLD("LightSource \"spot\" \"float coneangle\" 120\n" TRI), CST_ERR_INVALID_ARG,
                 "LightSource", 0, "coneangle 120");
}

static void test_shapes(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD(
        "AttributeBegin\nTranslate 1 2 3\nScale 2 2 2\nShape \"sphere\" \"float radius\" 0.5\nAttributeEnd\n"
        "AttributeBegin\nScale 1 1 3\nShape \"sphere\"\nAttributeEnd\n"
        "Shape \"sphere\" \"float zmax\" 0.5\n"
        "Shape \"disk\" \"float radius\" 2 \"float height\" 1\n"
        "Shape \"bilinearmesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0 1 1 0] \"integer indices\" [0 1 2 3]\n"
        "Shape \"loopsubdiv\" \"integer levels\" 2 \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
        "Shape \"cylinder\"\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  2 0 0  0 1 0] \"integer indices\" [0 1 2 0 1 3]\n"),
        &w);
    assert_int_equal(s->num_spheres, 2);
    assert_vec(s->spheres[0].center, 1, 2, 3, 0);
    assert_true(s->spheres[0].radius == 1.0f);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "non-uniform transform tessellated") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "partial sphere") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "Shape \"cylinder\" is not supported") >= 0);
    assert_true(find_warning(&w, CST_WARN_GEOMETRY, "1 of 2 triangles are degenerate") >= 0);
    /* the disk: 128 triangles at z = 1 facing +z, total area pi r^2 */
    int first_disk = 2 * 64 * 31;
    double area = 0.0;
    for (int t = first_disk; t < first_disk + 128; t++) {
        assert_true(s->tri_normals[t].z > 0.999f);
        assert_true(tri_vertex(s, t, 0).z == 1.0f);
        area += (double)triangle_area(tri_vertex(s, t, 0), tri_vertex(s, t, 1), tri_vertex(s, t, 2));
    }
    assert_true(fabs(area - 4.0 * 3.14159265358979) < 1e-4);
    /* the bilinear patch: two triangles facing +z */
    int bl = first_disk + 128;
    assert_true(s->tri_normals[bl].z > 0.999f && s->tri_normals[bl + 1].z > 0.999f);
    assert_int_equal(s->num_triangles, bl + 2 + 1 + 1);
    cst_scene_destroy(s);
}

static void test_plymesh(void **state)
{
    (void)state;
    FILE *f = fopen(CST_BINARY_DIR "/pbrt_quad.ply", "w");
    assert_non_null(f);
    fputs("ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n"
          "property float z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
          "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n", f);
    fclose(f);
    const char *text = WORLD("Translate 0 0 7\nShape \"plymesh\" \"string filename\" \"pbrt_quad.ply\"\n");
    CstScene *s = NULL;
    CstError err;
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", NULL, &s, &err);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_triangles, 2);
    assert_vec(tri_vertex(s, 1, 2), 0, 1, 7, 0);
    cst_scene_destroy(s);
}

/* Directives that only warn, and the v3 leftovers that are accepted silently. */
static void test_other_directives(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok("Option \"bool disablepixeljitter\" true\n"
                         "ColorSpace \"aces2065-1\"\n"
                         "TransformTimes 0 1\n"
                         "WorldBegin\n"
                         "MakeNamedMedium \"fog\" \"string type\" \"homogeneous\"\n"
                         "MediumInterface \"fog\" \"\"\n"
                         "MediumInterface \"fog\"\n"
                         "Attribute \"shape\" \"float radius\" 2\n"
                         "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"vector3 S\" [1 0 0 1 0 0 1 0 0] "
                         "\"vector2 dpdu\" [1 0]\n"
                         "WorldEnd\n", &w);
    assert_int_equal(s->num_triangles, 1);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:1:1: Option is not supported") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "t.pbrt:2:12: ColorSpace \"aces2065-1\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:3:1: TransformTimes") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:5:1: MakeNamedMedium \"fog\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:6:1: MediumInterface") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:7:1: MediumInterface") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:8:1: Attribute \"shape\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"vector3 S\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"vector2 dpdu\"") >= 0);
    cst_scene_destroy(s);
}

/* imagemap as an image texture; binary PLY through assimp. */
static void test_imagemap_and_binary_ply(void **state)
{
    (void)state;
    const float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(CST_BINARY_DIR "/pbrt_tex.pfm", px, 2, 2, &err), CST_OK);
    FILE *f = fopen(CST_BINARY_DIR "/pbrt_bin.ply", "wb");
    assert_non_null(f);
    fputs("ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
          "property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n", f);
    const float v[9] = {0, 0, 0, 2, 0, 0, 0, 3, 0};
    fwrite(v, sizeof v, 1, f);
    const unsigned char n3 = 3;
    const int32_t idx[3] = {0, 1, 2};
    fwrite(&n3, 1, 1, f);
    fwrite(idx, sizeof idx, 1, f);
    fclose(f);
    const char *text = WORLD("Texture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex.pfm\"\n"
                             "Material \"diffuse\" \"texture reflectance\" \"img\"\n"
                             "Shape \"plymesh\" \"string filename\" \"pbrt_bin.ply\"\n");
    CstScene *s = NULL;
    Warnings w = {0};
    CstLoadOptions opt = {collect, &w, 0};
    if (cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", &opt, &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    Color a = s->materials[s->tri_info[0].material].albedo;
    assert_true(fabsf(a.c[0] - 0.5f) < 1e-6f && fabsf(a.c[1] - 0.5f) < 1e-6f && fabsf(a.c[2] - 0.5f) < 1e-6f);
    assert_int_equal(s->textures[s->materials[s->tri_info[0].material].albedo_texture - 1].type, TEXTURE_IMAGE);
    assert_int_equal(w.n, 0);
    assert_int_equal(s->num_triangles, 1);
    assert_vec(tri_vertex(s, 0, 2), 0, 3, 0, 0);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ textures */

static const Material *tri_material(const Scene *s, int t) { return &s->materials[s->tri_info[t].material]; }

static const Texture *albedo_tex(const Scene *s, int t)
{
    int id = tri_material(s, t)->albedo_texture;
    if (!id) fail_msg("triangle %d's material has no albedo texture", t);
    return &s->textures[id - 1];
}

static void assert_rgb(Color c, float r, float g, float b, float tol)
{
    if (!(fabsf(c.c[0] - r) <= tol && fabsf(c.c[1] - g) <= tol && fabsf(c.c[2] - b) <= tol))
        fail_msg("(%g, %g, %g), expected (%g, %g, %g)", (double)c.c[0], (double)c.c[1], (double)c.c[2],
                 (double)r, (double)g, (double)b);
}

/* The warning with `code` containing `what` must exist and name file:line of `needle`. */
static void assert_warning_at(const Warnings *w, CstWarningCode code, const char *what, const char *text,
                              const char *needle, int nth)
{
    int i = find_warning(w, code, what);
    if (i < 0) fail_msg("no warning with \"%s\"", what);
    int line, col;
    pos_of(text, needle, nth, &line, &col);
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:", line);
    const char *at = strstr(w->msg[i], prefix); /* after the directory, for files on disk */
    if (!at || (at != w->msg[i] && at[-1] != '/') || strchr(w->msg[i], ' ') < at)
        fail_msg("\"%s\" does not start with \"%s\"", w->msg[i], prefix);
}

/* checkerboard, scale and constant textures as caustic textures; the classes caustic has
 * no counterpart for as their averages, with located warnings. */
static void test_texture_classes(void **state)
{
    (void)state;
    Warnings w = {0};
    const char *text = WORLD(
        "Texture \"c\" \"spectrum\" \"constant\" \"rgb value\" [.1 .2 .3]\n"
        "Texture \"k\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [1 0 0] \"texture tex2\" \"c\" "
        "\"float uscale\" 2 \"float vscale\" 3 \"float udelta\" 0.5 \"float vdelta\" -1\n"
        "Texture \"kk\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"k\" \"rgb tex2\" [0 1 0]\n"
        "Texture \"half\" \"float\" \"constant\" \"float value\" 0.5\n"
        "Texture \"s1\" \"spectrum\" \"scale\" \"rgb tex\" [.4 .6 .8] \"texture scale\" \"half\"\n"
        "Texture \"s2\" \"spectrum\" \"scale\" \"texture tex\" \"k\" \"float scale\" 0.5\n"
        "Texture \"fk\" \"float\" \"checkerboard\" \"float tex1\" 0.25 \"float tex2\" 1\n"
        "Texture \"s3\" \"spectrum\" \"scale\" \"rgb tex\" [1 .5 0] \"texture scale\" \"fk\"\n"
        "Texture \"k3\" \"spectrum\" \"checkerboard\" \"integer dimension\" 3 \"rgb tex1\" [1 1 1] \"rgb tex2\" [0 0 0]\n"
        "Texture \"m\" \"spectrum\" \"mix\" \"texture tex1\" \"k\" \"rgb tex2\" [1 1 1]\n"
        "Texture \"f\" \"spectrum\" \"fbm\"\n"
        "Material \"diffuse\" \"texture reflectance\" \"c\"\n" TRI   /* 0 */
        "Material \"diffuse\" \"texture reflectance\" \"k\"\n" TRI   /* 1 */
        "Material \"diffuse\" \"texture reflectance\" \"kk\"\n" TRI  /* 2 */
        "Material \"diffuse\" \"texture reflectance\" \"s1\"\n" TRI  /* 3 */
        "Material \"diffuse\" \"texture reflectance\" \"s2\"\n" TRI  /* 4 */
        "Material \"diffuse\" \"texture reflectance\" \"s3\"\n" TRI  /* 5 */
        "Material \"diffuse\" \"texture reflectance\" \"k3\"\n" TRI  /* 6 */
        "Material \"diffuse\" \"texture reflectance\" \"m\"\n" TRI   /* 7 */
        "Material \"diffuse\" \"texture reflectance\" \"f\"\n" TRI); /* 8 */
    Scene *s = expect_ok(text, &w);
    /* a constant texture is a constant albedo */
    assert_int_equal(tri_material(s, 0)->albedo_texture, 0);
    assert_rgb(tri_material(s, 0)->albedo, 0.1f, 0.2f, 0.3f, 0.0f);
    /* checkerboard: tex1 on even squares of the mapped (s, t) = (2u + 0.5, 3v - 1) */
    const Texture *k = albedo_tex(s, 1);
    assert_int_equal(k->type, TEXTURE_CHECKERBOARD);
    assert_true(k->checker.scale == 1.0f);
    assert_true(k->uv_scale.x == 2.0f && k->uv_scale.y == 3.0f && k->uv_offset.x == 0.5f && k->uv_offset.y == -1.0f);
    assert_rgb(s->textures[k->checker.even].value, 1, 0, 0, 0);
    assert_rgb(s->textures[k->checker.odd].value, 0.1f, 0.2f, 0.3f, 0);
    int kid = tri_material(s, 1)->albedo_texture - 1;
    assert_rgb(texture_eval(s->textures, kid, v2(0.1f, 0.4f)), 1, 0, 0, 0);          /* (0.7, 0.2) */
    assert_rgb(texture_eval(s->textures, kid, v2(0.3f, 0.4f)), 0.1f, 0.2f, 0.3f, 0); /* (1.1, 0.2) */
    assert_rgb(texture_eval(s->textures, kid, v2(0.1f, 0.1f)), 0.1f, 0.2f, 0.3f, 0); /* (0.7, -0.7) */
    /* a checkerboard of a checkerboard: the inner one keeps its own mapping */
    const Texture *kk = albedo_tex(s, 2);
    assert_int_equal(kk->checker.even, kid);
    assert_true(kk->uv_scale.x == 1.0f && kk->uv_offset.x == 0.0f);
    int kkid = tri_material(s, 2)->albedo_texture - 1;
    assert_rgb(texture_eval(s->textures, kkid, v2(0.3f, 0.4f)), 0.1f, 0.2f, 0.3f, 0);
    assert_rgb(texture_eval(s->textures, kkid, v2(1.3f, 0.4f)), 0, 1, 0, 0);
    /* scale: two constants multiply; a constant factor is folded into a texture's values */
    assert_int_equal(tri_material(s, 3)->albedo_texture, 0);
    assert_rgb(tri_material(s, 3)->albedo, 0.2f, 0.3f, 0.4f, 1e-6f);
    const Texture *s2 = albedo_tex(s, 4);
    assert_int_equal(s2->type, TEXTURE_CHECKERBOARD);
    assert_true(s2->uv_scale.x == 2.0f && s2->uv_offset.y == -1.0f);
    assert_rgb(s->textures[s2->checker.even].value, 0.5f, 0, 0, 0);
    assert_rgb(s->textures[s2->checker.odd].value, 0.05f, 0.1f, 0.15f, 1e-7f);
    const Texture *s3 = albedo_tex(s, 5);
    assert_int_equal(s3->type, TEXTURE_CHECKERBOARD);
    assert_rgb(s->textures[s3->checker.even].value, 0.25f, 0.125f, 0, 0);
    assert_rgb(s->textures[s3->checker.odd].value, 1, 0.5f, 0, 0);
    /* 3D checkerboards, mix and fbm: their averages, with warnings at their lines */
    assert_int_equal(tri_material(s, 6)->albedo_texture, 0);
    assert_rgb(tri_material(s, 6)->albedo, 0.5f, 0.5f, 0.5f, 0);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "3D (solid) checkerboard", text, "Texture \"k3\"", 0);
    assert_int_equal(tri_material(s, 7)->albedo_texture, 0);
    assert_rgb(tri_material(s, 7)->albedo, 0.775f, 0.55f, 0.575f, 1e-6f);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "texture \"k\" is taken as its average", text, "\"texture tex1\" \"k\"", 1);
    assert_warning_at(&w, CST_WARN_UNSUPPORTED, "texture class not supported", text, "Texture \"f\"", 0);
    assert_int_equal(tri_material(s, 8)->albedo_texture, 0);
    cst_scene_destroy(s);
    expect_error(WORLD("Texture \"k\" \"spectrum\" \"checkerboard\" \"texture tex1\" \"nope\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"texture tex1\"", 0, "spectrum texture \"nope\" is not defined");
    expect_error(WORLD("Texture \"k\" \"spectrum\" \"checkerboard\" \"integer dimension\" 4\n" TRI),
                 CST_ERR_INVALID_ARG, "\"integer dimension\"", 0, "expected 2 or 3");
}

/* Textures in material parameters: reflectances, roughness (caustic's perceptual
 * roughness texel by texel), what caustic cannot texture, and float / spectrum mix-ups. */
static void test_texture_materials(void **state)
{
    (void)state;
    Warnings w = {0};
    const char *text = WORLD(
        "Texture \"k\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [1 0 0] \"rgb tex2\" [0 0 1]\n"
        "Texture \"hot\" \"spectrum\" \"checkerboard\" \"rgb tex1\" [2 0.5 0] \"rgb tex2\" [0 0 1]\n"
        "Texture \"r\" \"float\" \"checkerboard\" \"float tex1\" 0.0625 \"float tex2\" 0.25\n"
        "Material \"conductor\" \"texture roughness\" \"r\"\n" TRI                            /* 0 */
        "Material \"conductor\" \"texture roughness\" \"r\" \"bool remaproughness\" false\n" TRI /* 1 */
        "Material \"dielectric\" \"texture roughness\" \"r\"\n" TRI                           /* 2 */
        "Material \"coateddiffuse\" \"texture reflectance\" \"k\" \"texture roughness\" \"r\"\n" TRI /* 3 */
        "Material \"diffuse\" \"texture reflectance\" \"hot\"\n" TRI                          /* 4 */
        "Material \"conductor\" \"texture uroughness\" \"r\" \"float vroughness\" 0.0625\n" TRI /* 5 */
        "Material \"diffusetransmission\" \"texture reflectance\" \"k\"\n" TRI                /* 6 */
        "Material \"coatedconductor\" \"texture conductor.roughness\" \"r\"\n" TRI            /* 7 */
        "Material \"diffuse\" \"texture reflectance\" \"hot\"\n" TRI);                         /* 8 */
    Scene *s = expect_ok(text, &w);
    const Material *m = tri_material(s, 0);
    assert_int_equal(m->type, MATERIAL_CONDUCTOR);
    assert_int_not_equal(m->roughness_texture, 0);
    const Texture *t = &s->textures[m->roughness_texture - 1];
    assert_int_equal(t->type, TEXTURE_CHECKERBOARD);
    /* remapped: alpha = sqrt(r), caustic's roughness sqrt(alpha) = r^(1/4) */
    assert_rgb(s->textures[t->checker.even].value, 0.5f, 0.5f, 0.5f, 1e-6f);
    assert_rgb(s->textures[t->checker.odd].value, 0.70710678f, 0.70710678f, 0.70710678f, 1e-6f);
    t = &s->textures[tri_material(s, 1)->roughness_texture - 1];
    assert_rgb(s->textures[t->checker.even].value, 0.25f, 0.25f, 0.25f, 1e-6f);
    m = tri_material(s, 2);
    assert_int_equal(m->type, MATERIAL_DIELECTRIC);
    assert_int_not_equal(m->roughness_texture, 0);
    m = tri_material(s, 3);
    assert_int_equal(m->type, MATERIAL_PLASTIC);
    assert_int_equal(m->roughness_texture, 0);
    assert_true(fabsf(m->roughness - powf(0.15625f, 0.25f)) < 1e-6f); /* the average's */
    assert_int_equal(albedo_tex(s, 3)->type, TEXTURE_CHECKERBOARD);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "\"texture roughness\" cannot be textured", text,
                      "Material \"coateddiffuse\"", 0);
    /* pbrt clamps reflectances to 1 */
    const Texture *hot = albedo_tex(s, 4);
    assert_rgb(s->textures[hot->checker.even].value, 1, 0.5f, 0, 0);
    assert_rgb(hot->max, 1, 0.5f, 1, 0);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "values up to 2", text, "\"texture reflectance\" \"hot\"", 0);
    /* anisotropic: averages */
    assert_int_equal(tri_material(s, 5)->roughness_texture, 0);
    assert_int_equal(albedo_tex(s, 6)->type, TEXTURE_CHECKERBOARD);
    /* coatedconductor's conductor roughness */
    assert_int_not_equal(tri_material(s, 7)->roughness_texture, 0);
    /* derived textures are made once per texture and shared */
    assert_int_equal(tri_material(s, 7)->roughness_texture, tri_material(s, 0)->roughness_texture);
    assert_int_equal(tri_material(s, 8)->albedo_texture, tri_material(s, 4)->albedo_texture);
    cst_scene_destroy(s);
    /* pbrt-v4 looks float and spectrum textures up apart and stops at a missing one */
    expect_error(WORLD("Texture \"r\" \"float\" \"constant\" \"float value\" 0.5\n"
                       "Material \"diffuse\" \"texture reflectance\" \"r\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"texture reflectance\"", 0, "texture \"r\" is a float texture; expected a spectrum");
    expect_error(WORLD("Texture \"k\" \"spectrum\" \"constant\" \"rgb value\" [.5 .5 .5]\n"
                       "Material \"conductor\" \"texture roughness\" \"k\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"texture roughness\"", 0, "texture \"k\" is a spectrum texture; expected a float");
    expect_error(WORLD("Material \"conductor\" \"texture roughness\" \"none\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"texture roughness\"", 0, "float texture \"none\" is not defined");
    expect_error(WORLD("Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\"\n" TRI),
                 CST_ERR_UNSUPPORTED, "\"string filename\"", 0, "file access is disabled");
    expect_error(WORLD("Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"string wrap\" \"mirror\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"string wrap\"", 0, "wrap \"mirror\" is not known");
    expect_error(WORLD("Texture \"i\" \"spectrum\" \"imagemap\" \"string filename\" \"a.png\" \"string encoding\" \"gamma x\"\n" TRI),
                 CST_ERR_INVALID_ARG, "\"string encoding\"", 0, "expected \"gamma\" and a number > 0");
    expect_error(WORLD("Texture \"i\" \"spectrum\" \"imagemap\" \"string encoding\" \"linear\"\n" TRI),
                 CST_ERR_INVALID_ARG, "Texture", 0, "missing \"string filename\"");
}

/* imagemap: the file (missing: an I/O error at its name), scale, invert, float textures
 * (the first channel), wrap, filter, encodings and the uv mapping. */
static void test_imagemap_params(void **state)
{
    (void)state;
    /* row 0 is the top: red, green / blue, white */
    const float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(CST_BINARY_DIR "/pbrt_tex4.pfm", px, 2, 2, &err), CST_OK);
    const float grey[12] = {0.2f, 0.2f, 0.2f, 0.4f, 0.4f, 0.4f, 0.6f, 0.6f, 0.6f, 0.8f, 0.8f, 0.8f};
    assert_int_equal(image_write(CST_BINARY_DIR "/pbrt_tex4.png", grey, 2, 2, &err), CST_OK);
    Warnings w = {0};
    const char *text = WORLD(
        "Texture \"a\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex4.pfm\" \"float scale\" 0.5 "
        "\"bool invert\" true \"string wrap\" \"black\" \"string filter\" \"ewa\"\n"
        "Texture \"f\" \"float\" \"imagemap\" \"string filename\" \"pbrt_tex4.pfm\" \"string wrap\" \"clamp\" "
        "\"float uscale\" 2 \"float vscale\" 0.5 \"float udelta\" 0.25 \"float vdelta\" 0.125\n"
        "Texture \"lin\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex4.png\" \"string encoding\" \"linear\"\n"
        "Texture \"gam\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex4.png\" \"string encoding\" \"gamma 2.2\"\n"
        "Texture \"srgb\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex4.png\"\n"
        "Material \"diffuse\" \"texture reflectance\" \"a\"\n" TRI       /* 0 */
        "Material \"conductor\" \"texture roughness\" \"f\" \"bool remaproughness\" false\n" TRI /* 1 */
        "Material \"diffuse\" \"texture reflectance\" \"lin\"\n" TRI     /* 2 */
        "Material \"diffuse\" \"texture reflectance\" \"gam\"\n" TRI     /* 3 */
        "Material \"diffuse\" \"texture reflectance\" \"srgb\"\n" TRI);  /* 4 */
    Scene *s = load_file_scene(text, &w);
    const Texture *a = albedo_tex(s, 0);
    assert_int_equal(a->type, TEXTURE_IMAGE);
    assert_int_equal(a->image.wrap, TEXTURE_WRAP_CLAMP);
    const float *p = a->image.rgb; /* max(0, 1 - 0.5 v) */
    assert_rgb(color_rgb(p[0], p[1], p[2]), 0.5f, 1, 1, 0);
    assert_rgb(color_rgb(p[9], p[10], p[11]), 0.5f, 0.5f, 0.5f, 0);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "wrap \"black\" approximated by \"clamp\"", text, "\"string wrap\"", 0);
    assert_warning_at(&w, CST_WARN_APPROXIMATED, "filter \"ewa\" approximated", text, "\"string filter\"", 0);
    /* the float texture: red channel, then caustic's roughness sqrt(v) */
    const Material *m = tri_material(s, 1);
    const Texture *f = &s->textures[m->roughness_texture - 1];
    assert_int_equal(f->image.wrap, TEXTURE_WRAP_CLAMP);
    assert_true(f->uv_scale.x == 2.0f && f->uv_scale.y == 0.5f && f->uv_offset.x == 0.25f && f->uv_offset.y == 0.125f);
    const float expect_red[4] = {1, 0, 0, 1};
    for (int i = 0; i < 4; i++)
        assert_rgb(color_rgb(f->image.rgb[3 * i], f->image.rgb[3 * i + 1], f->image.rgb[3 * i + 2]), expect_red[i],
                   expect_red[i], expect_red[i], 0);
    /* encodings of one 8-bit PNG: gamma 2.2 of the linear codes; sRGB decodes to the floats written */
    const Texture *lin = albedo_tex(s, 2), *gam = albedo_tex(s, 3), *srgb = albedo_tex(s, 4);
    for (int i = 0; i < 12; i++) {
        float l = lin->image.rgb[i];
        assert_true(fabsf(gam->image.rgb[i] - powf(l, 2.2f)) < 1e-6f);
        assert_true(fabsf(srgb->image.rgb[i] - grey[i]) < 0.004f);
        assert_true(fabsf(l - grey[i]) > 0.05f); /* linear really is the raw codes */
    }
    cst_scene_destroy(s);
    /* a missing image: an I/O error at its file name */
    text = WORLD("Texture \"i\" \"spectrum\" \"imagemap\"\n  \"string filename\" \"no-such-image.png\"\n" TRI);
    CstScene *cs = NULL;
    CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/t.pbrt", NULL, &cs, &err);
    assert_int_equal(st, CST_ERR_IO);
    assert_null(cs);
    if (!strstr(err.msg, "/t.pbrt:5:3: Texture \"i\" \"imagemap\": ") || !strstr(err.msg, "no-such-image.png"))
        fail_msg("%s", err.msg);
}

/* A quad with uvs (0,0) at the bottom left to (1,1) at the top right and a 2x2 image,
 * seen through a 2x2 orthographic camera from -z: pbrt-v4 looks images up at (u, 1 - v)
 * with row 0 at the top, and its LookAt images are mirrored (left-handed), so each pixel
 * shows the texel at the same place in the image file. Checked at the pixel centres'
 * hits, where bilinear filtering returns the texel exactly. */
static void test_texture_orientation(void **state)
{
    (void)state;
    const float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(CST_BINARY_DIR "/pbrt_tex_orient.pfm", px, 2, 2, &err), CST_OK);
    Warnings w = {0};
    Scene *s = load_file_scene(
        "Film \"rgb\" \"integer xresolution\" 2 \"integer yresolution\" 2\n"
        "LookAt 0.5 0.5 -1  0.5 0.5 0  0 1 0\n"
        "Camera \"orthographic\" \"float screenwindow\" [-0.5 0.5 -0.5 0.5]\nWorldBegin\n"
        "Texture \"img\" \"spectrum\" \"imagemap\" \"string filename\" \"pbrt_tex_orient.pfm\"\n"
        "Material \"diffuse\" \"texture reflectance\" \"img\"\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  1 1 0  0 1 0] \"point2 uv\" [0 0  1 0  1 1  0 1] "
        "\"integer indices\" [0 1 2  0 2 3]\n", &w);
    Camera cam;
    camera_init(&cam, &s->camera, 2, 2);
    if (s->camera_mirror) camera_mirror_x(&cam);
    for (int y = 0; y < 2; y++)
        for (int x = 0; x < 2; x++) {
            Ray r = camera_generate_ray(&cam, (float)x + 0.5f, (float)y + 0.5f, v2(0.5f, 0.5f));
            SurfaceHit sh;
            assert_true(scene_intersect(s, &r, &sh));
            Bsdf b;
            scene_bsdf(s, &sh, &b);
            const float *t = &px[3 * (2 * y + x)];
            assert_rgb(b.albedo, t[0], t[1], t[2], 1e-4f);
        }
    cst_scene_destroy(s);
}

static void test_instances(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("ObjectBegin \"pair\"\n Translate 0 0 1\n" TRI
                               " AreaLightSource \"diffuse\"\n Shape \"sphere\" \"float radius\" 0.25\nObjectEnd\n"
                               "AttributeBegin\n Translate 10 0 0\n ObjectInstance \"pair\"\nAttributeEnd\n"
                               "AttributeBegin\n Translate 20 0 0\n ObjectInstance \"pair\"\nAttributeEnd\n"),
                         &w);
    assert_int_equal(s->num_triangles, 0); /* the triangle is instanced, not copied */
    assert_non_null(s->instances);
    assert_int_equal(s->instances->num_protos, 1);
    assert_int_equal(s->instances->num_insts, 2);
    assert_int_equal(s->instances->protos[0].num_triangles, 1);
    assert_vec(s->instances->protos[0].positions[1], 1, 0, 1, 0); /* the definition's CTM */
    assert_vec(transform_point(&s->instances->insts[1].world_from_obj, v3(1, 0, 1)), 21, 0, 1, 0);
    assert_int_equal(s->num_spheres, 2); /* spheres are copied */
    assert_vec(s->spheres[0].center, 10, 0, 1, 0);
    assert_int_equal(s->num_emitters, 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "spheres in instanced objects") >= 0);
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "area lights inside ObjectBegin") >= 0);
    /* a ray down onto the second instance's triangle */
    SurfaceHit sh;
    Ray r = ray_make(v3(20.25f, 0.25f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    assert_true(fabsf(sh.t - 4.0f) < 1e-5f);
    assert_vec(sh.p, 20.25f, 0.25f, 1.0f, 1e-5f);
    assert_vec(sh.ng, 0, 0, 1, 1e-6f);
    assert_true(scene_occluded(s, &r));
    r.d = v3(0.0f, 0.0f, 1.0f);
    assert_false(scene_intersect(s, &r, &sh));
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.instances, 2);
    assert_int_equal(info.instanced_objects, 1);
    assert_true(info.instanced_triangles == 1);
    cst_scene_destroy(s);
}

/* The same objects instanced and written out as copies: every camera ray finds the same
 * surface (t to 1e-4 relative, same material, same normal), with rotations, non-uniform
 * scales and a mirror among the instance transforms. */
static void test_instances_match_copies(void **state)
{
    (void)state;
#define OBJ_SHAPES "Shape \"trianglemesh\" \"point3 P\" [-1 -1 0  1 -1 0  1 1 0  -1 1 0] \"integer indices\" [0 1 2 0 2 3]\n" \
                   "  \"normal N\" [0.3 0 1  0 0.4 1  -0.2 0.1 1  0 0 1]\n" \
                   "Material \"diffuse\" \"rgb reflectance\" [.1 .2 .3]\n" \
                   "Shape \"trianglemesh\" \"point3 P\" [0 0 0  0 1 1  1 0 1] \"integer indices\" [0 1 2]\n"
    static const char *const xfs[] = {"Translate -2 0 0", "Translate 2 0 1\nRotate 30 0 1 0",
                                      "Translate 0 2 0\nScale 0.5 1 2", "Translate 0 -2 0\nScale -1 1 1",
                                      "Translate 0 0 3\nRotate 200 1 1 0"};
    char inst[4096], copy[4096];
    int ni = snprintf(inst, sizeof inst, "LookAt 0 0 -8  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\n"
                      "WorldBegin\nObjectBegin \"o\"\n" OBJ_SHAPES "ObjectEnd\n");
    int nc = snprintf(copy, sizeof copy, "LookAt 0 0 -8  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 60\nWorldBegin\n");
    for (int i = 0; i < 5; i++) {
        ni += snprintf(inst + ni, sizeof inst - (size_t)ni, "AttributeBegin\n%s\nObjectInstance \"o\"\nAttributeEnd\n", xfs[i]);
        nc += snprintf(copy + nc, sizeof copy - (size_t)nc, "AttributeBegin\n%s\n" OBJ_SHAPES "AttributeEnd\n", xfs[i]);
    }
#undef OBJ_SHAPES
    Scene *a = expect_ok(inst, NULL), *b = expect_ok(copy, NULL);
    assert_int_equal(a->num_triangles, 0);
    assert_int_equal(b->num_triangles, 15);
    int hits = 0, smooth_hits = 0;
    for (int y = 0; y < 64; y++)
        for (int x = 0; x < 64; x++) {
            Vec3 d = v3_normalize(v3(((float)x + 0.5f) / 32.0f - 1.0f, ((float)y + 0.5f) / 32.0f - 1.0f, 1.6f));
            Ray r = ray_make(v3(0.0f, 0.0f, -8.0f), d, 0.0f, INFINITY);
            SurfaceHit ha, hb;
            bool ia = scene_intersect(a, &r, &ha), ib = scene_intersect(b, &r, &hb);
            if (ia != ib) fail_msg("ray %d,%d: instanced %d, copies %d", x, y, ia, ib);
            if (!ia) continue;
            hits++;
            if (fabsf(ha.t - hb.t) > 1e-4f * hb.t) fail_msg("ray %d,%d: t %g vs %g", x, y, (double)ha.t, (double)hb.t);
            assert_true(a->materials[ha.material].albedo.c[0] == b->materials[hb.material].albedo.c[0]);
            if (v3_dot(ha.ng, hb.ng) < 0.9999f)
                fail_msg("ray %d,%d: normal (%g %g %g) vs (%g %g %g)", x, y, (double)ha.ng.x, (double)ha.ng.y,
                         (double)ha.ng.z, (double)hb.ng.x, (double)hb.ng.y, (double)hb.ng.z);
            /* Shading normals (the square's N) carried the same way, except under the
             * non-uniform scale (copy 2, triangles 6..8 of b): copies renormalise each
             * transformed vertex normal before interpolating, instances interpolate in
             * object space and then transform (as pbrt-v4 does both), which differ there. */
            if (hb.prim / 3 != 2 && v3_dot(ha.ns, hb.ns) < 0.9999f)
                fail_msg("ray %d,%d: shading normal (%g %g %g) vs (%g %g %g)", x, y, (double)ha.ns.x, (double)ha.ns.y,
                         (double)ha.ns.z, (double)hb.ns.x, (double)hb.ns.y, (double)hb.ns.z);
            if (a->materials[ha.material].albedo.c[0] != 0.1f) smooth_hits += v3_dot(ha.ns, ha.ng) < 0.999f;
            assert_true(scene_occluded(a, &r) && scene_occluded(b, &r));
        }
    assert_true(hits > 300 && smooth_hits > 100);
    cst_scene_destroy(a);
    cst_scene_destroy(b);
}

/* Issue #6: 10^4 instances of a 70k-triangle mesh cost about one copy of the mesh plus the
 * instance table, not 10^4 copies (7 * 10^8 triangles, tens of GB). */
static void test_instances_memory(void **state)
{
    (void)state;
    enum { N = 188, INSTANCES = 10000 }; /* (N-1)^2 * 2 = 69938 triangles */
    size_t cap = 8u << 20, n = 0;
    char *t = malloc(cap);
    assert_non_null(t);
    n += (size_t)snprintf(t + n, cap - n, "LookAt 50 50 -150  50 50 0  0 1 0\nCamera \"perspective\" \"float fov\" 50\n"
                          "WorldBegin\nAttributeBegin\nAreaLightSource \"diffuse\" \"rgb L\" [4 4 4]\n"
                          "Translate 50 50 -60 Shape \"sphere\" \"float radius\" 20\nAttributeEnd\n"
                          "ObjectBegin \"bumps\"\nShape \"trianglemesh\" \"point3 P\" [");
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++)
            n += (size_t)snprintf(t + n, cap - n, "%.4f %.4f %.4f ", i / (double)(N - 1), j / (double)(N - 1),
                                  0.05 * sin(i * 0.3) * cos(j * 0.2));
    n += (size_t)snprintf(t + n, cap - n, "] \"integer indices\" [");
    for (int j = 0; j + 1 < N; j++)
        for (int i = 0; i + 1 < N; i++) {
            int v = j * N + i;
            n += (size_t)snprintf(t + n, cap - n, "%d %d %d %d %d %d ", v, v + 1, v + N + 1, v, v + N + 1, v + N);
        }
    n += (size_t)snprintf(t + n, cap - n, "]\nObjectEnd\n");
    for (int k = 0; k < INSTANCES; k++)
        n += (size_t)snprintf(t + n, cap - n, "AttributeBegin Translate %d %d 0 Rotate %d 0 0 1 ObjectInstance \"bumps\" AttributeEnd\n",
                              (k % 100) * 1, (k / 100) * 1, (k * 37) % 360);
    assert_true(n < cap - 1);
    Scene *s = expect_ok(t, NULL);
    free(t);
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.instances, INSTANCES);
    assert_true(info.instanced_triangles == (size_t)2 * (N - 1) * (N - 1));
    const InstProto *p = &s->instances->protos[0];
    size_t one_copy = (size_t)p->num_positions * sizeof(Vec3) +
                      (size_t)p->num_triangles * (3 * sizeof(int32_t) + sizeof(int32_t) + sizeof(Vec3)) +
                      accel_memory_bytes(&p->accel);
    size_t table = info.instance_bytes - one_copy;
    print_message("10^4 instances of a %zu-triangle mesh: %zu bytes in all = one copy %zu "
                  "(geometry + BVH) + instance table and top-level tree %zu (%.0f bytes per "
                  "instance); as copies: about %.1f GB\n",
                  info.instanced_triangles, info.instance_bytes, one_copy, table,
                  (double)table / INSTANCES, (double)one_copy * INSTANCES / 1e9);
    assert_true(table < (size_t)INSTANCES * 400);
    assert_true(info.instance_bytes < one_copy + (size_t)INSTANCES * 400);
    /* and it renders: the mesh field is lit, not black */
    CstRenderSettings st;
    cst_render_settings_init(&st); /* the scene's max_depth (pbrt: 5) */
    st.width = st.height = 24;
    st.spp = 4;
    st.threads = 2;
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    int lit = 0;
    for (int y = 0; y < 24; y++)
        for (int x = 0; x < 24; x++) {
            double c[3];
            cst_film_pixel(f, x, y, c);
            lit += c[0] + c[1] + c[2] > 0.0;
        }
    /* the field covers about half the image at this distance */
    if (!(lit > 24 * 24 / 4)) fail_msg("%d of %d pixels lit", lit, 24 * 24);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ camera and options */

static void test_camera_and_options(void **state)
{
    (void)state;
    Warnings w = {0};
    /* portrait film: pbrt's fov 60 spans the (shorter) horizontal axis */
    Scene *s = expect_ok("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 200 "
                         "\"string filename\" \"out.exr\" \"float iso\" 100\n"
                         "LookAt 1 2 3  1 2 4  0 1 0\n"
                         "Camera \"perspective\" \"float fov\" 60 \"float lensradius\" 0.1 \"float focaldistance\" 7\n"
                         "Sampler \"halton\" \"integer pixelsamples\" 32\n"
                         "Integrator \"mlt\" \"integer maxdepth\" 7\n"
                         "PixelFilter \"gaussian\"\n"
                         "WorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.width, 100);
    assert_int_equal(s->settings.height, 200);
    assert_int_equal(s->settings.spp, 32);
    assert_int_equal(s->settings.sampler, CST_SAMPLER_SOBOL); /* halton: the nearest we have */
    assert_int_equal(s->settings.max_depth, 7);
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_PATH);
    assert_int_equal(s->settings.filter, CST_FILTER_GAUSSIAN); /* pbrt's default parameters: exact */
    assert_string_equal(s->output_path, "out.exr");
    double vfov = 2.0 * atan(tan(30.0 * 3.14159265358979 / 180.0) * 2.0) * 180.0 / 3.14159265358979;
    assert_true(fabs((double)s->camera.vfov_deg - vfov) < 1e-4);
    assert_vec(s->camera.position, 1, 2, 3, 0);
    assert_true(s->camera_mirror); /* a plain LookAt is left-handed */
    assert_true(s->camera.aperture_radius == 0.1f && s->camera.focus_distance == 7.0f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"float iso\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "Sampler \"halton\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "Integrator \"mlt\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "PixelFilter \"gaussian\"") < 0);
    cst_scene_destroy(s);
    /* pbrt defaults; Scale -1 1 1 before LookAt makes the frame right-handed */
    s = expect_ok("Scale -1 1 1\nLookAt 0 0 0  0 0 1  0 1 0\nCamera \"perspective\"\nWorldBegin\n" TRI, NULL);
    assert_int_equal(s->settings.width, 1280);
    assert_int_equal(s->settings.height, 720);
    assert_int_equal(s->settings.max_depth, 5);
    assert_true(s->camera.vfov_deg == 90.0f);
    assert_false(s->camera_mirror);
    assert_int_equal(s->settings.filter, CST_FILTER_GAUSSIAN); /* pbrt's default filter */
    cst_scene_destroy(s);
    /* filters: Mitchell with pbrt's defaults is exact; other parameters, sinc: approximated */
    memset(&w, 0, sizeof w);
    s = expect_ok("PixelFilter \"mitchell\" \"float B\" 0.33333333 \"float xradius\" 2\nWorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.filter, CST_FILTER_MITCHELL);
    assert_int_equal(w.n, 0);
    cst_scene_destroy(s);
    s = expect_ok("PixelFilter \"gaussian\" \"float sigma\" 1\nWorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.filter, CST_FILTER_GAUSSIAN);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "sigma 0.5 and radius 1.5") >= 0);
    cst_scene_destroy(s);
    s = expect_ok("PixelFilter \"sinc\"\nWorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.filter, CST_FILTER_MITCHELL);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "PixelFilter \"sinc\" approximated by the Mitchell") >= 0);
    cst_scene_destroy(s);
    s = expect_ok("Integrator \"bdpt\"\nWorldBegin\n" TRI, NULL);
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_BDPT);
    cst_scene_destroy(s);
    s = expect_ok("Integrator \"path\" \"integer maxdepth\" -1\nWorldBegin\n" TRI, NULL);
    assert_int_equal(s->settings.max_depth, 0); /* unbounded */
    assert_false(s->camera_set == 0);
    cst_scene_destroy(s);
    s = expect_ok("Integrator \"sppm\" \"integer photonsperiteration\" 5000 \"float radius\" 0.5\n"
                  "Accelerator \"kdtree\"\nWorldBegin\n" TRI, NULL);
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_SPPM);
    assert_int_equal(s->settings.photons, 5000);
    assert_int_equal(s->accel_type, ACCEL_KDTREE);
    cst_scene_destroy(s);
}

/* Camera "orthographic": the view's height is the screen window's (default [-1, 1] on the
 * shorter axis), in camera units scaled into the world; a lens is ignored with a warning. */
static void test_orthographic_camera(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok("Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                         "LookAt 0 0 -5  0 0 0  0 1 0\n"
                         "Camera \"orthographic\" \"float lensradius\" 0.5 \"float fov\" 30\n"
                         "WorldBegin\n" TRI, &w);
    assert_true(s->camera.ortho_height == 2.0f); /* landscape: y spans [-1, 1] */
    assert_true(s->camera.aperture_radius == 0.0f);
    assert_vec(s->camera.position, 0, 0, -5, 0);
    assert_vec(s->camera.up, 0, 1, 0, 0);
    assert_true(s->camera_mirror);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "lensradius 0.5 and focaldistance 1e+06 ignored") >= 0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"float fov\"") >= 0);
    cst_scene_destroy(s);
    /* portrait: x spans [-1, 1], y [-2, 2] */
    s = expect_ok("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 200\n"
                  "Camera \"orthographic\"\nWorldBegin\n" TRI, NULL);
    assert_true(s->camera.ortho_height == 4.0f);
    cst_scene_destroy(s);
    memset(&w, 0, sizeof w);
    s = expect_ok("Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                  "Camera \"orthographic\" \"float screenwindow\" [-3 3 -1.5 1.5]\nWorldBegin\n" TRI, &w);
    assert_true(s->camera.ortho_height == 3.0f);
    assert_int_equal(w.n, 0);
    cst_scene_destroy(s);
    /* a scaled camera transform: world-from-camera halves camera units */
    s = expect_ok("Film \"rgb\" \"integer xresolution\" 200 \"integer yresolution\" 100\n"
                  "Scale 2 2 2\nLookAt 0 0 -5  0 0 0  0 1 0\nCamera \"orthographic\"\nWorldBegin\n" TRI, NULL);
    assert_true(fabsf(s->camera.ortho_height - 1.0f) < 1e-6f);
    cst_scene_destroy(s);
    expect_error("Camera \"orthographic\" \"float screenwindow\" [-1 1 -1]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"float screenwindow\"", 0, "expected 4");
    expect_error("Camera \"orthographic\" \"float screenwindow\" [1 -1 -1 1]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"float screenwindow\"", 0, "is empty");
}

/* ------------------------------------------------------------------ rendering */

static Film *render_small(const CstScene *s, int w, int h, int spp)
{
    CstRenderSettings st;
    cst_render_settings_init(&st); /* the scene's max_depth (pbrt: 5) */
    st.width = w;
    st.height = h;
    st.spp = spp;
    st.threads = 2;
    st.filter = CST_FILTER_BOX;
    st.integrator = CST_INTEGRATOR_PATH;
    st.seed = 9;
    st.seed_set = 1;
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    return f;
}

static int films_identical(const Film *a, const Film *b)
{
    size_t n = (size_t)a->width * (size_t)a->height * 3u;
    return a->width == b->width && a->height == b->height && a->spp == b->spp &&
           memcmp(a->sum, b->sum, n * sizeof *a->sum) == 0 &&
           memcmp(a->sum_sq, b->sum_sq, n * sizeof *a->sum_sq) == 0;
}

/* scenes/cornell-box.pbrt holds the JSON box's triangles in the same order and its camera:
 * the images must be equal bit for bit, at the file's own settings too. */
static void test_cornell_pbrt_equals_json(void **state)
{
    (void)state;
    CstScene *json = NULL, *pbrt = NULL;
    CstError err;
    Warnings w = {0};
    CstLoadOptions opt = {collect, &w, 0};
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-box.json", &json, &err) != CST_OK) fail_msg("%s", err.msg);
    if (cst_scene_load_pbrt(CST_SOURCE_DIR "/scenes/cornell-box.pbrt", &opt, &pbrt, &err) != CST_OK) fail_msg("%s", err.msg);
    if (w.n) fail_msg("unexpected warning: %s", w.msg[0]);
    assert_int_equal(pbrt->num_triangles, json->num_triangles);
    for (int t = 0; t < json->num_triangles; t++)
        for (int k = 0; k < 3; k++) {
            Vec3 a = tri_vertex(json, t, k), b = tri_vertex(pbrt, t, k);
            assert_memory_equal(&a, &b, sizeof a);
        }
    assert_memory_equal(&pbrt->camera.position, &json->camera.position, sizeof(Vec3));
    assert_true(pbrt->camera.vfov_deg == json->camera.vfov_deg);
    assert_false(pbrt->camera_mirror);
    CstRenderSettings a = {0}, b = {0};
    cst_render_settings_resolve(json, NULL, &a);
    cst_render_settings_resolve(pbrt, NULL, &b);
    assert_int_equal(a.width, b.width);
    assert_int_equal(a.height, b.height);
    assert_int_equal(a.spp, b.spp);
    assert_true(a.seed == b.seed && a.seed_set == b.seed_set);
    assert_int_equal(a.integrator, b.integrator);
    assert_int_equal(a.filter, b.filter);
    assert_int_equal(a.max_depth, b.max_depth);
    assert_int_equal(a.rr_depth, b.rr_depth);
    assert_string_equal(cst_scene_output_path(json), cst_scene_output_path(pbrt));
    Film *fa = render_small(json, 96, 80, 8), *fb = render_small(pbrt, 96, 80, 8);
    assert_true(films_identical(fa, fb));
    film_destroy(fa);
    film_destroy(fb);
    cst_scene_destroy(json);
    cst_scene_destroy(pbrt);
}

/* A diffuse sphere under a constant sky: the pbrt file (LightSource "infinite") and the
 * JSON scene ("environment") render the same film bit for bit. */
static void test_env_sphere_pbrt_equals_json(void **state)
{
    (void)state;
    const char *json_text =
        "{\"film\": {\"width\": 32, \"height\": 24, \"filter\": \"box\"},\n"
        " \"camera\": {\"type\": \"pinhole\", \"position\": [0, 0, -4], \"look_at\": [0, 0, 0],\n"
        "            \"up\": [0, 1, 0], \"fov\": 40},\n"
        " \"integrator\": {\"type\": \"path\", \"max_depth\": 5},\n"
        " \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.6, 0.7]}},\n"
        " \"shapes\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1, \"material\": \"m\"}],\n"
        " \"environment\": {\"radiance\": [0.8, 0.9, 1.0]}}\n";
    const char *pbrt_text =
        "Film \"rgb\" \"integer xresolution\" 32 \"integer yresolution\" 24\n"
        "PixelFilter \"box\"\nIntegrator \"path\" \"integer maxdepth\" 5\n"
        "Scale -1 1 1\nLookAt 0 0 -4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n"
        "WorldBegin\nLightSource \"infinite\" \"rgb L\" [0.8 0.9 1.0]\n"
        "Material \"diffuse\" \"rgb reflectance\" [0.5 0.6 0.7]\nShape \"sphere\" \"float radius\" 1\n";
    FILE *f = fopen(CST_BINARY_DIR "/pbrt_env_sphere.json", "w");
    assert_non_null(f);
    fputs(json_text, f);
    fclose(f);
    CstScene *json = NULL, *pbrt = NULL;
    CstError err;
    Warnings w = {0};
    if (cst_scene_load_json(CST_BINARY_DIR "/pbrt_env_sphere.json", &json, &err) != CST_OK) fail_msg("%s", err.msg);
    if (load_w(pbrt_text, &pbrt, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    if (w.n) fail_msg("unexpected warning: %s", w.msg[0]);
    /* the same pinhole (the focus distance, unused without a lens, differs) */
    assert_memory_equal(&pbrt->camera, &json->camera, offsetof(CameraDesc, focus_distance));
    assert_true(pbrt->camera.aperture_radius == 0.0f && pbrt->camera.ortho_height == json->camera.ortho_height);
    assert_false(pbrt->camera_mirror);
    assert_memory_equal(&pbrt->env->scale, &json->env->scale, sizeof(Color));
    CstRenderSettings a = {0}, b = {0};
    cst_render_settings_resolve(json, NULL, &a);
    cst_render_settings_resolve(pbrt, NULL, &b);
    assert_true(a.max_depth == b.max_depth && a.rr_depth == b.rr_depth && a.filter == b.filter);
    Film *fa = render_small(json, 32, 24, 16), *fb = render_small(pbrt, 32, 24, 16);
    assert_true(films_identical(fa, fb));
    double c[3]; /* the sky is seen around the sphere */
    cst_film_pixel(fb, 0, 0, c);
    assert_true(c[2] > 0.9 && c[2] < 1.1);
    film_destroy(fa);
    film_destroy(fb);
    cst_scene_destroy(json);
    cst_scene_destroy(pbrt);
}

/* Red minus green in the left and right thirds of the image. */
static void red_sides(const Film *f, double *left, double *right)
{
    *left = *right = 0.0;
    for (int y = 0; y < f->height; y++)
        for (int x = 0; x < f->width; x++) {
            double c[3];
            cst_film_pixel(f, x, y, c);
            if (x < f->width / 3) *left += c[0] - c[1];
            if (x >= f->width - f->width / 3) *right += c[0] - c[1];
        }
}

/* pbrt's image right is the camera's +x. With "Scale -1 1 1" before LookAt (the Cornell
 * file) the red wall at x = 550 is on the left, as in the JSON scene; the same file with
 * a plain LookAt (x = up x view = world +x on the right) shows it on the right. */
static void test_cornell_handedness(void **state)
{
    (void)state;
    FILE *f = fopen(CST_SOURCE_DIR "/scenes/cornell-box.pbrt", "rb");
    assert_non_null(f);
    static char text[1 << 16];
    size_t n = fread(text, 1, sizeof text - 1, f);
    fclose(f);
    text[n] = '\0';
    CstScene *a = NULL, *b = NULL;
    CstError err;
    if (cst_scene_load_pbrt_string(text, n, "cornell.pbrt", NULL, &a, &err) != CST_OK) fail_msg("%s", err.msg);
    char *sc = strstr(text, "Scale -1 1 1\n");
    assert_non_null(sc);
    memcpy(sc, "#cale", 5);
    if (cst_scene_load_pbrt_string(text, n, "cornell.pbrt", NULL, &b, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_true(b->camera_mirror);
    Film *fa = render_small(a, 48, 48, 4), *fb = render_small(b, 48, 48, 4);
    double al, ar, bl, br;
    red_sides(fa, &al, &ar);
    red_sides(fb, &bl, &br);
    if (!(al > 0.0 && ar < 0.0 && bl < 0.0 && br > 0.0))
        fail_msg("red - green: Scale -1 1 1 left %g right %g; plain LookAt left %g right %g", al, ar, bl, br);
    film_destroy(fa);
    film_destroy(fb);
    cst_scene_destroy(a);
    cst_scene_destroy(b);
}

/* Film cropwindow (fractions, pbrt-v4's ceil(res * c)) and pixelbounds onto the crop. */
static void test_film_crop(void **state)
{
    (void)state;
    Scene *s = expect_ok("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 50 "
                         "\"float cropwindow\" [0.105 0.5 0.2 1]\nWorldBegin\n" TRI, NULL);
    assert_int_equal(s->settings.crop[0], 11);
    assert_int_equal(s->settings.crop[1], 50);
    assert_int_equal(s->settings.crop[2], 10);
    assert_int_equal(s->settings.crop[3], 50);
    cst_scene_destroy(s);
    Warnings w = {0};
    s = expect_ok("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 50 "
                  "\"float cropwindow\" [0 0.5 0 1] \"integer pixelbounds\" [3 7 4 9]\nWorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.crop[0], 3);
    assert_int_equal(s->settings.crop[1], 7);
    assert_int_equal(s->settings.crop[2], 4);
    assert_int_equal(s->settings.crop[3], 9);
    cst_scene_destroy(s);
    expect_error("Film \"rgb\" \"integer xresolution\" 100 \"float cropwindow\" [0.5 0.2 0 1]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"float cropwindow\"", 0, "cropwindow; expected 4 values");
    expect_error("Film \"rgb\" \"integer xresolution\" 100 \"float cropwindow\" [0 0.5 0]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"float cropwindow\"", 0, "cropwindow");
    expect_error("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 50 "
                 "\"integer pixelbounds\" [0 101 0 5]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"integer pixelbounds\"", 0, "0 <= x0 < x1 <= 100");
    expect_error("Film \"rgb\" \"integer xresolution\" 100 \"integer yresolution\" 50 "
                 "\"float cropwindow\" [0.001 0.002 0 1]\nWorldBegin\n" TRI,
                 CST_ERR_INVALID_ARG, "\"float cropwindow\"", 0, "holds no pixel");
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_film_crop),
        cmocka_unit_test(test_tokens),
        cmocka_unit_test(test_token_errors),
        cmocka_unit_test(test_parse_errors),
        cmocka_unit_test(test_parse_errors_located),
        cmocka_unit_test(test_semantic_errors),
        cmocka_unit_test(test_missing_files),
        cmocka_unit_test(test_transforms),
        cmocka_unit_test(test_orientation),
        cmocka_unit_test(test_attributes_scope),
        cmocka_unit_test(test_include),
        cmocka_unit_test(test_parameter_types),
        cmocka_unit_test(test_colour_conversions),
        cmocka_unit_test(test_materials),
        cmocka_unit_test(test_lights),
        cmocka_unit_test(test_delta_lights),
        cmocka_unit_test(test_equal_area_map),
        cmocka_unit_test(test_infinite_lights),
        cmocka_unit_test(test_shapes),
        cmocka_unit_test(test_plymesh),
        cmocka_unit_test(test_other_directives),
        cmocka_unit_test(test_imagemap_and_binary_ply),
        cmocka_unit_test(test_texture_classes),
        cmocka_unit_test(test_texture_materials),
        cmocka_unit_test(test_imagemap_params),
        cmocka_unit_test(test_texture_orientation),
        cmocka_unit_test(test_instances),
        cmocka_unit_test(test_instances_match_copies),
        cmocka_unit_test(test_instances_memory),
        cmocka_unit_test(test_camera_and_options),
        cmocka_unit_test(test_orthographic_camera),
        cmocka_unit_test(test_cornell_pbrt_equals_json),
        cmocka_unit_test(test_env_sphere_pbrt_equals_json),
        cmocka_unit_test(test_cornell_handedness),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
