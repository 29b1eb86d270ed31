/* Bounding volume hierarchy over triangles and spheres: binned SAH build (Wald,
 * "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007), parallel over
 * subtrees, collapsed into an 8-wide tree for AVX box tests; near-to-far ordered
 * traversal for closest hits and early exit for occlusion. */
#ifndef CST_ACCEL_BVH_H
#define CST_ACCEL_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "geometry/sphere.h"
#include "math/bbox.h"
#include "accel/accel_geometry.h"

#define BVH_WIDTH 8

/* An 8-wide node: the boxes of its children in structure-of-arrays form so one AVX slab
 * test checks all eight. Rows are [2 * axis + side] (side 0: min plane, 1: max plane).
 * Empty slots hold NaN bounds, which every finite ray misses (see node_hit8 in bvh.c).
 * 224 bytes, 32-byte aligned. */
typedef struct BvhNode {
    float bounds[6][BVH_WIDTH];
    uint32_t child[BVH_WIDTH]; /* a BvhRef */
} BvhNode;

/* Child references. Inner: index of a BvhNode. Leaf (BVH_LEAF set): a run of 1 to 8
 * triangle blocks or, with BVH_SPHERES set, of 1 to 8 spheres; leaves hold one kind only,
 * so the reference says everything traversal needs without another memory access. */
#define BVH_LEAF 0x80000000u
#define BVH_SPHERES 0x40000000u
#define BVH_COUNT_SHIFT 27 /* count - 1, three bits */
#define BVH_INDEX_MASK 0x07ffffffu
#define BVH_EMPTY 0xffffffffu
static inline bool bvh_ref_is_leaf(uint32_t ref) { return (ref & BVH_LEAF) != 0u; }
static inline uint32_t bvh_ref_index(uint32_t ref) { return ref & BVH_INDEX_MASK; }
static inline uint32_t bvh_ref_count(uint32_t ref) { return ((ref >> BVH_COUNT_SHIFT) & 7u) + 1u; }

/* Four triangles' vertices in SoA form, v[vertex][axis][lane], for one SSE watertight
 * test; indexing by axis lets the per-ray axis permutation pick rows. Unused lanes have
 * id BVH_NO_PRIM and NaN vertices. */
typedef struct BvhTriBlock {
    float v[3][3][4];
    uint32_t id[4]; /* scene primitive ids */
} BvhTriBlock;
#define BVH_NO_PRIM 0xffffffffu

typedef struct BvhSphere {
    Vec3 center;
    float radius;
    uint32_t id;
} BvhSphere;

typedef struct Bvh {
    BvhNode *nodes; /* nodes[0] is the root (also when the whole scene is one leaf) */
    int num_nodes;
    BvhTriBlock *blocks;
    int num_blocks;
    BvhSphere *spheres;
    int num_spheres;
    int num_leaves;
    int num_prims;
    BBox bounds;
} Bvh;

/* Zero primitives is valid (every ray misses). The build runs on all online CPUs; the
 * tree does not depend on how many. */
CstStatus bvh_build(Bvh *bvh, const AccelGeometry *geom, CstError *err);
void bvh_free(Bvh *bvh);
/* Closest hit in (ray.t_min, ray.t_max). */
bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit);
/* Any hit in (ray.t_min, ray.t_max). */
bool bvh_occluded(const Bvh *bvh, const Ray *ray);
size_t bvh_memory_bytes(const Bvh *bvh);

#endif
