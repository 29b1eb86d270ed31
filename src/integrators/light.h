/* Light tracing (particle tracing): paths start on emitters and every vertex is
 * connected to the camera, its contribution splatted to the film. Converges to the path
 * tracer's image except for what a camera connection cannot reach (docs/integrators.md). */
#ifndef CST_INTEGRATORS_LIGHT_H
#define CST_INTEGRATORS_LIGHT_H

#include <stdint.h>

#include "camera/camera.h"
#include "film/film.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

typedef struct LightParams {
    int max_depth;   /* bounces, as PathParams: a vertex after b bounces of the light path
                      * makes a camera path of b bounces; 0 = unbounded */
    int rr_depth;    /* first bounce at which Russian roulette may stop a path */
    SplatFrame frame; /* the film the splats are for: its size and pixel filter */
    bool spectral;    /* spectral mode: each path draws its own wavelengths (math/spectrum.h) */
    /* NULL, or the scene's emitting media as lights (media_lights.h; integrator.c owns
     * them): light paths then also start inside those media. */
    const struct MediaLights *media_lights;
} LightParams;

/* Traces one light path and splats each camera connection into *out, per unit film
 * (camera_sample_wi's normalisation): the pixel estimate is (pixel count / light paths)
 * times the sum of its splats. Adds the rays traced to *rays. No allocation except the
 * amortised growth of *out; safe to call from many threads on one committed scene, each
 * with its own list. */
void light_trace(const Scene *scene, const Camera *cam, const LightParams *params, Sampler *rng,
                 SplatList *out, uint64_t *rays);

#endif
