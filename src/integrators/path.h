/* Unidirectional path tracing in three flavours that estimate the same integral:
 * BSDF sampling only, next-event estimation only, and both combined with MIS. */
#ifndef CST_INTEGRATORS_PATH_H
#define CST_INTEGRATORS_PATH_H

#include <stdint.h>

#include "sampling/sampler.h"
#include "scene/scene.h"

typedef enum PathMode { PATH_MIS, PATH_NEE, PATH_BSDF } PathMode;

typedef struct PathParams {
    PathMode mode;
    int max_depth; /* bounces after the camera vertex; 0 = unbounded (Russian roulette only) */
    int rr_depth;  /* first depth at which Russian roulette may stop a path */
    bool regularize; /* bsdf_regularize after the first non-delta bounce (pbrt-v4's option) */
    struct Recorder *rec; /* `caustic explain` (recorder.h): the path's events; NULL in renders */
} PathParams;

/* Radiance arriving along `ray` (toward its origin). Adds the number of rays traced to
 * *rays. No allocation; safe to call from many threads on one committed scene. */
Color path_li(const Scene *scene, const PathParams *params, Ray ray, Sampler *smp, Wavelengths *wl, uint64_t *rays);

#endif
