/* The JSON scene loader (format: docs/scene-format.md): the entry points and the root
 * object. jansson parses; the json_*.c files beside this one validate every value, name
 * its file:line:column on error, and build the scene through the public builder (cst_scene_*) only. */
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"
#include "scene/json/json_geometry.h"
#include "scene/json/json_light.h"
#include "scene/json/json_locate.h"
#include "scene/json/json_material.h"
#include "scene/json/json_medium.h"
#include "scene/json/json_reader.h"
#include "scene/json/json_settings.h"
#include "scene/json/json_texture.h"

/* Sections are read in dependency order (materials before the shapes naming them), not
 * file order, so a file may list them in any order. */
static CstStatus parse_root(Loader *ld, const json_t *root)
{
    static const char *const keys[] = {"film", "camera", "integrator", "sampler", "materials",
                                       "shapes", "lights", "environment", "accel", "textures",
                                       "media", "camera_medium"};
    json_t *v;
    LOADER_TRY(json_expect_object(ld, root, "an object with the scene sections"));
    LOADER_TRY(json_check_keys(ld, root, keys, 12));
    if ((v = json_object_get(root, "accel"))) {
        json_path_push_key(ld, "accel");
        const char *name = NULL;
        AccelType type = ACCEL_BVH;
        LOADER_TRY(json_read_string(ld, v, &name));
        if (!accel_type_from_name(name, &type))
            return json_fail_here(ld, "unknown acceleration structure \"%s\"; expected one of: bvh, "
                                      "kdtree, grid, list, embree, octree", name);
        if (!accel_type_available(type))
            return json_fail_here(ld, "acceleration structure \"%s\" is not available in this build; "
                                      "expected one of: bvh, kdtree, grid, list, octree", name);
        LOADER_TRY(cst_scene_set_accel(ld->scene, name, ld->err)); /* before commit: its choice */
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "film"))) {
        json_path_push_key(ld, "film");
        LOADER_TRY(json_parse_film(ld, v));
        json_path_pop(ld);
    }
    LOADER_TRY(json_member_required(ld, root, "camera", "a camera object", &v));
    json_path_push_key(ld, "camera");
    LOADER_TRY(json_parse_camera(ld, v));
    json_path_pop(ld);
    if ((v = json_object_get(root, "integrator"))) {
        json_path_push_key(ld, "integrator");
        LOADER_TRY(json_parse_integrator(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "sampler"))) {
        json_path_push_key(ld, "sampler");
        LOADER_TRY(json_parse_sampler(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "textures"))) {
        json_path_push_key(ld, "textures");
        LOADER_TRY(json_parse_textures(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "materials"))) {
        json_path_push_key(ld, "materials");
        LOADER_TRY(json_parse_materials(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "media"))) {
        json_path_push_key(ld, "media");
        LOADER_TRY(json_parse_media(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "camera_medium"))) {
        json_path_push_key(ld, "camera_medium");
        LOADER_TRY(json_parse_camera_medium(ld, v));
        json_path_pop(ld);
    }
    LOADER_TRY(json_member_required(ld, root, "shapes", "an array of shapes", &v));
    json_path_push_key(ld, "shapes");
    LOADER_TRY(json_parse_shapes(ld, v));
    json_path_pop(ld);
    if ((v = json_object_get(root, "lights"))) {
        json_path_push_key(ld, "lights");
        LOADER_TRY(json_parse_lights(ld, v));
        json_path_pop(ld);
    }
    if ((v = json_object_get(root, "environment"))) {
        json_path_push_key(ld, "environment");
        LOADER_TRY(json_parse_environment(ld, v));
        json_path_pop(ld);
    }
    return CST_OK;
}

/* opt: the caller's load options (warnings), or NULL. */
static CstStatus load_json_string(const char *text, size_t len, const char *name, const CstLoadOptions *opt,
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

    /* A UTF-8 byte order mark (some Windows editors write one) is skipped, as RFC 8259 §8.1
     * allows a reader to; jansson would stop at it. Positions count from after it, as an
     * editor shows them. UTF-16 text is named as such rather than as a NUL byte. */
    if (text && len >= 3 && memcmp(text, "\xEF\xBB\xBF", 3) == 0) {
        text += 3;
        len -= 3;
    } else if (text && len >= 2 && ((unsigned char)text[0] == 0xFF || (unsigned char)text[0] == 0xFE) &&
               (unsigned char)text[1] == ((unsigned char)text[0] ^ 0x01)) {
        return cst_fail(err, CST_ERR_PARSE, "%.200s:1:1: the text is UTF-16 (it starts with a UTF-16 byte "
                        "order mark); expected UTF-8", name);
    }

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
        json_buf_append(text_safe, sizeof text_safe, &pos, jerr.text);
        return cst_fail(err, CST_ERR_PARSE, "%.200s:%d:%d: %s", name, line, col, text_safe);
    }

    Loader ld = {0};
    ld.boundary_material = -1;
    ld.text = text ? text : "";
    ld.len = len;
    ld.name = name;
    ld.err = err;
    ld.opt = opt;
    cst_render_settings_init(&ld.settings);
    ld.settings.width = ld.settings.height = ld.settings.spp = 0;
    ld.settings.rr_depth = ld.settings.photons = 0;
    ld.settings.photon_radius = 0.0;
    ld.settings.aovs = 0;
    CstStatus st;
    if (cst_scene_create(&ld.scene, err) != CST_OK) {
        st = cst_fail(err, CST_ERR_OOM, "%.200s: out of memory creating the scene", name);
    } else {
        st = parse_root(&ld, root);
        if (st == CST_OK && (st = cst_scene_set_render_settings(ld.scene, &ld.settings, err)) != CST_OK)
            st = json_fail_builder(&ld, st);
        if (st == CST_OK) {
            st = cst_scene_commit(ld.scene, err);
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
    free(ld.med_names);
    free(ld.tex_names);
    free(ld.tex_state);
    free(ld.tex_ids);
    free(ld.tex_sorted);
    json_decref(root);
    if (st != CST_OK) {
        cst_scene_destroy(ld.scene);
        return st;
    }
    *out = ld.scene;
    return CST_OK;
}

CstStatus cst_scene_load_json_string(const char *text, size_t len, const char *name,
                                     CstScene **out, CstError *err)
{
    return load_json_string(text, len, name, NULL, out, err);
}

CstStatus cst_scene_load_json(const char *path, CstScene **out, CstError *err)
{
    return cst_scene_load_json_opt(path, NULL, out, err);
}

CstStatus cst_scene_load_json_opt(const char *path, const CstLoadOptions *options, CstScene **out,
                                  CstError *err)
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
    st = load_json_string(text, len, path, options, out, err);
    free(text);
    return st;
}
