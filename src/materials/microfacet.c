/* GGX (Trowbridge-Reitz) distribution, Smith masking-shadowing and visible-normal sampling;
 * formulas in microfacet.h. */
#include "materials/microfacet.h"

float ggx_d(Vec3 m, float alpha)
{
    if (!(m.z > 0.0f)) return 0.0f;
    /* alpha^2 / (pi (cos^2 (alpha^2 - 1) + 1)^2), with 1 - cos^2 written as x^2 + y^2 (m is
     * a unit vector) so that narrow lobes keep their precision near m = +z. */
    float a2 = alpha * alpha;
    float d = m.x * m.x + m.y * m.y + a2 * m.z * m.z;
    return a2 / (CST_PI * d * d);
}

float ggx_lambda(Vec3 w, float alpha)
{
    float z2 = w.z * w.z;
    if (z2 == 0.0f) return INFINITY;
    float a2_tan2 = alpha * alpha * (w.x * w.x + w.y * w.y) / z2;
    return 0.5f * (sqrtf(1.0f + a2_tan2) - 1.0f);
}

float ggx_g1(Vec3 w, float alpha) { return 1.0f / (1.0f + ggx_lambda(w, alpha)); }

float ggx_g2(Vec3 wo, Vec3 wi, float alpha)
{
    return 1.0f / (1.0f + ggx_lambda(wo, alpha) + ggx_lambda(wi, alpha));
}

Vec3 ggx_sample_visible(Vec3 wo, float alpha, Vec2 u)
{
    /* Stretch wo so the ellipsoid of normals becomes the hemisphere (Heitz 2018 sec. 3). */
    Vec3 vh = v3_normalize(v3(alpha * wo.x, alpha * wo.y, wo.z));
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
    return v3_normalize(v3(alpha * nh.x, alpha * nh.y, maxf(nh.z, 0.0f)));
}

float ggx_visible_pdf(Vec3 wo, Vec3 m, float alpha)
{
    if (wo.z == 0.0f) return 0.0f;
    return ggx_g1(wo, alpha) * fabsf(v3_dot(wo, m)) * ggx_d(m, alpha) / fabsf(wo.z);
}
