/* The pbrt-v4 scene loader's entry points and directive loop: a table from directive name to
 * handler. What is supported, approximated or skipped is tabled in docs/pbrt-compat.md;
 * everything approximated or skipped is reported through the CstLoadOptions warning callback
 * with its location. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "io/gzip.h"
#include "io/path.h"
#include "scene/pbrt/pbrt_camera.h"
#include "scene/pbrt/pbrt_light.h"
#include "scene/pbrt/pbrt_loader.h"
#include "scene/pbrt/pbrt_material.h"
#include "scene/pbrt/pbrt_medium.h"
#include "scene/pbrt/pbrt_options.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_shape.h"
#include "scene/pbrt/pbrt_texture.h"
#include "scene/pbrt/pbrt_transform.h"

/* Nesting of Include/Import: deep enough for any real scene, and stops a file including
 * itself. */
#define PBRT_MAX_INCLUDE_DEPTH 16

static CstStatus parse_text(Loader *ld, const char *text, size_t len, const char *name);

/* Include splices the file's tokens into the includer's (pbrt_lex_push), as pbrt-v4 does: a
 * parameter list left open at its end goes on after the Include. Import parses the file
 * on its own (pbrt-v4 reads it separately, so its lists end with it). Either may be
 * gzip-compressed (.gz or the gzip magic: io/gzip.h). */
static CstStatus include_directive(Loader *ld, Lexer *lx, Loc loc, const char *d)
{
    char *file = NULL;
    Loc fl;
    TRY(pbrt_expect_string(ld, lx, d, "a file name", &file, &fl));
    CstStatus st = pbrt_check_file_access(ld, fl, d);
    if (!st && ld->depth + lx->num_saved >= PBRT_MAX_INCLUDE_DEPTH)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: more than %d nested includes (does a file "
                          "include itself?)", d, PBRT_MAX_INCLUDE_DEPTH);
    char *path = st ? NULL : pbrt_resolve_path(ld, file);
    free(file);
    if (st) return st;
    if (!path) return pbrt_oom(ld);
    if (!GROW(ld->files, ld->cap_files, ld->num_files + 1)) {
        free(path);
        return pbrt_oom(ld);
    }
    ld->files[ld->num_files++] = path; /* owned by the loader; Locs point into it */
    char *text = NULL;
    size_t len = 0;
    st = gzip_read_file(path, &text, &len, ld->err);
    if (st) return pbrt_fail_wrap(ld, st, fl, d);
    if (strcmp(d, "Include") == 0) return pbrt_lex_push(ld, lx, text, len, path);
    ld->depth++;
    st = parse_text(ld, text, len, path);
    ld->depth--;
    free(text);
    return st;
}

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
    {"Translate", pbrt_translate_directive, NULL, 0},
    {"Scale", pbrt_scale_directive, NULL, 0},
    {"Rotate", pbrt_rotate_directive, NULL, 0},
    {"LookAt", pbrt_look_at_directive, NULL, 0},
    {"Transform", pbrt_transform_directive, NULL, 0},
    {"ConcatTransform", pbrt_transform_directive, NULL, 0},
    {"Identity", pbrt_identity_directive, NULL, 0},
    {"CoordinateSystem", pbrt_coordinate_system_directive, NULL, 0},
    {"CoordSysTransform", pbrt_coordinate_system_directive, NULL, 0},
    {"ActiveTransform", pbrt_active_transform_directive, NULL, 0},
    {"TransformTimes", pbrt_transform_times_directive, NULL, 0},
    {"ReverseOrientation", pbrt_reverse_orientation_directive, NULL, 0},
    {"AttributeBegin", pbrt_begin_directive, NULL, 0},
    {"AttributeEnd", pbrt_end_directive, NULL, 0},
    {"TransformBegin", pbrt_begin_directive, NULL, 0},
    {"TransformEnd", pbrt_end_directive, NULL, 0},
    {"WorldBegin", pbrt_world_begin_directive, NULL, 0},
    {"WorldEnd", pbrt_world_end_directive, NULL, 0},
    /* files, shapes, objects, camera, textures, materials */
    {"Include", include_directive, NULL, 0},
    {"Import", include_directive, NULL, 0},
    {"Shape", pbrt_shape_directive, NULL, 0},
    {"Camera", pbrt_camera_directive, NULL, 0},
    {"Texture", pbrt_texture_directive, NULL, 0},
    {"ObjectBegin", pbrt_object_begin_directive, NULL, 0},
    {"ObjectEnd", pbrt_object_end_directive, NULL, 0},
    {"ObjectInstance", pbrt_object_instance_directive, NULL, 0},
    {"NamedMaterial", pbrt_named_material_directive, NULL, 0},
    {"MediumInterface", pbrt_medium_interface_directive, NULL, 0},
    {"Option", pbrt_option_directive, NULL, 0},
    /* a type name and parameters */
    {"Film", NULL, pbrt_film_directive, DIRECTIVE_OPTIONS},
    {"Sampler", NULL, pbrt_sampler_directive, DIRECTIVE_OPTIONS},
    {"Integrator", NULL, pbrt_integrator_directive, DIRECTIVE_OPTIONS},
    {"PixelFilter", NULL, pbrt_pixel_filter_directive, DIRECTIVE_OPTIONS},
    {"Accelerator", NULL, pbrt_accelerator_directive, DIRECTIVE_OPTIONS},
    {"ColorSpace", NULL, pbrt_color_space_directive, DIRECTIVE_NO_PARAMS},
    {"MakeNamedMedium", NULL, pbrt_make_named_medium_directive, 0},
    {"Attribute", NULL, pbrt_attribute_directive, 0},
    {"LightSource", NULL, pbrt_light_source_directive, 0},
    {"AreaLightSource", NULL, pbrt_area_light_source_directive, 0},
    {"Material", NULL, pbrt_material_directive, 0},
    {"MakeNamedMaterial", NULL, pbrt_material_directive, 0},
};

/* Reads the type name and (unless DIRECTIVE_NO_PARAMS) the parameter list of `dir`, runs
 * its handler, and reports the parameters it left unused. */
static CstStatus named_call(Loader *ld, Lexer *lx, Loc loc, const Directive *dir)
{
    char *type = NULL, nm[72];
    NamedCall call = {.dname = dir->name, .loc = loc};
    CstStatus st = pbrt_expect_string(ld, lx, dir->name, "a type name in quotes", &type, &call.tl);
    if (!st && !(dir->flags & DIRECTIVE_NO_PARAMS)) st = pbrt_parse_params(ld, lx, &call.ps);
    if (st) goto done;
    call.type = type;
    /* (the guard only quiets GCC's format-truncation analysis, which loses track of the name) */
    snprintf(call.d, sizeof call.d, "%s \"%s\"", dir->name ? dir->name : "?", pbrt_clip(type, nm));
    if ((dir->flags & DIRECTIVE_OPTIONS) && ld->in_world) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s after WorldBegin; expected it before WorldBegin",
                          dir->name);
        goto done;
    }
    st = dir->named(ld, &call);
    if (!st) pbrt_params_warn_unused(ld, &call.ps, call.d);
done:
    free(type);
    pbrt_params_free(&call.ps);
    return st;
}

static CstStatus directive(Loader *ld, Lexer *lx, const PbrtToken *t)
{
    Loc loc = pbrt_tok_loc(lx, t);
    for (size_t i = 0; i < sizeof DIRECTIVES / sizeof DIRECTIVES[0]; i++) {
        const Directive *dir = &DIRECTIVES[i];
        if (!pbrt_tok_is(t, dir->name)) continue;
        CstStatus st = dir->parse ? dir->parse(ld, lx, loc, dir->name) : named_call(ld, lx, loc, dir);
        if (st == CST_OK && ld->opt.max_primitives) {
            /* Checked per directive: one directive adds a bounded amount (its own mesh, or an
             * instance's sphere copies), so a file cannot pile up far beyond the limit. */
            CstSceneInfo info;
            cst_scene_info(ld->scene, &info);
            size_t n = (size_t)info.triangles + (size_t)info.spheres + (size_t)info.shapes + (size_t)info.instances;
            if (n > ld->opt.max_primitives)
                st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the scene holds %zu primitives after it; "
                                  "expected at most %zu (CstLoadOptions.max_primitives)", dir->name, n,
                                  ld->opt.max_primitives);
        }
        return st;
    }
    char got[96];
    pbrt_token_describe(t, got, sizeof got);
    return pbrt_fail_at(ld, CST_ERR_PARSE, loc, "unknown directive: got %s; expected a pbrt directive "
                        "such as Shape, Material, AttributeBegin, LookAt, Camera or WorldBegin", got);
}

static CstStatus parse_text(Loader *ld, const char *text, size_t len, const char *name)
{
    Lexer lx = {0};
    pbrt_tokenizer_init(&lx.tz, text, len, name);
    CstStatus st = CST_OK;
    for (;;) {
        PbrtToken t;
        if ((st = pbrt_lex_next(ld, &lx, &t))) break;
        if (t.kind == PBRT_TOK_EOF) {
            if (ld->depth == 0) ld->end = pbrt_tok_loc(&lx, &t);
            break;
        }
        if (t.kind != PBRT_TOK_WORD) {
            char got[96];
            pbrt_token_describe(&t, got, sizeof got);
            st = pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(&lx, &t),
                              "got %s; expected a directive such as Shape or AttributeBegin%s", got,
                              t.kind == PBRT_TOK_STRING ? " (a parameter outside a directive?)" : "");
            break;
        }
        if ((st = directive(ld, &lx, &t))) break;
    }
    pbrt_lex_free(&lx);
    return st;
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
    ld.gs.active_start = 1;
    ld.gs.active_end = 1;
    ld.gs.ctm = ld.gs.ctm_end = pbrt_xf_identity();
    ld.transform_times[1] = 1.0;
    ld.end = (Loc){name, 1, 1};
    CstStatus st = CST_OK;
    size_t dl = path_dir_len(name);
    ld.base_dir = malloc(dl + 1);
    CstError create_err;
    if (cst_scene_create(&ld.scene, &create_err) != CST_OK) ld.scene = NULL;
    if (!ld.base_dir || !ld.scene) {
        st = pbrt_oom(&ld);
        goto done;
    }
    memcpy(ld.base_dir, name, dl);
    ld.base_dir[dl] = '\0';
    /* pbrt-v4 samples a triangle light by the solid angle it subtends (Triangle::Sample) */
    if ((st = cst_scene_set_light_sampling(ld.scene, "solid_angle", ld.err)) != CST_OK) goto done;
    /* pbrt's defaults where they differ from caustic's: a 1280 x 720 film, the volumetric
     * path tracer with at most 5 bounces (as "path"), the Gaussian filter (sigma 0.5, radius
     * 1.5: caustic's). */
    cst_render_settings_init(&ld.settings);
    ld.settings.spp = ld.settings.rr_depth = ld.settings.photons = 0; /* 0 reads as unset */
    ld.settings.photon_radius = 0.0;
    ld.settings.aovs = 0;
    ld.settings.width = 1280;
    ld.settings.height = 720;
    ld.settings.integrator = CST_INTEGRATOR_PATH;
    ld.settings.max_depth = 5;
    ld.settings.color_mode = CST_COLOR_SPECTRAL; /* pbrt-v4 is a spectral renderer */
    ld.settings.filter = CST_FILTER_GAUSSIAN;
    Material def = {.type = MATERIAL_DIFFUSE, .albedo = color_s(0.5f), .ior = 1.0f};
    if ((st = pbrt_add_mat_entry(&ld, NULL, &def, &ld.gs.material))) goto done;

    st = parse_text(&ld, text ? text : "", len, name);
    if (st) goto done;
    if (ld.num_stack > 0) {
        const GState *top = &ld.stack[ld.num_stack - 1];
        pbrt_warn_at(&ld, CST_WARN_GEOMETRY, top->loc, "%s%s is never closed",
                     ld.cur_obj >= 0 ? "ObjectBegin" : (top->transform_only ? "TransformBegin" : "AttributeBegin"),
                     ld.cur_obj >= 0 ? " (its shapes are never instanced unless referenced)" : "");
    }
    if (!ld.in_world)
        pbrt_warn_at(&ld, CST_WARN_GEOMETRY, ld.end, "the file has no WorldBegin");
    CstSceneInfo info;
    cst_scene_info(ld.scene, &info);
    /* pbrt-v4 renders an empty (or media-only) world: every ray misses, so the image shows
     * the infinite lights, or is black. */
    if (info.triangles == 0 && info.spheres == 0 && info.shapes == 0 && info.instances == 0)
        pbrt_warn_at(&ld, CST_WARN_GEOMETRY, ld.end, "the world has no shapes caustic can render; "
                     "every ray misses (infinite lights are seen, or the image is black)");
    if ((st = pbrt_camera_finish(&ld))) goto done;
    st = cst_scene_set_render_settings(ld.scene, &ld.settings, err);
    if (!st) st = cst_scene_commit(ld.scene, err);
    if (st) {
        char msg[sizeof err->msg];
        memcpy(msg, err->msg, sizeof msg);
        msg[sizeof msg - 1] = '\0';
        cst_fail(err, st, "%.200s: %.800s", name, msg);
    }
done:
    pbrt_loader_free(&ld);
    if (st) {
        cst_scene_destroy(ld.scene);
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
    CstStatus st = gzip_read_file(path, &text, &len, err); /* scene.pbrt.gz too */
    if (st) return st;
    st = cst_scene_load_pbrt_string(text, len, path, options, out, err);
    free(text);
    return st;
}
