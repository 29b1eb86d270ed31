/* The checks the public scene builder shares between its files (scene_build.c,
 * scene_build_lights.c): ids, vectors, colours and products validated with messages that
 * name the API function and the field. Private to src/scene. */
#ifndef CST_SCENE_SCENE_BUILD_CHECK_H
#define CST_SCENE_SCENE_BUILD_CHECK_H

#include <math.h>

#include "core/error.h"
#include "scene/scene.h"


/* The loaders' bound on coordinates and lengths (scene_json.c explains the figure). */
#define BUILD_MAX_LENGTH 1e18f
/* A sphere's area must not underflow (scene_json.c's LOADER_MIN_RADIUS). */
#define BUILD_MIN_RADIUS 1e-18f

static inline CstStatus check_scene(const Scene *s, const char *fn, CstError *err)
{
    if (!s) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene is NULL", fn);
    if (s->committed)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: the scene is already committed; expected "
                        "additions before cst_scene_commit", fn);
    return CST_OK;
}

/* A point or vector: every component finite and within BUILD_MAX_LENGTH. */
static inline CstStatus read_vec3(const float v[3], const char *fn, const char *what, Vec3 *out, CstError *err)
{
    for (int k = 0; k < 3; k++)
        if (!(fabsf(v[k]) <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s (%g, %g, %g) is not finite or beyond "
                            "1e18; expected finite coordinates", fn, what, (double)v[0], (double)v[1], (double)v[2]);
    *out = v3(v[0], v[1], v[2]);
    return CST_OK;
}

/* A 3 x 4 row-major affine transform (an instance's or the camera's placement, named `what`
 * in errors) as a checked Transform: finite and invertible. */
static inline CstStatus read_instance_matrix(const float m[12], const char *fn, const char *what, Transform *out,
                                      CstError *err)
{
    if (!m) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s is NULL", fn, what);
    float rows[16] = {0};
    for (int k = 0; k < 12; k++) {
        if (!isfinite(m[k]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s[%d] is %g; expected finite numbers",
                            fn, what, k, (double)m[k]);
        rows[k] = m[k];
    }
    rows[15] = 1.0f;
    Transform xf = transform_from_rows(rows), inv;
    if (!transform_invert(&xf, &inv))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s is singular (or its inverse is not "
                        "finite); expected an invertible affine transform", fn, what);
    *out = xf;
    return CST_OK;
}

/* A colour: finite, >= 0 and, for reflectances (max_one), <= 1. */
static inline CstStatus read_rgb(const float c[3], int max_one, const char *fn, const char *what, Color *out,
                          CstError *err)
{
    for (int k = 0; k < 3; k++)
        if (!(c[k] >= 0.0f && c[k] <= (max_one ? 1.0f : FLT_MAX)))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s (%g, %g, %g) is out of range; expected %s",
                            fn, what, (double)c[0], (double)c[1], (double)c[2],
                            max_one ? "values from 0 to 1 (more than 1 would create energy)" : "finite values >= 0");
    *out = color_rgb(c[0], c[1], c[2]);
    return CST_OK;
}

/* Products of values that are each in range but overflow together (issue 25: an emission
 * radiance of 1e30 times a scale of 1e30 rendered black with exit 0): a light's radiance
 * after its scale and texture, and its power, must be finite floats. Power is what light
 * selection and every light path start from (light_power(), emitter_sample_emission()):
 * pi x area x radiance for an emitting surface (x 2 two-sided), 4 pi x intensity for a
 * point light, 4 pi x radiance for an environment; per channel, in double. */
static inline CstStatus check_product(const char *fn, const char *what, double value, const char *expect, CstError *err)
{
    if (value <= (double)FLT_MAX) return CST_OK;
    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s = %g overflows a float (above 3.4e38); expected %s",
                    fn, what, value, expect);
}

/* The largest channel of a colour, in double. */
static inline double color_peak(Color c) { return (double)color_max(c); }

/* A public texture id (>= 1, 0 = none) checked against the scene. */
static inline CstStatus check_texture_id(const Scene *s, int id, int allow_none, const char *fn, const char *what,
                                  CstError *err)
{
    if ((allow_none && id == 0) || (id >= 1 && id <= s->num_textures)) return CST_OK;
    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s %d is not a texture of this scene; expected %s1 to %d",
                    fn, what, id, allow_none ? "0 (none) or " : "", s->num_textures);
}


/* The effective stride of an attribute of `elem` bytes: 0 means packed. */
static inline CstStatus check_stride(size_t *stride, size_t elem, const char *fn, const char *what, CstError *err)
{
    if (*stride == 0) *stride = elem;
    if (*stride < elem)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s_stride %zu is smaller than an element (%zu bytes); "
                        "expected 0 (packed) or at least %zu", fn, what, *stride, elem, elem);
    return CST_OK;
}

/* A public alpha cut-out as the id scene_add_alpha gives (0: opaque, also for a constant
 * alpha of 1, which then costs nothing). scene_build_textures.c. */
CstStatus scene_build_alpha(Scene *s, const CstAlpha *a, const char *fn, int *out, CstError *err);
/* A mesh desc's cut-outs as one alpha id per triangle: d->triangle_alphas when given (runs
 * of equal cut-outs share an id), else *out = NULL and the mesh's d->alpha applies. The
 * caller frees *out. scene_build_textures.c. */
CstStatus scene_build_triangle_alphas(Scene *s, const CstMeshDesc *d, const char *fn, int **out, CstError *err);

#endif
