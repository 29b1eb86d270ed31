/* The "lights" (point, spot, directional, projection) and "environment" sections. */
#include "scene/json/json_light.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/image_io.h"
#include "io/path.h"

/* A direction that must not be zero, as read (the builder normalises it). */
static CstStatus read_direction(Loader *ld, const json_t *v, float out[3])
{
    Vec3 d;
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &d));
    float len = v3_length(d);
    if (!(len > 0.0f) || !isfinite(len))
        return json_fail_here(ld, "direction [%g, %g, %g] has no length; expected a nonzero vector",
                              (double)d.x, (double)d.y, (double)d.z);
    json_vec3_floats(d, out);
    return CST_OK;
}

static CstStatus read_angle(Loader *ld, const json_t *obj, const char *key, float dflt, float lo,
                            float hi, float *out)
{
    json_t *v = json_object_get(obj, key);
    *out = dflt;
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, out));
    if (!(*out >= lo && *out <= hi))
        return json_fail_here(ld, "%s %g is out of range; expected degrees from %g to %g", key, (double)*out,
                              (double)lo, (double)hi);
    json_path_pop(ld);
    return CST_OK;
}

/* A light's "type" (json_light.h). */
const char *const json_light_types[] = {"point", "spot", "directional", "projection", NULL};

/* A projection light: "position", "look_at" (the axis), "up" (default +y), "file" (an
 * image, relative to the scene file), "fov" (degrees across the image's shorter side,
 * default 90) and "intensity" (W/sr per unit pixel value, default [1, 1, 1]). Light space:
 * z along the axis, y toward "up", x = y cross z. */
static CstStatus parse_projection(Loader *ld, const json_t *obj)
{
    static const char *const keys[] = {"type", "position", "look_at", "up", "file", "fov", "intensity"};
    CstLightDesc l = {0};
    json_t *v;
    Vec3 p, at, up = v3(0.0f, 1.0f, 0.0f);
    Color c = color_s(1.0f);
    LOADER_TRY(json_check_keys(ld, obj, keys, 7));
    l.type = CST_LIGHT_PROJECTION;
    LOADER_TRY(json_member_required(ld, obj, "position", "the light's position, 3 numbers", &v));
    json_path_push_key(ld, "position");
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &p));
    json_path_pop(ld);
    LOADER_TRY(json_member_required(ld, obj, "look_at", "the point the light's axis goes through", &v));
    json_path_push_key(ld, "look_at");
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &at));
    Vec3 z = v3_sub(at, p);
    if (!(v3_length(z) > 0.0f) || !isfinite(v3_length(z)))
        return json_fail_here(ld, "look_at equals position; expected a point away from the light");
    json_path_pop(ld);
    if ((v = json_object_get(obj, "up"))) {
        json_path_push_key(ld, "up");
        LOADER_TRY(read_direction(ld, v, l.direction));
        up = v3(l.direction[0], l.direction[1], l.direction[2]);
        memset(l.direction, 0, sizeof l.direction);
        if (!(v3_length(v3_cross(up, v3_normalize(z))) > 1e-6f * v3_length(up)))
            return json_fail_here(ld, "up is parallel to the axis (look_at - position); expected another direction");
        json_path_pop(ld);
    }
    z = v3_normalize(z);
    Vec3 y = v3_sub(up, v3_scale(z, v3_dot(up, z)));
    if (!(v3_length(y) > 1e-6f * v3_length(up)))
        return json_fail_here(ld, "the default up [0, 1, 0] is parallel to the axis (look_at - position); "
                              "expected \"up\", another direction");
    y = v3_normalize(y);
    Vec3 x = v3_cross(y, z);
    const Vec3 rows[3] = {x, y, z};
    for (int k = 0; k < 3; k++) json_vec3_floats(rows[k], &l.light_from_world[3 * k]);
    json_vec3_floats(p, l.position);
    if ((v = json_object_get(obj, "intensity"))) {
        json_path_push_key(ld, "intensity");
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
        json_path_pop(ld);
    }
    json_color_floats(c, l.intensity);
    LOADER_TRY(read_angle(ld, obj, "fov", 90.0f, 0.001f, 179.0f, &l.fov));
    const char *name = NULL;
    LOADER_TRY(json_member_required(ld, obj, "file", "the image to project, a file name", &v));
    json_path_push_key(ld, "file");
    LOADER_TRY(json_read_string(ld, v, &name));
    if (!name[0]) return json_fail_here(ld, "the file name is empty; expected the path of an image");
    char *path = path_resolve(ld->name, name);
    if (!path) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    float *px = NULL;
    CstStatus st = image_read_radiance(path, &px, &l.image_width, &l.image_height, ld->err);
    free(path);
    if (st != CST_OK) return json_fail_builder(ld, st);
    l.image = px;
    st = cst_scene_add_light(ld->scene, &l, ld->err);
    free(px);
    if (st != CST_OK) return json_fail_builder(ld, st);
    json_path_pop(ld);
    return CST_OK;
}

/* "lights": point, spot, directional and projection lights (area lights are shapes with
 * "emission"). */
static CstStatus parse_light(Loader *ld, const json_t *obj)
{
    const char *const *types = json_light_types;
    static const char *const point_keys[] = {"type", "position", "intensity"};
    static const char *const spot_keys[] = {"type", "position", "look_at", "intensity", "cone_angle",
                                            "cone_delta"};
    static const char *const dir_keys[] = {"type", "direction", "irradiance"};
    int type = 0;
    json_t *v;
    CstLightDesc l = {0};
    Color c;
    Vec3 p;
    LOADER_TRY(json_expect_object(ld, obj, "a light object"));
    LOADER_TRY(json_read_type(ld, obj, "light type", types, 4, -1, &type));
    if (type == 3) return parse_projection(ld, obj);
    if (type == 2) {
        LOADER_TRY(json_check_keys(ld, obj, dir_keys, 3));
        l.type = CST_LIGHT_DIRECTIONAL;
        LOADER_TRY(json_member_required(ld, obj, "direction", "the direction the light travels, 3 numbers", &v));
        json_path_push_key(ld, "direction");
        LOADER_TRY(read_direction(ld, v, l.direction));
        json_path_pop(ld);
        LOADER_TRY(json_member_required(ld, obj, "irradiance", "an array of 3 numbers >= 0", &v));
        json_path_push_key(ld, "irradiance");
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
        json_color_floats(c, l.intensity);
        json_path_pop(ld);
    } else {
        LOADER_TRY(json_check_keys(ld, obj, type == 0 ? point_keys : spot_keys, type == 0 ? 3 : 6));
        l.type = type == 0 ? CST_LIGHT_POINT : CST_LIGHT_SPOT;
        LOADER_TRY(json_member_required(ld, obj, "position", "the light's position, 3 numbers", &v));
        json_path_push_key(ld, "position");
        LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &p));
        json_vec3_floats(p, l.position);
        json_path_pop(ld);
        LOADER_TRY(json_member_required(ld, obj, "intensity", "an array of 3 numbers >= 0 (W/sr)", &v));
        json_path_push_key(ld, "intensity");
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
        json_color_floats(c, l.intensity);
        json_path_pop(ld);
        if (type == 1) {
            Vec3 at;
            LOADER_TRY(json_member_required(ld, obj, "look_at", "the point the spot's axis goes through", &v));
            json_path_push_key(ld, "look_at");
            LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &at));
            Vec3 d = v3_sub(at, p);
            float len = v3_length(d);
            if (!(len > 0.0f) || !isfinite(len))
                return json_fail_here(ld, "look_at equals position; expected a point away from the light");
            json_vec3_floats(d, l.direction); /* the builder normalises it */
            json_path_pop(ld);
            /* pbrt-v4's parameters: the cone's half-angle, and how much of it the falloff
             * takes at its edge. */
            LOADER_TRY(read_angle(ld, obj, "cone_angle", 30.0f, 0.001f, 90.0f, &l.cone_angle));
            LOADER_TRY(read_angle(ld, obj, "cone_delta", 5.0f, 0.0f, l.cone_angle, &l.cone_delta));
        }
    }
    CstStatus st = cst_scene_add_light(ld->scene, &l, ld->err);
    return st == CST_OK ? st : json_fail_builder(ld, st); /* located: the power check (issue 25) */
}

CstStatus json_parse_lights(Loader *ld, const json_t *lights)
{
    char kind[48];
    if (!json_is_array(lights))
        return json_fail_here(ld, "got %s; expected an array of lights", json_describe(lights, kind));
    size_t i;
    json_t *light;
    json_array_foreach(lights, i, light) {
        json_path_push_index(ld, i);
        LOADER_TRY(parse_light(ld, light));
        json_path_pop(ld);
    }
    return CST_OK;
}

/* "environment": a constant radiance, or an equirectangular image (EXR, PFM or PNG,
 * relative to the scene file) times a scale. */
CstStatus json_parse_environment(Loader *ld, const json_t *obj)
{
    static const char *const keys[] = {"radiance", "file", "scale", "portal"};
    json_t *v;
    LOADER_TRY(json_expect_object(ld, obj, "an object with radiance, or file and scale, and optionally portal"));
    LOADER_TRY(json_check_keys(ld, obj, keys, 4));
    if ((v = json_object_get(obj, "portal"))) {
        /* four corners of a window rectangle: NEE samples the environment through it */
        char kind[48];
        float c[12];
        json_path_push_key(ld, "portal");
        if (!json_is_array(v) || json_array_size(v) != 4)
            return json_fail_here(ld, "got %s; expected 4 corners, each an array of 3 numbers", json_describe(v, kind));
        for (size_t k = 0; k < 4; k++) {
            Vec3 p;
            json_path_push_index(ld, k);
            LOADER_TRY(json_read_vec3(ld, json_array_get(v, k), LOADER_MAX_LENGTH, &p));
            json_path_pop(ld);
            c[3 * k] = p.x;
            c[3 * k + 1] = p.y;
            c[3 * k + 2] = p.z;
        }
        CstStatus pst = cst_scene_set_environment_portal(ld->scene, c, ld->err);
        if (pst != CST_OK) return json_fail_builder(ld, pst);
        json_path_pop(ld);
    }
    json_t *rad = json_object_get(obj, "radiance"), *file = json_object_get(obj, "file");
    if (!rad == !file)
        return json_fail_here(ld, "expected exactly one of radiance (a constant environment) and file "
                                  "(an equirectangular image)");
    if (rad) {
        if (json_object_get(obj, "scale")) {
            json_path_push_key(ld, "scale");
            return json_fail_here(ld, "scale goes with file; a constant environment is just its radiance");
        }
        Color L;
        float radiance[3];
        json_path_push_key(ld, "radiance");
        LOADER_TRY(json_read_rgb(ld, rad, 0, &L));
        json_path_pop(ld);
        json_color_floats(L, radiance);
        CstStatus st = cst_scene_set_environment_constant(ld->scene, radiance, ld->err);
        return st == CST_OK ? st : json_fail_builder(ld, st); /* located (issue 25) */
    }
    Color scale = color_s(1.0f);
    if ((v = json_object_get(obj, "scale"))) {
        json_path_push_key(ld, "scale");
        if (json_is_number(v)) {
            float k;
            LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &k));
            if (!(k >= 0.0f)) return json_fail_here(ld, "scale %g is negative; expected a number >= 0", (double)k);
            scale = color_s(k);
        } else {
            LOADER_TRY(json_read_rgb(ld, v, 0, &scale));
        }
        json_path_pop(ld);
    }
    const char *name = NULL;
    json_path_push_key(ld, "file");
    LOADER_TRY(json_read_string(ld, file, &name));
    if (!name[0]) return json_fail_here(ld, "the file name is empty; expected the path of an image");
    char *path = path_resolve(ld->name, name);
    if (!path) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    float k[3];
    json_color_floats(scale, k);
    CstStatus st = cst_scene_set_environment_image(ld->scene, path, k, ld->err);
    free(path);
    if (st != CST_OK) return json_fail_builder(ld, st); /* at "file": the image's own errors */
    json_path_pop(ld);
    return CST_OK;
}
