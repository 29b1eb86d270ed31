/* Curves (curve.h): pbrt-v4 (Pharr, Jakob, Humphreys, 4th ed.) §6.7, after Nakamaru and
 * Ohno, "Ray tracing for curves primitive", WSCG 2002: a cubic Bezier in ray space,
 * subdivided until nearly straight, its last pieces tested as lines of varying width. */
#include "geometry/curve.h"

#include <float.h>

/* ------------------------------------------------------------ Bezier arithmetic */

static inline Vec3 lerp3(float t, Vec3 a, Vec3 b) { return v3_add(v3_scale(a, 1.0f - t), v3_scale(b, t)); }

Vec3 curve_eval(const Vec3 cp[4], float w, Vec3 *deriv)
{
    /* de Casteljau; the derivative is 3 (b1 - b0) of the second level (pbrt-v4 eq. 6.x). */
    Vec3 a0 = lerp3(w, cp[0], cp[1]), a1 = lerp3(w, cp[1], cp[2]), a2 = lerp3(w, cp[2], cp[3]);
    Vec3 b0 = lerp3(w, a0, a1), b1 = lerp3(w, a1, a2);
    if (deriv) {
        Vec3 d = v3_sub(b1, b0);
        /* at the ends b1 - b0 vanishes when two control points coincide: use the chord */
        if (v3_length2(d) > 0.0f) *deriv = v3_scale(d, 3.0f);
        else *deriv = v3_sub(cp[3], cp[0]);
    }
    return lerp3(w, b0, b1);
}

/* The blossom p(a, b, c) of the cubic Bezier q (Ramshaw 1987), in double: the control
 * points of q restricted to [u0, u1] are p(u0,u0,u0), p(u0,u0,u1), p(u0,u1,u1), p(u1,u1,u1). */
static Vec3 blossom(const Vec3 q[4], double a, double b, double c)
{
    double p[4][3];
    for (int i = 0; i < 4; i++) { p[i][0] = (double)q[i].x; p[i][1] = (double)q[i].y; p[i][2] = (double)q[i].z; }
    double r[3];
    for (int k = 0; k < 3; k++) {
        double a01 = p[0][k] + a * (p[1][k] - p[0][k]), a12 = p[1][k] + a * (p[2][k] - p[1][k]);
        double a23 = p[2][k] + a * (p[3][k] - p[2][k]);
        double b0 = a01 + b * (a12 - a01), b1 = a12 + b * (a23 - a12);
        r[k] = b0 + c * (b1 - b0);
    }
    return v3((float)r[0], (float)r[1], (float)r[2]);
}

void curve_bezier_segment(const Vec3 *cp, int degree, bool bspline, int seg, Vec3 out[4])
{
    if (!bspline) {
        const Vec3 *p = cp + seg * degree;
        if (degree == 3) {
            for (int i = 0; i < 4; i++) out[i] = p[i];
        } else { /* degree elevation of a quadratic: (p0, p0 + 2/3 (p1 - p0), p2 + 2/3 (p1 - p2), p2) */
            out[0] = p[0];
            out[1] = lerp3(2.0f / 3.0f, p[0], p[1]);
            out[2] = lerp3(1.0f / 3.0f, p[1], p[2]);
            out[3] = p[2];
        }
        return;
    }
    /* Uniform B-spline segments as Bezier (Boehm's knot insertion, as pbrt-v4 does). */
    const Vec3 *p = cp + seg;
    if (degree == 2) {
        Vec3 p11 = lerp3(0.5f, p[0], p[1]), p22 = lerp3(0.5f, p[1], p[2]);
        out[0] = p11;
        out[1] = lerp3(2.0f / 3.0f, p11, p[1]);
        out[2] = lerp3(1.0f / 3.0f, p[1], p22);
        out[3] = p22;
    } else {
        Vec3 p122 = lerp3(2.0f / 3.0f, p[0], p[1]), p223 = lerp3(1.0f / 3.0f, p[1], p[2]);
        Vec3 p233 = lerp3(2.0f / 3.0f, p[1], p[2]), p334 = lerp3(1.0f / 3.0f, p[2], p[3]);
        out[0] = lerp3(0.5f, p122, p223);
        out[1] = p223;
        out[2] = p233;
        out[3] = lerp3(0.5f, p233, p334);
    }
}

/* ------------------------------------------------------------ construction */

/* pbrt-v4's refinement depth: subdivide until the pieces deviate from their chords by at
 * most eps = 5% of the width; a cubic's deviation after d halvings is bounded by
 * (sqrt(2) * 6 * L0 / 8) / 4^d, L0 the largest second difference of the control points
 * (pbrt-v4 §6.7.3). log2 rounded to the nearest integer, halved, clamped to [0, 10]. */
static uint8_t refine_depth(const Vec3 cp[4], float w0, float w1)
{
    float l0 = 0.0f;
    for (int i = 0; i < 2; i++)
        l0 = maxf(l0, v3_max_abs(v3_add(v3_sub(cp[i], v3_scale(cp[i + 1], 2.0f)), cp[i + 2])));
    const float eps = maxf(w0, w1) * 0.05f;
    if (!(l0 > 0.0f) || !(eps > 0.0f)) return 0;
    const float x = 1.41421356237f * 6.0f * l0 / (8.0f * eps);
    if (!(x > 1.0f)) return 0;
    int r = (int)lrintf(log2f(x)) / 2;
    return (uint8_t)(r < 0 ? 0 : r > 10 ? 10 : r);
}

/* The squared distance from p to the segment [a, b], in double. */
static double point_chord_dist2(Vec3 p, Vec3 a, Vec3 b)
{
    const double e[3] = {(double)b.x - (double)a.x, (double)b.y - (double)a.y, (double)b.z - (double)a.z};
    const double w[3] = {(double)p.x - (double)a.x, (double)p.y - (double)a.y, (double)p.z - (double)a.z};
    const double ee = e[0] * e[0] + e[1] * e[1] + e[2] * e[2];
    double s = ee > 0.0 ? (w[0] * e[0] + w[1] * e[1] + w[2] * e[2]) / ee : 0.0;
    s = fmin(1.0, fmax(0.0, s));
    double d2 = 0.0;
    for (int k = 0; k < 3; k++) d2 += (w[k] - s * e[k]) * (w[k] - s * e[k]);
    return d2;
}

bool curve_init(Curve *c, const Vec3 whole_cp[4], float u0, float u1, float w0, float w1, CurveType type,
                const Vec3 *n, bool flip)
{
    *c = (Curve){0};
    if (!(u0 >= 0.0f && u0 < u1 && u1 <= 1.0f)) return false;
    if (!(w0 >= 0.0f && w1 >= 0.0f && isfinite(w0) && isfinite(w1)) || !(w0 + w1 > 0.0f)) return false;
    if ((unsigned)type > CURVE_RIBBON) return false;
    for (int i = 0; i < 4; i++)
        if (!v3_is_finite(whole_cp[i])) return false;
    c->cp[0] = blossom(whole_cp, (double)u0, (double)u0, (double)u0);
    c->cp[1] = blossom(whole_cp, (double)u0, (double)u0, (double)u1);
    c->cp[2] = blossom(whole_cp, (double)u0, (double)u1, (double)u1);
    c->cp[3] = blossom(whole_cp, (double)u1, (double)u1, (double)u1);
    c->u0 = u0; c->u1 = u1; c->w0 = w0; c->w1 = w1;
    c->type = (uint8_t)type;
    c->flip = flip;
    if (type == CURVE_RIBBON) {
        if (!n || !v3_is_finite(n[0]) || !v3_is_finite(n[1]) || !(v3_length2(n[0]) > 0.0f) ||
            !(v3_length2(n[1]) > 0.0f))
            return false;
        c->n0 = v3_normalize(n[0]);
        c->n1 = v3_normalize(n[1]);
        /* the angle between unit vectors, stable for small and large angles */
        float dot = v3_dot(c->n0, c->n1);
        c->normal_angle = dot < 0.0f ? CST_PI - 2.0f * asinf(minf(1.0f, 0.5f * v3_length(v3_add(c->n0, c->n1))))
                                     : 2.0f * asinf(minf(1.0f, 0.5f * v3_length(v3_sub(c->n1, c->n0))));
        c->inv_sin_angle = c->normal_angle > 0.0f ? 1.0f / sinf(c->normal_angle) : 0.0f;
    }
    c->depth = refine_depth(c->cp, w0, w1);
    /* Every point of the segment is in the convex hull of its control points, so within
     * max(dist(cp1, chord), dist(cp2, chord)) of the chord (a segment, convex); every hit
     * within half a width more. Padded by 2^-16 of the extent for the float arithmetic. */
    double reach = 0.0;
    for (int i = 1; i <= 2; i++) reach = fmax(reach, sqrt((double)point_chord_dist2(c->cp[i], c->cp[0], c->cp[3])));
    reach += 0.5 * (double)fmaxf(curve_width(c, u0), curve_width(c, u1));
    reach += (double)fmaxf(v3_max_abs(c->cp[0]), v3_max_abs(c->cp[3])) * 0x1p-16 + (double)v3_length(v3_sub(c->cp[3], c->cp[0])) * 0x1p-16;
    c->reach = (float)reach;
    BBox b = curve_bounds(c);
    return v3_is_finite(b.min) && v3_is_finite(b.max);
}

BBox curve_bounds(const Curve *c)
{
    BBox b = {c->cp[0], c->cp[0]};
    for (int i = 1; i < 4; i++) { b.min = v3_min(b.min, c->cp[i]); b.max = v3_max(b.max, c->cp[i]); }
    const float half = 0.5f * maxf(curve_width(c, c->u0), curve_width(c, c->u1));
    const float pad = half + maxf(v3_max_abs(b.min), v3_max_abs(b.max)) * 0x1p-18f + 1e-30f;
    b.min = v3_sub(b.min, v3s(pad));
    b.max = v3_add(b.max, v3s(pad));
    return b;
}

int curve_piece_bounds(const Curve *c, BBox boxes[CURVE_MAX_PIECES])
{
    /* the control polygon's length bounds the segment's; pieces at most 8 widths long,
     * so the BVH offers a ray the fibres near it, not every fibre whose diagonal box it
     * crosses (bench/hair_ball.py, 1M segments: render 1.6x faster; 4 widths rendered no
     * faster, built 1.5x slower and peaked 160 MB higher: docs/benchmarks-history.md) */
    const float wmax = maxf(curve_width(c, c->u0), curve_width(c, c->u1));
    const float len = v3_length(v3_sub(c->cp[1], c->cp[0])) + v3_length(v3_sub(c->cp[2], c->cp[1])) +
                      v3_length(v3_sub(c->cp[3], c->cp[2]));
    int k = 1;
    while (k < CURVE_MAX_PIECES && len > 8.0f * wmax * (float)k) k *= 2;
    if (k == 1) { boxes[0] = curve_bounds(c); return 1; }
    for (int j = 0; j < k; j++) {
        const double a = (double)j / k, b = (double)(j + 1) / k;
        Curve piece = *c;
        piece.cp[0] = blossom(c->cp, a, a, a);
        piece.cp[1] = blossom(c->cp, a, a, b);
        piece.cp[2] = blossom(c->cp, a, b, b);
        piece.cp[3] = blossom(c->cp, b, b, b);
        piece.u0 = (float)((double)c->u0 + a * (double)(c->u1 - c->u0));
        piece.u1 = (float)((double)c->u0 + b * (double)(c->u1 - c->u0));
        /* the widths are linear in u: the largest at a piece's end, and the rounding of
         * its ends in u is covered by curve_bounds' relative padding */
        boxes[j] = curve_bounds(&piece);
    }
    return k;
}

/* The ribbon's normal at u: the spherical interpolation of n0 and n1 (pbrt-v4). */
static Vec3 ribbon_normal(const Curve *c, float u)
{
    if (c->normal_angle == 0.0f) return c->n0;
    const float s0 = sinf((1.0f - u) * c->normal_angle) * c->inv_sin_angle;
    const float s1 = sinf(u * c->normal_angle) * c->inv_sin_angle;
    return v3_add(v3_scale(c->n0, s0), v3_scale(c->n1, s1));
}

/* ------------------------------------------------------------ intersection */

/* One query: the ray's unit direction (world) and the interval in ray-space z (distance
 * along the unit direction); z_best shrinks with every hit. */
typedef struct CurveQuery {
    const Curve *c;     /* ribbons: the normals (NULL on a CurveSeg, which is never a ribbon) */
    float w0, w1;       /* the whole curve's widths */
    int type;           /* CurveType */
    Vec3 dir;
    float len;          /* |r->d|: t = z / len */
    float t_min;
    float t_best;       /* the closest hit so far (or r->t_max) */
    float u, v;
} CurveQuery;

/* The width at the whole curve's u: curve_width's expression on the query's copies. */
static inline float q_width(const CurveQuery *q, float u) { return (1.0f - u) * q->w0 + u * q->w1; }

/* Whether the box of cp widened by half_w contains the ray's line x = y = 0 within
 * z in [0, z_max]. */
static inline bool box_meets_ray(const Vec3 cp[4], float half_w, float z_max)
{
    Vec3 lo = cp[0], hi = cp[0];
    for (int i = 1; i < 4; i++) { lo = v3_min(lo, cp[i]); hi = v3_max(hi, cp[i]); }
    return !(lo.x - half_w > 0.0f || hi.x + half_w < 0.0f || lo.y - half_w > 0.0f || hi.y + half_w < 0.0f ||
             hi.z + half_w < 0.0f || lo.z - half_w > z_max);
}

/* The last piece, nearly straight: the ray (the origin in xy) must lie between the normals
 * of its end tangents; the closest point of the chord in xy gives u; the curve at that
 * parameter must be within half the width of the ray and inside the interval. */
static bool leaf_hit(CurveQuery *q, const Vec3 cp[4], float ua, float ub)
{
    /* (cp1 - cp0) . (0 - cp0) >= 0 and (cp2 - cp3) . (0 - cp3) >= 0 in xy */
    if ((cp[1].x - cp[0].x) * -cp[0].x + (cp[1].y - cp[0].y) * -cp[0].y < 0.0f) return false;
    if ((cp[2].x - cp[3].x) * -cp[3].x + (cp[2].y - cp[3].y) * -cp[3].y < 0.0f) return false;
    const float sx = cp[3].x - cp[0].x, sy = cp[3].y - cp[0].y, denom = sx * sx + sy * sy;
    if (!(denom > 0.0f)) return false;
    const float w = (-cp[0].x * sx - cp[0].y * sy) / denom;
    const float u = clampf(ua + w * (ub - ua), ua, ub);
    const float width = q_width(q, u);
    float hit_w = width;
    if (q->type == CURVE_RIBBON) hit_w *= fabsf(v3_dot(ribbon_normal(q->c, u), q->dir)); /* its projected width */
    if (!(hit_w > 0.0f)) return false;
    Vec3 dpc;
    const Vec3 pc = curve_eval(cp, clampf(w, 0.0f, 1.0f), &dpc);
    const float dist2 = pc.x * pc.x + pc.y * pc.y;
    if (dist2 > hit_w * hit_w * 0.25f) return false;
    const float t = pc.z / q->len;
    if (!(t > q->t_min && t < q->t_best)) return false;
    /* A ray leaving this fibre: its origin within one width of the piece's chord (a hit
     * point lies within half a width of it). pbrt-v4 moves such a ray's origin 2 widths
     * off instead (Curve's pError); caustic's spawn offset is a few ulps, so the test
     * skips the piece. */
    const Vec3 ab = v3_sub(cp[3], cp[0]);
    const float s = clampf(-v3_dot(cp[0], ab) / v3_length2(ab), 0.0f, 1.0f);
    if (v3_length2(v3_madd(cp[0], ab, s)) < width * width) return false;
    const float dist = sqrtf(dist2);
    /* the side of the centre line: the sign of the 2D cross product of the tangent and pc */
    const float edge = dpc.x * -pc.y + pc.x * dpc.y;
    q->v = edge > 0.0f ? 0.5f + dist / hit_w : 0.5f - dist / hit_w;
    q->u = u;
    q->t_best = t;
    return true;
}

static bool recurse(CurveQuery *q, const Vec3 cp[4], float ua, float ub, int depth)
{
    if (depth == 0) return leaf_hit(q, cp, ua, ub);
    /* de Casteljau halving at 1/2: the halves' control points share cps[3] */
    Vec3 cps[7];
    cps[0] = cp[0];
    cps[1] = v3_scale(v3_add(cp[0], cp[1]), 0.5f);
    cps[2] = v3_scale(v3_add(v3_add(cp[0], v3_scale(cp[1], 2.0f)), cp[2]), 0.25f);
    cps[3] = v3_scale(v3_add(v3_add(cp[0], v3_scale(cp[1], 3.0f)), v3_add(v3_scale(cp[2], 3.0f), cp[3])), 0.125f);
    cps[4] = v3_scale(v3_add(v3_add(cp[1], v3_scale(cp[2], 2.0f)), cp[3]), 0.25f);
    cps[5] = v3_scale(v3_add(cp[2], cp[3]), 0.5f);
    cps[6] = cp[3];
    const float us[3] = {ua, 0.5f * (ua + ub), ub};
    bool hit = false;
    for (int h = 0; h < 2; h++) {
        const float half_w = 0.5f * maxf(q_width(q, us[h]), q_width(q, us[h + 1]));
        /* z bound from the closest hit so far, widened by 2^-20 for its rounding */
        if (!box_meets_ray(&cps[3 * h], half_w, q->t_best * q->len * (1.0f + 0x1p-20f))) continue;
        hit |= recurse(q, &cps[3 * h], us[h], us[h + 1], depth - 1);
    }
    return hit;
}

/* A right-handed orthonormal frame with z = dir and x perpendicular to the chord's
 * component across the ray (pbrt-v4 uses LookAt with up = dir x chord), so the chord lies
 * along x in ray space. */
static void ray_frame(Vec3 dir, Vec3 chord, Vec3 *ex, Vec3 *ey)
{
    Vec3 up = v3_cross(dir, chord);
    if (!(v3_length2(up) > 0.0f)) /* the ray along the chord: any perpendicular */
        up = fabsf(dir.x) > fabsf(dir.z) ? v3(-dir.y, dir.x, 0.0f) : v3(0.0f, -dir.z, dir.y);
    *ex = v3_normalize(v3_cross(up, dir));
    *ey = v3_cross(dir, *ex);
}

/* Whether the ray's line passes within reach of the chord: the closest points of a
 * line and a segment (the segment's parameter clamped, the line's free). Conservative:
 * false only when the distance exceeds the reach by more than the rounding. */
static inline bool near_chord(const Vec3 cpw[4], float reach, const Ray *r)
{
    const Vec3 e = v3_sub(cpw[3], cpw[0]), w = v3_sub(r->o, cpw[0]);
    const float a = v3_dot(r->d, r->d), b = v3_dot(r->d, e), ce = v3_dot(e, e);
    const float dw = v3_dot(r->d, w), ew = v3_dot(e, w);
    const float denom = a * ce - b * b;
    float s = denom > 1e-6f * a * ce ? clampf((a * ew - b * dw) / denom, 0.0f, 1.0f) : 0.0f;
    if (!(s >= 0.0f)) s = 0.0f; /* NaN from a zero chord */
    /* the line's closest point to cp0 + s e */
    const Vec3 q = v3_madd(w, e, -s);            /* o - (cp0 + s e) */
    const float t = -v3_dot(r->d, q) / a;
    const Vec3 gap = v3_madd(q, r->d, t);
    /* slack for the float rounding of q + t d, which cancels from |q| down to |gap| */
    const float lim = reach + 1e-5f * v3_max_abs(q);
    return v3_length2(gap) <= lim * lim;
}

/* The test past near_chord, on either record: the segment's control points cpw (world),
 * its u range, the whole curve's widths, type and depth; c for a ribbon's normals. */
static inline bool intersect_near(const Vec3 cpw[4], float u0, float u1, float w0, float w1, int type, int depth,
                                  const Curve *c, const Ray *r, float *t, float *u, float *v)
{
    const float len = v3_length(r->d);
    if (!(len > 0.0f)) return false;
    CurveQuery q = {c, w0, w1, type, v3_scale(r->d, 1.0f / len), len, r->t_min, r->t_max, 0.0f, 0.0f};
    Vec3 ex, ey;
    ray_frame(q.dir, v3_sub(cpw[3], cpw[0]), &ex, &ey);
    Vec3 cp[4];
    for (int i = 0; i < 4; i++) {
        Vec3 d = v3_sub(cpw[i], r->o);
        cp[i] = v3(v3_dot(d, ex), v3_dot(d, ey), v3_dot(d, q.dir));
    }
    const float half_w = 0.5f * maxf(q_width(&q, u0), q_width(&q, u1));
    if (!box_meets_ray(cp, half_w, q.t_best * len * (1.0f + 0x1p-20f))) return false;
    if (!recurse(&q, cp, u0, u1, depth)) return false;
    *t = q.t_best;
    *u = q.u;
    *v = q.v;
    return true;
}

bool curve_intersect(const Curve *c, const Ray *r, float *t, float *u, float *v)
{
    if (!near_chord(c->cp, c->reach, r)) return false;
    return intersect_near(c->cp, c->u0, c->u1, c->w0, c->w1, c->type, c->depth, c, r, t, u, v);
}

bool curve_seg_init(CurveSeg *s, const Curve *c, uint32_t index)
{
    if (c->type == CURVE_RIBBON || index > CURVE_SEG_INDEX_MAX || c->depth > 15) return false;
    for (int i = 0; i < 4; i++) s->cp[i] = c->cp[i];
    s->reach = c->reach;
    s->u0 = c->u0;
    s->u1 = c->u1;
    s->info = (uint32_t)c->depth << 28 | (uint32_t)c->type << 26 | index;
    return true;
}

bool curve_seg_intersect(const CurveSeg *s, const CurveWidths *widths, const Ray *r, float *t, float *u, float *v)
{
    /* the widths' line is touched only by rays near the chord */
    if (!near_chord(s->cp, s->reach, r)) return false;
    const CurveWidths w = widths[s->info & CURVE_SEG_INDEX_MAX];
    return intersect_near(s->cp, s->u0, s->u1, w.w0, w.w1, (int)(s->info >> 26 & 3u), (int)(s->info >> 28), NULL, r,
                          t, u, v);
}

/* ------------------------------------------------------------ surface */

void curve_derivatives(const Curve *c, float u, Vec3 *dpdu, Vec3 *dpdv)
{
    const float span = c->u1 - c->u0;
    Vec3 d;
    curve_eval(c->cp, clampf((u - c->u0) / span, 0.0f, 1.0f), &d);
    *dpdu = v3_scale(d, 1.0f / span); /* the segment's derivative in the whole curve's u */
    Vec3 across;
    if (c->type == CURVE_RIBBON) {
        across = v3_cross(ribbon_normal(c, u), *dpdu);
    } else { /* any perpendicular: the axis least along the tangent, crossed */
        Vec3 a = fabsf(d.x) < fabsf(d.y) ? (fabsf(d.x) < fabsf(d.z) ? v3(1.0f, 0.0f, 0.0f) : v3(0.0f, 0.0f, 1.0f))
                                         : (fabsf(d.y) < fabsf(d.z) ? v3(0.0f, 1.0f, 0.0f) : v3(0.0f, 0.0f, 1.0f));
        across = v3_cross(d, a);
    }
    *dpdv = v3_length2(across) > 0.0f ? v3_scale(v3_normalize(across), curve_width(c, u)) : v3s(0.0f);
}

void curve_surface(const Curve *c, const Ray *r, float t, float u, float v, Vec3 *p, Vec3 *n, Vec3 *dpdu,
                   Vec3 *dpdv)
{
    *p = ray_at(r, t);
    const float span = c->u1 - c->u0;
    Vec3 d;
    curve_eval(c->cp, clampf((u - c->u0) / span, 0.0f, 1.0f), &d);
    *dpdu = v3_scale(d, 1.0f / span);
    const float width = curve_width(c, u);
    const Vec3 dir = v3_normalize(r->d);
    Vec3 across;
    if (c->type == CURVE_RIBBON) {
        const Vec3 nh = ribbon_normal(c, u);
        across = v3_scale(v3_normalize(v3_cross(nh, *dpdu)), width * fabsf(v3_dot(nh, dir)));
    } else {
        /* (-y, x, 0) of dp/du in ray space is dir x dp/du in world space */
        across = v3_scale(v3_normalize(v3_cross(dir, *dpdu)), width);
        if (c->type == CURVE_CYLINDER) {
            /* pbrt-v4: rotate by -theta about dp/du, theta = lerp(v, -90, 90) degrees;
             * Rodrigues' formula, across being perpendicular to the axis */
            const Vec3 k = v3_normalize(*dpdu);
            const float a = -(v - 0.5f) * CST_PI;
            across = v3_add(v3_scale(across, cosf(a)), v3_scale(v3_cross(k, across), sinf(a)));
        }
    }
    *dpdv = across;
    Vec3 nn = v3_cross(*dpdu, across);
    if (!(v3_length2(nn) > 0.0f) || !v3_is_finite(nn)) nn = v3_neg(dir); /* degenerate: face the ray */
    nn = v3_normalize(nn);
    *n = c->flip ? v3_neg(nn) : nn;
}
