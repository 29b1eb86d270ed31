/* The public hooks `caustic view` refines its image with: a render of samples
 * [first_sample, first_sample + spp) (CstRenderSettings.first_sample), one-sample renders
 * of consecutive ranges summing bit for bit to the render of the whole range for every
 * integrator that allows it; the camera read back (cst_scene_camera) and moved after
 * commit; the first-hit AOVs read from a film (cst_film_aov_pixels); the photon maps kept
 * between renders (CstRenderSettings.photon_cache). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"

enum { W = 24, H = 24, N = 4 };

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), e->msg);
}

static CstScene *cornell(void)
{
    CstScene *s = NULL;
    CstError e = {0};
    ok(cst_scene_create_cornell_box(&s, &e), &e);
    return s;
}

static CstFilm *render(const CstScene *s, CstIntegrator integrator, int spp, int first)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = W, st.height = H, st.threads = 2, st.spp = spp, st.first_sample = first;
    st.integrator = integrator;
    st.photons = 20000;
    CstFilm *film = NULL;
    CstError e = {0};
    ok(cst_render(s, &st, &film, NULL, &e), &e);
    return film;
}

/* N one-sample renders, first_sample 0..N-1, summed in order, equal the N-sample render
 * bit for bit: each pixel's sum is the same sequence of additions (cst_film_pixel of a
 * one-sample film is its sample's value exactly), and the mean the same product. */
static void test_passes_sum_to_the_render(void **state)
{
    (void)state;
    CstScene *s = cornell();
    const CstIntegrator all[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_LIGHT,
                                 CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (size_t k = 0; k < sizeof all / sizeof all[0]; k++) {
        CstFilm *whole = render(s, all[k], N, 0);
        double *sum = calloc(3 * W * H, sizeof *sum);
        assert_non_null(sum);
        for (int p = 0; p < N; p++) {
            CstFilm *pass = render(s, all[k], 1, p);
            assert_int_equal(cst_film_spp(pass), 1);
            for (int i = 0; i < W * H; i++) {
                double rgb[3];
                cst_film_pixel(pass, i % W, i / W, rgb);
                for (int c = 0; c < 3; c++) sum[3 * i + c] += rgb[c];
            }
            cst_film_destroy(pass);
        }
        int differ = 0;
        double total = 0.0;
        for (int i = 0; i < W * H; i++) {
            double rgb[3];
            cst_film_pixel(whole, i % W, i / W, rgb);
            for (int c = 0; c < 3; c++) {
                differ += rgb[c] != sum[3 * i + c] * (1.0 / N);
                total += rgb[c];
            }
        }
        if (differ) fail_msg("%s: %d channel values differ", cst_integrator_name(all[k]), differ);
        assert_true(total > 0.0); /* not a black image agreeing with itself */
        free(sum);
        cst_film_destroy(whole);
    }
    cst_scene_destroy(s);
}

static void test_first_sample_rejected(void **state)
{
    (void)state;
    CstScene *s = cornell();
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = W, st.height = H, st.spp = 1, st.first_sample = 1, st.integrator = CST_INTEGRATOR_SPPM;
    CstFilm *film = NULL;
    CstError e = {0};
    assert_int_equal(cst_render(s, &st, &film, NULL, &e), CST_ERR_UNSUPPORTED);
    assert_null(film);
    st.integrator = CST_INTEGRATOR_PATH, st.first_sample = -3;
    assert_int_equal(cst_render(s, &st, &film, NULL, &e), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(e.msg, "first_sample -3"));
    cst_scene_destroy(s);
    /* A render's, not a scene's. */
    CstScene *b = NULL;
    ok(cst_scene_create(&b, &e), &e);
    cst_render_settings_init(&st);
    st.first_sample = 2;
    assert_int_equal(cst_scene_set_render_settings(b, &st, &e), CST_ERR_INVALID_ARG);
    cst_scene_destroy(b);
}

static int films_equal(const CstFilm *a, const CstFilm *b)
{
    for (int i = 0; i < W * H; i++) {
        double x[3], y[3];
        cst_film_pixel(a, i % W, i / W, x);
        cst_film_pixel(b, i % W, i / W, y);
        if (memcmp(x, y, sizeof x) != 0) return 0;
    }
    return 1;
}

/* The camera read back sets the same camera; a moved camera (after commit) renders
 * another image, and moving it back gives the first one bit for bit. */
static void test_camera_after_commit(void **state)
{
    (void)state;
    CstScene *s = cornell();
    CstError e = {0};
    CstCameraDesc cam, moved, back;
    cst_scene_camera(s, &cam);
    assert_int_equal(cam.type, CST_CAMERA_PERSPECTIVE);
    assert_true(cam.fov > 0.0f && cam.focus_distance > 0.0f);
    CstFilm *a = render(s, CST_INTEGRATOR_PATH, 1, 0);
    moved = cam;
    moved.position[0] += 50.0f;
    ok(cst_scene_set_camera(s, &moved, &e), &e);
    CstFilm *b = render(s, CST_INTEGRATOR_PATH, 1, 0);
    assert_false(films_equal(a, b));
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    cst_scene_camera(s, &back);
    assert_memory_equal(&cam, &back, sizeof cam);
    CstFilm *c = render(s, CST_INTEGRATOR_PATH, 1, 0);
    assert_true(films_equal(a, c));
    cst_film_destroy(a);
    cst_film_destroy(b);
    cst_film_destroy(c);
    cst_scene_destroy(s);
}

/* Albedo in [0, 1], unit normals and positive depths where the camera hits the box (most
 * of the view), no normal and an infinite depth where it does not; no AOV a film was not
 * rendered with. */
static void test_film_aov_pixels(void **state)
{
    (void)state;
    CstScene *s = cornell();
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = W, st.height = H, st.spp = 2, st.threads = 2;
    st.aovs = CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH;
    CstFilm *film = NULL;
    CstError e = {0};
    ok(cst_render(s, &st, &film, NULL, &e), &e);
    float *alb = malloc(3 * W * H * sizeof *alb), *nrm = malloc(3 * W * H * sizeof *nrm);
    float *dep = malloc(W * H * sizeof *dep);
    ok(cst_film_aov_pixels(film, CST_AOV_ALBEDO, alb, &e), &e);
    ok(cst_film_aov_pixels(film, CST_AOV_NORMAL, nrm, &e), &e);
    ok(cst_film_aov_pixels(film, CST_AOV_DEPTH, dep, &e), &e);
    int hits = 0;
    for (int i = 0; i < W * H; i++) {
        for (int c = 0; c < 3; c++) assert_true(alb[3 * i + c] >= 0.0f && alb[3 * i + c] <= 1.0f);
        double nx = (double)nrm[3 * i], ny = (double)nrm[3 * i + 1], nz = (double)nrm[3 * i + 2];
        double len = sqrt(nx * nx + ny * ny + nz * nz);
        if (!isfinite(dep[i])) { /* no sample hit: no normal either */
            assert_true(len == 0.0);
            continue;
        }
        hits++;
        assert_true(dep[i] > 0.0f);
        /* the renormalised mean; 0 only where a pixel's normals cancel exactly */
        assert_true(fabs(len - 1.0) < 1e-5 || len == 0.0);
    }
    assert_true(hits > W * H * 9 / 10); /* the box fills the view but for its outer edge */
    assert_int_equal(cst_film_aov_pixels(film, CST_AOV_VARIANCE, alb, &e), CST_ERR_INVALID_ARG);
    cst_film_destroy(film);
    film = render(s, CST_INTEGRATOR_PATH, 1, 0);
    assert_int_equal(cst_film_aov_pixels(film, CST_AOV_ALBEDO, alb, &e), CST_ERR_INVALID_ARG);
    cst_film_destroy(film);
    free(alb);
    free(nrm);
    free(dep);
    cst_scene_destroy(s);
}

/* The photon cache: renders through it equal renders without it bit for bit (the first,
 * which builds the maps, a later pass reusing them, and one after a camera move, whose
 * automatic radius follows the new camera); one build for all of them, another for a new
 * seed; the positions read back; a scene refuses it as a setting. */
static CstFilm *render_cached(const CstScene *s, CstPhotonCache *cache, int first, uint64_t seed)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = W, st.height = H, st.threads = 2, st.spp = 1, st.first_sample = first;
    st.integrator = CST_INTEGRATOR_PHOTON;
    st.photons = 20000;
    st.seed = seed, st.seed_set = 1;
    st.photon_cache = cache;
    CstFilm *film = NULL;
    CstError e = {0};
    ok(cst_render(s, &st, &film, NULL, &e), &e);
    return film;
}

static void assert_same_film(const CstFilm *a, const CstFilm *b)
{
    float *pa = malloc(3 * W * H * sizeof *pa), *pb = malloc(3 * W * H * sizeof *pb);
    assert_non_null(pa);
    assert_non_null(pb);
    cst_film_pixels(a, pa);
    cst_film_pixels(b, pb);
    assert_memory_equal(pa, pb, 3 * W * H * sizeof *pa);
    free(pa);
    free(pb);
}

static void test_photon_cache(void **state)
{
    (void)state;
    CstScene *s = cornell();
    CstPhotonCache *cache = cst_photon_cache_create();
    assert_non_null(cache);
    assert_int_equal(cst_photon_cache_builds(cache), 0);
    assert_int_equal(cst_photon_cache_positions(cache, 0, NULL, 0), 0);
    for (int first = 0; first < 2; first++) {
        CstFilm *a = render_cached(s, cache, first, 7), *b = render_cached(s, NULL, first, 7);
        assert_same_film(a, b);
        cst_film_destroy(a);
        cst_film_destroy(b);
    }
    assert_int_equal(cst_photon_cache_builds(cache), 1);
    CstCameraDesc cam;
    cst_scene_camera(s, &cam);
    cam.position[0] += 60.0f;
    CstError e = {0};
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    CstFilm *a = render_cached(s, cache, 0, 7), *b = render_cached(s, NULL, 0, 7);
    assert_same_film(a, b);
    cst_film_destroy(a);
    cst_film_destroy(b);
    assert_int_equal(cst_photon_cache_builds(cache), 1);
    cst_film_destroy(render_cached(s, cache, 0, 8)); /* another seed: other photons */
    assert_int_equal(cst_photon_cache_builds(cache), 2);
    size_t n = cst_photon_cache_positions(cache, 0, NULL, 0), nc = cst_photon_cache_positions(cache, 1, NULL, 0);
    assert_true(n > 10000 && nc <= n); /* the caustic map: a subset (empty in the diffuse box) */
    float *xyz = malloc(3 * n * sizeof *xyz);
    assert_non_null(xyz);
    assert_int_equal(cst_photon_cache_positions(cache, 0, xyz, n), n);
    for (size_t i = 0; i < 3 * n; i++) assert_true(isfinite(xyz[i]));
    free(xyz);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.photon_cache = cache;
    CstScene *fresh = NULL;
    ok(cst_scene_create(&fresh, &e), &e);
    assert_int_equal(cst_scene_set_render_settings(fresh, &st, &e), CST_ERR_INVALID_ARG);
    if (!strstr(e.msg, "photon_cache")) fail_msg("%s", e.msg);
    cst_scene_destroy(fresh);
    cst_photon_cache_destroy(cache);
    cst_photon_cache_destroy(NULL);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_passes_sum_to_the_render),
        cmocka_unit_test(test_first_sample_rejected),
        cmocka_unit_test(test_camera_after_commit),
        cmocka_unit_test(test_film_aov_pixels),
        cmocka_unit_test(test_photon_cache),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
