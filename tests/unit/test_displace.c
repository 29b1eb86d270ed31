/* True displacement (geometry/displace.c, cst_scene_displace_mesh, the pbrt and JSON
 * loaders' "displacement"): a plane moved by a constant, vertices of a sine displacement on
 * the analytic surface, watertightness of a displaced closed mesh, the triangle limit, and
 * located errors for bad edge lengths. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "caustic/caustic.h"
#include "geometry/displace.h"
#include "scene/scene.h"
#include "unit/pbrt_test_util.h"

#define TWO_PI 6.28318530717958647692

/* The square [0, 2]^2 at z = 0, uv = xy / 2, two triangles facing +z. */
static const float SQ_P[12] = {0, 0, 0, 2, 0, 0, 2, 2, 0, 0, 2, 0};
static const float SQ_UV[8] = {0, 0, 1, 0, 1, 1, 0, 1};
static const int SQ_IDX[6] = {0, 1, 2, 0, 2, 3};

static CstDisplaceDesc square_desc(float edge)
{
    CstDisplaceDesc d = {0};
    d.positions = SQ_P;
    d.uvs = SQ_UV;
    d.num_vertices = 4;
    d.indices = SQ_IDX;
    d.num_triangles = 2;
    d.edge_length = edge;
    return d;
}

static Vec3 vtx(const CstDisplacedMesh *m, int i)
{
    return v3(m->positions[3 * i], m->positions[3 * i + 1], m->positions[3 * i + 2]);
}

/* The longest edge of m. */
static float longest_edge(const CstDisplacedMesh *m)
{
    float e = 0.0f;
    for (int t = 0; t < m->num_triangles; t++)
        for (int k = 0; k < 3; k++) {
            float l = v3_length(v3_sub(vtx(m, m->indices[3 * t + k]), vtx(m, m->indices[3 * t + (k + 1) % 3])));
            if (l > e) e = l;
        }
    return e;
}

/* A constant displacement d (a texture and the plain value) moves the plane by d along its
 * normal: every vertex at z = d, the square still covered (area 4), every edge shorter
 * than the edge length, normals +z; measured through a scale of 2, the edges halve. */
static void test_constant_plane(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    CstTextureDesc td = {0};
    td.type = CST_TEXTURE_CONSTANT;
    td.value[0] = td.value[1] = td.value[2] = 0.3f;
    int tex = 0;
    if (cst_scene_add_texture(s, &td, &tex, &err) != CST_OK) fail_msg("%s", err.msg);
    for (int variant = 0; variant < 3; variant++) {
        CstDisplaceDesc d = square_desc(0.3f);
        float want = 0.3f, max_edge = 0.3f;
        if (variant == 0) d.texture = tex;
        if (variant >= 1) d.value = want = -0.7f;
        if (variant == 2) { /* edges measured after x 2 */
            d.measure_from_object[0] = d.measure_from_object[5] = d.measure_from_object[10] = 2.0f;
            max_edge = 0.15f;
        }
        CstDisplacedMesh m;
        if (cst_scene_displace_mesh(s, &d, &m, &err) != CST_OK) fail_msg("%s", err.msg);
        assert_true(m.num_triangles > 100 && m.num_vertices > 50);
        double area = 0.0;
        for (int i = 0; i < m.num_vertices; i++) {
            Vec3 p = vtx(&m, i);
            if (!(fabsf(p.z - want) < 1e-6f && p.x >= 0.0f && p.x <= 2.0f && p.y >= 0.0f && p.y <= 2.0f))
                fail_msg("variant %d: vertex %d at (%g, %g, %g); expected z = %g inside the square", variant, i,
                         (double)p.x, (double)p.y, (double)p.z, (double)want);
            assert_true(fabsf(m.normals[3 * i + 2] - 1.0f) < 1e-6f);
            /* uv interpolated with the position: uv = xy / 2 */
            assert_true(fabsf(m.uvs[2 * i] - 0.5f * p.x) < 1e-6f && fabsf(m.uvs[2 * i + 1] - 0.5f * p.y) < 1e-6f);
        }
        for (int t = 0; t < m.num_triangles; t++) {
            const int *v = &m.indices[3 * t];
            Vec3 c = v3_cross(v3_sub(vtx(&m, v[1]), vtx(&m, v[0])), v3_sub(vtx(&m, v[2]), vtx(&m, v[0])));
            assert_true(c.z > 0.0f); /* the parent's winding */
            assert_true(m.parents[t] == 0 || m.parents[t] == 1);
            area += 0.5 * (double)c.z;
        }
        assert_true(fabs(area - 4.0) < 1e-4);
        float e = longest_edge(&m);
        if (!(e < max_edge && e > 0.5f * max_edge)) fail_msg("variant %d: longest edge %g", variant, (double)e);
        cst_displaced_mesh_free(&m);
    }
    cst_scene_destroy(s);
}

static float sine_u(void *user, Vec3 p, Vec3 n, Vec2 uv)
{
    (void)user, (void)p, (void)n;
    return (float)(0.1 * sin(TWO_PI * (double)uv.x));
}

/* d = 0.1 sin(2 pi u) on the unit square (uv = xy, normal +z): every vertex on the surface
 * z = 0.1 sin(2 pi x), and the recomputed normals close to the analytic ones
 * (-dz/dx, 0, 1) / |.|. */
static void test_sine_surface(void **state)
{
    (void)state;
    const Vec3 p[4] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}};
    const Vec2 uv[4] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
    const Vec3 n[4] = {{0, 0, 1}, {0, 0, 1}, {0, 0, 1}, {0, 0, 1}};
    const int idx[6] = {0, 1, 2, 0, 2, 3};
    DisplaceInput in = {p, n, uv, 4, idx, 2, NULL, 0.02f, 1 << 20, sine_u, NULL};
    DisplacedMesh m;
    CstError err;
    if (displace_mesh(&in, &m, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_true(m.nt > 5000);
    double worst_p = 0.0, worst_n = 1.0;
    for (int i = 0; i < m.nv; i++) {
        double z = 0.1 * sin(TWO_PI * (double)m.p[i].x);
        double dp = fabs((double)m.p[i].z - z);
        if (dp > worst_p) worst_p = dp;
        assert_true(m.p[i].x == m.uv[i].x && m.p[i].y == m.uv[i].y);
        if (m.p[i].x <= 0.0f || m.p[i].x >= 1.0f || m.p[i].y <= 0.0f || m.p[i].y >= 1.0f) continue; /* rim */
        double s = -0.1 * TWO_PI * cos(TWO_PI * (double)m.p[i].x), l = sqrt(s * s + 1.0);
        double c = ((double)m.n[i].x * s + (double)m.n[i].z) / l;
        if (c < worst_n) worst_n = c;
    }
    if (!(worst_p < 1e-6)) fail_msg("a vertex is %g off the surface", worst_p);
    /* edges below 0.02 on a regular grid: measured cos > 1 - 5e-7 (a normal from the
     * undisplaced plane, +z, would give cos 0.85 where the slope is steepest) */
    if (!(worst_n > 0.99999)) fail_msg("a normal is off the analytic one: cos %g", worst_n);
    displaced_mesh_free(&m);
}

static float bumpy(void *user, Vec3 p, Vec3 n, Vec2 uv)
{
    (void)user, (void)n, (void)uv;
    return 0.2f * sinf(5.0f * p.x) * cosf(3.0f * p.y);
}

/* A key for an undirected edge; the direction in the low bit. */
static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return x < y ? -1 : x > y;
}

/* The icosahedron (closed, consistently wound), displaced along its computed normals and
 * tessellated at two edge lengths: every undirected edge belongs to exactly two triangles,
 * once in each direction (closed, no T-junction, no crack), and V - E + F = 2. */
static void test_watertight(void **state)
{
    (void)state;
    const float g = 1.6180339887f;
    const Vec3 p[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                        {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    const int idx[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2,
                         10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5,
                         2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    const float lens[2] = {0.37f, 0.11f};
    for (int li = 0; li < 2; li++) {
        DisplaceInput in = {p, NULL, NULL, 12, idx, 20, NULL, lens[li], 1 << 20, bumpy, NULL};
        DisplacedMesh m;
        CstError err;
        if (displace_mesh(&in, &m, &err) != CST_OK) fail_msg("%s", err.msg);
        size_t ne = 3 * (size_t)m.nt;
        uint64_t *e = malloc(ne * sizeof *e);
        assert_non_null(e);
        for (int t = 0; t < m.nt; t++)
            for (int k = 0; k < 3; k++) {
                uint64_t a = (uint64_t)m.idx[3 * t + k], b = (uint64_t)m.idx[3 * t + (k + 1) % 3];
                e[3 * t + k] = a < b ? (a << 33 | b << 1) : (b << 33 | a << 1 | 1u);
            }
        qsort(e, ne, sizeof *e, cmp_u64);
        assert_true(ne % 2 == 0);
        for (size_t i = 0; i < ne; i += 2)
            if (e[i] >> 1 != e[i + 1] >> 1 || (e[i] & 1u) != 0 || (e[i + 1] & 1u) != 1 ||
                (i + 2 < ne && e[i + 2] >> 1 == e[i] >> 1))
                fail_msg("edge (%llu, %llu) is not shared by exactly two opposite triangles",
                         (unsigned long long)(e[i] >> 33), (unsigned long long)((e[i] >> 1) & 0xffffffffu));
        assert_int_equal(m.nv - (int)(ne / 2) + m.nt, 2);
        assert_true(m.nt > 20 * (li + 1) * 10);
        free(e);
        displaced_mesh_free(&m);
    }
}

/* A tessellation beyond max_triangles fails before it is made; bad edge lengths and
 * descriptions are CST_ERR_INVALID_ARG naming the field. */
static void test_limits_and_bad_lengths(void **state)
{
    (void)state;
    CstScene *s = NULL;
    CstError err;
    assert_int_equal(cst_scene_create(&s, &err), CST_OK);
    CstDisplaceDesc d = square_desc(1e-3f);
    d.max_triangles = 1000;
    CstDisplacedMesh m;
    assert_int_equal(cst_scene_displace_mesh(s, &d, &m, &err), CST_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "exceed 1000 triangles"));
    assert_non_null(strstr(err.msg, "alone need at least 9.24e+06")); /* 4 / (sqrt(3)/4 1e-6) */
    assert_null(m.positions);
    /* the bounds pass (area: 103 triangles) but the bisection makes 256: stopped at 200 */
    d = square_desc(0.3f);
    d.max_triangles = 200;
    assert_int_equal(cst_scene_displace_mesh(s, &d, &m, &err), CST_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "exceed 200 triangles"));
    assert_null(strstr(err.msg, "alone need"));
    d.max_triangles = 256;
    if (cst_scene_displace_mesh(s, &d, &m, &err) != CST_OK) fail_msg("%s", err.msg);
    assert_int_equal(m.num_triangles, 256); /* legs 2 / sqrt(2)^7: 2 x 2^7 right isosceles triangles */
    cst_displaced_mesh_free(&m);
    /* a sliver (area 5e-5, perimeter 20) caught at once by its edges, 20 / (3 x 1e-3) = 6667
     * pieces, where its area alone asks for 115 */
    static const float SLIVER[9] = {0, 0, 0, 10, 0, 0, 5, 1e-5f, 0};
    static const int ONE[3] = {0, 1, 2};
    d = square_desc(1e-3f);
    d.positions = SLIVER, d.uvs = NULL, d.num_vertices = 3, d.indices = ONE, d.num_triangles = 1;
    d.max_triangles = 5000;
    assert_int_equal(cst_scene_displace_mesh(s, &d, &m, &err), CST_ERR_UNSUPPORTED);
    assert_non_null(strstr(err.msg, "alone need at least 6.67e+03"));
    const float bad[3] = {0.0f, -1.0f, NAN};
    for (int i = 0; i < 3; i++) {
        d = square_desc(bad[i]);
        assert_int_equal(cst_scene_displace_mesh(s, &d, &m, &err), CST_ERR_INVALID_ARG);
        assert_non_null(strstr(err.msg, "edge_length"));
    }
    d = square_desc(0.5f);
    d.texture = 1; /* the scene has none */
    assert_int_equal(cst_scene_displace_mesh(s, &d, &m, &err), CST_ERR_INVALID_ARG);
    cst_displaced_mesh_free(NULL);
    cst_scene_destroy(s);
}

#define PLY_HEAD "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\nproperty float z\n"
#define PLY_FACES "element face 2\nproperty list uchar int vertex_indices\nend_header\n"

/* pbrt-v4's plymesh "displacement": a constant float texture of 0.25 moves the unit square
 * (under Translate 0 0 7) to z = 7.25, tessellated to edges below "edgelength"; a mesh
 * without uvs and an edgelength <= 0 are errors located at the shape or the parameter. */
static void test_pbrt_plymesh(void **state)
{
    (void)state;
    write_text(CST_BINARY_DIR "/displace_uv.ply", PLY_HEAD "property float u\nproperty float v\n" PLY_FACES
               "0 0 0 0 0\n1 0 0 1 0\n1 1 0 1 1\n0 1 0 0 1\n3 0 1 2\n3 0 2 3\n");
    write_text(CST_BINARY_DIR "/displace_nouv.ply", PLY_HEAD PLY_FACES "0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
    const char *text = WORLD("Texture \"d\" \"float\" \"constant\" \"float value\" 0.25\n"
                             "Translate 0 0 7\nShape \"plymesh\" \"string filename\" \"displace_uv.ply\" "
                             "\"texture displacement\" \"d\" \"float edgelength\" 0.1\n");
    CstScene *s = NULL;
    CstError err;
    Warnings w = {0};
    if (load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, &w) != CST_OK) fail_msg("%s", err.msg);
    assert_true(s->num_triangles > 200);
    for (int t = 0; t < s->num_triangles; t++)
        for (int k = 0; k < 3; k++) assert_true(fabsf(tri_vertex(s, t, k).z - 7.25f) < 1e-6f);
    assert_true(find_warning(&w, CST_WARN_PARAMETER_IGNORED, "edgelength") < 0);
    cst_scene_destroy(s);
    /* a bilerp texture: d = u, the plane tilted to z = 7 + x */
    text = WORLD("Texture \"d\" \"float\" \"bilerp\" \"float v00\" 0 \"float v01\" 0 \"float v10\" 1 "
                 "\"float v11\" 1\nTranslate 0 0 7\nShape \"plymesh\" \"string filename\" \"displace_uv.ply\" "
                 "\"texture displacement\" \"d\" \"float edgelength\" 0.3\n");
    if (load_at(text, CST_BINARY_DIR "/t.pbrt", &s, &err, NULL) != CST_OK) fail_msg("%s", err.msg);
    for (int t = 0; t < s->num_triangles; t++)
        for (int k = 0; k < 3; k++) {
            Vec3 v = tri_vertex(s, t, k);
            if (!(fabsf(v.z - 7.0f - v.x) < 1e-6f)) fail_msg("vertex (%g, %g, %g)", (double)v.x, (double)v.y, (double)v.z);
        }
    cst_scene_destroy(s);
    static const char *const bad[3] = {"0", "-1", NULL};
    for (int i = 0; i < 3; i++) {
        char body[600];
        snprintf(body, sizeof body, WORLD("Texture \"d\" \"float\" \"constant\" \"float value\" 0.25\n"
                                          "Shape \"plymesh\" \"string filename\" \"%s\" \"texture displacement\" "
                                          "\"d\" \"float edgelength\" %s\n"),
                 bad[i] ? "displace_uv.ply" : "displace_nouv.ply", bad[i] ? bad[i] : "0.5");
        s = (CstScene *)(uintptr_t)1;
        assert_int_equal(load_at(body, CST_BINARY_DIR "/t.pbrt", &s, &err, NULL), CST_ERR_INVALID_ARG);
        assert_null(s);
        int line, col;
        pos_of(body, bad[i] ? "\"float edgelength\"" : "Shape", 0, &line, &col);
        char want[600];
        snprintf(want, sizeof want, CST_BINARY_DIR "/t.pbrt:%d:%d: Shape \"plymesh\": ", line, col);
        if (strncmp(err.msg, want, strlen(want)) != 0) fail_msg("message \"%s\"; expected \"%s...\"", err.msg, want);
        assert_non_null(strstr(err.msg, bad[i] ? "expected a length > 0" : "needs vertex uvs"));
    }
}

#define JSON_HEAD "{\"camera\": {\"position\": [0, 0, 5], \"look_at\": [0, 0, 0], \"fov\": 40},\n" \
                  "\"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"

/* The JSON meshes' "displacement": an inline mesh (world space) and a PLY meshfile under a
 * scale of 2 (displaced in the file's units, edges measured after the scale); a bad
 * edgelength is located at its value. */
static void test_json(void **state)
{
    (void)state;
    const char *text = JSON_HEAD
        "\"shapes\": [{\"type\": \"mesh\", \"material\": \"m\", \"vertices\": [[0,0,0],[1,0,0],[1,1,0],[0,1,0]],\n"
        "  \"indices\": [[0,1,2],[0,2,3]], \"displacement\": {\"texture\": -0.5, \"edgelength\": 0.2}},\n"
        " {\"type\": \"meshfile\", \"file\": \"" CST_BINARY_DIR "/displace_uv.ply\", \"material\": \"m\",\n"
        "  \"transform\": {\"scale\": [2, 2, 2]}, \"displacement\": {\"texture\": 0.25, \"edgelength\": 0.2}}]}";
    CstScene *s = NULL;
    CstError err;
    if (cst_scene_load_json_string(text, strlen(text), "d.json", &s, &err) != CST_OK) fail_msg("%s", err.msg);
    int n_inline = 0;
    for (int t = 0; t < s->num_triangles; t++) {
        float z = tri_vertex(s, t, 0).z;
        assert_true(fabsf(z + 0.5f) < 1e-6f || fabsf(z - 0.5f) < 1e-6f); /* 0.25 in the file's units, x 2 */
        n_inline += z < 0.0f;
        for (int k = 0; k < 3; k++) {
            float l = v3_length(v3_sub(tri_vertex(s, t, k), tri_vertex(s, t, (k + 1) % 3)));
            assert_true(l < 0.2f);
        }
    }
    assert_true(n_inline > 50 && s->num_triangles - n_inline > 4 * 50);
    cst_scene_destroy(s);
    const char *bad = JSON_HEAD
        "\"shapes\": [{\"type\": \"mesh\", \"material\": \"m\", \"vertices\": [[0,0,0],[1,0,0],[1,1,0]],\n"
        "  \"indices\": [[0,1,2]], \"displacement\": {\"texture\": 0.1, \"edgelength\": 0}}]}";
    s = (CstScene *)(uintptr_t)1;
    assert_int_equal(cst_scene_load_json_string(bad, strlen(bad), "d.json", &s, &err), CST_ERR_INVALID_ARG);
    assert_null(s);
    int line, col;
    pos_of(bad, "0}}]}", 0, &line, &col);
    char want[64];
    snprintf(want, sizeof want, "d.json:%d:%d: ", line, col);
    if (strncmp(err.msg, want, strlen(want)) != 0 || !strstr(err.msg, "expected a length > 0"))
        fail_msg("message \"%s\"; expected \"%s...\"", err.msg, want);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_constant_plane),
        cmocka_unit_test(test_sine_surface),
        cmocka_unit_test(test_watertight),
        cmocka_unit_test(test_limits_and_bad_lengths),
        cmocka_unit_test(test_pbrt_plymesh),
        cmocka_unit_test(test_json),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
