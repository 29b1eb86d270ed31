/* BDPT's and VCM's MIS weights computed explicitly from a whole path (issue 30's check of
 * explain): every strategy's density of the same path, connections and merges, as a product
 * of per-vertex area densities, not Georgiev's recursion that subpath.c and vcm.c carry. */
#ifndef CST_INTEGRATORS_BDPT_MIS_H
#define CST_INTEGRATORS_BDPT_MIS_H

#include <stdbool.h>

#include "camera/camera.h"
#include "integrators/subpath.h"
#include "scene/scene.h"

enum { BDPT_MIS_MAX = 130 };

/* A path x_0 .. x_k: x_0 on an area emitter (emitter index, point, normal), x_1 .. x_{k-1}
 * surface hits (with whether the path's direction pair there was a delta lobe's: sampled by
 * one, on either subpath), x_k the lens point. */
typedef struct BdptMisPath {
    int k;
    int emitter;
    Vec3 p0, n0;
    const SurfaceHit *hit[BDPT_MIS_MAX]; /* hit[i] for 1 <= i < k */
    bool delta[BDPT_MIS_MAX];
    Vec3 lens;
    /* Segment x_i x_{i+1} as the ray that sampled it saw it: unit direction dir[i] (x_i to
     * x_{i+1}) and length len[i] from its offset origin, the geometry the subpaths' own
     * densities use; len[i] 0 for the connection (the vertices' positions). */
    Vec3 dir[BDPT_MIS_MAX];
    float len[BDPT_MIS_MAX];
    /* VCM: eta = pi r^2 N_light (Georgiev et al. 2012 eq. 11; tech. rep. eq. 12), the factor
     * from a connection's density to a merge's at the same vertex; 0 for BDPT (no merging).
     * A merged path (merged > 0) has two points at vertex `merged`: the light vertex y its
     * light subpath reached (normal n_light, the end of segment merged - 1) and the camera
     * vertex x its camera subpath reached (hit[merged], the start of segment merged; x's
     * BSDF is the vertex's, as the merge evaluates it). 0: a path of single points. */
    double eta;
    int merged;
    Vec3 n_light;
    /* Through media (subpath_media.c; media false: no medium vertex, every chain factor 1):
     * medium[i] >= 0 makes x_i a medium vertex of that medium (no cosine; the phase
     * function's density, its HG asymmetry); chain_fwd[i] / chain_rev[i]: the distance-
     * sampling densities (subpath_media_step.h's chain: pass probabilities, and the free-flight
     * density at a medium vertex, majorant-based in grids) of segment x_i x_{i+1} made from
     * x_i / from x_{i+1}; eta_vol: VCM's eta at a medium vertex, (4/3) pi r^3 N_light (UPBP's
     * point-point 3D merge, Krivanek et al. 2014). */
    bool media;
    int medium[BDPT_MIS_MAX];
    float chain_fwd[BDPT_MIS_MAX], chain_rev[BDPT_MIS_MAX];
    double eta_vol;
} BdptMisPath;

/* The power-heuristic weight (Veach eq. 9.13) for path x of the connection strategy s
 * (merge false: light vertices x_0 .. x_{s-1}, camera vertices x_s .. x_k) or of merging at
 * vertex s (merge true: both subpaths reach x_s, 1 <= s < k), from the densities of every
 * strategy that subpath.c and vcm.c have (s = 0 emission hits, s = 1 NEE, connections, t = 1
 * camera connections counted light_paths times, and with eta > 0 a merge at every non-delta
 * vertex x_1 .. x_{k-1} counted eta times; none through a delta vertex, none from a light
 * point straight to the camera), Russian roulette left out as subpath.c leaves it out.
 * *sum: the weights of all those strategies summed (1 up to rounding), *strategies their
 * number. False when the path has no density by that strategy. */
bool bdpt_mis_weight(const Scene *s, const Camera *cam, const SubpathIteration *it, const BdptMisPath *x,
                     int strategy, bool merge, double *weight, double *sum, int *strategies);

#endif
