/* Loop subdivision surfaces (C. Loop, "Smooth Subdivision Surfaces Based on Triangles",
 * 1987): a triangle control mesh refined `levels` times and pushed to the limit surface,
 * with limit normals, as pbrt-v4's `loopsubdiv` shape. */
#ifndef CST_GEOMETRY_LOOP_SUBDIV_H
#define CST_GEOMETRY_LOOP_SUBDIV_H

#include <stdint.h>

#include "core/error.h"
#include "math/vec3.h"

/* A refined mesh: positions on the limit surface, one limit normal per vertex (unit, or
 * zero where the tangents degenerate) and 3 indices per triangle. The first nv vertices of
 * the control mesh keep their indices; each triangle keeps its control triangle's winding.
 * The normals point as pbrt-v4's do: against the winding's normal (v1 - v0) x (v2 - v0)
 * of a consistently wound mesh (pbrt-v4 then turns the triangles to face them). */
typedef struct LoopMesh {
    Vec3 *p;
    Vec3 *n;
    int nv;
    int *idx;
    int nt;
} LoopMesh;

/* Triangles after `levels` refinements of nt triangles (nt * 4^levels), or -1 beyond
 * INT32_MAX / 3. */
int64_t loop_triangle_count(int nt, int levels);

/* Refines the control mesh p[nv], idx[3 nt] (indices in [0, nv)) `levels` >= 0 times
 * and pushes it to the limit. The mesh must be manifold: a face with a repeated vertex,
 * an edge shared by more than two faces, or a vertex whose faces form more than one fan
 * fails with CST_ERR_INVALID_ARG and a message naming the face, edge or vertex (orientation
 * need not be consistent). Vertices no face uses stay where they are, with a zero normal.
 * Returns CST_ERR_UNSUPPORTED when the result would exceed loop_triangle_count's bound,
 * CST_ERR_OOM. On success *out owns new arrays: loop_mesh_free(). */
CstStatus loop_subdivide(const Vec3 *p, int nv, const int *idx, int nt, int levels, LoopMesh *out,
                         CstError *err);

/* Frees m's arrays; accepts a zeroed mesh. */
void loop_mesh_free(LoopMesh *m);

#endif
