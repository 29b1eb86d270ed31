/* The settings sections of a JSON scene: "film", "camera", "integrator", "sampler". */
#ifndef CST_SCENE_JSON_JSON_SETTINGS_H
#define CST_SCENE_JSON_JSON_SETTINGS_H

#include "scene/json/json_reader.h"

/* Each reads one settings section into ld->scene->settings (or its camera); the current
 * path is the section. */
CstStatus json_parse_film(Loader *ld, const json_t *film);

CstStatus json_parse_camera(Loader *ld, const json_t *cam);

CstStatus json_parse_integrator(Loader *ld, const json_t *integ);

CstStatus json_parse_sampler(Loader *ld, const json_t *sampler);

#endif
