/* stb_image (Debian's libstb-dev header), built into the library with only the formats
 * caustic documents and reads through it: PNG, BMP, TGA and Radiance HDR, decoded from
 * memory (JPEG goes through libjpeg-turbo, io/jpeg.h). */
#ifndef CST_IO_IMAGE_STB_H
#define CST_IO_IMAGE_STB_H

#include <stdbool.h>

/* stb's largest width or height (STBI_MAX_DIMENSIONS, stb's own default written out):
 * the pixel limit of image_size_ok (io/image_io.h) applies on top. */
#define IMAGE_STB_MAX_SIDE (1 << 24)

/* The header's width and height (stbi_info_from_memory): false when stb cannot read it. */
bool image_stb_info(const unsigned char *data, int len, int *width, int *height);
/* A Radiance HDR file (stbi_is_hdr_from_memory). */
bool image_stb_is_hdr(const unsigned char *data, int len);
/* A 16-bit PNG (stbi_is_16_bit_from_memory). */
bool image_stb_is_16_bit(const unsigned char *data, int len);
/* Decodes to 3 channels, row 0 at the top: bits 8 gives bytes, 16 uint16_t, 32 floats
 * (Radiance HDR only: stbi_loadf, linear). The result is free()d by the caller; NULL on
 * failure, with the reason in image_stb_failure_reason(). */
void *image_stb_load(const unsigned char *data, int len, int bits, int *width, int *height);
/* image_stb_load of an 8- or 16-bit image keeping grey images grey: *channels is 1 for
 * grey and grey + alpha files (alpha dropped), else 3 (alpha dropped). */
void *image_stb_load_channels(const unsigned char *data, int len, int bits, int *width, int *height,
                              int *channels);
/* image_stb_load of an 8- or 16-bit image as `channels` (1 to 4) channels, stb's conversion
 * (4: alpha kept, 255 / 65535 where the file has none). */
void *image_stb_load_n(const unsigned char *data, int len, int bits, int channels, int *width, int *height);
/* stb's reason for the last failure on this thread ("unknown reason" when it gave none). */
const char *image_stb_failure_reason(void);

#endif
