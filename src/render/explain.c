/* cst_explain (caustic.h, issue 30): one sample of one pixel replayed through the
 * render's own steps (integrator.c) on a one-pixel crop, one thread, with a recorder
 * (integrators/recorder.h) that the path tracers, Whitted, photon mapping and BDPT/VCM
 * fill; then the recorded additions are summed again in the integrator's order and
 * checked against the film. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/film.h"
#include "film/filter.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"
#include "render/explain.h"
#include "render/explain_mis.h"
#include "render/explain_sppm.h"
#include "render/explain_mlt.h"
#include "render/render.h"
#include "scene/scene.h"

/* Events kept per sample: a path tracer's path of 1,000 bounces, or a BDPT camera path
 * with its connections; longer ones are reported truncated (and not checked). */
enum { EXPLAIN_EVENTS = 8192 };

const char *cst_explain_integrators(void)
{
    return "path, path-nee, path-bsdf, whitted, light, photon, bdpt, vcm, sppm, pssmlt, mmlt";
}

void cst_explain_destroy(CstExplain *e)
{
    if (!e) return;
    free(e->events);
    free(e);
}

static CstStatus check(const Scene *scene, const CstRenderSettings *st, int x, int y, int sample, CstError *err)
{
    if (!scene->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene not committed");
    if (st->width <= 0 || st->height <= 0 || st->width > 65536 || st->height > 65536)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image size %dx%d: expected 1..65536 in each dimension",
                        st->width, st->height);
    if (x < 0 || y < 0 || x >= st->width || y >= st->height)
        return cst_fail(err, CST_ERR_INVALID_ARG, "pixel %d,%d: expected 0 <= x < %d and 0 <= y < %d (the "
                        "image's width and height)", x, y, st->width, st->height);
    if (sample < 0) return cst_fail(err, CST_ERR_INVALID_ARG, "sample %d: expected >= 0", sample);
    switch (st->integrator) {
    case CST_INTEGRATOR_PATH:
    case CST_INTEGRATOR_PATH_NEE:
    case CST_INTEGRATOR_PATH_BSDF:
    case CST_INTEGRATOR_DEFAULT: return CST_OK; /* path_li, volpath_li and path_sss_li are recorded */
    case CST_INTEGRATOR_WHITTED:
    case CST_INTEGRATOR_LIGHT: return CST_OK; /* (integrator_prepare refuses media for whitted) */
    case CST_INTEGRATOR_PHOTON: return CST_OK; /* photon_li_surface and photon_li_media are recorded */
    case CST_INTEGRATOR_BDPT:
    case CST_INTEGRATOR_VCM: return CST_OK; /* subpath.c and subpath_media.c are recorded */
    case CST_INTEGRATOR_SPPM: return CST_OK; /* explain_sppm.c refuses what it cannot follow */
    case CST_INTEGRATOR_PSSMLT:
    case CST_INTEGRATOR_MMLT: return CST_OK; /* the chains' splats (explain_mlt.c) */
    default: break;
    }
    return cst_fail(err, CST_ERR_UNSUPPORTED, "explain supports: %s; not %s", cst_explain_integrators(),
                    cst_integrator_name(st->integrator));
}

/* Whitted's ray tree summed again as whitted_trace sums it, from the node whose VERTEX
 * (or ESCAPE) event is at *i: its emission, plus its direct light, plus each branch's
 * weight times its child's value. */
static Color replay_whitted(const Recorder *r, int *i)
{
    if (*i >= r->n) return color_s(0.0f);
    const int at = (*i)++, d = r->ev[at].depth;
    if (r->ev[at].kind == CST_EXPLAIN_ESCAPE) return r->value[at];
    Color L = color_s(0.0f);
    if (*i < r->n && r->ev[*i].kind == CST_EXPLAIN_EMISSION && r->ev[*i].depth == d) L = r->value[(*i)++];
    /* whitted_direct's shadow rays (not ADDED), then their mean, which the tree adds */
    while (*i < r->n && r->ev[*i].kind == CST_EXPLAIN_NEE && r->ev[*i].depth == d && !(r->ev[*i].flags & CST_EXPLAIN_ADDED))
        (*i)++;
    if (*i < r->n && r->ev[*i].kind == CST_EXPLAIN_NEE && r->ev[*i].depth == d) L = color_add(L, r->value[(*i)++]);
    while (*i < r->n && r->ev[*i].kind == CST_EXPLAIN_SCATTER && r->ev[*i].depth == d) {
        Color w = r->value[(*i)++];
        Color child = replay_whitted(r, i);
        L = color_madd(L, w, child);
    }
    return L;
}

/* A run of BDPT connections (or of VCM's merges) at one camera vertex, summed before it is
 * added times the vertex's throughput; spectral mode keeps the dispersed ones apart (H). */
typedef struct ReplayGroup {
    int depth, kind;
    bool cam_dispersed; /* merges: the camera subpath's, which sends both sums to H */
    Color beta, c, ch;
} ReplayGroup;

/* The group's sums added as subpath_trace_camera adds them (VCM: after merge()'s
 * normalisation, the dispersed light vertices' apart). */
static void replay_flush(const Integrator *it, const Recorder *r, const ReplayGroup *g, Color *L, Color *H)
{
    const bool spectral = it->spectral;
    if (g->kind == CST_EXPLAIN_CONNECT) {
        *L = color_madd(*L, g->beta, g->c);
        if (spectral) *H = color_madd(*H, g->beta, g->ch);
        return;
    }
    /* A volume vertex's merges: media_merge's per-lane 1 / ((4/3) pi r^3 N sigma_s). */
    const bool vol = g->depth >= 0 && g->depth <= RECORDER_PATH_MAX + 1 && r->merge_vol[g->depth];
    const Color norm = vol ? r->merge_norm[g->depth] : color_s(it->light.vcm_it.vm_norm);
    Color m = color_mul(g->c, norm), mh = color_mul(g->ch, norm);
    if (spectral && g->cam_dispersed) {
        m = color_add(m, mh);
        mh = color_s(0.0f);
        *H = color_madd(*H, g->beta, m);
    } else {
        *L = color_madd(*L, g->beta, m);
    }
    if (spectral) *H = color_madd(*H, g->beta, mh);
}

/* The recorded additions summed in the order path_li and subpath_trace_camera add them
 * (BDPT's connections of a vertex first among themselves), then as camera_tile turns the
 * path's value into the film's sample: spectral conversion, non-finite to 0, clamp, filter
 * weight. */
/* photon_li summed again: the specular chain's emission L (each emission or environment
 * it met madd'ed with its throughput, as photon_trace_to_diffuse adds it), plus beta (the
 * chain's throughput at the diffuse vertex x, which x's NEE event carries) times (the
 * direct light, plus the caustic map's estimate, plus the gather's throughput times the
 * global map's), each estimate the photons' f * power summed in the order the map visited
 * them, times the box kernel 1 / (pi r^2) (Jensen 2001 eq. 7.6). */
static Color replay_photon(const Recorder *r)
{
    Color L = color_s(0.0f), lx = color_s(0.0f), beta = color_s(1.0f), sum = color_s(0.0f);
    bool diffuse = false;
    for (int i = 0; i < r->n; i++) {
        const CstExplainEvent *e = &r->ev[i];
        switch (e->kind) {
        case CST_EXPLAIN_ESCAPE:
        case CST_EXPLAIN_EMISSION:
            if (e->flags & CST_EXPLAIN_ADDED) L = color_madd(L, r->beta[i], r->value[i]);
            break;
        case CST_EXPLAIN_NEE:
            lx = r->value[i];
            beta = r->beta[i];
            diffuse = true;
            break;
        case CST_EXPLAIN_PHOTON: sum = color_madd(sum, r->beta[i], r->value[i]); break;
        case CST_EXPLAIN_ESTIMATE: {
            /* pmf: the kernel the estimate used, its time window's factor included. */
            Color est = color_scale(sum, e->pmf);
            lx = color_add(lx, (e->flags & CST_EXPLAIN_CAUSTIC) ? est : color_mul(r->beta[i], est));
            sum = color_s(0.0f);
            break;
        }
        default: break;
        }
    }
    return diffuse ? color_madd(L, beta, lx) : L;
}

/* photon_li_media summed again, addition by addition in its order: the emission (and
 * environment) the camera walk met, each madd'ed with its throughput; NEE at a vertex in or
 * beside media (beta times the light sample); the caustic and global maps' estimates at
 * surface vertices, each times its vertex's throughput (the gather's included in y's); the
 * volume map's at a medium vertex, beta sum kernel / sigma_s per lane (Jensen & Christensen
 * 1998 eq. 11, photon.c's volume_estimate). */
static Color replay_photon_media(const Recorder *r)
{
    Color L = color_s(0.0f), sum = color_s(0.0f);
    for (int i = 0; i < r->n; i++) {
        const CstExplainEvent *e = &r->ev[i];
        if (e->kind == CST_EXPLAIN_PHOTON) {
            sum = color_madd(sum, r->beta[i], r->value[i]);
            continue;
        }
        if (!(e->flags & CST_EXPLAIN_ADDED)) continue;
        if (e->kind == CST_EXPLAIN_EMISSION || e->kind == CST_EXPLAIN_ESCAPE) {
            L = color_madd(L, r->beta[i], r->value[i]);
        } else if (e->kind == CST_EXPLAIN_NEE) {
            L = color_add(L, color_mul(r->beta[i], r->value[i]));
        } else if (e->kind == CST_EXPLAIN_ESTIMATE && (e->flags & CST_EXPLAIN_VOLUME)) {
            Color out = color_s(0.0f);
            if (e->pmf > 0.0f) {
                const float inv_vol = e->pmf; /* the kernel, its time window's factor included */
                for (int k = 0; k < COLOR_LANES; k++) {
                    const float ss = r->value[i].c[k];
                    out.c[k] = ss > 0.0f ? r->beta[i].c[k] * sum.c[k] * inv_vol / ss : 0.0f;
                }
            }
            L = color_add(L, out);
            sum = color_s(0.0f);
        } else if (e->kind == CST_EXPLAIN_ESTIMATE) {
            L = color_madd(L, r->beta[i], color_scale(sum, e->pmf));
            sum = color_s(0.0f);
        }
    }
    return L;
}

static Color replay(const Integrator *it, const Recorder *r, int x, int y, int sample, float *fw)
{
    /* L: the sample; H (spectral BDPT/VCM): what counts at the hero wavelength alone. */
    Color L = color_s(0.0f), H = color_s(0.0f);
    ReplayGroup g = {.depth = -1};
    if (it->kind == INTEGRATOR_WHITTED) {
        int i = 0;
        L = replay_whitted(r, &i);
    }
    if (it->kind == INTEGRATOR_PHOTON) {
        const Scene *sc = it->scene;
        L = sc->num_media || sc->num_medium_ifaces ? replay_photon_media(r) : replay_photon(r);
    }
    for (int i = 0; i <= r->n && it->kind != INTEGRATOR_WHITTED && it->kind != INTEGRATOR_PHOTON; i++) {
        const CstExplainEvent *e = i < r->n ? &r->ev[i] : NULL;
        const bool group = e && (e->kind == CST_EXPLAIN_CONNECT || e->kind == CST_EXPLAIN_MERGE) &&
                           (e->flags & CST_EXPLAIN_ADDED);
        if (g.depth >= 0 && (!group || e->depth != g.depth || (int)e->kind != g.kind)) {
            replay_flush(it, r, &g, &L, &H);
            g.depth = -1;
        }
        if (!e || !(e->flags & CST_EXPLAIN_ADDED) || e->kind == CST_EXPLAIN_SPLAT) continue;
        const bool hero = e->flags & CST_EXPLAIN_HERO;
        if (group) {
            if (g.depth < 0) {
                g = (ReplayGroup){e->depth, (int)e->kind, hero, r->beta[i], color_s(0.0f), color_s(0.0f)};
            }
            /* A connection counts at the hero alone when either subpath is dispersed; a
             * merge's sums are kept apart by the light vertex (replay_flush). */
            const bool apart = (e->flags & CST_EXPLAIN_LIGHT_DISPERSED) || (e->kind == CST_EXPLAIN_CONNECT && hero);
            if (apart) g.ch = color_add(g.ch, r->value[i]);
            else g.c = color_add(g.c, r->value[i]);
            continue;
        }
        if (hero) H = color_madd(H, r->beta[i], r->value[i]);
        else L = color_madd(L, r->beta[i], r->value[i]);
    }
    if (it->kind == INTEGRATOR_BIDIR && it->spectral) {
        /* subpath_trace_camera's end: H's hero lane times the lane count (the hero alone,
         * as spectrum_to_rgb counts a terminated path). */
        Color hero = color_s(0.0f);
        hero.c[0] = H.c[0] * (float)COLOR_LANES;
        L = color_add(L, hero);
    }
    if (it->spectral && r->has_wl) L = spectrum_to_rgb(L, &r->wl);
    if (!color_is_finite(L)) L = color_s(0.0f);
    else if (it->clamp > 0.0f) L = color_clamp_xyz_max(L, it->clamp);
    Sampler smp;
    sampler_start(&smp, &it->sampler, (uint64_t)y * (uint64_t)it->film->width + (uint64_t)x, (uint32_t)sample);
    Vec2 uf = sampler_2d(&smp);
    filter_film_position(&it->pixel_filter, x, y, uf, fw);
    if (*fw != 1.0f) L = color_scale(L, *fw);
    return L;
}

/* The render's steps for sample `sample`, each item run here in order on worker 0.
 * *camera: BDPT's iteration image at the pixel before the last step (the splat merge),
 * which is the camera step's sample. */
static CstStatus run(Integrator *it, Recorder *rec, int pixel, int sample, double camera[3], CstError *err)
{
    integrator_pass_begin(it, sample, 1);
    for (;;) {
        IntegratorStep step;
        CstStatus st = integrator_next_step(it, &step, err);
        if (st != CST_OK) return st;
        if (step.items == 0) return CST_OK;
        if (it->kind == INTEGRATOR_BIDIR) {
            it->light.vcm_it.rec = rec; /* vcm_iteration_init (the first step) clears it */
            memcpy(camera, &it->light.iteration_rgb[3 * (size_t)pixel], 3 * sizeof *camera);
        }
        for (int i = 0; i < step.items; i++) step.fn(step.ctx, i, 0);
    }
}

/* The light tracer: every light path of the iteration traced again (integrator.c), and
 * each splat's share of pixel (x, y) added as light_merge_band adds it, path by path in
 * the order the chunks made them; *sum gets the pixel's value. False on OOM. */
static bool explain_light(const Integrator *it, Recorder *r, int x, int y, int iteration, double sum[3])
{
    const SplatFrame *fr = &it->light.params.frame;
    const size_t pixels = (size_t)fr->width * (size_t)fr->height;
    const double scale = (double)pixels / (double)it->light.light_paths;
    double *row = calloc(3 * pixels, sizeof *row);
    SplatList l;
    if (!row || !splat_list_init(&l, 16)) {
        free(row);
        return false;
    }
    uint64_t rays = 0;
    double *px = &row[3 * ((size_t)y * (size_t)fr->width + (size_t)x)];
    sum[0] = sum[1] = sum[2] = 0.0;
    r->depth = 0;
    for (int i = 0; i < it->light.light_paths && !l.oom; i++) {
        l.n = 0;
        integrator_light_path(it, iteration, i, &l, &rays);
        for (size_t k = 0; k < l.n; k++) {
            const FilmSplat *sp = &l.v[k];
            if (y < sp->row0 || y > sp->row1) continue;
            film_add_splat_rows(sp, fr, row, scale, y, y + 1);
            const double share[3] = {px[0], px[1], px[2]};
            memset(&row[3 * (size_t)y * (size_t)fr->width], 0, 3 * (size_t)fr->width * sizeof *row);
            if (share[0] == 0.0 && share[1] == 0.0 && share[2] == 0.0) continue; /* adds no bit */
            for (int c = 0; c < 3; c++) sum[c] += share[c];
            CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SPLAT);
            e->flags |= CST_EXPLAIN_ADDED;
            e->t = 1;
            e->path = i;
            e->wi[0] = sp->x;
            e->wi[1] = sp->y;
            e->value[0] = sp->r; e->value[1] = sp->g; e->value[2] = sp->b;
            e->beta[0] = e->beta[1] = e->beta[2] = 1.0f;
            for (int c = 0; c < 3; c++) {
                e->share[c] = share[c];
                e->contribution[c] = (float)share[c];
            }
        }
    }
    const bool ok = !l.oom;
    splat_list_free(&l);
    free(row);
    return ok;
}

/* BDPT/VCM: the iteration's t = 1 splats on pixel (x, y) added to the camera sample as
 * light_merge_band adds them (chunk by chunk, each chunk's splats in the order they were
 * made, which is the order of its band's bin), each one's share kept in its SPLAT event
 * (matched by raster position: the recorder saw them in the same order); *film gets the
 * pixel's value. False on OOM. */
static bool explain_splats(const Integrator *it, Recorder *r, int x, int y, const double camera[3], double film[3])
{
    const LightIterations *L = &it->light;
    const SplatFrame *fr = &L->params.frame;
    const size_t pixels = (size_t)fr->width * (size_t)fr->height;
    const double scale = (double)pixels / (double)L->light_paths;
    double *row = calloc(3 * pixels, sizeof *row);
    if (!row) return false;
    double *px = &row[3 * ((size_t)y * (size_t)fr->width + (size_t)x)];
    for (int c = 0; c < 3; c++) film[c] = camera[c];
    int next = 0; /* the next SPLAT event to match */
    for (int ch = 0; ch < L->num_chunks; ch++) {
        const SplatList *l = &L->chunks[ch].splats;
        for (size_t k = 0; k < l->n; k++) {
            const FilmSplat *sp = &l->v[k];
            if (y < sp->row0 || y > sp->row1) continue;
            film_add_splat_rows(sp, fr, row, scale, y, y + 1);
            const double share[3] = {px[0], px[1], px[2]};
            memset(&row[3 * (size_t)y * (size_t)fr->width], 0, 3 * (size_t)fr->width * sizeof *row);
            if (share[0] == 0.0 && share[1] == 0.0 && share[2] == 0.0) continue; /* adds no bit */
            for (int c = 0; c < 3; c++) film[c] += share[c];
            for (int i = next; i < r->n; i++) {
                CstExplainEvent *e = &r->ev[i];
                if (e->kind != CST_EXPLAIN_SPLAT || e->wi[0] != sp->x || e->wi[1] != sp->y) continue;
                for (int c = 0; c < 3; c++) e->share[c] = share[c];
                next = i + 1;
                break;
            }
        }
    }
    free(row);
    return true;
}

CstStatus explain_begin(ExplainRun *xr, const Scene *scene, const CstRenderSettings *st, int x, int y, int sample,
                        int cap, CstError *err)
{
    memset(xr, 0, sizeof *xr);
    xr->ex = calloc(1, sizeof *xr->ex);
    xr->film = film_create(st->width, st->height);
    xr->it = calloc(1, sizeof *xr->it);
    xr->rec.cap = cap;
    xr->rec.ev = calloc((size_t)cap, sizeof *xr->rec.ev);
    xr->rec.beta = calloc((size_t)cap, sizeof *xr->rec.beta);
    xr->rec.value = calloc((size_t)cap, sizeof *xr->rec.value);
    xr->rec.px = x;
    xr->rec.py = y;
    if (!xr->ex || !xr->film || !xr->it || !xr->rec.ev || !xr->rec.beta || !xr->rec.value)
        return cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", st->width, st->height);
    CstStatus status = integrator_prepare(xr->it, scene, st, xr->film, &xr->worker, &xr->rays, NULL, NULL, err);
    if (status != CST_OK) return status;
    xr->ex->x = x;
    xr->ex->y = y;
    xr->ex->sample = sample;
    xr->ex->integrator = st->integrator;
    xr->ex->spectral = xr->it->spectral;
    return CST_OK;
}

CstStatus explain_finish(ExplainRun *xr, CstStatus status, CstExplain **out)
{
    if (status == CST_OK) {
        xr->ex->num_events = xr->rec.n;
        xr->ex->events = xr->rec.ev;
        xr->rec.ev = NULL;
        *out = xr->ex;
        xr->ex = NULL;
    }
    if (xr->it) integrator_destroy(xr->it);
    free(xr->it);
    film_destroy(xr->film);
    free(xr->rec.ev);
    free(xr->rec.beta);
    free(xr->rec.value);
    recorder_mlt_free(&xr->rec);
    cst_explain_destroy(xr->ex);
    return status;
}

CstStatus cst_explain(const CstScene *scene, const CstRenderSettings *settings, int x, int y, int sample,
                      CstExplain **out, CstError *err)
{
    *out = NULL;
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.integrator == CST_INTEGRATOR_DEFAULT) st.integrator = CST_INTEGRATOR_PATH;
    CstStatus status = check(scene, &st, x, y, sample, err);
    if (status != CST_OK) return status;
    if (st.integrator == CST_INTEGRATOR_SPPM) return explain_sppm(scene, &st, x, y, sample, out, err);
    /* One pixel, one sample, one thread, nothing but the film's sums. */
    st.threads = 1;
    st.first_sample = sample;
    /* (MLT: the chains roam the whole film, which the iteration's merge writes.) */
    const bool mlt = st.integrator == CST_INTEGRATOR_PSSMLT || st.integrator == CST_INTEGRATOR_MMLT;
    if (!mlt) {
        st.crop[0] = x; st.crop[1] = x + 1; st.crop[2] = y; st.crop[3] = y + 1;
    }
    st.aovs = 0;
    st.time_limit = 0.0;
    st.sample_block = 1;
    st.resume = NULL;
    st.pass_done = NULL;
    st.progress = NULL;

    ExplainRun xr;
    if ((status = explain_begin(&xr, scene, &st, x, y, sample, EXPLAIN_EVENTS, err)) != CST_OK)
        return explain_finish(&xr, status, out);
    CstExplain *ex = xr.ex;
    Film *film = xr.film;
    Integrator *it = xr.it;
    Recorder *rec = &xr.rec;
    rec->paths.light_path = y * st.width + x; /* BDPT: the light subpath of the pixel's index */
    ex->photon_set = -1;
    if (it->kind == INTEGRATOR_PATH) it->path.rec = rec;
    else if (it->kind == INTEGRATOR_WHITTED) it->whitted.rec = rec;
    else if (it->kind == INTEGRATOR_PHOTON) it->photon.rec = rec;
    else if (it->kind == INTEGRATOR_LIGHT) rec->radius = 0.0f;
    else rec->radius = filter_radius(it->light.vcm_params.frame.filter);
    /* BDPT, VCM: the pixel's light subpath listed too (not summed) */
    rec->light_events = it->kind == INTEGRATOR_BIDIR && !mlt;
    const int pixel = y * st.width + x;
    double camera[3] = {0.0, 0.0, 0.0};
    if (mlt) {
        if ((status = explain_mlt(it, film, rec, x, y, sample, ex, err)) != CST_OK) goto done;
        ex->truncated = rec->truncated;
        goto done;
    }
    if ((status = run(it, rec, pixel, sample, camera, err)) != CST_OK) goto done;

    ex->truncated = rec->truncated;
    Color sum = replay(it, rec, x, y, sample, &ex->filter_weight);
    for (int c = 0; c < 3; c++) {
        ex->sum[c] = sum.c[c];
        ex->film_value[c] = film->sum[3 * (size_t)pixel + (size_t)c];
        ex->camera_value[c] = it->kind == INTEGRATOR_BIDIR ? camera[c] : ex->film_value[c];
        ex->splat_value[c] = ex->film_value[c] - ex->camera_value[c];
    }
    if (it->spectral && rec->has_wl) {
        for (int k = 0; k < 4 && k < COLOR_LANES; k++) ex->wavelengths[k] = rec->wl.lambda[k];
    }
    if (it->kind == INTEGRATOR_PHOTON && it->spectral && rec->has_wl) {
        /* The set the sample picked (photon_maps_pick): the one whose wavelengths it took. */
        for (int k = 0; k < it->photon.num_sets; k++)
            if (memcmp(&it->photon.sets[k].wl, &rec->wl, sizeof rec->wl) == 0) ex->photon_set = k;
    }
    ex->exact = !rec->truncated;
    for (int c = 0; c < 3; c++) {
        /* Added to a zeroed sum, as the film adds it: a -0 contribution leaves +0 there. */
        double s = 0.0 + (double)ex->sum[c];
        if (memcmp(&s, &ex->camera_value[c], sizeof s) != 0) ex->exact = 0;
    }
    if (it->kind == INTEGRATOR_LIGHT) {
        /* No camera step: the film's value is the splats', summed again here. */
        double light[3];
        if (!explain_light(it, rec, x, y, sample, light)) {
            status = cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", st.width, st.height);
            goto done;
        }
        ex->truncated = rec->truncated;
        ex->exact = !rec->truncated;
        ex->filter_weight = 1.0f;
        for (int c = 0; c < 3; c++) {
            ex->sum[c] = (float)light[c];
            ex->camera_value[c] = 0.0;
            ex->splat_value[c] = ex->film_value[c];
            if (memcmp(&light[c], &ex->film_value[c], sizeof light[c]) != 0) ex->exact = 0;
        }
    }
    if (it->kind == INTEGRATOR_BIDIR) {
        double film_sum[3];
        if (!explain_splats(it, rec, x, y, ex->camera_value, film_sum) || !explain_mis_check(it, sample, rec, ex)) {
            status = cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", st.width, st.height);
            goto done;
        }
        ex->splats_exact = memcmp(film_sum, ex->film_value, sizeof film_sum) == 0;
    }
done:
    return explain_finish(&xr, status, out);
}
