/* BDPT's MIS weights computed explicitly from a whole path (issue 30's check of explain):
 * every strategy's density of the same path as a product of per-vertex area densities,
 * not Georgiev's recursion that subpath.c carries. */
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
} BdptMisPath;

/* The power-heuristic weight (Veach eq. 9.13) of strategy s (light vertices x_0 .. x_{s-1},
 * camera vertices x_s .. x_k) for path x, from the densities of every strategy that
 * subpath.c has (s = 0 emission hits, s = 1 NEE, connections, t = 1 camera connections
 * counted light_paths times; none through a delta vertex, none from a light point straight
 * to the camera), Russian roulette left out as subpath.c leaves it out. *sum: the weights of
 * all those strategies summed (1 up to rounding), *strategies their number. False when the
 * path has no density by strategy s. */
bool bdpt_mis_weight(const Scene *s, const Camera *cam, const SubpathIteration *it, const BdptMisPath *x,
                     int strategy, double *weight, double *sum, int *strategies);

#endif
