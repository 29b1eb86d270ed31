/* Unit tests for the PLY reader (io/ply.c) and gzip reading (io/gzip.c), on files built in
 * memory: the three encodings giving the same mesh, quads, pbrt-v4's texture-coordinate
 * names, skipped elements and properties, and every kind of lying or truncated file, each
 * a located CST_ERR_PARSE; corrupt, truncated and oversized gzip streams. */
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <setjmp.h>
#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "caustic/caustic.h"
#include "io/gzip.h"
#include "io/ply.h"

/* ------------------------------------------------------------------ building files */

typedef struct Buf {
    unsigned char d[8192];
    size_t n;
} Buf;

static void put(Buf *b, const void *p, size_t n)
{
    assert_true(b->n + n <= sizeof b->d);
    memcpy(b->d + b->n, p, n);
    b->n += n;
}

static void puts_(Buf *b, const char *s) { put(b, s, strlen(s)); }

static void putf(Buf *b, const char *fmt, ...)
{
    char tmp[1024];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(tmp, sizeof tmp, fmt, ap);
    va_end(ap);
    puts_(b, tmp);
}

/* One value of `bytes` bytes from its little-endian image, in the file's byte order. */
static void put_bin(Buf *b, const void *le, int bytes, int big)
{
    unsigned char t[8];
    for (int i = 0; i < bytes; i++) t[i] = ((const unsigned char *)le)[big ? bytes - 1 - i : i];
    put(b, t, (size_t)bytes);
}

static void put_f32(Buf *b, float v, int big) { put_bin(b, &v, 4, big); }
static void put_i32(Buf *b, int32_t v, int big) { put_bin(b, &v, 4, big); }
static void put_u8(Buf *b, uint8_t v) { put(b, &v, 1); }

/* The reference mesh: 4 vertices with normals and uvs, a triangle and a quad. */
static const float P[4][3] = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0.5f}};
static const float N[4][3] = {{0, 0, 1}, {0, 0, 2}, {0, 0, 1}, {0, 0, 1}};
static const float UV[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 0.25f}};

enum { ASCII, LE, BE };

static void reference_ply(Buf *b, int enc, const char *uname, const char *vname)
{
    static const char *const fmt[] = {"ascii", "binary_little_endian", "binary_big_endian"};
    putf(b, "ply\nformat %s 1.0\ncomment made by test_ply\nelement vertex 4\n", fmt[enc]);
    puts_(b, "property float x\nproperty float y\nproperty float z\n"
             "property float nx\nproperty float ny\nproperty float nz\n");
    putf(b, "property float %s\nproperty float %s\n", uname, vname);
    puts_(b, "element face 2\nproperty list uchar int vertex_indices\nend_header\n");
    for (int i = 0; i < 4; i++) {
        float v[8] = {P[i][0], P[i][1], P[i][2], N[i][0], N[i][1], N[i][2], UV[i][0], UV[i][1]};
        for (int k = 0; k < 8; k++) {
            if (enc == ASCII) putf(b, "%g%s", (double)v[k], k == 7 ? "\n" : " ");
            else put_f32(b, v[k], enc == BE);
        }
    }
    if (enc == ASCII) {
        puts_(b, "3 0 1 3\n4 0 1 2 3\n");
    } else {
        int32_t f0[3] = {0, 1, 3}, f1[4] = {0, 1, 2, 3};
        put_u8(b, 3);
        for (int k = 0; k < 3; k++) put_i32(b, f0[k], enc == BE);
        put_u8(b, 4);
        for (int k = 0; k < 4; k++) put_i32(b, f1[k], enc == BE);
    }
}

static PlyMesh read_ok(const Buf *b)
{
    PlyMesh m;
    CstError err = {0};
    CstStatus st = ply_read("mem.ply", b->d, b->n, &m, &err);
    if (st != CST_OK) fail_msg("%s: %s", cst_status_name(st), err.msg);
    return m;
}

static void expect_fail(const Buf *b, CstStatus want, const char *what)
{
    PlyMesh m;
    memset(&m, 0xAB, sizeof m);
    CstError err = {0};
    CstStatus st = ply_read("lie.ply", b->d, b->n, &m, &err);
    if (st != want)
        fail_msg("status %s, expected %s (%s); message: %s", cst_status_name(st),
                 cst_status_name(want), what, err.msg);
    assert_null(m.positions);
    assert_null(m.indices);
    if (strncmp(err.msg, "lie.ply", 7) != 0) fail_msg("message \"%s\" does not name the file", err.msg);
    if (!strstr(err.msg, what)) fail_msg("message \"%s\" lacks \"%s\"", err.msg, what);
}

/* ------------------------------------------------------------------ tests */

/* ASCII, little and big endian: the same mesh bit for bit; the quad split as pbrt-v4
 * splits it: (v0, v1, v2), (v0, v2, v3). */
static void test_encodings(void **state)
{
    (void)state;
    for (int enc = ASCII; enc <= BE; enc++) {
        Buf b = {0};
        reference_ply(&b, enc, "u", "v");
        PlyMesh m = read_ok(&b);
        assert_int_equal(m.num_vertices, 4);
        assert_int_equal(m.num_triangles, 3);
        assert_int_equal(m.num_quads, 1);
        assert_int_equal(m.num_skipped_faces, 0);
        assert_non_null(m.normals);
        assert_non_null(m.uvs);
        for (int i = 0; i < 4; i++) {
            assert_true(m.positions[i].x == P[i][0] && m.positions[i].y == P[i][1] && m.positions[i].z == P[i][2]);
            assert_true(m.normals[i].x == N[i][0] && m.normals[i].y == N[i][1] && m.normals[i].z == N[i][2]);
            assert_true(m.uvs[i].x == UV[i][0] && m.uvs[i].y == UV[i][1]);
        }
        const int32_t want[9] = {0, 1, 3, 0, 1, 2, 0, 2, 3};
        for (int k = 0; k < 9; k++) assert_int_equal(m.indices[k], want[k]);
        assert_null(m.face_indices);
        ply_free(&m);
    }
}

/* Every name pair pbrt-v4 accepts for texture coordinates, and its order of preference. */
static void test_uv_names(void **state)
{
    (void)state;
    static const char *const pairs[4][2] = {{"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"},
                                            {"texture_s", "texture_t"}};
    for (int k = 0; k < 4; k++) {
        Buf b = {0};
        reference_ply(&b, LE, pairs[k][0], pairs[k][1]);
        PlyMesh m = read_ok(&b);
        assert_non_null(m.uvs);
        assert_true(m.uvs[3].x == 0.0f && m.uvs[3].y == 0.25f);
        ply_free(&m);
    }
    /* a lone "u" (no "v") is no texture coordinate; "s","t" after "u","v": u,v win */
    Buf b = {0};
    puts_(&b, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty float s\nproperty float t\nproperty float u\n"
              "property float v\nelement face 1\nproperty list uchar uint vertex_index\nend_header\n"
              "0 0 0 9 9 1 2\n1 0 0 9 9 3 4\n0 1 0 9 9 5 6\n3 0 1 2\n");
    PlyMesh m = read_ok(&b);
    assert_true(m.uvs[0].x == 1.0f && m.uvs[0].y == 2.0f);
    assert_int_equal(m.num_triangles, 1); /* "vertex_index" as well as "vertex_indices" */
    ply_free(&m);
    Buf c = {0};
    puts_(&c, "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\n"
              "property float z\nproperty float u\nelement face 1\n"
              "property list uchar int vertex_indices\nend_header\n0 0 0 1\n1 0 0 1\n0 1 0 1\n3 0 1 2\n");
    m = read_ok(&c);
    assert_null(m.uvs);
    assert_null(m.normals);
    ply_free(&m);
}

/* assimp 5.2.5 skipped a first data byte 0x0A as white space and misread the whole file
 * (9 scenes of issue 26). x = 0x3F80000A as little-endian bytes 0A 00 80 3F. */
static void test_first_data_byte_newline(void **state)
{
    (void)state;
    for (int big = 0; big < 2; big++) {
        Buf b = {0};
        putf(&b, "ply\r\nformat %s 1.0\r\nelement vertex 3\r\nproperty float x\r\nproperty float y\r\n"
                 "property float z\r\nelement face 1\r\nproperty list uchar int vertex_indices\r\n"
                 "end_header\r\n", big ? "binary_big_endian" : "binary_little_endian");
        uint32_t bits = big ? 0x0A0A0A0Au : 0x3F80000Au;
        float x0;
        memcpy(&x0, &bits, 4);
        float v[9] = {x0, 0, 0, 1, 0, 0, 0, 1, 0};
        for (int k = 0; k < 9; k++) put_f32(&b, v[k], big);
        assert_int_equal(b.d[b.n - 36], 0x0A);
        put_u8(&b, 3);
        for (int k = 0; k < 3; k++) put_i32(&b, k, big);
        PlyMesh m = read_ok(&b);
        assert_true(m.positions[0].x == x0 && m.positions[1].x == 1.0f && m.positions[2].y == 1.0f);
        assert_int_equal(m.indices[2], 2);
        ply_free(&m);
    }
}

/* Other elements and properties, lists among them, skipped by their declared types; every
 * scalar type read; face_indices kept per triangle; faces of other sizes skipped. */
static void test_skipping_and_types(void **state)
{
    (void)state;
    for (int big = 0; big < 2; big++) {
        Buf b = {0};
        putf(&b, "ply\nformat %s 1.0\nobj_info anything\nelement material 2\nproperty list ushort double k\n"
                 "property char c\nelement vertex 3\nproperty double x\nproperty short y\nproperty uint8 z\n"
                 "property list int uchar junk\nproperty ushort w\nelement face 3\n"
                 "property int16 flags\nproperty list uint16 uint vertex_indices\nproperty int face_indices\n"
                 "element edge 1\nproperty int a\nend_header\n", big ? "binary_big_endian" : "binary_little_endian");
        /* materials: 2 doubles, then 0 doubles */
        uint16_t two = 2, zero = 0;
        double d = 7.0;
        put_bin(&b, &two, 2, big);
        put_bin(&b, &d, 8, big);
        put_bin(&b, &d, 8, big);
        put_u8(&b, 1);
        put_bin(&b, &zero, 2, big);
        put_u8(&b, 2);
        for (int i = 0; i < 3; i++) {
            double x = i == 1 ? -1.5 : 0.0;
            int16_t y = i == 2 ? -3 : 0;
            int32_t nj = i;
            uint16_t w = 65535;
            put_bin(&b, &x, 8, big);
            put_bin(&b, &y, 2, big);
            put_u8(&b, 200);
            put_bin(&b, &nj, 4, big);
            for (int j = 0; j < i; j++) put_u8(&b, 0xFF);
            put_bin(&b, &w, 2, big);
        }
        uint16_t n3 = 3, n5 = 5;
        int16_t fl = -1;
        for (int f = 0; f < 3; f++) {
            put_bin(&b, &fl, 2, big);
            put_bin(&b, f == 1 ? &n5 : &n3, 2, big);
            for (int k = 0; k < (f == 1 ? 5 : 3); k++) {
                uint32_t ix = (uint32_t)k % 3;
                put_bin(&b, &ix, 4, big);
            }
            int32_t fi = 10 + f;
            put_bin(&b, &fi, 4, big);
        }
        int32_t a = 0;
        put_bin(&b, &a, 4, big);
        PlyMesh m = read_ok(&b);
        assert_int_equal(m.num_vertices, 3);
        assert_true(m.positions[1].x == -1.5f && m.positions[2].y == -3.0f && m.positions[0].z == 200.0f);
        assert_int_equal(m.num_triangles, 2);
        assert_int_equal(m.num_skipped_faces, 1);
        assert_int_equal(m.skipped_face_size, 5);
        assert_non_null(m.face_indices);
        assert_int_equal(m.face_indices[0], 10);
        assert_int_equal(m.face_indices[1], 12);
        ply_free(&m);
    }
}

/* Lying and truncated files: each a located parse error, none allocating what the file
 * cannot hold. */
static void test_lying_files(void **state)
{
    (void)state;
    static const char *const HDR =
        "ply\nformat %s 1.0\nelement vertex %s\nproperty float x\nproperty float y\n"
        "property float z\nelement face %s\nproperty list %s int vertex_indices\nend_header\n";
    Buf b;
    /* header garbage, located by line */
    static const struct { const char *text, *what; } headers[] = {
        {"plx\n", "lie.ply:1: malformed PLY header: expected \"ply\""},
        {"ply\nformat ascii 2.0\n", "lie.ply:2: malformed PLY header: expected \"format ascii"},
        {"ply\nformat ebcdic 1.0\n", "lie.ply:2:"},
        {"ply\nformat ascii 1.0\nproperty float x\n", "lie.ply:3: malformed PLY header: a property before any element"},
        {"ply\nformat ascii 1.0\nelement vertex -3\n", "lie.ply:3: malformed PLY header: element count \"-3\""},
        {"ply\nformat ascii 1.0\nelement vertex 99999999999999999999999\n", "lie.ply:3:"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float128 x\n", "lie.ply:4: malformed PLY header: unknown property type"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty list float int x\n", "lie.ply:4: malformed PLY header: list length type"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float x\n", "lie.ply:5: malformed PLY header: property \"x\" declared twice"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nelement vertex 1\n", "lie.ply:4: malformed PLY header: element \"vertex\" declared twice"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\n", "no end_header line"},
        {"ply\nformat ascii 1.0\nbogus line\nend_header\n", "lie.ply:3: malformed PLY header: unknown line"},
        {"ply\nformat ascii 1.0\nend_header\n", "has no \"vertex\" element"},
        {"ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\nend_header\n0 0\n", "no scalar property \"z\""},
        {"ply\nformat ascii 1.0\nelement vertex 0\nproperty float x\nproperty float y\nproperty float z\n"
         "element face 0\nproperty int vertex_indices\nend_header\n", "no list property \"vertex_indices\""},
    };
    for (size_t i = 0; i < sizeof headers / sizeof headers[0]; i++) {
        memset(&b, 0, sizeof b);
        puts_(&b, headers[i].text);
        expect_fail(&b, CST_ERR_PARSE, headers[i].what);
    }
    memset(&b, 0, sizeof b); /* a NUL byte in the header */
    put(&b, "ply\nformat ascii 1.0\ncom\0ment\nend_header\n", 39);
    expect_fail(&b, CST_ERR_PARSE, "lie.ply:3: malformed PLY header: a NUL byte");

    /* counts larger than the data: refused before anything is allocated for them */
    memset(&b, 0, sizeof b);
    putf(&b, HDR, "binary_little_endian", "1000000", "0", "uchar");
    expect_fail(&b, CST_ERR_PARSE, "byte 175: malformed PLY data: element \"vertex\" declares 1000000 records of at least 12 bytes");
    memset(&b, 0, sizeof b);
    putf(&b, HDR, "binary_little_endian", "3000000000", "0", "uchar");
    expect_fail(&b, CST_ERR_UNSUPPORTED, "3000000000 vertices are too many");
    memset(&b, 0, sizeof b);
    putf(&b, HDR, "ascii", "3", "2000000", "uchar");
    puts_(&b, "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
    expect_fail(&b, CST_ERR_PARSE, "element \"face\" declares 2000000 records");

    /* binary faces: index out of range, negative, list lengths huge or negative, cut short */
    for (int c = 0; c < 5; c++) {
        memset(&b, 0, sizeof b);
        putf(&b, HDR, "binary_little_endian", "3", "2", c == 3 ? "int" : "uint");
        for (int k = 0; k < 9; k++) put_f32(&b, k == 3 || k == 7 ? 1.0f : 0.0f, 0);
        for (int f = 0; f < 2; f++) {
            int32_t cnt = 3;
            if (f == 1 && c == 2) cnt = (int32_t)0xFFFFFFF0; /* as uint: 4294967280 */
            if (f == 1 && c == 3) cnt = -1;
            put_i32(&b, cnt, 0);
            for (int k = 0; k < 3; k++) {
                int32_t ix = k;
                if (f == 1 && k == 2 && c == 0) ix = 7;
                if (f == 1 && k == 1 && c == 1) ix = -2;
                put_i32(&b, ix, 0);
            }
        }
        if (c == 4) b.n -= 5;
        static const char *const what[] = {
            "malformed PLY data: face 2 of 2 (starting at byte 220): vertex index 7 (number 2 of the face) is out of range; expected 0 to 2",
            "vertex index -2 (number 1 of the face) is out of range",
            "list \"vertex_indices\" of length 4294967280, but 12 bytes are left",
            "list \"vertex_indices\" of length -1",
            "face 2 of 2 (starting at byte 220): list \"vertex_indices\" of length 3, but 7 bytes are left"};
        expect_fail(&b, CST_ERR_PARSE, what[c]);
    }
    /* the same in ASCII, located by line */
    static const struct { const char *body, *what; } ascii[] = {
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1 3\n", "lie.ply:14: malformed PLY data: face 2 of 2: vertex index 3"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 -1 2\n", "lie.ply:14: malformed PLY data: face 2 of 2: vertex index -1"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n300 0 1 2\n", "lie.ply:14: malformed PLY data: face 2 of 2: \"300\"; expected an integer in [0, 255]"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 0 1\n", "face 2 of 2: the file ends inside the record"},
        {"0 0 0\n1 0 0\n0 one 0\n3 0 1 2\n3 0 1 2\n", "lie.ply:12: malformed PLY data: vertex 3 of 3: \"one\"; expected a number"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1.5 2\n3 0 1 2\n", "lie.ply:13: malformed PLY data: face 1 of 2: \"1.5\"; expected an integer"},
        {"0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n", "lie.ply:14: malformed PLY data: face 2 of 2: the file ends inside the record"},
    };
    for (size_t i = 0; i < sizeof ascii / sizeof ascii[0]; i++) {
        memset(&b, 0, sizeof b);
        putf(&b, HDR, "ascii", "3", "2", "uchar");
        puts_(&b, ascii[i].body);
        expect_fail(&b, CST_ERR_PARSE, ascii[i].what);
    }
}

/* A gzip stream of data, written with zlib (gzip header: windowBits 16 + 15). */
static size_t gzip_of(const void *data, size_t n, unsigned char *out, size_t cap)
{
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    assert_int_equal(deflateInit2(&zs, 9, Z_DEFLATED, 16 + 15, 8, Z_DEFAULT_STRATEGY), Z_OK);
    zs.next_in = (Bytef *)(uintptr_t)data;
    zs.avail_in = (uInt)n;
    zs.next_out = out;
    zs.avail_out = (uInt)cap;
    assert_int_equal(deflate(&zs, Z_FINISH), Z_STREAM_END);
    size_t len = cap - zs.avail_out;
    deflateEnd(&zs);
    return len;
}

static void test_gzip(void **state)
{
    (void)state;
    Buf plain = {0};
    reference_ply(&plain, BE, "s", "t");
    static unsigned char gz[16384];
    size_t n = gzip_of(plain.d, plain.n, gz, sizeof gz);
    /* ply_read inflates gzip data (the magic), ply_is_ply knows the names */
    PlyMesh m;
    CstError err = {0};
    assert_int_equal(ply_read("mesh.ply.gz", gz, n, &m, &err), CST_OK);
    assert_int_equal(m.num_triangles, 3);
    assert_true(m.uvs[3].y == 0.25f);
    ply_free(&m);
    assert_true(ply_is_ply("a/b.PLY.gz", NULL, 0) && ply_is_ply("x.ply", NULL, 0));
    assert_true(ply_is_ply("noext", "ply\r\n", 5) && !ply_is_ply("noext", "plyply", 6));
    assert_true(gzip_is_compressed("a.pbrt.gz", "", 0) && gzip_is_compressed(NULL, gz, 2));

    char *out = NULL;
    size_t out_len = 0;
    /* two members, as gzip(1) concatenates them, plus zero padding */
    static unsigned char two[32768];
    memcpy(two, gz, n);
    memcpy(two + n, gz, n);
    memset(two + 2 * n, 0, 8);
    assert_int_equal(gzip_inflate("two.gz", two, 2 * n + 8, GZIP_MAX_OUTPUT_BYTES, &out, &out_len, &err), CST_OK);
    assert_int_equal(out_len, 2 * plain.n);
    assert_memory_equal(out, plain.d, plain.n);
    assert_memory_equal(out + plain.n, plain.d, plain.n);
    assert_int_equal(out[out_len], '\0');
    free(out);
    /* the limit: exactly the size passes, one byte less fails */
    assert_int_equal(gzip_inflate("lim.gz", gz, n, plain.n, &out, &out_len, &err), CST_OK);
    free(out);
    assert_int_equal(gzip_inflate("lim.gz", gz, n, plain.n - 1, &out, &out_len, &err), CST_ERR_UNSUPPORTED);
    assert_null(out);
    assert_non_null(strstr(err.msg, "lim.gz: the gzip data decompresses to more than"));
    /* a bomb: 64 MiB of zeros in ~64 KiB, against a 1 MiB limit; fails without taking 64 MiB */
    size_t big = (size_t)64 << 20;
    unsigned char *zeros = calloc(1, big);
    static unsigned char bomb[131072];
    assert_non_null(zeros);
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    assert_int_equal(deflateInit2(&zs, 9, Z_DEFLATED, 16 + 15, 8, Z_DEFAULT_STRATEGY), Z_OK);
    zs.next_in = zeros;
    zs.avail_in = (uInt)big;
    zs.next_out = bomb;
    zs.avail_out = sizeof bomb;
    assert_int_equal(deflate(&zs, Z_FINISH), Z_STREAM_END);
    size_t bomb_n = sizeof bomb - zs.avail_out;
    deflateEnd(&zs);
    free(zeros);
    assert_int_equal(gzip_inflate("bomb.gz", bomb, bomb_n, (uint64_t)1 << 20, &out, &out_len, &err),
                     CST_ERR_UNSUPPORTED);
    /* corrupt, truncated, trailing garbage, not gzip at all */
    static unsigned char bad[16384];
    memcpy(bad, gz, n);
    bad[n / 2] ^= 0x55;
    bad[n / 2 + 1] ^= 0xAA;
    CstStatus st = gzip_inflate("bad.gz", bad, n, GZIP_MAX_OUTPUT_BYTES, &out, &out_len, &err);
    assert_int_equal(st, CST_ERR_PARSE);
    if (!strstr(err.msg, "bad.gz: corrupt gzip data at compressed byte")) fail_msg("%s", err.msg);
    assert_int_equal(ply_read("bad.ply.gz", bad, n, &m, &err), CST_ERR_PARSE);
    assert_null(m.positions);
    assert_int_equal(gzip_inflate("cut.gz", gz, n - 9, GZIP_MAX_OUTPUT_BYTES, &out, &out_len, &err), CST_ERR_PARSE);
    if (!strstr(err.msg, "cut.gz: the gzip data ends early")) fail_msg("%s", err.msg);
    memcpy(bad, gz, n);
    memcpy(bad + n, "junk", 4);
    assert_int_equal(gzip_inflate("tail.gz", bad, n + 4, GZIP_MAX_OUTPUT_BYTES, &out, &out_len, &err), CST_ERR_PARSE);
    if (!strstr(err.msg, "tail.gz: 4 bytes of garbage after the gzip data")) fail_msg("%s", err.msg);
    assert_int_equal(gzip_inflate("no.gz", (const unsigned char *)"ply\n", 4, 100, &out, &out_len, &err), CST_ERR_PARSE);
    if (!strstr(err.msg, "no.gz: not gzip data")) fail_msg("%s", err.msg);
    /* a gzip header whose CRC does not match the data */
    memcpy(bad, gz, n);
    bad[n - 8] ^= 1;
    assert_int_equal(gzip_inflate("crc.gz", bad, n, GZIP_MAX_OUTPUT_BYTES, &out, &out_len, &err), CST_ERR_PARSE);
    if (!strstr(err.msg, "crc.gz: corrupt gzip data")) fail_msg("%s", err.msg);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_encodings),
        cmocka_unit_test(test_uv_names),
        cmocka_unit_test(test_first_data_byte_newline),
        cmocka_unit_test(test_skipping_and_types),
        cmocka_unit_test(test_lying_files),
        cmocka_unit_test(test_gzip),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
