/* caustic: the command-line front end. Parses arguments (args.c), builds or loads the
 * scene, renders with progress on stderr and writes the image. The only place in the
 * project that turns a CstStatus into an exit code (see docs/cli.md). */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <inttypes.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include "args.h"
#include "caustic/caustic.h"

/* Exit codes: the contract with scripts, documented in --help and docs/cli.md. */
#define CLI_EXIT_OK       0
#define CLI_EXIT_INTERNAL 1 /* not the user's fault: OOM, library failure, I/O while writing */
#define CLI_EXIT_USAGE    2 /* bad command line, bad scene file, unusable output path */

#define CLI_BUILTIN_OUTPUT "cornell-box.png"

/* Where a library call failed; an I/O error means a different thing at each stage. */
typedef enum CliStage { CLI_STAGE_LOAD, CLI_STAGE_RENDER, CLI_STAGE_WRITE } CliStage;

/* Maps a library status to an exit code. Scene I/O errors (missing, unreadable file) are
 * the user's; an I/O error while rendering or writing, after main() has checked the
 * output directory, is the environment's (disk full, file system failure). */
static int cli_exit_code(CstStatus status, CliStage stage)
{
    switch (status) {
    case CST_OK:
        return CLI_EXIT_OK;
    case CST_ERR_INVALID_ARG:
    case CST_ERR_PARSE:
    case CST_ERR_UNSUPPORTED:
        return CLI_EXIT_USAGE;
    case CST_ERR_IO:
        return stage == CLI_STAGE_LOAD ? CLI_EXIT_USAGE : CLI_EXIT_INTERNAL;
    case CST_ERR_OOM:
    case CST_ERR_INTERNAL:
        return CLI_EXIT_INTERNAL;
    }
    return CLI_EXIT_INTERNAL;
}

static void cli_print_error(const CstError *err, CstStatus status)
{
    fprintf(stderr, "caustic: error: %s\n",
            err->msg[0] ? err->msg : cst_status_name(status));
}

/* ------------------------------------------------------------ paths */

static bool cli_has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

static bool cli_output_format_ok(const char *path)
{
    return cli_has_suffix(path, ".png") || cli_has_suffix(path, ".exr") ||
           cli_has_suffix(path, ".pfm");
}

/* Checks, before any rendering, that `path` has a supported extension and names a file
 * in an existing, writable directory, so a long render is never thrown away at the end.
 * `origin` says where the path came from, for the message. */
static bool cli_check_output(const char *path, const char *origin)
{
    if (!cli_output_format_ok(path)) {
        fprintf(stderr, "caustic: error: %s '%s': unsupported image format (supported: %s)\n",
                origin, path, ARGS_OUTPUT_FORMATS);
        return false;
    }
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        fprintf(stderr, "caustic: error: %s '%s' is a directory\n", origin, path);
        return false;
    }
    /* The writer creates a temporary file next to `path`, then renames it: what must be
     * writable is the directory. */
    char dir[4096];
    const char *slash = strrchr(path, '/');
    if (!slash) {
        strcpy(dir, ".");
    } else {
        size_t n = slash == path ? 1 : (size_t)(slash - path);
        if (n >= sizeof dir) {
            fprintf(stderr, "caustic: error: %s '%s': path too long\n", origin, path);
            return false;
        }
        memcpy(dir, path, n);
        dir[n] = '\0';
    }
    if (stat(dir, &st) != 0) {
        fprintf(stderr, "caustic: error: %s '%s': directory '%s': %s\n", origin, path, dir,
                strerror(errno));
        return false;
    }
    if (!S_ISDIR(st.st_mode)) {
        fprintf(stderr, "caustic: error: %s '%s': '%s' is not a directory\n", origin, path,
                dir);
        return false;
    }
    if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "caustic: error: %s '%s': directory '%s' is not writable: %s\n",
                origin, path, dir, strerror(errno));
        return false;
    }
    return true;
}

/* "<stem of the scene file>.png" in the current directory; "scene.png" if the stem is
 * empty. Returns false if it does not fit. */
static bool cli_default_output(const char *scene_path, char *buf, size_t size)
{
    const char *base = strrchr(scene_path, '/');
    base = base ? base + 1 : scene_path;
    size_t stem = strlen(base);
    const char *dot = strrchr(base, '.');
    if (dot)
        stem = (size_t)(dot - base);
    int n = stem ? snprintf(buf, size, "%.*s.png", (int)stem, base)
                 : snprintf(buf, size, "scene.png");
    return n > 0 && (size_t)n < size;
}

/* ------------------------------------------------------------ progress */

typedef struct CliProgress {
    bool tty;      /* redraw a bar in place; otherwise one line per 10% */
    int last_step; /* plain mode: the last 10% step printed, 0..10 */
    int last_len;  /* bar mode: characters of the last line drawn, to blank leftovers */
    bool drawn;    /* bar mode: a bar is on screen without its newline */
} CliProgress;

/* m:ss, or h:mm:ss from one hour on. */
static void cli_format_clock(double seconds, char *buf, size_t size)
{
    if (!(seconds >= 0.0) || seconds > 359999.0) {
        snprintf(buf, size, "--:--");
        return;
    }
    long s = (long)(seconds + 0.5);
    if (s >= 3600)
        snprintf(buf, size, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else
        snprintf(buf, size, "%ld:%02ld", s / 60, s % 60);
}

static void cli_progress_draw(CliProgress *p, double fraction, double elapsed)
{
    enum { BAR = 30 };
    char line[160], eta[32], el[32];
    int filled = (int)(fraction * BAR);
    /* The first instants extrapolate badly; show no ETA until there is something to go on. */
    if (fraction > 0.0 && fraction < 1.0 && elapsed >= 0.5)
        cli_format_clock(elapsed * (1.0 - fraction) / fraction, eta, sizeof eta);
    else if (fraction >= 1.0)
        cli_format_clock(0.0, eta, sizeof eta);
    else
        snprintf(eta, sizeof eta, "--:--");
    cli_format_clock(elapsed, el, sizeof el);

    int n = snprintf(line, sizeof line, "\r[%.*s%.*s] %3d%%  ETA %s  elapsed %s",
                     filled, "##############################",
                     BAR - filled, "..............................",
                     (int)(fraction * 100.0), eta, el);
    if (n < 0)
        return;
    if (n >= (int)sizeof line)
        n = (int)sizeof line - 1;
    int len = n - 1; /* without the '\r' */
    fputs(line, stderr);
    if (len < p->last_len)
        fprintf(stderr, "%*s", p->last_len - len, "");
    fflush(stderr);
    p->last_len = len;
    p->drawn = true;
}

/* CstProgressFn: called from the rendering (calling) thread about ten times a second. */
static void cli_progress_report(void *user, double fraction, double elapsed)
{
    CliProgress *p = user;
    if (!(fraction >= 0.0))
        fraction = 0.0;
    if (fraction > 1.0)
        fraction = 1.0;
    if (p->tty) {
        cli_progress_draw(p, fraction, elapsed);
        return;
    }
    /* A long gap between calls may cross several steps; print only the latest. */
    int step = (int)(fraction * 10.0 + 1e-9);
    if (step > p->last_step) {
        p->last_step = step;
        fprintf(stderr, "caustic: %d%% (elapsed %.1f s)\n", step * 10, elapsed);
    }
}

/* After a successful render: complete the bar, or the 100% line if the library's last
 * report fell short of it (a very short render may not report at all). */
static void cli_progress_finish(CliProgress *p, double seconds)
{
    if (p->tty) {
        cli_progress_draw(p, 1.0, seconds);
        fputc('\n', stderr);
        p->drawn = false;
    } else if (p->last_step < 10) {
        p->last_step = 10;
        fprintf(stderr, "caustic: 100%% (elapsed %.1f s)\n", seconds);
    }
}

/* After a failed render: end the bar's line so the error message starts on its own. */
static void cli_progress_abort(CliProgress *p)
{
    if (p->tty && p->drawn) {
        fputc('\n', stderr);
        p->drawn = false;
    }
}

/* ------------------------------------------------------------ job and summary lines */

/* "N M", "N.N M" or "N.NN M" per second: three significant digits from 1 M/s on. */
static void cli_format_rate(double count, double seconds, char *buf, size_t size)
{
    double m = count / seconds / 1e6;
    snprintf(buf, size, m >= 100.0 ? "%.0f" : m >= 10.0 ? "%.1f" : "%.2f", m);
}

/* One line describing the job, with the settings the render will really use. */
static void cli_print_job(const CliArgs *a, const CstScene *scene, const CstRenderSettings *settings,
                          const char *output)
{
    CstRenderSettings s;
    cst_render_settings_resolve(scene, settings, &s);
    char work[96];
    if (s.spp && s.time_limit > 0.0)
        snprintf(work, sizeof work, "%d spp or %g s, whichever comes first", s.spp, s.time_limit);
    else if (s.time_limit > 0.0)
        snprintf(work, sizeof work, "time limit %g s", s.time_limit);
    else
        snprintf(work, sizeof work, "%d spp", s.spp);
    fprintf(stderr, "caustic: rendering %s (%dx%d, %s, %s, %s filter, %d thread%s) to %s\n",
            a->scene_path ? a->scene_path : "the built-in Cornell box", s.width, s.height, work,
            cst_integrator_name(s.integrator), cst_filter_name(s.filter), s.threads,
            s.threads == 1 ? "" : "s", output);
}

/* `caustic info`: what the scene holds and what its acceleration structure costs. */
static void cli_print_info(const CliArgs *a, const CstScene *scene)
{
    CstSceneInfo in;
    cst_scene_info(scene, &in);
    printf("scene:       %s\n", a->scene_path ? a->scene_path : "built-in Cornell box");
    printf("triangles:   %d\n", in.triangles);
    printf("spheres:     %d\n", in.spheres);
    printf("emitters:    %d\n", in.emitters);
    printf("materials:   %d\n", in.materials);
    printf("accel:       %s\n", in.accel);
    printf("build:       %.2f ms\n", in.accel_build_seconds * 1e3);
    printf("memory:      %zu bytes", in.accel_bytes);
    int prims = in.triangles + in.spheres;
    if (prims > 0) printf(" (%.1f bytes per primitive)", (double)in.accel_bytes / prims);
    printf("\n");
}

static void cli_print_summary(const char *output, const CstRenderStats *st)
{
    char line[512];
    int n = snprintf(line, sizeof line, "caustic: wrote %s: %dx%d, %d spp, %s, %d thread%s, %.2f s",
                     output, st->width, st->height, st->spp,
                     cst_integrator_name(st->integrator), st->threads,
                     st->threads == 1 ? "" : "s", st->seconds);
    if (n > 0 && (size_t)n < sizeof line && st->seconds > 0.0) {
        char samples[32], rays[32];
        cli_format_rate((double)st->samples, st->seconds, samples, sizeof samples);
        cli_format_rate((double)st->rays, st->seconds, rays, sizeof rays);
        snprintf(line + n, sizeof line - (size_t)n, ", %s M samples/s, %s M rays/s", samples,
                 rays);
    }
    fprintf(stderr, "%s\n", line);
}

/* ------------------------------------------------------------ commands */

static int cli_render(const CliArgs *a)
{
    int code = CLI_EXIT_INTERNAL;
    CstScene *scene = NULL;
    CstFilm *film = NULL;
    CstError err = {0};
    CstStatus status;
    char default_output[4096];
    const char *output = a->output_path;
    CliProgress progress = {.tty = isatty(STDERR_FILENO) == 1};
    CstRenderSettings settings = a->settings;
    CstRenderStats stats = {0};

    /* Everything checkable from the command line alone, before the scene is loaded. */
    if (a->scene_path && !cli_has_suffix(a->scene_path, ".json")) {
        fprintf(stderr, "caustic: error: '%s': unsupported scene format (supported: .json, "
                "a caustic JSON scene; omit SCENE for the built-in Cornell box)\n",
                a->scene_path);
        return CLI_EXIT_USAGE;
    }
    if (output && !cli_check_output(output, "output"))
        return CLI_EXIT_USAGE;

    if (a->scene_path) {
        struct stat st;
        if (stat(a->scene_path, &st) != 0) {
            fprintf(stderr, "caustic: error: cannot open scene '%s': %s\n", a->scene_path,
                    strerror(errno));
            return CLI_EXIT_USAGE;
        }
        if (S_ISDIR(st.st_mode)) {
            fprintf(stderr, "caustic: error: scene '%s' is a directory\n", a->scene_path);
            return CLI_EXIT_USAGE;
        }
        status = cst_scene_load_json(a->scene_path, &scene, &err);
    } else {
        status = cst_scene_create_cornell_box(&scene, &err);
    }
    if (status != CST_OK) {
        cli_print_error(&err, status);
        /* Nothing the user wrote can break the built-in scene. */
        code = a->scene_path ? cli_exit_code(status, CLI_STAGE_LOAD) : CLI_EXIT_INTERNAL;
        goto done;
    }
    if (a->accel) {
        status = cst_scene_set_accel(scene, a->accel, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            code = cli_exit_code(status, CLI_STAGE_LOAD);
            goto done;
        }
    }
    if (a->command == ARGS_CMD_INFO) {
        cli_print_info(a, scene);
        code = CLI_EXIT_OK;
        goto done;
    }

    if (!output) {
        const char *from_scene = cst_scene_output_path(scene);
        if (from_scene) {
            output = from_scene;
            if (!cli_check_output(output, "the scene's output")) {
                fprintf(stderr, "caustic: use -o to write somewhere else\n");
                code = CLI_EXIT_USAGE;
                goto done;
            }
        } else {
            if (!a->scene_path)
                snprintf(default_output, sizeof default_output, "%s", CLI_BUILTIN_OUTPUT);
            else if (!cli_default_output(a->scene_path, default_output, sizeof default_output)) {
                fprintf(stderr, "caustic: error: scene path too long: '%s'\n", a->scene_path);
                code = CLI_EXIT_USAGE;
                goto done;
            }
            output = default_output;
            if (!cli_check_output(output, "output")) {
                code = CLI_EXIT_USAGE;
                goto done;
            }
        }
    }

    if (!a->quiet) {
        settings.progress = cli_progress_report;
        settings.progress_user = &progress;
        cli_print_job(a, scene, &settings, output);
    }

    status = cst_render(scene, &settings, &film, &stats, &err);
    if (status != CST_OK) {
        if (!a->quiet)
            cli_progress_abort(&progress);
        cli_print_error(&err, status);
        code = cli_exit_code(status, CLI_STAGE_RENDER);
        goto done;
    }
    if (!a->quiet)
        cli_progress_finish(&progress, stats.seconds);

    status = cst_film_write(film, output, &err);
    if (status != CST_OK) {
        cli_print_error(&err, status);
        code = cli_exit_code(status, CLI_STAGE_WRITE);
        goto done;
    }
    if (!a->quiet)
        cli_print_summary(output, &stats);
    if (stats.nonfinite > 0)
        fprintf(stderr, "caustic: warning: %" PRIu64 " NaN/Inf samples discarded "
                "(%.3g%% of %" PRIu64 "; counted, never added to the image)\n",
                stats.nonfinite,
                stats.samples ? 100.0 * (double)stats.nonfinite / (double)stats.samples : 0.0,
                stats.samples);
    code = CLI_EXIT_OK;

done:
    cst_film_destroy(film);
    cst_scene_destroy(scene);
    return code;
}

/* Help and version go to stdout; a failed write there (a closed pipe, a full disk) is an
 * error like any other. */
static int cli_finish_stdout(void)
{
    if (fflush(stdout) != 0 || ferror(stdout)) {
        fprintf(stderr, "caustic: error: writing to standard output: %s\n", strerror(errno));
        return CLI_EXIT_INTERNAL;
    }
    return CLI_EXIT_OK;
}

int main(int argc, char **argv)
{
    CliArgs args;
    ArgsError aerr;
    if (!args_parse(argc, argv, &args, &aerr)) {
        fprintf(stderr, "caustic: %s\n", aerr.msg);
        if (aerr.hint)
            fprintf(stderr, "caustic: see caustic --help\n");
        exit(CLI_EXIT_USAGE);
    }
    int code = CLI_EXIT_OK;
    switch (args.command) {
    case ARGS_CMD_HELP:
    case ARGS_CMD_RENDER_HELP:
        args_print_help(stdout);
        code = cli_finish_stdout();
        break;
    case ARGS_CMD_VERSION:
        printf("caustic %s\n", CST_VERSION_STRING);
        code = cli_finish_stdout();
        break;
    case ARGS_CMD_RENDER:
    case ARGS_CMD_INFO:
        code = cli_render(&args);
        break;
    }
    exit(code);
}
