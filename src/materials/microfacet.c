/* GGX (Trowbridge-Reitz) distribution, anisotropic, with Smith masking-shadowing and
 * visible-normal sampling; formulas in microfacet.h. */
#include "materials/microfacet.h"

float ggx_d(Vec3 m, float ax, float ay)
{
    if (!(m.z > 0.0f)) return 0.0f;
    /* 1 / (pi ax ay (x^2/ax^2 + y^2/ay^2 + z^2)^2) (Heitz 2014 eq. 85), times (ax ay)^2 / (ax ay)^2:
     * ax ay / (pi (x^2 ay/ax + y^2 ax/ay + ax ay z^2)^2). The terms are x^2 and y^2 rather
     * than 1 - z^2 (m is a unit vector) so that narrow lobes keep their precision near
     * m = +z; for ax = ay the ratios are exactly 1 and the products those of the isotropic
     * alpha^2 / (pi (x^2 + y^2 + alpha^2 z^2)^2), bit for bit. */
    float a2 = ax * ay;
    float d = m.x * m.x * (ay / ax) + m.y * m.y * (ax / ay) + a2 * m.z * m.z;
    return a2 / (CST_PI * d * d);
}

float ggx_lambda(Vec3 w, float ax, float ay)
{
    float z2 = w.z * w.z;
    if (z2 == 0.0f) return INFINITY;
    /* alpha(phi)^2 tan^2(theta) with alpha(phi)^2 = cos^2 phi ax^2 + sin^2 phi ay^2 (Heitz
     * 2014 eq. 80); the isotropic case keeps its historical order of operations. */
    float a2_tan2 = ax == ay ? ax * ax * (w.x * w.x + w.y * w.y) / z2
                             : (ax * ax * (w.x * w.x) + ay * ay * (w.y * w.y)) / z2;
    return 0.5f * (sqrtf(1.0f + a2_tan2) - 1.0f);
}

float ggx_g1(Vec3 w, float ax, float ay) { return 1.0f / (1.0f + ggx_lambda(w, ax, ay)); }

float ggx_g2(Vec3 wo, Vec3 wi, float ax, float ay)
{
    return 1.0f / (1.0f + ggx_lambda(wo, ax, ay) + ggx_lambda(wi, ax, ay));
}

Vec3 ggx_sample_visible(Vec3 wo, float ax, float ay, Vec2 u)
{
    /* Stretch wo so the ellipsoid of normals becomes the hemisphere (Heitz 2018 sec. 3). */
    Vec3 vh = v3_normalize(v3(ax * wo.x, ay * wo.y, wo.z));
    /* An orthonormal basis around vh; T1 is horizontal. */
    float len2 = vh.x * vh.x + vh.y * vh.y;
    Vec3 t1 = len2 > 0.0f ? v3_scale(v3(-vh.y, vh.x, 0.0f), 1.0f / sqrtf(len2)) : v3(1.0f, 0.0f, 0.0f);
    Vec3 t2 = v3_cross(vh, t1);
    /* A point on the projected half disk: uniform on the disk, then the lower half is
     * squeezed by the foreshortening s of the hemisphere's projection. */
    float r = sqrtf(u.x), phi = 2.0f * CST_PI * u.y;
    float p1 = r * cosf(phi), p2 = r * sinf(phi);
    float s = 0.5f * (1.0f + vh.z);
    p2 = (1.0f - s) * safe_sqrtf(1.0f - p1 * p1) + s * p2;
    /* Back onto the hemisphere, then unstretch (normals transform with the inverse). */
    Vec3 nh = v3_add(v3_add(v3_scale(t1, p1), v3_scale(t2, p2)), v3_scale(vh, safe_sqrtf(1.0f - p1 * p1 - p2 * p2)));
    return v3_normalize(v3(ax * nh.x, ay * nh.y, maxf(nh.z, 0.0f)));
}

float ggx_visible_pdf(Vec3 wo, Vec3 m, float ax, float ay)
{
    if (wo.z == 0.0f) return 0.0f;
    return ggx_g1(wo, ax, ay) * fabsf(v3_dot(wo, m)) * ggx_d(m, ax, ay) / fabsf(wo.z);
}
