/* The path recorder of `caustic explain` (recorder.h): events in a caller-owned array,
 * the exact lanes of every addition kept beside them so that the sum can be replayed. */
#include "integrators/recorder.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"

#include "integrators/direct.h"
#include "integrators/photon_map.h"
#include "integrators/volpath.h"
#include "media/phase.h"
#include "sampling/pss_sampler.h"

static void put3(float o[3], Vec3 v) { o[0] = v.x; o[1] = v.y; o[2] = v.z; }
static void put_color(float o[3], Color c) { for (int i = 0; i < 3; i++) o[i] = c.c[i]; }

/* The scene formats' names of the material types (docs/scene-format.md). */
static const char *material_type_name(MaterialType t)
{
    switch (t) {
    case MATERIAL_DIFFUSE: return "diffuse";
    case MATERIAL_MIRROR: return "mirror";
    case MATERIAL_GLASS: return "glass";
    case MATERIAL_CONDUCTOR: return "conductor";
    case MATERIAL_DIELECTRIC: return "dielectric";
    case MATERIAL_PLASTIC: return "plastic";
    case MATERIAL_COATED_DIFFUSE: return "coateddiffuse";
    case MATERIAL_COATED_CONDUCTOR: return "coatedconductor";
    case MATERIAL_MIX: return "mix";
    case MATERIAL_DIFFUSE_TRANSMISSION: return "diffusetransmission";
    case MATERIAL_THIN_DIELECTRIC: return "thindielectric";
    case MATERIAL_MEASURED: return "measured";
    case MATERIAL_HAIR: return "hair";
    }
    return "unknown";
}

CstExplainEvent *recorder_push(Recorder *r, CstExplainKind k)
{
    CstExplainEvent *e = &r->spare;
    if (r->n < r->cap) e = &r->ev[r->n++];
    else r->truncated = 1;
    memset(e, 0, sizeof *e);
    e->kind = k;
    e->depth = r->depth;
    e->s = e->t = e->light = -1;
    e->material = e->mix_material = -1;
    e->mis_weight = -1.0f;
    e->mis_explicit = e->mis_sum = -1.0f;
    e->path = -1;
    e->medium = -1;
    return e;
}

void recorder_added(Recorder *r, CstExplainEvent *e, Color beta, Color value)
{
    e->flags |= CST_EXPLAIN_ADDED;
    put_color(e->beta, beta);
    put_color(e->value, value);
    put_color(e->contribution, color_mul(beta, value));
    if (e == &r->spare) return;
    r->beta[e - r->ev] = beta;
    r->value[e - r->ev] = value;
}

void recorder_wavelengths(Recorder *r, const Wavelengths *wl)
{
    if (!wl) return;
    r->wl = *wl;
    r->has_wl = true;
}

/* The camera subpath's hit d just kept: the flight that reached it, through media. */
static void keep_flight(Recorder *r, int d, int medium)
{
    RecorderPaths *rp = &r->paths;
    if (d < 1 || d > RECORDER_PATH_MAX) return;
    rp->cam_medium[d - 1] = medium;
    rp->cam_fwd[d - 1] = rp->cam_rev[d - 1] = 1.0f;
    if (!rp->next_flight) return;
    rp->next_flight = false;
    rp->cam[d - 1].t = rp->next_len;
    rp->cam_fwd[d - 1] = rp->next_fwd;
    rp->cam_rev[d - 1] = rp->next_rev;
}

void recorder_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, int depth, const Wavelengths *wl)
{
    r->depth = depth;
    recorder_wavelengths(r, wl);
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_VERTEX);
    put3(e->p, sh->p);
    put3(e->n, sh->ns);
    put3(e->ng, sh->ng);
    e->material = sh->material;
    if (depth >= 1 && depth <= RECORDER_PATH_MAX) {
        r->paths.cam[depth - 1] = *sh;
        r->paths.cam_dir[depth - 1] = r->paths.next_dir;
        r->paths.cam_delta[depth - 1] = false;
        r->paths.ncam = depth;
        keep_flight(r, depth, -1);
    }
    e->material_type = sh->material >= 0 ? material_type_name(s->materials[sh->material].type) : "none";
    if (sh->material >= 0 && s->materials[sh->material].type == MATERIAL_MIX) {
        /* the same pure function of the hit the integrators' BSDF set-up calls */
        const Material *chosen = scene_mix_choose(s, &s->materials[sh->material], sh);
        e->mix_material = (int)(chosen - s->materials);
        e->mix_material_type = material_type_name(chosen->type);
    }
    e->light = sh->emitter;
}

void recorder_emission(Recorder *r, const SurfaceHit *sh, Vec3 wo, Color beta, Color value, float w,
                       float pdf_bsdf, float pdf_light)
{
    CstExplainEvent *e = recorder_push(r, sh ? CST_EXPLAIN_EMISSION : CST_EXPLAIN_ESCAPE);
    e->mis_weight = w;
    e->pdf_w = pdf_bsdf;
    e->pdf_other_w = pdf_light;
    if (sh) {
        e->light = sh->emitter;
        put3(e->p, sh->p);
        /* The BSDF sample's density at the emitter point per unit area: pdf_w |cos| / d^2. */
        float d2 = sh->t * sh->t;
        e->pdf_a = d2 > 0.0f ? pdf_bsdf * fabsf(v3_dot(sh->ng, wo)) / d2 : 0.0f;
    }
    recorder_added(r, e, beta, value);
}

void recorder_nee(Recorder *r, const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                  Vec2 u, bool mis, Color beta, Color value)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_NEE);
    recorder_added(r, e, beta, value);
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_nee(&s->emitter_sampler, &g, sh->p, sh->ns, u_sel, u, &ls)) return;
    e->light = ls.light;
    put3(e->p, ls.p);
    put3(e->wi, ls.wi);
    e->pdf_w = ls.pdf_w;
    e->pmf = ls.delta ? ls.pmf : light_nee_pmf(&s->emitter_sampler, sh->p, sh->ns, ls.light);
    /* The light point's density per unit area: pdf_w |cos_light| / dist^2. */
    if (!ls.delta && ls.finite && ls.dist > 0.0f)
        e->pdf_a = ls.pdf_w * fabsf(v3_dot(ls.n, ls.wi)) / (ls.dist * ls.dist);
    if (ls.delta) e->flags |= CST_EXPLAIN_DELTA;
    float pdf_bsdf = bsdf_pdf(bsdf, wo, ls.wi);
    e->pdf_other_w = pdf_bsdf;
    e->mis_weight = mis && !ls.delta ? power_heuristic(ls.pdf_w, pdf_bsdf) : 1.0f;
    if (color_is_black(value) && !color_is_black(bsdf_eval(bsdf, wo, ls.wi)) &&
        !scene_visible_at(s, sh->p, sh->ng, ls.p, ls.n, sh->time))
        e->flags |= CST_EXPLAIN_OCCLUDED;
}

/* A NEE event (added: flagged ADDED and summed by the replay) with the light sample drawn
 * again from the render's uniforms at p (shading normal n, zero in a medium): the light, its point and normal (ng), wi, pdf_w,
 * pdf_a and the pick's pmf. NULL (the event without them) when no light was sampled. */
static CstExplainEvent *nee_light_event(Recorder *r, const Scene *s, Vec3 p, Vec3 n, float u_sel, Vec2 u, bool added,
                                        Color beta, Color value, LightLi *ls)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_NEE);
    if (added) {
        recorder_added(r, e, beta, value);
    } else { /* a detail event (whitted's shadow rays): printed, not summed */
        put_color(e->beta, beta);
        put_color(e->value, value);
        put_color(e->contribution, color_mul(beta, value));
    }
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_nee(&s->emitter_sampler, &g, p, n, u_sel, u, ls)) return NULL;
    e->light = ls->light;
    put3(e->p, ls->p);
    put3(e->ng, ls->n);
    put3(e->wi, ls->wi);
    e->pdf_w = ls->pdf_w;
    e->pmf = ls->delta ? ls->pmf : light_nee_pmf(&s->emitter_sampler, p, n, ls->light);
    /* The light point's density per unit area: pdf_w |cos_light| / dist^2. */
    if (!ls->delta && ls->finite && ls->dist > 0.0f)
        e->pdf_a = ls->pdf_w * fabsf(v3_dot(ls->n, ls->wi)) / (ls->dist * ls->dist);
    if (ls->delta) e->flags |= CST_EXPLAIN_DELTA;
    return e;
}

void recorder_vol_nee(Recorder *r, const Scene *s, const VolVertex *v, float u_sel, Vec2 u, bool mis, Color beta,
                      Color value)
{
    LightLi ls;
    CstExplainEvent *e = nee_light_event(r, s, v->p, v->ns, u_sel, u, true, beta, value, &ls);
    if (!e) return;
    /* volpath_nee_u's partner: the BSDF's pdf_w at a surface, the phase function's (which
     * samples itself exactly) in a medium */
    const float other = v->bsdf ? bsdf_pdf(v->bsdf, v->wo, ls.wi) : phase_hg_eval(v->wo, ls.wi, v->g);
    e->pdf_other_w = other;
    e->mis_weight = mis && !ls.delta ? power_heuristic(ls.pdf_w, other) : 1.0f;
    /* The shadow ray's transmittance, traced again as volpath_nee_u traced it (its ratio
     * tracking in grids draws from a hash of the segment, so the same value): shown in
     * transmittance, and OCCLUDED when it is 0 where the BSDF or phase function was not. */
    const Color f = v->bsdf ? bsdf_eval(v->bsdf, v->wo, ls.wi) : color_s(other);
    if (color_is_black(f)) return;
    const int medium = v->sh ? scene_medium_after(s, v->sh, ls.wi, v->medium) : v->medium;
    uint64_t rays = 0;
    const Color tr = scene_transmittance_at(s, v->p, v->ng, ls.p, ls.n, medium, v->time, r->has_wl ? &r->wl : NULL,
                                            &rays);
    put_color(e->transmittance, tr);
    if (color_is_black(tr)) e->flags |= CST_EXPLAIN_OCCLUDED;
}

void recorder_sss_nee(Recorder *r, const Scene *s, const SurfaceHit *x, float u_sel, Vec2 u, bool mis, Color beta,
                      Color value)
{
    LightLi ls;
    CstExplainEvent *e = nee_light_event(r, s, x->p, x->ns, u_sel, u, true, beta, value, &ls);
    if (!e) return;
    /* path_sss.c's partner: the exit's cosine sampling of Sw, cos / pi (0 below the exit) */
    const float cos_s = v3_dot(ls.wi, x->ns);
    const float other = cos_s > 0.0f ? cos_s * CST_INV_PI : 0.0f;
    e->pdf_other_w = other;
    e->mis_weight = mis && !ls.delta ? power_heuristic(ls.pdf_w, other) : 1.0f;
    /* sss_nee traces its shadow ray only for a light above the exit (both normals): the
     * same test, then the same ray */
    if (cos_s > 0.0f && v3_dot(ls.wi, x->ng) > 0.0f && !scene_visible_at(s, x->p, x->ng, ls.p, ls.n, x->time))
        e->flags |= CST_EXPLAIN_OCCLUDED;
}

void recorder_scatter(Recorder *r, const BsdfSample *bs, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SCATTER);
    put3(e->wi, bs->wi);
    e->lobe = bsdf_lobe_name(bs->lobe);
    e->pdf_w = bs->pdf_w;
    e->pmf = bs->pmf;
    if (bs->delta) e->flags |= CST_EXPLAIN_DELTA;
    if (r->depth >= 1 && r->depth <= RECORDER_PATH_MAX) r->paths.cam_delta[r->depth - 1] = bs->delta;
    r->paths.next_dir = bs->wi;
    put_color(e->beta, beta);
    put_color(e->value, bs->weight);
    put_color(e->contribution, color_mul(beta, bs->weight));
}

void recorder_roulette(Recorder *r, float q, bool survived)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_ROULETTE);
    e->q = q;
    if (survived) e->flags |= CST_EXPLAIN_SURVIVED;
}

void recorder_strategy(Recorder *r, CstExplainKind kind, int s_light, int light, Vec3 p, Color beta, Color value,
                       float w, float w_light, float w_camera, float pdf_w, float pdf_a, bool occluded)
{
    CstExplainEvent *e = recorder_push(r, kind);
    e->s = s_light;
    e->t = r->depth + 1; /* the camera subpath's vertices, the lens one included */
    e->light = light;
    put3(e->p, p);
    e->mis_weight = w;
    e->pdf_other_w = w_light;
    e->pdf_other2 = w_camera;
    e->pdf_w = pdf_w;
    e->pdf_a = pdf_a;
    if (occluded) e->flags |= CST_EXPLAIN_OCCLUDED;
    if (r->cam_dispersed) e->flags |= CST_EXPLAIN_HERO;
    recorder_added(r, e, beta, value);
}

void recorder_splat(Recorder *r, float x, float y, int s_light, Vec3 p, Vec3 lens, Color value, float w,
                    float w_light, float pdf_a)
{
    RecorderPaths *rp = &r->paths;
    if (rp->light_on && s_light >= 2 && s_light - 1 == rp->nlight && s_light - 2 < RECORDER_PATH_MAX)
        rp->light_lens[s_light - 2] = lens;
    if (!(fabsf(x - ((float)r->px + 0.5f)) < r->radius && fabsf(y - ((float)r->py + 0.5f)) < r->radius))
        return;
    const int depth = r->depth;
    r->depth = 0;
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SPLAT);
    r->depth = depth;
    e->s = s_light;
    e->t = 1;
    e->path = rp->light_started - 1; /* the light step starts its paths in order (RecorderPaths) */
    put3(e->p, p);
    e->wi[0] = x; /* the raster position, for the reader */
    e->wi[1] = y;
    e->mis_weight = w;
    e->pdf_other_w = w_light;
    e->pdf_a = pdf_a;
    put_color(e->value, value);
    put_color(e->contribution, value);
    e->beta[0] = e->beta[1] = e->beta[2] = 1.0f;
}

void recorder_camera(Recorder *r, Vec3 origin, Vec3 dir, float time, const Wavelengths *wl)
{
    r->paths.camera_time = time;
    recorder_wavelengths(r, wl); /* a camera ray may miss everything */
    r->cam_dispersed = false;
    r->paths.camera_o = origin;
    r->paths.next_dir = dir;
    r->paths.ncam = 0;
}

void recorder_cam_dispersed(Recorder *r, bool dispersed) { r->cam_dispersed = dispersed; }

void recorder_light_dispersed(Recorder *r, bool dispersed)
{
    if (dispersed && r->n > 0) r->ev[r->n - 1].flags |= CST_EXPLAIN_LIGHT_DISPERSED;
}

void recorder_nee_normal(Recorder *r, Vec3 n)
{
    if (r->n > 0 && r->ev[r->n - 1].kind == CST_EXPLAIN_NEE) put3(r->ev[r->n - 1].ng, n);
}

void recorder_light_start(Recorder *r, const EmissionSample *es)
{
    RecorderPaths *p = &r->paths;
    p->light_on = p->light_started++ == p->light_path;
    if (!p->light_on) return;
    p->has_light = true;
    p->start = *es;
    p->nlight = 0;
}

void recorder_light_hit(Recorder *r, const SurfaceHit *sh, Vec3 dir)
{
    RecorderPaths *p = &r->paths;
    if (!p->light_on) return;
    if (p->nlight < RECORDER_PATH_MAX) {
        p->light[p->nlight] = *sh;
        p->light_dir[p->nlight] = dir;
        p->light_delta[p->nlight] = false;
    }
    p->nlight++;
}

/* Whether the light subpath being traced is listed as events (recorder.h, light_events). */
static bool light_listed(const Recorder *r) { return r->light_events && r->paths.light_on; }

void recorder_light_scatter(Recorder *r, const Bsdf *b, const BsdfSample *bs, Vec3 wo, Color beta, int bounces)
{
    RecorderPaths *p = &r->paths;
    if (p->light_on && p->nlight >= 1 && p->nlight <= RECORDER_PATH_MAX) p->light_delta[p->nlight - 1] = bs->delta;
    if (!light_listed(r)) return;
    const int depth = r->depth; /* the camera side's, which later strategies carry */
    const Vec3 next = r->paths.next_dir; /* the camera subpath's, which recorder_scatter sets */
    r->depth = -bounces;
    recorder_scatter(r, bs, beta);
    r->depth = depth;
    r->paths.next_dir = next;
    CstExplainEvent *e = r->truncated ? &r->spare : &r->ev[r->n - 1];
    /* subpath_scatter_rr's reverse density for the MIS ratios (tech. rep. eqs. 34-36) */
    e->pdf_other_w = bs->delta ? bs->pmf : bsdf_pdf(b, bs->wi, wo);
}

void recorder_light_phase(Recorder *r, Vec3 wi, float pdf_w, Color beta, int bounces)
{
    if (!light_listed(r)) return;
    const int depth = r->depth;
    const Vec3 next = r->paths.next_dir; /* the camera subpath's, which recorder_phase sets */
    r->depth = -bounces;
    recorder_phase(r, wi, pdf_w, beta);
    r->depth = depth;
    r->paths.next_dir = next;
    CstExplainEvent *e = r->truncated ? &r->spare : &r->ev[r->n - 1];
    e->pdf_other_w = pdf_w; /* Henyey-Greenstein is symmetric: the reverse density is the same */
}

void recorder_subpath_roulette(Recorder *r, bool light, int bounces, float q, bool survived)
{
    if (!light) {
        recorder_roulette(r, q, survived);
        return;
    }
    if (!light_listed(r)) return;
    const int depth = r->depth;
    r->depth = -bounces;
    recorder_roulette(r, q, survived);
    r->depth = depth;
}

void recorder_photon_chain(Recorder *r, Color beta)
{
    for (int i = r->n - 1; i >= 0; i--)
        if (r->ev[i].kind == CST_EXPLAIN_VERTEX) {
            put_color(r->ev[i].beta, beta); /* shown; the replay takes it from NEE's event */
            return;
        }
}

int recorder_depth(const Recorder *r) { return r->depth; }

void recorder_photon(Recorder *r, const Photon *ph, Color f)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_PHOTON);
    put3(e->p, ph->pos);
    put3(e->wi, ph->wi);
    put_color(e->beta, f);
    put_color(e->value, ph->power);
    put_color(e->contribution, color_mul(f, ph->power));
    if (e == &r->spare) return;
    r->beta[e - r->ev] = f;
    r->value[e - r->ev] = ph->power;
}

/* An estimate's time window (recorder_estimate). */
static void put_window(CstExplainEvent *e, const float window[3])
{
    e->time_window[0] = window[0];
    e->time_window[1] = window[1];
    e->time_scale = window[2];
}

void recorder_estimate(Recorder *r, bool caustic, float radius, Color g, Color est, const float window[3])
{
    int count = 0;
    while (count < r->n && r->ev[r->n - 1 - count].kind == CST_EXPLAIN_PHOTON) count++;
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_ESTIMATE);
    if (caustic) e->flags |= CST_EXPLAIN_CAUSTIC;
    e->distance = radius;
    e->pmf = window[2] / (CST_PI * radius * radius); /* the kernel the estimate used */
    e->path = count;
    put_window(e, window);
    recorder_added(r, e, g, est);
}

void recorder_volume_estimate(Recorder *r, float radius, float kernel, Color beta, Color sigma_s, Color li,
                              Color out, const float window[3])
{
    int count = 0;
    while (count < r->n && r->ev[r->n - 1 - count].kind == CST_EXPLAIN_PHOTON) count++;
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_ESTIMATE);
    e->flags |= CST_EXPLAIN_VOLUME | CST_EXPLAIN_ADDED;
    e->distance = radius;
    e->pmf = kernel;
    e->path = count;
    put_window(e, window);
    put_color(e->beta, beta);
    put_color(e->value, li);
    put_color(e->contribution, out);
    put_color(e->transmittance, sigma_s); /* shown as sigma_s (its RGB lanes) */
    if (e == &r->spare) return;
    r->beta[e - r->ev] = beta;
    r->value[e - r->ev] = sigma_s; /* the replay divides by it, lane by lane */
}

/* The throughput of the whitted node at depth d: 1 at the camera's hit, else its branch's. */
static Color tree_beta(const Recorder *r, int d);

void recorder_whitted_light(Recorder *r, const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                            Vec2 u, Color value)
{
    LightLi ls;
    CstExplainEvent *e = nee_light_event(r, s, sh->p, sh->ns, u_sel, u, false, tree_beta(r, r->depth), value, &ls);
    if (!e) return;
    e->pdf_other_w = bsdf_pdf(bsdf, wo, ls.wi);
    e->mis_weight = 1.0f; /* direct_light: no MIS */
    /* direct_light traces the shadow ray only where f is not black: the same ray again */
    if (!color_is_black(bsdf_eval(bsdf, wo, ls.wi)) && !scene_visible_at(s, sh->p, sh->ng, ls.p, ls.n, sh->time))
        e->flags |= CST_EXPLAIN_OCCLUDED;
}

static Color tree_beta(const Recorder *r, int d)
{
    return d >= 2 && d <= RECORDER_PATH_MAX + 1 ? r->tree_beta[d] : color_s(1.0f);
}

void recorder_whitted(Recorder *r, CstExplainKind kind, int depth, Color value)
{
    r->depth = depth;
    CstExplainEvent *e = recorder_push(r, kind);
    e->mis_weight = 1.0f;
    recorder_added(r, e, tree_beta(r, depth), value);
}

void recorder_whitted_branch(Recorder *r, const BsdfSample *bs, Color w, int depth)
{
    r->depth = depth;
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SCATTER);
    put3(e->wi, bs->wi);
    e->lobe = bsdf_lobe_name(bs->lobe);
    e->pmf = bs->pmf;
    e->flags |= CST_EXPLAIN_DELTA;
    Color beta = tree_beta(r, depth);
    put_color(e->beta, beta);
    put_color(e->value, w);
    put_color(e->contribution, color_mul(beta, w));
    if (e != &r->spare) r->value[e - r->ev] = w; /* the replay's branch weight */
    if (depth + 1 <= RECORDER_PATH_MAX + 1) r->tree_beta[depth + 1] = color_mul(beta, w);
}

void recorder_merge(Recorder *r, Vec3 p, int light_bounces, Color beta, Color value, float vm_norm, float w,
                    float w_light, float w_camera, bool dispersed)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_MERGE);
    if (r->cam_dispersed) e->flags |= CST_EXPLAIN_HERO;
    if (dispersed) e->flags |= CST_EXPLAIN_LIGHT_DISPERSED;
    e->s = light_bounces + 1; /* the light vertices, the merged one included */
    e->t = r->depth + 1;
    put3(e->p, p);
    e->mis_weight = w;
    e->pdf_other_w = w_light;
    e->pdf_other2 = w_camera;
    e->pmf = vm_norm;
    recorder_added(r, e, beta, value); /* exact lanes, unnormalised: the replay's */
    Color shown = color_scale(value, vm_norm);
    put_color(e->value, shown);
    put_color(e->contribution, color_mul(beta, shown));
}

void recorder_sss_exit(Recorder *r, const SurfaceHit *x, float pdf_a, int count, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_VERTEX);
    put3(e->p, x->p);
    put3(e->n, x->ns);
    put3(e->ng, x->ng);
    e->material = x->material;
    e->material_type = "subsurface exit";
    e->pdf_a = pdf_a;
    e->pmf = count > 0 ? 1.0f / (float)count : 0.0f;
    put_color(e->beta, beta);
}

void recorder_sss_scatter(Recorder *r, Vec3 wi, float pdf_w, float w, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SCATTER);
    put3(e->wi, wi);
    e->lobe = "subsurface exit";
    e->pdf_w = pdf_w;
    put_color(e->beta, beta);
    put_color(e->value, color_s(w));
    put_color(e->contribution, color_scale(beta, w));
}

void recorder_distance(Recorder *r, int medium, const MediumCoeffs *mc, bool hetero, Ray ray, float t_max,
                       const MediumSample *ms)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_DISTANCE);
    e->medium = medium;
    e->distance = ms->scattered ? ms->t : t_max;
    put3(e->p, ray_at(&ray, ms->scattered ? ms->t : fminf(t_max, 3.0e38f)));
    put3(e->wi, ray.d);
    if (ms->scattered) e->flags |= CST_EXPLAIN_SCATTERED;
    if (!hetero && isfinite(e->distance)) {
        Color tr = medium_transmittance(mc, e->distance);
        put_color(e->transmittance, tr);
        /* The mixture over lanes (medium.h): pdf(t) = 1/4 sum_c sigma_t[c] Tr_c per unit
         * length when it scattered, P(t >= t_max) = 1/4 sum_c Tr_c when it passed. */
        float pdf = 0.0f;
        for (int c = 0; c < COLOR_LANES; c++) pdf += (ms->scattered ? mc->sigma_t.c[c] : 1.0f) * tr.c[c];
        e->pdf_w = pdf / (float)COLOR_LANES;
    }
    put_color(e->value, ms->weight);
}

void recorder_medium_vertex(Recorder *r, Vec3 p, int medium, int depth)
{
    r->depth = depth;
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_VERTEX);
    put3(e->p, p);
    e->medium = medium;
    e->material_type = "medium";
    if (depth >= 1 && depth <= RECORDER_PATH_MAX) { /* for the MIS check (subpath_media.c) */
        r->paths.cam[depth - 1] = (SurfaceHit){.p = p, .material = -1, .emitter = -1};
        r->paths.cam_dir[depth - 1] = r->paths.next_dir;
        r->paths.cam_delta[depth - 1] = false;
        r->paths.ncam = depth;
        keep_flight(r, depth, medium);
    }
}

void recorder_add(Recorder *r, CstExplainKind kind, Color beta, Color value)
{
    recorder_added(r, recorder_push(r, kind), beta, value);
}

void recorder_media_strategy(Recorder *r, CstExplainKind kind, int s_light, int light, Vec3 p, Vec3 n, Color beta,
                             Color value, float w, float w_light, float w_camera, float pdf_w, float pdf_a,
                             const Color *tr, float chain_fwd, float chain_rev)
{
    r->paths.media = true;
    recorder_strategy(r, kind, s_light, light, p, beta, value, w, w_light, w_camera, pdf_w, pdf_a, tr == NULL);
    CstExplainEvent *e = r->truncated ? &r->spare : &r->ev[r->n - 1];
    put3(e->ng, n);
    if (tr) put_color(e->transmittance, *tr);
    e->chain_fwd = chain_fwd;
    e->chain_rev = chain_rev;
}

void recorder_media_light_hit(Recorder *r, const SurfaceHit *sh, Vec3 p, int medium, Vec3 dir, float dist, float fwd,
                              float rev)
{
    RecorderPaths *rp = &r->paths;
    if (!rp->light_on) return;
    rp->media = true;
    const int b = rp->nlight;
    SurfaceHit at = {.p = p, .material = -1, .emitter = -1};
    recorder_light_hit(r, sh ? sh : &at, dir);
    if (b >= RECORDER_PATH_MAX) return;
    rp->light[b].t = dist;
    rp->light_medium[b] = sh ? -1 : medium;
    rp->light_fwd[b] = fwd;
    rp->light_rev[b] = rev;
}

void recorder_media_light_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, Vec3 p, int medium, int bounces)
{
    if (!r->light_vertices && !light_listed(r)) return;
    if (sh) {
        recorder_light_vertex(r, s, sh, bounces);
        return;
    }
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_VERTEX);
    e->depth = -bounces;
    put3(e->p, p);
    e->medium = medium;
    e->material_type = "medium";
}

void recorder_media_splat(Recorder *r, float x, float y, int s_light, Vec3 p, Vec3 lens, Color value, float w,
                          float w_light, float pdf_a, float fwd, float rev)
{
    const int n = r->n;
    recorder_splat(r, x, y, s_light, p, lens, value, w, w_light, pdf_a);
    if (r->n == n || r->truncated) return;
    r->ev[r->n - 1].chain_fwd = fwd;
    r->ev[r->n - 1].chain_rev = rev;
}

void recorder_media_flight(Recorder *r, Vec3 p, int medium, bool volume, float dist, float fwd, float rev, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_DISTANCE);
    e->medium = medium;
    e->distance = dist;
    put3(e->p, p);
    if (volume) e->flags |= CST_EXPLAIN_SCATTERED;
    e->chain_fwd = fwd;
    e->chain_rev = rev;
    put_color(e->beta, beta);
    RecorderPaths *rp = &r->paths;
    rp->media = true;
    rp->next_flight = true;
    rp->next_fwd = fwd;
    rp->next_rev = rev;
    rp->next_len = dist;
}


void recorder_media_emission(Recorder *r, int depth, Color value)
{
    const int d = r->depth;
    r->depth = depth;
    recorder_strategy(r, CST_EXPLAIN_EMISSION, 0, -1, v3s(0.0f), color_s(1.0f), value, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f,
                      false);
    r->depth = d;
}

void recorder_merge_norm(Recorder *r, Color norm)
{
    const int d = r->depth;
    if (d < 0 || d > RECORDER_PATH_MAX + 1) {
        r->truncated = 1; /* the replay could not normalise these merges */
        return;
    }
    r->merge_norm[d] = norm;
    r->merge_vol[d] = true;
    for (int i = r->n - 1; i >= 0 && r->ev[i].depth == d; i--) {
        CstExplainEvent *e = &r->ev[i];
        if (e->kind != CST_EXPLAIN_MERGE) continue;
        e->pmf = norm.c[0];
        Color shown = color_mul(r->value[i], norm);
        put_color(e->value, shown);
        put_color(e->contribution, color_mul(r->beta[i], shown));
    }
}

void recorder_phase(Recorder *r, Vec3 wi, float pdf_w, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SCATTER);
    put3(e->wi, wi);
    e->pdf_w = pdf_w;
    e->material_type = "phase";
    e->lobe = "phase function";
    r->paths.next_dir = wi;
    put_color(e->beta, beta);
    put_color(e->value, color_s(1.0f));
    put_color(e->contribution, beta);
}

void recorder_mixed(Recorder *r, float prob, Color beta)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_SCATTER);
    e->lobe = "delta split";
    e->pmf = prob;
    put_color(e->beta, beta);
    const Color w = color_s(1.0f / prob);
    put_color(e->value, w);
    put_color(e->contribution, color_mul(beta, w));
}

void recorder_sppm_photon(Recorder *r, Vec3 p, Vec3 wi, Color power, Color f, Color d, int path, int depth,
                          float dist)
{
    CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_PHOTON);
    put3(e->p, p);
    put3(e->wi, wi);
    e->path = path;
    e->s = depth;
    e->distance = dist;
    put_color(e->beta, f);
    put_color(e->value, power);
    put_color(e->contribution, d);
    if (e == &r->spare) return;
    r->beta[e - r->ev] = f;
    r->value[e - r->ev] = d; /* the replay sums d, the render's own product */
}

/* The sample of the MUTATION event just pushed (index r->n - 1): its vector's values. */
static void keep_mlt_sample(Recorder *r, const PssSampler *pss, bool proposal, int depth, Color L)
{
    if (r->truncated || r->n == 0 || !pss) return;
    if (!array_grow(&r->mlt, &r->mlt_cap, r->mlt_n + 1, sizeof *r->mlt) ||
        !array_grow(&r->mlt_pool, &r->mlt_pool_cap, r->mlt_pool_n + pss->n, sizeof *r->mlt_pool)) {
        r->mlt_oom = true;
        return;
    }
    double *v = &r->mlt_pool[r->mlt_pool_n];
    for (size_t i = 0; i < pss->n; i++) {
        const PssValue *x = &pss->x[i];
        /* pss_next dated what the proposal read with this iteration, its old value kept in
         * backup (pss_reject restores it): the current state read the old values. */
        v[i] = !proposal && x->modified == pss->iteration ? x->backup : x->value;
    }
    r->mlt[r->mlt_n++] = (RecorderMltSample){r->n - 1, depth, r->mlt_pool_n, pss->n, L};
    r->mlt_pool_n += pss->n;
}

void recorder_mlt_free(Recorder *r)
{
    free(r->mlt);
    free(r->mlt_pool);
    r->mlt = NULL;
    r->mlt_pool = NULL;
    r->mlt_n = r->mlt_cap = r->mlt_pool_n = r->mlt_pool_cap = 0;
}

void recorder_light_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, int bounces)
{
    if (!r->light_vertices && !light_listed(r)) return;
    const int depth = r->depth; /* the camera side's, which later strategies carry */
    recorder_vertex(r, s, sh, -bounces, NULL);
    r->depth = depth;
}

void recorder_mlt_step(Recorder *r, int chain, int step, int length, bool large, bool accepted, float a,
                       const RecorderMltSplat sp[2], const PssSampler *pss)
{
    for (int k = 0; k < 2; k++) {
        const RecorderMltSplat *s = &sp[k];
        if (s->index < 0) continue;
        if (!(fabsf(s->fp.x - ((float)r->px + 0.5f)) < r->radius && fabsf(s->fp.y - ((float)r->py + 0.5f)) < r->radius))
            continue;
        CstExplainEvent *e = recorder_push(r, CST_EXPLAIN_MUTATION);
        e->flags = (k == 0 ? CST_EXPLAIN_PROPOSAL : 0) | (large ? CST_EXPLAIN_LARGE_STEP : 0) |
                   (accepted ? CST_EXPLAIN_ACCEPTED : 0);
        e->chain = chain;
        e->step = step;
        e->path_length = length;
        if (s->s >= 0 && length >= 0) { /* mmlt: the BDPT strategy (s, t) of the path length */
            e->s = s->s;
            e->t = length + 2 - s->s;
        }
        e->path = (int)s->index;
        e->accept = a;
        e->importance = s->I;
        e->weight = s->weight;
        e->wi[0] = s->fp.x;
        e->wi[1] = s->fp.y;
        put_color(e->value, s->L);
        e->beta[0] = e->beta[1] = e->beta[2] = s->weight;
        put_color(e->contribution, color_scale(s->L, s->weight));
        keep_mlt_sample(r, pss, k == 0, length, s->L);
    }
}
