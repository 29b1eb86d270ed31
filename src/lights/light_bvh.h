/* The light BVH: next-event estimation's choice of a light by its estimated contribution
 * at the shading point (Conty Estevez & Kulla 2018, as pbrt-v4's BVHLightSampler). */
#ifndef CST_LIGHTS_LIGHT_BVH_H
#define CST_LIGHTS_LIGHT_BVH_H

#include "lights/light.h"

/* What a light (or a subtree of lights) can send where: its box, its power phi (luminance
 * of the flux, W), and the cone of its emission: surface normals within theta_o of the
 * unit axis w, each emitting up to theta_e beyond its normal (pi/2 for a Lambertian
 * surface); two_sided emits on both sides (pbrt-v4 LightBounds). phi = 0: empty. */
typedef struct LightBounds {
    Vec3 lo, hi;
    Vec3 w;
    float phi;
    float cos_o, cos_e;
    int two_sided;
} LightBounds;

typedef struct LightBvhNode {
    LightBounds b;
    int index;   /* interior: the second child (the first is the next node); leaf: the light */
    int parent;  /* -1 at the root */
    int is_leaf;
} LightBvhNode;

/* Built over the lights with a position (area, point, spot, goniometric); the infinitely
 * distant ones (directional, environment) are picked apart from it, each with probability
 * p_infinite / num_infinite (pbrt-v4: p_infinite = num_infinite / (num_infinite + 1)). */
typedef struct LightBvh {
    LightBvhNode *nodes;
    int num_nodes;
    int *leaf;        /* per light of the EmitterSampler: its leaf, -1 for infinite lights */
    int *infinite;    /* light indices of the infinite lights */
    int num_infinite;
    float p_infinite;
} LightBvh;

/* Builds the tree over s's lights (g: their geometry). Returns CST_ERR_OOM on failure,
 * leaving *bvh empty. Free with light_bvh_free (accepts an empty one). */
CstStatus light_bvh_build(LightBvh *bvh, const EmitterSampler *s, const EmitterGeometry *g, CstError *err);
void light_bvh_free(LightBvh *bvh);

/* The bounds of one light with a position (pbrt-v4's Light::Bounds). */
LightBounds light_bounds_of(const Light *l, const EmitterGeometry *g, float phi);

/* The importance of bounds b for a shading point x with unit normal n (n = 0: none, a
 * point in a medium): phi times a conservative bound on cos theta at the light over d^2,
 * times a bound on |cos| at x (Conty & Kulla eq. 3; pbrt-v4 LightBounds::Importance). */
float light_bounds_importance(const LightBounds *b, Vec3 x, Vec3 n);

/* A light chosen at x with normal n by u in [0, 1): its index into the EmitterSampler's
 * lights and its probability *pmf; -1 when no light can contribute (every importance 0). */
int light_bvh_sample(const LightBvh *bvh, Vec3 x, Vec3 n, float u, float *pmf);
/* The probability that light_bvh_sample picks `light` at x, n. */
float light_bvh_pmf(const LightBvh *bvh, Vec3 x, Vec3 n, int light);

#endif
