/* Materials: pbrt-v4's material types mapped onto caustic's Material (roughness remapping,
 * conductors, coated layers), named materials, and the Material directives. */
#ifndef CST_SCENE_PBRT_PBRT_MATERIAL_H
#define CST_SCENE_PBRT_PBRT_MATERIAL_H

#include "scene/pbrt/pbrt_loader.h"

CstStatus pbrt_add_mat_entry(Loader *ld, const char *name, const Material *m, int *out);

CstStatus pbrt_material_scene_id(Loader *ld, int entry, int *out);

/* Material and MakeNamedMaterial. */
CstStatus pbrt_material_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_named_material_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
