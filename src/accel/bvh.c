/* BVH build (binned SAH) and traversal (closest hit, occlusion). */
#include "accel/bvh.h"

#include <immintrin.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

enum {
    BVH_BINS = 32,
    BVH_MAX_LEAF = 8,      /* larger leaves are always split */
    BVH_MAX_DEPTH = 60,    /* beyond this, split at the median: traversal stacks stay bounded */
    BVH_STACK = 384 /* tree depth <= ~91 (see BVH_MAX_DEPTH), at most 3 pending siblings each */
};
/* SAH costs relative to one 4-triangle block test. One SSE node visit tests four boxes;
 * on the Cornell box (bench_render, 1 thread, 4 alternating runs each) 0.25, 0.5 and 1.0
 * gave 1.48, 1.53 and 1.50 M paths/s: within this machine's +-6% noise, so 0.5 it is. */
static const float SAH_TRAVERSAL_COST = 0.5f;
static const float SAH_ISECT_COST = 1.0f;

/* Binary node of the intermediate SAH tree, flattened depth-first (left child follows). */
typedef struct BinNode {
    BBox box;
    int32_t offset; /* leaf: first primitive; inner: index of the right child */
    int32_t count;  /* primitives in a leaf; 0 for inner nodes */
} BinNode;

/* Leaves are tested four primitives at a time, so a leaf of n costs ceil(n / 4) tests
 * (the "block SAH" of wide BVHs). */
static inline float sah_blocks(int n) { return (float)((n + 3) / 4); }

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
            float cost = bbox_area(acc) * sah_blocks(cnt) + right_area[i + 1] * sah_blocks(right_count[i + 1]);
            if (cost < best_cost) { best_cost = cost; best_axis = axis; best_bin = i; }
        }
    }
    float parent_area = bbox_area(box);
    float split_cost = SAH_TRAVERSAL_COST +
                       (parent_area > 0.0f ? SAH_ISECT_COST * best_cost / parent_area : INFINITY);
    float leaf_cost = SAH_ISECT_COST * sah_blocks(n);
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

static void wide_set_child(BvhNode *w, int slot, BBox box, int32_t child, int is_leaf)
{
    w->bmin_x[slot] = box.min.x; w->bmax_x[slot] = box.max.x;
    w->bmin_y[slot] = box.min.y; w->bmax_y[slot] = box.max.y;
    w->bmin_z[slot] = box.min.z; w->bmax_z[slot] = box.max.z;
    w->child[slot] = child;
    w->is_leaf[slot] = (uint16_t)is_leaf;
}

/* Everything the collapse pass writes: wide nodes, leaves, triangle blocks, spheres. */
typedef struct Emitter4 {
    const BinNode *bin;
    const uint32_t *idx;
    const Vec3 *positions;
    const int32_t *tri_indices;
    int num_tris;
    const Sphere *spheres;
    Bvh *out;
} Emitter4;

/* Writes the leaf for binary leaf `bn` and returns its index: triangles packed four to a
 * block in the SAH's order, spheres after them. */
static int emit_leaf(Emitter4 *e, const BinNode *bn)
{
    Bvh *o = e->out;
    BvhLeaf *leaf = &o->leaves[o->num_leaves];
    leaf->first_block = (uint32_t)o->num_blocks;
    leaf->first_sphere = (uint32_t)o->num_spheres;
    leaf->num_blocks = 0;
    leaf->num_spheres = 0;
    int lane = 4;
    BvhTriBlock *blk = NULL;
    for (int i = bn->offset; i < bn->offset + bn->count; i++) {
        uint32_t id = e->idx[i];
        if ((int)id >= e->num_tris) {
            const Sphere *sp = &e->spheres[id - (uint32_t)e->num_tris];
            BvhSphere *d = &o->spheres[o->num_spheres++];
            d->center = sp->center;
            d->radius = sp->radius;
            d->id = id;
            leaf->num_spheres++;
            continue;
        }
        if (lane == 4) {
            blk = &o->blocks[o->num_blocks++];
            /* Unused lanes hold NaN vertices: every comparison in the SIMD test then
             * fails (det != 0 holds for NaN, but t > t_min does not), so they need no mask. */
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++)
                    for (int l = 0; l < 4; l++) blk->v[k][a][l] = NAN;
            for (int k = 0; k < 4; k++) blk->id[k] = BVH_NO_PRIM;
            leaf->num_blocks++;
            lane = 0;
        }
        const int32_t *t = &e->tri_indices[3 * id];
        for (int k = 0; k < 3; k++) {
            Vec3 p = e->positions[t[k]];
            blk->v[k][0][lane] = p.x; blk->v[k][1][lane] = p.y; blk->v[k][2][lane] = p.z;
        }
        blk->id[lane] = id;
        lane++;
    }
    return o->num_leaves++;
}

/* Turns binary node `bin` into wide node `out`: its children, with the largest-area inner
 * ones replaced by their own children while slots remain (fewer, fuller wide nodes cut
 * the node visits per ray). Children are laid out depth-first after their parent. */
static void collapse(Emitter4 *e, int bin, int out)
{
    const BinNode *bn = e->bin;
    int kids[4], nk = 0;
    kids[nk++] = bin + 1;
    kids[nk++] = bn[bin].offset;
    while (nk < 4) {
        int best = -1;
        float best_area = -1.0f;
        for (int i = 0; i < nk; i++) {
            const BinNode *k = &bn[kids[i]];
            if (k->count == 0 && bbox_area(k->box) > best_area) { best = i; best_area = bbox_area(k->box); }
        }
        if (best < 0) break;
        int k = kids[best];
        kids[best] = k + 1;
        kids[nk++] = bn[k].offset;
    }
    BvhNode *w = &e->out->nodes[out];
    w->valid_mask = (1u << nk) - 1u;
    w->pad = 0;
    for (int i = nk; i < 4; i++) wide_set_child(w, i, bbox_empty(), -1, 0);
    for (int i = 0; i < nk; i++) {
        const BinNode *k = &bn[kids[i]];
        if (k->count > 0) {
            wide_set_child(w, i, k->box, emit_leaf(e, k), 1);
        } else {
            int idx = e->out->num_nodes++;
            wide_set_child(w, i, k->box, idx, 0);
            collapse(e, kids[i], idx);
        }
    }
}

CstStatus bvh_build(Bvh *bvh, const AccelGeometry *geom, CstError *err)
{
    const Vec3 *positions = geom->positions;
    const int32_t *tri_indices = geom->tri_indices;
    const Sphere *spheres = geom->spheres;
    int num_tris = geom->num_tris, num_spheres = geom->num_spheres;
    memset(bvh, 0, sizeof *bvh);
    bvh->bounds = bbox_empty();
    int n = num_tris + num_spheres;
    if (n == 0) return CST_OK;
    BuildPrim *bp = malloc((size_t)n * sizeof *bp);
    uint32_t *idx = malloc((size_t)n * sizeof *idx);
    BinNode *nodes = malloc((size_t)(2 * n) * sizeof *nodes);
    /* Every wide node but the root absorbs at least one binary inner node, and a binary
     * tree over n primitives has fewer than n inner nodes and at most n leaves; each
     * leaf needs at most one block per triangle. */
    bvh->nodes = malloc((size_t)(n + 1) * sizeof *bvh->nodes);
    bvh->leaves = malloc((size_t)n * sizeof *bvh->leaves);
    bvh->blocks = malloc((size_t)(num_tris > 0 ? num_tris : 1) * sizeof *bvh->blocks);
    bvh->spheres = malloc((size_t)(num_spheres > 0 ? num_spheres : 1) * sizeof *bvh->spheres);
    if (!bp || !idx || !nodes || !bvh->nodes || !bvh->leaves || !bvh->blocks || !bvh->spheres) goto oom;

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

    BBox root = nodes[0].box;
    float margin = 1e-7f * maxf(v3_max_abs(root.min), v3_max_abs(root.max)) + 1e-30f;
    for (int i = 0; i < b.num_nodes; i++) nodes[i].box = widen(nodes[i].box, margin);

    Emitter4 e = {nodes, idx, positions, tri_indices, num_tris, spheres, bvh};
    bvh->num_nodes = 1;
    if (nodes[0].count > 0) {
        /* A root that is a leaf (few primitives) becomes the single slot of the root. */
        BvhNode *w = &bvh->nodes[0];
        for (int i = 1; i < 4; i++) wide_set_child(w, i, bbox_empty(), -1, 0);
        wide_set_child(w, 0, nodes[0].box, emit_leaf(&e, &nodes[0]), 1);
        w->valid_mask = 1u;
        w->pad = 0;
    } else {
        collapse(&e, 0, 0);
    }
    bvh->num_prims = n;
    bvh->bounds = root;
    free(bp);
    free(idx);
    free(nodes);
    return CST_OK;
oom:
    free(bp); free(idx); free(nodes);
    bvh_free(bvh);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the BVH over %d primitives", n);
}

void bvh_free(Bvh *bvh)
{
    if (!bvh) return;
    free(bvh->nodes);
    free(bvh->leaves);
    free(bvh->blocks);
    free(bvh->spheres);
    memset(bvh, 0, sizeof *bvh);
}

size_t bvh_memory_bytes(const Bvh *bvh)
{
    return (size_t)bvh->num_nodes * sizeof(BvhNode) + (size_t)bvh->num_leaves * sizeof(BvhLeaf) +
           (size_t)bvh->num_blocks * sizeof(BvhTriBlock) + (size_t)bvh->num_spheres * sizeof(BvhSphere);
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

/* Per-ray constants of the SIMD watertight test. */
typedef struct RayTri4 {
    TriangleRay tr;
    __m128 o[3]; /* origin, per world axis */
    __m128 sx, sy, sz;
} RayTri4;

static inline RayTri4 ray_tri4(const Ray *r)
{
    RayTri4 q;
    q.tr = triangle_ray_setup(r->d);
    q.o[0] = _mm_set1_ps(r->o.x); q.o[1] = _mm_set1_ps(r->o.y); q.o[2] = _mm_set1_ps(r->o.z);
    q.sx = _mm_set1_ps(q.tr.sx); q.sy = _mm_set1_ps(q.tr.sy); q.sz = _mm_set1_ps(q.tr.sz);
    return q;
}

static inline Vec3 block_vertex(const BvhTriBlock *b, int k, int lane)
{
    return v3(b->v[k][0][lane], b->v[k][1][lane], b->v[k][2][lane]);
}

/* triangle_intersect_watertight() on four triangles at once, with the same operations in
 * the same order, so each lane's t, u, v are bit-identical to the scalar test. Lanes whose
 * edge functions hit zero need the scalar's double-precision recomputation: they are
 * returned in *scalar_lanes for the caller to run through the scalar test. Returns the
 * mask of the other lanes that hit within (t_min, t_max). */
static inline int block_intersect4(const BvhTriBlock *b, const RayTri4 *q, __m128 t_min, __m128 t_max,
                                   __m128 *t_out, __m128 *u_out, __m128 *v_out, int *scalar_lanes)
{
    const int kx = q->tr.kx, ky = q->tr.ky, kz = q->tr.kz;
    __m128 px[3], py[3], pz[3];
    for (int k = 0; k < 3; k++) {
        pz[k] = _mm_sub_ps(_mm_loadu_ps(b->v[k][kz]), q->o[kz]);
        px[k] = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(b->v[k][kx]), q->o[kx]), _mm_mul_ps(q->sx, pz[k]));
        py[k] = _mm_sub_ps(_mm_sub_ps(_mm_loadu_ps(b->v[k][ky]), q->o[ky]), _mm_mul_ps(q->sy, pz[k]));
    }
    /* U, V, W: scaled barycentrics of vertices 0, 1, 2 (edge functions, JCGT 2013 eq. 4) */
    __m128 U = _mm_sub_ps(_mm_mul_ps(px[2], py[1]), _mm_mul_ps(py[2], px[1]));
    __m128 V = _mm_sub_ps(_mm_mul_ps(px[0], py[2]), _mm_mul_ps(py[0], px[2]));
    __m128 W = _mm_sub_ps(_mm_mul_ps(px[1], py[0]), _mm_mul_ps(py[1], px[0]));
    const __m128 zero = _mm_setzero_ps();
    int zero_lanes = _mm_movemask_ps(_mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)),
                                               _mm_cmpeq_ps(W, zero)));
    *scalar_lanes = zero_lanes;
    __m128 neg = _mm_or_ps(_mm_or_ps(_mm_cmplt_ps(U, zero), _mm_cmplt_ps(V, zero)), _mm_cmplt_ps(W, zero));
    __m128 pos = _mm_or_ps(_mm_or_ps(_mm_cmpgt_ps(U, zero), _mm_cmpgt_ps(V, zero)), _mm_cmpgt_ps(W, zero));
    __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
    __m128 T = _mm_add_ps(_mm_add_ps(_mm_mul_ps(U, _mm_mul_ps(q->sz, pz[0])), _mm_mul_ps(V, _mm_mul_ps(q->sz, pz[1]))),
                          _mm_mul_ps(W, _mm_mul_ps(q->sz, pz[2])));
    __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
    __m128 t = _mm_mul_ps(T, inv_det);
    __m128 ok = _mm_andnot_ps(_mm_and_ps(neg, pos), _mm_cmpneq_ps(det, zero));
    ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, t_min));
    ok = _mm_and_ps(ok, _mm_cmplt_ps(t, t_max));
    *t_out = t;
    *u_out = _mm_mul_ps(V, inv_det);
    *v_out = _mm_mul_ps(W, inv_det);
    return _mm_movemask_ps(ok) & ~zero_lanes;
}

/* Closest hit in a leaf; shortens r->t_max on a hit. */
static inline bool leaf_intersect(const Bvh *bvh, const BvhLeaf *leaf, const RayTri4 *q, Ray *r, Hit *hit)
{
    bool found = false;
    const __m128 t_min = _mm_set1_ps(r->t_min);
    for (uint32_t bi = 0; bi < leaf->num_blocks; bi++) {
        const BvhTriBlock *b = &bvh->blocks[leaf->first_block + bi];
        __m128 t4, u4, v4;
        int scalar_lanes;
        int mask = block_intersect4(b, q, t_min, _mm_set1_ps(r->t_max), &t4, &u4, &v4, &scalar_lanes);
        if (!(mask | scalar_lanes)) continue;
        float t[4], u[4], v[4];
        _mm_storeu_ps(t, t4); _mm_storeu_ps(u, u4); _mm_storeu_ps(v, v4);
        /* In lane order with strict <, as a scalar loop would pick among equal t. */
        for (int i = 0; i < 4; i++) {
            if (scalar_lanes & (1 << i)) {
                float ts, us, vs;
                if (triangle_intersect_watertight(&q->tr, r, block_vertex(b, 0, i), block_vertex(b, 1, i),
                                                  block_vertex(b, 2, i), &ts, &us, &vs)) {
                    r->t_max = ts;
                    hit->t = ts; hit->u = us; hit->v = vs; hit->prim = b->id[i];
                    found = true;
                }
            } else if ((mask & (1 << i)) && t[i] < r->t_max) {
                r->t_max = t[i];
                hit->t = t[i]; hit->u = u[i]; hit->v = v[i]; hit->prim = b->id[i];
                found = true;
            }
        }
    }
    for (uint32_t si = 0; si < leaf->num_spheres; si++) {
        const BvhSphere *sp = &bvh->spheres[leaf->first_sphere + si];
        float t;
        if (sphere_intersect(sp->center, sp->radius, r, &t)) {
            r->t_max = t;
            hit->t = t; hit->u = 0.0f; hit->v = 0.0f; hit->prim = sp->id;
            found = true;
        }
    }
    return found;
}

static inline bool leaf_occluded(const Bvh *bvh, const BvhLeaf *leaf, const RayTri4 *q, const Ray *r)
{
    const __m128 t_min = _mm_set1_ps(r->t_min), t_max = _mm_set1_ps(r->t_max);
    for (uint32_t bi = 0; bi < leaf->num_blocks; bi++) {
        const BvhTriBlock *b = &bvh->blocks[leaf->first_block + bi];
        __m128 t4, u4, v4;
        int scalar_lanes;
        if (block_intersect4(b, q, t_min, t_max, &t4, &u4, &v4, &scalar_lanes)) return true;
        for (int i = 0; i < 4; i++) {
            float ts, us, vs;
            if ((scalar_lanes & (1 << i)) &&
                triangle_intersect_watertight(&q->tr, r, block_vertex(b, 0, i), block_vertex(b, 1, i),
                                              block_vertex(b, 2, i), &ts, &us, &vs))
                return true;
        }
    }
    for (uint32_t si = 0; si < leaf->num_spheres; si++) {
        const BvhSphere *sp = &bvh->spheres[leaf->first_sphere + si];
        float t;
        if (sphere_intersect(sp->center, sp->radius, r, &t)) return true;
    }
    return false;
}

typedef struct StackEntry {
    int32_t child;
    int32_t is_leaf;
    float t; /* entry distance, to skip entries beyond a closer hit */
} StackEntry;

bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit)
{
    if (bvh->num_nodes == 0) return false;
    Ray r = *ray;
    RaySimd q = ray_simd(&r);
    RayTri4 qt = ray_tri4(&r);
    StackEntry stack[BVH_STACK];
    int sp = 0;
    stack[sp++] = (StackEntry){0, 0, r.t_min};
    bool found = false;
    while (sp > 0) {
        StackEntry e = stack[--sp];
        if (e.t > r.t_max) continue;
        if (e.is_leaf) {
            found |= leaf_intersect(bvh, &bvh->leaves[e.child], &qt, &r, hit);
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
            StackEntry k = {n->child[i], n->is_leaf[i], tn[i]};
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
    RayTri4 qt = ray_tri4(ray);
    StackEntry stack[BVH_STACK];
    int sp = 0;
    stack[sp++] = (StackEntry){0, 0, 0.0f};
    while (sp > 0) {
        StackEntry e = stack[--sp];
        if (e.is_leaf) {
            if (leaf_occluded(bvh, &bvh->leaves[e.child], &qt, ray)) return true;
            continue;
        }
        const BvhNode *n = &bvh->nodes[e.child];
        __m128 tn4;
        int mask = node_hit4(n, &q, ray->t_min, ray->t_max, &tn4);
        for (int i = 0; i < 4; i++)
            if (mask & (1 << i)) stack[sp++] = (StackEntry){n->child[i], n->is_leaf[i], 0.0f};
    }
    return false;
}
