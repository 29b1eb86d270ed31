/* The measured material (materials/measured.c) on files this test writes (the corpus's
 * .bsdf files are not available): the RGL tensor reader (io/tensor.c) and the .bsdf
 * checks (a valid file, its RGB variant, every truncation, each structural and value
 * error with its location); and the tabulated BRDF of a rough GGX conductor written in
 * the Dupuy & Jakob parameterisation: chi-square of its sampling against its pdf, its
 * albedo against the analytic conductor's, spectral evaluation and the RGB conversion. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/tensor.h"
#include "materials/measured.h"
#include "core/rng.h"
#include "materials/bsdf.h"
#include "materials/bsdf_lobe.h"
#include "materials/fresnel.h"
#include "materials/material.h"
#include "materials/microfacet.h"
#include "scene/scene.h"
#include "unit/chi2.h"
#include "unit/scratch_dir.h"

#define NELEM(a) ((int)(sizeof(a) / sizeof((a)[0])))

#define PI_F 3.14159265f

/* ------------------------------------------------------------------ a tensor file writer */

typedef struct WField {
    const char *name;
    int dtype, ndim;
    uint64_t shape[5];
    const void *data; /* count x dtype size bytes, little-endian (the test runs on x86) */
} WField;

static void put(uint8_t **p, uint64_t v, int n)
{
    for (int i = 0; i < n; i++) *(*p)++ = (uint8_t)(v >> (8 * i));
}

static uint64_t wcount(const WField *f)
{
    uint64_t c = 1;
    for (int d = 0; d < f->ndim; d++) c *= f->shape[d];
    return c;
}

/* Writes the fields as a tensor file (header, then the data in field order); returns a
 * malloc'ed buffer and its size. */
static uint8_t *write_tensor(const WField *f, int n, size_t *len)
{
    size_t header = 18, total;
    for (int i = 0; i < n; i++) header += 2 + strlen(f[i].name) + 2 + 1 + 8 + 8 * (size_t)f[i].ndim;
    total = header;
    for (int i = 0; i < n; i++) total += (size_t)wcount(&f[i]) * tensor_dtype_size(f[i].dtype);
    uint8_t *buf = calloc(total, 1), *p = buf;
    assert_non_null(buf);
    memcpy(p, "tensor_file", 12);
    p += 12;
    put(&p, 1, 1);
    put(&p, 0, 1);
    put(&p, (uint64_t)n, 4);
    size_t off = header;
    for (int i = 0; i < n; i++) {
        put(&p, strlen(f[i].name), 2);
        memcpy(p, f[i].name, strlen(f[i].name));
        p += strlen(f[i].name);
        put(&p, (uint64_t)f[i].ndim, 2);
        put(&p, (uint64_t)f[i].dtype, 1);
        put(&p, off, 8);
        for (int d = 0; d < f[i].ndim; d++) put(&p, f[i].shape[d], 8);
        size_t bytes = (size_t)wcount(&f[i]) * tensor_dtype_size(f[i].dtype);
        memcpy(buf + off, f[i].data, bytes);
        off += bytes;
    }
    *len = total;
    return buf;
}

/* ------------------------------------------------------------------ a GGX table */

enum { NT = 4, NPHI = 2, RES = 4, NL = 3, NDF_W = 8, NDF_H = 6 };
static const float ALPHA = 0.3f;

/* pbrt-v4's unit-square coordinates: u = sqrt(theta 2 / pi) (theta2u), phi over 2 pi. */
static float u2theta(float u) { return u * u * (PI_F / 2.0f); }
static float u2phi(float u) { return (2.0f * u - 1.0f) * PI_F; }

typedef struct Tables {
    float theta_i[NT], phi_i[NPHI], wl[NL];
    float ndf[NDF_H][NDF_W], sigma[NDF_H][NDF_W];
    float vndf[NPHI][NT][RES][RES], lum[NPHI][NT][RES][RES], spec[NPHI][NT][NL][RES][RES],
        rgb[NPHI][NT][3][RES][RES];
    uint8_t jac, desc[20];
} Tables;

/* The NDF D(m) and the projected area sigma(w) = cos theta (1 + Lambda(w)) = (cos theta +
 * sqrt(cos^2 theta + alpha^2 sin^2 theta)) / 2 of GGX (Heitz 2014 eqs. 18, 86) at each node
 * of the unit square; the rest constant. */
static void fill(Tables *t)
{
    for (int i = 0; i < NT; i++) t->theta_i[i] = u2theta((float)i / (NT - 1));
    t->phi_i[0] = -PI_F;
    t->phi_i[1] = PI_F;
    for (int i = 0; i < NL; i++) t->wl[i] = 400.0f + 150.0f * (float)i;
    for (int y = 0; y < NDF_H; y++)
        for (int x = 0; x < NDF_W; x++) {
            float th = u2theta((float)x / (NDF_W - 1)), ph = u2phi((float)y / (NDF_H - 1));
            Vec3 w = v3(sinf(th) * cosf(ph), sinf(th) * sinf(ph), cosf(th));
            t->ndf[y][x] = ggx_d(w, ALPHA, ALPHA);
            /* cos (1 + Lambda) in the form that stays positive at the horizon */
            float c = fmaxf(w.z, 0.0f), s2 = 1.0f - c * c;
            t->sigma[y][x] = 0.5f * (c + sqrtf(c * c + ALPHA * ALPHA * s2));
        }
    for (int a = 0; a < NPHI; a++)
        for (int b = 0; b < NT; b++)
            for (int y = 0; y < RES; y++)
                for (int x = 0; x < RES; x++) {
                    t->vndf[a][b][y][x] = t->lum[a][b][y][x] = 1.0f;
                    for (int l = 0; l < NL; l++) t->spec[a][b][l][y][x] = 0.5f + 0.1f * (float)l;
                    for (int l = 0; l < 3; l++) t->rgb[a][b][l][y][x] = 0.25f * (float)(l + 1);
                }
    t->jac = 1;
    memcpy(t->desc, "GGX alpha 0.3 table", 20);
}

enum { F_THETA, F_PHI, F_NDF, F_SIGMA, F_VNDF, F_LUM, F_DESC, F_JAC, F_SPEC, F_WL, NF };

static void fields(const Tables *t, WField *f, bool rgb)
{
    f[F_THETA] = (WField){"theta_i", TENSOR_F32, 1, {NT}, t->theta_i};
    f[F_PHI] = (WField){"phi_i", TENSOR_F32, 1, {NPHI}, t->phi_i};
    f[F_NDF] = (WField){"ndf", TENSOR_F32, 2, {NDF_H, NDF_W}, t->ndf};
    f[F_SIGMA] = (WField){"sigma", TENSOR_F32, 2, {NDF_H, NDF_W}, t->sigma};
    f[F_VNDF] = (WField){"vndf", TENSOR_F32, 4, {NPHI, NT, RES, RES}, t->vndf};
    f[F_LUM] = (WField){"luminance", TENSOR_F32, 4, {NPHI, NT, RES, RES}, t->lum};
    f[F_DESC] = (WField){"description", TENSOR_U8, 1, {20}, t->desc};
    f[F_JAC] = (WField){"jacobian", TENSOR_U8, 1, {1}, &t->jac};
    f[F_SPEC] = rgb ? (WField){"rgb", TENSOR_F32, 5, {NPHI, NT, 3, RES, RES}, t->rgb}
                    : (WField){"spectra", TENSOR_F32, 5, {NPHI, NT, NL, RES, RES}, t->spec};
    f[F_WL] = (WField){"wavelengths", TENSOR_F32, 1, {NL}, t->wl};
}

static Tables *tables(void)
{
    static Tables t;
    fill(&t);
    return &t;
}

/* Expects measured_read to fail with `status` and a message containing `what`. */
static void expect_fail(const uint8_t *buf, size_t len, CstStatus status, const char *what)
{
    MeasuredData m;
    CstError err = {0};
    CstStatus st = measured_read("t.bsdf", buf, len, &m, &err);
    if (st != status || strncmp(err.msg, "t.bsdf: ", 8) != 0 || (what && !strstr(err.msg, what)))
        fail_msg("got %s \"%s\"; expected %s with \"%s\"", cst_status_name(st), err.msg, cst_status_name(status),
                 what ? what : "");
    assert_null(m.ndf);
}


/* ------------------------------------------------------------------ a tabulated GGX conductor
 * The generator of the measured BRDF tests: an isotropic rough conductor (GGX alpha GA,
 * gold's complex IOR per RGB channel) in the Dupuy & Jakob parameterisation, written as a
 * .bsdf and read back. theta_i nodes u-spaced (theta = u^2 pi / 2), phi_i two nodes; the
 * NDF D over the half vector's unit square, sigma = cos (1 + Lambda); the VNDF table the
 * density of visible normals times the square's Jacobian 2 pi^2 u sin theta; luminance and
 * R over the VNDF warp's sample space: R = F G2 / G1(wo) at the half vector that sample
 * maps to (f |cos_i| = R D / (4 sigma(wo)) is then the microfacet BRDF), luminance its
 * channels' mean. The spectral variant puts the blue, green and red channels' IOR at
 * 450, 550 and 650 nm. */
enum { GT = 16, GR = 24, GN = 32 };
static const float GA = 0.3f;

typedef struct GgxTables {
    float theta[GT], phi[2], wl[3];
    float ndf[GN][GN], sigma[GN][GN];
    float vndf[2][GT][GR][GR], lum[2][GT][GR][GR], refl[2][GT][3][GR][GR];
    uint8_t jac, desc[8];
} GgxTables;

static Vec3 dir(float theta, float phi) { return v3(sinf(theta) * cosf(phi), sinf(theta) * sinf(phi), cosf(theta)); }

static GgxTables *ggx_tables(void)
{
    static GgxTables t;
    Color eta, k;
    assert_true(material_metal("gold", &eta, &k));
    for (int i = 0; i < GT; i++) t.theta[i] = u2theta((float)i / (GT - 1)) * 0.9999f;
    t.phi[0] = -PI_F, t.phi[1] = PI_F;
    t.wl[0] = 450.0f, t.wl[1] = 550.0f, t.wl[2] = 650.0f;
    for (int y = 0; y < GN; y++)
        for (int x = 0; x < GN; x++) {
            Vec3 w = dir(u2theta((float)x / (GN - 1)), u2phi((float)y / (GN - 1)));
            t.ndf[y][x] = ggx_d(w, GA, GA);
            float c = fmaxf(w.z, 0.0f);
            t.sigma[y][x] = 0.5f * (c + sqrtf(c * c + GA * GA * (1.0f - c * c)));
        }
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < GT; b++) {
            Vec3 wo = dir(t.theta[b], 0.0f);
            if (wo.z < 1e-3f) wo = v3_normalize(v3(wo.x, wo.y, 1e-3f));
            for (int y = 0; y < GR; y++)
                for (int x = 0; x < GR; x++) {
                    float th = u2theta((float)x / (GR - 1));
                    Vec3 m = dir(th, u2phi((float)y / (GR - 1)));
                    t.vndf[a][b][y][x] = fmaxf(ggx_visible_pdf(wo, m, GA, GA) * fmaxf(v3_dot(wo, m), 0.0f) /
                                                   fmaxf(fabsf(v3_dot(wo, m)), 1e-30f),
                                               0.0f) * 2.0f * PI_F * PI_F * ((float)x / (GR - 1)) * sinf(th);
                }
        }
    /* luminance and R need the VNDF warp: build it, then map each sample node to its
     * half vector */
    PLinear2D vw;
    CstError err = {0};
    const int sizes[2] = {2, GT};
    const float *vals[2] = {t.phi, t.theta};
    assert_int_equal(pl2d_init(&vw, &t.vndf[0][0][0][0], GR, GR, 2, sizes, vals, true, &err), CST_OK);
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < GT; b++) {
            Vec3 wo = dir(t.theta[b], 0.0f);
            if (wo.z < 1e-3f) wo = v3_normalize(v3(wo.x, wo.y, 1e-3f));
            float prm[2] = {t.phi[a], t.theta[b]};
            for (int y = 0; y < GR; y++)
                for (int x = 0; x < GR; x++) {
                    float pdf;
                    Vec2 um = pl2d_sample(&vw, v2((float)x / (GR - 1), (float)y / (GR - 1)), prm, &pdf);
                    Vec3 m = dir(u2theta(um.x), u2phi(um.y));
                    Vec3 wi = reflect_about(wo, m);
                    float g = wi.z > 0.0f ? ggx_g2(wo, wi, GA, GA) / ggx_g1(wo, GA, GA) : 0.0f;
                    Color F = fresnel_conductor_rgb(fmaxf(v3_dot(wo, m), 0.0f), eta, k);
                    float sum = 0.0f;
                    for (int c = 0; c < 3; c++) {
                        /* spectral variant: channel c at wl[2 - c] (R at 650, B at 450) */
                        t.refl[a][b][c][y][x] = F.c[c] * g;
                        sum += F.c[c] * g;
                    }
                    t.lum[a][b][y][x] = fmaxf(sum / 3.0f, 1e-3f);
                }
        }
    pl2d_free(&vw);
    t.jac = 1;
    memcpy(t.desc, "GGX 0.3", 8);
    return &t;
}

/* The tables as a .bsdf file's bytes: RGB (the rgb field) or spectral (the channels
 * reversed onto 450, 550, 650 nm). */
static uint8_t *ggx_file(bool spectral, size_t *len)
{
    GgxTables *t = ggx_tables();
    static float spec[2][GT][3][GR][GR];
    for (int a = 0; a < 2; a++)
        for (int b = 0; b < GT; b++)
            for (int c = 0; c < 3; c++) memcpy(spec[a][b][c], t->refl[a][b][2 - c], sizeof spec[a][b][c]);
    WField f[] = {{"theta_i", TENSOR_F32, 1, {GT}, t->theta},
                  {"phi_i", TENSOR_F32, 1, {2}, t->phi},
                  {"ndf", TENSOR_F32, 2, {GN, GN}, t->ndf},
                  {"sigma", TENSOR_F32, 2, {GN, GN}, t->sigma},
                  {"vndf", TENSOR_F32, 4, {2, GT, GR, GR}, t->vndf},
                  {"luminance", TENSOR_F32, 4, {2, GT, GR, GR}, t->lum},
                  {"description", TENSOR_U8, 1, {8}, t->desc},
                  {"jacobian", TENSOR_U8, 1, {1}, &t->jac},
                  spectral ? (WField){"spectra", TENSOR_F32, 5, {2, GT, 3, GR, GR}, spec}
                           : (WField){"rgb", TENSOR_F32, 5, {2, GT, 3, GR, GR}, t->refl},
                  {"wavelengths", TENSOR_F32, 1, {3}, t->wl}};
    return write_tensor(f, spectral ? 10 : 9, len);
}

/* The same read back as a MeasuredBsdf. */
static void ggx_bsdf(bool spectral, MeasuredBsdf *out)
{
    size_t len;
    uint8_t *buf = ggx_file(spectral, &len);
    MeasuredData m;
    CstError err = {0};
    if (measured_read("ggx.bsdf", buf, len, &m, &err) != CST_OK) fail_msg("%s", err.msg);
    if (measured_bsdf_init(out, &m, &err) != CST_OK) fail_msg("%s", err.msg);
    measured_free(&m);
    free(buf);
}

static Vec3 wo_at(float c, float az) { float s = sqrtf(1.0f - c * c); return v3(s * cosf(az), s * sinf(az), c); }

/* Chi-square of measured_sample against measured_pdf: cells uniform in (cos theta, phi)
 * over the hemisphere, each expectation the pdf integrated by a 12 x 12 midpoint rule, and
 * one cell for failed samples (1 - the integral); the sample's weight against eval / pdf. */
static void test_measured_chi2(void **state)
{
    (void)state;
    enum { N = 200000, HT = 16, HP = 32, SUB = 12 };
    static const float COS[] = {0.95f, 0.6f, 0.25f};
    static const float AZ[] = {0.3f, 2.0f, -2.8f};
    MeasuredBsdf b;
    ggx_bsdf(false, &b);
    double worst_p = 1.0, worst_w = 0.0;
    const int ncase = NELEM(COS) * NELEM(AZ);
    for (int ci = 0; ci < NELEM(COS); ci++)
        for (int ai = 0; ai < NELEM(AZ); ai++) {
            Vec3 wo = wo_at(COS[ci], AZ[ai]);
            static double obs[HT * HP + 1], expd[HT * HP + 1];
            memset(obs, 0, sizeof obs);
            Pcg32 r;
            pcg32_seed(&r, 4000u + (uint64_t)(ci * 10 + ai), 3u);
            for (int s = 0; s < N; s++) {
                Vec3 wi;
                Color w;
                float pdf;
                if (!measured_sample(&b, wo, pcg32_v2(&r), NULL, &wi, &w, &pdf)) { obs[HT * HP] += 1.0; continue; }
                Color f = measured_eval(&b, wo, wi, NULL);
                for (int c = 0; c < 3; c++) worst_w = fmax(worst_w, fabs((double)w.c[c] - (double)f.c[c] / (double)pdf) / fmax((double)w.c[c], 1e-6));
                double ph = atan2((double)wi.y, (double)wi.x) + 3.14159265358979;
                int it = (int)((double)wi.z * HT), ip = (int)(ph / (2.0 * 3.14159265358979) * HP);
                obs[(it < HT ? it : HT - 1) * HP + (ip < HP ? ip : HP - 1)] += 1.0;
            }
            double total = 0.0;
            for (int it = 0; it < HT; it++)
                for (int ip = 0; ip < HP; ip++) {
                    double sum = 0.0;
                    for (int a = 0; a < SUB; a++)
                        for (int c = 0; c < SUB; c++) {
                            double z = (it + (a + 0.5) / SUB) / HT, ph = -3.14159265358979 + 2.0 * 3.14159265358979 * (ip + (c + 0.5) / SUB) / HP;
                            double sn = sqrt(1.0 - z * z);
                            sum += (double)measured_pdf(&b, wo, v3((float)(sn * cos(ph)), (float)(sn * sin(ph)), (float)z));
                        }
                    double cell = sum / (SUB * SUB) * (1.0 / HT) * (2.0 * 3.14159265358979 / HP);
                    expd[it * HP + ip] = cell * N;
                    total += cell;
                }
            expd[HT * HP] = fmax(1.0 - total, 0.0) * N;
            for (int i = 0; i <= HT * HP; i++)
                if (expd[i] <= 0.0) expd[i] = 1e-9;
            int dof;
            double stat, outside;
            double p = chi2_pvalue(obs, expd, HT * HP + 1, &dof, &stat, &outside);
            print_message("measured GGX cos_o %.2f az %.1f: chi2 %.1f dof %d p %.3g (pdf integral %.4f, failed %.0f)\n",
                          (double)COS[ci], (double)AZ[ai], stat, dof, p, total, obs[HT * HP]);
            worst_p = fmin(worst_p, p);
            if (!(p > 0.01 / ncase) || outside > 0.0) fail_msg("cos_o %.2f az %.1f: p = %.3g", (double)COS[ci], (double)AZ[ai], p);
        }
    print_message("measured chi-square: %d cases, worst p %.3g; weight vs eval/pdf max relative %.2g\n", ncase, worst_p, worst_w);
    assert_true(worst_w < 1e-5);
    measured_bsdf_free(&b);
}

/* The measured table against the analytic BRDF it tabulates: directional albedos by
 * sampling each (N samples, independent streams) at several incident angles, per channel.
 * Their difference is the tabulation's bias (interpolation between GR^2 sample-space
 * nodes and GT incident angles) plus noise: it must stay within ALBEDO_TOL plus 4 combined
 * standard errors. */
/* Measured worst bias 0.0031 (cos_o 0.25, all channels +0.003; 0.0017 or less above); with
 * 8 theta_i nodes instead of 16 it was 0.028 at cos_o 0.25: tabulation error, shrinking
 * with the resolution, not a bias of the evaluation. */
static const double ALBEDO_TOL = 0.01;
static void test_measured_albedo(void **state)
{
    (void)state;
    enum { N = 200000 };
    static const float COS[] = {0.95f, 0.7f, 0.45f, 0.25f};
    MeasuredBsdf mb;
    ggx_bsdf(false, &mb);
    Material m = {.type = MATERIAL_CONDUCTOR, .albedo = {{1, 1, 1}}, .ior = 1.0f, .roughness = sqrtf(GA)};
    assert_true(material_metal("gold", &m.eta, &m.k));
    Bsdf b;
    bsdf_init(&b, &m, v3(0.0f, 0.0f, 1.0f));
    double worst = 0.0;
    for (int ci = 0; ci < NELEM(COS); ci++) {
        Vec3 wo = wo_at(COS[ci], 0.9f);
        double s1[2][3] = {{0}}, s2[2][3] = {{0}};
        Pcg32 r;
        pcg32_seed(&r, 5000u + (uint64_t)ci, 7u);
        for (int s = 0; s < N; s++) {
            Vec3 wi;
            Color w = color_s(0.0f);
            float pdf;
            if (!measured_sample(&mb, wo, pcg32_v2(&r), NULL, &wi, &w, &pdf)) w = color_s(0.0f);
            BsdfSample bs;
            float uc = pcg32_float(&r);
            Vec2 u = pcg32_v2(&r);
            Color wa = bsdf_sample(&b, wo, uc, u, &bs) ? bs.weight : color_s(0.0f);
            for (int c = 0; c < 3; c++) {
                s1[0][c] += (double)w.c[c], s2[0][c] += (double)w.c[c] * (double)w.c[c];
                s1[1][c] += (double)wa.c[c], s2[1][c] += (double)wa.c[c] * (double)wa.c[c];
            }
        }
        for (int c = 0; c < 3; c++) {
            double a = s1[0][c] / N, e = s1[1][c] / N;
            double se = sqrt(fmax(s2[0][c] / N - a * a, 0.0) / N + fmax(s2[1][c] / N - e * e, 0.0) / N);
            worst = fmax(worst, fabs(a - e));
            print_message("cos_o %.2f channel %d: measured albedo %.5f, analytic %.5f (difference %+.5f, se %.1e)\n",
                          (double)COS[ci], c, a, e, a - e, se);
            if (!(fabs(a - e) <= ALBEDO_TOL + 4.0 * se))
                fail_msg("cos_o %.2f channel %d: measured %.5f vs analytic %.5f", (double)COS[ci], c, a, e);
        }
    }
    print_message("measured vs analytic albedo: worst |difference| %.4f (tolerance %.3f + 4 se)\n", worst, ALBEDO_TOL);
    measured_bsdf_free(&mb);
}

/* Spectral mode: a spectral table evaluated at its nodes' wavelengths is the RGB table's
 * channels (the generator put R, G, B at 650, 550, 450 nm); at load in RGB mode a
 * constant reflectance spectrum becomes that grey (D65 white is sRGB white). */
static void test_measured_spectral(void **state)
{
    (void)state;
    MeasuredBsdf rgb, spec;
    ggx_bsdf(false, &rgb);
    ggx_bsdf(true, &spec);
    static const float lambda[4] = {650.0f, 550.0f, 450.0f, 550.0f};
    Pcg32 r;
    pcg32_seed(&r, 3u, 3u);
    double worst = 0.0;
    for (int k = 0; k < 2000; k++) {
        Vec3 wo = warp_cosine_hemisphere(pcg32_v2(&r)), wi = warp_cosine_hemisphere(pcg32_v2(&r));
        Color a = measured_eval(&rgb, wo, wi, NULL), b = measured_eval(&spec, wo, wi, lambda);
        for (int c = 0; c < 4; c++) worst = fmax(worst, fabs((double)a.c[c] - (double)b.c[c]) / fmax((double)a.c[c], 1e-6));
    }
    print_message("spectral table at its nodes vs RGB table: max relative difference %.2g\n", worst);
    assert_true(worst < 1e-5);
    measured_bsdf_free(&rgb);
    measured_bsdf_free(&spec);
    /* constant 0.5 over 380..780 nm (two nodes): grey 0.5 in RGB */
    Tables *t = tables();
    for (int a = 0; a < NPHI; a++)
        for (int b = 0; b < NT; b++)
            for (int l = 0; l < NL; l++)
                for (int y = 0; y < RES; y++)
                    for (int x = 0; x < RES; x++) t->spec[a][b][l][y][x] = 0.5f;
    t->wl[0] = 380.0f, t->wl[1] = 580.0f, t->wl[2] = 780.0f;
    WField f[NF];
    fields(t, f, false);
    size_t len;
    uint8_t *buf = write_tensor(f, NF, &len);
    MeasuredData m;
    CstError err = {0};
    assert_int_equal(measured_read("t.bsdf", buf, len, &m, &err), CST_OK);
    MeasuredBsdf g;
    assert_int_equal(measured_bsdf_init(&g, &m, &err), CST_OK);
    float p[3] = {0.0f, 0.3f, 0.0f};
    for (int c = 0; c < 3; c++) {
        p[2] = (float)c;
        float v = pl2d_eval(&g.refl_rgb, v2(0.4f, 0.6f), p);
        print_message("grey 0.5 spectrum -> channel %d: %.5f\n", c, (double)v);
        assert_true(fabsf(v - 0.5f) < 5e-3f);
    }
    measured_bsdf_free(&g);
    measured_free(&m);
    free(buf);
}

/* ------------------------------------------------------------------ the material */

static int g_warnings;
static void count_warning(void *user, CstWarningCode code, const char *msg)
{
    (void)user;
    (void)msg;
    if (code == CST_WARN_MISSING_FILE) g_warnings++;
}

static void write_file(const char *path, const uint8_t *buf, size_t len)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(buf, 1, len, f), len);
    fclose(f);
}

/* The measured material through the loaders: the JSON "measured" type and pbrt-v4's
 * "measured" (one table per file however many materials name it; a missing file warned
 * about and replaced by diffuse; a malformed one a located CST_ERR_PARSE); scene_bsdf's
 * BSDF is measured_eval's function, in RGB and at a path's wavelengths. */
static void test_material(void **state)
{
    (void)state;
    assert_int_equal(scratch_dir_make("/tmp/caustic-measured-XXXXXX"), 0);
    char good[300], bad[300], scene_path[300];
    tpath(good, sizeof good, "ggx.bsdf");
    tpath(bad, sizeof bad, "bad.bsdf");
    tpath(scene_path, sizeof scene_path, "s.pbrt");
    size_t len;
    uint8_t *buf = ggx_file(true, &len);
    write_file(good, buf, len);
    write_file(bad, buf, len - 7); /* the last field's data cut short */
    free(buf);
    /* JSON, the file relative to the scene */
    char text[2048];
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}, "
             "\"materials\": {\"m\": {\"type\": \"measured\", \"file\": \"ggx.bsdf\"}}, "
             "\"shapes\": [{\"type\": \"quad\", \"material\": \"m\", \"vertices\": [[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}]}");
    char json_name[300];
    tpath(json_name, sizeof json_name, "s.json");
    CstScene *s = NULL;
    CstError err = {0};
    if (cst_scene_load_json_string(text, strlen(text), json_name, &s, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_measured, 1);
    assert_true(s->materials[0].type == MATERIAL_MEASURED && s->materials[0].measured == s->measured[0]);
    SurfaceHit sh = {0};
    sh.p = v3(0.5f, 0.5f, 0.0f);
    sh.ng = sh.ns = v3(0.0f, 0.0f, 1.0f);
    sh.material = 0;
    Bsdf b;
    scene_bsdf(s, &sh, NULL, &b);
    Vec3 wo = wo_at(0.6f, 0.4f), wi = wo_at(0.8f, 2.9f);
    Color f = bsdf_eval(&b, wo, wi), want = measured_eval(s->measured[0], wo, wi, NULL);
    assert_true(f.c[0] > 0.0f && memcmp(&f, &want, sizeof f) == 0);
    assert_true(fabsf(bsdf_pdf(&b, wo, wi) - measured_pdf(s->measured[0], wo, wi)) == 0.0f);
    /* explain's lobe (BsdfSample.lobe): the table is one reflection lobe, sampled on wo's side */
    int sampled = 0;
    for (int i = 0; i < 64; i++) {
        BsdfSample bs;
        if (!bsdf_sample(&b, wo, (i + 0.5f) / 64.0f, v2((i * 0.618034f) - floorf(i * 0.618034f), (i + 0.5f) / 64.0f), &bs))
            continue;
        sampled++;
        assert_int_equal(bs.lobe, BSDF_LOBE_GLOSSY_REFLECTION);
        assert_string_equal(bsdf_lobe_name(bs.lobe), "glossy reflection");
        assert_true(bs.wi.z * wo.z > 0.0f);
    }
    assert_true(sampled >= 32);
    Wavelengths wl = {{450.0f, 500.0f, 600.0f, 700.0f}, {1, 1, 1, 1}};
    scene_bsdf(s, &sh, &wl, &b);
    f = bsdf_eval(&b, wo, wi), want = measured_eval(s->measured[0], wo, wi, wl.lambda);
    assert_true(f.c[3] > 0.0f && memcmp(&f, &want, sizeof f) == 0);
    cst_scene_destroy(s);
    /* JSON errors: no "file", a malformed file (located at "file" by the loader) */
    const char *no_file = "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}, "
                          "\"materials\": {\"m\": {\"type\": \"measured\"}}, \"shapes\": []}";
    s = NULL;
    assert_int_equal(cst_scene_load_json_string(no_file, strlen(no_file), json_name, &s, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "missing key \"file\""));
    snprintf(text, sizeof text,
             "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}, "
             "\"materials\": {\"m\": {\"type\": \"measured\", \"file\": \"bad.bsdf\"}}, \"shapes\": []}");
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), json_name, &s, &err), CST_ERR_PARSE);
    print_message("malformed .bsdf from JSON: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "bad.bsdf: byte "));
    /* pbrt: two materials, one file; a missing file; a malformed one */
    snprintf(text, sizeof text,
             "Camera \"perspective\"\nWorldBegin\n"
             "MakeNamedMaterial \"a\" \"string type\" \"measured\" \"string filename\" \"ggx.bsdf\"\n"
             "Material \"measured\" \"string filename\" \"%s\"\n"
             "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n"
             "NamedMaterial \"a\"\n"
             "Shape \"trianglemesh\" \"point3 P\" [0 0 1 1 0 1 0 1 1] \"integer indices\" [0 1 2]\n"
             "Material \"measured\" \"string filename\" \"missing.bsdf\"\n"
             "Shape \"trianglemesh\" \"point3 P\" [0 0 2 1 0 2 0 1 2] \"integer indices\" [0 1 2]\n", good);
    CstLoadOptions opt = {.warning = count_warning};
    g_warnings = 0;
    if (cst_scene_load_pbrt_string(text, strlen(text), scene_path, &opt, &s, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(s->num_measured, 1);
    assert_int_equal(g_warnings, 1);
    assert_int_equal(s->materials[s->tri_info[0].material].type, MATERIAL_MEASURED);
    assert_int_equal(s->materials[s->tri_info[1].material].type, MATERIAL_MEASURED);
    assert_int_equal(s->materials[s->tri_info[2].material].type, MATERIAL_DIFFUSE);
    cst_scene_destroy(s);
    snprintf(text, sizeof text,
             "Camera \"perspective\"\nWorldBegin\nMaterial \"measured\" \"string filename\" \"bad.bsdf\"\n"
             "Shape \"trianglemesh\" \"point3 P\" [0 0 0 1 0 0 0 1 0] \"integer indices\" [0 1 2]\n");
    s = NULL;
    assert_int_equal(cst_scene_load_pbrt_string(text, strlen(text), scene_path, NULL, &s, &err), CST_ERR_PARSE);
    assert_null(s);
    print_message("malformed .bsdf: %s\n", err.msg);
    assert_non_null(strstr(err.msg, "bad.bsdf: byte "));
    assert_non_null(strstr(err.msg, "runs past the end of the file"));
    scratch_dir_remove();
}

/* ------------------------------------------------------------------ file tests */

static void test_read_valid(void **state)
{
    (void)state;
    Tables *t = tables();
    WField f[NF];
    for (int rgb = 0; rgb < 2; rgb++) {
        fields(t, f, rgb);
        size_t len;
        uint8_t *buf = write_tensor(f, rgb ? NF - 1 : NF, &len);
        MeasuredData m;
        CstError err = {0};
        if (measured_read("t.bsdf", buf, len, &m, &err) != CST_OK) fail_msg("%s", err.msg);
        assert_true(m.n_theta == NT && m.n_phi == NPHI && m.res == RES && m.isotropic && m.jacobian);
        assert_true(m.ndf_w == NDF_W && m.ndf_h == NDF_H && m.sigma_w == NDF_W && m.sigma_h == NDF_H);
        assert_string_equal(m.description, "GGX alpha 0.3 table");
        assert_memory_equal(m.ndf, t->ndf, sizeof t->ndf);
        assert_memory_equal(m.sigma, t->sigma, sizeof t->sigma);
        assert_memory_equal(m.theta_i, t->theta_i, sizeof t->theta_i);
        if (rgb) {
            assert_true(m.n_lambda == 0 && !m.spectra && m.rgb);
            assert_true(m.rgb[RES * RES] == 0.5f);
        } else {
            assert_true(m.n_lambda == NL && m.wavelengths[2] == 700.0f && !m.rgb);
            assert_memory_equal(m.spectra, t->spec, sizeof t->spec);
        }
        /* the tabulated NDF is GGX's: normalised at theta = 0 to 1 / (pi alpha^2) */
        assert_true(fabsf(m.ndf[0] * PI_F * ALPHA * ALPHA - 1.0f) < 1e-5f);
        measured_free(&m);
        free(buf);
    }
}

/* Every prefix of a valid file is refused with a located message (never a crash or a read
 * past the end: the sanitizer build checks that), and so is the file with bytes appended
 * to its header's field count. */
static void test_truncations(void **state)
{
    (void)state;
    WField f[NF];
    fields(tables(), f, false);
    size_t len;
    uint8_t *buf = write_tensor(f, NF, &len);
    for (size_t n = 0; n < len; n++) {
        uint8_t *copy = malloc(n ? n : 1); /* exactly n bytes, so ASan sees any overread */
        memcpy(copy, buf, n);
        MeasuredData m;
        CstError err = {0};
        CstStatus st = measured_read("t.bsdf", copy, n, &m, &err);
        if (st != CST_ERR_PARSE || strncmp(err.msg, "t.bsdf: ", 8) != 0)
            fail_msg("prefix of %zu bytes: %s \"%s\"", n, cst_status_name(st), err.msg);
        free(copy);
    }
    expect_fail(buf, len - 1, CST_ERR_PARSE, "runs past the end of the file");
    free(buf);
}

static void test_structure_errors(void **state)
{
    (void)state;
    Tables *t = tables();
    WField f[NF];
    size_t len;
    uint8_t *buf;
    fields(t, f, false);
    buf = write_tensor(f, NF, &len);
    buf[0] = 'T';
    expect_fail(buf, len, CST_ERR_PARSE, "byte 0: not a tensor file");
    buf[0] = 't';
    buf[12] = 2;
    expect_fail(buf, len, CST_ERR_PARSE, "byte 12: tensor file version 2.0; expected 1.0");
    buf[12] = 1;
    buf[14] = 0xff, buf[15] = 0xff;
    expect_fail(buf, len, CST_ERR_PARSE, "byte 14: 65535 fields; expected 1 to 256");
    buf[14] = 200, buf[15] = 0;
    expect_fail(buf, 300, CST_ERR_PARSE, "byte 14: 200 fields cannot fit in the file (300 bytes)");
    free(buf);
    /* a missing field, a wrong type, a wrong shape, a duplicate */
    buf = write_tensor(f, NF - 1, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "no field \"wavelengths\"");
    free(buf);
    WField g[NF];
    memcpy(g, f, sizeof g);
    g[F_JAC].dtype = TENSOR_I8;
    buf = write_tensor(g, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"jacobian\" is 1-dimensional int8; expected 1-dimensional uint8");
    free(buf);
    memcpy(g, f, sizeof g);
    g[F_VNDF].shape[1] = NT - 1; /* data still fits: the file is large enough */
    buf = write_tensor(g, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"vndf\" has size 3 along dimension 1; expected 4");
    free(buf);
    memcpy(g, f, sizeof g);
    g[F_WL].name = "ndf";
    buf = write_tensor(g, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "a second field \"ndf\"");
    free(buf);
    /* a field claiming more elements than the file holds */
    memcpy(g, f, sizeof g);
    buf = write_tensor(g, NF, &len);
    size_t at = 18 + 2 + 7 + 2 + 1 + 8; /* theta_i's size */
    buf[at + 7] = 0x40;
    expect_fail(buf, len, CST_ERR_PARSE, "field \"theta_i\" has more float32 values than the file");
    free(buf);
    /* 1-node grids cannot be interpolated */
    memcpy(g, f, sizeof g);
    g[F_NDF].shape[0] = 1;
    buf = write_tensor(g, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"ndf\" has size 1 along dimension 0; expected 2 to 4096");
    free(buf);
}

static void test_value_errors(void **state)
{
    (void)state;
    WField f[NF];
    size_t len;
    Tables *t = tables();
    t->ndf[1][2] = -1.0f;
    fields(t, f, false);
    uint8_t *buf = write_tensor(f, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"ndf\" value 10 (-1) is negative");
    free(buf);
    t = tables();
    t->theta_i[2] = t->theta_i[1];
    buf = write_tensor(f, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"theta_i\" value 2");
    free(buf);
    t = tables();
    t->spec[0][0][0][0][0] = NAN;
    buf = write_tensor(f, NF, &len);
    expect_fail(buf, len, CST_ERR_PARSE, "field \"spectra\" value 0 (nan) is not finite");
    free(buf);
}

/* tensor_value reads every element type, float16 included. */
static void test_tensor_values(void **state)
{
    (void)state;
    const uint16_t h[] = {0x3c00, 0xc000, 0x0001, 0x7c00};  /* 1, -2, 2^-24, inf */
    const int16_t s[] = {-3, 7};
    const double d[] = {0.125};
    WField f[] = {{"h", TENSOR_F16, 1, {4}, h}, {"s", TENSOR_I16, 1, {2}, s}, {"d", TENSOR_F64, 0, {0}, d}};
    size_t len;
    uint8_t *buf = write_tensor(f, 3, &len);
    TensorFile t;
    CstError err = {0};
    assert_int_equal(tensor_read("t.bsdf", buf, len, &t, &err), CST_OK);
    const TensorField *fh = tensor_field(&t, "h"), *fs = tensor_field(&t, "s"), *fd = tensor_field(&t, "d");
    assert_true(fh && fs && fd && fd->count == 1 && fd->ndim == 0);
    assert_true(tensor_value(fh, 0) == 1.0 && tensor_value(fh, 1) == -2.0 && tensor_value(fh, 2) == ldexp(1.0, -24) &&
                isinf(tensor_value(fh, 3)));
    assert_true(tensor_value(fs, 0) == -3.0 && tensor_value(fs, 1) == 7.0 && tensor_value(fd, 0) == 0.125);
    assert_null(tensor_field(&t, "x"));
    tensor_free(&t);
    free(buf);
}

/* The fuzzer's committed seeds (tests/fuzz/corpus/fuzz_bsdf, written by make_corpus.sh's
 * python) are valid files, so the fuzzer starts from inputs that reach the value checks;
 * measured_read_file reads them through the input-file gate. */
static void test_fuzz_seeds(void **state)
{
    (void)state;
    static const char *const seeds[] = {"iso-spectral", "iso-rgb", "aniso-spectral"};
    for (int i = 0; i < 3; i++) {
        char path[512];
        snprintf(path, sizeof path, "%s/tests/fuzz/corpus/fuzz_bsdf/%s", CST_SOURCE_DIR, seeds[i]);
        MeasuredData m;
        CstError err = {0};
        if (measured_read_file(path, &m, &err) != CST_OK) fail_msg("%s", err.msg);
        assert_true(m.isotropic == (i < 2) && (m.n_lambda == 0) == (i == 1));
        measured_free(&m);
    }
    MeasuredData m;
    CstError err = {0};
    assert_int_equal(measured_read_file(CST_SOURCE_DIR "/tests/fuzz/corpus/fuzz_bsdf/none", &m, &err), CST_ERR_IO);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_read_valid),
        cmocka_unit_test(test_truncations),
        cmocka_unit_test(test_structure_errors),
        cmocka_unit_test(test_value_errors),
        cmocka_unit_test(test_tensor_values),
        cmocka_unit_test(test_fuzz_seeds),
        cmocka_unit_test(test_measured_chi2),
        cmocka_unit_test(test_measured_albedo),
        cmocka_unit_test(test_measured_spectral),
        cmocka_unit_test(test_material),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
