/* Bounding volume hierarchy over triangles and spheres: binned SAH build (Wald,
 * "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007) collapsed into a
 * 4-wide tree for SSE box tests, near-to-far ordered traversal for closest hits and early
 * exit for occlusion. */
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

/* A 4-wide node: the boxes of its (up to) four children in structure-of-arrays form so
 * one SSE slab test checks all four. Built by collapsing a binary SAH tree (each wide
 * node absorbs the largest-area inner grandchildren). Child i is an inner node
 * (is_leaf[i] == 0: child[i] indexes Bvh.nodes) or a leaf (child[i] indexes Bvh.leaves);
 * slots outside valid_mask are empty. (An inverted box cannot mark an empty slot: the
 * min/max form of the slab test turns it into an infinite one.) */
typedef struct BvhNode {
    float bmin_x[4], bmax_x[4], bmin_y[4], bmax_y[4], bmin_z[4], bmax_z[4];
    int32_t child[4];
    uint16_t is_leaf[4];
    uint32_t valid_mask; /* bit i set: child i exists */
    uint32_t pad;
} BvhNode;

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

/* A leaf's contents: a run of triangle blocks and a run of spheres. */
typedef struct BvhLeaf {
    uint32_t first_block, first_sphere;
    uint16_t num_blocks, num_spheres;
} BvhLeaf;

typedef struct Bvh {
    BvhNode *nodes;
    int num_nodes;
    BvhLeaf *leaves;
    int num_leaves;
    BvhTriBlock *blocks;
    int num_blocks;
    BvhSphere *spheres;
    int num_spheres;
    int num_prims;
    BBox bounds;
} Bvh;


/* Zero primitives is valid (every ray misses). */
CstStatus bvh_build(Bvh *bvh, const AccelGeometry *geom, CstError *err);
void bvh_free(Bvh *bvh);
/* Closest hit in (ray.t_min, ray.t_max). */
bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit);
/* Any hit in (ray.t_min, ray.t_max). */
bool bvh_occluded(const Bvh *bvh, const Ray *ray);
size_t bvh_memory_bytes(const Bvh *bvh);

#endif
