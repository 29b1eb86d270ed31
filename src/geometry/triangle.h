/* Ray-triangle intersection (Moller & Trumbore, "Fast, Minimum Storage Ray/Triangle
 * Intersection", JGT 1997) on precomputed (v0, e1 = v1 - v0, e2 = v2 - v0). */
#ifndef CST_GEOMETRY_TRIANGLE_H
#define CST_GEOMETRY_TRIANGLE_H

#include <stdbool.h>
#include <stdint.h>

#include "geometry/ray.h"

/* Area of triangle (a, b, c): half the length of (b - a) x (c - a); 0 for a degenerate one.
 * The one test of degeneracy every loader and the scene builder share. */
static inline float triangle_area(Vec3 a, Vec3 b, Vec3 c)
{
    return 0.5f * v3_length(v3_cross(v3_sub(b, a), v3_sub(c, a)));
}

/* Two-sided test. On a hit in (t_min, t_max) writes t and the barycentrics (u, v) of v1
 * and v2. A ray parallel to the plane (det == 0) never hits, including rays lying in the
 * plane: such grazing hits have no well-defined t and are left to the neighbours. */
static inline bool triangle_intersect_mt(Vec3 v0, Vec3 e1, Vec3 e2, const Ray *r,
                                      float *t_out, float *u_out, float *v_out)
{
    Vec3 p = v3_cross(r->d, e2);
    float det = v3_dot(e1, p);
    if (det == 0.0f) return false;
    float inv_det = 1.0f / det;
    Vec3 s = v3_sub(r->o, v0);
    float u = v3_dot(s, p) * inv_det;
    if (u < 0.0f || u > 1.0f) return false;
    Vec3 q = v3_cross(s, e1);
    float v = v3_dot(r->d, q) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return false;
    float t = v3_dot(e2, q) * inv_det;
    if (!(t > r->t_min && t < r->t_max)) return false;
    *t_out = t; *u_out = u; *v_out = v;
    return true;
}

/* Per-ray set-up of the watertight test: the ray's dominant axis becomes z, the other two
 * are sheared so the ray runs along +z from the origin (Woop, Benthin & Wald, "Watertight
 * Ray/Triangle Intersection", JCGT 2(1), 2013, sec. 3). */
typedef struct TriangleRay {
    int kx, ky, kz;
    float sx, sy, sz;
} TriangleRay;

static inline TriangleRay triangle_ray_setup(Vec3 d)
{
    /* The axis choice and the winding swap by table lookups, not branches: for incoherent
     * rays (bounces, shadow rays) the branches were mispredicted about once per ray
     * (cachegrind, the bunny's secondary rays). Bit 0: |x| > |y|, bit 1: |x| > |z|,
     * bit 2: |y| > |z|; the largest component becomes z, ties going to the later axis. */
    static const unsigned char KZ[8] = {2, 2, 2, 0, 1, 2, 1, 0};
    /* [2 kz + (d_kz < 0)]: kx and ky cyclic after kz, swapped to keep the winding. */
    static const unsigned char KX[6] = {1, 2, 2, 0, 0, 1}, KY[6] = {2, 1, 0, 2, 1, 0};
    const float c[3] = {d.x, d.y, d.z};
    const float ax = fabsf(d.x), ay = fabsf(d.y), az = fabsf(d.z);
    const unsigned key = (unsigned)(ax > ay) | (unsigned)(ax > az) << 1 | (unsigned)(ay > az) << 2;
    TriangleRay tr;
    tr.kz = KZ[key];
    const float dz = c[tr.kz];
    const unsigned row = 2u * (unsigned)tr.kz + (unsigned)(dz < 0.0f);
    tr.kx = KX[row];
    tr.ky = KY[row];
    /* One division: the shear only has to be the same for every triangle a ray meets. */
    tr.sz = 1.0f / dz;
    tr.sx = c[tr.kx] * tr.sz;
    tr.sy = c[tr.ky] * tr.sz;
    return tr;
}

/* gamma(n) = n eps / (1 - n eps), eps = 2^-24: the relative error bound of n float
 * operations (Higham; pbrt-v3 sec. 3.9.1). */
#define TRIANGLE_GAMMA(n) ((float)(n) * 0x1p-24f / (1.0f - (float)(n) * 0x1p-24f))

/* A conservative bound on the rounding error of the watertight test's t, from the
 * sheared vertices (x, y and the scaled z), the edge functions and 1 / det (pbrt-v3
 * sec. 3.9.6, "Ensuring positive t"). Rounding can make a ray that leaves a surface hit
 * that surface, or a neighbour it cannot reach, at a tiny positive t: where the
 * coordinates are large and the ray origin's offset is small (a wall at x = 0 in a box
 * of size 500 with Ray Tracing Gems' fixed offset of 2^-16; scenes now scale theirs,
 * Scene.offset_near, but any caller may pass small ones), the sheared vertices err by
 * more than the offset.
 * A t within the bound is not provably positive and is rejected. block_intersect4 in
 * accel/bvh.c repeats these operations in this order, lane by lane. */
static inline float triangle_t_error(float Ax, float Ay, float Bx, float By, float Cx, float Cy, float azt,
                                     float bzt, float czt, float U, float V, float W, float inv_det)
{
    float max_zt = maxf(maxf(fabsf(azt), fabsf(bzt)), fabsf(czt));
    float max_xt = maxf(maxf(fabsf(Ax), fabsf(Bx)), fabsf(Cx));
    float max_yt = maxf(maxf(fabsf(Ay), fabsf(By)), fabsf(Cy));
    float delta_z = TRIANGLE_GAMMA(3) * max_zt;
    float delta_x = TRIANGLE_GAMMA(5) * (max_xt + max_zt);
    float delta_y = TRIANGLE_GAMMA(5) * (max_yt + max_zt);
    float delta_e = 2.0f * (TRIANGLE_GAMMA(2) * max_xt * max_yt + delta_y * max_xt + delta_x * max_yt);
    float max_e = maxf(maxf(fabsf(U), fabsf(V)), fabsf(W));
    return 3.0f * (TRIANGLE_GAMMA(3) * max_e * max_zt + delta_e * max_zt + delta_z * max_e) * fabsf(inv_det);
}

/* The watertight test on the triangle's own vertices a, b, c (not on precomputed edges:
 * two triangles sharing an edge must see bit-identical vertices). A ray through a shared
 * edge or vertex hits at least one of the triangles, never neither: the edge functions
 * of a shared edge are exact negatives of each other, and when one is zero it is
 * recomputed in double so its sign is exact (JCGT 2013, sec. 4). Two-sided. On a hit
 * in (t_min, t_max) beyond t's error bound writes t and the barycentrics u, v of b and c. */
static inline bool triangle_intersect_watertight(const TriangleRay *tr, const Ray *r, Vec3 a, Vec3 b,
                                                 Vec3 c, float *t_out, float *u_out, float *v_out)
{
    Vec3 A = v3_sub(a, r->o), B = v3_sub(b, r->o), C = v3_sub(c, r->o);
    float az = v3_get(A, tr->kz), bz = v3_get(B, tr->kz), cz = v3_get(C, tr->kz);
    float Ax = v3_get(A, tr->kx) - tr->sx * az, Ay = v3_get(A, tr->ky) - tr->sy * az;
    float Bx = v3_get(B, tr->kx) - tr->sx * bz, By = v3_get(B, tr->ky) - tr->sy * bz;
    float Cx = v3_get(C, tr->kx) - tr->sx * cz, Cy = v3_get(C, tr->ky) - tr->sy * cz;
    float U = Cx * By - Cy * Bx;
    float V = Ax * Cy - Ay * Cx;
    float W = Bx * Ay - By * Ax;
    if (U == 0.0f || V == 0.0f || W == 0.0f) {
        /* Products of floats are exact in double, so the sign of each difference is too. */
        U = (float)((double)Cx * (double)By - (double)Cy * (double)Bx);
        V = (float)((double)Ax * (double)Cy - (double)Ay * (double)Cx);
        W = (float)((double)Bx * (double)Ay - (double)By * (double)Ax);
    }
    if ((U < 0.0f || V < 0.0f || W < 0.0f) && (U > 0.0f || V > 0.0f || W > 0.0f)) return false;
    float det = U + V + W;
    if (det == 0.0f) return false;
    float azt = tr->sz * az, bzt = tr->sz * bz, czt = tr->sz * cz;
    float T = U * azt + V * bzt + W * czt;
    float inv_det = 1.0f / det;
    float t = T * inv_det;
    if (!(t > r->t_min && t < r->t_max)) return false;
    if (!(t > triangle_t_error(Ax, Ay, Bx, By, Cx, Cy, azt, bzt, czt, U, V, W, inv_det))) return false;
    *t_out = t;
    *u_out = V * inv_det;
    *v_out = W * inv_det;
    return true;
}

/* Texture coordinates at barycentrics (b1, b2) (the weights of v1 and v2) of triangle t,
 * whose vertex indices are tri_indices[3t..3t+2]: interpolated from the per-vertex uvs when
 * the triangle has them (has_uv[t]; has_uv NULL: none has), else the default
 * (0,0), (1,0), (0,1) at v0, v1, v2, which is (b1, b2) itself. */
static inline Vec2 triangle_uv(const Vec2 *uvs, const unsigned char *has_uv, const int32_t *tri_indices,
                               uint32_t t, float b1, float b2)
{
    if (!has_uv || !has_uv[t]) return v2(b1, b2);
    const int32_t *i = &tri_indices[3 * t];
    Vec2 a = uvs[i[0]], b = uvs[i[1]], c = uvs[i[2]];
    float b0 = 1.0f - b1 - b2;
    return v2(b0 * a.x + b1 * b.x + b2 * c.x, b0 * a.y + b1 * b.y + b2 * c.y);
}

#endif
