/* Whitted-style ray tracing (T. Whitted, "An Improved Illumination Model for Shaded
 * Display", CACM 1980): at mirrors and glass the ray tree branches deterministically into
 * every specular lobe, weighted by its Fresnel probability; at diffuse surfaces only the
 * light arriving straight from emitters (shadow rays) is reflected. What it leaves out,
 * and so where it is darker than the path tracer: diffuse interreflection and any light
 * reaching a diffuse surface through a mirror or glass (caustics). */
#include "integrators/whitted.h"

#include "integrators/direct.h"
#include "integrators/recorder.h"
#include "materials/bsdf.h"

/* Branches whose weight falls below this stop: adaptive tree depth control (Hall &
 * Greenberg, "A Testbed for Realistic Image Synthesis", 1983). Bounds the cost of glass,
 * where every hit splits in two, at a bias below 1e-4 of the radiance of what is cut. */
static const float WHITTED_MIN_WEIGHT = 1e-4f;

/* Direct light at a diffuse point: the mean of n light samples (direct.c: area points
 * converted to solid angle with dist^2 / |cos theta_light|, or point, spot and
 * directional lights, whose shadow rays are Whitted's own). */
static Color whitted_direct(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, int n, Sampler *smp,
                          const Wavelengths *wl, uint64_t *rays, Recorder *rec)
{
    Color sum = color_s(0.0f);
    for (int i = 0; i < n; i++) {
        float u_sel = sampler_1d(smp);
        Vec2 u = sampler_2d(smp);
        const Color d = direct_light(s, bsdf, sh, wo, u_sel, u, wl, rays);
        sum = color_add(sum, d);
        /* explain: each shadow ray apart (its share of the mean; not summed) */
        if (rec) recorder_whitted_light(rec, s, bsdf, sh, wo, u_sel, u, color_scale(d, 1.0f / (float)n));
    }
    return color_scale(sum, 1.0f / (float)n);
}

static Color whitted_trace(const Scene *s, const WhittedParams *wp, Ray ray, int depth, float weight, Sampler *smp,
                         const Wavelengths *wl, uint64_t *rays)
{
    SurfaceHit sh;
    ++*rays;
    if (!scene_intersect(s, &ray, &sh)) {
        Color le = scene_env_radiance(s, ray.d, wl);
        if (wp->rec) recorder_whitted(wp->rec, CST_EXPLAIN_ESCAPE, depth + 1, le);
        return le;
    }
    Vec3 wo = v3_neg(ray.d);
    Color L = sh.emitter >= 0 ? scene_emission(s, &sh, wo, wl) : color_s(0.0f);
    if (wp->rec) recorder_vertex(wp->rec, s, &sh, depth + 1, wl);
    if (wp->rec && sh.emitter >= 0) recorder_whitted(wp->rec, CST_EXPLAIN_EMISSION, depth + 1, L);

    Bsdf bsdf;
    scene_bsdf(s, &sh, wl, &bsdf);
    /* Non-delta lobes (diffuse, and glossy ones: rough metal, rough glass, the base of
     * plastic) get direct light only, Whitted's diffuse rule; a BSDF that also has delta
     * lobes (smooth-coat plastic) then branches into those below as well. */
    if (!bsdf_is_delta(&bsdf)) {
        if (s->emitter_sampler.lights > 0) {
            Color d = whitted_direct(s, &bsdf, &sh, wo, wp->light_samples, smp, wl, rays, wp->rec);
            L = color_add(L, d);
            if (wp->rec) recorder_whitted(wp->rec, CST_EXPLAIN_NEE, depth + 1, d);
        }
        if (!bsdf_has_delta(&bsdf)) return L;
    }
    if (depth >= wp->max_depth) return L;

    /* Every specular lobe once: the lobe choice of bsdf_sample (uc < F reflects) asked
     * for at both ends of [0, 1); under total internal reflection both give the mirror
     * direction, which is then counted once. A lobe's share of the radiance is its
     * probability times its sample weight (f |cos| / pdf). */
    const float ucs[2] = {0.0f, 0x1.fffffep-1f};
    bool reflected = false, refracted = false;
    Vec3 n = sh.ng;
    float side_o = v3_dot(wo, n);
    for (int k = 0; k < 2; k++) {
        BsdfSample bs;
        if (!bsdf_sample(&bsdf, wo, ucs[k], v2(0.5f, 0.5f), &bs) || !bs.delta) continue;
        bool reflect = (v3_dot(bs.wi, n) > 0.0f) == (side_o > 0.0f);
        if (reflect ? reflected : refracted) continue;
        if (reflect) reflected = true;
        else refracted = true;
        Color w = color_scale(bs.weight, bs.pmf);
        float wmax = weight * color_max(w);
        if (!(wmax >= WHITTED_MIN_WEIGHT)) continue;
        Ray next = ray_make_at(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY, sh.time);
        if (wp->rec) recorder_whitted_branch(wp->rec, &bs, w, depth + 1);
        L = color_madd(L, w, whitted_trace(s, wp, next, depth + 1, wmax, smp, wl, rays));
    }
    return L;
}

Color whitted_li(const Scene *s, const WhittedParams *wp, Ray ray, Sampler *smp, const Wavelengths *wl, uint64_t *rays)
{
    WhittedParams p = *wp;
    if (p.max_depth <= 0) p.max_depth = WHITTED_DEFAULT_DEPTH;
    if (p.light_samples <= 0) p.light_samples = 1;
    return whitted_trace(s, &p, ray, 0, 1.0f, smp, wl, rays);
}
