/* Analytic shapes, the accels' third primitive kind: one tagged struct per primitive
 * (pbrt-v4's quadrics: cylinder, disk, partial sphere) with its transforms and bounds,
 * and shape_intersect(), a switch on the tag that every back end calls. */
#ifndef CST_GEOMETRY_SHAPE_H
#define CST_GEOMETRY_SHAPE_H

#include <stdbool.h>

#include "geometry/curve.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "geometry/sdf.h"
#include "math/bbox.h"
#include "math/transform.h"

/* Further kinds (curves, bilinear patches, implicit surfaces) are further tags: a case in
 * shape_intersect(), shape_surface(), shape_object_bounds() and, if they emit, in
 * shape_area()/shape_sample_area(). Nothing outside this module switches on the tag. */
typedef enum ShapeTag {
    SHAPE_TAG_CYLINDER = 0, /* about +z, radius r, z in [z_min, z_max], phi in [0, phi_max] */
    SHAPE_TAG_DISK,         /* in the plane z = height, inner_radius <= rho <= r, phi in [0, phi_max] */
    SHAPE_TAG_SPHERE,       /* centred at the origin, clipped to [z_min, z_max] and [0, phi_max] */
    SHAPE_TAG_BILINEAR,     /* pbrt-v4's bilinear patch: four world-space corners (shape_init_bilinear) */
    SHAPE_TAG_TORUS,        /* about +z: radius (major) to the tube's centre, minor_radius the tube's;
                             * the quartic solved in double (math/polynomial.h) */
    SHAPE_TAG_SDF,          /* a signed-distance CSG tree (geometry/sdf.h, shape_init_sdf), sphere-traced */
    SHAPE_TAG_CURVE         /* one segment of pbrt-v4's curve, world space (shape_init_curve, curve.h) */
} ShapeTag;
enum { SHAPE_TAG_COUNT = 7 };

/* A bilinear patch p(u, v) = (1-u)(1-v) p00 + u(1-v) p10 + (1-u)v p01 + uv p11 (pbrt-v4
 * §6.6; corners in pbrt's order p00, p10, p01, p11), in world space, in double; optional
 * per-corner normals (the shading normal interpolated bilinearly, the geometric normal
 * turned to face it, as pbrt-v4) and texture coordinates (interpolated bilinearly). */
typedef struct BilinearPatch {
    double q[4][3];
    float uv[4][2];
    float n[4][3];
    bool has_uv, has_n;
} BilinearPatch;

/* The parameters in object space, as pbrt-v4 takes them (lengths in the object's units,
 * phi_max in radians). */
typedef struct ShapeParams {
    ShapeTag type;
    float radius;
    float z_min, z_max;   /* cylinder, sphere (clamped to [-r, r] for the sphere) */
    float height;         /* disk */
    float inner_radius;   /* disk */
    float phi_max;        /* (0, 2 pi] (the torus is always whole) */
    bool reverse_orientation;
    float minor_radius;   /* torus: 0 < minor_radius < radius */
} ShapeParams;

/* One primitive: parameters, object-to-world and its inverse in double (the intersection
 * runs in object space in double, so every back end, given the same ray, finds the same
 * t to the bit), the world bounds. Laid out for the leaf test, which reads the tag and
 * then the union: the union follows the tag's ShapeParams, so a curve's test data (tag,
 * control points, reach, widths, type, depth) is bytes 0-111, and the size is six cache
 * lines (no normal matrix: w2o holds it). */
typedef struct AnalyticShape {
    ShapeParams p;                  /* p.type first: the tag every test reads */
    union {
        struct {                        /* the quadrics */
            double o2w[3][4], w2o[3][4]; /* affine rows: linear part | translation; the
                                          * normal matrix (o2w's inverse transpose) is
                                          * w2o's linear part transposed (shape.c) */
        };
        BilinearPatch bl;               /* SHAPE_TAG_BILINEAR */
        SdfTree *sdf;                   /* SHAPE_TAG_SDF: owned (shape_release); copies borrow it */
        Curve cv;                       /* SHAPE_TAG_CURVE */
    };
    double r, z_min, z_max, height, r_inner, phi_max; /* p's, in double for the arithmetic */
    double theta_z_min, theta_z_max; /* sphere: acos(z_min / r), acos(z_max / r) */
    double r_minor;                 /* torus */
    bool flip_normal;               /* reverse_orientation XOR the transform mirrors */
    BBox bounds;                    /* world, padded outward to contain every reported hit */
    char pad_to_lines[48];          /* 336 -> 384 bytes: six whole cache lines */
} AnalyticShape;
_Static_assert(sizeof(AnalyticShape) % 64 == 0, "AnalyticShape: whole cache lines");

/* Builds a shape from its parameters and object-to-world transform. False when the
 * parameters are out of range (radius <= 0, z_min >= z_max for cylinders, phi_max
 * outside (0, 2 pi], inner_radius outside [0, r)) or the transform is singular. */
bool shape_init(AnalyticShape *s, const ShapeParams *p, const Transform *object_to_world);

/* A bilinear patch from its corners p[4] (p00, p10, p01, p11, world space), optional
 * normals n[4] and uvs uv[4] (NULL: none); flip: pbrt-v4's ReverseOrientation XOR a
 * handedness-swapping transform (used without normals). False for non-finite corners or
 * a patch without area (every corner on one line). */
bool shape_init_bilinear(AnalyticShape *s, const Vec3 p[4], const Vec3 *n, const Vec2 *uv, bool flip);

/* An SDF shape from its tree, whose ownership passes to the shape (freed by shape_release).
 * Not emitting: shape_area is 0, no sampling. */
void shape_init_sdf(AnalyticShape *s, SdfTree *tree);

/* Frees what the shape owns (an SDF tree); the owner of the shape array calls it once per
 * shape, copies (an octree's) never. NULL-safe. */
void shape_release(AnalyticShape *s);

/* A curve segment (curve_init's arguments; the whole curve's control points, world
 * space): false where curve_init is. Curves do not emit (shape_area is 0). */
bool shape_init_curve(AnalyticShape *s, const Vec3 whole_cp[4], float u0, float u1, float w0, float w1,
                      CurveType type, const Vec3 *n, bool flip);

/* The shape's curve segment, NULL for other kinds: for an accel's compact curve records
 * (curve_seg_init). */
static inline const Curve *shape_curve(const AnalyticShape *s)
{
    return s->p.type == SHAPE_TAG_CURVE ? &s->cv : NULL;
}

/* The boxes an accel may bound the shape by, their union holding every hit: a curve's
 * pieces (curve_piece_bounds), else the one box s->bounds. Returns their count. */
static inline int shape_piece_bounds(const AnalyticShape *s, BBox boxes[CURVE_MAX_PIECES])
{
    if (s->p.type == SHAPE_TAG_CURVE) return curve_piece_bounds(&s->cv, boxes);
    boxes[0] = s->bounds;
    return 1;
}

/* Nearest hit in (r->t_min, r->t_max): *t and the shape's (u, v) parameters (pbrt-v4:
 * u = phi / phi_max, v along z for cylinders and spheres, from the rim inward for disks).
 * The ray's t is world t (the object-space direction is not renormalised). */
bool shape_intersect(const AnalyticShape *s, const Ray *r, float *t, float *u, float *v);

/* The surface at a hit shape_intersect reported at t: the point reprojected onto the
 * shape in double (so it is off the surface by the final rounding to float only, which
 * the fixed-ulp spawn offset of ray_offset_origin covers: pbrt-v4 §6.8 bounds it by
 * gamma(n) |p| per coordinate for these reprojected quadric points), the unit geometric
 * normal (outward for cylinders and spheres, +z for disks, flipped by flip_normal as
 * pbrt-v4's SurfaceInteraction does), and dp/du, dp/dv in world space. */
typedef struct ShapeSurface {
    Vec3 p, n, dpdu, dpdv;
    Vec2 uv;
    Vec3 ns; /* shading normal: n, or a bilinear patch's interpolated normals */
} ShapeSurface;
void shape_surface(const AnalyticShape *s, const Ray *r, float t, ShapeSurface *out);

/* The surface at parameters (u, v) in [0,1]^2 (the same conventions): for area sampling.
 * For bilinear patches (u, v) are the patch parameters (out->uv the texture coordinates). */
void shape_surface_at(const AnalyticShape *s, Vec2 uv, ShapeSurface *out);

/* The derivatives of the outward unit normal at parameters (u, v) (the same conventions),
 * in world space: what the Weingarten equations give (PBR 4th ed. eq. 6.5-6.7), here in
 * closed form (the quadrics' and the torus's unit normal differentiated), mapped as
 * normals are (pbrt-v4 transforms dndu by the inverse transpose and does not flip it
 * with ReverseOrientation). False, with zeros, for bilinear patches, curves and SDFs. */
bool shape_dnduv(const AnalyticShape *s, Vec2 uv, Vec3 *dndu, Vec3 *dndv);

/* World-space area (bilinear patches: composite Simpson over 64 x 64 cells of |dp/du x
 * dp/dv|, exact for parallelograms): exact for a similarity transform (uniform scale), pbrt-v4's Area()
 * scaled by the area factor of the transform otherwise (the sampled density is then not
 * uniform; shape_sample_area reports the true pdf of what it draws). */
float shape_area(const AnalyticShape *s);

/* Whether the object-to-world map is a similarity (rotation, mirror, uniform scale, to a
 * relative 1e-5): then shape_sample_area is uniform by world area, its pdf_a the constant
 * 1 / shape_area, which area lights need (emitting shapes must pass this). False for
 * bilinear patches (sampled uniformly in (u, v), density 1 / |dp/du x dp/dv| per area). */
bool shape_uniform_area(const AnalyticShape *s);

/* A point by area (pbrt-v4 Cylinder/Disk/Sphere::Sample(u)): cylinders uniform in (phi, z),
 * disks by the concentric map restricted to the annulus (uniform in area), spheres
 * uniform in (phi, z) (Archimedes: uniform in area). *pdf_a per world area at the point,
 * 1 / world area for similarity transforms. */
void shape_sample_area(const AnalyticShape *s, Vec2 u, ShapeSurface *out, float *pdf_a);
/* The density shape_sample_area draws a point with, per world area, at surface sf. */
float shape_pdf_area(const AnalyticShape *s, const ShapeSurface *sf);

/* The leaf test of every back end: shapes ids[0..count) (scene primitive ids; shape k has
 * id base + k), closest hit in r's interval, r->t_max shrunk to it. Ids in the order the
 * back end stores them; ties keep the first, as the triangle and sphere leaves do. */
static inline bool shape_leaf_intersect(const AnalyticShape *shapes, uint32_t base, const uint32_t *ids,
                                        uint32_t count, Ray *r, Hit *hit)
{
    bool found = false;
    for (uint32_t i = 0; i < count; i++) {
        float t, u, v;
        if (shape_intersect(&shapes[ids[i] - base], r, &t, &u, &v)) {
            r->t_max = t;
            hit->t = t; hit->u = u; hit->v = v; hit->prim = ids[i];
            found = true;
        }
    }
    return found;
}
static inline bool shape_leaf_occluded(const AnalyticShape *shapes, uint32_t base, const uint32_t *ids,
                                       uint32_t count, const Ray *r)
{
    for (uint32_t i = 0; i < count; i++) {
        float t, u, v;
        if (shape_intersect(&shapes[ids[i] - base], r, &t, &u, &v)) return true;
    }
    return false;
}

#endif
