/* Moving shapes of the JSON format ("motion" on a mesh, sphere, cylinder, disk or torus):
 * each an object of its own placed by one moving instance (cst_scene_add_instance_motion). */
#ifndef CST_SCENE_JSON_JSON_MOTION_H
#define CST_SCENE_JSON_JSON_MOTION_H

#include "scene/json/json_reader.h"

/* A mesh with "motion" (json_parse_motion): its vertices are in object space and it becomes
 * an object and one moving instance, so instances' limits hold: no emission or medium (uvs
 * and alpha are kept). */
CstStatus json_add_moving_mesh(Loader *ld, const json_t *motion, const CstMeshDesc *mesh, const json_t *shape);

/* An analytic shape with "motion": sd (its world_from_object placing it in object space)
 * as an object of its own (cst_scene_add_object_shape) under one moving instance; the same
 * limits as a moving mesh's. */
CstStatus json_add_moving_shape(Loader *ld, const json_t *motion, const CstShapeDesc *sd, const json_t *shape);

/* The rotation that gives an analytic sphere (pole on object +z, u from +x toward +y) the
 * uvs of caustic's spheres (pole on +y, u from +z toward +x; geometry/sphere.h): object x to
 * world z, y to x, z to y. */
Transform json_sphere_uv_frame(void);

#endif
