/* caustic explain for pssmlt and mmlt (issue 30): one iteration of the Metropolis chains
 * replayed from the render's start, the steps whose splats reach one pixel listed. */
#ifndef CST_RENDER_EXPLAIN_MLT_H
#define CST_RENDER_EXPLAIN_MLT_H

#include "caustic/caustic.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"

/* MLT's "sample" I of a pixel is iteration I of the chains (W x H mutations over all of
 * them, the film's one sample per pixel per iteration): the render's steps run on one
 * thread from the bootstrap through iterations 0 .. I - 1 unrecorded, then iteration I with
 * r recording every step whose splat lands near pixel (x, y) (MUTATION events); the splats
 * that reached the pixel are re-added in the film's order (chain by chain, each chain's in
 * the order it made them) and compared with the value the render merged, bit for bit.
 * Fills ex's values, mlt_* and exact/splats_exact; drops the recorded events that added
 * nothing. it: prepared for the whole film (no crop), film: its film. */
CstStatus explain_mlt(Integrator *it, Film *film, Recorder *r, int x, int y, int sample, CstExplain *ex,
                      CstError *err);

#endif
