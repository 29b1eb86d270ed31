/* File names: those inside scene files, resolved against the directory of the scene file
 * that names them (the rule both loaders, JSON and pbrt, follow for meshes, textures,
 * includes); and the temporary files of atomic writes, next to the file they become. */
#ifndef CST_IO_PATH_H
#define CST_IO_PATH_H

#include "caustic/caustic.h"

#include <stddef.h>

/* Bytes of `path` up to and including its last '/', 0 when it has none ("scene.pbrt",
 * "<string>"): the directory part, kept with its slash so it can be prefixed as is. */
size_t path_dir_len(const char *path);

/* `file` resolved against the directory of `scene_file` (the current directory when that
 * name has no directory, as for "<string>"); absolute files stay as they are. A new
 * NUL-terminated string (free()), or NULL on OOM. */
char *path_resolve(const char *scene_file, const char *file);

/* ---- temporary files of atomic writes
 * The temporary of `path` lives in the same directory (so rename() is atomic) and is named
 *     <name>.tmp.<pid>.<n>                      when that fits in NAME_MAX bytes for any
 *                                               pid and n (a name of at most 229 bytes),
 *     .cst-<16 hex digits>.tmp.<pid>.<n>        otherwise, or when the file system refuses
 *                                               the long form (ENAMETOOLONG),
 * where <name> is the last component of `path`, the hex digits its 64-bit FNV-1a hash,
 * <pid> the writing process and <n> the first number from 0 whose name is free. */

/* Creates the temporary file for writing `path` exclusively (O_EXCL), mode 0666 so the
 * umask decides the final permissions as for a plain fopen (mkstemp would force 0600).
 * `announce` (may be NULL) is called with each name before the file is created, so a
 * signal handler that removes the announced name never leaves one behind; every name it
 * may see holds this process's pid. On success *tmp_out (free()) and *fd_out are the
 * file's; on failure the message names the directory and the reason. */
CstStatus path_temp_create(const char *path, CstTempFileFn announce, void *user, char **tmp_out,
                           int *fd_out, CstError *err);

/* Removes the temporaries of `path` left by processes that no longer exist: names of
 * exactly the two forms above for this `path`, whose pid is not this process's and for
 * which kill(pid, 0) fails with ESRCH. Other files are never touched. Returns how many
 * were removed; a directory that cannot be read removes nothing. */
int path_temp_remove_stale(const char *path);

#endif
