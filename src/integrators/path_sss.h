/* The path tracer's loop for scenes with subsurface materials (path_sss.c): path_li runs
 * it when the scene has any. */
#ifndef CST_INTEGRATORS_PATH_SSS_H
#define CST_INTEGRATORS_PATH_SSS_H

#include "integrators/path.h"

/* As path_li (same modes, depth and roulette rules), with pbrt-v4's BSSRDF step after a
 * refraction into a subsurface material. No allocation. */
Color path_sss_li(const Scene *scene, const PathParams *params, Ray ray, Sampler *smp, Wavelengths *wl,
                  uint64_t *rays);

#endif
