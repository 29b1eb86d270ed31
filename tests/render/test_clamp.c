/* The film's per-sample clamp (CstRenderSettings.max_component; JSON film "max_component";
 * pbrt-v4's RGBFilm "maxcomponentvalue"): with a box filter every camera sample, and so every
 * pixel mean, has its largest CIE XYZ component at most max_component / 2^exposure, hue kept;
 * light-tracing splats are clamped one by one; no clamp leaves the image bit-identical. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"

/* A grey floor under a small, very bright red-orange sphere light seen directly. */
static const char scene_fmt[] =
    "{\"film\": {\"width\": 24, \"height\": 16, \"filter\": \"box\"%s},"
    " \"camera\": {\"position\": [0, 1.5, 4], \"look_at\": [0, 0.4, 0], \"fov\": 45},"
    " \"integrator\": {\"type\": \"path\", \"max_depth\": 4},"
    " \"materials\": {\"grey\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]},"
    "  \"black\": {\"type\": \"diffuse\", \"albedo\": [0, 0, 0]}},"
    " \"shapes\": [{\"type\": \"quad\", \"material\": \"grey\","
    "   \"vertices\": [[-5, 0, -5], [-5, 0, 5], [5, 0, 5], [5, 0, -5]]},"
    "  {\"type\": \"sphere\", \"material\": \"black\", \"center\": [0, 0.6, 0], \"radius\": 0.3,"
    "   \"emission\": {\"radiance\": [400, 120, 20]}}]}";

static CstFilm *render(const char *film_extra, CstIntegrator integ, double exposure, int spp)
{
    char text[2048];
    snprintf(text, sizeof text, scene_fmt, film_extra);
    CstScene *s = NULL;
    CstError e;
    if (cst_scene_load_json_string(text, strlen(text), "clamp.json", &s, &e) != CST_OK) fail_msg("%s", e.msg);
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.spp = spp;
    rs.threads = 2;
    rs.integrator = integ;
    rs.seed = 5;
    rs.seed_set = 1;
    if (exposure != 0.0) {
        rs.exposure = exposure;
        rs.exposure_set = 1;
    }
    CstFilm *f = NULL;
    if (cst_render(s, &rs, &f, NULL, &e) != CST_OK) fail_msg("%s", e.msg);
    cst_scene_destroy(s);
    return f;
}

static double max_xyz(const double p[3])
{
    double x = 0.4124 * p[0] + 0.3576 * p[1] + 0.1805 * p[2];
    double y = 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    double z = 0.0193 * p[0] + 0.1192 * p[1] + 0.9505 * p[2];
    return fmax(x, fmax(y, z));
}

/* Every pixel mean of the clamped path-traced image within the bound (exposure 0 and 1);
 * the unclamped image exceeds it where the light is seen; the clamped light pixels keep the
 * emitter's hue (r : g : b = 400 : 120 : 20). */
static void test_camera_samples_clamped(void **state)
{
    (void)state;
    CstFilm *free_f = render("", CST_INTEGRATOR_PATH, 0.0, 8);
    for (int ev = 0; ev < 2; ev++) {
        CstFilm *f = render(", \"max_component\": 2", CST_INTEGRATOR_PATH, (double)ev, 8);
        const double bound = 2.0 / exp2((double)ev);
        int over_free = 0, clamped_light = 0;
        for (int y = 0; y < cst_film_height(f); y++)
            for (int x = 0; x < cst_film_width(f); x++) {
                double p[3], q[3];
                cst_film_pixel(f, x, y, p);
                cst_film_pixel(free_f, x, y, q);
                if (!(max_xyz(p) <= bound * (1.0 + 1e-5)))
                    fail_msg("exposure %d, pixel (%d, %d): max XYZ %g above %g", ev, x, y, max_xyz(p), bound);
                for (int c = 0; c < 3; c++)
                    if (!(p[c] <= q[c] * (1.0 + 1e-6) + 1e-12)) fail_msg("pixel (%d, %d) brighter when clamped", x, y);
                if (max_xyz(q) > bound) over_free++;
                /* a pixel whose every sample saw the light (X = 211.48 unclamped): all clamped */
                if (max_xyz(q) > 0.999 * (0.4124 * 400 + 0.3576 * 120 + 0.1805 * 20)) {
                    clamped_light++;
                    if (fabs(p[1] / p[0] - 0.3) > 1e-4 || fabs(p[2] / p[0] - 0.05) > 1e-4)
                        fail_msg("pixel (%d, %d): hue (%g, %g, %g) not the emitter's", x, y, p[0], p[1], p[2]);
                }
            }
        assert_true(over_free > 0);
        assert_true(clamped_light > 0);
        cst_film_destroy(f);
    }
    cst_film_destroy(free_f);
}

/* A bound above every sample changes no bit; the light tracer's splats are clamped too (its
 * image darkens where the floor's direct splats of the light exceed the bound). */
static void test_no_effect_and_splats(void **state)
{
    (void)state;
    CstFilm *a = render("", CST_INTEGRATOR_PATH, 0.0, 4), *b = render(", \"max_component\": 1e30", CST_INTEGRATOR_PATH, 0.0, 4);
    int n = cst_film_width(a) * cst_film_height(a);
    float *pa = malloc(3u * (size_t)n * sizeof *pa), *pb = malloc(3u * (size_t)n * sizeof *pb);
    assert_true(pa && pb);
    cst_film_pixels(a, pa);
    cst_film_pixels(b, pb);
    assert_memory_equal(pa, pb, 3u * (size_t)n * sizeof *pa);
    cst_film_destroy(a);
    cst_film_destroy(b);
    CstFilm *la = render("", CST_INTEGRATOR_LIGHT, 0.0, 4), *lb = render(", \"max_component\": 0.05", CST_INTEGRATOR_LIGHT, 0.0, 4);
    cst_film_pixels(la, pa);
    cst_film_pixels(lb, pb);
    double sa = 0.0, sb = 0.0;
    for (int i = 0; i < 3 * n; i++) {
        if (!(pb[i] <= pa[i] * (1.0f + 1e-6f) + 1e-12f)) fail_msg("value %d brighter when clamped", i);
        sa += (double)pa[i];
        sb += (double)pb[i];
    }
    if (!(sb < 0.99 * sa)) fail_msg("light tracer: clamped sum %g, unclamped %g", sb, sa);
    cst_film_destroy(la);
    cst_film_destroy(lb);
    free(pa);
    free(pb);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_camera_samples_clamped),
        cmocka_unit_test(test_no_effect_and_splats),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
