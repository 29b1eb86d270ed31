/* The "shapes" section: quads, triangle meshes, spheres and mesh files (through
 * mesh_import), with their transforms, validated and added to the scene. */
#ifndef CST_SCENE_JSON_JSON_GEOMETRY_H
#define CST_SCENE_JSON_JSON_GEOMETRY_H

#include "scene/json/json_reader.h"

/* The "shapes" array: every shape validated and added to the scene. */
CstStatus json_parse_shapes(Loader *ld, const json_t *shapes);

/* A "motion" object (a mesh's or the camera's): {"transform": the placement at time 0
 * (default identity), "transform_end": at time 1 (required)}, each a transform as a shape's. */
CstStatus json_parse_motion(Loader *ld, const json_t *motion, Transform *t0, Transform *t1);

#endif
