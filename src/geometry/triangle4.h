/* triangle_intersect_watertight() on four triangles at once with SSE, for the grid, which
 * gathers a cell's triangles four at a time (stored blocks use triangle_block.h). */
#ifndef CST_GEOMETRY_TRIANGLE4_H
#define CST_GEOMETRY_TRIANGLE4_H

#include <immintrin.h>

#include "geometry/triangle.h"

/* Per-ray constants of the 4-wide test. */
typedef struct TriangleRay4 {
    TriangleRay tr;
    __m128 o[3]; /* origin, per world axis */
    __m128 sx, sy, sz;
} TriangleRay4;

static inline TriangleRay4 triangle_ray4_setup(const Ray *r)
{
    TriangleRay4 q;
    q.tr = triangle_ray_setup(r->d);
    q.o[0] = _mm_set1_ps(r->o.x); q.o[1] = _mm_set1_ps(r->o.y); q.o[2] = _mm_set1_ps(r->o.z);
    q.sx = _mm_set1_ps(q.tr.sx); q.sy = _mm_set1_ps(q.tr.sy); q.sz = _mm_set1_ps(q.tr.sz);
    return q;
}

/* Vertex k of lane `lane` of a block v[vertex][axis][lane]. */
static inline Vec3 triangle4_vertex(const float v[3][3][4], int k, int lane)
{
    return v3(v[k][0][lane], v[k][1][lane], v[k][2][lane]);
}

/* The four triangles v[vertex][axis][lane] (16-byte aligned rows; unused lanes NaN) with
 * the same operations in the same order as triangle_intersect_watertight() (the build has
 * -ffp-contract=off, so nothing is fused into FMAs): each lane's t, u, v are bit-identical
 * to the scalar test's, and so is its rejection of t within triangle_t_error(). Lanes
 * whose edge functions are exactly zero need the scalar's recomputation in double: they
 * come back in *scalar_lanes for the caller to run through the scalar test. Returns the
 * mask of the other lanes that hit within (t_min, t_max). */
static inline int triangle4_intersect(const float v[3][3][4], const TriangleRay4 *q, __m128 t_min, __m128 t_max,
                                      __m128 *t_out, __m128 *u_out, __m128 *v_out, int *scalar_lanes)
{
    const int kx = q->tr.kx, ky = q->tr.ky, kz = q->tr.kz;
    __m128 px[3], py[3], pz[3];
    for (int k = 0; k < 3; k++) {
        pz[k] = _mm_sub_ps(_mm_load_ps(v[k][kz]), q->o[kz]);
        px[k] = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(v[k][kx]), q->o[kx]), _mm_mul_ps(q->sx, pz[k]));
        py[k] = _mm_sub_ps(_mm_sub_ps(_mm_load_ps(v[k][ky]), q->o[ky]), _mm_mul_ps(q->sy, pz[k]));
    }
    /* U, V, W: scaled barycentrics of vertices 0, 1, 2 (edge functions, JCGT 2013 eq. 4) */
    __m128 U = _mm_sub_ps(_mm_mul_ps(px[2], py[1]), _mm_mul_ps(py[2], px[1]));
    __m128 V = _mm_sub_ps(_mm_mul_ps(px[0], py[2]), _mm_mul_ps(py[0], px[2]));
    __m128 W = _mm_sub_ps(_mm_mul_ps(px[1], py[0]), _mm_mul_ps(py[1], px[0]));
    const __m128 zero = _mm_setzero_ps();
    int zero_lanes = _mm_movemask_ps(_mm_or_ps(_mm_or_ps(_mm_cmpeq_ps(U, zero), _mm_cmpeq_ps(V, zero)),
                                               _mm_cmpeq_ps(W, zero)));
    *scalar_lanes = zero_lanes;
    /* With no zero among U, V, W, "some negative and some positive" is "some sign bit
     * differs from U's": two xors and an or instead of six compares. Most rays pass outside
     * all four: stop before the division. Unused lanes are NaN, whose sign bits mean
     * nothing, so they are dropped explicitly. */
    __m128 mixed = _mm_or_ps(_mm_xor_ps(U, V), _mm_xor_ps(U, W));
    int inside = ~_mm_movemask_ps(mixed) & _mm_movemask_ps(_mm_cmpord_ps(U, U)) & ~zero_lanes;
    if (!inside) {
        *t_out = *u_out = *v_out = zero;
        return 0;
    }
    __m128 det = _mm_add_ps(_mm_add_ps(U, V), W);
    __m128 zt[3];
    for (int k = 0; k < 3; k++) zt[k] = _mm_mul_ps(q->sz, pz[k]);
    __m128 T = _mm_add_ps(_mm_add_ps(_mm_mul_ps(U, zt[0]), _mm_mul_ps(V, zt[1])), _mm_mul_ps(W, zt[2]));
    /* t = T * (1 / det) is positive only where T and det have the same sign. A ray that
     * leaves a surface passes "inside" the triangle it starts on (and often a neighbour),
     * behind its origin (about three such blocks per bounce ray on the bunny). With t_min
     * >= 0 (the renderer's rays) such lanes cannot hit, so when no lane is left they skip
     * the division and the error bound (Woop et al. 2013 test the sign before dividing
     * too); the result is the full test's, bit for bit. */
    if (!(inside & ~_mm_movemask_ps(_mm_xor_ps(T, det))) && _mm_movemask_ps(_mm_cmpge_ps(t_min, zero)) == 0xf) {
        *t_out = *u_out = *v_out = zero;
        return 0;
    }
    __m128 inv_det = _mm_div_ps(_mm_set1_ps(1.0f), det);
    __m128 t = _mm_mul_ps(T, inv_det);
    __m128 ok = _mm_cmpneq_ps(det, zero);
    ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, t_min));
    ok = _mm_and_ps(ok, _mm_cmplt_ps(t, t_max));
    /* triangle_t_error(), lane by lane, same operations in the same order. */
    const __m128 abs_mask = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff));
#define ABS4(x) _mm_and_ps((x), abs_mask)
#define MAX3(a, b, c) _mm_max_ps(_mm_max_ps(ABS4(a), ABS4(b)), ABS4(c))
    __m128 max_zt = MAX3(zt[0], zt[1], zt[2]);
    __m128 max_xt = MAX3(px[0], px[1], px[2]);
    __m128 max_yt = MAX3(py[0], py[1], py[2]);
    __m128 max_e = MAX3(U, V, W);
#undef MAX3
    const __m128 g2 = _mm_set1_ps(TRIANGLE_GAMMA(2)), g3 = _mm_set1_ps(TRIANGLE_GAMMA(3)),
                 g5 = _mm_set1_ps(TRIANGLE_GAMMA(5));
    __m128 delta_z = _mm_mul_ps(g3, max_zt);
    __m128 delta_x = _mm_mul_ps(g5, _mm_add_ps(max_xt, max_zt));
    __m128 delta_y = _mm_mul_ps(g5, _mm_add_ps(max_yt, max_zt));
    __m128 delta_e = _mm_mul_ps(_mm_set1_ps(2.0f),
                                _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_mul_ps(g2, max_xt), max_yt), _mm_mul_ps(delta_y, max_xt)),
                                           _mm_mul_ps(delta_x, max_yt)));
    __m128 delta_t = _mm_mul_ps(
        _mm_mul_ps(_mm_set1_ps(3.0f), _mm_add_ps(_mm_add_ps(_mm_mul_ps(_mm_mul_ps(g3, max_e), max_zt),
                                                            _mm_mul_ps(delta_e, max_zt)),
                                                 _mm_mul_ps(delta_z, max_e))),
        ABS4(inv_det));
#undef ABS4
    ok = _mm_and_ps(ok, _mm_cmpgt_ps(t, delta_t));
    *t_out = t;
    *u_out = _mm_mul_ps(V, inv_det);
    *v_out = _mm_mul_ps(W, inv_det);
    return _mm_movemask_ps(ok) & inside;
}

#endif
