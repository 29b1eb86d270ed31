/* The public scene builder (cst_scene_create ... cst_scene_commit): a scene built through
 * it renders bit for bit the image of the same scene in JSON; interleaved, strided vertex
 * buffers give the same scene as packed arrays; every invalid input is rejected with
 * CST_ERR_INVALID_ARG and leaves the scene as it was. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <string.h>

#include "caustic/caustic.h"
#include "scene/scene.h"

static void ok(CstStatus st, const CstError *e)
{
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), e->msg);
}

/* The same scene in JSON; test_matches_json builds it through the API. */
static const char scene_json[] =
    "{\"camera\": {\"type\": \"thinlens\", \"position\": [0, 1, 5], \"look_at\": [0, 0.5, 0], \"fov\": 40,"
    "  \"aperture_radius\": 0.05, \"focus_distance\": 4.5},"
    " \"textures\": {\"a\": {\"type\": \"constant\", \"value\": [0.8, 0.8, 0.8]},"
    "  \"b\": {\"type\": \"constant\", \"value\": [0.1, 0.2, 0.3]},"
    "  \"check\": {\"type\": \"checkerboard\", \"even\": \"a\", \"odd\": \"b\", \"scale\": 4}},"
    " \"materials\": {\"floor\": {\"type\": \"diffuse\", \"albedo\": \"check\"},"
    "  \"glass\": {\"type\": \"dielectric\", \"ior\": 1.5, \"roughness\": 0.3},"
    "  \"gold\": {\"type\": \"conductor\", \"metal\": \"gold\", \"roughness\": 0.2},"
    "  \"plastic\": {\"type\": \"plastic\", \"albedo\": [0.2, 0.5, 0.8], \"roughness\": 0.1}},"
    " \"shapes\": ["
    "  {\"type\": \"mesh\", \"material\": \"floor\", \"vertices\": [[-3, 0, -3], [3, 0, -3], [3, 0, 3], [-3, 0, 3]],"
    "   \"indices\": [[0, 2, 1], [0, 3, 2]], \"uvs\": [[0, 0], [1, 0], [1, 1], [0, 1]],"
    "   \"normals\": [[0, 1, 0], [0, 2, 0], [0, 1, 0.1], [0, 1, 0]]},"
    "  {\"type\": \"sphere\", \"material\": \"glass\", \"center\": [-0.8, 0.5, 0], \"radius\": 0.5},"
    "  {\"type\": \"sphere\", \"material\": \"gold\", \"center\": [0.8, 0.5, 0], \"radius\": 0.5},"
    "  {\"type\": \"sphere\", \"material\": \"plastic\", \"center\": [0, 1.5, -1], \"radius\": 0.4,"
    "   \"emission\": {\"radiance\": [4, 4, 3]}}],"
    " \"lights\": [{\"type\": \"point\", \"position\": [0, 3, 2], \"intensity\": [5, 5, 5]},"
    "  {\"type\": \"spot\", \"position\": [2, 3, 2], \"look_at\": [0, 0, 0], \"intensity\": [10, 10, 10],"
    "   \"cone_angle\": 25, \"cone_delta\": 5},"
    "  {\"type\": \"directional\", \"direction\": [-1, -2, -1], \"irradiance\": [0.5, 0.5, 0.5]}],"
    " \"environment\": {\"radiance\": [0.1, 0.1, 0.15]}}";

/* One vertex of an interleaved buffer, as an application might keep it. */
typedef struct AppVertex {
    float pos[3];
    uint32_t flags; /* something of the application's own between the attributes */
    float normal[3];
    float uv[2];
} AppVertex;

typedef struct AppTriangle {
    uint32_t v[3];
    uint32_t material_tag;
} AppTriangle;

static const AppVertex floor_vertices[4] = {
    {{-3, 0, -3}, 0xdeadu, {0, 1, 0}, {0, 0}},
    {{3, 0, -3}, 0xdeadu, {0, 2, 0}, {1, 0}},
    {{3, 0, 3}, 0xdeadu, {0, 1, 0.1f}, {1, 1}},
    {{-3, 0, 3}, 0xdeadu, {0, 1, 0}, {0, 1}},
};
static const AppTriangle floor_triangles[2] = {{{0, 2, 1}, 7}, {{0, 3, 2}, 7}};

static CstMeshDesc floor_interleaved(int material)
{
    CstMeshDesc m = {0};
    m.positions = floor_vertices[0].pos;
    m.position_stride = sizeof(AppVertex);
    m.normals = floor_vertices[0].normal;
    m.normal_stride = sizeof(AppVertex);
    m.uvs = floor_vertices[0].uv;
    m.uv_stride = sizeof(AppVertex);
    m.num_vertices = 4;
    m.indices = floor_triangles[0].v;
    m.index_stride = sizeof(AppTriangle);
    m.num_triangles = 2;
    m.material = material;
    return m;
}

static CstScene *build_api_scene(void)
{
    CstError e;
    CstScene *s = NULL;
    ok(cst_scene_create(&s, &e), &e);
    CstCameraDesc cam = {CST_CAMERA_PERSPECTIVE, {0, 1, 5}, {0, 0.5f, 0}, {0, 0, 0}, 40, 0.05f, 4.5f, 0, 0};
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    CstTextureDesc ta = {0}, tb = {0}, tc = {0};
    int a = 0, b = 0, check = 0;
    ta.type = tb.type = CST_TEXTURE_CONSTANT;
    ta.value[0] = ta.value[1] = ta.value[2] = 0.8f;
    tb.value[0] = 0.1f, tb.value[1] = 0.2f, tb.value[2] = 0.3f;
    ok(cst_scene_add_texture(s, &ta, &a, &e), &e);
    ok(cst_scene_add_texture(s, &tb, &b, &e), &e);
    tc.type = CST_TEXTURE_CHECKERBOARD;
    tc.even = a, tc.odd = b, tc.scale = 4;
    ok(cst_scene_add_texture(s, &tc, &check, &e), &e);
    CstMaterialDesc md;
    int floor = 0, glass = 0, gold = 0, plastic = 0;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.albedo_texture = check;
    ok(cst_scene_add_material(s, &md, &floor, &e), &e);
    cst_material_desc_init(&md, CST_MATERIAL_DIELECTRIC);
    md.roughness = 0.3f;
    ok(cst_scene_add_material(s, &md, &glass, &e), &e);
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR);
    md.metal = "gold";
    md.roughness = 0.2f;
    ok(cst_scene_add_material(s, &md, &gold, &e), &e);
    cst_material_desc_init(&md, CST_MATERIAL_PLASTIC);
    md.albedo[0] = 0.2f, md.albedo[1] = 0.5f, md.albedo[2] = 0.8f;
    md.roughness = 0.1f;
    ok(cst_scene_add_material(s, &md, &plastic, &e), &e);
    CstMeshDesc mesh = floor_interleaved(floor);
    ok(cst_scene_add_mesh(s, &mesh, NULL, &e), &e);
    ok(cst_scene_add_sphere(s, (const float[3]){-0.8f, 0.5f, 0}, 0.5f, glass, NULL, &e), &e);
    ok(cst_scene_add_sphere(s, (const float[3]){0.8f, 0.5f, 0}, 0.5f, gold, NULL, &e), &e);
    CstEmission em = {{4, 4, 3}, 0, 0, 0};
    ok(cst_scene_add_sphere(s, (const float[3]){0, 1.5f, -1}, 0.4f, plastic, &em, &e), &e);
    CstLightDesc point = {CST_LIGHT_POINT, {0, 3, 2}, {0, 0, 0}, {5, 5, 5}, 0, 0, NULL, 0, {0}, 0, 0, 0.0f, 0};
    CstLightDesc spot = {CST_LIGHT_SPOT, {2, 3, 2}, {-2, -3, -2}, {10, 10, 10}, 25, 5, NULL, 0, {0}, 0, 0, 0.0f, 0};
    CstLightDesc dir = {CST_LIGHT_DIRECTIONAL, {0, 0, 0}, {-1, -2, -1}, {0.5f, 0.5f, 0.5f}, 0, 0, NULL, 0, {0}, 0, 0, 0.0f, 0};
    ok(cst_scene_add_light(s, &point, &e), &e);
    ok(cst_scene_add_light(s, &spot, &e), &e);
    ok(cst_scene_add_light(s, &dir, &e), &e);
    ok(cst_scene_set_environment_constant(s, (const float[3]){0.1f, 0.1f, 0.15f}, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

/* FNV-1a over the film's means: equal hashes = bit-identical images (in practice). */
static uint64_t film_hash(const CstFilm *f)
{
    uint64_t h = 1469598103934665603ull;
    for (int y = 0; y < cst_film_height(f); y++)
        for (int x = 0; x < cst_film_width(f); x++) {
            double rgb[3];
            unsigned char bytes[sizeof rgb];
            cst_film_pixel(f, x, y, rgb);
            memcpy(bytes, rgb, sizeof bytes);
            for (size_t k = 0; k < sizeof bytes; k++) h = (h ^ bytes[k]) * 1099511628211ull;
        }
    return h;
}

static uint64_t render_hash(const CstScene *s, CstIntegrator integrator)
{
    CstRenderSettings rs;
    memset(&rs, 0, sizeof rs);
    rs.width = 40, rs.height = 30, rs.spp = 4, rs.threads = 2;
    rs.seed = 11, rs.seed_set = 1;
    rs.integrator = integrator;
    CstFilm *f = NULL;
    CstError e;
    ok(cst_render(s, &rs, &f, NULL, &e), &e);
    uint64_t h = film_hash(f);
    double rgb[3];
    cst_film_pixel(f, 20, 25, rgb); /* the lit floor: not a black image */
    assert_true(rgb[0] + rgb[1] + rgb[2] > 0.0);
    cst_film_destroy(f);
    return h;
}

static void test_matches_json(void **state)
{
    (void)state;
    CstError e;
    CstScene *json = NULL;
    ok(cst_scene_load_json_string(scene_json, sizeof scene_json - 1, "api.json", &json, &e), &e);
    CstScene *api = build_api_scene();
    static const CstIntegrator integs[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_BDPT, CST_INTEGRATOR_LIGHT};
    for (size_t k = 0; k < sizeof integs / sizeof integs[0]; k++) {
        uint64_t a = render_hash(json, integs[k]), b = render_hash(api, integs[k]);
        if (a != b)
            fail_msg("%s: JSON scene %016llx, API scene %016llx", cst_integrator_name(integs[k]),
                     (unsigned long long)a, (unsigned long long)b);
    }
    cst_scene_destroy(json);
    cst_scene_destroy(api);
}

/* Interleaved buffers with strides give the scene packed arrays give. */
static void test_strided_equals_packed(void **state)
{
    (void)state;
    float pos[4][3], nrm[4][3], uv[4][2];
    uint32_t idx[2][3];
    for (int i = 0; i < 4; i++) {
        memcpy(pos[i], floor_vertices[i].pos, sizeof pos[i]);
        memcpy(nrm[i], floor_vertices[i].normal, sizeof nrm[i]);
        memcpy(uv[i], floor_vertices[i].uv, sizeof uv[i]);
    }
    for (int t = 0; t < 2; t++) memcpy(idx[t], floor_triangles[t].v, sizeof idx[t]);
    CstScene *s[2];
    CstError e;
    for (int k = 0; k < 2; k++) {
        CstMaterialDesc md;
        int mat = 0;
        ok(cst_scene_create(&s[k], &e), &e);
        cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
        ok(cst_scene_add_material(s[k], &md, &mat, &e), &e);
        CstMeshDesc m = floor_interleaved(mat);
        if (k == 1) { /* packed: stride 0 and explicit element sizes */
            m.positions = pos, m.position_stride = 0;
            m.normals = nrm, m.normal_stride = 3 * sizeof(float);
            m.uvs = uv, m.uv_stride = 0;
            m.indices = idx, m.index_stride = 0;
        }
        ok(cst_scene_add_mesh(s[k], &m, NULL, &e), &e);
        ok(cst_scene_set_environment_constant(s[k], (const float[3]){1, 1, 1}, &e), &e);
        CstCameraDesc cam = {CST_CAMERA_PERSPECTIVE, {0, 3, 6}, {0, 0, 0}, {0, 0, 0}, 40, 0, 0, 0, 0};
        ok(cst_scene_set_camera(s[k], &cam, &e), &e);
        ok(cst_scene_commit(s[k], &e), &e);
    }
    assert_int_equal(s[0]->num_positions, 4);
    assert_int_equal(s[0]->num_triangles, s[1]->num_triangles);
    assert_memory_equal(s[0]->positions, s[1]->positions, 4 * sizeof(Vec3));
    assert_memory_equal(s[0]->normals, s[1]->normals, 4 * sizeof(Vec3));
    assert_memory_equal(s[0]->uvs, s[1]->uvs, 4 * sizeof(Vec2));
    assert_memory_equal(s[0]->tri_indices, s[1]->tri_indices, 6 * sizeof(int32_t));
    assert_true(fabsf(s[0]->normals[1].y - 1.0f) < 1e-7f); /* normalised */
    assert_int_equal(render_hash(s[0], CST_INTEGRATOR_PATH), render_hash(s[1], CST_INTEGRATOR_PATH));
    cst_scene_destroy(s[0]);
    cst_scene_destroy(s[1]);
}

/* cst_film_pixels / cst_film_variances: the per-pixel getters' values, rows from the top. */
static void test_film_bulk(void **state)
{
    (void)state;
    CstScene *s = build_api_scene();
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = 13, rs.height = 7, rs.spp = 3, rs.threads = 2;
    CstFilm *f = NULL;
    CstError e;
    ok(cst_render(s, &rs, &f, NULL, &e), &e);
    float rgb[13 * 7 * 3], var[13 * 7 * 3];
    cst_film_pixels(f, rgb);
    cst_film_variances(f, var);
    int nonzero = 0;
    for (int y = 0; y < 7; y++)
        for (int x = 0; x < 13; x++) {
            double m[3], v[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, v);
            for (int c = 0; c < 3; c++) {
                assert_true(rgb[3 * (y * 13 + x) + c] == (float)m[c]);
                assert_true(var[3 * (y * 13 + x) + c] == (float)v[c]);
                nonzero += v[c] > 0.0;
            }
        }
    assert_true(nonzero > 0);
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ rejected input */

typedef struct Fixture {
    CstScene *s;
    int mat, tex;
} Fixture;

static Fixture fixture(void)
{
    Fixture f;
    CstError e;
    CstMaterialDesc md;
    CstTextureDesc td = {0};
    ok(cst_scene_create(&f.s, &e), &e);
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    ok(cst_scene_add_material(f.s, &md, &f.mat, &e), &e);
    td.type = CST_TEXTURE_CONSTANT;
    td.value[0] = 2.0f; /* too bright for an albedo */
    ok(cst_scene_add_texture(f.s, &td, &f.tex, &e), &e);
    return f;
}

/* The call failed with INVALID_ARG, its message mentions `word`, and the scene is as it was. */
static void expect_invalid(const Fixture *f, CstStatus st, const CstError *e, const char *word)
{
    if (st != CST_ERR_INVALID_ARG) fail_msg("expected CST_ERR_INVALID_ARG for \"%s\", got %s", word, cst_status_name(st));
    if (!strstr(e->msg, word)) fail_msg("message \"%s\" does not mention \"%s\"", e->msg, word);
    assert_int_equal(e->status, CST_ERR_INVALID_ARG);
    assert_int_equal(f->s->num_triangles, 0);
    assert_int_equal(f->s->num_positions, 0);
    assert_int_equal(f->s->num_spheres, 0);
    assert_int_equal(f->s->num_delta_lights, 0);
    assert_int_equal(f->s->num_emitters, 0);
}

static void test_rejects_mesh_input(void **state)
{
    (void)state;
    Fixture f = fixture();
    CstError e;
    CstMeshDesc m = floor_interleaved(f.mat);
    AppVertex bad[4];
    memcpy(bad, floor_vertices, sizeof bad);

    bad[2].pos[1] = NAN;
    m.positions = bad[0].pos;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "vertex 2");
    bad[2].pos[1] = INFINITY;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "vertex 2");
    memcpy(bad, floor_vertices, sizeof bad);
    bad[1].normal[0] = bad[1].normal[1] = bad[1].normal[2] = 0.0f;
    m.normals = bad[0].normal;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "normal of vertex 1");
    memcpy(bad, floor_vertices, sizeof bad);
    bad[3].uv[0] = NAN;
    m.uvs = bad[0].uv;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "uv of vertex 3");

    m = floor_interleaved(f.mat);
    m.position_stride = 8;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "position_stride 8");
    m = floor_interleaved(f.mat);
    m.normal_stride = 11;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "normal_stride 11");
    m = floor_interleaved(f.mat);
    m.uv_stride = 4;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "uv_stride 4");
    m = floor_interleaved(f.mat);
    m.index_stride = 8;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "index_stride 8");

    AppTriangle tris[2];
    memcpy(tris, floor_triangles, sizeof tris);
    tris[1].v[2] = 4; /* one past the last vertex */
    m = floor_interleaved(f.mat);
    m.indices = tris[0].v;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "vertex index 4");
    tris[1].v[2] = 3;
    tris[1].v[1] = 0; /* triangle 1 = (0, 0, 3): zero area; triangle 0 must not stay behind */
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "triangle 1");
    m.skip_degenerate = 1;
    int dropped = -1;
    ok(cst_scene_add_mesh(f.s, &m, &dropped, &e), &e);
    assert_int_equal(dropped, 1);
    assert_int_equal(f.s->num_triangles, 1);
    cst_scene_destroy(f.s);

    f = fixture();
    m = floor_interleaved(f.mat);
    m.material = 1;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "material 1");
    m = floor_interleaved(f.mat);
    m.num_triangles = 0;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "0 triangles");
    m = floor_interleaved(f.mat);
    m.emission.radiance[0] = -1.0f;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "emission radiance");
    m = floor_interleaved(f.mat);
    m.emission.radiance[0] = 1.0f;
    m.emission.texture = 5;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &m, NULL, &e), &e, "emission texture 5");
    cst_scene_destroy(f.s);
}

static void test_rejects_other_input(void **state)
{
    (void)state;
    Fixture f = fixture();
    CstError e;
    const float c[3] = {0, 0, 0};
    expect_invalid(&f, cst_scene_add_sphere(f.s, c, -1.0f, f.mat, NULL, &e), &e, "radius -1");
    expect_invalid(&f, cst_scene_add_sphere(f.s, c, 0.0f, f.mat, NULL, &e), &e, "radius 0");
    expect_invalid(&f, cst_scene_add_sphere(f.s, c, NAN, f.mat, NULL, &e), &e, "radius nan");
    expect_invalid(&f, cst_scene_add_sphere(f.s, (const float[3]){0, NAN, 0}, 1.0f, f.mat, NULL, &e), &e, "center");
    expect_invalid(&f, cst_scene_add_sphere(f.s, c, 1.0f, 3, NULL, &e), &e, "material 3");

    CstMaterialDesc md;
    int id = 0;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.albedo[1] = 1.5f;
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "albedo");
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    md.albedo_texture = f.tex;
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "values up to 2");
    md.albedo_texture = 9;
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "albedo_texture 9");
    cst_material_desc_init(&md, CST_MATERIAL_GLASS);
    md.ior = NAN;
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "ior");
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR);
    md.metal = "unobtainium";
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "unknown metal");
    cst_material_desc_init(&md, CST_MATERIAL_CONDUCTOR);
    md.roughness = 1.5f;
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "roughness");
    memset(&md, 0, sizeof md);
    expect_invalid(&f, cst_scene_add_material(f.s, &md, &id, &e), &e, "material type 0");
    assert_int_equal(f.s->num_materials, 1);

    CstTextureDesc td = {0};
    td.type = CST_TEXTURE_CHECKERBOARD;
    td.even = f.tex, td.odd = 0;
    expect_invalid(&f, cst_scene_add_texture(f.s, &td, &id, &e), &e, "odd 0");
    td.type = CST_TEXTURE_IMAGE;
    expect_invalid(&f, cst_scene_add_texture(f.s, &td, &id, &e), &e, "exactly one of path and pixels");
    assert_int_equal(f.s->num_textures, 1);

    CstLightDesc l = {CST_LIGHT_SPOT, {0, 1, 0}, {0, -1, 0}, {1, 1, 1}, 95, 5, NULL, 0, {0}, 0, 0, 0.0f, 0};
    expect_invalid(&f, cst_scene_add_light(f.s, &l, &e), &e, "cone_angle 95");
    l.cone_angle = 30, l.cone_delta = 40;
    expect_invalid(&f, cst_scene_add_light(f.s, &l, &e), &e, "cone_delta 40");
    l.cone_delta = 5, l.direction[1] = 0;
    expect_invalid(&f, cst_scene_add_light(f.s, &l, &e), &e, "no length");
    l.type = CST_LIGHT_POINT, l.position[0] = NAN;
    expect_invalid(&f, cst_scene_add_light(f.s, &l, &e), &e, "position");
    l.position[0] = 0, l.intensity[2] = -1;
    expect_invalid(&f, cst_scene_add_light(f.s, &l, &e), &e, "intensity");
    expect_invalid(&f, cst_scene_set_environment_constant(f.s, (const float[3]){1, INFINITY, 1}, &e), &e, "radiance");
    assert_null(f.s->env);

    CstCameraDesc cam = {CST_CAMERA_PERSPECTIVE, {0, 0, 5}, {0, 0, 0}, {0, 0, 0}, 180, 0, 0, 0, 0};
    expect_invalid(&f, cst_scene_set_camera(f.s, &cam, &e), &e, "fov 180");
    cam.fov = 40, cam.up[2] = 1;
    expect_invalid(&f, cst_scene_set_camera(f.s, &cam, &e), &e, "parallel");
    cam.up[2] = 0, cam.aperture_radius = -0.1f;
    expect_invalid(&f, cst_scene_set_camera(f.s, &cam, &e), &e, "aperture_radius");
    cam.aperture_radius = 0, cam.look_at[2] = 5;
    expect_invalid(&f, cst_scene_set_camera(f.s, &cam, &e), &e, "look_at equals position");
    cam.type = CST_CAMERA_ORTHOGRAPHIC, cam.look_at[2] = 0;
    expect_invalid(&f, cst_scene_set_camera(f.s, &cam, &e), &e, "height");
    assert_false(f.s->camera_set);

    /* After commit nothing can be added; NULL arguments are errors, not crashes. */
    ok(cst_scene_commit(f.s, &e), &e);
    expect_invalid(&f, cst_scene_add_sphere(f.s, c, 1.0f, f.mat, NULL, &e), &e, "already committed");
    expect_invalid(&f, cst_scene_add_mesh(f.s, NULL, NULL, &e), &e, "already committed");
    cst_scene_destroy(f.s);
    CstScene *none = NULL;
    assert_int_equal(cst_scene_create(NULL, &e), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_add_sphere(none, c, 1.0f, 0, NULL, &e), CST_ERR_INVALID_ARG);
}

/* A perspective thin-lens camera and an orthographic one reach the internal camera. */
static void test_camera_types(void **state)
{
    (void)state;
    Fixture f = fixture();
    CstError e;
    CstCameraDesc cam = {CST_CAMERA_ORTHOGRAPHIC, {0, 0, 5}, {0, 0, 0}, {0, 0, 0}, 0, 0, 0, 2.5f, 0};
    ok(cst_scene_set_camera(f.s, &cam, &e), &e);
    assert_true(f.s->camera.ortho_height == 2.5f);
    cam = (CstCameraDesc){CST_CAMERA_PERSPECTIVE, {0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 30, 0.2f, 3, 0, 0};
    ok(cst_scene_set_camera(f.s, &cam, &e), &e);
    assert_true(f.s->camera.ortho_height == 0.0f && f.s->camera.aperture_radius == 0.2f);
    assert_true(f.s->camera.focus_distance == 3.0f && f.s->camera.vfov_deg == 30.0f);
    cst_scene_destroy(f.s);
}

/* The output path and the render settings a scene asks for: set fields replace the scene's,
 * unset ones leave it, resolve reads them back; bad values fail and change nothing. */
static void test_output_and_settings(void **state)
{
    (void)state;
    Fixture f = fixture();
    CstError e;
    assert_null(cst_scene_output_path(f.s));
    ok(cst_scene_set_output_path(f.s, "out.exr", &e), &e);
    assert_string_equal(cst_scene_output_path(f.s), "out.exr");
    assert_int_equal(cst_scene_set_output_path(f.s, "", &e), CST_ERR_INVALID_ARG);
    assert_string_equal(cst_scene_output_path(f.s), "out.exr");

    CstRenderSettings rs, got;
    cst_render_settings_init(&rs);
    rs.width = 64;
    rs.spp = 8;
    rs.max_depth = 0; /* set: unbounded */
    rs.seed = 42;
    rs.seed_set = 1;
    rs.integrator = CST_INTEGRATOR_BDPT;
    ok(cst_scene_set_render_settings(f.s, &rs, &e), &e);
    cst_render_settings_init(&rs); /* all unset: nothing changes */
    rs.height = 32;
    ok(cst_scene_set_render_settings(f.s, &rs, &e), &e);
    cst_render_settings_resolve(f.s, NULL, &got);
    assert_int_equal(got.width, 64);
    assert_int_equal(got.height, 32);
    assert_int_equal(got.spp, 8);
    assert_int_equal(got.max_depth, 0);
    assert_int_equal((int)got.seed, 42);
    assert_int_equal(got.integrator, CST_INTEGRATOR_BDPT);
    assert_int_equal(got.filter, CST_FILTER_BOX); /* never set: the default */

    static const char *const words[] = {"spp", "threads", "integrator", "crop", "photon_radius", "aovs"};
    for (int k = 0; k < 6; k++) {
        cst_render_settings_init(&rs);
        if (k == 0) rs.spp = -3;
        if (k == 1) rs.threads = 4;
        if (k == 2) rs.integrator = (CstIntegrator)99;
        if (k == 3) { rs.crop[0] = 10; rs.crop[1] = 5; rs.crop[2] = 0; rs.crop[3] = 4; }
        if (k == 4) rs.photon_radius = -1.0;
        if (k == 5) rs.aovs = 64;
        assert_int_equal(cst_scene_set_render_settings(f.s, &rs, &e), CST_ERR_INVALID_ARG);
        if (!strstr(e.msg, words[k])) fail_msg("message \"%s\" does not mention \"%s\"", e.msg, words[k]);
    }
    cst_render_settings_resolve(f.s, NULL, &got);
    assert_int_equal(got.spp, 8);
    assert_int_equal(got.integrator, CST_INTEGRATOR_BDPT);
    assert_int_equal(cst_scene_set_render_settings(f.s, NULL, &e), CST_ERR_INVALID_ARG);
    ok(cst_scene_commit(f.s, &e), &e);
    cst_render_settings_init(&rs);
    assert_int_equal(cst_scene_set_render_settings(f.s, &rs, &e), CST_ERR_INVALID_ARG);
    assert_int_equal(cst_scene_set_output_path(f.s, "x.png", &e), CST_ERR_INVALID_ARG);
    cst_scene_destroy(f.s);
}

/* A mesh with a material per triangle and normals stored as given (unit, or zero for a
 * vertex without one); ids out of range and non-unit normals fail and change nothing. */
static void test_mesh_materials_and_unit_normals(void **state)
{
    (void)state;
    Fixture f = fixture();
    CstError e;
    CstMaterialDesc md;
    int mat2 = 0;
    cst_material_desc_init(&md, CST_MATERIAL_MIRROR);
    ok(cst_scene_add_material(f.s, &md, &mat2, &e), &e);
    static const float pos[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    /* 0.6, 0.8 is not exactly unit in float: stored as given, not renormalised */
    static const float nrm[4][3] = {{0, 0, 1}, {0.6f, 0, 0.8f}, {0, 0, 0}, {0, 0, 1}};
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    int tri_mats[2] = {mat2, f.mat};
    CstMeshDesc d = {0};
    d.positions = pos;
    d.num_vertices = 4;
    d.normals = nrm;
    d.normals_unit = 1;
    d.indices = idx;
    d.num_triangles = 2;
    d.material = -1; /* unused with triangle_materials */
    d.triangle_materials = tri_mats;

    tri_mats[1] = 7;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &d, NULL, &e), &e, "triangle_materials[1]");
    tri_mats[1] = f.mat;
    float bad[4][3];
    memcpy(bad, nrm, sizeof bad);
    bad[3][2] = 2.0f;
    d.normals = bad;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &d, NULL, &e), &e, "normals_unit");
    d.normals = nrm;
    d.normals_unit = 2;
    expect_invalid(&f, cst_scene_add_mesh(f.s, &d, NULL, &e), &e, "normals_unit");
    d.normals_unit = 1;

    ok(cst_scene_add_mesh(f.s, &d, NULL, &e), &e);
    assert_int_equal(f.s->num_triangles, 2);
    assert_int_equal(f.s->tri_info[0].material, mat2);
    assert_int_equal(f.s->tri_info[1].material, f.mat);
    assert_true(f.s->normals[1].x == 0.6f && f.s->normals[1].z == 0.8f);
    assert_true(f.s->normals[2].x == 0.0f && f.s->normals[2].y == 0.0f && f.s->normals[2].z == 0.0f);
    assert_int_equal(f.s->normals_partial, 1);
    cst_scene_destroy(f.s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_matches_json),
        cmocka_unit_test(test_strided_equals_packed),
        cmocka_unit_test(test_rejects_mesh_input),
        cmocka_unit_test(test_rejects_other_input),
        cmocka_unit_test(test_camera_types),
        cmocka_unit_test(test_film_bulk),
        cmocka_unit_test(test_output_and_settings),
        cmocka_unit_test(test_mesh_materials_and_unit_normals),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
