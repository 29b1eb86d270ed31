/* Light sampling: selection by power, points and directions for next-event estimation and
 * for the starts of light paths, for area emitters and delta lights alike. */
#include "lights/light.h"

#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/triangle.h"
#include "lights/light_bvh.h"
#include "math/frame.h"
#include "sampling/spherical.h"
#include "sampling/warp.h"

/* pbrt-v4's spotlight falloff (SpotLight::I): smoothstep between the cone's cosines. */
static float spot_falloff(const SpotLight *l, float cos_theta)
{
    if (cos_theta >= l->cos_inner) return 1.0f;
    if (cos_theta <= l->cos_outer) return 0.0f;
    float t = (cos_theta - l->cos_outer) / (l->cos_inner - l->cos_outer);
    return t * t * (3.0f - 2.0f * t);
}

/* The factor a goniometric image gives world direction w (unit, away from the light):
 * Clarberg's equal-area octahedral map of the light-space direction ("Fast Equal-Area
 * Mapping of the (Hemi)Sphere using SIMD", JGT 2008; pbrt-v4 EqualAreaSphereToSquare,
 * here with the exact arctangent), nearest pixel as pbrt-v4's GoniometricLight::I. */
static float gonio_factor(const GonioImage *g, Vec3 w)
{
    const float *m = g->light_from_world;
    double d[3];
    double len = 0.0;
    for (int r = 0; r < 3; r++) {
        d[r] = (double)m[3 * r] * (double)w.x + (double)m[3 * r + 1] * (double)w.y + (double)m[3 * r + 2] * (double)w.z;
        len += d[r] * d[r];
    }
    len = sqrt(len);
    if (!(len > 0.0)) return 0.0f;
    double x = fabs(d[0]) / len, y = fabs(d[1]) / len, z = fabs(d[2]) / len;
    double rr = sqrt(fmax(0.0, 1.0 - z));
    double a = fmax(x, y), b = fmin(x, y);
    double phi = atan(a == 0.0 ? 0.0 : b / a) * (2.0 / (double)CST_PI);
    if (x < y) phi = 1.0 - phi;
    double v = phi * rr, u = rr - v;
    if (d[2] < 0.0) {
        double t = u;
        u = 1.0 - v;
        v = 1.0 - t;
    }
    u = 0.5 * (copysign(u, d[0]) + 1.0);
    v = 0.5 * (copysign(v, d[1]) + 1.0);
    int px = (int)(u * g->n), py = (int)(v * g->n);
    px = px < 0 ? 0 : px >= g->n ? g->n - 1 : px;
    py = py < 0 ? 0 : py >= g->n ? g->n - 1 : py;
    return g->factor[(size_t)py * (size_t)g->n + (size_t)px];
}

Color proj_factor(const ProjImage *g, Vec3 w, float *pdf_w)
{
    if (pdf_w) *pdf_w = 0.0f;
    const float *m = g->light_from_world;
    Vec3 d = v3(m[0] * w.x + m[1] * w.y + m[2] * w.z, m[3] * w.x + m[4] * w.y + m[5] * w.z,
                m[6] * w.x + m[7] * w.y + m[8] * w.z);
    if (!(d.z > 0.0f)) return color_s(0.0f);
    /* pbrt-v4 ProjectionLight::I: the point on the screen (its Perspective(fov) transform) */
    float x = d.x / (d.z * g->tan_half), y = d.y / (d.z * g->tan_half);
    if (!(fabsf(x) <= g->sx && fabsf(y) <= g->sy)) return color_s(0.0f);
    int px = (int)((x + g->sx) / (2.0f * g->sx) * (float)g->w), py = (int)((y + g->sy) / (2.0f * g->sy) * (float)g->h);
    px = px < 0 ? 0 : px >= g->w ? g->w - 1 : px;
    py = py < 0 ? 0 : py >= g->h ? g->h - 1 : py;
    const float *c = &g->rgb[3 * ((size_t)py * (size_t)g->w + (size_t)px)];
    if (pdf_w) {
        /* uniform over the window's area A on the plane z = 1, and dA = d omega / cos^3 */
        float cz = d.z / v3_length(d);
        *pdf_w = 1.0f / (g->area * cz * cz * cz);
    }
    return color_rgb(c[0], c[1], c[2]);
}

/* A direction uniform over a projection light's window (u), in world space. */
static Vec3 proj_sample_dir(const ProjImage *g, Vec2 u)
{
    Vec3 d = v3_normalize(v3((2.0f * u.x - 1.0f) * g->sx * g->tan_half, (2.0f * u.y - 1.0f) * g->sy * g->tan_half, 1.0f));
    const float *m = g->light_from_world; /* a rotation: its transpose maps back */
    return v3(m[0] * d.x + m[3] * d.y + m[6] * d.z, m[1] * d.x + m[4] * d.y + m[7] * d.z,
              m[2] * d.x + m[5] * d.y + m[8] * d.z);
}

/* A Lambertian emitter of radiance L and area A emits pi A L per side; a textured one is
 * weighted by its texture's average, which only shifts samples between lights (the point
 * density on an emitter stays uniform by area, so NEE's pdf is unchanged). 4 pi I for a
 * point; for a spot 2 pi I times the cone's solid-angle fraction with the falloff's mean
 * taken as half way (pbrt-v4 SpotLight::Phi); E pi R^2 for a directional light over the
 * scene's disk; the environment's flux through that disk: pi R^2 times the integral of its
 * luminance over the sphere (pbrt-v4's UniformInfiniteLight::Phi for a constant one). */
float light_power(const Light *l, float scene_radius)
{
    switch (l->type) {
    case LIGHT_AREA: {
        const Emitter *e = &l->u.area;
        return CST_PI * e->area * color_luminance(e->average) * (e->two_sided ? 2.0f : 1.0f);
    }
    case LIGHT_POINT: return 4.0f * CST_PI * color_luminance(l->u.point.intensity);
    case LIGHT_SPOT:
        return 2.0f * CST_PI * color_luminance(l->u.spot.intensity) *
               (1.0f - 0.5f * (l->u.spot.cos_inner + l->u.spot.cos_outer));
    case LIGHT_DIRECTIONAL:
        return CST_PI * scene_radius * scene_radius * color_luminance(l->u.directional.irradiance);
    case LIGHT_ENVIRONMENT: return CST_PI * scene_radius * scene_radius * l->u.env->power;
    /* pbrt-v4 GoniometricLight::Phi: 4 pi I times the image's mean (equal-area pixels). */
    case LIGHT_GONIO: return 4.0f * CST_PI * color_luminance(l->u.gonio.intensity) * l->u.gonio.image.mean;
    /* pbrt-v4 ProjectionLight::Phi: I times the image integrated over its solid angle. */
    case LIGHT_PROJECTION: return color_luminance(color_mul(l->u.proj.intensity, l->u.proj.image.integral));
    }
    return 0.0f;
}

static Light light_from_delta(const DeltaLight *d)
{
    Light l;
    memset(&l, 0, sizeof l);
    switch (d->type) {
    case DELTA_POINT:
        l.type = LIGHT_POINT;
        l.u.point.p = d->p;
        l.u.point.intensity = d->intensity;
        break;
    case DELTA_SPOT:
        l.type = LIGHT_SPOT;
        l.u.spot.p = d->p;
        l.u.spot.dir = d->dir;
        l.u.spot.intensity = d->intensity;
        l.u.spot.cos_inner = d->cos_inner;
        l.u.spot.cos_outer = d->cos_outer;
        break;
    case DELTA_DIRECTIONAL:
        l.type = LIGHT_DIRECTIONAL;
        l.u.directional.dir = d->dir;
        l.u.directional.irradiance = d->intensity;
        break;
    case DELTA_GONIO:
        l.type = LIGHT_GONIO;
        l.u.gonio.p = d->p;
        l.u.gonio.intensity = d->intensity;
        l.u.gonio.image = d->gonio;
        break;
    case DELTA_PROJECTION:
        l.type = LIGHT_PROJECTION;
        l.u.proj.p = d->p;
        l.u.proj.intensity = d->intensity;
        l.u.proj.image = d->proj;
        break;
    }
    return l;
}

CstStatus emitter_sampler_init(EmitterSampler *s, const Emitter *emitters, int n, const DeltaLight *delta,
                               int num_delta, const EnvMap *env, Vec3 lo, Vec3 hi, CstError *err)
{
    memset(s, 0, sizeof *s);
    s->center = v3_scale(v3_add(lo, hi), 0.5f);
    s->radius = 0.5f * v3_length(v3_sub(hi, lo));
    if (!(s->radius > 0.0f) || !isfinite(s->radius)) s->radius = 1.0f;
    s->count = n;
    s->num_delta = num_delta;
    s->env = env;
    s->lights = n + num_delta + (env ? 1 : 0);
    if (s->lights == 0) return CST_OK;
    float *w = malloc((size_t)s->lights * sizeof *w);
    s->pdf_a = malloc((size_t)(n > 0 ? n : 1) * sizeof *s->pdf_a);
    s->light = malloc((size_t)s->lights * sizeof *s->light);
    if (!w || !s->pdf_a || !s->light) {
        free(w);
        emitter_sampler_free(s);
        return cst_fail(err, CST_ERR_OOM, "out of memory for %d lights", n + num_delta + (env ? 1 : 0));
    }
    for (int i = 0; i < n; i++) {
        s->light[i].type = LIGHT_AREA;
        s->light[i].u.area = emitters[i];
    }
    for (int i = 0; i < num_delta; i++) s->light[n + i] = light_from_delta(&delta[i]);
    if (env) {
        s->light[n + num_delta].type = LIGHT_ENVIRONMENT;
        s->light[n + num_delta].u.env = env;
    }
    for (int i = 0; i < s->lights; i++) w[i] = light_power(&s->light[i], s->radius);
    /* Lights of zero luminance (pure blue has 0.07, but a hand-written [0, 0, 1e-30]
     * might round to 0) still emit: give every light a floor so none is never picked. */
    double total = 0.0;
    for (int i = 0; i < s->lights; i++) total += (double)w[i];
    for (int i = 0; i < s->lights; i++)
        if (!(w[i] > 1e-6f * (float)total) || !isfinite(w[i])) w[i] = total > 0.0 && isfinite(total) ? 1e-6f * (float)total : 1.0f;
    CstStatus st = distrib1d_init(&s->by_power, w, s->lights, err);
    free(w);
    if (st != CST_OK) {
        emitter_sampler_free(s);
        return st;
    }
    for (int i = 0; i < n; i++) s->pdf_a[i] = s->by_power.pmf[i] / emitters[i].area;
    return CST_OK;
}

void emitter_sampler_free(EmitterSampler *s)
{
    light_bvh_free(s->bvh);
    free(s->bvh);
    distrib1d_free(&s->by_power);
    free(s->pdf_a);
    free(s->light);
    memset(s, 0, sizeof *s);
}

/* The sphere or analytic shape an area emitter is, or NULL (a triangle, or the other kind).
 * Prim ids: triangles, then spheres, then analytic shapes (scene.h scene_prim_info). */
static inline const Sphere *emitter_sphere(const Emitter *e, const EmitterGeometry *g)
{
    int k = (int)e->prim - g->num_triangles;
    return k >= 0 && k < g->num_spheres ? &g->spheres[k] : NULL;
}
static inline const AnalyticShape *emitter_shape(const Emitter *e, const EmitterGeometry *g)
{
    int k = (int)e->prim - g->num_triangles - g->num_spheres;
    return k >= 0 && g->shapes ? &g->shapes[k] : NULL;
}

void emitter_sample_point(const Emitter *e, const EmitterGeometry *g, Vec2 u, Vec3 *p, Vec3 *n, Vec2 *uv)
{
    const AnalyticShape *shape = emitter_shape(e, g);
    if (shape) {
        /* Uniform by area (pbrt-v4 Cylinder/Disk/Sphere::Sample(u)); emitting shapes have a
         * similarity transform (scene_add_shape), so the density is 1 / e->area, the one
         * EmitterSampler.pdf_a assumes. */
        ShapeSurface sf;
        float pdf_a;
        shape_sample_area(shape, u, &sf, &pdf_a);
        *p = sf.p;
        *n = sf.n;
        *uv = sf.uv;
    } else if ((int)e->prim < g->num_triangles) {
        const int32_t *t = &g->tri_indices[3 * e->prim];
        Vec3 a = g->positions[t[0]], b = g->positions[t[1]], c = g->positions[t[2]];
        Vec2 bc = warp_uniform_triangle(u);
        Vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a);
        *p = v3_add(a, v3_add(v3_scale(e1, bc.x), v3_scale(e2, bc.y)));
        *n = e->n;
        *uv = e->texture ? triangle_uv(g->uvs, g->tri_has_uv, g->tri_indices, e->prim, bc.x, bc.y) : v2(0.0f, 0.0f);
    } else {
        const Sphere *sp = &g->spheres[(int)e->prim - g->num_triangles];
        Vec3 d = warp_uniform_sphere(u);
        *p = v3_madd(sp->center, d, sp->radius);
        *n = d;
        *uv = e->texture ? sphere_uv(d) : v2(0.0f, 0.0f);
    }
}

/* The cone of directions a sphere subtends from an outside point x: half angle theta_max
 * with sin^2 theta_max = r^2 / |c - x|^2, returned as 1 - cos theta_max. Computed as
 * s / (1 + sqrt(1 - s)), which keeps its digits for distant spheres where 1 - sqrt(1 - s)
 * cancels to 0 in float (pbrt-v4 Sphere::Sample switches to the Taylor term s / 2 below
 * sin^2 = sin^2(1.5 deg) instead; this form needs no threshold). Returns false when x is
 * inside the sphere or on it: there is no cone and the point is sampled by area. "On it"
 * is a shell of 5e-5 r outside: a hit point on the sphere itself (inside a two-sided
 * emitting sphere, say) is off the surface by rounding, to either side, and a cone of
 * nearly 90 degrees from just outside would be the wrong density for it (pbrt-v4 makes
 * the same call from the point offset toward the centre). */
static bool sphere_cone(const Sphere *sp, Vec3 x, float *one_minus_cos_max, float *sin2_max)
{
    float d2 = v3_length2(v3_sub(sp->center, x));
    float r2 = sp->radius * sp->radius;
    if (!(d2 > 1.0001f * r2)) return false;
    float s2 = r2 / d2;
    *sin2_max = s2;
    *one_minus_cos_max = s2 / (1.0f + sqrtf(1.0f - s2));
    return *one_minus_cos_max > 0.0f;
}

/* A point on sphere sp seen from outside point x, by a direction uniform in the cone the
 * sphere subtends (pbrt-v4 Sphere::Sample(ctx, u); the geometry is pbrt-v3 book sec.
 * 14.2.2): 1 - cos theta uniform in [0, 1 - cos theta_max] by u.x, phi = 2 pi u.y, then the
 * nearer intersection of that direction with the sphere, found by the angle alpha at the
 * centre: cos alpha = sin^2 theta / sin theta_max + cos theta sqrt(1 - sin^2 theta /
 * sin^2 theta_max). The density is 1 / (2 pi (1 - cos theta_max)) per unit solid angle.
 * sin^2 theta comes from t = 1 - cos theta as t (2 - t), exact for small cones. */
static void sphere_sample_cone(const Sphere *sp, Vec3 x, Vec2 u, float omc_max, float sin2_max, Vec3 *n)
{
    float t = u.x * omc_max;
    float sin2 = t * (2.0f - t), cos_t = 1.0f - t;
    float ratio = fminf(sin2 / sin2_max, 1.0f);
    float cos_a = sin2 / sqrtf(sin2_max) + cos_t * sqrtf(1.0f - ratio);
    cos_a = clampf(cos_a, -1.0f, 1.0f);
    float sin_a = sqrtf(fmaxf(0.0f, 1.0f - cos_a * cos_a));
    float phi = 2.0f * CST_PI * u.y;
    Frame f = frame_from_normal(v3_normalize(v3_sub(sp->center, x)));
    /* The normal points back toward x's side: -z in the frame whose z runs from x to c. */
    *n = frame_to_world(&f, v3(-sin_a * cosf(phi), -sin_a * sinf(phi), -cos_a));
}

/* NEE by the solid angle a triangle subtends (s->solid_angle; pbrt-v4 Triangle::Sample(ctx,
 * u)): when triangle emitter em's solid angle from x lies in [SPH_MIN_SOLID_ANGLE,
 * SPH_MAX_SOLID_ANGLE], *tri is set up (its solid_angle omega, and the unit directions the
 * sample reuses) and the direction is drawn uniformly over it (density 1 / omega per unit
 * solid angle; the warp uses that same omega); outside that range, by area. Sampling and the MIS density
 * both decide here, from the same floats, so they always agree. pbrt-v4's extra bilinear
 * warp by |cos theta| at the vertices is not applied. */
static bool tri_solid_angle(const EmitterSampler *s, const EmitterGeometry *g, const Emitter *em, Vec3 x, SphTri *tri)
{
    if (!s->solid_angle || (int)em->prim >= g->num_triangles) return false;
    const int32_t *t = &g->tri_indices[3 * em->prim];
    (void)sph_tri_init(tri, x, g->positions[t[0]], g->positions[t[1]], g->positions[t[2]]);
    return tri->solid_angle >= SPH_MIN_SOLID_ANGLE && tri->solid_angle <= SPH_MAX_SOLID_ANGLE;
}

/* light_area_pdf_w for emitter e picked with probability pmf (pdf_a = pmf / area: with
 * the power's pmf the same float as s->pdf_a[e]). */
static float area_pdf_w(const EmitterSampler *s, const EmitterGeometry *g, int e, float pmf, Vec3 x, float dist,
                        float cos_l, bool nee)
{
    const Emitter *em = &s->light[e].u.area;
    float omc, sin2;
    SphTri tri;
    if (nee && tri_solid_angle(s, g, em, x, &tri)) return pmf / tri.solid_angle;
    const Sphere *sp = emitter_sphere(em, g);
    if (sp && sphere_cone(sp, x, &omc, &sin2)) return pmf / (2.0f * CST_PI * omc);
    /* triangles, analytic shapes, spheres from inside: by area, pdf_w = pdf_a dist^2 / |cos| */
    return cos_l > 0.0f ? pmf / em->area * dist * dist / cos_l : 0.0f;
}

float light_area_pdf_w(const EmitterSampler *s, const EmitterGeometry *g, int e, Vec3 x, float dist, float cos_l)
{
    return area_pdf_w(s, g, e, s->by_power.pmf[e], x, dist, cos_l, false);
}

/* The emission direction density at a delta light (per unit solid angle) of direction w. */
static float delta_emit_pdf_w(const Light *l, Vec3 w)
{
    float pdf = 0.0f;
    switch (l->type) {
    case LIGHT_PROJECTION: (void)proj_factor(&l->u.proj.image, w, &pdf); return pdf;
    case LIGHT_POINT:
    case LIGHT_GONIO: return CST_INV_4PI;
    case LIGHT_SPOT: return warp_uniform_cone_pdf(l->u.spot.cos_outer);
    case LIGHT_DIRECTIONAL: return 1.0f;
    default: return 0.0f;
    }
}

/* A point on triangle emitter e from a direction uniform in its solid angle from x
 * (tri_solid_angle): where the ray x + t w meets the triangle's plane, with its
 * texture coordinates. False when the direction misses the plane (rounding at an edge seen
 * edge-on). */
static bool tri_sample_solid_angle(const Emitter *e, const EmitterGeometry *g, const SphTri *tri, Vec3 x, Vec2 u,
                                   Vec3 *p, Vec2 *uv)
{
    const int32_t *t = &g->tri_indices[3 * e->prim];
    Vec3 a = g->positions[t[0]], b = g->positions[t[1]], c = g->positions[t[2]];
    Vec3 w;
    if (!sph_tri_sample(tri, u, &w)) return false;
    float wn = v3_dot(w, e->n);
    float tt = v3_dot(v3_sub(a, x), e->n) / wn;
    if (!(tt > 0.0f) || !isfinite(tt)) return false;
    *p = v3_madd(x, w, tt);
    *uv = v2(0.0f, 0.0f);
    if (e->texture) {
        /* barycentrics of p by the Gram system of the edges */
        Vec3 e1 = v3_sub(b, a), e2 = v3_sub(c, a), d = v3_sub(*p, a);
        float d11 = v3_dot(e1, e1), d12 = v3_dot(e1, e2), d22 = v3_dot(e2, e2);
        float r1 = v3_dot(d, e1), r2 = v3_dot(d, e2), det = d11 * d22 - d12 * d12;
        float b1 = det != 0.0f ? (d22 * r1 - d12 * r2) / det : 0.0f, b2 = det != 0.0f ? (d11 * r2 - d12 * r1) / det : 0.0f;
        *uv = triangle_uv(g->uvs, g->tri_has_uv, g->tri_indices, e->prim, b1, b2);
    }
    return true;
}

/* NEE toward triangle emitter e by its solid angle from x when tri_solid_angle says so: 1
 * with *p, *uv and *omega (sr); 0 when that sample failed; -1 when the triangle is to be
 * sampled by area. Apart from area_sample_li so that the SphTri (80 bytes, its address
 * passed on) is not in the frame of every area-sampled NEE call. */
static __attribute__((noinline)) int tri_solid_sample(const EmitterSampler *s, const EmitterGeometry *g,
                                                      const Emitter *e, Vec3 x, Vec2 u, Vec3 *p, Vec2 *uv, float *omega)
{
    SphTri tri;
    if (!tri_solid_angle(s, g, e, x, &tri)) return -1;
    *omega = tri.solid_angle;
    return tri_sample_solid_angle(e, g, &tri, x, u, p, uv) ? 1 : 0;
}

static bool area_sample_li(const EmitterSampler *s, int i, float pmf, const EmitterGeometry *g, Vec3 x, Vec2 u,
                           bool nee, LightLi *out)
{
    const float pdf_a = pmf / s->light[i].u.area.area; /* == s->pdf_a[i] for the power's pmf */
    const Emitter *e = &s->light[i].u.area;
    Vec2 uv;
    float omc = 0.0f, sin2 = 0.0f, omega = 0.0f;
    const Sphere *sp = emitter_sphere(e, g);
    const bool cone = sp && sphere_cone(sp, x, &omc, &sin2);
    int solid = nee && s->solid_angle ? tri_solid_sample(s, g, e, x, u, &out->p, &uv, &omega) : -1;
    if (solid == 0) return false;
    if (solid > 0) {
        out->n = e->n;
    } else if (cone) {
        sphere_sample_cone(sp, x, u, omc, sin2, &out->n);
        out->p = v3_madd(sp->center, out->n, sp->radius);
        uv = e->texture ? sphere_uv(out->n) : v2(0.0f, 0.0f);
    } else {
        emitter_sample_point(e, g, u, &out->p, &out->n, &uv);
    }
    Vec3 to = v3_sub(out->p, x);
    float dist2 = v3_length2(to);
    if (!(dist2 > 0.0f)) return false;
    out->dist = sqrtf(dist2);
    out->wi = v3_scale(to, 1.0f / out->dist);
    out->cos_light = fabsf(v3_dot(out->n, out->wi));
    out->li = emitter_radiance(e, g->textures, out->n, uv, v3_neg(out->wi));
    if (color_is_black(out->li) || !(out->cos_light > 0.0f)) return false;
    /* Area sampling: dA -> d omega, pdf_w = pdf_a dist^2 / |cos theta_light|. This is also
     * the density the bidirectional MIS weights use for NEE (direct_pdf) even when the
     * sphere's cone was sampled: subpath.c's weights of every strategy come from one set
     * of densities, so they still sum to 1 (pbrt-v4's BDPT does the same). */
    const float area_pdf_w = pdf_a * dist2 / out->cos_light;
    out->pdf_w = solid > 0 ? pmf / omega : cone ? pmf / (2.0f * CST_PI * omc) : area_pdf_w;
    out->finite = true;
    out->emit_pdf = pdf_a * emitter_emission_pdf_w(e, out->n, v3_neg(out->wi));
    out->direct_pdf = area_pdf_w;
    return true;
}

/* From beyond the bounding sphere like a directional light, but a direction from the
 * environment's distribution: not a delta, so MIS applies. */
static bool env_sample_li(const EmitterSampler *s, float pmf, Vec3 x, Vec2 u, bool nee, LightLi *out)
{
    float pdf_w;
    if (nee && s->env->portal) {
        /* through the portal only (envmap.h EnvPortal): from behind it, nothing */
        if (!envmap_portal_sample(s->env, x, u, &out->wi, &pdf_w)) return false;
    } else {
        out->wi = envmap_sample(s->env, u, &pdf_w);
    }
    if (!(pdf_w > 0.0f)) return false;
    out->pdf_w = pmf * pdf_w;
    out->dist = 2.0f * s->radius + v3_length(v3_sub(x, s->center));
    out->p = v3_madd(x, out->wi, out->dist);
    out->n = v3_neg(out->wi);
    out->li = envmap_eval(s->env, out->wi);
    out->finite = false;
    out->cos_light = 1.0f;
    out->emit_pdf = out->pdf_w / (CST_PI * s->radius * s->radius);
    out->direct_pdf = out->pdf_w;
    return !color_is_black(out->li);
}

static bool delta_sample_li(const EmitterSampler *s, const Light *l, float pmf, Vec3 x, LightLi *out)
{
    out->delta = true;
    out->pmf = pmf;
    out->cos_light = 1.0f;
    if (l->type == LIGHT_DIRECTIONAL) {
        /* From outside the scene's bounding sphere, so every occluder is on the segment;
         * the direct_pdf of an infinitely distant light has no distance factor, and a
         * light path starts from the disk of the bounding sphere (density 1 / (pi R^2)). */
        out->wi = v3_neg(l->u.directional.dir);
        out->dist = 2.0f * s->radius + v3_length(v3_sub(x, s->center));
        out->p = v3_madd(x, out->wi, out->dist);
        out->n = l->u.directional.dir;
        out->li = l->u.directional.irradiance;
        out->finite = false;
        out->emit_pdf = pmf / (CST_PI * s->radius * s->radius);
        out->direct_pdf = pmf;
        return true;
    }
    const Vec3 lp = l->type == LIGHT_SPOT         ? l->u.spot.p
                    : l->type == LIGHT_GONIO      ? l->u.gonio.p
                    : l->type == LIGHT_PROJECTION ? l->u.proj.p
                                                  : l->u.point.p;
    Vec3 to = v3_sub(lp, x);
    float dist2 = v3_length2(to);
    if (!(dist2 > 0.0f)) return false;
    out->p = lp;
    out->dist = sqrtf(dist2);
    out->wi = v3_scale(to, 1.0f / out->dist);
    out->n = v3_neg(out->wi);
    out->finite = true;
    out->emit_pdf = pmf * delta_emit_pdf_w(l, v3_neg(out->wi));
    if (l->type == LIGHT_PROJECTION) {
        Color f = proj_factor(&l->u.proj.image, v3_neg(out->wi), NULL);
        out->li = color_scale(color_mul(l->u.proj.intensity, f), 1.0f / dist2);
        out->direct_pdf = pmf * dist2;
        return !color_is_black(f);
    }
    float falloff = l->type == LIGHT_SPOT    ? spot_falloff(&l->u.spot, v3_dot(l->u.spot.dir, v3_neg(out->wi)))
                    : l->type == LIGHT_GONIO ? gonio_factor(&l->u.gonio.image, v3_neg(out->wi))
                                             : 1.0f;
    const Color intensity = l->type == LIGHT_SPOT    ? l->u.spot.intensity
                            : l->type == LIGHT_GONIO ? l->u.gonio.intensity
                                                     : l->u.point.intensity;
    out->li = color_scale(intensity, falloff / dist2);
    out->direct_pdf = pmf * dist2;
    return falloff > 0.0f;
}

/* The sample of light i, picked with probability pmf. */
static bool sample_light(const EmitterSampler *s, const EmitterGeometry *g, int i, float pmf, Vec3 x, Vec2 u,
                         bool nee, LightLi *out)
{
    out->light = i;
    const Light *l = &s->light[i];
    switch (l->type) {
    case LIGHT_AREA: return area_sample_li(s, i, pmf, g, x, u, nee, out);
    case LIGHT_ENVIRONMENT: return env_sample_li(s, pmf, x, u, nee, out);
    case LIGHT_POINT:
    case LIGHT_SPOT:
    case LIGHT_GONIO:
    case LIGHT_PROJECTION:
    case LIGHT_DIRECTIONAL: return delta_sample_li(s, l, pmf, x, out);
    }
    return false;
}

bool light_sample_li(const EmitterSampler *s, const EmitterGeometry *g, Vec3 x, float u_sel, Vec2 u,
                     LightLi *out)
{
    memset(out, 0, sizeof *out);
    if (s->lights == 0) return false;
    int i = distrib1d_sample(&s->by_power, u_sel);
    return sample_light(s, g, i, s->by_power.pmf[i], x, u, false, out);
}

bool light_sample_nee(const EmitterSampler *s, const EmitterGeometry *g, Vec3 x, Vec3 n, float u_sel, Vec2 u,
                      LightLi *out)
{
    memset(out, 0, sizeof *out);
    if (s->lights == 0) return false;
    int i;
    float pmf;
    if (s->nee == LIGHT_SELECT_POWER) {
        i = distrib1d_sample(&s->by_power, u_sel);
        pmf = s->by_power.pmf[i];
    } else if (s->nee == LIGHT_SELECT_BVH) {
        i = light_bvh_sample(s->bvh, x, n, u_sel, &pmf);
        if (i < 0) return false;
    } else {
        i = (int)(u_sel * (float)s->lights);
        i = i >= s->lights ? s->lights - 1 : i;
        pmf = 1.0f / (float)s->lights;
    }
    return sample_light(s, g, i, pmf, x, u, true, out);
}

float light_nee_pmf(const EmitterSampler *s, Vec3 x, Vec3 n, int i)
{
    switch (s->nee) {
    case LIGHT_SELECT_BVH: return light_bvh_pmf(s->bvh, x, n, i);
    case LIGHT_SELECT_UNIFORM: return 1.0f / (float)s->lights;
    case LIGHT_SELECT_POWER: break;
    }
    return s->by_power.pmf[i];
}

float light_area_nee_pdf_w(const EmitterSampler *s, const EmitterGeometry *g, int e, Vec3 x, Vec3 n, float dist,
                           float cos_l)
{
    if (s->nee == LIGHT_SELECT_POWER) return area_pdf_w(s, g, e, s->by_power.pmf[e], x, dist, cos_l, true);
    return area_pdf_w(s, g, e, light_nee_pmf(s, x, n, e), x, dist, cos_l, true);
}

float light_env_nee_pdf(const EmitterSampler *s, Vec3 x, Vec3 n, Vec3 w)
{
    if (!s->env) return 0.0f;
    if (s->env->portal) return light_nee_pmf(s, x, n, light_env_index(s)) * envmap_portal_pdf(s->env, x, w);
    if (s->nee == LIGHT_SELECT_POWER) return light_env_pdf(s, w);
    return light_nee_pmf(s, x, n, light_env_index(s)) * envmap_pdf(s->env, w);
}

LightSelect emitter_sampler_auto_nee(const EmitterSampler *s)
{
    int bounded = 0;
    for (int i = 0; i < s->count + s->num_delta; i++) bounded += s->light[i].type != LIGHT_DIRECTIONAL;
    return bounded > LIGHT_SELECT_BVH_ABOVE ? LIGHT_SELECT_BVH : LIGHT_SELECT_POWER;
}

CstStatus emitter_sampler_set_nee(EmitterSampler *s, const EmitterGeometry *g, LightSelect sel, CstError *err)
{
    if (sel == LIGHT_SELECT_BVH && !s->bvh && s->lights > 0) {
        LightBvh *bvh = malloc(sizeof *bvh);
        if (!bvh) return cst_fail(err, CST_ERR_OOM, "out of memory for the light BVH");
        CstStatus st = light_bvh_build(bvh, s, g, err);
        if (st != CST_OK) {
            free(bvh);
            return st;
        }
        s->bvh = bvh;
    }
    /* no lights: nothing to pick, and power selection's checks come first everywhere */
    s->nee = s->lights > 0 ? sel : LIGHT_SELECT_POWER;
    return CST_OK;
}

static void area_sample_emission(const EmitterSampler *s, int i, const EmitterGeometry *g, Vec2 u_pos,
                                 Vec2 u_dir, EmissionSample *out)
{
    const Emitter *e = &s->light[i].u.area;
    Vec3 p, n;
    emitter_sample_point(e, g, u_pos, &p, &n, &out->uv);
    float side = 1.0f;
    if (e->two_sided) {
        /* Reuse u_dir.x for the side: [0, 1/2) front, [1/2, 1) back, stretched back to [0, 1). */
        if (u_dir.x < 0.5f) u_dir.x *= 2.0f;
        else { u_dir.x = 2.0f * u_dir.x - 1.0f; side = -1.0f; }
    }
    Vec3 local = warp_cosine_hemisphere(u_dir);
    Frame f = frame_from_normal(v3_scale(n, side));
    out->p = p;
    out->n = n;
    out->w = frame_to_world(&f, local);
    out->pdf_a = s->pdf_a[i];
    out->nee_pdf = out->pdf_a;
    out->pdf_w = local.z > 0.0f ? emitter_emission_pdf_w(e, n, out->w) : 0.0f;
    out->cos_l = fabsf(v3_dot(n, out->w));
    out->finite = true;
    if (out->pdf_w > 0.0f)
        out->beta = color_scale(emitter_radiance(e, g->textures, n, out->uv, out->w),
                                out->cos_l / (out->pdf_a * out->pdf_w));
}

/* A direction w_in toward the environment from its distribution (u_dir), the light
 * travelling -w_in from a uniform point on the disk of the bounding sphere facing it, one
 * radius upstream (u_pos): pbrt-v4 ImageInfiniteLight::SampleLe. */
static void env_sample_emission(const EmitterSampler *s, float pmf, Vec2 u_pos, Vec2 u_dir,
                                EmissionSample *out)
{
    float pdf_dir;
    Vec3 w_in = envmap_sample(s->env, u_dir, &pdf_dir);
    Frame f = frame_from_normal(w_in);
    Vec2 d = warp_concentric_disk(u_pos);
    Vec3 off = frame_to_world(&f, v3(d.x * s->radius, d.y * s->radius, 0.0f));
    out->p = v3_add(v3_madd(s->center, w_in, s->radius), off);
    out->w = v3_neg(w_in);
    out->n = out->w;
    float area = CST_PI * s->radius * s->radius;
    out->pdf_a = pmf / area;
    out->pdf_w = pdf_dir;
    out->cos_l = 1.0f;
    out->nee_pdf = pmf * pdf_dir;
    out->finite = false;
    if (pdf_dir > 0.0f) out->beta = color_scale(envmap_eval(s->env, w_in), area / (pmf * pdf_dir));
}

static void delta_sample_emission(const EmitterSampler *s, const Light *l, float pmf, Vec2 u_pos,
                                  Vec2 u_dir, EmissionSample *out)
{
    out->delta = true;
    out->cos_l = 1.0f;
    out->nee_pdf = pmf;
    switch (l->type) {
    case LIGHT_POINT:
        out->p = l->u.point.p;
        out->w = warp_uniform_sphere(u_dir);
        out->pdf_a = pmf;
        out->pdf_w = CST_INV_4PI;
        out->beta = color_scale(l->u.point.intensity, 1.0f / (pmf * out->pdf_w));
        out->finite = true;
        break;
    case LIGHT_GONIO:
        /* A uniform direction weighted by the image (pbrt-v4 samples the image's own
         * distribution: same expectation, more noise where the image is uneven). */
        out->p = l->u.gonio.p;
        out->w = warp_uniform_sphere(u_dir);
        out->pdf_a = pmf;
        out->pdf_w = CST_INV_4PI;
        out->beta = color_scale(l->u.gonio.intensity, gonio_factor(&l->u.gonio.image, out->w) / (pmf * out->pdf_w));
        out->finite = true;
        break;
    case LIGHT_PROJECTION: {
        /* uniform over the window (pbrt-v4 samples the image's distribution: the same
         * expectation, more noise where the image is uneven) */
        const ProjectionLight *pl = &l->u.proj;
        out->p = pl->p;
        out->w = proj_sample_dir(&pl->image, u_dir);
        out->pdf_a = pmf;
        Color f = proj_factor(&pl->image, out->w, &out->pdf_w);
        if (out->pdf_w > 0.0f) out->beta = color_scale(color_mul(pl->intensity, f), 1.0f / (pmf * out->pdf_w));
        out->finite = true;
        break;
    }
    case LIGHT_SPOT: {
        const SpotLight *sp = &l->u.spot;
        Frame f = frame_from_normal(sp->dir);
        out->p = sp->p;
        out->w = frame_to_world(&f, warp_uniform_cone(u_dir, sp->cos_outer));
        out->pdf_a = pmf;
        out->pdf_w = warp_uniform_cone_pdf(sp->cos_outer);
        float falloff = spot_falloff(sp, v3_dot(sp->dir, out->w));
        out->beta = color_scale(sp->intensity, falloff / (pmf * out->pdf_w));
        out->finite = true;
        break;
    }
    case LIGHT_DIRECTIONAL: {
        /* A uniform point on the disk of the bounding sphere facing the light, one radius
         * upstream of the centre: every ray through the scene is covered. */
        const DirectionalLight *dl = &l->u.directional;
        Frame f = frame_from_normal(dl->dir);
        Vec2 d = warp_concentric_disk(u_pos);
        Vec3 off = frame_to_world(&f, v3(d.x * s->radius, d.y * s->radius, 0.0f));
        out->p = v3_add(v3_madd(s->center, dl->dir, -s->radius), off);
        out->w = dl->dir;
        float area = CST_PI * s->radius * s->radius;
        out->pdf_a = pmf / area;
        out->pdf_w = 1.0f;
        out->beta = color_scale(dl->irradiance, area / pmf);
        out->finite = false;
        break;
    }
    default: break;
    }
    out->n = out->w;
}

void emitter_sample_emission(const EmitterSampler *s, const EmitterGeometry *g, float u_sel, Vec2 u_pos,
                             Vec2 u_dir, EmissionSample *out)
{
    memset(out, 0, sizeof *out);
    if (s->lights == 0) return;
    int i = distrib1d_sample(&s->by_power, u_sel);
    float pmf = s->by_power.pmf[i];
    out->emitter = i;
    const Light *l = &s->light[i];
    switch (l->type) {
    case LIGHT_AREA: area_sample_emission(s, i, g, u_pos, u_dir, out); return;
    case LIGHT_ENVIRONMENT: env_sample_emission(s, pmf, u_pos, u_dir, out); return;
    case LIGHT_POINT:
    case LIGHT_SPOT:
    case LIGHT_GONIO:
    case LIGHT_PROJECTION:
    case LIGHT_DIRECTIONAL: delta_sample_emission(s, l, pmf, u_pos, u_dir, out); return;
    }
}

float emitter_emission_pdf_w(const Emitter *e, Vec3 n, Vec3 w)
{
    float c = v3_dot(n, w);
    if (e->two_sided) return 0.5f * fabsf(c) * CST_INV_PI;
    return c > 0.0f ? c * CST_INV_PI : 0.0f;
}
