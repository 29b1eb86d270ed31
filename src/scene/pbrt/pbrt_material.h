/* Materials: pbrt-v4's material types mapped onto caustic's Material (roughness remapping,
 * conductors, coated layers), named materials, and the Material directives. */
#ifndef CST_SCENE_PBRT_PBRT_MATERIAL_H
#define CST_SCENE_PBRT_PBRT_MATERIAL_H

#include "scene/pbrt/pbrt_loader.h"

/* Adds a material (named, or anonymous when name is NULL) to the loader; *out is its
 * index in ld->mats. It reaches the scene on first use (pbrt_material_scene_id). */
CstStatus pbrt_add_mat_entry(Loader *ld, const char *name, const Material *m, int *out);

/* The scene's id of material entry `entry`, adding it to the scene on first use. */
CstStatus pbrt_material_scene_id(Loader *ld, int entry, int *out);

/* Directive handlers, called through the table in pbrt_scene.c; pbrt_material_directive
 * serves Material and MakeNamedMaterial. */
CstStatus pbrt_material_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_named_material_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
