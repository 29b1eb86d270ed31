/* stb_image's implementation, compiled here from Debian's libstb-dev header instead of
 * linking libstb.so, so that only the documented formats are built in (docs/fuzzing.md,
 * fixed finding 3: stb's GIF, PSD, PIC and PNM readers are out; its JPEG reader too since
 * JPEG goes through libjpeg-turbo, io/jpeg.h). Reached only through io/image_stb.h;
 * untrusted bytes are checked first by io/image_precheck.h. */
#include "io/image_stb.h"

#include <stdlib.h>

#define STBI_ONLY_PNG
#define STBI_ONLY_BMP
#define STBI_ONLY_TGA
#define STBI_ONLY_HDR
#define STBI_NO_STDIO /* the caller reads the file through core/file.h's gate */
#define STBI_MAX_DIMENSIONS IMAGE_STB_MAX_SIDE
/* Every stbi_ function static to this file: no symbol clash with a program that links its
 * own stb_image next to libcaustic.a. */
#define STB_IMAGE_STATIC
/* stb's allocator is the C library's, so its results are free()d by our callers. */
#define STBI_MALLOC(size) malloc(size)
#define STBI_REALLOC(p, size) realloc(p, size)
#define STBI_FREE(p) free(p)
#define STB_IMAGE_IMPLEMENTATION
/* Third-party code under our warning set: its style is not ours to change. Its unused
 * static functions (STB_IMAGE_STATIC; some declared and never defined, reported at the end
 * of the file) are expected for the whole file. */
#pragma GCC diagnostic ignored "-Wunused-function"
#pragma GCC diagnostic push
#pragma GCC diagnostic ignored "-Wshadow"
#pragma GCC diagnostic ignored "-Wdouble-promotion"
#pragma GCC diagnostic ignored "-Wsign-compare"
#pragma GCC diagnostic ignored "-Wunused-parameter"
#pragma GCC diagnostic ignored "-Wimplicit-fallthrough"
#pragma GCC diagnostic ignored "-Wmissing-prototypes"
#pragma GCC diagnostic ignored "-Wstrict-prototypes"
#include <stb_image.h>
#pragma GCC diagnostic pop

bool image_stb_info(const unsigned char *data, int len, int *width, int *height)
{
    int comp = 0;
    return stbi_info_from_memory(data, len, width, height, &comp) != 0;
}

bool image_stb_is_hdr(const unsigned char *data, int len) { return stbi_is_hdr_from_memory(data, len) != 0; }

bool image_stb_is_16_bit(const unsigned char *data, int len) { return stbi_is_16_bit_from_memory(data, len) != 0; }

void *image_stb_load(const unsigned char *data, int len, int bits, int *width, int *height)
{
    int comp = 0;
    if (bits == 32) return stbi_loadf_from_memory(data, len, width, height, &comp, 3);
    if (bits == 16) return stbi_load_16_from_memory(data, len, width, height, &comp, 3);
    return stbi_load_from_memory(data, len, width, height, &comp, 3);
}

void *image_stb_load_channels(const unsigned char *data, int len, int bits, int *width, int *height,
                              int *channels)
{
    int x = 0, y = 0, comp = 0;
    int want = stbi_info_from_memory(data, len, &x, &y, &comp) && comp <= 2 ? 1 : 3;
    *channels = want;
    if (bits == 16) return stbi_load_16_from_memory(data, len, width, height, &comp, want);
    return stbi_load_from_memory(data, len, width, height, &comp, want);
}

void *image_stb_load_n(const unsigned char *data, int len, int bits, int channels, int *width, int *height)
{
    int comp = 0;
    if (bits == 16) return stbi_load_16_from_memory(data, len, width, height, &comp, channels);
    return stbi_load_from_memory(data, len, width, height, &comp, channels);
}

const char *image_stb_failure_reason(void)
{
    const char *why = stbi_failure_reason();
    return why ? why : "unknown reason";
}
