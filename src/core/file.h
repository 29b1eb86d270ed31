/* Whole-file reads for the scene loaders: one buffer, pipes and FIFOs included. */
#ifndef CST_CORE_FILE_H
#define CST_CORE_FILE_H

#include <stddef.h>

#include "caustic/caustic.h"

/* Reads all of path into a new malloc'd buffer (not NUL-terminated; *out_len bytes).
 * Errors (CST_ERR_IO, CST_ERR_OOM) name the path and the system's reason. */
CstStatus file_read_all(const char *path, char **out, size_t *out_len, CstError *err);

#endif
