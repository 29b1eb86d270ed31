/* The JSON loader's participating media: the "media" section, "camera_medium", and a
 * shape's "medium" interface (docs/scene-format.md). */
#ifndef CST_SCENE_JSON_JSON_MEDIUM_H
#define CST_SCENE_JSON_JSON_MEDIUM_H

#include "scene/json/json_reader.h"

/* "media": an object mapping names to media; each is added to the scene in file order. */
CstStatus json_parse_media(Loader *ld, const json_t *media);
/* "camera_medium": a medium's name, or null (vacuum). */
CstStatus json_parse_camera_medium(Loader *ld, const json_t *v);
/* A shape's "medium" ({"inside", "outside", "boundary"}): sets the interface of the shape
 * about to be added (none when absent). *boundary: the shape is a pure medium boundary,
 * whose "material" is then optional (*material, when it is -1, gets a placeholder). */
CstStatus json_read_shape_medium(Loader *ld, const json_t *shape, int *boundary);
CstStatus json_boundary_material(Loader *ld, int *material);

#endif
