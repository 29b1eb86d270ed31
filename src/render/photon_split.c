/* SPPM's photon pass split across processes (CstPhotonSplit, caustic.h): the public chunk
 * count and chunk tracer a process that traces photons for another render calls. */
#include <stdlib.h>

#include "core/error.h"
#include "integrators/media_lights.h"
#include "integrators/sppm.h"
#include "scene/scene.h"

/* The SppmParams integrator.c gives sppm_create, for the photon walk's draws: the seed, the
 * depths, the colour mode and the iteration's photon count (resolved). */
static SppmParams split_params(const CstScene *scene, const CstRenderSettings *st)
{
    const size_t pixels = (size_t)st->width * (size_t)st->height;
    SppmParams sp = {st->photons, (float)st->photon_radius, st->max_depth, st->rr_depth, st->filter, st->seed,
                     st->threads, st->color_mode == CST_COLOR_SPECTRAL, NULL, NULL, NULL};
    (void)scene;
    if (sp.photons <= 0) sp.photons = (int)(pixels < (size_t)1 << 30 ? pixels : (size_t)1 << 30);
    return sp;
}

int cst_sppm_photon_chunks(const CstScene *scene, const CstRenderSettings *settings)
{
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.width <= 0 || st.height <= 0 || st.photons < 0) return 0;
    return sppm_photon_chunks(st.photons, (size_t)st.width * (size_t)st.height);
}

CstStatus cst_sppm_trace_chunk(const CstScene *scene, const CstRenderSettings *settings, int iteration, int chunk,
                               float **hits, size_t *count, size_t *cap, uint64_t *rays, CstError *err)
{
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.integrator != CST_INTEGRATOR_SPPM || !scene->committed)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_sppm_trace_chunk: the %s integrator%s: expected sppm and a "
                        "committed scene", cst_integrator_name(st.integrator), scene->committed ? "" : ", no commit");
    const int chunks = cst_sppm_photon_chunks(scene, settings);
    if (chunk < 0 || chunk >= chunks || iteration < 0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_sppm_trace_chunk: chunk %d of iteration %d: expected a chunk "
                        "in [0, %d) and an iteration >= 0", chunk, iteration, chunks);
    SppmParams sp = split_params(scene, &st);
    Camera cam; /* in scenes with media, its origin tells the medium each photon starts in */
    camera_init(&cam, &scene->camera, st.width, st.height);
    sp.cam = &cam;
    /* Emitting media: their light sampler, built as the render's integrator builds it. */
    MediaLights *ml = NULL;
    CstStatus ms = media_lights_create(scene, cst_integrator_name(st.integrator), &ml, err);
    if (ms != CST_OK) return ms;
    sp.media_lights = ml;
    uint64_t traced = 0;
    const bool ok = sppm_trace_chunk(scene, &sp, iteration, chunk, hits, count, cap, &traced);
    media_lights_destroy(ml);
    if (!ok) return cst_fail(err, CST_ERR_OOM, "out of memory for the photon hits of chunk %d", chunk);
    if (rays) *rays += traced;
    return CST_OK;
}
