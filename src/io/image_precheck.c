/* Checks of an image file's bytes before stb_image or libjpeg decodes them: the format as
 * stb tells it, JPEG Huffman tables stb 2.27 overflowed on and scans using undefined tables
 * (kept for libjpeg), declared sizes the pixel limit or the file's length refuses
 * (docs/fuzzing.md, "Fixed findings"). */
#include "io/image_precheck.h"

#include <limits.h>
#include <stdbool.h>
#include <stdint.h>
#include <string.h>

#include "core/error.h"
#include "io/image_io.h"
#include "io/image_stb.h"
#include "io/jpeg.h"

#define PRECHECK_FORMATS "PNG, JPEG, BMP, TGA, Radiance HDR, OpenEXR or PFM"

static unsigned le16(const unsigned char *p) { return (unsigned)p[0] | (unsigned)p[1] << 8; }
static uint32_t le32(const unsigned char *p) { return (uint32_t)le16(p) | (uint32_t)le16(p + 2) << 16; }

/* stbi__tga_test: the header of a colour-mapped, true-colour or grey TGA, plain or RLE. */
static bool precheck_is_tga(const unsigned char *d, size_t n)
{
    if (n < 18 || d[1] > 1) return false;
    unsigned type = d[2], bits = d[16];
    if (d[1] == 1) {
        unsigned pal = d[7];
        if ((type != 1 && type != 9) || (pal != 8 && pal != 15 && pal != 16 && pal != 24 && pal != 32)) return false;
        if (bits != 8 && bits != 16) return false;
    } else if (type != 2 && type != 3 && type != 10 && type != 11) {
        return false;
    }
    return le16(d + 12) >= 1 && le16(d + 14) >= 1 &&
           (bits == 8 || bits == 15 || bits == 16 || bits == 24 || bits == 32);
}

ImageStbFormat image_precheck_format(const unsigned char *d, size_t n)
{
    static const unsigned char png[8] = {0x89, 'P', 'N', 'G', '\r', '\n', 0x1a, '\n'};
    if (n >= 8 && memcmp(d, png, 8) == 0) return IMAGE_STB_PNG;
    if (n >= 18 && d[0] == 'B' && d[1] == 'M') { /* stbi__bmp_test: the info header's size */
        uint32_t hsz = le32(d + 14);
        if (hsz == 12 || hsz == 40 || hsz == 56 || hsz == 108 || hsz == 124) return IMAGE_STB_BMP;
    }
    /* stb's JPEG start: 0xFF, any more 0xFF fill bytes, then SOI (0xD8). */
    size_t i = 0;
    while (i < n && d[i] == 0xff) i++;
    if (i > 0 && i < n && d[i] == 0xd8) return IMAGE_STB_JPEG;
    if ((n >= 11 && memcmp(d, "#?RADIANCE\n", 11) == 0) || (n >= 7 && memcmp(d, "#?RGBE\n", 7) == 0))
        return IMAGE_STB_HDR;
    if (precheck_is_tga(d, n)) return IMAGE_STB_TGA;
    return IMAGE_STB_NONE;
}

/* A format stb_image knows but caustic does not read, for the message; NULL if none. */
static const char *precheck_other_format(const unsigned char *d, size_t n)
{
    if (n >= 6 && (memcmp(d, "GIF87a", 6) == 0 || memcmp(d, "GIF89a", 6) == 0)) return "GIF";
    if (n >= 4 && memcmp(d, "8BPS", 4) == 0) return "Photoshop (PSD)";
    if (n >= 4 && memcmp(d, "\x53\x80\xf6\x34", 4) == 0) return "Softimage PIC";
    if (n >= 2 && d[0] == 'P' && d[1] >= '1' && d[1] <= '6') return "PNM (PGM/PPM/PBM)";
    return NULL;
}

/* ---------------------------------------------------------------- JPEG markers */

/* A read position in the file; reads past the end give 0, as stbi__get8 does. */
typedef struct PrecheckBytes {
    const unsigned char *d;
    size_t n, pos;
} PrecheckBytes;

static unsigned precheck_get8(PrecheckBytes *b) { return b->pos < b->n ? b->d[b->pos++] : 0; }
static unsigned precheck_get16(PrecheckBytes *b)
{
    unsigned hi = precheck_get8(b);
    return hi << 8 | precheck_get8(b);
}
static void precheck_skip(PrecheckBytes *b, size_t k) { b->pos = k > b->n - b->pos ? b->n : b->pos + k; }

/* The next marker as stb finds one between segments: bytes up to a 0xFF are skipped (stb
 * takes them for padding or fails), 0xFF fill bytes too; -1 at the end of the file. */
static int precheck_next_marker(PrecheckBytes *b)
{
    while (b->pos < b->n && b->d[b->pos] != 0xff) b->pos++;
    while (b->pos < b->n && b->d[b->pos] == 0xff) b->pos++;
    return b->pos < b->n ? (int)b->d[b->pos++] : -1;
}

/* The marker ending a scan's entropy-coded data, read as stb's bit reader reads it: 0xFF 0x00
 * is a data byte and 0xFF 0xD0-0xD7 a restart, whatever else follows 0xFF (and its fill
 * bytes) is a marker; -1 at the end of the file. */
static int precheck_scan_end(PrecheckBytes *b)
{
    while (b->pos < b->n) {
        if (b->d[b->pos++] != 0xff) continue;
        while (b->pos < b->n && b->d[b->pos] == 0xff) b->pos++;
        if (b->pos >= b->n) return -1;
        unsigned c = b->d[b->pos++];
        if (c != 0 && !(c >= 0xd0 && c <= 0xd7)) return (int)c;
    }
    return -1;
}

/* One DHT segment as stbi__process_marker reads it (tables one after another while its
 * length lasts). stb 2.27 builds each table's code-size list from the 16 counts before
 * checking them, so counts adding up to more than 256 write past stbi__huffman.size[257];
 * 2.28 refuses them, and so do we. Each table read is marked in *defined (bit 4 tc + th).
 * *stop is set where stb itself gives up. */
static CstStatus precheck_dht(const char *path, PrecheckBytes *b, unsigned *defined, bool *stop, CstError *err)
{
    size_t at = b->pos - 2;
    long left = (long)precheck_get16(b) - 2;
    while (left > 0) {
        unsigned q = precheck_get8(b);
        if (q >> 4 > 1 || (q & 15) > 3) { /* stb: "bad DHT header" */
            *stop = true;
            return CST_OK;
        }
        unsigned total = 0;
        for (int i = 0; i < 16; i++) total += precheck_get8(b);
        if (total > 256)
            return cst_fail(err, CST_ERR_PARSE,
                            "%s: corrupt JPEG: the Huffman table (DHT segment at byte %zu) declares %u "
                            "codes; at most 256 are possible", path, at, total);
        *defined |= 1u << ((q >> 4) * 4 + (q & 15)); /* bit 4 tc + th */
        precheck_skip(b, total);
        left -= 17 + (long)total;
    }
    *stop = left != 0; /* stb fails a segment whose tables do not fill it exactly */
    return CST_OK;
}

/* One SOS header as stbi__process_scan_header reads it. stb 2.27 allocates its decoder
 * without clearing it, so a scan decoding with a Huffman table no DHT defined reads heap
 * garbage as a table, and a garbage table indexes past its symbols (an assertion in a
 * debug build, an out-of-bounds read in a release one). The tables a scan decodes with:
 * baseline, each component's DC and AC table; progressive, the DC table in a first DC
 * scan, none in a DC refinement, the AC table in an AC scan. */
static CstStatus precheck_sos(const char *path, PrecheckBytes *b, bool progressive, unsigned defined,
                              bool *stop, CstError *err)
{
    size_t at = b->pos - 2;
    unsigned len = precheck_get16(b), ns = precheck_get8(b);
    if (ns < 1 || ns > 4 || len != 6 + 2 * ns) { /* stb: "bad SOS component count", "bad SOS len" */
        *stop = true;
        return CST_OK;
    }
    unsigned tables[4];
    for (unsigned i = 0; i < ns; i++) {
        precheck_get8(b); /* component id */
        tables[i] = precheck_get8(b);
    }
    unsigned ss = precheck_get8(b);
    precheck_get8(b); /* end of spectral selection */
    unsigned ah = precheck_get8(b) >> 4;
    bool dc = !progressive || (ss == 0 && ah == 0), ac = !progressive || ss != 0;
    for (unsigned i = 0; i < ns; i++) {
        unsigned td = tables[i] >> 4, ta = tables[i] & 15;
        if (td > 3 || ta > 3) { /* stb: "bad DC huff", "bad AC huff" */
            *stop = true;
            return CST_OK;
        }
        unsigned tc = dc && !(defined & 1u << td) ? 0 : ac && !(defined & 1u << (4 + ta)) ? 1 : 2;
        if (tc < 2)
            return cst_fail(err, CST_ERR_PARSE,
                            "%s: corrupt JPEG: the scan at byte %zu decodes with %s Huffman table %u, which no "
                            "DHT segment before it defines", path, at, tc == 0 ? "DC" : "AC", tc == 0 ? td : ta);
    }
    return CST_OK;
}

/* Walks the marker segments stb reads, in its order, up to EOI or the point where stb
 * stops; checks every Huffman table on the way, and that the ones each scan decodes with
 * are defined. Segment data (APPn, COM, ...) is skipped by its length, so bytes inside it
 * are not taken for markers. */
static CstStatus precheck_jpeg_tables(const char *path, const unsigned char *d, size_t n, CstError *err)
{
    PrecheckBytes b = {d, n, 0};
    while (b.d[b.pos] == 0xff) b.pos++;
    b.pos++; /* SOI (image_precheck_format) */
    unsigned defined = 0; /* Huffman tables read so far: bit 4 tc + th */
    bool progressive = false;
    int m = precheck_next_marker(&b);
    for (;;) {
        if (m < 0 || m == 0xd9) return CST_OK; /* the end of the file, or EOI */
        bool stop = false;
        if (m == 0xc4) {
            CstStatus st = precheck_dht(path, &b, &defined, &stop, err);
            if (st != CST_OK || stop) return st;
        } else if (m == 0xda) { /* SOS, then entropy-coded data up to the next marker */
            CstStatus st = precheck_sos(path, &b, progressive, defined, &stop, err);
            if (st != CST_OK || stop) return st;
            m = precheck_scan_end(&b);
            continue;
        } else if (m == 0xc0 || m == 0xc1 || m == 0xc2 || m == 0xdb || m == 0xdd || m == 0xdc ||
                   (m >= 0xe0 && m <= 0xef) || m == 0xfe) {
            if (m == 0xc2) progressive = true;
            unsigned len = precheck_get16(&b);
            if (len < 2) return CST_OK; /* stb: a bad length, it fails */
            precheck_skip(&b, len - 2);
        } else {
            return CST_OK; /* stb: "unknown marker", it fails */
        }
        m = precheck_next_marker(&b);
    }
}

/* ---------------------------------------------------------------- PNG chunks */

static uint32_t be32(const unsigned char *p)
{
    return (uint32_t)p[0] << 24 | (uint32_t)p[1] << 16 | (uint32_t)p[2] << 8 | (uint32_t)p[3];
}

/* Every chunk up to IEND must fit in the file: stb 2.27 grows its IDAT buffer to a chunk's
 * declared length before reading it, so a 100-byte file declaring a 2 GB chunk costs a
 * 2 GB allocation before stb finds the data missing. A file stb decodes never has such a
 * chunk (stb stops at IEND and fails on whatever follows a truncated chunk). */
static CstStatus precheck_png_chunks(const char *path, const unsigned char *d, size_t n, CstError *err)
{
    for (size_t at = 8; at + 8 <= n;) {
        uint32_t len = be32(d + at);
        if (memcmp(d + at + 4, "IEND", 4) == 0) return CST_OK;
        if ((uint64_t)len + 12 > n - at)
            return cst_fail(err, CST_ERR_PARSE,
                            "%s: truncated or corrupt PNG: the chunk at byte %zu declares %lu bytes of data, "
                            "the file has %zu after its header", path, at, (unsigned long)len, n - at - 8);
        at += 12 + (size_t)len;
    }
    return CST_OK; /* no IEND: stb fails on its own */
}

/* ---------------------------------------------------------------- declared sizes */

static uint64_t div_up(uint64_t a, uint64_t b) { return (a + b - 1) / b; }

/* TGA as stbi__tga_load reads it: header, image ID, palette (after the bytes it skips),
 * then pixels of 1 or 2 (indices, 15/16-bit) or 1-4 bytes, raw or in RLE packets of at most
 * 128 pixels, each at least a count byte and one pixel. */
static uint64_t precheck_tga_min_bytes(const unsigned char *d, uint64_t w, uint64_t h)
{
    bool indexed = d[1] == 1, rle = d[2] >= 8;
    unsigned bits = d[16], pal_bits = d[7];
    uint64_t start = 18 + (uint64_t)d[0], px_bytes;
    if (indexed) {
        start += le16(d + 3) + (uint64_t)le16(d + 5) * (pal_bits == 15 || pal_bits == 16 ? 2 : pal_bits / 8);
        px_bytes = bits == 8 ? 1 : 2;
    } else {
        px_bytes = (bits + 7) / 8;
    }
    uint64_t pixels = w * h;
    return start + (rle ? div_up(pixels, 128) * (1 + px_bytes) : pixels * px_bytes);
}

/* The least a file declaring w x h pixels can hold in its format (a lower bound). */
static uint64_t precheck_min_bytes(ImageStbFormat f, const unsigned char *d, size_t n, uint64_t w, uint64_t h)
{
    switch (f) {
    case IMAGE_STB_PNG:
        /* Rows of at least 1 bit a pixel after a filter byte, through deflate, which
         * expands at most 1032:1 (a 258-byte match in 2 bits). */
        return div_up(h * (1 + div_up(w, 8)), 1032);
    case IMAGE_STB_JPEG:
        /* Every 8 x 8 block of every component codes its DC difference in at least one bit;
         * a component subsampled at most 4 x 4 has at least ceil(w/32) ceil(h/32) blocks. */
        return div_up(div_up(w, 32) * div_up(h, 32), 8);
    case IMAGE_STB_BMP: {
        /* stb reads only uncompressed BMPs: both headers (14 bytes, then the info header
         * of the size it states), then rows of w pixels of the header's bit depth. */
        uint64_t header = 14 + (uint64_t)le32(d + 14);
        if (header > n) return header; /* the bit depth is not even there */
        unsigned bits = header == 26 ? le16(d + 24) : le16(d + 28);
        return header + h * div_up(w * (bits ? bits : 1), 8);
    }
    case IMAGE_STB_HDR: {
        /* Flat: 4 bytes a pixel. RLE (widths 8 to 32767): a 4-byte scanline header, then for
         * each of 4 channels runs of at most 127 pixels in 2 bytes. */
        uint64_t line = 4 * w;
        if (w >= 8 && w < 32768 && 4 + 8 * div_up(w, 127) < line) line = 4 + 8 * div_up(w, 127);
        return h * line;
    }
    case IMAGE_STB_TGA: return precheck_tga_min_bytes(d, w, h);
    case IMAGE_STB_NONE: break;
    }
    return 0;
}

static const char *precheck_name(ImageStbFormat f)
{
    static const char *const names[] = {"image", "PNG", "JPEG", "BMP", "Radiance HDR", "TGA"};
    return names[f];
}

CstStatus image_precheck_stb(const char *path, const unsigned char *data, size_t size, int *width,
                             int *height, CstError *err)
{
    ImageStbFormat f = image_precheck_format(data, size);
    if (f == IMAGE_STB_NONE) {
        const char *other = precheck_other_format(data, size);
        if (other)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: a %s file; texture images must be %s files",
                            path, other, PRECHECK_FORMATS);
        return cst_fail(err, CST_ERR_PARSE, "%s: not a %s file (unrecognised content)", path,
                        PRECHECK_FORMATS);
    }
    if (size > INT_MAX) /* stb's memory reader takes an int length */
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%s: a %zu-byte %s file; stb_image reads at most %d bytes",
                        path, size, precheck_name(f), INT_MAX);
    if (f == IMAGE_STB_JPEG) { /* before stbi_info, which reads the tables too */
        CstStatus st = precheck_jpeg_tables(path, data, size, err);
        if (st != CST_OK) return st;
    } else if (f == IMAGE_STB_PNG) {
        CstStatus st = precheck_png_chunks(path, data, size, err);
        if (st != CST_OK) return st;
    }
    uint64_t w, h;
    if (f == IMAGE_STB_TGA) { /* read here: stbi_info refuses some headers stbi_load takes */
        w = le16(data + 12);
        h = le16(data + 14);
    } else if (f == IMAGE_STB_JPEG) { /* the decoder's own header reader (io/jpeg.h) */
        int iw = 0, ih = 0;
        CstStatus st = jpeg_info(path, data, size, &iw, &ih, err);
        if (st != CST_OK) return st;
        w = (uint64_t)iw;
        h = (uint64_t)ih;
    } else {
        int iw = 0, ih = 0;
        if (!image_stb_info(data, (int)size, &iw, &ih) || iw <= 0 || ih <= 0)
            return cst_fail(err, CST_ERR_PARSE, "%s: cannot decode the %s header (%s)", path, precheck_name(f),
                            image_stb_failure_reason());
        w = (uint64_t)iw;
        h = (uint64_t)ih;
    }
    if (!image_size_ok(w, h) || w > IMAGE_STB_MAX_SIDE || h > IMAGE_STB_MAX_SIDE)
        return cst_fail(err, CST_ERR_UNSUPPORTED,
                        "%s: the %s declares %llu x %llu pixels; images are limited to %llu pixels "
                        "(16384 x 16384) and %d on a side", path, precheck_name(f), (unsigned long long)w,
                        (unsigned long long)h, (unsigned long long)IMAGE_MAX_PIXELS, IMAGE_STB_MAX_SIDE);
    uint64_t need = precheck_min_bytes(f, data, size, w, h);
    if (need > size)
        return cst_fail(err, CST_ERR_PARSE,
                        "%s: truncated or corrupt %s: %llu x %llu pixels need at least %llu bytes, the file "
                        "has %zu", path, precheck_name(f), (unsigned long long)w, (unsigned long long)h,
                        (unsigned long long)need, size);
    *width = (int)w;
    *height = (int)h;
    return CST_OK;
}
