/* BVH build (binned SAH) and traversal (closest hit, occlusion). */
#include "accel/bvh.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/triangle.h"

enum {
    BVH_BINS = 32,
    BVH_MAX_LEAF = 8,      /* larger leaves are always split */
    BVH_MAX_DEPTH = 60,    /* beyond this, split at the median: traversal stacks stay bounded */
    BVH_STACK = 128
};
/* SAH costs relative to one primitive test. A node visit (box test + stack work) costs
 * about as much as a triangle test here; the figure only shifts where leaves stop. */
static const float SAH_TRAVERSAL_COST = 1.0f;
static const float SAH_ISECT_COST = 1.0f;

typedef struct BuildPrim {
    BBox box;
    Vec3 centroid;
} BuildPrim;

typedef struct Builder {
    const BuildPrim *bp;
    uint32_t *idx;
    BvhNode *nodes;
    int num_nodes, cap_nodes;
} Builder;

static int builder_new_node(Builder *b)
{
    /* A binary tree over n leaves-with-at-least-one-primitive has at most 2n - 1 nodes,
     * and the array was sized for that up front, so this never reallocates. */
    return b->num_nodes++;
}

static void node_set_bounds(BvhNode *n, BBox box)
{
    n->bmin[0] = box.min.x; n->bmin[1] = box.min.y; n->bmin[2] = box.min.z;
    n->bmax[0] = box.max.x; n->bmax[1] = box.max.y; n->bmax[2] = box.max.z;
}

/* Picks the split of idx[begin, end) with the lowest binned SAH cost over all three
 * axes. Returns the partition point, or -1 when a leaf is cheaper (or nothing splits). */
static int find_split(Builder *b, int begin, int end, BBox box, BBox cbox, int *axis_out)
{
    int n = end - begin;
    float best_cost = INFINITY;
    int best_axis = -1, best_bin = -1;
    Vec3 cext = v3_sub(cbox.max, cbox.min);
    for (int axis = 0; axis < 3; axis++) {
        float lo = v3_get(cbox.min, axis), ext = v3_get(cext, axis);
        if (!(ext > 0.0f)) continue;
        float scale = (float)BVH_BINS / ext;
        BBox bin_box[BVH_BINS];
        int bin_count[BVH_BINS];
        for (int i = 0; i < BVH_BINS; i++) { bin_box[i] = bbox_empty(); bin_count[i] = 0; }
        for (int i = begin; i < end; i++) {
            const BuildPrim *p = &b->bp[b->idx[i]];
            int k = (int)((v3_get(p->centroid, axis) - lo) * scale);
            k = k < 0 ? 0 : (k >= BVH_BINS ? BVH_BINS - 1 : k);
            bin_count[k]++;
            bin_box[k] = bbox_union(bin_box[k], p->box);
        }
        /* Sweep from the right to get suffix areas, then from the left to evaluate. */
        float right_area[BVH_BINS];
        int right_count[BVH_BINS];
        BBox acc = bbox_empty();
        int cnt = 0;
        for (int i = BVH_BINS - 1; i > 0; i--) {
            acc = bbox_union(acc, bin_box[i]);
            cnt += bin_count[i];
            right_area[i] = bbox_area(acc);
            right_count[i] = cnt;
        }
        acc = bbox_empty();
        cnt = 0;
        for (int i = 0; i < BVH_BINS - 1; i++) {
            acc = bbox_union(acc, bin_box[i]);
            cnt += bin_count[i];
            if (cnt == 0 || right_count[i + 1] == 0) continue;
            float cost = bbox_area(acc) * (float)cnt + right_area[i + 1] * (float)right_count[i + 1];
            if (cost < best_cost) { best_cost = cost; best_axis = axis; best_bin = i; }
        }
    }
    float parent_area = bbox_area(box);
    float split_cost = SAH_TRAVERSAL_COST +
                       (parent_area > 0.0f ? SAH_ISECT_COST * best_cost / parent_area : INFINITY);
    float leaf_cost = SAH_ISECT_COST * (float)n;
    if (best_axis < 0 || (split_cost >= leaf_cost && n <= BVH_MAX_LEAF)) return -1;

    float lo = v3_get(cbox.min, best_axis);
    float scale = (float)BVH_BINS / v3_get(cext, best_axis);
    int i = begin, j = end - 1;
    while (i <= j) {
        const BuildPrim *p = &b->bp[b->idx[i]];
        int k = (int)((v3_get(p->centroid, best_axis) - lo) * scale);
        k = k < 0 ? 0 : (k >= BVH_BINS ? BVH_BINS - 1 : k);
        if (k <= best_bin) i++;
        else { uint32_t t = b->idx[i]; b->idx[i] = b->idx[j]; b->idx[j] = t; j--; }
    }
    *axis_out = best_axis;
    return i;
}

static int build_recursive(Builder *b, int begin, int end, int depth)
{
    int node = builder_new_node(b);
    BBox box = bbox_empty(), cbox = bbox_empty();
    for (int i = begin; i < end; i++) {
        const BuildPrim *p = &b->bp[b->idx[i]];
        box = bbox_union(box, p->box);
        cbox = bbox_add(cbox, p->centroid);
    }
    node_set_bounds(&b->nodes[node], box);
    int n = end - begin;
    int axis = 0, mid = -1;
    if (n > 1) {
        if (depth < BVH_MAX_DEPTH) mid = find_split(b, begin, end, box, cbox, &axis);
        if (mid < 0 && n > BVH_MAX_LEAF) {
            /* Coincident centroids (or too deep): split the range in the middle; any
             * partition is correct, this one only keeps leaves small. */
            Vec3 ext = v3_sub(cbox.max, cbox.min);
            axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
            mid = begin + n / 2;
        }
    }
    if (mid < 0) {
        b->nodes[node].offset = begin;
        b->nodes[node].count = (uint16_t)n;
        b->nodes[node].axis = 0;
        return node;
    }
    build_recursive(b, begin, mid, depth + 1);
    int right = build_recursive(b, mid, end, depth + 1);
    b->nodes[node].offset = right;
    b->nodes[node].count = 0;
    b->nodes[node].axis = (uint8_t)axis;
    return node;
}

CstStatus bvh_build(Bvh *bvh, const Vec3 *positions, const int32_t *tri_indices, int num_tris,
                    const Sphere *spheres, int num_spheres, CstError *err)
{
    memset(bvh, 0, sizeof *bvh);
    bvh->bounds = bbox_empty();
    int n = num_tris + num_spheres;
    if (n == 0) return CST_OK;
    BuildPrim *bp = malloc((size_t)n * sizeof *bp);
    uint32_t *idx = malloc((size_t)n * sizeof *idx);
    BvhNode *nodes = malloc((size_t)(2 * n) * sizeof *nodes);
    BvhPrim *prims = malloc((size_t)n * sizeof *prims);
    if (!bp || !idx || !nodes || !prims) goto oom;

    for (int i = 0; i < num_tris; i++) {
        Vec3 a = positions[tri_indices[3 * i]], bb = positions[tri_indices[3 * i + 1]],
             c = positions[tri_indices[3 * i + 2]];
        BBox box = bbox_add(bbox_add(bbox_add(bbox_empty(), a), bb), c);
        bp[i].box = box;
        bp[i].centroid = bbox_center(box);
    }
    for (int i = 0; i < num_spheres; i++) {
        Vec3 r = v3s(spheres[i].radius);
        BBox box = {v3_sub(spheres[i].center, r), v3_add(spheres[i].center, r)};
        bp[num_tris + i].box = box;
        bp[num_tris + i].centroid = spheres[i].center;
    }
    for (int i = 0; i < n; i++) idx[i] = (uint32_t)i;

    Builder b = {bp, idx, nodes, 0, 2 * n};
    build_recursive(&b, 0, n, 0);

    for (int i = 0; i < n; i++) {
        uint32_t id = idx[i];
        BvhPrim *p = &prims[i];
        memset(p, 0, sizeof *p);
        p->id = id;
        if ((int)id < num_tris) {
            Vec3 a = positions[tri_indices[3 * id]], bb = positions[tri_indices[3 * id + 1]],
                 c = positions[tri_indices[3 * id + 2]];
            p->kind = BVH_PRIM_TRIANGLE;
            p->v0 = a;
            p->e1 = v3_sub(bb, a);
            p->e2 = v3_sub(c, a);
        } else {
            const Sphere *s = &spheres[id - (uint32_t)num_tris];
            p->kind = BVH_PRIM_SPHERE;
            p->v0 = s->center;
            p->e1 = v3(s->radius, 0.0f, 0.0f);
        }
    }
    bvh->nodes = nodes;
    bvh->num_nodes = b.num_nodes;
    bvh->prims = prims;
    bvh->num_prims = n;
    bvh->bounds.min = v3(nodes[0].bmin[0], nodes[0].bmin[1], nodes[0].bmin[2]);
    bvh->bounds.max = v3(nodes[0].bmax[0], nodes[0].bmax[1], nodes[0].bmax[2]);
    free(bp);
    free(idx);
    return CST_OK;
oom:
    free(bp); free(idx); free(nodes); free(prims);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the BVH over %d primitives", n);
}

void bvh_free(Bvh *bvh)
{
    if (!bvh) return;
    free(bvh->nodes);
    free(bvh->prims);
    memset(bvh, 0, sizeof *bvh);
}

size_t bvh_memory_bytes(const Bvh *bvh)
{
    return (size_t)bvh->num_nodes * sizeof(BvhNode) + (size_t)bvh->num_prims * sizeof(BvhPrim);
}

/* Slab test against a node; see bbox_intersect for the robustness argument. */
static inline bool node_hit(const BvhNode *n, Vec3 o, Vec3 inv, float t_min, float t_max)
{
    float tx0 = (n->bmin[0] - o.x) * inv.x, tx1 = (n->bmax[0] - o.x) * inv.x;
    float ty0 = (n->bmin[1] - o.y) * inv.y, ty1 = (n->bmax[1] - o.y) * inv.y;
    float tz0 = (n->bmin[2] - o.z) * inv.z, tz1 = (n->bmax[2] - o.z) * inv.z;
    float tn = maxf(maxf(minf(tx0, tx1), minf(ty0, ty1)), maxf(minf(tz0, tz1), t_min));
    float tf = minf(minf(maxf(tx0, tx1), maxf(ty0, ty1)), minf(maxf(tz0, tz1), t_max));
    return tn <= tf * 1.00000024f;
}

static inline bool prim_intersect(const BvhPrim *p, const Ray *r, float *t, float *u, float *v)
{
    if (p->kind == BVH_PRIM_TRIANGLE) return triangle_intersect(p->v0, p->e1, p->e2, r, t, u, v);
    *u = *v = 0.0f;
    return sphere_intersect(p->v0, p->e1.x, r, t);
}

bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit)
{
    if (bvh->num_nodes == 0) return false;
    Ray r = *ray;
    Vec3 inv = ray_inv_dir(r.d);
    int neg[3] = {inv.x < 0.0f, inv.y < 0.0f, inv.z < 0.0f};
    int stack[BVH_STACK];
    int sp = 0, node = 0;
    bool found = false;
    for (;;) {
        const BvhNode *n = &bvh->nodes[node];
        if (node_hit(n, r.o, inv, r.t_min, r.t_max)) {
            if (n->count > 0) {
                const BvhPrim *p = &bvh->prims[n->offset];
                for (int i = 0; i < n->count; i++) {
                    float t, u, v;
                    if (prim_intersect(&p[i], &r, &t, &u, &v)) {
                        r.t_max = t;
                        hit->t = t; hit->u = u; hit->v = v; hit->prim = p[i].id;
                        found = true;
                    }
                }
            } else {
                /* Visit the child on the side the ray comes from first. */
                if (neg[n->axis]) { stack[sp++] = node + 1; node = n->offset; }
                else { stack[sp++] = n->offset; node = node + 1; }
                continue;
            }
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return found;
}

bool bvh_occluded(const Bvh *bvh, const Ray *ray)
{
    if (bvh->num_nodes == 0) return false;
    Vec3 inv = ray_inv_dir(ray->d);
    int neg[3] = {inv.x < 0.0f, inv.y < 0.0f, inv.z < 0.0f};
    int stack[BVH_STACK];
    int sp = 0, node = 0;
    for (;;) {
        const BvhNode *n = &bvh->nodes[node];
        if (node_hit(n, ray->o, inv, ray->t_min, ray->t_max)) {
            if (n->count > 0) {
                const BvhPrim *p = &bvh->prims[n->offset];
                for (int i = 0; i < n->count; i++) {
                    float t, u, v;
                    if (prim_intersect(&p[i], ray, &t, &u, &v)) return true;
                }
            } else {
                if (neg[n->axis]) { stack[sp++] = node + 1; node = n->offset; }
                else { stack[sp++] = n->offset; node = node + 1; }
                continue;
            }
        }
        if (sp == 0) break;
        node = stack[--sp];
    }
    return false;
}
