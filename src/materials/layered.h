/* Layered BSDFs (pbrt-v4's coateddiffuse and coatedconductor): a dielectric interface over a
 * Lambertian or conductor base with a homogeneous slab of medium between them, evaluated
 * by the stochastic random walk of Guo, Hasan, Yan & Zhao 2018 ("Position-free Monte Carlo
 * simulation for arbitrary layered BSDFs"), as pbrt-v4's LayeredBxDF (book 4th ed.
 * sec. 14.3). Local shading frame, wo.z >= 0 (bsdf.c mirrors back-side queries first). */
#ifndef CST_MATERIALS_LAYERED_H
#define CST_MATERIALS_LAYERED_H

#include <stdbool.h>
#include <stdint.h>

#include "materials/material.h"
#include "math/color.h"
#include "math/vec3.h"

typedef struct LayeredLobe {
    Color reflectance; /* Lambertian base (coated diffuse): hemispherical reflectance */
    Color eta, k;      /* conductor base (coated conductor): complex IOR relative to the layer's
                        * medium (the scene's eta, k divided by top_eta, as pbrt-v4 does) */
    Color albedo;      /* the slab's single-scattering albedo; black: absorbing only */
    float top_eta;     /* interface: inside over outside IOR */
    float top_alpha;   /* interface GGX alpha; 0 = smooth (delta) */
    float base_alpha;  /* conductor base GGX alpha; 0 = smooth (delta) */
    float top_alpha_y, base_alpha_y; /* their widths along the frame's t (= the above unless
                                      * anisotropic; the above are along s) */
    float thickness;   /* optical thickness along the normal (sigma_t = 1 per unit) */
    float g;           /* Henyey-Greenstein asymmetry in (-1, 1) */
    int max_depth;     /* random-walk steps per estimate */
    int nsamples;      /* walks averaged per eval / pdf */
    bool conductor;    /* base: conductor (true) or Lambert (false) */
    /* Decorrelates the estimates of different hits (scene_bsdf sets it from the hit); the
     * random numbers of an eval or pdf are a hash of (seed, wo, wi), so the same query at
     * the same hit always returns the same number (see layered_eval). */
    uint64_t seed;
} LayeredLobe;

/* The lobe of a coated material (material.h) with a smooth or rough interface and base as
 * its roughness says (material_bsdf_alpha), seed 0. */
void layered_init(LayeredLobe *l, const Material *m);

/* `importance` below: the walk carries importance (bsdf.h's BSDF_IMPORTANCE, light paths)
 * rather than radiance; it changes the refractions' 1 / eta^2 factor. */
typedef struct LayeredSample {
    Color weight; /* f |cos_i| / pdf of the sampled path (an unbiased estimate, pbrt-v4's
                   * "pdfIsProportional" sample) */
    Vec3 wi;
    float pdf;    /* the path's density (delta: its discrete probability) */
    bool delta;   /* every scattering event on the path was specular */
    uint8_t lobe; /* BsdfLobe: coat reflection, or through the coat to the base and out */
} LayeredSample;

/* Stochastic estimate of f(wo, wi) |cos_i| (radiance when importance is false, else the
 * adjoint); its expectation is the layered BSDF. Deterministic: the random numbers come
 * from a hash of (seed, wo, wi), as pbrt-v4 seeds its RNG with Hash(seed, wo), Hash(wi). */
Color layered_eval(const LayeredLobe *l, Vec3 wo, Vec3 wi, bool importance);
/* pbrt-v4's stochastic estimate of the density of layered_sample's directions (per unit
 * solid angle), mixed 9:1 with the uniform density over the hemisphere so it is never 0
 * where f may be > 0. It approximates the density, it is not its expectation: the MIS
 * weights that use it stay unbiased because every query of the same (seed, wo, wi) gets
 * the same number, so the weights of the strategies still sum to one. Deterministic like
 * layered_eval (the hash takes wi first, so pdf(wo, wi) and pdf(wi, wo) differ). */
float layered_pdf(const LayeredLobe *l, Vec3 wo, Vec3 wi);
/* A random walk from wo: false when the path is absorbed, stopped by Russian roulette or
 * by max_depth. uc and u drive the first interface sample and seed the walk. */
bool layered_sample(const LayeredLobe *l, Vec3 wo, float uc, Vec2 u, bool importance, LayeredSample *out);
/* True when every path is specular (smooth interface, smooth conductor, black albedo). */
bool layered_is_delta(const LayeredLobe *l);
/* The probability that layered_sample returns a delta sample when the paths that are
 * specular only through the interface reflection (smooth interface, rough or Lambertian
 * base): the interface's Fresnel reflectance. With a smooth interface, a smooth conductor
 * and a scattering slab some walks through the slab are specular too, which this omits. */
float layered_delta_probability(const LayeredLobe *l, float cos_o);

/* The Henyey-Greenstein phase function (Henyey & Greenstein 1941) in pbrt-v4's convention:
 * wo and wi both point away from the scattering point, so forward scattering (g > 0) peaks
 * at wi = -wo. Per unit solid angle; integrates to 1 over the sphere. */
float layered_hg_pdf(Vec3 wo, Vec3 wi, float g);
Vec3 layered_hg_sample(Vec3 wo, float g, Vec2 u);

#endif
