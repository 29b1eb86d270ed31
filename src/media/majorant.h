/* The coarse majorant grid of a heterogeneous medium (a bound on the density per cell of
 * the medium's unit cube, pbrt-v4's MajorantGrid) and the 3-D DDA that walks a ray through
 * its cells (Amanatides & Woo 1987, "A fast voxel traversal algorithm for ray tracing"). */
#ifndef CST_MEDIA_MAJORANT_H
#define CST_MEDIA_MAJORANT_H

#include <stdbool.h>

#include "math/vec3.h"

/* res[0] x res[1] x res[2] cells over [0,1]^3, x fastest; max[i] >= the density anywhere in
 * cell i (dimensionless: the density multiplies the medium's sigma_t). Owns max. */
typedef struct MajorantGrid {
    int res[3];
    float *max;
} MajorantGrid;

/* A ray's walk through the grid, cell by cell, in increasing t. */
typedef struct MajorantDda {
    const MajorantGrid *g;
    float t, t_end;         /* entry of the current cell, end of the walk */
    float next_t[3], dt[3]; /* t of the next crossing per axis, t between crossings */
    int cell[3], step[3], limit[3];
} MajorantDda;

/* One cell's piece of the ray: t in [t0, t1), density bound maj, cell index. */
typedef struct MajorantSeg {
    float t0, t1, maj;
    int cell[3];
} MajorantSeg;

/* Starts the walk of o + t d (o, d in the grid's unit-cube coordinates; d need not be
 * unit length) over [t0, t1], an interval already clipped to [0,1]^3 (majorant_clip). */
void majorant_dda_init(MajorantDda *it, const MajorantGrid *g, Vec3 o, Vec3 d, float t0, float t1);
/* The next cell's segment; false when the walk has reached t_end. Segments are
 * contiguous: each t0 is the previous t1. */
bool majorant_dda_next(MajorantDda *it, MajorantSeg *seg);

/* The part of o + t d, t in [t0, t1], inside the box [lo, hi] (slab test); false when
 * none of positive length. */
bool majorant_clip(Vec3 o, Vec3 d, Vec3 lo, Vec3 hi, float t0, float t1, float *out0, float *out1);

#endif
