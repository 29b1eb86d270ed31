/* caustic view's camera moves (view_camera.h): orbit, pan and dolly of a CstCameraDesc. */
#include "view_camera.h"

#include <string.h>

static void v3_set(float o[3], double x, double y, double z)
{
    o[0] = (float)x;
    o[1] = (float)y;
    o[2] = (float)z;
}

static void v3_cross(const double a[3], const double b[3], double o[3])
{
    o[0] = a[1] * b[2] - a[2] * b[1];
    o[1] = a[2] * b[0] - a[0] * b[2];
    o[2] = a[0] * b[1] - a[1] * b[0];
}

/* Rotates v about the unit axis a by angle t (Rodrigues). */
static void v3_rotate(double v[3], const double a[3], double t)
{
    double c = cos(t), s = sin(t), axv[3], d = view_v3_dot(a, v);
    v3_cross(a, v, axv);
    for (int k = 0; k < 3; k++) v[k] = v[k] * c + axv[k] * s + a[k] * d * (1.0 - c);
}

double view_camera_frame(const CstCameraDesc *c, double f[3], double r[3], double u[3])
{
    double up[3] = {(double)c->up[0], (double)c->up[1], (double)c->up[2]};
    if (up[0] == 0.0 && up[1] == 0.0 && up[2] == 0.0) up[1] = 1.0;
    for (int k = 0; k < 3; k++) f[k] = (double)c->look_at[k] - (double)c->position[k];
    double dist = view_v3_norm(f);
    v3_cross(f, up, r);
    view_v3_norm(r);
    v3_cross(r, f, u);
    return dist;
}

void view_camera_orbit(CstCameraDesc *c, int height, double dx, double dy)
{
    double f[3], r[3], u[3], up[3] = {(double)c->up[0], (double)c->up[1], (double)c->up[2]};
    view_camera_frame(c, f, r, u);
    if (up[0] == 0.0 && up[1] == 0.0 && up[2] == 0.0) up[1] = 1.0;
    view_v3_norm(up);
    double off[3];
    for (int k = 0; k < 3; k++) off[k] = (double)c->position[k] - (double)c->look_at[k];
    const double per_pixel = VIEW_PI / (double)height;
    v3_rotate(off, up, -dx * per_pixel);
    v3_rotate(r, up, -dx * per_pixel);
    double dist = sqrt(view_v3_dot(off, off)), pitch = asin(fmax(-1.0, fmin(1.0, view_v3_dot(off, up) / dist)));
    double lim = VIEW_PI / 2.0 - VIEW_PI / 180.0, t = -dy * per_pixel;
    if (pitch + t > lim) t = lim - pitch;
    if (pitch + t < -lim) t = -lim - pitch;
    v3_rotate(off, r, -t);
    v3_set(c->position, (double)c->look_at[0] + off[0], (double)c->look_at[1] + off[1], (double)c->look_at[2] + off[2]);
}

void view_camera_pan(CstCameraDesc *c, int height, double dx, double dy)
{
    double f[3], r[3], u[3];
    double dist = view_camera_frame(c, f, r, u);
    double px = c->type == CST_CAMERA_ORTHOGRAPHIC ? (double)c->height / height
                                                   : 2.0 * dist * tan((double)c->fov * VIEW_PI / 360.0) / height;
    double sx = c->mirror ? -1.0 : 1.0;
    for (int k = 0; k < 3; k++) {
        double d = (-dx * sx * r[k] + dy * u[k]) * px;
        c->position[k] = (float)((double)c->position[k] + d);
        c->look_at[k] = (float)((double)c->look_at[k] + d);
    }
}

bool view_camera_dolly(CstCameraDesc *c, double steps)
{
    double k = pow(0.9, steps);
    if (c->type == CST_CAMERA_ORTHOGRAPHIC) {
        c->height = (float)((double)c->height * k);
        return true;
    }
    double p[3], off[3];
    for (int i = 0; i < 3; i++) {
        off[i] = ((double)c->position[i] - (double)c->look_at[i]) * k;
        p[i] = (double)c->look_at[i] + off[i];
    }
    if (sqrt(view_v3_dot(off, off)) < 1e-6) return false;
    v3_set(c->position, p[0], p[1], p[2]);
    if (c->focus_distance > 0.0f && c->aperture_radius == 0.0f) c->focus_distance = 0.0f;
    return true;
}

bool view_camera_moved(const CstCameraDesc *c, const CstCameraDesc *c0)
{
    return memcmp(c->position, c0->position, sizeof c->position) != 0 ||
           memcmp(c->look_at, c0->look_at, sizeof c->look_at) != 0 || c->fov != c0->fov || c->height != c0->height ||
           c->focus_distance != c0->focus_distance;
}
