/* The "lights" (point, spot, directional) and "environment" sections. */
#ifndef CST_SCENE_JSON_JSON_LIGHT_H
#define CST_SCENE_JSON_JSON_LIGHT_H

#include "scene/json/json_reader.h"

/* The light "type" names, NULL-terminated (cst_list_names). */
extern const char *const json_light_types[];
/* The "lights" array. */
CstStatus json_parse_lights(Loader *ld, const json_t *lights);

/* "environment": a constant radiance, or an equirectangular image (EXR, PFM or PNG,
 * relative to the scene file) times a scale. */
CstStatus json_parse_environment(Loader *ld, const json_t *obj);

#endif
