/* 4x4 affine transforms: composition, inversion, and application to points, vectors and
 * normals. Conventions: column vectors, p' = M p, so m[r][3] is the translation and
 * compose(a, b) applies b first; the bottom row is (0, 0, 0, 1); right-handed rotations
 * (counter-clockwise looking down the axis toward the origin), angles in radians.
 * Products and inverses are computed in double and rounded once to float. */
#ifndef CST_MATH_TRANSFORM_H
#define CST_MATH_TRANSFORM_H

#include <stdbool.h>

#include "math/vec3.h"

typedef struct Transform {
    float m[4][4]; /* row-major: m[row][col] */
} Transform;

Transform transform_identity(void);
Transform transform_translate(Vec3 t);
Transform transform_scale(Vec3 s);
/* Rotation by angle_rad about axis (any nonzero length; normalised here). */
Transform transform_rotate(Vec3 axis, float angle_rad);
/* The same from degrees, exact for multiples of 90 (scene files give angles in degrees). */
Transform transform_rotate_degrees(Vec3 axis, double degrees);
/* From 16 numbers, row by row; the bottom row is taken as given (check transform_is_affine). */
Transform transform_from_rows(const float rows[16]);
/* a * b: the transform that applies b, then a. */
Transform transform_compose(Transform a, Transform b);
bool transform_is_identity(const Transform *t);
/* Bottom row exactly (0, 0, 0, 1) and every element finite. */
bool transform_is_affine(const Transform *t);
/* Determinant of the linear (upper-left 3x3) part: < 0 means the transform mirrors, which
 * reverses the winding of triangles; 0 flattens. */
double transform_det(const Transform *t);
/* Inverse of an affine transform; false (out untouched) when the linear part is singular
 * or the inverse is not finite in float. */
bool transform_invert(const Transform *t, Transform *out);
/* The normal matrix: inverse transpose of the linear part, no translation. Normals
 * transformed by it stay perpendicular to transformed surfaces (apply with
 * transform_normal). False when the linear part is singular. */
bool transform_normal_matrix(const Transform *t, Transform *out);

/* Row r of the linear part times v, plus w times the translation, in double. */
static inline float transform_row_(const Transform *t, int r, Vec3 v, double w)
{
    const float *m = t->m[r];
    return (float)((double)m[0] * (double)v.x + (double)m[1] * (double)v.y +
                   (double)m[2] * (double)v.z + (double)m[3] * w);
}

/* M (p, 1): a point. */
static inline Vec3 transform_point(const Transform *t, Vec3 p)
{
    return v3(transform_row_(t, 0, p, 1.0), transform_row_(t, 1, p, 1.0), transform_row_(t, 2, p, 1.0));
}

/* M (v, 0): a direction or offset (no translation). */
static inline Vec3 transform_vector(const Transform *t, Vec3 v)
{
    return v3(transform_row_(t, 0, v, 0.0), transform_row_(t, 1, v, 0.0), transform_row_(t, 2, v, 0.0));
}

/* A normal through a normal matrix (transform_normal_matrix), renormalised to unit
 * length; a zero normal (meaning "none") stays zero. */
static inline Vec3 transform_normal(const Transform *normal_matrix, Vec3 n)
{
    Vec3 r = transform_vector(normal_matrix, n);
    float len = v3_length(r);
    return len > 0.0f && isfinite(len) ? v3_scale(r, 1.0f / len) : v3s(0.0f);
}

#endif
