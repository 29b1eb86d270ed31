/* The one render driver: every integrator (integrators/integrator.h) runs here as passes
 * of samples, each pass a sequence of parallel steps on one thread pool made once per
 * render; this file reports progress, honours cancellation at work-item boundaries, and
 * crops and reports the film. Images are bit-identical for any thread count: the work
 * is cut into items by the integrator, never by the threads (integrator.c). */
#include "render/render.h"

#include <limits.h>
#include <inttypes.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/clock.h"
#include "core/error.h"
#include "core/threadpool.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "render/adaptive.h"
#include "scene/scene.h"

/* Passes a fixed-spp render of few camera tiles is cut into, for progress (run_passes). */
enum { RENDER_SPLIT_PASSES = 20 };

/* What the passes share: the pool, the integrator, and progress reporting. */
typedef struct Driver {
    ThreadPool *pool;
    Integrator *it;
    const CstRenderSettings *st;
    double t0;            /* the render's start */
    double last_progress; /* when progress was last reported: light iterations can be short */
    bool stopped;         /* pass_done asked to stop */
} Driver;

/* With a pass_done callback, the longest a pass is planned to take: a stop (Ctrl-C in the
 * CLI) waits for the pass in progress, and a checkpoint can only be written between
 * passes. Per-pass costs (a pool dispatch, the callback) are microseconds against it. */
#define RENDER_PASS_SECONDS 1.0

/* After a pass: tells pass_done, if any, that samples [0, done) are complete. Returns
 * true when it asked to stop. */
static bool pass_finished(Driver *d, int done, bool last)
{
    const CstRenderSettings *st = d->st;
    if (!st->pass_done) return false;
    if (d->it->kind != INTEGRATOR_SPPM) d->it->film->spp = done;
    CstPassInfo info = {done, last, clock_seconds() - d->t0};
    /* SPPM, MLT: its state into the film, for a checkpoint the callback may write. Without
     * the memory for it the state is left out: refused as a resume, never wrong. */
    if (!integrator_export_progressive(d->it, done)) {
        free(d->it->film->progressive);
        d->it->film->progressive = NULL;
        free(d->it->film->chains);
        d->it->film->chains = NULL;
        d->it->film->chains_len = 0;
    }
    if (st->pass_done(st->pass_user, d->it->film, &info) == 0) return false;
    d->stopped = !last;
    return true;
}

/* Runs one step on the pool while the calling thread reports progress, f of the render
 * being done_before + fraction * (the step's share of its pass). Returns
 * CST_ERR_CANCELLED when the progress callback asked to stop: the items already running
 * finish, no other starts. */
static CstStatus run_step(Driver *d, const IntegratorStep *step, double done_before, double fraction)
{
    const CstRenderSettings *st = d->st;
    threadpool_begin(d->pool, step->items, step->fn, step->ctx);
    bool cancelled = false, done = false;
    while (!done) {
        done = threadpool_wait(d->pool, cancelled || !st->progress ? -1.0 : 0.1);
        if (cancelled || !st->progress) continue;
        /* Reported after every wait, the step's end included, but for short steps about
         * 10 times a second at most. */
        if (step->throttle && clock_seconds() - d->last_progress < 0.1) continue;
        d->last_progress = clock_seconds();
        double share = step->progress_lo + (step->progress_hi - step->progress_lo) *
                                               threadpool_done(d->pool) / step->items;
        double f = done_before + fraction * share;
        if (st->time_limit > 0.0) {
            double ft = (clock_seconds() - d->t0) / st->time_limit;
            f = ft > f ? ft : f;
        }
        if (st->progress(st->progress_user, f > 1.0 ? 1.0 : f, clock_seconds() - d->t0) != 0) {
            threadpool_cancel(d->pool);
            cancelled = true;
        }
    }
    return cancelled ? CST_ERR_CANCELLED : CST_OK;
}

/* Samples (iterations) [first, first + count) of every pixel: the integrator's steps for
 * them, in order. */
static CstStatus run_pass(Driver *d, int first, int count, double done_before, double fraction, CstError *err)
{
    integrator_pass_begin(d->it, first, count);
    for (;;) {
        IntegratorStep step;
        CstStatus status = integrator_next_step(d->it, &step, err);
        if (status != CST_OK || step.items == 0) return status;
        if ((status = run_step(d, &step, done_before, fraction)) != CST_OK)
            return cst_fail(err, status, "render cancelled by the progress callback");
    }
}

/* Every pass of the render, from sample *done (a resumed film's count, else 0); *done:
 * the samples completed. Every pixel always holds the same number of samples, each
 * pixel's in sample order, so how the samples are cut into passes never changes the
 * image (light, bdpt and vcm: iterations, each a function of its index alone). */
static CstStatus run_passes(Driver *d, int *done, CstError *err)
{
    const CstRenderSettings *st = d->st;
    const int start = *done;
    /* Fixed sample count: one pass. With camera tiles too few to show progress (a small
     * image or crop at high spp), up to RENDER_SPLIT_PASSES passes of consecutive
     * samples. */
    if (st->time_limit <= 0.0 && !st->pass_done) {
        const IntegratorKind kind = d->it->kind;
        const int todo = st->spp - start;
        int passes = todo > 0 ? 1 : 0;
        if ((kind == INTEGRATOR_PATH || kind == INTEGRATOR_WHITTED || kind == INTEGRATOR_PHOTON) &&
            d->it->num_tiles < 8 * st->threads)
            passes = todo < RENDER_SPLIT_PASSES ? todo : RENDER_SPLIT_PASSES;
        for (int k = 0; k < passes; k++) {
            int first = start + (int)((int64_t)todo * k / passes);
            int last = start + (int)((int64_t)todo * (k + 1) / passes);
            CstStatus status = run_pass(d, st->first_sample + first, last - first, (double)first / st->spp,
                                        (double)(last - first) / st->spp, err);
            if (status != CST_OK) return status;
            *done = last;
        }
        return CST_OK;
    }
    /* Passes of growing size until the sample cap is reached (without one, INT_MAX, less
     * first_sample) or, with a time budget, the next one would not fit; with pass_done,
     * none planned longer than RENDER_PASS_SECONDS. Every pixel always holds the same
     * number of samples. */
    const int cap = st->spp > 0 ? st->spp : INT_MAX - st->first_sample;
    const double budget = st->time_limit > 0.0 ? st->time_limit : (double)INFINITY;
    int pass = 1;
    for (;;) {
        if (pass > cap - *done) pass = cap - *done;
        if (pass <= 0) {
            pass_finished(d, *done, true); /* a resume with nothing left to render */
            return CST_OK;
        }
        double pass_t0 = clock_seconds();
        double frac = st->spp > 0 ? (double)*done / st->spp : 0.0;
        CstStatus status = run_pass(d, st->first_sample + *done, pass, frac, st->spp > 0 ? (double)pass / st->spp : 0.0, err);
        if (status != CST_OK) return status;
        *done += pass;
        double now = clock_seconds(), pass_time = now - pass_t0;
        double left = budget - (now - d->t0);
        /* Next pass: the largest of 2x, x, x/2, ... that is predicted to fit in the time left. */
        double per_spp = pass_time / pass;
        int next = pass <= INT_MAX / 2 ? pass * 2 : pass;
        while (next > 1 && per_spp * next > left) next /= 2;
        if (st->pass_done)
            while (next > 1 && per_spp * next > RENDER_PASS_SECONDS) next /= 2;
        bool last = *done >= cap || left <= 0.0 || per_spp * next > left;
        if (pass_finished(d, *done, last) || last) return CST_OK;
        pass = next;
    }
}

/* Every block of a render with sample_block B > 1, from sample *done (a resumed film's
 * count, at a block end): each block's samples [kB, (k+1)B), cut at the render's range,
 * are rendered into `block` (zeroed first), whose sums are then added to the film's, in
 * block order. A film of whole blocks rendered elsewhere (an MPI rank, another machine)
 * holds exactly the sums of `block` here, so they combine bit for bit (cst_film_add). The
 * pass callback, the time limit and stops act at block ends: only there is the film the
 * sum of whole blocks. */
static CstStatus run_blocks(Driver *d, Film *block, int *done, CstError *err)
{
    const CstRenderSettings *st = d->st;
    const int B = st->sample_block;
    const int cap = st->spp > 0 ? st->spp : INT_MAX - st->first_sample;
    const double budget = st->time_limit > 0.0 ? st->time_limit : (double)INFINITY;
    Film *film = d->it->film;
    const size_t n = 3 * (size_t)film->width * (size_t)film->height;
    if (*done >= cap) {
        pass_finished(d, *done, true); /* a resume with nothing left to render */
        return CST_OK;
    }
    while (*done < cap) {
        const int s0 = st->first_sample + *done;
        const int64_t end = ((int64_t)s0 / B + 1) * B;
        int count = (int)(end - s0);
        if (count > cap - *done) count = cap - *done;
        memset(block->sum, 0, n * sizeof *block->sum);
        memset(block->sum_sq, 0, n * sizeof *block->sum_sq);
        if (block->aov) memset(block->aov, 0, n / 3 * FILM_AOV_STRIDE * sizeof *block->aov);
        const double t0 = clock_seconds();
        d->it->film = block;
        CstStatus status = run_pass(d, s0, count, st->spp > 0 ? (double)*done / st->spp : 0.0,
                                    st->spp > 0 ? (double)count / st->spp : 0.0, err);
        d->it->film = film;
        if (status != CST_OK) return status;
        film_add(film, block);
        *done += count;
        /* The next block is predicted to take as long as this one, per sample. */
        const double now = clock_seconds(), per_spp = (now - t0) / count;
        const bool last = *done >= cap || now - d->t0 + per_spp * B > budget;
        if (pass_finished(d, *done, last) || last) return CST_OK;
    }
    return CST_OK;
}

/* The next round of run_adaptive: with per-pixel counts, runs[0..*n); else *more
 * iterations of the whole image. Returns its pixel samples, 0 when the render is done. */
static uint64_t plan_round(const Film *film, const AdaptiveGrid *g, const CstRenderSettings *st, int cap,
                           IntegratorTileRun *runs, int *n, int *more)
{
    uint64_t samples = 0;
    if (film->pixel_spp) {
        *n = adaptive_plan(film, g, st->noise_target, cap, runs, &samples);
        return samples;
    }
    *more = adaptive_plan_uniform(film, g, st->noise_target, cap);
    return (uint64_t)*more * (uint64_t)(g->x1 - g->x0) * (uint64_t)(g->y1 - g->y0);
}

/* A render with a noise target (adaptive.h), from the film as it is (a resumed one's sums
 * and counts): rounds until no block asks for more samples, the sample cap (per pixel)
 * or the time limit. Camera integrators: each round renders only the blocks above the
 * target, each its own next samples (film->pixel_spp); light, bdpt and vcm: a round of
 * iterations of the whole image, as many as the worst block asks for. Each round is
 * planned from the completed rounds' sums alone; the time limit and pass_done act
 * between rounds (a round is not cut: its plan is not in a state file). *done: film->spp. */
static CstStatus run_adaptive(Driver *d, int *done, CstError *err)
{
    const CstRenderSettings *st = d->st;
    Integrator *it = d->it;
    Film *film = it->film;
    const int cap = st->spp > 0 ? st->spp : CST_NOISE_SPP_CAP;
    const double budget = st->time_limit > 0.0 ? st->time_limit : (double)INFINITY;
    const AdaptiveGrid g = adaptive_grid(st->crop);
    const bool per_block = film->pixel_spp != NULL;
    IntegratorTileRun *runs = per_block ? malloc((size_t)g.tiles * sizeof *runs) : NULL;
    if (per_block && !runs) return cst_fail(err, CST_ERR_OOM, "out of memory for %d blocks", g.tiles);
    CstStatus status = CST_OK;
    int n = 0, more = 0; /* the round planned: runs[0..n), or `more` iterations of the whole image */
    uint64_t samples = plan_round(film, &g, st, cap, runs, &n, &more);
    if (samples == 0) pass_finished(d, film->spp, true); /* a resume with nothing left to render */
    while (samples > 0) {
        const double t0 = clock_seconds();
        if (per_block) {
            it->tile_runs = runs;
            it->num_tile_runs = n;
            /* Progress: the share of blocks already within the target. */
            status = run_pass(d, 0, 1, 1.0 - (double)n / g.tiles, 0.0, err);
            it->tile_runs = NULL;
            if (status == CST_OK) adaptive_commit(film, &g, runs, n);
        } else {
            status = run_pass(d, film->spp, more, 0.0, 0.0, err);
            if (status == CST_OK) film->spp += more;
        }
        if (status != CST_OK) break;
        /* The next round is predicted to cost what this one did per pixel sample. */
        const double now = clock_seconds(), per_sample = (now - t0) / (double)samples;
        samples = plan_round(film, &g, st, cap, runs, &n, &more);
        const bool last = samples == 0 || now - d->t0 + per_sample * (double)samples > budget;
        if (pass_finished(d, film->spp, last) || last) break;
    }
    *done = film->spp;
    free(runs);
    return status;
}

/* The photon pass's progress (integrator_prepare), throttled like run_step's: the phase's
 * own fraction when the caller follows phases, else 0 (or the time limit's share). */
static int prepare_progress(void *user, double fraction)
{
    Driver *d = user;
    const CstRenderSettings *st = d->st;
    double now = clock_seconds();
    if (now - d->last_progress < 0.1) return 0;
    d->last_progress = now;
    double f = st->progress_phase ? fraction : 0.0;
    if (!st->progress_phase && st->time_limit > 0.0) f = (now - d->t0) / st->time_limit;
    return st->progress(st->progress_user, f > 1.0 ? 1.0 : f, now - d->t0);
}

uint64_t cst_render_memory_estimate(const CstScene *scene, const CstRenderSettings *settings)
{
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    const uint64_t pixels = (uint64_t)(st.width > 0 ? st.width : 0) * (uint64_t)(st.height > 0 ? st.height : 0);
    const uint64_t cw = (uint64_t)(st.crop[1] > st.crop[0] ? st.crop[1] - st.crop[0] : 0);
    const uint64_t crop = cw * (uint64_t)(st.crop[3] > st.crop[2] ? st.crop[3] - st.crop[2] : 0);
    uint64_t per_pixel = 6 * sizeof(double); /* film_create: sum and sum of squares */
    if (st.aovs & FILM_AOV_FIRST_HIT) per_pixel += FILM_AOV_STRIDE * sizeof(double);
    if (st.sample_block > 1) per_pixel *= 2; /* run_blocks' block film: the sums and AOV sums again */
    if (st.noise_target > 0.0) per_pixel += sizeof(int); /* Film.pixel_spp (adaptive.h) */
    if (st.integrator == CST_INTEGRATOR_LIGHT || st.integrator == CST_INTEGRATOR_BDPT ||
        st.integrator == CST_INTEGRATOR_VCM || st.integrator == CST_INTEGRATOR_PSSMLT ||
        st.integrator == CST_INTEGRATOR_MMLT)
        per_pixel += 3 * sizeof(double); /* the iteration's image */
    uint64_t bytes = pixels * per_pixel;
    if (crop != pixels) bytes += crop * (6 + ((st.aovs & FILM_AOV_FIRST_HIT) ? FILM_AOV_STRIDE : 0)) * sizeof(double);
    return bytes + crop * 3 * sizeof(float); /* cst_film_write's float image */
}

/* The pixel samples the crop's pixels hold. */
static uint64_t crop_samples(const Film *f, const AdaptiveGrid *g)
{
    uint64_t total = 0;
    for (int y = g->y0; y < g->y1; y++)
        for (int x = g->x0; x < g->x1; x++) total += (uint64_t)film_pixel_spp(f, (size_t)y * (size_t)f->width + (size_t)x);
    return total;
}

static void fill_stats(CstRenderStats *stats, const CstRenderSettings *st, const Integrator *it,
                       const IntegratorWorker *workers, int first, int samples, uint64_t rays, double seconds)
{
    const int cw = st->crop[1] - st->crop[0], ch = st->crop[3] - st->crop[2];
    memset(stats, 0, sizeof *stats);
    stats->seconds = seconds;
    /* SPPM: the film holds one final estimate per pixel; spp reports the iterations. */
    stats->spp = samples;
    stats->threads = st->threads;
    stats->width = cw;
    stats->height = ch;
    stats->integrator = st->integrator;
    stats->filter = st->filter;
    /* Light tracing traces width x height light paths per iteration, whatever the crop
     * (and BDPT/VCM as many light paths as there are pixels, SPPM as many visible
     * points); camera passes cover the crop. */
    bool whole = it->kind == INTEGRATOR_LIGHT || it->kind == INTEGRATOR_BIDIR || it->kind == INTEGRATOR_SPPM ||
                 it->kind == INTEGRATOR_PSSMLT;
    uint64_t per_spp = whole ? (uint64_t)st->width * (uint64_t)st->height : (uint64_t)cw * (uint64_t)ch;
    stats->samples = (uint64_t)(samples - first) * per_spp;
    stats->first_spp = first;
    stats->rays = rays;
    integrator_counters(it, &stats->rays, &stats->nonfinite);
    for (int i = 0; i < st->threads; i++) {
        stats->rays += workers[i].rays;
        stats->nonfinite += workers[i].nonfinite;
    }
}

CstStatus cst_film_create(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out, CstError *err)
{
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    const int cw = st.crop[1] - st.crop[0], ch = st.crop[3] - st.crop[2];
    *out = NULL;
    if (cw <= 0 || ch <= 0 || cw > 65536 || ch > 65536)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_create: a %dx%d film; expected 1..65536 in each "
                        "dimension", cw, ch);
    Film *film = film_create(cw, ch);
    if (film) film_set_white_balance(film, st.white_balance);
    if (film && !film_set_output(film, st.aovs, st.exposure, st.png_linear)) {
        film_destroy(film);
        film = NULL;
    }
    if (!film) return cst_fail(err, CST_ERR_OOM, "out of memory for a %dx%d film", cw, ch);
    *out = film;
    return CST_OK;
}

/* A film to resume st from (every integrator can: cst_integrator_resumable): the same size
 * and AOVs, no more samples than asked for, and for SPPM its state. */
static CstStatus check_resume(const CstRenderSettings *st, const Film *resume, CstError *err)
{
    if (resume->width != st->width || resume->height != st->height ||
        (!resume->aov) != !(st->aovs & FILM_AOV_FIRST_HIT) || resume->spp < 0 ||
        (st->spp > 0 && resume->spp > st->spp))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "resume: a %dx%d film%s of %d samples for a %dx%d render%s of %d: expected the same "
                        "size and AOVs, and no more samples (cst_film_state_read checks a state file)",
                        resume->width, resume->height, resume->aov ? " with AOV sums" : "", resume->spp, st->width,
                        st->height, (st->aovs & FILM_AOV_FIRST_HIT) ? " with AOV sums" : "", st->spp);
    const bool mlt = st->integrator == CST_INTEGRATOR_PSSMLT || st->integrator == CST_INTEGRATOR_MMLT;
    if (mlt != (resume->chains != NULL))
        return cst_fail(err, CST_ERR_INVALID_ARG, "resume: %s", mlt ? "the film holds no MLT chains (the state of "
                        "every chain and b, state version 4)" : "a film with MLT chains for another integrator");
    if (st->integrator == CST_INTEGRATOR_SPPM && !resume->progressive)
        return cst_fail(err, CST_ERR_INVALID_ARG, "resume: the film holds no SPPM state (per-pixel radii, photon "
                        "counts and flux); expected a state written by a checkpoint of an sppm render");
    return CST_OK;
}

/* The render's film (NULL on OOM): empty, or with a resumed film's sums and counts (the
 * passes add to them in the order an uninterrupted render would have); per-pixel counts
 * when per_block. */
static Film *render_film(const CstRenderSettings *st, bool per_block)
{
    const Film *resume = st->resume;
    Film *film = film_create(st->width, st->height);
    if (film) film_set_white_balance(film, st->white_balance);
    if (!film || !film_set_output(film, st->aovs, st->exposure, st->png_linear) ||
        (per_block && !film_enable_pixel_spp(film))) {
        film_destroy(film);
        return NULL;
    }
    if (resume) {
        const size_t n = (size_t)st->width * (size_t)st->height;
        memcpy(film->sum, resume->sum, 3 * n * sizeof *film->sum);
        memcpy(film->sum_sq, resume->sum_sq, 3 * n * sizeof *film->sum_sq);
        if (film->aov) memcpy(film->aov, resume->aov, n * FILM_AOV_STRIDE * sizeof *film->aov);
        if (film->pixel_spp) memcpy(film->pixel_spp, resume->pixel_spp, n * sizeof *film->pixel_spp);
        film->spp = resume->spp;
    }
    return film;
}

/* The noise fields of a render's stats from adaptive_summary's; with per-block sampling
 * also the pixel samples taken (light paths: as fill_stats counts them). */
static void noise_stats_copy(CstRenderStats *done, const CstRenderStats *noise, bool per_block)
{
    done->noise_rms = noise->noise_rms;
    done->noise_rms_lo = noise->noise_rms_lo;
    done->noise_rms_hi = noise->noise_rms_hi;
    done->noise_max = noise->noise_max;
    done->noise_blocks = noise->noise_blocks;
    done->noise_blocks_over = noise->noise_blocks_over;
    done->spp_min = noise->spp_min;
    if (per_block) done->samples = noise->samples;
}

/* The noise target's checks (and spp 0's without a time limit, which a target allows). */
static CstStatus check_noise(const CstRenderSettings *st, bool *per_block, CstError *err)
{
    /* Camera integrators sample each block on its own under a noise target. */
    const CstIntegrator i = st->integrator;
    *per_block = st->noise_target > 0.0 && (i == CST_INTEGRATOR_PATH || i == CST_INTEGRATOR_PATH_NEE ||
                                            i == CST_INTEGRATOR_PATH_BSDF || i == CST_INTEGRATOR_WHITTED ||
                                            i == CST_INTEGRATOR_PHOTON || i == CST_INTEGRATOR_DEFAULT);
    if (st->resume && (!st->resume->pixel_spp) != !*per_block)
        return cst_fail(err, CST_ERR_INVALID_ARG, "resume: a film %s per-pixel sample counts for a render %s them "
                        "(a noise target with a camera integrator keeps them)",
                        st->resume->pixel_spp ? "with" : "without", *per_block ? "with" : "without");
    if (!(st->noise_target >= 0.0 && st->noise_target < (double)INFINITY))
        return cst_fail(err, CST_ERR_INVALID_ARG, "noise target %g: expected a relative standard error > 0 (or 0: "
                        "none)", st->noise_target);
    if (st->spp == 0 && !(st->time_limit > 0.0) && !(st->noise_target > 0.0))
        return cst_fail(err, CST_ERR_INVALID_ARG, "spp CST_SPP_UNLIMITED without a time limit would never end; "
                        "expected a time limit, or a sample count");
    if (st->noise_target > 0.0 && (st->integrator == CST_INTEGRATOR_SPPM || st->integrator == CST_INTEGRATOR_PSSMLT))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "noise target: the %s integrator's pixels are not means of "
                        "independent samples (%s), so their variances say nothing of the error; expected path, "
                        "path-nee, path-bsdf, whitted, photon (per block), light, bdpt or vcm (whole image)",
                        cst_integrator_name(st->integrator),
                        st->integrator == CST_INTEGRATOR_SPPM ? "one progressive estimate" : "Markov chains");
    if (st->noise_target > 0.0 && (st->first_sample > 0 || st->sample_block > 1))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "noise target with first_sample %d and sample_block %d: adaptive "
                        "rounds are planned from the whole film; expected first_sample 0 and sample_block 1",
                        st->first_sample, st->sample_block);
    return CST_OK;
}

CstStatus cst_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                     CstRenderStats *stats, CstError *err)
{
    *out = NULL;
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.width <= 0 || st.height <= 0 || st.width > 65536 || st.height > 65536)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image size %dx%d: expected 1..65536 in each dimension",
                        st.width, st.height);
    if (st.spp < 0 || st.time_limit < 0.0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "spp and time limit must be positive");
    bool per_block;
    const CstStatus noise_ok = check_noise(&st, &per_block, err);
    if (noise_ok != CST_OK) return noise_ok;
    const bool noise = st.noise_target > 0.0;
    if (!scene->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene not committed");
    if (st.first_sample < 0 || st.first_sample > INT_MAX - (st.spp > 0 ? st.spp : INT_MAX / 2))
        return cst_fail(err, CST_ERR_INVALID_ARG, "first_sample %d: expected >= 0, with first_sample + spp "
                        "within an int", st.first_sample);
    if (st.first_sample > 0 && st.integrator == CST_INTEGRATOR_SPPM)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "first_sample %d: SPPM's iterations depend on every one "
                        "before them (radii, flux); expected first_sample 0 for sppm", st.first_sample);
    if (st.first_sample > 0 && (st.integrator == CST_INTEGRATOR_PSSMLT || st.integrator == CST_INTEGRATOR_MMLT))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "first_sample %d: MLT's mutations continue its chains from "
                        "every one before them; expected first_sample 0 for %s", st.first_sample,
                        cst_integrator_name(st.integrator));
    if (!(0 <= st.crop[0] && st.crop[0] < st.crop[1] && st.crop[1] <= st.width && 0 <= st.crop[2] &&
          st.crop[2] < st.crop[3] && st.crop[3] <= st.height))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "crop [%d, %d) x [%d, %d): expected 0 <= x0 < x1 <= %d and 0 <= y0 < y1 <= %d (the "
                        "image's width and height)",
                        st.crop[0], st.crop[1], st.crop[2], st.crop[3], st.width, st.height);

    if (st.integrator == CST_INTEGRATOR_LIGHT && scene->camera.ortho_height > 0.0f)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "the light tracer cannot render through an orthographic camera (its rays are "
                        "parallel, so no light path can connect to it); expected a pinhole or thin-lens "
                        "camera, or another integrator");
    if ((st.aovs & FILM_AOV_FIRST_HIT) &&
        (st.integrator == CST_INTEGRATOR_LIGHT || st.integrator == CST_INTEGRATOR_SPPM ||
         st.integrator == CST_INTEGRATOR_PSSMLT || st.integrator == CST_INTEGRATOR_MMLT))
        return cst_fail(err, CST_ERR_UNSUPPORTED,
                        "the albedo, normal and depth AOVs come from camera rays, which the %s integrator "
                        "does not trace; expected path, path-nee, path-bsdf, whitted, photon, bdpt or vcm "
                        "(the variance AOV works with every integrator)",
                        cst_integrator_name(st.integrator));
    if (st.sample_block < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "sample_block %d: expected a number of samples >= 1",
                        st.sample_block);
    if (st.sample_block > 1 && st.integrator == CST_INTEGRATOR_SPPM)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "sample_block %d: SPPM's film is one estimate, not sums of "
                        "samples; expected sample_block 1 for sppm", st.sample_block);
    if (st.resume && st.sample_block > 1 && (st.first_sample + st.resume->spp) % st.sample_block != 0 &&
        !(st.spp > 0 && st.resume->spp >= st.spp))
        return cst_fail(err, CST_ERR_INVALID_ARG, "resume: the film ends at sample %d, inside a block of %d; "
                        "expected a film of whole blocks (a state written at a block end)",
                        st.first_sample + st.resume->spp, st.sample_block);
    const Film *resume = st.resume;
    CstStatus rst = resume ? check_resume(&st, resume, err) : CST_OK;
    if (rst != CST_OK) return rst;
    Film *film = render_film(&st, per_block);
    IntegratorWorker *workers = calloc((size_t)st.threads, sizeof *workers);
    Integrator *it = calloc(1, sizeof *it);
    Driver d = {NULL, it, &st, clock_seconds(), 0.0, false};
    CstStatus status = CST_OK;
    uint64_t rays = 0;
    int samples = resume ? resume->spp : 0, first = samples;
    const AdaptiveGrid grid = adaptive_grid(st.crop);
    const uint64_t pixel_samples0 = film && noise ? crop_samples(film, &grid) : 0;
    if (!film || !workers || !it)
        status = cst_fail(err, CST_ERR_OOM, "out of memory for a %dx%d film", st.width, st.height);
    else if ((status = threadpool_create(st.threads, &d.pool)) != CST_OK)
        cst_fail(err, status, "could not start %d render threads", st.threads);
    /* The integrator's preparation (photon maps, SPPM's radius) is part of the render's
     * time, and of a time limit's budget; the photon pass is a phase of its own. */
    else {
        if (st.progress && st.progress_phase && st.integrator == CST_INTEGRATOR_PHOTON)
            st.progress_phase(st.progress_user, CST_PHASE_PHOTONS);
        status = integrator_prepare(it, scene, &st, film, workers, &rays, st.progress ? prepare_progress : NULL, &d,
                                    err);
        if (status == CST_OK && resume && !integrator_import_progressive(it, resume))
            status = resume->chains
                         ? cst_fail(err, CST_ERR_INVALID_ARG, "resume: the state's MLT chains are not ones this "
                                    "render makes (another chain count or path length, a value out of range, or "
                                    "the wrong length)")
                         : cst_fail(err, CST_ERR_INVALID_ARG, "resume: the state's SPPM values are not ones a render "
                                    "makes (a radius not positive and finite, or a negative photon count)");
        if (status == CST_OK && st.progress && st.progress_phase)
            st.progress_phase(st.progress_user, CST_PHASE_RENDER);
        Film *block = NULL;
        if (status == CST_OK && st.sample_block > 1) {
            block = film_create(st.width, st.height);
            if (!block || !film_set_output(block, st.aovs, 0.0, 0))
                status = cst_fail(err, CST_ERR_OOM, "out of memory for a %dx%d block film", st.width, st.height);
        }
        if (status == CST_OK &&
            (status = noise ? run_adaptive(&d, &samples, err)
                      : block ? run_blocks(&d, block, &samples, err) : run_passes(&d, &samples, err)) == CST_OK)
            integrator_finish(it, samples);
        film_destroy(block);
    }
    double seconds = clock_seconds() - d.t0;
    threadpool_destroy(d.pool);
    CstRenderStats noise_stats = {0};
    if (status == CST_OK && noise) {
        adaptive_summary(film, &grid, st.noise_target, &noise_stats);
        noise_stats.samples = crop_samples(film, &grid) - pixel_samples0;
    }
    const int cw = st.crop[1] - st.crop[0], ch = st.crop[3] - st.crop[2];
    if (status == CST_OK && (cw != st.width || ch != st.height)) {
        /* Light paths were traced for the whole image (their splats land anywhere), camera
         * passes for the crop only: keep the crop. */
        Film *cropped = film_crop(film, st.crop[0], st.crop[2], cw, ch);
        film_destroy(film);
        film = cropped;
        if (!film) status = cst_fail(err, CST_ERR_OOM, "out of memory for the %dx%d crop", cw, ch);
    }
    if (status == CST_OK) {
        if (st.progress) st.progress(st.progress_user, 1.0, seconds);
        CstRenderStats done;
        fill_stats(&done, &st, it, workers, first, samples, rays, seconds);
        done.stopped = d.stopped;
        if (noise) noise_stats_copy(&done, &noise_stats, per_block);
        if (stats) *stats = done;
        *out = film;
        /* Issue 25: a render that lost many samples to NaN/Inf fails, film kept (caustic.h). */
        if ((double)done.nonfinite > CST_NONFINITE_LIMIT * (double)done.samples)
            status = cst_fail(err, CST_ERR_NONFINITE,
                              "%" PRIu64 " of %" PRIu64 " samples (%.3g%%) were NaN or infinite and were discarded, "
                              "more than the %g%% a render may lose (CST_NONFINITE_LIMIT): the image is biased. "
                              "Expected finite values: look for emission, light or texture values near the float "
                              "limit (3.4e38) or a radius tiny for the scene",
                              done.nonfinite, done.samples,
                              done.samples ? 100.0 * (double)done.nonfinite / (double)done.samples : 100.0,
                              100.0 * CST_NONFINITE_LIMIT);
    } else {
        film_destroy(film);
    }
    if (it) integrator_destroy(it);
    free(it);
    free(workers);
    return status;
}
