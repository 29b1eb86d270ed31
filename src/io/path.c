/* Scene-relative file names (io/path.h). No normalisation ("..", "//" stay): the names
 * appear in messages exactly as the scene writes them, after its directory. */
#include "io/path.h"

#include <stdlib.h>
#include <string.h>

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
