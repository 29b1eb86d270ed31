/* caustic: the command-line front end. Parses arguments (args.c), builds or loads the
 * scene, renders with progress on stderr and writes the image; `bench rays` traces the
 * acceleration benchmark's ray sets (bench/raysets.c). The only place in the
 * project that turns a CstStatus into an exit code (see docs/cli.md). */
#define _POSIX_C_SOURCE 200809L

#include <errno.h>
#include <inttypes.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

#include "accel/accel.h"
#include "args.h"
#include "caustic/caustic.h"
#include "core/clock.h"
#include "core/rng.h"
#include "film/film_compare.h"
#include "io/image_io.h"
#include "integrators/photon.h"
#include "raysets.h"

/* Exit codes: the contract with scripts, documented in --help and docs/cli.md. */
#define CLI_EXIT_OK       0
#define CLI_EXIT_INTERNAL 1 /* not the user's fault: OOM, library failure, I/O while writing */
#define CLI_EXIT_USAGE    2 /* bad command line, bad scene file, unusable output path */
#define CLI_EXIT_MISMATCH 1 /* bench rays: a checksum did not match */
#define CLI_EXIT_DISAGREE 1 /* verify: a pair of integrators disagrees */

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
    case CST_ERR_CANCELLED: /* the CLI never cancels */
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
    return image_format_is_writable(image_format_from_path(path));
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
static int cli_progress_report(void *user, double fraction, double elapsed)
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
    return 0; /* never cancels */
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
    char crop[96] = "";
    if (s.crop[0] != 0 || s.crop[1] != s.width || s.crop[2] != 0 || s.crop[3] != s.height)
        snprintf(crop, sizeof crop, " cropped to [%d, %d) x [%d, %d)", s.crop[0], s.crop[1], s.crop[2], s.crop[3]);
    fprintf(stderr, "caustic: rendering %s (%dx%d%s, %s, %s, %s filter, %d thread%s) to %s\n",
            a->scene_path ? a->scene_path : "the built-in Cornell box", s.width, s.height, crop, work,
            cst_integrator_name(s.integrator), cst_filter_name(s.filter), s.threads,
            s.threads == 1 ? "" : "s", output);
}

/* `caustic info`: what the scene holds and what its acceleration structure costs. */
static void cli_print_info(const CliArgs *a, const CstScene *scene, double read_seconds)
{
    CstSceneInfo in;
    cst_scene_info(scene, &in);
    printf("scene:       %s\n", a->scene_path ? a->scene_path : "built-in Cornell box");
    printf("load:        %.2f ms (parsing and mesh import)\n", read_seconds * 1e3);
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
    if (in.instances > 0)
        printf("instances:   %d of %d object%s (%zu triangles), %zu bytes\n", in.instances,
               in.instanced_objects, in.instanced_objects == 1 ? "" : "s", in.instanced_triangles,
               in.instance_bytes);
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

/* ------------------------------------------------------------ scenes */

/* The scene argument's format, checkable before anything is loaded. */
static bool cli_check_scene_path(const CliArgs *a)
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
static int cli_load_scene(const CliArgs *a, CstScene **out, double *read_seconds)
{
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus status;
    *out = NULL;
    double t0 = clock_seconds();
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
        *read_seconds = clock_seconds() - t0 - in.accel_build_seconds;
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
    if (!cli_check_scene_path(a))
        return CLI_EXIT_USAGE;
    if (output && !cli_check_output(output, "output"))
        return CLI_EXIT_USAGE;

    double read_seconds = 0.0;
    code = cli_load_scene(a, &scene, &read_seconds);
    if (code != CLI_EXIT_OK)
        return code;
    code = CLI_EXIT_INTERNAL;
    if (a->command == ARGS_CMD_INFO) {
        cli_print_info(a, scene, read_seconds);
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

    {
        /* AOVs are EXR channels: refused before rendering, not after. */
        CstRenderSettings rs;
        cst_render_settings_resolve(scene, &settings, &rs);
        if (rs.aovs && !image_path_is_exr(output)) {
            fprintf(stderr, "caustic: error: output '%s': AOVs (--aov or the scene's \"aovs\") are "
                            "written as extra EXR channels; expected an output ending in .exr\n", output);
            code = CLI_EXIT_USAGE;
            goto done;
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

/* ------------------------------------------------------------ caustic bench rays */

/* Back ends run by default: brute force only where it finishes in seconds. */
#define CLI_BENCH_LIST_MAX_TRIS 1000
/* --stadium alone: a 20,480-triangle bumpy ball as the teapot. */
#define CLI_BENCH_BALL_LEVELS 5
/* Each figure is the best of up to this many runs, repeated while under a second in all. */
#define CLI_BENCH_MAX_REPEATS 5
#define CLI_BENCH_REPEAT_SECONDS 1.0

enum { BENCH_PRIMARY, BENCH_SECONDARY, BENCH_OCCLUSION, BENCH_NUM_SETS };
static const char *const BENCH_SET_NAMES[BENCH_NUM_SETS] = {"primary", "secondary", "occlusion"};

/* A back end of the benchmark: an acceleration structure, and for Embree which mode. */
typedef struct BenchBackend {
    AccelType type;
    bool robust; /* Embree in its robust mode (EMBREE_NATIVE_ROBUST) */
} BenchBackend;

static const char *cli_bench_name(BenchBackend b)
{
    return b.type == ACCEL_EMBREE && b.robust ? ARGS_EMBREE_ROBUST : accel_type_name(b.type);
}

static bool cli_bench_same(BenchBackend a, BenchBackend b) { return a.type == b.type && a.robust == b.robust; }

typedef struct BenchRow {
    BenchBackend accel;
    double build_ms, bytes_per_tri;
    int set, threads;
    RaysetStats st; /* of the fastest run */
    int runs;
    bool checked, ok;   /* checked: there was something to compare with */
    const char *against; /* "reference", the back end compared with, or "1 thread" */
    double vs_embree;   /* M rays/s ratio to Embree's row; < 0 when there is none */
    double vs_robust;   /* the same against Embree's robust mode */
    /* Scenes without a reference, 1-thread rows of all but the first back end: the rays
     * whose result differs from the first back end's (rayset_compare). */
    bool compared;
    size_t rays_differing;
    double dt_sum;
} BenchRow;

typedef struct BenchRays {
    const Ray *rays[BENCH_NUM_SETS];
    size_t count[BENCH_NUM_SETS];
} BenchRays;

static double cli_bench_mrays(const RaysetStats *st)
{
    return st->seconds > 0.0 ? (double)st->rays / st->seconds / 1e6 : 0.0;
}

/* The expected (hits, sum t) of a set from RAYSETS.md's reference row. */
static void cli_bench_expected(const RaysetReference *ref, int set, size_t *hits, double *sum_t)
{
    *hits = set == BENCH_PRIMARY ? ref->primary_hits : ref->secondary_hits;
    *sum_t = set == BENCH_PRIMARY ? ref->primary_sum_t : ref->secondary_sum_t;
}

/* Checks every row. With a reference row (RAYSETS.md): hits, ray counts and sum t against
 * it. Without: each back end's 1-thread rows against the first back end's, ray by ray (at
 * most a handful of rays may differ, and they must explain the sum-t difference). Every
 * N-thread row must equal the same back end's 1-thread row exactly. */
static void cli_bench_check(BenchRow *rows, int n, const RaysetReference *ref, bool published_bounces)
{
    for (int i = 0; i < n; i++) {
        BenchRow *r = &rows[i];
        bool any = r->set == BENCH_OCCLUSION;
        r->ok = true;
        r->checked = false;
        if (ref) {
            size_t hits;
            double sum_t;
            cli_bench_expected(ref, r->set, &hits, &sum_t);
            /* Bounce rays made from other hits than Embree's are not exactly the published
             * set (a few start on other surfaces): only their counts can be checked. */
            bool counts_only = r->set != BENCH_PRIMARY && !published_bounces;
            r->ok = rayset_hits_match(r->st.hits, hits) &&
                    (any || counts_only ||
                     rayset_sum_t_match(r->st.sum_t, sum_t, r->st.hits, hits, (double)r->st.max_t));
            if (r->set != BENCH_PRIMARY) r->ok = r->ok && rayset_hits_match(r->st.rays, ref->secondary_rays);
            r->checked = true;
            r->against = counts_only && !any ? "reference (counts only)" : "reference";
        } else if (r->compared) {
            /* The first back end's 1-thread row of this set: rows[0..) are its rows. */
            const BenchRow *b = r;
            for (int k = 0; k < n; k++)
                if (cli_bench_same(rows[k].accel, rows[0].accel) && rows[k].set == r->set && rows[k].threads == 1)
                    b = &rows[k];
            r->ok = r->rays_differing <= rayset_rays_tolerance(r->st.rays) &&
                    rayset_hits_match(r->st.hits, b->st.hits) &&
                    (any || fabs(r->st.sum_t - b->st.sum_t) <= RAYSET_SUM_T_TOLERANCE * fabs(b->st.sum_t) + r->dt_sum);
            r->checked = true;
            r->against = cli_bench_name(b->accel);
        }
        if (r->threads != 1)
            for (int k = 0; k < i; k++) {
                const BenchRow *o = &rows[k];
                if (!cli_bench_same(o->accel, r->accel) || o->set != r->set || o->threads != 1) continue;
                bool same = o->st.hits == r->st.hits && o->st.sum_t == r->st.sum_t &&
                            o->st.sum_prim == r->st.sum_prim;
                r->ok = r->ok && same && (!o->checked || o->ok);
                if (!r->checked) {
                    r->checked = true;
                    r->against = o->checked ? o->against : "1 thread";
                }
            }
        r->vs_embree = r->vs_robust = -1.0;
        for (int k = 0; k < n; k++)
            if (rows[k].accel.type == ACCEL_EMBREE && rows[k].set == r->set && rows[k].threads == r->threads &&
                cli_bench_mrays(&rows[k].st) > 0.0)
                *(rows[k].accel.robust ? &r->vs_robust : &r->vs_embree) =
                    cli_bench_mrays(&r->st) / cli_bench_mrays(&rows[k].st);
    }
}

/* Three significant digits, without exponent down to 0.001 (slow back ends). */
static void cli_bench_format3(double v, char *buf, size_t size)
{
    snprintf(buf, size, v >= 100.0 ? "%.0f" : v >= 10.0 ? "%.1f" : v >= 1.0 ? "%.2f" : v >= 0.001 ? "%.3f" : "%.2g",
             v);
}

/* "1.23x", or "-" for a ratio that is missing (< 0). */
static void cli_bench_format_ratio(double v, char *buf, size_t size)
{
    if (v < 0.0) {
        snprintf(buf, size, "-");
        return;
    }
    cli_bench_format3(v, buf, size - 1);
    strcat(buf, "x");
}

static void cli_bench_print_table(const BenchRow *rows, int n)
{
    printf("%-13s %9s %9s  %-9s %7s %9s %9s %9s %9s %9s %16s  %s\n", "accel", "build ms", "bytes/tri",
           "set", "threads", "rays", "Mrays/s", "vs embree", "vs robust", "hits", "sum_t", "check");
    for (int i = 0; i < n; i++) {
        const BenchRow *r = &rows[i];
        char ratio[32], ratio_robust[32], rate[32], sum[32], check[48];
        cli_bench_format3(cli_bench_mrays(&r->st), rate, sizeof rate);
        cli_bench_format_ratio(r->vs_embree, ratio, sizeof ratio);
        cli_bench_format_ratio(r->vs_robust, ratio_robust, sizeof ratio_robust);
        if (r->set == BENCH_OCCLUSION) snprintf(sum, sizeof sum, "-");
        else snprintf(sum, sizeof sum, "%.9e", r->st.sum_t);
        if (!r->checked) snprintf(check, sizeof check, "(basis)");
        else if (r->against && strcmp(r->against, "reference (counts only)") == 0)
            snprintf(check, sizeof check, "%s (counts only)", r->ok ? "OK" : "MISMATCH");
        else if (r->compared && r->rays_differing > 0)
            snprintf(check, sizeof check, "%s (%zu ray%s differ%s)", r->ok ? "OK" : "MISMATCH", r->rays_differing,
                     r->rays_differing == 1 ? "" : "s", r->rays_differing == 1 ? "s" : "");
        else snprintf(check, sizeof check, "%s", r->ok ? "OK" : "MISMATCH");
        printf("%-13s %9.2f %9.1f  %-9s %7d %9zu %9s %9s %9s %9zu %16s  %s\n", cli_bench_name(r->accel),
               r->build_ms, r->bytes_per_tri, BENCH_SET_NAMES[r->set], r->threads, r->st.rays, rate, ratio,
               ratio_robust, r->st.hits, sum, check);
    }
}

/* One compact JSON object per row; false if jansson runs out of memory. */
static bool cli_bench_print_json(const BenchRow *rows, int n, const RaysetScene *scene)
{
    for (int i = 0; i < n; i++) {
        const BenchRow *r = &rows[i];
        bool closest = r->set != BENCH_OCCLUSION;
        json_t *o = json_pack("{s:s, s:i, s:s, s:i, s:s, s:I, s:f, s:i, s:f, s:I, s:o, s:o, s:f, s:f, s:o, s:o, s:o, s:o, s:o}",
            "scene", scene->name, "triangles", scene->num_tris,
            "accel", cli_bench_name(r->accel), "threads", r->threads,
            "set", BENCH_SET_NAMES[r->set], "rays", (json_int_t)r->st.rays,
            "seconds", r->st.seconds, "runs", r->runs, "mrays_per_s", cli_bench_mrays(&r->st),
            "hits", (json_int_t)r->st.hits,
            "sum_t", closest ? json_real(r->st.sum_t) : json_null(),
            "sum_prim", closest ? json_integer((json_int_t)r->st.sum_prim) : json_null(),
            "build_ms", r->build_ms, "bytes_per_tri", r->bytes_per_tri,
            "vs_embree", r->vs_embree >= 0.0 ? json_real(r->vs_embree) : json_null(),
            "vs_embree_robust", r->vs_robust >= 0.0 ? json_real(r->vs_robust) : json_null(),
            "check", r->checked ? json_string(r->ok ? "OK" : "MISMATCH") : json_null(),
            "checked_against", r->checked ? json_string(r->against) : json_null(),
            "rays_differing", r->compared ? json_integer((json_int_t)r->rays_differing) : json_null());
        char *line = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
        json_decref(o);
        if (!line) return false;
        printf("%s\n", line);
        free(line);
    }
    return true;
}

/* Traces one set with one thread count through every built back end, in rounds: each
 * round runs each back end once, and each row keeps its fastest run. A back end leaves
 * the rounds once its runs add up to CLI_BENCH_REPEAT_SECONDS (the grid in the stadium
 * runs once). Interleaving puts the VM's slow spells, which last seconds, into every back
 * end's runs alike instead of into one back end's whole series, so they move the ratios
 * less. rows[i] is back end i's row. When `basis` is given (scenes without a
 * reference), the first run at 1 thread keeps its results there (back end 0) or compares
 * them with it ray by ray (the others, through `scratch`). */
static CstStatus cli_bench_set(const Accel *accels, int num_accels, const BenchRays *rays, int set, int threads,
                               RaysetResult *const *basis, RaysetResult *scratch, BenchRow *const *rows, CstError *err)
{
    RaysetQuery q = set == BENCH_OCCLUSION ? RAYSET_ANY : RAYSET_CLOSEST;
    double spent[ARGS_BENCH_MAX_ACCELS] = {0.0};
    for (int rep = 0; rep < CLI_BENCH_MAX_REPEATS; rep++)
        for (int i = 0; i < num_accels; i++) {
            BenchRow *r = rows[i];
            if (rep > 0 && spent[i] >= CLI_BENCH_REPEAT_SECONDS) continue;
            RaysetResult *out = rep == 0 && basis && threads == 1 ? (i == 0 ? basis[set] : scratch) : NULL;
            RaysetStats run;
            CstStatus st = rayset_trace(&accels[i], rays->rays[set], rays->count[set], q, threads, out, &run, err);
            if (st != CST_OK) return st;
            spent[i] += run.seconds;
            if (rep == 0 || run.seconds < r->st.seconds) r->st = run;
            r->runs = rep + 1;
            if (out && i > 0) {
                r->compared = true;
                r->rays_differing = rayset_compare(out, basis[set], rays->count[set], q, &r->dt_sum);
            }
        }
    return CST_OK;
}

static int cli_bench_rays(const CliArgs *a)
{
    const BenchArgs *b = &a->bench;
    int code = CLI_EXIT_INTERNAL;
    CstError err = {0};
    CstStatus st;
    RaysetScene scene;
    Ray *primary = NULL, *secondary = NULL, *occlusion = NULL;
    RaysetResult *hits = NULL, *basis[BENCH_NUM_SETS] = {NULL, NULL, NULL}, *scratch = NULL;
    BenchRow *rows = NULL;
    Accel gen;
    memset(&gen, 0, sizeof gen);
    Accel built[ARGS_BENCH_MAX_ACCELS]; /* built[0 .. num_built) are freed at done */
    BenchBackend built_as[ARGS_BENCH_MAX_ACCELS];
    int num_built = 0;
    memset(&scene, 0, sizeof scene);

    /* The back ends, checked before any work: as listed (one this build lacks is a usage
     * error), else every one this build has, brute force only for tiny scenes. */
    BenchBackend accels[ARGS_BENCH_MAX_ACCELS];
    int num_accels = 0;
    bool explicit_accels = b->num_accels > 0;
    if (explicit_accels) {
        for (int i = 0; i < b->num_accels; i++) {
            BenchBackend be = {ACCEL_EMBREE, strcmp(b->accels[i], ARGS_EMBREE_ROBUST) == 0};
            if (!be.robust && !accel_type_from_name(b->accels[i], &be.type)) {
                fprintf(stderr, "caustic: error: unknown acceleration structure '%s'\n", b->accels[i]);
                code = CLI_EXIT_USAGE;
                goto done;
            }
            if (!accel_type_available(be.type)) {
                fprintf(stderr, "caustic: error: acceleration structure '%s' is not available in this build\n",
                        b->accels[i]);
                code = CLI_EXIT_USAGE;
                goto done;
            }
            accels[num_accels++] = be;
        }
    }

    /* The scene. */
    if (b->mesh_path) {
        struct stat sb;
        if (stat(b->mesh_path, &sb) != 0) {
            fprintf(stderr, "caustic: error: cannot open mesh '%s': %s\n", b->mesh_path, strerror(errno));
            return CLI_EXIT_USAGE;
        }
        if (S_ISDIR(sb.st_mode)) {
            fprintf(stderr, "caustic: error: mesh '%s' is a directory\n", b->mesh_path);
            return CLI_EXIT_USAGE;
        }
        st = rayset_scene_mesh(b->mesh_path, &scene, &err);
    } else if (b->stadium && !b->cornell) {
        st = rayset_scene_bumpy_ball(CLI_BENCH_BALL_LEVELS, &scene, &err);
    } else {
        st = rayset_scene_cornell(&scene, &err);
    }
    if (st == CST_OK && b->stadium) st = rayset_scene_add_stadium(&scene, &err);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        rayset_scene_free(&scene);
        return b->mesh_path ? cli_exit_code(st, CLI_STAGE_LOAD) : CLI_EXIT_INTERNAL;
    }
    const RaysetReference *ref = b->stadium ? NULL : rayset_reference(&scene);

    if (!explicit_accels) {
        for (int t = 0; t < ACCEL_TYPE_COUNT; t++) {
            if (!accel_type_available((AccelType)t)) continue;
            if (t == ACCEL_LIST && scene.num_tris > CLI_BENCH_LIST_MAX_TRIS) {
                fprintf(stderr, "caustic: bench rays: skipping list (brute force over %d triangles; "
                        "name it with --accel to run it anyway)\n", scene.num_tris);
                continue;
            }
            accels[num_accels++] = (BenchBackend){(AccelType)t, false};
            if (t == ACCEL_EMBREE) accels[num_accels++] = (BenchBackend){ACCEL_EMBREE, true};
        }
    }

    int max_threads = b->threads;
    if (max_threads == 0) {
        long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
        max_threads = ncpu > 0 ? (int)(ncpu < ARGS_MAX_THREADS ? ncpu : ARGS_MAX_THREADS) : 1;
    }
    int threads[2] = {1, max_threads};
    int num_threads = max_threads > 1 ? 2 : 1;

    /* The ray sets. Bounce rays come once from one back end's primary hits and are shared
     * by all: Embree's when this build has it (RAYSETS.md's references were made from
     * Embree's hits, so the secondary set is then the published one bit for bit), else
     * the BVH's. */
    size_t num_primary, num_secondary;
    primary = rayset_primary(&scene, &num_primary);
    hits = primary ? malloc(num_primary * sizeof *hits) : NULL;
    if (!primary || !hits) {
        fprintf(stderr, "caustic: error: out of memory for %d x %d primary rays\n", scene.camera.width,
                scene.camera.height);
        goto done;
    }
    AccelType gen_type = accel_type_available(ACCEL_EMBREE) ? ACCEL_EMBREE : ACCEL_BVH;
    AccelGeometry geom = rayset_scene_geometry(&scene);
    RaysetStats gen_stats;
    /* Embree alone, its own hits: RAYSETS.md's bounces come from them. */
    if ((st = accel_build_native(&gen, gen_type, &geom, &err)) != CST_OK ||
        (st = rayset_trace(&gen, primary, num_primary, RAYSET_CLOSEST, max_threads, hits, &gen_stats, &err)) != CST_OK) {
        cli_print_error(&err, st);
        goto done;
    }
    accel_free(&gen);
    secondary = rayset_secondary(&scene, primary, hits, num_primary, &num_secondary);
    occlusion = secondary ? rayset_occlusion(secondary, num_secondary) : NULL;
    rows = calloc((size_t)ARGS_BENCH_MAX_ACCELS * BENCH_NUM_SETS * 2, sizeof *rows);
    if (!secondary || !occlusion || !rows) {
        fprintf(stderr, "caustic: error: out of memory for %zu secondary rays\n", num_primary);
        goto done;
    }
    BenchRays rays = {{primary, secondary, occlusion}, {num_primary, num_secondary, num_secondary}};
    if (!ref) { /* per-ray comparison with the first back end */
        for (int set = 0; set < BENCH_NUM_SETS; set++)
            if (!(basis[set] = malloc((rays.count[set] ? rays.count[set] : 1) * sizeof *basis[set]))) break;
        size_t most = num_primary > num_secondary ? num_primary : num_secondary;
        scratch = malloc((most ? most : 1) * sizeof *scratch);
        if (!basis[BENCH_NUM_SETS - 1] || !scratch) {
            fprintf(stderr, "caustic: error: out of memory for the per-ray results\n");
            goto done;
        }
    }

    if (!b->json) {
        printf("scene:   %s, %d triangles, bbox diagonal %.9g", scene.name, scene.num_tris, scene.diag);
        if (b->stadium)
            printf(" (the teapot's: camera and offsets are its own; stadium half-size %g x diagonal)",
                   RAYSET_STADIUM_SCALE);
        printf("\n");
        printf("rays:    primary %zu (%dx%d), secondary %zu and occlusion %zu (bounces of %s's primary hits)\n",
               num_primary, scene.camera.width, scene.camera.height, num_secondary, num_secondary,
               accel_type_name(gen_type));
        if (ref)
            printf("checks:  against RAYSETS.md's \"%s\" row: hits within max(%d, %g x count); sum_t within %g "
                   "relative, plus |hits difference| x largest t%s\n", ref->scene, RAYSET_HITS_TOLERANCE_ABS,
                   RAYSET_HITS_TOLERANCE_REL, RAYSET_SUM_T_TOLERANCE,
                   gen_type == ACCEL_EMBREE ? "" : "; secondary sum_t unchecked (bounces not made from Embree's hits)");
        else
            printf("checks:  no reference checksums: every back end against the first, ray by ray: at most "
                   "max(%d, %g x count) rays may differ (hit vs miss, or t off by more than %g relative); hits "
                   "within the same; sum_t within %g relative plus what the differing rays explain\n",
                   RAYSET_HITS_TOLERANCE_ABS, RAYSET_HITS_TOLERANCE_REL, RAYSET_T_TOLERANCE,
                   RAYSET_SUM_T_TOLERANCE);
        printf("timing:  Mrays/s of the fastest of up to %d runs (repeated while under %g s in all), the back "
               "ends taking turns on each set\n", CLI_BENCH_MAX_REPEATS, CLI_BENCH_REPEAT_SECONDS);
        printf("\n");
        fflush(stdout);
    }

    /* Every back end is built before any is timed, so that the rounds can interleave
     * them (cli_bench_set). */
    for (int i = 0; i < num_accels; i++) {
        Accel *accel = &built[num_built];
        st = (accels[i].robust ? accel_build_native_robust : accel_build_native)(accel, accels[i].type, &geom, &err);
        if (st == CST_ERR_UNSUPPORTED && !explicit_accels) {
            fprintf(stderr, "caustic: bench rays: skipping %s: %s\n", cli_bench_name(accels[i]), err.msg);
            continue;
        }
        if (st != CST_OK) {
            cli_print_error(&err, st);
            code = st == CST_ERR_UNSUPPORTED ? CLI_EXIT_USAGE : CLI_EXIT_INTERNAL;
            goto done;
        }
        built_as[num_built++] = accels[i];
        if (isatty(STDERR_FILENO) == 1)
            fprintf(stderr, "caustic: bench rays: %s built in %.1f ms\n", cli_bench_name(accels[i]),
                    accel->build_seconds * 1e3);
    }
    const int nb = num_built;
    if (nb == 0) {
        fprintf(stderr, "caustic: error: no acceleration structure could be built\n");
        goto done;
    }
    if (isatty(STDERR_FILENO) == 1) fprintf(stderr, "caustic: bench rays: tracing...\n");

    /* Rows grouped by back end, then set, then thread count. */
    int n = nb * BENCH_NUM_SETS * num_threads;
    for (int i = 0; i < nb; i++) {
        double bpt = scene.num_tris > 0 ? (double)accel_memory_bytes(&built[i]) / scene.num_tris : 0.0;
        for (int set = 0; set < BENCH_NUM_SETS; set++)
            for (int k = 0; k < num_threads; k++) {
                BenchRow *r = &rows[(i * BENCH_NUM_SETS + set) * num_threads + k];
                r->accel = built_as[i];
                r->build_ms = built[i].build_seconds * 1e3;
                r->bytes_per_tri = bpt;
                r->set = set;
                r->threads = threads[k];
            }
    }
    for (int set = 0; set < BENCH_NUM_SETS; set++)
        for (int k = 0; k < num_threads; k++) {
            BenchRow *set_rows[ARGS_BENCH_MAX_ACCELS];
            for (int i = 0; i < nb; i++) set_rows[i] = &rows[(i * BENCH_NUM_SETS + set) * num_threads + k];
            st = cli_bench_set(built, nb, &rays, set, threads[k], ref ? NULL : basis, scratch, set_rows, &err);
            if (st != CST_OK) {
                cli_print_error(&err, st);
                goto done;
            }
        }

    cli_bench_check(rows, n, ref, gen_type == ACCEL_EMBREE);
    if (b->json) {
        if (!cli_bench_print_json(rows, n, &scene)) {
            fprintf(stderr, "caustic: error: out of memory writing JSON\n");
            goto done;
        }
    } else {
        cli_bench_print_table(rows, n);
    }
    int mismatches = 0;
    for (int i = 0; i < n; i++) mismatches += rows[i].checked && !rows[i].ok;
    if (mismatches)
        fprintf(stderr, "caustic: bench rays: %d of %d checks MISMATCH\n", mismatches, n);
    code = mismatches ? CLI_EXIT_MISMATCH : CLI_EXIT_OK;

done:
    accel_free(&gen);
    for (int i = 0; i < num_built; i++) accel_free(&built[i]);
    for (int set = 0; set < BENCH_NUM_SETS; set++) free(basis[set]);
    free(scratch);
    free(rows);
    free(occlusion);
    free(secondary);
    free(hits);
    free(primary);
    rayset_scene_free(&scene);
    return code;
}

/* ------------------------------------------------------------ caustic verify */

/* How verify judges each integrator, by cst_integrator_name(); one line per integrator.
 * EXACT: unbiased, so any two must agree at any sample count (whitted too: it is biased by
 * design, and verify reports that it disagrees). CONVERGE_*: consistent but biased at every
 * finite sample count (density estimation), where a z-test would flag the bias, correctly
 * and uselessly; judged instead by the convergence check against the reference (the first
 * EXACT integrator listed), with the work that shrinks the bias growing by 4 per level:
 * iterations (--spp) or the photon count. A name not listed is judged EXACT. */
typedef enum VerifyJudge { VERIFY_EXACT, VERIFY_CONVERGE_SPP, VERIFY_CONVERGE_PHOTONS } VerifyJudge;

static const struct { const char *name; VerifyJudge judge; } CLI_VERIFY_JUDGES[] = {
    {"path", VERIFY_EXACT},
    {"path-nee", VERIFY_EXACT},
    {"path-bsdf", VERIFY_EXACT},
    {"light", VERIFY_EXACT},
    {"whitted", VERIFY_EXACT},
    {"photon", VERIFY_CONVERGE_PHOTONS},
    {"sppm", VERIFY_CONVERGE_SPP},
    {"bdpt", VERIFY_EXACT},
    {"vcm", VERIFY_CONVERGE_SPP}, /* --spp counts iterations; the merging radius shrinks over them */
};

static VerifyJudge cli_verify_judge(CstIntegrator id)
{
    const char *name = cst_integrator_name(id);
    for (size_t i = 0; i < sizeof CLI_VERIFY_JUDGES / sizeof CLI_VERIFY_JUDGES[0]; i++)
        if (strcmp(name, CLI_VERIFY_JUDGES[i].name) == 0) return CLI_VERIFY_JUDGES[i].judge;
    return VERIFY_EXACT;
}

/* Render k (0-based) of a verify run renders with output k+1 of SplitMix64 (Steele et al.
 * 2014) started at the base seed: independent streams for every render, so the images
 * compared are independent estimates, even of the same integrator. Integrator k of the
 * list is render k; render i of level l of the convergence check of integrator k is
 * render MAX_INTEGRATORS + 2 (k MAX_LEVELS + l) + i. */
static uint64_t cli_verify_seed(uint64_t base, int k)
{
    return mix64(base + (uint64_t)(k + 1) * 0x9e3779b97f4a7c15ULL);
}

static uint64_t cli_verify_level_seed(uint64_t base, int k, int level, int i)
{
    return cli_verify_seed(base, ARGS_VERIFY_MAX_INTEGRATORS + 2 * (k * ARGS_VERIFY_MAX_LEVELS + level) + i);
}

static const char CLI_CHANNELS[3] = {'r', 'g', 'b'};

/* Below this many samples per block and integrator the z of a heavy-tailed estimator is
 * itself skewed: a block that happened to miss the rare large samples has a low mean and
 * a low variance estimate at once. Measured on the Cornell box with path, path-nee and
 * path-bsdf at alpha 0.01 (runs with any false alarm; docs/cli.md): 64x64 in 16 blocks,
 * 4096 samples per block 22 of 100, 16384 2-3 of 100, 65536 0 of 100; 512x512, 16384
 * samples in each of 1024 blocks 4 of 4, 65536 in each of 256 blocks 0 of 6. */
#define CLI_VERIFY_MIN_BLOCK_SAMPLES 65536

/* jansson cannot represent infinities (zero-variance disagreements): null instead. */
static json_t *cli_json_real(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

typedef struct VerifyRender {
    CstIntegrator id;
    char label[40]; /* the integrator's name; "path#2" for its second occurrence */
    uint64_t seed;
    CstFilm *film;
    CstRenderStats stats;
} VerifyRender;

/* The convergence check of one consistent integrator (index k of --integrators). */
typedef struct VerifyConvergence {
    int k;
    VerifyJudge judge;
    char label[40];
    int work[ARGS_VERIFY_MAX_LEVELS];      /* iterations or photons */
    double radius[ARGS_VERIFY_MAX_LEVELS]; /* photon: the fixed radius, 0 = automatic */
    uint64_t seed[ARGS_VERIFY_MAX_LEVELS][2];
    double seconds[ARGS_VERIFY_MAX_LEVELS];  /* both renders */
    ConvergenceLevel lv[ARGS_VERIFY_MAX_LEVELS];
    double step_diff[ARGS_VERIFY_MAX_LEVELS - 1], step_se[ARGS_VERIFY_MAX_LEVELS - 1];
    ConvergenceVerdict verdict;
} VerifyConvergence;

typedef struct VerifyPlan {
    int width, height, block, nbx, nby, blocks;
    int pairs, checks, levels, reference; /* reference: index of the first EXACT integrator */
    int64_t tests; /* m: pairs x 3 channels x (1 + blocks) + checks x levels */
    double alpha, alpha_1, z_crit, z_conv; /* z_conv: one-sided, for the convergence tests */
} VerifyPlan;

static const char *cli_verify_verdict(ConvergenceVerdict v)
{
    return v == CONVERGENCE_WITHIN_NOISE ? "within-noise" : v == CONVERGENCE_SHRINKS ? "shrinks" : "fails";
}

static void cli_verify_print_header(const CliArgs *a, const CstRenderSettings *rs,
                                    const VerifyPlan *p, const VerifyRender *r, int n)
{
    const char *scene = a->scene_path ? a->scene_path : "the built-in Cornell box";
    char work[96];
    if (rs->spp && rs->time_limit > 0.0)
        snprintf(work, sizeof work, "%d spp or %g s each, whichever first", rs->spp, rs->time_limit);
    else if (rs->time_limit > 0.0)
        snprintf(work, sizeof work, "%g s each (equal time)", rs->time_limit);
    else
        snprintf(work, sizeof work, "%d spp each", rs->spp);
    printf("scene:     %s, %dx%d, %s filter, %s\n", scene, p->width, p->height,
           cst_filter_name(rs->filter), work);
    printf("renders:   %-12s %-18s %6s %9s\n", "integrator", "seed", "spp", "seconds");
    for (int k = 0; k < n; k++)
        if (r[k].film)
            printf("           %-12s 0x%016" PRIx64 " %6d %9.2f\n", r[k].label, r[k].seed, r[k].stats.spp,
                   r[k].stats.seconds);
    bool partial = p->width % p->block || p->height % p->block;
    if (p->pairs > 0)
        printf("tests:     per pair and channel, z = (mean_a - mean_b) / sqrt(var_a + var_b) of the\n"
               "           image mean and of each of the %d blocks of %dx%d pixels (a %dx%d grid%s);\n"
               "           var of a mean = sum of its pixel-mean variances / n^2\n",
               p->blocks, p->block, p->block, p->nbx, p->nby, partial ? ", edge blocks partial" : "");
    if (p->checks > 0)
        printf("%s per consistent integrator X, %d levels of work (x1, x4, x16, ...), two renders\n"
               "           x1, x2 each, against the reference %s r: per block b, with block means,\n"
               "           t_b = sum over channels of ((x1+x2)/2 - r)^2 - (x1-x2)^2/4 - var(r);\n"
               "           D = mean of t_b over the %d blocks (the squared bias net of noise), se from\n"
               "           their spread; X converges if at the last level D <= z se and the image\n"
               "           mean's |z| <= z_crit per channel (within noise), or if D falls\n"
               "           significantly at every step (paired over blocks: dD > z se)\n",
               p->pairs > 0 ? "           and" : "tests:    ", p->levels, r[p->reference].label, p->blocks);
    char checks[64] = "";
    if (p->checks > 0)
        snprintf(checks, sizeof checks, " + %d check%s x (%d + 3)", p->checks, p->checks == 1 ? "" : "s",
                 p->levels);
    printf("threshold: m = %" PRId64 " tests (%d pair%s x 3 channels x (1 + %d)%s), family-wise alpha %g,\n"
           "           Sidak per-test alpha %.4g: a pair disagrees where |z| > z_crit = %.3f\n",
           p->tests, p->pairs, p->pairs == 1 ? "" : "s", p->blocks, checks, p->alpha, p->alpha_1, p->z_crit);
    if (p->checks > 0)
        printf("           (the image means of a convergence check too); D and its steps are\n"
               "           significant where z > %.3f (one-sided)\n", p->z_conv);
    printf("\n");
}

static void cli_verify_print_row(const VerifyRender *ra, const VerifyRender *rb, int width,
                                 const CompareResult *c, const VerifyPlan *p)
{
    char pair[96], where[48], failing[48];
    snprintf(pair, sizeof pair, "%s vs %s", ra->label, rb->label);
    snprintf(where, sizeof where, "(%d, %d) %c", c->worst_bx * p->block, c->worst_by * p->block,
             CLI_CHANNELS[c->worst_channel]);
    snprintf(failing, sizeof failing, "%d of %d", c->blocks_failing, c->blocks);
    printf("%-*s  %+7.2f %+7.2f %+7.2f  %+13.2f  %-16s  %-14s  %s\n", width, pair, c->z_mean[0],
           c->z_mean[1], c->z_mean[2], c->worst_z, where, failing, c->pass ? "agree" : "DISAGREE");
    if (c->zero_variance_disagreements > 0)
        printf("%-*s  (%d test%s with zero variance in both images and different means)\n", width,
               "", c->zero_variance_disagreements, c->zero_variance_disagreements == 1 ? "" : "s");
}

static void cli_verify_print_convergence(const VerifyConvergence *cv, const VerifyRender *ref,
                                         const VerifyPlan *p)
{
    const bool photons = cv->judge == VERIFY_CONVERGE_PHOTONS;
    printf("convergence: %s against %s\n", cv->label, ref->label);
    printf("  %-5s %10s  %-37s %10s %9s %6s %8s  %s\n", "level", photons ? "photons" : "iterations",
           "seeds", "D", "se", "z(D)", "rms bias", "image-mean diff (z) r, g, b");
    for (int l = 0; l < p->levels; l++) {
        const ConvergenceLevel *lv = &cv->lv[l];
        /* rms bias per channel of a block mean: sqrt(D / 3), 0 when noise exceeds it */
        printf("  %-5d %10d  0x%016" PRIx64 " 0x%016" PRIx64 " %+10.3e %9.2e %+6.2f %8.5f ", l, cv->work[l],
               cv->seed[l][0], cv->seed[l][1], lv->d2, lv->d2_se, lv->d2 / lv->d2_se,
               lv->d2 > 0.0 ? sqrt(lv->d2 / 3.0) : 0.0);
        for (int c = 0; c < 3; c++) printf(" %+.5f (%+.1f)", lv->mean_diff[c], lv->mean_z[c]);
        if (photons && cv->radius[l] > 0.0) printf("  (radius %g)", cv->radius[l]);
        printf("\n");
    }
    for (int l = 0; l + 1 < p->levels; l++)
        printf("  step %d->%d: D falls by %+.3e (se %.2e, z = %+.2f)\n", l, l + 1, cv->step_diff[l],
               cv->step_se[l], cv->step_diff[l] / cv->step_se[l]);
    if (cv->verdict == CONVERGENCE_WITHIN_NOISE)
        printf("  result: converges (within noise at level %d: z(D) <= %.3f, |image-mean z| <= %.3f)\n",
               p->levels - 1, p->z_conv, p->z_crit);
    else if (cv->verdict == CONVERGENCE_SHRINKS)
        printf("  result: converges (D falls significantly at every step: z > %.3f)\n", p->z_conv);
    else
        printf("  result: DISAGREE (a bias remains at level %d and D is not shown to fall at every step)\n",
               p->levels - 1);
}

/* One compact JSON line; false if jansson runs out of memory. */
static bool cli_print_json_line(json_t *o)
{
    char *line = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!line) return false;
    printf("%s\n", line);
    free(line);
    return true;
}

static bool cli_verify_print_json(const VerifyRender *ra, const VerifyRender *rb,
                                  const CompareResult *c, const VerifyPlan *p)
{
    char seed_a[24], seed_b[24], ch[2] = {CLI_CHANNELS[c->worst_channel], '\0'};
    snprintf(seed_a, sizeof seed_a, "0x%016" PRIx64, ra->seed);
    snprintf(seed_b, sizeof seed_b, "0x%016" PRIx64, rb->seed);
    json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:[o,o,o], s:o, s:o, s:[i,i], s:s, s:i, s:i, "
                          "s:i, s:i, s:f, s:f, s:I, s:b, s:b}",
        "a", ra->label, "b", rb->label, "seed_a", seed_a, "seed_b", seed_b,
        "spp_a", ra->stats.spp, "spp_b", rb->stats.spp,
        "z_mean", cli_json_real(c->z_mean[0]), cli_json_real(c->z_mean[1]), cli_json_real(c->z_mean[2]),
        "max_abs_block_z", cli_json_real(c->max_abs_block_z), "worst_block_z", cli_json_real(c->worst_z),
        "worst_block", c->worst_bx * p->block, c->worst_by * p->block, "worst_channel", ch,
        "block", p->block, "blocks", c->blocks, "blocks_failing", c->blocks_failing,
        "zero_variance_disagreements", c->zero_variance_disagreements,
        "alpha", p->alpha, "z_crit", p->z_crit, "tests", (json_int_t)p->tests,
        "judged", 1, "pass", c->pass);
    return cli_print_json_line(o);
}

static bool cli_verify_print_json_convergence(const VerifyConvergence *cv, const VerifyRender *ref,
                                              const VerifyPlan *p)
{
    json_t *levels = json_array(), *steps = json_array();
    for (int l = 0; levels && l < p->levels; l++) {
        char s0[24], s1[24];
        snprintf(s0, sizeof s0, "0x%016" PRIx64, cv->seed[l][0]);
        snprintf(s1, sizeof s1, "0x%016" PRIx64, cv->seed[l][1]);
        const ConvergenceLevel *lv = &cv->lv[l];
        json_array_append_new(levels, json_pack("{s:i, s:f, s:[s,s], s:o, s:o, s:[o,o,o], s:[o,o,o]}",
            "work", cv->work[l], "radius", cv->radius[l], "seeds", s0, s1,
            "d2", cli_json_real(lv->d2), "d2_se", cli_json_real(lv->d2_se),
            "mean_diff", cli_json_real(lv->mean_diff[0]), cli_json_real(lv->mean_diff[1]),
            cli_json_real(lv->mean_diff[2]),
            "mean_z", cli_json_real(lv->mean_z[0]), cli_json_real(lv->mean_z[1]), cli_json_real(lv->mean_z[2])));
    }
    for (int l = 0; steps && l + 1 < p->levels; l++)
        json_array_append_new(steps, json_pack("{s:o, s:o}", "diff", cli_json_real(cv->step_diff[l]),
                                               "se", cli_json_real(cv->step_se[l])));
    char seed_r[24];
    snprintf(seed_r, sizeof seed_r, "0x%016" PRIx64, ref->seed);
    /* "o" steals levels and steps, also when json_pack fails. */
    json_t *o = levels && steps
        ? json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:o, s:o, s:f, s:f, s:f, s:I, s:s, s:b}",
            "convergence", cv->label, "reference", ref->label,
            "work", cv->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", "seed_reference", seed_r,
            "block", p->block, "blocks", p->blocks, "levels", levels, "steps", steps,
            "alpha", p->alpha, "z_conv", p->z_conv, "z_crit", p->z_crit, "tests", (json_int_t)p->tests,
            "verdict", cli_verify_verdict(cv->verdict), "pass", cv->verdict != CONVERGENCE_FAILS)
        : NULL;
    if (!o && !(levels && steps)) {
        json_decref(levels);
        json_decref(steps);
    }
    return cli_print_json_line(o);
}

/* One render of verify, with a bar on a terminal (otherwise one line per render, not ten).
 * Returns an exit code; on success *film is the caller's. */
static int cli_verify_render(const CliArgs *a, CstScene *scene, CstRenderSettings settings, const char *what,
                             CstFilm **film, CstRenderStats *stats)
{
    CliProgress progress = {.tty = isatty(STDERR_FILENO) == 1};
    CstError err = {0};
    if (!a->quiet && progress.tty) {
        settings.progress = cli_progress_report;
        settings.progress_user = &progress;
    }
    CstStatus status = cst_render(scene, &settings, film, stats, &err);
    if (status != CST_OK) {
        if (settings.progress) cli_progress_abort(&progress);
        cli_print_error(&err, status);
        return cli_exit_code(status, CLI_STAGE_RENDER);
    }
    if (settings.progress) cli_progress_finish(&progress, stats->seconds);
    if (!a->quiet)
        fprintf(stderr, "caustic: verify: %s: %d spp in %.2f s\n", what, stats->spp, stats->seconds);
    if (stats->nonfinite > 0)
        fprintf(stderr, "caustic: warning: %s: %" PRIu64 " NaN/Inf samples discarded "
                "(counted as zero: the image is biased low there)\n", what, stats->nonfinite);
    return CLI_EXIT_OK;
}

/* The levels of one convergence check: render, compare with the reference, judge. terms
 * holds levels x blocks doubles. */
static int cli_verify_converge(const CliArgs *a, CstScene *scene, const CstRenderSettings *rs,
                               const VerifyPlan *p, const VerifyRender *ref, VerifyConvergence *cv,
                               double *terms)
{
    for (int l = 0; l < p->levels; l++) {
        CstFilm *x[2] = {NULL, NULL};
        for (int i = 0; i < 2; i++) {
            CstRenderSettings settings = a->settings;
            CstRenderStats stats;
            char what[96];
            settings.integrator = a->verify.integrators[cv->k];
            settings.seed = cv->seed[l][i];
            settings.seed_set = 1;
            if (cv->judge == VERIFY_CONVERGE_PHOTONS) {
                settings.photons = cv->work[l];
                settings.photon_radius = cv->radius[l];
                settings.spp = rs->spp;
            } else {
                settings.spp = cv->work[l];
            }
            snprintf(what, sizeof what, "%s level %d (%d %s) render %d", cv->label, l, cv->work[l],
                     cv->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", i + 1);
            int code = cli_verify_render(a, scene, settings, what, &x[i], &stats);
            if (code != CLI_EXIT_OK) {
                cst_film_destroy(x[0]);
                return code;
            }
            cv->seconds[l] += stats.seconds;
        }
        CstError err = {0};
        CstStatus status = compare_convergence_level(ref->film, x[0], x[1], p->block,
                                                     &terms[(size_t)l * (size_t)p->blocks], &cv->lv[l], &err);
        cst_film_destroy(x[0]);
        cst_film_destroy(x[1]);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            return CLI_EXIT_USAGE; /* the only failures are the arguments' (block count) */
        }
    }
    for (int l = 0; l + 1 < p->levels; l++)
        compare_convergence_step(&terms[(size_t)l * (size_t)p->blocks], &terms[(size_t)(l + 1) * (size_t)p->blocks],
                                 p->blocks, &cv->step_diff[l], &cv->step_se[l]);
    cv->verdict = compare_convergence_judge(cv->lv, cv->step_diff, cv->step_se, p->levels, p->z_conv, p->z_crit);
    return CLI_EXIT_OK;
}

static int cli_verify(const CliArgs *a)
{
    const VerifyArgs *v = &a->verify;
    const int n = v->num_integrators;
    int code = CLI_EXIT_INTERNAL;
    CstScene *scene = NULL;
    CstError err = {0};
    CstStatus status;
    VerifyRender r[ARGS_VERIFY_MAX_INTEGRATORS];
    VerifyConvergence cv[ARGS_VERIFY_MAX_INTEGRATORS];
    double *block_z = NULL, *worst_z = NULL, *terms = NULL;
    float *map = NULL;
    memset(r, 0, sizeof r);
    memset(cv, 0, sizeof cv);

    if (!cli_check_scene_path(a))
        return CLI_EXIT_USAGE;
    if (v->map_path && !cli_check_output(v->map_path, "--map"))
        return CLI_EXIT_USAGE;

    /* The plan, before rendering: pairs of EXACT integrators, convergence checks of the
     * others against the first EXACT one, how many tests, the critical values. */
    VerifyPlan p = {.block = v->block, .alpha = v->alpha, .levels = v->levels, .reference = -1};
    int exact = 0;
    for (int i = 0; i < n; i++) {
        if (cli_verify_judge(v->integrators[i]) == VERIFY_EXACT) {
            if (p.reference < 0) p.reference = i;
            exact++;
        } else {
            cv[p.checks].k = i;
            cv[p.checks].judge = cli_verify_judge(v->integrators[i]);
            p.checks++;
        }
    }
    p.pairs = exact * (exact - 1) / 2;
    if (p.checks > 0 && p.reference < 0) {
        fprintf(stderr, "caustic: error: verify: %s is judged by convergence against an unbiased "
                "reference; add one to --integrators (e.g. path,%s)\n",
                cst_integrator_name(v->integrators[cv[0].k]), cst_integrator_name(v->integrators[cv[0].k]));
        return CLI_EXIT_USAGE;
    }

    code = cli_load_scene(a, &scene, NULL);
    if (code != CLI_EXIT_OK)
        return code;
    code = CLI_EXIT_INTERNAL;

    CstRenderSettings rs;
    cst_render_settings_resolve(scene, &a->settings, &rs);
    p.width = rs.width;
    p.height = rs.height;
    p.nbx = compare_blocks_x(p.width, p.block);
    p.nby = compare_blocks_y(p.height, p.block);
    p.blocks = p.nbx * p.nby;
    /* A check: D and the image mean per channel at the last level, and every step. */
    p.tests = p.pairs * compare_tests_per_pair(p.width, p.height, p.block) + (int64_t)p.checks * (p.levels + 3);
    p.alpha_1 = compare_sidak_alpha(p.alpha, (double)p.tests);
    p.z_crit = compare_z_critical(p.alpha, (double)p.tests);
    p.z_conv = -compare_normal_quantile(p.alpha_1);
    if (p.checks > 0) {
        /* Levels are multiples of work; a time limit would make them depend on the machine. */
        if (rs.time_limit > 0.0) {
            fprintf(stderr, "caustic: error: verify: the convergence check of %s needs a sample count "
                    "(--spp), not a time limit: its levels are 1, 4, 16, ... times that work\n",
                    cst_integrator_name(v->integrators[cv[0].k]));
            code = CLI_EXIT_USAGE;
            goto done;
        }
        if (p.blocks < 2) {
            fprintf(stderr, "caustic: error: verify: the convergence check needs at least 2 blocks "
                    "(%dx%d image, --block %d); its standard error comes from their spread\n",
                    p.width, p.height, p.block);
            code = CLI_EXIT_USAGE;
            goto done;
        }
        const int64_t grow = (int64_t)1 << (2 * (p.levels - 1));
        for (int c = 0; c < p.checks; c++) {
            VerifyConvergence *x = &cv[c];
            int64_t base = x->judge == VERIFY_CONVERGE_PHOTONS
                               ? (rs.photons > 0 ? rs.photons : PHOTON_DEFAULT_COUNT) : rs.spp;
            if (base * grow > INT32_MAX) {
                fprintf(stderr, "caustic: error: verify: %s: %" PRId64 " %s times 4^%d is too many "
                        "(at most %d); lower --spp or --convergence\n",
                        cst_integrator_name(v->integrators[x->k]), base,
                        x->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", p.levels - 1, INT32_MAX);
                code = CLI_EXIT_USAGE;
                goto done;
            }
            for (int l = 0; l < p.levels; l++) {
                x->work[l] = (int)(base << (2 * l));
                /* A fixed radius would keep a fixed bias; halving it with 4x the photons
                 * keeps the photons per disc and halves the first-order bias. */
                x->radius[l] = x->judge == VERIFY_CONVERGE_PHOTONS ? rs.photon_radius / (double)(1 << l) : 0.0;
                for (int i = 0; i < 2; i++) x->seed[l][i] = cli_verify_level_seed(rs.seed, x->k, l, i);
            }
        }
    }

    for (int k = 0; k < n; k++) {
        r[k].id = v->integrators[k];
        r[k].seed = cli_verify_seed(rs.seed, k);
        int seen = 1;
        for (int i = 0; i < k; i++) seen += r[i].id == r[k].id;
        if (seen > 1)
            snprintf(r[k].label, sizeof r[k].label, "%s#%d", cst_integrator_name(r[k].id), seen);
        else
            snprintf(r[k].label, sizeof r[k].label, "%s", cst_integrator_name(r[k].id));
    }
    for (int c = 0; c < p.checks; c++) memcpy(cv[c].label, r[cv[c].k].label, sizeof cv[c].label);

    if (!a->quiet) {
        char work[96];
        if (rs.spp && rs.time_limit > 0.0)
            snprintf(work, sizeof work, "%d spp or %g s each", rs.spp, rs.time_limit);
        else if (rs.time_limit > 0.0)
            snprintf(work, sizeof work, "%g s each", rs.time_limit);
        else
            snprintf(work, sizeof work, "%d spp each", rs.spp);
        fprintf(stderr, "caustic: verify: rendering %s (%dx%d, %s, %d thread%s) with",
                a->scene_path ? a->scene_path : "the built-in Cornell box", rs.width, rs.height,
                work, rs.threads, rs.threads == 1 ? "" : "s");
        for (int k = 0; k < n; k++) fprintf(stderr, "%s %s", k ? "," : "", r[k].label);
        if (p.checks > 0)
            fprintf(stderr, " (consistent ones: %d levels x 2 renders)", p.levels);
        fprintf(stderr, "\n");
    }
    int min_spp = INT32_MAX;
    for (int k = 0; k < n; k++) {
        if (cli_verify_judge(r[k].id) != VERIFY_EXACT) continue;
        CstRenderSettings settings = a->settings;
        settings.integrator = r[k].id;
        settings.seed = r[k].seed;
        settings.seed_set = 1;
        code = cli_verify_render(a, scene, settings, r[k].label, &r[k].film, &r[k].stats);
        if (code != CLI_EXIT_OK) goto done;
        code = CLI_EXIT_INTERNAL;
        if (r[k].stats.spp < 2) {
            fprintf(stderr, "caustic: error: verify: %s rendered %d sample per pixel; the "
                    "variance estimate needs at least 2 (use --spp 2 or more, or a longer --time)\n",
                    r[k].label, r[k].stats.spp);
            code = CLI_EXIT_USAGE;
            goto done;
        }
        if (r[k].stats.spp < min_spp) min_spp = r[k].stats.spp;
    }
    double block_samples = (double)(p.block < p.width ? p.block : p.width) *
                           (double)(p.block < p.height ? p.block : p.height) * min_spp;
    if (p.pairs > 0 && block_samples < CLI_VERIFY_MIN_BLOCK_SAMPLES)
        fprintf(stderr, "caustic: warning: verify: %.0f samples per block (%dx%d pixels x %d spp); "
                "with fewer than %d, heavy-tailed estimators (e.g. path-bsdf) give false alarms "
                "far above alpha: raise --spp or --block (see docs/cli.md)\n", block_samples,
                p.block, p.block, min_spp, CLI_VERIFY_MIN_BLOCK_SAMPLES);

    block_z = malloc((size_t)p.blocks * sizeof *block_z);
    worst_z = calloc((size_t)p.blocks, sizeof *worst_z);
    terms = malloc((size_t)p.levels * (size_t)p.blocks * sizeof *terms);
    if (!block_z || !worst_z || !terms) {
        fprintf(stderr, "caustic: error: out of memory for %d blocks\n", p.blocks);
        goto done;
    }
    for (int c = 0; c < p.checks; c++) {
        code = cli_verify_converge(a, scene, &rs, &p, &r[p.reference], &cv[c], terms);
        if (code != CLI_EXIT_OK) goto done;
        code = CLI_EXIT_INTERNAL;
    }

    int width = 0;
    for (int k = 0; k < n; k++) {
        int len = (int)strlen(r[k].label);
        if (len > width) width = len;
    }
    width = 2 * width + 4;
    if (!v->json) {
        cli_verify_print_header(a, &rs, &p, r, n);
        if (p.pairs > 0)
            printf("%-*s  %-23s  %13s  %-16s  %-14s  %s\n", width, "pair", "image-mean z (r, g, b)",
                   "worst block z", "at (x, y) ch", "failing blocks", "result");
    }
    int disagree = 0, diverge = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            if (!r[i].film || !r[j].film) continue; /* a consistent integrator: its own check */
            CompareResult c;
            status = compare_films(r[i].film, r[j].film, p.block, p.z_crit, &c, block_z, &err);
            if (status != CST_OK) {
                cli_print_error(&err, status);
                goto done;
            }
            disagree += !c.pass;
            for (int b = 0; b < p.blocks; b++)
                if (block_z[b] > worst_z[b]) worst_z[b] = block_z[b];
            if (v->json) {
                if (!cli_verify_print_json(&r[i], &r[j], &c, &p)) {
                    fprintf(stderr, "caustic: error: out of memory writing JSON\n");
                    goto done;
                }
            } else {
                cli_verify_print_row(&r[i], &r[j], width, &c, &p);
            }
        }
    for (int c = 0; c < p.checks; c++) {
        diverge += cv[c].verdict == CONVERGENCE_FAILS;
        if (v->json) {
            if (!cli_verify_print_json_convergence(&cv[c], &r[p.reference], &p)) {
                fprintf(stderr, "caustic: error: out of memory writing JSON\n");
                goto done;
            }
        } else {
            if (c > 0 || p.pairs > 0) printf("\n");
            cli_verify_print_convergence(&cv[c], &r[p.reference], &p);
        }
    }
    if (!v->json) {
        printf("\n");
        if (p.pairs > 0) {
            if (disagree)
                printf("result:    %d of %d pair%s DISAGREE\n", disagree, p.pairs, p.pairs == 1 ? "" : "s");
            else
                printf("result:    %s\n", p.pairs == 1 ? "the pair agrees" : "all pairs agree");
        }
        if (p.checks > 0) {
            if (diverge)
                printf("%s %d of %d consistent integrator%s not shown to converge (DISAGREE)\n",
                       p.pairs > 0 ? "          " : "result:   ", diverge, p.checks, p.checks == 1 ? "" : "s");
            else
                printf("%s %s\n", p.pairs > 0 ? "          " : "result:   ",
                       p.checks == 1 ? "the consistent integrator converges" : "every consistent integrator converges");
        }
    }

    if (v->map_path) {
        map = malloc((size_t)p.width * (size_t)p.height * 3u * sizeof *map);
        if (!map) {
            fprintf(stderr, "caustic: error: out of memory for the %dx%d map\n", p.width, p.height);
            goto done;
        }
        compare_map_image(worst_z, p.width, p.height, p.block, p.z_crit, map);
        status = image_write(v->map_path, map, p.width, p.height, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            code = cli_exit_code(status, CLI_STAGE_WRITE);
            goto done;
        }
        if (!a->quiet)
            fprintf(stderr, "caustic: verify: wrote the z map to %s\n", v->map_path);
    }
    if (disagree)
        fprintf(stderr, "caustic: verify: %d of %d pair%s disagree (|z| > %.3f)\n", disagree,
                p.pairs, p.pairs == 1 ? "" : "s", p.z_crit);
    if (diverge)
        fprintf(stderr, "caustic: verify: %d of %d consistent integrator%s not shown to converge\n", diverge,
                p.checks, p.checks == 1 ? "" : "s");
    code = disagree || diverge ? CLI_EXIT_DISAGREE : CLI_EXIT_OK;

done:
    free(map);
    free(terms);
    free(worst_z);
    free(block_z);
    for (int k = 0; k < n; k++) cst_film_destroy(r[k].film);
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
    case ARGS_CMD_BENCH_RAYS:
        code = cli_bench_rays(&args);
        if (code != CLI_EXIT_USAGE && cli_finish_stdout() != CLI_EXIT_OK)
            code = CLI_EXIT_INTERNAL;
        break;
    case ARGS_CMD_VERIFY:
        code = cli_verify(&args);
        if (code != CLI_EXIT_USAGE && cli_finish_stdout() != CLI_EXIT_OK)
            code = CLI_EXIT_INTERNAL;
        break;
    }
    exit(code);
}
