/* Fresnel reflectance: dielectric interfaces, conductors with a complex index of refraction
 * (per RGB channel), and the hemispherical (diffuse) average of the dielectric case. */
#ifndef CST_MATERIALS_FRESNEL_H
#define CST_MATERIALS_FRESNEL_H

#include "math/color.h"

/* Unpolarised Fresnel reflectance of a smooth dielectric interface; cos_i is the cosine
 * on the incident side (sign picks the side), eta = inside over outside IOR. */
float fresnel_dielectric(float cos_i, float eta);

/* Unpolarised reflectance of a conductor of complex relative IOR eta + i k, seen from a
 * dielectric of IOR 1, at |cos_i| (the sign is ignored: a conductor has no inside). */
float fresnel_conductor(float cos_i, float eta, float k);
Color fresnel_conductor_rgb(float cos_i, Color eta, Color k);

/* Cosine-weighted hemispherical average 2 int_0^1 F(mu) mu dmu of fresnel_dielectric seen
 * from outside, in closed form; eta >= 1. */
float fresnel_diffuse_reflectance(float eta);

#endif
