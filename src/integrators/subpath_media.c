/* Light tracing, BDPT, VCM, MMLT and SPPM's photons through participating media
 * (subpath_media.h): free flights and Henyey-Greenstein scattering on both subpaths, medium
 * tracking across interface shapes, transmittance on every connection, and subpath.c's
 * recursive MIS (Georgiev, "Implementing Vertex Connection and Merging", 2012) extended to
 * volume vertices as in UPBP (Krivanek et al. 2014, sec. 4 and supplement): a volume vertex
 * has no cosine, and a vertex's density includes the distance sampling that made it
 * (medium.h's lane-balanced medium_distance_pdf() and medium_pass_prob(), per piece between
 * boundaries). Scenes without media keep subpath.c and light.c bit for bit. Grids and clouds:
 * delta tracking on walks, ratio tracking on connections, MIS densities from chain_piece's
 * majorant stand-ins (computed alike by every strategy, so the weights still sum to 1).
 * Emissive media: gathered by BDPT's, VCM's and MMLT's camera walks with weight 1 (see
 * media_subpath_trace_camera); the light tracer's paths and SPPM's photons start in them too
 * (media_lights.h; media_light_trace_volume, media_photon_walk). VCM merges volume
 * vertices by UPBP's point-point 3D estimator (1 / ((4/3) pi r^3 N); media_merge). Motion
 * blur: every ray carries its path's time (walks keep the time of the ray they continue;
 * connections take the camera vertex's or the light subpath's); media do not move. */
#include "integrators/subpath_media.h"

#include <math.h>

#include "core/array.h"
#include "core/rng.h"
#include "film/filter.h"
#include "integrators/media_lights.h"
#include "integrators/recorder.h"
#include "integrators/subpath_media_step.h"
#include "integrators/subpath_walk.h"
#include "media/phase.h"

/* ------------------------------------------------------------------ light subpaths */

/* A light subpath vertex that can be connected to (non-delta surface, or in a medium). */
typedef struct MediaLightVertex {
    Vec3 p, ng;           /* ng = 0 in a medium */
    const SurfaceHit *sh; /* NULL in a medium */
    const Bsdf *bsdf;     /* NULL in a medium */
    float g;              /* HG asymmetry in a medium */
    int medium;           /* in a medium: its index; on a surface: the medium arrived through */
    Vec3 w_prev;
    SubPath sp; /* on arrival */
    int bounces;
    Vec2 u_lens;
} MediaLightVertex;

typedef bool (*MediaLightVisit)(void *ctx, const MediaLightVertex *v);

typedef struct MediaWalk {
    int max_depth, rr_depth;
    const SubpathIteration *mis; /* BDPT: the MIS quantities; NULL: light tracing */
    const Wavelengths *wl;
    Wavelengths *disperse; /* as LightWalk.disperse */
    MediaLightVisit visit;
    void *ctx;
    bool from_volume; /* es->p is a point in a medium (media_lights.h), not on a surface */
} MediaWalk;

/* subpath_walk_light through media: the same random numbers per surface vertex (lens, BSDF,
 * roulette), two per medium piece crossed, a lens 2D, a phase 2D and roulette's per volume vertex. */
static bool media_walk_light(const Scene *s, const MediaWalk *w, const EmissionSample *es, SubPath sp, int medium,
                             Sampler *rng, uint64_t *rays)
{
    const SubpathIteration *it = w->mis;
    Ray ray = ray_make_at(w->from_volume ? es->p : scene_offset(s, es->p, es->n, es->w), es->w, 0.0f, INFINITY,
                          es->time);
    Vec3 x_prev = es->p;
    bool prev_med = w->from_volume;
    /* BDPT (it) keeps medium.h's per-segment mixture in homogeneous media, whose exact
     * densities its MIS uses; grid pieces take the walk's hero lane whatever the
     * integrator, each stored vertex's throughput divided by the walk's mean lane ratio so
     * far (hero_beta), and their MIS densities are chain_piece's. */
    HeroMis hm = {-1, color_s(1.0f), it == NULL};
    for (int bounces = 1;; bounces++) {
        MediaHit h;
        if (!media_next(s, ray, x_prev, prev_med, false, &medium, &sp, &hm, rng, w->wl, &h, rays)) return true;
        if (h.kind == MEDIA_MISS) return true;
        Vec3 w_prev = v3_neg(ray.d);
        const bool vol = h.kind == MEDIA_VOLUME;
        if (it) {
            float cos_in = vol ? 1.0f : fabsf(v3_dot(h.sh.ng, w_prev));
            if (!(cos_in > 0.0f)) return true;
            mis_arrive_media(&sp, bounces > 1 || es->finite ? h.dist : 1.0f, cos_in, h.fwd, h.rev);
            if (it->rec) {
                recorder_media_light_hit(it->rec, vol ? NULL : &h.sh, h.p, medium, ray.d, h.dist, h.fwd, h.rev);
                recorder_media_light_vertex(it->rec, s, vol ? NULL : &h.sh, h.p, medium, bounces);
            }
        }
        const bool last = w->max_depth > 0 && bounces >= w->max_depth;
        if (vol) {
            const float g = s->media[medium].g;
            MediaLightVertex v = {h.p, v3s(0.0f), NULL, NULL, g, medium, w_prev, sp, bounces, sampler_2d(rng)};
            v.sp.beta = hero_beta(&hm, sp.beta);
            const bool more = !last && media_scatter_phase(&sp, it, true, h.p, w_prev, g, bounces, w->rr_depth, hero_scale(&hm), rng, &ray);
            if (more && it && it->rec)
                recorder_light_phase(it->rec, ray.d, phase_hg_eval(w_prev, ray.d, g), hero_beta(&hm, sp.beta), bounces);
            if (!w->visit(w->ctx, &v)) return false;
            if (!more) return true;
            x_prev = h.p;
            prev_med = true;
            continue;
        }
        Bsdf bsdf;
        if (w->disperse) scene_bsdf_disperse(s, &h.sh, w->disperse, &bsdf);
        else scene_bsdf(s, &h.sh, w->wl, &bsdf);
        const bool visit = !bsdf_is_delta(&bsdf);
        MediaLightVertex v = {h.p, h.sh.ng, &h.sh, &bsdf, 0.0f, medium, w_prev, sp, bounces, {0.0f, 0.0f}};
        v.sp.beta = hero_beta(&hm, sp.beta);
        if (visit) v.u_lens = sampler_2d(rng);
        const bool more = !last && subpath_scatter_rr(s, &sp, it, &bsdf, &h.sh, w_prev, BSDF_IMPORTANCE, bounces,
                                                      w->rr_depth, hero_scale(&hm), rng, &ray);
        if (visit && !w->visit(w->ctx, &v)) return false;
        if (!more) return true;
        medium = scene_medium_after(s, &h.sh, ray.d, medium);
        x_prev = h.p;
        prev_med = false;
    }
}

/* f |cos theta_cam| / |cos theta_prev| toward the camera direction wc at light vertex v
 * (light.c explains the cosine swap), with its reverse density (toward w_prev) in *pdf_rev. */
static Color light_vertex_f(const MediaLightVertex *v, Vec3 wc, float *pdf_rev)
{
    if (!v->bsdf) {
        float p = phase_hg_eval(wc, v->w_prev, v->g);
        *pdf_rev = p;
        return color_s(p);
    }
    float cos_prev = fabsf(v3_dot(v->ng, v->w_prev)), cos_cam = fabsf(v3_dot(v->ng, wc));
    if (!(cos_prev > 0.0f) || !(cos_cam > 0.0f)) return color_s(0.0f);
    float unused;
    return color_scale(bsdf_eval_pdfs(v->bsdf, wc, v->w_prev, pdf_rev, &unused), cos_cam / cos_prev);
}

/* What a camera connection of a light vertex needs. */
typedef struct MediaCamCtx {
    const Scene *s;
    const Camera *cam;
    const SplatFrame *frame;
    float margin;
    const SubpathIteration *it; /* BDPT: weights; NULL: the light tracer (no MIS) */
    SubpathVertexList *verts;   /* BDPT: the stored vertices */
    const Wavelengths *wl;      /* the splats' wavelengths (NULL: RGB) */
    const Wavelengths *walk_wl; /* BDPT, spectral: the walk's copy (dispersion) */
    SplatList *out;
    uint64_t *rays;
    float time; /* the light subpath's (motion blur); cam is placed at it */
} MediaCamCtx;

/* The t = 1 connection of v to the lens point drawn for it, with transmittance; with an
 * iteration, MIS-weighted as subpath.c's connect_to_camera with the camera's density of v
 * including the distance sampling along the way (tech. rep. eq. 46, UPBP). */
static void media_connect_camera(const MediaCamCtx *c, const MediaLightVertex *v, const Wavelengths *wl)
{
    CameraWiSample cs;
    if (!camera_sample_wi(c->cam, v->p, v->u_lens, c->margin, &cs)) return;
    float pdf_rev = 0.0f;
    Color f = light_vertex_f(v, cs.wi, &pdf_rev);
    if (color_is_black(f)) return;
    int m = v->sh ? scene_medium_after(c->s, v->sh, cs.wi, v->medium) : v->medium;
    MediaSegment seg;
    if (!media_connect(c->s, v->p, v->ng, cs.p_lens, v3s(0.0f), false, m, c->time, wl, &seg, c->rays)) return;
    float weight = 1.0f, w_light = 0.0f, cam_pdf_a = 0.0f;
    if (c->it) {
        float cos_cam = v->sh ? fabsf(v3_dot(v->ng, cs.wi)) : 1.0f;
        float cos_theta = v3_dot(v3_neg(cs.wi), c->cam->forward);
        cam_pdf_a = cos_cam * seg.rev / (c->it->pixel_area * cos_theta * cos_theta * cos_theta * cs.dist * cs.dist);
        w_light = mis(cam_pdf_a / (float)c->it->light_paths) *
                  (eta_vm(c->it, !v->sh) + v->sp.d_vcm + v->sp.d_vc * mis(pdf_rev));
        weight = 1.0f / (1.0f + w_light);
    }
    Color col = color_scale(color_mul(color_mul(v->sp.beta, f), seg.tr), weight * cs.we / cs.pdf_w);
    if (c->it && c->it->rec)
        recorder_media_splat(c->it->rec, cs.raster.x, cs.raster.y, v->bounces + 1, v->p, cs.p_lens, col, weight,
                             w_light, cam_pdf_a, seg.fwd, seg.rev);
    film_splat(c->out, c->frame, cs.raster.x, cs.raster.y, wl ? spectrum_to_rgb(col, wl) : col);
}

static bool visit_light_trace(void *ctx, const MediaLightVertex *v)
{
    const MediaCamCtx *c = ctx;
    media_connect_camera(c, v, c->wl);
    return true;
}

/* The light tracer's and SPPM's walk depth after a start in a medium: a vertex j bounces
 * after it closes a camera path that gathers the emission after j bounces, which volpath.c
 * counts below max_depth only (a surface emitter's after j <= max_depth); -1: no walk. */
static int medium_start_depth(int max_depth)
{
    return max_depth == 0 ? 0 : max_depth == 1 ? -1 : max_depth - 1;
}

/* The start on the light sampler's emitters when media emit too: picked with probability
 * 1 - p_media (media_lights.h), so its flux and its density of the point carry it. */
static void emit_on_emitters(const Scene *s, const MediaLights *ml, Sampler *rng, const Wavelengths *wl,
                             EmissionSample *es)
{
    subpath_emit(s, rng, wl, es);
    if (!ml) return;
    const float q = 1.0f - ml->p_media;
    es->beta = color_scale(es->beta, 1.0f / q);
    es->pdf_a *= q;
}

/* A light path of the light tracer that starts in an emitting medium: the start connected
 * to the lens (sigma_a Le / (p_sel p_V) Tr W_e / pdf_w: a volume vertex, no cosine), then
 * the walk from it (isotropic first direction). */
static void media_light_trace_volume(MediaCamCtx *c, const LightParams *lp, const MediaLights *ml,
                                     Sampler *rng, const Wavelengths *wlp, Wavelengths *walk_wl)
{
    MediaEmission me;
    const bool ok = media_lights_sample(ml, c->s, c->cam, c->time, wlp, rng, &me, c->rays);
    const Vec2 u_lens = sampler_2d(rng);
    if (!ok) return;
    CameraWiSample cs;
    MediaSegment seg;
    if (camera_sample_wi(c->cam, me.p, u_lens, c->margin, &cs) &&
        media_connect(c->s, me.p, v3s(0.0f), cs.p_lens, v3s(0.0f), false, me.medium, c->time, wlp, &seg, c->rays)) {
        Color v = color_scale(color_mul(me.le, seg.tr), cs.we / cs.pdf_w);
        film_splat(c->out, c->frame, cs.raster.x, cs.raster.y, wlp ? spectrum_to_rgb(v, wlp) : v);
    }
    const int depth = medium_start_depth(lp->max_depth);
    if (depth < 0) return;
    EmissionSample es = {.p = me.p, .w = me.w, .time = c->time, .finite = true, .pdf_w = CST_INV_4PI};
    const MediaWalk w = {depth, lp->rr_depth, NULL, wlp, walk_wl, visit_light_trace, c, true};
    media_walk_light(c->s, &w, &es, subpath_start(me.beta), me.medium, rng, c->rays);
}

void media_light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng, SplatList *out,
                       uint64_t *rays)
{
    const MediaLights *ml = lp->media_lights;
    if (s->emitter_sampler.lights == 0 && !ml) return;
    Wavelengths wl;
    if (lp->spectral) wl = wavelengths_sample(sampler_1d(rng));
    const Wavelengths *wlp = lp->spectral ? &wl : NULL;
    /* Motion blur: the light path's own time and the camera placed there (light.c). */
    const float time = scene_has_motion(s) ? camera_time(cam, sampler_1d(rng)) : 0.0f;
    Camera placed;
    if (cam->moving) {
        placed = camera_at(cam, time);
        cam = &placed;
    }
    MediaCamCtx c = {s, cam, &lp->frame, filter_radius(lp->frame.filter) - 0.5f, NULL, NULL, wlp, NULL, out, rays,
                     time};
    /* Emitting media: a light path starts in one with probability p_media (one more
     * random number; scenes without them keep their streams). */
    if (ml && sampler_1d(rng) < ml->p_media) {
        media_light_trace_volume(&c, lp, ml, rng, wlp, lp->spectral ? &wl : NULL);
        return;
    }
    EmissionSample es;
    emit_on_emitters(s, ml, rng, wlp, &es);
    es.time = time;

    /* y0 seen directly, through the media between it and the lens (light.c). */
    CameraWiSample cs;
    Vec2 u_lens = sampler_2d(rng);
    bool cut = s->num_alphas && !es.delta && es.finite && scene_emitter_cut(s, es.emitter, es.p);
    if (!es.delta && es.finite && !cut && camera_sample_wi(cam, es.p, u_lens, c.margin, &cs)) {
        const Emitter *e = &s->emitter_sampler.light[es.emitter].u.area;
        Color le = scene_emitter_color(s, es.emitter, emitter_radiance(e, s->textures, es.n, es.uv, cs.wi), wlp);
        le = color_scale(le, fabsf(v3_dot(es.n, cs.wi)) / es.pdf_a);
        MediaSegment seg;
        if (!color_is_black(le) &&
            media_connect(s, es.p, es.n, cs.p_lens, v3s(0.0f), false,
                          medium_at_emitter(s, cam, es.p, cs.wi, time, rays), time, wlp, &seg, rays)) {
            Color v = color_scale(color_mul(le, seg.tr), cs.we / cs.pdf_w);
            film_splat(out, &lp->frame, cs.raster.x, cs.raster.y, wlp ? spectrum_to_rgb(v, wlp) : v);
        }
    }
    if (!(es.pdf_w > 0.0f) || color_is_black(es.beta)) return;
    int medium = medium_at_emitter(s, cam, es.p, es.w, time, rays);
    /* Light from infinitely far through a medium that reaches infinity arrives black (as
     * the path tracer's escaping rays see it). */
    if (!es.finite && medium >= 0) return;
    const MediaWalk w = {lp->max_depth, lp->rr_depth, NULL, wlp, lp->spectral ? &wl : NULL, visit_light_trace, &c,
                         false};
    media_walk_light(s, &w, &es, subpath_start(es.beta), medium, rng, rays);
}

/* ------------------------------------------------------------------ BDPT */

static bool visit_store_connect(void *ctx, const MediaLightVertex *v)
{
    const MediaCamCtx *c = ctx;
    const int dispersed = c->walk_wl && wavelengths_secondary_terminated(c->walk_wl);
    SubpathVertex sv;
    if (v->sh) {
        sv = (SubpathVertex){v->p, v->ng, v->sh->ns, v->w_prev, v->sp.beta, v->sp.d_vcm, v->sp.d_vc, v->sp.d_vm,
                             v->sh->material, v->bounces, v->sh->uv, dispersed};
    } else {
        sv = (SubpathVertex){v->p, v3s(0.0f), v3s(0.0f), v->w_prev, v->sp.beta, v->sp.d_vcm, v->sp.d_vc,
                             v->sp.d_vm, -1 - v->medium, v->bounces, {0.0f, 0.0f}, dispersed};
    }
    if (!array_push(c->verts, sv)) c->verts->oom = 1;
    media_connect_camera(c, v, dispersed ? c->walk_wl : c->wl);
    return true;
}

void media_subpath_trace_light(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                               Sampler *rng, float time, const Wavelengths *wl, SubpathVertexList *verts,
                               SplatList *splats, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return;
    EmissionSample es;
    subpath_emit(s, rng, wl, &es);
    es.time = time;
    if (it->rec) recorder_light_start(it->rec, &es); /* explain: every path, in order */
    if (!(es.pdf_w > 0.0f) || color_is_black(es.beta)) return;
    int medium = medium_at_emitter(s, cam, es.p, es.w, time, rays);
    if (!es.finite && medium >= 0) return; /* as media_light_trace */
    float emission_pdf = es.pdf_a * es.pdf_w;
    /* tech. rep. eqs. 31-33, as subpath_trace_light; the distance densities of the first
     * segment join at its end (mis_arrive_media). */
    SubPath sp = subpath_start(es.beta);
    sp.d_vcm = mis(es.nee_pdf / emission_pdf);
    sp.d_vc = es.delta ? 0.0f : mis(es.cos_l / emission_pdf);
    sp.d_vm = sp.d_vc * it->mis_vc;
    Wavelengths walk_wl;
    if (wl) walk_wl = *wl;
    MediaCamCtx c = {s, cam, &vp->frame, filter_radius(vp->frame.filter) - 0.5f, it, verts, wl,
                     wl ? &walk_wl : NULL, splats, rays, time};
    const MediaWalk w = {vp->max_depth, vp->light_rr_depth, it, wl, wl ? &walk_wl : NULL, visit_store_connect,
                         &c, false};
    media_walk_light(s, &w, &es, sp, medium, rng, rays);
}

/* A camera subpath vertex: on a surface (bsdf) or in a medium (bsdf NULL, ng 0). */
typedef struct CamVertex {
    Vec3 p, ng, wo;
    const SurfaceHit *sh;
    const Bsdf *bsdf;
    float g;
    int medium; /* in a medium: its index; on a surface: the medium arrived through */
    float time; /* the camera subpath's (motion blur): its connections' rays carry it */
} CamVertex;

/* f toward wi at camera vertex x (f |cos| for a surface, the phase function in a medium)
 * with the densities of scattering toward wi (fwd) and back toward wo (rev), per solid
 * angle; *cos_wi the cosine at x (1 in a medium). */
static Color cam_vertex_f(const CamVertex *x, Vec3 wi, float *fwd, float *rev, float *cos_wi)
{
    if (!x->bsdf) {
        float p = phase_hg_eval(x->wo, wi, x->g);
        *fwd = *rev = p;
        *cos_wi = 1.0f;
        return color_s(p);
    }
    *cos_wi = fabsf(v3_dot(x->ng, wi));
    return bsdf_eval_pdfs(x->bsdf, x->wo, wi, fwd, rev);
}

static inline int cam_vertex_medium(const Scene *s, const CamVertex *x, Vec3 d)
{
    return x->sh ? scene_medium_after(s, x->sh, d, x->medium) : x->medium;
}

/* NEE (s = 1) through media: subpath.c's connect_to_light with transmittance, the
 * camera's BSDF / phase density of the light point gaining the pass probability of the
 * way there and the light's density of x the distance sampling of x. */
static Color media_connect_light(const Scene *s, const SubpathIteration *it, const SubPath *sp, const CamVertex *x,
                                 Color beta, Sampler *rng, const Wavelengths *wl, uint64_t *rays)
{
    float u_sel = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_li(&s->emitter_sampler, &g, x->p, u_sel, u, &ls)) return color_s(0.0f);
    float fwd, rev, cos_x;
    Color f = cam_vertex_f(x, ls.wi, &fwd, &rev, &cos_x);
    if (!(cos_x > 0.0f) || color_is_black(f)) return color_s(0.0f);
    MediaSegment seg;
    if (!media_connect(s, x->p, x->ng, ls.p, ls.n, false, cam_vertex_medium(s, x, ls.wi), x->time, wl, &seg, rays)) {
        /* explain: an occluded (or fully absorbed) connection is listed, adding 0 */
        if (it->rec) recorder_media_strategy(it->rec, CST_EXPLAIN_NEE, 1, ls.light, ls.p, ls.n, beta, color_s(0.0f),
                                             -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, NULL, 0.0f, 0.0f);
        return color_s(0.0f);
    }
    float w_light = ls.delta ? 0.0f : mis(fwd * seg.fwd / ls.direct_pdf);
    float w_camera = mis(ls.emit_pdf * cos_x * seg.rev / (ls.direct_pdf * ls.cos_light)) *
                     (eta_vm(it, !x->bsdf) + sp->d_vcm + sp->d_vc * mis(rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    Color c = color_mul(color_mul(f, seg.tr), scene_light_li(s, &ls, wl));
    c = color_scale(c, weight / (ls.delta ? ls.pmf : ls.pdf_w));
    if (it->rec)
        recorder_media_strategy(it->rec, CST_EXPLAIN_NEE, 1, ls.light, ls.p, ls.n, beta, c, weight, w_light, w_camera,
                                ls.delta ? ls.pmf : ls.pdf_w, ls.direct_pdf, &seg.tr, seg.fwd, seg.rev);
    return c;
}

/* A connection between camera vertex x and light vertex y (tech. rep. eqs. 40-41) through
 * media; y's BSDF rebuilt as subpath.c's light_bsdf does (not cached here). */
static Color media_connect_vertices(const Scene *s, const SubpathIteration *it, const SubPath *sp, const CamVertex *x,
                                    Color beta, const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays)
{
    Vec3 to = v3_sub(y->p, x->p);
    float dist2 = v3_length2(to);
    if (!(dist2 > 0.0f)) return color_s(0.0f);
    float dist = sqrtf(dist2);
    Vec3 d = v3_scale(to, 1.0f / dist); /* x -> y */
    Vec3 nd = v3_neg(d);
    float x_fwd, x_rev, cos_x;
    Color fx = cam_vertex_f(x, d, &x_fwd, &x_rev, &cos_x);
    if (!(cos_x > 0.0f) || color_is_black(fx)) return color_s(0.0f);
    const bool y_vol = y->material < 0;
    float y_fwd, y_rev, cos_y;
    Color fy;
    if (y_vol) {
        float p = phase_hg_eval(nd, y->w_prev, s->media[-1 - y->material].g);
        y_fwd = y_rev = p;
        cos_y = 1.0f;
        fy = color_s(p);
    } else {
        cos_y = fabsf(v3_dot(y->ng, d));
        float cos_y_prev = fabsf(v3_dot(y->ng, y->w_prev));
        if (!(cos_y > 0.0f) || !(cos_y_prev > 0.0f)) return color_s(0.0f);
        SurfaceHit yh = {.p = y->p, .ng = y->ng, .ns = y->ns, .material = y->material, .emitter = -1, .uv = y->uv};
        Bsdf by;
        if (y->dispersed && wl) {
            Wavelengths t = *wl;
            scene_bsdf_disperse(s, &yh, &t, &by);
        } else {
            scene_bsdf(s, &yh, wl, &by);
        }
        fy = color_scale(bsdf_eval_pdfs(&by, nd, y->w_prev, &y_rev, &y_fwd), cos_y / cos_y_prev);
    }
    if (color_is_black(fy)) return color_s(0.0f);
    MediaSegment seg;
    if (!media_connect(s, x->p, x->ng, y->p, y->ng, y_vol, cam_vertex_medium(s, x, d), x->time, wl, &seg, rays)) {
        if (it->rec) {
            recorder_media_strategy(it->rec, CST_EXPLAIN_CONNECT, y->bounces + 1, -1, y->p, y->ng, beta,
                                    color_s(0.0f), -1.0f, 0.0f, 0.0f, 0.0f, 0.0f, NULL, 0.0f, 0.0f);
            recorder_light_dispersed(it->rec, y->dispersed);
        }
        return color_s(0.0f);
    }
    float x_fwd_a = x_fwd * cos_y * seg.fwd / dist2; /* the camera subpath reaching y */
    float y_fwd_a = y_fwd * cos_x * seg.rev / dist2; /* the light subpath reaching x */
    float w_light = mis(x_fwd_a) * (eta_vm(it, y_vol) + y->d_vcm + y->d_vc * mis(y_rev));
    float w_camera = mis(y_fwd_a) * (eta_vm(it, !x->bsdf) + sp->d_vcm + sp->d_vc * mis(x_rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    Color c = color_scale(color_mul(color_mul(color_mul(fx, fy), y->beta), seg.tr), weight / dist2);
    if (it->rec) {
        recorder_media_strategy(it->rec, CST_EXPLAIN_CONNECT, y->bounces + 1, -1, y->p, y->ng, beta, c, weight,
                                w_light, w_camera, x_fwd, x_fwd_a, &seg.tr, seg.fwd, seg.rev);
        recorder_light_dispersed(it->rec, y->dispersed);
    }
    return c;
}

/* VCM's merging at camera vertex x (vcm.c's merge, over the grid cells merge->plan and
 * merge->fetch found) with the light vertices of x's kind. On a surface: a disk of radius
 * r, f / |cos| at x, 1 / (pi r^2 N) (tech. rep. eqs. 42-43). In a medium: UPBP's point-
 * point 3D estimator (Krivanek et al. 2014, sec. 5 and table 1), a ball of radius r,
 * 1 / ((4/3) pi r^3 N), the phase function at x, and one 1 / sigma_s(x): both subpaths'
 * throughputs end with the sigma_s of the free-flight sample that made their vertex, and
 * the merged path scatters once there. The MIS weights are vcm.c's with the eta of x's
 * kind. Merges with dispersed light vertices go to *hero (as vcm.c's). */
static Color media_merge(const Scene *s, const SubpathParams *vp, const SubpathIteration *it, const MergeQuery *q,
                         const SubPath *sp, const CamVertex *x, Color beta, int bounces, const Wavelengths *wl,
                         Color *hero)
{
    const bool vol = x->bsdf == NULL;
    const float r2 = it->radius * it->radius;
    const float mis_vc = vol ? it->mis_vc_vol : it->mis_vc;
    /* d_vm is relative to the surface eta (media_scatter_phase): eta_surface / eta_x. */
    const float vm_scale = vol ? it->mis_vm * it->mis_vc_vol : 1.0f;
    Color acc = color_s(0.0f), acc_hero = color_s(0.0f);
    for (int b = 0; b < q->nb; b++)
        for (uint32_t k = q->first[b]; k < q->last[b]; k++) {
            const MergeVertex *y = &it->cell_vertices[k];
            if (((y->dispersed & MERGE_VOLUME) != 0) != vol) continue;
            Vec3 dv = v3_sub(y->p, x->p);
            if (v3_dot(dv, dv) > r2) continue;
            if (vp->max_depth > 0 && bounces + y->bounces - 1 > vp->max_depth) continue;
            float x_fwd, x_rev;
            Color f;
            if (vol) {
                x_fwd = x_rev = phase_hg_eval(x->wo, y->w_prev, x->g);
                f = color_s(x_fwd);
            } else {
                float cos_w = fabsf(v3_dot(x->ng, y->w_prev));
                if (!(cos_w > 0.0f)) continue;
                f = bsdf_eval_pdfs(x->bsdf, x->wo, y->w_prev, &x_fwd, &x_rev);
                if (color_is_black(f)) continue;
                f = color_scale(f, 1.0f / cos_w); /* merging wants f without the cosine */
            }
            float w_light = y->d_vcm * mis_vc + y->d_vm * mis(x_fwd) * vm_scale;
            float w_camera = sp->d_vcm * mis_vc + sp->d_vm * mis(x_rev) * vm_scale;
            float weight = 1.0f / (w_light + 1.0f + w_camera);
            if (y->dispersed & 1) acc_hero = color_add(acc_hero, color_scale(color_mul(f, y->beta), weight));
            else acc = color_add(acc, color_scale(color_mul(f, y->beta), weight));
            if (it->rec)
                recorder_merge(it->rec, y->p, y->bounces, beta, color_scale(color_mul(f, y->beta), weight),
                               it->vm_norm, weight, w_light, w_camera, y->dispersed & 1);
        }
    Color norm = color_s(it->vm_norm);
    if (vol) {
        /* sigma_s(x): in a grid, the density at x times the medium's sigma_s (delta
         * tracking's weights hold sigma_s(y) / sigma_t(y) like the closed form's). */
        const Medium *med = &s->media[x->medium];
        const MediumCoeffs mc = medium_coeffs(med, wl);
        const float dens = medium_is_hetero(med) ? hetero_density_world(&med->u.het, x->p) : 1.0f;
        for (int c = 0; c < COLOR_LANES; c++) {
            const float ss = mc.sigma_s.c[c] * dens;
            norm.c[c] = ss > 0.0f ? it->vm_norm_vol / ss : 0.0f;
        }
    }
    if (it->rec && vol) recorder_merge_norm(it->rec, norm);
    *hero = color_mul(acc_hero, norm);
    return color_mul(acc, norm);
}

/* The s = 0 strategy of camera vertex t: the environment after a miss (the pass
 * probabilities of the way out joined to the camera's density: no distance, no cosine) or
 * an area emitter hit, as in subpath.c; le times its MIS weight (black: nothing to add).
 * beta: the vertex's throughput, for explain's recorder. */
static Color media_emitted(const Scene *s, const SubpathIteration *it, SubPath *sp, const MediaHit *h, Vec3 dir, int t,
                           Color beta, const Wavelengths *wl)
{
    const bool miss = h->kind == MEDIA_MISS;
    Color le = miss ? scene_env_radiance(s, dir, wl) : scene_emission(s, &h->sh, v3_neg(dir), wl);
    if (color_is_black(le)) return le;
    float w = 1.0f;
    if (t > 1 && miss) {
        mis_arrive_media(sp, 1.0f, 1.0f, h->fwd, h->rev);
        float direct = light_env_pdf(&s->emitter_sampler, dir);
        float emission = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
        w = 1.0f / (1.0f + mis(direct) * sp->d_vcm + mis(emission) * sp->d_vc);
    } else if (t > 1) {
        const Emitter *e = &s->emitter_sampler.light[h->sh.emitter].u.area;
        float pdf_a = emitter_pdf_a(&s->emitter_sampler, h->sh.emitter);
        float emission_pdf = pdf_a * emitter_emission_pdf_w(e, h->sh.ng, v3_neg(dir));
        w = 1.0f / (1.0f + mis(pdf_a) * sp->d_vcm + mis(emission_pdf) * sp->d_vc);
    }
    Color c = color_scale(le, w);
    if (it->rec)
        recorder_strategy(it->rec, miss ? CST_EXPLAIN_ESCAPE : CST_EXPLAIN_EMISSION, 0, miss ? -1 : h->sh.emitter,
                          miss ? dir : h->sh.p, beta, c, w, 1.0f / w - 1.0f, 0.0f, 0.0f, 0.0f, false);
    return c;
}

Color media_subpath_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                 const SubpathIteration *it, int path, Ray ray, Sampler *rng, const Wavelengths *wl,
                                 uint64_t *rays, const SubpathMerge *merge)
{
    const bool merging = merge && it->cells > 0;
    Color L = color_s(0.0f), H = color_s(0.0f);
    float cos_theta = v3_dot(ray.d, cam->forward);
    if (!(cos_theta > 0.0f)) return L;
    SubPath sp = {color_s(1.0f), color_s(1.0f),
                  camera_is_orthographic(cam)
                      ? 0.0f
                      : mis((float)it->light_paths * it->pixel_area * cos_theta * cos_theta * cos_theta),
                  0.0f, 0.0f, false};
    const SubpathVertex *lv = it->vertices + it->path_start[path];
    const int nlv = (int)(it->path_start[path + 1] - it->path_start[path]);
    const bool has_lights = s->emitter_sampler.lights > 0;
    Wavelengths wc;
    if (wl) wc = *wl;
    bool cam_dispersed = false;
    int medium = s->camera_medium;
    Vec3 x_prev = ray.o;
    bool prev_med = false;
    /* Grid media: delta tracking with one hero lane for the whole camera subpath, every
     * contribution weighted by hero_beta (the balance heuristic over the lanes of the
     * subpath's grid pieces, as volpath.c's mis_beta; the light subpath's vertices carry
     * their own). Each subpath is then an estimator for the mixture over hero lanes, a
     * proper density, and the two are independent: their product stays unbiased. */
    HeroMis hm = {-1, color_s(1.0f), false};
    if (it->rec) recorder_camera(it->rec, ray.o, ray.d, ray.time, wl);
    for (int t = 1;; t++) {
        MediaHit h;
        /* Emissive media: their emission is gathered by this walk alone, with MIS weight
         * 1. No other strategy makes such a path: light subpaths start on the emitters of
         * the light sampler only (never inside a medium), so connections and merges end
         * on those, and the paths whose last vertex is a point of emitting medium have
         * one strategy, s = 0, whose weight is 1 (Veach's thesis sec. 9.2.2: the weights
         * need only sum to 1 over the strategies that can make a path). Below the depth
         * limit only, as volpath.c and pbrt-v4. */
        const bool emit = !(vp->max_depth > 0 && t - 1 >= vp->max_depth);
        const bool go = media_next(s, ray, x_prev, prev_med, emit, &medium, &sp, &hm, rng, wl, &h, rays);
        if (emit) {
            if (cam_dispersed) H = color_add(H, h.le);
            else L = color_add(L, h.le);
            if (it->rec && !color_is_black(h.le)) recorder_media_emission(it->rec, t, h.le);
        }
        if (!go) break;
        const Color beta = hero_beta(&hm, sp.beta); /* the throughput of this vertex's contributions */
        if (it->rec && h.kind != MEDIA_MISS)
            recorder_media_flight(it->rec, h.p, medium, h.kind == MEDIA_VOLUME, h.dist, h.fwd, h.rev, beta);
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            Color c = media_emitted(s, it, &sp, &h, ray.d, t, beta, wl);
            if (!color_is_black(c)) {
                if (cam_dispersed) H = color_madd(H, beta, c);
                else L = color_madd(L, beta, c);
            }
            break;
        }
        const bool vol = h.kind == MEDIA_VOLUME;
        float cos_in = vol ? 1.0f : fabsf(v3_dot(h.sh.ng, wo));
        if (!(cos_in > 0.0f)) break;
        mis_arrive_media(&sp, h.dist, cos_in, h.fwd, h.rev);
        if (it->rec) {
            if (vol) recorder_medium_vertex(it->rec, h.p, medium, t);
            else recorder_vertex(it->rec, s, &h.sh, t, wl);
        }

        if (!vol && h.sh.emitter >= 0) { /* s = 0, as subpath.c */
            Color c = media_emitted(s, it, &sp, &h, ray.d, t, beta, wl);
            if (!color_is_black(c)) {
                if (cam_dispersed) H = color_madd(H, beta, c);
                else L = color_madd(L, beta, c);
            }
        }
        if (vp->max_depth > 0 && t - 1 >= vp->max_depth) break;

        Bsdf bsdf;
        CamVertex x = {h.p, v3s(0.0f), wo, NULL, NULL, 0.0f, medium, ray.time};
        if (vol) {
            x.g = s->media[medium].g;
        } else {
            if (wl) {
                scene_bsdf_disperse(s, &h.sh, &wc, &bsdf);
                cam_dispersed = wavelengths_secondary_terminated(&wc);
                if (it->rec) recorder_cam_dispersed(it->rec, cam_dispersed);
            } else {
                scene_bsdf(s, &h.sh, wl, &bsdf);
            }
            x.ng = h.sh.ng;
            x.sh = &h.sh;
            x.bsdf = &bsdf;
        }
        if (vol || !bsdf_is_delta(&bsdf)) {
            MergeQuery mq;
            if (merging) merge->plan(it, h.p, &mq);
            if (has_lights) {
                Color nee = media_connect_light(s, it, &sp, &x, beta, rng, wl, rays);
                if (cam_dispersed) H = color_madd(H, beta, nee);
                else L = color_madd(L, beta, nee);
            }
            if (merging) merge->fetch(it, &mq);
            Color c = color_s(0.0f), ch = color_s(0.0f);
            for (int j = 0; j < nlv; j++) {
                if (vp->max_depth > 0 && t + lv[j].bounces > vp->max_depth) break;
                Color cj = media_connect_vertices(s, it, &sp, &x, beta, &lv[j], wl, rays);
                if (cam_dispersed || lv[j].dispersed) ch = color_add(ch, cj);
                else c = color_add(c, cj);
            }
            L = color_madd(L, beta, c);
            if (wl) H = color_madd(H, beta, ch);
            if (merging) { /* as subpath_trace_camera */
                Color mh = color_s(0.0f), m = media_merge(s, vp, it, &mq, &sp, &x, beta, t, wl, &mh);
                if (cam_dispersed) m = color_add(m, mh), mh = color_s(0.0f);
                if (cam_dispersed) H = color_madd(H, beta, m);
                else L = color_madd(L, beta, m);
                if (wl) H = color_madd(H, beta, mh);
            }
        }
        if (vol) {
            if (!media_scatter_phase(&sp, it, false, h.p, wo, x.g, t, vp->rr_depth, hero_scale(&hm), rng, &ray)) break;
            if (it->rec) recorder_phase(it->rec, ray.d, phase_hg_eval(wo, ray.d, x.g), sp.beta);
            prev_med = true;
        } else {
            if (!subpath_scatter_rr(s, &sp, it, &bsdf, &h.sh, wo, BSDF_RADIANCE, t, vp->rr_depth, hero_scale(&hm), rng, &ray))
                break;
            medium = scene_medium_after(s, &h.sh, ray.d, medium);
            prev_med = false;
        }
        x_prev = h.p;
    }
    if (!wl) return L;
    Color hero = color_s(0.0f);
    hero.c[0] = H.c[0] * (float)COLOR_LANES;
    return color_add(L, hero);
}

/* ------------------------------------------------------------------ single strategies */

/* The visitor of a light walk cut at vertex `bounces`: stores that vertex (out) or
 * connects it to the lens at u_lens (cam), then stops the walk. */
typedef struct MediaTargetCtx {
    int bounces;
    bool found;
    SubpathVertex *out;
    const MediaCamCtx *cam;
    Vec2 u_lens;
    const Wavelengths *walk_wl;
} MediaTargetCtx;

static bool visit_target(void *ctx, const MediaLightVertex *v)
{
    MediaTargetCtx *c = ctx;
    if (v->bounces < c->bounces) return true;
    if (v->bounces > c->bounces) return false;
    const int dispersed = c->walk_wl && wavelengths_secondary_terminated(c->walk_wl);
    if (c->cam) {
        /* The strategy's lens point comes from the connection stream, not the walk's. */
        MediaLightVertex u = *v;
        u.u_lens = c->u_lens;
        media_connect_camera(c->cam, &u, dispersed ? c->cam->walk_wl : c->cam->wl);
    } else if (v->sh) { /* stored as visit_store_connect stores it */
        *c->out = (SubpathVertex){v->p, v->ng, v->sh->ns, v->w_prev, v->sp.beta, v->sp.d_vcm, v->sp.d_vc,
                                  v->sp.d_vm, v->sh->material, v->bounces, v->sh->uv, dispersed};
    } else {
        *c->out = (SubpathVertex){v->p, v3s(0.0f), v3s(0.0f), v->w_prev, v->sp.beta, v->sp.d_vcm, v->sp.d_vc,
                                  v->sp.d_vm, -1 - v->medium, v->bounces, {0.0f, 0.0f}, dispersed};
    }
    c->found = true;
    return false;
}

/* media_subpath_trace_light's start and walk, with max_depth = the target's bounces (no
 * continuation is sampled past it). */
static bool media_walk_to(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                          Sampler *rng, float time, const Wavelengths *wl, Wavelengths *walk_wl, MediaTargetCtx *tc,
                          uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return false;
    EmissionSample es;
    subpath_emit(s, rng, wl, &es);
    es.time = time;
    if (!(es.pdf_w > 0.0f) || color_is_black(es.beta)) return false;
    int medium = medium_at_emitter(s, cam, es.p, es.w, time, rays);
    if (!es.finite && medium >= 0) return false;
    float emission_pdf = es.pdf_a * es.pdf_w;
    SubPath sp = subpath_start(es.beta);
    sp.d_vcm = mis(es.nee_pdf / emission_pdf);
    sp.d_vc = es.delta ? 0.0f : mis(es.cos_l / emission_pdf);
    sp.d_vm = sp.d_vc * it->mis_vc;
    if (wl) *walk_wl = *wl;
    tc->walk_wl = wl ? walk_wl : NULL;
    if (it->rec) recorder_light_start(it->rec, &es); /* explain's mmlt replay: its scatters listed */
    const MediaWalk w = {tc->bounces, vp->rr_depth, it, wl, wl ? walk_wl : NULL, visit_target, tc, false};
    media_walk_light(s, &w, &es, sp, medium, rng, rays);
    return tc->found;
}

bool media_subpath_light_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                const SubpathIteration *it, int bounces, Sampler *rng, float time,
                                const Wavelengths *wl, SubpathVertex *out, Wavelengths *walk_wl, uint64_t *rays)
{
    MediaTargetCtx tc = {bounces, false, out, NULL, {0.0f, 0.0f}, NULL};
    return media_walk_to(s, cam, vp, it, rng, time, wl, walk_wl, &tc, rays);
}

bool media_subpath_connect_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                  const SubpathIteration *it, int bounces, Sampler *rng, float time, Vec2 u_lens,
                                  const Wavelengths *wl, Vec2 *raster, Color *rgb, uint64_t *rays)
{
    /* One splat into a list of one on the stack, unclamped (subpath_connect_camera). */
    FilmSplat one;
    SplatList l = {.v = &one, .cap = 1};
    SplatFrame frame = vp->frame;
    frame.clamp = 0.0f;
    Wavelengths walk_wl;
    MediaCamCtx c = {s, cam, &frame, filter_radius(vp->frame.filter) - 0.5f, it, NULL, wl, wl ? &walk_wl : NULL,
                     &l, rays, time};
    MediaTargetCtx tc = {bounces, false, NULL, &c, u_lens, NULL};
    media_walk_to(s, cam, vp, it, rng, time, wl, &walk_wl, &tc, rays);
    if (l.n == 0) return false;
    *raster = v2(one.x, one.y);
    *rgb = color_rgb(one.r, one.g, one.b);
    return true;
}

bool media_subpath_camera_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                 const SubpathIteration *it, Ray ray, int hits, bool emission, Sampler *rng,
                                 const Wavelengths *wl, MediaCameraVertex *out, Color *emitted, uint64_t *rays)
{
    *emitted = color_s(0.0f);
    float cos_theta = v3_dot(ray.d, cam->forward);
    if (!(cos_theta > 0.0f)) return false;
    /* As media_subpath_trace_camera. */
    SubPath sp = {color_s(1.0f), color_s(1.0f),
                  camera_is_orthographic(cam)
                      ? 0.0f
                      : mis((float)it->light_paths * it->pixel_area * cos_theta * cos_theta * cos_theta),
                  0.0f, 0.0f, false};
    Wavelengths wc;
    if (wl) wc = *wl;
    bool dispersed = false;
    int medium = s->camera_medium;
    Vec3 x_prev = ray.o;
    bool prev_med = false;
    HeroMis hm = {-1, color_s(1.0f), false}; /* grid media: the hero lane, as media_subpath_trace_camera */
    if (it->rec) recorder_camera(it->rec, ray.o, ray.d, ray.time, wl); /* explain: mmlt's replay */
    for (int t = 1;; t++) {
        MediaHit h;
        /* Emitting media on the last segment (s = 0): media_subpath_trace_camera's weight 1
         * and depth limit, so that mmlt's strategies of a length sum to BDPT's estimate. */
        const bool last = emission && t == hits, emit = last && !(vp->max_depth > 0 && t - 1 >= vp->max_depth);
        const bool go = media_next(s, ray, x_prev, prev_med, emit, &medium, &sp, &hm, rng, wl, &h, rays);
        if (emit) *emitted = dispersed ? subpath_hero_only(h.le) : h.le;
        if (!go) return false;
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            if (!last) return false;
            Color le = scene_env_radiance(s, ray.d, wl);
            if (color_is_black(le)) return false;
            float w = 1.0f;
            if (t > 1) {
                mis_arrive_media(&sp, 1.0f, 1.0f, h.fwd, h.rev);
                float direct = light_env_pdf(&s->emitter_sampler, ray.d);
                float em = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
                w = 1.0f / (1.0f + mis(direct) * sp.d_vcm + mis(em) * sp.d_vc);
            }
            Color add = color_mul(hero_beta(&hm, sp.beta), color_scale(le, w));
            *emitted = color_add(*emitted, dispersed ? subpath_hero_only(add) : add);
            return false;
        }
        const bool vol = h.kind == MEDIA_VOLUME;
        float cos_in = vol ? 1.0f : fabsf(v3_dot(h.sh.ng, wo));
        if (!(cos_in > 0.0f)) return false;
        mis_arrive_media(&sp, h.dist, cos_in, h.fwd, h.rev);
        if (it->rec) { /* explain (mmlt's replay): the flight and the vertex, as media_subpath_trace_camera lists them */
            recorder_media_flight(it->rec, h.p, medium, vol, h.dist, h.fwd, h.rev, hero_beta(&hm, sp.beta));
            if (vol) recorder_medium_vertex(it->rec, h.p, medium, t);
            else recorder_vertex(it->rec, s, &h.sh, t, wl);
        }
        if (last) {
            if (vol || h.sh.emitter < 0) return false;
            const Emitter *e = &s->emitter_sampler.light[h.sh.emitter].u.area;
            Color le = scene_emission(s, &h.sh, wo, wl);
            if (color_is_black(le)) return false;
            float w = 1.0f;
            if (t > 1) {
                float pdf_a = emitter_pdf_a(&s->emitter_sampler, h.sh.emitter);
                float emission_pdf = pdf_a * emitter_emission_pdf_w(e, h.sh.ng, wo);
                w = 1.0f / (1.0f + mis(pdf_a) * sp.d_vcm + mis(emission_pdf) * sp.d_vc);
            }
            Color add = color_mul(hero_beta(&hm, sp.beta), color_scale(le, w));
            *emitted = color_add(*emitted, dispersed ? subpath_hero_only(add) : add);
            return false;
        }
        if (vol) {
            const float g = s->media[medium].g;
            if (t == hits) {
                *out = (MediaCameraVertex){.p = h.p, .wo = wo, .vol = true, .g = g, .medium = medium, .sp = sp,
                                           .dispersed = dispersed, .time = ray.time};
                out->sp.beta = hero_beta(&hm, sp.beta);
                return true;
            }
            if (!media_scatter_phase(&sp, it, false, h.p, wo, g, t, vp->rr_depth, hero_scale(&hm), rng, &ray)) return false;
            if (it->rec) recorder_phase(it->rec, ray.d, phase_hg_eval(wo, ray.d, g), sp.beta);
            prev_med = true;
        } else {
            Bsdf bsdf;
            if (wl) {
                scene_bsdf_disperse(s, &h.sh, &wc, &bsdf);
                dispersed = wavelengths_secondary_terminated(&wc);
            } else {
                scene_bsdf(s, &h.sh, wl, &bsdf);
            }
            if (t == hits) {
                if (bsdf_is_delta(&bsdf)) return false; /* no connection to a Dirac */
                *out = (MediaCameraVertex){h.sh, bsdf, h.p, wo, false, 0.0f, medium, sp, dispersed, ray.time};
                out->sp.beta = hero_beta(&hm, sp.beta);
                return true;
            }
            if (!subpath_scatter_rr(s, &sp, it, &bsdf, &h.sh, wo, BSDF_RADIANCE, t, vp->rr_depth, hero_scale(&hm), rng,
                                    &ray))
                return false;
            medium = scene_medium_after(s, &h.sh, ray.d, medium);
            prev_med = false;
        }
        x_prev = h.p;
    }
}

/* The CamVertex of a strategy's camera vertex (its pointers into *x). */
static CamVertex cam_vertex_of(const MediaCameraVertex *x)
{
    if (x->vol) return (CamVertex){x->p, v3s(0.0f), x->wo, NULL, NULL, x->g, x->medium, x->time};
    return (CamVertex){x->p, x->sh.ng, x->wo, &x->sh, &x->bsdf, 0.0f, x->medium, x->time};
}

Color media_subpath_connect_light(const Scene *s, const SubpathIteration *it, const MediaCameraVertex *x,
                                  Sampler *rng, const Wavelengths *wl, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return color_s(0.0f);
    CamVertex cx = cam_vertex_of(x);
    return color_mul(x->sp.beta, media_connect_light(s, it, &x->sp, &cx, x->sp.beta, rng, wl, rays));
}

Color media_subpath_connect_pair(const Scene *s, const SubpathIteration *it, const MediaCameraVertex *x,
                                 const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays)
{
    CamVertex cx = cam_vertex_of(x);
    return color_mul(x->sp.beta, media_connect_vertices(s, it, &x->sp, &cx, x->sp.beta, y, wl, rays));
}

/* ------------------------------------------------------------------ SPPM (sppm.c) */

typedef struct MediaPhotonCtx {
    MediaPhotonVisit visit;
    void *ctx;
    float time;
    bool medium_start;
} MediaPhotonCtx;

static bool visit_photon(void *ctx, const MediaLightVertex *v)
{
    const MediaPhotonCtx *c = ctx;
    MediaPhoton ph = {v->p, v->w_prev, v3s(0.0f), v->sp.beta, v->bounces, v->sp.specular_only, c->time, v->sh,
                      c->medium_start, v->medium};
    if (v->sh) ph.n = v3_dot(v->ng, v->w_prev) >= 0.0f ? v->ng : v3_neg(v->ng);
    return c->visit(c->ctx, &ph);
}

bool media_photon_walk(const Scene *s, const Camera *cam, const PhotonWalk *pw, uint64_t index, MediaPhotonVisit visit,
                       void *ctx, uint64_t *rays)
{
    Sampler rng;
    sampler_start_stream(&rng, pw->seed, index, pw->stream);
    const float time = photon_walk_time(pw, &rng); /* the path's instant, as photon_walk's */
    const MediaLights *ml = pw->media_lights;
    if (ml && sampler_1d(&rng) < ml->p_media) { /* a start in an emitting medium (media_light_trace) */
        MediaEmission me;
        if (!media_lights_sample(ml, s, cam, time, pw->wl, &rng, &me, rays)) return true;
        const int depth = medium_start_depth(pw->max_depth);
        if (depth < 0) return true;
        EmissionSample es = {.p = me.p, .w = me.w, .time = time, .finite = true, .pdf_w = CST_INV_4PI};
        MediaPhotonCtx c = {visit, ctx, time, true};
        const MediaWalk w = {depth, pw->rr_depth, NULL, pw->wl, NULL, visit_photon, &c, true};
        return media_walk_light(s, &w, &es, subpath_start(color_scale(me.beta, pw->scale)), me.medium, &rng, rays);
    }
    EmissionSample es;
    emit_on_emitters(s, ml, &rng, pw->wl, &es);
    if (!(es.pdf_w > 0.0f) || !(es.pdf_a > 0.0f) || color_is_black(es.beta)) return true; /* still one of the N */
    es.time = time;
    int medium = medium_at_emitter(s, cam, es.p, es.w, es.time, rays);
    if (!es.finite && medium >= 0) return true; /* as media_light_trace */
    MediaPhotonCtx c = {visit, ctx, time, false};
    /* No MIS (light tracing's walk): the hero lane's free-flight sampling in every medium,
     * each vertex's flux divided by the walk's mean lane ratio (hero_beta). */
    const MediaWalk w = {pw->max_depth, pw->rr_depth, NULL, pw->wl, NULL, visit_photon, &c, false};
    return media_walk_light(s, &w, &es, subpath_start(color_scale(es.beta, pw->scale)), medium, &rng, rays);
}

bool media_visible_point(const Scene *s, Ray ray, int medium, Sampler *rng, const Wavelengths *wl, Color beta,
                         Color *le, MediaVisiblePoint *out, uint64_t *rays)
{
    return media_visible_point_rec(s, ray, medium, rng, wl, beta, le, false, out, rays, NULL);
}

/* explain (rec not NULL): the flight that reached a vertex and the vertex, numbered on from
 * rec->depth (a medium vertex or a surface hit). */
static void record_visible_hit(Recorder *rec, const Scene *s, const MediaHit *h, int medium, Color beta,
                               const Wavelengths *wl)
{
    const bool vol = h->kind == MEDIA_VOLUME;
    /* A flight in vacuum (no medium crossed on the way) is no decision: not listed. */
    if (vol || medium >= 0 || h->fwd != 1.0f) recorder_media_flight(rec, h->p, medium, vol, h->dist, h->fwd, h->rev, beta);
    if (vol) {
        recorder_medium_vertex(rec, h->p, medium, rec->depth + 1);
        CstExplainEvent *e = rec->truncated ? &rec->spare : &rec->ev[rec->n - 1];
        e->q = s->media[medium].g; /* the Henyey-Greenstein asymmetry the estimate evaluates */
    } else {
        recorder_vertex(rec, s, &h->sh, rec->depth + 1, wl);
    }
}

bool media_visible_point_rec(const Scene *s, Ray ray, int medium, Sampler *rng, const Wavelengths *wl, Color beta,
                             Color *le, bool le_media_only, MediaVisiblePoint *out, uint64_t *rays, Recorder *rec)
{
    /* The emission of emitters and of the environment, wanted unless le_media_only. */
    Color *le_surf = le_media_only ? NULL : le;
    SubPath sp = subpath_start(beta);
    sp.specular_only = false;
    HeroMis hm = {-1, color_s(1.0f), false};
    Vec3 x_prev = ray.o;
    for (int depth = 0; depth <= PHOTON_MAX_SPECULAR; depth++) {
        MediaHit h;
        /* The emission of emitting media on the way (volpath.c's estimators, as BDPT's camera
         * walk gathers it): what reaches x after a scattering, the photons that start in the
         * media carry (media_photon_walk). Gathered also when the path ends on this segment. */
        const bool go = media_next(s, ray, x_prev, false, true, &medium, &sp, &hm, rng, wl, &h, rays);
        /* (le NULL: photon's final gather in scenes without emitting media; le_media_only:
         * its gather with them, whose emitters' and environment's light is NEE's or the
         * caustic map's.) Recorded for explain as added (h.le holds the throughput). */
        if (le) {
            if (rec && !color_is_black(h.le)) recorder_media_emission(rec, rec->depth, h.le);
            *le = color_add(*le, h.le);
        }
        if (!go) return false;
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            const Color env = scene_env_radiance(s, ray.d, wl);
            if (le_surf && rec) recorder_add(rec, CST_EXPLAIN_ESCAPE, hero_beta(&hm, sp.beta), env);
            if (le_surf) *le_surf = color_madd(*le_surf, hero_beta(&hm, sp.beta), env);
            return false;
        }
        if (rec) record_visible_hit(rec, s, &h, medium, hero_beta(&hm, sp.beta), wl);
        out->p = h.p;
        out->wo = wo;
        out->medium = medium;
        if (h.kind == MEDIA_VOLUME) {
            out->vol = true;
            out->g = s->media[medium].g;
            out->beta = hero_beta(&hm, sp.beta);
            return true;
        }
        out->vol = false;
        out->sh = h.sh;
        if (h.sh.emitter >= 0 && le_surf) {
            const Color e = scene_emission(s, &h.sh, wo, wl);
            if (rec) recorder_add(rec, CST_EXPLAIN_EMISSION, hero_beta(&hm, sp.beta), e);
            *le_surf = color_madd(*le_surf, hero_beta(&hm, sp.beta), e);
        }
        scene_bsdf(s, &h.sh, wl, &out->bsdf);
        /* photon_trace_to_diffuse's rule for BSDFs with delta and non-delta lobes. */
        float p_delta = bsdf_delta_probability(&out->bsdf, wo);
        out->beta = hero_beta(&hm, sp.beta);
        if (!(p_delta > 0.0f)) return true;
        BsdfSample bs;
        bs.delta = false;
        float uc = sampler_1d(rng);
        Vec2 u = sampler_2d(rng);
        bool sampled = bsdf_sample(&out->bsdf, wo, uc, u, &bs);
        if (!bsdf_is_delta(&out->bsdf) && !bs.delta) {
            if (rec) recorder_mixed(rec, 1.0f - p_delta, out->beta);
            out->beta = color_scale(out->beta, 1.0f / (1.0f - p_delta));
            return color_is_finite(out->beta);
        }
        if (!sampled) return false;
        if (rec) recorder_scatter(rec, &bs, out->beta);
        sp.beta = color_mul(sp.beta, bs.weight);
        sp.scatter = color_mul(sp.scatter, bs.weight);
        if (color_is_black(sp.scatter)) return false;
        medium = scene_medium_after(s, &h.sh, bs.wi, medium);
        ray = ray_make_at(scene_offset(s, h.sh.p, h.sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, ray.time);
        x_prev = h.p;
    }
    return false; /* photon_trace_to_diffuse's cut */
}
