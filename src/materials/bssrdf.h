/* The tabulated BSSRDF of pbrt-v4's subsurface material (pbrt 4th ed. sec. 11.4): the
 * photon-beam-diffusion radial profile (Habel, Christensen & Jarosz 2013; d'Eon & Irving
 * 2011), its evaluation Sp(r), sampling of r, the probe segments and their pdf, and Sw. */
#ifndef CST_MATERIALS_BSSRDF_H
#define CST_MATERIALS_BSSRDF_H

#include <stdbool.h>

#include "math/color.h"
#include "math/frame.h"
#include "math/vec3.h"

/* pbrt-v4's table size (SubsurfaceMaterial: BSSRDFTable(100, 64)). */
#define BSSRDF_NUM_RHO 100
#define BSSRDF_NUM_RADIUS 64

/* The profile of a unit-extinction medium (sigma_t = 1), so radii are optical (r sigma_t):
 * profile[i][j] = 2 pi r_j Sr(rho_i, r_j) (the radial density, with its circumference),
 * profile_cdf its running integral over r by the Catmull-Rom spline, and rho_eff[i] the
 * whole integral: the diffuse reflectance (effective albedo) of single-scattering albedo
 * rho_i. Made for one (g, eta); about 1.3 M exponentials, computed once per material. */
typedef struct BssrdfTable {
    float g, eta;
    float rho[BSSRDF_NUM_RHO];
    float radius[BSSRDF_NUM_RADIUS];
    float profile[BSSRDF_NUM_RHO * BSSRDF_NUM_RADIUS];
    float profile_cdf[BSSRDF_NUM_RHO * BSSRDF_NUM_RADIUS];
    float rho_eff[BSSRDF_NUM_RHO];
} BssrdfTable;

void bssrdf_table_build(BssrdfTable *t, float g, float eta);

/* The two parts of the profile at optical radius r of a medium of albedo rho = sigma_s /
 * sigma_t with sigma_t = 1 (per unit area, without the 2 pi r): single scattering (pbrt
 * BeamDiffusionSS) and multiple scattering by photon beam diffusion (BeamDiffusionMS). */
float bssrdf_beam_ss(float sigma_s, float sigma_a, float g, float eta, float r);
float bssrdf_beam_ms(float sigma_s, float sigma_a, float g, float eta, float r);

/* Fresnel moments int_0^1 F(mu) mu^i dmu, i = 1, 2, as d'Eon & Irving's (2011) fifth-
 * order polynomial fits in eta. */
float bssrdf_fresnel_moment1(float eta);
float bssrdf_fresnel_moment2(float eta);

/* The single-scattering albedo whose rho_eff is rho_eff (the spline of rho_eff over rho,
 * inverted by Newton-bisection; pbrt InvertCatmullRom), clamped to the table's ends. */
float bssrdf_invert_rho_eff(const BssrdfTable *t, float rho_eff);
/* sigma_a, sigma_s of a medium of diffuse reflectance r and mean free path mfp (= 1 /
 * sigma_t) per lane (pbrt SubsurfaceFromDiffuse). */
void bssrdf_from_reflectance(const BssrdfTable *t, Color r, Color mfp, Color *sigma_a, Color *sigma_s);

/* The BSSRDF at an entry point po with shading normal ns, for the path's lanes. */
typedef struct Bssrdf {
    const BssrdfTable *table;
    Color sigma_t, rho; /* per unit length of the scene; rho = sigma_s / sigma_t */
    float eta;
    Vec3 po;
    Frame frame; /* of ns: the probe axes */
} Bssrdf;

void bssrdf_init(Bssrdf *b, const BssrdfTable *t, Color sigma_a, Color sigma_s, Vec3 po, Vec3 ns);

/* Sr(r) per lane: the exitance per unit area at distance r (scene units) from the entry
 * point, for unit incident flux (1 / area). */
Color bssrdf_sr(const Bssrdf *b, float r);
/* A radius from lane c's profile (inverse CDF of the 2D spline), or < 0 when the lane
 * scatters nothing. */
float bssrdf_sample_sr(const Bssrdf *b, int c, float u);
/* Its density per unit area of the plane (pdf_a): Sr_c(r) / rho_eff_c. */
float bssrdf_pdf_sr(const Bssrdf *b, int c, float r);

/* A probe segment p0 -> p1: an axis of the entry frame (probabilities 1/4, 1/4 and 1/2 for
 * the normal, pbrt-v4's choice) and a lane (uniform over COLOR_LANES) from u1; r from that
 * lane, phi from u2; the segment crosses the sphere of radius r_max (the lane's 0.999
 * quantile) around po at distance r from the axis through po. False when none. */
bool bssrdf_sample_probe(const Bssrdf *b, float u1, Vec2 u2, Vec3 *p0, Vec3 *p1);
/* The density per unit area (pdf_a) of finding pi, normal ni, by bssrdf_sample_probe: the
 * mixture over the 3 axes and the lanes of pdf_sr of pi's distance from the axis, times
 * |cos| between ni and the axis (one-sample MIS, balance heuristic, as pbrt-v3/v4). */
float bssrdf_pdf_sp(const Bssrdf *b, Vec3 pi, Vec3 ni);

/* Sw(cos_i) = (1 - F(cos_i)) / (c pi), c = 1 - 2 FM1(1 / eta): the normalised Fresnel
 * lobe of the exit point (pbrt NormalizedFresnelBxDF), cos_i > 0 on the outside. */
float bssrdf_sw(float eta, float cos_i);

#endif
