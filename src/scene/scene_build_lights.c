/* The public scene builder's lights, environment, camera and output path
 * (cst_scene_add_light ... cst_scene_set_output_path), validated as scene_build.c validates
 * the rest. */
#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "scene/scene.h"
#include "scene/scene_build.h"
#include "scene/scene_build_check.h"

/* ------------------------------------------------------------------ lights, camera */

/* v / |v| for a nonzero finite v. */
static CstStatus read_direction(const float d[3], const char *fn, const char *what, Vec3 *out, CstError *err)
{
    Vec3 v = {0.0f, 0.0f, 0.0f};
    CstStatus st = read_vec3(d, fn, what, &v, err);
    if (st != CST_OK) return st;
    float len = v3_length(v);
    if (!(len > 0.0f) || !isfinite(len))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s (%g, %g, %g) has no length; expected a nonzero vector",
                        fn, what, (double)d[0], (double)d[1], (double)d[2]);
    *out = v3_scale(v, 1.0f / len);
    return CST_OK;
}

/* A goniometric light's image and map, copied (the scene frees the copy). */
#define GONIO_MAX_SIDE 65536
static CstStatus read_gonio(const CstLightDesc *d, const char *fn, GonioImage *g, CstError *err)
{
    const int n = d->image_size;
    if (!d->image || !(n >= 1 && n <= GONIO_MAX_SIDE))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: goniometric image %s of size %d; expected an image of "
                        "1 to %d pixels square", fn, d->image ? "given" : "NULL", n, GONIO_MAX_SIDE);
    bool zero = true;
    for (int k = 0; k < 9; k++) {
        if (!isfinite(d->light_from_world[k]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: light_from_world[%d] is not finite", fn, k);
        zero &= d->light_from_world[k] == 0.0f;
    }
    for (int k = 0; k < 9; k++) g->light_from_world[k] = zero ? (k % 4 == 0 ? 1.0f : 0.0f) : d->light_from_world[k];
    size_t count = (size_t)n * (size_t)n;
    float *f = malloc(count * sizeof *f);
    if (!f) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d goniometric image", fn, n, n);
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) {
        if (!(d->image[i] >= 0.0f) || !isfinite(d->image[i])) {
            free(f);
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: goniometric image pixel (%d, %d) is %g; expected a "
                            "finite value >= 0", fn, (int)(i % (size_t)n), (int)(i / (size_t)n), (double)d->image[i]);
        }
        f[i] = d->image[i];
        sum += (double)f[i];
    }
    g->factor = f;
    g->n = n;
    g->mean = (float)(sum / (double)count);
    return CST_OK;
}

/* A projection light's image, copied, and its frame made a rotation: rows orthonormalised
 * from the third (the axis) by Gram-Schmidt, the second's sign kept. The window and the
 * image's integral over its solid angle (pixel centres, d omega = cos^3 theta dA on the
 * plane z = 1: pbrt-v4 ProjectionLight::Phi). */
#define PROJ_MAX_SIDE 65536
static CstStatus read_proj(const CstLightDesc *d, const char *fn, ProjImage *g, CstError *err)
{
    const int w = d->image_width, h = d->image_height;
    if (!d->image || !(w >= 1 && w <= PROJ_MAX_SIDE && h >= 1 && h <= PROJ_MAX_SIDE))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: projection image %s of %d x %d; expected 1 to %d pixels "
                        "each way", fn, d->image ? "given" : "NULL", w, h, PROJ_MAX_SIDE);
    if (!(d->fov > 0.0f && d->fov < 180.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: fov %g; expected degrees in (0, 180)", fn, (double)d->fov);
    bool zero = true;
    for (int k = 0; k < 9; k++) {
        if (!isfinite(d->light_from_world[k]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: light_from_world[%d] is not finite", fn, k);
        zero &= d->light_from_world[k] == 0.0f;
    }
    Vec3 r[3];
    for (int k = 0; k < 3; k++)
        r[k] = zero ? v3(k == 0 ? 1.0f : 0.0f, k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f)
                    : v3(d->light_from_world[3 * k], d->light_from_world[3 * k + 1], d->light_from_world[3 * k + 2]);
    Vec3 z = r[2], y = v3_sub(r[1], v3_scale(r[2], v3_dot(r[1], r[2]) / v3_length2(r[2])));
    if (!(v3_length2(z) > 0.0f) || !(v3_length2(y) > 0.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: light_from_world is singular; expected an invertible map", fn);
    z = v3_normalize(z);
    y = v3_normalize(y);
    Vec3 x = v3_cross(y, z);
    if (v3_dot(x, r[0]) < 0.0f) x = v3_neg(x); /* keep a mirror's handedness */
    const Vec3 rows[3] = {x, y, z};
    for (int k = 0; k < 3; k++) {
        g->light_from_world[3 * k] = rows[k].x;
        g->light_from_world[3 * k + 1] = rows[k].y;
        g->light_from_world[3 * k + 2] = rows[k].z;
    }
    const float aspect = (float)w / (float)h;
    g->w = w;
    g->h = h;
    g->tan_half = tanf(0.5f * d->fov * (CST_PI / 180.0f));
    g->sx = aspect > 1.0f ? aspect : 1.0f;
    g->sy = aspect > 1.0f ? 1.0f : 1.0f / aspect;
    g->area = 4.0f * g->sx * g->sy * g->tan_half * g->tan_half;
    size_t count = (size_t)w * (size_t)h * 3;
    float *px = malloc(count * sizeof *px);
    if (!px) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d projection image", fn, w, h);
    double sum[3] = {0.0, 0.0, 0.0};
    for (int j = 0; j < h; j++)
        for (int i = 0; i < w; i++) {
            double sx = ((2.0 * i + 1.0) / w - 1.0) * (double)(g->sx * g->tan_half);
            double sy = ((2.0 * j + 1.0) / h - 1.0) * (double)(g->sy * g->tan_half);
            double c = 1.0 / sqrt(1.0 + sx * sx + sy * sy);
            for (int k = 0; k < 3; k++) {
                size_t at = 3 * ((size_t)j * (size_t)w + (size_t)i) + (size_t)k;
                float v = d->image[at];
                if (!(v >= 0.0f) || !isfinite(v)) {
                    free(px);
                    return cst_fail(err, CST_ERR_INVALID_ARG, "%s: projection image pixel (%d, %d) channel %d is "
                                    "%g; expected a finite value >= 0", fn, i, j, k, (double)v);
                }
                px[at] = v;
                sum[k] += (double)v * c * c * c;
            }
        }
    const double da = (double)g->area / ((double)w * (double)h);
    g->integral = color_rgb((float)(sum[0] * da), (float)(sum[1] * da), (float)(sum[2] * da));
    g->rgb = px;
    return CST_OK;
}

CstStatus cst_scene_add_light(CstScene *scene, const CstLightDesc *d, CstError *err)
{
    static const char fn[] = "cst_scene_add_light";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    DeltaLight l;
    memset(&l, 0, sizeof l);
    if ((st = read_rgb(d->intensity, 0, fn, d->type == CST_LIGHT_DIRECTIONAL ? "irradiance" : "intensity",
                       &l.intensity, err)) != CST_OK)
        return st;
    switch (d->type) {
    case CST_LIGHT_DIRECTIONAL:
        l.type = DELTA_DIRECTIONAL;
        if ((st = read_direction(d->direction, fn, "direction", &l.dir, err)) != CST_OK) return st;
        break;
    case CST_LIGHT_POINT:
    case CST_LIGHT_SPOT:
        l.type = d->type == CST_LIGHT_POINT ? DELTA_POINT : DELTA_SPOT;
        if ((st = read_vec3(d->position, fn, "position", &l.p, err)) != CST_OK) return st;
        if (d->type == CST_LIGHT_POINT) break;
        if ((st = read_direction(d->direction, fn, "direction", &l.dir, err)) != CST_OK) return st;
        if (!(d->cone_angle >= 0.001f && d->cone_angle <= 90.0f))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: cone_angle %g; expected degrees from 0.001 to 90",
                            fn, (double)d->cone_angle);
        if (!(d->cone_delta >= 0.0f && d->cone_delta <= d->cone_angle))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: cone_delta %g; expected degrees from 0 to cone_angle (%g)",
                            fn, (double)d->cone_delta, (double)d->cone_angle);
        l.cos_outer = cosf(d->cone_angle * (CST_PI / 180.0f));
        l.cos_inner = cosf((d->cone_angle - d->cone_delta) * (CST_PI / 180.0f));
        break;
    case CST_LIGHT_GONIOMETRIC:
        l.type = DELTA_GONIO;
        if ((st = read_vec3(d->position, fn, "position", &l.p, err)) != CST_OK) return st;
        if ((st = read_gonio(d, fn, &l.gonio, err)) != CST_OK) return st;
        break;
    case CST_LIGHT_PROJECTION:
        l.type = DELTA_PROJECTION;
        if ((st = read_vec3(d->position, fn, "position", &l.p, err)) != CST_OK) return st;
        if ((st = read_proj(d, fn, &l.proj, err)) != CST_OK) return st;
        break;
    default:
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown light type %d; expected CST_LIGHT_POINT, _SPOT, "
                        "_DIRECTIONAL, _GONIOMETRIC or _PROJECTION", fn, (int)d->type);
    }
    /* A directional light's power depends on the scene's size: cst_scene_commit checks it. */
    if (d->type != CST_LIGHT_DIRECTIONAL)
        st = check_product(fn, "the power 4 pi x intensity", 4.0 * (double)CST_PI * color_peak(l.intensity),
                           "a smaller intensity", err);
    if (st == CST_OK && (d->spectrum < 0 || d->spectrum > scene->num_spectra))
        st = cst_fail(err, CST_ERR_INVALID_ARG, "%s: spectrum %d; expected 0 or a cst_scene_add_spectrum id "
                      "(1 to %d)", fn, d->spectrum, scene->num_spectra);
    if (st == CST_OK) st = scene_add_delta_light(scene, &l, err);
    if (st == CST_OK) return scene_set_delta_spectrum(scene, d->spectrum, err); /* the light is the scene's now */
    if (st != CST_OK && l.type == DELTA_GONIO)
        free((void *)(uintptr_t)l.gonio.factor);
    if (st != CST_OK && l.type == DELTA_PROJECTION)
        free((void *)(uintptr_t)l.proj.rgb);
    return st;
}

CstStatus cst_scene_set_environment_constant(CstScene *scene, const float radiance[3], CstError *err)
{
    static const char fn[] = "cst_scene_set_environment_constant";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!radiance) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: radiance is NULL", fn);
    Color L;
    EnvMap env;
    if ((st = read_rgb(radiance, 0, fn, "radiance", &L, err)) != CST_OK) return st;
    if ((st = check_product(fn, "4 pi x radiance (the radiance over the sphere of directions)",
                            4.0 * (double)CST_PI * color_peak(L), "a smaller radiance", err)) != CST_OK)
        return st;
    if ((st = envmap_init_constant(&env, L, err)) != CST_OK) return st;
    return scene_set_environment(scene, &env, err);
}

CstStatus cst_scene_set_environment_spectrum(CstScene *scene, int spectrum, CstError *err)
{
    static const char fn[] = "cst_scene_set_environment_spectrum";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (spectrum < 0 || spectrum > scene->num_spectra)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: spectrum %d; expected 0 or a cst_scene_add_spectrum id "
                        "(1 to %d)", fn, spectrum, scene->num_spectra);
    scene->env_spectrum = spectrum;
    return CST_OK;
}

CstStatus cst_scene_set_environment_image(CstScene *scene, const char *path, const float scale[3], CstError *err)
{
    static const char fn[] = "cst_scene_set_environment_image";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: path is NULL or empty", fn);
    Color k = color_s(1.0f);
    if (scale && (st = read_rgb(scale, 0, fn, "scale", &k, err)) != CST_OK) return st;
    float *rgb = NULL;
    int w = 0, h = 0;
    EnvMap env;
    if ((st = image_read_radiance(path, &rgb, &w, &h, err)) != CST_OK) return st; /* NaN, Inf, < 0: errors */
    double brightest = 0.0;
    for (size_t i = 0; i < (size_t)w * (size_t)h * 3; i++)
        if ((double)rgb[i] > brightest) brightest = (double)rgb[i];
    if ((st = check_product(fn, "4 pi x scale x the image's largest value",
                            4.0 * (double)CST_PI * color_peak(k) * brightest, "a smaller scale", err)) != CST_OK) {
        free(rgb);
        return st;
    }
    if ((st = envmap_init_image(&env, rgb, w, h, k, err)) != CST_OK) return st;
    return scene_set_environment(scene, &env, err);
}

/* The largest side of an environment image from pixels (as for image textures). */
#define BUILD_MAX_ENV_SIDE 65536

/* Pixel (x, y) of a caller's strided RGB image. */
static const float *env_pixel(const float *rgb, size_t ps, size_t rs, int x, int y)
{
    return (const float *)(const void *)((const char *)rgb + (size_t)y * rs + (size_t)x * ps);
}

/* 3 x 3 inverse in double (cofactors over the determinant); false when singular or not
 * finite. */
static int invert3(const double m[9], double inv[9])
{
    double c[9] = {m[4] * m[8] - m[5] * m[7], m[2] * m[7] - m[1] * m[8], m[1] * m[5] - m[2] * m[4],
                   m[5] * m[6] - m[3] * m[8], m[0] * m[8] - m[2] * m[6], m[2] * m[3] - m[0] * m[5],
                   m[3] * m[7] - m[4] * m[6], m[1] * m[6] - m[0] * m[7], m[0] * m[4] - m[1] * m[3]};
    double det = m[0] * c[0] + m[1] * c[3] + m[2] * c[6];
    if (!(det != 0.0) || !isfinite(det)) return 0;
    for (int k = 0; k < 9; k++) {
        inv[k] = c[k] / det;
        if (!isfinite(inv[k])) return 0;
    }
    return 1;
}

/* out (w x h, packed) = the map `in` seen through world_from_map: each pixel takes, by
 * nearest lookup, the pixel of `in` that its centre's world direction has in map space
 * (envmap.h's convention on both sides). */
static void env_resample(const float *in, int w, int h, const double map_from_world[9], float *out)
{
    const double pi = 3.14159265358979323846;
    for (int y = 0; y < h; y++) {
        double th = pi * (y + 0.5) / h;
        for (int x = 0; x < w; x++) {
            double ph = 2.0 * pi * (x + 0.5) / w;
            double wv[3] = {sin(th) * cos(ph), cos(th), sin(th) * sin(ph)}, dm[3], len = 0.0;
            for (int r = 0; r < 3; r++) {
                dm[r] = map_from_world[3 * r] * wv[0] + map_from_world[3 * r + 1] * wv[1] +
                        map_from_world[3 * r + 2] * wv[2];
                len += dm[r] * dm[r];
            }
            len = sqrt(len);
            double phi = atan2(dm[2] / len, dm[0] / len), theta = acos(fmax(-1.0, fmin(1.0, dm[1] / len)));
            if (phi < 0.0) phi += 2.0 * pi;
            int sx = (int)(phi / (2.0 * pi) * w), sy = (int)(theta / pi * h);
            sx = sx < 0 ? 0 : sx >= w ? w - 1 : sx;
            sy = sy < 0 ? 0 : sy >= h ? h - 1 : sy;
            memcpy(&out[3 * ((size_t)y * (size_t)w + (size_t)x)], &in[3 * ((size_t)sy * (size_t)w + (size_t)sx)],
                   3 * sizeof *out);
        }
    }
}

CstStatus cst_scene_set_environment_pixels(CstScene *scene, const float *rgb, int w, int h, size_t ps, size_t rs,
                                           const float scale[3], const float world_from_map[9], CstError *err)
{
    static const char fn[] = "cst_scene_set_environment_pixels";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!rgb) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: rgb is NULL", fn);
    if (w <= 0 || h <= 0 || w > BUILD_MAX_ENV_SIDE || h > BUILD_MAX_ENV_SIDE)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: image of %d x %d pixels; expected 1 to %d on each side",
                        fn, w, h, BUILD_MAX_ENV_SIDE);
    if ((st = check_stride(&ps, 3 * sizeof(float), fn, "pixel", err)) != CST_OK) return st;
    size_t row_min = (size_t)(w - 1) * ps + 3 * sizeof(float);
    if (rs == 0) rs = (size_t)w * ps;
    if (rs < row_min)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: row_stride %zu is shorter than a row (%zu bytes); expected "
                        "0 (width * pixel_stride) or at least %zu", fn, rs, row_min, row_min);
    Color k = color_s(1.0f);
    if (scale && (st = read_rgb(scale, 0, fn, "scale", &k, err)) != CST_OK) return st;
    double m[9], inv[9];
    int rotate = 0;
    for (int i = 0; world_from_map && i < 9; i++) {
        m[i] = (double)world_from_map[i];
        rotate |= world_from_map[i] != ((i % 4) == 0 ? 1.0f : 0.0f); /* the identity needs no resampling */
    }
    if (rotate && !invert3(m, inv))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_map is singular or not finite; expected an "
                        "invertible 3 x 3 matrix (a rotation)", fn);
    size_t n = (size_t)w * (size_t)h * 3;
    float *px = malloc(n * sizeof *px), *turned = rotate ? malloc(n * sizeof *turned) : NULL;
    if (!px || (rotate && !turned)) {
        free(px);
        free(turned);
        return cst_fail(err, CST_ERR_OOM, "%s: out of memory for a %d x %d environment", fn, w, h);
    }
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            const float *p = env_pixel(rgb, ps, rs, x, y);
            float *o = &px[3 * ((size_t)y * (size_t)w + (size_t)x)];
            memcpy(o, p, 3 * sizeof *o);
            if (!(o[0] >= 0.0f && o[1] >= 0.0f && o[2] >= 0.0f && o[0] <= FLT_MAX && o[1] <= FLT_MAX &&
                  o[2] <= FLT_MAX)) {
                st = cst_fail(err, CST_ERR_INVALID_ARG, "%s: pixel (%d, %d) is (%g, %g, %g); expected finite "
                              "radiance >= 0", fn, x, y, (double)o[0], (double)o[1], (double)o[2]);
                free(px);
                free(turned);
                return st;
            }
        }
    if (rotate) {
        env_resample(px, w, h, inv, turned);
        free(px);
        px = turned;
    }
    EnvMap env;
    if ((st = envmap_init_image(&env, px, w, h, k, err)) != CST_OK) return st; /* takes px */
    return scene_set_environment(scene, &env, err);
}

CstStatus cst_scene_set_camera(CstScene *scene, const CstCameraDesc *d, CstError *err)
{
    static const char fn[] = "cst_scene_set_camera";
    cst_error_clear(err);
    /* Also after commit (caustic.h): the camera is the view, not the scene's contents. */
    CstStatus st = CST_OK;
    if (!scene) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene is NULL", fn);
    if (!d) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: desc is NULL", fn);
    if (d->type != CST_CAMERA_PERSPECTIVE && d->type != CST_CAMERA_ORTHOGRAPHIC)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown camera type %d; expected CST_CAMERA_PERSPECTIVE "
                        "or CST_CAMERA_ORTHOGRAPHIC", fn, (int)d->type);
    CameraDesc c = {0};
    if ((st = read_vec3(d->position, fn, "position", &c.position, err)) != CST_OK ||
        (st = read_vec3(d->up, fn, "up", &c.up, err)) != CST_OK)
        return st;
    /* Only look_at's direction from position counts: it may lie beyond BUILD_MAX_LENGTH
     * (pbrt's loader puts it a power of two past |position|, which keeps the difference
     * exact), as long as that difference has a finite length. */
    if (!isfinite(d->look_at[0]) || !isfinite(d->look_at[1]) || !isfinite(d->look_at[2]))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: look_at (%g, %g, %g) is not finite; expected a point on "
                        "the view axis", fn, (double)d->look_at[0], (double)d->look_at[1], (double)d->look_at[2]);
    c.look_at = v3(d->look_at[0], d->look_at[1], d->look_at[2]);
    if (c.up.x == 0.0f && c.up.y == 0.0f && c.up.z == 0.0f) c.up = v3(0.0f, 1.0f, 0.0f);
    Vec3 forward = v3_sub(c.look_at, c.position);
    float dist = v3_length(forward);
    if (!(dist > 0.0f) || !isfinite(dist))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: look_at equals position or lies too far from it (more "
                        "than about 1e19), so there is no view direction", fn);
    /* right = normalize(forward x up) must exist: sin(forward, up) > 1e-6, the bound the
     * pbrt loader has always used (the JSON loader checks 1e-4 first, for its own message). */
    float ul = v3_length(c.up);
    if (!(v3_length(v3_cross(v3_scale(forward, 1.0f / dist), c.up)) > 1e-6f * ul))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: up (%g, %g, %g) is parallel to the view direction; "
                        "expected a vector not parallel to look_at - position",
                        fn, (double)c.up.x, (double)c.up.y, (double)c.up.z);
    if (d->mirror != 0 && d->mirror != 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: mirror %d; expected 0 or 1", fn, d->mirror);
    c.focus_distance = dist;
    if (d->type == CST_CAMERA_ORTHOGRAPHIC) {
        if (!(d->height > 0.0f && d->height <= BUILD_MAX_LENGTH))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: height %g; expected the view's height in scene units, > 0",
                            fn, (double)d->height);
        if (!(d->fov == 0.0f || (d->fov > 0.0f && d->fov < 180.0f)))
            return cst_fail(err, CST_ERR_INVALID_ARG, "%s: fov %g for an orthographic camera; expected 0 or "
                            "degrees in (0, 180)", fn, (double)d->fov);
        c.ortho_height = d->height;
        c.vfov_deg = d->fov; /* not the rays': the film-area term of bdpt/vcm (subpath.c) */
        scene_set_camera(scene, &c);
        scene->camera_mirror = d->mirror;
        return CST_OK;
    }
    if (!(d->fov > 0.0f && d->fov < 180.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: fov %g; expected the vertical field of view in degrees, "
                        "greater than 0 and less than 180", fn, (double)d->fov);
    if (!(d->aperture_radius >= 0.0f && d->aperture_radius <= BUILD_MAX_LENGTH))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: aperture_radius %g; expected a lens radius >= 0",
                        fn, (double)d->aperture_radius);
    if (!(d->focus_distance >= 0.0f && d->focus_distance <= BUILD_MAX_LENGTH))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: focus_distance %g; expected a distance > 0 (or 0 for "
                        "|look_at - position|)", fn, (double)d->focus_distance);
    c.vfov_deg = d->fov;
    c.aperture_radius = d->aperture_radius;
    if (d->focus_distance > 0.0f) c.focus_distance = d->focus_distance;
    scene_set_camera(scene, &c);
    scene->camera_mirror = d->mirror;
    return CST_OK;
}

void cst_scene_camera(const CstScene *scene, CstCameraDesc *out)
{
    const CameraDesc *c = &scene->camera;
    memset(out, 0, sizeof *out);
    out->type = c->ortho_height > 0.0f ? CST_CAMERA_ORTHOGRAPHIC : CST_CAMERA_PERSPECTIVE;
    const float p[3] = {c->position.x, c->position.y, c->position.z};
    const float l[3] = {c->look_at.x, c->look_at.y, c->look_at.z};
    const float u[3] = {c->up.x, c->up.y, c->up.z};
    memcpy(out->position, p, sizeof p);
    memcpy(out->look_at, l, sizeof l);
    memcpy(out->up, u, sizeof u);
    out->fov = c->vfov_deg;
    out->aperture_radius = c->aperture_radius;
    out->focus_distance = c->focus_distance;
    out->height = c->ortho_height;
    out->mirror = scene->camera_mirror;
}

CstStatus cst_scene_set_camera_motion(CstScene *scene, const float start[12], const float end[12], CstError *err)
{
    static const char fn[] = "cst_scene_set_camera_motion";
    cst_error_clear(err);
    if (!scene) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene is NULL", fn);
    if (!start && !end) {
        scene->camera_placed = false;
        return CST_OK;
    }
    Transform t0, t1;
    CstStatus st = read_instance_matrix(start, fn, "world_from_camera", &t0, err);
    if (st == CST_OK) st = read_instance_matrix(end, fn, "world_from_camera_end", &t1, err);
    if (st != CST_OK) return st;
    /* The camera's handedness (mirror) is one for the whole shutter: a placement that
     * mirrors at one end only would pass through a singular one. */
    double d0 = transform_det(&t0), d1 = transform_det(&t1);
    if ((d0 < 0.0) != (d1 < 0.0))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: world_from_camera mirrors (determinant %g) and "
                        "world_from_camera_end %s (%g); expected both or neither to mirror", fn, d0,
                        d1 < 0.0 ? "does" : "does not", d1);
    MotionTransform mt;
    if (!motion_init(&mt, &t0, &t1))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: the transforms cannot be decomposed; expected "
                        "invertible affine transforms", fn);
    scene->camera_motion = mt;
    scene->camera_placed = true;
    return CST_OK;
}

CstStatus cst_scene_set_shutter(CstScene *scene, float open, float close, CstError *err)
{
    static const char fn[] = "cst_scene_set_shutter";
    cst_error_clear(err);
    if (!scene) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene is NULL", fn);
    if (!(fabsf(open) <= 1e6f) || !(fabsf(close) <= 1e6f) || !(open <= close))
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: shutter [%g, %g]; expected finite times (within 1e6) with "
                        "open <= close", fn, (double)open, (double)close);
    scene->shutter[0] = open;
    scene->shutter[1] = close;
    return CST_OK;
}

CstStatus cst_scene_set_output_path(CstScene *scene, const char *path, CstError *err)
{
    static const char fn[] = "cst_scene_set_output_path";
    cst_error_clear(err);
    CstStatus st = check_scene(scene, fn, err);
    if (st != CST_OK) return st;
    if (!path || !path[0]) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: path is NULL or empty", fn);
    return scene_set_output_path(scene, path, err);
}


/* ------------------------------------------------------------------ light sampler */

CstStatus cst_scene_set_light_sampling(CstScene *scene, const char *name, CstError *err)
{
    static const char fn[] = "cst_scene_set_light_sampling";
    if (!scene || !name) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s is NULL", fn, scene ? "name" : "scene");
    int solid;
    if (strcmp(name, "area") == 0) solid = 0;
    else if (strcmp(name, "solid_angle") == 0) solid = 1;
    else return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown light sampling '%s'; expected area or solid_angle", fn, name);
    scene->light_solid_angle = solid;
    if (scene->committed) scene->emitter_sampler.solid_angle = solid != 0;
    return CST_OK;
}

CstStatus cst_scene_set_environment_portal(CstScene *scene, const float corners[12], CstError *err)
{
    static const char fn[] = "cst_scene_set_environment_portal";
    if (!scene || !corners) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s is NULL", fn, scene ? "corners" : "scene");
    if (scene->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: scene already committed", fn);
    for (int i = 0; i < 12; i++)
        if (!isfinite(corners[i])) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: corner %d is not finite", fn, i / 3);
    for (int i = 0; i < 4; i++) scene->env_portal[i] = v3(corners[3 * i], corners[3 * i + 1], corners[3 * i + 2]);
    /* the rectangle check now, with a dummy map, so the caller hears of it here */
    EnvMap probe;
    CstStatus st = envmap_init_constant(&probe, color_s(1.0f), err);
    if (st == CST_OK) st = envmap_set_portal(&probe, scene->env_portal, err);
    envmap_free(&probe);
    if (st != CST_OK) return st;
    scene->has_env_portal = 1;
    return CST_OK;
}

CstStatus cst_scene_set_light_sampler(CstScene *scene, const char *name, CstError *err)
{
    static const char fn[] = "cst_scene_set_light_sampler";
    if (!scene || !name) return cst_fail(err, CST_ERR_INVALID_ARG, "%s: %s is NULL", fn, scene ? "name" : "scene");
    LightSelect sel;
    if (strcmp(name, "power") == 0) sel = LIGHT_SELECT_POWER;
    else if (strcmp(name, "bvh") == 0) sel = LIGHT_SELECT_BVH;
    else if (strcmp(name, "uniform") == 0) sel = LIGHT_SELECT_UNIFORM;
    else return cst_fail(err, CST_ERR_INVALID_ARG, "%s: unknown light sampler '%s'; expected power, bvh or uniform", fn, name);
    if (scene->committed) {
        EmitterGeometry g = scene_emitter_geometry(scene);
        CstStatus st = emitter_sampler_set_nee(&scene->emitter_sampler, &g, sel, err);
        if (st != CST_OK) return st;
    }
    scene->light_select = 1 + (int)sel;
    return CST_OK;
}
