/* Per-pixel-sample random numbers for camera paths: independent (PCG32), stratified
 * (jittered), Owen-scrambled Sobol' and ZSobol' (Sobol' over Morton-ordered pixels). A Sampler is a value started once per (pixel,
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

/* zsobol: what one dimension's permutation and scrambles take from its 64-bit hash
 * (sampler_setup works them out once per render). */
typedef struct ZSobolDim {
    uint64_t swap, shear;  /* digits whose hi and lo bits are swapped, or hi ^= lo */
    uint64_t add, mul;     /* the nested scramble's seed terms (mul odd) */
    uint32_t seed, seed_y; /* the Owen scrambles' seeds: x, and y's xor with x's */
} ZSobolDim;

/* zsobol draws every dimension from Sobol' (as pbrt-v4's ZSobolSampler does), in blocks of
 * ZSOBOL_BLOCK dimensions: ZSOBOL_BLOCK / 2 2D points computed together, the first block at
 * sampler_start (film, lens, wavelengths, the first bounce and a half of the path tracer),
 * the next when a request passes the end of the last. Computed together the points overlap
 * in the pipeline, and their 32-bit halves run as the lanes of one SIMD register (sampler.c,
 * zsobol_block); one at a time each request would wait ~50 cycles on its chain of
 * multiplies where a PCG32 draw waits ~6. A 2D request starts at an even dimension (an odd
 * one is skipped), so it is always one Sobol' point, never split across blocks. */
#define ZSOBOL_BLOCK 16u
/* A block's points: one SIMD register of 32-bit lanes (AVX2: 8). */
#define ZSOBOL_LANES (ZSOBOL_BLOCK / 2u)
/* The points whose permutation and scrambles sampler_setup keeps (the first 64 dimensions:
 * 8 bounces of the path tracer); deeper points derive theirs from the hash when drawn. */
#define ZSOBOL_TABLE 32u

/* zsobol: the ZSobolDims of a block's ZSOBOL_LANES points, one array per field, so that
 * zsobol_block loads each field of all its points as one SIMD vector. */
typedef struct ZSobolLanes {
    uint64_t swap[ZSOBOL_LANES], shear[ZSOBOL_LANES], add[ZSOBOL_LANES], mul[ZSOBOL_LANES];
    uint32_t seed[ZSOBOL_LANES], seed_y[ZSOBOL_LANES];
} ZSobolLanes;

struct SamplerSetup;

typedef struct Sampler {
    /* The PCG32 stream of the sample, pcg32_seed_sample(seed, pixel, index), for every type
     * but zsobol, whose draws never need it (it is seeded only when sampler_continue_sample
     * asks: four mix64 a sample saved, about 1% of a Cornell box render).
     * The independent sampler draws from it; the others leave it for code that still takes
     * a Pcg32 (the photon and BDPT/VCM camera paths continue from it after the film and
     * lens dimensions: sampler_continue_sample). */
    Pcg32 rng;
    CstSampler type;   /* never CST_SAMPLER_DEFAULT */
    uint32_t dim;      /* the next dimension (stratified, sobol) */
    uint32_t index;    /* the sample index within the pixel */
    uint32_t spp;      /* stratified: the sample count the strata divide; 0 = unknown */
    uint32_t nx;       /* stratified: 2D strata are nx x (spp / nx) */
    uint64_t key;      /* hash of (seed, pixel): seeds every per-dimension scramble
                        * (zsobol: of the seed alone, the pixel is in zrev) */
    uint64_t zrev;     /* zsobol: the sample's Morton index (sampler_start), bit-reversed */
    uint32_t zend;     /* zsobol: the end of the block of dimensions in zval */
    uint64_t pixel;    /* zsobol: the sample's pixel (to seed rng when asked) */
    const struct SamplerSetup *zsetup; /* zsobol: the render's setup (the points' hashes) */
    float zval[ZSOBOL_BLOCK]; /* zsobol: dimensions zend - ZSOBOL_BLOCK .. zend - 1 */
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
    uint32_t width;    /* zsobol: the image width, to find (x, y) from the pixel index */
    uint32_t morton_bits; /* zsobol: 2 log2 of the image's larger side, rounded up */
    uint64_t zkey;     /* zsobol: hash of the seed; point k's hash is mix64(zkey + k * phi) */
    /* zsobol: the first ZSOBOL_TABLE points' ZSobolDims, from hashes of (seed, point) */
    ZSobolLanes zblocks[ZSOBOL_TABLE / ZSOBOL_LANES];
} SamplerSetup;

/* zsobol: the sample indices of a pixel form blocks of 2^ZSOBOL_LOG2_BLOCK in the Morton
 * order, so the first 2^k <= 256 samples of every pixel are a (0, k, 2)-net in every 2D
 * request, and the 256 samples of a block of 2^j x 2^j pixels are a (0, 8 + 2j, 2)-net:
 * the pixels' errors are negatively correlated (blue noise, Ahmed & Wonka 2020) at 256 spp.
 * pbrt-v4 sizes the block by the render's spp instead; a fixed size keeps every sample a
 * function of (seed, pixel, index) alone, so a render resumed to more samples, or stopped
 * early, equals one of that count in one go. Samples past 256 start new blocks. */
#define ZSOBOL_LOG2_BLOCK 8u

/* The setup of a render's camera samples: `spp` per pixel (the stratified sampler divides
 * [0,1) into that many strata; 0 = not known in advance, e.g. a render with only a time
 * limit, and then it jitters without strata) on a width x height image (zsobol orders its
 * pixels; 1..65536 each). type CST_SAMPLER_DEFAULT means zsobol, the library default. */
SamplerSetup sampler_setup(CstSampler type, uint64_t seed, uint32_t spp, int width, int height);
/* Starts sample `index` of `pixel`; O(1) for every type. A zsobol Sampler reads *setup
 * until its last draw (the hashes of blocks past the first), so setup must outlive s. */
void sampler_start(Sampler *s, const SamplerSetup *setup, uint64_t pixel, uint32_t index);
/* zsobol: the Morton index of sample `index` of `pixel` (sampler.c), before reversal. */
uint64_t zsobol_morton_index(const SamplerSetup *setup, uint64_t pixel, uint32_t index);
/* zsobol: the permutation and scrambles of 2D point k (dimensions 2k, 2k + 1), from the
 * setup's table or, past it, from the hash. */
ZSobolDim zsobol_dim(const SamplerSetup *setup, uint32_t k);
/* zsobol: computes the block of dimensions that holds s->dim into s->zval (sampler.c). */
void zsobol_fill(Sampler *s);
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
    s->zrev = 0;
    s->zend = 0;
    s->pixel = 0;
    s->zsetup = NULL;
}
/* An independent sampler continuing from `rng`: camera paths of the photon mapper and
 * BDPT/VCM draw past the film and lens dimensions from their pixel sample's PCG32
 * stream, whatever the sampler (their strategies are not stratified). */
static inline Sampler sampler_continue(Pcg32 rng)
{
    Sampler s = {.rng = rng, .type = CST_SAMPLER_INDEPENDENT, .nx = 1};
    return s;
}
/* An independent sampler continuing from the PCG32 stream of pixel sample `s` (seeded here
 * for zsobol, which leaves it unseeded): the camera paths of the photon mapper and BDPT/VCM
 * past the film and lens dimensions. */
static inline Sampler sampler_continue_sample(const Sampler *s)
{
    Pcg32 r = s->rng;
    if (s->type == CST_SAMPLER_ZSOBOL) pcg32_seed_sample(&r, s->zsetup->seed, s->pixel, s->index);
    return sampler_continue(r);
}
/* A sampler whose every draw is the next value of the chain's current stream: how the
 * path tracer's estimate runs over MLT's primary sample space (integrators/mlt.c). Draws
 * take the slow branch of sampler_1d/2d, so the other samplers' inline path is unchanged. */
static inline Sampler sampler_pss(PssSampler *pss)
{
    Sampler s = {.rng = {0, 1}, .type = SAMPLER_PSS, .nx = 1, .pss = pss};
    return s;
}
/* The stratified, Sobol' and primary-sample-space draws (sampler.c); sampler_1d/2d call them. */
float sampler_1d_ld(Sampler *s);
Vec2 sampler_2d_ld(Sampler *s);

/* Bit reversal of a 32-bit word: a byte swap, then nibbles, pairs and bits. */
static inline uint32_t sampler_rev32(uint32_t x)
{
    x = __builtin_bswap32(x);
    x = ((x >> 4) & 0x0f0f0f0fu) | ((x & 0x0f0f0f0fu) << 4);
    x = ((x >> 2) & 0x33333333u) | ((x & 0x33333333u) << 2);
    return ((x >> 1) & 0x55555555u) | ((x & 0x55555555u) << 1);
}

/* The hash of owen_scramble without its two bit reversals: in it every bit depends only
 * on the bits below it, so on a bit-reversed fraction it is a nested uniform (Owen)
 * scramble (Burley 2020, after Laine & Karras 2011; constants Vegdahl 2021). */
static inline uint32_t owen_hash(uint32_t x, uint32_t seed)
{
    x ^= x * 0x3d20adeau;
    x += seed;
    x *= (seed >> 16) | 1u;
    x ^= x * 0x05526c56u;
    x ^= x * 0x53a22864u;
    return x;
}

/* Sobol' dimension 1 of index i, bit-reversed: sobol_sample(i, 1) == sampler_rev32(this).
 * Its generator is Pascal's matrix mod 2, whose entry (row r, column k) is C(k, r) mod 2,
 * odd exactly when the bits of r are a subset of those of k (Lucas's theorem); so bit r of
 * the reversed point is the parity of the index bits k that contain r: a superset-sum
 * (zeta) transform over the five bits of a bit position, one shift-and-xor per bit. */
static inline uint32_t sobol1_reversed(uint32_t i)
{
    i ^= (i >> 1) & 0x55555555u;
    i ^= (i >> 2) & 0x33333333u;
    i ^= (i >> 4) & 0x0f0f0f0fu;
    i ^= (i >> 8) & 0x00ff00ffu;
    i ^= i >> 16;
    return i;
}

/* zsobol: the sample's Morton index permuted for one dimension, still bit-reversed (Ahmed
 * & Wonka 2020 §4; pbrt-v4's ZSobolSampler permutes each base-4 digit by one of the 24
 * permutations, chosen by a hash of the digits above it and the dimension). Here the
 * permutation of a base-4 digit d = (hi, lo) is written, as every one of the 24 can be, as
 * an affine map of GF(2)^2, d -> A d + c:
 *  - A from bits of the dimension's hash, the same for all digits of one level (swap hi
 *    and lo with probability 1/2, then hi ^= lo with probability 5/16, so the sequence's
 *    halves go to the pixel rows, columns or diagonals with probability 11/32, 11/32,
 *    5/16: 1/3 each in pbrt-v4);
 *  - then a nested scramble of the bit-reversed index, a Laine-Karras hash on 64 bits: each
 *    bit is flipped by a hash of the more significant index bits, so c, and the lower
 *    triangle of A, are chosen per digit by the digits above it.
 * A permutation of digits that depends only on the digits above maps every aligned block
 * of 4^j indices onto another one, which is what keeps a pixel's samples, and a block of
 * pixels' samples, a Sobol' net. No loop over the digits: 12 integer operations. */
static inline uint64_t zsobol_permuted(uint64_t zrev, const ZSobolDim *d)
{
    uint64_t y = zrev;
    uint64_t t = (y ^ (y >> 1)) & d->swap;
    y ^= t | (t << 1);
    y ^= (y >> 1) & d->shear;
    y ^= y * 0x6c50b47cdb8a36d6ULL;
    y += d->add;
    y *= d->mul;
    y ^= y * 0xb82f1e52c0a7e73cULL;
    return y;
}

/* 32-bit fraction to a float in [0, 1): 24 bits, so 1.0f is never returned. */
static inline float sampler_u32_to_float(uint32_t x) { return (float)(x >> 8) * 0x1p-24f; }

/* zsobol, one Sobol' 2D point of the sample (zsobol_fill computes ZSOBOL_LANES of them): dimensions 0 and 1 of the low 32 bits of the index permuted for this pair, each
 * Owen-scrambled by its own seed. For van der Corput (dimension 0) the point is the
 * reversed index, so its scramble is reverse(owen_hash(index)). The seeds also take the
 * permuted index's bits above 32, constant over aligned blocks of 2^32 indices, so that
 * images of more than 2^32 samples do not repeat points. */
static inline void zsobol_point(uint64_t zrev, const ZSobolDim *d, float *out)
{
    uint64_t z = zsobol_permuted(zrev, d);
    uint32_t i = sampler_rev32((uint32_t)(z >> 32));
    uint32_t sx = d->seed ^ ((uint32_t)z * 0x9e3779b9u);
    out[0] = sampler_u32_to_float(sampler_rev32(owen_hash(i, sx)));
    out[1] = sampler_u32_to_float(sampler_rev32(owen_hash(sobol1_reversed(i), sx ^ d->seed_y)));
}

static inline float zsobol_1d(Sampler *s)
{
    if (s->dim >= s->zend) zsobol_fill(s);
    return s->zval[s->dim++ % ZSOBOL_BLOCK];
}

static inline Vec2 zsobol_2d(Sampler *s)
{
    s->dim += s->dim & 1u;
    if (s->dim >= s->zend) zsobol_fill(s);
    uint32_t k = s->dim % ZSOBOL_BLOCK;
    s->dim += 2;
    return v2(s->zval[k], s->zval[k + 1]);
}

/* The next dimension, uniform in [0, 1). Inline for the default independent sampler, the
 * path tracer's inner loop draws several per bounce. */
static inline float sampler_1d(Sampler *s)
{
    if (s->type == CST_SAMPLER_INDEPENDENT || s->type == CST_SAMPLER_DEFAULT) return pcg32_float(&s->rng);
    if (s->type == CST_SAMPLER_ZSOBOL) return zsobol_1d(s);
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
    if (s->type == CST_SAMPLER_ZSOBOL) return zsobol_2d(s);
    return sampler_2d_ld(s);
}

/* Sobol' point `index` in dimension 0 or 1, as a 32-bit fraction (unscrambled). */
uint32_t sobol_sample(uint32_t index, int dim);
/* Nested uniform (Owen) scramble of a 32-bit fraction in base 2, seeded (Burley 2020). */
uint32_t owen_scramble(uint32_t x, uint32_t seed);
/* A pseudo-random permutation of [0, n) (Kensler 2013): the image of i for key p. */
uint32_t permute_index(uint32_t i, uint32_t n, uint32_t p);

#endif
