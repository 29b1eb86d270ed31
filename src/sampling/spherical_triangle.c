/* Spherical triangle sampling (Arvo 1995) and its inverse, in double: the formulas take
 * differences of cosines near 1 for small triangles, which float would round away; the
 * callers (lights/light.c) use them only for triangles of 3e-4 sr and more, as pbrt-v4. */
#include "sampling/spherical_triangle.h"

#include <math.h>

typedef struct D3 {
    double x, y, z;
} D3;

static D3 d3(Vec3 v) { return (D3){(double)v.x, (double)v.y, (double)v.z}; }
static double dot3(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
static D3 cross3(D3 a, D3 b) { return (D3){a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x}; }
static D3 madd3(D3 a, D3 b, double s) { return (D3){a.x + b.x * s, a.y + b.y * s, a.z + b.z * s}; }
static D3 scale3(D3 a, double s) { return (D3){a.x * s, a.y * s, a.z * s}; }
static double len3(D3 a) { return sqrt(dot3(a, a)); }
static D3 norm3(D3 a)
{
    double l = len3(a);
    return l > 0.0 ? scale3(a, 1.0 / l) : a;
}
static double clamp1(double x) { return x < -1.0 ? -1.0 : x > 1.0 ? 1.0 : x; }

/* The component of b orthogonal to unit a, normalised: the tangent at a toward b. */
static D3 tangent(D3 a, D3 b) { return norm3(madd3(b, a, -dot3(a, b))); }

static double area_d(D3 a, D3 b, D3 c)
{
    double num = fabs(dot3(a, cross3(b, c)));
    double den = 1.0 + dot3(a, b) + dot3(b, c) + dot3(c, a);
    return 2.0 * atan2(num, den);
}

float spherical_triangle_area(Vec3 a, Vec3 b, Vec3 c) { return (float)area_d(d3(a), d3(b), d3(c)); }

bool spherical_triangle_sample(Vec3 a_f, Vec3 b_f, Vec3 c_f, Vec2 u, Vec3 *w, float *solid_angle)
{
    D3 A = d3(a_f), B = d3(b_f), C = d3(c_f);
    double omega = area_d(A, B, C);
    *solid_angle = (float)omega;
    if (!(omega > 0.0)) return false;
    /* alpha: the triangle's angle at A, between the arcs toward B and toward C. */
    D3 tb = tangent(A, B), tc = tangent(A, C);
    double cos_alpha = clamp1(dot3(tb, tc)), sin_alpha = len3(cross3(tb, tc));
    double alpha = atan2(sin_alpha, cos_alpha);
    /* Arvo's eqs.: the sub-triangle A, B, C' of area A' = u.x Omega, C' on the arc A -> C
     * at cos(arc) = q from A. */
    double ap = (double)u.x * omega;
    double s = sin(ap - alpha), t = cos(ap - alpha);
    double uu = t - cos_alpha, vv = s + sin_alpha * dot3(A, B);
    double den = (vv * s + uu * t) * sin_alpha;
    double q = den != 0.0 ? clamp1(((vv * t - uu * s) * cos_alpha - vv) / den) : 1.0;
    D3 cp = madd3(scale3(A, q), tc, sqrt(fmax(0.0, 1.0 - q * q)));
    /* Then the point on the arc B -> C' with 1 - cos from B uniform in u.y. */
    double z = 1.0 - (double)u.y * (1.0 - dot3(cp, B));
    z = clamp1(z);
    D3 p = madd3(scale3(B, z), tangent(B, cp), sqrt(fmax(0.0, 1.0 - z * z)));
    p = norm3(p);
    *w = v3((float)p.x, (float)p.y, (float)p.z);
    return true;
}

Vec2 spherical_triangle_invert(Vec3 a_f, Vec3 b_f, Vec3 c_f, Vec3 w_f)
{
    D3 A = d3(a_f), B = d3(b_f), C = d3(c_f), W = norm3(d3(w_f));
    double omega = area_d(A, B, C);
    /* C': where the great circle through B and w meets the arc A -> C. */
    D3 cp = norm3(cross3(cross3(B, W), cross3(A, C)));
    if (dot3(cp, madd3(A, C, 1.0)) < 0.0) cp = scale3(cp, -1.0);
    double u0 = omega > 0.0 ? area_d(A, B, cp) / omega : 0.0;
    double den = 1.0 - dot3(cp, B);
    double u1 = den > 0.0 ? (1.0 - dot3(W, B)) / den : 0.0;
    u0 = u0 < 0.0 ? 0.0 : u0 > 1.0 ? 1.0 : u0;
    u1 = u1 < 0.0 ? 0.0 : u1 > 1.0 ? 1.0 : u1;
    return v2((float)u0, (float)u1);
}

/* x in [0, 1] with density proportional to (1 - x) a + x b (pbrt-v4 SampleLinear). */
static float sample_linear(float u, float a, float b)
{
    if (u == 0.0f && a == 0.0f) return 0.0f;
    float x = u * (a + b) / (a + sqrtf((1.0f - u) * a * a + u * b * b));
    return x < 0x1.fffffep-1f ? x : 0x1.fffffep-1f;
}

Vec2 warp_bilinear(Vec2 u, const float v[4])
{
    float y = sample_linear(u.y, v[0] + v[1], v[2] + v[3]);
    float x = sample_linear(u.x, (1.0f - y) * v[0] + y * v[2], (1.0f - y) * v[1] + y * v[3]);
    return v2(x, y);
}

float warp_bilinear_pdf(Vec2 p, const float v[4])
{
    float sum = v[0] + v[1] + v[2] + v[3];
    if (!(sum > 0.0f)) return 1.0f;
    return 4.0f *
           ((1.0f - p.x) * (1.0f - p.y) * v[0] + p.x * (1.0f - p.y) * v[1] + (1.0f - p.x) * p.y * v[2] +
            p.x * p.y * v[3]) /
           sum;
}
