/* The hair fibre BSDF of Chiang, Bitterli, Tappan & Burley 2016 ("A practical and
 * controllable hair and fur model for production path tracing"), as pbrt-v4's HairBxDF
 * (pbrt 4th ed. sec. 9.9): the lobe's parameters, eval, pdf and importance sampling.
 *
 * Frame (pbrt-v4's): local x along the fibre (the BSDF frame's s, the hit's dp/du), y = n x s,
 * z = the normal; sin theta = w.x is the longitudinal angle, phi = atan2(w.z, w.y) the
 * azimuth about the fibre. h in [-1, 1] is the offset of the hit across the fibre's width
 * (h = -1 + 2 v of the hit's uv, as pbrt-v4 takes it for curves). Lengths inside the fibre
 * are in units of its radius, so sigma_a is per fibre radius.
 * The sum of the lobes p = 0 (R), 1 (TT), 2 (TRT) and p_max = 3 (the rest, eq. 6 of
 * Chiang's paper) is f(wo, wi) |cos theta_i| with pbrt-v4's convention that theta_i of
 * the cosine is the angle to the frame's z: hair_eval returns sum_p Mp Ap Np, which is
 * that product. The model is not reciprocal (Ap and the azimuthal offsets depend on wo
 * alone; pbrt-v4 keeps its reciprocity test disabled): the adjoint is eval with the
 * directions swapped (hair_eval_adjoint). */
#ifndef CST_MATERIALS_HAIR_H
#define CST_MATERIALS_HAIR_H

#include <stdbool.h>

#include "materials/material.h"
#include "math/color.h"
#include "math/vec3.h"

enum { HAIR_P_MAX = 3 };

typedef struct HairLobe {
    Color sigma_a;      /* absorption per unit fibre radius, per channel or wavelength */
    /* What sigma_a comes from (bsdf_at_wavelengths re-derives it per wavelength): sigma_a
     * itself (an unbounded RGB), or with from_color the fibre's colour (a reflectance,
     * Chiang eq. 9). */
    Color source;
    bool from_color;
    float eta;          /* the fibre's IOR */
    float beta_n;       /* azimuthal roughness in [0, 1] (eq. 9 needs it) */
    float h, gamma_o;   /* offset across the fibre, asin(h) */
    float s;            /* logistic scale of Np (Chiang eq. 8) */
    float v[HAIR_P_MAX + 1];                     /* Mp variances per lobe (Chiang eq. 7) */
    float sin2k_alpha[3], cos2k_alpha[3];        /* the cuticle tilt 2^k alpha, k = 0..2 */
} HairLobe;

/* From the material (beta_m, beta_n, hair_alpha in degrees, ior as eta, sigma_a or the
 * colour in albedo); h = 0 until hair_set_offset. */
void hair_init(HairLobe *l, const Material *m);
/* h = -1 + 2 v (clamped to [-1, 1]), v the hit's second texture coordinate. */
void hair_set_offset(HairLobe *l, float v);

/* sigma_a of a fibre whose multiple scattering looks like colour c (in [0, 1]) for
 * azimuthal roughness beta_n: Chiang et al. eq. 9, per lane. Black gives a large finite
 * value (1e6 per radius: no light through). */
Color hair_sigma_a_from_color(Color c, float beta_n);
/* sigma_a of eumelanin and pheomelanin concentrations, as linear sRGB (pbrt-v4's
 * HairBxDF::SigmaAFromConcentration coefficients, after d'Eon et al. 2011). */
Color hair_sigma_a_from_melanin(float eumelanin, float pheomelanin);

/* sum_p Mp Ap Np = f(wo, wi) |wi.z| (local directions, unit). */
Color hair_eval(const HairLobe *l, Vec3 wo, Vec3 wi);
/* The adjoint f*(wo, wi) |wi.z| = f(wi, wo) |wi.z|, for light paths. */
Color hair_eval_adjoint(const HairLobe *l, Vec3 wo, Vec3 wi);
/* Density per solid angle of hair_sample's wi. */
float hair_pdf(const HairLobe *l, Vec3 wo, Vec3 wi);
/* pbrt-v4 HairBxDF::Sample_f: the lobe p chosen by uc with probability of its share of
 * the attenuations Ap (averaged over the lanes), theta_i from Mp (d'Eon et al. 2013) by
 * u.x and u.y, phi_i from Np (the trimmed logistic) by uc remapped. Returns false when
 * nothing can be sampled. */
bool hair_sample(const HairLobe *l, Vec3 wo, float uc, Vec2 u, Vec3 *wi, float *pdf_w);
/* The same, and the lobe p that drew wi (0 R, 1 TT, 2 TRT, HAIR_P_MAX the residual). */
bool hair_sample_lobe(const HairLobe *l, Vec3 wo, float uc, Vec2 u, Vec3 *wi, float *pdf_w, int *lobe_p);

/* The longitudinal scattering function Mp (d'Eon et al. 2011, with the low-variance form
 * for v <= 0.1 of pbrt-v4); exposed for the tests. Symmetric in (i, o). */
float hair_mp(float cos_i, float cos_o, float sin_i, float sin_o, float v);

#endif
