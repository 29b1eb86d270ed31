/* Cameras: pinhole and thin lens (the lens is a disk of aperture_radius, focused on the
 * plane at focus_distance). Generates world-space primary rays from film positions and,
 * for light tracing, connects scene points back to the film with their importance. */
#ifndef CST_CAMERA_CAMERA_H
#define CST_CAMERA_CAMERA_H

#include <stdbool.h>

#include "geometry/ray.h"
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
} Camera;

void camera_init(Camera *cam, const CameraDesc *desc, int width, int height);
/* Flips the image horizontally: image right becomes up x forward, the left-handed frame
 * of a pbrt LookAt (scene/pbrt/pbrt_transform.c). Call after camera_init; every use of right
 * (rays, lens offsets, camera_sample_wi) flips together. */
void camera_mirror_x(Camera *cam);
/* film_x in [0, width), film_y in [0, height), y = 0 the top row; lens_u in [0,1)^2. */
Ray camera_generate_ray(const Camera *cam, float film_x, float film_y, Vec2 lens_u);

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
