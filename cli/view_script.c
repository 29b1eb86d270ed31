/* caustic view's script (--script FILE or CAUSTIC_VIEW_SCRIPT): the lines that drive the
 * viewer without a user, for tests under xvfb-run. Parsed whole before the window opens,
 * so a bad line is a located error (FILE:LINE:COL) and exit 2, never a half-run session. */
#include "view_script.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdlib.h>
#include <string.h>

#define SCRIPT_MAX_BYTES (1 << 20)
#define SCRIPT_MAX_LINE  4096

static const struct { const char *name; ViewScriptOp op; int args; } SCRIPT_OPS[] = {
    {"key", VIEW_SCRIPT_KEY, 1},       {"wait-spp", VIEW_SCRIPT_WAIT_SPP, 1},
    {"save", VIEW_SCRIPT_SAVE, 1},     {"orbit", VIEW_SCRIPT_ORBIT, 2},
    {"pan", VIEW_SCRIPT_PAN, 2},       {"dolly", VIEW_SCRIPT_DOLLY, 1},
    {"status", VIEW_SCRIPT_STATUS, 0}, {"quit", VIEW_SCRIPT_QUIT, 0},
    {"click", VIEW_SCRIPT_CLICK, 2},   {"camera", VIEW_SCRIPT_CAMERA, 1},
    {"explain", VIEW_SCRIPT_EXPLAIN, 2},
};
#define SCRIPT_NUM_OPS (sizeof SCRIPT_OPS / sizeof SCRIPT_OPS[0])
#define SCRIPT_OP_NAMES "key, wait-spp, save, orbit, pan, dolly, status, quit, click, camera, explain"

static bool script_fail(char *msg, size_t size, const char *path, int line, int col, const char *fmt, ...)
{
    int n = snprintf(msg, size, "%s:%d:%d: ", path, line, col);
    if (n < 0 || (size_t)n >= size) return false;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg + n, size - (size_t)n, fmt, ap);
    va_end(ap);
    return false;
}

/* The key a token names: one printable character (letters lower-cased), or esc, tab,
 * plus, minus, space. 0 if none. */
static int script_key(const char *tok)
{
    static const struct { const char *name; int key; } NAMED[] = {
        {"esc", VIEW_KEY_ESCAPE}, {"escape", VIEW_KEY_ESCAPE}, {"tab", '\t'},
        {"plus", '+'},            {"minus", '-'},              {"space", ' '},
    };
    for (size_t k = 0; k < sizeof NAMED / sizeof NAMED[0]; k++)
        if (strcmp(tok, NAMED[k].name) == 0) return NAMED[k].key;
    if (tok[0] && !tok[1] && isgraph((unsigned char)tok[0])) return tolower((unsigned char)tok[0]);
    return 0;
}

static bool script_number(const char *tok, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(tok, &end);
    if (end == tok || *end || errno || !isfinite(v)) return false;
    *out = v;
    return true;
}

/* One non-empty line (comments stripped) into *cmd. */
static bool script_parse_line(char *line, const char *path, int lineno, ViewScriptCmd *cmd, char *msg,
                              size_t size)
{
    char *tok[4] = {NULL, NULL, NULL, NULL};
    int col[4] = {0, 0, 0, 0}, n = 0;
    for (char *p = line; *p;) {
        while (*p == ' ' || *p == '\t') p++;
        if (!*p) break;
        if (n == 4) return script_fail(msg, size, path, lineno, (int)(p - line) + 1, "too many words; "
                                       "expected a command and at most two arguments");
        col[n] = (int)(p - line) + 1;
        tok[n++] = p;
        while (*p && *p != ' ' && *p != '\t') p++;
        if (*p) *p++ = '\0';
    }
    size_t k = 0;
    while (k < SCRIPT_NUM_OPS && strcmp(tok[0], SCRIPT_OPS[k].name) != 0) k++;
    if (k == SCRIPT_NUM_OPS)
        return script_fail(msg, size, path, lineno, col[0], "unknown command '%s'; expected one of "
                           SCRIPT_OP_NAMES, tok[0]);
    if (n - 1 != SCRIPT_OPS[k].args)
        return script_fail(msg, size, path, lineno, col[0], "%s takes %d argument%s, got %d", tok[0],
                           SCRIPT_OPS[k].args, SCRIPT_OPS[k].args == 1 ? "" : "s", n - 1);
    memset(cmd, 0, sizeof *cmd);
    cmd->op = SCRIPT_OPS[k].op;
    cmd->line = lineno;
    switch (cmd->op) {
    case VIEW_SCRIPT_KEY:
        if (!(cmd->key = script_key(tok[1])))
            return script_fail(msg, size, path, lineno, col[1], "key '%s': expected one character "
                               "(1-9, p, s, c, q, +, -, [, ]) or esc, tab, plus, minus, space", tok[1]);
        return true;
    case VIEW_SCRIPT_WAIT_SPP:
        if (!script_number(tok[1], &cmd->a) || cmd->a < 1.0 || cmd->a > 1e9 || cmd->a != floor(cmd->a))
            return script_fail(msg, size, path, lineno, col[1], "wait-spp '%s': expected a whole number of "
                               "samples per pixel, 1 to 1e9", tok[1]);
        return true;
    case VIEW_SCRIPT_SAVE:
    case VIEW_SCRIPT_CAMERA:
        if (!(cmd->path = strdup(tok[1])))
            return script_fail(msg, size, path, lineno, col[1], "out of memory");
        return true;
    case VIEW_SCRIPT_ORBIT:
    case VIEW_SCRIPT_PAN:
    case VIEW_SCRIPT_DOLLY:
        for (int i = 1; i < n; i++)
            if (!script_number(tok[i], i == 1 ? &cmd->a : &cmd->b) || fabs(i == 1 ? cmd->a : cmd->b) > 1e6)
                return script_fail(msg, size, path, lineno, col[i], "%s '%s': expected a number of pixels "
                                   "(wheel steps for dolly) within 1e6", tok[0], tok[i]);
        return true;
    case VIEW_SCRIPT_CLICK:
    case VIEW_SCRIPT_EXPLAIN:
        for (int i = 1; i < n; i++)
            if (!script_number(tok[i], i == 1 ? &cmd->a : &cmd->b) || (i == 1 ? cmd->a : cmd->b) < 0.0 ||
                (i == 1 ? cmd->a : cmd->b) > 65536.0 || (i == 1 ? cmd->a : cmd->b) != floor(i == 1 ? cmd->a : cmd->b))
                return script_fail(msg, size, path, lineno, col[i], "%s '%s': expected a pixel coordinate, "
                                   "a whole number from 0 (left or top)", tok[0], tok[i]);
        return true;
    case VIEW_SCRIPT_STATUS:
    case VIEW_SCRIPT_QUIT:
        return true;
    }
    return true;
}

bool view_script_parse(const char *text, size_t len, const char *path, ViewScript *out, char *msg, size_t size)
{
    memset(out, 0, sizeof *out);
    if (len > SCRIPT_MAX_BYTES) return script_fail(msg, size, path, 1, 1, "the script is over %d bytes", SCRIPT_MAX_BYTES);
    char line[SCRIPT_MAX_LINE + 1];
    int lineno = 0;
    bool ok = true;
    for (size_t pos = 0; ok && pos < len;) {
        lineno++;
        size_t end = pos;
        while (end < len && text[end] != '\n') end++;
        size_t n = end - pos;
        if (n > SCRIPT_MAX_LINE) {
            ok = script_fail(msg, size, path, lineno, SCRIPT_MAX_LINE + 1, "line longer than %d bytes",
                             SCRIPT_MAX_LINE);
            break;
        }
        memcpy(line, text + pos, n);
        line[n] = '\0';
        pos = end + 1;
        for (size_t c = 0; c < n && line[c] != '#'; c++)
            if (!isprint((unsigned char)line[c]) && line[c] != '\t' && line[c] != '\r') {
                ok = script_fail(msg, size, path, lineno, (int)c + 1, "byte 0x%02x; expected printable ASCII",
                                 (unsigned)(unsigned char)line[c]);
                break;
            }
        if (!ok) break;
        line[strcspn(line, "#\r")] = '\0';
        char *p = line;
        while (*p == ' ' || *p == '\t') p++;
        if (!*p) continue;
        ViewScriptCmd cmd;
        if (!(ok = script_parse_line(line, path, lineno, &cmd, msg, size))) break;
        if (out->count == out->cap) {
            int cap = out->cap ? 2 * out->cap : 16;
            ViewScriptCmd *c = realloc(out->cmds, (size_t)cap * sizeof *c);
            if (!c) {
                free(cmd.path);
                ok = script_fail(msg, size, path, lineno, 1, "out of memory");
                break;
            }
            out->cmds = c;
            out->cap = cap;
        }
        out->cmds[out->count++] = cmd;
    }
    if (!ok) view_script_free(out);
    return ok;
}

bool view_script_load(const char *path, ViewScript *out, char *msg, size_t size)
{
    memset(out, 0, sizeof *out);
    FILE *f = fopen(path, "rb");
    if (!f) {
        snprintf(msg, size, "%s: cannot open the script: %s", path, strerror(errno));
        return false;
    }
    char *text = malloc(SCRIPT_MAX_BYTES + 1);
    size_t len = text ? fread(text, 1, SCRIPT_MAX_BYTES + 1, f) : 0;
    bool ok = text && !ferror(f);
    if (!ok) snprintf(msg, size, "%s: reading the script: %s", path, text ? strerror(errno) : "out of memory");
    fclose(f);
    if (ok) ok = view_script_parse(text, len, path, out, msg, size);
    free(text);
    return ok;
}

void view_script_free(ViewScript *s)
{
    for (int i = 0; i < s->count; i++) free(s->cmds[i].path);
    free(s->cmds);
    memset(s, 0, sizeof *s);
}
