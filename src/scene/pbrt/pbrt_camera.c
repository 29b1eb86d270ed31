/* The Camera directive, and at the end of the file the camera it leaves to the scene
 * (pbrt's screen window and field of view onto caustic's camera). */
#include "scene/pbrt/pbrt_camera.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_shape.h"
#include "scene/pbrt/pbrt_transform.h"

CstStatus pbrt_camera_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *type = NULL, nm[72], d[96];
    Params ps = {0};
    Loc tl;
    CstStatus st = pbrt_expect_string(ld, lx, "Camera", "the camera type, as in \"perspective\"", &type, &tl);
    if (!st) st = pbrt_parse_params(ld, lx, &ps);
    if (st) goto done;
    snprintf(d, sizeof d, "Camera \"%s\"", pbrt_clip(type, nm));
    if (ld->in_world) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "Camera after WorldBegin; expected the camera before WorldBegin");
        goto done;
    }
    int ortho = strcmp(type, "orthographic") == 0;
    if (strcmp(type, "perspective") != 0 && !ortho) {
        st = pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, tl, "%s is not supported; expected \"perspective\" or "
                          "\"orthographic\" (caustic has pinhole, thin-lens and orthographic cameras)", d);
        goto done;
    }
    if (!ld->gs.ctm.inv_ok || !ld->gs.ctm_end.inv_ok) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: the camera transform%s is singular; expected "
                          "an invertible transform (as from LookAt)", d, ld->gs.ctm.inv_ok ? " at the end time" : "");
        goto done;
    }
    CamRec *c = &ld->cam;
    memset(c, 0, sizeof *c);
    c->set = 1;
    c->ctm = ld->gs.ctm;
    c->ctm_end = ld->gs.ctm_end;
    c->loc = loc;
    c->ortho = ortho;
    c->medium = ld->gs.med_out; /* pbrt-v4's CameraMedium: the outside medium here */
    c->fov = 90.0f;
    Param *p;
    if (!ortho && (st = pbrt_get_float(ld, &ps, d, "fov", 90.0f, &c->fov, NULL))) goto done;
    if ((st = pbrt_get_float(ld, &ps, d, "lensradius", 0.0f, &c->lens_radius, NULL))) goto done;
    if ((st = pbrt_get_float(ld, &ps, d, "focaldistance", 1e6f, &c->focal_distance, NULL))) goto done;
    if ((st = pbrt_get_float(ld, &ps, d, "frameaspectratio", 0.0f, &c->frame, &c->has_frame))) goto done;
    /* pbrt-v4's sensor exposes for shutterclose - shutteropen (default 1): the imaging
     * ratio exposure_time * iso / 100 (film.cpp PixelSensor::Create), here stops of the
     * output exposure, added to the Film's iso ones (pbrt_options.c) in either order. */
    float t0 = 0.0f, t1 = 1.0f;
    if ((st = pbrt_get_float(ld, &ps, d, "shutteropen", 0.0f, &t0, NULL))) goto done;
    if ((st = pbrt_get_float(ld, &ps, d, "shutterclose", 1.0f, &t1, NULL))) goto done;
    if (t1 - t0 != 1.0f) {
        if (!(t1 > t0) || !isfinite(t1 - t0)) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: shutteropen %g, shutterclose %g; expected "
                              "shutteropen < shutterclose (the exposure time is their difference)", d,
                              (double)t0, (double)t1);
            goto done;
        }
        ld->settings.exposure = (ld->settings.exposure_set ? ld->settings.exposure : 0.0) + log2((double)(t1 - t0));
        ld->settings.exposure_set = 1;
    }
    c->shutter[0] = t0; /* the interval of ray times too (pbrt-v4 CameraBase::SampleTime) */
    c->shutter[1] = t1;
    if ((st = pbrt_lookup(ld, &ps, d, "screenwindow", PT_MASK(PT_FLOAT), "float", &p))) goto done;
    if (p) {
        if (p->num_nums != 4) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"float screenwindow\" has %d values; "
                              "expected 4: xmin xmax ymin ymax", d, p->num_nums);
            goto done;
        }
        memcpy(c->screen, p->nums, sizeof c->screen);
        c->has_screen = 1;
        if (!(c->screen[1] > c->screen[0]) || !(c->screen[3] > c->screen[2])) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: screenwindow (%g %g %g %g) is empty; "
                              "expected xmin < xmax and ymin < ymax", d, c->screen[0], c->screen[1],
                              c->screen[2], c->screen[3]);
            goto done;
        }
    }
    if (!(c->fov > 0.0f && c->fov < 180.0f)) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: fov %g; expected degrees in (0, 180)", d, (double)c->fov);
        goto done;
    }
    if (!(c->lens_radius >= 0.0f) || !(c->focal_distance > 0.0f) || (c->has_frame && !(c->frame > 0.0f))) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: lensradius %g, focaldistance %g, "
                          "frameaspectratio %g; expected lensradius >= 0 and the others > 0", d,
                          (double)c->lens_radius, (double)c->focal_distance, (double)c->frame);
        goto done;
    }
    if (ortho && c->lens_radius > 0.0f) {
        /* pbrt-v4's orthographic camera can have a thin lens; caustic's cannot. */
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: lensradius %g and focaldistance %g ignored: "
                     "caustic's orthographic camera is always in focus", d, (double)c->lens_radius,
                     (double)c->focal_distance);
        c->lens_radius = 0.0f;
    }
    pbrt_params_warn_unused(ld, &ps, d);
    /* pbrt names the camera's space "camera": world-from-camera for CoordSysTransform. */
    st = pbrt_set_named_xf(ld, "camera", pbrt_xf_swap(c->ctm), pbrt_xf_swap(c->ctm_end));
done:
    free(type);
    pbrt_params_free(&ps);
    return st;
}

/* The CstCameraDesc equal to pbrt's view: position and axes from world-from-camera; pbrt's
 * image right is the camera's +x, ours forward x up, so a frame where those disagree
 * (every plain LookAt: x = up x dir) is rendered mirrored (CstCameraDesc.mirror). fov spans
 * the shorter image axis in pbrt and the vertical one in caustic. */
CstStatus pbrt_camera_finish(Loader *ld)
{
    CamRec c = ld->cam;
    if (!c.set) { /* pbrt's default: at the origin looking down +z, fov 90 */
        c.ctm = c.ctm_end = pbrt_xf_identity();
        c.fov = 90.0f;
        c.focal_distance = 1e6f;
        c.shutter[1] = 1.0f;
        c.loc = ld->end;
    }
    const int moving = memcmp(c.ctm.m.m, c.ctm_end.m.m, sizeof c.ctm.m.m) != 0;
    const Transform *w = &c.ctm.inv;
    CstCameraDesc desc = {0};
    Vec3 pos = transform_point(w, v3s(0.0f));
    Vec3 f = transform_vector(w, v3(0.0f, 0.0f, 1.0f));
    Vec3 u = transform_vector(w, v3(0.0f, 1.0f, 0.0f));
    Vec3 x = transform_vector(w, v3(1.0f, 0.0f, 0.0f));
    float fl = v3_length(f);
    if (!pbrt_coords_ok(pos) || !(fl > 0.0f) || !isfinite(fl) || !v3_is_finite(u) ||
        !(v3_length(v3_cross(f, u)) > 1e-6f * fl * v3_length(u)))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: the camera transform gives no usable "
                            "view (position (%g, %g, %g)); expected an invertible, finite transform",
                            (double)pos.x, (double)pos.y, (double)pos.z);
    f = v3_scale(f, 1.0f / fl);
    /* look_at a power-of-two multiple of the unit forward away, at least |position|: the
     * scaling is exact and the difference look_at - position loses at most an ulp. */
    float s = 1.0f;
    while (s < v3_max_abs(pos) && s < 1e30f) s *= 2.0f;
    pbrt_vec3_floats(pos, desc.position);
    pbrt_vec3_floats(v3_add(pos, v3_scale(f, s)), desc.look_at);
    pbrt_vec3_floats(u, desc.up);
    desc.mirror = v3_dot(x, v3_cross(f, u)) < 0.0f;
    if (moving) {
        /* A moving camera (CameraTransform with two transforms): the view in camera space
         * (pbrt's: looking down +z, y up), placed by world-from-camera at the start and
         * end times (cst_scene_set_camera_motion); mirror as the start placement sees it. */
        static const float origin[3] = {0.0f, 0.0f, 0.0f}, ahead[3] = {0.0f, 0.0f, 1.0f}, y[3] = {0.0f, 1.0f, 0.0f};
        memcpy(desc.position, origin, sizeof origin);
        memcpy(desc.look_at, ahead, sizeof ahead);
        memcpy(desc.up, y, sizeof y);
    }
    int w_px = ld->settings.width, h_px = ld->settings.height;
    double aspect = (double)w_px / (double)h_px;
    double frame = c.has_frame ? (double)c.frame : aspect;
    /* pbrt's default screen window spans [-1, 1] on the shorter axis. */
    double sx0, sx1, sy0, sy1;
    if (frame > 1.0) { sx0 = -frame; sx1 = frame; sy0 = -1.0; sy1 = 1.0; }
    else { sx0 = -1.0; sx1 = 1.0; sy0 = -1.0 / frame; sy1 = 1.0 / frame; }
    if (c.has_screen) { sx0 = c.screen[0]; sx1 = c.screen[1]; sy0 = c.screen[2]; sy1 = c.screen[3]; }
    double half_h = 0.5 * (sy1 - sy0), half_w = 0.5 * (sx1 - sx0);
    if (fabs(sx0 + sx1) > 1e-6 * half_w || fabs(sy0 + sy1) > 1e-6 * half_h)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, c.loc, "Camera: off-centre screenwindow (%g %g %g %g) "
                     "rendered centred with the same size", sx0, sx1, sy0, sy1);
    if (fabs(half_w / half_h - aspect) > 1e-4 * aspect)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, c.loc, "Camera: screen window aspect %g differs from "
                     "the film's %g; the vertical extent is kept and the image is not stretched",
                     half_w / half_h, aspect);
    if (c.ortho) {
        /* pbrt's orthographic rays leave the screen window at z = 0 in camera space, so the
         * view's height is the window's, in camera units scaled into the world. */
        desc.type = CST_CAMERA_ORTHOGRAPHIC;
        desc.fov = 90.0f; /* not the rays': bdpt/vcm's film-area term, as it has always been */
        desc.height = (float)(2.0 * half_h * (double)v3_length(u));
        if (!(desc.height > 0.0f) || !isfinite(desc.height))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: the orthographic view is %g high; "
                                "expected a finite height > 0 (from screenwindow and the transform)",
                                (double)desc.height);
    } else {
        desc.type = CST_CAMERA_PERSPECTIVE;
        if (half_h == 1.0) {
            desc.fov = c.fov; /* the common case, bit for bit */
        } else {
            double t = tan((double)c.fov * PBRT_PI / 360.0) * half_h;
            desc.fov = (float)(360.0 / PBRT_PI * atan(t));
        }
        if (!(desc.fov > 0.0f && desc.fov < 180.0f))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, c.loc, "Camera: fov %g with this screen window gives a "
                                "vertical field of view of %g degrees; expected less than 180",
                                (double)c.fov, (double)desc.fov);
        desc.aperture_radius = c.lens_radius;
        /* The builder's bound on lengths; only a thin lens reads the distance. */
        desc.focus_distance = minf(c.focal_distance, (float)PBRT_MAX_LENGTH);
        if (c.lens_radius > 0.0f && c.focal_distance > desc.focus_distance)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, c.loc, "Camera: focaldistance %g is beyond caustic's limit "
                         "on lengths; focused at %g", (double)c.focal_distance, PBRT_MAX_LENGTH);
    }
    CstStatus st = cst_scene_set_camera(ld->scene, &desc, ld->err);
    if (!st && c.medium) st = cst_scene_set_camera_medium(ld->scene, c.medium - 1, ld->err);
    if (!st && moving) {
        float r0[12], r1[12];
        for (int r = 0; r < 3; r++) {
            memcpy(&r0[4 * r], c.ctm.inv.m[r], sizeof c.ctm.inv.m[r]);
            memcpy(&r1[4 * r], c.ctm_end.inv.m[r], sizeof c.ctm_end.inv.m[r]);
        }
        st = cst_scene_set_camera_motion(ld->scene, r0, r1, ld->err);
    }
    /* The shutter in caustic's times: TransformTimes' start at 0, its end at 1. */
    const double t0 = ld->transform_times[0], span = ld->transform_times[1] - t0;
    const float open = (float)(((double)c.shutter[0] - t0) / span), close = (float)(((double)c.shutter[1] - t0) / span);
    if (!st && (open != 0.0f || close != 1.0f)) st = cst_scene_set_shutter(ld->scene, open, close, ld->err);
    return st ? pbrt_fail_wrap(ld, st, c.loc, "Camera") : CST_OK;
}
