/* Bounding volume hierarchy over triangles and spheres: binned SAH build (Wald,
 * "On fast Construction of SAH-based Bounding Volume Hierarchies", 2007), flattened
 * depth-first so the first child directly follows its parent, ordered traversal for
 * closest hits and early exit for occlusion. */
#ifndef CST_ACCEL_BVH_H
#define CST_ACCEL_BVH_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "geometry/ray.h"
#include "geometry/sphere.h"
#include "math/bbox.h"

typedef struct BvhNode {
    float bmin[3];
    int32_t offset; /* leaf: first index into Bvh.prims; inner: index of the second child */
    float bmax[3];
    uint16_t count; /* number of primitives in a leaf; 0 for inner nodes */
    uint8_t axis;   /* inner: split axis, picks the near child from the ray direction sign */
    uint8_t pad;
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
