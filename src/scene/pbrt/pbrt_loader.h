/* The pbrt loader's shared state (Loader: the graphics state and its stack, named materials,
 * textures, coordinate systems and objects, the camera) and what every directive uses:
 * located errors and warnings, the lexer with one token of lookahead, file names. */
#ifndef CST_SCENE_PBRT_PBRT_LOADER_H
#define CST_SCENE_PBRT_PBRT_LOADER_H

#include <limits.h>
#include <stdbool.h>
#include <stddef.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/transform.h"
#include "materials/material.h"
#include "math/vec3.h"
#include "scene/pbrt/pbrt_tokenizer.h"

/* Same bound on coordinates as the JSON loader (LOADER_MAX_LENGTH, json/json_reader.h): squared distances of
 * coordinates within 1e18 stay finite in float. */
#define PBRT_MAX_LENGTH 1e18

/* The scene indexes triangles with int, three indices each. */
#define PBRT_MAX_TRIANGLES (INT_MAX / 3 - 1)

#define PBRT_PI 3.14159265358979323846 /* double; PBRT_PI is a float */

#define TRY(expr)                         \
    do {                                  \
        CstStatus try_st_ = (expr);       \
        if (try_st_ != CST_OK)            \
            return try_st_;               \
    } while (0)

typedef struct Loc {
    const char *file;
    int line, col;
} Loc;

typedef enum PType {
    PT_INTEGER, PT_FLOAT, PT_POINT2, PT_VECTOR2, PT_POINT3, PT_VECTOR3, PT_NORMAL, PT_RGB,
    PT_SPECTRUM, PT_BLACKBODY, PT_BOOL, PT_STRING, PT_TEXTURE, PT_XYZ
} PType;

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
    int texture;     /* "filename": the image's texture id (public, >= 1), L = scale x image; 0 = none */
    float image_lum; /* with texture: the image's mean luminance, power's k_e (pbrt-v4) */
    int spectrum;  /* "L" kept as a spectrum (blackbody, named, pairs, .spd): its id, or 0 */
} AreaLight;

typedef struct GState {
    /* pbrt-v4's pair of CTMs: ctm at the start time and ctm_end at the end time of
     * TransformTimes. They differ only after ActiveTransform StartTime or EndTime; then
     * what follows moves (pbrt_ctm_moving): the camera, triangle shapes and instances. */
    Xf ctm, ctm_end;
    int reverse;
    int material; /* index into Loader.mats */
    AreaLight area;
    int active_start;   /* ActiveTransform includes StartTime: transforms change ctm */
    int active_end;     /* ActiveTransform includes EndTime: transforms change ctm_end; both
                           are attributes, restored by AttributeEnd, as in pbrt-v4 */
    int transform_only; /* pushed by TransformBegin (pbrt-v3): pops only the CTM */
    int med_in, med_out; /* MediumInterface: 1 + the scene's medium id, 0 = vacuum */
    Loc loc;            /* of the Begin, for messages */
} GState;

typedef struct MatEntry {
    char *name; /* NULL for anonymous Material directives */
    Material m;
    int scene_id; /* added to the scene on first use, -1 before */
    /* pbrt-v4's "interface" (also v3's "" and "none"): a medium boundary that does not
     * scatter. Between two different media shapes with it become pure boundaries
     * (pbrt_medium.h); otherwise they are left out of the scene (invisible to every ray),
     * unless they emit; then m stands in for it. */
    int interface;
} MatEntry;

typedef struct TexEntry {
    char *name;
    int is_float; /* pbrt keeps float and spectrum textures in two name spaces */
    int id;       /* the scene's texture (its public id - 1), or -1 for a constant, which
                   * is kept here alone; float textures hold the value in all three channels */
    Color value;    /* a constant's value, else the texture's average: for parameters caustic
                     * cannot texture */
    /* Derived scene textures made on first use and shared by every material that uses
     * them (an image is copied once): clamped to 1 as a reflectance; as caustic's
     * roughness without and with pbrt's remapping. -1 until made. */
    int clamped, rough[2];
} TexEntry;

typedef struct NamedXf {
    char *name;
    Xf xf, xf_end; /* both CTMs, as pbrt-v4 names a TransformSet */
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
    int power_group; /* triangles per pbrt shape, for an area light's "power": 2 for a
                      * bilinear patch, all of them for a tessellated disk or sphere;
                      * 0 = 1 (each triangle is a shape in pbrt-v4) */
} ShapeGeom;

typedef struct ObjShape {
    ShapeGeom g;
    Xf xf;
    int reverse;
    int material;
    CstAlpha alpha; /* the shape's "alpha" (zero: opaque) */
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
    Xf ctm, ctm_end; /* camera-from-world at the start and end times */
    float fov;
    float shutter[2]; /* shutteropen, shutterclose (pbrt-v4's times, before TransformTimes maps them) */
    double screen[4];
    int has_screen;
    float frame;
    int has_frame;
    float lens_radius, focal_distance;
    int ortho; /* Camera "orthographic" */
    int medium; /* 1 + the camera's medium id (the outside medium at Camera), 0 vacuum */
    Loc loc;
} CamRec;

/* A file whose reading an Include interrupted: its tokenizer, resumed when the included
 * file's tokens end, and the text it reads (owned, NULL for the caller's text). */
typedef struct LexSaved {
    PbrtTokenizer tz;
    char *text;
} LexSaved;

/* Tokens of one file and, as pbrt-v4 reads them, of the files it Includes: an included
 * file's tokens are spliced into the includer's stream, so a parameter list that an
 * included file leaves open goes on after the Include in the includer. */
typedef struct Lexer {
    PbrtTokenizer tz;
    PbrtToken peek;
    int has_peek;
    char *text;          /* what tz reads, when owned (an included file) */
    LexSaved *saved;     /* the includers of tz, innermost last */
    int num_saved, cap_saved;
    char *retired;       /* the text of the last file finished: freed one file later, as
                            a token of it may still be in use */
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

/* The loader builds its scene through the public builder alone (the cst_scene_* calls of
 * include/caustic/caustic.h), as any program could; it never reaches into Scene. */
typedef struct Loader {
    CstScene *scene;
    CstError *err;
    /* What Film, Sampler and Integrator ask for (over pbrt's defaults), handed to the scene
     * with cst_scene_set_render_settings before commit. */
    CstRenderSettings settings;
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
    double transform_times[2]; /* TransformTimes: the times of ctm and ctm_end, 0 and 1 by default */
    CamRec cam;
    int env_set; /* an infinite light has made the scene's environment */
    /* The sum of the infinite lights so far (pbrt-v4 sums them; caustic has one
     * environment): env_const plus, when env_rgb is not NULL, env_w x env_h pixels (caustic's
     * equirectangular layout) times env_k. Owned; freed by pbrt_loader_free. */
    float *env_rgb;
    int env_w, env_h;
    float env_k[3], env_const[3];
    int num_instances_expanded; /* instances whose spheres were copied */
    int num_interface_shapes;   /* shapes with material "interface", left out */
    /* MakeNamedMedium names and their scene media (-1: a type caustic does not render,
     * warned about, read as vacuum). */
    char **med_names;
    int *med_ids;
    int num_meds, cap_meds, cap_med_ids;
    int num_triangles, num_spheres; /* added to the scene so far (for its limits) */
    Loc end; /* end of the main file, for errors about the whole scene */
} Loader;

/* The three floats of v or c, as the public builder's descriptions take them (exact). */
static inline void pbrt_vec3_floats(Vec3 v, float out[3])
{
    out[0] = v.x, out[1] = v.y, out[2] = v.z;
}

static inline void pbrt_color_floats(Color c, float out[3])
{
    for (int k = 0; k < 3; k++) out[k] = color_channel(c, k);
}

/* Grows *arr (element size `size`) to hold `need` elements, doubling; 0 on overflow or OOM.
 * Use through GROW(arr, cap, need). */
int pbrt_grow(void **arr, int *cap, int need, size_t size);

#define GROW(arr, cap, need) pbrt_grow((void **)&(arr), &(cap), (need), sizeof *(arr))

/* A malloc'd copy of s, or NULL on OOM. */
char *pbrt_dup_str(const char *s);

/* A name from the file, printable and short enough to quote. */
const char *pbrt_clip(const char *s, char buf[72]);

/* Fails with status st and "file:line:column: message" at loc. */
CstStatus pbrt_fail_at(Loader *ld, CstStatus st, Loc loc, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* CST_ERR_OOM with the loader's message. */
CstStatus pbrt_oom(Loader *ld);

/* Reports a located warning through the CstLoadOptions callback, if any. */
void pbrt_warn_at(Loader *ld, CstWarningCode code, Loc loc, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

/* The file, line and column of token t. */
Loc pbrt_tok_loc(const Lexer *lx, const PbrtToken *t);

/* True when t's text is exactly `word`. */
int pbrt_tok_is(const PbrtToken *t, const char *word);

/* Continues lx with text (owned by lx from now on, freed when its tokens end or by
 * pbrt_lex_free) named name, the includer resuming after it. */
CstStatus pbrt_lex_push(Loader *ld, Lexer *lx, char *text, size_t len, const char *name);

/* Frees what lx owns (the texts of unfinished includes). */
void pbrt_lex_free(Lexer *lx);

/* The next token, left for the next pbrt_lex_next. */
CstStatus pbrt_lex_peek(Loader *ld, Lexer *lx, PbrtToken *t);

/* The next token, consumed. */
CstStatus pbrt_lex_next(Loader *ld, Lexer *lx, PbrtToken *t);

/* A quoted string (decoded into a new *out, free()) or a located parse error naming
 * `directive` and `what`; *loc, when not NULL, gets the token's location. */
CstStatus pbrt_expect_string(Loader *ld, Lexer *lx, const char *directive, const char *what,
                             char **out, Loc *loc);

/* n bare numbers into out, or a located parse error. */
CstStatus pbrt_expect_numbers(Loader *ld, Lexer *lx, const char *directive, int n, double *out);

/* n numbers in brackets; pbrt-v3 files sometimes leave the brackets out. */
CstStatus pbrt_expect_number_array(Loader *ld, Lexer *lx, const char *directive, int n, double *out);

/* A failure of a library call (mesh import, image read): keep its text, add the location. */
CstStatus pbrt_fail_wrap(Loader *ld, CstStatus st, Loc loc, const char *d);

/* `file` relative to the main scene file's directory (pbrt's search directory). */
char *pbrt_resolve_path(Loader *ld, const char *file);

/* CST_ERR_UNSUPPORTED at loc when CstLoadOptions.no_file_access is set. */
CstStatus pbrt_check_file_access(Loader *ld, Loc loc, const char *d);

/* Frees everything the loader owns (not the scene). */
void pbrt_loader_free(Loader *ld);

#endif
