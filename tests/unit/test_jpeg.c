/* io/jpeg.c: JPEG decoding through libjpeg-turbo. Inputs are written by libjpeg's own
 * compressor (baseline, progressive, grey, 4:2:0, CMYK, hand-made scan scripts); checks:
 * pixels within the codec's error of the source, located errors for corrupt data
 * (libjpeg's warnings included) and the progressive scan limit. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <cmocka.h>
#include <jpeglib.h>

#include "io/jpeg.h"

typedef struct Encoded {
    unsigned char *data;
    unsigned long size;
} Encoded;

/* A smooth test pattern (a gradient per channel): JPEG at quality 100 keeps it within a
 * few levels, so a decode error shows as a large difference. */
static unsigned char pattern(int x, int y, int c) { return (unsigned char)(x * 3 + y * 2 + c * 30 + 20); } /* x < 38, y < 22 */

/* Encodes w x h pixels of `components` channels in colour space `in` (the pattern, or the
 * constant `fill` if non-NULL), 4:4:4 unless subsample, with libjpeg's default progression
 * when progressive, or the scan script `scans` (n_scans entries) when given. */
static Encoded encode(int w, int h, int components, J_COLOR_SPACE in, const unsigned char *fill, int progressive,
                      int subsample, const jpeg_scan_info *scans, int n_scans)
{
    struct jpeg_compress_struct c;
    struct jpeg_error_mgr e;
    Encoded out = {NULL, 0};
    c.err = jpeg_std_error(&e);
    jpeg_create_compress(&c);
    jpeg_mem_dest(&c, &out.data, &out.size);
    c.image_width = (JDIMENSION)w;
    c.image_height = (JDIMENSION)h;
    c.input_components = components;
    c.in_color_space = in;
    jpeg_set_defaults(&c);
    jpeg_set_quality(&c, 100, TRUE);
    if (components == 3) c.comp_info[0].h_samp_factor = c.comp_info[0].v_samp_factor = subsample ? 2 : 1;
    if (progressive) jpeg_simple_progression(&c);
    if (scans) {
        c.scan_info = scans;
        c.num_scans = n_scans;
    }
    jpeg_start_compress(&c, TRUE);
    unsigned char *row = malloc((size_t)w * (size_t)components);
    assert_non_null(row);
    for (int y = 0; y < h; y++) {
        for (int x = 0; x < w; x++)
            for (int k = 0; k < components; k++) row[x * components + k] = fill ? fill[k] : pattern(x, y, k);
        JSAMPROW r = row;
        jpeg_write_scanlines(&c, &r, 1);
    }
    free(row);
    jpeg_finish_compress(&c);
    jpeg_destroy_compress(&c);
    return out;
}

/* The largest difference between a decode and the pattern. */
static int max_error(const unsigned char *px, int w, int h, int ch)
{
    int worst = 0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++)
            for (int k = 0; k < ch; k++) {
                int d = abs((int)px[(y * w + x) * ch + k] - (int)pattern(x, y, k));
                if (d > worst) worst = d;
            }
    return worst;
}

static void test_colour_and_grey(void **state)
{
    (void)state;
    /* baseline 4:4:4, progressive 4:4:4, baseline 4:2:0 (odd size: partial MCUs), grey */
    static const struct { int w, h, comps, prog, sub, tol; } cases[] = {
        {37, 21, 3, 0, 0, 3}, {37, 21, 3, 1, 0, 3}, {37, 21, 3, 0, 1, 3}, {37, 21, 1, 1, 0, 3}};
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        Encoded j = encode(cases[i].w, cases[i].h, cases[i].comps, cases[i].comps == 3 ? JCS_RGB : JCS_GRAYSCALE,
                           NULL, cases[i].prog, cases[i].sub, NULL, 0);
        unsigned char *px = NULL;
        int w = 0, h = 0, ch = 0;
        CstError err;
        assert_int_equal(jpeg_info("t.jpg", j.data, j.size, &w, &h, &err), CST_OK);
        assert_int_equal(w, cases[i].w);
        assert_int_equal(h, cases[i].h);
        assert_int_equal(jpeg_decode("t.jpg", j.data, j.size, &px, &w, &h, &ch, &err), CST_OK);
        assert_int_equal(w, cases[i].w);
        assert_int_equal(h, cases[i].h);
        assert_int_equal(ch, cases[i].comps);
        /* A linear ramp survives 4:2:0 too: fancy upsampling interpolates it back. */
        int e = max_error(px, w, h, ch);
        if (e > cases[i].tol) fail_msg("case %zu: max error %d > %d", i, e, cases[i].tol);
        free(px);
        free(j.data);
    }
}

/* Adobe CMYK as libjpeg writes it: R = C K / 255 on the stored values (stb_image's rule). */
static void test_cmyk(void **state)
{
    (void)state;
    static const unsigned char cmyk[4] = {200, 100, 50, 128};
    Encoded j = encode(16, 16, 4, JCS_CMYK, cmyk, 0, 0, NULL, 0);
    unsigned char *px = NULL;
    int w = 0, h = 0, ch = 0;
    CstError err;
    assert_int_equal(jpeg_decode("c.jpg", j.data, j.size, &px, &w, &h, &ch, &err), CST_OK);
    assert_int_equal(ch, 3);
    for (int k = 0; k < 3; k++) {
        int want = (cmyk[k] * cmyk[3] + 127) / 255;
        assert_true(abs((int)px[(5 * 16 + 7) * 3 + k] - want) <= 2);
    }
    free(px);
    free(j.data);
}

/* A file cut inside its scan: libjpeg's "premature end" warning is an error, located. */
static void test_truncated(void **state)
{
    (void)state;
    Encoded j = encode(64, 64, 3, JCS_RGB, NULL, 0, 0, NULL, 0);
    unsigned char *px = (unsigned char *)"x";
    int w = 0, h = 0, ch = 0;
    CstError err;
    assert_int_equal(jpeg_decode("cut.jpg", j.data, j.size * 3 / 4, &px, &w, &h, &ch, &err), CST_ERR_PARSE);
    assert_null(px);
    assert_non_null(strstr(err.msg, "cut.jpg: cannot decode the JPEG (libjpeg-turbo, at or after byte "));
    assert_non_null(strstr(err.msg, "Premature end of JPEG file"));
    /* only the header: jpeg_info reads it, jpeg_decode fails */
    assert_int_equal(jpeg_info("cut.jpg", j.data, 700, &w, &h, &err), CST_OK);
    assert_int_equal(jpeg_decode("cut.jpg", j.data, 700, &px, &w, &h, &ch, &err), CST_ERR_PARSE);
    /* no SOI at all */
    assert_int_equal(jpeg_info("x.jpg", (const unsigned char *)"\xff\xd9junk", 6, &w, &h, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "x.jpg: cannot decode the JPEG"));
    free(j.data);
}

/* A valid grey progressive script of `al + 1` successive-approximation scans for the DC
 * and for each of the 63 AC coefficients: 64 (al + 1) scans. */
static int script(jpeg_scan_info *s, int al)
{
    int n = 0;
    for (int k = 0; k < 64; k++)
        for (int a = al; a >= 0; a--) {
            s[n].comps_in_scan = 1;
            s[n].component_index[0] = 0;
            s[n].Ss = s[n].Se = k;
            s[n].Ah = a == al ? 0 : a + 1;
            s[n].Al = a;
            n++;
        }
    return n;
}

static void test_scan_limit(void **state)
{
    (void)state;
    static jpeg_scan_info scans[64 * 11];
    unsigned char *px = NULL;
    int w = 0, h = 0, ch = 0;
    CstError err;
    /* 448 scans: within the limit, and decoded exactly as a one-scan file */
    int n = script(scans, 6);
    assert_true(n <= JPEG_MAX_SCANS);
    Encoded j = encode(16, 8, 1, JCS_GRAYSCALE, NULL, 1, 0, scans, n);
    assert_int_equal(jpeg_decode("p.jpg", j.data, j.size, &px, &w, &h, &ch, &err), CST_OK);
    assert_true(max_error(px, w, h, ch) <= 3);
    free(px);
    free(j.data);
    /* 704 scans: refused */
    n = script(scans, 10);
    assert_true(n > JPEG_MAX_SCANS);
    j = encode(16, 8, 1, JCS_GRAYSCALE, NULL, 1, 0, scans, n);
    assert_int_equal(jpeg_decode("p.jpg", j.data, j.size, &px, &w, &h, &ch, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "p.jpg: cannot decode the JPEG (libjpeg-turbo, at or after byte "));
    assert_non_null(strstr(err.msg, "a progressive JPEG of more than 500 scans"));
    free(j.data);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_colour_and_grey),
        cmocka_unit_test(test_cmyk),
        cmocka_unit_test(test_truncated),
        cmocka_unit_test(test_scan_limit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
