/* Color: the one type of radiance, throughput, reflectance and flux. Every integrator and
 * BSDF does its colour arithmetic through these functions, so that the spectral mode
 * (four sampled wavelengths) changes this module and the conversions at the inputs
 * (color_rgb) and outputs (color_channel), not the estimators.
 * RGB mode: lanes 0-2 hold linear RGB with sRGB primaries, never gamma-encoded (encoding
 * happens only when an image is written); lane 3 is a copy of lane 1 (green) from every
 * constructor, and stays one bit for bit through the lane-wise arithmetic below (the
 * same operation on the same operands, no contraction), so the reductions (max, black,
 * finite) can read all four lanes and still give the three channels' answer.
 * Spectral mode (math/spectrum.h): lane i is the value at the path's wavelength i; every
 * lane carries colour, and the reductions must see all four, which they do. Estimators
 * never tell the modes apart: only the conversions at the inputs (materials, lights) and
 * the film do. Luminance is RGB-only (light selection, statistics). */
#ifndef CST_MATH_COLOR_H
#define CST_MATH_COLOR_H

#include <math.h>
#include <stdbool.h>

enum {
    COLOR_LANES = 4,   /* the storage and arithmetic width */
    COLOR_CHANNELS = 3 /* the lanes that carry colour: R, G, B */
};

typedef struct Color { float c[COLOR_LANES]; } Color;

/* From linear RGB (sRGB primaries): the input conversion. Lane 3 mirrors green (above). */
static inline Color color_rgb(float r, float g, float b)
{
    Color o = {{r, g, b, g}};
    return o;
}
/* The same value in every lane (a grey, or a scalar weight). */
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
/* Lane-wise f applied to each lane (exp, sqrt: attenuation, roughness maps). */
static inline Color color_map(Color a, float (*f)(float))
{
    Color o;
    for (int i = 0; i < COLOR_LANES; i++) o.c[i] = f(a.c[i]);
    return o;
}

static inline float color_max(Color a)
{
    float m = a.c[0];
    for (int i = 1; i < COLOR_LANES; i++) m = m > a.c[i] ? m : a.c[i];
    return m;
}
static inline bool color_is_black(Color a)
{
    for (int i = 0; i < COLOR_LANES; i++)
        if (a.c[i] != 0.0f) return false;
    return true;
}
/* a scaled by min(1, limit / m), m the largest component of a's CIE XYZ (a in linear sRGB,
 * IEC 61966-2-1's matrix): pbrt-v4's RGBFilm clamp of a sample's sensor values (its
 * "maxcomponentvalue"; the cie1931 sensor's values are XYZ), which keeps the hue. */
static inline Color color_clamp_xyz_max(Color a, float limit)
{
    float x = 0.4124f * a.c[0] + 0.3576f * a.c[1] + 0.1805f * a.c[2];
    float y = 0.2126f * a.c[0] + 0.7152f * a.c[1] + 0.0722f * a.c[2];
    float z = 0.0193f * a.c[0] + 0.1192f * a.c[1] + 0.9505f * a.c[2];
    float m = x > y ? x : y;
    m = m > z ? m : z;
    if (!(m > limit)) return a;
    return color_scale(a, limit / m);
}

static inline bool color_is_finite(Color a)
{
    for (int i = 0; i < COLOR_LANES; i++)
        if (!isfinite(a.c[i])) return false;
    return true;
}
/* Luminance Y of linear sRGB (ITU-R BT.709 weights). */
static inline float color_luminance(Color a)
{
    return 0.2126f * a.c[0] + 0.7152f * a.c[1] + 0.0722f * a.c[2];
}

#endif
