/* Stochastic progressive photon mapping (Hachisuka & Jensen, "Stochastic Progressive
 * Photon Mapping", SIGGRAPH Asia 2009; bookkeeping after pbrt-v3 sec. 16.2): iterations
 * of one visible point per pixel and one photon pass, with per-pixel radii that shrink. */
#ifndef CST_INTEGRATORS_SPPM_H
#define CST_INTEGRATORS_SPPM_H

#include <stdint.h>

#include "camera/camera.h"
#include "core/threadpool.h"
#include "film/film.h"
#include "scene/scene.h"

#define SPPM_ALPHA (2.0f / 3.0f) /* fraction of new photons kept per iteration (HJ 2009 sec. 4) */

typedef struct SppmParams {
    int iterations;      /* > 0; with time_limit, an upper bound (0 = no bound) */
    double time_limit;   /* seconds; 0 = none: stop after the iteration that exceeds it */
    int photons;         /* photon paths per iteration; 0 = width x height */
    float radius;        /* initial radius (scene units); 0 = automatic (see sppm.c) */
    int max_depth;       /* bounces of a photon path; 0 = unbounded */
    int rr_depth;        /* Russian roulette from this photon bounce on */
    CstFilter filter;    /* how camera samples are placed in their pixel (render.c's rule) */
    uint64_t seed;
    CstProgressFn progress; /* may be NULL; called after every iteration, nonzero: cancel */
    void *progress_user;
    ThreadPool *pool;    /* runs the iterations' phases; the calling thread waits */
} SppmParams;

typedef struct SppmResult {
    int iterations;      /* completed */
    uint64_t photons;    /* photon paths emitted in all */
    float radius0;       /* initial radius used */
    uint64_t nonfinite;  /* NaN/Inf contributions dropped */
} SppmResult;

/* Renders into `film` (empty, width x height of cam) on sp->pool; the image is
 * a function of the params (but the thread count) and the scene only, bit for bit. The film receives the final estimate of every
 * pixel as one sample (film->spp = 1, so its per-pixel variance is unavailable, reported
 * as 0): SPPM's iterations are not independent samples of the pixel (each one's radius
 * depends on all before it). Fails with CST_ERR_OOM, CST_ERR_CANCELLED (sp->progress asked to stop),
 * or CST_ERR_INVALID_ARG for more than 2^29 pixels. */
CstStatus sppm_render(const Scene *scene, const Camera *cam, const SppmParams *sp, Film *film,
                      SppmResult *res, uint64_t *rays, CstError *err);

#endif
