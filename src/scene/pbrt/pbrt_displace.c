/* pbrt-v4's plymesh "displacement" and "edgelength" (shapes.cpp, TriQuadMesh::Displace):
 * the tessellation and displacement asked of the public builder, in pbrt-v4's spaces. */
#include "scene/pbrt/pbrt_displace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_shape.h"
#include "scene/pbrt/pbrt_texture.h"

/* The 3 x 4 rows of t's affine part (transform_point's). */
static void xf_rows(const Transform *t, float rows[12])
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) rows[4 * r + c] = t->m[r][c];
}

CstStatus pbrt_displace_shape(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g)
{
    float edge = 1.0f;
    TRY(pbrt_get_float(ld, ps, d, "edgelength", 1.0f, &edge, NULL));
    Param *p = pbrt_find_param(ps, "displacement");
    if (!p || p->type != PT_TEXTURE) return CST_OK; /* a "float displacement" stays unused, warned */
    int tex = 0;
    Color val = color_s(0.0f);
    TRY(pbrt_tex_param(ld, ps, d, "displacement", 1, &tex, &val, NULL));
    Param *pe = pbrt_find_param(ps, "edgelength");
    if (!(edge > 0.0f)) /* pbrt-v4 would split forever */
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pe ? pe->loc : loc, "%s: \"edgelength\" %g; expected a "
                            "length > 0 (the longest edge the displaced mesh may keep)", d, (double)edge);
    if (!g->uv)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: \"displacement\" needs vertex uvs, which the "
                            "mesh has not (pbrt-v4 stops with an error too); expected a PLY with u, v", d);
    /* pbrt-v4's render space is "cameraworld" by default: world translated to the camera's
     * position (caustic ignores Option "rendercoordsys"). Edges are measured there, and the
     * texture reads the object-space point as a render-space one, so a solid texture sees
     * world_from_render(p_object) = p_object + the camera's position. */
    Vec3 cam = v3s(0.0f);
    if (ld->cam.set && ld->cam.ctm.inv_ok) cam = transform_point(&ld->cam.ctm.inv, v3s(0.0f));
    Transform render_from_object = transform_compose(transform_translate(v3_neg(cam)), ld->gs.ctm.m);
    CstDisplaceDesc dd = {0};
    dd.positions = &g->p[0].x;
    dd.normals = g->n ? &g->n[0].x : NULL;
    dd.uvs = &g->uv[0].x;
    dd.num_vertices = g->nv;
    dd.indices = g->idx;
    dd.num_triangles = g->nt;
    dd.texture = tex;
    dd.value = color_channel(val, 0);
    dd.edge_length = edge;
    xf_rows(&render_from_object, dd.measure_from_object);
    if (cam.x != 0.0f || cam.y != 0.0f || cam.z != 0.0f) {
        Transform world_from_render = transform_translate(cam);
        xf_rows(&world_from_render, dd.texture_from_object);
    }
    int64_t cap = (int64_t)PBRT_MAX_TRIANGLES - ld->num_triangles;
    if (cap > CST_DISPLACE_MAX_TRIANGLES) cap = CST_DISPLACE_MAX_TRIANGLES;
    dd.max_triangles = cap < g->nt ? g->nt : (int)cap; /* beyond the scene's limit: emit_shape says so */
    CstDisplacedMesh m;
    CstStatus st = cst_scene_displace_mesh(ld->scene, &dd, &m, ld->err);
    if (st == CST_ERR_OOM) return pbrt_oom(ld);
    if (st) return pbrt_fail_wrap(ld, st, loc, d);
    pbrt_geom_free(g);
    g->p = (Vec3 *)(void *)m.positions;
    g->n = (Vec3 *)(void *)m.normals;
    g->uv = (Vec2 *)(void *)m.uvs;
    g->nv = m.num_vertices;
    g->idx = m.indices;
    g->nt = m.num_triangles;
    free(m.parents);
    return CST_OK;
}
