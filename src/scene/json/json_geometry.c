/* The "shapes" section: quads, triangle meshes, spheres and mesh files (through
 * mesh_import), with their transforms, validated and added to the scene. */
#include "scene/json/json_geometry.h"
#include "scene/json/json_motion.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/path.h"
#include "geometry/sdf.h"
#include "math/transform.h"
#include "scene/json/json_displace.h"
#include "scene/json/json_material.h"
#include "scene/json/json_medium.h"
#include "scene/json/json_texture.h"
#include "scene/mesh_import.h"

/* parse_mesh hands its Vec3/Vec2/int arrays to cst_scene_add_mesh as packed floats and
 * uint32_t indices. */
_Static_assert(sizeof(Vec3) == 3 * sizeof(float) && sizeof(Vec2) == 2 * sizeof(float) &&
               sizeof(int) == sizeof(uint32_t), "packed vertex arrays");

/* A quad's fourth vertex may lie this fraction of the quad's longer diagonal off the plane
 * of the other three. The measured Cornell box data is off by 0.41% (the left wall: the
 * room was surveyed, not modelled), so 1% passes it while a visibly bent quad fails. */
#define LOADER_QUAD_PLANARITY_TOL 0.01

/* A sphere's area 4 pi r^2 must not underflow to 0 in float: an emitter of area 0 cannot
 * be sampled. 1e-18 keeps r^2 a normal float. */
#define LOADER_MIN_RADIUS 1e-18

/* Triangle (a, b, c) has an area > 0, the same test the builder applies. */
static int triangle_ok(Vec3 a, Vec3 b, Vec3 c)
{
    float area = triangle_area(a, b, c);
    return area > 0.0f && isfinite(area);
}

static CstEmission emission_desc(const Emission *em)
{
    CstEmission e = {{0.0f, 0.0f, 0.0f}, 0, 0, 0};
    json_color_floats(em->radiance, e.radiance);
    e.texture = em->texture;
    e.two_sided = em->two_sided;
    return e;
}

static CstStatus parse_quad(Loader *ld, const json_t *shape, int material, const Emission *em,
                             const CstAlpha *alpha)
{
    json_t *arr;
    Vec3 v[4] = {{0}};
    char kind[48];
    LOADER_TRY(json_member_required(ld, shape, "vertices", "4 vertices, each an array of 3 numbers",
                                    &arr));
    json_path_push_key(ld, "vertices");
    if (!json_is_array(arr) || json_array_size(arr) != 4)
        return json_fail_here(ld, "got %s; expected 4 vertices, each an array of 3 numbers",
                              json_describe(arr, kind));
    for (size_t k = 0; k < 4; k++) {
        json_path_push_index(ld, k);
        LOADER_TRY(json_read_vec3(ld, json_array_get(arr, k), LOADER_MAX_LENGTH, &v[k]));
        json_path_pop(ld);
    }
    /* The builder splits the quad along v0-v2 into (v0, v1, v2) and (v0, v2, v3). */
    if (!triangle_ok(v[0], v[1], v[2]))
        return json_fail_here(ld, "triangle 0 of the quad (v0, v1, v2) is degenerate (zero area); "
                                  "expected 4 vertices in order around a quad of nonzero area");
    if (!triangle_ok(v[0], v[2], v[3]))
        return json_fail_here(ld, "triangle 1 of the quad (v0, v2, v3) is degenerate (zero area); "
                                  "expected 4 vertices in order around a quad of nonzero area");
    /* Checked in double: the cancellation in these differences is what we measure. */
    double e1[3], e2[3], e3[3], n0[3], n1[3], d13[3];
    for (int k = 0; k < 3; k++) {
        e1[k] = (double)v3_get(v[1], k) - (double)v3_get(v[0], k);
        e2[k] = (double)v3_get(v[2], k) - (double)v3_get(v[0], k);
        e3[k] = (double)v3_get(v[3], k) - (double)v3_get(v[0], k);
        d13[k] = (double)v3_get(v[3], k) - (double)v3_get(v[1], k);
    }
    for (int k = 0; k < 3; k++) {
        int a = (k + 1) % 3, b = (k + 2) % 3;
        n0[k] = e1[a] * e2[b] - e1[b] * e2[a]; /* (v1 - v0) x (v2 - v0) */
        n1[k] = e2[a] * e3[b] - e2[b] * e3[a]; /* (v2 - v0) x (v3 - v0) */
    }
    double dot01 = n0[0] * n1[0] + n0[1] * n1[1] + n0[2] * n1[2];
    if (!(dot01 > 0.0))
        return json_fail_here(ld, "the quad's triangles (v0, v1, v2) and (v0, v2, v3) face opposite "
                                  "ways; expected vertices in order around the quad (not crossing)");
    double n0_len = sqrt(n0[0] * n0[0] + n0[1] * n0[1] + n0[2] * n0[2]);
    double off = fabs(e3[0] * n0[0] + e3[1] * n0[1] + e3[2] * n0[2]) / n0_len;
    double diag = fmax(sqrt(e2[0] * e2[0] + e2[1] * e2[1] + e2[2] * e2[2]),
                       sqrt(d13[0] * d13[0] + d13[1] * d13[1] + d13[2] * d13[2]));
    double tol = LOADER_QUAD_PLANARITY_TOL * diag;
    if (off > tol)
        return json_fail_here(ld, "the quad is not planar: v3 is %g off the plane of v0, v1, v2 (more "
                                  "than %g, 1%% of its longer diagonal); expected 4 coplanar vertices",
                              off, tol);
    json_path_pop(ld);
    /* Two triangles (v0, v1, v2), (v0, v2, v3) with uvs (0,0), (1,0), (1,1), (0,1). */
    static const uint32_t quad_idx[6] = {0, 1, 2, 0, 2, 3};
    static const float quad_uv[8] = {0.0f, 0.0f, 1.0f, 0.0f, 1.0f, 1.0f, 0.0f, 1.0f};
    float pos[4][3];
    for (int k = 0; k < 4; k++) json_vec3_floats(v[k], pos[k]);
    CstMeshDesc mesh = {0};
    mesh.positions = pos;
    mesh.num_vertices = 4;
    mesh.uvs = quad_uv;
    mesh.indices = quad_idx;
    mesh.num_triangles = 2;
    mesh.material = material;
    mesh.emission = emission_desc(em);
    mesh.alpha = *alpha;
    CstStatus st = cst_scene_add_mesh(ld->scene, &mesh, NULL, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

static CstStatus read_mesh_indices(Loader *ld, const json_t *arr, int num_vertices, Vec3 *pos,
                                   int *idx)
{
    char kind[48];
    size_t t;
    json_t *tri;
    json_array_foreach(arr, t, tri) {
        json_path_push_index(ld, t);
        if (!json_is_array(tri) || json_array_size(tri) != 3)
            return json_fail_here(ld, "got %s; expected a triangle, an array of 3 vertex indices",
                                  json_describe(tri, kind));
        for (size_t k = 0; k < 3; k++) {
            json_t *iv = json_array_get(tri, k);
            json_path_push_index(ld, k);
            if (!json_is_integer(iv))
                return json_fail_here(ld, "got %s; expected a vertex index, an integer from 0 to %d",
                                      json_describe(iv, kind), num_vertices - 1);
            json_int_t i = json_integer_value(iv);
            if (i < 0 || i >= num_vertices)
                return json_fail_here(ld, "vertex index %" JSON_INTEGER_FORMAT " is out of range; "
                                          "expected 0 to %d (the mesh has %d vertices)",
                                      i, num_vertices - 1, num_vertices);
            idx[3 * t + k] = (int)i;
            json_path_pop(ld);
        }
        if (!triangle_ok(pos[idx[3 * t]], pos[idx[3 * t + 1]], pos[idx[3 * t + 2]]))
            return json_fail_here(ld, "triangle %zu is degenerate (zero area); expected 3 distinct, "
                                      "non-collinear vertices",
                                  t);
        json_path_pop(ld);
    }
    return CST_OK;
}

/* An inline mesh's "normals": one nonzero vector per vertex. */
static CstStatus read_mesh_normals(Loader *ld, const json_t *narr, size_t nv, Vec3 **out)
{
    char kind[48];
    json_path_push_key(ld, "normals");
    if (!json_is_array(narr) || json_array_size(narr) != nv)
        return json_fail_here(ld, "got %s; expected an array of %zu normals (one per vertex), each an "
                                  "array of 3 numbers",
                              json_describe(narr, kind), nv);
    Vec3 *n = malloc(nv * sizeof *n);
    if (!n) return json_fail_at(ld, CST_ERR_OOM, "out of memory for %zu normals", nv);
    for (size_t k = 0; k < nv; k++) {
        json_path_push_index(ld, k);
        CstStatus st = json_read_vec3(ld, json_array_get(narr, k), LOADER_MAX_LENGTH, &n[k]);
        if (st == CST_OK && !(v3_max_abs(n[k]) > 0.0f))
            st = json_fail_here(ld, "the normal is zero; expected a nonzero vector");
        if (st != CST_OK) {
            free(n);
            return st;
        }
        /* Kept as read: the builder normalises it (scaled first, so tiny or huge normals
         * normalise without under- or overflow). */
        json_path_pop(ld);
    }
    json_path_pop(ld);
    *out = n;
    return CST_OK;
}

/* A mesh's "shading": "smooth" (default) makes its vertex normals shading normals; "flat"
 * drops them, so the mesh shades with its geometric normals. */
static CstStatus read_shading(Loader *ld, const json_t *shape, bool *flat)
{
    json_t *v = json_object_get(shape, "shading");
    *flat = false;
    if (!v) return CST_OK;
    const char *sv = NULL;
    json_path_push_key(ld, "shading");
    LOADER_TRY(json_read_string(ld, v, &sv));
    if (strcmp(sv, "flat") == 0) {
        *flat = true;
    } else if (strcmp(sv, "smooth") != 0) {
        char name[72];
        return json_fail_here(ld, "unknown shading \"%s\"; expected one of: smooth, flat", json_clip_name(sv, name));
    }
    json_path_pop(ld);
    return CST_OK;
}

static CstStatus parse_transform(Loader *ld, const json_t *obj, Transform *out);

CstStatus json_parse_motion(Loader *ld, const json_t *motion, Transform *t0, Transform *t1)
{
    static const char *const keys[] = {"transform", "transform_end"};
    LOADER_TRY(json_expect_object(ld, motion, "an object with \"transform_end\" (and optionally \"transform\")"));
    LOADER_TRY(json_check_keys(ld, motion, keys, 2));
    *t0 = transform_identity();
    json_t *v = json_object_get(motion, "transform");
    if (v) {
        json_path_push_key(ld, "transform");
        LOADER_TRY(parse_transform(ld, v, t0));
        json_path_pop(ld);
    }
    LOADER_TRY(json_member_required(ld, motion, "transform_end", "the transform at time 1 (shutter close)", &v));
    json_path_push_key(ld, "transform_end");
    LOADER_TRY(parse_transform(ld, v, t1));
    json_path_pop(ld);
    return CST_OK;
}

static CstStatus parse_mesh(Loader *ld, const json_t *shape, int material, const Emission *em,
                             const CstAlpha *alpha)
{
    json_t *varr, *iarr;
    char kind[48];
    LOADER_TRY(json_member_required(ld, shape, "vertices",
                                    "an array of vertices, each an array of 3 numbers", &varr));
    LOADER_TRY(json_member_required(ld, shape, "indices",
                                    "an array of triangles, each an array of 3 vertex indices", &iarr));
    json_path_push_key(ld, "vertices");
    if (!json_is_array(varr) || json_array_size(varr) < 3)
        return json_fail_here(ld, "got %s; expected at least 3 vertices, each an array of 3 numbers",
                              json_describe(varr, kind));
    json_path_pop(ld);
    json_path_push_key(ld, "indices");
    if (!json_is_array(iarr) || json_array_size(iarr) == 0)
        return json_fail_here(ld, "got %s; expected at least 1 triangle, each an array of 3 vertex "
                                  "indices",
                              json_describe(iarr, kind));
    json_path_pop(ld);
    size_t nv = json_array_size(varr), nt = json_array_size(iarr);
    /* The builder counts in int, 3 indices per triangle. */
    if (nv > (size_t)INT_MAX || nt > (size_t)(INT_MAX / 3))
        return json_fail_here(ld, "the mesh is too large; expected fewer than %d triangles", INT_MAX / 3);

    CstStatus st = CST_OK;
    json_t *uarr = json_object_get(shape, "uvs");
    Vec3 *pos = malloc(nv * sizeof *pos), *nrm = NULL;
    int *idx = malloc(nt * 3 * sizeof *idx);
    Vec2 *uvs = uarr ? malloc(nv * sizeof *uvs) : NULL;
    if (!pos || !idx || (uarr && !uvs)) {
        st = json_fail_at(ld, CST_ERR_OOM, "out of memory for %zu vertices and %zu triangles", nv, nt);
        goto done;
    }
    json_path_push_key(ld, "vertices");
    for (size_t k = 0; k < nv; k++) {
        json_path_push_index(ld, k);
        st = json_read_vec3(ld, json_array_get(varr, k), LOADER_MAX_LENGTH, &pos[k]);
        if (st != CST_OK)
            goto done;
        json_path_pop(ld);
    }
    json_path_pop(ld);
    json_path_push_key(ld, "indices");
    st = read_mesh_indices(ld, iarr, (int)nv, pos, idx);
    if (st != CST_OK)
        goto done;
    json_path_pop(ld);
    if (uarr) {
        /* Texture coordinates, one [u, v] per vertex. */
        json_path_push_key(ld, "uvs");
        if (!json_is_array(uarr) || json_array_size(uarr) != nv) {
            st = json_fail_here(ld, "got %s; expected one [u, v] per vertex (%zu)", json_describe(uarr, kind), nv);
            goto done;
        }
        for (size_t k = 0; k < nv; k++) {
            json_t *e = json_array_get(uarr, k);
            float c[2] = {0.0f, 0.0f};
            json_path_push_index(ld, k);
            if (!json_is_array(e) || json_array_size(e) != 2) {
                st = json_fail_here(ld, "got %s; expected an array of 2 numbers", json_describe(e, kind));
                goto done;
            }
            for (size_t j = 0; j < 2; j++) {
                json_path_push_index(ld, j);
                st = json_read_float(ld, json_array_get(e, j), (double)FLT_MAX, &c[j]);
                if (st != CST_OK)
                    goto done;
                json_path_pop(ld);
            }
            uvs[k] = v2(c[0], c[1]);
            json_path_pop(ld);
        }
        json_path_pop(ld);
    }
    bool flat = false;
    if ((st = read_shading(ld, shape, &flat)) != CST_OK)
        goto done;
    json_t *narr = json_object_get(shape, "normals");
    if (narr && (st = read_mesh_normals(ld, narr, nv, &nrm)) != CST_OK)
        goto done;
    /* "displacement": the arrays replaced by the displaced mesh's (world space) */
    JsonMesh jm = {pos, nrm, uvs, idx, (int)nv, (int)nt, NULL};
    st = json_read_displacement(ld, shape, NULL, &jm);
    pos = jm.p, nrm = jm.n, uvs = jm.uv, idx = jm.idx, nv = (size_t)jm.nv, nt = (size_t)jm.nt;
    if (st != CST_OK)
        goto done;
    /* Vec3 and Vec2 are packed floats and the indices non-negative ints, which the
     * builder reads as uint32_t (the same bytes). */
    CstMeshDesc mesh = {0};
    mesh.positions = pos;
    mesh.position_stride = sizeof *pos;
    mesh.num_vertices = (int)nv;
    mesh.uvs = uvs;
    mesh.uv_stride = sizeof(Vec2);
    mesh.normals = flat ? NULL : nrm;
    mesh.normal_stride = sizeof(Vec3);
    mesh.indices = idx;
    mesh.index_stride = 3 * sizeof *idx;
    mesh.num_triangles = (int)nt;
    mesh.material = material;
    mesh.emission = emission_desc(em);
    mesh.alpha = *alpha;
    mesh.skip_degenerate = json_object_get(shape, "displacement") != NULL; /* displacement may fold some */
    json_t *motion = json_object_get(shape, "motion");
    if (motion) {
        json_path_push_key(ld, "motion");
        st = json_add_moving_mesh(ld, motion, &mesh, shape);
        if (st == CST_OK) json_path_pop(ld);
        goto done;
    }
    st = cst_scene_add_mesh(ld->scene, &mesh, NULL, ld->err);
    if (st != CST_OK)
        st = json_fail_builder(ld, st);
done:
    free(pos);
    free(idx);
    free(uvs);
    free(nrm);
    return st;
}

static CstStatus parse_sphere(Loader *ld, const json_t *shape, int material, const Emission *em,
                               const CstAlpha *alpha)
{
    json_t *v;
    Vec3 center = {0};
    float radius = 0.0f;
    LOADER_TRY(json_member_required(ld, shape, "center", "an array of 3 numbers", &v));
    json_path_push_key(ld, "center");
    LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &center));
    json_path_pop(ld);
    LOADER_TRY(json_member_required(ld, shape, "radius", "a number > 0", &v));
    json_path_push_key(ld, "radius");
    LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &radius));
    if (!(radius > 0.0f))
        return json_fail_here(ld, "radius %g is not positive; expected a number > 0", (double)radius);
    if (!(radius >= (float)LOADER_MIN_RADIUS))
        return json_fail_here(ld, "radius %g is too small (its area would underflow a 32-bit float); "
                                  "expected a radius of at least %g",
                              (double)radius, LOADER_MIN_RADIUS);
    json_path_pop(ld);
    float c[3];
    json_vec3_floats(center, c);
    CstEmission e = emission_desc(em);
    CstStatus st = cst_scene_add_sphere_alpha(ld->scene, c, radius, material, &e, alpha, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

/* One rotation {"axis": [x, y, z], "angle": degrees}. */
static CstStatus read_rotation(Loader *ld, const json_t *obj, Transform *out)
{
    static const char *const keys[] = {"axis", "angle"};
    json_t *v;
    Vec3 axis = {0};
    float angle = 0.0f;
    LOADER_TRY(json_expect_object(ld, obj, "a rotation, an object with axis and angle"));
    LOADER_TRY(json_check_keys(ld, obj, keys, 2));
    LOADER_TRY(json_member_required(ld, obj, "axis", "the rotation axis, an array of 3 numbers", &v));
    json_path_push_key(ld, "axis");
    LOADER_TRY(json_read_vec3(ld, v, (double)FLT_MAX, &axis));
    if (!(v3_max_abs(axis) > 0.0f))
        return json_fail_here(ld, "the axis is zero; expected a nonzero vector");
    json_path_pop(ld);
    LOADER_TRY(json_member_required(ld, obj, "angle", "the rotation angle in degrees", &v));
    json_path_push_key(ld, "angle");
    LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &angle));
    json_path_pop(ld);
    *out = transform_rotate_degrees(axis, (double)angle);
    return CST_OK;
}

/* "transform": {"scale", "rotate", "translate"} applied in that order, or {"matrix"}. */
static CstStatus parse_transform(Loader *ld, const json_t *obj, Transform *out)
{
    static const char *const keys[] = {"translate", "rotate", "scale", "matrix"};
    char kind[48];
    json_t *v;
    LOADER_TRY(json_expect_object(ld, obj,
                                  "an object with translate, rotate and scale, or with matrix"));
    LOADER_TRY(json_check_keys(ld, obj, keys, 4));
    Transform t = transform_identity();
    if ((v = json_object_get(obj, "matrix"))) {
        for (int k = 0; k < 3; k++)
            if (json_object_get(obj, keys[k])) {
                json_path_push_key(ld, keys[k]);
                return json_fail_key(ld, "\"%s\" cannot be combined with \"matrix\"; expected either "
                                         "a matrix or translate, rotate and scale", keys[k]);
            }
        json_path_push_key(ld, "matrix");
        if (!json_is_array(v) || json_array_size(v) != 16)
            return json_fail_here(ld, "got %s; expected 16 numbers, a 4x4 matrix row by row",
                                  json_describe(v, kind));
        float rows[16];
        for (size_t k = 0; k < 16; k++) {
            json_path_push_index(ld, k);
            LOADER_TRY(json_read_float(ld, json_array_get(v, k), (double)FLT_MAX, &rows[k]));
            json_path_pop(ld);
        }
        static const float bottom[4] = {0.0f, 0.0f, 0.0f, 1.0f};
        for (size_t k = 12; k < 16; k++)
            if (rows[k] != bottom[k - 12]) {
                json_path_push_index(ld, k);
                return json_fail_here(ld, "element %g of the bottom row is not %g; expected an affine "
                                          "matrix, bottom row 0, 0, 0, 1",
                                      (double)rows[k], (double)bottom[k - 12]);
            }
        t = transform_from_rows(rows);
        json_path_pop(ld);
    } else {
        if ((v = json_object_get(obj, "scale"))) {
            Vec3 sc = {0};
            json_path_push_key(ld, "scale");
            if (json_is_number(v)) {
                float f = 0.0f;
                LOADER_TRY(json_read_float(ld, v, (double)FLT_MAX, &f));
                sc = v3s(f);
            } else if (json_is_array(v)) {
                LOADER_TRY(json_read_vec3(ld, v, (double)FLT_MAX, &sc));
            } else {
                return json_fail_here(ld, "got %s; expected a number or an array of 3 numbers",
                                      json_describe(v, kind));
            }
            for (int k = 0; k < 3; k++)
                if (v3_get(sc, k) == 0.0f) {
                    if (json_is_array(v))
                        json_path_push_index(ld, (size_t)k);
                    return json_fail_here(ld, "scale 0 flattens the mesh; expected a nonzero number "
                                              "(a negative one mirrors)");
                }
            t = transform_scale(sc);
            json_path_pop(ld);
        }
        if ((v = json_object_get(obj, "rotate"))) {
            Transform r = transform_identity();
            json_path_push_key(ld, "rotate");
            if (json_is_array(v)) {
                if (json_array_size(v) == 0)
                    return json_fail_here(ld, "got an empty array; expected a rotation or an array "
                                              "of rotations, each an object with axis and angle");
                size_t i;
                json_t *rv;
                json_array_foreach(v, i, rv) {
                    json_path_push_index(ld, i);
                    LOADER_TRY(read_rotation(ld, rv, &r));
                    t = transform_compose(r, t); /* the list in order: first applied first */
                    json_path_pop(ld);
                }
            } else {
                LOADER_TRY(read_rotation(ld, v, &r));
                t = transform_compose(r, t);
            }
            json_path_pop(ld);
        }
        if ((v = json_object_get(obj, "translate"))) {
            Vec3 d = {0};
            json_path_push_key(ld, "translate");
            LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &d));
            t = transform_compose(transform_translate(d), t);
            json_path_pop(ld);
        }
    }
    Transform nm;
    if (!transform_normal_matrix(&t, &nm))
        return json_fail_here(ld, "the transform is singular (determinant %g) or not invertible in "
                             "32-bit floats, so it flattens the mesh; expected an invertible "
                                  "transform",
                              transform_det(&t));
    *out = t;
    return CST_OK;
}

/* Applies the shape's transform to the imported mesh in place; a mirroring transform gets
 * the triangles' winding swapped back so that outside stays outside (the geometric normal
 * is (b - a) x (c - a)). */
static void transform_mesh(ImportedMesh *im, const Transform *t)
{
    Transform nm = transform_identity();
    transform_normal_matrix(t, &nm); /* checked invertible by parse_transform */
    for (int i = 0; i < im->num_vertices; i++)
        im->positions[i] = transform_point(t, im->positions[i]);
    for (int i = 0; im->normals && i < im->num_vertices; i++)
        im->normals[i] = transform_normal(&nm, im->normals[i]);
    if (transform_det(t) < 0.0)
        for (int i = 0; i < im->num_triangles; i++) {
            int32_t tmp = im->indices[3 * i + 1];
            im->indices[3 * i + 1] = im->indices[3 * i + 2];
            im->indices[3 * i + 2] = tmp;
        }
}

/* Scene material ids for the file's materials, added to the scene on first use. Fails
 * at the shape when a triangle has only assimp's stand-in material. */
static CstStatus file_materials(Loader *ld, const ImportedMesh *im, int *tri_ids)
{
    int *ids = malloc((size_t)(im->num_materials > 0 ? im->num_materials : 1) * sizeof *ids);
    if (!ids)
        return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    for (int i = 0; i < im->num_materials; i++)
        ids[i] = -1;
    CstStatus st = CST_OK;
    for (int t = 0; t < im->num_triangles && st == CST_OK; t++) {
        const ImportedMaterial *fm = &im->materials[im->tri_material[t]];
        int *id = &ids[im->tri_material[t]];
        if (*id < 0 && !fm->from_file) {
            st = json_fail_here(ld, "missing key \"material\": the mesh file names no material for "
                               "its triangle %d; expected the name of a material for the whole "
                                    "mesh",
                                t);
        } else if (*id < 0) {
            Material m = {0};
            m.type = (MaterialType)fm->type;
            m.albedo = fm->albedo;
            m.ior = fm->ior;
            st = json_add_material(ld, &m, id);
        }
        tri_ids[t] = *id;
    }
    free(ids);
    return st;
}

static CstStatus parse_meshfile(Loader *ld, const json_t *shape, int material, const Emission *em,
                                 const CstAlpha *alpha)
{
    json_t *fv, *v;
    const char *file = NULL;
    Transform xf = transform_identity();
    LOADER_TRY(json_member_required(ld, shape, "file",
                               "the path of a mesh file (OBJ, PLY, glTF, ...), relative to the "
                                    "scene file",
                                    &fv));
    if ((v = json_object_get(shape, "transform"))) {
        json_path_push_key(ld, "transform");
        LOADER_TRY(parse_transform(ld, v, &xf));
        json_path_pop(ld);
    }
    bool flat = false;
    LOADER_TRY(read_shading(ld, shape, &flat));
    json_path_push_key(ld, "file");
    LOADER_TRY(json_read_string(ld, fv, &file));
    if (!file[0])
        return json_fail_here(ld, "the file name is empty; expected the path of a mesh file");
    char *path = path_resolve(ld->name, file);
    if (!path)
        return json_fail_at(ld, CST_ERR_OOM, "out of memory");
    ImportedMesh im = {0};
    int *tri_ids = NULL;
    CstStatus st = mesh_import(path, &im, ld->err);
    if (st != CST_OK) {
        st = json_fail_builder(ld, st); /* "<json>:l:c: shapes[i].file: <resolved path>: ..." */
        goto done;
    }
    if (im.warning[0] && ld->opt && ld->opt->warning)
        ld->opt->warning(ld->opt->warning_user, CST_WARN_MISSING_FILE, im.warning);
    if (im.num_skipped_primitives && im.from_ply && ld->opt && ld->opt->warning) {
        /* a PLY's faces of other than 3 or 4 vertices, skipped as pbrt-v4 skips them */
        char msg[700];
        snprintf(msg, sizeof msg, "%.400s: %d faces of other than 3 or 4 vertices skipped (the "
                 "first has %d)", path, im.num_skipped_primitives, im.skipped_face_size);
        ld->opt->warning(ld->opt->warning_user, CST_WARN_GEOMETRY, msg);
    }
    if (json_object_get(shape, "displacement")) {
        /* in the file's space, before the transform: edges measured and textures read after it */
        json_path_pop(ld);
        JsonMesh jm = {im.positions, im.normals, im.uvs, im.indices, im.num_vertices, im.num_triangles,
                       im.tri_material};
        st = json_read_displacement(ld, shape, &xf, &jm);
        im.positions = jm.p, im.normals = jm.n, im.uvs = jm.uv, im.indices = jm.idx;
        im.num_vertices = jm.nv, im.num_triangles = jm.nt, im.tri_material = jm.tri_mat;
        if (st != CST_OK)
            goto done;
        json_path_push_key(ld, "file");
    }
    if (!transform_is_identity(&xf))
        transform_mesh(&im, &xf);
    for (int i = 0; i < im.num_vertices; i++) {
        Vec3 p = im.positions[i];
        if (!v3_is_finite(p) || !((double)v3_max_abs(p) <= LOADER_MAX_LENGTH)) {
            st = json_fail_here(ld, "vertex %d of the mesh is at (%g, %g, %g)%s, beyond the scene "
                                    "limit; expected coordinates of magnitude at most %g",
                                i, (double)p.x, (double)p.y, (double)p.z,
                                json_object_get(shape, "transform") ? " after the transform" : "",
                                LOADER_MAX_LENGTH);
            goto done;
        }
    }
    if (material < 0) {
        tri_ids = malloc((size_t)im.num_triangles * sizeof *tri_ids);
        if (!tri_ids) {
            st = json_fail_at(ld, CST_ERR_OOM, "out of memory");
            goto done;
        }
        json_path_pop(ld); /* a missing material is the shape's error, not the file's */
        st = file_materials(ld, &im, tri_ids);
        json_path_push_key(ld, "file");
        if (st != CST_OK)
            goto done;
    }
    /* mesh_import's normals are unit (transform_normal) or zero where a mesh has none. */
    CstMeshDesc mesh = {0};
    mesh.positions = im.positions;
    mesh.position_stride = sizeof(Vec3);
    mesh.num_vertices = im.num_vertices;
    mesh.normals = flat ? NULL : im.normals;
    mesh.normal_stride = sizeof(Vec3);
    mesh.normals_unit = 1;
    mesh.uvs = im.uvs;
    mesh.uv_stride = sizeof(Vec2);
    mesh.indices = im.indices;
    mesh.index_stride = 3 * sizeof(int32_t);
    mesh.num_triangles = im.num_triangles;
    mesh.material = material;
    mesh.triangle_materials = tri_ids;
    mesh.emission = emission_desc(em);
    mesh.alpha = *alpha;
    mesh.skip_degenerate = 1; /* scanned meshes have some; documented in scene-format.md */
    int dropped = 0;
    st = cst_scene_add_mesh(ld->scene, &mesh, &dropped, ld->err);
    if (st != CST_OK) {
        st = json_fail_builder(ld, st);
    } else if (dropped == im.num_triangles) {
        st = json_fail_here(ld, "all %d triangles of the mesh are degenerate (zero area)%s; expected "
                                "a mesh with some area",
                            dropped, json_object_get(shape, "transform") ? " after the transform" : "");
    } else {
        json_path_pop(ld);
    }
done:
    free(tri_ids);
    mesh_import_free(&im);
    free(path);
    return st;
}

enum { SHAPE_QUAD, SHAPE_MESH, SHAPE_SPHERE, SHAPE_MESHFILE, SHAPE_CYLINDER, SHAPE_DISK, SHAPE_TORUS, SHAPE_SDF, SHAPE_CURVE };

/* An optional number under `key` (default `def`, magnitude at most 1e18). */
static CstStatus read_opt_float(Loader *ld, const json_t *shape, const char *key, float def, float *out)
{
    json_t *v = json_object_get(shape, key);
    *out = def;
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, out));
    json_path_pop(ld);
    return CST_OK;
}

/* "cylinder", "disk", and a "sphere" with "z_min", "z_max" or "phi_max": analytic shapes
 * (cst_scene_add_shape), in object space placed by "transform" (a sphere: moved to its
 * "center"); an "emission" makes it an area light. With "motion", an object placed by a
 * moving instance (json_add_moving_shape); plain: a sphere with none of the analytic keys. */
static CstStatus parse_analytic(Loader *ld, const json_t *shape, int type, int material, const Emission *em,
                                const CstAlpha *alpha, int plain)
{
    CstShapeDesc sd = {0};
    sd.emission = emission_desc(em); /* an area light sampled by area; needs a similarity "transform" */
    sd.type = type == SHAPE_CYLINDER ? CST_SHAPE_CYLINDER : type == SHAPE_DISK ? CST_SHAPE_DISK : CST_SHAPE_SPHERE;
    json_t *v;
    LOADER_TRY(json_member_required(ld, shape, "radius", "a number > 0", &v));
    LOADER_TRY(read_opt_float(ld, shape, "radius", 0.0f, &sd.radius));
    float zdef = type == SHAPE_SPHERE ? sd.radius : 1.0f;
    LOADER_TRY(read_opt_float(ld, shape, "z_min", -zdef, &sd.z_min));
    LOADER_TRY(read_opt_float(ld, shape, "z_max", zdef, &sd.z_max));
    LOADER_TRY(read_opt_float(ld, shape, "height", 0.0f, &sd.height));
    LOADER_TRY(read_opt_float(ld, shape, "inner_radius", 0.0f, &sd.inner_radius));
    LOADER_TRY(read_opt_float(ld, shape, "phi_max", 360.0f, &sd.phi_max_degrees));
    json_t *ro = json_object_get(shape, "reverse_orientation");
    if (ro && !json_is_boolean(ro)) {
        json_path_push_key(ld, "reverse_orientation");
        return json_fail_here(ld, "expected true or false");
    }
    sd.reverse_orientation = ro && json_is_true(ro);
    Transform xf = transform_identity();
    if ((v = json_object_get(shape, "transform"))) {
        json_path_push_key(ld, "transform");
        LOADER_TRY(parse_transform(ld, v, &xf));
        json_path_pop(ld);
    }
    const json_t *motion = json_object_get(shape, "motion");
    if (type == SHAPE_SPHERE) {
        Vec3 c = {0};
        LOADER_TRY(json_member_required(ld, shape, "center", "an array of 3 numbers", &v));
        json_path_push_key(ld, "center");
        LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &c));
        json_path_pop(ld);
        if (motion && plain) /* a plain moving sphere keeps a static one's uvs: pole on +y, u from +z to +x */
            xf = json_sphere_uv_frame();
        xf = transform_compose(transform_translate(c), xf);
    }
    for (int r = 0; r < 3; r++)
        for (int k = 0; k < 4; k++) sd.world_from_object[4 * r + k] = xf.m[r][k];
    if (transform_is_identity(&xf)) memset(sd.world_from_object, 0, sizeof sd.world_from_object);
    sd.material = material;
    sd.alpha = *alpha;
    if (motion) return json_add_moving_shape(ld, motion, &sd, shape);
    CstStatus st = cst_scene_add_shape(ld->scene, &sd, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

/* A shape's optional "transform" into the 3 x 4 rows of a Cst*Desc (all 0: identity). */
static CstStatus read_rows(Loader *ld, const json_t *obj, float rows[12])
{
    json_t *v = json_object_get(obj, "transform");
    memset(rows, 0, 12 * sizeof *rows);
    if (!v) return CST_OK;
    Transform xf = transform_identity();
    json_path_push_key(ld, "transform");
    LOADER_TRY(parse_transform(ld, v, &xf));
    json_path_pop(ld);
    if (!transform_is_identity(&xf))
        for (int r = 0; r < 3; r++)
            for (int k = 0; k < 4; k++) rows[4 * r + k] = xf.m[r][k];
    return CST_OK;
}

/* A required number under `key`, > 0 (or >= 0 with zero_ok). */
static CstStatus read_length(Loader *ld, const json_t *obj, const char *key, int zero_ok, float *out)
{
    json_t *v;
    LOADER_TRY(json_member_required(ld, obj, key, zero_ok ? "a number >= 0" : "a number > 0", &v));
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, out));
    if (!(zero_ok ? *out >= 0.0f : *out > 0.0f))
        return json_fail_here(ld, "%s %g; expected a number %s", key, (double)*out, zero_ok ? ">= 0" : "> 0");
    json_path_pop(ld);
    return CST_OK;
}

/* "torus": the quartic torus about the object's z axis (cst_scene_add_shape). */
static CstStatus parse_torus(Loader *ld, const json_t *shape, int material, const Emission *em, const CstAlpha *alpha)
{
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_TORUS;
    sd.emission = emission_desc(em); /* refused by the builder: tori do not emit */
    LOADER_TRY(read_length(ld, shape, "major_radius", 0, &sd.radius));
    LOADER_TRY(read_length(ld, shape, "minor_radius", 0, &sd.minor_radius));
    if (!(sd.minor_radius < sd.radius)) {
        json_path_push_key(ld, "minor_radius");
        return json_fail_here(ld, "minor_radius %g >= major_radius %g; expected a ring torus (minor < major)",
                              (double)sd.minor_radius, (double)sd.radius);
    }
    LOADER_TRY(read_rows(ld, shape, sd.world_from_object));
    sd.material = material;
    sd.alpha = *alpha;
    const json_t *motion = json_object_get(shape, "motion");
    if (motion) return json_add_moving_shape(ld, motion, &sd, shape);
    CstStatus st = cst_scene_add_shape(ld->scene, &sd, ld->err);
    return st == CST_OK ? CST_OK : json_fail_builder(ld, st);
}

/* An optional string under `key` that must be one of names[0..n): its index (default 0). */
static CstStatus read_choice(Loader *ld, const json_t *obj, const char *key, const char *const *names, int n,
                             int *out)
{
    json_t *v = json_object_get(obj, key);
    const char *str;
    *out = 0;
    if (!v) return CST_OK;
    json_path_push_key(ld, key);
    LOADER_TRY(json_read_string(ld, v, &str));
    for (int k = 0; k < n; k++)
        if (strcmp(str, names[k]) == 0) {
            *out = k;
            json_path_pop(ld);
            return CST_OK;
        }
    if (n == 2) return json_fail_here(ld, "\"%.60s\"; expected \"%s\" or \"%s\"", str, names[0], names[1]);
    return json_fail_here(ld, "\"%.60s\"; expected \"%s\", \"%s\" or \"%s\"", str, names[0], names[1], names[2]);
}

/* An array of at least `min` points (or normals), each an array of 3 numbers, into a new
 * array of 3 floats per point. */
static CstStatus read_points(Loader *ld, const json_t *obj, const char *key, size_t min, float **out, int *count)
{
    char kind[48];
    json_t *arr = json_object_get(obj, key);
    *out = NULL;
    *count = 0;
    json_path_push_key(ld, key);
    if (!json_is_array(arr) || json_array_size(arr) < min || json_array_size(arr) > 1u << 24)
        return json_fail_here(ld, "got %s; expected an array of at least %zu points, each an array of 3 numbers",
                              json_describe(arr, kind), min);
    const size_t n = json_array_size(arr);
    float *p = malloc(3 * n * sizeof *p);
    if (!p) return json_fail_here(ld, "out of memory for %zu points", n);
    for (size_t k = 0; k < n; k++) {
        Vec3 v;
        json_path_push_index(ld, k);
        const CstStatus st = json_read_vec3(ld, json_array_get(arr, k), LOADER_MAX_LENGTH, &v);
        if (st != CST_OK) {
            free(p);
            return st;
        }
        json_vec3_floats(v, p + 3 * k);
        json_path_pop(ld);
    }
    json_path_pop(ld);
    *out = p;
    *count = (int)n;
    return CST_OK;
}

/* "curve": pbrt-v4's curve (cst_scene_add_curves): "points" as Bezier segments sharing their
 * end points or a uniform B-spline ("basis"), of "degree" 2 or 3, "curve_type" flat,
 * cylinder or ribbon (with "normals", one per segment end), widths "width" or "width0" and
 * "width1", each segment split into 2^"split_depth" primitives. */
static CstStatus parse_curve(Loader *ld, const json_t *shape, int material, const CstAlpha *alpha)
{
    static const char *const bases[] = {"bezier", "bspline"};
    static const char *const types[] = {"flat", "cylinder", "ribbon"};
    CstCurvesDesc cd = {.material = material, .alpha = *alpha, .degree = 3, .split_depth = 3};
    json_t *v;
    json_int_t iv;
    int ctype = 0, ro = 0;
    float width = 1.0f;
    LOADER_TRY(read_choice(ld, shape, "basis", bases, 2, &cd.bspline));
    LOADER_TRY(read_choice(ld, shape, "curve_type", types, 3, &ctype));
    cd.type = (CstCurveType)ctype;
    if ((v = json_object_get(shape, "degree"))) {
        json_path_push_key(ld, "degree");
        LOADER_TRY(json_read_int(ld, v, 2, 3, &iv));
        json_path_pop(ld);
        cd.degree = (int)iv;
    }
    if ((v = json_object_get(shape, "split_depth"))) {
        json_path_push_key(ld, "split_depth");
        LOADER_TRY(json_read_int(ld, v, 0, 10, &iv));
        json_path_pop(ld);
        cd.split_depth = (int)iv;
    }
    if ((v = json_object_get(shape, "reverse_orientation"))) {
        json_path_push_key(ld, "reverse_orientation");
        LOADER_TRY(json_read_bool(ld, v, &ro));
        json_path_pop(ld);
        cd.reverse_orientation = ro;
    }
    LOADER_TRY(read_opt_float(ld, shape, "width", 1.0f, &width));
    LOADER_TRY(read_opt_float(ld, shape, "width0", width, &cd.width0));
    LOADER_TRY(read_opt_float(ld, shape, "width1", width, &cd.width1));
    if (!(cd.width0 >= 0.0f && cd.width1 >= 0.0f && cd.width0 + cd.width1 > 0.0f)) {
        json_path_push_key(ld, json_object_get(shape, "width1") ? "width1" : json_object_get(shape, "width0") ? "width0"
                                                                                                             : "width");
        return json_fail_here(ld, "widths %g and %g; expected widths >= 0, not both 0", (double)cd.width0,
                              (double)cd.width1);
    }
    LOADER_TRY(read_rows(ld, shape, cd.world_from_object));
    float *points = NULL, *normals = NULL;
    int npoints = 0, nnormals = 0;
    LOADER_TRY(json_member_required(ld, shape, "points", "an array of control points", &v));
    LOADER_TRY(read_points(ld, shape, "points", 3, &points, &npoints));
    cd.points = points;
    cd.num_points = npoints;
    CstError cerr;
    const int nseg = cst_curves_segments(&cd, &cerr);
    CstStatus st = CST_OK;
    if (nseg < 0) {
        json_path_push_key(ld, "points");
        st = json_fail_here(ld, "%d control points; expected %s for the degree %d %s basis", npoints,
                            cd.bspline ? "more than the degree" : (cd.degree == 3 ? "3n + 1" : "2n + 1"), cd.degree,
                            cd.bspline ? "B-spline" : "Bezier");
    } else if (cd.type == CST_CURVE_RIBBON) {
        if (!json_object_get(shape, "normals")) {
            st = json_fail_here(ld, "a ribbon curve without \"normals\"; expected one normal per segment end (%d)",
                                nseg + 1);
        } else if ((st = read_points(ld, shape, "normals", 1, &normals, &nnormals)) == CST_OK && nnormals != nseg + 1) {
            json_path_push_key(ld, "normals");
            st = json_fail_here(ld, "%d normals; expected one per segment end (%d)", nnormals, nseg + 1);
        }
        cd.normals = normals;
    } else if (json_object_get(shape, "normals")) {
        json_path_push_key(ld, "normals");
        st = json_fail_here(ld, "normals are for \"curve_type\": \"ribbon\" only; expected no normals");
    }
    if (st == CST_OK && (st = cst_scene_add_curves(ld->scene, &cd, ld->err)) != CST_OK) st = json_fail_builder(ld, st);
    free(points);
    free(normals);
    return st;
}

/* One node of an "sdf" tree and its subtree, appended to nodes[] in post-order (operands
 * before their operator); *index the node's. An operator's "children" (at least 2) fold
 * left: union [a, b, c] is union(union(a, b), c), difference [a, b, c] is (a - b) - c; its
 * "transform" goes on the last fold. */
static CstStatus parse_sdf_node(Loader *ld, const json_t *obj, CstSdfNode *nodes, int *count, int depth, int *index)
{
    static const char *const kinds[] = {"sphere", "box", "round_box", "torus", "capsule", "cylinder",
                                        "union", "intersection", "difference", "smooth_union"};
    static const char *const keys[][4] = {
        {"radius"}, {"half_size"}, {"half_size", "radius"}, {"major_radius", "minor_radius"},
        {"half_length", "radius"}, {"radius", "half_height"}, {"children"}, {"children"}, {"children"},
        {"children", "k"}};
    static const int nkeys[] = {1, 1, 2, 2, 2, 2, 1, 1, 1, 2};
    if (depth > SDF_MAX_DEPTH) return json_fail_here(ld, "the SDF tree is deeper than %d levels", SDF_MAX_DEPTH);
    LOADER_TRY(json_expect_object(ld, obj, "an SDF node object"));
    int kind = 0;
    LOADER_TRY(json_read_type(ld, obj, "SDF node type", kinds, 10, -1, &kind));
    const char *allowed[6] = {"type", "transform"};
    for (int k = 0; k < nkeys[kind]; k++) allowed[2 + k] = keys[kind][k];
    LOADER_TRY(json_check_keys(ld, obj, allowed, 2 + nkeys[kind]));
    CstSdfNode nd = {0};
    nd.kind = (CstSdfKind)kind;
    LOADER_TRY(read_rows(ld, obj, nd.parent_from_node));
    if (kind < CST_SDF_UNION) {
        float *c = nd.params;
        switch (kind) {
        case CST_SDF_SPHERE: LOADER_TRY(read_length(ld, obj, "radius", 0, &c[0])); break;
        case CST_SDF_BOX:
        case CST_SDF_ROUND_BOX: {
            json_t *v;
            Vec3 h;
            LOADER_TRY(json_member_required(ld, obj, "half_size", "an array of 3 numbers > 0", &v));
            json_path_push_key(ld, "half_size");
            LOADER_TRY(json_read_vec3(ld, v, LOADER_MAX_LENGTH, &h));
            if (!(h.x > 0.0f && h.y > 0.0f && h.z > 0.0f))
                return json_fail_here(ld, "half_size (%g, %g, %g); expected 3 numbers > 0", (double)h.x, (double)h.y, (double)h.z);
            json_path_pop(ld);
            c[0] = h.x, c[1] = h.y, c[2] = h.z;
            if (kind == CST_SDF_ROUND_BOX) {
                LOADER_TRY(read_length(ld, obj, "radius", 0, &c[3]));
                if (!(c[3] <= minf(h.x, minf(h.y, h.z)))) {
                    json_path_push_key(ld, "radius");
                    return json_fail_here(ld, "radius %g exceeds the smallest half_size %g; expected a rounding "
                                          "radius at most that", (double)c[3], (double)minf(h.x, minf(h.y, h.z)));
                }
            }
            break;
        }
        case CST_SDF_TORUS:
            LOADER_TRY(read_length(ld, obj, "major_radius", 0, &c[0]));
            LOADER_TRY(read_length(ld, obj, "minor_radius", 0, &c[1]));
            if (!(c[1] < c[0])) {
                json_path_push_key(ld, "minor_radius");
                return json_fail_here(ld, "minor_radius %g >= major_radius %g; expected minor < major", (double)c[1],
                                      (double)c[0]);
            }
            break;
        case CST_SDF_CAPSULE:
            LOADER_TRY(read_length(ld, obj, "half_length", 1, &c[0]));
            LOADER_TRY(read_length(ld, obj, "radius", 0, &c[1]));
            break;
        default:
            LOADER_TRY(read_length(ld, obj, "radius", 0, &c[0]));
            LOADER_TRY(read_length(ld, obj, "half_height", 0, &c[1]));
            break;
        }
    } else {
        char what[48];
        json_t *ch;
        LOADER_TRY(json_member_required(ld, obj, "children", "an array of at least 2 SDF nodes", &ch));
        json_path_push_key(ld, "children");
        if (!json_is_array(ch) || json_array_size(ch) < 2)
            return json_fail_here(ld, "got %s; expected an array of at least 2 SDF nodes",
                                  json_is_array(ch) ? "fewer than 2 nodes" : json_describe(ch, what));
        if (kind == CST_SDF_SMOOTH_UNION) {
            json_path_pop(ld);
            LOADER_TRY(read_length(ld, obj, "k", 0, &nd.k));
            json_path_push_key(ld, "children");
        }
        int acc = -1;
        for (size_t i = 0; i < json_array_size(ch); i++) {
            int child;
            json_path_push_index(ld, i);
            LOADER_TRY(parse_sdf_node(ld, json_array_get(ch, i), nodes, count, depth + 1, &child));
            json_path_pop(ld);
            if (acc < 0) { acc = child; continue; }
            if (*count >= SDF_MAX_NODES)
                return json_fail_here(ld, "the SDF tree has more than %d nodes", SDF_MAX_NODES);
            CstSdfNode op = nd;
            op.a = acc, op.b = child;
            if (i + 1 < json_array_size(ch)) memset(op.parent_from_node, 0, sizeof op.parent_from_node);
            nodes[*count] = op;
            acc = (*count)++;
        }
        json_path_pop(ld);
        *index = acc;
        return CST_OK;
    }
    if (*count >= SDF_MAX_NODES) return json_fail_here(ld, "the SDF tree has more than %d nodes", SDF_MAX_NODES);
    nodes[*count] = nd;
    *index = (*count)++;
    return CST_OK;
}

/* "sdf": a signed-distance CSG tree under "root", placed by "transform"; "epsilon" and
 * "max_steps" tune the sphere tracing (cst_scene_add_shape, CST_SHAPE_SDF). */
static CstStatus parse_sdf(Loader *ld, const json_t *shape, int material, const Emission *em, const CstAlpha *alpha)
{
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_SDF;
    sd.emission = emission_desc(em); /* refused by the builder: SDF shapes do not emit */
    LOADER_TRY(read_rows(ld, shape, sd.world_from_object));
    json_t *v;
    if ((v = json_object_get(shape, "epsilon"))) {
        json_path_push_key(ld, "epsilon");
        LOADER_TRY(json_read_float(ld, v, LOADER_MAX_LENGTH, &sd.sdf_epsilon));
        if (!(sd.sdf_epsilon > 0.0f)) return json_fail_here(ld, "epsilon %g; expected a number > 0", (double)sd.sdf_epsilon);
        json_path_pop(ld);
    }
    if ((v = json_object_get(shape, "max_steps"))) {
        json_int_t n = 0;
        json_path_push_key(ld, "max_steps");
        LOADER_TRY(json_read_int(ld, v, 1, SDF_MAX_STEPS, &n));
        json_path_pop(ld);
        sd.sdf_max_steps = (int)n;
    }
    CstSdfNode *nodes = calloc(SDF_MAX_NODES, sizeof *nodes);
    if (!nodes) return json_fail_here(ld, "out of memory for an SDF tree");
    int count = 0, root = -1;
    CstStatus st = json_member_required(ld, shape, "root", "an SDF node object", &v);
    if (st == CST_OK) {
        json_path_push_key(ld, "root");
        st = parse_sdf_node(ld, v, nodes, &count, 1, &root);
        if (st == CST_OK) json_path_pop(ld);
    }
    if (st == CST_OK) {
        sd.sdf_nodes = nodes;
        sd.sdf_num_nodes = count;
        sd.material = material;
        sd.alpha = *alpha;
        st = cst_scene_add_shape(ld->scene, &sd, ld->err);
        if (st != CST_OK) st = json_fail_builder(ld, st);
    }
    free(nodes);
    return st;
}

/* A shape's "alpha" (pbrt-v4's Shape "alpha"): a number from 0 to 1 or the name of a
 * texture with values at most 1, whose scalar (mean of the channels) is the alpha at the
 * shape's uvs. Absent: opaque. */
static CstStatus read_alpha(Loader *ld, const json_t *shape, CstAlpha *out)
{
    json_t *v = json_object_get(shape, "alpha");
    char kind[48];
    memset(out, 0, sizeof *out);
    if (!v) return CST_OK;
    json_path_push_key(ld, "alpha");
    if (json_is_string(v)) {
        LOADER_TRY(json_read_param_texture(ld, v, "an alpha", &out->texture));
    } else if (json_is_number(v)) {
        LOADER_TRY(json_read_float(ld, v, 1.0, &out->value));
        if (!(out->value >= 0.0f))
            return json_fail_here(ld, "alpha %g is negative; expected a number from 0 to 1", (double)out->value);
    } else {
        return json_fail_here(ld, "got %s; expected a number from 0 to 1 or a texture name", json_describe(v, kind));
    }
    out->enabled = 1;
    json_path_pop(ld);
    return CST_OK;
}

static CstStatus parse_shape(Loader *ld, const json_t *shape)
{
    static const char *const types[] = {"quad", "mesh", "sphere", "meshfile", "cylinder", "disk", "torus", "sdf",
                                        "curve"};
    static const char *const torus_keys[] = {"type", "major_radius", "minor_radius", "transform", "material",
                                             "emission", "alpha", "medium", "motion"};
    static const char *const sdf_keys[] = {"type", "root", "transform", "epsilon", "max_steps", "material",
                                           "emission", "alpha", "medium"};
    static const char *const curve_keys[] = {"type", "points", "basis", "degree", "curve_type", "width", "width0",
                                             "width1", "normals", "split_depth", "transform", "reverse_orientation",
                                             "material", "alpha"};
    static const char *const quad_keys[] = {"type", "vertices", "material", "emission", "alpha", "medium"};
    static const char *const mesh_keys[] = {"type", "vertices", "indices", "uvs", "material", "emission",
                                            "normals", "shading", "alpha", "medium", "displacement", "motion"};
    static const char *const sphere_keys[] = {"type", "center", "radius", "material", "emission", "alpha",
                                              "z_min", "z_max", "phi_max", "transform", "reverse_orientation",
                                              "medium", "motion"};
    static const char *const cylinder_keys[] = {"type", "radius", "z_min", "z_max", "phi_max", "transform",
                                                "reverse_orientation", "material", "emission", "alpha", "medium",
                                                "motion"};
    static const char *const disk_keys[] = {"type", "radius", "height", "inner_radius", "phi_max", "transform",
                                            "reverse_orientation", "material", "emission", "alpha", "medium",
                                            "motion"};
    static const char *const meshfile_keys[] = {"type", "file", "material", "emission",
                                                "transform", "shading", "alpha", "medium", "displacement"};
    int type = 0, material = -1;
    Emission em = {0};
    LOADER_TRY(json_expect_object(ld, shape, "a shape object"));
    LOADER_TRY(json_read_type(ld, shape, "shape type", types, 9, -1, &type));
    switch (type) {
    case SHAPE_QUAD: LOADER_TRY(json_check_keys(ld, shape, quad_keys, 6)); break;
    case SHAPE_MESH: LOADER_TRY(json_check_keys(ld, shape, mesh_keys, 12)); break;
    case SHAPE_MESHFILE: LOADER_TRY(json_check_keys(ld, shape, meshfile_keys, 9)); break;
    case SHAPE_CYLINDER: LOADER_TRY(json_check_keys(ld, shape, cylinder_keys, 12)); break;
    case SHAPE_DISK: LOADER_TRY(json_check_keys(ld, shape, disk_keys, 12)); break;
    case SHAPE_TORUS: LOADER_TRY(json_check_keys(ld, shape, torus_keys, 9)); break;
    case SHAPE_SDF: LOADER_TRY(json_check_keys(ld, shape, sdf_keys, 9)); break;
    case SHAPE_CURVE: LOADER_TRY(json_check_keys(ld, shape, curve_keys, 14)); break;
    default: LOADER_TRY(json_check_keys(ld, shape, sphere_keys, 13)); break;
    }
    int boundary = 0;
    LOADER_TRY(json_read_shape_medium(ld, shape, &boundary));
    /* A mesh file may bring its own materials: then "material" is optional (-1 = none);
     * so may a pure medium boundary, which has no surface. */
    if ((type != SHAPE_MESHFILE && !boundary) || json_object_get(shape, "material"))
        LOADER_TRY(json_read_material_ref(ld, shape, &material));
    if (boundary && material < 0) LOADER_TRY(json_boundary_material(ld, &material));
    LOADER_TRY(json_read_emission(ld, shape, &em));
    CstAlpha alpha = {0};
    LOADER_TRY(read_alpha(ld, shape, &alpha));
    switch (type) {
    case SHAPE_QUAD: return parse_quad(ld, shape, material, &em, &alpha);
    case SHAPE_MESH: return parse_mesh(ld, shape, material, &em, &alpha);
    case SHAPE_MESHFILE: return parse_meshfile(ld, shape, material, &em, &alpha);
    case SHAPE_CYLINDER:
    case SHAPE_DISK: return parse_analytic(ld, shape, type, material, &em, &alpha, 0);
    case SHAPE_TORUS: return parse_torus(ld, shape, material, &em, &alpha);
    case SHAPE_SDF: return parse_sdf(ld, shape, material, &em, &alpha);
    case SHAPE_CURVE: return parse_curve(ld, shape, material, &alpha);
    default:
        if (json_object_get(shape, "z_min") || json_object_get(shape, "z_max") || json_object_get(shape, "phi_max") ||
            json_object_get(shape, "transform") || json_object_get(shape, "reverse_orientation"))
            return parse_analytic(ld, shape, type, material, &em, &alpha, 0);
        if (json_object_get(shape, "motion")) return parse_analytic(ld, shape, type, material, &em, &alpha, 1);
        return parse_sphere(ld, shape, material, &em, &alpha);
    }
}

CstStatus json_parse_shapes(Loader *ld, const json_t *shapes)
{
    char kind[48];
    if (!json_is_array(shapes))
        return json_fail_here(ld, "got %s; expected an array of shapes", json_describe(shapes, kind));
    /* An empty world renders, as in pbrt-v4: every ray misses (the environment, or black). */
    if (json_array_size(shapes) == 0 && ld->opt && ld->opt->warning) {
        char msg[300];
        snprintf(msg, sizeof msg, "%.200s: \"shapes\" is empty: the world has no shapes (every ray "
                 "misses)", ld->name);
        ld->opt->warning(ld->opt->warning_user, CST_WARN_GEOMETRY, msg);
    }
    size_t i;
    json_t *shape;
    json_array_foreach(shapes, i, shape) {
        json_path_push_index(ld, i);
        LOADER_TRY(parse_shape(ld, shape));
        json_path_pop(ld);
    }
    return CST_OK;
}
