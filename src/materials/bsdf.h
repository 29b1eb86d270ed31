/* BSDFs at a surface point: a tagged union evaluated in the local shading frame.
 * Conventions (pbrt-v4's): wo points away from the surface toward the previous vertex,
 * wi toward the next; both world-space unit vectors at the API. bsdf_eval returns
 * f(wo, wi) * |cos theta_i|; pdfs are per unit solid angle. Delta lobes (mirror, smooth
 * glass) have eval = pdf = 0 and are reached only through bsdf_sample. */
#ifndef CST_MATERIALS_BSDF_H
#define CST_MATERIALS_BSDF_H

#include <stdbool.h>

#include "materials/material.h"
#include "math/frame.h"
#include "math/rgb.h"

typedef struct Bsdf {
    MaterialType type;
    Frame frame; /* n = the outward geometric/shading normal (glass: the outside) */
    Rgb albedo;
    float eta;   /* glass: inside over outside IOR */
} Bsdf;

/* What a path carries, which decides the adjoint of a non-reciprocal lobe (Veach thesis
 * ch. 5, pbrt-v4 TransportMode): camera paths carry radiance, light paths importance. */
typedef enum BsdfTransport {
    BSDF_RADIANCE,  /* camera paths: wo toward the camera side */
    BSDF_IMPORTANCE /* light paths: wo toward the light side */
} BsdfTransport;

typedef struct BsdfSample {
    Vec3 wi;      /* world space */
    Rgb weight;   /* f * |cos theta_i| / pdf */
    float pdf;    /* solid angle; for delta lobes, the discrete probability of the lobe */
    bool delta;
} BsdfSample;

void bsdf_init(Bsdf *b, const Material *m, Vec3 n);
static inline bool bsdf_is_delta(const Bsdf *b) { return b->type != MATERIAL_DIFFUSE; }
Rgb bsdf_eval(const Bsdf *b, Vec3 wo, Vec3 wi);
float bsdf_pdf(const Bsdf *b, Vec3 wo, Vec3 wi);
/* uc picks a lobe (glass: reflect vs refract), u samples a direction. Returns false for
 * no usable sample (e.g. wo exactly in the tangent plane). For camera paths. */
bool bsdf_sample(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfSample *out);
/* The same for either transport: the weight is f(wo, wi) |cos theta_i| / pdf for
 * BSDF_RADIANCE and the adjoint f*(wo, wi) |cos theta_i| / pdf = f(wi, wo) |cos theta_i| / pdf
 * for BSDF_IMPORTANCE. They differ only in refraction, by the factor 1/eta^2. */
bool bsdf_sample_transport(const Bsdf *b, Vec3 wo, float uc, Vec2 u, BsdfTransport mode,
                           BsdfSample *out);

/* Unpolarised Fresnel reflectance of a smooth dielectric interface; cos_i is the cosine
 * on the incident side (sign picks the side), eta = inside over outside IOR. */
float fresnel_dielectric(float cos_i, float eta);

#endif
