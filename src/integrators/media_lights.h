/* Emitting participating media as light sources for the light tracer and SPPM's photons:
 * a start point in the medium by a volume density, an isotropic direction, and the flux
 * the start carries (docs/integrators.md, "Emissive media"). */
#ifndef CST_INTEGRATORS_MEDIA_LIGHTS_H
#define CST_INTEGRATORS_MEDIA_LIGHTS_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "math/bbox.h"
#include "math/spectrum.h"
#include "sampling/distrib1d.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

/* One emitting medium as a light. Homogeneous: points uniform in `box`, the world bounds of
 * the shapes whose inside it is. Grid (and cloud): a majorant cell by its density bound,
 * then a point uniform in the cell (medium space, mapped to world). */
typedef struct MediaLight {
    int medium;
    bool grid;
    BBox box;                    /* homogeneous */
    Transform world_from_medium; /* grid */
    Vec3 p0, ext;                /* grid: its box's corner and extent in medium space */
    int res[3];                  /* grid: majorant cells per axis */
    Distrib1D cells;             /* grid: per majorant cell, its density bound */
    float inv_volume;            /* 1 / world volume of the box (homogeneous) or of one cell (grid) */
} MediaLight;

typedef struct MediaLights {
    MediaLight *light;
    int count;
    Distrib1D by_power; /* a medium by its bound on the power it emits (luminance) */
    float p_media;      /* probability that a light path starts in a medium rather than on
                         * the light sampler's emitters: 1/2, or 1 without such emitters */
} MediaLights;

/* A start in an emitting medium: point p (in `medium`), isotropic direction w. */
typedef struct MediaEmission {
    Vec3 p, w;
    int medium;
    Color le;   /* sigma_a(p) Le(p) / (p_sel p_V(p)): the radiance the volume emits per unit
                 * length toward any direction, over the density of p per unit volume (times
                 * the choice of a medium start and of this medium) */
    Color beta; /* le / pdf_w, pdf_w = 1 / (4 pi): the light path's first throughput */
} MediaEmission;

/* The index of the first medium of s that emits, or -1. */
int media_lights_first_emissive(const Scene *s);

/* The emitting media of s as lights into *out (NULL when none emits). Fails with
 * CST_ERR_UNSUPPORTED for a homogeneous emitting medium that no shape bounds (no shape has
 * it inside, a shape with it outside reaches past those, or the camera sits in it outside
 * them): its volume cannot be sampled. `who` names the integrator in the message. CST_ERR_OOM.
 * Caller owns *out: media_lights_destroy(). */
CstStatus media_lights_create(const Scene *s, const char *who, MediaLights **out, CstError *err);
void media_lights_destroy(MediaLights *ml);

/* A start point and direction (six random numbers from rng, always all drawn). False when
 * the start carries nothing: the point is outside the medium's region (another medium
 * there, as the camera's ray sees it: medium_at_point) or where it does not emit. */
bool media_lights_sample(const MediaLights *ml, const Scene *s, const Camera *cam, float time, const Wavelengths *wl,
                         Sampler *rng, MediaEmission *out, uint64_t *rays);

#endif
