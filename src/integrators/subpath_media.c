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
 * Emissive media: gathered by BDPT's and VCM's camera walks with weight 1 (see
 * media_subpath_trace_camera); refused for the light tracer, MMLT and SPPM. VCM merges volume
 * vertices by UPBP's point-point 3D estimator (1 / ((4/3) pi r^3 N); media_merge). Motion
 * blur: every ray carries its path's time (walks keep the time of the ray they continue;
 * connections take the camera vertex's or the light subpath's); media do not move. */
#include "integrators/subpath_media.h"

#include <math.h>

#include "core/array.h"
#include "core/rng.h"
#include "film/filter.h"
#include "integrators/subpath_walk.h"
#include "media/phase.h"

/* Boundary crossings in a row before a walk or a connection gives up (volpath.c's bound). */
enum { MEDIA_MAX_CROSSINGS = 256 };

/* The distance-sampling densities of a straight chain of pieces from a vertex a to a
 * vertex b (pieces split by boundary shapes, each in one medium or vacuum): fwd is the
 * density with which a walk from a makes b (the product of the pass probabilities of every
 * piece before b's, times b's piece's free-flight density at b if b is in a medium, or its
 * pass probability if b is a surface); rev the same from b back to a. Vacuum pieces count 1. */
typedef struct ChainPdf {
    int pieces;
    float first_pass, first_pdf; /* the piece at a: pass probability, density at a */
    float last_pass, last_pdf;   /* the piece at b: pass probability, density at b */
    float mid;                   /* pass probabilities of the pieces between */
} ChainPdf;

/* A piece with its pass probability and its free-flight densities at its start (pdf_a,
 * the density of a walk from its far end stopping there) and at its end (pdf_b); they
 * differ in a grid medium only. */
static inline void chain_add(ChainPdf *c, float pass, float pdf_a, float pdf_b)
{
    if (c->pieces == 0) {
        c->first_pass = pass;
        c->first_pdf = pdf_a;
    }
    if (c->pieces >= 2) c->mid *= c->last_pass;
    c->last_pass = pass;
    c->last_pdf = pdf_b;
    c->pieces++;
}

/* fwd and rev of a finished chain; a_med / b_med: the end is a medium vertex. */
static inline void chain_pdfs(const ChainPdf *c, bool a_med, bool b_med, float *fwd, float *rev)
{
    if (c->pieces <= 1) {
        *fwd = c->pieces ? (b_med ? c->last_pdf : c->first_pass) : 1.0f;
        *rev = c->pieces ? (a_med ? c->first_pdf : c->first_pass) : 1.0f;
        return;
    }
    *fwd = c->first_pass * c->mid * (b_med ? c->last_pdf : c->last_pass);
    *rev = c->last_pass * c->mid * (a_med ? c->first_pdf : c->first_pass);
}

/* Optical depths above this (in the largest lane) count as this in the MIS densities of
 * grid media: e^-20 keeps the recursion's squared ratios (subpath.h's mis) inside float. */
#define MEDIA_GRID_MIS_DEPTH 20.0f

/* A piece o + t dir, t in [0, len], in medium m (-1 vacuum): its pass probability and
 * densities; a_vertex / b_vertex: its start / end is a volume vertex (else that density is
 * not used). Homogeneous media: medium.h's exact densities (the balance heuristic over the
 * lanes, as medium_sample_distance samples). Grid and cloud media: delta tracking's true
 * density of stopping at x, sigma_t(x) Tr(0, x), is the expectation of a random process
 * nobody can evaluate exactly; MIS needs only densities that every strategy computes the
 * same way for the same path (the weights then still sum to 1 and each strategy's estimator
 * stays unbiased, Veach's thesis sec. 9.2.2: any weights summing to 1 over the strategies
 * that can make the path). So a grid piece uses the majorant's transmittance in place of
 * Tr, mean_c exp(-sigma_t[c] tau_maj), with the real sigma_t(x) = density(x) sigma_t at a
 * vertex: the densities pbrt-v4's volpath weighs NEE with, and Miller et al. 2019's
 * null-scattering path pdf summed over no null vertex. tau_maj is deterministic and the
 * same for the piece walked either way, so a walk, the reverse walk and a connection all
 * see the same value. */
static void chain_piece(ChainPdf *c, const Scene *s, const MediumCoeffs *mc, int m, Vec3 o, Vec3 dir, float len,
                        bool a_vertex, bool b_vertex)
{
    if (m < 0) {
        chain_add(c, 1.0f, 0.0f, 0.0f);
        return;
    }
    const Medium *med = &s->media[m];
    if (!medium_is_hetero(med)) {
        float pdf = medium_distance_pdf(mc, len);
        chain_add(c, medium_pass_prob(mc, len), pdf, pdf);
        return;
    }
    const HeteroMedium *h = &med->u.het;
    float tau = hetero_majorant_depth(h, o, dir, len);
    const float smax = color_max(mc->sigma_t);
    if (smax * tau > MEDIA_GRID_MIS_DEPTH) tau = MEDIA_GRID_MIS_DEPTH / smax;
    const float pd = medium_distance_pdf(mc, tau);
    const float pdf_a = a_vertex ? hetero_density_world(h, o) * pd : 0.0f;
    const float pdf_b = b_vertex ? hetero_density_world(h, v3_add(o, v3_scale(dir, len))) * pd : 0.0f;
    chain_add(c, medium_pass_prob(mc, tau), pdf_a, pdf_b);
}

/* A connection from p (normal n_p; 0 in a medium) to q (n_q likewise; q_med: q is a
 * volume vertex, not a surface or the lens), leaving p in medium `medium`: its transmittance (black when a surface other than a boundary is in
 * the way) and its chain densities. */
typedef struct MediaSegment {
    Color tr;
    float fwd, rev; /* ChainPdf's, for q made from p and p from q */
} MediaSegment;

static bool media_connect(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, bool q_med, int medium, float time,
                          const Wavelengths *wl, MediaSegment *out, uint64_t *rays)
{
    Vec3 d = v3_sub(q, p);
    Vec3 o = scene_offset(s, p, n_p, d); /* a zero normal leaves the point where it is */
    const Vec3 end = scene_offset(s, q, n_q, v3_neg(d));
    ChainPdf c = {0, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f};
    Color tr = color_s(1.0f);
    for (int step = 0; step < MEDIA_MAX_CROSSINGS; step++) {
        Vec3 od = v3_sub(end, o);
        float len = v3_length(od);
        if (!(len > 0.0f)) break;
        Vec3 dir = v3_scale(od, 1.0f / len);
        Ray r = ray_make_at(o, dir, 0.0f, len * (1.0f - 1e-5f), time);
        SurfaceHit sh;
        ++*rays;
        bool hit = scene_intersect(s, &r, &sh);
        float piece = hit ? sh.t : len;
        MediumCoeffs mc = {0};
        if (medium >= 0) {
            const Medium *m = &s->media[medium];
            mc = medium_coeffs(m, wl);
            if (medium_is_hetero(m)) {
                /* Ratio tracking (unbiased per lane, Novak et al. 2014), its random
                 * stream a hash of the piece as scene_transmittance's; the MIS densities
                 * of the piece are chain_piece's majorant-based ones, not this estimate. */
                const float seg[6] = {o.x, o.y, o.z, end.x, end.y, end.z};
                uint64_t seed = 0x3c6ef372fe94f82bULL + (uint64_t)step;
                for (int i = 0; i < 6; i++) {
                    union { float f; uint32_t u; } b = {seg[i]};
                    seed = mix64(seed ^ b.u);
                }
                tr = color_mul(tr, hetero_transmittance(&m->u.het, &mc, o, dir, piece, seed));
            } else {
                tr = color_mul(tr, medium_transmittance(&mc, piece));
            }
        }
        chain_piece(&c, s, &mc, medium, o, dir, piece, step == 0 && v3_length2(n_p) == 0.0f, !hit && q_med);
        if (!hit) {
            out->tr = tr;
            chain_pdfs(&c, v3_length2(n_p) == 0.0f, q_med, &out->fwd, &out->rev);
            return !color_is_black(tr);
        }
        const MediumInterface *mi = scene_hit_medium_iface(s, &sh);
        if (!mi || !mi->boundary || color_is_black(tr)) return false;
        medium = v3_dot(dir, sh.ng) < 0.0f ? mi->inside : mi->outside;
        o = scene_offset(s, sh.p, sh.ng, dir);
    }
    return false;
}

/* The medium at point q as a ray from the camera's origin sees it: starting in the
 * camera's medium, switched at every interface shape on the way (as a camera path tracks
 * it). Light subpaths start from it: lights carry no medium of their own. cam: placed at
 * the path's time, which the rays carry. */
static int medium_at(const Scene *s, const Camera *cam, Vec3 q, float time, uint64_t *rays)
{
    int medium = s->camera_medium;
    Vec3 o = cam->origin;
    for (int step = 0; step < MEDIA_MAX_CROSSINGS; step++) {
        Vec3 od = v3_sub(q, o);
        float len = v3_length(od);
        if (!(len > 0.0f)) return medium;
        Vec3 dir = v3_scale(od, 1.0f / len);
        Ray r = ray_make_at(o, dir, 0.0f, len * (1.0f - 1e-5f), time);
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &r, &sh)) return medium;
        medium = scene_medium_after(s, &sh, dir, medium);
        o = scene_offset(s, sh.p, sh.ng, dir);
    }
    return medium;
}

/* The medium on the side of emission sample point p toward direction w: just off the
 * surface (further than medium_at's end tolerance), so that an emitter that is itself an
 * interface is crossed when the camera sits on its other side. */
static int medium_at_emitter(const Scene *s, const Camera *cam, Vec3 p, Vec3 w, float time, uint64_t *rays)
{
    float scale = fmaxf(1.0f, v3_length(v3_sub(p, cam->origin)));
    return medium_at(s, cam, v3_add(p, v3_scale(w, 1e-4f * scale)), time, rays);
}

/* The spectral MIS of delta tracking over the lanes (hetero_medium.h), for the light
 * tracer's walks through grid media: the hero lane (-1 until the first grid piece) and
 * p_c / p_hero over the grid pieces so far. */
typedef struct HeroMis {
    int hero;
    Color r_u;
    bool homogeneous; /* homogeneous media too (the light tracer): see hero_sample_homogeneous */
} HeroMis;

/* Free-flight sampling in a homogeneous medium by the hero lane alone, t ~ sigma_t[h]
 * exp(-sigma_t[h] t), with the lanes' densities relative to the hero's in out->r, as
 * hetero_sample_distance does for grids: the light tracer's walks take the balance
 * heuristic over lanes for the whole path (hero_beta) instead of per segment, whose
 * product over many scattering events has a heavy tail where the lanes' sigma_t differ
 * (spectral mode: the light tracer's furnace missed by 4x in one channel at 256 paths per
 * pixel). False when the hero's density underflows. */
static bool hero_sample_homogeneous(const MediumCoeffs *mc, float t_max, int h, float u, MediumSample *out)
{
    float st = mc->sigma_t.c[h];
    float t = st > 0.0f ? -log1pf(-u) / st : INFINITY;
    out->scattered = t < t_max;
    out->t = out->scattered ? t : t_max;
    Color tr = medium_transmittance(mc, out->t);
    float p = out->scattered ? st * tr.c[h] : tr.c[h]; /* the hero's density of this outcome */
    if (!(p > 0.0f)) return false;
    out->weight = color_scale(out->scattered ? color_mul(tr, mc->sigma_s) : tr, 1.0f / p);
    out->r = color_scale(out->scattered ? color_mul(tr, mc->sigma_t) : tr, 1.0f / p);
    return true;
}

/* beta / mean(r_u): a contribution's throughput (volpath.c's mis_beta); beta itself on a
 * walk that met no grid. */
static inline Color hero_beta(const HeroMis *hm, Color beta)
{
    if (hm->hero < 0) return beta;
    float m = 0.0f;
    for (int c = 0; c < COLOR_LANES; c++) m += hm->r_u.c[c];
    return m > 0.0f && isfinite(m) ? color_scale(beta, (float)COLOR_LANES / m) : color_s(0.0f);
}

/* What a walk's ray met after free-flight sampling through the pieces of its way. */
typedef enum MediaHitKind { MEDIA_MISS, MEDIA_SURFACE, MEDIA_VOLUME } MediaHitKind;
typedef struct MediaHit {
    MediaHitKind kind;
    SurfaceHit sh; /* MEDIA_SURFACE */
    Vec3 p;        /* the vertex (surface or volume) */
    float dist;    /* |p - the previous vertex| */
    float fwd, rev; /* ChainPdf's: this vertex from the previous one, and back */
    Color le;       /* with `emit`: the media's emission along the way, times the throughput
                     * (hero-normalised), to be added as it is */
} MediaHit;

/* Follows ray (from vertex x_prev, a volume vertex when prev_med) through media and
 * boundaries, in *medium (updated at each boundary), to the next vertex: a free-flight
 * sample in each medium piece (two 1D numbers: the lane, the distance; medium.h), its
 * weight multiplied into sp's beta and scatter. Grid media are delta-tracked with the
 * walk's hero lane (hm), homogeneous ones too when hm->homogeneous. With emit, the
 * emission of every emissive piece is gathered into out->le (volpath.c's estimators:
 * sigma_a Le Tr / pdf at a homogeneous scattering point, hetero_sample_distance's at every
 * tentative collision of a grid). False when the path ends (black weight or a stack of
 * boundaries); a miss is returned as MEDIA_MISS. */
static bool media_next(const Scene *s, Ray ray, Vec3 x_prev, bool prev_med, bool emit, int *medium, SubPath *sp,
                       HeroMis *hm, Sampler *rng, const Wavelengths *wl, MediaHit *out, uint64_t *rays)
{
    ChainPdf c = {0, 1.0f, 0.0f, 1.0f, 0.0f, 1.0f};
    out->le = color_s(0.0f);
    for (int step = 0; step < MEDIA_MAX_CROSSINGS; step++) {
        SurfaceHit *sh = &out->sh;
        ++*rays;
        const bool hit = scene_intersect(s, &ray, sh);
        if (*medium >= 0) {
            const Medium *med = &s->media[*medium];
            MediumCoeffs mc = medium_coeffs(med, wl);
            float u_ch = sampler_1d(rng), u_t = sampler_1d(rng);
            MediumSample ms;
            if (medium_is_hetero(med)) { /* delta tracking with the walk's hero lane (volpath.c) */
                if (hm->hero < 0) hm->hero = (int)fminf(u_ch * (float)COLOR_LANES, (float)(COLOR_LANES - 1));
                hetero_sample_distance(&med->u.het, &mc, ray.o, ray.d, hit ? sh->t : INFINITY, hm->hero, hm->r_u, u_t,
                                       &ms);
                /* ms.le is already divided by the lanes' mean ratio, the walk's so far
                 * included (hetero_medium.h). */
                if (emit && mc.emissive) out->le = color_madd(out->le, sp->beta, ms.le);
                hm->r_u = color_mul(hm->r_u, ms.r);
            } else if (hm->homogeneous) {
                if (hm->hero < 0) hm->hero = (int)fminf(u_ch * (float)COLOR_LANES, (float)(COLOR_LANES - 1));
                if (!hero_sample_homogeneous(&mc, hit ? sh->t : INFINITY, hm->hero, u_t, &ms)) return false;
                hm->r_u = color_mul(hm->r_u, ms.r);
            } else {
                medium_sample_distance(&mc, hit ? sh->t : INFINITY, u_ch, u_t, &ms);
            }
            if (emit && mc.emissive && ms.scattered && !medium_is_hetero(med))
                out->le = color_madd(out->le, hero_beta(hm, sp->beta), color_mul(ms.tr_pdf, color_mul(mc.sigma_a, mc.le)));
            sp->beta = color_mul(sp->beta, ms.weight);
            sp->scatter = color_mul(sp->scatter, ms.weight);
            if (color_is_black(sp->scatter)) return false;
            chain_piece(&c, s, &mc, *medium, ray.o, ray.d, ms.t, step == 0 && prev_med, ms.scattered);
            if (ms.scattered) {
                out->kind = MEDIA_VOLUME;
                out->p = ray_at(&ray, ms.t);
                out->dist = v3_length(v3_sub(out->p, x_prev));
                chain_pdfs(&c, prev_med, true, &out->fwd, &out->rev);
                return out->fwd > 0.0f;
            }
        } else {
            chain_add(&c, 1.0f, 0.0f, 0.0f);
        }
        if (!hit) {
            out->kind = MEDIA_MISS;
            chain_pdfs(&c, prev_med, false, &out->fwd, &out->rev);
            return true;
        }
        const MediumInterface *mi = scene_hit_medium_iface(s, sh);
        if (mi && mi->boundary) { /* only a boundary: cross it, not a vertex */
            *medium = v3_dot(ray.d, sh->ng) < 0.0f ? mi->inside : mi->outside;
            ray = ray_make_at(scene_offset(s, sh->p, sh->ng, ray.d), ray.d, 0.0f, INFINITY, ray.time);
            continue;
        }
        out->kind = MEDIA_SURFACE;
        out->p = sh->p;
        out->dist = v3_length(v3_sub(sh->p, x_prev));
        chain_pdfs(&c, prev_med, false, &out->fwd, &out->rev);
        return out->fwd > 0.0f;
    }
    return false;
}

/* mis_arrive (subpath_walk.h) at a vertex reached through media: the area (or volume)
 * density of this vertex gains the distance sampling density fwd, and the reverse
 * density of the previous vertex, which d_vc and d_vm carry, gains rev (UPBP's
 * extension of tech. rep. eqs. 31-33; cos_in = 1 at a volume vertex). */
static inline void mis_arrive_media(SubPath *sp, float dist, float cos_in, float fwd, float rev)
{
    float inv = 1.0f / mis(cos_in * fwd);
    sp->d_vcm *= mis(dist * dist) * inv;
    sp->d_vc *= mis(rev) * inv;
    sp->d_vm *= mis(rev) * inv;
}

/* mis(eta) of merging at a vertex (tech. rep. eq. 12's eta_vcm): a disk's at a surface,
 * a ball's in a medium; 0 without merging (BDPT). */
static inline float eta_vm(const SubpathIteration *it, bool vol)
{
    return vol ? it->mis_vm_vol : it->mis_vm;
}

/* A phase-function scattering at a volume vertex: HG sampled exactly (weight 1), Russian
 * roulette, the MIS quantities (tech. rep. eqs. 34-36 with no cosine; HG is symmetric,
 * so the reverse density is the forward one) and the next ray, at *ray's time (the ray
 * that reached p). */
static bool media_scatter_phase(SubPath *sp, const SubpathIteration *it, Vec3 p, Vec3 wo, float g, int depth,
                                int rr_depth, Sampler *rng, Ray *ray)
{
    Vec2 u = sampler_2d(rng);
    float pdf;
    Vec3 wi = phase_hg_sample(wo, g, u.x, u.y, &pdf);
    if (!(pdf > 0.0f)) return false;
    sp->specular_only = false;
    if (!subpath_roulette(sp, depth, rr_depth, rng)) return false;
    if (it) {
        /* mis_scatter (subpath_walk.h) with cos_out = 1 and the eta of a volume vertex:
         * merging here is the point-point 3D estimator. With two etas the merge
         * strategies' densities no longer share one factor: d_vm keeps the sum of their
         * ratios each times its own vertex's eta, divided by the surface eta throughout
         * (so that subpath_scatter's recursion at surfaces holds unchanged: its "+ 1" is
         * eta_surface / eta_surface), and media_merge divides by the merging vertex's eta. */
        float gm = mis(1.0f / pdf);
        sp->d_vc = gm * (sp->d_vc * mis(pdf) + sp->d_vcm + it->mis_vm_vol);
        sp->d_vm = gm * (sp->d_vm * mis(pdf) + (sp->d_vcm + it->mis_vm_vol) * it->mis_vc);
        sp->d_vcm = mis(1.0f / pdf);
    }
    *ray = ray_make_at(p, wi, 0.0f, INFINITY, ray->time);
    return true;
}

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
} MediaWalk;

/* subpath_walk_light through media: the same random numbers per surface vertex (lens,
 * BSDF, roulette), two per medium piece crossed, a lens 2D, a phase 2D and roulette's per
 * volume vertex. */
static bool media_walk_light(const Scene *s, const MediaWalk *w, const EmissionSample *es, SubPath sp, int medium,
                             Sampler *rng, uint64_t *rays)
{
    const SubpathIteration *it = w->mis;
    Ray ray = ray_make_at(scene_offset(s, es->p, es->n, es->w), es->w, 0.0f, INFINITY, es->time);
    Vec3 x_prev = es->p;
    bool prev_med = false;
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
        }
        const bool last = w->max_depth > 0 && bounces >= w->max_depth;
        if (vol) {
            const float g = s->media[medium].g;
            MediaLightVertex v = {h.p, v3s(0.0f), NULL, NULL, g, medium, w_prev, sp, bounces, sampler_2d(rng)};
            v.sp.beta = hero_beta(&hm, sp.beta);
            const bool more = !last && media_scatter_phase(&sp, it, h.p, w_prev, g, bounces, w->rr_depth, rng, &ray);
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
        const bool more = !last && subpath_scatter(s, &sp, it, &bsdf, &h.sh, w_prev, BSDF_IMPORTANCE, bounces,
                                                   w->rr_depth, rng, &ray);
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
    float weight = 1.0f;
    if (c->it) {
        float cos_cam = v->sh ? fabsf(v3_dot(v->ng, cs.wi)) : 1.0f;
        float cos_theta = v3_dot(v3_neg(cs.wi), c->cam->forward);
        float cam_pdf_a = cos_cam * seg.rev /
                          (c->it->pixel_area * cos_theta * cos_theta * cos_theta * cs.dist * cs.dist);
        float w_light = mis(cam_pdf_a / (float)c->it->light_paths) *
                        (eta_vm(c->it, !v->sh) + v->sp.d_vcm + v->sp.d_vc * mis(pdf_rev));
        weight = 1.0f / (1.0f + w_light);
    }
    Color col = color_scale(color_mul(color_mul(v->sp.beta, f), seg.tr), weight * cs.we / cs.pdf_w);
    film_splat(c->out, c->frame, cs.raster.x, cs.raster.y, wl ? spectrum_to_rgb(col, wl) : col);
}

static bool visit_light_trace(void *ctx, const MediaLightVertex *v)
{
    const MediaCamCtx *c = ctx;
    media_connect_camera(c, v, c->wl);
    return true;
}

void media_light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng, SplatList *out,
                       uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return;
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
    EmissionSample es;
    subpath_emit(s, rng, wlp, &es);
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
    const MediaWalk w = {lp->max_depth, lp->rr_depth, NULL, wlp, lp->spectral ? &wl : NULL, visit_light_trace, &c};
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
    const MediaWalk w = {vp->max_depth, vp->light_rr_depth, it, wl, wl ? &walk_wl : NULL, visit_store_connect, &c};
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
                                 Sampler *rng, const Wavelengths *wl, uint64_t *rays)
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
    if (!media_connect(s, x->p, x->ng, ls.p, ls.n, false, cam_vertex_medium(s, x, ls.wi), x->time, wl, &seg, rays))
        return color_s(0.0f);
    float w_light = ls.delta ? 0.0f : mis(fwd * seg.fwd / ls.direct_pdf);
    float w_camera = mis(ls.emit_pdf * cos_x * seg.rev / (ls.direct_pdf * ls.cos_light)) *
                     (eta_vm(it, !x->bsdf) + sp->d_vcm + sp->d_vc * mis(rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    Color c = color_mul(color_mul(f, seg.tr), scene_light_li(s, &ls, wl));
    return color_scale(c, weight / (ls.delta ? ls.pmf : ls.pdf_w));
}

/* A connection between camera vertex x and light vertex y (tech. rep. eqs. 40-41) through
 * media; y's BSDF rebuilt as subpath.c's light_bsdf does (not cached here). */
static Color media_connect_vertices(const Scene *s, const SubpathIteration *it, const SubPath *sp, const CamVertex *x,
                                    const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays)
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
    if (!media_connect(s, x->p, x->ng, y->p, y->ng, y_vol, cam_vertex_medium(s, x, d), x->time, wl, &seg, rays))
        return color_s(0.0f);
    float x_fwd_a = x_fwd * cos_y * seg.fwd / dist2; /* the camera subpath reaching y */
    float y_fwd_a = y_fwd * cos_x * seg.rev / dist2; /* the light subpath reaching x */
    float w_light = mis(x_fwd_a) * (eta_vm(it, y_vol) + y->d_vcm + y->d_vc * mis(y_rev));
    float w_camera = mis(y_fwd_a) * (eta_vm(it, !x->bsdf) + sp->d_vcm + sp->d_vc * mis(x_rev));
    float weight = 1.0f / (w_light + 1.0f + w_camera);
    return color_scale(color_mul(color_mul(color_mul(fx, fy), y->beta), seg.tr), weight / dist2);
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
                         const SubPath *sp, const CamVertex *x, int bounces, const Wavelengths *wl, Color *hero)
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
    *hero = color_mul(acc_hero, norm);
    return color_mul(acc, norm);
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
        }
        if (!go) break;
        const Color beta = hero_beta(&hm, sp.beta); /* the throughput of this vertex's contributions */
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            Color le = scene_env_radiance(s, ray.d, wl);
            if (!color_is_black(le)) {
                float w = 1.0f;
                if (t > 1) {
                    /* The environment as in subpath.c, the pass probabilities of the way
                     * out joined to the camera's density (no distance, no cosine). */
                    mis_arrive_media(&sp, 1.0f, 1.0f, h.fwd, h.rev);
                    float direct = light_env_pdf(&s->emitter_sampler, ray.d);
                    float emission = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
                    w = 1.0f / (1.0f + mis(direct) * sp.d_vcm + mis(emission) * sp.d_vc);
                }
                if (cam_dispersed) H = color_madd(H, beta, color_scale(le, w));
                else L = color_madd(L, beta, color_scale(le, w));
            }
            break;
        }
        const bool vol = h.kind == MEDIA_VOLUME;
        float cos_in = vol ? 1.0f : fabsf(v3_dot(h.sh.ng, wo));
        if (!(cos_in > 0.0f)) break;
        mis_arrive_media(&sp, h.dist, cos_in, h.fwd, h.rev);

        if (!vol && h.sh.emitter >= 0) { /* s = 0, as subpath.c */
            const Emitter *e = &s->emitter_sampler.light[h.sh.emitter].u.area;
            Color le = scene_emission(s, &h.sh, wo, wl);
            if (!color_is_black(le)) {
                float w = 1.0f;
                if (t > 1) {
                    float pdf_a = emitter_pdf_a(&s->emitter_sampler, h.sh.emitter);
                    float emission_pdf = pdf_a * emitter_emission_pdf_w(e, h.sh.ng, wo);
                    w = 1.0f / (1.0f + mis(pdf_a) * sp.d_vcm + mis(emission_pdf) * sp.d_vc);
                }
                if (cam_dispersed) H = color_madd(H, beta, color_scale(le, w));
                else L = color_madd(L, beta, color_scale(le, w));
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
                Color nee = media_connect_light(s, it, &sp, &x, rng, wl, rays);
                if (cam_dispersed) H = color_madd(H, beta, nee);
                else L = color_madd(L, beta, nee);
            }
            if (merging) merge->fetch(it, &mq);
            Color c = color_s(0.0f), ch = color_s(0.0f);
            for (int j = 0; j < nlv; j++) {
                if (vp->max_depth > 0 && t + lv[j].bounces > vp->max_depth) break;
                Color cj = media_connect_vertices(s, it, &sp, &x, &lv[j], wl, rays);
                if (cam_dispersed || lv[j].dispersed) ch = color_add(ch, cj);
                else c = color_add(c, cj);
            }
            L = color_madd(L, beta, c);
            if (wl) H = color_madd(H, beta, ch);
            if (merging) { /* as subpath_trace_camera */
                Color mh = color_s(0.0f), m = media_merge(s, vp, it, &mq, &sp, &x, t, wl, &mh);
                if (cam_dispersed) m = color_add(m, mh), mh = color_s(0.0f);
                if (cam_dispersed) H = color_madd(H, beta, m);
                else L = color_madd(L, beta, m);
                if (wl) H = color_madd(H, beta, mh);
            }
        }
        if (vol) {
            if (!media_scatter_phase(&sp, it, h.p, wo, x.g, t, vp->rr_depth, rng, &ray)) break;
            prev_med = true;
        } else {
            if (!subpath_scatter(s, &sp, it, &bsdf, &h.sh, wo, BSDF_RADIANCE, t, vp->rr_depth, rng, &ray)) break;
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
    const MediaWalk w = {tc->bounces, vp->rr_depth, it, wl, wl ? walk_wl : NULL, visit_target, tc};
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
    for (int t = 1;; t++) {
        MediaHit h;
        if (!media_next(s, ray, x_prev, prev_med, false, &medium, &sp, &hm, rng, wl, &h, rays)) return false;
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            if (!emission || t != hits) return false;
            Color le = scene_env_radiance(s, ray.d, wl);
            if (color_is_black(le)) return false;
            float w = 1.0f;
            if (t > 1) {
                mis_arrive_media(&sp, 1.0f, 1.0f, h.fwd, h.rev);
                float direct = light_env_pdf(&s->emitter_sampler, ray.d);
                float em = direct / (CST_PI * s->emitter_sampler.radius * s->emitter_sampler.radius);
                w = 1.0f / (1.0f + mis(direct) * sp.d_vcm + mis(em) * sp.d_vc);
            }
            *emitted = color_mul(hero_beta(&hm, sp.beta), color_scale(le, w));
            if (dispersed) *emitted = subpath_hero_only(*emitted);
            return false;
        }
        const bool vol = h.kind == MEDIA_VOLUME;
        float cos_in = vol ? 1.0f : fabsf(v3_dot(h.sh.ng, wo));
        if (!(cos_in > 0.0f)) return false;
        mis_arrive_media(&sp, h.dist, cos_in, h.fwd, h.rev);
        if (emission && t == hits) {
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
            *emitted = color_mul(hero_beta(&hm, sp.beta), color_scale(le, w));
            if (dispersed) *emitted = subpath_hero_only(*emitted);
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
            if (!media_scatter_phase(&sp, it, h.p, wo, g, t, vp->rr_depth, rng, &ray)) return false;
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
            if (!subpath_scatter(s, &sp, it, &bsdf, &h.sh, wo, BSDF_RADIANCE, t, vp->rr_depth, rng, &ray)) return false;
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
    return color_mul(x->sp.beta, media_connect_light(s, it, &x->sp, &cx, rng, wl, rays));
}

Color media_subpath_connect_pair(const Scene *s, const SubpathIteration *it, const MediaCameraVertex *x,
                                 const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays)
{
    CamVertex cx = cam_vertex_of(x);
    return color_mul(x->sp.beta, media_connect_vertices(s, it, &x->sp, &cx, y, wl, rays));
}

/* ------------------------------------------------------------------ SPPM (sppm.c) */

typedef struct MediaPhotonCtx {
    MediaPhotonVisit visit;
    void *ctx;
} MediaPhotonCtx;

static bool visit_photon(void *ctx, const MediaLightVertex *v)
{
    const MediaPhotonCtx *c = ctx;
    MediaPhoton ph = {v->p, v->w_prev, v3s(0.0f), v->sp.beta, v->bounces, v->sp.specular_only};
    if (v->sh) ph.n = v3_dot(v->ng, v->w_prev) >= 0.0f ? v->ng : v3_neg(v->ng);
    return c->visit(c->ctx, &ph);
}

bool media_photon_walk(const Scene *s, const Camera *cam, const PhotonWalk *pw, uint64_t index, MediaPhotonVisit visit,
                       void *ctx, uint64_t *rays)
{
    Sampler rng;
    sampler_start_stream(&rng, pw->seed, index, pw->stream);
    EmissionSample es;
    subpath_emit(s, &rng, pw->wl, &es);
    if (!(es.pdf_w > 0.0f) || !(es.pdf_a > 0.0f) || color_is_black(es.beta)) return true; /* still one of the N */
    es.time = pw->time; /* the iteration's instant, as photon_walk's */
    int medium = medium_at_emitter(s, cam, es.p, es.w, es.time, rays);
    if (!es.finite && medium >= 0) return true; /* as media_light_trace */
    MediaPhotonCtx c = {visit, ctx};
    /* No MIS (light tracing's walk): the hero lane's free-flight sampling in every medium,
     * each vertex's flux divided by the walk's mean lane ratio (hero_beta). */
    const MediaWalk w = {pw->max_depth, pw->rr_depth, NULL, pw->wl, NULL, visit_photon, &c};
    return media_walk_light(s, &w, &es, subpath_start(color_scale(es.beta, pw->scale)), medium, &rng, rays);
}

bool media_visible_point(const Scene *s, Ray ray, int medium, Sampler *rng, const Wavelengths *wl, Color beta,
                         Color *le, MediaVisiblePoint *out, uint64_t *rays)
{
    SubPath sp = subpath_start(beta);
    sp.specular_only = false;
    HeroMis hm = {-1, color_s(1.0f), false};
    Vec3 x_prev = ray.o;
    for (int depth = 0; depth <= PHOTON_MAX_SPECULAR; depth++) {
        MediaHit h;
        /* emit false: integrator.c refuses emitting media for SPPM (its photons and NEE
         * start on the light sampler's emitters, so a medium's emission would reach the
         * visible points by no estimator). */
        if (!media_next(s, ray, x_prev, false, false, &medium, &sp, &hm, rng, wl, &h, rays)) return false;
        Vec3 wo = v3_neg(ray.d);
        if (h.kind == MEDIA_MISS) {
            *le = color_madd(*le, hero_beta(&hm, sp.beta), scene_env_radiance(s, ray.d, wl));
            return false;
        }
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
        if (h.sh.emitter >= 0) *le = color_madd(*le, hero_beta(&hm, sp.beta), scene_emission(s, &h.sh, wo, wl));
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
            out->beta = color_scale(out->beta, 1.0f / (1.0f - p_delta));
            return color_is_finite(out->beta);
        }
        if (!sampled) return false;
        sp.beta = color_mul(sp.beta, bs.weight);
        sp.scatter = color_mul(sp.scatter, bs.weight);
        if (color_is_black(sp.scatter)) return false;
        medium = scene_medium_after(s, &h.sh, bs.wi, medium);
        ray = ray_make_at(scene_offset(s, h.sh.p, h.sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, ray.time);
        x_prev = h.p;
    }
    return false; /* photon_trace_to_diffuse's cut */
}
