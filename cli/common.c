/* The CLI's shared helpers: exit codes, error printing, output and scene path checks,
 * scene loading with --accel (the progress display is in progress.c). */
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

/* A pbrt-v4 scene: "x.pbrt", or "x.pbrt.gz" (the library inflates it, as pbrt-v4 does). */
bool cli_is_pbrt_path(const char *s)
{
    return cli_has_suffix(s, ".pbrt") || cli_has_suffix(s, ".pbrt.gz");
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
    /* access() does not know every refusal (a name too long for the temporary file, /sys
     * and /proc for root): the library creates and removes the very temporary file the
     * write will use. */
    CstError err = {0};
    if (cst_image_write_check(path, &err) != CST_OK) {
        fprintf(stderr, "caustic: error: %s: %s\n", origin, err.msg);
        return false;
    }
    return true;
}


/* ------------------------------------------------------------ scenes */

/* The scene argument's format, checkable before anything is loaded. */
bool cli_check_scene_path(const CliArgs *a)
{
    if (a->scene_path && !cli_has_suffix(a->scene_path, ".json") && !cli_is_pbrt_path(a->scene_path)) {
        fprintf(stderr, "caustic: error: '%s': unsupported scene format (supported: .json, "
                "a caustic JSON scene; .pbrt or .pbrt.gz, a pbrt-v4 scene, gzip-compressed or "
                "not; omit SCENE for the built-in Cornell box)\n",
                a->scene_path);
        return false;
    }
    return true;
}

/* Loader warnings (pbrt's approximations, a JSON mesh's missing .mtl): printed as they
 * come; a long list is cut after the first CLI_MAX_WARNINGS with a count of the rest,
 * printed by cli_load_scene. */
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
        int warnings = 0;
        CstLoadOptions opt = {0};
        opt.warning = cli_print_warning;
        opt.warning_user = &warnings;
        if (cli_is_pbrt_path(a->scene_path))
            status = cst_scene_load_pbrt(a->scene_path, &opt, &scene, &err);
        else
            status = cst_scene_load_json_opt(a->scene_path, &opt, &scene, &err);
        if (warnings > CLI_MAX_WARNINGS)
            fprintf(stderr, "caustic: warning: %d more warnings not shown\n",
                    warnings - CLI_MAX_WARNINGS);
    } else {
        status = cst_scene_create_cornell_box(&scene, &err);
    }
    if (status != CST_OK) {
        cli_print_error(&err, status);
        cst_scene_destroy(scene);
        /* Nothing the user wrote can break the built-in scene. */
        return a->scene_path ? cli_exit_code(status, CLI_STAGE_LOAD) : CLI_EXIT_INTERNAL;
    }
    CstSceneInfo in;
    cst_scene_info(scene, &in);
    if (read_seconds)
        *read_seconds = cli_clock_seconds() - t0 - in.accel_build_seconds;
    if (in.lights == 0 && in.emitting_media == 0)
        fprintf(stderr, "caustic: warning: %s has no light: no emitting shape or medium, no point, spot or "
                "directional light and no environment, so every image of it is black\n",
                a->scene_path ? a->scene_path : "the scene");
    if (a->accel) {
        status = cst_scene_set_accel(scene, a->accel, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            cst_scene_destroy(scene);
            return cli_exit_code(status, CLI_STAGE_LOAD);
        }
    }
    if (a->light_sampler) {
        status = cst_scene_set_light_sampler(scene, a->light_sampler, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            cst_scene_destroy(scene);
            return cli_exit_code(status, CLI_STAGE_LOAD);
        }
    }
    if (a->light_sampling) {
        status = cst_scene_set_light_sampling(scene, a->light_sampling, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            cst_scene_destroy(scene);
            return cli_exit_code(status, CLI_STAGE_LOAD);
        }
    }
    *out = scene;
    return CLI_EXIT_OK;
}

