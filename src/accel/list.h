/* The brute-force "acceleration structure": every ray tests every primitive. The oracle
 * the other back ends are tested against, and the baseline of the ray benchmark. */
#ifndef CST_ACCEL_LIST_H
#define CST_ACCEL_LIST_H

#include <stdbool.h>
#include <stddef.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"

typedef struct ListAccel {
    AccelGeometry geom; /* borrowed */
} ListAccel;

CstStatus list_build(ListAccel *l, const AccelGeometry *geom, CstError *err);
void list_free(ListAccel *l);
bool list_intersect(const ListAccel *l, const Ray *r, Hit *hit);
bool list_occluded(const ListAccel *l, const Ray *r);
size_t list_memory_bytes(const ListAccel *l);

#endif
