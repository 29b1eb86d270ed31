/* Transforms that move over the shutter interval: one at shutter open and one at close,
 * interpolated by decomposition (pbrt-v4's AnimatedTransform). */
#ifndef CST_MATH_MOTION_H
#define CST_MATH_MOTION_H

#include <stdbool.h>
#include <stdint.h>

#include "math/bbox.h"
#include "math/transform.h"

/* M = T R S at each end (Shoemake & Duff, "Matrix Animation and Polar Decomposition",
 * Graphics Interface 1992): translation T, rotation R as a unit quaternion, and the
 * symmetric stretch S of the polar decomposition. At time t in [0, 1] the translation and
 * the stretch (element by element) are interpolated linearly and the rotation by slerp on
 * the shorter arc, so a rotating object turns at constant angular velocity instead of
 * shrinking through the matrices' linear blend. Kept in double. */
typedef struct MotionTransform {
    Transform start, end;  /* as given */
    double tr[2][3];       /* translations */
    double q[2][4];        /* unit quaternions (x, y, z, w); q[1] on q[0]'s side */
    double stretch[2][9];  /* S, row-major */
    bool moving;           /* false when start == end: motion_at returns start exactly */
} MotionTransform;

/* Decomposes both ends; false when either is singular or not affine. A mirroring
 * transform (det < 0) is decomposed with the reflection in its stretch. */
bool motion_init(MotionTransform *mt, const Transform *start, const Transform *end);
/* The transform at time t in [0, 1] (0: start, 1: end). */
Transform motion_at(const MotionTransform *mt, float t);
/* A box holding the box b moved by the transform at every time in [0, 1]: b's corners
 * placed at MOTION_BOUND_STEPS + 1 evenly spaced times, widened by the longest distance a
 * corner moves between two consecutive times (a corner's path between them stays within
 * that distance of both ends, to first order in the step: the path is a rotation at
 * constant rate about a fixed axis plus linear translation and stretch). Every point of
 * b is an affine combination of the corners with non-negative weights, so its path stays
 * within the corners' boxes. */
#define MOTION_BOUND_STEPS 64
BBox motion_bounds(const MotionTransform *mt, BBox b);

/* The shutter instant of pass `pass` of an estimator whose paths all share their pass's
 * instant (VCM's and SPPM's iterations: a merge joins paths of one instant only), with
 * `offset` a uniform number fixed per render: {offset + pass / golden ratio}, a Kronecker
 * sequence. Each pass's instant is uniform in [0, 1) (the random offset), so each pass is
 * an unbiased estimate at its instant, and any run of passes is spread evenly over the
 * shutter (discrepancy O(log n / n)); its differences are irrational, so it does not line
 * up with the wavelengths' radical-inverse sequence (wavelengths_pass_u) of the same
 * passes, whose pairs then fill the square. */
static inline float motion_pass_time(uint32_t pass, float offset)
{
    double u = (double)offset + 0.6180339887498949 * (double)pass;
    float t = (float)(u - (double)(uint64_t)u);
    return t < 1.0f ? t : 0x1.fffffep-1f;
}

#endif
