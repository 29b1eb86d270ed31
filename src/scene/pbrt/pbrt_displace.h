/* pbrt-v4's true displacement of "plymesh" ("texture displacement", "float edgelength"):
 * the shape's object-space mesh tessellated and displaced through the public builder. */
#ifndef CST_SCENE_PBRT_PBRT_DISPLACE_H
#define CST_SCENE_PBRT_PBRT_DISPLACE_H

#include "scene/pbrt/pbrt_loader.h"

/* With a "texture displacement", replaces g (object space, placed by the CTM) by its
 * displaced tessellation (cst_scene_displace_mesh) as pbrt-v4's plymesh: "edgelength"
 * (default 1) measured in pbrt-v4's render space, the texture evaluated at the vertex's
 * uv and at its object-space point read as a render-space one, the normals recomputed.
 * Without it, g is left alone ("edgelength" is read either way, as pbrt-v4 reads it).
 * Located errors: an edgelength <= 0, a mesh without uvs (pbrt-v4 stops there too), a
 * tessellation beyond the triangle limit. */
CstStatus pbrt_displace_shape(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g);

#endif
