/* Unit tests for textures (textures/texture.c) and texture coordinates: exact bilinear
 * lookups and wrapping on a tiny image, sRGB decoding of 8-bit files, float formats taken
 * as they are, checkerboards, uvs at triangle, quad, sphere and instance hits and at
 * sampled emitter points, and the JSON "textures" section with its errors. */
#define _POSIX_C_SOURCE 200809L

#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <stb_image_write.h>

#include "io/image_io.h"
#include "scene/scene.h"
#include "textures/texture.h"

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_texture.XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static void assert_rgb_near(Color got, double r, double g, double b, double tol)
{
    if (!(fabs((double)got.c[0] - r) <= tol && fabs((double)got.c[1] - g) <= tol && fabs((double)got.c[2] - b) <= tol))
        fail_msg("got (%.9g, %.9g, %.9g), expected (%.9g, %.9g, %.9g) within %g", (double)got.c[0], (double)got.c[1],
                 (double)got.c[2], r, g, b, tol);
}

/* The sRGB EOTF (IEC 61966-2-1), written out independently of image_io.c. */
static double srgb_eotf(double s) { return s <= 0.04045 ? s / 12.92 : pow((s + 0.055) / 1.055, 2.4); }

/* ------------------------------------------------------------------ images */

enum { IW = 3, IH = 2 };
/* Texel (x, y) of the 3 x 2 test image, y = 0 the top row: dyadic values, so bilinear
 * weights of 1/2 and 1/4 give exact results. */
static void texel(int x, int y, float out[3])
{
    out[0] = (float)x + 4.0f * (float)y;
    out[1] = 0.25f * (float)x;
    out[2] = 0.5f + 0.5f * (float)y;
}

static Texture tiny_image(TextureWrap wrap)
{
    float *px = malloc(IW * IH * 3 * sizeof *px);
    assert_non_null(px);
    for (int y = 0; y < IH; y++)
        for (int x = 0; x < IW; x++) texel(x, y, &px[3 * (y * IW + x)]);
    Texture t;
    CstError err;
    assert_int_equal(texture_image(&t, px, IW, IH, wrap, &err), CST_OK);
    return t;
}

/* A negative or non-finite texel is rejected with its place and value in the message
 * (texture_image takes the pixels and frees them on failure too; ASan checks that the
 * message is written before). */
static void test_image_rejects_bad_texels(void **state)
{
    (void)state;
    float *px = calloc(IW * IH * 3, sizeof *px);
    assert_non_null(px);
    px[3 * (1 * IW + 2) + 1] = -0.5f;
    Texture t;
    CstError err = {0};
    assert_int_equal(texture_image(&t, px, IW, IH, TEXTURE_WRAP_REPEAT, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "pixel (2, 1) channel G is -0.5; expected a finite value >= 0"));
}

/* uv of the centre of texel (x, y) (v = 0 is the bottom row). */
static Vec2 centre(double x, double y) { return v2((float)((x + 0.5) / IW), (float)(1.0 - (y + 0.5) / IH)); }

static void expect_mix(const Texture *t, Vec2 uv, const int (*xy)[2], int n)
{
    double want[3] = {0, 0, 0};
    for (int i = 0; i < n; i++) {
        float c[3];
        texel(xy[i][0], xy[i][1], c);
        for (int k = 0; k < 3; k++) want[k] += (double)c[k] / n;
    }
    assert_rgb_near(texture_eval(t, 0, uv), want[0], want[1], want[2], 1e-5);
}

static void test_bilinear_exact(void **state)
{
    (void)state;
    for (int w = 0; w < 2; w++) {
        Texture t = tiny_image(w ? TEXTURE_WRAP_CLAMP : TEXTURE_WRAP_REPEAT);
        /* texel centres give the texels */
        for (int y = 0; y < IH; y++)
            for (int x = 0; x < IW; x++) {
                int one[1][2] = {{x, y}};
                expect_mix(&t, centre(x, y), one, 1);
            }
        /* half way between two texel centres, and the middle of four */
        int pair[2][2] = {{0, 0}, {1, 0}};
        expect_mix(&t, centre(0.5, 0), pair, 2);
        int four[4][2] = {{1, 0}, {2, 0}, {1, 1}, {2, 1}};
        expect_mix(&t, centre(1.5, 0.5), four, 4);
        /* a quarter of the way from (0, 1) to (1, 1): weights 3/4, 1/4 */
        float a[3], b[3];
        texel(0, 1, a);
        texel(1, 1, b);
        assert_rgb_near(texture_eval(&t, 0, centre(0.25, 1)), 0.75 * (double)a[0] + 0.25 * (double)b[0],
                        0.75 * (double)a[1] + 0.25 * (double)b[1], 0.75 * (double)a[2] + 0.25 * (double)b[2], 1e-5);
        /* average and max over the texels */
        assert_rgb_near(t.average, (0 + 1 + 2 + 4 + 5 + 6) / 6.0, 0.25, 0.75, 1e-6);
        assert_rgb_near(t.max, 6.0, 0.5, 1.0, 0.0);
        texture_free(&t);
    }
    /* At the left edge (u = 0, the first centre is half a texel in): repeat mixes the last
     * and first columns equally, clamp sees the first column; a whole period away is the
     * same point under repeat. */
    Texture rep = tiny_image(TEXTURE_WRAP_REPEAT), cl = tiny_image(TEXTURE_WRAP_CLAMP);
    int wrapped[2][2] = {{2, 0}, {0, 0}}, first[1][2] = {{0, 0}};
    Vec2 edge = v2(0.0f, centre(0, 0).y);
    expect_mix(&rep, edge, wrapped, 2);
    expect_mix(&cl, edge, first, 1);
    int one[1][2] = {{1, 1}};
    expect_mix(&rep, v2(centre(1, 1).x + 3.0f, centre(1, 1).y - 2.0f), one, 1);
    /* clamp: far outside is the corner texel; non-finite uv counts as 0 */
    int corner[1][2] = {{2, 0}};
    expect_mix(&cl, v2(50.0f, 50.0f), corner, 1);
    Color nan_uv = texture_eval(&cl, 0, v2(NAN, INFINITY));
    assert_true(color_is_finite(nan_uv));
    texture_free(&rep);
    texture_free(&cl);
}

static void test_srgb_decode(void **state)
{
    (void)state;
    /* A 4 x 1 PNG with the bytes 0, 10, 128, 255 in every channel: image_write encodes
     * linear values, so give it the linear values of those bytes. */
    static const int bytes[4] = {0, 10, 128, 255};
    float px[12];
    for (int i = 0; i < 4; i++) px[3 * i] = px[3 * i + 1] = px[3 * i + 2] = (float)srgb_eotf(bytes[i] / 255.0);
    char path[512];
    tpath(path, sizeof path, "ramp.png");
    CstError err;
    assert_int_equal(image_write(path, px, 4, 1, &err), CST_OK);
    for (int linear = 0; linear < 2; linear++) {
        Texture t;
        assert_int_equal(texture_image_load(&t, path, linear, TEXTURE_WRAP_CLAMP, &err), CST_OK);
        assert_int_equal(t.image.width, 4);
        assert_int_equal(t.image.height, 1);
        for (int i = 0; i < 4; i++) {
            double s = bytes[i] / 255.0, want = linear ? s : srgb_eotf(s);
            Color got = texture_eval(&t, 0, v2((float)((i + 0.5) / 4.0), 0.5f));
            assert_rgb_near(got, want, want, want, 1e-6);
        }
        texture_free(&t);
    }
    /* Known values of the curve: byte 128 is 0.2158605 linear, byte 10 is 10/255/12.92. */
    assert_true(fabs(srgb_eotf(128 / 255.0) - 0.21586050011389923) < 1e-12);
    assert_true(fabs(srgb_eotf(10 / 255.0) - 0.0030352698354883752) < 1e-12);
}

/* Float files are linear: EXR and PFM (through image_read) and Radiance HDR (stb_image)
 * come back as written; an 8-bit JPEG decodes through the sRGB curve. */
static void test_float_and_jpeg(void **state)
{
    (void)state;
    /* RGBE stores a shared exponent: (4, 2, 0.5) and (1, 0.25, 0.125) are exact in it. */
    float px[6] = {4.0f, 2.0f, 0.5f, 1.0f, 0.25f, 0.125f};
    static const char *const names[3] = {"f.exr", "f.pfm", "f.hdr"};
    CstError err;
    for (int k = 0; k < 3; k++) {
        char path[512];
        tpath(path, sizeof path, names[k]);
        if (k < 2) assert_int_equal(image_write(path, px, 2, 1, &err), CST_OK);
        else assert_true(stbi_write_hdr(path, 2, 1, 3, px) != 0);
        Texture t;
        /* linear = false must not touch float data */
        assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_CLAMP, &err), CST_OK);
        assert_rgb_near(texture_eval(&t, 0, v2(0.25f, 0.5f)), 4.0, 2.0, 0.5, 0.0);
        assert_rgb_near(texture_eval(&t, 0, v2(0.75f, 0.5f)), 1.0, 0.25, 0.125, 0.0);
        texture_free(&t);
    }
    /* A uniform JPEG block is its DC term: byte 200 comes back within one step. */
    unsigned char grey[8 * 8 * 3];
    memset(grey, 200, sizeof grey);
    char path[512];
    tpath(path, sizeof path, "g.jpg");
    assert_true(stbi_write_jpg(path, 8, 8, 3, grey, 100) != 0);
    Texture t;
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_OK);
    Color c = texture_eval(&t, 0, v2(0.5f, 0.5f));
    assert_true(fabs((double)c.c[0] - srgb_eotf(200 / 255.0)) < srgb_eotf(201 / 255.0) - srgb_eotf(200 / 255.0));
    texture_free(&t);
    /* failures: a missing file (I/O), a file that is no image (parse) */
    tpath(path, sizeof path, "missing.png");
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_ERR_IO);
    assert_non_null(strstr(err.msg, "missing.png"));
    tpath(path, sizeof path, "text.png");
    FILE *fp = fopen(path, "w");
    assert_non_null(fp);
    fputs("not an image at all\n", fp);
    fclose(fp);
    assert_int_equal(texture_image_load(&t, path, false, TEXTURE_WRAP_REPEAT, &err), CST_ERR_PARSE);
    assert_non_null(strstr(err.msg, "text.png"));
}

static void test_checkerboard(void **state)
{
    (void)state;
    Texture tex[4];
    texture_constant(&tex[0], color_rgb(0.1f, 0.2f, 0.3f));
    texture_constant(&tex[1], color_rgb(0.9f, 0.8f, 0.7f));
    texture_checkerboard(&tex[2], tex, 0, 1, 2.0f); /* squares of 1/2 */
    /* (floor(2u) + floor(2v)) even -> texture 0 */
    assert_rgb_near(texture_eval(tex, 2, v2(0.1f, 0.1f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.6f, 0.1f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.1f, 0.6f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(0.6f, 0.6f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(-0.1f, 0.1f)), 0.9, 0.8, 0.7, 1e-7); /* floor(-0.2) = -1 */
    assert_rgb_near(texture_eval(tex, 2, v2(-0.1f, -0.1f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 2, v2(1e30f, NAN)), 0.1, 0.2, 0.3, 1e-7); /* no overflow */
    assert_rgb_near(tex[2].average, 0.5, 0.5, 0.5, 1e-7);
    assert_rgb_near(tex[2].max, 0.9, 0.8, 0.7, 1e-7);
    /* nested: the odd squares of a coarse board are a finer board */
    texture_checkerboard(&tex[3], tex, 1, 2, 1.0f);
    assert_rgb_near(texture_eval(tex, 3, v2(0.3f, 0.3f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(texture_eval(tex, 3, v2(1.3f, 0.3f)), 0.1, 0.2, 0.3, 1e-7);
    assert_rgb_near(texture_eval(tex, 3, v2(1.3f, 0.8f)), 0.9, 0.8, 0.7, 1e-7);
    assert_rgb_near(tex[3].average, 0.7, 0.65, 0.6, 1e-6);
}

/* texture_set_uv_transform: an image looked up at (su u + du, sv v + dv); a checkerboard's
 * squares on its mapped coordinates while its textures see the coordinates unmapped. */
static void test_uv_transform(void **state)
{
    (void)state;
    Texture tex[4];
    tex[0] = tiny_image(TEXTURE_WRAP_REPEAT);
    float c[3];
    /* (0.5 u + 0.25, 2 v - 0.5): texel (1, 0)'s centre from the uv below */
    texture_set_uv_transform(&tex[0], v2(0.5f, 2.0f), v2(0.25f, -0.5f));
    Vec2 at = centre(1, 0);
    texel(1, 0, c);
    assert_rgb_near(texture_eval(tex, 0, v2((at.x - 0.25f) / 0.5f, (at.y + 0.5f) / 2.0f)), (double)c[0], (double)c[1],
                    (double)c[2], 1e-6);
    texture_constant(&tex[1], color_rgb(0.1f, 0.2f, 0.3f));
    texture_constant(&tex[2], color_rgb(0.9f, 0.8f, 0.7f));
    texture_checkerboard(&tex[3], tex, 0, 1, 1.0f);
    texture_set_uv_transform(&tex[3], v2(2.0f, 1.0f), v2(-0.5f, 0.0f));
    /* uv = (0.5, 0.625) -> (s, t) = (0.5, 0.625), even: the image, at the unmapped uv */
    Vec2 uv = v2((at.x - 0.25f) / 0.5f, (at.y + 0.5f) / 2.0f);
    assert_rgb_near(texture_eval(tex, 3, uv), (double)c[0], (double)c[1], (double)c[2], 1e-6);
    assert_rgb_near(texture_eval(tex, 3, v2(0.8f, 0.5f)), 0.1, 0.2, 0.3, 1e-7); /* s = 1.1: odd */
    texture_free(&tex[0]);
}

/* ------------------------------------------------------------------ uvs at hits */

/* The closest hit of a ray from o toward target. */
static SurfaceHit hit_toward(const Scene *s, Vec3 o, Vec3 target)
{
    SurfaceHit sh;
    Ray r = ray_make(o, v3_normalize(v3_sub(target, o)), 0.0f, INFINITY);
    assert_true(scene_intersect(s, &r, &sh));
    return sh;
}

static Vec3 bary(Vec3 a, Vec3 b, Vec3 c, float b1, float b2)
{
    return v3_add(v3_add(v3_scale(a, 1.0f - b1 - b2), v3_scale(b, b1)), v3_scale(c, b2));
}

static void assert_uv(Vec2 got, double u, double v)
{
    if (!(fabs((double)got.x - u) < 1e-5 && fabs((double)got.y - v) < 1e-5))
        fail_msg("uv (%.7f, %.7f), expected (%.7f, %.7f)", (double)got.x, (double)got.y, u, v);
}

static void test_uv_at_hits(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.5f, 0.5f, 0.5f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    /* uvs are computed in scenes with textures only */
    Texture tc;
    texture_constant(&tc, color_s(1.0f));
    int tid;
    assert_int_equal(scene_add_texture(s, &tc, &tid, &err), CST_OK);
    /* a triangle without uvs at z = 0 (added first: before the scene has a uv array) */
    Vec3 t0[3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    static const int tri[3] = {0, 1, 2};
    assert_int_equal(scene_add_mesh(s, t0, 3, tri, 1, mat, NULL, &err), CST_OK);
    /* a triangle with uvs at z = 1 */
    Vec3 t1[3] = {{0, 0, 1}, {1, 0, 1}, {0, 1, 1}};
    Vec2 uv1[3] = {{0.2f, 0.3f}, {0.8f, 0.1f}, {0.4f, 0.9f}};
    SceneMesh sm = {0};
    sm.positions = t1;
    sm.num_vertices = 3;
    sm.uvs = uv1;
    sm.indices = tri;
    sm.num_triangles = 1;
    sm.material = mat;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
    /* a quad at z = 2 (after a mesh with uvs) and a triangle without uvs at z = 3 */
    Vec3 q[4] = {{0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {0, 2, 2}};
    assert_int_equal(scene_add_quad(s, q, mat, NULL, &err), CST_OK);
    Vec3 t3[3] = {{0, 0, 3}, {1, 0, 3}, {0, 1, 3}};
    assert_int_equal(scene_add_mesh(s, t3, 3, tri, 1, mat, NULL, &err), CST_OK);
    /* a sphere at (10, 0, 0) */
    assert_int_equal(scene_add_sphere(s, v3(10, 0, 0), 1.0f, mat, NULL, &err), CST_OK);
    /* an instanced triangle at z = 5 (object space z = 0, translated) */
    int proto, pmat[1] = {mat};
    assert_int_equal(scene_add_instance_proto(s, t0, NULL, 3, tri, pmat, 1, &proto, &err), CST_OK);
    Transform tr = transform_translate(v3(20, 0, 5));
    assert_int_equal(scene_add_instance(s, proto, &tr, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);

    const float bs[3][2] = {{0.25f, 0.5f}, {0.1f, 0.1f}, {0.6f, 0.3f}};
    for (int i = 0; i < 3; i++) {
        float b1 = bs[i][0], b2 = bs[i][1], b0 = 1.0f - b1 - b2;
        /* the default mapping: (b1, b2) */
        Vec3 p = bary(t0[0], t0[1], t0[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, -1), p).uv, (double)b1, (double)b2);
        p = bary(t3[0], t3[1], t3[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, 3.5f), p).uv, (double)b1, (double)b2);
        /* interpolated */
        p = bary(t1[0], t1[1], t1[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x, p.y, 0.5f), p).uv, (double)(0.2f * b0 + 0.8f * b1 + 0.4f * b2),
                  (double)(0.3f * b0 + 0.1f * b1 + 0.9f * b2));
        /* instances have no uvs: the default */
        p = bary(t0[0], t0[1], t0[2], b1, b2);
        assert_uv(hit_toward(s, v3(p.x + 20, p.y, 4), v3(p.x + 20, p.y, 5)).uv, (double)b1, (double)b2);
    }
    /* the quad: (0,0), (1,0), (1,1), (0,1) at its corners, linear across it */
    const float qp[4][2] = {{0.5f, 0.5f}, {1.5f, 0.3f}, {0.2f, 1.7f}, {1.9f, 1.9f}};
    for (int i = 0; i < 4; i++)
        assert_uv(hit_toward(s, v3(qp[i][0], qp[i][1], 2.5f), v3(qp[i][0], qp[i][1], 2)).uv,
                  (double)qp[i][0] / 2.0, (double)qp[i][1] / 2.0);
    /* the sphere: u = phi / 2pi about +y from +z toward +x, v = theta / pi from -y */
    assert_uv(hit_toward(s, v3(13, 0, 0), v3(10, 0, 0)).uv, 0.25, 0.5);   /* +x */
    assert_uv(hit_toward(s, v3(10, 0, -3), v3(10, 0, 0)).uv, 0.5, 0.5);  /* -z */
    assert_uv(hit_toward(s, v3(7, 0, 0), v3(10, 0, 0)).uv, 0.75, 0.5);   /* -x */
    assert_true(hit_toward(s, v3(10, 3, 0.001f), v3(10, 0, 0.001f)).uv.y > 0.999f); /* top: v = 1 */
    Vec3 d = v3_normalize(v3(1, 1, 1)); /* phi = 45 deg, theta = pi - acos(1/sqrt 3) */
    assert_uv(hit_toward(s, v3_add(v3(10, 0, 0), v3_scale(d, 3)), v3(10, 0, 0)).uv, 0.125,
              (3.14159265358979 - acos(1.0 / sqrt(3.0))) / 3.14159265358979);
    scene_destroy(s);
}

/* Points sampled on textured emitters carry the uv of where they are: a quad's position
 * maps linearly to its uv, a sphere point's direction to sphere_uv. */
static void test_emitter_sample_uv(void **state)
{
    (void)state;
    CstError err;
    Scene *s = scene_create();
    int mat, tid;
    Material m = {.type = MATERIAL_DIFFUSE, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &mat, &err), CST_OK);
    Texture tex[3];
    texture_constant(&tex[0], color_rgb(1.0f, 0.5f, 0.25f));
    texture_constant(&tex[1], color_rgb(0.0f, 2.0f, 4.0f));
    for (int i = 0; i < 2; i++) assert_int_equal(scene_add_texture(s, &tex[i], &tid, &err), CST_OK);
    texture_checkerboard(&tex[2], s->textures, 0, 1, 4.0f);
    assert_int_equal(scene_add_texture(s, &tex[2], &tid, &err), CST_OK);
    Emission em = {{{2.0f, 2.0f, 2.0f}}, 1, tid + 1};
    Vec3 q[4] = {{0, 0, 0}, {4, 0, 0}, {4, 0, 4}, {0, 0, 4}}; /* u along x, v along z */
    assert_int_equal(scene_add_quad(s, q, mat, &em, &err), CST_OK);
    assert_int_equal(scene_add_sphere(s, v3(0, 10, 0), 1.0f, mat, &em, &err), CST_OK);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    /* the emitters' selection weights use the texture's average: (0.5, 1.25, 2.125) * 2 */
    for (int i = 0; i < s->num_emitters; i++) assert_rgb_near(s->emitters[i].average, 1.0, 2.5, 4.25, 1e-6);
    EmitterGeometry g = scene_emitter_geometry(s);
    int checked = 0;
    for (int i = 0; i < 256; i++) {
        Vec2 u = v2((float)((i * 37) % 256) / 256.0f + 1e-3f, (float)i / 256.0f + 1e-3f);
        for (int e = 0; e < s->num_emitters; e++) {
            Vec3 p, n;
            Vec2 uv;
            emitter_sample_point(&s->emitters[e], &g, u, &p, &n, &uv);
            if ((int)s->emitters[e].prim < s->num_triangles) assert_uv(uv, (double)p.x / 4.0, (double)p.z / 4.0);
            else assert_uv(uv, (double)sphere_uv(v3_sub(p, v3(0, 10, 0))).x, (double)sphere_uv(v3_sub(p, v3(0, 10, 0))).y);
            /* the radiance there is the texture's, scaled */
            Color want = color_scale(texture_eval(s->textures, tid, uv), 2.0f);
            Color got = emitter_radiance(&s->emitters[e], s->textures, n, uv, n);
            assert_rgb_near(got, (double)want.c[0], (double)want.c[1], (double)want.c[2], 0.0);
            checked++;
        }
    }
    assert_int_equal(checked, 3 * 256); /* the quad is two emitters */
    /* light_sample_li returns the radiance at the point it picked */
    for (int i = 0; i < 64; i++) {
        LightLi ls;
        Vec3 x = v3(2, 3, 2);
        if (!light_sample_li(&s->emitter_sampler, &g, x, (float)i / 64.0f,
                             v2((float)((i * 29) % 64) / 64.0f + 0.01f, (float)i / 64.0f + 0.005f), &ls))
            continue;
        Vec2 uv = ls.light == 0 || ls.light == 1 ? v2(ls.p.x / 4.0f, ls.p.z / 4.0f)
                                                  : sphere_uv(v3_normalize(v3_sub(ls.p, v3(0, 10, 0))));
        Color want = color_scale(texture_eval(s->textures, tid, uv), 2.0f);
        assert_rgb_near(ls.li, (double)want.c[0], (double)want.c[1], (double)want.c[2], 1e-6);
    }
    scene_destroy(s);
}

/* ------------------------------------------------------------------ JSON */

#define NAME "t.json"

static const char *json_head =
    "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n";

/* Loads head + body; expects status and, when not OK, "t.json:<line>:<col>:" at the
 * nth occurrence of needle and `what` in the message. */
static CstScene *load_json(const char *body, CstStatus status, const char *needle, int nth, const char *what)
{
    char text[4096];
    snprintf(text, sizeof text, "%s%s", json_head, body);
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus st = cst_scene_load_json_string(text, strlen(text), NAME, &scene, &err);
    if (st != status) fail_msg("status %s, expected %s: %s", cst_status_name(st), cst_status_name(status), err.msg);
    if (st == CST_OK) return scene;
    const char *at = text;
    for (int i = 0; i <= nth; i++) {
        at = strstr(i ? at + 1 : at, needle);
        if (!at) fail_msg("needle %s not found", needle);
    }
    int line = 1, col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') { line++; col = 1; } else { col++; }
    }
    char prefix[64];
    snprintf(prefix, sizeof prefix, NAME ":%d:%d: ", line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0) fail_msg("message \"%s\" does not start with \"%s\"", err.msg, prefix);
    if (what && !strstr(err.msg, what)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
    return NULL;
}

static void test_json_textures(void **state)
{
    (void)state;
    char png[512], body[3072];
    tpath(png, sizeof png, "j.png");
    float px[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, 1, 1, 1};
    CstError err;
    assert_int_equal(image_write(png, px, 2, 2, &err), CST_OK);
    /* names may be used before they are listed; colours or names in a checkerboard */
    snprintf(body, sizeof body,
             "\"textures\": {\"board\": {\"type\": \"checkerboard\", \"even\": \"img\", \"odd\": [0.1, 0.2, 0.3], \"scale\": 4},\n"
             " \"img\": {\"type\": \"image\", \"file\": \"%s\", \"wrap\": \"clamp\"},\n"
             " \"rough\": {\"type\": \"constant\", \"value\": [0.5, 0.5, 0.5]},\n"
             " \"hot\": {\"type\": \"constant\", \"value\": [3, 2, 1]}},\n"
             "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"board\"},\n"
             " \"b\": {\"type\": \"conductor\", \"metal\": \"gold\", \"roughness\": \"rough\"}},\n"
             "\"shapes\": [{\"type\": \"mesh\", \"material\": \"a\", \"vertices\": [[0,0,0],[1,0,0],[0,1,0]],\n"
             "  \"indices\": [[0,1,2]], \"uvs\": [[0,0],[0.5,0],[0,0.5]]},\n"
             " {\"type\": \"sphere\", \"material\": \"b\", \"center\": [0,0,-3], \"radius\": 1,\n"
             "  \"emission\": {\"radiance\": \"hot\", \"scale\": 2}}]}",
             png);
    CstScene *s = load_json(body, CST_OK, NULL, 0, NULL);
    assert_int_equal(s->num_textures, 5); /* img, the odd colour, board, rough, hot */
    const Material *ma = &s->materials[0], *mb = &s->materials[1];
    assert_true(ma->albedo_texture > 0 && s->textures[ma->albedo_texture - 1].type == TEXTURE_CHECKERBOARD);
    assert_true(mb->roughness_texture > 0);
    assert_int_equal(s->num_emitters, 1);
    Color le = emitter_radiance(&s->emitters[0], s->textures, v3(0, 0, 1), v2(0.3f, 0.3f), v3(0, 0, 1));
    assert_rgb_near(le, 6.0, 4.0, 2.0, 0.0);
    assert_true(s->tri_has_uv && s->tri_has_uv[0]);
    /* a hit on the mesh: uv from its uvs, albedo from the board (odd square at uv (0.3, 0.05)) */
    SurfaceHit sh = hit_toward(s, v3(0.6f, 0.1f, 1), v3(0.6f, 0.1f, 0));
    assert_uv(sh.uv, 0.3, 0.05);
    Bsdf b;
    scene_bsdf(s, &sh, NULL, &b);
    assert_rgb_near(bsdf_albedo(&b), 0.1, 0.2, 0.3, 1e-7);
    cst_scene_destroy(s);

    /* errors, each at the value that causes it */
    load_json("\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"nope\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"nope\"", 0, "texture \"nope\" is not defined (no textures are)");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [1, 1, 1]}},\n"
              "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"tt\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"tt\"", 0, "expected one of: t");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"/nonexistent/dir/x.png\"}},\n\"shapes\": []}",
              CST_ERR_IO, "\"/nonexistent", 0, "cannot open");
    load_json("\"textures\": {\"a\": {\"type\": \"checkerboard\", \"even\": \"b\", \"odd\": [0,0,0]},\n"
              " \"b\": {\"type\": \"checkerboard\", \"even\": [0,0,0], \"odd\": \"a\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"a\"", 1, "contains itself");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [0.5, 1.5, 0]}},\n"
              "\"materials\": {\"a\": {\"type\": \"diffuse\", \"albedo\": \"t\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"t\"}", 0, "values up to 1.5");
    load_json("\"textures\": {\"t\": {\"type\": \"constant\", \"value\": [0.5, 0.5, 0.5]}},\n"
              "\"materials\": {\"a\": {\"type\": \"plastic\", \"roughness\": \"t\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"t\"}", 0, "plastic's roughness cannot be a texture");
    load_json("\"textures\": {\"t\": {\"type\": \"image\", \"file\": \"x.png\", \"wrap\": \"mirror\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"mirror\"", 0, "expected one of: repeat, clamp");
    load_json("\"textures\": {\"t\": {\"type\": \"checkerboard\", \"even\": [0,0,0], \"odd\": [1,1,1], \"scale\": 0}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "0}}", 0, "scale 0 is not positive");
    load_json("\"textures\": {\"t\": {\"type\": \"marble\"}},\n\"shapes\": []}",
              CST_ERR_INVALID_ARG, "\"marble\"", 0, "unknown texture type");
    load_json("\"shapes\": [{\"type\": \"mesh\", \"material\": \"m\", \"vertices\": [[0,0,0],[1,0,0],[0,1,0]],\n"
              " \"indices\": [[0,1,2]], \"uvs\": [[0,0],[1,0]]}],\n\"materials\": {\"m\": {\"type\": \"diffuse\"}}}",
              CST_ERR_INVALID_ARG, "[[0,0],[1,0]]", 0, "one [u, v] per vertex");
}

/* The example scene loads (its image texture found next to it) with its textures in use. */
static void test_example_scene(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json(CST_SOURCE_DIR "/scenes/textured.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    int images = 0, textured = 0;
    for (int i = 0; i < s->num_textures; i++)
        if (s->textures[i].type == TEXTURE_IMAGE) {
            images++;
            assert_int_equal(s->textures[i].image.width, 256);
            assert_int_equal(s->textures[i].image.height, 256);
        }
    for (int i = 0; i < s->num_materials; i++)
        textured += s->materials[i].albedo_texture > 0 || s->materials[i].roughness_texture > 0;
    assert_int_equal(images, 1);
    assert_true(textured >= 3);
    int lit = 0;
    for (int i = 0; i < s->num_emitters; i++) lit += s->emitters[i].texture > 0;
    assert_true(lit > 0);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_bilinear_exact),
        cmocka_unit_test(test_image_rejects_bad_texels),
        cmocka_unit_test(test_srgb_decode),
        cmocka_unit_test(test_float_and_jpeg),
        cmocka_unit_test(test_checkerboard),
        cmocka_unit_test(test_uv_transform),
        cmocka_unit_test(test_uv_at_hits),
        cmocka_unit_test(test_emitter_sample_uv),
        cmocka_unit_test(test_json_textures),
        cmocka_unit_test(test_example_scene),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
