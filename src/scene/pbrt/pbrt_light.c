/* Lights: point, spot and distant lights, area lights, and infinite lights whose
 * equal-area octahedral images are remapped to caustic's environment map. */
#include "scene/pbrt/pbrt_light.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "io/image_io.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_shape.h"
#include "scene/pbrt/pbrt_spectrum.h"
#include "scene/pbrt/pbrt_transform.h"

static CstStatus get_point3(Loader *ld, Params *ps, const char *d, const char *name, Vec3 def, Vec3 *out)
{
    Param *p;
    *out = def;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_POINT3), "point3", &p));
    if (!p) return CST_OK;
    char nm[72];
    if (p->num_nums != 3)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" has %d values; expected 3", d,
                            pbrt_clip(p->decl, nm), p->num_nums);
    *out = v3((float)p->nums[0], (float)p->nums[1], (float)p->nums[2]);
    if (!pbrt_coords_ok(*out))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" is beyond the scene limit", d,
                            pbrt_clip(p->decl, nm));
    return CST_OK;
}

/* Clarberg's equal-area octahedral map ("Fast Equal-Area Mapping of the (Hemi)Sphere using
 * SIMD", JGT 2008), which pbrt-v4 uses for the images of infinite lights
 * (EqualAreaSphereToSquare / EqualAreaSquareToSphere): the square's centre is +z, its
 * corners -z, u = 1 is +x and v = 1 is +y; equal areas of the square cover equal solid
 * angles. Here with the exact arctangent where pbrt uses a polynomial fit of it. */
void pbrt_equal_area_sphere_to_square(const double d[3], double uv[2])
{
    double x = fabs(d[0]), y = fabs(d[1]), z = fabs(d[2]);
    double r = sqrt(fmax(0.0, 1.0 - z));
    double a = fmax(x, y), b = fmin(x, y);
    double phi = atan(a == 0.0 ? 0.0 : b / a) * (2.0 / PBRT_PI);
    if (x < y) phi = 1.0 - phi;
    double v = phi * r, u = r - v;
    if (d[2] < 0.0) {
        double t = u;
        u = 1.0 - v;
        v = 1.0 - t;
    }
    uv[0] = 0.5 * (copysign(u, d[0]) + 1.0);
    uv[1] = 0.5 * (copysign(v, d[1]) + 1.0);
}

void pbrt_equal_area_square_to_sphere(const double uv[2], double d[3])
{
    double u = 2.0 * uv[0] - 1.0, v = 2.0 * uv[1] - 1.0, up = fabs(u), vp = fabs(v);
    double sd = 1.0 - (up + vp), r = 1.0 - fabs(sd);
    double phi = (r == 0.0 ? 1.0 : (vp - up) / r + 1.0) * (PBRT_PI / 4.0);
    double s = r * sqrt(fmax(0.0, 2.0 - r * r));
    d[0] = copysign(cos(phi), u) * s;
    d[1] = copysign(sin(phi), v) * s;
    d[2] = copysign(1.0 - r * r, sd);
}

/* The pixel of a w x h image (row 0 at the top, as pbrt and image_read store it) that an
 * infinite light shows in light-space direction d: nearest lookup as pbrt-v4's
 * ImageInfiniteLight does. Square images use the equal-area map; others pbrt-v3's
 * equirectangular one (+z up: u = phi / 2 pi, phi = atan2(y, x), v = theta / pi). */
static size_t env_source_pixel(const double d[3], int w, int h)
{
    double uv[2];
    if (w == h) {
        pbrt_equal_area_sphere_to_square(d, uv);
    } else {
        double phi = atan2(d[1], d[0]);
        if (phi < 0.0) phi += 2.0 * PBRT_PI;
        uv[0] = phi / (2.0 * PBRT_PI);
        uv[1] = acos(fmax(-1.0, fmin(1.0, d[2]))) / PBRT_PI;
    }
    int x = (int)(uv[0] * w), y = (int)(uv[1] * h);
    x = x < 0 ? 0 : x >= w ? w - 1 : x;
    y = y < 0 ? 0 : y >= h ? h - 1 : y;
    return (size_t)y * (size_t)w + (size_t)x;
}

/* A light's image ("filename" at fl): file access checked, resolved against the scene's
 * directory, read as radiance (NaN, Inf and negative pixels are errors naming the pixel). */
static CstStatus light_image_read(Loader *ld, const char *d, const char *file, Loc fl, float **px, int *w, int *h)
{
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    CstStatus st = image_read_radiance(path, px, w, h, ld->err);
    free(path);
    return st ? pbrt_fail_wrap(ld, st, fl, d) : CST_OK;
}

/* pbrt-v4's "illuminance" normaliser of an image light: over the pixels whose direction has
 * light-space z > 0, the sum of luminance times cos theta, times 2 pi / (number of pixels)
 * (lights.cpp, Light::Create). A pixel covers 4 pi / (number of pixels) sr, so this is half
 * the patch's illuminance; kept, so that the image renders as bright as in pbrt. Non-square
 * (equirectangular) images get the same half from their pixels' solid angles. */
static double env_illuminance(const float *px, int w, int h)
{
    double sum = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double d[3], uv[2] = {(x + 0.5) / w, (y + 0.5) / h}, dw;
            if (w == h) {
                pbrt_equal_area_square_to_sphere(uv, d);
                dw = 2.0 * PBRT_PI / ((double)w * h);
            } else {
                double th = PBRT_PI * uv[1];
                d[2] = cos(th);
                dw = 0.5 * (2.0 * PBRT_PI / w) * (PBRT_PI / h) * sin(th); /* half of the pixel's sr, as above */
            }
            if (d[2] <= 0.0) continue;
            const float *p = &px[3 * ((size_t)y * (size_t)w + (size_t)x)];
            sum += (0.2126 * (double)p[0] + 0.7152 * (double)p[1] + 0.0722 * (double)p[2]) * d[2] * dw;
        }
    return sum;
}

/* Pixel of a w x h map in caustic's equirectangular layout at (u, v) in [0,1)^2. */
static const float *env_at(const float *rgb, int w, int h, double u, double v)
{
    int x = (int)(u * w), y = (int)(v * h);
    x = x < 0 ? 0 : x >= w ? w - 1 : x;
    y = y < 0 ? 0 : y >= h ? h - 1 : y;
    return &rgb[3 * ((size_t)y * (size_t)w + (size_t)x)];
}

/* Makes the scene's environment the sum of the infinite lights so far plus this one:
 * pbrt-v4 adds the radiance of every infinite light; caustic has one environment map,
 * which then holds their sum. img (owned; NULL for a constant light c) is in caustic's
 * equirectangular layout, times k. The first light is set as it comes (exactly as
 * before); a later one is added pixel by pixel, constants to every pixel, two images on
 * the grid of the larger (nearest lookup of each at the pixel centre, which is exact for
 * equal sizes). NEE then samples the sum's luminance rather than each light by its own
 * distribution: the same radiance, different noise. */
static CstStatus env_accumulate(Loader *ld, float *img, int w, int h, const float k[3], const float c[3], Loc loc,
                                const char *d)
{
    CstStatus st;
    if (!ld->env_set) {
        ld->env_rgb = img;
        ld->env_w = w;
        ld->env_h = h;
        for (int i = 0; i < 3; i++) {
            ld->env_k[i] = k[i];
            ld->env_const[i] = img ? 0.0f : c[i];
        }
        st = img ? cst_scene_set_environment_pixels(ld->scene, img, w, h, 0, 0, k, NULL, ld->err)
                 : cst_scene_set_environment_constant(ld->scene, c, ld->err);
        if (!st) ld->env_set = 1;
        return st;
    }
    pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: another infinite light; caustic adds it to the "
                 "environment (one map, the sum of the lights, as pbrt-v4 renders them)", d);
    for (int i = 0; i < 3; i++) ld->env_const[i] += img ? 0.0f : c[i];
    if (!img && !ld->env_rgb) return cst_scene_set_environment_constant(ld->scene, ld->env_const, ld->err);
    const bool on_old = ld->env_rgb && (!img || ld->env_w * (long long)ld->env_h > w * (long long)h);
    int ow = on_old ? ld->env_w : w, oh = on_old ? ld->env_h : h;
    float *sum = malloc(3u * (size_t)ow * (size_t)oh * sizeof *sum);
    if (!sum) {
        free(img);
        return pbrt_oom(ld);
    }
    for (int y = 0; y < oh; y++)
        for (int x = 0; x < ow; x++) {
            double u = (x + 0.5) / ow, v = (y + 0.5) / oh;
            float *o = &sum[3 * ((size_t)y * (size_t)ow + (size_t)x)];
            for (int i = 0; i < 3; i++) o[i] = ld->env_const[i];
            if (ld->env_rgb) {
                const float *p = env_at(ld->env_rgb, ld->env_w, ld->env_h, u, v);
                for (int i = 0; i < 3; i++) o[i] += p[i] * ld->env_k[i];
            }
            if (img) {
                const float *p = env_at(img, w, h, u, v);
                for (int i = 0; i < 3; i++) o[i] += p[i] * k[i];
            }
        }
    free(img);
    free(ld->env_rgb);
    ld->env_rgb = sum;
    ld->env_w = ow;
    ld->env_h = oh;
    for (int i = 0; i < 3; i++) {
        ld->env_k[i] = 1.0f;
        ld->env_const[i] = 0.0f;
    }
    return cst_scene_set_environment_pixels(ld->scene, sum, ow, oh, 0, 0, ld->env_k, NULL, ld->err);
}

/* LightSource "infinite": the scene's environment (lights/envmap.h). A constant one is
 * L x scale, with pbrt-v4's "illuminance" E making it L x scale x E / pi (the illuminance of a
 * uniform unit sky on an upward patch is pi). An image is resampled once, at load, into
 * caustic's equirectangular map (+y up, theta = acos(w.y), phi = atan2(w.z, w.x)): each
 * pixel takes, by nearest lookup, the source pixel its centre direction sees through the
 * light's transform (light-from-world, so any rotation is exact up to the resampling). A
 * square source of N x N becomes 2kN x kN, others of W x H kW x kH, with k the smallest
 * whole factor giving at least 1024 rows (at most 4096), so that a ray sees the source
 * pixel pbrt-v4's per-ray nearest lookup picks except within one copy pixel of its edges. */
static CstStatus infinite_light(Loader *ld, Params *ps, Loc loc, const char *d)
{
    char nm[72];
    Color c = color_s(1.0f);
    float scale = 1.0f, illum = 0.0f;
    int has_l = 0;
    const char *file = NULL;
    Loc fl = loc;
    Param *pp;
    int spectrum = 0;
    TRY(pbrt_get_spectrum_id(ld, ps, d, "L", SPEC_ILLUMINANT, 0, &c, &has_l, &spectrum));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "illuminance", 0.0f, &illum, NULL));
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (file && !file[0]) file = NULL; /* pbrt: an empty name is no image */
    TRY(pbrt_lookup(ld, ps, d, "portal", PT_MASK(PT_POINT3), "point3", &pp));
    if (pp) {
        /* pbrt-v4 PortalImageInfiniteLight: four corners of a rectangle, in the light's
         * space (through the CTM, as the image's directions are); NEE then samples through
         * it (envmap.h EnvPortal) */
        if (pp->num_nums != 12)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pp->loc, "%s: \"portal\" has %d values; expected 4 "
                                "points (12 values)", d, pp->num_nums);
        float corners[12];
        for (int i = 0; i < 4; i++) {
            Vec3 q = transform_point(&ld->gs.ctm.m, v3((float)pp->nums[3 * i], (float)pp->nums[3 * i + 1],
                                                        (float)pp->nums[3 * i + 2]));
            corners[3 * i] = q.x;
            corners[3 * i + 1] = q.y;
            corners[3 * i + 2] = q.z;
        }
        CstStatus pst = cst_scene_set_environment_portal(ld->scene, corners, ld->err);
        if (pst) return pbrt_fail_wrap(ld, pst, pp->loc, d);
    }
    if (file && has_l)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, fl, "%s: both \"L\" and \"filename\"; expected one "
                            "of them (as pbrt-v4)", d);
    if (!(scale >= 0.0f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g; expected a finite scale >= 0", d,
                            (double)scale);
    CstStatus st;
    if (!file) {
        double k = (double)scale * (illum > 0.0f ? (double)illum / PBRT_PI : 1.0);
        Color L = color_scale(c, (float)k);
        if (!color_is_finite(L))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the radiance is not finite", d);
        float lf[3], one[3] = {1.0f, 1.0f, 1.0f};
        pbrt_color_floats(L, lf);
        int first = !ld->env_set;
        st = env_accumulate(ld, NULL, 0, 0, one, lf, loc, d);
        /* Spectral mode: a lone uniform light keeps its spectrum's shape (pbrt-v4
         * UniformInfiniteLight, L / SpectrumToPhotometric(L) x scale: the RGB above holds
         * the luminance); a sum of lights is one RGB map, upsampled. */
        if (!st && !first && spectrum)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: \"L\" added to another infinite light: "
                         "in spectral mode their sum is upsampled from RGB, not kept as a spectrum", d);
        if (!st) st = cst_scene_set_environment_spectrum(ld->scene, first ? spectrum : 0, ld->err);
    } else {
        if (!ld->gs.ctm.inv_ok)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's transform is singular; "
                                "expected an invertible transform", d);
        float *src = NULL;
        int w = 0, h = 0;
        TRY(light_image_read(ld, d, file, fl, &src, &w, &h));
        if (w != h)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, fl, "%s: \"%s\" is %d x %d, not square: pbrt-v4 "
                    "expects an equal-area (square) image; read as an equirectangular map in "
                         "pbrt-v3's convention (+z up in light space)", d, pbrt_clip(file, nm), w, h);
        double k = (double)scale;
        if (illum > 0.0f) {
            double e = env_illuminance(src, w, h);
            k = e > 0.0 ? k * (double)illum / e : k;
        }
        /* Nearest lookup of a nearest lookup: the copy's pixels must be much finer than the
         * source's, or the radiance seen along a ray is a neighbour's (a 16 x 16 map seen
         * through a 32 x 16 copy was 17 % off in one channel against pbrt-v4). So the copy
         * has at least 1024 rows, scaled by a whole factor. */
        int up = h < 1024 ? (1024 + h - 1) / h : 1;
        int ow = (w == h ? 2 * w : w) * up, oh = h * up;
        if (oh > 4096) { /* cap the copy at 8192 x 4096 (400 MB of floats) */
            ow = (int)((long long)ow * 4096 / oh);
            oh = 4096;
        }
        float *out = malloc(3u * (size_t)ow * (size_t)oh * sizeof *out);
        if (!out) {
            free(src);
            return pbrt_oom(ld);
        }
        const Transform *li = &ld->gs.ctm.inv; /* light-from-world */
        for (int y = 0; y < oh; y++) {
            double th = PBRT_PI * (y + 0.5) / oh;
            for (int x = 0; x < ow; x++) {
                double ph = 2.0 * PBRT_PI * (x + 0.5) / ow;
                double wv[3] = {sin(th) * cos(ph), cos(th), sin(th) * sin(ph)}, dl[3], len = 0.0;
                for (int r = 0; r < 3; r++) {
                    dl[r] = (double)li->m[r][0] * wv[0] + (double)li->m[r][1] * wv[1] + (double)li->m[r][2] * wv[2];
                    len += dl[r] * dl[r];
                }
                len = sqrt(len);
                for (int r = 0; r < 3; r++) dl[r] /= len;
                const float *p = &src[3 * env_source_pixel(dl, w, h)];
                float *o = &out[3 * ((size_t)y * (size_t)ow + (size_t)x)];
                for (int ch = 0; ch < 3; ch++) o[ch] = p[ch] > 0.0f ? p[ch] : 0.0f; /* pbrt: ClampZero */
            }
        }
        free(src);
        if (!isfinite(k))
            k = 0.0;
        /* Already in world space: no world_from_map. The builder copies the pixels. */
        float kf[3] = {(float)k, (float)k, (float)k}, zero[3] = {0.0f, 0.0f, 0.0f};
        st = env_accumulate(ld, out, ow, oh, kf, zero, loc, d); /* takes out */
        if (!st) st = cst_scene_set_environment_spectrum(ld->scene, 0, ld->err); /* an image: RGB */
    }
    if (st) return pbrt_fail_wrap(ld, st, loc, d);
    return CST_OK;
}

/* LightSource "goniometric" (pbrt-v4 GoniometricLight::Create): a point at the CTM's origin
 * whose intensity I x scale is multiplied per direction by a square image in the equal-area
 * layout, each pixel the mean of its R, G, B; light space is the CTM's with y and z
 * swapped (pbrt-v4's swapYZ), so the image's +z (its centre) is the CTM's +y. "power" > 0
 * scales to that flux: 4 pi I mean(image). */
static CstStatus gonio_light(Loader *ld, Params *ps, Loc loc, const char *d)
{
    char nm[72];
    Color c = color_s(1.0f);
    float scale = 1.0f, power = 0.0f;
    const char *file = NULL;
    Loc fl = loc;
    int spectrum = 0;
    TRY(pbrt_get_spectrum_id(ld, ps, d, "I", SPEC_ILLUMINANT, 0, &c, NULL, &spectrum));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "power", 0.0f, &power, NULL));
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (!ld->gs.ctm.inv_ok)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's transform is singular; expected an "
                            "invertible transform", d);
    float *px = NULL;
    int w = 1, h = 1;
    if (!file || !file[0]) {
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: no \"filename\"; the light is isotropic", d);
        if (!(px = malloc(3 * sizeof *px))) return pbrt_oom(ld);
        px[0] = px[1] = px[2] = 1.0f;
    } else {
        TRY(light_image_read(ld, d, file, fl, &px, &w, &h));
        if (w != h) {
            free(px);
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, fl, "%s: \"%s\" is %d x %d; expected a square "
                                "(equal-area) image, as pbrt-v4", d, pbrt_clip(file, nm), w, h);
        }
    }
    size_t count = (size_t)w * (size_t)h;
    double sum = 0.0;
    for (size_t i = 0; i < count; i++) { /* in place: pixel i's mean over its channels */
        px[i] = (px[3 * i] + px[3 * i + 1] + px[3 * i + 2]) / 3.0f;
        sum += (double)px[i];
    }
    double k = (double)scale;
    if (power > 0.0f && sum > 0.0) k *= (double)power / (4.0 * PBRT_PI * sum / (double)count);
    Color intensity = color_scale(c, (float)k);
    if (!color_is_finite(intensity) || !(k >= 0.0)) {
        free(px);
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g gives an intensity that is negative or "
                            "not finite", d, (double)scale);
    }
    CstLightDesc l;
    memset(&l, 0, sizeof l);
    l.type = CST_LIGHT_GONIOMETRIC;
    l.spectrum = spectrum;
    Vec3 p = transform_point(&ld->gs.ctm.m, v3s(0.0f));
    pbrt_vec3_floats(p, l.position);
    pbrt_color_floats(intensity, l.intensity);
    l.image = px;
    l.image_size = w;
    /* light from world: swapYZ x (the CTM's inverse), linear part */
    static const int row[3] = {0, 2, 1};
    for (int r = 0; r < 3; r++)
        for (int col = 0; col < 3; col++) l.light_from_world[3 * r + col] = ld->gs.ctm.inv.m[row[r]][col];
    CstStatus st = pbrt_coords_ok(p) ? cst_scene_add_light(ld->scene, &l, ld->err) : CST_ERR_INVALID_ARG;
    free(px);
    if (st == CST_ERR_INVALID_ARG && !pbrt_coords_ok(p))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's position is beyond the scene limit", d);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

/* LightSource "projection" (pbrt-v4 ProjectionLight::Create): a point at the CTM's origin
 * projecting an RGB image down the CTM's +z, "fov" (default 90) across the image's shorter
 * side; "scale" multiplies and "power" > 0 scales the flux to it, dividing by the image's
 * luminance over its solid angle (pbrt-v4's k_e: pixel centres, cos^3 theta dA on the
 * plane z = 1). The light's frame is the CTM's rotation (a shear or non-uniform scale is
 * made orthonormal by the builder). */
static CstStatus projection_light(Loader *ld, Params *ps, Loc loc, const char *d)
{
    float scale = 1.0f, power = 0.0f, fov = 90.0f;
    const char *file = NULL;
    Loc fl = loc, fovl = loc;
    Param *fp = NULL;
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    TRY(pbrt_get_float(ld, ps, d, "power", 0.0f, &power, NULL));
    TRY(pbrt_lookup(ld, ps, d, "fov", PT_MASK(PT_FLOAT), "float", &fp));
    if (fp) fovl = fp->loc;
    TRY(pbrt_get_float(ld, ps, d, "fov", 90.0f, &fov, NULL));
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (!(fov > 0.0f && fov < 180.0f))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, fovl, "%s: fov %g; expected degrees in (0, 180)", d, (double)fov);
    if (!file || !file[0])
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the image "
                            "to project (pbrt-v4 requires one)", d);
    if (!ld->gs.ctm.inv_ok)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's transform is singular; expected an "
                            "invertible transform", d);
    float *px = NULL;
    int w = 0, h = 0;
    TRY(light_image_read(ld, d, file, fl, &px, &w, &h));
    double k = (double)scale;
    if (power > 0.0f) {
        const double aspect = (double)w / (double)h, t = tan(0.5 * (double)fov * PBRT_PI / 180.0);
        const double sx = aspect > 1.0 ? aspect : 1.0, sy = aspect > 1.0 ? 1.0 : 1.0 / aspect;
        double k_e = 0.0;
        for (int j = 0; j < h; j++)
            for (int i = 0; i < w; i++) {
                double x = ((2.0 * i + 1.0) / w - 1.0) * sx * t, y = ((2.0 * j + 1.0) / h - 1.0) * sy * t;
                double c = 1.0 / sqrt(1.0 + x * x + y * y);
                const float *q = &px[3 * ((size_t)j * (size_t)w + (size_t)i)];
                k_e += (double)color_luminance(color_rgb(q[0], q[1], q[2])) * c * c * c;
            }
        k_e *= 4.0 * sx * sy * t * t / ((double)w * (double)h);
        if (k_e > 0.0) k *= (double)power / k_e;
    }
    CstLightDesc l;
    memset(&l, 0, sizeof l);
    l.type = CST_LIGHT_PROJECTION;
    Vec3 p = transform_point(&ld->gs.ctm.m, v3s(0.0f));
    pbrt_vec3_floats(p, l.position);
    for (int c = 0; c < 3; c++) l.intensity[c] = (float)k;
    l.image = px;
    l.image_width = w;
    l.image_height = h;
    l.fov = fov;
    for (int r = 0; r < 3; r++)
        for (int col = 0; col < 3; col++) l.light_from_world[3 * r + col] = ld->gs.ctm.inv.m[r][col];
    if (!(k >= 0.0) || !isfinite((float)k)) {
        free(px);
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g gives an intensity that is negative or "
                            "not finite", d, (double)scale);
    }
    CstStatus st = pbrt_coords_ok(p) ? cst_scene_add_light(ld->scene, &l, ld->err) : CST_ERR_INVALID_ARG;
    free(px);
    if (st == CST_ERR_INVALID_ARG && !pbrt_coords_ok(p))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's position is beyond the scene limit", d);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

/* LightSource: point, spot and distant as caustic's delta lights, placed by the CTM, with
 * pbrt-v4's scale and power (phi / 4 pi for a point; phi / (2 pi (1 - (cos_start +
 * cos_end) / 2)) for a spot) and illuminance for a distant light; as for area lights an
 * "rgb" spectrum is used as given and blackbody and sampled spectra are normalised to
 * luminance 1 first. "infinite" becomes the environment (infinite_light); others are
 * skipped with a warning. */
static CstStatus light_source(Loader *ld, const char *type, Params *ps, Loc loc, const char *d)
{
    int point = strcmp(type, "point") == 0, spot = strcmp(type, "spot") == 0,
        distant = strcmp(type, "distant") == 0;
    if (strcmp(type, "infinite") == 0) return infinite_light(ld, ps, loc, d);
    if (strcmp(type, "goniometric") == 0) return gonio_light(ld, ps, loc, d);
    if (strcmp(type, "projection") == 0) return projection_light(ld, ps, loc, d);
    if (!point && !spot && !distant) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported (caustic has area, point, "
                     "spot, goniometric, projection, distant and infinite lights); skipped", d);
        return CST_OK;
    }
    CstLightDesc l;
    memset(&l, 0, sizeof l);
    Color c = color_s(1.0f);
    float scale = 1.0f, power = 0.0f, illum = 0.0f;
    TRY(pbrt_get_spectrum_id(ld, ps, d, distant ? "L" : "I", SPEC_ILLUMINANT, 0, &c, NULL, &l.spectrum));
    TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &scale, NULL));
    if (distant) TRY(pbrt_get_float(ld, ps, d, "illuminance", 0.0f, &illum, NULL));
    else TRY(pbrt_get_float(ld, ps, d, "power", 0.0f, &power, NULL));
    Vec3 from, to;
    TRY(get_point3(ld, ps, d, "from", v3s(0.0f), &from));
    TRY(get_point3(ld, ps, d, "to", v3(0.0f, 0.0f, 1.0f), &to));
    if (point) { /* pbrt-v4 reads no "to" for a point light */
        Param *pt = pbrt_find_param(ps, "to");
        if (pt) pt->used = 0;
    }
    const Transform *m = &ld->gs.ctm.m;
    double k = (double)scale;
    if (point || spot) {
        l.type = point ? CST_LIGHT_POINT : CST_LIGHT_SPOT;
        Vec3 p = transform_point(m, from);
        if (spot) {
            float cone = 30.0f, delta = 5.0f;
            TRY(pbrt_get_float(ld, ps, d, "coneangle", 30.0f, &cone, NULL));
            /* pbrt-v4's name (SpotLight::Create); the falloff is smoothstep from
             * cos(coneangle) to cos(coneangle - conedeltaangle). */
            TRY(pbrt_get_float(ld, ps, d, "conedeltaangle", 5.0f, &delta, NULL));
            /* The builder's range: a cone under 0.001 degrees has cos = 1 in float, no
             * directions at all (pbrt itself takes any coneangle > 0). */
            if (!(cone >= 0.001f && cone <= 90.0f) || !(delta >= 0.0f && delta <= cone))
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: coneangle %g, conedeltaangle %g; expected "
                                    "0.001 <= coneangle <= 90 and 0 <= conedeltaangle <= coneangle", d,
                                    (double)cone, (double)delta);
            l.cone_angle = cone;
            l.cone_delta = delta;
            /* The cosines the builder derives from the angles, for pbrt's power. */
            float cos_outer = cosf(cone * (CST_PI / 180.0f)), cos_inner = cosf((cone - delta) * (CST_PI / 180.0f));
            Vec3 axis = transform_vector(m, v3_sub(to, from));
            float len = v3_length(axis);
            if (!(len > 0.0f) || !isfinite(len))
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: \"from\" equals \"to\"; expected the "
                                    "spot's axis", d);
            pbrt_vec3_floats(axis, l.direction); /* normalised by the builder */
            if (power > 0.0f)
                k *= (double)power / (2.0 * PBRT_PI * (1.0 - 0.5 * ((double)cos_inner + (double)cos_outer)));
        } else if (power > 0.0f) {
            k *= (double)power / (4.0 * PBRT_PI);
        }
        if (!pbrt_coords_ok(p))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the light's position is beyond the scene limit", d);
        pbrt_vec3_floats(p, l.position);
    } else {
        l.type = CST_LIGHT_DIRECTIONAL;
        Vec3 dir = transform_vector(m, v3_sub(to, from)); /* the way the light travels */
        float len = v3_length(dir);
        if (!(len > 0.0f) || !isfinite(len))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: \"from\" equals \"to\"; expected the "
                                "light's direction", d);
        pbrt_vec3_floats(dir, l.direction); /* normalised by the builder */
        if (illum > 0.0f) k *= (double)illum;
    }
    Color intensity = color_scale(c, (float)k);
    if (!color_is_finite(intensity) || !(k >= 0.0))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g gives an intensity that is negative "
                            "or not finite", d, (double)scale);
    pbrt_color_floats(intensity, l.intensity);
    CstStatus st = cst_scene_add_light(ld->scene, &l, ld->err);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

CstStatus pbrt_light_source_directive(Loader *ld, NamedCall *call)
{
    if (!ld->in_world)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, call->loc, "LightSource before WorldBegin; expected it in the world block");
    pbrt_warn_static(ld, call->loc, call->d, "lights do not move (as in pbrt-v4)");
    return light_source(ld, call->type, &call->ps, call->loc, call->d);
}

/* pbrt-v4's DiffuseAreaLight "filename": radiance scale x the image's RGB at the shape's
 * (u, v), looked up bilinearly with clamping and v flipped as pbrt-v4's imagemap (the
 * texture's own convention), decoded as pbrt-v4 reads images (sRGB for PNG, linear for the
 * rest). The image's mean luminance is kept for "power" (pbrt-v4 divides the power by it:
 * DiffuseAreaLight::Create's k_e). */
static CstStatus area_light_image(Loader *ld, const char *file, Loc fl, const char *d, AreaLight *al)
{
    char nm[72];
    if (image_format_from_path(file) == IMAGE_FILE_NONE)
        return pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, fl, "%s: image \"%s\" is not PNG, JPEG, BMP, TGA, HDR, EXR "
                            "or PFM; expected an image file", d, pbrt_clip(file, nm));
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    size_t n = strlen(file);
    CstTextureDesc t = {0};
    t.type = CST_TEXTURE_IMAGE;
    t.path = path;
    t.encoding = n >= 4 && strcasecmp(file + n - 4, ".png") == 0 ? CST_TEXTURE_ENCODING_SRGB
                                                                 : CST_TEXTURE_ENCODING_LINEAR;
    t.wrap = CST_TEXTURE_WRAP_CLAMP;
    t.filter = CST_TEXTURE_FILTER_BILINEAR;
    int id = 0;
    CstStatus st = cst_scene_add_texture(ld->scene, &t, &id, ld->err);
    free(path);
    if (st) return pbrt_fail_wrap(ld, st, fl, d);
    CstTextureInfo info;
    if ((st = cst_scene_texture_info(ld->scene, id, &info, ld->err))) return pbrt_fail_wrap(ld, st, fl, d);
    al->texture = id;
    al->L = color_s(1.0f);
    al->image_lum = color_luminance(color_rgb(info.average[0], info.average[1], info.average[2]));
    return CST_OK;
}

CstStatus pbrt_area_light_source_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    if (!ld->in_world) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "AreaLightSource before WorldBegin; expected it in the world block");
    }
    if (strcmp(type, "diffuse") != 0 && strcmp(type, "area") != 0) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not supported; the shapes that follow do not emit", d);
        ld->gs.area.active = 0;
    } else {
        AreaLight al = {1, color_s(1.0f), 1.0f, 0.0f, 0, 0, 1.0f, 0};
        const char *file = NULL;
        Loc fl = loc;
        int has_l = 0;
        TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
        TRY(pbrt_get_spectrum_id(ld, ps, d, "L", SPEC_ILLUMINANT, 0, &al.L, &has_l, &al.spectrum));
        if (file && has_l)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, fl, "%s: both \"L\" and \"filename\"; expected one "
                                "of them (pbrt-v4 refuses both)", d);
        if (file) TRY(area_light_image(ld, file, fl, d, &al));
        TRY(pbrt_get_float(ld, ps, d, "scale", 1.0f, &al.scale, NULL));
        TRY(pbrt_get_float(ld, ps, d, "power", 0.0f, &al.power, NULL));
        TRY(pbrt_get_bool(ld, ps, d, "twosided", 0, &al.two_sided));
        if (!(al.scale >= 0.0f) || !color_is_finite(color_scale(al.L, al.scale))) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: scale %g; expected a finite scale >= 0",
                              d, (double)al.scale);
        }
        ld->gs.area = al;
    }
    return CST_OK;
}
