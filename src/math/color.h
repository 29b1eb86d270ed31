/* Color: the one type of radiance, throughput, reflectance and flux. Every integrator and
 * BSDF does its colour arithmetic through these functions, so that the spectral mode
 * (four sampled wavelengths) changes this module and the conversions at the inputs
 * (color_rgb) and outputs (color_channel), not the estimators.
 * Today the lanes hold linear RGB with sRGB primaries, never gamma-encoded (encoding
 * happens only when an image is written); lane 3 is padding, 0 from every constructor.
 * Lane-wise arithmetic runs over all four lanes (one SSE operation), so lane 3 may turn
 * NaN (0 * inf): the reductions (max, finite, black, luminance) read only the channels. */
#ifndef CST_MATH_COLOR_H
#define CST_MATH_COLOR_H

#include <math.h>
#include <stdbool.h>

enum {
    COLOR_LANES = 4,   /* the storage and arithmetic width */
    COLOR_CHANNELS = 3 /* the lanes that carry colour: R, G, B */
};

typedef struct Color { float c[COLOR_LANES]; } Color;

/* From linear RGB (sRGB primaries): the input conversion. */
static inline Color color_rgb(float r, float g, float b)
{
    Color o = {{r, g, b, 0.0f}};
    return o;
}
/* The same value in every channel (a grey, or a scalar weight). */
static inline Color color_s(float s) { return color_rgb(s, s, s); }
/* Channel i (0..COLOR_CHANNELS-1) as linear RGB: the output conversion. */
static inline float color_channel(Color a, int i) { return a.c[i]; }

static inline Color color_add(Color a, Color b)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = a.c[i] + b.c[i];
    return o;
}
static inline Color color_mul(Color a, Color b)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = a.c[i] * b.c[i];
    return o;
}
static inline Color color_scale(Color a, float s)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = a.c[i] * s;
    return o;
}
/* a + b * c, rounded twice (no fused multiply-add: the build forbids contraction). */
static inline Color color_madd(Color a, Color b, Color c)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = a.c[i] + b.c[i] * c.c[i];
    return o;
}
/* Lane-wise max(a, b). */
static inline Color color_max2(Color a, Color b)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = a.c[i] > b.c[i] ? a.c[i] : b.c[i];
    return o;
}
/* Lane-wise a / b, 0 where b is 0 (ratios of reflectances, pbrt's SafeDiv). */
static inline Color color_div_safe(Color a, Color b)
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = b.c[i] != 0.0f ? a.c[i] / b.c[i] : 0.0f;
    return o;
}
/* Lane-wise f applied to each channel (exp, sqrt: attenuation, roughness maps). */
static inline Color color_map(Color a, float (*f)(float))
{
    Color o = a;
    for (int i = 0; i < COLOR_CHANNELS; i++) o.c[i] = f(a.c[i]);
    return o;
}

static inline float color_max(Color a)
{
    float m = a.c[0];
    for (int i = 1; i < COLOR_CHANNELS; i++) m = m > a.c[i] ? m : a.c[i];
    return m;
}
static inline bool color_is_black(Color a)
{
    for (int i = 0; i < COLOR_CHANNELS; i++)
        if (a.c[i] != 0.0f) return false;
    return true;
}
static inline bool color_is_finite(Color a)
{
    for (int i = 0; i < COLOR_CHANNELS; i++)
        if (!isfinite(a.c[i])) return false;
    return true;
}
/* Luminance Y of linear sRGB (ITU-R BT.709 weights). */
static inline float color_luminance(Color a)
{
    return 0.2126f * a.c[0] + 0.7152f * a.c[1] + 0.0722f * a.c[2];
}

#endif
