/* The one light subpath walk of light tracing, photon mapping, SPPM, BDPT and VCM, with the
 * subpath state's steps it shares with the camera walk (scattering, Russian roulette, the
 * recursive MIS quantities). Inline, and forced so: each estimator's copy has its visitor
 * and parameters known at compile time, so the visitor is inlined and a walk without MIS
 * carries none of its arithmetic or branches (out of line, with a function-pointer call
 * per vertex and the MIS tests, the light tracer took about 4% more CPU time). */
#ifndef CST_INTEGRATORS_SUBPATH_WALK_H
#define CST_INTEGRATORS_SUBPATH_WALK_H

#include "integrators/recorder.h"
#include "integrators/roulette.h"
#include "integrators/subpath.h"

/* A light subpath's first state: throughput beta (the emission sample's, or a scaled
 * one), nothing scattered yet, MIS quantities zero (subpath_trace_light sets its own). */
static inline SubPath subpath_start(Color beta)
{
    return (SubPath){beta, color_s(1.0f), 0.0f, 0.0f, 0.0f, true};
}

/* A non-delta vertex of a light subpath (a BSDF with a non-delta part: one a camera
 * connection or a photon can use), as the walk hands it to its visitor. */
typedef struct LightVertex {
    const SurfaceHit *sh;
    const Bsdf *bsdf;
    Vec3 w_prev;     /* unit, toward the previous vertex (where the light came from) */
    SubPath sp;      /* on arrival, before this vertex scatters: beta is the flux reaching it */
    int bounces;     /* 1 for the first hit after the emitter */
    Vec2 u_lens;     /* the lens sample drawn for this vertex (LightWalk.lens), else 0 */
} LightVertex;

/* Called at every non-delta vertex, after the walk has sampled the vertex's continuation
 * (so a camera connection's shadow ray overlaps the next bounce instead of holding it back;
 * the vertex is what it was before scattering). Returns false to stop the walk (OOM). */
typedef bool (*LightVisit)(void *ctx, const LightVertex *v);

/* How a light subpath is walked. The random numbers a walk draws: per vertex, with `lens`
 * a 2D lens sample if the vertex is non-delta, then (unless max_depth ends the path) the
 * BSDF sample's 1D + 2D, then Russian roulette's 1D from rr_depth on (roulette.h). */
typedef struct LightWalk {
    int max_depth;  /* bounces; 0 = unbounded */
    int rr_depth;   /* first bounce at which Russian roulette may stop the path */
    const SubpathIteration *mis; /* BDPT/VCM: carry the MIS quantities of this iteration (and end
                              * at a hit at grazing incidence, which their area conversion
                              * divides by); NULL: none (light tracing, photons) */
    bool lens;      /* draw LightVertex.u_lens (the estimators that connect to the camera) */
    const Wavelengths *wl; /* spectral mode: the path's wavelengths; NULL in RGB mode */
    LightVisit visit;
    void *ctx;
    /* Spectral mode, light tracing: wl itself, writable, so that a dispersive dielectric
     * terminates its secondary wavelengths (scene_bsdf_disperse) for the rest of the path
     * and its splats; BDPT and VCM: a copy of wl, whose termination marks the light
     * vertices after it (SubpathVertex.dispersed). NULL for photons (photon maps, SPPM),
     * which take such an ior as the constant of RGB mode. */
    Wavelengths *disperse;
} LightWalk;

/* The emission sample that starts every light subpath: a light by power, a point and a
 * direction on it (emitter_sample_emission), from 1D + 2D + 2D of rng; its flux at wl in
 * spectral mode (wl NULL: RGB). */
void subpath_emit(const Scene *s, Sampler *rng, const Wavelengths *wl, EmissionSample *es);

/* After scattering at a vertex into a direction with |cos| cos_out, forward pdf pdf_fwd
 * and reverse pdf pdf_rev (tech. rep. eqs. 34-36; for delta lobes eqs. 53-55, where the
 * forward and reverse discrete probabilities are the same and cancel). The division by
 * the next vertex's distance and cosine happens at the next hit. */
static inline void mis_scatter(SubPath *sp, const SubpathIteration *it, const BsdfSample *bs,
                               float cos_out, float pdf_rev)
{
    if (bs->delta) {
        sp->d_vcm = 0.0f;
        sp->d_vc *= mis(cos_out);
        sp->d_vm *= mis(cos_out);
        return;
    }
    float g = mis(cos_out / bs->pdf_w);
    sp->d_vc = g * (sp->d_vc * mis(pdf_rev) + sp->d_vcm + it->mis_vm);
    sp->d_vm = g * (sp->d_vm * mis(pdf_rev) + sp->d_vcm * it->mis_vc + 1.0f);
    sp->d_vcm = mis(1.0f / bs->pdf_w);
}

/* At a hit at distance dist with |cos| cos_in to the incoming direction: completes the
 * area conversion of the previous scattering (tech. rep. eqs. 31-33, 37-38). */
static inline void mis_arrive(SubPath *sp, float dist, float cos_in)
{
    sp->d_vcm *= mis(dist * dist);
    float inv = 1.0f / mis(cos_in);
    sp->d_vcm *= inv;
    sp->d_vc *= inv;
    sp->d_vm *= inv;
}

/* Russian roulette (roulette.h) on a subpath's throughputs, its survival probability
 * following scatter x rr_scale: 1 on surfaces and in media sampled lane by lane per segment;
 * the walk's hero normalisation (subpath_media_step.h's hero_scale) once a walk samples
 * distances with a hero lane, whose raw per-lane scatter is not what its contributions
 * carry (volpath.c's roulette on mis_beta, pbrt-v4 sec. 14.2). False when the path stops. */
static inline bool subpath_roulette(SubPath *sp, int depth, int rr_depth, float rr_scale, Sampler *rng)
{
    float rr = roulette(rng, depth, rr_depth, color_scale(sp->scatter, rr_scale));
    if (rr == 0.0f) return false;
    sp->beta = color_scale(sp->beta, rr);
    sp->scatter = color_scale(sp->scatter, rr);
    return true;
}

/* subpath_roulette, and with a recorder (explain: it->rec) from rr_depth on its ROULETTE
 * event on the light (light) or camera subpath, with roulette.h's survival probability. */
static inline bool subpath_roulette_rec(SubPath *sp, const SubpathIteration *it, bool light, int depth, int rr_depth,
                                        float rr_scale, Sampler *rng)
{
    if (!it || !it->rec || depth < rr_depth) return subpath_roulette(sp, depth, rr_depth, rr_scale, rng);
    const float q = roulette_survival(color_scale(sp->scatter, rr_scale));
    const bool survived = subpath_roulette(sp, depth, rr_depth, rr_scale, rng);
    recorder_subpath_roulette(it->rec, light, depth, q, survived);
    return survived;
}

/* The continuation of a subpath at a vertex (wo: back along the subpath; mode: what it
 * carries): a BSDF sample, the throughput, Russian roulette from depth rr_depth on (on
 * scatter x rr_scale: subpath_roulette), the MIS quantities (with an iteration `it`; NULL:
 * none) and the next ray. False when the subpath ends here. */
static inline bool subpath_scatter_rr(const Scene *s, SubPath *sp, const SubpathIteration *it, const Bsdf *b,
                                      const SurfaceHit *sh, Vec3 wo, BsdfTransport mode, int depth, int rr_depth,
                                      float rr_scale, Sampler *rng, Ray *ray)
{
    BsdfSample bs;
    float uc = sampler_1d(rng);
    Vec2 u = sampler_2d(rng);
    /* bsdf_sample_transport rejects samples without a density (bsdf.h): the MIS ratios
     * below may divide by it. */
    if (!bsdf_sample_transport(b, wo, uc, u, mode, &bs)) return false;
    if (it && it->rec && mode == BSDF_RADIANCE) recorder_scatter(it->rec, &bs, sp->beta);
    if (it && it->rec && mode == BSDF_IMPORTANCE) recorder_light_scatter(it->rec, b, &bs, wo, sp->beta, depth);
    sp->specular_only = sp->specular_only && bs.delta;
    sp->beta = color_mul(sp->beta, bs.weight);
    sp->scatter = color_mul(sp->scatter, bs.weight);
    if (color_is_black(sp->scatter)) return false;
    if (!subpath_roulette_rec(sp, it, mode == BSDF_IMPORTANCE, depth, rr_depth, rr_scale, rng)) return false;
    if (it) mis_scatter(sp, it, &bs, fabsf(v3_dot(sh->ng, bs.wi)), bs.delta ? bs.pmf : bsdf_pdf(b, bs.wi, wo));
    *ray = ray_make_at(scene_offset(s, sh->p, sh->ng, bs.wi), bs.wi, 0.0f, INFINITY, sh->time);
    return true;
}

/* subpath_scatter_rr with rr_scale 1: the walks without media (x 1 is exact, so their
 * paths are unchanged bit for bit). */
static inline bool subpath_scatter(const Scene *s, SubPath *sp, const SubpathIteration *it, const Bsdf *b,
                                   const SurfaceHit *sh, Vec3 wo, BsdfTransport mode, int depth, int rr_depth,
                                   Sampler *rng, Ray *ray)
{
    return subpath_scatter_rr(s, sp, it, b, sh, wo, mode, depth, rr_depth, 1.0f, rng, ray);
}

/* The one light subpath walk: from es with state sp, traces importance-mode BSDF samples
 * (adjoint: light carries flux, refraction does not scale it by 1/eta^2) with Russian
 * roulette (roulette.h), calling w->visit at every non-delta vertex. Adds the rays it
 * traces to *rays. False if the visitor stopped it. */
static inline __attribute__((always_inline)) bool
subpath_walk_light(const Scene *s, const LightWalk *w, const EmissionSample *es, SubPath sp, Sampler *rng,
                   uint64_t *rays)
{
    const SubpathIteration *it = w->mis;
    Ray ray = ray_make_at(scene_offset(s, es->p, es->n, es->w), es->w, 0.0f, INFINITY, es->time);
    for (int bounces = 1;; bounces++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) return true;
        Vec3 w_prev = v3_neg(ray.d); /* toward the previous vertex, where the light came from */
        if (it) {
            float cos_in = fabsf(v3_dot(sh.ng, w_prev));
            if (!(cos_in > 0.0f)) return true;
            /* From a directional light the first segment has no distance: its density is
             * per unit area of the disk already (tech. rep. sec. 5.1, SmallVCM). */
            mis_arrive(&sp, bounces > 1 || es->finite ? sh.t : 1.0f, cos_in);
            if (it->rec) { /* explain's MIS check, and mmlt's replay (recorder.h) */
                recorder_light_hit(it->rec, &sh, ray.d);
                recorder_light_vertex(it->rec, s, &sh, bounces);
            }
        }
        Bsdf bsdf;
        if (w->disperse) scene_bsdf_disperse(s, &sh, w->disperse, &bsdf);
        else scene_bsdf(s, &sh, w->wl, &bsdf);
        /* Delta lobes can neither be connected to (f is a Dirac in the direction of the
         * other vertex) nor hold photons (no density estimate can find their direction). */
        const bool visit = !bsdf_is_delta(&bsdf);
        LightVertex v = {&sh, &bsdf, w_prev, sp, bounces, {0.0f, 0.0f}}; /* sp before scattering */
        if (visit && w->lens) v.u_lens = sampler_2d(rng);
        /* The next direction before the visit, whose camera connection is a chain of
         * divisions and a shadow ray nothing else waits on: after the sampling it overlaps
         * the next bounce instead of holding it back. */
        const bool more = !(w->max_depth > 0 && bounces >= w->max_depth) &&
                          subpath_scatter(s, &sp, it, &bsdf, &sh, w_prev, BSDF_IMPORTANCE, bounces, w->rr_depth,
                                          rng, &ray);
        if (visit && !w->visit(w->ctx, &v)) return false;
        if (!more) return true;
    }
}

#endif
