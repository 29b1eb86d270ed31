/* The public builder's true displacement (cst_scene_displace_mesh): validates a
 * CstDisplaceDesc, runs geometry/displace.c with the scene's texture as the displacement. */
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/displace.h"
#include "scene/scene.h"
#include "scene/scene_build_check.h"
#include "textures/texture.h"

/* What the displacement function reads: the scene's textures, or a constant. */
typedef struct DisplaceTex {
    const Texture *textures;
    int id; /* 0-based, or -1: value */
    float value;
    const Transform *tex_xf; /* texture_from_object, NULL: identity */
} DisplaceTex;

/* The texture's channel mean at the vertex, with no footprint (pbrt-v4 evaluates its
 * displacement with a TextureEvalContext of p and uv alone: the finest MIP level, every
 * noise octave); the normal is given too (pbrt-v4 leaves it zero: see pbrt-compat.md). */
static float displace_value(void *user, Vec3 p, Vec3 n, Vec2 uv)
{
    const DisplaceTex *dt = user;
    if (dt->id < 0) return dt->value;
    TexCtx c = {.uv = uv, .p = dt->tex_xf ? transform_point(dt->tex_xf, p) : p, .n = n};
    return texture_eval_scalar_ctx(dt->textures, dt->id, &c);
}

/* rows (3 x 4, all zero: identity) as a Transform; false when not finite. */
static bool rows_transform(const float rows12[12], Transform *xf, bool *identity)
{
    float rows[16] = {0};
    bool zero = true;
    for (int k = 0; k < 12; k++) {
        if (!isfinite(rows12[k])) return false;
        rows[k] = rows12[k];
        zero &= rows[k] == 0.0f;
    }
    rows[15] = 1.0f;
    *identity = zero;
    *xf = zero ? transform_identity() : transform_from_rows(rows);
    return true;
}

static CstStatus check_desc(const Scene *s, const CstDisplaceDesc *d, const char *fn, CstError *err)
{
    if (!s) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene is NULL", fn);
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    if (d->num_vertices <= 0 || d->num_triangles <= 0 || !d->positions || !d->indices)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d vertices and %d triangles (positions %s, indices %s); "
                        "expected at least one of each, with their arrays", fn, d->num_vertices, d->num_triangles,
                        d->positions ? "given" : "NULL", d->indices ? "given" : "NULL");
    if (!(d->edge_length > 0.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: edge_length %g; expected a length > 0", fn,
                        (double)d->edge_length);
    int max = d->max_triangles ? d->max_triangles : CST_DISPLACE_MAX_TRIANGLES;
    if (max < d->num_triangles || max > INT32_MAX / 3)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: max_triangles %d; expected 0 (the default, %d) or from "
                        "num_triangles (%d) to %d", fn, d->max_triangles, CST_DISPLACE_MAX_TRIANGLES,
                        d->num_triangles, INT32_MAX / 3);
    CstStatus st = check_texture_id(s, d->texture, 1, fn, "texture", err);
    if (st != CST_OK) return st;
    if (!d->texture && !isfinite(d->value))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: value %g; expected a finite displacement", fn, (double)d->value);
    for (int i = 0; i < 3 * d->num_vertices; i++)
        if (!(fabsf(d->positions[i]) <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: position of vertex %d is not finite or beyond 1e18",
                            fn, i / 3);
    for (int i = 0; d->uvs && i < 2 * d->num_vertices; i++)
        if (!isfinite(d->uvs[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: uv of vertex %d is not finite", fn, i / 2);
    for (int i = 0; i < 3 * d->num_triangles; i++)
        if (d->indices[i] < 0 || d->indices[i] >= d->num_vertices)
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: triangle %d: vertex index %d is out of range; "
                            "expected 0 to %d", fn, i / 3, d->indices[i], d->num_vertices - 1);
    return CST_OK;
}

CstStatus cst_scene_displace_mesh(const CstScene *scene, const CstDisplaceDesc *d, CstDisplacedMesh *out,
                                  CstError *err)
{
    static const char fn[] = "cst_scene_displace_mesh";
    cst_error_clear(err);
    if (!out) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: out is NULL", fn);
    memset(out, 0, sizeof *out);
    CstStatus st = check_desc(scene, d, fn, err);
    if (st != CST_OK) return st;
    Transform measure, tex_xf;
    bool measure_id, tex_id;
    if (!rows_transform(d->measure_from_object, &measure, &measure_id) ||
        !rows_transform(d->texture_from_object, &tex_xf, &tex_id))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: measure_from_object or texture_from_object has an entry "
                        "that is not finite", fn);
    /* Vec3 and Vec2 are packed floats: the caller's arrays are read in place, but the
     * normals, which are normalised first (a zero one stays zero). */
    Vec3 *n = NULL;
    if (d->normals) {
        n = malloc((size_t)d->num_vertices * sizeof *n);
        if (!n) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for %d normals", fn, d->num_vertices);
        for (int i = 0; i < d->num_vertices; i++) {
            Vec3 v = v3(d->normals[3 * i], d->normals[3 * i + 1], d->normals[3 * i + 2]);
            float m = v3_max_abs(v);
            n[i] = v3_is_finite(v) && m > 0.0f ? v3_normalize(v3_scale(v, 1.0f / m)) : v3s(0.0f);
        }
    }
    DisplaceTex dt = {scene->textures, d->texture - 1, d->value, tex_id ? NULL : &tex_xf};
    DisplaceInput in = {(const Vec3 *)(const void *)d->positions, n, (const Vec2 *)(const void *)d->uvs,
                        d->num_vertices, d->indices, d->num_triangles, measure_id ? NULL : &measure,
                        d->edge_length, d->max_triangles ? d->max_triangles : CST_DISPLACE_MAX_TRIANGLES,
                        displace_value, &dt};
    DisplacedMesh m;
    CstError sub;
    st = displace_mesh(&in, &m, &sub);
    free(n);
    if (st != CST_OK) return cst_fail(err, st, "%s: %s", fn, sub.msg);
    for (int i = 0; i < m.nv; i++)
        if (!((double)v3_max_abs(m.p[i]) <= (double)BUILD_MAX_LENGTH)) {
            st = cst_fail(err, CST_ERR_INVALID_ARG, "%s: displaced vertex %d is at (%g, %g, %g), beyond 1e18; "
                          "expected a smaller displacement", fn, i, (double)m.p[i].x, (double)m.p[i].y,
                          (double)m.p[i].z);
            displaced_mesh_free(&m);
            return st;
        }
    out->positions = (float *)(void *)m.p;
    out->normals = (float *)(void *)m.n;
    out->uvs = (float *)(void *)m.uv;
    out->num_vertices = m.nv;
    out->indices = m.idx;
    out->parents = m.parent;
    out->num_triangles = m.nt;
    return CST_OK;
}

void cst_displaced_mesh_free(CstDisplacedMesh *m)
{
    if (!m) return;
    free(m->positions);
    free(m->normals);
    free(m->uvs);
    free(m->indices);
    free(m->parents);
    memset(m, 0, sizeof *m);
}
