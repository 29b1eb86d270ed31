/* Part of caustic's public API, included by caustic/caustic.h (include that, not this):
 * analytic shapes, intersected exactly rather than tessellated (pbrt-v4's quadrics,
 * bilinear patches and curves; tori; signed-distance CSG trees), and cst_scene_add_shape.
 * Kept apart only to keep each header readable. */
#ifndef CAUSTIC_CAUSTIC_SHAPES_H
#define CAUSTIC_CAUSTIC_SHAPES_H

#ifndef CAUSTIC_CAUSTIC_H
#error "include caustic/caustic.h, which includes this header"
#endif

/* Analytic shapes (pbrt-v4's quadrics), intersected exactly rather than tessellated. */
typedef enum CstShapeType {
    CST_SHAPE_CYLINDER = 0, /* about the object's z axis, z_min <= z <= z_max */
    CST_SHAPE_DISK,         /* in the plane z = height, inner_radius <= distance to the axis <= radius */
    CST_SHAPE_SPHERE,       /* centred at the object's origin, cut to z_min <= z <= z_max */
    CST_SHAPE_BILINEAR,     /* pbrt-v4's bilinear patch through patch[0..3] (p00, p10, p01, p11),
                             * world space (world_from_object applied); not emitting */
    CST_SHAPE_TORUS,        /* about z: radius to the tube's centre, minor_radius (< radius) the tube's */
    CST_SHAPE_SDF,          /* a signed-distance CSG tree sdf_nodes[0..sdf_num_nodes), sphere-traced */
    CST_SHAPE_CURVE         /* pbrt-v4's curve: one cubic Bezier (curve_*), not emitting */
} CstShapeType;
/* pbrt-v4's curve types: a ribbon facing the ray; the same with its normal turned across
 * the width like a tube's; a ribbon oriented by curve_normals. */
typedef enum CstCurveType { CST_CURVE_FLAT = 0, CST_CURVE_CYLINDER, CST_CURVE_RIBBON } CstCurveType;

/* A CST_SHAPE_SDF tree's nodes; primitives centred at the node's origin, params: sphere
 * radius; box half extents xyz; round box those and a rounding radius (<= the smallest);
 * torus about z major, minor (< major); capsule along z half length (>= 0), radius; capped
 * cylinder about z radius, half height. Operators take nodes a, b (earlier ones; each node
 * but the last, the root, an operand exactly once); difference is a minus b; smooth union
 * blends over k > 0. parent_from_node: 3 x 4 row-major, the node in its parent; 0: identity. */
typedef enum CstSdfKind {
    CST_SDF_SPHERE = 0, CST_SDF_BOX, CST_SDF_ROUND_BOX, CST_SDF_TORUS, CST_SDF_CAPSULE, CST_SDF_CYLINDER,
    CST_SDF_UNION, CST_SDF_INTERSECTION, CST_SDF_DIFFERENCE, CST_SDF_SMOOTH_UNION
} CstSdfKind;
typedef struct CstSdfNode {
    CstSdfKind kind;
    float params[4];
    int a, b;
    float k;
    float parent_from_node[12];
} CstSdfNode;
typedef struct CstShapeDesc {
    CstShapeType type;
    float radius;
    float z_min, z_max;      /* cylinder (z_min < z_max); sphere (clamped to [-r, r]; both 0: whole) */
    float height;            /* disk */
    float inner_radius;      /* disk: 0 <= inner_radius < radius */
    float phi_max_degrees;   /* the swept angle about z from +x toward +y, (0, 360]; 0: 360 */
    int reverse_orientation; /* flips the normal (pbrt's ReverseOrientation) */
    float world_from_object[12]; /* 3 x 4 row-major affine, as cst_scene_add_instance; all 0: identity */
    int material;
    CstEmission emission;    /* zero: none; else an area light sampled by area, which needs a
                              * similarity world_from_object (CST_ERR_UNSUPPORTED otherwise) */
    CstAlpha alpha;          /* over the shape's uvs; zero: opaque */
    /* CST_SHAPE_BILINEAR: p(u, v) = (1-u)(1-v) p00 + u(1-v) p10 + (1-u)v p01 + uv p11; optional
     * per-corner normals (the shading normal, interpolated; the geometric normal faces it)
     * and texture coordinates (interpolated; default (u, v)). The normal is dp/du x dp/dv,
     * flipped by reverse_orientation and a mirroring world_from_object when no normals. */
    float patch[4][3];
    int patch_has_normals, patch_has_uvs;
    float patch_normals[4][3];
    float patch_uvs[4][2];
    float minor_radius;          /* CST_SHAPE_TORUS; tori and SDF shapes do not emit */
    /* CST_SHAPE_SDF: the tree (copied), epsilon (world units; 0: 1e-5 of the size), step limit (0: 1024) */
    const CstSdfNode *sdf_nodes;
    int sdf_num_nodes;
    float sdf_epsilon;
    int sdf_max_steps;
    /* CST_SHAPE_CURVE: the cubic Bezier through curve_p[0..3] (object space, world_from_object
     * applied), widths curve_width[0..1] at its ends (object units, times the cube root of
     * |det| of world_from_object: exact for uniform scales), curve_normals[0..1] at its ends
     * (CST_CURVE_RIBBON only; nonzero), split into 2^curve_split_depth segments (0..10, pbrt's
     * "splitdepth"), each a primitive of its own (pbrt-v4's Curve: about 0.43 KB with its
     * AnalyticShape and PrimInfo). u runs along the curve, v across it (the hair material's
     * offset h = -1 + 2 v). Width 0 at both ends, non-finite points: CST_ERR_INVALID_ARG. */
    float curve_p[4][3];
    float curve_width[2];
    CstCurveType curve_type;
    float curve_normals[2][3];
    int curve_split_depth;
} CstShapeDesc;
/* u = phi / phi_max; v along z (cylinder, sphere) or from the rim inward (disk), as pbrt-v4.
 * The normal points away from the axis (cylinder), outward (sphere), along +z (disk),
 * flipped by reverse_orientation and by a mirroring world_from_object, as pbrt-v4 does. */
CST_API CstStatus cst_scene_add_shape(CstScene *scene, const CstShapeDesc *desc, CstError *err);
/* An analytic shape in an instanced object (pbrt-v4's AnimatedPrimitive over a sphere,
 * cylinder, disk, ...: the object placed by cst_scene_add_instance_motion moves it). desc
 * as for cst_scene_add_shape, its world_from_object placing the shape in the object's
 * space; its emission must be zero (instances do not emit: CST_ERR_UNSUPPORTED). object:
 * -1 makes a new object holding the shape, else an id from cst_scene_add_object or this
 * call gets it added. *out_id (may be NULL) gets the object's id. */
CST_API CstStatus cst_scene_add_object_shape(CstScene *scene, int object, const CstShapeDesc *desc, int *out_id,
                                             CstError *err);

/* A whole pbrt-v4 curve (its CreateCurves): num_points control points (object space) that
 * make cubic or quadratic Bezier segments sharing their end points (bspline 0:
 * degree * n + 1 points) or a uniform B-spline (bspline 1: n + degree points), each segment
 * converted to a cubic Bezier and added as a CST_SHAPE_CURVE of its own. Widths run
 * linearly from width0 to width1 over the segments by index (as pbrt-v4); a ribbon takes
 * normals[3 * (n + 1)], one per segment end. */
typedef struct CstCurvesDesc {
    const float *points;     /* 3 * num_points */
    int num_points;
    int degree;              /* 2 or 3 */
    int bspline;
    float width0, width1;    /* >= 0, not both 0 */
    CstCurveType type;
    const float *normals;    /* CST_CURVE_RIBBON: 3 * (segments + 1); otherwise unused */
    int split_depth;         /* each segment split into 2^split_depth primitives, 0..10 */
    float world_from_object[12]; /* as CstShapeDesc; all 0: identity */
    int material;
    CstAlpha alpha;
    int reverse_orientation;
} CstCurvesDesc;
/* The number of segments desc's points make, or -1 (with err) if their count does not fit
 * its degree and basis. */
CST_API int cst_curves_segments(const CstCurvesDesc *desc, CstError *err);
CST_API CstStatus cst_scene_add_curves(CstScene *scene, const CstCurvesDesc *desc, CstError *err);


#endif
