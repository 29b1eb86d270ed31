/* Alpha cut-outs (pbrt-v4's Shape "alpha") in light transport: a cut-out quad in front of an
 * emitter against the closed-form coverage, in every accel back end; a cut-away occluder
 * and emitter equal to their absence bit for bit (camera rays, shadow rays, light paths);
 * a scene of cut-outs (textured, stochastic, on an emitter) on which every estimator
 * agrees; and a cut-out leaf inside an instance rendering as the same leaf placed directly. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

/* The colour mode of the renders that compare estimators (`test_alpha --spectral`); the
 * closed forms stay in RGB, where a white emitter is exactly 1. */
static CstColorMode g_color_mode = CST_COLOR_RGB;

static int add_texture(Scene *s, const Texture *t)
{
    int id;
    CstError err;
    assert_int_equal(scene_add_texture(s, t, &id, &err), CST_OK);
    return id;
}

/* A checkerboard of two grey values; returns its public id (1 + index). */
static int add_checker(Scene *s, float even, float odd, float scale)
{
    Texture t;
    texture_constant(&t, color_s(even));
    int e = add_texture(s, &t);
    texture_constant(&t, color_s(odd));
    int o = add_texture(s, &t);
    texture_checkerboard(&t, s->textures, e, o, scale);
    return add_texture(s, &t) + 1;
}

static int add_diffuse(Scene *s, Color albedo)
{
    int id;
    CstError err;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = albedo, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &id, &err), CST_OK);
    return id;
}

/* The quad v0..v3 through the public builder, uvs (0,0), (1,0), (1,1), (0,1), with an
 * alpha (NULL: opaque) and an emission (NULL: none). */
static void add_quad(Scene *s, const float v[4][3], int material, const CstAlpha *alpha, const CstEmission *em)
{
    static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
    static const float uv[8] = {0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f};
    CstMeshDesc d = {0};
    d.positions = v;
    d.num_vertices = 4;
    d.uvs = uv;
    d.indices = idx;
    d.num_triangles = 2;
    d.material = material;
    if (em) d.emission = *em;
    if (alpha) d.alpha = *alpha;
    CstError err;
    if (cst_scene_add_mesh(s, &d, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
}

/* ------------------------------------------------------------------ closed form */

/* A black 1 x 1 quad at y = 0 whose alpha is a 4 x 4 checkerboard of A0 and A1 (or the
 * constant A0 when checker is 0), over a 2 x 2 emitter of radiance 1 at y = -1 facing up,
 * seen straight down by an orthographic camera that frames the quad: a pixel sees the
 * emitter with probability 1 - alpha, so each 8 x 8 block of the 32 x 32 image averages
 * 1 - A0 or 1 - A1, the image their mean. */
static Scene *coverage_scene(int checker, float a0, float a1)
{
    CstError err;
    Scene *s = scene_create();
    int black = add_diffuse(s, color_s(0.0f));
    const float occ[4][3] = {{-0.5f, 0, -0.5f}, {-0.5f, 0, 0.5f}, {0.5f, 0, 0.5f}, {0.5f, 0, -0.5f}};
    const float lit[4][3] = {{-1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, -1}}; /* normal +y */
    CstAlpha alpha = {1, a0, checker ? add_checker(s, a0, a1, 4.0f) : 0};
    CstEmission em = {{1.0f, 1.0f, 1.0f}, 0, 0, 0};
    add_quad(s, lit, black, NULL, &em);
    add_quad(s, occ, black, &alpha, NULL);
    CameraDesc cam = {{0, 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 0.0f, 0.0f, 1.0f, 1.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

static void check_coverage(const Scene *s, const char *what, int checker, float a0, float a1, uint64_t seed)
{
    enum { SIZE = 32, SQUARE = 8 };
    static const char *const names[ACCEL_TYPE_COUNT] = {"bvh", "kdtree", "grid", "list", "embree", "octree"};
    CstError err;
    for (int a = 0; a < ACCEL_TYPE_COUNT; a++) {
        if (!accel_type_available((AccelType)a)) continue; /* embree not built in */
        assert_int_equal(scene_set_accel((Scene *)s, (AccelType)a, &err), CST_OK);
        CstRenderSettings rs = {0};
        rs.width = rs.height = SIZE;
        rs.filter = CST_FILTER_BOX;
        rs.threads = 2;
        CstFilm *f = render_film(s, &rs, CST_INTEGRATOR_PATH, 64, seed);
        double worst = 0.0;
        for (int by = 0; by < SIZE / SQUARE; by++)
            for (int bx = 0; bx < SIZE / SQUARE; bx++) {
                RegionStat r = region_stat(f, bx * SQUARE, by * SQUARE, (bx + 1) * SQUARE, (by + 1) * SQUARE);
                /* which square this is: the block at (0, 0) sets the phase */
                RegionStat r0 = region_stat(f, 0, 0, SQUARE, SQUARE);
                int first = !checker || fabs(r0.mean[0] - (1.0 - (double)a0)) < fabs(r0.mean[0] - (1.0 - (double)a1));
                int is_a0 = !checker || (first ^ ((bx + by) & 1));
                double want = 1.0 - (double)(is_a0 ? a0 : a1);
                /* a deterministic alpha (0 or 1) gives exactly 0 or 1: no variance */
                double z = r.se[0] > 0.0 ? (r.mean[0] - want) / r.se[0] : (r.mean[0] == want ? 0.0 : 1e9);
                if (fabs(z) > worst) worst = fabs(z);
                if (!(fabs(z) <= Z_LIMIT))
                    fail_msg("%s (%s): square (%d, %d): %.6f, closed form %.6f (z = %.2f)", what, names[a], bx, by,
                             r.mean[0], want, z);
            }
        RegionStat all = region_stat(f, 0, 0, SIZE, SIZE);
        double want = checker ? 1.0 - 0.5 * ((double)a0 + (double)a1) : 1.0 - (double)a0;
        double z = all.se[0] > 0.0 ? (all.mean[0] - want) / all.se[0] : (all.mean[0] == want ? 0.0 : 1e9);
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("%s (%s): whole image %.6f, closed form %.6f (z = %.2f)", what, names[a], all.mean[0], want, z);
        print_message("%s (%s): emitter seen through %.5f of the image (closed form %.5f, z = %.2f), largest "
                      "block |z| = %.2f\n", what, names[a], all.mean[0], want, z, worst);
        cst_film_destroy(f);
    }
    assert_int_equal(scene_set_accel((Scene *)s, ACCEL_BVH, &err), CST_OK);
}

/* A black sphere of constant alpha 0.3 between the camera and the emitter, covering the
 * whole view: each ray crosses its near and far sides, each kept independently with
 * probability 0.3, so the image must average (1 - 0.3)^2 = 0.49 (0.7 if the two sides
 * made one choice, as they did when the test's number ignored the hit's distance). */
static void test_sphere_coverage(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int black = add_diffuse(s, color_s(0.0f));
    const float lit[4][3] = {{-1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, -1}}; /* normal +y */
    CstEmission em = {{1.0f, 1.0f, 1.0f}, 0, 0, 0};
    add_quad(s, lit, black, NULL, &em);
    CstAlpha a = {1, 0.3f, 0};
    const float c[3] = {0.0f, 1.5f, 0.0f};
    assert_int_equal(cst_scene_add_sphere_alpha(s, c, 1.0f, black, NULL, &a, &err), CST_OK);
    CameraDesc cam = {{0, 5.0f, 0}, {0, 0, 0}, {0, 0, 1}, 0.0f, 0.0f, 1.0f, 1.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings rs = {0};
    rs.width = rs.height = 32;
    rs.filter = CST_FILTER_BOX;
    CstFilm *f = render_film(s, &rs, CST_INTEGRATOR_PATH, 64, 44);
    RegionStat all = region_stat(f, 0, 0, 32, 32);
    double z = (all.mean[0] - 0.49) / all.se[0];
    print_message("sphere of alpha 0.3, both sides crossed: %.5f, closed form 0.49000 (z = %.2f)\n", all.mean[0], z);
    if (!(fabs(z) <= Z_LIMIT)) fail_msg("sphere coverage %.6f, closed form 0.49 (z = %.2f)", all.mean[0], z);
    cst_film_destroy(f);
    scene_destroy(s);
}

static void test_coverage_closed_form(void **state)
{
    (void)state;
    Scene *s = coverage_scene(1, 0.0f, 1.0f);
    check_coverage(s, "checkerboard alpha 0/1", 1, 0.0f, 1.0f, 41);
    scene_destroy(s);
    s = coverage_scene(1, 0.25f, 0.8f);
    check_coverage(s, "checkerboard alpha 0.25/0.8 (stochastic)", 1, 0.25f, 0.8f, 42);
    scene_destroy(s);
    s = coverage_scene(0, 0.3f, 0.0f);
    check_coverage(s, "constant alpha 0.3 (stochastic)", 0, 0.3f, 0.0f, 43);
    scene_destroy(s);
}

/* ------------------------------------------------------------------ holes are absent */

/* A diffuse floor lit by a small emitter above it; with `blocker`, an occluder between them
 * of constant alpha 0 (camera rays, shadow rays and light paths pass it as if it were not
 * there) and a second emitter of alpha 0 (never hit, emits nothing). */
static Scene *hole_scene(int blocker)
{
    CstError err;
    Scene *s = scene_create();
    int white = add_diffuse(s, color_s(0.7f));
    const float floor_q[4][3] = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    const float light_q[4][3] = {{-0.5f, 2, -0.5f}, {0.5f, 2, -0.5f}, {0.5f, 2, 0.5f}, {-0.5f, 2, 0.5f}};
    const float occ_q[4][3] = {{-1, 1, -1}, {-1, 1, 1}, {1, 1, 1}, {1, 1, -1}};
    const float dead_q[4][3] = {{1, 1.5f, -1}, {1.5f, 1.5f, -1}, {1.5f, 1.5f, -0.5f}, {1, 1.5f, -0.5f}};
    CstEmission em = {{4.0f, 4.0f, 4.0f}, 0, 0, 0};
    add_quad(s, floor_q, white, NULL, NULL);
    add_quad(s, light_q, white, NULL, &em);
    if (blocker) {
        CstAlpha cut = {1, 0.0f, 0};
        add_quad(s, occ_q, white, &cut, NULL);
        CstEmission em2 = {{9.0f, 9.0f, 9.0f}, 0, 1, 0};
        add_quad(s, dead_q, white, &cut, &em2);
    }
    CameraDesc cam = {{0, 3.0f, -4.0f}, {0, 0.5f, 0}, {0, 1, 0}, 50.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* The cut-away emitter still takes its share of the light selection (as pbrt-v4's does),
 * so estimators that sample lights differ in noise, not in mean; the path tracer without
 * NEE and a render without lights sampled are compared bit for bit, the others by mean. */
static void test_holes_are_absent(void **state)
{
    (void)state;
    enum { SIZE = 24 };
    Scene *open_s = hole_scene(0), *cut_s = hole_scene(1);
    CstRenderSettings rs = {0};
    rs.width = rs.height = SIZE;
    rs.filter = CST_FILTER_BOX;
    rs.color_mode = g_color_mode;
    CstFilm *a = render_film(open_s, &rs, CST_INTEGRATOR_PATH_BSDF, 16, 7);
    CstFilm *b = render_film(cut_s, &rs, CST_INTEGRATOR_PATH_BSDF, 16, 7);
    for (int y = 0; y < SIZE; y++)
        for (int x = 0; x < SIZE; x++) {
            double pa[3], pb[3];
            cst_film_pixel(a, x, y, pa);
            cst_film_pixel(b, x, y, pb);
            if (memcmp(pa, pb, sizeof pa) != 0)
                fail_msg("path-bsdf: pixel (%d, %d) differs with an alpha-0 occluder: %.9g vs %.9g", x, y, pa[0], pb[0]);
        }
    cst_film_destroy(a);
    cst_film_destroy(b);
    print_message("path-bsdf: an alpha-0 occluder and emitter leave every pixel bit-identical\n");
    Regions ro = regions(SIZE, SIZE / 2), rc = ro, rl = ro, rlc = ro;
    camera_regions(open_s, &rs, CST_INTEGRATOR_PATH, 256, 8, &ro);
    camera_regions(cut_s, &rs, CST_INTEGRATOR_PATH, 256, 9, &rc);
    compare(&ro, &rc, "path, no occluder", "path, alpha-0 occluder and emitter");
    split_regions(open_s, &rs, CST_INTEGRATOR_LIGHT, 64, 1000, &rl);
    split_regions(cut_s, &rs, CST_INTEGRATOR_LIGHT, 64, 2000, &rlc);
    compare(&rl, &rlc, "light, no occluder", "light, alpha-0 occluder and emitter");
    scene_destroy(open_s);
    scene_destroy(cut_s);
}

/* ------------------------------------------------------------------ consistency */

/* A floor, a leaf quad with a checkerboard alpha of 0 and 1 over it, a sphere of constant
 * alpha 0.5, lit by a quad emitter whose alpha is a checkerboard of 0 and 0.6 (cut parts
 * neither hit nor emitting, the rest stochastic) and a small opaque emitting sphere. */
static Scene *alpha_scene(void)
{
    CstError err;
    Scene *s = scene_create();
    int floor_m = add_diffuse(s, color_rgb(0.8f, 0.6f, 0.4f));
    int leaf_m = add_diffuse(s, color_rgb(0.2f, 0.7f, 0.3f));
    int ball_m = add_diffuse(s, color_rgb(0.3f, 0.4f, 0.9f));
    int black = add_diffuse(s, color_s(0.0f));
    const float floor_q[4][3] = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    const float leaf_q[4][3] = {{-1.2f, 1, -1}, {-1.2f, 1, 1}, {0.8f, 1.2f, 1}, {0.8f, 1.2f, -1}};
    const float light_q[4][3] = {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}}; /* normal -y */
    add_quad(s, floor_q, floor_m, NULL, NULL);
    CstAlpha leaf_a = {1, 0.0f, add_checker(s, 0.0f, 0.6f, 3.0f)};
    add_quad(s, leaf_q, leaf_m, &leaf_a, NULL);
    CstAlpha light_a = {1, 0.0f, add_checker(s, 0.0f, 0.6f, 2.0f)};
    CstEmission em = {{5.0f, 5.0f, 5.0f}, 0, 0, 0};
    add_quad(s, light_q, black, &light_a, &em);
    CstAlpha half = {1, 0.5f, 0};
    const float c[3] = {0.7f, 0.45f, 0.2f}, c2[3] = {-0.9f, 0.6f, 0.6f};
    assert_int_equal(cst_scene_add_sphere_alpha(s, c, 0.4f, ball_m, NULL, &half, &err), CST_OK);
    CstEmission em2 = {{3.0f, 2.0f, 1.0f}, 0, 0, 0};
    assert_int_equal(cst_scene_add_sphere(s, c2, 0.15f, black, &em2, &err), CST_OK);
    CameraDesc cam = {{0, 1.4f, -3.4f}, {0, 0.5f, 0}, {0, 1, 0}, 55.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

enum { CSIZE = 32, CBLOCK = 8 };

static void test_alpha_estimators_agree(void **state)
{
    (void)state;
    Scene *s = alpha_scene();
    CstRenderSettings rs = {0};
    rs.width = rs.height = CSIZE;
    rs.filter = CST_FILTER_BOX;
    rs.color_mode = g_color_mode;
    Regions rp = regions(CSIZE, CBLOCK), rn = rp, rb = rp, rl = rp, rd = rp, rv = rp;
    camera_regions(s, &rs, CST_INTEGRATOR_PATH, 512, 21, &rp);
    camera_regions(s, &rs, CST_INTEGRATOR_PATH_NEE, 512, 22, &rn);
    camera_regions(s, &rs, CST_INTEGRATOR_PATH_BSDF, 1024, 23, &rb);
    split_regions(s, &rs, CST_INTEGRATOR_LIGHT, 128, 24000, &rl);
    split_regions(s, &rs, CST_INTEGRATOR_BDPT, 48, 25000, &rd);
    split_regions(s, &rs, CST_INTEGRATOR_VCM, 48, 26000, &rv);
    compare(&rp, &rn, "path", "path-nee");
    compare(&rp, &rb, "path", "path-bsdf");
    compare(&rp, &rl, "path", "light");
    compare(&rp, &rd, "path", "bdpt");
    compare(&rp, &rv, "path", "vcm");
    scene_destroy(s);
}

/* ------------------------------------------------------------------ instanced cut-outs */

/* A floor lit by a quad emitter above it, with a leaf between them whose alpha is a
 * checkerboard of 0 and 0.6 over its uvs (cut parts and stochastic parts): camera rays
 * meet the leaf from the side, shadow rays from the floor cross it. world_from_leaf places
 * the leaf (3 x 4 rows); `instanced`: as an object placed by that transform, else as a mesh
 * of the transformed vertices, added first so that its triangles are primitives 0 and 1,
 * as in the object (the stochastic test hashes the triangle's index). */
static Scene *leaf_scene(int instanced, const float world_from_leaf[12])
{
    CstError err;
    Scene *s = scene_create();
    int floor_m = add_diffuse(s, color_rgb(0.8f, 0.6f, 0.4f));
    int leaf_m = add_diffuse(s, color_rgb(0.2f, 0.7f, 0.3f));
    int black = add_diffuse(s, color_s(0.0f));
    CstAlpha leaf_a = {1, 0.0f, add_checker(s, 0.0f, 0.6f, 3.0f)};
    const float leaf_q[4][3] = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
    float placed[4][3];
    for (int v = 0; v < 4; v++)
        for (int r = 0; r < 3; r++)
            placed[v][r] = world_from_leaf[4 * r] * leaf_q[v][0] + world_from_leaf[4 * r + 1] * leaf_q[v][1] +
                           world_from_leaf[4 * r + 2] * leaf_q[v][2] + world_from_leaf[4 * r + 3];
    if (instanced) {
        static const uint32_t idx[6] = {0, 1, 2, 0, 2, 3};
        static const float uv[8] = {0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f};
        CstMeshDesc d = {0};
        d.positions = leaf_q;
        d.num_vertices = 4;
        d.uvs = uv;
        d.indices = idx;
        d.num_triangles = 2;
        d.material = leaf_m;
        d.alpha = leaf_a;
        int obj;
        if (cst_scene_add_object(s, &d, &obj, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
        if (cst_scene_add_instance(s, obj, world_from_leaf, &err) != CST_OK) fail_msg("%s", err.msg);
    } else {
        add_quad(s, (const float(*)[3])placed, leaf_m, &leaf_a, NULL);
    }
    const float floor_q[4][3] = {{-2, 0, -2}, {-2, 0, 2}, {2, 0, 2}, {2, 0, -2}};
    const float light_q[4][3] = {{-1, 2, -1}, {1, 2, -1}, {1, 2, 1}, {-1, 2, 1}}; /* normal -y */
    CstEmission em = {{5.0f, 5.0f, 5.0f}, 0, 0, 0};
    add_quad(s, floor_q, floor_m, NULL, NULL);
    add_quad(s, light_q, black, NULL, &em);
    CameraDesc cam = {{0, 1.4f, -3.4f}, {0, 0.5f, 0}, {0, 1, 0}, 55.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* The leaf as an object placed by a translation, and by a rotation, scale and translation,
 * agrees with the same leaf placed directly as a mesh within Z_LIMIT standard errors, per
 * block and over the image (path: camera rays through the cut-out, NEE's shadow rays from
 * the floor through it). Not bit for bit: an instance applies its transform to the ray
 * (docs/pbrt-compat.md), so hit distances differ in their last bits, and the stochastic
 * test hashes the distance. */
static void test_instanced_alpha(void **state)
{
    (void)state;
    enum { SIZE = 24 };
    const float lift[12] = {1, 0, 0, 0, 0, 1, 0, 1.0f, 0, 0, 1, 0}; /* the leaf at y = 1 */
    /* 0.8 x a rotation by 0.5 rad about z, lifted to y = 1 (the leaf tilts over the floor) */
    const float c = 0.8f * cosf(0.5f), sn = 0.8f * sinf(0.5f);
    const float tilted[12] = {c, -sn, 0, 0.1f, sn, c, 0, 1.0f, 0, 0, 0.8f, 0.2f};
    const float *const placements[2] = {lift, tilted};
    const char *const names[2] = {"lifted", "tilted"};
    CstRenderSettings rs = {0};
    rs.width = rs.height = SIZE;
    rs.filter = CST_FILTER_BOX;
    rs.color_mode = g_color_mode;
    for (int k = 0; k < 2; k++) {
        Scene *direct = leaf_scene(0, placements[k]), *inst = leaf_scene(1, placements[k]);
        Regions rd = regions(SIZE, SIZE / 4), ri = rd;
        camera_regions(direct, &rs, CST_INTEGRATOR_PATH, 64, 31 + (uint64_t)k, &rd);
        camera_regions(inst, &rs, CST_INTEGRATOR_PATH, 64, 41 + (uint64_t)k, &ri);
        char na[64], nb[64];
        snprintf(na, sizeof na, "path, %s leaf placed directly", names[k]);
        snprintf(nb, sizeof nb, "path, %s leaf as an instance", names[k]);
        compare(&rd, &ri, na, nb);
        scene_destroy(direct);
        scene_destroy(inst);
    }
}

/* ------------------------------------------------------------------ JSON "alpha" */

static Scene *json_ok(const char *text)
{
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_string(text, strlen(text), "t.json", &s, &err) != CST_OK)
        fail_msg("%s\ntext: %s", err.msg, text);
    return s;
}

/* Fails with a message located at the first `needle` (line 1, so its column) and holding `what`. */
static void json_bad(const char *text, const char *needle, const char *what)
{
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), "t.json", &s, &err), CST_ERR_INVALID_ARG);
    assert_null(s);
    char prefix[32];
    snprintf(prefix, sizeof prefix, "t.json:1:%d: ", (int)(strstr(text, needle) - text) + 1);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0 || !strstr(err.msg, what))
        fail_msg("message \"%s\"; expected \"%s...%s...\"", err.msg, prefix, what);
}

#define JHEAD "\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40}, " \
              "\"materials\": {\"white\": {\"type\": \"diffuse\"}}, "
#define JQUAD(alpha) "{" JHEAD "\"shapes\": [{\"type\": \"quad\", \"material\": \"white\", \"vertices\": " \
              "[[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], \"alpha\": " alpha "}]}"

/* A shape's "alpha": a number from 0 to 1 or a texture name; absent or 1 costs nothing; a
 * moving mesh keeps it. */
static void test_json_alpha(void **state)
{
    (void)state;
    Scene *s = json_ok(JQUAD("0.25"));
    assert_int_equal(s->num_alphas, 1);
    assert_true(s->alphas[0].value == 0.25f && s->alphas[0].texture == 0);
    assert_true(s->tri_info[0].alpha == 1 && s->tri_info[1].alpha == 1);
    scene_destroy(s);
    s = json_ok(JQUAD("1"));
    assert_int_equal(s->num_alphas, 0); /* opaque: no cut-out, no cost */
    scene_destroy(s);
    s = json_ok("{\"textures\": {\"leaf\": {\"type\": \"checkerboard\", \"scale\": 4, \"even\": [0, 0, 0], "
                "\"odd\": [1, 1, 1]}}, " JHEAD "\"shapes\": [{\"type\": \"sphere\", \"material\": \"white\", "
                "\"center\": [0, 0, 0], \"radius\": 1, \"alpha\": \"leaf\"}]}");
    assert_int_equal(s->num_alphas, 1);
    assert_true(s->alphas[0].texture > 0);
    assert_int_equal(s->sphere_info[0].alpha, 1);
    scene_destroy(s);
    /* a moving mesh is an instanced object: it keeps its uvs and its cut-out */
    s = json_ok("{" JHEAD "\"shapes\": [{\"type\": \"mesh\", \"material\": \"white\", \"vertices\": "
                "[[0, 0, 0], [1, 0, 0], [1, 1, 0]], \"indices\": [[0, 1, 2]], \"uvs\": [[0, 0], [1, 0], [1, 1]], "
                "\"alpha\": 0.5, \"motion\": {\"transform_end\": {\"translate\": [1, 0, 0]}}}]}");
    assert_non_null(s->instances);
    assert_non_null(s->instances->protos[0].uvs);
    assert_true(s->instances->protos[0].tri_alpha && s->instances->protos[0].tri_alpha[0] == 1);
    assert_true(s->num_alphas == 1 && s->alphas[0].value == 0.5f);
    scene_destroy(s);
    json_bad(JQUAD("-0.5"), "-0.5", "alpha -0.5 is negative");
    json_bad(JQUAD("1.5"), "1.5", "shapes[0].alpha");
    json_bad(JQUAD("true"), "true", "expected a number from 0 to 1 or a texture name");
    json_bad(JQUAD("\"nope\""), "\"nope\"", "texture \"nope\" is not defined");
}

int main(int argc, char **argv)
{
    if (argc > 1 && strcmp(argv[1], "--spectral") == 0) g_color_mode = CST_COLOR_SPECTRAL;
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_json_alpha),
        cmocka_unit_test(test_coverage_closed_form),
        cmocka_unit_test(test_sphere_coverage),
        cmocka_unit_test(test_holes_are_absent),
        cmocka_unit_test(test_alpha_estimators_agree),
        cmocka_unit_test(test_instanced_alpha),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
