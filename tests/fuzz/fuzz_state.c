/* libFuzzer target for the film state reader (film/film_state.c), from memory: any bytes
 * must give CST_OK with a film of the declared size and key entries within their bounds, or
 * CST_ERR_PARSE (CST_ERR_OOM) naming "fuzz.state:" with nothing returned; never a crash, a
 * hang or a leak. The checksum stops most mutations after the structure checks, which are
 * what this exercises. Built by -DCST_FUZZ=ON; run with scripts/fuzz.sh fuzz_state. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "film/film_state.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static StateKey keys[STATE_KEYS_MAX];
    Film *film = NULL;
    int n = -1;
    CstError err;
    err.msg[0] = '\0';
    CstStatus st = film_state_read_mem("fuzz.state", data, size, &film, keys, &n, &err);
    if (st != CST_OK) {
        if (film || n != 0) abort();
        if (st != CST_ERR_PARSE && st != CST_ERR_OOM) abort();
        if (strncmp(err.msg, "fuzz.state:", 11) != 0) abort();
        return 0;
    }
    if (!film || n < 0 || n > STATE_KEYS_MAX || film->width < 1 || film->height < 1 || film->spp < 0) abort();
    if (!film->chains != !film->chains_len) abort(); /* version 4: MLT's chains, 1 byte or more */
    for (int k = 0; k < n; k++)
        if (keys[k].type < STATE_INT || keys[k].type > STATE_TEXT || !keys[k].name[0] ||
            strlen(keys[k].name) > STATE_NAME_MAX || strlen(keys[k].text) > STATE_TEXT_MAX)
            abort();
    film_destroy(film);
    return 0;
}
