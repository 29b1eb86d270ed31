/* Part of caustic's public API, included by caustic/caustic.h (include that, not this):
 * true displacement of triangle meshes, cst_scene_displace_mesh. Kept apart only to keep
 * each header readable. */
#ifndef CAUSTIC_CAUSTIC_DISPLACE_H
#define CAUSTIC_CAUSTIC_DISPLACE_H

#ifndef CAUSTIC_CAUSTIC_H
#error "include caustic/caustic.h, which includes this header"
#endif

/* True displacement (pbrt-v4's plymesh "displacement" and "edgelength"; the JSON meshes'
 * "displacement"): a triangle mesh in its own (object) space is tessellated until every
 * edge, measured after measure_from_object, is shorter than edge_length (an edge at least
 * that long is split at its midpoint, repeatedly, the longest edge of a triangle first, as
 * pbrt-v4; a shared edge splits the same way for both its triangles, so closed meshes stay
 * closed), new vertices get the interpolated uv and normal, every vertex then moves along
 * its unit normal by the displacement (the texture's channel mean, in object units, at
 * the vertex: uv, the point texture_from_object p and the normal; or the constant `value`),
 * and the normals are recomputed from the displaced triangles. The result is handed back,
 * still in object space, for cst_scene_add_mesh. Zero-initialise, then set. */
typedef struct CstDisplaceDesc {
    const float *positions; /* num_vertices x 3, packed, finite */
    const float *normals;   /* optional num_vertices x 3, packed: each normalised, a zero one
                             * leaves its vertex in place; NULL: each vertex gets the
                             * normalised sum of its triangles' unit normals (v1 - v0) x (v2 - v1) */
    const float *uvs;       /* optional num_vertices x 2, packed; NULL: textures see (0, 0) */
    int num_vertices;
    const int *indices;     /* num_triangles x 3, in [0, num_vertices) */
    int num_triangles;
    int texture;            /* a texture id, or 0: the constant `value` */
    float value;
    float edge_length;      /* > 0 (+inf: no tessellation), in the units after measure_from_object */
    float measure_from_object[12]; /* 3 x 4 row-major affine (as cst_scene_add_instance's);
                                    * all 0: the identity */
    float texture_from_object[12]; /* the point a texture sees; all 0: the identity */
    int max_triangles;      /* the most triangles the result may have; 0: CST_DISPLACE_MAX_TRIANGLES */
} CstDisplaceDesc;

/* The default bound on a displaced mesh's triangles (2^24; measured 77 bytes per triangle at
 * the peak: about 1.2 GiB, and about 1.5 microseconds per triangle). */
#define CST_DISPLACE_MAX_TRIANGLES (1 << 24)

/* A displaced mesh, owned by the caller: cst_displaced_mesh_free(). The input's vertices
 * keep their indices; parents[t] is the input triangle output triangle t came from (each
 * keeps its parent's winding). Normals are unit, or zero where every triangle of a vertex
 * degenerated; uvs NULL when the input had none. */
typedef struct CstDisplacedMesh {
    float *positions, *normals, *uvs;
    int num_vertices;
    int *indices;
    int *parents;
    int num_triangles;
} CstDisplacedMesh;

/* Fails with CST_ERR_INVALID_ARG for a bad description (an edge_length <= 0 or NaN, an
 * index out of range, a position or displaced position that is not finite or beyond 1e18),
 * CST_ERR_UNSUPPORTED when the tessellation would exceed max_triangles (at once when the
 * mesh's area or edges alone need more, else on reaching the limit: memory stays bounded),
 * CST_ERR_OOM. The scene is only read (its textures). */
CST_API CstStatus cst_scene_displace_mesh(const CstScene *scene, const CstDisplaceDesc *desc,
                                          CstDisplacedMesh *out, CstError *err);
/* Frees m's arrays and zeroes it; accepts NULL and a zeroed mesh. */
CST_API void cst_displaced_mesh_free(CstDisplacedMesh *m);

#endif
