/* The path tracer in scenes with subsurface materials (path_li hands them here): path_li's
 * loop plus pbrt-v4's BSSRDF step (VolPathIntegrator, pbrt 4th ed. sec. 14.3.3 / 3rd ed.
 * sec. 15.4): a refraction into a subsurface material samples a probe segment
 * (materials/bssrdf.h), picks one of the material's intersections along it uniformly
 * (reservoir of one), and the path continues from there with the Sw lobe and NEE. The
 * recorder hooks of path_li (`caustic explain`; pp->rec NULL in renders) plus the exit. */
#include "integrators/path_sss.h"

#include "core/rng.h"
#include "integrators/direct.h"
#include "integrators/path_state.h"
#include "integrators/roulette.h"
#include "materials/bssrdf.h"
#include "sampling/warp.h"

/* Hits along one probe segment before it gives up (a stack of coincident surfaces would
 * otherwise never end). */
enum { PROBE_MAX_HITS = 64 };

/* The medium's sigma_a, sigma_s at the entry hit, at the path's wavelengths (wl) or in RGB:
 * given, or from the diffuse reflectance (texture at the hit) and mean free path (pbrt-v4
 * SubsurfaceMaterial::GetBSSRDF: reflectance as an albedo spectrum clamped to [0, 1], the
 * coefficients and mfp as unbounded spectra). */
static void sss_coeffs(const Scene *s, const Material *m, const SurfaceHit *sh, const Wavelengths *wl,
                       Color *sigma_a, Color *sigma_s)
{
    if (!m->sss_from_reflectance) {
        *sigma_a = wl ? spectrum_unbounded(m->sss_sigma_a, wl) : m->sss_sigma_a;
        *sigma_s = wl ? spectrum_unbounded(m->sss_sigma_s, wl) : m->sss_sigma_s;
        return;
    }
    Color r = m->sss_reflectance;
    if (m->sss_reflectance_texture) {
        TexCtx c = {.uv = sh->uv, .p = sh->p, .n = sh->ng};
        r = texture_eval_ctx(s->textures, m->sss_reflectance_texture - 1, &c);
    }
    if (wl) r = spectrum_albedo(r, wl);
    Color mfp = wl ? spectrum_unbounded(m->sss_mfp, wl) : m->sss_mfp;
    for (int c = 0; c < COLOR_LANES; c++) r.c[c] = clampf(r.c[c], 0.0f, 1.0f);
    bssrdf_from_reflectance(m->bssrdf, r, mfp, sigma_a, sigma_s);
}

/* The intersections of material `material` on the segment p0 -> p1, one kept uniformly
 * (weighted reservoir sampling with equal weights, its random numbers from u). Returns
 * their count. */
static int sss_probe(const Scene *s, Vec3 p0, Vec3 p1, int material, float u, float time, SurfaceHit *pick,
                     uint64_t *rays)
{
    Pcg32 rng;
    pcg32_seed(&rng, (uint64_t)(u * 4294967296.0f), 0x55u);
    int count = 0;
    Vec3 o = p0;
    for (int i = 0; i < PROBE_MAX_HITS; i++) {
        Vec3 d = v3_sub(p1, o);
        float len = v3_length(d);
        if (!(len > 0.0f)) break;
        Ray r = ray_make_at(o, v3_scale(d, 1.0f / len), 0.0f, len, time);
        SurfaceHit h;
        ++*rays;
        if (!scene_intersect(s, &r, &h)) break;
        if (h.material == material && pcg32_float(&rng) * (float)++count < 1.0f) *pick = h;
        o = scene_offset(s, h.p, h.ng, r.d);
    }
    return count;
}

/* One light sample at the exit point (Sw lobe f = Sw(cos) eta^2 on ng's side; the eta^2
 * undoes the entry's radiance scaling 1 / eta^2, as pbrt-v4's NormalizedFresnelBxDF in
 * radiance mode), MIS-weighted against the lobe's cosine sampling when mis. */
static Color sss_nee(const Scene *s, const SurfaceHit *x, float eta, bool mis, float u_sel, Vec2 u,
                     const Wavelengths *wl, uint64_t *rays)
{
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_nee(&s->emitter_sampler, &g, x->p, x->ns, u_sel, u, &ls)) return color_s(0.0f);
    float cos_s = v3_dot(ls.wi, x->ns);
    if (!(cos_s > 0.0f) || !(v3_dot(ls.wi, x->ng) > 0.0f)) return color_s(0.0f);
    float f = bssrdf_sw(eta, cos_s) * eta * eta * cos_s;
    if (!(f > 0.0f)) return color_s(0.0f);
    ++*rays;
    if (!scene_visible_at(s, x->p, x->ng, ls.p, ls.n, x->time)) return color_s(0.0f);
    float w = mis && !ls.delta ? power_heuristic(ls.pdf_w, cos_s * CST_INV_PI) : 1.0f;
    return color_scale(scene_light_li(s, &ls, wl), f * w / (ls.delta ? ls.pmf : ls.pdf_w));
}

Color path_sss_li(const Scene *s, const PathParams *pp, Ray ray, Sampler *smp, Wavelengths *wl, uint64_t *rays)
{
    PathState ps = path_state_camera(ray.o); /* the camera vertex acts like a delta lobe */
    const bool use_nee = pp->mode != PATH_BSDF && s->emitter_sampler.lights > 0;
    for (int depth = 0;; depth++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) {
            if (pp->rec) recorder_wavelengths(pp->rec, wl); /* as path_li */
            path_add_env(s, pp, &ps, ps.beta, ray.d, wl);
            break;
        }
        Vec3 wo = v3_neg(ray.d);
        if (pp->rec) recorder_vertex(pp->rec, s, &sh, depth + 1, wl);
        /* NEE's pdf from the previous vertex (the BSSRDF's exit point is one too) */
        if (sh.emitter >= 0) path_add_emitted(s, pp, &ps, ps.beta, &sh, wo, v3_length(v3_sub(sh.p, ps.prev_p)), wl);
        if (pp->max_depth > 0 && depth >= pp->max_depth) break;

        Bsdf bsdf;
        const Material *m = scene_bsdf_material(s, &sh, wl, wl != NULL, &bsdf);
        if (wl && m->ior_dispersive) wavelengths_terminate_secondary(wl);
        if (pp->rec) recorder_wavelengths(pp->rec, wl);
        if (pp->regularize && ps.any_non_delta) bsdf_regularize(&bsdf);
        if (use_nee && !bsdf_is_delta(&bsdf)) path_add_nee(s, pp, &ps, &bsdf, &sh, wo, smp, wl, rays);
        BsdfSample bs;
        if (!path_sample_bsdf(pp, &ps, &bsdf, &sh, wo, smp, &bs)) break;

        const bool transmitted = (v3_dot(bs.wi, sh.ng) > 0.0f) != (v3_dot(wo, sh.ng) > 0.0f);
        if (m->subsurface && m->bssrdf && transmitted) {
            /* The BSSRDF step: Sp(pi) / (pdf_sp(pi) / count), then the Sw lobe at pi. */
            Color sa, ss;
            sss_coeffs(s, m, &sh, wl, &sa, &ss);
            Bssrdf b;
            bssrdf_init(&b, m->bssrdf, sa, ss, sh.p, sh.ns);
            float u1 = sampler_1d(smp);
            Vec2 u2 = sampler_2d(smp);
            float u_pick = sampler_1d(smp);
            Vec3 p0, p1;
            if (!bssrdf_sample_probe(&b, u1, u2, &p0, &p1)) break;
            SurfaceHit x;
            int count = sss_probe(s, p0, p1, sh.material, u_pick, sh.time, &x, rays);
            if (count == 0) break;
            float pdf = bssrdf_pdf_sp(&b, x.p, x.ng) / (float)count;
            if (!(pdf > 0.0f)) break;
            ps.beta = color_scale(color_mul(ps.beta, bssrdf_sr(&b, v3_length(v3_sub(x.p, sh.p)))), 1.0f / pdf);
            if (color_is_black(ps.beta)) break;
            const float eta = m->bssrdf->eta;
            if (pp->rec) recorder_sss_exit(pp->rec, &x, pdf, count, ps.beta);
            if (use_nee) {
                const float u_sel = sampler_1d(smp); /* kept for explain's recorder_sss_nee */
                const Vec2 u_l = sampler_2d(smp);
                Color d = sss_nee(s, &x, eta, pp->mode == PATH_MIS, u_sel, u_l, wl, rays);
                ps.L = color_madd(ps.L, ps.beta, d);
                if (pp->rec) recorder_sss_nee(pp->rec, s, &x, u_sel, u_l, pp->mode == PATH_MIS, ps.beta, d);
            }
            /* Sw by cosine sampling about the exit's shading normal (on ng's side):
             * weight Sw cos eta^2 / (cos / pi) */
            Vec2 uw = sampler_2d(smp);
            Vec3 wl_local = warp_cosine_hemisphere(uw);
            Frame f = frame_from_normal(x.ns);
            Vec3 wi = frame_to_world(&f, wl_local);
            if (!(v3_dot(wi, x.ng) > 0.0f) || !(wl_local.z > 0.0f)) break;
            const float sw = bssrdf_sw(eta, wl_local.z) * eta * eta * CST_PI;
            if (pp->rec) recorder_sss_scatter(pp->rec, wi, wl_local.z * CST_INV_PI, sw, ps.beta);
            ps.beta = color_scale(ps.beta, sw);
            if (color_is_black(ps.beta)) break;
            ps.specular = false;
            ps.any_non_delta = true;
            ps.prev_pdf = wl_local.z * CST_INV_PI;
            ps.prev_p = x.p;
            ps.prev_n = x.ns;
            float rr = roulette(smp, depth + 1, pp->rr_depth, ps.beta);
            if (pp->rec && depth + 1 >= pp->rr_depth) recorder_roulette(pp->rec, roulette_survival(ps.beta), rr != 0.0f);
            if (rr == 0.0f) break;
            ps.beta = color_scale(ps.beta, rr);
            ray = ray_make_at(scene_offset(s, x.p, x.ng, wi), wi, 0.0f, INFINITY, x.time);
            continue;
        }

        float rr = roulette(smp, depth + 1, pp->rr_depth, ps.beta);
        if (pp->rec && depth + 1 >= pp->rr_depth) recorder_roulette(pp->rec, roulette_survival(ps.beta), rr != 0.0f);
        if (rr == 0.0f) break;
        ps.beta = color_scale(ps.beta, rr);
        ray = ray_make_at(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, sh.time);
    }
    return ps.L;
}
