/* Object instancing as a two-level acceleration structure: prototypes (triangle meshes and
 * analytic shapes, each prototype with its own BVH built once, in object space) placed by
 * instances (an affine transform, or two for a moving one, and a prototype id) under a
 * top-level BVH over the instances' world bounds. Memory is one copy of each prototype plus
 * a fixed record per instance. */
#ifndef CST_ACCEL_INSTANCES_H
#define CST_ACCEL_INSTANCES_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "accel/accel.h"
#include "caustic/caustic.h"
#include "geometry/shape.h"
#include "math/motion.h"
#include "math/transform.h"

typedef struct InstProto {
    Vec3 *positions;
    int num_positions;
    Vec3 *normals;        /* unit vertex normals, object space (zero = none), or NULL */
    int32_t *tri_indices; /* 3 per triangle */
    int32_t *tri_material; /* scene material id per triangle */
    /* Texture coordinates per position (object space meshes keep theirs: textured leaves),
     * or NULL: every triangle's barycentric default (triangle_uv). */
    Vec2 *uvs;
    /* Per triangle, the scene's alpha cut-out id (Scene.alphas, 1-based; 0 opaque), or
     * NULL when no triangle has one: only then do hits inside instances pay the test. */
    int32_t *tri_alpha;
    Vec3 *tri_normals;     /* unit, object space, (v1-v0) x (v2-v0); made by instances_build */
    int num_triangles;
    /* Analytic shapes (geometry/shape.h: spheres, cylinders, disks, tori, patches, curves,
     * SDFs) in object space, prototype primitive ids num_triangles + k: pbrt-v4's
     * AnimatedPrimitive over a Sphere is a moving instance of an object holding one. Per
     * shape its scene material and alpha cut-out id (0 opaque). Owned: shape_release. */
    AnalyticShape *shapes;
    int32_t *shape_material, *shape_alpha;
    int num_shapes; size_t cap_shapes;
    Accel accel;           /* BVH over the prototype's triangles, object space */
} InstProto;

typedef struct Instance {
    Transform world_from_obj, obj_from_world;
    Transform normal_matrix; /* of world_from_obj: normals keep the object's outside */
    BBox bounds;             /* world space; of a moving instance, over its whole motion */
    int32_t proto;
    int32_t motion;          /* index into InstanceSet.motions, or -1: static (the three
                              * transforms above hold at every time) */
} Instance;

/* Top-level node: an inner node's children are nodes[first] and nodes[first + 1]; a leaf
 * (count > 0) holds order[first .. first + count). */
typedef struct InstNode {
    BBox box;
    int32_t first, count;
} InstNode;

typedef struct InstanceSet {
    InstProto *protos;
    int num_protos; size_t cap_protos;
    Instance *insts;
    int num_insts; size_t cap_insts;
    InstNode *nodes;
    int num_nodes;
    int32_t *order;
    int built;
    /* Moving instances' transforms (motion blur): world_from_obj at shutter open and
     * close, placed at each ray's time (Ray.time). */
    MotionTransform *motions;
    int num_motions; size_t cap_motions;
} InstanceSet;

/* A hit inside an instance: t along the world ray, barycentrics and triangle of the
 * prototype (or a shape's (u, v) and num_triangles + its index); t_obj the same hit's t
 * along the object-space ray (instances_object_ray), which shape_surface takes. */
typedef struct InstHit {
    float t, u, v, t_obj;
    uint32_t prim; /* triangle of the prototype, or num_triangles + shape */
    int32_t inst;
} InstHit;

/* Copies the mesh (triangles must be non-degenerate; material ids are the scene's);
 * normals (per position, unit or zero) may be NULL. */
CstStatus instances_add_proto(InstanceSet *set, const Vec3 *positions, const Vec3 *normals,
                              int num_positions, const int *indices, const int *tri_material,
                              int num_triangles, int *out_id, CstError *err);
/* Gives prototype `proto` (not yet built) texture coordinates (num_positions of them, or
 * NULL) and per-triangle alpha ids (num_triangles, or NULL; all zero keeps none). Copied. */
CstStatus instances_proto_set_surface(InstanceSet *set, int proto, const Vec2 *uvs, const int *tri_alpha,
                                      CstError *err);
/* Adds a copy of shape (in the prototype's object space; its SDF tree, if any, passes to the
 * prototype) to prototype `proto`, not yet built, with scene material and alpha ids. */
CstStatus instances_proto_add_shape(InstanceSet *set, int proto, const AnalyticShape *shape, int material, int alpha,
                                    CstError *err);
/* Removes the last prototype added (no instance may place it yet): a builder's undo. */
void instances_pop_proto(InstanceSet *set);
/* world_from_obj must be affine and invertible. */
CstStatus instances_add(InstanceSet *set, int proto, const Transform *world_from_obj, CstError *err);
/* A moving instance: world_from_obj at shutter open (start) and close (end), each affine
 * and invertible, interpolated by decomposition (math/motion.h). start == end adds a
 * static instance. */
CstStatus instances_add_moving(InstanceSet *set, int proto, const Transform *start, const Transform *end,
                               CstError *err);
/* Instance `inst`'s world_from_obj and normal matrix at time (static: its own). */
void instances_placement(const InstanceSet *set, int inst, float time, Transform *world_from_obj,
                         Transform *normal_matrix);
/* A moving instance's rest frame (photon.c: photons on moving geometry are stored where
 * they would be with the instance at its start placement, so that a point of the surface
 * keeps its photons while the surface moves). False for a static instance (nothing set);
 * else rest_from_world = W(0) W(time)^-1, its inverse and its normal matrix, W(t) the
 * instance's world_from_obj at t. Also false when a placement is singular. */
bool instances_rest_frame(const InstanceSet *set, int inst, float time, Transform *rest_from_world,
                          Transform *world_from_rest, Transform *normal_matrix);
/* Builds every prototype's BVH and the top-level tree; call once, after the last add. */
CstStatus instances_build(InstanceSet *set, CstError *err);
/* Accepts a zeroed set; frees what the set owns, not the set itself. */
void instances_free(InstanceSet *set);
/* Prototype geometry and BVHs, the instance records and the top-level tree. */
size_t instances_memory_bytes(const InstanceSet *set);
/* Closest hit in (ray->t_min, ray->t_max); ray->d unit length; moving instances placed at
 * ray->time. */
bool instances_intersect(const InstanceSet *set, const Ray *ray, InstHit *hit);
/* The ray in instance `inst`'s object space (placed at ray->time), unit direction, as the
 * traversal makes it; *scale = object t per world t (0: no placement at that time). */
Ray instances_object_ray(const InstanceSet *set, int inst, const Ray *ray, float *scale);
bool instances_occluded(const InstanceSet *set, const Ray *ray);

#endif
