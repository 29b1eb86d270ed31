/* Shading normals in light transport: camera paths (path tracing) and light paths (light
 * tracing, the light subpaths of BDPT) must estimate the same image of a smooth-shaded
 * low-poly sphere, which they do only with the adjoint correction of importance transport
 * (Veach thesis eq. 5.19); and a closed form for the energy a shading normal loses. */
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

static CstRenderSettings sized(int size)
{
    CstRenderSettings st = {0};
    st.width = st.height = size;
    st.filter = CST_FILTER_BOX;
    return st;
}

/* Quad c, c + e1, c + e1 + e2, c + e2: normal e1 x e2. */
static void add_quad(Scene *s, Vec3 c, Vec3 e1, Vec3 e2, int mat, const Emission *em)
{
    CstError err;
    Vec3 v[4] = {c, v3_add(c, e1), v3_add(v3_add(c, e1), e2), v3_add(c, e2)};
    assert_int_equal(scene_add_quad(s, v, mat, em, &err), CST_OK);
}

/* A UV sphere of nphi segments and ntheta rings (2 nphi (ntheta - 1) triangles), wound
 * outward, with the radial directions as vertex normals when smooth: the facets' normals
 * differ from the shading normals by up to about half a facet's angle. */
static void add_tessellated_sphere(Scene *s, Vec3 center, float radius, int nphi, int ntheta, int mat,
                                   bool smooth)
{
    const int nv = 2 + nphi * (ntheta - 1), nt = 2 * nphi * (ntheta - 1);
    Vec3 *pos = malloc((size_t)nv * sizeof *pos), *nrm = malloc((size_t)nv * sizeof *nrm);
    int *idx = malloc((size_t)nt * 3 * sizeof *idx);
    assert_true(pos && nrm && idx);
    nrm[0] = v3(0, 1, 0);
    nrm[1] = v3(0, -1, 0);
    for (int i = 1; i < ntheta; i++)
        for (int j = 0; j < nphi; j++) {
            float th = CST_PI * (float)i / (float)ntheta, ph = 2.0f * CST_PI * (float)j / (float)nphi;
            nrm[2 + (i - 1) * nphi + j] = v3(sinf(th) * cosf(ph), cosf(th), sinf(th) * sinf(ph));
        }
    for (int k = 0; k < nv; k++) pos[k] = v3_madd(center, nrm[k], radius);
#define RING(i, j) (2 + ((i) - 1) * nphi + ((j) % nphi))
    int t = 0;
    for (int j = 0; j < nphi; j++) {
        int tri[2][3] = {{0, RING(1, j), RING(1, j + 1)}, {1, RING(ntheta - 1, j), RING(ntheta - 1, j + 1)}};
        for (int k = 0; k < 2; k++, t++) memcpy(&idx[3 * t], tri[k], sizeof tri[k]);
        for (int i = 1; i + 1 < ntheta; i++) {
            int q[2][3] = {{RING(i, j), RING(i + 1, j), RING(i + 1, j + 1)}, {RING(i, j), RING(i + 1, j + 1), RING(i, j + 1)}};
            for (int k = 0; k < 2; k++, t++) memcpy(&idx[3 * t], q[k], sizeof q[k]);
        }
    }
#undef RING
    assert_int_equal(t, nt);
    for (int k = 0; k < nt; k++) { /* wind outward */
        Vec3 a = pos[idx[3 * k]], b = pos[idx[3 * k + 1]], c = pos[idx[3 * k + 2]];
        Vec3 n = v3_cross(v3_sub(b, a), v3_sub(c, a));
        if (v3_dot(n, v3_sub(a, center)) < 0.0f) { int tmp = idx[3 * k + 1]; idx[3 * k + 1] = idx[3 * k + 2]; idx[3 * k + 2] = tmp; }
    }
    SceneMesh sm = {0};
    sm.positions = pos;
    sm.num_vertices = nv;
    sm.normals = smooth ? nrm : NULL;
    sm.indices = idx;
    sm.num_triangles = nt;
    sm.material = mat;
    CstError err;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
    free(pos);
    free(nrm);
    free(idx);
}

/* The floor y = -1 of the box as a mesh whose vertex normals all lean by `tilt` radians
 * toward +x: a constant shading normal off the geometric one, as a normal map would give.
 * On the sphere the shading normals lean to all sides and the correction's first-order
 * effect averages out over each facet; here it does not, which gives the test its power. */
static void add_tilted_floor(Scene *s, float tilt, int mat)
{
    Vec3 pos[4] = {{-1, -1, -1}, {-1, -1, 1}, {1, -1, 1}, {1, -1, -1}};
    Vec3 n = v3(sinf(tilt), cosf(tilt), 0.0f);
    Vec3 nrm[4] = {n, n, n, n};
    int idx[6] = {0, 1, 2, 0, 2, 3}; /* normal +y */
    SceneMesh sm = {0};
    sm.positions = pos;
    sm.num_vertices = 4;
    sm.normals = nrm;
    sm.indices = idx;
    sm.num_triangles = 2;
    sm.material = mat;
    CstError err;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
}

/* A Cornell-like box [-1, 1]^3 open toward the camera, with a small one-sided area light
 * under the ceiling, a smooth-shaded low-poly sphere of albedo 0.9 and a floor whose
 * shading normals lean by 30 degrees. */
static Scene *sphere_box_scene(int nphi, int ntheta)
{
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white, red, green, ball, black;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{0.75f, 0.75f, 0.75f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    m.albedo = color_rgb(0.7f, 0.1f, 0.1f);
    assert_int_equal(scene_add_material(s, &m, &red, &err), CST_OK);
    m.albedo = color_rgb(0.1f, 0.7f, 0.1f);
    assert_int_equal(scene_add_material(s, &m, &green, &err), CST_OK);
    m.albedo = color_rgb(0.9f, 0.9f, 0.9f);
    assert_int_equal(scene_add_material(s, &m, &ball, &err), CST_OK);
    m.albedo = color_s(0.0f);
    assert_int_equal(scene_add_material(s, &m, &black, &err), CST_OK);
    add_tilted_floor(s, 30.0f * CST_PI / 180.0f, white);
    add_quad(s, v3(-1, 1, -1), v3(2, 0, 0), v3(0, 0, 2), white, NULL);  /* ceiling, -y */
    add_quad(s, v3(-1, -1, 1), v3(0, 2, 0), v3(2, 0, 0), white, NULL);  /* back, -z */
    add_quad(s, v3(-1, -1, -1), v3(0, 2, 0), v3(0, 0, 2), red, NULL);   /* x = -1, +x */
    add_quad(s, v3(1, -1, -1), v3(0, 0, 2), v3(0, 2, 0), green, NULL);  /* x = 1, -x */
    Emission em = {{{12.0f, 12.0f, 12.0f}}, 0, 0};
    add_quad(s, v3(-0.3f, 0.99f, -0.1f), v3(0.6f, 0, 0), v3(0, 0, 0.6f), black, &em); /* faces -y */
    add_tessellated_sphere(s, v3(0.1f, -0.45f, 0.15f), 0.55f, nphi, ntheta, ball, true);
    CameraDesc cam = {{0, 0, -3.4f}, {0, 0, 0}, {0, 1, 0}, 38.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    return s;
}

/* path (MIS) vs light vs bdpt (and vcm) on the smooth-shaded sphere in the box. The light paths'
 * bounces off the sphere and the floor carry the adjoint correction. With the factor set to
 * 1 (a mutation check), the green wall's block lit by the floor differs from path by
 * z = 17.6 (light), 17.2 (bdpt), 16.7 (vcm); the sphere alone gave at most 3.2, its
 * normals leaning to all sides. */
static void test_smooth_sphere_consistency(void **state)
{
    (void)state;
    Scene *s = sphere_box_scene(16, 10); /* 288 triangles */
    enum { SIZE = 32, BLOCK = 8 };
    CstRenderSettings st = sized(SIZE);
    Regions rp = regions(SIZE, BLOCK), rl = rp, rb = rp, rv = rp;
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 1024, 101, &rp);
    split_regions(s, &st, CST_INTEGRATOR_LIGHT, 256, 2000, &rl);
    split_regions(s, &st, CST_INTEGRATOR_BDPT, 128, 4000, &rb);
    split_regions(s, &st, CST_INTEGRATOR_VCM, 128, 6000, &rv);
    compare(&rp, &rl, "path (smooth sphere)", "light (smooth sphere)");
    compare(&rp, &rb, "path (smooth sphere)", "bdpt (smooth sphere)");
    compare(&rl, &rb, "light (smooth sphere)", "bdpt (smooth sphere)");
    /* VCM's merges divide f |cos| by the geometric cosine, as photon density estimates do */
    compare(&rp, &rv, "path (smooth sphere)", "vcm (smooth sphere)");
    scene_destroy(s);
}

/* Fails at |z| > Z_LIMIT of any region and channel against the constant `expect`. */
static void check_constant(const Regions *r, double expect, const char *label)
{
    double worst = 0.0;
    for (int i = 0; i < r->count; i++)
        for (int c = 0; c < 3; c++) {
            double z = (r->stat[i].mean[c] - expect) / r->stat[i].se[c];
            if (fabs(z) > fabs(worst)) worst = z;
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("%s: block %d channel %d: mean %.6f, expected %.6f (z = %.2f)", label, i - 1, c,
                         r->stat[i].mean[c], expect, z);
        }
    print_message("%s: whole image %.5f (se %.1e), expected %.5f; largest |z| = %.2f\n", label, r->stat[0].mean[0],
                  r->stat[0].se[0], expect, fabs(worst));
}

/* A white (albedo 1) Lambertian plane whose shading normal leans by theta from its
 * geometric normal, under a uniform sky of radiance 1, seen from above. Every direction
 * above the plane sees the sky, so the reflected radiance is (1/pi) times the projected
 * solid angle, about ns, of the directions above both ns's and ng's tangent planes (the
 * pairs bsdf_init_shading keeps): the unit disk minus the half-ellipse between the two
 * horizons, pi - (pi/2)(1 - cos theta), so L = (1 + cos theta) / 2 < 1. Shading normals do
 * not conserve energy (Veach thesis sec. 5.3): this convention loses what would cross ng,
 * and the adjoint's directional albedo |wo.ns| / |wo.ng| (1 + cos theta) / 2 can exceed
 * one. The camera's directions stay within 15 degrees of ng, so wo.ns > 0 everywhere. */
static void test_tilted_plane_furnace(void **state)
{
    (void)state;
    const float theta = 40.0f * CST_PI / 180.0f;
    CstError err;
    Scene *s = scene_create();
    assert_non_null(s);
    int white;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{1.0f, 1.0f, 1.0f}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &white, &err), CST_OK);
    Vec3 pos[4] = {{-1, 0, -1}, {-1, 0, 1}, {1, 0, 1}, {1, 0, -1}};
    Vec3 n = v3(sinf(theta), cosf(theta), 0.0f);
    Vec3 nrm[4] = {n, n, n, n};
    int idx[6] = {0, 1, 2, 0, 2, 3}; /* ng = +y */
    SceneMesh sm = {0};
    sm.positions = pos;
    sm.num_vertices = 4;
    sm.normals = nrm;
    sm.indices = idx;
    sm.num_triangles = 2;
    sm.material = white;
    assert_int_equal(scene_add_mesh_ex(s, &sm, NULL, &err), CST_OK);
    EnvMap env;
    assert_int_equal(envmap_init_constant(&env, color_s(1.0f), &err), CST_OK);
    assert_int_equal(scene_set_environment(s, &env, &err), CST_OK);
    CameraDesc cam = {{0, 3, 0}, {0, 0, 0}, {0, 0, 1}, 30.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    const double expect = (1.0 + cos((double)theta)) / 2.0;
    enum { SIZE = 32, BLOCK = 8 };
    CstRenderSettings st = sized(SIZE);
    Regions rp = regions(SIZE, BLOCK), rl = rp;
    camera_regions(s, &st, CST_INTEGRATOR_PATH, 256, 500, &rp);
    check_constant(&rp, expect, "path (tilted plane)");
    split_regions(s, &st, CST_INTEGRATOR_LIGHT, 256, 600, &rl);
    check_constant(&rl, expect, "light (tilted plane)");
    scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_smooth_sphere_consistency),
        cmocka_unit_test(test_tilted_plane_furnace),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
