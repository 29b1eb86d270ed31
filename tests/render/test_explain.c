/* caustic explain (issue 30): for the path tracer's three modes, BDPT and VCM, on the
 * Cornell boxes and a few pixels and samples, the recorded contributions sum bit for bit to
 * the camera sample the render computes, and that sample plus BDPT's/VCM's splats (re-added
 * one by one) is what a one-sample render of the pixel accumulates; the strategies' MIS
 * weights lie in [0, 1] and BDPT's and VCM's (connections, merges, splats) equal the ones
 * computed from every strategy's pdfs of the same path, which sum to 1; paths through
 * subsurface materials are recorded (the BSSRDF's exit); BDPT and VCM through media (a fog
 * box: homogeneous, grid, emitting grid), subsurface walks and a moving camera likewise, their
 * weights checked explicitly too; whitted's ray tree and the light tracer's splats sum to the film's value;
 * photon mapping with a moving instance prints and sums with its time window's kernel;
 * BDPT's and VCM's pixel light subpath is listed, not summed (its scatters' directions and,
 * at diffuse vertices, forward and reverse densities checked; through fog its medium
 * vertices and phase samples); integrators explain cannot follow and bad pixels are refused. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <math.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "render/media_scenes.h"

enum { W = 24, H = 20 };

static int mis_checked; /* BDPT/VCM strategies whose weight explain computed explicitly */
static int merges;      /* VCM merges recorded */
static int merges_checked, splats_checked; /* of them, and of the splats, checked explicitly */
static double mis_error; /* the largest relative difference from the explicit weights */
static int sss_exits;    /* subsurface exits recorded (path_sss.c) */
static float radius;    /* photon_radius of the settings (0: the default) */
static int heroes;      /* spectral BDPT/VCM: additions at the hero wavelength alone */
static int light_dispersed; /* of them, connections and merges with a dispersed light vertex */
static int photons_gathered[2]; /* photon: photons listed by the caustic and the global estimates */
/* The pixels explain_all explains (NULL: its own five). */
static const int (*pixels)[2];
static size_t num_pixels;
static int subsurface_walk; /* subsurface_walk of the settings */
static int medium_vertices, volume_merges, media_flights; /* BDPT/VCM through media: what was recorded */
static int volume_merges_checked, media_emissions; /* of the volume merges, checked explicitly; media's Le */
static int s0_emissions; /* emission events with s = 0 (photon: the emission of media on its walks) */
static int photon_count = 20000; /* photons of the settings: a small map is built for every explained sample */
/* photon through media: volume estimates that gathered photons, and those photons; estimates
 * of the surface maps at vertices reached through fog; explained spectral samples whose
 * photon set was named. */
static int volume_estimates, volume_photons, surface_estimates_in_fog, photon_sets_named;
/* photon with moving instances: estimates whose kernel carries the time window's factor
 * (time_scale >= 8: the window is at most 1/8 of the shutter), and their photons. */
static int windowed_estimates, windowed_photons;
static const double PI_D = 3.14159265358979323846;
/* BDPT/VCM: the pixel's light subpath listed (events of depth -bounces, not summed): its
 * scatters, those whose direction was checked against the next light vertex, those at
 * diffuse vertices whose forward and reverse densities were checked, its roulette events,
 * its medium vertices and phase-function scatters. */
static int light_scatters, light_dirs_checked, light_pdfs_checked, light_roulettes, light_medium_vertices,
    light_phases;
/* Roulette events at medium vertices (media_scatter_phase): the light subpath's, the camera's. */
static int light_medium_roulettes, camera_medium_roulettes;

/* The largest component of the difference between wi and the unit direction from a to b;
 * -1 when a and b are closer than 1e-2 (a glass sphere resting on the floor: the scattered
 * ray starts from an offset origin, so a segment that short has no comparable direction). */
static double unit_diff(const float a[3], const float b[3], const float wi[3])
{
    double d[3], l = 0.0, m = 0.0;
    for (int c = 0; c < 3; c++) {
        d[c] = (double)b[c] - (double)a[c];
        l += d[c] * d[c];
    }
    if (l < 1e-4) return -1.0;
    for (int c = 0; c < 3; c++) m = fmax(m, fabs(d[c] / sqrt(l) - (double)wi[c]));
    return m;
}

/* The light subpath's events of a BDPT/VCM explain: vertices -1, -2, ... in order, none
 * summed; each scatter after its vertex, its wi pointing at the next light vertex; at a
 * diffuse vertex the forward density |n.wi| / pi and the reverse one |n.wo| / pi (wo toward
 * the previous light vertex), as BDPT's MIS ratios use them. */
static void check_light_subpath(const CstExplain *ex)
{
    const CstExplainEvent *v[66] = {NULL};
    int nv = 0;
    for (int i = 0; i < ex->num_events; i++) {
        const CstExplainEvent *e = &ex->events[i];
        if (e->depth >= 0 || e->kind == CST_EXPLAIN_SPLAT) continue;
        assert_false(e->flags & CST_EXPLAIN_ADDED); /* contribution-neutral */
        const int b = -e->depth;
        if (e->kind == CST_EXPLAIN_VERTEX) {
            assert_int_equal(b, nv + 1);
            if (nv < 65) v[++nv] = e;
            light_medium_vertices += e->medium >= 0;
            continue;
        }
        assert_int_equal(b, nv); /* after its vertex */
        if (e->kind == CST_EXPLAIN_ROULETTE) {
            assert_true(e->q > 0.0f && e->q <= 0.95f);
            light_roulettes++;
            light_medium_roulettes += v[b] && v[b]->medium >= 0;
            continue;
        }
        assert_int_equal(e->kind, CST_EXPLAIN_SCATTER);
        assert_non_null(e->lobe);
        light_scatters++;
        light_phases += !strcmp(e->lobe, "phase function");
        if (!(e->flags & CST_EXPLAIN_DELTA)) assert_true(e->pdf_w > 0.0f && e->pdf_other_w >= 0.0f);
        /* the next vertex, if the walk made one */
        for (int k = i + 1; k < ex->num_events; k++) {
            const CstExplainEvent *n = &ex->events[k];
            if (n->kind != CST_EXPLAIN_VERTEX || n->depth != -(b + 1)) continue;
            const double dev = unit_diff(v[b]->p, n->p, e->wi);
            if (dev > 1e-3)
                fail_msg("%s pixel %d,%d sample %d: light vertex %d: wi is %.3g off the direction to vertex %d",
                         cst_integrator_name(ex->integrator), ex->x, ex->y, ex->sample, b, dev, b + 1);
            light_dirs_checked += dev >= 0.0;
            break;
        }
        const CstExplainEvent *x = v[b];
        if (b < 2 || !x || !x->material_type || strcmp(x->material_type, "diffuse") || x->medium >= 0) continue;
        double co = 0.0, ci = 0.0, d[3], l = 0.0;
        for (int c = 0; c < 3; c++) {
            d[c] = (double)v[b - 1]->p[c] - (double)x->p[c];
            l += d[c] * d[c];
        }
        if (l < 1e-4) continue; /* too short for wo (unit_diff) */
        for (int c = 0; c < 3; c++) {
            co += (double)x->n[c] * d[c] / sqrt(l);
            ci += (double)x->n[c] * (double)e->wi[c];
        }
        const double fwd = fabs(ci) / PI_D, rev = fabs(co) / PI_D;
        if (fabs((double)e->pdf_w - fwd) > 1e-4 * fwd || fabs((double)e->pdf_other_w - rev) > 1e-3 * rev + 1e-7)
            fail_msg("light vertex %d (diffuse): pdf_w %.7g (|n.wi|/pi %.7g), reverse %.7g (|n.wo|/pi %.7g)", b,
                     (double)e->pdf_w, fwd, (double)e->pdf_other_w, rev);
        light_pdfs_checked++;
    }
}

static void settings(CstRenderSettings *st, CstIntegrator integ, CstFilter filter, CstColorMode color)
{
    memset(st, 0, sizeof *st);
    st->integrator = integ;
    st->width = W;
    st->height = H;
    st->spp = 4;
    st->threads = 1;
    st->filter = filter;
    st->color_mode = color;
    st->seed = 7;
    st->seed_set = 1;
    /* The pixels and samples below were chosen with the independent sampler (some paths
     * must reach the light); the other samplers' replays are test_strata's (and
     * test_whitted_light's signed zero, under zsobol). */
    st->sampler = CST_SAMPLER_INDEPENDENT;
    if (radius > 0.0f) st->photon_radius = radius;
    st->photons = photon_count;
    st->subsurface_walk = subsurface_walk;
}

/* The film value of sample `sample` of pixel (x, y) alone: a one-pixel crop rendered
 * from first_sample = sample, one sample (its mean is its sum). */
static void render_one(const CstScene *s, const CstRenderSettings *base, int x, int y, int sample, double rgb[3])
{
    CstRenderSettings st = *base;
    st.spp = 1;
    st.first_sample = sample;
    st.crop[0] = x; st.crop[1] = x + 1; st.crop[2] = y; st.crop[3] = y + 1;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    cst_film_pixel(f, 0, 0, rgb);
    cst_film_destroy(f);
}

static int explain_all(const CstScene *s, CstIntegrator integ, CstFilter filter, CstColorMode color)
{
    static const int PIX[][2] = {{12, 10}, {3, 17}, {20, 2}, {12, 1}, {8, 14}};
    const int (*pix)[2] = pixels ? pixels : PIX;
    const size_t npix = pixels ? num_pixels : sizeof PIX / sizeof PIX[0];
    int added = 0;
    CstRenderSettings st;
    settings(&st, integ, filter, color);
    for (size_t p = 0; p < npix; p++) {
        for (int sample = 0; sample < 4; sample += 3) {
            const int x = pix[p][0], y = pix[p][1];
            CstExplain *ex = NULL;
            CstError err;
            assert_int_equal(cst_explain(s, &st, x, y, sample, &ex, &err), CST_OK);
            assert_false(ex->truncated);
            if (!ex->exact)
                fail_msg("%s pixel %d,%d sample %d: sum (%.9g %.9g %.9g) != camera (%.9g %.9g %.9g)",
                         cst_integrator_name(integ), x, y, sample, (double)ex->sum[0], (double)ex->sum[1],
                         (double)ex->sum[2], ex->camera_value[0], ex->camera_value[1], ex->camera_value[2]);
            double film[3];
            render_one(s, &st, x, y, sample, film);
            for (int c = 0; c < 3; c++) {
                /* bit for bit: the render's film holds what explain replayed */
                assert_memory_equal(&film[c], &ex->film_value[c], sizeof film[c]);
                if (integ != CST_INTEGRATOR_BDPT && integ != CST_INTEGRATOR_VCM && integ != CST_INTEGRATOR_LIGHT)
                    assert_true(ex->splat_value[c] == 0.0);
            }
            /* BDPT, VCM: the camera sample plus the splats, re-added as the film adds them. */
            if (integ == CST_INTEGRATOR_BDPT || integ == CST_INTEGRATOR_VCM) assert_true(ex->splats_exact);
            /* BDPT, VCM: every strategy's weight (splats and merges too) equals the one
             * computed from all strategies' pdfs of the same path (on the rays' own segments),
             * and those weights sum to 1. Measured: at most 4.4e-7 relative on the Cornell
             * box's pixels (2.9e-4 when the explicit weights took the segments from the
             * vertices' positions instead of the offset rays'); a t = 1 density off by 2x
             * gives 0.1 to 2.4. */
            mis_checked += ex->mis_checked;
            if (ex->mis_max_error > mis_error) mis_error = ex->mis_max_error;
            if (ex->mis_max_error > 1e-4 || ex->mis_max_sum_error > 1e-6)
                fail_msg("%s pixel %d,%d sample %d: MIS weight differs from the explicit one by %.3g (rel), sum "
                         "off 1 by %.3g", cst_integrator_name(integ), x, y, sample, ex->mis_max_error,
                         ex->mis_max_sum_error);
            if (integ == CST_INTEGRATOR_PHOTON && color == CST_COLOR_SPECTRAL) {
                /* the sample's wavelengths and the photon set whose maps it read */
                assert_true(ex->photon_set >= 0 && ex->photon_set < 16);
                assert_true(ex->wavelengths[0] >= 360.0f && ex->wavelengths[3] <= 830.0f);
                photon_sets_named++;
            }
            if (integ == CST_INTEGRATOR_BDPT || integ == CST_INTEGRATOR_VCM) check_light_subpath(ex);
            bool in_medium = false; /* the camera vertex the events belong to is a medium vertex */
            bool flown = false; /* photon: the camera walk has crossed a medium */
            for (int i = 0; i < ex->num_events; i++) {
                const CstExplainEvent *e = &ex->events[i];
                if (e->kind == CST_EXPLAIN_VERTEX && e->depth >= 0) {
                    in_medium = e->material_type && !strcmp(e->material_type, "medium");
                    medium_vertices += in_medium;
                }
                if (e->kind == CST_EXPLAIN_ROULETTE && e->depth >= 0 && in_medium) camera_medium_roulettes++;
                if (e->kind == CST_EXPLAIN_MERGE && in_medium) volume_merges++;
                if (e->kind == CST_EXPLAIN_MERGE && in_medium && e->mis_strategies > 0) volume_merges_checked++;
                if (e->kind == CST_EXPLAIN_EMISSION && e->light < 0 && e->contribution[0] != 0.0f) media_emissions++;
                /* recorder_media_emission's (s = 0): photon's emission of media on its walks */
                if (e->kind == CST_EXPLAIN_EMISSION && e->s == 0 && e->contribution[0] != 0.0f) s0_emissions++;
                if (e->kind == CST_EXPLAIN_DISTANCE) media_flights++;
                if (e->flags & CST_EXPLAIN_ADDED) added++;
                if ((e->flags & CST_EXPLAIN_ADDED) && (e->flags & (CST_EXPLAIN_HERO | CST_EXPLAIN_LIGHT_DISPERSED)) &&
                    e->contribution[0] != 0.0f)
                    heroes++;
                if ((e->flags & CST_EXPLAIN_ADDED) && (e->flags & CST_EXPLAIN_LIGHT_DISPERSED) &&
                    e->contribution[0] != 0.0f)
                    light_dispersed++;
                if (e->mis_strategies > 0) assert_true(e->mis_strategies >= 1 && e->mis_explicit > 0.0f);
                if (e->mis_weight != -1.0f) assert_true(e->mis_weight >= 0.0f && e->mis_weight <= 1.0f);
                if (e->kind == CST_EXPLAIN_MERGE) merges++;
                if (e->kind == CST_EXPLAIN_ESTIMATE && e->value[0] != 0.0f && !(e->flags & CST_EXPLAIN_VOLUME))
                    photons_gathered[(e->flags & CST_EXPLAIN_CAUSTIC) ? 0 : 1] += e->path;
                if (e->kind == CST_EXPLAIN_ESTIMATE && (e->flags & CST_EXPLAIN_VOLUME) && e->path > 0) {
                    volume_estimates++;
                    volume_photons += e->path;
                }
                if (e->kind == CST_EXPLAIN_ESTIMATE && e->time_scale != 1.0f) {
                    /* The kernel printed is the one the estimate used: the window's factor
                     * s = shutter / window over pi r^2 (or (4/3) pi r^3), the window inside
                     * the shutter and at most an eighth of it. */
                    const double r = (double)e->distance;
                    const double area = (e->flags & CST_EXPLAIN_VOLUME) ? 4.0 / 3.0 * PI_D * r * r * r : PI_D * r * r;
                    const double shutter = 1.0, width = (double)e->time_window[1] - (double)e->time_window[0];
                    assert_true(e->time_window[0] >= 0.0f && e->time_window[1] <= 1.0f && width > 0.0);
                    assert_true(width <= shutter / 8.0 * 1.000001);
                    assert_true(fabs((double)e->time_scale - shutter / width) <= 1e-5 * (double)e->time_scale);
                    assert_true(fabs((double)e->pmf - (double)e->time_scale / area) <= 1e-5 * (double)e->pmf);
                    windowed_estimates++;
                    windowed_photons += e->path;
                }
                if (e->kind == CST_EXPLAIN_DISTANCE) flown = true;
                if (e->kind == CST_EXPLAIN_ESTIMATE && !(e->flags & CST_EXPLAIN_VOLUME) && e->path > 0 && flown)
                    surface_estimates_in_fog++;
                if (e->kind == CST_EXPLAIN_VERTEX && e->material_type && !strcmp(e->material_type, "subsurface exit"))
                    sss_exits++;
                if (e->kind == CST_EXPLAIN_MERGE && e->mis_strategies > 0) merges_checked++;
                if (e->kind == CST_EXPLAIN_SPLAT && e->mis_strategies > 0) splats_checked++;
                if ((integ == CST_INTEGRATOR_BDPT || integ == CST_INTEGRATOR_VCM) && e->kind != CST_EXPLAIN_VERTEX && e->kind != CST_EXPLAIN_SCATTER &&
                    e->kind != CST_EXPLAIN_ROULETTE && e->mis_weight >= 0.0f) {
                    /* Georgiev's recursive form: w = 1 / (w_light + 1 + w_camera). */
                    float w = 1.0f / (e->pdf_other_w + 1.0f + e->pdf_other2);
                    assert_true(fabsf(w - e->mis_weight) <= 1e-5f * e->mis_weight);
                    assert_true(e->s >= 0 && e->t >= 1);
                }
            }
            cst_explain_destroy(ex);
        }
    }
    return added;
}

static CstScene *load(const char *name)
{
    char path[1024];
    snprintf(path, sizeof path, "%s/scenes/%s", CST_SOURCE_DIR, name);
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(path, &s, &err) != CST_OK) fail_msg("%s: %s", path, err.msg);
    return s;
}

static void test_path_cornell(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_PATH_NEE, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_PATH_BSDF, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    /* A filter weight other than 1 and spectral mode's conversion. */
    assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_MITCHELL, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    cst_scene_destroy(s);
}

static void test_path_specular(void **state)
{
    (void)state;
    CstScene *s = load("cornell-spheres.json");
    assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    cst_scene_destroy(s);
}

/* Participating media (volpath_li): the fog and the grid-medium Cornell boxes, whose
 * distance sampling, medium vertices, medium NEE and spectral MIS over lanes (grid) add up
 * to the camera sample bit for bit; the distance events are recorded. */
static void test_path_media(void **state)
{
    (void)state;
    static const char *const SCENES[] = {CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt",
                                         CST_SOURCE_DIR "/tests/render/media/cornell-grid.pbrt"};
    for (size_t k = 0; k < sizeof SCENES / sizeof SCENES[0]; k++) {
        CstScene *s = NULL;
        CstError err;
        if (cst_scene_load_pbrt(SCENES[k], NULL, &s, &err) != CST_OK) fail_msg("%s: %s", SCENES[k], err.msg);
        assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
        assert_true(explain_all(s, CST_INTEGRATOR_PATH_NEE, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
        CstRenderSettings st;
        settings(&st, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB);
        CstExplain *ex = NULL;
        assert_int_equal(cst_explain(s, &st, 12, 10, 0, &ex, &err), CST_OK);
        int distances = 0;
        for (int i = 0; i < ex->num_events; i++) distances += ex->events[i].kind == CST_EXPLAIN_DISTANCE;
        assert_true(distances > 0);
        cst_explain_destroy(ex);
        cst_scene_destroy(s);
    }
}

/* Subsurface materials (path_sss_li): the BSSRDF step's exit, its NEE and Sw scatter are
 * recorded and the sum is the camera sample bit for bit, in RGB and spectral mode; pixels on
 * the two spheres besides explain_all's. */
static void test_path_subsurface(void **state)
{
    (void)state;
    static const char *const SCENE = CST_SOURCE_DIR "/tests/render/subsurface/sss-spheres.pbrt";
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt(SCENE, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", SCENE, err.msg);
    sss_exits = 0;
    assert_true(explain_all(s, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_PATH_NEE, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    static const int PIX[][2] = {{6, 10}, {17, 10}, {18, 8}, {5, 12}};
    CstRenderSettings st;
    settings(&st, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_SPECTRAL);
    for (size_t p = 0; p < sizeof PIX / sizeof PIX[0]; p++)
        for (int sample = 0; sample < 4; sample++) {
            CstExplain *ex = NULL;
            assert_int_equal(cst_explain(s, &st, PIX[p][0], PIX[p][1], sample, &ex, &err), CST_OK);
            assert_true(ex->exact && !ex->truncated);
            for (int i = 0; i < ex->num_events; i++) {
                const CstExplainEvent *e = &ex->events[i];
                if (e->kind == CST_EXPLAIN_VERTEX && e->material_type && !strcmp(e->material_type, "subsurface exit"))
                    sss_exits++;
            }
            cst_explain_destroy(ex);
        }
    print_message("subsurface: %d exits recorded\n", sss_exits);
    assert_true(sss_exits > 0);
    cst_scene_destroy(s);
}

/* The light subpaths' events seen since the last report (check_light_subpath): some of
 * each kind. */
static void report_light_subpaths(const char *name)
{
    print_message("%s: light subpaths: %d scatters (%d directions and %d diffuse densities checked), %d roulette "
                  "events\n", name, light_scatters, light_dirs_checked, light_pdfs_checked, light_roulettes);
    assert_true(light_scatters > 20 && light_dirs_checked > 10 && light_pdfs_checked > 10 && light_roulettes > 5);
    light_scatters = light_dirs_checked = light_pdfs_checked = light_roulettes = 0;
}

static void test_bdpt(void **state)
{
    (void)state;
    light_scatters = light_dirs_checked = light_pdfs_checked = light_roulettes = 0;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_TENT, CST_COLOR_RGB) > 0);
    cst_scene_destroy(s);
    s = load("cornell-spheres.json");
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_MITCHELL, CST_COLOR_SPECTRAL) > 0);
    cst_scene_destroy(s);
    print_message("bdpt: %d strategies' MIS weights checked against the explicit ones (%d splats), largest "
                  "relative difference %.3g\n", mis_checked, splats_checked, mis_error);
    assert_true(mis_checked >= 50 && splats_checked >= 20);
    report_light_subpaths("bdpt");
}

/* VCM: connections and merges (summed, normalised and added per camera vertex as the walk
 * does) give the camera sample bit for bit; a larger radius than the default so that this
 * small image's light vertices merge. */
static void test_vcm(void **state)
{
    (void)state;
    CstScene *s = load("cornell-spheres.json");
    merges = merges_checked = splats_checked = mis_checked = 0;
    light_scatters = light_dirs_checked = light_pdfs_checked = light_roulettes = 0;
    mis_error = 0.0;
    radius = 20.0f; /* the box is 555 units wide */
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    cst_scene_destroy(s);
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_TENT, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    cst_scene_destroy(s);
    radius = 0.0f;
    /* Every merge and every splat near the pixel is checked (their light subpaths traced
     * again), with the merging strategies in every weight (explain_all's thresholds). */
    print_message("vcm: %d merges recorded, %d checked; %d splats checked; %d strategies in all, largest relative "
                  "difference %.3g\n", merges, merges_checked, splats_checked, mis_checked, mis_error);
    assert_true(merges > 0 && merges_checked == merges);
    assert_true(splats_checked >= 50 && mis_checked >= 100);
    report_light_subpaths("vcm");
}

/* Spectral BDPT and VCM through SF11 glass (scenes/prism.pbrt): camera subpaths and light
 * subpaths whose secondary wavelengths a dispersive refraction terminated add at the hero
 * wavelength alone (subpath_trace_camera's H, flags HERO and LIGHT_DISPERSED); the replay
 * keeps them apart and the sums are the camera sample and the film's value bit for bit,
 * with every MIS weight checked (explain_all). */
static void test_bidir_spectral(void **state)
{
    (void)state;
    static const char *const SCENE = CST_SOURCE_DIR "/scenes/prism.pbrt";
    static const int PIX[][2] = {{9, 10}, {10, 10}, {12, 10}, {14, 12}, {10, 16}};
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt(SCENE, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", SCENE, err.msg);
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    heroes = 0;
    radius = 0.2f; /* the prism is 1.6 units wide */
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    const int bdpt_heroes = heroes;
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_TENT, CST_COLOR_SPECTRAL) > 0);
    radius = 0.0f;
    pixels = NULL;
    print_message("prism: %d bdpt and %d vcm additions at the hero wavelength alone\n", bdpt_heroes,
                  heroes - bdpt_heroes);
    assert_true(bdpt_heroes > 0 && heroes > bdpt_heroes);
    cst_scene_destroy(s);
    /* Light subpaths dispersed by a glass sphere, connected to from the floor and the wall
     * (pixels where the pixel's own light subpath went through the sphere). */
    static const char *const CAUSTIC = CST_SOURCE_DIR "/tests/render/explain/dispersed-caustic.pbrt";
    static const int PIX2[][2] = {{2, 0}, {16, 1}, {1, 4}, {23, 5}, {17, 16}, {3, 17}};
    if (cst_scene_load_pbrt(CAUSTIC, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", CAUSTIC, err.msg);
    pixels = PIX2;
    num_pixels = sizeof PIX2 / sizeof PIX2[0];
    light_dispersed = 0;
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    pixels = NULL;
    print_message("dispersed caustic: %d connections and merges with dispersed light vertices\n", light_dispersed);
    assert_true(light_dispersed >= 4);
    cst_scene_destroy(s);
}

/* Photon mapping: the specular chain's emission, the direct light, the caustic map's and the
 * final gather's global-map estimates, each photon's f * power re-summed in the map's order
 * times the box kernel, give the camera sample and the film's value bit for bit; the
 * spheres' glass puts photons in the caustic map. */
static void test_photon(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    photons_gathered[0] = photons_gathered[1] = 0;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    cst_scene_destroy(s);
    s = load("cornell-spheres.json");
    static const int PIX[][2] = {{12, 10}, {3, 17}, {20, 2}, {8, 14}, {7, 15}, {16, 15}, {15, 16}};
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_MITCHELL, CST_COLOR_RGB) > 0);
    pixels = NULL;
    cst_scene_destroy(s);
    print_message("photon: %d caustic and %d global photons in nonzero estimates\n", photons_gathered[0],
                  photons_gathered[1]);
    assert_true(photons_gathered[0] > 0 && photons_gathered[1] > 100);
}

/* Photon mapping with a moving instance (Cammarano & Jensen's time windows, photon.c): every
 * estimate counts the photons of a window of 1/8 of the shutter around the camera path's
 * time, scaled by shutter / window; the kernel explain prints and re-sums with is that scaled
 * one, so the sum is the film's bit for bit (with 1 / (pi r^2) it is 8 times too small). */
static void test_photon_moving(void **state)
{
    (void)state;
    CstScene *s = load("../tests/render/explain/moving-box.json");
    windowed_estimates = windowed_photons = 0;
    photon_count = 20000;
    assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    cst_scene_destroy(s);
    print_message("photon, moving box: %d windowed estimates over %d photons\n", windowed_estimates,
                  windowed_photons);
    assert_true(windowed_estimates >= 10 && windowed_photons > 50);
}

/* Whitted's ray tree (mirror and glass branch in two) and the light tracer's splats: the
 * replayed sum is the film's value bit for bit (explain_all). */
static void test_whitted_light(void **state)
{
    (void)state;
    CstScene *s = load("cornell-spheres.json");
    assert_true(explain_all(s, CST_INTEGRATOR_WHITTED, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_WHITTED, CST_FILTER_MITCHELL, CST_COLOR_SPECTRAL) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_LIGHT, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    assert_true(explain_all(s, CST_INTEGRATOR_LIGHT, CST_FILTER_TENT, CST_COLOR_RGB) > 0);
    /* Under zsobol, whitted's pixel 12,1 sample 0 through Mitchell's negative lobe adds -0
     * to a zeroed sum, which holds +0: the replay is compared as the film adds it (it read
     * MISMATCH before). */
    CstRenderSettings st;
    settings(&st, CST_INTEGRATOR_WHITTED, CST_FILTER_MITCHELL, CST_COLOR_RGB);
    st.sampler = CST_SAMPLER_ZSOBOL;
    CstExplain *ex = NULL;
    CstError err;
    assert_int_equal(cst_explain(s, &st, 12, 1, 0, &ex, &err), CST_OK);
    assert_true(ex->exact);
    cst_explain_destroy(ex);
    cst_scene_destroy(s);
}

/* Samplers whose numbers depend on the render's spp (strata): the four samples explain
 * replays under --spp 4 add up, in order, to the pixel's sum in a 4-sample render. */
static void test_strata(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    static const CstSampler SAMPLERS[] = {CST_SAMPLER_STRATIFIED, CST_SAMPLER_SOBOL, CST_SAMPLER_ZSOBOL};
    for (size_t k = 0; k < sizeof SAMPLERS / sizeof SAMPLERS[0]; k++) {
        CstRenderSettings st;
        settings(&st, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB);
        st.sampler = SAMPLERS[k];
        double sum[3] = {0.0, 0.0, 0.0};
        for (int i = 0; i < st.spp; i++) {
            CstExplain *ex = NULL;
            assert_int_equal(cst_explain(s, &st, 9, 11, i, &ex, &err), CST_OK);
            assert_true(ex->exact);
            for (int c = 0; c < 3; c++) sum[c] += ex->camera_value[c];
            cst_explain_destroy(ex);
        }
        CstRenderSettings one = st;
        one.crop[0] = 9; one.crop[1] = 10; one.crop[2] = 11; one.crop[3] = 12;
        CstFilm *f = NULL;
        assert_int_equal(cst_render(s, &one, &f, NULL, &err), CST_OK);
        double mean[3];
        cst_film_pixel(f, 0, 0, mean);
        for (int c = 0; c < 3; c++) assert_true(mean[c] * 4.0 == sum[c]); /* x4: exact */
        cst_film_destroy(f);
    }
    cst_scene_destroy(s);
}

/* BDPT and VCM through media (subpath_media.c): the fog box with homogeneous fog, with a
 * random grid (delta tracking on the walks, ratio tracking on the connections, majorant-
 * based densities) and with that grid emitting (gathered by the camera walk, weight 1), in
 * RGB and spectral mode. Medium vertices, their free flights and VCM's merges at volume
 * vertices (UPBP's point-point 3D, normalised per lane) are recorded; the sums are the
 * camera sample and the film's value bit for bit, and every weight (volume merges, splats
 * and connections through media included) equals the one computed from all strategies'
 * densities of the path, phase functions and distance sampling included (explain_all). */
static void test_bidir_media(void **state)
{
    (void)state;
    static const int PIX[][2] = {{12, 10}, {10, 12}, {8, 9}, {14, 13}, {3, 17}};
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    medium_vertices = volume_merges = volume_merges_checked = media_flights = media_emissions = 0;
    light_medium_vertices = light_phases = light_medium_roulettes = camera_medium_roulettes = 0;
    merges = merges_checked = splats_checked = mis_checked = 0;
    mis_error = 0.0;
    for (int kind = 0; kind < 3; kind++) { /* homogeneous, grid, emitting grid */
        CstScene *s = fog_box(kind == 0 ? FOG_HOMOGENEOUS : kind == 1 ? FOG_GRID : FOG_GRID_EMISSIVE);
        assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, kind == 2 ? CST_COLOR_SPECTRAL : CST_COLOR_RGB) > 0);
        radius = 0.15f; /* the box is 2 units wide */
        assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_TENT, kind == 1 ? CST_COLOR_SPECTRAL : CST_COLOR_RGB) > 0);
        radius = 0.0f;
        cst_scene_destroy(s);
    }
    pixels = NULL;
    print_message("media: %d medium vertices, %d flights, %d emissions, %d merges (%d at volume vertices, %d of them "
                  "checked) recorded; %d strategies checked (%d splats), largest relative difference %.3g\n",
                  medium_vertices, media_flights, media_emissions, merges, volume_merges, volume_merges_checked,
                  mis_checked, splats_checked, mis_error);
    assert_true(medium_vertices > 0 && media_flights > 0 && media_emissions > 0);
    /* the pixels' light subpaths through the fog: medium vertices and phase-function samples */
    print_message("media: light subpaths: %d medium vertices, %d phase-function scatters; roulette at medium "
                  "vertices: %d on light subpaths, %d on camera subpaths\n", light_medium_vertices, light_phases,
                  light_medium_roulettes, camera_medium_roulettes);
    assert_true(light_medium_vertices >= 3 && light_phases >= 3);
    /* media_scatter_phase's roulette is listed on both subpaths, as subpath_scatter_rr's */
    assert_true(light_medium_roulettes > 0 && camera_medium_roulettes > 0);
    assert_true(volume_merges > 0 && volume_merges_checked == volume_merges && merges_checked == merges);
    assert_true(mis_checked >= 100 && splats_checked >= 20);
}

/* Photon mapping through media (photon.c's photon_li_media) on the fog box, homogeneous fog
 * and the random grid, RGB and spectral: the camera walk's flights and vertices (medium
 * vertices, surfaces through fog), NEE at each, the volume map's estimate at a medium vertex
 * (each photon's f_HG * power re-summed in the map's order, times the ball kernel, divided
 * by sigma_s per lane, times beta), the caustic map's at a surface and the final gather's
 * vertex (global map or, in fog, NEE and the volume map) give the camera sample and the
 * film's value bit for bit; and spectral photon on the Cornell box (no media): the
 * sample's wavelengths and photon set named, the sum converted at them. */
static void test_photon_in_media_spectral(void **state)
{
    (void)state;
    static const int PIX[][2] = {{12, 10}, {10, 12}, {8, 9}, {14, 13}, {3, 17}};
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    medium_vertices = media_flights = 0;
    volume_estimates = volume_photons = surface_estimates_in_fog = photon_sets_named = 0;
    photons_gathered[0] = photons_gathered[1] = 0;
    photon_count = 3000; /* volume and surface maps of ~2000 and ~5000 photons: enough to gather */
    radius = 0.2f;       /* the box is 2 units wide */
    for (int kind = 0; kind < 2; kind++) { /* homogeneous, grid */
        CstScene *s = fog_box(kind > 0 ? FOG_GRID : FOG_HOMOGENEOUS);
        assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
        if (kind == 0) assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_TENT, CST_COLOR_SPECTRAL) > 0);
        cst_scene_destroy(s);
    }
    const int named_in_fog = photon_sets_named;
    radius = 0.0f;
    pixels = NULL;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
    cst_scene_destroy(s);
    photon_count = 20000;
    print_message("photon in media: %d medium vertices, %d flights, %d volume estimates over %d photons, %d surface "
                  "estimates through fog; %d spectral samples named their photon set\n", medium_vertices,
                  media_flights, volume_estimates, volume_photons, surface_estimates_in_fog, photon_sets_named);
    assert_true(medium_vertices > 0 && media_flights > 0);
    assert_true(volume_estimates >= 5 && volume_photons >= 20 && surface_estimates_in_fog > 0);
    assert_true(named_in_fog == 10 && photon_sets_named == 20);
}

/* Photon mapping in emitting media (issue 27): the fog box with emitting fog and with the
 * emitting grid (RGB, and the fog spectral): the emission the camera walk and the final
 * gather pass (media_visible_point_rec's medium-emission events, weight 1, the throughput
 * in the value) and the volume and global maps with the photons that started in the media
 * sum to the camera sample and the film bit for bit. */
static void test_photon_emitting_media(void **state)
{
    (void)state;
    static const int PIX[][2] = {{12, 10}, {10, 12}, {8, 9}, {14, 13}, {3, 17}};
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    s0_emissions = 0;
    photon_count = 3000;
    radius = 0.2f;
    for (int kind = 0; kind < 2; kind++) {
        CstScene *s = fog_box(kind > 0 ? FOG_GRID_EMISSIVE : FOG_HOMOGENEOUS_EMISSIVE);
        assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
        if (kind == 0) assert_true(explain_all(s, CST_INTEGRATOR_PHOTON, CST_FILTER_BOX, CST_COLOR_SPECTRAL) > 0);
        cst_scene_destroy(s);
    }
    radius = 0.0f;
    pixels = NULL;
    photon_count = 20000;
    print_message("photon in emitting media: %d emissions of media recorded\n", s0_emissions);
    assert_true(s0_emissions > 0);
}

/* Subsurface materials under --subsurface walk (sss_walk.h: their media walked by
 * subpath_media.c): BDPT and VCM on the subsurface sphere. */
static void test_bidir_subsurface(void **state)
{
    (void)state;
    static const char *const SCENE = CST_SOURCE_DIR "/tests/render/subsurface/sss-walk.pbrt";
    static const int PIX[][2] = {{12, 10}, {11, 11}, {13, 9}, {12, 14}};
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt(SCENE, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", SCENE, err.msg);
    pixels = PIX;
    num_pixels = sizeof PIX / sizeof PIX[0];
    subsurface_walk = 1;
    medium_vertices = volume_merges = volume_merges_checked = merges = merges_checked = mis_checked = 0;
    mis_error = 0.0;
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    radius = 0.1f;
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    radius = 0.0f;
    print_message("subsurface walk: %d medium vertices, %d merges (%d at volume vertices) recorded; %d strategies "
                  "checked, largest relative difference %.3g\n", medium_vertices, merges, volume_merges, mis_checked,
                  mis_error);
    assert_true(medium_vertices > 0 && mis_checked >= 20 && merges_checked == merges);
    subsurface_walk = 0;
    pixels = NULL;
    cst_scene_destroy(s);
}

/* A moving camera (cst_scene_set_camera_motion, shutter [0.2, 0.7]): each path's camera
 * placed at its time, for the sums and for the explicit MIS weights (explain_mis.c). Left
 * unplaced, the explicit weights differ (measured: see the report of issue 30's helper). */
static void test_bidir_moving_camera(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    static const float c0[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    /* turned 10 degrees about the vertical and moved: the view axis changes with time, so
     * the camera's density of a direction (camera_pdf_w) depends on where the path put it */
    static const float c1[12] = {0.984808f, 0, 0.173648f, 60, 0, 1, 0, 25, -0.173648f, 0, 0.984808f, -40};
    assert_int_equal(cst_scene_set_camera_motion(s, c0, c1, &err), CST_OK);
    assert_int_equal(cst_scene_set_shutter(s, 0.2f, 0.7f, &err), CST_OK);
    mis_checked = splats_checked = merges = merges_checked = 0;
    mis_error = 0.0;
    assert_true(explain_all(s, CST_INTEGRATOR_BDPT, CST_FILTER_BOX, CST_COLOR_RGB) > 0);
    radius = 20.0f; /* the box is 555 units wide */
    assert_true(explain_all(s, CST_INTEGRATOR_VCM, CST_FILTER_TENT, CST_COLOR_RGB) > 0);
    radius = 0.0f;
    print_message("moving camera: %d strategies checked (%d splats, %d of %d merges), largest relative difference "
                  "%.3g\n", mis_checked, splats_checked, merges_checked, merges, mis_error);
    assert_true(mis_checked >= 50 && splats_checked >= 10 && merges_checked == merges && merges > 0);
    cst_scene_destroy(s);
}

static void test_refused(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    CstRenderSettings st;
    CstExplain *ex = NULL;
    /* Every integrator is explained (photon through media and in spectral mode too:
     * test_photon_in_media_spectral); bad pixels and samples are refused. */
    settings(&st, CST_INTEGRATOR_PATH, CST_FILTER_BOX, CST_COLOR_RGB);
    assert_int_equal(cst_explain(s, &st, W, 0, 0, &ex, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_explain(s, &st, 0, -1, 0, &ex, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_explain(s, &st, 0, 0, -1, &ex, &err), CST_ERR_INVALID_ARG);
    assert_null(ex);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_cornell),
        cmocka_unit_test(test_path_specular),
        cmocka_unit_test(test_path_media),
        cmocka_unit_test(test_path_subsurface),
        cmocka_unit_test(test_bdpt),
        cmocka_unit_test(test_whitted_light),
        cmocka_unit_test(test_vcm),
        cmocka_unit_test(test_bidir_spectral),
        cmocka_unit_test(test_bidir_media),
        cmocka_unit_test(test_bidir_subsurface),
        cmocka_unit_test(test_bidir_moving_camera),
        cmocka_unit_test(test_photon),
        cmocka_unit_test(test_photon_moving),
        cmocka_unit_test(test_photon_in_media_spectral),
        cmocka_unit_test(test_photon_emitting_media),
        cmocka_unit_test(test_strata),
        cmocka_unit_test(test_refused),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
