/* Input files: the regular-file and size check every reader goes through, and whole-file
 * reads for the scene loaders. */
#include "core/file.h"

#include <errno.h>
#include <fcntl.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "core/error.h"

/* What a non-regular file is, for "is not a regular file (...)". */
static const char *file_kind(mode_t m)
{
    if (S_ISDIR(m)) return "a directory";
    if (S_ISFIFO(m)) return "a FIFO";
    if (S_ISCHR(m)) return "a character device";
    if (S_ISBLK(m)) return "a block device";
    if (S_ISSOCK(m)) return "a socket";
    return "not a file";
}

CstStatus file_open_input(const char *path, FILE **out, uint64_t *size_out, CstError *err)
{
    *out = NULL;
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "an input file name is empty");
    /* O_NONBLOCK: opening a FIFO without a writer (or some devices) would wait forever;
     * for a regular file the flag changes nothing and is cleared below anyway. */
    int fd = open(path, O_RDONLY | O_NONBLOCK | O_CLOEXEC | O_NOCTTY);
    if (fd < 0) return cst_fail(err, CST_ERR_IO, "%.300s: cannot open: %s", path, strerror(errno));
    struct stat sb;
    CstStatus st = CST_OK;
    if (fstat(fd, &sb) != 0)
        st = cst_fail(err, CST_ERR_IO, "%.300s: cannot open: %s", path, strerror(errno));
    else if (!S_ISREG(sb.st_mode))
        st = cst_fail(err, CST_ERR_IO, "%.300s: is not a regular file (%s); expected a file", path,
                      file_kind(sb.st_mode));
    else if (sb.st_size < 0 || (uint64_t)sb.st_size > FILE_MAX_INPUT_BYTES)
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%.300s: is %.1f GiB; expected at most %llu GiB (the "
                      "input file size limit)", path, (double)sb.st_size / (1u << 30),
                      (unsigned long long)(FILE_MAX_INPUT_BYTES >> 30));
    else {
        int flags = fcntl(fd, F_GETFL);
        if (flags == -1 || fcntl(fd, F_SETFL, flags & ~O_NONBLOCK) == -1)
            st = cst_fail(err, CST_ERR_IO, "%.300s: cannot open: %s", path, strerror(errno));
    }
    FILE *f = st == CST_OK ? fdopen(fd, "rb") : NULL;
    if (st == CST_OK && !f) st = cst_fail(err, CST_ERR_IO, "%.300s: cannot open: %s", path, strerror(errno));
    if (st != CST_OK) {
        close(fd);
        return st;
    }
    if (size_out) *size_out = (uint64_t)sb.st_size;
    *out = f;
    return CST_OK;
}

CstStatus file_check_input(const char *path, CstError *err)
{
    FILE *f = NULL;
    CstStatus st = file_open_input(path, &f, NULL, err);
    if (f) fclose(f);
    return st;
}

CstStatus file_read_all(const char *path, char **out, size_t *out_len, CstError *err)
{
    FILE *f = NULL;
    uint64_t size = 0;
    CstStatus st = file_open_input(path, &f, &size, err);
    if (st != CST_OK) return st;
    /* The size at the check sizes the buffer; a file that grows meanwhile is read on, up to
     * the limit and no further. */
    size_t cap = (size_t)size + 1, len = 0;
    char *buf = malloc(cap + 1);
    if (!buf) {
        st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory reading the file", path);
        goto done;
    }
    for (;;) {
        if (len == cap) {
            if ((uint64_t)cap > FILE_MAX_INPUT_BYTES) {
                st = cst_fail(err, CST_ERR_UNSUPPORTED, "%.300s: grew beyond %llu GiB while being read "
                              "(the input file size limit)", path,
                              (unsigned long long)(FILE_MAX_INPUT_BYTES >> 30));
                goto done;
            }
            size_t ncap = cap * 2 > (size_t)FILE_MAX_INPUT_BYTES + 1 ? (size_t)FILE_MAX_INPUT_BYTES + 1 : cap * 2;
            char *nb = realloc(buf, ncap + 1);
            if (!nb) {
                st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory reading the file", path);
                goto done;
            }
            buf = nb;
            cap = ncap;
        }
        size_t n = fread(buf + len, 1, cap - len, f);
        len += n;
        if (n == 0) {
            if (ferror(f)) st = cst_fail(err, CST_ERR_IO, "%.300s: cannot read: %s", path, strerror(errno));
            break;
        }
    }
done:
    fclose(f);
    if (st != CST_OK) {
        free(buf);
        return st;
    }
    buf[len] = '\0';
    *out = buf;
    *out_len = len;
    return CST_OK;
}
