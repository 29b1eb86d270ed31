/* Reading possibly gzip-compressed files (zlib's inflate with gzip decoding), with a bound
 * on the decompressed size so that a small "zip bomb" cannot take the memory. */
#include "io/gzip.h"

#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <zlib.h>

#include "core/error.h"
#include "core/file.h"

int gzip_is_compressed(const char *path, const void *data, size_t len)
{
    const unsigned char *b = data;
    if (len >= 2 && b[0] == 0x1f && b[1] == 0x8b) return 1;
    size_t n = path ? strlen(path) : 0;
    return n >= 3 && strcasecmp(path + n - 3, ".gz") == 0;
}

/* zlib counts in uInt (32 bits): inputs and outputs are fed to it in slices of this size. */
#define GZIP_SLICE ((size_t)1 << 30)

CstStatus gzip_inflate(const char *name, const unsigned char *in, size_t in_len, uint64_t max_out,
                       char **out, size_t *out_len, CstError *err)
{
    *out = NULL;
    *out_len = 0;
    if (in_len < 2 || in[0] != 0x1f || in[1] != 0x8b)
        return cst_fail(err, CST_ERR_PARSE, "%.300s: not gzip data (expected the bytes 1f 8b "
                        "at the start)", name);
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    /* 16 + MAX_WBITS: gzip header and trailer (CRC-32, length) checked by zlib. */
    if (inflateInit2(&zs, 16 + MAX_WBITS) != Z_OK)
        return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory for the gzip decoder", name);
    /* First guess: 4x the compressed size (typical for meshes), never over the limit + 1
     * (one byte past the limit is how an oversized stream is detected). */
    uint64_t cap64 = (uint64_t)in_len * 4 + 64;
    if (cap64 > max_out + 1) cap64 = max_out + 1;
    size_t cap = (size_t)cap64, used = 0, in_pos = 0;
    char *buf = malloc(cap + 1);
    CstStatus st = CST_OK;
    if (!buf) {
        st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory for %zu decompressed bytes", name, cap);
        goto done;
    }
    for (;;) {
        if (used == cap) {
            if ((uint64_t)used > max_out) break; /* reported below */
            uint64_t next = (uint64_t)cap * 2;
            if (next > max_out + 1) next = max_out + 1;
            char *nb = realloc(buf, (size_t)next + 1);
            if (!nb) {
                st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory for %llu decompressed bytes",
                              name, (unsigned long long)next);
                goto done;
            }
            buf = nb;
            cap = (size_t)next;
        }
        size_t in_avail = in_len - in_pos, out_avail = cap - used;
        zs.next_in = (Bytef *)(uintptr_t)(in + in_pos);
        zs.avail_in = (uInt)(in_avail < GZIP_SLICE ? in_avail : GZIP_SLICE);
        zs.next_out = (Bytef *)buf + used;
        zs.avail_out = (uInt)(out_avail < GZIP_SLICE ? out_avail : GZIP_SLICE);
        uInt gave_in = zs.avail_in, gave_out = zs.avail_out;
        int rc = inflate(&zs, Z_NO_FLUSH);
        in_pos += gave_in - zs.avail_in;
        used += gave_out - zs.avail_out;
        if (rc == Z_STREAM_END) {
            /* Another member may follow (gzip(1) concatenates them); trailing zero bytes
             * (padding some tools add) end the data. Anything else is an error. */
            size_t k = in_pos;
            while (k < in_len && in[k] == 0) k++;
            if (k == in_len) break;
            if (in_len - in_pos < 2 || in[in_pos] != 0x1f || in[in_pos + 1] != 0x8b) {
                st = cst_fail(err, CST_ERR_PARSE, "%.300s: %zu bytes of garbage after the gzip "
                              "data at compressed byte %zu; expected the end of the file or "
                              "another gzip member", name, in_len - in_pos, in_pos);
                goto done;
            }
            if (inflateReset(&zs) != Z_OK) {
                st = cst_fail(err, CST_ERR_PARSE, "%.300s: gzip decoder reset failed", name);
                goto done;
            }
            continue;
        }
        if (rc == Z_BUF_ERROR && in_pos == in_len && used < cap) {
            st = cst_fail(err, CST_ERR_PARSE, "%.300s: the gzip data ends early after %zu "
                          "compressed bytes (%zu decompressed); the file is truncated", name,
                          in_len, used);
            goto done;
        }
        if (rc != Z_OK && rc != Z_BUF_ERROR) {
            if (rc == Z_MEM_ERROR)
                st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory in the gzip decoder", name);
            else
                st = cst_fail(err, CST_ERR_PARSE, "%.300s: corrupt gzip data at compressed byte "
                              "%zu: %.100s", name, in_pos, zs.msg ? zs.msg : "invalid stream");
            goto done;
        }
    }
    if ((uint64_t)used > max_out) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%.300s: the gzip data decompresses to more than "
                      "%llu bytes (the limit); expected a smaller file", name,
                      (unsigned long long)max_out);
        goto done;
    }
    buf[used] = '\0';
    *out = buf;
    *out_len = used;
    buf = NULL;
done:
    inflateEnd(&zs);
    free(buf);
    return st;
}

CstStatus gzip_read_file(const char *path, char **out, size_t *out_len, CstError *err)
{
    char *raw = NULL;
    size_t len = 0;
    CstStatus st = file_read_all(path, &raw, &len, err);
    if (st != CST_OK) return st;
    if (!gzip_is_compressed(path, raw, len)) {
        *out = raw;
        *out_len = len;
        return CST_OK;
    }
    st = gzip_inflate(path, (const unsigned char *)raw, len, GZIP_MAX_OUTPUT_BYTES, out, out_len, err);
    free(raw);
    return st;
}
