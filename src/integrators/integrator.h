/* The integrator interface: one tagged union over every light-transport algorithm
 * (pbrt-v4 and SmallVCM in spirit), which render.c drives the same way for all of them:
 * prepare, passes made of parallel steps, finish. Also the public name table. */
#ifndef CST_INTEGRATORS_INTEGRATOR_H
#define CST_INTEGRATORS_INTEGRATOR_H

#include <stdbool.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "camera/camera.h"
#include "core/threadpool.h"
#include "film/film.h"
#include "film/filter.h"
#include "integrators/bdpt.h"
#include "integrators/light.h"
#include "integrators/mlt.h"
#include "integrators/path.h"
#include "integrators/photon.h"
#include "integrators/sppm.h"
#include "integrators/vcm.h"
#include "integrators/whitted.h"
#include "scene/scene.h"

/* Camera work items are square tiles of this many pixels a side over the crop. */
enum { INTEGRATOR_TILE = 16 };

/* One camera tile's share of a pass when the tiles' sample ranges differ (adaptive
 * sampling, render/adaptive.h): tile `tile` renders samples [first, first + count). */
typedef struct IntegratorTileRun {
    int tile, first, count;
} IntegratorTileRun;

typedef enum IntegratorKind {
    INTEGRATOR_PATH,    /* path, path-nee, path-bsdf: camera tiles */
    INTEGRATOR_WHITTED, /* camera tiles */
    INTEGRATOR_PHOTON,  /* photon maps built by prepare, then camera tiles */
    INTEGRATOR_LIGHT,   /* iterations: light-path chunks, then the splat merge */
    INTEGRATOR_BIDIR,   /* BDPT and VCM iterations: light chunks, vertex gather (and the
                         * merging grid), camera tiles, merge */
    INTEGRATOR_SPPM,    /* iterations of sppm.c's phases; the film written by finish */
    INTEGRATOR_PSSMLT   /* MLT (mlt.h): the bootstrap and the chains' starts once, then
                         * iterations of chain steps (width x height mutations in all) and
                         * the splat merge of the light tracer, chains for chunks */
} IntegratorKind;

/* Per pool worker: integer counters, summed in any order. The padding keeps neighbouring
 * workers' counters on different cache lines: bumped on every ray, they bounced one line
 * between cores (false sharing), which cost the light tracer a third of its time
 * (docs/benchmarks.md). */
typedef struct IntegratorWorker {
    uint64_t rays, nonfinite;
    char pad[64];
} IntegratorWorker;

/* One parallel step of a pass: fn(ctx, item, worker) for every item, on render.c's pool.
 * The progress of the step is mapped linearly onto [progress_lo, progress_hi] of the
 * pass. */
typedef struct IntegratorStep {
    int items; /* 0: the pass is complete */
    ThreadPoolFn fn;
    void *ctx;
    double progress_lo, progress_hi;
    bool throttle; /* short steps (one iteration of light paths): report at most ~10 times a second */
} IntegratorStep;

/* What one light chunk writes (LIGHT_CHUNK light paths): its splats and, for BDPT/VCM, its
 * light vertices. Each on cache lines of its own: the two threads trace neighbouring
 * chunks and bump their lists' counts on every splat and vertex, and with the lists
 * packed in an array those counts shared a line between cores (false sharing;
 * docs/benchmarks.md has the figures). */
typedef struct LightChunk {
    _Alignas(64) SplatList splats;
    SubpathVertexList verts;
    Vec3 lo;      /* VCM: the lowest corner of the vertices' positions */
    size_t first; /* BDPT/VCM: where the vertices go in the iteration's array */
} LightChunk;

/* Bucket ranges of the merging grid's parallel sort (vcm.h): a few per thread, for
 * balance; any number gives the same grid. */
enum { GRID_RANGES_MAX = 64 };

/* Light tracing, BDPT and VCM: iterations of width x height light paths. */
typedef struct LightIterations {
    LightParams params;    /* the light tracer's */
    int light_paths;       /* per iteration: width x height */
    int num_chunks;
    LightChunk *chunks;    /* one per chunk, reused by every iteration */
    double *iteration_rgb; /* the iteration's image, width x height x 3 */
    /* BDPT / VCM */
    SubpathParams vcm_params;
    float vcm_radius;          /* the first iteration's merging radius */
    SubpathIteration vcm_it;       /* the iteration in progress */
    uint32_t *path_count;      /* light_paths: vertices each path stored */
    uint32_t *path_start;      /* light_paths + 1 */
    SubpathVertex *vertices;       /* the iteration's, concatenated */
    uint32_t *cell_of;         /* VCM: each vertex's grid bucket */
    size_t total;              /* vertices this iteration */
    int grid_ranges;
    uint32_t grid_base[GRID_RANGES_MAX + 1]; /* per range: its vertices, then the count below it */
    bool grid_fill;            /* the grid step in progress: false counts, true fills */
    uint32_t *cell_start;
    MergeVertex *cell_items;
    size_t cap[4];             /* capacities of vertices, cell_items, cell_start, cell_of */
} LightIterations;

typedef struct Integrator {
    IntegratorKind kind;
    const Scene *scene;          /* the render's scene, or sss_view */
    const Scene *sss_view;       /* light, bdpt, vcm, mmlt (path with subsurface_walk): the
                                  * scene's subsurface materials as media (sss_walk.h), owned;
                                  * NULL without them */
    Film *film;
    Camera camera;
    struct MediaLights *media_lights; /* light, sppm, photon: the scene's emitting media as lights
                                       * (media_lights.h), owned; NULL without them */
    uint64_t seed;
    int threads;                 /* the render's thread count (it sizes some work cuts that
                                  * never change the image) */
    IntegratorWorker *workers;   /* one per pool worker */
    /* Camera tiles: INTEGRATOR_TILE-square tiles over the crop, one thread per tile. */
    Filter pixel_filter;
    SamplerSetup sampler;        /* camera paths': type, seed, the sample count strata divide
                                  * (0 = not known: a time limit) and the strata, set once */
    bool aov_hit;                /* albedo, normal or depth AOVs: trace the first hit for them */
    bool motion;                 /* the scene moves: each camera path draws its time */
    bool spectral;               /* spectral mode (math/spectrum.h): paths carry 4 wavelengths */
    float clamp;                 /* > 0: camera samples and splats through color_clamp_xyz_max
                                  * (the settings' max_component over 2^exposure); 0 = none */
    int tiles_x, num_tiles;
    int crop_x0, crop_x1, crop_y0, crop_y1;
    /* The pass in progress: samples (iterations) [pass_first, pass_first + pass_count);
     * `iteration` the one running, `step` the next step of it. */
    int pass_first, pass_count, iteration, step;
    /* camera tiles: the samples [tile_first, tile_first + tile_spp) of every pixel */
    int tile_first, tile_spp;
    /* Path, whitted, photon: NULL, or the pass's items are these num_tile_runs tiles, each
     * with its own samples (tile_first/tile_spp unused); set by the caller of
     * integrator_pass_begin. */
    const IntegratorTileRun *tile_runs;
    int num_tile_runs;
    bool photon_borrowed; /* photon: the maps are CstRenderSettings.photon_cache's */
    Mlt *mlt;             /* INTEGRATOR_PSSMLT (its splats in `light`'s chunks) */
    union {
        PathParams path;
        WhittedParams whitted;
        PhotonMaps photon;    /* built once by prepare (or borrowed: photon_borrowed) */
        LightIterations light; /* INTEGRATOR_LIGHT, INTEGRATOR_BIDIR and INTEGRATOR_PSSMLT */
        Sppm *sppm;
    };
} Integrator;

/* Sets up the integrator of st->integrator (settings resolved and validated by the
 * caller) to render into `film`, with `workers` counters for a pool that size: the photon
 * maps, the light-path buffers, SPPM's state. Adds the rays prepare traces to *rays.
 * Fails with CST_ERR_OOM or CST_ERR_INVALID_ARG (photon or radius settings), message set.
 * Caller frees with integrator_destroy, also after a failure. progress (may be NULL)
 * reports the photon integrator's photon pass as PhotonParams.progress does (nonzero:
 * CST_ERR_CANCELLED). */
CstStatus integrator_prepare(Integrator *it, const Scene *scene, const CstRenderSettings *st, Film *film,
                             IntegratorWorker *workers, uint64_t *rays, int (*progress)(void *, double),
                             void *progress_user, CstError *err);
/* Starts the pass of samples (iterations) [first, first + count). */
void integrator_pass_begin(Integrator *it, int first, int count);
/* The next step of the pass into *step (items 0 once the pass is complete), after the
 * serial work between steps. Fails with CST_ERR_OOM (lost splats, vertices or photon
 * hits), message set. */
CstStatus integrator_next_step(Integrator *it, IntegratorStep *step, CstError *err);
/* After the last pass, `samples` done in all: the film's final contents (SPPM writes its
 * estimate, film->spp = 1) and film->spp. */
void integrator_finish(Integrator *it, int samples);
/* Checkpoints of integrators whose state is more than the film's sums (SPPM, MLT): after
 * `done` iterations, the state into it->film (Film.progressive, film->spp = done; MLT's
 * chains into Film.chains; false on OOM, or for MLT a chain that ran out); before the first pass of a resumed render, back from the state file's film (false
 * when it holds none or a value no render makes). True and nothing done for the others. */
bool integrator_export_progressive(Integrator *it, int done);
bool integrator_import_progressive(Integrator *it, const Film *resume);
/* Counters of the integrator's own state (SPPM's workers, dropped splats), added to the
 * stats. */
void integrator_counters(const Integrator *it, uint64_t *rays, uint64_t *nonfinite);
/* Accepts a zeroed or failed integrator. */
void integrator_destroy(Integrator *it);
/* INTEGRATOR_LIGHT: light path `path` of iteration `iteration` traced again as its chunk
 * traced it (the same random numbers), its splats appended to *out (`caustic explain`). */
void integrator_light_path(const Integrator *it, int iteration, int path, SplatList *out, uint64_t *rays);
/* INTEGRATOR_BIDIR, after the light step of iteration `iteration`: its light subpath `path`
 * traced again as its chunk traced it (the same random numbers), with recorder rec (its
 * RecorderPaths set to keep this path), into scratch lists verts and splats (`caustic
 * explain`'s MIS check). */
void integrator_bidir_light_path(const Integrator *it, int iteration, int path, struct Recorder *rec,
                                 SubpathVertexList *verts, SplatList *splats, uint64_t *rays);

#endif
