/* The "materials" section: material types, roughness, textured parameters, and the
 * material references and emission of shapes. */
#ifndef CST_SCENE_JSON_JSON_MATERIAL_H
#define CST_SCENE_JSON_JSON_MATERIAL_H

#include "scene/json/json_reader.h"

/* The material "type" names, NULL-terminated (cst_list_names). */
extern const char *const json_material_types[];
/* The "materials" object: every material, added to the scene in file order. */
CstStatus json_parse_materials(Loader *ld, const json_t *mats);

/* shape["material"] -> scene material id. */
CstStatus json_read_material_ref(Loader *ld, const json_t *shape, int *out);

/* A shape's optional "emission" object (radiance, two_sided, scale) into *em. */
CstStatus json_read_emission(Loader *ld, const json_t *shape, Emission *em);
/* Adds m (filled by the loader) through the public builder; fails at the current path. */
CstStatus json_add_material(Loader *ld, const Material *m, int *out_id);

#endif
