/* What cst_film_write does with a render's output settings: exposure scales the written
 * pixels (not the film), PNG can be written linear, and AOVs land in extra EXR channels
 * (read back here with the OpenEXR C API): on the Cornell box's back wall, depth 1359.2
 * (559.2 + 800 along the view axis), normal (0, 0, -1) toward the camera, the white
 * albedo, and variance equal to the film's variance of the mean. */
#include <math.h>
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include <openexr.h>
#include <png.h>

#include "film/film.h"
#include "scene/scene.h"

enum { SIZE = 16, MAX_CHANNELS = 16 };

typedef struct ExrImage {
    int n;
    char names[MAX_CHANNELS][32];
    float *data[MAX_CHANNELS]; /* SIZE x SIZE each */
} ExrImage;

/* Every channel of a SIZE x SIZE scanline EXR, as floats. */
static void exr_load(const char *path, ExrImage *img)
{
    memset(img, 0, sizeof *img);
    exr_context_t ctx = NULL;
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    assert_int_equal(exr_start_read(&ctx, path, &init), EXR_ERR_SUCCESS);
    const exr_attr_chlist_t *ch = NULL;
    assert_int_equal(exr_get_channels(ctx, 0, &ch), EXR_ERR_SUCCESS);
    assert_true(ch->num_channels <= MAX_CHANNELS);
    img->n = ch->num_channels;
    for (int c = 0; c < img->n; c++) {
        snprintf(img->names[c], sizeof img->names[c], "%s", ch->entries[c].name.str);
        img->data[c] = calloc(SIZE * SIZE, sizeof(float));
        assert_non_null(img->data[c]);
    }
    int32_t lines = 0;
    assert_int_equal(exr_get_scanlines_per_chunk(ctx, 0, &lines), EXR_ERR_SUCCESS);
    exr_decode_pipeline_t dec = EXR_DECODE_PIPELINE_INITIALIZER;
    bool live = false;
    for (int y = 0; y < SIZE; y += lines) {
        exr_chunk_info_t ci;
        assert_int_equal(exr_read_scanline_chunk_info(ctx, 0, y, &ci), EXR_ERR_SUCCESS);
        assert_int_equal(live ? exr_decoding_update(ctx, 0, &ci, &dec) : exr_decoding_initialize(ctx, 0, &ci, &dec),
                         EXR_ERR_SUCCESS);
        live = true;
        for (int c = 0; c < dec.channel_count; c++) {
            exr_coding_channel_info_t *cc = &dec.channels[c];
            int k = 0;
            while (k < img->n && strcmp(img->names[k], cc->channel_name) != 0) k++;
            assert_true(k < img->n);
            cc->decode_to_ptr = (uint8_t *)(img->data[k] + (size_t)ci.start_y * SIZE);
            cc->user_pixel_stride = (int32_t)sizeof(float);
            cc->user_line_stride = SIZE * (int32_t)sizeof(float);
            cc->user_bytes_per_element = (int16_t)sizeof(float);
            cc->user_data_type = EXR_PIXEL_FLOAT;
        }
        if (!dec.unpack_and_convert_fn)
            assert_int_equal(exr_decoding_choose_default_routines(ctx, 0, &dec), EXR_ERR_SUCCESS);
        assert_int_equal(exr_decoding_run(ctx, 0, &dec), EXR_ERR_SUCCESS);
    }
    if (live) exr_decoding_destroy(ctx, &dec);
    exr_finish(&ctx);
}

static const float *exr_channel(const ExrImage *img, const char *name)
{
    for (int c = 0; c < img->n; c++)
        if (strcmp(img->names[c], name) == 0) return img->data[c];
    fail_msg("no channel %s", name);
    return NULL;
}

static Film *render(const CstScene *s, int aovs, double exposure, int png_linear)
{
    CstRenderSettings st = {0};
    st.width = st.height = SIZE;
    st.spp = 8;
    st.threads = 2;
    st.aovs = aovs;
    st.exposure = exposure;
    st.exposure_set = 1;
    st.png_linear = png_linear;
    CstFilm *f = NULL;
    CstError err;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    return f;
}

static void test_aov_channels(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    Film *f = render(s, CST_AOV_ALBEDO | CST_AOV_NORMAL | CST_AOV_DEPTH | CST_AOV_VARIANCE, 1.0, 0);
    const char *path = CST_BINARY_DIR "/test_film_output_aov.exr";
    assert_int_equal(cst_film_write(f, path, &err), CST_OK);
    ExrImage img;
    exr_load(path, &img);
    /* OpenEXR keeps channels sorted by name. */
    static const char *const expected[] = {"B", "G", "N.X", "N.Y", "N.Z", "R", "Z", "albedo.B",
                                           "albedo.G", "albedo.R", "variance.B", "variance.G", "variance.R"};
    assert_int_equal(img.n, 13);
    for (int c = 0; c < 13; c++) assert_string_equal(img.names[c], expected[c]);

    /* Pixel (8, 5) sees only the back wall (above the tall block, below the ceiling). */
    const int i = 5 * SIZE + 8;
    assert_float_equal(exr_channel(&img, "Z")[i], 1359.2f, 1e-3f);
    assert_float_equal(exr_channel(&img, "N.X")[i], 0.0f, 1e-6f);
    assert_float_equal(exr_channel(&img, "N.Y")[i], 0.0f, 1e-6f);
    assert_float_equal(exr_channel(&img, "N.Z")[i], -1.0f, 1e-6f);
    assert_float_equal(exr_channel(&img, "albedo.R")[i], 0.725f, 1e-6f);
    assert_float_equal(exr_channel(&img, "albedo.G")[i], 0.71f, 1e-6f);
    assert_float_equal(exr_channel(&img, "albedo.B")[i], 0.68f, 1e-6f);
    /* Every pixel: exposure +1 doubles the colour and quadruples its variance. */
    static const char *const rgb[3] = {"R", "G", "B"}, *const var[3] = {"variance.R", "variance.G", "variance.B"};
    for (int y = 0; y < SIZE; y++)
        for (int x = 0; x < SIZE; x++) {
            double m[3], v[3];
            cst_film_pixel(f, x, y, m);
            cst_film_pixel_variance(f, x, y, v);
            for (int c = 0; c < 3; c++) {
                assert_true(exr_channel(&img, rgb[c])[y * SIZE + x] == (float)((double)(float)m[c] * 2.0));
                assert_float_equal(exr_channel(&img, var[c])[y * SIZE + x], (float)(4.0 * v[c]),
                                   1e-6f * (float)(4.0 * v[c]) + 1e-30f);
            }
        }
    for (int c = 0; c < img.n; c++) free(img.data[c]);
    /* AOVs need EXR. */
    assert_int_equal(cst_film_write(f, CST_BINARY_DIR "/test_film_output_aov.png", &err), CST_ERR_INVALID_ARG);
    film_destroy(f);
    cst_scene_destroy(s);
}

/* The first row of an 8-bit RGB PNG, and whether it carries an sRGB chunk. */
static void png_first_row(const char *path, uint8_t *row, int *srgb)
{
    FILE *fp = fopen(path, "rb");
    assert_non_null(fp);
    png_structp png = png_create_read_struct(PNG_LIBPNG_VER_STRING, NULL, NULL, NULL);
    png_infop info = png_create_info_struct(png);
    assert_true(png && info);
    if (setjmp(png_jmpbuf(png))) fail_msg("libpng failed on %s", path);
    png_init_io(png, fp);
    png_read_info(png, info);
    int intent;
    *srgb = png_get_sRGB(png, info, &intent) != 0;
    png_read_row(png, row, NULL);
    png_destroy_read_struct(&png, &info, NULL);
    fclose(fp);
}

/* PNG bytes: round(255 v) when linear, round(255 srgb(v)) otherwise, v clamped. */
static void test_png_linear(void **state)
{
    (void)state;
    CstScene *s;
    CstError err;
    assert_int_equal(cst_scene_create_cornell_box(&s, &err), CST_OK);
    Film *f = render(s, 0, -3.0, 1);
    const char *path = CST_BINARY_DIR "/test_film_output_linear.png";
    assert_int_equal(cst_film_write(f, path, &err), CST_OK);
    uint8_t row[3 * SIZE];
    int srgb;
    png_first_row(path, row, &srgb);
    assert_false(srgb);
    for (int x = 0; x < SIZE; x++) {
        double m[3];
        cst_film_pixel(f, x, 0, m);
        for (int c = 0; c < 3; c++) {
            float v = (float)((double)(float)m[c] * 0.125);
            v = v < 0.0f ? 0.0f : (v > 1.0f ? 1.0f : v);
            assert_int_equal(row[3 * x + c], (uint8_t)(v * 255.0f + 0.5f));
        }
    }
    f->png_linear = 0;
    assert_int_equal(cst_film_write(f, path, &err), CST_OK);
    png_first_row(path, row, &srgb);
    assert_true(srgb);
    film_destroy(f);
    cst_scene_destroy(s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_aov_channels),
        cmocka_unit_test(test_png_linear),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
