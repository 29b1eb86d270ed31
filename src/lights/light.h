/* Lights: area emitters (any primitive with emission) and delta lights (point, spot,
 * directional). NEE picks a light with probability proportional to its power and, on an
 * area emitter, a point: uniform by area on triangles (or by their solid angle,
 * EmitterSampler.solid_angle), by the subtended cone on spheres, uniform by area on analytic
 * shapes (cylinders, disks, partial spheres: pbrt-v4 samples these by area too); light
 * paths start from a uniform point and add a direction. */
#ifndef CST_LIGHTS_LIGHT_H
#define CST_LIGHTS_LIGHT_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry/shape.h"
#include "geometry/sphere.h"
#include "lights/envmap.h"
#include "math/color.h"
#include "sampling/distrib1d.h"
#include "textures/texture.h"

typedef struct Emitter {
    uint32_t prim;  /* scene primitive id */
    Color radiance;   /* times the texture's value at the point, when textured */
    int texture;    /* 1 + index into the scene's textures; 0: constant radiance */
    Color average;    /* radiance averaged over the texture: the selection weight */
    int two_sided;
    float area;
    Vec3 n;        /* triangles: unit geometric normal (set by scene_commit) */
    int is_sphere; /* scene construction only: prim is still a sphere index */
    int is_shape;  /* scene construction only: prim is still an analytic shape index */
} Emitter;

/* Lights whose position or direction is a Dirac delta: no surface, never hit by a ray,
 * reached only by sampling them (pbrt-v4 sec. 12.1-12.4). */
typedef enum DeltaLightType {
    DELTA_POINT,       /* isotropic point: intensity I in every direction */
    DELTA_SPOT,        /* point with a cone: I on the axis, smoothstep falloff to 0 at cos_outer */
    DELTA_DIRECTIONAL, /* parallel light from infinitely far: irradiance E on a surface facing it */
    DELTA_GONIO,       /* point whose intensity I times an image over the sphere (goniometric) */
    DELTA_PROJECTION   /* point projecting an image through a frustum (pbrt-v4 ProjectionLight) */
} DeltaLightType;

/* A goniometric light's angular distribution (pbrt-v4 GoniometricLight): an n x n image of
 * factors over the sphere in Clarberg's equal-area octahedral layout (row 0 at the top,
 * as pbrt-v4 reads it), looked up nearest at the light-space direction light_from_world w. */
typedef struct GonioImage {
    const float *factor;     /* n * n values >= 0, owned by the scene */
    int n;
    float light_from_world[9]; /* row-major 3 x 3 */
    float mean;              /* the factors' mean: the light emits 4 pi I mean */
} GonioImage;

/* A projection light's image (pbrt-v4 ProjectionLight): light space has the axis along +z;
 * a light-space direction d (d.z > 0) meets the plane z = 1 at screen point (d.x, d.y) /
 * (d.z tan_half), which must lie in the window [-sx, sx] x [-sy, sy] (the image's aspect on
 * the longer side, 1 on the shorter: fov spans the shorter side); u = (x + sx) / 2 sx,
 * v = (y + sy) / 2 sy pick the nearest pixel, row v h counted from row 0 as pbrt-v4's
 * LookupNearest does (no flip). Outside the window the light is dark. */
typedef struct ProjImage {
    const float *rgb;          /* w * h * 3 linear values >= 0, owned by the scene */
    int w, h;
    float light_from_world[9]; /* row-major rotation */
    float tan_half;            /* tan(fov / 2) */
    float sx, sy;
    Color integral;            /* the integral of the image over its solid angle, per channel
                                * (sr): the flux per unit intensity */
    float area;                /* the window's area on the plane z = 1: 4 sx sy tan_half^2 */
} ProjImage;

/* A point, spot or directional light as a scene is built (scene_add_delta_light);
 * emitter_sampler_init turns each into its Light. */
typedef struct DeltaLight {
    DeltaLightType type;
    Vec3 p;        /* point, spot: position */
    Vec3 dir;      /* spot: unit axis; directional: unit direction the light travels */
    Color intensity; /* point, spot: radiant intensity (W/sr) on the axis; directional: irradiance */
    float cos_inner, cos_outer; /* spot: full intensity within cos_inner, none beyond cos_outer */
    GonioImage gonio;           /* goniometric */
    ProjImage proj;             /* projection: intensity x the image's RGB */
} DeltaLight;

/* The kinds of light, one tag of the Light union. */
typedef enum LightType {
    LIGHT_AREA,        /* an emitting triangle or sphere (Emitter) */
    LIGHT_POINT,       /* isotropic point */
    LIGHT_SPOT,        /* point with a cone and smoothstep falloff */
    LIGHT_DIRECTIONAL, /* parallel light from infinitely far */
    LIGHT_ENVIRONMENT, /* radiance from every direction at infinity (EnvMap) */
    LIGHT_GONIO,       /* point with an image of its intensity over the sphere */
    LIGHT_PROJECTION   /* point projecting an image through a frustum */
} LightType;

typedef struct PointLight {
    Vec3 p;
    Color intensity; /* radiant intensity I, W/sr */
} PointLight;
typedef struct SpotLight {
    Vec3 p, dir;     /* position; unit axis */
    Color intensity; /* I on the axis, W/sr */
    float cos_inner, cos_outer; /* full intensity within cos_inner, none beyond cos_outer */
} SpotLight;
typedef struct GonioLight {
    Vec3 p;
    Color intensity; /* times the image's factor in each direction, W/sr */
    GonioImage image;
} GonioLight;
typedef struct ProjectionLight {
    Vec3 p;
    Color intensity; /* times the image's RGB in each direction, W/sr */
    ProjImage image;
} ProjectionLight;
typedef struct DirectionalLight {
    Vec3 dir;         /* unit direction the light travels */
    Color irradiance; /* E on a surface facing it, W/m^2 */
} DirectionalLight;

/* One light: a tagged union. Every sampling routine below switches on the tag. */
typedef struct Light {
    LightType type;
    union {
        Emitter area;
        PointLight point;
        SpotLight spot;
        DirectionalLight directional;
        GonioLight gonio;
        ProjectionLight proj;
        const EnvMap *env; /* borrowed from the scene */
    } u;
} Light;

/* How next-event estimation picks a light: by power (one distribution for every shading
 * point, also the light paths' choice), by the light BVH (light_bvh.h: by each light's
 * estimated contribution at the shading point, pbrt-v4's default "bvh"), or uniformly
 * (pbrt-v4 "uniform"). Light paths (emitter_sample_emission) and the bidirectional
 * integrators' connections (light_sample_li) always pick by power. */
typedef enum LightSelect { LIGHT_SELECT_POWER, LIGHT_SELECT_BVH, LIGHT_SELECT_UNIFORM } LightSelect;

/* The rule for a scene that names no light sampler: the BVH once it has more than this
 * many lights with a position (area emitters, point, spot and goniometric lights), power
 * below, where one distribution does as well and keeps today's images bit for bit. */
#define LIGHT_SELECT_BVH_ABOVE 64

struct LightBvh;

/* The scene's lights in one array, with light selection: one distribution over
 * light[0, lights), proportional to each light's power (luminance of its flux), so bright
 * lights get the samples. The area emitters come first, in the scene's emitter order (so
 * an emitter's index is its light index), then the point, spot and directional lights,
 * then the environment; a point on area light e has the area density
 * pdf_a[e] = pmf(e) / area(e). */
typedef struct EmitterSampler {
    Light *light;    /* lights entries */
    Distrib1D by_power;
    float *pdf_a;    /* per area light */
    int count;       /* area lights */
    int num_delta;   /* point, spot and directional lights */
    int lights;      /* count + num_delta (+ 1 with an environment): 0 = nothing to sample */
    const EnvMap *env;       /* borrowed from the scene, or NULL; light index count + num_delta */
    Vec3 center;     /* the scene's bounding sphere: directional lights cover its disk */
    float radius;
    LightSelect nee;       /* NEE's choice (emitter_sampler_set_nee); POWER after init */
    struct LightBvh *bvh;  /* with nee == LIGHT_SELECT_BVH, else NULL; owned */
    /* NEE (light_sample_nee and its densities) samples a triangle emitter by the solid
     * angle it subtends (sampling/spherical.h) where pbrt-v4 does; false: by area, as
     * light paths and the bidirectional connections always do. The environment's portal
     * (EnvMap.portal), when it has one, likewise serves NEE only. */
    bool solid_angle;
} EmitterSampler;

/* The geometry NEE needs, borrowed from the scene (scene_emitter_geometry() fills it). */
typedef struct EmitterGeometry {
    const Vec3 *positions;
    const int32_t *tri_indices;
    int num_triangles;
    const Sphere *spheres;
    /* texture coordinates (triangle_uv()) and textures, for textured emission */
    const Vec2 *uvs;
    const unsigned char *tri_has_uv;
    const Texture *textures;
    /* analytic shapes (geometry/shape.h): prim ids num_triangles + num_spheres + k */
    int num_spheres;
    const AnalyticShape *shapes;
} EmitterGeometry;

/* bounds_lo/hi: the scene's geometry bounds (directional lights' power and emission disk). */
CstStatus emitter_sampler_init(EmitterSampler *s, const Emitter *emitters, int n, const DeltaLight *delta,
                               int num_delta, const EnvMap *env, Vec3 bounds_lo, Vec3 bounds_hi, CstError *err);
void emitter_sampler_free(EmitterSampler *s);
/* Sets how NEE (light_sample_nee) picks lights, building the light BVH for
 * LIGHT_SELECT_BVH. On failure (OOM) the previous choice stays. */
CstStatus emitter_sampler_set_nee(EmitterSampler *s, const EmitterGeometry *g, LightSelect sel, CstError *err);
/* The rule for scenes that name none (LIGHT_SELECT_BVH_ABOVE). */
LightSelect emitter_sampler_auto_nee(const EmitterSampler *s);

/* Radiance leaving the emitter at a point with geometric normal ng and texture
 * coordinates uv toward direction w (unit, pointing away from the surface). One-sided
 * emitters are dark behind. textures: the scene's (read only when e is textured). */
static inline Color emitter_radiance(const Emitter *e, const Texture *textures, Vec3 ng, Vec2 uv, Vec3 w)
{
    if (!(e->two_sided || v3_dot(ng, w) > 0.0f)) return color_s(0.0f);
    return e->texture ? color_mul(e->radiance, texture_eval(textures, e->texture - 1, uv)) : e->radiance;
}

/* The area density of a point on area emitter e, selection included. */
static inline float emitter_pdf_a(const EmitterSampler *s, int e) { return s->pdf_a[e]; }

/* The environment: its radiance arriving from direction w (toward it; black without one),
 * and NEE's density of sampling w per unit solid angle, selection included. */
static inline Color light_env_radiance(const EmitterSampler *s, Vec3 w)
{
    return s->env ? envmap_eval(s->env, w) : color_s(0.0f);
}
static inline float light_env_pdf(const EmitterSampler *s, Vec3 w)
{
    return s->env ? s->by_power.pmf[s->count + s->num_delta] * envmap_pdf(s->env, w) : 0.0f;
}
static inline int light_env_index(const EmitterSampler *s) { return s->count + s->num_delta; }

/* NEE's density (per unit solid angle at x, selection included) of sampling the point at
 * distance dist on area emitter e, |cos| cos_l there, from x: what light_sample_li reports
 * as pdf_w for it, for the MIS weight of a BSDF-sampled ray that hits e. Spheres seen from
 * outside: pmf / (2 pi (1 - cos theta_max)); otherwise pdf_a dist^2 / cos_l. */
float light_area_pdf_w(const EmitterSampler *s, const EmitterGeometry *g, int e, Vec3 x, float dist, float cos_l);

/* Next-event estimation at x: a light picked by power (u_sel) and, for an area emitter, a
 * point on it (u): uniform by area on triangles and, from inside, on spheres; a sphere
 * seen from outside by a direction uniform in the cone it subtends (pbrt-v4
 * Sphere::Sample(ctx, u)). The estimate of direct light is f(wo, wi) li / pdf with the
 * shadow ray from x toward p (an area point or a delta light's position; for a
 * directional light a point beyond the scene). */
typedef struct LightLi {
    Vec3 p, n;   /* the light point and its unit normal (delta lights: n = -wi) */
    Vec3 wi;     /* unit, from x toward the light */
    float dist;  /* |p - x| */
    Color li;      /* area: L_e toward x; point/spot: I(-wi) / dist^2; directional: E */
    float pdf_w; /* area, environment: density of wi per unit solid angle, the light's
                  * selection included (the density the sample was drawn with; divide by
                  * it); 0 for delta lights */
    float pmf;   /* delta lights: the probability of picking this light, the whole
                  * density of the sample (a discrete one: the estimate has no MIS
                  * partner); 0 for the others. The estimate divides by pmf or pdf_w. */
    bool delta;
    bool finite; /* false for directional lights (no distance falloff) */
    int light;   /* area: emitter index; delta: count + delta light index */
    /* For bidirectional MIS (vcm.c; Georgiev's tech. rep. eqs. 44-45): a light path's
     * density of leaving the light toward x (position density per area, or selection
     * for delta positions, times the direction's per solid angle), the density NEE picks
     * the light point with expressed as SmallVCM's "directPdfW", and |cos| at the light.
     * For area lights direct_pdf is area sampling's, pdf_a dist^2 / |cos|, also where
     * the sample came from a sphere's cone: the bidirectional weights stay on the
     * densities of emitter_pdf_a, which the s = 0 strategy uses too. */
    float emit_pdf;
    float direct_pdf;
    float cos_light;
} LightLi;

/* False when no light can contribute (no lights, x on the light, or outside a spot's
 * cone); li is then black. */
bool light_sample_li(const EmitterSampler *s, const EmitterGeometry *g, Vec3 x, float u_sel, Vec2 u,
                     LightLi *out);

/* Next-event estimation at x with unit normal n (the shading normal; 0 in a medium): the
 * light picked by the NEE sampler (s->nee; with power selection the light_sample_li
 * picks), then a point or direction on it as light_sample_li samples one, except that
 * with s->solid_angle a triangle is sampled by its solid angle from x and an environment
 * with a portal through the portal (light_area_nee_pdf_w and light_env_nee_pdf give these
 * densities). pdf_w and pmf include the selection; emit_pdf and direct_pdf are the power
 * selection's (bidirectional MIS uses light_sample_li). */
bool light_sample_nee(const EmitterSampler *s, const EmitterGeometry *g, Vec3 x, Vec3 n, float u_sel, Vec2 u,
                      LightLi *out);
/* The probability that light_sample_nee picks light i at x, n. */
float light_nee_pmf(const EmitterSampler *s, Vec3 x, Vec3 n, int i);
/* light_area_pdf_w and light_env_pdf for light_sample_nee's selection at x, n: the
 * densities a BSDF-sampled ray's MIS weight needs (with power selection, the same). */
float light_area_nee_pdf_w(const EmitterSampler *s, const EmitterGeometry *g, int e, Vec3 x, Vec3 n, float dist,
                           float cos_l);
float light_env_nee_pdf(const EmitterSampler *s, Vec3 x, Vec3 n, Vec3 w);

typedef struct EmitterSample {
    Vec3 p, n; /* point and unit geometric normal */
    int emitter;
} EmitterSample;

/* A uniform point on area emitter i (u), its normal and texture coordinates. */
void emitter_sample_point(const Emitter *e, const EmitterGeometry *g, Vec2 u, Vec3 *p, Vec3 *n, Vec2 *uv);

/* The start of a light path. Area emitters: a uniform point and a cosine-weighted
 * direction around the emitting side's normal (two-sided ones pick either side with
 * probability 1/2). Point and goniometric lights: a uniform direction; spots: uniform in the cone;
 * directional: a uniform point on the disk of the scene's bounding sphere, upstream. */
typedef struct EmissionSample {
    Vec3 p, n;   /* point and unit normal (delta lights: n = w) */
    Vec2 uv;     /* area emitters: texture coordinates at p */
    Vec3 w;      /* unit direction of emission */
    int emitter; /* area: emitter index; delta: count + delta light index */
    Color beta;    /* the path's first throughput, the flux it carries:
                  * L_e |cos| / (pdf_a pdf_w), I(w) / (pmf pdf_w), or E pi R^2 / pmf */
    float pdf_a; /* area: density of p per unit area; point/spot: the selection
                  * probability; directional: pmf / (pi R^2) */
    float pdf_w; /* density of w per unit solid angle (directional: 1, a delta); 0 = no usable sample */
    float cos_l; /* |cos| between w and n: 1 for delta lights */
    float nee_pdf; /* the density with which NEE picks p: area: pdf_a; delta: the selection probability */
    bool delta;  /* a delta light: never hit, never connected to as a surface */
    float time;  /* the light path's time in the shutter (motion blur): 0 from emitter_sample_emission,
                  * set by the light tracer in a moving scene; the walk's rays carry it */
    bool finite; /* false for directional lights and the environment */
} EmissionSample;

void emitter_sample_emission(const EmitterSampler *s, const EmitterGeometry *g, float u_sel, Vec2 u_pos,
                             Vec2 u_dir, EmissionSample *out);
/* pdf_w of emitter_sample_emission for direction w at a point with normal n. */
float emitter_emission_pdf_w(const Emitter *e, Vec3 n, Vec3 w);

/* A projection light's image factor (RGB) toward world direction w (unit, away from the
 * light), black outside its window; *pdf_w (may be NULL) gets the density with which
 * emission sampling (uniform over the window) picks w, 1 / (area cos^3 theta), per solid angle. */
Color proj_factor(const ProjImage *g, Vec3 w, float *pdf_w);

/* Emitted power (luminance of the flux) of each kind of light: the selection weights. */
/* The luminance of a light's flux, its selection weight; infinitely distant lights (and
 * the environment) count the flux through the disk of the scene's bounding sphere. */
float light_power(const Light *l, float scene_radius);

#endif
