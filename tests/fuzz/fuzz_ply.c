/* libFuzzer target for the PLY reader (io/ply.c) and gzip reading (io/gzip.c), from memory:
 * any bytes must give CST_OK with a consistent mesh or a located error, never a crash, a
 * hang, a leak or an allocation the input cannot justify (the 2 GB RSS limit of
 * scripts/fuzz.sh). Inputs starting with the gzip magic go through inflate; an input whose
 * first byte is 'Z' is gzip-compressed here first (the rest of it), so that mutations of
 * plain PLY text also reach the reader through a valid gzip stream. Built by -DCST_FUZZ=ON
 * (tests/fuzz/CMakeLists.txt); run with scripts/fuzz.sh, see docs/fuzzing.md. */
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <zlib.h>

#include "caustic/caustic.h"
#include "io/ply.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static unsigned char *gzip_copy(const uint8_t *data, size_t size, size_t *out_len)
{
    z_stream zs;
    memset(&zs, 0, sizeof zs);
    if (deflateInit2(&zs, 6, Z_DEFLATED, 16 + 15, 8, Z_DEFAULT_STRATEGY) != Z_OK) abort();
    size_t cap = deflateBound(&zs, (uLong)size) + 64;
    unsigned char *out = malloc(cap);
    if (!out) abort();
    zs.next_in = (Bytef *)(uintptr_t)data;
    zs.avail_in = (uInt)size;
    zs.next_out = out;
    zs.avail_out = (uInt)cap;
    if (deflate(&zs, Z_FINISH) != Z_STREAM_END) abort();
    *out_len = cap - zs.avail_out;
    deflateEnd(&zs);
    return out;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    unsigned char *gz = NULL;
    size_t gz_len = 0;
    if (size >= 1 && data[0] == 'Z') gz = gzip_copy(data + 1, size - 1, &gz_len);
    PlyMesh m;
    CstError err;
    err.msg[0] = '\0';
    CstStatus st = ply_read("fuzz.ply", gz ? gz : data, gz ? gz_len : size, &m, &err);
    free(gz);
    if (st != CST_OK) {
        if (err.msg[0] == '\0' || strncmp(err.msg, "fuzz.ply", 8) != 0 || m.positions || m.indices) abort();
        return 0;
    }
    /* What ply.h promises: indices name vertices; face_indices, normals and uvs sized. */
    if (m.num_vertices < 0 || m.num_triangles < 0 || (m.num_triangles && !m.indices)) abort();
    for (int i = 0; i < 3 * m.num_triangles; i++)
        if (m.indices[i] < 0 || m.indices[i] >= m.num_vertices) abort();
    volatile float sink = 0.0f;
    for (int i = 0; i < m.num_vertices; i++) {
        sink += m.positions[i].x;
        if (m.normals) sink += m.normals[i].z;
        if (m.uvs) sink += m.uvs[i].y;
    }
    if (m.face_indices)
        for (int t = 0; t < m.num_triangles; t++) sink += (float)m.face_indices[t];
    (void)sink;
    ply_free(&m);
    return 0;
}

#include "fuzz_replay.h"
