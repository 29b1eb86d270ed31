/* One acceleration interface over interchangeable back ends: build, closest hit,
 * occlusion, bounds, memory, free. Dispatch is a switch on the type tag (closed
 * polymorphism: the compiler sees every case, no indirect calls per ray). */
#ifndef CST_ACCEL_ACCEL_H
#define CST_ACCEL_ACCEL_H

#include <stdbool.h>
#include <stddef.h>

#include "accel/accel_geometry.h"
#include "accel/bvh.h"
#include "accel/embree.h"
#include "accel/grid.h"
#include "accel/kdtree.h"
#include "accel/list.h"
#include "accel/octree.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "math/bbox.h"

typedef enum AccelType {
    ACCEL_BVH = 0, /* the default */
    ACCEL_KDTREE,
    ACCEL_GRID,
    ACCEL_LIST,    /* brute force: the correctness oracle */
    ACCEL_EMBREE,  /* Intel Embree 3, when built with it: the speed anchor */
    ACCEL_OCTREE
} AccelType;
enum { ACCEL_TYPE_COUNT = 6 };

typedef struct Accel {
    AccelType type;
    union {
        Bvh bvh;
        KdTree kdtree;
        Grid grid;
        ListAccel list;
        EmbreeAccel *embree;
        Octree octree;
    };
    BBox bounds;          /* of all primitives */
    double build_seconds; /* wall time of accel_build */
} Accel;

/* "bvh", "kdtree", ... */
const char *accel_type_name(AccelType type);
/* Returns false for an unknown name. */
bool accel_type_from_name(const char *name, AccelType *out);
/* Whether this build can construct the type (embree needs the library at build time). */
bool accel_type_available(AccelType type);

/* Every back end finds the same hits, bit for bit: Embree's BVH is given our triangles
 * as user geometry whose callbacks run our watertight test. */
CstStatus accel_build(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err);
/* The same, except that Embree intersects triangles with its own arithmetic (its BVH8
 * triangle kernels, its speed; t, u, v differ from ours in the last bits): the ray
 * benchmark's speed anchor. */
CstStatus accel_build_native(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err);
/* accel_build_native, with Embree in its robust mode (EMBREE_NATIVE_ROBUST): the anchor
 * with our BVH's guarantees. The other back ends build as always. */
CstStatus accel_build_native_robust(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err);
/* Accepts a zeroed or already freed Accel. */
void accel_free(Accel *a);
size_t accel_memory_bytes(const Accel *a);

static inline bool accel_intersect(const Accel *a, const Ray *r, Hit *hit)
{
    switch (a->type) {
    case ACCEL_BVH: return bvh_intersect(&a->bvh, r, hit);
    case ACCEL_KDTREE: return kdtree_intersect(&a->kdtree, r, hit);
    case ACCEL_GRID: return grid_intersect(&a->grid, r, hit);
    case ACCEL_LIST: return list_intersect(&a->list, r, hit);
    case ACCEL_EMBREE: return embree_intersect(a->embree, r, hit);
    case ACCEL_OCTREE: return octree_intersect(&a->octree, r, hit);
    }
    return false;
}

static inline bool accel_occluded(const Accel *a, const Ray *r)
{
    switch (a->type) {
    case ACCEL_BVH: return bvh_occluded(&a->bvh, r);
    case ACCEL_KDTREE: return kdtree_occluded(&a->kdtree, r);
    case ACCEL_GRID: return grid_occluded(&a->grid, r);
    case ACCEL_LIST: return list_occluded(&a->list, r);
    case ACCEL_EMBREE: return embree_occluded(a->embree, r);
    case ACCEL_OCTREE: return octree_occluded(&a->octree, r);
    }
    return false;
}

#endif
