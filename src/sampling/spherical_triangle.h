/* Sampling a triangle by the solid angle it subtends: the spherical triangle of the unit
 * directions toward its vertices (Arvo, "Stratified Sampling of Spherical Triangles",
 * SIGGRAPH 1995), its inverse, and the bilinear warp of [0,1)^2 pbrt-v4 puts in front of it
 * to approximate the cosine at the receiving point (pbrt-v4 Triangle::Sample(ctx, u)). */
#ifndef CST_SAMPLING_SPHERICAL_TRIANGLE_H
#define CST_SAMPLING_SPHERICAL_TRIANGLE_H

#include <stdbool.h>

#include "math/vec3.h"

/* The solid angle (sr) of the spherical triangle of unit vectors a, b, c: Van Oosterom and
 * Strackee's formula, tan(Omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a), stable for
 * small and large triangles. */
float spherical_triangle_area(Vec3 a, Vec3 b, Vec3 c);

/* A unit direction uniform over the spherical triangle a, b, c (unit vectors) by u:
 * u.x picks the sub-triangle a, b, c' of area u.x Omega (c' on the arc a -> c), u.y the
 * point on the arc b -> c' so that the density is uniform (Arvo 1995, sec. 2-3).
 * u = (x, 0) gives b; (0, 1) gives a; (1, 1) gives c. *solid_angle gets Omega; the
 * density is 1 / Omega. Returns false for a degenerate triangle (Omega not > 0). */
bool spherical_triangle_sample(Vec3 a, Vec3 b, Vec3 c, Vec2 u, Vec3 *w, float *solid_angle);

/* The u that spherical_triangle_sample maps to direction w (unit, inside the triangle):
 * needed for the density of the bilinear warp at a direction BSDF sampling found. */
Vec2 spherical_triangle_invert(Vec3 a, Vec3 b, Vec3 c, Vec3 w);

/* Bilinear density on [0,1)^2 with corner weights v[0] at (0,0), v[1] at (1,0), v[2] at
 * (0,1), v[3] at (1,1) (pbrt-v4 SampleBilinear / BilinearPDF): y from its marginal, a
 * linear density, then x from the conditional, also linear. */
Vec2 warp_bilinear(Vec2 u, const float v[4]);
float warp_bilinear_pdf(Vec2 p, const float v[4]);

#endif
