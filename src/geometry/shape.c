/* The analytic shapes' intersection, surface reconstruction, bounds and area sampling:
 * pbrt-v4 (Pharr, Jakob, Humphreys, 4th ed.) §6.2 spheres, §6.3 cylinders, §6.4 disks,
 * §6.6 bilinear patches (Reshetov, "Cool Patches", Ray Tracing Gems, 2019, ch. 8); curves
 * (§6.7) are curve.c's, dispatched here. */
#include "geometry/shape.h"

#include <float.h>

#include "math/polynomial.h"

#define TWO_PI_D 6.28318530717958647692

/* ------------------------------------------------------------ affine maps in double */

typedef struct V3d { double x, y, z; } V3d;

static inline V3d map_point(const double m[3][4], V3d p)
{
    V3d r = {m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z + m[0][3],
             m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z + m[1][3],
             m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z + m[2][3]};
    return r;
}
static inline V3d map_vector(const double m[3][4], V3d v)
{
    V3d r = {m[0][0] * v.x + m[0][1] * v.y + m[0][2] * v.z,
             m[1][0] * v.x + m[1][1] * v.y + m[1][2] * v.z,
             m[2][0] * v.x + m[2][1] * v.y + m[2][2] * v.z};
    return r;
}
/* A normal to world space: by o2w's inverse transpose, which is w2o's linear part
 * transposed (read by columns here rather than stored a second time). */
static inline V3d map_normal(const double w2o[3][4], V3d v)
{
    V3d r = {w2o[0][0] * v.x + w2o[1][0] * v.y + w2o[2][0] * v.z,
             w2o[0][1] * v.x + w2o[1][1] * v.y + w2o[2][1] * v.z,
             w2o[0][2] * v.x + w2o[1][2] * v.y + w2o[2][2] * v.z};
    return r;
}
static inline V3d d3(Vec3 v) { V3d r = {(double)v.x, (double)v.y, (double)v.z}; return r; }
static inline V3d d3v(double x, double y, double z) { V3d r = {x, y, z}; return r; }
static inline Vec3 f3(V3d v) { return v3((float)v.x, (float)v.y, (float)v.z); }
static inline double d3_len(V3d v) { return sqrt(v.x * v.x + v.y * v.y + v.z * v.z); }
static inline Vec3 f3_unit(V3d v)
{
    double l = d3_len(v);
    return l > 0.0 ? v3((float)(v.x / l), (float)(v.y / l), (float)(v.z / l)) : v3s(0.0f);
}

static inline V3d d3_sub(V3d a, V3d b) { return d3v(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline V3d d3_lerp(double t, V3d a, V3d b)
{
    return d3v(a.x + t * (b.x - a.x), a.y + t * (b.y - a.y), a.z + t * (b.z - a.z));
}
static inline double d3_dot(V3d a, V3d b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline V3d d3_cross(V3d a, V3d b)
{
    return d3v(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}

/* ------------------------------------------------------------ bilinear patches */

static inline V3d bl_corner(const AnalyticShape *s, int i) { return d3v(s->bl.q[i][0], s->bl.q[i][1], s->bl.q[i][2]); }

bool shape_init_bilinear(AnalyticShape *s, const Vec3 p[4], const Vec3 *n, const Vec2 *uv, bool flip)
{
    *s = (AnalyticShape){0};
    s->p.type = SHAPE_TAG_BILINEAR;
    s->p.reverse_orientation = flip;
    s->flip_normal = flip;
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX}, ext = 0.0;
    for (int i = 0; i < 4; i++) {
        if (!v3_is_finite(p[i]) || (n && !v3_is_finite(n[i]))) return false;
        const double c[3] = {(double)p[i].x, (double)p[i].y, (double)p[i].z};
        for (int k = 0; k < 3; k++) {
            s->bl.q[i][k] = c[k];
            lo[k] = fmin(lo[k], c[k]);
            hi[k] = fmax(hi[k], c[k]);
            ext = fmax(ext, fabs(c[k]));
        }
        if (n) { s->bl.n[i][0] = n[i].x; s->bl.n[i][1] = n[i].y; s->bl.n[i][2] = n[i].z; }
        if (uv) { s->bl.uv[i][0] = uv[i].x; s->bl.uv[i][1] = uv[i].y; }
    }
    s->bl.has_n = n != NULL;
    s->bl.has_uv = uv != NULL;
    /* No area: the corners on one line (or one point), |dp/du x dp/dv| = 0 at all four. */
    V3d c00 = bl_corner(s, 0), c10 = bl_corner(s, 1), c01 = bl_corner(s, 2), c11 = bl_corner(s, 3);
    double a0 = d3_len(d3_cross(d3_sub(c10, c00), d3_sub(c01, c00)));
    double a1 = d3_len(d3_cross(d3_sub(c11, c01), d3_sub(c11, c10)));
    double a2 = d3_len(d3_cross(d3_sub(c10, c00), d3_sub(c11, c10)));
    double a3 = d3_len(d3_cross(d3_sub(c11, c01), d3_sub(c01, c00)));
    if (!(fmax(fmax(a0, a1), fmax(a2, a3)) > 0.0)) return false;
    /* The patch lies in the convex hull of its corners: their box, padded as the quadrics'. */
    double pad = ext * 0x1p-20 + 1e-30;
    s->bounds.min = v3((float)(lo[0] - pad), (float)(lo[1] - pad), (float)(lo[2] - pad));
    s->bounds.max = v3((float)(hi[0] + pad), (float)(hi[1] + pad), (float)(hi[2] + pad));
    return v3_is_finite(s->bounds.min) && v3_is_finite(s->bounds.max);
}

/* Ray against patch (Reshetov 2019; pbrt-v4 IntersectBilinearPatch), in double. The ray
 * meets the segment L(u) from p(u, 0) to p(u, 1) where o, d and L(u) are coplanar:
 * (p(u,0) - o) . (d x (p(u,1) - p(u,0))) = 0, a quadratic a u^2 + b u + c = 0 with
 * c its value at u = 0, a + b + c at u = 1, a = ((p10 - p00) x (p01 - p11)) . d. For each
 * root u in [0, 1], v and t by Cramer's rule on o + t d = p(u,0) + v (p(u,1) - p(u,0)),
 * with perp = d x ud as the third column: t = det(p(u,0) - o, ud, perp) / |perp|^2,
 * v = det(p(u,0) - o, d, perp) / |perp|^2. The nearer valid root wins. */
static bool bilinear_intersect(const AnalyticShape *s, const Ray *r, float *t_out, float *u_out, float *v_out)
{
    const V3d o = d3(r->o), d = d3(r->d);
    const V3d p00 = bl_corner(s, 0), p10 = bl_corner(s, 1), p01 = bl_corner(s, 2), p11 = bl_corner(s, 3);
    const double a = d3_dot(d3_cross(d3_sub(p10, p00), d3_sub(p01, p11)), d);
    const double c = d3_dot(d3_cross(d3_sub(p00, o), d), d3_sub(p01, p00));
    const double b = d3_dot(d3_cross(d3_sub(p10, o), d), d3_sub(p11, p10)) - (a + c);
    double roots[2];
    int nroots;
    if (a == 0.0) { /* linear in u (a planar patch seen so, or a parallelogram) */
        if (b == 0.0) return false;
        roots[0] = -c / b;
        nroots = 1;
    } else {
        const double disc = b * b - 4.0 * a * c;
        if (disc < 0.0) return false;
        const double q = -0.5 * (b + copysign(sqrt(disc), b));
        roots[0] = q / a;
        roots[1] = q != 0.0 ? c / q : roots[0];
        nroots = 2;
    }
    bool found = false;
    float best_t = r->t_max;
    for (int i = 0; i < nroots; i++) {
        const double u = roots[i];
        if (!(u >= 0.0 && u <= 1.0)) continue;
        const V3d uo = d3_lerp(u, p00, p10), ud = d3_sub(d3_lerp(u, p01, p11), uo);
        const V3d delta = d3_sub(uo, o), perp = d3_cross(d, ud);
        const double p2 = d3_dot(perp, perp);
        if (!(p2 > 0.0)) continue;
        const double v1 = d3_dot(delta, d3_cross(d, perp)), t1 = d3_dot(delta, d3_cross(ud, perp));
        if (!(v1 >= 0.0 && v1 <= p2)) continue;
        const float tf = (float)(t1 / p2);
        /* The float t must itself lie in the open interval: every back end compares it so. */
        if (!(tf > r->t_min && tf < best_t)) continue;
        best_t = tf;
        *t_out = tf;
        *u_out = (float)u;
        *v_out = (float)(v1 / p2);
        found = true;
    }
    return found;
}

/* The surface at patch parameters (u, v) in double: point, dp/du, dp/dv (pbrt-v4: along
 * the patch's own parameters), geometric normal dp/du x dp/dv turned to the interpolated
 * shading normal when the patch has normals, else flipped by flip_normal; uv interpolated. */
static void bilinear_surface(const AnalyticShape *s, double u, double v, ShapeSurface *out)
{
    const V3d p00 = bl_corner(s, 0), p10 = bl_corner(s, 1), p01 = bl_corner(s, 2), p11 = bl_corner(s, 3);
    const V3d p = d3_lerp(v, d3_lerp(u, p00, p10), d3_lerp(u, p01, p11));
    const V3d dpdu = d3_lerp(v, d3_sub(p10, p00), d3_sub(p11, p01));
    const V3d dpdv = d3_lerp(u, d3_sub(p01, p00), d3_sub(p11, p10));
    V3d n = d3_cross(dpdu, dpdv);
    if (d3_dot(n, n) == 0.0) /* a degenerate corner: the normal of the opposite triangle */
        n = d3_cross(d3_sub(p11, p10), d3_sub(p11, p01));
    out->p = f3(p);
    out->dpdu = f3(dpdu);
    out->dpdv = f3(dpdv);
    Vec3 ng = f3_unit(n);
    const double w[4] = {(1.0 - u) * (1.0 - v), u * (1.0 - v), (1.0 - u) * v, u * v};
    if (s->bl.has_n) {
        V3d ns = d3v(0.0, 0.0, 0.0);
        for (int i = 0; i < 4; i++)
            ns = d3v(ns.x + w[i] * (double)s->bl.n[i][0], ns.y + w[i] * (double)s->bl.n[i][1],
                     ns.z + w[i] * (double)s->bl.n[i][2]);
        out->ns = d3_dot(ns, ns) > 0.0 ? f3_unit(ns) : ng;
        if (v3_dot(ng, out->ns) < 0.0f) ng = v3_neg(ng);
        if (!(d3_dot(ns, ns) > 0.0)) out->ns = ng;
    } else {
        if (s->flip_normal) ng = v3_neg(ng);
        out->ns = ng;
    }
    out->n = ng;
    if (s->bl.has_uv) {
        double tu = 0.0, tv = 0.0;
        for (int i = 0; i < 4; i++) tu += w[i] * (double)s->bl.uv[i][0], tv += w[i] * (double)s->bl.uv[i][1];
        out->uv = v2((float)tu, (float)tv);
    } else {
        out->uv = v2((float)u, (float)v);
    }
}

/* |dp/du x dp/dv| at (u, v): the area element of the patch's parameterisation. */
static double bilinear_jacobian(const AnalyticShape *s, double u, double v)
{
    const V3d p00 = bl_corner(s, 0), p10 = bl_corner(s, 1), p01 = bl_corner(s, 2), p11 = bl_corner(s, 3);
    return d3_len(d3_cross(d3_lerp(v, d3_sub(p10, p00), d3_sub(p11, p01)), d3_lerp(u, d3_sub(p01, p00), d3_sub(p11, p10))));
}

static double bilinear_area(const AnalyticShape *s)
{
    /* composite Simpson, 64 intervals per parameter (weights 1 4 2 4 ... 4 1) / 3 */
    enum { N = 64 };
    double sum = 0.0;
    for (int i = 0; i <= N; i++) {
        double wi = (i == 0 || i == N) ? 1.0 : (i % 2 ? 4.0 : 2.0);
        for (int j = 0; j <= N; j++) {
            double wj = (j == 0 || j == N) ? 1.0 : (j % 2 ? 4.0 : 2.0);
            sum += wi * wj * bilinear_jacobian(s, (double)i / N, (double)j / N);
        }
    }
    return sum / (9.0 * N * N);
}

/* ------------------------------------------------------------ construction */

static BBox object_bounds(const ShapeParams *p)
{
    float r = p->radius;
    BBox b;
    switch (p->type) {
    case SHAPE_TAG_DISK: b.min = v3(-r, -r, p->height); b.max = v3(r, r, p->height); break;
    case SHAPE_TAG_TORUS: {
        float e = r + p->minor_radius;
        b.min = v3(-e, -e, -p->minor_radius); b.max = v3(e, e, p->minor_radius);
        break;
    }
    default: b.min = v3(-r, -r, p->z_min); b.max = v3(r, r, p->z_max); break;
    }
    return b;
}

bool shape_init(AnalyticShape *s, const ShapeParams *p, const Transform *o2w)
{
    if (!(p->radius > 0.0f) || !isfinite(p->radius) || !(p->phi_max > 0.0f) ||
        !((double)p->phi_max <= TWO_PI_D + 1e-6) || (unsigned)p->type >= SHAPE_TAG_COUNT ||
        p->type == SHAPE_TAG_BILINEAR || p->type == SHAPE_TAG_SDF || p->type == SHAPE_TAG_CURVE) /* shape_init_bilinear, _sdf, _curve */
        return false;
    *s = (AnalyticShape){0};
    s->p = *p;
    if (s->p.phi_max > 2.0f * CST_PI) s->p.phi_max = 2.0f * CST_PI;
    switch (p->type) {
    case SHAPE_TAG_BILINEAR:
    case SHAPE_TAG_SDF: return false; /* not a quadric: handled before */
    case SHAPE_TAG_TORUS:
        if (!(p->minor_radius > 0.0f && p->minor_radius < p->radius)) return false;
        s->p.phi_max = 2.0f * CST_PI;
        s->r_minor = (double)p->minor_radius;
        break;
    case SHAPE_TAG_CURVE: return false; /* not a quadric: handled before */
    case SHAPE_TAG_CYLINDER:
        if (!(p->z_min < p->z_max) || !isfinite(p->z_min) || !isfinite(p->z_max)) return false;
        break;
    case SHAPE_TAG_DISK:
        if (!(p->inner_radius >= 0.0f && p->inner_radius < p->radius) || !isfinite(p->height)) return false;
        break;
    case SHAPE_TAG_SPHERE: {
        /* pbrt-v4 Sphere: z range clamped to the sphere, in either order. */
        float r = p->radius, lo = clampf(minf(p->z_min, p->z_max), -r, r), hi = clampf(maxf(p->z_min, p->z_max), -r, r);
        if (!(lo < hi)) return false;
        s->p.z_min = lo; s->p.z_max = hi;
        s->theta_z_min = acos(fmax(-1.0, fmin(1.0, (double)lo / (double)r)));
        s->theta_z_max = acos(fmax(-1.0, fmin(1.0, (double)hi / (double)r)));
        break;
    }
    }
    s->r = (double)s->p.radius; s->z_min = (double)s->p.z_min; s->z_max = (double)s->p.z_max;
    s->height = (double)s->p.height; s->r_inner = (double)s->p.inner_radius; s->phi_max = (double)s->p.phi_max;
    double m[3][3], det;
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) m[i][j] = s->o2w[i][j] = (double)o2w->m[i][j];
        s->o2w[i][3] = (double)o2w->m[i][3];
    }
    det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
          m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 1e-30) || !isfinite(det)) return false;
    double inv[3][3] = {
        {(m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det},
        {(m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det},
        {(m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det}};
    for (int i = 0; i < 3; i++) {
        for (int j = 0; j < 3; j++) s->w2o[i][j] = inv[i][j];
        s->w2o[i][3] = -(inv[i][0] * s->o2w[0][3] + inv[i][1] * s->o2w[1][3] + inv[i][2] * s->o2w[2][3]);
    }
    /* pbrt-v4 flips the normal for ReverseOrientation and for a handedness-swapping
     * transform, so n stays cross(dp/du, dp/dv) of the world surface up to the former. */
    s->flip_normal = p->reverse_orientation != (det < 0.0);
    /* World bounds: the eight corners of the object box in double, then widened by a
     * relative 2^-20 (and an absolute floor) so that rounding the corners to float cannot
     * cut off a point the double-precision test reports. */
    BBox ob = object_bounds(&s->p), wb = bbox_empty();
    double lo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, hi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (int c = 0; c < 8; c++) {
        V3d q = map_point(s->o2w, d3(v3((c & 1) ? ob.max.x : ob.min.x, (c & 2) ? ob.max.y : ob.min.y,
                                        (c & 4) ? ob.max.z : ob.min.z)));
        double w[3] = {q.x, q.y, q.z};
        for (int k = 0; k < 3; k++) { lo[k] = fmin(lo[k], w[k]); hi[k] = fmax(hi[k], w[k]); }
    }
    double ext = 0.0;
    for (int k = 0; k < 3; k++) ext = fmax(ext, fmax(fabs(lo[k]), fabs(hi[k])));
    double pad = ext * 0x1p-20 + 1e-30;
    wb.min = v3((float)(lo[0] - pad), (float)(lo[1] - pad), (float)(lo[2] - pad));
    wb.max = v3((float)(hi[0] + pad), (float)(hi[1] + pad), (float)(hi[2] + pad));
    s->bounds = wb;
    return v3_is_finite(wb.min) && v3_is_finite(wb.max);
}

/* ------------------------------------------------------------ curves */

bool shape_init_curve(AnalyticShape *s, const Vec3 whole_cp[4], float u0, float u1, float w0, float w1,
                      CurveType type, const Vec3 *n, bool flip)
{
    *s = (AnalyticShape){0};
    s->p.type = SHAPE_TAG_CURVE;
    s->p.reverse_orientation = flip;
    s->flip_normal = flip;
    if (!curve_init(&s->cv, whole_cp, u0, u1, w0, w1, type, n, flip)) return false;
    s->bounds = curve_bounds(&s->cv);
    return true;
}

/* ------------------------------------------------------------ intersection */

/* Roots of a t^2 + b t + c with discriminant disc >= 0 given (so callers can compute it
 * in the cancellation-free form), in the stable form q = -(b + sign(b) sqrt(disc)) / 2
 * (pbrt-v4 Quadratic()). Returns t0 <= t1. */
static inline void quadratic_roots(double a, double b, double c, double disc, double *t0, double *t1)
{
    double q = -0.5 * (b + copysign(sqrt(disc), b));
    double r0 = q / a, r1 = q != 0.0 ? c / q : r0;
    if (r0 > r1) { double tmp = r0; r0 = r1; r1 = tmp; }
    *t0 = r0; *t1 = r1;
}

static inline double phi_of(double x, double y)
{
    double phi = atan2(y, x);
    return phi < 0.0 ? phi + TWO_PI_D : phi;
}

/* Whether the object-space point at t lies on the clipped shape; its (u, v) if so. */
static bool clip_and_uv(const AnalyticShape *s, V3d o, V3d d, double t, float *u, float *v)
{
    const ShapeParams *p = &s->p;
    (void)p;
    V3d h = d3v(o.x + t * d.x, o.y + t * d.y, o.z + t * d.z);
    switch (p->type) {
    case SHAPE_TAG_BILINEAR:
    case SHAPE_TAG_TORUS:
    case SHAPE_TAG_SDF:
    case SHAPE_TAG_CURVE: return false; /* not a quadric: handled before */
    case SHAPE_TAG_CYLINDER: {
        if (h.z < s->z_min || h.z > s->z_max) return false;
        double phi = phi_of(h.x, h.y);
        if (phi > s->phi_max) return false;
        *u = (float)(phi / s->phi_max);
        *v = (float)((h.z - s->z_min) / (s->z_max - s->z_min));
        return true;
    }
    case SHAPE_TAG_DISK: {
        double rho2 = h.x * h.x + h.y * h.y;
        if (rho2 > s->r * s->r || rho2 < s->r_inner * s->r_inner) return false;
        double phi = phi_of(h.x, h.y);
        if (phi > s->phi_max) return false;
        *u = (float)(phi / s->phi_max);
        *v = (float)((s->r - sqrt(rho2)) / (s->r - s->r_inner));
        return true;
    }
    case SHAPE_TAG_SPHERE: {
        if (h.z < s->z_min || h.z > s->z_max) return false;
        /* pbrt-v4: a hit at a pole has phi 0 (x nudged off zero). */
        double x = (h.x == 0.0 && h.y == 0.0) ? 1e-5 * s->r : h.x;
        double phi = phi_of(x, h.y);
        if (phi > s->phi_max) return false;
        double theta = acos(fmax(-1.0, fmin(1.0, h.z / s->r)));
        *u = (float)(phi / s->phi_max);
        *v = (float)((theta - s->theta_z_min) / (s->theta_z_max - s->theta_z_min));
        return true;
    }
    }
    return false;
}

/* The torus (x^2 + y^2 + z^2 + R^2 - r^2)^2 - 4 R^2 (x^2 + y^2) = 0 along the object-space
 * ray: a quartic in t. The ray is first clipped to the torus' object box [t0, t1] (t0 from
 * t_min and the box alone, never t_max, so every back end solves the same quartic) and the
 * quartic written in s = t - t0 about the clipped start q = o + t0 d, which keeps its
 * coefficients of the size of the torus however far the ray starts. With G(s) = |q + s d|^2
 * + R^2 - r^2 = a s^2 + b s + c and H(s) = x^2 + y^2 = a' s^2 + b' s + c': G^2 - 4 R^2 H. */
static bool torus_intersect(const AnalyticShape *s, V3d o, V3d d, const Ray *r, float *t_out, float *u, float *v)
{
    const double R = s->r, rm = s->r_minor, e[3] = {R + rm, R + rm, rm};
    const double oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
    double t0 = (double)r->t_min, t1 = HUGE_VAL;
    for (int k = 0; k < 3; k++) {
        if (dd[k] == 0.0) {
            if (fabs(oo[k]) > e[k]) return false;
            continue;
        }
        double ta = (-e[k] - oo[k]) / dd[k], tb = (e[k] - oo[k]) / dd[k];
        if (ta > tb) { double tmp = ta; ta = tb; tb = tmp; }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
    }
    if (!(t0 <= t1) || !isfinite(t1)) return false;
    const V3d q = d3v(o.x + t0 * d.x, o.y + t0 * d.y, o.z + t0 * d.z);
    const double a = d3_dot(d, d), b = 2.0 * d3_dot(q, d), c = d3_dot(q, q) + R * R - rm * rm;
    const double axy = d.x * d.x + d.y * d.y, bxy = 2.0 * (q.x * d.x + q.y * d.y), cxy = q.x * q.x + q.y * q.y;
    const double r4 = 4.0 * R * R;
    const double coef[5] = {c * c - r4 * cxy, 2.0 * b * c - r4 * bxy, b * b + 2.0 * a * c - r4 * axy, 2.0 * a * b, a * a};
    double roots[4];
    const int n = poly_roots(coef, 4, 0.0, t1 - t0, roots);
    for (int i = 0; i < n; i++) {
        const double th = t0 + roots[i];
        const float tf = (float)th;
        /* The float t must itself lie in the open interval: every back end compares it so. */
        if (!(tf > r->t_min && tf < r->t_max)) continue;
        const V3d h = d3v(o.x + th * d.x, o.y + th * d.y, o.z + th * d.z);
        double theta = atan2(h.z, sqrt(h.x * h.x + h.y * h.y) - R);
        if (theta < 0.0) theta += TWO_PI_D;
        *u = (float)(phi_of(h.x, h.y) / TWO_PI_D);
        *v = (float)(theta / TWO_PI_D);
        *t_out = tf;
        return true;
    }
    return false;
}

bool shape_intersect(const AnalyticShape *s, const Ray *r, float *t_out, float *u, float *v)
{
    if (s->p.type == SHAPE_TAG_BILINEAR) return bilinear_intersect(s, r, t_out, u, v);
    if (s->p.type == SHAPE_TAG_SDF) {
        *u = *v = 0.0f; /* shape_surface rebuilds everything from t */
        return sdf_intersect(s->sdf, r, t_out);
    }
    if (s->p.type == SHAPE_TAG_CURVE) return curve_intersect(&s->cv, r, t_out, u, v);
    V3d o = map_point(s->w2o, d3(r->o)), d = map_vector(s->w2o, d3(r->d));
    if (s->p.type == SHAPE_TAG_TORUS) return torus_intersect(s, o, d, r, t_out, u, v);
    const double tmin = (double)r->t_min, tmax = (double)r->t_max;
    const ShapeParams *p = &s->p;
    (void)p;
    double t0, t1;
    if (p->type == SHAPE_TAG_DISK) {
        if (d.z == 0.0) return false;
        t0 = (s->height - o.z) / d.z;
        if (!(t0 > tmin && t0 < tmax)) return false;
        if (!clip_and_uv(s, o, d, t0, u, v)) return false;
        *t_out = (float)t0;
        return *t_out > r->t_min && *t_out < r->t_max;
    }
    /* The discriminant as 4 a (r^2 - |f - (f.d / a) d|^2) over the coordinates that count
     * (x, y for cylinders): no cancellation of b^2 against 4ac for shapes small against
     * their distance (Haines et al., Ray Tracing Gems ch. 7, eq. 7.5; pbrt-v4 §6.2.2). */
    const bool cyl = p->type == SHAPE_TAG_CYLINDER;
    const double dz = cyl ? 0.0 : d.z, oz = cyl ? 0.0 : o.z;
    const double a = d.x * d.x + d.y * d.y + dz * dz;
    if (a == 0.0) return false;
    const double b = 2.0 * (d.x * o.x + d.y * o.y + dz * oz);
    const double r2 = s->r * s->r;
    const double c = o.x * o.x + o.y * o.y + oz * oz - r2;
    const double k = b / (2.0 * a);
    const double fx = o.x - k * d.x, fy = o.y - k * d.y, fz = oz - k * dz;
    const double disc = 4.0 * a * (r2 - (fx * fx + fy * fy + fz * fz));
    if (disc < 0.0) return false;
    quadratic_roots(a, b, c, disc, &t0, &t1);
    /* The float t must itself lie in the open interval: every back end compares it so. */
    const double roots[2] = {t0, t1};
    for (int i = 0; i < 2; i++) {
        float tf = (float)roots[i];
        if (!(tf > r->t_min && tf < r->t_max)) continue;
        if (!clip_and_uv(s, o, d, roots[i], u, v)) continue;
        *t_out = tf;
        return true;
    }
    return false;
}

/* ------------------------------------------------------------ surface */

/* Object-space point, dp/du, dp/dv and unit normal at phi and q: the cylinder's z, the
 * disk's radius or the sphere's z. */
static void surface_object(const AnalyticShape *s, double phi, double q, V3d *pt, V3d *dpdu, V3d *dpdv, V3d *n)
{
    const ShapeParams *p = &s->p;
    (void)p;
    const double pm = s->phi_max, cp = cos(phi), sp = sin(phi);
    switch (p->type) {
    case SHAPE_TAG_BILINEAR:
    case SHAPE_TAG_SDF: return; /* not a quadric: bilinear_surface, sdf_surface */
    case SHAPE_TAG_TORUS: { /* q: the angle theta about the tube, from the outer equator toward +z */
        const double R = s->r, rm = s->r_minor, ct = cos(q), st = sin(q), rho = R + rm * ct;
        *pt = d3v(rho * cp, rho * sp, rm * st);
        *dpdu = d3v(-TWO_PI_D * pt->y, TWO_PI_D * pt->x, 0.0);
        *dpdv = d3v(-TWO_PI_D * rm * st * cp, -TWO_PI_D * rm * st * sp, TWO_PI_D * rm * ct);
        *n = d3v(ct * cp, ct * sp, st); /* = dp/du x dp/dv, normalised */
        return;
    }
    case SHAPE_TAG_CURVE: return; /* not a quadric: bilinear_surface, curve_surface */
    case SHAPE_TAG_CYLINDER:
        *pt = d3v(s->r * cp, s->r * sp, q);
        *dpdu = d3v(-pm * pt->y, pm * pt->x, 0.0);
        *dpdv = d3v(0.0, 0.0, s->z_max - s->z_min);
        *n = d3v(cp, sp, 0.0);
        return;
    case SHAPE_TAG_DISK:
        *pt = d3v(q * cp, q * sp, s->height);
        *dpdu = d3v(-pm * pt->y, pm * pt->x, 0.0);
        *dpdv = d3v((s->r_inner - s->r) * cp, (s->r_inner - s->r) * sp, 0.0);
        *n = d3v(0.0, 0.0, 1.0);
        return;
    case SHAPE_TAG_SPHERE: {
        double r = s->r, z = fmax(-r, fmin(r, q)), rho = sqrt(fmax(0.0, r * r - z * z));
        double theta = acos(z / r), sin_t = sin(theta);
        *pt = d3v(rho * cp, rho * sp, z);
        *dpdu = d3v(-pm * pt->y, pm * pt->x, 0.0);
        double dt = s->theta_z_max - s->theta_z_min;
        *dpdv = d3v(dt * z * cp, dt * z * sp, -dt * r * sin_t);
        *n = d3v(pt->x / r, pt->y / r, pt->z / r);
        return;
    }
    }
}

static void surface_world(const AnalyticShape *s, V3d pt, V3d dpdu, V3d dpdv, V3d n, Vec2 uv, ShapeSurface *out)
{
    out->p = f3(map_point(s->o2w, pt));
    out->dpdu = f3(map_vector(s->o2w, dpdu));
    out->dpdv = f3(map_vector(s->o2w, dpdv));
    Vec3 nw = f3_unit(map_normal(s->w2o, n));
    out->n = s->flip_normal ? v3_neg(nw) : nw;
    out->ns = out->n;
    out->uv = uv;
}

void shape_surface(const AnalyticShape *s, const Ray *r, float t, ShapeSurface *out)
{
    if (s->p.type == SHAPE_TAG_SDF) {
        sdf_surface(s->sdf, r, t, &out->p, &out->n, &out->uv);
        /* dp/du, dp/dv: a tangent frame about n (the field has no parameterisation) */
        Vec3 a = fabsf(out->n.x) > 0.9f ? v3(0.0f, 1.0f, 0.0f) : v3(1.0f, 0.0f, 0.0f);
        out->dpdu = v3_normalize(v3_cross(a, out->n));
        out->dpdv = v3_cross(out->n, out->dpdu);
        out->ns = out->n;
        return;
    }
    if (s->p.type == SHAPE_TAG_BILINEAR) {
        /* The patch parameters of the hit at t: the same test on the interval holding only
         * the float t (bit-identical arithmetic, so the same root); pbrt-v4 likewise builds
         * the surface from the hit's (u, v). */
        Ray rr = *r;
        rr.t_min = nextafterf(t, -INFINITY);
        rr.t_max = nextafterf(t, INFINITY);
        float tt, u = 0.5f, v = 0.5f;
        (void)bilinear_intersect(s, &rr, &tt, &u, &v);
        bilinear_surface(s, (double)u, (double)v, out);
        return;
    }
    if (s->p.type == SHAPE_TAG_CURVE) {
        /* (u, v) of the hit at t: the same test on an interval ending just past t (the
         * same arithmetic, so the same closest hit), as for the patches above. */
        Ray rr = *r;
        rr.t_max = nextafterf(t, INFINITY);
        float tt, u = 0.5f, v = 0.5f;
        (void)curve_intersect(&s->cv, &rr, &tt, &u, &v);
        curve_surface(&s->cv, r, t, u, v, &out->p, &out->n, &out->dpdu, &out->dpdv);
        out->ns = out->n;
        out->uv = v2(u, v);
        return;
    }
    V3d o = map_point(s->w2o, d3(r->o)), d = map_vector(s->w2o, d3(r->d));
    V3d h = d3v(o.x + (double)t * d.x, o.y + (double)t * d.y, o.z + (double)t * d.z);
    const ShapeParams *p = &s->p;
    (void)p;
    double phi, q;
    Vec2 uv;
    /* Reprojection onto the surface (pbrt-v4 §6.8.5): only the phi and the height (or the
     * disk's radius) of the float hit are kept, the point is rebuilt on the surface. */
    switch (p->type) {
    case SHAPE_TAG_TORUS: /* reprojected: the hit's phi and tube angle kept, the point rebuilt */
        phi = phi_of(h.x, h.y);
        q = atan2(h.z, sqrt(h.x * h.x + h.y * h.y) - s->r);
        if (q < 0.0) q += TWO_PI_D;
        uv = v2((float)(phi / TWO_PI_D), (float)(q / TWO_PI_D));
        break;
    case SHAPE_TAG_CYLINDER:
        phi = phi_of(h.x, h.y);
        q = fmax(s->z_min, fmin(s->z_max, h.z));
        uv = v2((float)(phi / s->phi_max), (float)((q - s->z_min) / (s->z_max - s->z_min)));
        break;
    case SHAPE_TAG_DISK:
        phi = phi_of(h.x, h.y);
        q = fmax(s->r_inner, fmin(s->r, sqrt(h.x * h.x + h.y * h.y)));
        uv = v2((float)(phi / s->phi_max), (float)((s->r - q) / (s->r - s->r_inner)));
        break;
    default: {
        /* Scaled onto the sphere along the hit's own direction from the centre (pbrt-v4
         * §6.2.2), so the point is as accurate as that direction. */
        const double r0 = s->r, len = d3_len(h), pm = s->phi_max;
        V3d pt = len > 0.0 ? d3v(h.x * r0 / len, h.y * r0 / len, h.z * r0 / len) : d3v(0.0, 0.0, r0);
        phi = (pt.x == 0.0 && pt.y == 0.0) ? 0.0 : phi_of(pt.x, pt.y);
        double z = fmax(s->z_min, fmin(s->z_max, pt.z));
        double theta = acos(fmax(-1.0, fmin(1.0, z / r0)));
        uv = v2((float)(phi / pm), (float)((theta - s->theta_z_min) / (s->theta_z_max - s->theta_z_min)));
        double rho = sqrt(pt.x * pt.x + pt.y * pt.y), cp = rho > 0.0 ? pt.x / rho : 1.0, sp = rho > 0.0 ? pt.y / rho : 0.0;
        double dt = s->theta_z_max - s->theta_z_min;
        V3d dpdu = d3v(-pm * pt.y, pm * pt.x, 0.0), dpdv = d3v(dt * pt.z * cp, dt * pt.z * sp, -dt * r0 * sin(theta));
        surface_world(s, pt, dpdu, dpdv, d3v(pt.x / r0, pt.y / r0, pt.z / r0), uv, out);
        return;
    }
    }
    V3d pt, dpdu, dpdv, n;
    surface_object(s, phi, q, &pt, &dpdu, &dpdv, &n);
    surface_world(s, pt, dpdu, dpdv, n, uv, out);
}

void shape_surface_at(const AnalyticShape *s, Vec2 uv, ShapeSurface *out)
{
    if (s->p.type == SHAPE_TAG_BILINEAR) {
        bilinear_surface(s, (double)uv.x, (double)uv.y, out);
        return;
    }
    if (s->p.type == SHAPE_TAG_SDF) { /* not parameterised: never sampled (not emitting) */
        *out = (ShapeSurface){0};
        return;
    }
    if (s->p.type == SHAPE_TAG_CURVE) { /* no ray: the centre line, its tangent, a width across */
        const float u = clampf(uv.x, s->cv.u0, s->cv.u1), span = s->cv.u1 - s->cv.u0;
        out->p = curve_eval(s->cv.cp, (u - s->cv.u0) / span, NULL);
        curve_derivatives(&s->cv, u, &out->dpdu, &out->dpdv);
        Vec3 n = v3_cross(out->dpdu, out->dpdv);
        out->n = out->ns = v3_length2(n) > 0.0f ? v3_normalize(n) : v3(0.0f, 0.0f, 1.0f);
        out->uv = uv;
        return;
    }
    const ShapeParams *p = &s->p;
    (void)p;
    double phi = (double)uv.x * s->phi_max, q;
    switch (p->type) {
    case SHAPE_TAG_CYLINDER: q = s->z_min + (double)uv.y * (s->z_max - s->z_min); break;
    case SHAPE_TAG_DISK: q = s->r - (double)uv.y * (s->r - s->r_inner); break;
    case SHAPE_TAG_TORUS: q = (double)uv.y * TWO_PI_D; break;
    default: q = s->r * cos(s->theta_z_min + (double)uv.y * (s->theta_z_max - s->theta_z_min)); break;
    }
    V3d pt, dpdu, dpdv, n;
    surface_object(s, phi, q, &pt, &dpdu, &dpdv, &n);
    surface_world(s, pt, dpdu, dpdv, n, uv, out);
}

bool shape_dnduv(const AnalyticShape *s, Vec2 uv, Vec3 *dndu, Vec3 *dndv)
{
    *dndu = *dndv = v3s(0.0f);
    double phi = (double)uv.x * s->phi_max, q, ir = 0.0, ir_v = 0.0;
    switch (s->p.type) {
    case SHAPE_TAG_CYLINDER: /* n = (cos phi, sin phi, 0): dn/du = dp/du / r, dn/dv = 0 */
        q = s->z_min + (double)uv.y * (s->z_max - s->z_min), ir = 1.0 / s->r;
        break;
    case SHAPE_TAG_SPHERE: /* n = p / r: dn/du = dp/du / r, dn/dv = dp/dv / r */
        q = s->r * cos(s->theta_z_min + (double)uv.y * (s->theta_z_max - s->theta_z_min));
        ir = ir_v = 1.0 / s->r;
        break;
    case SHAPE_TAG_TORUS: { /* n = (cos t cos phi, cos t sin phi, sin t): dn/dv = dp/dv / r_minor */
        q = (double)uv.y * TWO_PI_D;
        V3d pt, dpdu, dpdv, n;
        surface_object(s, phi, q, &pt, &dpdu, &dpdv, &n);
        const double ct = cos(q), im = 1.0 / s->r_minor;
        *dndu = f3(map_normal(s->w2o, d3v(-TWO_PI_D * ct * sin(phi), TWO_PI_D * ct * cos(phi), 0.0)));
        *dndv = f3(map_normal(s->w2o, d3v(dpdv.x * im, dpdv.y * im, dpdv.z * im)));
        return true;
    }
    case SHAPE_TAG_DISK: return true; /* flat */
    default: return false;
    }
    V3d pt, dpdu, dpdv, n;
    surface_object(s, phi, q, &pt, &dpdu, &dpdv, &n);
    *dndu = f3(map_normal(s->w2o, d3v(dpdu.x * ir, dpdu.y * ir, dpdu.z * ir)));
    *dndv = f3(map_normal(s->w2o, d3v(dpdv.x * ir_v, dpdv.y * ir_v, dpdv.z * ir_v)));
    return true;
}

/* ------------------------------------------------------------ area and sampling */

static double object_area(const AnalyticShape *s)
{
    const ShapeParams *p = &s->p;
    (void)p;
    switch (p->type) {
    case SHAPE_TAG_CYLINDER: return s->phi_max * s->r * (s->z_max - s->z_min);
    case SHAPE_TAG_DISK:
        return 0.5 * s->phi_max * (s->r * s->r - s->r_inner * s->r_inner);
    case SHAPE_TAG_TORUS: return TWO_PI_D * TWO_PI_D * s->r * s->r_minor; /* Pappus: 2 pi R x 2 pi r */
    default: return s->phi_max * s->r * (s->z_max - s->z_min);
    }
}

/* dA_world / dA_object at a point with object normal n: |det M| |M^-T n| (the area
 * element of a linear map). Constant for similarity transforms. */
static double area_factor(const AnalyticShape *s, V3d n)
{
    const double (*m)[4] = s->o2w;
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    return fabs(det) * d3_len(map_normal(s->w2o, n));
}

float shape_area(const AnalyticShape *s)
{
    if (s->p.type == SHAPE_TAG_BILINEAR) return (float)bilinear_area(s);
    if (s->p.type == SHAPE_TAG_SDF) return 0.0f; /* not emitting: never needed */
    if (s->p.type == SHAPE_TAG_CURVE) return 0.0f; /* curves do not emit */
    /* The factor at the middle of the parameter domain: exact for similarity transforms. */
    const ShapeParams *p = &s->p;
    (void)p;
    double phi = 0.5 * s->phi_max, z = 0.5 * (s->z_min + s->z_max);
    V3d n = p->type == SHAPE_TAG_DISK ? d3v(0.0, 0.0, 1.0) : d3v(cos(phi), sin(phi), 0.0);
    if (p->type == SHAPE_TAG_SPHERE) {
        double rho = sqrt(fmax(0.0, s->r * s->r - z * z));
        n = d3v(rho * cos(phi) / s->r, rho * sin(phi) / s->r, z / s->r);
    }
    return (float)(object_area(s) * area_factor(s, n));
}

bool shape_uniform_area(const AnalyticShape *s)
{
    if (s->p.type == SHAPE_TAG_BILINEAR || s->p.type == SHAPE_TAG_SDF || s->p.type == SHAPE_TAG_CURVE) return false;
    /* M^T M = k^2 I for a similarity: the columns orthogonal and of one length. */
    double g[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            g[i][j] = s->o2w[0][i] * s->o2w[0][j] + s->o2w[1][i] * s->o2w[1][j] + s->o2w[2][i] * s->o2w[2][j];
    double k2 = (g[0][0] + g[1][1] + g[2][2]) / 3.0;
    if (!(k2 > 0.0) || !isfinite(k2)) return false;
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++)
            if (fabs(g[i][j] - (i == j ? k2 : 0.0)) > 1e-5 * k2) return false;
    return true;
}

void shape_sample_area(const AnalyticShape *s, Vec2 u, ShapeSurface *out, float *pdf_a)
{
    const ShapeParams *p = &s->p;
    (void)p;
    Vec2 uv;
    switch (p->type) {
    case SHAPE_TAG_SDF: /* not emitting: never sampled */
        *out = (ShapeSurface){0};
        *pdf_a = 0.0f;
        return;
    case SHAPE_TAG_BILINEAR:
        /* uniform in (u, v): density 1 / |dp/du x dp/dv| per area (shape_pdf_area) */
        bilinear_surface(s, (double)u.x, (double)u.y, out);
        *pdf_a = shape_pdf_area(s, out);
        return;
    case SHAPE_TAG_CURVE: /* not sampled: curves do not emit */
        shape_surface_at(s, u, out);
        *pdf_a = 0.0f;
        return;
    case SHAPE_TAG_DISK: {
        /* Uniform in the annulus: rho^2 uniform in [ri^2, r^2] (pbrt-v4 samples the full
         * disk and ignores innerradius; this keeps the points on the surface). */
        double ri2 = s->r_inner * s->r_inner, r2 = s->r * s->r;
        double rho = sqrt(ri2 + (double)u.y * (r2 - ri2));
        uv = v2(u.x, (float)((s->r - rho) / (s->r - s->r_inner)));
        break;
    }
    case SHAPE_TAG_SPHERE: {
        /* z uniform in [z_min, z_max] is uniform in area (Archimedes); v is theta's. */
        double z = s->z_min + (double)u.y * (s->z_max - s->z_min);
        double theta = acos(fmax(-1.0, fmin(1.0, z / s->r)));
        uv = v2(u.x, (float)((theta - s->theta_z_min) / (s->theta_z_max - s->theta_z_min)));
        break;
    }
    default: uv = u; break;
    }
    shape_surface_at(s, uv, out);
    *pdf_a = shape_pdf_area(s, out);
}

float shape_pdf_area(const AnalyticShape *s, const ShapeSurface *sf)
{
    if (s->p.type == SHAPE_TAG_SDF) return 0.0f;
    if (s->p.type == SHAPE_TAG_CURVE) return 0.0f;
    if (s->p.type == SHAPE_TAG_BILINEAR) {
        float j = v3_length(v3_cross(sf->dpdu, sf->dpdv));
        return j > 0.0f ? 1.0f / j : 0.0f;
    }
    /* The object normal at the point, back through the inverse map (n_obj ∝ M^T n_world). */
    V3d nw = d3(sf->n), n = d3v(s->o2w[0][0] * nw.x + s->o2w[1][0] * nw.y + s->o2w[2][0] * nw.z,
                                s->o2w[0][1] * nw.x + s->o2w[1][1] * nw.y + s->o2w[2][1] * nw.z,
                                s->o2w[0][2] * nw.x + s->o2w[1][2] * nw.y + s->o2w[2][2] * nw.z);
    double l = d3_len(n);
    if (l > 0.0) n = d3v(n.x / l, n.y / l, n.z / l);
    return (float)(1.0 / (object_area(s) * area_factor(s, n)));
}

/* ------------------------------------------------------------ signed-distance shapes */

void shape_init_sdf(AnalyticShape *s, SdfTree *tree)
{
    *s = (AnalyticShape){0};
    s->p.type = SHAPE_TAG_SDF;
    s->p.phi_max = 2.0f * CST_PI;
    s->sdf = tree;
    s->bounds = sdf_tree_bounds(tree);
}

void shape_release(AnalyticShape *s)
{
    if (s && s->p.type == SHAPE_TAG_SDF) {
        sdf_tree_destroy(s->sdf);
        s->sdf = NULL;
    }
}
