/* BVH build (binned SAH, parallel over subtrees, collapsed to 8-wide nodes) and traversal
 * (closest hit, occlusion). */
#include "accel/bvh.h"

#include <assert.h>
#include <immintrin.h>
#include <float.h>
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
    BVH_MAX_DEPTH = 60, /* beyond this, split at the median: traversal stacks stay bounded */
    /* The binary tree is at most BVH_MAX_DEPTH + 32 deep (median splits halve), so is the
     * wide one, and each wide level leaves at most 7 siblings on the stack. */
    BVH_STACK = 7 * (BVH_MAX_DEPTH + 33) + 1,
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
    uint32_t num_tris; /* ids below are triangles, the rest spheres */
} Builder;

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
    bool tris = b->idx[bn->offset] < b->num_tris; /* a binary leaf holds one kind */
    float c = leaf_sah(bbox_area(bn->box), bn->count, tris);
    for (int i = 0; i < BVH_WIDTH; i++) {
        out->cost[i] = c;
        b->choice[node][i] = 0;
    }
    out->count = bn->count;
    out->kinds = tris ? 1u : 2u;
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
        (out->kinds == 2u && out->count <= WIDE_LEAF_MAX_SPHERES))
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
            /* A leaf holds one kind of primitive: separate triangles from spheres. */
            int i = begin, j = end - 1;
            while (i <= j) {
                if (b->idx[i] < b->num_tris) i++;
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
    if ((uint32_t)num_spheres > BVH_INDEX_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "the BVH holds at most %u spheres", BVH_INDEX_MAX);
    BuildPrim *bp = aligned_alloc(16, (size_t)n * sizeof *bp);
    uint32_t *idx = malloc((size_t)n * sizeof *idx);
    BinNode *nodes = malloc((size_t)2 * (size_t)n * sizeof *nodes);
    CollapseChoice *choice = malloc((size_t)2 * (size_t)n * sizeof *choice);
    if (!bp || !idx || !nodes || !choice) goto oom;

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
    for (int i = 0; i < n; i++) idx[i] = (uint32_t)i;

    Builder b = {bp, idx, nodes, choice, (uint32_t)num_tris};
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
        free(bp); free(idx); free(nodes); free(choice);
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "the BVH holds at most %u units of 32 bytes (%zu nodes and %zu triangle blocks need more)",
                        BVH_INDEX_MAX, wide, blocks);
    }
    size_t units = wide * NODE_UNITS + blocks * BLOCK_UNITS;
    bvh->units = memory_alloc_large(units * BVH_UNIT);
    bvh->spheres = malloc((size_t)(num_spheres > 0 ? num_spheres : 1) * sizeof *bvh->spheres);
    if (!bvh->units || !bvh->spheres) goto oom;

    BBox root = nodes[0].box;
    Emitter e = {nodes, idx, positions, tri_indices, (uint32_t)num_tris, spheres, 0.0f, choice, bvh, NODE_UNITS};
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
    bvh->num_prims = n;
    bvh->bounds = root;
    /* Every node's box lies in the root's widened one (widen() is monotonic). */
    const BBox outer = widen(root, e.margin);
    for (int a = 0; a < 3; a++) bvh->coord_max[a] = maxf(fabsf(v3_get(outer.min, a)), fabsf(v3_get(outer.max, a)));
    bvh->coord_max[3] = 0.0f;
    free(bp);
    free(idx);
    free(nodes);
    free(choice);
    return CST_OK;
oom:
    free(bp); free(idx); free(nodes); free(choice);
    bvh_free(bvh);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the BVH over %d primitives", n);
}

void bvh_free(Bvh *bvh)
{
    if (!bvh) return;
    free(bvh->units);
    free(bvh->spheres);
    memset(bvh, 0, sizeof *bvh);
}

size_t bvh_memory_bytes(const Bvh *bvh)
{
    return bvh_num_units(bvh) * BVH_UNIT + (size_t)bvh->num_spheres * sizeof(BvhSphere);
}

/* ------------------------------------------------------------------ traversal */

/* Eight floats: one AVX register, or two SSE ones where AVX is missing. */
#if defined(__AVX__)
typedef __m256 F8;
static inline F8 f8_set1(float x) { return _mm256_set1_ps(x); }
static inline F8 f8_load(const float *p) { return _mm256_load_ps(p); }
static inline F8 f8_sub(F8 a, F8 b) { return _mm256_sub_ps(a, b); }
static inline F8 f8_mul(F8 a, F8 b) { return _mm256_mul_ps(a, b); }
static inline unsigned f8_le_mask(F8 a, F8 b) { return (unsigned)_mm256_movemask_ps(_mm256_cmp_ps(a, b, _CMP_LE_OQ)); }
static inline void f8_store(float *p, F8 a) { _mm256_storeu_ps(p, a); }
#if defined(__AVX2__)
/* Max and min of floats by their bit patterns as signed integers (Embree's trick): exact
 * where one operand is non-negative, and otherwise, with both negative, the one nearer
 * zero for min and the farther for max, which can only widen the slab interval. One
 * cycle of latency instead of several on the node test's critical path. */
static inline F8 f8_maxi(F8 a, F8 b)
{
    return _mm256_castsi256_ps(_mm256_max_epi32(_mm256_castps_si256(a), _mm256_castps_si256(b)));
}
static inline F8 f8_mini(F8 a, F8 b)
{
    return _mm256_castsi256_ps(_mm256_min_epi32(_mm256_castps_si256(a), _mm256_castps_si256(b)));
}
#else
static inline F8 f8_maxi(F8 a, F8 b) { return _mm256_max_ps(a, b); }
static inline F8 f8_mini(F8 a, F8 b) { return _mm256_min_ps(a, b); }
#endif
#else
typedef struct F8 {
    __m128 lo, hi;
} F8;
static inline F8 f8_set1(float x) { F8 r = {_mm_set1_ps(x), _mm_set1_ps(x)}; return r; }
static inline F8 f8_load(const float *p) { F8 r = {_mm_load_ps(p), _mm_load_ps(p + 4)}; return r; }
static inline F8 f8_sub(F8 a, F8 b) { F8 r = {_mm_sub_ps(a.lo, b.lo), _mm_sub_ps(a.hi, b.hi)}; return r; }
static inline F8 f8_mul(F8 a, F8 b) { F8 r = {_mm_mul_ps(a.lo, b.lo), _mm_mul_ps(a.hi, b.hi)}; return r; }
static inline F8 f8_min(F8 a, F8 b) { F8 r = {_mm_min_ps(a.lo, b.lo), _mm_min_ps(a.hi, b.hi)}; return r; }
static inline F8 f8_max(F8 a, F8 b) { F8 r = {_mm_max_ps(a.lo, b.lo), _mm_max_ps(a.hi, b.hi)}; return r; }
static inline unsigned f8_le_mask(F8 a, F8 b)
{
    return (unsigned)(_mm_movemask_ps(_mm_cmple_ps(a.lo, b.lo)) | (_mm_movemask_ps(_mm_cmple_ps(a.hi, b.hi)) << 4));
}
static inline void f8_store(float *p, F8 a) { _mm_storeu_ps(p, a.lo); _mm_storeu_ps(p + 4, a.hi); }
static inline F8 f8_maxi(F8 a, F8 b) { return f8_max(a, b); }
static inline F8 f8_mini(F8 a, F8 b) { return f8_min(a, b); }
#endif

/* Per-ray constants of the slab test, and which plane of each axis the ray meets first
 * (the min plane where the direction is non-negative), as byte offsets of that row within
 * a node. The sub-mul form (node_hit8) uses a, b, c = the origin, the negated reciprocal
 * and that times the exit widening; the FMA form (node_hit8_fma) the reciprocal and the
 * origin's product with it moved down and up by a bound on the rounding. */
typedef struct RayBox8 {
    F8 a[3], b[3], c[3];
    size_t near[3], far[3];
} RayBox8;

#define LANE(v, a) _mm_cvtss_f32(_mm_shuffle_ps((v), (v), _MM_SHUFFLE(a, a, a, a)))
#define SET3(dst, v) (dst[0] = f8_set1(LANE(v, 0)), dst[1] = f8_set1(LANE(v, 1)), dst[2] = f8_set1(LANE(v, 2)))

/* By the reciprocal's sign bit (one movemask for the three axes): ray_inv_dir4 keeps a
 * zero component's sign, so a -0 direction enters through the max plane like any other
 * negative one. An axis's two rows are neighbours, 2a and 2a + 1, so the far row's
 * offset is the near one's with the row-size bit flipped. */
static inline void ray_box8_planes(RayBox8 *q, __m128 inv)
{
    const unsigned neg = (unsigned)_mm_movemask_ps(inv);
    for (int a = 0; a < 3; a++) {
        q->near[a] = (2u * (size_t)a + ((neg >> a) & 1u)) * sizeof(float[BVH_WIDTH]);
        q->far[a] = q->near[a] ^ sizeof(float[BVH_WIDTH]);
    }
}

static inline RayBox8 ray_box8(const Ray *r)
{
    const __m128 o = _mm_loadu_ps(&r->o.x), inv = ray_inv_dir4(_mm_loadu_ps(&r->d.x));
    const __m128 ninv = _mm_xor_ps(inv, _mm_set1_ps(-0.0f));
    RayBox8 q;
    SET3(q.a, o);
    SET3(q.b, ninv);
    SET3(q.c, _mm_mul_ps(ninv, _mm_set1_ps(BBOX_EXIT_WIDEN)));
    ray_box8_planes(&q, inv);
    return q;
}

/* Where FMA exists, occlusion rays test a node's planes with one fused multiply-subtract
 * each, plane * r - c with r = 1 / d and c = o * r per ray (Embree's form), instead of a
 * subtraction and a multiplication: occlusion rays 6-14% faster on the dragon, the
 * bumpysphere, the bunny and the Cornell box. Closest-hit traversal measured 2-4% slower
 * with it on the dragon (no cause found), so it keeps the sub-mul form
 * (docs/benchmarks.md). */
#if defined(__AVX__) && defined(__FMA__)
#define BVH_SLAB_FMA 1

/* Sets up q for node_hit8_fma; false, with q unset, where a constant would not be finite
 * (an origin or scene beyond about 1e18 with a direction component near zero).
 *
 * delta = 8u (P + |o|) |r| + 2^-126, u = 2^-24, P the largest |coordinate| of the BVH's
 * boxes on the axis: |plane - o| <= P + |o|, so the exact distance's magnitude, and each
 * of the four rounding errors of plane * r - (c -+ delta) (r's, c's, the sum's and the
 * fma's), stay below u (P + |o|) |r| (1 + O(u)); delta covers their sum twice over, and
 * the 2^-126 the absolute error of results too small to be normal floats. */
static inline bool ray_box8_fma(const Bvh *bvh, const Ray *r, RayBox8 *q)
{
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
    const __m128 o = _mm_loadu_ps(&r->o.x), inv = ray_inv_dir4(_mm_loadu_ps(&r->d.x));
    const __m128 c = _mm_mul_ps(o, inv);
    const __m128 reach = _mm_add_ps(_mm_loadu_ps(bvh->coord_max), _mm_and_ps(o, abs_mask)); /* P + |o| */
    const __m128 delta = _mm_add_ps(_mm_mul_ps(_mm_mul_ps(reach, _mm_and_ps(inv, abs_mask)), _mm_set1_ps(0x1p-21f)),
                                    _mm_set1_ps(0x1p-126f));
    const __m128 c_near = _mm_add_ps(c, delta), c_far = _mm_sub_ps(c, delta);
    const __m128 big = _mm_set1_ps(FLT_MAX);
    const __m128 finite = _mm_and_ps(_mm_cmple_ps(_mm_and_ps(c_near, abs_mask), big),
                                     _mm_cmple_ps(_mm_and_ps(c_far, abs_mask), big));
    if ((_mm_movemask_ps(finite) & 7) != 7) return false;
    SET3(q->a, inv);
    SET3(q->b, c_near);
    SET3(q->c, c_far);
    ray_box8_planes(q, inv);
    return true;
}
#else
#define BVH_SLAB_FMA 0
#endif
#undef SET3
#undef LANE

static inline const float *node_row(const BvhNode *n, size_t offset)
{
    return (const float *)((const char *)n->bounds + offset);
}

/* The min and max are a tree, not a chain, since no NaN has to reach the compare: empty
 * slots hold inverted infinite bounds, entry +inf and exit -inf for every direction, and
 * ray_inv_dir4's finite reciprocals (and ray_box8_fma's finite c) make no 0 * inf and no
 * inf - inf. Returns the mask of children hit and their entry distances. */
static inline unsigned node_mask8(F8 t0x, F8 t1x, F8 t0y, F8 t1y, F8 t0z, F8 t1z, F8 t_min, F8 t_max, F8 *t_enter)
{
    F8 tn = f8_maxi(f8_maxi(t0x, t0y), f8_maxi(t0z, t_min));
    F8 tf = f8_mini(f8_mini(t1x, t1y), f8_mini(t1z, t_max));
    *t_enter = tn;
    return f8_le_mask(tn, tf);
}

/* The eight children's slab tests at once (see bbox_intersect for the robustness
 * argument: zero direction components and the exit widening, BBOX_EXIT_WIDEN). Picking
 * each axis's entry and exit plane by the direction's sign (Williams et al. 2005) gives
 * the same distances as the min and max of both planes' without computing them, for
 * boxes with lo <= hi: the products are monotonic in the plane. (o - plane) * -(1 / d)
 * is bit for bit (plane - o) * (1 / d), and lets the plane be a memory operand of the
 * subtraction. The exit widening w is folded into the per-ray constants, -(1 / d) * w
 * for the exit planes and t_max * w (t_max_widened), which keeps its multiplication off
 * the path from a node's load to its mask; min(a, b) * w = min(a * w, b * w) exactly. */
static inline unsigned node_hit8(const BvhNode *n, const RayBox8 *q, F8 t_min, F8 t_max_widened, F8 *t_enter)
{
    return node_mask8(f8_mul(f8_sub(q->a[0], f8_load(node_row(n, q->near[0]))), q->b[0]),
                      f8_mul(f8_sub(q->a[0], f8_load(node_row(n, q->far[0]))), q->c[0]),
                      f8_mul(f8_sub(q->a[1], f8_load(node_row(n, q->near[1]))), q->b[1]),
                      f8_mul(f8_sub(q->a[1], f8_load(node_row(n, q->far[1]))), q->c[1]),
                      f8_mul(f8_sub(q->a[2], f8_load(node_row(n, q->near[2]))), q->b[2]),
                      f8_mul(f8_sub(q->a[2], f8_load(node_row(n, q->far[2]))), q->c[2]), t_min, t_max_widened,
                      t_enter);
}

#if BVH_SLAB_FMA
/* The same test as plane * r - c. Rounding c = o * r once would make the error absolute,
 * u |o r|, not relative to the distance, and the cancellation near the origin's plane
 * would let it exceed any relative widening. So the whole error is bounded absolutely
 * instead, by delta (ray_box8_fma): entry planes use c + delta and exit planes c - delta,
 * which puts computed entries at or before the exact ones and exits at or after them,
 * with no widening needed (a widened t_max only loosens the test). In space, delta pads
 * each box by 8u (P + |o|) per axis, about 5e-7 of the scene's size plus the origin's
 * distance from zero: the order of the build's own widening of the boxes (widen()). */
static inline unsigned node_hit8_fma(const BvhNode *n, const RayBox8 *q, F8 t_min, F8 t_max, F8 *t_enter)
{
    return node_mask8(_mm256_fmsub_ps(f8_load(node_row(n, q->near[0])), q->a[0], q->b[0]),
                      _mm256_fmsub_ps(f8_load(node_row(n, q->far[0])), q->a[0], q->c[0]),
                      _mm256_fmsub_ps(f8_load(node_row(n, q->near[1])), q->a[1], q->b[1]),
                      _mm256_fmsub_ps(f8_load(node_row(n, q->far[1])), q->a[1], q->c[1]),
                      _mm256_fmsub_ps(f8_load(node_row(n, q->near[2])), q->a[2], q->b[2]),
                      _mm256_fmsub_ps(f8_load(node_row(n, q->far[2])), q->a[2], q->c[2]), t_min, t_max, t_enter);
}
#endif

static inline bool leaf_spheres(const Bvh *bvh, uint32_t ref, Ray *r, Hit *hit)
{
    bool found = false;
    const BvhSphere *sp = &bvh->spheres[bvh_ref_index(ref)];
    for (uint32_t si = bvh_ref_count(ref); si > 0; si--, sp++) {
        float t;
        if (sphere_intersect(sp->center, sp->radius, r, &t)) {
            r->t_max = t;
            hit->t = t; hit->u = 0.0f; hit->v = 0.0f; hit->prim = sp->id;
            found = true;
        }
    }
    return found;
}

static inline bool leaf_occluded(const Bvh *bvh, uint32_t ref, const TriangleRayBlock *q, const Ray *r)
{
    if (ref & BVH_SPHERES) {
        const BvhSphere *sp = &bvh->spheres[bvh_ref_index(ref)];
        for (uint32_t si = bvh_ref_count(ref); si > 0; si--, sp++) {
            float t;
            if (sphere_intersect(sp->center, sp->radius, r, &t)) return true;
        }
        return false;
    }
    return triangle_blocks_occluded(bvh_blocks(bvh, bvh_ref_index(ref)), bvh_ref_count(ref), q, r);
}

static inline unsigned ctz(unsigned m) { return (unsigned)__builtin_ctz(m); }

/* Starts loading the first four lines of whatever `ref` names, without a branch on its
 * kind: issued before the branches on how many children were hit, so a mispredicted one
 * overlaps the load instead of delaying it (Embree prefetches the chosen child the same
 * way). For a sphere leaf the address is meaningless, which a prefetch tolerates. */
static inline void prefetch_next(const Bvh *bvh, uint32_t ref)
{
    const char *p = (const char *)bvh->units + (ref & ~(uint32_t)(BVH_UNIT - 1u));
    _mm_prefetch(p, _MM_HINT_T0);
    _mm_prefetch(p + 64, _MM_HINT_T0);
    _mm_prefetch(p + 128, _MM_HINT_T0);
    _mm_prefetch(p + 192, _MM_HINT_T0);
}

/* A NaN or infinite origin or direction would make every slab test pass, empty slots
 * included; such a ray hits nothing. */
static inline bool ray_is_finite(const Ray *r)
{
    /* Ray is {o, t_min, d, t_max}: two loads, one compare each, lanes 0-2. */
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)), big = _mm_set1_ps(FLT_MAX);
    __m128 o = _mm_and_ps(_mm_loadu_ps(&r->o.x), abs_mask), d = _mm_and_ps(_mm_loadu_ps(&r->d.x), abs_mask);
    return (_mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(o, big), _mm_cmple_ps(d, big))) & 7) == 7;
}

/* Starts loading a child that will be visited later, so the visit of its nearer sibling
 * overlaps the memory latency (Embree's traversal does the same). Exactly its lines, by
 * kind: using prefetch_next here instead measured 7% slower on the dragon's primary rays
 * (docs/benchmarks.md). */
static inline void prefetch_ref(const Bvh *bvh, uint32_t ref)
{
    const char *p;
    size_t bytes;
    if (!bvh_ref_is_leaf(ref)) {
        p = (const char *)bvh_node(bvh, ref);
        bytes = sizeof(BvhNode);
    } else if (ref & BVH_SPHERES) {
        p = (const char *)&bvh->spheres[bvh_ref_index(ref)];
        bytes = bvh_ref_count(ref) * sizeof(BvhSphere);
    } else {
        p = (const char *)bvh_blocks(bvh, bvh_ref_index(ref));
        bytes = bvh_ref_count(ref) * sizeof(TriangleBlock);
    }
#ifndef BVH_NO_PREFETCH
    for (size_t off = 0; off < bytes; off += 64) _mm_prefetch(p + off, _MM_HINT_T0);
#else
    (void)p; (void)bytes;
#endif
}

bool bvh_intersect(const Bvh *bvh, const Ray *ray, Hit *hit)
{
    if (bvh->num_nodes == 0 || !ray_is_finite(ray)) return false;
    Ray r = *ray;
    RayBox8 q = ray_box8(&r);
    TriangleRayBlock qt; /* set up at the first leaf: many rays never reach one */
    bool qt_ready = false;
    const F8 t_min = f8_set1(r.t_min);
    uint32_t stack_ref[BVH_STACK];
    float stack_t[BVH_STACK];
    int sp = 0;
    uint32_t cur = 0; /* the root */
    bool found = false;
    F8 t_max_widened = f8_set1(r.t_max * BBOX_EXIT_WIDEN);
    for (;;) {
        if (!bvh_ref_is_leaf(cur)) {
            const BvhNode *n = bvh_node(bvh, cur);
            F8 tn8;
            unsigned mask = node_hit8(n, &q, t_min, t_max_widened, &tn8);
            if (mask) {
                unsigned c0 = ctz(mask);
                prefetch_next(bvh, n->child[c0]);
                mask &= mask - 1u;
                if (!mask) { cur = n->child[c0]; continue; } /* the common case: one child */
                float tn[BVH_WIDTH];
                f8_store(tn, tn8);
                unsigned c1 = ctz(mask);
                mask &= mask - 1u;
                if (!mask) {
                    /* Two: descend into the nearer, keep the farther with its entry
                     * distance so a closer hit found first lets it be skipped. */
                    if (tn[c1] < tn[c0]) { unsigned t = c0; c0 = c1; c1 = t; }
                    prefetch_ref(bvh, n->child[c1]);
                    stack_ref[sp] = n->child[c1];
                    stack_t[sp++] = tn[c1];
                    cur = n->child[c0];
                    continue;
                }
                /* Three or more: push all, sorted far to near, and pop the nearest. */
                int base = sp;
                stack_ref[sp] = n->child[c0]; stack_t[sp++] = tn[c0];
                mask |= 1u << c1;
                while (mask) {
                    unsigned c = ctz(mask);
                    mask &= mask - 1u;
                    prefetch_ref(bvh, n->child[c]);
                    float t = tn[c];
                    int j = sp++;
                    while (j > base && stack_t[j - 1] < t) {
                        stack_ref[j] = stack_ref[j - 1];
                        stack_t[j] = stack_t[j - 1];
                        j--;
                    }
                    stack_ref[j] = n->child[c];
                    stack_t[j] = t;
                }
                cur = stack_ref[--sp];
                continue;
            }
        } else {
            if (cur & BVH_SPHERES) {
                found |= leaf_spheres(bvh, cur, &r, hit);
            } else {
                if (!qt_ready) { qt = triangle_block_ray_setup(&r); qt_ready = true; }
                found |= triangle_blocks_intersect(bvh_blocks(bvh, bvh_ref_index(cur)), bvh_ref_count(cur), &qt, &r,
                                                   hit);
            }
            t_max_widened = f8_set1(r.t_max * BBOX_EXIT_WIDEN);
        }
        /* Next: the nearest pending entry not beyond the closest hit so far. */
        do {
            if (sp == 0) return found;
            sp--;
        } while (stack_t[sp] > r.t_max);
        cur = stack_ref[sp];
    }
}

#if defined(__AVX2__) && !defined(__AVX512VL__)
/* For each 8-bit mask, the indices of its set bits in increasing order, three bits each:
 * the lane permutation that packs the selected lanes to the front (a left-pack). */
static const uint32_t LEFT_PACK[256] = {
    0x000000, 0x000000, 0x000001, 0x000008, 0x000002, 0x000010, 0x000011, 0x000088,
    0x000003, 0x000018, 0x000019, 0x0000c8, 0x00001a, 0x0000d0, 0x0000d1, 0x000688,
    0x000004, 0x000020, 0x000021, 0x000108, 0x000022, 0x000110, 0x000111, 0x000888,
    0x000023, 0x000118, 0x000119, 0x0008c8, 0x00011a, 0x0008d0, 0x0008d1, 0x004688,
    0x000005, 0x000028, 0x000029, 0x000148, 0x00002a, 0x000150, 0x000151, 0x000a88,
    0x00002b, 0x000158, 0x000159, 0x000ac8, 0x00015a, 0x000ad0, 0x000ad1, 0x005688,
    0x00002c, 0x000160, 0x000161, 0x000b08, 0x000162, 0x000b10, 0x000b11, 0x005888,
    0x000163, 0x000b18, 0x000b19, 0x0058c8, 0x000b1a, 0x0058d0, 0x0058d1, 0x02c688,
    0x000006, 0x000030, 0x000031, 0x000188, 0x000032, 0x000190, 0x000191, 0x000c88,
    0x000033, 0x000198, 0x000199, 0x000cc8, 0x00019a, 0x000cd0, 0x000cd1, 0x006688,
    0x000034, 0x0001a0, 0x0001a1, 0x000d08, 0x0001a2, 0x000d10, 0x000d11, 0x006888,
    0x0001a3, 0x000d18, 0x000d19, 0x0068c8, 0x000d1a, 0x0068d0, 0x0068d1, 0x034688,
    0x000035, 0x0001a8, 0x0001a9, 0x000d48, 0x0001aa, 0x000d50, 0x000d51, 0x006a88,
    0x0001ab, 0x000d58, 0x000d59, 0x006ac8, 0x000d5a, 0x006ad0, 0x006ad1, 0x035688,
    0x0001ac, 0x000d60, 0x000d61, 0x006b08, 0x000d62, 0x006b10, 0x006b11, 0x035888,
    0x000d63, 0x006b18, 0x006b19, 0x0358c8, 0x006b1a, 0x0358d0, 0x0358d1, 0x1ac688,
    0x000007, 0x000038, 0x000039, 0x0001c8, 0x00003a, 0x0001d0, 0x0001d1, 0x000e88,
    0x00003b, 0x0001d8, 0x0001d9, 0x000ec8, 0x0001da, 0x000ed0, 0x000ed1, 0x007688,
    0x00003c, 0x0001e0, 0x0001e1, 0x000f08, 0x0001e2, 0x000f10, 0x000f11, 0x007888,
    0x0001e3, 0x000f18, 0x000f19, 0x0078c8, 0x000f1a, 0x0078d0, 0x0078d1, 0x03c688,
    0x00003d, 0x0001e8, 0x0001e9, 0x000f48, 0x0001ea, 0x000f50, 0x000f51, 0x007a88,
    0x0001eb, 0x000f58, 0x000f59, 0x007ac8, 0x000f5a, 0x007ad0, 0x007ad1, 0x03d688,
    0x0001ec, 0x000f60, 0x000f61, 0x007b08, 0x000f62, 0x007b10, 0x007b11, 0x03d888,
    0x000f63, 0x007b18, 0x007b19, 0x03d8c8, 0x007b1a, 0x03d8d0, 0x03d8d1, 0x1ec688,
    0x00003e, 0x0001f0, 0x0001f1, 0x000f88, 0x0001f2, 0x000f90, 0x000f91, 0x007c88,
    0x0001f3, 0x000f98, 0x000f99, 0x007cc8, 0x000f9a, 0x007cd0, 0x007cd1, 0x03e688,
    0x0001f4, 0x000fa0, 0x000fa1, 0x007d08, 0x000fa2, 0x007d10, 0x007d11, 0x03e888,
    0x000fa3, 0x007d18, 0x007d19, 0x03e8c8, 0x007d1a, 0x03e8d0, 0x03e8d1, 0x1f4688,
    0x0001f5, 0x000fa8, 0x000fa9, 0x007d48, 0x000faa, 0x007d50, 0x007d51, 0x03ea88,
    0x000fab, 0x007d58, 0x007d59, 0x03eac8, 0x007d5a, 0x03ead0, 0x03ead1, 0x1f5688,
    0x000fac, 0x007d60, 0x007d61, 0x03eb08, 0x007d62, 0x03eb10, 0x03eb11, 0x1f5888,
    0x007d63, 0x03eb18, 0x03eb19, 0x1f58c8, 0x03eb1a, 0x1f58d0, 0x1f58d1, 0xfac688,
};
#endif

/* Written once and inlined twice, for the FMA and the sub-mul forms of the node test, so
 * the choice costs one branch per ray, not one per node. */
static inline __attribute__((always_inline)) bool occluded_ray(const Bvh *bvh, const Ray *ray, const RayBox8 *q,
                                                               const bool fma)
{
    TriangleRayBlock qt;
    bool qt_ready = false;
    const F8 t_min = f8_set1(ray->t_min), t_max = f8_set1(ray->t_max * BBOX_EXIT_WIDEN);
    uint32_t stack[BVH_STACK + BVH_WIDTH]; /* room for a whole vector store at the top */
    int sp = 0;
    uint32_t cur = 0;
    for (;;) {
        if (!bvh_ref_is_leaf(cur)) {
            const BvhNode *n = bvh_node(bvh, cur);
            F8 tn8;
#if BVH_SLAB_FMA
            unsigned mask = fma ? node_hit8_fma(n, q, t_min, t_max, &tn8) : node_hit8(n, q, t_min, t_max, &tn8);
#else
            (void)fma;
            unsigned mask = node_hit8(n, q, t_min, t_max, &tn8);
#endif
            if (mask) {
                /* Any order finds an occluder; descend into the first, keep the rest. */
                cur = n->child[ctz(mask)];
                prefetch_next(bvh, cur);
                mask &= mask - 1u;
#if defined(__AVX512VL__)
                /* The others in slot order by one compress and one store (the stack has
                 * room for all eight), not a loop whose trip count the branch predictor
                 * misses: dragon occlusion rays 3.77 -> 3.95 Mrays/s (docs/benchmarks.md). */
                const __m256i kids = _mm256_load_si256((const __m256i *)(const void *)n->child);
                _mm256_storeu_si256((__m256i *)(void *)&stack[sp], _mm256_maskz_compress_epi32((__mmask8)mask, kids));
                sp += __builtin_popcount(mask);
#elif defined(__AVX2__)
                /* Without AVX-512's compress: the same single store, the lanes gathered by
                 * one permutation looked up by the mask. */
                const __m256i kids = _mm256_load_si256((const __m256i *)(const void *)n->child);
                const __m256i lanes = _mm256_and_si256(
                    _mm256_srlv_epi32(_mm256_set1_epi32((int)LEFT_PACK[mask]), _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21)),
                    _mm256_set1_epi32(7));
                _mm256_storeu_si256((__m256i *)(void *)&stack[sp], _mm256_permutevar8x32_epi32(kids, lanes));
                sp += __builtin_popcount(mask);
#else
                while (mask) {
                    prefetch_ref(bvh, n->child[ctz(mask)]);
                    stack[sp++] = n->child[ctz(mask)];
                    mask &= mask - 1u;
                }
#endif
                continue;
            }
        } else {
            if (!qt_ready && !(cur & BVH_SPHERES)) { qt = triangle_block_ray_setup(ray); qt_ready = true; }
            if (leaf_occluded(bvh, cur, &qt, ray)) return true;
        }
        if (sp == 0) return false;
        cur = stack[--sp];
    }
}

bool bvh_occluded(const Bvh *bvh, const Ray *ray)
{
    if (bvh->num_nodes == 0 || !ray_is_finite(ray)) return false;
    RayBox8 q;
#if BVH_SLAB_FMA
    if (ray_box8_fma(bvh, ray, &q)) return occluded_ray(bvh, ray, &q, true);
#endif
    q = ray_box8(ray);
    return occluded_ray(bvh, ray, &q, false);
}

bool bvh_node_test(const Bvh *bvh, const BvhNode *n, const Ray *r, bool fma, unsigned *mask)
{
    F8 tn;
    const F8 t_min = f8_set1(r->t_min), t_max = f8_set1(r->t_max * BBOX_EXIT_WIDEN);
    if (fma) {
#if BVH_SLAB_FMA
        RayBox8 q;
        if (!ray_box8_fma(bvh, r, &q)) return false;
        *mask = node_hit8_fma(n, &q, t_min, t_max, &tn);
        return true;
#else
        (void)bvh;
        return false;
#endif
    }
    RayBox8 q = ray_box8(r);
    *mask = node_hit8(n, &q, t_min, t_max, &tn);
    return true;
}
