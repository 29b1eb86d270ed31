/* Emitting media sampled as light sources (media_lights.h). The volume emission term of the
 * RTE adds sigma_a(x) Le(x) per unit length along every ray through x, isotropically, so a
 * light path that starts at x with density p_V(x) per unit volume and direction w with
 * density 1 / (4 pi) carries beta = sigma_a Le / (p_sel p_V / (4 pi)) (the volume form of
 * Veach's emission sampling, thesis sec. 10.2, with a volume vertex and no cosine; UPBP,
 * Krivanek et al. 2014, sec. 3). */
#include "integrators/media_lights.h"

#include <math.h>
#include <stdlib.h>

#include "core/error.h"
#include "integrators/subpath_media_step.h"
#include "media/medium.h"
#include "sampling/warp.h"

int media_lights_first_emissive(const Scene *s)
{
    for (int i = 0; i < s->num_media; i++) {
        const Medium *m = &s->media[i];
        if (!color_is_black(medium_is_hetero(m) ? m->u.het.le : m->u.homog.le)) return i;
    }
    return -1;
}

static bool box_inside(BBox in, BBox out)
{
    return in.min.x >= out.min.x && in.min.y >= out.min.y && in.min.z >= out.min.z && in.max.x <= out.max.x &&
           in.max.y <= out.max.y && in.max.z <= out.max.z;
}

/* The world bounds of primitive `prim` (triangles, spheres, analytic shapes in turn). */
static BBox prim_box(const Scene *s, int prim)
{
    BBox b = bbox_empty();
    if (prim < s->num_triangles) {
        for (int k = 0; k < 3; k++) b = bbox_add(b, s->positions[s->tri_indices[3 * prim + k]]);
        return b;
    }
    prim -= s->num_triangles;
    if (prim < s->num_spheres) {
        const Sphere *sp = &s->spheres[prim];
        return (BBox){v3_sub(sp->center, v3s(sp->radius)), v3_add(sp->center, v3s(sp->radius))};
    }
    return s->shapes[prim - s->num_spheres].bounds;
}

/* A homogeneous medium's box: the union of the shapes that have it inside; a shape that has
 * it outside must lie within, and so must the camera if it sits in it (else the medium
 * reaches past every bound we know). */
static CstStatus homogeneous_box(const Scene *s, int m, const char *who, BBox *out, CstError *err)
{
    const int n = s->num_triangles + s->num_spheres + s->num_shapes;
    BBox in = bbox_empty(), outside = bbox_empty();
    bool any_in = false, any_out = false;
    for (int p = 0; p < n; p++) {
        const PrimInfo *pi = scene_prim_info(s, (uint32_t)p);
        if (!pi->medium) continue;
        const MediumInterface *mi = &s->medium_ifaces[pi->medium - 1];
        if (mi->inside == m) in = bbox_union(in, prim_box(s, p)), any_in = true;
        if (mi->outside == m) outside = bbox_union(outside, prim_box(s, p)), any_out = true;
    }
    const bool cam_out = s->camera_medium == m && !box_inside((BBox){s->camera.position, s->camera.position}, in);
    if (!any_in || (any_out && !box_inside(outside, in)) || cam_out)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "integrator %s: emissive medium %d is not bounded by a shape "
                        "(%s): its light paths start at points sampled in its volume, which needs a bounded "
                        "region: use path, path-nee, path-bsdf, bdpt, vcm or mmlt", who, m,
                        !any_in ? "no shape has it inside" : cam_out ? "the camera is in it, outside its shapes"
                                                                     : "a shape with it outside reaches past them");
    *out = in;
    return CST_OK;
}

/* A grid's cells by their density bound, its box in world space; its power bound. */
static CstStatus grid_light(const HeteroMedium *h, MediaLight *l, double *power, CstError *err)
{
    const MajorantGrid *g = &h->maj;
    const int cells = g->res[0] * g->res[1] * g->res[2];
    Transform inv;
    if (!transform_invert(&h->medium_from_world, &inv))
        return cst_fail(err, CST_ERR_INVALID_ARG, "grid medium: its transform cannot be inverted");
    l->world_from_medium = inv;
    l->p0 = h->p0;
    l->ext = v3_sub(h->p1, h->p0);
    for (int a = 0; a < 3; a++) l->res[a] = g->res[a];
    /* Volume of a cell in world space: the medium-space cell over |det| of medium_from_world. */
    const double det = fabs(transform_det(&h->medium_from_world));
    const double cell = (double)l->ext.x * (double)l->ext.y * (double)l->ext.z / (double)cells / det;
    double sum = 0.0;
    for (int i = 0; i < cells; i++) sum += (double)g->max[i];
    float le_max = h->le_scale_1;
    if (h->le_scale) {
        le_max = 0.0f;
        for (int i = 0; i < h->n[0] * h->n[1] * h->n[2]; i++) le_max = fmaxf(le_max, h->le_scale[i]);
    }
    *power = sum * cell * (double)le_max;
    if (!(*power > 0.0) || !(cell > 0.0) || !isfinite(cell)) return CST_OK; /* emits nothing */
    l->inv_volume = (float)(1.0 / cell);
    return distrib1d_init(&l->cells, g->max, cells, err);
}

void media_lights_destroy(MediaLights *ml)
{
    if (!ml) return;
    for (int i = 0; i < ml->count; i++) distrib1d_free(&ml->light[i].cells);
    distrib1d_free(&ml->by_power);
    free(ml->light);
    free(ml);
}

CstStatus media_lights_create(const Scene *s, const char *who, MediaLights **out, CstError *err)
{
    *out = NULL;
    if (media_lights_first_emissive(s) < 0) return CST_OK;
    MediaLights *ml = calloc(1, sizeof *ml);
    float *power = calloc((size_t)s->num_media, sizeof *power);
    if (ml) ml->light = calloc((size_t)s->num_media, sizeof *ml->light);
    CstStatus st = CST_OK;
    if (!ml || !power || !ml->light) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for the emitting media's light sampler");
        goto fail;
    }
    for (int m = 0; m < s->num_media; m++) {
        const Medium *med = &s->media[m];
        const bool het = medium_is_hetero(med);
        const Color sa_le = het ? color_mul(med->u.het.sigma_a, med->u.het.le)
                                : color_mul(med->u.homog.sigma_a, med->u.homog.le);
        if (color_is_black(het ? med->u.het.le : med->u.homog.le)) continue;
        MediaLight *l = &ml->light[ml->count];
        l->medium = m;
        l->grid = het;
        double p = 0.0;
        if (het) {
            st = grid_light(&med->u.het, l, &p, err);
        } else {
            st = homogeneous_box(s, m, who, &l->box, err);
            const Vec3 e = v3_sub(l->box.max, l->box.min);
            p = (double)e.x * (double)e.y * (double)e.z;
            l->inv_volume = p > 0.0 ? (float)(1.0 / p) : 0.0f;
        }
        if (st != CST_OK) goto fail;
        p *= (double)color_luminance(sa_le);
        if (!(p > 0.0) || !isfinite(p) || !(l->inv_volume > 0.0f)) { /* emits nothing anywhere */
            distrib1d_free(&l->cells);
            continue;
        }
        power[ml->count++] = (float)p;
    }
    if (ml->count == 0) goto fail; /* st CST_OK: no medium emits anything */
    st = distrib1d_init(&ml->by_power, power, ml->count, err);
    if (st != CST_OK) goto fail;
    ml->p_media = s->emitter_sampler.lights > 0 ? 0.5f : 1.0f;
    free(power);
    *out = ml;
    return CST_OK;
fail:
    free(power);
    media_lights_destroy(ml);
    return st;
}

bool media_lights_sample(const MediaLights *ml, const Scene *s, const Camera *cam, float time, const Wavelengths *wl,
                         Sampler *rng, MediaEmission *out, uint64_t *rays)
{
    const float u_sel = sampler_1d(rng), u_cell = sampler_1d(rng), u_z = sampler_1d(rng);
    const Vec2 u_xy = sampler_2d(rng), u_dir = sampler_2d(rng);
    const int i = distrib1d_sample(&ml->by_power, u_sel);
    const MediaLight *l = &ml->light[i];
    float pdf_v;
    if (l->grid) {
        const int c = distrib1d_sample(&l->cells, u_cell);
        const int cx = c % l->res[0], cy = (c / l->res[0]) % l->res[1], cz = c / (l->res[0] * l->res[1]);
        Vec3 pm = v3(l->p0.x + l->ext.x * ((float)cx + u_xy.x) / (float)l->res[0],
                     l->p0.y + l->ext.y * ((float)cy + u_xy.y) / (float)l->res[1],
                     l->p0.z + l->ext.z * ((float)cz + u_z) / (float)l->res[2]);
        out->p = transform_point(&l->world_from_medium, pm);
        pdf_v = l->cells.pmf[c] * l->inv_volume;
    } else {
        const Vec3 e = v3_sub(l->box.max, l->box.min);
        out->p = v3(l->box.min.x + e.x * u_xy.x, l->box.min.y + e.y * u_xy.y, l->box.min.z + e.z * u_z);
        pdf_v = l->inv_volume;
    }
    out->w = warp_uniform_sphere(u_dir);
    out->medium = l->medium;
    /* The box (or cell) may reach outside the medium's region: there the emission is 0
     * (an unbiased estimator with a density that covers the region, only slower). */
    if (medium_at_point(s, cam, out->p, time, rays) != l->medium) return false;
    const Medium *m = &s->media[l->medium];
    const MediumCoeffs mc = medium_coeffs(m, wl);
    const float k = l->grid ? hetero_emission_world(&m->u.het, out->p) : 1.0f;
    const float pdf = ml->p_media * ml->by_power.pmf[i] * pdf_v;
    if (!(k > 0.0f) || !(pdf > 0.0f)) return false;
    out->le = color_scale(color_mul(mc.sigma_a, mc.le), k / pdf);
    out->beta = color_scale(out->le, 4.0f * CST_PI);
    return color_is_finite(out->beta) && !color_is_black(out->beta);
}
