/* caustic explain for sppm (issue 30): on the Cornell box and the Cornell spheres (the glass
 * sphere's caustic), at several pixels and iterations 0, 1 and 5, the explanation's value
 * (direct light, photons and progressive update) is the film of a render of I + 1
 * iterations (on two threads) bit for bit; the test sums it again from the public events
 * alone, and the same sum without one photon misses the film (a broken replay fails);
 * spectral mode and a fog ball (visible points and photons in a medium) check too. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"

enum { W = 32, H = 32 };
#define ALPHA ((double)(2.0f / 3.0f)) /* sppm.h's SPPM_ALPHA (a float), Hachisuka & Jensen 2009 sec. 4 */
#define PI_F 3.14159265358979323846f

static int photons_seen, caustic_photons, chains_through_glass, volume_points;

static void settings(CstRenderSettings *st, CstColorMode color)
{
    memset(st, 0, sizeof *st);
    st->integrator = CST_INTEGRATOR_SPPM;
    st->width = W;
    st->height = H;
    st->threads = 2;
    st->color_mode = color;
    st->seed = 11;
    st->seed_set = 1;
    st->photons = 8000;
    st->filter = CST_FILTER_BOX;
}

static int same(double a, double b) { return memcmp(&a, &b, sizeof a) == 0; }

/* The pixel's value summed again from the public record (RGB mode: the events' first three
 * lanes are the exact ones), dropping photon event `drop` (-1: none), as camera_row,
 * progressive_update and sppm_finish compute it. */
static void resum(const CstExplain *x, int drop, double out[3])
{
    const struct CstExplainSppm *s = &x->sppm;
    float L[3] = {0.0f, 0.0f, 0.0f};
    double phi[3] = {0.0, 0.0, 0.0};
    long long m = 0;
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        if (e->kind == CST_EXPLAIN_PHOTON) {
            if (i == drop) continue;
            for (int c = 0; c < 3; c++) phi[c] += (double)e->contribution[c];
            m++;
        } else if (e->flags & CST_EXPLAIN_ADDED) {
            for (int c = 0; c < 3; c++) {
                const float p = e->beta[c] * e->value[c];
                L[c] = L[c] + p;
            }
        }
    }
    double n = s->n_before, tau[3];
    float r = s->r_before;
    for (int c = 0; c < 3; c++) tau[c] = s->tau_before[c];
    if (s->visible && m > 0) { /* a disc, or in a medium a ball */
        const double n_new = n + ALPHA * (double)m;
        const double q = n_new / (n + (double)m);
        const double r_new = (double)r * (s->volume ? cbrt(q) : sqrt(q));
        const double shrink = s->volume ? r_new * r_new * r_new / ((double)r * (double)r * (double)r)
                                        : r_new * r_new / ((double)r * (double)r);
        for (int c = 0; c < 3; c++) tau[c] = (tau[c] + (double)s->beta[c] * phi[c]) * shrink;
        r = (float)r_new;
    }
    const float r_disc = s->volume ? s->r_other : r, r_ball = s->volume ? r : s->r_other;
    const double area = (double)PI_F * (double)r_disc * (double)r_disc;
    const double rv = (double)r_ball, volume = 4.0 / 3.0 * (double)PI_F * rv * rv * rv;
    for (int c = 0; c < 3; c++) {
        const double ld = s->ld_before[c] + (double)L[c];
        const double t_disc = s->volume ? s->tau_other[c] : tau[c], t_ball = s->volume ? tau[c] : s->tau_other[c];
        double v = ld / (x->sample + 1) + (s->emitted > 0.0 ? t_disc / (s->emitted * area) : 0.0);
        if (s->media && s->emitted > 0.0) v += t_ball / (s->emitted * volume);
        out[c] = 0.0 + v;
    }
}

static void explain_pixels(const CstScene *scene, CstColorMode color, const int (*pix)[2], int npix)
{
    static const int ITER[] = {0, 1, 5};
    CstRenderSettings st;
    settings(&st, color);
    for (size_t k = 0; k < sizeof ITER / sizeof ITER[0]; k++) {
        const int it = ITER[k];
        CstRenderSettings rs = st;
        rs.spp = it + 1; /* SPPM's spp is its iteration count */
        CstFilm *film = NULL;
        CstError err;
        if (cst_render(scene, &rs, &film, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
        for (int p = 0; p < npix; p++) {
            const int x = pix[p][0], y = pix[p][1];
            CstExplain *ex = NULL;
            if (cst_explain(scene, &st, x, y, it, &ex, &err) != CST_OK) fail_msg("%s", err.msg);
            double rgb[3];
            cst_film_pixel(film, x, y, rgb);
            assert_false(ex->truncated);
            assert_int_equal(ex->sample, it);
            if (!ex->exact || !ex->sppm.state_exact)
                fail_msg("pixel (%d, %d) iteration %d: explain's sum (%.17g, ...) is not the render's (%.17g, ...)",
                         x, y, it, ex->sppm.value[0], ex->film_value[0]);
            for (int c = 0; c < 3; c++)
                if (!same(ex->film_value[c], rgb[c]))
                    fail_msg("pixel (%d, %d) iteration %d channel %d: explain's film %.17g, the %d-thread render's "
                             "%.17g", x, y, it, c, ex->film_value[c], rs.threads, rgb[c]);
            int largest = -1;
            for (int i = 0; i < ex->num_events; i++) {
                const CstExplainEvent *e = &ex->events[i];
                if (e->kind == CST_EXPLAIN_SCATTER && (e->flags & CST_EXPLAIN_DELTA)) chains_through_glass++;
                if (e->kind == CST_EXPLAIN_VERTEX && e->medium >= 0) volume_points++;
                if (e->kind != CST_EXPLAIN_PHOTON) continue;
                photons_seen++;
                assert_true(e->s >= 2 && e->path >= 0 && e->path < st.photons);
                assert_true(e->distance <= ex->sppm.r_before);
                if (largest < 0 || e->share[1] > ex->events[largest].share[1]) largest = i;
            }
            int listed = 0;
            for (int i = 0; i < ex->num_events; i++) listed += ex->events[i].kind == CST_EXPLAIN_PHOTON;
            assert_int_equal(ex->sppm.m, listed);
            if (color == CST_COLOR_RGB) {
                double v[3];
                resum(ex, -1, v);
                for (int c = 0; c < 3; c++)
                    if (!same(v[c], rgb[c]))
                        fail_msg("pixel (%d, %d) iteration %d channel %d: the public events re-sum to %.17g, the "
                                 "film holds %.17g", x, y, it, c, v[c], rgb[c]);
                if (largest >= 0 && ex->events[largest].share[1] > 0.0) {
                    /* A replay that drops one photon cannot match the film. */
                    resum(ex, largest, v);
                    assert_false(same(v[0], rgb[0]) && same(v[1], rgb[1]) && same(v[2], rgb[2]));
                    if (ex->events[largest].s >= 3) caustic_photons++;
                }
            }
            cst_explain_destroy(ex);
        }
        cst_film_destroy(film);
    }
}

static const int PIX[][2] = {{16, 16}, {5, 27}, {26, 8}, {16, 2}, {10, 29}, {22, 25}};

static void test_cornell_box(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    photons_seen = 0;
    explain_pixels(s, CST_COLOR_RGB, PIX, (int)(sizeof PIX / sizeof PIX[0]));
    print_message("cornell box: %d photons explained\n", photons_seen);
    assert_true(photons_seen > 100);
    cst_scene_destroy(s);
}

/* The spheres: pixels on the glass sphere (chains through delta lobes) and on the floor
 * under it (the caustic, photons of more than one bounce). */
static void test_cornell_spheres(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/cornell-spheres.json", &s, &err) != CST_OK)
        fail_msg("%s", err.msg);
    photons_seen = caustic_photons = chains_through_glass = 0;
    static const int SP[][2] = {{21, 24}, {19, 22}, {25, 29}, {23, 30}, {8, 27}, {16, 16}};
    explain_pixels(s, CST_COLOR_RGB, SP, (int)(sizeof SP / sizeof SP[0]));
    print_message("cornell spheres: %d photons, %d largest ones of 3+ bounces, %d delta scatters\n", photons_seen,
                  caustic_photons, chains_through_glass);
    assert_true(chains_through_glass > 0 && caustic_photons > 0);
    cst_scene_destroy(s);
}

static void test_spectral(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    explain_pixels(s, CST_COLOR_SPECTRAL, PIX, 2);
    cst_scene_destroy(s);
}

static void test_bad_input_and_media(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st;
    settings(&st, CST_COLOR_RGB);
    CstExplain *ex = NULL;
    assert_int_equal(cst_explain(s, &st, W, 0, 0, &ex, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_explain(s, &st, 0, 0, -1, &ex, &err), CST_ERR_INVALID_ARG);
    assert_null(ex);
    cst_scene_destroy(s);
    /* Media: visible points and photons in a fog ball over a floor. */
    static const char *json =
        "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},"
        " \"media\": {\"fog\": {\"sigma_a\": 0.1, \"sigma_s\": 0.5}},"
        " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.7, 0.7, 0.7]}},"
        " \"shapes\": [{\"type\": \"sphere\", \"center\": [0, 0, 0], \"radius\": 1,"
        "              \"medium\": {\"inside\": \"fog\", \"outside\": null, \"boundary\": true}},"
        "             {\"type\": \"quad\", \"material\": \"white\","
        "              \"vertices\": [[-4, -1.2, -4], [-4, -1.2, 4], [4, -1.2, 4], [4, -1.2, -4]]},"
        "             {\"type\": \"sphere\", \"center\": [0, 3, 0], \"radius\": 0.5, \"material\": \"white\","
        "              \"emission\": {\"radiance\": [5, 5, 5]}}]}";
    if (cst_scene_load_json_string(json, strlen(json), "fog.json", &s, &err) != CST_OK)
        fail_msg("the media scene: %s", err.msg);
    static const int FOG[][2] = {{16, 16}, {12, 18}, {20, 13}, {16, 30}, {3, 3}};
    photons_seen = volume_points = 0;
    explain_pixels(s, CST_COLOR_RGB, FOG, (int)(sizeof FOG / sizeof FOG[0]));
    print_message("fog: %d photons, %d visible points in the medium\n", photons_seen, volume_points);
    assert_true(volume_points > 0 && photons_seen > 0);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_cornell_box),
        cmocka_unit_test(test_cornell_spheres),
        cmocka_unit_test(test_spectral),
        cmocka_unit_test(test_bad_input_and_media),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
