/* Perlin's improved noise (Perlin 2002, "Improving Noise", SIGGRAPH) and the sums of its
 * octaves that pbrt-v4's procedural textures use: fractional Brownian motion and
 * turbulence, with the octave count limited by the lookup's footprint so that octaves
 * finer than a pixel fade out instead of aliasing (PBR 4th ed. sec. 10.6). */
#ifndef CST_TEXTURES_NOISE_H
#define CST_TEXTURES_NOISE_H

#include "math/vec3.h"

/* Gradient noise at p: 0 on the integer lattice, within about [-1, 1], period 256. */
float noise3(Vec3 p);
/* sum_i omega^i noise(1.99^i p) over the octaves the footprint (dpdx, dpdy: the change of p
 * per pixel) resolves, at most max_octaves; the last one faded in by a smoothstep. */
float noise_fbm(Vec3 p, Vec3 dpdx, Vec3 dpdy, float omega, int max_octaves);
/* The same sum of |noise|; octaves past the footprint count their mean, 0.2. */
float noise_turbulence(Vec3 p, Vec3 dpdx, Vec3 dpdy, float omega, int max_octaves);

#endif
