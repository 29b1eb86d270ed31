/* The BSDFs of src/materials against their own claims: chi-square goodness-of-fit of every
 * sampling routine against bsdf_pdf, sample weights against eval / pdf, white-furnace
 * directional albedos (with the rough dielectric's single-scattering loss measured and
 * bounded), reciprocity, the refraction adjoint, and the Fresnel helpers against
 * independent references. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <complex.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "materials/bsdf.h"
#include "materials/fresnel.h"
#include "materials/microfacet.h"
#include "sampling/warp.h"
#include "unit/chi2.h"

/* C11's CMPLX, which glibc defines only for GCC (through __builtin_complex): Clang has
 * __builtin_complex too. */
#ifndef CMPLX
#define CMPLX(x, y) __builtin_complex((double)(x), (double)(y))
#endif

#define PI_D 3.14159265358979323846

/* ------------------------------------------------------------------ cases */

static const float ROUGHNESS[] = {0.05f, 0.2f, 0.5f, 1.0f};
static const float IORS[] = {1.33f, 1.5f, 2.4f};
/* cos theta_o; negative: wo below the surface (inside a dielectric, so the relative IOR is
 * inverted; the back of a two-sided reflector). 0.05 is 87 degrees: near grazing. */
static const float COS_REFLECT[] = {0.95f, 0.6f, 0.25f, 0.05f};
static const float COS_DIELECTRIC[] = {0.95f, 0.6f, 0.25f, 0.05f, -0.95f, -0.6f, -0.25f, -0.05f};
static const float PLASTIC_ROUGHNESS[] = {0.0f, 0.05f, 0.2f, 0.5f, 1.0f};
static const float COS_PLASTIC[] = {0.95f, 0.5f, 0.1f};
static const float COS_LAMBERT[] = {0.9f, 0.5f, 0.1f, -0.6f};

#define NELEM(a) ((int)(sizeof(a) / sizeof((a)[0])))

typedef struct Case {
    char name[112];
    Material mat;
    float cos_o;
    BsdfTransport mode;
    /* framed: the BSDF's normal n and tangent (bsdf_set_tangent) instead of test_normal()'s
     * identity frame (the anisotropic cases) */
    bool framed;
    Vec3 n, tangent;
} Case;

static Material make_material(MaterialType t, float roughness, float ior)
{
    Material m = {.type = t, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = ior, .roughness = roughness};
    if (t == MATERIAL_CONDUCTOR) assert_true(material_metal("gold", &m.eta, &m.k));
    if (t == MATERIAL_PLASTIC) m.albedo = color_rgb(0.8f, 0.5f, 0.2f);
    if (t == MATERIAL_DIFFUSE) m.albedo = color_rgb(0.7f, 0.7f, 0.7f);
    material_prepare(&m);
    return m;
}

/* An anisotropic conductor or dielectric of GGX widths (ax, ay): perceptual roughness
 * sqrt(alpha) each (material.h: alpha = r^2). */
static Material make_aniso(MaterialType t, float ax, float ay, float ior)
{
    Material m = make_material(t, sqrtf(ax), ior);
    m.anisotropic = true;
    m.roughness_v = sqrtf(ay);
    return m;
}

/* The anisotropic cases' widths and frames: the identity frame (tangent +x), the tangent
 * turned 0.6 rad about +z, and a tilted normal with a tangent not orthogonal to it
 * (bsdf_set_tangent orthogonalises). */
static const float ANISO_ALPHA[][2] = {{0.05f, 0.5f}, {0.5f, 0.05f}};
static void aniso_frame(int f, Vec3 *n, Vec3 *tangent)
{
    *n = f < 2 ? v3(0.0f, 0.0f, 1.0f) : v3_normalize(v3(0.3f, -0.4f, 0.8f));
    *tangent = f == 0 ? v3(1.0f, 0.0f, 0.0f) : f == 1 ? v3(cosf(0.6f), sinf(0.6f), 0.0f) : v3(0.2f, 1.0f, 0.3f);
}

/* Every chi-square case, in a fixed order (the seeds follow the index). */
static int build_cases(Case *out)
{
    int n = 0;
    for (int a = 0; a < NELEM(COS_LAMBERT); a++) {
        Case *c = &out[n++];
        c->mat = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
        c->cos_o = COS_LAMBERT[a];
        c->mode = BSDF_RADIANCE;
        snprintf(c->name, sizeof c->name, "lambert cos_o=%.2f", (double)c->cos_o);
    }
    for (int r = 0; r < NELEM(ROUGHNESS); r++)
        for (int a = 0; a <= NELEM(COS_REFLECT); a++) {
            Case *c = &out[n++];
            c->mat = make_material(MATERIAL_CONDUCTOR, ROUGHNESS[r], 1.0f);
            /* the extra angle: the back of the two-sided conductor */
            c->cos_o = a < NELEM(COS_REFLECT) ? COS_REFLECT[a] : -0.5f;
            c->mode = BSDF_RADIANCE;
            snprintf(c->name, sizeof c->name, "conductor r=%.2f cos_o=%.2f", (double)ROUGHNESS[r], (double)c->cos_o);
        }
    for (int r = 0; r < NELEM(ROUGHNESS); r++)
        for (int i = 0; i < NELEM(IORS); i++)
            for (int a = 0; a < NELEM(COS_DIELECTRIC); a++) {
                Case *c = &out[n++];
                c->mat = make_material(MATERIAL_DIELECTRIC, ROUGHNESS[r], IORS[i]);
                c->cos_o = COS_DIELECTRIC[a];
                /* Sampling does not depend on the transport; the weights do: check both. */
                c->mode = (a & 1) ? BSDF_IMPORTANCE : BSDF_RADIANCE;
                snprintf(c->name, sizeof c->name, "dielectric r=%.2f ior=%.2f cos_o=%.2f %s", (double)ROUGHNESS[r],
                         (double)IORS[i], (double)c->cos_o, c->mode == BSDF_RADIANCE ? "radiance" : "importance");
            }
    /* diffuse transmission: both sides of the surface, unequal colours and shares */
    for (int a = 0; a < NELEM(COS_LAMBERT); a++) {
        Case *c = &out[n++];
        c->mat = make_material(MATERIAL_DIFFUSE_TRANSMISSION, 0.0f, 1.0f);
        c->mat.albedo = color_rgb(0.6f, 0.3f, 0.1f);
        c->mat.transmittance = color_rgb(0.2f, 0.5f, 0.3f);
        c->cos_o = COS_LAMBERT[a];
        c->mode = BSDF_RADIANCE;
        snprintf(c->name, sizeof c->name, "diffuse transmission cos_o=%.2f", (double)c->cos_o);
    }
    for (int r = 0; r < NELEM(PLASTIC_ROUGHNESS); r++)
        for (int a = 0; a < NELEM(COS_PLASTIC); a++) {
            Case *c = &out[n++];
            c->mat = make_material(MATERIAL_PLASTIC, PLASTIC_ROUGHNESS[r], 1.5f);
            c->cos_o = COS_PLASTIC[a];
            c->mode = BSDF_RADIANCE;
            snprintf(c->name, sizeof c->name, "plastic r=%.2f cos_o=%.2f", (double)PLASTIC_ROUGHNESS[r],
                     (double)c->cos_o);
        }
    /* anisotropic GGX (after the others, whose seeds follow their indices): both width
     * orders, three frames, the conductor from above and its back, the dielectric from
     * both sides */
    for (int w = 0; w < NELEM(ANISO_ALPHA); w++)
        for (int f = 0; f < 3; f++)
            for (int t = 0; t < 2; t++)
                for (int a = 0; a < 4; a++) {
                    static const float COS_C[] = {0.95f, 0.5f, 0.1f, -0.6f}, COS_D[] = {0.9f, 0.3f, -0.8f, -0.2f};
                    Case *c = &out[n++];
                    MaterialType ty = t ? MATERIAL_DIELECTRIC : MATERIAL_CONDUCTOR;
                    c->mat = make_aniso(ty, ANISO_ALPHA[w][0], ANISO_ALPHA[w][1], 1.5f);
                    c->cos_o = t ? COS_D[a] : COS_C[a];
                    c->mode = (t && (a & 1)) ? BSDF_IMPORTANCE : BSDF_RADIANCE;
                    c->framed = true;
                    aniso_frame(f, &c->n, &c->tangent);
                    snprintf(c->name, sizeof c->name, "anisotropic %s alpha=(%.2f, %.2f) frame %d cos_o=%.2f",
                             t ? "dielectric" : "conductor", (double)ANISO_ALPHA[w][0], (double)ANISO_ALPHA[w][1], f,
                             (double)c->cos_o);
                }
    return n;
}
#define MAX_CASES 256

/* The normal +z: frame_from_normal gives the identity frame exactly, so world and local
 * directions are the same floats and the sample-vs-eval checks below see only the BSDF's
 * own arithmetic (a tilted frame's rounding moves narrow grazing lobes by ~1e-3). */
static Vec3 test_normal(void) { return v3(0.0f, 0.0f, 1.0f); }

/* wo in the BSDF's local frame at cosine c, azimuth 0.7 rad; returned in world space. */
static Vec3 make_wo(const Bsdf *b, float c, Vec3 *wo_local)
{
    float s = sqrtf(1.0f - c * c);
    *wo_local = v3(s * cosf(0.7f), s * sinf(0.7f), c);
    return frame_to_world(&b->frame, *wo_local);
}

/* ------------------------------------------------------------------ chi-square */

enum {
    SAMPLES = 100000, /* per case */
    NT = 24,          /* theta' bins */
    NP = 32,          /* phi' bins */
    SUB = 8,          /* midpoint sub-samples per cell side for the expected counts */
    SUB_FINE = 48     /* the same in cells with a discontinuity */
};
static const double ALPHA = 0.01; /* significance of the whole file, Sidak-corrected per case */

/* The histogram: for each side of the surface (0: wo's side, 1: the other), spherical
 * coordinates (theta', phi') about a pole where that side's lobe is (the mirror direction,
 * the refracted one, or the normal for diffuse lobes), with theta' bins spaced
 * exponentially, theta'_j = theta0 (exp(t_j L) - 1), t_j = j / NT, L = ln(1 + pi / theta0):
 * bins a fraction of alpha wide at the pole, so lobes far narrower than a uniform grid's
 * cells are still resolved, and the expected counts integrate accurately. Still a
 * theta/phi histogram over the whole sphere, per side. */
typedef struct Hist {
    Frame pole[2];
    float theta0, L;
    float side_sign; /* sign of wo.z: side 0 is where wi.z has this sign */
} Hist;

static Vec3 hist_dir(const Hist *h, int side, double t, double phi, double *jac)
{
    double e = exp(t * (double)h->L);
    double th = (double)h->theta0 * (e - 1.0);
    /* d omega = sin theta' d theta' d phi, d theta' = theta0 L e dt */
    *jac = sin(th) * (double)h->theta0 * (double)h->L * e;
    Vec3 d = v3((float)(sin(th) * cos(phi)), (float)(sin(th) * sin(phi)), (float)cos(th));
    return frame_to_world(&h->pole[side], d);
}

static int hist_cell(const Hist *h, Vec3 wi_local)
{
    int side = wi_local.z * h->side_sign > 0.0f ? 0 : 1;
    Vec3 d = frame_to_local(&h->pole[side], wi_local);
    /* atan2, not acos: acos of a float cosine near 1 is quantised to ~3e-4 rad, coarser
     * than the narrowest lobes' pole cells. */
    double th = atan2(hypot((double)d.x, (double)d.y), (double)d.z);
    double t = log1p(th / (double)h->theta0) / (double)h->L;
    double phi = atan2((double)d.y, (double)d.x);
    if (phi < 0.0) phi += 2.0 * PI_D;
    int it = (int)(t * NT), ip = (int)(phi / (2.0 * PI_D) * NP);
    if (it >= NT) it = NT - 1;
    if (ip >= NP) ip = NP - 1;
    if (it < 0) it = 0;
    return (side * NT + it) * NP + ip;
}

/* GGX's alpha of the lobe (the narrower width of an anisotropic one; 0 for the lobes that
 * are always smooth). */
static float lobe_alpha(const Bsdf *b)
{
    switch (b->type) {
    case MATERIAL_CONDUCTOR: return fminf(b->lobe.conductor.alpha, b->lobe.conductor.alpha_y);
    case MATERIAL_DIELECTRIC: return fminf(b->lobe.dielectric.alpha, b->lobe.dielectric.alpha_y);
    case MATERIAL_PLASTIC: return b->lobe.plastic.alpha;
    default: return 0.0f;
    }
}

static Hist make_hist(const Bsdf *b, Vec3 wo, MaterialType type)
{
    Hist h;
    float sgn = wo.z > 0.0f ? 1.0f : -1.0f;
    h.side_sign = sgn;
    Vec3 p0 = v3(-wo.x, -wo.y, wo.z), p1 = v3(0.0f, 0.0f, -sgn);
    Vec3 wt;
    float etap;
    if (type == MATERIAL_DIELECTRIC && refract_about(wo, v3(0.0f, 0.0f, 1.0f), b->lobe.dielectric.eta, &wt, &etap))
        p1 = v3_normalize(wt);
    if (type == MATERIAL_DIFFUSE || type == MATERIAL_DIFFUSE_TRANSMISSION) p0 = v3(0.0f, 0.0f, sgn);
    h.pole[0] = frame_from_normal(p0);
    h.pole[1] = frame_from_normal(p1);
    h.theta0 = type == MATERIAL_DIFFUSE || type == MATERIAL_DIFFUSE_TRANSMISSION ? 100.0f
                                                                                : fmaxf(0.5f * lobe_alpha(b), 1e-3f);
    if (type == MATERIAL_PLASTIC && lobe_alpha(b) == 0.0f) h.theta0 = 100.0f;
    h.L = logf(1.0f + CST_PI / h.theta0);
    return h;
}

typedef struct ChiResult {
    double p;
    int dof;
    double max_rel_pdf, max_rel_weight; /* sample pdf vs bsdf_pdf, weight vs eval / pdf */
    long inconsistent;                  /* samples beyond the 1e-3 relative tolerance */
} ChiResult;

static ChiResult run_chi2(const Case *c, uint64_t seed)
{
    ChiResult res = {0};
    Bsdf b;
    bsdf_init(&b, &c->mat, c->framed ? c->n : test_normal());
    if (c->framed) bsdf_set_tangent(&b, c->tangent);
    Vec3 wo_l;
    Vec3 wo = make_wo(&b, c->cos_o, &wo_l);
    Hist h = make_hist(&b, wo_l, c->mat.type);
    const int cells = 2 * NT * NP;
    const int DELTA = cells, FAIL = cells + 1, TOTAL = cells + 2;
    double *obs = calloc((size_t)TOTAL, sizeof *obs), *expd = calloc((size_t)TOTAL, sizeof *expd);
    assert_non_null(obs);
    assert_non_null(expd);

    Pcg32 rng;
    pcg32_seed(&rng, seed, 0x5eedu);
    for (int i = 0; i < SAMPLES; i++) {
        float uc = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        BsdfSample s;
        if (!bsdf_sample_transport(&b, wo, uc, u, c->mode, &s)) { obs[FAIL] += 1.0; continue; }
        if (s.delta) { obs[DELTA] += 1.0; continue; }
        obs[hist_cell(&h, frame_to_local(&b.frame, s.wi))] += 1.0;
        /* The sample's own pdf and weight against eval and pdf. */
        double pdf = (double)bsdf_pdf(&b, wo, s.wi);
        Color f = bsdf_eval_transport(&b, wo, s.wi, c->mode);
        double rp = fabs((double)s.pdf_w - pdf) / fmax(pdf, 1e-30);
        double fw[3] = {(double)f.c[0], (double)f.c[1], (double)f.c[2]}, ww[3] = {(double)s.weight.c[0], (double)s.weight.c[1],
                                                                          (double)s.weight.c[2]};
        double rw = 0.0;
        for (int k = 0; k < 3; k++) {
            double want = fw[k] / (double)s.pdf_w;
            rw = fmax(rw, fabs(ww[k] - want) / fmax(fabs(want), 1e-6));
        }
        /* A tilted frame's round trip (local -> world -> local) moves wi by ~1e-7, which
         * changes G2 by more than 1e-3 within ~1e-4 of the horizon (Lambda ~ 1 / cos):
         * the framed cases check the sample against eval and pdf away from it only (the
         * histogram above keeps every sample). */
        if (c->framed && fabsf(v3_dot(s.wi, b.frame.n)) < 1e-2f) continue;
        res.max_rel_pdf = fmax(res.max_rel_pdf, rp);
        res.max_rel_weight = fmax(res.max_rel_weight, rw);
        if (rp > 1e-3 || rw > 1e-3) res.inconsistent++;
    }

    /* Expected counts: the pdf integrated over each cell by the midpoint rule in (t, phi);
     * cells where the integrand jumps to zero inside (the horizon, or a pdf's support
     * ending) are integrated again on a finer grid, the midpoint rule's error there being
     * first order in the spacing. */
    double total = 0.0;
    for (int side = 0; side < 2; side++)
        for (int it = 0; it < NT; it++)
            for (int ip = 0; ip < NP; ip++) {
                double cell = 0.0;
                for (int sub = SUB, pass = 0; pass < 2; pass++, sub = SUB_FINE) {
                    double sum = 0.0;
                    bool zero = false, nonzero = false;
                    for (int a = 0; a < sub; a++)
                        for (int bb = 0; bb < sub; bb++) {
                            double t = ((double)it + ((double)a + 0.5) / sub) / NT;
                            double phi = 2.0 * PI_D * ((double)ip + ((double)bb + 0.5) / sub) / NP;
                            double jac;
                            Vec3 d = hist_dir(&h, side, t, phi, &jac);
                            bool on_side0 = d.z * h.side_sign > 0.0f;
                            double pdf = on_side0 == (side == 0)
                                             ? (double)bsdf_pdf(&b, wo, frame_to_world(&b.frame, d)) : 0.0;
                            sum += pdf * jac;
                            if (pdf > 0.0) nonzero = true;
                            else zero = true;
                        }
                    cell = sum * (1.0 / NT) * (2.0 * PI_D / NP) / ((double)sub * sub);
                    if (!(zero && nonzero)) break;
                }
                expd[(side * NT + it) * NP + ip] = cell * SAMPLES;
                total += cell;
            }
    double pdelta = (double)bsdf_delta_probability(&b, wo);
    expd[DELTA] = pdelta * SAMPLES;
    expd[FAIL] = fmax(0.0, 1.0 - pdelta - total) * SAMPLES;

    /* Diagnostics for a failing case: BSDF_DEBUG=1 prints totals and outlying cells,
     * BSDF_GRID="<case name>" the z-score of every cell. */
    if (getenv("BSDF_DEBUG")) {
        double so = 0, se = 0;
        for (int i = 0; i < cells; i++) { so += obs[i]; se += expd[i]; }
        fprintf(stderr, "%s: cells obs %.0f exp %.1f; delta obs %.0f exp %.1f; fail obs %.0f exp %.1f\n", c->name, so, se,
                obs[DELTA], expd[DELTA], obs[FAIL], expd[FAIL]);
        for (int i = 0; i < cells; i++)
            if (expd[i] > 20 && fabs(obs[i] - expd[i]) > 4 * sqrt(expd[i]))
                fprintf(stderr, "  cell side %d it %d ip %d: obs %.0f exp %.1f\n", i / (NT * NP), (i / NP) % NT, i % NP,
                        obs[i], expd[i]);
    }
    if (getenv("BSDF_GRID") && strcmp(getenv("BSDF_GRID"), c->name) == 0)
        for (int side = 0; side < 2; side++)
            for (int it = 0; it < NT; it++) {
                for (int ip = 0; ip < NP; ip++) {
                    int i = (side * NT + it) * NP + ip;
                    fprintf(stderr, "%5.1f", expd[i] > 0 ? (obs[i] - expd[i]) / sqrt(expd[i]) : 0.0);
                }
                fprintf(stderr, "\n");
            }
    /* A cell whose every integration point has pdf 0 can still hold a sliver of the
     * support (a horizon crossing it near a corner). Give such cells a negligible
     * expectation so they join the pool of low-expectation cells rather than fail on
     * sight: samples really outside the support still blow up the pooled term. */
    for (int i = 0; i < TOTAL; i++)
        if (expd[i] <= 0.0) expd[i] = 1e-9;
    double stat, outside;
    res.p = chi2_pvalue(obs, expd, TOTAL, &res.dof, &stat, &outside);
    if (outside > 0.0) res.p = 0.0; /* samples where the pdf says none can be */
    if (res.dof < 1) res.p = 1.0;   /* everything in one cell: nothing to compare */
    free(obs);
    free(expd);
    return res;
}

static void test_chi2_all_samplers(void **state)
{
    (void)state;
    static Case cases[MAX_CASES];
    int n = build_cases(cases);
    assert_true(n <= MAX_CASES);
    const double threshold = 1.0 - pow(1.0 - ALPHA, 1.0 / (double)n);
    double worst_p = 1.0, worst_pdf = 0.0, worst_w = 0.0;
    int worst = 0, failures = 0;
    for (int i = 0; i < n; i++) {
        ChiResult r = run_chi2(&cases[i], 1000u + (uint64_t)i);
        if (r.p < worst_p) { worst_p = r.p; worst = i; }
        worst_pdf = fmax(worst_pdf, r.max_rel_pdf);
        worst_w = fmax(worst_w, r.max_rel_weight);
        if (r.p < threshold || r.inconsistent > 0) {
            print_error("%s: p = %.3g (dof %d, threshold %.3g); %ld samples with pdf or weight off by > 1e-3 "
                        "(max rel. %.2g, %.2g)\n",
                        cases[i].name, r.p, r.dof, threshold, r.inconsistent, r.max_rel_pdf, r.max_rel_weight);
            failures++;
        }
    }
    print_message("chi-square: %d cases of %d samples, Sidak threshold %.3g; worst p = %.3g (%s); "
                  "max relative |pdf - bsdf_pdf| %.2g, |weight - eval/pdf| %.2g\n",
                  n, SAMPLES, threshold, worst_p, cases[worst].name, worst_pdf, worst_w);
    assert_int_equal(failures, 0);
}

/* ------------------------------------------------------------------ Fresnel references */

/* fresnel_conductor's real-arithmetic form against the Fresnel equations in complex double
 * arithmetic (r_s = (cos - n cos_t) / (cos + n cos_t), r_p = (n cos - cos_t) / (n cos + cos_t),
 * n cos_t = sqrt(n^2 - sin^2)). */
static void test_fresnel_conductor_complex(void **state)
{
    (void)state;
    const double etas[] = {0.05, 0.14, 0.943, 1.47, 1.5}, ks[] = {0.0, 0.5, 2.455, 4.483, 7.79};
    double worst = 0.0;
    for (int i = 0; i < 5; i++)
        for (int j = 0; j < 5; j++)
            for (int a = 0; a <= 20; a++) {
                double c = a == 0 ? 1e-3 : (double)a / 20.0;
                double complex n = CMPLX(etas[i], ks[j]);
                double s2 = 1.0 - c * c;
                double complex nct = csqrt(n * n - s2); /* n cos_t */
                double complex rs = (c - nct) / (c + nct);
                double complex rp = (n * n * c - nct) / (n * n * c + nct);
                double want = 0.5 * (creal(rs * conj(rs)) + creal(rp * conj(rp)));
                double got = (double)fresnel_conductor((float)c, (float)etas[i], (float)ks[j]);
                worst = fmax(worst, fabs(got - want));
            }
    print_message("fresnel_conductor vs complex arithmetic: max |error| %.2g\n", worst);
    assert_true(worst < 1e-5);
    /* A conductor with k = 0 is a dielectric seen from outside. */
    for (int a = 1; a <= 10; a++) {
        float c = (float)a / 10.0f;
        assert_true(fabsf(fresnel_conductor(c, 1.5f, 0.0f) - fresnel_dielectric(c, 1.5f)) < 1e-6f);
    }
}

static double fresnel_dielectric_d(double c, double n)
{
    double st2 = (1.0 - c * c) / (n * n);
    if (st2 >= 1.0) return 1.0;
    double ct = sqrt(1.0 - st2);
    double a = (n * c - ct) / (n * c + ct), b = (c - n * ct) / (c + n * ct);
    return 0.5 * (a * a + b * b);
}

/* The closed form of the diffuse Fresnel reflectance against a 10^5-point midpoint rule. */
static void test_fresnel_diffuse_reflectance(void **state)
{
    (void)state;
    const double etas[] = {1.01, 1.1, 1.33, 1.5, 2.0, 2.4, 4.0};
    for (int i = 0; i < 7; i++) {
        const int n = 100000;
        double sum = 0.0;
        for (int k = 0; k < n; k++) {
            double mu = ((double)k + 0.5) / n;
            sum += 2.0 * fresnel_dielectric_d(mu, etas[i]) * mu / n;
        }
        double got = (double)fresnel_diffuse_reflectance((float)etas[i]);
        if (!(fabs(got - sum) < 1e-6)) fail_msg("eta %.2f: closed form %.8f, quadrature %.8f", etas[i], got, sum);
    }
    assert_true(fresnel_diffuse_reflectance(1.0f) == 0.0f);
}

/* ------------------------------------------------------------------ white furnace */

typedef struct Albedo { double mean[3], se[3]; } Albedo;

/* Directional albedo int f(wo, wi) |cos_i| dwi = E[weight] (failed samples count as 0),
 * with its standard error, by `n` samples. In BSDF_IMPORTANCE mode this is the energy
 * (flux) a BSDF passes on; radiance-mode refraction adds 1/eta^2 to it. */
static Albedo directional_albedo(const Material *m, float cos_o, BsdfTransport mode, int n, uint64_t seed)
{
    Bsdf b;
    bsdf_init(&b, m, test_normal());
    Vec3 wo_l;
    Vec3 wo = make_wo(&b, cos_o, &wo_l);
    Pcg32 rng;
    pcg32_seed(&rng, seed, 0xa1bedu);
    double sum[3] = {0, 0, 0}, sum2[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        float uc = pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        BsdfSample s;
        if (!bsdf_sample_transport(&b, wo, uc, u, mode, &s)) continue;
        double w[3] = {(double)s.weight.c[0], (double)s.weight.c[1], (double)s.weight.c[2]};
        for (int k = 0; k < 3; k++) { sum[k] += w[k]; sum2[k] += w[k] * w[k]; }
    }
    Albedo a;
    for (int k = 0; k < 3; k++) {
        a.mean[k] = sum[k] / n;
        double var = fmax(0.0, sum2[k] / n - a.mean[k] * a.mean[k]);
        a.se[k] = sqrt(var / (n - 1));
    }
    return a;
}

static const float FURNACE_COS[] = {1.0f, 0.9f, 0.7f, 0.5f, 0.3f, 0.1f, 0.02f};
enum { FURNACE_SAMPLES = 50000 };
/* |z| beyond which a furnace mean disagrees with its bound (the render tests' Z_LIMIT). */
static const double FURNACE_Z = 4.0;

/* Albedo-1 Lambert, the smooth dielectric (reflect + transmit) in flux, and the smooth-coat
 * plastic of base albedo 1 conserve energy exactly: every one of these must give 1 (the
 * first two with zero variance). Everything energy-conserving stays <= 1. */
static void test_white_furnace(void **state)
{
    (void)state;
    const int n = FURNACE_SAMPLES;
    double worst_excess_z = -HUGE_VAL;
    for (int a = 0; a < NELEM(FURNACE_COS); a++) {
        float c = FURNACE_COS[a];
        Material lam = {.type = MATERIAL_DIFFUSE, .albedo = {{1, 1, 1}}, .ior = 1.0f};
        Albedo al = directional_albedo(&lam, c, BSDF_RADIANCE, n, 1u);
        assert_true(fabs(al.mean[0] - 1.0) < 1e-6);
        for (int i = 0; i < NELEM(IORS); i++)
            for (int side = 0; side < 2; side++) {
                Material glass = {.type = MATERIAL_GLASS, .albedo = {{1, 1, 1}}, .ior = IORS[i]};
                Material diel = make_material(MATERIAL_DIELECTRIC, 0.0f, IORS[i]);
                Albedo ag = directional_albedo(&glass, side ? -c : c, BSDF_IMPORTANCE, n, 2u);
                Albedo ad = directional_albedo(&diel, side ? -c : c, BSDF_IMPORTANCE, n, 3u);
                if (!(fabs(ag.mean[0] - 1.0) < 1e-6 && fabs(ad.mean[0] - 1.0) < 1e-6))
                    fail_msg("smooth dielectric ior %.2f cos_o %.2f: R + T = %.7f / %.7f, expected 1", (double)IORS[i],
                             (double)(side ? -c : c), ag.mean[0], ad.mean[0]);
            }
        /* plastic of base albedo 1: E + (1 - E) = 1 */
        for (int r = 0; r < NELEM(PLASTIC_ROUGHNESS); r++) {
            Material pl = make_material(MATERIAL_PLASTIC, PLASTIC_ROUGHNESS[r], 1.5f);
            pl.albedo = color_s(1.0f);
            Albedo ap = directional_albedo(&pl, c, BSDF_RADIANCE, n, 4u + (uint64_t)r);
            double z = (ap.mean[0] - 1.0) / ap.se[0];
            if (PLASTIC_ROUGHNESS[r] == 0.0f && !(fabs(z) <= FURNACE_Z))
                fail_msg("smooth plastic rho=1 cos_o %.2f: albedo %.5f (se %.1e), expected 1", (double)c, ap.mean[0],
                         ap.se[0]);
            /* Rough coat: 1 up to the coat table's error (test_plastic_coat_table bounds it
             * by PLASTIC_TABLE_TOL). */
            if (!(ap.mean[0] - 1.0 <= FURNACE_Z * ap.se[0] + 2e-3))
                fail_msg("rough plastic r=%.2f rho=1 cos_o %.2f: albedo %.5f (se %.1e) > 1", (double)PLASTIC_ROUGHNESS[r],
                         (double)c, ap.mean[0], ap.se[0]);
            worst_excess_z = fmax(worst_excess_z, z);
        }
        /* conductors: F <= 1 and the microfacet loss, so < 1 */
        for (int r = 0; r < NELEM(ROUGHNESS); r++) {
            const char *metals[] = {"gold", "silver", "copper", "aluminium"};
            for (int mi = 0; mi < 4; mi++) {
                Material co = make_material(MATERIAL_CONDUCTOR, ROUGHNESS[r], 1.0f);
                assert_true(material_metal(metals[mi], &co.eta, &co.k));
                Albedo ac = directional_albedo(&co, c, BSDF_RADIANCE, n / 4, 5u);
                for (int k = 0; k < 3; k++)
                    if (!(ac.mean[k] <= 1.0 + FURNACE_Z * ac.se[k]))
                        fail_msg("%s r=%.2f cos_o %.2f: albedo[%d] %.5f > 1", metals[mi], (double)ROUGHNESS[r],
                                 (double)c, k, ac.mean[k]);
            }
        }
    }
    print_message("white furnace: Lambert and smooth dielectrics exactly 1; plastic rho=1 largest z above 1: "
                  "%.2f\n",
                  worst_excess_z);
}

/* Diffuse transmission with R + T = 1 and the thin dielectric (R + T = 1 by construction)
 * reflect and transmit all the light, on both sides, in both transports: every sample
 * weighs exactly 1. The thin dielectric's reflectance at normal incidence is the slab's,
 * 2 R0 / (1 + R0) (the sum over internal reflections). */
static void test_transmitters_furnace(void **state)
{
    (void)state;
    const int n = FURNACE_SAMPLES;
    for (int a = 0; a < NELEM(FURNACE_COS); a++)
        for (int side = 0; side < 2; side++)
            for (int t = 0; t < 2; t++) {
                float c = side ? -FURNACE_COS[a] : FURNACE_COS[a];
                Material m = {.type = MATERIAL_DIFFUSE_TRANSMISSION, .albedo = color_s(0.7f), .ior = 1.0f};
                m.transmittance = color_s(0.3f);
                if (t) m = (Material){.type = MATERIAL_THIN_DIELECTRIC, .albedo = color_s(1.0f), .ior = 1.5f};
                BsdfTransport mode = a & 1 ? BSDF_IMPORTANCE : BSDF_RADIANCE;
                Albedo al = directional_albedo(&m, c, mode, n, 40u + (uint64_t)a);
                if (!(fabs(al.mean[0] - 1.0) < 1e-6))
                    fail_msg("%s cos_o %.2f: albedo %.7f, expected 1", t ? "thin dielectric" : "diffuse transmission",
                             (double)c, al.mean[0]);
            }
    Material thin = {.type = MATERIAL_THIN_DIELECTRIC, .albedo = color_s(1.0f), .ior = 1.5f};
    Bsdf b;
    bsdf_init(&b, &thin, test_normal());
    BsdfSample s;
    assert_true(bsdf_sample(&b, v3(0.0f, 0.0f, 1.0f), 0.0f, v2(0.5f, 0.5f), &s));
    float r0 = 0.04f, want = 2.0f * r0 / (1.0f + r0);
    assert_true(s.delta && s.wi.z > 0.0f && fabsf(s.pmf - want) < 1e-6f);
    assert_true(bsdf_sample(&b, v3(0.6f, 0.0f, 0.8f), 0.999f, v2(0.5f, 0.5f), &s));
    assert_true(s.delta && s.wi.x == -0.6f && s.wi.z == -0.8f); /* undeviated */
    assert_true(bsdf_is_delta(&b) && bsdf_has_transmission(&b));
}

/* The rough dielectric in flux (importance mode, so refraction's 1/eta^2 does not enter):
 * reflection + transmission lose what single scattering cannot return (rays that the
 * microsurface would scatter again). Measured per roughness as the worst loss over
 * IORS, both sides and FURNACE_COS; bounded by ROUGH_LOSS_BOUND, the measured value plus
 * a margin of a few standard errors (see the print for the figures). */
/* measured worst (se): 0.0100 (3e-4), 0.1004 (1e-3), 0.2311 (1.5e-3), 0.6934 (1.6e-3); each
 * bound is that plus 5 se, rounded up */
static const double ROUGH_LOSS_BOUND[] = {0.012, 0.106, 0.24, 0.71}; /* per ROUGHNESS */
static void test_rough_dielectric_energy_loss(void **state)
{
    (void)state;
    const int n = FURNACE_SAMPLES;
    for (int r = 0; r < NELEM(ROUGHNESS); r++) {
        double worst = 0.0, worst_se = 0.0, mean_loss = 0.0;
        int count = 0;
        float worst_cos = 0.0f, worst_ior = 0.0f;
        for (int i = 0; i < NELEM(IORS); i++)
            for (int a = 0; a < NELEM(FURNACE_COS); a++)
                for (int side = 0; side < 2; side++) {
                    float c = side ? -FURNACE_COS[a] : FURNACE_COS[a];
                    Material m = make_material(MATERIAL_DIELECTRIC, ROUGHNESS[r], IORS[i]);
                    Albedo al = directional_albedo(&m, c, BSDF_IMPORTANCE, n, 100u + (uint64_t)(r * 100 + i * 10 + a));
                    double loss = 1.0 - al.mean[0];
                    if (!(loss >= -FURNACE_Z * al.se[0]))
                        fail_msg("rough dielectric r=%.2f ior %.2f cos_o %.2f: albedo %.5f (se %.1e) > 1",
                                 (double)ROUGHNESS[r], (double)IORS[i], (double)c, al.mean[0], al.se[0]);
                    mean_loss += loss;
                    count++;
                    if (loss > worst) { worst = loss; worst_se = al.se[0]; worst_cos = c; worst_ior = IORS[i]; }
                }
        print_message("rough dielectric r=%.2f (alpha %.4f): energy loss mean %.4f, worst %.4f (se %.1e) at ior %.2f "
                      "cos_o %.2f; bound %.3f\n",
                      (double)ROUGHNESS[r], (double)material_alpha(ROUGHNESS[r]), mean_loss / count, worst, worst_se,
                      (double)worst_ior, (double)worst_cos, ROUGH_LOSS_BOUND[r]);
        assert_true(worst <= ROUGH_LOSS_BOUND[r]);
    }
}

/* ------------------------------------------------------------------ reciprocity, adjoint */

static Vec3 random_dir(Pcg32 *rng) { return warp_uniform_sphere(pcg32_v2(rng)); }

static double rel_diff(Color a, Color b)
{
    double d = 0.0;
    double x[3] = {(double)a.c[0], (double)a.c[1], (double)a.c[2]}, y[3] = {(double)b.c[0], (double)b.c[1], (double)b.c[2]};
    for (int k = 0; k < 3; k++) d = fmax(d, fabs(x[k] - y[k]) / fmax(fmax(fabs(x[k]), fabs(y[k])), 1e-30));
    return d;
}

/* One material of every non-delta type and roughness the chi-square cases use; returns
 * how many (mats has room for 24). */
static int non_delta_materials(Material *mats)
{
    int nm = 0;
    mats[nm++] = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
    for (int r = 0; r < NELEM(ROUGHNESS); r++) {
        mats[nm++] = make_material(MATERIAL_CONDUCTOR, ROUGHNESS[r], 1.0f);
        mats[nm++] = make_material(MATERIAL_DIELECTRIC, ROUGHNESS[r], 1.5f);
    }
    for (int r = 0; r < NELEM(PLASTIC_ROUGHNESS); r++) mats[nm++] = make_material(MATERIAL_PLASTIC, PLASTIC_ROUGHNESS[r], 1.5f);
    for (int w = 0; w < NELEM(ANISO_ALPHA); w++) {
        mats[nm++] = make_aniso(MATERIAL_CONDUCTOR, ANISO_ALPHA[w][0], ANISO_ALPHA[w][1], 1.0f);
        mats[nm++] = make_aniso(MATERIAL_DIELECTRIC, ANISO_ALPHA[w][0], ANISO_ALPHA[w][1], 1.5f);
    }
    Material dt = make_material(MATERIAL_DIFFUSE_TRANSMISSION, 0.0f, 1.0f);
    dt.albedo = color_rgb(0.6f, 0.3f, 0.1f);
    dt.transmittance = color_rgb(0.2f, 0.5f, 0.3f);
    mats[nm++] = dt;
    assert_true(nm < 24);
    return nm;
}

/* f(wo, wi) = f(wi, wo) for every reflection lobe: eval is f |cos_i|, so compare
 * eval(wo, wi) / |cos_i| with eval(wi, wo) / |cos_o|. */
static void test_reciprocity(void **state)
{
    (void)state;
    Material mats[24];
    int nm = non_delta_materials(mats);
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 1u);
    double worst = 0.0;
    long checked = 0;
    for (int i = 0; i < nm; i++) {
        Bsdf b;
        bsdf_init(&b, &mats[i], test_normal());
        for (int k = 0; k < 20000; k++) {
            Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
            if (wo.z * wi.z <= 0.0f) wi.z = -wi.z; /* reflection pairs, either side */
            if (fabsf(wo.z) < 1e-3f || fabsf(wi.z) < 1e-3f) continue;
            Color f1 = color_scale(bsdf_eval(&b, wo, wi), 1.0f / fabsf(wi.z));
            Color f2 = color_scale(bsdf_eval(&b, wi, wo), 1.0f / fabsf(wo.z));
            if (color_is_black(f1) && color_is_black(f2)) continue;
            double d = rel_diff(f1, f2);
            worst = fmax(worst, d);
            checked++;
            if (!(d <= 1e-4))
                fail_msg("material %d: f(wo,wi) = %g, f(wi,wo) = %g (relative %.2g)", i, (double)f1.c[0], (double)f2.c[0], d);
        }
    }
    print_message("reciprocity: %ld pairs, max relative difference %.2g\n", checked, worst);
}

/* bsdf_eval_pdfs is the three calls it replaces, bit for bit, for every material, with and
 * without a shading normal (one-sided and two-sided), on directions on both sides. */
static void test_eval_pdfs_matches_calls(void **state)
{
    (void)state;
    Material mats[24];
    int nm = non_delta_materials(mats);
    mats[nm] = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
    mats[nm++].one_sided = true;
    Pcg32 rng;
    pcg32_seed(&rng, 79u, 1u);
    long nonzero = 0;
    for (int i = 0; i < nm; i++)
        for (int shading = 0; shading < 2; shading++) {
            Bsdf b;
            Vec3 ng = v3_normalize(v3(0.1f, 0.2f, 1.0f));
            bsdf_init_shading(&b, &mats[i], shading ? v3_normalize(v3(0.3f, -0.1f, 1.0f)) : ng, ng);
            for (int k = 0; k < 5000; k++) {
                Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
                float fwd, rev;
                Color f = bsdf_eval_pdfs(&b, wo, wi, &fwd, &rev);
                Color f1 = bsdf_eval(&b, wo, wi);
                float fwd1 = bsdf_pdf(&b, wo, wi), rev1 = bsdf_pdf(&b, wi, wo);
                if (memcmp(&f, &f1, sizeof f) != 0 || memcmp(&fwd, &fwd1, sizeof fwd) != 0 ||
                    memcmp(&rev, &rev1, sizeof rev) != 0)
                    fail_msg("material %d, shading %d: (%g, %g, %g) against (%g, %g, %g)", i, shading, (double)f.c[0],
                             (double)fwd, (double)rev, (double)f1.c[0], (double)fwd1, (double)rev1);
                nonzero += !color_is_black(f) && fwd > 0.0f && rev > 0.0f;
            }
        }
    assert_true(nonzero > 1000); /* the pairs were not all trivially zero */
}

/* The inline bsdf_init_shading fills every field as the general one does, for every
 * material type, with and without a shading normal: a type with a roughness or a coat
 * left out of the inline dispatch would lose them here. */
static void test_init_inline_matches_general(void **state)
{
    (void)state;
    Material mats[24];
    int nm = non_delta_materials(mats);
    mats[nm++] = make_material(MATERIAL_MIRROR, 0.0f, 1.0f);
    mats[nm++] = make_material(MATERIAL_GLASS, 0.0f, 1.5f);
    mats[nm] = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
    mats[nm++].one_sided = true;
    const Vec3 ng = v3_normalize(v3(0.1f, 0.2f, -1.0f));
    for (int i = 0; i < nm; i++)
        for (int shading = 0; shading < 2; shading++) {
            Bsdf a, b;
            memset(&a, 0, sizeof a);
            memset(&b, 0, sizeof b);
            const Vec3 ns = shading ? v3_normalize(v3(0.3f, -0.1f, -1.0f)) : ng;
            bsdf_init_shading(&a, &mats[i], ns, ng);
            bsdf_init_shading_general(&b, &mats[i], ns, ng);
            if (memcmp(&a, &b, sizeof a) != 0)
                fail_msg("material %d (type %d), shading %d", i, (int)mats[i].type, shading);
        }
}

/* The inline Lambert path (bsdf_is_plain_diffuse) is the general code's diffuse branch,
 * bit for bit: eval in both transports, both densities and sampling, one- and two-sided,
 * directions on both sides and exactly in the tangent plane (cosines +0 and -0). */
static void test_plain_diffuse_matches_general(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 81u, 1u);
    long checked = 0;
    for (int one_sided = 0; one_sided < 2; one_sided++) {
        Material m = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
        m.one_sided = one_sided;
        Bsdf b;
        bsdf_init(&b, &m, v3(0.0f, 0.0f, 1.0f));
        assert_true(bsdf_is_plain_diffuse(&b));
        const Vec3 tangent[3] = {v3(1.0f, 0.0f, 0.0f), v3(0.0f, 1.0f, -0.0f), v3(0.6f, -0.8f, 0.0f)};
        for (int k = 0; k < 20000; k++) {
            Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
            if (k % 7 == 0) wo = tangent[k % 3];
            if (k % 11 == 0) wi = tangent[(k / 11) % 3];
            float fwd, rev, fwd1, rev1;
            Color f = bsdf_eval_pdfs(&b, wo, wi, &fwd, &rev);
            Color f1 = bsdf_eval_pdfs_general(&b, wo, wi, &fwd1, &rev1);
            Color fi = bsdf_eval_transport(&b, wo, wi, BSDF_IMPORTANCE);
            Color fi1 = bsdf_eval_transport_general(&b, wo, wi, BSDF_IMPORTANCE);
            float p = bsdf_pdf(&b, wo, wi), p1 = bsdf_pdf_general(&b, wo, wi);
            if (memcmp(&f, &f1, sizeof f) != 0 || memcmp(&fwd, &fwd1, sizeof fwd) != 0 ||
                memcmp(&rev, &rev1, sizeof rev) != 0 || memcmp(&fi, &fi1, sizeof fi) != 0 ||
                memcmp(&p, &p1, sizeof p) != 0)
                fail_msg("one_sided %d, wo.z %g, wi.z %g: (%g, %g, %g) against (%g, %g, %g)", one_sided,
                         (double)wo.z, (double)wi.z, (double)f.c[0], (double)fwd, (double)rev, (double)f1.c[0],
                         (double)fwd1, (double)rev1);
            checked += fwd > 0.0f;
            BsdfSample bs, bs1;
            memset(&bs, 0, sizeof bs);
            memset(&bs1, 0, sizeof bs1);
            const float uc = pcg32_float(&rng);
            const float u_y = k % 13 == 0 ? 0.5f : pcg32_float(&rng);
            const Vec2 u = v2(pcg32_float(&rng), u_y);
            const BsdfTransport mode = k % 2 ? BSDF_IMPORTANCE : BSDF_RADIANCE;
            bool ok = bsdf_sample_transport(&b, wo, uc, u, mode, &bs);
            bool ok1 = bsdf_sample_transport_general(&b, wo, uc, u, mode, &bs1);
            if (ok != ok1 || (ok && memcmp(&bs, &bs1, sizeof bs) != 0))
                fail_msg("one_sided %d, wo.z %g: sample %d (%g, %g, %g) against %d (%g, %g, %g)", one_sided,
                         (double)wo.z, ok, (double)bs.wi.x, (double)bs.wi.y, (double)bs.pdf_w, ok1, (double)bs1.wi.x,
                         (double)bs1.wi.y, (double)bs1.pdf_w);
        }
        assert_true(checked > 2000);
    }
}

/* The rough dielectric's transmission: the importance BSDF is the radiance BSDF with wo
 * and wi swapped, f*(wo, wi) = f(wi, wo), and the two differ by etap^2 (etap the IOR of
 * wi's side over wo's), Veach thesis sec. 5.2. */
static void test_transmission_adjoint(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 78u, 1u);
    double worst = 0.0;
    for (int r = 0; r < NELEM(ROUGHNESS); r++)
        for (int i = 0; i < NELEM(IORS); i++) {
            Material m = make_material(MATERIAL_DIELECTRIC, ROUGHNESS[r], IORS[i]);
            Bsdf b;
            bsdf_init(&b, &m, test_normal());
            for (int k = 0; k < 5000; k++) {
                Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
                if (wo.z * wi.z >= 0.0f) wi.z = -wi.z; /* transmission pairs */
                if (fabsf(wo.z) < 1e-3f || fabsf(wi.z) < 1e-3f) continue;
                Color rad = bsdf_eval_transport(&b, wo, wi, BSDF_RADIANCE);
                Color imp = bsdf_eval_transport(&b, wo, wi, BSDF_IMPORTANCE);
                Color swapped = color_scale(bsdf_eval_transport(&b, wi, wo, BSDF_RADIANCE), fabsf(wi.z) / fabsf(wo.z));
                if (color_is_black(imp) && color_is_black(swapped)) continue;
                float etap = wo.z > 0.0f ? b.lobe.dielectric.eta : 1.0f / b.lobe.dielectric.eta;
                double d1 = rel_diff(imp, swapped), d2 = rel_diff(imp, color_scale(rad, etap * etap));
                /* Relative 1e-4, except in the far tails of the lobes (f |cos| < 1e-3): there
                 * swapping wo and wi rounds the half vector differently (~1e-7 rad), which D
                 * amplifies by up to ~4 tan(theta_m) / alpha^2; an absolute 1e-7 of a lobe
                 * that integrates to ~1 is far below anything a render can see. */
                double mag = fmax((double)color_max(imp), (double)color_max(swapped));
                double tol = mag >= 1e-3 ? 1e-4 : 1e-4 + 1e-7 / mag;
                if (mag >= 1e-3) worst = fmax(worst, fmax(d1, d2));
                if (!(d1 <= tol && d2 <= tol))
                    fail_msg("r=%.2f ior %.2f: f* %g, f(wi,wo) %g, eta^2 f %g", (double)ROUGHNESS[r], (double)IORS[i],
                             (double)imp.c[0], (double)swapped.c[0], (double)(rad.c[0] * etap * etap));
            }
        }
    print_message("transmission adjoint: max relative difference %.2g where f |cos| >= 1e-3\n", worst);
}

/* The rough plastic's coat table E(mu) (material_prepare) against a Monte Carlo estimate
 * of the coat's directional albedo: the diffuse lobe's normalisation rests on it. */
static const double PLASTIC_TABLE_TOL = 2e-3;
/* ------------------------------------------------------------------ anisotropic GGX */

/* The anisotropic distribution by quadrature over the hemisphere (theta = pi/2 t^2, so the
 * nodes crowd at the pole where the narrow width puts the mass; 2000 x 2000 midpoints):
 * int D(m) m.z dm = 1 (the projected-area normalisation) and, for Smith's Lambda to belong
 * to D, int G1(wo) max(0, wo.m) D(m) dm = wo.z (Heitz 2014 eq. 18, which makes the visible
 * normals' density integrate to 1), for several azimuths of wo. Quadrature error, not
 * noise: the measured worst is printed, the tolerance is 1e-3. */
static void test_ggx_anisotropic_normalisation(void **state)
{
    (void)state;
    enum { NQ = 2000 };
    static const float AZ[] = {0.0f, 0.7f, 1.5707964f, 2.5f};
    static const float COS[] = {0.9f, 0.4f, 0.1f};
    double worst = 0.0;
    for (int w = 0; w < NELEM(ANISO_ALPHA); w++) {
        const float ax = ANISO_ALPHA[w][0], ay = ANISO_ALPHA[w][1];
        double norm = 0.0, vis[NELEM(AZ)][NELEM(COS)] = {{0}};
        Vec3 wos[NELEM(AZ)][NELEM(COS)];
        for (int a = 0; a < NELEM(AZ); a++)
            for (int c = 0; c < NELEM(COS); c++) {
                float sn = sqrtf(1.0f - COS[c] * COS[c]);
                wos[a][c] = v3(sn * cosf(AZ[a]), sn * sinf(AZ[a]), COS[c]);
            }
        for (int i = 0; i < NQ; i++) {
            double t = (i + 0.5) / NQ, th = 0.5 * PI_D * t * t, dth = PI_D * t / NQ;
            for (int j = 0; j < NQ; j++) {
                double ph = 2.0 * PI_D * (j + 0.5) / NQ, dw = sin(th) * dth * 2.0 * PI_D / NQ;
                Vec3 m = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th));
                double d = (double)ggx_d(m, ax, ay) * dw;
                norm += d * (double)m.z;
                for (int a = 0; a < NELEM(AZ); a++)
                    for (int c = 0; c < NELEM(COS); c++) vis[a][c] += d * fmax(0.0, (double)v3_dot(wos[a][c], m));
            }
        }
        worst = fmax(worst, fabs(norm - 1.0));
        if (!(fabs(norm - 1.0) < 1e-3)) fail_msg("alpha (%.2f, %.2f): int D cos = %.6f, expected 1", (double)ax, (double)ay, norm);
        for (int a = 0; a < NELEM(AZ); a++)
            for (int c = 0; c < NELEM(COS); c++) {
                double got = (double)ggx_g1(wos[a][c], ax, ay) * vis[a][c] / (double)COS[c];
                worst = fmax(worst, fabs(got - 1.0));
                if (!(fabs(got - 1.0) < 1e-3))
                    fail_msg("alpha (%.2f, %.2f) wo azimuth %.2f cos %.2f: int D_wo = %.6f, expected 1", (double)ax,
                             (double)ay, (double)AZ[a], (double)COS[c], got);
            }
    }
    print_message("anisotropic GGX normalisation: worst |integral - 1| = %.2e\n", worst);
}

/* Turning the tangent by 90 degrees about the normal is swapping the widths: the BSDF of
 * (ax, ay) with tangent s equals that of (ay, ax) with tangent n x s (eval and pdf, to
 * float rounding of the two frames); an isotropic lobe does not change with the tangent. */
static void test_anisotropic_tangent(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 83u, 1u);
    const Vec3 n = v3_normalize(v3(0.3f, -0.4f, 0.8f)), s = v3_normalize(v3(0.2f, 1.0f, 0.3f));
    double worst = 0.0;
    long checked = 0;
    for (int t = 0; t < 3; t++) {
        MaterialType ty = t == 1 ? MATERIAL_DIELECTRIC : MATERIAL_CONDUCTOR;
        Material m1 = t < 2 ? make_aniso(ty, 0.05f, 0.5f, 1.5f) : make_material(ty, 0.6f, 1.5f);
        Material m2 = t < 2 ? make_aniso(ty, 0.5f, 0.05f, 1.5f) : m1;
        Bsdf b1, b2;
        bsdf_init(&b1, &m1, n);
        bsdf_set_tangent(&b1, s);
        bsdf_init(&b2, &m2, n);
        if (t < 2) bsdf_set_tangent(&b2, v3_cross(n, s));
        for (int k = 0; k < 20000; k++) {
            Vec3 wo = random_dir(&rng), wi = random_dir(&rng);
            if (fabsf(v3_dot(wo, n)) < 0.05f || fabsf(v3_dot(wi, n)) < 0.05f) continue;
            Color f1 = bsdf_eval(&b1, wo, wi), f2 = bsdf_eval(&b2, wo, wi);
            float p1 = bsdf_pdf(&b1, wo, wi), p2 = bsdf_pdf(&b2, wo, wi);
            if (color_is_black(f1) && color_is_black(f2)) continue;
            double d = fmax(rel_diff(f1, f2), fabs((double)p1 - (double)p2) / fmax(fmax((double)p1, (double)p2), 1e-30));
            worst = fmax(worst, d);
            checked++;
            if (!(d <= 1e-3))
                fail_msg("case %d: f %g / %g, pdf %g / %g (relative %.2g)", t, (double)f1.c[0], (double)f2.c[0], (double)p1,
                         (double)p2, d);
        }
    }
    assert_true(checked > 10000);
    print_message("tangent turned 90 degrees = widths swapped: %ld pairs, max relative difference %.2g\n", checked,
                  worst);
}

/* Energy bounds of the anisotropic lobes: the conductor reflects at most 1 (a perfect
 * reflector, eta 1 and k 1e4, loses only what single scattering cannot return), the rough
 * dielectric passes on at most 1 of the flux (importance mode) from either side. */
static void test_anisotropic_furnace(void **state)
{
    (void)state;
    const int n = FURNACE_SAMPLES;
    double lo = 1.0, hi = 0.0;
    for (int w = 0; w < NELEM(ANISO_ALPHA); w++)
        for (int a = 0; a < NELEM(FURNACE_COS); a++)
            for (int t = 0; t < 3; t++) {
                float c = t == 2 ? -FURNACE_COS[a] : FURNACE_COS[a];
                Material m = make_aniso(t ? MATERIAL_DIELECTRIC : MATERIAL_CONDUCTOR, ANISO_ALPHA[w][0], ANISO_ALPHA[w][1], 1.5f);
                if (t == 0) {
                    m.eta = color_s(1.0f);
                    m.k = color_s(1e4f);
                }
                Albedo al = directional_albedo(&m, c, BSDF_IMPORTANCE, n, 300u + (uint64_t)(w * 100 + a * 10 + t));
                lo = fmin(lo, al.mean[0]);
                hi = fmax(hi, al.mean[0]);
                if (!(al.mean[0] <= 1.0 + FURNACE_Z * al.se[0]) || !(al.mean[0] > 0.0))
                    fail_msg("anisotropic %s alpha (%.2f, %.2f) cos_o %.2f: albedo %.5f (se %.1e), expected in (0, 1]",
                             t ? "dielectric" : "conductor", (double)ANISO_ALPHA[w][0], (double)ANISO_ALPHA[w][1],
                             (double)c, al.mean[0], al.se[0]);
            }
    print_message("anisotropic furnace: albedos from %.4f to %.4f\n", lo, hi);
}

static void test_plastic_coat_table(void **state)
{
    (void)state;
    double worst = 0.0;
    for (int r = 1; r < NELEM(PLASTIC_ROUGHNESS); r++) {
        Material m = make_material(MATERIAL_PLASTIC, PLASTIC_ROUGHNESS[r], 1.5f);
        m.albedo = color_s(0.0f); /* coat only */
        Bsdf b;
        bsdf_init(&b, &m, test_normal());
        for (int a = 0; a < NELEM(FURNACE_COS); a++) {
            float c = FURNACE_COS[a];
            Albedo al = directional_albedo(&m, c, BSDF_RADIANCE, 200000, 9u + (uint64_t)a);
            float x = sqrtf(c) * (float)(MATERIAL_COAT_TABLE - 1);
            int i = (int)x < MATERIAL_COAT_TABLE - 2 ? (int)x : MATERIAL_COAT_TABLE - 2;
            double tab = (double)m.coat_e[i] + (double)(x - (float)i) * (double)(m.coat_e[i + 1] - m.coat_e[i]);
            double err = fabs(tab - al.mean[0]);
            worst = fmax(worst, err - FURNACE_Z * al.se[0]);
            if (!(err <= FURNACE_Z * al.se[0] + PLASTIC_TABLE_TOL))
                fail_msg("plastic r=%.2f cos_o %.2f: table E %.5f, Monte Carlo %.5f (se %.1e)",
                         (double)PLASTIC_ROUGHNESS[r], (double)c, tab, al.mean[0], al.se[0]);
        }
    }
    print_message("plastic coat table vs Monte Carlo: worst |error| beyond 4 se: %.2g\n", worst);
}

/* pbrt-v4's regularization (bsdf_regularize): GGX widths below 0.3 double into [0.1, 0.3],
 * smooth glass becomes a rough dielectric of width 0.1 and stops being delta, wide lobes
 * and lobes without a microfacet distribution are left alone; the regularized lobes' samples
 * report the density bsdf_pdf gives (the chi-square tests cover GGX lobes of these widths)
 * and their albedo stays within 1 (furnace). */
static void test_regularize(void **state)
{
    (void)state;
    assert_true(bsdf_regularized_alpha(0.0f) == 0.1f);
    assert_true(bsdf_regularized_alpha(0.02f) == 0.1f);
    assert_true(bsdf_regularized_alpha(0.1f) == 0.2f);
    assert_true(bsdf_regularized_alpha(0.2f) == 0.3f);
    assert_true(bsdf_regularized_alpha(0.3f) == 0.3f);
    assert_true(bsdf_regularized_alpha(0.7f) == 0.7f);
    const Vec3 n = v3(0.0f, 0.0f, 1.0f);
    Material glass = make_material(MATERIAL_GLASS, 0.0f, 1.5f);
    Bsdf b;
    bsdf_init(&b, &glass, n);
    assert_true(bsdf_is_delta(&b));
    bsdf_regularize(&b);
    assert_int_equal(b.type, MATERIAL_DIELECTRIC);
    assert_false(bsdf_is_delta(&b));
    assert_true(b.lobe.dielectric.alpha == 0.1f && b.lobe.dielectric.alpha_y == 0.1f);
    Material metal = make_aniso(MATERIAL_CONDUCTOR, 0.05f, 0.6f, 1.0f);
    bsdf_init(&b, &metal, n);
    bsdf_regularize(&b);
    assert_true(b.lobe.conductor.alpha == 0.1f && b.lobe.conductor.alpha_y == 0.6f);
    Material diffuse = make_material(MATERIAL_DIFFUSE, 0.0f, 1.0f);
    Bsdf d0, d1;
    bsdf_init(&d0, &diffuse, n);
    d1 = d0;
    bsdf_regularize(&d1);
    assert_memory_equal(&d0, &d1, sizeof d0);
    /* the regularized smooth glass and mirror-smooth conductor: sampling against pdf, energy */
    Material smooth_metal = make_material(MATERIAL_CONDUCTOR, 0.0f, 1.0f);
    const Material *ms[2] = {&glass, &smooth_metal};
    for (int k = 0; k < 2; k++) {
        Bsdf r;
        bsdf_init(&r, ms[k], n);
        bsdf_regularize(&r);
        Pcg32 rng;
        pcg32_seed(&rng, 77u, (uint64_t)k);
        for (int j = 0; j < 3; j++) {
            float ct = 0.9f - 0.35f * (float)j;
            Vec3 wo = v3(sqrtf(1.0f - ct * ct), 0.0f, ct);
            double sum = 0.0;
            const int N = 200000;
            for (int i = 0; i < N; i++) {
                BsdfSample bs;
                float uc = pcg32_float(&rng);
                Vec2 u = pcg32_v2(&rng);
                if (!bsdf_sample(&r, wo, uc, u, &bs)) continue;
                assert_false(bs.delta);
                float pdf = bsdf_pdf(&r, wo, bs.wi);
                if (!(fabsf(pdf - bs.pdf_w) <= 2e-3f * bs.pdf_w + 1e-6f))
                    fail_msg("material %d: sample pdf %g, bsdf_pdf %g", k, (double)bs.pdf_w, (double)pdf);
                sum += (double)color_luminance(bs.weight);
            }
            double albedo = sum / N;
            if (!(albedo <= 1.0 + 4.0 * 0.01)) fail_msg("material %d, cos %g: albedo %g above 1", k, (double)ct, albedo);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_all_samplers),
        cmocka_unit_test(test_fresnel_conductor_complex),
        cmocka_unit_test(test_fresnel_diffuse_reflectance),
        cmocka_unit_test(test_white_furnace),
        cmocka_unit_test(test_transmitters_furnace),
        cmocka_unit_test(test_rough_dielectric_energy_loss),
        cmocka_unit_test(test_reciprocity),
        cmocka_unit_test(test_eval_pdfs_matches_calls),
        cmocka_unit_test(test_plain_diffuse_matches_general),
        cmocka_unit_test(test_init_inline_matches_general),
        cmocka_unit_test(test_transmission_adjoint),
        cmocka_unit_test(test_plastic_coat_table),
        cmocka_unit_test(test_ggx_anisotropic_normalisation),
        cmocka_unit_test(test_anisotropic_tangent),
        cmocka_unit_test(test_anisotropic_furnace),
        cmocka_unit_test(test_regularize),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
