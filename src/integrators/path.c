/* Path tracer with next-event estimation and multiple importance sampling.
 * Estimator: Veach's thesis ch. 9; power heuristic with beta = 2 (eq. 9.13). */
#include "integrators/path.h"

#include "integrators/direct.h"
#include "integrators/roulette.h"
#include "integrators/path_sss.h"
#include "integrators/recorder.h"
#include "integrators/volpath.h"
#include "materials/bsdf.h"

/* explain's record of a ray that left the scene: the environment's radiance le (black
 * without one) with the weight path_li applies, computed again. */
static void path_record_env(const PathParams *pp, const Scene *s, bool specular, Color le, Color beta, float prev_pdf,
                            Vec3 prev_p, Vec3 prev_n, Vec3 d)
{
    if (color_is_black(le) || (!specular && pp->mode == PATH_NEE)) { /* nothing added here */
        recorder_push(pp->rec, CST_EXPLAIN_ESCAPE);
        return;
    }
    if (specular || pp->mode == PATH_BSDF) { recorder_emission(pp->rec, NULL, d, beta, le, 1.0f, prev_pdf, 0.0f); return; }
    float pdf_light = light_env_nee_pdf(&s->emitter_sampler, prev_p, prev_n, d);
    recorder_emission(pp->rec, NULL, d, beta, color_scale(le, power_heuristic(prev_pdf, pdf_light)),
                      power_heuristic(prev_pdf, pdf_light), prev_pdf, pdf_light);
}

Color path_li(const Scene *s, const PathParams *pp, Ray ray, Sampler *smp, Wavelengths *wl, uint64_t *rays)
{
    /* Participating media: the volumetric loop (volpath.c); one branch for other scenes. */
    if (s->num_media | s->num_medium_ifaces) return volpath_li(s, pp, ray, smp, wl, rays);
    /* Subsurface materials: the loop with the BSSRDF step (path_sss.c). */
    if (s->num_subsurface) return path_sss_li(s, pp, ray, smp, wl, rays);
    Color L = color_s(0.0f), beta = color_s(1.0f);
    bool specular = true; /* the camera vertex acts like a delta lobe: nothing to MIS with */
    float prev_pdf = 0.0f;
    Vec3 prev_p = ray.o; /* the previous vertex: NEE's reference point there */
    Vec3 prev_n = v3s(0.0f); /* and its shading normal, for the light BVH's pmf */
    bool use_nee = pp->mode != PATH_BSDF && s->emitter_sampler.lights > 0;
    bool any_non_delta = false; /* a non-delta bounce so far: regularize from then on */
    for (int depth = 0;; depth++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) {
            /* The environment: counted like an emitter hit, with the same MIS against
             * NEE's density of sampling this direction. */
            Color le = scene_env_radiance(s, ray.d, wl);
            if (!color_is_black(le)) {
                if (specular || pp->mode == PATH_BSDF) L = color_madd(L, beta, le);
                else if (pp->mode == PATH_MIS)
                    L = color_madd(L, beta, color_scale(le, power_heuristic(prev_pdf, light_env_nee_pdf(&s->emitter_sampler, prev_p, prev_n, ray.d))));
            }
            if (pp->rec) path_record_env(pp, s, specular, le, beta, prev_pdf, prev_p, prev_n, ray.d);
            break;
        }
        Vec3 wo = v3_neg(ray.d);
        if (pp->rec) recorder_vertex(pp->rec, s, &sh, depth + 1, wl);

        if (sh.emitter >= 0) {
            Color le = scene_emission(s, &sh, wo, wl);
            if (!color_is_black(le)) {
                if (specular || pp->mode == PATH_BSDF) {
                    L = color_madd(L, beta, le);
                    if (pp->rec) recorder_emission(pp->rec, &sh, wo, beta, le, 1.0f, prev_pdf, 0.0f);
                } else if (pp->mode == PATH_MIS) {
                    float cos_l = fabsf(v3_dot(sh.ng, wo));
                    EmitterGeometry g = scene_emitter_geometry(s);
                    float pdf_light =
                        light_area_nee_pdf_w(&s->emitter_sampler, &g, sh.emitter, prev_p, prev_n, sh.t, cos_l);
                    L = color_madd(L, beta, color_scale(le, power_heuristic(prev_pdf, pdf_light)));
                    if (pp->rec)
                        recorder_emission(pp->rec, &sh, wo, beta, color_scale(le, power_heuristic(prev_pdf, pdf_light)),
                                          power_heuristic(prev_pdf, pdf_light), prev_pdf, pdf_light);
                }
                /* PATH_NEE: this emitter was already counted by the previous vertex's NEE. */
            }
        }
        if (pp->max_depth > 0 && depth >= pp->max_depth) break;

        Bsdf bsdf;
        /* A dispersive dielectric terminates wl's secondary wavelengths here (the rest of
         * the path and the film's conversion then follow the hero alone). */
        scene_bsdf_disperse(s, &sh, wl, &bsdf);
        if (pp->rec) recorder_wavelengths(pp->rec, wl);
        if (pp->regularize && any_non_delta) bsdf_regularize(&bsdf);
        if (use_nee && !bsdf_is_delta(&bsdf)) {
            float u_sel = sampler_1d(smp);
            Vec2 u_light = sampler_2d(smp);
            Color d = pp->mode == PATH_MIS ? direct_light_mis(s, &bsdf, &sh, wo, u_sel, u_light, wl, rays)
                                           : direct_light(s, &bsdf, &sh, wo, u_sel, u_light, wl, rays);
            L = color_madd(L, beta, d);
            if (pp->rec) recorder_nee(pp->rec, s, &bsdf, &sh, wo, u_sel, u_light, pp->mode == PATH_MIS, beta, d);
        }

        BsdfSample bs;
        float uc = sampler_1d(smp);
        Vec2 u = sampler_2d(smp);
        if (!bsdf_sample(&bsdf, wo, uc, u, &bs)) break;
        if (pp->rec) recorder_scatter(pp->rec, &bs, beta);
        beta = color_mul(beta, bs.weight);
        if (color_is_black(beta)) break;
        specular = bs.delta;
        any_non_delta |= !bs.delta;
        prev_pdf = bs.delta ? bs.pmf : bs.pdf_w;
        prev_p = sh.p;
        prev_n = sh.ns;

        /* Russian roulette (roulette.h): beta is the path's scatter. */
        float rr = roulette(smp, depth + 1, pp->rr_depth, beta);
        if (pp->rec && depth + 1 >= pp->rr_depth) recorder_roulette(pp->rec, minf(0.95f, color_max(beta)), rr != 0.0f);
        if (rr == 0.0f) break;
        beta = color_scale(beta, rr);
        ray = ray_make(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY);
    }
    return L;
}
