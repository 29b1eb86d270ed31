/* SAH kd-tree over triangles and spheres: Wald & Havran's O(N log N) event-sweep build
 * with perfect splits ("On building fast kd-Trees for Ray Tracing, and on doing that in
 * O(N log N)", IEEE RT 2006), 8-byte nodes as in pbrt, and front-to-back stack traversal
 * (Havran's TA_rec_B, as in pbrt-v3's KdTreeAccel). */
#ifndef CST_ACCEL_KDTREE_H
#define CST_ACCEL_KDTREE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "math/bbox.h"

enum {
    KD_LEAF = 3,       /* KdNode.flags & 3: 0, 1, 2 = split axis of an inner node */
    KD_MAX_DEPTH = 60  /* cap on the build's depth limit; the fixed traversal stack is sized by it */
};

/* 8 bytes. Inner node: `split` is the plane's coordinate on axis flags & 3; the child
 * below the plane is the next node (depth-first layout), the one above is flags >> 2.
 * Leaf (flags & 3 == KD_LEAF): flags >> 2 primitives; one is stored inline in
 * `one_prim`, more are KdTree.prim_ids[first_prim ..] (local indices, see KdTree). */
typedef struct KdNode {
    union {
        float split;
        uint32_t one_prim;
        uint32_t first_prim;
    };
    uint32_t flags;
} KdNode;

/* A triangle's own vertices, as triangle_intersect_watertight() takes them. */
typedef struct KdTri {
    Vec3 v0, v1, v2;
} KdTri;

/* Primitives are renumbered ("local" indices) in the order the depth-first node array
 * first references them, so the data of neighbouring cells is close in memory: triangles
 * 0..num_tris-1, then spheres. Leaf lists hold local indices, in ascending order of scene
 * id. Only primitives in the tree are stored. */
typedef struct KdTree {
    KdNode *nodes;      /* nodes[0] is the root; NULL when no primitive can be hit */
    int num_nodes;
    uint32_t *prim_ids; /* leaf lists of more than one primitive (local indices) */
    int num_prim_ids;
    KdTri *tris;        /* by local index */
    int num_tris;
    Sphere *spheres;    /* by local index - num_tris */
    int num_spheres;
    uint32_t *scene_id; /* local index -> scene primitive id */
    BBox bounds;        /* of the primitives in the tree */
    float max_abs;      /* largest |coordinate| of bounds: scales the traversal's plane margin */
    int max_depth;      /* the depth limit the build used */
} KdTree;

/* Zero primitives is valid (every ray misses). Triangles of zero area (repeated or
 * collinear vertices) are left out of the tree and so never hit, as are non-finite
 * triangles and spheres. On failure (CST_ERR_OOM, or CST_ERR_UNSUPPORTED past 2^30 nodes)
 * *a is zeroed. */
CstStatus kdtree_build(KdTree *a, const AccelGeometry *geom, CstError *err);
/* Accepts NULL and a zeroed tree. */
void kdtree_free(KdTree *a);
/* Closest hit in (r.t_min, r.t_max). */
bool kdtree_intersect(const KdTree *a, const Ray *r, Hit *hit);
/* Any hit in (r.t_min, r.t_max). */
bool kdtree_occluded(const KdTree *a, const Ray *r);
/* Nodes, leaf lists, the primitive arrays and the map to scene ids. */
size_t kdtree_memory_bytes(const KdTree *a);

#endif
