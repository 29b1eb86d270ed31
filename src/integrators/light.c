/* Light tracer: Veach thesis ch. 10 (the t = 1 strategies of bidirectional path tracing,
 * here without MIS); pbrt-v4 LightPathIntegrator. A light path y0 (on an emitter), y1, ...
 * with throughput beta_j connects every non-delta vertex y_j to a point on the lens:
 *   splat = beta_j f(y_j: w_cam <- w_prev) |cos theta_cam| W_e / pdf_w   (j >= 1)
 *   splat = L_e(y0 -> w_cam) |cos theta_cam| W_e / (pdf_a pdf_w)           (j = 0)
 * with V(y_j, lens) = 1; W_e / pdf_w = 1 / (A cos^3 theta d^2) (camera.c). */
#include "integrators/light.h"

#include "film/filter.h"
#include "integrators/roulette.h"
#include "materials/bsdf.h"

/* Splats weight * W_e / pdf_w if the lens point is visible; weight already holds the
 * throughput and the vertex's f |cos theta_cam| (or L_e |cos theta_cam|). */
static void splat_if_visible(const Scene *s, const LightParams *lp,
                             Vec3 p, Vec3 ng, const CameraWiSample *cs, Color weight,
                             SplatList *out, uint64_t *rays)
{
    if (color_is_black(weight)) return;
    ++*rays;
    if (!scene_visible_point(s, p, ng, cs->p_lens)) return;
    film_splat(out, &lp->frame, cs->raster.x, cs->raster.y,
               color_scale(weight, cs->we / cs->pdf_w));
}

void light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng,
                 SplatList *out, uint64_t *rays)
{
    if (s->emitter_sampler.lights == 0) return;
    /* The tent reaches half a pixel past the film's edge (film_splat). */
    const float margin = filter_radius(lp->frame.filter) - 0.5f;
    float u_sel = sampler_1d(rng);
    Vec2 u_pos = sampler_2d(rng);
    Vec2 u_dir = sampler_2d(rng);
    EmissionSample es;
    EmitterGeometry g = scene_emitter_geometry(s);
    emitter_sample_emission(&s->emitter_sampler, &g, u_sel, u_pos, u_dir, &es);

    /* y0 seen directly: the only way this estimator renders visible emitters (delta
     * lights are never seen, nor is the environment: it is no surface a connection could
     * reach). */
    CameraWiSample cs;
    Vec2 u_lens = sampler_2d(rng);
    if (!es.delta && es.finite && camera_sample_wi(cam, es.p, u_lens, margin, &cs)) {
        const Emitter *e = &s->emitters[es.emitter];
        Color le = emitter_radiance(e, s->textures, es.n, es.uv, cs.wi);
        splat_if_visible(s, lp, es.p, es.n, &cs,
                         color_scale(le, fabsf(v3_dot(es.n, cs.wi)) / es.pdf_a), out, rays);
    }
    if (!(es.pdf_w > 0.0f)) return;

    /* beta = L_e |cos theta_0| / (pdf_a pdf_w) (or a delta light's, light.c): the flux a
     * path carries. Russian roulette looks at `scatter`, the product of the BSDF weights
     * (and 1/q), which is what the path tracer's beta is: beta's flux scale would keep
     * every path alive. */
    Color beta = es.beta;
    Color scatter = color_s(1.0f);
    Ray ray = ray_make(scene_offset(s, es.p, es.n, es.w), es.w, 0.0f, INFINITY);
    for (int depth = 1;; depth++) {
        SurfaceHit sh;
        ++*rays;
        if (!scene_intersect(s, &ray, &sh)) break;
        Vec3 w_prev = v3_neg(ray.d); /* toward y_{j-1}, where the light came from */
        Bsdf bsdf;
        scene_bsdf(s, &sh, &bsdf);
        /* Delta lobes cannot be connected: f is a Dirac in the direction to the lens. */
        const bool connect = !bsdf_is_delta(&bsdf);
        if (connect) u_lens = sampler_2d(rng);
        /* The next direction is sampled before this vertex's camera connection (the
         * random numbers are drawn in the same order as ever): the connection is a chain
         * of divisions and a shadow ray nothing else waits on, and after the sampling it
         * overlaps the next bounce instead of holding it back. */
        bool end = lp->max_depth > 0 && depth >= lp->max_depth;
        BsdfSample bs;
        if (!end) {
            float uc = sampler_1d(rng);
            Vec2 u = sampler_2d(rng);
            /* Adjoint sampling: wo is where the light came from, and refraction does not
             * scale flux by 1/eta^2 (bsdf.c). */
            end = !bsdf_sample_transport(&bsdf, w_prev, uc, u, BSDF_IMPORTANCE, &bs);
        }
        if (connect) {
            float cos_prev = fabsf(v3_dot(sh.ng, w_prev));
            if (camera_sample_wi(cam, sh.p, u_lens, margin, &cs) && cos_prev > 0.0f) {
                /* The camera path through this vertex evaluates f(wo = w_cam, wi = w_prev)
                 * |cos theta_prev|; the connection wants |cos theta_cam| instead (the
                 * geometry term toward the lens). Evaluated that way round rather than
                 * relying on reciprocity, so a non-reciprocal lobe would stay right. */
                Color f = bsdf_eval(&bsdf, cs.wi, w_prev);
                f = color_scale(f, fabsf(v3_dot(sh.ng, cs.wi)) / cos_prev);
                splat_if_visible(s, lp, sh.p, sh.ng, &cs, color_mul(beta, f), out, rays);
            }
        }
        if (end) break;
        beta = color_mul(beta, bs.weight);
        scatter = color_mul(scatter, bs.weight);
        if (color_is_black(scatter)) break;

        /* Russian roulette as in path.c: from the same depth, the same survival rule. */
        float rr = roulette(rng, depth, lp->rr_depth, scatter);
        if (rr == 0.0f) break;
        beta = color_scale(beta, rr);
        scatter = color_scale(scatter, rr);
        ray = ray_make(scene_offset(s, sh.p, sh.ng, bs.wi), bs.wi, 0.0f, INFINITY);
    }
}
