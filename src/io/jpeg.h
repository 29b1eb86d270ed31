/* JPEG decoding through libjpeg-turbo (Debian's libjpeg62-turbo), from memory: every
 * libjpeg error, and every warning that means corrupt data, is a located CstError. */
#ifndef CST_IO_JPEG_H
#define CST_IO_JPEG_H

#include <stddef.h>

#include "caustic/caustic.h"

/* Progressive scans read before a file is refused: each scan is a pass over the whole
 * coefficient buffer, so a small file of thousands of tiny scans costs minutes (the limit
 * TurboJPEG's own tools use; an encoder's progression has about 10). */
#define JPEG_MAX_SCANS 500

/* The frame header's width and height (jpeg_read_header; nothing is decoded). Fails with
 * CST_ERR_PARSE, the message "path: cannot decode the JPEG (libjpeg-turbo, at or after
 * byte N): <libjpeg's reason>", N being where libjpeg's reader stood (inside a scan, the
 * start of the MCU it was decoding). */
CstStatus jpeg_info(const char *path, const unsigned char *data, size_t size, int *width, int *height,
                    CstError *err);

/* Decodes to 8-bit samples, row 0 at the top: one channel for a greyscale file, else three
 * (YCbCr and RGB as libjpeg converts them; Adobe CMYK and YCCK multiplied out as
 * stb_image did, R = C K / 255 on the stored, inverted values). *pixels is malloc'd, the
 * caller free()s it. Fails with CST_ERR_PARSE for corrupt or truncated data (libjpeg's
 * corrupt-data warnings included: it would otherwise fill the rest with grey), more than
 * JPEG_MAX_SCANS scans, or what libjpeg does not read (12-bit samples); CST_ERR_OOM.
 * Callers check the declared size first (io/image_precheck.h): nothing here bounds it. */
CstStatus jpeg_decode(const char *path, const unsigned char *data, size_t size, unsigned char **pixels,
                      int *width, int *height, int *channels, CstError *err);

#endif
