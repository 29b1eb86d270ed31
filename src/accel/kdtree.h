/* SAH kd-tree over triangles and spheres: Wald & Havran's O(N log N) event-sweep build
 * with perfect splits ("On building fast kd-Trees for Ray Tracing, and on doing that in
 * O(N log N)", IEEE RT 2006), 8-byte nodes as in pbrt, front-to-back stack traversal
 * (Havran's TA_rec_B, as in pbrt-v3's KdTreeAccel) and leaves of SIMD triangle blocks. */
#ifndef CST_ACCEL_KDTREE_H
#define CST_ACCEL_KDTREE_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "geometry/triangle_block.h"
#include "math/bbox.h"

enum {
    KD_LEAF = 3,         /* KdNode.flags & 3: 0, 1, 2 = split axis of an inner node */
    KD_EMPTY_BELOW = 4,  /* inner node flag: the child below the plane is an empty leaf */
    KD_EMPTY_ABOVE = 8,  /* inner node flag: the child above the plane is an empty leaf */
    KD_LEAF_SPHERES = 4, /* leaf flag: the leaf holds spheres */
    KD_MAX_DEPTH = 60    /* cap on the build's depth limit; the fixed traversal stack is sized by it */
};

/* 8 bytes. Inner node: `split` is the plane's coordinate on axis flags & 3 and flags >> 4
 * is the child above the plane; the child below is the next node (depth-first layout).
 * A child that is an empty leaf is not stored: the parent's KD_EMPTY_BELOW or
 * KD_EMPTY_ABOVE says so, and the traversal never enters it (with the empty-space bonus
 * most leaves are empty). Leaf (flags & 3 == KD_LEAF): without KD_LEAF_SPHERES, triangles
 * only, flags >> 3 blocks from KdTree.blocks[first]; with it, KdTree.sphere_leaves[first]
 * says where its blocks and spheres are. */
typedef struct KdNode {
    union {
        float split;
        uint32_t first;
    };
    uint32_t flags;
} KdNode;

typedef struct KdSphere {
    Vec3 center;
    float radius;
    uint32_t id; /* scene primitive id */
} KdSphere;

/* A leaf holding spheres: its triangle blocks, then its spheres (scene ids of spheres
 * exceed every triangle's, so this is ascending id order). */
typedef struct KdSphereLeaf {
    uint32_t first_block, num_blocks;
    uint32_t first_sphere, num_spheres;
    uint32_t first_shape, num_shapes; /* in KdTree.shape_ids, after the spheres in id order */
} KdSphereLeaf;

/* Each leaf holds copies of its primitives in ascending order of scene id (the order exact
 * ties in t resolve in): a primitive straddling several leaves is copied into each. Only
 * primitives in the tree are stored. */
typedef struct KdTree {
    KdNode *nodes;      /* nodes[0] is the root; NULL when no primitive can be hit */
    int num_nodes;
    /* By leaf, in node order: a leaf's triangles are consecutive blocks, one dependent
     * memory access, not one per triangle. */
    TriangleBlock *blocks;
    int num_blocks;
    KdSphere *spheres;  /* by leaf, in node order */
    int num_spheres;
    KdSphereLeaf *sphere_leaves; /* also the leaves holding analytic shapes */
    int num_sphere_leaves;
    const AnalyticShape *shapes; /* borrowed from the AccelGeometry */
    uint32_t *shape_ids;         /* by leaf, in node order: scene primitive ids */
    int num_shape_ids;
    uint32_t shape_base;         /* shape k has id shape_base + k */
    BBox bounds;        /* of the primitives in the tree */
    float max_abs;      /* largest |coordinate| of bounds: scales the traversal's plane margin */
    int max_depth;      /* the depth limit the build used */
} KdTree;

/* Zero primitives is valid (every ray misses). Triangles of zero area (repeated or
 * collinear vertices) are left out of the tree and so never hit, as are non-finite
 * triangles and spheres. On failure (CST_ERR_OOM, or CST_ERR_UNSUPPORTED past 2^28 nodes
 * or 2^31 primitive references) *a is zeroed. */
CstStatus kdtree_build(KdTree *a, const AccelGeometry *geom, CstError *err);
/* Accepts NULL and a zeroed tree. */
void kdtree_free(KdTree *a);
/* Closest hit in (r.t_min, r.t_max). */
bool kdtree_intersect(const KdTree *a, const Ray *r, Hit *hit);
/* Any hit in (r.t_min, r.t_max). */
bool kdtree_occluded(const KdTree *a, const Ray *r);
/* Nodes, triangle blocks, spheres and sphere-leaf records. */
size_t kdtree_memory_bytes(const KdTree *a);

#endif
