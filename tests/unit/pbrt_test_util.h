/* Helpers shared by the pbrt loader's unit tests (test_pbrt_parse.c, test_pbrt_materials.c,
 * test_pbrt_shapes.c): loading text with warnings collected, located-error checks, and a
 * minimal camera, triangle and world block. */
#ifndef CST_TESTS_PBRT_TEST_UTIL_H
#define CST_TESTS_PBRT_TEST_UTIL_H

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "caustic/caustic.h"
#include "camera/camera.h"
#include "film/film.h"
#include "io/image_io.h"
#include "scene/pbrt/pbrt_tokenizer.h"
#include "scene/scene.h"
#include "scene/pbrt/pbrt_light.h"
#include "scene/pbrt/pbrt_spectrum.h"

#define NAME "t.pbrt"

typedef struct Warnings {
    int n;
    CstWarningCode code[64];
    char msg[64][256];
} Warnings;

static inline void collect(void *user, CstWarningCode code, const char *message)
{
    Warnings *w = user;
    if (w->n < 64) {
        w->code[w->n] = code;
        snprintf(w->msg[w->n], sizeof w->msg[0], "%s", message);
    }
    w->n++;
}

/* The first warning with `code` whose message contains `what`, or -1. */
static inline int find_warning(const Warnings *w, CstWarningCode code, const char *what)
{
    for (int i = 0; i < w->n && i < 64; i++)
        if (w->code[i] == code && strstr(w->msg[i], what)) return i;
    return -1;
}

/* Writes n bytes to path (the test fails if it cannot). */
static inline void write_file(const char *path, const void *data, size_t n)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, n, f), n);
    assert_int_equal(fclose(f), 0);
}

static inline void write_text(const char *path, const char *text) { write_file(path, text, strlen(text)); }

/* Loads text as the file `path` (Include, Import and shape files resolve against its
 * directory), with file access; warnings go to *w unless w is NULL. */
static inline CstStatus load_at(const char *text, const char *path, CstScene **out, CstError *err, Warnings *w)
{
    CstLoadOptions opt = {.warning = collect, .warning_user = w};
    return cst_scene_load_pbrt_string(text, strlen(text), path, w ? &opt : NULL, out, err);
}

static inline CstStatus load_w(const char *text, CstScene **out, CstError *err, Warnings *w)
{
    CstLoadOptions opt = {0};
    opt.warning = collect;
    opt.warning_user = w;
    opt.no_file_access = 1;
    return cst_scene_load_pbrt_string(text, strlen(text), NAME, &opt, out, err);
}

/* 1-based line and column of the nth occurrence of needle. */
static inline void pos_of(const char *text, const char *needle, int nth, int *line, int *col)
{
    const char *at = text;
    for (int i = 0;; i++) {
        at = strstr(at, needle);
        if (!at) fail_msg("needle \"%s\" #%d not in the test text", needle, nth);
        if (i == nth) break;
        at++;
    }
    *line = 1;
    *col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') { (*line)++; *col = 1; }
        else if (((unsigned char)*p & 0xC0) != 0x80) (*col)++;
    }
}

static inline void expect_error(const char *text, CstStatus status, const char *needle, int nth,
                                const char *what)
{
    CstScene *scene = (CstScene *)(uintptr_t)1;
    CstError err = {0};
    Warnings w = {0};
    CstStatus st = load_w(text, &scene, &err, &w);
    if (st != status)
        fail_msg("status %s, expected %s; message: %s\ntext: %s", cst_status_name(st),
                 cst_status_name(status), err.msg, text);
    assert_null(scene);
    int line, col;
    pos_of(text, needle, nth, &line, &col);
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("message \"%s\" does not start with \"%s\"\ntext: %s", err.msg, prefix, text);
    if (what && !strstr(err.msg, what)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
}

static inline Scene *expect_ok(const char *text, Warnings *w)
{
    CstScene *scene = NULL;
    CstError err = {0};
    Warnings local = {0};
    CstStatus st = load_w(text, &scene, &err, w ? w : &local);
    if (st != CST_OK) fail_msg("%s: %s\ntext: %s", cst_status_name(st), err.msg, text);
    assert_non_null(scene);
    return scene;
}

#define CAMERA "LookAt 0 0 -5  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 45\n"
#define TRI "Shape \"trianglemesh\" \"point3 P\" [0 0 0  1 0 0  0 1 0] \"integer indices\" [0 1 2]\n"
#define WORLD(body) CAMERA "WorldBegin\n" body

static inline void assert_vec(Vec3 v, float x, float y, float z, float tol)
{
    if (!(fabsf(v.x - x) <= tol && fabsf(v.y - y) <= tol && fabsf(v.z - z) <= tol))
        fail_msg("(%g, %g, %g), expected (%g, %g, %g)", (double)v.x, (double)v.y, (double)v.z,
                 (double)x, (double)y, (double)z);
}

static inline Vec3 tri_vertex(const Scene *s, int t, int k) { return s->positions[s->tri_indices[3 * t + k]]; }


#endif
