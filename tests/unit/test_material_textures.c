/* Material parameters that pbrt-v4 may texture, beyond albedo and roughness: bump mapping
 * of analytic shapes (d dn/du, pbrt-v4 BumpMap) and textured conductors (eta, k and
 * reflectance), against closed forms. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "caustic/caustic.h"
#include "scene/scene.h"

/* The hit of a ray straight down (-z) at (x, y) on a scene's quad. */
static SurfaceHit hit_at(const Scene *s, float x, float y)
{
    Ray r = ray_make(v3(x, y, 1.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, 10.0f);
    SurfaceHit sh;
    assert_true(scene_intersect(s, &r, &sh));
    return sh;
}

/* Bump mapping of an analytic sphere (pbrt-v4's sphere, as a textured one in a pbrt scene):
 * the bent normal is the normal of the displaced surface p(u, v) + d(u, v) n(u, v), here
 * with d = c + a u + b v (a bilerp, exact under forward differences), whose tangents
 * dp/du + a n + d dn/du (PBR 4th ed. eq. 10.12) are taken here by central differences of
 * that surface (shape_surface_at). Leaving out d dn/du (as scene_bump did for analytic
 * shapes) tilts the normal by about d / r times too much: off by 0.05-0.1 here. */
static void test_bump_analytic_sphere(void **state)
{
    (void)state;
    CstError err;
    CstScene *cs = NULL;
    assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
    const float c0 = 0.2f, a = 1.0f, b = 0.5f;
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_BILERP;
    float c[4] = {c0, c0 + b, c0 + a, c0 + a + b}; /* v00, v01, v10, v11 */
    for (int i = 0; i < 4; i++) t.corners[i][0] = t.corners[i][1] = t.corners[i][2] = c[i];
    int tid = 0, mid = 0;
    assert_int_equal(cst_scene_add_texture(cs, &t, &tid, &err), CST_OK);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.displacement_texture = tid;
    assert_int_equal(cst_scene_add_material(cs, &md, &mid, &err), CST_OK);
    Scene *s = cs;
    ShapeParams sp = {SHAPE_TAG_SPHERE, 1.0f, -1.0f, 1.0f, 0.0f, 0.0f, 2.0f * CST_PI, false, 0.0f};
    Transform xf = transform_compose(transform_translate(v3(0.1f, -0.2f, 0.3f)),
                                     transform_rotate(v3(0.3f, 1.0f, 0.2f), 0.7f));
    if (scene_add_shape(s, &sp, &xf, mid, NULL, 0, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    const AnalyticShape *sh_shape = &s->shapes[0];
    int checked = 0;
    for (int i = 0; i < 12; i++) {
        Vec2 uv = v2(0.05f + 0.075f * (float)i, 0.2f + 0.05f * (float)i);
        ShapeSurface sf;
        shape_surface_at(sh_shape, uv, &sf);
        /* a ray from outside along -n onto the point */
        Ray r = ray_make(v3_madd(sf.p, sf.n, 2.0f), v3_neg(sf.n), 0.0f, 10.0f);
        SurfaceHit sh;
        assert_true(scene_intersect(s, &r, &sh));
        /* the displaced surface's tangents by central differences at the hit's uv */
        Vec3 tan[2];
        for (int k = 0; k < 2; k++) {
            const float h = 1e-3f;
            Vec2 d2 = k ? v2(0.0f, h) : v2(h, 0.0f);
            Vec3 q[2];
            for (int j = 0; j < 2; j++) {
                float sg = j ? -1.0f : 1.0f;
                Vec2 w = v2(sh.uv.x + sg * d2.x, sh.uv.y + sg * d2.y);
                ShapeSurface f;
                shape_surface_at(sh_shape, w, &f);
                q[j] = v3_madd(f.p, f.n, c0 + a * w.x + b * w.y);
            }
            tan[k] = v3_scale(v3_sub(q[0], q[1]), 0.5f / h);
        }
        Vec3 want = v3_normalize(v3_cross(tan[0], tan[1]));
        if (v3_dot(want, sh.ns) < 0.0f) want = v3_neg(want);
        Vec3 n = scene_bump(s, &s->materials[sh.material], &sh);
        if (v3_length(v3_sub(n, want)) > 2e-3f)
            fail_msg("bumped sphere at uv (%g, %g): (%g, %g, %g), expected (%g, %g, %g)", (double)sh.uv.x,
                     (double)sh.uv.y, (double)n.x, (double)n.y, (double)n.z, (double)want.x, (double)want.y,
                     (double)want.z);
        checked++;
    }
    assert_int_equal(checked, 12);
    cst_scene_destroy(cs);
}

/* Textured conductors (pbrt-v4's spectrum-textured eta, k and reflectance): eta and k
 * textures give the BSDF exactly the constant material's values (RGB mode) and their
 * unbounded upsampling (spectral mode); a reflectance texture R gives eta 1 and a k whose
 * normal-incidence Fresnel reflectance is R per channel, and per wavelength the albedo
 * spectrum of R (closed form: k^2 / (4 + k^2) = R), also under a coat (divided by its
 * eta). Wrong combinations are refused by the builder. */
static void test_conductor_textures(void **state)
{
    (void)state;
    CstError err;
    CstScene *cs = NULL;
    assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
    const float eta[3] = {0.2f, 0.9f, 1.1f}, k[3] = {3.9f, 2.4f, 2.1f}, refl[3] = {0.9f, 0.5f, 0.1f};
    int te = 0, tk = 0, tr = 0;
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_CONSTANT;
    memcpy(t.value, eta, sizeof eta);
    assert_int_equal(cst_scene_add_texture(cs, &t, &te, &err), CST_OK);
    memcpy(t.value, k, sizeof k);
    assert_int_equal(cst_scene_add_texture(cs, &t, &tk, &err), CST_OK);
    memcpy(t.value, refl, sizeof refl);
    assert_int_equal(cst_scene_add_texture(cs, &t, &tr, &err), CST_OK);
    int ids[5];
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR); /* 0: constants */
    memcpy(md.eta, eta, sizeof eta), memcpy(md.k, k, sizeof k);
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[0], &err), CST_OK);
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR); /* 1: textured eta and k */
    md.metal = "gold";
    md.eta_texture = te, md.k_texture = tk;
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[1], &err), CST_OK);
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR); /* 2: reflectance texture */
    md.metal = "gold";
    md.reflectance_texture = tr;
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[2], &err), CST_OK);
    cst_material_desc_init(&md, CST_MATERIAL_COATED_CONDUCTOR); /* 3: the same under a coat */
    md.metal = "gold";
    md.reflectance_texture = tr;
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[3], &err), CST_OK);
    md.eta_texture = te; /* refused: reflectance with eta */
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[4], &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "reflectance_texture with eta_texture"));
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.k_texture = tk;
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[4], &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "expected a conductor"));
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR);
    md.reflectance_texture = tk; /* values above 1 */
    assert_int_equal(cst_scene_add_material(cs, &md, &ids[4], &err), CST_ERR_INVALID_ARG);
    Scene *s = cs;
    const Vec3 q[4] = {v3(0, 0, 0), v3(1, 0, 0), v3(1, 1, 0), v3(0, 1, 0)};
    if (scene_add_quad(s, q, ids[0], NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    SurfaceHit sh = hit_at(s, 0.3f, 0.6f);
    Wavelengths wl = wavelengths_sample(0.37f);
    for (int spectral = 0; spectral < 2; spectral++) {
        const Wavelengths *w = spectral ? &wl : NULL;
        Bsdf b0, b1, b2, b3;
        sh.material = ids[0], scene_bsdf(s, &sh, w, &b0);
        sh.material = ids[1], scene_bsdf(s, &sh, w, &b1);
        sh.material = ids[2], scene_bsdf(s, &sh, w, &b2);
        sh.material = ids[3], scene_bsdf(s, &sh, w, &b3);
        assert_memory_equal(&b0.lobe.conductor.eta, &b1.lobe.conductor.eta, sizeof(Color));
        assert_memory_equal(&b0.lobe.conductor.k, &b1.lobe.conductor.k, sizeof(Color));
        Color r = color_rgb(refl[0], refl[1], refl[2]);
        if (spectral) r = spectrum_albedo(r, &wl);
        float top = b3.lobe.layered.top_eta;
        for (int i = 0; i < (spectral ? COLOR_LANES : 3); i++) {
            float kk = b2.lobe.conductor.k.c[i], kc = b3.lobe.layered.k.c[i] * top;
            assert_true(b2.lobe.conductor.eta.c[i] == 1.0f);
            assert_true(fabsf(b3.lobe.layered.eta.c[i] * top - 1.0f) < 1e-6f);
            if (fabsf(kk * kk / (4.0f + kk * kk) - r.c[i]) > 1e-5f || fabsf(kc * kc / (4.0f + kc * kc) - r.c[i]) > 1e-5f)
                fail_msg("%s lane %d: k %g (coated %g) reflects %g, expected %g", spectral ? "spectral" : "rgb", i,
                         (double)kk, (double)kc, (double)(kk * kk / (4.0f + kk * kk)), (double)r.c[i]);
        }
    }
    cst_scene_destroy(cs);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bump_analytic_sphere),
        cmocka_unit_test(test_conductor_textures),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
