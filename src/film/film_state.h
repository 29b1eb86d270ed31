/* Film state files: a film's per-pixel sums with the samples they cover and a key of named
 * values that say what they are valid for, in the versioned, checksummed, little-endian
 * binary format of docs/state-format.md, written atomically. What goes in the key is
 * render/checkpoint.c's business; this module only stores, reads and checks bytes. */
#ifndef CST_FILM_FILM_STATE_H
#define CST_FILM_FILM_STATE_H

#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "film/film.h"

#define FILM_STATE_MAGIC   "CSTSTATE"
/* Version 3 adds a progressive integrator's per-pixel state (Film.progressive, SPPM). A
 * film with neither is written as version 1, byte for byte as before. */
#define FILM_STATE_VERSION 1u
/* Version 2: version 1 and, after the AOV sums, every pixel's own sample count (a film
 * with pixel_spp, adaptive sampling). Films without per-pixel counts are written as 1. */
#define FILM_STATE_VERSION_PIXEL_SPP 2u
#define FILM_STATE_VERSION_PROGRESSIVE 3u
/* Version 4: version 1 and an MLT render's chains (Film.chains, opaque bytes) after the
 * AOV sums. */
#define FILM_STATE_VERSION_CHAINS 4u
/* The largest chain state a reader accepts (bytes): far above any render's (a chain is a
 * few kB), far below what would overflow a size. */
#define FILM_STATE_CHAINS_MAX ((uint64_t)1 << 40)

typedef enum StateValueType { STATE_INT = 1, STATE_REAL = 2, STATE_TEXT = 3 } StateValueType;

/* One entry of the key: a name (1..STATE_NAME_MAX bytes) and a value of one type. */
enum { STATE_NAME_MAX = 63, STATE_TEXT_MAX = 1024, STATE_KEYS_MAX = 64 };
typedef struct StateKey {
    char name[STATE_NAME_MAX + 1];
    StateValueType type;
    int64_t i;
    double r;                         /* compared bit for bit */
    char text[STATE_TEXT_MAX + 1];
} StateKey;

/* Writes `film` (its sums, sums of squares, AOV sums, per-pixel counts or progressive
 * state, film->spp as the samples [0, spp) of every pixel, or with pixel_spp each pixel's
 * [0, count)) and the nkeys entries of `keys` to `path` through a temporary file renamed
 * into place (io/path.h; `announce` as CstImageWriteOptions.temp_file, may be NULL), so
 * an interrupted write never replaces a previous state. CST_ERR_IO with the reason. */
CstStatus film_state_write(const char *path, const Film *film, const StateKey *keys, int nkeys,
                           CstTempFileFn announce, void *user, CstError *err);

/* Reads a state file: every field checked (magic, version, sizes against the file's length,
 * the CRC-32 of the whole), so a truncated or corrupted file is CST_ERR_PARSE with "PATH:
 * ..." naming what is wrong, an unreadable one CST_ERR_IO. On success *film_out (caller:
 * film_destroy) holds the sums and spp, with no output settings, and keys[0..*nkeys) the key
 * (keys: room for STATE_KEYS_MAX). */
CstStatus film_state_read(const char *path, Film **film_out, StateKey *keys, int *nkeys, CstError *err);
/* The same from len bytes in memory (name: for messages), for the fuzz target. */
CstStatus film_state_read_mem(const char *name, const void *bytes, size_t len, Film **film_out, StateKey *keys,
                              int *nkeys, CstError *err);

#endif
