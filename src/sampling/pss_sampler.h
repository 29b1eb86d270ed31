/* The primary-sample-space sampler of Metropolis light transport (Kelemen et al. 2002, as
 * pbrt-v4's MLTSampler): a lazily grown vector of [0,1) values, mutated by small steps
 * (a wrapped normal perturbation) and large steps (fresh uniforms), with backup/restore
 * for Metropolis accept/reject, read through interleaved streams. */
#ifndef CST_SAMPLING_PSS_SAMPLER_H
#define CST_SAMPLING_PSS_SAMPLER_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "core/rng.h"

/* One coordinate of the state. A coordinate is brought up to date only when read
 * (lazy mutation, Kelemen et al. 2002 sec. 4.2): `modified` is the iteration of its last
 * change, so the small steps it missed are applied at once as one normal step of width
 * sigma sqrt(missed) (the sum of independent normals), and a large step since then
 * replaces it by a fresh uniform. */
typedef struct PssValue {
    double value, backup;
    int64_t modified, modified_backup;
} PssValue;

typedef struct PssSampler {
    Pcg32 rng;                 /* the chain's own stream: every mutation and acceptance draw */
    double sigma;              /* small-step width in primary sample space */
    float large_step_prob;     /* probability of a large step per iteration */
    int stream_count;          /* streams interleaved in the vector (pbrt-v4: camera, light,
                                * connection) */
    int stream, stream_next;   /* the stream being read and its next sample index */
    bool large_step;           /* the current iteration's proposal is a large step */
    bool oom;                  /* a value could not be stored: the chain is invalid */
    int64_t iteration;         /* the current iteration (proposal) */
    int64_t last_large;        /* the last accepted large step */
    PssValue *x;               /* the state, grown lazily */
    size_t n, cap;
} PssSampler;

/* A chain's sampler on the PCG32 stream `rng` (the caller seeds it). sigma > 0,
 * large_step_prob in [0, 1], stream_count >= 1. No allocation until the first read. */
void pss_init(PssSampler *s, Pcg32 rng, double sigma, float large_step_prob, int stream_count);
/* A fresh state on the stream `rng` with the same parameters, keeping the vector's
 * memory (no allocation when one sampler serves many independent paths). */
void pss_restart(PssSampler *s, Pcg32 rng);
/* Frees the vector; accepts a zeroed sampler. */
void pss_free(PssSampler *s);
/* Starts a proposal: the next iteration, a large step with probability large_step_prob
 * (one draw from the chain's stream). */
void pss_start_iteration(PssSampler *s);
/* Reads from stream `index` (< stream_count) from its first sample on. */
void pss_start_stream(PssSampler *s, int index);
/* The next value of the current stream, uniform in [0, 1) under a large step, otherwise
 * the state's value mutated by the missed small steps. */
float pss_next(PssSampler *s);
/* Metropolis outcome of the current proposal: accept keeps the mutated values (a large
 * step becomes the reference for values not read since); reject restores every value
 * this iteration changed and steps the iteration counter back. */
void pss_accept(PssSampler *s);
void pss_reject(PssSampler *s);

/* `caustic explain` (MLT): a sampler whose reads give back a sample's own values, the
 * coordinate values v[0 .. n) of a state's vector (one sample's: the proposal's or the
 * current state's), so that its estimate can be evaluated again with the recorder on. It
 * is a small step of width 0 on a vector dated now: pss_next returns to_unit_float(v[i])
 * for coordinate i, as it did for that sample. Owns a copy (pss_free); false on OOM. */
bool pss_replay_init(PssSampler *s, const double *v, size_t n, int stream_count);

/* The small-step proposal density of one coordinate, a normal of width w = sigma
 * sqrt(steps) wrapped onto [0,1): q(x -> y) = sum_k phi((y - x + k) / w) / w. Symmetric,
 * so the Metropolis acceptance needs no proposal ratio. For tests. */
double pss_small_step_pdf(double x, double y, double w);

#endif
