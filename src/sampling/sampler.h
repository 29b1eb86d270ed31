/* Per-pixel-sample random numbers for camera paths: independent (PCG32), stratified
 * (jittered) and Owen-scrambled Sobol'. A Sampler is a value started once per (pixel,
 * sample index) and read dimension by dimension, so every draw is a function of
 * (seed, pixel, sample index, dimension) alone, whatever thread renders the pixel. */
#ifndef CST_SAMPLING_SAMPLER_H
#define CST_SAMPLING_SAMPLER_H

#include <stdint.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "math/vec3.h"
#include "sampling/pss_sampler.h"

/* The type of a Sampler that reads a Metropolis chain's primary sample space (pss, below):
 * not a CstSampler a user can pick, so outside that enum's values. */
#define SAMPLER_PSS ((CstSampler)0x100)

typedef struct Sampler {
    /* The PCG32 stream of the sample, pcg32_seed_sample(seed, pixel, index) for every type.
     * The independent sampler draws from it; the others leave it for code that still takes
     * a Pcg32 (the photon and BDPT/VCM camera paths continue from it after the film and
     * lens dimensions). */
    Pcg32 rng;
    CstSampler type;   /* never CST_SAMPLER_DEFAULT */
    uint32_t dim;      /* the next dimension (stratified, sobol) */
    uint32_t index;    /* the sample index within the pixel */
    uint32_t spp;      /* stratified: the sample count the strata divide; 0 = unknown */
    uint32_t nx;       /* stratified: 2D strata are nx x (spp / nx) */
    uint64_t key;      /* hash of (seed, pixel): seeds every per-dimension scramble */
    PssSampler *pss;   /* SAMPLER_PSS: the chain's state every draw reads (MLT) */
} Sampler;

/* What every camera sample of a render shares: the sampler type, the seed and the sample
 * count, with the stratified sampler's 2D grid worked out from that count once, by
 * sampler_setup, not per sample: finding the grid is a divisor search of O(sqrt(spp)) steps,
 * which at spp = 2^31 - 1 took 46,000 steps per sample (issue 25). */
typedef struct SamplerSetup {
    CstSampler type;   /* never CST_SAMPLER_DEFAULT */
    uint64_t seed;
    uint32_t spp;      /* stratified: the sample count the strata divide; 0 = unknown */
    uint32_t nx;       /* stratified: 2D strata are nx x (spp / nx); 1 otherwise */
} SamplerSetup;

/* The setup of a render's camera samples: `spp` per pixel (the stratified sampler divides
 * [0,1) into that many strata; 0 = not known in advance, e.g. a render with only a time
 * limit, and then it jitters without strata). type CST_SAMPLER_DEFAULT means independent. */
SamplerSetup sampler_setup(CstSampler type, uint64_t seed, uint32_t spp);
/* Starts sample `index` of `pixel`; O(1) for every type. */
void sampler_start(Sampler *s, const SamplerSetup *setup, uint64_t pixel, uint32_t index);
/* An independent sampler on the PCG32 stream (seed, a, b): the random numbers of every
 * path that is not a pixel sample (light subpaths, photons), so that every integrator
 * draws through one type. */
static inline void sampler_start_stream(Sampler *s, uint64_t seed, uint64_t a, uint64_t b)
{
    pcg32_seed_sample(&s->rng, seed, a, b);
    s->type = CST_SAMPLER_INDEPENDENT;
    s->dim = s->index = s->spp = 0;
    s->nx = 1;
    s->key = 0;
}
/* An independent sampler continuing from `rng`: camera paths of the photon mapper and
 * BDPT/VCM draw past the film and lens dimensions from their pixel sample's PCG32
 * stream, whatever the sampler (their strategies are not stratified). */
static inline Sampler sampler_continue(Pcg32 rng)
{
    Sampler s = {rng, CST_SAMPLER_INDEPENDENT, 0, 0, 0, 1, 0, NULL};
    return s;
}
/* A sampler whose every draw is the next value of the chain's current stream: how the
 * path tracer's estimate runs over MLT's primary sample space (integrators/mlt.c). Draws
 * take the slow branch of sampler_1d/2d, so the other samplers' inline path is unchanged. */
static inline Sampler sampler_pss(PssSampler *pss)
{
    Sampler s = {{0, 1}, SAMPLER_PSS, 0, 0, 0, 1, 0, pss};
    return s;
}
/* The stratified, Sobol' and primary-sample-space draws (sampler.c); sampler_1d/2d call them. */
float sampler_1d_ld(Sampler *s);
Vec2 sampler_2d_ld(Sampler *s);

/* The next dimension, uniform in [0, 1). Inline for the default independent sampler, the
 * path tracer's inner loop draws several per bounce. */
static inline float sampler_1d(Sampler *s)
{
    if (s->type == CST_SAMPLER_INDEPENDENT || s->type == CST_SAMPLER_DEFAULT) return pcg32_float(&s->rng);
    return sampler_1d_ld(s);
}

/* The next two dimensions, uniform in [0, 1)^2 and stratified jointly. */
static inline Vec2 sampler_2d(Sampler *s)
{
    if (s->type == CST_SAMPLER_INDEPENDENT || s->type == CST_SAMPLER_DEFAULT) {
        /* y first: the order GCC gave the v2(pcg32_float(), pcg32_float()) this replaced
         * (arguments evaluated right to left), so independent images stay bit-identical. */
        float y = pcg32_float(&s->rng);
        float x = pcg32_float(&s->rng);
        return v2(x, y);
    }
    return sampler_2d_ld(s);
}

/* Sobol' point `index` in dimension 0 or 1, as a 32-bit fraction (unscrambled). */
uint32_t sobol_sample(uint32_t index, int dim);
/* Nested uniform (Owen) scramble of a 32-bit fraction in base 2, seeded (Burley 2020). */
uint32_t owen_scramble(uint32_t x, uint32_t seed);
/* A pseudo-random permutation of [0, n) (Kensler 2013): the image of i for key p. */
uint32_t permute_index(uint32_t i, uint32_t n, uint32_t p);

#endif
