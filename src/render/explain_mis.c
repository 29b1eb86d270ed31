/* explain's explicit MIS check (explain_mis.h): a strategy's path is the camera subpath the
 * recorder kept and a light subpath: the pixel's own (kept in the same run), or for merges
 * and splats, which use other pixels' light subpaths, that subpath traced again with the
 * same random numbers (integrator_bidir_light_path) into a scratch recorder. */
#include "render/explain_mis.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "integrators/bdpt_mis.h"

/* Light vertices x_0 .. x_nl of path x from the kept light subpath lp: its emission sample
 * and first nl hits, each segment as its ray saw it. False when lp has not got them. */
static bool put_light(BdptMisPath *x, const RecorderPaths *lp, int nl)
{
    if (!lp->has_light || lp->start.delta || !lp->start.finite || nl > lp->nlight || nl > RECORDER_PATH_MAX ||
        nl >= BDPT_MIS_MAX)
        return false;
    x->emitter = lp->start.emitter;
    x->p0 = lp->start.p;
    x->n0 = lp->start.n;
    for (int b = 1; b <= nl; b++) {
        x->hit[b] = &lp->light[b - 1];
        x->delta[b] = lp->light_delta[b - 1];
        x->len[b - 1] = lp->light[b - 1].t;
        x->dir[b - 1] = lp->light_dir[b - 1];
        /* through media: the light walk's flight made x_b from x_{b-1} */
        x->medium[b] = lp->light_medium[b - 1];
        x->chain_fwd[b - 1] = lp->light_fwd[b - 1];
        x->chain_rev[b - 1] = lp->light_rev[b - 1];
    }
    return true;
}

/* Camera vertices x_{k - tc} .. x_{k - 1} of path x: the camera subpath's hits tc .. 1 (hit
 * d ends segment x_{k-d} x_{k-d+1}, traversed toward x_{k-d}), and x_k its lens point. */
static bool put_camera(BdptMisPath *x, const RecorderPaths *rp, int tc)
{
    if (tc > rp->ncam || tc > RECORDER_PATH_MAX || x->k - tc < 0) return false;
    for (int d = 1; d <= tc; d++) {
        x->hit[x->k - d] = &rp->cam[d - 1];
        x->delta[x->k - d] = rp->cam_delta[d - 1];
        x->len[x->k - d] = rp->cam[d - 1].t;
        x->dir[x->k - d] = v3_neg(rp->cam_dir[d - 1]);
        /* through media: the camera walk's flight made x_{k-d} from x_{k-d+1} */
        x->medium[x->k - d] = rp->cam_medium[d - 1];
        x->chain_fwd[x->k - d] = rp->cam_rev[d - 1];
        x->chain_rev[x->k - d] = rp->cam_fwd[d - 1];
    }
    x->lens = rp->camera_o;
    return true;
}

static bool same_point(const float a[3], Vec3 b) { return a[0] == b.x && a[1] == b.y && a[2] == b.z; }

/* The light path of the iteration that stored the vertex at p after `bounces` bounces
 * (the vertex a merge used), or -1. */
static int vertex_path(const LightIterations *L, const float p[3], int bounces)
{
    for (size_t i = 0; i < L->total; i++) {
        const SubpathVertex *v = &L->vertices[i];
        if (v->bounces != bounces || !same_point(p, v->p)) continue;
        int lo = 0, hi = L->light_paths - 1; /* the last path whose run starts at or before i */
        while (lo < hi) {
            int mid = (lo + hi + 1) / 2;
            if (L->path_start[mid] <= i) lo = mid;
            else hi = mid - 1;
        }
        return lo;
    }
    return -1;
}

/* Light subpath `path` traced again into the scratch recorder t (its paths kept). */
static bool retrace(const Integrator *it, int iteration, Recorder *t, int path)
{
    memset(&t->paths, 0, sizeof t->paths);
    t->paths.light_path = path;
    t->paths.light_started = path;
    SubpathVertexList verts = {0};
    SplatList splats;
    if (!splat_list_init(&splats, 16)) return false;
    uint64_t rays = 0;
    integrator_bidir_light_path(it, iteration, path, t, &verts, &splats, &rays);
    const bool ok = !verts.oom && !splats.oom;
    subpath_vertex_list_free(&verts);
    splat_list_free(&splats);
    return ok;
}

/* The path of event e rebuilt into x with the strategy that sampled it; *lp_out the light
 * subpath used. False when the check does not cover it (delta light, a path longer than
 * the recorder keeps, a vertex the trace again does not find). */
static bool rebuild(const Integrator *it, int iteration, const Recorder *r, Recorder *t, const CstExplainEvent *e, BdptMisPath *x,
                    int *strategy, bool *merge, bool *ok)
{
    const RecorderPaths *rp = &r->paths;
    memset(x, 0, sizeof *x);
    x->media = it->scene->num_media | it->scene->num_medium_ifaces;
    for (int i = 0; i < BDPT_MIS_MAX; i++) {
        x->medium[i] = -1;
        x->chain_fwd[i] = x->chain_rev[i] = 1.0f;
    }
    *merge = e->kind == CST_EXPLAIN_MERGE;
    const int tc = e->t - 1; /* camera hits */
    const int s = e->s;
    if (e->kind == CST_EXPLAIN_MERGE || e->kind == CST_EXPLAIN_SPLAT) {
        const int b = s - 1; /* the light vertex's bounces */
        int path = e->path;
        if (e->kind == CST_EXPLAIN_MERGE) path = vertex_path(&it->light, e->p, b);
        if (path < 0 || b < 1) return false;
        if (!retrace(it, iteration, t, path)) {
            *ok = false;
            return false;
        }
        const RecorderPaths *lp = &t->paths;
        if (b > lp->nlight || b > RECORDER_PATH_MAX || !same_point(e->p, lp->light[b - 1].p)) return false;
        x->k = e->kind == CST_EXPLAIN_MERGE ? b + tc : b + 1;
        if (x->k >= BDPT_MIS_MAX || !put_light(x, lp, b)) return false;
        if (e->kind == CST_EXPLAIN_SPLAT) {
            x->lens = lp->light_lens[b - 1];
            x->len[b] = 0.0f; /* the connection to the lens */
            x->chain_fwd[b] = e->chain_fwd; /* media_connect from the light vertex */
            x->chain_rev[b] = e->chain_rev;
        } else {
            if (tc < 1 || !put_camera(x, rp, tc)) return false;
            x->merged = b;
            x->n_light = lp->light[b - 1].ng;
        }
        x->delta[b] = false; /* evaluated there, by the merge or the connection */
        *strategy = b + (e->kind == CST_EXPLAIN_SPLAT);
        return true;
    }
    /* Emission (s = 0), NEE (s = 1) and connections with the pixel's own light subpath. */
    x->k = s + e->t - 1;
    if (x->k >= BDPT_MIS_MAX || x->k < 1) return false;
    if (s == 0) {
        /* (media's emission, light -1, has no other strategy: weight 1, nothing to check) */
        if (tc < 1 || tc > rp->ncam || tc > RECORDER_PATH_MAX || e->light < 0) return false;
        const SurfaceHit *h = &rp->cam[tc - 1];
        x->emitter = h->emitter;
        x->p0 = h->p;
        x->n0 = h->ng;
    } else if (s == 1) {
        x->emitter = e->light;
        x->p0 = v3(e->p[0], e->p[1], e->p[2]);
        x->n0 = v3(e->ng[0], e->ng[1], e->ng[2]);
    } else if (!put_light(x, rp, s - 1)) {
        return false;
    }
    if (!put_camera(x, rp, tc)) return false;
    if (s >= 1) { /* the connection's ends are evaluated, never delta; its segment is 0 */
        x->delta[s - 1] = false;
        if (s < x->k) x->delta[s] = false;
        x->len[s - 1] = 0.0f;
        /* through media: media_connect from the camera vertex x_s to x_{s-1} */
        if (x->media && s < x->k) {
            x->chain_fwd[s - 1] = e->chain_rev;
            x->chain_rev[s - 1] = e->chain_fwd;
        }
    }
    *strategy = s;
    return true;
}

bool explain_mis_check(const Integrator *it, int iteration, Recorder *r, CstExplain *ex)
{
    const SubpathIteration *vi = &it->light.vcm_it;
    /* Georgiev et al. 2012 eq. 11 (tech. rep. eq. 12): eta_VCM = pi r^2 N_light. */
    const double eta = it->light.vcm_params.merge
                           ? 3.14159265358979323846 * (double)vi->radius * (double)vi->radius * (double)vi->light_paths
                           : 0.0;
    Recorder *t = calloc(1, sizeof *t); /* traces again: no events kept, radius 0 */
    BdptMisPath *x = malloc(sizeof *x);
    bool ok = t && x;
    for (int i = 0; ok && i < r->n; i++) {
        CstExplainEvent *e = &r->ev[i];
        const bool splat = e->kind == CST_EXPLAIN_SPLAT;
        if (!(e->flags & CST_EXPLAIN_ADDED) && !splat) continue;
        if (e->s < 0 || e->t < 1 || (e->flags & CST_EXPLAIN_DELTA)) continue;
        if (e->mis_weight < 0.0f) continue; /* blocked before a weight (subpath_media.c) */
        if (e->kind != CST_EXPLAIN_EMISSION && e->kind != CST_EXPLAIN_NEE && e->kind != CST_EXPLAIN_CONNECT &&
            e->kind != CST_EXPLAIN_MERGE && !splat)
            continue;
        int strategy;
        bool merge;
        if (!rebuild(it, iteration, r, t, e, x, &strategy, &merge, &ok)) continue;
        x->eta = eta;
        /* UPBP's ball: eta = (4/3) pi r^3 N_light at a medium vertex. */
        x->eta_vol = eta > 0.0 ? eta * (4.0 / 3.0) * (double)vi->radius : 0.0;
        /* A moving camera stood where the path's time placed it (integrator.c's
         * camera_placed): the camera subpath's time, or for a splat its light subpath's,
         * whose t = 1 connection reached the lens there. */
        const Camera *cam = &it->camera;
        Camera placed;
        if (cam->moving) {
            placed = camera_at(cam, splat ? t->paths.start.time : r->paths.camera_time);
            cam = &placed;
        }
        double w, sum;
        int n;
        if (!bdpt_mis_weight(it->scene, cam, vi, x, strategy, merge, &w, &sum, &n)) continue;
        e->mis_explicit = (float)w;
        e->mis_sum = (float)sum;
        e->mis_strategies = n;
        double err = fabs((double)e->mis_weight - w) / w;
        if (err > ex->mis_max_error) ex->mis_max_error = err;
        if (fabs(sum - 1.0) > ex->mis_max_sum_error) ex->mis_max_sum_error = fabs(sum - 1.0);
        ex->mis_checked++;
    }
    free(t);
    free(x);
    return ok;
}
