/* Perlin's improved noise (Perlin 2002) and its octave sums (pbrt-v4 FBm, Turbulence).
 * Our own implementation of the published algorithm: quintic fade 6t^5 - 15t^4 + 10t^3,
 * twelve edge gradients picked by a hash of the lattice point through Perlin's permutation. */
#include "textures/noise.h"

#include <math.h>

/* Ken Perlin's permutation of 0..255 from his reference implementation of improved noise
 * (https://mrl.nyu.edu/~perlin/noise/, 2002), the table pbrt-v4 uses as well. Numeric data. */
static const unsigned char perm[256] = {
    151, 160, 137, 91,  90,  15,  131, 13,  201, 95,  96,  53,  194, 233, 7,   225, 140, 36,  103, 30,  69,  142,
    8,   99,  37,  240, 21,  10,  23,  190, 6,   148, 247, 120, 234, 75,  0,   26,  197, 62,  94,  252, 219, 203,
    117, 35,  11,  32,  57,  177, 33,  88,  237, 149, 56,  87,  174, 20,  125, 136, 171, 168, 68,  175, 74,  165,
    71,  134, 139, 48,  27,  166, 77,  146, 158, 231, 83,  111, 229, 122, 60,  211, 133, 230, 220, 105, 92,  41,
    55,  46,  245, 40,  244, 102, 143, 54,  65,  25,  63,  161, 1,   216, 80,  73,  209, 76,  132, 187, 208, 89,
    18,  169, 200, 196, 135, 130, 116, 188, 159, 86,  164, 100, 109, 198, 173, 186, 3,   64,  52,  217, 226, 250,
    124, 123, 5,   202, 38,  147, 118, 126, 255, 82,  85,  212, 207, 206, 59,  227, 47,  16,  58,  17,  182, 189,
    28,  42,  223, 183, 170, 213, 119, 248, 152, 2,   44,  154, 163, 70,  221, 153, 101, 155, 167, 43,  172, 9,
    129, 22,  39,  253, 19,  98,  108, 110, 79,  113, 224, 232, 178, 185, 112, 104, 218, 246, 97,  228, 251, 34,
    242, 193, 238, 210, 144, 12,  191, 179, 162, 241, 81,  51,  145, 235, 249, 14,  239, 107, 49,  192, 214, 31,
    181, 199, 106, 157, 184, 84,  204, 176, 115, 121, 50,  45,  127, 4,   150, 254, 138, 236, 205, 93,  222, 114,
    67,  29,  24,  72,  243, 141, 128, 195, 78,  66,  215, 61,  156, 180};

/* The hash of lattice point (x, y, z), each in [0, 256]. */
static inline int hash3(int x, int y, int z) { return perm[(perm[(perm[x & 255] + y) & 255] + z) & 255]; }

/* The dot product of the offset (dx, dy, dz) with one of Perlin's 12 edge gradients
 * (+-1, +-1, 0) and permutations (16 hash values, four repeated), chosen by h. */
static inline float grad(int h, float dx, float dy, float dz)
{
    h &= 15;
    float u = h < 8 || h == 12 || h == 13 ? dx : dy;
    float v = h < 4 || h == 12 || h == 13 ? dy : dz;
    return ((h & 1) ? -u : u) + ((h & 2) ? -v : v);
}

/* Perlin 2002's interpolant: C2 continuous, so the noise's second derivative is too. */
static inline float fade(float t) { return t * t * t * (t * (t * 6.0f - 15.0f) + 10.0f); }

static inline float lerp(float t, float a, float b) { return a + t * (b - a); }

float noise3(Vec3 p)
{
    if (!isfinite(p.x) || !isfinite(p.y) || !isfinite(p.z)) return 0.0f;
    /* The period first, so large coordinates keep their fractional precision and the
     * int conversions below cannot overflow. */
    float x = fmodf(p.x, 256.0f), y = fmodf(p.y, 256.0f), z = fmodf(p.z, 256.0f);
    float fx = floorf(x), fy = floorf(y), fz = floorf(z);
    float dx = x - fx, dy = y - fy, dz = z - fz;
    int ix = (int)fx & 255, iy = (int)fy & 255, iz = (int)fz & 255;
    float w000 = grad(hash3(ix, iy, iz), dx, dy, dz);
    float w100 = grad(hash3(ix + 1, iy, iz), dx - 1.0f, dy, dz);
    float w010 = grad(hash3(ix, iy + 1, iz), dx, dy - 1.0f, dz);
    float w110 = grad(hash3(ix + 1, iy + 1, iz), dx - 1.0f, dy - 1.0f, dz);
    float w001 = grad(hash3(ix, iy, iz + 1), dx, dy, dz - 1.0f);
    float w101 = grad(hash3(ix + 1, iy, iz + 1), dx - 1.0f, dy, dz - 1.0f);
    float w011 = grad(hash3(ix, iy + 1, iz + 1), dx, dy - 1.0f, dz - 1.0f);
    float w111 = grad(hash3(ix + 1, iy + 1, iz + 1), dx - 1.0f, dy - 1.0f, dz - 1.0f);
    float wx = fade(dx), wy = fade(dy), wz = fade(dz);
    float y0 = lerp(wy, lerp(wx, w000, w100), lerp(wx, w010, w110));
    float y1 = lerp(wy, lerp(wx, w001, w101), lerp(wx, w011, w111));
    return lerp(wz, y0, y1);
}

static inline float smoothstep(float x, float a, float b)
{
    float t = clampf((x - a) / (b - a), 0.0f, 1.0f);
    return t * t * (3.0f - 2.0f * t);
}

/* How many octaves the footprint resolves: octave i has features of size 1.99^-i, so stop
 * where they shrink below the larger of the per-pixel changes (PBR 4th ed. eq. 10.24). */
static inline float octaves_for(Vec3 dpdx, Vec3 dpdy, int max_octaves)
{
    float len2 = maxf(v3_length2(dpdx), v3_length2(dpdy));
    float n = -1.0f - 0.5f * log2f(len2); /* +inf for a zero footprint */
    return clampf(isnan(n) ? 0.0f : n, 0.0f, (float)max_octaves);
}

float noise_fbm(Vec3 p, Vec3 dpdx, Vec3 dpdy, float omega, int max_octaves)
{
    float n = octaves_for(dpdx, dpdy, max_octaves);
    int ni = (int)floorf(n);
    float sum = 0.0f, lambda = 1.0f, o = 1.0f;
    for (int i = 0; i < ni; i++) {
        sum += o * noise3(v3_scale(p, lambda));
        lambda *= 1.99f;
        o *= omega;
    }
    return sum + o * smoothstep(n - (float)ni, 0.3f, 0.7f) * noise3(v3_scale(p, lambda));
}

float noise_turbulence(Vec3 p, Vec3 dpdx, Vec3 dpdy, float omega, int max_octaves)
{
    float n = octaves_for(dpdx, dpdy, max_octaves);
    int ni = (int)floorf(n);
    float sum = 0.0f, lambda = 1.0f, o = 1.0f;
    for (int i = 0; i < ni; i++) {
        sum += o * fabsf(noise3(v3_scale(p, lambda)));
        lambda *= 1.99f;
        o *= omega;
    }
    /* The partly resolved octave blends toward |noise|'s mean, 0.2; unresolved ones add it. */
    sum += o * lerp(smoothstep(n - (float)ni, 0.3f, 0.7f), 0.2f, fabsf(noise3(v3_scale(p, lambda))));
    for (int i = ni; i < max_octaves; i++) {
        sum += o * 0.2f;
        o *= omega;
    }
    return sum;
}
