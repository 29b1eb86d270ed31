/* BSDF lobes: Lambert, perfect mirror, smooth dielectric. */
#include "materials/bsdf.h"

#include "sampling/warp.h"

void bsdf_init(Bsdf *b, const Material *m, Vec3 n)
{
    b->type = m->type;
    b->frame = frame_from_normal(n);
    b->albedo = m->albedo;
    b->eta = m->ior;
}

/* Exact Fresnel equations for unpolarised light (pbrt-v4 eq. 9.4-9.5, averaged). */
float fresnel_dielectric(float cos_i, float eta)
{
    cos_i = clampf(cos_i, -1.0f, 1.0f);
    if (cos_i < 0.0f) { eta = 1.0f / eta; cos_i = -cos_i; }
    float sin2_i = 1.0f - cos_i * cos_i;
    float sin2_t = sin2_i / (eta * eta);
    if (sin2_t >= 1.0f) return 1.0f; /* total internal reflection */
    float cos_t = safe_sqrtf(1.0f - sin2_t);
    float r_par = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    float r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    return 0.5f * (r_par * r_par + r_perp * r_perp);
}

Rgb bsdf_eval(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (b->type != MATERIAL_DIFFUSE) return rgb_s(0.0f);
    float co = v3_dot(wo, b->frame.n), ci = v3_dot(wi, b->frame.n);
    /* Two-sided Lambert: reflection only, on whichever side wo is. */
    if (co * ci <= 0.0f) return rgb_s(0.0f);
    return rgb_scale(b->albedo, CST_INV_PI * fabsf(ci));
}

float bsdf_pdf(const Bsdf *b, Vec3 wo, Vec3 wi)
{
    if (b->type != MATERIAL_DIFFUSE) return 0.0f;
    float co = v3_dot(wo, b->frame.n), ci = v3_dot(wi, b->frame.n);
    if (co * ci <= 0.0f) return 0.0f;
    return fabsf(ci) * CST_INV_PI;
}

bool bsdf_sample(const Bsdf *b, Vec3 wo_world, float uc, Vec2 u, BsdfSample *out)
{
    return bsdf_sample_transport(b, wo_world, uc, u, BSDF_RADIANCE, out);
}

bool bsdf_sample_transport(const Bsdf *b, Vec3 wo_world, float uc, Vec2 u, BsdfTransport mode,
                           BsdfSample *out)
{
    Vec3 wo = frame_to_local(&b->frame, wo_world);
    if (wo.z == 0.0f) return false;
    switch (b->type) {
    case MATERIAL_DIFFUSE: {
        Vec3 wi = warp_cosine_hemisphere(u);
        if (wo.z < 0.0f) wi.z = -wi.z;
        if (wi.z == 0.0f) return false;
        out->wi = frame_to_world(&b->frame, wi);
        out->pdf = fabsf(wi.z) * CST_INV_PI;
        out->weight = b->albedo; /* (albedo/pi) |cos| / (|cos|/pi) */
        out->delta = false;
        return true;
    }
    case MATERIAL_MIRROR:
        out->wi = frame_to_world(&b->frame, v3(-wo.x, -wo.y, wo.z));
        out->pdf = 1.0f;
        out->weight = b->albedo;
        out->delta = true;
        return true;
    case MATERIAL_GLASS: {
        float f = fresnel_dielectric(wo.z, b->eta);
        out->delta = true;
        if (uc < f) {
            out->wi = frame_to_world(&b->frame, v3(-wo.x, -wo.y, wo.z));
            out->pdf = f;
            out->weight = b->albedo; /* (F / |cos|) |cos| / F */
            return true;
        }
        /* Refraction by Snell's law; etap is the relative IOR across the interface as
         * seen from wo's side (pbrt-v4 sec. 9.3.2). */
        float etap = wo.z > 0.0f ? b->eta : 1.0f / b->eta;
        float cos_i = fabsf(wo.z);
        float sin2_t = (1.0f - cos_i * cos_i) / (etap * etap);
        if (sin2_t >= 1.0f) return false; /* unreachable: f == 1 under TIR */
        float cos_t = safe_sqrtf(1.0f - sin2_t);
        Vec3 wt = v3_add(v3_scale(v3_neg(wo), 1.0f / etap),
                         v3(0.0f, 0.0f, (cos_i / etap - cos_t) * (wo.z > 0.0f ? 1.0f : -1.0f)));
        out->wi = frame_to_world(&b->frame, v3_normalize(wt));
        out->pdf = 1.0f - f;
        /* Radiance is compressed by 1/etap^2 entering a denser medium (Veach thesis sec. 5.2, pbrt-v4 sec. 9.5.2);
         * camera paths carry radiance, so the factor applies to them. Light paths carry
         * flux, which refraction does not compress: the adjoint BTDF lacks the factor
         * (Veach thesis sec. 5.2, pbrt-v4 DielectricBxDF with TransportMode::Importance). */
        out->weight = mode == BSDF_RADIANCE ? rgb_scale(b->albedo, 1.0f / (etap * etap)) : b->albedo;
        return true;
    }
    }
    return false;
}
