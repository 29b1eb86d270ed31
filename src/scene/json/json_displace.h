/* A mesh's "displacement" (true displacement: docs/scene-format.md): the mesh's arrays
 * replaced by its tessellated, displaced copy from the public builder. */
#ifndef CST_SCENE_JSON_JSON_DISPLACE_H
#define CST_SCENE_JSON_JSON_DISPLACE_H

#include "math/transform.h"
#include "scene/json/json_reader.h"

/* A mesh being loaded: malloc'd arrays (n, uv, tri_mat may be NULL). */
typedef struct JsonMesh {
    Vec3 *p, *n;
    Vec2 *uv;
    int *idx;
    int nv, nt;
    int *tri_mat; /* optional per-triangle values, carried to each triangle's pieces */
} JsonMesh;

/* With shape["displacement"] = {"texture": a texture name or a number (a constant
 * displacement), "edgelength": a length > 0}, replaces m's arrays (object space, placed by
 * xf; NULL: world space already) by the displaced mesh: edges measured after xf, the
 * texture at the vertex's uv, normal and point xf p. m->n is set (recomputed) either way.
 * Without the key, m is left alone. Errors are located inside "displacement". */
CstStatus json_read_displacement(Loader *ld, const json_t *shape, const Transform *xf, JsonMesh *m);

#endif
