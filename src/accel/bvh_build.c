/* BVH build: binned SAH, parallel over subtrees, collapsed to 8-wide nodes (traversal is
 * in bvh.c). */
#include "accel/bvh.h"

#include <assert.h>
#include <immintrin.h>
#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/array.h"
#include "core/error.h"
#include "core/memory.h"
#include "core/threadpool.h"
#include "geometry/sphere.h"

enum {
    BVH_BINS = 32,
    BVH_MAX_LEAF = 8,   /* larger binary leaves are always split (a BvhRef holds up to 8 spheres) */
    /* Subtrees over fewer primitives are built by the thread that reached them: thread
     * start-up would cost more than it saves. */
    BVH_PARALLEL_MIN = 16384,
    BVH_MAX_BUILD_THREADS = 16
};
/* SAH costs relative to one 4-triangle block test. One node visit tests eight boxes with
 * one AVX slab test. 0.3 since the node test picks its planes by the ray's signs: on the
 * Cornell box's ray sets 1.4 -> 1.75x Embree on primary rays, 1.0 -> 1.2x on secondary
 * and occlusion rays against 0.5, the light tracer 7% faster on cornell-spheres, and no
 * change on the meshes (0.1 and 0.2: no better; docs/benchmarks.md). */
static const float SAH_TRAVERSAL_COST = 0.3f;
static const float SAH_ISECT_COST = 1.0f;
/* The collapse's cost of one wide-node visit, relative to one block test: what a visit
 * costs on the large meshes, where it is a dependent load that often misses the cache.
 * Dragon and bumpysphere, 1 thread, against Embree: 1.0 and 1.5 gave the same within
 * the noise, 3.0 too, 0.5 slightly slower (docs/benchmarks.md). */
static const float WIDE_NODE_COST = 2.0f;

/* ------------------------------------------------------------------ build */

/* Box with SSE lanes x, y, z (lane 3 unused). */
typedef struct Box4 {
    __m128 lo, hi;
} Box4;

static inline Box4 box4_empty(void)
{
    Box4 b = {_mm_set1_ps(INFINITY), _mm_set1_ps(-INFINITY)};
    return b;
}
static inline Box4 box4_union(Box4 a, Box4 b)
{
    Box4 r = {_mm_min_ps(a.lo, b.lo), _mm_max_ps(a.hi, b.hi)};
    return r;
}
static inline Box4 box4_add(Box4 a, __m128 p)
{
    Box4 r = {_mm_min_ps(a.lo, p), _mm_max_ps(a.hi, p)};
    return r;
}
static inline float box4_half_area(Box4 b)
{
    float e[4];
    _mm_storeu_ps(e, _mm_sub_ps(b.hi, b.lo));
    return e[0] * e[1] + e[1] * e[2] + e[2] * e[0];
}
static inline BBox box4_to_bbox(Box4 b)
{
    float lo[4], hi[4];
    _mm_storeu_ps(lo, b.lo);
    _mm_storeu_ps(hi, b.hi);
    BBox r = {v3(lo[0], lo[1], lo[2]), v3(hi[0], hi[1], hi[2])};
    return r;
}

/* A primitive's bounds; its centroid is taken doubled, lo + hi, which bins the same. */
typedef struct BuildPrim {
    float lo[4], hi[4];
} BuildPrim;

static inline Box4 prim_box(const BuildPrim *p)
{
    Box4 b = {_mm_load_ps(p->lo), _mm_load_ps(p->hi)};
    return b;
}

/* Binary node of the intermediate SAH tree. The left child follows its parent; each
 * subtree over m primitives owns the 2m - 1 slots from its root on, so subtrees built
 * by different threads never share an index and the layout does not depend on timing. */
typedef struct BinNode {
    BBox box;
    int32_t offset; /* leaf: first primitive in idx; inner: index of the right child */
    int32_t count;  /* primitives in a leaf; 0 for inner nodes */
} BinNode;

/* Leaves are tested TRI_BLOCK_WIDTH triangles at a time, so a leaf of n costs
 * ceil(n / width) tests (the "block SAH" of wide BVHs). */
static inline float sah_blocks(int n) { return (float)((n + TRI_BLOCK_WIDTH - 1) / TRI_BLOCK_WIDTH); }

/* The collapse into wide nodes (Ylitie et al., "Efficient Incoherent Ray Traversal on
 * GPUs Through Compressed Wide BVHs", HPG 2017, section 4.1): for every binary node n
 * and i = 1..8, the least SAH cost of n's subtree when it may take up to i slots of its
 * wide parent, as one leaf, one wide node, or split between n's children. Computed
 * bottom-up as the binary build returns, so it runs on the build's threads. The cost of
 * a slot's subtree counts its root's area once per block tested (a leaf) or once per
 * visit (a wide node, WIDE_NODE_COST), as the SAH of the finished wide tree does. */
typedef struct SubtreeCost {
    float cost[BVH_WIDTH]; /* cost[i - 1]: in at most i slots */
    int count;             /* primitives */
    unsigned kinds;        /* 1: has triangles, 2: has spheres */
} SubtreeCost;

/* choice[n][0]: 0 if n becomes one leaf, else k, when n becomes a wide node: k of its
 * eight slots go to the left child's subtree, 8 - k to the right's. choice[n][i - 1] for
 * i > 1: 0 if n takes fewer than i slots, else k, the left child's share of the i. */
typedef int8_t CollapseChoice[BVH_WIDTH];

/* 32 triangles: 4 blocks of 8 (AVX) or 8 of 4, the most a BvhRef counts; 64 with AVX
 * measured no faster (docs/benchmarks.md). */
enum { WIDE_LEAF_MAX_TRIS = 32, WIDE_LEAF_MAX_SPHERES = 8 };

typedef struct Builder {
    const BuildPrim *bp;
    uint32_t *idx;
    BinNode *nodes;
    CollapseChoice *choice;
    uint32_t num_tris;   /* ids below are triangles, then spheres */
    uint32_t shape_base; /* ids from here on are analytic shapes */
} Builder;

/* 1: triangle, 2: sphere, 4: analytic shape (SubtreeCost.kinds). */
static inline unsigned prim_kind(const Builder *b, uint32_t id) { return id < b->num_tris ? 1u : (id < b->shape_base ? 2u : 4u); }

/* Bounds and centroid bounds of idx[begin, end): for the root and the rare splits that
 * do not come out of binning. */
static void range_bounds(const Builder *b, int begin, int end, Box4 *box, Box4 *cbox)
{
    Box4 bb = box4_empty(), cb = box4_empty();
    for (int i = begin; i < end; i++) {
        Box4 p = prim_box(&b->bp[b->idx[i]]);
        bb = box4_union(bb, p);
        cb = box4_add(cb, _mm_add_ps(p.lo, p.hi));
    }
    *box = bb;
    *cbox = cb;
}

typedef struct Split {
    int mid; /* partition point; -1: make a leaf */
    Box4 lbox, lcbox, rbox, rcbox;
} Split;

/* Bins for a node over n primitives: as many as pay off. The SAH sweep over the bins
 * costs as much as binning ~100 primitives, and most nodes are small (Embree sizes its
 * bins the same way, 4 + n / 20 up to its maximum). */
static inline int bin_count(int n) { return n / 20 + 4 < BVH_BINS ? n / 20 + 4 : BVH_BINS; }

/* Per-axis bin scale: bins across the centroid extent, 0 where it is flat (everything
 * then lands in bin 0 and the axis is skipped). */
static inline __m128 bin_scale(Box4 cbox, int nbins)
{
    __m128 ext = _mm_sub_ps(cbox.hi, cbox.lo);
    __m128 s = _mm_div_ps(_mm_set1_ps((float)nbins * 0.99999f), ext);
    return _mm_and_ps(s, _mm_cmpgt_ps(ext, _mm_setzero_ps()));
}

static inline __m128i bin_index(__m128 c, __m128 cmin, __m128 scale, __m128 last_bin)
{
    __m128 k = _mm_mul_ps(_mm_sub_ps(c, cmin), scale);
    k = _mm_min_ps(_mm_max_ps(k, _mm_setzero_ps()), last_bin);
    return _mm_cvttps_epi32(k);
}

/* Binned SAH over all three axes in one pass (Wald 2007), on doubled centroids. Fills
 * the split and both sides' bounds, or sets mid = -1 when a leaf is cheaper. */
static void find_split(Builder *b, int begin, int end, Box4 box, Box4 cbox, Split *out)
{
    out->mid = -1;
    int n = end - begin;
    Box4 bins[3][BVH_BINS], cbins[3][BVH_BINS];
    int counts[3][BVH_BINS];
    const int nbins = bin_count(n);
    for (int a = 0; a < 3; a++)
        for (int i = 0; i < nbins; i++) {
            bins[a][i] = box4_empty();
            cbins[a][i] = box4_empty();
            counts[a][i] = 0;
        }
    __m128 cmin = cbox.lo, scale = bin_scale(cbox, nbins), last_bin = _mm_set1_ps((float)(nbins - 1));
    for (int i = begin; i < end; i++) {
        Box4 p = prim_box(&b->bp[b->idx[i]]);
        __m128 c = _mm_add_ps(p.lo, p.hi);
        int k[4];
        _mm_storeu_si128((__m128i *)k, bin_index(c, cmin, scale, last_bin));
        for (int a = 0; a < 3; a++) {
            bins[a][k[a]] = box4_union(bins[a][k[a]], p);
            cbins[a][k[a]] = box4_add(cbins[a][k[a]], c);
            counts[a][k[a]]++;
        }
    }
    float ext[4];
    _mm_storeu_ps(ext, _mm_sub_ps(cbox.hi, cbox.lo));
    float best_cost = INFINITY;
    int best_axis = -1, best_bin = -1;
    for (int a = 0; a < 3; a++) {
        if (!(ext[a] > 0.0f)) continue;
        /* Sweep from the right for suffix areas, then from the left to evaluate. */
        float right_area[BVH_BINS];
        int right_count[BVH_BINS];
        Box4 acc = box4_empty();
        int cnt = 0;
        for (int i = nbins - 1; i > 0; i--) {
            acc = box4_union(acc, bins[a][i]);
            cnt += counts[a][i];
            right_area[i] = box4_half_area(acc);
            right_count[i] = cnt;
        }
        acc = box4_empty();
        cnt = 0;
        for (int i = 0; i < nbins - 1; i++) {
            acc = box4_union(acc, bins[a][i]);
            cnt += counts[a][i];
            if (cnt == 0 || right_count[i + 1] == 0) continue;
            float cost = box4_half_area(acc) * sah_blocks(cnt) + right_area[i + 1] * sah_blocks(right_count[i + 1]);
            if (cost < best_cost) { best_cost = cost; best_axis = a; best_bin = i; }
        }
    }
    if (best_axis < 0) return;
    float parent_area = box4_half_area(box);
    float split_cost = SAH_TRAVERSAL_COST + (parent_area > 0.0f ? SAH_ISECT_COST * best_cost / parent_area : INFINITY);
    if (split_cost >= SAH_ISECT_COST * sah_blocks(n) && n <= BVH_MAX_LEAF) return;

    out->lbox = out->lcbox = out->rbox = out->rcbox = box4_empty();
    for (int i = 0; i < nbins; i++) {
        if (i <= best_bin) {
            out->lbox = box4_union(out->lbox, bins[best_axis][i]);
            out->lcbox = box4_union(out->lcbox, cbins[best_axis][i]);
        } else {
            out->rbox = box4_union(out->rbox, bins[best_axis][i]);
            out->rcbox = box4_union(out->rcbox, cbins[best_axis][i]);
        }
    }
    int i = begin, j = end - 1;
    while (i <= j) {
        Box4 p = prim_box(&b->bp[b->idx[i]]);
        int k[4];
        _mm_storeu_si128((__m128i *)k, bin_index(_mm_add_ps(p.lo, p.hi), cmin, scale, last_bin));
        if (k[best_axis] <= best_bin) i++;
        else { uint32_t t = b->idx[i]; b->idx[i] = b->idx[j]; b->idx[j] = t; j--; }
    }
    out->mid = i;
}

/* A leaf's SAH cost: its blocks, or its spheres, one at a time. */
static inline float leaf_sah(float area, int count, bool tris)
{
    return area * (tris ? sah_blocks(count) : (float)count);
}

static void leaf_cost(Builder *b, int node, SubtreeCost *out)
{
    const BinNode *bn = &b->nodes[node];
    unsigned kind = prim_kind(b, b->idx[bn->offset]); /* a binary leaf holds one kind */
    bool tris = kind == 1u;
    float c = leaf_sah(bbox_area(bn->box), bn->count, tris);
    for (int i = 0; i < BVH_WIDTH; i++) {
        out->cost[i] = c;
        b->choice[node][i] = 0;
    }
    out->count = bn->count;
    out->kinds = kind;
}

static void inner_cost(Builder *b, int node, const SubtreeCost *l, const SubtreeCost *r, SubtreeCost *out)
{
    const float area = bbox_area(b->nodes[node].box);
    int8_t *choice = b->choice[node];
    /* split[j]: both children's subtrees in j slots, the best division */
    float split[BVH_WIDTH + 1];
    int8_t left_share[BVH_WIDTH + 1];
    for (int j = 2; j <= BVH_WIDTH; j++) {
        split[j] = INFINITY;
        left_share[j] = 1;
        for (int k = 1; k < j; k++) {
            float c = l->cost[k - 1] + r->cost[j - k - 1];
            if (c < split[j]) { split[j] = c; left_share[j] = (int8_t)k; }
        }
    }
    out->count = l->count + r->count;
    out->kinds = l->kinds | r->kinds;
    float as_node = area * WIDE_NODE_COST + split[BVH_WIDTH], as_leaf = INFINITY;
    if ((out->kinds == 1u && out->count <= WIDE_LEAF_MAX_TRIS) ||
        ((out->kinds == 2u || out->kinds == 4u) && out->count <= WIDE_LEAF_MAX_SPHERES))
        as_leaf = leaf_sah(area, out->count, out->kinds == 1u);
    /* The root is a wide node whatever its size: the ray tests it in any case. */
    if (as_leaf <= as_node && node != 0) { out->cost[0] = as_leaf; choice[0] = 0; }
    else { out->cost[0] = as_node; choice[0] = left_share[BVH_WIDTH]; }
    for (int i = 2; i <= BVH_WIDTH; i++) {
        if (split[i] < out->cost[i - 2]) { out->cost[i - 1] = split[i]; choice[i - 1] = left_share[i]; }
        else { out->cost[i - 1] = out->cost[i - 2]; choice[i - 1] = 0; }
    }
}

/* Node `node` over idx[begin, end): its box, then a split (true, *s, the node inner with
 * its right child at node + 2 * (s->mid - begin)) or a leaf (false). */
static bool split_node(Builder *b, int node, int begin, int end, Box4 box, Box4 cbox, int depth, Split *s)
{
    BinNode *bn = &b->nodes[node];
    bn->box = box4_to_bbox(box);
    int n = end - begin;
    s->mid = -1;
    if (n > 1 && depth < BVH_MAX_DEPTH) find_split(b, begin, end, box, cbox, s);
    if (s->mid < 0 && n > 1) {
        int split_at = -1;
        if (n > BVH_MAX_LEAF) {
            /* Coincident centroids (or too deep): any partition is correct, the middle
             * keeps leaves small. */
            split_at = begin + n / 2;
        } else {
            /* A leaf holds one kind of primitive: the lowest kind present goes first. */
            unsigned k0 = 4u;
            for (int i = begin; i < end; i++) k0 = prim_kind(b, b->idx[i]) < k0 ? prim_kind(b, b->idx[i]) : k0;
            int i = begin, j = end - 1;
            while (i <= j) {
                if (prim_kind(b, b->idx[i]) == k0) i++;
                else { uint32_t t = b->idx[i]; b->idx[i] = b->idx[j]; b->idx[j] = t; j--; }
            }
            if (i > begin && i < end) split_at = i;
        }
        if (split_at >= 0) {
            s->mid = split_at;
            range_bounds(b, begin, split_at, &s->lbox, &s->lcbox);
            range_bounds(b, split_at, end, &s->rbox, &s->rcbox);
        }
    }
    if (s->mid < 0) {
        bn->offset = begin;
        bn->count = n;
        return false;
    }
    bn->offset = node + 2 * (s->mid - begin);
    bn->count = 0;
    return true;
}

/* The subtree of `node`, depth first on the calling thread; *out its collapse costs. */
static void build_node(Builder *b, int node, int begin, int end, Box4 box, Box4 cbox, int depth, SubtreeCost *out)
{
    Split s;
    if (!split_node(b, node, begin, end, box, cbox, depth, &s)) {
        leaf_cost(b, node, out);
        return;
    }
    SubtreeCost lc, rc;
    build_node(b, node + 1, begin, s.mid, s.lbox, s.lcbox, depth + 1, &lc);
    build_node(b, b->nodes[node].offset, s.mid, end, s.rbox, s.rcbox, depth + 1, &rc);
    inner_cost(b, node, &lc, &rc, out);
}

/* The parallel build. Node numbering is fixed by the splits alone (left child node + 1,
 * right child node + 2 * left count), so any thread may build any subtree and the tree
 * is the serial one, bit for bit. The top of the tree, nodes of BVH_PARALLEL_MIN
 * primitives or more, is split level by level, a level's nodes in parallel; the
 * smaller subtrees under it are work items built whole; then the top's collapse costs
 * are computed bottom-up, serially (a few nodes). */
typedef struct TopNode {
    int node, begin, end, depth;
    Box4 box, cbox;
    bool inner;        /* split; its children are entries kid[0], kid[1] */
    Split split;       /* the split, from its parallel-for until its children are added */
    int kid[2];
    SubtreeCost cost;
} TopNode;

typedef struct TopBuild {
    Builder *b;
    ARRAY(TopNode) top;
    ARRAY(int) items;  /* entries of the current parallel-for */
} TopBuild;

static void top_split_item(void *ctx, int item, int worker)
{
    (void)worker;
    TopBuild *tb = ctx;
    TopNode *t = &tb->top.v[tb->items.v[item]];
    t->inner = split_node(tb->b, t->node, t->begin, t->end, t->box, t->cbox, t->depth, &t->split);
    if (!t->inner) leaf_cost(tb->b, t->node, &t->cost);
}

static void top_subtree_item(void *ctx, int item, int worker)
{
    (void)worker;
    TopBuild *tb = ctx;
    TopNode *t = &tb->top.v[tb->items.v[item]];
    build_node(tb->b, t->node, t->begin, t->end, t->box, t->cbox, t->depth, &t->cost);
}

/* Builds the whole tree on `pool` (see TopNode); *out is the root's costs. False on OOM. */
static bool build_parallel(Builder *b, ThreadPool *pool, int n, Box4 box, Box4 cbox, SubtreeCost *out)
{
    TopBuild tb = {b, {0}, {0}};
    bool ok = false;
    if (!array_push(&tb.top, ((TopNode){.node = 0, .begin = 0, .end = n, .box = box, .cbox = cbox}))) goto done;
    /* Entries [level, top.n) are the level being split; the ones under BVH_PARALLEL_MIN
     * wait for the subtree step. */
    for (size_t level = 0, next; level < tb.top.n; level = next) {
        tb.items.n = 0;
        for (size_t i = level; i < tb.top.n; i++)
            if (tb.top.v[i].end - tb.top.v[i].begin >= BVH_PARALLEL_MIN && !array_push(&tb.items, (int)i)) goto done;
        threadpool_for(pool, (int)tb.items.n, top_split_item, &tb);
        next = tb.top.n;
        for (size_t k = 0; k < tb.items.n; k++) {
            const TopNode t = tb.top.v[tb.items.v[k]];
            if (!t.inner) continue;
            const Split *sp = &t.split;
            if (!array_push(&tb.top, ((TopNode){.node = t.node + 1, .begin = t.begin, .end = sp->mid,
                                                .depth = t.depth + 1, .box = sp->lbox, .cbox = sp->lcbox})) ||
                !array_push(&tb.top, ((TopNode){.node = b->nodes[t.node].offset, .begin = sp->mid, .end = t.end,
                                                .depth = t.depth + 1, .box = sp->rbox, .cbox = sp->rcbox})))
                goto done;
            tb.top.v[tb.items.v[k]].kid[0] = (int)tb.top.n - 2;
            tb.top.v[tb.items.v[k]].kid[1] = (int)tb.top.n - 1;
        }
    }
    /* The subtrees under the top, one work item each. */
    tb.items.n = 0;
    for (size_t i = 0; i < tb.top.n; i++)
        if (tb.top.v[i].end - tb.top.v[i].begin < BVH_PARALLEL_MIN && !array_push(&tb.items, (int)i)) goto done;
    threadpool_for(pool, (int)tb.items.n, top_subtree_item, &tb);
    /* Children come after their parent in the array: backwards is bottom-up. */
    for (size_t i = tb.top.n; i-- > 0;) {
        TopNode *t = &tb.top.v[i];
        if (t->inner) inner_cost(b, t->node, &tb.top.v[t->kid[0]].cost, &tb.top.v[t->kid[1]].cost, &t->cost);
    }
    *out = tb.top.v[0].cost;
    ok = true;
done:
    array_free(&tb.top);
    array_free(&tb.items);
    return ok;
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

static void wide_set_child(BvhNode *w, int slot, BBox box, uint32_t ref)
{
    w->bounds[0][slot] = box.min.x; w->bounds[1][slot] = box.max.x;
    w->bounds[2][slot] = box.min.y; w->bounds[3][slot] = box.max.y;
    w->bounds[4][slot] = box.min.z; w->bounds[5][slot] = box.max.z;
    w->child[slot] = ref;
}

static void wide_clear(BvhNode *w)
{
    BBox inverted = {v3s(INFINITY), v3s(-INFINITY)}; /* see node_hit8 */
    for (int i = 0; i < BVH_WIDTH; i++) wide_set_child(w, i, inverted, BVH_EMPTY);
}

/* Everything the collapse pass writes: wide nodes, triangle blocks, spheres. */
typedef struct Emitter {
    const BinNode *bin;
    const uint32_t *idx;
    const Vec3 *positions;
    const int32_t *tri_indices;
    uint32_t num_tris;
    const Sphere *spheres;
    uint32_t shape_base;
    uint32_t num_ids;       /* ids from here on are further pieces of shapes: */
    const uint32_t *owner;  /* owner[id - num_ids], that shape's id */
    float margin;
    const CollapseChoice *choice;
    Bvh *out;
    size_t cursor; /* units written */
} Emitter;

_Static_assert(sizeof(BvhNode) % BVH_UNIT == 0 && sizeof(TriangleBlock) % BVH_UNIT == 0,
               "nodes and blocks are whole units");
enum { NODE_UNITS = sizeof(BvhNode) / BVH_UNIT, BLOCK_UNITS = sizeof(TriangleBlock) / BVH_UNIT };

static inline void *unit_at(Emitter *e, size_t u) { return e->out->units + u * BVH_UNIT; }

/* The primitives of binary node `node`'s subtree, idx[*begin, *end): contiguous, from its
 * leftmost binary leaf to its rightmost. */
static void subtree_range(const BinNode *bin, int node, int *begin, int *end)
{
    int lo = node, hi = node;
    while (bin[lo].count == 0) lo++;
    while (bin[hi].count == 0) hi = bin[hi].offset;
    *begin = bin[lo].offset;
    *end = bin[hi].offset + bin[hi].count;
}

/* Writes the leaf for the primitives of binary node `node`'s subtree and returns its
 * reference: triangles packed TRI_BLOCK_WIDTH to a block in the SAH's order, or spheres. */
static uint32_t emit_leaf(Emitter *e, int node)
{
    Bvh *o = e->out;
    o->num_leaves++;
    int begin, end;
    subtree_range(e->bin, node, &begin, &end);
    uint32_t first_id = e->idx[begin];
    if (first_id >= e->shape_base) { /* shapes: their ids, under BVH_SHAPES in a sphere reference */
        uint32_t first = (uint32_t)o->num_shape_ids;
        for (int i = begin; i < end; i++) {
            uint32_t id = e->idx[i] < e->num_ids ? e->idx[i] : e->owner[e->idx[i] - e->num_ids];
            bool dup = false; /* two pieces of one curve in one leaf: test it once */
            for (uint32_t k = first; k < (uint32_t)o->num_shape_ids; k++) dup |= o->shape_ids[k] == id;
            if (!dup) o->shape_ids[o->num_shape_ids++] = id;
        }
        return BVH_LEAF | BVH_SPHERES | BVH_SHAPES | (((uint32_t)o->num_shape_ids - first - 1) << BVH_COUNT_SHIFT) |
               first << BVH_INDEX_SHIFT;
    }
    if (first_id >= e->num_tris) {
        uint32_t first = (uint32_t)o->num_spheres;
        for (int i = begin; i < end; i++) {
            const Sphere *sp = &e->spheres[e->idx[i] - e->num_tris];
            BvhSphere *d = &o->spheres[o->num_spheres++];
            d->center = sp->center;
            d->radius = sp->radius;
            d->id = e->idx[i];
        }
        return BVH_LEAF | BVH_SPHERES | ((uint32_t)(end - begin - 1) << BVH_COUNT_SHIFT) | first << BVH_INDEX_SHIFT;
    }
    uint32_t first = (uint32_t)e->cursor;
    uint32_t count = 0;
    int lane = TRI_BLOCK_WIDTH;
    TriangleBlock *blk = NULL;
    for (int i = begin; i < end; i++) {
        uint32_t id = e->idx[i];
        if (lane == TRI_BLOCK_WIDTH) {
            blk = unit_at(e, e->cursor);
            e->cursor += BLOCK_UNITS;
            o->num_blocks++;
            count++;
            /* Unused lanes hold NaN vertices: every comparison in the SIMD test then
             * fails, so they need no mask. */
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++)
                    for (int l = 0; l < TRI_BLOCK_WIDTH; l++) blk->v[k][a][l] = NAN;
            for (int l = 0; l < TRI_BLOCK_WIDTH; l++) blk->id[l] = TRI_BLOCK_NO_PRIM;
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
    return BVH_LEAF | ((count - 1u) << BVH_COUNT_SHIFT) | first << BVH_INDEX_SHIFT;
}

/* The roots of the subtrees that binary node n's subtree becomes in at most i slots, as
 * the collapse's costs chose. */
static void gather(const BinNode *bin, const CollapseChoice *choice, int n, int i, int *kids, int *nk)
{
    while (i > 1 && choice[n][i - 1] == 0) i--;
    if (i == 1) {
        kids[(*nk)++] = n;
        return;
    }
    const int k = choice[n][i - 1];
    gather(bin, choice, n + 1, k, kids, nk);
    gather(bin, choice, bin[n].offset, i - k, kids, nk);
}

/* The slots of the wide node that binary inner node `bin` becomes, in order. */
static int wide_kids(const BinNode *bin, const CollapseChoice *choice, int node, int kids[BVH_WIDTH])
{
    int nk = 0;
    gather(bin, choice, node + 1, choice[node][0], kids, &nk);
    gather(bin, choice, bin[node].offset, BVH_WIDTH - choice[node][0], kids, &nk);
    return nk;
}

/* Turns binary node `bin` into the wide node at unit `out`, its slots shared between its
 * children's subtrees as the collapse's costs chose. After the node come its leaves'
 * blocks, then its inner children depth first (bvh.h). */
static void collapse(Emitter *e, int bin, size_t out)
{
    int kids[BVH_WIDTH];
    const int nk = wide_kids(e->bin, e->choice, bin, kids);
    BvhNode *w = unit_at(e, out);
    wide_clear(w);
    for (int i = 0; i < nk; i++)
        if (e->choice[kids[i]][0] == 0) wide_set_child(w, i, widen(e->bin[kids[i]].box, e->margin), emit_leaf(e, kids[i]));
    for (int i = 0; i < nk; i++) {
        if (e->choice[kids[i]][0] == 0) continue;
        size_t at = e->cursor;
        e->cursor += NODE_UNITS;
        e->out->num_nodes++;
        wide_set_child(w, i, widen(e->bin[kids[i]].box, e->margin), (uint32_t)(at * BVH_UNIT));
        collapse(e, kids[i], at);
    }
}

/* The wide nodes and triangle blocks that collapse() writes for binary node `node`'s
 * subtree as one slot (a leaf if the collapse chose one), so the array is allocated at
 * its size. */
static void count_wide(const BinNode *bin, const CollapseChoice *choice, const uint32_t *idx, uint32_t num_tris,
                       int node, size_t *nodes, size_t *blocks)
{
    if (choice[node][0] == 0) {
        int begin, end;
        subtree_range(bin, node, &begin, &end);
        if (idx[begin] < num_tris) *blocks += (size_t)(end - begin + TRI_BLOCK_WIDTH - 1) / TRI_BLOCK_WIDTH;
        return;
    }
    (*nodes)++;
    int kids[BVH_WIDTH];
    const int nk = wide_kids(bin, choice, node, kids);
    for (int i = 0; i < nk; i++) count_wide(bin, choice, idx, num_tris, kids[i], nodes, blocks);
}

static int build_threads(void)
{
    long n = sysconf(_SC_NPROCESSORS_ONLN);
    return n < 1 ? 1 : (n > BVH_MAX_BUILD_THREADS ? BVH_MAX_BUILD_THREADS : (int)n);
}

/* The compact curve records (bvh.h), when the scene has curves, one per shape_ids slot
 * (a curve cut in pieces has one in each leaf holding one), in leaf order: a leaf's
 * records are consecutive lines, reached without reading shape_ids. A curve's segments
 * are consecutive shapes with the same widths, which they share: a widths entry is
 * reused while they repeat bit for bit. False when out of memory. */
static bool build_curve_segs(Bvh *bvh, const AnalyticShape *shapes, int num_shapes)
{
    int curves = 0;
    for (int i = 0; i < num_shapes; i++) curves += shape_curve(&shapes[i]) != NULL;
    if (curves == 0) return true;
    uint32_t *windex = malloc((size_t)num_shapes * sizeof *windex); /* shape -> its widths entry */
    bvh->curve_segs = aligned_alloc(64, (size_t)(bvh->num_shape_ids > 0 ? bvh->num_shape_ids : 1) * sizeof(CurveSeg));
    bvh->curve_widths = malloc((size_t)curves * sizeof(CurveWidths));
    if (!windex || !bvh->curve_segs || !bvh->curve_widths) {
        free(windex);
        return false;
    }
    uint32_t nw = 0;
    for (int i = 0; i < num_shapes; i++) {
        const Curve *c = shape_curve(&shapes[i]);
        if (!c) continue;
        const CurveWidths w = {c->w0, c->w1};
        if (nw == 0 || memcmp(&bvh->curve_widths[nw - 1], &w, sizeof w) != 0) bvh->curve_widths[nw++] = w;
        windex[i] = nw - 1;
    }
    bvh->num_curve_widths = (int)nw;
    bvh->num_curve_segs = bvh->num_shape_ids;
    for (int j = 0; j < bvh->num_shape_ids; j++) {
        const uint32_t k = bvh->shape_ids[j] - bvh->shape_base;
        const Curve *c = shape_curve(&shapes[k]);
        CurveSeg *s = &bvh->curve_segs[j];
        if (!c || !curve_seg_init(s, c, windex[k])) {
            memset(s, 0, sizeof *s);
            s->info = BVH_NO_CURVE_SEG;
        }
    }
    free(windex);
    return true;
}

CstStatus bvh_build(Bvh *bvh, const AccelGeometry *geom, CstError *err)
{
    const Vec3 *positions = geom->positions;
    const int32_t *tri_indices = geom->tri_indices;
    const Sphere *spheres = geom->spheres;
    int num_tris = geom->num_tris, num_spheres = geom->num_spheres;
    memset(bvh, 0, sizeof *bvh);
    bvh->bounds = bbox_empty();
    const int num_shapes = geom->num_shapes;
    const uint32_t shape_base = accel_shape_base(geom);
    const int num_ids = num_tris + num_spheres + num_shapes;
    if (num_ids == 0) return CST_OK;
    if ((uint32_t)num_spheres > BVH_SHAPE_INDEX_MAX || (uint32_t)num_shapes > BVH_SHAPE_INDEX_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "the BVH holds at most %u spheres and as many shapes", BVH_SHAPE_INDEX_MAX);
    /* Curves enter as several pieces (curve_piece_bounds), each a build primitive of its
     * own: a long thin segment's one box holds far more empty space than its pieces'.
     * Piece 0 keeps the shape's id, the others take ids from num_ids on (owner[]). */
    long long n_ll = num_ids;
    for (int i = 0; i < num_shapes; i++) {
        BBox pieces[CURVE_MAX_PIECES];
        n_ll += shape_piece_bounds(&geom->shapes[i], pieces) - 1;
    }
    if (n_ll - num_tris - num_spheres > (long long)BVH_SHAPE_INDEX_MAX || n_ll > INT_MAX / 2)
        return cst_fail(err, CST_ERR_INVALID_ARG, "the BVH holds at most %u shapes and curve pieces", BVH_SHAPE_INDEX_MAX);
    const int n = (int)n_ll;
    BuildPrim *bp = aligned_alloc(16, (size_t)n * sizeof *bp);
    uint32_t *idx = malloc((size_t)n * sizeof *idx);
    uint32_t *owner = malloc((size_t)(n - num_ids + 1) * sizeof *owner);
    BinNode *nodes = malloc((size_t)2 * (size_t)n * sizeof *nodes);
    CollapseChoice *choice = malloc((size_t)2 * (size_t)n * sizeof *choice);
    if (!bp || !idx || !owner || !nodes || !choice) goto oom;

    for (int i = 0; i < num_tris; i++) {
        Vec3 a = positions[tri_indices[3 * i]], bb = positions[tri_indices[3 * i + 1]],
             c = positions[tri_indices[3 * i + 2]];
        BBox box = bbox_add(bbox_add(bbox_add(bbox_empty(), a), bb), c);
        bp[i] = (BuildPrim){{box.min.x, box.min.y, box.min.z, 0.0f}, {box.max.x, box.max.y, box.max.z, 0.0f}};
    }
    for (int i = 0; i < num_spheres; i++) {
        Vec3 c = spheres[i].center;
        float r = fabsf(spheres[i].radius); /* sphere_intersect squares the radius: its sign is moot */
        bp[num_tris + i] = (BuildPrim){{c.x - r, c.y - r, c.z - r, 0.0f}, {c.x + r, c.y + r, c.z + r, 0.0f}};
    }
    for (int i = 0, extra = num_ids; i < num_shapes; i++) {
        BBox pieces[CURVE_MAX_PIECES];
        const int k = shape_piece_bounds(&geom->shapes[i], pieces);
        for (int j = 0; j < k; j++) {
            const BBox sb = pieces[j];
            const int at = j == 0 ? (int)shape_base + i : extra++;
            if (j > 0) owner[at - num_ids] = shape_base + (uint32_t)i;
            bp[at] = (BuildPrim){{sb.min.x, sb.min.y, sb.min.z, 0.0f}, {sb.max.x, sb.max.y, sb.max.z, 0.0f}};
        }
    }
    for (int i = 0; i < n; i++) idx[i] = (uint32_t)i;

    Builder b = {bp, idx, nodes, choice, (uint32_t)num_tris, shape_base};
    Box4 root_box, root_cbox;
    range_bounds(&b, 0, n, &root_box, &root_cbox);
    SubtreeCost root_cost;
    ThreadPool *pool = NULL;
    /* Small scenes are built on the calling thread: the tree is the same either way. */
    if (n >= BVH_PARALLEL_MIN && threadpool_create(build_threads(), &pool) == CST_OK) {
        bool built = build_parallel(&b, pool, n, root_box, root_cbox, &root_cost);
        threadpool_destroy(pool);
        if (!built) goto oom;
    } else {
        build_node(&b, 0, 0, n, root_box, root_cbox, 0, &root_cost);
    }

    /* A root that is a binary leaf is the single slot of a root node (below). */
    size_t wide = nodes[0].count > 0 ? 1 : 0, blocks = 0;
    count_wide(nodes, choice, idx, (uint32_t)num_tris, 0, &wide, &blocks);
    /* Leaf references carry a unit index in 27 bits, inner ones a byte offset in 32 (4 GiB
     * of nodes and blocks either way). */
    if (wide * NODE_UNITS + blocks * BLOCK_UNITS > BVH_INDEX_MAX) {
        free(bp); free(idx); free(owner); free(nodes); free(choice);
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "the BVH holds at most %u units of 32 bytes (%zu nodes and %zu triangle blocks need more)",
                        BVH_INDEX_MAX, wide, blocks);
    }
    size_t units = wide * NODE_UNITS + blocks * BLOCK_UNITS;
    bvh->units = memory_alloc_large(units * BVH_UNIT);
    bvh->spheres = malloc((size_t)(num_spheres > 0 ? num_spheres : 1) * sizeof *bvh->spheres);
    bvh->shape_ids = malloc((size_t)(n - num_tris - num_spheres > 0 ? n - num_tris - num_spheres : 1) *
                            sizeof *bvh->shape_ids);
    if (!bvh->units || !bvh->spheres || !bvh->shape_ids) goto oom;
    bvh->shapes = geom->shapes;
    bvh->shape_base = shape_base;

    BBox root = nodes[0].box;
    Emitter e = {nodes, idx, positions, tri_indices, (uint32_t)num_tris, spheres, shape_base, (uint32_t)num_ids,
                 owner, 0.0f, choice, bvh, NODE_UNITS};
    /* Not smaller: at 2^-30 of the extent the conformance test's unit icosphere (coordinates
     * around 0, where the relative widening vanishes) lost closest hits to the slab test's
     * rounding.
     * Scene.offset_near (scene_commit) is four times this, so that rays leaving a surface
     * in a coordinate plane start outside its box: change the two together. */
    e.margin = 1e-7f * maxf(v3_max_abs(root.min), v3_max_abs(root.max)) + 1e-30f;
    bvh->num_nodes = 1;
    if (nodes[0].count > 0) {
        /* A root that is a leaf (few primitives) becomes the single slot of the root. */
        BvhNode *w = unit_at(&e, 0);
        wide_clear(w);
        wide_set_child(w, 0, widen(root, e.margin), emit_leaf(&e, 0));
    } else {
        collapse(&e, 0, 0);
    }
    assert(e.cursor == units); /* count_wide() counted what collapse() wrote */
    if (!build_curve_segs(bvh, geom->shapes, num_shapes)) goto oom;
    bvh->num_prims = num_ids;
    bvh->bounds = root;
    /* Every node's box lies in the root's widened one (widen() is monotonic). */
    const BBox outer = widen(root, e.margin);
    for (int a = 0; a < 3; a++) bvh->coord_max[a] = maxf(fabsf(v3_get(outer.min, a)), fabsf(v3_get(outer.max, a)));
    bvh->coord_max[3] = 0.0f;
    free(bp);
    free(idx);
    free(owner);
    free(nodes);
    free(choice);
    return CST_OK;
oom:
    free(bp); free(idx); free(owner); free(nodes); free(choice);
    bvh_free(bvh);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the BVH over %d primitives", num_ids);
}

void bvh_free(Bvh *bvh)
{
    if (!bvh) return;
    free(bvh->units);
    free(bvh->spheres);
    free(bvh->shape_ids);
    free(bvh->curve_segs);
    free(bvh->curve_widths);
    memset(bvh, 0, sizeof *bvh);
}

size_t bvh_memory_bytes(const Bvh *bvh)
{
    return bvh_num_units(bvh) * BVH_UNIT + (size_t)bvh->num_spheres * sizeof(BvhSphere) +
           (size_t)bvh->num_shape_ids * sizeof(uint32_t) + (size_t)bvh->num_curve_segs * sizeof(CurveSeg) +
           (size_t)bvh->num_curve_widths * sizeof(CurveWidths);
}
