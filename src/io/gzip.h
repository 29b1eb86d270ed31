/* Files that may be gzip-compressed: recognised by a ".gz" name or the gzip magic bytes
 * (1f 8b), inflated with zlib under a stated limit on the decompressed size. */
#ifndef CST_IO_GZIP_H
#define CST_IO_GZIP_H

#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"

/* Largest decompressed size gzip_read_file accepts: 4 GiB, the same bound as an
 * uncompressed input file (FILE_MAX_INPUT_BYTES, docs/scene-format.md). */
#define GZIP_MAX_OUTPUT_BYTES ((uint64_t)4 << 30)

/* True when data (len bytes) starts with the gzip magic 1f 8b, or path (may be NULL) ends
 * in ".gz" (any case). */
int gzip_is_compressed(const char *path, const void *data, size_t len);

/* Inflates the gzip stream in[0..in_len) (one or more concatenated members, as gzip(1)
 * writes them) into a new malloc'd buffer, NUL-terminated one byte past *out_len. The
 * buffer grows by doubling as output arrives, so its size is at most twice what the
 * stream really holds. Errors name `name`: CST_ERR_PARSE for a corrupt or truncated
 * stream ("NAME: corrupt gzip data at compressed byte N: REASON"), CST_ERR_UNSUPPORTED
 * when the output exceeds max_out bytes, CST_ERR_OOM. */
CstStatus gzip_inflate(const char *name, const unsigned char *in, size_t in_len, uint64_t max_out,
                       char **out, size_t *out_len, CstError *err);

/* Reads all of path (core/file.h's file_read_all: a regular file of at most 4 GiB) and,
 * when gzip_is_compressed says so, inflates it with the limit GZIP_MAX_OUTPUT_BYTES.
 * *out is malloc'd and NUL-terminated like file_read_all's; the caller frees it. */
CstStatus gzip_read_file(const char *path, char **out, size_t *out_len, CstError *err);

#endif
