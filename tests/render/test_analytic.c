/* Analytic test: radiance reflected by a diffuse plane under a rectangular emitter (and a
 * sphere light, a point or spot light, an environment), against the closed-form irradiance: at one point for the path tracers, over a whole
 * image for the light tracer. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "render/regions.h"
#include "render/render_util.h"
#include "scene/scene.h"

/* Form factor from a differential area to a parallel rectangle a x b at height h whose
 * corner lies straight above it (Howell's catalogue of configuration factors, B-3):
 * F = 1/(2 pi) [X/sqrt(1+X^2) atan(Y/sqrt(1+X^2)) + Y/sqrt(1+Y^2) atan(X/sqrt(1+Y^2))],
 * X = a/h, Y = b/h. Irradiance from a Lambertian emitter of radiance L is E = pi L F. */
static double corner_form_factor(double a, double b, double h)
{
    double X = a / h, Y = b / h;
    double sx = sqrt(1.0 + X * X), sy = sqrt(1.0 + Y * Y);
    return (X / sx * atan(Y / sx) + Y / sy * atan(X / sy)) / (2.0 * 3.14159265358979323846);
}

/* Form factor from the point (x, 0, z) of the plane to the emitter [-a/2, a/2] x
 * [-b/2, b/2] at height h, by superposition of the four rectangles that have a corner
 * above the point; a signed extent subtracts the part beyond the emitter's edge. */
static double signed_corner(double u, double v, double h)
{
    double s = (u < 0.0 ? -1.0 : 1.0) * (v < 0.0 ? -1.0 : 1.0);
    return s * corner_form_factor(fabs(u), fabs(v), h);
}

static double point_form_factor(double a, double b, double h, double x, double z)
{
    return signed_corner(a / 2 - x, b / 2 - z, h) + signed_corner(a / 2 + x, b / 2 - z, h) +
           signed_corner(a / 2 - x, b / 2 + z, h) + signed_corner(a / 2 + x, b / 2 + z, h);
}

static const float RHO = 0.8f, LE = 3.0f;

/* A scene holding the plane y = 0 (albedo RHO, normal +y) of half side `half`, centred on
 * the origin; with light_mat, also a black material for an emitter (*light_mat). */
static Scene *plane_scene(float half, int *light_mat)
{
    CstError err;
    Scene *s = scene_create();
    int plane_mat;
    Material m = {.type = MATERIAL_DIFFUSE, .albedo = {{RHO, RHO, RHO}}, .ior = 1.0f};
    assert_int_equal(scene_add_material(s, &m, &plane_mat, &err), CST_OK);
    if (light_mat) {
        m.albedo = color_s(0.0f);
        assert_int_equal(scene_add_material(s, &m, light_mat, &err), CST_OK);
    }
    Vec3 plane[4] = {{-half, 0, -half}, {-half, 0, half}, {half, 0, half}, {half, 0, -half}};
    assert_int_equal(scene_add_quad(s, plane, plane_mat, NULL, &err), CST_OK);
    return s;
}

/* The plane y = 0 (albedo RHO, normal +y) and an a x b emitter (LE, facing down) at
 * height h, centred above the origin. */
static Scene *plane_under_light(double a, double b, double h)
{
    CstError err;
    int light_mat;
    Scene *s = plane_scene(50.0f, &light_mat); /* the emitter at y = h faces -y (its winding) */
    float ha = (float)(a / 2), hb = (float)(b / 2), fh = (float)h;
    Vec3 light[4] = {{-ha, fh, -hb}, {ha, fh, -hb}, {ha, fh, hb}, {-ha, fh, hb}};
    Emission em = {{{LE, LE, LE}}, 0, 0};
    assert_int_equal(scene_add_quad(s, light, light_mat, &em, &err), CST_OK);
    return s;
}

/* The one-pixel render every closed form here is checked against: spp samples of the
 * pixel with `integ`, 2 threads, no NaN/Inf; the pixel's mean and standard error. */
static RegionStat render_pixel(const Scene *s, CstIntegrator integ, int spp, uint64_t seed)
{
    CstRenderSettings st = {.width = 1, .height = 1, .threads = 2};
    CstFilm *f = render_film(s, &st, integ, spp, seed);
    RegionStat r = region_stat(f, 0, 0, 1, 1);
    cst_film_destroy(f);
    return r;
}

/* Radiance leaving a diffuse plane of albedo rho at the point below an a x b emitter's
 * centre: L_o = rho E / pi = rho L * 4 F(a/2, b/2, h). */
static void run_case_spp(CstIntegrator integ, double a, double b, double h, uint64_t seed, int spp)
{
    CstError err;
    Scene *s = plane_under_light(a, b, h);
    float fh = (float)h;
    /* A pinhole (which blocks nothing) between the two, looking straight down with a
     * field of view so narrow that the pixel sees a single point of the plane. */
    CameraDesc cam = {{0, fh * 0.5f, 0}, {0, 0, 0}, {0, 0, 1}, 1e-3f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);

    double expected = (double)RHO * (double)LE * 4.0 * corner_form_factor(a / 2, b / 2, h);
    RegionStat r = render_pixel(s, integ, spp, seed);
    for (int c = 0; c < 3; c++) {
        double z = (r.mean[c] - expected) / r.se[c];
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("%s a=%g b=%g h=%g: L = %.6f, closed form %.6f (z = %.2f)",
                     cst_integrator_name(integ), a, b, h, r.mean[c], expected, z);
    }
    scene_destroy(s);
}

static void run_case(CstIntegrator integ, double a, double b, double h, uint64_t seed)
{
    run_case_spp(integ, a, b, h, seed, 1 << 20);
}

/* The light tracer cannot render the single-point view above (a vertex would have to land
 * on that point), so it gets a 90-degree view of the plane from height h/2 and every
 * pixel a closed form. The camera looks straight down, so film and plane are parallel and
 * raster (x, y) maps linearly to the plane point (-(2x/W - 1) h/2, (1 - 2y/H) h/2) (right =
 * -x, up = +z), also past the film's edge. */
enum { LT_SIZE = 32, LT_BLOCK = 8, LT_SUB = 8, LT_REGIONS = 1 + 16 + 4 };

static double radiance_at_raster(double a, double b, double h, double fx, double fy)
{
    const double c = h / 2, n = LT_SIZE;
    double x = -(2.0 * fx / n - 1.0) * c, z = (1.0 - 2.0 * fy / n) * c;
    return (double)RHO * (double)LE * point_form_factor(a, b, h, x, z);
}

/* Pixel (px, py) under the filter: box, the mean of L over the pixel; tent, L weighted by
 * (1 - |dx|)(1 - |dy|) around the pixel centre. Midpoint rule on cells of 1/LT_SUB pixel,
 * whose edges include the tent's kinks, so the weights are integrated exactly. */
static double expected_pixel(double a, double b, double h, CstFilter filter, int px, int py)
{
    double sum = 0.0;
    if (filter != CST_FILTER_TENT) {
        for (int j = 0; j < LT_SUB; j++)
            for (int i = 0; i < LT_SUB; i++)
                sum += radiance_at_raster(a, b, h, px + (i + 0.5) / LT_SUB, py + (j + 0.5) / LT_SUB);
        return sum / (LT_SUB * LT_SUB);
    }
    for (int j = 0; j < 2 * LT_SUB; j++)
        for (int i = 0; i < 2 * LT_SUB; i++) {
            double dx = (i + 0.5) / LT_SUB - 1.0, dy = (j + 0.5) / LT_SUB - 1.0;
            double w = (1.0 - fabs(dx)) * (1.0 - fabs(dy));
            sum += w * radiance_at_raster(a, b, h, px + 0.5 + dx, py + 0.5 + dy);
        }
    return sum / (LT_SUB * LT_SUB);
}

/* The whole image, its 4 x 4 blocks and its four one-pixel edges (top, bottom, left,
 * right): past the edge of the film lies half a pixel of the border pixels' tents, which
 * a light tracer that drops connections landing there would miss (1/8 of their weight). */
static void light_regions(int rect[LT_REGIONS][4])
{
    const int nb = LT_SIZE / LT_BLOCK, s = LT_SIZE;
    const int edges[4][4] = {{0, 0, s, 1}, {0, s - 1, s, s}, {0, 0, 1, s}, {s - 1, 0, s, s}};
    rect[0][0] = 0; rect[0][1] = 0; rect[0][2] = s; rect[0][3] = s;
    for (int k = 0; k < nb * nb; k++) {
        rect[1 + k][0] = (k % nb) * LT_BLOCK; rect[1 + k][1] = (k / nb) * LT_BLOCK;
        rect[1 + k][2] = rect[1 + k][0] + LT_BLOCK; rect[1 + k][3] = rect[1 + k][1] + LT_BLOCK;
    }
    for (int e = 0; e < 4; e++)
        for (int i = 0; i < 4; i++) rect[1 + nb * nb + e][i] = edges[e][i];
}

/* Box filter: one render of `iterations`, standard errors from region_stat. Each light
 * path reaches the plane at most once (the emitter is black, the plane flat), so its
 * splats in an iteration fall into different pixels, which only makes pixel estimates
 * negatively correlated: region_stat's standard errors are conservative, by 1 / sqrt(1 - P)
 * for a region a path lands in with probability P (about 1.2 for the whole image, 1.01 for
 * a block). Tent filter: a splat is shared by neighbouring pixels, so the standard errors
 * come from independent one-iteration renders (region_stats_by_render). */
static void run_light_case(double a, double b, double h, CstFilter filter, int iterations,
                           uint64_t seed)
{
    CstError err;
    Scene *s = plane_under_light(a, b, h);
    CameraDesc cam = {{0, (float)(h * 0.5), 0}, {0, 0, 0}, {0, 0, 1}, 90.0f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st = {0};
    st.width = st.height = LT_SIZE;
    st.spp = iterations;
    st.integrator = CST_INTEGRATOR_LIGHT;
    st.filter = filter;
    st.seed = seed;
    st.seed_set = 1;
    st.threads = 2;

    int rect[LT_REGIONS][4];
    light_regions(rect);
    const int count = filter == CST_FILTER_TENT ? LT_REGIONS : LT_REGIONS - 4;
    RegionStat r[LT_REGIONS];
    if (filter == CST_FILTER_TENT) {
        CstRenderSettings one = st; /* `iterations` renders of one iteration each */
        one.spp = 1;
        if (region_stats_by_render(s, &one, iterations, seed, count, (const int (*)[4])rect, r,
                                   NULL, &err) != CST_OK)
            fail_msg("%s", err.msg);
    } else {
        CstFilm *f = NULL;
        CstRenderStats stats;
        st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
        assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
        assert_int_equal(stats.nonfinite, 0);
        for (int i = 0; i < count; i++) r[i] = region_stat(f, rect[i][0], rect[i][1], rect[i][2], rect[i][3]);
        cst_film_destroy(f);
    }

    double pixel[LT_SIZE][LT_SIZE];
    for (int y = 0; y < LT_SIZE; y++)
        for (int x = 0; x < LT_SIZE; x++) pixel[y][x] = expected_pixel(a, b, h, filter, x, y);
    double worst = 0.0;
    for (int i = 0; i < count; i++) {
        double expected = 0.0;
        for (int y = rect[i][1]; y < rect[i][3]; y++)
            for (int x = rect[i][0]; x < rect[i][2]; x++) expected += pixel[y][x];
        expected /= (double)(rect[i][2] - rect[i][0]) * (double)(rect[i][3] - rect[i][1]);
        for (int c = 0; c < 3; c++) {
            double z = (r[i].mean[c] - expected) / r[i].se[c];
            if (fabs(z) > fabs(worst)) worst = z;
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("light (%s) a=%g b=%g h=%g region %d (0 = whole image, then blocks, "
                         "then edges): L = %.6f, closed form %.6f (z = %.2f)", cst_filter_name(filter),
                         a, b, h, i, r[i].mean[c], expected, z);
        }
        if (i == 0)
            print_message("light (%s) a=%g b=%g h=%g: whole image %.5f, closed form %.5f, "
                          "relative standard error %.1e\n", cst_filter_name(filter), a, b, h,
                          r[i].mean[0], expected, r[i].se[0] / expected);
    }
    print_message("light (%s) a=%g b=%g h=%g: largest |z| = %.2f\n", cst_filter_name(filter), a,
                  b, h, fabs(worst));
    scene_destroy(s);
}

static void test_light_tracer_irradiance(void **state)
{
    (void)state;
    run_light_case(1.0, 1.0, 1.0, CST_FILTER_BOX, 8192, 41);
    run_light_case(4.0, 0.5, 0.7, CST_FILTER_BOX, 8192, 42);
    run_light_case(0.2, 0.3, 2.0, CST_FILTER_BOX, 8192, 43);
    run_light_case(1.0, 1.0, 1.0, CST_FILTER_TENT, 2048, 44000);
}

static void test_rectangle_irradiance(void **state)
{
    (void)state;
    const CstIntegrator v[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_PATH_BSDF};
    for (int i = 0; i < 3; i++) {
        run_case(v[i], 1.0, 1.0, 1.0, 11 + i);  /* square, moderate solid angle */
        run_case(v[i], 4.0, 0.5, 0.7, 21 + i);  /* elongated, large solid angle */
        run_case(v[i], 0.2, 0.3, 2.0, 31 + i);  /* small and far: NEE's favourable case */
    }
}

/* An orthographic camera of view height h at height h/2 looking straight down sees the
 * plane point (-(2x/W - 1) h/2, (1 - 2y/H) h/2) at raster (x, y): the mapping of
 * run_light_case's 90-degree perspective view, so the same closed form holds per pixel.
 * Its rays are parallel, so no light path can connect to it; BDPT and VCM must drop that
 * strategy from their weights and still converge. */
static void run_ortho_case(CstIntegrator integ, double a, double b, double h, int spp, uint64_t seed)
{
    CstError err;
    Scene *s = plane_under_light(a, b, h);
    CameraDesc cam = {{0, (float)(h * 0.5), 0}, {0, 0, 0}, {0, 0, 1}, 0.0f, 0.0f, 1.0f, (float)h};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    CstRenderSettings st = {0};
    st.width = st.height = LT_SIZE;
    st.spp = spp;
    st.integrator = integ;
    st.seed = seed;
    st.seed_set = 1;
    st.threads = 2;
    /* VCM's default radius is 0.003 of the scene's bounding sphere, here the 100 x 100
     * plane's: 0.21, a fifth of the view, whose blur of the falloff under the light would
     * be a bias of 2% (measured) where merging takes the weight that light tracing has
     * with a perspective camera. A radius at the scale of the view keeps it negligible. */
    st.photon_radius = 0.005;
    int rect[LT_REGIONS][4];
    light_regions(rect);
    const int count = LT_REGIONS - 4;
    RegionStat r[LT_REGIONS];
    if (integ == CST_INTEGRATOR_PATH) {
        CstFilm *f = NULL;
        CstRenderStats stats;
        st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
        assert_int_equal(cst_render(s, &st, &f, &stats, &err), CST_OK);
        for (int i = 0; i < count; i++) r[i] = region_stat(f, rect[i][0], rect[i][1], rect[i][2], rect[i][3]);
        cst_film_destroy(f);
    } else {
        CstRenderSettings one = st;
        one.spp = 1;
        if (region_stats_by_render(s, &one, spp, seed, count, (const int (*)[4])rect, r, NULL, &err) != CST_OK)
            fail_msg("%s", err.msg);
    }
    double worst = 0.0;
    for (int i = 0; i < count; i++) {
        double expected = 0.0;
        for (int y = rect[i][1]; y < rect[i][3]; y++)
            for (int x = rect[i][0]; x < rect[i][2]; x++) expected += expected_pixel(a, b, h, CST_FILTER_BOX, x, y);
        expected /= (double)(rect[i][2] - rect[i][0]) * (double)(rect[i][3] - rect[i][1]);
        for (int c = 0; c < 3; c++) {
            double z = (r[i].mean[c] - expected) / r[i].se[c];
            if (fabs(z) > fabs(worst)) worst = z;
            if (!(fabs(z) <= Z_LIMIT))
                fail_msg("%s (orthographic) region %d: L = %.6f, closed form %.6f (z = %.2f)",
                         cst_integrator_name(integ), i, r[i].mean[c], expected, z);
        }
    }
    print_message("%s (orthographic): whole image %.5f, largest |z| = %.2f\n", cst_integrator_name(integ),
                  r[0].mean[0], fabs(worst));
    /* The light tracer has no way to the camera: a clear error, not a black image. */
    st.integrator = CST_INTEGRATOR_LIGHT;
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_ERR_INVALID_ARG);
    scene_destroy(s);
}

static void test_orthographic(void **state)
{
    (void)state;
    run_ortho_case(CST_INTEGRATOR_PATH, 1.0, 1.0, 1.0, 1024, 81);
    run_ortho_case(CST_INTEGRATOR_BDPT, 1.0, 1.0, 1.0, 256, 82000);
    run_ortho_case(CST_INTEGRATOR_VCM, 1.0, 1.0, 1.0, 256, 83000);
}

/* BDPT and VCM run one light and one camera path per iteration on this 1-pixel film, and
 * an iteration has a fixed cost, so they get fewer samples (their error bars say so). */
static void test_rectangle_irradiance_bidir(void **state)
{
    (void)state;
    const CstIntegrator v[] = {CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (int i = 0; i < 2; i++) {
        run_case_spp(v[i], 1.0, 1.0, 1.0, 51 + i, 4096);
        run_case_spp(v[i], 4.0, 0.5, 0.7, 61 + i, 4096);
        run_case_spp(v[i], 0.2, 0.3, 2.0, 71 + i, 4096);
    }
}

/* Delta lights over the plane y = 0 (albedo RHO) seen at its origin by the 1-pixel camera:
 * a point light of intensity I at height h gives L = RHO/pi I / h^2; a spot there whose
 * axis is tilted by 25 degrees, with a 30-degree cone and a 10-degree falloff, gives that
 * times pbrt-v4's smoothstep falloff at 25 degrees; a directional light of irradiance E
 * at 30 degrees from the normal gives RHO/pi E cos 30. No other geometry: direct light is
 * all there is. NEE of a delta light has no variance, so the check allows float rounding
 * (1e-5 relative) besides 4 standard errors. */
static void run_delta_case(CstIntegrator integ, int kind, int spp, uint64_t seed)
{
    CstError err;
    Scene *s = plane_scene(50.0f, NULL);
    const double h = 2.0, I = 5.0, E = 1.5, pi = 3.14159265358979323846;
    DeltaLight l;
    memset(&l, 0, sizeof l);
    double expected = 0.0;
    if (kind == 0) {
        l.type = DELTA_POINT;
        l.p = v3(0, (float)h, 0);
        l.intensity = color_s((float)I);
        expected = (double)RHO / pi * I / (h * h);
    } else if (kind == 1) {
        const double tilt = 25.0 * pi / 180.0, cone = 30.0 * pi / 180.0, inner = 20.0 * pi / 180.0;
        l.type = DELTA_SPOT;
        l.p = v3(0, (float)h, 0);
        l.dir = v3((float)sin(tilt), (float)-cos(tilt), 0);
        l.intensity = color_s((float)I);
        l.cos_outer = (float)cos(cone);
        l.cos_inner = (float)cos(inner);
        double t = (cos(tilt) - cos(cone)) / (cos(inner) - cos(cone));
        expected = (double)RHO / pi * I * t * t * (3.0 - 2.0 * t) / (h * h);
    } else if (kind == 3) {
        /* A goniometric light straight above: an 8 x 8 equal-area image with factor 2 on its
         * top half (where light-space -y, straight down, falls: row 0) and 0.5 elsewhere, so
         * light paths leave with the image's weights and NEE sees factor 2. */
        enum { N = 8 };
        float *img = malloc(N * N * sizeof *img);
        assert_non_null(img);
        for (int i = 0; i < N * N; i++) img[i] = i < N * N / 2 ? 2.0f : 0.5f;
        l.type = DELTA_GONIO;
        l.p = v3(0, (float)h, 0);
        l.intensity = color_s((float)I);
        l.gonio.factor = img;
        l.gonio.n = N;
        l.gonio.mean = 1.25f;
        for (int k = 0; k < 9; k++) l.gonio.light_from_world[k] = k % 4 == 0 ? 1.0f : 0.0f;
        expected = (double)RHO / pi * I * 2.0 / (h * h);
    } else {
        const double beta = 30.0 * pi / 180.0;
        l.type = DELTA_DIRECTIONAL;
        l.dir = v3((float)sin(beta), (float)-cos(beta), 0);
        l.intensity = color_s((float)E);
        expected = (double)RHO / pi * E * cos(beta);
    }
    assert_int_equal(scene_add_delta_light(s, &l, &err), CST_OK);
    CameraDesc cam = {{0, 1.0f, 0}, {0, 0, 0}, {0, 0, 1}, 1e-3f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    RegionStat r = render_pixel(s, integ, spp, seed);
    for (int c = 0; c < 3; c++)
        if (!(fabs(r.mean[c] - expected) <= Z_LIMIT * r.se[c] + 1e-5 * expected))
            fail_msg("%s, light kind %d: L = %.7f, closed form %.7f (se %.2g)", cst_integrator_name(integ), kind,
                     r.mean[c], expected, r.se[c]);
    print_message("%s, light kind %d: L = %.6f (se %.1e), closed form %.6f\n", cst_integrator_name(integ), kind,
                  r.mean[0], r.se[0], expected);
    scene_destroy(s);
}

/* A diffuse plane (albedo RHO, normal +y) under an equirectangular environment, seen at
 * its origin by the 1-pixel camera: L = RHO/pi times the cosine-weighted integral of the
 * map over the upper hemisphere, by exact quadrature per pixel (the map is piecewise
 * constant; a pixel row from theta0 to theta1 contributes (2 pi / W) (sin^2 theta1 -
 * sin^2 theta0) / 2 per unit radiance; the horizon is a row edge). The map has a small
 * bright sun, so NEE, BSDF sampling and their MIS all matter. */
static void run_env_case(CstIntegrator integ, int spp, uint64_t seed)
{
    enum { W = 64, H = 32 };
    CstError err;
    Scene *s = plane_scene(500.0f, NULL);
    float *rgb = malloc(W * H * 3 * sizeof *rgb);
    assert_non_null(rgb);
    double expected[3] = {0, 0, 0};
    const double pi = 3.14159265358979323846;
    for (int r = 0; r < H; r++)
        for (int c = 0; c < W; c++) {
            float *p = &rgb[3 * (r * W + c)];
            float sky = 0.3f + 0.7f * (float)(H - r) / H;
            p[0] = 0.4f * sky; p[1] = 0.6f * sky; p[2] = sky;
            if (r == 5 && (c == 12 || c == 13)) { p[0] = 300.0f; p[1] = 250.0f; p[2] = 200.0f; }
            if (r < H / 2) {
                double t0 = pi * r / H, t1 = pi * (r + 1) / H;
                double w = (2.0 * pi / W) * 0.5 * (sin(t1) * sin(t1) - sin(t0) * sin(t0));
                for (int k = 0; k < 3; k++) expected[k] += (double)p[k] * w;
            }
        }
    for (int k = 0; k < 3; k++) expected[k] *= (double)RHO / pi;
    EnvMap env;
    assert_int_equal(envmap_init_image(&env, rgb, W, H, color_s(1.0f), &err), CST_OK);
    assert_int_equal(scene_set_environment(s, &env, &err), CST_OK);
    CameraDesc cam = {{0, 1.0f, 0}, {0, 0, 0}, {0, 0, 1}, 1e-3f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    RegionStat r = render_pixel(s, integ, spp, seed);
    for (int c = 0; c < 3; c++) {
        double z = (r.mean[c] - expected[c]) / r.se[c];
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("%s under the environment: L = %.6f, quadrature %.6f (z = %.2f)", cst_integrator_name(integ),
                     r.mean[c], expected[c], z);
    }
    print_message("%s under the environment: L = %.5f (se %.1e), quadrature %.5f\n", cst_integrator_name(integ),
                  r.mean[0], r.se[0], expected[0]);
    scene_destroy(s);
}

/* A diffuse plane (albedo RHO, normal +y) lit by a sphere light of radius r and radiance
 * LE centred at (dx, h, 0), wholly above the horizon of the point at the origin: the
 * irradiance there is pi LE sin^2 theta_max cos beta (a uniformly bright sphere's projected
 * solid angle; sin theta_max = r / d, cos beta = h / d), so L_o = RHO LE (r / d)^2 h / d.
 * NEE samples the sphere by its cone (light.c); the MIS weights of BSDF-sampled hits use
 * light_area_pdf_w, so a wrong density in either biases path and whitted here. */
static void run_sphere_case(CstIntegrator integ, double dx, double h, double r, int spp, uint64_t seed)
{
    CstError err;
    int light_mat;
    Scene *s = plane_scene(500.0f, &light_mat);
    Emission em = {{{LE, LE, LE}}, 0, 0};
    assert_int_equal(scene_add_sphere(s, v3((float)dx, (float)h, 0), (float)r, light_mat, &em, &err), CST_OK);
    CameraDesc cam = {{0, 0.05f, 0}, {0, 0, 0}, {0, 0, 1}, 1e-3f, 0.0f, 1.0f, 0.0f};
    scene_set_camera(s, &cam);
    assert_int_equal(scene_commit(s, &err), CST_OK);
    /* From the float centre and radius the scene holds. */
    double fx = (double)(float)dx, fh = (double)(float)h, fr = (double)(float)r;
    double d2 = fx * fx + fh * fh;
    double expected = (double)RHO * (double)LE * fr * fr / d2 * fh / sqrt(d2);
    RegionStat st = render_pixel(s, integ, spp, seed);
    for (int c = 0; c < 3; c++) {
        double z = (st.mean[c] - expected) / st.se[c];
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("%s, sphere light r=%g at (%g, %g): L = %.7f, closed form %.7f (z = %.2f)",
                     cst_integrator_name(integ), r, dx, h, st.mean[c], expected, z);
    }
    print_message("%s, sphere r=%g at (%g, %g): L = %.6g (se %.1e), closed form %.6g\n", cst_integrator_name(integ),
                  r, dx, h, st.mean[0], st.se[0], expected);
    scene_destroy(s);
}

static void test_sphere_irradiance(void **state)
{
    (void)state;
    const CstIntegrator v[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_WHITTED,
                               CST_INTEGRATOR_BDPT, CST_INTEGRATOR_VCM};
    for (int i = 0; i < 5; i++) {
        int spp = v[i] >= CST_INTEGRATOR_SPPM ? 4096 : 1 << 16;
        run_sphere_case(v[i], 0.5, 2.0, 1.0, spp, 300 + 10 * (uint64_t)i);   /* large, theta_max 29 deg */
        run_sphere_case(v[i], 3.0, 4.0, 0.05, spp, 301 + 10 * (uint64_t)i);  /* small and oblique */
    }
    run_sphere_case(CST_INTEGRATOR_PATH_BSDF, 0.5, 2.0, 1.0, 1 << 20, 399);
}

static void test_environment_irradiance(void **state)
{
    (void)state;
    run_env_case(CST_INTEGRATOR_PATH, 1 << 18, 201);
    run_env_case(CST_INTEGRATOR_PATH_NEE, 1 << 18, 202);
    run_env_case(CST_INTEGRATOR_PATH_BSDF, 1 << 20, 203);
    run_env_case(CST_INTEGRATOR_WHITTED, 1 << 18, 204);
    run_env_case(CST_INTEGRATOR_PHOTON, 1 << 16, 205);
    run_env_case(CST_INTEGRATOR_BDPT, 4096, 206);
    run_env_case(CST_INTEGRATOR_VCM, 4096, 207);
}

static void test_delta_lights(void **state)
{
    (void)state;
    const CstIntegrator v[] = {CST_INTEGRATOR_PATH, CST_INTEGRATOR_PATH_NEE, CST_INTEGRATOR_WHITTED,
                               CST_INTEGRATOR_PHOTON, CST_INTEGRATOR_SPPM, CST_INTEGRATOR_BDPT,
                               CST_INTEGRATOR_VCM};
    for (int i = 0; i < 7; i++)
        for (int kind = 0; kind < 4; kind++)
            run_delta_case(v[i], kind, v[i] >= CST_INTEGRATOR_SPPM ? 1024 : 65536, 100 + 10 * (uint64_t)i + (uint64_t)kind);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_rectangle_irradiance),
        cmocka_unit_test(test_rectangle_irradiance_bidir),
        cmocka_unit_test(test_delta_lights),
        cmocka_unit_test(test_sphere_irradiance),
        cmocka_unit_test(test_environment_irradiance),
        cmocka_unit_test(test_orthographic),
        cmocka_unit_test(test_light_tracer_irradiance),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
