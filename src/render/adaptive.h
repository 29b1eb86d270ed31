/* Adaptive sampling by quality (CstRenderSettings.noise_target, --noise): each 16x16 block's
 * estimated relative standard error, the plan of the next round of samples from it, and
 * the summary a render reports. Every value is computed from the film's sums alone, in a
 * fixed order, so the rounds are the same for any thread count and after a resume. */
#ifndef CST_RENDER_ADAPTIVE_H
#define CST_RENDER_ADAPTIVE_H

#include <stdint.h>

#include "caustic/caustic.h"
#include "film/film.h"
#include "integrators/integrator.h"

/* Samples every block gets in the first round: fewer make the variance estimates, and so
 * the first decisions, too unreliable (a block whose few samples all missed the light
 * would look converged). */
enum { ADAPTIVE_MIN_SPP = 16 };

/* One block's noise: rel, the relative standard error of the block's mean luminance (0 for
 * a black block, +inf while a pixel holds fewer than 2 samples); dof, the degrees of
 * freedom of its variance estimate (Satterthwaite); spp, the samples of its first pixel
 * (all of a block's pixels hold the same count). */
typedef struct BlockNoise {
    double rel, dof;
    int spp;
} BlockNoise;

/* The noise of the pixels [x0, x1) x [y0, y1) of f. */
BlockNoise adaptive_block_noise(const Film *f, int x0, int y0, int x1, int y1);

/* Samples to add to a block of n samples with relative error rel, for target and at most
 * cap samples in all: 0 when it is done. */
int adaptive_more(int n, double rel, double target, int cap);

/* The blocks of the crop [crop[0], crop[1]) x [crop[2], crop[3]), INTEGRATOR_TILE a side,
 * in the integrators' tile order. */
typedef struct AdaptiveGrid {
    int x0, y0, x1, y1, tiles_x, tiles;
} AdaptiveGrid;
AdaptiveGrid adaptive_grid(const int crop[4]);
void adaptive_tile_rect(const AdaptiveGrid *g, int tile, int *x0, int *y0, int *x1, int *y1);

/* The next round for film f (per-pixel counts, pixel_spp): runs[0..return) (room for
 * g->tiles) lists each block that needs samples and the ones it gets, continuing its own
 * count; *samples: the pixel samples of the round. */
int adaptive_plan(const Film *f, const AdaptiveGrid *g, double target, int cap, IntegratorTileRun *runs,
                  uint64_t *samples);
/* After a round: every pixel of each run's block holds count more samples; f->spp the most
 * any pixel of the grid holds. */
void adaptive_commit(Film *f, const AdaptiveGrid *g, const IntegratorTileRun *runs, int n);
/* Whole-image stopping (light, bdpt, vcm: every pixel holds f->spp samples): the samples
 * the worst block asks for, 0 when every block is within target or at cap. */
int adaptive_plan_uniform(const Film *f, const AdaptiveGrid *g, double target, int cap);

/* The noise fields of stats (caustic.h) for film f over grid g. */
void adaptive_summary(const Film *f, const AdaptiveGrid *g, double target, CstRenderStats *stats);

#endif
