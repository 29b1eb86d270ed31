/* Film state files and resume (issue 29): a render cut in two by a state file holds the
 * same film sums, bit for bit, as one in a single go (AOV sums and a crop included); a
 * pass_done stop keeps exactly the passes done; every truncation and every changed byte of
 * a state file is refused with CST_ERR_PARSE, never read. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "film/film.h"
#include "film/film_state.h"
#include "unit/scratch_dir.h"

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), e->msg);
}

static CstScene *g_scene;

static int setup(void **state)
{
    (void)state;
    CstError err = {0};
    if (cst_scene_create_cornell_box(&g_scene, &err) != CST_OK) return -1;
    return scratch_dir_make("/tmp/cst-checkpoint-XXXXXX");
}

static int teardown(void **state)
{
    (void)state;
    cst_scene_destroy(g_scene);
    return scratch_dir_remove();
}

static void settings_for(CstRenderSettings *s, CstIntegrator integ, int spp)
{
    cst_render_settings_init(s);
    s->width = 40;
    s->height = 30;
    s->spp = spp;
    s->threads = 2;
    s->seed = 11;
    s->seed_set = 1;
    s->integrator = integ;
    /* MLT: few chains and a small bootstrap keep it cheap (they change the noise only). */
    s->mlt_chains = 16;
    s->mlt_bootstrap = 512;
}

/* The pass callback of a render whose state goes to `path` at its last pass, or that stops
 * after stop_after passes. */
typedef struct Writer {
    const char *path;
    const CstRenderSettings *settings;
    int passes, stop_after;
    CstStatus status;
    CstError err;
} Writer;

static int write_state(void *user, const CstFilm *film, const CstPassInfo *info)
{
    Writer *w = user;
    w->passes++;
    if (info->last || w->passes == w->stop_after)
        w->status = cst_film_state_write(w->path, film, g_scene, w->settings, "test", NULL, &w->err);
    return w->passes == w->stop_after;
}

static void assert_same_sums(const CstFilm *a, const CstFilm *b)
{
    assert_int_equal(a->width, b->width);
    assert_int_equal(a->height, b->height);
    assert_int_equal(a->spp, b->spp);
    size_t n = 3 * (size_t)a->width * (size_t)a->height;
    assert_memory_equal(a->sum, b->sum, n * sizeof *a->sum);
    assert_memory_equal(a->sum_sq, b->sum_sq, n * sizeof *a->sum_sq);
    assert_true(!a->aov == !b->aov);
    if (a->aov) assert_memory_equal(a->aov, b->aov, n / 3 * FILM_AOV_STRIDE * sizeof *a->aov);
}

/* N spp in one go against N/2, state, resume to N. */
static void resume_matches(CstIntegrator integ, int aovs, int crop)
{
    CstError err = {0};
    CstRenderSettings s;
    settings_for(&s, integ, 6);
    s.aovs = aovs;
    if (crop) { s.crop[0] = 5; s.crop[1] = 33; s.crop[2] = 3; s.crop[3] = 21; }
    CstFilm *full = NULL, *half = NULL, *resumed = NULL, *state = NULL;
    ok(cst_render(g_scene, &s, &full, NULL, &err), &err);

    char path[512];
    tpath(path, sizeof path, "resume.state");
    CstRenderSettings h = s;
    h.spp = 3;
    Writer w = {path, &h, 0, 0, CST_ERR_INTERNAL, {0}};
    h.pass_done = write_state;
    h.pass_user = &w;
    ok(cst_render(g_scene, &h, &half, NULL, &err), &err);
    ok(w.status, &w.err);

    ok(cst_film_state_read(path, g_scene, &s, "test", &state, &err), &err);
    assert_int_equal(cst_film_spp(state), 3);
    CstRenderSettings r = s;
    r.resume = state;
    CstRenderStats stats;
    ok(cst_render(g_scene, &r, &resumed, &stats, &err), &err);
    assert_int_equal(stats.first_spp, 3);
    assert_int_equal(stats.spp, 6);
    assert_int_equal(stats.stopped, 0);
    assert_same_sums(full, resumed);
    cst_film_destroy(full);
    cst_film_destroy(half);
    cst_film_destroy(resumed);
    cst_film_destroy(state);
}

static void test_resume_path_aovs(void **state)
{
    (void)state;
    resume_matches(CST_INTEGRATOR_PATH, CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH, 0);
}
static void test_resume_path_crop(void **state) { (void)state; resume_matches(CST_INTEGRATOR_PATH, 0, 1); }
static void test_resume_whitted(void **state) { (void)state; resume_matches(CST_INTEGRATOR_WHITTED, 0, 0); }
static void test_resume_light(void **state) { (void)state; resume_matches(CST_INTEGRATOR_LIGHT, 0, 1); }
static void test_resume_bdpt_aovs(void **state) { (void)state; resume_matches(CST_INTEGRATOR_BDPT, CST_AOV_ALBEDO, 0); }
static void test_resume_vcm(void **state) { (void)state; resume_matches(CST_INTEGRATOR_VCM, 0, 0); }
static void test_resume_photon(void **state) { (void)state; resume_matches(CST_INTEGRATOR_PHOTON, 0, 0); }
/* SPPM: the state is its per-pixel radii, photon counts and flux (Film.progressive). */
static void test_resume_sppm(void **state) { (void)state; resume_matches(CST_INTEGRATOR_SPPM, 0, 0); }
/* MLT: the state is its chains and b (Film.chains, state version 4). */
static void test_resume_pssmlt(void **state) { (void)state; resume_matches(CST_INTEGRATOR_PSSMLT, 0, 0); }
static void test_resume_mmlt(void **state) { (void)state; resume_matches(CST_INTEGRATOR_MMLT, 0, 0); }

/* An MLT state for another MLT render (its chain count) is refused by its key; one whose
 * chains hold a value no render makes (behind a valid checksum: the bytes in memory) is
 * refused before any chain runs; a film of sums is not an MLT state, nor an MLT state
 * another integrator's. */
static void test_mlt_refusals(void **state)
{
    (void)state;
    CstError err = {0};
    CstRenderSettings s;
    settings_for(&s, CST_INTEGRATOR_MMLT, 2);
    char path[512];
    tpath(path, sizeof path, "mlt.state");
    Writer w = {path, &s, 0, 0, CST_ERR_INTERNAL, {0}};
    s.pass_done = write_state;
    s.pass_user = &w;
    CstFilm *film = NULL, *st = NULL, *out = NULL;
    ok(cst_render(g_scene, &s, &film, NULL, &err), &err);
    ok(w.status, &w.err);
    s.pass_done = NULL;
    /* The final film (no chains: the image is made) is no state. */
    assert_int_equal(cst_film_state_write(path, film, g_scene, &s, "test", NULL, &err), CST_ERR_INVALID_ARG);
    CstRenderSettings other = s;
    other.mlt_chains = 17;
    assert_int_equal(cst_film_state_read(path, g_scene, &other, "test", &st, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "mlt.chains: 16 in the state, 17 here"));
    ok(cst_film_state_read(path, g_scene, &s, "test", &st, &err), &err);
    assert_non_null(st->chains);
    CstRenderSettings r = s;
    r.spp = 4;
    r.resume = st;
    /* Another integrator with these chains. */
    r.integrator = CST_INTEGRATOR_BDPT;
    assert_int_equal(cst_render(g_scene, &r, &out, NULL, &err), CST_ERR_INVALID_ARG);
    r.integrator = CST_INTEGRATOR_MMLT;
    /* b (bytes 8..15 of the chains) negative; then the chain count; then one byte short. */
    unsigned char saved = st->chains[15];
    st->chains[15] = 0xbf;
    assert_int_equal(cst_render(g_scene, &r, &out, NULL, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "MLT chains"));
    st->chains[15] = saved;
    st->chains[0] ^= 1;
    assert_int_equal(cst_render(g_scene, &r, &out, NULL, &err), CST_ERR_INVALID_ARG);
    st->chains[0] ^= 1;
    st->chains_len--;
    assert_int_equal(cst_render(g_scene, &r, &out, NULL, &err), CST_ERR_INVALID_ARG);
    st->chains_len++;
    assert_null(out);
    /* Restored, it resumes. */
    ok(cst_render(g_scene, &r, &out, NULL, &err), &err);
    assert_int_equal(cst_film_spp(out), 4);
    /* A film of sums for an MLT render. */
    CstRenderSettings p;
    settings_for(&p, CST_INTEGRATOR_PATH, 2);
    CstFilm *sums = NULL;
    ok(cst_render(g_scene, &p, &sums, NULL, &err), &err);
    r.resume = sums;
    CstFilm *none = NULL;
    assert_int_equal(cst_render(g_scene, &r, &none, NULL, &err), CST_ERR_INVALID_ARG);
    assert_null(none);
    cst_film_destroy(sums);
    cst_film_destroy(out);
    cst_film_destroy(st);
    cst_film_destroy(film);
}

/* pass_done's stop: CST_OK, stats.stopped, the film of the passes done = a render of that
 * many samples. */
static void test_stop(void **state)
{
    (void)state;
    CstError err = {0};
    CstRenderSettings s;
    settings_for(&s, CST_INTEGRATOR_PATH, 1000000);
    char path[512];
    tpath(path, sizeof path, "stop.state");
    Writer w = {path, &s, 0, 3, CST_ERR_INTERNAL, {0}};
    s.pass_done = write_state;
    s.pass_user = &w;
    CstFilm *stopped = NULL, *ref = NULL;
    CstRenderStats stats;
    ok(cst_render(g_scene, &s, &stopped, &stats, &err), &err);
    ok(w.status, &w.err);
    assert_int_equal(stats.stopped, 1);
    assert_int_equal(w.passes, 3);
    assert_true(stats.spp >= 3 && stats.spp < 1000000);
    CstRenderSettings r;
    settings_for(&r, CST_INTEGRATOR_PATH, stats.spp);
    ok(cst_render(g_scene, &r, &ref, NULL, &err), &err);
    assert_same_sums(stopped, ref);
    cst_film_destroy(stopped);
    cst_film_destroy(ref);
}

/* What cannot be resumed, and what a scene may not hold. */
static void test_refusals(void **state)
{
    (void)state;
    CstError err = {0};
    CstRenderSettings s;
    settings_for(&s, CST_INTEGRATOR_PATH, 2);
    CstFilm *film = NULL, *out = NULL;
    ok(cst_render(g_scene, &s, &film, NULL, &err), &err);
    assert_int_equal(cst_integrator_resumable(CST_INTEGRATOR_PSSMLT), 1);
    assert_int_equal(cst_integrator_resumable(CST_INTEGRATOR_SPPM), 1);
    assert_int_equal(cst_integrator_resumable(CST_INTEGRATOR_VCM), 1);
    char path[512];
    tpath(path, sizeof path, "refuse.state");
    /* MLT: a film of sums is not its state (its chains), neither to write nor to resume. */
    CstRenderSettings p = s;
    p.integrator = CST_INTEGRATOR_PSSMLT;
    assert_int_equal(cst_film_state_write(path, film, g_scene, &p, "x", NULL, &err), CST_ERR_INVALID_ARG);
    p.resume = film;
    assert_int_equal(cst_render(g_scene, &p, &out, NULL, &err), CST_ERR_INVALID_ARG);
    assert_null(out);
    /* SPPM: a film of sums is not its state, neither to write nor to resume from. */
    p.integrator = CST_INTEGRATOR_SPPM;
    p.resume = NULL;
    assert_int_equal(cst_film_state_write(path, film, g_scene, &p, "x", NULL, &err), CST_ERR_INVALID_ARG);
    p.resume = film;
    assert_int_equal(cst_render(g_scene, &p, &out, NULL, &err), CST_ERR_INVALID_ARG);
    assert_null(out);
    /* The film written must be the render's whole image. */
    CstRenderSettings wide = s;
    wide.width = 80;
    assert_int_equal(cst_film_state_write(path, film, g_scene, &wide, "x", NULL, &err), CST_ERR_INVALID_ARG);
    /* A resume film of more samples than asked for. */
    CstRenderSettings fewer = s;
    fewer.spp = 1;
    fewer.resume = film;
    assert_int_equal(cst_render(g_scene, &fewer, &out, NULL, &err), CST_ERR_INVALID_ARG);
    /* Another scene id. */
    ok(cst_film_state_write(path, film, g_scene, &s, "one", NULL, &err), &err);
    assert_int_equal(cst_film_state_read(path, g_scene, &s, "two", &out, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "scene: \"one\" in the state, \"two\" here"));
    cst_film_destroy(film);
}

/* Every prefix of a state file is refused as truncated (or, too short to hold the magic,
 * as not a state), every one-byte change as corrupted: none is read. With SPPM's
 * progressive state (version 2) too. */
static void truncated_and_corrupted(bool progressive, bool chains)
{
    CstError err = {0};
    Film *f = film_create(3, 2);
    assert_non_null(f);
    assert_int_equal(film_set_output(f, CST_AOV_ALBEDO, 0.0, 0), 1);
    for (int i = 0; i < 18; i++) { f->sum[i] = 0.5 * i; f->sum_sq[i] = 0.25 * i * i; }
    for (int i = 0; i < 6 * FILM_AOV_STRIDE; i++) f->aov[i] = -1.0 * i;
    if (progressive) {
        f->progressive = malloc(6 * FILM_PROGRESSIVE_STRIDE * sizeof *f->progressive);
        assert_non_null(f->progressive);
        for (int i = 0; i < 6 * FILM_PROGRESSIVE_STRIDE; i++) f->progressive[i] = 0.0625 * i;
    }
    if (chains) { /* version 4: opaque bytes to the film state */
        f->chains_len = 37;
        f->chains = malloc(f->chains_len);
        assert_non_null(f->chains);
        for (size_t i = 0; i < f->chains_len; i++) f->chains[i] = (unsigned char)(7 * i + 1);
    }
    f->spp = 7;
    StateKey keys[3] = {{.name = "a", .type = STATE_INT, .i = -5},
                        {.name = "b", .type = STATE_REAL, .r = 0.125},
                        {.name = "c", .type = STATE_TEXT, .text = "hello"}};
    char path[512], cut[512];
    tpath(path, sizeof path, "small.state");
    tpath(cut, sizeof cut, "cut.state");
    ok(film_state_write(path, f, keys, 3, NULL, NULL, &err), &err);

    Film *back = NULL;
    StateKey *got = calloc(STATE_KEYS_MAX, sizeof *got);
    int n = 0;
    ok(film_state_read(path, &back, got, &n, &err), &err);
    assert_int_equal(n, 3);
    assert_int_equal(got[0].i, -5);
    assert_true(got[1].r == 0.125);
    assert_string_equal(got[2].text, "hello");
    assert_same_sums(f, back);
    assert_true(!f->progressive == !back->progressive);
    if (progressive)
        assert_memory_equal(f->progressive, back->progressive, 6 * FILM_PROGRESSIVE_STRIDE * sizeof *f->progressive);
    assert_true(!f->chains == !back->chains);
    if (chains) {
        assert_int_equal(back->chains_len, f->chains_len);
        assert_memory_equal(f->chains, back->chains, f->chains_len);
    }
    film_destroy(back);

    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    unsigned char bytes[4096];
    size_t len = fread(bytes, 1, sizeof bytes, fp);
    fclose(fp);
    assert_true(len > 100 && len < sizeof bytes);
    for (size_t k = 0; k < len; k++) {
        fp = fopen(cut, "wb");
        fwrite(bytes, 1, k, fp);
        fclose(fp);
        assert_int_equal(film_state_read(cut, &back, got, &n, &err), CST_ERR_PARSE);
        assert_true(strstr(err.msg, "truncated") || (k < 8 && strstr(err.msg, "not a caustic state file")));
    }
    for (size_t k = 0; k < len; k++) {
        unsigned char saved = bytes[k];
        bytes[k] ^= 0x10;
        fp = fopen(cut, "wb");
        fwrite(bytes, 1, len, fp);
        fclose(fp);
        bytes[k] = saved;
        if (film_state_read(cut, &back, got, &n, &err) != CST_ERR_PARSE)
            fail_msg("byte %zu changed: read as a valid state", k);
    }
    free(got);
    film_destroy(f);
}

static void test_truncated_and_corrupted(void **state)
{
    (void)state;
    truncated_and_corrupted(false, false);
    truncated_and_corrupted(true, false);
    truncated_and_corrupted(false, true);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_resume_path_aovs), cmocka_unit_test(test_resume_path_crop),
        cmocka_unit_test(test_resume_whitted),   cmocka_unit_test(test_resume_light),
        cmocka_unit_test(test_resume_bdpt_aovs), cmocka_unit_test(test_resume_vcm),
        cmocka_unit_test(test_resume_photon),    cmocka_unit_test(test_resume_sppm), cmocka_unit_test(test_stop),
        cmocka_unit_test(test_resume_pssmlt),    cmocka_unit_test(test_resume_mmlt),
        cmocka_unit_test(test_mlt_refusals),
        cmocka_unit_test(test_refusals),         cmocka_unit_test(test_truncated_and_corrupted),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
