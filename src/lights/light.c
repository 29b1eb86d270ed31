/* Area-emitter sampling for next-event estimation. */
#include "lights/light.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
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
