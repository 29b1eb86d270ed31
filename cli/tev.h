/* The tev stream (--display tev[:HOST:PORT] of render and view): a TCP client of the tev
 * image viewer's IPC protocol that sends a linear RGB image tile by tile as it converges. */
#ifndef CST_CLI_TEV_H
#define CST_CLI_TEV_H

#include <stdbool.h>
#include <stddef.h>

#define CLI_TEV_DEFAULT_HOST "127.0.0.1"
#define CLI_TEV_DEFAULT_PORT 14158 /* tev's own default */
#define CLI_TEV_TILE         128   /* tile side in pixels: 192 KiB of floats per packet */

typedef struct CliTev CliTev;

/* Reads a --display value: "tev" (127.0.0.1:14158) or "tev:HOST:PORT" (HOST up to the
 * last colon, so "tev:::1:14158" is IPv6 loopback; PORT 1..65535). False with msg (what
 * was expected) for anything else. */
bool cli_tev_parse(const char *spec, char *host, size_t host_size, int *port, char *msg, size_t msg_size);

/* A stream to tev at host:port for images named `name` (tev's image list shows it; an
 * image of that name already open in tev is replaced). Connects here, with a 2 s limit;
 * when the connection is refused or fails, prints one warning on stderr and returns a
 * stream that sends nothing, so the caller carries on. NULL only on out of memory. The
 * caller owns it: cli_tev_destroy(). */
CliTev *cli_tev_create(const char *host, int port, const char *name);

/* Sends the image (width x height x 3 floats, rows from the top, R, G, B per pixel,
 * linear: tev tone-maps): a create-image packet (channels R, G, B) the first time and
 * whenever the size changes, then one update packet per CLI_TEV_TILE-square tile, rows of
 * tiles from the top. A broken connection prints one warning and ends the stream (every
 * later call returns at once). Returns whether the stream is still up. */
bool cli_tev_send(CliTev *t, const float *rgb, int width, int height);

/* Asks tev to close the image (the close-image packet), e.g. before a new one replaces it
 * under another name. The stream stays usable: the next send creates the image again. */
bool cli_tev_close_image(CliTev *t);

/* Whether the stream is up (connected and not broken). */
bool cli_tev_connected(const CliTev *t);

/* Closes the connection (tev keeps the image). Accepts NULL. */
void cli_tev_destroy(CliTev *t);

#endif
