/* Films in blocks of samples (CstRenderSettings.sample_block, issue 29): one render of
 * [0, 16) in blocks of 8 holds, sum by sum, the films of [0, 8) and [8, 16) rendered apart
 * and added with cst_film_add from an empty film (what caustic merge and the MPI ranks
 * do), for every integrator that keeps film sums; a block of 1 is the plain render. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <string.h>

#include "caustic/caustic.h"

enum { W = 20, H = 16 };

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), e->msg);
}

static void settings(CstRenderSettings *st, CstIntegrator integrator, int spp, int first, int block)
{
    cst_render_settings_init(st);
    st->width = W, st->height = H, st->threads = 2, st->spp = spp, st->first_sample = first;
    st->sample_block = block;
    st->integrator = integrator;
    st->photons = 5000;
    st->aovs = integrator == CST_INTEGRATOR_LIGHT ? 0 : CST_AOV_ALBEDO | CST_AOV_DEPTH;
}

static CstFilm *render(const CstScene *s, CstIntegrator integrator, int spp, int first, int block)
{
    CstRenderSettings st;
    settings(&st, integrator, spp, first, block);
    CstFilm *film = NULL;
    CstError e = {0};
    ok(cst_render(s, &st, &film, NULL, &e), &e);
    return film;
}

/* Every sum, sum of squares and AOV sum equal bit for bit, and the sample counts. */
static void assert_same_sums(CstFilm *a, CstFilm *b, const char *what)
{
    CstFilmSums x, y;
    cst_film_sums(a, &x);
    cst_film_sums(b, &y);
    assert_int_equal(x.pixels, y.pixels);
    assert_int_equal(*x.spp, *y.spp);
    if (memcmp(x.sum, y.sum, 3 * x.pixels * sizeof *x.sum) != 0) fail_msg("%s: sums differ", what);
    if (memcmp(x.sum_sq, y.sum_sq, 3 * x.pixels * sizeof *x.sum_sq) != 0) fail_msg("%s: sums of squares differ", what);
    assert_true((x.aov == NULL) == (y.aov == NULL));
    if (x.aov && memcmp(x.aov, y.aov, 8 * x.pixels * sizeof *x.aov) != 0) fail_msg("%s: AOV sums differ", what);
}

static void test_blocks_add_up(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError e = {0};
    ok(cst_scene_create_cornell_box(&s, &e), &e);
    const CstIntegrator all[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_LIGHT,
                                 CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) {
        const char *name = cst_integrator_name(all[k]);
        CstFilm *whole = render(s, all[k], 16, 0, 8);
        CstFilm *a = render(s, all[k], 8, 0, 8), *b = render(s, all[k], 8, 8, 8);
        CstRenderSettings st;
        settings(&st, all[k], 16, 0, 8);
        CstFilm *total = NULL;
        ok(cst_film_create(s, &st, &total, &e), &e);
        ok(cst_film_add(total, a, &e), &e);
        ok(cst_film_add(total, b, &e), &e);
        assert_same_sums(whole, total, name);
        /* A block of 1 adds sample after sample: the render as it always was. */
        CstFilm *plain = render(s, all[k], 5, 0, CST_UNSET), *one = render(s, all[k], 5, 0, 1);
        assert_same_sums(plain, one, name);
        cst_film_destroy(plain);
        cst_film_destroy(one);
        cst_film_destroy(total);
        cst_film_destroy(a);
        cst_film_destroy(b);
        cst_film_destroy(whole);
    }
    cst_scene_destroy(s);
}

static void test_add_refuses_other_sizes(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError e = {0};
    ok(cst_scene_create_cornell_box(&s, &e), &e);
    CstFilm *a = render(s, CST_INTEGRATOR_PATH, 1, 0, 1);
    CstRenderSettings st;
    settings(&st, CST_INTEGRATOR_PATH, 1, 0, 1);
    st.width = W + 1;
    CstFilm *b = NULL;
    ok(cst_film_create(s, &st, &b, &e), &e);
    assert_int_equal(cst_film_add(b, a, &e), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(e.msg, "expected the same size"));
    settings(&st, CST_INTEGRATOR_PATH, 1, 0, 0);
    st.sample_block = -2;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &e), CST_ERR_INVALID_ARG);
    assert_null(f);
    cst_film_destroy(a);
    cst_film_destroy(b);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_blocks_add_up),
        cmocka_unit_test(test_add_refuses_other_sizes),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
