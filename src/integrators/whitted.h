/* Whitted-style recursive ray tracing: perfect mirror reflection and dielectric
 * reflection + refraction traced recursively, direct light by shadow rays at diffuse
 * surfaces, no diffuse interreflection (biased by design). */
#ifndef CST_INTEGRATORS_WHITTED_H
#define CST_INTEGRATORS_WHITTED_H

#include <stdint.h>

#include "sampling/sampler.h"
#include "scene/scene.h"

typedef struct WhittedParams {
    int max_depth;     /* specular bounces after the camera vertex; 0 = WHITTED_DEFAULT_DEPTH */
    int light_samples; /* shadow rays per diffuse hit; 0 = 1 */
    struct Recorder *rec; /* `caustic explain` (recorder.h): the ray tree's events; NULL in renders */
} WhittedParams;

enum { WHITTED_DEFAULT_DEPTH = 10 };

/* Radiance arriving along `ray` (toward its origin) under the Whitted model. Adds the
 * number of rays traced to *rays. No allocation (recursion depth <= max_depth). */
Color whitted_li(const Scene *scene, const WhittedParams *params, Ray ray, Sampler *smp, const Wavelengths *wl,
                 uint64_t *rays);

#endif
