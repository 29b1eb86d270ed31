/* Path tracer with next-event estimation and multiple importance sampling.
 * Estimator: Veach's thesis ch. 9; power heuristic with beta = 2 (eq. 9.13). */
#include "integrators/path.h"

#include "materials/bsdf.h"

static inline float power_heuristic(float pdf_a, float pdf_b)
{
    float a = pdf_a * pdf_a, b = pdf_b * pdf_b;
    return a / (a + b);
}

/* Direct light at a non-delta vertex by sampling a light (light_sample_li: an area point
 * converted to solid angle, pdf_w = pdf_a dist^2 / |cos theta_light|, or a delta light). */
static Rgb sample_direct(const Scene *s, const PathParams *pp, const Bsdf *bsdf,
                         const SurfaceHit *sh, Vec3 wo, Pcg32 *rng, uint64_t *rays)
{
    float u_sel = pcg32_float(rng);
    Vec2 u = v2(pcg32_float(rng), pcg32_float(rng));
    LightLi ls;
    EmitterGeometry g = {s->positions, s->tri_indices, s->num_triangles, s->spheres};
    if (!light_sample_li(&s->emitter_sampler, s->emitters, &g, sh->p, u_sel, u, &ls)) return rgb_s(0.0f);
    Rgb f = bsdf_eval(bsdf, wo, ls.wi);
    if (rgb_is_black(f)) return rgb_s(0.0f);
    ++*rays;
    if (!scene_visible(s, sh->p, sh->ng, ls.p, ls.n)) return rgb_s(0.0f);
    /* A delta light cannot be hit by BSDF sampling: NEE is its only strategy. */
    float w = pp->mode == PATH_MIS && !ls.delta ? power_heuristic(ls.pdf, bsdf_pdf(bsdf, wo, ls.wi)) : 1.0f;
    return rgb_scale(rgb_mul(f, ls.li), w / ls.pdf);
}

Rgb path_li(const Scene *s, const PathParams *pp, Ray ray, Pcg32 *rng, uint64_t *rays)
{
    Rgb L = rgb_s(0.0f), beta = rgb_s(1.0f);
    bool specular = true; /* the camera vertex acts like a delta lobe: nothing to MIS with */
    float prev_pdf = 0.0f;
    bool use_nee = pp->mode != PATH_BSDF && s->emitter_sampler.lights > 0;
    for (int depth = 0;; depth++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) break;
        Vec3 wo = v3_neg(ray.d);

        if (sh.emitter >= 0) {
            Rgb le = emitter_radiance(&s->emitters[sh.emitter], sh.ng, wo);
            if (!rgb_is_black(le)) {
                if (specular || pp->mode == PATH_BSDF) {
                    L = rgb_madd(L, beta, le);
                } else if (pp->mode == PATH_MIS) {
                    float cos_l = fabsf(v3_dot(sh.ng, wo));
                    float pdf_light = cos_l > 0.0f ? emitter_pdf_a(&s->emitter_sampler, sh.emitter) * sh.t * sh.t / cos_l : 0.0f;
                    L = rgb_madd(L, beta, rgb_scale(le, power_heuristic(prev_pdf, pdf_light)));
                }
                /* PATH_NEE: this emitter was already counted by the previous vertex's NEE. */
            }
        }
        if (pp->max_depth > 0 && depth >= pp->max_depth) break;

        Bsdf bsdf;
        bsdf_init(&bsdf, &s->materials[sh.material], sh.ng);
        if (use_nee && !bsdf_is_delta(&bsdf))
            L = rgb_madd(L, beta, sample_direct(s, pp, &bsdf, &sh, wo, rng, rays));

        BsdfSample bs;
        float uc = pcg32_float(rng);
        Vec2 u = v2(pcg32_float(rng), pcg32_float(rng));
        if (!bsdf_sample(&bsdf, wo, uc, u, &bs)) break;
        beta = rgb_mul(beta, bs.weight);
        if (rgb_is_black(beta)) break;
        specular = bs.delta;
        prev_pdf = bs.pdf;

        /* Russian roulette: survive with probability q, reweight by 1/q (unbiased).
         * q follows the throughput so dim paths stop early; capped below 1 so even an
         * albedo-1 furnace terminates. */
        if (depth + 1 >= pp->rr_depth) {
            float q = minf(0.95f, rgb_max(beta));
            if (!(pcg32_float(rng) < q)) break;
            beta = rgb_scale(beta, 1.0f / q);
        }
        ray = ray_make(scene_offset(sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY);
    }
    return L;
}
