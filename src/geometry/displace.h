/* True displacement of triangle meshes (pbrt-v4's TriQuadMesh::Displace, for plymesh
 * "displacement" and "edgelength"): tessellation by edge length, then each vertex moved
 * along its normal by a displacement function, then normals recomputed. */
#ifndef CST_GEOMETRY_DISPLACE_H
#define CST_GEOMETRY_DISPLACE_H

#include <stdint.h>

#include "core/error.h"
#include "math/transform.h"
#include "math/vec3.h"

/* The displacement at a vertex, in the mesh's units along its unit normal: (object-space)
 * position, unit normal (zero where a vertex has none) and texture coordinates ((0, 0)
 * without uvs). Called once per vertex of the tessellated mesh, in vertex order. */
typedef float (*DisplaceFn)(void *user, Vec3 p, Vec3 n, Vec2 uv);

typedef struct DisplaceInput {
    const Vec3 *p;   /* nv positions (object space), finite */
    const Vec3 *n;   /* optional nv unit (or zero) normals; NULL: computed as pbrt-v4 does */
    const Vec2 *uv;  /* optional nv texture coordinates */
    int nv;
    const int *idx;  /* 3 nt indices in [0, nv) */
    int nt;
    const Transform *measure; /* where edges are measured (pbrt-v4: render from object); NULL: as given */
    float edge_length;        /* > 0; +inf: no tessellation */
    int64_t max_triangles;    /* the most triangles the result may have, <= INT32_MAX / 3 */
    DisplaceFn fn;
    void *user;
} DisplaceInput;

/* The result: the input's vertices first (same indices), then one per split edge; one
 * parent (input triangle) per triangle; normals unit, or zero at vertices whose triangles
 * all degenerate; uv NULL when the input had none. */
typedef struct DisplacedMesh {
    Vec3 *p, *n;
    Vec2 *uv;
    int nv;
    int *idx;
    int *parent;
    int nt;
} DisplacedMesh;

/* Splits every edge whose measured length is not below edge_length at its midpoint
 * (position, uv and the normalised sum of the normals interpolated), repeatedly, as
 * pbrt-v4's TriQuadMesh::Refine: each triangle bisects its longest edge (ties broken by
 * its vertex order, as pbrt-v4) until all three are shorter. Whether and where an edge
 * splits depends on that edge alone and a split edge's midpoint is one vertex for both of
 * its triangles, so a closed mesh stays closed (no T-junctions, no cracks). Then
 * p += fn(p, n, uv) n at every vertex and the normals are recomputed from the displaced
 * triangles (the normalised sum of their unit face normals, pbrt-v4's ComputeNormals).
 * Fails with CST_ERR_INVALID_ARG for a bad edge_length or a displaced position that is
 * not finite, CST_ERR_UNSUPPORTED when the tessellation would exceed max_triangles: at
 * once when the measured area or edge lengths alone need more (each piece is smaller than
 * the equilateral triangle of side edge_length; an edge of length E ends in more than
 * E / edge_length pieces, at most 3 in each output triangle), else before the triangle
 * that would exceed it (memory and time stay bounded: at most max_triangles triangles and
 * as many new vertices are made), CST_ERR_OOM. On success *out owns new arrays: displaced_mesh_free(). */
CstStatus displace_mesh(const DisplaceInput *in, DisplacedMesh *out, CstError *err);

/* Frees m's arrays; accepts a zeroed mesh. */
void displaced_mesh_free(DisplacedMesh *m);

/* pbrt-v4's TriQuadMesh::ComputeNormals: n[i] = the normalised sum of the unit normals
 * (v1 - v0) x (v2 - v1) of the triangles using vertex i, zero where there are none. */
void displace_vertex_normals(const Vec3 *p, int nv, const int *idx, int nt, Vec3 *n);

#endif
