/* Reproducibility metadata for rendered images (cli/metadata.h): SHA-256 of the scene
 * file, the command line quoted for a POSIX shell, and the settings of the render. */
#define _POSIX_C_SOURCE 200809L

#include "metadata.h"

#include <inttypes.h>
#include <stdbool.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

/* ------------------------------------------------------------ SHA-256 (FIPS 180-4) */

typedef struct Sha256 {
    uint32_t h[8];
    uint8_t block[64];
    size_t used;    /* bytes in block */
    uint64_t bytes; /* message length so far */
} Sha256;

static const uint32_t sha256_k[64] = {
    0x428a2f98, 0x71374491, 0xb5c0fbcf, 0xe9b5dba5, 0x3956c25b, 0x59f111f1, 0x923f82a4, 0xab1c5ed5,
    0xd807aa98, 0x12835b01, 0x243185be, 0x550c7dc3, 0x72be5d74, 0x80deb1fe, 0x9bdc06a7, 0xc19bf174,
    0xe49b69c1, 0xefbe4786, 0x0fc19dc6, 0x240ca1cc, 0x2de92c6f, 0x4a7484aa, 0x5cb0a9dc, 0x76f988da,
    0x983e5152, 0xa831c66d, 0xb00327c8, 0xbf597fc7, 0xc6e00bf3, 0xd5a79147, 0x06ca6351, 0x14292967,
    0x27b70a85, 0x2e1b2138, 0x4d2c6dfc, 0x53380d13, 0x650a7354, 0x766a0abb, 0x81c2c92e, 0x92722c85,
    0xa2bfe8a1, 0xa81a664b, 0xc24b8b70, 0xc76c51a3, 0xd192e819, 0xd6990624, 0xf40e3585, 0x106aa070,
    0x19a4c116, 0x1e376c08, 0x2748774c, 0x34b0bcb5, 0x391c0cb3, 0x4ed8aa4a, 0x5b9cca4f, 0x682e6ff3,
    0x748f82ee, 0x78a5636f, 0x84c87814, 0x8cc70208, 0x90befffa, 0xa4506ceb, 0xbef9a3f7, 0xc67178f2};

static uint32_t sha256_rotr(uint32_t x, int n) { return x >> n | x << (32 - n); }

static void sha256_block(Sha256 *s, const uint8_t *p)
{
    uint32_t w[64], v[8];
    for (int i = 0; i < 16; i++)
        w[i] = (uint32_t)p[4 * i] << 24 | (uint32_t)p[4 * i + 1] << 16 | (uint32_t)p[4 * i + 2] << 8 | p[4 * i + 3];
    for (int i = 16; i < 64; i++) {
        uint32_t s0 = sha256_rotr(w[i - 15], 7) ^ sha256_rotr(w[i - 15], 18) ^ w[i - 15] >> 3;
        uint32_t s1 = sha256_rotr(w[i - 2], 17) ^ sha256_rotr(w[i - 2], 19) ^ w[i - 2] >> 10;
        w[i] = w[i - 16] + s0 + w[i - 7] + s1;
    }
    memcpy(v, s->h, sizeof v);
    for (int i = 0; i < 64; i++) {
        uint32_t e = v[4], a = v[0];
        uint32_t t1 = v[7] + (sha256_rotr(e, 6) ^ sha256_rotr(e, 11) ^ sha256_rotr(e, 25)) +
                      ((e & v[5]) ^ (~e & v[6])) + sha256_k[i] + w[i];
        uint32_t t2 = (sha256_rotr(a, 2) ^ sha256_rotr(a, 13) ^ sha256_rotr(a, 22)) +
                      ((a & v[1]) ^ (a & v[2]) ^ (v[1] & v[2]));
        memmove(v + 1, v, 7 * sizeof v[0]);
        v[4] += t1;
        v[0] = t1 + t2;
    }
    for (int i = 0; i < 8; i++) s->h[i] += v[i];
}

static void sha256_init(Sha256 *s)
{
    static const uint32_t h0[8] = {0x6a09e667, 0xbb67ae85, 0x3c6ef372, 0xa54ff53a,
                                   0x510e527f, 0x9b05688c, 0x1f83d9ab, 0x5be0cd19};
    memcpy(s->h, h0, sizeof h0);
    s->used = 0;
    s->bytes = 0;
}

static void sha256_update(Sha256 *s, const uint8_t *p, size_t n)
{
    s->bytes += n;
    while (n > 0) {
        size_t take = 64 - s->used < n ? 64 - s->used : n;
        memcpy(s->block + s->used, p, take);
        s->used += take;
        p += take;
        n -= take;
        if (s->used == 64) {
            sha256_block(s, s->block);
            s->used = 0;
        }
    }
}

static void sha256_hex(Sha256 *s, char hex[65])
{
    uint64_t bits = s->bytes * 8;
    uint8_t pad[72] = {0x80};
    size_t n = (s->used < 56 ? 56 : 120) - s->used;
    for (int i = 0; i < 8; i++) pad[n + (size_t)i] = (uint8_t)(bits >> (56 - 8 * i));
    sha256_update(s, pad, n + 8);
    for (int i = 0; i < 8; i++) snprintf(hex + 8 * i, 9, "%08" PRIx32, s->h[i]);
}

bool cli_sha256_file(const char *path, char hex[65])
{
    hex[0] = '\0';
    FILE *f = fopen(path, "rb");
    struct stat st;
    if (!f) return false;
    if (fstat(fileno(f), &st) != 0 || !S_ISREG(st.st_mode)) {
        fclose(f);
        return false;
    }
    Sha256 s;
    sha256_init(&s);
    uint8_t buf[65536];
    size_t n;
    while ((n = fread(buf, 1, sizeof buf, f)) > 0) sha256_update(&s, buf, n);
    bool ok = !ferror(f);
    fclose(f);
    if (ok) sha256_hex(&s, hex);
    return ok;
}

/* ------------------------------------------------------------ quoting */

/* Whether s[0..n) is well-formed UTF-8 without control characters: what a value may hold
 * as it is (the library accepts only UTF-8). */
static bool cli_printable_utf8(const unsigned char *s, size_t n)
{
    for (size_t i = 0; i < n;) {
        unsigned c = s[i];
        int more = c < 0x80 ? 0 : (c & 0xe0) == 0xc0 ? 1 : (c & 0xf0) == 0xe0 ? 2 : (c & 0xf8) == 0xf0 ? 3 : -1;
        if (c < 0x20 || c == 0x7f || more < 0 || i + (size_t)more >= n) return false;
        uint32_t cp = c & (0x7fu >> more);
        for (int k = 1; k <= more; k++) {
            if ((s[i + (size_t)k] & 0xc0) != 0x80) return false;
            cp = cp << 6 | (s[i + (size_t)k] & 0x3fu);
        }
        static const uint32_t least[4] = {0, 0x80, 0x800, 0x10000};
        if (cp < least[more] || cp > 0x10ffff || (cp >= 0xd800 && cp <= 0xdfff)) return false;
        i += 1 + (size_t)more;
    }
    return true;
}

/* Appends `arg` (n bytes) quoted so that a POSIX shell (bash for the $'' form) reads it
 * back as the same bytes: as is when it holds only safe characters, in single quotes when
 * it is printable UTF-8, else $'...' with \xNN escapes. `out` has room for 4n + 3. */
static size_t cli_shell_quote(const char *arg, size_t n, char *out)
{
    static const char safe[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789_@%+=:,./-";
    size_t o = 0, plain = 0;
    while (plain < n && arg[plain] && strchr(safe, arg[plain])) plain++;
    if (n > 0 && plain == n) {
        memcpy(out, arg, n);
        return n;
    }
    bool printable = cli_printable_utf8((const unsigned char *)arg, n);
    if (!printable) out[o++] = '$';
    out[o++] = '\'';
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)arg[i];
        if (printable && c == '\'') {
            memcpy(out + o, "'\\''", 4);
            o += 4;
        } else if (!printable && (c < 0x20 || c >= 0x7f || c == '\'' || c == '\\')) {
            o += (size_t)snprintf(out + o, 5, "\\x%02x", c);
        } else {
            out[o++] = (char)c;
        }
    }
    out[o++] = '\'';
    return o;
}

/* The NUL-separated arguments of args[0..len) as one quoted command line; NULL on OOM. */
static char *cli_quote_args(const char *args, size_t len)
{
    char *out = malloc(4 * len + 4);
    if (!out) return NULL;
    size_t o = 0;
    for (size_t i = 0; i < len;) {
        size_t n = strnlen(args + i, len - i);
        if (o) out[o++] = ' ';
        o += cli_shell_quote(args + i, n, out + o);
        i += n + 1;
    }
    out[o] = '\0';
    return out;
}

/* The command line of this process, from /proc/self/cmdline (Linux): the arguments as
 * the kernel received them, quoted. NULL where there is no such file. */
static char *cli_command_line(void)
{
    FILE *f = fopen("/proc/self/cmdline", "rb");
    if (!f) return NULL;
    size_t cap = 4096, len = 0;
    char *buf = malloc(cap);
    for (size_t n; buf && (n = fread(buf + len, 1, cap - len, f)) > 0;) {
        len += n;
        if (len == cap) {
            char *bigger = realloc(buf, cap *= 2);
            if (!bigger) free(buf);
            buf = bigger;
        }
    }
    fclose(f);
    char *quoted = buf && len > 0 ? cli_quote_args(buf, len) : NULL;
    free(buf);
    return quoted;
}

/* ------------------------------------------------------------ the entries */

void cli_metadata_begin(CliMetadata *md, const char *scene_path)
{
    memset(md, 0, sizeof *md);
    md->command = cli_command_line();
    if (scene_path) {
        size_t n = strlen(scene_path);
        md->scene = malloc(4 * n + 4);
        if (md->scene) md->scene[cli_shell_quote(scene_path, n, md->scene)] = '\0';
        cli_sha256_file(scene_path, md->sha256);
    }
}

static void cli_metadata_add(CliMetadata *md, const char *key, const char *value)
{
    if (value && value[0] && md->count < CLI_METADATA_MAX)
        md->entry[md->count++] = (CstImageMetadata){key, value};
}

void cli_metadata_finish(CliMetadata *md, const CstRenderSettings *used, const CstRenderStats *stats)
{
    snprintf(md->seed, sizeof md->seed, "%" PRIu64, used->seed);
    snprintf(md->spp, sizeof md->spp, "%d", stats->spp);
    snprintf(md->seconds, sizeof md->seconds, "%.3f", stats->seconds);
    md->count = 0;
    cli_metadata_add(md, "caustic.version", CST_VERSION_STRING);
    cli_metadata_add(md, "caustic.command", md->command);
    cli_metadata_add(md, "caustic.scene", md->scene ? md->scene : "built-in Cornell box");
    cli_metadata_add(md, "caustic.scene_sha256", md->sha256);
    cli_metadata_add(md, "caustic.integrator", cst_integrator_name(stats->integrator));
    cli_metadata_add(md, "caustic.sampler", cst_sampler_name(used->sampler));
    cli_metadata_add(md, "caustic.color", used->color_mode == CST_COLOR_SPECTRAL ? "spectral" : "rgb");
    cli_metadata_add(md, "caustic.filter", cst_filter_name(stats->filter));
    cli_metadata_add(md, "caustic.seed", md->seed);
    cli_metadata_add(md, "caustic.spp", md->spp);
    cli_metadata_add(md, "caustic.render_seconds", md->seconds);
}

void cli_metadata_free(CliMetadata *md)
{
    free(md->command);
    free(md->scene);
    md->command = md->scene = NULL;
    md->count = 0;
}
