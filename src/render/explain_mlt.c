/* caustic explain for pssmlt and mmlt (explain_mlt.h): MLT's image is no sum of per-pixel
 * samples but of the chains' splats (mlt.c), so the pixel's value in one iteration is
 * explained by the Metropolis steps that splatted there, in the order the film added them
 * (integrator.c's light_merge_band: chain order, each chain's splats in the order made). */
#include "render/explain_mlt.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/filter.h"

/* Pass `iteration` of the render, every step's items in order on worker 0 (the chains are
 * assigned to items deterministically, so one thread gives the render's values). */
static CstStatus run_iteration(Integrator *it, int iteration, CstError *err)
{
    integrator_pass_begin(it, iteration, 1);
    for (;;) {
        IntegratorStep step;
        CstStatus st = integrator_next_step(it, &step, err);
        if (st != CST_OK || step.items == 0) return st;
        for (int i = 0; i < step.items; i++) step.fn(step.ctx, i, 0);
    }
}

/* Each splat of the iteration's chain lists that adds to pixel (x, y), its share computed
 * with the merge's arithmetic (film_add_splat_rows on a zeroed row: 0 + share is share) and
 * added to sum[] in the merge's order; the MUTATION event recorded for it (matched by chain
 * and list index, both increasing in r's order) gets the share and CST_EXPLAIN_ADDED. A
 * splat with no event (not recorded: the recorder was full) is not added, so the sum then
 * differs from the film's. False on OOM. */
static bool add_shares(const Integrator *it, Recorder *r, int x, int y, double sum[3])
{
    const LightIterations *L = &it->light;
    const SplatFrame *fr = &L->params.frame;
    const double scale = mlt_splat_scale(it->mlt);
    /* film_add_splat_rows indexes the whole image (only row y is written). */
    double *img = calloc(3 * (size_t)fr->width * (size_t)fr->height, sizeof *img);
    if (!img) return false;
    double *row = &img[3 * (size_t)y * (size_t)fr->width];
    double *px = &row[3 * (size_t)x];
    sum[0] = sum[1] = sum[2] = 0.0;
    int next = 0;
    for (int c = 0; c < L->num_chunks; c++) {
        const SplatList *l = &L->chunks[c].splats;
        for (size_t k = 0; k < l->n; k++) {
            const FilmSplat *sp = &l->v[k];
            if (y < sp->row0 || y > sp->row1) continue;
            film_add_splat_rows(sp, fr, img, scale, y, y + 1);
            const double share[3] = {px[0], px[1], px[2]};
            memset(row, 0, 3 * (size_t)fr->width * sizeof *row);
            if (share[0] == 0.0 && share[1] == 0.0 && share[2] == 0.0) continue; /* adds no bit */
            for (int i = next; i < r->n; i++) {
                CstExplainEvent *e = &r->ev[i];
                if (e->chain != c || e->path != (int)k) continue;
                for (int j = 0; j < 3; j++) {
                    e->share[j] = share[j];
                    sum[j] += share[j];
                }
                e->flags |= CST_EXPLAIN_ADDED;
                next = i + 1;
                break;
            }
        }
    }
    free(img);
    return true;
}

CstStatus explain_mlt(Integrator *it, Film *film, Recorder *r, int x, int y, int sample, CstExplain *ex,
                      CstError *err)
{
    const size_t pixel = (size_t)y * (size_t)film->width + (size_t)x;
    /* Kept when within the filter's reach plus a pixel (the shares decide what counted). */
    r->radius = filter_radius(it->light.params.frame.filter) + 1.0f;
    r->n = 0;
    CstStatus st = CST_OK;
    for (int i = 0; i < sample && st == CST_OK; i++) st = run_iteration(it, i, err);
    if (st != CST_OK) return st;
    memcpy(ex->camera_value, &film->sum[3 * pixel], sizeof ex->camera_value);
    it->mlt->rec = r;
    st = run_iteration(it, sample, err);
    it->mlt->rec = NULL;
    if (st != CST_OK) return st;
    double sum[3];
    if (!add_shares(it, r, x, y, sum))
        return cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", film->width, film->height);
    /* The events that added nothing (near the pixel, outside the filter's support) go. */
    int kept = 0;
    for (int i = 0; i < r->n; i++)
        if (r->ev[i].flags & CST_EXPLAIN_ADDED) r->ev[kept++] = r->ev[i];
    r->n = kept;
    const Mlt *m = it->mlt;
    ex->mlt_scale = mlt_splat_scale(m);
    ex->mlt_b = m->mean_I * ((double)m->p.width + 2.0 * (double)m->p.margin) *
                ((double)m->p.height + 2.0 * (double)m->p.margin);
    ex->mlt_chains = m->p.chains;
    ex->filter_weight = 1.0f;
    const double *merged = &it->light.iteration_rgb[3 * pixel];
    ex->exact = !r->truncated;
    for (int c = 0; c < 3; c++) {
        ex->sum[c] = (float)sum[c];
        ex->splat_value[c] = sum[c];
        ex->film_value[c] = film->sum[3 * pixel + (size_t)c];
        /* The re-added splats are the iteration's value, and the film added it. */
        const double after = ex->camera_value[c] + merged[c];
        if (memcmp(&sum[c], &merged[c], sizeof sum[c]) != 0 || memcmp(&after, &ex->film_value[c], sizeof after) != 0)
            ex->exact = 0;
    }
    ex->splats_exact = ex->exact;
    return CST_OK;
}
