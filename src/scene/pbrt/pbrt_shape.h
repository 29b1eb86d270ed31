/* Shapes: spheres, disks, triangle meshes and PLY files placed by the CTM with pbrt's
 * orientation rules; ObjectBegin/End definitions and their instances. */
#ifndef CST_SCENE_PBRT_PBRT_SHAPE_H
#define CST_SCENE_PBRT_PBRT_SHAPE_H

#include "scene/pbrt/pbrt_loader.h"

/* Frees g's arrays. */
void pbrt_geom_free(ShapeGeom *g);

/* Finite and within PBRT_MAX_LENGTH on every axis. */
int pbrt_coords_ok(Vec3 p);

/* A shape's "alpha" (a float or a float texture) as a cut-out; zero when opaque. */
CstStatus pbrt_shape_alpha(Loader *ld, Params *ps, const char *d, CstAlpha *out);

/* Directive handlers, called through the table in pbrt_scene.c. */
CstStatus pbrt_shape_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_object_instance_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_object_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_object_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
