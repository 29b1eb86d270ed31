/* Intel Embree 3 as a comparison back end (built when CMake finds Embree: CST_HAVE_EMBREE).
 * Without it, embree_build fails with CST_ERR_UNSUPPORTED. */
#ifndef CST_ACCEL_EMBREE_H
#define CST_ACCEL_EMBREE_H

#include <stdbool.h>
#include <stddef.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"

typedef struct EmbreeAccel EmbreeAccel;

bool embree_available(void);
/* *out is a new handle; embree_free releases it (accepts NULL). native_triangles: Embree's
 * own triangle geometry; else a user geometry running triangle_intersect_watertight, so
 * hits equal the other back ends' (see accel_build). */
CstStatus embree_build(EmbreeAccel **out, const AccelGeometry *geom, bool native_triangles, CstError *err);
void embree_free(EmbreeAccel *a);
bool embree_intersect(const EmbreeAccel *a, const Ray *r, Hit *hit);
bool embree_occluded(const EmbreeAccel *a, const Ray *r);
size_t embree_memory_bytes(const EmbreeAccel *a);

#endif
