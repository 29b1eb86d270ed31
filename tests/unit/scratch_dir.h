/* A per-run scratch directory for the tests that write files (image I/O, textures, mesh
 * import): made by the cmocka group setup, removed with its files by the teardown. */
#ifndef CST_TESTS_SCRATCH_DIR_H
#define CST_TESTS_SCRATCH_DIR_H

#include <dirent.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

static char g_dir[256]; /* the directory, valid between setup and teardown */

/* out = g_dir/name */
static inline void tpath(char *out, size_t n, const char *name) { snprintf(out, n, "%s/%s", g_dir, name); }

/* template: a path ending in XXXXXX (mkdtemp). Returns 0, or -1 if it cannot be made. */
static inline int scratch_dir_make(const char *template_path)
{
    snprintf(g_dir, sizeof g_dir, "%s", template_path);
    return mkdtemp(g_dir) ? 0 : -1;
}

/* Removes the directory with its files and empty subdirectories. */
static inline int scratch_dir_remove(void)
{
    DIR *d = opendir(g_dir);
    if (!d) return -1;
    struct dirent *e;
    while ((e = readdir(d))) {
        if (!strcmp(e->d_name, ".") || !strcmp(e->d_name, "..")) continue;
        char p[512];
        tpath(p, sizeof p, e->d_name);
        if (unlink(p) != 0) rmdir(p);
    }
    closedir(d);
    return rmdir(g_dir);
}

#endif
