/* Checks of an image file's bytes before stb_image (io/image_stb.h) or, for JPEG,
 * libjpeg-turbo (io/jpeg.h) decodes them: which of the documented formats it is, as stb
 * tells them apart, and what stb 2.27 does not check. */
#ifndef CST_IO_IMAGE_PRECHECK_H
#define CST_IO_IMAGE_PRECHECK_H

#include <stddef.h>

#include "caustic/caustic.h"

/* The texture formats stb decodes for caustic, told apart by content in stb's order. */
typedef enum ImageStbFormat {
    IMAGE_STB_NONE, IMAGE_STB_PNG, IMAGE_STB_JPEG, IMAGE_STB_BMP, IMAGE_STB_HDR, IMAGE_STB_TGA
} ImageStbFormat;

/* The format stb_image (built with only the documented formats) takes these bytes for;
 * IMAGE_STB_JPEG by stb's test, though JPEG is decoded by io/jpeg.h. */
ImageStbFormat image_precheck_format(const unsigned char *data, size_t size);

/* Refuses, before stb allocates or decodes anything:
 * - a format stb knows but caustic does not read (GIF, PSD, PIC, PNM): CST_ERR_UNSUPPORTED
 *   naming it and the formats that are read; content of no known format: CST_ERR_PARSE;
 * - a JPEG Huffman table (DHT) of more than 256 codes, which stb 2.27 writes past its
 *   table for (docs/fuzzing.md, fixed finding 1), and a scan decoding with a table no DHT
 *   defined, which stb reads from uninitialised memory: CST_ERR_PARSE;
 * - a PNG chunk before IEND longer than the rest of the file, for which stb 2.27
 *   allocates its declared length before reading: CST_ERR_PARSE;
 * - a JPEG whose header libjpeg cannot read (io/jpeg.h's jpeg_info): CST_ERR_PARSE;
 * - a declared size image_size_ok refuses: CST_ERR_UNSUPPORTED;
 * - a declared size the file is too short to hold in its format (uncompressed and RLE
 *   data, JPEG's 1 bit per 8 x 8 block, deflate's 1032:1), which stb would fill with
 *   zeros or leave uninitialised after spending time and memory on it: CST_ERR_PARSE.
 * Messages start with path. On success *width, *height are the declared size. */
CstStatus image_precheck_stb(const char *path, const unsigned char *data, size_t size, int *width,
                             int *height, CstError *err);

#endif
