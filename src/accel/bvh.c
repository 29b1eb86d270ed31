/* BVH build (binned SAH) and traversal (closest hit, occlusion). */
#include "accel/bvh.h"

#include <immintrin.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/triangle.h"

enum {
    BVH_BINS = 32,
    BVH_MAX_LEAF = 8,      /* larger leaves are always split */
    BVH_MAX_DEPTH = 60,    /* beyond this, split at the median: traversal stacks stay bounded */
    BVH_STACK = 384 /* tree depth <= ~91 (see BVH_MAX_DEPTH), at most 3 pending siblings each */
};
/* SAH costs relative to one primitive test. A node visit (box test + stack work) costs
 * about as much as a triangle test here; the figure only shifts where leaves stop. */
static const float SAH_TRAVERSAL_COST = 1.0f;
static const float SAH_ISECT_COST = 1.0f;

/* Binary node of the intermediate SAH tree, flattened depth-first (left child follows). */
typedef struct BinNode {
    BBox box;
    int32_t offset; /* leaf: first primitive; inner: index of the right child */
    int32_t count;  /* primitives in a leaf; 0 for inner nodes */
} BinNode;

typedef struct BuildPrim {
    BBox box;
    Vec3 centroid;
} BuildPrim;

typedef struct Builder {
    const BuildPrim *bp;
    uint32_t *idx;
    BinNode *nodes;
    int num_nodes, cap_nodes;
} Builder;

static int builder_new_node(Builder *b)
{
    /* A binary tree over n leaves-with-at-least-one-primitive has at most 2n - 1 nodes,
     * and the array was sized for that up front, so this never reallocates. */
    return b->num_nodes++;
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
    b->nodes[node].box = box;
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
        b->nodes[node].count = n;
        return node;
    }
    (void)axis;
    build_recursive(b, begin, mid, depth + 1);
    int right = build_recursive(b, mid, end, depth + 1);
    b->nodes[node].offset = right;
    b->nodes[node].count = 0;
    return node;
}

/* Node boxes are widened a little, outward: a ray lying exactly in a box's face plane
 * with a zero direction component computes (face - origin) * (1 / tiny) = 0, which the
 * slab test would read as "leaving at t = 0" instead of "inside for all t". Widening
 * puts such rays strictly inside; it only adds node visits, never changes a hit. The
 * margin is 8 ulps of the coordinate plus a hair of the scene's extent (for coordinates
 * at or near zero). */
static BBox widen(BBox b, float abs_margin)
{
    const float rel = 0x1p-20f;
    b.min = v3(b.min.x - fabsf(b.min.x) * rel - abs_margin, b.min.y - fabsf(b.min.y) * rel - abs_margin,
               b.min.z - fabsf(b.min.z) * rel - abs_margin);
    b.max = v3(b.max.x + fabsf(b.max.x) * rel + abs_margin, b.max.y + fabsf(b.max.y) * rel + abs_margin,
               b.max.z + fabsf(b.max.z) * rel + abs_margin);
    return b;
}

static void wide_set_child(BvhNode *w, int slot, BBox box, int32_t child, int count)
{
    w->bmin_x[slot] = box.min.x; w->bmax_x[slot] = box.max.x;
    w->bmin_y[slot] = box.min.y; w->bmax_y[slot] = box.max.y;
    w->bmin_z[slot] = box.min.z; w->bmax_z[slot] = box.max.z;
    w->child[slot] = child;
    w->count[slot] = (uint16_t)count;
}

/* Turns binary node `bin` into wide node `out`: its children, with the largest-area inner
 * ones replaced by their own children while slots remain (fewer, fuller wide nodes cut
 * the node visits per ray). Children are laid out depth-first after their parent. */
static void collapse(const BinNode *bin_nodes, int bin, BvhNode *wide, int *num_wide, int out)
{
    int kids[4], nk = 0;
    kids[nk++] = bin + 1;
    kids[nk++] = bin_nodes[bin].offset;
    while (nk < 4) {
        int best = -1;
        float best_area = -1.0f;
        for (int i = 0; i < nk; i++) {
            const BinNode *k = &bin_nodes[kids[i]];
            if (k->count == 0 && bbox_area(k->box) > best_area) { best = i; best_area = bbox_area(k->box); }
        }
        if (best < 0) break;
        int k = kids[best];
        kids[best] = k + 1;
        kids[nk++] = bin_nodes[k].offset;
    }
    BvhNode *w = &wide[out];
    w->valid_mask = (1u << nk) - 1u;
    for (int i = 0; i < 4; i++) {
        if (i >= nk) {
            BBox empty = bbox_empty();
            wide_set_child(w, i, empty, -1, 0);
            continue;
        }
        const BinNode *k = &bin_nodes[kids[i]];
        if (k->count > 0) {
            wide_set_child(w, i, k->box, k->offset, k->count);
        } else {
            int idx = (*num_wide)++;
            wide_set_child(w, i, k->box, idx, 0);
            collapse(bin_nodes, kids[i], wide, num_wide, idx);
        }
    }
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
    BinNode *nodes = malloc((size_t)(2 * n) * sizeof *nodes);
    BvhPrim *prims = malloc((size_t)n * sizeof *prims);
    /* Every wide node but the root absorbs at least one binary inner node, so n wide
     * nodes always suffice (a binary tree over n primitives has < n inner nodes). */
    BvhNode *wide = malloc((size_t)(n + 1) * sizeof *wide);
    if (!bp || !idx || !nodes || !prims || !wide) goto oom;

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
    BBox root = nodes[0].box;
    float margin = 1e-7f * maxf(v3_max_abs(root.min), v3_max_abs(root.max)) + 1e-30f;
    for (int i = 0; i < b.num_nodes; i++) nodes[i].box = widen(nodes[i].box, margin);
    /* The wide root: a binary leaf root (few primitives) becomes one leaf slot. */
    int num_wide = 1;
    if (nodes[0].count > 0) {
        for (int i = 1; i < 4; i++) wide_set_child(&wide[0], i, bbox_empty(), -1, 0);
        wide_set_child(&wide[0], 0, nodes[0].box, nodes[0].offset, nodes[0].count);
        wide[0].valid_mask = 1u;
    } else {
        collapse(nodes, 0, wide, &num_wide, 0);
    }
    for (int i = 0; i < num_wide; i++) wide[i].pad = 0;
    bvh->nodes = wide;
    bvh->num_nodes = num_wide;
    bvh->prims = prims;
    bvh->num_prims = n;
    bvh->bounds = root;
    free(bp);
    free(idx);
    free(nodes);
    return CST_OK;
oom:
    free(bp); free(idx); free(nodes); free(prims); free(wide);
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

/* Per-ray data for the SSE slab test, broadcast once per ray. */
typedef struct RaySimd {
    __m128 ox, oy, oz, ix, iy, iz;
} RaySimd;

static inline RaySimd ray_simd(const Ray *r)
{
    Vec3 inv = ray_inv_dir(r->d);
    RaySimd q = {_mm_set1_ps(r->o.x), _mm_set1_ps(r->o.y), _mm_set1_ps(r->o.z),
                 _mm_set1_ps(inv.x), _mm_set1_ps(inv.y), _mm_set1_ps(inv.z)};
    return q;
}

/* The four children's slab tests at once (see bbox_intersect for the robustness
 * argument: zero direction components and the 1 + 2 gamma(3) widening). Returns a bit
 * mask of the children hit and their entry distances. */
static inline int node_hit4(const BvhNode *n, const RaySimd *q, float t_min, float t_max, __m128 *t_enter)
{
    __m128 tx0 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmin_x), q->ox), q->ix);
    __m128 tx1 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmax_x), q->ox), q->ix);
    __m128 ty0 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmin_y), q->oy), q->iy);
    __m128 ty1 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmax_y), q->oy), q->iy);
    __m128 tz0 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmin_z), q->oz), q->iz);
    __m128 tz1 = _mm_mul_ps(_mm_sub_ps(_mm_loadu_ps(n->bmax_z), q->oz), q->iz);
    __m128 tn = _mm_max_ps(_mm_max_ps(_mm_min_ps(tx0, tx1), _mm_min_ps(ty0, ty1)),
                           _mm_max_ps(_mm_min_ps(tz0, tz1), _mm_set1_ps(t_min)));
    __m128 tf = _mm_min_ps(_mm_min_ps(_mm_max_ps(tx0, tx1), _mm_max_ps(ty0, ty1)),
                           _mm_min_ps(_mm_max_ps(tz0, tz1), _mm_set1_ps(t_max)));
    tf = _mm_mul_ps(tf, _mm_set1_ps(1.00000024f));
    *t_enter = tn;
    return _mm_movemask_ps(_mm_cmple_ps(tn, tf)) & (int)n->valid_mask;
}

static inline bool prim_intersect(const BvhPrim *p, const Ray *r, float *t, float *u, float *v)
{
    if (p->kind == BVH_PRIM_TRIANGLE) return triangle_intersect(p->v0, p->e1, p->e2, r, t, u, v);
    *u = *v = 0.0f;
    return sphere_intersect(p->v0, p->e1.x, r, t);
}

typedef struct StackEntry {
    int32_t child;
    int32_t count; /* > 0: a leaf */
    float t;       /* entry distance, to skip entries beyond a closer hit */
} StackEntry;

bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit)
{
    if (bvh->num_nodes == 0) return false;
    Ray r = *ray;
    RaySimd q = ray_simd(&r);
    StackEntry stack[BVH_STACK];
    int sp = 0;
    stack[sp++] = (StackEntry){0, 0, r.t_min};
    bool found = false;
    while (sp > 0) {
        StackEntry e = stack[--sp];
        if (e.t > r.t_max) continue;
        if (e.count > 0) {
            const BvhPrim *p = &bvh->prims[e.child];
            for (int i = 0; i < e.count; i++) {
                float t, u, v;
                if (prim_intersect(&p[i], &r, &t, &u, &v)) {
                    r.t_max = t;
                    hit->t = t; hit->u = u; hit->v = v; hit->prim = p[i].id;
                    found = true;
                }
            }
            continue;
        }
        const BvhNode *n = &bvh->nodes[e.child];
        __m128 tn4;
        int mask = node_hit4(n, &q, r.t_min, r.t_max, &tn4);
        if (!mask) continue;
        float tn[4];
        _mm_storeu_ps(tn, tn4);
        /* Push the hit children far to near so the nearest is popped first; a closer hit
         * found there lets the farther entries be skipped by their entry distance. */
        StackEntry kids[4];
        int nk = 0;
        for (int i = 0; i < 4; i++) {
            if (!(mask & (1 << i))) continue;
            StackEntry k = {n->child[i], n->count[i], tn[i]};
            int j = nk++;
            while (j > 0 && kids[j - 1].t < k.t) { kids[j] = kids[j - 1]; j--; }
            kids[j] = k;
        }
        for (int i = 0; i < nk; i++) stack[sp++] = kids[i];
    }
    return found;
}

bool bvh_occluded(const Bvh *bvh, const Ray *ray)
{
    if (bvh->num_nodes == 0) return false;
    RaySimd q = ray_simd(ray);
    StackEntry stack[BVH_STACK];
    int sp = 0;
    stack[sp++] = (StackEntry){0, 0, ray->t_min};
    while (sp > 0) {
        StackEntry e = stack[--sp];
        if (e.count > 0) {
            const BvhPrim *p = &bvh->prims[e.child];
            for (int i = 0; i < e.count; i++) {
                float t, u, v;
                if (prim_intersect(&p[i], ray, &t, &u, &v)) return true;
            }
            continue;
        }
        const BvhNode *n = &bvh->nodes[e.child];
        __m128 tn4;
        int mask = node_hit4(n, &q, ray->t_min, ray->t_max, &tn4);
        for (int i = 0; i < 4; i++)
            if (mask & (1 << i)) stack[sp++] = (StackEntry){n->child[i], n->count[i], 0.0f};
    }
    return false;
}
