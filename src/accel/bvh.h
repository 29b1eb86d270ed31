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
#include "geometry/triangle_block.h"
#include "math/bbox.h"
#include "accel/accel_geometry.h"

#define BVH_WIDTH 8
/* Beyond this depth the build splits at the median: traversal stacks stay bounded. */
#define BVH_MAX_DEPTH 60

/* An 8-wide node: the boxes of its children in structure-of-arrays form so one AVX slab
 * test checks all eight. Rows are [2 * axis + side] (side 0: min plane, 1: max plane).
 * Empty slots hold inverted infinite bounds (+inf min, -inf max), which every ray misses.
 * 224 bytes (7 units of BVH_UNIT bytes), 32-byte aligned. */
typedef struct BvhNode {
    float bounds[6][BVH_WIDTH];
    uint32_t child[BVH_WIDTH]; /* a BvhRef */
} BvhNode;

/* Child references. Inner: the byte offset in Bvh.units where a BvhNode starts (a
 * multiple of BVH_UNIT, so the low five bits are zero and the node's address is one add
 * away). Leaf (BVH_LEAF set): count - 1 in three bits, and above bit 5 either the unit
 * (Bvh.units) of a run of 1 to 8 triangle blocks or, with BVH_SPHERES set, the index of
 * a run of 1 to 8 spheres (or, with BVH_SHAPES too, analytic shapes); leaves hold one kind only, so the reference says everything
 * traversal needs without another memory access. */
#define BVH_LEAF 0x1u
#define BVH_SPHERES 0x2u
#define BVH_COUNT_SHIFT 2 /* count - 1, three bits */
#define BVH_INDEX_SHIFT 5
#define BVH_INDEX_MAX 0x07ffffffu /* largest index a leaf can hold */
#define BVH_EMPTY 0xffffffffu
/* A sphere reference with its top bit set names a run of analytic shapes instead: its
 * index (below the bit) is into Bvh.shape_ids. Sphere and shape indices thus have 26 bits;
 * triangle leaves, which never carry BVH_SPHERES, keep their 27. */
#define BVH_SHAPES 0x80000000u
#define BVH_SHAPE_INDEX_MAX 0x03ffffffu
#define BVH_NO_CURVE_SEG 0xffffffffu /* a CurveSeg.info no segment has (type 3) */
static inline bool bvh_ref_is_leaf(uint32_t ref) { return (ref & BVH_LEAF) != 0u; }
static inline uint32_t bvh_ref_index(uint32_t ref) { return ref >> BVH_INDEX_SHIFT; }
static inline uint32_t bvh_ref_count(uint32_t ref) { return ((ref >> BVH_COUNT_SHIFT) & 7u) + 1u; }

/* A leaf's triangles are TriangleBlocks (triangle_block.h): 10 units with AVX, 5 without. */

typedef struct BvhSphere {
    Vec3 center;
    float radius;
    uint32_t id;
} BvhSphere;

/* Nodes and triangle blocks share one array of 32-byte units, depth first: a node, then
 * each child in slot order (a leaf's blocks, or an inner child's node and everything
 * below it). A node's leaves thus sit right after it in memory, where the load that
 * reaches them is more likely to find its DRAM page open or its lines prefetched than in
 * an array of its own (Embree allocates nodes and leaves from one pool, in build order). */
#define BVH_UNIT 32u
typedef struct Bvh {
    unsigned char *units; /* the root node is at unit 0 (also when the scene is one leaf) */
    int num_nodes;
    int num_blocks;
    BvhSphere *spheres;
    int num_spheres;
    const AnalyticShape *shapes; /* borrowed from the AccelGeometry */
    uint32_t *shape_ids;         /* the shape leaves' scene primitive ids, leaf by leaf */
    int num_shape_ids;
    uint32_t shape_base;         /* shape k has id shape_base + k */
    /* When the scene has curves: the compact record (curve.h) of the shape in slot j of
     * shape_ids is curve_segs[j] (info BVH_NO_CURVE_SEG for other shapes and ribbons,
     * tested on their AnalyticShape), and the widths a curve's segments share: a curve
     * candidate costs one 64-byte line, in its leaf's run, not six lines and an id. */
    CurveSeg *curve_segs;        /* num_curve_segs = num_shape_ids, 64-byte aligned */
    CurveWidths *curve_widths;
    int num_curve_segs, num_curve_widths;
    int num_leaves;
    int num_prims;
    BBox bounds;
    /* The largest magnitude of any node box coordinate, per axis (lanes x, y, z, 0): the
     * FMA form of the slab test bounds its rounding with it (bvh.c, ray_box8_fma). */
    float coord_max[4];
} Bvh;

/* Units in use: every node and block, nothing else. */
static inline size_t bvh_num_units(const Bvh *bvh)
{
    return (size_t)bvh->num_nodes * (sizeof(BvhNode) / BVH_UNIT) +
           (size_t)bvh->num_blocks * (sizeof(TriangleBlock) / BVH_UNIT);
}
static inline const BvhNode *bvh_node(const Bvh *bvh, uint32_t ref)
{
    return (const BvhNode *)(const void *)(bvh->units + ref);
}
static inline const TriangleBlock *bvh_blocks(const Bvh *bvh, uint32_t index)
{
    return (const TriangleBlock *)(const void *)(bvh->units + (size_t)index * BVH_UNIT);
}

/* Zero primitives is valid (every ray misses). The build runs on all online CPUs; the
 * tree does not depend on how many. */
CstStatus bvh_build(Bvh *bvh, const AccelGeometry *geom, CstError *err);
void bvh_free(Bvh *bvh);
/* Closest hit in (ray.t_min, ray.t_max). */
bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit);
/* Any hit in (ray.t_min, ray.t_max). */
bool bvh_occluded(const Bvh *bvh, const Ray *ray);
size_t bvh_memory_bytes(const Bvh *bvh);
/* For tests: *mask = the children of node n that traversal's node test finds r meets
 * within (r.t_min, r.t_max), in the FMA form bvh_occluded uses where that is compiled in
 * and usable for r (fma), else in the sub-mul form. Returns false if fma was asked for
 * and that form is not available for r. */
bool bvh_node_test(const Bvh *bvh, const BvhNode *n, const Ray *r, bool fma, unsigned *mask);

#endif
