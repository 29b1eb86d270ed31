/* Metropolis light transport in primary sample space (Kelemen et al. 2002) over the path
 * tracer's estimate (pssmlt): Markov chains of PSS states (sampling/pss_sampler.h), the
 * normalisation b from an independent bootstrap, chains started from the bootstrap's
 * distribution, and splats of both the proposal and the current state weighted by the
 * acceptance probability (Veach's expected-value estimator, thesis sec. 11.3). With depths > 0
 * (mmlt), multiplexed MLT over BDPT instead (Hachisuka, Kaplanyan & Dachsbacher 2014, as
 * pbrt-v4's MLTIntegrator): each chain keeps one path length and its state picks one BDPT
 * strategy of that length (subpath.h's single strategies). */
#ifndef CST_INTEGRATORS_MLT_H
#define CST_INTEGRATORS_MLT_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "core/rng.h"
#include "film/film.h"
#include "integrators/path.h"
#include "integrators/subpath.h"
#include "sampling/pss_sampler.h"
#include "scene/scene.h"

/* Bootstrap paths per work item of the bootstrap step. Fixed: the items write their own
 * slots of one array, so this never changes the image. */
enum { MLT_BOOTSTRAP_CHUNK = 1024 };
/* mmlt's path length for max_depth 0 (unbounded): pbrt-v4's default maxdepth. */
enum { MMLT_DEFAULT_DEPTH = 5 };

typedef struct MltParams {
    PathParams path;       /* the path tracer whose radiance estimate is the target */
    int width, height;     /* the film; the chains explore it and a margin (margin) */
    float margin;          /* pixels past each edge the filter reaches (filter radius - 1/2) */
    float large_step_prob; /* Kelemen's p_large */
    double sigma;          /* small-step width in primary sample space */
    int bootstrap;         /* bootstrap paths (mmlt: in all, depths per path length) */
    int chains;
    uint64_t seed;
    bool spectral;
    /* mmlt: 0 for pssmlt; else path lengths 0 .. depths - 1 (bounces), a chain for one
     * length, bootstrap path i of length i % depths. */
    int depths;
    SubpathParams sub;   /* mmlt: BDPT's (merge false, max_depth depths - 1) */
    SubpathIteration it; /* mmlt: BDPT's MIS constants (vcm_iteration_init with one light
                          * path per pixel and no merging: the weights of one light path
                          * per camera sample over the whole film) */
} MltParams;

/* One Markov chain: its PSS state and the current sample's film position, radiance (RGB)
 * and contribution I (the scalar target, mlt_importance). */
typedef struct MltChain {
    _Alignas(64) PssSampler pss;
    Pcg32 accept_rng; /* the Metropolis acceptance draws */
    Vec2 fp;
    Color L;
    float I;
    int depth; /* mmlt: the path length (bounces) the chain explores */
    int strategy; /* mmlt: the current sample's strategy (light vertices s); -1 for pssmlt
                   * and after a checkpoint (for `caustic explain` only) */
} MltChain;

typedef struct Mlt {
    MltParams p;
    float *boot_I;       /* the bootstrap paths' contributions, by index */
    double *boot_cdf;    /* their running sums, by index (bootstrap + 1 entries) */
    double mean_I;       /* the bootstrap's mean contribution over the film domain: b / area */
    bool ready;          /* bootstrap done and chains started */
    MltChain *chains;
    struct Recorder *rec; /* `caustic explain` (recorder.h): the steps' splats near a pixel;
                           * NULL in renders (one branch per step) */
} Mlt;

/* A new MLT state for p, or NULL on OOM. Caller owns it: mlt_destroy (accepts NULL). */
Mlt *mlt_create(const MltParams *p);
void mlt_destroy(Mlt *m);

/* The bootstrap paths [item * MLT_BOOTSTRAP_CHUNK, ...): each a fresh PSS state (a large
 * step) from a stream of its own index, its contribution stored in boot_I. */
void mlt_bootstrap_item(Mlt *m, const Scene *s, const Camera *cam, int item, uint64_t *rays, uint64_t *nonfinite);
/* Serial, after every bootstrap item: b (mean_I) and the cumulative distribution the
 * chains start from, summed in index order. */
void mlt_bootstrap_finish(Mlt *m);
/* Chain c's start: a bootstrap path picked in proportion to its contribution, whose PSS
 * state is rebuilt exactly from that path's stream (so the chain starts in the bootstrap's
 * resampled distribution: no start-up bias beyond the bootstrap's finite size). */
void mlt_chain_start(Mlt *m, const Scene *s, const Camera *cam, int c, uint64_t *rays, uint64_t *nonfinite);
/* (rays and nonfinite: counters the calls add to; a NaN/Inf estimate counts as a zero one.)
 * `mutations` Metropolis steps of chain c, each splatting the proposal and the current
 * state into `out` with weights a / I and (1 - a) / I. The film's pixel estimate is
 * mean_I * area / (mutations per iteration over all chains) times the splats' sum. */
void mlt_chain_run(Mlt *m, const Scene *s, const Camera *cam, int c, int mutations, SplatList *out,
                   const SplatFrame *fr, uint64_t *rays, uint64_t *nonfinite);
/* `caustic explain`: the estimate of the sample whose primary sample vector has the values
 * v[0 .. n) (recorder.h's RecorderMltSample), evaluated again with the recorder rec on
 * (pssmlt: path_li's events; mmlt: the strategy's walks and connection, of path length
 * depth), into *L (a pure function of the vector: the splatted radiance, bit for bit) and
 * *strategy. False on OOM. */
struct Recorder;
bool mlt_replay(const Mlt *m, const Scene *s, const Camera *cam, const double *v, size_t n, int depth,
                struct Recorder *rec, Color *L, int *strategy);
/* The mutations chain c makes in each iteration of width x height in all. */
static inline int mlt_chain_mutations(const Mlt *m, int c)
{
    int64_t total = (int64_t)m->p.width * m->p.height;
    return (int)(total / m->p.chains + (c < total % m->p.chains ? 1 : 0));
}
/* The factor from one iteration's splat sums to the film's pixel means (box filter: the
 * mean over the pixel of the path tracer's estimate): b / (width x height). */
double mlt_splat_scale(const Mlt *m);
/* Checkpoints (docs/state-format.md, version 4): the bytes of the chains and b once they
 * have started (mlt_state_size of them; false, nothing valid written, before the chains
 * start or when a chain ran out of memory), and a state read back into m, which must have
 * been made with the same parameters: false when the bytes are not a state this m could
 * have written (counts, ranges, lengths), m's chains then unusable. */
size_t mlt_state_size(const Mlt *m);
bool mlt_state_write(const Mlt *m, unsigned char *out);
bool mlt_state_read(Mlt *m, const unsigned char *in, size_t len);

/* The scalar contribution I of a radiance: luminance of the channels' magnitudes, positive
 * wherever the radiance is not zero, so the chains reach every path that contributes. */
static inline float mlt_importance(Color L)
{
    return 0.2126f * fabsf(L.c[0]) + 0.7152f * fabsf(L.c[1]) + 0.0722f * fabsf(L.c[2]);
}

#endif
