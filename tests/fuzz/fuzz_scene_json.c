/* libFuzzer target for the JSON scene loader: any bytes must give CST_OK or a located
 * error, never a crash, an out-of-bounds read or a leak.
 *
 * Built by -DCST_FUZZ=ON (clang; tests/fuzz/CMakeLists.txt), run by scripts/fuzz.sh with
 * its seed corpus tests/fuzz/corpus/fuzz_scene_json/: see docs/fuzzing.md.
 *
 * Without clang, -DFUZZ_STANDALONE adds a main() that replays the files named on the
 * command line (a crash corpus, say) through the same entry point, e.g. with gcc -fsanitize=address. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    CstScene *scene = NULL;
    CstError err;
    CstStatus st = cst_scene_load_json_string((const char *)data, size, "fuzz.json", &scene, &err);
    /* The contract the fuzzer checks beyond memory safety: a scene exactly on success,
     * every failure explained, and every syntax or semantic error located. */
    if ((st == CST_OK) != (scene != NULL) || (st != CST_OK && err.msg[0] == '\0'))
        abort();
    int line = 0, col = 0;
    if ((st == CST_ERR_PARSE || st == CST_ERR_INVALID_ARG) &&
        (sscanf(err.msg, "fuzz.json:%d:%d: ", &line, &col) != 2 || line < 1 || col < 1))
        abort();
    cst_scene_destroy(scene);
    return 0;
}

#include "fuzz_replay.h"
