/* Command-line parsing for the caustic tool: the option table, strict number parsing
 * (whole string consumed, range checked) and the help text, kept side by side so they
 * cannot drift apart. */
#include "args.h"

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
    ARGS_OPT_PNG_LINEAR, ARGS_OPT_AOV, ARGS_OPT_CROP, ARGS_OPT_MAX_DEPTH
} ArgsOpt;

typedef struct ArgsOptSpec {
    const char *long_name; /* without the leading "--" */
    char short_name;       /* 0 = none */
    bool takes_value;
    ArgsOpt id;
} ArgsOptSpec;

static const ArgsOptSpec ARGS_OPTS[] = {
    {"output",     'o', true,  ARGS_OPT_OUTPUT},
    {"spp",        0,   true,  ARGS_OPT_SPP},
    {"time",       0,   true,  ARGS_OPT_TIME},
    {"threads",    0,   true,  ARGS_OPT_THREADS},
    {"seed",       0,   true,  ARGS_OPT_SEED},
    {"integrator", 0,   true,  ARGS_OPT_INTEGRATOR},
    {"filter",     0,   true,  ARGS_OPT_FILTER},
    {"width",      0,   true,  ARGS_OPT_WIDTH},
    {"height",     0,   true,  ARGS_OPT_HEIGHT},
    {"accel",      0,   true,  ARGS_OPT_ACCEL},
    {"sampler",    0,   true,  ARGS_OPT_SAMPLER},
    {"exposure",   0,   true,  ARGS_OPT_EXPOSURE},
    {"png-linear", 0,   false, ARGS_OPT_PNG_LINEAR},
    {"aov",        0,   true,  ARGS_OPT_AOV},
    {"crop",       0,   true,  ARGS_OPT_CROP},
    {"max-depth",  0,   true,  ARGS_OPT_MAX_DEPTH},
    {"quiet",      'q', false, ARGS_OPT_QUIET},
    {"help",       'h', false, ARGS_OPT_HELP},
};
#define ARGS_NUM_OPTS (sizeof ARGS_OPTS / sizeof ARGS_OPTS[0])

/* The --help text (docs/cli.md says the same at more length). */
static const char ARGS_HELP[] =
"caustic " CST_VERSION_STRING ": a physically based renderer\n"
"\n"
"Usage:\n"
"  caustic render [SCENE] [options]\n"
"  caustic render --help\n"
"  caustic info [SCENE] [--accel NAME]\n"
"  caustic bench rays [MESH | --cornell] [--stadium] [--accel NAME[,NAME...]]\n"
"                     [--threads N] [--json]\n"
"  caustic verify [SCENE] --integrators NAME,NAME[,...] [--spp N | --time S]\n"
"                 [--threads N] [--seed S] [--alpha A] [--block N] [--map OUT.png]\n"
"                 [--convergence K] [--json] [--width W] [--height H] [--quiet]\n"
"  caustic --help | -h\n"
"  caustic --version\n"
"\n"
"Renders SCENE, a caustic JSON scene file (*.json, see docs/scene-format.md) or a\n"
"pbrt-v4 scene (*.pbrt, see docs/pbrt-compat.md), or the built-in Cornell box when SCENE\n"
"is omitted, and writes one image. 'info' loads the scene, builds its acceleration\n"
"structure and prints the load time, its size, build time and memory.\n"
"\n"
"Options (both --opt VALUE and --opt=VALUE are accepted; a later option wins):\n"
"  -o, --output OUT     output image; the format follows the extension: .png (8-bit\n"
"                       sRGB), .exr or .pfm (linear float). Default: the scene file's\n"
"                       \"output\", else <scene file stem>.png in the current directory,\n"
"                       cornell-box.png for the built-in scene. The extension and the\n"
"                       directory are checked before rendering starts.\n"
"      --spp N          samples per pixel, N >= 1 (default: the scene's, else 16)\n"
"      --time SECONDS   stop after SECONDS of rendering, > 0; with --spp too, stops at\n"
"                       whichever comes first (default: no time limit)\n"
"      --threads N      render threads, 0..1024; 0 = one per core (the default)\n"
"      --seed S         random seed, any unsigned 64-bit integer, decimal or 0x-hex\n"
"                       (default: the scene's, else 0)\n"
"      --integrator NAME  path (default: NEE and BSDF sampling combined by MIS),\n"
"                       path-nee (emitters reached by NEE only), path-bsdf (BSDF\n"
"                       sampling only), light (light tracing from the emitters; --spp\n"
"                       counts iterations of W x H light paths; misses what is seen in\n"
"                       mirrors or through glass), whitted (mirror and glass recursion\n"
"                       with direct light only; biased by design), photon (photon\n"
"                       mapping with final gathering; consistent but biased, photon\n"
"                       count and radius from the scene file), sppm (stochastic\n"
"                       progressive photon mapping; --spp counts iterations, each one\n"
"                       camera sample per pixel and one photon pass; consistent but\n"
"                       biased), bdpt (bidirectional path tracing, all\n"
"                       connection strategies with MIS; --spp counts iterations of one\n"
"                       light and one camera path per pixel), vcm (vertex connection\n"
"                       and merging: bdpt plus photon merging with a shrinking radius,\n"
"                       the first from the scene's \"radius\", else automatic;\n"
"                       consistent); default: the scene's, else path\n"
"      --filter NAME    box, tent, gaussian or mitchell (default: the scene's, else box)\n"
"      --width W        image width in pixels, 1..65536 (default: the scene's, else 512)\n"
"      --height H       image height in pixels, 1..65536 (default: the scene's, else\n"
"                       512); --width and --height may each be given alone\n"
"      --accel NAME     acceleration structure: bvh (default), kdtree, grid, list (brute\n"
"                       force) or embree (when built with Embree); default: the scene's\n"
"      --sampler NAME   random numbers of camera paths: independent (PCG32, the\n"
"                       default), stratified (jittered; 2D strata nx x ny = spp, so\n"
"                       choose square or power-of-two spp) or sobol (Owen-scrambled\n"
"                       Sobol'; fewer samples for the same noise, see docs/benchmarks.md).\n"
"                       Light paths (light, photon, sppm, bdpt, vcm) stay independent\n"
"      --max-depth N    maximum bounces of a path, 0..2147483647; 0 = unbounded, also\n"
"                       over a scene's own limit (default: the scene's, else unbounded)\n"
"      --exposure EV    scale the written image by 2^EV, -64..64 (default: the scene's,\n"
"                       else 0); the film's stored means are not changed\n"
"      --png-linear     write PNG values linearly (no sRGB curve; tagged gAMA 1.0)\n"
"      --aov LIST       extra EXR channels, comma-separated: albedo (albedo.R/G/B),\n"
"                       normal (N.X/Y/Z), depth (Z), variance (variance.R/G/B); needs an\n"
"                       .exr output (docs/cli.md)\n"
"      --crop X0,X1,Y0,Y1  render and write only the pixels X0 <= x < X1, Y0 <= y < Y1\n"
"                       (y = 0 the top row) of the image; each holds the value it has in\n"
"                       the whole image (default: the scene's crop, else none)\n"
"  -q, --quiet          no job line, progress or summary; warnings and errors remain\n"
"  -h, --help           show this help and exit\n"
"      --version        print the version and exit\n"
"\n"
"Progress goes to stderr: a redrawn bar when stderr is a terminal, otherwise one line\n"
"per 10% of the render. The image is written atomically (temporary file, rename).\n"
"\n"
"Benchmark: caustic bench rays\n"
"Traces the acceleration benchmark's three ray sets (/work/shared/bench/RAYSETS.md:\n"
"primary closest hits, secondary bounce rays generated once and shared by every back\n"
"end, and the bounce rays as occlusion queries) through each back end with 1 thread and\n"
"with N threads, and prints build time, bytes per triangle, M rays/s, the speed ratios to\n"
"Embree (its default configuration) and to Embree in its robust mode (robust box test,\n"
"edge-consistent triangle test: the guarantees of our BVH), hits and sum of t, checked\n"
"against the published checksums (or, for scenes without them, against the first back\n"
"end).\n"
"  MESH                 a triangle mesh file (read through the mesh importer, e.g. a\n"
"                       PLY of /work/shared/meshes); default: the built-in Cornell box\n"
"      --cornell        the built-in Cornell box (the default)\n"
"      --stadium        put the scene inside a huge box of 12 triangles (teapot in a\n"
"                       stadium); alone: a built-in 20,480-triangle bumpy ball inside it\n"
"      --accel LIST     comma-separated back ends: bvh, kdtree, grid, list, embree,\n"
"                       embree-robust (default: all this build has; list only for\n"
"                       scenes of at most 1,000 triangles)\n"
"      --threads N      the second thread count, 0..1024; 0 = one per core (default)\n"
"      --json           one JSON object per line on stdout instead of the table\n"
"\n"
"Consistency check: caustic verify\n"
"Renders SCENE (or the built-in Cornell box) once per integrator, each with its own seed,\n"
"and tests every pair for agreement: per channel, the z-score of the difference of the\n"
"image means and of every NxN block mean, z = (mean_a - mean_b) / sqrt(var_a + var_b),\n"
"with variances from the per-pixel sample variances. A pair disagrees if any |z| exceeds\n"
"the critical z of a Sidak correction over all tests of all pairs at family-wise\n"
"significance A. Prints one row per pair (image-mean z per channel, largest |block z|,\n"
"failing blocks) and the critical z; see docs/cli.md for the statistics.\n"
"Consistent but biased integrators (photon, sppm, vcm) are judged by convergence\n"
"instead, against the first unbiased integrator in the list (the reference, e.g. path):\n"
"each is rendered twice (independent seeds) at K levels of work, 1, 4, 16, ... times the\n"
"base (sppm, vcm: --spp iterations; photon: the scene's photon count, and its radius\n"
"halved per level if the scene fixes one); the disagreement D (the mean squared block\n"
"bias, estimated net of noise) and the image mean must be within noise at the last\n"
"level, or D must fall significantly at every step.\n"
"  SCENE                a caustic JSON or pbrt-v4 scene; default: the built-in Cornell box\n"
"      --integrators LIST  comma-separated, at least two (any name --integrator takes;\n"
"                       a name may repeat: a same-integrator pair checks the test itself)\n"
"      --spp N          samples per pixel of each render (default: the scene's, else 16)\n"
"      --time SECONDS   render each integrator for SECONDS (equal time); with --spp\n"
"                       (or a scene's spp) too, each stops at whichever comes first\n"
"      --seed S         base seed (default: the scene's, else 0); integrator k (0-based,\n"
"                       in list order) renders with SplitMix64's output k+1 from S, shown\n"
"                       in the report, so 'caustic render --seed' reproduces it\n"
"      --alpha A        family-wise significance, 0 < A < 1 (default: 0.01)\n"
"      --block N        block side in pixels, 1..65536 (default: 16); edge blocks are\n"
"                       partial and tested with their own pixel counts. Each block needs\n"
"                       many samples (block^2 x spp >= 65536, else a warning) for z to be\n"
"                       near normal with heavy-tailed estimators such as path-bsdf\n"
"      --map OUT        false-colour map of the largest block |z| over channels and\n"
"                       pairs, at the image's size (.png, .exr or .pfm): black to blue\n"
"                       up to z_crit/2, blue to yellow at z_crit, red beyond\n"
"      --convergence K  levels of the convergence check, 2..6 (default: 3)\n"
"      --json           one JSON object per pair (then per convergence check) on stdout\n"
"                       instead of the report\n"
"      --width W, --height H, --threads N, -q/--quiet: as for render\n"
"\n"
"Exit status:\n"
"  0  success: the image was written (bench rays: every check passed; verify: every\n"
"     pair of integrators agrees and every consistent one converges)\n"
"  1  internal error: out of memory, a library failure, or an I/O error while writing\n"
"     the image although its directory was checked writable before rendering\n"
"     (disk full, file system error)\n"
"     bench rays: a checksum did not match; verify: a pair of integrators disagrees\n"
"     or a consistent integrator is not shown to converge\n"
"  2  bad input or usage: unknown command or option, invalid value, unsupported scene\n"
"     or output format, a scene file that is missing, unreadable or invalid, an output\n"
"     directory that does not exist or is not writable (checked before rendering)\n"
"\n"
"Examples:\n"
"  caustic render --spp 64 -o box.png\n"
"  caustic render scenes/cornell-box.json --time 60 --threads 8 -o box.exr\n"
"  caustic render scene.json --width=1920 --height=1080 --integrator=path-nee\n"
"  caustic bench rays ../shared/meshes/bunny.ply --accel bvh,embree --json\n"
"  caustic verify --integrators path,path-nee,path-bsdf --spp 64 --map z.png\n";

void args_print_help(FILE *f) { fputs(ARGS_HELP, f); }

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

/* The long option closest to name[0..len), or NULL if none is plausibly meant. */
static const char *args_suggest_option(const char *name, size_t len)
{
    const char *best = NULL;
    size_t best_d = 3; /* suggest only within two edits */
    for (size_t i = 0; i < ARGS_NUM_OPTS; i++) {
        size_t d = args_edit_distance(name, len, ARGS_OPTS[i].long_name);
        if (d < best_d && d < strlen(ARGS_OPTS[i].long_name)) {
            best_d = d;
            best = ARGS_OPTS[i].long_name;
        }
    }
    return best;
}

static void args_fail_unknown_option(ArgsError *err, const char *arg, const char *name,
                                     size_t len)
{
    const char *s = args_suggest_option(name, len);
    if (s)
        args_fail(err, true, "unknown option '%s' (did you mean --%s?)", arg, s);
    else
        args_fail(err, true, "unknown option '%s'", arg);
}

/* ------------------------------------------------------------ option values */

static bool args_apply(const ArgsOptSpec *o, const char *value, CliArgs *out, ArgsError *err)
{
    CstRenderSettings *s = &out->settings;
    long v;
    switch (o->id) {
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
            strcmp(value, "list") && strcmp(value, "embree")) {
            args_fail(err, false, "--accel: unknown acceleration structure '%s' (valid: %s)", value,
                      ARGS_ACCEL_NAMES);
            return false;
        }
        out->accel = value;
        return true;
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
    case ARGS_OPT_AOV: {
        char bad[64];
        if (!args_parse_aovs(value, &s->aovs, bad, sizeof bad)) {
            args_fail(err, false, "--aov: unknown AOV '%s' in '%s' (valid: a comma-separated list of %s)",
                      bad, value, ARGS_AOV_NAMES);
            return false;
        }
        return true;
    }
    case ARGS_OPT_CROP: {
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
    case ARGS_OPT_MAX_DEPTH:
        if (!args_parse_long(value, 0, INT_MAX, &v)) {
            args_fail(err, false, "--max-depth: expected an integer from 0 (unbounded) to %d, got '%s'",
                      INT_MAX, value);
            return false;
        }
        s->max_depth = (int)v; /* 0 is a value: unbounded, even over the scene's limit */
        return true;
    case ARGS_OPT_QUIET:
        out->quiet = true;
        return true;
    case ARGS_OPT_HELP:
        out->command = ARGS_CMD_RENDER_HELP;
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
        const char *arg = argv[i];
        const ArgsOptSpec *o = NULL;
        const char *value = NULL;

        if (only_positional || arg[0] != '-' || arg[1] == '\0') {
            if (out->scene_path) {
                args_fail(err, true, "unexpected argument '%s' (only one SCENE may be given)",
                          arg);
                return false;
            }
            out->scene_path = arg;
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            only_positional = true;
            continue;
        }
        if (arg[1] == '-') { /* --name, --name=value, --name value */
            const char *name = arg + 2;
            const char *eq = strchr(name, '=');
            size_t len = eq ? (size_t)(eq - name) : strlen(name);
            for (size_t k = 0; k < ARGS_NUM_OPTS; k++)
                if (strlen(ARGS_OPTS[k].long_name) == len &&
                    strncmp(ARGS_OPTS[k].long_name, name, len) == 0)
                    o = &ARGS_OPTS[k];
            if (!o) {
                if (len == 7 && strncmp(name, "version", 7) == 0) {
                    args_fail(err, true, "--version is not an option of 'render'");
                    return false;
                }
                args_fail_unknown_option(err, arg, name, len);
                return false;
            }
            if (eq && !o->takes_value) {
                args_fail(err, true, "--%s does not take a value (got '%s')", o->long_name,
                          arg);
                return false;
            }
            value = eq ? eq + 1 : NULL;
        } else { /* -o OUT, -oOUT, -q, -h */
            for (size_t k = 0; k < ARGS_NUM_OPTS; k++)
                if (ARGS_OPTS[k].short_name == arg[1])
                    o = &ARGS_OPTS[k];
            if (!o || (!o->takes_value && arg[2] != '\0')) {
                args_fail(err, true, "unknown option '%s'", arg);
                return false;
            }
            value = arg[2] != '\0' ? arg + 2 : NULL;
        }
        if (o->takes_value && !value) {
            if (i + 1 >= argc) {
                args_fail(err, true, "--%s: missing value", o->long_name);
                return false;
            }
            value = argv[++i]; /* taken even if it starts with '-': "--seed -1" fails clearly */
        }
        if (!args_apply(o, value, out, err))
            return false;
    }
    return true;
}

/* ------------------------------------------------------------ caustic bench rays */

typedef struct ArgsBenchOpt {
    const char *long_name;
    bool takes_value;
} ArgsBenchOpt;

static const ArgsBenchOpt ARGS_BENCH_OPTS[] = {
    {"cornell", false}, {"stadium", false}, {"accel", true},
    {"threads", true},  {"json", false},    {"help", false},
};
#define ARGS_NUM_BENCH_OPTS (sizeof ARGS_BENCH_OPTS / sizeof ARGS_BENCH_OPTS[0])

static const char *const ARGS_BENCH_ACCELS[] = {"bvh", "kdtree", "grid", "list", "embree", ARGS_EMBREE_ROBUST};
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
        const char *arg = argv[i];
        if (only_positional || arg[0] != '-' || arg[1] == '\0') {
            if (b->mesh_path) {
                args_fail(err, true, "unexpected argument '%s' (only one MESH may be given)", arg);
                return false;
            }
            b->mesh_path = arg;
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            only_positional = true;
            continue;
        }
        if (strcmp(arg, "-h") == 0) {
            out->command = ARGS_CMD_HELP;
            continue;
        }
        const char *name = arg + 2, *eq = strchr(name, '=');
        size_t len = eq ? (size_t)(eq - name) : strlen(name);
        const ArgsBenchOpt *o = NULL;
        if (arg[1] == '-')
            for (size_t k = 0; k < ARGS_NUM_BENCH_OPTS; k++)
                if (strlen(ARGS_BENCH_OPTS[k].long_name) == len &&
                    strncmp(ARGS_BENCH_OPTS[k].long_name, name, len) == 0)
                    o = &ARGS_BENCH_OPTS[k];
        if (!o) {
            const char *best = NULL;
            size_t best_d = 3;
            for (size_t k = 0; arg[1] == '-' && k < ARGS_NUM_BENCH_OPTS; k++) {
                size_t d = args_edit_distance(name, len, ARGS_BENCH_OPTS[k].long_name);
                if (d < best_d && d < strlen(ARGS_BENCH_OPTS[k].long_name)) {
                    best_d = d;
                    best = ARGS_BENCH_OPTS[k].long_name;
                }
            }
            if (best)
                args_fail(err, true, "unknown option '%s' for 'bench rays' (did you mean --%s?)", arg, best);
            else
                args_fail(err, true, "unknown option '%s' for 'bench rays'", arg);
            return false;
        }
        if (eq && !o->takes_value) {
            args_fail(err, true, "--%s does not take a value (got '%s')", o->long_name, arg);
            return false;
        }
        const char *value = eq ? eq + 1 : NULL;
        if (o->takes_value && !value) {
            if (i + 1 >= argc) {
                args_fail(err, true, "--%s: missing value", o->long_name);
                return false;
            }
            value = argv[++i];
        }
        long v;
        if (strcmp(o->long_name, "cornell") == 0) {
            b->cornell = true;
        } else if (strcmp(o->long_name, "stadium") == 0) {
            b->stadium = true;
        } else if (strcmp(o->long_name, "json") == 0) {
            b->json = true;
        } else if (strcmp(o->long_name, "help") == 0) {
            out->command = ARGS_CMD_HELP;
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

typedef struct ArgsVerifyOpt {
    const char *long_name;
    char short_name;
    bool takes_value;
} ArgsVerifyOpt;

/* spp, time, threads, seed, width, height and quiet mean what they mean for render and go
 * through args_apply, so their checks and messages are the same. */
static const ArgsVerifyOpt ARGS_VERIFY_OPTS[] = {
    {"integrators", 0, true}, {"spp", 0, true},     {"time", 0, true},   {"threads", 0, true},
    {"seed", 0, true},        {"alpha", 0, true},   {"block", 0, true},  {"map", 0, true},
    {"json", 0, false},       {"width", 0, true},   {"height", 0, true}, {"quiet", 'q', false},
    {"help", 'h', false},     {"convergence", 0, true},
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

static bool args_apply_verify(const ArgsVerifyOpt *o, const char *value, CliArgs *out,
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
        const char *arg = argv[i];
        if (only_positional || arg[0] != '-' || arg[1] == '\0') {
            if (out->scene_path) {
                args_fail(err, true, "unexpected argument '%s' (only one SCENE may be given)", arg);
                return false;
            }
            out->scene_path = arg;
            continue;
        }
        if (strcmp(arg, "--") == 0) {
            only_positional = true;
            continue;
        }
        const ArgsVerifyOpt *o = NULL;
        const char *value = NULL;
        if (arg[1] == '-') { /* --name, --name=value, --name value */
            const char *name = arg + 2, *eq = strchr(name, '=');
            size_t len = eq ? (size_t)(eq - name) : strlen(name);
            for (size_t k = 0; k < ARGS_NUM_VERIFY_OPTS; k++)
                if (strlen(ARGS_VERIFY_OPTS[k].long_name) == len &&
                    strncmp(ARGS_VERIFY_OPTS[k].long_name, name, len) == 0)
                    o = &ARGS_VERIFY_OPTS[k];
            if (!o) {
                const char *best = NULL;
                size_t best_d = 3;
                for (size_t k = 0; k < ARGS_NUM_VERIFY_OPTS; k++) {
                    size_t d = args_edit_distance(name, len, ARGS_VERIFY_OPTS[k].long_name);
                    if (d < best_d && d < strlen(ARGS_VERIFY_OPTS[k].long_name)) {
                        best_d = d;
                        best = ARGS_VERIFY_OPTS[k].long_name;
                    }
                }
                if (best)
                    args_fail(err, true, "unknown option '%s' for 'verify' (did you mean --%s?)", arg, best);
                else
                    args_fail(err, true, "unknown option '%s' for 'verify'", arg);
                return false;
            }
            if (eq && !o->takes_value) {
                args_fail(err, true, "--%s does not take a value (got '%s')", o->long_name, arg);
                return false;
            }
            value = eq ? eq + 1 : NULL;
        } else { /* -q, -h */
            for (size_t k = 0; k < ARGS_NUM_VERIFY_OPTS; k++)
                if (ARGS_VERIFY_OPTS[k].short_name == arg[1] && arg[2] == '\0')
                    o = &ARGS_VERIFY_OPTS[k];
            if (!o) {
                args_fail(err, true, "unknown option '%s' for 'verify'", arg);
                return false;
            }
        }
        if (o->takes_value && !value) {
            if (i + 1 >= argc) {
                args_fail(err, true, "--%s: missing value", o->long_name);
                return false;
            }
            value = argv[++i]; /* taken even if it starts with '-', as for render */
        }
        if (!args_apply_verify(o, value, out, err))
            return false;
    }
    if (out->command == ARGS_CMD_VERIFY && v->num_integrators == 0) {
        args_fail(err, true, "verify: --integrators is required (e.g. --integrators path,path-nee)");
        return false;
    }
    return true;
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
    if (strcmp(cmd, "--help") == 0 || strcmp(cmd, "-h") == 0 || strcmp(cmd, "help") == 0) {
        out->command = ARGS_CMD_HELP;
    } else if (strcmp(cmd, "--version") == 0) {
        out->command = ARGS_CMD_VERSION;
    } else if (strcmp(cmd, "render") == 0) {
        out->command = ARGS_CMD_RENDER;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "info") == 0) {
        out->command = ARGS_CMD_INFO;
        return args_parse_render(argc, argv, 2, out, err);
    } else if (strcmp(cmd, "bench") == 0) {
        return args_parse_bench(argc, argv, out, err);
    } else if (strcmp(cmd, "verify") == 0) {
        out->command = ARGS_CMD_VERIFY;
        return args_parse_verify(argc, argv, 2, out, err);
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
        else
            args_fail(err, true, "unknown command '%s' (commands: render, info, bench, verify)", cmd);
        return false;
    }
    if (argc > 2) {
        args_fail(err, true, "unexpected argument '%s' after %s", argv[2], cmd);
        return false;
    }
    return true;
}
