/* PLY meshes (binary little/big endian and ASCII, possibly gzip-compressed) read from memory
 * into triangle lists, the way pbrt-v4 reads them: positions, normals, texture coordinates
 * under any of pbrt-v4's names, triangles and quads (split in two), face_indices. */
#ifndef CST_IO_PLY_H
#define CST_IO_PLY_H

#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"
#include "math/vec3.h"

typedef struct PlyMesh {
    Vec3 *positions;      /* num_vertices, as stored (float) */
    Vec3 *normals;        /* per vertex (nx, ny, nz as stored, not normalised), or NULL */
    Vec2 *uvs;            /* per vertex (u,v / s,t / texture_u,texture_v / texture_s,
                           * texture_t, the first pair present, as pbrt-v4 picks), or NULL */
    int num_vertices;
    int32_t *indices;     /* 3 per triangle, into positions, in the file's face order */
    int32_t *face_indices; /* per triangle: the face's `face_indices` value, or NULL */
    int num_triangles;
    int num_quads;        /* faces of 4 vertices, each split into (v0,v1,v2), (v0,v2,v3) */
    int num_skipped_faces; /* faces of other vertex counts, skipped as pbrt-v4 skips them */
    int skipped_face_size; /* the vertex count of the first skipped face */
} PlyMesh;

/* Reads the PLY file held in data[0..len) (not NUL-terminated; gzip-compressed data is
 * inflated first, up to GZIP_MAX_OUTPUT_BYTES). `name` is used in messages only. Every
 * count, list length and index is checked against the data before anything is allocated
 * for it, so memory stays proportional to len. Errors (CST_ERR_PARSE) name the file and
 * the place: "NAME:LINE: ..." in the header and in ASCII data, "NAME: byte OFFSET
 * (element "face" number N): ..." in binary data. CST_ERR_UNSUPPORTED for more than
 * INT_MAX vertices or triangles. On success the caller frees *out with ply_free. */
CstStatus ply_read(const char *name, const void *data, size_t len, PlyMesh *out, CstError *err);

/* ply_read of a file, read through gzip_read_file (io/gzip.h). */
CstStatus ply_read_file(const char *path, PlyMesh *out, CstError *err);

/* True when the file is one ply_read should take: its name ends in ".ply" or ".ply.gz"
 * (any case), or data (its first len bytes, may be fewer than the file's) starts with
 * "ply" and a line end. */
int ply_is_ply(const char *path, const void *data, size_t len);

/* Frees the arrays; *mesh is empty again. NULL is fine. */
void ply_free(PlyMesh *mesh);

#endif
