/* pbrt-v4's image-textured diffuse area light (AreaLightSource "diffuse" "string filename"):
 * a uniform image times scale is the constant L of the same value (the emitters' selection
 * weights, and renders of the two scenes pixel for pixel), "power" normalises by the image's
 * mean luminance as pbrt-v4 does (closed form: luminance of the mean radiance = P / (pi A)),
 * and "L" with "filename" is a located error. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "io/image_io.h"
#include "scene/scene.h"
#include "unit/scratch_dir.h"

#define PI_D 3.14159265358979323846

static int setup(void **state)
{
    (void)state;
    if (scratch_dir_make("/tmp/caustic-arealight-XXXXXX") != 0) return -1;
    float px[4 * 4 * 3];
    for (int i = 0; i < 16; i++) px[3 * i] = 0.25f, px[3 * i + 1] = 0.5f, px[3 * i + 2] = 1.0f;
    char p[512];
    CstError err;
    tpath(p, sizeof p, "uniform.pfm");
    return image_write(p, px, 4, 4, &err) == CST_OK ? 0 : -1;
}
static int teardown(void **state)
{
    (void)state;
    return scratch_dir_remove();
}

/* A 2 x 1 quad light above a diffuse sphere, facing down at it. */
static CstScene *load(const char *light_params, CstError *err, CstStatus *st)
{
    char text[2048], name[512];
    snprintf(text, sizeof text,
             "LookAt 0 0 -6  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" 40\n"
             "Sampler \"independent\" \"integer pixelsamples\" 4\n"
             "Film \"rgb\" \"integer xresolution\" 16 \"integer yresolution\" 16\nWorldBegin\n"
             "AttributeBegin\nAreaLightSource \"diffuse\" %s\n"
             "Shape \"trianglemesh\" \"point3 P\" [-1 1.2 -0.5  1 1.2 -0.5  1 1.2 0.5  -1 1.2 0.5]\n"
             "  \"integer indices\" [0 1 2  0 2 3] \"point2 uv\" [0 0 1 0 1 1 0 1]\nAttributeEnd\n"
             "Material \"diffuse\"\nShape \"sphere\" \"float radius\" 0.8\n",
             light_params);
    tpath(name, sizeof name, "t.pbrt");
    CstScene *sc = NULL;
    *st = cst_scene_load_pbrt_string(text, strlen(text), name, NULL, &sc, err);
    return sc;
}

static CstFilm *render(const CstScene *sc)
{
    CstRenderSettings rs;
    cst_render_settings_init(&rs);
    rs.threads = 2;
    rs.seed = 3;
    rs.seed_set = 1;
    rs.color_mode = CST_COLOR_RGB;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(sc, &rs, &f, NULL, &err), CST_OK);
    return f;
}

static void same_light(const char *image_params, const char *const_params, double power, double area)
{
    CstError err;
    CstStatus st;
    CstScene *a = load(image_params, &err, &st);
    if (st != CST_OK) fail_msg("%s", err.msg);
    CstScene *b = load(const_params, &err, &st);
    if (st != CST_OK) fail_msg("%s", err.msg);
    const Scene *sa = (const Scene *)a, *sb = (const Scene *)b;
    assert_int_equal(sa->num_emitters, 2);
    assert_int_equal(sb->num_emitters, 2);
    for (int i = 0; i < 2; i++) {
        const Emitter *ea = &sa->emitter_sampler.light[i].u.area, *eb = &sb->emitter_sampler.light[i].u.area;
        assert_true(ea->texture != 0);
        assert_true(eb->texture == 0);
        for (int c = 0; c < 3; c++) {
            double x = (double)color_channel(ea->average, c), y = (double)color_channel(eb->average, c);
            assert_true(fabs(x - y) <= 1e-6 * y);
        }
        if (power > 0.0) {
            /* pbrt-v4: L = power / (pi A k), k the image's (or spectrum's) luminance: the
             * luminance of the emitted radiance is then power / (pi A) */
            double lum = (double)color_luminance(ea->average);
            print_message("  luminance of L %.6f, power / (pi A) %.6f\n", lum, power / (PI_D * area));
            assert_true(fabs(lum - power / (PI_D * area)) <= 1e-5 * lum);
        }
    }
    CstFilm *fa = render(a), *fb = render(b);
    double max_rel = 0.0, mean = 0.0;
    for (int y = 0; y < 16; y++)
        for (int x = 0; x < 16; x++) {
            double pa[3], pb[3];
            cst_film_pixel(fa, x, y, pa);
            cst_film_pixel(fb, x, y, pb);
            for (int c = 0; c < 3; c++) {
                max_rel = fmax(max_rel, fabs(pa[c] - pb[c]) / fmax(pb[c], 1e-3));
                mean += pb[c];
            }
        }
    print_message("  image vs constant: max relative pixel difference %.2e (image mean %.4f)\n", max_rel,
                  mean / (16.0 * 16.0 * 3.0));
    assert_true(mean > 0.0);
    assert_true(max_rel <= 1e-5);
    cst_film_destroy(fa);
    cst_film_destroy(fb);
    cst_scene_destroy(a);
    cst_scene_destroy(b);
}

static void test_uniform_image_is_constant_L(void **state)
{
    (void)state;
    same_light("\"string filename\" \"uniform.pfm\" \"float scale\" 4", "\"rgb L\" [1 2 4]", 0.0, 2.0);
}

static void test_power_normalisation(void **state)
{
    (void)state;
    /* The image's mean luminance k_e = Y(0.25, 0.5, 1): L = (0.25, 0.5, 1) P / (pi A k_e);
     * the constant's "L" has the same chromaticity, and pbrt-v4 normalises it the same way. */
    const double y = 0.2126 * 0.25 + 0.7152 * 0.5 + 0.0722 * 1.0;
    char lp[128];
    snprintf(lp, sizeof lp, "\"rgb L\" [%.9g %.9g %.9g] \"float power\" 10", 0.25 / y, 0.5 / y, 1.0 / y);
    /* power is per shape: each triangle (area 1) gets 10 W */
    same_light("\"string filename\" \"uniform.pfm\" \"float power\" 10", lp, 10.0, 1.0);
}

static void test_errors(void **state)
{
    (void)state;
    CstError err;
    CstStatus st;
    CstScene *s = load("\"string filename\" \"uniform.pfm\" \"rgb L\" [1 1 1]", &err, &st);
    assert_int_equal(st, CST_ERR_INVALID_ARG);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "t.pbrt:7:"));
    cst_scene_destroy(s);
    s = load("\"string filename\" \"missing.pfm\"", &err, &st);
    assert_int_not_equal(st, CST_OK);
    print_message("  %s\n", err.msg);
    assert_non_null(strstr(err.msg, "t.pbrt:7:"));
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_uniform_image_is_constant_L),
        cmocka_unit_test(test_power_normalisation),
        cmocka_unit_test(test_errors),
    };
    return cmocka_run_group_tests(tests, setup, teardown);
}
