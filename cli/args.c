/* Command-line parsing for the caustic tool: the option tables and strict number parsing
 * (whole string consumed, range checked); the help texts are in help.c. */
#include "args.h"
#include "tev.h"

#include <ctype.h>
#include <errno.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

typedef enum ArgsOpt {
    ARGS_OPT_OUTPUT, ARGS_OPT_SPP, ARGS_OPT_TIME, ARGS_OPT_THREADS, ARGS_OPT_SEED,
    ARGS_OPT_INTEGRATOR, ARGS_OPT_FILTER, ARGS_OPT_WIDTH, ARGS_OPT_HEIGHT,
    ARGS_OPT_QUIET, ARGS_OPT_HELP, ARGS_OPT_ACCEL, ARGS_OPT_SAMPLER, ARGS_OPT_EXPOSURE,
    ARGS_OPT_PNG_LINEAR, ARGS_OPT_AOV, ARGS_OPT_CROP, ARGS_OPT_MAX_DEPTH, ARGS_OPT_JSON,
    ARGS_OPT_FORCE, ARGS_OPT_SPECTRAL, ARGS_OPT_RGB, ARGS_OPT_LIGHT_SAMPLER, ARGS_OPT_LIGHT_SAMPLING,
    ARGS_OPT_CHECKPOINT, ARGS_OPT_CHECKPOINT_EVERY, ARGS_OPT_RESUME, ARGS_OPT_SCRIPT,
    ARGS_OPT_DISPLAY,
    ARGS_OPT_FIRST_SAMPLE, ARGS_OPT_SAMPLE_BLOCK, ARGS_OPT_PIXEL, ARGS_OPT_SAMPLE, ARGS_OPT_NOISE,
    ARGS_OPT_WHY_DARK, ARGS_OPT_WHY_BRIGHT, ARGS_OPT_SUBSURFACE
} ArgsOpt;

/* How an option takes its value. */
typedef enum ArgsValueKind {
    ARGS_FLAG,          /* none: --name, -x */
    ARGS_VALUE,         /* required: --name VALUE, --name=VALUE, -x VALUE, -xVALUE */
    ARGS_OPTIONAL_VALUE /* only as --name=VALUE (--json=FILE) */
} ArgsValueKind;

/* One option of one command's table (render, bench rays, verify, compare share the type
 * and args_read_option). */
typedef struct ArgsOptSpec {
    const char *long_name; /* without the leading "--" */
    char short_name;       /* 0 = none */
    ArgsValueKind value;
    int id;                /* an ArgsOpt in render's table; the others dispatch by name */
} ArgsOptSpec;

static const ArgsOptSpec ARGS_OPTS[] = {
    {"output",     'o', ARGS_VALUE,  ARGS_OPT_OUTPUT},
    {"spp",        0,   ARGS_VALUE,  ARGS_OPT_SPP},
    {"time",       0,   ARGS_VALUE,  ARGS_OPT_TIME},
    {"threads",    0,   ARGS_VALUE,  ARGS_OPT_THREADS},
    {"seed",       0,   ARGS_VALUE,  ARGS_OPT_SEED},
    {"integrator", 0,   ARGS_VALUE,  ARGS_OPT_INTEGRATOR},
    {"filter",     0,   ARGS_VALUE,  ARGS_OPT_FILTER},
    {"width",      0,   ARGS_VALUE,  ARGS_OPT_WIDTH},
    {"height",     0,   ARGS_VALUE,  ARGS_OPT_HEIGHT},
    {"accel",      0,   ARGS_VALUE,  ARGS_OPT_ACCEL},
    {"sampler",    0,   ARGS_VALUE,  ARGS_OPT_SAMPLER},
    {"light-sampler", 0, ARGS_VALUE, ARGS_OPT_LIGHT_SAMPLER},
    {"light-sampling", 0, ARGS_VALUE, ARGS_OPT_LIGHT_SAMPLING},
    {"exposure",   0,   ARGS_VALUE,  ARGS_OPT_EXPOSURE},
    {"png-linear", 0,   ARGS_FLAG,  ARGS_OPT_PNG_LINEAR},
    {"spectral",   0,   ARGS_FLAG,  ARGS_OPT_SPECTRAL},
    {"rgb",        0,   ARGS_FLAG,  ARGS_OPT_RGB},
    {"aov",        0,   ARGS_VALUE,  ARGS_OPT_AOV},
    {"crop",       0,   ARGS_VALUE,  ARGS_OPT_CROP},
    {"max-depth",  0,   ARGS_VALUE,  ARGS_OPT_MAX_DEPTH},
    {"subsurface", 0,   ARGS_VALUE,  ARGS_OPT_SUBSURFACE},
    {"json",       0,   ARGS_OPTIONAL_VALUE, ARGS_OPT_JSON},  /* --json or --json=FILE */
    {"force",      0,   ARGS_FLAG,  ARGS_OPT_FORCE},
    {"checkpoint", 0,   ARGS_VALUE, ARGS_OPT_CHECKPOINT},
    {"checkpoint-every", 0, ARGS_VALUE, ARGS_OPT_CHECKPOINT_EVERY},
    {"resume",     0,   ARGS_VALUE, ARGS_OPT_RESUME},
    {"first-sample", 0, ARGS_VALUE, ARGS_OPT_FIRST_SAMPLE},
    {"sample-block", 0, ARGS_VALUE, ARGS_OPT_SAMPLE_BLOCK},
    {"noise",      0,   ARGS_VALUE, ARGS_OPT_NOISE},
    {"quiet",      'q', ARGS_FLAG,  ARGS_OPT_QUIET},
    {"help",       'h', ARGS_FLAG,  ARGS_OPT_HELP},
    {"script",     0,   ARGS_VALUE,  ARGS_OPT_SCRIPT}, /* view only */
    {"display",    0,   ARGS_VALUE,  ARGS_OPT_DISPLAY}, /* render and view */
    {"pixel",      0,   ARGS_VALUE,  ARGS_OPT_PIXEL},   /* explain only */
    {"sample",     0,   ARGS_VALUE,  ARGS_OPT_SAMPLE},  /* explain only */
    {"why-dark",   0,   ARGS_FLAG,   ARGS_OPT_WHY_DARK},   /* explain only */
    {"why-bright", 0,   ARGS_FLAG,   ARGS_OPT_WHY_BRIGHT}, /* explain only */
};
#define ARGS_NUM_OPTS (sizeof ARGS_OPTS / sizeof ARGS_OPTS[0])


static void args_fail(ArgsError *err, bool hint, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static void args_fail(ArgsError *err, bool hint, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->hint = hint;
}

/* ------------------------------------------------------------ number parsing
 * strtol and friends skip leading white space and accept a sign; we want neither
 * surprise, so each parser first checks the leading character, then requires the
 * whole string to be consumed without ERANGE. */

static bool args_parse_long(const char *s, long lo, long hi, long *out)
{
    if (!(isdigit((unsigned char)s[0]) || s[0] == '+' || s[0] == '-'))
        return false;
    char *end;
    errno = 0;
    long v = strtol(s, &end, 10);
    if (end == s || *end != '\0' || errno == ERANGE || v < lo || v > hi)
        return false;
    *out = v;
    return true;
}

/* Decimal or 0x-hexadecimal; no sign (strtoull would silently wrap "-1"). */
static bool args_parse_u64(const char *s, uint64_t *out)
{
    int base = 10;
    if (s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
        base = 16;
        s += 2;
    }
    if (!(base == 16 ? isxdigit((unsigned char)s[0]) : isdigit((unsigned char)s[0])))
        return false;
    char *end;
    errno = 0;
    unsigned long long v = strtoull(s, &end, base);
    if (*end != '\0' || errno == ERANGE || v > UINT64_MAX)
        return false;
    *out = (uint64_t)v;
    return true;
}

/* A finite number > 0; rejects "inf", "nan", signs other than '+', and overflow. */
static bool args_parse_seconds(const char *s, double *out)
{
    if (!(isdigit((unsigned char)s[0]) || s[0] == '.' || s[0] == '+'))
        return false;
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !isfinite(v) || !(v > 0.0))
        return false;
    *out = v;
    return true;
}

/* A finite number of stops in [-ARGS_MAX_EXPOSURE, ARGS_MAX_EXPOSURE]. */
static bool args_parse_exposure(const char *s, double *out)
{
    char *end;
    errno = 0;
    double v = strtod(s, &end);
    if (end == s || *end != '\0' || errno == ERANGE || !(v >= -ARGS_MAX_EXPOSURE && v <= ARGS_MAX_EXPOSURE))
        return false;
    *out = v;
    return true;
}

/* "albedo,normal,..." to CST_AOV_* bits; false (and the bad name in *bad) on an unknown one. */
static bool args_parse_aovs(const char *s, int *out, char *bad, size_t bad_len)
{
    int bits = 0;
    while (*s) {
        const char *comma = strchr(s, ',');
        size_t n = comma ? (size_t)(comma - s) : strlen(s);
        char name[32];
        snprintf(bad, bad_len, "%.*s", (int)n, s);
        if (n == 0 || n >= sizeof name) return false;
        memcpy(name, s, n);
        name[n] = '\0';
        int bit = cst_aov_from_name(name);
        if (!bit) return false;
        bits |= bit;
        s += n + (comma ? 1 : 0);
        if (comma && !*s) { bad[0] = '\0'; return false; }
    }
    if (!bits) { bad[0] = '\0'; return false; }
    *out = bits;
    return true;
}

/* ------------------------------------------------------------ suggestions */

/* Edit distance (Levenshtein) of two short strings; long ones count as far apart. */
static size_t args_edit_distance(const char *a, size_t na, const char *b)
{
    size_t nb = strlen(b);
    enum { N = 40 };
    if (na >= N || nb >= N)
        return SIZE_MAX;
    size_t row[N];
    for (size_t j = 0; j <= nb; j++)
        row[j] = j;
    for (size_t i = 1; i <= na; i++) {
        size_t diag = row[0];
        row[0] = i;
        for (size_t j = 1; j <= nb; j++) {
            size_t up = row[j];
            size_t best = diag + (a[i - 1] != b[j - 1]);
            if (up + 1 < best) best = up + 1;
            if (row[j - 1] + 1 < best) best = row[j - 1] + 1;
            row[j] = best;
            diag = up;
        }
    }
    return row[nb];
}

/* The long option of table[0..n) closest to name[0..len), or NULL if none is plausibly
 * meant (within two edits, and fewer edits than the option's length). */
static const char *args_suggest_option(const ArgsOptSpec *table, size_t n, const char *name, size_t len)
{
    const char *best = NULL;
    size_t best_d = 3;
    for (size_t i = 0; i < n; i++) {
        size_t d = args_edit_distance(name, len, table[i].long_name);
        if (d < best_d && d < strlen(table[i].long_name)) {
            best_d = d;
            best = table[i].long_name;
        }
    }
    return best;
}

/* Reads the option argv[*i] (--name, --name=VALUE, --name VALUE, -x, -xVALUE) against
 * table[0..n): sets *o and *value (NULL for a flag or an absent optional value) and
 * consumes argv[*i + 1] for a required value, even one starting with '-' ("--seed -1"
 * then fails clearly in the value's check). An unknown option suggests the closest long
 * name; cmd names the command in the messages ("" for render, whose messages name none). */
static bool args_read_option(const ArgsOptSpec *table, size_t n, const char *cmd, int argc, char **argv,
                             int *i, const ArgsOptSpec **o, const char **value, ArgsError *err)
{
    const char *arg = argv[*i];
    char for_cmd[32] = "";
    if (cmd[0]) snprintf(for_cmd, sizeof for_cmd, " for '%s'", cmd);
    *o = NULL;
    *value = NULL;
    if (arg[1] == '-') {
        const char *name = arg + 2, *eq = strchr(name, '=');
        size_t len = eq ? (size_t)(eq - name) : strlen(name);
        for (size_t k = 0; k < n; k++)
            if (strlen(table[k].long_name) == len && strncmp(table[k].long_name, name, len) == 0)
                *o = &table[k];
        if (!*o) {
            const char *s = args_suggest_option(table, n, name, len);
            if (s)
                args_fail(err, true, "unknown option '%s'%s (did you mean --%s?)", arg, for_cmd, s);
            else
                args_fail(err, true, "unknown option '%s'%s", arg, for_cmd);
            return false;
        }
        if (eq && (*o)->value == ARGS_FLAG) {
            args_fail(err, true, "--%s does not take a value (got '%s')", (*o)->long_name, arg);
            return false;
        }
        *value = eq ? eq + 1 : NULL;
    } else {
        for (size_t k = 0; k < n; k++)
            if (table[k].short_name != 0 && table[k].short_name == arg[1])
                *o = &table[k];
        if (!*o || ((*o)->value != ARGS_VALUE && arg[2] != '\0')) {
            args_fail(err, true, "unknown option '%s'%s", arg, for_cmd);
            return false;
        }
        *value = arg[2] != '\0' ? arg + 2 : NULL;
    }
    if ((*o)->value == ARGS_VALUE && !*value) {
        if (*i + 1 >= argc) {
            args_fail(err, true, "--%s: missing value", (*o)->long_name);
            return false;
        }
        *value = argv[++*i];
    }
    return true;
}

/* One step of the argv walk every command shares: argv[*i] is positional (a word not
 * starting with '-', a lone "-", anything after "--"), returned in *positional; or an option,
 * read by args_read_option into *o and *value; or "--" itself, consumed, all three NULL. */
static bool args_next(const ArgsOptSpec *table, size_t n, const char *cmd, int argc, char **argv, int *i,
                      bool *only_positional, const char **positional, const ArgsOptSpec **o,
                      const char **value, ArgsError *err)
{
    const char *arg = argv[*i];
    *positional = NULL;
    *o = NULL;
    *value = NULL;
    if (*only_positional || arg[0] != '-' || arg[1] == '\0') {
        *positional = arg;
        return true;
    }
    if (strcmp(arg, "--") == 0) {
        *only_positional = true;
        return true;
    }
    return args_read_option(table, n, cmd, argc, argv, i, o, value, err);
}

/* A command's single positional argument (`what`: "SCENE", "MESH"): a second one is an error. */
static bool args_take_one(const char **slot, const char *arg, const char *what, ArgsError *err)
{
    if (*slot) {
        args_fail(err, true, "unexpected argument '%s' (only one %s may be given)", arg, what);
        return false;
    }
    *slot = arg;
    return true;
}

/* ------------------------------------------------------------ option values */

/* --crop X0,X1,Y0,Y1 into s->crop. */
static bool args_parse_crop(const char *value, CstRenderSettings *s, ArgsError *err)
{
    /* Four integers; their bounds against the image are checked by cst_render, which
     * knows the final width and height. */
    const char *p = value;
    for (int k = 0; k < 4; k++) {
        char *end;
        errno = 0;
        long c = strtol(p, &end, 10);
        bool sep_ok = k < 3 ? *end == ',' : *end == '\0';
        if (end == p || errno || !sep_ok || c < 0 || c > ARGS_MAX_DIMENSION) {
            args_fail(err, false, "--crop: expected X0,X1,Y0,Y1: four integers from 0 to %d, got '%s'",
                      ARGS_MAX_DIMENSION, value);
            return false;
        }
        s->crop[k] = (int)c;
        p = end + 1;
    }
    if (!(s->crop[0] < s->crop[1] && s->crop[2] < s->crop[3])) {
        args_fail(err, false, "--crop: expected X0 < X1 and Y0 < Y1, got '%s'", value);
        return false;
    }
    return true;
}

/* --checkpoint FILE, --resume FILE, --checkpoint-every SECONDS. */
static bool args_apply_checkpoint(const ArgsOptSpec *o, const char *value, CliArgs *out, ArgsError *err)
{
    if (o->id == ARGS_OPT_CHECKPOINT_EVERY) {
        if (args_parse_seconds(value, &out->checkpoint_every)) return true;
        args_fail(err, false, "--checkpoint-every: expected a positive number of seconds, got '%s'", value);
        return false;
    }
    if (value[0] == '\0') {
        args_fail(err, false, "--%s: expected a file name, got ''", o->long_name);
        return false;
    }
    *(o->id == ARGS_OPT_CHECKPOINT ? &out->checkpoint_path : &out->resume_path) = value;
    return true;
}

/* --first-sample N (>= 0) and --sample-block B (>= 1). */
static bool args_apply_range(const ArgsOptSpec *o, const char *value, CstRenderSettings *s, ArgsError *err)
{
    const bool first = o->id == ARGS_OPT_FIRST_SAMPLE;
    long v;
    if (!args_parse_long(value, first ? 0 : 1, INT_MAX / 2, &v)) {
        args_fail(err, false, "--%s: expected an integer from %d to %d, got '%s'", o->long_name, first ? 0 : 1,
                  INT_MAX / 2, value);
        return false;
    }
    *(first ? &s->first_sample : &s->sample_block) = (int)v;
    return true;
}

/* --light-sampler and --light-sampling: names checked here, applied to the scene later */
static bool args_apply_light(const ArgsOptSpec *o, const char *value, CliArgs *out, ArgsError *err)
{
    if (o->id == ARGS_OPT_LIGHT_SAMPLER) {
        if (strcmp(value, "power") && strcmp(value, "bvh") && strcmp(value, "uniform")) {
            args_fail(err, false, "--light-sampler: unknown light sampler '%s' (valid: power, bvh, uniform)", value);
            return false;
        }
        out->light_sampler = value;
        return true;
    }
    if (strcmp(value, "area") && strcmp(value, "solid_angle")) {
        args_fail(err, false, "--light-sampling: unknown light sampling '%s' (valid: area, solid_angle)", value);
        return false;
    }
    out->light_sampling = value;
    return true;
}

/* view's --script FILE (the render table holds it, so view takes every render option). */
static bool args_apply_script(const char *value, CliArgs *out, ArgsError *err)
{
    if (out->command != ARGS_CMD_VIEW) {
        args_fail(err, true, "--script is an option of 'view' (caustic view [SCENE] --script FILE)");
        return false;
    }
    if (value[0] == '\0') {
        args_fail(err, false, "--script: expected a file name, got ''");
        return false;
    }
    out->script_path = value;
    return true;
}

/* render's and view's --display tev[:HOST:PORT] (the stream to tev, cli/tev.c). */
static bool args_apply_display(const char *value, CliArgs *out, ArgsError *err)
{
    if (out->command != ARGS_CMD_RENDER && out->command != ARGS_CMD_VIEW) {
        args_fail(err, true, "--display is an option of 'render' and 'view'");
        return false;
    }
    if (!cli_tev_parse(value, out->display_host, sizeof out->display_host, &out->display_port, err->msg,
                       sizeof err->msg)) {
        err->hint = false;
        return false;
    }
    out->display = value;
    return true;
}

/* explain's --pixel X,Y and --sample I. */
static bool args_apply_explain(const ArgsOptSpec *o, const char *value, CliArgs *out, ArgsError *err)
{
    if (out->command != ARGS_CMD_EXPLAIN) {
        args_fail(err, true, "--%s is an option of 'explain' (caustic explain [SCENE] --pixel X,Y [--sample I])",
                  o->long_name);
        return false;
    }
    long v;
    if (o->id == ARGS_OPT_WHY_DARK || o->id == ARGS_OPT_WHY_BRIGHT) {
        out->explain_why = o->id == ARGS_OPT_WHY_DARK ? 1 : 2;
        return true;
    }
    if (o->id == ARGS_OPT_SAMPLE) {
        if (!args_parse_long(value, 0, INT_MAX, &v)) {
            args_fail(err, false, "--sample: expected an integer from 0 to %d, got '%s'", INT_MAX, value);
            return false;
        }
        out->explain_sample = (int)v;
        return true;
    }
    char buf[64];
    const char *comma = strchr(value, ',');
    long x, y;
    if (!comma || (size_t)(comma - value) >= sizeof buf) goto bad;
    memcpy(buf, value, (size_t)(comma - value));
    buf[comma - value] = '\0';
    if (!args_parse_long(buf, 0, ARGS_MAX_DIMENSION - 1, &x) ||
        !args_parse_long(comma + 1, 0, ARGS_MAX_DIMENSION - 1, &y))
        goto bad;
    out->pixel_x = (int)x;
    out->pixel_y = (int)y;
    out->pixel_set = true;
    return true;
bad:
    args_fail(err, false, "--pixel: expected X,Y, two integers from 0 to %d (0,0 the top left), got '%s'",
              ARGS_MAX_DIMENSION - 1, value);
    return false;
}

/* --noise TARGET: a positive finite number, the seconds parser's rule (no sign, NaN, inf). */
static bool args_apply_noise(const char *value, CstRenderSettings *s, ArgsError *err)
{
    if (args_parse_seconds(value, &s->noise_target)) return true;
    args_fail(err, false, "--noise: expected a relative standard error > 0 (0.01: 1%%), got '%s'", value);
    return false;
}

static bool args_apply_max_depth(const char *value, CstRenderSettings *s, ArgsError *err)
{
    long v;
    if (!args_parse_long(value, 0, INT_MAX, &v)) {
        args_fail(err, false, "--max-depth: expected an integer from 0 (unbounded) to %d, got '%s'", INT_MAX, value);
        return false;
    }
    s->max_depth = (int)v; /* 0 is a value: unbounded, even over the scene's limit */
    return true;
}

/* --subsurface walk|bssrdf: CstRenderSettings.subsurface_walk. */
static bool args_apply_subsurface(const char *value, CstRenderSettings *s, ArgsError *err)
{
    if (strcmp(value, "walk") != 0 && strcmp(value, "bssrdf") != 0) {
        args_fail(err, false, "--subsurface: expected walk or bssrdf, got '%s'", value);
        return false;
    }
    s->subsurface_walk = strcmp(value, "walk") == 0;
    return true;
}

static bool args_apply(const ArgsOptSpec *o, const char *value, CliArgs *out, ArgsError *err)
{
    CstRenderSettings *s = &out->settings;
    long v;
    switch ((ArgsOpt)o->id) {
    case ARGS_OPT_SCRIPT: return args_apply_script(value, out, err);
    case ARGS_OPT_DISPLAY: return args_apply_display(value, out, err);
    case ARGS_OPT_PIXEL: case ARGS_OPT_SAMPLE: case ARGS_OPT_WHY_DARK: case ARGS_OPT_WHY_BRIGHT: return args_apply_explain(o, value, out, err);
    case ARGS_OPT_OUTPUT:
        if (value[0] == '\0') {
            args_fail(err, false, "--output: expected a file name, got ''");
            return false;
        }
        out->output_path = value;
        return true;
    case ARGS_OPT_SPP:
        if (!args_parse_long(value, 1, INT_MAX, &v)) {
            args_fail(err, false, "--spp: expected a positive integer, got '%s'", value);
            return false;
        }
        s->spp = (int)v;
        return true;
    case ARGS_OPT_TIME:
        if (!args_parse_seconds(value, &s->time_limit)) {
            args_fail(err, false, "--time: expected a positive number of seconds, got '%s'",
                      value);
            return false;
        }
        return true;
    case ARGS_OPT_NOISE: return args_apply_noise(value, s, err);
    case ARGS_OPT_THREADS:
        if (!args_parse_long(value, 0, ARGS_MAX_THREADS, &v)) {
            args_fail(err, false,
                      "--threads: expected an integer from 0 (one per core) to %d, got '%s'",
                      ARGS_MAX_THREADS, value);
            return false;
        }
        s->threads = (int)v;
        return true;
    case ARGS_OPT_SEED:
        if (!args_parse_u64(value, &s->seed)) {
            args_fail(err, false,
                      "--seed: expected an unsigned 64-bit integer (decimal or 0x-hex), got '%s'",
                      value);
            return false;
        }
        s->seed_set = 1;
        return true;
    case ARGS_OPT_INTEGRATOR:
        s->integrator = cst_integrator_from_name(value);
        if (s->integrator == CST_INTEGRATOR_DEFAULT) {
            args_fail(err, false, "--integrator: unknown integrator '%s' (valid: %s)", value,
                      ARGS_INTEGRATOR_NAMES);
            return false;
        }
        return true;
    case ARGS_OPT_FILTER:
        s->filter = cst_filter_from_name(value);
        if (s->filter == CST_FILTER_DEFAULT) {
            args_fail(err, false, "--filter: unknown filter '%s' (valid: %s)", value,
                      ARGS_FILTER_NAMES);
            return false;
        }
        return true;
    case ARGS_OPT_WIDTH:
    case ARGS_OPT_HEIGHT:
        if (!args_parse_long(value, 1, ARGS_MAX_DIMENSION, &v)) {
            args_fail(err, false, "--%s: expected an integer from 1 to %d, got '%s'",
                      o->long_name, ARGS_MAX_DIMENSION, value);
            return false;
        }
        *(o->id == ARGS_OPT_WIDTH ? &s->width : &s->height) = (int)v;
        return true;
    case ARGS_OPT_ACCEL:
        if (strcmp(value, "bvh") && strcmp(value, "kdtree") && strcmp(value, "grid") &&
            strcmp(value, "list") && strcmp(value, "embree") && strcmp(value, "octree")) {
            args_fail(err, false, "--accel: unknown acceleration structure '%s' (valid: %s)", value,
                      ARGS_ACCEL_NAMES);
            return false;
        }
        out->accel = value;
        return true;
    case ARGS_OPT_LIGHT_SAMPLER:
    case ARGS_OPT_LIGHT_SAMPLING: return args_apply_light(o, value, out, err);
    case ARGS_OPT_SAMPLER:
        s->sampler = cst_sampler_from_name(value);
        if (s->sampler == CST_SAMPLER_DEFAULT) {
            args_fail(err, false, "--sampler: unknown sampler '%s' (valid: %s)", value, ARGS_SAMPLER_NAMES);
            return false;
        }
        return true;
    case ARGS_OPT_EXPOSURE:
        if (!args_parse_exposure(value, &s->exposure)) {
            args_fail(err, false, "--exposure: expected a number of stops from -%d to %d, got '%s'",
                      ARGS_MAX_EXPOSURE, ARGS_MAX_EXPOSURE, value);
            return false;
        }
        s->exposure_set = 1;
        return true;
    case ARGS_OPT_PNG_LINEAR:
        s->png_linear = 1;
        return true;
    case ARGS_OPT_SPECTRAL:
    case ARGS_OPT_RGB:
        s->color_mode = o->id == ARGS_OPT_SPECTRAL ? CST_COLOR_SPECTRAL : CST_COLOR_RGB;
        return true;
    case ARGS_OPT_AOV: {
        char bad[64];
        if (!args_parse_aovs(value, &s->aovs, bad, sizeof bad)) {
            args_fail(err, false, "--aov: unknown AOV '%s' in '%s' (valid: a comma-separated list of %s)",
                      bad, value, ARGS_AOV_NAMES);
            return false;
        }
        return true;
    }
    case ARGS_OPT_CROP:
        return args_parse_crop(value, s, err);
    case ARGS_OPT_MAX_DEPTH: return args_apply_max_depth(value, s, err);
    case ARGS_OPT_SUBSURFACE: return args_apply_subsurface(value, s, err);
    case ARGS_OPT_QUIET:
        out->quiet = true;
        return true;
    case ARGS_OPT_JSON:
        if (value && value[0] == '\0') {
            args_fail(err, false, "--json=FILE: expected a file name, got ''");
            return false;
        }
        out->json = true;
        out->json_path = value; /* NULL: stdout */
        return true;
    case ARGS_OPT_FORCE:
        out->force = true;
        return true;
    case ARGS_OPT_CHECKPOINT: case ARGS_OPT_RESUME: case ARGS_OPT_CHECKPOINT_EVERY:
        return args_apply_checkpoint(o, value, out, err);
    case ARGS_OPT_FIRST_SAMPLE: case ARGS_OPT_SAMPLE_BLOCK: return args_apply_range(o, value, s, err);
    case ARGS_OPT_HELP:
        if (out->command != ARGS_CMD_HELP) out->help_for = out->command;
        out->command = ARGS_CMD_HELP;
        return true;
    }
    args_fail(err, false, "internal error: unhandled option --%s", o->long_name);
    return false;
}

/* ------------------------------------------------------------ argv */

static bool args_parse_render(int argc, char **argv, int first, CliArgs *out, ArgsError *err)
{
    bool only_positional = false; /* after "--" */
    for (int i = first; i < argc; i++) {
        const char *arg = argv[i], *positional, *value;
        const ArgsOptSpec *o;
        if (!only_positional && strncmp(arg, "--version", 9) == 0 && (arg[9] == '\0' || arg[9] == '=')) {
            args_fail(err, true, "--version is not an option of 'render'");
            return false;
        }
        if (!args_next(ARGS_OPTS, ARGS_NUM_OPTS, "", argc, argv, &i, &only_positional, &positional, &o,
                       &value, err))
            return false;
        if (positional ? !args_take_one(&out->scene_path, positional, "SCENE", err)
                       : o && !args_apply(o, value, out, err))
            return false;
    }
    if (out->checkpoint_every > 0.0 && !out->checkpoint_path) {
        args_fail(err, true, "--checkpoint-every needs --checkpoint FILE (where to write the state)");
        return false;
    }
    if (out->command == ARGS_CMD_EXPLAIN && !out->pixel_set) {
        args_fail(err, true, "explain: expected --pixel X,Y (the pixel whose sample to explain)");
        return false;
    }
    if (out->command == ARGS_CMD_INFO && (out->checkpoint_path || out->resume_path)) {
        args_fail(err, true, "--checkpoint and --resume are options of 'render', not of 'info'");
        return false;
    }
    /* --time without --spp: as many samples as fit, whatever spp the scene file sets
     * (the README's promise); with both, whichever comes first. */
    if (out->command == ARGS_CMD_RENDER && out->settings.time_limit != CST_UNSET &&
        out->settings.spp == CST_UNSET)
        out->settings.spp = CST_SPP_UNLIMITED;
    /* --noise without --spp: as many samples as the target needs, up to CST_NOISE_SPP_CAP. */
    if (out->command == ARGS_CMD_RENDER && out->settings.noise_target != CST_UNSET &&
        out->settings.spp == CST_UNSET)
        out->settings.spp = CST_SPP_UNLIMITED;
    return true;
}

/* ------------------------------------------------------------ caustic bench rays */

static const ArgsOptSpec ARGS_BENCH_OPTS[] = {
    {"cornell", 0, ARGS_FLAG, 0},  {"stadium", 0, ARGS_FLAG, 0}, {"accel", 0, ARGS_VALUE, 0},
    {"threads", 0, ARGS_VALUE, 0}, {"json", 0, ARGS_FLAG, 0},    {"help", 'h', ARGS_FLAG, 0},
};
#define ARGS_NUM_BENCH_OPTS (sizeof ARGS_BENCH_OPTS / sizeof ARGS_BENCH_OPTS[0])

static const char *const ARGS_BENCH_ACCELS[] = {"bvh", "kdtree", "grid", "list", "embree", ARGS_EMBREE_ROBUST, "octree"};
_Static_assert(sizeof ARGS_BENCH_ACCELS / sizeof ARGS_BENCH_ACCELS[0] == ARGS_BENCH_MAX_ACCELS, "one slot per name");

/* --accel bvh,embree: each name known, none empty, none twice. */
static bool args_parse_bench_accels(const char *value, BenchArgs *b, ArgsError *err)
{
    b->num_accels = 0;
    const char *p = value;
    for (;;) {
        size_t len = strcspn(p, ",");
        if (len == 0) {
            args_fail(err, false, "--accel: empty name in '%s' (valid: %s)", value, ARGS_BENCH_ACCEL_NAMES);
            return false;
        }
        const char *name = NULL;
        for (size_t k = 0; k < sizeof ARGS_BENCH_ACCELS / sizeof ARGS_BENCH_ACCELS[0]; k++)
            if (strlen(ARGS_BENCH_ACCELS[k]) == len && strncmp(ARGS_BENCH_ACCELS[k], p, len) == 0)
                name = ARGS_BENCH_ACCELS[k];
        if (!name) {
            args_fail(err, false, "--accel: unknown acceleration structure '%.*s' (valid: %s)",
                      (int)len, p, ARGS_BENCH_ACCEL_NAMES);
            return false;
        }
        for (int k = 0; k < b->num_accels; k++)
            if (b->accels[k] == name) {
                args_fail(err, false, "--accel: '%s' listed twice in '%s'", name, value);
                return false;
            }
        b->accels[b->num_accels++] = name; /* cannot overflow: names are distinct */
        if (p[len] == '\0') return true;
        p += len + 1;
    }
}

static bool args_parse_bench_rays(int argc, char **argv, int first, CliArgs *out, ArgsError *err)
{
    BenchArgs *b = &out->bench;
    bool only_positional = false;
    for (int i = first; i < argc; i++) {
        const char *positional, *value;
        const ArgsOptSpec *o;
        if (!args_next(ARGS_BENCH_OPTS, ARGS_NUM_BENCH_OPTS, "bench rays", argc, argv, &i, &only_positional,
                       &positional, &o, &value, err))
            return false;
        if (positional && !args_take_one(&b->mesh_path, positional, "MESH", err)) return false;
        if (!o) continue;
        long v;
        if (strcmp(o->long_name, "cornell") == 0) {
            b->cornell = true;
        } else if (strcmp(o->long_name, "stadium") == 0) {
            b->stadium = true;
        } else if (strcmp(o->long_name, "json") == 0) {
            b->json = true;
        } else if (strcmp(o->long_name, "help") == 0) {
            out->command = ARGS_CMD_HELP;
            out->help_for = ARGS_CMD_BENCH_RAYS;
        } else if (strcmp(o->long_name, "threads") == 0) {
            if (!args_parse_long(value, 0, ARGS_MAX_THREADS, &v)) {
                args_fail(err, false,
                          "--threads: expected an integer from 0 (one per core) to %d, got '%s'",
                          ARGS_MAX_THREADS, value);
                return false;
            }
            b->threads = (int)v;
        } else if (!args_parse_bench_accels(value, b, err)) { /* accel */
            return false;
        }
    }
    if (b->mesh_path && b->cornell) {
        args_fail(err, true, "MESH '%s' and --cornell exclude each other", b->mesh_path);
        return false;
    }
    return true;
}

static bool args_parse_bench(int argc, char **argv, CliArgs *out, ArgsError *err)
{
    if (argc < 3) {
        args_fail(err, true, "bench: missing benchmark name (benchmarks: rays)");
        return false;
    }
    const char *what = argv[2];
    if (strcmp(what, "--help") == 0 || strcmp(what, "-h") == 0) {
        out->command = ARGS_CMD_HELP;
        out->help_for = ARGS_CMD_BENCH_RAYS;
        return true;
    }
    if (strcmp(what, "rays") != 0) {
        args_fail(err, true, "bench: unknown benchmark '%s' (benchmarks: rays)", what);
        return false;
    }
    out->command = ARGS_CMD_BENCH_RAYS;
    return args_parse_bench_rays(argc, argv, 3, out, err);
}

/* ------------------------------------------------------------ caustic verify */

/* spp, time, threads, seed, width, height and quiet mean what they mean for render and go
 * through args_apply, so their checks and messages are the same. */
static const ArgsOptSpec ARGS_VERIFY_OPTS[] = {
    {"integrators", 0, ARGS_VALUE, 0}, {"spp", 0, ARGS_VALUE, 0},    {"time", 0, ARGS_VALUE, 0},
    {"threads", 0, ARGS_VALUE, 0},     {"seed", 0, ARGS_VALUE, 0},   {"alpha", 0, ARGS_VALUE, 0},
    {"block", 0, ARGS_VALUE, 0},       {"map", 0, ARGS_VALUE, 0},    {"json", 0, ARGS_FLAG, 0},
    {"width", 0, ARGS_VALUE, 0},       {"height", 0, ARGS_VALUE, 0}, {"quiet", 'q', ARGS_FLAG, 0},
    {"help", 'h', ARGS_FLAG, 0},       {"convergence", 0, ARGS_VALUE, 0},
    {"subsurface", 0, ARGS_VALUE, 0},
};
#define ARGS_NUM_VERIFY_OPTS (sizeof ARGS_VERIFY_OPTS / sizeof ARGS_VERIFY_OPTS[0])

/* "path, path-nee, ...": every integrator the library names, so an integrator added to the
 * library is listed (and accepted, through cst_integrator_from_name) without a change here.
 * Relies on cst_integrator_name() answering "default" past the last enumerator. */
static void args_integrator_list(char *buf, size_t size)
{
    size_t n = 0;
    buf[0] = '\0';
    for (int k = CST_INTEGRATOR_DEFAULT + 1; k < 64; k++) {
        const char *name = cst_integrator_name((CstIntegrator)k);
        if (strcmp(name, "default") == 0) break;
        int w = snprintf(buf + n, size - n, "%s%s", n ? ", " : "", name);
        if (w < 0 || (size_t)w >= size - n) break;
        n += (size_t)w;
    }
}

/* --integrators path,path-nee: each name known, at least two. A name may repeat: the two
 * renders still get different seeds, and the pair tests the test's false-alarm rate. */
static bool args_parse_verify_integrators(const char *value, VerifyArgs *v, ArgsError *err)
{
    char valid[256];
    v->num_integrators = 0;
    const char *p = value;
    for (;;) {
        size_t len = strcspn(p, ",");
        char name[64];
        CstIntegrator id = CST_INTEGRATOR_DEFAULT;
        if (len > 0 && len < sizeof name) {
            memcpy(name, p, len);
            name[len] = '\0';
            id = cst_integrator_from_name(name);
        }
        if (id == CST_INTEGRATOR_DEFAULT) {
            args_integrator_list(valid, sizeof valid);
            if (len == 0)
                args_fail(err, false, "--integrators: empty name in '%s' (valid: %s)", value, valid);
            else
                args_fail(err, false, "--integrators: unknown integrator '%.*s' (valid: %s)",
                          (int)len, p, valid);
            return false;
        }
        if (v->num_integrators == ARGS_VERIFY_MAX_INTEGRATORS) {
            args_fail(err, false, "--integrators: at most %d integrators, got more in '%s'",
                      ARGS_VERIFY_MAX_INTEGRATORS, value);
            return false;
        }
        v->integrators[v->num_integrators++] = id;
        if (p[len] == '\0') break;
        p += len + 1;
    }
    if (v->num_integrators < 2) {
        args_fail(err, false, "--integrators: verify compares at least two integrators, got "
                  "only '%s'", value);
        return false;
    }
    return true;
}

static bool args_apply_verify(const ArgsOptSpec *o, const char *value, CliArgs *out,
                              ArgsError *err)
{
    VerifyArgs *v = &out->verify;
    long n;
    if (strcmp(o->long_name, "integrators") == 0)
        return args_parse_verify_integrators(value, v, err);
    if (strcmp(o->long_name, "alpha") == 0) {
        if (!args_parse_seconds(value, &v->alpha) || !(v->alpha < 1.0)) {
            args_fail(err, false, "--alpha: expected a number between 0 and 1 (exclusive), got '%s'",
                      value);
            return false;
        }
        return true;
    }
    if (strcmp(o->long_name, "block") == 0) {
        if (!args_parse_long(value, 1, ARGS_MAX_DIMENSION, &n)) {
            args_fail(err, false, "--block: expected an integer from 1 to %d, got '%s'",
                      ARGS_MAX_DIMENSION, value);
            return false;
        }
        v->block = (int)n;
        return true;
    }
    if (strcmp(o->long_name, "convergence") == 0) {
        if (!args_parse_long(value, 2, ARGS_VERIFY_MAX_LEVELS, &n)) {
            args_fail(err, false, "--convergence: expected a number of levels from 2 to %d, got '%s'",
                      ARGS_VERIFY_MAX_LEVELS, value);
            return false;
        }
        v->levels = (int)n;
        return true;
    }
    if (strcmp(o->long_name, "map") == 0) {
        if (value[0] == '\0') {
            args_fail(err, false, "--map: expected a file name, got ''");
            return false;
        }
        v->map_path = value;
        return true;
    }
    if (strcmp(o->long_name, "json") == 0) {
        v->json = true;
        return true;
    }
    if (strcmp(o->long_name, "help") == 0) {
        out->command = ARGS_CMD_HELP;
        out->help_for = ARGS_CMD_VERIFY;
        return true;
    }
    for (size_t k = 0; k < ARGS_NUM_OPTS; k++) /* shared with render */
        if (strcmp(ARGS_OPTS[k].long_name, o->long_name) == 0)
            return args_apply(&ARGS_OPTS[k], value, out, err);
    args_fail(err, false, "internal error: unhandled option --%s", o->long_name);
    return false;
}

static bool args_parse_verify(int argc, char **argv, int first, CliArgs *out, ArgsError *err)
{
    VerifyArgs *v = &out->verify;
    v->alpha = ARGS_VERIFY_DEFAULT_ALPHA;
    v->block = ARGS_VERIFY_DEFAULT_BLOCK;
    v->levels = ARGS_VERIFY_DEFAULT_LEVELS;
    bool only_positional = false;
    for (int i = first; i < argc; i++) {
        const char *positional, *value;
        const ArgsOptSpec *o;
        if (!args_next(ARGS_VERIFY_OPTS, ARGS_NUM_VERIFY_OPTS, "verify", argc, argv, &i, &only_positional,
                       &positional, &o, &value, err))
            return false;
        if (positional && !args_take_one(&out->scene_path, positional, "SCENE", err)) return false;
        if (!o) continue;
        if (!args_apply_verify(o, value, out, err))
            return false;
    }
    if (out->command == ARGS_CMD_VERIFY && v->num_integrators == 0) {
        args_fail(err, true, "verify: --integrators is required (e.g. --integrators path,path-nee)");
        return false;
    }
    return true;
}

/* ------------------------------------------------------------ caustic compare */

static const ArgsOptSpec ARGS_COMPARE_OPTS[] = {
    {"map", 0, ARGS_VALUE, 0},        {"json", 0, ARGS_FLAG, 0},     {"variance-a", 0, ARGS_VALUE, 0},
    {"variance-b", 0, ARGS_VALUE, 0}, {"block", 0, ARGS_VALUE, 0},   {"flip", 0, ARGS_VALUE, 0},
    {"ppd", 0, ARGS_VALUE, 0},        {"help", 'h', ARGS_FLAG, 0},
};
#define ARGS_NUM_COMPARE_OPTS (sizeof ARGS_COMPARE_OPTS / sizeof ARGS_COMPARE_OPTS[0])

static bool args_apply_compare(const char *name, const char *value, CliArgs *out, ArgsError *err)
{
    CompareArgs *c = &out->compare;
    long n;
    if (strcmp(name, "json") == 0) {
        c->json = true;
    } else if (strcmp(name, "help") == 0) {
        out->command = ARGS_CMD_HELP;
        out->help_for = ARGS_CMD_COMPARE;
    } else if (value[0] == '\0') {
        args_fail(err, false, "--%s: expected a value, got ''", name);
        return false;
    } else if (strcmp(name, "map") == 0) {
        c->map_path = value;
    } else if (strcmp(name, "variance-a") == 0) {
        c->var_a = value;
    } else if (strcmp(name, "variance-b") == 0) {
        c->var_b = value;
    } else if (strcmp(name, "block") == 0) {
        if (!args_parse_long(value, 1, ARGS_MAX_DIMENSION, &n)) {
            args_fail(err, false, "--block: expected an integer from 1 to %d, got '%s'", ARGS_MAX_DIMENSION, value);
            return false;
        }
        c->block = (int)n;
    } else if (strcmp(name, "flip") == 0) {
        if (strcmp(value, "ldr") == 0) c->flip = CST_FLIP_LDR;
        else if (strcmp(value, "hdr") == 0) c->flip = CST_FLIP_HDR;
        else if (strcmp(value, "auto") == 0) c->flip = 0;
        else {
            args_fail(err, false, "--flip: expected ldr, hdr or auto, got '%s'", value);
            return false;
        }
    } else { /* ppd */
        if (!args_parse_seconds(value, &c->ppd) || c->ppd > ARGS_COMPARE_MAX_PPD) {
            args_fail(err, false, "--ppd: expected pixels per degree, a number > 0 and <= %g, got '%s'",
                      ARGS_COMPARE_MAX_PPD, value);
            return false;
        }
    }
    return true;
}

/* caustic compare A B [options]: exactly two images, options anywhere (--name VALUE or
 * --name=VALUE, -h), "--" ends the options. */
static bool args_parse_compare(int argc, char **argv, int first, CliArgs *out, ArgsError *err)
{
    CompareArgs *c = &out->compare;
    c->block = ARGS_COMPARE_DEFAULT_BLOCK;
    bool only_positional = false;
    for (int i = first; i < argc; i++) {
        const char *positional, *value;
        const ArgsOptSpec *o;
        if (!args_next(ARGS_COMPARE_OPTS, ARGS_NUM_COMPARE_OPTS, "compare", argc, argv, &i, &only_positional,
                       &positional, &o, &value, err))
            return false;
        if (positional) {
            if (c->a && c->b) {
                args_fail(err, true, "compare: unexpected argument '%s' (give two images: A B)", positional);
                return false;
            }
            *(c->a ? &c->b : &c->a) = positional;
        }
        if (!o) continue;
        if (!args_apply_compare(o->long_name, value ? value : "", out, err)) return false;
    }
    if (out->command == ARGS_CMD_COMPARE && !c->b) {
        args_fail(err, true, "compare: expected two images, A and the reference B (got %s)",
                  c->a ? "one" : "none");
        return false;
    }
    return true;
}

/* ------------------------------------------------------------ caustic merge */

/* caustic merge STATE... -o OUT [-q]: the states in argv order (cli/merge.c sorts them). */
static bool args_parse_merge(int argc, char **argv, CliArgs *out, ArgsError *err)
{
    MergeArgs *m = &out->merge;
    m->paths = (const char *const *)&argv[2];
    bool only_positional = false;
    for (int i = 2; i < argc; i++) {
        const char *arg = argv[i];
        if (only_positional || arg[0] != '-' || arg[1] == '\0') {
            argv[2 + m->count++] = argv[i]; /* packed in place: options are skipped */
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            only_positional = true;
        } else if (strcmp(arg, "-h") == 0 || strcmp(arg, "--help") == 0) {
            out->command = ARGS_CMD_HELP;
            out->help_for = ARGS_CMD_MERGE;
            return true;
        } else if (strcmp(arg, "-q") == 0 || strcmp(arg, "--quiet") == 0) {
            out->quiet = true;
        } else if (strcmp(arg, "-o") == 0 || strcmp(arg, "--output") == 0) {
            if (i + 1 >= argc || argv[i + 1][0] == '\0') {
                args_fail(err, true, "merge: %s needs a file name (the image to write)", arg);
                return false;
            }
            out->output_path = argv[++i];
        } else if (strncmp(arg, "--output=", 9) == 0 && arg[9]) {
            out->output_path = arg + 9;
        } else {
            args_fail(err, true, "merge: unknown option '%s' (merge takes STATE... -o IMAGE [-q])", arg);
            return false;
        }
    }
    if (m->count == 0 || !out->output_path) {
        args_fail(err, true, "merge: expected state files and -o IMAGE (got %d state%s%s)", m->count,
                  m->count == 1 ? "" : "s", out->output_path ? "" : " and no -o");
        return false;
    }
    return true;
}

/* ------------------------------------------------------------ caustic help, caustic list */

static const struct { const char *name; ArgsCommand command; } ARGS_COMMANDS[] = {
    {"render", ARGS_CMD_RENDER}, {"info", ARGS_CMD_INFO},     {"bench", ARGS_CMD_BENCH_RAYS},
    {"verify", ARGS_CMD_VERIFY}, {"list", ARGS_CMD_LIST},     {"compare", ARGS_CMD_COMPARE},
    {"view", ARGS_CMD_VIEW},     {"merge", ARGS_CMD_MERGE},     {"explain", ARGS_CMD_EXPLAIN},
};

static bool args_parse_help_topic(const char *topic, CliArgs *out, ArgsError *err)
{
    for (size_t k = 0; k < sizeof ARGS_COMMANDS / sizeof ARGS_COMMANDS[0]; k++)
        if (strcmp(topic, ARGS_COMMANDS[k].name) == 0) {
            out->command = ARGS_CMD_HELP;
            out->help_for = ARGS_COMMANDS[k].command;
            return true;
        }
    args_fail(err, true, "help: unknown command '%s' (commands: render, info, bench, verify, list, compare, view, merge, "
              "explain)",
              topic);
    return false;
}

/* The kinds of `caustic list KIND` (cli/list.c lists them). */
const char *const ARGS_LIST_KINDS[] = {"integrators", "samplers", "filters", "accels", "materials",
                                       "lights", "formats", "metals", NULL};

static bool args_parse_list(int argc, char **argv, CliArgs *out, ArgsError *err)
{
    out->command = ARGS_CMD_LIST;
    if (argc < 3) return true;
    const char *kind = argv[2];
    if (strcmp(kind, "--help") == 0 || strcmp(kind, "-h") == 0) {
        out->command = ARGS_CMD_HELP;
        out->help_for = ARGS_CMD_LIST;
        return true;
    }
    if (argc > 3) {
        args_fail(err, true, "list: unexpected argument '%s' (only one KIND may be given)", argv[3]);
        return false;
    }
    for (int k = 0; ARGS_LIST_KINDS[k]; k++)
        if (strcmp(kind, ARGS_LIST_KINDS[k]) == 0) {
            out->list_kind = ARGS_LIST_KINDS[k];
            return true;
        }
    args_fail(err, true, "list: unknown kind '%s' (kinds: integrators, samplers, filters, accels, "
              "materials, lights, formats, metals)", kind);
    return false;
}

bool args_parse(int argc, char **argv, CliArgs *out, ArgsError *err)
{
    memset(out, 0, sizeof *out);
    cst_render_settings_init(&out->settings); /* every setting unset: the scene's, else the default */
    err->msg[0] = '\0';
    err->hint = false;

    if (argc < 2) {
        args_fail(err, true, "missing command");
        return false;
    }
    const char *cmd = argv[1];
    if (strcmp(cmd, "help") == 0 && argc == 3) { /* caustic help COMMAND */
        return args_parse_help_topic(argv[2], out, err);
    } else if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        out->command = ARGS_CMD_HELP;
        out->help_for = ARGS_CMD_HELP;
    } else if (strcmp(cmd, "list") == 0) {
        return args_parse_list(argc, argv, out, err);
    } else if (strcmp(cmd, "--version") == 0) {
        out->command = ARGS_CMD_VERSION;
    } else if (strcmp(cmd, "render") == 0) {
        out->command = ARGS_CMD_RENDER;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "info") == 0) {
        out->command = ARGS_CMD_INFO;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "view") == 0) {
        out->command = ARGS_CMD_VIEW;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "explain") == 0) {
        out->command = ARGS_CMD_EXPLAIN;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "bench") == 0) {
        return args_parse_bench(argc, argv, out, err);
    } else if (strcmp(cmd, "verify") == 0) {
        out->command = ARGS_CMD_VERIFY;
        return args_parse_verify(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "compare") == 0) {
        out->command = ARGS_CMD_COMPARE;
        return args_parse_compare(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "merge") == 0) {
        out->command = ARGS_CMD_MERGE;
        return args_parse_merge(argc, argv, out, err);
    } else if (cmd[0] == '-') {
        const char *name = cmd + strspn(cmd, "-");
        for (size_t k = 0; k < ARGS_NUM_OPTS; k++)
            if (strcmp(ARGS_OPTS[k].long_name, name) == 0 ||
                (ARGS_OPTS[k].short_name && name[0] == ARGS_OPTS[k].short_name && !name[1])) {
                args_fail(err, true, "'%s' is an option of the render command: caustic render %s ...",
                          cmd, cmd);
                return false;
            }
        if (args_edit_distance(name, strlen(name), "help") <= 2)
            args_fail(err, true, "unknown option '%s' (did you mean --help?)", cmd);
        else if (args_edit_distance(name, strlen(name), "version") <= 2)
            args_fail(err, true, "unknown option '%s' (did you mean --version?)", cmd);
        else
            args_fail(err, true, "unknown option '%s'", cmd);
        return false;
    } else {
        if (args_edit_distance(cmd, strlen(cmd), "render") <= 2)
            args_fail(err, true, "unknown command '%s' (did you mean 'render'?)", cmd);
        else if (args_edit_distance(cmd, strlen(cmd), "verify") <= 2)
            args_fail(err, true, "unknown command '%s' (did you mean 'verify'?)", cmd);
        else if (args_edit_distance(cmd, strlen(cmd), "compare") <= 2)
            args_fail(err, true, "unknown command '%s' (did you mean 'compare'?)", cmd);
        else
            args_fail(err, true, "unknown command '%s' (commands: render, info, bench, verify, list, compare, view, merge, "
                      "explain)", cmd);
        return false;
    }
    if (argc > 2) {
        args_fail(err, true, "unexpected argument '%s' after %s", argv[2], cmd);
        return false;
    }
    return true;
}
