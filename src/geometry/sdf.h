/* Signed-distance shapes: a CSG tree of primitives (sphere, box, rounded box, torus, capsule,
 * capped cylinder) under union, intersection, difference and smooth union, each node with
 * its own transform, intersected by sphere tracing (Hart 1996) with a final bisection. */
#ifndef CST_GEOMETRY_SDF_H
#define CST_GEOMETRY_SDF_H

#include <stdbool.h>

#include "geometry/ray.h"
#include "math/bbox.h"
#include "math/transform.h"

/* In the order of the public CstSdfKind. Primitives are centred at their node's origin;
 * lengths in the node's units. */
typedef enum SdfKind {
    SDF_SPHERE = 0,   /* prm[0] radius */
    SDF_BOX,          /* prm[0..2] half extents */
    SDF_ROUND_BOX,    /* prm[0..2] half extents (of the rounded box itself), prm[3] rounding radius */
    SDF_TORUS,        /* about z: prm[0] major radius (axis to tube centre), prm[1] minor radius */
    SDF_CAPSULE,      /* along z: the segment z in [-prm[0], prm[0]] swept by a ball of radius prm[1] */
    SDF_CYLINDER,     /* capped, about z: prm[0] radius, z in [-prm[1], prm[1]] */
    SDF_UNION,        /* min(a, b) */
    SDF_INTERSECTION, /* max(a, b) */
    SDF_DIFFERENCE,   /* a minus b: max(a, -b) */
    SDF_SMOOTH_UNION  /* polynomial smooth minimum of a and b with blend radius k */
} SdfKind;
enum { SDF_KIND_COUNT = 10, SDF_FIRST_OPERATOR = SDF_UNION };

/* Limits of a tree: nodes, depth (the evaluation recurses), sphere-tracing steps. */
enum { SDF_MAX_NODES = 256, SDF_MAX_DEPTH = 24, SDF_DEFAULT_STEPS = 1024, SDF_MAX_STEPS = 1 << 16 };

/* The default epsilon relative to the shape's world extent (SdfTree.eps). */
#define SDF_EPS_RELATIVE 1e-5

/* One node as a caller describes it: operands a, b are indices of earlier nodes (so the
 * array is in post-order and acyclic); every node but the last (the root) is the operand of
 * exactly one other. parent_from_node places the node (and its subtree) in its parent's
 * space, or the shape's object space for the root; has_xf false: identity. */
typedef struct SdfNodeDesc {
    SdfKind kind;
    double prm[4];
    int a, b;
    double k;
    bool has_xf;
    Transform parent_from_node;
} SdfNodeDesc;

typedef enum SdfError {
    SDF_OK = 0,
    SDF_ERR_EMPTY,     /* no nodes, or more than SDF_MAX_NODES */
    SDF_ERR_KIND,      /* kind not an SdfKind */
    SDF_ERR_PARAM,     /* a primitive's lengths not finite and > 0 (rounding radius > min half extent; minor >= major) */
    SDF_ERR_BLEND,     /* smooth union k not finite and > 0 */
    SDF_ERR_OPERAND,   /* an operand not an earlier node */
    SDF_ERR_SHARED,    /* a node used as an operand twice, or never (but the root) */
    SDF_ERR_DEPTH,     /* deeper than SDF_MAX_DEPTH */
    SDF_ERR_TRANSFORM, /* a transform singular or not finite */
    SDF_ERR_OPTIONS    /* epsilon not finite and >= 0, max_steps outside [0, SDF_MAX_STEPS] */
} SdfError;
const char *sdf_error_string(SdfError e);

typedef struct SdfOptions {
    double epsilon; /* world units; 0: SDF_EPS_RELATIVE x the world extent */
    int max_steps;  /* 0: SDF_DEFAULT_STEPS */
} SdfOptions;

typedef struct SdfTree SdfTree;

/* A tree from nodes[0..n), placed in the world by world_from_object. Returns SDF_OK and a
 * new tree (caller owns it: sdf_tree_destroy), or the error and in *bad the index of the
 * offending node (-1 for the options or the world transform). */
SdfError sdf_tree_create(const SdfNodeDesc *nodes, int n, const Transform *world_from_object,
                         const SdfOptions *opt, SdfTree **out, int *bad);
void sdf_tree_destroy(SdfTree *t);

/* World bounds of the surface (every point with field <= 0), padded outward so that the
 * rounding to float cannot cut off a hit sdf_intersect reports. */
BBox sdf_tree_bounds(const SdfTree *t);
/* The field at a world point, in world units: negative inside, positive outside, a lower
 * bound of the distance to the surface times sdf_tree_lipschitz (see sdf.c). */
double sdf_eval(const SdfTree *t, const double p[3]);
double sdf_tree_lipschitz(const SdfTree *t);
double sdf_tree_epsilon(const SdfTree *t);

/* Nearest surface crossing with float t in (r->t_min, r->t_max), world t. Deterministic in
 * (r->o, r->d, r->t_min): r->t_max only cuts the march off, so every back end, whatever
 * t_max it holds, gets the same t to the bit. */
bool sdf_intersect(const SdfTree *t, const Ray *r, float *t_out);

/* The surface at a reported hit: the point (one Newton step onto the surface along the
 * gradient), the unit outward normal (the field's gradient by central differences), uv
 * (spherical angles about the centre of the bounds: u = phi / 2 pi, v = theta / pi). */
void sdf_surface(const SdfTree *t, const Ray *r, float t_hit, Vec3 *p, Vec3 *n, Vec2 *uv);

#endif
