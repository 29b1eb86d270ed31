/* caustic explain names the lobe of every scatter (issue 30): on a box with a glass sphere,
 * a smooth-coated diffuse sphere, a rough plastic one and diffuse walls, every SCATTER event
 * of the path tracer, BDPT's camera subpaths, whitted's branches and photon's camera walk
 * (and SPPM's camera chain, photon's final gather) has a lobe; it is one the vertex's
 * material has; reflection lobes leave wi on wo's side
 * of the geometric normal and transmission lobes on the other; and over the image each
 * material shows each of its lobes. The back wall is a mix of the white diffuse and the coated
 * material: at its vertices the lobe must be one of the material the mix chose there, as
 * explain reports it (both choices are seen). A smooth coat's "coat specular reflection" is
 * the mirror direction of wo and "base diffuse reflection" never is; lobes2.json adds hair,
 * rough dielectric and diffuse transmission. NEE events say when the shadow ray was blocked
 * (OCCLUDED, adding exactly 0): volpath's at medium vertices in the fog box, at subsurface
 * exits under a blocker (sss-occluder.json), whitted's shadow rays. */
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

enum { W = 24, H = 20, DMAX = 64 };

/* The pinhole of lobes.json and of the fog box. */
static const double CAM[3] = {278.0, 273.0, -800.0};

/* Lobe names counted over the image, per integrator (the order of LOBES). */
static const char *const LOBES[] = {"diffuse reflection",       "specular reflection",      "specular transmission",
                                    "coat specular reflection", "base diffuse reflection",  "coat glossy reflection",
                                    "delta split",              "glossy reflection",        "glossy transmission",
                                    "diffuse transmission",     "hair R",                   "hair TT",
                                    "hair TRT",                 "hair residual"};
enum { NLOBES = sizeof LOBES / sizeof LOBES[0] };

/* The lobes a material type (recorder.c's names) may report. */
static bool lobe_allowed(const char *type, const char *lobe)
{
    if (!strcmp(type, "diffuse")) return !strcmp(lobe, "diffuse reflection");
    if (!strcmp(type, "glass")) return !strcmp(lobe, "specular reflection") || !strcmp(lobe, "specular transmission");
    if (!strcmp(type, "coateddiffuse"))
        return !strcmp(lobe, "coat specular reflection") || !strcmp(lobe, "base diffuse reflection") ||
               !strcmp(lobe, "delta split");
    if (!strcmp(type, "plastic"))
        return !strcmp(lobe, "coat glossy reflection") || !strcmp(lobe, "base diffuse reflection");
    if (!strcmp(type, "dielectric")) /* rough: GGX reflection or transmission */
        return !strcmp(lobe, "glossy reflection") || !strcmp(lobe, "glossy transmission");
    if (!strcmp(type, "diffusetransmission"))
        return !strcmp(lobe, "diffuse reflection") || !strcmp(lobe, "diffuse transmission");
    if (!strcmp(type, "hair")) return !strncmp(lobe, "hair ", 5);
    return false;
}

static bool is_transmission(const char *lobe) { return strstr(lobe, "transmission") != NULL; }

static double dot3(const float a[3], const double b[3])
{
    return (double)a[0] * b[0] + (double)a[1] * b[1] + (double)a[2] * b[2];
}

/* The settings every explain of this file uses: W x H, 2 samples, one thread, seed 7. */
static CstRenderSettings explain_settings(CstIntegrator integ)
{
    CstRenderSettings st;
    memset(&st, 0, sizeof st);
    st.integrator = integ;
    st.width = W;
    st.height = H;
    st.spp = 2;
    st.threads = 1;
    st.seed = 7;
    st.seed_set = 1;
    st.sampler = CST_SAMPLER_INDEPENDENT;
    return st;
}

static int mix_seen[2]; /* back-wall vertices where the mix chose diffuse, coateddiffuse */
static int shadow_checked; /* whitted: direct-light sums checked against their shadow rays */
static int shadow_occluded, shadow_lit; /* whitted: shadow rays flagged OCCLUDED, and adding light */

/* Coat against base (the coated materials at a smooth interface): a "coat specular
 * reflection" is the mirror direction of wo about the shading normal n, wi = 2 (n.wo) n - wo
 * (to float rounding: 1e-4 allows wo's own, from float positions); a "base diffuse
 * reflection" went through the interface and a Lambertian base, and is never that
 * direction (1e-3: a cosine sample falls within it with probability about 3e-7). Were the
 * two names swapped, both would fail. */
static int coat_checked, base_checked;

static void check_coat(const CstExplainEvent *v, const CstExplainEvent *e, const double wo[3])
{
    const bool coat = !strcmp(e->lobe, "coat specular reflection");
    if (!coat && strcmp(e->lobe, "base diffuse reflection")) return;
    const double nw = dot3(v->n, wo);
    double dev = 0.0;
    for (int c = 0; c < 3; c++) {
        const double m = 2.0 * nw * (double)v->n[c] - wo[c];
        dev = fmax(dev, fabs(m - (double)e->wi[c]));
    }
    if (coat ? dev > 1e-4 : dev < 1e-3)
        fail_msg("\"%s\" at a %s vertex: wi is %.3g from the mirror direction of wo", e->lobe, v->material_type,
                 dev);
    coat_checked += coat;
    base_checked += !coat;
}

/* Explains samples 0 and 1 of every step-th pixel across and down; counts[k] the SCATTER events of lobe LOBES[k].
 * Returns the number of SCATTER events whose geometry was checked. */
static int explain_image(const CstScene *s, CstIntegrator integ, int step, int counts[NLOBES])
{
    CstRenderSettings st = explain_settings(integ);
    st.photons = 2000;
    const double *cam = CAM;
    int checked = 0;
    for (int y = 0; y < H; y += step) {
        for (int x = 0; x < W; x += step) {
            for (int sample = 0; sample < 2; sample++) {
                CstExplain *ex = NULL;
                CstError err;
                assert_int_equal(cst_explain(s, &st, x, y, sample, &ex, &err), CST_OK);
                assert_int_equal(ex->integrator, integ);
                /* per camera depth: the last vertex recorded, the direction toward the
                 * previous vertex (the camera at the first hit, else back along the
                 * scatter that reached it: whitted's tree too) and the last scatter's wi */
                const CstExplainEvent *vd[DMAX + 1] = {NULL};
                double wo[DMAX + 1][3], wi_prev[DMAX + 1][3];
                double shadow[3] = {0.0, 0.0, 0.0}; /* whitted: the shadow rays' shares so far */
                int rays = 0;
                for (int i = 0; i < ex->num_events; i++) {
                    const CstExplainEvent *e = &ex->events[i];
                    if (e->flags & CST_EXPLAIN_IN_SPLAT) continue;
                    const int d = e->depth;
                    if (integ == CST_INTEGRATOR_WHITTED && e->kind == CST_EXPLAIN_NEE) {
                        /* each shadow ray's event (not ADDED), then their mean (ADDED), which
                         * is their shares' sum up to rounding */
                        if (!(e->flags & CST_EXPLAIN_ADDED)) {
                            for (int c = 0; c < 3; c++) shadow[c] += (double)e->value[c];
                            rays++;
                            /* a blocked shadow ray adds exactly 0 */
                            const bool lit = e->value[0] != 0.0f || e->value[1] != 0.0f || e->value[2] != 0.0f;
                            if ((e->flags & CST_EXPLAIN_OCCLUDED) && lit)
                                fail_msg("whitted pixel %d,%d: an occluded shadow ray adds %.9g", x, y,
                                         (double)e->value[0]);
                            shadow_occluded += (e->flags & CST_EXPLAIN_OCCLUDED) != 0;
                            shadow_lit += lit;
                            continue;
                        }
                        assert_true(rays >= 1);
                        for (int c = 0; c < 3; c++)
                            if (fabs(shadow[c] - (double)e->value[c]) > 1e-5 * fabs((double)e->value[c]) + 1e-12)
                                fail_msg("whitted pixel %d,%d: shadow rays sum to %.9g, the mean is %.9g", x, y,
                                         shadow[c], (double)e->value[c]);
                        shadow_checked++;
                        rays = 0;
                        shadow[0] = shadow[1] = shadow[2] = 0.0;
                    }
                    if (e->kind == CST_EXPLAIN_VERTEX && d >= 1 && d <= DMAX) {
                        if (d == 1) {
                            double dir[3], l = 0.0;
                            for (int c = 0; c < 3; c++) {
                                dir[c] = cam[c] - (double)e->p[c];
                                l += dir[c] * dir[c];
                            }
                            for (int c = 0; c < 3; c++) wo[1][c] = dir[c] / sqrt(l);
                        } else {
                            for (int c = 0; c < 3; c++) wo[d][c] = -wi_prev[d - 1][c];
                        }
                        vd[d] = e;
                        if (!strcmp(e->material_type, "mix")) {
                            if (!e->mix_material_type) fail_msg("a vertex of the mix without the mix's choice");
                            mix_seen[!strcmp(e->mix_material_type, "coateddiffuse")]++;
                        }
                    }
                    if (e->kind != CST_EXPLAIN_SCATTER) continue;
                    if (!e->lobe) fail_msg("%s pixel %d,%d sample %d: a SCATTER event without a lobe",
                                           cst_integrator_name(integ), x, y, sample);
                    for (int k = 0; k < NLOBES; k++) counts[k] += !strcmp(e->lobe, LOBES[k]);
                    if (d < 1 || d > DMAX || !vd[d] || !vd[d]->material_type || !strcmp(e->lobe, "delta split"))
                        continue;
                    const CstExplainEvent *v = vd[d];
                    const char *type = v->mix_material_type ? v->mix_material_type : v->material_type;
                    if (!lobe_allowed(type, e->lobe))
                        fail_msg("%s pixel %d,%d: lobe \"%s\" at a %s vertex", cst_integrator_name(integ), x, y,
                                 e->lobe, type);
                    for (int c = 0; c < 3; c++) wi_prev[d][c] = (double)e->wi[c];
                    check_coat(v, e, wo[d]);
                    /* hair: R, TT, TRT are the fibre's, not the sphere's sides */
                    if (!strcmp(type, "hair")) continue;
                    const double co = dot3(v->ng, wo[d]), ci = dot3(v->ng, wi_prev[d]);
                    if (co * ci == 0.0) continue;
                    if ((co * ci < 0.0) != is_transmission(e->lobe))
                        fail_msg("%s pixel %d,%d sample %d depth %d: lobe \"%s\" at a %s vertex but wo.ng %.4g, "
                                 "wi.ng %.4g", cst_integrator_name(integ), x, y, sample, d, e->lobe,
                                 v->material_type, co, ci);
                    checked++;
                }
                cst_explain_destroy(ex);
            }
        }
    }
    return checked;
}

static CstScene *load_lobes(void)
{
    CstScene *s = NULL;
    CstError err;
    const char *path = CST_SOURCE_DIR "/tests/render/explain/lobes.json";
    if (cst_scene_load_json(path, &s, &err) != CST_OK) fail_msg("%s: %s", path, err.msg);
    return s;
}

static void report(const char *name, const int counts[NLOBES], int checked)
{
    print_message("%s: %d scatters checked against ng;", name, checked);
    for (int k = 0; k < NLOBES; k++) print_message(" %s %d%s", LOBES[k], counts[k], k + 1 < NLOBES ? "," : "\n");
}

/* The path tracer (MIS): every lobe of the scene appears over the image; BDPT's camera
 * subpaths on every other pixel (its lobes come from the same sampling routines). */
static void test_path_bdpt_lobes(void **state)
{
    (void)state;
    CstScene *s = load_lobes();
    int counts[NLOBES] = {0};
    mix_seen[0] = mix_seen[1] = 0;
    int checked = explain_image(s, CST_INTEGRATOR_PATH, 1, counts);
    report("path", counts, checked);
    print_message("path: the back wall's mix chose diffuse at %d vertices, coateddiffuse at %d\n", mix_seen[0],
                  mix_seen[1]);
    print_message("path: %d coat specular reflections at the mirror direction, %d base diffuse ones off it\n",
                  coat_checked, base_checked);
    assert_true(checked > 500 && mix_seen[0] > 0 && mix_seen[1] > 0 && coat_checked >= 10 && base_checked > 50);
    for (int l = 0; l < 6; l++)
        if (counts[l] == 0) fail_msg("path: no \"%s\" scatter over the image", LOBES[l]);
    memset(counts, 0, sizeof counts);
    checked = explain_image(s, CST_INTEGRATOR_BDPT, 2, counts);
    report("bdpt", counts, checked);
    assert_true(checked > 100 && counts[0] > 0 && counts[2] > 0 && counts[4] > 0);
    cst_scene_destroy(s);
}

/* The materials lobes.json has not (issue 30): hair (R, TT, TRT, the residual: the lobes
 * Chiang et al. 2016's sampling picks by their attenuations), rough dielectric (glossy
 * reflection on wo's side of ng, glossy transmission on the other), diffuse transmission
 * (likewise); each one seen over the image, under the path tracer and BDPT's camera
 * subpaths. The measured material needs an RGL .bsdf file, which neither the repository
 * nor ../shared holds: not covered here (tests/unit/test_measured.c checks its sampling). */
static void test_more_lobes(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    const char *path = CST_SOURCE_DIR "/tests/render/explain/lobes2.json";
    if (cst_scene_load_json(path, &s, &err) != CST_OK) fail_msg("%s: %s", path, err.msg);
    int counts[NLOBES] = {0};
    int checked = explain_image(s, CST_INTEGRATOR_PATH, 1, counts);
    report("path (lobes2)", counts, checked);
    assert_true(checked > 300);
    for (int l = 7; l < NLOBES; l++)
        if (counts[l] == 0) fail_msg("path: no \"%s\" scatter over lobes2.json", LOBES[l]);
    memset(counts, 0, sizeof counts);
    checked = explain_image(s, CST_INTEGRATOR_BDPT, 2, counts);
    report("bdpt (lobes2)", counts, checked);
    assert_true(checked > 50 && counts[8] > 0 && counts[9] > 0 && counts[10] > 0);
    cst_scene_destroy(s);
}

/* Whitted's branches (glass: both lobes; the coat's mirror); SPPM's camera chain through
 * the delta lobes (the glass, the coat's mirror and the delta split at the coat); photon's
 * final gather and its camera chain (photon_trace_to_diffuse's delta lobes and splits).
 * Whitted's direct light: one event per shadow ray (not summed) before their mean. */
static void test_whitted_sppm_photon_lobes(void **state)
{
    (void)state;
    CstScene *s = load_lobes();
    int counts[NLOBES] = {0};
    int checked = explain_image(s, CST_INTEGRATOR_WHITTED, 1, counts);
    report("whitted", counts, checked);
    print_message("whitted: %d direct-light means checked against their shadow rays' events\n", shadow_checked);
    print_message("whitted: %d shadow rays occluded, %d lit\n", shadow_occluded, shadow_lit);
    assert_true(shadow_checked > 100 && shadow_occluded > 10 && shadow_lit > 10);
    assert_true(checked > 100 && counts[1] > 0 && counts[2] > 0 && counts[3] > 0);
    memset(counts, 0, sizeof counts);
    checked = explain_image(s, CST_INTEGRATOR_SPPM, 2, counts);
    report("sppm", counts, checked);
    assert_true(checked > 10 && counts[1] > 0 && counts[2] > 0 && counts[3] > 0 && counts[6] > 0);
    memset(counts, 0, sizeof counts);
    checked = explain_image(s, CST_INTEGRATOR_PHOTON, 2, counts);
    report("photon", counts, checked);
    /* its camera chain itemised too: the glass's and the coat's delta lobes, the split */
    assert_true(checked > 50 && counts[0] > 0 && counts[4] > 0 && counts[1] > 0 && counts[2] > 0 && counts[6] > 0);
    cst_scene_destroy(s);
}

/* Both pdfs of volpath's and path_sss.c's NEE (issue 30): at every medium vertex of the
 * fog box and every subsurface exit, the NEE event names the light point (p, its normal
 * in ng), pdf_w > 0, pdf_a = pdf_w |cos_light| / d^2 from the vertex to that point (wi
 * pointing at it; area lights: lights at infinity have no pdf_a), the pick's pmf in (0, 1], the partner's pdf_w (fog: Henyey-Greenstein
 * with g = 0.4 of wo.wi, wo toward the previous vertex; exit: max(0, ns.wi) / pi) and the power-heuristic weight of the two. Returns the events checked. */
static int area_checked; /* of the events check_nee_pdfs checked, those at area lights */
static int nee_occluded, nee_lit; /* of them, flagged OCCLUDED, and adding light */

static int check_nee_pdfs(const CstScene *s, CstIntegrator integ, const char *vertex_type, int step, double g)
{
    CstRenderSettings st = explain_settings(integ);
    const double pi = 3.14159265358979323846;
    int checked = 0;
    for (int y = 0; y < H; y += step) {
        for (int x = 0; x < W; x += step) {
            for (int sample = 0; sample < 2; sample++) {
                CstExplain *ex = NULL;
                CstError err;
                assert_int_equal(cst_explain(s, &st, x, y, sample, &ex, &err), CST_OK);
                assert_true(ex->exact);
                const CstExplainEvent *v = NULL;
                double prev[3] = {0.0, 0.0, 0.0}; /* the vertex before v (the camera before the first) */
                for (int i = 0; i < ex->num_events; i++) {
                    const CstExplainEvent *e = &ex->events[i];
                    if (e->kind == CST_EXPLAIN_VERTEX) {
                        for (int c = 0; c < 3; c++) prev[c] = e->depth == 1 ? CAM[c] : v ? (double)v->p[c] : 0.0;
                        v = e;
                    }
                    if (e->kind != CST_EXPLAIN_NEE || !v || !v->material_type || strcmp(v->material_type, vertex_type))
                        continue;
                    if (e->light < 0) continue; /* no light sampled */
                    /* OCCLUDED: the shadow ray was blocked (volpath: its transmittance 0), and the
                     * event adds exactly 0. In the fog every point lies below the one-sided
                     * light, the phase function is never 0 and the fog's transmittance never
                     * is: a medium vertex's NEE adds 0 exactly when it is occluded. */
                    const bool lit = e->contribution[0] != 0.0f || e->contribution[1] != 0.0f ||
                                     e->contribution[2] != 0.0f;
                    const bool occluded = (e->flags & CST_EXPLAIN_OCCLUDED) != 0;
                    if ((occluded && lit) || (g >= 0.0 && occluded == lit))
                        fail_msg("%s pixel %d,%d sample %d: NEE at a %s vertex %s OCCLUDED adds %.9g",
                                 cst_integrator_name(integ), x, y, sample, vertex_type, occluded ? "flagged" : "not",
                                 (double)e->contribution[0]);
                    if (g >= 0.0 && !occluded && !(e->transmittance[0] > 0.0f && e->transmittance[0] <= 1.0f))
                        fail_msg("fog: NEE's shadow-ray transmittance %.6g", (double)e->transmittance[0]);
                    nee_occluded += occluded;
                    nee_lit += lit;
                    if (e->flags & CST_EXPLAIN_DELTA) { /* a delta light: its pmf, no MIS partner */
                        assert_true(e->pmf > 0.0f && e->pmf <= 1.0f && e->pdf_w == 0.0f && e->mis_weight == 1.0f);
                        checked++;
                        continue;
                    }
                    double d[3], d2 = 0.0, cos_l = 0.0, dot_wi = 0.0;
                    for (int c = 0; c < 3; c++) {
                        d[c] = (double)e->p[c] - (double)v->p[c];
                        d2 += d[c] * d[c];
                    }
                    for (int c = 0; c < 3; c++) {
                        cos_l += (double)e->ng[c] * (double)e->wi[c];
                        dot_wi += d[c] / sqrt(d2) * (double)e->wi[c];
                    }
                    const double pw = (double)e->pdf_w, pa = pw * fabs(cos_l) / d2;
                    /* pdf_a 0: a light at infinity (the environment, a distant light), no area measure */
                    if (e->pdf_a != 0.0f) area_checked++;
                    if (!(pw > 0.0) || (e->pdf_a != 0.0f && (fabs((double)e->pdf_a - pa) > 1e-4 * pa || dot_wi < 1.0 - 1e-5)))
                        fail_msg("%s pixel %d,%d: NEE at a %s vertex: pdf_w %.6g, pdf_a %.6g but pdf_w |cos| / d^2 = "
                                 "%.6g (cos %.4g, d %.6g, wi.dir %.7f)", cst_integrator_name(integ), x, y, vertex_type,
                                 pw, (double)e->pdf_a, pa, cos_l, sqrt(d2), dot_wi);
                    assert_true(e->pmf > 0.0f && e->pmf <= 1.0f);
                    const double po = (double)e->pdf_other_w;
                    const double lo = g >= 0.0 ? (1.0 - g) / (4.0 * pi * (1.0 + g) * (1.0 + g)) : 0.0;
                    const double hi = g >= 0.0 ? (1.0 + g) / (4.0 * pi * (1.0 - g) * (1.0 - g)) : 1.0 / pi;
                    if (!(po >= lo * (1.0 - 1e-5) && po <= hi * (1.0 + 1e-5)))
                        fail_msg("%s: partner pdf_w %.6g outside [%.6g, %.6g]", vertex_type, po, lo, hi);
                    /* the partner itself: HG(wo.wi) with wo toward the previous vertex in a
                     * medium (pbrt-v4's argument), max(0, ns.wi) / pi at a subsurface exit */
                    double want = -1.0;
                    if (g >= 0.0) {
                        double wo[3], l = 0.0, mu = 0.0;
                        for (int c = 0; c < 3; c++) {
                            wo[c] = prev[c] - (double)v->p[c];
                            l += wo[c] * wo[c];
                        }
                        for (int c = 0; c < 3; c++) mu += wo[c] / sqrt(l) * (double)e->wi[c];
                        const double den = 1.0 + g * g + 2.0 * g * mu;
                        want = (1.0 - g * g) / (4.0 * pi * den * sqrt(den));
                    } else if (!strcmp(vertex_type, "subsurface exit")) {
                        want = fmax(0.0, dot3(v->n, (const double[3]){e->wi[0], e->wi[1], e->wi[2]})) / pi;
                    }
                    if (want >= 0.0 && fabs(po - want) > 1e-3 * want + 1e-7)
                        fail_msg("%s pixel %d,%d: partner pdf_w %.7g, expected %.7g", vertex_type, x, y, po, want);
                    const double w = pw * pw / (pw * pw + po * po);
                    assert_true(fabs((double)e->mis_weight - w) <= 1e-5);
                    checked++;
                }
                cst_explain_destroy(ex);
            }
        }
    }
    return checked;
}

static void test_nee_pdfs_media_sss(void **state)
{
    (void)state;
    static const char *const FOG = CST_SOURCE_DIR "/tests/render/media/cornell-fog.pbrt";
    static const char *const SSS = CST_SOURCE_DIR "/tests/render/subsurface/sss-spheres.pbrt";
    static const char *const OCC = CST_SOURCE_DIR "/tests/render/explain/sss-occluder.json";
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_pbrt(FOG, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", FOG, err.msg);
    area_checked = nee_occluded = nee_lit = 0;
    int n = check_nee_pdfs(s, CST_INTEGRATOR_PATH, "medium", 2, 0.4);
    const int n_area = area_checked;
    print_message("fog: %d NEE events at medium vertices checked (%d pdf_a; %d occluded, %d lit)\n", n, n_area,
                  nee_occluded, nee_lit);
    assert_true(n > 50 && n_area == n && nee_occluded > 5 && nee_lit > 5);
    nee_occluded = nee_lit = 0;
    int n_surface = check_nee_pdfs(s, CST_INTEGRATOR_PATH, "diffuse", 4, -1.0);
    print_message("fog: %d NEE events at surfaces (%d occluded, %d lit)\n", n_surface, nee_occluded, nee_lit);
    assert_true(n_surface > 10 && nee_occluded > 0 && nee_lit > 0);
    cst_scene_destroy(s);
    if (cst_scene_load_pbrt(SSS, NULL, &s, &err) != CST_OK) fail_msg("%s: %s", SSS, err.msg);
    n = check_nee_pdfs(s, CST_INTEGRATOR_PATH, "subsurface exit", 2, -1.0);
    print_message("subsurface: %d NEE events at exits checked\n", n);
    assert_true(n > 10);
    cst_scene_destroy(s);
    /* OCCLUDED at subsurface exits: a sphere under a quad light half hidden by a blocker */
    if (cst_scene_load_json(OCC, &s, &err) != CST_OK) fail_msg("%s: %s", OCC, err.msg);
    nee_occluded = nee_lit = 0;
    n = check_nee_pdfs(s, CST_INTEGRATOR_PATH, "subsurface exit", 1, -1.0);
    print_message("subsurface under a blocker: %d NEE events at exits (%d occluded, %d lit)\n", n, nee_occluded,
                  nee_lit);
    assert_true(n > 50 && nee_occluded > 20 && nee_lit > 5);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_path_bdpt_lobes),
        cmocka_unit_test(test_whitted_sppm_photon_lobes),
        cmocka_unit_test(test_more_lobes),
        cmocka_unit_test(test_nee_pdfs_media_sss),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
