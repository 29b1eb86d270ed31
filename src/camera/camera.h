/* Cameras: pinhole and thin lens (the lens is a disk of aperture_radius, focused on the
 * plane at focus_distance). Generates world-space primary rays from film positions. */
#ifndef CST_CAMERA_CAMERA_H
#define CST_CAMERA_CAMERA_H

#include "geometry/ray.h"
#include "math/vec3.h"

typedef struct CameraDesc {
    Vec3 position, look_at, up;
    float vfov_deg;        /* full vertical field of view in degrees, (0, 180) */
    float aperture_radius; /* 0 = pinhole */
    float focus_distance;  /* > 0; distance along the view axis to the plane in focus */
} CameraDesc;

typedef struct Camera {
    Vec3 origin, forward, right, up; /* right = normalize(forward x up_hint), up = right x forward */
    float tan_half_vfov, aspect;
    float aperture_radius, focus_distance;
    int width, height;
} Camera;

void camera_init(Camera *cam, const CameraDesc *desc, int width, int height);
/* film_x in [0, width), film_y in [0, height), y = 0 the top row; lens_u in [0,1)^2. */
Ray camera_generate_ray(const Camera *cam, float film_x, float film_y, Vec2 lens_u);

#endif
