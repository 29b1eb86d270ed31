/* Determinism: the same scene, seed and sample count give bit-identical images whatever
 * the thread count, for the path tracer, for the light tracer (whose splats land on
 * any pixel), for photon mapping (whose maps are shared by all threads) and for SPPM
 * (whose photons update every visible point in reach); the JSON Cornell box equals the
 * built-in one bit for bit. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "film/film.h"
#include "scene/scene.h"

static Film *render_with(const CstScene *s, CstIntegrator integ, int threads, CstFilter filter,
                         uint64_t seed)
{
    CstRenderSettings st = {0};
    st.integrator = integ;
    st.width = 96;
    st.height = 80; /* not a multiple of the tile size: partial tiles too */
    st.spp = 8;
    st.threads = threads;
    st.filter = filter;
    st.seed = seed;
    st.seed_set = 1;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    return f;
}

static Film *render(const CstScene *s, int threads, CstFilter filter, uint64_t seed)
{
    return render_with(s, CST_INTEGRATOR_PATH, threads, filter, seed);
}

static int films_identical(const Film *a, const Film *b)
{
    size_t n = (size_t)a->width * (size_t)a->height * 3u;
    return a->width == b->width && a->height == b->height && a->spp == b->spp &&
           memcmp(a->sum, b->sum, n * sizeof *a->sum) == 0 &&
           memcmp(a->sum_sq, b->sum_sq, n * sizeof *a->sum_sq) == 0;
}

static void check_thread_count_invariance(CstIntegrator integ)
{
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    const CstFilter filters[] = {CST_FILTER_BOX, CST_FILTER_TENT};
    for (int fi = 0; fi < 2; fi++) {
        Film *one = render_with(s, integ, 1, filters[fi], 5);
        const int counts[] = {2, 3, 7};
        for (int i = 0; i < 3; i++) {
            Film *many = render_with(s, integ, counts[i], filters[fi], 5);
            if (!films_identical(one, many))
                fail_msg("%s, filter %s: 1 thread and %d threads differ", cst_integrator_name(integ),
                         cst_filter_name(filters[fi]), counts[i]);
            film_destroy(many);
        }
        /* ...and the seed matters (guards against a test that cannot fail). */
        Film *other = render_with(s, integ, 2, filters[fi], 6);
        assert_false(films_identical(one, other));
        film_destroy(other);
        film_destroy(one);
    }
    cst_scene_destroy(s);
}

static void test_thread_count_invariance(void **state)
{
    (void)state;
    check_thread_count_invariance(CST_INTEGRATOR_PATH);
}

/* The stratified and Sobol' samplers: every draw is a function of (seed, pixel, sample
 * index, dimension), so their images do not depend on the thread count either. */
static void test_sampler_thread_count_invariance(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    const CstSampler samplers[] = {CST_SAMPLER_STRATIFIED, CST_SAMPLER_SOBOL, CST_SAMPLER_ZSOBOL};
    for (int k = 0; k < 3; k++) {
        Film *f[3];
        const int threads[3] = {1, 3, 3};
        for (int i = 0; i < 3; i++) {
            CstRenderSettings st = {0};
            st.width = 96;
            st.height = 80;
            st.spp = 8;
            st.threads = threads[i];
            st.seed = i < 2 ? 5 : 6;
            st.seed_set = 1;
            st.sampler = samplers[k];
            assert_int_equal(cst_render(s, &st, &f[i], NULL, &err), CST_OK);
        }
        if (!films_identical(f[0], f[1]))
            fail_msg("%s sampler: 1 thread and 3 threads differ", cst_sampler_name(samplers[k]));
        assert_false(films_identical(f[0], f[2])); /* the seed matters */
        for (int i = 0; i < 3; i++) film_destroy(f[i]);
    }
    cst_scene_destroy(s);
}

/* 96 x 80 = 7680 light paths per iteration: 8 chunks, split unevenly over 2, 3 and 7
 * threads, and 8 iterations, so both the chunk order within an iteration and the
 * iteration order are exercised. */
static void test_light_thread_count_invariance(void **state)
{
    (void)state;
    check_thread_count_invariance(CST_INTEGRATOR_LIGHT);
}

/* BDPT and VCM: light vertex lists and camera splats per chunk, concatenated in chunk
 * order, the merging grid built from them in vertex order, camera paths per pixel. */
static void test_bidir_thread_count_invariance(void **state)
{
    (void)state;
    check_thread_count_invariance(CST_INTEGRATOR_BDPT);
    check_thread_count_invariance(CST_INTEGRATOR_VCM);
}

/* The photon maps are built single-threaded from the render seed (200000 photons, the
 * default, and the automatic radius), then read by every thread: the image must still
 * not depend on the thread count, and the seed must change the maps too. */
static void test_photon_thread_count_invariance(void **state)
{
    (void)state;
    check_thread_count_invariance(CST_INTEGRATOR_PHOTON);
}

/* SPPM (8 iterations of 7680 photons, automatic initial radius) traces its photons in
 * parallel chunks of 1024 (7.5 chunks: the last one partial) and deposits them over 4 x
 * threads pixel ranges (8, 12 and 28 here), each reading the chunks in order: every pixel
 * must still receive its photons in photon order, so the images must be identical. */
static void test_sppm_thread_count_invariance(void **state)
{
    (void)state;
    check_thread_count_invariance(CST_INTEGRATOR_SPPM);
    /* ...and the threads are used, and reported. */
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st = {0};
    st.integrator = CST_INTEGRATOR_SPPM;
    st.width = 16;
    st.height = 16;
    st.spp = 2;
    st.threads = 3;
    CstFilm *f = NULL;
    CstRenderStats stats;
    assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
    assert_int_equal(stats.threads, 3);
    assert_int_equal(stats.spp, 2);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

static void test_json_cornell_equals_builtin(void **state)
{
    (void)state;
    CstScene *builtin, *json;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&builtin, &err), CST_OK);
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-box.json", &json, &err) != CST_OK)
        fail_msg("%s", err.msg);
    Film *a = render(builtin, 2, CST_FILTER_BOX, 9);
    Film *b = render(json, 2, CST_FILTER_BOX, 9);
    assert_true(films_identical(a, b));
    film_destroy(a);
    film_destroy(b);
    cst_scene_destroy(builtin);
    cst_scene_destroy(json);
}

/* Every back end runs the same watertight triangle test (Embree through user geometry,
 * see accel_build), so they return the same hits and the image is the same bit for bit
 * whichever one the scene uses. */
static void test_accel_backends_identical_images(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    Film *ref = render(s, 2, CST_FILTER_BOX, 11);
    const char *names[] = {"kdtree", "grid", "list", "embree", "octree"};
    for (int i = 0; i < 5; i++) {
        CstStatus st = cst_scene_set_accel(s, names[i], &err);
        if (st == CST_ERR_UNSUPPORTED) {
            print_message("%s: not in this build, skipped\n", names[i]);
            continue;
        }
        assert_int_equal(st, CST_OK);
        Film *f = render(s, 2, CST_FILTER_BOX, 11);
        if (!films_identical(ref, f)) fail_msg("accel %s: image differs from the BVH's", names[i]);
        film_destroy(f);
    }
    film_destroy(ref);
    cst_scene_destroy(s);
}

/* A crop holds exactly the pixels of the whole image, for every integrator: camera passes
 * seed each pixel by its whole-image index, light paths are traced for the whole image.
 * (Also with AOVs, which are cropped with the film.) */
static void test_crop_equals_whole_image(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    const CstIntegrator integs[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_LIGHT,
                                    CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM, CST_INTEGRATOR_BDPT,
                                    CST_INTEGRATOR_VCM};
    const int crop[4] = {17, 61, 30, 79}; /* partial tiles, touching the bottom edge */
    for (size_t k = 0; k < sizeof integs / sizeof integs[0]; k++) {
        CstRenderSettings st = {0};
        st.integrator = integs[k];
        st.width = 96;
        st.height = 80;
        st.spp = 2;
        st.threads = 2;
        st.filter = CST_FILTER_TENT;
        st.seed = 9;
        st.seed_set = 1;
        st.photons = 20000;
        if (integs[k] == CST_INTEGRATOR_PATH) st.aovs = CST_AOV_ALBEDO | CST_AOV_DEPTH;
        CstFilm *whole = NULL, *part = NULL;
        CstRenderStats stats;
        assert_int_equal(cst_render(s, &st, &whole, NULL, &err), CST_OK);
        memcpy(st.crop, crop, sizeof st.crop);
        assert_int_equal(cst_render(s, &st, &part, &stats, &err), CST_OK);
        assert_int_equal(part->width, crop[1] - crop[0]);
        assert_int_equal(part->height, crop[3] - crop[2]);
        assert_int_equal(stats.width, part->width);
        assert_int_equal(part->spp, whole->spp);
        for (int y = 0; y < part->height; y++) {
            size_t a = (size_t)(crop[2] + y) * 96u + (size_t)crop[0], b = (size_t)y * (size_t)part->width;
            size_t n = 3u * (size_t)part->width;
            if (memcmp(&whole->sum[3 * a], &part->sum[3 * b], n * sizeof *part->sum) ||
                memcmp(&whole->sum_sq[3 * a], &part->sum_sq[3 * b], n * sizeof *part->sum_sq) ||
                (whole->aov && memcmp(&whole->aov[FILM_AOV_STRIDE * a], &part->aov[FILM_AOV_STRIDE * b],
                                      FILM_AOV_STRIDE * (size_t)part->width * sizeof *part->aov)))
                fail_msg("%s: row %d of the crop differs from the whole image", cst_integrator_name(integs[k]), y);
        }
        cst_film_destroy(whole);
        cst_film_destroy(part);
    }
    /* Bounds outside the image are refused. */
    CstRenderSettings bad = {0};
    bad.width = 64;
    bad.height = 64;
    bad.spp = 1;
    bad.crop[0] = 0; bad.crop[1] = 65; bad.crop[2] = 0; bad.crop[3] = 10;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &bad, &f, NULL, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "crop"));
    cst_scene_destroy(s);
}

/* CstProgressFn that cancels at its first call, counting the calls. */
static int cancel_at_once(void *user, double fraction, double elapsed)
{
    (void)fraction;
    (void)elapsed;
    ++*(int *)user;
    return 1;
}

/* A progress callback that returns nonzero stops every integrator at the next work-item
 * boundary: CST_ERR_CANCELLED, no film, no further progress report. */
static void test_cancel(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    const CstIntegrator all[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_WHITTED, CST_INTEGRATOR_PHOTON,
                                 CST_INTEGRATOR_LIGHT, CST_INTEGRATOR_SPPM, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (size_t i = 0; i < sizeof all / sizeof all[0]; i++) {
        CstRenderSettings st = {0};
        st.integrator = all[i];
        st.width = 32;
        st.height = 32;
        st.spp = 4;
        st.threads = 2;
        st.photons = 1000;
        int calls = 0;
        st.progress = cancel_at_once;
        st.progress_user = &calls;
        CstFilm *f = NULL;
        assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_CANCELLED);
        assert_null(f);
        assert_int_equal(calls, 1);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_thread_count_invariance),
        cmocka_unit_test(test_sampler_thread_count_invariance),
        cmocka_unit_test(test_light_thread_count_invariance),
        cmocka_unit_test(test_bidir_thread_count_invariance),
        cmocka_unit_test(test_photon_thread_count_invariance),
        cmocka_unit_test(test_sppm_thread_count_invariance),
        cmocka_unit_test(test_accel_backends_identical_images),
        cmocka_unit_test(test_json_cornell_equals_builtin),
        cmocka_unit_test(test_crop_equals_whole_image),
        cmocka_unit_test(test_cancel),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
