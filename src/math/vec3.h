/* Small by-value vector math: Vec2, Vec3 and float helpers.
 * Conventions: right-handed cross product, angles in radians, directions are not
 * assumed normalised unless a name says so (wi, wo, n are normalised). */
#ifndef CST_MATH_VEC3_H
#define CST_MATH_VEC3_H

#include <math.h>

#define CST_PI      3.14159265358979323846f
#define CST_INV_PI  0.31830988618379067154f
#define CST_INV_2PI 0.15915494309189533577f
#define CST_INV_4PI 0.07957747154594766788f

typedef struct Vec2 { float x, y; } Vec2;
typedef struct Vec3 { float x, y, z; } Vec3;

static inline float minf(float a, float b) { return a < b ? a : b; }
static inline float maxf(float a, float b) { return a > b ? a : b; }
static inline float clampf(float v, float lo, float hi) { return v < lo ? lo : (v > hi ? hi : v); }
static inline float sqrf(float v) { return v * v; }
/* sqrt that tolerates tiny negative arguments from rounding. */
static inline float safe_sqrtf(float v) { return sqrtf(maxf(v, 0.0f)); }

static inline Vec2 v2(float x, float y) { Vec2 r = {x, y}; return r; }
static inline Vec3 v3(float x, float y, float z) { Vec3 r = {x, y, z}; return r; }
static inline Vec3 v3s(float s) { return v3(s, s, s); }
static inline Vec3 v3_add(Vec3 a, Vec3 b) { return v3(a.x + b.x, a.y + b.y, a.z + b.z); }
static inline Vec3 v3_sub(Vec3 a, Vec3 b) { return v3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline Vec3 v3_mul(Vec3 a, Vec3 b) { return v3(a.x * b.x, a.y * b.y, a.z * b.z); }
static inline Vec3 v3_scale(Vec3 a, float s) { return v3(a.x * s, a.y * s, a.z * s); }
static inline Vec3 v3_neg(Vec3 a) { return v3(-a.x, -a.y, -a.z); }
/* a + b * s */
static inline Vec3 v3_madd(Vec3 a, Vec3 b, float s) { return v3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
static inline float v3_dot(Vec3 a, Vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline Vec3 v3_cross(Vec3 a, Vec3 b)
{
    return v3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
static inline float v3_length2(Vec3 a) { return v3_dot(a, a); }
static inline float v3_length(Vec3 a) { return sqrtf(v3_dot(a, a)); }
static inline Vec3 v3_normalize(Vec3 a) { return v3_scale(a, 1.0f / v3_length(a)); }
static inline Vec3 v3_min(Vec3 a, Vec3 b) { return v3(minf(a.x, b.x), minf(a.y, b.y), minf(a.z, b.z)); }
static inline Vec3 v3_max(Vec3 a, Vec3 b) { return v3(maxf(a.x, b.x), maxf(a.y, b.y), maxf(a.z, b.z)); }
static inline float v3_max_comp(Vec3 a) { return maxf(a.x, maxf(a.y, a.z)); }
static inline float v3_max_abs(Vec3 a) { return maxf(fabsf(a.x), maxf(fabsf(a.y), fabsf(a.z))); }
static inline float v3_get(Vec3 a, int axis) { return axis == 0 ? a.x : (axis == 1 ? a.y : a.z); }
static inline int v3_is_finite(Vec3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
/* Flip v so that it lies in the hemisphere of ref. */
static inline Vec3 v3_face_forward(Vec3 v, Vec3 ref) { return v3_dot(v, ref) < 0.0f ? v3_neg(v) : v; }

#endif
