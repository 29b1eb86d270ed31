/* SPPM's photon pass split across processes without MPI (CstPhotonSplit, issue 29): a render
 * that traces some photon chunks and fetches the others' hits from cst_sppm_trace_chunk (as
 * cli/cluster.c's ranks send them) makes the film of a render that traces them all, bit
 * for bit, in RGB and spectral mode, whatever the split; a failed fetch ends the render
 * with CST_ERR_CANCELLED and a split outside the chunks is refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "film/film.h"

/* 40 x 30 pixels, 2500 photons per iteration: three chunks (1024, 1024, 452). */
enum { W = 40, H = 30, PHOTONS = 2500, ITERATIONS = 3 };

static CstScene *g_scene;

static int setup(void **state)
{
    (void)state;
    CstError err = {0};
    return cst_scene_create_cornell_box(&g_scene, &err) == CST_OK ? 0 : -1;
}

static int teardown(void **state)
{
    (void)state;
    cst_scene_destroy(g_scene);
    return 0;
}

static void settings_for(CstRenderSettings *s, CstColorMode mode)
{
    cst_render_settings_init(s);
    s->width = W;
    s->height = H;
    s->spp = ITERATIONS;
    s->threads = 2;
    s->photons = PHOTONS;
    s->integrator = CST_INTEGRATOR_SPPM;
    s->color_mode = mode;
}

/* The other process: traces the chunk it is asked for when asked (fail_at: the call that
 * fails instead, -1 = none). */
typedef struct Remote {
    const CstRenderSettings *settings;
    float *hits;
    size_t cap;
    int calls, fail_at;
} Remote;

static int remote_fetch(void *user, int iteration, int chunk, const float **hits, size_t *count)
{
    Remote *r = user;
    if (r->calls++ == r->fail_at) return 1;
    CstError err = {0};
    *count = 0;
    if (cst_sppm_trace_chunk(g_scene, r->settings, iteration, chunk, &r->hits, count, &r->cap, NULL, &err) != CST_OK)
        fail_msg("cst_sppm_trace_chunk: %s", err.msg);
    *hits = r->hits;
    return 0;
}

static CstFilm *render(const CstRenderSettings *s)
{
    CstFilm *film = NULL;
    CstError err = {0};
    CstStatus st = cst_render(g_scene, s, &film, NULL, &err);
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), err.msg);
    return film;
}

static void split_matches(CstColorMode mode)
{
    CstRenderSettings s;
    settings_for(&s, mode);
    assert_int_equal(cst_sppm_photon_chunks(g_scene, &s), 3);
    CstFilm *whole = render(&s);
    const size_t n = 3 * (size_t)W * (size_t)H;
    /* Here: none, the first, the middle one, the last two. */
    static const int ranges[][2] = {{0, 0}, {0, 1}, {1, 2}, {1, 3}};
    for (size_t k = 0; k < sizeof ranges / sizeof ranges[0]; k++) {
        Remote remote = {&s, NULL, 0, 0, -1};
        const CstPhotonSplit split = {ranges[k][0], ranges[k][1], remote_fetch, &remote};
        CstRenderSettings t = s;
        t.photon_split = &split;
        CstFilm *part = render(&t);
        assert_int_equal(remote.calls, ITERATIONS * (3 - (ranges[k][1] - ranges[k][0])));
        assert_memory_equal(whole->sum, part->sum, n * sizeof *whole->sum);
        cst_film_destroy(part);
        free(remote.hits);
    }
    cst_film_destroy(whole);
}

static void test_split_rgb(void **state) { (void)state; split_matches(CST_COLOR_RGB); }
static void test_split_spectral(void **state) { (void)state; split_matches(CST_COLOR_SPECTRAL); }

static void test_split_failures(void **state)
{
    (void)state;
    CstRenderSettings s;
    settings_for(&s, CST_COLOR_RGB);
    Remote remote = {&s, NULL, 0, 0, 2};
    CstPhotonSplit split = {0, 1, remote_fetch, &remote};
    s.photon_split = &split;
    CstFilm *film = NULL;
    CstError err = {0};
    assert_int_equal(cst_render(g_scene, &s, &film, NULL, &err), CST_ERR_CANCELLED);
    assert_null(film);
    assert_non_null(strstr(err.msg, "did not arrive"));
    free(remote.hits);
    split.chunk_hi = 4;
    assert_int_equal(cst_render(g_scene, &s, &film, NULL, &err), CST_ERR_INVALID_ARG);
    assert_null(film);
    /* Not a chunk, or not sppm. */
    float *hits = NULL;
    size_t count = 0, cap = 0;
    assert_int_equal(cst_sppm_trace_chunk(g_scene, &s, 0, 3, &hits, &count, &cap, NULL, &err), CST_ERR_INVALID_ARG);
    s.integrator = CST_INTEGRATOR_PATH;
    assert_int_equal(cst_sppm_trace_chunk(g_scene, &s, 0, 0, &hits, &count, &cap, NULL, &err), CST_ERR_INVALID_ARG);
    assert_null(hits);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_split_rgb),
        cmocka_unit_test(test_split_spectral),
        cmocka_unit_test(test_split_failures),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
