/* cst_scene_add_curves: a whole pbrt-v4 curve (control points, basis, degree, widths,
 * ribbon normals) split into its cubic Bezier segments, each added by cst_scene_add_shape.
 * Shared by the pbrt loader's "curve" and the JSON format's "curve" shape. */
#include <stdbool.h>

#include "caustic/caustic.h"
#include "core/error.h"
#include "geometry/curve.h"

int cst_curves_segments(const CstCurvesDesc *d, CstError *err)
{
    static const char fn[] = "cst_curves_segments";
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn), -1;
    if (d->degree != 2 && d->degree != 3)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: degree %d; expected 2 or 3", fn, d->degree), -1;
    const int n = d->num_points, deg = d->degree;
    const bool ok = d->bspline ? n > deg : n >= deg + 1 && (n - 1) % deg == 0;
    if (!d->points || !ok)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %d control points; expected %s for the degree %d %s basis",
                        fn, d->points ? n : 0, d->bspline ? "more than the degree" : (deg == 3 ? "3n + 1" : "2n + 1"),
                        deg, d->bspline ? "B-spline" : "Bezier"), -1;
    return d->bspline ? n - deg : (n - 1) / deg;
}

CstStatus cst_scene_add_curves(CstScene *scene, const CstCurvesDesc *d, CstError *err)
{
    static const char fn[] = "cst_scene_add_curves";
    cst_error_clear(err);
    const int nseg = cst_curves_segments(d, err);
    if (nseg < 0) return err ? err->status : CST_ERR_INVALID_ARG;
    if (d->type == CST_CURVE_RIBBON && !d->normals)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: a ribbon without normals; expected one per segment end (%d)",
                        fn, nseg + 1);
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_CURVE;
    sd.curve_type = d->type;
    sd.curve_split_depth = d->split_depth;
    sd.reverse_orientation = d->reverse_orientation;
    sd.alpha = d->alpha;
    sd.material = d->material;
    for (int k = 0; k < 12; k++) sd.world_from_object[k] = d->world_from_object[k];
    for (int seg = 0; seg < nseg; seg++) {
        Vec3 cp[4], b[4];
        const int first = d->bspline ? seg : seg * d->degree;
        for (int i = 0; i <= d->degree; i++) {
            const float *p = d->points + 3 * (first + i);
            cp[i] = v3(p[0], p[1], p[2]);
        }
        curve_bezier_segment(cp, d->degree, d->bspline != 0, 0, b); /* cp holds this segment's points */
        for (int k = 0; k < 4; k++)
            for (int c = 0; c < 3; c++) sd.curve_p[k][c] = v3_get(b[k], c);
        /* pbrt-v4: the widths linear over the segments */
        const float a0 = (float)seg / (float)nseg, a1 = (float)(seg + 1) / (float)nseg;
        sd.curve_width[0] = d->width0 + a0 * (d->width1 - d->width0);
        sd.curve_width[1] = d->width0 + a1 * (d->width1 - d->width0);
        if (d->type == CST_CURVE_RIBBON)
            for (int k = 0; k < 2; k++)
                for (int c = 0; c < 3; c++) sd.curve_normals[k][c] = d->normals[3 * (seg + k) + c];
        const CstStatus st = cst_scene_add_shape(scene, &sd, err);
        if (st != CST_OK) return st;
    }
    return CST_OK;
}
