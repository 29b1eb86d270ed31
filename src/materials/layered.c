/* The layered BSDF's random walk (Guo et al. 2018; pbrt-v4 LayeredBxDF, book sec. 14.3):
 * the two interfaces as local BxDFs (a GGX or smooth dielectric on top, Lambert or a GGX or
 * smooth conductor at the bottom), a Henyey-Greenstein slab between, and the stochastic
 * eval, pdf and sample. The slab spans z in [0, thickness]; its top interface is at
 * z = thickness. Inside the walk BxDF values are f without the cosine (pbrt's convention);
 * the public functions return f |cos_i| as bsdf.h does. */
#include "materials/layered.h"

#include <float.h>
#include <string.h>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "materials/fresnel.h"
#include "materials/microfacet.h"
#include "math/frame.h"
#include "sampling/warp.h"

void layered_init(LayeredLobe *l, const Material *m)
{
    const bool cond = m->type == MATERIAL_COATED_CONDUCTOR;
    const float eta = m->ior > 0.0f ? m->ior : 1.0f;
    l->reflectance = cond ? color_s(0.0f) : m->albedo;
    /* The conductor sits in the slab's medium: its IOR relative to it (pbrt-v4
     * CoatedConductorMaterial divides eta and k by the interface's eta). */
    l->eta = cond ? color_scale(m->eta, 1.0f / eta) : color_s(1.0f);
    l->k = cond ? color_scale(m->k, 1.0f / eta) : color_s(0.0f);
    l->albedo = m->layer_albedo;
    l->top_eta = eta;
    material_bsdf_alpha2(m->roughness, m->anisotropic ? m->roughness_v : m->roughness, &l->top_alpha, &l->top_alpha_y);
    l->base_alpha = l->base_alpha_y = 0.0f;
    if (cond)
        material_bsdf_alpha2(m->base_roughness, m->anisotropic ? m->base_roughness_v : m->base_roughness,
                             &l->base_alpha, &l->base_alpha_y);
    l->thickness = m->thickness;
    l->g = clampf(m->g, -0.99f, 0.99f);
    l->max_depth = m->max_depth;
    l->nsamples = m->nsamples;
    l->conductor = cond;
    l->seed = 0;
}

/* ------------------------------------------------------------------ the two interfaces */

enum { SIDE_REFLECT = 1, SIDE_TRANSMIT = 2, SIDE_ALL = 3 }; /* pbrt's BxDFReflTransFlags */

typedef struct IfaceSample {
    Color f;   /* f(wo, wi), no cosine */
    Vec3 wi;
    float pdf; /* per unit solid angle, or the discrete probability when specular */
    bool specular, transmit;
} IfaceSample;

static inline bool top_specular(const LayeredLobe *l) { return l->top_alpha == 0.0f; }
static inline bool base_specular(const LayeredLobe *l) { return l->conductor && l->base_alpha == 0.0f; }

/* Walter et al. 2007 eq. 16: the generalised half vector, on +z; false when a direction
 * is on the back of it (no microfacet scatters the pair). Same as bsdf.c's. */
static bool top_half(const LayeredLobe *l, Vec3 wo, Vec3 wi, Vec3 *m, float *etap, bool *reflect)
{
    return bsdf_dielectric_half(wo, wi, l->top_eta, m, etap, reflect);
}

/* F at the microfacet, from the outside direction for refraction (bsdf.c's reason). */
static inline float top_fresnel(const LayeredLobe *l, Vec3 wo, Vec3 wi, Vec3 m, bool reflect)
{
    return fresnel_dielectric(v3_dot(reflect || wo.z > 0.0f ? wo : wi, m), l->top_eta);
}

/* The rough dielectric interface, Walter et al. 2007 eqs. 20-21; the 1 / etap^2 of
 * radiance only (the adjoint lacks it, Veach thesis sec. 5.2). Smooth: 0 (delta). */
static float top_f(const LayeredLobe *l, Vec3 wo, Vec3 wi, bool importance)
{
    Vec3 m;
    float etap;
    bool reflect;
    if (top_specular(l) || !top_half(l, wo, wi, &m, &etap, &reflect)) return 0.0f;
    float dg = ggx_d(m, l->top_alpha, l->top_alpha_y) * ggx_g2(wo, wi, l->top_alpha, l->top_alpha_y);
    float F = top_fresnel(l, wo, wi, m, reflect), cc = fabsf(wo.z * wi.z);
    if (reflect) return F * dg / (4.0f * cc);
    float denom = sqrf(v3_dot(wi, m) + v3_dot(wo, m) / etap);
    float f = (1.0f - F) * dg * fabsf(v3_dot(wi, m) * v3_dot(wo, m)) / (cc * denom);
    return importance ? f : f / (etap * etap);
}

/* Visible-normal sampling, then reflection with probability R / (R + T) (R = F, T = 1 - F,
 * each zero when `sides` excludes it): the density of top_sample. */
static float top_pdf(const LayeredLobe *l, Vec3 wo, Vec3 wi, int sides)
{
    Vec3 m;
    float etap;
    bool reflect;
    if (top_specular(l) || !top_half(l, wo, wi, &m, &etap, &reflect)) return 0.0f;
    float F = top_fresnel(l, wo, wi, m, reflect);
    float R = (sides & SIDE_REFLECT) ? F : 0.0f, T = (sides & SIDE_TRANSMIT) ? 1.0f - F : 0.0f;
    if (!(R + T > 0.0f)) return 0.0f;
    float pm = ggx_visible_pdf(wo, m, l->top_alpha, l->top_alpha_y);
    if (reflect) return pm / (4.0f * fabsf(v3_dot(wo, m))) * R / (R + T);
    float denom = sqrf(v3_dot(wi, m) + v3_dot(wo, m) / etap);
    return pm * fabsf(v3_dot(wi, m)) / denom * T / (R + T);
}

static bool top_sample(const LayeredLobe *l, Vec3 wo, float uc, Vec2 u, bool importance, int sides, IfaceSample *s)
{
    if (wo.z == 0.0f) return false;
    if (top_specular(l)) {
        float F = fresnel_dielectric(wo.z, l->top_eta);
        float R = (sides & SIDE_REFLECT) ? F : 0.0f, T = (sides & SIDE_TRANSMIT) ? 1.0f - F : 0.0f;
        if (!(R + T > 0.0f)) return false;
        s->specular = true;
        if (uc < R / (R + T)) {
            s->wi = v3(-wo.x, -wo.y, wo.z);
            s->f = color_s(R / fabsf(wo.z));
            s->pdf = R / (R + T);
            s->transmit = false;
            return true;
        }
        Vec3 wt;
        float etap;
        if (!refract_about(wo, v3(0.0f, 0.0f, 1.0f), l->top_eta, &wt, &etap)) return false;
        s->wi = v3_normalize(wt);
        if (s->wi.z == 0.0f) return false;
        float f = T / fabsf(s->wi.z);
        s->f = color_s(importance ? f : f / (etap * etap));
        s->pdf = T / (R + T);
        s->transmit = true;
        return true;
    }
    Vec3 m = ggx_sample_visible(wo.z > 0.0f ? wo : v3_neg(wo), l->top_alpha, l->top_alpha_y, u);
    float F = fresnel_dielectric(v3_dot(wo, m), l->top_eta);
    float R = (sides & SIDE_REFLECT) ? F : 0.0f, T = (sides & SIDE_TRANSMIT) ? 1.0f - F : 0.0f;
    if (!(R + T > 0.0f)) return false;
    Vec3 wi;
    if (uc < R / (R + T)) {
        wi = reflect_about(wo, m);
        if (wi.z * wo.z <= 0.0f) return false;
    } else {
        float etap;
        if (!refract_about(wo, m, l->top_eta, &wi, &etap)) return false;
        wi = v3_normalize(wi);
        if (wi.z * wo.z >= 0.0f) return false;
    }
    s->wi = wi;
    s->specular = false;
    s->transmit = wi.z * wo.z < 0.0f;
    s->f = color_s(top_f(l, wo, wi, importance));
    s->pdf = top_pdf(l, wo, wi, sides);
    return s->pdf > 0.0f && !color_is_black(s->f);
}

/* The base: Lambert, or a conductor (Cook-Torrance with GGX, Walter et al. 2007 eq. 20),
 * reflecting on whichever side wo is. */
static Color base_f(const LayeredLobe *l, Vec3 wo, Vec3 wi)
{
    if (!(wo.z * wi.z > 0.0f)) return color_s(0.0f);
    if (!l->conductor) return color_scale(l->reflectance, CST_INV_PI);
    if (base_specular(l)) return color_s(0.0f);
    if (wo.z < 0.0f) { wo = v3_neg(wo); wi = v3_neg(wi); }
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return color_s(0.0f);
    Vec3 m = v3_normalize(h);
    float s = ggx_d(m, l->base_alpha, l->base_alpha_y) * ggx_g2(wo, wi, l->base_alpha, l->base_alpha_y) / (4.0f * wo.z * wi.z);
    return color_scale(fresnel_conductor_rgb(v3_dot(wo, m), l->eta, l->k), s);
}

static float base_pdf(const LayeredLobe *l, Vec3 wo, Vec3 wi)
{
    if (!(wo.z * wi.z > 0.0f)) return 0.0f;
    if (!l->conductor) return fabsf(wi.z) * CST_INV_PI;
    if (base_specular(l)) return 0.0f;
    if (wo.z < 0.0f) { wo = v3_neg(wo); wi = v3_neg(wi); }
    Vec3 h = v3_add(wo, wi);
    if (v3_length2(h) == 0.0f) return 0.0f;
    Vec3 m = v3_normalize(h);
    return ggx_visible_pdf(wo, m, l->base_alpha, l->base_alpha_y) / (4.0f * v3_dot(wo, m));
}

static bool base_sample(const LayeredLobe *l, Vec3 wo, Vec2 u, IfaceSample *s)
{
    if (wo.z == 0.0f) return false;
    const bool flip = wo.z < 0.0f;
    Vec3 w = flip ? v3_neg(wo) : wo, wi;
    s->transmit = false;
    if (base_specular(l)) {
        wi = v3(-w.x, -w.y, w.z);
        s->f = color_scale(fresnel_conductor_rgb(w.z, l->eta, l->k), 1.0f / w.z);
        s->pdf = 1.0f;
        s->specular = true;
    } else {
        if (l->conductor) {
            wi = reflect_about(w, ggx_sample_visible(w, l->base_alpha, l->base_alpha_y, u));
            if (wi.z <= 0.0f) return false; /* lost: single scattering */
        } else {
            wi = warp_cosine_hemisphere(u);
            if (wi.z <= 0.0f) return false;
        }
        s->f = base_f(l, w, wi);
        s->pdf = base_pdf(l, w, wi);
        s->specular = false;
    }
    s->wi = flip ? v3_neg(wi) : wi;
    return s->pdf > 0.0f && !color_is_black(s->f);
}

/* ------------------------------------------------------------------ the slab */

float layered_hg_pdf(Vec3 wo, Vec3 wi, float g)
{
    float denom = 1.0f + g * g + 2.0f * g * v3_dot(wo, wi);
    return CST_INV_4PI * (1.0f - g * g) / (denom * safe_sqrtf(denom));
}

/* Inversion of the HG cosine's CDF about the propagation direction -wo (e.g. Pharr et al.,
 * pbrt-v3 sec. 15.2.3); the sign flip turns it into pbrt-v4's both-outward convention. */
Vec3 layered_hg_sample(Vec3 wo, float g, Vec2 u)
{
    float c;
    if (fabsf(g) < 1e-3f) c = 1.0f - 2.0f * u.x;
    else c = (1.0f + g * g - sqrf((1.0f - g * g) / (1.0f - g + 2.0f * g * u.x))) / (2.0f * g);
    c = clampf(c, -1.0f, 1.0f);
    float s = safe_sqrtf(1.0f - c * c), phi = 2.0f * CST_PI * u.y;
    Frame f = frame_from_normal(v3_neg(wo));
    return frame_to_world(&f, v3(s * cosf(phi), s * sinf(phi), c));
}

/* Beer-Lambert transmittance over a height difference dz along w (sigma_t = 1). */
static inline float slab_tr(float dz, Vec3 w)
{
    if (fabsf(dz) <= FLT_MIN) return 1.0f;
    return expf(-fabsf(dz / w.z));
}

/* Veach's power heuristic (thesis eq. 9.13) for one sample of each strategy. */
static inline float power2(float fp, float gp)
{
    float f2 = fp * fp, g2 = gp * gp;
    if (isinf(f2)) return 1.0f;
    return f2 + g2 > 0.0f ? f2 / (f2 + g2) : 0.0f;
}

static inline uint64_t hash_dir(Vec3 w)
{
    uint32_t b[3];
    memcpy(&b[0], &w.x, 4);
    memcpy(&b[1], &w.y, 4);
    memcpy(&b[2], &w.z, 4);
    return mix64(((uint64_t)b[0] << 32 | b[1]) ^ mix64((uint64_t)b[2] + 0x9e3779b97f4a7c15ULL));
}

/* The walk's random numbers: PCG32 seeded from the lobe's seed, a salt per use and two
 * 64-bit keys (pbrt-v4: RNG(Hash(seed, wo), Hash(wi))). */
static inline void walk_rng(Pcg32 *r, const LayeredLobe *l, uint64_t salt, uint64_t a, uint64_t b)
{
    pcg32_seed(r, mix64(l->seed ^ salt ^ a), b);
}

static inline Vec2 rv2(Pcg32 *r) { return pcg32_v2(r); }

bool layered_is_delta(const LayeredLobe *l)
{
    return top_specular(l) && base_specular(l) && color_is_black(l->albedo);
}

float layered_delta_probability(const LayeredLobe *l, float cos_o)
{
    if (layered_is_delta(l)) return 1.0f;
    return top_specular(l) ? fresnel_dielectric(fabsf(cos_o), l->top_eta) : 0.0f;
}

/* pbrt-v4 LayeredBxDF::f for a twoSided BxDF with wo on top and an opaque base: the
 * interface's reflection, then per sample a walk from the interface sample of wo, with
 * next-event estimation through the exit interface toward wi (its transmission sampled
 * from wi in the adjoint mode) at every slab scattering and base reflection, each MIS
 * weighted against the walk's own continuation (power heuristic).
 * One deliberate difference: where the walk's continuation leaves through a rough
 * interface, its MIS weight takes the density of the competing strategy, the interface's
 * transmission sampled from wi, p(wi -> -w); pbrt-v4 takes p(-w -> wi), which differs by
 * refraction's Jacobian, so its two weights do not sum to 1 and its eval is biased
 * (test_layered's sample-vs-eval and reciprocity tests measured it: -7 % at cos_o 0.9,
 * roughness 0.5, before this change; +13 % at normal incidence for the sharper coat of
 * pbrt-v4's killeroo-coated-gold, test_sharp_coat_eval_integral, which is why pbrt-v4
 * renders that scene about 1.4 % brighter: its lights are sampled through this eval). */
Color layered_eval(const LayeredLobe *l, Vec3 wo, Vec3 wi, bool importance)
{
    if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return color_s(0.0f);
    const int n = l->nsamples > 0 ? l->nsamples : 1;
    const float thick = maxf(l->thickness, FLT_MIN), exit_z = thick;
    const bool has_albedo = !color_is_black(l->albedo);
    Color f = color_s((float)n * top_f(l, wo, wi, importance));
    Pcg32 rng;
    walk_rng(&rng, l, 0x5eedf00dULL, hash_dir(wo), hash_dir(wi));
    for (int s = 0; s < n; s++) {
        IfaceSample wos, wis;
        float uc = pcg32_float(&rng);
        if (!top_sample(l, wo, uc, rv2(&rng), importance, SIDE_TRANSMIT, &wos) || wos.wi.z == 0.0f) continue;
        /* The exit transmission toward wi for next-event estimation. When it fails the walk
         * still runs: its continuation terms keep their MIS weights (functions of the
         * directions alone), which is what makes the two strategies sum to the integral.
         * pbrt-v4 skips the whole walk there, a bias (test_layered measured sample weights
         * up to 2x eval in the tails of a rough coat over a rough conductor). */
        uc = pcg32_float(&rng);
        bool nee_ok = top_sample(l, wi, uc, rv2(&rng), !importance, SIDE_TRANSMIT, &wis) && wis.wi.z != 0.0f;
        Color beta = color_scale(wos.f, fabsf(wos.wi.z) / wos.pdf);
        Color nee = nee_ok ? color_scale(wis.f, 1.0f / wis.pdf) : color_s(0.0f);
        float z = thick;
        Vec3 w = wos.wi;
        for (int depth = 0; depth < l->max_depth; depth++) {
            /* Russian roulette (pbrt-v4's): after 3 steps, on a throughput below 0.25. */
            if (depth > 3 && color_max(beta) < 0.25f) {
                float q = maxf(0.0f, 1.0f - color_max(beta));
                if (pcg32_float(&rng) < q) break;
                beta = color_scale(beta, 1.0f / (1.0f - q));
            }
            if (!has_albedo) {
                z = z == thick ? 0.0f : thick;
                beta = color_scale(beta, slab_tr(thick, w));
            } else {
                float dz = -logf(1.0f - pcg32_float(&rng)) * fabsf(w.z); /* exponential, sigma_t = 1 */
                float zp = w.z > 0.0f ? z + dz : z - dz;
                if (zp == z) continue;
                if (0.0f < zp && zp < thick) {
                    /* Scattering in the slab: NEE through the exit, then the phase sample. */
                    if (nee_ok) {
                        float ph = layered_hg_pdf(v3_neg(w), v3_neg(wis.wi), l->g);
                        float wt = top_specular(l) ? 1.0f : power2(wis.pdf, ph);
                        f = color_add(f, color_scale(color_mul(color_mul(beta, l->albedo), nee),
                                                     ph * wt * slab_tr(zp - exit_z, wis.wi)));
                    }
                    Vec3 wp = layered_hg_sample(v3_neg(w), l->g, rv2(&rng));
                    float pp = layered_hg_pdf(v3_neg(w), wp, l->g);
                    if (!(pp > 0.0f) || wp.z == 0.0f) break;
                    beta = color_mul(beta, l->albedo); /* p / pdf = 1: exact sampling */
                    w = wp;
                    z = zp;
                    if (((z < exit_z && w.z > 0.0f) || (z > exit_z && w.z < 0.0f)) && !top_specular(l)) {
                        float fe = top_f(l, v3_neg(w), wi, importance);
                        if (fe > 0.0f) {
                            float wt2 = power2(pp, top_pdf(l, wi, v3_neg(w), SIDE_TRANSMIT));
                            f = color_add(f, color_scale(beta, slab_tr(zp - exit_z, w) * fe * wt2));
                        }
                    }
                    continue;
                }
                z = clampf(zp, 0.0f, thick);
            }
            IfaceSample bs;
            if (z == exit_z) {
                /* At the interface from below: only its reflection continues the walk. */
                uc = pcg32_float(&rng);
                if (!top_sample(l, v3_neg(w), uc, rv2(&rng), importance, SIDE_REFLECT, &bs)) break;
                beta = color_mul(beta, color_scale(bs.f, fabsf(bs.wi.z) / bs.pdf));
                w = bs.wi;
                continue;
            }
            /* At the base: NEE through the exit, then the base's sample. */
            if (nee_ok && !base_specular(l)) {
                float wt = top_specular(l) ? 1.0f : power2(wis.pdf, base_pdf(l, v3_neg(w), v3_neg(wis.wi)));
                Color fb = base_f(l, v3_neg(w), v3_neg(wis.wi));
                f = color_add(f, color_scale(color_mul(color_mul(beta, fb), nee),
                                             fabsf(wis.wi.z) * wt * slab_tr(thick, wis.wi)));
            }
            if (!base_sample(l, v3_neg(w), rv2(&rng), &bs)) break;
            beta = color_mul(beta, color_scale(bs.f, fabsf(bs.wi.z) / bs.pdf));
            w = bs.wi;
            if (!top_specular(l)) {
                float fe = top_f(l, v3_neg(w), wi, importance);
                if (fe > 0.0f) {
                    float wt = base_specular(l) ? 1.0f : power2(bs.pdf, top_pdf(l, wi, v3_neg(w), SIDE_TRANSMIT));
                    f = color_add(f, color_scale(beta, slab_tr(thick, bs.wi) * fe * wt));
                }
            }
        }
    }
    return color_scale(f, wi.z / (float)n);
}

/* pbrt-v4 LayeredBxDF::PDF, reflection case: the interface's reflection plus, per sample,
 * an estimate of the transmission-reflection-transmission density: the base's density
 * between the two refracted directions (smooth interface), the interface's density after
 * a base sample (smooth base), or both MIS-combined. The interface term takes its
 * reflection probability (pbrt-v4 drops it); the uniform share is over the hemisphere. */
float layered_pdf(const LayeredLobe *l, Vec3 wo, Vec3 wi)
{
    if (!(wo.z > 0.0f) || !(wi.z > 0.0f)) return 0.0f;
    const int n = l->nsamples > 0 ? l->nsamples : 1;
    float sum = (float)n * top_pdf(l, wo, wi, SIDE_ALL);
    Pcg32 rng;
    walk_rng(&rng, l, 0x9dfULL, hash_dir(wi), hash_dir(wo));
    for (int s = 0; s < n; s++) {
        IfaceSample wos, wis, rs;
        float uc = pcg32_float(&rng);
        bool ok_o = top_sample(l, wo, uc, rv2(&rng), false, SIDE_TRANSMIT, &wos);
        uc = pcg32_float(&rng);
        bool ok_i = top_sample(l, wi, uc, rv2(&rng), true, SIDE_TRANSMIT, &wis);
        if (!ok_o || !ok_i) continue;
        if (top_specular(l)) {
            sum += base_pdf(l, v3_neg(wos.wi), v3_neg(wis.wi));
            continue;
        }
        if (!base_sample(l, v3_neg(wos.wi), rv2(&rng), &rs)) continue;
        if (base_specular(l)) {
            sum += top_pdf(l, v3_neg(rs.wi), wi, SIDE_ALL);
        } else {
            float r_pdf = base_pdf(l, v3_neg(wos.wi), v3_neg(wis.wi));
            sum += power2(wis.pdf, r_pdf) * r_pdf;
            float t_pdf = top_pdf(l, v3_neg(rs.wi), wi, SIDE_ALL);
            sum += power2(rs.pdf, t_pdf) * t_pdf;
        }
    }
    return 0.1f * CST_INV_2PI + 0.9f * sum / (float)n;
}

/* pbrt-v4 LayeredBxDF::Sample_f: the interface's sample; a reflection is returned as it
 * is, a transmission starts a walk through slab and base that ends when it leaves through
 * the interface. The weight is the path's f |cos| / pdf. */
bool layered_sample(const LayeredLobe *l, Vec3 wo, float uc, Vec2 u, bool importance, LayeredSample *out)
{
    if (!(wo.z > 0.0f)) return false;
    IfaceSample bs;
    if (!top_sample(l, wo, uc, u, importance, SIDE_ALL, &bs)) return false;
    if (!bs.transmit) {
        out->wi = bs.wi;
        out->pdf = bs.pdf;
        out->weight = color_scale(bs.f, fabsf(bs.wi.z) / bs.pdf);
        out->delta = bs.specular;
        out->lobe = bs.specular ? BSDF_LOBE_COAT_SPECULAR_REFLECTION : BSDF_LOBE_COAT_GLOSSY_REFLECTION;
        return true;
    }
    const float thick = maxf(l->thickness, FLT_MIN);
    const bool has_albedo = !color_is_black(l->albedo);
    uint32_t ub[3];
    memcpy(&ub[0], &uc, 4);
    memcpy(&ub[1], &u.x, 4);
    memcpy(&ub[2], &u.y, 4);
    Pcg32 rng;
    walk_rng(&rng, l, 0xa11ceULL, hash_dir(wo), mix64((uint64_t)ub[0] << 32 ^ (uint64_t)ub[1] << 16 ^ ub[2]));
    /* beta = f / pdf of the path so far, kept as one ratio: f and pdf apart (as pbrt-v4
     * keeps them) underflow after some 40 slab scatterings and the sample is lost (a
     * 0.4 % energy loss in the white-furnace test, before this). pdf is only reported for
     * delta paths, which do not scatter in the slab. */
    Color beta = color_scale(bs.f, fabsf(bs.wi.z) / bs.pdf);
    float pdf = bs.pdf, z = thick;
    bool specular = bs.specular;
    Vec3 w = bs.wi;
    for (int depth = 0; depth < l->max_depth; depth++) {
        float rr = color_max(beta);
        if (depth > 3 && rr < 0.25f) {
            float q = maxf(0.0f, 1.0f - rr);
            if (pcg32_float(&rng) < q) return false;
            beta = color_scale(beta, 1.0f / (1.0f - q));
            pdf *= 1.0f - q;
        }
        if (w.z == 0.0f) return false;
        if (has_albedo) {
            float dz = -logf(1.0f - pcg32_float(&rng)) * fabsf(w.z);
            float zp = w.z > 0.0f ? z + dz : z - dz;
            if (zp == z) return false;
            if (0.0f < zp && zp < thick) {
                Vec3 wp = layered_hg_sample(v3_neg(w), l->g, rv2(&rng));
                float pp = layered_hg_pdf(v3_neg(w), wp, l->g);
                if (!(pp > 0.0f) || wp.z == 0.0f) return false;
                beta = color_mul(beta, l->albedo); /* p / pdf = 1: exact sampling */
                pdf *= pp;
                specular = false;
                w = wp;
                z = zp;
                continue;
            }
            z = clampf(zp, 0.0f, thick);
        } else {
            z = z == thick ? 0.0f : thick;
            beta = color_scale(beta, slab_tr(thick, w));
        }
        bool ok;
        if (z == 0.0f) {
            ok = base_sample(l, v3_neg(w), rv2(&rng), &bs);
        } else {
            float uc2 = pcg32_float(&rng);
            ok = top_sample(l, v3_neg(w), uc2, rv2(&rng), importance, SIDE_ALL, &bs);
        }
        if (!ok) return false;
        beta = color_mul(beta, color_scale(bs.f, 1.0f / bs.pdf));
        pdf *= bs.pdf;
        specular = specular && bs.specular;
        w = bs.wi;
        if (bs.transmit) {
            if (!(w.z > 0.0f)) return false;
            out->wi = w;
            out->pdf = pdf;
            out->weight = color_scale(beta, w.z);
            out->delta = specular;
            /* through the interface: named by the base (a walk in a scattering slab is
             * not specular even over a smooth conductor) */
            out->lobe = specular ? BSDF_LOBE_BASE_SPECULAR_REFLECTION
                        : l->conductor ? BSDF_LOBE_BASE_GLOSSY_REFLECTION
                                       : BSDF_LOBE_BASE_DIFFUSE_REFLECTION;
            return true;
        }
        beta = color_scale(beta, fabsf(bs.wi.z));
    }
    return false;
}
