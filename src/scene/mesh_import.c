/* Mesh files in through assimp's C API (the only file that includes assimp): the node
 * hierarchy flattened into one triangle list in world space, with per-vertex normals and
 * UVs, and the file's materials mapped onto ours. PLY files go to our own reader (io/ply.c). */
#include "scene/mesh_import.h"

#include <assimp/ObjMaterial.h>
#include <assimp/cfileio.h>
#include <assimp/cimport.h>
#include <assimp/material.h>
#include <assimp/postprocess.h>
#include <assimp/scene.h>
#include <errno.h>
#include <jansson.h>
#include <limits.h>
#include <pthread.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>

#include "core/error.h"
#include "io/path.h"
#include "core/file.h"
#include "io/gzip.h"
#include "io/ply.h"
#include "materials/material.h"
#include "math/transform.h"

/* Triangulate: polygons become fans/ear-clipped triangles in place of the polygon, so face
 * order is kept. SortByPType: points and lines go to meshes of their own, which we skip.
 * ValidateDataStructure: out-of-range indices and the like fail the import instead of
 * reaching us (it costs ~0.02 s on the 1.3M-triangle bumpysphere). Deliberately NOT
 * JoinIdenticalVertices (it would re-index and drop vertices) nor anything that reorders
 * faces (OptimizeMeshes, FindDegenerates, ImproveCacheLocality). */
#define MESH_IMPORT_FLAGS \
    (aiProcess_Triangulate | aiProcess_SortByPType | aiProcess_ValidateDataStructure)

/* assimp keeps its last error in one global string (aiGetErrorString), so an import and the
 * read of its error must not interleave with another thread's import. */
static pthread_mutex_t import_lock = PTHREAD_MUTEX_INITIALIZER;

/* ------------------------------------------------------------------ materials */

static float clamp01(float v) { return isfinite(v) ? clampf(v, 0.0f, 1.0f) : 0.0f; }

static int get_color(const struct aiMaterial *mat, const char *key, unsigned type,
                     unsigned index, Color *out)
{
    struct aiColor4D c;
    if (aiGetMaterialColor(mat, key, type, index, &c) != AI_SUCCESS) return 0;
    *out = color_rgb(clamp01(c.r), clamp01(c.g), clamp01(c.b));
    return 1;
}

static int get_float(const struct aiMaterial *mat, const char *key, unsigned type,
                     unsigned index, float *out)
{
    ai_real v = 0;
    unsigned n = 1;
    if (aiGetMaterialFloatArray(mat, key, type, index, &v, &n) != AI_SUCCESS || n < 1 ||
        !isfinite(v))
        return 0;
    *out = (float)v;
    return 1;
}

/* The mapping onto our three materials (also in docs/scene-format.md). assimp presents
 * OBJ/MTL and glTF 2.0 materials through the same keys:
 *
 *   glass   if MTL illum is 4, 6, 7 or 9 (the "transparency/refraction" models), or an MTL
 *           material has dissolve d < 1, or glTF KHR_materials_transmission factor >= 0.5.
 *           albedo = MTL Tf (transmission filter) when present and not black, else Kd /
 *           base colour; ior = Ni when present and not 1 (MTL writers put Ni 1 for
 *           "unset"), else 1.5.
 *   mirror  if MTL illum is 3, 5 or 8 (the "reflection" models), or a glTF material has
 *           metallicFactor >= 0.99 and roughnessFactor <= 0.01. albedo = MTL Ks when
 *           present and not black, else white; glTF: the base colour.
 *   diffuse otherwise, albedo = Kd / base colour (assimp fills in 0.6 grey for an MTL
 *           material without Kd), 0.5 grey if none.
 * Every albedo channel is clamped to [0, 1]. glTF's dissolve (base colour alpha) is an
 * alpha cutout, not transparency, so the d < 1 rule applies to MTL only; MTL is told apart
 * by assimp's "$mat.illum" key, which only the OBJ importer sets. */
static void map_material(const struct aiMaterial *mat, ImportedMaterial *out)
{
    memset(out, 0, sizeof *out);
    struct aiString name;
    if (aiGetMaterialString(mat, AI_MATKEY_NAME, &name) == AI_SUCCESS && name.length > 0) {
        size_t len = strnlen(name.data, sizeof out->name - 1); /* truncated to fit */
        memcpy(out->name, name.data, len);
        out->name[len] = '\0';
        /* assimp's stand-in for files (or faces) that name no material. PLY and unnamed
         * glTF materials have no name at all and count as not from the file too. */
        out->from_file = strcmp(name.data, AI_DEFAULT_MATERIAL_NAME) != 0;
    }
    Color kd = color_s(0.5f), ks = color_s(0.0f), tf = color_s(0.0f);
    int has_kd = get_color(mat, AI_MATKEY_COLOR_DIFFUSE, &kd);
    if (!has_kd) has_kd = get_color(mat, AI_MATKEY_BASE_COLOR, &kd);
    int has_ks = get_color(mat, AI_MATKEY_COLOR_SPECULAR, &ks);
    int has_tf = get_color(mat, AI_MATKEY_COLOR_TRANSPARENT, &tf);
    int illum = -1;
    unsigned n = 1;
    int is_mtl = aiGetMaterialIntegerArray(mat, AI_MATKEY_OBJ_ILLUM, &illum, &n) == AI_SUCCESS;
    float opacity = 1.0f, ni = 1.0f, transmission = 0.0f, metallic = 0.0f, roughness = 1.0f;
    get_float(mat, AI_MATKEY_OPACITY, &opacity);
    get_float(mat, AI_MATKEY_REFRACTI, &ni);
    get_float(mat, AI_MATKEY_TRANSMISSION_FACTOR, &transmission);
    int has_metallic = get_float(mat, AI_MATKEY_METALLIC_FACTOR, &metallic);
    get_float(mat, AI_MATKEY_ROUGHNESS_FACTOR, &roughness);

    int glass = (is_mtl && (illum == 4 || illum == 6 || illum == 7 || illum == 9 || opacity < 1.0f)) ||
                transmission >= 0.5f;
    int mirror = (is_mtl && (illum == 3 || illum == 5 || illum == 8)) ||
                 (has_metallic && metallic >= 0.99f && roughness <= 0.01f);
    out->ior = 1.0f;
    if (glass) {
        out->type = MATERIAL_GLASS;
        out->albedo = has_tf && !color_is_black(tf) ? tf : (is_mtl ? color_s(1.0f) : kd);
        out->ior = ni > 0.0f && ni != 1.0f ? ni : 1.5f;
    } else if (mirror) {
        out->type = MATERIAL_MIRROR;
        out->albedo = is_mtl ? (has_ks && !color_is_black(ks) ? ks : color_s(1.0f)) : kd;
    } else {
        out->type = MATERIAL_DIFFUSE;
        out->albedo = kd;
    }
}

/* ------------------------------------------------------------------ geometry */

typedef struct Flatten {
    const struct aiScene *scene;
    ImportedMesh *out;
    /* pass 1 counts, pass 2 fills */
    int fill;
    long long vertices, triangles, skipped;
    int any_normals, any_uvs, partial_normals, partial_uvs;
    int bad_index;
} Flatten;

static Transform from_ai(const struct aiMatrix4x4 *a)
{
    const float rows[16] = {a->a1, a->a2, a->a3, a->a4, a->b1, a->b2, a->b3, a->b4,
                            a->c1, a->c2, a->c3, a->c4, a->d1, a->d2, a->d3, a->d4};
    return transform_from_rows(rows);
}

static long long count_triangles(const struct aiMesh *m)
{
    long long n = 0;
    for (unsigned f = 0; f < m->mNumFaces; f++) n += m->mFaces[f].mNumIndices == 3;
    return n;
}

/* One mesh instance under the accumulated transform `to_world`. */
static void flatten_mesh(Flatten *fl, const struct aiMesh *m, const Transform *to_world)
{
    long long tris = count_triangles(m);
    if (!fl->fill) {
        fl->skipped += (long long)m->mNumFaces - tris;
        if (tris == 0) return;
        fl->any_normals |= m->mNormals != NULL;
        fl->any_uvs |= m->mTextureCoords[0] != NULL;
        fl->partial_normals |= m->mNormals == NULL;
        fl->partial_uvs |= m->mTextureCoords[0] == NULL;
        fl->vertices += m->mNumVertices;
        fl->triangles += tris;
        return;
    }
    if (tris == 0) return;
    ImportedMesh *out = fl->out;
    int base = (int)fl->vertices, nv = (int)m->mNumVertices;
    int identity = transform_is_identity(to_world);
    Transform nmat = transform_identity();
    if (!transform_normal_matrix(to_world, &nmat)) nmat = transform_identity(); /* flat: any */
    /* A mirroring transform reverses the winding, which defines our geometric normal (and
     * so the outside of glass and the lit side of emitters): swap two corners back, as
     * glTF prescribes for nodes with a negative determinant. */
    int swap = transform_det(to_world) < 0.0;
    for (int i = 0; i < nv; i++) {
        Vec3 p = v3(m->mVertices[i].x, m->mVertices[i].y, m->mVertices[i].z);
        out->positions[base + i] = identity ? p : transform_point(to_world, p);
    }
    if (out->normals)
        for (int i = 0; i < nv; i++)
            out->normals[base + i] = m->mNormals
                ? transform_normal(&nmat, v3(m->mNormals[i].x, m->mNormals[i].y, m->mNormals[i].z))
                : v3s(0.0f);
    if (out->uvs)
        for (int i = 0; i < nv; i++)
            out->uvs[base + i] = m->mTextureCoords[0]
                ? v2(m->mTextureCoords[0][i].x, m->mTextureCoords[0][i].y)
                : v2(0.0f, 0.0f);
    int t = (int)fl->triangles;
    for (unsigned f = 0; f < m->mNumFaces; f++) {
        const struct aiFace *face = &m->mFaces[f];
        if (face->mNumIndices != 3) continue;
        for (int k = 0; k < 3; k++) {
            unsigned ix = face->mIndices[swap && k ? 3 - k : k];
            if (ix >= m->mNumVertices) {
                fl->bad_index = 1;
                ix = 0;
            }
            out->indices[3 * t + k] = base + (int)ix;
        }
        out->tri_material[t] = (int32_t)m->mMaterialIndex;
        t++;
    }
    fl->vertices += nv;
    fl->triangles = t;
}

/* Depth-first, parent before children, a node's meshes in its order: the file's order
 * for single-node formats (PLY) and for OBJ, whose importer starts a new mesh at each
 * group or material change. */
static void flatten_node(Flatten *fl, const struct aiNode *node, const Transform *parent)
{
    Transform to_world = transform_compose(*parent, from_ai(&node->mTransformation));
    for (unsigned i = 0; i < node->mNumMeshes; i++)
        if (node->mMeshes[i] < fl->scene->mNumMeshes)
            flatten_mesh(fl, fl->scene->mMeshes[node->mMeshes[i]], &to_world);
    for (unsigned i = 0; i < node->mNumChildren; i++) flatten_node(fl, node->mChildren[i], &to_world);
}

/* ------------------------------------------------------------------ PLY: our reader */
/* Every PLY goes to io/ply.c, never to assimp: assimp 5.2.5 misread binary PLYs whose first
 * data byte is 0x0A (it skipped it as white space before the data), aborted on one, and
 * looped or read out of bounds on malformed headers (docs/fuzzing.md). A file is a PLY here
 * when its name ends in .ply or .ply.gz, when its first three bytes spell "ply" in any case
 * (assimp's own test, so no malformed PLY reaches assimp under another name), or when it is
 * gzip data (no other mesh format is read compressed). */
static CstStatus mesh_is_ply(const char *path, int *is_ply, CstError *err)
{
    *is_ply = ply_is_ply(path, NULL, 0);
    if (*is_ply) return CST_OK;
    FILE *f = NULL;
    CstStatus st = file_open_input(path, &f, NULL, err); /* regular files only, bounded */
    if (st != CST_OK) return st;
    char magic[3] = {0};
    size_t got = fread(magic, 1, 3, f);
    fclose(f);
    *is_ply = (got == 3 && strncasecmp(magic, "ply", 3) == 0) || gzip_is_compressed(path, magic, got);
    return CST_OK;
}

/* A PlyMesh as an ImportedMesh: the arrays are moved, normals made unit (zero where they
 * cannot be, as for assimp's meshes), one stand-in material (a PLY names none). */
static CstStatus ply_import(const char *path, ImportedMesh *out, CstError *err)
{
    PlyMesh pm;
    CstStatus st = ply_read_file(path, &pm, err);
    if (st != CST_OK) return st;
    if (pm.num_triangles == 0) {
        st = cst_fail(err, CST_ERR_PARSE, "%.300s: no triangles in the file (%d faces of other "
                      "than 3 or 4 vertices skipped)", path, pm.num_skipped_faces);
        ply_free(&pm);
        return st;
    }
    out->tri_material = calloc((size_t)pm.num_triangles, sizeof *out->tri_material);
    out->materials = calloc(1, sizeof *out->materials);
    if (!out->tri_material || !out->materials) {
        ply_free(&pm);
        mesh_import_free(out);
        return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory for %d triangles", path, pm.num_triangles);
    }
    Transform id = transform_identity();
    if (pm.normals)
        for (int i = 0; i < pm.num_vertices; i++) pm.normals[i] = transform_normal(&id, pm.normals[i]);
    out->positions = pm.positions;
    out->num_vertices = pm.num_vertices;
    out->indices = pm.indices;
    out->num_triangles = pm.num_triangles;
    out->normals = pm.normals;
    out->uvs = pm.uvs;
    out->num_materials = 1;
    strcpy(out->materials[0].name, "DefaultMaterial");
    out->materials[0].type = MATERIAL_DIFFUSE;
    out->materials[0].albedo = color_s(0.5f);
    out->materials[0].ior = 1.0f;
    out->num_skipped_primitives = pm.num_skipped_faces;
    out->skipped_face_size = pm.skipped_face_size;
    out->num_quads = pm.num_quads;
    out->from_ply = 1;
    free(pm.face_indices); /* pbrt-v4 keeps them for ptex textures only, which we lack */
    return CST_OK;
}

/* ------------------------------------------------------------------ OBJ material libraries */

/* assimp imports an OBJ whose "mtllib" file is missing without a word (its logger is
 * not attached), every face then on its default material: look for each named library
 * the way assimp does (the rest of the line, relative to the OBJ's directory) and note
 * the first one missing in out->warning. Only the "mtllib" lines are read. */
static void obj_check_mtl(const char *path, ImportedMesh *out)
{
    size_t n = strlen(path);
    if (n < 4 || strcasecmp(path + n - 4, ".obj") != 0) return;
    FILE *fp = fopen(path, "rb");
    if (!fp) return;
    char line[1024];
    int lineno = 0;
    while (fgets(line, sizeof line, fp)) {
        lineno++;
        const char *p = line + strspn(line, " \t");
        if (strncmp(p, "mtllib", 6) != 0 || (p[6] != ' ' && p[6] != '\t')) continue;
        p += 6 + strspn(p + 6, " \t");
        size_t len = strcspn(p, "\r\n");
        while (len > 0 && (p[len - 1] == ' ' || p[len - 1] == '\t')) len--;
        if (len == 0) continue;
        char name[512];
        snprintf(name, sizeof name, "%.*s", (int)(len < sizeof name ? len : sizeof name - 1), p);
        char *lib = path_resolve(path, name);
        struct stat sb;
        int found = lib && stat(lib, &sb) == 0 && S_ISREG(sb.st_mode);
        if (!found)
            snprintf(out->warning, sizeof out->warning, "%.160s:%d: material library '%.100s' not found "
                     "(looked for '%.120s'): the mesh is loaded without its materials", path, lineno,
                     name, lib ? lib : name);
        free(lib);
        if (!found) break;
    }
    fclose(fp);
}

/* ------------------------------------------------------------------ glTF pre-check */
/* assimp 5.2.5's glTF 2.0 importer aborts or writes out of bounds on some valid-looking
 * files: a LINE_LOOP whose first segments are dropped dereferences an empty face (SIGSEGV),
 * one of 1 index fails an ai_assert (abort, exit 134); a LINE_STRIP of 1 and a strip or
 * fan of 2 vertices write past an empty face array; a node hierarchy some thousands deep
 * overflows its recursion. So a glTF file's JSON is read here (jansson bounds its own
 * nesting at JSON_PARSER_MAX_DEPTH) and those cases are refused before assimp sees it. */

/* Deeper than any real scene graph, far below what overflows assimp's recursion. */
#define GLTF_MAX_NODE_DEPTH 256

static CstStatus gltf_fail(CstError *err, CstStatus st, const char *path, const char *fmt, ...)
    __attribute__((format(printf, 4, 5)));

static CstStatus gltf_fail(CstError *err, CstStatus st, const char *path, const char *fmt, ...)
{
    char what[400];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return cst_fail(err, st, "%.300s: %s glTF file: %s", path, st == CST_ERR_PARSE ? "malformed" : "unsupported",
                    what);
}

static uint32_t gltf_le32(const unsigned char *p)
{
    return (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
}

/* True when the file name ends in ext (".gltf"), ASCII case-insensitively. */
static int gltf_has_ext(const char *path, const char *ext)
{
    size_t n = strlen(path), e = strlen(ext);
    if (n < e) return 0;
    for (size_t i = 0; i < e; i++) {
        char c = path[n - e + i];
        if ((c >= 'A' && c <= 'Z' ? c + 32 : c) != ext[i]) return 0;
    }
    return 1;
}

/* nodes[]: a tree (one parent per node, as glTF 2.0 requires) no deeper than the limit. */
static CstStatus gltf_check_nodes(const json_t *nodes, const char *path, CstError *err)
{
    size_t n = json_array_size(nodes);
    if (n == 0) return CST_OK;
    long long *parent = malloc(n * sizeof *parent);
    if (!parent) return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory", path);
    for (size_t i = 0; i < n; i++) parent[i] = -1;
    CstStatus st = CST_OK;
    for (size_t i = 0; i < n && st == CST_OK; i++) {
        const json_t *children = json_object_get(json_array_get(nodes, i), "children");
        for (size_t k = 0; k < json_array_size(children) && st == CST_OK; k++) {
            const json_t *c = json_array_get(children, k);
            if (!json_is_integer(c) || json_integer_value(c) < 0 || (size_t)json_integer_value(c) >= n)
                continue; /* assimp reports bad references itself */
            size_t ci = (size_t)json_integer_value(c);
            if (parent[ci] >= 0)
                st = gltf_fail(err, CST_ERR_PARSE, path, "node %zu is a child of nodes %lld and %zu; expected "
                               "a tree (one parent per node)", ci, parent[ci], i);
            parent[ci] = (long long)i;
        }
    }
    /* Each node has at most one parent now, so walking up is a chain: a long one is too
     * deep, an endless one a cycle. */
    for (size_t i = 0; i < n && st == CST_OK; i++) {
        long long p = (long long)i;
        int depth = 0;
        while (p >= 0 && depth <= GLTF_MAX_NODE_DEPTH) {
            p = parent[p];
            depth++;
        }
        if (depth > GLTF_MAX_NODE_DEPTH)
            st = gltf_fail(err, CST_ERR_UNSUPPORTED, path, "node %zu is nested more than %d deep (or in a cycle "
                           "of children); expected at most %d levels", i, GLTF_MAX_NODE_DEPTH, GLTF_MAX_NODE_DEPTH);
    }
    free(parent);
    return st;
}

/* The vertex count a primitive's faces are built from: its indices' count, else its
 * positions'; -1 when the file does not say (assimp then reports the file itself). */
static long long gltf_prim_count(const json_t *prim, const json_t *accessors)
{
    const json_t *a = json_object_get(prim, "indices");
    if (!a) a = json_object_get(json_object_get(prim, "attributes"), "POSITION");
    if (!json_is_integer(a) || json_integer_value(a) < 0) return -1;
    const json_t *count = json_object_get(json_array_get(accessors, (size_t)json_integer_value(a)), "count");
    return json_is_integer(count) ? (long long)json_integer_value(count) : -1;
}

static CstStatus gltf_check_meshes(const json_t *root, const char *path, CstError *err)
{
    const json_t *meshes = json_object_get(root, "meshes"), *accessors = json_object_get(root, "accessors");
    for (size_t m = 0; m < json_array_size(meshes); m++) {
        const json_t *prims = json_object_get(json_array_get(meshes, m), "primitives");
        for (size_t k = 0; k < json_array_size(prims); k++) {
            const json_t *prim = json_array_get(prims, k), *mode_v = json_object_get(prim, "mode");
            long long mode = json_is_integer(mode_v) ? (long long)json_integer_value(mode_v) : 4;
            long long count = gltf_prim_count(prim, accessors);
            if (mode == 2)
                return gltf_fail(err, CST_ERR_UNSUPPORTED, path, "meshes[%zu].primitives[%zu] is a LINE_LOOP; "
                                 "expected triangles (assimp 5.2 can crash on line loops, and caustic skips "
                                 "lines anyway)", m, k);
            long long need = mode == 3 ? 2 : (mode == 5 || mode == 6) ? 3 : 0;
            if (count >= 0 && count < need)
                return gltf_fail(err, CST_ERR_PARSE, path, "meshes[%zu].primitives[%zu] is a %s of %lld "
                                 "vertices; expected at least %lld", m, k, mode == 3 ? "LINE_STRIP" : mode == 5
                                 ? "TRIANGLE_STRIP" : "TRIANGLE_FAN", count, need);
        }
    }
    return CST_OK;
}

/* Reads the JSON of a .gltf file, or of a GLB container's first chunk, into a new buffer;
 * *json stays NULL for files that are neither (or glTF 1.0 binaries: left to assimp). */
static CstStatus gltf_read_json(FILE *f, uint64_t size, const char *path, char **json, size_t *len,
                                CstError *err)
{
    unsigned char hdr[20] = {0};
    size_t got = fread(hdr, 1, sizeof hdr, f);
    uint64_t off = 0;
    *json = NULL;
    if (got >= 4 && memcmp(hdr, "glTF", 4) == 0) {
        if (got >= 8 && gltf_le32(hdr + 4) != 2) return CST_OK;
        if (got < 20) return gltf_fail(err, CST_ERR_PARSE, path, "the file ends inside its %zu-byte header", sizeof hdr);
        if (gltf_le32(hdr + 16) != 0x4E4F534Au)
            return gltf_fail(err, CST_ERR_PARSE, path, "the first chunk is not JSON");
        *len = gltf_le32(hdr + 12);
        if (*len > size - 20)
            return gltf_fail(err, CST_ERR_PARSE, path, "a JSON chunk of %zu bytes, but only %llu bytes follow "
                             "the header", *len, (unsigned long long)(size - 20));
        off = 20;
    } else if (gltf_has_ext(path, ".gltf")) {
        *len = (size_t)size;
    } else {
        return CST_OK;
    }
    char *buf = malloc(*len + 1);
    if (!buf) return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory reading the file", path);
    if (fseeko(f, (off_t)off, SEEK_SET) != 0 || fread(buf, 1, *len, f) != *len) {
        free(buf);
        return cst_fail(err, CST_ERR_IO, "%.300s: cannot read: %s", path, strerror(errno));
    }
    *json = buf;
    return CST_OK;
}

static CstStatus gltf_precheck(const char *path, CstError *err)
{
    FILE *f = NULL;
    uint64_t size = 0;
    CstStatus st = file_open_input(path, &f, &size, err);
    if (st != CST_OK) return st;
    char *text = NULL;
    size_t len = 0;
    st = gltf_read_json(f, size, path, &text, &len, err);
    fclose(f);
    if (st != CST_OK || !text) return st;
    json_error_t jerr;
    json_t *root = json_loadb(text, len, 0, &jerr);
    free(text);
    if (!root)
        return gltf_fail(err, CST_ERR_PARSE, path, "JSON line %d, column %d: %.200s", jerr.line, jerr.column,
                         jerr.text);
    const json_t *version = json_object_get(json_object_get(root, "asset"), "version");
    if (json_is_string(version) && json_string_value(version)[0] == '2') {
        st = gltf_check_nodes(json_object_get(root, "nodes"), path, err);
        if (st == CST_OK) st = gltf_check_meshes(root, path, err);
    }
    json_decref(root);
    return st;
}

/* Every check before assimp reads the file; each opens it through file_open_input. */
static CstStatus mesh_precheck(const char *path, CstError *err)
{
    return gltf_precheck(path, err);
}

/* ------------------------------------------------------------------ assimp's file access */
/* assimp opens files through these (the mesh and what it references: .mtl, .bin), so they
 * pass the same gate as every input. A refusal of a file that exists is kept, to be the
 * message when the import then fails. */

typedef struct ImportIo {
    int refused;
    CstError err;
} ImportIo;

typedef struct ImportFile {
    struct aiFile file; /* first: assimp hands back this pointer */
    FILE *fp;
    uint64_t size;
} ImportFile;

static size_t import_read(struct aiFile *af, char *buf, size_t size, size_t count)
{
    return fread(buf, size, count, ((ImportFile *)af)->fp);
}

static size_t import_write(struct aiFile *af, const char *buf, size_t size, size_t count)
{
    (void)af, (void)buf, (void)size, (void)count;
    return 0;
}

static size_t import_tell(struct aiFile *af)
{
    off_t p = ftello(((ImportFile *)af)->fp);
    return p < 0 ? 0 : (size_t)p;
}

static size_t import_size(struct aiFile *af) { return (size_t)((ImportFile *)af)->size; }

static void import_flush(struct aiFile *af) { (void)af; }

static enum aiReturn import_seek(struct aiFile *af, size_t offset, enum aiOrigin origin)
{
    int whence = origin == aiOrigin_SET ? SEEK_SET : origin == aiOrigin_CUR ? SEEK_CUR : SEEK_END;
    /* (off_t) of a size_t: assimp passes backward moves as wrapped-around offsets */
    return fseeko(((ImportFile *)af)->fp, (off_t)offset, whence) == 0 ? aiReturn_SUCCESS : aiReturn_FAILURE;
}

static struct aiFile *import_open(struct aiFileIO *fio, const char *path, const char *mode)
{
    ImportIo *io = (ImportIo *)(void *)fio->UserData;
    if (!path || !mode || strchr(mode, 'w') || strchr(mode, 'a') || strchr(mode, '+')) return NULL;
    ImportFile *f = calloc(1, sizeof *f);
    if (!f) return NULL;
    CstError e;
    if (file_open_input(path, &f->fp, &f->size, &e) != CST_OK) {
        struct stat sb;
        if (!io->refused && stat(path, &sb) == 0) { /* not a probe for a missing file */
            io->refused = 1;
            io->err = e;
        }
        free(f);
        return NULL;
    }
    f->file.ReadProc = import_read;
    f->file.WriteProc = import_write;
    f->file.TellProc = import_tell;
    f->file.FileSizeProc = import_size;
    f->file.SeekProc = import_seek;
    f->file.FlushProc = import_flush;
    return &f->file;
}

static void import_close(struct aiFileIO *fio, struct aiFile *af)
{
    (void)fio;
    if (!af) return;
    fclose(((ImportFile *)af)->fp);
    free(af);
}

static struct aiFileIO import_file_io(ImportIo *io)
{
    struct aiFileIO fio = {import_open, import_close, (aiUserData)(void *)io};
    return fio;
}

/* ------------------------------------------------------------------ entry points */

void mesh_import_free(ImportedMesh *mesh)
{
    if (!mesh) return;
    free(mesh->positions);
    free(mesh->indices);
    free(mesh->normals);
    free(mesh->uvs);
    free(mesh->tri_material);
    free(mesh->materials);
    memset(mesh, 0, sizeof *mesh);
}

/* The errors assimp reports by text only: a file that vanished between our check and its
 * open is I/O, everything else is a malformed (or unrecognised) file. */
static CstStatus import_error_status(const char *msg)
{
    return strstr(msg, "Unable to open file") ? CST_ERR_IO : CST_ERR_PARSE;
}

CstStatus mesh_import(const char *path, ImportedMesh *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    int is_ply = 0;
    CstStatus route = mesh_is_ply(path, &is_ply, err);
    if (route != CST_OK) return route;
    if (is_ply) return ply_import(path, out, err);
    /* assimp's own message for a missing file lacks the reason, and it would block on a
     * FIFO or read a device forever: the pre-checks open the file through the one gate
     * (core/file.h), and so does assimp, for the file and what it references (.mtl, .bin). */
    CstStatus pre = mesh_precheck(path, err);
    if (pre != CST_OK) return pre;

    struct aiPropertyStore *props = aiCreatePropertyStore();
    if (!props) return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory", path);
    /* Files with bones but no meshes would otherwise get a made-up skeleton mesh. */
    aiSetImportPropertyInteger(props, AI_CONFIG_IMPORT_NO_SKELETON_MESHES, 1);
    pthread_mutex_lock(&import_lock);
    ImportIo io = {0};
    struct aiFileIO fio = import_file_io(&io);
    const struct aiScene *scene = aiImportFileExWithProperties(path, MESH_IMPORT_FLAGS, &fio, props);
    CstStatus st = CST_OK;
    if (!scene && io.refused) { /* our reason, not assimp's "could not open" */
        st = cst_fail(err, io.err.status, "%.300s: cannot import: %.600s", path, io.err.msg);
    } else if (!scene) {
        const char *msg = aiGetErrorString();
        msg = msg && *msg ? msg : "unknown error";
        st = cst_fail(err, import_error_status(msg), "%.300s: cannot import: %.600s", path, msg);
    }
    pthread_mutex_unlock(&import_lock);
    aiReleasePropertyStore(props);
    if (!scene) return st;

    Flatten fl = {0};
    fl.scene = scene;
    fl.out = out;
    Transform root = transform_identity();
    if (scene->mRootNode) flatten_node(&fl, scene->mRootNode, &root);
    if (fl.triangles == 0) {
        st = cst_fail(err, CST_ERR_PARSE, "%.300s: no triangles in the file (%lld point and line "
                      "primitives skipped)", path, fl.skipped);
        goto done;
    }
    if (fl.vertices > INT_MAX || fl.triangles > INT_MAX / 3) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "%.300s: %lld vertices and %lld triangles are "
                      "too many; expected fewer than %d of each", path, fl.vertices, fl.triangles,
                      INT_MAX / 3);
        goto done;
    }
    size_t nv = (size_t)fl.vertices, nt = (size_t)fl.triangles;
    out->positions = malloc(nv * sizeof *out->positions);
    out->indices = malloc(3 * nt * sizeof *out->indices);
    out->tri_material = malloc(nt * sizeof *out->tri_material);
    out->normals = fl.any_normals ? malloc(nv * sizeof *out->normals) : NULL;
    out->uvs = fl.any_uvs ? malloc(nv * sizeof *out->uvs) : NULL;
    unsigned nm = scene->mNumMaterials;
    out->materials = calloc(nm ? nm : 1, sizeof *out->materials);
    if (!out->positions || !out->indices || !out->tri_material || !out->materials ||
        (fl.any_normals && !out->normals) || (fl.any_uvs && !out->uvs)) {
        st = cst_fail(err, CST_ERR_OOM, "%.300s: out of memory for %lld vertices and %lld "
                      "triangles", path, fl.vertices, fl.triangles);
        goto done;
    }
    out->normals_partial = fl.any_normals && fl.partial_normals;
    out->uvs_partial = fl.any_uvs && fl.partial_uvs;
    out->num_skipped_primitives = fl.skipped > INT_MAX ? INT_MAX : (int)fl.skipped;
    fl.fill = 1;
    fl.vertices = fl.triangles = 0;
    flatten_node(&fl, scene->mRootNode, &root);
    out->num_vertices = (int)fl.vertices;
    out->num_triangles = (int)fl.triangles;
    for (unsigned i = 0; i < nm; i++) map_material(scene->mMaterials[i], &out->materials[i]);
    out->num_materials = (int)nm;
    if (fl.bad_index) { /* ValidateDataStructure rules this out; keep the promise anyway */
        st = cst_fail(err, CST_ERR_PARSE, "%.300s: a face has a vertex index out of range", path);
        goto done;
    }
    for (int t = 0; t < out->num_triangles; t++)
        if (out->tri_material[t] < 0 || out->tri_material[t] >= out->num_materials) {
            st = cst_fail(err, CST_ERR_PARSE, "%.300s: triangle %d has material index %d out of "
                          "range", path, t, (int)out->tri_material[t]);
            goto done;
        }
done:
    aiReleaseImport(scene);
    if (st != CST_OK) mesh_import_free(out);
    else obj_check_mtl(path, out);
    return st;
}
