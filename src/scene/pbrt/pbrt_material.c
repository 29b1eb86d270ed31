/* Materials: pbrt-v4's material types mapped onto caustic's Material (roughness remapping,
 * conductors, coated layers), named materials, and the Material directives. */
#include "scene/pbrt/pbrt_material.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "materials/bssrdf.h"
#include "media/medium_presets.h"
#include "materials/hair.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_spectrum.h"
#include "scene/pbrt/pbrt_texture.h"
#include "scene/scene_build.h"

/* A reflectance parameter (diffuse "reflectance", pbrt-v3 "Kd", ...) as albedo or albedo
 * texture. pbrt-v4's materials clamp reflectances to [0, 1]; a texture with larger values
 * is clamped per texel. */
static CstStatus get_albedo(Loader *ld, Params *ps, const char *d, const char *name, Material *m)
{
    int tex = 0, e = 0;
    Color avg = m->albedo;
    TRY(pbrt_tex_param(ld, ps, d, name, 0, &tex, &avg, &e));
    if (!tex) return pbrt_get_spectrum(ld, ps, d, name, SPEC_REFLECTANCE, 1, &m->albedo, NULL);
    Param *p = pbrt_find_param(ps, name);
    CstTextureInfo info;
    TRY(pbrt_texture_info(ld, tex - 1, &info));
    float mx = maxf(info.max[0], maxf(info.max[1], info.max[2]));
    if (mx > 1.0f) {
        char nm[72];
        if (ld->texs[e].clamped < 0) {
            int id = 0;
            TRY(pbrt_tex_map(ld, tex - 1, TEXOP_MIN1, color_s(0.0f), color_s(0.0f), p->loc, d, &id));
            ld->texs[e].clamped = id;
        }
        tex = ld->texs[e].clamped + 1;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: texture \"%s\" has values up to %g; "
                     "clamped to 1 texel by texel (pbrt-v4 clamps the filtered reflectance)", d,
                     pbrt_clip(p->strs[0], nm), (double)mx);
    }
    m->albedo_texture = tex;
    TRY(pbrt_texture_info(ld, tex - 1, &info));
    m->albedo = color_rgb(info.average[0], info.average[1], info.average[2]);
    return CST_OK;
}

CstStatus pbrt_add_mat_entry(Loader *ld, const char *name, const Material *m, int *out)
{
    if (!GROW(ld->mats, ld->cap_mats, ld->num_mats + 1)) return pbrt_oom(ld);
    MatEntry *e = &ld->mats[ld->num_mats];
    e->name = NULL;
    if (name && !(e->name = pbrt_dup_str(name))) return pbrt_oom(ld);
    e->m = *m;
    e->scene_id = -1;
    e->interface = 0;
    *out = ld->num_mats++;
    return CST_OK;
}

static int find_named_material(Loader *ld, const char *name)
{
    for (int i = ld->num_mats - 1; i >= 0; i--)
        if (ld->mats[i].name && strcmp(ld->mats[i].name, name) == 0) return i;
    return -1;
}

/* pbrt's roughness parameters (names after `prefix`: "", "conductor." or "interface.") as
 * caustic's perceptual roughness. pbrt-v4's GGX width is alpha = sqrt(roughness) when
 * remaproughness is true, its default (TrowbridgeReitzDistribution::RoughnessToAlpha),
 * else alpha = roughness; caustic's is alpha = r^2 (material.h), so r = sqrt(alpha), and
 * below alpha 1e-3 (both widths) both render the smooth delta lobes. uroughness and
 * vroughness give the widths along dp/du and dp/dv (pbrt-v4's anisotropic
 * TrowbridgeReitzDistribution): *out is the one along u, *out_v the one along v (equal
 * when isotropic; the caller sets Material.anisotropic when they differ). */
/* One roughness texture parameter as a texture of caustic's perceptual roughness (r^(1/4)
 * remapped, else r^(1/2), texel by texel; made once per texture and remap): *id_out 1 +
 * its index (0 when the parameter names no texture), *avg its average, clamped to 1. */
static CstStatus pbrt_roughness_tex(Loader *ld, Params *ps, const char *d, Param *p, int remap, int *id_out,
                                    float *avg)
{
    int tex = 0, e = 0;
    Color a = color_s(0.0f);
    *id_out = 0;
    TRY(pbrt_tex_param(ld, ps, d, p->name, 1, &tex, &a, &e));
    if (!tex) return CST_OK;
    int *id = &ld->texs[e].rough[remap != 0];
    if (*id < 0) {
        int made = 0;
        TRY(pbrt_tex_map(ld, tex - 1, TEXOP_POW, color_s(remap ? 0.25f : 0.5f), color_s(0.0f), p->loc, d, &made));
        *id = made;
    }
    CstTextureInfo t;
    TRY(pbrt_texture_info(ld, *id, &t));
    *id_out = *id + 1;
    *avg = minf(t.average[0], 1.0f);
    if (t.max[0] > 1.0f)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, p->loc, "%s: roughness texture values up to "
                     "GGX alpha %g are beyond caustic's roughest (alpha 1); rendered with alpha 1",
                     d, (double)(t.max[0] * t.max[0]));
    return CST_OK;
}

static CstStatus pbrt_roughness(Loader *ld, Params *ps, const char *d, const char *prefix, Loc loc,
                                float *out, float *out_v, int *tex_out, int *tex_v_out)
{
    char n_r[64], n_u[64], n_v[64];
    snprintf(n_r, sizeof n_r, "%sroughness", prefix);
    snprintf(n_u, sizeof n_u, "%suroughness", prefix);
    snprintf(n_v, sizeof n_v, "%svroughness", prefix);
    float r = 0.0f, ur = 0.0f, vr = 0.0f;
    int remap = 1;
    TRY(pbrt_get_bool(ld, ps, d, "remaproughness", 1, &remap));
    if (tex_v_out) *tex_v_out = 0;
    if (tex_out) {
        /* An isotropic roughness texture (u and v from the same one) becomes a roughness
         * texture of caustic's perceptual roughness, r^(1/4) (remapped) or r^(1/2) texel by
         * texel, as the constant below; two different textures (with tex_v_out) become one
         * per width; a texture mixed with a constant takes its average. */
        Param *pr = pbrt_find_param(ps, n_r), *pu = pbrt_find_param(ps, n_u), *pv = pbrt_find_param(ps, n_v);
        Param *eu = pu ? pu : pr, *ev = pv ? pv : pr;
        *tex_out = 0;
        if (tex_v_out && eu && ev && eu->type == PT_TEXTURE && ev->type == PT_TEXTURE && eu->num_strs == 1 &&
            ev->num_strs == 1 && strcmp(eu->strs[0], ev->strs[0]) != 0) {
            int tu = 0, tv = 0;
            float au = 0.0f, av = 0.0f;
            TRY(pbrt_roughness_tex(ld, ps, d, eu, remap, &tu, &au));
            TRY(pbrt_roughness_tex(ld, ps, d, ev, remap, &tv, &av));
            if (tu && tv) {
                if (pr) pr->used = 1; /* shadowed by uroughness and vroughness */
                *tex_out = tu, *tex_v_out = tv;
                *out = au, *out_v = av;
                return CST_OK;
            }
        }
        if (eu && ev && eu->type == PT_TEXTURE && ev->type == PT_TEXTURE && eu->num_strs == 1 &&
            ev->num_strs == 1 && strcmp(eu->strs[0], ev->strs[0]) == 0) {
            if (ev != eu) { /* the same texture: read only to mark the parameter used */
                int tx = 0, ex = 0;
                Color ax = color_s(0.0f);
                TRY(pbrt_tex_param(ld, ps, d, ev->name, 1, &tx, &ax, &ex));
            }
            int t = 0;
            float a = 0.0f;
            TRY(pbrt_roughness_tex(ld, ps, d, eu, remap, &t, &a));
            if (t) {
                if (pr) pr->used = 1; /* shadowed by uroughness and vroughness */
                *tex_out = t;
                *out = *out_v = a;
                return CST_OK;
            }
        }
    }
    TRY(pbrt_get_float_tex(ld, ps, d, n_r, 0.0f, &r, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, n_u, r, &ur, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, n_v, r, &vr, NULL));
    if (!(ur >= 0.0f) || !(vr >= 0.0f)) {
        Param *p = pbrt_find_param(ps, !(ur >= 0.0f) ? n_u : n_v);
        if (!p) p = pbrt_find_param(ps, n_r);
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: roughness %g is negative; "
                            "expected a roughness >= 0", d, (double)(!(ur >= 0.0f) ? ur : vr));
    }
    float au = remap ? sqrtf(ur) : ur, av = remap ? sqrtf(vr) : vr;
    float *dst[2] = {out, out_v}, alpha[2] = {au, av};
    for (int i = 0; i < 2; i++) {
        *dst[i] = sqrtf(alpha[i]);
        if (*dst[i] > 1.0f) {
            if (i == 0 || au != av)
                pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: GGX alpha %g is beyond caustic's roughest "
                             "(alpha 1); rendered with alpha 1", d, (double)alpha[i]);
            *dst[i] = 1.0f;
        }
    }
    return CST_OK;
}

/* pbrt_roughness into a material's roughness fields and textures. */
static CstStatus material_roughness(Loader *ld, Params *ps, const char *d, const char *prefix, Loc loc, Material *m)
{
    return pbrt_roughness(ld, ps, d, prefix, loc, &m->roughness, &m->roughness_v, &m->roughness_texture,
                          &m->roughness_v_texture);
}

/* A conductor (pbrt-v4 ConductorMaterial): complex IOR from eta and k (default copper), or
 * from "reflectance" as pbrt-v4 converts it: eta = 1, k = 2 sqrt(R) / sqrt(1 - R) with R
 * clamped to [0, 0.9999], whose normal-incidence Fresnel reflectance ((n-1)^2 + k^2) /
 * ((n+1)^2 + k^2) = k^2 / (4 + k^2) is exactly R. coatedconductor reads the same with
 * prefix "conductor." (its reflectance keeps the plain name). */
static CstStatus conductor(Loader *ld, Params *ps, const char *d, const char *prefix, Loc loc,
                           Material *m)
{
    char n_eta[64], n_k[64], nm[72];
    snprintf(n_eta, sizeof n_eta, "%seta", prefix);
    snprintf(n_k, sizeof n_k, "%sk", prefix);
    Color eta, k, refl = color_s(0.0f);
    material_metal("copper", &eta, &k); /* pbrt's default conductor is copper */
    Param *pe = pbrt_find_param(ps, n_eta), *pk = pbrt_find_param(ps, n_k), *pr = pbrt_find_param(ps, "reflectance");
    if (pr && (pe || pk))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pr->loc, "%s: \"reflectance\" given with \"%s\"; "
                            "expected either reflectance or eta and k (as pbrt-v4)", d,
                            pbrt_clip(pe ? pe->decl : pk->decl, nm));
    int has_refl = 0, eta_sp = 0, k_sp = 0, eta_tex = 0, k_tex = 0, refl_tex = 0, e = 0;
    /* Textures (pbrt-v4's eta, k and reflectance are spectrum textures): kept as textures,
     * evaluated per hit (scene_bsdf_textures); eta and k hold their averages. A constant
     * texture is its value, as before. */
    if (pe && pe->type == PT_TEXTURE) {
        TRY(pbrt_tex_param(ld, ps, d, n_eta, 0, &eta_tex, &eta, &e));
    } else if (pe && pe->type == PT_FLOAT) { /* pbrt-v4 also takes a plain float eta */
        float eta_f = 1.0f;
        TRY(pbrt_get_float(ld, ps, d, n_eta, 1.0f, &eta_f, NULL));
        if (!(eta_f >= 0.0f))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pe->loc, "%s: eta %g is negative; expected "
                                "the real part of a conductor's index of refraction, >= 0", d, (double)eta_f);
        eta = color_s(eta_f);
    } else {
        TRY(pbrt_get_spectrum_id(ld, ps, d, n_eta, SPEC_UNBOUNDED, 1, &eta, NULL, &eta_sp));
    }
    if (pk && pk->type == PT_TEXTURE) TRY(pbrt_tex_param(ld, ps, d, n_k, 0, &k_tex, &k, &e));
    else TRY(pbrt_get_spectrum_id(ld, ps, d, n_k, SPEC_UNBOUNDED, 1, &k, NULL, &k_sp));
    if (pr && pr->type == PT_TEXTURE) { /* clamped to 1 texel by texel as other reflectances */
        Material tmp = {0};
        TRY(get_albedo(ld, ps, d, "reflectance", &tmp));
        refl = tmp.albedo, refl_tex = tmp.albedo_texture, has_refl = 1;
    } else {
        TRY(pbrt_get_spectrum(ld, ps, d, "reflectance", SPEC_REFLECTANCE, 1, &refl, &has_refl));
    }
    if (has_refl) {
        float r[3] = {refl.c[0], refl.c[1], refl.c[2]}, kk[3];
        for (int i = 0; i < 3; i++) {
            float c = clampf(r[i], 0.0f, 0.9999f);
            kk[i] = 2.0f * sqrtf(c) / sqrtf(1.0f - c);
        }
        eta = color_s(1.0f);
        k = color_rgb(kk[0], kk[1], kk[2]);
    }
    m->type = MATERIAL_CONDUCTOR;
    m->albedo = color_s(1.0f);
    m->ior = 1.0f;
    m->eta = eta;
    m->k = k;
    /* Spectra (named, pairs, .spd) stay spectra in spectral mode; cst_scene_add_material
     * replaces eta and k by their RGB reductions. */
    m->eta_spectrum = has_refl ? 0 : eta_sp;
    m->k_spectrum = has_refl ? 0 : k_sp;
    m->eta_texture = has_refl ? 0 : eta_tex;
    m->k_texture = has_refl ? 0 : k_tex;
    m->reflectance_texture = refl_tex;
    return material_roughness(ld, ps, d, prefix, loc, m);
}

/* The layer of pbrt-v4's coated materials (CoatedDiffuseMaterial, CoatedConductorMaterial):
 * thickness (0.01), albedo (0), g (0), maxdepth (10), nsamples (1), pbrt-v4's defaults,
 * for caustic's random walk (layered.c). Textured ones take their averages (pbrt_get_*). */
static CstStatus coat_layer_params(Loader *ld, Params *ps, const char *d, Material *m)
{
    m->thickness = 0.01f;
    m->g = 0.0f;
    m->layer_albedo = color_s(0.0f);
    m->max_depth = 10;
    m->nsamples = 1;
    TRY(pbrt_get_float_tex(ld, ps, d, "thickness", 0.01f, &m->thickness, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, "g", 0.0f, &m->g, NULL));
    TRY(pbrt_get_spectrum(ld, ps, d, "albedo", SPEC_REFLECTANCE, 1, &m->layer_albedo, NULL));
    TRY(pbrt_get_int(ld, ps, d, "maxdepth", 10, &m->max_depth));
    TRY(pbrt_get_int(ld, ps, d, "nsamples", 1, &m->nsamples));
    Param *p;
    if (!(m->thickness >= 0.0f && m->thickness <= FLT_MAX))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, (p = pbrt_find_param(ps, "thickness")) ? p->loc : ld->end,
                            "%s: thickness %g; expected a layer thickness >= 0", d, (double)m->thickness);
    if (!(m->g > -1.0f && m->g < 1.0f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, (p = pbrt_find_param(ps, "g")) ? p->loc : ld->end,
                            "%s: g %g is outside (-1, 1); expected a Henyey-Greenstein asymmetry", d, (double)m->g);
    if (m->max_depth < 1 || m->max_depth > 100000)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, (p = pbrt_find_param(ps, "maxdepth")) ? p->loc : ld->end,
                            "%s: maxdepth %d; expected 1 to 100000", d, m->max_depth);
    if (m->nsamples < 1 || m->nsamples > 10000)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, (p = pbrt_find_param(ps, "nsamples")) ? p->loc : ld->end,
                            "%s: nsamples %d; expected 1 to 10000", d, m->nsamples);
    return CST_OK;
}

/* A dielectric's eta: a float (or float texture, its average), or a spectrum (named,
 * pairs, .spd) kept as *ior_spectrum for spectral mode, where it disperses; *eta its
 * y-bar-weighted mean for RGB mode (cst_scene_add_material sets the same). */
static CstStatus dielectric_eta(Loader *ld, Params *ps, const char *d, const char *name, float *eta,
                                int *ior_spectrum)
{
    Param *p = pbrt_find_param(ps, name);
    *ior_spectrum = 0;
    if (p && p->type == PT_SPECTRUM) {
        Color c = color_s(1.5f);
        TRY(pbrt_get_spectrum_id(ld, ps, d, name, SPEC_UNBOUNDED, 0, &c, NULL, ior_spectrum));
        *eta = c.c[1];
    } else {
        TRY(pbrt_get_float_tex(ld, ps, d, name, *eta, eta, NULL));
    }
    if (!(*eta > 0.0f)) {
        Loc l = p ? p->loc : ld->end;
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, l, "%s: eta %g is not positive; expected an index "
                            "of refraction > 0 (glass is about 1.5)", d, (double)*eta);
    }
    return CST_OK;
}

/* pbrt-v4's subsurface material (SubsurfaceMaterial::Create): a dielectric surface (eta,
 * default 1.33; roughness as the dielectric's) over a medium given, in pbrt's order of
 * precedence, by "name" (measured, g forced to 0), "sigma_a" with "sigma_s", or
 * "reflectance" with "mfp" (default 1), else pbrt-v4's default coefficients; "scale"
 * multiplies the coefficients or the mean free path. Constant coefficients only (a
 * coefficient texture is an error); the reflectance may be a texture. */
static CstStatus subsurface_material(Loader *ld, Params *ps, const char *d, Loc loc, Material *m)
{
    char nm[72];
    m->type = MATERIAL_DIELECTRIC;
    m->albedo = color_s(1.0f);
    m->ior = 1.33f;
    m->subsurface = true;
    float eta = 1.33f, g = 0.0f, scale = 1.0f;
    int found_g = 0;
    TRY(pbrt_get_float(ld, ps, d, "eta", 1.33f, &eta, NULL));
    if (!(eta > 0.0f) || !(eta < 1e6f)) {
        Param *p = pbrt_find_param(ps, "eta");
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: eta %g; expected an index of "
                            "refraction > 0 (skin is about 1.33)", d, (double)eta);
    }
    m->ior = eta;
    TRY(pbrt_get_float(ld, ps, d, "g", 0.0f, &g, &found_g));
    if (!(g > -1.0f && g < 1.0f)) {
        Param *p = pbrt_find_param(ps, "g");
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: g %g is outside (-1, 1); expected "
                            "a Henyey-Greenstein asymmetry", d, (double)g);
    }
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    if (!(scale >= 0.0f) || !(scale < 1e30f)) {
        Param *p = pbrt_find_param(ps, "scale");
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: scale %g; expected a finite "
                            "scale >= 0", d, (double)scale);
    }
    TRY(material_roughness(ld, ps, d, "", loc, m));
    const char *name = NULL;
    Loc nloc = loc;
    TRY(pbrt_get_string(ld, ps, d, "name", &name, &nloc));
    Param *pa = pbrt_find_param(ps, "sigma_a"), *pss = pbrt_find_param(ps, "sigma_s");
    if (name && name[0]) {
        Color sa, ss;
        if (!medium_preset(name, &sa, &ss))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, nloc, "%s: unknown named medium \"%s\"; expected one "
                                "of %s", d, pbrt_clip(name, nm), MEDIUM_PRESET_EXAMPLES);
        if (found_g && g != 0.0f)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: g %g is ignored with a named medium (its "
                         "coefficients are reduced scattering: g = 0), as pbrt-v4 does", d, (double)g);
        g = 0.0f;
        if (pa) pa->used = 1;
        if (pss) pss->used = 1;
        m->sss_sigma_a = color_scale(sa, scale);
        m->sss_sigma_s = color_scale(ss, scale);
    } else if (pa || pss) {
        if (!pa || !pss)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, (pa ? pa : pss)->loc, "%s: \"%s\" without \"%s\"; "
                                "expected both sigma_a and sigma_s", d, pa ? "sigma_a" : "sigma_s",
                                pa ? "sigma_s" : "sigma_a");
        Color sa = color_s(0.0f), ss = color_s(0.0f);
        TRY(pbrt_get_spectrum(ld, ps, d, "sigma_a", SPEC_UNBOUNDED, 0, &sa, NULL));
        TRY(pbrt_get_spectrum(ld, ps, d, "sigma_s", SPEC_UNBOUNDED, 0, &ss, NULL));
        /* pbrt-v4 clamps the coefficients at 0 (ClampZero) */
        for (int c = 0; c < COLOR_LANES; c++) {
            sa.c[c] = maxf(sa.c[c], 0.0f);
            ss.c[c] = maxf(ss.c[c], 0.0f);
        }
        m->sss_sigma_a = color_scale(sa, scale);
        m->sss_sigma_s = color_scale(ss, scale);
    } else if (pbrt_find_param(ps, "reflectance")) {
        m->sss_from_reflectance = true;
        Material r = *m;
        r.albedo = color_s(1.0f);
        r.albedo_texture = 0;
        TRY(get_albedo(ld, ps, d, "reflectance", &r));
        m->sss_reflectance = r.albedo;
        m->sss_reflectance_texture = r.albedo_texture;
        for (int c = 0; c < COLOR_LANES; c++) m->sss_reflectance.c[c] = clampf(m->sss_reflectance.c[c], 0.0f, 1.0f);
        Color mfp = color_s(1.0f);
        TRY(pbrt_get_spectrum(ld, ps, d, "mfp", SPEC_UNBOUNDED, 0, &mfp, NULL));
        mfp = color_scale(mfp, scale);
        if (!(mfp.c[0] > 0.0f && mfp.c[1] > 0.0f && mfp.c[2] > 0.0f)) {
            Param *p = pbrt_find_param(ps, "mfp");
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc, "%s: mean free path (%g, %g, %g) "
                                "(times scale); expected values > 0", d, (double)mfp.c[0], (double)mfp.c[1],
                                (double)mfp.c[2]);
        }
        m->sss_mfp = mfp;
    } else {
        if (pbrt_find_param(ps, "mfp")) pbrt_find_param(ps, "mfp")->used = 1; /* pbrt ignores it too */
        m->sss_sigma_a = color_scale(color_rgb(0.0011f, 0.0024f, 0.014f), scale);
        m->sss_sigma_s = color_scale(color_rgb(2.55f, 3.21f, 3.77f), scale);
    }
    m->sss_mfp = m->sss_from_reflectance ? m->sss_mfp : color_s(1.0f);
    m->g = g;
    return CST_OK;
}

/* pbrt-v4's measured material: "string filename", an RGL .bsdf read when the material is
 * first used (cst_scene_add_material; a malformed file is an error there, located by
 * byte). A file that does not exist (the corpus's are not distributed) is reported and
 * replaced by diffuse reflectance 0.5, as an unsupported material is. The resolved path
 * is the loader's (MatEntry) until then. */
static CstStatus measured_material(Loader *ld, Params *ps, const char *d, Loc loc, Material *m)
{
    memset(m, 0, sizeof *m); /* make_material's defaults: the stand-in's */
    m->type = MATERIAL_DIFFUSE;
    m->albedo = color_s(0.5f);
    m->ior = 1.0f;
    const char *file = NULL;
    Loc fl = loc;
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (!file || !file[0])
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the "
                            "path of a .bsdf file", d);
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    if (access(path, F_OK) != 0) {
        char nm[72];
        pbrt_warn_at(ld, CST_WARN_MISSING_FILE, fl, "%s: file \"%s\" not found; diffuse reflectance 0.5 is used "
                     "instead", d, pbrt_clip(file, nm));
        free(path);
        return CST_OK;
    }
    m->type = MATERIAL_MEASURED;
    m->measured_file = path;
    return CST_OK;
}

/* pbrt-v4's hair (pbrt-v3's too): the fibre BSDF (materials/hair.h) with pbrt-v4's
 * HairMaterial defaults and precedence: sigma_a, else "reflectance" (pbrt-v3 "color"),
 * else eumelanin and pheomelanin, else eumelanin 1.3. Textured parameters take their
 * average (pbrt_get_float_tex's warning), except a reflectance texture, kept as such. */
static CstStatus hair_material(Loader *ld, Params *ps, const char *d, Loc loc, Material *m)
{
    m->type = MATERIAL_HAIR;
    m->albedo = color_s(1.0f);
    TRY(pbrt_get_float_tex(ld, ps, d, "eta", 1.55f, &m->ior, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, "beta_m", 0.3f, &m->beta_m, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, "beta_n", 0.3f, &m->beta_n, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, "alpha", 2.0f, &m->hair_alpha, NULL));
    if (!(m->ior > 0.0f && m->ior <= FLT_MAX))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: eta %g; expected the fibre's index of refraction "
                            "> 0 (1.55)", d, (double)m->ior);
    if (!(m->beta_m > 0.0f && m->beta_m <= 1.0f) || !(m->beta_n > 0.0f && m->beta_n <= 1.0f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: beta_m %g, beta_n %g; expected roughnesses in "
                            "(0, 1]", d, (double)m->beta_m, (double)m->beta_n);
    if (!(m->hair_alpha >= -90.0f && m->hair_alpha <= 90.0f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: alpha %g; expected the cuticle tilt in degrees, "
                            "in [-90, 90]", d, (double)m->hair_alpha);
    /* Parameters of the sources not taken stay unread: the loader's unused-parameter
     * warning names them (pbrt-v4 warns that it ignores them). */
    int has_sigma = 0;
    TRY(pbrt_get_spectrum(ld, ps, d, "sigma_a", SPEC_UNBOUNDED, 1, &m->sigma_a, &has_sigma));
    const char *refl = pbrt_find_param(ps, "reflectance") ? "reflectance"
                       : pbrt_find_param(ps, "color") ? "color" : NULL;
    if (has_sigma) return CST_OK;
    if (refl) {
        TRY(get_albedo(ld, ps, d, refl, m));
        m->hair_color = true;
        return CST_OK;
    }
    /* pbrt-v4: eumelanin 1.3 when neither concentration is given, else an absent one is 0 */
    const bool given = pbrt_find_param(ps, "eumelanin") || pbrt_find_param(ps, "pheomelanin");
    float eu = 0.0f, ph = 0.0f;
    TRY(pbrt_get_float_tex(ld, ps, d, "eumelanin", given ? 0.0f : 1.3f, &eu, NULL));
    TRY(pbrt_get_float_tex(ld, ps, d, "pheomelanin", 0.0f, &ph, NULL));
    if (!(eu >= 0.0f && eu <= 1e6f) || !(ph >= 0.0f && ph <= 1e6f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: eumelanin %g, pheomelanin %g; expected "
                            "concentrations >= 0 (and at most 1e6)", d, (double)eu, (double)ph);
    m->sigma_a = hair_sigma_a_from_melanin(eu, ph);
    return CST_OK;
}

/* pbrt material `type` with its parameters as our nearest Material (docs/pbrt-compat.md). */
static CstStatus make_material(Loader *ld, const char *type, Params *ps, Loc loc, Material *m)
{
    char d[96], nm[72];
    snprintf(d, sizeof d, "material \"%s\"", pbrt_clip(type, nm));
    /* Fields a mapping does not set keep their zero defaults. one_sided stays false: pbrt-v4's
     * reflective BxDFs (diffuse, conductor, coated) reflect on both sides of a surface, as
     * caustic's two-sided default does. */
    memset(m, 0, sizeof *m);
    m->type = MATERIAL_DIFFUSE;
    m->albedo = color_s(0.5f);
    m->ior = 1.0f;
    if (strcmp(type, "diffuse") == 0) {
        TRY(get_albedo(ld, ps, d, "reflectance", m));
    } else if (strcmp(type, "matte") == 0) { /* pbrt-v3 */
        TRY(get_albedo(ld, ps, d, "Kd", m));
    } else if (strcmp(type, "coateddiffuse") == 0) {
        /* pbrt-v4's LayeredBxDF by the same random walk (layered.c). */
        m->type = MATERIAL_COATED_DIFFUSE;
        m->ior = 1.5f;
        TRY(get_albedo(ld, ps, d, "reflectance", m));
        TRY(dielectric_eta(ld, ps, d, "eta", &m->ior, &m->ior_spectrum));
        TRY(material_roughness(ld, ps, d, "", loc, m));
        TRY(coat_layer_params(ld, ps, d, m));
    } else if (strcmp(type, "diffusetransmission") == 0) {
        /* pbrt-v4 DiffuseTransmissionMaterial: reflectance and transmittance (0.25 each)
         * times scale, each clamped to [0, 1]. */
        m->type = MATERIAL_DIFFUSE_TRANSMISSION;
        m->albedo = color_s(0.25f);
        m->transmittance = color_s(0.25f);
        float scale = 1.0f;
        TRY(get_albedo(ld, ps, d, "reflectance", m));
        TRY(pbrt_get_spectrum(ld, ps, d, "transmittance", SPEC_REFLECTANCE, 1, &m->transmittance, NULL));
        TRY(pbrt_get_float_tex(ld, ps, d, "scale", 1.0f, &scale, NULL));
        if (scale != 1.0f) {
            if (m->albedo_texture)
                pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: \"scale\" %g is not applied to the "
                             "reflectance texture", d, (double)scale);
            for (int c = 0; c < 3; c++) {
                m->albedo.c[c] = clampf(m->albedo.c[c] * scale, 0.0f, 1.0f);
                m->transmittance.c[c] = clampf(m->transmittance.c[c] * scale, 0.0f, 1.0f);
            }
        }
    } else if (strcmp(type, "plastic") == 0 || strcmp(type, "substrate") == 0 ||
               strcmp(type, "uber") == 0 || strcmp(type, "translucent") == 0 ||
               strcmp(type, "disney") == 0) { /* pbrt-v3 */
        m->albedo = color_s(strcmp(type, "plastic") == 0 ? 0.25f : 0.5f);
        TRY(get_albedo(ld, ps, d, strcmp(type, "disney") == 0 ? "color" : "Kd", m));
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated as diffuse with its diffuse "
                     "reflectance (specular lobes dropped)", d);
    } else if (strcmp(type, "conductor") == 0 || strcmp(type, "metal") == 0) {
        TRY(conductor(ld, ps, d, "", loc, m));
    } else if (strcmp(type, "coatedconductor") == 0) {
        /* The conductor (its roughness becomes base_roughness), the interface over it and
         * the layer between, by pbrt-v4's random walk (layered.c). A conductor roughness
         * texture takes its average (only the interface's roughness can be a texture). */
        TRY(conductor(ld, ps, d, "conductor.", loc, m));
        m->type = MATERIAL_COATED_CONDUCTOR;
        m->base_roughness = m->roughness; /* a texture's average (pbrt_roughness), two textures' each */
        m->base_roughness_v = m->roughness_v;
        if (m->roughness_texture) {
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: the conductor's roughness texture is "
                         "rendered with its average, perceptual roughness %g", d, (double)m->base_roughness);
        }
        m->roughness_texture = m->roughness_v_texture = 0; /* pbrt_roughness sets roughness and roughness_v */
        m->ior = 1.5f;
        TRY(material_roughness(ld, ps, d, "interface.", loc, m));
        TRY(dielectric_eta(ld, ps, d, "interface.eta", &m->ior, &m->ior_spectrum));
        TRY(coat_layer_params(ld, ps, d, m));
    } else if (strcmp(type, "mirror") == 0) { /* pbrt-v3 */
        m->type = MATERIAL_MIRROR;
        m->albedo = color_s(0.9f);
        TRY(get_albedo(ld, ps, d, "Kr", m));
    } else if (strcmp(type, "thindielectric") == 0) {
        m->type = MATERIAL_THIN_DIELECTRIC;
        m->albedo = color_s(1.0f);
        m->ior = 1.5f;
        TRY(dielectric_eta(ld, ps, d, "eta", &m->ior, &m->ior_spectrum));
    } else if (strcmp(type, "dielectric") == 0 || strcmp(type, "glass") == 0) {
        m->type = MATERIAL_GLASS;
        m->albedo = color_s(1.0f);
        m->ior = 1.5f;
        TRY(dielectric_eta(ld, ps, d, strcmp(type, "glass") == 0 && pbrt_find_param(ps, "index") ? "index" : "eta",
                           &m->ior, &m->ior_spectrum));
        /* Rough: GGX reflection and transmission (Walter et al. 2007), as pbrt-v4's
         * DielectricBxDF; below alpha 1e-3 both are smooth. */
        TRY(material_roughness(ld, ps, d, "", loc, m));
        if (m->roughness_texture || material_alpha(maxf(m->roughness, m->roughness_v)) >= MATERIAL_SMOOTH_ALPHA)
            m->type = MATERIAL_DIELECTRIC;
        else m->roughness = m->roughness_v = 0.0f;
    } else if (strcmp(type, "interface") == 0 || strcmp(type, "") == 0 || strcmp(type, "none") == 0) {
        m->type = MATERIAL_GLASS;
        m->albedo = color_s(1.0f);
        m->ior = 1.0f;
        /* Shapes with it are left out (pbrt_shape.c); this glass of eta 1 stands in only
         * for an emitting one, which must stay to emit. */
    } else if (strcmp(type, "mix") == 0) {
        Param *p;
        TRY(pbrt_lookup(ld, ps, d, "materials", PT_MASK(PT_STRING), "string", &p));
        if (!p || p->num_strs != 2)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p ? p->loc : loc,
                                "%s: expected \"string materials\" with two named materials", d);
        int a = find_named_material(ld, p->strs[0]), b = find_named_material(ld, p->strs[1]);
        if (a < 0 || b < 0)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "%s: material \"%s\" is not defined; expected names given to "
                                "MakeNamedMaterial before", d, pbrt_clip(p->strs[a < 0 ? 0 : 1], nm));
        /* amount: a constant, or a float texture kept as the mix's amount texture */
        int amount_tex = 0, e = 0;
        float amount = 0.5f;
        Param *pa = pbrt_find_param(ps, "amount");
        if (pa && pa->type == PT_TEXTURE) {
            Color amount_c = color_s(0.5f);
            TRY(pbrt_tex_param(ld, ps, d, "amount", 1, &amount_tex, &amount_c, &e));
            amount = amount_c.c[0];
        } else {
            TRY(pbrt_get_float_tex(ld, ps, d, "amount", 0.5f, &amount, NULL));
        }
        amount = clampf(amount, 0.0f, 1.0f);
        Material ma = ld->mats[a].m, mb = ld->mats[b].m;
        if (!amount_tex && ma.type == mb.type && (ma.type == MATERIAL_DIFFUSE || ma.type == MATERIAL_MIRROR) &&
            ma.one_sided == mb.one_sided && !ma.albedo_texture && !mb.albedo_texture) {
            /* Choosing one of two Lambertian (or two mirror) lobes with probability amount
             * is the same lobe with the blended albedo: exact. (Conductors, plastics and
             * dielectrics are not linear in a single albedo.) */
            *m = ma;
            m->albedo = color_add(color_scale(ma.albedo, 1.0f - amount), color_scale(mb.albedo, amount));
        } else {
            /* pbrt-v4's MixMaterial: one of the two per hit (scene_mix_choose). */
            m->type = MATERIAL_MIX;
            TRY(pbrt_material_scene_id(ld, a, &m->mix[0]));
            TRY(pbrt_material_scene_id(ld, b, &m->mix[1]));
            m->amount = amount;
            m->amount_texture = amount_tex;
        }
    } else if (strcmp(type, "hair") == 0 || strcmp(type, "subsurface") == 0) {
        TRY(type[0] == 'h' ? hair_material(ld, ps, d, loc, m) : subsurface_material(ld, ps, d, loc, m));
    } else if (strcmp(type, "kdsubsurface") == 0 || strcmp(type, "fourier") == 0) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported; diffuse reflectance 0.5 is used instead", d);
    } else {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc,
                       "unknown material type \"%s\"; expected one of: diffuse, coateddiffuse, "
                       "conductor, coatedconductor, dielectric, thindielectric, diffusetransmission, "
                            "interface, mix, measured, hair, subsurface", pbrt_clip(type, nm));
    }
    return CST_OK;
}

CstStatus pbrt_material_scene_id(Loader *ld, int entry, int *out)
{
    MatEntry *e = &ld->mats[entry];
    if (e->scene_id < 0) {
        CstMaterialDesc desc;
        scene_material_desc(&e->m, &desc);
        TRY(cst_scene_add_material(ld->scene, &desc, &e->scene_id, ld->err));
    }
    *out = e->scene_id;
    return CST_OK;
}

/* Material and MakeNamedMaterial. */
CstStatus pbrt_material_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d, *dname = call->dname;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    if (!ld->in_world) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s before WorldBegin; expected materials in the world block", dname);
    }
    Material m = {0};
    const char *mt = type;
    if (dname[0] == 'M' && dname[1] == 'a' && dname[2] == 'k') {
        /* MakeNamedMaterial "name" "string type" "diffuse" ... */
        if (find_named_material(ld, type) >= 0) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "MakeNamedMaterial: \"%s\" is already "
                              "defined; expected each name once", pbrt_clip(type, nm));
        }
        Loc l2 = loc;
        TRY(pbrt_get_string(ld, ps, d, "type", &mt, &l2));
        if (!mt) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string type\"; expected the "
                              "material type, as in \"string type\" \"diffuse\"", d);
        }
    }
    if (strcmp(mt, "measured") == 0) {
        char dm[96], nm2[72];
        snprintf(dm, sizeof dm, "material \"%s\"", pbrt_clip(mt, nm2));
        TRY(measured_material(ld, ps, dm, loc, &m));
    } else {
        TRY(make_material(ld, mt, ps, loc, &m));
    }
    /* pbrt_roughness gave equal widths unless uroughness and vroughness differ */
    m.anisotropic = m.roughness != m.roughness_v || m.base_roughness != m.base_roughness_v || m.roughness_v_texture;
    int id = 0;
    CstStatus st = pbrt_material_normal_textures(ld, ps, d, &m);
    if (st == CST_OK) st = pbrt_add_mat_entry(ld, dname[0] == 'M' && dname[2] == 'k' ? type : NULL, &m, &id);
    if (st != CST_OK) {
        free((char *)(uintptr_t)m.measured_file); /* the entry would have owned it */
        return st;
    }
    ld->mats[id].interface = strcmp(mt, "interface") == 0 || strcmp(mt, "") == 0 || strcmp(mt, "none") == 0;
    if (dname[2] != 'k') ld->gs.material = id;
    return CST_OK;
}

CstStatus pbrt_named_material_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)loc;
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    Loc nl;
    TRY(pbrt_expect_string(ld, lx, dname, "a material name", &s, &nl));
    int i = find_named_material(ld, s);
    if (i < 0)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, nl, "NamedMaterial: \"%s\" is not defined; expected "
                          "a name given to MakeNamedMaterial before", pbrt_clip(s, nm));
    else
        ld->gs.material = i;
    free(s);
    return st;
}
