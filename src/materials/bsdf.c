/* BSDF lobes: Lambert, perfect mirror, smooth and rough conductor, smooth and rough
 * dielectric, plastic (a dielectric coat over Lambert); the coated materials' random walk
 * is layered.c's. Everything below works in the local
 * shading frame (normal +z); the public wrappers at the end convert and reject degenerate
 * samples in one place. Microfacet lobes use GGX with height-correlated Smith G2 and
 * visible-normal sampling (microfacet.h). */
#include "materials/bsdf.h"

#include <stddef.h>

#include "materials/measured.h"
#include "materials/microfacet.h"
#include "sampling/warp.h"

void bsdf_init(Bsdf *b, const Material *m, Vec3 n) { bsdf_init_shading(b, m, n, n); }

Color bsdf_albedo(const Bsdf *b)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
    case MATERIAL_MIRROR: return b->lobe.diffuse.albedo;
    case MATERIAL_GLASS:
    case MATERIAL_DIELECTRIC: return b->lobe.dielectric.tint;
    case MATERIAL_PLASTIC: return b->lobe.plastic.albedo;
    case MATERIAL_CONDUCTOR: return fresnel_conductor_rgb(1.0f, b->lobe.conductor.eta, b->lobe.conductor.k);
    case MATERIAL_COATED_DIFFUSE: return b->lobe.layered.reflectance;
    case MATERIAL_COATED_CONDUCTOR: return fresnel_conductor_rgb(1.0f, b->lobe.layered.eta, b->lobe.layered.k);
    case MATERIAL_DIFFUSE_TRANSMISSION: return b->lobe.difftrans.reflectance;
    case MATERIAL_THIN_DIELECTRIC: return b->lobe.dielectric.tint;
    case MATERIAL_MEASURED: return b->lobe.measured.table->albedo;
    case MATERIAL_HAIR: { /* its colour, or the transmittance across one diameter */
        if (b->lobe.hair.from_color) return b->lobe.hair.source;
        Color t;
        for (int i = 0; i < COLOR_LANES; i++) t.c[i] = expf(-2.0f * b->lobe.hair.sigma_a.c[i]);
        return t;
    }
    case MATERIAL_MIX: break;
    }
    return color_s(0.0f);
}

void bsdf_init_shading_general(Bsdf *b, const Material *m, Vec3 ns, Vec3 ng)
{
    bsdf_init_smooth(b, m, ns, ng);
    float ax, ay; /* layered_init has set the coated materials' widths */
    material_bsdf_alpha2(m->roughness, m->anisotropic ? m->roughness_v : m->roughness, &ax, &ay);
    if (m->type == MATERIAL_CONDUCTOR) {
        b->lobe.conductor.alpha = ax;
        b->lobe.conductor.alpha_y = ay;
    } else if (m->type == MATERIAL_DIELECTRIC) {
        b->lobe.dielectric.alpha = ax;
        b->lobe.dielectric.alpha_y = ay;
    } else if (m->type == MATERIAL_PLASTIC) {
        b->lobe.plastic.alpha = ax; /* isotropic: its coat table is made for one roughness */
    }
    if (m->type == MATERIAL_PLASTIC) {
        PlasticLobe *pl = &b->lobe.plastic;
        if (pl->alpha > 0.0f && m->prepared) {
            pl->coat_e = m->coat_e;
            pl->coat_e_avg = m->coat_e_avg;
        } else {
            /* Smooth coat (or an unprepared rough one, approximated by it): E = F. */
            pl->coat_e_avg = fresnel_diffuse_reflectance(m->ior);
        }
    }
}

/* ------------------------------------------------------------------ shared helpers */

/* Reflective BSDFs see the world from +z: a two-sided one mirrors a back-side query to the
 * front (both directions flip, which keeps reciprocity), a one-sided one is black behind.
 * Returns false when the query has no value. wi may be NULL (sampling). */
static bool reflect_side(const Bsdf *b, Vec3 *wo, Vec3 *wi)
{
    if (wo->z >= 0.0f) return true;
    if (b->one_sided) return false;
    wo->z = -wo->z;
    if (wi) wi->z = -wi->z;
    return true;
}

static inline Vec3 mirror_z(Vec3 w) { return v3(-w.x, -w.y, w.z); }

/* ------------------------------------------------------------------ rough conductor */

/* Torrance-Sparrow / Cook-Torrance reflection with GGX (Walter et al. 2007 eq. 20):
 *   f(wo, wi) = F(wo.m) D(m) G2(wo, wi) / (4 cos_o cos_i),  m = normalize(wo + wi). */
static Color conductor_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return color_s(0.0f);
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return color_s(0.0f);
    Vec3 m = v3_normalize(h);
    const float ax = b->lobe.conductor.alpha, ay = b->lobe.conductor.alpha_y;
    float s = ggx_d(m, ax, ay) * ggx_g2(wo, wi, ax, ay) / (4.0f * wo.z);
    return color_scale(fresnel_conductor_rgb(v3_dot(wo, m), b->lobe.conductor.eta, b->lobe.conductor.k), s);
}

/* Visible-normal sampling then reflection: pdf = D_wo(m) / (4 wo.m) (the reflection
 * Jacobian, Walter 2007 eq. 14) = G1(wo) D(m) / (4 cos_o). */
static float microfacet_reflect_pdf(Vec3 wo, Vec3 wi, float ax, float ay)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return 0.0f;
    Vec3 m = v3_normalize(h);
    return ggx_g1(wo, ax, ay) * ggx_d(m, ax, ay) / (4.0f * wo.z);
}

static bool conductor_sample(const Bsdf *b, Vec3 wo, Vec2 u, BsdfSample *out)
{
    if (b->lobe.conductor.alpha == 0.0f) {
        out->wi = mirror_z(wo);
        out->pmf = 1.0f;
        out->pdf_w = 0.0f;
        out->weight = fresnel_conductor_rgb(wo.z, b->lobe.conductor.eta, b->lobe.conductor.k);
        out->delta = true;
        out->lobe = BSDF_LOBE_SPECULAR_REFLECTION;
        return true;
    }
    Vec3 m = ggx_sample_visible(wo, b->lobe.conductor.alpha, b->lobe.conductor.alpha_y, u);
    Vec3 wi = reflect_about(wo, m);
    if (wi.z <= 0.0f) return false; /* reflected into the surface: lost (single scattering) */
    out->wi = wi;
    out->pdf_w = microfacet_reflect_pdf(wo, wi, b->lobe.conductor.alpha, b->lobe.conductor.alpha_y);
    out->pmf = 0.0f;
    /* f cos_i / pdf = F G2 / G1(wo): D and the Jacobian cancel. */
    const float ax = b->lobe.conductor.alpha, ay = b->lobe.conductor.alpha_y;
    float g = ggx_g2(wo, wi, ax, ay) / ggx_g1(wo, ax, ay);
    out->weight = color_scale(fresnel_conductor_rgb(v3_dot(wo, m), b->lobe.conductor.eta, b->lobe.conductor.k), g);
    out->delta = false;
    out->lobe = BSDF_LOBE_GLOSSY_REFLECTION;
    return true;
}

/* ------------------------------------------------------------------ rough dielectric */


/* F at the microfacet. For refraction, from the outside direction's cosine: F(cos_o, eta)
 * and F(cos_t, 1/eta) are equal in exact arithmetic, but the inside cosine is near the
 * critical angle where 1 - F is ill-conditioned, and one formula for both orders keeps
 * f(wo, wi) and f(wi, wo) (the adjoint) consistent to rounding. */
static float dielectric_fresnel(const Bsdf *b, Vec3 wo, Vec3 wi, Vec3 m, bool reflect)
{
    Vec3 w = reflect || wo.z > 0.0f ? wo : wi;
    return fresnel_dielectric(v3_dot(w, m), b->lobe.dielectric.eta);
}

/* Walter et al. 2007 eq. 20 (reflection) and eq. 21 (transmission), with eta_o and eta_i
 * divided out: f_t = |wi.m| |wo.m| (1 - F) D G2 / (|cos_i| |cos_o| (wi.m + wo.m / etap)^2)
 * / etap^2. The 1 / etap^2 is radiance compression: it belongs to the radiance BSDF;
 * the adjoint f*(wo, wi) = f(wi, wo) lacks it (Veach thesis sec. 5.2; swapping wo and wi
 * in the formula above shows it). Returns f |cos_i|. */
static float dielectric_eval(const Bsdf *b, Vec3 wo, Vec3 wi, BsdfTransport mode)
{
    Vec3 m;
    float etap;
    bool reflect;
    if (!bsdf_dielectric_half(wo, wi, b->lobe.dielectric.eta, &m, &etap, &reflect)) return 0.0f;
    const float ax = b->lobe.dielectric.alpha, ay = b->lobe.dielectric.alpha_y;
    float dm = ggx_d(m, ax, ay) * ggx_g2(wo, wi, ax, ay);
    float F = dielectric_fresnel(b, wo, wi, m, reflect);
    if (reflect) return F * dm / (4.0f * fabsf(wo.z));
    float denom = sqrf(v3_dot(wi, m) + v3_dot(wo, m) / etap);
    float f = (1.0f - F) * dm * fabsf(v3_dot(wi, m) * v3_dot(wo, m) / (wo.z * denom));
    return mode == BSDF_RADIANCE ? f / (etap * etap) : f;
}

/* Lobe chosen with probability F(wo.m) / (1 - F(wo.m)) after sampling m from the visible
 * normals of |wo|; pdf = D_wo(m) * (F / (4 |wo.m|) or (1 - F) |wi.m| / (wi.m + wo.m/etap)^2)
 * (the refraction Jacobian, Walter 2007 eq. 17). */
static float dielectric_pdf(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    Vec3 m;
    float etap;
    bool reflect;
    if (!bsdf_dielectric_half(wo, wi, b->lobe.dielectric.eta, &m, &etap, &reflect)) return 0.0f;
    float pm = ggx_visible_pdf(wo, m, b->lobe.dielectric.alpha, b->lobe.dielectric.alpha_y);
    float F = dielectric_fresnel(b, wo, wi, m, reflect);
    if (reflect) return F * pm / (4.0f * fabsf(v3_dot(wo, m)));
    float denom = sqrf(v3_dot(wi, m) + v3_dot(wo, m) / etap);
    return (1.0f - F) * pm * fabsf(v3_dot(wi, m)) / denom;
}

static bool dielectric_smooth_sample(const Bsdf *b, Vec3 wo, float uc, BsdfTransport mode, BsdfSample *out)
{
    float f = fresnel_dielectric(wo.z, b->lobe.dielectric.eta);
    out->delta = true;
    if (uc < f) {
        out->wi = mirror_z(wo);
        out->pmf = f;
        out->pdf_w = 0.0f;
        out->weight = b->lobe.dielectric.tint; /* (F / |cos|) |cos| / F */
        out->lobe = BSDF_LOBE_SPECULAR_REFLECTION;
        return true;
    }
    /* Refraction by Snell's law about the macro normal. */
    Vec3 wt;
    float etap;
    if (!refract_about(wo, v3(0.0f, 0.0f, 1.0f), b->lobe.dielectric.eta, &wt, &etap)) return false; /* f == 1 under TIR */
    out->wi = v3_normalize(wt);
    out->pmf = 1.0f - f;
    out->lobe = BSDF_LOBE_SPECULAR_TRANSMISSION;
    out->pdf_w = 0.0f;
    /* Radiance is compressed by 1/etap^2 entering a denser medium (Veach thesis sec. 5.2,
     * pbrt-v4 sec. 9.5.2); camera paths carry radiance, so the factor applies to them.
     * Light paths carry flux, which refraction does not compress: the adjoint BTDF lacks
     * the factor (pbrt-v4 DielectricBxDF with TransportMode::Importance). */
    out->weight = mode == BSDF_RADIANCE ? color_scale(b->lobe.dielectric.tint, 1.0f / (etap * etap)) : b->lobe.dielectric.tint;
    return true;
}

static bool dielectric_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfTransport mode, BsdfSample *out)
{
    if (b->lobe.dielectric.alpha == 0.0f) return dielectric_smooth_sample(b, wo, uc, mode, out);
    /* Visible normals of the side wo is on (the distribution is symmetric under z -> -z). */
    Vec3 m = ggx_sample_visible(wo.z > 0.0f ? wo : v3_neg(wo), b->lobe.dielectric.alpha, b->lobe.dielectric.alpha_y, u);
    float F = fresnel_dielectric(v3_dot(wo, m), b->lobe.dielectric.eta);
    Vec3 wi;
    float extra = 1.0f;
    if (uc < F) {
        wi = reflect_about(wo, m);
        if (wi.z * wo.z <= 0.0f) return false; /* lost: single scattering */
    } else {
        float etap;
        if (!refract_about(wo, m, b->lobe.dielectric.eta, &wi, &etap)) return false; /* F == 1 there: unreachable */
        wi = v3_normalize(wi);
        if (wi.z * wo.z >= 0.0f) return false; /* stays on wo's side: lost */
        if (mode == BSDF_RADIANCE) extra = 1.0f / (etap * etap);
    }
    out->wi = wi;
    out->pdf_w = dielectric_pdf(b, wo, wi);
    out->pmf = 0.0f;
    out->delta = false;
    out->lobe = uc < F ? BSDF_LOBE_GLOSSY_REFLECTION : BSDF_LOBE_GLOSSY_TRANSMISSION;
    /* f |cos_i| / pdf = G2 / G1(wo) for both lobes (D, F and the Jacobians cancel), times
     * 1 / etap^2 for radiance through refraction. */
    const float ax = b->lobe.dielectric.alpha, ay = b->lobe.dielectric.alpha_y;
    float g = ggx_g2(wo, wi, ax, ay) / ggx_g1(wo, ax, ay);
    out->weight = color_scale(b->lobe.dielectric.tint, g * extra);
    return true;
}

/* ------------------------------------------------------------------ plastic
 * A dielectric coat (IOR eta, smooth or GGX-rough) over a Lambertian base of albedo rho,
 * after Kelemen & Szirmay-Kalos 2001 ("A Microfacet Based Coupled Specular-Matte BRDF
 * Model with Importance Sampling"):
 *   f = f_coat(wo, wi) + rho (1 - E(cos_o)) (1 - E(cos_i)) / (pi (1 - E_avg)),
 * f_coat the coat's reflection (a delta mirror lobe weighted by F when smooth, the rough
 * dielectric's reflection lobe when rough), E(mu) its directional albedo (F(mu) when
 * smooth; tabulated by material_prepare when rough) and E_avg = 2 int E(mu) mu dmu.
 * Energy: the directional albedo is E(cos_o) + rho (1 - E(cos_o)) <= 1 by construction,
 * exactly 1 for rho = 1 (up to the table's interpolation error when rough). Reciprocal.
 * The approximation: light refracted through the coat is treated as one diffuse bounce
 * whose angular shape is (1 - E) on both sides; the internal reflections between coat
 * and base that would saturate colours (rho^2, rho^3 ... terms) are folded into the
 * normalisation instead of modelled, and the layer does not absorb. */

static float coat_albedo(const Bsdf *b, float mu)
{
    if (!b->lobe.plastic.coat_e) return fresnel_dielectric(mu, b->lobe.plastic.eta);
    /* linear in x = sqrt(mu), the table's abscissa (material_prepare) */
    float x = sqrtf(clampf(mu, 0.0f, 1.0f)) * (float)(MATERIAL_COAT_TABLE - 1);
    int i = (int)x;
    if (i > MATERIAL_COAT_TABLE - 2) i = MATERIAL_COAT_TABLE - 2;
    float t = x - (float)i;
    return b->lobe.plastic.coat_e[i] + t * (b->lobe.plastic.coat_e[i + 1] - b->lobe.plastic.coat_e[i]);
}

/* Probability of sampling the coat: its share of the expected reflected energy. */
static float plastic_coat_prob(const Bsdf *b, float cos_o)
{
    float e = coat_albedo(b, cos_o);
    float d = e + color_max(b->lobe.plastic.albedo) * (1.0f - e);
    return d > 0.0f ? e / d : 1.0f;
}

static Color plastic_diffuse_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    float s = (1.0f - coat_albedo(b, wo.z)) * (1.0f - coat_albedo(b, wi.z)) /
              (CST_PI * (1.0f - b->lobe.plastic.coat_e_avg));
    return color_scale(b->lobe.plastic.albedo, s * wi.z);
}

/* The coat's rough reflection (f |cos_i|), the rough dielectric's reflection lobe. */
static float plastic_coat_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return 0.0f;
    Vec3 m = v3_normalize(h);
    return fresnel_dielectric(v3_dot(wo, m), b->lobe.plastic.eta) * ggx_d(m, b->lobe.plastic.alpha, b->lobe.plastic.alpha) *
           ggx_g2(wo, wi, b->lobe.plastic.alpha, b->lobe.plastic.alpha) /
           (4.0f * wo.z);
}

/* Non-delta part only: the diffuse base, and the coat when rough. */
static Color plastic_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return color_s(0.0f);
    Color f = plastic_diffuse_eval(b, wo, wi);
    if (b->lobe.plastic.alpha > 0.0f) f = color_add(f, color_s(plastic_coat_eval(b, wo, wi)));
    return f;
}

static float plastic_pdf(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (wo.z <= 0.0f || wi.z <= 0.0f) return 0.0f;
    float pc = plastic_coat_prob(b, wo.z);
    float p = (1.0f - pc) * wi.z * CST_INV_PI;
    if (b->lobe.plastic.alpha > 0.0f) p += pc * microfacet_reflect_pdf(wo, wi, b->lobe.plastic.alpha, b->lobe.plastic.alpha);
    return p;
}

static bool plastic_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfSample *out)
{
    float pc = plastic_coat_prob(b, wo.z);
    Vec3 wi;
    if (uc < pc) {
        if (b->lobe.plastic.alpha == 0.0f) {
            out->wi = mirror_z(wo);
            out->pmf = pc;
            out->pdf_w = 0.0f;
            out->weight = color_s(fresnel_dielectric(wo.z, b->lobe.plastic.eta) / pc);
            out->delta = true;
            out->lobe = BSDF_LOBE_COAT_SPECULAR_REFLECTION;
            return true;
        }
        wi = reflect_about(wo, ggx_sample_visible(wo, b->lobe.plastic.alpha, b->lobe.plastic.alpha, u));
        if (wi.z <= 0.0f) return false;
    } else {
        wi = warp_cosine_hemisphere(u);
        if (wi.z <= 0.0f) return false;
    }
    /* One-sample MIS over the lobes (the mixture pdf), so the weight is f / pdf of the
     * whole non-delta part whichever lobe drew wi. */
    out->wi = wi;
    out->pdf_w = plastic_pdf(b, wo, wi);
    out->pmf = 0.0f;
    out->weight = color_scale(plastic_eval(b, wo, wi), 1.0f / out->pdf_w);
    out->delta = false;
    /* the lobe that drew wi; the weight is the mixture's (one-sample MIS) all the same */
    out->lobe = uc < pc ? BSDF_LOBE_COAT_GLOSSY_REFLECTION : BSDF_LOBE_BASE_DIFFUSE_REFLECTION;
    return true;
}

/* ------------------------------------------------------------------ diffuse transmission
 * pbrt-v4 DiffuseTransmissionBxDF: f = R / pi for wi on wo's side, T / pi on the other;
 * the side picked with probability max(R) : max(T), then cosine-weighted. Reciprocal,
 * and without a radiance scaling (no refraction). */

static void difftrans_probs(const Bsdf *b, float *pr, float *pt)
{
    *pr = color_max(b->lobe.difftrans.reflectance);
    *pt = color_max(b->lobe.difftrans.transmittance);
}

static Color difftrans_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (wo.z == 0.0f || wi.z == 0.0f) return color_s(0.0f);
    Color c = wo.z * wi.z > 0.0f ? b->lobe.difftrans.reflectance : b->lobe.difftrans.transmittance;
    return color_scale(c, CST_INV_PI * fabsf(wi.z));
}

static float difftrans_pdf(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    float pr, pt;
    difftrans_probs(b, &pr, &pt);
    if (wo.z == 0.0f || wi.z == 0.0f || !(pr + pt > 0.0f)) return 0.0f;
    return (wo.z * wi.z > 0.0f ? pr : pt) / (pr + pt) * fabsf(wi.z) * CST_INV_PI;
}

static bool difftrans_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfSample *out)
{
    float pr, pt;
    difftrans_probs(b, &pr, &pt);
    if (!(pr + pt > 0.0f)) return false;
    Vec3 wi = warp_cosine_hemisphere(u);
    const bool reflect = uc < pr / (pr + pt);
    if ((wo.z > 0.0f) != reflect) wi.z = -wi.z; /* reflection: wo's side; else the other */
    float p = (reflect ? pr : pt) / (pr + pt);
    out->wi = wi;
    out->pdf_w = p * fabsf(wi.z) * CST_INV_PI;
    out->pmf = 0.0f;
    out->weight = color_scale(reflect ? b->lobe.difftrans.reflectance : b->lobe.difftrans.transmittance, 1.0f / p);
    out->delta = false;
    out->lobe = reflect ? BSDF_LOBE_DIFFUSE_REFLECTION : BSDF_LOBE_DIFFUSE_TRANSMISSION;
    return wi.z != 0.0f;
}

/* ------------------------------------------------------------------ thin dielectric
 * pbrt-v4 ThinDielectricBxDF: a slab thin enough that light leaves where it entered. Per
 * interface R0 = F(|cos|, eta), T0 = 1 - R0; the internal reflections sum to
 * R = R0 + T0^2 R0 / (1 - R0^2), T = 1 - R (pbrt-v4 book eq. 14.4). Reflection is the
 * mirror direction, transmission -wo (undeviated, no radiance scaling: the two
 * refractions cancel). Both lobes are delta lobes. */
static bool thin_dielectric_sample(const Bsdf *b, Vec3 wo, float uc, BsdfSample *out)
{
    float R = fresnel_dielectric(fabsf(wo.z), b->lobe.dielectric.eta), T = 1.0f - R;
    if (R < 1.0f) {
        R += T * T * R / (1.0f - R * R);
        T = 1.0f - R;
    }
    out->delta = true;
    out->pdf_w = 0.0f;
    out->weight = b->lobe.dielectric.tint; /* (R / |cos|) |cos| / R, and the same for T */
    if (uc < R) {
        out->wi = mirror_z(wo);
        out->pmf = R;
        out->lobe = BSDF_LOBE_SPECULAR_REFLECTION;
    } else {
        out->wi = v3_neg(wo);
        out->pmf = T;
        out->lobe = BSDF_LOBE_SPECULAR_TRANSMISSION;
    }
    return true;
}

/* ------------------------------------------------------------------ coated (layered.c) */

/* A walk's sample as a BsdfSample. Its weight is the walk's own f |cos| / pdf, an unbiased
 * estimate; the density a non-delta sample reports is layered_pdf's estimate instead of
 * the walk's (as pbrt-v4's integrators use BSDF::PDF when pdfIsProportional), so that MIS
 * weights computed from the sample and from bsdf_pdf at the same hit agree exactly. */
static bool layered_bsdf_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfTransport mode, BsdfSample *out)
{
    LayeredSample ls;
    if (!layered_sample(&b->lobe.layered, wo, uc, u, mode == BSDF_IMPORTANCE, &ls)) return false;
    out->wi = ls.wi;
    out->weight = ls.weight;
    out->delta = ls.delta;
    out->lobe = ls.lobe;
    out->pmf = ls.delta ? ls.pdf : 0.0f;
    out->pdf_w = ls.delta ? 0.0f : layered_pdf(&b->lobe.layered, wo, ls.wi);
    return true;
}

float bsdf_delta_probability(const Bsdf *b, Vec3 wo_world)
{
    if (bsdf_is_delta(b)) return 1.0f;
    if (!bsdf_has_delta(b)) return 0.0f;
    Vec3 wo = frame_to_local(&b->frame, wo_world);
    if (!reflect_side(b, &wo, NULL)) return 0.0f;
    if (material_is_layered(b->type)) return layered_delta_probability(&b->lobe.layered, wo.z);
    return plastic_coat_prob(b, wo.z);
}

/* ------------------------------------------------------------------ shading normals
 * (Veach thesis sec. 5.3; the convention is bsdf_init_shading's.) */

/* Whether the geometric normal allows the pair the shading frame sees: both tests must say
 * reflection (same side), or both transmission. ng_o, ng_i: wo.ng, wi.ng; z_o, z_i: the
 * local (shading) cosines. A one-sided reflector is black from ng's back. */
static inline bool shading_allows(const Bsdf *b, float ng_o, float ng_i, float z_o, float z_i)
{
    if (ng_o == 0.0f || ng_i == 0.0f) return false;
    if (b->one_sided && ng_o < 0.0f && !bsdf_has_transmission(b)) return false;
    return (ng_o * ng_i > 0.0f) == (z_o * z_i > 0.0f);
}

/* Veach eq. 5.19 from the cosines: |wo.ns| |wi.ng| / (|wo.ng| |wi.ns|). */
static inline float shading_adjoint(float ng_o, float ng_i, float z_o, float z_i)
{
    float den = fabsf(ng_o * z_i);
    return den > 0.0f ? fabsf(z_o * ng_i) / den : 0.0f;
}

float bsdf_shading_adjoint(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    return shading_adjoint(v3_dot(wo, b->ng), v3_dot(wi, b->ng), v3_dot(wo, b->frame.n), v3_dot(wi, b->frame.n));
}

/* ------------------------------------------------------------------ public wrappers */

static Color eval_local(const Bsdf *b, Vec3 wo, Vec3 wi, BsdfTransport mode)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
        /* Lambert reflects on whichever side wo is (unless one-sided). */
        if (!reflect_side(b, &wo, &wi) || wo.z == 0.0f || wi.z <= 0.0f) return color_s(0.0f);
        return color_scale(b->lobe.diffuse.albedo, CST_INV_PI * wi.z);
    case MATERIAL_CONDUCTOR:
        if (b->lobe.conductor.alpha == 0.0f || !reflect_side(b, &wo, &wi)) return color_s(0.0f);
        return conductor_eval(b, wo, wi);
    case MATERIAL_DIELECTRIC:
        if (b->lobe.dielectric.alpha == 0.0f) return color_s(0.0f);
        return color_scale(b->lobe.dielectric.tint, dielectric_eval(b, wo, wi, mode));
    case MATERIAL_PLASTIC:
        if (!reflect_side(b, &wo, &wi)) return color_s(0.0f);
        return plastic_eval(b, wo, wi);
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        if (bsdf_is_delta(b) || !reflect_side(b, &wo, &wi)) return color_s(0.0f);
        return layered_eval(&b->lobe.layered, wo, wi, mode == BSDF_IMPORTANCE);
    case MATERIAL_DIFFUSE_TRANSMISSION: return difftrans_eval(b, wo, wi);
    case MATERIAL_MEASURED:
        if (!reflect_side(b, &wo, &wi)) return color_s(0.0f);
        return measured_eval(b->lobe.measured.table, wo, wi, b->lobe.measured.spectral ? b->lobe.measured.lambda : NULL);
    case MATERIAL_HAIR:
        return mode == BSDF_RADIANCE ? hair_eval(&b->lobe.hair, wo, wi) : hair_eval_adjoint(&b->lobe.hair, wo, wi);
    case MATERIAL_MIRROR:
    case MATERIAL_GLASS:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MIX: break;
    }
    return color_s(0.0f);
}

Color bsdf_eval_transport_general(const Bsdf *b, Vec3 wo_world, Vec3 wi_world, BsdfTransport mode)
{
    Vec3 wo = frame_to_local(&b->frame, wo_world), wi = frame_to_local(&b->frame, wi_world);
    if (!b->shading) return eval_local(b, wo, wi, mode);
    float ng_o = v3_dot(wo_world, b->ng), ng_i = v3_dot(wi_world, b->ng);
    if (!shading_allows(b, ng_o, ng_i, wo.z, wi.z)) return color_s(0.0f);
    Color f = eval_local(b, wo, wi, mode);
    return mode == BSDF_RADIANCE ? f : color_scale(f, shading_adjoint(ng_o, ng_i, wo.z, wi.z));
}

static float pdf_local(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    switch (b->type) {
    case MATERIAL_DIFFUSE:
        if (!reflect_side(b, &wo, &wi) || wo.z == 0.0f || wi.z <= 0.0f) return 0.0f;
        return wi.z * CST_INV_PI;
    case MATERIAL_CONDUCTOR:
        if (b->lobe.conductor.alpha == 0.0f || !reflect_side(b, &wo, &wi)) return 0.0f;
        return microfacet_reflect_pdf(wo, wi, b->lobe.conductor.alpha, b->lobe.conductor.alpha_y);
    case MATERIAL_DIELECTRIC:
        if (b->lobe.dielectric.alpha == 0.0f) return 0.0f;
        return dielectric_pdf(b, wo, wi);
    case MATERIAL_PLASTIC:
        if (!reflect_side(b, &wo, &wi)) return 0.0f;
        return plastic_pdf(b, wo, wi);
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        if (bsdf_is_delta(b) || !reflect_side(b, &wo, &wi)) return 0.0f;
        return layered_pdf(&b->lobe.layered, wo, wi);
    case MATERIAL_DIFFUSE_TRANSMISSION: return difftrans_pdf(b, wo, wi);
    case MATERIAL_MEASURED:
        if (!reflect_side(b, &wo, &wi)) return 0.0f;
        return measured_pdf(b->lobe.measured.table, wo, wi);
    case MATERIAL_HAIR: return hair_pdf(&b->lobe.hair, wo, wi);
    case MATERIAL_MIRROR:
    case MATERIAL_GLASS:
    case MATERIAL_THIN_DIELECTRIC:
    case MATERIAL_MIX: break;
    }
    return 0.0f;
}

/* The density of the directions bsdf_sample returns: with a shading normal it rejects
 * the pairs shading_allows refuses, so they have density zero. */
float bsdf_pdf_general(const Bsdf *b, Vec3 wo_world, Vec3 wi_world)
{
    Vec3 wo = frame_to_local(&b->frame, wo_world), wi = frame_to_local(&b->frame, wi_world);
    if (b->shading && !shading_allows(b, v3_dot(wo_world, b->ng), v3_dot(wi_world, b->ng), wo.z, wi.z))
        return 0.0f;
    return pdf_local(b, wo, wi);
}

Color bsdf_eval_pdfs_general(const Bsdf *b, Vec3 wo_world, Vec3 wi_world, float *pdf_fwd, float *pdf_rev)
{
    Vec3 wo = frame_to_local(&b->frame, wo_world), wi = frame_to_local(&b->frame, wi_world);
    if (!b->shading) {
        *pdf_fwd = pdf_local(b, wo, wi);
        *pdf_rev = pdf_local(b, wi, wo);
        return eval_local(b, wo, wi, BSDF_RADIANCE);
    }
    float ng_o = v3_dot(wo_world, b->ng), ng_i = v3_dot(wi_world, b->ng);
    bool fwd = shading_allows(b, ng_o, ng_i, wo.z, wi.z);
    *pdf_fwd = fwd ? pdf_local(b, wo, wi) : 0.0f;
    *pdf_rev = shading_allows(b, ng_i, ng_o, wi.z, wo.z) ? pdf_local(b, wi, wo) : 0.0f;
    return fwd ? eval_local(b, wo, wi, BSDF_RADIANCE) : color_s(0.0f);
}

bool bsdf_sample(const Bsdf *b, Vec3 wo_world, float uc, Vec2 u, BsdfSample *out)
{
    return bsdf_sample_transport(b, wo_world, uc, u, BSDF_RADIANCE, out);
}

bool bsdf_sample_transport_general(const Bsdf *b, Vec3 wo_world, float uc, Vec2 u, BsdfTransport mode,
                                   BsdfSample *out)
{
    Vec3 wo = frame_to_local(&b->frame, wo_world);
    if (wo.z == 0.0f) return false;
    const float z_o = wo.z; /* before the reflective types flip it */
    bool flipped = false; /* reflective types sample from +z and flip back */
    bool ok = false;
    switch (b->type) {
    case MATERIAL_DIFFUSE:
        if ((flipped = wo.z < 0.0f) && b->one_sided) return false;
        out->wi = warp_cosine_hemisphere(u);
        out->pdf_w = out->wi.z * CST_INV_PI;
        out->pmf = 0.0f;
        out->weight = b->lobe.diffuse.albedo; /* (albedo/pi) |cos| / (|cos|/pi) */
        out->delta = false;
        out->lobe = BSDF_LOBE_DIFFUSE_REFLECTION;
        ok = out->wi.z > 0.0f;
        break;
    case MATERIAL_MIRROR:
        /* Mirrors reflect on both sides unless one-sided. */
        if (wo.z < 0.0f && b->one_sided) return false;
        out->wi = mirror_z(wo);
        out->pmf = 1.0f;
        out->pdf_w = 0.0f;
        out->weight = b->lobe.diffuse.albedo;
        out->delta = true;
        out->lobe = BSDF_LOBE_SPECULAR_REFLECTION;
        ok = true;
        break;
    case MATERIAL_CONDUCTOR:
        if ((flipped = wo.z < 0.0f) && b->one_sided) return false;
        if (flipped) wo.z = -wo.z;
        ok = conductor_sample(b, wo, u, out);
        break;
    case MATERIAL_GLASS:
        ok = dielectric_smooth_sample(b, wo, uc, mode, out);
        break;
    case MATERIAL_DIELECTRIC:
        ok = dielectric_sample(b, wo, uc, u, mode, out);
        break;
    case MATERIAL_PLASTIC:
        if ((flipped = wo.z < 0.0f) && b->one_sided) return false;
        if (flipped) wo.z = -wo.z;
        ok = plastic_sample(b, wo, uc, u, out);
        break;
    case MATERIAL_COATED_DIFFUSE:
    case MATERIAL_COATED_CONDUCTOR:
        if ((flipped = wo.z < 0.0f) && b->one_sided) return false;
        if (flipped) wo.z = -wo.z;
        ok = layered_bsdf_sample(b, wo, uc, u, mode, out);
        break;
    case MATERIAL_DIFFUSE_TRANSMISSION:
        ok = difftrans_sample(b, wo, uc, u, out);
        break;
    case MATERIAL_THIN_DIELECTRIC:
        ok = thin_dielectric_sample(b, wo, uc, out);
        break;
    case MATERIAL_MEASURED:
        if ((flipped = wo.z < 0.0f) && b->one_sided) return false;
        if (flipped) wo.z = -wo.z;
        out->pmf = 0.0f;
        out->delta = false;
        out->lobe = BSDF_LOBE_GLOSSY_REFLECTION; /* one tabulated lobe (Dupuy & Jakob 2018) */
        ok = measured_sample(b->lobe.measured.table, wo, u, b->lobe.measured.spectral ? b->lobe.measured.lambda : NULL,
                             &out->wi, &out->weight, &out->pdf_w);
        break;
    case MATERIAL_HAIR:
        /* Both sides, transmission included; the weight from eval over the sample's pdf
         * (the lobes' mixture density, so one-sample MIS over them). */
        out->pmf = 0.0f;
        out->delta = false;
        int p;
        ok = hair_sample_lobe(&b->lobe.hair, wo, uc, u, &out->wi, &out->pdf_w, &p);
        out->lobe = (uint8_t)(BSDF_LOBE_HAIR_R + (p < 3 ? p : 3));
        if (ok) {
            Color f = mode == BSDF_RADIANCE ? hair_eval(&b->lobe.hair, wo, out->wi)
                                            : hair_eval_adjoint(&b->lobe.hair, wo, out->wi);
            out->weight = color_scale(f, 1.0f / out->pdf_w);
        }
        break;
    case MATERIAL_MIX: return false;
    }
    /* The one place degenerate samples are rejected: no pdf, or a weight that is not a
     * number (e.g. a direction exactly in the tangent plane). */
    if (!ok || !((out->delta ? out->pmf : out->pdf_w) > 0.0f) || !color_is_finite(out->weight)) return false;
    if (flipped) out->wi.z = -out->wi.z;
    const float z_i = out->wi.z;
    out->wi = frame_to_world(&b->frame, out->wi);
    if (b->shading) {
        /* Delta lobes included: a mirror about ns can send light under the surface. */
        float ng_o = v3_dot(wo_world, b->ng), ng_i = v3_dot(out->wi, b->ng);
        if (!shading_allows(b, ng_o, ng_i, z_o, z_i)) return false;
        if (mode == BSDF_IMPORTANCE) {
            out->weight = color_scale(out->weight, shading_adjoint(ng_o, ng_i, z_o, z_i));
            if (!color_is_finite(out->weight)) return false;
        }
    }
    return true;
}
