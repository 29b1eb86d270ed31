/* Lights: point, spot and distant lights, area lights, and infinite lights whose
 * equal-area octahedral images are remapped to caustic's environment map. */
#ifndef CST_SCENE_PBRT_PBRT_LIGHT_H
#define CST_SCENE_PBRT_PBRT_LIGHT_H

#include "scene/pbrt/pbrt_loader.h"

/* Directive handlers, called through the table in pbrt_scene.c. */
CstStatus pbrt_light_source_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_area_light_source_directive(Loader *ld, NamedCall *call);

/* pbrt-v4's equal-area octahedral map between unit directions and [0, 1]^2 (Clarberg 2008),
 * the layout of infinite lights' images. */
void pbrt_equal_area_sphere_to_square(const double d[3], double uv[2]);
void pbrt_equal_area_square_to_sphere(const double uv[2], double d[3]);

#endif
