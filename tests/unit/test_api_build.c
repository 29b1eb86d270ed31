/* The public builder's calls that the pbrt loader needed (issue 24): reading textures back,
 * instancing (objects and instances), environments from the caller's pixels, the camera's
 * mirror flag, look_at and up bounds, and the accel and info calls before commit. Each is
 * checked for what it builds and for the values it rejects (CST_ERR_INVALID_ARG or
 * CST_ERR_UNSUPPORTED with a message naming the value, the scene left as it was). */
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

/* The call failed with `want` and its message mentions `word`. */
static void expect_fail(CstStatus st, CstStatus want, const CstError *e, const char *word)
{
    if (st != want)
        fail_msg("expected %s for \"%s\", got %s (%s)", cst_status_name(want), word, cst_status_name(st), e->msg);
    if (!strstr(e->msg, word)) fail_msg("message \"%s\" does not mention \"%s\"", e->msg, word);
}

static CstScene *scene_with_material(int *mat)
{
    CstError e;
    CstScene *s = NULL;
    CstMaterialDesc md;
    ok(cst_scene_create(&s, &e), &e);
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    ok(cst_scene_add_material(s, &md, mat, &e), &e);
    return s;
}

static CstFilm *render(const CstScene *s, int w, int h, int spp)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.width = w, rs.height = h, rs.spp = spp, rs.threads = 2, rs.seed = 3, rs.seed_set = 1;
    CstFilm *f = NULL;
    CstError e;
    ok(cst_render(s, &rs, &f, NULL, &e), &e);
    return f;
}

static double film_mean(const CstFilm *f)
{
    double sum = 0.0, m[3];
    for (int y = 0; y < cst_film_height(f); y++)
        for (int x = 0; x < cst_film_width(f); x++) {
            cst_film_pixel(f, x, y, m);
            sum += m[0] + m[1] + m[2];
        }
    return sum / (3.0 * cst_film_width(f) * cst_film_height(f));
}

static int films_equal(const CstFilm *a, const CstFilm *b)
{
    for (int y = 0; y < cst_film_height(a); y++)
        for (int x = 0; x < cst_film_width(a); x++) {
            double ma[3], mb[3];
            cst_film_pixel(a, x, y, ma);
            cst_film_pixel(b, x, y, mb);
            if (memcmp(ma, mb, sizeof ma) != 0) return 0;
        }
    return 1;
}

/* ------------------------------------------------------------------ textures */

static void test_texture_info(void **state)
{
    (void)state;
    int mat = 0, a = 0, b = 0, check = 0, img = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_CONSTANT;
    t.value[0] = 0.25f, t.value[1] = 0.5f, t.value[2] = 2.0f;
    ok(cst_scene_add_texture(s, &t, &a, &e), &e);
    t.value[2] = 0.0f;
    ok(cst_scene_add_texture(s, &t, &b, &e), &e);
    CstTextureDesc c = {0};
    c.type = CST_TEXTURE_CHECKERBOARD;
    c.even = a, c.odd = b, c.scale = 3.0f;
    c.uv_scale[0] = 2.0f, c.uv_scale[1] = 0.5f, c.uv_offset[1] = 0.25f;
    ok(cst_scene_add_texture(s, &c, &check, &e), &e);
    const float px[2 * 2 * 3] = {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11};
    CstTextureDesc im = {0};
    im.type = CST_TEXTURE_IMAGE;
    im.pixels = px, im.width = 2, im.height = 2, im.wrap = CST_TEXTURE_WRAP_CLAMP;
    ok(cst_scene_add_texture(s, &im, &img, &e), &e);

    CstTextureInfo info;
    ok(cst_scene_texture_info(s, a, &info, &e), &e);
    assert_int_equal(info.desc.type, CST_TEXTURE_CONSTANT);
    assert_true(info.desc.value[0] == 0.25f && info.desc.value[2] == 2.0f);
    assert_true(info.average[1] == 0.5f && info.max[2] == 2.0f);
    assert_true(info.desc.uv_scale[0] == 1.0f && info.desc.uv_scale[1] == 1.0f);
    ok(cst_scene_texture_info(s, check, &info, &e), &e);
    assert_int_equal(info.desc.type, CST_TEXTURE_CHECKERBOARD);
    assert_int_equal(info.desc.even, a);
    assert_int_equal(info.desc.odd, b);
    assert_true(info.desc.scale == 3.0f);
    assert_true(info.desc.uv_scale[0] == 2.0f && info.desc.uv_scale[1] == 0.5f && info.desc.uv_offset[1] == 0.25f);
    assert_true(info.max[2] == 2.0f); /* the larger of its squares */
    ok(cst_scene_texture_info(s, img, &info, &e), &e);
    assert_int_equal(info.desc.type, CST_TEXTURE_IMAGE);
    assert_int_equal(info.desc.width, 2);
    assert_int_equal(info.desc.height, 2);
    assert_int_equal(info.desc.wrap, CST_TEXTURE_WRAP_CLAMP);
    assert_null(info.desc.path);
    assert_true(info.desc.pixels != px && memcmp(info.desc.pixels, px, sizeof px) == 0); /* the scene's copy */
    assert_true(info.average[0] == 4.5f && info.max[2] == 11.0f);
    /* The description read back adds an equal texture. */
    int again = 0;
    ok(cst_scene_add_texture(s, &info.desc, &again, &e), &e);
    CstTextureInfo info2;
    ok(cst_scene_texture_info(s, again, &info2, &e), &e);
    assert_true(memcmp(info2.desc.pixels, px, sizeof px) == 0 && info2.average[0] == info.average[0]);

    expect_fail(cst_scene_texture_info(s, 0, &info, &e), CST_ERR_INVALID_ARG, &e, "id 0");
    expect_fail(cst_scene_texture_info(s, 9, &info, &e), CST_ERR_INVALID_ARG, &e, "id 9");
    expect_fail(cst_scene_texture_info(s, a, NULL, &e), CST_ERR_INVALID_ARG, &e, "NULL");
    expect_fail(cst_scene_texture_info(NULL, a, &info, &e), CST_ERR_INVALID_ARG, &e, "NULL");
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ instancing */

static const float quad_pos[4][3] = {{-1, -1, 0}, {1, -1, 0}, {1, 1, 0}, {-1, 1, 0}};
static const uint32_t quad_idx[2][3] = {{0, 1, 2}, {0, 2, 3}};

static CstMeshDesc quad_desc(int mat)
{
    CstMeshDesc m = {0};
    m.positions = quad_pos;
    m.num_vertices = 4;
    m.indices = quad_idx;
    m.num_triangles = 2;
    m.material = mat;
    return m;
}

/* A quad lit by a constant sky, seen by the default camera (at z = 5 looking at the
 * origin), added either as a mesh moved by (0.5, 0, 0) or as an object instanced there. */
static CstScene *quad_scene(int instanced)
{
    int mat = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    CstMeshDesc m = quad_desc(mat);
    if (instanced) {
        int obj = -1;
        ok(cst_scene_add_object(s, &m, &obj, NULL, &e), &e);
        assert_int_equal(obj, 0);
        const float xf[12] = {1, 0, 0, 0.5f, 0, 1, 0, 0, 0, 0, 1, 0};
        ok(cst_scene_add_instance(s, obj, xf, &e), &e);
    } else {
        float moved[4][3];
        memcpy(moved, quad_pos, sizeof moved);
        for (int v = 0; v < 4; v++) moved[v][0] += 0.5f;
        m.positions = moved;
        ok(cst_scene_add_mesh(s, &m, NULL, &e), &e);
    }
    ok(cst_scene_set_environment_constant(s, (const float[3]){1, 1, 1}, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

static void test_instances_render_like_meshes(void **state)
{
    (void)state;
    CstScene *mesh = quad_scene(0), *inst = quad_scene(1);
    CstSceneInfo info;
    cst_scene_info(inst, &info);
    assert_int_equal(info.instances, 1);
    assert_int_equal(info.instanced_objects, 1);
    assert_int_equal((int)info.instanced_triangles, 2);
    assert_int_equal(info.triangles, 0);
    CstFilm *a = render(mesh, 24, 24, 4), *b = render(inst, 24, 24, 4);
    double ma = film_mean(a), mb = film_mean(b);
    /* Same geometry, same samples: only the instance's transformed hit points differ, by ulps. */
    assert_true(ma > 0.4 && ma < 1.0);
    assert_true(fabs(ma - mb) < 1e-3 * ma);
    cst_film_destroy(a);
    cst_film_destroy(b);
    cst_scene_destroy(mesh);
    cst_scene_destroy(inst);
}

static void test_object_and_instance_rejects(void **state)
{
    (void)state;
    int mat = 0, obj = -1, dropped = -1;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    const float xf[12] = {1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
    expect_fail(cst_scene_add_instance(s, 0, xf, &e), CST_ERR_INVALID_ARG, &e, "object 0");

    CstMeshDesc m = quad_desc(mat);
    m.emission.radiance[0] = 1.0f;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_UNSUPPORTED, &e, "emission");
    m = quad_desc(mat);
    const float uv[4][2] = {{0, 0}, {1, 0}, {1, NAN}, {0, 1}}; /* objects keep uvs: finite ones */
    m.uvs = uv;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "uv of vertex 2");
    m = quad_desc(mat);
    const CstAlpha cut[2] = {{1, 0.5f, 0}, {1, 0.0f, 9}}; /* and per-triangle cut-outs: checked */
    m.triangle_alphas = cut;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "triangle_alphas[1]");
    m = quad_desc(mat);
    m.material = 4;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "material 4");
    m = quad_desc(mat);
    m.position_stride = 4;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "position_stride 4");
    const uint32_t bad_idx[2][3] = {{0, 1, 2}, {0, 0, 3}}; /* triangle 1 has zero area */
    m = quad_desc(mat);
    m.indices = bad_idx;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "triangle 1");
    const uint32_t all_bad[1][3] = {{0, 0, 3}};
    m.indices = all_bad, m.num_triangles = 1, m.skip_degenerate = 1;
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "zero area");
    assert_true(!s->instances || s->instances->num_protos == 0); /* nothing was added */
    expect_fail(cst_scene_add_object(s, &m, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e, "out_id");

    m.indices = bad_idx, m.num_triangles = 2;
    ok(cst_scene_add_object(s, &m, &obj, &dropped, &e), &e);
    assert_int_equal(obj, 0);
    assert_int_equal(dropped, 1);
    assert_int_equal(s->instances->protos[0].num_triangles, 1);

    expect_fail(cst_scene_add_instance(s, 1, xf, &e), CST_ERR_INVALID_ARG, &e, "object 1");
    expect_fail(cst_scene_add_instance(s, 0, NULL, &e), CST_ERR_INVALID_ARG, &e, "NULL");
    float bad[12];
    memcpy(bad, xf, sizeof bad);
    bad[3] = NAN;
    expect_fail(cst_scene_add_instance(s, 0, bad, &e), CST_ERR_INVALID_ARG, &e, "world_from_object[3]");
    memcpy(bad, xf, sizeof bad);
    bad[5] = 0.0f; /* flattens y */
    expect_fail(cst_scene_add_instance(s, 0, bad, &e), CST_ERR_INVALID_ARG, &e, "singular");
    assert_int_equal(s->instances->num_insts, 0);
    ok(cst_scene_add_instance(s, 0, xf, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    expect_fail(cst_scene_add_instance(s, 0, xf, &e), CST_ERR_INVALID_ARG, &e, "already committed");
    expect_fail(cst_scene_add_object(s, &m, &obj, NULL, &e), CST_ERR_INVALID_ARG, &e, "already committed");
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ environment pixels */

#define ENV_W 8
#define ENV_H 3

/* A pixel of the test map: column x + 1 in red, row y + 1 in green. */
static float env_value(int x, int y, int c) { return c == 0 ? (float)(x + 1) : c == 1 ? (float)(y + 1) : 0.5f; }

/* A scene that sees only the environment: a 1-degree pinhole camera at the origin looking
 * along the horizon at the centre of column `col` (phi = 2 pi (col + 0.5) / ENV_W), the
 * middle row. A far sphere behind the camera gives the scene a shape. */
static CstScene *env_scene(int col, const float *rgb, size_t ps, size_t rs, const float *scale,
                           const float *world_from_map)
{
    int mat = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    double phi = 2.0 * 3.14159265358979323846 * (col + 0.5) / ENV_W;
    CstCameraDesc cam = {0};
    cam.type = CST_CAMERA_PERSPECTIVE;
    cam.look_at[0] = (float)cos(phi), cam.look_at[2] = (float)sin(phi);
    cam.fov = 1.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    const float far[3] = {-100.0f * cam.look_at[0], 0, -100.0f * cam.look_at[2]};
    ok(cst_scene_add_sphere(s, far, 1.0f, mat, NULL, &e), &e);
    ok(cst_scene_set_environment_pixels(s, rgb, ENV_W, ENV_H, ps, rs, scale, world_from_map, &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    return s;
}

static void pixel0(const CstScene *s, double rgb[3])
{
    CstFilm *f = render(s, 1, 1, 1);
    cst_film_pixel(f, 0, 0, rgb);
    cst_film_destroy(f);
}

static void test_environment_pixels(void **state)
{
    (void)state;
    float packed[ENV_H][ENV_W][3];
    /* The same image as RGBA floats in rows padded to 40 floats. */
    float strided[ENV_H][40];
    memset(strided, 0, sizeof strided);
    for (int y = 0; y < ENV_H; y++)
        for (int x = 0; x < ENV_W; x++)
            for (int c = 0; c < 4; c++) {
                if (c < 3) packed[y][x][c] = env_value(x, y, c);
                strided[y][4 * x + c] = c < 3 ? env_value(x, y, c) : -7.0f; /* alpha: never read */
            }
    double rgb[3];
    CstScene *s = env_scene(1, &packed[0][0][0], 0, 0, NULL, NULL);
    pixel0(s, rgb);
    assert_true(rgb[0] == 2.0 && rgb[1] == 2.0 && rgb[2] == 0.5); /* column 1, row 1 */
    CstFilm *a = render(s, 6, 4, 2);
    cst_scene_destroy(s);

    s = env_scene(1, &strided[0][0], 4 * sizeof(float), sizeof strided[0], NULL, NULL);
    CstFilm *b = render(s, 6, 4, 2);
    assert_true(films_equal(a, b)); /* strided = packed, bit for bit */
    cst_film_destroy(b);
    cst_scene_destroy(s);
    const float identity[9] = {1, 0, 0, 0, 1, 0, 0, 0, 1};
    s = env_scene(1, &packed[0][0][0], 0, 0, NULL, identity);
    b = render(s, 6, 4, 2);
    assert_true(films_equal(a, b)); /* the identity resamples nothing */
    cst_film_destroy(a);
    cst_film_destroy(b);
    cst_scene_destroy(s);

    /* Rotated 90 degrees about y (x -> -z, z -> x): world phi sees map phi + 90 degrees,
     * two columns on; scale multiplies. */
    const float rot[9] = {0, 0, 1, 0, 1, 0, -1, 0, 0};
    s = env_scene(1, &packed[0][0][0], 0, 0, (const float[3]){2, 1, 1}, rot);
    pixel0(s, rgb);
    assert_true(rgb[0] == 8.0 && rgb[1] == 2.0 && rgb[2] == 0.5); /* column 3: red 4, times 2 */
    cst_scene_destroy(s);
}

static void test_environment_pixels_rejects(void **state)
{
    (void)state;
    int mat = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    float px[2][4][3];
    for (int i = 0; i < 24; i++) (&px[0][0][0])[i] = 1.0f;
    const float *p = &px[0][0][0];
    expect_fail(cst_scene_set_environment_pixels(s, NULL, 4, 2, 0, 0, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "rgb is NULL");
    expect_fail(cst_scene_set_environment_pixels(s, p, 0, 2, 0, 0, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "0 x 2");
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 8, 0, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "pixel_stride 8");
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 40, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "row_stride 40");
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 0, (const float[3]){1, -1, 1}, NULL, &e),
                CST_ERR_INVALID_ARG, &e, "scale");
    const float singular[9] = {1, 0, 0, 0, 0, 0, 0, 0, 1};
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 0, NULL, singular, &e), CST_ERR_INVALID_ARG, &e,
                "singular");
    px[1][2][1] = -0.5f;
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 0, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "pixel (2, 1)");
    px[1][2][1] = NAN;
    expect_fail(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 0, NULL, NULL, &e), CST_ERR_INVALID_ARG, &e,
                "pixel (2, 1)");
    assert_null(s->env);
    px[1][2][1] = 1.0f;
    ok(cst_scene_set_environment_pixels(s, p, 4, 2, 0, 0, NULL, NULL, &e), &e);
    assert_non_null(s->env);
    assert_int_equal(s->env->width, 4);
    cst_scene_destroy(s);
}

/* ------------------------------------------------------------------ camera, accel, info */

static void test_camera_mirror_and_bounds(void **state)
{
    (void)state;
    int mat = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    CstCameraDesc cam = {CST_CAMERA_PERSPECTIVE, {0, 0, 5}, {0, 0, 0}, {0, 1, 0}, 40, 0, 0, 0, 1};
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    assert_int_equal(s->camera_mirror, 1);
    cam.mirror = 0;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    assert_int_equal(s->camera_mirror, 0);
    cam.mirror = 2;
    expect_fail(cst_scene_set_camera(s, &cam, &e), CST_ERR_INVALID_ARG, &e, "mirror 2");
    cam.mirror = 0;

    /* look_at only gives a direction: past 1e18 is fine, not finite or too far is not. */
    cam.look_at[2] = -4e18f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    assert_true(s->camera.look_at.z == -4e18f);
    cam.look_at[2] = -INFINITY;
    expect_fail(cst_scene_set_camera(s, &cam, &e), CST_ERR_INVALID_ARG, &e, "look_at");
    cam.look_at[2] = -1e30f;
    expect_fail(cst_scene_set_camera(s, &cam, &e), CST_ERR_INVALID_ARG, &e, "too far");
    cam.look_at[2] = 0;

    /* up 1e-5 radians off the view axis: a frame pbrt files use; 1e-7 is none. */
    cam.up[1] = 1e-5f, cam.up[2] = -1.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    cam.up[1] = 1e-7f;
    expect_fail(cst_scene_set_camera(s, &cam, &e), CST_ERR_INVALID_ARG, &e, "parallel");
    cam.up[1] = 1, cam.up[2] = 0;

    /* Orthographic: fov 0 or a field of view, kept for bdpt/vcm's film area. */
    cam.type = CST_CAMERA_ORTHOGRAPHIC, cam.height = 2.0f, cam.fov = 90.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    assert_true(s->camera.vfov_deg == 90.0f && s->camera.ortho_height == 2.0f);
    cam.fov = 0.0f;
    ok(cst_scene_set_camera(s, &cam, &e), &e);
    assert_true(s->camera.vfov_deg == 0.0f);
    cam.fov = 200.0f;
    expect_fail(cst_scene_set_camera(s, &cam, &e), CST_ERR_INVALID_ARG, &e, "fov 200");
    cst_scene_destroy(s);
}

static void test_accel_and_info_before_commit(void **state)
{
    (void)state;
    int mat = 0;
    CstScene *s = scene_with_material(&mat);
    CstError e;
    CstMeshDesc m = quad_desc(mat);
    ok(cst_scene_add_mesh(s, &m, NULL, &e), &e);
    ok(cst_scene_add_sphere(s, (const float[3]){0, 0, -3}, 1.0f, mat, NULL, &e), &e);
    CstSceneInfo info;
    cst_scene_info(s, &info);
    assert_int_equal(info.triangles, 2);
    assert_int_equal(info.spheres, 1);
    assert_int_equal(info.instances, 0);
    expect_fail(cst_scene_set_accel(s, "bih", &e), CST_ERR_INVALID_ARG, &e, "bih");
    ok(cst_scene_set_accel(s, "kdtree", &e), &e);
    ok(cst_scene_commit(s, &e), &e);
    cst_scene_info(s, &info);
    assert_string_equal(info.accel, "kdtree");
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_texture_info),
        cmocka_unit_test(test_instances_render_like_meshes),
        cmocka_unit_test(test_object_and_instance_rejects),
        cmocka_unit_test(test_environment_pixels),
        cmocka_unit_test(test_environment_pixels_rejects),
        cmocka_unit_test(test_camera_mirror_and_bounds),
        cmocka_unit_test(test_accel_and_info_before_commit),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
