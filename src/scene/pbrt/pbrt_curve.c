/* pbrt-v4's "curve" shape (CreateCurves) read into a CstCurvesDesc for
 * cst_scene_add_curves. */
#include "scene/pbrt/pbrt_curve.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "scene/pbrt/pbrt_material.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_shape.h"
#include "scene/pbrt/pbrt_transform.h"

/* pbrt-v4's "curve" (CreateCurves): P as cubic or quadratic Bezier segments sharing their
 * end points ("basis" "bezier", 3n + 1 or 2n + 1 points) or a uniform B-spline ("bspline",
 * n + degree points), each converted to a cubic Bezier; "type" flat, cylinder or ribbon
 * (with "N": one normal per segment end); widths interpolated over the segments from
 * "width0" to "width1" (both "width", default 1); every segment split into 2^splitdepth
 * primitives (default 3). Curves are analytic shapes (geometry/curve.c): in an object, as
 * an interface or emitting they are skipped with a warning. */
CstStatus pbrt_curve_shape(Loader *ld, Params *ps, const char *d, Loc loc)
{
    Param *pp, *pn;
    const char *basis = NULL, *type = NULL;
    Loc bl = loc, tl = loc;
    int degree = 3, split = 3;
    float width = 1.0f, w0 = 1.0f, w1 = 1.0f;
    TRY(pbrt_lookup(ld, ps, d, "P", PT_MASK(PT_POINT3), "point3", &pp));
    TRY(pbrt_lookup(ld, ps, d, "N", PT_MASK(PT_NORMAL), "normal", &pn));
    TRY(pbrt_get_string(ld, ps, d, "basis", &basis, &bl));
    TRY(pbrt_get_string(ld, ps, d, "type", &type, &tl));
    TRY(pbrt_get_int(ld, ps, d, "degree", 3, &degree));
    TRY(pbrt_get_int(ld, ps, d, "splitdepth", 3, &split));
    TRY(pbrt_get_float(ld, ps, d, "width", 1.0f, &width, NULL));
    TRY(pbrt_get_float(ld, ps, d, "width0", width, &w0, NULL));
    TRY(pbrt_get_float(ld, ps, d, "width1", width, &w1, NULL));
    const bool bspline = basis && strcmp(basis, "bspline") == 0;
    if (basis && !bspline && strcmp(basis, "bezier") != 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, bl, "%s: basis \"%s\"; expected \"bezier\" or \"bspline\"", d, basis);
    CstCurveType ct = CST_CURVE_FLAT;
    if (type && strcmp(type, "ribbon") == 0) ct = CST_CURVE_RIBBON;
    else if (type && strcmp(type, "cylinder") == 0) ct = CST_CURVE_CYLINDER;
    else if (type && strcmp(type, "flat") != 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "%s: type \"%s\"; expected \"flat\", \"cylinder\" or \"ribbon\"", d, type);
    if (degree != 2 && degree != 3)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: degree %d; expected 2 or 3", d, degree);
    if (split < 0 || split > 10)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: splitdepth %d; expected 0 to 10", d, split);
    if (!(w0 >= 0.0f && w1 >= 0.0f && w0 + w1 > 0.0f) || !pbrt_coords_ok(v3(w0, w1, 0.0f)))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: widths %g and %g; expected widths >= 0, not both 0",
                            d, (double)w0, (double)w1);
    if (!pp)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"point3 P\"; expected the control points", d);
    const int ncp = pp->num_nums / 3;
    int nseg = bspline ? ncp - degree : (ncp - 1) / degree;
    if (bspline ? ncp <= degree : (ncp < degree + 1 || (ncp - 1) % degree != 0))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pp->loc, "%s: %d control points; expected %s for the degree %d %s "
                            "basis", d, ncp, bspline ? "more than the degree" : (degree == 3 ? "3n + 1" : "2n + 1"),
                            degree, bspline ? "B-spline" : "Bezier");
    if (ct == CST_CURVE_RIBBON && (!pn || pn->num_nums != 3 * (nseg + 1)))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pn ? pn->loc : loc, "%s: a ribbon with %d normals; expected "
                            "\"normal N\" with one normal per segment end (%d)", d, pn ? pn->num_nums / 3 : 0, nseg + 1);
    if (pn && ct != CST_CURVE_RIBBON)
        pbrt_warn_at(ld, CST_WARN_PARAMETER_IGNORED, pn->loc, "%s: \"N\" is used by ribbons only; ignored", d);
    CstAlpha alpha = {0};
    TRY(pbrt_shape_alpha(ld, ps, d, &alpha));
    pbrt_params_warn_unused(ld, ps, d);
    if (ld->cur_obj >= 0 || ld->mats[ld->gs.material].interface || ld->gs.area.active ||
        !transform_is_affine(&ld->gs.ctm.m)) {
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s in an object, as an interface, emitting or under a projective "
                     "transform is not supported; skipped", d);
        return CST_OK;
    }
    pbrt_warn_static(ld, loc, d, "curves do not move in caustic (triangle shapes and quadrics do)");
    if (alpha.enabled && !alpha.texture && alpha.value == 0.0f) return CST_OK; /* as emit_shape's callers */
    const int nnorm = ct == CST_CURVE_RIBBON ? nseg + 1 : 0;
    float *cp = malloc((size_t)(ncp + nnorm) * 3 * sizeof *cp);
    if (!cp) return pbrt_fail_at(ld, CST_ERR_OOM, loc, "%s: out of memory for %d control points", d, ncp);
    for (int i = 0; i < 3 * ncp; i++) cp[i] = (float)pp->nums[i];
    for (int i = 0; i < ncp; i++)
        if (!pbrt_coords_ok(v3(cp[3 * i], cp[3 * i + 1], cp[3 * i + 2]))) {
            free(cp);
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pp->loc, "%s: control point %d is beyond the scene limit; "
                                "expected coordinates of magnitude at most %g", d, i, PBRT_MAX_LENGTH);
        }
    for (int i = 0; i < 3 * nnorm; i++) cp[3 * ncp + i] = (float)pn->nums[i];
    CstCurvesDesc cd = {.points = cp, .num_points = ncp, .degree = degree, .bspline = bspline, .width0 = w0,
                        .width1 = w1, .type = ct, .normals = nnorm ? cp + 3 * ncp : NULL, .split_depth = split,
                        .reverse_orientation = ld->gs.reverse != 0, .alpha = alpha};
    const Transform *m = &ld->gs.ctm.m;
    if (!transform_is_identity(m))
        for (int r = 0; r < 3; r++)
            for (int c = 0; c < 4; c++) cd.world_from_object[4 * r + c] = m->m[r][c];
    CstStatus st = pbrt_material_scene_id(ld, ld->gs.material, &cd.material);
    if (st == CST_OK && (st = cst_scene_add_curves(ld->scene, &cd, ld->err)) != CST_OK)
        st = pbrt_fail_wrap(ld, st, loc, d);
    free(cp);
    return st;
}
