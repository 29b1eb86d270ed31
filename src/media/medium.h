/* Participating media: the scene's Medium (a tagged union: homogeneous, or heterogeneous in
 * media/hetero_medium.h), the interfaces that shapes put between two media, and the two
 * queries a path tracer asks of a medium: transmittance along a segment and a sampled
 * free-flight distance. */
#ifndef CST_MEDIA_MEDIUM_H
#define CST_MEDIA_MEDIUM_H

#include <stdbool.h>
#include <stdint.h>

#include "math/color.h"
#include "math/spectrum.h"
#include "media/hetero_medium.h"

/* MEDIUM_GRID and MEDIUM_CLOUD: u.het (HeteroMedium.cloud tells them apart too). */
typedef enum MediumType { MEDIUM_HOMOGENEOUS, MEDIUM_GRID, MEDIUM_CLOUD } MediumType;

/* Coefficients per unit length of the scene (1/m when the scene is in metres), already
 * multiplied by pbrt's "scale"; linear RGB (sRGB primaries), upsampled in spectral mode. */
typedef struct HomogeneousMedium {
    Color sigma_a, sigma_s; /* absorption and scattering, >= 0 */
    Color le;               /* emitted radiance (pbrt-v4's Le x Lescale); the medium adds
                             * sigma_a Le per unit length (the emission term of the RTE) */
} HomogeneousMedium;

/* A medium's sigma_a, sigma_s (unbounded) and Le (illuminant) spectra, looked up once by
 * medium_prepare_spectra: the RGB-to-spectrum table lookup is most of a conversion's cost,
 * and spectral paths convert at every medium they enter and on every shadow ray through
 * one (scene_transmittance_at). ready false: medium_coeffs converts from the RGB values. */
typedef struct MediumSpectra {
    SpectrumRgb sigma_a, sigma_s, le;
    bool ready;
} MediumSpectra;

typedef struct Medium {
    MediumType type;
    float g; /* Henyey–Greenstein asymmetry in (-1, 1) (media/phase.h) */
    union { HomogeneousMedium homog; HeteroMedium het; } u;
    MediumSpectra spec; /* medium_prepare_spectra; the scene fills it when the medium is added */
} Medium;

/* Fills m->spec from m's coefficients (call again after changing them). */
void medium_prepare_spectra(Medium *m);

/* What a shape separates (pbrt-v4 MediumInterface): the medium on the side opposite its
 * geometric normal (inside) and on the normal's side (outside); -1 = vacuum. boundary:
 * the shape is nothing but that boundary (pbrt's "interface" material): rays cross it
 * without scattering and shadow rays pass it. */
typedef struct MediumInterface {
    int32_t inside, outside;
    int32_t boundary;
} MediumInterface;

/* A medium's coefficients at a path's wavelengths (or in RGB), made once when a path
 * enters the medium: the queries below then do no conversion. Heterogeneous media: the
 * coefficients at density 1. */
typedef struct MediumCoeffs {
    Color sigma_a, sigma_s, sigma_t; /* per unit length */
    Color le;                        /* radiance; black when the medium does not emit */
    float g;
    bool emissive;
} MediumCoeffs;

/* m's coefficients in RGB mode (wl NULL) or at wl: sigma_a and sigma_s as unbounded
 * spectra, Le as an illuminant, the conversions materials and lights use. */
MediumCoeffs medium_coeffs(const Medium *m, const Wavelengths *wl);

/* Transmittance exp(-sigma_t d) per lane along a segment of length d (Beer–Lambert). */
Color medium_transmittance(const MediumCoeffs *m, float d);

/* A free-flight sample along a ray with its surface at t_max (INFINITY for none). */
typedef struct MediumSample {
    float t;        /* the scattering distance, or t_max when the ray reaches its surface */
    bool scattered; /* t < t_max: a real scattering event in the medium */
    Color weight;   /* the estimator's factor: scattered: Tr(t) sigma_s / pdf(t);
                     * else Tr(t_max) / P(t >= t_max) */
    Color tr_pdf;   /* scattered: Tr(t) / pdf(t), the factor of the emission term
                     * (times sigma_a Le); else unset */
    Color le;       /* heterogeneous media only: the segment's emission estimate (times the
                     * path throughput), gathered whether or not it scattered */
    Color r;        /* heterogeneous media only: p_c / p_hero of the segment (hetero_medium.h) */
} MediumSample;

/* Distance sampling for the path tracer: one lane c picked uniformly from the four (u_ch;
 * in RGB mode lane 3 repeats green) and t ~ sigma_t[c] exp(-sigma_t[c] t). The density
 * used is the mixture over lanes, pdf(t) = 1/4 sum_c sigma_t[c] exp(-sigma_t[c] t) per
 * unit length, with P(t >= t_max) = 1/4 sum_c exp(-sigma_t[c] t_max): the balance
 * heuristic over channels (one-sample MIS, Veach eq. 9.15; Mitsuba's and PBRT-v3's
 * HomogeneousMedium::Sample), unbiased for every lane, also where another lane's
 * sigma_t is 0. u in [0,1). */
void medium_sample_distance(const MediumCoeffs *m, float t_max, float u_ch, float u, MediumSample *out);

/* The density medium_sample_distance gives t < t_max (per unit length), and the
 * probability that it passes t_max. */
float medium_distance_pdf(const MediumCoeffs *m, float t);
float medium_pass_prob(const MediumCoeffs *m, float t_max);

/* True for the media tracked by hetero_sample_distance and hetero_transmittance
 * (u.het); homogeneous ones use the closed forms above. */
static inline bool medium_is_hetero(const Medium *m) { return m->type != MEDIUM_HOMOGENEOUS; }

/* Frees what a medium owns (heterogeneous grids); m may be zeroed. */
void medium_release(Medium *m);

#endif
