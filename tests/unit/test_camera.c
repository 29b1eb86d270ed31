/* Camera: camera_sample_wi inverts camera_generate_ray (film position, lens point,
 * direction) and its importance is normalised, the integral of W_e cos theta over lens
 * and directions being 1, for pinhole and thin-lens cameras. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "camera/camera.h"
#include "core/rng.h"
#include "render/render_util.h"

/* A non-square film so that the aspect ratio is exercised. */
static Camera make_camera(float aperture)
{
    CameraDesc d = {{1.0f, 2.0f, -3.0f}, {0.5f, 1.5f, 4.0f}, {0.0f, 1.0f, 0.0f}, 40.0f, aperture, 5.0f, 0.0f};
    Camera cam;
    camera_init(&cam, &d, 64, 48);
    return cam;
}

static void check_round_trip(float aperture)
{
    Camera cam = make_camera(aperture);
    Pcg32 rng;
    pcg32_seed(&rng, 7, 1);
    for (int i = 0; i < 10000; i++) {
        float fx = 64.0f * pcg32_float(&rng), fy = 48.0f * pcg32_float(&rng);
        Vec2 u = pcg32_v2(&rng);
        Ray r = camera_generate_ray(&cam, fx, fy, u);
        float t = 1.0f + 9.0f * pcg32_float(&rng);
        Vec3 p = ray_at(&r, t);
        CameraWiSample cs;
        if (!camera_sample_wi(&cam, p, u, 0.0f, &cs))
            fail_msg("aperture %g: (%g, %g) not projected back onto the film", (double)aperture,
                     (double)fx, (double)fy);
        if (fabsf(cs.raster.x - fx) > 1e-3f || fabsf(cs.raster.y - fy) > 1e-3f)
            fail_msg("aperture %g: film (%g, %g) came back as (%g, %g)", (double)aperture, (double)fx,
                     (double)fy, (double)cs.raster.x, (double)cs.raster.y);
        assert_true(v3_length(v3_sub(cs.p_lens, r.o)) < 1e-5f);
        assert_true(v3_dot(cs.wi, r.d) < -0.99999f);
        assert_true(fabsf(cs.dist - t) < 1e-4f * t);
    }
}

static void test_round_trip_pinhole(void **state)
{
    (void)state;
    check_round_trip(0.0f);
}

static void test_round_trip_thin_lens(void **state)
{
    (void)state;
    check_round_trip(0.3f);
}

/* Monte Carlo over a cone of directions around the view axis that contains the film
 * (uniform, pdf 1 / (2 pi (1 - cos theta_max))) and, for the thin lens, the lens point
 * camera_sample_wi draws itself (area density 1 / A_lens): the estimate of
 * integral W_e cos theta d omega dA_lens must be 1 within 4 standard errors. */
static void check_normalisation(float aperture)
{
    Camera cam = make_camera(aperture);
    const float cos_max = cosf(45.0f * (CST_PI / 180.0f));
    const double pdf_dir = 1.0 / (2.0 * 3.14159265358979323846 * (1.0 - (double)cos_max));
    const double lens_area = aperture > 0.0f ? 3.14159265358979323846 * (double)aperture * (double)aperture : 1.0;
    Pcg32 rng;
    pcg32_seed(&rng, 11, 3);
    const int n = 1 << 22;
    double sum = 0.0, sum_sq = 0.0;
    for (int i = 0; i < n; i++) {
        float ct = 1.0f - pcg32_float(&rng) * (1.0f - cos_max);
        float st = sqrtf(fmaxf(0.0f, 1.0f - ct * ct)), phi = 2.0f * CST_PI * pcg32_float(&rng);
        Vec3 w = v3_add(v3_scale(cam.forward, ct),
                        v3_add(v3_scale(cam.right, st * cosf(phi)), v3_scale(cam.up, st * sinf(phi))));
        Vec2 u = pcg32_v2(&rng);
        /* The lens point of u, from camera_generate_ray (any film position). */
        Vec3 o = camera_generate_ray(&cam, 0.0f, 0.0f, u).o;
        CameraWiSample cs;
        double x = 0.0;
        if (camera_sample_wi(&cam, v3_madd(o, w, 2.0f), u, 0.0f, &cs))
            x = (double)cs.we * (double)ct / pdf_dir * lens_area;
        sum += x;
        sum_sq += x * x;
    }
    double mean = sum / n, se = sqrt((sum_sq / n - mean * mean) / (n - 1));
    print_message("aperture %g: integral of W_e cos = %.5f (se %.1e)\n", (double)aperture, mean, se);
    if (!(fabs(mean - 1.0) <= Z_LIMIT * se))
        fail_msg("aperture %g: importance integrates to %.5f, not 1 (z = %.2f)", (double)aperture,
                 mean, (mean - 1.0) / se);
}

static void test_importance_normalised(void **state)
{
    (void)state;
    check_normalisation(0.0f);
    check_normalisation(0.3f);
}

/* Points just past the film's edge are rejected, unless a filter's margin covers them. */
static void test_margin(void **state)
{
    (void)state;
    Camera cam = make_camera(0.0f);
    Ray r = camera_generate_ray(&cam, -0.25f, 10.0f, v2(0.5f, 0.5f));
    CameraWiSample cs;
    assert_false(camera_sample_wi(&cam, ray_at(&r, 3.0f), v2(0.5f, 0.5f), 0.0f, &cs));
    assert_true(camera_sample_wi(&cam, ray_at(&r, 3.0f), v2(0.5f, 0.5f), 0.5f, &cs));
    assert_true(fabsf(cs.raster.x + 0.25f) < 1e-3f);
    /* Behind the camera: never. */
    assert_false(camera_sample_wi(&cam, v3_madd(cam.origin, cam.forward, -1.0f), v2(0.5f, 0.5f), 0.5f, &cs));
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_round_trip_pinhole),
        cmocka_unit_test(test_round_trip_thin_lens),
        cmocka_unit_test(test_importance_normalised),
        cmocka_unit_test(test_margin),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
