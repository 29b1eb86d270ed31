/* BSDFs at a surface point: a tagged union evaluated in the local shading frame.
 * Conventions (pbrt-v4's): wo points away from the surface toward the previous vertex,
 * wi toward the next; both world-space unit vectors at the API. bsdf_eval returns
 * f(wo, wi) * |cos theta_i|; pdfs are per unit solid angle. Delta lobes (mirror, smooth
 * glass, a smooth conductor, the smooth coat of plastic) are reached only through
 * bsdf_sample: bsdf_eval and bsdf_pdf return the non-delta part of a BSDF only (zero for
 * an all-delta one), and bsdf_sample says per sample whether it took a delta lobe. */
#ifndef CST_MATERIALS_BSDF_H
#define CST_MATERIALS_BSDF_H

#include <stdbool.h>
#include <stddef.h>

#include "materials/bsdf_lobe.h"
#include "materials/fresnel.h"
#include "materials/hair.h"
#include "materials/layered.h"
#include "materials/material.h"
#include "math/frame.h"
#include "math/color.h"
#include "sampling/warp.h"

/* The lobes' parameters, one struct per material type; Bsdf.type says which member of
 * Bsdf.lobe is live. Roughness is GGX's alpha, 0 for the smooth (delta) lobes; alpha is
 * the width along the frame's s axis, alpha_y along t (equal unless the material is
 * anisotropic, whose frame's s is the tangent dp/du: bsdf_set_tangent). */
typedef struct DiffuseLobe {   /* MATERIAL_DIFFUSE (Lambert) and MATERIAL_MIRROR (its tint) */
    Color albedo;
} DiffuseLobe;
typedef struct ConductorLobe { /* MATERIAL_CONDUCTOR */
    Color eta, k;              /* complex IOR, per channel */
    float alpha, alpha_y;
} ConductorLobe;
typedef struct DielectricLobe { /* MATERIAL_GLASS (alpha 0) and MATERIAL_DIELECTRIC */
    Color tint;                 /* scales reflection and transmission alike */
    float eta;                  /* inside over outside IOR */
    float alpha, alpha_y;
} DielectricLobe;
typedef struct DiffuseTransmissionLobe { /* MATERIAL_DIFFUSE_TRANSMISSION */
    Color reflectance, transmittance;     /* each lobe's hemispherical share */
} DiffuseTransmissionLobe;
typedef struct MeasuredLobe {   /* MATERIAL_MEASURED */
    const struct MeasuredBsdf *table; /* the scene's */
    bool spectral;              /* evaluate at lambda (bsdf_at_wavelengths), else in RGB */
    float lambda[COLOR_LANES];  /* the path's wavelengths, nm */
} MeasuredLobe;
typedef struct PlasticLobe {    /* MATERIAL_PLASTIC: a dielectric coat over Lambert */
    Color albedo;               /* the base's */
    float eta;                  /* the coat's inside over outside IOR */
    float alpha;                /* the coat's */
    /* The coat's directional albedo E(mu) (NULL: the smooth coat's Fresnel F(mu)) and its
     * cosine-weighted hemispherical average. */
    const float *coat_e;
    float coat_e_avg;
} PlasticLobe;

typedef struct Bsdf {
    MaterialType type;
    Frame frame; /* n = the shading normal ns (the geometric one without shading normals) */
    /* The geometric normal (glass: its side is the outside). It decides on which side of
     * the surface a direction is: a pair (wo, wi) scatters only when ng and the shading
     * frame agree on reflection vs transmission (pbrt-v3's convention), so interpolated
     * normals never let light through an opaque surface; see bsdf_init_shading. */
    Vec3 ng;
    bool shading;   /* ns != ng: the side checks and the adjoint correction apply */
    bool one_sided; /* reflective types: black seen from the back */
    union {
        DiffuseLobe diffuse; /* diffuse and mirror */
        ConductorLobe conductor;
        DielectricLobe dielectric; /* glass and dielectric */
        PlasticLobe plastic;
        LayeredLobe layered; /* coated diffuse and coated conductor */
        DiffuseTransmissionLobe difftrans;
        MeasuredLobe measured;
        HairLobe hair;
    } lobe;
} Bsdf;

/* What a path carries, which decides the adjoint of a non-reciprocal lobe (Veach thesis
 * ch. 5, pbrt-v4 TransportMode): camera paths carry radiance, light paths importance. */
typedef enum BsdfTransport {
    BSDF_RADIANCE,  /* camera paths: wo toward the camera side */
    BSDF_IMPORTANCE /* light paths: wo toward the light side */
} BsdfTransport;

typedef struct BsdfSample {
    Vec3 wi;      /* world space */
    Color weight; /* f * |cos theta_i| / pdf_w, or the delta lobe's weight / pmf */
    /* Non-delta samples: density of wi per unit solid angle; for a BSDF with delta lobes
     * too it includes the probability of not taking them, and equals bsdf_pdf(wo, wi).
     * 0 for delta samples. */
    float pdf_w;
    /* Delta samples: the discrete probability of the lobe taken (glass: F or 1 - F);
     * 0 for non-delta samples. MIS bookkeeping that treats both alike (SmallVCM's
     * "pdf") reads delta ? pmf : pdf_w. */
    float pmf;
    bool delta;
    uint8_t lobe; /* BsdfLobe: which lobe drew wi (explain prints it; renders never read it) */
} BsdfSample;

/* m must outlive b when m is a rough plastic (b points at its coat table). The shading
 * and geometric normals are both n. */
void bsdf_init(Bsdf *b, const Material *m, Vec3 n);
/* A BSDF with shading normal ns (unit, on ng's side) and geometric normal ng (unit), after
 * Veach's thesis sec. 5.3. The lobes work in the frame of ns; a pair (wo, wi) has a value
 * only when the lobe's own test (both in ns's hemisphere for reflection, opposite ones
 * for transmission) and the geometric one (the same with ng) agree, otherwise zero:
 * no light leaks through the surface, at the price of some energy at grazing angles
 * where the two normals disagree. Camera paths (BSDF_RADIANCE) see f_s(wo, wi) |wi.ns|,
 * light paths (BSDF_IMPORTANCE) its adjoint times |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|)
 * (Veach eq. 5.19, pbrt-v3 CorrectShadingNormal), so both transports estimate the same
 * integral with the geometric normals of the measurement (area <-> solid angle). */
void bsdf_init_shading_general(Bsdf *b, const Material *m, Vec3 ns, Vec3 ng);
/* Every field as for a material without a roughness or a coat (Lambert, mirror, smooth
 * glass); bsdf_init_shading_general starts from it and adds those. */
static inline void bsdf_init_smooth(Bsdf *b, const Material *m, Vec3 ns, Vec3 ng)
{
    b->type = m->type;
    b->frame = frame_from_normal(ns);
    b->ng = ng;
    b->shading = ns.x != ng.x || ns.y != ng.y || ns.z != ng.z;
    b->one_sided = m->one_sided;
    switch (m->type) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_MIRROR: b->lobe.diffuse.albedo = m->albedo; break;
    case MATERIAL_GLASS:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC:
        b->lobe.dielectric.tint = m->albedo;
        b->lobe.dielectric.eta = m->ior;
        b->lobe.dielectric.alpha = 0.0f;
        b->lobe.dielectric.alpha_y = 0.0f;
        break;
    case MATERIAL_CONDUCTOR:
        b->lobe.conductor.eta = m->eta;
        b->lobe.conductor.k = m->k;
        b->lobe.conductor.alpha = 0.0f;
        b->lobe.conductor.alpha_y = 0.0f;
        break;
    case MATERIAL_PLASTIC:
        b->lobe.plastic.albedo = m->albedo;
        b->lobe.plastic.eta = m->ior;
        b->lobe.plastic.alpha = 0.0f;
        b->lobe.plastic.coat_e = NULL;
        b->lobe.plastic.coat_e_avg = 0.0f;
        break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR: layered_init(&b->lobe.layered, m); break;
    case MATERIAL_DIFFUSE_TRANSMISSION:
        b->lobe.difftrans.reflectance = m->albedo;
        b->lobe.difftrans.transmittance = m->transmittance;
        break;
    case MATERIAL_MEASURED:
        b->lobe.measured.table = m->measured;
        b->lobe.measured.spectral = false;
        if (!m->measured) { /* no tables (a Material never added to a scene): black */
            b->type = MATERIAL_DIFFUSE;
            b->lobe.diffuse.albedo = color_s(0.0f);
        }
        break;
    case MATERIAL_HAIR: hair_init(&b->lobe.hair, m); break; /* h by scene_bsdf (hair_set_offset) */
    case MATERIAL_MIX: /* resolved by scene_bsdf; black if it ever gets here */
        b->type = MATERIAL_DIFFUSE;
        b->lobe.diffuse.albedo = color_s(0.0f);
        break;
    }
}
/* Inline for those materials: every hit of every path builds one. */
static inline void bsdf_init_shading(Bsdf *b, const Material *m, Vec3 ns, Vec3 ng)
{
    if (m->type == MATERIAL_CONDUCTOR || m->type == MATERIAL_DIELECTRIC || m->type == MATERIAL_PLASTIC ||
        material_is_layered(m->type))
        bsdf_init_shading_general(b, m, ns, ng);
    else
        bsdf_init_smooth(b, m, ns, ng);
}
/* The generalised half vector of Walter et al. 2007 (eq. 16): for reflection
 * m ~ wo + wi, for transmission m ~ -(eta_o wo + eta_i wi), i.e. wo + etap wi with
 * etap = eta_i / eta_o the IOR of wi's side over wo's; oriented to +z. Returns false
 * for configurations no microfacet produces (either direction on the back of m).
 * eta here is the inside (-z) over the outside (+z). */
static inline bool bsdf_dielectric_half(Vec3 wo, Vec3 wi, float eta, Vec3 *m, float *etap, bool *reflect)
{
    float co = wo.z, ci = wi.z;
    if (co == 0.0f || ci == 0.0f) return false;
    *reflect = co * ci > 0.0f;
    *etap = *reflect ? 1.0f : (co > 0.0f ? eta : 1.0f / eta);
    Vec3 h = v3_add(wo, v3_scale(wi, *etap));
    if (v3_length2(h) == 0.0f) return false;
    h = v3_normalize(h);
    if (h.z < 0.0f) h = v3_neg(h);
    if (v3_dot(h, wo) * co <= 0.0f || v3_dot(h, wi) * ci <= 0.0f) return false;
    *m = h;
    return true;
}

/* True when every lobe is a delta lobe: eval and pdf are zero everywhere, NEE is useless. */
static inline bool bsdf_is_delta(const Bsdf *b)
{
    switch (b->type) {
    case MATERIAL_MIRROR:
    case MATERIAL_GLASS:
    case MATERIAL_THIN_DIELECTRIC: return true;
    case MATERIAL_CONDUCTOR: return b->lobe.conductor.alpha == 0.0f;
    case MATERIAL_DIELECTRIC: return b->lobe.dielectric.alpha == 0.0f;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR: return layered_is_delta(&b->lobe.layered);
    default: return false;
    }
}
/* True when some lobe is a delta lobe (all-delta BSDFs, and the smooth-coat plastic, which
 * mixes a delta coat reflection with a diffuse base; so do the coated materials with a
 * smooth interface). */
static inline bool bsdf_has_delta(const Bsdf *b)
{
    return bsdf_is_delta(b) || (b->type == MATERIAL_PLASTIC && b->lobe.plastic.alpha == 0.0f) ||
           (material_is_layered(b->type) && b->lobe.layered.top_alpha == 0.0f);
}
/* True when some lobe transmits (light crosses to the other side of the surface). */
static inline bool bsdf_has_transmission(const Bsdf *b)
{
    return b->type == MATERIAL_GLASS || b->type == MATERIAL_DIELECTRIC || b->type == MATERIAL_THIN_DIELECTRIC ||
           b->type == MATERIAL_DIFFUSE_TRANSMISSION || b->type == MATERIAL_HAIR;
}
/* Texture overrides (scene_bsdf): the reflectance or tint of the lobes that have one (a
 * conductor's colour is its complex IOR: unchanged), and GGX's alpha of the rough-capable
 * lobes (conductor, dielectric, plastic; the others are smooth by definition). */
static inline void bsdf_set_albedo(Bsdf *b, Color albedo)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_MIRROR: b->lobe.diffuse.albedo = albedo; break;
    case MATERIAL_GLASS:
    case MATERIAL_DIELECTRIC:
    case MATERIAL_THIN_DIELECTRIC: b->lobe.dielectric.tint = albedo; break;
    case MATERIAL_DIFFUSE_TRANSMISSION: b->lobe.difftrans.reflectance = albedo; break;
    case MATERIAL_PLASTIC: b->lobe.plastic.albedo = albedo; break;
    case MATERIAL_COATED_DIFFUSE: b->lobe.layered.reflectance = albedo; break;
    case MATERIAL_HAIR: /* a textured colour (the fibre's absorption comes from it) */
        if (b->lobe.hair.from_color) {
            b->lobe.hair.source = albedo;
            b->lobe.hair.sigma_a = hair_sigma_a_from_color(albedo, b->lobe.hair.beta_n);
        }
        break;
    case MATERIAL_CONDUCTOR:
    case MATERIAL_COATED_CONDUCTOR:
    case MATERIAL_MEASURED:
    case MATERIAL_MIX: break;
    }
}
static inline void bsdf_set_alpha(Bsdf *b, float alpha)
{
    switch (b->type) {
    case MATERIAL_CONDUCTOR: b->lobe.conductor.alpha = b->lobe.conductor.alpha_y = alpha; break;
    case MATERIAL_DIELECTRIC: b->lobe.dielectric.alpha = b->lobe.dielectric.alpha_y = alpha; break;
    case MATERIAL_PLASTIC: b->lobe.plastic.alpha = alpha; break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR: /* the interface's */
        b->lobe.layered.top_alpha = b->lobe.layered.top_alpha_y = alpha;
        break;
    default: break;
    }
}
/* A conductor's complex IOR per hit (a textured eta, k): a coated conductor's base takes it
 * divided by the interface's eta, as layered_init does (pbrt-v4 CoatedConductorMaterial). */
static inline void bsdf_set_conductor_ior(Bsdf *b, Color eta, Color k)
{
    if (b->type == MATERIAL_CONDUCTOR) {
        b->lobe.conductor.eta = eta;
        b->lobe.conductor.k = k;
    } else if (b->type == MATERIAL_COATED_CONDUCTOR) {
        float inv = 1.0f / b->lobe.layered.top_eta;
        b->lobe.layered.eta = color_scale(eta, inv);
        b->lobe.layered.k = color_scale(k, inv);
    }
}
/* The two GGX widths of an anisotropic lobe (material_bsdf_alpha2's): ax along the
 * tangent, ay along the bitangent; lobes without anisotropy take ax. */
static inline void bsdf_set_alpha2(Bsdf *b, float ax, float ay)
{
    switch (b->type) {
    case MATERIAL_CONDUCTOR: b->lobe.conductor.alpha = ax, b->lobe.conductor.alpha_y = ay; break;
    case MATERIAL_DIELECTRIC: b->lobe.dielectric.alpha = ax, b->lobe.dielectric.alpha_y = ay; break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR: /* the interface's */
        b->lobe.layered.top_alpha = ax, b->lobe.layered.top_alpha_y = ay;
        break;
    default: bsdf_set_alpha(b, ax); break;
    }
}
/* pbrt-v4's regularization of a GGX width (TrowbridgeReitzDistribution::Regularize, after
 * Kaplanyan & Dachsbacher 2013, "Path space regularization for holistic and robust light
 * transport"): below 0.3, twice the width clamped to [0.1, 0.3]; a smooth lobe (0) so
 * becomes 0.1. */
static inline float bsdf_regularized_alpha(float a) { return a < 0.3f ? fminf(fmaxf(2.0f * a, 0.1f), 0.3f) : a; }
/* pbrt-v4's BSDF::Regularize: the microfacet lobes of conductors, dielectrics (smooth glass
 * becomes a rough dielectric) and the coated materials' interface and conductor base get
 * bsdf_regularized_alpha on both widths; other lobes (Lambert, mirror, thin dielectric,
 * plastic, measured) are left as they are, as pbrt-v4 leaves its own. */
static inline void bsdf_regularize(Bsdf *b)
{
    switch (b->type) {
    case MATERIAL_GLASS:
        b->type = MATERIAL_DIELECTRIC; /* the same lobe, made rough below */
        /* fall through */
    case MATERIAL_DIELECTRIC:
        b->lobe.dielectric.alpha = bsdf_regularized_alpha(b->lobe.dielectric.alpha);
        b->lobe.dielectric.alpha_y = bsdf_regularized_alpha(b->lobe.dielectric.alpha_y);
        break;
    case MATERIAL_CONDUCTOR:
        b->lobe.conductor.alpha = bsdf_regularized_alpha(b->lobe.conductor.alpha);
        b->lobe.conductor.alpha_y = bsdf_regularized_alpha(b->lobe.conductor.alpha_y);
        break;
    case MATERIAL_COATED_CONDUCTOR:
        b->lobe.layered.base_alpha = bsdf_regularized_alpha(b->lobe.layered.base_alpha);
        b->lobe.layered.base_alpha_y = bsdf_regularized_alpha(b->lobe.layered.base_alpha_y);
        /* fall through */
    case MATERIAL_COATED_DIFFUSE:
        b->lobe.layered.top_alpha = bsdf_regularized_alpha(b->lobe.layered.top_alpha);
        b->lobe.layered.top_alpha_y = bsdf_regularized_alpha(b->lobe.layered.top_alpha_y);
        break;
    default: break;
    }
}
/* An anisotropic BSDF's frame: s along the tangent dpdu (world space, any length) made
 * orthogonal to the shading normal (Gram-Schmidt), t = n x s, as pbrt-v4's BSDF frame
 * Frame::FromXZ(shading dpdu, ns); the lobes' alpha lies along s, alpha_y along t.
 * Unchanged when dpdu is (nearly) parallel to the normal or not finite. Isotropic lobes
 * do not depend on the frame's rotation; scene_bsdf calls this for anisotropic ones only,
 * so the others keep frame_from_normal's frame, and their values, bit for bit. */
static inline void bsdf_set_tangent(Bsdf *b, Vec3 dpdu)
{
    Vec3 n = b->frame.n;
    Vec3 s = v3_sub(dpdu, v3_scale(n, v3_dot(n, dpdu)));
    float l2 = v3_length2(s), d2 = v3_length2(dpdu);
    if (!(l2 > 1e-12f * d2) || !isfinite(l2)) return;
    s = v3_scale(s, 1.0f / sqrtf(l2));
    b->frame.s = s;
    b->frame.t = v3_cross(n, s);
}
/* The surface's colour for the albedo AOV: the reflectance or tint; for a conductor, its
 * Fresnel reflectance at normal incidence. */
Color bsdf_albedo(const Bsdf *b);
/* The probability that bsdf_sample takes a delta lobe from wo (0 or 1 except for mixed
 * BSDFs); lets a caller that splits the two parts weight each by its share. */
float bsdf_delta_probability(const Bsdf *b, Vec3 wo);

/* The general cases of the three functions below (every material, shading normals). */
Color bsdf_eval_transport_general(const Bsdf *b, Vec3 wo, Vec3 wi, BsdfTransport mode);
float bsdf_pdf_general(const Bsdf *b, Vec3 wo, Vec3 wi);
Color bsdf_eval_pdfs_general(const Bsdf *b, Vec3 wo, Vec3 wi, float *pdf_fwd, float *pdf_rev);

/* Lambert without a shading normal, the common case of every connection and merge, inline
 * in the callers: the general path's diffuse branches with the two-sided flip folded in
 * (both directions strictly on one side; a one-sided surface only from the front), from
 * the two cosines to the frame's normal alone, the same products bit for bit. */
static inline bool bsdf_is_plain_diffuse(const Bsdf *b) { return !b->shading && b->type == MATERIAL_DIFFUSE; }
static inline Color bsdf_diffuse_eval_pdfs(const Bsdf *b, Vec3 wo, Vec3 wi, float *pdf_fwd, float *pdf_rev)
{
    const float z_o = v3_dot(wo, b->frame.n), z_i = v3_dot(wi, b->frame.n);
    const bool same_side = z_o > 0.0f ? z_i > 0.0f : (z_o < 0.0f && z_i < 0.0f);
    const bool fwd = same_side && (z_o > 0.0f || !b->one_sided);
    const bool rev = same_side && (z_i > 0.0f || !b->one_sided);
    *pdf_fwd = fwd ? fabsf(z_i) * CST_INV_PI : 0.0f;
    *pdf_rev = rev ? fabsf(z_o) * CST_INV_PI : 0.0f;
    return fwd ? color_scale(b->lobe.diffuse.albedo, CST_INV_PI * fabsf(z_i)) : color_s(0.0f);
}

/* bsdf_eval for either transport: BSDF_IMPORTANCE gives the adjoint f*(wo, wi) |cos theta_i|
 * = f(wi, wo) |cos theta_i|, which differs from the radiance BSDF only in refraction
 * (by eta^2) and, with a shading normal, by the factor of bsdf_init_shading. bsdf_eval is
 * the BSDF_RADIANCE case. */
static inline Color bsdf_eval_transport(const Bsdf *b, Vec3 wo, Vec3 wi, BsdfTransport mode)
{
    float pdf_fwd, pdf_rev;
    if (bsdf_is_plain_diffuse(b)) return bsdf_diffuse_eval_pdfs(b, wo, wi, &pdf_fwd, &pdf_rev);
    return bsdf_eval_transport_general(b, wo, wi, mode);
}
static inline Color bsdf_eval(const Bsdf *b, Vec3 wo, Vec3 wi) { return bsdf_eval_transport(b, wo, wi, BSDF_RADIANCE); }
static inline float bsdf_pdf(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    float pdf_fwd, pdf_rev;
    if (!bsdf_is_plain_diffuse(b)) return bsdf_pdf_general(b, wo, wi);
    bsdf_diffuse_eval_pdfs(b, wo, wi, &pdf_fwd, &pdf_rev);
    return pdf_fwd;
}
/* bsdf_eval(b, wo, wi), with bsdf_pdf(b, wo, wi) in *pdf_fwd and bsdf_pdf(b, wi, wo) in
 * *pdf_rev, bit for bit: what the MIS weight of a bidirectional connection needs, for one
 * change of frame instead of three (SmallVCM's BSDF::Evaluate returns the same triple). */
static inline Color bsdf_eval_pdfs(const Bsdf *b, Vec3 wo, Vec3 wi, float *pdf_fwd, float *pdf_rev)
{
    if (bsdf_is_plain_diffuse(b)) return bsdf_diffuse_eval_pdfs(b, wo, wi, pdf_fwd, pdf_rev);
    return bsdf_eval_pdfs_general(b, wo, wi, pdf_fwd, pdf_rev);
}
/* uc picks a lobe (glass: reflect vs refract), u samples a direction. Returns false for
 * no usable sample (e.g. wo exactly in the tangent plane, a microfacet reflection below
 * the surface: that energy is lost, the single-scattering loss of microfacet models).
 * On false, out->delta is true when the failed sample came from a delta lobe (e.g. a
 * mirror direction about a shading normal that points under the surface, refused), and
 * otherwise false or untouched: a caller splitting a mixed BSDF by lobe sets it to false
 * first and so learns which lobe failed.
 * For camera paths. */
bool bsdf_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfSample *out);
/* The same for either transport: the weight is f(wo, wi) |cos theta_i| / pdf for
 * BSDF_RADIANCE and the adjoint f*(wo, wi) |cos theta_i| / pdf = f(wi, wo) |cos theta_i| / pdf
 * for BSDF_IMPORTANCE. They differ only in refraction, by the factor 1/eta^2, and with a
 * shading normal by the adjoint correction (bsdf_init_shading). */
bool bsdf_sample_transport_general(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfTransport mode,
                                   BsdfSample *out);
static inline bool bsdf_sample_transport(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfTransport mode,
                                         BsdfSample *out)
{
    if (!bsdf_is_plain_diffuse(b)) return bsdf_sample_transport_general(b, wo, uc, u, mode, out);
    /* The general path's diffuse case, inline: cosine-weighted about the side wo is on
     * (none behind a one-sided surface), weight = albedo. */
    const float z_o = v3_dot(wo, b->frame.n);
    if (z_o == 0.0f || (z_o < 0.0f && b->one_sided)) return false;
    Vec3 wi = warp_cosine_hemisphere(u);
    out->wi = wi;
    out->pdf_w = wi.z * CST_INV_PI;
    out->pmf = 0.0f;
    out->weight = b->lobe.diffuse.albedo;
    out->delta = false;
    out->lobe = BSDF_LOBE_DIFFUSE_REFLECTION;
    if (!(wi.z > 0.0f) || !(out->pdf_w > 0.0f) || !color_is_finite(out->weight)) return false;
    if (z_o < 0.0f) wi.z = -wi.z;
    out->wi = frame_to_world(&b->frame, wi);
    return true;
}
/* The factor by which importance transport differs from radiance transport with a shading
 * normal, |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|) (Veach thesis eq. 5.19); 1 when ns = ng, 0
 * when wo or wi lies in a tangent plane. */
float bsdf_shading_adjoint(const Bsdf *b, Vec3 wo, Vec3 wi);

#endif
