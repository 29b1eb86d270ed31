/* Film state files (film_state.h): the byte layout of docs/state-format.md, written through
 * a CRC-32 (zlib's crc32(), the polynomial of PNG and gzip) kept as the bytes go out, and
 * read back with every length checked against the file before it is used. */
#define _POSIX_C_SOURCE 200809L

#include "film/film_state.h"

#include <errno.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <zlib.h>

#include "core/error.h"
#include "core/file.h"
#include "io/path.h"

/* ------------------------------------------------------------------ writing */

/* Buffered little-endian output with a running CRC-32; the first error sticks. */
typedef struct StateOut {
    FILE *fp;
    uLong crc;
    unsigned char buf[1 << 16];
    size_t used;
    int failed; /* errno of the first failed write, or 0 */
} StateOut;

static void out_flush(StateOut *o)
{
    if (o->used == 0 || o->failed) { o->used = 0; return; }
    o->crc = crc32(o->crc, o->buf, (uInt)o->used);
    if (fwrite(o->buf, 1, o->used, o->fp) != o->used) o->failed = errno ? errno : EIO;
    o->used = 0;
}

static void out_bytes(StateOut *o, const void *p, size_t n)
{
    const unsigned char *b = p;
    while (n > 0) {
        if (o->used == sizeof o->buf) out_flush(o);
        size_t take = sizeof o->buf - o->used < n ? sizeof o->buf - o->used : n;
        memcpy(o->buf + o->used, b, take);
        o->used += take;
        b += take;
        n -= take;
    }
}

static void out_u64(StateOut *o, uint64_t v, int bytes)
{
    unsigned char b[8];
    for (int k = 0; k < bytes; k++) b[k] = (unsigned char)(v >> (8 * k));
    out_bytes(o, b, (size_t)bytes);
}

static void out_doubles(StateOut *o, const double *v, size_t n)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    /* The file's byte order: the arrays go out as they are (a 512x512 film is 12 MiB). */
    out_bytes(o, v, n * sizeof *v);
#else
    for (size_t i = 0; i < n; i++) {
        uint64_t bits;
        memcpy(&bits, &v[i], sizeof bits);
        out_u64(o, bits, 8);
    }
#endif
}

static void state_encode(StateOut *o, const Film *f, const StateKey *keys, int nkeys)
{
    out_bytes(o, FILM_STATE_MAGIC, 8);
    /* The lowest version that holds the film: 1, 2 with per-pixel counts, 3 with a
     * progressive integrator's state, 4 with MLT's chains (never two: a noise target
     * refuses SPPM and MLT). */
    out_u64(o, f->chains ? FILM_STATE_VERSION_CHAINS : f->progressive ? FILM_STATE_VERSION_PROGRESSIVE
               : f->pixel_spp ? FILM_STATE_VERSION_PIXEL_SPP : FILM_STATE_VERSION, 4);
    out_u64(o, (uint64_t)nkeys, 4);
    for (int k = 0; k < nkeys; k++) {
        const StateKey *e = &keys[k];
        size_t n = strlen(e->name);
        out_u64(o, (uint64_t)e->type, 1);
        out_u64(o, (uint64_t)n, 1);
        out_bytes(o, e->name, n);
        if (e->type == STATE_INT) out_u64(o, (uint64_t)e->i, 8);
        else if (e->type == STATE_REAL) out_doubles(o, &e->r, 1);
        else {
            size_t t = strlen(e->text);
            out_u64(o, (uint64_t)t, 4);
            out_bytes(o, e->text, t);
        }
    }
    const size_t pixels = (size_t)f->width * (size_t)f->height;
    const int stride = f->aov ? FILM_AOV_STRIDE : 0;
    out_u64(o, (uint64_t)f->width, 4);
    out_u64(o, (uint64_t)f->height, 4);
    out_u64(o, (uint64_t)f->spp, 4);
    out_u64(o, (uint64_t)stride, 4);
    if (f->progressive) out_u64(o, FILM_PROGRESSIVE_STRIDE, 4);
    if (f->chains) out_u64(o, (uint64_t)f->chains_len, 8);
    out_doubles(o, f->sum, 3 * pixels);
    out_doubles(o, f->sum_sq, 3 * pixels);
    if (stride) out_doubles(o, f->aov, (size_t)stride * pixels);
    if (f->progressive) out_doubles(o, f->progressive, FILM_PROGRESSIVE_STRIDE * pixels);
    if (f->chains) out_bytes(o, f->chains, f->chains_len);
    if (f->pixel_spp)
        for (size_t i = 0; i < pixels; i++) out_u64(o, (uint64_t)f->pixel_spp[i], 4);
    out_flush(o);
    uLong crc = o->crc;
    out_u64(o, (uint64_t)crc, 4);
    out_flush(o);
}

CstStatus film_state_write(const char *path, const Film *film, const StateKey *keys, int nkeys,
                           CstTempFileFn announce, void *user, CstError *err)
{
    if (nkeys < 0 || nkeys > STATE_KEYS_MAX)
        return cst_fail(err, CST_ERR_INTERNAL, "%s: %d key entries, at most %d", path, nkeys, STATE_KEYS_MAX);
    path_temp_remove_stale(path);
    char *tmp = NULL;
    int fd = -1;
    CstStatus st = path_temp_create(path, announce, user, &tmp, &fd, err);
    if (st != CST_OK) return st;
    StateOut *o = calloc(1, sizeof *o);
    FILE *fp = o ? fdopen(fd, "wb") : NULL;
    int e = 0;
    if (!o) {
        close(fd);
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory for the write buffer", path);
    } else if (!fp) {
        e = errno;
        close(fd);
    } else {
        o->fp = fp;
        o->crc = crc32(0L, Z_NULL, 0);
        state_encode(o, film, keys, nkeys);
        e = o->failed;
        if (!e && fflush(fp) != 0) e = errno;
        /* On disk before the rename, as image_io.c does: a crash right after it must not
         * leave an empty file under the final name. */
        if (!e && fsync(fileno(fp)) != 0 && errno != EINVAL) e = errno;
        if (fclose(fp) != 0 && !e) e = errno;
        if (!e && rename(tmp, path) != 0) e = errno;
    }
    if (e) st = cst_fail(err, CST_ERR_IO, "%s: cannot write the state file: %s", path, strerror(e));
    if (st != CST_OK) unlink(tmp);
    if (announce) announce(user, NULL);
    free(tmp);
    free(o);
    return st;
}

/* ------------------------------------------------------------------ reading */

typedef struct StateIn {
    const unsigned char *p;
    size_t len, off;
    const char *path;
} StateIn;

/* Fails (truncated) when fewer than n bytes are left. */
static CstStatus in_need(const StateIn *in, size_t n, const char *what, CstError *err)
{
    if (in->len - in->off >= n) return CST_OK;
    return cst_fail(err, CST_ERR_PARSE,
                    "%s: truncated state file: %zu bytes, ending inside %s at byte %zu (expected %zu more)",
                    in->path, in->len, what, in->off, n - (in->len - in->off));
}

static uint64_t in_u64(StateIn *in, int bytes)
{
    uint64_t v = 0;
    for (int k = 0; k < bytes; k++) v |= (uint64_t)in->p[in->off + (size_t)k] << (8 * k);
    in->off += (size_t)bytes;
    return v;
}

static void in_doubles(StateIn *in, double *v, size_t n)
{
#if defined(__BYTE_ORDER__) && __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__
    memcpy(v, in->p + in->off, n * sizeof *v);
    in->off += n * sizeof *v;
#else
    for (size_t i = 0; i < n; i++) {
        uint64_t bits = in_u64(in, 8);
        memcpy(&v[i], &bits, sizeof bits);
    }
#endif
}

static CstStatus read_key(StateIn *in, StateKey *e, int index, CstError *err)
{
    CstStatus st;
    if ((st = in_need(in, 2, "a key entry", err)) != CST_OK) return st;
    const size_t at = in->off;
    unsigned type = (unsigned)in_u64(in, 1), n = (unsigned)in_u64(in, 1);
    if (type < STATE_INT || type > STATE_TEXT || n == 0 || n > STATE_NAME_MAX)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: byte %zu: key entry %d has type %u and a name of %u bytes; expected type 1 to 3 "
                        "and 1 to %d bytes (a corrupted state file)",
                        in->path, at, index, type, n, STATE_NAME_MAX);
    if ((st = in_need(in, n, "a key name", err)) != CST_OK) return st;
    memcpy(e->name, in->p + in->off, n);
    e->name[n] = '\0';
    in->off += n;
    e->type = (StateValueType)type;
    if (type == STATE_TEXT) {
        if ((st = in_need(in, 4, "a key value", err)) != CST_OK) return st;
        uint64_t t = in_u64(in, 4);
        if (t > STATE_TEXT_MAX)
            return cst_fail(err, CST_ERR_PARSE, "%s: byte %zu: key \"%s\" has a text of %llu bytes, at most %d",
                            in->path, in->off - 4, e->name, (unsigned long long)t, STATE_TEXT_MAX);
        if ((st = in_need(in, (size_t)t, "a key value", err)) != CST_OK) return st;
        memcpy(e->text, in->p + in->off, (size_t)t);
        e->text[t] = '\0';
        in->off += (size_t)t;
        return CST_OK;
    }
    if ((st = in_need(in, 8, "a key value", err)) != CST_OK) return st;
    if (type == STATE_INT) e->i = (int64_t)in_u64(in, 8);
    else in_doubles(in, &e->r, 1);
    return CST_OK;
}

static CstStatus state_decode(StateIn *in, Film **film_out, StateKey *keys, int *nkeys, CstError *err)
{
    CstStatus st;
    /* A file that does not start as a state is named as such, a short one that does as
     * truncated. */
    if (memcmp(in->p, FILM_STATE_MAGIC, in->len < 8 ? in->len : 8) != 0)
        return cst_fail(err, CST_ERR_PARSE, "%s: not a caustic state file (expected the bytes \"%s\" at its start)",
                        in->path, FILM_STATE_MAGIC);
    if ((st = in_need(in, 16, "the header", err)) != CST_OK) return st;
    in->off = 8;
    uint64_t version = in_u64(in, 4);
    if (version != FILM_STATE_VERSION && version != FILM_STATE_VERSION_PIXEL_SPP &&
        version != FILM_STATE_VERSION_PROGRESSIVE && version != FILM_STATE_VERSION_CHAINS)
        return cst_fail(err, CST_ERR_PARSE, "%s: state format version %llu; this caustic reads versions %u, %u, %u "
                        "and %u", in->path, (unsigned long long)version, FILM_STATE_VERSION,
                        FILM_STATE_VERSION_PIXEL_SPP, FILM_STATE_VERSION_PROGRESSIVE, FILM_STATE_VERSION_CHAINS);
    const bool counts = version == FILM_STATE_VERSION_PIXEL_SPP;
    uint64_t n = in_u64(in, 4);
    if (n > STATE_KEYS_MAX)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte 12: %llu key entries, at most %d (a corrupted state file)",
                        in->path, (unsigned long long)n, STATE_KEYS_MAX);
    for (int k = 0; k < (int)n; k++)
        if ((st = read_key(in, &keys[k], k, err)) != CST_OK) return st;
    *nkeys = (int)n;
    const bool prog = version == FILM_STATE_VERSION_PROGRESSIVE, chains = version == FILM_STATE_VERSION_CHAINS;
    if ((st = in_need(in, prog ? 20 : chains ? 24 : 16, "the film header", err)) != CST_OK) return st;
    const size_t at = in->off;
    uint64_t w = in_u64(in, 4), h = in_u64(in, 4), spp = in_u64(in, 4), stride = in_u64(in, 4);
    uint64_t pstride = prog ? in_u64(in, 4) : 0;
    uint64_t clen = chains ? in_u64(in, 8) : 0;
    if (chains && (clen == 0 || clen > FILM_STATE_CHAINS_MAX || clen > in->len))
        return cst_fail(err, CST_ERR_PARSE, "%s: byte %zu: a chain state of %llu bytes; expected 1 to %llu bytes "
                        "within the file's %zu (a corrupted state file)", in->path, at + 16,
                        (unsigned long long)clen, (unsigned long long)FILM_STATE_CHAINS_MAX, in->len);
    if (prog && pstride != FILM_PROGRESSIVE_STRIDE)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte %zu: %llu progressive state values per pixel; expected %d (8: an "
                        "SPPM state from before SPPM rendered media; else a corrupted state file)", in->path, at + 16, (unsigned long long)pstride,
                        FILM_PROGRESSIVE_STRIDE);
    if (w < 1 || w > 65536 || h < 1 || h > 65536 || spp > INT32_MAX || (stride != 0 && stride != FILM_AOV_STRIDE))
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: byte %zu: film %llux%llu, %llu samples, %llu AOV sums per pixel; expected 1..65536 "
                        "pixels a side, at most 2^31 - 1 samples and 0 or %d AOV sums (a corrupted state file)",
                        in->path, at, (unsigned long long)w, (unsigned long long)h, (unsigned long long)spp,
                        (unsigned long long)stride, FILM_AOV_STRIDE);
    const size_t pixels = (size_t)w * (size_t)h;
    const size_t data = (6 + (size_t)stride + (size_t)pstride) * pixels * sizeof(double) + (counts ? 4 * pixels : 0) +
                        (size_t)clen;
    if ((st = in_need(in, data + 4, "the film's sums and the checksum", err)) != CST_OK) return st;
    if (in->len - in->off != data + 4)
        return cst_fail(err, CST_ERR_PARSE, "%s: %zu bytes after the end of the state (at byte %zu)", in->path,
                        in->len - in->off - data - 4, in->off + data + 4);
    /* The checksum before any value is trusted. */
    uLong crc = crc32(0L, Z_NULL, 0);
    for (size_t done = 0; done < in->len - 4;) {
        size_t take = in->len - 4 - done < (1u << 30) ? in->len - 4 - done : (1u << 30);
        crc = crc32(crc, in->p + done, (uInt)take);
        done += take;
    }
    StateIn tail = {in->p, in->len, in->len - 4, in->path};
    uint64_t stored = in_u64(&tail, 4);
    if ((uint64_t)crc != stored)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: corrupted state file: CRC-32 %08llx of its bytes, %08llx stored in its last 4 bytes",
                        in->path, (unsigned long long)crc, (unsigned long long)stored);
    Film *f = film_create((int)w, (int)h);
    if (f && stride) f->aov = malloc(pixels * FILM_AOV_STRIDE * sizeof *f->aov);
    if (f && pstride) f->progressive = malloc(pixels * FILM_PROGRESSIVE_STRIDE * sizeof *f->progressive);
    if (f && clen) f->chains = malloc((size_t)clen);
    if (!f || (stride && !f->aov) || (pstride && !f->progressive) || (clen && !f->chains)) {
        film_destroy(f);
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %llux%llu film", in->path,
                        (unsigned long long)w, (unsigned long long)h);
    }
    f->spp = (int)spp;
    in_doubles(in, f->sum, 3 * pixels);
    in_doubles(in, f->sum_sq, 3 * pixels);
    if (stride) in_doubles(in, f->aov, FILM_AOV_STRIDE * pixels);
    if (pstride) in_doubles(in, f->progressive, FILM_PROGRESSIVE_STRIDE * pixels);
    if (clen) {
        memcpy(f->chains, in->p + in->off, (size_t)clen);
        f->chains_len = (size_t)clen;
        in->off += (size_t)clen;
    }
    if (counts) {
        if (!(f->pixel_spp = malloc(pixels * sizeof *f->pixel_spp))) {
            film_destroy(f);
            return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %llux%llu film", in->path,
                            (unsigned long long)w, (unsigned long long)h);
        }
        for (size_t i = 0; i < pixels; i++) {
            const size_t at_count = in->off;
            uint64_t c = in_u64(in, 4);
            if (c > spp) {
                film_destroy(f);
                return cst_fail(err, CST_ERR_PARSE, "%s: byte %zu: pixel %zu holds %llu samples, more than the "
                                "film's %llu (a corrupted state file)", in->path, at_count, i,
                                (unsigned long long)c, (unsigned long long)spp);
            }
            f->pixel_spp[i] = (int)c;
        }
    }
    *film_out = f;
    return CST_OK;
}

CstStatus film_state_read_mem(const char *name, const void *bytes, size_t len, Film **film_out, StateKey *keys,
                              int *nkeys, CstError *err)
{
    *film_out = NULL;
    *nkeys = 0;
    StateIn in = {bytes, len, 0, name};
    CstStatus st = state_decode(&in, film_out, keys, nkeys, err);
    if (st != CST_OK) *nkeys = 0;
    return st;
}

CstStatus film_state_read(const char *path, Film **film_out, StateKey *keys, int *nkeys, CstError *err)
{
    *film_out = NULL;
    *nkeys = 0;
    char *bytes = NULL;
    size_t len = 0;
    CstStatus st = file_read_all(path, &bytes, &len, err);
    if (st != CST_OK) return st;
    st = film_state_read_mem(path, bytes, len, film_out, keys, nkeys, err);
    free(bytes);
    return st;
}
