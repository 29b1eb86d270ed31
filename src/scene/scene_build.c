/* The public scene builder (cst_scene_create ... cst_scene_commit): validates what callers
 * pass through include/caustic/caustic.h, converts it to the internal types and adds it
 * with the scene_add_* calls, as the JSON and pbrt loaders do. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "materials/hair.h"
#include "materials/measured.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

CstStatus cst_scene_create(CstScene **out, CstError *err)
{
    cst_error_clear(err);
    if (!out) return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_create: out is NULL");
    *out = scene_create();
    return *out ? CST_OK : cst_fail(err, CST_ERR_OOM, "cst_scene_create: out of memory");
}

/* ------------------------------------------------------------------ materials */

void cst_material_desc_init(CstMaterialDesc *d, CstMaterialType type)
{
    memset(d, 0, sizeof *d);
    d->type = type;
    float a = type == CST_MATERIAL_DIFFUSE || type == CST_MATERIAL_PLASTIC || type == CST_MATERIAL_COATED_DIFFUSE
                  ? 0.5f : type == CST_MATERIAL_DIFFUSE_TRANSMISSION ? 0.25f : 1.0f;
    d->albedo[0] = d->albedo[1] = d->albedo[2] = a;
    if (type == CST_MATERIAL_DIFFUSE_TRANSMISSION) /* pbrt-v4's defaults */
        d->transmittance[0] = d->transmittance[1] = d->transmittance[2] = 0.25f;
    d->ior = type == CST_MATERIAL_GLASS || type == CST_MATERIAL_DIELECTRIC || type == CST_MATERIAL_PLASTIC ||
             type == CST_MATERIAL_COATED_DIFFUSE || type == CST_MATERIAL_COATED_CONDUCTOR ||
             type == CST_MATERIAL_THIN_DIELECTRIC ? 1.5f : 1.0f;
    d->two_sided = 1;
    if (type == CST_MATERIAL_HAIR) { /* pbrt-v4's HairMaterial defaults */
        d->ior = 1.55f;
        d->beta_m = d->beta_n = 0.3f;
        d->hair_alpha = 2.0f;
        d->hair_absorption = CST_HAIR_MELANIN;
        d->eumelanin = 1.3f;
    }
    if (type == CST_MATERIAL_SUBSURFACE) { /* pbrt-v4's SubsurfaceMaterial defaults */
        static const float sa[3] = {0.0011f, 0.0024f, 0.014f}, ss[3] = {2.55f, 3.21f, 3.77f};
        d->ior = 1.33f;
        for (int k = 0; k < 3; k++) {
            d->sss_sigma_a[k] = sa[k];
            d->sss_sigma_s[k] = ss[k];
            d->sss_mfp[k] = 1.0f;
        }
    }
    d->amount = 0.5f;     /* pbrt-v4's mix default */
    d->thickness = 0.01f; /* pbrt-v4's coated materials' defaults */
    d->max_depth = 10;
    d->nsamples = 1;
}

void scene_material_desc(const Material *m, CstMaterialDesc *d)
{
    static const CstMaterialType types[] = {
        [MATERIAL_DIFFUSE] = CST_MATERIAL_DIFFUSE, [MATERIAL_MIRROR] = CST_MATERIAL_MIRROR,
        [MATERIAL_GLASS] = CST_MATERIAL_GLASS, [MATERIAL_CONDUCTOR] = CST_MATERIAL_CONDUCTOR,
        [MATERIAL_DIELECTRIC] = CST_MATERIAL_DIELECTRIC, [MATERIAL_PLASTIC] = CST_MATERIAL_PLASTIC,
        [MATERIAL_COATED_DIFFUSE] = CST_MATERIAL_COATED_DIFFUSE,
        [MATERIAL_COATED_CONDUCTOR] = CST_MATERIAL_COATED_CONDUCTOR, [MATERIAL_MIX] = CST_MATERIAL_MIX,
        [MATERIAL_DIFFUSE_TRANSMISSION] = CST_MATERIAL_DIFFUSE_TRANSMISSION,
        [MATERIAL_THIN_DIELECTRIC] = CST_MATERIAL_THIN_DIELECTRIC, [MATERIAL_MEASURED] = CST_MATERIAL_MEASURED,
        [MATERIAL_HAIR] = CST_MATERIAL_HAIR};
    cst_material_desc_init(d, m->subsurface ? CST_MATERIAL_SUBSURFACE : types[m->type]);
    if (m->type == MATERIAL_HAIR) { /* melanin was turned into sigma_a when it was added */
        d->beta_m = m->beta_m;
        d->beta_n = m->beta_n;
        d->hair_alpha = m->hair_alpha;
        d->hair_absorption = m->hair_color ? CST_HAIR_COLOR : CST_HAIR_SIGMA_A;
        for (int k = 0; k < 3; k++) d->sigma_a[k] = color_channel(m->sigma_a, k);
    }
    for (int k = 0; k < 3; k++) {
        d->albedo[k] = color_channel(m->albedo, k);
        d->eta[k] = color_channel(m->eta, k);
        d->k[k] = color_channel(m->k, k);
    }
    d->albedo_texture = m->albedo_texture;
    if (m->type == MATERIAL_MEASURED) d->measured_file = m->measured ? m->measured->path : m->measured_file;
    d->ior = m->ior;
    d->roughness = m->roughness;
    d->roughness_texture = m->roughness_texture;
    d->roughness_v_texture = m->roughness_v_texture;
    if (m->anisotropic) {
        d->anisotropic = 1;
        d->roughness_v = m->roughness_v;
        d->base_roughness_v = m->base_roughness_v;
    }
    d->two_sided = !m->one_sided;
    d->displacement_texture = m->displacement_texture;
    d->normal_map_texture = m->normal_map_texture;
    if (material_is_layered(m->type)) {
        d->base_roughness = m->base_roughness;
        d->thickness = m->thickness;
        for (int k = 0; k < 3; k++) d->layer_albedo[k] = color_channel(m->layer_albedo, k);
        d->g = m->g;
        d->max_depth = m->max_depth;
        d->nsamples = m->nsamples;
    }
    for (int k = 0; k < 3; k++) d->transmittance[k] = color_channel(m->transmittance, k);
    d->eta_spectrum = m->eta_spectrum;
    d->k_spectrum = m->k_spectrum;
    d->ior_spectrum = m->ior_spectrum;
    d->eta_texture = m->eta_texture;
    d->k_texture = m->k_texture;
    d->reflectance_texture = m->reflectance_texture;
    if (m->subsurface) { /* the reflectance travels in albedo (the surface's tint is 1) */
        d->sss_from_reflectance = m->sss_from_reflectance;
        d->g = m->g;
        for (int k = 0; k < 3; k++) {
            d->albedo[k] = color_channel(m->sss_reflectance, k);
            d->sss_sigma_a[k] = color_channel(m->sss_sigma_a, k);
            d->sss_sigma_s[k] = color_channel(m->sss_sigma_s, k);
            d->sss_mfp[k] = color_channel(m->sss_mfp, k);
        }
        d->albedo_texture = m->sss_reflectance_texture;
    }
    if (m->type == MATERIAL_MIX) {
        d->mix_materials[0] = m->mix[0];
        d->mix_materials[1] = m->mix[1];
        d->amount = m->amount;
        d->amount_texture = m->amount_texture;
    }
}

/* A material's spectra (cst_scene_add_material): checked ids, and the RGB-mode reductions
 * they replace (math/spectrum_sampled.h). */
static CstStatus build_spectra(const Scene *s, const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    const int ids[3] = {d->eta_spectrum, d->k_spectrum, d->ior_spectrum};
    static const char *const names[3] = {"eta_spectrum", "k_spectrum", "ior_spectrum"};
    for (int i = 0; i < 3; i++)
        if (ids[i] < 0 || ids[i] > s->num_spectra)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s %d is not a spectrum of this scene; expected 0 "
                            "(none) or 1 to %d (cst_scene_add_spectrum)", fn, names[i], ids[i], s->num_spectra);
    bool conductor = m->type == MATERIAL_CONDUCTOR || m->type == MATERIAL_COATED_CONDUCTOR;
    bool dielectric = m->type == MATERIAL_GLASS || m->type == MATERIAL_DIELECTRIC ||
                      m->type == MATERIAL_THIN_DIELECTRIC || material_is_layered(m->type);
    if (conductor) {
        for (int i = 0; i < 2; i++) {
            if (!ids[i]) continue;
            const SampledSpectrum *sp = &s->spectra[ids[i] - 1];
            for (int j = 0; j < SAMPLED_SPECTRUM_N; j++)
                if (!(sp->v[j] >= 0.0f))
                    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s %d is %g at %d nm; expected a complex IOR "
                                    "part >= 0", fn, names[i], ids[i], (double)sp->v[j], SPECTRUM_LAMBDA_MIN + j);
            Color rgb = sampled_spectrum_rgb_unbounded(sp);
            if (i == 0) m->eta = rgb;
            else m->k = rgb;
        }
        m->eta_spectrum = ids[0];
        m->k_spectrum = ids[1];
    }
    if (dielectric && ids[2]) {
        const SampledSpectrum *sp = &s->spectra[ids[2] - 1];
        for (int j = 0; j < SAMPLED_SPECTRUM_N; j++)
            if (!(sp->v[j] > 0.0f))
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: ior_spectrum %d is %g at %d nm; expected an index "
                                "of refraction > 0 over 360-830 nm", fn, ids[2], (double)sp->v[j], SPECTRUM_LAMBDA_MIN + j);
        m->ior = sampled_spectrum_mean_y(sp);
        m->ior_spectrum = ids[2];
        m->ior_dispersive = !sp->constant;
    }
    return CST_OK;
}

/* The coated materials' layer (cst_scene_add_material). */
/* A hair's parameters (hair.h), its melanin turned into sigma_a as pbrt-v4 does (an RGB
 * absorption, upsampled as an unbounded spectrum in spectral mode). */
static CstStatus build_hair(const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    if (!(d->beta_m > 0.0f && d->beta_m <= 1.0f) || !(d->beta_n > 0.0f && d->beta_n <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: hair beta_m %g, beta_n %g; expected roughnesses in (0, 1] "
                        "(pbrt's default 0.3)", fn, (double)d->beta_m, (double)d->beta_n);
    if (!(d->hair_alpha >= -90.0f && d->hair_alpha <= 90.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: hair_alpha %g; expected the cuticle tilt in degrees, "
                        "in [-90, 90] (pbrt's default 2)", fn, (double)d->hair_alpha);
    m->beta_m = d->beta_m;
    m->beta_n = d->beta_n;
    m->hair_alpha = d->hair_alpha;
    switch (d->hair_absorption) {
    case CST_HAIR_MELANIN:
        if (!(d->eumelanin >= 0.0f && d->eumelanin <= FLT_MAX) || !(d->pheomelanin >= 0.0f && d->pheomelanin <= FLT_MAX))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: eumelanin %g, pheomelanin %g; expected finite "
                            "concentrations >= 0", fn, (double)d->eumelanin, (double)d->pheomelanin);
        m->sigma_a = hair_sigma_a_from_melanin(d->eumelanin, d->pheomelanin);
        if (!color_is_finite(m->sigma_a))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: eumelanin %g, pheomelanin %g overflow sigma_a; expected "
                            "smaller concentrations", fn, (double)d->eumelanin, (double)d->pheomelanin);
        return CST_OK;
    case CST_HAIR_SIGMA_A: return read_rgb(d->sigma_a, 0, fn, "sigma_a", &m->sigma_a, err);
    case CST_HAIR_COLOR: m->hair_color = true; return CST_OK; /* albedo, read and checked above */
    default:
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: hair_absorption %d; expected CST_HAIR_MELANIN, "
                        "CST_HAIR_SIGMA_A or CST_HAIR_COLOR", fn, d->hair_absorption);
    }
}

static CstStatus build_layer(const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    if (!(d->base_roughness >= 0.0f && d->base_roughness <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: base_roughness %g is outside [0, 1]; expected 0 "
                        "(smooth) to 1 (roughest)", fn, (double)d->base_roughness);
    if (!(d->thickness >= 0.0f && d->thickness <= FLT_MAX))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: thickness %g; expected a layer thickness >= 0",
                        fn, (double)d->thickness);
    if (!(d->g > -1.0f && d->g < 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: g %g is outside (-1, 1); expected a Henyey-Greenstein "
                        "asymmetry (0 isotropic)", fn, (double)d->g);
    if (d->max_depth < 1 || d->max_depth > 100000 || d->nsamples < 1 || d->nsamples > 10000)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: max_depth %d, nsamples %d; expected max_depth in "
                        "[1, 100000] and nsamples in [1, 10000]", fn, d->max_depth, d->nsamples);
    CstStatus st = read_rgb(d->layer_albedo, 1, fn, "layer_albedo", &m->layer_albedo, err);
    if (st != CST_OK) return st;
    m->base_roughness = d->base_roughness;
    m->thickness = d->thickness;
    m->g = d->g;
    m->max_depth = d->max_depth;
    m->nsamples = d->nsamples;
    return CST_OK;
}

/* Subsurface (cst_scene_add_material): a dielectric surface over the medium, whose
 * reflectance (from_reflectance) moves from albedo to sss_reflectance. */
static CstStatus build_subsurface(const Scene *s, const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    CstStatus st;
    if (d->sss_from_reflectance != 0 && d->sss_from_reflectance != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: sss_from_reflectance %d; expected 0 or 1", fn,
                        d->sss_from_reflectance);
    if (!(d->g > -1.0f && d->g < 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: g %g is outside (-1, 1); expected a Henyey-Greenstein "
                        "asymmetry (0 isotropic)", fn, (double)d->g);
    if ((st = read_rgb(d->sss_sigma_a, 0, fn, "sss_sigma_a", &m->sss_sigma_a, err)) != CST_OK ||
        (st = read_rgb(d->sss_sigma_s, 0, fn, "sss_sigma_s", &m->sss_sigma_s, err)) != CST_OK ||
        (st = read_rgb(d->sss_mfp, 0, fn, "sss_mfp", &m->sss_mfp, err)) != CST_OK)
        return st;
    if (d->sss_from_reflectance && !(d->sss_mfp[0] > 0.0f && d->sss_mfp[1] > 0.0f && d->sss_mfp[2] > 0.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: sss_mfp (%g, %g, %g); expected mean free paths > 0", fn,
                        (double)d->sss_mfp[0], (double)d->sss_mfp[1], (double)d->sss_mfp[2]);
    (void)s;
    m->subsurface = true;
    m->sss_from_reflectance = d->sss_from_reflectance != 0;
    m->g = d->g;
    m->sss_reflectance = m->albedo;
    m->sss_reflectance_texture = m->albedo_texture;
    m->albedo = color_s(1.0f);
    m->albedo_texture = 0;
    return CST_OK;
}

/* Anisotropic roughness (cst_scene_add_material): the types that have it; textured, a
 * texture for each width. */
static CstStatus build_anisotropic(const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    if (d->anisotropic == 0 && d->roughness_v_texture)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: roughness_v_texture with anisotropic 0; expected "
                        "anisotropic 1", fn);
    if (d->anisotropic == 0) return CST_OK;
    if (d->anisotropic != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: anisotropic %d; expected 0 or 1", fn, d->anisotropic);
    if (d->type != CST_MATERIAL_CONDUCTOR && d->type != CST_MATERIAL_DIELECTRIC &&
        d->type != CST_MATERIAL_COATED_DIFFUSE && d->type != CST_MATERIAL_COATED_CONDUCTOR &&
        d->type != CST_MATERIAL_SUBSURFACE)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: anisotropic roughness on a material of type %d; expected "
                        "a conductor, dielectric, coated diffuse or coated conductor", fn, (int)d->type);
    if (d->roughness_v_texture && !d->roughness_texture)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: roughness_v_texture without a roughness_texture; expected "
                        "both (the widths along u and v) or neither", fn);
    if (d->roughness_texture && !d->roughness_v_texture && d->roughness_v != d->roughness) /* the texture sets both widths */
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: roughness_v %g with a roughness_texture; expected an "
                        "isotropic textured roughness (roughness_v = roughness) or no texture", fn,
                        (double)d->roughness_v);
    if (!(d->roughness_v >= 0.0f && d->roughness_v <= 1.0f) || !(d->base_roughness_v >= 0.0f && d->base_roughness_v <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: roughness_v %g, base_roughness_v %g; expected 0 (smooth) "
                        "to 1 (roughest)", fn, (double)d->roughness_v, (double)d->base_roughness_v);
    m->anisotropic = true;
    m->roughness_v = d->roughness_v;
    m->roughness_v_texture = d->roughness_v_texture;
    m->base_roughness_v = d->type == CST_MATERIAL_COATED_CONDUCTOR ? d->base_roughness_v : 0.0f;
    return CST_OK;
}

/* A conductor's textured eta and k, or its reflectance texture (cst_scene_add_material). */
static CstStatus build_conductor_textures(const Scene *s, const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    if (!(d->eta_texture | d->k_texture | d->reflectance_texture)) return CST_OK;
    if (d->type != CST_MATERIAL_CONDUCTOR && d->type != CST_MATERIAL_COATED_CONDUCTOR)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: eta_texture, k_texture or reflectance_texture on a material "
                        "of type %d; expected a conductor or coated conductor", fn, (int)d->type);
    if (d->reflectance_texture && (d->eta_texture | d->k_texture))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: reflectance_texture with eta_texture or k_texture; expected "
                        "either a reflectance or eta and k (as pbrt-v4)", fn);
    CstStatus st;
    if ((st = check_texture_id(s, d->eta_texture, 1, fn, "eta_texture", err)) != CST_OK ||
        (st = check_texture_id(s, d->k_texture, 1, fn, "k_texture", err)) != CST_OK)
        return st;
    m->eta_texture = d->eta_texture;
    m->k_texture = d->k_texture;
    m->reflectance_texture = d->reflectance_texture; /* checked by check_unit_texture */
    return CST_OK;
}

/* A texture standing for a reflectance or a roughness: its values must stay within 1. */
static CstStatus check_unit_texture(const Scene *s, int id, const char *what, CstError *err)
{
    CstStatus st = check_texture_id(s, id, 1, "cst_scene_add_material", what, err);
    if (st != CST_OK || id == 0) return st;
    float mx = color_max(s->textures[id - 1].max);
    if (mx > 1.0f)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_add_material: %s %d has values up to %g; "
                        "expected at most 1", what, id, (double)mx);
    return CST_OK;
}

static CstStatus build_conductor(const CstMaterialDesc *d, Material *m, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    if (d->metal) {
        if (!material_metal(d->metal, &m->eta, &m->k))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown metal \"%.64s\"; expected gold, silver, "
                            "copper or aluminium", fn, d->metal);
        return CST_OK;
    }
    CstStatus st = read_rgb(d->eta, 0, fn, "eta", &m->eta, err);
    if (st == CST_OK) st = read_rgb(d->k, 0, fn, "k", &m->k, err);
    return st;
}

CstStatus cst_scene_add_material(CstScene *scene, const CstMaterialDesc *d, int *out_id, CstError *err)
{
    static const char fn[] = "cst_scene_add_material";
    static const MaterialType types[] = {MATERIAL_DIFFUSE, MATERIAL_MIRROR, MATERIAL_GLASS,
                                         MATERIAL_CONDUCTOR, MATERIAL_DIELECTRIC, MATERIAL_PLASTIC,
                                         MATERIAL_COATED_DIFFUSE, MATERIAL_COATED_CONDUCTOR, MATERIAL_MIX,
                                         MATERIAL_DIFFUSE_TRANSMISSION, MATERIAL_THIN_DIELECTRIC, MATERIAL_MEASURED,
                                         MATERIAL_HAIR, MATERIAL_DIELECTRIC /* subsurface */};
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d || !out_id) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc and out_id must not be NULL", fn);
    if (d->type < CST_MATERIAL_DIFFUSE || d->type > CST_MATERIAL_SUBSURFACE)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown material type %d; expected CST_MATERIAL_DIFFUSE "
                        "to CST_MATERIAL_SUBSURFACE (cst_material_desc_init sets it)", fn, (int)d->type);
    Material m = {0};
    m.type = types[d->type - CST_MATERIAL_DIFFUSE];
    if ((st = read_rgb(d->albedo, 1, fn, "albedo", &m.albedo, err)) != CST_OK) return st;
    if ((st = check_unit_texture(scene, d->albedo_texture, "albedo_texture", err)) != CST_OK ||
        (st = check_unit_texture(scene, d->roughness_texture, "roughness_texture", err)) != CST_OK ||
        (st = check_unit_texture(scene, d->roughness_v_texture, "roughness_v_texture", err)) != CST_OK ||
        (st = check_unit_texture(scene, d->reflectance_texture, "reflectance_texture", err)) != CST_OK)
        return st;
    m.albedo_texture = d->albedo_texture;
    m.roughness_texture = d->roughness_texture;
    if ((st = check_texture_id(scene, d->displacement_texture, 1, fn, "displacement_texture", err)) != CST_OK ||
        (st = check_texture_id(scene, d->normal_map_texture, 1, fn, "normal_map_texture", err)) != CST_OK)
        return st;
    m.displacement_texture = d->displacement_texture;
    m.normal_map_texture = d->normal_map_texture;
    if (!(d->ior > 0.0f && d->ior <= FLT_MAX))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: ior %g; expected an index of refraction > 0 "
                        "(glass is about 1.5)", fn, (double)d->ior);
    if (d->type == CST_MATERIAL_PLASTIC && !(d->ior >= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: ior %g is below 1; expected the coat's index of "
                        "refraction >= 1", fn, (double)d->ior);
    m.ior = d->ior;
    if (!(d->roughness >= 0.0f && d->roughness <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: roughness %g is outside [0, 1]; expected 0 (smooth) "
                        "to 1 (roughest)", fn, (double)d->roughness);
    m.roughness = d->roughness;
    if ((st = build_anisotropic(d, &m, err)) != CST_OK) return st;
    if ((st = build_conductor_textures(scene, d, &m, err)) != CST_OK) return st;
    if (d->two_sided != 0 && d->two_sided != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: two_sided %d; expected 0 or 1", fn, d->two_sided);
    m.one_sided = !d->two_sided;
    if ((d->type == CST_MATERIAL_CONDUCTOR || d->type == CST_MATERIAL_COATED_CONDUCTOR) &&
        (st = build_conductor(d, &m, err)) != CST_OK)
        return st;
    if ((d->type == CST_MATERIAL_COATED_DIFFUSE || d->type == CST_MATERIAL_COATED_CONDUCTOR) &&
        (st = build_layer(d, &m, err)) != CST_OK)
        return st;
    if (d->type == CST_MATERIAL_DIFFUSE_TRANSMISSION &&
        (st = read_rgb(d->transmittance, 1, fn, "transmittance", &m.transmittance, err)) != CST_OK)
        return st;
    if (d->type == CST_MATERIAL_MIX) {
        for (int i = 0; i < 2; i++)
            if (d->mix_materials[i] < 0 || d->mix_materials[i] >= scene->num_materials)
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mix_materials[%d] = %d is not a material of this "
                                "scene; expected 0 to %d (materials added before the mix)", fn, i,
                                d->mix_materials[i], scene->num_materials - 1);
        if (!(d->amount >= 0.0f && d->amount <= 1.0f))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: amount %g is outside [0, 1]; expected the "
                            "probability of the second material", fn, (double)d->amount);
        if ((st = check_texture_id(scene, d->amount_texture, 1, fn, "amount_texture", err)) != CST_OK) return st;
        m.mix[0] = d->mix_materials[0];
        m.mix[1] = d->mix_materials[1];
        m.amount = d->amount;
        m.amount_texture = d->amount_texture;
    }
    if (d->type == CST_MATERIAL_HAIR && (st = build_hair(d, &m, err)) != CST_OK) return st;
    if (d->type == CST_MATERIAL_SUBSURFACE && (st = build_subsurface(scene, d, &m, err)) != CST_OK) return st;
    if ((st = build_spectra(scene, d, &m, err)) != CST_OK) return st;
    if (d->type == CST_MATERIAL_MEASURED) {
        if (!d->measured_file || !d->measured_file[0])
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: a measured material without measured_file; expected "
                            "the path of a .bsdf file", fn);
        m.measured_file = d->measured_file; /* read by scene_add_material */
    }
    return scene_add_material(scene, &m, out_id, err);
}

CstStatus cst_scene_add_spectrum(CstScene *scene, const float *lambda, const float *values, int n, int *out_id,
                                 CstError *err)
{
    static const char fn[] = "cst_scene_add_spectrum";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!lambda || !values || !out_id)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: lambda_nm, values and out_id must not be NULL", fn);
    if (n < 1) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: n = %d; expected at least one sample", fn, n);
    for (int i = 0; i < n; i++) {
        if (!(isfinite(lambda[i]) && lambda[i] > 0.0f) || !isfinite(values[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: sample %d (%g nm, %g); expected a finite wavelength "
                            "> 0 and a finite value", fn, i, (double)lambda[i], (double)values[i]);
        if (i > 0 && !(lambda[i] > lambda[i - 1]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: wavelength %g nm (sample %d) does not increase; "
                            "expected strictly increasing wavelengths", fn, (double)lambda[i], i);
    }
    SampledSpectrum *sp = malloc(sizeof *sp);
    if (!sp) return cst_fail(err, CST_ERR_OOM, "%s: out of memory", fn);
    sampled_spectrum_from_pairs(lambda, values, n, sp);
    int id = 0;
    st = scene_add_spectrum(scene, sp, &id, err);
    free(sp);
    if (st == CST_OK) *out_id = id + 1;
    return st;
}

/* ------------------------------------------------------------------ shapes */

/* *peak: the largest radiance of any channel anywhere on the surface (radiance x the
 * texture's largest value), for the power checks of the shapes. */
static CstStatus read_emission(const Scene *s, const CstEmission *e, const char *fn, Emission *out, double *peak,
                               CstError *err)
{
    memset(out, 0, sizeof *out);
    *peak = 0.0;
    if (!e) return CST_OK;
    if (e->spectrum < 0 || e->spectrum > s->num_spectra)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: emission spectrum %d is not a spectrum of this scene; "
                        "expected 0 (none) or 1 to %d (cst_scene_add_spectrum)", fn, e->spectrum, s->num_spectra);
    CstStatus st = read_rgb(e->radiance, 0, fn, "emission radiance", &out->radiance, err);
    if (st == CST_OK) st = check_texture_id(s, e->texture, 1, fn, "emission texture", err);
    if (st != CST_OK) return st;
    *peak = color_peak(out->radiance);
    if (e->texture) {
        *peak *= color_peak(s->textures[e->texture - 1].max);
        if ((st = check_product(fn, "emission radiance x its texture's largest value", *peak,
                                "a smaller radiance (or scale) or texture", err)) != CST_OK)
            return st;
    }
    if (e->two_sided != 0 && e->two_sided != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: emission two_sided %d; expected 0 or 1", fn, e->two_sided);
    out->texture = e->texture;
    out->two_sided = e->two_sided;
    return CST_OK;
}



/* n floats at element i of a strided array (memcpy: the caller's struct may not align them). */
static void fetch(const void *base, size_t stride, int i, int n, float *out)
{
    memcpy(out, (const char *)base + (size_t)i * stride, (size_t)n * sizeof(float));
}

/* The caller's strided arrays gathered into packed, validated internal arrays. */
typedef struct MeshArrays {
    Vec3 *pos, *nrm;
    Vec2 *uv;
    int *idx;
    int normals_partial; /* some normals are zero (normals_unit) */
} MeshArrays;

static CstStatus gather_mesh(const CstMeshDesc *d, const char *fn, MeshArrays *a, CstError *err)
{
    size_t ps = d->position_stride, ns = d->normal_stride, us = d->uv_stride, is = d->index_stride;
    CstStatus st;
    if ((st = check_stride(&ps, 3 * sizeof(float), fn, "position", err)) != CST_OK ||
        (d->normals && (st = check_stride(&ns, 3 * sizeof(float), fn, "normal", err)) != CST_OK) ||
        (d->uvs && (st = check_stride(&us, 2 * sizeof(float), fn, "uv", err)) != CST_OK) ||
        (st = check_stride(&is, 3 * sizeof(uint32_t), fn, "index", err)) != CST_OK)
        return st;
    int nv = d->num_vertices, nt = d->num_triangles;
    a->pos = malloc((size_t)nv * sizeof *a->pos);
    a->idx = malloc((size_t)nt * 3 * sizeof *a->idx);
    a->nrm = d->normals ? malloc((size_t)nv * sizeof *a->nrm) : NULL;
    a->uv = d->uvs ? malloc((size_t)nv * sizeof *a->uv) : NULL;
    if (!a->pos || !a->idx || (d->normals && !a->nrm) || (d->uvs && !a->uv))
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for %d vertices and %d triangles", fn, nv, nt);
    for (int i = 0; i < nv; i++) {
        float p[3];
        fetch(d->positions, ps, i, 3, p);
        if ((st = read_vec3(p, fn, "a position", &a->pos[i], err)) != CST_OK)
            return cst_fail(err, st, "%s: position of vertex %d (%g, %g, %g) is not finite or beyond 1e18",
                            fn, i, (double)p[0], (double)p[1], (double)p[2]);
        if (d->normals) {
            float n[3];
            fetch(d->normals, ns, i, 3, n);
            Vec3 v = v3(n[0], n[1], n[2]);
            if (d->normals_unit) {
                float l2 = v3_length2(v);
                if (!(l2 == 0.0f || fabsf(l2 - 1.0f) <= 1e-3f))
                    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: normal of vertex %d (%g, %g, %g) is neither "
                                    "unit length nor zero, as normals_unit = 1 requires", fn, i,
                                    (double)n[0], (double)n[1], (double)n[2]);
                a->nrm[i] = v;
                a->normals_partial |= l2 == 0.0f;
            } else if (!v3_is_finite(v) || !(v3_max_abs(v) > 0.0f))
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: normal of vertex %d (%g, %g, %g) is zero or not "
                                "finite; expected a nonzero vector", fn, i, (double)n[0], (double)n[1], (double)n[2]);
            else /* scaled first, so tiny or huge normals normalise */
                a->nrm[i] = v3_normalize(v3_scale(v, 1.0f / v3_max_abs(v)));
        }
        if (d->uvs) {
            float t[2];
            fetch(d->uvs, us, i, 2, t);
            if (!isfinite(t[0]) || !isfinite(t[1]))
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: uv of vertex %d (%g, %g) is not finite",
                                fn, i, (double)t[0], (double)t[1]);
            a->uv[i] = v2(t[0], t[1]);
        }
    }
    for (int t = 0; t < nt; t++) {
        uint32_t tri[3];
        memcpy(tri, (const char *)d->indices + (size_t)t * is, sizeof tri);
        for (int k = 0; k < 3; k++) {
            if (tri[k] >= (uint32_t)nv)
                return cst_fail(err, CST_ERR_INVALID_ARG, "%s: triangle %d: vertex index %u is out of range; "
                                "expected 0 to %d", fn, t, tri[k], nv - 1);
            a->idx[3 * t + k] = (int)tri[k];
        }
    }
    return CST_OK;
}

/* The checks of a mesh description that need no pass over its arrays (cst_scene_add_mesh,
 * cst_scene_add_object). */
static CstStatus check_mesh_desc(const Scene *scene, const CstMeshDesc *d, const char *fn, CstError *err)
{
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    if (d->num_vertices <= 0 || d->num_triangles <= 0 || !d->positions || !d->indices)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d vertices and %d triangles (positions %s, indices %s); "
                        "expected at least one of each, with their arrays", fn, d->num_vertices, d->num_triangles,
                        d->positions ? "given" : "NULL", d->indices ? "given" : "NULL");
    if (d->num_triangles > INT32_MAX / 3)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d triangles; expected fewer than %d", fn,
                        d->num_triangles, INT32_MAX / 3);
    if (!d->triangle_materials && (d->material < 0 || d->material >= scene->num_materials))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: material %d is not a material of this scene; expected 0 to %d",
                        fn, d->material, scene->num_materials - 1);
    for (int t = 0; d->triangle_materials && t < d->num_triangles; t++)
        if (d->triangle_materials[t] < 0 || d->triangle_materials[t] >= scene->num_materials)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: triangle_materials[%d] = %d is not a material of this "
                            "scene; expected 0 to %d", fn, t, d->triangle_materials[t], scene->num_materials - 1);
    if (d->skip_degenerate != 0 && d->skip_degenerate != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: skip_degenerate %d; expected 0 or 1", fn, d->skip_degenerate);
    if (d->normals_unit != 0 && d->normals_unit != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: normals_unit %d; expected 0 or 1", fn, d->normals_unit);
    return CST_OK;
}

/* Without skip_degenerate, fails at the first zero-area triangle (before anything is added,
 * so that a failure leaves the scene untouched: scene_add_mesh_ex finds a degenerate
 * triangle only after adding the ones before it). */
static CstStatus check_degenerate(const CstMeshDesc *d, const MeshArrays *a, const char *fn, CstError *err)
{
    for (int t = 0; !d->skip_degenerate && t < d->num_triangles; t++) {
        const int *i = &a->idx[3 * t];
        if (!(triangle_area(a->pos[i[0]], a->pos[i[1]], a->pos[i[2]]) > 0.0f))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: triangle %d (vertices %d, %d, %d) has zero area; "
                            "expected distinct, non-collinear vertices (or skip_degenerate = 1)",
                            fn, t, i[0], i[1], i[2]);
    }
    return CST_OK;
}

static void mesh_arrays_free(MeshArrays *a)
{
    free(a->pos);
    free(a->nrm);
    free(a->uv);
    free(a->idx);
}

CstStatus cst_scene_add_mesh(CstScene *scene, const CstMeshDesc *d, int *num_dropped, CstError *err)
{
    static const char fn[] = "cst_scene_add_mesh";
    cst_error_clear(err);
    if (num_dropped) *num_dropped = 0;
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if ((st = check_mesh_desc(scene, d, fn, err)) != CST_OK) return st;
    Emission em;
    double peak = 0.0;
    if ((st = read_emission(scene, &d->emission, fn, &em, &peak, err)) != CST_OK) return st;
    MeshArrays a = {0};
    st = gather_mesh(d, fn, &a, err);
    if (st == CST_OK && peak > 0.0) {
        /* Each emitting triangle is a light of power pi x area x radiance (x 2 two-sided). */
        double area = 0.0;
        for (int t = 0; t < d->num_triangles; t++) {
            const int *i = &a.idx[3 * t];
            double at = (double)triangle_area(a.pos[i[0]], a.pos[i[1]], a.pos[i[2]]);
            if (at > area) area = at;
        }
        st = check_product(fn, "the emitted power pi x area x radiance of its largest triangle",
                           (double)CST_PI * area * peak * (em.two_sided ? 2.0 : 1.0),
                           "a smaller radiance (or scale) or smaller triangles", err);
    }
    if (st == CST_OK) st = check_degenerate(d, &a, fn, err);
    int alpha = 0, *tri_alpha = NULL;
    if (st == CST_OK) st = scene_build_alpha(scene, &d->alpha, fn, &alpha, err);
    if (st == CST_OK) st = scene_build_triangle_alphas(scene, d, fn, &tri_alpha, err);
    if (st == CST_OK) {
        SceneMesh sm = {0};
        sm.alpha = alpha;
        sm.tri_alpha = tri_alpha;
        sm.positions = a.pos;
        sm.num_vertices = d->num_vertices;
        sm.normals = a.nrm;
        sm.normals_partial = a.normals_partial;
        sm.uvs = a.uv;
        sm.indices = a.idx;
        sm.num_triangles = d->num_triangles;
        sm.material = d->material;
        sm.tri_material = d->triangle_materials;
        sm.emission = &em;
        sm.skip_degenerate = d->skip_degenerate;
        const int first = scene->num_emitters;
        st = scene_add_mesh_ex(scene, &sm, num_dropped, err);
        if (st == CST_OK && peak > 0.0) st = scene_set_emitter_spectrum(scene, first, d->emission.spectrum, err);
    }
    free(tri_alpha);
    mesh_arrays_free(&a);
    return st;
}

/* ------------------------------------------------------------------ instancing */

CstStatus cst_scene_add_object(CstScene *scene, const CstMeshDesc *d, int *out_id, int *num_dropped, CstError *err)
{
    static const char fn[] = "cst_scene_add_object";
    cst_error_clear(err);
    if (num_dropped) *num_dropped = 0;
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!out_id) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: out_id is NULL", fn);
    if ((st = check_mesh_desc(scene, d, fn, err)) != CST_OK) return st;
    const CstEmission *e = &d->emission;
    if (e->radiance[0] != 0.0f || e->radiance[1] != 0.0f || e->radiance[2] != 0.0f || e->texture || e->two_sided)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: the object has an emission; instances do not emit "
                        "(expected a zero emission; add emitters with cst_scene_add_mesh)", fn);
    MeshArrays a = {0};
    int *mat = malloc((size_t)d->num_triangles * sizeof *mat), *tri_alpha = NULL, alpha = 0;
    st = mat ? gather_mesh(d, fn, &a, err)
             : cst_fail(err, CST_ERR_OOM, "%s: out of memory for %d triangles", fn, d->num_triangles);
    if (st == CST_OK) st = check_degenerate(d, &a, fn, err);
    for (int i = 0; st == CST_OK && a.uv && i < d->num_vertices; i++)
        if (!isfinite(a.uv[i].x) || !isfinite(a.uv[i].y))
            st = cst_fail(err, CST_ERR_INVALID_ARG, "%s: uv of vertex %d is not finite", fn, i);
    if (st == CST_OK) st = scene_build_alpha(scene, &d->alpha, fn, &alpha, err);
    if (st == CST_OK) st = scene_build_triangle_alphas(scene, d, fn, &tri_alpha, err);
    int kept = 0;
    for (int t = 0; st == CST_OK && t < d->num_triangles; t++) {
        const int *i = &a.idx[3 * t];
        if (!(triangle_area(a.pos[i[0]], a.pos[i[1]], a.pos[i[2]]) > 0.0f)) continue; /* skip_degenerate */
        memmove(&a.idx[3 * kept], i, 3 * sizeof *i);
        if (tri_alpha) tri_alpha[kept] = tri_alpha[t];
        mat[kept++] = d->triangle_materials ? d->triangle_materials[t] : d->material;
    }
    if (st == CST_OK && kept == 0)
        st = cst_fail(err, CST_ERR_INVALID_ARG, "%s: all %d triangles have zero area; expected at least one "
                      "that is not degenerate", fn, d->num_triangles);
    if (st == CST_OK)
        st = scene_add_instance_proto(scene, a.pos, a.nrm, d->num_vertices, a.idx, mat, kept, out_id, err);
    /* uvs and cut-outs (the mesh's one alpha as every triangle's) for the prototype */
    for (int t = 0; st == CST_OK && alpha && !tri_alpha && t < kept; t++) mat[t] = alpha;
    if (st == CST_OK && (a.uv || tri_alpha || alpha))
        st = instances_proto_set_surface(scene->instances, *out_id, a.uv, tri_alpha ? tri_alpha : alpha ? mat : NULL,
                                         err);
    if (st == CST_OK && num_dropped) *num_dropped = d->num_triangles - kept;
    mesh_arrays_free(&a);
    free(tri_alpha);
    free(mat);
    return st;
}

static CstStatus add_instance(CstScene *scene, int object, const float m[12], const float m_end[12], const char *fn,
                              CstError *err)
{
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!m) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_object is NULL", fn);
    int objects = scene->instances ? scene->instances->num_protos : 0;
    if (object < 0 || object >= objects)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: object %d is not an object of this scene; expected %s%d",
                        fn, object, objects ? "0 to " : "an id from cst_scene_add_object (there are none), ",
                        objects - 1);
    Transform xf, xf_end;
    if ((st = read_instance_matrix(m, fn, "world_from_object", &xf, err)) != CST_OK) return st;
    if (m_end && (st = read_instance_matrix(m_end, fn, "world_from_object_end", &xf_end, err)) != CST_OK) return st;
    return scene_add_instance_moving(scene, object, &xf, m_end ? &xf_end : &xf, err);
}

CstStatus cst_scene_add_instance(CstScene *scene, int object, const float m[12], CstError *err)
{
    return add_instance(scene, object, m, NULL, "cst_scene_add_instance", err);
}

CstStatus cst_scene_add_instance_motion(CstScene *scene, int object, const float start[12], const float end[12],
                                        CstError *err)
{
    if (!end) {
        cst_error_clear(err);
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_add_instance_motion: world_from_object_end is NULL");
    }
    return add_instance(scene, object, start, end, "cst_scene_add_instance_motion", err);
}

static CstStatus add_sphere(CstScene *scene, const float center[3], float radius, int material,
                            const CstEmission *emission, const CstAlpha *alpha, const char *fn, CstError *err)
{
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!center) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: center is NULL", fn);
    Vec3 c;
    if ((st = read_vec3(center, fn, "center", &c, err)) != CST_OK) return st;
    if (!(radius >= BUILD_MIN_RADIUS && radius <= BUILD_MAX_LENGTH))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: radius %g; expected a finite radius from 1e-18 to 1e18",
                        fn, (double)radius);
    if (material < 0 || material >= scene->num_materials)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: material %d is not a material of this scene; expected 0 to %d",
                        fn, material, scene->num_materials - 1);
    Emission em;
    double peak = 0.0;
    if ((st = read_emission(scene, emission, fn, &em, &peak, err)) != CST_OK) return st;
    if (peak > 0.0 && (st = check_product(fn, "the emitted power pi x 4 pi r^2 x radiance",
                                          4.0 * (double)CST_PI * (double)CST_PI * (double)radius * (double)radius *
                                              peak * (em.two_sided ? 2.0 : 1.0),
                                          "a smaller radiance (or scale) or radius", err)) != CST_OK)
        return st;
    const int first = scene->num_emitters;
    int alpha_id = 0;
    if ((st = scene_build_alpha(scene, alpha, fn, &alpha_id, err)) != CST_OK) return st;
    if ((st = scene_add_sphere(scene, c, radius, material, &em, err)) != CST_OK) return st;
    scene->sphere_info[scene->num_spheres - 1].alpha = alpha_id;
    return peak > 0.0 && emission ? scene_set_emitter_spectrum(scene, first, emission->spectrum, err) : CST_OK;
}

/* A shape desc's world_from_object (3 x 4 rows; all zero: the identity) into *xf, and its
 * normal matrix into *nm when nm is not NULL; CST_ERR_INVALID_ARG naming a non-finite
 * entry, or for a singular transform when invertible is asked for. */
static CstStatus desc_transform(const CstShapeDesc *d, const char *fn, bool invertible, Transform *xf, Transform *nm,
                                CstError *err)
{
    float rows[16] = {0};
    int all_zero = 1;
    for (int k = 0; k < 12; k++) {
        if (!isfinite(d->world_from_object[k]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_object[%d] is %g; expected finite numbers", fn,
                            k, (double)d->world_from_object[k]);
        rows[k] = d->world_from_object[k];
        all_zero &= rows[k] == 0.0f;
    }
    rows[15] = 1.0f;
    *xf = all_zero ? transform_identity() : transform_from_rows(rows);
    Transform inv;
    if (invertible && !transform_invert(xf, &inv))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_object is singular (or its inverse is not "
                        "finite); expected an invertible affine transform", fn);
    if (nm) {
        *nm = transform_identity();
        transform_normal_matrix(xf, nm);
    }
    return CST_OK;
}

/* cst_scene_add_shape's bilinear patch: corners through world_from_object (all zero:
 * identity), normals through its normal matrix, then shape_init_bilinear. */
static CstStatus add_patch(CstScene *scene, const CstShapeDesc *d, double peak, const char *fn, CstError *err)
{
    if (peak > 0.0)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: emitting bilinear patches are not supported; expected a zero "
                        "emission (split an emitting patch into two triangles)", fn);
    if (d->patch_has_normals != 0 && d->patch_has_normals != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: patch_has_normals %d; expected 0 or 1", fn, d->patch_has_normals);
    if (d->patch_has_uvs != 0 && d->patch_has_uvs != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: patch_has_uvs %d; expected 0 or 1", fn, d->patch_has_uvs);
    Transform xf, nm;
    const CstStatus st0 = desc_transform(d, fn, true, &xf, &nm, err);
    if (st0 != CST_OK) return st0;
    Vec3 p[4], n[4];
    Vec2 uv[4];
    for (int i = 0; i < 4; i++) {
        Vec3 q = v3(d->patch[i][0], d->patch[i][1], d->patch[i][2]);
        p[i] = transform_point(&xf, q);
        if (!(v3_max_abs(p[i]) <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: patch corner %d is (%g, %g, %g) in world space; expected "
                            "finite coordinates within 1e18", fn, i, (double)p[i].x, (double)p[i].y, (double)p[i].z);
        n[i] = transform_normal(&nm, v3(d->patch_normals[i][0], d->patch_normals[i][1], d->patch_normals[i][2]));
        if (d->reverse_orientation) n[i] = v3_neg(n[i]);
        uv[i] = v2(d->patch_uvs[i][0], d->patch_uvs[i][1]);
        if (!isfinite(uv[i].x) || !isfinite(uv[i].y))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: patch_uvs[%d] is not finite", fn, i);
    }
    AnalyticShape sh;
    bool flip = (d->reverse_orientation != 0) != (transform_det(&xf) < 0.0);
    if (!shape_init_bilinear(&sh, p, d->patch_has_normals ? n : NULL, d->patch_has_uvs ? uv : NULL, flip))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: the bilinear patch has no area (its corners lie on one line) "
                        "or a normal is not finite; expected a patch with area", fn);
    int alpha_id = 0;
    CstStatus st = scene_build_alpha(scene, &d->alpha, fn, &alpha_id, err);
    return st != CST_OK ? st : scene_add_patch(scene, &sh, d->material, alpha_id, err);
}

/* cst_scene_add_shape's signed-distance tree: the nodes converted and checked by
 * sdf_tree_create (the offending node named), the shape added without an emitter. */
static CstStatus add_sdf(CstScene *scene, const CstShapeDesc *d, double peak, const char *fn, CstError *err)
{
    if (peak > 0.0)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: emitting SDF shapes are not supported; expected a zero emission", fn);
    const int n = d->sdf_num_nodes;
    if (!d->sdf_nodes || n < 1 || n > SDF_MAX_NODES)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: sdf_num_nodes %d (sdf_nodes %s); expected 1 to %d nodes", fn, n,
                        d->sdf_nodes ? "given" : "NULL", SDF_MAX_NODES);
    Transform xf;
    const CstStatus st0 = desc_transform(d, fn, false, &xf, NULL, err);
    if (st0 != CST_OK) return st0;
    SdfNodeDesc *nd = calloc((size_t)n, sizeof *nd);
    if (!nd) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for an SDF tree", fn);
    for (int i = 0; i < n; i++) {
        const CstSdfNode *c = &d->sdf_nodes[i];
        int zero = 1;
        float nr[16] = {0};
        for (int k = 0; k < 12; k++) nr[k] = c->parent_from_node[k], zero &= nr[k] == 0.0f;
        nr[15] = 1.0f;
        nd[i] = (SdfNodeDesc){(SdfKind)c->kind,
                              {(double)c->params[0], (double)c->params[1], (double)c->params[2], (double)c->params[3]},
                              c->a, c->b, (double)c->k, !zero, zero ? transform_identity() : transform_from_rows(nr)};
    }
    const SdfOptions opt = {(double)d->sdf_epsilon, d->sdf_max_steps};
    SdfTree *tree = NULL;
    int bad = -1;
    const SdfError e = sdf_tree_create(nd, n, &xf, &opt, &tree, &bad);
    free(nd);
    if (e != SDF_OK) {
        if (bad >= 0) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: sdf_nodes[%d]: %s", fn, bad, sdf_error_string(e));
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: SDF tree: %s", fn, sdf_error_string(e));
    }
    AnalyticShape sh;
    shape_init_sdf(&sh, tree);
    int alpha_id = 0;
    CstStatus st = scene_build_alpha(scene, &d->alpha, fn, &alpha_id, err);
    if (st == CST_OK) st = scene_add_patch(scene, &sh, d->material, alpha_id, err);
    if (st != CST_OK) sdf_tree_destroy(tree);
    return st;
}

/* cst_scene_add_shape's curve: control points through world_from_object, widths times the
 * cube root of its |det|, ribbon normals through its normal matrix; 2^curve_split_depth
 * segments, each an AnalyticShape (shape_init_curve) added as a patch is. */
static CstStatus add_curve(CstScene *scene, const CstShapeDesc *d, double peak, const char *fn, CstError *err)
{
    if (peak > 0.0)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: emitting curves are not supported; expected a zero emission", fn);
    if ((unsigned)d->curve_type > CST_CURVE_RIBBON)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: curve_type %d is not a CstCurveType value", fn, (int)d->curve_type);
    if (d->curve_split_depth < 0 || d->curve_split_depth > 10)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: curve_split_depth %d; expected 0 to 10", fn, d->curve_split_depth);
    Transform xf, nm;
    const CstStatus st0 = desc_transform(d, fn, true, &xf, &nm, err);
    if (st0 != CST_OK) return st0;
    const double det = (double)transform_det(&xf);
    const float scale = (float)cbrt(fabs(det));
    Vec3 cp[4], n[2];
    for (int i = 0; i < 4; i++) {
        cp[i] = transform_point(&xf, v3(d->curve_p[i][0], d->curve_p[i][1], d->curve_p[i][2]));
        if (!(v3_max_abs(cp[i]) <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: curve point %d is (%g, %g, %g) in world space; expected "
                            "finite coordinates within 1e18", fn, i, (double)cp[i].x, (double)cp[i].y, (double)cp[i].z);
    }
    for (int i = 0; i < 2; i++) n[i] = transform_normal(&nm, v3(d->curve_normals[i][0], d->curve_normals[i][1], d->curve_normals[i][2]));
    const float w0 = d->curve_width[0] * scale, w1 = d->curve_width[1] * scale;
    if (!(w0 >= 0.0f && w1 >= 0.0f && w0 + w1 > 0.0f && w0 <= BUILD_MAX_LENGTH && w1 <= BUILD_MAX_LENGTH))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: curve widths %g, %g; expected finite widths >= 0, not both 0",
                        fn, (double)d->curve_width[0], (double)d->curve_width[1]);
    int alpha_id = 0;
    CstStatus st = scene_build_alpha(scene, &d->alpha, fn, &alpha_id, err);
    if (st != CST_OK) return st;
    const bool flip = (d->reverse_orientation != 0) != (det < 0.0);
    const int segs = 1 << d->curve_split_depth;
    for (int i = 0; i < segs; i++) {
        AnalyticShape sh;
        if (!shape_init_curve(&sh, cp, (float)i / (float)segs, (float)(i + 1) / (float)segs, w0, w1,
                              (CurveType)d->curve_type, d->curve_type == CST_CURVE_RIBBON ? n : NULL, flip))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: curve segment %d of %d: a ribbon normal is zero or not "
                            "finite, or the segment's bounds overflow; expected nonzero normals", fn, i, segs);
        if ((st = scene_add_patch(scene, &sh, d->material, alpha_id, err)) != CST_OK) return st;
    }
    return CST_OK;
}

CstStatus cst_scene_add_shape(CstScene *scene, const CstShapeDesc *d, CstError *err)
{
    static const char fn[] = "cst_scene_add_shape";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    if ((int)d->type < CST_SHAPE_CYLINDER || d->type > CST_SHAPE_CURVE)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: type %d is not a CstShapeType value", fn, (int)d->type);
    if (d->material < 0 || d->material >= scene->num_materials)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: material %d is not a material of this scene; expected 0 to %d",
                        fn, d->material, scene->num_materials - 1);
    Emission em;
    double peak = 0.0;
    if ((st = read_emission(scene, &d->emission, fn, &em, &peak, err)) != CST_OK) return st;
    if (d->type == CST_SHAPE_BILINEAR) return add_patch(scene, d, peak, fn, err);
    if (d->type == CST_SHAPE_SDF) return add_sdf(scene, d, peak, fn, err);
    if (d->type == CST_SHAPE_TORUS && peak > 0.0)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: emitting tori are not supported; expected a zero emission", fn);
    if (d->type == CST_SHAPE_TORUS && !(d->minor_radius > 0.0f && d->minor_radius < d->radius))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: torus minor_radius %g, radius %g; expected 0 < minor_radius < "
                        "radius", fn, (double)d->minor_radius, (double)d->radius);
    if (d->type == CST_SHAPE_CURVE) return add_curve(scene, d, peak, fn, err);
    const float vals[5] = {d->radius, d->z_min, d->z_max, d->height, d->inner_radius};
    for (int k = 0; k < 5; k++)
        if (!(fabsf(vals[k]) <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: radius, z_min, z_max, height or inner_radius %g; expected "
                            "finite lengths within 1e18", fn, (double)vals[k]);
    if (!(d->radius >= BUILD_MIN_RADIUS) || !(d->phi_max_degrees >= 0.0f && d->phi_max_degrees <= 360.0f) ||
        (d->type == CST_SHAPE_CYLINDER && !(d->z_min < d->z_max)) ||
        (d->type == CST_SHAPE_DISK && !(d->inner_radius >= 0.0f && d->inner_radius < d->radius)))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: radius %g, z %g..%g, inner_radius %g, phi_max_degrees %g; "
                        "expected radius >= 1e-18, z_min < z_max (cylinder), 0 <= inner_radius < radius (disk), "
                        "phi_max_degrees in [0, 360]", fn, (double)d->radius, (double)d->z_min, (double)d->z_max,
                        (double)d->inner_radius, (double)d->phi_max_degrees);
    Transform xf;
    const CstStatus st0 = desc_transform(d, fn, true, &xf, NULL, err);
    if (st0 != CST_OK) return st0;
    ShapeParams p = {(ShapeTag)d->type, d->radius, d->z_min, d->z_max, d->height, d->inner_radius,
                     (d->phi_max_degrees > 0.0f ? d->phi_max_degrees : 360.0f) * (CST_PI / 180.0f),
                     d->reverse_orientation != 0, d->minor_radius};
    if (d->type == CST_SHAPE_SPHERE && !(d->z_min < d->z_max)) p.z_min = -d->radius, p.z_max = d->radius;
    int alpha_id = 0;
    if ((st = scene_build_alpha(scene, &d->alpha, fn, &alpha_id, err)) != CST_OK) return st;
    if (peak > 0.0) {
        /* The power check as for spheres, from the world area (shape_init again: cheap). */
        AnalyticShape tmp;
        if (shape_init(&tmp, &p, &xf) &&
            (st = check_product(fn, "the emitted power pi x area x radiance",
                                (double)CST_PI * (double)shape_area(&tmp) * peak * (em.two_sided ? 2.0 : 1.0),
                                "a smaller radiance (or scale) or shape", err)) != CST_OK)
            return st;
    }
    const int first = scene->num_emitters;
    if ((st = scene_add_shape(scene, &p, &xf, d->material, &em, alpha_id, err)) != CST_OK) return st;
    return peak > 0.0 ? scene_set_emitter_spectrum(scene, first, d->emission.spectrum, err) : CST_OK;
}

CstStatus cst_scene_add_sphere(CstScene *scene, const float center[3], float radius, int material,
                               const CstEmission *emission, CstError *err)
{
    return add_sphere(scene, center, radius, material, emission, NULL, "cst_scene_add_sphere", err);
}

CstStatus cst_scene_add_sphere_alpha(CstScene *scene, const float center[3], float radius, int material,
                                     const CstEmission *emission, const CstAlpha *alpha, CstError *err)
{
    return add_sphere(scene, center, radius, material, emission, alpha, "cst_scene_add_sphere_alpha", err);
}

/* ------------------------------------------------------------------ render settings */

/* cst_render_settings_resolve's rule: a field holds a value unless it is CST_UNSET or, where
 * 0 means nothing, 0. */
static int setting_set(double v, int zero_unset) { return v != CST_UNSET && !(zero_unset && v == 0.0); }

static CstStatus check_settings(const CstRenderSettings *r, CstError *err)
{
    static const char fn[] = "cst_scene_set_render_settings";
    if (setting_set(r->threads, 0) || r->progress || r->progress_user || setting_set(r->first_sample, 1) ||
        setting_set(r->sample_block, 1) || setting_set(r->noise_target, 1))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: threads, progress, progress_user, first_sample, "
                        "sample_block and noise_target belong to a render, not to a scene; expected them unset "
                        "(cst_render_settings_init)", fn);
    if (r->resume || r->pass_done || r->pass_user || r->photon_cache || r->photon_split)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: resume, pass_done, pass_user, photon_cache and photon_split belong to a render, "
                        "not to a scene; expected them NULL (cst_render_settings_init)", fn);
    const int ints[] = {r->width, r->height, r->spp, r->rr_depth, r->light_rr_depth, r->photons};
    static const char *const names[] = {"width", "height", "spp", "rr_depth", "light_rr_depth", "photons"};
    for (int k = 0; k < 6; k++)
        if (setting_set(ints[k], 1) && ints[k] < 1)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s %d; expected > 0", fn, names[k], ints[k]);
    if (setting_set(r->max_depth, 0) && r->max_depth < 0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: max_depth %d; expected >= 0 (0 = unbounded)", fn, r->max_depth);
    if (setting_set(r->time_limit, 0) && !(r->time_limit >= 0.0 && isfinite(r->time_limit)))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: time_limit %g; expected seconds >= 0 (0 = none)", fn, r->time_limit);
    if (setting_set(r->photon_radius, 1) && !(r->photon_radius > 0.0 && isfinite(r->photon_radius)))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: photon_radius %g; expected a radius > 0", fn, r->photon_radius);
    if (r->exposure_set && !isfinite(r->exposure))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: exposure %g; expected a finite number of stops", fn, r->exposure);
    if (setting_set(r->max_component, 1) && !(r->max_component > 0.0 && r->max_component <= (double)FLT_MAX))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: max_component %g; expected a number > 0 (0 = no clamp)", fn,
                        r->max_component);
    if ((int)r->integrator < CST_INTEGRATOR_DEFAULT || r->integrator > CST_INTEGRATOR_MMLT ||
        (int)r->filter < CST_FILTER_DEFAULT || r->filter > CST_FILTER_MITCHELL ||
        (int)r->sampler < CST_SAMPLER_DEFAULT || r->sampler > CST_SAMPLER_ZSOBOL)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: integrator %d, filter %d or sampler %d is not one of the "
                        "CstIntegrator, CstFilter or CstSampler values", fn, (int)r->integrator, (int)r->filter,
                        (int)r->sampler);
    if ((int)r->color_mode < CST_COLOR_DEFAULT || r->color_mode > CST_COLOR_SPECTRAL)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: color_mode %d is not a CstColorMode value", fn,
                        (int)r->color_mode);
    if (setting_set(r->white_balance, 1) && !(r->white_balance > 0.0 && r->white_balance <= 1e6))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: white_balance %g; expected a colour temperature in kelvin "
                        "in (0, 1e6], or 0 for none", fn, r->white_balance);
    if (setting_set(r->regularize, 0) && r->regularize != 0 && r->regularize != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: regularize %d; expected 0 or 1", fn, r->regularize);
    if (setting_set(r->mlt_large_step, 0) && !(r->mlt_large_step >= 0.0 && r->mlt_large_step <= 1.0))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mlt_large_step %g; expected a probability in [0, 1]", fn,
                        r->mlt_large_step);
    if (setting_set(r->mlt_sigma, 1) && !(r->mlt_sigma > 0.0 && r->mlt_sigma <= 1.0))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mlt_sigma %g; expected a width in (0, 1]", fn, r->mlt_sigma);
    if ((setting_set(r->mlt_bootstrap, 1) && r->mlt_bootstrap < 1) || (setting_set(r->mlt_chains, 1) && r->mlt_chains < 1))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mlt_bootstrap %d, mlt_chains %d; expected counts > 0", fn,
                        r->mlt_bootstrap, r->mlt_chains);
    if (setting_set(r->png_linear, 0) && r->png_linear != 0 && r->png_linear != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: png_linear %d; expected 0 or 1", fn, r->png_linear);
    if (setting_set(r->aovs, 0) && (r->aovs & ~(CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH | CST_AOV_VARIANCE)))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: aovs 0x%x holds bits other than CST_AOV_*", fn, (unsigned)r->aovs);
    if (r->crop[0] != CST_UNSET && (r->crop[0] | r->crop[1] | r->crop[2] | r->crop[3]) &&
        !(r->crop[0] >= 0 && r->crop[2] >= 0 && r->crop[0] < r->crop[1] && r->crop[2] < r->crop[3]))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: crop [%d, %d, %d, %d]; expected 0 <= x0 < x1 and "
                        "0 <= y0 < y1 (or all zero)", fn, r->crop[0], r->crop[1], r->crop[2], r->crop[3]);
    return CST_OK;
}

#define SETTING_MERGE(field, zero_unset) \
    if (setting_set(r->field, zero_unset)) sc->field = r->field

CstStatus cst_scene_set_render_settings(CstScene *scene, const CstRenderSettings *r, CstError *err)
{
    static const char fn[] = "cst_scene_set_render_settings";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!r) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: settings is NULL", fn);
    if ((st = check_settings(r, err)) != CST_OK) return st;
    CstRenderSettings *sc = &scene->settings;
    SETTING_MERGE(width, 1);
    SETTING_MERGE(height, 1);
    SETTING_MERGE(spp, 1);
    SETTING_MERGE(time_limit, 0);
    SETTING_MERGE(integrator, 1);
    SETTING_MERGE(filter, 1);
    SETTING_MERGE(max_depth, 0);
    SETTING_MERGE(rr_depth, 1);
    SETTING_MERGE(light_rr_depth, 1);
    SETTING_MERGE(photons, 1);
    SETTING_MERGE(photon_radius, 1);
    SETTING_MERGE(sampler, 1);
    SETTING_MERGE(color_mode, 1);
    SETTING_MERGE(png_linear, 0);
    SETTING_MERGE(aovs, 0);
    SETTING_MERGE(max_component, 1);
    SETTING_MERGE(regularize, 0);
    SETTING_MERGE(white_balance, 1);
    SETTING_MERGE(mlt_large_step, 0);
    SETTING_MERGE(mlt_sigma, 1);
    SETTING_MERGE(mlt_bootstrap, 1);
    SETTING_MERGE(mlt_chains, 1);
    if (r->seed_set) { sc->seed = r->seed; sc->seed_set = 1; }
    if (r->exposure_set) { sc->exposure = r->exposure; sc->exposure_set = 1; }
    if (r->crop[0] != CST_UNSET) memcpy(sc->crop, r->crop, sizeof sc->crop);
    return CST_OK;
}
#undef SETTING_MERGE

/* Every light's power once the scene's size is known (check_product): directional lights
 * and the environment send pi R^2 x their irradiance through the scene's bounding sphere
 * of radius R; the pbrt loader adds its point, spot and distant lights and environment
 * without the public calls, so all lights are checked here. */
static CstStatus check_light_powers(const Scene *s, CstError *err)
{
    static const char fn[] = "cst_scene_commit";
    const EmitterSampler *es = &s->emitter_sampler;
    const double disk = (double)CST_PI * (double)es->radius * (double)es->radius;
    for (int i = 0; i < es->lights; i++) {
        const Light *l = &es->light[i];
        double power = 0.0;
        const char *what = "";
        switch (l->type) {
        case LIGHT_AREA: {
            const Emitter *e = &l->u.area;
            double peak = color_peak(e->radiance) * (e->texture ? color_peak(s->textures[e->texture - 1].max) : 1.0);
            power = (double)CST_PI * (double)e->area * peak * (e->two_sided ? 2.0 : 1.0);
            what = "an emitting surface's power pi x area x radiance";
            break;
        }
        case LIGHT_POINT:
            power = 4.0 * (double)CST_PI * color_peak(l->u.point.intensity);
            what = "a point light's power 4 pi x intensity";
            break;
        case LIGHT_SPOT:
            power = 4.0 * (double)CST_PI * color_peak(l->u.spot.intensity);
            what = "a spot light's power (bound) 4 pi x intensity";
            break;
        case LIGHT_GONIO:
            power = 4.0 * (double)CST_PI * color_peak(l->u.gonio.intensity) * (double)l->u.gonio.image.mean;
            what = "a goniometric light's power 4 pi x intensity x the image's mean";
            break;
        case LIGHT_PROJECTION:
            power = color_peak(color_mul(l->u.proj.intensity, l->u.proj.image.integral));
            what = "a projection light's power intensity x the image over its solid angle";
            break;
        case LIGHT_DIRECTIONAL:
            power = disk * color_peak(l->u.directional.irradiance);
            what = "a directional light's power pi R^2 x irradiance (R the scene's bounding radius)";
            break;
        case LIGHT_ENVIRONMENT:
            power = disk * (double)l->u.env->power;
            what = "the environment's power pi R^2 x its radiance over the sphere (R the scene's bounding radius)";
            break;
        }
        if (!(power <= (double)FLT_MAX))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: light %d: %s = %g overflows a float (above 3.4e38); "
                            "expected a smaller value (or a smaller scene)", fn, i, what, power);
    }
    return CST_OK;
}

CstStatus cst_scene_commit(CstScene *scene, CstError *err)
{
    cst_error_clear(err);
    if (!scene) return cst_fail(err, CST_ERR_INVALID_ARG, "cst_scene_commit: scene is NULL");
    CstStatus st = scene_commit(scene, err);
    /* After a failure here the scene can only be destroyed (the loaders do). */
    return st == CST_OK ? check_light_powers(scene, err) : st;
}
