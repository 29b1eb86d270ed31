/* triangle_intersect_watertight() on a block of TRI_BLOCK_WIDTH triangles at once (eight
 * with AVX, four with SSE): the leaves of the BVH and of the kd-tree store their triangles
 * in such blocks, v[vertex][axis][lane], unused lanes NaN, and the grid gathers its cells'
 * triangles into one. */
#ifndef CST_GEOMETRY_TRIANGLE_BLOCK_H
#define CST_GEOMETRY_TRIANGLE_BLOCK_H

#include <immintrin.h>
#include <math.h>

#include <stdbool.h>
#include <stdint.h>

#include "geometry/hit.h"
#include "geometry/ray.h"
#include "geometry/triangle.h"

/* Triangles per block: one AVX or SSE register of floats. */
#ifdef __AVX__
#define TRI_BLOCK_WIDTH 8
#else
#define TRI_BLOCK_WIDTH 4
#endif

/* TRI_BLOCK_WIDTH triangles in SoA form, v[vertex][axis][lane]; indexing by axis lets the
 * per-ray axis permutation pick rows. Unused lanes have NaN vertices, which fail every
 * comparison of the test, and id TRI_BLOCK_NO_PRIM. 320 bytes with AVX, 160 without. */
typedef struct TriangleBlock {
    float v[3][3][TRI_BLOCK_WIDTH];
    uint32_t id[TRI_BLOCK_WIDTH]; /* scene primitive ids */
} TriangleBlock;
#define TRI_BLOCK_NO_PRIM 0xffffffffu

/* The lanes of a block test: TRI_BLOCK_WIDTH floats, AVX or SSE. Comparisons are the
 * ordered ones of the scalar test (false on NaN), except neq, true on NaN as in C; max is
 * maxf's a > b ? a : b and abs fabsf's sign-bit clear. */
#ifdef __AVX__
typedef __m256 TriLanes;
static inline TriLanes lanes_load(const float *p) { return _mm256_loadu_ps(p); }
static inline void lanes_store(float *p, TriLanes a) { _mm256_storeu_ps(p, a); }
static inline TriLanes lanes_set1(float x) { return _mm256_set1_ps(x); }
static inline TriLanes lanes_zero(void) { return _mm256_setzero_ps(); }
static inline TriLanes lanes_add(TriLanes a, TriLanes b) { return _mm256_add_ps(a, b); }
static inline TriLanes lanes_sub(TriLanes a, TriLanes b) { return _mm256_sub_ps(a, b); }
static inline TriLanes lanes_mul(TriLanes a, TriLanes b) { return _mm256_mul_ps(a, b); }
static inline TriLanes lanes_div(TriLanes a, TriLanes b) { return _mm256_div_ps(a, b); }
static inline TriLanes lanes_and(TriLanes a, TriLanes b) { return _mm256_and_ps(a, b); }
static inline TriLanes lanes_or(TriLanes a, TriLanes b) { return _mm256_or_ps(a, b); }
static inline TriLanes lanes_xor(TriLanes a, TriLanes b) { return _mm256_xor_ps(a, b); }
static inline TriLanes lanes_ge(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_GE_OQ); }
static inline TriLanes lanes_max(TriLanes a, TriLanes b) { return _mm256_max_ps(a, b); } /* a > b ? a : b */
static inline TriLanes lanes_abs(TriLanes a)
{
    return _mm256_and_ps(a, _mm256_castsi256_ps(_mm256_set1_epi32(0x7fffffff)));
}
static inline TriLanes lanes_lt(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_LT_OQ); }
static inline TriLanes lanes_gt(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_GT_OQ); }
static inline TriLanes lanes_eq(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_EQ_OQ); }
static inline TriLanes lanes_neq(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_NEQ_UQ); }
static inline TriLanes lanes_ord(TriLanes a, TriLanes b) { return _mm256_cmp_ps(a, b, _CMP_ORD_Q); }
static inline int lanes_mask(TriLanes a) { return _mm256_movemask_ps(a); }
#else
typedef __m128 TriLanes;
static inline TriLanes lanes_load(const float *p) { return _mm_loadu_ps(p); }
static inline void lanes_store(float *p, TriLanes a) { _mm_storeu_ps(p, a); }
static inline TriLanes lanes_set1(float x) { return _mm_set1_ps(x); }
static inline TriLanes lanes_zero(void) { return _mm_setzero_ps(); }
static inline TriLanes lanes_add(TriLanes a, TriLanes b) { return _mm_add_ps(a, b); }
static inline TriLanes lanes_sub(TriLanes a, TriLanes b) { return _mm_sub_ps(a, b); }
static inline TriLanes lanes_mul(TriLanes a, TriLanes b) { return _mm_mul_ps(a, b); }
static inline TriLanes lanes_div(TriLanes a, TriLanes b) { return _mm_div_ps(a, b); }
static inline TriLanes lanes_and(TriLanes a, TriLanes b) { return _mm_and_ps(a, b); }
static inline TriLanes lanes_or(TriLanes a, TriLanes b) { return _mm_or_ps(a, b); }
static inline TriLanes lanes_xor(TriLanes a, TriLanes b) { return _mm_xor_ps(a, b); }
static inline TriLanes lanes_ge(TriLanes a, TriLanes b) { return _mm_cmpge_ps(a, b); }
static inline TriLanes lanes_max(TriLanes a, TriLanes b) { return _mm_max_ps(a, b); } /* a > b ? a : b */
static inline TriLanes lanes_abs(TriLanes a) { return _mm_and_ps(a, _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff))); }
static inline TriLanes lanes_lt(TriLanes a, TriLanes b) { return _mm_cmplt_ps(a, b); }
static inline TriLanes lanes_gt(TriLanes a, TriLanes b) { return _mm_cmpgt_ps(a, b); }
static inline TriLanes lanes_eq(TriLanes a, TriLanes b) { return _mm_cmpeq_ps(a, b); }
static inline TriLanes lanes_neq(TriLanes a, TriLanes b) { return _mm_cmpneq_ps(a, b); }
static inline TriLanes lanes_ord(TriLanes a, TriLanes b) { return _mm_cmpord_ps(a, b); }
static inline int lanes_mask(TriLanes a) { return _mm_movemask_ps(a); }
#endif

/* Per-ray constants of the block test. */
typedef struct TriangleRayBlock {
    TriangleRay tr;
    TriLanes o[3]; /* origin, per world axis */
    TriLanes sx, sy, sz;
} TriangleRayBlock;

static inline TriangleRayBlock triangle_block_ray_setup(const Ray *r)
{
    TriangleRayBlock q;
    q.tr = triangle_ray_setup(r->d);
    q.o[0] = lanes_set1(r->o.x); q.o[1] = lanes_set1(r->o.y); q.o[2] = lanes_set1(r->o.z);
    q.sx = lanes_set1(q.tr.sx); q.sy = lanes_set1(q.tr.sy); q.sz = lanes_set1(q.tr.sz);
    return q;
}

static inline Vec3 triangle_block_vertex(const float v[3][3][TRI_BLOCK_WIDTH], int k, int lane)
{
    return v3(v[k][0][lane], v[k][1][lane], v[k][2][lane]);
}

/* triangle_intersect_watertight() on a block's triangles at once, with the same operations
 * in the same order (the build has -ffp-contract=off, so nothing is fused into FMAs), so
 * each lane's t, u, v are bit-identical to the scalar test's, and so is its rejection of t
 * within triangle_t_error(). Lanes with an edge function of exactly zero need the scalar's
 * recomputation in double: they come back in *scalar_lanes, for the caller to run through
 * the scalar test. Returns the mask of the other lanes that hit within (t_min, t_max). */
static inline int triangle_block_intersect(const float v[3][3][TRI_BLOCK_WIDTH], const TriangleRayBlock *q,
                                           TriLanes t_min, TriLanes t_max, TriLanes *t_out, TriLanes *u_out,
                                           TriLanes *v_out, int *scalar_lanes)
{
    const int kx = q->tr.kx, ky = q->tr.ky, kz = q->tr.kz;
    TriLanes px[3], py[3], pz[3];
    for (int k = 0; k < 3; k++) {
        pz[k] = lanes_sub(lanes_load(v[k][kz]), q->o[kz]);
        px[k] = lanes_sub(lanes_sub(lanes_load(v[k][kx]), q->o[kx]), lanes_mul(q->sx, pz[k]));
        py[k] = lanes_sub(lanes_sub(lanes_load(v[k][ky]), q->o[ky]), lanes_mul(q->sy, pz[k]));
    }
    /* U, V, W: the edge functions, scaled barycentrics of vertices 0, 1, 2 (JCGT 2013 eq. 4) */
    TriLanes U = lanes_sub(lanes_mul(px[2], py[1]), lanes_mul(py[2], px[1]));
    TriLanes V = lanes_sub(lanes_mul(px[0], py[2]), lanes_mul(py[0], px[2]));
    TriLanes W = lanes_sub(lanes_mul(px[1], py[0]), lanes_mul(py[1], px[0]));
    const TriLanes zero = lanes_zero();
    int zero_lanes = lanes_mask(lanes_or(lanes_or(lanes_eq(U, zero), lanes_eq(V, zero)), lanes_eq(W, zero)));
    *scalar_lanes = zero_lanes;
    /* With no zero among U, V, W, "some negative and some positive" is "some sign bit
     * differs from U's": two xors and an or instead of six compares. Most rays pass
     * outside every triangle of a block: stop before the division. Unused lanes are NaN,
     * whose sign bits mean nothing, so they are dropped explicitly. */
    TriLanes mixed = lanes_or(lanes_xor(U, V), lanes_xor(U, W));
    int inside = ~lanes_mask(mixed) & lanes_mask(lanes_ord(U, U)) & ~zero_lanes;
    if (!inside) {
        *t_out = *u_out = *v_out = zero;
        return 0;
    }
    TriLanes det = lanes_add(lanes_add(U, V), W);
    TriLanes zt[3];
    for (int k = 0; k < 3; k++) zt[k] = lanes_mul(q->sz, pz[k]);
    TriLanes T = lanes_add(lanes_add(lanes_mul(U, zt[0]), lanes_mul(V, zt[1])), lanes_mul(W, zt[2]));
    /* t = T / det is positive only where T and det have the same sign: a ray leaving a
     * surface is "inside" the triangle it starts on (and often a neighbour), behind its
     * origin. With t_min >= 0 such lanes cannot hit, so when no other lane is left the
     * division and the error bound are skipped (Woop et al. 2013 test the sign before
     * dividing too); the result is the full test's, bit for bit. */
    if (!(inside & ~lanes_mask(lanes_xor(T, det))) && (lanes_mask(lanes_ge(t_min, zero)) & 1)) {
        *t_out = *u_out = *v_out = zero;
        return 0;
    }
    TriLanes inv_det = lanes_div(lanes_set1(1.0f), det);
    TriLanes t = lanes_mul(T, inv_det);
    TriLanes ok = lanes_neq(det, zero);
    ok = lanes_and(ok, lanes_gt(t, t_min));
    ok = lanes_and(ok, lanes_lt(t, t_max));
    /* triangle_t_error(), lane by lane. */
    TriLanes max_zt = lanes_max(lanes_max(lanes_abs(zt[0]), lanes_abs(zt[1])), lanes_abs(zt[2]));
    TriLanes max_xt = lanes_max(lanes_max(lanes_abs(px[0]), lanes_abs(px[1])), lanes_abs(px[2]));
    TriLanes max_yt = lanes_max(lanes_max(lanes_abs(py[0]), lanes_abs(py[1])), lanes_abs(py[2]));
    const TriLanes g2 = lanes_set1(TRIANGLE_GAMMA(2)), g3 = lanes_set1(TRIANGLE_GAMMA(3)),
                  g5 = lanes_set1(TRIANGLE_GAMMA(5));
    TriLanes delta_z = lanes_mul(g3, max_zt);
    TriLanes delta_x = lanes_mul(g5, lanes_add(max_xt, max_zt));
    TriLanes delta_y = lanes_mul(g5, lanes_add(max_yt, max_zt));
    TriLanes delta_e = lanes_mul(lanes_set1(2.0f), lanes_add(lanes_add(lanes_mul(lanes_mul(g2, max_xt), max_yt),
                                                                       lanes_mul(delta_y, max_xt)),
                                                             lanes_mul(delta_x, max_yt)));
    TriLanes max_e = lanes_max(lanes_max(lanes_abs(U), lanes_abs(V)), lanes_abs(W));
    TriLanes sum_t = lanes_add(lanes_add(lanes_mul(lanes_mul(g3, max_e), max_zt), lanes_mul(delta_e, max_zt)),
                               lanes_mul(delta_z, max_e));
    TriLanes delta_t = lanes_mul(lanes_mul(lanes_set1(3.0f), sum_t), lanes_abs(inv_det));
    ok = lanes_and(ok, lanes_gt(t, delta_t));
    *t_out = t;
    *u_out = lanes_mul(V, inv_det);
    *v_out = lanes_mul(W, inv_det);
    return lanes_mask(ok) & inside;
}

/* The closest hit among n consecutive blocks; shortens r->t_max on a hit. Lanes are taken
 * in order with a strict <, as a scalar loop over the blocks' triangles would pick among
 * equal t; only the lanes hit or left to the scalar test are visited. */
static inline bool triangle_blocks_intersect(const TriangleBlock *b, uint32_t n, const TriangleRayBlock *q, Ray *r,
                                             Hit *hit)
{
    bool found = false;
    const TriLanes t_min = lanes_set1(r->t_min);
    for (; n > 0; n--, b++) {
        TriLanes tl, ul, vl;
        int scalar_lanes;
        int mask = triangle_block_intersect(b->v, q, t_min, lanes_set1(r->t_max), &tl, &ul, &vl, &scalar_lanes);
        if (!(mask | scalar_lanes)) continue;
        float t[TRI_BLOCK_WIDTH], u[TRI_BLOCK_WIDTH], v[TRI_BLOCK_WIDTH];
        lanes_store(t, tl); lanes_store(u, ul); lanes_store(v, vl);
        for (unsigned lanes = (unsigned)(mask | scalar_lanes); lanes; lanes &= lanes - 1u) {
            const int i = __builtin_ctz(lanes);
            if (scalar_lanes & (1 << i)) {
                float ts, us, vs;
                if (triangle_intersect_watertight(&q->tr, r, triangle_block_vertex(b->v, 0, i),
                                                  triangle_block_vertex(b->v, 1, i), triangle_block_vertex(b->v, 2, i),
                                                  &ts, &us, &vs)) {
                    r->t_max = ts;
                    hit->t = ts; hit->u = us; hit->v = vs; hit->prim = b->id[i];
                    found = true;
                }
            } else if (t[i] < r->t_max) {
                r->t_max = t[i];
                hit->t = t[i]; hit->u = u[i]; hit->v = v[i]; hit->prim = b->id[i];
                found = true;
            }
        }
    }
    return found;
}

/* Whether any triangle of n consecutive blocks is hit within (r->t_min, r->t_max). */
static inline bool triangle_blocks_occluded(const TriangleBlock *b, uint32_t n, const TriangleRayBlock *q, const Ray *r)
{
    const TriLanes t_min = lanes_set1(r->t_min), t_max = lanes_set1(r->t_max);
    for (; n > 0; n--, b++) {
        TriLanes tl, ul, vl;
        int scalar_lanes;
        if (triangle_block_intersect(b->v, q, t_min, t_max, &tl, &ul, &vl, &scalar_lanes)) return true;
        for (unsigned lanes = (unsigned)scalar_lanes; lanes; lanes &= lanes - 1u) {
            const int i = __builtin_ctz(lanes);
            float ts, us, vs;
            if (triangle_intersect_watertight(&q->tr, r, triangle_block_vertex(b->v, 0, i),
                                              triangle_block_vertex(b->v, 1, i), triangle_block_vertex(b->v, 2, i), &ts,
                                              &us, &vs))
                return true;
        }
    }
    return false;
}

/* A triangle's own vertices and scene primitive id, as the grid and the octree keep them
 * (the floats the list back end tests, so hits are bit-identical); gathered by pointer
 * into a batch for tri_batch_intersect(). */
typedef struct TriVerts {
    Vec3 v0, v1, v2;
    uint32_t id;
} TriVerts;

/* Fills the unused lanes of a batch: NaN vertices fail every comparison of the test. */
static const TriVerts TRI_VERTS_NAN = {{NAN, NAN, NAN}, {NAN, NAN, NAN}, {NAN, NAN, NAN}, 0u};

/* triangle_block_intersect() on up to TRI_BLOCK_WIDTH triangles gathered from a grid cell's or an
 * octree leaf's list: they
 * are gathered four at a time and transposed in registers (a vertex is 12 bytes, so each
 * load takes the three coordinates and one float of whatever follows inside the TriVerts);
 * groups of four past the n triangles collected are NaN, which fails every comparison.
 * Lanes with an edge function of exactly zero need the scalar's recomputation in double:
 * they come back in *scalar_lanes for the caller to run through the scalar test. Returns
 * the mask of the other lanes that hit within (t_min, t_max). */
static inline int tri_batch_intersect(const TriVerts *const tri[TRI_BLOCK_WIDTH], int n, const TriangleRayBlock *q,
                                      TriLanes t_min, TriLanes t_max, TriLanes *t_out, TriLanes *u_out,
                                      TriLanes *v_out, int *scalar_lanes)
{
    _Alignas(32) float vtx[3][3][TRI_BLOCK_WIDTH]; /* [vertex][axis][lane] */
    for (int g = 0; g < TRI_BLOCK_WIDTH; g += 4) {
        if (g >= n) {
            const __m128 nan = _mm_set1_ps(NAN);
            for (int k = 0; k < 3; k++)
                for (int a = 0; a < 3; a++) _mm_store_ps(&vtx[k][a][g], nan);
            continue;
        }
        for (int k = 0; k < 3; k++) {
            __m128 r0 = _mm_loadu_ps(&tri[g]->v0.x + 3 * k), r1 = _mm_loadu_ps(&tri[g + 1]->v0.x + 3 * k);
            __m128 r2 = _mm_loadu_ps(&tri[g + 2]->v0.x + 3 * k), r3 = _mm_loadu_ps(&tri[g + 3]->v0.x + 3 * k);
            _MM_TRANSPOSE4_PS(r0, r1, r2, r3);
            _mm_store_ps(&vtx[k][0][g], r0);
            _mm_store_ps(&vtx[k][1][g], r1);
            _mm_store_ps(&vtx[k][2][g], r2);
        }
    }
    return triangle_block_intersect((const float(*)[3][TRI_BLOCK_WIDTH])vtx, q, t_min, t_max, t_out, u_out, v_out,
                                    scalar_lanes);
}


#endif
