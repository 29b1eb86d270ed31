/* Uniform grid over triangles and spheres: about 27 cells per primitive, near-cubic cells,
 * primitives stored per occupied cell in compressed sparse rows, 3D-DDA traversal
 * (Amanatides & Woo, "A Fast Voxel Traversal Algorithm for Ray Tracing", Eurographics
 * 1987) that crosses empty space a brick of 64 cells (or a cube of empty bricks) at a
 * time, a small per-ray hashed mailbox so a primitive spanning several cells is (almost
 * always) tested once per ray, and a cell's untested triangles tested four at a time
 * with SSE. Read-only after grid_build: any number of threads may traverse it. Hits are
 * bit-identical to the list back end's (see grid.c for the one exception, ill-conditioned
 * grazing hits). */
#ifndef CST_ACCEL_GRID_H
#define CST_ACCEL_GRID_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "accel/accel_geometry.h"
#include "caustic/caustic.h"
#include "geometry/hit.h"
#include "geometry/ray.h"
#include "geometry/triangle_block.h"
#include "math/bbox.h"

/* A triangle's own vertices, as triangle_intersect_watertight() takes them (the same
 * floats the list back end tests, so hits are bit-identical). */
typedef TriVerts GridTri; /* geometry/triangle_block.h: the vertices and the scene primitive id */

typedef struct GridSphere {
    Vec3 center;
    float radius;
    uint32_t id; /* scene primitive id */
} GridSphere;

/* An empty brick's Grid.brick_info is at most this: the bricks farther away than that
 * are not looked at (grid_build). */
#define GRID_BRICK_REACH 16

/* Cells are numbered in bricks of 64, 4 x 4 x 4: with (bx, by, bz) =
 * (x >> 2, y >> 2, z >> 2) and (lx, ly, lz) the low bits, cell (x, y, z) is number
 * 64 * brick + lx + 4 ly + 16 lz, brick = bx + brick_res[0] * (by + brick_res[1] * bz).
 * Neighbouring cells are then neighbours in memory on all three axes (a ray's cells share
 * cache lines of offsets and slots), a brick's 64 occupancy bits are one word (an empty
 * brick is a zero word), and the traversal finds the cells a ray crosses in a brick from
 * three 4 x 4 tables (grid.c). Cells of the last bricks past res are padding (empty,
 * never visited); a flat grid pads its bricks to 4 cells deep, at one bit per cell.
 *
 * The occupied cells, in cell order, have their primitives in compressed sparse rows: the
 * k-th occupied cell's are slots[list_start[k] .. list_start[k + 1]), and k is its
 * brick's `first` plus the number of occupied cells before it in the brick (a popcount):
 * with ~97% of cells empty on a surface mesh, offsets for occupied cells alone are a
 * thirtieth of the size of one offset per cell, and stay in cache. A slot holds a
 * grid-local index: below num_tris it is tris[slot],
 * below num_tris + num_spheres spheres[slot - num_tris], otherwise the analytic shape
 * shapes[shape_ids[slot - num_tris - num_spheres] - shape_base]. The grid keeps its own copies of the primitives,
 * in Morton order of their box centres, so the primitives of one cell sit together in
 * memory. The cell geometry is kept in double so the traversal's cell boundaries are
 * exact to far below the build margin (see grid.c). */
typedef struct Grid {
    int res[3];             /* cells per axis, each >= 1 */
    int brick_res[3];       /* bricks per axis: ceil(res / 4) */
    int num_cells;          /* 64 per brick, padding included; 0 for an empty grid */
    double org[3];          /* minimum corner of the grid */
    double cell_size[3];    /* per axis */
    double inv_cell_size[3];
    BBox bounds;            /* float copy of the grid box (primitive boxes plus the margin) */
    float margin;           /* every primitive is in every cell it comes within `margin` of */
    /* Per brick: occupancy, bit c % 64 of word c / 64 (1 bit per cell, so an empty cell
     * costs no memory trip); and in brick_info, for an occupied brick the index in
     * list_start of its first occupied cell, for an empty one its distance D to the
     * nearest occupied brick in bricks along the farthest axis (Chebyshev), at most
     * GRID_BRICK_REACH: every brick within D - 1 of it is empty too, and a ray crosses
     * that cube of bricks in one step. */
    uint64_t *cell_bits;
    uint32_t *brick_info;
    uint32_t *list_start;   /* num_occupied + 1 offsets into slots */
    int num_occupied;
    uint32_t *slots;        /* num_refs grid-local primitive indices */
    size_t num_refs;
    GridTri *tris;
    int num_tris;
    GridSphere *spheres;
    int num_spheres;
    const AnalyticShape *shapes; /* borrowed from the AccelGeometry */
    uint32_t *shape_ids;         /* scene ids of the shapes, in grid-local order */
    int num_shapes;
    uint32_t shape_base;         /* shape k has id shape_base + k */
} Grid;

/* Zero primitives is valid (every ray misses). Copies what it needs from geom; returns
 * CST_ERR_OOM (and leaves a freed grid) when memory runs out. */
CstStatus grid_build(Grid *a, const AccelGeometry *geom, CstError *err);
/* Accepts NULL and a zeroed or already freed grid. */
void grid_free(Grid *a);
/* Closest hit in (r.t_min, r.t_max). */
bool grid_intersect(const Grid *a, const Ray *r, Hit *hit);
/* Any hit in (r.t_min, r.t_max). */
bool grid_occluded(const Grid *a, const Ray *r);
/* Bricks, list offsets, the slot array and the grid's copies of the primitives. */
size_t grid_memory_bytes(const Grid *a);

#endif
