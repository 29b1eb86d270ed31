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
    cam->projection = d->ortho_height > 0.0f ? PROJECTION_ORTHOGRAPHIC : PROJECTION_PERSPECTIVE;
    cam->ortho_half_height = cam->projection == PROJECTION_ORTHOGRAPHIC ? 0.5f * d->ortho_height : 0.0f;
    cam->width = width;
    cam->height = height;
    cam->inv_tan_x = 1.0f / (cam->tan_half_vfov * cam->aspect);
    cam->inv_tan_y = 1.0f / cam->tan_half_vfov;
    cam->inv_focus = cam->focus_distance > 0.0f ? 1.0f / cam->focus_distance : 0.0f;
    cam->lens_area = cam->aperture_radius > 0.0f ? CST_PI * cam->aperture_radius * cam->aperture_radius : 1.0f;
    cam->film_area = 4.0f * cam->tan_half_vfov * cam->tan_half_vfov * cam->aspect;
    cam->mirrored = false;
    cam->shutter_open = 0.0f;
    cam->shutter_close = 1.0f;
    cam->moving = false;
}

void camera_mirror_x(Camera *cam)
{
    cam->right = v3_neg(cam->right);
    cam->mirrored = !cam->mirrored;
}

void camera_set_motion(Camera *cam, const MotionTransform *world_from_camera, float shutter_open,
                       float shutter_close)
{
    cam->shutter_open = shutter_open;
    cam->shutter_close = shutter_close;
    cam->moving = false;
    if (!world_from_camera) return;
    cam->motion = *world_from_camera;
    cam->moving = true;
    /* A placement that does not move is applied once: the camera is static again. */
    if (!world_from_camera->moving) *cam = camera_at(cam, 0.0f);
}

Camera camera_at(const Camera *cam, float time)
{
    Camera c = *cam;
    if (!cam->moving) return c;
    c.moving = false;
    /* pbrt-v4 places camera-space rays by the interpolated world-from-camera
     * (CameraTransform, AnimatedTransform::Interpolate); for the rigid placements of real
     * cameras this frame is exactly that. */
    Transform w = motion_at(&cam->motion, time);
    c.origin = transform_point(&w, cam->origin);
    c.forward = v3_normalize(transform_vector(&w, cam->forward));
    c.right = v3_normalize(v3_cross(c.forward, transform_vector(&w, cam->up))); /* up: unmirrored */
    c.up = v3_cross(c.right, c.forward);
    if (cam->mirrored) c.right = v3_neg(c.right);
    return c;
}

Ray camera_generate_ray_at(const Camera *cam, float film_x, float film_y, Vec2 lens_u, float time)
{
    Ray r;
    if (cam->moving) {
        Camera c = camera_at(cam, time);
        r = camera_generate_ray(&c, film_x, film_y, lens_u);
    } else {
        r = camera_generate_ray(cam, film_x, film_y, lens_u);
    }
    r.time = time;
    return r;
}

Ray camera_generate_ray(const Camera *cam, float film_x, float film_y, Vec2 lens_u)
{
    if (camera_is_orthographic(cam)) {
        /* The film is a rectangle through the camera position, perpendicular to the view
         * axis, 2 h aspect wide and 2 h high; every ray leaves it along the axis. */
        float h = cam->ortho_half_height;
        float sx = (2.0f * film_x / (float)cam->width - 1.0f) * h * cam->aspect;
        float sy = (1.0f - 2.0f * film_y / (float)cam->height) * h;
        Vec3 o = v3_add(cam->origin, v3_add(v3_scale(cam->right, sx), v3_scale(cam->up, sy)));
        return ray_make(o, cam->forward, 0.0f, INFINITY);
    }
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

/* Importance of a perspective camera: Veach thesis ch. 10 (light tracing as the t = 1
 * strategies of bidirectional path tracing); pbrt-v3 sec. 16.1.1, pbrt-v4
 * PerspectiveCamera::We and SampleWi.
 *
 * With the box filter a pixel is the average of radiance over its film area (raster
 * units, area 1), and raster units map to the image plane at distance 1 with the constant
 * Jacobian W H / A, A = (2 tan(vfov/2) aspect) (2 tan(vfov/2)) that plane's area. A patch
 * dA of the plane seen from the lens along a ray at angle theta to the view axis subtends
 * d omega = cos^3 theta dA (distance 1/cos theta, tilt theta); for the thin lens the same
 * holds on the plane of focus, where every ray of a film position meets its pinhole ray.
 * Averaging over the lens too (area A_lens), per unit film area as pbrt normalises it
 * (the integral of W_e cos theta over lens and directions is 1):
 *   W_e = 1 / (A A_lens cos^4 theta),
 * one cos theta being the lens's own cosine in the geometry term. The lens point, uniform
 * on the disk (area density 1 / A_lens), has density pdf_w = d^2 / (cos theta A_lens) per
 * unit solid angle at a point p at distance d, so
 *   W_e / pdf_w = 1 / (A cos^3 theta d^2):
 * the film-plane-to-solid-angle conversion 1 / (A cos^3 theta) times 1 / d^2, as in
 * SmallVCM's light tracer; the cosine at p comes with the BSDF. A pinhole is the limit
 * with A_lens = 1 as a formal unit (pbrt's convention): only the ratio matters. "Per unit
 * film" becomes "per pixel" by the factor W H, which the render driver applies as
 * (pixel count / light paths). */
bool camera_sample_wi(const Camera *cam, Vec3 p, Vec2 lens_u, float margin, CameraWiSample *out)
{
    if (camera_is_orthographic(cam)) return false;
    Vec3 o = cam->origin;
    float lens_x = 0.0f, lens_y = 0.0f;
    if (cam->aperture_radius > 0.0f) {
        Vec2 l = warp_concentric_disk(lens_u);
        lens_x = l.x * cam->aperture_radius;
        lens_y = l.y * cam->aperture_radius;
        o = v3_add(o, v3_add(v3_scale(cam->right, lens_x), v3_scale(cam->up, lens_y)));
    }
    Vec3 d = v3_sub(p, o);
    float dz = v3_dot(d, cam->forward);
    if (!(dz > 0.0f)) return false;
    /* The inverse of camera_generate_ray: the film position is that of the pinhole ray
     * through the point where o -> p crosses the plane of focus. On the image plane at
     * distance 1 that point is (lens offset) / focus_distance + (d's slope); the pinhole
     * has no lens offset (lens_x = lens_y = 0). Reciprocals precomputed by camera_init:
     * this runs at every vertex of every light path. */
    float inv_dz = 1.0f / dz;
    float sx = v3_dot(d, cam->right) * inv_dz + lens_x * cam->inv_focus;
    float sy = v3_dot(d, cam->up) * inv_dz + lens_y * cam->inv_focus;
    float fx = (sx * cam->inv_tan_x + 1.0f) * 0.5f * (float)cam->width;
    float fy = (1.0f - sy * cam->inv_tan_y) * 0.5f * (float)cam->height;
    if (!(fx >= -margin && fx < (float)cam->width + margin && fy >= -margin &&
          fy < (float)cam->height + margin))
        return false;
    float dist2 = v3_length2(d);
    float dist = sqrtf(dist2);
    if (!(dist > 0.0f)) return false;
    float inv_dist = 1.0f / dist;
    float cos_theta = dz * inv_dist;
    float cos2 = cos_theta * cos_theta;
    out->raster = v2(fx, fy);
    out->p_lens = o;
    out->wi = v3_scale(d, -inv_dist);
    out->dist = dist;
    out->we = 1.0f / (cam->film_area * cam->lens_area * cos2 * cos2);
    out->pdf_w = dist2 / (cos_theta * cam->lens_area);
    return true;
}
