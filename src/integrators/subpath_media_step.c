/* The steps of subpaths through participating media (subpath_media_step.h): free flights,
 * connections' transmittance (ratio tracking in grids) and their chain densities. */
#include "integrators/subpath_media_step.h"

#include <math.h>

#include "core/rng.h"
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

bool media_connect(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, bool q_med, int medium, float time,
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

int medium_at_point(const Scene *s, const Camera *cam, Vec3 q, float time, uint64_t *rays)
{
    return medium_at(s, cam, q, time, rays);
}

/* The medium on the side of emission sample point p toward direction w: just off the
 * surface (further than medium_at's end tolerance), so that an emitter that is itself an
 * interface is crossed when the camera sits on its other side. */
int medium_at_emitter(const Scene *s, const Camera *cam, Vec3 p, Vec3 w, float time, uint64_t *rays)
{
    float scale = fmaxf(1.0f, v3_length(v3_sub(p, cam->origin)));
    return medium_at(s, cam, v3_add(p, v3_scale(w, 1e-4f * scale)), time, rays);
}

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

/* Follows ray (from vertex x_prev, a volume vertex when prev_med) through media and
 * boundaries, in *medium (updated at each boundary), to the next vertex: a free-flight
 * sample in each medium piece (two 1D numbers: the lane, the distance; medium.h), its
 * weight multiplied into sp's beta and scatter. Grid media are delta-tracked with the
 * walk's hero lane (hm), homogeneous ones too when hm->homogeneous. With emit, the
 * emission of every emissive piece is gathered into out->le (volpath.c's estimators:
 * sigma_a Le Tr / pdf at a homogeneous scattering point, hetero_sample_distance's at every
 * tentative collision of a grid). False when the path ends (black weight or a stack of
 * boundaries); a miss is returned as MEDIA_MISS. */
bool media_next(const Scene *s, Ray ray, Vec3 x_prev, bool prev_med, bool emit, int *medium, SubPath *sp,
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

/* A phase-function scattering at a volume vertex: HG sampled exactly (weight 1), Russian
 * roulette on scatter x rr_scale (recorded for explain on the light or camera subpath), the MIS quantities (tech. rep. eqs. 34-36 with no cosine;
 * HG is symmetric, so the reverse density is the forward one) and the next ray, at *ray's
 * time (the ray that reached p). */
bool media_scatter_phase(SubPath *sp, const SubpathIteration *it, bool light, Vec3 p, Vec3 wo, float g, int depth,
                         int rr_depth, float rr_scale, Sampler *rng, Ray *ray)
{
    Vec2 u = sampler_2d(rng);
    float pdf;
    Vec3 wi = phase_hg_sample(wo, g, u.x, u.y, &pdf);
    if (!(pdf > 0.0f)) return false;
    sp->specular_only = false;
    if (!subpath_roulette_rec(sp, it, light, depth, rr_depth, rr_scale, rng)) return false;
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
