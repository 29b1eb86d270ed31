/* The ball of the volume density estimate (sppm's and photon's volume photons): how much of
 * it lies in the query point's medium, for the boundary correction of the kernel. */
#ifndef CST_INTEGRATORS_VOLUME_BALL_H
#define CST_INTEGRATORS_VOLUME_BALL_H

#include <stdint.h>

#include "math/vec3.h"
#include "scene/scene.h"

enum {
    VOLUME_BALL_DIRS = 16 /* quadrature directions, one short ray each */
};

/* The smallest fraction volume_ball_fraction() returns: the correction 1 / f is at most 8,
 * a point at a cube's corner (f = 1/8). Thinner regions (sharper wedges) stay darkened
 * rather than turn a few quadrature rays into fireflies. */
#define VOLUME_BALL_MIN_FRACTION 0.125f

/* The fraction f of the ball of radius r around p (a scattering point in a medium, not on
 * a surface) that is reachable from p without crossing a surface, estimated by
 * VOLUME_BALL_DIRS rays of length r (see volume_ball.c for the quadrature and why it is
 * rotated). 1 when the ball touches no surface. Clamped to [VOLUME_BALL_MIN_FRACTION, 1].
 * Deterministic: a function of (scene, p, r, time) only; draws no random numbers. rays
 * (may be NULL) counts the rays traced. */
float volume_ball_fraction(const Scene *s, Vec3 p, float r, float time, uint64_t *rays);

#endif
