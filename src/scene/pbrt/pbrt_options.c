/* Rendering options (Film, Sampler, Integrator, PixelFilter, Accelerator, ColorSpace) mapped
 * onto caustic's settings, and the directives reported as unsupported (media, Attribute,
 * Option). */
#include "scene/pbrt/pbrt_options.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "io/image_io.h"
#include "scene/pbrt/pbrt_params.h"

#define PBRT_MAX_FILM_SIZE 65536

/* Film, Sampler, Integrator, PixelFilter, Accelerator, ColorSpace, MakeNamedMedium, Attribute:
 * a type name and parameters, mapped to settings or reported. */
CstStatus pbrt_film_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->settings;
    int w = 1280, h = 720;
    const char *file = NULL;
    Loc fl = loc;
    TRY(pbrt_get_int(ld, ps, d, "xresolution", 1280, &w));
    TRY(pbrt_get_int(ld, ps, d, "yresolution", 720, &h));
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (w < 1 || h < 1 || w > PBRT_MAX_FILM_SIZE || h > PBRT_MAX_FILM_SIZE) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: resolution %d x %d; expected 1 to %d "
                          "pixels on each side", d, w, h, PBRT_MAX_FILM_SIZE);
    }
    rs->width = w;
    rs->height = h;
    if (file && image_path_is_scene_output(file)) {
        TRY(cst_scene_set_output_path(ld->scene, file, ld->err));
    } else if (file) {
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, fl, "%s: output \"%s\" is not .png, .exr or .pfm; "
                     "ignored (the default output name is used)", d, pbrt_clip(file, nm));
    }
    /* pbrt-v4 (film.cpp): cropwindow [x0 x1 y0 y1] in [0, 1], y down, to the pixel bounds
     * ceil(res * c); pixelbounds given directly, and preferred when both are. */
    Param *pc, *pb;
    TRY(pbrt_lookup(ld, ps, d, "cropwindow", PT_MASK(PT_FLOAT), "float", &pc));
    TRY(pbrt_lookup(ld, ps, d, "pixelbounds", PT_MASK(PT_INTEGER), "integer", &pb));
    if (pc && pb) {
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, pc->loc, "%s: both cropwindow and pixelbounds given; "
                     "pixelbounds is used", d);
        pc = NULL;
    }
    if (pc) {
        const double *c = pc->nums;
        if (pc->num_nums != 4 || !(0.0 <= c[0] && c[0] < c[1] && c[1] <= 1.0 && 0.0 <= c[2] && c[2] < c[3] &&
                                   c[3] <= 1.0)) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pc->loc, "%s: cropwindow; expected 4 values x0 x1 y0 y1 with "
                              "0 <= x0 < x1 <= 1 and 0 <= y0 < y1 <= 1", d);
        }
        rs->crop[0] = (int)ceil(w * c[0]); rs->crop[1] = (int)ceil(w * c[1]);
        rs->crop[2] = (int)ceil(h * c[2]); rs->crop[3] = (int)ceil(h * c[3]);
        if (rs->crop[0] == rs->crop[1] || rs->crop[2] == rs->crop[3]) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pc->loc, "%s: cropwindow holds no pixel of the %d x %d "
                              "image; expected a wider window", d, w, h);
        }
    }
    if (pb) {
        const double *b = pb->nums;
        if (pb->num_nums != 4 || !(0.0 <= b[0] && b[0] < b[1] && b[1] <= w && 0.0 <= b[2] && b[2] < b[3] &&
                                   b[3] <= h)) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pb->loc, "%s: pixelbounds; expected 4 integers x0 x1 y0 y1 "
                              "with 0 <= x0 < x1 <= %d and 0 <= y0 < y1 <= %d", d, w, h);
        }
        for (int k = 0; k < 4; k++) rs->crop[k] = (int)b[k];
    }
    /* The sensor (pbrt-v4 film.cpp PixelSensor::Create): the imaging ratio exposure_time *
     * iso / 100 scales the image in both colour modes; as stops of the output exposure,
     * added to the camera's shutter ones (pbrt_camera.c). */
    float iso = 100.0f, wb = 0.0f;
    int has_iso = 0, has_wb = 0;
    TRY(pbrt_get_float(ld, ps, d, "iso", 100.0f, &iso, &has_iso));
    if (has_iso) {
        if (!(iso > 0.0f) || !isfinite(iso))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: iso %g; expected a positive number (100: "
                                "no scaling)", d, (double)iso);
        rs->exposure = (rs->exposure_set ? rs->exposure : 0.0) + log2((double)iso / 100.0);
        rs->exposure_set = 1;
    }
    /* RGBFilm's clamp of each sample's sensor values (after the imaging ratio above). */
    float maxcv = 0.0f;
    int has_maxcv = 0;
    TRY(pbrt_get_float(ld, ps, d, "maxcomponentvalue", 0.0f, &maxcv, &has_maxcv));
    if (has_maxcv) {
        if (!(maxcv > 0.0f))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: maxcomponentvalue %g; expected a positive "
                                "number", d, (double)maxcv);
        if (isfinite(maxcv)) rs->max_component = (double)maxcv;
    }
    const char *sensor = NULL;
    Loc sl = loc;
    TRY(pbrt_get_string(ld, ps, d, "sensor", &sensor, &sl));
    TRY(pbrt_get_float(ld, ps, d, "whitebalance", 0.0f, &wb, &has_wb));
    if (sensor && strcmp(sensor, "cie1931") != 0)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, sl, "%s: sensor \"%s\" approximated by cie1931 (the CIE 1931 "
                     "matching functions; no camera curves)", d, pbrt_clip(sensor, nm));
    if (has_wb && !(wb >= 0.0f && isfinite(wb)))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: whitebalance %g; expected a colour temperature in "
                            "kelvin > 0, or 0 for none", d, (double)wb);
    /* pbrt-v4's cie1931 sensor: von Kries from the illuminant's white to D65 (film/sensor.h). */
    if (has_wb) rs->white_balance = (double)wb;
    if (strcmp(type, "rgb") != 0 && strcmp(type, "image") != 0)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s rendered as an RGB film", d);
    return CST_OK;
}

CstStatus pbrt_sampler_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    CstRenderSettings *rs = &ld->settings;
    int spp = 16, seed = 0;
    Param *ps_seed = pbrt_find_param(ps, "seed");
    if (strcmp(type, "stratified") == 0) {
        int xs = 4, ys = 4, jitter = 1;
        TRY(pbrt_get_int(ld, ps, d, "xsamples", 4, &xs));
        TRY(pbrt_get_int(ld, ps, d, "ysamples", 4, &ys));
        TRY(pbrt_get_bool(ld, ps, d, "jitter", 1, &jitter));
        spp = (xs > 0 && ys > 0 && xs <= INT_MAX / ys) ? xs * ys : 0;
    } else {
        TRY(pbrt_get_int(ld, ps, d, "pixelsamples", 16, &spp));
    }
    if (spp < 1) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: %d samples per pixel; expected at least 1", d, spp);
    }
    rs->spp = spp;
    TRY(pbrt_get_int(ld, ps, d, "seed", 0, &seed));
    if (ps_seed) {
        if (seed < 0) {
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, ps_seed->loc, "%s: seed %d; expected >= 0", d, seed);
        }
        rs->seed = (uint64_t)seed;
        rs->seed_set = 1;
    }
    /* The nearest of caustic's samplers (sampling/sampler.c): same expectation; only
     * independent is the same kind of noise as pbrt's. */
    if (strcmp(type, "independent") == 0 || strcmp(type, "random") == 0) {
        rs->sampler = CST_SAMPLER_INDEPENDENT;
    } else if (strcmp(type, "stratified") == 0) {
        rs->sampler = CST_SAMPLER_STRATIFIED;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: caustic's stratified sampler (jittered, 2D strata "
                "nx x ny = %d with nx the largest divisor up to its square root); same expectation, "
                     "different noise", d, spp);
    } else if (strcmp(type, "zsobol") == 0) {
        rs->sampler = CST_SAMPLER_ZSOBOL;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: caustic's zsobol sampler (blocks of 256 samples per "
                     "pixel, whatever pixelsamples); same expectation, different noise", d);
    } else {
        rs->sampler = CST_SAMPLER_SOBOL;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: caustic's Owen-scrambled Sobol' sampler; same "
                     "expectation, different noise", d);
    }
    return CST_OK;
}

CstStatus pbrt_integrator_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->settings;
    static const struct { const char *pbrt; CstIntegrator ours; int exact; } map[] = {
        {"path", CST_INTEGRATOR_PATH, 1}, {"volpath", CST_INTEGRATOR_PATH, 1},
        {"simplepath", CST_INTEGRATOR_PATH_NEE, 0}, {"randomwalk", CST_INTEGRATOR_PATH_BSDF, 0},
        {"lightpath", CST_INTEGRATOR_LIGHT, 1}, {"sppm", CST_INTEGRATOR_SPPM, 1},
        {"whitted", CST_INTEGRATOR_WHITTED, 1}, {"bdpt", CST_INTEGRATOR_BDPT, 1},
        {"mlt", CST_INTEGRATOR_MMLT, 1}, {"simplevolpath", CST_INTEGRATOR_PATH, 0},
        {"directlighting", CST_INTEGRATOR_PATH, 0}, {"ambientocclusion", CST_INTEGRATOR_PATH, 0},
        {"aov", CST_INTEGRATOR_PATH, 0}};
    int k = -1;
    for (int i = 0; i < (int)(sizeof map / sizeof map[0]); i++)
        if (strcmp(type, map[i].pbrt) == 0) k = i;
    if (k < 0) {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown integrator \"%s\"; expected one of: "
                     "path, volpath, simplepath, randomwalk, lightpath, bdpt, mlt, sppm, "
                          "simplevolpath, ambientocclusion, aov (pbrt-v3: whitted, directlighting)",
                          pbrt_clip(type, nm));
    }
    rs->integrator = map[k].ours;
    /* pbrt-v4's "lightsampler" (default "bvh"; here, when absent, the rule of
     * cst_scene_set_light_sampler). "exhaustive" (every light per vertex) is not one. */
    const char *lsamp = NULL;
    Loc lsloc = loc;
    TRY(pbrt_get_string(ld, ps, d, "lightsampler", &lsamp, &lsloc));
    if (lsamp) {
        if (strcmp(lsamp, "exhaustive") == 0) {
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, lsloc, "%s: lightsampler \"exhaustive\" rendered with \"bvh\"", d);
            lsamp = "bvh";
        }
        if (strcmp(lsamp, "power") != 0 && strcmp(lsamp, "bvh") != 0 && strcmp(lsamp, "uniform") != 0)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, lsloc, "%s: unknown lightsampler \"%s\"; expected bvh, "
                                "power, uniform or exhaustive", d, pbrt_clip(lsamp, nm));
        TRY(cst_scene_set_light_sampler(ld->scene, lsamp, ld->err));
    }
    /* pbrt-v4's "regularize" (path, volpath, bdpt): caustic's path tracers do it */
    int reg = 0;
    TRY(pbrt_get_bool(ld, ps, d, "regularize", 0, &reg));
    if (reg && map[k].ours != CST_INTEGRATOR_PATH && map[k].ours != CST_INTEGRATOR_PATH_NEE &&
        map[k].ours != CST_INTEGRATOR_PATH_BSDF)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: \"regularize\" is done by caustic's path tracers only; "
                     "this integrator renders without it", d);
    rs->regularize = reg ? 1 : 0;
    int depth = 5;
    TRY(pbrt_get_int(ld, ps, d, "maxdepth", 5, &depth));
    if (strcmp(type, "directlighting") == 0) depth = 1;
    if (depth == 0)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: maxdepth 0 (emitters seen directly only) "
                     "is not expressible; rendered with maxdepth 1", d);
    rs->max_depth = depth < 0 ? 0 : (depth == 0 ? 1 : depth); /* pbrt: < 0 never stops */
    if (map[k].ours == CST_INTEGRATOR_SPPM) {
        int photons = 0;
        float radius = 0.0f;
        int has_r = 0;
        TRY(pbrt_get_int(ld, ps, d, "photonsperiteration", -1, &photons));
        TRY(pbrt_get_float(ld, ps, d, "radius", 1.0f, &radius, &has_r));
        if (photons > 0) rs->photons = photons < (1 << 28) ? photons : (1 << 28);
        /* The radius's square must stay a finite normal float (issue 25); the render also
         * refuses radii below 1e-6 of the scene's diagonal (integrators/integrator.c). */
        if (has_r && radius > 0.0f && !(radius >= 1e-18f && radius <= 1e18f))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g; expected 1e-18 to 1e18 (and at "
                                "least 1e-6 of the scene's size)", d, (double)radius);
        if (has_r && radius > 0.0f) rs->photon_radius = (double)radius;
        int iters = 0;
        TRY(pbrt_get_int(ld, ps, d, "iterations", 0, &iters));
        if (iters > 0) rs->spp = iters;
    }
    if (map[k].ours == CST_INTEGRATOR_MMLT) {
        /* pbrt-v4's MLTIntegrator parameters, its defaults; mutationsperpixel, when given, is
         * the sample count (else the Sampler's pixelsamples, whichever directive comes first) */
        int mpp = -1, boot = 100000, chains = 1000;
        float lsp = 0.3f, sigma = 0.01f;
        TRY(pbrt_get_int(ld, ps, d, "mutationsperpixel", -1, &mpp));
        TRY(pbrt_get_int(ld, ps, d, "bootstrapsamples", 100000, &boot));
        TRY(pbrt_get_int(ld, ps, d, "chains", 1000, &chains));
        TRY(pbrt_get_float(ld, ps, d, "largestepprobability", 0.3f, &lsp, NULL));
        TRY(pbrt_get_float(ld, ps, d, "sigma", 0.01f, &sigma, NULL));
        if ((mpp < 1 && mpp != -1) || boot < 1 || chains < 1 || boot > (1 << 28) || chains > (1 << 24) || !(lsp >= 0.0f && lsp <= 1.0f) ||
            !(sigma > 0.0f && sigma <= 1.0f))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: mutationsperpixel %d, bootstrapsamples %d, chains %d, "
                                "largestepprobability %g, sigma %g; expected counts >= 1 (bootstrapsamples at most "
                                "2^28, chains 2^24), a probability in [0, 1] and a sigma in (0, 1]",
                                d, mpp, boot, chains, (double)lsp, (double)sigma);
        if (mpp > 0) rs->spp = mpp;
        rs->mlt_bootstrap = boot;
        rs->mlt_chains = chains;
        rs->mlt_large_step = (double)lsp;
        rs->mlt_sigma = (double)sigma;
    }
    if (strcmp(type, "ambientocclusion") == 0 || strcmp(type, "aov") == 0) {
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not supported; the path tracer renders "
                     "the image instead", d);
    } else if (!map[k].exact) {
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s rendered with caustic's \"%s\" (the same "
                     "expected image in scenes without participating media)", d,
                     cst_integrator_name(map[k].ours));
    }
    return CST_OK;
}

CstStatus pbrt_pixel_filter_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc loc = call->loc, tl = call->tl;
    char nm[72];
    CstRenderSettings *rs = &ld->settings;
    float rx = 0.0f, ry = 0.0f;
    int hx = 0, hy = 0;
    TRY(pbrt_get_float(ld, ps, d, "xradius", 0.0f, &rx, &hx));
    TRY(pbrt_get_float(ld, ps, d, "yradius", 0.0f, &ry, &hy));
    if (strcmp(type, "box") == 0) {
        rs->filter = CST_FILTER_BOX;
        if ((hx && rx != 0.5f) || (hy && ry != 0.5f))
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: radius other than 0.5 rendered as "
                         "the one-pixel box", d);
    } else if (strcmp(type, "triangle") == 0) {
        rs->filter = CST_FILTER_TENT;
        if (!hx || !hy || rx != 1.0f || ry != 1.0f)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: rendered as caustic's tent of "
                         "radius 1 pixel (pbrt's default radius is 2)", d);
    } else if (strcmp(type, "gaussian") == 0 || strcmp(type, "mitchell") == 0) {
        /* caustic's are pbrt-v4's defaults (film/filter.c): Gaussian sigma 0.5 pixel,
         * radius 1.5, minus its value at the radius; Mitchell radius 2, B = C = 1/3. */
        int gauss = type[0] == 'g', hs = 0, hb = 0, hc = 0;
        float def_r = gauss ? 1.5f : 2.0f, sigma = 0.5f, b = 1.0f / 3.0f, c = 1.0f / 3.0f;
        rs->filter = gauss ? CST_FILTER_GAUSSIAN : CST_FILTER_MITCHELL;
        if (gauss) {
            TRY(pbrt_get_float(ld, ps, d, "sigma", 0.5f, &sigma, &hs));
        } else {
            TRY(pbrt_get_float(ld, ps, d, "B", b, &b, &hb));
            TRY(pbrt_get_float(ld, ps, d, "C", c, &c, &hc));
        }
        if ((hx && rx != def_r) || (hy && ry != def_r) || (hs && sigma != 0.5f) ||
            (hb && fabsf(b - 1.0f / 3.0f) > 1e-6f) || (hc && fabsf(c - 1.0f / 3.0f) > 1e-6f))
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: rendered with caustic's %s filter, %s", d,
                         gauss ? "Gaussian" : "Mitchell", gauss ? "sigma 0.5 and radius 1.5 pixels"
                         : "B = C = 1/3 and radius 2 pixels");
    } else if (strcmp(type, "sinc") == 0 || strcmp(type, "lanczos") == 0) {
        rs->filter = CST_FILTER_MITCHELL;
        pbrt_params_mark_all_used(ps);
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s approximated by the Mitchell filter (B = C = "
                     "1/3, radius 2 pixels), the nearest caustic has to a windowed sinc", d);
    } else {
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown pixel filter \"%s\"; expected one of: "
                          "box, triangle, gaussian, mitchell, sinc", pbrt_clip(type, nm));
    }
    return CST_OK;
}

CstStatus pbrt_accelerator_directive(Loader *ld, NamedCall *call)
{
    Params *ps = &call->ps;
    const char *type = call->type, *d = call->d;
    Loc tl = call->tl;
    pbrt_params_mark_all_used(ps);
    if (strcmp(type, "kdtree") == 0) TRY(cst_scene_set_accel(ld->scene, "kdtree", ld->err));
    else if (strcmp(type, "bvh") != 0)
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, tl, "%s is not known; the BVH is used", d);
    return CST_OK;
}

CstStatus pbrt_color_space_directive(Loader *ld, NamedCall *call)
{
    const char *type = call->type, *d = call->d;
    Loc tl = call->tl;
    if (strcmp(type, "srgb") != 0)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, tl, "%s: RGB values are taken as linear sRGB", d);
    return CST_OK;
}

/* A directive caustic skips whole: its parameters count as used (no second warning per
 * parameter) and one warning says what is missing. */
static CstStatus ignore_directive(Loader *ld, NamedCall *call, const char *what)
{
    pbrt_params_mark_all_used(&call->ps);
    pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, call->loc, "%s: %s are not supported; ignored", call->d, what);
    return CST_OK;
}

CstStatus pbrt_attribute_directive(Loader *ld, NamedCall *call)
{
    return ignore_directive(ld, call, "default parameters by Attribute");
}

/* Option "type name" value: a single parameter, no type name before it */
CstStatus pbrt_option_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    Params ps = {0};
    CstStatus st = pbrt_parse_params(ld, lx, &ps);
    if (!st) pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "Option is not supported; ignored");
    pbrt_params_free(&ps);
    return st;
}
