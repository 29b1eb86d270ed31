/* Checkpoints: the key that makes a film state file valid for one scene and one set of
 * settings (docs/state-format.md), and the public cst_film_state_write/read around
 * film/film_state.c. Every value that changes a pixel's sums is in the key; the sample count
 * asked for is not (a resume may go further), except for the stratified sampler, whose
 * strata are laid out for it (sampling/sampler.c). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/film.h"
#include "film/film_state.h"
#include "scene/scene.h"

int cst_integrator_resumable(CstIntegrator integrator)
{
    /* SPPM's state is its visible points' radii, photon counts and flux, MLT's its chains,
     * not film sums. */
    return integrator != CST_INTEGRATOR_SPPM && integrator != CST_INTEGRATOR_PSSMLT;
}

typedef struct KeyBuilder {
    StateKey *k;
    int n;
} KeyBuilder;

static StateKey *key_add(KeyBuilder *b, const char *name, StateValueType type)
{
    StateKey *e = &b->k[b->n++];
    memset(e, 0, sizeof *e);
    snprintf(e->name, sizeof e->name, "%s", name);
    e->type = type;
    return e;
}
static void key_int(KeyBuilder *b, const char *name, int64_t v) { key_add(b, name, STATE_INT)->i = v; }
static void key_real(KeyBuilder *b, const char *name, double v) { key_add(b, name, STATE_REAL)->r = v; }
static void key_text(KeyBuilder *b, const char *name, const char *v)
{
    snprintf(key_add(b, name, STATE_TEXT)->text, STATE_TEXT_MAX + 1, "%s", v ? v : "");
}

/* The key of a render of `scene` with resolved settings `st` (at most STATE_KEYS_MAX). */
static int state_key(const CstScene *scene, const CstRenderSettings *st, const char *scene_id, StateKey *keys)
{
    KeyBuilder b = {keys, 0};
    CstSceneInfo in;
    cst_scene_info(scene, &in);
    key_text(&b, "library", CST_VERSION_STRING);
    key_text(&b, "scene", scene_id);
    key_int(&b, "scene.triangles", in.triangles);
    key_int(&b, "scene.spheres", in.spheres);
    key_int(&b, "scene.emitters", in.emitters);
    key_int(&b, "scene.materials", in.materials);
    key_int(&b, "scene.lights", in.lights);
    key_int(&b, "scene.instances", in.instances);
    key_text(&b, "accel", in.accel);
    key_text(&b, "light_sampler", in.light_sampler);
    key_int(&b, "width", st->width);
    key_int(&b, "height", st->height);
    char crop[64];
    snprintf(crop, sizeof crop, "[%d, %d) x [%d, %d)", st->crop[0], st->crop[1], st->crop[2], st->crop[3]);
    key_text(&b, "crop", crop);
    key_text(&b, "integrator", cst_integrator_name(st->integrator));
    key_int(&b, "seed", (int64_t)st->seed);
    key_text(&b, "sampler", cst_sampler_name(st->sampler));
    key_int(&b, "sampler.spp", st->sampler == CST_SAMPLER_STRATIFIED ? st->spp : 0);
    key_text(&b, "filter", cst_filter_name(st->filter));
    key_int(&b, "max_depth", st->max_depth);
    key_int(&b, "rr_depth", st->rr_depth);
    key_int(&b, "photons", st->photons);
    key_real(&b, "photon_radius", st->photon_radius);
    key_text(&b, "color_mode", st->color_mode == CST_COLOR_SPECTRAL ? "spectral" : "rgb");
    /* The clamp integrator.c applies to every sample: max_component over 2^exposure. The
     * exposure alone is applied when the image is written, so it may change on a resume. */
    key_real(&b, "clamp", st->max_component > 0.0 ? st->max_component / exp2(st->exposure) : 0.0);
    key_int(&b, "regularize", st->regularize == 1);
    key_int(&b, "aov_sums", (st->aovs & FILM_AOV_FIRST_HIT) != 0);
    return b.n;
}

static void key_value(const StateKey *e, char *buf, size_t size)
{
    if (e->type == STATE_INT) snprintf(buf, size, "%lld", (long long)e->i);
    else if (e->type == STATE_REAL) snprintf(buf, size, "%.17g", e->r);
    else snprintf(buf, size, "\"%.90s\"", e->text);
}

static int key_equal(const StateKey *a, const StateKey *b)
{
    if (a->type != b->type) return 0;
    if (a->type == STATE_INT) return a->i == b->i;
    if (a->type == STATE_REAL) return memcmp(&a->r, &b->r, sizeof a->r) == 0;
    return strcmp(a->text, b->text) == 0;
}

/* Fails with CST_ERR_INVALID_ARG listing every entry of `want` that `have` (the file's)
 * lacks or holds with another value, and every entry the file has in excess. */
static CstStatus key_compare(const char *path, const StateKey *have, int nhave, const StateKey *want, int nwant,
                             CstError *err)
{
    char diff[900] = "";
    size_t used = 0;
    int count = 0;
    for (int i = 0; i < nwant; i++) {
        const StateKey *h = NULL;
        for (int j = 0; j < nhave && !h; j++)
            if (strcmp(have[j].name, want[i].name) == 0) h = &have[j];
        if (h && key_equal(h, &want[i])) continue;
        char a[96] = "absent", b[96];
        if (h) key_value(h, a, sizeof a);
        key_value(&want[i], b, sizeof b);
        if (used < sizeof diff)
            used += (size_t)snprintf(diff + used, sizeof diff - used, "%s%s: %s in the state, %s here",
                                     count ? "; " : "", want[i].name, a, b);
        count++;
    }
    for (int j = 0; j < nhave; j++) {
        int known = 0;
        for (int i = 0; i < nwant && !known; i++) known = strcmp(have[j].name, want[i].name) == 0;
        if (known) continue;
        if (used < sizeof diff)
            used += (size_t)snprintf(diff + used, sizeof diff - used, "%s%s: in the state, unknown here",
                                     count ? "; " : "", have[j].name);
        count++;
    }
    if (!count) return CST_OK;
    return cst_fail(err, CST_ERR_INVALID_ARG,
                    "%s: the state was made for another render (%d value%s differ%s: %s); expected the same "
                    "scene, library and settings as the render that wrote it (the sample count may grow)",
                    path, count, count == 1 ? "" : "s", count == 1 ? "s" : "", diff);
}

CstStatus cst_film_state_write(const char *path, const CstFilm *film, const CstScene *scene,
                               const CstRenderSettings *settings, const char *scene_id,
                               const CstImageWriteOptions *options, CstError *err)
{
    if (!path || !path[0] || !film || !scene)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_state_write: a path, a film and a scene are required");
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (!cst_integrator_resumable(st.integrator))
        return cst_fail(err, CST_ERR_UNSUPPORTED,
                        "%s: the %s integrator cannot be checkpointed yet (its state is more than the film's "
                        "sums); expected path, path-nee, path-bsdf, whitted, photon, light, bdpt or vcm",
                        path, cst_integrator_name(st.integrator));
    if (film->width != st.width || film->height != st.height || (!film->aov) != !(st.aovs & FILM_AOV_FIRST_HIT))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "%s: the film is %dx%d%s, the render %dx%d%s: expected the film a render's pass_done "
                        "is given (the whole image, not a crop)",
                        path, film->width, film->height, film->aov ? " with AOV sums" : "", st.width, st.height,
                        (st.aovs & FILM_AOV_FIRST_HIT) ? " with AOV sums" : "");
    StateKey *keys = calloc(STATE_KEYS_MAX, sizeof *keys);
    if (!keys) return cst_fail(err, CST_ERR_OOM, "%s: out of memory", path);
    int n = state_key(scene, &st, scene_id, keys);
    CstStatus status = film_state_write(path, film, keys, n, options ? options->temp_file : NULL,
                                        options ? options->temp_file_user : NULL, err);
    free(keys);
    return status;
}

CstStatus cst_film_state_read(const char *path, const CstScene *scene, const CstRenderSettings *settings,
                              const char *scene_id, CstFilm **out, CstError *err)
{
    *out = NULL;
    if (!path || !path[0] || !scene)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_state_read: a path and a scene are required");
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (!cst_integrator_resumable(st.integrator))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: the %s integrator cannot resume from a state file yet",
                        path, cst_integrator_name(st.integrator));
    StateKey *h = calloc(2 * STATE_KEYS_MAX, sizeof *h);
    if (!h) return cst_fail(err, CST_ERR_OOM, "%s: out of memory", path);
    StateKey *w = h + STATE_KEYS_MAX;
    int nh = 0, nw = state_key(scene, &st, scene_id, w);
    Film *film = NULL;
    CstStatus status = film_state_read(path, &film, h, &nh, err);
    if (status == CST_OK) status = key_compare(path, h, nh, w, nw, err);
    if (status == CST_OK && (film->width != st.width || film->height != st.height ||
                             (!film->aov) != !(st.aovs & FILM_AOV_FIRST_HIT)))
        status = cst_fail(err, CST_ERR_PARSE, "%s: its film is %dx%d but its key says %dx%d (a corrupted state file)",
                          path, film->width, film->height, st.width, st.height);
    if (status == CST_OK && st.spp > 0 && film->spp > st.spp)
        status = cst_fail(err, CST_ERR_INVALID_ARG,
                          "%s: the state holds %d samples per pixel, more than the %d asked for; expected a "
                          "sample count of at least %d", path, film->spp, st.spp, film->spp);
    free(h);
    if (status != CST_OK) {
        film_destroy(film);
        return status;
    }
    *out = film;
    return CST_OK;
}
