/* Bidirectional path tracing (bdpt.h): the camera walk of subpath.c with no merging. Its
 * MIS weights are VCM's with the merging terms zero (vcm_iteration_init leaves mis_vm and
 * mis_vc at 0 when vp->merge is false), which are the balance of BDPT's strategies alone. */
#include "integrators/bdpt.h"

Color bdpt_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                        Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays)
{
    return subpath_trace_camera(s, cam, vp, it, path, ray, rng, wl, rays, NULL);
}
