/* The GGX (Trowbridge-Reitz) microfacet distribution, anisotropic: normal distribution,
 * Smith masking-shadowing, and sampling of the distribution of visible normals.
 * Local shading space, macro normal +z; ax and ay are the GGX widths along the frame's
 * x axis (the tangent dp/du when the BSDF is anisotropic) and y axis (see material.h for
 * how a scene's roughness maps to them); ax = ay > 0 is the isotropic distribution, whose
 * values do not depend on the frame's rotation about z. */
#ifndef CST_MATERIALS_MICROFACET_H
#define CST_MATERIALS_MICROFACET_H

#include <stdbool.h>

#include "math/vec3.h"

/* D(m): microfacet normals per unit solid angle and unit projected macro area, for m.z > 0
 * (Walter et al. 2007 eq. 33; Trowbridge & Reitz 1975; anisotropic: Heitz 2014,
 * "Understanding the Masking-Shadowing Function", eq. 85). Normalised: int D(m) m.z dm = 1. */
float ggx_d(Vec3 m, float ax, float ay);
/* Smith's Lambda for GGX (Heitz 2014 eq. 86, with the anisotropic alpha of the projected
 * direction, eq. 80): symmetric in the sign of w.z. */
float ggx_lambda(Vec3 w, float ax, float ay);
/* Smith masking G1(w) = 1 / (1 + Lambda(w)). */
float ggx_g1(Vec3 w, float ax, float ay);
/* Height-correlated masking-shadowing G2(wo, wi) = 1 / (1 + Lambda(wo) + Lambda(wi))
 * (Heitz 2014 eq. 99). Exact for reflection under Smith's assumptions; for transmission
 * Heitz's eq. 101 would need a Beta function, and we use the same form there (as
 * pbrt-v4 does). Symmetric, so reciprocity holds. */
float ggx_g2(Vec3 wo, Vec3 wi, float ax, float ay);

/* A microfacet normal m from the distribution of normals visible from wo, wo.z > 0:
 *   D_wo(m) = G1(wo) max(0, wo.m) D(m) / wo.z
 * (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4), eq. 2;
 * the sampling routine is its listing 1, which stretches by ax and ay separately). */
Vec3 ggx_sample_visible(Vec3 wo, float ax, float ay, Vec2 u);
/* D_wo(m) per unit solid angle of m; wo.z != 0 (|wo.z| and |wo.m| are used). */
float ggx_visible_pdf(Vec3 wo, Vec3 m, float ax, float ay);

/* Mirror reflection of w about the unit vector m. */
static inline Vec3 reflect_about(Vec3 w, Vec3 m) { return v3_sub(v3_scale(m, 2.0f * v3_dot(w, m)), w); }

/* Refraction of w (pointing away from the surface) through the interface with unit normal
 * m, eta = IOR on m's back side over IOR on its front side. Works for w on either side of
 * m; *etap gets the relative IOR actually crossed (eta or 1/eta). Returns false on total
 * internal reflection. Snell's law in vector form (pbrt-v4 sec. 9.3.2). */
static inline bool refract_about(Vec3 w, Vec3 m, float eta, Vec3 *wt, float *etap)
{
    float cos_i = v3_dot(w, m);
    if (cos_i < 0.0f) { eta = 1.0f / eta; cos_i = -cos_i; m = v3_neg(m); }
    float sin2_t = (1.0f - cos_i * cos_i) / (eta * eta);
    if (sin2_t >= 1.0f) return false;
    float cos_t = safe_sqrtf(1.0f - sin2_t);
    *wt = v3_add(v3_scale(v3_neg(w), 1.0f / eta), v3_scale(m, cos_i / eta - cos_t));
    *etap = eta;
    return true;
}

#endif
