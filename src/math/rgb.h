/* Linear RGB radiance/reflectance triples (linear sRGB primaries). Never gamma-encoded:
 * encoding happens only when an image is written. */
#ifndef CST_MATH_RGB_H
#define CST_MATH_RGB_H

#include <math.h>

typedef struct Rgb { float r, g, b; } Rgb;

static inline Rgb rgb(float r, float g, float b) { Rgb c = {r, g, b}; return c; }
static inline Rgb rgb_s(float s) { return rgb(s, s, s); }
static inline Rgb rgb_add(Rgb a, Rgb b) { return rgb(a.r + b.r, a.g + b.g, a.b + b.b); }
static inline Rgb rgb_mul(Rgb a, Rgb b) { return rgb(a.r * b.r, a.g * b.g, a.b * b.b); }
static inline Rgb rgb_scale(Rgb a, float s) { return rgb(a.r * s, a.g * s, a.b * s); }
/* a + b * c */
static inline Rgb rgb_madd(Rgb a, Rgb b, Rgb c) { return rgb(a.r + b.r * c.r, a.g + b.g * c.g, a.b + b.b * c.b); }
static inline float rgb_max(Rgb a) { float m = a.r > a.g ? a.r : a.g; return m > a.b ? m : a.b; }
static inline int rgb_is_black(Rgb a) { return a.r == 0.0f && a.g == 0.0f && a.b == 0.0f; }
static inline int rgb_is_finite(Rgb a) { return isfinite(a.r) && isfinite(a.g) && isfinite(a.b); }
static inline float rgb_luminance(Rgb a) { return 0.2126f * a.r + 0.7152f * a.g + 0.0722f * a.b; }

#endif
