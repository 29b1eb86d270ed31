/* Area-emitter sampling: points for next-event estimation, points and directions for
 * light paths. */
#include "lights/light.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "math/frame.h"
#include "sampling/warp.h"

CstStatus emitter_sampler_init(EmitterSampler *s, const Emitter *emitters, int n, CstError *err)
{
    memset(s, 0, sizeof *s);
    if (n == 0) return CST_OK;
    float stack_w[64] = {0};
    float *w = n <= 64 ? stack_w : malloc((size_t)n * sizeof *w);
    if (!w) return cst_fail(err, CST_ERR_OOM, "out of memory for %d emitters", n);
    for (int i = 0; i < n; i++) w[i] = emitters[i].area;
    CstStatus st = distrib1d_init(&s->by_area, w, n, err);
    if (w != stack_w) free(w);
    if (st != CST_OK) return st;
    s->pdf_a = (float)(1.0 / s->by_area.total);
    s->count = n;
    return CST_OK;
}

void emitter_sampler_free(EmitterSampler *s)
{
    distrib1d_free(&s->by_area);
    memset(s, 0, sizeof *s);
}

void emitter_sample(const EmitterSampler *s, const Emitter *emitters, const EmitterGeometry *g,
                    float u_sel, Vec2 u, EmitterSample *out)
{
    int i = distrib1d_sample(&s->by_area, u_sel);
    const Emitter *e = &emitters[i];
    out->emitter = i;
    if ((int)e->prim < g->num_triangles) {
        const int32_t *t = &g->tri_indices[3 * e->prim];
        Vec3 a = g->positions[t[0]], b = g->positions[t[1]], c = g->positions[t[2]];
        Vec2 bc = warp_uniform_triangle(u);
        Vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a);
        out->p = v3_add(a, v3_add(v3_scale(e1, bc.x), v3_scale(e2, bc.y)));
        out->n = e->n;
    } else {
        const Sphere *sp = &g->spheres[(int)e->prim - g->num_triangles];
        Vec3 d = warp_uniform_sphere(u);
        out->p = v3_madd(sp->center, d, sp->radius);
        out->n = d;
    }
}

/* Emitters are chosen by area, not by power: the NEE distribution already exists and
 * both are unbiased; by power would spend fewer paths on dim emitters when radiances
 * differ. The cosine-weighted direction is proportional to the emitted flux
 * L_e |cos theta| of a Lambertian emitter, so the first throughput
 * L_e |cos theta| / (pdf_a pdf_w) is the same for every path of an emitter. */
void emitter_sample_emission(const EmitterSampler *s, const Emitter *emitters,
                             const EmitterGeometry *g, float u_sel, Vec2 u_pos, Vec2 u_dir,
                             EmissionSample *out)
{
    EmitterSample es;
    emitter_sample(s, emitters, g, u_sel, u_pos, &es);
    const Emitter *e = &emitters[es.emitter];
    float side = 1.0f;
    if (e->two_sided) {
        /* Reuse u_dir.x for the side: [0, 1/2) front, [1/2, 1) back, stretched back to [0, 1). */
        if (u_dir.x < 0.5f) u_dir.x *= 2.0f;
        else { u_dir.x = 2.0f * u_dir.x - 1.0f; side = -1.0f; }
    }
    Vec3 local = warp_cosine_hemisphere(u_dir);
    Frame f = frame_from_normal(v3_scale(es.n, side));
    out->p = es.p;
    out->n = es.n;
    out->w = frame_to_world(&f, local);
    out->emitter = es.emitter;
    out->pdf_a = s->pdf_a;
    out->pdf_w = local.z > 0.0f ? emitter_emission_pdf_w(e, es.n, out->w) : 0.0f;
}

float emitter_emission_pdf_w(const Emitter *e, Vec3 n, Vec3 w)
{
    float c = v3_dot(n, w);
    if (e->two_sided) return 0.5f * fabsf(c) * CST_INV_PI;
    return c > 0.0f ? c * CST_INV_PI : 0.0f;
}
