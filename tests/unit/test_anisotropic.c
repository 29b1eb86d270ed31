/* Anisotropic roughness outside the BSDF (test_bsdf and test_layered test the lobes): the
 * JSON keys (uroughness, vroughness, base_*, remaproughness) and their errors, the public
 * builder's checks, and scene_bsdf's tangent frame (along dp/du for anisotropic materials,
 * frame_from_normal's for all others, bit for bit). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "caustic/caustic.h"
#include "scene/scene.h"

#define CAM "\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}"
#define SHAPES "\"shapes\": [{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " \
               "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]]}]"
#define SCENE(mats) "{" CAM ", " mats ", " SHAPES "}"

static CstScene *load_ok(const char *text)
{
    CstScene *s = NULL;
    CstError err = {0};
    CstStatus st = cst_scene_load_json_string(text, strlen(text), "t.json", &s, &err);
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), err.msg);
    return s;
}

/* Fails with CST_ERR_INVALID_ARG, a message located in t.json and containing `what`. */
static void load_error(const char *text, const char *what)
{
    CstScene *s = NULL;
    CstError err = {0};
    CstStatus st = cst_scene_load_json_string(text, strlen(text), "t.json", &s, &err);
    assert_null(s);
    if (st != CST_ERR_INVALID_ARG || strncmp(err.msg, "t.json:1:", 9) != 0 || !strstr(err.msg, what))
        fail_msg("got %s \"%s\"; expected a located error with \"%s\"", cst_status_name(st), err.msg, what);
}

static void test_json_keys(void **state)
{
    (void)state;
    CstScene *s = load_ok(SCENE(
        "\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"gold\", \"uroughness\": 0.2, \"vroughness\": 0.6}, "
        "\"b\": {\"type\": \"dielectric\", \"roughness\": 0.3, \"vroughness\": 0.5}, "
        "\"c\": {\"type\": \"coated_conductor\", \"metal\": \"gold\", \"roughness\": 0.1, \"base_roughness\": 0.2, "
        "\"base_vroughness\": 0.7}, "
        "\"d\": {\"type\": \"conductor\", \"metal\": \"gold\", \"uroughness\": 0.25, \"vroughness\": 0.0625, "
        "\"remaproughness\": false}, "
        "\"e\": {\"type\": \"coated_diffuse\", \"uroughness\": 0.4, \"vroughness\": 0.4}}"));
    assert_int_equal(s->num_materials, 5);
    const Material *m = s->materials;
    assert_true(m[0].anisotropic && m[0].roughness == 0.2f && m[0].roughness_v == 0.6f && material_is_anisotropic(&m[0]));
    assert_true(m[1].anisotropic && m[1].roughness == 0.3f && m[1].roughness_v == 0.5f);
    assert_true(m[2].anisotropic && m[2].roughness == 0.1f && m[2].roughness_v == 0.1f);
    assert_true(m[2].base_roughness == 0.2f && m[2].base_roughness_v == 0.7f && material_is_anisotropic(&m[2]));
    assert_true(m[3].anisotropic && m[3].roughness == 0.5f && m[3].roughness_v == 0.25f); /* sqrt(alpha) */
    assert_true(!m[4].anisotropic && !material_is_anisotropic(&m[4]) && m[4].roughness == 0.4f);
    cst_scene_destroy(s);
    load_error(SCENE("\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"gold\", \"vroughness\": 2}}"),
               "materials.white.vroughness: roughness 2 is outside [0, 1]");
    load_error(SCENE("\"materials\": {\"white\": {\"type\": \"plastic\", \"uroughness\": 0.2}}"), "unknown key \"uroughness\"");
    load_error(SCENE("\"materials\": {\"white\": {\"type\": \"coated_diffuse\", \"base_vroughness\": 0.2}}"),
               "unknown key \"base_vroughness\"");
    load_error("{\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [0.5, 0.5, 0.5]}}, " CAM ", "
               "\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"gold\", \"roughness\": \"t\", "
               "\"uroughness\": 0.2}}, " SHAPES "}",
               "uroughness with a roughness texture");
    load_error(SCENE("\"materials\": {\"white\": {\"type\": \"conductor\", \"metal\": \"gold\", \"remaproughness\": 1}}"),
               "materials.white.remaproughness");
}

static CstStatus add_desc(CstScene *s, CstMaterialType t, float ru, float rv, int aniso, int *id, CstError *err)
{
    CstMaterialDesc d;
    cst_material_desc_init(&d, t);
    if (t == CST_MATERIAL_CONDUCTOR || t == CST_MATERIAL_COATED_CONDUCTOR) d.metal = "aluminium";
    d.roughness = ru;
    d.roughness_v = rv;
    d.anisotropic = aniso;
    return cst_scene_add_material(s, &d, id, err);
}

static void test_builder_checks(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err = {0};
    int id = -1;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    assert_int_equal(add_desc(s, CST_MATERIAL_CONDUCTOR, 0.2f, 0.6f, 1, &id, &err), CST_OK);
    assert_int_equal(add_desc(s, CST_MATERIAL_PLASTIC, 0.2f, 0.6f, 1, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "anisotropic roughness on a material of type"));
    assert_int_equal(add_desc(s, CST_MATERIAL_DIELECTRIC, 0.2f, 1.5f, 1, &id, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "roughness_v 1.5"));
    assert_int_equal(add_desc(s, CST_MATERIAL_DIELECTRIC, 0.2f, 0.3f, 2, &id, &err), CST_ERR_INVALID_ARG);
    /* round trip through scene_material_desc */
    CstMaterialDesc d;
    scene_material_desc(&s->materials[0], &d);
    assert_true(d.anisotropic == 1 && d.roughness == 0.2f && d.roughness_v == 0.6f);
    cst_scene_destroy(s);
}

/* One triangle in the plane z = 0 whose uvs make dp/du point along (1, 1, 0)/sqrt(2): an
 * anisotropic material's BSDF frame has s there, t = n x s; an isotropic one keeps
 * frame_from_normal's frame exactly (so its values stay bit-identical). */
static void test_tangent_frame(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err = {0};
    int aniso = -1, iso = -1;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    assert_int_equal(add_desc(s, CST_MATERIAL_CONDUCTOR, 0.2f, 0.6f, 1, &aniso, &err), CST_OK);
    assert_int_equal(add_desc(s, CST_MATERIAL_CONDUCTOR, 0.3f, 0.3f, 1, &iso, &err), CST_OK);
    /* p = u (1, 1, 0) + v (-1, 1, 0) at the vertices */
    const float pos[] = {0, 0, 0, 1, 1, 0, -1, 1, 0}, uv[] = {0, 0, 1, 0, 0, 1};
    const uint32_t idx[] = {0, 1, 2};
    for (int k = 0; k < 2; k++) {
        CstMeshDesc md = {.positions = pos, .num_vertices = 3, .uvs = uv, .indices = idx, .num_triangles = 1};
        md.material = k ? iso : aniso;
        assert_int_equal(cst_scene_add_mesh(s, &md, NULL, &err), CST_OK);
    }
    assert_int_equal(cst_scene_commit(s, &err), CST_OK);
    for (int k = 0; k < 2; k++) {
        SurfaceHit sh = {0};
        sh.prim = (uint32_t)k;
        sh.p = v3(0.0f, 0.5f, 0.0f);
        sh.ng = sh.ns = v3(0.0f, 0.0f, 1.0f);
        sh.material = k ? iso : aniso;
        Bsdf b;
        scene_bsdf(s, &sh, NULL, &b);
        if (k == 0) {
            const float r = 0.70710678f;
            assert_true(fabsf(b.frame.s.x - r) < 1e-6f && fabsf(b.frame.s.y - r) < 1e-6f && b.frame.s.z == 0.0f);
            assert_true(fabsf(b.frame.t.x + r) < 1e-6f && fabsf(b.frame.t.y - r) < 1e-6f);
            assert_true(b.lobe.conductor.alpha == 0.2f * 0.2f && b.lobe.conductor.alpha_y == 0.6f * 0.6f);
        } else {
            Frame f = frame_from_normal(sh.ns);
            assert_memory_equal(&b.frame, &f, sizeof f);
            assert_true(b.lobe.conductor.alpha == 0.3f * 0.3f && b.lobe.conductor.alpha_y == b.lobe.conductor.alpha);
        }
    }
    cst_scene_destroy(s);
}

/* Two roughness textures (pbrt-v4's uroughness and vroughness naming different textures):
 * constant ones give the BSDF the widths (to float rounding: a texture's scalar is its
 * channels' mean) and exactly the frame of the constant anisotropic material, for the
 * conductor, the dielectric and the coated interface; the builder
 * refuses a v texture without anisotropy or without a u texture. */
static void test_textured_widths(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err = {0};
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    int tu = 0, tv = 0;
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_CONSTANT;
    t.value[0] = t.value[1] = t.value[2] = 0.2f;
    assert_int_equal(cst_scene_add_texture(s, &t, &tu, &err), CST_OK);
    t.value[0] = t.value[1] = t.value[2] = 0.6f;
    assert_int_equal(cst_scene_add_texture(s, &t, &tv, &err), CST_OK);
    const CstMaterialType types[3] = {CST_MATERIAL_CONDUCTOR, CST_MATERIAL_DIELECTRIC, CST_MATERIAL_COATED_DIFFUSE};
    int ids[3][2];
    for (int i = 0; i < 3; i++) {
        assert_int_equal(add_desc(s, types[i], 0.2f, 0.6f, 1, &ids[i][0], &err), CST_OK);
        CstMaterialDesc d;
        cst_material_desc_init(&d, types[i]);
        if (types[i] == CST_MATERIAL_CONDUCTOR) d.metal = "aluminium";
        d.roughness = d.roughness_v = 0.9f; /* replaced by the textures */
        d.anisotropic = 1;
        d.roughness_texture = tu;
        d.roughness_v_texture = tv;
        assert_int_equal(cst_scene_add_material(s, &d, &ids[i][1], &err), CST_OK);
    }
    CstMaterialDesc d;
    cst_material_desc_init(&d, CST_MATERIAL_CONDUCTOR);
    d.roughness_texture = tu;
    d.roughness_v_texture = tv;
    int bad = -1;
    assert_int_equal(cst_scene_add_material(s, &d, &bad, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "roughness_v_texture with anisotropic 0"));
    d.anisotropic = 1;
    d.roughness_texture = 0;
    assert_int_equal(cst_scene_add_material(s, &d, &bad, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "roughness_v_texture without a roughness_texture"));
    /* p = u (1, 1, 0) + v (-1, 1, 0) at the vertices */
    const float pos[] = {0, 0, 0, 1, 1, 0, -1, 1, 0}, uv[] = {0, 0, 1, 0, 0, 1};
    const uint32_t idx[] = {0, 1, 2};
    CstMeshDesc md = {.positions = pos, .num_vertices = 3, .uvs = uv, .indices = idx, .num_triangles = 1};
    md.material = ids[0][0];
    assert_int_equal(cst_scene_add_mesh(s, &md, NULL, &err), CST_OK);
    assert_int_equal(cst_scene_commit(s, &err), CST_OK);
    for (int i = 0; i < 3; i++) {
        Bsdf b[2];
        for (int k = 0; k < 2; k++) {
            SurfaceHit sh = {0};
            sh.prim = 0;
            sh.p = v3(0.0f, 0.5f, 0.0f);
            sh.ng = sh.ns = v3(0.0f, 0.0f, 1.0f);
            sh.material = ids[i][k];
            scene_bsdf(s, &sh, NULL, &b[k]);
        }
        assert_memory_equal(&b[0].frame, &b[1].frame, sizeof b[0].frame);
        float w[2][2];
        for (int k = 0; k < 2; k++) {
            if (i == 0) w[k][0] = b[k].lobe.conductor.alpha, w[k][1] = b[k].lobe.conductor.alpha_y;
            else if (i == 1) w[k][0] = b[k].lobe.dielectric.alpha, w[k][1] = b[k].lobe.dielectric.alpha_y;
            else w[k][0] = b[k].lobe.layered.top_alpha, w[k][1] = b[k].lobe.layered.top_alpha_y;
        }
        if (!(fabsf(w[0][0] - w[1][0]) < 1e-6f && fabsf(w[0][1] - w[1][1]) < 1e-6f && fabsf(w[0][0] - 0.04f) < 1e-6f && fabsf(w[0][1] - 0.36f) < 1e-6f))
            fail_msg("type %d: widths (%g, %g) textured, (%g, %g) constant", i, (double)w[1][0], (double)w[1][1],
                     (double)w[0][0], (double)w[0][1]);
    }
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_keys),
        cmocka_unit_test(test_builder_checks),
        cmocka_unit_test(test_tangent_frame),
        cmocka_unit_test(test_textured_widths),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
