/* The "textures" section: constants, checkerboards and image files, read on first use so
 * that checkerboards may name textures listed after them. */
#ifndef CST_SCENE_JSON_JSON_TEXTURE_H
#define CST_SCENE_JSON_JSON_TEXTURE_H

#include "scene/json/json_reader.h"

/* Scene id of the texture called `name`, read now if it has not been. The error points at
 * the current path (the value naming it). */
CstStatus json_read_texture_name(Loader *ld, const char *name, int *out);

/* The "textures" object: every texture read and added to the scene (checkerboards read
 * the textures they name first, wherever those are listed). */
CstStatus json_parse_textures(Loader *ld, const json_t *texs);

/* A material parameter given as a texture name: its id + 1 (Material's convention), after
 * checking the texture's values fit the parameter (at most 1 for reflectances and
 * roughness). The current path is the parameter's value. */
CstStatus json_read_param_texture(Loader *ld, const json_t *v, const char *what, int *out);

#endif
