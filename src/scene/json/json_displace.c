/* A mesh's "displacement": {"texture", "edgelength"} read and applied through
 * cst_scene_displace_mesh (true displacement, as pbrt-v4's plymesh "displacement"). */
#include "scene/json/json_displace.h"

#include <float.h>
#include <stdlib.h>
#include <string.h>

#include "scene/json/json_texture.h"

static void xf_rows(const Transform *t, float rows[12])
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) rows[4 * r + c] = t->m[r][c];
}

/* The displaced mesh in place of m's arrays; the per-triangle values through parents. */
static CstStatus take_mesh(Loader *ld, CstDisplacedMesh *d, JsonMesh *m)
{
    int *tm = NULL;
    if (m->tri_mat) {
        tm = malloc((size_t)d->num_triangles * sizeof *tm);
        if (!tm) {
            cst_displaced_mesh_free(d);
            return json_fail_at(ld, CST_ERR_OOM, "out of memory for %d triangles", d->num_triangles);
        }
        for (int t = 0; t < d->num_triangles; t++) tm[t] = m->tri_mat[d->parents[t]];
    }
    free(m->p);
    free(m->n);
    free(m->uv);
    free(m->idx);
    free(m->tri_mat);
    m->p = (Vec3 *)(void *)d->positions;
    m->n = (Vec3 *)(void *)d->normals;
    m->uv = (Vec2 *)(void *)d->uvs;
    m->idx = d->indices;
    m->nv = d->num_vertices;
    m->nt = d->num_triangles;
    m->tri_mat = tm;
    free(d->parents);
    return CST_OK;
}

CstStatus json_read_displacement(Loader *ld, const json_t *shape, const Transform *xf, JsonMesh *m)
{
    static const char *const keys[] = {"texture", "edgelength"};
    json_t *obj = json_object_get(shape, "displacement"), *tv, *ev;
    if (!obj) return CST_OK;
    json_path_push_key(ld, "displacement");
    LOADER_TRY(json_expect_object(ld, obj, "a displacement object {\"texture\": a texture name or a number, "
                                           "\"edgelength\": a length > 0}"));
    LOADER_TRY(json_check_keys(ld, obj, keys, 2));
    LOADER_TRY(json_member_required(ld, obj, "texture", "a float texture's name or a number (a constant "
                                                        "displacement, in the mesh's units)", &tv));
    LOADER_TRY(json_member_required(ld, obj, "edgelength", "the longest edge the tessellation may keep, "
                                                           "a length > 0 in scene units", &ev));
    CstDisplaceDesc dd = {0};
    json_path_push_key(ld, "texture");
    if (json_is_string(tv)) {
        int id = 0;
        LOADER_TRY(json_read_texture_name(ld, json_string_value(tv), &id));
        dd.texture = id + 1;
    } else {
        LOADER_TRY(json_read_float(ld, tv, LOADER_MAX_LENGTH, &dd.value));
    }
    json_path_pop(ld);
    json_path_push_key(ld, "edgelength");
    LOADER_TRY(json_read_float(ld, ev, (double)FLT_MAX, &dd.edge_length));
    if (!(dd.edge_length > 0.0f))
        return json_fail_here(ld, "edgelength %g; expected a length > 0 (the longest edge the displaced mesh "
                                  "may keep)", (double)dd.edge_length);
    json_path_pop(ld);
    dd.positions = &m->p[0].x;
    dd.normals = m->n ? &m->n[0].x : NULL;
    dd.uvs = m->uv ? &m->uv[0].x : NULL;
    dd.num_vertices = m->nv;
    dd.indices = m->idx;
    dd.num_triangles = m->nt;
    if (xf && !transform_is_identity(xf)) {
        xf_rows(xf, dd.measure_from_object);
        xf_rows(xf, dd.texture_from_object);
    }
    CstDisplacedMesh out;
    CstStatus st = cst_scene_displace_mesh(ld->scene, &dd, &out, ld->err);
    if (st != CST_OK) return json_fail_builder(ld, st);
    LOADER_TRY(take_mesh(ld, &out, m));
    json_path_pop(ld);
    return CST_OK;
}
