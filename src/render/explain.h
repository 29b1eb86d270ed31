/* cst_explain's replay state (explain.c, explain_sppm.c): the explanation, film, integrator
 * and recorder of one explained render, made and released in one place. */
#ifndef CST_RENDER_EXPLAIN_H
#define CST_RENDER_EXPLAIN_H

#include "caustic/caustic.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"
#include "scene/scene.h"

typedef struct ExplainRun {
    CstExplain *ex;          /* the explanation being filled; handed out by explain_finish */
    Film *film;              /* the render's film, st's size */
    Integrator *it;          /* prepared for st on film */
    IntegratorWorker worker; /* worker 0's state: it points here, so the ExplainRun must not move */
    Recorder rec;            /* events of pixel (x, y), up to `cap` */
    uint64_t rays;
} ExplainRun;

/* Makes xr's explanation, film (st's size), integrator and a recorder of cap events for
 * pixel (x, y), prepares the integrator for st and fills the explanation's x, y, sample,
 * integrator and spectral. On an error (CST_ERR_OOM, or integrator_prepare's) returns it
 * with err set; explain_finish releases whatever was made, in every case. */
CstStatus explain_begin(ExplainRun *xr, const Scene *scene, const CstRenderSettings *st, int x, int y, int sample,
                        int cap, CstError *err);

/* The end of every explanation: when status is CST_OK, hands xr's explanation with the
 * recorded events to *out (the caller owns it: cst_explain_destroy); then frees the
 * integrator, the film, the recorder's arrays and the explanation if not handed out.
 * Returns status. */
CstStatus explain_finish(ExplainRun *xr, CstStatus status, CstExplain **out);

#endif
