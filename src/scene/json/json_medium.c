/* The JSON loader's participating media (json_medium.h): homogeneous media with pbrt-v4's
 * parameters and defaults, medium references by name, shapes' medium interfaces. */
#include "scene/json/json_medium.h"

#include <stdlib.h>
#include <string.h>

/* A colour given as [r, g, b] or one number (a grey). */
static CstStatus read_coeff(Loader *ld, const json_t *obj, const char *key, float out[3])
{
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    Color c;
    if (json_is_number(v)) {
        float x;
        LOADER_TRY(json_read_float(ld, v, 1e30, &x));
        c = color_s(x);
    } else {
        LOADER_TRY(json_read_rgb(ld, v, 0, &c));
    }
    if (!(c.c[0] >= 0.0f && c.c[1] >= 0.0f && c.c[2] >= 0.0f))
        return json_fail_here(ld, "a negative value; expected numbers >= 0");
    json_color_floats(c, out);
    json_path_pop(ld);
    return CST_OK;
}

static CstStatus read_scalar(Loader *ld, const json_t *obj, const char *key, double max_abs, float *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, max_abs, out));
    json_path_pop(ld);
    return CST_OK;
}

CstStatus json_parse_media(Loader *ld, const json_t *media)
{
    static const char *const keys[] = {"type", "sigma_a", "sigma_s", "scale", "g", "Le", "Lescale"};
    static const char *const types[] = {"homogeneous"};
    LOADER_TRY(json_expect_object(ld, media, "an object mapping medium names to media"));
    size_t n = json_object_size(media);
    if (n > 65536) return json_fail_here(ld, "%zu media; expected at most 65536", n);
    ld->med_names = malloc((n ? n : 1) * sizeof *ld->med_names);
    if (!ld->med_names) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    const char *name;
    json_t *v;
    json_object_foreach((json_t *)media, name, v) {
        json_path_push_key(ld, name);
        LOADER_TRY(json_expect_object(ld, v, "a medium object"));
        int type = 0;
        LOADER_TRY(json_read_type(ld, v, "medium type", types, 1, 0, &type));
        LOADER_TRY(json_check_keys(ld, v, keys, 7));
        CstMediumDesc d;
        cst_medium_desc_init(&d);
        LOADER_TRY(read_coeff(ld, v, "sigma_a", d.sigma_a));
        LOADER_TRY(read_coeff(ld, v, "sigma_s", d.sigma_s));
        LOADER_TRY(read_coeff(ld, v, "Le", d.le));
        LOADER_TRY(read_scalar(ld, v, "scale", 1e30, &d.scale));
        LOADER_TRY(read_scalar(ld, v, "Lescale", 1e30, &d.le_scale));
        LOADER_TRY(read_scalar(ld, v, "g", 1e30, &d.g));
        if (!(d.g > -1.0f && d.g < 1.0f)) {
            json_path_push_key(ld, "g");
            return json_fail_here(ld, "%g; expected a number in (-1, 1) (Henyey–Greenstein asymmetry)", (double)d.g);
        }
        if (!(d.scale >= 0.0f && d.le_scale >= 0.0f))
            return json_fail_here(ld, "a negative scale or Lescale; expected numbers >= 0");
        int id;
        if (cst_scene_add_medium(ld->scene, &d, &id, ld->err) != CST_OK)
            return json_fail_builder(ld, ld->err->status);
        ld->med_names[ld->num_media++] = name;
        json_path_pop(ld);
    }
    return CST_OK;
}

/* A medium by name (-1 for null). */
static CstStatus read_medium_ref(Loader *ld, const json_t *v, int *out)
{
    if (json_is_null(v)) {
        *out = -1;
        return CST_OK;
    }
    const char *s = NULL;
    LOADER_TRY(json_read_string(ld, v, &s));
    for (int i = 0; i < ld->num_media; i++)
        if (strcmp(ld->med_names[i], s) == 0) {
            *out = i;
            return CST_OK;
        }
    char name[72], list[512];
    if (ld->num_media == 0)
        return json_fail_here(ld, "medium \"%s\" is not defined (no media are); expected a name defined under "
                                  "\"media\", or null for vacuum", json_clip_name(s, name));
    json_join_names(ld->med_names, ld->num_media, list, sizeof list);
    return json_fail_here(ld, "medium \"%s\" is not defined; expected null or one of: %s", json_clip_name(s, name),
                          list);
}

CstStatus json_parse_camera_medium(Loader *ld, const json_t *v)
{
    int m;
    LOADER_TRY(read_medium_ref(ld, v, &m));
    if (cst_scene_set_camera_medium(ld->scene, m, ld->err) != CST_OK) return json_fail_builder(ld, ld->err->status);
    return CST_OK;
}

CstStatus json_read_shape_medium(Loader *ld, const json_t *shape, int *boundary)
{
    static const char *const keys[] = {"inside", "outside", "boundary"};
    json_t *v = json_object_get(shape, "medium");
    int inside = -1, outside = -1;
    *boundary = 0;
    if (v) {
        json_path_push_key(ld, "medium");
        LOADER_TRY(json_expect_object(ld, v, "an object with \"inside\" and \"outside\" media"));
        LOADER_TRY(json_check_keys(ld, v, keys, 3));
        json_t *m;
        if ((m = json_object_get(v, "inside"))) {
            json_path_push_key(ld, "inside");
            LOADER_TRY(read_medium_ref(ld, m, &inside));
            json_path_pop(ld);
        }
        if ((m = json_object_get(v, "outside"))) {
            json_path_push_key(ld, "outside");
            LOADER_TRY(read_medium_ref(ld, m, &outside));
            json_path_pop(ld);
        }
        if ((m = json_object_get(v, "boundary"))) {
            json_path_push_key(ld, "boundary");
            LOADER_TRY(json_read_bool(ld, m, boundary));
            json_path_pop(ld);
        }
        json_path_pop(ld);
    }
    /* Scenes without media never change the builder's state. */
    if (!v && ld->num_media == 0) return CST_OK;
    if (cst_scene_set_medium_interface(ld->scene, inside, outside, *boundary, ld->err) != CST_OK)
        return json_fail_builder(ld, ld->err->status);
    return CST_OK;
}

CstStatus json_boundary_material(Loader *ld, int *material)
{
    if (ld->boundary_material < 0) {
        CstMaterialDesc d;
        cst_material_desc_init(&d, CST_MATERIAL_DIFFUSE);
        d.albedo[0] = d.albedo[1] = d.albedo[2] = 0.0f;
        if (cst_scene_add_material(ld->scene, &d, &ld->boundary_material, ld->err) != CST_OK)
            return json_fail_builder(ld, ld->err->status);
    }
    *material = ld->boundary_material;
    return CST_OK;
}
