/* Heterogeneous media (src/media/hetero_medium.c, majorant.c): the majorant DDA visits
 * exactly the cells a segment crosses, in order, with their entry and exit t; the majorant
 * bounds the trilinear density; ratio tracking and delta tracking (with the balance
 * heuristic over chromatic lanes) estimate closed forms for a constant grid and for a
 * linear ramp (exact under trilinear interpolation): transmittance e^{-sigma_t tau}, the
 * scattering probability (sigma_s / sigma_t)(1 - T) and the emission (sigma_a / sigma_t)
 * Le (1 - T); distance samples of a grey ramp against their pdf (chi-square); scenes
 * reject bad grids. Fixed seeds, 4 standard errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "media/medium.h"
#include "media/medium_presets.h"
#include "scene/scene.h"
#include "unit/chi2.h"

/* ------------------------------------------------------------------ DDA */

/* Whether the segment o + t d, t in [t0, t1], overlaps cell c of g over a positive length
 * (brute force: the slab test on the cell's box), and where. */
static bool cell_overlap(const MajorantGrid *g, const int c[3], Vec3 o, Vec3 d, float t0, float t1, float *a,
                         float *b)
{
    Vec3 lo = v3((float)c[0] / (float)g->res[0], (float)c[1] / (float)g->res[1], (float)c[2] / (float)g->res[2]);
    Vec3 hi = v3((float)(c[0] + 1) / (float)g->res[0], (float)(c[1] + 1) / (float)g->res[1],
                 (float)(c[2] + 1) / (float)g->res[2]);
    return majorant_clip(o, d, lo, hi, t0, t1, a, b);
}

static void check_dda(const int res[3], uint64_t seed, int rays)
{
    MajorantGrid g = {{res[0], res[1], res[2]}, NULL};
    int cells = res[0] * res[1] * res[2];
    g.max = malloc((size_t)cells * sizeof(float));
    for (int i = 0; i < cells; i++) g.max[i] = (float)i;
    Pcg32 r;
    pcg32_seed_sample(&r, seed, 0, 0);
    char *seen = malloc((size_t)cells);
    int checked = 0;
    for (int k = 0; k < rays; k++) {
        /* Origins in and around the cube; some directions along an axis or a plane. */
        Vec3 o = v3(pcg32_float(&r) * 1.6f - 0.3f, pcg32_float(&r) * 1.6f - 0.3f, pcg32_float(&r) * 1.6f - 0.3f);
        Vec3 d = v3(pcg32_float(&r) - 0.5f, pcg32_float(&r) - 0.5f, pcg32_float(&r) - 0.5f);
        if (k % 7 == 1) d.x = 0.0f;
        if (k % 11 == 2) d.y = d.z = 0.0f;
        if (!(v3_length(d) > 1e-3f)) continue;
        d = v3_normalize(d);
        float tmax = pcg32_float(&r) < 0.5f ? INFINITY : pcg32_float(&r) * 2.0f;
        float t0, t1;
        if (!majorant_clip(o, d, v3s(0.0f), v3s(1.0f), 0.0f, tmax, &t0, &t1)) continue;
        memset(seen, 0, (size_t)cells);
        MajorantDda it;
        majorant_dda_init(&it, &g, o, d, t0, t1);
        MajorantSeg seg;
        float prev = t0;
        int n = 0;
        while (majorant_dda_next(&it, &seg)) {
            int idx = (seg.cell[2] * res[1] + seg.cell[1]) * res[0] + seg.cell[0];
            assert_true(seg.t0 == prev); /* contiguous */
            assert_true(seg.t1 >= seg.t0);
            assert_true(seg.maj == g.max[idx]);
            prev = seg.t1;
            seen[idx] = 1;
            n++;
            if (seg.t1 - seg.t0 > 1e-5f) {
                /* A visited cell of positive length is the cell the segment is in there. */
                float a, b;
                if (!cell_overlap(&g, seg.cell, o, d, t0, t1, &a, &b))
                    fail_msg("ray %d: cell (%d %d %d) visited over [%g, %g] but not crossed", k, seg.cell[0],
                             seg.cell[1], seg.cell[2], (double)seg.t0, (double)seg.t1);
                assert_true(fabsf(a - seg.t0) < 1e-4f && fabsf(b - seg.t1) < 1e-4f);
            }
        }
        assert_true(n > 0 && fabsf(prev - t1) < 1e-5f * fmaxf(1.0f, t1));
        /* Every cell crossed over a positive length was visited. */
        for (int z = 0; z < res[2]; z++)
            for (int y = 0; y < res[1]; y++)
                for (int x = 0; x < res[0]; x++) {
                    int c[3] = {x, y, z};
                    float a, b;
                    if (cell_overlap(&g, c, o, d, t0, t1, &a, &b) && b - a > 1e-4f && !seen[(z * res[1] + y) * res[0] + x])
                        fail_msg("ray %d: cell (%d %d %d) crossed over [%g, %g] but not visited", k, x, y, z,
                                 (double)a, (double)b);
                }
        checked++;
    }
    assert_true(checked > rays / 4);
    free(seen);
    free(g.max);
}

static void test_dda_cells(void **state)
{
    (void)state;
    const int cube[3] = {16, 16, 16}, odd[3] = {3, 5, 7}, one[3] = {1, 1, 1};
    check_dda(cube, 1, 4000);
    check_dda(odd, 2, 4000);
    check_dda(one, 3, 200);
}

/* ------------------------------------------------------------------ media */

/* A grid medium over the box [-1, 1]^3 with density f(x, y, z) at the sample centres. */
static Medium grid_medium(int n, float (*f)(Vec3), Color sigma_a, Color sigma_s, Color le)
{
    Medium m = {0};
    m.type = MEDIUM_GRID;
    HeteroMedium *h = &m.u.het;
    h->sigma_a = sigma_a;
    h->sigma_s = sigma_s;
    h->le = le;
    h->medium_from_world = transform_identity();
    h->p0 = v3s(-1.0f);
    h->p1 = v3s(1.0f);
    h->n[0] = h->n[1] = h->n[2] = n;
    h->le_scale_1 = 1.0f;
    h->density = malloc((size_t)n * (size_t)n * (size_t)n * sizeof(float));
    for (int z = 0; z < n; z++)
        for (int y = 0; y < n; y++)
            for (int x = 0; x < n; x++) {
                Vec3 p = v3(-1.0f + 2.0f * ((float)x + 0.5f) / (float)n, -1.0f + 2.0f * ((float)y + 0.5f) / (float)n,
                            -1.0f + 2.0f * ((float)z + 0.5f) / (float)n);
                h->density[(z * n + y) * n + x] = f(p);
            }
    assert_true(hetero_medium_prepare(h));
    return m;
}

static float constant_density(Vec3 p) { (void)p; return 0.7f; }
/* Linear in x: trilinear interpolation reproduces it exactly between the sample centres. */
static float ramp_density(Vec3 p) { return 0.2f + 0.9f * (p.x + 1.0f); }

/* A segment inside the region where both fields are exact (|coordinate| <= 1 - 1/n). */
static const Vec3 SEG_O = {-0.8f, -0.5f, 0.3f}, SEG_Q = {0.7f, 0.6f, -0.4f};

/* The integral of the density along SEG_O .. SEG_Q. */
static double optical_density(float (*f)(Vec3))
{
    double len = (double)v3_length(v3_sub(SEG_Q, SEG_O));
    Vec3 mid = v3_scale(v3_add(SEG_O, SEG_Q), 0.5f);
    return len * (double)f(mid); /* both are affine along the segment: exact at the midpoint */
}

/* Mean and standard error of each lane over `count` samples, added by stat_add. */
typedef struct LaneStat { double s[COLOR_LANES], s2[COLOR_LANES]; int count; } LaneStat;
static void stat_add(LaneStat *st, Color x)
{
    for (int c = 0; c < COLOR_LANES; c++) {
        st->s[c] += (double)x.c[c];
        st->s2[c] += (double)x.c[c] * (double)x.c[c];
    }
    st->count++;
}
static void stat_check(const LaneStat *st, const double want[COLOR_LANES], const char *what)
{
    for (int c = 0; c < COLOR_LANES; c++) {
        double n = (double)st->count, mean = st->s[c] / n;
        double se = sqrt(fmax(st->s2[c] / n - mean * mean, 0.0) / n);
        double z = (mean - want[c]) / fmax(se, 1e-12);
        print_message("%s lane %d: %.5f (se %.1e), expected %.5f, z %.2f\n", what, c, mean, se, want[c], z);
        if (!(fabs(mean - want[c]) <= 4.0 * se + 1e-6)) fail_msg("%s lane %d: z = %.2f", what, c, z);
    }
}

static void check_tracking(float (*f)(Vec3), int n, uint64_t seed, const char *what)
{
    /* Chromatic: lane 3 scatters nothing and absorbs little, lane 0 is dense. */
    const Color sa = {{0.5f, 0.1f, 0.3f, 0.05f}}, ss = {{1.5f, 0.4f, 1.0f, 0.0f}}, le = {{1.0f, 2.0f, 0.5f, 3.0f}};
    Medium m = grid_medium(n, f, sa, ss, le);
    MediumCoeffs mc = {0};
    mc.sigma_a = sa;
    mc.sigma_s = ss;
    mc.sigma_t = color_add(sa, ss);
    mc.le = le;
    mc.emissive = true;
    const double tau = optical_density(f);
    Vec3 dir = v3_normalize(v3_sub(SEG_Q, SEG_O));
    float len = v3_length(v3_sub(SEG_Q, SEG_O));
    double T[COLOR_LANES], scat[COLOR_LANES], emit[COLOR_LANES];
    for (int c = 0; c < COLOR_LANES; c++) {
        double st = (double)mc.sigma_t.c[c];
        T[c] = exp(-st * tau);
        scat[c] = st > 0.0 ? (double)ss.c[c] / st * (1.0 - T[c]) : 0.0;
        emit[c] = st > 0.0 ? (double)sa.c[c] / st * (double)le.c[c] * (1.0 - T[c]) : 0.0;
    }
    LaneStat rt = {0}, pass = {0}, sc = {0}, em = {0};
    Pcg32 r;
    pcg32_seed_sample(&r, seed, 0, 0);
    const int N = 200000;
    for (int i = 0; i < N; i++) {
        uint64_t s64 = ((uint64_t)pcg32_next(&r) << 32) | pcg32_next(&r);
        stat_add(&rt, hetero_transmittance(&m.u.het, &mc, SEG_O, dir, len, s64));
        MediumSample ms;
        int hero = (int)(pcg32_float(&r) * (float)COLOR_LANES);
        hetero_sample_distance(&m.u.het, &mc, SEG_O, dir, len, hero, color_s(1.0f), pcg32_float(&r), &ms);
        /* A one-segment path: f / p_hero / mean(p_c / p_hero), the balance heuristic. */
        Color w = color_scale(ms.weight, (float)COLOR_LANES / (ms.r.c[0] + ms.r.c[1] + ms.r.c[2] + ms.r.c[3]));
        stat_add(&pass, ms.scattered ? color_s(0.0f) : w);
        stat_add(&sc, ms.scattered ? w : color_s(0.0f));
        stat_add(&em, ms.le);
    }
    char name[96];
    snprintf(name, sizeof name, "%s: ratio tracking T", what);
    stat_check(&rt, T, name);
    snprintf(name, sizeof name, "%s: delta tracking, passing weight (T)", what);
    stat_check(&pass, T, name);
    snprintf(name, sizeof name, "%s: delta tracking, scattering weight", what);
    stat_check(&sc, scat, name);
    snprintf(name, sizeof name, "%s: delta tracking, emission", what);
    stat_check(&em, emit, name);
    medium_release(&m);
}

static void test_tracking_constant(void **state)
{
    (void)state;
    check_tracking(constant_density, 8, 11, "constant grid");
}

static void test_tracking_ramp(void **state)
{
    (void)state;
    check_tracking(ramp_density, 8, 12, "linear ramp");
}

/* The majorant bounds the trilinear density at random points of each cell. */
static void test_majorant_bounds(void **state)
{
    (void)state;
    Pcg32 r;
    pcg32_seed_sample(&r, 5, 0, 0);
    Medium m = grid_medium(5, constant_density, color_s(1.0f), color_s(1.0f), color_s(0.0f));
    HeteroMedium *h = &m.u.het;
    for (int i = 0; i < 125; i++) h->density[i] = pcg32_float(&r) * 3.0f;
    assert_true(hetero_medium_prepare(h));
    for (int k = 0; k < 200000; k++) {
        Vec3 u = v3(pcg32_float(&r), pcg32_float(&r), pcg32_float(&r));
        int c[3] = {(int)(u.x * 16.0f), (int)(u.y * 16.0f), (int)(u.z * 16.0f)};
        float d = hetero_grid_lookup(h->density, h->n, u);
        float mx = h->maj.max[(c[2] * 16 + c[1]) * 16 + c[0]];
        if (!(d <= mx * (1.0f + 1e-6f))) fail_msg("density %g above the majorant %g", (double)d, (double)mx);
    }
    medium_release(&m);
}

/* Delta tracking in a grey ramp: scattering distances follow sigma_t(t) T(t) (chi-square,
 * 40 bins over the segment plus one for passing). */
static void test_delta_tracking_chi2(void **state)
{
    (void)state;
    const Color sa = color_s(0.3f), ss = color_s(0.9f);
    Medium m = grid_medium(8, ramp_density, sa, ss, color_s(0.0f));
    MediumCoeffs mc = medium_coeffs(&m, NULL);
    Vec3 dir = v3_normalize(v3_sub(SEG_Q, SEG_O));
    float len = v3_length(v3_sub(SEG_Q, SEG_O));
    enum { BINS = 40, N = 400000 };
    double obs[BINS + 1] = {0}, expd[BINS + 1];
    const double st = 1.2;
    /* Optical depth at t: the density is affine along the segment. */
    double d0 = (double)ramp_density(SEG_O), d1 = (double)ramp_density(SEG_Q);
    double prevT = 1.0;
    for (int b = 0; b < BINS; b++) {
        double t = (double)len * (b + 1) / BINS;
        double s = t / (double)len;
        double tau = t * (d0 + 0.5 * (d1 - d0) * s);
        double T = exp(-st * tau);
        expd[b] = N * (prevT - T);
        prevT = T;
    }
    expd[BINS] = N * prevT;
    Pcg32 r;
    pcg32_seed_sample(&r, 21, 0, 0);
    for (int i = 0; i < N; i++) {
        MediumSample ms;
        hetero_sample_distance(&m.u.het, &mc, SEG_O, dir, len, (int)(pcg32_float(&r) * 4.0f), color_s(1.0f),
                               pcg32_float(&r), &ms);
        if (ms.scattered) {
            int b = (int)(ms.t / len * BINS);
            obs[b < BINS ? b : BINS - 1] += 1.0;
            assert_true(fabsf(ms.weight.c[0] - 0.75f) < 1e-5f); /* grey: the albedo */
        } else {
            obs[BINS] += 1.0;
            assert_true(fabsf(ms.weight.c[0] - 1.0f) < 1e-5f);
        }
    }
    int dof;
    double stat, outside = 0.0;
    double p = chi2_pvalue(obs, expd, BINS + 1, &dof, &stat, &outside);
    print_message("delta tracking distances: p = %.4f (%d dof)\n", p, dof);
    assert_true(p > 0.01);
    medium_release(&m);
}

/* A ray that misses the box, or a medium that is empty there: weight 1, nothing added. */
static void test_miss_and_empty(void **state)
{
    (void)state;
    Medium m = grid_medium(4, constant_density, color_s(1.0f), color_s(1.0f), color_s(0.0f));
    MediumCoeffs mc = medium_coeffs(&m, NULL);
    MediumSample ms;
    hetero_sample_distance(&m.u.het, &mc, v3(0, 5, 0), v3(1, 0, 0), INFINITY, 1, color_s(1.0f), 0.5f, &ms);
    assert_false(ms.scattered);
    assert_true(ms.weight.c[0] == 1.0f && ms.weight.c[3] == 1.0f);
    Color tr = hetero_transmittance(&m.u.het, &mc, v3(0, 5, 0), v3(1, 0, 0), 10.0f, 1);
    assert_true(tr.c[0] == 1.0f);
    medium_release(&m);
}

/* The scene validates grids: negative or non-finite densities, an empty box. */
static void test_scene_rejects(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    Medium m = grid_medium(2, constant_density, color_s(1.0f), color_s(1.0f), color_s(0.0f));
    int id;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_OK);
    m.u.het.density[3] = -1.0f;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_ERR_INVALID_ARG);
    m.u.het.density[3] = NAN;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_ERR_INVALID_ARG);
    m.u.het.density[3] = 1.0f;
    m.u.het.p1.y = -1.0f;
    assert_int_equal(scene_add_medium(s, &m, &id, &err), CST_ERR_INVALID_ARG);
    medium_release(&m);
    scene_destroy(s);
}

static void test_presets(void **state)
{
    (void)state;
    Color sa, ss;
    assert_true(medium_preset("Wholemilk", &sa, &ss));
    assert_true(ss.c[0] == 2.55f && sa.c[2] == 0.014f);
    assert_true(medium_preset("Pacific Ocean Surface Water", &sa, &ss));
    assert_false(medium_preset("wholemilk", &sa, &ss)); /* exact names, as pbrt-v4 */
    assert_int_equal(medium_preset_count(), 47);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_dda_cells),
        cmocka_unit_test(test_majorant_bounds),
        cmocka_unit_test(test_tracking_constant),
        cmocka_unit_test(test_tracking_ramp),
        cmocka_unit_test(test_delta_tracking_chi2),
        cmocka_unit_test(test_miss_and_empty),
        cmocka_unit_test(test_scene_rejects),
        cmocka_unit_test(test_presets),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
