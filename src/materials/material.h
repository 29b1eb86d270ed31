/* Material descriptions as stored in the scene. A Material is turned into a Bsdf at each
 * hit (materials/bsdf.h); keeping the two apart lets textures plug in later.
 * Roughness: scenes give a perceptual roughness r in [0, 1] and the GGX width is
 * alpha = r^2 (Burley 2012, "Physically-Based Shading at Disney", sec. 5.4), so equal
 * steps of r look like equal steps of blur. Below MATERIAL_SMOOTH_ALPHA the lobes become
 * the exact delta lobes of a smooth surface. */
#ifndef CST_MATERIALS_MATERIAL_H
#define CST_MATERIALS_MATERIAL_H

#include <stdbool.h>

#include "math/color.h"

typedef enum MaterialType {
    MATERIAL_DIFFUSE,    /* Lambertian: albedo = hemispherical reflectance */
    MATERIAL_MIRROR,     /* perfect specular reflection scaled by albedo */
    MATERIAL_GLASS,      /* smooth dielectric: exact Fresnel, reflect or refract; albedo tints both */
    MATERIAL_CONDUCTOR,  /* metal: complex-IOR Fresnel, GGX when rough, mirror when smooth */
    MATERIAL_DIELECTRIC, /* glass that may be rough: GGX reflection + transmission (Walter 2007) */
    MATERIAL_PLASTIC,    /* dielectric coat (smooth or GGX) over Lambert; see bsdf.c */
    /* pbrt-v4's layered materials (layered.c): a dielectric interface (ior, roughness) over
     * Lambert (albedo) or a conductor (eta, k, base_roughness) with a scattering slab between,
     * evaluated by a stochastic random walk. */
    MATERIAL_COATED_DIFFUSE,
    MATERIAL_COATED_CONDUCTOR,
    /* pbrt-v4's mix: at each hit one of two materials, the second with probability amount
     * (scene_bsdf chooses; a Bsdf is never of this type). */
    MATERIAL_MIX,
    /* pbrt-v4's diffusetransmission: Lambertian reflection (albedo) on wo's side and
     * Lambertian transmission (transmittance) to the other */
    MATERIAL_DIFFUSE_TRANSMISSION,
    /* pbrt-v4's thindielectric: a thin slab of ior; mirror reflection and undeviated
     * transmission, the slab's internal reflections summed in closed form */
    MATERIAL_THIN_DIELECTRIC,
    /* pbrt-v4's measured: a tabulated BRDF read from an RGL .bsdf file (measured.h) */
    MATERIAL_MEASURED,
    /* pbrt-v4's hair: the fibre BSDF of Chiang et al. 2016 (hair.h) */
    MATERIAL_HAIR
} MaterialType;

static inline bool material_is_layered(MaterialType t)
{
    return t == MATERIAL_COATED_DIFFUSE || t == MATERIAL_COATED_CONDUCTOR;
}

/* GGX alpha below this is treated as perfectly smooth (pbrt-v4 uses the same cut). */
#define MATERIAL_SMOOTH_ALPHA 1e-3f

/* The rough plastic's coat albedo E(mu), tabulated at mu_j = (j / (N - 1))^2 (bsdf.c). */
#define MATERIAL_COAT_TABLE 32

typedef struct Material {
    MaterialType type;
    Color albedo;      /* diffuse, mirror, plastic base; dielectric tint */
    float ior;       /* glass, dielectric, plastic coat: interior over exterior IOR, > 0 */
    float roughness; /* conductor, dielectric, plastic: perceptual roughness in [0, 1] */
    /* Anisotropic roughness (conductor, dielectric and the coated materials' interface and
     * conductor base; pbrt-v4's uroughness, vroughness): when set, roughness and
     * base_roughness are the perceptual roughness along the surface's dp/du and
     * roughness_v and base_roughness_v along the other tangent; when clear (a zero-
     * initialised Material) the lobes are isotropic and the _v fields unused. */
    bool anisotropic;
    float roughness_v, base_roughness_v;
    Color eta, k;      /* conductor: complex IOR eta + i k per RGB channel (material_metal) */
    /* Coated (layered) materials: the conductor base's perceptual roughness (coated
     * conductor; roughness is the interface's), the slab's optical thickness, its
     * single-scattering albedo and Henyey-Greenstein g, and the random walk's steps and
     * walks per estimate (pbrt-v4's maxdepth, nsamples; > 0). */
    float base_roughness;
    float thickness, g;
    Color layer_albedo;
    int max_depth, nsamples;
    /* Mix: the two materials (indices into the scene's materials, both added before this
     * one, so chains of mixes end), the probability of the second, and a texture replacing
     * it (1 + index, 0 for none; its mean over channels, clamped to [0, 1]). */
    int mix[2];
    float amount;
    int amount_texture;
    Color transmittance; /* diffuse transmission: the transmitted lobe's hemispherical share */
    /* Spectra replacing eta, k (conductors, the coated conductor's base) and ior (glass,
     * dielectric, thin dielectric, the coated interface) in spectral mode: 1 + an index
     * into the scene's spectra, 0 for none (scene_bsdf applies them). eta, k and ior hold
     * their RGB-mode reductions. ior_dispersive: the ior spectrum is not constant. */
    int eta_spectrum, k_spectrum, ior_spectrum;
    bool ior_dispersive;
    /* Textures replacing albedo and roughness: 1 + an index into the scene's textures, 0 for
     * none (so a zero-initialised Material has none). A roughness texture gives the mean of
     * its channels; a rough plastic cannot take one (its coat table depends on roughness). */
    int albedo_texture, roughness_texture;
    /* With anisotropic set: 1 + a texture index for the roughness along the other tangent
     * (roughness_texture is then the one along dp/du), or 0 (roughness_texture sets both). */
    int roughness_v_texture;
    /* Conductor, coated conductor: 1 + texture indices replacing eta and k per hit, or a
     * reflectance texture replacing both (pbrt-v4's "reflectance": eta 1, k = 2 sqrt(R) /
     * sqrt(1 - R)); 0 for none (scene_bsdf_textures applies them). */
    int eta_texture, k_texture, reflectance_texture;
    /* Shading-normal textures, 1 + a texture index or 0 (scene_bsdf applies them): a float
     * displacement for bump mapping and a tangent-space normal map (pbrt-v4 BumpMap and
     * NormalMap); the displacement wins when both are set, as in pbrt-v4. */
    int displacement_texture, normal_map_texture;
    /* Reflective materials (diffuse, mirror, conductor, plastic) reflect on both sides
     * unless one_sided is set, when the back (against the normal) is black. Stored
     * inverted so that a zero-initialised Material keeps the historical two-sided
     * behaviour; the scene file's key is "two_sided". Dielectrics have an inside and
     * ignore it. */
    bool one_sided;
    /* Measured: the tables (owned by the scene, which keeps them until scene_destroy) and,
     * between a loader and cst_scene_add_material only, the file to read them from. */
    const struct MeasuredBsdf *measured;
    const char *measured_file;
    /* Hair (hair.h; ior is the fibre's eta): longitudinal and azimuthal roughness beta_m,
     * beta_n in (0, 1], the cuticle tilt hair_alpha in degrees, and the absorption: sigma_a
     * per fibre radius (linear RGB, >= 0), or with hair_color set the colour in albedo
     * from which the BSDF derives it (Chiang et al. eq. 9). */
    float beta_m, beta_n, hair_alpha;
    Color sigma_a;
    bool hair_color;
    /* Subsurface (pbrt-v4's subsurface material; materials/bssrdf.h): a MATERIAL_DIELECTRIC
     * (ior = eta, roughness; albedo 1) over a homogeneous medium of phase asymmetry g,
     * rendered by the path tracer's BSSRDF step. The medium: sss_sigma_a, sss_sigma_s per
     * unit length (linear RGB, >= 0, pbrt's scale applied), or with sss_from_reflectance
     * the one of diffuse reflectance sss_reflectance (or 1 + texture index
     * sss_reflectance_texture, 0 none) and mean free path sss_mfp (scale applied). The
     * profile table (for this g and eta) is the scene's, made by scene_add_material. */
    bool subsurface, sss_from_reflectance;
    Color sss_sigma_a, sss_sigma_s, sss_mfp, sss_reflectance;
    int sss_reflectance_texture;
    const struct BssrdfTable *bssrdf;
    /* Derived by material_prepare() (scene_add_material calls it): the rough plastic's
     * coat albedo table and its cosine-weighted average. */
    bool prepared;
    float coat_e[MATERIAL_COAT_TABLE];
    float coat_e_avg;
} Material;

/* GGX alpha of a perceptual roughness (alpha = r^2). */
static inline float material_alpha(float roughness) { return roughness * roughness; }
/* The alpha a BSDF uses: 0 (the smooth, delta lobes) below MATERIAL_SMOOTH_ALPHA. */
static inline float material_bsdf_alpha(float roughness)
{
    float a = material_alpha(roughness);
    return a < MATERIAL_SMOOTH_ALPHA ? 0.0f : a;
}

/* GGX widths (ax along the tangent, ay along the bitangent) of a perceptual roughness pair
 * as a BSDF uses them: both 0 (the smooth, delta lobes) when the larger is below
 * MATERIAL_SMOOTH_ALPHA (pbrt-v4 TrowbridgeReitzDistribution::EffectivelySmooth), else
 * each at least 1e-4 (as pbrt-v4 clamps them) so that D stays finite. With ru = rv this
 * is material_bsdf_alpha twice, bit for bit. */
static inline void material_bsdf_alpha2(float ru, float rv, float *ax, float *ay)
{
    float a = material_alpha(ru), b = material_alpha(rv);
    if (a < MATERIAL_SMOOTH_ALPHA && b < MATERIAL_SMOOTH_ALPHA) {
        *ax = *ay = 0.0f;
    } else if (ru == rv) {
        *ax = *ay = a;
    } else {
        *ax = a < 1e-4f ? 1e-4f : a;
        *ay = b < 1e-4f ? 1e-4f : b;
    }
}
/* True when the material's lobes are anisotropic (its BSDF needs the tangent dp/du). */
static inline bool material_is_anisotropic(const Material *m)
{
    if (!m->anisotropic) return false;
    switch (m->type) {
    case MATERIAL_CONDUCTOR:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_COATED_DIFFUSE: return m->roughness != m->roughness_v || m->roughness_v_texture;
    case MATERIAL_COATED_CONDUCTOR:
        return m->roughness != m->roughness_v || m->base_roughness != m->base_roughness_v || m->roughness_v_texture;
    default: return false;
    }
}

/* Fills the derived fields (about 1 ms of SIMD quadrature for a rough plastic, nothing
 * otherwise). */
void material_prepare(Material *m);

/* Named conductors: "gold", "silver", "copper", "aluminium". Sets eta and k; returns
 * false for an unknown name. material_metal_names lists them, NULL-terminated. */
bool material_metal(const char *name, Color *eta, Color *k);
extern const char *const material_metal_names[];

#endif
