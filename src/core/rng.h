/* Random numbers: PCG32 (O'Neill 2014, pcg32_srandom_r / pcg32_random_r) and a 64-bit
 * mixer that derives an independent stream from (seed, pixel, sample) so images do not
 * depend on which thread rendered which pixel. */
#ifndef CST_CORE_RNG_H
#define CST_CORE_RNG_H

#include <stdint.h>

#include "math/vec3.h"

typedef struct Pcg32 { uint64_t state, inc; } Pcg32;

#define PCG32_MULT 6364136223846793005ULL

static inline uint32_t pcg32_next(Pcg32 *r)
{
    uint64_t old = r->state;
    r->state = old * PCG32_MULT + r->inc;
    uint32_t x = (uint32_t)(((old >> 18u) ^ old) >> 27u);
    uint32_t rot = (uint32_t)(old >> 59u);
    return (x >> rot) | (x << ((-rot) & 31u));
}

/* Exactly pcg32_srandom_r of the reference implementation. */
static inline void pcg32_seed(Pcg32 *r, uint64_t initstate, uint64_t initseq)
{
    r->state = 0u;
    r->inc = (initseq << 1u) | 1u;
    pcg32_next(r);
    r->state += initstate;
    pcg32_next(r);
}

/* Uniform float in [0, 1): 24 random mantissa bits, so 1.0f is never returned. */
static inline float pcg32_float(Pcg32 *r)
{
    return (float)(pcg32_next(r) >> 8) * 0x1p-24f;
}

/* Two uniform floats in [0, 1)^2. C leaves the evaluation order of a call's arguments
 * unspecified, so v2(pcg32_float(r), pcg32_float(r)) drew different samples under GCC
 * (right to left) and Clang (left to right): every pair is drawn here, in sequence. y is
 * drawn first, the order GCC gave the calls this replaced, so GCC images did not change. */
static inline Vec2 pcg32_v2(Pcg32 *r)
{
    float y = pcg32_float(r);
    float x = pcg32_float(r);
    return v2(x, y);
}

/* SplitMix64 finaliser (Steele et al. 2014): a bijective avalanche mix. */
static inline uint64_t mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

/* The stream of one pixel sample: a function of (seed, pixel, sample) only. */
static inline void pcg32_seed_sample(Pcg32 *r, uint64_t seed, uint64_t pixel, uint64_t sample)
{
    uint64_t h = mix64(seed * 0x9e3779b97f4a7c15ULL + pixel);
    uint64_t s = mix64(h ^ (sample * 0xd1b54a32d192ed03ULL + 0x632be59bd9b4e019ULL));
    r->inc = (mix64(h + 0x2545f4914f6cdd1dULL) << 1u) | 1u;
    r->state = s + r->inc;
    pcg32_next(r);
}

#endif
