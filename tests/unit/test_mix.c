/* The mix material (pbrt-v4's MixMaterial): scene_bsdf's choice per hit against its
 * probabilities (binomial z-tests), nested mixes, an amount texture, determinism per hit,
 * and the builder's checks. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "scene/scene.h"

/* |z| beyond which a frequency disagrees with its probability. */
static const double Z_LIMIT = 4.0;

static CstScene *new_scene(void)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    return s;
}

static int add(CstScene *s, CstMaterialType t, float albedo)
{
    CstMaterialDesc d;
    cst_material_desc_init(&d, t);
    d.albedo[0] = d.albedo[1] = d.albedo[2] = albedo;
    int id = -1;
    CstError err;
    assert_int_equal(cst_scene_add_material(s, &d, &id, &err), CST_OK);
    return id;
}

static int add_mix(CstScene *s, int a, int b, float amount, int amount_texture)
{
    CstMaterialDesc d;
    cst_material_desc_init(&d, CST_MATERIAL_MIX);
    d.mix_materials[0] = a;
    d.mix_materials[1] = b;
    d.amount = amount;
    d.amount_texture = amount_texture;
    int id = -1;
    CstError err;
    CstStatus st = cst_scene_add_material(s, &d, &id, &err);
    if (st != CST_OK) fail_msg("%s", err.msg);
    return id;
}

/* The frequencies with which N random hits choose each material. */
static void frequencies(const Scene *s, int mix, int n, double *freq)
{
    for (int i = 0; i < s->num_materials; i++) freq[i] = 0.0;
    Pcg32 r;
    pcg32_seed(&r, 2024u, 7u);
    for (int i = 0; i < n; i++) {
        SurfaceHit sh = {0};
        sh.p = v3(pcg32_float(&r), pcg32_float(&r), pcg32_float(&r));
        sh.prim = pcg32_next(&r) & 0xffffu;
        sh.material = mix;
        const Material *m = scene_mix_choose(s, &s->materials[mix], &sh);
        freq[m - s->materials] += 1.0 / n;
        /* the same hit always chooses the same */
        assert_ptr_equal(m, scene_mix_choose(s, &s->materials[mix], &sh));
    }
}

static void expect_freq(double f, double p, int n, const char *what)
{
    double se = sqrt(p * (1.0 - p) / n);
    double z = se > 0.0 ? (f - p) / se : (fabs(f - p) < 1e-9 ? 0.0 : HUGE_VAL);
    print_message("%s: frequency %.5f, probability %.5f, z %.2f\n", what, f, p, z);
    if (!(fabs(z) <= Z_LIMIT)) fail_msg("%s: frequency %.5f, expected %.5f (z %.2f)", what, f, p, z);
}

static void test_choice(void **state)
{
    (void)state;
    enum { N = 200000 };
    CstScene *s = new_scene();
    int a = add(s, CST_MATERIAL_DIFFUSE, 0.2f), b = add(s, CST_MATERIAL_MIRROR, 1.0f);
    int c = add(s, CST_MATERIAL_COATED_DIFFUSE, 0.5f);
    int m1 = add_mix(s, a, b, 0.3f, 0), m0 = add_mix(s, a, b, 0.0f, 0), m_one = add_mix(s, a, b, 1.0f, 0);
    int nested = add_mix(s, m1, c, 0.6f, 0);
    CstTextureDesc td = {0};
    td.type = CST_TEXTURE_CONSTANT;
    td.value[0] = td.value[1] = td.value[2] = 0.8f;
    int tex = -1;
    CstError err;
    assert_int_equal(cst_scene_add_texture(s, &td, &tex, &err), CST_OK);
    int mt = add_mix(s, a, b, 0.5f, tex);
    double f[16];
    frequencies(s, m1, N, f);
    expect_freq(f[b], 0.3, N, "mix amount 0.3: second");
    expect_freq(f[a], 0.7, N, "mix amount 0.3: first");
    frequencies(s, m0, N, f);
    expect_freq(f[a], 1.0, N, "mix amount 0: first");
    frequencies(s, m_one, N, f);
    expect_freq(f[b], 1.0, N, "mix amount 1: second");
    frequencies(s, nested, N, f);
    expect_freq(f[c], 0.6, N, "nested: c");
    expect_freq(f[a], 0.4 * 0.7, N, "nested: a");
    expect_freq(f[b], 0.4 * 0.3, N, "nested: b");
    frequencies(s, mt, N, f);
    expect_freq(f[b], 0.8, N, "amount texture 0.8: second");
    cst_scene_destroy(s);
}

/* scene_bsdf builds the chosen material's BSDF: the mean albedo over hits is the blend. */
static void test_bsdf_blend(void **state)
{
    (void)state;
    enum { N = 100000 };
    CstScene *s = new_scene();
    int a = add(s, CST_MATERIAL_DIFFUSE, 0.2f), b = add(s, CST_MATERIAL_DIFFUSE, 0.9f);
    int m = add_mix(s, a, b, 0.25f, 0);
    Pcg32 r;
    pcg32_seed(&r, 5u, 5u);
    double sum = 0.0, sum2 = 0.0;
    for (int i = 0; i < N; i++) {
        SurfaceHit sh = {0};
        sh.p = v3(pcg32_float(&r), pcg32_float(&r), 0.0f);
        sh.ng = sh.ns = v3(0.0f, 0.0f, 1.0f);
        sh.material = m;
        Bsdf bsdf;
        scene_bsdf(s, &sh, NULL, &bsdf);
        double v = (double)color_channel(bsdf_albedo(&bsdf), 0);
        sum += v;
        sum2 += v * v;
    }
    double mean = sum / N, se = sqrt((sum2 / N - mean * mean) / N), want = 0.75 * 0.2 + 0.25 * 0.9;
    print_message("mix of diffuse 0.2 and 0.9, amount 0.25: mean albedo %.5f (se %.1e), blend %.5f\n", mean, se, want);
    assert_true(fabs(mean - want) <= Z_LIMIT * se);
    cst_scene_destroy(s);
}

static void test_builder_errors(void **state)
{
    (void)state;
    CstScene *s = new_scene();
    int a = add(s, CST_MATERIAL_DIFFUSE, 0.5f);
    CstMaterialDesc d;
    cst_material_desc_init(&d, CST_MATERIAL_MIX);
    assert_true(d.amount == 0.5f);
    d.mix_materials[0] = a;
    d.mix_materials[1] = a + 1; /* not added yet: also what keeps chains of mixes finite */
    int id;
    CstError err;
    assert_int_equal(cst_scene_add_material(s, &d, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "mix_materials[1] = 1 is not a material"));
    d.mix_materials[1] = a;
    d.amount = 1.5f;
    assert_int_equal(cst_scene_add_material(s, &d, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "amount 1.5 is outside [0, 1]"));
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_choice),
        cmocka_unit_test(test_bsdf_blend),
        cmocka_unit_test(test_builder_errors),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
