/* Unit tests for the pbrt-v4 loader (scene/pbrt/), parsing: tokens and their locations,
 * lexical, syntax and semantic errors (status and file:line:column), the transform and
 * state directives, Include, parameter types and colour conversions, the camera and the
 * rendering options, and the Cornell box in pbrt format rendering bit for bit like the
 * JSON one. */
#include "unit/pbrt_test_util.h"

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
                 CST_ERR_PARSE, "AttributeBegin", 0, "expected ']' to close the '[' at t.pbrt:4:33");
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
    expect_error(WORLD("Transform [1 0 0 1e39 0 1 0 0 0 0 1 0 0 0 0 1]\n"), CST_ERR_INVALID_ARG,
                 "Transform", 0, "element 4 is not finite");
    expect_error("Film \"rgb\" \"integer xresolution\" 0\n", CST_ERR_INVALID_ARG, "Film", 0,
                 "resolution 0 x 720");
    expect_error(WORLD("Material \"dielectric\" \"float eta\" -1\n" TRI), CST_ERR_INVALID_ARG,
                 "\"float eta\"", 0, "not positive");
    /* no shapes: loads (as pbrt-v4 renders it), with a warning located at the end of the file */
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    if (load_w(WORLD("Shape \"cone\"\n"), &s, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(w.n, 2); /* the skipped cone, then the empty world */
    assert_int_equal(w.code[1], CST_WARN_GEOMETRY);
    if (strncmp(w.msg[1], "t.pbrt:5:1: the world has no shapes", 35) != 0) fail_msg("%s", w.msg[1]);
    cst_scene_destroy(s);
    /* a cylinder alone is a world with a shape: no warning at all */
    w.n = 0;
    if (load_w(WORLD("Shape \"cylinder\"\n"), &s, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(w.n, 0);
    cst_scene_destroy(s);
}

/* Errors without file access disabled: a missing PLY (I/O, located at its file name)
 * and a missing Include. */
static void test_missing_files(void **state)
{
    (void)state;
    const char *text = WORLD("Shape \"plymesh\" \"string filename\" \"no-such-mesh.ply\"\n");
    CstScene *s = NULL;
    CstError err;
    CstStatus st = load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, NULL);
    assert_int_equal(st, CST_ERR_IO);
    assert_null(s);
    if (!strstr(err.msg, "/t.pbrt:4:17: Shape \"plymesh\": ") || !strstr(err.msg, "no-such-mesh.ply"))
        fail_msg("%s", err.msg);
    text = WORLD("Include \"no-such-file.pbrt\"\n");
    st = load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, NULL);
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
        " ActiveTransform StartTime\n Translate 100 0 0\n" /* both CTMs moved alike: static */
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
    assert_vec(tri_vertex(s, 8, 0), 104, 0, 0, 0);
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

/* CstLoadOptions.max_primitives: the load fails at the directive that passes the limit,
 * counting instances and the sphere copies an instance of a sphere object places. */
static void test_max_primitives(void **state)
{
    (void)state;
    static const char text[] =
        "WorldBegin\n"
        "ObjectBegin \"balls\"\n"
        "Shape \"sphere\" \"float radius\" 0.5\n"
        "Shape \"sphere\" \"float radius\" 0.25\n"
        "ObjectEnd\n"
        "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
        "ObjectInstance \"balls\"\n"
        "ObjectInstance \"balls\"\n";
    for (size_t limit = 0; limit <= 6; limit++) {
        CstLoadOptions opt = {0};
        opt.no_file_access = 1;
        opt.max_primitives = limit;
        CstScene *scene = NULL;
        CstError err = {0};
        CstStatus st = cst_scene_load_pbrt_string(text, strlen(text), NAME, &opt, &scene, &err);
        /* 1 triangle, then 2 sphere copies per instance: 3 after the first, 5 after the second */
        if (limit == 0 || limit >= 5) {
            if (st != CST_OK) fail_msg("limit %zu: %s", limit, err.msg);
            cst_scene_destroy(scene);
            continue;
        }
        assert_int_equal(st, CST_ERR_INVALID_ARG);
        assert_null(scene);
        int line, col;
        pos_of(text, limit < 1 ? "Shape \"tri" : "ObjectInstance", limit < 1 ? 0 : limit < 3 ? 0 : 1, &line, &col);
        char prefix[64];
        snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
        if (strncmp(err.msg, prefix, strlen(prefix)) != 0 || !strstr(err.msg, "max_primitives"))
            fail_msg("limit %zu: \"%s\", expected it to start with \"%s\"", limit, err.msg, prefix);
    }
}

static void test_include(void **state)
{
    (void)state;
    const char *dir = CST_BINARY_DIR "/pbrt_include";
    mkdir(dir, 0755);
    write_text(CST_BINARY_DIR "/pbrt_include/geometry.pbrt",
               "# included\nTranslate 0 0 1\n" TRI "Shape \"sphere\" \"float radiu\" 1\n");
    write_text(CST_BINARY_DIR "/pbrt_include/bad.pbrt", "\n  Shape \"sphere\" \"float radius\" [1\n");
    const char *text = WORLD("Include \"geometry.pbrt\"\nImport \"geometry.pbrt\"\n");
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    CstStatus st = load_at(text, CST_BINARY_DIR "/pbrt_include/main.pbrt", &s, &err, &w);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_triangles, 2);
    assert_int_equal(s->num_spheres, 2);
    assert_vec(tri_vertex(s, 1, 0), 0, 0, 2, 0); /* the CTM carries across includes */
    /* warnings name the included file and its line */
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "geometry.pbrt:4:16: Shape \"sphere\": "
                                                           "parameter \"float radiu\"") >= 0);
    cst_scene_destroy(s);
    text = WORLD("Include \"bad.pbrt\"\n");
    st = load_at(text, CST_BINARY_DIR "/pbrt_include/main.pbrt", &s, &err, NULL);
    /* the list left open by bad.pbrt goes on in main.pbrt (pbrt-v4 splices the tokens), so
     * the missing ']' shows at main.pbrt's end, naming the '[' in bad.pbrt */
    assert_int_equal(st, CST_ERR_PARSE);
    if (!strstr(err.msg, "pbrt_include/main.pbrt:5:1: ") || !strstr(err.msg, "bad.pbrt:2:33"))
        fail_msg("%s", err.msg);
}

/* A parameter list an included file leaves open goes on after the Include, in the includer
 * (checked with pbrt-v4's reference build: its "unused parameter" error names the includer's
 * line); Import ends it. Include and Import read .gz files. */
static void test_include_splices_tokens(void **state)
{
    (void)state;
    const char *dir = CST_BINARY_DIR "/pbrt_include2";
    mkdir(dir, 0755);
    write_text(CST_BINARY_DIR "/pbrt_include2/open.pbrt", "Shape \"sphere\"\n");
    const char *text = WORLD("Include \"open.pbrt\"\n  \"float radius\" 3\n");
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    CstStatus st = load_at(text, CST_BINARY_DIR "/pbrt_include2/main.pbrt", &s, &err, &w);
    if (st != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_spheres, 1);
    assert_true(s->spheres[0].radius == 3.0f);
    cst_scene_destroy(s);
    /* Import: the list does not go on; the string is a parse error in main.pbrt */
    text = WORLD("Import \"open.pbrt\"\n  \"float radius\" 3\n");
    st = load_at(text, CST_BINARY_DIR "/pbrt_include2/main.pbrt", &s, &err, NULL);
    assert_int_equal(st, CST_ERR_PARSE);
    if (!strstr(err.msg, "main.pbrt:5:3: ")) fail_msg("%s", err.msg);
    /* gzip-compressed include: "Shape sphere radius 2" */
    static const unsigned char gz[] = { /* printf 'Shape "sphere" "float radius" 2\n' | gzip -9n */
        0x1f, 0x8b, 0x08, 0x00, 0x00, 0x00, 0x00, 0x00, 0x02, 0x03, 0x0b, 0xce, 0x48, 0x2c, 0x48,
        0x55, 0x50, 0x2a, 0x2e, 0xc8, 0x48, 0x2d, 0x4a, 0x55, 0x52, 0x50, 0x4a, 0xcb, 0xc9, 0x4f,
        0x2c, 0x51, 0x28, 0x4a, 0x4c, 0xc9, 0x2c, 0x2d, 0x56, 0x52, 0x30, 0xe2, 0x02, 0x00, 0xf9,
        0x8e, 0x0c, 0x40, 0x20, 0x00, 0x00, 0x00};
    write_file(CST_BINARY_DIR "/pbrt_include2/geo.pbrt.gz", gz, sizeof gz);
    for (int imp = 0; imp < 2; imp++) {
        text = imp ? WORLD("Import \"geo.pbrt.gz\"\n") : WORLD("Include \"geo.pbrt.gz\"\n");
        st = load_at(text, CST_BINARY_DIR "/pbrt_include2/main.pbrt", &s, &err, NULL);
        if (st != CST_OK) fail_msg("%s", err.msg);
        assert_int_equal(s->num_spheres, 1);
        assert_true(s->spheres[0].radius == 2.0f);
        cst_scene_destroy(s);
    }
    /* a corrupt one: a located error naming the Include and the byte */
    unsigned char bad[sizeof gz];
    memcpy(bad, gz, sizeof gz);
    bad[12] ^= 0xff;
    write_file(CST_BINARY_DIR "/pbrt_include2/bad.pbrt.gz", bad, sizeof bad);
    text = WORLD("Include \"bad.pbrt.gz\"\n");
    st = load_at(text, CST_BINARY_DIR "/pbrt_include2/main.pbrt", &s, &err, NULL);
    assert_int_equal(st, CST_ERR_PARSE);
    if (!strstr(err.msg, "main.pbrt:4:9: ") || !strstr(err.msg, "bad.pbrt.gz") || !strstr(err.msg, "gzip"))
        fail_msg("%s", err.msg);
}

/* A parameter given twice: the last wins, as in pbrt-v4 (checked with the reference build:
 * "string filename" twice writes the second file), with a located warning. */
static void test_duplicate_parameter(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("Shape \"sphere\" \"float radius\" 1 \"float radius\" 2\n"), &w);
    assert_int_equal(s->num_spheres, 1);
    assert_true(s->spheres[0].radius == 2.0f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "t.pbrt:4:33: parameter \"radius\" given "
                             "twice: this one is used, the one at t.pbrt:4:16 is ignored") >= 0);
    cst_scene_destroy(s);
    /* not adjacent: still the last */
    w.n = 0;
    s = expect_ok(WORLD("Shape \"sphere\" \"float radius\" 1 \"float zmin\" -1 \"float radius\" 4\n"), &w);
    assert_int_equal(s->num_shapes, 1); /* zmin -1 > -4: a partial sphere, analytic */
    assert_true(s->shapes[0].p.radius == 4.0f && s->shapes[0].p.z_min == -1.0f);
    cst_scene_destroy(s);
}

/* Motion: a transform under ActiveTransform StartTime alone moves only the start (pbrt-v4
 * blurs between start and end): the triangle and the sphere become moving instances (the
 * sphere an analytic shape in an object of its own), without warnings; an emitting sphere
 * that moves is rendered static, with a located warning; TransformTimes is an option (an
 * error in the world block). test_motion and test_motion_shapes render and check the rest. */
static void test_motion_warnings(void **state)
{
    (void)state;
    Warnings w = {0};
    Scene *s = expect_ok(WORLD("ActiveTransform StartTime\nTranslate 1 0 0\nActiveTransform All\n"
                               "Translate 0 1 0\n" TRI "Shape \"sphere\"\n"
                               "AreaLightSource \"diffuse\"\nShape \"sphere\"\n"), &w);
    assert_int_equal(s->num_triangles, 0);
    assert_non_null(s->instances);
    assert_int_equal(s->instances->num_motions, 2);
    for (int i = 0; i < 2; i++) {
        const MotionTransform *mt = &s->instances->motions[i];
        assert_true(mt->start.m[0][3] == 1.0f && mt->start.m[1][3] == 1.0f);
        assert_true(mt->end.m[0][3] == 0.0f && mt->end.m[1][3] == 1.0f);
    }
    assert_int_equal(s->instances->protos[1].num_shapes, 1); /* the moving sphere */
    assert_int_equal(s->num_spheres, 1);                       /* the emitting one, static */
    assert_int_equal(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:9:1:"), -1); /* the moving sphere */
    assert_true(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:11:1: Shape \"sphere\" moves") >= 0);
    assert_int_equal(find_warning(&w, CST_WARN_UNSUPPORTED, "t.pbrt:8:1:"), -1); /* the moving triangle */
    cst_scene_destroy(s);
    expect_error(WORLD("TransformTimes 0 1\n"), CST_ERR_INVALID_ARG, "TransformTimes", 0, "before WorldBegin");
}

/* A projective ConcatTransform (the sssdragon scenes have one): accepted with a warning;
 * triangle vertices divided by w as pbrt-v4's point transform does. */
static void test_projective_transform(void **state)
{
    (void)state;
    Warnings w = {0};
    /* column-major: the bottom row is elements 4, 8, 12, 16 = 0 0 1 1, so w = z + 1 */
    Scene *s = expect_ok(WORLD("ConcatTransform [1 0 0 0  0 1 0 0  0 0 1 1  0 0 0 1]\n"
                               "Shape \"trianglemesh\" \"point3 P\" [0 0 1  4 0 1  0 4 3] "
                               "\"integer indices\" [0 1 2]\n"), &w);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "t.pbrt:4:1: ConcatTransform: a projective "
                             "matrix (bottom row 0 0 1 1") >= 0);
    assert_vec(tri_vertex(s, 0, 0), 0.0f, 0.0f, 0.5f, 1e-6f);
    assert_vec(tri_vertex(s, 0, 1), 2.0f, 0.0f, 0.5f, 1e-6f);
    assert_vec(tri_vertex(s, 0, 2), 0.0f, 1.0f, 0.75f, 1e-6f);
    cst_scene_destroy(s);
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
    assert_int_equal(s->settings.integrator, CST_INTEGRATOR_MMLT); /* mlt: multiplexed MLT over BDPT */
    assert_int_equal(s->settings.filter, CST_FILTER_GAUSSIAN); /* pbrt's default parameters: exact */
    assert_string_equal(s->output_path, "out.exr");
    double vfov = 2.0 * atan(tan(30.0 * 3.14159265358979 / 180.0) * 2.0) * 180.0 / 3.14159265358979;
    assert_true(fabs((double)s->camera.vfov_deg - vfov) < 1e-4);
    assert_vec(s->camera.position, 1, 2, 3, 0);
    assert_true(s->camera_mirror); /* a plain LookAt is left-handed */
    assert_true(s->camera.aperture_radius == 0.1f && s->camera.focus_distance == 7.0f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "\"float iso\"") < 0); /* the sensor's */
    assert_true(s->settings.exposure_set && s->settings.exposure == 0.0); /* iso 100: ratio 1 */
    assert_int_equal(s->settings.color_mode, CST_COLOR_SPECTRAL);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "Sampler \"halton\"") >= 0);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "Integrator \"mlt\"") < 0); /* mmlt: the same algorithm */
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "PixelFilter \"gaussian\"") < 0);
    cst_scene_destroy(s);
    /* pbrt-v4's default sampler, zsobol, is caustic's zsobol (blocks of 256: a warning). */
    Warnings wz = {0};
    s = expect_ok("Sampler \"zsobol\" \"integer pixelsamples\" 64\nWorldBegin\n" TRI, &wz);
    assert_int_equal(s->settings.sampler, CST_SAMPLER_ZSOBOL);
    assert_int_equal(s->settings.spp, 64);
    assert_true(find_warning(&wz, CST_WARN_APPROXIMATED, "Sampler \"zsobol\"") >= 0);
    cst_scene_destroy(s);
    /* No Sampler directive: pbrt-v4's default, zsobol, which is caustic's default too. */
    Warnings wn = {0};
    s = expect_ok("WorldBegin\n" TRI, &wn);
    assert_int_equal(s->settings.sampler, CST_SAMPLER_DEFAULT);
    CstRenderSettings resolved;
    cst_render_settings_resolve(s, NULL, &resolved);
    assert_int_equal(resolved.sampler, CST_SAMPLER_ZSOBOL);
    cst_scene_destroy(s);
    /* The sensor's imaging ratio (shutterclose - shutteropen) iso / 100, as exposure stops:
     * 0.5 * 400 / 100 = 2 is one stop, whichever of Film and Camera comes first; another
     * sensor is a located approximation; white balance a render setting (film/sensor.h). */
    Warnings w2 = {0};
    s = expect_ok("Film \"rgb\" \"float iso\" 400 \"string sensor\" \"nikon_d850\" \"float whitebalance\" 5000\n"
                  "LookAt 0 0 -5  0 0 0  0 1 0\n"
                  "Camera \"perspective\" \"float shutteropen\" 0.25 \"float shutterclose\" 0.75\n"
                  "WorldBegin\n" TRI, &w2);
    assert_true(s->settings.exposure_set && fabs(s->settings.exposure - 1.0) < 1e-6);
    assert_true(find_warning(&w2, CST_WARN_APPROXIMATED, "approximated by cie1931") >= 0);
    assert_true(find_warning(&w2, CST_WARN_UNSUPPORTED, "whitebalance") < 0);
    assert_true(s->settings.white_balance == 5000.0);
    cst_scene_destroy(s);
    expect_error("Film \"rgb\" \"float whitebalance\" -5\nWorldBegin\n" TRI, CST_ERR_INVALID_ARG, "Film \"rgb\"", 0,
                 "whitebalance -5; expected a colour temperature");
    s = expect_ok("LookAt 0 0 -5  0 0 0  0 1 0\n"
                  "Camera \"perspective\" \"float shutterclose\" 0.5\n"
                  "Film \"rgb\" \"float iso\" 400\n"
                  "WorldBegin\n" TRI, NULL);
    assert_true(s->settings.exposure_set && fabs(s->settings.exposure - 1.0) < 1e-6);
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
    /* RGBFilm's maxcomponentvalue: the film's clamp, without a warning; <= 0 is an error */
    memset(&w, 0, sizeof w);
    s = expect_ok("Film \"rgb\" \"float maxcomponentvalue\" 10\nWorldBegin\n" TRI, &w);
    assert_true(s->settings.max_component == 10.0);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "maxcomponentvalue") < 0);
    cst_scene_destroy(s);
    expect_error("Film \"rgb\" \"float maxcomponentvalue\" 0\nWorldBegin\n" TRI, CST_ERR_INVALID_ARG, "Film", 0,
                 "maxcomponentvalue 0; expected a positive number");
    /* pbrt-v4's "regularize": the path tracers' option, approximated (off) for the others */
    memset(&w, 0, sizeof w);
    s = expect_ok("Integrator \"volpath\" \"bool regularize\" true\nWorldBegin\n" TRI, &w);
    assert_int_equal(s->settings.regularize, 1);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "regularize") < 0);
    cst_scene_destroy(s);
    memset(&w, 0, sizeof w);
    s = expect_ok("Integrator \"bdpt\" \"bool regularize\" true\nWorldBegin\n" TRI, &w);
    assert_true(find_warning(&w, CST_WARN_APPROXIMATED, "\"regularize\" is done by caustic's path tracers only") >= 0);
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
    st.color_mode = CST_COLOR_RGB; /* pbrt scenes default to spectral: compare like with like */
    st.sampler = CST_SAMPLER_ZSOBOL; /* and a pbrt Sampler directive against JSON's default */
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
    CstLoadOptions opt = {.warning = collect, .warning_user = &w};
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
    assert_int_equal(a.sampler, CST_SAMPLER_ZSOBOL); /* JSON: the default; the pbrt file's own */
    assert_int_equal(b.sampler, CST_SAMPLER_INDEPENDENT);
    assert_int_equal(a.color_mode, CST_COLOR_RGB); /* JSON: RGB by default, pbrt: spectral */
    assert_int_equal(b.color_mode, CST_COLOR_SPECTRAL);
    assert_string_equal(cst_scene_output_path(json), cst_scene_output_path(pbrt));
    /* pbrt scenes sample triangle lights by solid angle (pbrt-v4's Triangle::Sample), JSON
     * scenes by area unless they ask: the same choice for the comparison */
    assert_int_equal(cst_scene_set_light_sampling(json, "solid_angle", &err), CST_OK);
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
    write_text(CST_BINARY_DIR "/pbrt_env_sphere.json", json_text);
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
        cmocka_unit_test(test_include_splices_tokens),
        cmocka_unit_test(test_duplicate_parameter),
        cmocka_unit_test(test_projective_transform),
        cmocka_unit_test(test_motion_warnings),
        cmocka_unit_test(test_parameter_types),
        cmocka_unit_test(test_colour_conversions),
        cmocka_unit_test(test_camera_and_options),
        cmocka_unit_test(test_orthographic_camera),
        cmocka_unit_test(test_max_primitives),
        cmocka_unit_test(test_cornell_pbrt_equals_json),
        cmocka_unit_test(test_env_sphere_pbrt_equals_json),
        cmocka_unit_test(test_cornell_handedness),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
