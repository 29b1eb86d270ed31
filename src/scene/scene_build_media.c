/* The public scene builder's participating media (cst_scene_add_medium, medium
 * interfaces, the camera's medium), validated as scene_build.c validates the rest. */
#include <float.h>
#include <math.h>

#include "core/error.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

void cst_medium_desc_init(CstMediumDesc *d)
{
    if (!d) return;
    *d = (CstMediumDesc){{1.0f, 1.0f, 1.0f}, {1.0f, 1.0f, 1.0f}, 1.0f, 0.0f, {0.0f, 0.0f, 0.0f}, 1.0f};
}

static CstStatus read_scale(float v, const char *fn, const char *what, CstError *err)
{
    if (!(v >= 0.0f && v <= FLT_MAX))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s %g; expected a finite value >= 0", fn, what, (double)v);
    return CST_OK;
}

CstStatus cst_scene_add_medium(CstScene *scene, const CstMediumDesc *d, int *out_id, CstError *err)
{
    const char *fn = "cst_scene_add_medium";
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d || !out_id) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc and out_id must not be NULL", fn);
    Medium m = {0};
    m.type = MEDIUM_HOMOGENEOUS;
    Color sa, ss, le;
    if ((st = read_rgb(d->sigma_a, 0, fn, "sigma_a", &sa, err)) != CST_OK ||
        (st = read_rgb(d->sigma_s, 0, fn, "sigma_s", &ss, err)) != CST_OK ||
        (st = read_rgb(d->le, 0, fn, "le", &le, err)) != CST_OK ||
        (st = read_scale(d->scale, fn, "scale", err)) != CST_OK ||
        (st = read_scale(d->le_scale, fn, "le_scale", err)) != CST_OK)
        return st;
    if (!(fabsf(d->g) < 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: g %g; expected a value in (-1, 1)", fn, (double)d->g);
    m.g = d->g;
    m.u.homog.sigma_a = color_scale(sa, d->scale);
    m.u.homog.sigma_s = color_scale(ss, d->scale);
    m.u.homog.le = color_scale(le, d->le_scale);
    /* Products of finite values may overflow: checked by scene_add_medium (finite). */
    return scene_add_medium(scene, &m, out_id, err);
}

CstStatus cst_scene_set_medium_interface(CstScene *scene, int inside, int outside, int boundary, CstError *err)
{
    CstStatus st = check_scene(scene, "cst_scene_set_medium_interface", err);
    if (st != CST_OK) return st;
    return scene_set_medium_interface(scene, inside, outside, boundary, err);
}

CstStatus cst_scene_set_camera_medium(CstScene *scene, int medium, CstError *err)
{
    CstStatus st = check_scene(scene, "cst_scene_set_camera_medium", err);
    if (st != CST_OK) return st;
    return scene_set_camera_medium(scene, medium, err);
}
