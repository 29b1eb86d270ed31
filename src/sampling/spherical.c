/* Spherical triangle and rectangle sampling (spherical.h): Arvo 1995, Urena et al. 2013. */
#include "sampling/spherical.h"

#include <math.h>

static const double SPH_PI = 3.14159265358979323846;

typedef struct D3 { double x, y, z; } D3;

static inline D3 d3(double x, double y, double z) { D3 r = {x, y, z}; return r; }
static inline D3 d3_of(Vec3 v) { return d3((double)v.x, (double)v.y, (double)v.z); }
static inline D3 d3_sub(D3 a, D3 b) { return d3(a.x - b.x, a.y - b.y, a.z - b.z); }
static inline D3 d3_scale(D3 a, double s) { return d3(a.x * s, a.y * s, a.z * s); }
static inline D3 d3_madd(D3 a, D3 b, double s) { return d3(a.x + b.x * s, a.y + b.y * s, a.z + b.z * s); }
static inline double d3_dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static inline D3 d3_cross(D3 a, D3 b) { return d3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x); }
static inline double d3_len(D3 a) { return sqrt(d3_dot(a, a)); }
static inline double clampd(double v, double lo, double hi) { return v < lo ? lo : v > hi ? hi : v; }
static inline double safe_sqrt(double v) { return sqrt(v > 0.0 ? v : 0.0); }
/* The unit vector along a, or false for a zero (or non-finite) one. */
static inline bool d3_unit(D3 a, D3 *out)
{
    double l = d3_len(a);
    if (!(l > 0.0) || !isfinite(l)) return false;
    *out = d3_scale(a, 1.0 / l);
    return true;
}
/* Van Oosterom & Strackee's solid angle from unit directions a, b, c. */
static float solid_angle_of(D3 a, D3 b, D3 c)
{
    double num = fabs(d3_dot(a, d3_cross(b, c)));
    double den = 1.0 + d3_dot(a, b) + d3_dot(b, c) + d3_dot(c, a);
    return (float)fabs(2.0 * atan2(num, den));
}

static void d3_store(double out[3], D3 v) { out[0] = v.x; out[1] = v.y; out[2] = v.z; }
static D3 d3_load(const double v[3]) { return d3(v[0], v[1], v[2]); }

bool sph_tri_init(SphTri *t, Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2)
{
    D3 o = d3_of(x), a, b, c;
    t->solid_angle = 0.0f;
    if (!d3_unit(d3_sub(d3_of(p0), o), &a) || !d3_unit(d3_sub(d3_of(p1), o), &b) ||
        !d3_unit(d3_sub(d3_of(p2), o), &c))
        return false;
    d3_store(t->a, a);
    d3_store(t->b, b);
    d3_store(t->c, c);
    t->solid_angle = solid_angle_of(a, b, c);
    return true;
}

float sph_triangle_solid_angle(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2)
{
    SphTri t;
    (void)sph_tri_init(&t, x, p0, p1, p2);
    return t.solid_angle;
}

bool sph_triangle_sample(Vec3 x, Vec3 p0, Vec3 p1, Vec3 p2, Vec2 u, Vec3 *w)
{
    SphTri t;
    return sph_tri_init(&t, x, p0, p1, p2) && sph_tri_sample(&t, u, w);
}

bool sph_tri_sample(const SphTri *t, Vec2 u, Vec3 *w)
{
    D3 a = d3_load(t->a), b = d3_load(t->b), c = d3_load(t->c);
    /* Arvo's warp needs the spherical area A and the inner angle alpha at a only. A is the
     * solid angle sph_tri_init already has (Van Oosterom & Strackee's atan2, accurate for
     * small triangles, where Girard's excess alpha + beta + gamma - pi cancels), and it is
     * the very float the density 1 / A uses, so the warp and its density agree. alpha, the
     * angle between the planes through (a, b) and (a, c), comes as its cosine and sine
     * straight from the planes' unit normals (the dot and the cross product's length):
     * no inverse sines for alpha, beta, gamma and no sin(alpha), cos(alpha). */
    D3 n_ab, n_ca;
    if (!(t->solid_angle > 0.0f) || !d3_unit(d3_cross(a, b), &n_ab) || !d3_unit(d3_cross(c, a), &n_ca))
        return false;
    double cos_alpha = clampd(-d3_dot(n_ab, n_ca), -1.0, 1.0);
    double sin_alpha = d3_len(d3_cross(n_ab, n_ca));
    /* A_hat = u.x A, the sub-triangle's area (Arvo eq. 4). The paper's s and t with
     * phi = A_hat - alpha, through the sum formulas; carried as A_hat + pi (whose sine and
     * cosine are minus A_hat's), the form in which the cosine below was derived. */
    double area_hat = (double)u.x * (double)t->solid_angle;
    double sin_ap = -sin(area_hat), cos_ap = -cos(area_hat);
    double sin_phi = sin_ap * cos_alpha - cos_ap * sin_alpha;
    double cos_phi = cos_ap * cos_alpha + sin_ap * sin_alpha;
    double k1 = cos_phi + cos_alpha;
    double k2 = sin_phi - sin_alpha * d3_dot(a, b); /* a . b = cos of the side c */
    /* the cosine of the arc from a to the new vertex c_hat on the side a c (Arvo's q) */
    double den = (k2 * sin_phi + k1 * cos_phi) * sin_alpha;
    double cos_bp = den != 0.0 ? (k2 + (k2 * cos_phi - k1 * sin_phi) * cos_alpha) / den : 1.0;
    cos_bp = clampd(cos_bp, -1.0, 1.0);
    double sin_bp = safe_sqrt(1.0 - cos_bp * cos_bp);
    D3 c_perp;
    if (!d3_unit(d3_madd(c, a, -d3_dot(c, a)), &c_perp)) return false;
    D3 cp = d3_madd(d3_scale(a, cos_bp), c_perp, sin_bp);
    /* then a point on the arc from b to c_hat, cos theta uniform in [cos(b, c_hat), 1] */
    double cos_t = 1.0 - (double)u.y * (1.0 - d3_dot(cp, b));
    double sin_t = safe_sqrt(1.0 - cos_t * cos_t);
    D3 cp_perp;
    if (!d3_unit(d3_madd(cp, b, -d3_dot(cp, b)), &cp_perp)) {
        /* c_hat = b (u.x = 0): the sub-triangle is the vertex b */
        *w = v3((float)b.x, (float)b.y, (float)b.z);
        return true;
    }
    D3 r = d3_madd(d3_scale(b, cos_t), cp_perp, sin_t);
    if (!d3_unit(r, &r)) return false;
    *w = v3((float)r.x, (float)r.y, (float)r.z);
    return true;
}

bool sph_rect_init(SphRect *r, Vec3 x, Vec3 s, Vec3 ex, Vec3 ey)
{
    D3 dx = d3_of(ex), dy = d3_of(ey), ax, ay, az;
    double exl = d3_len(dx), eyl = d3_len(dy);
    if (!d3_unit(dx, &ax) || !d3_unit(dy, &ay) || !d3_unit(d3_cross(ax, ay), &az)) return false;
    D3 d = d3_sub(d3_of(s), d3_of(x));
    double z0 = d3_dot(d, az);
    /* z away from the rectangle, so that z0 < 0 (Urena et al. Algorithm 1) */
    if (z0 > 0.0) {
        az = d3_scale(az, -1.0);
        z0 = -z0;
    }
    if (!(z0 < 0.0)) return false;
    r->x0 = d3_dot(d, ax);
    r->y0 = d3_dot(d, ay);
    r->x1 = r->x0 + exl;
    r->y1 = r->y0 + eyl;
    r->z0 = z0;
    /* the normals of the four planes through x and each edge, and the inner angles */
    D3 v00 = d3(r->x0, r->y0, z0), v01 = d3(r->x0, r->y1, z0), v10 = d3(r->x1, r->y0, z0), v11 = d3(r->x1, r->y1, z0);
    D3 n0, n1, n2, n3;
    if (!d3_unit(d3_cross(v00, v10), &n0) || !d3_unit(d3_cross(v10, v11), &n1) ||
        !d3_unit(d3_cross(v11, v01), &n2) || !d3_unit(d3_cross(v01, v00), &n3))
        return false;
    double g0 = acos(clampd(-d3_dot(n0, n1), -1.0, 1.0)), g1 = acos(clampd(-d3_dot(n1, n2), -1.0, 1.0));
    double g2 = acos(clampd(-d3_dot(n2, n3), -1.0, 1.0)), g3 = acos(clampd(-d3_dot(n3, n0), -1.0, 1.0));
    r->b0 = n0.z;
    r->b1 = n2.z;
    r->k = 2.0 * SPH_PI - g2 - g3;
    r->solid_angle = g0 + g1 - r->k; /* the quadrilateral's angle excess */
    r->ax = v3((float)ax.x, (float)ax.y, (float)ax.z);
    r->ay = v3((float)ay.x, (float)ay.y, (float)ay.z);
    r->az = v3((float)az.x, (float)az.y, (float)az.z);
    r->o = x;
    return r->solid_angle > 0.0;
}

Vec3 sph_rect_sample(const SphRect *r, Vec2 u, Vec3 *p)
{
    /* the x coordinate: the sub-rectangle [x0, xu] has solid angle u.x S (Urena eqs. 8-9) */
    double au = (double)u.x * r->solid_angle + r->k;
    double fu = (cos(au) * r->b0 - r->b1) / sin(au);
    double cu = (fu > 0.0 ? 1.0 : -1.0) / sqrt(fu * fu + r->b0 * r->b0);
    cu = clampd(cu, -1.0, 1.0);
    double xu = -(cu * r->z0) / safe_sqrt(1.0 - cu * cu);
    xu = clampd(xu, r->x0, r->x1);
    /* then y uniform in h = cos of the angle to the y axis (Urena eq. 10) */
    double dd = sqrt(xu * xu + r->z0 * r->z0);
    double h0 = r->y0 / sqrt(dd * dd + r->y0 * r->y0), h1 = r->y1 / sqrt(dd * dd + r->y1 * r->y1);
    double hv = h0 + (double)u.y * (h1 - h0), hv2 = hv * hv;
    double yv = hv2 < 1.0 - 1e-12 ? hv * dd / sqrt(1.0 - hv2) : r->y1;
    yv = clampd(yv, r->y0, r->y1);
    D3 ax = d3_of(r->ax), ay = d3_of(r->ay), az = d3_of(r->az);
    D3 loc = d3_madd(d3_madd(d3_scale(ax, xu), ay, yv), az, r->z0);
    D3 o = d3_of(r->o);
    *p = v3((float)(o.x + loc.x), (float)(o.y + loc.y), (float)(o.z + loc.z));
    D3 w;
    if (!d3_unit(loc, &w)) w = d3_scale(az, -1.0);
    return v3((float)w.x, (float)w.y, (float)w.z);
}
