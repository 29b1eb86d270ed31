/* The JSON loader's participating media (json_medium.h): homogeneous, uniform-grid and
 * cloud media with pbrt-v4's parameters and defaults (and its measured presets), medium
 * references by name, shapes' medium interfaces. */
#include "scene/json/json_medium.h"

#include <stdlib.h>
#include <string.h>

#include "media/medium_presets.h"

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

/* obj[key], an array of exactly count numbers >= 0, into a new array (*out; NULL when the
 * key is absent). The error points at the array (its length) or at the bad element. */
static CstStatus read_grid(Loader *ld, const json_t *obj, const char *key, size_t count, float **out)
{
    *out = NULL;
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    if (!json_is_array(v)) {
        char buf[48];
        return json_fail_here(ld, "got %s; expected an array of nx*ny*nz = %zu numbers >= 0", json_describe(v, buf),
                              count);
    }
    if (json_array_size(v) != count)
        return json_fail_here(ld, "%zu values; expected nx*ny*nz = %zu numbers >= 0", json_array_size(v), count);
    float *a = malloc((count ? count : 1) * sizeof *a);
    if (!a) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    for (size_t i = 0; i < count; i++) {
        json_path_push_index(ld, i);
        CstStatus st = json_read_float(ld, json_array_get(v, i), 1e30, &a[i]);
        if (st == CST_OK && !(a[i] >= 0.0f)) st = json_fail_here(ld, "%g; expected a number >= 0", (double)a[i]);
        if (st != CST_OK) {
            free(a);
            return st;
        }
        json_path_pop(ld);
    }
    json_path_pop(ld);
    *out = a;
    return CST_OK;
}

static CstStatus read_int_key(Loader *ld, const json_t *obj, const char *key, int *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    json_int_t x;
    LOADER_TRY(json_read_int(ld, v, 1, 4096, &x));
    *out = (int)x;
    json_path_pop(ld);
    return CST_OK;
}

static CstStatus read_point(Loader *ld, const json_t *obj, const char *key, float out[3])
{
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    Vec3 p;
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &p));
    json_vec3_floats(p, out);
    json_path_pop(ld);
    return CST_OK;
}

/* The keys each type accepts, in the order of json_parse_media's `types`. */
static const char *const KEYS_HOMOG[] = {"type", "sigma_a", "sigma_s", "scale", "g", "Le", "Lescale", "preset"};
static const char *const KEYS_GRID[] = {"type", "sigma_a", "sigma_s", "scale", "g", "Le", "Lescale", "preset",
                                        "p0", "p1", "nx", "ny", "nz", "density"};
static const char *const KEYS_CLOUD[] = {"type", "sigma_a", "sigma_s", "scale", "g", "preset",
                                         "p0", "p1", "density", "wispiness", "frequency"};

/* The heterogeneous keys of medium v (type 1: uniformgrid, 2: cloud) into d; a grid's
 * arrays are new (*density, *le_grid: the caller frees them). */
static CstStatus read_hetero(Loader *ld, const json_t *v, int type, CstMediumDesc *d, float **density,
                             float **le_grid)
{
    d->type = type == 1 ? CST_MEDIUM_UNIFORMGRID : CST_MEDIUM_CLOUD;
    LOADER_TRY(read_point(ld, v, "p0", d->p0));
    LOADER_TRY(read_point(ld, v, "p1", d->p1));
    for (int a = 0; a < 3; a++)
        if (!(d->p0[a] != d->p1[a])) return json_fail_here(ld, "p0 and p1 are equal on an axis; expected a box of "
                                                              "positive size");
    if (type == 2) {
        LOADER_TRY(read_scalar(ld, v, "density", 1e30, &d->cloud_density));
        LOADER_TRY(read_scalar(ld, v, "wispiness", 1e30, &d->wispiness));
        LOADER_TRY(read_scalar(ld, v, "frequency", 1e30, &d->frequency));
        return CST_OK;
    }
    LOADER_TRY(read_int_key(ld, v, "nx", &d->nx));
    LOADER_TRY(read_int_key(ld, v, "ny", &d->ny));
    LOADER_TRY(read_int_key(ld, v, "nz", &d->nz));
    size_t count = (size_t)d->nx * (size_t)d->ny * (size_t)d->nz;
    if (count > ((size_t)1 << 28)) return json_fail_here(ld, "nx*ny*nz = %zu; expected at most 2^28 samples", count);
    json_t *lv = json_object_get(v, "Lescale");
    if (!json_object_get(v, "density")) {
        json_t *dummy;
        return json_member_required(ld, v, "density", "an array of nx*ny*nz densities >= 0", &dummy);
    }
    LOADER_TRY(read_grid(ld, v, "density", count, density));
    if (lv && json_is_array(lv)) {
        CstStatus st = read_grid(ld, v, "Lescale", count, le_grid);
        if (st != CST_OK) return st;
    }
    d->density = *density;
    d->le_scale_grid = *le_grid;
    return CST_OK;
}

CstStatus json_parse_media(Loader *ld, const json_t *media)
{
    static const char *const types[] = {"homogeneous", "uniformgrid", "cloud"};
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
        LOADER_TRY(json_read_type(ld, v, "medium type", types, 3, 0, &type));
        if (type == 0) LOADER_TRY(json_check_keys(ld, v, KEYS_HOMOG, 8));
        else if (type == 1) LOADER_TRY(json_check_keys(ld, v, KEYS_GRID, 14));
        else LOADER_TRY(json_check_keys(ld, v, KEYS_CLOUD, 11));
        CstMediumDesc d;
        cst_medium_desc_init(&d);
        LOADER_TRY(read_coeff(ld, v, "sigma_a", d.sigma_a));
        LOADER_TRY(read_coeff(ld, v, "sigma_s", d.sigma_s));
        LOADER_TRY(read_coeff(ld, v, "Le", d.le));
        LOADER_TRY(read_scalar(ld, v, "scale", 1e30, &d.scale));
        json_t *lv = json_object_get(v, "Lescale");
        /* A grid's Lescale may be a grid too (read_hetero); elsewhere one number. */
        if (!(type == 1 && lv && json_is_array(lv))) LOADER_TRY(read_scalar(ld, v, "Lescale", 1e30, &d.le_scale));
        LOADER_TRY(read_scalar(ld, v, "g", 1e30, &d.g));
        json_t *pv = json_object_get(v, "preset");
        if (pv) {
            json_path_push_key(ld, "preset");
            LOADER_TRY(json_read_string(ld, pv, &d.preset));
            Color sa, ss;
            if (!medium_preset(d.preset, &sa, &ss)) {
                char buf[72];
                return json_fail_here(ld, "no scattering preset is called \"%s\"; expected one of pbrt-v4's "
                                          "measured media (\"Skimmilk\", \"Wholemilk\", \"Ketchup\", \"Regular "
                                          "Milk\", \"Espresso\", ... see docs/scene-format.md)",
                                      json_clip_name(d.preset, buf));
            }
            json_path_pop(ld);
        }
        if (!(d.g > -1.0f && d.g < 1.0f)) {
            json_path_push_key(ld, "g");
            return json_fail_here(ld, "%g; expected a number in (-1, 1) (Henyey–Greenstein asymmetry)", (double)d.g);
        }
        if (!(d.scale >= 0.0f && d.le_scale >= 0.0f))
            return json_fail_here(ld, "a negative scale or Lescale; expected numbers >= 0");
        float *density = NULL, *le_grid = NULL;
        CstStatus st = type ? read_hetero(ld, v, type, &d, &density, &le_grid) : CST_OK;
        int id;
        if (st == CST_OK && cst_scene_add_medium(ld->scene, &d, &id, ld->err) != CST_OK)
            st = json_fail_builder(ld, ld->err->status);
        free(density);
        free(le_grid);
        if (st != CST_OK) return st;
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
