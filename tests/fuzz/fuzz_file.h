/* For the fuzz targets whose parser takes a file name (mesh import, image readers): the
 * input written to a temporary file with a chosen extension in a directory of the
 * process's own, rewritten for every input; and the replay main() of FUZZ_STANDALONE. */
#ifndef CST_FUZZ_FILE_H
#define CST_FUZZ_FILE_H

#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

enum { FUZZ_MAX_EXTS = 8 };

/* Writes data to "<tmpdir>/cst-fuzz-XXXXXX/input<ext>" (a directory of this process's own,
 * one file per extension, all removed at exit) and returns its path, or aborts: a
 * harness failure must not pass for a clean run. */
static char fuzz_dir[256];
static char fuzz_paths[FUZZ_MAX_EXTS][300];
static const char *fuzz_exts[FUZZ_MAX_EXTS];

static void fuzz_remove_files(void)
{
    for (int i = 0; i < FUZZ_MAX_EXTS; i++)
        if (fuzz_paths[i][0]) unlink(fuzz_paths[i]);
    if (fuzz_dir[0]) rmdir(fuzz_dir);
}

static const char *fuzz_write_file(const uint8_t *data, size_t size, const char *ext)
{
    if (!fuzz_dir[0]) {
        const char *tmp = getenv("TMPDIR");
        if (!tmp || !*tmp) tmp = access("/dev/shm", W_OK) == 0 ? "/dev/shm" : "/tmp";
        snprintf(fuzz_dir, sizeof fuzz_dir, "%s/cst-fuzz-XXXXXX", tmp);
        if (!mkdtemp(fuzz_dir)) abort();
        atexit(fuzz_remove_files);
    }
    int i = 0;
    while (i < FUZZ_MAX_EXTS && fuzz_exts[i] && strcmp(fuzz_exts[i], ext) != 0) i++;
    if (i == FUZZ_MAX_EXTS) abort();
    if (!fuzz_exts[i]) {
        snprintf(fuzz_paths[i], sizeof fuzz_paths[i], "%s/input%s", fuzz_dir, ext);
        fuzz_exts[i] = ext;
    }
    FILE *f = fopen(fuzz_paths[i], "wb");
    if (!f || fwrite(data, 1, size, f) != size || fclose(f) != 0) abort();
    return fuzz_paths[i];
}

#include "fuzz_replay.h"

#endif
