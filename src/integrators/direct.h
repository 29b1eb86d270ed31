/* Direct light by one light sample without MIS: the next-event estimate the Whitted,
 * photon-mapping and SPPM integrators share (path.c's adds MIS with BSDF sampling). */
#ifndef CST_INTEGRATORS_DIRECT_H
#define CST_INTEGRATORS_DIRECT_H

#include <stdint.h>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "scene/scene.h"

/* f(wo, wi) L_i / pdf for one light picked by power (area point or delta light), with a
 * shadow ray; black when the scene has no lights. Draws three numbers from rng. */
Rgb direct_light(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, Pcg32 *rng, uint64_t *rays);

#endif
