/* The path tracer's loop for scenes with participating media (volpath.c): path_li runs it
 * when the scene has media or medium boundaries. */
#ifndef CST_INTEGRATORS_VOLPATH_H
#define CST_INTEGRATORS_VOLPATH_H

#include "integrators/path.h"

/* As path_li (same modes, depth and roulette rules; medium vertices count as bounces),
 * starting in the camera's medium. No allocation. */
Color volpath_li(const Scene *scene, const PathParams *params, Ray ray, Sampler *smp, Wavelengths *wl,
                 uint64_t *rays);

#endif
