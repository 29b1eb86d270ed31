/* Environment lighting: radiance arriving from infinitely far in every direction, either
 * constant or an equirectangular (latitude-longitude) image, importance-sampled by a 2D
 * piecewise-constant distribution over the image (pbrt-v4 sec. 12.5.2). Directions w point
 * toward the environment; +y is up: theta = acos(w.y) from the top row down, phi =
 * atan2(w.z, w.x) in [0, 2 pi) from the left column. */
#ifndef CST_LIGHTS_ENVMAP_H
#define CST_LIGHTS_ENVMAP_H

#include <stdbool.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"
#include "sampling/distrib1d.h"

/* A portal (pbrt-v4 PortalImageInfiniteLight; Bitterli, Novak & Jarosz, "Portal-masked
 * environment map sampling", CGF 2015): a rectangle, a window through which the environment
 * is seen. Directions are rectified in the portal's frame (x, y along its edges, z through
 * it toward the environment): a local direction (x, y, z), z > 0, has coordinates
 * u = (atan(x / z) + pi / 2) / pi, v = (atan(y / z) + pi / 2) / pi in [0, 1]^2, and
 * d omega = pi^2 (1 - x^2)(1 - y^2) / z du dv. From any point in front of the window the
 * directions through it are exactly a rectangle of (u, v), so sampling a 2-D piecewise-
 * constant density over (u, v), restricted to that rectangle (a summed-area table), puts
 * every sample through the window (pbrt-v4 4th ed. sec. 12.5.3). Only sampling changes:
 * radiance is still envmap_eval's. */
typedef struct EnvPortal {
    Vec3 p0, p2;      /* opposite corners */
    Vec3 ax, ay, az;  /* the frame: ax along p0 -> p3, ay along p0 -> p1, az = ax x ay */
    int n;            /* n x n cells over [0, 1]^2 */
    float *f;         /* n * n cell densities (luminance times d omega / du dv, floored) */
    double *sat;      /* (n + 1)^2 summed-area table: sat[j (n + 1) + i] = the integral of f
                       * over [0, i / n] x [0, j / n] */
} EnvPortal;

typedef struct EnvMap {
    Color scale;      /* multiplies the image; the radiance itself when there is none */
    float *rgb;     /* width * height * 3 linear values, row 0 = theta 0 (up); NULL = constant */
    int width, height;
    Distrib1D marginal; /* rows, weighted by their luminance times sin theta */
    Distrib1D *rows;    /* per row, its columns by luminance */
    float power;        /* the integral of luminance over the sphere (W/m^2 per unit area of a disk...) */
    EnvPortal *portal;  /* NEE through a portal (envmap_set_portal), or NULL; owned */
} EnvMap;

CstStatus envmap_init_constant(EnvMap *m, Color radiance, CstError *err);
/* Takes ownership of rgb (malloc'd) on success and on failure. */
CstStatus envmap_init_image(EnvMap *m, float *rgb, int width, int height, Color scale, CstError *err);
void envmap_free(EnvMap *m);

/* Radiance arriving from direction w (unit, toward the environment). */
Color envmap_eval(const EnvMap *m, Vec3 w);
/* A direction by u, with its density per unit solid angle (0: unusable). */
Vec3 envmap_sample(const EnvMap *m, Vec2 u, float *pdf);
float envmap_pdf(const EnvMap *m, Vec3 w);

/* Gives m a portal with corners p[0..3] in order (a rectangle; pbrt-v4's "point3 portal",
 * the environment seen through it along ax x ay with ax = p3 - p0, ay = p1 - p0). Errors
 * (CST_ERR_INVALID_ARG) for four points that are not a rectangle; CST_ERR_OOM. */
CstStatus envmap_set_portal(EnvMap *m, const Vec3 p[4], CstError *err);
/* A direction from x through m's portal by u, with its density per unit solid angle
 * (envmap_portal_pdf's); false when x sees no window (behind or in the portal's plane). */
bool envmap_portal_sample(const EnvMap *m, Vec3 x, Vec2 u, Vec3 *w, float *pdf);
/* The density of envmap_portal_sample's w from x per unit solid angle; 0 outside the window. */
float envmap_portal_pdf(const EnvMap *m, Vec3 x, Vec3 w);

#endif
