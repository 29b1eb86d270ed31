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
#include "unit/chi2.h"

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
    char name[96];
    Material mat;
    float cos_o;
    BsdfTransport mode;
} Case;

static Material make_material(MaterialType t, float roughness, float ior)
{
    Material m = {.type = t, .albedo = {1.0f, 1.0f, 1.0f}, .ior = ior, .roughness = roughness};
    if (t == MATERIAL_CONDUCTOR) assert_true(material_metal("gold", &m.eta, &m.k));
    if (t == MATERIAL_PLASTIC) m.albedo = rgb(0.8f, 0.5f, 0.2f);
    if (t == MATERIAL_DIFFUSE) m.albedo = rgb(0.7f, 0.7f, 0.7f);
    material_prepare(&m);
    return m;
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
    for (int r = 0; r < NELEM(PLASTIC_ROUGHNESS); r++)
        for (int a = 0; a < NELEM(COS_PLASTIC); a++) {
            Case *c = &out[n++];
            c->mat = make_material(MATERIAL_PLASTIC, PLASTIC_ROUGHNESS[r], 1.5f);
            c->cos_o = COS_PLASTIC[a];
            c->mode = BSDF_RADIANCE;
            snprintf(c->name, sizeof c->name, "plastic r=%.2f cos_o=%.2f", (double)PLASTIC_ROUGHNESS[r],
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
    SUB = 10,         /* midpoint sub-samples per cell side for the expected counts */
    SUB_FINE = 80     /* the same in cells with a discontinuity */
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

static Hist make_hist(const Bsdf *b, Vec3 wo, MaterialType type)
{
    Hist h;
    float sgn = wo.z > 0.0f ? 1.0f : -1.0f;
    h.side_sign = sgn;
    Vec3 p0 = v3(-wo.x, -wo.y, wo.z), p1 = v3(0.0f, 0.0f, -sgn);
    Vec3 wt;
    float etap;
    if (type == MATERIAL_DIELECTRIC && refract_about(wo, v3(0.0f, 0.0f, 1.0f), b->eta, &wt, &etap))
        p1 = v3_normalize(wt);
    if (type == MATERIAL_DIFFUSE) p0 = v3(0.0f, 0.0f, sgn);
    h.pole[0] = frame_from_normal(p0);
    h.pole[1] = frame_from_normal(p1);
    h.theta0 = type == MATERIAL_DIFFUSE ? 100.0f : fmaxf(0.5f * b->alpha, 1e-3f);
    if (type == MATERIAL_PLASTIC && b->alpha == 0.0f) h.theta0 = 100.0f;
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
    bsdf_init(&b, &c->mat, test_normal());
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
        Vec2 u = v2(pcg32_float(&rng), pcg32_float(&rng));
        BsdfSample s;
        if (!bsdf_sample_transport(&b, wo, uc, u, c->mode, &s)) { obs[FAIL] += 1.0; continue; }
        if (s.delta) { obs[DELTA] += 1.0; continue; }
        obs[hist_cell(&h, frame_to_local(&b.frame, s.wi))] += 1.0;
        /* The sample's own pdf and weight against eval and pdf. */
        double pdf = (double)bsdf_pdf(&b, wo, s.wi);
        Rgb f = bsdf_eval_transport(&b, wo, s.wi, c->mode);
        double rp = fabs((double)s.pdf - pdf) / fmax(pdf, 1e-30);
        double fw[3] = {(double)f.r, (double)f.g, (double)f.b}, ww[3] = {(double)s.weight.r, (double)s.weight.g,
                                                                          (double)s.weight.b};
        double rw = 0.0;
        for (int k = 0; k < 3; k++) {
            double want = fw[k] / (double)s.pdf;
            rw = fmax(rw, fabs(ww[k] - want) / fmax(fabs(want), 1e-6));
        }
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

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_chi2_all_samplers),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
