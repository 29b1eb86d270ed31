/* Vertex connection and merging (Georgiev et al., "Light Transport Simulation with Vertex
 * Connection and Merging", SIGGRAPH Asia 2012): BDPT's subpaths (subpath.h) plus merging.
 * Each iteration traces one light path per pixel (subpath_trace_light), then one camera
 * path per pixel that connects to "its" light path (same index) and merges with the light
 * vertices of every light path near its vertices, through a hashed grid. The iteration
 * setup is shared with BDPT (merging off: vp->merge false). */
#ifndef CST_INTEGRATORS_VCM_H
#define CST_INTEGRATORS_VCM_H

#include <stdbool.h>
#include <stdint.h>

#include "integrators/subpath.h"

/* Sets everything but the vertex and grid arrays for iteration `index` (0-based): the
 * radius shrinks as r0 (index + 1)^((alpha - 1) / 2), alpha = 3/4 (Knaus and Zwicker
 * 2011, as SmallVCM does), so merging's bias vanishes as iterations grow. */
void vcm_iteration_init(SubpathIteration *it, const SubpathParams *vp, const Camera *cam, int light_paths,
                        float base_radius, int index);

/* The merging grid over it->vertices, a hashed grid of cells 2r wide from lo (the lowest
 * corner of the vertices), sorted into `cells` buckets of caller-owned arrays: cell_start
 * (cells + 1 entries) and cell_vertices (one per vertex). Built in steps that threads can
 * share: vcm_grid_cell gives every vertex's bucket (cell_of[i]); the buckets are cut into
 * `ranges` ranges, and vcm_grid_count counts range r (returning its vertices); once every
 * range is counted, vcm_grid_bases turns the per-range counts into each range's first
 * index (returning the total), and vcm_grid_fill sorts range r from there. Any number of
 * ranges gives the same grid. */
void vcm_grid_init(SubpathIteration *it, Vec3 lo, uint32_t cells, uint32_t *cell_start, MergeVertex *cell_vertices);
uint32_t vcm_grid_cell(const SubpathIteration *it, Vec3 p);
uint32_t vcm_grid_count(const SubpathIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges,
                        uint32_t *cell_start);
uint32_t vcm_grid_bases(uint32_t *per_range, int ranges);
void vcm_grid_fill(const SubpathIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges, uint32_t base,
                   uint32_t *cell_start, MergeVertex *cell_vertices);

/* One camera path for the pixel whose light path is `path`: emission hits (s = 0), NEE
 * (s = 1), connections to the light path's vertices, and merges with every light vertex
 * within the radius; all MIS-weighted. Returns the pixel sample. */
Color vcm_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                       Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays);

/* A merging radius from the scene's size: the base radius r0 when none is given. */
float vcm_default_radius(const Scene *s);

#endif

