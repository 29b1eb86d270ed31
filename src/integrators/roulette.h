/* Russian roulette, the one rule every integrator uses (path tracing, light tracing,
 * photon mapping, SPPM, BDPT, VCM), so that all of them trace the same paths. */
#ifndef CST_INTEGRATORS_ROULETTE_H
#define CST_INTEGRATORS_ROULETTE_H

#include "math/color.h"
#include "sampling/sampler.h"

/* roulette_survival: q below (explain's recorders print it). From bounce `depth` on
 * (depth >= rr_depth) the path survives with probability
 * q = min(0.95, max channel of `scatter`) and its throughputs are divided by q, which
 * keeps the estimate unbiased (Arvo & Kirk, "Particle Transport and Image Synthesis",
 * 1990; pbrt-v4 sec. 14.1). `scatter` is the product of the BSDF weights (and earlier
 * 1/q): the path tracer's beta, not a light path's flux, whose scale would keep every
 * light path alive (walks that sample media by a hero lane pass it divided by the lanes'
 * mean density ratio: subpath_roulette, hero_scale). q follows it so dim paths stop early
 * and is capped below 1 so even an albedo-1 furnace ends. Draws one number, only when the rule applies. Returns the
 * factor to scale the throughputs by: 1 before rr_depth, 1 / q on survival, 0 when the
 * path stops (also for a NaN throughput). */
static inline float roulette_survival(Color scatter) { return minf(0.95f, color_max(scatter)); }

static inline float roulette(Sampler *smp, int depth, int rr_depth, Color scatter)
{
    if (depth < rr_depth) return 1.0f;
    float q = roulette_survival(scatter);
    return sampler_1d(smp) < q ? 1.0f / q : 0.0f;
}

#endif
