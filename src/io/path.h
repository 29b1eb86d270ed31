/* File names inside scene files: resolved against the directory of the scene file that
 * names them, the rule both loaders (JSON and pbrt) follow for meshes, textures, includes. */
#ifndef CST_IO_PATH_H
#define CST_IO_PATH_H

#include <stddef.h>

/* Bytes of `path` up to and including its last '/', 0 when it has none ("scene.pbrt",
 * "<string>"): the directory part, kept with its slash so it can be prefixed as is. */
size_t path_dir_len(const char *path);

/* `file` resolved against the directory of `scene_file` (the current directory when that
 * name has no directory, as for "<string>"); absolute files stay as they are. A new
 * NUL-terminated string (free()), or NULL on OOM. */
char *path_resolve(const char *scene_file, const char *file);

#endif
