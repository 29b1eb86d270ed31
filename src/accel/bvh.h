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
#include "geometry/ray.h"
#include "geometry/sphere.h"
#include "math/bbox.h"

/* A 4-wide node: the boxes of its (up to) four children in structure-of-arrays form so
 * one SSE slab test checks all four. Built by collapsing a binary SAH tree (each wide
 * node absorbs the largest-area inner grandchildren). A child is an inner node
 * (count == 0, child >= 0), a leaf (count > 0, child = first index into Bvh.prims) or
 * empty (not in valid_mask: an inverted box is no use, since the min/max form of the slab
 * test turns an inverted box into an infinite one). */
typedef struct BvhNode {
    float bmin_x[4], bmax_x[4], bmin_y[4], bmax_y[4], bmin_z[4], bmax_z[4];
    int32_t child[4];
    uint16_t count[4];
    uint32_t valid_mask; /* bit i set: child i exists */
    uint32_t pad;
} BvhNode;

enum { BVH_PRIM_TRIANGLE = 0, BVH_PRIM_SPHERE = 1 };

/* Leaf-ordered primitive data so a leaf reads one contiguous block: triangles as
 * (v0, e1, e2) for Moller-Trumbore; spheres as centre = v0, radius = e1.x. */
typedef struct BvhPrim {
    Vec3 v0, e1, e2;
    uint32_t id;   /* scene primitive id */
    uint32_t kind; /* BVH_PRIM_* */
    float pad;
} BvhPrim;

typedef struct Bvh {
    BvhNode *nodes;
    int num_nodes;
    BvhPrim *prims;
    int num_prims;
    BBox bounds;
} Bvh;

typedef struct Hit {
    float t;
    float u, v;    /* triangle barycentrics of v1, v2 */
    uint32_t prim; /* scene primitive id */
} Hit;

/* Triangles are tri_indices[3i..3i+2] into positions, ids 0..num_tris-1; spheres get ids
 * num_tris.. in order. Zero primitives is valid (every ray misses). */
CstStatus bvh_build(Bvh *bvh, const Vec3 *positions, const int32_t *tri_indices, int num_tris,
                    const Sphere *spheres, int num_spheres, CstError *err);
void bvh_free(Bvh *bvh);
/* Closest hit in (ray.t_min, ray.t_max). */
bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit);
/* Any hit in (ray.t_min, ray.t_max). */
bool bvh_occluded(const Bvh *bvh, const Ray *ray);
size_t bvh_memory_bytes(const Bvh *bvh);

#endif
