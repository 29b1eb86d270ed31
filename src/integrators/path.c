/* Path tracer with next-event estimation and multiple importance sampling.
 * Estimator: Veach's thesis ch. 9; power heuristic with beta = 2 (eq. 9.13). */
#include "integrators/path.h"

#include "integrators/path_sss.h"
#include "integrators/path_state.h"
#include "integrators/roulette.h"
#include "integrators/volpath.h"

Color path_li(const Scene *s, const PathParams *pp, Ray ray, Sampler *smp, Wavelengths *wl, uint64_t *rays)
{
    /* Participating media: the volumetric loop (volpath.c); one branch for other scenes. */
    if (s->num_media | s->num_medium_ifaces) return volpath_li(s, pp, ray, smp, wl, rays);
    /* Subsurface materials: the loop with the BSSRDF step (path_sss.c). */
    if (s->num_subsurface) return path_sss_li(s, pp, ray, smp, wl, rays);
    PathState ps = path_state_camera(ray.o); /* the camera vertex acts like a delta lobe */
    const bool use_nee = pp->mode != PATH_BSDF && s->emitter_sampler.lights > 0;
    for (int depth = 0;; depth++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) {
            /* The environment: counted like an emitter hit, with the same MIS against
             * NEE's density of sampling this direction. */
            if (pp->rec) recorder_wavelengths(pp->rec, wl); /* a camera ray may miss everything */
            path_add_env(s, pp, &ps, ps.beta, ray.d, wl);
            break;
        }
        Vec3 wo = v3_neg(ray.d);
        if (pp->rec) recorder_vertex(pp->rec, s, &sh, depth + 1, wl);
        if (sh.emitter >= 0) path_add_emitted(s, pp, &ps, ps.beta, &sh, wo, sh.t, wl);
        if (pp->max_depth > 0 && depth >= pp->max_depth) break;

        Bsdf bsdf;
        /* A dispersive dielectric terminates wl's secondary wavelengths here (the rest of
         * the path and the film's conversion then follow the hero alone). */
        scene_bsdf_disperse(s, &sh, wl, &bsdf);
        if (pp->rec) recorder_wavelengths(pp->rec, wl);
        if (pp->regularize && ps.any_non_delta) bsdf_regularize(&bsdf);
        if (use_nee && !bsdf_is_delta(&bsdf)) path_add_nee(s, pp, &ps, &bsdf, &sh, wo, smp, wl, rays);

        BsdfSample bs;
        if (!path_sample_bsdf(pp, &ps, &bsdf, &sh, wo, smp, &bs)) break;
        /* Russian roulette (roulette.h): beta is the path's scatter. */
        float rr = roulette(smp, depth + 1, pp->rr_depth, ps.beta);
        if (pp->rec && depth + 1 >= pp->rr_depth) recorder_roulette(pp->rec, roulette_survival(ps.beta), rr != 0.0f);
        if (rr == 0.0f) break;
        ps.beta = color_scale(ps.beta, rr);
        ray = ray_make_at(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, sh.time);
    }
    return ps.L;
}
