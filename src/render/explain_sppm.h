/* caustic explain for sppm (issue 30): an iteration of one pixel, its camera chain, the
 * photons it gathered and its progressive update, checked against the render's film. */
#ifndef CST_RENDER_EXPLAIN_SPPM_H
#define CST_RENDER_EXPLAIN_SPPM_H

#include "caustic/caustic.h"
#include "scene/scene.h"

/* cst_explain's sppm case: settings resolved and checked by the caller (pixel on the image,
 * iteration >= 0). Runs the render's iterations 0..iteration over the whole image on one
 * thread, recording pixel (x, y) in the last one (visible points and photons in media too). */
CstStatus explain_sppm(const Scene *scene, const CstRenderSettings *st, int x, int y, int iteration,
                       CstExplain **out, CstError *err);

#endif
