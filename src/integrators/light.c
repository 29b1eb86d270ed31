/* Light tracer: Veach thesis ch. 10 (the t = 1 strategies of bidirectional path tracing,
 * here without MIS); pbrt-v4 LightPathIntegrator. A light path y0 (on an emitter), y1, ...
 * with throughput beta_j connects every non-delta vertex y_j to a point on the lens:
 *   splat = beta_j f(y_j: w_cam <- w_prev) |cos theta_cam| W_e / pdf_w   (j >= 1)
 *   splat = L_e(y0 -> w_cam) |cos theta_cam| W_e / (pdf_a pdf_w)           (j = 0)
 * with V(y_j, lens) = 1; W_e / pdf_w = 1 / (A cos^3 theta d^2) (camera.c). The path is
 * the one light subpath walk (subpath.h) that BDPT, VCM and the photon passes take too. */
#include "integrators/light.h"

#include "film/filter.h"
#include "integrators/subpath_media.h"
#include "integrators/subpath_walk.h"
#include "materials/bsdf.h"

/* What the camera connections of one light path need. */
typedef struct LightTraceCtx {
    const Scene *s;
    const Camera *cam;
    const LightParams *lp;
    float margin; /* the tent reaches half a pixel past the film's edge (film_splat) */
    SplatList *out;
    const Wavelengths *wl; /* spectral mode: the path's; NULL in RGB mode */
    uint64_t *rays;
    float time;            /* the path's time (motion blur; 0 in static scenes) */
} LightTraceCtx;

/* Splats weight * W_e / pdf_w if the lens point is visible; weight already holds the
 * throughput and the vertex's f |cos theta_cam| (or L_e |cos theta_cam|). */
static void splat_if_visible(const LightTraceCtx *c, Vec3 p, Vec3 ng, const CameraWiSample *cs, Color weight)
{
    if (color_is_black(weight)) return;
    ++*c->rays;
    if (!scene_visible_point_at(c->s, p, ng, cs->p_lens, c->time)) return;
    Color v = color_scale(weight, cs->we / cs->pdf_w);
    film_splat(c->out, &c->lp->frame, cs->raster.x, cs->raster.y, c->wl ? spectrum_to_rgb(v, c->wl) : v);
}

/* The walk's visitor: y_j (j >= 1) connected to the lens point drawn for it. */
static bool connect_to_camera(void *ctx, const LightVertex *v)
{
    const LightTraceCtx *c = ctx;
    const SurfaceHit *sh = v->sh;
    CameraWiSample cs;
    float cos_prev = fabsf(v3_dot(sh->ng, v->w_prev));
    if (camera_sample_wi(c->cam, sh->p, v->u_lens, c->margin, &cs) && cos_prev > 0.0f) {
        /* The camera path through this vertex evaluates f(wo = w_cam, wi = w_prev)
         * |cos theta_prev|; the connection wants |cos theta_cam| instead (the geometry
         * term toward the lens). Evaluated that way round rather than relying on
         * reciprocity, so a non-reciprocal lobe would stay right. */
        Color f = bsdf_eval(v->bsdf, cs.wi, v->w_prev);
        f = color_scale(f, fabsf(v3_dot(sh->ng, cs.wi)) / cos_prev);
        splat_if_visible(c, sh->p, sh->ng, &cs, color_mul(v->sp.beta, f));
    }
    return true;
}

void light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng,
                 SplatList *out, uint64_t *rays)
{
    /* Participating media: the walk through media (subpath_media.c; emitting media may be
     * the only lights); one branch for the others. */
    if (s->num_media | s->num_medium_ifaces) {
        media_light_trace(s, cam, lp, rng, out, rays);
        return;
    }
    if (s->emitter_sampler.lights == 0) return;
    /* Spectral mode: the path's own wavelengths, from its first random number. */
    Wavelengths wl;
    if (lp->spectral) wl = wavelengths_sample(sampler_1d(rng));
    /* Motion blur: the light path's own time, uniform over the shutter (drawn only in
     * scenes that move: static ones keep their streams); its connections reach the camera
     * where that time places it. */
    const float time = scene_has_motion(s) ? camera_time(cam, sampler_1d(rng)) : 0.0f;
    Camera placed;
    if (cam->moving) {
        placed = camera_at(cam, time);
        cam = &placed;
    }
    LightTraceCtx c = {s, cam, lp, filter_radius(lp->frame.filter) - 0.5f, out, lp->spectral ? &wl : NULL, rays,
                       time};
    EmissionSample es;
    subpath_emit(s, rng, c.wl, &es);
    es.time = time;

    /* y0 seen directly: the only way this estimator renders visible emitters (delta
     * lights are never seen, nor is the environment: it is no surface a connection could
     * reach). */
    CameraWiSample cs;
    Vec2 u_lens = sampler_2d(rng);
    /* (not from an emitter's alpha-cut-away surface: subpath_emit zeroed that start's flux) */
    bool cut = s->num_alphas && !es.delta && es.finite && scene_emitter_cut(s, es.emitter, es.p);
    if (!es.delta && es.finite && !cut && camera_sample_wi(cam, es.p, u_lens, c.margin, &cs)) {
        const Emitter *e = &s->emitter_sampler.light[es.emitter].u.area;
        Color le = scene_emitter_color(s, es.emitter, emitter_radiance(e, s->textures, es.n, es.uv, cs.wi), c.wl);
        splat_if_visible(&c, es.p, es.n, &cs, color_scale(le, fabsf(v3_dot(es.n, cs.wi)) / es.pdf_a));
    }
    if (!(es.pdf_w > 0.0f)) return;

    /* beta = L_e |cos theta_0| / (pdf_a pdf_w) (or a delta light's, light.c): the flux a
     * path carries. Russian roulette looks at the product of the BSDF weights (and 1/q),
     * which is what the path tracer's beta is: beta's flux scale would keep every path
     * alive (roulette.h). */
    const LightWalk w = {lp->max_depth, lp->rr_depth, NULL, true, c.wl, connect_to_camera, &c,
                         lp->spectral ? &wl : NULL};
    subpath_walk_light(s, &w, &es, subpath_start(es.beta), rng, rays);
}
