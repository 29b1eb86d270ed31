/* caustic explain for pssmlt and mmlt (issue 30): on a 16x16 Cornell box with few
 * mutations, the Metropolis splats explain lists for a pixel and an iteration re-add, in
 * the listed order, to the value the render merged for that iteration, bit for bit; the
 * film's sums before and after it are a whole render's (1 and 2 iterations, any thread
 * count); leaving out the largest splat breaks the equality (the check sees a missing
 * step); the listed steps are consistent (weights a / I and (1 - a) / I; mmlt's strategy
 * (s, t) of the chain's path length); the first CST_EXPLAIN_MLT_PATHS splats carry their
 * sample's path, evaluated again from its primary sample vector: its radiance is the
 * splatted L bit for bit and its vertices are its path's (pssmlt: 1, 2, ... in order; mmlt:
 * t - 1 camera hits, s - 1 light hits and the one (s, t) connection with its MIS weight);
 * RGB and spectral, box, tent and Gaussian filters; mmlt through fog lists its medium
 * vertices on both subpaths. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdbool.h>
#include <stddef.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"

enum { SIZE = 16 };

static CstColorMode color_mode = CST_COLOR_RGB;

static CstRenderSettings mlt_settings(CstIntegrator integ, CstFilter filter)
{
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.integrator = integ;
    st.width = st.height = SIZE;
    st.filter = filter;
    st.spp = 2; /* iterations: mutations per pixel */
    st.max_depth = 4;
    st.mlt_chains = 24;
    st.mlt_bootstrap = 2048;
    st.seed = 5;
    st.seed_set = 1;
    st.threads = 1;
    st.color_mode = color_mode;
    return st;
}

static double lum(const double v[3]) { return 0.2126 * v[0] + 0.7152 * v[1] + 0.0722 * v[2]; }

/* Replayed samples' paths seen over the test, and of them those whose vertex counts were
 * checked against the strategy (mmlt) or that reached a light (pssmlt). */
static int replayed, replayed_light_side;
/* mmlt through media: replayed paths' medium vertices on the camera and the light side. */
static int medium_cam, medium_light;
/* mmlt: the light subpath's scatters listed in replays (lobe named, after their vertex). */
static int light_scatters;

/* The path of the splat m (its path_events events after it), evaluated again from the
 * sample's primary sample vector: it gave the splatted L bit for bit, and its vertices are
 * those of its path: pssmlt, the path tracer's vertices 1, 2, ... in order, at most
 * max_depth + 1 of them, something added; mmlt, the camera subpath's t - 1 hits (t - 2 when
 * the environment ends it) and the light subpath's s - 1, with one strategy event (s, t) of
 * the chain's path length carrying an MIS weight in (0, 1] (hits + light point = length + 1). */
static void check_path(CstIntegrator integ, const CstRenderSettings *st, const CstExplainEvent *m,
                       const CstExplainEvent *ev, int n)
{
    if (!(m->flags & CST_EXPLAIN_REPLAY_EXACT))
        fail_msg("%s chain %d step %d (%s): evaluated again L (%.9g %.9g %.9g), splatted (%.9g %.9g %.9g)",
                 cst_integrator_name(integ), m->chain, m->step, (m->flags & CST_EXPLAIN_PROPOSAL) ? "proposal" : "current",
                 (double)m->replay_value[0], (double)m->replay_value[1], (double)m->replay_value[2],
                 (double)m->value[0], (double)m->value[1], (double)m->value[2]);
    assert_memory_equal(m->replay_value, m->value, sizeof m->value);
    assert_true(m->path_events > 0 && m->path_events <= n);
    int cam = 0, light = 0, strategies = 0, added = 0, scatters = 0;
    for (int k = 0; k < m->path_events; k++) {
        const CstExplainEvent *e = &ev[k];
        assert_true(e->flags & CST_EXPLAIN_IN_SPLAT);
        assert_int_not_equal(e->kind, CST_EXPLAIN_MUTATION);
        added += (e->flags & CST_EXPLAIN_ADDED) != 0;
        if (e->kind == CST_EXPLAIN_DISTANCE) continue; /* a flight through media: neither vertex nor strategy */
        if ((e->kind == CST_EXPLAIN_SCATTER || e->kind == CST_EXPLAIN_ROULETTE) && e->depth < 0) {
            assert_int_equal(-e->depth, light); /* the light subpath's, after its vertex */
            if (e->kind == CST_EXPLAIN_SCATTER) assert_non_null(e->lobe);
            scatters += e->kind == CST_EXPLAIN_SCATTER;
            continue;
        }
        if (e->kind == CST_EXPLAIN_VERTEX && e->material_type && !strcmp(e->material_type, "medium")) {
            assert_true(e->medium >= 0);
            medium_cam += e->depth > 0;
            medium_light += e->depth < 0;
        }
        if (e->kind == CST_EXPLAIN_VERTEX && e->depth > 0) {
            assert_int_equal(e->depth, ++cam); /* the camera side's, in order */
        } else if (e->kind == CST_EXPLAIN_VERTEX) {
            assert_int_equal(-e->depth, ++light); /* the light side's, from the emitter */
        } else if (integ == CST_INTEGRATOR_MMLT && e->kind != CST_EXPLAIN_SCATTER && e->kind != CST_EXPLAIN_ROULETTE) {
            strategies++;
            assert_int_equal(e->s, m->s);
            assert_int_equal(e->t, m->t);
            assert_true(e->mis_weight > 0.0f && e->mis_weight <= 1.0f);
            const CstExplainKind want = m->t == 1   ? CST_EXPLAIN_SPLAT
                                        : m->s == 0 ? (e->kind == CST_EXPLAIN_ESCAPE ? CST_EXPLAIN_ESCAPE
                                                                                      : CST_EXPLAIN_EMISSION)
                                        : m->s == 1 ? CST_EXPLAIN_NEE
                                                    : CST_EXPLAIN_CONNECT;
            assert_int_equal(e->kind, want);
            if (e->kind == CST_EXPLAIN_ESCAPE) cam++; /* the escaping ray counts as the emitter's vertex */
        }
    }
    if (integ == CST_INTEGRATOR_MMLT) {
        if (strategies != 1 || cam != m->t - 1 || light != (m->s > 1 ? m->s - 1 : 0))
            fail_msg("mmlt chain %d step %d (s=%d, t=%d, length %d): %d strategy events, %d camera hits, %d light hits",
                     m->chain, m->step, m->s, m->t, m->path_length, strategies, cam, light);
        assert_int_equal(cam + light + (m->s >= 1 ? 1 : 0), m->path_length + 1);
        /* the walk scatters at every light hit but the last (no continuation past it) */
        if (scatters != (light > 0 ? light - 1 : 0))
            fail_msg("mmlt chain %d step %d (s=%d, t=%d): %d light hits, %d light-subpath scatters listed", m->chain,
                     m->step, m->s, m->t, light, scatters);
        light_scatters += scatters;
        replayed_light_side += light > 0;
    } else {
        assert_true(cam >= 1 && cam <= st->max_depth + 1 && light == 0 && added > 0);
        replayed_light_side += added > 0;
    }
    replayed++;
}

/* The film's sum at (x, y) after `iterations` iterations of a whole render with `threads`
 * threads: the mean times the count (1 or 2: exact in binary). */
static void film_sum(const CstScene *s, const CstRenderSettings *base, int iterations, int threads, double out[SIZE][SIZE][3])
{
    CstRenderSettings st = *base;
    st.spp = iterations;
    st.threads = threads;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    for (int y = 0; y < SIZE; y++)
        for (int x = 0; x < SIZE; x++) {
            cst_film_pixel(f, x, y, out[y][x]);
            for (int c = 0; c < 3; c++) out[y][x][c] *= (double)iterations;
        }
    cst_film_destroy(f);
}


/* Explains the `npix` pixels and the three the chains splatted most onto (at one
 * mutation per pixel and iteration most pixels get no splat) at iterations 0 and 1, and
 * checks them against whole renders; returns the splats listed. */
static int check(const CstScene *s, CstIntegrator integ, CstFilter filter, const int (*given)[2], int npix)
{
    static double film[2][SIZE][SIZE][3], film2[SIZE][SIZE][3];
    const CstRenderSettings st = mlt_settings(integ, filter);
    replayed = replayed_light_side = 0;
    film_sum(s, &st, 1, 1, film[0]);
    film_sum(s, &st, 2, 1, film[1]);
    film_sum(s, &st, 2, 3, film2);
    /* Determinism the replay relies on: the thread count changes no bit. */
    assert_memory_equal(film[1], film2, sizeof film2);
    int pix[16][2];
    assert_true(npix <= 13);
    if (npix) memcpy(pix, given, (size_t)npix * sizeof pix[0]);
    for (int k = 0; k < 3; k++, npix++) { /* the brightest pixels after two iterations, in order */
        int bx = -1, by = -1;
        for (int y = 0; y < SIZE; y++)
            for (int x = 0; x < SIZE; x++) {
                bool taken = false;
                for (int q = 0; q < npix; q++) taken |= pix[q][0] == x && pix[q][1] == y;
                if (!taken && (bx < 0 || lum(film[1][y][x]) > lum(film[1][by][bx]))) bx = x, by = y;
            }
        pix[npix][0] = bx;
        pix[npix][1] = by;
    }
    int listed = 0, proposals = 0, currents = 0, large = 0, broken = 0, lit = 0;
    for (int p = 0; p < npix; p++)
        for (int it = 0; it < 2; it++) {
            const int x = pix[p][0], y = pix[p][1];
            CstExplain *ex = NULL;
            CstError err;
            assert_int_equal(cst_explain(s, &st, x, y, it, &ex, &err), CST_OK);
            assert_false(ex->truncated);
            assert_int_equal(ex->integrator, integ);
            if (!ex->splats_exact)
                fail_msg("%s pixel %d,%d iteration %d: splats (%.17g %.17g %.17g) != the render's", cst_integrator_name(integ),
                         x, y, it, ex->splat_value[0], ex->splat_value[1], ex->splat_value[2]);
            /* The film's sums before and after the iteration are the renders'. */
            const double zero[3] = {0.0, 0.0, 0.0};
            assert_memory_equal(ex->camera_value, it == 0 ? zero : film[0][y][x], sizeof zero);
            assert_memory_equal(ex->film_value, film[it][y][x], sizeof zero);
            assert_true(ex->mlt_b > 0.0 && ex->mlt_scale > 0.0);
            /* The listed splats re-added here in their order: the iteration's value. */
            double sum[3] = {0.0, 0.0, 0.0}, best = -1.0;
            int bi = -1, splats = 0, with_path = 0;
            const CstExplainEvent *prev = NULL;
            for (int i = 0; i < ex->num_events; i++) {
                const CstExplainEvent *e = &ex->events[i];
                if (e->flags & CST_EXPLAIN_IN_SPLAT) continue; /* checked with its splat */
                assert_int_equal(e->kind, CST_EXPLAIN_MUTATION);
                /* The first CST_EXPLAIN_MLT_PATHS splats carry their sample's path. */
                if (splats++ < CST_EXPLAIN_MLT_PATHS) {
                    assert_true(e->flags & CST_EXPLAIN_REPLAYED);
                    check_path(integ, &st, e, e + 1, ex->num_events - i - 1);
                    with_path++;
                } else {
                    assert_false(e->flags & CST_EXPLAIN_REPLAYED);
                }
                assert_true(e->flags & CST_EXPLAIN_ADDED);
                assert_true(e->chain >= 0 && e->chain < ex->mlt_chains && e->step >= 0);
                assert_true(e->accept >= 0.0f && e->accept <= 1.0f && e->importance > 0.0f);
                const float w = (e->flags & CST_EXPLAIN_PROPOSAL) ? e->accept / e->importance
                                                                  : (1.0f - e->accept) / e->importance;
                assert_true(e->weight == w);
                if (integ == CST_INTEGRATOR_MMLT)
                    assert_true(e->path_length >= 0 && e->path_length <= st.max_depth && e->s >= 0 && e->t >= 1 &&
                                e->s + e->t == e->path_length + 2);
                else
                    assert_true(e->path_length == -1 && e->s == -1);
                if (prev) /* the film's order: chain by chain, step by step */
                    assert_true(e->chain > prev->chain || (e->chain == prev->chain && e->step >= prev->step));
                prev = e;
                for (int c = 0; c < 3; c++) sum[c] += e->share[c];
                if (lum(e->share) > best) best = lum(e->share), bi = i;
                proposals += (e->flags & CST_EXPLAIN_PROPOSAL) != 0;
                currents += !(e->flags & CST_EXPLAIN_PROPOSAL);
                large += (e->flags & CST_EXPLAIN_LARGE_STEP) != 0;
            }
            assert_memory_equal(sum, ex->splat_value, sizeof sum);
            assert_int_equal(ex->mlt_replayed, with_path);
            assert_int_equal(ex->mlt_replay_exact, with_path);
            assert_true(ex->exact); /* the splats' sum and every evaluation again */
            for (int c = 0; c < 3; c++) {
                const double after = ex->camera_value[c] + sum[c];
                assert_memory_equal(&after, &ex->film_value[c], sizeof after);
            }
            /* A broken replay, one step missing: the sum is no longer the film's. */
            if (bi >= 0) {
                double part[3] = {0.0, 0.0, 0.0};
                for (int i = 0; i < ex->num_events; i++)
                    for (int c = 0; c < 3; c++)
                        if (i != bi && !(ex->events[i].flags & CST_EXPLAIN_IN_SPLAT)) part[c] += ex->events[i].share[c];
                if (memcmp(part, ex->splat_value, sizeof part) != 0) broken++;
                else fail_msg("pixel %d,%d: a sum without its largest splat equals the film's", x, y);
            }
            listed += splats;
            lit += splats > 0;
            cst_explain_destroy(ex);
        }
    /* Splats listed at several pixels and iterations: both kinds, and large steps. */
    /* Paths evaluated again, and among them (mmlt) strategies with light-subpath hits. */
    if (replayed < 20 || (integ == CST_INTEGRATOR_PSSMLT && replayed_light_side < 5)) fail_msg("%s: %d paths evaluated again, %d of them with light "
                                                          "hits", cst_integrator_name(integ), replayed, replayed_light_side);
    if (lit < 3 || !proposals || !currents || !large || broken < 3)
        fail_msg("%s: %d pixel iterations with splats, %d proposals, %d current states, %d large steps",
                 cst_integrator_name(integ), lit, proposals, currents, large);
    print_message("%s: %d splats listed, at %d of %d pixel iterations (%d proposals, %d large steps); %d paths "
                  "evaluated again, %d %s\n", cst_integrator_name(integ), listed, lit, 2 * npix, proposals, large,
                  replayed, replayed_light_side, integ == CST_INTEGRATOR_MMLT ? "with light-subpath hits" : "lit");
    return listed;
}

static void test_pssmlt(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    static const int PIX[][2] = {{8, 8}, {3, 12}, {12, 3}, {8, 1}};
    assert_true(check(s, CST_INTEGRATOR_PSSMLT, CST_FILTER_BOX, PIX, 4) > 0);
    /* The tent: splats shared between neighbouring pixels. */
    assert_true(check(s, CST_INTEGRATOR_PSSMLT, CST_FILTER_TENT, PIX, 2) > 0);
    cst_scene_destroy(s);
}

/* mmlt's splats on the light's pixels are mostly of length 0 (s = 0, t = 2); below it, on
 * the ceiling and walls, the chains of longer paths splat: pixels there are explained (iteration
 * 1) until 5 replayed strategies with light-subpath hits (s >= 2, or t = 1) have been checked. */
static void mmlt_light_side(const CstScene *s, CstColorMode mode)
{
    color_mode = mode;
    const CstRenderSettings st = mlt_settings(CST_INTEGRATOR_MMLT, CST_FILTER_BOX);
    replayed = replayed_light_side = light_scatters = 0;
    int explained = 0;
    for (int y = 3; y < SIZE && replayed_light_side < 5; y++)
        for (int x = 0; x < SIZE && replayed_light_side < 5; x++) {
            CstExplain *ex = NULL;
            CstError err;
            assert_int_equal(cst_explain(s, &st, x, y, 1, &ex, &err), CST_OK);
            assert_true(ex->exact && !ex->truncated);
            for (int i = 0; i < ex->num_events; i++)
                if (ex->events[i].flags & CST_EXPLAIN_REPLAYED)
                    check_path(CST_INTEGRATOR_MMLT, &st, &ex->events[i], &ex->events[i + 1], ex->num_events - i - 1);
            explained++;
            cst_explain_destroy(ex);
        }
    print_message("mmlt: %d paths evaluated again at %d pixels below the light, %d with light-subpath hits, %d "
                  "light-subpath scatters\n", replayed, explained, replayed_light_side, light_scatters);
    assert_true(replayed_light_side >= 5);
    color_mode = CST_COLOR_RGB;
}

static void test_mmlt(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    mmlt_light_side(s, CST_COLOR_RGB);
    static const int PIX[][2] = {{8, 8}, {2, 14}, {13, 5}, {7, 2}};
    assert_true(check(s, CST_INTEGRATOR_MMLT, CST_FILTER_BOX, PIX, 4) > 0);
    assert_true(check(s, CST_INTEGRATOR_MMLT, CST_FILTER_GAUSSIAN, PIX, 2) > 0);
    cst_scene_destroy(s);
}

/* mmlt through participating media (the fog-filled Cornell box, subpath_media.c's single
 * strategies): each replayed strategy lists its camera subpath's t - 1 vertices and its
 * light subpath's s - 1, medium vertices among them on both sides (check_path's counts), its
 * flights apart; the radiance is still the splatted one bit for bit. Pixels are explained
 * until both sides have shown medium vertices (iteration 1). */
static void test_mmlt_media(void **state)
{
    (void)state;
    static const char *const FOG = CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt";
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt(FOG, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", FOG, err.msg);
    const CstRenderSettings st = mlt_settings(CST_INTEGRATOR_MMLT, CST_FILTER_BOX);
    replayed = replayed_light_side = medium_cam = medium_light = light_scatters = 0;
    int explained = 0;
    for (int y = 4; y < SIZE && (medium_cam < 5 || medium_light < 5); y += 2)
        for (int x = 1; x < SIZE && (medium_cam < 5 || medium_light < 5); x += 3) {
            CstExplain *ex = NULL;
            assert_int_equal(cst_explain(s, &st, x, y, 1, &ex, &err), CST_OK);
            assert_true(ex->exact && !ex->truncated);
            for (int i = 0; i < ex->num_events; i++)
                if (ex->events[i].flags & CST_EXPLAIN_REPLAYED)
                    check_path(CST_INTEGRATOR_MMLT, &st, &ex->events[i], &ex->events[i + 1], ex->num_events - i - 1);
            explained++;
            cst_explain_destroy(ex);
        }
    print_message("mmlt in fog: %d paths evaluated again at %d pixels (%d with light-subpath hits): %d camera-side and "
                  "%d light-side medium vertices, %d light-subpath scatters\n", replayed, explained, replayed_light_side,
                  medium_cam, medium_light, light_scatters);
    assert_true(replayed > 0 && medium_cam >= 5 && medium_light >= 5 && light_scatters > 0);
    cst_scene_destroy(s);
}

/* Spectral mode: the samples' wavelengths are primary sample dimensions too. */
static void test_spectral(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    mmlt_light_side(s, CST_COLOR_SPECTRAL);
    color_mode = CST_COLOR_SPECTRAL;
    assert_true(check(s, CST_INTEGRATOR_PSSMLT, CST_FILTER_BOX, NULL, 0) > 0);
    assert_true(check(s, CST_INTEGRATOR_MMLT, CST_FILTER_TENT, NULL, 0) > 0);
    color_mode = CST_COLOR_RGB;
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pssmlt),
        cmocka_unit_test(test_mmlt),
        cmocka_unit_test(test_mmlt_media),
        cmocka_unit_test(test_spectral),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
