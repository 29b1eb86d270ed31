/* Texture footprints at hits: pbrt-v4's approximation of a hit's screen-space derivatives
 * from the camera alone (Camera::Approximate_dp_dxy, PBR 4th ed. sec. 10.1.1), then of its
 * texture coordinates (SurfaceInteraction::ComputeDifferentials, sec. 10.1.2), so that MIP
 * filters can pick their level at every hit, after any number of bounces, without tracking
 * ray differentials along paths. */
#ifndef CST_SCENE_FOOTPRINT_H
#define CST_SCENE_FOOTPRINT_H

#include <math.h>
#include <stdbool.h>

#include "camera/camera.h"
#include "math/vec3.h"
#include "textures/texture.h"

typedef struct Footprint {
    bool enabled; /* some texture filters with a footprint (scene_commit) */
    bool ortho;
    Vec3 origin, forward, right, up; /* the camera's frame */
    /* The smallest change of a camera ray per pixel step over the film, in x and y: of its
     * origin (scene units; orthographic cameras) and of its unit direction (perspective). */
    float pos_dx, pos_dy, dir_dx, dir_dy;
    /* pbrt-v4 shrinks the footprint with the pixel's sample count, max(1/8, 1/sqrt(spp)):
     * samples that jitter over the pixel already average what a wider filter would. */
    float spp_scale;
} Footprint;

/* The camera of desc at width x height (mirrored like the render when mirror), searched
 * over a grid of film positions as pbrt-v4's FindMinimumDifferentials does. */
void footprint_init(Footprint *fp, const CameraDesc *desc, bool mirror, int width, int height, int spp);

/* The approximate change of the surface point p (geometric normal n) per pixel step in x
 * and y: the camera's minimal differential rays, turned to look at p, met with p's tangent
 * plane. */
void footprint_dp_dxy(const Footprint *fp, Vec3 p, Vec3 n, Vec3 *dpdx, Vec3 *dpdy);

/* The texture context at p (normal n): p, n, dp/dx, dp/dy, uv and its derivatives, the least-squares solution of
 * dp/dx = dpdu du/dx + dpdv dv/dx (and for y) (PBR 4th ed. eq. 10.7), clamped to 1e8. */
TexCtx footprint_tex_ctx(const Footprint *fp, Vec3 p, Vec3 n, Vec2 uv, Vec3 dpdu, Vec3 dpdv);

#endif
