/* caustic view's camera moves: the frame of a CstCameraDesc and the orbit, pan and dolly the
 * mouse (or a script) applies to it, in doubles. No SDL here: view.c maps the input. */
#ifndef CST_CLI_VIEW_CAMERA_H
#define CST_CLI_VIEW_CAMERA_H

#include <math.h>
#include <stdbool.h>

#include "caustic/caustic.h"

#define VIEW_PI 3.14159265358979323846

static inline double view_v3_dot(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Normalises a in place (left as is when zero); returns its former length. */
static inline double view_v3_norm(double a[3])
{
    double l = sqrt(view_v3_dot(a, a));
    if (l > 0.0)
        for (int k = 0; k < 3; k++) a[k] /= l;
    return l;
}

/* The camera's frame: forward (unit, towards look_at), right, up (units); returns the
 * target distance. */
double view_camera_frame(const CstCameraDesc *c, double f[3], double r[3], double u[3]);

/* Left drag of (dx, dy) pixels on a window `height` pixels tall: orbit about look_at, dx
 * turning about the up hint, dy about right (a drag across the height is half a turn); the
 * pitch stops 1 degree short of the up hint so the frame stays defined. */
void view_camera_orbit(CstCameraDesc *c, int height, double dx, double dy);

/* Middle (or shift-left) drag: position and look_at slide with the image, by the pixel
 * size at the target's distance. */
void view_camera_pan(CstCameraDesc *c, int height, double dx, double dy);

/* Wheel: dolly towards (steps > 0) or away from look_at, 10% of the distance a step (an
 * orthographic camera's height instead). False when the camera would reach look_at (not
 * moved). */
bool view_camera_dolly(CstCameraDesc *c, double steps);

/* Whether c is not c0 in any of what the viewer changes (position, look_at, fov, height,
 * focus distance). */
bool view_camera_moved(const CstCameraDesc *c, const CstCameraDesc *c0);

#endif
