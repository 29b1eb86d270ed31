/* pbrt-v4's "curve" shape: its control points, basis, widths and type read and handed to
 * cst_scene_add_curves. */
#ifndef CST_SCENE_PBRT_PBRT_CURVE_H
#define CST_SCENE_PBRT_PBRT_CURVE_H

#include "scene/pbrt/pbrt_loader.h"

/* Shape "curve" with parameters ps at loc (d: the directive's description for messages). */
CstStatus pbrt_curve_shape(Loader *ld, Params *ps, const char *d, Loc loc);

#endif
