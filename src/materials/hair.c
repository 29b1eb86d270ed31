/* The hair fibre BSDF (hair.h): Chiang et al. 2016's model as pbrt-v4 states it, written
 * from the paper's and the book's equations. Equation numbers are Chiang et al.'s unless
 * said otherwise. Everything is in the lobe's local frame (x along the fibre). */
#include "materials/hair.h"

#include <float.h>
#include <math.h>

#include "materials/fresnel.h"

#define HAIR_2PI (2.0f * CST_PI)

/* ------------------------------------------------------------------ parameters */

Color hair_sigma_a_from_color(Color c, float beta_n)
{
    /* Chiang eq. 9: sigma_a = (ln c / (5.969 - 0.215 b + 2.532 b^2 - 10.73 b^3 + 5.574 b^4
     * + 0.245 b^5))^2, b = beta_n; fitted to the multiple-scattered colour of a fibre. */
    const float b = beta_n, b2 = b * b, b3 = b2 * b;
    const float den = 5.969f - 0.215f * b + 2.532f * b2 - 10.73f * b3 + 5.574f * b2 * b2 + 0.245f * b2 * b3;
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) {
        float ci = clampf(c.c[i], 0.0f, 1.0f);
        float s = sqrf(logf(ci) / den);
        o.c[i] = s < 1e6f ? s : 1e6f; /* black (ln 0): opaque, and finite so that 0 x it is 0 */
    }
    return o;
}

Color hair_sigma_a_from_melanin(float eumelanin, float pheomelanin)
{
    /* Absorption per unit concentration in linear sRGB, pbrt-v4's values (after d'Eon et
     * al. 2011, "An energy-conserving hair reflectance model", sec. 6). */
    return color_add(color_scale(color_rgb(0.419f, 0.697f, 1.37f), eumelanin),
                     color_scale(color_rgb(0.187f, 0.4f, 1.05f), pheomelanin));
}

void hair_init(HairLobe *l, const Material *m)
{
    l->from_color = m->hair_color;
    l->source = m->hair_color ? m->albedo : m->sigma_a;
    l->beta_n = m->beta_n;
    l->sigma_a = m->hair_color ? hair_sigma_a_from_color(m->albedo, m->beta_n) : m->sigma_a;
    l->eta = m->ior;
    l->h = 0.0f;
    l->gamma_o = 0.0f;
    /* Longitudinal variances from beta_m (eq. 7): R has v, TT v/4, TRT and the rest 4v. */
    const float bm = m->beta_m, bm2 = bm * bm, bm4 = bm2 * bm2, bm20 = bm4 * bm4 * bm4 * bm4 * bm4;
    l->v[0] = sqrf(0.726f * bm + 0.812f * bm2 + 3.7f * bm20);
    l->v[1] = 0.25f * l->v[0];
    l->v[2] = 4.0f * l->v[0];
    l->v[3] = l->v[2];
    /* Azimuthal logistic scale from beta_n (eq. 8). */
    const float bn = m->beta_n, bn2 = bn * bn, bn22 = powf(bn, 22.0f);
    l->s = 0.62665707f * (0.265f * bn + 1.194f * bn2 + 5.372f * bn22); /* sqrt(pi / 8) */
    /* sin and cos of 2^k alpha by the double-angle formulas (pbrt-v4 sec. 9.9.4). */
    l->sin2k_alpha[0] = sinf(m->hair_alpha * (CST_PI / 180.0f));
    l->cos2k_alpha[0] = safe_sqrtf(1.0f - sqrf(l->sin2k_alpha[0]));
    for (int k = 1; k < 3; k++) {
        l->sin2k_alpha[k] = 2.0f * l->cos2k_alpha[k - 1] * l->sin2k_alpha[k - 1];
        l->cos2k_alpha[k] = sqrf(l->cos2k_alpha[k - 1]) - sqrf(l->sin2k_alpha[k - 1]);
    }
}

void hair_set_offset(HairLobe *l, float v)
{
    l->h = clampf(-1.0f + 2.0f * v, -1.0f, 1.0f);
    l->gamma_o = asinf(l->h);
}

/* ------------------------------------------------------------------ Mp */

/* The modified Bessel function I0 by its power series sum (x^2/4)^i / (i!)^2, summed until
 * the terms no longer change the float (x <= 12 here: at most ~30 terms). */
static float bessel_i0(float x)
{
    const float q = 0.25f * x * x;
    float sum = 1.0f, term = 1.0f;
    for (int i = 1; i < 64; i++) {
        term *= q / (float)(i * i);
        sum += term;
        if (term < sum * 1e-8f) break;
    }
    return sum;
}

float hair_mp(float cos_i, float cos_o, float sin_i, float sin_o, float v)
{
    /* d'Eon et al. 2011 eq. 7: Mp = csch(1/v) / (2v) exp(-sin_i sin_o / v) I0(cos_i cos_o / v). */
    const float a = cos_i * cos_o / v, b = sin_i * sin_o / v;
    if (v > 0.1f) return expf(-b) * bessel_i0(a) / (sinhf(1.0f / v) * 2.0f * v);
    /* Small v: in logarithms (pbrt-v4), csch(1/v) ~ 2 exp(-1/v), and for a > 12 the
     * asymptotic expansion I0(a) ~ e^a / sqrt(2 pi a) (1 + 1/(8a) + 9/(128a^2) +
     * 225/(3072a^3)) (Abramowitz & Stegun 9.7.1), whose next term, 11025/(98304a^4), is
     * 5e-6 at a = 12: below float rounding, so the furnace test needs no allowance for it
     * (pbrt-v4 keeps only half the 1/(8a) term, 0.26 % off at a = 12). There a - b - 1/v =
     * -(1 - cos(theta_i + theta_o)) / v, which is formed here as sin^2 / (1 + cos) to
     * keep its digits where the lobe peaks (theta_i = -theta_o). */
    float lg;
    if (a > 12.0f) {
        const float c = cos_i * cos_o - sin_i * sin_o, s = sin_i * cos_o + cos_i * sin_o;
        const float one_minus = c > 0.0f ? s * s / (1.0f + c) : 1.0f - c;
        const float r = 1.0f / a;
        const float series = 1.0f + r * (0.125f + r * (9.0f / 128.0f + r * (225.0f / 3072.0f)));
        lg = -one_minus / v - 0.5f * logf(HAIR_2PI * a) + logf(series);
    } else {
        lg = logf(bessel_i0(a)) - b - 1.0f / v;
    }
    return expf(lg + 0.69314718f + logf(1.0f / (2.0f * v))); /* ln 2 (pbrt-v4: 0.6931) */
}

/* ------------------------------------------------------------------ Np */

static inline float logistic(float x, float s)
{
    const float e = expf(-fabsf(x) / s);
    return e / (s * sqrf(1.0f + e));
}
static inline float logistic_cdf(float x, float s) { return 1.0f / (1.0f + expf(-x / s)); }

/* The logistic of scale s restricted to [-pi, pi] and renormalised (eq. 8). */
static inline float trimmed_logistic(float x, float s)
{
    return logistic(x, s) / (logistic_cdf(CST_PI, s) - logistic_cdf(-CST_PI, s));
}
/* Its inverse CDF at u in [0, 1). */
static inline float sample_trimmed_logistic(float u, float s)
{
    const float lo = logistic_cdf(-CST_PI, s), k = logistic_cdf(CST_PI, s) - lo;
    const float x = -s * logf(1.0f / (u * k + lo) - 1.0f);
    return clampf(x, -CST_PI, CST_PI);
}

/* The exit azimuth of lobe p for a path entering at gamma_o and refracting to gamma_t
 * (eq. 3 with the sign convention of pbrt-v4 eq. 9.44): 2p gamma_t - 2 gamma_o + p pi. */
static inline float hair_phi(int p, float gamma_o, float gamma_t)
{
    return 2.0f * (float)p * gamma_t - 2.0f * gamma_o + (float)p * CST_PI;
}

static inline float hair_np(float phi, int p, float s, float gamma_o, float gamma_t)
{
    /* the difference wrapped to [-pi, pi] */
    const float d = remainderf(phi - hair_phi(p, gamma_o, gamma_t), HAIR_2PI);
    return trimmed_logistic(d, s);
}

/* ------------------------------------------------------------------ shared set-up */

typedef struct HairWo {
    float sin_o, cos_o, phi_o, gamma_t;
    Color ap[HAIR_P_MAX + 1];
} HairWo;

/* What depends on wo alone: the angles, the refracted azimuth gamma_t and the
 * attenuations Ap (eqs. 3-6 with the absorption along the refracted chord). */
static bool hair_setup(const HairLobe *l, Vec3 wo, HairWo *o)
{
    o->sin_o = clampf(wo.x, -1.0f, 1.0f);
    o->cos_o = safe_sqrtf(1.0f - sqrf(o->sin_o));
    if (!(o->cos_o > 0.0f)) return false; /* along the fibre: no azimuth */
    o->phi_o = atan2f(wo.z, wo.y);
    /* Inside: the refracted longitudinal angle (Snell) and the modified index for the
     * azimuthal projection (Bravais; pbrt-v4 eq. 9.47). */
    const float sin_t = o->sin_o / l->eta, cos_t = safe_sqrtf(1.0f - sqrf(sin_t));
    const float etap = safe_sqrtf(sqrf(l->eta) - sqrf(o->sin_o)) / o->cos_o;
    const float sin_gt = etap > 0.0f ? clampf(l->h / etap, -1.0f, 1.0f) : 0.0f;
    const float cos_gt = safe_sqrtf(1.0f - sqrf(sin_gt));
    o->gamma_t = asinf(sin_gt);
    /* One pass across the fibre is the chord 2 cos(gamma_t) of the unit circle, stretched
     * by 1 / cos(theta_t) along the fibre. */
    const float len = cos_t > 0.0f ? 2.0f * cos_gt / cos_t : 0.0f;
    Color T;
    for (int i = 0; i < COLOR_LANES; i++) T.c[i] = expf(-l->sigma_a.c[i] * len);
    /* Fresnel at the entry point: the angle between wo and the surface normal there. */
    const float f = fresnel_dielectric(o->cos_o * safe_sqrtf(1.0f - sqrf(l->h)), l->eta);
    o->ap[0] = color_s(f);
    o->ap[1] = color_scale(T, sqrf(1.0f - f));
    o->ap[2] = color_scale(color_mul(o->ap[1], T), f);
    /* The rest as a geometric series (eq. 6): A_2 f T / (1 - f T). */
    for (int i = 0; i < COLOR_LANES; i++) {
        const float ft = f * T.c[i];
        o->ap[3].c[i] = ft < 1.0f ? o->ap[2].c[i] * ft / (1.0f - ft) : 0.0f;
    }
    return true;
}

/* theta_o rotated by the cuticle scales' tilt for lobe p (pbrt-v4 sec. 9.9.4): R by
 * -2 alpha, TT by alpha, TRT by 4 alpha; the rest untilted. |cos| keeps the result a
 * longitudinal angle. */
static inline void hair_tilt(const HairLobe *l, int p, float sin_o, float cos_o, float *sp, float *cp)
{
    if (p == 0) {
        *sp = sin_o * l->cos2k_alpha[1] - cos_o * l->sin2k_alpha[1];
        *cp = cos_o * l->cos2k_alpha[1] + sin_o * l->sin2k_alpha[1];
    } else if (p == 1) {
        *sp = sin_o * l->cos2k_alpha[0] + cos_o * l->sin2k_alpha[0];
        *cp = cos_o * l->cos2k_alpha[0] - sin_o * l->sin2k_alpha[0];
    } else if (p == 2) {
        *sp = sin_o * l->cos2k_alpha[2] + cos_o * l->sin2k_alpha[2];
        *cp = cos_o * l->cos2k_alpha[2] - sin_o * l->sin2k_alpha[2];
    } else {
        *sp = sin_o;
        *cp = cos_o;
    }
    *cp = fabsf(*cp);
}

/* The lobes' sampling probabilities: each Ap's share, Ap averaged over the lanes. */
static bool hair_ap_pdf(const HairWo *o, float pdf[HAIR_P_MAX + 1])
{
    float sum = 0.0f;
    for (int p = 0; p <= HAIR_P_MAX; p++) {
        float a = 0.0f;
        for (int i = 0; i < COLOR_LANES; i++) a += o->ap[p].c[i];
        pdf[p] = a;
        sum += a;
    }
    if (!(sum > 0.0f)) return false;
    for (int p = 0; p <= HAIR_P_MAX; p++) pdf[p] /= sum;
    return true;
}

/* ------------------------------------------------------------------ eval, pdf, sample */

Color hair_eval(const HairLobe *l, Vec3 wo, Vec3 wi)
{
    HairWo o;
    if (!hair_setup(l, wo, &o)) return color_s(0.0f);
    const float sin_i = clampf(wi.x, -1.0f, 1.0f), cos_i = safe_sqrtf(1.0f - sqrf(sin_i));
    const float phi = atan2f(wi.z, wi.y) - o.phi_o;
    Color sum = color_s(0.0f);
    for (int p = 0; p < HAIR_P_MAX; p++) {
        float sp, cp;
        hair_tilt(l, p, o.sin_o, o.cos_o, &sp, &cp);
        const float w = hair_mp(cos_i, cp, sin_i, sp, l->v[p]) * hair_np(phi, p, l->s, l->gamma_o, o.gamma_t);
        sum = color_add(sum, color_scale(o.ap[p], w));
    }
    /* The rest: untilted, uniform in azimuth. */
    const float w = hair_mp(cos_i, o.cos_o, sin_i, o.sin_o, l->v[HAIR_P_MAX]) * (1.0f / HAIR_2PI);
    return color_add(sum, color_scale(o.ap[HAIR_P_MAX], w));
}

Color hair_eval_adjoint(const HairLobe *l, Vec3 wo, Vec3 wi)
{
    if (wo.z == 0.0f) return color_s(0.0f);
    return color_scale(hair_eval(l, wi, wo), fabsf(wi.z) / fabsf(wo.z));
}

static float hair_pdf_setup(const HairLobe *l, const HairWo *o, const float ap_pdf[HAIR_P_MAX + 1], Vec3 wi)
{
    const float sin_i = clampf(wi.x, -1.0f, 1.0f), cos_i = safe_sqrtf(1.0f - sqrf(sin_i));
    const float phi = atan2f(wi.z, wi.y) - o->phi_o;
    float pdf = 0.0f;
    for (int p = 0; p < HAIR_P_MAX; p++) {
        float sp, cp;
        hair_tilt(l, p, o->sin_o, o->cos_o, &sp, &cp);
        pdf += hair_mp(cos_i, cp, sin_i, sp, l->v[p]) * ap_pdf[p] * hair_np(phi, p, l->s, l->gamma_o, o->gamma_t);
    }
    pdf += hair_mp(cos_i, o->cos_o, sin_i, o->sin_o, l->v[HAIR_P_MAX]) * ap_pdf[HAIR_P_MAX] * (1.0f / HAIR_2PI);
    return pdf;
}

float hair_pdf(const HairLobe *l, Vec3 wo, Vec3 wi)
{
    HairWo o;
    float ap_pdf[HAIR_P_MAX + 1];
    if (!hair_setup(l, wo, &o) || !hair_ap_pdf(&o, ap_pdf)) return 0.0f;
    return hair_pdf_setup(l, &o, ap_pdf, wi);
}

bool hair_sample(const HairLobe *l, Vec3 wo, float uc, Vec2 u, Vec3 *wi, float *pdf_w)
{
    int p;
    return hair_sample_lobe(l, wo, uc, u, wi, pdf_w, &p);
}

bool hair_sample_lobe(const HairLobe *l, Vec3 wo, float uc, Vec2 u, Vec3 *wi, float *pdf_w, int *lobe_p)
{
    *lobe_p = 0;
    HairWo o;
    float ap_pdf[HAIR_P_MAX + 1];
    if (!hair_setup(l, wo, &o) || !hair_ap_pdf(&o, ap_pdf)) return false;
    /* The lobe, and uc remapped to [0, 1) within its share for the azimuth. */
    int p = 0;
    while (p < HAIR_P_MAX && uc >= ap_pdf[p]) uc -= ap_pdf[p++];
    *lobe_p = p;
    uc = ap_pdf[p] > 0.0f ? fminf(uc / ap_pdf[p], 0x1.fffffep-1f) : 0.5f;
    float sp, cp;
    hair_tilt(l, p, o.sin_o, o.cos_o, &sp, &cp);
    /* Mp by d'Eon et al. 2013 ("Importance sampling for physically-based hair fiber
     * models", sec. 3): a direction about the mirror of theta_o with cos = 1 + v ln(u +
     * (1 - u) e^(-2/v)) and a uniform angle about it, projected to the longitudinal angle.
     * u.x is kept >= 1e-5 as pbrt-v4 does (the log's argument stays away from 0). */
    const float v = l->v[p];
    const float cos_c = 1.0f + v * logf(fmaxf(u.x, 1e-5f) + (1.0f - u.x) * expf(-2.0f / v));
    const float sin_c = safe_sqrtf(1.0f - sqrf(cos_c));
    const float sin_i = clampf(-cos_c * sp + sin_c * cosf(HAIR_2PI * u.y) * cp, -1.0f, 1.0f);
    const float cos_i = safe_sqrtf(1.0f - sqrf(sin_i));
    /* Np: the logistic about the lobe's exit azimuth, or uniform for the rest. */
    const float dphi = p < HAIR_P_MAX ? hair_phi(p, l->gamma_o, o.gamma_t) + sample_trimmed_logistic(uc, l->s)
                                      : HAIR_2PI * uc;
    const float phi_i = o.phi_o + dphi;
    *wi = v3(sin_i, cos_i * cosf(phi_i), cos_i * sinf(phi_i));
    *pdf_w = hair_pdf_setup(l, &o, ap_pdf, *wi);
    return *pdf_w > 0.0f;
}
