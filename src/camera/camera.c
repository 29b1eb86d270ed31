/* Pinhole and thin-lens cameras. The image plane convention matches
 * ../shared/bench/RAYSETS.md: right = normalize(forward x up), up' = right x forward. */
#include "camera/camera.h"

#include "sampling/warp.h"

void camera_init(Camera *cam, const CameraDesc *d, int width, int height)
{
    cam->origin = d->position;
    cam->forward = v3_normalize(v3_sub(d->look_at, d->position));
    cam->right = v3_normalize(v3_cross(cam->forward, d->up));
    cam->up = v3_cross(cam->right, cam->forward);
    cam->tan_half_vfov = tanf(d->vfov_deg * (CST_PI / 360.0f));
    cam->aspect = (float)width / (float)height;
    cam->aperture_radius = d->aperture_radius;
    cam->focus_distance = d->focus_distance;
    cam->width = width;
    cam->height = height;
}

Ray camera_generate_ray(const Camera *cam, float film_x, float film_y, Vec2 lens_u)
{
    float sx = (2.0f * film_x / (float)cam->width - 1.0f) * cam->tan_half_vfov * cam->aspect;
    float sy = (1.0f - 2.0f * film_y / (float)cam->height) * cam->tan_half_vfov;
    Vec3 d = v3_normalize(v3_add(cam->forward, v3_add(v3_scale(cam->right, sx), v3_scale(cam->up, sy))));
    if (cam->aperture_radius <= 0.0f) return ray_make(cam->origin, d, 0.0f, INFINITY);
    /* Thin lens: every ray through the lens disk meets the pinhole ray on the plane of
     * focus (perpendicular to the view axis at focus_distance). */
    Vec3 focus = v3_madd(cam->origin, d, cam->focus_distance / v3_dot(d, cam->forward));
    Vec2 l = warp_concentric_disk(lens_u);
    Vec3 o = v3_add(cam->origin, v3_add(v3_scale(cam->right, l.x * cam->aperture_radius),
                                        v3_scale(cam->up, l.y * cam->aperture_radius)));
    return ray_make(o, v3_normalize(v3_sub(focus, o)), 0.0f, INFINITY);
}
