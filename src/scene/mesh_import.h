/* Mesh files in: PLY (binary and ASCII, gzip-compressed or not) through our own reader
 * (io/ply.h), OBJ (with MTL materials), glTF 2.0 and whatever else assimp reads through
 * assimp's C API. Triangles keep the file's face order (so a PLY
 * face's index is its triangle's index), vertices keep their positions bit for bit (where
 * the file's node transforms are the identity, as in PLY and OBJ). */
#ifndef CST_SCENE_MESH_IMPORT_H
#define CST_SCENE_MESH_IMPORT_H

#include <stdint.h>

#include "caustic/caustic.h"
#include "math/color.h"
#include "math/vec3.h"

/* A material as the file describes it, mapped to our closest one by the importer. */
typedef struct ImportedMaterial {
    char name[64];
    int type;    /* a MaterialType (materials/material.h) */
    Color albedo;
    float ior;
    int from_file; /* 0 for assimp's stand-ins: "DefaultMaterial" or a material without a
                      name (PLY has no materials; unnamed glTF materials look the same) */
} ImportedMaterial;

typedef struct ImportedMesh {
    Vec3 *positions;
    int num_vertices;
    int32_t *indices;      /* 3 per triangle, into positions */
    int num_triangles;
    Vec3 *normals;         /* per vertex, unit, through the node transforms; or NULL */
    Vec2 *uvs;             /* per vertex, channel 0 (v up: assimp flips glTF's), or NULL */
    int32_t *tri_material; /* per triangle: index into materials, or NULL */
    ImportedMaterial *materials;
    int num_materials;
    /* Meshes of the file without normals (UVs) got zero fills next to others with them. */
    int normals_partial, uvs_partial;
    int num_skipped_primitives; /* point and line faces, not imported; for a PLY, faces of
                                   other than 3 or 4 vertices (skipped as pbrt-v4 does) */
    int from_ply;               /* read by io/ply.c */
    int skipped_face_size;      /* PLY: the vertex count of the first such face */
    int num_quads;              /* PLY: faces of 4 vertices, each split into two triangles */
    char warning[512]; /* "": none; else what the loader should pass on (an OBJ's missing
                        * .mtl: CST_WARN_MISSING_FILE) */
} ImportedMesh;

/* Reads every mesh of the file into one triangle list. Errors name the file (and, where
 * assimp reports it, the line). The caller frees *out with mesh_import_free. */
CstStatus mesh_import(const char *path, ImportedMesh *out, CstError *err);
void mesh_import_free(ImportedMesh *mesh);

#endif
