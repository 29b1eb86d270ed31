/* PLACEHOLDER: the kdtree back end is being written. */
#ifndef CST_ACCEL_KDTREE_H
#define CST_ACCEL_KDTREE_H

#include <stdbool.h>
#include <stddef.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"

typedef struct KdTree {
    int unused;
} KdTree;

CstStatus kdtree_build(KdTree *a, const AccelGeometry *geom, CstError *err);
void kdtree_free(KdTree *a);
bool kdtree_intersect(const KdTree *a, const Ray *r, Hit *hit);
bool kdtree_occluded(const KdTree *a, const Ray *r);
size_t kdtree_memory_bytes(const KdTree *a);

#endif
