/* Bidirectional path tracing (Veach thesis ch. 10; Lafortune & Willems 1993) with the
 * recursive MIS of Georgiev's VCM report: every connection strategy of a light and a
 * camera subpath (subpath.h), without VCM's merging. Each iteration traces one light path
 * per pixel, then one camera path per pixel that connects to "its" light path. */
#ifndef CST_INTEGRATORS_BDPT_H
#define CST_INTEGRATORS_BDPT_H

#include "integrators/subpath.h"

/* One camera path for the pixel whose light path is `path` (vp->merge is false): emission
 * hits, NEE, connections to the light path's vertices, MIS-weighted. The light paths are
 * subpath_trace_light's. Returns the pixel sample. */
Color bdpt_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                        Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays);

#endif
