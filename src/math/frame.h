/* Orthonormal frames: local shading space has the normal along +z, so
 * cos(theta) of a local direction is simply its z component. */
#ifndef CST_MATH_FRAME_H
#define CST_MATH_FRAME_H

#include "math/vec3.h"

typedef struct Frame { Vec3 s, t, n; } Frame;

/* Branchless basis from a unit normal: Duff et al., "Building an Orthonormal Basis,
 * Revisited", JCGT 6(1) 2017, listing 3. */
static inline Frame frame_from_normal(Vec3 n)
{
    float sign = copysignf(1.0f, n.z);
    float a = -1.0f / (sign + n.z);
    float b = n.x * n.y * a;
    Frame f;
    f.s = v3(1.0f + sign * n.x * n.x * a, sign * b, -sign * n.x);
    f.t = v3(b, sign + n.y * n.y * a, -n.y);
    f.n = n;
    return f;
}

static inline Vec3 frame_to_local(const Frame *f, Vec3 v)
{
    return v3(v3_dot(v, f->s), v3_dot(v, f->t), v3_dot(v, f->n));
}

static inline Vec3 frame_to_world(const Frame *f, Vec3 v)
{
    return v3(f->s.x * v.x + f->t.x * v.y + f->n.x * v.z,
              f->s.y * v.x + f->t.y * v.y + f->n.y * v.z,
              f->s.z * v.x + f->t.z * v.y + f->n.z * v.z);
}

#endif
