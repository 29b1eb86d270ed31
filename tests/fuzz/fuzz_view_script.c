/* libFuzzer target for caustic view's script parser (cli/view_script.c), from memory: any
 * bytes give either commands whose arguments are in range, or an error located as
 * "fuzz.txt:LINE:COL:" (or over the size limit) with no commands kept; never a crash, a
 * hang or a leak. Built by -DCST_FUZZ=ON (tests/fuzz/CMakeLists.txt); run with
 * scripts/fuzz.sh. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "view_script.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    ViewScript s;
    char msg[512];
    msg[0] = '\0';
    if (!view_script_parse((const char *)data, size, "fuzz.txt", &s, msg, sizeof msg)) {
        if (s.cmds || s.count != 0) abort();
        if (strncmp(msg, "fuzz.txt:", 9) != 0) abort();
        return 0;
    }
    for (int i = 0; i < s.count; i++) {
        const ViewScriptCmd *c = &s.cmds[i];
        if (c->line < 1) abort();
        if (c->op == VIEW_SCRIPT_KEY && c->key == 0) abort();
        if (c->op == VIEW_SCRIPT_WAIT_SPP && !(c->a >= 1.0 && c->a <= 1e9)) abort();
        if (c->op == VIEW_SCRIPT_SAVE && (!c->path || !c->path[0])) abort();
        if (!isfinite(c->a) || !isfinite(c->b)) abort();
    }
    view_script_free(&s);
    return 0;
}

#include "fuzz_replay.h"
