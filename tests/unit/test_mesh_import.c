/* Unit tests for mesh files: the assimp importer (scene/mesh_import.c) on small OBJ+MTL,
 * ASCII and binary PLY and glTF 2.0 files written to a temporary directory; the affine
 * transform module (math/transform.c); the JSON "meshfile" shape; and, when the shared
 * meshes are present, bunny.ply's face order checked bit for bit against the file. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include "unit/scratch_dir.h"

#include <dirent.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "caustic/caustic.h"
#include "math/transform.h"
#include "scene/mesh_import.h"
#include "scene/scene.h"

#define BUNNY_PATH CST_SOURCE_DIR "/../shared/meshes/bunny.ply"

/* ------------------------------------------------------------------ helpers */

static int group_setup(void **state)
{
    (void)state;
    return scratch_dir_make("/tmp/cst_mesh_XXXXXX");
}

static int group_teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

static const char *path_of(const char *name)
{
    static char buf[4][512];
    static int next;
    char *p = buf[next++ % 4];
    snprintf(p, sizeof buf[0], "%s/%s", g_dir, name);
    return p;
}

static void write_file(const char *name, const void *data, size_t len)
{
    FILE *f = fopen(path_of(name), "wb");
    assert_non_null(f);
    assert_int_equal(fwrite(data, 1, len, f), len);
    assert_int_equal(fclose(f), 0);
}

static void write_text(const char *name, const char *text) { write_file(name, text, strlen(text)); }

static void import_ok(const char *name, ImportedMesh *m)
{
    CstError err = {0};
    CstStatus st = mesh_import(path_of(name), m, &err);
    if (st != CST_OK)
        fail_msg("%s: %s: %s", name, cst_status_name(st), err.msg);
}

static Vec3 corner(const ImportedMesh *m, int tri, int k) { return m->positions[m->indices[3 * tri + k]]; }

static void assert_vec3_eq(Vec3 a, Vec3 b)
{
    if (a.x != b.x || a.y != b.y || a.z != b.z)
        fail_msg("(%.9g, %.9g, %.9g) != (%.9g, %.9g, %.9g)", (double)a.x, (double)a.y, (double)a.z,
                 (double)b.x, (double)b.y, (double)b.z);
}

static void assert_vec3_near(Vec3 a, Vec3 b, float tol)
{
    if (!(fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol))
        fail_msg("(%.9g, %.9g, %.9g) != (%.9g, %.9g, %.9g) within %g", (double)a.x, (double)a.y,
                 (double)a.z, (double)b.x, (double)b.y, (double)b.z, (double)tol);
}

static void assert_rgb_near(Color a, Color b)
{
    assert_vec3_near(v3(a.c[0], a.c[1], a.c[2]), v3(b.c[0], b.c[1], b.c[2]), 1e-6f);
}

/* Triangle `tri` has exactly the corners a, b, c in this order. */
static void assert_tri(const ImportedMesh *m, int tri, Vec3 a, Vec3 b, Vec3 c)
{
    assert_vec3_eq(corner(m, tri, 0), a);
    assert_vec3_eq(corner(m, tri, 1), b);
    assert_vec3_eq(corner(m, tri, 2), c);
}

/* Triangles t and t+1 split the unit square z = 0 (counter-clockwise from +z), whichever
 * diagonal assimp chose: every corner is a square corner and the areas, +z facing, add up. */
static void assert_unit_square(const ImportedMesh *m, int t)
{
    float area = 0.0f;
    for (int i = t; i < t + 2; i++) {
        for (int k = 0; k < 3; k++) {
            Vec3 p = corner(m, i, k);
            assert_true((p.x == 0.0f || p.x == 1.0f) && (p.y == 0.0f || p.y == 1.0f) && p.z == 0.0f);
        }
        Vec3 n = v3_cross(v3_sub(corner(m, i, 1), corner(m, i, 0)), v3_sub(corner(m, i, 2), corner(m, i, 0)));
        assert_true(n.z > 0.0f);
        area += 0.5f * n.z;
    }
    assert_true(area == 1.0f);
}

/* Canonical binary PLY (format in /work/shared/meshes/README.md). */
static void write_binary_ply(const char *name, const float *pos, int nv, const int32_t *idx, int nt)
{
    char header[256];
    int hl = snprintf(header, sizeof header,
                      "ply\nformat binary_little_endian 1.0\ncomment test\nelement vertex %d\n"
                      "property float x\nproperty float y\nproperty float z\nelement face %d\n"
                      "property list uchar int vertex_indices\nend_header\n",
                      nv, nt);
    size_t len = (size_t)hl + 12 * (size_t)nv + 13 * (size_t)nt;
    unsigned char *buf = malloc(len), *p = buf;
    assert_non_null(buf);
    memcpy(p, header, (size_t)hl);
    p += hl;
    memcpy(p, pos, 12 * (size_t)nv); /* this host is little-endian, like the format */
    p += 12 * nv;
    for (int t = 0; t < nt; t++) {
        *p++ = 3;
        memcpy(p, &idx[3 * t], 12);
        p += 12;
    }
    write_file(name, buf, len);
    free(buf);
}

static void base64(const unsigned char *in, size_t n, char *out)
{
    static const char tab[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t o = 0;
    for (size_t i = 0; i < n; i += 3) {
        uint32_t v = (uint32_t)in[i] << 16 | (i + 1 < n ? (uint32_t)in[i + 1] << 8 : 0) |
                     (i + 2 < n ? in[i + 2] : 0);
        out[o++] = tab[v >> 18 & 63];
        out[o++] = tab[v >> 12 & 63];
        out[o++] = i + 1 < n ? tab[v >> 6 & 63] : '=';
        out[o++] = i + 2 < n ? tab[v & 63] : '=';
    }
    out[o] = '\0';
}

/* ------------------------------------------------------------------ transform module */

static void test_transform_compose(void **state)
{
    (void)state;
    Transform id = transform_identity();
    assert_true(transform_is_identity(&id));
    assert_true(transform_is_affine(&id));
    /* compose(a, b) applies b first: scale, then translate. */
    Transform t = transform_compose(transform_translate(v3(1, 0, 0)), transform_scale(v3s(2)));
    assert_vec3_eq(transform_point(&t, v3(1, 1, 1)), v3(3, 2, 2));
    assert_vec3_eq(transform_vector(&t, v3(1, 1, 1)), v3(2, 2, 2)); /* no translation */
    Transform u = transform_compose(transform_scale(v3s(2)), transform_translate(v3(1, 0, 0)));
    assert_vec3_eq(transform_point(&u, v3(1, 1, 1)), v3(4, 2, 2));
    /* Quarter turns are exact; right-handed: +x about +z goes to +y. */
    Transform rz = transform_rotate_degrees(v3(0, 0, 5), 90.0);
    assert_vec3_eq(transform_point(&rz, v3(1, 0, 0)), v3(0, 1, 0));
    Transform ry = transform_rotate_degrees(v3(0, 1, 0), -270.0);
    assert_vec3_eq(transform_point(&ry, v3(1, 2, 0)), v3(0, 2, -1));
    Transform r = transform_rotate(v3(1, 1, 1), 2.0943951f); /* 120 degrees: x -> y -> z */
    assert_vec3_near(transform_point(&r, v3(1, 0, 0)), v3(0, 1, 0), 1e-6f);
    Transform rd = transform_rotate_degrees(v3(1, 1, 1), 120.0);
    assert_vec3_near(transform_point(&rd, v3(0, 1, 0)), v3(0, 0, 1), 1e-6f);
    /* From rows: translation in the last column. */
    const float rows[16] = {1, 0, 0, 5, 0, 1, 0, 6, 0, 0, 1, 7, 0, 0, 0, 1};
    Transform m = transform_from_rows(rows);
    assert_vec3_eq(transform_point(&m, v3(1, 1, 1)), v3(6, 7, 8));
    Transform bad = m;
    bad.m[3][2] = 1.0f;
    assert_false(transform_is_affine(&bad));
    bad = m;
    bad.m[0][1] = NAN;
    assert_false(transform_is_affine(&bad));
}

static void test_transform_inverse_normals(void **state)
{
    (void)state;
    Transform s = transform_scale(v3(-1, 2, 3));
    assert_true(transform_det(&s) == -6.0);
    Transform rows = transform_compose(transform_translate(v3(3, -2, 1)),
                                       transform_compose(transform_rotate_degrees(v3(1, 2, 3), 33.0),
                                                         transform_scale(v3(2, 0.5f, 1.5f))));
    Transform inv;
    assert_true(transform_invert(&rows, &inv));
    Transform prod = transform_compose(rows, inv);
    for (int i = 0; i < 4; i++)
        for (int j = 0; j < 4; j++)
            assert_true(fabsf(prod.m[i][j] - (i == j ? 1.0f : 0.0f)) < 1e-6f);
    /* Non-uniform scale: the normal (1, 1, 0)/sqrt2 of the plane x + y = c becomes
     * (1/2, 1, 0) normalised, not (2, 1, 0). */
    Transform nm;
    Transform sc = transform_scale(v3(2, 1, 1));
    assert_true(transform_normal_matrix(&sc, &nm));
    Vec3 n = transform_normal(&nm, v3(0.70710678f, 0.70710678f, 0));
    assert_vec3_near(n, v3_normalize(v3(0.5f, 1, 0)), 1e-6f);
    /* In general normals stay perpendicular to transformed tangents. */
    assert_true(transform_normal_matrix(&rows, &nm));
    Vec3 n0 = v3_normalize(v3(1, 2, 2)), t0 = v3(2, -1, 0); /* n0 . t0 = 0 */
    Vec3 n1 = transform_normal(&nm, n0), t1 = transform_vector(&rows, t0);
    assert_true(fabsf(v3_dot(n1, t1)) < 1e-5f * v3_length(t1));
    assert_true(fabsf(v3_length(n1) - 1.0f) < 1e-6f);
    assert_vec3_eq(transform_normal(&nm, v3s(0)), v3s(0)); /* "no normal" stays so */
    Transform flat = transform_scale(v3(1, 0, 1));
    assert_false(transform_normal_matrix(&flat, &nm));
    assert_false(transform_invert(&flat, &inv));
}

/* ------------------------------------------------------------------ importer */

static const char obj_mtl[] =
    "newmtl red\nKd 0.8 0.1 0.1\nillum 2\n"
    "newmtl mirror\nKd 0.2 0.2 0.2\nKs 0.9 0.9 0.9\nillum 3\n"
    "newmtl glass\nKd 1 1 1\nTf 0.9 1 0.9\nNi 1.52\nillum 7\n"
    "newmtl dissolve\nKd 0.2 0.3 0.4\nd 0.5\nillum 2\n"
    "newmtl bright\nKd 1.5 0.5 -0.2\nillum 1\n";

static const char obj_text[] =
    "mtllib m.mtl\n"
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0.5 0.5 1\n"
    "vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n"
    "vn 0 0 2\n"
    "usemtl red\nf 1/1/1 2/2/1 3/3/1\n"
    "usemtl mirror\nf 1/1/1 3/3/1 4/4/1\n"
    "usemtl red\nf 1/1/1 2/2/1 3/3/1 4/4/1\nl 1 2\np 5\n"
    "usemtl glass\nf 3 4 5\n"
    "usemtl dissolve\nf 1 2 5\n"
    "usemtl bright\nf 2 3 5\n";

static const ImportedMaterial *tri_mat(const ImportedMesh *m, int t)
{
    assert_non_null(m->tri_material);
    assert_in_range(m->tri_material[t], 0, m->num_materials - 1);
    return &m->materials[m->tri_material[t]];
}

static void test_obj_mtl(void **state)
{
    (void)state;
    write_text("m.mtl", obj_mtl);
    write_text("m.obj", obj_text);
    ImportedMesh m;
    import_ok("m.obj", &m);
    Vec3 p1 = v3(0, 0, 0), p2 = v3(1, 0, 0), p3 = v3(1, 1, 0), p4 = v3(0, 1, 0), p5 = v3(0.5f, 0.5f, 1);
    assert_int_equal(m.num_triangles, 7);
    assert_int_equal(m.num_skipped_primitives, 2); /* the line and the point */
    /* Face order of the file, across material changes; the quad keeps its place. */
    assert_tri(&m, 0, p1, p2, p3);
    assert_tri(&m, 1, p1, p3, p4);
    assert_unit_square(&m, 2);
    assert_tri(&m, 4, p3, p4, p5);
    assert_tri(&m, 5, p1, p2, p5);
    assert_tri(&m, 6, p2, p3, p5);
    /* Normals normalised; faces without them get zeros, flagged partial. Same for UVs. */
    assert_non_null(m.normals);
    assert_non_null(m.uvs);
    assert_true(m.normals_partial);
    assert_true(m.uvs_partial);
    for (int k = 0; k < 3; k++) {
        assert_vec3_eq(m.normals[m.indices[k]], v3(0, 0, 1));
        assert_vec3_eq(m.normals[m.indices[12 + k]], v3s(0));
    }
    static const float uv0[3][2] = {{0, 0}, {1, 0}, {1, 1}};
    for (int k = 0; k < 3; k++) {
        Vec2 uv = m.uvs[m.indices[k]];
        assert_true(uv.x == uv0[k][0] && uv.y == uv0[k][1]);
    }
    /* Materials: the mapping documented in mesh_import.c. */
    const ImportedMaterial *red = tri_mat(&m, 0), *mir = tri_mat(&m, 1);
    assert_string_equal(red->name, "red");
    assert_true(red->from_file);
    assert_int_equal(red->type, MATERIAL_DIFFUSE);
    assert_rgb_near(red->albedo, color_rgb(0.8f, 0.1f, 0.1f));
    assert_ptr_equal(tri_mat(&m, 2), red);
    assert_ptr_equal(tri_mat(&m, 3), red);
    assert_int_equal(mir->type, MATERIAL_MIRROR);
    assert_rgb_near(mir->albedo, color_s(0.9f));
    const ImportedMaterial *glass = tri_mat(&m, 4), *dis = tri_mat(&m, 5), *bright = tri_mat(&m, 6);
    assert_int_equal(glass->type, MATERIAL_GLASS);
    assert_true(fabsf(glass->ior - 1.52f) < 1e-6f);
    assert_rgb_near(glass->albedo, color_rgb(0.9f, 1.0f, 0.9f));
    assert_int_equal(dis->type, MATERIAL_GLASS); /* d < 1 */
    assert_true(dis->ior == 1.5f);               /* no Ni: the default */
    assert_int_equal(bright->type, MATERIAL_DIFFUSE);
    assert_rgb_near(bright->albedo, color_rgb(1.0f, 0.5f, 0.0f)); /* clamped to [0, 1] */
    mesh_import_free(&m);
    assert_null(m.positions);
    mesh_import_free(NULL);
}

static void test_ply_ascii(void **state)
{
    (void)state;
    write_text("a.ply", "ply\nformat ascii 1.0\ncomment test\nelement vertex 5\n"
                        "property float x\nproperty float y\nproperty float z\n"
                        "property float nx\nproperty float ny\nproperty float nz\n"
                        "property float s\nproperty float t\n"
                        "element face 3\nproperty list uchar int vertex_indices\nend_header\n"
                        "0 0 0 0 0 1 0 0\n1 0 0 0 0 1 1 0\n1 1 0 0 0 1 1 1\n0 1 0 0 0 1 0 1\n"
                        "9 9 9 0 1 0 0.5 0.25\n"
                        "3 0 1 2\n4 0 1 2 3\n3 4 0 1\n");
    ImportedMesh m;
    import_ok("a.ply", &m);
    assert_int_equal(m.num_vertices, 5); /* indexed: the file's vertex array as is */
    assert_int_equal(m.num_triangles, 4);
    assert_int_equal(m.indices[0], 0);
    assert_int_equal(m.indices[1], 1);
    assert_int_equal(m.indices[2], 2);
    assert_unit_square(&m, 1);
    assert_int_equal(m.indices[9], 4);
    assert_int_equal(m.indices[10], 0);
    assert_int_equal(m.indices[11], 1);
    assert_vec3_eq(m.positions[4], v3(9, 9, 9));
    assert_non_null(m.normals);
    assert_false(m.normals_partial);
    assert_vec3_eq(m.normals[4], v3(0, 1, 0));
    assert_non_null(m.uvs);
    assert_true(m.uvs[4].x == 0.5f && m.uvs[4].y == 0.25f); /* PLY s, t as written */
    /* PLY has no materials: assimp's stand-in is not the file's. */
    assert_false(tri_mat(&m, 0)->from_file);
    mesh_import_free(&m);
}

static void test_ply_binary(void **state)
{
    (void)state;
    /* Values that are not short decimals, a negative zero, a degenerate triangle (kept:
     * dropping is the scene's business), an unused vertex. */
    const float pos[] = {0.1f, -0.0f, 1e-7f, 3.14159274f, 2.0f / 3.0f, -5.5f, -1e6f, 0.3f, 7.0f,
                         42.0f, 42.0f, 42.0f, 0.1f, -0.0f, 1e-7f};
    const int32_t idx[] = {0, 1, 2, 2, 1, 0, 0, 4, 1, 1, 2, 4};
    write_binary_ply("b.ply", pos, 5, idx, 4);
    ImportedMesh m;
    import_ok("b.ply", &m);
    assert_int_equal(m.num_vertices, 5);
    assert_int_equal(m.num_triangles, 4);
    assert_memory_equal(m.positions, pos, sizeof pos); /* bit for bit, -0.0 included */
    for (int i = 0; i < 12; i++)
        assert_int_equal(m.indices[i], idx[i]);
    assert_null(m.normals);
    assert_null(m.uvs);
    mesh_import_free(&m);
}

/* glTF 2.0 with an embedded buffer: a node hierarchy (translate, then non-uniform scale),
 * a mirrored node, normals, UVs, a metal and a transmissive material. */
static void test_gltf(void **state)
{
    (void)state;
    const float pos[12] = {0, 0, 0, 1, 0, 0, 0, 1, 0, 1, 1, 0};
    const float nrm[12] = {0.6f, 0.8f, 0, 0.6f, 0.8f, 0, 0.6f, 0.8f, 0, 0.6f, 0.8f, 0};
    const float uv[8] = {0, 0, 1, 0, 0, 1, 1, 1.0f};
    const uint16_t idx[6] = {0, 1, 2, 1, 3, 2};
    unsigned char buf[140] = {0};
    memcpy(buf, pos, 48);
    memcpy(buf + 48, nrm, 48);
    memcpy(buf + 96, uv, 32);
    memcpy(buf + 128, idx, 12);
    char b64[200];
    base64(buf, sizeof buf, b64);
    char text[4096];
    snprintf(text, sizeof text,
             "{\"asset\": {\"version\": \"2.0\"}, \"scene\": 0, \"scenes\": [{\"nodes\": [0, 2]}],\n"
             " \"extensionsUsed\": [\"KHR_materials_transmission\", \"KHR_materials_ior\"],\n"
             " \"nodes\": [{\"translation\": [10, 0, 0], \"children\": [1]},\n"
             "           {\"scale\": [2, 1, 1], \"mesh\": 0}, {\"scale\": [-1, 1, 1], \"mesh\": 1}],\n"
             " \"meshes\": [{\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, "
             "\"TEXCOORD_0\": 2}, \"indices\": 3, \"material\": 0}]},\n"
             "            {\"primitives\": [{\"attributes\": {\"POSITION\": 0, \"NORMAL\": 1, "
             "\"TEXCOORD_0\": 2}, \"indices\": 3, \"material\": 1}]}],\n"
             " \"materials\": [{\"name\": \"gold\", \"pbrMetallicRoughness\": {\"baseColorFactor\": "
             "[1, 0.8, 0.2, 1], \"metallicFactor\": 1, \"roughnessFactor\": 0}},\n"
             "   {\"name\": \"water\", \"pbrMetallicRoughness\": {\"baseColorFactor\": [0.9, 1, 0.9, 1], "
             "\"metallicFactor\": 0, \"roughnessFactor\": 0}, \"extensions\": "
             "{\"KHR_materials_transmission\": {\"transmissionFactor\": 1}, \"KHR_materials_ior\": "
             "{\"ior\": 1.33}}}],\n"
             " \"buffers\": [{\"byteLength\": 140, \"uri\": \"data:application/octet-stream;base64,%s\"}],\n"
             " \"bufferViews\": [{\"buffer\": 0, \"byteOffset\": 0, \"byteLength\": 48},\n"
             "   {\"buffer\": 0, \"byteOffset\": 48, \"byteLength\": 48},\n"
             "   {\"buffer\": 0, \"byteOffset\": 96, \"byteLength\": 32},\n"
             "   {\"buffer\": 0, \"byteOffset\": 128, \"byteLength\": 12}],\n"
             " \"accessors\": [{\"bufferView\": 0, \"componentType\": 5126, \"count\": 4, \"type\": "
             "\"VEC3\", \"min\": [0, 0, 0], \"max\": [1, 1, 0]},\n"
             "   {\"bufferView\": 1, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC3\"},\n"
             "   {\"bufferView\": 2, \"componentType\": 5126, \"count\": 4, \"type\": \"VEC2\"},\n"
             "   {\"bufferView\": 3, \"componentType\": 5123, \"count\": 6, \"type\": \"SCALAR\"}]}\n",
             b64);
    write_text("g.gltf", text);
    ImportedMesh m;
    import_ok("g.gltf", &m);
    assert_int_equal(m.num_triangles, 4);
    assert_int_equal(m.num_vertices, 8);
    /* Node 1 under node 0: x -> 2x + 10. */
    assert_tri(&m, 0, v3(10, 0, 0), v3(12, 0, 0), v3(10, 1, 0));
    assert_tri(&m, 1, v3(12, 0, 0), v3(12, 1, 0), v3(10, 1, 0));
    /* Node 2 mirrors x: the winding is swapped back so the +z side stays the front. */
    assert_tri(&m, 2, v3(0, 0, 0), v3(0, 1, 0), v3(-1, 0, 0));
    Vec3 a = corner(&m, 2, 0);
    Vec3 ng = v3_cross(v3_sub(corner(&m, 2, 1), a), v3_sub(corner(&m, 2, 2), a));
    assert_true(ng.z > 0.0f);
    /* Normals by the inverse transpose: diag(2, 1, 1) -> diag(1/2, 1, 1). */
    assert_vec3_near(m.normals[m.indices[0]], v3_normalize(v3(0.3f, 0.8f, 0)), 1e-6f);
    assert_vec3_near(m.normals[m.indices[6]], v3(-0.6f, 0.8f, 0), 1e-6f);
    /* UVs: assimp flips glTF's v (origin top-left) to its own (bottom-left). */
    Vec2 uv2 = m.uvs[m.indices[2]]; /* vertex 2, glTF uv (0, 1) */
    assert_true(uv2.x == 0.0f && uv2.y == 0.0f);
    Vec2 uv1 = m.uvs[m.indices[1]]; /* vertex 1, glTF uv (1, 0) */
    assert_true(uv1.x == 1.0f && uv1.y == 1.0f);
    const ImportedMaterial *gold = tri_mat(&m, 0), *water = tri_mat(&m, 3);
    assert_int_equal(gold->type, MATERIAL_MIRROR);
    assert_rgb_near(gold->albedo, color_rgb(1.0f, 0.8f, 0.2f));
    assert_true(gold->from_file);
    assert_int_equal(water->type, MATERIAL_GLASS);
    assert_true(fabsf(water->ior - 1.33f) < 1e-6f);
    assert_rgb_near(water->albedo, color_rgb(0.9f, 1.0f, 0.9f));
    mesh_import_free(&m);
}

static void expect_import_error(const char *name, CstStatus status, const char *what)
{
    ImportedMesh m;
    memset(&m, 0xAB, sizeof m);
    CstError err = {0};
    CstStatus st = mesh_import(path_of(name), &m, &err);
    if (st != status)
        fail_msg("%s: status %s, expected %s: %s", name, cst_status_name(st), cst_status_name(status),
                 err.msg);
    assert_int_equal(err.status, status);
    assert_null(m.positions);
    assert_int_equal(m.num_triangles, 0);
    if (!strstr(err.msg, path_of(name)))
        fail_msg("message \"%s\" does not name the file %s", err.msg, path_of(name));
    if (what && !strstr(err.msg, what))
        fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
    mesh_import_free(&m);
}

static void test_import_errors(void **state)
{
    (void)state;
    expect_import_error("missing.obj", CST_ERR_IO, "No such file or directory");
    expect_import_error("", CST_ERR_IO, "is not a regular file (a directory)"); /* the temp dir itself */
    /* PLY files are checked before assimp sees them (it hangs or crashes on these). */
    write_text("garbage.ply", "ply\nthis is not a header\n\x01\x02\x03");
    expect_import_error("garbage.ply", CST_ERR_PARSE, "garbage.ply:2: malformed PLY header");
    write_text("noend.ply", "ply\nformat ascii 1.0\nelement vertex 3\n");
    expect_import_error("noend.ply", CST_ERR_PARSE, "no end_header");
    write_text("short.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                            "property float y\nproperty float z\nelement face 1\n"
                            "property list uchar int vertex_indices\nend_header\n"
                            "0 0 0\n1 0 0\n0 1 0\n3 0 1\n");
    expect_import_error("short.ply", CST_ERR_PARSE, "face 1 of 1: the file ends inside the record");
    write_text("word.ply", "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n"
                           "property float y\nproperty float z\nend_header\n"
                           "0 0 0\n1 zero 0\n0 1 0\n");
    expect_import_error("word.ply", CST_ERR_PARSE, "word.ply:9: malformed PLY data: vertex 2 of 3: \"zero\"; expected a number");
    const float pos[9] = {0, 0, 0, 1, 0, 0, 0, 1, 0};
    const int32_t idx[6] = {0, 1, 2, 0, 2, 1};
    write_binary_ply("cut.ply", pos, 3, idx, 2);
    FILE *f = fopen(path_of("cut.ply"), "rb");
    assert_non_null(f);
    char whole[1024];
    size_t n = fread(whole, 1, sizeof whole, f);
    fclose(f);
    write_file("cut.ply", whole, n - 1); /* one byte short: assimp would read past the end */
    expect_import_error("cut.ply", CST_ERR_PARSE, "face 2 of 2 (starting at byte");
    write_file("cut.ply", whole, n - 20); /* into the faces: assimp would crash */
    expect_import_error("cut.ply", CST_ERR_PARSE, "face 1 of 2 (starting at byte");
    unsigned char noise[2048];
    uint32_t x = 12345;
    for (size_t i = 0; i < sizeof noise; i++) {
        x = x * 1664525u + 1013904223u;
        noise[i] = (unsigned char)(x >> 24);
    }
    write_file("noise.bin", noise, sizeof noise);
    expect_import_error("noise.bin", CST_ERR_PARSE, "cannot import");
    write_text("badindex.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 9\n");
    expect_import_error("badindex.obj", CST_ERR_PARSE, "out of range");
    write_text("lines.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nl 1 2\nl 2 3\n");
    expect_import_error("lines.obj", CST_ERR_PARSE, "no triangles");
}

/* Every triangle of bunny.ply against the file read directly: face i is triangle i, its
 * vertex indices and positions bit for bit. */
static void test_bunny_face_order(void **state)
{
    (void)state;
    FILE *f = fopen(BUNNY_PATH, "rb");
    if (!f) {
        print_message("skipped: %s not found\n", BUNNY_PATH);
        skip();
    }
    char line[256];
    long nv = -1, nt = -1;
    int props = 0;
    while (fgets(line, sizeof line, f) && strcmp(line, "end_header\n") != 0) {
        if (strncmp(line, "element vertex ", 15) == 0)
            nv = atol(line + 15);
        else if (strncmp(line, "element face ", 13) == 0)
            nt = atol(line + 13);
        else if (strncmp(line, "property ", 9) == 0)
            props++;
    }
    assert_true(nv > 0 && nt > 0);
    assert_int_equal(props, 4); /* x, y, z, vertex_indices: the canonical form */
    float *pos = malloc((size_t)nv * 12);
    unsigned char *faces = malloc((size_t)nt * 13);
    assert_non_null(pos);
    assert_non_null(faces);
    assert_int_equal(fread(pos, 12, (size_t)nv, f), (size_t)nv);
    assert_int_equal(fread(faces, 13, (size_t)nt, f), (size_t)nt);
    fclose(f);

    ImportedMesh m;
    CstError err = {0};
    CstStatus st = mesh_import(BUNNY_PATH, &m, &err);
    if (st != CST_OK)
        fail_msg("%s", err.msg);
    assert_int_equal(m.num_vertices, nv);
    assert_int_equal(m.num_triangles, nt);
    long index_mismatch = 0, position_mismatch = 0;
    for (long t = 0; t < nt; t++) {
        const unsigned char *rec = faces + 13 * t;
        assert_int_equal(rec[0], 3);
        for (int k = 0; k < 3; k++) {
            int32_t fi;
            memcpy(&fi, rec + 1 + 4 * k, 4);
            assert_in_range(fi, 0, nv - 1);
            index_mismatch += m.indices[3 * t + k] != fi;
            position_mismatch += memcmp(&m.positions[m.indices[3 * t + k]], pos + 3 * (size_t)fi, 12) != 0;
        }
    }
    if (index_mismatch || position_mismatch)
        fail_msg("bunny: %ld corner indices and %ld corner positions differ from the file",
                 index_mismatch, position_mismatch);
    free(pos);
    free(faces);
    mesh_import_free(&m);
}

/* ------------------------------------------------------------------ JSON "meshfile" */

/* 1-based line and column of the first occurrence of needle in text. */
static void pos_of(const char *text, const char *needle, int *line, int *col)
{
    const char *at = strstr(text, needle);
    if (!at)
        fail_msg("needle \"%s\" not in the test text", needle);
    *line = 1;
    *col = 1;
    for (const char *p = text; p < at; p++) {
        if (*p == '\n') {
            (*line)++;
            *col = 1;
        } else if (((unsigned char)*p & 0xC0) != 0x80) {
            (*col)++;
        }
    }
}

#define SCENE_HEAD                                                                         \
    "{\"camera\": {\"position\": [0, 0, 10], \"look_at\": [0, 0, 0], \"fov\": 40},\n"       \
    " \"materials\": {\"white\": {\"type\": \"diffuse\", \"albedo\": [0.7, 0.7, 0.7]}},\n" \
    " \"shapes\": [\n"

static const char *scene_name(void) { return path_of("scene.json"); }

static CstStatus load_scene(const char *text, CstScene **out, CstError *err)
{
    return cst_scene_load_json_string(text, strlen(text), scene_name(), out, err);
}

static Scene *load_scene_ok(const char *text)
{
    CstScene *s = NULL;
    CstError err = {0};
    CstStatus st = load_scene(text, &s, &err);
    if (st != CST_OK)
        fail_msg("%s: %s\ntext: %s", cst_status_name(st), err.msg, text);
    return s;
}

/* Fails with status at the position of needle, the message holding `what` (and `what2`). */
static void expect_scene_error(const char *text, CstStatus status, const char *needle,
                               const char *what, const char *what2)
{
    CstScene *s = NULL;
    CstError err = {0};
    CstStatus st = load_scene(text, &s, &err);
    if (st != status)
        fail_msg("status %s, expected %s; message: %s\ntext: %s", cst_status_name(st),
                 cst_status_name(status), err.msg, text);
    assert_null(s);
    int line, col;
    pos_of(text, needle, &line, &col);
    char prefix[640];
    snprintf(prefix, sizeof prefix, "%s:%d:%d: ", scene_name(), line, col);
    if (strncmp(err.msg, prefix, strlen(prefix)) != 0)
        fail_msg("message \"%s\" does not start with \"%s\"", err.msg, prefix);
    if (what && !strstr(err.msg, what))
        fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
    if (what2 && !strstr(err.msg, what2))
        fail_msg("message \"%s\" lacks \"%s\"", err.msg, what2);
}

/* Two triangles facing +z with normals and UVs, one degenerate (collinear) in between. */
static void write_json_meshes(void)
{
    write_text("j.mtl", "newmtl blue\nKd 0.1 0.2 0.7\nillum 2\n");
    write_text("j.obj", "mtllib j.mtl\nv 1 0 0\nv 0 1 0\nv 0 0 0\nv 2 0 0\nv 3 0 0\n"
                        "vt 0.25 0.75\nvn 0 0 1\nusemtl blue\n"
                        "f 3/1/1 1/1/1 2/1/1\nf 3/1/1 1/1/1 4/1/1\nf 1/1/1 4/1/1 2/1/1\n");
    write_text("plain.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
}

static void test_json_meshfile(void **state)
{
    (void)state;
    write_json_meshes();
    /* An inline mesh (no normals) first, then the file: scale, quarter turn about +y
     * ((x, y, z) -> (z, y, -x)), translate; the file's material; the degenerate dropped. */
    Scene *s = load_scene_ok(SCENE_HEAD
                             "  {\"type\": \"mesh\", \"material\": \"white\", \"vertices\": "
                             "[[0, 0, 0], [1, 0, 0], [0, 1, 0]], \"indices\": [[0, 1, 2]]},\n"
                             "  {\"type\": \"meshfile\", \"file\": \"j.obj\", \"transform\": "
                             "{\"scale\": 2, \"rotate\": {\"axis\": [0, 1, 0], \"angle\": 90}, "
                             "\"translate\": [1, 2, 3]}}\n ]}\n");
    assert_int_equal(s->num_triangles, 3);
    assert_int_equal(s->num_materials, 2);
    const Material *blue = &s->materials[s->tri_info[1].material];
    assert_int_equal(blue->type, MATERIAL_DIFFUSE);
    assert_rgb_near(blue->albedo, color_rgb(0.1f, 0.2f, 0.7f));
    assert_int_equal(s->tri_info[2].material, s->tri_info[1].material);
    assert_int_equal(s->tri_info[0].material, 0);
    /* Triangle 1 = file face 0: (0,0,0) (1,0,0) (0,1,0) -> (1,2,3) (1,2,1) (1,4,3). */
    const int32_t *t1 = &s->tri_indices[3];
    assert_vec3_eq(s->positions[t1[0]], v3(1, 2, 3));
    assert_vec3_eq(s->positions[t1[1]], v3(1, 2, 1));
    assert_vec3_eq(s->positions[t1[2]], v3(1, 4, 3));
    /* Triangle 2 = file face 2 (face 1 was degenerate): corner 1 (2,0,0) -> (1,2,-1). */
    assert_vec3_eq(s->positions[s->tri_indices[7]], v3(1, 2, -1));
    /* Normals: the inline mesh's are zero fills; the file's (0,0,1) turned to (1,0,0). */
    assert_non_null(s->normals);
    assert_true(s->normals_partial);
    assert_vec3_eq(s->normals[s->tri_indices[0]], v3s(0));
    assert_vec3_eq(s->normals[t1[0]], v3(1, 0, 0));
    assert_non_null(s->uvs);
    assert_true(s->uvs[t1[2]].x == 0.25f && s->uvs[t1[2]].y == 0.75f);
    /* After commit the geometric normal agrees with the shading normal. */
    assert_vec3_near(s->tri_normals[1], v3(1, 0, 0), 1e-6f);
    cst_scene_destroy(s);

    /* A material named in the scene overrides the file's; "matrix"; a mirror keeps the
     * outside out (winding swapped back); rotations in list order. */
    s = load_scene_ok(SCENE_HEAD
                      "  {\"type\": \"meshfile\", \"file\": \"j.obj\", \"material\": \"white\", "
                      "\"transform\": {\"matrix\": [1, 0, 0, 5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}},\n"
                      "  {\"type\": \"meshfile\", \"file\": \"j.obj\", \"material\": \"white\", "
                      "\"transform\": {\"scale\": [-1, 1, 1]}},\n"
                      "  {\"type\": \"meshfile\", \"file\": \"" "plain.obj\", \"material\": \"white\", "
                      "\"transform\": {\"rotate\": [{\"axis\": [0, 0, 1], \"angle\": 90}, "
                      "{\"axis\": [1, 0, 0], \"angle\": 90}]}}\n ]}\n");
    assert_int_equal(s->num_materials, 1);
    assert_int_equal(s->num_triangles, 5);
    for (int t = 0; t < 5; t++)
        assert_int_equal(s->tri_info[t].material, 0);
    assert_vec3_eq(s->positions[s->tri_indices[1]], v3(6, 0, 0));
    assert_vec3_near(s->tri_normals[2], v3(0, 0, 1), 1e-6f); /* mirrored, still +z */
    assert_vec3_eq(s->normals[s->tri_indices[6]], v3(0, 0, 1));
    /* (1,0,0): about z first -> (0,1,0), then about x -> (0,0,1). */
    assert_vec3_eq(s->positions[s->tri_indices[13]], v3(0, 0, 1));
    assert_true(s->uvs_partial); /* plain.obj has none */
    cst_scene_destroy(s);
}

static void test_json_meshfile_errors(void **state)
{
    (void)state;
    write_json_meshes();
    char text[1024], resolved[600];
    /* A missing file: the "file" value's position and the resolved path. */
    snprintf(text, sizeof text, SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\",\n"
                                           "   \"file\": \"nope/missing.obj\"}\n ]}\n");
    snprintf(resolved, sizeof resolved, "%s/nope/missing.obj", g_dir);
    expect_scene_error(text, CST_ERR_IO, "\"nope/missing.obj\"", resolved,
                       "No such file or directory");
    /* A malformed one. */
    write_text("junk.ply", "ply\nformat ascii 1.0\nelement vertex x\n");
    expect_scene_error(SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\", \"file\": "
                                  "\"junk.ply\"}\n ]}\n",
                       CST_ERR_PARSE, "\"junk.ply\"", "junk.ply:3: malformed PLY header", NULL);
    write_file("junk.obj", "\x7f\x45\x4c\x46\x02\x01\x01", 7);
    expect_scene_error(SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\", \"file\": "
                                  "\"junk.obj\"}\n ]}\n",
                       CST_ERR_PARSE, "\"junk.obj\"", "junk.obj: ", NULL);
    /* No "material" and a file without materials: the shape's error. */
    expect_scene_error(SCENE_HEAD "  {\"type\": \"meshfile\", \"file\": \"plain.obj\"}\n ]}\n",
                       CST_ERR_INVALID_ARG, "{\"type\": \"meshfile\"", "missing key \"material\"",
                       NULL);
    expect_scene_error(SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\"}\n ]}\n",
                       CST_ERR_INVALID_ARG, "{\"type\": \"meshfile\"", "missing key \"file\"", NULL);
    expect_scene_error(SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\", \"file\": "
                                  "\"plain.obj\", \"scale\": 2}\n ]}\n",
                       CST_ERR_INVALID_ARG, "\"scale\"", "unknown key \"scale\"", "transform");
    /* Transform errors, each at its value or key. */
    static const struct {
        const char *transform, *needle, *what;
    } cases[] = {
        {"{\"rotation\": 1}", "\"rotation\"", "unknown key \"rotation\""},
        {"{\"translate\": [1, 2, 3], \"matrix\": [1]}", "\"translate\"", "cannot be combined"},
        {"{\"matrix\": [1, 0, 0]}", "[1, 0, 0]", "expected 16 numbers"},
        {"{\"matrix\": [1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 1, 1]}", "1, 1]", "affine"},
        {"{\"matrix\": [1, 0, 0, 0, 0, 0, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1]}", "{\"matrix\"", "singular"},
        {"{\"scale\": [1, 0, 1]}", "0, 1]", "scale 0"},
        {"{\"scale\": \"big\"}", "\"big\"", "expected a number or an array of 3 numbers"},
        {"{\"rotate\": {\"axis\": [0.0, 0, 0], \"angle\": 5}}", "[0.0, 0, 0]", "axis is zero"},
        {"{\"rotate\": {\"axis\": [0, 0, 1]}}", "{\"axis\"", "missing key \"angle\""},
        {"{\"rotate\": []}", "[]", "empty array"},
        {"{\"rotate\": [{\"axis\": [0, 0, 1], \"angle\": 5, \"x\": 1}]}", "\"x\"", "unknown key \"x\""},
        {"{\"translate\": [1e30, 0, 0]}", "1e30", "too large"},
        {"{\"scale\": 1e-39}", "{\"scale\"", "not invertible in 32-bit floats"},
        {"{\"scale\": 1e-30}", "\"plain.obj\"", "degenerate"},
        {"{\"scale\": 1e30}", "\"plain.obj\"", "beyond the scene limit"},
        {"{\"scale\": [1, 1e-30, 1]}", "\"plain.obj\"", "degenerate"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        snprintf(text, sizeof text,
                 SCENE_HEAD "  {\"type\": \"meshfile\", \"material\": \"white\", \"file\": "
                            "\"plain.obj\", \"transform\": %s}\n ]}\n",
                 cases[i].transform);
        expect_scene_error(text, CST_ERR_INVALID_ARG, cases[i].needle, cases[i].what, NULL);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_transform_compose),
        cmocka_unit_test(test_transform_inverse_normals),
        cmocka_unit_test(test_obj_mtl),
        cmocka_unit_test(test_ply_ascii),
        cmocka_unit_test(test_ply_binary),
        cmocka_unit_test(test_gltf),
        cmocka_unit_test(test_import_errors),
        cmocka_unit_test(test_bunny_face_order),
        cmocka_unit_test(test_json_meshfile),
        cmocka_unit_test(test_json_meshfile_errors),
    };
    return cmocka_run_group_tests(tests, group_setup, group_teardown);
}
