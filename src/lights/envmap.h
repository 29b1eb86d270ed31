/* Environment lighting: radiance arriving from infinitely far in every direction, either
 * constant or an equirectangular (latitude-longitude) image, importance-sampled by a 2D
 * piecewise-constant distribution over the image (pbrt-v4 sec. 12.5.2). Directions w point
 * toward the environment; +y is up: theta = acos(w.y) from the top row down, phi =
 * atan2(w.z, w.x) in [0, 2 pi) from the left column. */
#ifndef CST_LIGHTS_ENVMAP_H
#define CST_LIGHTS_ENVMAP_H

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"
#include "sampling/distrib1d.h"

typedef struct EnvMap {
    Color scale;      /* multiplies the image; the radiance itself when there is none */
    float *rgb;     /* width * height * 3 linear values, row 0 = theta 0 (up); NULL = constant */
    int width, height;
    Distrib1D marginal; /* rows, weighted by their luminance times sin theta */
    Distrib1D *rows;    /* per row, its columns by luminance */
    float power;        /* the integral of luminance over the sphere (W/m^2 per unit area of a disk...) */
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

#endif
