/* Area emitters: any primitive with emission. NEE picks an emitter with probability
 * proportional to its area and a uniform point on it, so a point on any emitter has the
 * area density pdf_a = 1 / (total emitting area). Light tracing starts its paths the same
 * way and adds a cosine-weighted direction on an emitting side. */
#ifndef CST_LIGHTS_LIGHT_H
#define CST_LIGHTS_LIGHT_H

#include <stdint.h>

#include "geometry/sphere.h"
#include "math/rgb.h"
#include "sampling/distrib1d.h"

typedef struct Emitter {
    uint32_t prim;  /* scene primitive id */
    Rgb radiance;
    int two_sided;
    float area;
    Vec3 n;        /* triangles: unit geometric normal (set by scene_commit) */
    int is_sphere; /* scene construction only: prim is still a sphere index */
} Emitter;

typedef struct EmitterSampler {
    Distrib1D by_area;
    float pdf_a; /* 1 / total area */
    int count;
} EmitterSampler;

/* The geometry NEE needs, borrowed from the scene. */
typedef struct EmitterGeometry {
    const Vec3 *positions;
    const int32_t *tri_indices;
    int num_triangles;
    const Sphere *spheres;
} EmitterGeometry;

CstStatus emitter_sampler_init(EmitterSampler *s, const Emitter *emitters, int n, CstError *err);
void emitter_sampler_free(EmitterSampler *s);

/* Radiance leaving the emitter at a point with geometric normal ng toward direction w
 * (unit, pointing away from the surface). One-sided emitters are dark behind. */
static inline Rgb emitter_radiance(const Emitter *e, Vec3 ng, Vec3 w)
{
    return (e->two_sided || v3_dot(ng, w) > 0.0f) ? e->radiance : rgb_s(0.0f);
}

typedef struct EmitterSample {
    Vec3 p, n; /* point and unit geometric normal */
    int emitter;
} EmitterSample;

/* Picks an emitter by area with u_sel and a uniform point on it with u. The point's
 * density is s->pdf_a per unit area. */
void emitter_sample(const EmitterSampler *s, const Emitter *emitters, const EmitterGeometry *g,
                    float u_sel, Vec2 u, EmitterSample *out);

typedef struct EmissionSample {
    Vec3 p, n;   /* point and unit geometric normal */
    Vec3 w;      /* unit direction of emission, on an emitting side */
    int emitter;
    float pdf_a; /* density of p per unit area (= s->pdf_a) */
    float pdf_w; /* density of w given p per unit solid angle; 0 = no usable sample */
} EmissionSample;

/* The start of a light path: a point as emitter_sample picks it (emitter by area, uniform
 * on it; u_sel, u_pos) and a cosine-weighted direction around the emitting side's normal
 * (u_dir); two-sided emitters pick either side with probability 1/2. */
void emitter_sample_emission(const EmitterSampler *s, const Emitter *emitters,
                             const EmitterGeometry *g, float u_sel, Vec2 u_pos, Vec2 u_dir,
                             EmissionSample *out);
/* pdf_w of emitter_sample_emission for direction w at a point with normal n. */
float emitter_emission_pdf_w(const Emitter *e, Vec3 n, Vec3 w);

#endif
