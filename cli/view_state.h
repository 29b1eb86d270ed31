/* caustic view's checkpoint (key k): the current mode's accumulated film written as the state
 * file `caustic render --checkpoint` writes, so that `caustic render --resume` continues it. */
#ifndef CST_CLI_VIEW_STATE_H
#define CST_CLI_VIEW_STATE_H

#include <stdbool.h>
#include <stddef.h>

#include "caustic/caustic.h"

/* What a checkpoint is made of: the viewer's accumulation in its current mode. refused: the
 * preview and SPPM (whose passes re-render from scratch); moved: the camera is not the
 * scene's (a state's key does not hold the camera, so it is refused too). */
typedef struct ViewCheckpoint {
    const CstScene *scene;
    const CstFilm *acc;
    int spp;
    const char *scene_path;
    const char *mode_name;
    CstIntegrator integrator;
    bool refused, moved;
} ViewCheckpoint;

/* The accumulation's film after a pass: restarted (first) from an empty film when `wanted`,
 * then `film` added (cst_film_add); NULL (no checkpoint) when not wanted or on failure. */
void view_state_add(CstFilm **acc, const CstScene *scene, const CstRenderSettings *pass, const CstFilm *film,
                    bool first, bool wanted);

/* Key k: writes the checkpoint as `name` (view_state_write) and says so on stdout, or why
 * not on stderr; true when written. */
bool view_state_checkpoint(const char *name, const CstRenderSettings *pass, const ViewCheckpoint *k);

/* Writes acc (the one-pass films added in order, cst_film_add: a render's sums with
 * sample_block 1) as the state of a render of samples [0, spp) with the viewer's pass
 * settings `pass` (its spp, first sample and callbacks replaced), keyed as the CLI keys it:
 * the SHA-256 of scene_path, or the built-in box when NULL. False with msg set on failure. */
bool view_state_write(const char *path, const CstScene *scene, const CstRenderSettings *pass, const CstFilm *acc,
                      int spp, const char *scene_path, char *msg, size_t size);

#endif
