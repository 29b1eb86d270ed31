/* The public scene builder's participating media (cst_scene_add_medium, medium
 * interfaces, the camera's medium), validated as scene_build.c validates the rest. */
#include <float.h>
#include <math.h>
#include <stdint.h>
#include <string.h>

#include "core/error.h"
#include "media/medium_presets.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

void cst_medium_desc_init(CstMediumDesc *d)
{
    if (!d) return;
    memset(d, 0, sizeof *d);
    for (int i = 0; i < 3; i++) d->sigma_a[i] = d->sigma_s[i] = 1.0f;
    d->scale = d->le_scale = 1.0f;
    d->type = CST_MEDIUM_HOMOGENEOUS;
    d->world_from_medium[0] = d->world_from_medium[5] = d->world_from_medium[10] = 1.0f;
    d->p1[0] = d->p1[1] = d->p1[2] = 1.0f;
    d->nx = d->ny = d->nz = 1;
    d->cloud_density = 1.0f;
    d->wispiness = 1.0f;
    d->frequency = 5.0f;
}

/* The heterogeneous part of d into m (arrays borrowed: scene_add_medium copies them). */
static CstStatus read_hetero(const CstMediumDesc *d, const char *fn, Medium *m, CstError *err)
{
    HeteroMedium *h = &m->u.het;
    m->type = d->type == CST_MEDIUM_CLOUD ? MEDIUM_CLOUD : MEDIUM_GRID;
    h->cloud = d->type == CST_MEDIUM_CLOUD;
    float rows[16] = {0};
    memcpy(rows, d->world_from_medium, sizeof d->world_from_medium);
    rows[15] = 1.0f;
    Transform w = transform_from_rows(rows);
    if (!transform_is_affine(&w) || !transform_invert(&w, &h->medium_from_world))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_medium is not a finite invertible affine transform",
                        fn);
    h->p0 = v3(fminf(d->p0[0], d->p1[0]), fminf(d->p0[1], d->p1[1]), fminf(d->p0[2], d->p1[2]));
    h->p1 = v3(fmaxf(d->p0[0], d->p1[0]), fmaxf(d->p0[1], d->p1[1]), fmaxf(d->p0[2], d->p1[2]));
    h->cloud_density = d->cloud_density;
    h->wispiness = d->wispiness;
    h->frequency = d->frequency;
    if (!h->cloud) {
        if (!d->density) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: a uniform grid needs its density", fn);
        h->n[0] = d->nx;
        h->n[1] = d->ny;
        h->n[2] = d->nz;
        h->density = (float *)(uintptr_t)d->density;
        h->le_scale = (float *)(uintptr_t)d->le_scale_grid;
        h->le_scale_1 = d->le_scale;
    }
    /* scene_add_medium validates the rest (grid shape, values, box). */
    return CST_OK;
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
    if (d->preset && !medium_preset(d->preset, &sa, &ss))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: no scattering preset is called \"%.64s\" (pbrt-v4's names, "
                        "e.g. \"Skimmilk\", \"Wholemilk\", \"Ketchup\", \"Regular Milk\", \"Espresso\")", fn, d->preset);
    if (d->type != CST_MEDIUM_HOMOGENEOUS && d->type != CST_MEDIUM_UNIFORMGRID && d->type != CST_MEDIUM_CLOUD)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: type %d; expected a CstMediumType", fn, (int)d->type);
    m.g = d->g;
    if (d->type != CST_MEDIUM_HOMOGENEOUS) {
        if ((st = read_hetero(d, fn, &m, err)) != CST_OK) return st;
        /* A grid's le_scale is its constant Lescale (le_scale_1), not folded into le. */
        m.u.het.sigma_a = color_scale(sa, d->scale);
        m.u.het.sigma_s = color_scale(ss, d->scale);
        m.u.het.le = d->type == CST_MEDIUM_CLOUD ? color_s(0.0f) : le;
        return scene_add_medium(scene, &m, out_id, err);
    }
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
