/* caustic explain's explicit MIS check of BDPT and VCM (issue 30): every recorded strategy's
 * whole path rebuilt and its power-heuristic weight computed again (bdpt_mis.h). */
#ifndef CST_RENDER_EXPLAIN_MIS_H
#define CST_RENDER_EXPLAIN_MIS_H

#include "caustic/caustic.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"

/* After explain's run of BDPT/VCM iteration `iteration`: for each of r's emission, NEE, connection
 * (the camera subpath and the pixel's light subpath), merge (the merged light vertex's light
 * subpath, traced again) and splat event (the splatting light subpath, traced again) at an
 * area light, sets mis_explicit, mis_sum and mis_strategies and folds the difference into
 * ex's mis_checked, mis_max_error and mis_max_sum_error. False on OOM. */
bool explain_mis_check(const Integrator *it, int iteration, Recorder *r, CstExplain *ex);

#endif
