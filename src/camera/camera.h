/* Cameras: pinhole and thin lens (the lens is a disk of aperture_radius, focused on the
 * plane at focus_distance). Generates world-space primary rays from film positions and,
 * for light tracing, connects scene points back to the film with their importance. */
#ifndef CST_CAMERA_CAMERA_H
#define CST_CAMERA_CAMERA_H

#include <stdbool.h>

#include "geometry/ray.h"
#include "math/motion.h"
#include "math/vec3.h"

/* The projection. A thin-lens camera is a perspective one with aperture_radius > 0. */
typedef enum CameraProjection {
    PROJECTION_PERSPECTIVE,  /* pinhole or thin lens: rays through one point (or the lens disk) */
    PROJECTION_ORTHOGRAPHIC  /* parallel rays along the view axis from a film of ortho height */
} CameraProjection;

typedef struct CameraDesc {
    Vec3 position, look_at, up;
    float vfov_deg;        /* full vertical field of view in degrees, (0, 180) */
    float aperture_radius; /* 0 = pinhole */
    float focus_distance;  /* > 0; distance along the view axis to the plane in focus */
    float ortho_height;    /* > 0: an orthographic camera, the view's height in scene units
                            * (vfov and the lens are then unused); 0: perspective */
} CameraDesc;

typedef struct Camera {
    CameraProjection projection;
    Vec3 origin, forward, right, up; /* right = normalize(forward x up_hint), up = right x forward */
    float tan_half_vfov, aspect;
    float aperture_radius, focus_distance;
    float ortho_half_height; /* orthographic: half the film's height in scene units */
    int width, height;
    /* Derived by camera_init for camera_sample_wi, which runs at every light-path vertex:
     * 1 / (tan_half_vfov aspect), 1 / tan_half_vfov, 1 / focus_distance, the lens area
     * (1 for a pinhole) and the film area at distance 1. */
    float inv_tan_x, inv_tan_y, inv_focus, lens_area, film_area;
    bool mirrored; /* camera_mirror_x was applied: camera_at flips every placed frame too */
    /* Motion blur (camera_set_motion). A ray's time is uniform over [shutter_open,
     * shutter_close] (camera_time), in the units where every motion has its start transform
     * at 0 and its end transform at 1 ([0, 1] by default). A moving camera's frame above is
     * the camera in its own space; camera_at places it by `motion` at a time. */
    float shutter_open, shutter_close;
    bool moving;
    MotionTransform motion; /* world_from_camera over [0, 1]; read only when moving */
} Camera;

void camera_init(Camera *cam, const CameraDesc *desc, int width, int height);
/* Flips the image horizontally: image right becomes up x forward, the left-handed frame
 * of a pbrt LookAt (scene/pbrt/pbrt_transform.c). Call after camera_init; every use of right
 * (rays, lens offsets, camera_sample_wi) flips together. */
void camera_mirror_x(Camera *cam);
/* film_x in [0, width), film_y in [0, height), y = 0 the top row; lens_u in [0,1)^2. */
Ray camera_generate_ray(const Camera *cam, float film_x, float film_y, Vec2 lens_u);

/* Motion blur: the shutter interval and, when world_from_camera is not NULL, the camera's
 * placement over [0, 1] (the frame camera_init and camera_mirror_x made is then read as the
 * camera in its own space; call after them). A placement that does not move is applied at
 * once and leaves a static camera. camera_init sets a static camera with the shutter [0, 1]. */
void camera_set_motion(Camera *cam, const MotionTransform *world_from_camera, float shutter_open,
                       float shutter_close);
/* The time of a ray from u uniform in [0, 1): uniform over the shutter interval. With the
 * default shutter [0, 1] it is u itself, bit for bit. */
static inline float camera_time(const Camera *cam, float u)
{
    return cam->shutter_open + u * (cam->shutter_close - cam->shutter_open);
}
/* The camera at `time`: a static copy (moving false) whose frame is the moving camera's
 * frame placed by its motion at that time (origin as a point, the view axis and the up
 * hint as vectors, then re-orthonormalised as camera_init does, so a stretch in the
 * transforms never shears the view). A static camera is returned as it is. */
Camera camera_at(const Camera *cam, float time);
/* camera_generate_ray of the camera at `time` (camera_at), the ray carrying that time. */
Ray camera_generate_ray_at(const Camera *cam, float film_x, float film_y, Vec2 lens_u, float time);

/* A scene point connected to the camera (pbrt-v4 PerspectiveCamera::SampleWi). A light
 * path vertex p with throughput beta adds beta * f * |cos theta_p| * we / pdf_w to the
 * film at `raster`, where f |cos theta_p| is its BSDF (or emitted radiance) toward wi. */
typedef struct CameraWiSample {
    Vec2 raster;  /* film position in camera_generate_ray's convention */
    Vec3 p_lens;  /* the point on the lens (pinhole: the origin) */
    Vec3 wi;      /* unit, from p toward p_lens */
    float dist;   /* |p_lens - p| */
    float we;     /* importance W_e of the ray p_lens -> p, normalised over the whole film */
    float pdf_w;  /* density of p_lens per unit solid angle at p */
} CameraWiSample;

/* An orthographic camera's rays are parallel: its direction is a Dirac delta, so no
 * connection from a scene point can reach it (pbrt-v4 leaves OrthographicCamera::SampleWi
 * unimplemented for the same reason) and camera_sample_wi returns false for it. */
static inline bool camera_is_orthographic(const Camera *cam) { return cam->projection == PROJECTION_ORTHOGRAPHIC; }

/* Picks a lens point with lens_u (uniform on the disk, as camera_generate_ray does) and
 * projects p through it. False when p is behind the lens or lands outside the film
 * grown by `margin` pixels on every side (a filter wider than a pixel reaches past the
 * edge). Visibility is the caller's. */
bool camera_sample_wi(const Camera *cam, Vec3 p, Vec2 lens_u, float margin, CameraWiSample *out);

#endif
