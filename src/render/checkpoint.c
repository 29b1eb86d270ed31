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
    /* Every one: SPPM's visible points' radii, photon counts and flux go in the state as
     * Film.progressive, MLT's chains as Film.chains. */
    (void)integrator;
    return 1;
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
    /* Written only when not the default, so that states of plain renders keep their key. */
    if (st->first_sample > 0) key_int(&b, "first_sample", st->first_sample);
    if (st->light_rr_depth != st->rr_depth) key_int(&b, "light_rr_depth", st->light_rr_depth);
    if (st->sample_block > 1) key_int(&b, "sample_block", st->sample_block);
    if (st->subsurface_walk == 1) key_int(&b, "subsurface_walk", 1);
    /* Adaptive rounds are planned from the target (render/adaptive.h). */
    if (st->noise_target > 0.0) key_real(&b, "noise", st->noise_target);
    /* MLT's parameters shape its chains (integrators/mlt.c); other states keep their key. */
    if (st->integrator == CST_INTEGRATOR_PSSMLT || st->integrator == CST_INTEGRATOR_MMLT) {
        key_real(&b, "mlt.large_step", st->mlt_large_step);
        key_real(&b, "mlt.sigma", st->mlt_sigma);
        key_int(&b, "mlt.bootstrap", st->mlt_bootstrap);
        key_int(&b, "mlt.chains", st->mlt_chains);
    }
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
    const bool mlt = st.integrator == CST_INTEGRATOR_PSSMLT || st.integrator == CST_INTEGRATOR_MMLT;
    if (mlt != (film->chains != NULL))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "%s: %s: an MLT state is its chains, which a film holds between its passes "
                        "(CstRenderSettings.pass_done) and not once the render has made its image",
                        path, film->chains ? "a film with MLT chains for another integrator"
                                           : "the film of an MLT render without its chains");
    if ((st.integrator == CST_INTEGRATOR_SPPM) != (film->progressive != NULL))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "%s: %s: an SPPM state is its per-pixel radii, photon counts and flux, which a film holds "
                        "between its passes (CstRenderSettings.pass_done) and not once the render has made its image",
                        path, film->progressive ? "a film with SPPM state for another integrator"
                                                : "the film of an sppm render without its state");
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

/* ---------------------------------------------------------------- merging states */

/* One state of a merge: its film and key, and the samples it holds. */
typedef struct MergePart {
    const char *path;
    Film *film;
    StateKey *keys;
    int nkeys;
    int64_t first, end;
} MergePart;

static const StateKey *key_find(const StateKey *k, int n, const char *name)
{
    for (int i = 0; i < n; i++)
        if (strcmp(k[i].name, name) == 0) return &k[i];
    return NULL;
}

static int64_t key_int_or(const StateKey *k, int n, const char *name, int64_t dflt)
{
    const StateKey *e = key_find(k, n, name);
    return e && e->type == STATE_INT ? e->i : dflt;
}

/* Every entry of b's key but first_sample equals a's, and b has no other: else the list. */
static CstStatus merge_compare(const MergePart *a, const MergePart *b, CstError *err)
{
    char diff[900] = "";
    size_t used = 0;
    int count = 0;
    for (int pass = 0; pass < 2; pass++) {
        const MergePart *x = pass ? b : a, *y = pass ? a : b;
        for (int i = 0; i < x->nkeys; i++) {
            if (strcmp(x->keys[i].name, "first_sample") == 0) continue;
            const StateKey *e = key_find(y->keys, y->nkeys, x->keys[i].name);
            if (pass && e) continue; /* compared in the first pass */
            if (e && key_equal(e, &x->keys[i])) continue;
            char va[96] = "absent", vb[96] = "absent";
            key_value(&x->keys[i], pass ? vb : va, 96);
            if (e) key_value(e, pass ? va : vb, 96);
            if (used < sizeof diff)
                used += (size_t)snprintf(diff + used, sizeof diff - used, "%s%s: %s in %s, %s in %s", count ? "; " : "",
                                         x->keys[i].name, va, a->path, vb, b->path);
            count++;
        }
    }
    if (!count) return CST_OK;
    return cst_fail(err, CST_ERR_INVALID_ARG, "%s and %s were made for different renders (%d value%s differ%s: %s); "
                    "expected states of one scene and one set of settings, over different samples",
                    a->path, b->path, count, count == 1 ? "" : "s", count == 1 ? "s" : "", diff);
}

/* The checks of cst_film_state_merge on parts sorted by first sample. */
static CstStatus merge_check(const MergePart *p, int count, CstError *err)
{
    for (int i = 1; i < count; i++) {
        CstStatus status = merge_compare(&p[0], &p[i], err);
        if (status != CST_OK) return status;
    }
    if (key_int_or(p[0].keys, p[0].nkeys, "sampler.spp", 0) != 0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: the stratified sampler lays its strata out for each render's "
                        "sample count, so renders of parts of a range are not parts of one render; expected "
                        "another sampler", p[0].path);
    if (key_find(p[0].keys, p[0].nkeys, "noise"))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: a render with a noise target plans its rounds from its whole "
                        "film, so it is not a part of a range of samples; expected states rendered without --noise",
                        p[0].path);
    const int64_t B = key_int_or(p[0].keys, p[0].nkeys, "sample_block", 1);
    for (int i = 0; i < count; i++) {
        if (p[i].end == p[i].first)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s holds no samples", p[i].path);
        if (i > 0 && p[i].first < p[i - 1].end)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s holds samples [%lld, %lld) and %s [%lld, %lld): they overlap; "
                            "expected disjoint sample ranges", p[i - 1].path, (long long)p[i - 1].first,
                            (long long)p[i - 1].end, p[i].path, (long long)p[i].first, (long long)p[i].end);
        if (i > 0 && p[i].first > p[i - 1].end)
            return cst_fail(err, CST_ERR_INVALID_ARG, "samples [%lld, %lld) are in none of the states (%s ends at %lld, "
                            "%s starts at %lld); expected ranges that leave no gap", (long long)p[i - 1].end,
                            (long long)p[i].first, p[i - 1].path, (long long)p[i - 1].end, p[i].path,
                            (long long)p[i].first);
        /* One render of the union adds block after block to its sums: a state that does not
         * start the union must be one block, and only the last may end inside one. */
        if (i > 0 && (p[i].first % B != 0 || p[i].end > (p[i].first / B + 1) * B))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s holds samples [%lld, %lld), more than one block of %lld "
                            "(sample_block): a render of the union adds each block's sums to its film in turn, so "
                            "only the state that starts the union may hold several; expected one block per state "
                            "after the first (render each part with --sample-block at least its --spp)", p[i].path,
                            (long long)p[i].first, (long long)p[i].end, (long long)B);
        if (i + 1 < count && p[i].end % B != 0)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s ends at sample %lld, inside a block of %lld "
                            "(sample_block); expected every state but the last to end at a block end", p[i].path,
                            (long long)p[i].end, (long long)B);
    }
    return CST_OK;
}

CstStatus cst_film_state_merge(const char *const *paths, int count, CstFilm **out, int *first_sample, CstError *err)
{
    *out = NULL;
    if (!paths || count < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "cst_film_state_merge: expected at least one state file");
    MergePart *p = calloc((size_t)count, sizeof *p);
    StateKey *keys = calloc((size_t)count * STATE_KEYS_MAX, sizeof *keys);
    CstStatus status = p && keys ? CST_OK : cst_fail(err, CST_ERR_OOM, "out of memory for %d states", count);
    for (int i = 0; i < count && status == CST_OK; i++) {
        p[i].path = paths[i];
        p[i].keys = keys + (size_t)i * STATE_KEYS_MAX;
        status = film_state_read(paths[i], &p[i].film, p[i].keys, &p[i].nkeys, err);
        if (status != CST_OK) break;
        p[i].first = key_int_or(p[i].keys, p[i].nkeys, "first_sample", 0);
        p[i].end = p[i].first + p[i].film->spp;
        if (p[i].film->progressive)
            status = cst_fail(err, CST_ERR_INVALID_ARG, "%s: an SPPM state (radii, photon counts, flux): SPPM's "
                              "iterations each depend on all before them and do not merge; expected states of sums",
                              paths[i]);
        else if (p[i].film->chains)
            status = cst_fail(err, CST_ERR_INVALID_ARG, "%s: an MLT state (chains): its iterations continue the "
                              "same chains and do not merge; expected states of sums", paths[i]);
    }
    if (status == CST_OK) {
        /* Insertion sort by first sample: the order of the command line does not matter. */
        for (int i = 1; i < count; i++)
            for (int j = i; j > 0 && p[j].first < p[j - 1].first; j--) {
                MergePart t = p[j]; p[j] = p[j - 1]; p[j - 1] = t;
            }
        status = merge_check(p, count, err);
    }
    Film *total = NULL;
    if (status == CST_OK) {
        total = film_create(p[0].film->width, p[0].film->height);
        if (!total || !film_set_output(total, p[0].film->aov ? FILM_AOV_FIRST_HIT : 0, 0.0, 0))
            status = cst_fail(err, CST_ERR_OOM, "out of memory for the merged film");
    }
    if (status == CST_OK) {
        /* From zero, in sample order: the additions one render of the union makes. */
        for (int i = 0; i < count; i++) film_add(total, p[i].film);
        total->spp = (int)(p[count - 1].end - p[0].first);
        const StateKey *crop = key_find(p[0].keys, p[0].nkeys, "crop");
        int c[4];
        if (crop && crop->type == STATE_TEXT &&
            sscanf(crop->text, "[%d, %d) x [%d, %d)", &c[0], &c[1], &c[2], &c[3]) == 4 && 0 <= c[0] && c[0] < c[1] &&
            c[1] <= total->width && 0 <= c[2] && c[2] < c[3] && c[3] <= total->height &&
            (c[1] - c[0] != total->width || c[3] - c[2] != total->height)) {
            Film *cropped = film_crop(total, c[0], c[2], c[1] - c[0], c[3] - c[2]);
            film_destroy(total);
            total = cropped;
            if (!total) status = cst_fail(err, CST_ERR_OOM, "out of memory for the merged crop");
        }
    }
    if (status == CST_OK) {
        *out = total;
        if (first_sample) *first_sample = (int)p[0].first;
    } else {
        film_destroy(total);
    }
    for (int i = 0; p && i < count; i++) film_destroy(p[i].film);
    free(p);
    free(keys);
    return status;
}
