/* Unit tests for hostile inputs (issue 25): the regular-file gate of core/file.c, the
 * escaping of messages (core/error.c), the one pixel rule of image inputs
 * (image_check_radiance), checkerboard chains far deeper than any stack, and byte order
 * marks in the JSON and pbrt loaders. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "caustic/caustic.h"
#include "core/error.h"
#include "core/file.h"
#include "io/image_io.h"

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_inputs_XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static void expect_refused(const char *path, const char *kind)
{
    FILE *f = (FILE *)(uintptr_t)1;
    CstError err = {0};
    assert_int_equal(file_open_input(path, &f, NULL, &err), CST_ERR_IO);
    assert_null(f);
    char want[128];
    snprintf(want, sizeof want, "is not a regular file (%s); expected a file", kind);
    if (!strstr(err.msg, want) || !strstr(err.msg, path)) fail_msg("%s: \"%s\" lacks \"%s\"", path, err.msg, want);
    char *text = NULL;
    size_t len = 0;
    assert_int_equal(file_read_all(path, &text, &len, &err), CST_ERR_IO);
    assert_null(text);
}

/* A FIFO without a writer, a symlink to /dev/zero and a directory are refused at once
 * (the FIFO would block an open without O_NONBLOCK; /dev/zero would be read forever). */
static void test_file_gate(void **state)
{
    (void)state;
    char fifo[300], zero[300], reg[300];
    tpath(fifo, sizeof fifo, "fifo");
    tpath(zero, sizeof zero, "zero");
    tpath(reg, sizeof reg, "regular");
    if (mkfifo(fifo, 0600) == 0) expect_refused(fifo, "a FIFO");
    else print_message("skipped the FIFO: mkfifo failed\n");
    if (symlink("/dev/zero", zero) == 0) expect_refused(zero, "a character device");
    expect_refused(g_dir, "a directory");
    /* a regular file, through a symlink too */
    FILE *w = fopen(reg, "wb");
    assert_non_null(w);
    fputs("hello", w);
    fclose(w);
    char link[300];
    tpath(link, sizeof link, "link");
    assert_int_equal(symlink(reg, link), 0);
    char *text = NULL;
    size_t len = 0;
    CstError err = {0};
    assert_int_equal(file_read_all(link, &text, &len, &err), CST_OK);
    assert_int_equal(len, 5);
    assert_string_equal(text, "hello"); /* NUL-terminated past the end */
    free(text);
    FILE *f = NULL;
    uint64_t size = 0;
    assert_int_equal(file_open_input(reg, &f, &size, &err), CST_OK);
    assert_int_equal(size, 5);
    fclose(f);
    char missing[300];
    tpath(missing, sizeof missing, "missing");
    assert_int_equal(file_open_input(missing, &f, NULL, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "cannot open: No such file or directory"));
}

static void expect_escaped(const char *in, const char *want)
{
    CstError err = {0};
    cst_fail(&err, CST_ERR_PARSE, "%s", in);
    assert_string_equal(err.msg, want);
    char again[sizeof err.msg];
    memcpy(again, err.msg, sizeof again);
    cst_escape_message(again, sizeof again); /* idempotent: wrapping does not escape twice */
    assert_string_equal(again, want);
}

static void test_escape(void **state)
{
    (void)state;
    expect_escaped("plain: text", "plain: text");
    expect_escaped("a\x1b[31mred\x1b[0m", "a\\x1B[31mred\\x1B[0m");
    expect_escaped("tab\there\r\x7f", "tab\\x09here\\x0D\\x7F");
    expect_escaped("line\nbreak", "line\nbreak");
    expect_escaped("caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80", "caf\xc3\xa9 \xe2\x82\xac \xf0\x9f\x98\x80");
    expect_escaped("bad \xff\xfe, cut \xe2\x82, overlong \xc0\xaf", "bad \\xFF\\xFE, cut \\xE2\\x82, overlong \\xC0\\xAF");
    expect_escaped("surrogate \xed\xa0\x80", "surrogate \\xED\\xA0\\x80");
    expect_escaped("\xef\xbb\xbf" "bom, \xe2\x80\xae" "rlo, \xc2\x9b" "csi", "\\uFEFFbom, \\u202Erlo, \\u009Bcsi");
    /* a long message is cut at a character, never inside an escape */
    char big[1500];
    memset(big, 0x1b, sizeof big - 1);
    big[sizeof big - 1] = '\0';
    CstError err = {0};
    cst_fail(&err, CST_ERR_PARSE, "%s", big);
    size_t n = strlen(err.msg);
    assert_true(n < sizeof err.msg && n % 4 == 0);
    for (size_t i = 0; i < n; i++) assert_true((unsigned char)err.msg[i] >= 0x20);
}

static void test_radiance_rule(void **state)
{
    (void)state;
    float px[2 * 2 * 3];
    for (int i = 0; i < 12; i++) px[i] = 0.25f;
    CstError err = {0};
    assert_int_equal(image_check_radiance(px, 2, 2, "x.pfm", &err), CST_OK);
    const float bad[3] = {NAN, INFINITY, -0.5f};
    const char *want[3] = {"x.pfm: pixel (1, 1) channel B is nan", "x.pfm: pixel (1, 1) channel B is inf",
                           "x.pfm: pixel (1, 1) channel B is -0.5"};
    for (int k = 0; k < 3; k++) {
        px[3 * 3 + 2] = bad[k];
        assert_int_equal(image_check_radiance(px, 2, 2, "x.pfm", &err), CST_ERR_INVALID_ARG);
        if (!strstr(err.msg, want[k])) fail_msg("\"%s\" lacks \"%s\"", err.msg, want[k]);
    }
    px[3 * 3 + 2] = -0.0f; /* negative zero is zero */
    assert_int_equal(image_check_radiance(px, 2, 2, "x.pfm", &err), CST_OK);
}

/* "t0" -> "t1" -> ... -> "t(n-1)": every checkerboard's "even" names the next texture. */
static char *chain_scene(int n, const char *prefix)
{
    size_t cap = (size_t)n * 120 + 1024, len = 0;
    char *s = malloc(cap);
    assert_non_null(s);
    len += (size_t)snprintf(s + len, cap - len, "%s{\"camera\": {\"position\": [0, 0, -5], \"look_at\": [0, 0, 0], "
                            "\"up\": [0, 1, 0], \"fov\": 40}, \"textures\": {", prefix);
    for (int i = 0; i < n; i++) {
        char next[32];
        if (i + 1 < n) snprintf(next, sizeof next, "\"t%d\"", i + 1);
        else snprintf(next, sizeof next, "[0.5, 0.5, 0.5]");
        len += (size_t)snprintf(s + len, cap - len, "%s\"t%d\": {\"type\": \"checkerboard\", \"even\": %s, "
                                "\"odd\": [0.1, 0.1, 0.1]}", i ? ", " : "", i, next);
    }
    snprintf(s + len, cap - len, "}, \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": \"t0\"}}, "
             "\"shapes\": [{\"type\": \"sphere\", \"material\": \"m\", \"center\": [0, 0, 0], \"radius\": 1, "
             "\"emission\": {\"radiance\": [1, 1, 1]}}]}");
    return s;
}

/* A chain of 100,000 overflowed the stack (10,000 without ASan, 5,000 with): the reader
 * now keeps its own stack. */
static void test_deep_checkerboard_chain(void **state)
{
    (void)state;
    static const int sizes[] = {10000, 100000};
    for (int k = 0; k < 2; k++) {
        char *text = chain_scene(sizes[k], "");
        CstScene *scene = NULL;
        CstError err = {0};
        CstStatus st = cst_scene_load_json_string(text, strlen(text), "chain.json", &scene, &err);
        if (st != CST_OK) fail_msg("%d textures: %s", sizes[k], err.msg);
        cst_scene_destroy(scene);
        free(text);
    }
}

static void test_byte_order_marks(void **state)
{
    (void)state;
    char *text = chain_scene(3, "\xef\xbb\xbf");
    CstScene *scene = NULL;
    CstError err = {0};
    if (cst_scene_load_json_string(text, strlen(text), "bom.json", &scene, &err) != CST_OK)
        fail_msg("JSON with a BOM: %s", err.msg);
    cst_scene_destroy(scene);
    free(text);
    /* positions count from after the mark */
    const char json_bad[] = "\xef\xbb\xbf{\"cameraa\": 1}";
    assert_int_not_equal(cst_scene_load_json_string(json_bad, sizeof json_bad - 1, "b.json", &scene, &err), CST_OK);
    assert_non_null(strstr(err.msg, "b.json:1:2:"));
    const char pbrt[] = "\xef\xbb\xbfWorldBegin\nShape \"sphere\"\n";
    if (cst_scene_load_pbrt_string(pbrt, sizeof pbrt - 1, "bom.pbrt", NULL, &scene, &err) != CST_OK)
        fail_msg("pbrt with a BOM: %s", err.msg);
    cst_scene_destroy(scene);
    const char pbrt_bad[] = "\xef\xbb\xbfWorldBeginn\n";
    assert_int_equal(cst_scene_load_pbrt_string(pbrt_bad, sizeof pbrt_bad - 1, "b.pbrt", NULL, &scene, &err),
                     CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "b.pbrt:1:1: unknown directive: got the word WorldBeginn;"));
    const char utf16[] = "\xff\xfeW\0";
    assert_int_equal(cst_scene_load_pbrt_string(utf16, sizeof utf16 - 1, "u.pbrt", NULL, &scene, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "u.pbrt:1:1: the file is UTF-16"));
    assert_int_equal(cst_scene_load_json_string(utf16, sizeof utf16 - 1, "u.json", &scene, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "u.json:1:1: the text is UTF-16"));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_file_gate),
        cmocka_unit_test(test_escape),
        cmocka_unit_test(test_radiance_rule),
        cmocka_unit_test(test_deep_checkerboard_chain),
        cmocka_unit_test(test_byte_order_marks),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
