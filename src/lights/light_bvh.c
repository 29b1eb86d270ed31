/* The light BVH (Conty Estevez & Kulla, "Importance Sampling of Many Lights with Adaptive
 * Tree Splitting", HPG 2018; pbrt-v4 BVHLightSampler): build, importance, sampling, pmf. */
#include "lights/light_bvh.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "math/bbox.h"

static LightBounds bounds_empty(void)
{
    LightBounds b;
    memset(&b, 0, sizeof b);
    b.lo = v3s(FLT_MAX);
    b.hi = v3s(-FLT_MAX);
    b.w = v3(0.0f, 0.0f, 1.0f);
    b.cos_o = 1.0f;
    b.cos_e = 1.0f;
    return b;
}

static float safe_acosf(float c) { return acosf(clampf(c, -1.0f, 1.0f)); }

/* The smallest cone holding cones (wa, cos_a) and (wb, cos_b) (pbrt-v4 Union(DirectionCone,
 * DirectionCone)): their axes' angle theta_d; one holds the other when theta_d plus the
 * smaller angle fits in the larger; otherwise the cone of half angle (theta_a + theta_d +
 * theta_b) / 2, its axis wa turned toward wb by that minus theta_a (Rodrigues' rotation). */
static void cone_union(Vec3 wa, float cos_a, Vec3 wb, float cos_b, Vec3 *w, float *cos_o)
{
    float ta = safe_acosf(cos_a), tb = safe_acosf(cos_b);
    float td = safe_acosf(v3_dot(wa, wb));
    if (minf(td + tb, CST_PI) <= ta) { *w = wa; *cos_o = cos_a; return; }
    if (minf(td + ta, CST_PI) <= tb) { *w = wb; *cos_o = cos_b; return; }
    float to = 0.5f * (ta + td + tb);
    Vec3 k = v3_cross(wa, wb);
    if (to >= CST_PI || !(v3_length2(k) > 0.0f)) { *w = wa; *cos_o = -1.0f; return; }
    k = v3_normalize(k);
    float tr = to - ta, c = cosf(tr), s = sinf(tr);
    /* k is perpendicular to wa, so Rodrigues' k (k . wa)(1 - cos) term vanishes. */
    *w = v3_normalize(v3_add(v3_scale(wa, c), v3_scale(v3_cross(k, wa), s)));
    *cos_o = cosf(to);
}

static LightBounds bounds_union(const LightBounds *a, const LightBounds *b)
{
    if (a->phi == 0.0f) return *b;
    if (b->phi == 0.0f) return *a;
    LightBounds r;
    r.lo = v3_min(a->lo, b->lo);
    r.hi = v3_max(a->hi, b->hi);
    cone_union(a->w, a->cos_o, b->w, b->cos_o, &r.w, &r.cos_o);
    r.phi = a->phi + b->phi;
    r.cos_e = minf(a->cos_e, b->cos_e);
    r.two_sided = a->two_sided || b->two_sided;
    return r;
}

LightBounds light_bounds_of(const Light *l, const EmitterGeometry *g, float phi)
{
    LightBounds b = bounds_empty();
    b.phi = phi;
    /* cos(pi / 2) in float, as pbrt-v4 writes std::cos(Pi / 2): slightly below 0, so a
     * direction exactly in the emitting plane keeps a (vanishing) importance. */
    const float cos_half_pi = cosf(0.5f * CST_PI);
    switch (l->type) {
    case LIGHT_AREA: {
        const Emitter *e = &l->u.area;
        if ((int)e->prim < g->num_triangles) {
            const int32_t *t = &g->tri_indices[3 * e->prim];
            for (int k = 0; k < 3; k++) {
                b.lo = v3_min(b.lo, g->positions[t[k]]);
                b.hi = v3_max(b.hi, g->positions[t[k]]);
            }
            b.w = e->n; /* a triangle's normals: one direction */
            b.cos_o = 1.0f;
        } else if ((int)e->prim < g->num_triangles + g->num_spheres) {
            const Sphere *sp = &g->spheres[(int)e->prim - g->num_triangles];
            b.lo = v3_sub(sp->center, v3s(sp->radius));
            b.hi = v3_add(sp->center, v3s(sp->radius));
            b.cos_o = -1.0f; /* every direction */
        } else {
            /* An analytic shape: its world box; a disk's normals are one direction (its
             * plane's), a cylinder's or a partial sphere's are bounded by every direction
             * (pbrt-v4 bounds these shapes' normals so too: DirectionCone::EntireSphere). */
            const AnalyticShape *sh = &g->shapes[(int)e->prim - g->num_triangles - g->num_spheres];
            b.lo = sh->bounds.min;
            b.hi = sh->bounds.max;
            if (sh->p.type == SHAPE_TAG_DISK) {
                ShapeSurface sf;
                shape_surface_at(sh, v2(0.0f, 0.0f), &sf);
                b.w = sf.n;
                b.cos_o = 1.0f;
            } else {
                b.cos_o = -1.0f;
            }
        }
        b.cos_e = cos_half_pi;
        b.two_sided = e->two_sided;
        break;
    }
    case LIGHT_POINT:
    case LIGHT_GONIO: {
        Vec3 p = l->type == LIGHT_POINT ? l->u.point.p : l->u.gonio.p;
        b.lo = b.hi = p;
        b.cos_o = -1.0f;
        b.cos_e = cos_half_pi;
        break;
    }
    case LIGHT_PROJECTION: {
        /* pbrt-v4 ProjectionLight::Bounds: the cone through the window's corners, no spread */
        const ProjImage *im = &l->u.proj.image;
        const float *m = im->light_from_world;
        b.lo = b.hi = l->u.proj.p;
        b.w = v3(m[6], m[7], m[8]); /* light +z in world space: the rotation's third row */
        float r2 = (im->sx * im->sx + im->sy * im->sy) * im->tan_half * im->tan_half;
        b.cos_o = 1.0f / sqrtf(1.0f + r2);
        b.cos_e = 1.0f;
        break;
    }
    case LIGHT_SPOT:
        /* pbrt-v4 SpotLight::Bounds: the cone of full intensity and the falloff's width */
        b.lo = b.hi = l->u.spot.p;
        b.w = l->u.spot.dir;
        b.cos_o = l->u.spot.cos_inner;
        b.cos_e = cosf(safe_acosf(l->u.spot.cos_outer) - safe_acosf(l->u.spot.cos_inner));
        break;
    default: b.phi = 0.0f; break;
    }
    return b;
}

/* cos(max(0, a - b)) and sin of it from the sines and cosines of a and b (pbrt-v4's
 * cosSubClamped / sinSubClamped: when a < b the difference clamps to 0). */
static float cos_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b)
{
    return cos_a > cos_b ? 1.0f : cos_a * cos_b + sin_a * sin_b;
}
static float sin_sub_clamped(float sin_a, float cos_a, float sin_b, float cos_b)
{
    return cos_a > cos_b ? 0.0f : sin_a * cos_b - cos_a * sin_b;
}

float light_bounds_importance(const LightBounds *b, Vec3 x, Vec3 n)
{
    if (b->phi == 0.0f) return 0.0f;
    Vec3 pc = v3_scale(v3_add(b->lo, b->hi), 0.5f);
    Vec3 dx = v3_sub(x, pc);
    float dc2 = v3_length2(dx);
    /* pbrt-v4 bounds d^2 below by half the box's diagonal (sic: a length), so points near
     * or in a cluster do not get an unbounded importance. */
    float d2 = maxf(dc2, 0.5f * v3_length(v3_sub(b->hi, b->lo)));
    if (!(d2 > 0.0f)) return 0.0f;
    Vec3 wi = dc2 > 0.0f ? v3_scale(dx, 1.0f / sqrtf(dc2)) : v3(0.0f, 0.0f, 1.0f);
    float cos_w = v3_dot(b->w, wi);
    if (b->two_sided) cos_w = fabsf(cos_w);
    float sin_w = safe_sqrtf(1.0f - cos_w * cos_w);
    /* theta_b: the half angle of the cone the box's bounding sphere subtends from x
     * (pbrt-v4 BoundSubtendedDirections); every direction from inside it. */
    float r2 = 0.25f * v3_length2(v3_sub(b->hi, b->lo));
    float cos_b = dc2 > r2 ? safe_sqrtf(1.0f - r2 / dc2) : -1.0f;
    float sin_b = safe_sqrtf(1.0f - cos_b * cos_b);
    /* theta' = max(0, theta_w - theta_o - theta_b): the smallest angle between the
     * direction toward x from any point of the box and any normal of the cone. */
    float sin_o = safe_sqrtf(1.0f - b->cos_o * b->cos_o);
    float cos_x = cos_sub_clamped(sin_w, cos_w, sin_o, b->cos_o);
    float sin_x = sin_sub_clamped(sin_w, cos_w, sin_o, b->cos_o);
    float cos_p = cos_sub_clamped(sin_x, cos_x, sin_b, cos_b);
    /* Beyond theta_e nothing arrives. Strict, unlike pbrt-v4's <=: a hard-edged spot or a
     * projection light has theta_e = 0, and inside its cone cos theta' is exactly 1. */
    if (cos_p < b->cos_e) return 0.0f;
    float imp = b->phi * cos_p / d2;
    if (n.x != 0.0f || n.y != 0.0f || n.z != 0.0f) {
        /* the receiver's |cos theta_i|, bounded the same way by theta_b */
        float cos_i = fabsf(v3_dot(wi, n));
        float sin_i = safe_sqrtf(1.0f - cos_i * cos_i);
        imp *= cos_sub_clamped(sin_i, cos_i, sin_b, cos_b);
    }
    return maxf(imp, 0.0f);
}

/* ---- build ---- */

typedef struct BuildItem {
    LightBounds b;
    int light;
} BuildItem;

typedef struct Builder {
    LightBvh *bvh;
    BuildItem *items;
} Builder;

/* The cost of a cluster (pbrt-v4 BVHLightSampler::EvaluateCost; Conty & Kulla sec. 4.1):
 * power times the orientation measure M_omega of its cone (theta_w = min(theta_o +
 * theta_e, pi)) times the box's surface area, times Kr, which favours splitting across a
 * box's long axis. */
static float cluster_cost(const LightBounds *b, Vec3 extent, int dim)
{
    if (b->phi == 0.0f) return 0.0f;
    float theta_o = safe_acosf(b->cos_o), theta_e = safe_acosf(b->cos_e);
    float theta_w = minf(theta_o + theta_e, CST_PI);
    float sin_o = safe_sqrtf(1.0f - b->cos_o * b->cos_o);
    float m_omega = 2.0f * CST_PI * (1.0f - b->cos_o) +
                    0.5f * CST_PI *
                        (2.0f * theta_w * sin_o - cosf(theta_o - 2.0f * theta_w) - 2.0f * theta_o * sin_o + b->cos_o);
    float ext_dim = v3_get(extent, dim);
    float kr = ext_dim > 0.0f ? v3_max_comp(extent) / ext_dim : 1.0f;
    BBox box = {b->lo, b->hi};
    return b->phi * m_omega * kr * bbox_area(box);
}

enum { LIGHT_BVH_BUCKETS = 12 };

static Vec3 item_centroid(const BuildItem *it) { return v3_scale(v3_add(it->b.lo, it->b.hi), 0.5f); }

/* Builds the subtree over items [start, end) at node index *next; returns its index. */
static int build_node(Builder *bd, int start, int end, int parent)
{
    LightBvh *bvh = bd->bvh;
    int at = bvh->num_nodes++;
    LightBvhNode *node = &bvh->nodes[at];
    node->parent = parent;
    if (end - start == 1) {
        node->b = bd->items[start].b;
        node->index = bd->items[start].light;
        node->is_leaf = 1;
        bvh->leaf[node->index] = at;
        return at;
    }
    BBox box = bbox_empty(), cbox = bbox_empty();
    for (int i = start; i < end; i++) {
        box = bbox_union(box, (BBox){bd->items[i].b.lo, bd->items[i].b.hi});
        cbox = bbox_add(cbox, item_centroid(&bd->items[i]));
    }
    Vec3 extent = v3_sub(box.max, box.min);
    float best = INFINITY;
    int best_dim = -1, best_bucket = -1;
    for (int dim = 0; dim < 3; dim++) {
        float lo = v3_get(cbox.min, dim), hi = v3_get(cbox.max, dim);
        if (!(hi > lo)) continue;
        LightBounds bucket[LIGHT_BVH_BUCKETS];
        for (int k = 0; k < LIGHT_BVH_BUCKETS; k++) bucket[k] = bounds_empty();
        for (int i = start; i < end; i++) {
            int k = (int)(LIGHT_BVH_BUCKETS * (v3_get(item_centroid(&bd->items[i]), dim) - lo) / (hi - lo));
            k = k < 0 ? 0 : k >= LIGHT_BVH_BUCKETS ? LIGHT_BVH_BUCKETS - 1 : k;
            bucket[k] = bounds_union(&bucket[k], &bd->items[i].b);
        }
        for (int split = 0; split < LIGHT_BVH_BUCKETS - 1; split++) {
            LightBounds b0 = bounds_empty(), b1 = bounds_empty();
            for (int k = 0; k <= split; k++) b0 = bounds_union(&b0, &bucket[k]);
            for (int k = split + 1; k < LIGHT_BVH_BUCKETS; k++) b1 = bounds_union(&b1, &bucket[k]);
            if (b0.phi == 0.0f || b1.phi == 0.0f) continue;
            float cost = cluster_cost(&b0, extent, dim) + cluster_cost(&b1, extent, dim);
            if (cost < best) {
                best = cost;
                best_dim = dim;
                best_bucket = split;
            }
        }
    }
    int mid = (start + end) / 2;
    if (best_dim >= 0) {
        float lo = v3_get(cbox.min, best_dim), hi = v3_get(cbox.max, best_dim);
        int i = start, j = end - 1;
        while (i <= j) {
            int k = (int)(LIGHT_BVH_BUCKETS * (v3_get(item_centroid(&bd->items[i]), best_dim) - lo) / (hi - lo));
            k = k < 0 ? 0 : k >= LIGHT_BVH_BUCKETS ? LIGHT_BVH_BUCKETS - 1 : k;
            if (k <= best_bucket) {
                i++;
            } else {
                BuildItem t = bd->items[i];
                bd->items[i] = bd->items[j];
                bd->items[j--] = t;
            }
        }
        if (i > start && i < end) mid = i;
    }
    build_node(bd, start, mid, at);
    int second = build_node(bd, mid, end, at);
    node = &bvh->nodes[at]; /* (the array does not move: sized up front) */
    node->index = second;
    node->is_leaf = 0;
    node->b = bounds_union(&bvh->nodes[at + 1].b, &bvh->nodes[second].b);
    return at;
}

void light_bvh_free(LightBvh *bvh)
{
    if (!bvh) return;
    free(bvh->nodes);
    free(bvh->leaf);
    free(bvh->infinite);
    memset(bvh, 0, sizeof *bvh);
}

CstStatus light_bvh_build(LightBvh *bvh, const EmitterSampler *s, const EmitterGeometry *g, CstError *err)
{
    memset(bvh, 0, sizeof *bvh);
    const int n = s->lights;
    bvh->leaf = malloc((size_t)(n > 0 ? n : 1) * sizeof *bvh->leaf);
    bvh->infinite = malloc((size_t)(n > 0 ? n : 1) * sizeof *bvh->infinite);
    BuildItem *items = malloc((size_t)(n > 0 ? n : 1) * sizeof *items);
    bvh->nodes = malloc((size_t)(2 * n > 0 ? 2 * n : 1) * sizeof *bvh->nodes);
    if (!bvh->leaf || !bvh->infinite || !items || !bvh->nodes) {
        free(items);
        light_bvh_free(bvh);
        return cst_fail(err, CST_ERR_OOM, "out of memory for the light BVH of %d lights", n);
    }
    /* The same floor as the power distribution's (light.c): a light of zero luminance
     * still emits and must keep a nonzero probability. */
    double total = 0.0;
    for (int i = 0; i < n; i++) {
        float p = light_power(&s->light[i], s->radius);
        if (isfinite(p) && p > 0.0f) total += (double)p;
    }
    const float floor_phi = total > 0.0 && isfinite(total) ? 1e-6f * (float)total : 1.0f;
    int bounded = 0;
    for (int i = 0; i < n; i++) {
        const Light *l = &s->light[i];
        bvh->leaf[i] = -1;
        if (l->type == LIGHT_DIRECTIONAL || l->type == LIGHT_ENVIRONMENT) {
            bvh->infinite[bvh->num_infinite++] = i;
            continue;
        }
        /* pbrt-v4 bounds a spot by a point light of its intensity (SpotLight::Bounds). */
        float phi = l->type == LIGHT_SPOT ? 4.0f * CST_PI * color_luminance(l->u.spot.intensity)
                                          : light_power(l, s->radius);
        if (!(phi > floor_phi) || !isfinite(phi)) phi = floor_phi;
        items[bounded].b = light_bounds_of(l, g, phi);
        items[bounded].light = i;
        bounded++;
    }
    bvh->p_infinite = (float)bvh->num_infinite / (float)(bvh->num_infinite + (bounded > 0 ? 1 : 0));
    if (bounded > 0) {
        Builder bd = {bvh, items};
        build_node(&bd, 0, bounded, -1);
    }
    free(items);
    return CST_OK;
}

/* ---- sampling ---- */

int light_bvh_sample(const LightBvh *bvh, Vec3 x, Vec3 n, float u, float *pmf)
{
    *pmf = 0.0f;
    const float p_inf = bvh->p_infinite;
    if (u < p_inf) {
        /* uniform among the infinite lights (pbrt-v4) */
        int k = (int)(u / p_inf * (float)bvh->num_infinite);
        k = k >= bvh->num_infinite ? bvh->num_infinite - 1 : k;
        *pmf = p_inf / (float)bvh->num_infinite;
        return bvh->infinite[k];
    }
    if (bvh->num_nodes == 0) return -1;
    u = minf((u - p_inf) / (1.0f - p_inf), 0x1.fffffep-1f);
    float p = 1.0f - p_inf;
    int at = 0;
    for (;;) {
        const LightBvhNode *node = &bvh->nodes[at];
        if (node->is_leaf) {
            /* a lone light is still checked: behind a one-sided emitter it gives nothing */
            if (at > 0 || light_bounds_importance(&node->b, x, n) > 0.0f) {
                *pmf = p;
                return node->index;
            }
            return -1;
        }
        float c0 = light_bounds_importance(&bvh->nodes[at + 1].b, x, n);
        float c1 = light_bounds_importance(&bvh->nodes[node->index].b, x, n);
        if (!(c0 + c1 > 0.0f)) return -1;
        /* SampleDiscrete of two weights, u rescaled to [0, 1) for the next level */
        float p0 = c0 / (c0 + c1);
        if (u < p0) {
            p *= p0;
            u = minf(u / p0, 0x1.fffffep-1f);
            at = at + 1;
        } else {
            p *= 1.0f - p0;
            u = minf((u - p0) / (1.0f - p0), 0x1.fffffep-1f);
            at = node->index;
        }
    }
}

float light_bvh_pmf(const LightBvh *bvh, Vec3 x, Vec3 n, int light)
{
    int at = bvh->leaf[light];
    if (at < 0) return bvh->num_infinite > 0 ? bvh->p_infinite / (float)bvh->num_infinite : 0.0f;
    if (at == 0) return light_bounds_importance(&bvh->nodes[0].b, x, n) > 0.0f ? 1.0f - bvh->p_infinite : 0.0f;
    /* Up from the leaf: the product of the choices that lead to it, each as
     * light_bvh_sample computes it (p0 or 1 - p0). */
    float p = 1.0f - bvh->p_infinite;
    while (at > 0) {
        int parent = bvh->nodes[at].parent;
        const LightBvhNode *pn = &bvh->nodes[parent];
        float c0 = light_bounds_importance(&bvh->nodes[parent + 1].b, x, n);
        float c1 = light_bounds_importance(&bvh->nodes[pn->index].b, x, n);
        if (!(c0 + c1 > 0.0f)) return 0.0f;
        float p0 = c0 / (c0 + c1);
        p *= at == parent + 1 ? p0 : 1.0f - p0;
        at = parent;
    }
    return p;
}
