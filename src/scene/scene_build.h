/* What the public scene builder (scene_build.c) offers the loaders beyond
 * include/caustic/caustic.h: the conversion of a loader's Material into a CstMaterialDesc.
 * The loaders build scenes through the cst_scene_* calls alone; this header holds no
 * building call and needs no Scene. */
#ifndef CST_SCENE_SCENE_BUILD_H
#define CST_SCENE_SCENE_BUILD_H

#include "caustic/caustic.h"
#include "materials/material.h"

/* The public description of a loader's Material (its texture ids are 1-based, as the
 * public ones), for cst_scene_add_material: the same material, bit for bit. */
void scene_material_desc(const Material *m, CstMaterialDesc *d);

#endif
