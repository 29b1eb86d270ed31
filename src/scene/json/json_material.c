/* The "materials" section: material types, roughness, textured parameters, and the
 * material references and emission of shapes. */
#include "scene/json/json_material.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/path.h"
#include "materials/bssrdf.h"
#include "media/medium_presets.h"
#include "materials/hair.h"
#include "scene/json/json_texture.h"

enum { MAT_DIFFUSE, MAT_MIRROR, MAT_GLASS, MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_PLASTIC, MAT_COATED_DIFFUSE,
       MAT_COATED_CONDUCTOR, MAT_MIX, MAT_DIFFUSE_TRANSMISSION, MAT_THIN_DIELECTRIC, MAT_MEASURED, MAT_HAIR,
       MAT_SUBSURFACE, MAT_COUNT };

/* A material's "type", in MAT_* order (json_material.h). */
const char *const json_material_types[] = {"diffuse", "mirror", "glass", "conductor", "dielectric",
                                           "plastic", "coated_diffuse", "coated_conductor", "mix", "diffuse_transmission",
                                           "thin_dielectric", "measured", "hair", "subsurface", NULL};

/* "roughness" (or another roughness key): perceptual, in [0, 1] (material.h: alpha =
 * roughness^2). */
static CstStatus read_roughness_key(Loader *ld, const json_t *v, const char *key, float *out)
{
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, out));
    if (!(*out >= 0.0f && *out <= 1.0f))
        return json_fail_here(ld, "roughness %g is outside [0, 1]; expected 0 (smooth) to 1 (roughest)",
                              (double)*out);
    json_path_pop(ld);
    return CST_OK;
}
static CstStatus read_roughness(Loader *ld, const json_t *v, float *out) { return read_roughness_key(ld, v, "roughness", out); }

/* Anisotropic roughness and pbrt-v4's remapping switch: "uroughness" and "vroughness"
 * (along the surface's dp/du and across it; default "roughness"), for a coated conductor
 * also "base_uroughness" and "base_vroughness" (default "base_roughness"); all perceptual
 * in [0, 1] unless "remaproughness" is false, when every roughness number of the material
 * is GGX's alpha itself, in [0, 1] (stored as its square root, the perceptual roughness of
 * that alpha). Not with a roughness texture. */
static CstStatus read_anisotropy(Loader *ld, const json_t *obj, Material *m)
{
    json_t *v;
    int remap = 1;
    if ((v = json_object_get(obj, "remaproughness"))) {
        json_path_push_key(ld, "remaproughness");
        LOADER_TRY(json_read_bool(ld, v, &remap));
        if (!remap && m->roughness_texture)
            return json_fail_here(ld, "remaproughness false with a roughness texture; expected a texture of "
                                      "perceptual roughness (remaproughness true)");
        json_path_pop(ld);
    }
    const bool coated_cond = m->type == MATERIAL_COATED_CONDUCTOR;
    static const char *const keys[4] = {"uroughness", "vroughness", "base_uroughness", "base_vroughness"};
    float r[4] = {m->roughness, m->roughness, m->base_roughness, m->base_roughness};
    for (int i = 0; i < (coated_cond ? 4 : 2); i++) {
        if (!(v = json_object_get(obj, keys[i]))) continue;
        if (i < 2 && m->roughness_texture) {
            json_path_push_key(ld, keys[i]);
            return json_fail_here(ld, "%s with a roughness texture; expected either a textured (isotropic) "
                                      "\"roughness\" or numbers", keys[i]);
        }
        LOADER_TRY(read_roughness_key(ld, v, keys[i], &r[i]));
    }
    if (!remap)
        for (int i = 0; i < 4; i++) r[i] = sqrtf(r[i]);
    m->roughness = r[0];
    m->roughness_v = r[1];
    m->base_roughness = r[2];
    m->base_roughness_v = r[3];
    m->anisotropic = r[0] != r[1] || r[2] != r[3];
    return CST_OK;
}

/* The coated materials' layer: "thickness" (>= 0, default 0.01), "layer_albedo" (RGB in
 * [0, 1], default 0), "g" (in (-1, 1), default 0), "max_depth" (default 10), "nsamples"
 * (default 1): pbrt-v4's parameters and defaults. */
static CstStatus read_layer(Loader *ld, const json_t *obj, Material *m)
{
    json_t *v;
    json_int_t n;
    m->thickness = 0.01f;
    m->max_depth = 10;
    m->nsamples = 1;
    if ((v = json_object_get(obj, "base_roughness"))) {
        LOADER_TRY(read_roughness_key(ld, v, "base_roughness", &m->base_roughness));
    }
    if ((v = json_object_get(obj, "thickness"))) {
        json_path_push_key(ld, "thickness");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m->thickness));
        if (!(m->thickness >= 0.0f))
            return json_fail_here(ld, "thickness %g is negative; expected the layer's thickness >= 0",
                                  (double)m->thickness);
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "layer_albedo"))) {
        json_path_push_key(ld, "layer_albedo");
        LOADER_TRY(json_read_rgb(ld, v, 1, &m->layer_albedo));
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "g"))) {
        json_path_push_key(ld, "g");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m->g));
        if (!(m->g > -1.0f && m->g < 1.0f))
            return json_fail_here(ld, "g %g is outside (-1, 1); expected a Henyey-Greenstein asymmetry "
                                      "(0 isotropic)", (double)m->g);
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "max_depth"))) {
        json_path_push_key(ld, "max_depth");
        LOADER_TRY(json_read_int(ld, v, 1, 100000, &n));
        m->max_depth = (int)n;
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "nsamples"))) {
        json_path_push_key(ld, "nsamples");
        LOADER_TRY(json_read_int(ld, v, 1, 10000, &n));
        m->nsamples = (int)n;
        json_path_pop(ld);
    }
    return CST_OK;
}

/* A mix: "materials", the names of two materials defined before it, and "amount" (the
 * probability of the second, in [0, 1], default 0.5, or a texture name). */
static CstStatus read_mix(Loader *ld, const json_t *obj, Material *m)
{
    json_t *v;
    m->amount = 0.5f;
    LOADER_TRY(json_member_required(ld, obj, "materials", "the names of two materials defined before the mix", &v));
    json_path_push_key(ld, "materials");
    if (!json_is_array(v) || json_array_size(v) != 2)
        return json_fail_here(ld, "expected an array of the names of two materials defined before the mix");
    for (size_t i = 0; i < 2; i++) {
        const char *name = NULL;
        json_path_push_index(ld, i);
        LOADER_TRY(json_read_string(ld, json_array_get(v, i), &name));
        int found = -1;
        for (int j = 0; j < ld->num_materials; j++)
            if (strcmp(ld->mat_names[j], name) == 0) found = ld->mat_ids[j];
        if (found < 0) {
            char clipped[72];
            return json_fail_here(ld, "material \"%s\" is not defined before the mix; expected the name of "
                                      "a material listed above it", json_clip_name(name, clipped));
        }
        m->mix[i] = found;
        json_path_pop(ld);
    }
    json_path_pop(ld);
    if ((v = json_object_get(obj, "amount"))) {
        json_path_push_key(ld, "amount");
        if (json_is_string(v)) {
            LOADER_TRY(json_read_param_texture(ld, v, "an amount", &m->amount_texture));
        } else {
            LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m->amount));
            if (!(m->amount >= 0.0f && m->amount <= 1.0f))
                return json_fail_here(ld, "amount %g is outside [0, 1]; expected the probability of the "
                                          "second material", (double)m->amount);
        }
        json_path_pop(ld);
    }
    return CST_OK;
}

/* A float key in [lo, hi] into *out, if present. */
static CstStatus read_float_range(Loader *ld, const json_t *obj, const char *key, float lo, float hi,
                                  const char *expected, float *out)
{
    json_t *v = json_object_get(obj, key);
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, out));
    if (!(*out >= lo && *out <= hi)) return json_fail_here(ld, "%s %g; expected %s", key, (double)*out, expected);
    json_path_pop(ld);
    return CST_OK;
}

/* A hair (pbrt-v4's, hair.h): "ior" (default 1.55), "beta_m" and "beta_n" in (0, 1]
 * (0.3), "alpha" the cuticle tilt in degrees (2), and one way of giving the absorption:
 * "sigma_a" (RGB per fibre radius, >= 0), "color" (RGB in [0, 1] or a texture name: the
 * fibre's colour, Chiang et al. eq. 9) or "eumelanin" and "pheomelanin" (>= 0; the
 * default, 1.3 and 0). */
static CstStatus read_hair(Loader *ld, const json_t *obj, Material *m)
{
    json_t *v;
    m->ior = 1.55f;
    m->beta_m = m->beta_n = 0.3f;
    m->hair_alpha = 2.0f;
    if ((v = json_object_get(obj, "ior"))) {
        json_path_push_key(ld, "ior");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m->ior));
        if (!(m->ior > 0.0f))
            return json_fail_here(ld, "ior %g is not positive; expected the fibre's index of refraction > 0 "
                                      "(hair is about 1.55)", (double)m->ior);
        json_path_pop(ld);
    }
    LOADER_TRY(read_float_range(ld, obj, "beta_m", 1e-30f, 1.0f, "a longitudinal roughness in (0, 1]", &m->beta_m));
    LOADER_TRY(read_float_range(ld, obj, "beta_n", 1e-30f, 1.0f, "an azimuthal roughness in (0, 1]", &m->beta_n));
    LOADER_TRY(read_float_range(ld, obj, "alpha", -90.0f, 90.0f, "the cuticle tilt in degrees, in [-90, 90]",
                                &m->hair_alpha));
    json_t *sig = json_object_get(obj, "sigma_a"), *col = json_object_get(obj, "color");
    const bool mel = json_object_get(obj, "eumelanin") || json_object_get(obj, "pheomelanin");
    if ((sig != NULL) + (col != NULL) + mel > 1) {
        json_path_push_key(ld, sig ? "sigma_a" : "color");
        return json_fail_here(ld, "more than one of \"sigma_a\", \"color\" and \"eumelanin\"/\"pheomelanin\"; "
                                  "expected one way of giving the fibre's absorption");
    }
    if (sig) {
        json_path_push_key(ld, "sigma_a");
        LOADER_TRY(json_read_rgb(ld, sig, 0, &m->sigma_a));
        json_path_pop(ld);
    } else if (col) {
        m->hair_color = true;
        json_path_push_key(ld, "color");
        if (json_is_string(col))
            LOADER_TRY(json_read_param_texture(ld, col, "a colour", &m->albedo_texture));
        else
            LOADER_TRY(json_read_rgb(ld, col, 1, &m->albedo));
        json_path_pop(ld);
    } else {
        float eu = mel ? 0.0f : 1.3f, ph = 0.0f;
        LOADER_TRY(read_float_range(ld, obj, "eumelanin", 0.0f, 1e6f, "a concentration >= 0 (and at most 1e6)", &eu));
        LOADER_TRY(read_float_range(ld, obj, "pheomelanin", 0.0f, 1e6f, "a concentration >= 0 (and at most 1e6)", &ph));
        m->sigma_a = hair_sigma_a_from_melanin(eu, ph);
    }
    return CST_OK;
}

/* A subsurface material (pbrt-v4's): the medium by "name" (a measured one, g = 0),
 * "sigma_a" with "sigma_s" (per unit length), or "reflectance" (RGB or a texture) with
 * "mfp" (default 1), else pbrt-v4's defaults; "scale" multiplies the coefficients or the
 * mean free path; "g" the phase asymmetry. The surface (ior, roughness) is read by the
 * caller as a dielectric's. */
static CstStatus read_subsurface(Loader *ld, const json_t *obj, Material *m)
{
    float scale = 1.0f;
    json_t *name = json_object_get(obj, "name"), *sa = json_object_get(obj, "sigma_a"),
           *ss = json_object_get(obj, "sigma_s"), *refl = json_object_get(obj, "reflectance"),
           *mfp = json_object_get(obj, "mfp");
    m->subsurface = true;
    m->sss_mfp = color_s(1.0f);
    LOADER_TRY(read_float_range(ld, obj, "scale", 0.0f, 1e30f, "a scale >= 0", &scale));
    LOADER_TRY(read_float_range(ld, obj, "g", -0.999f, 0.999f, "a Henyey-Greenstein asymmetry in (-1, 1)", &m->g));
    if ((name != NULL) + (sa != NULL || ss != NULL) + (refl != NULL) > 1) {
        json_path_push_key(ld, name ? "name" : "sigma_a");
        return json_fail_here(ld, "more than one of \"name\", \"sigma_a\"/\"sigma_s\" and \"reflectance\"; "
                                  "expected one way of giving the medium");
    }
    if (mfp && !refl) {
        json_path_push_key(ld, "mfp");
        return json_fail_here(ld, "\"mfp\" without \"reflectance\"; expected both (or sigma_a and sigma_s)");
    }
    if (name) {
        const char *s = NULL;
        json_path_push_key(ld, "name");
        LOADER_TRY(json_read_string(ld, name, &s));
        if (!medium_preset(s, &m->sss_sigma_a, &m->sss_sigma_s)) {
            char clipped[72];
            return json_fail_here(ld, "unknown named medium \"%s\"; expected one of %s", json_clip_name(s, clipped),
                                  MEDIUM_PRESET_EXAMPLES);
        }
        if (m->g != 0.0f)
            return json_fail_here(ld, "a named medium with g %g; expected g 0 (its coefficients are reduced "
                                      "scattering)", (double)m->g);
        json_path_pop(ld);
    } else if (sa || ss) {
        if (!sa || !ss) {
            json_path_push_key(ld, sa ? "sigma_a" : "sigma_s");
            return json_fail_here(ld, "\"%s\" without \"%s\"; expected both", sa ? "sigma_a" : "sigma_s",
                                  sa ? "sigma_s" : "sigma_a");
        }
        json_path_push_key(ld, "sigma_a");
        LOADER_TRY(json_read_rgb(ld, sa, 0, &m->sss_sigma_a));
        json_path_pop(ld);
        json_path_push_key(ld, "sigma_s");
        LOADER_TRY(json_read_rgb(ld, ss, 0, &m->sss_sigma_s));
        json_path_pop(ld);
    } else if (refl) {
        m->sss_from_reflectance = true;
        json_path_push_key(ld, "reflectance");
        if (json_is_string(refl))
            LOADER_TRY(json_read_param_texture(ld, refl, "a reflectance", &m->sss_reflectance_texture));
        else
            LOADER_TRY(json_read_rgb(ld, refl, 1, &m->sss_reflectance));
        json_path_pop(ld);
        if (mfp) {
            json_path_push_key(ld, "mfp");
            LOADER_TRY(json_read_rgb(ld, mfp, 0, &m->sss_mfp));
            if (!(m->sss_mfp.c[0] > 0.0f && m->sss_mfp.c[1] > 0.0f && m->sss_mfp.c[2] > 0.0f))
                return json_fail_here(ld, "a mean free path of 0; expected values > 0");
            json_path_pop(ld);
        }
        m->sss_mfp = color_scale(m->sss_mfp, scale);
        if (!(m->sss_mfp.c[0] > 0.0f && m->sss_mfp.c[1] > 0.0f && m->sss_mfp.c[2] > 0.0f))
            return json_fail_here(ld, "\"scale\" 0 with \"mfp\"; expected a scale > 0");
        return CST_OK;
    } else {
        m->sss_sigma_a = color_rgb(0.0011f, 0.0024f, 0.014f);
        m->sss_sigma_s = color_rgb(2.55f, 3.21f, 3.77f);
    }
    m->sss_sigma_a = color_scale(m->sss_sigma_a, scale);
    m->sss_sigma_s = color_scale(m->sss_sigma_s, scale);
    return CST_OK;
}

static CstStatus parse_material(Loader *ld, const json_t *obj, Material *m)
{
    const char *const *types = json_material_types;
    static const MaterialType mtype[] = {MATERIAL_DIFFUSE, MATERIAL_MIRROR, MATERIAL_GLASS,
                                         MATERIAL_CONDUCTOR, MATERIAL_DIELECTRIC, MATERIAL_PLASTIC,
                                         MATERIAL_COATED_DIFFUSE, MATERIAL_COATED_CONDUCTOR, MATERIAL_MIX,
                                         MATERIAL_DIFFUSE_TRANSMISSION, MATERIAL_THIN_DIELECTRIC, MATERIAL_MEASURED,
                                         MATERIAL_HAIR, MATERIAL_DIELECTRIC /* subsurface */};
    /* The keys each type accepts, "type" first. */
    static const char *const keys_diffuse[] = {"type", "albedo", "two_sided"};
    static const char *const keys_glass[] = {"type", "albedo", "ior"};
    static const char *const keys_conductor[] = {"type", "metal", "eta", "k", "roughness", "two_sided",
                                                 "uroughness", "vroughness", "remaproughness"};
    static const char *const keys_dielectric[] = {"type", "albedo", "ior", "roughness", "uroughness", "vroughness",
                                                  "remaproughness"};
    static const char *const keys_plastic[] = {"type", "albedo", "ior", "roughness", "two_sided"};
    static const char *const keys_coated_diffuse[] = {"type", "albedo", "ior", "roughness", "two_sided",
                                                      "thickness", "layer_albedo", "g", "max_depth", "nsamples",
                                                      "uroughness", "vroughness", "remaproughness"};
    static const char *const keys_coated_conductor[] = {"type", "metal", "eta", "k", "ior", "roughness",
                                                        "base_roughness", "two_sided", "thickness",
                                                        "layer_albedo", "g", "max_depth", "nsamples",
                                                        "uroughness", "vroughness", "remaproughness",
                                                        "base_uroughness", "base_vroughness"};
    static const char *const keys_mix[] = {"type", "materials", "amount"};
    static const char *const keys_difftrans[] = {"type", "albedo", "transmittance"};
    static const char *const keys_measured[] = {"type", "file", "two_sided"};
    static const char *const keys_hair[] = {"type", "ior", "beta_m", "beta_n", "alpha", "sigma_a", "color",
                                            "eumelanin", "pheomelanin"};
    static const char *const keys_subsurface[] = {"type", "ior", "roughness", "uroughness", "vroughness",
                                                  "remaproughness", "g", "scale", "name", "sigma_a", "sigma_s",
                                                  "reflectance", "mfp"};
    static const char *const *const keys[] = {keys_diffuse, keys_diffuse, keys_glass, keys_conductor,
                                              keys_dielectric, keys_plastic, keys_coated_diffuse,
                                              keys_coated_conductor, keys_mix, keys_difftrans, keys_glass,
                                              keys_measured, keys_hair, keys_subsurface};
    static const int nkeys[] = {3, 3, 3, 9, 7, 5, 13, 18, 3, 3, 3, 3, 9, 13};
    int type = 0;
    json_t *v;
    LOADER_TRY(json_expect_object(ld, obj, "a material object"));
    LOADER_TRY(json_read_type(ld, obj, "material type", types, MAT_COUNT, -1, &type));
    LOADER_TRY(json_check_keys(ld, obj, keys[type], nkeys[type]));
    m->type = mtype[type];
    m->albedo = type == MAT_DIFFUSE || type == MAT_PLASTIC || type == MAT_COATED_DIFFUSE ? color_s(0.5f)
                : type == MAT_DIFFUSE_TRANSMISSION ? color_s(0.25f) : color_s(1.0f);
    m->ior = type == MAT_GLASS || type == MAT_DIELECTRIC || type == MAT_PLASTIC || type == MAT_COATED_DIFFUSE ||
             type == MAT_COATED_CONDUCTOR || type == MAT_THIN_DIELECTRIC ? 1.5f
             : type == MAT_SUBSURFACE ? 1.33f : 1.0f; /* pbrt-v4's subsurface default eta */
    if (type == MAT_DIFFUSE_TRANSMISSION) {
        m->transmittance = color_s(0.25f); /* pbrt-v4's default */
        if ((v = json_object_get(obj, "transmittance"))) {
            json_path_push_key(ld, "transmittance");
            LOADER_TRY(json_read_rgb(ld, v, 1, &m->transmittance));
            json_path_pop(ld);
        }
    }
    if (type == MAT_COATED_DIFFUSE || type == MAT_COATED_CONDUCTOR) LOADER_TRY(read_layer(ld, obj, m));
    if (type == MAT_MIX) return read_mix(ld, obj, m);
    if (type == MAT_HAIR) return read_hair(ld, obj, m);
    if (type == MAT_MEASURED) { /* "file": an RGL .bsdf, relative to the scene (json_add_material) */
        LOADER_TRY(json_member_required(ld, obj, "file", "the path of a .bsdf file", &v));
        json_path_push_key(ld, "file");
        LOADER_TRY(json_read_string(ld, v, &m->measured_file));
        if (!m->measured_file[0]) return json_fail_here(ld, "the file name is empty; expected the path of a .bsdf file");
        json_path_pop(ld);
    }
    m->roughness = 0.0f;
    if ((v = json_object_get(obj, "albedo"))) {
        /* A reflectance above 1 would make any of these create energy. */
        json_path_push_key(ld, "albedo");
        if (json_is_string(v))
            LOADER_TRY(json_read_param_texture(ld, v, "a reflectance", &m->albedo_texture));
        else
            LOADER_TRY(json_read_rgb(ld, v, 1, &m->albedo));
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "ior"))) {
        json_path_push_key(ld, "ior");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &m->ior));
        if (!(m->ior > 0.0f))
            return json_fail_here(ld, "ior %g is not positive; expected an index of refraction > 0 "
                                      "(glass is about 1.5)",
                                  (double)m->ior);
        /* The coat model (bsdf.c) needs light to enter a denser layer. */
        if (type == MAT_PLASTIC && !(m->ior >= 1.0f))
            return json_fail_here(ld, "ior %g is below 1; expected the coat's index of refraction >= 1 "
                                      "(plastics are about 1.5)",
                                  (double)m->ior);
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "roughness"))) {
        if (json_is_string(v)) {
            json_path_push_key(ld, "roughness");
            if (type == MAT_PLASTIC)
                return json_fail_here(ld, "a plastic's roughness cannot be a texture (its coat albedo "
                                          "table is made for one roughness); expected a number from 0 to 1");
            LOADER_TRY(json_read_param_texture(ld, v, "a roughness", &m->roughness_texture));
            json_path_pop(ld);
        } else {
            LOADER_TRY(read_roughness(ld, v, &m->roughness));
        }
    }
    if ((v = json_object_get(obj, "two_sided"))) {
        int two = 1;
        json_path_push_key(ld, "two_sided");
        LOADER_TRY(json_read_bool(ld, v, &two));
        m->one_sided = !two;
        json_path_pop(ld);
    }
    if (type == MAT_CONDUCTOR || type == MAT_DIELECTRIC || type == MAT_COATED_DIFFUSE || type == MAT_COATED_CONDUCTOR ||
        type == MAT_SUBSURFACE)
        LOADER_TRY(read_anisotropy(ld, obj, m));
    if (type == MAT_SUBSURFACE) LOADER_TRY(read_subsurface(ld, obj, m));
    if (type == MAT_CONDUCTOR || type == MAT_COATED_CONDUCTOR) {
        json_t *metal = json_object_get(obj, "metal"), *eta = json_object_get(obj, "eta"),
               *k = json_object_get(obj, "k");
        char list[128];
        json_join_names(material_metal_names, 4, list, sizeof list);
        if (metal && (eta || k))
            return json_fail_here(ld, "both \"metal\" and \"eta\"/\"k\"; expected either a named metal "
                                      "(%s) or \"eta\" and \"k\"",
                                  list);
        if (metal) {
            const char *name = NULL;
            json_path_push_key(ld, "metal");
            LOADER_TRY(json_read_string(ld, metal, &name));
            if (!material_metal(name, &m->eta, &m->k)) {
                char clipped[72];
                return json_fail_here(ld, "unknown metal \"%s\"; expected one of: %s", json_clip_name(name, clipped), list);
            }
            json_path_pop(ld);
        } else if (eta && k) {
            /* A complex IOR: eta >= 0 and k >= 0 per channel. */
            json_path_push_key(ld, "eta");
            LOADER_TRY(json_read_rgb(ld, eta, 0, &m->eta));
            json_path_pop(ld);
            json_path_push_key(ld, "k");
            LOADER_TRY(json_read_rgb(ld, k, 0, &m->k));
            json_path_pop(ld);
        } else {
            return json_fail_here(ld, "missing key \"%s\"; expected a named metal (\"metal\": one of %s) or "
                                      "a complex IOR (\"eta\" and \"k\", RGB triples)",
                                  eta ? "k" : k ? "eta" : "metal", list);
        }
    }
    return CST_OK;
}

/* Adds a material the loader filled (Material's fields, its texture ids 1-based as the
 * public ones) through the public builder. Fails at the current path. */
CstStatus json_add_material(Loader *ld, const Material *m, int *out_id)
{
    CstMaterialDesc d;
    scene_material_desc(m, &d);
    char *path = NULL; /* a measured material's file, relative to the scene file */
    if (m->type == MATERIAL_MEASURED && m->measured_file && !m->measured) {
        if (!(path = path_resolve(ld->name, m->measured_file))) return json_fail_at(ld, CST_ERR_OOM, "out of memory");
        d.measured_file = path;
    }
    CstStatus st = cst_scene_add_material(ld->scene, &d, out_id, ld->err);
    free(path);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

CstStatus json_parse_materials(Loader *ld, const json_t *mats)
{
    LOADER_TRY(json_expect_object(ld, mats, "an object mapping material names to materials"));
    size_t n = json_object_size(mats);
    if (n > (size_t)INT_MAX)
        return json_fail_here(ld, "too many materials");
    ld->mat_names = malloc((n ? n : 1) * sizeof *ld->mat_names);
    ld->mat_ids = malloc((n ? n : 1) * sizeof *ld->mat_ids);
    if (!ld->mat_names || !ld->mat_ids)
        return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    const char *name;
    json_t *v;
    json_object_foreach((json_t *)mats, name, v) {
        Material m = {0};
        int id = 0;
        json_path_push_key(ld, name);
        LOADER_TRY(parse_material(ld, v, &m));
        LOADER_TRY(json_add_material(ld, &m, &id));
        json_path_pop(ld);
        ld->mat_names[ld->num_materials] = name;
        ld->mat_ids[ld->num_materials] = id;
        ld->num_materials++;
    }
    return CST_OK;
}

/* shape["material"] -> scene material id. */
CstStatus json_read_material_ref(Loader *ld, const json_t *shape, int *out)
{
    json_t *v;
    const char *s = NULL;
    LOADER_TRY(json_member_required(ld, shape, "material", "the name of a material", &v));
    json_path_push_key(ld, "material");
    LOADER_TRY(json_read_string(ld, v, &s));
    for (int i = 0; i < ld->num_materials; i++)
        if (strcmp(ld->mat_names[i], s) == 0) {
            *out = ld->mat_ids[i];
            json_path_pop(ld);
            return CST_OK;
        }
    char name[72];
    if (ld->num_materials == 0)
        return json_fail_here(ld, "material \"%s\" is not defined (no materials are); expected a name "
                                  "defined under \"materials\"",
                              json_clip_name(s, name));
    char list[512];
    json_join_names(ld->mat_names, ld->num_materials, list, sizeof list);
    return json_fail_here(ld, "material \"%s\" is not defined; expected one of: %s", json_clip_name(s, name),
                          list);
}

CstStatus json_read_emission(Loader *ld, const json_t *shape, Emission *em)
{
    static const char *const keys[] = {"radiance", "two_sided", "scale"};
    json_t *obj = json_object_get(shape, "emission"), *v;
    em->radiance = color_s(0.0f);
    em->two_sided = 0;
    em->texture = 0;
    if (!obj)
        return CST_OK;
    json_path_push_key(ld, "emission");
    LOADER_TRY(json_expect_object(ld, obj, "an object with radiance, two_sided, scale"));
    LOADER_TRY(json_check_keys(ld, obj, keys, 3));
    LOADER_TRY(json_member_required(ld, obj, "radiance", "an array of 3 numbers >= 0 or a texture name", &v));
    json_path_push_key(ld, "radiance");
    if (json_is_string(v)) {
        int id = 0;
        LOADER_TRY(json_read_texture_name(ld, json_string_value(v), &id));
        em->texture = id + 1;
        em->radiance = color_s(1.0f);
    } else {
        LOADER_TRY(json_read_rgb(ld, v, 0, &em->radiance));
    }
    json_path_pop(ld);
    if ((v = json_object_get(obj, "scale"))) {
        float k = 1.0f;
        json_path_push_key(ld, "scale");
        LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &k));
        if (!(k >= 0.0f)) return json_fail_here(ld, "scale %g is negative; expected a number >= 0", (double)k);
        /* Each in range, the product may not be (issue 25: 1e30 x 1e30 rendered black). */
        double product = (double)color_max(em->radiance) * (double)k;
        if (!(product <= (double)FLT_MAX))
            return json_fail_here(ld, "radiance %g x scale %g = %g overflows a float (above 3.4e38); expected "
                                      "a product of at most 3.4e38",
                                  (double)color_max(em->radiance), (double)k, product);
        em->radiance = color_scale(em->radiance, k);
        json_path_pop(ld);
    }
    if ((v = json_object_get(obj, "two_sided"))) {
        json_path_push_key(ld, "two_sided");
        LOADER_TRY(json_read_bool(ld, v, &em->two_sided));
        json_path_pop(ld);
    }
    json_path_pop(ld);
    return CST_OK;
}
