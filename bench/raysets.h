/* The ray sets of the acceleration benchmark (/work/shared/bench/RAYSETS.md): the scenes
 * (Cornell box, PLY meshes, a teapot in a stadium), bit-exact generation of the primary,
 * secondary and occlusion rays, multithreaded tracing whose checksums do not depend on the
 * thread count, and the published reference checksums. Used by `caustic bench rays` and
 * tests/unit/test_raysets.c. */
#ifndef CST_BENCH_RAYSETS_H
#define CST_BENCH_RAYSETS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>

#include "accel/accel.h"
#include "caustic/caustic.h"
#include "geometry/ray.h"
#include "math/vec3.h"

/* A pinhole camera exactly as RAYSETS.md defines it, in double. */
typedef struct RaysetCamera {
    double eye[3], look[3], up[3];
    double vfov_deg; /* vertical field of view, degrees */
    int width, height;
} RaysetCamera;

/* Triangles only: primitive id = index in tri_indices / 3, as in the file. */
typedef struct RaysetScene {
    char name[64];    /* "cornell", "bunny", "stadium+bunny", ... */
    Vec3 *positions;  /* owned */
    int num_positions;
    int32_t *tri_indices; /* owned, 3 per triangle */
    int num_tris;
    RaysetCamera camera;
    double diag; /* secondary origins move 1e-4 diag off the surface */
} RaysetScene;

/* The built-in Cornell box (cst_scene_create_cornell_box's 32 triangles in order). */
CstStatus rayset_scene_cornell(RaysetScene *out, CstError *err);
/* A mesh through mesh_import(); name = the file's stem. Camera and diag from the bbox of
 * the triangles' vertices (RAYSETS.md "Meshes"). Degenerate triangles are kept. */
CstStatus rayset_scene_mesh(const char *path, RaysetScene *out, CstError *err);
/* A built-in dense mesh: the bumpysphere definition of /work/shared/meshes/README.md with
 * `levels` subdivisions instead of 8 (levels 5: 20,480 triangles), mesh camera. */
CstStatus rayset_scene_bumpy_ball(int levels, RaysetScene *out, CstError *err);
/* Teapot in a stadium: appends 12 triangles, an axis-aligned box of half-size
 * RAYSET_STADIUM_SCALE * diag around the scene, keeping the scene's camera and diag, so
 * the rays stay those of the small dense "teapot" and escape rays hit the far walls.
 * 50 diagonals: a box 10^6 times the teapot's bounding volume, yet wall coordinates keep
 * ~20 ulps of room for the 1e-4 diag offset of bounce rays leaving a wall (at 500 it was
 * 3 ulps, and a few hundred wall bounces re-hit their own wall in one back end only). */
#define RAYSET_STADIUM_SCALE 50.0
CstStatus rayset_scene_add_stadium(RaysetScene *s, CstError *err);
void rayset_scene_free(RaysetScene *s);

static inline AccelGeometry rayset_scene_geometry(const RaysetScene *s)
{
    AccelGeometry g = {s->positions, s->tri_indices, s->num_tris, NULL, 0, NULL, 0};
    return g;
}

/* One traced ray: prim == RAYSET_MISS for no hit; t is meaningless for any-hit queries. */
#define RAYSET_MISS UINT32_MAX
typedef struct RaysetResult {
    float t;
    uint32_t prim;
} RaysetResult;

/* width * height primary rays, index py * width + px. Returns NULL on OOM; free(). */
Ray *rayset_primary(const RaysetScene *s, size_t *count);
/* One bounce ray per primary hit, in increasing ray index (RAYSETS.md "Secondary").
 * hits[i] is primary[i]'s closest hit. Returns NULL on OOM (with *count = 0); free(). */
Ray *rayset_secondary(const RaysetScene *s, const Ray *primary, const RaysetResult *hits,
                      size_t num_primary, size_t *count);
/* The secondary rays with t_max = 1e30 (any-hit). Returns NULL on OOM; free(). */
Ray *rayset_occlusion(const Ray *secondary, size_t count);

typedef enum RaysetQuery { RAYSET_CLOSEST, RAYSET_ANY } RaysetQuery;
#define RAYSET_MAX_THREADS 1024

typedef struct RaysetStats {
    size_t rays, hits;
    double sum_t;      /* sum of float t over hits, in double, in ray order; 0 for any-hit */
    uint64_t sum_prim; /* sum of hit primitive ids; 0 for any-hit */
    float max_t;       /* largest hit t; 0 for any-hit */
    double seconds;    /* wall time of the tracing alone (CLOCK_MONOTONIC) */
} RaysetStats;

/* Traces rays[0..n) with `threads` threads (1 = the calling thread alone). Threads take
 * chunks of rays from an atomic counter and write each ray's result to its own slot of
 * `out` (n entries, or NULL for an internal buffer); the checksums are then reduced in ray
 * order, so they are identical for every thread count. */
CstStatus rayset_trace(const Accel *a, const Ray *rays, size_t n, RaysetQuery query, int threads,
                       RaysetResult *out, RaysetStats *st, CstError *err);

/* A row of RAYSETS.md's reference table. */
typedef struct RaysetReference {
    const char *scene; /* "bunny", "dragon", "bumpysphere", "cornell" */
    int num_tris;      /* the scene must have exactly this many triangles */
    size_t primary_hits;
    double primary_sum_t;
    size_t secondary_rays;
    size_t secondary_hits; /* also the occluded count */
    double secondary_sum_t;
} RaysetReference;

/* The row for this scene (matched by name and triangle count), or NULL. */
const RaysetReference *rayset_reference(const RaysetScene *s);

/* Agreement with a reference (or with another back end). Hit counts may differ by a few
 * rays that graze an edge shared by two triangles or a silhouette (Embree and our
 * Moller-Trumbore round differently there): at most RAYSET_HITS_TOLERANCE_ABS rays or
 * RAYSET_HITS_TOLERANCE_REL of the count, whichever is larger. sum_t must agree to
 * RAYSET_SUM_T_TOLERANCE relative, after removing the contribution the count difference
 * can explain (|dhits| times the largest t of the set) and, where per-ray results of
 * Embree's default mode are at hand, that of rays grazing a silhouette onto another surface
 * (rayset_sum_t_match_ties below: at most the same number of rays, each measured). */
#define RAYSET_HITS_TOLERANCE_ABS 16
#define RAYSET_HITS_TOLERANCE_REL 1e-4
#define RAYSET_SUM_T_TOLERANCE 1e-6
size_t rayset_rays_tolerance(size_t count); /* max(ABS, REL x count) */
bool rayset_hits_match(size_t hits, size_t ref_hits);
bool rayset_sum_t_match(double sum_t, double ref_sum_t, size_t hits, size_t ref_hits, double max_t);

/* Per-ray comparison of two back ends' results on the same rays: a ray differs when one
 * hits and the other misses or, for closest hits, when the distances differ by more than
 * RAYSET_T_TOLERANCE relative (rounding differences between two ray-triangle tests are
 * ~1e-7; a different surface is almost always much farther off). *dt_sum gets the sum of
 * |t_a - t_b| over the differing rays (a miss counting as t = 0): how much of the sum-t
 * difference the differing rays explain. Returns the number of differing rays. */
#define RAYSET_T_TOLERANCE 1e-4
size_t rayset_compare(const RaysetResult *a, const RaysetResult *b, size_t n, RaysetQuery query, double *dt_sum);

/* Grazing ties (closest hits). Two correct back ends may also disagree on a ray that grazes
 * a silhouette and lands on another surface behind it: no hit count changes, but sum t
 * moves by the whole gap (the Cornell box's secondary ray 183436 passes 1.5e-5 outside the tall block's
 * top edge, y = 330: t 331.6 on its side face in Embree's robust mode on AMD EPYC/AVX2,
 * t 582.8 on the back wall in its default mode; 251 of 5.25e7 = 4.8e-6, beyond
 * RAYSET_SUM_T_TOLERANCE). A differing ray (as rayset_compare) is a tie when the nearer of
 * its two hits lies within RAYSET_EDGE_TOLERANCE x diag of an edge of its triangle that is
 * a silhouette for the ray (no other triangle shares it, or the one that does faces the ray
 * the other way), or the ray runs parallel to that triangle's plane. A ray passing between
 * two triangles that both face it (a leak through a closed surface, as the Moller-Trumbore
 * BVH once let 9 bumpysphere rays through) is no tie: it gets no allowance.
 * rayset_compare_ties returns the number of differing rays, *ties and *dt_ties the number
 * of ties and their sum of |t_a - t_b| (a miss counting as t = 0).
 * rayset_sum_t_match_ties is rayset_sum_t_match with dt_ties added to the allowance when
 * the ties number at most rayset_rays_tolerance(rays) (the same budget as edge-grazing hit
 * flips), else with nothing added. `caustic bench rays` measures the ties of every back end
 * against Embree's default mode on the same rays when this build has Embree. A real
 * traversal error (a wrong t on 1% of rays) has no ties and still fails. */
#define RAYSET_EDGE_TOLERANCE 1e-6
size_t rayset_compare_ties(const RaysetScene *s, const Ray *rays, const RaysetResult *a, const RaysetResult *b,
                           size_t n, size_t *ties, double *dt_ties);
bool rayset_sum_t_match_ties(double sum_t, double ref_sum_t, size_t hits, size_t ref_hits, double max_t,
                             size_t rays, size_t ties, double dt_ties);

#endif
