/* caustic explain for pssmlt and mmlt (explain_mlt.h): MLT's image is no sum of per-pixel
 * samples but of the chains' splats (mlt.c), so the pixel's value in one iteration is
 * explained by the Metropolis steps that splatted there, in the order the film added them
 * (integrator.c's light_merge_band: chain order, each chain's splats in the order made); the
 * first CST_EXPLAIN_MLT_PATHS of them with their samples' paths, evaluated again. */
#include "render/explain_mlt.h"

#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "film/filter.h"
#include "integrators/mlt.h"

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

/* The events being rebuilt with the replayed paths in place (explain_mlt's r->ev, beta, value). */
typedef struct EventList {
    CstExplainEvent *ev;
    Color *beta, *value;
    size_t n, cap, cap_b, cap_v;
} EventList;

static bool event_append(EventList *l, const CstExplainEvent *e, Color beta, Color value)
{
    if (!array_grow(&l->ev, &l->cap, l->n + 1, sizeof *l->ev) ||
        !array_grow(&l->beta, &l->cap_b, l->n + 1, sizeof *l->beta) ||
        !array_grow(&l->value, &l->cap_v, l->n + 1, sizeof *l->value))
        return false;
    l->ev[l->n] = *e;
    l->beta[l->n] = beta;
    l->value[l->n] = value;
    l->n++;
    return true;
}

/* The first CST_EXPLAIN_MLT_PATHS splats that reached the pixel (r's MUTATION events, in the
 * film's order) with a kept sample (r->mlt, event indices as after the drop): each sample
 * evaluated again from its vector with a scratch recorder, its events inserted after its
 * MUTATION event (flag IN_SPLAT), and the radiance compared with the splatted one. r's
 * arrays are replaced by the longer ones. False on OOM. */
static bool replay_paths(const Integrator *it, Recorder *r, CstExplain *ex)
{
    Recorder *sc = calloc(1, sizeof *sc);
    EventList out = {0};
    bool ok = sc != NULL;
    if (ok) {
        sc->cap = r->cap;
        sc->ev = calloc((size_t)sc->cap, sizeof *sc->ev);
        sc->beta = calloc((size_t)sc->cap, sizeof *sc->beta);
        sc->value = calloc((size_t)sc->cap, sizeof *sc->value);
        ok = sc->ev && sc->beta && sc->value;
    }
    size_t next = 0; /* the next kept sample */
    for (int i = 0; ok && i < r->n; i++) {
        CstExplainEvent e = r->ev[i];
        while (next < r->mlt_n && r->mlt[next].event < i) next++;
        const RecorderMltSample *smp = next < r->mlt_n && r->mlt[next].event == i ? &r->mlt[next] : NULL;
        if (!smp || e.kind != CST_EXPLAIN_MUTATION || ex->mlt_replayed >= CST_EXPLAIN_MLT_PATHS) {
            ok = event_append(&out, &e, r->beta[i], r->value[i]);
            continue;
        }
        /* A fresh scratch recorder (its arrays kept) for the pixel: mmlt's t = 1 splat is
         * recorded when it lands within the same reach as the MUTATION events. */
        CstExplainEvent *ev = sc->ev;
        Color *beta = sc->beta, *value = sc->value;
        const int cap = sc->cap;
        memset(sc, 0, sizeof *sc);
        *sc = (Recorder){.ev = ev, .beta = beta, .value = value, .cap = cap, .px = r->px, .py = r->py,
                         .radius = r->radius, .light_vertices = true, .light_events = true};
        Color L;
        int strategy;
        ok = mlt_replay(it->mlt, it->scene, &it->camera, &r->mlt_pool[smp->off], smp->n, smp->depth, sc, &L,
                        &strategy);
        if (!ok) break;
        ex->mlt_replayed++;
        e.flags |= CST_EXPLAIN_REPLAYED;
        e.path_events = sc->n;
        for (int c = 0; c < 3; c++) e.replay_value[c] = L.c[c];
        if (!sc->truncated && memcmp(&L, &smp->L, sizeof L) == 0) {
            e.flags |= CST_EXPLAIN_REPLAY_EXACT;
            ex->mlt_replay_exact++;
        }
        ok = event_append(&out, &e, r->beta[i], r->value[i]);
        for (int k = 0; ok && k < sc->n; k++) {
            sc->ev[k].flags |= CST_EXPLAIN_IN_SPLAT;
            ok = event_append(&out, &sc->ev[k], sc->beta[k], sc->value[k]);
        }
    }
    if (sc) {
        free(sc->ev);
        free(sc->beta);
        free(sc->value);
        free(sc);
    }
    if (!ok || out.n > (size_t)INT32_MAX) {
        free(out.ev);
        free(out.beta);
        free(out.value);
        return false;
    }
    free(r->ev);
    free(r->beta);
    free(r->value);
    r->ev = out.ev;
    r->beta = out.beta;
    r->value = out.value;
    r->n = r->cap = (int)out.n;
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
    size_t ks = 0; /* their samples follow, with the events' new indices */
    for (size_t j = 0, i = 0; i < (size_t)r->n; i++) {
        const bool keep = r->ev[i].flags & CST_EXPLAIN_ADDED;
        for (; j < r->mlt_n && r->mlt[j].event == (int)i; j++)
            if (keep) {
                r->mlt[ks] = r->mlt[j];
                r->mlt[ks++].event = kept;
            }
        if (keep) {
            r->beta[kept] = r->beta[i];
            r->value[kept] = r->value[i];
            r->ev[kept++] = r->ev[i];
        }
    }
    r->n = kept;
    r->mlt_n = ks;
    /* The splatted samples' own paths, evaluated again (the ones reaching the pixel). */
    if (!replay_paths(it, r, ex))
        return cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", film->width, film->height);
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
    /* And every replayed sample gave its splat's radiance again. */
    if (ex->mlt_replay_exact != ex->mlt_replayed) ex->exact = 0;
    return CST_OK;
}
