/* The image writer's output side (issue 25): metadata read back with libpng (tEXt and
 * iTXt) and the OpenEXR C API (string attributes), PFM ignoring it; rejected keys and
 * values; the temporary-file callback; temporary names up to NAME_MAX (long and short
 * form); stale temporaries of dead processes; the pre-render check. */
#define _POSIX_C_SOURCE 200809L

#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <errno.h>
#include <limits.h>
#include <signal.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <openexr.h>
#include <png.h>

#include "io/image_io.h"
#include "io/path.h"

static const float PIXELS[2 * 2 * 3] = {0.1f, 0.2f, 0.3f, 1.0f, 0.5f, 0.25f,
                                        0.0f, 0.0f, 0.0f, 2.0f, 4.0f, 8.0f};
static const char UTF8_VALUE[] = "r\xc3\xa9sum\xc3\xa9 \xe2\x86\x92 caustic"; /* é, → */
static const CstImageMetadata META[] = {
    {"caustic.version", "0.1.0"},
    {"caustic.command", "caustic render 'a b.json' -o out.png"},
    {"caustic.note", UTF8_VALUE},
};
enum { NMETA = sizeof META / sizeof META[0] };

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_image_write.XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static bool exists(const char *p)
{
    struct stat sb;
    return lstat(p, &sb) == 0;
}

static int count_temps(void)
{
    DIR *d = opendir(g_dir);
    assert_non_null(d);
    int n = 0;
    for (struct dirent *e; (e = readdir(d));) n += strstr(e->d_name, ".tmp.") != NULL;
    closedir(d);
    return n;
}

static CstStatus write_meta(const char *path, const CstImageMetadata *m, int n, CstError *err)
{
    CstImageWriteOptions o = {m, n, NULL, NULL};
    ImageWriteOptions opt = {.out = &o};
    return image_write_opt(path, PIXELS, 2, 2, &opt, err);
}

/* ---------------------------------------------------------------- metadata */

static void test_png_text_chunks(void **state)
{
    (void)state;
    char p[512];
    tpath(p, sizeof p, "meta.png");
    CstError err;
    assert_int_equal(write_meta(p, META, NMETA, &err), CST_OK);

    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_non_null(info);
    if (setjmp(png_jmpbuf(png))) fail_msg("libpng error");
    png_init_io(png, f);
    png_read_info(png, info);
    png_textp text = NULL;
    int n = png_get_text(png, info, &text, NULL);
    assert_int_equal(n, NMETA);
    for (int i = 0; i < NMETA; i++) {
        int k = 0;
        while (k < n && strcmp(text[k].key, META[i].key) != 0) k++;
        assert_true(k < n);
        assert_string_equal(text[k].text, META[i].value);
        /* ASCII values as tEXt, others as iTXt (UTF-8) */
        bool ascii = META[i].value != UTF8_VALUE;
        assert_int_equal(text[k].compression, ascii ? PNG_TEXT_COMPRESSION_NONE : PNG_ITXT_COMPRESSION_NONE);
    }
    png_destroy_read_struct(&png, &info, NULL);
    fclose(f);
}

static void test_exr_string_attributes(void **state)
{
    (void)state;
    char p[512];
    tpath(p, sizeof p, "meta.exr");
    CstError err;
    assert_int_equal(write_meta(p, META, NMETA, &err), CST_OK);
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_read(&ctx, p, &init), EXR_ERR_SUCCESS);
    for (int i = 0; i < NMETA; i++) {
        int32_t len = 0;
        const char *s = NULL;
        assert_int_equal(exr_attr_get_string(ctx, 0, META[i].key, &len, &s), EXR_ERR_SUCCESS);
        assert_int_equal(len, (int32_t)strlen(META[i].value));
        assert_memory_equal(s, META[i].value, (size_t)len);
    }
    exr_finish(&ctx);
    /* and the pixels are still the pixels */
    float *rgb = NULL;
    int w = 0, h = 0;
    assert_int_equal(image_read(p, &rgb, &w, &h, &err), CST_OK);
    assert_memory_equal(rgb, PIXELS, sizeof PIXELS);
    free(rgb);
}

static uint8_t *slurp(const char *p, long *n)
{
    FILE *f = fopen(p, "rb");
    assert_non_null(f);
    fseek(f, 0, SEEK_END);
    *n = ftell(f);
    rewind(f);
    uint8_t *b = malloc((size_t)*n);
    assert_int_equal(fread(b, 1, (size_t)*n, f), (size_t)*n);
    fclose(f);
    return b;
}

/* PFM has no metadata: the same bytes with and without. */
static void test_pfm_ignores_metadata(void **state)
{
    (void)state;
    char a[512], b[512];
    tpath(a, sizeof a, "plain.pfm");
    tpath(b, sizeof b, "meta.pfm");
    CstError err;
    assert_int_equal(image_write(a, PIXELS, 2, 2, &err), CST_OK);
    assert_int_equal(write_meta(b, META, NMETA, &err), CST_OK);
    long na, nb;
    uint8_t *da = slurp(a, &na), *db = slurp(b, &nb);
    assert_int_equal(na, nb);
    assert_memory_equal(da, db, (size_t)na);
    free(da);
    free(db);
}

static void test_bad_metadata_rejected(void **state)
{
    (void)state;
    char p[512];
    tpath(p, sizeof p, "bad.exr");
    CstError err;
    const CstImageMetadata bad[][1] = {
        {{"", "x"}},
        {{"has space", "x"}},
        {{"a.key.of.thirty.two.bytes.long.x", "x"}},
        {{"channels", "x"}},
        {{"dataWindow", "x"}},
        {{"ok", "\xff\xfe"}},
        {{"ok", "\xc0\xaf"}},        /* overlong '/' */
        {{"ok", "\xed\xa0\x80"}},    /* a surrogate */
        {{"ok", NULL}},
        {{NULL, "x"}},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        assert_int_equal(write_meta(p, bad[i], 1, &err), CST_ERR_INVALID_ARG);
        assert_false(exists(p));
    }
    const CstImageMetadata twice[] = {{"k", "1"}, {"k", "2"}};
    assert_int_equal(write_meta(p, twice, 2, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "twice"));
    assert_int_equal(write_meta(p, NULL, 1, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(write_meta(p, META, -1, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(count_temps(), 0);
    const CstImageMetadata longest[] = {{"a.key.of.thirty.one.bytes.long.", "x"}};
    assert_int_equal(write_meta(p, longest, 1, &err), CST_OK);
}

/* ---------------------------------------------------------------- temporary files */

typedef struct TempLog {
    int calls;
    char first[600];
    bool existed_when_told;
    bool last_null;
} TempLog;

static void temp_told(void *user, const char *tmp)
{
    TempLog *l = user;
    if (l->calls++ == 0 && tmp) {
        snprintf(l->first, sizeof l->first, "%s", tmp);
        l->existed_when_told = exists(tmp);
    }
    l->last_null = tmp == NULL;
}

static void test_temp_callback(void **state)
{
    (void)state;
    char p[512], want[600];
    tpath(p, sizeof p, "told.png");
    TempLog log = {0};
    CstImageWriteOptions o = {NULL, 0, temp_told, &log};
    ImageWriteOptions opt = {.out = &o};
    CstError err;
    assert_int_equal(image_write_opt(p, PIXELS, 2, 2, &opt, &err), CST_OK);
    snprintf(want, sizeof want, "%s.tmp.%ld.0", p, (long)getpid());
    assert_int_equal(log.calls, 2);        /* the name, then NULL */
    assert_string_equal(log.first, want);
    assert_false(log.existed_when_told);   /* told before it is created */
    assert_true(log.last_null);
    assert_false(exists(want));
    /* a write that fails after the temporary exists (too wide for the EXR writer, refused
     * before any pixel is read) tells NULL too and leaves nothing */
    TempLog fail_log = {0};
    o.temp_file_user = &fail_log;
    tpath(p, sizeof p, "told.exr");
    assert_int_equal(image_write_opt(p, PIXELS, 200000000, 1, &opt, &err), CST_ERR_UNSUPPORTED);
    assert_int_equal(fail_log.calls, 2);
    assert_true(fail_log.last_null);
    assert_int_equal(count_temps(), 0);
}

static void name_of(char *out, size_t len, const char *ext)
{
    size_t n = len - strlen(ext);
    memset(out, 'n', n);
    snprintf(out + n, strlen(ext) + 1, "%s", ext);
}

/* Up to 229 bytes: "<name>.tmp.<pid>.<n>"; from 230 to 255: ".cst-<hash>.tmp.<pid>.<n>". */
static void test_temp_name_forms(void **state)
{
    (void)state;
    static const size_t lens[] = {229, 230, 250, NAME_MAX};
    for (size_t i = 0; i < sizeof lens / sizeof lens[0]; i++) {
        char name[NAME_MAX + 1], p[600];
        name_of(name, lens[i], ".exr");
        tpath(p, sizeof p, name);
        char *tmp = NULL;
        int fd = -1;
        CstError err;
        assert_int_equal(path_temp_create(p, NULL, NULL, &tmp, &fd, &err), CST_OK);
        const char *base = strrchr(tmp, '/') + 1;
        if (lens[i] <= 229) assert_memory_equal(base, name, lens[i]);
        else assert_memory_equal(base, ".cst-", 5);
        assert_non_null(strstr(base, ".tmp."));
        close(fd);
        unlink(tmp);
        free(tmp);
        /* and the whole write works */
        assert_int_equal(image_write(p, PIXELS, 2, 2, &err), CST_OK);
        assert_true(exists(p));
        assert_int_equal(image_write_check(p, &err), CST_OK);
        unlink(p);
    }
    char name[NAME_MAX + 2], p[600];
    name_of(name, NAME_MAX + 1, ".exr");
    tpath(p, sizeof p, name);
    CstError err;
    assert_int_equal(image_write_check(p, &err), CST_ERR_IO);
    assert_int_equal(image_write(p, PIXELS, 2, 2, &err), CST_ERR_IO);
    assert_int_equal(count_temps(), 0);
}

static long dead_pid(void)
{
    pid_t pid = fork();
    assert_true(pid >= 0);
    if (pid == 0) _exit(0);
    waitpid(pid, NULL, 0);
    return (long)pid;
}

/* The short form of a dead process is removed by the next write of the same name; the
 * short form of another name is not. */
static void test_stale_short_form(void **state)
{
    (void)state;
    char name[NAME_MAX + 1], p[600], other[600];
    name_of(name, 250, ".png");
    tpath(p, sizeof p, name);
    name[0] = 'm';
    tpath(other, sizeof other, name);
    /* the real short names of both, made as this process would, renamed to a dead pid */
    long dead = dead_pid();
    if (kill((pid_t)dead, 0) == 0) skip();
    char stale[2][700];
    const char *targets[2] = {p, other};
    for (int i = 0; i < 2; i++) {
        char *tmp = NULL;
        int fd = -1;
        CstError err;
        assert_int_equal(path_temp_create(targets[i], NULL, NULL, &tmp, &fd, &err), CST_OK);
        close(fd);
        char *dot = strstr(tmp, ".tmp.");
        snprintf(stale[i], sizeof stale[i], "%.*s.tmp.%ld.3", (int)(dot - tmp), tmp, dead);
        assert_int_equal(rename(tmp, stale[i]), 0);
        free(tmp);
    }
    assert_int_equal(path_temp_remove_stale(p), 1);
    assert_false(exists(stale[0]));
    assert_true(exists(stale[1]));
    CstError err;
    assert_int_equal(image_write(other, PIXELS, 2, 2, &err), CST_OK);
    assert_false(exists(stale[1]));
    assert_int_equal(count_temps(), 0);
    unlink(other);
}

static void test_write_check(void **state)
{
    (void)state;
    char p[512];
    CstError err;
    tpath(p, sizeof p, "check.png");
    assert_int_equal(image_write_check(p, &err), CST_OK);
    assert_false(exists(p));
    assert_int_equal(count_temps(), 0);
    tpath(p, sizeof p, "check.txt");
    assert_int_equal(image_write_check(p, &err), CST_ERR_INVALID_ARG);
    tpath(p, sizeof p, "no-such-dir/check.png");
    assert_int_equal(image_write_check(p, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "does not exist"));
    tpath(p, sizeof p, "dir.png");
    assert_int_equal(mkdir(p, 0755), 0);
    assert_int_equal(image_write_check(p, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "directory"));
    rmdir(p);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_png_text_chunks),
        cmocka_unit_test(test_exr_string_attributes),
        cmocka_unit_test(test_pfm_ignores_metadata),
        cmocka_unit_test(test_bad_metadata_rejected),
        cmocka_unit_test(test_temp_callback),
        cmocka_unit_test(test_temp_name_forms),
        cmocka_unit_test(test_stale_short_form),
        cmocka_unit_test(test_write_check),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
