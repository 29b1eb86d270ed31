/* Texture footprints at hits from the camera's minimal ray differentials (pbrt-v4
 * Camera::FindMinimumDifferentials and Approximate_dp_dxy; PBR 4th ed. sec. 10.1). */
#include "scene/footprint.h"

#include <string.h>

void footprint_init(Footprint *fp, const CameraDesc *desc, bool mirror, int width, int height, int spp)
{
    memset(fp, 0, sizeof *fp);
    Camera cam;
    camera_init(&cam, desc, width, height);
    if (mirror) camera_mirror_x(&cam);
    fp->ortho = camera_is_orthographic(&cam);
    fp->origin = cam.origin, fp->forward = cam.forward, fp->right = cam.right, fp->up = cam.up;
    /* Rays through the lens centre (pbrt-v4 does the same), on a 33 x 33 grid of the film
     * (pbrt-v4: 512 x 512; the minimum sits at the film's corners, on the grid either way). */
    enum { N = 33 };
    float pdx = INFINITY, pdy = INFINITY, ddx = INFINITY, ddy = INFINITY;
    Vec2 centre = v2(0.5f, 0.5f);
    for (int j = 0; j < N; j++)
        for (int i = 0; i < N; i++) {
            float fx = (float)i / (float)(N - 1) * (float)(width - 1), fy = (float)j / (float)(N - 1) * (float)(height - 1);
            Ray r = camera_generate_ray(&cam, fx, fy, centre);
            Ray rx = camera_generate_ray(&cam, fx + 1.0f, fy, centre);
            Ray ry = camera_generate_ray(&cam, fx, fy + 1.0f, centre);
            pdx = minf(pdx, v3_length(v3_sub(rx.o, r.o)));
            pdy = minf(pdy, v3_length(v3_sub(ry.o, r.o)));
            ddx = minf(ddx, v3_length(v3_sub(v3_normalize(rx.d), v3_normalize(r.d))));
            ddy = minf(ddy, v3_length(v3_sub(v3_normalize(ry.d), v3_normalize(r.d))));
        }
    fp->pos_dx = pdx, fp->pos_dy = pdy, fp->dir_dx = ddx, fp->dir_dy = ddy;
    fp->spp_scale = maxf(0.125f, 1.0f / sqrtf((float)(spp > 0 ? spp : 1)));
}

/* v turned by the smallest rotation taking unit f to unit w (Rodrigues, about f x w):
 * R v = v + 2 (v.f) w - (v.(f + w)) / (1 + f.w) (f + w). */
static Vec3 rotate_min(Vec3 v, Vec3 f, Vec3 w)
{
    float c = v3_dot(f, w);
    if (c < -0.999f) return v; /* p behind the camera: any frame will do */
    Vec3 s = v3_add(f, w);
    return v3_sub(v3_add(v, v3_scale(w, 2.0f * v3_dot(v, f))), v3_scale(s, v3_dot(v, s) / (1.0f + c)));
}

/* Where the ray (o, d) meets the plane through p with normal n, minus p; zero when it runs
 * parallel to the plane. */
static Vec3 plane_offset(Vec3 o, Vec3 d, Vec3 p, Vec3 n)
{
    float den = v3_dot(n, d);
    if (den == 0.0f) return v3(0.0f, 0.0f, 0.0f);
    float t = v3_dot(n, v3_sub(p, o)) / den;
    Vec3 q = v3_sub(v3_madd(o, d, t), p);
    return isfinite(q.x) && isfinite(q.y) && isfinite(q.z) ? q : v3(0.0f, 0.0f, 0.0f);
}

void footprint_dp_dxy(const Footprint *fp, Vec3 p, Vec3 n, Vec3 *dpdx, Vec3 *dpdy)
{
    Vec3 w, a = fp->right, b = fp->up, base;
    if (fp->ortho) {
        /* The ray reaching p leaves the film at p's projection onto it. */
        w = fp->forward;
        base = v3_madd(p, w, -v3_dot(v3_sub(p, fp->origin), w));
    } else {
        Vec3 to = v3_sub(p, fp->origin);
        float len = v3_length(to);
        if (!(len > 0.0f)) {
            *dpdx = *dpdy = v3(0.0f, 0.0f, 0.0f);
            return;
        }
        w = v3_scale(to, 1.0f / len);
        a = rotate_min(fp->right, fp->forward, w);
        b = rotate_min(fp->up, fp->forward, w);
        base = fp->origin;
    }
    Vec3 ox = v3_madd(base, a, fp->pos_dx), oy = v3_madd(base, b, fp->pos_dy);
    Vec3 dx = v3_madd(w, a, fp->dir_dx), dy = v3_madd(w, b, fp->dir_dy);
    *dpdx = v3_scale(plane_offset(ox, dx, p, n), fp->spp_scale);
    *dpdy = v3_scale(plane_offset(oy, dy, p, n), fp->spp_scale);
}

static float clamp_deriv(float v) { return isfinite(v) ? clampf(v, -1e8f, 1e8f) : 0.0f; }

TexCtx footprint_tex_ctx(const Footprint *fp, Vec3 p, Vec3 n, Vec2 uv, Vec3 dpdu, Vec3 dpdv)
{
    TexCtx c = {.uv = uv, .p = p, .n = n};
    Vec3 dpdx, dpdy;
    footprint_dp_dxy(fp, p, n, &dpdx, &dpdy);
    c.dpdx = dpdx, c.dpdy = dpdy;
    /* Normal equations of the 3 x 2 system [dpdu dpdv] (du, dv)^T = dp. */
    float a00 = v3_dot(dpdu, dpdu), a01 = v3_dot(dpdu, dpdv), a11 = v3_dot(dpdv, dpdv);
    float inv_det = 1.0f / (a00 * a11 - a01 * a01);
    if (!isfinite(inv_det)) return c;
    float b0x = v3_dot(dpdu, dpdx), b1x = v3_dot(dpdv, dpdx), b0y = v3_dot(dpdu, dpdy), b1y = v3_dot(dpdv, dpdy);
    c.dudx = clamp_deriv((a11 * b0x - a01 * b1x) * inv_det);
    c.dvdx = clamp_deriv((a00 * b1x - a01 * b0x) * inv_det);
    c.dudy = clamp_deriv((a11 * b0y - a01 * b1y) * inv_det);
    c.dvdy = clamp_deriv((a00 * b1y - a01 * b0y) * inv_det);
    return c;
}
