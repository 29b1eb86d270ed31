/* One-sample direct lighting shared by the integrators that do not MIS it. */
#include "integrators/direct.h"

static Color sample(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, bool mis, float u_sel,
                  Vec2 u, const Wavelengths *wl, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return color_s(0.0f);
    LightLi ls;
    EmitterGeometry g = scene_emitter_geometry(s);
    if (!light_sample_nee(&s->emitter_sampler, &g, sh->p, sh->ns, u_sel, u, &ls)) return color_s(0.0f);
    Color f = bsdf_eval(bsdf, wo, ls.wi);
    if (color_is_black(f)) return color_s(0.0f);
    ++*rays;
    if (!scene_visible_at(s, sh->p, sh->ng, ls.p, ls.n, sh->time)) return color_s(0.0f);
    float w = mis && !ls.delta ? power_heuristic(ls.pdf_w, bsdf_pdf(bsdf, wo, ls.wi)) : 1.0f;
    return color_scale(color_mul(f, scene_light_li(s, &ls, wl)), w / (ls.delta ? ls.pmf : ls.pdf_w));
}

Color direct_light(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel, Vec2 u,
                 const Wavelengths *wl, uint64_t *rays)
{
    return sample(s, bsdf, sh, wo, false, u_sel, u, wl, rays);
}

Color direct_light_mis(const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                     Vec2 u, const Wavelengths *wl, uint64_t *rays)
{
    return sample(s, bsdf, sh, wo, true, u_sel, u, wl, rays);
}
