/* The state a unidirectional camera path carries from bounce to bounce, and the steps the
 * three path loops share (path.c, path_sss.c, volpath.c): emitter and environment hits
 * MIS-weighted against next-event estimation, NEE at a surface, BSDF sampling. Each step
 * also tells `caustic explain`'s recorder (pp->rec, NULL in renders: one branch) what it
 * added. */
#ifndef CST_INTEGRATORS_PATH_STATE_H
#define CST_INTEGRATORS_PATH_STATE_H

#include "integrators/direct.h"
#include "integrators/path.h"
#include "integrators/recorder.h"
#include "materials/bsdf.h"

typedef struct PathState {
    Color L;    /* radiance gathered so far */
    Color beta; /* throughput: product of f cos / pdf (and 1 / q of Russian roulette) */
    /* The previous scattering vertex, as the MIS of an emitter hit needs it (Veach eq.
     * 9.13): */
    bool specular;  /* sampled by a delta lobe, or the camera: no NEE strategy to weigh */
    float prev_pdf; /* pdf_w of the direction taken there (a delta lobe's pmf) */
    Vec3 prev_p;    /* its position: NEE's reference point */
    Vec3 prev_n;    /* its shading normal, for the light BVH's pmf (zero in a medium) */
    bool any_non_delta; /* a non-delta bounce so far: regularize from then on */
} PathState;

static inline PathState path_state_camera(Vec3 origin)
{
    return (PathState){color_s(0.0f), color_s(1.0f), true, 0.0f, origin, v3s(0.0f), false};
}

/* L += w x the environment's radiance along d (a missed ray), with the MIS weight of BSDF
 * sampling against NEE's density of sampling d. `w` is the throughput to weight by:
 * beta, or volpath's spectral-MIS throughput. */
static inline void path_add_env(const Scene *s, const PathParams *pp, PathState *ps, Color w, Vec3 d,
                                const Wavelengths *wl)
{
    Color le = scene_env_radiance(s, d, wl);
    if (!color_is_black(le) && (ps->specular || pp->mode == PATH_BSDF)) {
        ps->L = color_madd(ps->L, w, le);
        if (pp->rec) recorder_emission(pp->rec, NULL, d, w, le, 1.0f, ps->prev_pdf, 0.0f);
    } else if (!color_is_black(le) && pp->mode == PATH_MIS) {
        float pdf_light = light_env_nee_pdf(&s->emitter_sampler, ps->prev_p, ps->prev_n, d);
        Color v = color_scale(le, power_heuristic(ps->prev_pdf, pdf_light));
        ps->L = color_madd(ps->L, w, v);
        if (pp->rec) recorder_emission(pp->rec, NULL, d, w, v, power_heuristic(ps->prev_pdf, pdf_light), ps->prev_pdf, pdf_light);
    } else if (pp->rec) {
        /* PATH_NEE: the environment was already counted by the previous vertex's NEE. */
        recorder_push(pp->rec, CST_EXPLAIN_ESCAPE);
    }
}

/* L += w x the emission of the emitter hit sh (sh->emitter >= 0) seen along wo, with the
 * MIS weight against NEE's pdf_w of sampling it from prev_p, `dist` away. */
static inline void path_add_emitted(const Scene *s, const PathParams *pp, PathState *ps, Color w,
                                    const SurfaceHit *sh, Vec3 wo, float dist, const Wavelengths *wl)
{
    Color le = scene_emission(s, sh, wo, wl);
    if (color_is_black(le)) return;
    if (ps->specular || pp->mode == PATH_BSDF) {
        ps->L = color_madd(ps->L, w, le);
        if (pp->rec) recorder_emission(pp->rec, sh, wo, w, le, 1.0f, ps->prev_pdf, 0.0f);
    } else if (pp->mode == PATH_MIS) {
        float cos_l = fabsf(v3_dot(sh->ng, wo));
        EmitterGeometry g = scene_emitter_geometry(s);
        float pdf_light = light_area_nee_pdf_w(&s->emitter_sampler, &g, sh->emitter, ps->prev_p, ps->prev_n, dist, cos_l);
        Color v = color_scale(le, power_heuristic(ps->prev_pdf, pdf_light));
        ps->L = color_madd(ps->L, w, v);
        if (pp->rec) recorder_emission(pp->rec, sh, wo, w, v, power_heuristic(ps->prev_pdf, pdf_light), ps->prev_pdf, pdf_light);
    }
    /* PATH_NEE: this emitter was already counted by the previous vertex's NEE. */
}

/* Next-event estimation at a non-delta surface vertex without media: one light sample
 * (direct.h), MIS-weighted in PATH_MIS. */
static inline void path_add_nee(const Scene *s, const PathParams *pp, PathState *ps, const Bsdf *bsdf,
                                const SurfaceHit *sh, Vec3 wo, Sampler *smp, const Wavelengths *wl, uint64_t *rays)
{
    float u_sel = sampler_1d(smp);
    Vec2 u_light = sampler_2d(smp);
    Color d = pp->mode == PATH_MIS ? direct_light_mis(s, bsdf, sh, wo, u_sel, u_light, wl, rays)
                                   : direct_light(s, bsdf, sh, wo, u_sel, u_light, wl, rays);
    ps->L = color_madd(ps->L, ps->beta, d);
    if (pp->rec) recorder_nee(pp->rec, s, bsdf, sh, wo, u_sel, u_light, pp->mode == PATH_MIS, ps->beta, d);
}

/* Samples the direction leaving surface hit sh by the BSDF and makes sh the previous
 * vertex. False when the path ends: no sample, or a black throughput. */
static inline bool path_sample_bsdf(const PathParams *pp, PathState *ps, const Bsdf *bsdf, const SurfaceHit *sh,
                                    Vec3 wo, Sampler *smp, BsdfSample *bs)
{
    float uc = sampler_1d(smp);
    Vec2 u = sampler_2d(smp);
    if (!bsdf_sample(bsdf, wo, uc, u, bs)) return false;
    if (pp->rec) recorder_scatter(pp->rec, bs, ps->beta);
    ps->beta = color_mul(ps->beta, bs->weight);
    if (color_is_black(ps->beta)) return false;
    ps->specular = bs->delta;
    ps->any_non_delta |= !bs->delta;
    ps->prev_pdf = bs->delta ? bs->pmf : bs->pdf_w;
    ps->prev_p = sh->p;
    ps->prev_n = sh->ns;
    return true;
}

#endif
