/* Photon mapping after Jensen 2001 (ch. 5-9) with the map split of Jensen & Christensen
 * 1998. The scheme, chosen so every light path is counted exactly once:
 *   photon pass: photon paths start on emitters with flux
 *     Phi = L_e |cos theta_0| / (pdf_a pdf_w) / N
 *   (one of N samples of the emitted power, Jensen 2001 sec. 5.1: the sum's expectation
 *   is pi L_e A for a one-sided Lambertian area emitter, 2 pi L_e A two-sided), are traced with
 *   importance-mode BSDF sampling and Russian roulette, and leave a copy at every
 *   non-delta hit: all of them go to the global map (paths L (S|D)* D), those whose path
 *   so far is L S+ D also to the caustic map.
 *   camera pass: follow delta lobes from the camera, adding emission seen through them;
 *   at the first non-delta point x add
 *     direct light by NEE (emitters seen straight from x: L D),
 *     the caustic map's density estimate at x (L S+ D),
 *     one final-gather ray: BSDF-sampled from x, through delta bounces, to the first
 *     non-delta point y, weighted by the global map's estimate at y (... D S* x).
 *   A gather ray that reaches an emitter adds nothing: that light is NEE's or the
 *   caustic map's at x.
 * Scenes with media add a volume map (Jensen & Christensen 1998; photon_li_media), whose
 * emitting media start photon paths too (media_lights.h) and are gathered by the camera's
 * and the final gather's walks (photon_li_media), and
 * spectral mode splits the photons into sets at wavelengths of their own (set_wavelengths);
 * docs/integrators.md has both schemes. */
#include "integrators/photon.h"

#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "integrators/direct.h"
#include "integrators/media_lights.h"
#include "integrators/recorder.h"
#include "integrators/subpath_media.h"
#include "integrators/subpath_walk.h"
#include "integrators/volpath.h"
#include "integrators/volume_ball.h"
#include "materials/bsdf.h"
#include "media/phase.h"

/* Stream ids: the photon pass and the radius probes draw from (seed, index, id), disjoint
 * from the camera samples' (seed, pixel, sample) for any sample index below 2^62. */
#define PHOTON_STREAM ((uint64_t)1 << 62)
#define RADIUS_STREAM (((uint64_t)1 << 62) + 1u)
/* Spectral mode: set k's photons draw from the stream PHOTON_STREAM + 2 + k. */
#define PHOTON_SET_STREAM (((uint64_t)1 << 62) + 2u)

static inline bool scene_has_media(const Scene *s) { return s->num_media || s->num_medium_ifaces; }

typedef ARRAY(Photon) PhotonArray;

static int photon_array_push(PhotonArray *a, const Photon *ph)
{
    return array_push(a, *ph);
}

/* photon_walk's visitor: the photon at a vertex, handed to the caller's PhotonVisit. */
typedef struct PhotonWalkCtx {
    PhotonVisit visit;
    void *ctx;
    float time;
    const Scene *scene; /* photon maps of moving geometry (pw->shutter): photon_to_rest; else NULL
                         * (SPPM's photons stay in world space, at the iteration's instant) */
} PhotonWalkCtx;

/* A photon that landed on a moving instance moves into the instance's rest frame (Photon.inst):
 * the surface point keeps its photons wherever the surface is at their times. */
static void photon_to_rest(const Scene *s, const SurfaceHit *sh, Photon *ph)
{
    ph->inst = -1;
    Transform rest, back, nm;
    if (sh->prim != UINT32_MAX || !scene_geometry_moves(s) ||
        !instances_rest_frame(s->instances, sh->inst, ph->time, &rest, &back, &nm))
        return;
    ph->inst = sh->inst;
    ph->pos = transform_point(&rest, ph->pos);
    ph->wi = v3_normalize(transform_vector(&rest, ph->wi));
    ph->n = transform_normal(&nm, ph->n);
}

static bool photon_at_vertex(void *ctx, const LightVertex *v)
{
    const PhotonWalkCtx *c = ctx;
    Vec3 ng = v->sh->ng;
    Photon ph;
    ph.pos = v->sh->p;
    ph.wi = v->w_prev;
    ph.power = v->sp.beta;
    ph.n = v3_dot(ng, v->w_prev) >= 0.0f ? ng : v3_neg(ng);
    ph.time = c->time;
    ph.inst = -1;
    if (c->scene) photon_to_rest(c->scene, v->sh, &ph);
    return c->visit(c->ctx, &ph, v->bounces, v->sp.specular_only);
}

bool photon_walk(const Scene *s, const PhotonWalk *pw, uint64_t index, PhotonVisit visit, void *ctx, uint64_t *rays)
{
    Sampler rng;
    sampler_start_stream(&rng, pw->seed, index, pw->stream);
    const float time = photon_walk_time(pw, &rng);
    EmissionSample es;
    subpath_emit(s, &rng, pw->wl, &es);
    es.time = time;
    if (!(es.pdf_w > 0.0f) || !(es.pdf_a > 0.0f)) return true; /* still one of the N */
    /* es.beta = L_e |cos| / (pdf_a pdf_w) for an area emitter: cosine-weighted directions
     * (pdf_w = |cos| / pi, or half that per side when two-sided) make every photon of a
     * uniform emitter carry the same flux, L_e pi A / N one-sided, L_e 2 pi A / N
     * two-sided, summing to the emitted power; delta lights likewise (light.c). The walk
     * is the light tracer's (subpath.h), so photons and light paths follow the same paths
     * (Russian roulette by the BSDF weights, not Jensen 2001 sec. 5.4's absorption
     * probability: unbiased, the power scaled by 1/q). */
    PhotonWalkCtx c = {visit, ctx, time, pw->shutter ? s : NULL};
    const LightWalk w = {pw->max_depth, pw->rr_depth, NULL, false, pw->wl, photon_at_vertex, &c, NULL};
    return subpath_walk_light(s, &w, &es, subpath_start(color_scale(es.beta, pw->scale)), &rng, rays);
}

/* The photon maps' store: every non-delta hit to the global map, and L S+ D ones, past
 * the first hit, to the caustic map too. */
typedef struct PhotonStore {
    PhotonArray *global, *caustic, *volume;
    const Scene *scene;
} PhotonStore;

static bool store_photon(void *ctx, const Photon *ph, int depth, bool specular_only)
{
    PhotonStore *st = ctx;
    if (!photon_array_push(st->global, ph)) return false;
    /* depth 1 is direct light (L D), which NEE handles at camera points. */
    return !(specular_only && depth > 1) || photon_array_push(st->caustic, ph);
}

/* store_photon through media (media_photon_walk): surface photons as above (a path with a
 * medium vertex is not a caustic one); volume photons (n = 0) past the first vertex to the
 * volume map: the first, L V, is NEE's at a medium vertex.
 * A path that started in an emitting medium at z0 (mp->medium_start) is stored from its
 * first vertex on: NEE samples the emitters only, so z0 V (the first volume vertex) is the
 * volume map's to count, and z0 S* D (the first surface vertex) the global map's. It never
 * goes to the caustic map: z0 S* x at a camera point x is the final gather's, which adds
 * the emission of the media it passes (photon_li_media; docs/integrators.md). */
static bool store_media_photon(void *ctx, const MediaPhoton *mp)
{
    PhotonStore *st = ctx;
    Photon ph = {mp->p, mp->wi, mp->power, mp->n, mp->time, -1};
    if (mp->sh) photon_to_rest(st->scene, mp->sh, &ph);
    const bool vol = mp->n.x == 0.0f && mp->n.y == 0.0f && mp->n.z == 0.0f;
    if (vol) ph.inst = mp->medium; /* photon_map.h: a volume photon's medium */
    if (vol) return (mp->bounces <= 1 && !mp->medium_start) || photon_array_push(st->volume, &ph);
    if (mp->medium_start) return photon_array_push(st->global, &ph);
    return store_photon(ctx, &ph, mp->bounces, mp->specular_only);
}

/* Follows delta lobes from `ray` (sampling one lobe at each; weights into *beta) to the
 * first non-delta hit; mixed BSDFs as photon.h says. Adds the emission it passes (and the
 * hit's) to *le when le is not NULL. *wo_out is the direction back along the last segment.
 * Returns false if the ray leaves the scene or the chain stops. */
bool photon_trace_to_diffuse(const Scene *s, Ray ray, Sampler *rng, const Wavelengths *wl, Color *beta, Color *le,
                             SurfaceHit *sh, Bsdf *bsdf, Vec3 *wo_out, uint64_t *rays, struct Recorder *rec)
{
    for (int depth = 0; depth <= PHOTON_MAX_SPECULAR; depth++) {
        ++*rays;
        if (!scene_intersect(s, &ray, sh)) {
            /* The environment seen from the camera, directly or through the chain. */
            if (le) {
                const Color env = scene_env_radiance(s, ray.d, wl);
                if (rec) recorder_add(rec, CST_EXPLAIN_ESCAPE, *beta, env);
                *le = color_madd(*le, *beta, env);
            }
            return false;
        }
        Vec3 wo = v3_neg(ray.d);
        if (rec) recorder_vertex(rec, s, sh, depth + 1, wl);
        if (le && sh->emitter >= 0) {
            const Color e = scene_emission(s, sh, wo, wl);
            if (rec) recorder_add(rec, CST_EXPLAIN_EMISSION, *beta, e);
            *le = color_madd(*le, *beta, e);
        }
        scene_bsdf(s, sh, wl, bsdf);
        float p_delta = bsdf_delta_probability(bsdf, wo);
        if (!(p_delta > 0.0f)) {
            *wo_out = wo;
            return true;
        }
        BsdfSample bs;
        bs.delta = false; /* a delta lobe that was taken but rejected sets it (bsdf.h) */
        float uc = sampler_1d(rng);
        Vec2 u = sampler_2d(rng);
        bool sampled = bsdf_sample(bsdf, wo, uc, u, &bs);
        if (!bsdf_is_delta(bsdf) && !bs.delta) {
            /* A BSDF with delta and non-delta lobes (smooth-coat plastic): bsdf_sample
             * took the non-delta part with probability 1 - p_delta, so this is the point
             * whose non-delta part the caller estimates, weighted by 1 / (1 - p_delta); the
             * other branch follows the delta lobe below (its weight holds 1 / p_delta). */
            if (rec) recorder_mixed(rec, 1.0f - p_delta, *beta);
            *beta = color_scale(*beta, 1.0f / (1.0f - p_delta));
            *wo_out = wo;
            return color_is_finite(*beta);
        }
        if (!sampled) return false;
        if (rec) recorder_scatter(rec, &bs, *beta);
        *beta = color_mul(*beta, bs.weight);
        if (color_is_black(*beta)) return false;
        ray = ray_make_at(scene_offset(s, sh->p, sh->ng, bs.wi), bs.wi, 0.0f, INFINITY, sh->time);
    }
    /* Cut after PHOTON_MAX_SPECULAR delta bounces: a bias of at most the throughput left,
     * which for Fresnel-weighted glass chains is negligible. */
    return false;
}

/* Motion blur in scenes with moving instances (Cammarano & Jensen 2002, "Time Dependent
 * Photon Mapping"): each photon path has its own time, uniform over the shutter, and an
 * estimate at time t counts only the photons within a window [t - h, t + h] (clipped to
 * the shutter), scaled by shutter length / window length: a box kernel in time, so the
 * estimate is the flux density averaged over the window, consistent as h (and r) fall.
 * A gather point on static geometry averages the window out over its own times exactly
 * but at the shutter's ends; one on moving geometry sees the light blurred over 2h. The
 * window is 1 / PHOTON_TIME_WINDOWS of the shutter, and the automatic radii widen so a
 * gather still holds about PHOTON_RADIUS_K of the window's photons (choose_radii). */
typedef struct TimeWindow {
    float t, h;  /* centre and half-width; h = 0: every photon counts (no scaling) */
} TimeWindow;

static inline bool time_outside(TimeWindow w, const Photon *ph)
{
    return w.h > 0.0f && !(fabsf(ph->time - w.t) <= w.h);
}

/* The window of a camera sample at time t, and the factor its estimates take. */
static TimeWindow time_window(const PhotonMaps *m, float t, float *scale)
{
    *scale = 1.0f;
    if (!(m->time_h > 0.0f)) return (TimeWindow){t, 0.0f};
    const float lo = fmaxf(t - m->time_h, m->shutter_open), hi = fminf(t + m->time_h, m->shutter_close);
    *scale = hi > lo ? (m->shutter_close - m->shutter_open) / (hi - lo) : 0.0f;
    return (TimeWindow){t, m->time_h};
}

/* explain: the window of an estimate at time t as [lo, hi] (0, 0 when nothing moves) and
 * its factor, for the recorder (the estimate's kernel is that factor / (pi r^2)). */
static void estimate_window(const PhotonMaps *m, float t, float w[3])
{
    const TimeWindow tw = time_window(m, t, &w[2]);
    w[0] = w[1] = 0.0f;
    if (tw.h > 0.0f) {
        w[0] = fmaxf(t - tw.h, m->shutter_open);
        w[1] = fminf(t + tw.h, m->shutter_close);
    }
}

typedef struct DensityCtx {
    const Bsdf *bsdf;
    Vec3 wo, n; /* n: x's geometric normal, on wo's side */
    Color sum;
    struct Recorder *rec; /* explain (NULL in renders) */
    TimeWindow tw;
    /* The photons' frame: inst -1 world; else x's moving instance, whose photons are in its
     * rest frame: n_ph is n there, and world_from_rest takes their wi back to x's time. */
    int32_t inst;
    Vec3 n_ph;
    Transform world_from_rest;
} DensityCtx;

/* One photon's share at x: wi its direction in world space (c->n_ph: x's normal in the
 * photon's frame, for the side test). */
static inline void density_add(DensityCtx *c, const Photon *ph, Vec3 wi)
{
    /* A photon on the other side of a thin wall must not light this side, unless this
     * surface transmits (rough glass is lit through itself). */
    if (!(v3_dot(ph->n, c->n_ph) > 0.0f) && !bsdf_has_transmission(c->bsdf)) return;
    float cos_i = fabsf(v3_dot(c->n, wi));
    if (!(cos_i > 0.0f)) return;
    /* bsdf_eval is f |cos theta_i|; the photon's flux already holds the projected area. */
    Color f = color_scale(bsdf_eval(c->bsdf, c->wo, wi), 1.0f / cos_i);
    c->sum = color_madd(c->sum, f, ph->power);
    if (c->rec) recorder_photon(c->rec, ph, f);
}

/* Maps without a time window (nothing moves): every photon is in world space. */
static void density_visit(void *ctx, const Photon *ph, float dist2)
{
    (void)dist2;
    density_add(ctx, ph, ph->wi);
}

/* Maps of moving geometry: the photons of x's frame (world, or x's instance's rest frame)
 * and of its time window only; a rest-frame photon's direction back in world space. */
static void density_visit_moving(void *ctx, const Photon *ph, float dist2)
{
    (void)dist2;
    DensityCtx *c = ctx;
    if (ph->inst != c->inst || time_outside(c->tw, ph)) return;
    density_add(c, ph, c->inst < 0 ? ph->wi : v3_normalize(transform_vector(&c->world_from_rest, ph->wi)));
}

/* Reflected radiance at sh toward wo: L = sum f(wo, wi_p) Phi_p / (pi r^2), the constant
 * (box) kernel density estimate of Jensen 2001 eq. 7.6. */
static Color radiance_estimate(const Scene *s, const PhotonMaps *m, const PhotonMap *map, float r,
                               const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, struct Recorder *rec)
{
    if (photon_map_count(map) == 0) return color_s(0.0f);
    float scale;
    const TimeWindow tw = time_window(m, sh->time, &scale);
    const Vec3 n = v3_dot(sh->ng, wo) >= 0.0f ? sh->ng : v3_neg(sh->ng);
    DensityCtx c = {bsdf, wo, n, color_s(0.0f), rec, tw, -1, n, transform_identity()};
    Vec3 q = sh->p;
    Transform rest, nm;
    if (m->time_h > 0.0f && sh->prim == UINT32_MAX &&
        instances_rest_frame(s->instances, sh->inst, sh->time, &rest, &c.world_from_rest, &nm)) {
        c.inst = sh->inst;
        c.n_ph = transform_normal(&nm, n);
        q = transform_point(&rest, q);
    }
    photon_map_radius(map, q, r, m->time_h > 0.0f ? density_visit_moving : density_visit, &c);
    return color_scale(c.sum, scale / (CST_PI * r * r));
}

/* Direct light at a non-delta point by one emitter sample (path.c's NEE, without MIS:
 * BSDF-sampled rays that reach emitters add nothing here). */
Color photon_direct_light(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, Sampler *rng,
                        const Wavelengths *wl, uint64_t *rays)
{
    float u_sel = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    return direct_light(s, bsdf, sh, wo, u_sel, u, wl, rays);
}

/* The surface integrator of scenes without media (the file comment's scheme). */
static Color photon_li_surface(const Scene *s, const PhotonMaps *m, const PhotonSet *set, Ray ray, Sampler *rng,
                               const Wavelengths *wl, uint64_t *rays)
{
    Color L = color_s(0.0f), beta = color_s(1.0f);
    SurfaceHit x;
    Bsdf bsdf_x;
    Vec3 wo;
    /* explain: the chain's vertices, delta scatters and emission itemised (m->rec) */
    const bool diffuse = photon_trace_to_diffuse(s, ray, rng, wl, &beta, &L, &x, &bsdf_x, &wo, rays, m->rec);
    if (m->rec && diffuse) recorder_photon_chain(m->rec, beta);
    if (!diffuse) return L;

    Color lx = photon_direct_light(s, &bsdf_x, &x, wo, rng, wl, rays);
    if (m->rec) recorder_add(m->rec, CST_EXPLAIN_NEE, beta, lx);
    Color caustic = radiance_estimate(s, m, &set->caustic, m->radius, &bsdf_x, &x, wo, m->rec);
    float win[3] = {0.0f, 0.0f, 1.0f};
    if (m->rec) estimate_window(m, x.time, win);
    if (m->rec) recorder_estimate(m->rec, true, m->radius, color_s(1.0f), caustic, win);
    lx = color_add(lx, caustic);

    /* Final gathering (Jensen 2001 sec. 9.3.3): the global map's blur is hidden behind one
     * more bounce; reading it at x directly would show its low-frequency noise. */
    BsdfSample bs;
    float uc = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    /* Only the non-delta part of x is estimated here (photon_trace_to_diffuse follows a
     * mixed BSDF's delta lobes itself): a delta gather sample adds nothing. Its weight
     * f / pdf has the probability of the non-delta lobes in pdf, so the estimate stays
     * that of the non-delta part alone. */
    if (bsdf_sample(&bsdf_x, wo, uc, u, &bs) && !bs.delta) {
        Color g = bs.weight;
        if (m->rec) recorder_scatter(m->rec, &bs, beta);
        SurfaceHit y;
        Bsdf bsdf_y;
        Vec3 wo_y;
        Ray gr = ray_make_at(scene_offset(s, x.p, x.ng, bs.wi), bs.wi, 0.0f, INFINITY, ray.time);
        /* Emission the gather ray meets is not added (le = NULL): see the header. */
        if (photon_trace_to_diffuse(s, gr, rng, wl, &g, NULL, &y, &bsdf_y, &wo_y, rays, NULL)) {
            if (m->rec) recorder_vertex(m->rec, s, &y, recorder_depth(m->rec) + 1, NULL); /* after x */
            Color global = radiance_estimate(s, m, &set->global, m->radius, &bsdf_y, &y, wo_y, m->rec);
            if (m->rec) estimate_window(m, y.time, win);
            if (m->rec) recorder_estimate(m->rec, false, m->radius, g, global, win);
            lx = color_add(lx, color_mul(g, global));
        }
    }
    return color_madd(L, beta, lx);
}

/* ------------------------------------------------------------ participating media */

typedef struct VolumeCtx {
    Vec3 wo;
    float g;
    int medium; /* x's: photons of other media are not x's (Photon.inst of a volume photon) */
    Color sum;
    TimeWindow tw;
    struct Recorder *rec; /* explain (NULL in renders) */
} VolumeCtx;

static void volume_visit(void *ctx, const Photon *ph, float dist2)
{
    (void)dist2;
    VolumeCtx *c = ctx;
    if (ph->inst != c->medium || time_outside(c->tw, ph)) return;
    const Color f = color_s(phase_hg_eval(c->wo, ph->wi, c->g));
    c->sum = color_madd(c->sum, f, ph->power);
    if (c->rec) recorder_photon(c->rec, ph, f);
}

/* In-scattered radiance from the volume map at a medium vertex, times the vertex's
 * throughput beta, which holds sigma_s(p) (its free-flight sample's weight): Jensen &
 * Christensen 1998 eq. 11, L_i(p, wo) = (1 / sigma_s(p)) sum_j f_p(wo, wi_j) Phi_j /
 * ((4/3) pi r^3) over the photons in the ball of radius r (each photon's flux holds the
 * sigma_s of its own free-flight sample), so the 1 / sigma_s(p) here cancels beta's
 * sigma_s(p), as SPPM's visible points in media (sppm.c, camera_media). */
static Color volume_estimate(const Scene *s, const PhotonMaps *m, const PhotonMap *map, float r,
                             const MediaVisiblePoint *v, float time, const Wavelengths *wl, struct Recorder *rec,
                             uint64_t *rays)
{
    if (photon_map_count(map) == 0) {
        const float none[3] = {0.0f, 0.0f, 1.0f};
        if (rec) recorder_volume_estimate(rec, r, 0.0f, v->beta, color_s(0.0f), color_s(0.0f), color_s(0.0f), none);
        return color_s(0.0f);
    }
    float scale;
    VolumeCtx c = {v->wo, v->g, v->medium, color_s(0.0f), time_window(m, time, &scale), rec};
    const size_t found = photon_map_radius(map, v->p, r, volume_visit, &c);
    /* The kernel over the ball's part inside the medium (issue 27: photons exist only
     * there; volume_ball.c), folded into beta (so explain's replay, beta sum kernel /
     * sigma_s, sums it again bit for bit); its rays only when a photon was found. */
    const Color beta = found ? color_scale(v->beta, 1.0f / volume_ball_fraction(s, v->p, r, time, rays)) : v->beta;
    const Medium *med = &s->media[v->medium];
    const MediumCoeffs mc = medium_coeffs(med, wl);
    const float dens = medium_is_hetero(med) ? hetero_density_world(&med->u.het, v->p) : 1.0f;
    const float inv_vol = scale / (4.0f / 3.0f * CST_PI * r * r * r);
    Color out, sigma_s, li;
    for (int k = 0; k < COLOR_LANES; k++) {
        const float ss = mc.sigma_s.c[k] * dens;
        sigma_s.c[k] = ss;
        out.c[k] = ss > 0.0f ? beta.c[k] * c.sum.c[k] * inv_vol / ss : 0.0f;
        li.c[k] = ss > 0.0f ? c.sum.c[k] * inv_vol / ss : 0.0f; /* explain's display only */
    }
    if (rec) {
        float win[3];
        estimate_window(m, time, win);
        recorder_volume_estimate(rec, r, inv_vol, beta, sigma_s, li, out, win);
    }
    return out;
}

/* Direct light at a media vertex (volpath's NEE without MIS: transmittance by ratio
 * tracking), times the vertex's throughput. */
static Color media_direct(const Scene *s, const MediaVisiblePoint *v, float time, Sampler *rng,
                          const Wavelengths *wl, uint64_t *rays, struct Recorder *rec)
{
    if (s->emitter_sampler.lights == 0) return color_s(0.0f);
    VolVertex x = {v->p, v3s(0.0f), v3s(0.0f), v->wo, NULL, NULL, v->g, v->medium, time};
    if (!v->vol) x = (VolVertex){v->sh.p, v->sh.ns, v->sh.ng, v->wo, &v->bsdf, &v->sh, 0.0f, v->medium, time};
    const Color nee = volpath_nee(s, &x, false, rng, wl, rays);
    if (rec) recorder_add(rec, CST_EXPLAIN_NEE, v->beta, nee); /* the light sample not itemised */
    return color_mul(v->beta, nee);
}

/* The scheme through media (Jensen & Christensen 1998, with the surface part as above):
 * the camera ray walks media by free-flight sampling (delta tracking in grids, as volpath)
 * and delta lobes to its first vertex x, in a medium or on a non-delta surface
 * (media_visible_point). In a medium: NEE at x (L V) plus the volume map at x (every
 * photon that scattered before reaching x: L (S|D|V)+ V). On a surface: NEE, the caustic
 * map (L S+ D, no medium vertex between), and one final-gather ray, which walks media the
 * same way to its first vertex y and takes y's estimate of every path with at least one
 * vertex before y: the global map on a surface, NEE plus the volume map in a medium. Each
 * light path is counted once: by where its last non-delta vertex before x lies.
 * Emitting media (m->media_emit): both walks add the emission of the media they pass
 * (volpath.c's free-flight estimators of sigma_a Le), so a path that starts at a point z0
 * of a medium is counted by the camera walk when z0 is x (or a tentative collision on the
 * way to x), by the gather when z0 is y (or on the way: z0 S* x), and otherwise by a
 * photon that started at z0: the volume map at x or y (z0 ... V, its first vertex
 * included, as NEE samples emitters only) or the global map at y (z0 ... D). */
static Color photon_li_media(const Scene *s, const PhotonMaps *m, const PhotonSet *set, Ray ray, Sampler *rng,
                             const Wavelengths *wl, uint64_t *rays)
{
    Color L = color_s(0.0f);
    MediaVisiblePoint x;
    /* explain (rec): the walks' flights, vertices and delta scatters, each addition with the
     * throughput it is multiplied by; explain.c's replay_photon_media sums them again. */
    struct Recorder *rec = m->rec;
    if (rec) rec->depth = 0;
    if (!media_visible_point_rec(s, ray, s->camera_medium, rng, wl, color_s(1.0f), &L, false, &x, rays, rec))
        return L;
    L = color_add(L, media_direct(s, &x, ray.time, rng, wl, rays, rec));
    if (x.vol) return color_add(L, volume_estimate(s, m, &set->volume, m->vol_radius, &x, ray.time, wl, rec, rays));
    Color caustic = radiance_estimate(s, m, &set->caustic, m->radius, &x.bsdf, &x.sh, x.wo, rec);
    float win[3] = {0.0f, 0.0f, 1.0f};
    if (rec) estimate_window(m, x.sh.time, win);
    if (rec) recorder_estimate(rec, true, m->radius, x.beta, caustic, win);
    L = color_madd(L, x.beta, caustic);
    BsdfSample bs;
    float uc = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    if (!bsdf_sample(&x.bsdf, x.wo, uc, u, &bs) || bs.delta) return L;
    if (rec) recorder_scatter(rec, &bs, x.beta);
    Ray gr = ray_make_at(scene_offset(s, x.sh.p, x.sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, ray.time);
    const int medium = scene_medium_after(s, &x.sh, bs.wi, x.medium);
    /* The emitters' and the environment's light the gather meets is NEE's or the caustic
     * map's at x, not added; emitting media's on the way is added (media_emit: z0 S* x, the
     * paths the media-started photons leave out of the caustic map; store_media_photon). */
    MediaVisiblePoint y;
    if (!media_visible_point_rec(s, gr, medium, rng, wl, color_mul(x.beta, bs.weight), m->media_emit ? &L : NULL,
                                 true, &y, rays, rec))
        return L;
    if (y.vol) {
        L = color_add(L, media_direct(s, &y, ray.time, rng, wl, rays, rec));
        return color_add(L, volume_estimate(s, m, &set->volume, m->vol_radius, &y, ray.time, wl, rec, rays));
    }
    Color global = radiance_estimate(s, m, &set->global, m->radius, &y.bsdf, &y.sh, y.wo, rec);
    if (rec) estimate_window(m, y.sh.time, win);
    if (rec) recorder_estimate(rec, false, m->radius, y.beta, global, win);
    return color_madd(L, y.beta, global);
}

Color photon_li(const Scene *s, const PhotonMaps *m, int set, Ray ray, Sampler *rng, uint64_t *rays)
{
    if (m->num_sets == 0) return color_s(0.0f);
    const PhotonSet *ps = &m->sets[set];
    const Wavelengths *wl = m->spectral ? &ps->wl : NULL;
    if (m->rec) recorder_wavelengths(m->rec, wl); /* explain: spectral mode's conversion */
    if (scene_has_media(s)) return photon_li_media(s, m, ps, ray, rng, wl, rays);
    return photon_li_surface(s, m, ps, ray, rng, wl, rays);
}

int photon_maps_pick(const PhotonMaps *m, float u)
{
    if (m->num_sets <= 1) return 0;
    int k = (int)(u * (float)m->num_sets);
    return k < m->num_sets - 1 ? k : m->num_sets - 1;
}

void photon_maps_free(PhotonMaps *m)
{
    if (!m) return;
    for (int k = 0; k < m->num_sets; k++) {
        photon_map_free(&m->sets[k].global);
        photon_map_free(&m->sets[k].caustic);
        photon_map_free(&m->sets[k].volume);
    }
    free(m->sets);
    memset(m, 0, sizeof *m);
}

static int cmp_float(const void *a, const void *b)
{
    float x = *(const float *)a, y = *(const float *)b;
    return (x > y) - (x < y);
}

/* Squared distance to the k-th nearest photon of the global map around p (fewer when the
 * map holds fewer than k). */
static float knn_dist2(const PhotonMap *map, Vec3 p)
{
    const Photon *found[PHOTON_RADIUS_K];
    float d2[PHOTON_RADIUS_K];
    int n = photon_map_knn(map, p, PHOTON_RADIUS_K, INFINITY, found, d2);
    return n > 0 ? d2[n - 1] : 0.0f;
}

/* The median, over up to PHOTON_RADIUS_POINTS of the map's own photons, of the distance
 * to the PHOTON_RADIUS_K-th nearest one; 1 for an empty map. */
static float self_radius(const PhotonMap *g)
{
    float d2[PHOTON_RADIUS_POINTS];
    int n = 0;
    size_t count = photon_map_count(g);
    size_t stride = count / PHOTON_RADIUS_POINTS + 1;
    for (size_t i = 0; i < count && n < PHOTON_RADIUS_POINTS; i += stride) {
        float v = knn_dist2(g, g->photons[i].pos);
        if (v > 0.0f) d2[n++] = v;
    }
    if (n == 0) return 1.0f; /* no photons, or every photon at one point */
    qsort(d2, (size_t)n, sizeof d2[0], cmp_float);
    return sqrtf(d2[n / 2]);
}

/* The automatic radius: the median, over PHOTON_RADIUS_POINTS first non-delta hits of
 * random camera rays, of the distance to the PHOTON_RADIUS_K-th nearest global photon,
 * so a typical visible point gathers about PHOTON_RADIUS_K photons (Jensen 2001 sec. 7.2
 * gathers a fixed count; a fixed radius keeps the estimate a plain box-kernel average).
 * When no camera ray finds a surface, the photons themselves are the probe points. A
 * moving camera probes from where it stands at shutter open (its frame alone is the camera
 * in its own space, camera.h); the rays carry time 0, as the photons (a heuristic only). */
static float auto_radius(const Scene *s, const Camera *moving, const PhotonParams *pp, const PhotonMap *g,
                         uint64_t *rays)
{
    Camera placed;
    const Camera *cam = moving;
    if (moving->moving) {
        placed = camera_at(moving, moving->shutter_open);
        cam = &placed;
    }
    float d2[PHOTON_RADIUS_POINTS];
    int n = 0;
    size_t count = photon_map_count(g);
    if (count == 0) return 1.0f; /* nothing to estimate: any radius gives zero */
    for (int i = 0; i < PHOTON_RADIUS_POINTS; i++) {
        Sampler rng;
        sampler_start_stream(&rng, pp->seed, (uint64_t)i, RADIUS_STREAM);
        float fx = sampler_1d(&rng) * (float)cam->width, fy = sampler_1d(&rng) * (float)cam->height;
        Vec2 ul = sampler_2d(&rng);
        Ray r = camera_generate_ray(cam, fx, fy, ul);
        Color beta = color_s(1.0f);
        SurfaceHit sh;
        Bsdf b;
        Vec3 wo;
        if (!photon_trace_to_diffuse(s, r, &rng, NULL, &beta, NULL, &sh, &b, &wo, rays, NULL)) continue;
        float v = knn_dist2(g, sh.p);
        if (v > 0.0f) d2[n++] = v;
    }
    if (n == 0) return self_radius(g);
    qsort(d2, (size_t)n, sizeof d2[0], cmp_float);
    return sqrtf(d2[n / 2]);
}

/* The radii of this render: the given one for both estimates, or the automatic ones, from
 * set 0 (in spectral mode each set holds 1 / PHOTON_SPECTRAL_SETS of the photons, so the
 * automatic radii are those of one set). The volume ball's automatic radius holds about
 * PHOTON_RADIUS_K volume photons around a typical volume photon. */
static void choose_radii(const Scene *s, const Camera *cam, const PhotonParams *pp, PhotonMaps *m, uint64_t *rays)
{
    const PhotonSet *set = &m->sets[0];
    m->radius = pp->radius > 0.0f ? pp->radius : auto_radius(s, cam, pp, &set->global, rays);
    m->vol_radius = pp->radius > 0.0f ? pp->radius : self_radius(&set->volume);
    if (m->time_h > 0.0f && !(pp->radius > 0.0f)) {
        /* A time window holds 1 / PHOTON_TIME_WINDOWS of the photons: the disc's area and
         * the ball's volume grow by that factor so they keep about PHOTON_RADIUS_K. */
        m->radius *= sqrtf((float)PHOTON_TIME_WINDOWS);
        m->vol_radius *= cbrtf((float)PHOTON_TIME_WINDOWS);
    }
}

/* One set's photon paths: n of them from stream `stream`, at wavelengths wl (NULL: RGB). */
static CstStatus build_set(const Scene *s, const Camera *cam, const PhotonParams *pp, uint64_t stream, int n,
                           const Wavelengths *wl, PhotonSet *out, double done, double part, uint64_t *rays,
                           CstError *err)
{
    PhotonArray global = {0}, caustic = {0}, volume = {0};
    CstStatus st = CST_OK;
    /* Emitting media (pp->media_lights): paths start in them too, as SPPM's photons. */
    const MediaLights *ml = pp->no_media ? NULL : pp->media_lights;
    if (s->emitter_sampler.lights > 0 || ml) {
        /* Moving geometry: each path its own time over the shutter (the static scene's
         * streams stay as they were: no time is drawn there). */
        const PhotonWalk pw = {pp->seed, stream, 1.0f / (float)n, pp->max_depth, pp->rr_depth, wl, 0.0f,
                               scene_geometry_moves(s) ? cam : NULL, ml};
        PhotonStore store = {&global, &caustic, &volume, s};
        for (int i = 0; i < n; i++) {
            if (pp->progress && i % PHOTON_PROGRESS_EVERY == 0 &&
                pp->progress(pp->progress_user, done + part * (double)i / n)) {
                st = cst_fail(err, CST_ERR_CANCELLED, "render cancelled by the progress callback");
                goto done;
            }
            const bool ok = scene_has_media(s) && !pp->no_media
                                ? media_photon_walk(s, cam, &pw, (uint64_t)i, store_media_photon, &store, rays)
                                : photon_walk(s, &pw, (uint64_t)i, store_photon, &store, rays);
            if (!ok) {
                st = cst_fail(err, CST_ERR_OOM, "out of memory for %zu photons", global.n + caustic.n + volume.n);
                goto done;
            }
        }
    }
    if ((st = photon_map_build(&out->global, global.v, global.n, err)) != CST_OK) goto done;
    if ((st = photon_map_build(&out->caustic, caustic.v, caustic.n, err)) != CST_OK) goto done;
    st = photon_map_build(&out->volume, volume.v, volume.n, err);
done:
    array_free(&global);
    array_free(&caustic);
    array_free(&volume);
    return st;
}

/* Spectral mode: set k's wavelengths, stratified over the sets as SPPM's over its
 * iterations (wavelengths_pass_u, offset from a stream of its own). A camera sample picks
 * a set uniformly, so each render is an unbiased estimate (in the limit r -> 0) of the
 * spectral image; within one render the PHOTON_SPECTRAL_SETS x 4 wavelengths are shared by
 * all pixels (a colour error correlated over the image, falling with the set count). */
static Wavelengths set_wavelengths(uint64_t seed, int k)
{
    Pcg32 r;
    pcg32_seed_sample(&r, seed ^ 0x85ebca6b27d4eb2fULL, 0, 0);
    return wavelengths_sample(wavelengths_pass_u((uint32_t)k, pcg32_next(&r)));
}

CstStatus photon_maps_build(const Scene *s, const Camera *cam, const PhotonParams *pp, PhotonMaps *out,
                            uint64_t *rays, CstError *err)
{
    memset(out, 0, sizeof *out);
    const int n = pp->photons > 0 ? pp->photons : PHOTON_DEFAULT_COUNT;
    const int sets = pp->spectral ? PHOTON_SPECTRAL_SETS : 1;
    /* Each set emits n / sets paths (at least one). */
    const int per_set = n / sets > 0 ? n / sets : 1;
    out->sets = calloc((size_t)sets, sizeof *out->sets);
    if (!out->sets) return cst_fail(err, CST_ERR_OOM, "out of memory for %d photon sets", sets);
    out->num_sets = sets;
    out->spectral = pp->spectral;
    for (int k = 0; k < sets; k++) {
        PhotonSet *set = &out->sets[k];
        /* RGB keeps the single map's stream (its images bit for bit). */
        const uint64_t stream = pp->spectral ? PHOTON_SET_STREAM + (uint64_t)k : PHOTON_STREAM;
        if (pp->spectral) set->wl = set_wavelengths(pp->seed, k);
        CstStatus st = build_set(s, cam, pp, stream, per_set, pp->spectral ? &set->wl : NULL, set,
                                 (double)k / sets, 1.0 / sets, rays, err);
        if (st != CST_OK) {
            photon_maps_free(out);
            return st;
        }
    }
    out->emitted = per_set;
    out->media_emit = pp->media_lights != NULL && !pp->no_media;
    if (scene_geometry_moves(s)) {
        out->shutter_open = cam->shutter_open;
        out->shutter_close = cam->shutter_close;
        out->time_h = (cam->shutter_close - cam->shutter_open) / (2.0f * PHOTON_TIME_WINDOWS);
    }
    choose_radii(s, cam, pp, out, rays);
    return CST_OK;
}

/* ------------------------------------------------------------ the cache between renders */

/* The cache: the maps of one build and what they were built from. */
struct CstPhotonCache {
    bool valid;
    const Scene *scene;
    int photons, max_depth, rr_depth;
    uint64_t seed;
    bool spectral;
    int builds;
    PhotonMaps maps; /* radius: the build's, not used (each render chooses its own) */
};

CstPhotonCache *cst_photon_cache_create(void) { return calloc(1, sizeof(CstPhotonCache)); }

void cst_photon_cache_destroy(CstPhotonCache *c)
{
    if (!c) return;
    photon_maps_free(&c->maps);
    free(c);
}

size_t cst_photon_cache_positions(const CstPhotonCache *c, int caustic, float *xyz, size_t max)
{
    if (!c || !c->valid || c->maps.num_sets == 0) return 0;
    const PhotonMap *m = caustic ? &c->maps.sets[0].caustic : &c->maps.sets[0].global;
    for (size_t i = 0; i < m->count && i < max; i++) {
        xyz[3 * i] = m->photons[i].pos.x;
        xyz[3 * i + 1] = m->photons[i].pos.y;
        xyz[3 * i + 2] = m->photons[i].pos.z;
    }
    return m->count;
}

int cst_photon_cache_builds(const CstPhotonCache *c) { return c ? c->builds : 0; }

CstStatus photon_maps_build_cached(CstPhotonCache *c, const Scene *s, const Camera *cam, const PhotonParams *pp,
                                   PhotonMaps *out, bool *borrowed, uint64_t *rays, CstError *err)
{
    *borrowed = false;
    if (!c) return photon_maps_build(s, cam, pp, out, rays, err);
    const bool same = c->valid && c->scene == s && c->photons == pp->photons && c->max_depth == pp->max_depth &&
                      c->rr_depth == pp->rr_depth && c->seed == pp->seed && c->spectral == pp->spectral;
    if (!same) {
        photon_maps_free(&c->maps);
        c->valid = false;
        CstStatus st = photon_maps_build(s, cam, pp, &c->maps, rays, err);
        if (st != CST_OK) return st;
        c->valid = true;
        c->scene = s;
        c->photons = pp->photons;
        c->max_depth = pp->max_depth;
        c->rr_depth = pp->rr_depth;
        c->seed = pp->seed;
        c->spectral = pp->spectral;
        c->builds++;
    }
    *out = c->maps;
    *borrowed = true;
    /* The radii as photon_maps_build picks them, from this render's camera. */
    choose_radii(s, cam, pp, out, rays);
    return CST_OK;
}
