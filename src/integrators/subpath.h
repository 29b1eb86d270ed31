/* The subpaths of light-path estimators: the state a subpath carries, with the recursive
 * MIS quantities of Georgiev's technical report ("Implementing Vertex Connection and
 * Merging", 2012); the stored light vertices; BDPT/VCM's light subpaths and their camera
 * subpath walk with the connection strategies (s = 0 emission hits, s = 1 NEE, t = 1 camera
 * connections, vertex connections). The one light subpath walk, which light tracing and
 * the photon passes share with BDPT/VCM, is subpath_walk.h. BDPT is this module alone
 * (bdpt.c); VCM adds merging (vcm.c) through the camera walk's merge hooks. */
#ifndef CST_INTEGRATORS_SUBPATH_H
#define CST_INTEGRATORS_SUBPATH_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "film/film.h"
#include "materials/bsdf.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

typedef struct SubpathParams {
    bool merge;      /* false: BDPT (connections only); true: VCM */
    int max_depth;   /* bounces of a full path, as PathParams; 0 = unbounded */
    int rr_depth;    /* first bounce at which Russian roulette may stop a camera subpath */
    int light_rr_depth; /* the same for a light subpath (bounces from the emitter) */
    SplatFrame frame; /* the film the t = 1 splats are for: its size and pixel filter */
} SubpathParams;

/* A stored light vertex (a non-delta surface hit of a light subpath). The d_* are the
 * recursive MIS quantities of Georgiev's technical report ("Implementing Vertex
 * Connection and Merging", 2012, eqs. 31-38) at this vertex, already powered (mis()). */
typedef struct SubpathVertex {
    Vec3 p, ng;
    Vec3 ns;       /* shading normal (SurfaceHit.ns): y's BSDF is rebuilt from it */
    Vec3 w_prev;   /* unit, toward the previous vertex (where the light came from) */
    Color beta;      /* flux-type throughput: L_e cos / (pdf_a pdf_w) times the BSDF weights */
    float d_vcm, d_vc, d_vm;
    int32_t material;
    int32_t bounces; /* 1 for the first hit after the emitter */
    Vec2 uv;         /* texture coordinates (the BSDF is rebuilt from material, ns, ng, uv) */
    /* Spectral mode: 1 if the light subpath met a dispersive dielectric at or before this
     * vertex (its BSDFs from there on refract the hero wavelength: only beta's lane 0 is
     * right, and every contribution through this vertex keeps the hero alone, as pbrt-v4's
     * TerminateSecondary); 0 otherwise and in RGB mode. */
    int32_t dispersed;
} SubpathVertex;

/* The part of a SubpathVertex that merging reads (48 bytes of its 88): about nine in ten
 * candidates of a query fail the distance test, so the bytes streamed per candidate are
 * most of a merge's cost. */
typedef struct MergeVertex {
    Vec3 p;
    Vec3 w_prev;
    Color beta;
    float d_vcm, d_vm;
    int32_t bounces;
    int32_t dispersed; /* SubpathVertex.dispersed, | MERGE_VOLUME for a vertex in a medium
                        * (ng = 0; only scenes with media have them) */
} MergeVertex;
enum { MERGE_VOLUME = 2 };

/* A growable list of light vertices; one per work unit, reused by every iteration. */
typedef struct SubpathVertexList {
    SubpathVertex *v;
    size_t n, cap;
    int oom;
} SubpathVertexList;

void subpath_vertex_list_free(SubpathVertexList *l);

/* What every light and camera path of one iteration shares. */
typedef struct SubpathIteration {
    int light_paths;     /* light paths this iteration (one per pixel) */
    float radius;        /* merging radius of this iteration */
    float mis_vm, mis_vc; /* mis(eta_vcm), mis(1 / eta_vcm); 0 without merging */
    float vm_norm;       /* 1 / (pi r^2 light_paths) */
    /* The same at a vertex in a participating medium (subpath_media.c): UPBP's point-point
     * 3D estimator (Krivanek et al. 2014, sec. 5) accepts light vertices in a ball, so its
     * eta is (4/3) pi r^3 light_paths; 0 without merging. */
    float mis_vm_vol, mis_vc_vol, vm_norm_vol;
    float pixel_area;    /* one pixel's area on the image plane at distance 1 */
    /* All light vertices of the iteration, path by path, and where each path's start. */
    const SubpathVertex *vertices;
    const uint32_t *path_start; /* light_paths + 1 entries */
    /* Merging: a hashed grid of cell size 2r over `vertices` (empty without merging). */
    const uint32_t *cell_start;     /* cells + 1 entries */
    const MergeVertex *cell_vertices; /* what merging reads of the vertices, cell by
                                          * cell, in vertex order: a query streams through
                                          * a cell's run instead of missing the cache on
                                          * every candidate */
    uint32_t cells;
    Vec3 grid_lo;
    float inv_cell;
    struct Recorder *rec; /* `caustic explain` (recorder.h): the camera path's strategies and
                           * the splats near its pixel; NULL in renders */
} SubpathIteration;

/* The MIS exponent: the power heuristic (Veach eq. 9.13, beta = 2). Applied to every
 * factor of a ratio, which is the same as to the ratio: (ab)^2 = a^2 b^2. */
static inline float mis(float x) { return x * x; }

/* The subpath state between vertices. */
typedef struct SubPath {
    Color beta, scatter; /* throughput; scatter = product of BSDF weights (roulette's input) */
    float d_vcm, d_vc, d_vm; /* MIS quantities: only a walk with a SubpathIteration keeps them */
    bool specular_only;  /* every BSDF sample so far took a delta lobe (photon maps' caustics) */
} SubPath;

/* Traces one light subpath of BDPT/VCM (subpath_walk_light with MIS): appends its
 * non-delta vertices to *verts and splats its connections to the camera (the t = 1
 * strategies, MIS-weighted) to *splats, per unit film as light_trace() does. time: the
 * subpath's instant in the shutter (motion blur; 0 in static scenes), carried by all its
 * rays, the t = 1 shadow rays included: the camera subpaths it is joined with must be at
 * the same instant (integrator.c draws both). Camera subpaths carry their ray's time. */
void subpath_trace_light(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                     Sampler *rng, float time, const Wavelengths *wl, SubpathVertexList *verts,
                     SplatList *splats, uint64_t *rays);

/* A merging query at one camera vertex (vcm.c), in three steps so that its two rounds of
 * cache misses overlap the vertex's NEE and connections instead of stalling the path:
 * which buckets (their bounds prefetched), then where their runs start (the runs
 * prefetched), then the sum. */
typedef struct MergeQuery {
    int nb;
    uint32_t bucket[8];
    uint32_t first[8], last[8];
} MergeQuery;

/* VCM's merging at a camera vertex, as hooks of the one camera walk: plan before NEE,
 * fetch after it, merge after the connections. */
typedef struct SubpathMerge {
    void (*plan)(const SubpathIteration *it, Vec3 p, MergeQuery *q);
    void (*fetch)(const SubpathIteration *it, MergeQuery *q);
    /* Returns the merges with undispersed light vertices; those with dispersed ones (only
     * their lane 0 is right) go to *hero. */
    Color (*merge)(const SubpathParams *vp, const SubpathIteration *it, const MergeQuery *q, const SubPath *sp,
                   const Bsdf *bx, const SurfaceHit *x, Vec3 wo, int bounces, Color *hero);
} SubpathMerge;

/* One camera subpath for the pixel whose light path is `path`: emission hits (s = 0),
 * NEE (s = 1), connections to the light path's vertices, and with `merge` (NULL: none;
 * used only when the iteration has a grid), merges with every light vertex within the
 * radius; all MIS-weighted. Returns the pixel sample. Spectral mode: both subpaths carry
 * wl; a contribution through a dispersive refraction on either subpath keeps the hero
 * wavelength alone (lane 0 times 4, the others 0: what wl's termination would give through
 * spectrum_to_rgb), the others all four, so the caller converts the sum with wl as is. */
Color subpath_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                           Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays, const SubpathMerge *merge);

/* ---- Single strategies, for multiplexed MLT (mlt.c; Hachisuka, Kaplanyan & Dachsbacher
 * 2014, as pbrt-v4's MLTIntegrator): one strategy (s, t) of one path length, its subpaths
 * walked to exactly the vertices it needs, each from its own sampler stream, and its
 * contribution with the same MIS weight as BDPT gives it (the walks and connections are
 * the ones above). pbrt's counts: t camera vertices with the camera, s light vertices with
 * the one on the emitter, s + t - 2 bounces. */

/* The last vertex of a camera subpath, kept for its connection. */
typedef struct SubpathCameraVertex {
    SurfaceHit sh;
    Bsdf bsdf;
    Vec3 wo;        /* unit, back along the camera subpath */
    SubPath sp;     /* on arrival (beta: the throughput reaching it) */
    bool dispersed; /* spectral: a dispersive refraction on the way (hero wavelength only) */
} SubpathCameraVertex;

/* Walks the camera subpath of `ray` to its hit number `hits` (>= 1). emission (the s = 0
 * strategy): returns false and sets *emitted to the MIS-weighted emission, times beta,
 * that the path finds there (an emitter hit, or the environment if it escapes after hits - 1
 * bounces). Otherwise true with *out that vertex when it exists and is not purely delta
 * (false, *emitted 0, when it does not). Spectral: *emitted keeps the hero alone after a
 * dispersive refraction (as subpath_trace_camera). */
bool subpath_camera_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                           Ray ray, int hits, bool emission, Sampler *rng, const Wavelengths *wl,
                           SubpathCameraVertex *out, Color *emitted, uint64_t *rays);
/* Walks a light subpath to its vertex `bounces` (>= 1), as subpath_trace_light's walk does
 * (no t = 1 splats), every ray at `time` (the path's: motion blur). True with *out when
 * that vertex exists and is not purely delta. Spectral: *walk_wl is the walk's copy of wl
 * (terminated by a dispersive refraction). */
bool subpath_light_vertex(const Scene *s, const SubpathParams *vp, const SubpathIteration *it, int bounces,
                          Sampler *rng, float time, const Wavelengths *wl, SubpathVertex *out, Wavelengths *walk_wl,
                          uint64_t *rays);
/* s = 1: NEE from x (1D + 2D of rng), MIS-weighted, times x's beta. */
Color subpath_connect_light(const Scene *s, const SubpathIteration *it, const SubpathCameraVertex *x, Sampler *rng,
                            const Wavelengths *wl, uint64_t *rays);
/* s >= 2, t >= 2: x connected to light vertex y, MIS-weighted, times x's beta. */
Color subpath_connect_pair(const Scene *s, const SubpathIteration *it, const SubpathCameraVertex *x,
                           const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays);
/* t = 1: y connected to a lens point (u_lens), MIS-weighted: true with the film position
 * and the splat's RGB (per unit film, as subpath_trace_light splats it; walk_wl: y's walk's
 * wavelengths, NULL in RGB mode). time: y's subpath's (the shadow ray's instant). */
bool subpath_connect_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                            const SubpathVertex *y, Vec2 u_lens, float time, const Wavelengths *wl,
                            const Wavelengths *walk_wl, Vec2 *raster, Color *rgb, uint64_t *rays);
/* Spectral: a contribution through a dispersive refraction, the hero wavelength alone (lane
 * 0 times 4, the others 0), as subpath_trace_camera counts it. */
static inline Color subpath_hero_only(Color c)
{
    Color h = color_s(0.0f);
    h.c[0] = c.c[0] * (float)COLOR_LANES;
    return h;
}

#endif
