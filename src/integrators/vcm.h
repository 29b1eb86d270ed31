/* Bidirectional path tracing and vertex connection and merging (Georgiev et al., "Light
 * Transport Simulation with Vertex Connection and Merging", SIGGRAPH Asia 2012): one
 * estimator, with merging switched off for BDPT. Each iteration traces one light path per
 * pixel, then one camera path per pixel that connects to "its" light path (same index)
 * and, for VCM, merges with the light vertices of every light path near its vertices. */
#ifndef CST_INTEGRATORS_VCM_H
#define CST_INTEGRATORS_VCM_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "film/film.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

typedef struct VcmParams {
    bool merge;      /* false: BDPT (connections only); true: VCM */
    int max_depth;   /* bounces of a full path, as PathParams; 0 = unbounded */
    int rr_depth;    /* first bounce at which Russian roulette may stop a subpath */
    SplatFrame frame; /* the film the t = 1 splats are for: its size and pixel filter */
} VcmParams;

/* A stored light vertex (a non-delta surface hit of a light subpath). The d_* are the
 * recursive MIS quantities of Georgiev's technical report ("Implementing Vertex
 * Connection and Merging", 2012, eqs. 31-38) at this vertex, already powered (mis()). */
typedef struct VcmVertex {
    Vec3 p, ng;
    Vec3 ns;       /* shading normal (SurfaceHit.ns): y's BSDF is rebuilt from it */
    Vec3 w_prev;   /* unit, toward the previous vertex (where the light came from) */
    Color beta;      /* flux-type throughput: L_e cos / (pdf_a pdf_w) times the BSDF weights */
    float d_vcm, d_vc, d_vm;
    int32_t material;
    int32_t bounces; /* 1 for the first hit after the emitter */
    Vec2 uv;         /* texture coordinates (the BSDF is rebuilt from material, ns, ng, uv) */
} VcmVertex;

/* The part of a VcmVertex that merging reads (48 bytes of its 88): about nine in ten
 * candidates of a query fail the distance test, so the bytes streamed per candidate are
 * most of a merge's cost. */
typedef struct VcmMergeVertex {
    Vec3 p;
    Vec3 w_prev;
    Color beta;
    float d_vcm, d_vm;
    int32_t bounces;
} VcmMergeVertex;

/* A growable list of light vertices; one per work unit, reused by every iteration. */
typedef struct VcmVertexList {
    VcmVertex *v;
    size_t n, cap;
    int oom;
} VcmVertexList;

void vcm_vertex_list_free(VcmVertexList *l);

/* What every light and camera path of one iteration shares. */
typedef struct VcmIteration {
    int light_paths;     /* light paths this iteration (one per pixel) */
    float radius;        /* merging radius of this iteration */
    float mis_vm, mis_vc; /* mis(eta_vcm), mis(1 / eta_vcm); 0 without merging */
    float vm_norm;       /* 1 / (pi r^2 light_paths) */
    float pixel_area;    /* one pixel's area on the image plane at distance 1 */
    /* All light vertices of the iteration, path by path, and where each path's start. */
    const VcmVertex *vertices;
    const uint32_t *path_start; /* light_paths + 1 entries */
    /* Merging: a hashed grid of cell size 2r over `vertices` (empty without merging). */
    const uint32_t *cell_start;     /* cells + 1 entries */
    const VcmMergeVertex *cell_vertices; /* what merging reads of the vertices, cell by
                                          * cell, in vertex order: a query streams through
                                          * a cell's run instead of missing the cache on
                                          * every candidate */
    uint32_t cells;
    Vec3 grid_lo;
    float inv_cell;
} VcmIteration;

/* Sets everything but the vertex and grid arrays for iteration `index` (0-based): the
 * radius shrinks as r0 (index + 1)^((alpha - 1) / 2), alpha = 3/4 (Knaus and Zwicker
 * 2011, as SmallVCM does), so merging's bias vanishes as iterations grow. */
void vcm_iteration_init(VcmIteration *it, const VcmParams *vp, const Camera *cam, int light_paths,
                        float base_radius, int index);

/* Traces one light subpath: appends its non-delta vertices to *verts and splats its
 * connections to the camera (the t = 1 strategies, MIS-weighted) to *splats, per unit
 * film as light_trace() does. */
void vcm_trace_light(const Scene *s, const Camera *cam, const VcmParams *vp, const VcmIteration *it,
                     Sampler *rng, VcmVertexList *verts, SplatList *splats, uint64_t *rays);

/* The merging grid over it->vertices, a hashed grid of cells 2r wide from lo (the lowest
 * corner of the vertices), sorted into `cells` buckets of caller-owned arrays: cell_start
 * (cells + 1 entries) and cell_vertices (one per vertex). Built in steps that threads can
 * share: vcm_grid_cell gives every vertex's bucket (cell_of[i]); the buckets are cut into
 * `ranges` ranges, and vcm_grid_count counts range r (returning its vertices); once every
 * range is counted, vcm_grid_bases turns the per-range counts into each range's first
 * index (returning the total), and vcm_grid_fill sorts range r from there. Any number of
 * ranges gives the same grid. */
void vcm_grid_init(VcmIteration *it, Vec3 lo, uint32_t cells, uint32_t *cell_start, VcmMergeVertex *cell_vertices);
uint32_t vcm_grid_cell(const VcmIteration *it, Vec3 p);
uint32_t vcm_grid_count(const VcmIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges,
                        uint32_t *cell_start);
uint32_t vcm_grid_bases(uint32_t *per_range, int ranges);
void vcm_grid_fill(const VcmIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges, uint32_t base,
                   uint32_t *cell_start, VcmMergeVertex *cell_vertices);

/* One camera path for the pixel whose light path is `path`: emission hits (s = 0), NEE
 * (s = 1), connections to the light path's vertices, and with merging, merges with every
 * light vertex within the radius; all MIS-weighted. Returns the pixel sample. */
Color vcm_trace_camera(const Scene *s, const Camera *cam, const VcmParams *vp, const VcmIteration *it,
                     int path, Ray ray, Sampler *rng, uint64_t *rays);

/* A merging radius from the scene's size: the base radius r0 when none is given. */
float vcm_default_radius(const Scene *s);

#endif
