/* The pbrt-v4 scene loader: directives, the graphics state, typed parameter lists, and
 * their mapping onto caustic's Scene through the scene_add_* builder. What is supported,
 * approximated or skipped is tabled in docs/pbrt-compat.md; everything approximated or
 * skipped is reported through the CstLoadOptions warning callback with its location. */
#include "scene/scene_pbrt.h"

#include <errno.h>
#include <float.h>
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
#include "scene/mesh_import.h"
#include "scene/pbrt_tokenizer.h"
#include "scene/scene.h"

/* Nesting of Include/Import: deep enough for any real scene, and stops a file including
 * itself. */
#define PBRT_MAX_INCLUDE_DEPTH 16
/* Same bound on coordinates as the JSON loader (scene_json.c): squared distances of
 * coordinates within 1e18 stay finite in float. */
#define PBRT_MAX_LENGTH 1e18
/* The scene indexes triangles with int, three indices each. */
#define PBRT_MAX_TRIANGLES (INT_MAX / 3 - 1)
#define PBRT_MAX_FILM_SIZE 65536
/* Segments of a tessellated disk and rings/segments of a tessellated sphere. */
#define PBRT_DISK_SEGMENTS 128
#define PBRT_SPHERE_SEGMENTS 64
#define PBRT_SPHERE_RINGS 32
#define PBRT_PI 3.14159265358979323846 /* double; PBRT_PI is a float */

#define TRY(expr)                         \
    do {                                  \
        CstStatus try_st_ = (expr);       \
        if (try_st_ != CST_OK)            \
            return try_st_;               \
    } while (0)

/* ------------------------------------------------------------------ types */

typedef struct Loc {
    const char *file;
    int line, col;
} Loc;

typedef enum PType {
    PT_INTEGER, PT_FLOAT, PT_POINT2, PT_VECTOR2, PT_POINT3, PT_VECTOR3, PT_NORMAL, PT_RGB,
    PT_SPECTRUM, PT_BLACKBODY, PT_BOOL, PT_STRING, PT_TEXTURE, PT_XYZ
} PType;
static const char *const PTYPE_NAMES[] = {"integer", "float", "point2", "vector2", "point3",
                                          "vector3", "normal", "rgb", "spectrum", "blackbody",
                                          "bool", "string", "texture", "xyz"};

typedef struct Param {
    PType type;
    char *name;
    char *decl; /* "type name" as written, for messages */
    double *nums;
    int num_nums;
    char **strs; /* string, texture, named spectrum; bools are stored as 0/1 in nums */
    int num_strs;
    Loc loc;
    int used;
} Param;

typedef struct Params {
    Param *v;
    int n, cap;
} Params;

/* A transform with its inverse composed alongside (as pbrt keeps both): the camera needs
 * world-from-camera, and inverting the product afresh would round what LookAt gives
 * exactly. */
typedef struct Xf {
    Transform m, inv;
    int inv_ok;
} Xf;

typedef struct AreaLight {
    int active;
    Color L;       /* linear sRGB radiance before scale */
    float scale;
    float power; /* > 0: radiant power per primitive, as pbrt-v4 normalises it */
    int two_sided;
} AreaLight;

typedef struct GState {
    Xf ctm;
    int reverse;
    int material; /* index into Loader.mats */
    AreaLight area;
    int transform_only; /* pushed by TransformBegin (pbrt-v3): pops only the CTM */
    Loc loc;            /* of the Begin, for messages */
} GState;

typedef struct MatEntry {
    char *name; /* NULL for anonymous Material directives */
    Material m;
    int scene_id; /* added to the scene on first use, -1 before */
} MatEntry;

typedef struct TexEntry {
    char *name;
    int is_float; /* pbrt keeps float and spectrum textures in two name spaces */
    int id;       /* the scene's texture; float textures hold the value in all three channels */
    Color value;    /* its average, for parameters caustic cannot texture */
    /* Derived scene textures made on first use and shared by every material that uses
     * them (an image is copied once): clamped to 1 as a reflectance; as caustic's
     * roughness without and with pbrt's remapping. -1 until made. */
    int clamped, rough[2];
} TexEntry;

typedef struct NamedXf {
    char *name;
    Xf xf;
} NamedXf;

/* Geometry in object space, with the transform that places it. Shapes inside
 * ObjectBegin/End are kept in this form and placed again by each ObjectInstance. */
typedef struct ShapeGeom {
    int is_sphere;
    float radius;  /* spheres */
    Vec3 *p;       /* meshes: positions, optional unit normals and uvs, 3 indices a triangle */
    Vec3 *n;
    Vec2 *uv;
    int nv;
    int *idx;
    int nt;
} ShapeGeom;

typedef struct ObjShape {
    ShapeGeom g;
    Xf xf;
    int reverse;
    int material;
    Loc loc;
} ObjShape;

typedef struct Object {
    char *name;
    ObjShape *shapes;
    int n, cap;
    Loc loc;
    int proto; /* the scene's instanced object, made at the first ObjectInstance; -1 before */
} Object;

typedef struct CamRec {
    int set;
    Xf ctm; /* camera-from-world */
    float fov;
    double screen[4];
    int has_screen;
    float frame;
    int has_frame;
    float lens_radius, focal_distance;
    int ortho; /* Camera "orthographic" */
    Loc loc;
} CamRec;

typedef struct Lexer {
    PbrtTokenizer tz;
    PbrtToken peek;
    int has_peek;
} Lexer;

/* A directive with a quoted type name and a parameter list (Film "rgb" ..., Material
 * "diffuse" ...), as read before its handler runs. */
typedef struct NamedCall {
    const char *dname; /* the directive, "Film" */
    const char *type;  /* its type name, "rgb" */
    Params ps;
    Loc loc;           /* of the directive */
    Loc tl;            /* of the type name */
    char d[128];       /* "Film \"rgb\"": the prefix of its messages */
} NamedCall;

typedef struct Loader {
    Scene *scene;
    CstError *err;
    CstLoadOptions opt;
    char *base_dir; /* with trailing '/', or "" */
    char **files;   /* every file name seen; Locs point into these */
    int num_files, cap_files;
    int depth;
    GState gs;
    GState *stack;
    int num_stack, cap_stack;
    MatEntry *mats;
    int num_mats, cap_mats;
    TexEntry *texs;
    int num_texs, cap_texs;
    NamedXf *coords;
    int num_coords, cap_coords;
    Object *objs;
    int num_objs, cap_objs;
    int cur_obj; /* -1 outside ObjectBegin/End */
    int in_world;
    int active_start; /* ActiveTransform includes StartTime: transforms apply */
    CamRec cam;
    int env_set; /* an infinite light has made the scene's environment */
    int num_instances_expanded; /* instances whose spheres were copied */
    Loc end; /* end of the main file, for errors about the whole scene */
} Loader;

/* ------------------------------------------------------------------ small helpers */

static int grow(void **arr, int *cap, int need, size_t size)
{
    if (need <= *cap)
        return 1;
    if (need > INT_MAX / 2)
        return 0;
    int c = *cap ? *cap : 8;
    while (c < need)
        c *= 2;
    void *p = realloc(*arr, (size_t)c * size);
    if (!p)
        return 0;
    *arr = p;
    *cap = c;
    return 1;
}
#define GROW(arr, cap, need) grow((void **)&(arr), &(cap), (need), sizeof *(arr))

static char *dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* A name from the file, printable and short enough to quote. */
static const char *clip(const char *s, char buf[72])
{
    size_t i = 0;
    for (; s[i] && i < 60; i++)
        buf[i] = ((unsigned char)s[i] < 0x20 || s[i] == 0x7f) ? '?' : s[i];
    buf[i] = '\0';
    if (s[i])
        memcpy(buf + i, "...", 4);
    return buf;
}

static CstStatus fail_at(Loader *ld, CstStatus st, Loc loc, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static CstStatus fail_at(Loader *ld, CstStatus st, Loc loc, const char *fmt, ...)
{
    char what[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return cst_fail(ld->err, st, "%.200s:%d:%d: %s", loc.file, loc.line, loc.col, what);
}

static CstStatus oom(Loader *ld) { return cst_fail(ld->err, CST_ERR_OOM, "out of memory loading the pbrt scene"); }

static void warn_at(Loader *ld, CstWarningCode code, Loc loc, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));
static void warn_at(Loader *ld, CstWarningCode code, Loc loc, const char *fmt, ...)
{
    if (!ld->opt.warning)
        return;
    char what[800], msg[1100];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(msg, sizeof msg, "%.200s:%d:%d: %s", loc.file, loc.line, loc.col, what);
    ld->opt.warning(ld->opt.warning_user, code, msg);
}

static Loc tok_loc(const Lexer *lx, const PbrtToken *t)
{
    Loc l = {lx->tz.name, t->line, t->column};
    return l;
}

static int tok_is(const PbrtToken *t, const char *word)
{
    size_t n = strlen(word);
    return t->len == n && memcmp(t->text, word, n) == 0;
}

/* ------------------------------------------------------------------ lexer with one token of lookahead */

static CstStatus lex_peek(Loader *ld, Lexer *lx, PbrtToken *t)
{
    if (!lx->has_peek) {
        TRY(pbrt_next_token(&lx->tz, &lx->peek, ld->err));
        lx->has_peek = 1;
    }
    *t = lx->peek;
    return CST_OK;
}

static CstStatus lex_next(Loader *ld, Lexer *lx, PbrtToken *t)
{
    TRY(lex_peek(ld, lx, t));
    lx->has_peek = 0;
    return CST_OK;
}

static CstStatus expect_string(Loader *ld, Lexer *lx, const char *directive, const char *what,
                               char **out, Loc *loc)
{
    PbrtToken t;
    TRY(lex_next(ld, lx, &t));
    if (loc)
        *loc = tok_loc(lx, &t);
    if (t.kind != PBRT_TOK_STRING) {
        char got[96];
        pbrt_token_describe(&t, got, sizeof got);
        return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t), "%s: got %s; expected %s, a quoted string",
                       directive, got, what);
    }
    *out = pbrt_token_string(&t);
    return *out ? CST_OK : oom(ld);
}

static CstStatus expect_numbers(Loader *ld, Lexer *lx, const char *directive, int n, double *out)
{
    for (int i = 0; i < n; i++) {
        PbrtToken t;
        TRY(lex_next(ld, lx, &t));
        if (t.kind != PBRT_TOK_NUMBER) {
            char got[96];
            pbrt_token_describe(&t, got, sizeof got);
            return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t),
                           "%s: got %s; expected %d numbers (%d given)", directive, got, n, i);
        }
        out[i] = t.number;
    }
    return CST_OK;
}

/* n numbers in brackets; pbrt-v3 files sometimes leave the brackets out. */
static CstStatus expect_number_array(Loader *ld, Lexer *lx, const char *directive, int n, double *out)
{
    PbrtToken t;
    TRY(lex_peek(ld, lx, &t));
    if (t.kind != PBRT_TOK_LBRACKET)
        return expect_numbers(ld, lx, directive, n, out);
    Loc open = tok_loc(lx, &t);
    TRY(lex_next(ld, lx, &t));
    TRY(expect_numbers(ld, lx, directive, n, out));
    TRY(lex_next(ld, lx, &t));
    if (t.kind != PBRT_TOK_RBRACKET) {
        char got[96];
        pbrt_token_describe(&t, got, sizeof got);
        return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t),
                       "%s: got %s; expected ']' closing the '[' at %d:%d after %d numbers",
                       directive, got, open.line, open.col, n);
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ parameter lists */

static void params_free(Params *ps)
{
    for (int i = 0; i < ps->n; i++) {
        Param *p = &ps->v[i];
        free(p->name);
        free(p->decl);
        free(p->nums);
        for (int k = 0; k < p->num_strs; k++)
            free(p->strs[k]);
        free(p->strs);
    }
    free(ps->v);
    memset(ps, 0, sizeof *ps);
}

static int ptype_from_name(const char *s, PType *out)
{
    for (int i = 0; i < (int)(sizeof PTYPE_NAMES / sizeof PTYPE_NAMES[0]); i++)
        if (strcmp(s, PTYPE_NAMES[i]) == 0) {
            *out = (PType)i;
            return 1;
        }
    /* pbrt-v3 spellings */
    static const struct { const char *name; PType t; } alias[] = {
        {"point", PT_POINT3}, {"vector", PT_VECTOR3}, {"normal3", PT_NORMAL}, {"color", PT_RGB}};
    for (int i = 0; i < 4; i++)
        if (strcmp(s, alias[i].name) == 0) {
            *out = alias[i].t;
            return 1;
        }
    return 0;
}

/* Splits "type name" (any whitespace around and between) into its two words. */
static int split_decl(const char *d, char *type, size_t type_cap, char *name, size_t name_cap)
{
    const char *p = d;
    size_t n;
    while (*p == ' ' || *p == '\t') p++;
    for (n = 0; p[n] && p[n] != ' ' && p[n] != '\t'; n++) {}
    if (n == 0 || n >= type_cap) return 0;
    memcpy(type, p, n);
    type[n] = '\0';
    p += n;
    while (*p == ' ' || *p == '\t') p++;
    for (n = 0; p[n] && p[n] != ' ' && p[n] != '\t'; n++) {}
    if (n == 0 || n >= name_cap) return 0;
    memcpy(name, p, n);
    name[n] = '\0';
    p += n;
    while (*p == ' ' || *p == '\t') p++;
    return *p == '\0';
}

static CstStatus param_add_num(Loader *ld, Param *p, int *cap, double v)
{
    if (!grow((void **)&p->nums, cap, p->num_nums + 1, sizeof *p->nums))
        return oom(ld);
    p->nums[p->num_nums++] = v;
    return CST_OK;
}

static CstStatus param_add_str(Loader *ld, Param *p, int *cap, const PbrtToken *t)
{
    if (!grow((void **)&p->strs, cap, p->num_strs + 1, sizeof *p->strs))
        return oom(ld);
    char *s = pbrt_token_string(t);
    if (!s)
        return oom(ld);
    p->strs[p->num_strs++] = s;
    return CST_OK;
}

/* One value token into p: numbers, strings, and the bare words true/false for bools. */
static CstStatus param_value(Loader *ld, Param *p, int *cap_n, int *cap_s, const PbrtToken *t,
                             int *ok)
{
    *ok = 1;
    if (t->kind == PBRT_TOK_NUMBER)
        return param_add_num(ld, p, cap_n, t->number);
    if (t->kind == PBRT_TOK_STRING)
        return param_add_str(ld, p, cap_s, t);
    if (t->kind == PBRT_TOK_WORD && (tok_is(t, "true") || tok_is(t, "false")) && p->type == PT_BOOL)
        return param_add_str(ld, p, cap_s, t);
    *ok = 0;
    return CST_OK;
}

/* Checks values against the declared type once the list is complete. */
static CstStatus param_check(Loader *ld, Param *p)
{
    char nm[72];
    if (p->num_nums == 0 && p->num_strs == 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has no values; expected at least one",
                       clip(p->decl, nm));
    if (p->num_nums > 0 && p->num_strs > 0)
        return fail_at(ld, CST_ERR_PARSE, p->loc,
                       "parameter \"%s\" mixes numbers and strings; expected values of one kind",
                       clip(p->decl, nm));
    int n = p->num_nums;
    switch (p->type) {
    case PT_STRING:
    case PT_TEXTURE:
        if (p->num_strs == 0)
            return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has numbers; expected quoted strings",
                           clip(p->decl, nm));
        return CST_OK;
    case PT_BOOL:
        if (p->num_strs == 0)
            return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "parameter \"%s\" has numbers; expected true or false", clip(p->decl, nm));
        for (int i = 0; i < p->num_strs; i++) {
            int v = strcmp(p->strs[i], "true") == 0 ? 1 : (strcmp(p->strs[i], "false") == 0 ? 0 : -1);
            char val[72];
            if (v < 0)
                return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                               "parameter \"%s\" has the value \"%s\"; expected true or false",
                               clip(p->decl, nm), clip(p->strs[i], val));
            int cap = p->num_nums;
            TRY(param_add_num(ld, p, &cap, v));
        }
        return CST_OK;
    case PT_SPECTRUM:
        if (p->num_strs > 1)
            return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "parameter \"%s\" has %d strings; expected one spectrum name or "
                           "(wavelength, value) pairs", clip(p->decl, nm), p->num_strs);
        if (p->num_strs == 0 && (n % 2 != 0))
            return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "parameter \"%s\" has %d numbers; expected (wavelength, value) pairs",
                           clip(p->decl, nm), n);
        return CST_OK;
    default: break;
    }
    if (p->num_strs > 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has strings; expected numbers",
                       clip(p->decl, nm));
    int per = 1, exact = 0;
    switch (p->type) {
    case PT_POINT2: case PT_VECTOR2: per = 2; break;
    case PT_POINT3: case PT_VECTOR3: case PT_NORMAL: per = 3; break;
    case PT_RGB: case PT_XYZ: exact = 3; break;
    case PT_BLACKBODY: if (n > 2) exact = 1; break; /* v4: kelvin; v3: kelvin, scale */
    default: break;
    }
    if ((exact && n != exact) || n % per != 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has %d numbers; expected %s %d",
                       clip(p->decl, nm), n, exact ? "exactly" : "a multiple of", exact ? exact : per);
    if (p->type == PT_INTEGER)
        for (int i = 0; i < n; i++)
            if (p->nums[i] != floor(p->nums[i]) || fabs(p->nums[i]) > (double)INT_MAX)
                return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                               "parameter \"%s\": value %g is not an integer; expected whole "
                               "numbers within +-%d", clip(p->decl, nm), p->nums[i], INT_MAX);
    return CST_OK;
}

/* Reads "type name" value pairs while the next token is a string. */
static CstStatus parse_params(Loader *ld, Lexer *lx, Params *ps)
{
    for (;;) {
        PbrtToken t;
        TRY(lex_peek(ld, lx, &t));
        if (t.kind != PBRT_TOK_STRING)
            return CST_OK;
        TRY(lex_next(ld, lx, &t));
        Loc loc = tok_loc(lx, &t);
        char *decl = pbrt_token_string(&t);
        if (!decl)
            return oom(ld);
        char tname[64], pname[256], nm[72];
        PType type;
        if (!split_decl(decl, tname, sizeof tname, pname, sizeof pname)) {
            CstStatus st = fail_at(ld, CST_ERR_PARSE, loc,
                                   "\"%s\" is not a parameter declaration; expected \"type name\", "
                                   "as in \"float fov\"", clip(decl, nm));
            free(decl);
            return st;
        }
        if (!ptype_from_name(tname, &type)) {
            CstStatus st = fail_at(ld, CST_ERR_PARSE, loc,
                                   "unknown parameter type \"%s\"; expected one of: integer, "
                                   "float, point2, vector2, point3, vector3, normal, rgb, "
                                   "spectrum, blackbody, bool, string, texture", clip(tname, nm));
            free(decl);
            return st;
        }
        for (int i = 0; i < ps->n; i++)
            if (strcmp(ps->v[i].name, pname) == 0) {
                CstStatus st = fail_at(ld, CST_ERR_INVALID_ARG, loc,
                                       "parameter \"%s\" given twice (first at line %d); expected "
                                       "each parameter once", clip(pname, nm), ps->v[i].loc.line);
                free(decl);
                return st;
            }
        if (!GROW(ps->v, ps->cap, ps->n + 1)) {
            free(decl);
            return oom(ld);
        }
        Param *p = &ps->v[ps->n++];
        memset(p, 0, sizeof *p);
        p->type = type;
        p->decl = decl;
        p->loc = loc;
        p->name = dup_str(pname);
        if (!p->name)
            return oom(ld);
        int cap_n = 0, cap_s = 0, ok = 0;
        TRY(lex_next(ld, lx, &t));
        if (t.kind == PBRT_TOK_LBRACKET) {
            Loc open = tok_loc(lx, &t);
            for (;;) {
                TRY(lex_next(ld, lx, &t));
                if (t.kind == PBRT_TOK_RBRACKET)
                    break;
                TRY(param_value(ld, p, &cap_n, &cap_s, &t, &ok));
                if (!ok) {
                    char got[96];
                    pbrt_token_describe(&t, got, sizeof got);
                    if (t.kind == PBRT_TOK_EOF || t.kind == PBRT_TOK_WORD)
                        return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t),
                                       "got %s inside the values of \"%s\"; expected ']' to "
                                       "close the '[' at %d:%d", got, clip(decl, nm), open.line,
                                       open.col);
                    return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t),
                                   "got %s inside the values of \"%s\"; expected numbers, "
                                   "strings or ']'", got, clip(decl, nm));
                }
            }
        } else {
            TRY(param_value(ld, p, &cap_n, &cap_s, &t, &ok));
            if (!ok) {
                char got[96];
                pbrt_token_describe(&t, got, sizeof got);
                return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &t),
                               "got %s after \"%s\"; expected its value: a number, a string "
                               "or '[' values ']'", got, clip(decl, nm));
            }
        }
        TRY(param_check(ld, p));
    }
}

/* Warns about every parameter no getter asked for. */
static void params_warn_unused(Loader *ld, const Params *ps, const char *directive)
{
    for (int i = 0; i < ps->n; i++)
        if (!ps->v[i].used) {
            char nm[72];
            warn_at(ld, CST_WARN_PARAMETER_IGNORED, ps->v[i].loc,
                    "%s: parameter \"%s\" is not supported; ignored", directive,
                    clip(ps->v[i].decl, nm));
        }
}

static void params_mark_all_used(Params *ps)
{
    for (int i = 0; i < ps->n; i++)
        ps->v[i].used = 1;
}

static Param *find_param(Params *ps, const char *name)
{
    for (int i = 0; i < ps->n; i++)
        if (strcmp(ps->v[i].name, name) == 0)
            return &ps->v[i];
    return NULL;
}

/* The parameter called name if it has one of the allowed types (a mask of 1 << PType);
 * a parameter of that name and another type is an error (pbrt would leave it unused). */
static CstStatus lookup(Loader *ld, Params *ps, const char *directive, const char *name,
                        unsigned allowed, const char *expected, Param **out)
{
    *out = NULL;
    Param *p = find_param(ps, name);
    if (!p)
        return CST_OK;
    p->used = 1;
    if (!(allowed & (1u << p->type))) {
        char nm[72];
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                       "%s: parameter \"%s\" has type %s; expected %s", directive,
                       clip(p->decl, nm), PTYPE_NAMES[p->type], expected);
    }
    *out = p;
    return CST_OK;
}

static CstStatus one_value(Loader *ld, const Param *p, const char *directive)
{
    int n = p->num_strs ? p->num_strs : p->num_nums;
    if (p->type == PT_BOOL)
        n = p->num_strs;
    char nm[72];
    if (n != 1)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: parameter \"%s\" has %d values; expected one",
                       directive, clip(p->decl, nm), n);
    return CST_OK;
}

#define M(t) (1u << (t))

static CstStatus get_float(Loader *ld, Params *ps, const char *d, const char *name, float def,
                           float *out, int *found)
{
    Param *p;
    *out = def;
    if (found) *found = 0;
    TRY(lookup(ld, ps, d, name, M(PT_FLOAT), "float", &p));
    if (!p) return CST_OK;
    TRY(one_value(ld, p, d));
    if (!(fabs(p->nums[0]) <= (double)FLT_MAX)) {
        char nm[72];
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" %g does not fit a 32-bit float",
                       d, clip(p->decl, nm), p->nums[0]);
    }
    *out = (float)p->nums[0];
    if (found) *found = 1;
    return CST_OK;
}

static CstStatus get_int(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out)
{
    Param *p;
    *out = def;
    TRY(lookup(ld, ps, d, name, M(PT_INTEGER), "integer", &p));
    if (!p) return CST_OK;
    TRY(one_value(ld, p, d));
    *out = (int)p->nums[0];
    return CST_OK;
}

static CstStatus get_bool(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out)
{
    Param *p;
    *out = def;
    TRY(lookup(ld, ps, d, name, M(PT_BOOL), "bool", &p));
    if (!p) return CST_OK;
    TRY(one_value(ld, p, d));
    *out = p->nums[0] != 0.0;
    return CST_OK;
}

static CstStatus get_string(Loader *ld, Params *ps, const char *d, const char *name,
                            const char **out, Loc *loc)
{
    Param *p;
    *out = NULL;
    TRY(lookup(ld, ps, d, name, M(PT_STRING), "string", &p));
    if (!p) return CST_OK;
    TRY(one_value(ld, p, d));
    *out = p->strs[0];
    if (loc) *loc = p->loc;
    return CST_OK;
}

/* ------------------------------------------------------------------ colour */

/* CIE 1931 colour matching functions by the multi-lobe Gaussian fit of Wyman, Sloan and
 * Shirley, "Simple Analytic Approximations to the CIE XYZ Color Matching Functions"
 * (JCGT 2013), eq. 2: close enough for turning a spectrum into three numbers. */
static double cmf_g(double x, double mu, double s1, double s2)
{
    double t = (x - mu) / (x < mu ? s1 : s2);
    return exp(-0.5 * t * t);
}

static void cmf(double l, double xyz[3])
{
    xyz[0] = 1.056 * cmf_g(l, 599.8, 37.9, 31.0) + 0.362 * cmf_g(l, 442.0, 16.0, 26.7) -
             0.065 * cmf_g(l, 501.1, 20.4, 26.2);
    xyz[1] = 0.821 * cmf_g(l, 568.8, 46.9, 40.5) + 0.286 * cmf_g(l, 530.9, 16.3, 31.1);
    xyz[2] = 1.217 * cmf_g(l, 437.0, 11.8, 36.0) + 0.681 * cmf_g(l, 459.0, 26.0, 13.8);
}

/* XYZ to linear sRGB (IEC 61966-2-1, D65 white). */
static void xyz_to_rgb(const double x[3], double out[3])
{
    out[0] = 3.2404542 * x[0] - 1.5371385 * x[1] - 0.4985314 * x[2];
    out[1] = -0.9692660 * x[0] + 1.8760108 * x[1] + 0.0415560 * x[2];
    out[2] = 0.0556434 * x[0] - 0.2040259 * x[1] + 1.0572252 * x[2];
}

static Color rgb_from_d(const double c[3]) { return color_rgb((float)c[0], (float)c[1], (float)c[2]); }

Color pbrt_blackbody_rgb(double kelvin)
{
    if (!(kelvin > 0.0))
        return color_s(0.0f);
    /* Planck's law up to a constant factor, which the luminance normalisation removes. */
    const double c2 = 1.4387769e7; /* h c / k_B in nm K */
    double xyz[3] = {0, 0, 0};
    for (double l = 360.0; l <= 830.0; l += 1.0) {
        double b = 1.0 / (pow(l * 1e-3, 5.0) * (exp(c2 / (l * kelvin)) - 1.0)), w[3];
        if (!isfinite(b)) continue;
        cmf(l, w);
        for (int k = 0; k < 3; k++) xyz[k] += b * w[k];
    }
    if (!(xyz[1] > 0.0))
        return color_s(0.0f);
    double y = xyz[1];
    for (int k = 0; k < 3; k++) xyz[k] /= y;
    double c[3];
    xyz_to_rgb(xyz, c);
    for (int k = 0; k < 3; k++) c[k] = c[k] > 0.0 ? c[k] : 0.0; /* outside the gamut: clip */
    return rgb_from_d(c);
}

static double spectrum_at(const double *pairs, int n, double l)
{
    if (n == 0 || l < pairs[0] || l > pairs[2 * (n - 1)]) return 0.0;
    for (int i = 0; i + 1 < n; i++) {
        double l0 = pairs[2 * i], l1 = pairs[2 * i + 2];
        if (l >= l0 && l <= l1)
            return l1 > l0 ? pairs[2 * i + 1] + (pairs[2 * i + 3] - pairs[2 * i + 1]) * (l - l0) / (l1 - l0)
                           : pairs[2 * i + 1];
    }
    return pairs[2 * n - 1];
}

Color pbrt_spectrum_rgb(const double *pairs, int num_pairs, bool illuminant)
{
    double xyz[3] = {0, 0, 0}, white[3] = {0, 0, 0};
    if (num_pairs == 1) /* a single sample: a constant spectrum */
        return illuminant ? color_s(1.0f) : color_s((float)pairs[1]);
    for (double l = 360.0; l <= 830.0; l += 1.0) {
        double w[3], s = spectrum_at(pairs, num_pairs, l);
        cmf(l, w);
        for (int k = 0; k < 3; k++) {
            xyz[k] += s * w[k];
            white[k] += w[k];
        }
    }
    double c[3], cw[3];
    if (illuminant) {
        double y = xyz[1];
        if (!(y > 0.0)) return color_s(0.0f);
        for (int k = 0; k < 3; k++) xyz[k] /= y;
        xyz_to_rgb(xyz, c);
    } else {
        /* Per-channel normalisation by the flat spectrum: a constant reflectance c maps to
         * exactly (c, c, c) despite the equal-energy white not being sRGB's D65. */
        xyz_to_rgb(xyz, c);
        xyz_to_rgb(white, cw);
        for (int k = 0; k < 3; k++) c[k] /= cw[k];
    }
    for (int k = 0; k < 3; k++) c[k] = c[k] > 0.0 ? c[k] : 0.0;
    return rgb_from_d(c);
}

/* pbrt-v4's named metals "metal-<X>-eta" / "-k". Gold, silver, copper and aluminium are
 * caustic's cited presets (material_metal, materials/material.c). The other three are RGB
 * readings at about 650, 550 and 450 nm of the sampled data pbrt ships (CuZn: brass; MgO
 * and TiO2 are dielectrics, k = 0; MgO's n agrees with Stephens & Malitson, J. Res. NBS
 * 49, 249 (1952), n = 1.7355 at 589 nm); get_spectrum reports them as approximated. */
static const struct { const char *name, *preset; float eta[3], k[3]; } PBRT_METALS[] = {
    {"Ag", "silver", {0}, {0}},
    {"Al", "aluminium", {0}, {0}},
    {"Au", "gold", {0}, {0}},
    {"Cu", "copper", {0}, {0}},
    {"CuZn", NULL, {0.444f, 0.527f, 1.094f}, {3.695f, 2.765f, 1.829f}},
    {"MgO", NULL, {1.732f, 1.738f, 1.750f}, {0.0f, 0.0f, 0.0f}},
    {"TiO2", NULL, {2.58f, 2.66f, 2.87f}, {0.0f, 0.0f, 0.0f}},
};

/* The table entry of a named metal spectrum, with is_k set for "-k"; -1 if unknown. */
static int named_metal_index(const char *name, int *is_k)
{
    if (strncmp(name, "metal-", 6) != 0) return -1;
    const char *m = name + 6;
    for (int i = 0; i < (int)(sizeof PBRT_METALS / sizeof PBRT_METALS[0]); i++) {
        size_t n = strlen(PBRT_METALS[i].name);
        if (strncmp(m, PBRT_METALS[i].name, n) == 0 && m[n] == '-') {
            if (strcmp(m + n, "-eta") == 0) *is_k = 0;
            else if (strcmp(m + n, "-k") == 0) *is_k = 1;
            else return -1;
            return i;
        }
    }
    return -1;
}

bool pbrt_named_metal(const char *name, Color *out)
{
    int is_k = 0, i = named_metal_index(name, &is_k);
    if (i < 0) return false;
    if (PBRT_METALS[i].preset) {
        Color eta, k;
        material_metal(PBRT_METALS[i].preset, &eta, &k);
        *out = is_k ? k : eta;
        return true;
    }
    const float *v = is_k ? PBRT_METALS[i].k : PBRT_METALS[i].eta;
    *out = color_rgb(v[0], v[1], v[2]);
    return true;
}

static float r0_channel(float n, float k)
{
    return ((n - 1.0f) * (n - 1.0f) + k * k) / ((n + 1.0f) * (n + 1.0f) + k * k);
}

Color pbrt_conductor_r0(Color eta, Color k)
{
    return color_rgb(r0_channel(eta.c[0], k.c[0]), r0_channel(eta.c[1], k.c[1]), r0_channel(eta.c[2], k.c[2]));
}

/* n_d (587.6 nm) of pbrt-v4's named glasses (Schott catalogue). */
static int named_glass(const char *name, float *eta)
{
    static const struct { const char *name; float eta; } g[] = {
        {"glass-BK7", 1.5168f}, {"glass-BAF10", 1.6700f}, {"glass-FK51A", 1.4866f},
        {"glass-LASF9", 1.8503f}, {"glass-F5", 1.6034f}, {"glass-F10", 1.6200f},
        {"glass-F11", 1.6259f}, {"glass-SF5", 1.6727f}, {"glass-SF10", 1.7283f},
        {"glass-SF11", 1.7847f}};
    for (size_t i = 0; i < sizeof g / sizeof g[0]; i++)
        if (strcmp(name, g[i].name) == 0) {
            *eta = g[i].eta;
            return 1;
        }
    return 0;
}

typedef enum SpecKind { SPEC_REFLECTANCE, SPEC_UNBOUNDED, SPEC_ILLUMINANT } SpecKind;

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
    TRY(one_value(ld, p, d));
    int i = find_texture(ld, p->strs[0], is_float);
    if (i >= 0) {
        *out = i;
        return CST_OK;
    }
    if (find_texture(ld, p->strs[0], !is_float) >= 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                       "%s: texture \"%s\" is a %s texture; expected a %s texture here", d,
                       clip(p->strs[0], nm), is_float ? "spectrum" : "float", is_float ? "float" : "spectrum");
    return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                   "%s: %s texture \"%s\" is not defined; expected the name of a Texture "
                   "declared earlier as \"%s\"", d, is_float ? "float" : "spectrum",
                   clip(p->strs[0], nm), is_float ? "float" : "spectrum");
}

static int texture_is_constant(const Loader *ld, int entry)
{
    return ld->scene->textures[ld->texs[entry].id].type == TEXTURE_CONSTANT;
}

/* A texture where caustic takes one value: its average, with a warning unless it is constant. */
static CstStatus texture_ref(Loader *ld, const Param *p, const char *d, int is_float, Color *out)
{
    int i = 0;
    char nm[72], nm2[72];
    TRY(texture_find_ref(ld, p, d, is_float, &i));
    *out = ld->texs[i].value;
    if (!texture_is_constant(ld, i))
        warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: \"%s\" cannot be textured in caustic; "
                "texture \"%s\" is taken as its average (%g, %g, %g)", d, clip(p->decl, nm),
                clip(p->strs[0], nm2), (double)out->c[0], (double)out->c[1], (double)out->c[2]);
    return CST_OK;
}

/* A spectrum-valued parameter as linear sRGB: rgb, blackbody, spectrum (pairs or a named
 * spectrum), xyz (pbrt-v3), or with allow_tex a spectrum texture (its constant or average).
 * *found says whether the file gave it; out keeps its default otherwise. */
static CstStatus get_spectrum(Loader *ld, Params *ps, const char *d, const char *name,
                              SpecKind kind, int allow_tex, Color *out, int *found)
{
    Param *p;
    char nm[72];
    unsigned allowed = M(PT_RGB) | M(PT_SPECTRUM) | M(PT_BLACKBODY) | M(PT_XYZ) |
                       (allow_tex ? M(PT_TEXTURE) : 0u);
    if (found) *found = 0;
    TRY(lookup(ld, ps, d, name, allowed,
               allow_tex ? "rgb, spectrum, blackbody or texture" : "rgb, spectrum or blackbody", &p));
    if (!p) return CST_OK;
    Color c = *out;
    switch (p->type) {
    case PT_TEXTURE: TRY(texture_ref(ld, p, d, 0, &c)); break;
    case PT_RGB: c = color_rgb((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]); break;
    case PT_XYZ: {
        double x[3] = {p->nums[0], p->nums[1], p->nums[2]}, r[3];
        xyz_to_rgb(x, r);
        c = rgb_from_d(r);
        break;
    }
    case PT_BLACKBODY:
        c = pbrt_blackbody_rgb(p->nums[0]);
        if (p->num_nums == 2) c = color_scale(c, (float)p->nums[1]);
        break;
    case PT_SPECTRUM:
        if (p->num_strs) {
            const char *s = p->strs[0];
            float eta = 0.0f;
            int is_k = 0, mi = named_metal_index(s, &is_k);
            if (mi >= 0) {
                pbrt_named_metal(s, &c);
                if (!PBRT_METALS[mi].preset)
                    warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                            "%s: \"%s\" taken as the RGB (%g, %g, %g) of its spectrum at about "
                            "650, 550 and 450 nm", d, clip(s, nm), (double)c.c[0], (double)c.c[1], (double)c.c[2]);
            } else if (named_glass(s, &eta)) {
                c = color_s(eta);
                warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                        "%s: \"%s\" \"%s\" taken as the constant %g (n_d): no dispersion", d,
                        clip(p->decl, nm), s, (double)eta);
            } else if (strcmp(s, "stdillum-D65") == 0 || strcmp(s, "illum-D65") == 0) {
                c = color_s(1.0f); /* sRGB's white point */
            } else if (strcmp(s, "stdillum-A") == 0 || strcmp(s, "illum-A") == 0) {
                c = pbrt_blackbody_rgb(2856.0);
            } else if (strncmp(s, "stdillum-", 9) == 0 || strncmp(s, "illum-", 6) == 0) {
                c = color_s(1.0f);
                warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: illuminant \"%s\" taken as white (D65)",
                        d, clip(s, nm));
            } else {
                warn_at(ld, CST_WARN_UNSUPPORTED, p->loc,
                        "%s: spectrum \"%s\" for \"%s\" is not known (spectrum files are not read); "
                        "the default is used", d, clip(s, nm), clip(p->decl, nm));
                return CST_OK;
            }
        } else {
            for (int i = 1; i < p->num_nums / 2; i++)
                if (!(p->nums[2 * i] > p->nums[2 * i - 2]))
                    return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                                   "%s: \"%s\": wavelength %g does not increase; expected "
                                   "(wavelength, value) pairs in increasing wavelength", d,
                                   clip(p->decl, nm), p->nums[2 * i]);
            c = pbrt_spectrum_rgb(p->nums, p->num_nums / 2, kind == SPEC_ILLUMINANT);
        }
        break;
    default: break;
    }
    if (!color_is_finite(c))
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" is not finite as a 32-bit RGB",
                       d, clip(p->decl, nm));
    if (c.c[0] < 0.0f || c.c[1] < 0.0f || c.c[2] < 0.0f || (kind == SPEC_REFLECTANCE && color_max(c) > 1.0f)) {
        Color k = color_rgb(clampf(c.c[0], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX),
                    clampf(c.c[1], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX),
                    clampf(c.c[2], 0.0f, kind == SPEC_REFLECTANCE ? 1.0f : FLT_MAX));
        warn_at(ld, CST_WARN_APPROXIMATED, p->loc,
                "%s: \"%s\" (%g, %g, %g) clamped to (%g, %g, %g)%s", d, clip(p->decl, nm),
                (double)c.c[0], (double)c.c[1], (double)c.c[2], (double)k.c[0], (double)k.c[1], (double)k.c[2],
                kind == SPEC_REFLECTANCE ? ": a reflectance lies in [0, 1]" : "");
        c = k;
    }
    *out = c;
    if (found) *found = 1;
    return CST_OK;
}

/* A float parameter that may also name a float texture. */
static CstStatus get_float_tex(Loader *ld, Params *ps, const char *d, const char *name, float def,
                               float *out, int *found)
{
    Param *p;
    *out = def;
    if (found) *found = 0;
    TRY(lookup(ld, ps, d, name, M(PT_FLOAT) | M(PT_TEXTURE), "float or texture", &p));
    if (!p) return CST_OK;
    if (p->type == PT_TEXTURE) {
        Color c;
        TRY(texture_ref(ld, p, d, 1, &c));
        *out = c.c[0];
    } else {
        TRY(one_value(ld, p, d));
        *out = (float)p->nums[0];
    }
    if (!isfinite(*out)) {
        char nm[72];
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" does not fit a 32-bit float", d,
                       clip(p->decl, nm));
    }
    if (found) *found = 1;
    return CST_OK;
}

/* ------------------------------------------------------------------ transforms */

static Xf xf_identity(void)
{
    Xf x = {transform_identity(), transform_identity(), 1};
    return x;
}

static Xf xf_compose(const Xf *a, const Xf *b)
{
    Xf r;
    r.m = transform_compose(a->m, b->m);
    r.inv = transform_compose(b->inv, a->inv);
    r.inv_ok = a->inv_ok && b->inv_ok;
    return r;
}

/* From a matrix alone, inverting it. */
static Xf xf_from(Transform m)
{
    Xf r;
    r.m = m;
    r.inv_ok = transform_invert(&m, &r.inv);
    if (!r.inv_ok) r.inv = transform_identity();
    return r;
}

static Xf xf_swap(Xf x)
{
    Transform t = x.m;
    x.m = x.inv;
    x.inv = t;
    return x;
}

/* pbrt's LookAt: camera-from-world for a camera at eye looking at look, with camera x =
 * normalize(up x dir) (left-handed), y the orthogonalised up and z = dir. Built directly
 * with its inverse (world-from-camera, the frame's columns), in double. */
static int xf_look_at(const double e[3], const double l[3], const double u[3], Xf *out)
{
    double d[3] = {l[0] - e[0], l[1] - e[1], l[2] - e[2]};
    double dl = sqrt(d[0] * d[0] + d[1] * d[1] + d[2] * d[2]);
    double ul = sqrt(u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
    if (!(dl > 0.0) || !(ul > 0.0) || !isfinite(dl) || !isfinite(ul)) return 0;
    double un[3] = {u[0] / ul, u[1] / ul, u[2] / ul};
    for (int k = 0; k < 3; k++) d[k] /= dl;
    double r[3] = {un[1] * d[2] - un[2] * d[1], un[2] * d[0] - un[0] * d[2], un[0] * d[1] - un[1] * d[0]};
    double rl = sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2]);
    if (!(rl > 1e-6)) return 0;
    for (int k = 0; k < 3; k++) r[k] /= rl;
    double nu[3] = {d[1] * r[2] - d[2] * r[1], d[2] * r[0] - d[0] * r[2], d[0] * r[1] - d[1] * r[0]};
    Transform w = transform_identity(), c = transform_identity();
    for (int k = 0; k < 3; k++) {
        w.m[k][0] = (float)r[k];
        w.m[k][1] = (float)nu[k];
        w.m[k][2] = (float)d[k];
        w.m[k][3] = (float)e[k];
        c.m[0][k] = (float)r[k];
        c.m[1][k] = (float)nu[k];
        c.m[2][k] = (float)d[k];
    }
    c.m[0][3] = (float)-(r[0] * e[0] + r[1] * e[1] + r[2] * e[2]);
    c.m[1][3] = (float)-(nu[0] * e[0] + nu[1] * e[1] + nu[2] * e[2]);
    c.m[2][3] = (float)-(d[0] * e[0] + d[1] * e[1] + d[2] * e[2]);
    out->m = c;
    out->inv = w;
    out->inv_ok = 1;
    return 1;
}

static int xf_finite(const Xf *x)
{
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++)
            if (!isfinite(x->m.m[r][c])) return 0;
    return 1;
}

static CstStatus apply_ctm(Loader *ld, Xf t, Loc loc, const char *d)
{
    if (!xf_finite(&t))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the transform is not finite in 32-bit floats", d);
    if (!ld->active_start) return CST_OK; /* only the end time is affected: no motion blur */
    ld->gs.ctm = xf_compose(&ld->gs.ctm, &t);
    return CST_OK;
}

/* ------------------------------------------------------------------ directives: state */

static int find_named_xf(Loader *ld, const char *name)
{
    for (int i = 0; i < ld->num_coords; i++)
        if (strcmp(ld->coords[i].name, name) == 0) return i;
    return -1;
}

static CstStatus set_named_xf(Loader *ld, const char *name, Xf xf)
{
    int i = find_named_xf(ld, name);
    if (i < 0) {
        if (!GROW(ld->coords, ld->cap_coords, ld->num_coords + 1)) return oom(ld);
        char *n = dup_str(name);
        if (!n) return oom(ld);
        i = ld->num_coords++;
        ld->coords[i].name = n;
    }
    ld->coords[i].xf = xf;
    return CST_OK;
}

static CstStatus push_state(Loader *ld, Loc loc, int transform_only)
{
    if (!GROW(ld->stack, ld->cap_stack, ld->num_stack + 1)) return oom(ld);
    ld->gs.transform_only = transform_only;
    ld->gs.loc = loc;
    ld->stack[ld->num_stack++] = ld->gs;
    return CST_OK;
}

static CstStatus pop_state(Loader *ld, Loc loc, int transform_only, const char *d)
{
    if (ld->num_stack == 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s without a matching %s; expected %s only "
                       "after %s", d, transform_only ? "TransformBegin" : "AttributeBegin", d,
                       transform_only ? "TransformBegin" : "AttributeBegin");
    GState *top = &ld->stack[ld->num_stack - 1];
    if (top->transform_only != transform_only)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s closes the %s at line %d; expected %s",
                       d, top->transform_only ? "TransformBegin" : "AttributeBegin", top->loc.line,
                       top->transform_only ? "TransformEnd" : "AttributeEnd");
    if (transform_only) {
        ld->gs.ctm = top->ctm;
    } else {
        ld->gs = *top;
    }
    ld->num_stack--;
    return CST_OK;
}

/* A failure of a library call (mesh import, image read): keep its text, add the location. */
static CstStatus fail_wrap(Loader *ld, CstStatus st, Loc loc, const char *d)
{
    char msg[sizeof ld->err->msg];
    memcpy(msg, ld->err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    return fail_at(ld, st, loc, "%s: %.700s", d, msg);
}

/* ------------------------------------------------------------------ scene textures */

/* Adds t to the scene (which takes its image), failures located at loc. */
static CstStatus tex_add(Loader *ld, Texture *t, Loc loc, const char *d, int *id)
{
    CstStatus st = scene_add_texture(ld->scene, t, id, ld->err);
    return st ? fail_wrap(ld, st, loc, d) : CST_OK;
}

static CstStatus tex_const(Loader *ld, Color c, Loc loc, const char *d, int *id)
{
    Texture t;
    texture_constant(&t, c);
    return tex_add(ld, &t, loc, d, id);
}

/* Per-value maps that pbrt applies after its lookups, applied here to every value a
 * texture holds (constants, texels, a checkerboard's two textures). Bilinear filtering
 * commutes with the affine maps; for the others (clamps, powers) mapping texels before
 * filtering differs from pbrt only between texels across a kink. */
typedef enum TexOp {
    TEXOP_AFFINE, /* max(0, a v + b): pbrt's scale, invert and ScaleTexture */
    TEXOP_MIN1,   /* min(v, 1): the reflectance clamp of pbrt's materials */
    TEXOP_POW,    /* max(v, 0)^a.r: gamma decoding, roughness to caustic's roughness */
    TEXOP_RED     /* the first channel in all three: pbrt's float image textures */
} TexOp;

static Color texop_apply(TexOp op, Color a, Color b, Color v)
{
    switch (op) {
    case TEXOP_AFFINE:
        return color_rgb(maxf(0.0f, a.c[0] * v.c[0] + b.c[0]), maxf(0.0f, a.c[1] * v.c[1] + b.c[1]), maxf(0.0f, a.c[2] * v.c[2] + b.c[2]));
    case TEXOP_MIN1: return color_rgb(minf(v.c[0], 1.0f), minf(v.c[1], 1.0f), minf(v.c[2], 1.0f));
    case TEXOP_POW:
        return color_rgb(powf(maxf(v.c[0], 0.0f), a.c[0]), powf(maxf(v.c[1], 0.0f), a.c[0]), powf(maxf(v.c[2], 0.0f), a.c[0]));
    case TEXOP_RED: return color_s(v.c[0]);
    }
    return v;
}

/* A new scene texture: texture `id` with op applied to its values, or id itself when op
 * changes nothing. A checkerboard's textures are mapped too, each once however often it
 * is shared (nested checkerboards may share children), without recursion: children have
 * lower indices, so one downward pass marks what is reachable and one upward pass copies. */
static CstStatus tex_map(Loader *ld, int id, TexOp op, Color a, Color b, Loc loc, const char *d, int *out)
{
    *out = id;
    /* Spectrum and image values are >= 0 already (get_spectrum, texture_image), so the
     * identity's max(0, v) could only change a negative float constant: left as it is. */
    if (op == TEXOP_AFFINE && a.c[0] == 1.0f && a.c[1] == 1.0f && a.c[2] == 1.0f && color_is_black(b)) return CST_OK;
    int n = id + 1, *memo = malloc((size_t)n * sizeof *memo);
    if (!memo) return oom(ld);
    for (int i = 0; i < n; i++) memo[i] = -1;
    memo[id] = 0; /* reachable */
    for (int i = id; i >= 0; i--) {
        const Texture *t = &ld->scene->textures[i];
        if (memo[i] == 0 && t->type == TEXTURE_CHECKERBOARD) memo[t->checker.even] = memo[t->checker.odd] = 0;
    }
    CstStatus st = CST_OK;
    for (int i = 0; i < n && !st; i++) {
        if (memo[i] < 0) continue;
        Texture src = ld->scene->textures[i], t; /* a copy: adding may move the array */
        if (src.type == TEXTURE_CONSTANT) {
            texture_constant(&t, texop_apply(op, a, b, src.value));
        } else if (src.type == TEXTURE_CHECKERBOARD) {
            texture_checkerboard(&t, ld->scene->textures, memo[src.checker.even], memo[src.checker.odd],
                                 src.checker.scale);
        } else {
            size_t np = (size_t)src.image.width * (size_t)src.image.height;
            float *px = malloc(np * 3 * sizeof *px);
            if (!px) {
                st = oom(ld);
                break;
            }
            for (size_t k = 0; k < np; k++) {
                const float *q = &src.image.rgb[3 * k];
                Color v = texop_apply(op, a, b, color_rgb(q[0], q[1], q[2]));
                px[3 * k] = v.c[0];
                px[3 * k + 1] = v.c[1];
                px[3 * k + 2] = v.c[2];
            }
            if ((st = texture_image(&t, px, src.image.width, src.image.height, src.image.wrap, ld->err))) {
                st = fail_wrap(ld, st, loc, d);
                break;
            }
        }
        texture_set_uv_transform(&t, src.uv_scale, src.uv_offset);
        st = tex_add(ld, &t, loc, d, &memo[i]);
    }
    if (!st) *out = memo[id];
    free(memo);
    return st;
}

/* The scene texture for a "texture" parameter of a material (its albedo or roughness):
 * 0 when the file gives a value or names a constant texture (*val then holds it), else
 * 1 + the scene texture's index, as Material stores it. */
static CstStatus tex_param(Loader *ld, Params *ps, const char *d, const char *name, int is_float,
                           int *tex, Color *val, int *entry)
{
    Param *p = find_param(ps, name);
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

/* A reflectance parameter (diffuse "reflectance", pbrt-v3 "Kd", ...) as albedo or albedo
 * texture. pbrt-v4's materials clamp reflectances to [0, 1]; a texture with larger values
 * is clamped per texel. */
static CstStatus get_albedo(Loader *ld, Params *ps, const char *d, const char *name, Material *m)
{
    int tex = 0, e = 0;
    Color avg = m->albedo;
    TRY(tex_param(ld, ps, d, name, 0, &tex, &avg, &e));
    if (!tex) return get_spectrum(ld, ps, d, name, SPEC_REFLECTANCE, 1, &m->albedo, NULL);
    Param *p = find_param(ps, name);
    float mx = color_max(ld->scene->textures[tex - 1].max);
    if (mx > 1.0f) {
        char nm[72];
        if (ld->texs[e].clamped < 0) {
            int id = 0;
            TRY(tex_map(ld, tex - 1, TEXOP_MIN1, color_s(0.0f), color_s(0.0f), p->loc, d, &id));
            ld->texs[e].clamped = id;
        }
        tex = ld->texs[e].clamped + 1;
        warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: texture \"%s\" has values up to %g; "
                "clamped to 1 texel by texel (pbrt-v4 clamps the filtered reflectance)", d,
                clip(p->strs[0], nm), (double)mx);
    }
    m->albedo_texture = tex;
    m->albedo = ld->scene->textures[tex - 1].average;
    return CST_OK;
}

/* ------------------------------------------------------------------ materials and textures */

static CstStatus add_mat_entry(Loader *ld, const char *name, const Material *m, int *out)
{
    if (!GROW(ld->mats, ld->cap_mats, ld->num_mats + 1)) return oom(ld);
    MatEntry *e = &ld->mats[ld->num_mats];
    e->name = NULL;
    if (name && !(e->name = dup_str(name))) return oom(ld);
    e->m = *m;
    e->scene_id = -1;
    *out = ld->num_mats++;
    return CST_OK;
}

static int find_named_material(Loader *ld, const char *name)
{
    for (int i = ld->num_mats - 1; i >= 0; i--)
        if (ld->mats[i].name && strcmp(ld->mats[i].name, name) == 0) return i;
    return -1;
}

/* pbrt's roughness parameters (names after `prefix`: "", "conductor." or "interface.") as
 * caustic's perceptual roughness. pbrt-v4's GGX width is alpha = sqrt(roughness) when
 * remaproughness is true, its default (TrowbridgeReitzDistribution::RoughnessToAlpha),
 * else alpha = roughness; caustic's is alpha = r^2 (material.h), so r = sqrt(alpha), and
 * below alpha 1e-3 both render the smooth delta lobes. Anisotropic widths become their
 * geometric mean sqrt(alpha_u alpha_v): GGX's density of normals along the macro normal is
 * 1 / (pi alpha_u alpha_v), so the isotropic lobe keeps that peak and the lobe's solid angle. */
static CstStatus pbrt_roughness(Loader *ld, Params *ps, const char *d, const char *prefix, Loc loc,
                                float *out, int *tex_out)
{
    char n_r[64], n_u[64], n_v[64];
    snprintf(n_r, sizeof n_r, "%sroughness", prefix);
    snprintf(n_u, sizeof n_u, "%suroughness", prefix);
    snprintf(n_v, sizeof n_v, "%svroughness", prefix);
    float r = 0.0f, ur = 0.0f, vr = 0.0f;
    int remap = 1;
    TRY(get_bool(ld, ps, d, "remaproughness", 1, &remap));
    if (tex_out) {
        /* An isotropic roughness texture (u and v from the same one) becomes a roughness
         * texture of caustic's perceptual roughness, r^(1/4) (remapped) or r^(1/2) texel by
         * texel, as the constant below; anisotropic or mixed ones take their averages. */
        Param *pr = find_param(ps, n_r), *pu = find_param(ps, n_u), *pv = find_param(ps, n_v);
        Param *eu = pu ? pu : pr, *ev = pv ? pv : pr;
        *tex_out = 0;
        if (eu && ev && eu->type == PT_TEXTURE && ev->type == PT_TEXTURE && eu->num_strs == 1 &&
            ev->num_strs == 1 && strcmp(eu->strs[0], ev->strs[0]) == 0) {
            int tex = 0, e = 0;
            Color avg = color_s(0.0f);
            TRY(tex_param(ld, ps, d, eu->name, 1, &tex, &avg, &e));
            if (ev != eu) TRY(tex_param(ld, ps, d, ev->name, 1, &tex, &avg, &e));
            if (tex) {
                if (pr) pr->used = 1; /* shadowed by uroughness and vroughness */
                int *id = &ld->texs[e].rough[remap != 0];
                if (*id < 0) {
                    int made = 0;
                    TRY(tex_map(ld, tex - 1, TEXOP_POW, color_s(remap ? 0.25f : 0.5f), color_s(0.0f), eu->loc, d, &made));
                    *id = made;
                }
                const Texture *t = &ld->scene->textures[*id];
                *tex_out = *id + 1;
                *out = minf(t->average.c[0], 1.0f);
                if (t->max.c[0] > 1.0f)
                    warn_at(ld, CST_WARN_APPROXIMATED, eu->loc, "%s: roughness texture values up to "
                            "GGX alpha %g are beyond caustic's roughest (alpha 1); rendered with alpha 1",
                            d, (double)(t->max.c[0] * t->max.c[0]));
                return CST_OK;
            }
        }
    }
    TRY(get_float_tex(ld, ps, d, n_r, 0.0f, &r, NULL));
    TRY(get_float_tex(ld, ps, d, n_u, r, &ur, NULL));
    TRY(get_float_tex(ld, ps, d, n_v, r, &vr, NULL));
    if (!(ur >= 0.0f) || !(vr >= 0.0f)) {
        Param *p = find_param(ps, !(ur >= 0.0f) ? n_u : n_v);
        if (!p) p = find_param(ps, n_r);
        return fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: roughness %g is negative; "
                       "expected a roughness >= 0", d, (double)(!(ur >= 0.0f) ? ur : vr));
    }
    float au = remap ? sqrtf(ur) : ur, av = remap ? sqrtf(vr) : vr;
    float alpha = au;
    if (au != av) {
        alpha = sqrtf(au * av);
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: anisotropic roughness (alpha %g along u, %g "
                "along v) approximated as isotropic with their geometric mean, alpha %g", d,
                (double)au, (double)av, (double)alpha);
    }
    *out = sqrtf(alpha);
    if (*out > 1.0f) {
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: GGX alpha %g is beyond caustic's roughest "
                "(alpha 1); rendered with alpha 1", d, (double)alpha);
        *out = 1.0f;
    }
    return CST_OK;
}

/* A conductor (pbrt-v4 ConductorMaterial): complex IOR from eta and k (default copper), or
 * from "reflectance" as pbrt-v4 converts it: eta = 1, k = 2 sqrt(R) / sqrt(1 - R) with R
 * clamped to [0, 0.9999], whose normal-incidence Fresnel reflectance ((n-1)^2 + k^2) /
 * ((n+1)^2 + k^2) = k^2 / (4 + k^2) is exactly R. coatedconductor reads the same with
 * prefix "conductor." (its reflectance keeps the plain name). */
static CstStatus conductor(Loader *ld, Params *ps, const char *d, const char *prefix, Loc loc,
                           Material *m)
{
    char n_eta[64], n_k[64], nm[72];
    snprintf(n_eta, sizeof n_eta, "%seta", prefix);
    snprintf(n_k, sizeof n_k, "%sk", prefix);
    Color eta, k, refl = color_s(0.0f);
    material_metal("copper", &eta, &k); /* pbrt's default conductor is copper */
    Param *pe = find_param(ps, n_eta), *pk = find_param(ps, n_k), *pr = find_param(ps, "reflectance");
    if (pr && (pe || pk))
        return fail_at(ld, CST_ERR_INVALID_ARG, pr->loc, "%s: \"reflectance\" given with \"%s\"; "
                       "expected either reflectance or eta and k (as pbrt-v4)", d,
                       clip(pe ? pe->decl : pk->decl, nm));
    int has_refl = 0;
    if (pe && pe->type == PT_FLOAT) { /* pbrt-v4 also takes a plain float eta */
        float eta_f = 1.0f;
        TRY(get_float(ld, ps, d, n_eta, 1.0f, &eta_f, NULL));
        if (!(eta_f >= 0.0f))
            return fail_at(ld, CST_ERR_INVALID_ARG, pe->loc, "%s: eta %g is negative; expected "
                           "the real part of a conductor's index of refraction, >= 0", d, (double)eta_f);
        eta = color_s(eta_f);
    } else {
        TRY(get_spectrum(ld, ps, d, n_eta, SPEC_UNBOUNDED, 1, &eta, NULL));
    }
    TRY(get_spectrum(ld, ps, d, n_k, SPEC_UNBOUNDED, 1, &k, NULL));
    TRY(get_spectrum(ld, ps, d, "reflectance", SPEC_REFLECTANCE, 1, &refl, &has_refl));
    if (has_refl) {
        float r[3] = {refl.c[0], refl.c[1], refl.c[2]}, kk[3];
        for (int i = 0; i < 3; i++) {
            float c = clampf(r[i], 0.0f, 0.9999f);
            kk[i] = 2.0f * sqrtf(c) / sqrtf(1.0f - c);
        }
        eta = color_s(1.0f);
        k = color_rgb(kk[0], kk[1], kk[2]);
    }
    m->type = MATERIAL_CONDUCTOR;
    m->albedo = color_s(1.0f);
    m->ior = 1.0f;
    m->eta = eta;
    m->k = k;
    return pbrt_roughness(ld, ps, d, prefix, loc, &m->roughness, &m->roughness_texture);
}

/* Layer parameters of pbrt-v4's coated materials that caustic's closed-form coat does not
 * have: a warning for each given with other than pbrt's default (a non-absorbing layer of
 * any thickness, isotropic phase); the random walk's maxdepth and nsamples are read
 * silently. */
static CstStatus coat_layer_params(Loader *ld, Params *ps, const char *d)
{
    static const struct { const char *name; float def; } skip[] = {{"thickness", 0.01f}, {"g", 0.0f}};
    for (size_t i = 0; i < sizeof skip / sizeof skip[0]; i++) {
        float v = skip[i].def;
        int found = 0;
        TRY(get_float_tex(ld, ps, d, skip[i].name, skip[i].def, &v, &found));
        if (found && v != skip[i].def)
            warn_at(ld, CST_WARN_PARAMETER_IGNORED, find_param(ps, skip[i].name)->loc,
                    "%s: \"%s\" %g is not supported (caustic's coat is an interface without a "
                    "scattering layer); ignored", d, skip[i].name, (double)v);
    }
    Color albedo = color_s(0.0f);
    int found = 0;
    TRY(get_spectrum(ld, ps, d, "albedo", SPEC_REFLECTANCE, 1, &albedo, &found));
    if (found && color_max(albedo) > 0.0f)
        warn_at(ld, CST_WARN_PARAMETER_IGNORED, find_param(ps, "albedo")->loc,
                "%s: a scattering layer (\"albedo\" > 0) is not supported; ignored", d);
    int n = 0;
    TRY(get_int(ld, ps, d, "maxdepth", 10, &n));
    TRY(get_int(ld, ps, d, "nsamples", 1, &n));
    return CST_OK;
}

static CstStatus dielectric_eta(Loader *ld, Params *ps, const char *d, const char *name, float *eta)
{
    Param *p = find_param(ps, name);
    if (p && p->type == PT_SPECTRUM) {
        Color c = color_s(1.5f);
        TRY(get_spectrum(ld, ps, d, name, SPEC_UNBOUNDED, 0, &c, NULL));
        *eta = c.c[1];
        if (p->num_strs == 0)
            warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: spectral eta taken as %g (no dispersion)",
                    d, (double)*eta);
    } else {
        TRY(get_float_tex(ld, ps, d, name, *eta, eta, NULL));
    }
    if (!(*eta > 0.0f)) {
        Loc l = p ? p->loc : ld->end;
        return fail_at(ld, CST_ERR_INVALID_ARG, l, "%s: eta %g is not positive; expected an index "
                       "of refraction > 0 (glass is about 1.5)", d, (double)*eta);
    }
    return CST_OK;
}

/* pbrt material `type` with its parameters as our nearest Material (docs/pbrt-compat.md). */
static CstStatus make_material(Loader *ld, const char *type, Params *ps, Loc loc, Material *m)
{
    char d[96], nm[72];
    snprintf(d, sizeof d, "material \"%s\"", clip(type, nm));
    /* Fields a mapping does not set keep their zero defaults. one_sided stays false: pbrt-v4's
     * reflective BxDFs (diffuse, conductor, coated) reflect on both sides of a surface, as
     * caustic's two-sided default does. */
    memset(m, 0, sizeof *m);
    m->type = MATERIAL_DIFFUSE;
    m->albedo = color_s(0.5f);
    m->ior = 1.0f;
    if (strcmp(type, "diffuse") == 0) {
        TRY(get_albedo(ld, ps, d, "reflectance", m));
    } else if (strcmp(type, "matte") == 0) { /* pbrt-v3 */
        TRY(get_albedo(ld, ps, d, "Kd", m));
    } else if (strcmp(type, "coateddiffuse") == 0) {
        /* caustic's plastic: the same interface over a Lambertian base, with the light
         * between them in closed form (bsdf.c) instead of pbrt's random walk. */
        m->type = MATERIAL_PLASTIC;
        m->ior = 1.5f;
        TRY(get_albedo(ld, ps, d, "reflectance", m));
        TRY(dielectric_eta(ld, ps, d, "eta", &m->ior));
        TRY(pbrt_roughness(ld, ps, d, "", loc, &m->roughness, NULL)); /* no plastic roughness textures */
        TRY(coat_layer_params(ld, ps, d));
        if (m->ior < 1.0f) {
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: coat eta %g below 1 rendered as 1 (no coat)",
                    d, (double)m->ior);
            m->ior = 1.0f;
        }
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated by caustic's plastic (reflectance "
                "%g %g %g, eta %g, roughness %g): the light between coat and base is modelled in "
                "closed form (Kelemen & Szirmay-Kalos 2001), not by pbrt's random walk", d,
                (double)m->albedo.c[0], (double)m->albedo.c[1], (double)m->albedo.c[2], (double)m->ior,
                (double)m->roughness);
    } else if (strcmp(type, "diffusetransmission") == 0) {
        TRY(get_albedo(ld, ps, d, "reflectance", m));
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated as diffuse with its reflectance "
                "(transmission is dropped)", d);
    } else if (strcmp(type, "plastic") == 0 || strcmp(type, "substrate") == 0 ||
               strcmp(type, "uber") == 0 || strcmp(type, "translucent") == 0 ||
               strcmp(type, "disney") == 0) { /* pbrt-v3 */
        m->albedo = color_s(strcmp(type, "plastic") == 0 ? 0.25f : 0.5f);
        TRY(get_albedo(ld, ps, d, strcmp(type, "disney") == 0 ? "color" : "Kd", m));
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated as diffuse with its diffuse "
                "reflectance (specular lobes dropped)", d);
    } else if (strcmp(type, "conductor") == 0 || strcmp(type, "metal") == 0) {
        TRY(conductor(ld, ps, d, "", loc, m));
    } else if (strcmp(type, "coatedconductor") == 0) {
        TRY(conductor(ld, ps, d, "conductor.", loc, m));
        /* The coat's parameters are read so that only the layer's unsupported ones warn. */
        float coat_rough = 0.0f, coat_eta = 1.5f;
        TRY(pbrt_roughness(ld, ps, d, "interface.", loc, &coat_rough, NULL));
        TRY(dielectric_eta(ld, ps, d, "interface.eta", &coat_eta));
        TRY(coat_layer_params(ld, ps, d));
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated as its conductor (the "
                "dielectric coating, eta %g, is dropped)", d, (double)coat_eta);
    } else if (strcmp(type, "mirror") == 0) { /* pbrt-v3 */
        m->type = MATERIAL_MIRROR;
        m->albedo = color_s(0.9f);
        TRY(get_albedo(ld, ps, d, "Kr", m));
    } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "glass") == 0 ||
               strcmp(type, "thindielectric") == 0) {
        m->type = MATERIAL_GLASS;
        m->albedo = color_s(1.0f);
        m->ior = 1.5f;
        TRY(dielectric_eta(ld, ps, d, strcmp(type, "glass") == 0 && find_param(ps, "index") ? "index" : "eta",
                           &m->ior));
        if (strcmp(type, "thindielectric") == 0) {
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated as a solid dielectric (glass) "
                    "of the same eta: rays refract at its surface instead of passing straight through", d);
        } else {
            /* Rough: GGX reflection and transmission (Walter et al. 2007), as pbrt-v4's
             * DielectricBxDF; below alpha 1e-3 both are smooth. */
            TRY(pbrt_roughness(ld, ps, d, "", loc, &m->roughness, &m->roughness_texture));
            if (m->roughness_texture || material_alpha(m->roughness) >= MATERIAL_SMOOTH_ALPHA)
                m->type = MATERIAL_DIELECTRIC;
            else m->roughness = 0.0f;
        }
    } else if (strcmp(type, "interface") == 0 || strcmp(type, "") == 0 || strcmp(type, "none") == 0) {
        m->type = MATERIAL_GLASS;
        m->albedo = color_s(1.0f);
        m->ior = 1.0f;
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s (a medium boundary) approximated as glass of "
                "eta 1: paths pass straight through, shadow rays are blocked", d);
    } else if (strcmp(type, "mix") == 0) {
        Param *p;
        TRY(lookup(ld, ps, d, "materials", M(PT_STRING), "string", &p));
        if (!p || p->num_strs != 2)
            return fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc,
                           "%s: expected \"string materials\" with two named materials", d);
        int a = find_named_material(ld, p->strs[0]), b = find_named_material(ld, p->strs[1]);
        if (a < 0 || b < 0)
            return fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "%s: material \"%s\" is not defined; expected names given to "
                           "MakeNamedMaterial before", d, clip(p->strs[a < 0 ? 0 : 1], nm));
        float amount = 0.5f;
        TRY(get_float_tex(ld, ps, d, "amount", 0.5f, &amount, NULL));
        amount = clampf(amount, 0.0f, 1.0f);
        Material ma = ld->mats[a].m, mb = ld->mats[b].m;
        if (ma.type == mb.type && (ma.type == MATERIAL_DIFFUSE || ma.type == MATERIAL_MIRROR) &&
            ma.one_sided == mb.one_sided && !ma.albedo_texture && !mb.albedo_texture) {
            /* Choosing one of two Lambertian (or two mirror) lobes with probability amount
             * is the same lobe with the blended albedo: exact. (Conductors, plastics and
             * dielectrics are not linear in a single albedo.) */
            *m = ma;
            m->albedo = color_add(color_scale(ma.albedo, 1.0f - amount), color_scale(mb.albedo, amount));
        } else {
            *m = amount < 0.5f ? ma : mb;
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s of materials that do not blend into one "
                    "(two untextured diffuse or two mirrors would) approximated by the one with the larger "
                    "weight, \"%s\"", d, clip(p->strs[amount < 0.5f ? 0 : 1], nm));
        }
    } else if (strcmp(type, "measured") == 0 || strcmp(type, "hair") == 0 ||
               strcmp(type, "subsurface") == 0 || strcmp(type, "kdsubsurface") == 0 ||
               strcmp(type, "fourier") == 0) {
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported; diffuse reflectance 0.5 is used instead", d);
    } else {
        return fail_at(ld, CST_ERR_INVALID_ARG, loc,
                       "unknown material type \"%s\"; expected one of: diffuse, coateddiffuse, "
                       "conductor, coatedconductor, dielectric, thindielectric, diffusetransmission, "
                       "interface, mix, measured, hair, subsurface", clip(type, nm));
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ file names */

/* `file` relative to the main scene file's directory (pbrt's search directory). */
static char *resolve_path(Loader *ld, const char *file)
{
    return path_resolve(ld->base_dir, file);
}

static CstStatus check_file_access(Loader *ld, Loc loc, const char *d)
{
    if (ld->opt.no_file_access)
        return fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: file access is disabled for this load "
                       "(CstLoadOptions.no_file_access)", d);
    return CST_OK;
}

/* op applied in place to image texture t's texels (its average and maximum recomputed),
 * keeping its uv transform. */
static CstStatus image_apply(Loader *ld, Texture *t, TexOp op, Color a, Color b, Loc loc, const char *d)
{
    Vec2 sc = t->uv_scale, off = t->uv_offset;
    float *px = t->image.rgb;
    int w = t->image.width, h = t->image.height;
    size_t np = (size_t)w * (size_t)h;
    for (size_t k = 0; k < np; k++) {
        Color v = texop_apply(op, a, b, color_rgb(px[3 * k], px[3 * k + 1], px[3 * k + 2]));
        px[3 * k] = v.c[0];
        px[3 * k + 1] = v.c[1];
        px[3 * k + 2] = v.c[2];
    }
    CstStatus st = texture_image(t, px, w, h, t->image.wrap, ld->err); /* takes px */
    if (st) return fail_wrap(ld, st, loc, d);
    texture_set_uv_transform(t, sc, off);
    return CST_OK;
}

/* pbrt's UVMapping ("uscale", "vscale", "udelta", "vdelta"): (s, t) = (su u + du, sv v + dv). */
static CstStatus tex_uv_mapping(Loader *ld, Params *ps, const char *d, Vec2 *scale, Vec2 *offset)
{
    const char *mapping = NULL;
    Loc ml;
    char nm[72];
    float su = 1.0f, sv = 1.0f, du = 0.0f, dv = 0.0f;
    TRY(get_string(ld, ps, d, "mapping", &mapping, &ml));
    if (mapping && strcmp(mapping, "uv") != 0)
        warn_at(ld, CST_WARN_UNSUPPORTED, ml, "%s: mapping \"%s\" is not supported; the surface's "
                "(u, v) are used (\"uv\")", d, clip(mapping, nm));
    TRY(get_float(ld, ps, d, "uscale", 1.0f, &su, NULL));
    TRY(get_float(ld, ps, d, "vscale", 1.0f, &sv, NULL));
    TRY(get_float(ld, ps, d, "udelta", 0.0f, &du, NULL));
    TRY(get_float(ld, ps, d, "vdelta", 0.0f, &dv, NULL));
    *scale = v2(su, sv);
    *offset = v2(du, dv);
    return CST_OK;
}

/* A texture-valued parameter of a Texture: another non-constant texture (*id >= 0), or a
 * value (*id = -1, *val: given, a constant texture's, or def). */
static CstStatus tex_operand(Loader *ld, Params *ps, const char *d, const char *name, int is_float,
                             float def, int *id, Color *val)
{
    int tex = 0;
    *id = -1;
    *val = color_s(def);
    TRY(tex_param(ld, ps, d, name, is_float, &tex, val, NULL));
    if (tex) {
        *id = tex - 1;
        return CST_OK;
    }
    Param *p = find_param(ps, name);
    if (p && p->type == PT_TEXTURE) return CST_OK;
    if (is_float) {
        float f = def;
        TRY(get_float_tex(ld, ps, d, name, def, &f, NULL));
        *val = color_s(f);
        return CST_OK;
    }
    return get_spectrum(ld, ps, d, name, SPEC_UNBOUNDED, 1, val, NULL);
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
    Vec2 uvs, uvo;
    TRY(get_string(ld, ps, d, "filename", &file, &fl));
    TRY(get_string(ld, ps, d, "filter", &filter, &il));
    TRY(get_string(ld, ps, d, "wrap", &wrap, &wl));
    TRY(get_string(ld, ps, d, "encoding", &enc, &el));
    TRY(get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(get_float(ld, ps, d, "maxanisotropy", 8.0f, &aniso, NULL)); /* for EWA only */
    TRY(get_bool(ld, ps, d, "invert", 0, &invert));
    TRY(tex_uv_mapping(ld, ps, d, &uvs, &uvo));
    *id = -1;
    if (!file)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the image file", d);
    TextureWrap tw = TEXTURE_WRAP_REPEAT;
    if (wrap && strcmp(wrap, "clamp") == 0) {
        tw = TEXTURE_WRAP_CLAMP;
    } else if (wrap && (strcmp(wrap, "black") == 0 || strcmp(wrap, "octahedralsphere") == 0)) {
        tw = TEXTURE_WRAP_CLAMP;
        warn_at(ld, CST_WARN_APPROXIMATED, wl, "%s: wrap \"%s\" approximated by \"clamp\"", d, wrap);
    } else if (wrap && strcmp(wrap, "repeat") != 0) {
        return fail_at(ld, CST_ERR_INVALID_ARG, wl, "%s: wrap \"%s\" is not known; expected \"repeat\", "
                       "\"clamp\", \"black\" or \"octahedralsphere\"", d, clip(wrap, nm));
    }
    if (filter && strcmp(filter, "bilinear") != 0)
        warn_at(ld, CST_WARN_APPROXIMATED, il, "%s: filter \"%s\" approximated by \"bilinear\" (caustic "
                "has no MIP maps)", d, clip(filter, nm));
    int linear = 0; /* pbrt-v4's default is sRGB for PNG; caustic takes 8- and 16-bit files as sRGB */
    if (enc) {
        if (strcmp(enc, "linear") == 0) {
            linear = 1;
        } else if (strncmp(enc, "gamma ", 6) == 0) {
            char *e = NULL;
            gamma = strtof(enc + 6, &e);
            if (!(gamma > 0.0f) || !isfinite(gamma) || *e)
                return fail_at(ld, CST_ERR_INVALID_ARG, el, "%s: encoding \"%s\"; expected \"gamma\" and "
                               "a number > 0, as in \"gamma 2.2\"", d, clip(enc, nm));
            linear = 1;
        } else if (strcmp(enc, "sRGB") != 0) {
            return fail_at(ld, CST_ERR_INVALID_ARG, el, "%s: encoding \"%s\" is not known; expected "
                           "\"sRGB\", \"linear\" or \"gamma\" and a number", d, clip(enc, nm));
        }
    }
    ImageFileFormat format = image_format_from_path(file);
    int readable = format != IMAGE_FILE_NONE, is_float_file = image_format_is_float(format);
    if (!readable) {
        *v = color_s(0.5f);
        warn_at(ld, CST_WARN_UNSUPPORTED, fl, "%s: image \"%s\" is not PNG, JPEG, BMP, TGA, HDR, EXR or "
                "PFM; the constant 0.5 is used instead", d, clip(file, nm));
        Color a = color_s(invert ? -scale : scale), b = color_s(invert ? 1.0f : 0.0f);
        *v = texop_apply(TEXOP_AFFINE, a, b, *v);
        return CST_OK;
    }
    TRY(check_file_access(ld, fl, d));
    char *path = resolve_path(ld, file);
    if (!path) return oom(ld);
    Texture t;
    CstStatus st = texture_image_load(&t, path, linear, tw, ld->err);
    free(path);
    if (st) return fail_wrap(ld, st, fl, d);
    texture_set_uv_transform(&t, uvs, uvo);
    /* pbrt's order: decode, take the first channel for a float texture, scale, invert. */
    if (gamma > 0.0f && !is_float_file) st = image_apply(ld, &t, TEXOP_POW, color_s(gamma), color_s(0.0f), el, d);
    if (!st && is_float) st = image_apply(ld, &t, TEXOP_RED, color_s(0.0f), color_s(0.0f), loc, d);
    if (!st && (scale != 1.0f || invert))
        st = image_apply(ld, &t, TEXOP_AFFINE, color_s(invert ? -scale : scale), color_s(invert ? 1.0f : 0.0f), loc, d);
    if (st) {
        texture_free(&t);
        return st;
    }
    return tex_add(ld, &t, loc, d, id);
}

/* pbrt-v4's "checkerboard": a 2D checkerboard of tex1 (where floor(s) + floor(t) is even)
 * and tex2, on the uv mapping. */
static CstStatus texture_checker(Loader *ld, Params *ps, const char *d, Loc loc, int is_float, int *id)
{
    int a = -1, b = -1;
    Color va, vb;
    Vec2 uvs, uvo;
    TRY(tex_operand(ld, ps, d, "tex1", is_float, 1.0f, &a, &va));
    TRY(tex_operand(ld, ps, d, "tex2", is_float, 0.0f, &b, &vb));
    TRY(tex_uv_mapping(ld, ps, d, &uvs, &uvo));
    if (a < 0) TRY(tex_const(ld, va, loc, d, &a));
    if (b < 0) TRY(tex_const(ld, vb, loc, d, &b));
    Texture t;
    texture_checkerboard(&t, ld->scene->textures, a, b, 1.0f);
    texture_set_uv_transform(&t, uvs, uvo);
    return tex_add(ld, &t, loc, d, id);
}

static CstStatus texture_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *name = NULL, *ttype = NULL, *cls = NULL, nm[72], nm2[72];
    Params ps = {0};
    Loc tl;
    CstStatus st = expect_string(ld, lx, "Texture", "the texture's name", &name, NULL);
    if (!st) st = expect_string(ld, lx, "Texture", "its type, \"spectrum\" or \"float\"", &ttype, &tl);
    if (!st) st = expect_string(ld, lx, "Texture", "its class, as in \"imagemap\"", &cls, NULL);
    if (!st) st = parse_params(ld, lx, &ps);
    if (st) goto done;
    if (!ld->in_world) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "Texture before WorldBegin; expected textures "
                     "in the world block");
        goto done;
    }
    int is_float = strcmp(ttype, "float") == 0;
    if (!is_float && strcmp(ttype, "spectrum") != 0 && strcmp(ttype, "color") != 0) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, tl, "Texture \"%s\": type \"%s\"; expected \"spectrum\" "
                     "or \"float\"", clip(name, nm), clip(ttype, nm2));
        goto done;
    }
    char d[160];
    snprintf(d, sizeof d, "Texture \"%s\" \"%s\"", clip(name, nm), clip(cls, nm2));
    Color v = color_s(1.0f); /* the value of a constant (id < 0) */
    int id = -1;         /* the scene texture, when not a constant */
    SpecKind sk = SPEC_UNBOUNDED;
/* A texture-valued parameter of this texture taken as one value (its average). */
#define TEXPARAM(pname, def, outv)                                                        \
    do {                                                                                  \
        (outv) = color_s(def);                                                              \
        if (is_float) {                                                                   \
            float f_ = (def);                                                             \
            st = get_float_tex(ld, &ps, d, (pname), (def), &f_, NULL);                    \
            (outv) = color_s(f_);                                                           \
        } else {                                                                          \
            st = get_spectrum(ld, &ps, d, (pname), sk, 1, &(outv), NULL);                 \
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
            b = ld->scene->textures[tb].average;
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: the product of two textures is approximated "
                    "by \"tex\" times the average of \"scale\", %g", d, (double)b.c[0]);
            st = tex_map(ld, ta, TEXOP_AFFINE, b, color_s(0.0f), loc, d, &id);
        } else {
            st = tex_map(ld, ta >= 0 ? ta : tb, TEXOP_AFFINE, ta >= 0 ? b : a, color_s(0.0f), loc, d, &id);
        }
        if (st) goto done;
    } else if (strcmp(cls, "mix") == 0 || strcmp(cls, "directionmix") == 0) {
        Color a, b;
        float amount = 0.5f;
        TEXPARAM("tex1", 0.0f, a);
        TEXPARAM("tex2", 1.0f, b);
        if (cls[0] == 'm') {
            st = get_float_tex(ld, &ps, d, "amount", 0.5f, &amount, NULL);
            if (st) goto done;
        }
        v = color_add(color_scale(a, 1.0f - amount), color_scale(b, amount));
        if (cls[0] == 'd')
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated by the average of its two textures", d);
    } else if (strcmp(cls, "checkerboard") == 0) {
        int dim = 2;
        if ((st = get_int(ld, &ps, d, "dimension", 2, &dim))) goto done;
        if (dim == 3) {
            Color a, b;
            TEXPARAM("tex1", 1.0f, a);
            TEXPARAM("tex2", 0.0f, b);
            v = color_scale(color_add(a, b), 0.5f);
            params_mark_all_used(&ps); /* the 3D mapping's parameters */
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: a 3D (solid) checkerboard approximated by its "
                    "average (%g, %g, %g)", d, (double)v.c[0], (double)v.c[1], (double)v.c[2]);
        } else if (dim == 2) {
            if ((st = texture_checker(ld, &ps, d, loc, is_float, &id))) goto done;
        } else {
            st = fail_at(ld, CST_ERR_INVALID_ARG, find_param(&ps, "dimension")->loc, "%s: dimension %d; "
                         "expected 2 or 3", d, dim);
            goto done;
        }
    } else if (strcmp(cls, "bilerp") == 0) {
        Color c[4];
        static const char *const names[4] = {"v00", "v01", "v10", "v11"};
        static const float defs[4] = {0.0f, 1.0f, 0.0f, 1.0f};
        for (int i = 0; i < 4; i++) TEXPARAM(names[i], defs[i], c[i]);
        v = color_scale(color_add(color_add(c[0], c[1]), color_add(c[2], c[3])), 0.25f);
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated by its average", d);
    } else if (strcmp(cls, "imagemap") == 0) {
        if ((st = texture_imagemap(ld, &ps, d, loc, is_float, &id, &v))) goto done;
    } else {
        v = color_s(0.5f);
        params_mark_all_used(&ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: texture class not supported; the constant 0.5 "
                "is used instead", d);
    }
#undef TEXPARAM
    params_warn_unused(ld, &ps, d);
    if (id < 0 && (st = tex_const(ld, v, loc, d, &id))) goto done;
    if (!GROW(ld->texs, ld->cap_texs, ld->num_texs + 1)) { st = oom(ld); goto done; }
    ld->texs[ld->num_texs].name = name;
    ld->texs[ld->num_texs].is_float = is_float;
    ld->texs[ld->num_texs].id = id;
    ld->texs[ld->num_texs].value = ld->scene->textures[id].average;
    ld->texs[ld->num_texs].clamped = ld->texs[ld->num_texs].rough[0] = ld->texs[ld->num_texs].rough[1] = -1;
    ld->num_texs++;
    name = NULL;
done:
    free(name);
    free(ttype);
    free(cls);
    params_free(&ps);
    return st;
}

/* ------------------------------------------------------------------ geometry */

static void geom_free(ShapeGeom *g)
{
    free(g->p);
    free(g->n);
    free(g->uv);
    free(g->idx);
    memset(g, 0, sizeof *g);
}

static CstStatus geom_alloc(Loader *ld, ShapeGeom *g, int nv, int nt, int normals, int uvs)
{
    memset(g, 0, sizeof *g);
    g->p = malloc((size_t)(nv ? nv : 1) * sizeof *g->p);
    g->idx = malloc((size_t)(nt ? nt : 1) * 3 * sizeof *g->idx);
    if (normals) g->n = malloc((size_t)(nv ? nv : 1) * sizeof *g->n);
    if (uvs) g->uv = malloc((size_t)(nv ? nv : 1) * sizeof *g->uv);
    if (!g->p || !g->idx || (normals && !g->n) || (uvs && !g->uv)) {
        geom_free(g);
        return oom(ld);
    }
    g->nv = nv;
    g->nt = nt;
    return CST_OK;
}

/* A UV sphere, outward-facing, for spheres under transforms that are not similarities. */
static CstStatus sphere_mesh(Loader *ld, float radius, ShapeGeom *g)
{
    const int S = PBRT_SPHERE_SEGMENTS, R = PBRT_SPHERE_RINGS;
    int nv = (R - 1) * S + 2, nt = 2 * S * (R - 1);
    TRY(geom_alloc(ld, g, nv, nt, 1, 0));
    int v = 0, t = 0;
    g->n[v] = v3(0.0f, 0.0f, -1.0f);
    g->p[v++] = v3(0.0f, 0.0f, -radius);
    for (int r = 1; r < R; r++) {
        double th = PBRT_PI * (double)r / R;
        for (int s = 0; s < S; s++) {
            double ph = 2.0 * PBRT_PI * (double)s / S;
            Vec3 n = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)-cos(th));
            g->n[v] = n;
            g->p[v++] = v3_scale(n, radius);
        }
    }
    g->n[v] = v3(0.0f, 0.0f, 1.0f);
    g->p[v++] = v3(0.0f, 0.0f, radius);
    for (int s = 0; s < S; s++) { /* bottom cap: counter-clockwise seen from outside */
        int a = 1 + s, b = 1 + (s + 1) % S;
        g->idx[3 * t] = 0; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = a; t++;
    }
    for (int r = 0; r < R - 2; r++)
        for (int s = 0; s < S; s++) {
            int a = 1 + r * S + s, b = 1 + r * S + (s + 1) % S;
            int c = a + S, e = b + S;
            g->idx[3 * t] = a; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = e; t++;
            g->idx[3 * t] = a; g->idx[3 * t + 1] = e; g->idx[3 * t + 2] = c; t++;
        }
    int top = nv - 1, base = 1 + (R - 2) * S;
    for (int s = 0; s < S; s++) {
        int a = base + s, b = base + (s + 1) % S;
        g->idx[3 * t] = a; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = top; t++;
    }
    g->nt = t;
    return CST_OK;
}

/* An annulus (inner may be 0) or sector at z = height facing +z, as a polygon whose
 * radii are scaled so that its area equals the true disk's: an emitting disk keeps its
 * power. */
static CstStatus disk_mesh(Loader *ld, float height, float radius, float inner, float phimax_deg,
                           ShapeGeom *g)
{
    double phimax = (double)clampf(phimax_deg, 0.0f, 360.0f) * PBRT_PI / 180.0;
    int segs = (int)ceil(PBRT_DISK_SEGMENTS * phimax / (2.0 * PBRT_PI));
    if (segs < 1) segs = 1;
    double step = phimax / segs;
    double k = sqrt(step / sin(step)); /* polygon area (segs/2) r^2 sin(step) -> (phimax/2) r^2 */
    int full = phimax >= 2.0 * PBRT_PI - 1e-9;
    int ring = full ? segs : segs + 1;
    int annulus = inner > 0.0f;
    int nv = annulus ? 2 * ring : ring + 1, nt = annulus ? 2 * segs : segs;
    TRY(geom_alloc(ld, g, nv, nt, 0, 0));
    for (int i = 0; i < ring; i++) {
        double ph = step * i;
        g->p[i] = v3((float)(k * (double)radius * cos(ph)), (float)(k * (double)radius * sin(ph)), height);
        if (annulus) g->p[ring + i] = v3((float)(k * (double)inner * cos(ph)), (float)(k * (double)inner * sin(ph)), height);
    }
    if (!annulus) g->p[ring] = v3(0.0f, 0.0f, height);
    for (int i = 0; i < segs; i++) {
        int a = i, b = (i + 1) % ring;
        if (!annulus) {
            g->idx[3 * i] = ring; g->idx[3 * i + 1] = a; g->idx[3 * i + 2] = b;
        } else {
            int *t = &g->idx[6 * i];
            t[0] = ring + a; t[1] = a; t[2] = b;
            t[3] = ring + a; t[4] = b; t[5] = ring + b;
        }
    }
    return CST_OK;
}

/* Linear part of m is a rotation times a uniform scale (to 1e-5): spheres stay spheres. */
static int is_similarity(const Transform *m, float *scale)
{
    Vec3 c[3];
    for (int k = 0; k < 3; k++) c[k] = v3(m->m[0][k], m->m[1][k], m->m[2][k]);
    float l0 = v3_length(c[0]), l1 = v3_length(c[1]), l2 = v3_length(c[2]);
    if (!(l0 > 0.0f)) return 0;
    float tol = 1e-5f * l0;
    if (fabsf(l1 - l0) > tol || fabsf(l2 - l0) > tol) return 0;
    if (fabsf(v3_dot(c[0], c[1])) > tol * l0 || fabsf(v3_dot(c[0], c[2])) > tol * l0 ||
        fabsf(v3_dot(c[1], c[2])) > tol * l0)
        return 0;
    *scale = l0;
    return 1;
}

static CstStatus material_scene_id(Loader *ld, int entry, int *out)
{
    MatEntry *e = &ld->mats[entry];
    if (e->scene_id < 0) TRY(scene_add_material(ld->scene, &e->m, &e->scene_id, ld->err));
    *out = e->scene_id;
    return CST_OK;
}

static int coords_ok(Vec3 p) { return v3_is_finite(p) && (double)v3_max_abs(p) <= PBRT_MAX_LENGTH; }

/* Places an object-space shape with xf into the scene with the given material and area
 * light. Winding follows pbrt's orientation rule: the geometric normal (v1-v0) x (v2-v0)
 * is flipped when ReverseOrientation differs from whether xf mirrors, or, for meshes
 * with normals, made to face the (possibly reversed) shading normals. */
static CstStatus emit_shape(Loader *ld, const ShapeGeom *g, const Xf *xf, int reverse,
                            int material, const AreaLight *al, Loc loc, const char *d)
{
    int mat = 0;
    float s = 1.0f;
    TRY(material_scene_id(ld, material, &mat));
    if (g->is_sphere && is_similarity(&xf->m, &s)) {
        Vec3 c = transform_point(&xf->m, v3s(0.0f));
        float r = g->radius * s;
        if (!coords_ok(c) || !(r > 1e-18f) || !((double)r <= PBRT_MAX_LENGTH))
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: sphere at (%g, %g, %g) radius %g is "
                           "beyond the scene limits (coordinates within 1e18, radius above 1e-18)",
                           d, (double)c.x, (double)c.y, (double)c.z, (double)r);
        Emission em = {color_s(0.0f), 0, 0};
        if (al && al->active) {
            em.radiance = color_scale(al->L, al->scale);
            em.two_sided = al->two_sided;
            if (al->power > 0.0f) {
                double k_e = (al->two_sided ? 2.0 : 1.0) * 4.0 * PBRT_PI * (double)r * (double)r * PBRT_PI;
                em.radiance = color_scale(em.radiance, (float)((double)al->power / k_e));
            }
            if (reverse && !al->two_sided)
                warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: ReverseOrientation on an emitting sphere "
                        "is ignored: it emits outward", d);
        }
        if (ld->scene->num_spheres >= INT_MAX - 1)
            return fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: too many spheres", d);
        CstStatus st = scene_add_sphere(ld->scene, c, r, mat, &em, ld->err);
        return st ? fail_wrap(ld, st, loc, d) : CST_OK;
    }
    ShapeGeom tess = {0};
    if (g->is_sphere) {
        TRY(sphere_mesh(ld, g->radius, &tess));
        g = &tess;
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: sphere under a non-uniform transform "
                "tessellated into %d triangles", d, tess.nt);
    }
    CstStatus st = CST_OK;
    Vec3 *p = malloc((size_t)(g->nv ? g->nv : 1) * sizeof *p);
    Vec3 *n = g->n ? malloc((size_t)g->nv * sizeof *n) : NULL;
    int *idx = malloc((size_t)(g->nt ? g->nt : 1) * 3 * sizeof *idx);
    if (!p || !idx || (g->n && !n)) { st = oom(ld); goto done; }
    if (g->nt > PBRT_MAX_TRIANGLES - ld->scene->num_triangles) {
        st = fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: the scene would exceed %d triangles", d,
                     PBRT_MAX_TRIANGLES);
        goto done;
    }
    int swap = (transform_det(&xf->m) < 0.0) != (reverse != 0);
    Transform nm = transform_identity();
    transform_normal_matrix(&xf->m, &nm);
    for (int i = 0; i < g->nv; i++) {
        p[i] = transform_is_identity(&xf->m) ? g->p[i] : transform_point(&xf->m, g->p[i]);
        if (!coords_ok(p[i])) {
            st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: vertex %d is at (%g, %g, %g), beyond the "
                         "scene limit; expected coordinates of magnitude at most %g", d, i,
                         (double)p[i].x, (double)p[i].y, (double)p[i].z, PBRT_MAX_LENGTH);
            goto done;
        }
        if (n) {
            n[i] = transform_normal(&nm, g->n[i]);
            if (reverse) n[i] = v3_neg(n[i]);
        }
    }
    for (int t = 0; t < g->nt; t++) {
        int a = g->idx[3 * t], b = g->idx[3 * t + 1], c = g->idx[3 * t + 2];
        int sw = swap;
        if (n) {
            Vec3 ng = v3_cross(v3_sub(p[b], p[a]), v3_sub(p[c], p[a]));
            Vec3 ns = v3_add(v3_add(n[a], n[b]), n[c]);
            sw = v3_dot(ng, ns) < 0.0f;
        }
        idx[3 * t] = a;
        idx[3 * t + 1] = sw ? c : b;
        idx[3 * t + 2] = sw ? b : c;
    }
    SceneMesh sm = {0};
    sm.positions = p;
    sm.num_vertices = g->nv;
    sm.normals = n;
    sm.uvs = g->uv;
    sm.indices = idx;
    sm.num_triangles = g->nt;
    sm.material = mat;
    sm.skip_degenerate = 1;
    Emission em = {color_s(0.0f), 0, 0};
    if (al && al->active) {
        em.radiance = color_scale(al->L, al->scale);
        em.two_sided = al->two_sided;
    }
    sm.emission = &em;
    int dropped = 0;
    if (al && al->active && al->power > 0.0f) {
        /* pbrt-v4 makes one light per triangle and normalises each to `power` by its own
         * area: L = power / (pi A sides) times the spectrum. */
        for (int t = 0; t < g->nt && !st; t++) {
            float area = triangle_area(p[idx[3 * t]], p[idx[3 * t + 1]], p[idx[3 * t + 2]]);
            Emission et = em;
            if (area > 0.0f)
                et.radiance = color_scale(em.radiance, (float)((double)al->power /
                                       (PBRT_PI * (double)area * (al->two_sided ? 2.0 : 1.0))));
            SceneMesh one = sm;
            one.indices = &idx[3 * t];
            one.num_triangles = 1;
            one.emission = &et;
            int dr = 0;
            st = scene_add_mesh_ex(ld->scene, &one, &dr, ld->err);
            dropped += dr;
        }
    } else {
        st = scene_add_mesh_ex(ld->scene, &sm, &dropped, ld->err);
    }
    if (st) {
        st = fail_wrap(ld, st, loc, d);
        goto done;
    }
    if (dropped)
        warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: %d of %d triangles are degenerate (zero area) "
                "and were dropped", d, dropped, g->nt);
done:
    free(p);
    free(n);
    free(idx);
    geom_free(&tess);
    return st;
}

/* Fills g from "point3 P", "integer indices" (optional for a single triangle), "normal N",
 * "point2 uv". */
static CstStatus read_mesh_params(Loader *ld, Params *ps, const char *d, Loc loc, int per_face,
                                  ShapeGeom *g)
{
    Param *pp, *pi, *pn, *puv;
    char nm[72];
    TRY(lookup(ld, ps, d, "P", M(PT_POINT3), "point3", &pp));
    TRY(lookup(ld, ps, d, "indices", M(PT_INTEGER), "integer", &pi));
    TRY(lookup(ld, ps, d, "N", M(PT_NORMAL), "normal", &pn));
    TRY(lookup(ld, ps, d, "uv", M(PT_POINT2) | M(PT_FLOAT), "point2", &puv));
    if (!puv) TRY(lookup(ld, ps, d, "st", M(PT_POINT2) | M(PT_FLOAT), "point2", &puv));
    if (!pp)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"point3 P\"; expected the vertex positions", d);
    int nv = pp->num_nums / 3;
    if (!pi && nv != per_face)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"integer indices\"; expected "
                       "indices unless there are exactly %d vertices", d, per_face);
    int ni = pi ? pi->num_nums : per_face;
    if (ni % per_face != 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, pi->loc, "%s: %d indices; expected a multiple of %d",
                       d, ni, per_face);
    if (pn && pn->num_nums != pp->num_nums)
        return fail_at(ld, CST_ERR_INVALID_ARG, pn->loc, "%s: %d normals for %d vertices; expected "
                       "one per vertex", d, pn->num_nums / 3, nv);
    if (puv && puv->num_nums != 2 * nv)
        return fail_at(ld, CST_ERR_INVALID_ARG, puv->loc, "%s: \"%s\" has %d values for %d vertices; "
                       "expected 2 per vertex", d, clip(puv->decl, nm), puv->num_nums, nv);
    int nfaces = ni / per_face, nt = per_face == 4 ? 2 * nfaces : nfaces;
    TRY(geom_alloc(ld, g, nv, nt, pn != NULL, puv != NULL));
    for (int i = 0; i < nv; i++) {
        g->p[i] = v3((float)pp->nums[3 * i], (float)pp->nums[3 * i + 1], (float)pp->nums[3 * i + 2]);
        if (!coords_ok(g->p[i]))
            return fail_at(ld, CST_ERR_INVALID_ARG, pp->loc, "%s: vertex %d is beyond the scene limit; "
                           "expected coordinates of magnitude at most %g", d, i, PBRT_MAX_LENGTH);
        if (pn) {
            Vec3 v = v3((float)pn->nums[3 * i], (float)pn->nums[3 * i + 1], (float)pn->nums[3 * i + 2]);
            float l = v3_length(v);
            g->n[i] = l > 0.0f && isfinite(l) ? v3_scale(v, 1.0f / l) : v3s(0.0f);
        }
        if (puv) g->uv[i] = v2((float)puv->nums[2 * i], (float)puv->nums[2 * i + 1]);
    }
    for (int i = 0; i < ni; i++) {
        double v = pi ? pi->nums[i] : (double)i;
        if (v < 0 || v >= nv)
            return fail_at(ld, CST_ERR_INVALID_ARG, pi->loc, "%s: index %g (number %d) is out of "
                           "range; expected 0 to %d (there are %d vertices)", d, v, i, nv - 1, nv);
    }
    for (int f = 0; f < nfaces; f++) {
        const double *q = pi ? &pi->nums[per_face * f] : NULL;
        int v[4];
        for (int k = 0; k < per_face; k++) v[k] = q ? (int)q[k] : per_face * f + k;
        if (per_face == 3) {
            for (int k = 0; k < 3; k++) g->idx[3 * f + k] = v[k];
        } else {
            /* bilinear patch p00 p10 p01 p11: (p00, p10, p11), (p00, p11, p01), the same
             * side as pbrt's dp/du x dp/dv */
            int *t = &g->idx[6 * f];
            t[0] = v[0]; t[1] = v[1]; t[2] = v[3];
            t[3] = v[0]; t[4] = v[3]; t[5] = v[2];
        }
    }
    return CST_OK;
}

static CstStatus plymesh(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g)
{
    const char *file = NULL;
    Loc fl = loc;
    TRY(get_string(ld, ps, d, "filename", &file, &fl));
    if (!file || !file[0])
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the PLY file", d);
    TRY(check_file_access(ld, fl, d));
    char *path = resolve_path(ld, file);
    if (!path) return oom(ld);
    ImportedMesh im = {0};
    CstStatus st = mesh_import(path, &im, ld->err);
    free(path);
    if (st) return fail_wrap(ld, st, fl, d);
    st = geom_alloc(ld, g, im.num_vertices, im.num_triangles, im.normals != NULL, im.uvs != NULL);
    if (!st) {
        memcpy(g->p, im.positions, (size_t)im.num_vertices * sizeof *g->p);
        for (int i = 0; i < 3 * im.num_triangles; i++) g->idx[i] = im.indices[i];
        if (im.normals) memcpy(g->n, im.normals, (size_t)im.num_vertices * sizeof *g->n);
        if (im.uvs) memcpy(g->uv, im.uvs, (size_t)im.num_vertices * sizeof *g->uv);
    }
    mesh_import_free(&im);
    return st;
}

static CstStatus shape_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *type = NULL, nm[72], d[96];
    Params ps = {0};
    ShapeGeom g = {0};
    Loc tl;
    CstStatus st = expect_string(ld, lx, "Shape", "the shape type, as in \"trianglemesh\"", &type, &tl);
    if (!st) st = parse_params(ld, lx, &ps);
    if (st) goto done;
    snprintf(d, sizeof d, "Shape \"%s\"", clip(type, nm));
    if (!ld->in_world) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "Shape before WorldBegin; expected shapes in the world block");
        goto done;
    }
    int skip = 0;
    if (strcmp(type, "trianglemesh") == 0) {
        st = read_mesh_params(ld, &ps, d, loc, 3, &g);
    } else if (strcmp(type, "bilinearmesh") == 0) {
        st = read_mesh_params(ld, &ps, d, loc, 4, &g);
        if (!st)
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: each bilinear patch split into two "
                    "triangles (exact for planar patches)", d);
    } else if (strcmp(type, "loopsubdiv") == 0) {
        int levels = 3;
        st = get_int(ld, &ps, d, "levels", 3, &levels);
        if (!st) st = read_mesh_params(ld, &ps, d, loc, 3, &g);
        if (!st)
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: the control mesh is rendered without "
                    "subdivision", d);
    } else if (strcmp(type, "plymesh") == 0) {
        st = plymesh(ld, &ps, d, loc, &g);
    } else if (strcmp(type, "sphere") == 0) {
        float r = 1.0f, zmin = 0, zmax = 0, phimax = 360.0f;
        int hz0 = 0, hz1 = 0, hp = 0;
        st = get_float(ld, &ps, d, "radius", 1.0f, &r, NULL);
        if (!st) st = get_float(ld, &ps, d, "zmin", -r, &zmin, &hz0);
        if (!st) st = get_float(ld, &ps, d, "zmax", r, &zmax, &hz1);
        if (!st) st = get_float(ld, &ps, d, "phimax", 360.0f, &phimax, &hp);
        if (st) goto done;
        if (!(r > 0.0f)) {
            st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g; expected a radius > 0", d, (double)r);
            goto done;
        }
        if ((hz0 && zmin > -r) || (hz1 && zmax < r) || (hp && phimax < 360.0f))
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: partial sphere (zmin, zmax, phimax) "
                    "rendered as the full sphere", d);
        g.is_sphere = 1;
        g.radius = r;
    } else if (strcmp(type, "disk") == 0) {
        float h = 0.0f, r = 1.0f, ri = 0.0f, phimax = 360.0f;
        st = get_float(ld, &ps, d, "height", 0.0f, &h, NULL);
        if (!st) st = get_float(ld, &ps, d, "radius", 1.0f, &r, NULL);
        if (!st) st = get_float(ld, &ps, d, "innerradius", 0.0f, &ri, NULL);
        if (!st) st = get_float(ld, &ps, d, "phimax", 360.0f, &phimax, NULL);
        if (st) goto done;
        if (!(r > 0.0f) || !(ri >= 0.0f) || !(ri < r) || !(phimax > 0.0f) || !coords_ok(v3(r, h, 0.0f))) {
            st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g, innerradius %g, phimax %g; "
                         "expected 0 <= innerradius < radius and phimax > 0", d, (double)r,
                         (double)ri, (double)phimax);
            goto done;
        }
        st = disk_mesh(ld, h, r, ri, phimax, &g);
        if (!st)
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s tessellated into %d triangles of the same "
                    "total area", d, g.nt);
    } else if (strcmp(type, "cylinder") == 0 || strcmp(type, "cone") == 0 ||
               strcmp(type, "paraboloid") == 0 || strcmp(type, "hyperboloid") == 0 ||
               strcmp(type, "curve") == 0 || strcmp(type, "nurbs") == 0 ||
               strcmp(type, "heightfield") == 0) {
        skip = 1;
        params_mark_all_used(&ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported; skipped", d);
    } else {
        st = fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown shape \"%s\"; expected one of: "
                     "trianglemesh, plymesh, bilinearmesh, loopsubdiv, sphere, disk (or the "
                     "unsupported cylinder, cone, paraboloid, hyperboloid, curve)", clip(type, nm));
    }
    if (st || skip) goto done;
    params_warn_unused(ld, &ps, d);
    if (ld->cur_obj >= 0) {
        Object *o = &ld->objs[ld->cur_obj];
        if (ld->gs.area.active)
            warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: area lights inside ObjectBegin are not "
                    "supported (as in pbrt-v4); the shape does not emit", d);
        if (!GROW(o->shapes, o->cap, o->n + 1)) { st = oom(ld); goto done; }
        ObjShape *os = &o->shapes[o->n++];
        os->g = g;
        os->xf = ld->gs.ctm;
        os->reverse = ld->gs.reverse;
        os->material = ld->gs.material;
        os->loc = loc;
        memset(&g, 0, sizeof g);
    } else {
        st = emit_shape(ld, &g, &ld->gs.ctm, ld->gs.reverse, ld->gs.material, &ld->gs.area, loc, d);
    }
done:
    geom_free(&g);
    free(type);
    params_free(&ps);
    return st;
}

/* The object's triangles, placed by their definition transforms with pbrt's orientation
 * rule (as emit_shape does), as one instanced object of the scene. Degenerate triangles
 * are dropped; an object without triangles gets no prototype. */
static CstStatus make_proto(Loader *ld, Object *obj, const char *d)
{
    int nv = 0, nt = 0;
    for (int i = 0; i < obj->n; i++)
        if (!obj->shapes[i].g.is_sphere) {
            if (obj->shapes[i].g.nv > INT_MAX - nv || obj->shapes[i].g.nt > PBRT_MAX_TRIANGLES - nt)
                return fail_at(ld, CST_ERR_UNSUPPORTED, obj->loc, "%s: the object has too many triangles", d);
            nv += obj->shapes[i].g.nv;
            nt += obj->shapes[i].g.nt;
        }
    if (nt == 0) return CST_OK;
    CstStatus st = CST_OK;
    int any_n = 0; /* vertex normals (N) on some shape: shading normals, zero where none */
    for (int i = 0; i < obj->n; i++) any_n |= !obj->shapes[i].g.is_sphere && obj->shapes[i].g.n != NULL;
    Vec3 *p = malloc((size_t)nv * sizeof *p), *n = any_n ? calloc((size_t)nv, sizeof *n) : NULL;
    int *idx = malloc((size_t)nt * 3 * sizeof *idx), *mat = malloc((size_t)nt * sizeof *mat);
    int vbase = 0, t_out = 0, dropped = 0;
    if (!p || !idx || !mat || (any_n && !n)) {
        st = oom(ld);
        goto done;
    }
    for (int i = 0; i < obj->n && !st; i++) {
        const ObjShape *os = &obj->shapes[i];
        const ShapeGeom *g = &os->g;
        if (g->is_sphere) continue;
        int m = 0;
        if ((st = material_scene_id(ld, os->material, &m))) goto done;
        int swap = (transform_det(&os->xf.m) < 0.0) != (os->reverse != 0);
        Transform nm = transform_identity();
        transform_normal_matrix(&os->xf.m, &nm);
        for (int v = 0; v < g->nv; v++) {
            p[vbase + v] = transform_point(&os->xf.m, g->p[v]);
            if (g->n) n[vbase + v] = transform_normal(&nm, g->n[v]);
            if (!coords_ok(p[vbase + v])) {
                st = fail_at(ld, CST_ERR_INVALID_ARG, os->loc, "%s: vertex %d of the object is beyond "
                             "the scene limit", d, v);
                goto done;
            }
        }
        for (int t = 0; t < g->nt; t++) {
            int a = g->idx[3 * t], b = g->idx[3 * t + 1], c = g->idx[3 * t + 2];
            int sw = swap;
            if (g->n) {
                Vec3 na = transform_normal(&nm, g->n[a]), nb = transform_normal(&nm, g->n[b]),
                     nc = transform_normal(&nm, g->n[c]);
                Vec3 ns = v3_add(v3_add(na, nb), nc);
                if (os->reverse) ns = v3_neg(ns);
                Vec3 ng = v3_cross(v3_sub(p[vbase + b], p[vbase + a]), v3_sub(p[vbase + c], p[vbase + a]));
                sw = v3_dot(ng, ns) < 0.0f;
            }
            if (!(triangle_area(p[vbase + a], p[vbase + b], p[vbase + c]) > 0.0f)) {
                dropped++;
                continue;
            }
            idx[3 * t_out] = vbase + a;
            idx[3 * t_out + 1] = vbase + (sw ? c : b);
            idx[3 * t_out + 2] = vbase + (sw ? b : c);
            mat[t_out++] = m;
        }
        vbase += g->nv;
    }
    if (dropped)
        warn_at(ld, CST_WARN_GEOMETRY, obj->loc, "ObjectBegin \"%s\": %d degenerate triangles dropped",
                obj->name, dropped);
    if (t_out > 0) {
        st = scene_add_instance_proto(ld->scene, p, n, nv, idx, mat, t_out, &obj->proto, ld->err);
        if (st) st = fail_wrap(ld, st, obj->loc, d);
    }
done:
    free(p);
    free(n);
    free(idx);
    free(mat);
    return st;
}

static CstStatus object_instance_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *name = NULL, nm[72];
    Loc nl;
    TRY(expect_string(ld, lx, "ObjectInstance", "the object's name", &name, &nl));
    CstStatus st = CST_OK;
    int o = -1;
    for (int i = 0; i < ld->num_objs; i++)
        if (strcmp(ld->objs[i].name, name) == 0) o = i;
    if (!ld->in_world)
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectInstance before WorldBegin; expected it in the world block");
    else if (ld->cur_obj >= 0)
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectInstance inside ObjectBegin \"%s\"; "
                     "expected instances outside object definitions", clip(ld->objs[ld->cur_obj].name, nm));
    else if (o < 0)
        st = fail_at(ld, CST_ERR_INVALID_ARG, nl, "ObjectInstance: object \"%s\" is not defined; "
                     "expected a name given to ObjectBegin before", clip(name, nm));
    if (st) {
        free(name);
        return st;
    }
    char d[96];
    snprintf(d, sizeof d, "ObjectInstance \"%s\"", clip(name, nm));
    free(name);
    Object *obj = &ld->objs[o];
    if (obj->proto < 0) {
        st = make_proto(ld, obj, d);
        if (st) return st;
    }
    if (obj->proto >= 0) {
        Xf xf = ld->gs.ctm;
        Transform inv;
        if (!transform_invert(&xf.m, &inv)) {
            /* flat (Scale 0) or not finite when inverted: nothing a ray could hit */
            warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: the instance transform is singular; skipped", d);
        } else {
            st = scene_add_instance(ld->scene, obj->proto, &xf.m, ld->err);
            if (st) return fail_wrap(ld, st, loc, d);
        }
    }
    /* Spheres are not instanced (the prototypes hold triangles): they are placed as copies. */
    for (int i = 0; i < obj->n && !st; i++) {
        const ObjShape *os = &obj->shapes[i];
        if (!os->g.is_sphere) continue;
        if (ld->num_instances_expanded++ == 0)
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: spheres in instanced objects are placed "
                    "as copies (only triangles are instanced)", d);
        Xf xf = xf_compose(&ld->gs.ctm, &os->xf);
        st = emit_shape(ld, &os->g, &xf, os->reverse, os->material, NULL, loc, d);
    }
    return st;
}

/* ------------------------------------------------------------------ camera and options */

static CstStatus camera_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *type = NULL, nm[72], d[96];
    Params ps = {0};
    Loc tl;
    CstStatus st = expect_string(ld, lx, "Camera", "the camera type, as in \"perspective\"", &type, &tl);
    if (!st) st = parse_params(ld, lx, &ps);
    if (st) goto done;
    snprintf(d, sizeof d, "Camera \"%s\"", clip(type, nm));
    if (ld->in_world) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "Camera after WorldBegin; expected the camera before WorldBegin");
        goto done;
    }
    int ortho = strcmp(type, "orthographic") == 0;
    if (strcmp(type, "perspective") != 0 && !ortho) {
        st = fail_at(ld, CST_ERR_UNSUPPORTED, tl, "%s is not supported; expected \"perspective\" or "
                     "\"orthographic\" (caustic has pinhole, thin-lens and orthographic cameras)", d);
        goto done;
    }
    if (!ld->gs.ctm.inv_ok) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the camera transform is singular; expected "
                     "an invertible transform (as from LookAt)", d);
        goto done;
    }
    CamRec *c = &ld->cam;
    memset(c, 0, sizeof *c);
    c->set = 1;
    c->ctm = ld->gs.ctm;
    c->loc = loc;
    c->ortho = ortho;
    c->fov = 90.0f;
    Param *p;
    if (!ortho && (st = get_float(ld, &ps, d, "fov", 90.0f, &c->fov, NULL))) goto done;
    if ((st = get_float(ld, &ps, d, "lensradius", 0.0f, &c->lens_radius, NULL))) goto done;
    if ((st = get_float(ld, &ps, d, "focaldistance", 1e6f, &c->focal_distance, NULL))) goto done;
    if ((st = get_float(ld, &ps, d, "frameaspectratio", 0.0f, &c->frame, &c->has_frame))) goto done;
    if ((st = lookup(ld, &ps, d, "screenwindow", M(PT_FLOAT), "float", &p))) goto done;
    if (p) {
        if (p->num_nums != 4) {
            st = fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"float screenwindow\" has %d values; "
                         "expected 4: xmin xmax ymin ymax", d, p->num_nums);
            goto done;
        }
        memcpy(c->screen, p->nums, sizeof c->screen);
        c->has_screen = 1;
        if (!(c->screen[1] > c->screen[0]) || !(c->screen[3] > c->screen[2])) {
            st = fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: screenwindow (%g %g %g %g) is empty; "
                         "expected xmin < xmax and ymin < ymax", d, c->screen[0], c->screen[1],
                         c->screen[2], c->screen[3]);
            goto done;
        }
    }
    if (!(c->fov > 0.0f && c->fov < 180.0f)) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: fov %g; expected degrees in (0, 180)", d, (double)c->fov);
        goto done;
    }
    if (!(c->lens_radius >= 0.0f) || !(c->focal_distance > 0.0f) || (c->has_frame && !(c->frame > 0.0f))) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: lensradius %g, focaldistance %g, "
                     "frameaspectratio %g; expected lensradius >= 0 and the others > 0", d,
                     (double)c->lens_radius, (double)c->focal_distance, (double)c->frame);
        goto done;
    }
    if (ortho && c->lens_radius > 0.0f) {
        /* pbrt-v4's orthographic camera can have a thin lens; caustic's cannot. */
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: lensradius %g and focaldistance %g ignored: "
                "caustic's orthographic camera is always in focus", d, (double)c->lens_radius,
                (double)c->focal_distance);
        c->lens_radius = 0.0f;
    }
    params_warn_unused(ld, &ps, d);
    /* pbrt names the camera's space "camera": world-from-camera for CoordSysTransform. */
    st = set_named_xf(ld, "camera", xf_swap(c->ctm));
done:
    free(type);
    params_free(&ps);
    return st;
}

/* The CameraDesc equal to pbrt's view: position and axes from world-from-camera; pbrt's
 * image right is the camera's +x, ours forward x up, so a frame where those disagree
 * (every plain LookAt: x = up x dir) is rendered mirrored (Scene.camera_mirror). fov spans the shorter image
 * axis in pbrt and the vertical one in caustic. */
static CstStatus camera_finish(Loader *ld)
{
    CamRec c = ld->cam;
    if (!c.set) { /* pbrt's default: at the origin looking down +z, fov 90 */
        c.ctm = xf_identity();
        c.fov = 90.0f;
        c.focal_distance = 1e6f;
        c.loc = ld->end;
    }
    const Transform *w = &c.ctm.inv;
    CameraDesc desc = {0};
    desc.position = transform_point(w, v3s(0.0f));
    Vec3 f = transform_vector(w, v3(0.0f, 0.0f, 1.0f));
    Vec3 u = transform_vector(w, v3(0.0f, 1.0f, 0.0f));
    Vec3 x = transform_vector(w, v3(1.0f, 0.0f, 0.0f));
    float fl = v3_length(f);
    if (!coords_ok(desc.position) || !(fl > 0.0f) || !isfinite(fl) || !v3_is_finite(u) ||
        !(v3_length(v3_cross(f, u)) > 1e-6f * fl * v3_length(u)))
        return fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: the camera transform gives no usable "
                       "view (position (%g, %g, %g)); expected an invertible, finite transform",
                       (double)desc.position.x, (double)desc.position.y, (double)desc.position.z);
    f = v3_scale(f, 1.0f / fl);
    /* look_at a power-of-two multiple of the unit forward away, at least |position|: the
     * scaling is exact and the difference look_at - position loses at most an ulp. */
    float s = 1.0f;
    while (s < v3_max_abs(desc.position) && s < 1e30f) s *= 2.0f;
    desc.look_at = v3_add(desc.position, v3_scale(f, s));
    desc.up = u;
    int mirror = v3_dot(x, v3_cross(f, u)) < 0.0f;
    int w_px = ld->scene->settings.width, h_px = ld->scene->settings.height;
    double aspect = (double)w_px / (double)h_px;
    double frame = c.has_frame ? (double)c.frame : aspect;
    /* pbrt's default screen window spans [-1, 1] on the shorter axis. */
    double sx0, sx1, sy0, sy1;
    if (frame > 1.0) { sx0 = -frame; sx1 = frame; sy0 = -1.0; sy1 = 1.0; }
    else { sx0 = -1.0; sx1 = 1.0; sy0 = -1.0 / frame; sy1 = 1.0 / frame; }
    if (c.has_screen) { sx0 = c.screen[0]; sx1 = c.screen[1]; sy0 = c.screen[2]; sy1 = c.screen[3]; }
    double half_h = 0.5 * (sy1 - sy0), half_w = 0.5 * (sx1 - sx0);
    if (fabs(sx0 + sx1) > 1e-6 * half_w || fabs(sy0 + sy1) > 1e-6 * half_h)
        warn_at(ld, CST_WARN_APPROXIMATED, c.loc, "Camera: off-centre screenwindow (%g %g %g %g) "
                "rendered centred with the same size", sx0, sx1, sy0, sy1);
    if (fabs(half_w / half_h - aspect) > 1e-4 * aspect)
        warn_at(ld, CST_WARN_APPROXIMATED, c.loc, "Camera: screen window aspect %g differs from "
                "the film's %g; the vertical extent is kept and the image is not stretched",
                half_w / half_h, aspect);
    if (c.ortho) {
        /* pbrt's orthographic rays leave the screen window at z = 0 in camera space, so the
         * view's height is the window's, in camera units scaled into the world. */
        desc.vfov_deg = 90.0f; /* unused */
        desc.ortho_height = (float)(2.0 * half_h * (double)v3_length(u));
        if (!(desc.ortho_height > 0.0f) || !isfinite(desc.ortho_height))
            return fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: the orthographic view is %g high; "
                           "expected a finite height > 0 (from screenwindow and the transform)",
                           (double)desc.ortho_height);
    } else if (half_h == 1.0) {
        desc.vfov_deg = c.fov; /* the common case, bit for bit */
    } else {
        double t = tan((double)c.fov * PBRT_PI / 360.0) * half_h;
        desc.vfov_deg = (float)(360.0 / PBRT_PI * atan(t));
    }
    if (!(desc.vfov_deg > 0.0f && desc.vfov_deg < 180.0f))
        return fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: fov %g with this screen window gives a "
                       "vertical field of view of %g degrees; expected less than 180",
                       (double)c.fov, (double)desc.vfov_deg);
    desc.aperture_radius = c.lens_radius;
    desc.focus_distance = c.focal_distance;
    scene_set_camera(ld->scene, &desc);
    ld->scene->camera_mirror = mirror;
    return CST_OK;
}

static CstStatus get_point3(Loader *ld, Params *ps, const char *d, const char *name, Vec3 def, Vec3 *out)
{
    Param *p;
    *out = def;
    TRY(lookup(ld, ps, d, name, M(PT_POINT3), "point3", &p));
    if (!p) return CST_OK;
    char nm[72];
    if (p->num_nums != 3)
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" has %d values; expected 3", d,
                       clip(p->decl, nm), p->num_nums);
    *out = v3((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]);
    if (!coords_ok(*out))
        return fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" is beyond the scene limit", d,
                       clip(p->decl, nm));
    return CST_OK;
}

/* Clarberg's equal-area octahedral map ("Fast Equal-Area Mapping of the (Hemi)Sphere using
 * SIMD", JGT 2008), which pbrt-v4 uses for the images of infinite lights
 * (EqualAreaSphereToSquare / EqualAreaSquareToSphere): the square's centre is +z, its
 * corners -z, u = 1 is +x and v = 1 is +y; equal areas of the square cover equal solid
 * angles. Here with the exact arctangent where pbrt uses a polynomial fit of it. */
void pbrt_equal_area_sphere_to_square(const double d[3], double uv[2])
{
    double x = fabs(d[0]), y = fabs(d[1]), z = fabs(d[2]);
    double r = sqrt(fmax(0.0, 1.0 - z));
    double a = fmax(x, y), b = fmin(x, y);
    double phi = atan(a == 0.0 ? 0.0 : b / a) * (2.0 / PBRT_PI);
    if (x < y) phi = 1.0 - phi;
    double v = phi * r, u = r - v;
    if (d[2] < 0.0) {
        double t = u;
        u = 1.0 - v;
        v = 1.0 - t;
    }
    uv[0] = 0.5 * (copysign(u, d[0]) + 1.0);
    uv[1] = 0.5 * (copysign(v, d[1]) + 1.0);
}

void pbrt_equal_area_square_to_sphere(const double uv[2], double d[3])
{
    double u = 2.0 * uv[0] - 1.0, v = 2.0 * uv[1] - 1.0, up = fabs(u), vp = fabs(v);
    double sd = 1.0 - (up + vp), r = 1.0 - fabs(sd);
    double phi = (r == 0.0 ? 1.0 : (vp - up) / r + 1.0) * (PBRT_PI / 4.0);
    double s = r * sqrt(fmax(0.0, 2.0 - r * r));
    d[0] = copysign(cos(phi), u) * s;
    d[1] = copysign(sin(phi), v) * s;
    d[2] = copysign(1.0 - r * r, sd);
}

/* The pixel of a w x h image (row 0 at the top, as pbrt and image_read store it) that an
 * infinite light shows in light-space direction d: nearest lookup as pbrt-v4's
 * ImageInfiniteLight does. Square images use the equal-area map; others pbrt-v3's
 * equirectangular one (+z up: u = phi / 2 pi, phi = atan2(y, x), v = theta / pi). */
static size_t env_source_pixel(const double d[3], int w, int h)
{
    double uv[2];
    if (w == h) {
        pbrt_equal_area_sphere_to_square(d, uv);
    } else {
        double phi = atan2(d[1], d[0]);
        if (phi < 0.0) phi += 2.0 * PBRT_PI;
        uv[0] = phi / (2.0 * PBRT_PI);
        uv[1] = acos(fmax(-1.0, fmin(1.0, d[2]))) / PBRT_PI;
    }
    int x = (int)(uv[0] * w), y = (int)(uv[1] * h);
    x = x < 0 ? 0 : x >= w ? w - 1 : x;
    y = y < 0 ? 0 : y >= h ? h - 1 : y;
    return (size_t)y * (size_t)w + (size_t)x;
}

/* pbrt-v4's "illuminance" normaliser of an image light: over the pixels whose direction has
 * light-space z > 0, the sum of luminance times cos theta, times 2 pi / (number of pixels)
 * (lights.cpp, Light::Create). A pixel covers 4 pi / (number of pixels) sr, so this is half
 * the patch's illuminance; kept, so that the image renders as bright as in pbrt. Non-square
 * (equirectangular) images get the same half from their pixels' solid angles. */
static double env_illuminance(const float *px, int w, int h)
{
    double sum = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double d[3], uv[2] = {(x + 0.5) / w, (y + 0.5) / h}, dw;
            if (w == h) {
                pbrt_equal_area_square_to_sphere(uv, d);
                dw = 2.0 * PBRT_PI / ((double)w * h);
            } else {
                double th = PBRT_PI * uv[1];
                d[2] = cos(th);
                dw = 0.5 * (2.0 * PBRT_PI / w) * (PBRT_PI / h) * sin(th); /* half of the pixel's sr, as above */
            }
            if (d[2] <= 0.0) continue;
            const float *p = &px[3 * ((size_t)y * (size_t)w + (size_t)x)];
            sum += (0.2126 * (double)p[0] + 0.7152 * (double)p[1] + 0.0722 * (double)p[2]) * d[2] * dw;
        }
    return sum;
}

/* LightSource "infinite": the scene's environment (lights/envmap.h). A constant one is
 * L x scale, with pbrt-v4's "illuminance" E making it L x scale x E / pi (the illuminance of a
 * uniform unit sky on an upward patch is pi). An image is resampled once, at load, into
 * caustic's equirectangular map (+y up, theta = acos(w.y), phi = atan2(w.z, w.x)): each
 * pixel takes, by nearest lookup, the source pixel its centre direction sees through the
 * light's transform (light-from-world, so any rotation is exact up to the resampling). A
 * square source of N x N becomes 2N x N (each new pixel covers at most the solid angle of
 * a source pixel, pi^2/N^2 against 4 pi/N^2 sr); others keep their size. */
static CstStatus infinite_light(Loader *ld, Params *ps, Loc loc, const char *d)
{
    char nm[72];
    if (ld->env_set) {
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: caustic has one environment and an infinite "
                "light was given before; skipped", d);
        return CST_OK;
    }
    Color c = color_s(1.0f);
    float scale = 1.0f, illum = 0.0f;
    int has_l = 0;
    const char *file = NULL;
    Loc fl = loc;
    Param *pp;
    TRY(get_spectrum(ld, ps, d, "L", SPEC_ILLUMINANT, 0, &c, &has_l));
    TRY(get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(get_float(ld, ps, d, "illuminance", 0.0f, &illum, NULL));
    TRY(get_string(ld, ps, d, "filename", &file, &fl));
    if (file && !file[0]) file = NULL; /* pbrt: an empty name is no image */
    TRY(lookup(ld, ps, d, "portal", M(PT_POINT3), "point3", &pp));
    if (pp)
        warn_at(ld, CST_WARN_PARAMETER_IGNORED, pp->loc, "%s: \"portal\" is not supported; the "
                "environment lights the scene from every direction", d);
    if (file && has_l)
        return fail_at(ld, CST_ERR_INVALID_ARG, fl, "%s: both \"L\" and \"filename\"; expected one "
                       "of them (as pbrt-v4)", d);
    if (!(scale >= 0.0f))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g; expected a finite scale >= 0", d,
                       (double)scale);
    EnvMap env;
    CstStatus st;
    if (!file) {
        double k = (double)scale * (illum > 0.0f ? (double)illum / PBRT_PI : 1.0);
        Color L = color_scale(c, (float)k);
        if (!color_is_finite(L))
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the radiance is not finite", d);
        TRY(envmap_init_constant(&env, L, ld->err));
    } else {
        if (!ld->gs.ctm.inv_ok)
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's transform is singular; "
                           "expected an invertible transform", d);
        TRY(check_file_access(ld, fl, d));
        char *path = resolve_path(ld, file);
        if (!path) return oom(ld);
        float *src = NULL;
        int w = 0, h = 0;
        st = image_read(path, &src, &w, &h, ld->err);
        free(path);
        if (st) return fail_wrap(ld, st, fl, d);
        size_t n = 3u * (size_t)w * (size_t)h;
        for (size_t i = 0; i < n; i++)
            if (!isfinite(src[i])) {
                free(src);
                return fail_at(ld, CST_ERR_INVALID_ARG, fl, "%s: \"%s\" has infinite or NaN pixels; "
                               "expected finite radiance (as pbrt-v4)", d, clip(file, nm));
            }
        if (w != h)
            warn_at(ld, CST_WARN_APPROXIMATED, fl, "%s: \"%s\" is %d x %d, not square: pbrt-v4 "
                    "expects an equal-area (square) image; read as an equirectangular map in "
                    "pbrt-v3's convention (+z up in light space)", d, clip(file, nm), w, h);
        double k = (double)scale;
        if (illum > 0.0f) {
            double e = env_illuminance(src, w, h);
            k = e > 0.0 ? k * (double)illum / e : k;
        }
        int ow = w == h ? 2 * w : w, oh = h;
        if (oh > 4096) { /* cap the copy at 8192 x 4096 (400 MB of floats) */
            ow = (int)((long long)ow * 4096 / oh);
            oh = 4096;
        }
        float *out = malloc(3u * (size_t)ow * (size_t)oh * sizeof *out);
        if (!out) {
            free(src);
            return oom(ld);
        }
        const Transform *li = &ld->gs.ctm.inv; /* light-from-world */
        for (int y = 0; y < oh; y++) {
            double th = PBRT_PI * (y + 0.5) / oh;
            for (int x = 0; x < ow; x++) {
                double ph = 2.0 * PBRT_PI * (x + 0.5) / ow;
                double wv[3] = {sin(th) * cos(ph), cos(th), sin(th) * sin(ph)}, dl[3], len = 0.0;
                for (int r = 0; r < 3; r++) {
                    dl[r] = (double)li->m[r][0] * wv[0] + (double)li->m[r][1] * wv[1] + (double)li->m[r][2] * wv[2];
                    len += dl[r] * dl[r];
                }
                len = sqrt(len);
                for (int r = 0; r < 3; r++) dl[r] /= len;
                const float *p = &src[3 * env_source_pixel(dl, w, h)];
                float *o = &out[3 * ((size_t)y * (size_t)ow + (size_t)x)];
                for (int ch = 0; ch < 3; ch++) o[ch] = p[ch] > 0.0f ? p[ch] : 0.0f; /* pbrt: ClampZero */
            }
        }
        free(src);
        if (!isfinite(k))
            k = 0.0;
        st = envmap_init_image(&env, out, ow, oh, color_s((float)k), ld->err);
        if (st) return fail_wrap(ld, st, fl, d);
    }
    st = scene_set_environment(ld->scene, &env, ld->err);
    if (st) return fail_wrap(ld, st, loc, d);
    ld->env_set = 1;
    return CST_OK;
}

/* LightSource: point, spot and distant as caustic's delta lights, placed by the CTM, with
 * pbrt-v4's scale and power (phi / 4 pi for a point; phi / (2 pi (1 - (cos_start +
 * cos_end) / 2)) for a spot) and illuminance for a distant light; as for area lights an
 * "rgb" spectrum is used as given and blackbody and sampled spectra are normalised to
 * luminance 1 first. "infinite" becomes the environment (infinite_light); others are
 * skipped with a warning. */
static CstStatus light_source(Loader *ld, const char *type, Params *ps, Loc loc, const char *d)
{
    int point = strcmp(type, "point") == 0, spot = strcmp(type, "spot") == 0,
        distant = strcmp(type, "distant") == 0;
    if (strcmp(type, "infinite") == 0) return infinite_light(ld, ps, loc, d);
    if (!point && !spot && !distant) {
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported (caustic has area, point, "
                "spot, distant and infinite lights); skipped", d);
        return CST_OK;
    }
    DeltaLight l;
    memset(&l, 0, sizeof l);
    Color c = color_s(1.0f);
    float scale = 1.0f, power = 0.0f, illum = 0.0f;
    TRY(get_spectrum(ld, ps, d, distant ? "L" : "I", SPEC_ILLUMINANT, 0, &c, NULL));
    TRY(get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    if (distant) TRY(get_float(ld, ps, d, "illuminance", 0.0f, &illum, NULL));
    else TRY(get_float(ld, ps, d, "power", 0.0f, &power, NULL));
    Vec3 from, to;
    TRY(get_point3(ld, ps, d, "from", v3s(0.0f), &from));
    TRY(get_point3(ld, ps, d, "to", v3(0.0f, 0.0f, 1.0f), &to));
    if (point) { /* pbrt-v4 reads no "to" for a point light */
        Param *pt = find_param(ps, "to");
        if (pt) pt->used = 0;
    }
    const Transform *m = &ld->gs.ctm.m;
    double k = (double)scale;
    if (point || spot) {
        l.type = point ? DELTA_POINT : DELTA_SPOT;
        l.p = transform_point(m, from);
        if (spot) {
            float cone = 30.0f, delta = 5.0f;
            TRY(get_float(ld, ps, d, "coneangle", 30.0f, &cone, NULL));
            TRY(get_float(ld, ps, d, "conedelta", 5.0f, &delta, NULL));
            if (!(cone > 0.0f && cone <= 90.0f) || !(delta >= 0.0f && delta <= cone))
                return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: coneangle %g, conedelta %g; expected "
                               "0 < coneangle <= 90 and 0 <= conedelta <= coneangle", d,
                               (double)cone, (double)delta);
            l.cos_outer = cosf(cone * (CST_PI / 180.0f));
            l.cos_inner = cosf((cone - delta) * (CST_PI / 180.0f));
            Vec3 axis = transform_vector(m, v3_sub(to, from));
            float len = v3_length(axis);
            if (!(len > 0.0f) || !isfinite(len))
                return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: \"from\" equals \"to\"; expected the "
                               "spot's axis", d);
            l.dir = v3_scale(axis, 1.0f / len);
            if (power > 0.0f)
                k *= (double)power / (2.0 * PBRT_PI * (1.0 - 0.5 * ((double)l.cos_inner + (double)l.cos_outer)));
        } else if (power > 0.0f) {
            k *= (double)power / (4.0 * PBRT_PI);
        }
        if (!coords_ok(l.p))
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's position is beyond the scene limit", d);
    } else {
        l.type = DELTA_DIRECTIONAL;
        Vec3 dir = transform_vector(m, v3_sub(to, from)); /* the way the light travels */
        float len = v3_length(dir);
        if (!(len > 0.0f) || !isfinite(len))
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: \"from\" equals \"to\"; expected the "
                           "light's direction", d);
        l.dir = v3_scale(dir, 1.0f / len);
        if (illum > 0.0f) k *= (double)illum;
    }
    l.intensity = color_scale(c, (float)k);
    if (!color_is_finite(l.intensity) || !(k >= 0.0))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g gives an intensity that is negative "
                       "or not finite", d, (double)scale);
    CstStatus st = scene_add_delta_light(ld->scene, &l, ld->err);
    return st ? fail_wrap(ld, st, loc, d) : CST_OK;
}

/* ------------------------------------------------------------------ directives: rendering options */

/* Film, Sampler, Integrator, PixelFilter, Accelerator, ColorSpace, MakeNamedMedium, Attribute:
 * a type name and parameters, mapped to settings or reported. */
static CstStatus film_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->scene->settings;
    int w = 1280, h = 720;
    const char *file = NULL;
    Loc fl = loc;
    TRY(get_int(ld, ps, d, "xresolution", 1280, &w));
    TRY(get_int(ld, ps, d, "yresolution", 720, &h));
    TRY(get_string(ld, ps, d, "filename", &file, &fl));
    if (w < 1 || h < 1 || w > PBRT_MAX_FILM_SIZE || h > PBRT_MAX_FILM_SIZE) {
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: resolution %d x %d; expected 1 to %d "
                     "pixels on each side", d, w, h, PBRT_MAX_FILM_SIZE);
    }
    rs->width = w;
    rs->height = h;
    if (file && image_path_is_scene_output(file)) {
        TRY(scene_set_output_path(ld->scene, file, ld->err));
    } else if (file) {
        warn_at(ld, CST_WARN_UNSUPPORTED, fl, "%s: output \"%s\" is not .png, .exr or .pfm; "
                "ignored (the default output name is used)", d, clip(file, nm));
    }
    /* pbrt-v4 (film.cpp): cropwindow [x0 x1 y0 y1] in [0, 1], y down, to the pixel bounds
     * ceil(res * c); pixelbounds given directly, and preferred when both are. */
    Param *pc, *pb;
    TRY(lookup(ld, ps, d, "cropwindow", M(PT_FLOAT), "float", &pc));
    TRY(lookup(ld, ps, d, "pixelbounds", M(PT_INTEGER), "integer", &pb));
    if (pc && pb) {
        warn_at(ld, CST_WARN_APPROXIMATED, pc->loc, "%s: both cropwindow and pixelbounds given; "
                "pixelbounds is used", d);
        pc = NULL;
    }
    if (pc) {
        const double *c = pc->nums;
        if (pc->num_nums != 4 || !(0.0 <= c[0] && c[0] < c[1] && c[1] <= 1.0 && 0.0 <= c[2] && c[2] < c[3] &&
                                   c[3] <= 1.0)) {
            return fail_at(ld, CST_ERR_INVALID_ARG, pc->loc, "%s: cropwindow; expected 4 values x0 x1 y0 y1 with "
                         "0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1", d);
        }
        rs->crop[0] = (int)ceil(w * c[0]); rs->crop[1] = (int)ceil(w * c[1]);
        rs->crop[2] = (int)ceil(h * c[2]); rs->crop[3] = (int)ceil(h * c[3]);
        if (rs->crop[0] == rs->crop[1] || rs->crop[2] == rs->crop[3]) {
            return fail_at(ld, CST_ERR_INVALID_ARG, pc->loc, "%s: cropwindow holds no pixel of the %d x %d "
                         "image; expected a wider window", d, w, h);
        }
    }
    if (pb) {
        const double *b = pb->nums;
        if (pb->num_nums != 4 || !(0.0 <= b[0] && b[0] < b[1] && b[1] <= w && 0.0 <= b[2] && b[2] < b[3] &&
                                   b[3] <= h)) {
            return fail_at(ld, CST_ERR_INVALID_ARG, pb->loc, "%s: pixelbounds; expected 4 integers x0 x1 y0 y1 "
                         "with 0 <= x0 < x1 <= %d and 0 <= y0 < y1 <= %d", d, w, h);
        }
        for (int k = 0; k < 4; k++) rs->crop[k] = (int)b[k];
    }
    if (strcmp(type, "rgb") != 0 && strcmp(type, "image") != 0)
        warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s rendered as an RGB film", d);
    return CST_OK;
}

static CstStatus sampler_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    CstRenderSettings *rs = &ld->scene->settings;
    int spp = 16, seed = 0;
    Param *ps_seed = find_param(ps, "seed");
    if (strcmp(type, "stratified") == 0) {
        int xs = 4, ys = 4, jitter = 1;
        TRY(get_int(ld, ps, d, "xsamples", 4, &xs));
        TRY(get_int(ld, ps, d, "ysamples", 4, &ys));
        TRY(get_bool(ld, ps, d, "jitter", 1, &jitter));
        spp = (xs > 0 && ys > 0 && xs <= INT_MAX / ys) ? xs * ys : 0;
    } else {
        TRY(get_int(ld, ps, d, "pixelsamples", 16, &spp));
    }
    if (spp < 1) {
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: %d samples per pixel; expected at least 1", d, spp);
    }
    rs->spp = spp;
    TRY(get_int(ld, ps, d, "seed", 0, &seed));
    if (ps_seed) {
        if (seed < 0) {
            return fail_at(ld, CST_ERR_INVALID_ARG, ps_seed->loc, "%s: seed %d; expected >= 0", d, seed);
        }
        rs->seed = (uint64_t)seed;
        rs->seed_set = 1;
    }
    /* The nearest of caustic's samplers (sampling/sampler.c): same expectation; only
     * independent is the same kind of noise as pbrt's. */
    if (strcmp(type, "independent") == 0 || strcmp(type, "random") == 0) {
        rs->sampler = CST_SAMPLER_INDEPENDENT;
    } else if (strcmp(type, "stratified") == 0) {
        rs->sampler = CST_SAMPLER_STRATIFIED;
        warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: caustic's stratified sampler (jittered, 2D strata "
                "nx x ny = %d with nx the largest divisor up to its square root); same expectation, "
                "different noise", d, spp);
    } else {
        rs->sampler = CST_SAMPLER_SOBOL;
        warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: caustic's Owen-scrambled Sobol' sampler; same "
                "expectation, different noise", d);
    }
    return CST_OK;
}

static CstStatus integrator_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->scene->settings;
    static const struct { const char *pbrt; CstIntegrator ours; int exact; } map[] = {
        {"path", CST_INTEGRATOR_PATH, 1}, {"volpath", CST_INTEGRATOR_PATH, 0},
        {"simplepath", CST_INTEGRATOR_PATH_NEE, 0}, {"randomwalk", CST_INTEGRATOR_PATH_BSDF, 0},
        {"lightpath", CST_INTEGRATOR_LIGHT, 1}, {"sppm", CST_INTEGRATOR_SPPM, 1},
        {"whitted", CST_INTEGRATOR_WHITTED, 1}, {"bdpt", CST_INTEGRATOR_BDPT, 1},
        {"mlt", CST_INTEGRATOR_PATH, 0}, {"simplevolpath", CST_INTEGRATOR_PATH, 0},
        {"directlighting", CST_INTEGRATOR_PATH, 0}, {"ambientocclusion", CST_INTEGRATOR_PATH, 0},
        {"aov", CST_INTEGRATOR_PATH, 0}};
    int k = -1;
    for (int i = 0; i < (int)(sizeof map / sizeof map[0]); i++)
        if (strcmp(type, map[i].pbrt) == 0) k = i;
    if (k < 0) {
        return fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown integrator \"%s\"; expected one of: "
                     "path, volpath, simplepath, randomwalk, lightpath, bdpt, mlt, sppm, "
                     "simplevolpath, ambientocclusion, aov (pbrt-v3: whitted, directlighting)",
                     clip(type, nm));
    }
    rs->integrator = map[k].ours;
    int depth = 5;
    TRY(get_int(ld, ps, d, "maxdepth", 5, &depth));
    if (strcmp(type, "directlighting") == 0) depth = 1;
    if (depth == 0)
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: maxdepth 0 (emitters seen directly only) "
                "is not expressible; rendered with maxdepth 1", d);
    rs->max_depth = depth < 0 ? 0 : (depth == 0 ? 1 : depth); /* pbrt: < 0 never stops */
    if (map[k].ours == CST_INTEGRATOR_SPPM) {
        int photons = 0;
        float radius = 0.0f;
        int has_r = 0;
        TRY(get_int(ld, ps, d, "photonsperiteration", -1, &photons));
        TRY(get_float(ld, ps, d, "radius", 1.0f, &radius, &has_r));
        if (photons > 0) rs->photons = photons < (1 << 28) ? photons : (1 << 28);
        if (has_r && radius > 0.0f) rs->photon_radius = (double)radius;
        int iters = 0;
        TRY(get_int(ld, ps, d, "iterations", 0, &iters));
        if (iters > 0) rs->spp = iters;
    }
    if (strcmp(type, "ambientocclusion") == 0 || strcmp(type, "aov") == 0) {
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not supported; the path tracer renders "
                "the image instead", d);
    } else if (!map[k].exact) {
        warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s rendered with caustic's \"%s\" (the same "
                "expected image in scenes without participating media)", d,
                cst_integrator_name(map[k].ours));
    }
    return CST_OK;
}

static CstStatus pixel_filter_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->scene->settings;
    float rx = 0.0f, ry = 0.0f;
    int hx = 0, hy = 0;
    TRY(get_float(ld, ps, d, "xradius", 0.0f, &rx, &hx));
    TRY(get_float(ld, ps, d, "yradius", 0.0f, &ry, &hy));
    if (strcmp(type, "box") == 0) {
        rs->filter = CST_FILTER_BOX;
        if ((hx && rx != 0.5f) || (hy && ry != 0.5f))
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: radius other than 0.5 rendered as "
                    "the one-pixel box", d);
    } else if (strcmp(type, "triangle") == 0) {
        rs->filter = CST_FILTER_TENT;
        if (!hx || !hy || rx != 1.0f || ry != 1.0f)
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: rendered as caustic's tent of "
                    "radius 1 pixel (pbrt's default radius is 2)", d);
    } else if (strcmp(type, "gaussian") == 0 || strcmp(type, "mitchell") == 0) {
        /* caustic's are pbrt-v4's defaults (film/filter.c): Gaussian sigma 0.5 pixel,
         * radius 1.5, minus its value at the radius; Mitchell radius 2, B = C = 1/3. */
        int gauss = type[0] == 'g', hs = 0, hb = 0, hc = 0;
        float def_r = gauss ? 1.5f : 2.0f, sigma = 0.5f, b = 1.0f / 3.0f, c = 1.0f / 3.0f;
        rs->filter = gauss ? CST_FILTER_GAUSSIAN : CST_FILTER_MITCHELL;
        if (gauss) {
            TRY(get_float(ld, ps, d, "sigma", 0.5f, &sigma, &hs));
        } else {
            TRY(get_float(ld, ps, d, "B", b, &b, &hb));
            TRY(get_float(ld, ps, d, "C", c, &c, &hc));
        }
        if ((hx && rx != def_r) || (hy && ry != def_r) || (hs && sigma != 0.5f) ||
            (hb && fabsf(b - 1.0f / 3.0f) > 1e-6f) || (hc && fabsf(c - 1.0f / 3.0f) > 1e-6f))
            warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: rendered with caustic's %s filter, %s", d,
                    gauss ? "Gaussian" : "Mitchell", gauss ? "sigma 0.5 and radius 1.5 pixels"
                    : "B = C = 1/3 and radius 2 pixels");
    } else if (strcmp(type, "sinc") == 0 || strcmp(type, "lanczos") == 0) {
        rs->filter = CST_FILTER_MITCHELL;
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated by the Mitchell filter (B = C = "
                "1/3, radius 2 pixels), the nearest caustic has to a windowed sinc", d);
    } else {
        return fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown pixel filter \"%s\"; expected one of: "
                     "box, triangle, gaussian, mitchell, sinc", clip(type, nm));
    }
    return CST_OK;
}

static CstStatus accelerator_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc tl = call->tl;
    params_mark_all_used(ps);
    if (strcmp(type, "kdtree") == 0) ld->scene->accel_type = ACCEL_KDTREE;
    else if (strcmp(type, "bvh") != 0)
        warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not known; the BVH is used", d);
    return CST_OK;
}

static CstStatus color_space_directive(Loader *ld, NamedCall *call)
{
    const char *type = call->type, *d = call->d;
    Loc tl = call->tl;
    if (strcmp(type, "srgb") != 0)
        warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: RGB values are taken as linear sRGB", d);
    return CST_OK;
}

static CstStatus make_named_medium_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *d = call->d;
    Loc loc = call->loc;
    params_mark_all_used(ps);
    warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: participating media are not supported; ignored", d);
    return CST_OK;
}

static CstStatus attribute_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *d = call->d;
    Loc loc = call->loc;
    params_mark_all_used(ps);
    warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: default parameters by Attribute are not supported; ignored", d);
    return CST_OK;
}

/* Material and MakeNamedMaterial. */
static CstStatus material_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d, *dname = call->dname;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    if (!ld->in_world) {
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s before WorldBegin; expected materials in the world block", dname);
    }
    Material m = {0};
    const char *mt = type;
    if (dname[0] == 'M' && dname[1] == 'a' && dname[2] == 'k') {
        /* MakeNamedMaterial "name" "string type" "diffuse" ... */
        if (find_named_material(ld, type) >= 0) {
            return fail_at(ld, CST_ERR_INVALID_ARG, tl, "MakeNamedMaterial: \"%s\" is already "
                         "defined; expected each name once", clip(type, nm));
        }
        Loc l2 = loc;
        TRY(get_string(ld, ps, d, "type", &mt, &l2));
        if (!mt) {
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string type\"; expected the "
                         "material type, as in \"string type\" \"diffuse\"", d);
        }
    }
    TRY(make_material(ld, mt, ps, loc, &m));
    int id = 0;
    TRY(add_mat_entry(ld, dname[0] == 'M' && dname[2] == 'k' ? type : NULL, &m, &id));
    if (dname[2] != 'k') ld->gs.material = id;
    return CST_OK;
}

/* ------------------------------------------------------------------ directives: lights */

static CstStatus light_source_directive(Loader *ld, NamedCall *call)
{
    if (!ld->in_world)
        return fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "LightSource before WorldBegin; expected it in the world block");
    return light_source(ld, call->type, &call->ps, call->loc, call->d);
}

static CstStatus area_light_source_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    if (!ld->in_world) {
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "AreaLightSource before WorldBegin; expected it in the world block");
    }
    if (strcmp(type, "diffuse") != 0 && strcmp(type, "area") != 0) {
        params_mark_all_used(ps);
        warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not supported; the shapes that follow do not emit", d);
        ld->gs.area.active = 0;
    } else {
        AreaLight al = {1, color_s(1.0f), 1.0f, 0.0f, 0};
        Param *pl;
        TRY(lookup(ld, ps, d, "filename", M(PT_STRING), "string", &pl));
        if (pl) warn_at(ld, CST_WARN_UNSUPPORTED, pl->loc, "%s: image emission is not supported; \"L\" is used", d);
        TRY(get_spectrum(ld, ps, d, "L", SPEC_ILLUMINANT, 0, &al.L, NULL));
        TRY(get_float(ld, ps, d, "scale", 1.0f, &al.scale, NULL));
        TRY(get_float(ld, ps, d, "power", 0.0f, &al.power, NULL));
        TRY(get_bool(ld, ps, d, "twosided", 0, &al.two_sided));
        if (!(al.scale >= 0.0f) || !color_is_finite(color_scale(al.L, al.scale))) {
            return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g; expected a finite scale >= 0",
                         d, (double)al.scale);
        }
        ld->gs.area = al;
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ directives: transforms and state */

static CstStatus translate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[3];
    TRY(expect_numbers(ld, lx, dname, 3, v));
    Xf x = {transform_translate(v3((float)v[0], (float)v[1], (float)v[2])),
            transform_translate(v3(-(float)v[0], -(float)v[1], -(float)v[2])), 1};
    return apply_ctm(ld, x, loc, dname);
}

static CstStatus scale_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[3];
    TRY(expect_numbers(ld, lx, dname, 3, v));
    Vec3 sc = v3((float)v[0], (float)v[1], (float)v[2]);
    Xf x = {transform_scale(sc), transform_identity(), 0};
    if (sc.x != 0.0f && sc.y != 0.0f && sc.z != 0.0f) {
        x.inv = transform_scale(v3(1.0f / sc.x, 1.0f / sc.y, 1.0f / sc.z));
        x.inv_ok = 1;
    }
    return apply_ctm(ld, x, loc, dname);
}

static CstStatus rotate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[4];
    TRY(expect_numbers(ld, lx, dname, 4, v));
    Vec3 axis = v3((float)v[1], (float)v[2], (float)v[3]);
    if (!(v3_max_abs(axis) > 0.0f) || !v3_is_finite(axis))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "Rotate: axis (%g, %g, %g); expected a "
                       "nonzero finite axis", v[1], v[2], v[3]);
    Xf x = {transform_rotate_degrees(axis, v[0]), transform_rotate_degrees(axis, -v[0]), 1};
    return apply_ctm(ld, x, loc, dname);
}

static CstStatus look_at_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[9];
    TRY(expect_numbers(ld, lx, dname, 9, v));
    Xf x;
    if (!xf_look_at(v, v + 3, v + 6, &x))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "LookAt: eye equals look, or up is zero or "
                       "parallel to the view direction; expected eye != look and up not along "
                       "look - eye");
    return apply_ctm(ld, x, loc, dname);
}

/* Transform replaces the CTM, ConcatTransform multiplies it. */
static CstStatus transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    double v[16];
    TRY(expect_number_array(ld, lx, d, 16, v));
    /* The file lists the matrix column by column (pbrt transposes it on reading). */
    float rows[16];
    for (int r = 0; r < 4; r++)
        for (int c = 0; c < 4; c++) rows[4 * r + c] = (float)v[4 * c + r];
    Transform m = transform_from_rows(rows);
    if (!transform_is_affine(&m))
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: a projective or non-finite matrix; "
                       "expected an affine one (translation in elements 13-15, then 0 0 0 1 "
                       "in elements 4, 8, 12, 16)", d);
    Xf x = xf_from(m);
    if (d[0] == 'T') {
        if (!ld->active_start) return CST_OK;
        ld->gs.ctm = x;
        return CST_OK;
    }
    return apply_ctm(ld, x, loc, d);
}

static CstStatus identity_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)loc, (void)dname;
    if (ld->active_start) ld->gs.ctm = xf_identity();
    return CST_OK;
}

/* CoordinateSystem names the CTM, CoordSysTransform makes a named one current. */
static CstStatus coordinate_system_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    (void)loc;
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    int set = strcmp(d, "CoordinateSystem") == 0;
    Loc nl;
    TRY(expect_string(ld, lx, d, "a coordinate system name", &s, &nl));
    if (set) {
        st = set_named_xf(ld, s, ld->gs.ctm);
    } else {
        int i = find_named_xf(ld, s);
        if (i < 0) st = fail_at(ld, CST_ERR_INVALID_ARG, nl, "CoordSysTransform: \"%s\" is not defined; "
                                "expected a name given to CoordinateSystem (or \"camera\" after Camera)",
                                clip(s, nm));
        else ld->gs.ctm = ld->coords[i].xf;
    }
    free(s);
    return st;
}

static CstStatus active_transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    PbrtToken w;
    TRY(lex_next(ld, lx, &w));
    if (w.kind == PBRT_TOK_WORD && tok_is(&w, "StartTime")) { ld->active_start = 1; }
    else if (w.kind == PBRT_TOK_WORD && tok_is(&w, "EndTime")) {
        ld->active_start = 0;
        warn_at(ld, CST_WARN_UNSUPPORTED, loc, "ActiveTransform EndTime: motion blur is not "
                "supported; end-time transforms are ignored");
    } else if (w.kind == PBRT_TOK_WORD && tok_is(&w, "All")) { ld->active_start = 1; }
    else {
        char got[96];
        pbrt_token_describe(&w, got, sizeof got);
        return fail_at(ld, CST_ERR_PARSE, tok_loc(lx, &w), "ActiveTransform: got %s; expected "
                       "StartTime, EndTime or All", got);
    }
    return CST_OK;
}

static CstStatus transform_times_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    double v[2];
    TRY(expect_numbers(ld, lx, dname, 2, v));
    warn_at(ld, CST_WARN_UNSUPPORTED, loc, "TransformTimes: motion blur is not supported; ignored");
    return CST_OK;
}

static CstStatus reverse_orientation_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)loc, (void)dname;
    ld->gs.reverse = !ld->gs.reverse;
    return CST_OK;
}

/* AttributeBegin/End push and pop the whole graphics state, TransformBegin/End (pbrt-v3)
 * only the CTM. */
static CstStatus begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    return push_state(ld, loc, dname[0] == 'T');
}

static CstStatus end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    return pop_state(ld, loc, dname[0] == 'T', dname);
}

static CstStatus world_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx, (void)dname;
    if (ld->in_world)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "WorldBegin a second time; expected one world block");
    ld->in_world = 1;
    ld->gs.ctm = xf_identity();
    return set_named_xf(ld, "world", ld->gs.ctm);
}

/* pbrt-v3: the end of the file follows */
static CstStatus world_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)ld, (void)lx, (void)loc, (void)dname;
    return CST_OK;
}

/* ------------------------------------------------------------------ directives: objects */

static CstStatus object_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    Loc nl;
    TRY(expect_string(ld, lx, dname, "the object's name", &s, &nl));
    if (!ld->in_world) st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectBegin before WorldBegin; expected it in the world block");
    else if (ld->cur_obj >= 0)
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectBegin inside ObjectBegin \"%s\"; "
                     "expected ObjectEnd first", clip(ld->objs[ld->cur_obj].name, nm));
    for (int i = 0; !st && i < ld->num_objs; i++)
        if (strcmp(ld->objs[i].name, s) == 0)
            st = fail_at(ld, CST_ERR_INVALID_ARG, nl, "ObjectBegin: \"%s\" is already defined "
                         "(line %d); expected each name once", clip(s, nm), ld->objs[i].loc.line);
    if (!st) st = push_state(ld, loc, 0);
    if (!st && !GROW(ld->objs, ld->cap_objs, ld->num_objs + 1)) st = oom(ld);
    if (st) {
        free(s);
        return st;
    }
    Object *o = &ld->objs[ld->num_objs];
    memset(o, 0, sizeof *o);
    o->name = s;
    o->loc = loc;
    o->proto = -1;
    ld->cur_obj = ld->num_objs++;
    return CST_OK;
}

static CstStatus object_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    if (ld->cur_obj < 0)
        return fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectEnd without ObjectBegin; expected it "
                       "only to close an object definition");
    ld->cur_obj = -1;
    return pop_state(ld, loc, 0, dname);
}

/* ------------------------------------------------------------------ directives: materials */

static CstStatus named_material_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)loc;
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    Loc nl;
    TRY(expect_string(ld, lx, dname, "a material name", &s, &nl));
    int i = find_named_material(ld, s);
    if (i < 0)
        st = fail_at(ld, CST_ERR_INVALID_ARG, nl, "NamedMaterial: \"%s\" is not defined; expected "
                     "a name given to MakeNamedMaterial before", clip(s, nm));
    else
        ld->gs.material = i;
    free(s);
    return st;
}

/* ------------------------------------------------------------------ directives: ignored */

static CstStatus medium_interface_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    char *s = NULL;
    TRY(expect_string(ld, lx, dname, "the inside medium's name", &s, NULL));
    free(s);
    PbrtToken n2;
    TRY(lex_peek(ld, lx, &n2));
    if (n2.kind == PBRT_TOK_STRING) {
        TRY(expect_string(ld, lx, dname, "the outside medium's name", &s, NULL));
        free(s);
    }
    warn_at(ld, CST_WARN_UNSUPPORTED, loc, "MediumInterface: participating media are not supported; ignored");
    return CST_OK;
}

/* Option "type name" value: a single parameter, no type name before it */
static CstStatus option_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    Params ps = {0};
    CstStatus st = parse_params(ld, lx, &ps);
    if (!st) warn_at(ld, CST_WARN_UNSUPPORTED, loc, "Option is not supported; ignored");
    params_free(&ps);
    return st;
}

static CstStatus parse_text(Loader *ld, const char *text, size_t len, const char *name);

static CstStatus include_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    char *file = NULL;
    Loc fl;
    TRY(expect_string(ld, lx, d, "a file name", &file, &fl));
    CstStatus st = check_file_access(ld, fl, d);
    if (!st && ld->depth >= PBRT_MAX_INCLUDE_DEPTH)
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: more than %d nested includes (does a file "
                     "include itself?)", d, PBRT_MAX_INCLUDE_DEPTH);
    char *path = st ? NULL : resolve_path(ld, file);
    free(file);
    if (st) return st;
    if (!path) return oom(ld);
    if (!GROW(ld->files, ld->cap_files, ld->num_files + 1)) {
        free(path);
        return oom(ld);
    }
    ld->files[ld->num_files++] = path; /* owned by the loader; Locs point into it */
    char *text = NULL;
    size_t len = 0;
    st = file_read_all(path, &text, &len, ld->err);
    if (st) return fail_wrap(ld, st, fl, d);
    ld->depth++;
    st = parse_text(ld, text, len, path);
    ld->depth--;
    free(text);
    return st;
}

/* ------------------------------------------------------------------ the directive table */

/* Reads a directive's own arguments from lx; dname is its name as in the table. */
typedef CstStatus (*DirectiveFn)(Loader *ld, Lexer *lx, Loc loc, const char *dname);
/* Acts on a directive whose type name and parameters named_call has read. */
typedef CstStatus (*NamedDirectiveFn)(Loader *ld, NamedCall *call);

enum {
    DIRECTIVE_NO_PARAMS = 1,   /* a type name only (ColorSpace) */
    DIRECTIVE_OPTIONS = 2      /* rendering options: only before WorldBegin */
};

typedef struct Directive {
    const char *name;
    DirectiveFn parse;       /* either this, */
    NamedDirectiveFn named;  /* or this with the arguments read by named_call */
    unsigned flags;
} Directive;

static const Directive DIRECTIVES[] = {
    /* transforms and the graphics state */
    {"Translate", translate_directive, NULL, 0},
    {"Scale", scale_directive, NULL, 0},
    {"Rotate", rotate_directive, NULL, 0},
    {"LookAt", look_at_directive, NULL, 0},
    {"Transform", transform_directive, NULL, 0},
    {"ConcatTransform", transform_directive, NULL, 0},
    {"Identity", identity_directive, NULL, 0},
    {"CoordinateSystem", coordinate_system_directive, NULL, 0},
    {"CoordSysTransform", coordinate_system_directive, NULL, 0},
    {"ActiveTransform", active_transform_directive, NULL, 0},
    {"TransformTimes", transform_times_directive, NULL, 0},
    {"ReverseOrientation", reverse_orientation_directive, NULL, 0},
    {"AttributeBegin", begin_directive, NULL, 0},
    {"AttributeEnd", end_directive, NULL, 0},
    {"TransformBegin", begin_directive, NULL, 0},
    {"TransformEnd", end_directive, NULL, 0},
    {"WorldBegin", world_begin_directive, NULL, 0},
    {"WorldEnd", world_end_directive, NULL, 0},
    /* files, shapes, objects, camera, textures, materials */
    {"Include", include_directive, NULL, 0},
    {"Import", include_directive, NULL, 0},
    {"Shape", shape_directive, NULL, 0},
    {"Camera", camera_directive, NULL, 0},
    {"Texture", texture_directive, NULL, 0},
    {"ObjectBegin", object_begin_directive, NULL, 0},
    {"ObjectEnd", object_end_directive, NULL, 0},
    {"ObjectInstance", object_instance_directive, NULL, 0},
    {"NamedMaterial", named_material_directive, NULL, 0},
    {"MediumInterface", medium_interface_directive, NULL, 0},
    {"Option", option_directive, NULL, 0},
    /* a type name and parameters */
    {"Film", NULL, film_directive, DIRECTIVE_OPTIONS},
    {"Sampler", NULL, sampler_directive, DIRECTIVE_OPTIONS},
    {"Integrator", NULL, integrator_directive, DIRECTIVE_OPTIONS},
    {"PixelFilter", NULL, pixel_filter_directive, DIRECTIVE_OPTIONS},
    {"Accelerator", NULL, accelerator_directive, DIRECTIVE_OPTIONS},
    {"ColorSpace", NULL, color_space_directive, DIRECTIVE_NO_PARAMS},
    {"MakeNamedMedium", NULL, make_named_medium_directive, 0},
    {"Attribute", NULL, attribute_directive, 0},
    {"LightSource", NULL, light_source_directive, 0},
    {"AreaLightSource", NULL, area_light_source_directive, 0},
    {"Material", NULL, material_directive, 0},
    {"MakeNamedMaterial", NULL, material_directive, 0},
};

/* Reads the type name and (unless DIRECTIVE_NO_PARAMS) the parameter list of `dir`, runs
 * its handler, and reports the parameters it left unused. */
static CstStatus named_call(Loader *ld, Lexer *lx, Loc loc, const Directive *dir)
{
    char *type = NULL, nm[72];
    NamedCall call = {.dname = dir->name, .loc = loc};
    CstStatus st = expect_string(ld, lx, dir->name, "a type name in quotes", &type, &call.tl);
    if (!st && !(dir->flags & DIRECTIVE_NO_PARAMS)) st = parse_params(ld, lx, &call.ps);
    if (st) goto done;
    call.type = type;
    /* (the guard only quiets GCC's format-truncation analysis, which loses track of the name) */
    snprintf(call.d, sizeof call.d, "%s \"%s\"", dir->name ? dir->name : "?", clip(type, nm));
    if ((dir->flags & DIRECTIVE_OPTIONS) && ld->in_world) {
        st = fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s after WorldBegin; expected it before WorldBegin",
                     dir->name);
        goto done;
    }
    st = dir->named(ld, &call);
    if (!st) params_warn_unused(ld, &call.ps, call.d);
done:
    free(type);
    params_free(&call.ps);
    return st;
}

static CstStatus directive(Loader *ld, Lexer *lx, const PbrtToken *t)
{
    Loc loc = tok_loc(lx, t);
    for (size_t i = 0; i < sizeof DIRECTIVES / sizeof DIRECTIVES[0]; i++) {
        const Directive *dir = &DIRECTIVES[i];
        if (tok_is(t, dir->name))
            return dir->parse ? dir->parse(ld, lx, loc, dir->name) : named_call(ld, lx, loc, dir);
    }
    char got[96];
    pbrt_token_describe(t, got, sizeof got);
    return fail_at(ld, CST_ERR_PARSE, loc, "unknown directive: got %s; expected a pbrt directive "
                   "such as Shape, Material, AttributeBegin, LookAt, Camera or WorldBegin", got);
}

/* ------------------------------------------------------------------ the directive loop */

static CstStatus parse_text(Loader *ld, const char *text, size_t len, const char *name)
{
    Lexer lx = {0};
    pbrt_tokenizer_init(&lx.tz, text, len, name);
    for (;;) {
        PbrtToken t;
        TRY(lex_next(ld, &lx, &t));
        if (t.kind == PBRT_TOK_EOF) {
            if (ld->depth == 0) ld->end = tok_loc(&lx, &t);
            return CST_OK;
        }
        if (t.kind != PBRT_TOK_WORD) {
            char got[96];
            pbrt_token_describe(&t, got, sizeof got);
            return fail_at(ld, CST_ERR_PARSE, tok_loc(&lx, &t),
                           "got %s; expected a directive such as Shape or AttributeBegin%s", got,
                           t.kind == PBRT_TOK_STRING ? " (a parameter outside a directive?)" : "");
        }
        TRY(directive(ld, &lx, &t));
    }
}

/* ------------------------------------------------------------------ entry points */

static void loader_free(Loader *ld)
{
    for (int i = 0; i < ld->num_files; i++) free(ld->files[i]);
    free(ld->files);
    free(ld->stack);
    for (int i = 0; i < ld->num_mats; i++) free(ld->mats[i].name);
    free(ld->mats);
    for (int i = 0; i < ld->num_texs; i++) free(ld->texs[i].name);
    free(ld->texs);
    for (int i = 0; i < ld->num_coords; i++) free(ld->coords[i].name);
    free(ld->coords);
    for (int i = 0; i < ld->num_objs; i++) {
        for (int k = 0; k < ld->objs[i].n; k++) geom_free(&ld->objs[i].shapes[k].g);
        free(ld->objs[i].shapes);
        free(ld->objs[i].name);
    }
    free(ld->objs);
    free(ld->base_dir);
}

CstStatus cst_scene_load_pbrt_string(const char *text, size_t len, const char *name,
                                     const CstLoadOptions *options, CstScene **out, CstError *err)
{
    CstError local;
    if (!err) err = &local;
    cst_error_clear(err);
    if (!name) name = "<string>";
    if (!out)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%.200s: no place for the scene (out is NULL)", name);
    *out = NULL;
    if (!text && len > 0) return cst_fail(err, CST_ERR_INVALID_ARG, "%.200s: text is NULL", name);

    Loader ld = {0};
    ld.err = err;
    if (options) ld.opt = *options;
    ld.cur_obj = -1;
    ld.active_start = 1;
    ld.gs.ctm = xf_identity();
    ld.end = (Loc){name, 1, 1};
    CstStatus st = CST_OK;
    size_t dl = path_dir_len(name);
    ld.base_dir = malloc(dl + 1);
    ld.scene = scene_create();
    if (!ld.base_dir || !ld.scene) {
        st = oom(&ld);
        goto done;
    }
    memcpy(ld.base_dir, name, dl);
    ld.base_dir[dl] = '\0';
    /* pbrt's defaults where they differ from caustic's: a 1280 x 720 film, the volumetric
     * path tracer with at most 5 bounces (as "path"), the Gaussian filter (sigma 0.5, radius
     * 1.5: caustic's). */
    ld.scene->settings.width = 1280;
    ld.scene->settings.height = 720;
    ld.scene->settings.integrator = CST_INTEGRATOR_PATH;
    ld.scene->settings.max_depth = 5;
    ld.scene->settings.filter = CST_FILTER_GAUSSIAN;
    Material def = {.type = MATERIAL_DIFFUSE, .albedo = color_s(0.5f), .ior = 1.0f};
    if ((st = add_mat_entry(&ld, NULL, &def, &ld.gs.material))) goto done;

    st = parse_text(&ld, text ? text : "", len, name);
    if (st) goto done;
    if (ld.num_stack > 0) {
        const GState *top = &ld.stack[ld.num_stack - 1];
        warn_at(&ld, CST_WARN_GEOMETRY, top->loc, "%s%s is never closed",
                ld.cur_obj >= 0 ? "ObjectBegin" : (top->transform_only ? "TransformBegin" : "AttributeBegin"),
                ld.cur_obj >= 0 ? " (its shapes are never instanced unless referenced)" : "");
    }
    if (!ld.in_world)
        warn_at(&ld, CST_WARN_GEOMETRY, ld.end, "the file has no WorldBegin");
    if (ld.scene->num_triangles == 0 && ld.scene->num_spheres == 0 &&
        !(ld.scene->instances && ld.scene->instances->num_insts > 0)) {
        st = fail_at(&ld, CST_ERR_INVALID_ARG, ld.end, "the scene has no shapes caustic can render; "
                     "expected at least one supported Shape in the world block");
        goto done;
    }
    if ((st = camera_finish(&ld))) goto done;
    st = scene_commit(ld.scene, err);
    if (st) {
        char msg[sizeof err->msg];
        memcpy(msg, err->msg, sizeof msg);
        msg[sizeof msg - 1] = '\0';
        cst_fail(err, st, "%.200s: %.800s", name, msg);
    }
done:
    loader_free(&ld);
    if (st) {
        scene_destroy(ld.scene);
        return st;
    }
    *out = ld.scene;
    return CST_OK;
}

CstStatus cst_scene_load_pbrt(const char *path, const CstLoadOptions *options, CstScene **out,
                              CstError *err)
{
    CstError local;
    if (!err) err = &local;
    if (!out || !path)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_load_pbrt: path and out must not be NULL");
    *out = NULL;
    char *text = NULL;
    size_t len = 0;
    CstStatus st = file_read_all(path, &text, &len, err);
    if (st) return st;
    st = cst_scene_load_pbrt_string(text, len, path, options, out, err);
    free(text);
    return st;
}
