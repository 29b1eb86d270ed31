/* Solid-angle sampling of polygons seen from a point: the spherical triangle (Arvo 1995)
 * and the spherical rectangle (Urena, Fajardo & King 2013), each with its solid angle, the
 * reciprocal of its density per unit solid angle. Computed in double: the angles involved
 * cancel badly in float for the small triangles near pbrt-v4's lower bound. */
#ifndef CST_SAMPLING_SPHERICAL_H
#define CST_SAMPLING_SPHERICAL_H

#include <stdbool.h>

#include "math/vec3.h"

/* pbrt-v4 Triangle::Sample(ctx, u): below this solid angle (sr) area sampling is used
 * (Arvo's warp loses its accuracy), above the other bound too (the triangle covers nearly
 * a hemisphere and the warp's derivatives blow up). */
#define SPH_MIN_SOLID_ANGLE 3e-4f
#define SPH_MAX_SOLID_ANGLE 6.22f

/* The solid angle (sr) triangle p0 p1 p2 subtends from x, by Van Oosterom & Strackee's
 * formula ("The solid angle of a plane triangle", IEEE TBME 1983):
 * tan(Omega / 2) = |a . (b x c)| / (1 + a.b + b.c + c.a) for the unit directions a, b, c. */
float sph_triangle_solid_angle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2);

/* A direction from x uniform over the solid angle of triangle p0 p1 p2 (Arvo, "Stratified
 * sampling of spherical triangles", SIGGRAPH 1995, sec. 3: u.x picks the sub-triangle's
 * area, u.y the point on the arc from the vertex at p1). The density per unit solid angle
 * is 1 / sph_triangle_solid_angle(x, p0, p1, p2). False for a degenerate triangle. */
bool sph_triangle_sample(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2, Vec2 u, Vec3 *w);

/* A spherical triangle set up once for both its solid angle and its samples: NEE needs the
 * solid angle (to decide between solid-angle and area sampling, and for the density) and
 * then a sample, from the same unit directions. Keeping them saves the second set of
 * normalisations; results are bit-identical to the two functions above. */
typedef struct SphTri {
    double a[3], b[3], c[3]; /* unit directions from x to p0, p1, p2 */
    float solid_angle;       /* sr, as sph_triangle_solid_angle; 0 when degenerate */
} SphTri;

/* False (and solid_angle 0) when a vertex coincides with x. */
bool sph_tri_init(SphTri *t, Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2);
/* sph_triangle_sample from a set-up triangle. */
bool sph_tri_sample(const SphTri *t, Vec2 u, Vec3 *w);

/* A rectangle: corner s, and the two edges ex, ey from it (perpendicular). */
typedef struct SphRect {
    /* in the rectangle's frame (x along ex, y along ey, z toward the side away from x),
     * the point x is at the origin and the rectangle at z = z0 over [x0, x1] x [y0, y1] */
    Vec3 ax, ay, az; /* the frame's unit axes */
    Vec3 o;          /* the reference point x */
    double x0, x1, y0, y1, z0;
    double b0, b1, k;  /* Urena et al. sec. 4: b0, b1 and k = 2 pi - g2 - g3 */
    double solid_angle; /* S, sr */
} SphRect;

/* The spherical rectangle of rectangle (s, ex, ey) from x (Urena et al. 2013, Algorithm 1's
 * set-up). False when x lies in the rectangle's plane (no solid angle). */
bool sph_rect_init(SphRect *r, Vec3 x, Vec3 s, Vec3 ex, Vec3 ey);
/* A direction from x uniform over the rectangle's solid angle (Urena et al. Algorithm 1's
 * sampling), density 1 / r->solid_angle per unit solid angle; *p gets the point on the
 * rectangle. */
Vec3 sph_rect_sample(const SphRect *r, Vec2 u, Vec3 *p);

#endif
