/* The measured material's file: the RGL tensor reader (io/tensor.c) and the .bsdf checks
 * (materials/measured.c) on files this test writes (the corpus's .bsdf files are not
 * available): a valid isotropic file tabulating a GGX conductor's NDF and projected area,
 * its RGB variant, every truncation, and each structural and value error with its
 * location. */
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
#include "materials/microfacet.h"

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

/* ------------------------------------------------------------------ tests */

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
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
