/* Adaptive octree over triangles, spheres and analytic shapes: a cell splits into its 8 octants while it
 * holds more than OCTREE_LEAF_PRIMS primitives (and is shallower than OCTREE_MAX_DEPTH),
 * primitives referenced in every octant they overlap (exact triangle-box and sphere-box
 * tests; a shape by its world bounds), front-to-back traversal of the octants in the ray's octant order, per-ray hashed
 * mailboxing and SIMD triangle tests. Hits are bit-identical to the list back end's. */
#ifndef CST_ACCEL_OCTREE_H
#define CST_ACCEL_OCTREE_H

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
    OCTREE_LEAF_PRIMS = 8,  /* a cell with more primitives splits (unless at the depth limit) */
    OCTREE_MAX_DEPTH = 16,  /* cells of depth 16 are as thin as the build margin (octree.c) */
    OCTREE_INNER = -1       /* OctNode.num_tris of an inner node (as a uint32_t) */
};

/* 16 bytes. Inner node (num_tris == OCTREE_INNER): its 8 children are nodes[first + c],
 * c = octant (bit a set: the upper half on axis a), and bit c of num_spheres says child c
 * is not an empty leaf (the traversal skips empty ones without loading them). Leaf: its primitives are
 * Octree.slots[first ..], num_tris triangle slots, num_spheres sphere slots, then
 * num_shapes shape slots (those hold scene primitive ids, as geometry/shape.h's leaf test
 * takes them); an empty leaf has all 0. One count per primitive kind. */
typedef struct OctNode {
    uint32_t first;
    uint32_t num_tris;
    uint32_t num_spheres;
    uint32_t num_shapes;
} OctNode;

/* A triangle's own vertices, the floats the list back end tests (bit-identical hits). */
typedef TriVerts OctTri; /* geometry/triangle_block.h: the vertices and the scene primitive id */

typedef struct OctSphere {
    Vec3 center;
    float radius;
    uint32_t id; /* scene primitive id */
} OctSphere;

/* A slot of a triangle leaf indexes tris, a slot of a sphere leaf indexes spheres. The
 * root cell is the box of the primitives grown by twice the margin; a cell holds every
 * primitive that comes within `margin` of it (max norm). Cell boxes are not stored: the
 * traversal halves the root's, exactly, in double. Read-only after octree_build. */
typedef struct Octree {
    OctNode *nodes;       /* nodes[0] is the root; NULL when no primitive can be hit */
    int num_nodes;
    uint32_t *slots;
    size_t num_refs;
    OctTri *tris;         /* in scene order, non-finite ones left out */
    int num_tris;
    OctSphere *spheres;
    int num_spheres;
    AnalyticShape *shapes; /* a copy of every shape of geom (shape k has id shape_base + k) */
    int num_shapes;
    uint32_t shape_base;
    double org[3];        /* root cell: minimum corner and size, per axis */
    double size[3];
    double cell[OCTREE_MAX_DEPTH + 1][3]; /* cell size at each depth: size / 2^depth, exact */
    BBox bounds;          /* float copy of the root cell (rounded outward) */
    float margin;
    int depth;            /* deepest leaf */
    int num_leaves;
} Octree;

/* Zero primitives is valid (every ray misses). Copies what it needs from geom. On failure
 * (CST_ERR_OOM, CST_ERR_INVALID_ARG past 2^31 primitives) *a is zeroed. */
CstStatus octree_build(Octree *a, const AccelGeometry *geom, CstError *err);
/* Accepts NULL and a zeroed or already freed octree. */
void octree_free(Octree *a);
/* Closest hit in (r.t_min, r.t_max). */
bool octree_intersect(const Octree *a, const Ray *r, Hit *hit);
/* Any hit in (r.t_min, r.t_max). */
bool octree_occluded(const Octree *a, const Ray *r);
/* Nodes, slots and the octree's copies of the primitives. */
size_t octree_memory_bytes(const Octree *a);

#endif
