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

/* How Embree meets our triangles. */
typedef enum EmbreeMode {
    /* A user geometry running triangle_intersect_watertight, under Embree's robust
     * traversal: hits equal the other back ends' (see accel_build). */
    EMBREE_EXACT,
    /* Embree's own triangle geometry and default scene flags: its speed, its arithmetic
     * (a Möller-Trumbore test and a box test of lower * rdir - org * rdir, neither
     * watertight). */
    EMBREE_NATIVE,
    /* Embree's own triangles under RTC_SCENE_FLAG_ROBUST, which in Embree's words "avoids
     * optimizations that reduce arithmetic accuracy" and is meant to stop rays shooting
     * through the shared edges of neighbouring triangles: a conservative box test and an
     * edge-consistent triangle test, the guarantees our BVH gives. */
    EMBREE_NATIVE_ROBUST
} EmbreeMode;

bool embree_available(void);
/* *out is a new handle; embree_free releases it (accepts NULL). */
CstStatus embree_build(EmbreeAccel **out, const AccelGeometry *geom, EmbreeMode mode, CstError *err);
void embree_free(EmbreeAccel *a);
bool embree_intersect(const EmbreeAccel *a, const Ray *r, Hit *hit);
bool embree_occluded(const EmbreeAccel *a, const Ray *r);
size_t embree_memory_bytes(const EmbreeAccel *a);

#endif
