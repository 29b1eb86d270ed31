/* The path tracer in scenes with participating media (path_li hands them here): free-flight
 * distance sampling in the ray's medium, Henyey–Greenstein scattering, next-event
 * estimation at surface and medium vertices with transmittance through media and medium
 * boundaries, MIS against BSDF / phase sampling (Veach eq. 9.13), emission from media.
 * The volume rendering equation as in pbrt-v4 ch. 14 for homogeneous media; the distance
 * pdf over colour channels is medium.h's (balance heuristic over channels). Heterogeneous
 * media (grids, the cloud) are delta-tracked per segment (hetero_sample_distance: null
 * collisions, the same balance heuristic over the lanes' collision densities). */
#include "integrators/volpath.h"

#include "integrators/path_state.h"
#include "integrators/roulette.h"
#include "media/phase.h"

/* Crossings of boundary shapes in a row before the path gives up (a stack of coincident
 * boundaries would otherwise never end). */
enum { VOLPATH_MAX_CROSSINGS = 256 };

Color volpath_nee(const Scene *s, const VolVertex *v, bool mis, Sampler *smp, const Wavelengths *wl, uint64_t *rays)
{
    float u_sel = sampler_1d(smp);
    Vec2 u = sampler_2d(smp);
    return volpath_nee_u(s, v, mis, u_sel, u, wl, rays);
}

Color volpath_nee_u(const Scene *s, const VolVertex *v, bool mis, float u_sel, Vec2 u, const Wavelengths *wl,
                    uint64_t *rays)
{
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_nee(&s->emitter_sampler, &g, v->p, v->ns, u_sel, u, &ls)) return color_s(0.0f);
    Color f;
    float scatter_pdf;
    if (v->bsdf) {
        f = bsdf_eval(v->bsdf, v->wo, ls.wi);
        scatter_pdf = mis && !ls.delta ? bsdf_pdf(v->bsdf, v->wo, ls.wi) : 0.0f;
    } else {
        scatter_pdf = phase_hg_eval(v->wo, ls.wi, v->g);
        f = color_s(scatter_pdf);
    }
    if (color_is_black(f)) return color_s(0.0f);
    /* The shadow ray starts in the medium on the light's side of the surface. */
    int medium = v->sh ? scene_medium_after(s, v->sh, ls.wi, v->medium) : v->medium;
    Color tr = scene_transmittance_at(s, v->p, v->ng, ls.p, ls.n, medium, v->time, wl, rays);
    if (color_is_black(tr)) return color_s(0.0f);
    float w = mis && !ls.delta ? power_heuristic(ls.pdf_w, scatter_pdf) : 1.0f;
    return color_scale(color_mul(color_mul(f, tr), scene_light_li(s, &ls, wl)), w / (ls.delta ? ls.pmf : ls.pdf_w));
}

/* The throughput a contribution is weighted by: beta / mean(r_u), the balance heuristic
 * over lanes of the path's grid segments; beta itself (same operations as before grid
 * media) on paths that met none. */
static inline Color mis_beta(Color beta, int hero, Color r_u)
{
    if (hero < 0) return beta;
    float m = 0.0f;
    for (int c = 0; c < COLOR_LANES; c++) m += r_u.c[c];
    /* m overflows only on absurdly unlikely hero paths: dropped rather than inf x 0. */
    return m > 0.0f && isfinite(m) ? color_scale(beta, (float)COLOR_LANES / m) : color_s(0.0f);
}

Color volpath_li(const Scene *s, const PathParams *pp, Ray ray, Sampler *smp, Wavelengths *wl, uint64_t *rays)
{
    PathState ps = path_state_camera(ray.o); /* the camera vertex: nothing to MIS with */
    const float time = ray.time; /* motion blur: every ray of the path carries the camera ray's */
    const bool use_nee = pp->mode != PATH_BSDF && s->emitter_sampler.lights > 0;
    int medium = s->camera_medium, coeffs_of = -1;
    MediumCoeffs mc = {0};
    int crossings = 0;
    /* Spectral MIS over the lanes for grid media (hetero_medium.h): the hero lane of the
     * path's delta tracking (-1 until its first grid segment; paths without one never
     * touch r_u) and p_c / p_hero over its grid segments. */
    int hero = -1;
    Color r_u = color_s(1.0f);
    if (pp->rec) recorder_wavelengths(pp->rec, wl); /* a path of medium vertices alone has no surface hit */
    for (int depth = 0;;) {
        SurfaceHit sh;
        ++*rays;
        const bool hit = scene_intersect(s, &ray, &sh);
        if (medium >= 0) {
            if (coeffs_of != medium) { /* converted once per medium entered */
                mc = medium_coeffs(&s->media[medium], wl);
                coeffs_of = medium;
            }
            float u_ch = sampler_1d(smp), u_t = sampler_1d(smp);
            MediumSample ms;
            const Medium *med = &s->media[medium];
            const bool het = medium_is_hetero(med);
            if (het) {
                /* Delta tracking with the path's hero lane (picked at its first grid
                 * segment); its emission estimate covers the whole segment, also when
                 * the path passes through (below the depth limit only, as pbrt-v4). */
                if (hero < 0) hero = (int)fminf(u_ch * (float)COLOR_LANES, (float)(COLOR_LANES - 1));
                hetero_sample_distance(&med->u.het, &mc, ray.o, ray.d, hit ? sh.t : INFINITY, hero, r_u, u_t, &ms);
                if (mc.emissive && !(pp->max_depth > 0 && depth >= pp->max_depth)) ps.L = color_madd(ps.L, ps.beta, ms.le);
                if (pp->rec && mc.emissive && !(pp->max_depth > 0 && depth >= pp->max_depth)) recorder_add(pp->rec, CST_EXPLAIN_EMISSION, ps.beta, ms.le);
                r_u = color_mul(r_u, ms.r);
            } else {
                medium_sample_distance(&mc, hit ? sh.t : INFINITY, u_ch, u_t, &ms);
            }
            if (pp->rec) recorder_distance(pp->rec, medium, &mc, het, ray, hit ? sh.t : INFINITY, &ms);
            if (ms.scattered) {
                /* Emission of the segment: sigma_a Le Tr / pdf(t) (pbrt-v4 adds it below
                 * the depth limit only). */
                const bool last = pp->max_depth > 0 && depth >= pp->max_depth;
                if (mc.emissive && !last && !het)
                    ps.L = color_madd(ps.L, mis_beta(ps.beta, hero, r_u), color_mul(ms.tr_pdf, color_mul(mc.sigma_a, mc.le)));
                if (pp->rec && mc.emissive && !last && !het)
                    recorder_add(pp->rec, CST_EXPLAIN_EMISSION, mis_beta(ps.beta, hero, r_u), color_mul(ms.tr_pdf, color_mul(mc.sigma_a, mc.le)));
                ps.beta = color_mul(ps.beta, ms.weight);
                if (last || color_is_black(ps.beta)) break;
                Vec3 p = ray_at(&ray, ms.t), wo = v3_neg(ray.d);
                if (pp->rec) recorder_medium_vertex(pp->rec, p, medium, depth + 1);
                if (use_nee) {
                    VolVertex v = {p, v3s(0.0f), v3s(0.0f), wo, NULL, NULL, mc.g, medium, time};
                    const float u_sel = sampler_1d(smp); /* volpath_nee's draws, kept for explain */
                    const Vec2 u_l = sampler_2d(smp);
                    Color d = volpath_nee_u(s, &v, pp->mode == PATH_MIS, u_sel, u_l, wl, rays);
                    ps.L = color_madd(ps.L, mis_beta(ps.beta, hero, r_u), d);
                    if (pp->rec) recorder_vol_nee(pp->rec, s, &v, u_sel, u_l, pp->mode == PATH_MIS, mis_beta(ps.beta, hero, r_u), d);
                }
                Vec2 u = sampler_2d(smp);
                float pdf;
                Vec3 wi = phase_hg_sample(wo, mc.g, u.x, u.y, &pdf);
                /* f / pdf = 1: HG is sampled exactly. */
                ps.specular = false;
                ps.any_non_delta = true;
                ps.prev_pdf = pdf;
                ps.prev_p = p;
                ps.prev_n = v3s(0.0f);
                depth++;
                float rr = roulette(smp, depth, pp->rr_depth, mis_beta(ps.beta, hero, r_u));
                if (rr == 0.0f) break;
                ps.beta = color_scale(ps.beta, rr);
                ray = ray_make_at(p, wi, 0.0f, INFINITY, time);
                crossings = 0;
                continue;
            }
            ps.beta = color_mul(ps.beta, ms.weight);
            if (color_is_black(ps.beta)) break;
        }
        if (!hit) {
            path_add_env(s, pp, &ps, mis_beta(ps.beta, hero, r_u), ray.d, wl);
            break;
        }
        const MediumInterface *mi = scene_hit_medium_iface(s, &sh);
        if (mi && mi->boundary) {
            /* Only a boundary: cross it into the next medium, not a path vertex. */
            if (++crossings > VOLPATH_MAX_CROSSINGS) break;
            medium = v3_dot(ray.d, sh.ng) < 0.0f ? mi->inside : mi->outside;
            ray = ray_make_at(scene_offset(s, sh.p, sh.ng, ray.d), ray.d, 0.0f, INFINITY, time);
            continue;
        }
        Vec3 wo = v3_neg(ray.d);
        if (pp->rec) recorder_vertex(pp->rec, s, &sh, depth + 1, wl);
        /* NEE's pdf from the previous vertex, across any boundaries crossed since. */
        if (sh.emitter >= 0)
            path_add_emitted(s, pp, &ps, mis_beta(ps.beta, hero, r_u), &sh, wo, v3_length(v3_sub(sh.p, ps.prev_p)), wl);
        if (pp->max_depth > 0 && depth >= pp->max_depth) break;

        Bsdf bsdf;
        scene_bsdf_disperse(s, &sh, wl, &bsdf);
        if (pp->rec) recorder_wavelengths(pp->rec, wl);
        if (pp->regularize && ps.any_non_delta) bsdf_regularize(&bsdf);
        if (use_nee && !bsdf_is_delta(&bsdf)) {
            VolVertex v = {sh.p, sh.ns, sh.ng, wo, &bsdf, &sh, 0.0f, medium, time};
            const float u_sel = sampler_1d(smp); /* volpath_nee's draws, kept for explain */
            const Vec2 u_l = sampler_2d(smp);
            Color d = volpath_nee_u(s, &v, pp->mode == PATH_MIS, u_sel, u_l, wl, rays);
            ps.L = color_madd(ps.L, mis_beta(ps.beta, hero, r_u), d);
            if (pp->rec) recorder_vol_nee(pp->rec, s, &v, u_sel, u_l, pp->mode == PATH_MIS, mis_beta(ps.beta, hero, r_u), d);
        }
        BsdfSample bs;
        if (!path_sample_bsdf(pp, &ps, &bsdf, &sh, wo, smp, &bs)) break;
        depth++;
        float rr = roulette(smp, depth, pp->rr_depth, mis_beta(ps.beta, hero, r_u));
        if (rr == 0.0f) break;
        ps.beta = color_scale(ps.beta, rr);
        medium = scene_medium_after(s, &sh, bs.wi, medium);
        ray = ray_make_at(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, time);
        crossings = 0;
    }
    return ps.L;
}
