/* libFuzzer target for the mesh import path (scene/mesh_import.c: our PLY pre-check, then
 * assimp, then the flattening into one triangle list): any bytes must give CST_OK with a
 * consistent mesh or an explained error, never a crash, an abort inside assimp, a hang or
 * a leak. Inputs starting "ply" are written to a .ply file, all others to .obj, so one
 * corpus drives both readers. Built by -DCST_FUZZ=ON (tests/fuzz/CMakeLists.txt); run
 * with scripts/fuzz.sh, see docs/fuzzing.md. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "fuzz_file.h"
#include "scene/mesh_import.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    bool ply = size >= 3 && (memcmp(data, "ply", 3) == 0 || memcmp(data, "PLY", 3) == 0);
    const char *path = fuzz_write_file(data, size, ply ? ".ply" : ".obj");
    ImportedMesh mesh;
    CstError err;
    err.msg[0] = '\0';
    CstStatus st = mesh_import(path, &mesh, &err);
    if (st != CST_OK) {
        if (err.msg[0] == '\0' || mesh.positions || mesh.indices) abort();
        return 0;
    }
    /* What mesh_import.h promises: triangles whose indices name vertices, and per-triangle
     * materials that name materials. */
    if (mesh.num_triangles <= 0 || mesh.num_vertices <= 0 || !mesh.positions || !mesh.indices)
        abort();
    for (int i = 0; i < 3 * mesh.num_triangles; i++)
        if (mesh.indices[i] < 0 || mesh.indices[i] >= mesh.num_vertices) abort();
    if (mesh.tri_material)
        for (int t = 0; t < mesh.num_triangles; t++)
            if (mesh.tri_material[t] < 0 || mesh.tri_material[t] >= mesh.num_materials) abort();
    mesh_import_free(&mesh);
    return 0;
}
