/* Light tracing and BDPT in scenes with participating media (homogeneous): the light and
 * camera subpaths with vertices inside media, connections through media and boundary
 * shapes, and the MIS quantities of subpath.h extended to volume vertices. */
#ifndef CST_INTEGRATORS_SUBPATH_MEDIA_H
#define CST_INTEGRATORS_SUBPATH_MEDIA_H

#include "integrators/light.h"
#include "integrators/subpath.h"

/* light_trace() for scenes with media (light.c hands them here). */
void media_light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng, SplatList *out,
                       uint64_t *rays);

/* subpath_trace_light() and subpath_trace_camera() for scenes with media (subpath.c hands
 * them here). A light vertex in a medium is stored with ng = ns = 0 and material = -1 - its
 * medium's index. With `merge` (VCM; NULL: BDPT) a camera vertex merges the light vertices
 * of its own kind: surface ones on a surface, volume ones in a medium (UPBP's point-point
 * 3D estimator). */
void media_subpath_trace_light(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                               Sampler *rng, const Wavelengths *wl, SubpathVertexList *verts, SplatList *splats,
                               uint64_t *rays);
Color media_subpath_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                 const SubpathIteration *it, int path, Ray ray, Sampler *rng, const Wavelengths *wl,
                                 uint64_t *rays, const SubpathMerge *merge);

#endif
