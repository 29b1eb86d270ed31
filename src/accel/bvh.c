/* BVH traversal: closest hit and occlusion over the 8-wide tree bvh_build.c makes. */
#include "accel/bvh.h"

#include <immintrin.h>
#include <float.h>
#include <math.h>

#include "geometry/sphere.h"

enum {
    /* The binary tree is at most BVH_MAX_DEPTH + 32 deep (median splits halve), so is the
     * wide one, and each wide level leaves at most 7 siblings on the stack. */
    BVH_STACK = 7 * (BVH_MAX_DEPTH + 33) + 1
};

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

/* The shape in slot j of shape_ids: a curve's test on its compact record when it has one
 * (bvh.h), which neither shape_ids nor the 384-byte AnalyticShape is read for; the same
 * t, u, v either way. */
static inline bool shape_hit(const Bvh *bvh, uint32_t j, const Ray *r, float *t, float *u, float *v)
{
    if (bvh->curve_segs && bvh->curve_segs[j].info != BVH_NO_CURVE_SEG)
        return curve_seg_intersect(&bvh->curve_segs[j], bvh->curve_widths, r, t, u, v);
    return shape_intersect(&bvh->shapes[bvh->shape_ids[j] - bvh->shape_base], r, t, u, v);
}

/* shape_leaf_intersect and _occluded through shape_hit: closest hit, ties keep the first.
 * A leaf's records are consecutive lines, all requested first so their misses overlap. */
static inline void shape_leaf_prefetch(const Bvh *bvh, uint32_t first, uint32_t count)
{
    if (!bvh->curve_segs || count < 2) return;
    for (uint32_t i = 0; i < count; i++) _mm_prefetch((const char *)&bvh->curve_segs[first + i], _MM_HINT_T0);
}
static inline bool shape_leaf_hit(const Bvh *bvh, uint32_t ref, Ray *r, Hit *hit)
{
    const uint32_t first = bvh_ref_index(ref) & BVH_SHAPE_INDEX_MAX, count = bvh_ref_count(ref);
    shape_leaf_prefetch(bvh, first, count);
    bool found = false;
    for (uint32_t j = first; j < first + count; j++) {
        float t, u, v;
        if (shape_hit(bvh, j, r, &t, &u, &v)) {
            r->t_max = t;
            hit->t = t; hit->u = u; hit->v = v; hit->prim = bvh->shape_ids[j];
            found = true;
        }
    }
    return found;
}
static inline bool shape_leaf_any(const Bvh *bvh, uint32_t ref, const Ray *r)
{
    const uint32_t first = bvh_ref_index(ref) & BVH_SHAPE_INDEX_MAX, count = bvh_ref_count(ref);
    shape_leaf_prefetch(bvh, first, count);
    for (uint32_t j = first; j < first + count; j++) {
        float t, u, v;
        if (shape_hit(bvh, j, r, &t, &u, &v)) return true;
    }
    return false;
}

static inline bool leaf_spheres(const Bvh *bvh, uint32_t ref, Ray *r, Hit *hit)
{
    if (ref & BVH_SHAPES) return shape_leaf_hit(bvh, ref, r, hit);
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
    if (ref & BVH_SPHERES) { /* triangle leaves test nothing more than before shapes came */
        if (ref & BVH_SHAPES) return shape_leaf_any(bvh, ref, r);
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
