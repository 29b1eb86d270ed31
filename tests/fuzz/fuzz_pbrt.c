/* libFuzzer target for the pbrt tokenizer and loader: any bytes must give CST_OK or a
 * located error, never a crash, an out-of-bounds read or a leak; every warning must be
 * located too. File access is disabled (Include, plymesh and imagemap fail cleanly), so
 * the fuzzer cannot wander the file system.
 *
 * Built by -DCST_FUZZ=ON (clang; tests/fuzz/CMakeLists.txt), run by scripts/fuzz.sh with
 * its seed corpus tests/fuzz/corpus/fuzz_pbrt/: see docs/fuzzing.md.
 *
 * Without clang, -DFUZZ_STANDALONE adds a main() that replays the files named on the
 * command line through the same entry point. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "scene/pbrt/pbrt_tokenizer.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static int located(const char *msg)
{
    int line = 0, col = 0;
    return sscanf(msg, "fuzz.pbrt:%d:%d: ", &line, &col) == 2 && line >= 1 && col >= 1;
}

static void on_warning(void *user, CstWarningCode code, const char *message)
{
    (void)user;
    if (code < CST_WARN_UNSUPPORTED || code > CST_WARN_GEOMETRY || !located(message))
        abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    /* The tokenizer alone: it must end, at EOF or at a located error. */
    PbrtTokenizer tz;
    PbrtToken tok;
    CstError err;
    pbrt_tokenizer_init(&tz, (const char *)data, size, "fuzz.pbrt");
    for (size_t n = 0;; n++) {
        CstStatus st = pbrt_next_token(&tz, &tok, &err);
        if (st != CST_OK) {
            if (st != CST_ERR_PARSE || !located(err.msg)) abort();
            break;
        }
        if (tok.kind == PBRT_TOK_EOF) break;
        if (n > size) abort(); /* no progress */
    }

    CstScene *scene = NULL;
    CstLoadOptions opt = {0};
    opt.warning = on_warning;
    opt.no_file_access = 1;
    opt.max_primitives = 16384; /* the BVH build of instance-heavy inputs was half the time */
    CstStatus st = cst_scene_load_pbrt_string((const char *)data, size, "fuzz.pbrt", &opt, &scene, &err);
    if ((st == CST_OK) != (scene != NULL) || (st != CST_OK && err.msg[0] == '\0'))
        abort();
    if ((st == CST_ERR_PARSE || st == CST_ERR_INVALID_ARG || st == CST_ERR_UNSUPPORTED) &&
        !located(err.msg))
        abort();
    cst_scene_destroy(scene);
    return 0;
}

#include "fuzz_replay.h"
