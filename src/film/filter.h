/* Pixel reconstruction filters: box, tent, Gaussian and Mitchell-Netravali, each a
 * separable h(x, y) = h1(x) h1(y) normalised to integrate to 1. Camera samples place
 * themselves by filter importance sampling (Ernst et al., "Filter Importance Sampling",
 * 2006) with a weight h / pdf; splats (light tracing) spread over the pixels whose
 * centres lie within the radius with weights h. Both then estimate the same pixel value,
 * I_p = integral of h(x - c_p) L(x) dx. */
#ifndef CST_FILM_FILTER_H
#define CST_FILM_FILTER_H

#include "caustic/caustic.h"
#include "math/vec3.h"
#include "sampling/warp.h"

enum { FILTER_TABLE = 64 }; /* bins per half-axis of the tabulated filters */

typedef struct Filter {
    CstFilter type;
    float radius; /* support [-radius, radius] per axis, in pixels */
    /* Gaussian and Mitchell: h1 on [0, radius] tabulated in FILTER_TABLE equal bins; the
     * sampling density is proportional to |h1| averaged per bin (piecewise constant), so
     * the sample weight h / pdf is close to 1 (Gaussian) or to +-C (Mitchell's negative
     * lobes) and exact for box and tent (weight 1). */
    float cdf[FILTER_TABLE + 1]; /* over [0, radius], of the binned |h1| */
    float bin_abs[FILTER_TABLE]; /* mean |h1| per bin */
    float norm;                  /* the integral of the unnormalised h1, numerically */
} Filter;

/* Sets up filter type (CST_FILTER_DEFAULT means box). */
void filter_init(Filter *f, CstFilter type);
/* h1 normalised: integrates to 1 over [-radius, radius]. */
float filter_eval1(const Filter *f, float x);
/* The same from the type alone (closed-form normalisation). */
float filter_weight1(CstFilter type, float x);
/* The support radius of a filter type, in pixels. */
static inline float filter_radius(CstFilter type)
{
    return type == CST_FILTER_GAUSSIAN ? 1.5f : type == CST_FILTER_MITCHELL ? 2.0f
         : type == CST_FILTER_TENT ? 1.0f : 0.5f;
}
/* An offset from the pixel centre, in pixels, with u in [0, 1)^2; *weight = h / pdf. */
Vec2 filter_sample(const Filter *f, Vec2 u, float *weight);

/* The film position of a camera sample of pixel (x, y) (camera_generate_ray's
 * convention) and its weight h / pdf: the box filter samples the pixel uniformly and the
 * tent by inverting its CDF (weight 1); the others by filter_sample. */
static inline Vec2 filter_film_position(const Filter *f, int x, int y, Vec2 u, float *weight)
{
    *weight = 1.0f;
    if (f->type == CST_FILTER_TENT)
        return v2((float)x + 0.5f + warp_tent(u.x), (float)y + 0.5f + warp_tent(u.y));
    if (f->type == CST_FILTER_GAUSSIAN || f->type == CST_FILTER_MITCHELL) {
        Vec2 d = filter_sample(f, u, weight);
        return v2((float)x + 0.5f + d.x, (float)y + 0.5f + d.y);
    }
    return v2((float)x + u.x, (float)y + u.y);
}

#endif
