/* Scene-relative file names and the temporary files of atomic writes (io/path.h). No
 * normalisation ("..", "//" stay): the names appear in messages exactly as the scene
 * writes them, after its directory. */
#define _POSIX_C_SOURCE 200809L

#include "io/path.h"

#include "core/error.h"

#include <dirent.h>
#include <errno.h>
#include <fcntl.h>
#include <limits.h>
#include <signal.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/types.h>
#include <unistd.h>

size_t path_dir_len(const char *path)
{
    const char *slash = strrchr(path, '/');
    return slash ? (size_t)(slash - path) + 1 : 0;
}

char *path_resolve(const char *scene_file, const char *file)
{
    size_t dir_len = file[0] == '/' ? 0 : path_dir_len(scene_file), len = strlen(file);
    char *p = malloc(dir_len + len + 1);
    if (!p)
        return NULL;
    memcpy(p, scene_file, dir_len);
    memcpy(p + dir_len, file, len + 1);
    return p;
}

/* ---------------------------------------------------------------- temporary files */

/* ".tmp." + a pid of up to 10 digits + "." + a number of up to 10 digits: the long form is
 * used only when it fits NAME_MAX whatever the pid and number, so the check before a
 * render (image_write_check) and the write after it pick the same form. */
enum { PATH_TEMP_SUFFIX_MAX = 5 + 10 + 1 + 10, PATH_TEMP_TRIES = 1000 };

/* FNV-1a, 64 bits (Fowler, Noll, Vo): names the short form after the file it becomes. */
static uint64_t path_fnv1a(const char *s)
{
    uint64_t h = 0xcbf29ce484222325u;
    for (; *s; ++s) h = (h ^ (uint8_t)*s) * 0x100000001b3u;
    return h;
}

/* ".cst-<16 hex>" for the last component `name`. */
static void path_temp_short_stem(const char *name, char buf[24])
{
    snprintf(buf, 24, ".cst-%016llx", (unsigned long long)path_fnv1a(name));
}

static void path_temp_name(char *buf, size_t cap, const char *path, bool short_form, long pid,
                           unsigned n)
{
    size_t dir = path_dir_len(path);
    if (!short_form) {
        snprintf(buf, cap, "%s.tmp.%ld.%u", path, pid, n);
        return;
    }
    char stem[24];
    path_temp_short_stem(path + dir, stem);
    snprintf(buf, cap, "%.*s%s.tmp.%ld.%u", (int)dir, path, stem, pid, n);
}

static CstStatus path_temp_fail(CstError *err, int e, const char *path)
{
    const char *slash = strrchr(path, '/');
    const char *dir = slash ? path : ".";
    int dir_len = slash && slash != path ? (int)(slash - path) : 1;
    char buf[128];
    if (strerror_r(e, buf, sizeof buf) != 0) snprintf(buf, sizeof buf, "error %d", e);
    if (e == ENOENT || e == ENOTDIR)
        return cst_fail(err, CST_ERR_IO, "%s: cannot write: directory \"%.*s\" does not exist (%s)",
                        path, dir_len, dir, buf);
    return cst_fail(err, CST_ERR_IO, "%s: cannot create a file in directory \"%.*s\": %s", path,
                    dir_len, dir, buf);
}

CstStatus path_temp_create(const char *path, CstTempFileFn announce, void *user, char **tmp_out,
                           int *fd_out, CstError *err)
{
    size_t name_len = strlen(path + path_dir_len(path));
    if (name_len > NAME_MAX)
        return cst_fail(err, CST_ERR_IO, "%s: file name too long (%zu bytes; at most %d)", path,
                        name_len, NAME_MAX);
    bool short_form = name_len + PATH_TEMP_SUFFIX_MAX > NAME_MAX;
    size_t cap = strlen(path) + 64;
    char *tmp = malloc(cap);
    if (!tmp) return cst_fail(err, CST_ERR_OOM, "%s: out of memory", path);
    long pid = (long)getpid();
    for (unsigned n = 0; n < PATH_TEMP_TRIES;) {
        path_temp_name(tmp, cap, path, short_form, pid, n);
        if (announce) announce(user, tmp);
        int fd = open(tmp, O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (fd >= 0) {
            *tmp_out = tmp;
            *fd_out = fd;
            return CST_OK;
        }
        int e = errno;
        if (announce) announce(user, NULL);
        if (e == EEXIST) ++n;  /* another write of this process, or a dead one's with our pid */
        else if (e == ENAMETOOLONG && !short_form) short_form = true; /* a smaller NAME_MAX */
        else if (e != EINTR) {
            free(tmp);
            return path_temp_fail(err, e, path);
        }
    }
    free(tmp);
    return cst_fail(err, CST_ERR_IO, "%s: cannot create a temporary file (%d names taken)", path,
                    PATH_TEMP_TRIES);
}

/* The pid of a temporary's name after its stem: "<pid>" or "<pid>.<n>", digits only, up
 * to the end of the name; 0 when `rest` is anything else. */
static long path_temp_pid(const char *rest)
{
    long pid = 0;
    int digits = 0;
    for (; *rest >= '0' && *rest <= '9'; ++rest, ++digits) {
        if (digits == 10) return 0;
        pid = pid * 10 + (*rest - '0');
    }
    if (digits == 0 || pid > INT_MAX) return 0;
    if (*rest == '\0') return pid;
    if (*rest++ != '.') return 0;
    for (digits = 0; *rest >= '0' && *rest <= '9'; ++rest) ++digits;
    return digits > 0 && digits <= 10 && *rest == '\0' ? pid : 0;
}

/* The pid of `entry` when it is a temporary of the file named `name` (either form). */
static long path_temp_entry_pid(const char *entry, const char *name, const char *short_stem)
{
    static const char mid[] = ".tmp.";
    size_t n = strlen(name), s = strlen(short_stem);
    if (strncmp(entry, name, n) == 0 && strncmp(entry + n, mid, sizeof mid - 1) == 0)
        return path_temp_pid(entry + n + sizeof mid - 1);
    if (strncmp(entry, short_stem, s) == 0 && strncmp(entry + s, mid, sizeof mid - 1) == 0)
        return path_temp_pid(entry + s + sizeof mid - 1);
    return 0;
}

int path_temp_remove_stale(const char *path)
{
    size_t dir_len = path_dir_len(path);
    const char *name = path + dir_len;
    if (!name[0] || strlen(name) > NAME_MAX) return 0;
    char stem[24];
    path_temp_short_stem(name, stem);
    char *file = malloc(dir_len + NAME_MAX + 2);
    if (!file) return 0;
    memcpy(file, path, dir_len);
    file[dir_len] = '\0';
    DIR *d = opendir(dir_len ? file : ".");
    int removed = 0;
    long self = (long)getpid();
    for (struct dirent *e; d && (e = readdir(d));) {
        long pid = path_temp_entry_pid(e->d_name, name, stem);
        /* Only a pid that names no process: EPERM means it lives under another user. */
        if (pid <= 0 || pid == self || kill((pid_t)pid, 0) == 0 || errno != ESRCH) continue;
        snprintf(file + dir_len, NAME_MAX + 2, "%s", e->d_name);
        removed += unlink(file) == 0;
    }
    if (d) closedir(d);
    free(file);
    return removed;
}
