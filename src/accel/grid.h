/* PLACEHOLDER: the grid back end is being written. */
#ifndef CST_ACCEL_GRID_H
#define CST_ACCEL_GRID_H

#include <stdbool.h>
#include <stddef.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"

typedef struct Grid {
    int unused;
} Grid;

CstStatus grid_build(Grid *a, const AccelGeometry *geom, CstError *err);
void grid_free(Grid *a);
bool grid_intersect(const Grid *a, const Ray *r, Hit *hit);
bool grid_occluded(const Grid *a, const Ray *r);
size_t grid_memory_bytes(const Grid *a);

#endif
