/* Whole-file reads shared by the scene loaders. */
#include "core/file.h"

#include <errno.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

CstStatus file_read_all(const char *path, char **out, size_t *out_len, CstError *err)
{
    FILE *f = fopen(path, "rb");
    if (!f)
        return cst_fail(err, CST_ERR_IO, "%.200s: cannot open: %s", path, strerror(errno));
    size_t cap = 1 << 16, len = 0;
    char *buf = malloc(cap);
    CstStatus st = CST_OK;
    if (!buf) {
        st = cst_fail(err, CST_ERR_OOM, "%.200s: out of memory reading the file", path);
        goto done;
    }
    for (;;) {
        if (len == cap) {
            char *nb = cap <= SIZE_MAX / 2 ? realloc(buf, cap * 2) : NULL;
            if (!nb) {
                st = cst_fail(err, CST_ERR_OOM, "%.200s: out of memory reading the file", path);
                goto done;
            }
            buf = nb;
            cap *= 2;
        }
        size_t n = fread(buf + len, 1, cap - len, f);
        len += n;
        if (n == 0) {
            if (ferror(f))
                st = cst_fail(err, CST_ERR_IO, "%.200s: cannot read: %s", path, strerror(errno));
            break;
        }
    }
done:
    fclose(f);
    if (st != CST_OK) {
        free(buf);
        return st;
    }
    *out = buf;
    *out_len = len;
    return CST_OK;
}
