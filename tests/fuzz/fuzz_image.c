/* libFuzzer target for the image readers: libpng (image_read on .png), OpenEXR's C API and
 * our PFM parser (image_read on .exr/.pfm, reached through the texture loader), stb_image
 * for HDR, BMP, TGA and PNG and libjpeg-turbo for JPEG (src/io/jpeg.c) after our pre-check
 * (texture_image_load; stb is compiled into the library, so it is instrumented like the
 * rest; libjpeg is the system's, so only our code around it is). Any bytes must give pixels of the
 * stated size or an explained error, never a crash or a leak. The file's extension follows
 * its magic bytes, as a real file's would. Built by -DCST_FUZZ=ON (tests/fuzz/CMakeLists.txt);
 * run with scripts/fuzz.sh, see docs/fuzzing.md. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "fuzz_file.h"
#include "io/image_io.h"
#include "io/image_precheck.h"
#include "textures/texture.h"

static void check_read(CstStatus st, const float *rgb, int w, int h, const CstError *err)
{
    if (st == CST_OK) {
        if (!rgb || w <= 0 || h <= 0) abort();
    } else if (err->msg[0] == '\0') {
        abort();
    }
}

/* Images the pre-check accepts and that declare more than FUZZ_MAX_PIXELS (256 x 256) are
 * not decoded, for speed alone: under ASan a few million pixels take seconds, which would
 * hold the fuzzer to a few inputs a second for no new code. Everything the pre-check
 * refuses still goes through texture_image_load. (The filters of the stb findings 2, 3 and
 * 4 of docs/fuzzing.md are gone with their fix.) */
#define FUZZ_MAX_PIXELS ((uint64_t)1 << 16)

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    CstError err;
    int iw = 0, ih = 0;
    err.msg[0] = '\0';
    if (image_precheck_format(data, size) != IMAGE_STB_NONE &&
        image_precheck_stb("fuzz", data, size, &iw, &ih, &err) == CST_OK &&
        (uint64_t)iw * (uint64_t)ih > FUZZ_MAX_PIXELS)
        return 0; /* speed only, see FUZZ_MAX_PIXELS */
    static const uint8_t png_magic[4] = {0x89, 'P', 'N', 'G'}, exr_magic[4] = {0x76, 0x2f, 0x31, 0x01};
    const char *ext = ".jpg"; /* the texture loader goes by content, whatever the name */
    if (size >= 4 && memcmp(data, png_magic, 4) == 0) ext = ".png";
    else if (size >= 4 && memcmp(data, exr_magic, 4) == 0) ext = ".exr";
    else if (size >= 2 && data[0] == 'P' && (data[1] == 'F' || data[1] == 'f')) ext = ".pfm";
    const char *path = fuzz_write_file(data, size, ext);

    if (strcmp(ext, ".jpg") != 0) { /* the film's readers, chosen by extension */
        float *rgb = NULL;
        int w = 0, h = 0;
        err.msg[0] = '\0';
        CstStatus st = image_read(path, &rgb, &w, &h, &err);
        check_read(st, rgb, w, h, &err);
        free(rgb);
    }
    /* The texture loader: EXR and PFM by magic through image_read, the rest through stb. */
    Texture tex;
    err.msg[0] = '\0';
    CstStatus st = texture_image_load(&tex, path, size & 1, TEXTURE_WRAP_REPEAT, &err);
    if (st == CST_OK) {
        if (tex.type != TEXTURE_IMAGE) abort();
        /* Compact storage (texture.h TexImage): level 0's texels in the file's own format. */
        const TexImage *im = tex.image.im;
        if (!im || im->num_levels < 1) abort();
        check_read(st, im->level[0].texels, tex.image.width, tex.image.height, &err);
        texture_free(&tex);
    } else {
        check_read(st, NULL, 0, 0, &err);
    }
    return 0;
}
