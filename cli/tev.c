/* The tev stream: tev's IPC protocol over one TCP connection (POSIX sockets), write only.
 * The protocol as tev's sources define it (Tom94/tev, src/Ipc.cpp and src/python/ipc.py):
 * every packet is a little-endian uint32 length (of the whole packet, these 4 bytes
 * included), a type byte, then the type's fields; strings are UTF-8 ending in a NUL byte;
 * int32/int64 little-endian; pixel data little-endian IEEE float32. Types used here:
 *   2 close image:      name
 *   4 create image:     grab_focus (1 byte), name, int32 width, height, channel count,
 *                       channel names
 *   6 update image v3:  grab_focus, name, int32 channel count, channel names, int32 x, y,
 *                       width, height of the tile, int64 offset[count], int64 stride[count],
 *                       floats: channel c of tile pixel i (row-major) at offset[c] + i * stride[c]
 * tev sends nothing back. */
#include "tev.h"

#include <errno.h>
#include <fcntl.h>
#include <netdb.h>
#include <poll.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#define TEV_CONNECT_MS 2000 /* a host that does not answer: give up after this */
#define TEV_SEND_S     10   /* a tev that stops reading: the connection counts as broken */
#define TEV_NAME_MAX   1024

enum { TEV_CLOSE_IMAGE = 2, TEV_CREATE_IMAGE = 4, TEV_UPDATE_IMAGE_V3 = 6 };

static const char *const TEV_CHANNELS[3] = {"R", "G", "B"};

struct CliTev {
    int fd;                 /* -1: not connected, or broken (warned) */
    char where[300];        /* "HOST:PORT", for messages */
    char name[TEV_NAME_MAX];
    int width, height;      /* of the image created in tev; 0 = none yet */
    unsigned char *buf;     /* one packet; sized for the largest tile at creation */
    size_t len, cap;
};

/* ------------------------------------------------------------ --display */

bool cli_tev_parse(const char *spec, char *host, size_t host_size, int *port, char *msg, size_t msg_size)
{
    if (strcmp(spec, "tev") == 0) {
        snprintf(host, host_size, "%s", CLI_TEV_DEFAULT_HOST);
        *port = CLI_TEV_DEFAULT_PORT;
        return true;
    }
    const char *rest = strncmp(spec, "tev:", 4) == 0 ? spec + 4 : NULL;
    const char *colon = rest ? strrchr(rest, ':') : NULL;
    if (!rest || !colon || colon == rest || (size_t)(colon - rest) >= host_size) {
        snprintf(msg, msg_size, "--display: expected tev or tev:HOST:PORT (tev's default: tev:%s:%d), got '%s'",
                 CLI_TEV_DEFAULT_HOST, CLI_TEV_DEFAULT_PORT, spec);
        return false;
    }
    char *end;
    errno = 0;
    long p = colon[1] >= '0' && colon[1] <= '9' ? strtol(colon + 1, &end, 10) : -1;
    if (p < 1 || p > 65535 || *end || errno) {
        snprintf(msg, msg_size, "--display: '%s': expected a port from 1 to 65535 after the last ':', got '%s'",
                 spec, colon + 1);
        return false;
    }
    snprintf(host, host_size, "%.*s", (int)(colon - rest), rest);
    *port = (int)p;
    return true;
}

/* ------------------------------------------------------------ the connection */

/* Connects fd-by-fd through getaddrinfo's answers, each with a TEV_CONNECT_MS limit
 * (a non-blocking connect and poll); -1 with errno's reason in why. */
static int tev_connect(const char *host, int port, char *why, size_t why_size)
{
    char service[16];
    snprintf(service, sizeof service, "%d", port);
    struct addrinfo hints = {0}, *res = NULL;
    hints.ai_family = AF_UNSPEC;
    hints.ai_socktype = SOCK_STREAM;
    int gai = getaddrinfo(host, service, &hints, &res);
    if (gai != 0) {
        snprintf(why, why_size, "cannot resolve the host: %s", gai_strerror(gai));
        return -1;
    }
    int fd = -1, e = ECONNREFUSED;
    for (struct addrinfo *ai = res; ai && fd < 0; ai = ai->ai_next) {
        fd = socket(ai->ai_family, ai->ai_socktype | SOCK_CLOEXEC, ai->ai_protocol);
        if (fd < 0) { e = errno; continue; }
        int flags = fcntl(fd, F_GETFL, 0);
        fcntl(fd, F_SETFL, flags | O_NONBLOCK);
        int rc = connect(fd, ai->ai_addr, ai->ai_addrlen);
        if (rc != 0 && errno == EINPROGRESS) {
            struct pollfd pfd = {fd, POLLOUT, 0};
            int ready;
            do ready = poll(&pfd, 1, TEV_CONNECT_MS); while (ready < 0 && errno == EINTR);
            socklen_t elen = sizeof e;
            if (ready == 1 && getsockopt(fd, SOL_SOCKET, SO_ERROR, &e, &elen) == 0 && e == 0) rc = 0;
            else if (ready == 0) e = ETIMEDOUT;
        } else if (rc != 0) {
            e = errno;
        }
        if (rc != 0) {
            close(fd);
            fd = -1;
            continue;
        }
        fcntl(fd, F_SETFL, flags); /* blocking again, with a send time limit */
        struct timeval tv = {TEV_SEND_S, 0};
        setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
    }
    freeaddrinfo(res);
    if (fd < 0) snprintf(why, why_size, "cannot connect: %s", strerror(e));
    return fd;
}

/* The one warning of a failed or broken stream; the stream sends nothing afterwards. */
static void tev_break(CliTev *t, const char *what, bool connecting)
{
    fprintf(stderr, "caustic: warning: --display tev:%s: %s; going on without the display%s\n", t->where, what,
            connecting ? " (is tev running there? start it with: tev --hostname HOST:PORT)" : "");
    if (t->fd >= 0) close(t->fd);
    t->fd = -1;
}

CliTev *cli_tev_create(const char *host, int port, const char *name)
{
    CliTev *t = calloc(1, sizeof *t);
    if (!t) return NULL;
    /* The largest packet: an update of a whole tile, its header included (the name and the
     * channel names are bounded; 1 KiB is the slack for the header's fixed fields). */
    t->cap = (size_t)CLI_TEV_TILE * CLI_TEV_TILE * 3 * sizeof(float) + TEV_NAME_MAX + 1024;
    t->buf = malloc(t->cap);
    if (!t->buf) {
        free(t);
        return NULL;
    }
    snprintf(t->name, sizeof t->name, "%s", name);
    snprintf(t->where, sizeof t->where, strchr(host, ':') ? "[%s]:%d" : "%s:%d", host, port);
    char why[256];
    t->fd = tev_connect(host, port, why, sizeof why);
    if (t->fd < 0) tev_break(t, why, true);
    return t;
}

bool cli_tev_connected(const CliTev *t) { return t && t->fd >= 0; }

void cli_tev_destroy(CliTev *t)
{
    if (!t) return;
    if (t->fd >= 0) close(t->fd);
    free(t->buf);
    free(t);
}

/* ------------------------------------------------------------ packets */

static void put_u8(CliTev *t, unsigned v) { t->buf[t->len++] = (unsigned char)v; }

static void put_u32(CliTev *t, uint32_t v)
{
    for (int k = 0; k < 4; k++) t->buf[t->len++] = (unsigned char)(v >> (8 * k));
}

static void put_i32(CliTev *t, int32_t v) { put_u32(t, (uint32_t)v); }

static void put_i64(CliTev *t, int64_t v)
{
    uint64_t u = (uint64_t)v;
    for (int k = 0; k < 8; k++) t->buf[t->len++] = (unsigned char)(u >> (8 * k));
}

static void put_str(CliTev *t, const char *s)
{
    size_t n = strlen(s) + 1;
    memcpy(t->buf + t->len, s, n);
    t->len += n;
}

static void put_f32(CliTev *t, float f)
{
    uint32_t u;
    memcpy(&u, &f, sizeof u); /* IEEE binary32 bits, written little-endian whatever the host */
    put_u32(t, u);
}

/* Starts a packet: the length, patched by tev_flush, then the type. */
static void tev_begin(CliTev *t, int type)
{
    t->len = 0;
    put_u32(t, 0);
    put_u8(t, (unsigned)type);
}

/* Patches the length in and sends the packet whole. */
static bool tev_flush(CliTev *t)
{
    uint32_t n = (uint32_t)t->len;
    for (int k = 0; k < 4; k++) t->buf[k] = (unsigned char)(n >> (8 * k));
    for (size_t sent = 0; sent < t->len;) {
        ssize_t r = send(t->fd, t->buf + sent, t->len - sent, MSG_NOSIGNAL);
        if (r < 0 && errno == EINTR) continue;
        if (r <= 0) {
            char why[160];
            snprintf(why, sizeof why, "the connection broke: %s",
                     r < 0 && (errno == EAGAIN || errno == EWOULDBLOCK) ? "tev stopped reading for 10 s"
                                                                        : strerror(r < 0 ? errno : EPIPE));
            tev_break(t, why, false);
            return false;
        }
        sent += (size_t)r;
    }
    return true;
}

static bool tev_create_image(CliTev *t, int width, int height)
{
    tev_begin(t, TEV_CREATE_IMAGE);
    put_u8(t, 1); /* grab focus: the image being rendered comes to the front */
    put_str(t, t->name);
    put_i32(t, width);
    put_i32(t, height);
    put_i32(t, 3);
    for (int c = 0; c < 3; c++) put_str(t, TEV_CHANNELS[c]);
    if (!tev_flush(t)) return false;
    t->width = width;
    t->height = height;
    return true;
}

/* One tile: x0, y0 its top-left pixel, w x h its size; channels interleaved (offset c,
 * stride 3), as the image holds them. */
static bool tev_update_tile(CliTev *t, const float *rgb, int x0, int y0, int w, int h)
{
    tev_begin(t, TEV_UPDATE_IMAGE_V3);
    put_u8(t, 0); /* no grab focus: the user may have moved to another image */
    put_str(t, t->name);
    put_i32(t, 3);
    for (int c = 0; c < 3; c++) put_str(t, TEV_CHANNELS[c]);
    put_i32(t, x0);
    put_i32(t, y0);
    put_i32(t, w);
    put_i32(t, h);
    for (int c = 0; c < 3; c++) put_i64(t, c);
    for (int c = 0; c < 3; c++) put_i64(t, 3);
    for (int y = y0; y < y0 + h; y++) {
        const float *row = rgb + 3 * ((size_t)y * (size_t)t->width + (size_t)x0);
        for (int k = 0; k < 3 * w; k++) put_f32(t, row[k]);
    }
    return tev_flush(t);
}

bool cli_tev_send(CliTev *t, const float *rgb, int width, int height)
{
    if (!cli_tev_connected(t) || width <= 0 || height <= 0) return false;
    if ((width != t->width || height != t->height) && !tev_create_image(t, width, height)) return false;
    for (int y = 0; y < height; y += CLI_TEV_TILE)
        for (int x = 0; x < width; x += CLI_TEV_TILE) {
            int w = width - x < CLI_TEV_TILE ? width - x : CLI_TEV_TILE;
            int h = height - y < CLI_TEV_TILE ? height - y : CLI_TEV_TILE;
            if (!tev_update_tile(t, rgb, x, y, w, h)) return false;
        }
    return true;
}

bool cli_tev_close_image(CliTev *t)
{
    if (!cli_tev_connected(t)) return false;
    tev_begin(t, TEV_CLOSE_IMAGE);
    put_str(t, t->name);
    if (!tev_flush(t)) return false;
    t->width = t->height = 0;
    return true;
}
