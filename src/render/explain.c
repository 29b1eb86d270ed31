/* cst_explain (caustic.h, issue 30): one sample of one pixel replayed through the
 * render's own steps (integrator.c) on a one-pixel crop, one thread, with a recorder
 * (integrators/recorder.h) that the path tracer and BDPT fill; then the recorded additions
 * are summed again in the integrator's order and checked against the film. */
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/film.h"
#include "film/filter.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"
#include "render/render.h"
#include "scene/scene.h"

/* Events kept per sample: a path tracer's path of 1,000 bounces, or a BDPT camera path
 * with its connections; longer ones are reported truncated (and not checked). */
enum { EXPLAIN_EVENTS = 8192 };

const char *cst_explain_integrators(void) { return "path, path-nee, path-bsdf, bdpt"; }

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
    case CST_INTEGRATOR_DEFAULT:
        /* volpath_li and path_sss_li carry no recorder hooks (yet). */
        if (scene->num_media | scene->num_medium_ifaces | scene->num_subsurface)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "explain does not follow paths through participating media "
                            "or subsurface materials yet; expected a scene without them");
        return CST_OK;
    case CST_INTEGRATOR_BDPT:
        if (st->color_mode == CST_COLOR_SPECTRAL)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "explain follows bdpt in RGB mode only; expected --rgb");
        /* subpath_media.c's walks and connections carry no recorder hooks (yet). */
        if (scene->num_media | scene->num_medium_ifaces)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "explain does not follow bdpt's paths through participating "
                            "media yet; expected a scene without them");
        return CST_OK;
    default: break;
    }
    return cst_fail(err, CST_ERR_UNSUPPORTED, "explain supports: %s; not %s", cst_explain_integrators(),
                    cst_integrator_name(st->integrator));
}

/* The recorded additions summed in the order path_li and subpath_trace_camera add them
 * (BDPT's connections of a vertex first among themselves), then as camera_tile turns the
 * path's value into the film's sample: spectral conversion, non-finite to 0, clamp, filter
 * weight. */
static Color replay(const Integrator *it, const Recorder *r, int x, int y, int sample, float *fw)
{
    Color L = color_s(0.0f), c = color_s(0.0f), beta_c = color_s(0.0f);
    int c_depth = -1;
    for (int i = 0; i <= r->n; i++) {
        const CstExplainEvent *e = i < r->n ? &r->ev[i] : NULL;
        const bool connect = e && e->kind == CST_EXPLAIN_CONNECT && (e->flags & CST_EXPLAIN_ADDED);
        if (c_depth >= 0 && (!connect || e->depth != c_depth)) {
            L = color_madd(L, beta_c, c);
            c_depth = -1;
        }
        if (!e || !(e->flags & CST_EXPLAIN_ADDED) || e->kind == CST_EXPLAIN_SPLAT) continue;
        if (connect) {
            if (c_depth < 0) {
                c = color_s(0.0f);
                c_depth = e->depth;
                beta_c = r->beta[i];
            }
            c = color_add(c, r->value[i]);
            continue;
        }
        L = color_madd(L, r->beta[i], r->value[i]);
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

CstStatus cst_explain(const CstScene *scene, const CstRenderSettings *settings, int x, int y, int sample,
                      CstExplain **out, CstError *err)
{
    *out = NULL;
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.integrator == CST_INTEGRATOR_DEFAULT) st.integrator = CST_INTEGRATOR_PATH;
    CstStatus status = check(scene, &st, x, y, sample, err);
    if (status != CST_OK) return status;
    /* One pixel, one sample, one thread, nothing but the film's sums. */
    st.threads = 1;
    st.first_sample = sample;
    st.crop[0] = x; st.crop[1] = x + 1; st.crop[2] = y; st.crop[3] = y + 1;
    st.aovs = 0;
    st.time_limit = 0.0;
    st.sample_block = 1;
    st.resume = NULL;
    st.pass_done = NULL;
    st.progress = NULL;

    CstExplain *ex = calloc(1, sizeof *ex);
    Film *film = film_create(st.width, st.height);
    Integrator *it = calloc(1, sizeof *it);
    IntegratorWorker worker;
    memset(&worker, 0, sizeof worker);
    Recorder rec;
    memset(&rec, 0, sizeof rec);
    rec.cap = EXPLAIN_EVENTS;
    rec.ev = calloc(EXPLAIN_EVENTS, sizeof *rec.ev);
    rec.beta = calloc(EXPLAIN_EVENTS, sizeof *rec.beta);
    rec.value = calloc(EXPLAIN_EVENTS, sizeof *rec.value);
    rec.px = x;
    rec.py = y;
    uint64_t rays = 0;
    if (!ex || !film || !it || !rec.ev || !rec.beta || !rec.value) {
        status = cst_fail(err, CST_ERR_OOM, "out of memory for explaining a %dx%d render", st.width, st.height);
        goto done;
    }
    if ((status = integrator_prepare(it, scene, &st, film, &worker, &rays, NULL, NULL, err)) != CST_OK) goto done;
    if (it->kind == INTEGRATOR_PATH) it->path.rec = &rec;
    else rec.radius = filter_radius(it->light.vcm_params.frame.filter);
    const int pixel = y * st.width + x;
    double camera[3] = {0.0, 0.0, 0.0};
    if ((status = run(it, &rec, pixel, sample, camera, err)) != CST_OK) goto done;

    ex->x = x;
    ex->y = y;
    ex->sample = sample;
    ex->integrator = st.integrator;
    ex->spectral = it->spectral;
    ex->truncated = rec.truncated;
    Color sum = replay(it, &rec, x, y, sample, &ex->filter_weight);
    for (int c = 0; c < 3; c++) {
        ex->sum[c] = sum.c[c];
        ex->film_value[c] = film->sum[3 * (size_t)pixel + (size_t)c];
        ex->camera_value[c] = it->kind == INTEGRATOR_BIDIR ? camera[c] : ex->film_value[c];
        ex->splat_value[c] = ex->film_value[c] - ex->camera_value[c];
    }
    ex->exact = !rec.truncated;
    for (int c = 0; c < 3; c++) {
        double s = (double)ex->sum[c];
        if (memcmp(&s, &ex->camera_value[c], sizeof s) != 0) ex->exact = 0;
    }
    ex->num_events = rec.n;
    ex->events = rec.ev;
    rec.ev = NULL;
    *out = ex;
    ex = NULL;
done:
    if (it) integrator_destroy(it);
    free(it);
    film_destroy(film);
    free(rec.ev);
    free(rec.beta);
    free(rec.value);
    cst_explain_destroy(ex);
    return status;
}
