/* The primitives every acceleration back end is built over, borrowed from the scene. */
#ifndef CST_ACCEL_ACCEL_GEOMETRY_H
#define CST_ACCEL_ACCEL_GEOMETRY_H

#include <stdint.h>

#include "geometry/shape.h"
#include "geometry/sphere.h"
#include "math/vec3.h"

/* Triangle i is positions[tri_indices[3i..3i+2]] with primitive id i; sphere j has id
 * num_tris + j; analytic shape k has id num_tris + num_spheres + k (accel_shape_base()).
 * The arrays must outlive the structure built over them. */
typedef struct AccelGeometry {
    const Vec3 *positions;
    const int32_t *tri_indices;
    int num_tris;
    const Sphere *spheres;
    int num_spheres;
    const AnalyticShape *shapes;
    int num_shapes;
} AccelGeometry;

static inline uint32_t accel_shape_base(const AccelGeometry *g) { return (uint32_t)g->num_tris + (uint32_t)g->num_spheres; }

#endif
