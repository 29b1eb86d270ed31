/* Heterogeneous media: pbrt-v4's "uniformgrid" (a density grid, trilinear, over a box in
 * the medium's space) and "cloud" (its procedural noise cloud), their majorant grids, and
 * the two estimators the path tracer needs: delta tracking for free-flight distances and
 * ratio tracking for transmittance (Novák et al. 2014, "Residual ratio tracking for
 * estimating attenuation in participating media"; Novák et al. 2018, "Monte Carlo methods
 * for volumetric light transport simulation", sec. 5 and 6). */
#ifndef CST_MEDIA_HETERO_MEDIUM_H
#define CST_MEDIA_HETERO_MEDIUM_H

#include <stdbool.h>
#include <stdint.h>

#include "math/color.h"
#include "math/transform.h"
#include "math/vec3.h"
#include "media/majorant.h"

/* sigma(p) = density(p) x (sigma_a, sigma_s) per unit length of the scene. */
typedef struct HeteroMedium {
    Color sigma_a, sigma_s;      /* at density 1, pbrt's "scale" applied, >= 0 */
    Color le;                    /* uniformgrid: emitted radiance where Lescale is 1 */
    Transform medium_from_world; /* affine; t along a ray is the same in both spaces */
    Vec3 p0, p1;                 /* the medium's box in its own space, p0 < p1 */
    bool cloud;                  /* false: uniformgrid; true: pbrt-v4's "cloud" */
    int n[3];                    /* uniformgrid: samples per axis (nx, ny, nz) */
    float *density;              /* uniformgrid: n[0] n[1] n[2] values >= 0, x fastest; owned */
    float *le_scale;             /* uniformgrid: the "Lescale" grid (same shape), or NULL */
    float le_scale_1;            /* ... NULL: the constant Lescale */
    float cloud_density, wispiness, frequency; /* cloud: pbrt-v4's parameters */
    MajorantGrid maj;            /* built by hetero_medium_prepare; owned */
} HeteroMedium;

/* Builds h->maj from the density (16^3 cells for a grid, as pbrt-v4; one cell bounded by 1
 * for the cloud, whose density is clamped to [0, 1]). false on OOM. */
bool hetero_medium_prepare(HeteroMedium *h);
/* NULL when h (its arrays given, maj not yet built) is a valid medium, else what is wrong
 * with it: coefficients finite and >= 0, p0 < p1, an affine transform, a grid of 1 ..
 * 4096 samples per axis with finite densities (and Lescale values) >= 0. */
const char *hetero_medium_invalid(const HeteroMedium *h);
/* dst = src with its own copies of the arrays and its majorant grid built; false on OOM
 * (dst then owns nothing). */
bool hetero_medium_clone(HeteroMedium *dst, const HeteroMedium *src);
/* Frees what h owns (density, le_scale, maj); h may be zeroed. */
void hetero_medium_release(HeteroMedium *h);

/* pbrt-v4's SampledGrid::Lookup: trilinear between samples at cell centres ((i + 0.5) /
 * n); samples outside the grid count as 0, so the density falls off within half a sample
 * spacing of the box's faces. u in the box's unit cube. */
float hetero_grid_lookup(const float *v, const int n[3], Vec3 u);
/* The density at p (medium space): the grid's, 0 outside the box; or the cloud's. */
float hetero_density(const HeteroMedium *h, Vec3 p_medium);

struct MediumCoeffs;
struct MediumSample;

/* Delta tracking along o + t d (world space, d unit length) over [0, t_max] (t_max may be
 * INFINITY): tentative collisions at rate sigma_t[hero] x majorant, real with probability
 * density / majorant (the same in every lane, since sigma_t = density x a constant colour).
 * Spectral MIS over the lanes as pbrt-v4's volpath (Miller, Georgiev & Jarosz 2019, "A
 * null-scattering path integral formulation of light transport", sec. 5.2): out->weight
 * is f_c / p_hero per lane and out->r = p_c / p_hero, the lanes' densities of the
 * collision sequence relative to the hero's; the path multiplies its throughput by weight
 * and its ratios by r, and divides every contribution by the mean ratio (the balance
 * heuristic over lanes for the whole path). Emission sigma_a Le is gathered at every
 * tentative collision (out->le: already divided by the mean of r_path x the segment's
 * ratios; to be multiplied by the throughput). u seeds the rest of the random numbers. */
void hetero_sample_distance(const HeteroMedium *h, const struct MediumCoeffs *mc, Vec3 o, Vec3 d, float t_max,
                            int hero, Color r_path, float u, struct MediumSample *out);

/* Ratio tracking of the transmittance along o + t d over [0, t_max] (finite), with one
 * majorant for every lane (the largest lane's sigma_t x the cell bound), so each lane's
 * estimate is the product of its 1 - sigma_t / majorant at the collisions; Russian roulette
 * once every lane's estimate is below 0.05 (pbrt-v4's volpath). Unbiased per lane. seed:
 * the random stream (any value, e.g. a hash of the segment). */
Color hetero_transmittance(const HeteroMedium *h, const struct MediumCoeffs *mc, Vec3 o, Vec3 d, float t_max,
                           uint64_t seed);

/* The density at world point p (hetero_density after the medium's transform). */
float hetero_density_world(const HeteroMedium *h, Vec3 p_world);
/* The factor of the medium's sigma_a Le at world point p: the density there times the
 * Lescale there (its grid's or the constant), as hetero_sample_distance gathers it. */
float hetero_emission_world(const HeteroMedium *h, Vec3 p_world);

/* The integral of the majorant grid's density bound along o + t d over [0, t_max] (world
 * space, d unit length; t_max may be INFINITY): the optical depth of the majorant at
 * density 1, to be multiplied by sigma_t. Deterministic (no random numbers) and, up to
 * rounding, the same for the segment walked either way: the bidirectional integrators'
 * MIS densities of grid media are made from it (subpath_media.c). */
float hetero_majorant_depth(const HeteroMedium *h, Vec3 o, Vec3 d, float t_max);

#endif
