/* Spectra of pbrt-v4's non-area lights in spectral mode against pbrt-v4 itself: a diffuse
 * orange floor lit by one light per scene (point with stdillum-F11, spot with a 2700 K
 * blackbody and "power", distant with a sampled spectrum and "illuminance", goniometric
 * with illum-acesD60 and an image, uniform infinite with stdillum-F4, and an RGB point as
 * the control), direct light only; the image's mean RGB must match pbrt-v4's. */
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

#define SCENE_HEAD                                                                                 \
    "Film \"rgb\" \"integer xresolution\" [16] \"integer yresolution\" [16] \"string filename\" "  \
    "\"out.exr\"\nSampler \"independent\"\nIntegrator \"path\" \"integer maxdepth\" [1]\n"         \
    "LookAt 0 4 4  0 0 0  0 1 0\nCamera \"perspective\" \"float fov\" [50]\nWorldBegin\n"          \
    "Material \"diffuse\" \"rgb reflectance\" [0.7 0.35 0.15]\n"                                   \
    "Shape \"bilinearmesh\" \"point3 P\" [-3 0 -3  3 0 -3  -3 0 3  3 0 3]\n"

/* The references: pbrt-v4 (/work/shared/tools/pbrt-v4, source commit 5f7a6068) rendering
 * exactly these scenes, `pbrt --nthreads 2 --spp 16384 --seed 1 X.pbrt --outfile X.exr`
 * (the goniometric one beside a 16 x 16 PFM of ones, "gonio.pfm"), mean over the 16 x 16
 * pixels of the linear sRGB EXR. Their own noise is below 0.1 % of the brightest channel. */
static const struct {
    const char *name, *light;
    double ref[3];
} CASES[] = {
    {"point", "LightSource \"point\" \"spectrum I\" \"stdillum-F11\" \"float scale\" 5 \"point3 from\" [0.5 2 0]\n",
     {0.106376, 0.040518, 0.007165}},
    {"spot", "LightSource \"spot\" \"blackbody I\" [2700] \"float power\" 40 \"point3 from\" [0 3 0] "
             "\"point3 to\" [0.3 0 0] \"float coneangle\" 40 \"float conedeltaangle\" 10\n",
     {0.443273, 0.097901, 0.001308}},
    {"distant", "LightSource \"distant\" \"spectrum L\" [400 1 450 3 500 0.5 550 2 600 0.2 650 1.5 700 0.5] "
                "\"float illuminance\" 2 \"point3 from\" [1 3 1] \"point3 to\" [0 0 0]\n",
     {0.233627, 0.164571, 0.126672}},
    {"gonio", "AttributeBegin\nTranslate 0 2 0\nLightSource \"goniometric\" \"spectrum I\" \"illum-acesD60\" "
              "\"string filename\" \"gonio.pfm\" \"float scale\" 4\nAttributeEnd\n",
     {0.071257, 0.033997, 0.013221}},
    {"infinite", "LightSource \"infinite\" \"spectrum L\" \"stdillum-F4\" \"float scale\" 0.7\n",
     {0.840059, 0.313309, 0.045480}},
    {"point rgb", "LightSource \"point\" \"rgb I\" [0.2 0.5 1.0] \"float scale\" 5 \"point3 from\" [0.5 2 0]\n",
     {0.020803, 0.021329, 0.019695}},
};

/* A 16 x 16 PFM of ones (the goniometric light's image: isotropic), in the build tree. */
static void write_gonio_image(const char *path)
{
    FILE *f = fopen(path, "wb");
    assert_non_null(f);
    fprintf(f, "PF\n16 16\n-1.0\n");
    const float one[3] = {1.0f, 1.0f, 1.0f};
    for (int i = 0; i < 16 * 16; i++) assert_int_equal(fwrite(one, sizeof one, 1, f), 1);
    assert_int_equal(fclose(f), 0);
}

/* Each channel's mean within 1 % of the reference's brightest channel plus 4 standard
 * errors of caustic's mean (from the film's per-pixel variances). Before the lights kept
 * their spectra, the named illuminants rendered as D65 white (point: (0.084, 0.042, 0.018)
 * against pbrt-v4's (0.106, 0.041, 0.007)) and the others as their RGB upsampled. */
static void test_lights_match_pbrt(void **state)
{
    (void)state;
    write_gonio_image(CST_BINARY_DIR "/gonio.pfm");
    for (size_t k = 0; k < sizeof CASES / sizeof CASES[0]; k++) {
        char text[2048];
        snprintf(text, sizeof text, "%s%s", SCENE_HEAD, CASES[k].light);
        CstScene *s = NULL;
        CstError err;
        if (cst_scene_load_pbrt_string(text, strlen(text), CST_BINARY_DIR "/light_spectra.pbrt", NULL, &s, &err))
            fail_msg("%s: %s", CASES[k].name, err.msg);
        CstRenderSettings rs;
        cst_render_settings_init(&rs);
        rs.spp = 2048;
        rs.seed = 7 + k;
        rs.seed_set = 1;
        rs.color_mode = CST_COLOR_SPECTRAL;
        CstFilm *film = NULL;
        if (cst_render(s, &rs, &film, NULL, &err)) fail_msg("%s: %s", CASES[k].name, err.msg);
        int w = cst_film_width(film), h = cst_film_height(film);
        assert_int_equal(w, 16);
        assert_int_equal(h, 16);
        double m[3] = {0, 0, 0}, var[3] = {0, 0, 0};
        for (int y = 0; y < h; y++)
            for (int x = 0; x < w; x++) {
                double p[3], v[3];
                cst_film_pixel(film, x, y, p);
                cst_film_pixel_variance(film, x, y, v);
                for (int c = 0; c < 3; c++) m[c] += p[c] / (w * h), var[c] += v[c] / ((double)w * h * w * h);
            }
        const double *ref = CASES[k].ref;
        double top = fmax(ref[0], fmax(ref[1], ref[2]));
        printf("%-10s caustic (%.6f %.6f %.6f)  pbrt-v4 (%.6f %.6f %.6f)\n", CASES[k].name, m[0], m[1], m[2],
               ref[0], ref[1], ref[2]);
        for (int c = 0; c < 3; c++)
            if (fabs(m[c] - ref[c]) > 0.01 * top + 4.0 * sqrt(var[c]))
                fail_msg("%s: channel %d mean %.6f, pbrt-v4 %.6f (limit %.6f)", CASES[k].name, c, m[c], ref[c],
                         0.01 * top + 4.0 * sqrt(var[c]));
        cst_film_destroy(film);
        cst_scene_destroy(s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {cmocka_unit_test(test_lights_match_pbrt)};
    return cmocka_run_group_tests(tests, NULL, NULL);
}
