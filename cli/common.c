/* The CLI's shared helpers: exit codes, error printing, output and scene path checks,
 * scene loading with --accel, and the progress display on stderr. */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <time.h>
#include <unistd.h>

#include "cli.h"

double cli_clock_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* Maps a library status to an exit code. Scene I/O errors (missing, unreadable file) are
 * the user's; an I/O error while rendering or writing, after main() has checked the
 * output directory, is the environment's (disk full, file system failure). */
int cli_exit_code(CstStatus status, CliStage stage)
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
    case CST_ERR_CANCELLED: /* the CLI never cancels */
    case CST_ERR_NONFINITE: /* the render ran and failed: like a failed check, 1 */
        return CLI_EXIT_INTERNAL;
    }
    return CLI_EXIT_INTERNAL;
}

void cli_print_error(const CstError *err, CstStatus status)
{
    fprintf(stderr, "caustic: error: %s\n",
            err->msg[0] ? err->msg : cst_status_name(status));
}

/* ------------------------------------------------------------ paths */

bool cli_has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && strcasecmp(s + n - m, suffix) == 0;
}

static bool cli_output_format_ok(const char *path)
{
    return cst_image_path_writable(path);
}

/* Checks, before any rendering, that `path` has a supported extension and names a file
 * in an existing, writable directory, so a long render is never thrown away at the end.
 * `origin` says where the path came from, for the message. */
bool cli_check_output(const char *path, const char *origin)
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


/* ------------------------------------------------------------ progress */


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

/* CstProgressFn: called from the rendering (calling) thread about ten times a second.
 * Returns 0: the CLI never cancels a render. */
int cli_progress_report(void *user, double fraction, double elapsed)
{
    CliProgress *p = user;
    if (!(fraction >= 0.0))
        fraction = 0.0;
    if (fraction > 1.0)
        fraction = 1.0;
    if (p->tty) {
        cli_progress_draw(p, fraction, elapsed);
        return 0;
    }
    /* A long gap between calls may cross several steps; print only the latest. */
    int step = (int)(fraction * 10.0 + 1e-9);
    if (step > p->last_step) {
        p->last_step = step;
        fprintf(stderr, "caustic: %d%% (elapsed %.1f s)\n", step * 10, elapsed);
    }
    return 0;
}

/* After a successful render: complete the bar, or the 100% line if the library's last
 * report fell short of it (a very short render may not report at all). */
void cli_progress_finish(CliProgress *p, double seconds)
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
void cli_progress_abort(CliProgress *p)
{
    if (p->tty && p->drawn) {
        fputc('\n', stderr);
        p->drawn = false;
    }
}

/* ------------------------------------------------------------ scenes */

/* The scene argument's format, checkable before anything is loaded. */
bool cli_check_scene_path(const CliArgs *a)
{
    if (a->scene_path && !cli_has_suffix(a->scene_path, ".json") &&
        !cli_has_suffix(a->scene_path, ".pbrt")) {
        fprintf(stderr, "caustic: error: '%s': unsupported scene format (supported: .json, "
                "a caustic JSON scene; .pbrt, a pbrt-v4 scene; omit SCENE for the built-in "
                "Cornell box)\n",
                a->scene_path);
        return false;
    }
    return true;
}

/* Loader warnings (pbrt scenes): printed as they come; a long list is cut after the
 * first CLI_MAX_WARNINGS with a count of the rest, printed by cli_load_scene. */
#define CLI_MAX_WARNINGS 50
static void cli_print_warning(void *user, CstWarningCode code, const char *message)
{
    (void)code;
    int *count = user;
    if (++*count <= CLI_MAX_WARNINGS)
        fprintf(stderr, "caustic: warning: %s\n", message);
}

/* Loads SCENE, or builds the built-in Cornell box, and applies --accel. Returns an exit
 * code: CLI_EXIT_OK with *out set, else the error has been printed and *out is NULL.
 * *read_seconds (may be NULL) gets the loader's time without the scene's own accel build:
 * parsing and mesh import, which is what `info` reports as the load time. */
int cli_load_scene(const CliArgs *a, CstScene **out, double *read_seconds)
{
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus status;
    *out = NULL;
    double t0 = cli_clock_seconds();
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
        if (cli_has_suffix(a->scene_path, ".pbrt")) {
            int warnings = 0;
            CstLoadOptions opt = {0};
            opt.warning = cli_print_warning;
            opt.warning_user = &warnings;
            status = cst_scene_load_pbrt(a->scene_path, &opt, &scene, &err);
            if (warnings > CLI_MAX_WARNINGS)
                fprintf(stderr, "caustic: warning: %d more warnings not shown\n",
                        warnings - CLI_MAX_WARNINGS);
        } else {
            status = cst_scene_load_json(a->scene_path, &scene, &err);
        }
    } else {
        status = cst_scene_create_cornell_box(&scene, &err);
    }
    if (status != CST_OK) {
        cli_print_error(&err, status);
        cst_scene_destroy(scene);
        /* Nothing the user wrote can break the built-in scene. */
        return a->scene_path ? cli_exit_code(status, CLI_STAGE_LOAD) : CLI_EXIT_INTERNAL;
    }
    if (read_seconds) {
        CstSceneInfo in;
        cst_scene_info(scene, &in);
        *read_seconds = cli_clock_seconds() - t0 - in.accel_build_seconds;
    }
    if (a->accel) {
        status = cst_scene_set_accel(scene, a->accel, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            cst_scene_destroy(scene);
            return cli_exit_code(status, CLI_STAGE_LOAD);
        }
    }
    *out = scene;
    return CLI_EXIT_OK;
}

