/* The pbrt-v4 scene loader (scene_pbrt.c): the public entry points are in caustic.h; these
 * are its colour conversions, exposed for the unit tests. */
#ifndef CST_SCENE_SCENE_PBRT_H
#define CST_SCENE_SCENE_PBRT_H

#include <stdbool.h>

#include "math/color.h"

/* Linear sRGB of a blackbody at kelvin, scaled to luminance Y = 1 (pbrt-v4 normalises
 * blackbody emitters to 1 nit before "scale"). */
Color pbrt_blackbody_rgb(double kelvin);
/* A sampled spectrum (lambda_nm, value pairs, piecewise linear, zero outside) as linear
 * sRGB. illuminant: scaled to luminance 1 as pbrt-v4 does for emitters; otherwise a
 * reflectance, normalised so that a constant spectrum c gives (c, c, c). */
Color pbrt_spectrum_rgb(const double *pairs, int num_pairs, bool illuminant);
/* RGB approximations of pbrt's named spectra "metal-<X>-eta" / "-k": false if unknown. */
bool pbrt_named_metal(const char *name, Color *out);
/* Normal-incidence Fresnel reflectance of a conductor, ((n-1)^2 + k^2) / ((n+1)^2 + k^2)
 * per channel. */
Color pbrt_conductor_r0(Color eta, Color k);
/* pbrt-v4's equal-area octahedral map between unit directions and [0, 1]^2 (Clarberg 2008),
 * the layout of infinite lights' images. */
void pbrt_equal_area_sphere_to_square(const double d[3], double uv[2]);
void pbrt_equal_area_square_to_sphere(const double uv[2], double d[3]);

#endif
