/* A minimal tev (IPC protocol) server for tests/cli/tev_tests.sh: listens on loopback,
 * receives one connection's packets (create, update v3, close image), checks every size
 * and offset against the packet and the image, reassembles the image, and at the end of
 * the stream compares it bit for bit (as float) with the EXR the render wrote.
 *   tev_server PORTFILE EXPECTED.exr [--drop-after N]
 * PORTFILE receives the port (written when listening); --drop-after N closes the
 * connection after N packets (a tev that goes away mid-render). Exit 0: the stream was
 * valid and (without --drop-after) equal to EXPECTED; 1: not equal; 3: a protocol error;
 * 2: usage or setup. */
#include <errno.h>
#include <netinet/in.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <unistd.h>

#include "caustic/caustic.h"

#define MAX_PACKET   (64u << 20) /* bytes: far above a 128 x 128 x 4-channel tile */
#define MAX_STRING   1024
#define MAX_CHANNELS 16
#define MAX_SIDE     65536
#define ACCEPT_MS    120000

typedef struct Image {
    char name[MAX_STRING];
    int width, height, nch;
    char ch[MAX_CHANNELS][MAX_STRING];
    float *px; /* width * height * nch, channel innermost */
    int open;
} Image;

typedef struct Counts {
    long creates, updates, closes, packets;
    long long pixels_updated; /* tile pixels over all updates */
    long long bytes;
} Counts;

/* A cursor over one packet's payload; every read checks what is left. */
typedef struct Cursor {
    const unsigned char *p;
    size_t left;
} Cursor;

static int protocol_error(const char *what)
{
    fprintf(stderr, "tev_server: protocol error: %s\n", what);
    return 3;
}

static int rd_u8(Cursor *c, unsigned *v)
{
    if (c->left < 1) return 0;
    *v = c->p[0];
    c->p++, c->left--;
    return 1;
}

static int rd_u32(Cursor *c, uint32_t *v)
{
    if (c->left < 4) return 0;
    *v = (uint32_t)c->p[0] | (uint32_t)c->p[1] << 8 | (uint32_t)c->p[2] << 16 | (uint32_t)c->p[3] << 24;
    c->p += 4, c->left -= 4;
    return 1;
}

static int rd_i32(Cursor *c, int32_t *v)
{
    uint32_t u;
    if (!rd_u32(c, &u)) return 0;
    *v = (int32_t)u;
    return 1;
}

static int rd_i64(Cursor *c, int64_t *v)
{
    uint32_t lo, hi;
    if (!rd_u32(c, &lo) || !rd_u32(c, &hi)) return 0;
    *v = (int64_t)((uint64_t)hi << 32 | lo);
    return 1;
}

/* A NUL-terminated string inside the packet, shorter than MAX_STRING. */
static int rd_str(Cursor *c, char *out)
{
    const unsigned char *nul = memchr(c->p, 0, c->left);
    if (!nul || (size_t)(nul - c->p) >= MAX_STRING) return 0;
    size_t n = (size_t)(nul - c->p) + 1;
    memcpy(out, c->p, n);
    c->p += n, c->left -= n;
    return 1;
}

static float rd_f32_at(const unsigned char *p)
{
    uint32_t u = (uint32_t)p[0] | (uint32_t)p[1] << 8 | (uint32_t)p[2] << 16 | (uint32_t)p[3] << 24;
    float f;
    memcpy(&f, &u, sizeof f);
    return f;
}

static int on_create(Cursor *c, Image *img, Counts *n)
{
    unsigned focus;
    int32_t w, h, nch;
    char name[MAX_STRING];
    if (!rd_u8(c, &focus) || !rd_str(c, name) || !rd_i32(c, &w) || !rd_i32(c, &h) || !rd_i32(c, &nch))
        return protocol_error("create image: the packet ends inside its header");
    if (w < 1 || h < 1 || w > MAX_SIDE || h > MAX_SIDE || (int64_t)w * h > (1 << 26))
        return protocol_error("create image: width or height out of range");
    if (nch < 1 || nch > MAX_CHANNELS) return protocol_error("create image: channel count out of range");
    free(img->px);
    memset(img, 0, sizeof *img);
    for (int k = 0; k < nch; k++)
        if (!rd_str(c, img->ch[k])) return protocol_error("create image: a channel name runs past the packet");
    if (c->left) return protocol_error("create image: bytes after the channel names");
    img->px = calloc((size_t)w * (size_t)h * (size_t)nch, sizeof *img->px);
    if (!img->px) return protocol_error("create image: out of memory");
    memcpy(img->name, name, sizeof name);
    img->width = w, img->height = h, img->nch = nch, img->open = 1;
    n->creates++;
    return 0;
}

static int on_update(Cursor *c, Image *img, Counts *n)
{
    unsigned focus;
    int32_t nch, x, y, w, h;
    char name[MAX_STRING], ch[MAX_CHANNELS][MAX_STRING];
    int64_t off[MAX_CHANNELS], stride[MAX_CHANNELS];
    int map[MAX_CHANNELS];
    if (!rd_u8(c, &focus) || !rd_str(c, name) || !rd_i32(c, &nch))
        return protocol_error("update image: the packet ends inside its header");
    if (!img->open || strcmp(name, img->name) != 0) return protocol_error("update image: no image of that name");
    if (nch < 1 || nch > MAX_CHANNELS) return protocol_error("update image: channel count out of range");
    for (int k = 0; k < nch; k++) {
        if (!rd_str(c, ch[k])) return protocol_error("update image: a channel name runs past the packet");
        map[k] = -1;
        for (int j = 0; j < img->nch; j++)
            if (strcmp(ch[k], img->ch[j]) == 0) map[k] = j;
        if (map[k] < 0) return protocol_error("update image: a channel the image does not have");
    }
    if (!rd_i32(c, &x) || !rd_i32(c, &y) || !rd_i32(c, &w) || !rd_i32(c, &h))
        return protocol_error("update image: the packet ends inside the tile's rectangle");
    if (x < 0 || y < 0 || w < 1 || h < 1 || (int64_t)x + w > img->width || (int64_t)y + h > img->height)
        return protocol_error("update image: the tile is not inside the image");
    for (int k = 0; k < nch; k++)
        if (!rd_i64(c, &off[k])) return protocol_error("update image: the packet ends inside the offsets");
    for (int k = 0; k < nch; k++)
        if (!rd_i64(c, &stride[k])) return protocol_error("update image: the packet ends inside the strides");
    if (c->left % 4) return protocol_error("update image: pixel data not a whole number of floats");
    const int64_t floats = (int64_t)(c->left / 4), count = (int64_t)w * h;
    for (int k = 0; k < nch; k++)
        if (off[k] < 0 || stride[k] < 0 || off[k] >= floats || (floats - 1 - off[k]) / (stride[k] ? stride[k] : 1) < count - 1 ||
            (stride[k] == 0 && count > 1))
            return protocol_error("update image: a channel's offset and stride reach past the pixel data");
    for (int k = 0; k < nch; k++)
        for (int64_t i = 0; i < count; i++) {
            int64_t px = x + i % w, py = y + i / w;
            img->px[((size_t)py * (size_t)img->width + (size_t)px) * (size_t)img->nch + (size_t)map[k]] =
                rd_f32_at(c->p + 4 * (off[k] + i * stride[k]));
        }
    n->updates++;
    n->pixels_updated += count;
    return 0;
}

static int on_close(Cursor *c, Image *img, Counts *n)
{
    char name[MAX_STRING];
    if (!rd_str(c, name) || c->left) return protocol_error("close image: expected exactly a name");
    if (img->open && strcmp(name, img->name) == 0) img->open = 0;
    n->closes++;
    return 0;
}

/* Reads exactly n bytes; 1, 0 at a clean end of stream before any byte, -1 on error. */
static int read_all(int fd, unsigned char *buf, size_t n)
{
    size_t got = 0;
    while (got < n) {
        ssize_t r = read(fd, buf + got, n - got);
        if (r < 0 && errno == EINTR) continue;
        if (r < 0) return -1;
        if (r == 0) return got == 0 ? 0 : -1;
        got += (size_t)r;
    }
    return 1;
}

/* The bit-for-bit comparison of channels R, G, B with the EXR. */
static int compare(const Image *img, const char *path)
{
    float *rgb = NULL;
    int w = 0, h = 0;
    CstError err = {0};
    if (cst_image_read(path, &rgb, &w, &h, &err) != CST_OK) {
        fprintf(stderr, "tev_server: cannot read %s: %s\n", path, err.msg);
        return 1;
    }
    int idx[3] = {-1, -1, -1}, status = 0;
    const char *names[3] = {"R", "G", "B"};
    for (int c = 0; c < 3; c++)
        for (int j = 0; j < img->nch; j++)
            if (strcmp(img->ch[j], names[c]) == 0) idx[c] = j;
    if (w != img->width || h != img->height || idx[0] < 0 || idx[1] < 0 || idx[2] < 0) {
        fprintf(stderr, "tev_server: %s is %dx%d; the stream's image is %dx%d with %d channels\n", path, w, h,
                img->width, img->height, img->nch);
        status = 1;
    }
    long differ = 0;
    for (long i = 0; status == 0 && i < (long)w * h; i++)
        for (int c = 0; c < 3; c++) {
            uint32_t a, b;
            memcpy(&a, &img->px[(size_t)i * (size_t)img->nch + (size_t)idx[c]], 4);
            memcpy(&b, &rgb[3 * (size_t)i + (size_t)c], 4);
            if (a != b && differ++ < 3)
                fprintf(stderr, "tev_server: pixel (%ld, %ld) channel %s: stream %.9g, EXR %.9g\n", i % w, i / w,
                        names[c], (double)img->px[(size_t)i * (size_t)img->nch + (size_t)idx[c]],
                        (double)rgb[3 * (size_t)i + (size_t)c]);
        }
    if (differ) status = 1;
    if (status == 0) printf("tev_server: equal bit for bit to %s\n", path);
    else if (differ) fprintf(stderr, "tev_server: %ld values differ from %s\n", differ, path);
    free(rgb);
    return status;
}

int main(int argc, char **argv)
{
    long drop_after = -1;
    if (argc == 5 && strcmp(argv[3], "--drop-after") == 0) drop_after = atol(argv[4]);
    else if (argc != 3) {
        fprintf(stderr, "usage: tev_server PORTFILE EXPECTED.exr [--drop-after N]\n");
        return 2;
    }
    int ls = socket(AF_INET, SOCK_STREAM, 0);
    struct sockaddr_in addr = {0};
    addr.sin_family = AF_INET;
    addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    addr.sin_port = 0; /* any free port: tests run in parallel */
    socklen_t alen = sizeof addr;
    if (ls < 0 || bind(ls, (struct sockaddr *)&addr, sizeof addr) != 0 || listen(ls, 1) != 0 ||
        getsockname(ls, (struct sockaddr *)&addr, &alen) != 0) {
        perror("tev_server: listen");
        return 2;
    }
    char tmp[4096];
    snprintf(tmp, sizeof tmp, "%s.tmp", argv[1]);
    FILE *pf = fopen(tmp, "w");
    if (!pf || fprintf(pf, "%d\n", ntohs(addr.sin_port)) < 0 || fclose(pf) != 0 || rename(tmp, argv[1]) != 0) {
        perror("tev_server: the port file");
        return 2;
    }
    struct pollfd pfd = {ls, POLLIN, 0};
    if (poll(&pfd, 1, ACCEPT_MS) != 1) {
        fprintf(stderr, "tev_server: nobody connected in %d s\n", ACCEPT_MS / 1000);
        return 2;
    }
    int fd = accept(ls, NULL, NULL);
    close(ls);
    if (fd < 0) {
        perror("tev_server: accept");
        return 2;
    }
    Image img = {0};
    Counts n = {0};
    unsigned char *buf = malloc(MAX_PACKET);
    int status = buf ? 0 : 2;
    while (status == 0) {
        unsigned char head[4];
        int r = read_all(fd, head, 4);
        if (r == 0) break; /* the end of the stream */
        if (r < 0) { status = protocol_error("the stream ends inside a packet's length"); break; }
        Cursor c = {head, 4};
        uint32_t len;
        rd_u32(&c, &len);
        if (len < 5 || len > MAX_PACKET) { status = protocol_error("packet length out of range"); break; }
        if (read_all(fd, buf, len - 4) != 1) { status = protocol_error("the stream ends inside a packet"); break; }
        n.packets++;
        n.bytes += len;
        c = (Cursor){buf + 1, len - 5};
        switch (buf[0]) {
        case 4: status = on_create(&c, &img, &n); break;
        case 6: status = on_update(&c, &img, &n); break;
        case 2: status = on_close(&c, &img, &n); break;
        default: status = protocol_error("a packet type this server does not expect"); break;
        }
        if (drop_after >= 0 && n.packets >= drop_after) break;
    }
    close(fd);
    free(buf);
    int tiles_per_image = img.open ? ((img.width + 127) / 128) * ((img.height + 127) / 128) : 0;
    printf("tev_server: image '%s' %dx%d, %d channels: %ld packets, %ld create, %ld update, %ld close, "
           "%lld bytes, %.2f images' worth of pixels (%d tiles each)\n", img.name, img.width, img.height, img.nch,
           n.packets, n.creates, n.updates, n.closes, n.bytes,
           img.open ? (double)n.pixels_updated / ((double)img.width * img.height) : 0.0, tiles_per_image);
    if (status == 0 && drop_after < 0) status = img.open ? compare(&img, argv[2]) : protocol_error("no image");
    free(img.px);
    return status;
}
