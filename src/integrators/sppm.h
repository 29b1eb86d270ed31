/* Stochastic progressive photon mapping (Hachisuka & Jensen, "Stochastic Progressive
 * Photon Mapping", SIGGRAPH Asia 2009; bookkeeping after pbrt-v3 sec. 16.2): iterations
 * of one visible point per pixel and one photon pass, with per-pixel radii that shrink. */
#ifndef CST_INTEGRATORS_SPPM_H
#define CST_INTEGRATORS_SPPM_H

#include <stdint.h>

#include "camera/camera.h"
#include "film/film.h"
#include "math/spectrum.h"
#include "scene/scene.h"

#define SPPM_ALPHA (2.0f / 3.0f) /* fraction of new photons kept per iteration (HJ 2009 sec. 4) */

typedef struct SppmParams {
    int photons;         /* photon paths per iteration; 0 = width x height */
    float radius;        /* initial radius (scene units); 0 = automatic (see sppm.c) */
    int max_depth;       /* bounces of a photon path; 0 = unbounded */
    int rr_depth;        /* Russian roulette from this photon bounce on */
    CstFilter filter;    /* how camera samples are placed in their pixel (render.c's rule) */
    uint64_t seed;
    int threads;         /* the render's thread count: it sizes the deposit's pixel ranges,
                          * which never changes the image */
    bool spectral;       /* spectral mode: each iteration's paths share one set of wavelengths */
    /* NULL, or the photon pass split across processes (CstPhotonSplit, caustic.h): only
     * chunks [chunk_lo, chunk_hi) are traced here, the others' hits fetched before the
     * deposit, in chunk order. */
    const CstPhotonSplit *split;
    /* Scenes with media: the camera whose origin tells the medium a photon starts in
     * (subpath_media.c's medium_at); sppm_create sets it to its own. */
    const Camera *cam;
    /* NULL, or the scene's emitting media as lights (media_lights.h): photons also start in
     * them. Borrowed (integrator.c, photon_split.c own them). */
    const struct MediaLights *media_lights;
} SppmParams;

/* Photon paths per chunk, the unit of the photon phase and of a split (see sppm.c), and
 * the floats of one hit as sppm_trace_chunk packs it: position, direction to the light,
 * geometric normal (3 each), power (COLOR_LANES). */
enum { SPPM_PHOTON_CHUNK = 1024, SPPM_HIT_FLOATS = 13 };

/* The progressive state of one render. Its iterations are driven from outside
 * (integrator.c): for iteration k = 0, 1, ..., every phase p in [0, SPPM_PHASES) in order,
 * n = sppm_phase_begin(sppm, k, p) (serial work, then the phase's item count: 0 skips it,
 * -1 means photon hits were lost to OOM), then sppm_item(sppm, i, worker) for every i in
 * [0, n) on any threads. The image is a function of the params and the scene only, bit
 * for bit, whatever the thread count or the order items run in. */
typedef struct Sppm Sppm;
enum { SPPM_PHASES = 3 };

/* For the film of `cam` (width x height), counters for `workers` pool workers. Traces the
 * photons of the automatic radius. Fails with CST_ERR_OOM, or CST_ERR_INVALID_ARG for more
 * than 2^29 pixels; *out is then NULL or to be destroyed. */
CstStatus sppm_create(const Scene *scene, const Camera *cam, const SppmParams *sp, int workers, Sppm **out,
                      CstError *err);
/* -1: photon hits lost to OOM; -2: a split's fetch failed. */
int sppm_phase_begin(Sppm *sppm, int iteration, int phase);
void sppm_item(void *sppm, int item, int worker);
/* After `iterations` iterations: the film receives the final estimate of every pixel as
 * one sample (film->spp = 1, so its per-pixel variance is unavailable, reported as 0):
 * SPPM's iterations are not independent samples of the pixel (each one's radius depends
 * on all before it). */
void sppm_finish(const Sppm *sppm, Film *film, int iterations);
/* Checkpoints: every pixel's progressive state to film->progressive (allocated here when
 * NULL; false on OOM), and back from a state file's film (false, nothing trusted, when it
 * has none, is of another size or holds a radius or photon count no render makes). With
 * the iterations done (the film's spp), that is all an SPPM render carries from one
 * iteration to the next: a resumed render is bit-identical to an uninterrupted one. */
bool sppm_export(const Sppm *sppm, Film *film);
bool sppm_import(Sppm *sppm, const Film *film);
/* The photon chunks of an iteration of sp->photons photons (0: `pixels`, as sppm_create). */
int sppm_photon_chunks(int photons, size_t pixels);
/* Chunk `chunk` of iteration `iteration` traced on the calling thread, exactly as the photon
 * phase traces it (sp->photons: the iteration's photon count, resolved), its hits appended
 * to hits[0 .. *count) (SPPM_HIT_FLOATS floats each, in photon order; *hits grown with
 * realloc, *cap its floats). False on OOM (the buffer kept as it was). */
bool sppm_trace_chunk(const Scene *scene, const SppmParams *sp, int iteration, int chunk, float **hits,
                      size_t *count, size_t *cap, uint64_t *rays);
/* caustic explain (issue 30, src/render/explain_sppm.c): one pixel's progressive state. */
typedef struct SppmPixelState {
    double ld[3], tau[3], n_photons;
    float r;
    double tau_vol[3], n_vol;
    float r_vol;
} SppmPixelState;

/* What iteration `iteration` did at pixel `pixel`: its camera chain, NEE and every photon
 * it gathered go to rec (in the order the render adds them), its state is copied before the
 * camera pass, at the update and after it. Set by sppm_trace() before the render; the
 * render itself is unchanged. */
typedef struct SppmTrace {
    struct Recorder *rec;
    int pixel, iteration;
    int photons;           /* photon paths per iteration (filled by sppm_trace) */
    SppmPixelState before, after;
    bool valid, vol;       /* the visible point, at the update */
    Color beta;            /* its throughput (filter weight included) */
    long m;                /* photons it gathered */
    Color direct;          /* the camera pass's sample as added to ld */
    float fw;              /* its filter weight (the chain's first throughput) */
    Wavelengths wl;        /* spectral mode: the iteration's wavelengths */
} SppmTrace;
/* Starts tracing (NULL: stops); the trace must outlive the render's iterations. */
void sppm_trace(Sppm *sppm, SppmTrace *trace);

/* Adds the rays traced and the NaN/Inf contributions dropped. */
void sppm_counters(const Sppm *sppm, uint64_t *rays, uint64_t *nonfinite);
/* Accepts NULL. */
void sppm_destroy(Sppm *sppm);

#endif
