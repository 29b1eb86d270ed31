/* The settings sections of a JSON scene: "film", "camera", "integrator", "sampler". */
#include "scene/json/json_settings.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/image_io.h"
#include "scene/json/json_geometry.h"

#define LOADER_MAX_FILM_SIZE 65536

CstStatus json_parse_film(Loader *ld, const json_t *film)
{
    static const char *const keys[] = {"width", "height", "filter", "output", "exposure", "png_encoding",
                                       "aovs", "crop", "max_component"};
    CstRenderSettings *rs = &ld->settings;
    LOADER_TRY(json_expect_object(ld, film, "an object with width, height, filter, output, exposure, png_encoding, "
                                            "aovs, crop, max_component"));
    LOADER_TRY(json_check_keys(ld, film, keys, 9));
    json_t *v;
    json_int_t i = 0;
    if ((v = json_object_get(film, "width"))) {
        json_path_push_key(ld, "width");
        LOADER_TRY(json_read_int(ld, v, 1, LOADER_MAX_FILM_SIZE, &i));
        rs->width = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "height"))) {
        json_path_push_key(ld, "height");
        LOADER_TRY(json_read_int(ld, v, 1, LOADER_MAX_FILM_SIZE, &i));
        rs->height = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "filter"))) {
        const char *s = NULL;
        json_path_push_key(ld, "filter");
        LOADER_TRY(json_read_string(ld, v, &s));
        CstFilter f = cst_filter_from_name(s);
        if (f == CST_FILTER_DEFAULT) {
            char name[72];
            return json_fail_here(ld, "unknown filter \"%s\"; expected one of: box, tent, gaussian, mitchell",
                                  json_clip_name(s, name));
        }
        rs->filter = f;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "output"))) {
        const char *s = NULL;
        json_path_push_key(ld, "output");
        LOADER_TRY(json_read_string(ld, v, &s));
        /* Checked now, not when the image is written hours later: the writer picks the
         * format from the extension. */
        if (!image_path_is_scene_output(s)) {
            char name[72];
            return json_fail_here(ld, "output \"%s\" has no supported extension; expected a file "
                                      "name ending in .png, .exr or .pfm",
                                  json_clip_name(s, name));
        }
        CstStatus st = cst_scene_set_output_path(ld->scene, s, ld->err);
        if (st != CST_OK)
            return json_fail_builder(ld, st);
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "exposure"))) {
        float ev = 0.0f;
        json_path_push_key(ld, "exposure");
        LOADER_TRY(json_read_float(ld, v, 64.0, &ev));
        rs->exposure = (double)ev;
        rs->exposure_set = 1;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "max_component"))) {
        float m = 0.0f;
        json_path_push_key(ld, "max_component");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m));
        if (!(m > 0.0f))
            return json_fail_here(ld, "%g; expected a number > 0 (the largest XYZ component a sample may "
                                      "add; leave the key out for no clamp)", (double)m);
        rs->max_component = (double)m;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "png_encoding"))) {
        const char *s = NULL;
        json_path_push_key(ld, "png_encoding");
        LOADER_TRY(json_read_string(ld, v, &s));
        if (strcmp(s, "srgb") != 0 && strcmp(s, "linear") != 0) {
            char name[72];
            return json_fail_here(ld, "unknown PNG encoding \"%s\"; expected \"srgb\" or \"linear\"", json_clip_name(s, name));
        }
        rs->png_linear = strcmp(s, "linear") == 0;
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "aovs"))) {
        json_path_push_key(ld, "aovs");
        if (!json_is_array(v))
            return json_fail_here(ld, "expected an array of AOV names (albedo, normal, depth, variance)");
        for (size_t k = 0; k < json_array_size(v); k++) {
            const char *s = NULL;
            json_path_push_index(ld, k);
            LOADER_TRY(json_read_string(ld, json_array_get(v, k), &s));
            int bit = cst_aov_from_name(s);
            if (!bit) {
                char name[72];
                return json_fail_here(ld, "unknown AOV \"%s\"; expected one of: albedo, normal, depth, variance",
                                      json_clip_name(s, name));
            }
            rs->aovs |= bit;
            json_path_pop(ld);
        }
        json_path_pop(ld);
    }
    if ((v = json_object_get(film, "crop"))) {
        /* Checked against the image size here only when the file gives both; cst_render
         * checks the final size (the command line may change it). */
        json_path_push_key(ld, "crop");
        if (!json_is_array(v) || json_array_size(v) != 4)
            return json_fail_here(ld, "expected [x0, x1, y0, y1]: the pixel bounds x0 <= x < x1, y0 <= y < y1 to render");
        for (size_t k = 0; k < 4; k++) {
            json_path_push_index(ld, k);
            LOADER_TRY(json_read_int(ld, json_array_get(v, k), 0, LOADER_MAX_FILM_SIZE, &i));
            rs->crop[k] = (int)i;
            json_path_pop(ld);
        }
        if (!(rs->crop[0] < rs->crop[1] && rs->crop[2] < rs->crop[3]))
            return json_fail_here(ld, "crop [%d, %d, %d, %d]: expected x0 < x1 and y0 < y1", rs->crop[0], rs->crop[1],
                                  rs->crop[2], rs->crop[3]);
        if ((rs->width && rs->crop[1] > rs->width) || (rs->height && rs->crop[3] > rs->height))
            return json_fail_here(ld, "crop [%d, %d, %d, %d]: expected x1 <= width (%d) and y1 <= height (%d)", rs->crop[0],
                                  rs->crop[1], rs->crop[2], rs->crop[3], rs->width, rs->height);
        json_path_pop(ld);
    }
    return CST_OK;
}

enum { CAMERA_PINHOLE, CAMERA_THINLENS, CAMERA_ORTHOGRAPHIC };

/* The camera the loader read and checked, through the public builder. */
static CstStatus set_camera(Loader *ld, const CameraDesc *c, CstCameraType type)
{
    CstCameraDesc d = {0};
    d.type = type;
    json_vec3_floats(c->position, d.position);
    json_vec3_floats(c->look_at, d.look_at);
    json_vec3_floats(c->up, d.up);
    d.fov = c->vfov_deg;
    d.aperture_radius = c->aperture_radius;
    d.focus_distance = c->focus_distance;
    d.height = c->ortho_height;
    CstStatus st = cst_scene_set_camera(ld->scene, &d, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

static CstStatus parse_camera_view(Loader *ld, const json_t *cam)
{
    static const char *const types[] = {"pinhole", "thinlens", "orthographic"};
    static const char *const keys[] = {"type", "position", "look_at", "up", "fov", "shutter", "motion",
                                       "aperture_radius", "focus_distance"};
    static const char *const ortho_keys[] = {"type", "position", "look_at", "up", "height", "shutter", "motion"};
    int type = 0;
    json_t *v;
    LOADER_TRY(json_expect_object(ld, cam, "a camera object"));
    LOADER_TRY(json_read_type(ld, cam, "camera type", types, 3, CAMERA_PINHOLE, &type));
    /* The lens keys mean nothing to a pinhole: reject rather than ignore them. */
    if (type == CAMERA_ORTHOGRAPHIC) LOADER_TRY(json_check_keys(ld, cam, ortho_keys, 7));
    else LOADER_TRY(json_check_keys(ld, cam, keys, type == CAMERA_THINLENS ? 9 : 7));

    CameraDesc desc = {0}; /* read and checked here, then handed over as a CstCameraDesc */
    desc.up = v3(0.0f, 1.0f, 0.0f);
    LOADER_TRY(json_member_required(ld, cam, "position", "the eye point, an array of 3 numbers", &v));
    json_path_push_key(ld, "position");
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.position));
    json_path_pop(ld);

    LOADER_TRY(json_member_required(ld, cam, "look_at", "the point looked at, an array of 3 numbers",
                                    &v));
    json_path_push_key(ld, "look_at");
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.look_at));
    Vec3 forward = v3_sub(desc.look_at, desc.position);
    float dist = v3_length(forward);
    if (!(dist > 0.0f) || !isfinite(dist))
        return json_fail_here(ld, "look_at equals position, so there is no view direction; expected "
                                  "a point other than position");
    json_path_pop(ld);

    if ((v = json_object_get(cam, "up"))) {
        json_path_push_key(ld, "up");
        LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &desc.up));
        json_path_pop(ld);
    }
    /* right = normalize(forward x up) must exist: up must not be zero or along forward.
     * sin(angle) below 1e-4 (0.006 degrees) leaves the frame to rounding. */
    float ul = v3_length(desc.up);
    Vec3 c = v3_cross(v3_scale(forward, 1.0f / dist), desc.up);
    if (!(ul > 0.0f) || !isfinite(ul) || !(v3_length(c) > 1e-4f * ul)) {
        if (json_object_get(cam, "up"))
            json_path_push_key(ld, "up");
        return json_fail_here(ld, "up (%g, %g, %g) is zero or parallel to the view direction; "
                                  "expected a vector not parallel to look_at - position",
                              (double)desc.up.x, (double)desc.up.y, (double)desc.up.z);
    }

    if (type == CAMERA_ORTHOGRAPHIC) {
        LOADER_TRY(json_member_required(ld, cam, "height", "the view's height in scene units, > 0", &v));
        json_path_push_key(ld, "height");
        LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &desc.ortho_height));
        if (!(desc.ortho_height > 0.0f))
            return json_fail_here(ld, "height %g is not positive; expected the view's height in scene units, > 0",
                                  (double)desc.ortho_height);
        json_path_pop(ld);
        return set_camera(ld, &desc, CST_CAMERA_ORTHOGRAPHIC);
    }
    LOADER_TRY(json_member_required(ld, cam, "fov",
                                    "the vertical field of view in degrees, in (0, 180)", &v));
    json_path_push_key(ld, "fov");
    LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &desc.vfov_deg));
    if (!(desc.vfov_deg > 0.0f && desc.vfov_deg < 180.0f))
        return json_fail_here(ld, "fov %g is out of range; expected the vertical field of view in "
                                  "degrees, greater than 0 and less than 180",
                              (double)desc.vfov_deg);
    json_path_pop(ld);

    desc.aperture_radius = 0.0f;
    desc.focus_distance = 0.0f; /* the builder's default: |look_at - position| */
    if (type == CAMERA_THINLENS) {
        LOADER_TRY(json_member_required(ld, cam, "aperture_radius",
                                        "the lens radius in scene units, >= 0", &v));
        json_path_push_key(ld, "aperture_radius");
        LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &desc.aperture_radius));
        if (desc.aperture_radius < 0.0f)
            return json_fail_here(ld, "aperture_radius %g is negative; expected a lens radius >= 0",
                                  (double)desc.aperture_radius);
        json_path_pop(ld);
        if ((v = json_object_get(cam, "focus_distance"))) {
            json_path_push_key(ld, "focus_distance");
            LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &desc.focus_distance));
            if (!(desc.focus_distance > 0.0f))
                return json_fail_here(ld, "focus_distance %g is not positive; expected a distance > 0",
                                      (double)desc.focus_distance);
            json_path_pop(ld);
        }
    }
    return set_camera(ld, &desc, CST_CAMERA_PERSPECTIVE);
}

/* Motion blur: "shutter": [open, close] (times where 0 and 1 are every motion's ends;
 * default [0, 1]) and "motion" (json_parse_motion), which places the camera the other keys
 * describe, as a moving mesh's transforms place its vertices. */
CstStatus json_parse_camera(Loader *ld, const json_t *cam)
{
    LOADER_TRY(parse_camera_view(ld, cam));
    json_t *v;
    CstStatus st = CST_OK;
    if ((v = json_object_get(cam, "shutter"))) {
        char kind[48];
        float t[2];
        json_path_push_key(ld, "shutter");
        if (!json_is_array(v) || json_array_size(v) != 2)
            return json_fail_here(ld, "got %s; expected [open, close], two times", json_describe(v, kind));
        for (size_t k = 0; k < 2; k++) {
            json_path_push_index(ld, k);
            LOADER_TRY(json_read_float(ld, json_array_get(v, k), 1e6, &t[k]));
            json_path_pop(ld);
        }
        if (!(t[0] <= t[1]))
            return json_fail_here(ld, "shutter [%g, %g] closes before it opens; expected open <= close",
                                  (double)t[0], (double)t[1]);
        if ((st = cst_scene_set_shutter(ld->scene, t[0], t[1], ld->err)) != CST_OK) return json_fail_builder(ld, st);
        json_path_pop(ld);
    }
    if ((v = json_object_get(cam, "motion"))) {
        Transform t0, t1;
        json_path_push_key(ld, "motion");
        LOADER_TRY(json_parse_motion(ld, v, &t0, &t1));
        float r0[12], r1[12];
        for (int r = 0; r < 3; r++)
            for (int k = 0; k < 4; k++) {
                r0[4 * r + k] = t0.m[r][k];
                r1[4 * r + k] = t1.m[r][k];
            }
        if ((st = cst_scene_set_camera_motion(ld->scene, r0, r1, ld->err)) != CST_OK) return json_fail_builder(ld, st);
        json_path_pop(ld);
    }
    return CST_OK;
}

/* Metropolis light transport's parameters (pssmlt; ignored by the other integrators, but
 * mutations_per_pixel, which sets spp, only with an MLT type). */
static CstStatus parse_mlt(Loader *ld, const json_t *integ)
{
    CstRenderSettings *rs = &ld->settings;
    json_t *v;
    json_int_t i = 0;
    if ((v = json_object_get(integ, "mutations_per_pixel"))) {
        json_path_push_key(ld, "mutations_per_pixel");
        if (rs->integrator != CST_INTEGRATOR_PSSMLT && rs->integrator != CST_INTEGRATOR_MMLT)
            return json_fail_here(ld, "mutations_per_pixel is the sample count of MLT; expected it with type "
                                      "\"pssmlt\" or \"mmlt\" (use the film's spp otherwise)");
        LOADER_TRY(json_read_int(ld, v, 1, INT_MAX, &i));
        rs->spp = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "large_step_probability"))) {
        float f = 0.0f;
        json_path_push_key(ld, "large_step_probability");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &f));
        if (!(f >= 0.0f && f <= 1.0f)) return json_fail_here(ld, "large_step_probability %g; expected a probability in [0, 1]", (double)f);
        rs->mlt_large_step = (double)f;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "sigma"))) {
        float f = 0.0f;
        json_path_push_key(ld, "sigma");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &f));
        if (!(f > 0.0f && f <= 1.0f)) return json_fail_here(ld, "sigma %g; expected a small-step width in (0, 1]", (double)f);
        rs->mlt_sigma = (double)f;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "bootstrap_samples"))) {
        json_path_push_key(ld, "bootstrap_samples");
        LOADER_TRY(json_read_int(ld, v, 1, 1 << 28, &i));
        rs->mlt_bootstrap = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "chains"))) {
        json_path_push_key(ld, "chains");
        LOADER_TRY(json_read_int(ld, v, 1, 1 << 24, &i));
        rs->mlt_chains = (int)i;
        json_path_pop(ld);
    }
    return CST_OK;
}

CstStatus json_parse_integrator(Loader *ld, const json_t *integ)
{
    static const char *const keys[] = {"type", "max_depth", "rr_depth", "light_rr_depth", "photons", "radius", "color",
                                       "light_sampler", "regularize", "light_sampling", "mutations_per_pixel",
                                       "large_step_probability", "sigma", "bootstrap_samples", "chains"};
    CstRenderSettings *rs = &ld->settings;
    json_t *v;
    json_int_t i = 0;
    LOADER_TRY(json_expect_object(ld, integ, "an object with type, max_depth, rr_depth, light_rr_depth, photons, radius, color, light_sampling, "
                                             "light_sampler, regularize, mutations_per_pixel, large_step_probability, "
                                             "sigma, bootstrap_samples, chains"));
    LOADER_TRY(json_check_keys(ld, integ, keys, (int)(sizeof keys / sizeof keys[0])));
    if ((v = json_object_get(integ, "regularize"))) {
        int reg = 0;
        json_path_push_key(ld, "regularize");
        LOADER_TRY(json_read_bool(ld, v, &reg));
        rs->regularize = reg ? 1 : 0;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "light_sampler"))) {
        /* NEE's choice of light: "power", "bvh" or "uniform" (docs/scene-format.md) */
        const char *s = NULL;
        json_path_push_key(ld, "light_sampler");
        LOADER_TRY(json_read_string(ld, v, &s));
        if (strcmp(s, "power") != 0 && strcmp(s, "bvh") != 0 && strcmp(s, "uniform") != 0) {
            char name[72];
            return json_fail_here(ld, "unknown light sampler \"%s\"; expected \"power\", \"bvh\" or \"uniform\"",
                                  json_clip_name(s, name));
        }
        LOADER_TRY(cst_scene_set_light_sampler(ld->scene, s, ld->err));
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "light_sampling"))) {
        /* NEE's point on an emitting triangle: "area" (default) or "solid_angle" */
        const char *s = NULL;
        json_path_push_key(ld, "light_sampling");
        LOADER_TRY(json_read_string(ld, v, &s));
        if (strcmp(s, "area") != 0 && strcmp(s, "solid_angle") != 0) {
            char name[72];
            return json_fail_here(ld, "unknown light sampling \"%s\"; expected \"area\" or \"solid_angle\"",
                                  json_clip_name(s, name));
        }
        LOADER_TRY(cst_scene_set_light_sampling(ld->scene, s, ld->err));
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "color"))) {
        /* "rgb" (the default) or "spectral" (docs/scene-format.md). */
        const char *s = NULL;
        json_path_push_key(ld, "color");
        LOADER_TRY(json_read_string(ld, v, &s));
        if (strcmp(s, "rgb") == 0) rs->color_mode = CST_COLOR_RGB;
        else if (strcmp(s, "spectral") == 0) rs->color_mode = CST_COLOR_SPECTRAL;
        else {
            char name[72];
            return json_fail_here(ld, "unknown color mode \"%s\"; expected \"rgb\" or \"spectral\"",
                                  json_clip_name(s, name));
        }
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "type"))) {
        const char *s = NULL;
        json_path_push_key(ld, "type");
        LOADER_TRY(json_read_string(ld, v, &s));
        CstIntegrator t = cst_integrator_from_name(s);
        if (t == CST_INTEGRATOR_DEFAULT) {
            char name[72];
            return json_fail_here(ld, "unknown integrator \"%s\"; expected one of: path, path-nee, "
                                      "path-bsdf, light, whitted, photon, sppm, bdpt, vcm, pssmlt, mmlt",
                                  json_clip_name(s, name));
        }
        rs->integrator = t;
        json_path_pop(ld);
    }
    LOADER_TRY(parse_mlt(ld, integ));
    if ((v = json_object_get(integ, "max_depth"))) {
        json_path_push_key(ld, "max_depth");
        LOADER_TRY(json_read_int(ld, v, 0, INT_MAX, &i)); /* 0 = unbounded */
        rs->max_depth = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "rr_depth"))) {
        /* From 1: the settings struct reads 0 as "default", which a file should not say. */
        json_path_push_key(ld, "rr_depth");
        LOADER_TRY(json_read_int(ld, v, 1, INT_MAX, &i));
        rs->rr_depth = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "light_rr_depth"))) { /* bdpt and vcm; from 1 as rr_depth */
        json_path_push_key(ld, "light_rr_depth");
        LOADER_TRY(json_read_int(ld, v, 1, INT_MAX, &i));
        rs->light_rr_depth = (int)i;
        json_path_pop(ld);
    }
    /* Photon mapping only (ignored by the other integrators). At most 2^28 photon paths:
     * the stored photons (several per path) must stay within the photon map's 2^30. */
    if ((v = json_object_get(integ, "photons"))) {
        json_path_push_key(ld, "photons");
        LOADER_TRY(json_read_int(ld, v, 1, (json_int_t)1 << 28, &i));
        rs->photons = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(integ, "radius"))) {
        float r = 0.0f;
        json_path_push_key(ld, "radius");
        LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &r));
        if (!(r > 0.0f))
            return json_fail_here(ld, "radius %g is not positive; expected a gather radius > 0 (omit it for "
                                      "the automatic radius)",
                                  (double)r);
        /* r^2 must stay a normal float (issue 25); the render also refuses radii below 1e-6 of
         * the scene's diagonal (integrator.c's check_radius), which only it knows. */
        if (!(r >= 1e-18f))
            return json_fail_here(ld, "radius %g is below 1e-18, whose square underflows; expected a gather "
                                      "radius of at least 1e-6 of the scene's size (omit it for the automatic "
                                      "radius)",
                                  (double)r);
        rs->photon_radius = (double)r;
        json_path_pop(ld);
    }
    return CST_OK;
}

CstStatus json_parse_sampler(Loader *ld, const json_t *sampler)
{
    static const char *const keys[] = {"spp", "seed", "type"};
    CstRenderSettings *rs = &ld->settings;
    json_t *v;
    json_int_t i = 0;
    LOADER_TRY(json_expect_object(ld, sampler, "an object with spp, seed, type"));
    LOADER_TRY(json_check_keys(ld, sampler, keys, 3));
    if ((v = json_object_get(sampler, "type"))) {
        const char *s = NULL;
        json_path_push_key(ld, "type");
        LOADER_TRY(json_read_string(ld, v, &s));
        rs->sampler = cst_sampler_from_name(s);
        if (rs->sampler == CST_SAMPLER_DEFAULT) {
            char name[72];
            return json_fail_here(ld, "unknown sampler \"%s\"; expected one of: independent, stratified, sobol, zsobol",
                                  json_clip_name(s, name));
        }
        json_path_pop(ld);
    }
    if ((v = json_object_get(sampler, "spp"))) {
        json_path_push_key(ld, "spp");
        LOADER_TRY(json_read_int(ld, v, 1, INT_MAX, &i));
        rs->spp = (int)i;
        json_path_pop(ld);
    }
    if ((v = json_object_get(sampler, "seed"))) {
        json_path_push_key(ld, "seed");
        LOADER_TRY(json_read_int(ld, v, 0, LOADER_NO_MAX, &i));
        rs->seed = (uint64_t)i;
        rs->seed_set = 1;
        json_path_pop(ld);
    }
    return CST_OK;
}
