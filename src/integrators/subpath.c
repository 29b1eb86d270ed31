/* Bidirectional subpaths (subpath.h), after Georgiev et al. 2012 and the recursive MIS of
 * Georgiev's technical report "Implementing Vertex Connection and Merging" (2012; the
 * "tech. rep." equations below), with the power heuristic (beta = 2, Veach eq. 9.13).
 *
 * Every strategy's MIS weight is 1 / (sum over strategies of (p_k / p_s)^2); the ratios
 * are carried along each subpath in three numbers (d_vcm, d_vc, d_vm) so that a weight
 * costs O(1) instead of a walk over the path. The pdfs in the weights leave out Russian
 * roulette (our roulette follows the throughput, which the reverse direction cannot know):
 * weights that sum to one over the strategies of a path keep the estimator unbiased
 * whatever pdfs they are computed from, so this only makes them slightly less optimal. */
#include "integrators/subpath.h"

#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "film/filter.h"
#include "integrators/recorder.h"
#include "integrators/subpath_media.h"
#include "integrators/subpath_walk.h"

void subpath_vertex_list_free(SubpathVertexList *l)
{
    free(l->v);
    memset(l, 0, sizeof *l);
}

static void push_vertex(SubpathVertexList *l, const SubpathVertex *v)
{
    if (!array_push(l, *v)) l->oom = 1;
}


/* The density, per unit solid angle, with which a camera sample of one pixel picks the
 * direction at angle theta to the view axis: 1 / (pixel area cos^3 theta) on the image
 * plane at distance 1 (camera.c). Exact for the box filter; for the tent and the thin
 * lens it is the same function used consistently by every strategy, which is all the
 * weights need. */
static inline float camera_pdf_w(const SubpathIteration *it, float cos_theta)
{
    return 1.0f / (it->pixel_area * cos_theta * cos_theta * cos_theta);
}


void subpath_emit(const Scene *s, Sampler *rng, const Wavelengths *wl, EmissionSample *es)
{
    float u_sel = sampler_1d(rng);
    Vec2 u_pos = sampler_2d(rng);
    Vec2 u_dir = sampler_2d(rng);
    EmitterGeometry g = scene_emitter_geometry(s);
    emitter_sample_emission(&s->emitter_sampler, &g, u_sel, u_pos, u_dir, es);
    /* A start on an emitter's cut-away surface (alpha cut-out) carries no flux. */
    if (s->num_alphas && !es->delta && es->emitter < s->emitter_sampler.count &&
        scene_emitter_cut(s, es->emitter, es->p))
        es->beta = color_s(0.0f);
    es->beta = scene_emitter_color(s, es->emitter, es->beta, wl);
}

/* The t = 1 strategy at light vertex v with BSDF b: connect to a lens point. */
static void connect_to_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                              const SubpathIteration *it, const SubpathVertex *v, const Bsdf *b,
                              Vec2 u_lens, float time, const Wavelengths *wl, SplatList *splats, uint64_t *rays)
{
    const float margin = filter_radius(vp->frame.filter) - 0.5f;
    CameraWiSample cs;
    if (!camera_sample_wi(cam, v->p, u_lens, margin, &cs)) return;
    float cos_prev = fabsf(v3_dot(v->ng, v->w_prev));
    float cos_cam = fabsf(v3_dot(v->ng, cs.wi));
    if (!(cos_prev > 0.0f) || !(cos_cam > 0.0f)) return;
    /* f(wo = toward the camera, wi = toward the light) |cos theta_cam|, evaluated the way
     * the camera path sees this vertex (light.c explains the cosine swap). */
    float pdf_rev, pdf_unused;
    Color f = color_scale(bsdf_eval_pdfs(b, cs.wi, v->w_prev, &pdf_rev, &pdf_unused), cos_cam / cos_prev);
    if (color_is_black(f)) return;
    float cos_theta = v3_dot(v3_neg(cs.wi), cam->forward);
    /* The camera's density of this vertex per unit area, per pixel (tech. rep. eq. 46). */
    float cam_pdf_a = camera_pdf_w(it, cos_theta) * cos_cam / (cs.dist * cs.dist);
    float w_light = mis(cam_pdf_a / (float)it->light_paths) *
                    (it->mis_vm + v->d_vcm + v->d_vc * mis(pdf_rev));
    float weight = 1.0f / (1.0f + w_light);
    ++*rays;
    if (!scene_visible_point_at(s, v->p, v->ng, cs.p_lens, time)) return;
    Color c = color_scale(color_mul(v->beta, f), weight * cs.we / cs.pdf_w);
    if (it->rec) recorder_splat(it->rec, cs.raster.x, cs.raster.y, v->bounces + 1, v->p, cs.p_lens, c, weight, w_light,
                                cam_pdf_a);
    film_splat(splats, &vp->frame, cs.raster.x, cs.raster.y, wl ? spectrum_to_rgb(c, wl) : c);
}

/* subpath_trace_light's visitor: stores the vertex and makes its t = 1 connection. */
typedef struct LightSubpathCtx {
    const Scene *s;
    const Camera *cam;
    const SubpathParams *vp;
    const SubpathIteration *it;
    SubpathVertexList *verts;
    SplatList *splats;
    const Wavelengths *wl;
    const Wavelengths *walk_wl; /* spectral mode: the walk's copy of wl, terminated by a
                                 * dispersive refraction (LightWalk.disperse); NULL in RGB */
    uint64_t *rays;
    float time; /* the light subpath's time (motion blur), which its t = 1 shadow rays carry */
} LightSubpathCtx;

static bool store_and_connect(void *ctx, const LightVertex *lv)
{
    const LightSubpathCtx *c = ctx;
    const SurfaceHit *sh = lv->sh;
    const SubPath *sp = &lv->sp;
    const int dispersed = c->walk_wl && wavelengths_secondary_terminated(c->walk_wl);
    SubpathVertex v = {sh->p, sh->ng, sh->ns, lv->w_prev, sp->beta, sp->d_vcm, sp->d_vc, sp->d_vm,
                   sh->material, lv->bounces, sh->uv, dispersed};
    push_vertex(c->verts, &v);
    /* The t = 1 splat uses this light subpath alone: its own (terminated) wavelengths. */
    connect_to_camera(c->s, c->cam, c->vp, c->it, &v, lv->bsdf, lv->u_lens, c->time,
                      dispersed ? c->walk_wl : c->wl, c->splats, c->rays);
    return true; /* OOM is the list's flag, checked after the step */
}

void subpath_trace_light(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                     Sampler *rng, float time, const Wavelengths *wl, SubpathVertexList *verts,
                     SplatList *splats, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return;
    if (s->num_media | s->num_medium_ifaces) { /* participating media: subpath_media.c */
        media_subpath_trace_light(s, cam, vp, it, rng, time, wl, verts, splats, rays);
        return;
    }
    EmissionSample es;
    subpath_emit(s, rng, wl, &es);
    es.time = time; /* every ray of the walk carries it (emitters do not move: es is timeless) */
    if (it->rec) recorder_light_start(it->rec, &es);
    if (!(es.pdf_w > 0.0f) || color_is_black(es.beta)) return;
    float emission_pdf = es.pdf_a * es.pdf_w; /* point and direction */

    /* tech. rep. eqs. 31-33: the light vertex's NEE density against its emission density;
     * a delta light cannot be hit, so no strategy reaches it by a connection (d_vc = 0). */
    SubPath sp = subpath_start(es.beta);
    sp.d_vcm = mis(es.nee_pdf / emission_pdf);
    sp.d_vc = es.delta ? 0.0f : mis(es.cos_l / emission_pdf);
    sp.d_vm = sp.d_vc * it->mis_vc;

    /* Spectral mode: a dispersive dielectric terminates the secondary wavelengths of this
     * walk's copy (the camera subpath keeps wl and masks per contribution). */
    Wavelengths walk_wl;
    if (wl) walk_wl = *wl;
    LightSubpathCtx c = {s, cam, vp, it, verts, splats, wl, wl ? &walk_wl : NULL, rays, time};
    const LightWalk w = {vp->max_depth, vp->light_rr_depth, it, true, wl, store_and_connect, &c, wl ? &walk_wl : NULL};
    subpath_walk_light(s, &w, &es, sp, rng, rays);
}


/* NEE, the s = 1 strategy (tech. rep. eqs. 44-45; a delta light has no w_light: BSDF
 * sampling cannot hit it). */
static Color connect_to_light(const Scene *s, const SubpathIteration *it, const SubPath *sp,
                            const Bsdf *b, const SurfaceHit *sh, Vec3 wo, Sampler *rng, const Wavelengths *wl,
                            uint64_t *rays)
{
    float u_sel = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_li(&s->emitter_sampler, &g, sh->p, u_sel, u, &ls)) return color_s(0.0f);
    float cos_x = fabsf(v3_dot(sh->ng, ls.wi));
    if (!(cos_x > 0.0f)) return color_s(0.0f);
    float bsdf_pdf_fwd, bsdf_pdf_rev;
    Color f = bsdf_eval_pdfs(b, wo, ls.wi, &bsdf_pdf_fwd, &bsdf_pdf_rev);
    if (color_is_black(f)) return color_s(0.0f);
    float w_light = ls.delta ? 0.0f : mis(bsdf_pdf_fwd / ls.direct_pdf);
    float w_camera = mis(ls.emit_pdf * cos_x / (ls.direct_pdf * ls.cos_light)) *
                     (it->mis_vm + sp->d_vcm + sp->d_vc * mis(bsdf_pdf_rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    ++*rays;
    if (it->rec) {
        const bool vis = scene_visible_at(s, sh->p, sh->ng, ls.p, ls.n, sh->time);
        Color v = vis ? color_scale(color_mul(f, scene_light_li(s, &ls, wl)), weight / (ls.delta ? ls.pmf : ls.pdf_w))
                      : color_s(0.0f);
        recorder_strategy(it->rec, CST_EXPLAIN_NEE, 1, ls.light, ls.p, sp->beta, v, weight, w_light, w_camera,
                          ls.delta ? ls.pmf : ls.pdf_w, ls.direct_pdf, !vis);
        recorder_nee_normal(it->rec, ls.n);
        return v;
    }
    if (!scene_visible_at(s, sh->p, sh->ng, ls.p, ls.n, sh->time)) return color_s(0.0f);
    return color_scale(color_mul(f, scene_light_li(s, &ls, wl)), weight / (ls.delta ? ls.pmf : ls.pdf_w));
}

/* The BSDFs of one light path's first vertices, built when a connection first needs
 * them: every vertex of the camera path connects to the same light vertices, and
 * rebuilding y's BSDF for each (a frame, the material's constants, textures) was a
 * visible part of BDPT's time (docs/benchmarks.md). */
enum { LIGHT_BSDF_CACHE = 16 };
typedef struct LightBsdfs {
    Bsdf b[LIGHT_BSDF_CACHE];
    uint32_t built; /* bit j: b[j] holds vertex j's BSDF */
} LightBsdfs;

/* y's BSDF as the light subpath saw it, through the scene's one hit-to-BSDF routine;
 * vertex j of its path, cached in c when j is small enough (else built into *tmp). */
static inline const Bsdf *light_bsdf(const Scene *s, LightBsdfs *c, int j, const SubpathVertex *y,
                                     const Wavelengths *wl, Bsdf *tmp)
{
    Bsdf *b = j < LIGHT_BSDF_CACHE ? &c->b[j] : tmp;
    if (j < LIGHT_BSDF_CACHE && (c->built >> j & 1u)) return b;
    SurfaceHit yh = {.p = y->p, .ng = y->ng, .ns = y->ns, .material = y->material, .emitter = -1, .uv = y->uv};
    if (y->dispersed && wl) { /* as the light subpath built it: a dispersive ior at the hero */
        Wavelengths t = *wl;
        scene_bsdf_disperse(s, &yh, &t, b);
    } else {
        scene_bsdf(s, &yh, wl, b);
    }
    if (j < LIGHT_BSDF_CACHE) c->built |= 1u << j;
    return b;
}

/* A connection between camera vertex x and light vertex y, vertex j of its light path
 * (tech. rep. eqs. 40-41). */
static Color connect_vertices(const Scene *s, const SubpathIteration *it, const SubPath *sp,
                            const Bsdf *bx, const SurfaceHit *x, Vec3 wo, const SubpathVertex *y, int j,
                            LightBsdfs *cache, const Wavelengths *wl, uint64_t *rays)
{
    Vec3 to = v3_sub(y->p, x->p);
    float dist2 = v3_length2(to);
    if (!(dist2 > 0.0f)) return color_s(0.0f);
    float dist = sqrtf(dist2);
    Vec3 d = v3_scale(to, 1.0f / dist); /* x -> y */
    Vec3 nd = v3_neg(d);
    float cos_x = fabsf(v3_dot(x->ng, d)), cos_y = fabsf(v3_dot(y->ng, d));
    float cos_y_prev = fabsf(v3_dot(y->ng, y->w_prev));
    if (!(cos_x > 0.0f) || !(cos_y > 0.0f) || !(cos_y_prev > 0.0f)) return color_s(0.0f);
    float x_fwd, x_rev;
    Color fx = bsdf_eval_pdfs(bx, wo, d, &x_fwd, &x_rev);
    if (color_is_black(fx)) return color_s(0.0f);
    Bsdf tmp;
    const Bsdf *by = light_bsdf(s, cache, j, y, wl, &tmp);
    /* y seen from the camera side: wo = toward x, wi = toward the light; the cosine
     * swap of light.c turns |cos theta_prev| into |cos theta_x-side|. */
    float y_fwd, y_rev; /* y's own direction is toward the light: forward is w_prev -> nd */
    Color fy = color_scale(bsdf_eval_pdfs(by, nd, y->w_prev, &y_rev, &y_fwd), cos_y / cos_y_prev);
    if (color_is_black(fy)) return color_s(0.0f);
    float x_fwd_a = x_fwd * cos_y / dist2; /* the camera subpath reaching y */
    float y_fwd_a = y_fwd * cos_x / dist2; /* the light subpath reaching x */
    float w_light = mis(x_fwd_a) * (it->mis_vm + y->d_vcm + y->d_vc * mis(y_rev));
    float w_camera = mis(y_fwd_a) * (it->mis_vm + sp->d_vcm + sp->d_vc * mis(x_rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    ++*rays;
    if (it->rec) {
        const bool vis = scene_visible_at(s, x->p, x->ng, y->p, y->ng, x->time);
        Color v = vis ? color_scale(color_mul(color_mul(fx, fy), y->beta), weight / dist2) : color_s(0.0f);
        recorder_strategy(it->rec, CST_EXPLAIN_CONNECT, y->bounces + 1, -1, y->p, sp->beta, v, weight, w_light,
                          w_camera, x_fwd, x_fwd_a, !vis);
        recorder_light_dispersed(it->rec, y->dispersed);
        return v;
    }
    if (!scene_visible_at(s, x->p, x->ng, y->p, y->ng, x->time)) return color_s(0.0f);
    return color_scale(color_mul(color_mul(fx, fy), y->beta), weight / dist2);
}


Color subpath_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                           Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays, const SubpathMerge *merge)
{
    /* Participating media: subpath_media.c (merging in media too: UPBP's point-point 3D). */
    if (s->num_media | s->num_medium_ifaces)
        return media_subpath_trace_camera(s, cam, vp, it, path, ray, rng, wl, rays, merge);
    Color L = color_s(0.0f);
    if (it->rec) recorder_camera(it->rec, ray.o, ray.d, ray.time, wl);
    float cos_theta = v3_dot(ray.d, cam->forward);
    if (!(cos_theta > 0.0f)) return L;
    /* tech. rep. eqs. 31-33 for the camera: d_vcm = N_light / p_camera. An orthographic
     * camera cannot be connected to (camera.h): like a delta vertex, 0 drops the t = 1
     * strategy from every weight. */
    SubPath sp = {color_s(1.0f), color_s(1.0f),
                  camera_is_orthographic(cam) ? 0.0f : mis((float)it->light_paths / camera_pdf_w(it, cos_theta)),
                  0.0f, 0.0f, false};
    const SubpathVertex *lv = it->vertices + it->path_start[path];
    const int nlv = (int)(it->path_start[path + 1] - it->path_start[path]);
    const bool has_lights = s->emitter_sampler.lights > 0;
    LightBsdfs light_bsdfs;
    light_bsdfs.built = 0;
    /* Spectral mode: wc is wl until the camera subpath refracts through a dispersive
     * dielectric (scene_bsdf_disperse terminates it); from then on, and for connections
     * and merges with dispersed light vertices, contributions go to H, whose lane 0 alone
     * counts (hero_only at the end). */
    Wavelengths wc;
    if (wl) wc = *wl;
    bool cam_dispersed = false;
    Color H = color_s(0.0f);
    for (int t = 1;; t++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) {
            /* s = 0 with the environment: an infinitely distant light, so its densities
             * have no distance factor and the last segment's is not converted (tech.
             * rep. sec. 5.1, SmallVCM's background). */
            Color le = scene_env_radiance(s, ray.d, wl);
            if (!color_is_black(le)) {
                float w = 1.0f;
                if (t > 1) {
                    float direct = light_env_pdf(&s->emitter_sampler, ray.d);
                    float emission = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
                    w = 1.0f / (1.0f + mis(direct) * sp.d_vcm + mis(emission) * sp.d_vc);
                }
                if (cam_dispersed) H = color_madd(H, sp.beta, color_scale(le, w));
                else L = color_madd(L, sp.beta, color_scale(le, w));
                if (it->rec) recorder_strategy(it->rec, CST_EXPLAIN_ESCAPE, 0, -1, ray.d, sp.beta, color_scale(le, w), w,
                                               1.0f / w - 1.0f, 0.0f, 0.0f, 0.0f, false);
            }
            break;
        }
        Vec3 wo = v3_neg(ray.d);
        float cos_in = fabsf(v3_dot(sh.ng, wo));
        if (!(cos_in > 0.0f)) break;
        mis_arrive(&sp, sh.t, cos_in);
        if (it->rec) recorder_vertex(it->rec, s, &sh, t, wl);

        /* s = 0: the camera subpath hits an emitter (tech. rep. eq. 39). Seen directly
         * there is no other strategy (light vertices on emitters are not splatted). */
        if (sh.emitter >= 0) {
            const Emitter *e = &s->emitter_sampler.light[sh.emitter].u.area;
            Color le = scene_emission(s, &sh, wo, wl);
            if (!color_is_black(le)) {
                float w = 1.0f;
                if (t > 1) {
                    float pdf_a = emitter_pdf_a(&s->emitter_sampler, sh.emitter);
                    float emission_pdf = pdf_a * emitter_emission_pdf_w(e, sh.ng, wo);
                    w = 1.0f / (1.0f + mis(pdf_a) * sp.d_vcm + mis(emission_pdf) * sp.d_vc);
                }
                if (cam_dispersed) H = color_madd(H, sp.beta, color_scale(le, w));
                else L = color_madd(L, sp.beta, color_scale(le, w));
                if (it->rec) recorder_strategy(it->rec, CST_EXPLAIN_EMISSION, 0, sh.emitter, sh.p, sp.beta,
                                               color_scale(le, w), w, 1.0f / w - 1.0f, 0.0f, 0.0f, 0.0f, false);
            }
        }
        /* The camera path's vertices so far are t bounces once this one scatters. */
        if (vp->max_depth > 0 && t - 1 >= vp->max_depth) break;

        Bsdf bsdf;
        if (wl) {
            scene_bsdf_disperse(s, &sh, &wc, &bsdf);
            cam_dispersed = wavelengths_secondary_terminated(&wc);
            if (it->rec) recorder_cam_dispersed(it->rec, cam_dispersed);
        } else {
            scene_bsdf(s, &sh, wl, &bsdf);
        }
        if (!bsdf_is_delta(&bsdf)) {
            const bool merging = merge && it->cells > 0;
            MergeQuery mq;
            if (merging) merge->plan(it, sh.p, &mq);
            if (has_lights) {
                Color nee = connect_to_light(s, it, &sp, &bsdf, &sh, wo, rng, wl, rays);
                if (cam_dispersed) H = color_madd(H, sp.beta, nee);
                else L = color_madd(L, sp.beta, nee);
            }
            if (merging) merge->fetch(it, &mq);
            Color c = color_s(0.0f), ch = color_s(0.0f);
            for (int j = 0; j < nlv; j++) {
                if (vp->max_depth > 0 && t + lv[j].bounces > vp->max_depth) break;
                Color cj = connect_vertices(s, it, &sp, &bsdf, &sh, wo, &lv[j], j, &light_bsdfs, wl, rays);
                if (cam_dispersed || lv[j].dispersed) ch = color_add(ch, cj);
                else c = color_add(c, cj);
            }
            L = color_madd(L, sp.beta, c);
            if (wl) H = color_madd(H, sp.beta, ch);
            if (merging) {
                Color mh = color_s(0.0f), m = merge->merge(vp, it, &mq, &sp, &bsdf, &sh, wo, t, &mh);
                if (cam_dispersed) m = color_add(m, mh), mh = color_s(0.0f);
                if (cam_dispersed) H = color_madd(H, sp.beta, m);
                else L = color_madd(L, sp.beta, m);
                if (wl) H = color_madd(H, sp.beta, mh);
            }
        }

        if (!subpath_scatter(s, &sp, it, &bsdf, &sh, wo, BSDF_RADIANCE, t, vp->rr_depth, rng, &ray)) break;
    }
    if (!wl) return L;
    /* The hero alone, as a terminated wl would count it through spectrum_to_rgb: lane 0 /
     * (pdf_0 / 4) where the caller divides by pdf_0. */
    Color hero = color_s(0.0f);
    hero.c[0] = H.c[0] * (float)COLOR_LANES;
    return color_add(L, hero);
}



/* ---- Single strategies (subpath.h), for multiplexed MLT: the walks above cut at the one
 * vertex a strategy needs, and the connections above applied to it alone. */

bool subpath_camera_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                           Ray ray, int hits, bool emission, Sampler *rng, const Wavelengths *wl,
                           SubpathCameraVertex *out, Color *emitted, uint64_t *rays)
{
    *emitted = color_s(0.0f);
    /* explain (mmlt's replay of a splatted sample): the walk's vertices, scatters and the
     * s = 0 strategy are recorded as subpath_trace_camera records them. */
    if (it->rec) recorder_camera(it->rec, ray.o, ray.d, ray.time, wl);
    float cos_theta = v3_dot(ray.d, cam->forward);
    if (!(cos_theta > 0.0f)) return false;
    /* As subpath_trace_camera: d_vcm = N_light / p_camera (tech. rep. eqs. 31-33). */
    SubPath sp = {color_s(1.0f), color_s(1.0f),
                  camera_is_orthographic(cam) ? 0.0f : mis((float)it->light_paths / camera_pdf_w(it, cos_theta)),
                  0.0f, 0.0f, false};
    Wavelengths wc;
    if (wl) wc = *wl;
    bool dispersed = false;
    for (int t = 1;; t++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) {
            if (!emission || t != hits) return false;
            /* s = 0 with the environment, weighted as subpath_trace_camera does. */
            Color le = scene_env_radiance(s, ray.d, wl);
            if (color_is_black(le)) return false;
            float w = 1.0f;
            if (t > 1) {
                float direct = light_env_pdf(&s->emitter_sampler, ray.d);
                float emission_pdf = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
                w = 1.0f / (1.0f + mis(direct) * sp.d_vcm + mis(emission_pdf) * sp.d_vc);
            }
            *emitted = color_mul(sp.beta, color_scale(le, w));
            if (dispersed) *emitted = subpath_hero_only(*emitted);
            if (it->rec) recorder_strategy(it->rec, CST_EXPLAIN_ESCAPE, 0, -1, ray.d, sp.beta, color_scale(le, w), w,
                                           1.0f / w - 1.0f, 0.0f, 0.0f, 0.0f, false);
            return false;
        }
        Vec3 wo = v3_neg(ray.d);
        float cos_in = fabsf(v3_dot(sh.ng, wo));
        if (!(cos_in > 0.0f)) return false;
        mis_arrive(&sp, sh.t, cos_in);
        if (it->rec) recorder_vertex(it->rec, s, &sh, t, wl);
        if (emission && t == hits) {
            /* s = 0 at an emitter (tech. rep. eq. 39), weighted as subpath_trace_camera does. */
            if (sh.emitter < 0) return false;
            const Emitter *e = &s->emitter_sampler.light[sh.emitter].u.area;
            Color le = scene_emission(s, &sh, wo, wl);
            if (color_is_black(le)) return false;
            float w = 1.0f;
            if (t > 1) {
                float pdf_a = emitter_pdf_a(&s->emitter_sampler, sh.emitter);
                float emission_pdf = pdf_a * emitter_emission_pdf_w(e, sh.ng, wo);
                w = 1.0f / (1.0f + mis(pdf_a) * sp.d_vcm + mis(emission_pdf) * sp.d_vc);
            }
            *emitted = color_mul(sp.beta, color_scale(le, w));
            if (dispersed) *emitted = subpath_hero_only(*emitted);
            if (it->rec) recorder_strategy(it->rec, CST_EXPLAIN_EMISSION, 0, sh.emitter, sh.p, sp.beta,
                                           color_scale(le, w), w, 1.0f / w - 1.0f, 0.0f, 0.0f, 0.0f, false);
            return false;
        }
        Bsdf bsdf;
        if (wl) {
            scene_bsdf_disperse(s, &sh, &wc, &bsdf);
            dispersed = wavelengths_secondary_terminated(&wc);
            if (it->rec) recorder_cam_dispersed(it->rec, dispersed);
        } else {
            scene_bsdf(s, &sh, wl, &bsdf);
        }
        if (t == hits) {
            if (emission || bsdf_is_delta(&bsdf)) return false; /* no connection to a Dirac */
            *out = (SubpathCameraVertex){sh, bsdf, wo, sp, dispersed};
            return true;
        }
        if (!subpath_scatter(s, &sp, it, &bsdf, &sh, wo, BSDF_RADIANCE, t, vp->rr_depth, rng, &ray)) return false;
    }
}

/* subpath_light_vertex's visitor: keeps the vertex `bounces` and stops the walk there. */
typedef struct LightTargetCtx {
    int bounces;
    bool found;
    SubpathVertex *out;
    const Wavelengths *walk_wl;
} LightTargetCtx;

static bool keep_target(void *ctx, const LightVertex *lv)
{
    LightTargetCtx *c = ctx;
    if (lv->bounces < c->bounces) return true;
    if (lv->bounces > c->bounces) return false;
    const SurfaceHit *sh = lv->sh;
    const SubPath *sp = &lv->sp;
    const int dispersed = c->walk_wl && wavelengths_secondary_terminated(c->walk_wl);
    *c->out = (SubpathVertex){sh->p, sh->ng, sh->ns, lv->w_prev, sp->beta, sp->d_vcm, sp->d_vc, sp->d_vm,
                              sh->material, lv->bounces, sh->uv, dispersed};
    c->found = true;
    return false;
}

bool subpath_light_vertex(const Scene *s, const SubpathParams *vp, const SubpathIteration *it, int bounces,
                          Sampler *rng, float time, const Wavelengths *wl, SubpathVertex *out, Wavelengths *walk_wl,
                          uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return false;
    EmissionSample es;
    subpath_emit(s, rng, wl, &es);
    es.time = time;
    if (!(es.pdf_w > 0.0f) || color_is_black(es.beta)) return false;
    /* The light subpath's first MIS quantities, as subpath_trace_light sets them. */
    float emission_pdf = es.pdf_a * es.pdf_w;
    SubPath sp = subpath_start(es.beta);
    sp.d_vcm = mis(es.nee_pdf / emission_pdf);
    sp.d_vc = es.delta ? 0.0f : mis(es.cos_l / emission_pdf);
    sp.d_vm = sp.d_vc * it->mis_vc;
    if (wl) *walk_wl = *wl;
    if (it->rec) recorder_light_start(it->rec, &es); /* explain's mmlt replay: its scatters listed */
    LightTargetCtx c = {bounces, false, out, wl ? walk_wl : NULL};
    /* max_depth = bounces: the walk samples no continuation past the vertex it needs. */
    const LightWalk w = {bounces, vp->rr_depth, it, false, wl, keep_target, &c, wl ? walk_wl : NULL};
    subpath_walk_light(s, &w, &es, sp, rng, rays);
    return c.found;
}

Color subpath_connect_light(const Scene *s, const SubpathIteration *it, const SubpathCameraVertex *x, Sampler *rng,
                            const Wavelengths *wl, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return color_s(0.0f); /* as subpath_trace_camera */
    return color_mul(x->sp.beta, connect_to_light(s, it, &x->sp, &x->bsdf, &x->sh, x->wo, rng, wl, rays));
}

Color subpath_connect_pair(const Scene *s, const SubpathIteration *it, const SubpathCameraVertex *x,
                           const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays)
{
    LightBsdfs cache;
    cache.built = 0;
    /* j = LIGHT_BSDF_CACHE: y's BSDF built on the stack, not cached (one connection). */
    return color_mul(x->sp.beta,
                     connect_vertices(s, it, &x->sp, &x->bsdf, &x->sh, x->wo, y, LIGHT_BSDF_CACHE, &cache, wl, rays));
}

bool subpath_connect_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                            const SubpathVertex *y, Vec2 u_lens, float time, const Wavelengths *wl,
                            const Wavelengths *walk_wl, Vec2 *raster, Color *rgb, uint64_t *rays)
{
    LightBsdfs cache;
    cache.built = 0;
    Bsdf tmp;
    const Bsdf *b = light_bsdf(s, &cache, LIGHT_BSDF_CACHE, y, wl, &tmp);
    /* connect_to_camera's one splat into a list of one on the stack (no allocation), with
     * no clamp: the caller's estimate is clamped where it is splatted. */
    FilmSplat one;
    SplatList l = {.v = &one, .cap = 1};
    SubpathParams vq = *vp;
    vq.frame.clamp = 0.0f;
    connect_to_camera(s, cam, &vq, it, y, b, u_lens, time, y->dispersed ? walk_wl : wl, &l, rays);
    if (l.n == 0) return false;
    *raster = v2(one.x, one.y);
    *rgb = color_rgb(one.r, one.g, one.b);
    return true;
}
