/* Spectra kept as spectra (math/spectrum_sampled.h, spectrum_data.c), the .spd reader
 * (io/spd.h) and their use by the scene: piecewise-linear construction, the named
 * spectra against published values, the RGB reductions, located .spd errors, a
 * conductor's spectra at a path's wavelengths, and dispersion's termination of the
 * secondary wavelengths (scene_bsdf_disperse). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "film/sensor.h"
#include "io/spd.h"
#include "math/cie_data.h"
#include "math/spectrum_sampled.h"
#include "scene/scene.h"

static void test_pairs(void **state)
{
    (void)state;
    static SampledSpectrum s;
    const float l[3] = {400.0f, 500.0f, 700.0f}, v[3] = {1.0f, 3.0f, 2.0f};
    sampled_spectrum_from_pairs(l, v, 3, &s);
    assert_false(s.constant);
    assert_true(sampled_spectrum_at(&s, 399.0f) == 0.0f); /* 0 outside, as pbrt-v4 */
    assert_true(sampled_spectrum_at(&s, 701.0f) == 0.0f);
    assert_true(fabsf(sampled_spectrum_at(&s, 450.0f) - 2.0f) < 1e-6f);
    assert_true(fabsf(sampled_spectrum_at(&s, 450.5f) - 2.01f) < 1e-5f);
    assert_true(fabsf(sampled_spectrum_at(&s, 600.0f) - 2.5f) < 1e-6f);
    assert_true(fabsf(sampled_spectrum_at(&s, 700.0f) - 2.0f) < 1e-6f);
    sampled_spectrum_from_pairs(l, v, 1, &s); /* one pair: a constant */
    assert_true(s.constant && sampled_spectrum_at(&s, 830.0f) == 1.0f && sampled_spectrum_at(&s, 360.0f) == 1.0f);
    /* reductions of a constant are the constant */
    Color c = sampled_spectrum_rgb_unbounded(&s);
    assert_true(c.c[0] == 1.0f && c.c[1] == 1.0f && c.c[2] == 1.0f);
    assert_true(sampled_spectrum_mean_y(&s) == 1.0f);
    /* a non-constant flat spectrum (0 beyond 830 only) still reduces to about itself */
    const float l2[2] = {300.0f, 900.0f}, v2[2] = {0.5f, 0.5f};
    sampled_spectrum_from_pairs(l2, v2, 2, &s);
    c = sampled_spectrum_rgb_unbounded(&s);
    for (int k = 0; k < 3; k++) assert_true(fabsf(c.c[k] - 0.5f) < 1e-4f);
    assert_true(fabsf(sampled_spectrum_mean_y(&s) - 0.5f) < 1e-6f);
}

/* Named spectra against their sources: SCHOTT's catalogue n_d (587.56 nm; and n_F at
 * 486.13 nm of BK7 and SF11, textbook values), Johnson & Christy's gold, D65 as the film's
 * white, illuminant A warm. */
static void test_named(void **state)
{
    (void)state;
    static SampledSpectrum s;
    static const struct { const char *name; float nd, nF; } G[] = {
        {"glass-BK7", 1.5168f, 1.52238f}, {"glass-SF11", 1.78472f, 1.80645f}, {"glass-FK51A", 1.48656f, 0.0f},
        {"glass-LASF9", 1.85025f, 0.0f}, {"glass-BAF10", 1.67003f, 0.0f}};
    for (size_t i = 0; i < sizeof G / sizeof G[0]; i++) {
        assert_true(spectrum_named(G[i].name, &s));
        assert_false(s.constant);
        assert_true(fabsf(sampled_spectrum_at(&s, 587.56f) - G[i].nd) < 2e-4f);
        if (G[i].nF > 0.0f) assert_true(fabsf(sampled_spectrum_at(&s, 486.13f) - G[i].nF) < 2e-4f);
    }
    /* pbrt-v4's "glass-F5/F10/F11" are SCHOTT SF5/SF10/SF11 (its GlassSF*_eta tables): the
     * same dispersive spectra as the catalogue names, not the light flint F5 */
    static const char *const FLINT[3][2] = {{"glass-F5", "glass-SF5"}, {"glass-F10", "glass-SF10"},
                                            {"glass-F11", "glass-SF11"}};
    for (int i = 0; i < 3; i++) {
        static SampledSpectrum t;
        assert_true(spectrum_named(FLINT[i][0], &s) && spectrum_named(FLINT[i][1], &t));
        assert_false(s.constant);
        assert_memory_equal(s.v, t.v, sizeof s.v);
    }
    assert_true(fabsf(sampled_spectrum_at(&s, 587.56f) - 1.78472f) < 2e-4f);
    /* gold, Johnson & Christy 1972: n = 0.29, k = 2.863 at 582.1 nm */
    assert_true(spectrum_named("metal-Au-eta", &s));
    assert_true(fabsf(sampled_spectrum_at(&s, 582.1f) - 0.29f) < 2e-3f);
    assert_true(spectrum_named("metal-Au-k", &s));
    assert_true(fabsf(sampled_spectrum_at(&s, 582.1f) - 2.863f) < 2e-3f);
    /* MgO, Stephens & Malitson 1952: n = 1.7355 at 589.3 nm (their visible fit) */
    assert_true(spectrum_named("metal-MgO-eta", &s));
    assert_true(fabsf(sampled_spectrum_at(&s, 589.3f) - 1.7355f) < 3e-3f);
    assert_true(spectrum_named("stdillum-D65", &s));
    Color c = sampled_spectrum_rgb_illuminant(&s);
    for (int k = 0; k < 3; k++) assert_true(fabsf(c.c[k] - 1.0f) < 2e-3f);
    assert_true(spectrum_named("stdillum-A", &s));
    assert_true(fabsf(sampled_spectrum_at(&s, 560.0f) - 100.0f) < 1e-3f);
    c = sampled_spectrum_rgb_illuminant(&s);
    assert_true(c.c[0] > c.c[1] && c.c[1] > c.c[2]); /* warm */
    for (int i = 0; spectrum_named_list[i]; i++) assert_true(spectrum_named(spectrum_named_list[i], &s));
    assert_false(spectrum_named("metal-Xx-eta", &s));
    assert_false(spectrum_named("metal-Au-kk", &s));
    assert_false(spectrum_named("glass-XY", &s));
    /* blackbody: peak 1 (Wien: 2898 um K / 5000 K = 579.6 nm) */
    sampled_spectrum_blackbody(5000.0f, &s);
    assert_true(fabsf(sampled_spectrum_at(&s, 579.6f) - 1.0f) < 1e-4f);
}

/* The named illuminants integrate to the chromaticities their standards state: CIE 15:2004
 * table T.8 (F1-F12, D50: x, y to 4 decimals) and SMPTE ST 2065-1 (the ACES white, 0.32168,
 * 0.33767). XYZ is summed at the 5 nm nodes of the CIE 1931 table, the CIE's own method
 * (CIE 15:2004 sec. 7.1), which the 1 nm storage reproduces exactly at those nodes. A
 * tolerance of 6e-5: half a unit of the 4th decimal of the stated value, plus float error. */
static void test_named_illuminants(void **state)
{
    (void)state;
    static const struct { const char *name; double x, y; } T[] = {
        {"stdillum-F1", 0.3131, 0.3371}, {"stdillum-F2", 0.3721, 0.3751}, {"stdillum-F3", 0.4091, 0.3941},
        {"stdillum-F4", 0.4402, 0.4031}, {"stdillum-F5", 0.3138, 0.3452}, {"stdillum-F6", 0.3779, 0.3882},
        {"stdillum-F7", 0.3129, 0.3292}, {"stdillum-F8", 0.3458, 0.3586}, {"stdillum-F9", 0.3741, 0.3727},
        {"stdillum-F10", 0.3458, 0.3588}, {"stdillum-F11", 0.3805, 0.3769}, {"stdillum-F12", 0.4370, 0.4042},
        {"stdillum-D50", 0.3457, 0.3585}, {"illum-acesD60", 0.32168, 0.33767}, {"stdillum-D65", 0.3127, 0.3290},
    };
    static SampledSpectrum s;
    for (size_t t = 0; t < sizeof T / sizeof T[0]; t++) {
        assert_true(spectrum_named(T[t].name, &s));
        assert_false(s.constant);
        double xyz[3] = {0.0, 0.0, 0.0};
        for (int i = 0; i < CIE_SAMPLES; i++) {
            double v = (double)sampled_spectrum_at(&s, (float)(CIE_LAMBDA_MIN + CIE_STEP * i));
            xyz[0] += v * (double)cie_x[i], xyz[1] += v * (double)cie_y[i], xyz[2] += v * (double)cie_z[i];
        }
        double sum = xyz[0] + xyz[1] + xyz[2], x = xyz[0] / sum, y = xyz[1] / sum;
        if (fabs(x - T[t].x) > 6e-5 || fabs(y - T[t].y) > 6e-5)
            fail_msg("%s: (x, y) = (%.5f, %.5f); expected (%.4f, %.4f)", T[t].name, x, y, T[t].x, T[t].y);
    }
    /* the F series is 0 outside its table (380-780 nm), D50 is 100 at 560 nm */
    assert_true(spectrum_named("stdillum-F11", &s));
    assert_true(sampled_spectrum_at(&s, 379.0f) == 0.0f && sampled_spectrum_at(&s, 781.0f) == 0.0f);
    assert_true(fabsf(sampled_spectrum_at(&s, 610.0f) - 55.27f) < 1e-3f); /* the table at 610 nm */
    assert_true(spectrum_named("stdillum-D50", &s));
    assert_true(fabsf(sampled_spectrum_at(&s, 560.0f) - 100.0f) < 1e-3f);
    assert_false(spectrum_named("stdillum-F0", &s));
    assert_false(spectrum_named("stdillum-F13", &s));
    assert_false(spectrum_named("stdillum-F1x", &s));
    assert_false(spectrum_named("stdillum-F", &s));
}

/* Delta lights and the environment with spectra of their own (CstLightDesc.spectrum,
 * cst_scene_set_environment_spectrum): in spectral mode NEE (scene_light_li), light-path
 * starts (scene_emitter_color) and escaped rays (scene_env_radiance) see the spectrum's
 * shape at the luminance of the RGB value; lights without one stay upsampled (RGB x D65). */
static void test_light_spectra(void **state)
{
    (void)state;
    CstError err;
    CstScene *cs = NULL;
    assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
    static SampledSpectrum f11, bb;
    assert_true(spectrum_named("stdillum-F11", &f11));
    sampled_spectrum_blackbody(3000.0f, &bb);
    float l[SAMPLED_SPECTRUM_N];
    for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) l[i] = (float)(SPECTRUM_LAMBDA_MIN + i);
    int id_f11 = 0, id_bb = 0;
    assert_int_equal(cst_scene_add_spectrum(cs, l, f11.v, SAMPLED_SPECTRUM_N, &id_f11, &err), CST_OK);
    assert_int_equal(cst_scene_add_spectrum(cs, l, bb.v, SAMPLED_SPECTRUM_N, &id_bb, &err), CST_OK);
    CstMaterialDesc d;
    cst_material_desc_init(&d, CST_MATERIAL_DIFFUSE);
    int mat = 0;
    assert_int_equal(cst_scene_add_material(cs, &d, &mat, &err), CST_OK);
    CstEmission em = {{1.0f, 1.0f, 1.0f}, 0, 0, 0}; /* an area emitter first: light index 0, no spectrum */
    assert_int_equal(cst_scene_add_sphere(cs, (const float[3]){0, 0, 0}, 1.0f, mat, &em, &err), CST_OK);
    CstLightDesc pt = {0}, dl = {0}, plain = {0};
    pt.type = CST_LIGHT_POINT;
    pt.position[1] = 3.0f;
    pt.intensity[0] = 4.0f, pt.intensity[1] = 3.0f, pt.intensity[2] = 2.0f;
    pt.spectrum = id_f11;
    plain = pt;
    plain.spectrum = 0;
    dl.type = CST_LIGHT_DIRECTIONAL;
    dl.direction[1] = -1.0f;
    dl.intensity[0] = dl.intensity[1] = dl.intensity[2] = 0.5f;
    dl.spectrum = id_bb;
    assert_int_equal(cst_scene_add_light(cs, &pt, &err), CST_OK);    /* light 1 */
    assert_int_equal(cst_scene_add_light(cs, &plain, &err), CST_OK); /* light 2 */
    assert_int_equal(cst_scene_add_light(cs, &dl, &err), CST_OK);    /* light 3 */
    pt.spectrum = 9;
    assert_int_equal(cst_scene_add_light(cs, &pt, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "spectrum 9"));
    const float env[3] = {0.2f, 0.3f, 0.4f};
    assert_int_equal(cst_scene_set_environment_constant(cs, env, &err), CST_OK);
    assert_int_equal(cst_scene_set_environment_spectrum(cs, 5, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_set_environment_spectrum(cs, id_bb, &err), CST_OK);
    assert_int_equal(cst_scene_commit(cs, &err), CST_OK);
    const Scene *s = cs;
    assert_int_equal(s->emitter_sampler.count, 1);
    assert_int_equal(light_env_index(&s->emitter_sampler), 4);
    Wavelengths w = wavelengths_sample(0.3f);
    const SampledSpectrum *sp[5] = {NULL, &f11, NULL, &bb, &bb};
    const Color rgb[5] = {color_s(1.0f), color_rgb(4.0f, 3.0f, 2.0f), color_rgb(4.0f, 3.0f, 2.0f), color_s(0.5f),
                          color_rgb(0.2f, 0.3f, 0.4f)};
    for (int light = 0; light < 5; light++) {
        LightLi ls;
        memset(&ls, 0, sizeof ls);
        ls.light = light;
        ls.li = rgb[light];
        Color got = scene_light_li(s, &ls, &w), path = scene_emitter_color(s, light, rgb[light], &w);
        Color want = spectrum_illuminant(rgb[light], &w);
        if (sp[light]) {
            double y = 0.0;
            for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
                float xyz[3];
                spectrum_cie_xyz((float)(SPECTRUM_LAMBDA_MIN + i), xyz);
                y += (double)sp[light]->v[i] * (double)xyz[1];
            }
            float lum = 0.2126729f * rgb[light].c[0] + 0.7151522f * rgb[light].c[1] + 0.0721750f * rgb[light].c[2];
            for (int i = 0; i < COLOR_LANES; i++) want.c[i] = sampled_spectrum_at(sp[light], w.lambda[i]) * lum / (float)y;
        }
        for (int i = 0; i < COLOR_LANES; i++) {
            if (fabsf(got.c[i] - want.c[i]) > 2e-3f * want.c[i] + 1e-6f ||
                fabsf(path.c[i] - want.c[i]) > 2e-3f * want.c[i] + 1e-6f)
                fail_msg("light %d lane %d (%g nm): NEE %g, light path %g; expected %g", light, i,
                         (double)w.lambda[i], (double)got.c[i], (double)path.c[i], (double)want.c[i]);
        }
    }
    Color e = scene_env_radiance(s, v3(0.0f, 1.0f, 0.0f), &w);
    for (int i = 0; i < COLOR_LANES; i++) {
        LightLi ls;
        memset(&ls, 0, sizeof ls);
        ls.light = 4;
        ls.li = rgb[4];
        assert_true(fabsf(e.c[i] - scene_light_li(s, &ls, &w).c[i]) <= 1e-6f * e.c[i]);
    }
    /* RGB mode ignores the spectra */
    Color rgb_env = scene_env_radiance(s, v3(0.0f, 1.0f, 0.0f), NULL);
    assert_true(rgb_env.c[0] == 0.2f && rgb_env.c[1] == 0.3f && rgb_env.c[2] == 0.4f);
    cst_scene_destroy(cs);
}

static CstStatus spd(const char *text, int *n, float **l, float **v, CstError *err)
{
    err->msg[0] = '\0';
    return spd_read("t.spd", text, strlen(text), l, v, n, err);
}

static void test_spd(void **state)
{
    (void)state;
    CstError err;
    float *l, *v;
    int n;
    assert_int_equal(spd("# gold\n300 1.5 # first\n\n  400\t1.25\r\n500 1e0", &n, &l, &v, &err), CST_OK);
    assert_int_equal(n, 3);
    assert_true(l[0] == 300.0f && v[0] == 1.5f && l[1] == 400.0f && v[1] == 1.25f && l[2] == 500.0f && v[2] == 1.0f);
    free(l), free(v);
    static const struct { const char *text, *msg; } BAD[] = {
        {"300 1.5\n400 x2\n", "t.spd:2:5: \"x2\" is not a number"},
        {"300 1.5\n400\n", "t.spd:2:1: wavelength 400 has no value"},
        {"300 1.5\n  300 2\n", "t.spd:2:3: wavelength 300 does not increase"},
        {"# nothing\n", "t.spd:2:1: no (wavelength, value) pairs"},
        {"-5 1\n", "t.spd:1:1: wavelength -5 is not positive"},
        /* found by fuzz_spd: positive as a double, 0 as the float it is kept as */
        {"6e-62\t1\n82\n6", "t.spd:1:1: wavelength 6e-62 is not positive as a 32-bit float"},
        {"300 nan\n", "t.spd:1:5: \"nan\" is not a number"},
        {"300 1e99\n", "t.spd:1:5: \"1e99\" is not a number"},
    };
    for (size_t i = 0; i < sizeof BAD / sizeof BAD[0]; i++) {
        assert_int_equal(spd(BAD[i].text, &n, &l, &v, &err), CST_ERR_PARSE);
        if (!strstr(err.msg, BAD[i].msg)) fail_msg("\"%s\": got \"%s\"", BAD[i].msg, err.msg);
        assert_null(l);
        assert_null(v);
    }
    assert_int_equal(spd_read_file("/nonexistent/x.spd", &l, &v, &n, &err), CST_ERR_IO);
}

/* A scene of one sphere of material m (built through the public calls), hit from +z. */
static Scene *one_sphere(const CstMaterialDesc *d, SurfaceHit *sh)
{
    CstError err;
    CstScene *cs = NULL;
    assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
    int mat = 0;
    CstMaterialDesc md = *d;
    if (md.type == CST_MATERIAL_CONDUCTOR) {
        const float l[3] = {400.0f, 600.0f, 800.0f}, eta[3] = {1.0f, 0.5f, 0.2f}, k[3] = {2.0f, 3.0f, 4.0f};
        assert_int_equal(cst_scene_add_spectrum(cs, l, eta, 3, &md.eta_spectrum, &err), CST_OK);
        assert_int_equal(cst_scene_add_spectrum(cs, l, k, 3, &md.k_spectrum, &err), CST_OK);
    }
    assert_int_equal(cst_scene_add_material(cs, &md, &mat, &err), CST_OK);
    const float c[3] = {0.0f, 0.0f, 0.0f};
    assert_int_equal(cst_scene_add_sphere(cs, c, 1.0f, mat, NULL, &err), CST_OK);
    assert_int_equal(cst_scene_commit(cs, &err), CST_OK);
    Scene *s = cs;
    Ray r = {v3(0.0f, 0.0f, 5.0f), 0.0f, v3(0.0f, 0.0f, -1.0f), 1e30f, 0.0f};
    assert_true(scene_intersect(s, &r, sh));
    return s;
}

static void test_scene_spectra(void **state)
{
    (void)state;
    CstError err;
    SurfaceHit sh;
    Wavelengths wl = wavelengths_sample(0.3f);
    /* a conductor's eta and k at the path's wavelengths; RGB mode: their reductions */
    CstMaterialDesc d;
    cst_material_desc_init(&d, CST_MATERIAL_CONDUCTOR);
    Scene *s = one_sphere(&d, &sh);
    const Material *m = &s->materials[sh.material];
    assert_true(m->eta_spectrum == 1 && m->k_spectrum == 2);
    Color e = sampled_spectrum_rgb_unbounded(&s->spectra[0]);
    assert_memory_equal(&m->eta, &e, sizeof e);
    Bsdf b;
    scene_bsdf(s, &sh, &wl, &b);
    for (int i = 0; i < COLOR_LANES; i++) {
        float li = wl.lambda[i];
        float want = li <= 600.0f ? 1.0f - 0.5f * (li - 400.0f) / 200.0f : 0.5f - 0.3f * (li - 600.0f) / 200.0f;
        if (li < 400.0f || li > 800.0f) want = 0.0f;
        assert_true(fabsf(b.lobe.conductor.eta.c[i] - want) < 2e-3f);
    }
    cst_scene_destroy(s);

    /* glass with a dispersive ior: scene_bsdf keeps the mean, scene_bsdf_disperse takes the
     * hero's ior and terminates the others; a constant ior spectrum terminates nothing */
    for (int dispersive = 0; dispersive < 2; dispersive++) {
        CstScene *cs = NULL;
        assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
        const float l[2] = {360.0f, 830.0f}, n[2] = {1.6f, dispersive ? 1.5f : 1.6f};
        cst_material_desc_init(&d, CST_MATERIAL_GLASS);
        assert_int_equal(cst_scene_add_spectrum(cs, l, n, dispersive ? 2 : 1, &d.ior_spectrum, &err), CST_OK);
        int mat = 0;
        assert_int_equal(cst_scene_add_material(cs, &d, &mat, &err), CST_OK);
        const float c[3] = {0.0f, 0.0f, 0.0f};
        assert_int_equal(cst_scene_add_sphere(cs, c, 1.0f, mat, NULL, &err), CST_OK);
        assert_int_equal(cst_scene_commit(cs, &err), CST_OK);
        s = cs;
        Ray r = {v3(0.0f, 0.0f, 5.0f), 0.0f, v3(0.0f, 0.0f, -1.0f), 1e30f, 0.0f};
        assert_true(scene_intersect(s, &r, &sh));
        m = &s->materials[sh.material];
        assert_true(m->ior_dispersive == (dispersive != 0));
        Wavelengths w = wavelengths_sample(0.6f), w0 = w;
        scene_bsdf(s, &sh, &w, &b);
        assert_true(b.lobe.dielectric.eta == m->ior);
        scene_bsdf_disperse(s, &sh, &w, &b);
        if (dispersive) {
            float hero = w0.lambda[0];
            float want = 1.6f - 0.1f * (hero - 360.0f) / 470.0f;
            assert_true(fabsf(b.lobe.dielectric.eta - want) < 1e-4f);
            assert_true(w.pdf[0] == w0.pdf[0] / 4.0f);
            for (int i = 1; i < COLOR_LANES; i++) assert_true(w.pdf[i] == 0.0f);
        } else {
            assert_memory_equal(&w, &w0, sizeof w);
            assert_true(b.lobe.dielectric.eta == 1.6f);
        }
        /* RGB mode (no wavelengths) is untouched */
        scene_bsdf_disperse(s, &sh, NULL, &b);
        assert_true(b.lobe.dielectric.eta == m->ior);
        cst_scene_destroy(s);
    }
    /* an emitter with its own spectrum (CstEmission.spectrum): the blackbody's shape at the
     * luminance of its radiance, in emission (scene_emission) and NEE (scene_light_li) */
    {
        CstScene *cs = NULL;
        assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
        static SampledSpectrum bb;
        sampled_spectrum_blackbody(4000.0f, &bb);
        float l[SAMPLED_SPECTRUM_N];
        for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) l[i] = (float)(SPECTRUM_LAMBDA_MIN + i);
        CstEmission em = {{3.0f, 2.0f, 1.0f}, 0, 1, 0};
        assert_int_equal(cst_scene_add_spectrum(cs, l, bb.v, SAMPLED_SPECTRUM_N, &em.spectrum, &err), CST_OK);
        cst_material_desc_init(&d, CST_MATERIAL_DIFFUSE);
        int mat = 0;
        assert_int_equal(cst_scene_add_material(cs, &d, &mat, &err), CST_OK);
        const float c[3] = {0.0f, 0.0f, 0.0f};
        assert_int_equal(cst_scene_add_sphere(cs, c, 1.0f, mat, &em, &err), CST_OK);
        em.spectrum = 7;
        assert_int_equal(cst_scene_add_sphere(cs, c, 2.0f, mat, &em, &err), CST_ERR_INVALID_ARG);
        assert_int_equal(cst_scene_commit(cs, &err), CST_OK);
        s = cs;
        Ray r = {v3(0.0f, 0.0f, 5.0f), 0.0f, v3(0.0f, 0.0f, -1.0f), 1e30f, 0.0f};
        assert_true(scene_intersect(s, &r, &sh));
        Wavelengths w = wavelengths_sample(0.45f);
        Color le = scene_emission(s, &sh, v3(0.0f, 0.0f, 1.0f), &w);
        double y = 0.0;
        for (int i = 0; i < SAMPLED_SPECTRUM_N; i++) {
            float xyz[3];
            spectrum_cie_xyz((float)(SPECTRUM_LAMBDA_MIN + i), xyz);
            y += (double)bb.v[i] * (double)xyz[1];
        }
        float lum = 0.2126729f * 3.0f + 0.7151522f * 2.0f + 0.0721750f * 1.0f;
        for (int i = 0; i < COLOR_LANES; i++) {
            float want = spectrum_blackbody(w.lambda[i], 4000.0f) * lum / (float)y;
            assert_true(fabsf(le.c[i] - want) < 2e-3f * want + 1e-7f);
        }
        cst_scene_destroy(cs);
    }
    /* bad spectra and ids are refused */
    CstScene *cs = NULL;
    assert_int_equal(cst_scene_create(&cs, &err), CST_OK);
    const float l[2] = {500.0f, 400.0f}, v[2] = {1.0f, 1.0f};
    int id = 0;
    assert_int_equal(cst_scene_add_spectrum(cs, l, v, 2, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "does not increase"));
    cst_material_desc_init(&d, CST_MATERIAL_GLASS);
    d.ior_spectrum = 3;
    assert_int_equal(cst_scene_add_material(cs, &d, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "ior_spectrum 3 is not a spectrum of this scene"));
    /* an ior must cover the visible range (0 outside a spectrum's samples, as pbrt-v4) */
    const float l3[2] = {400.0f, 700.0f}, v3_[2] = {1.5f, 1.4f};
    assert_int_equal(cst_scene_add_spectrum(cs, l3, v3_, 2, &d.ior_spectrum, &err), CST_OK);
    assert_int_equal(cst_scene_add_material(cs, &d, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "is 0 at 360 nm"));
    cst_scene_destroy(cs);
}

/* White balance (film/sensor.h): the daylight locus at D50 and D65, the identity at D65's
 * temperature, and the illuminant's own white mapped to (1, 1, 1) on both branches. */
static void test_white_balance(void **state)
{
    (void)state;
    double xy[2], m[3][3];
    sensor_illuminant_xy(5000.0, xy); /* D50: (0.3457, 0.3585) */
    assert_true(fabs(xy[0] - 0.3457) < 3e-4 && fabs(xy[1] - 0.3585) < 3e-4);
    sensor_illuminant_xy(6500.0, xy); /* D65: (0.3127, 0.3290) */
    assert_true(fabs(xy[0] - 0.3127) < 3e-4 && fabs(xy[1] - 0.3290) < 3e-4);
    sensor_illuminant_xy(2000.0, xy); /* a 2000 K blackbody: (0.5267, 0.4133) */
    assert_true(fabs(xy[0] - 0.5267) < 2e-3 && fabs(xy[1] - 0.4133) < 2e-3);
    sensor_white_balance(6500.0, m);
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) assert_true(fabs(m[i][j] - (i == j ? 1.0 : 0.0)) < 3e-3);
    sensor_white_balance(0.0, m);
    assert_true(m[0][0] == 1.0 && m[0][1] == 0.0 && m[2][2] == 1.0);
    static const double K[] = {2500.0, 3500.0, 5000.0, 9000.0, 20000.0};
    for (size_t k = 0; k < sizeof K / sizeof K[0]; k++) {
        sensor_illuminant_xy(K[k], xy);
        double X = xy[0] / xy[1], Z = (1.0 - xy[0] - xy[1]) / xy[1], rgb[3];
        for (int i = 0; i < 3; i++)
            rgb[i] = (double)cie_xyz_to_srgb[i][0] * X + (double)cie_xyz_to_srgb[i][1] + (double)cie_xyz_to_srgb[i][2] * Z;
        sensor_white_balance(K[k], m);
        for (int i = 0; i < 3; i++) {
            double o = m[i][0] * rgb[0] + m[i][1] * rgb[1] + m[i][2] * rgb[2];
            if (!(fabs(o - 1.0) < 1e-4)) fail_msg("%g K: channel %d of the white is %g", K[k], i, o);
        }
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_pairs),
        cmocka_unit_test(test_named),
        cmocka_unit_test(test_named_illuminants),
        cmocka_unit_test(test_light_spectra),
        cmocka_unit_test(test_spd),
        cmocka_unit_test(test_scene_spectra),
        cmocka_unit_test(test_white_balance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
