/* caustic render and caustic info: load the scene, print the job line, render with
 * progress, write the image and the summary; info prints the scene's size and its
 * acceleration structure's build time and memory. */
#include <errno.h>
#include <inttypes.h>
#include <signal.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include "cli.h"
#include "tev.h"
#include "metadata.h"
#include "cluster.h"
#include "signals.h"

/* "<stem of the scene file>.png" in the current directory; "scene.png" if the stem is
 * empty. Returns false if it does not fit. */
static bool cli_default_output(const char *scene_path, char *buf, size_t size)
{
    const char *base = strrchr(scene_path, '/');
    base = base ? base + 1 : scene_path;
    size_t stem = strlen(base);
    if (cli_has_suffix(base, ".gz")) stem -= 3; /* x.pbrt.gz: x.png */
    size_t dot = stem;
    while (dot > 0 && base[dot - 1] != '.') dot--;
    if (dot > 0)
        stem = dot - 1;
    int n = stem ? snprintf(buf, size, "%.*s.png", (int)stem, base)
                 : snprintf(buf, size, "scene.png");
    return n > 0 && (size_t)n < size;
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
    if (s.noise_target > 0.0 && s.time_limit > 0.0)
        snprintf(work, sizeof work, "noise target %g, at most %d spp and %g s", s.noise_target,
                 s.spp > 0 ? s.spp : CST_NOISE_SPP_CAP, s.time_limit);
    else if (s.noise_target > 0.0)
        snprintf(work, sizeof work, "noise target %g, at most %d spp", s.noise_target,
                 s.spp > 0 ? s.spp : CST_NOISE_SPP_CAP);
    else if (s.spp && s.time_limit > 0.0)
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
    if (in.shapes > 0) printf("shapes:      %d (cylinders, disks, partial spheres)\n", in.shapes);
    printf("emitters:    %d (emitting shapes)\n", in.emitters);
    printf("lights:      %d (the emitting shapes and every other light)\n", in.lights);
    printf("materials:   %d\n", in.materials);
    printf("accel:       %s\n", in.accel);
    printf("build:       %.2f ms\n", in.accel_build_seconds * 1e3);
    printf("memory:      %zu bytes", in.accel_bytes);
    int prims = in.triangles + in.spheres + in.shapes;
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
        n += snprintf(line + n, sizeof line - (size_t)n, ", %s M samples/s, %s M rays/s", samples,
                      rays);
    }
    /* --noise: the blocks' estimated relative error (render/adaptive.h) and its interval. */
    if (n > 0 && (size_t)n < sizeof line && st->noise_blocks > 0)
        snprintf(line + n, sizeof line - (size_t)n,
                 "; noise %.4g rms over %d blocks (95%% CI %.4g-%.4g), max %.4g, %d above the target; "
                 "%d-%d spp", st->noise_rms, st->noise_blocks, st->noise_rms_lo, st->noise_rms_hi,
                 st->noise_max, st->noise_blocks_over, st->spp_min, st->spp);
    fprintf(stderr, "%s\n", line);
}

/* ------------------------------------------------------------ checkpoints and stops */

/* --checkpoint-every's default: a state every 5 minutes costs nothing measurable (a 512x512
 * state is 12 MiB, written in tens of milliseconds: docs/benchmarks.md) and loses at most
 * 5 minutes of work to a kill -9. */
#define CLI_CHECKPOINT_EVERY 300.0

/* What the pass callback needs: where and how often to write the state, the stop request,
 * and what it did, for the summary. */
typedef struct CliPasses {
    const CstScene *scene;
    const CstRenderSettings *settings;
    char scene_id[96];        /* what a state file is keyed to (cli_passes_setup) */
    const char *checkpoint;  /* NULL: no state files */
    double every, last_write; /* seconds; the render's elapsed time of the last write */
    int passes;               /* completed */
    int written_spp;          /* samples in the last state written, -1 = none */
    int writes;
    double write_seconds;     /* all writes together */
    CstStatus failed;         /* a write failed: the render stops */
    CstError err;
    CliProgress *progress;    /* NULL: quiet */
    CliTev *tev;              /* --display: the stream, NULL = none */
    bool tev_passes;          /* stream after every pass (SPPM's film is whole only at the end) */
    float *tev_rgb;           /* the film as written, streamed (cli_tev_stream) */
} CliPasses;

/* --display: the film as cst_film_write writes it (exposure, white balance) to tev, so the
 * stream ends on the same floats as the EXR. */
static void cli_tev_stream(CliPasses *c, const CstFilm *film)
{
    if (!cli_tev_connected(c->tev)) return;
    int w = cst_film_width(film), h = cst_film_height(film);
    if (!c->tev_rgb && !(c->tev_rgb = malloc((size_t)w * (size_t)h * 3 * sizeof *c->tev_rgb))) return;
    cst_film_output_pixels(film, c->tev_rgb);
    cli_tev_send(c->tev, c->tev_rgb, w, h);
}

static int cli_pass_done(void *user, const CstFilm *film, const CstPassInfo *info)
{
    CliPasses *c = user;
    c->passes++;
    const int stop = cli_signals_stop_requested() != 0;
    if (c->tev_passes && !info->last) cli_tev_stream(c, film); /* the last: after the render */
    if (c->checkpoint && (info->last || stop || info->elapsed_seconds - c->last_write >= c->every)) {
        double t0 = cli_clock_seconds();
        CstImageWriteOptions wo = {NULL, 0, cli_signals_temp_file, NULL};
        CstStatus st = cst_film_state_write(c->checkpoint, film, c->scene, c->settings, c->scene_id, &wo, &c->err);
        c->write_seconds += cli_clock_seconds() - t0;
        c->last_write = info->elapsed_seconds;
        if (st != CST_OK) {
            c->failed = st;
            return 1;
        }
        c->writes++;
        c->written_spp = info->samples_done;
    }
    return stop;
}

/* The progress callback of every render: the display (unless quiet), and a stop request
 * that comes before any pass is complete cancels at once: there is nothing to keep. */
static int cli_render_progress(void *user, double fraction, double elapsed)
{
    CliPasses *c = user;
    if (cli_signals_stop_requested() && c->passes == 0) return 1;
    return c->progress ? cli_progress_report(c->progress, fraction, elapsed) : 0;
}

static void cli_render_phase(void *user, const char *phase)
{
    CliPasses *c = user;
    if (c->progress) cli_progress_phase(c->progress, phase);
}

/* Whether --checkpoint's file can be written, checked before rendering rather than at the
 * first write: not a directory, in an existing writable directory. Prints the error. */
static bool cli_check_state_path(const char *path)
{
    struct stat st;
    if (stat(path, &st) == 0 && S_ISDIR(st.st_mode)) {
        fprintf(stderr, "caustic: error: --checkpoint '%s' is a directory; expected a file name\n", path);
        return false;
    }
    const char *slash = strrchr(path, '/');
    char dir[4096];
    if (!slash) snprintf(dir, sizeof dir, ".");
    else if (slash == path) snprintf(dir, sizeof dir, "/");
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    if (access(dir, W_OK | X_OK) != 0) {
        fprintf(stderr, "caustic: error: --checkpoint '%s': directory '%s' is not writable: %s\n", path, dir,
                strerror(errno));
        return false;
    }
    return true;
}

/* The checks of --checkpoint and --resume, and the resumed film (*resume, NULL without
 * --resume). Returns an exit code. */
static int cli_prepare_resume(const CliArgs *a, const CstScene *scene, const CstRenderSettings *settings,
                              const char *scene_id, CstFilm **resume)
{
    *resume = NULL;
    if (!a->checkpoint_path && !a->resume_path) return CLI_EXIT_OK;
    if (a->checkpoint_path && !cli_check_state_path(a->checkpoint_path)) return CLI_EXIT_USAGE;
    if (!a->resume_path) return CLI_EXIT_OK;
    CstError err = {0};
    CstStatus st = cst_film_state_read(a->resume_path, scene, settings, scene_id, resume, &err);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        return cli_exit_code(st, CLI_STAGE_LOAD);
    }
    return CLI_EXIT_OK;
}

/* Before the render: the scene's id, the resumed state (*resume), the tev stream
 * (--display, images named `output`), the pass callback and the progress callbacks in
 * `settings`. Returns an exit code. */
static int cli_passes_setup(const CliArgs *a, const CstScene *scene, const CliMetadata *meta, const char *output,
                            CliPasses *passes, CliProgress *progress, CstRenderSettings *settings, CstFilm **resume)
{
    /* The scene file's bytes (files it includes are not hashed; the scene's counts are in
     * the key too: docs/state-format.md). */
    if (!a->scene_path) snprintf(passes->scene_id, sizeof passes->scene_id, "builtin:cornell-box");
    else if (meta->sha256[0]) snprintf(passes->scene_id, sizeof passes->scene_id, "sha256:%s", meta->sha256);
    else snprintf(passes->scene_id, sizeof passes->scene_id, "unhashed");
    int code = cli_prepare_resume(a, scene, settings, passes->scene_id, resume);
    if (code != CLI_EXIT_OK) return code;
    passes->scene = scene;
    passes->settings = settings;
    passes->checkpoint = a->checkpoint_path;
    passes->every = a->checkpoint_every > 0.0 ? a->checkpoint_every : CLI_CHECKPOINT_EVERY;
    passes->written_spp = -1;
    passes->progress = a->quiet ? NULL : progress;
    if (a->display) {
        CstRenderSettings rs;
        cst_render_settings_resolve(scene, settings, &rs);
        passes->tev_passes = rs.integrator != CST_INTEGRATOR_SPPM;
        /* Connected before the render; a refused connection is a warning only. */
        if (!(passes->tev = cli_tev_create(a->display_host, a->display_port, output))) {
            fprintf(stderr, "caustic: error: out of memory for --display\n");
            return CLI_EXIT_INTERNAL;
        }
    }
    settings->resume = *resume;
    settings->pass_done = cli_pass_done;
    settings->pass_user = passes;
    settings->progress = cli_render_progress;
    settings->progress_phase = cli_render_phase;
    settings->progress_user = passes;
    return CLI_EXIT_OK;
}

/* After everything (cli_render's end, whatever the outcome): the stream's last image (the
 * film as written, or as far as it got), the stream and the resumed film released. */
static void cli_passes_end(CliPasses *passes, const CstFilm *film, CstFilm *resume)
{
    if (film) cli_tev_stream(passes, film);
    cli_tev_destroy(passes->tev);
    free(passes->tev_rgb);
    cst_film_destroy(resume);
}

/* Right after the render: a stop before any pass (nothing to write) or a failed state
 * write. Returns an exit code to end with, or -1 to go on. */
static int cli_after_render(const CliArgs *a, CstStatus status, const CliPasses *passes, CliProgress *progress,
                            int stop_signal, int spp)
{
    if (status == CST_ERR_CANCELLED && stop_signal) {
        if (!a->quiet) cli_progress_abort(progress);
        fprintf(stderr, "caustic: interrupted before the first pass was complete: nothing written\n");
        return 128 + stop_signal;
    }
    if (status == CST_OK && passes->failed != CST_OK) {
        if (!a->quiet) cli_progress_abort(progress);
        cli_print_error(&passes->err, passes->failed);
        fprintf(stderr, "caustic: the render stopped because its checkpoint could not be written; the image of "
                        "the %d spp done is written next\n", spp);
    }
    return -1;
}

/* After the image is written: the states written, and the exit code of a failed state write
 * or a stop (or -1 to go on). */
static int cli_report_passes(const CliArgs *a, const CliPasses *passes, const CstRenderStats *stats,
                             const char *output, int stop_signal)
{
    if (passes->writes > 0 && !a->quiet)
        fprintf(stderr, "caustic: wrote the state %s: %d spp (%d write%s, %.1f ms each, %.2f%% of the render)\n",
                a->checkpoint_path, passes->written_spp, passes->writes, passes->writes == 1 ? "" : "s",
                1e3 * passes->write_seconds / passes->writes,
                stats->seconds > 0.0 ? 100.0 * passes->write_seconds / stats->seconds : 0.0);
    if (passes->failed != CST_OK) return cli_exit_code(passes->failed, CLI_STAGE_WRITE);
    if (!stats->stopped) return -1;
    fprintf(stderr, "caustic: interrupted (%s) after %d spp: wrote %s%s%s%s\n",
            stop_signal == SIGINT ? "SIGINT" : "SIGTERM", stats->spp, output, a->checkpoint_path ? " and " : "",
            a->checkpoint_path ? a->checkpoint_path : "",
            a->checkpoint_path ? "; continue with --resume and the same settings" : "");
    return 128 + stop_signal;
}

/* ------------------------------------------------------------ commands */

/* The output path: -o, else the scene's "output", else the scene's name with .png (the
 * built-in box: CLI_BUILTIN_OUTPUT), checked writable before rendering; NULL (after a
 * message) when it is not. buf holds a derived name. */
static const char *cli_resolve_output(const CliArgs *a, CstScene *scene, char *buf, size_t size)
{
    if (a->output_path)
        return a->output_path;
    const char *from_scene = cst_scene_output_path(scene);
    if (from_scene) {
        if (!cli_check_output(from_scene, "the scene's output")) {
            fprintf(stderr, "caustic: use -o to write somewhere else\n");
            return NULL;
        }
        return from_scene;
    }
    if (!a->scene_path)
        snprintf(buf, size, "%s", CLI_BUILTIN_OUTPUT);
    else if (!cli_default_output(a->scene_path, buf, size)) {
        fprintf(stderr, "caustic: error: scene path too long: '%s'\n", a->scene_path);
        return NULL;
    }
    return cli_check_output(buf, "output") ? buf : NULL;
}

/* The render: cst_render, or under mpirun cli_mpi_render (film NULL on ranks other than 0). */
static CstStatus cli_render_film(const CliArgs *a, const CstScene *scene, const CstRenderSettings *settings,
                                 CstFilm **film, CstRenderStats *stats, CstError *err)
{
    if (!cli_mpi_active()) {
        cli_signals_stop_arm();
        CstStatus status = cst_render(scene, settings, film, stats, err);
        cli_signals_stop_disarm();
        return status;
    }
    CstRenderSettings rs;
    cst_render_settings_resolve(scene, settings, &rs);
    if (rs.noise_target > 0.0) {
        snprintf(err->msg, sizeof err->msg, "under mpirun: --noise plans each round from the whole film, which no "
                 "rank holds; expected no --noise (or one process)");
        return CST_ERR_UNSUPPORTED;
    }
    /* Rank 0's film between blocks is a one-process render's: checkpoints, resume and stops
     * as without mpirun (cli/cluster.c), but of the crop only (sppm: rank 0 renders whole). */
    const bool cropped = rs.crop[0] != 0 || rs.crop[1] != rs.width || rs.crop[2] != 0 || rs.crop[3] != rs.height;
    if (cropped && (a->checkpoint_path || a->resume_path) && rs.integrator != CST_INTEGRATOR_SPPM) {
        snprintf(err->msg, sizeof err->msg, "under mpirun: a state file holds the whole image, and the ranks render "
                 "only the crop; expected no --crop with --checkpoint or --resume (or one process)");
        return CST_ERR_UNSUPPORTED;
    }
    cli_signals_stop_arm();
    CstStatus status = cli_mpi_render(scene, settings, film, stats, err);
    cli_signals_stop_disarm();
    return status;
}

int cli_render(const CliArgs *a)
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
    CstFilm *resume = NULL;
    CliPasses passes = {0};
    CliMetadata meta = {0};
    CliSummary summary = {.scene = a->scene_path};
    FILE *json = NULL;
    const double t_start = cli_clock_seconds();

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
    /* The loader's time without its acceleration build(s), which --accel may repeat. */
    summary.load_seconds = read_seconds;
    summary.accel_seconds = cli_clock_seconds() - t_start - read_seconds;
    if (a->command == ARGS_CMD_INFO) {
        cli_print_info(a, scene, read_seconds);
        code = CLI_EXIT_OK;
        goto done;
    }

    if (!(output = cli_resolve_output(a, scene, default_output, sizeof default_output))) {
        code = CLI_EXIT_USAGE;
        goto done;
    }

    {
        /* AOVs are EXR channels: refused before rendering, not after. */
        CstRenderSettings rs;
        cst_render_settings_resolve(scene, &settings, &rs);
        if (rs.aovs && !cst_image_path_is_exr(output)) {
            fprintf(stderr, "caustic: error: output '%s': AOVs (--aov or the scene's \"aovs\") are "
                            "written as extra EXR channels; expected an output ending in .exr\n", output);
            code = CLI_EXIT_USAGE;
            goto done;
        }
    }
    if (!cli_check_memory(scene, &settings, a->force, &summary.memory_estimate)) {
        code = CLI_EXIT_USAGE;
        goto done;
    }
    if (a->json && !(json = cli_summary_open(a->json_path))) {
        code = CLI_EXIT_USAGE;
        goto done;
    }
    cli_metadata_begin(&meta, a->scene_path);
    if ((code = cli_passes_setup(a, scene, &meta, output, &passes, &progress, &settings, &resume)) != CLI_EXIT_OK)
        goto done;
    code = CLI_EXIT_INTERNAL;
    if (!a->quiet) {
        cli_print_job(a, scene, &settings, output);
        if (resume)
            fprintf(stderr, "caustic: resuming from %s: %d spp done\n", a->resume_path, cst_film_spp(resume));
    }

    /* During the render the first SIGINT or SIGTERM stops it after its pass, and the image
     * of the passes done (and the state, with --checkpoint) is written; during that write,
     * as during any image write, a signal ends the process and leaves no partial file. */
    status = cli_render_film(a, scene, &settings, &film, &stats, &err);
    code = CLI_EXIT_OK; /* under mpirun, a rank other than 0 (no film) is done: rank 0 writes */
    if (status == CST_OK && cli_mpi_active() && !film) goto done;
    const int stop_signal = cli_signals_stop_requested();
    if ((code = cli_after_render(a, status, &passes, &progress, stop_signal, stats.spp)) >= 0)
        goto done;
    code = CLI_EXIT_INTERNAL;
    /* Too many NaN/Inf samples: the film is still written, for inspection, then exit 1. */
    CstStatus render_status = status;
    CstError render_err = err;
    if (status == CST_ERR_NONFINITE) status = CST_OK;
    if (status != CST_OK) {
        if (!a->quiet)
            cli_progress_abort(&progress);
        cli_print_error(&err, status);
        code = cli_exit_code(status, CLI_STAGE_RENDER);
        goto done;
    }
    if (!a->quiet)
        cli_progress_finish(&progress, stats.seconds);

    double t_write = cli_clock_seconds();
    {
        /* The image records how it was made (docs/cli.md, "Metadata"); no temporary file
         * survives a signal during the write. */
        CstRenderSettings used;
        cst_render_settings_resolve(scene, &settings, &used);
        cli_metadata_finish(&meta, &used, &stats);
        CstImageWriteOptions wo = {meta.entry, meta.count, cli_signals_temp_file, NULL};
        status = cst_film_write_opt(film, output, &wo, &err);
    }
    if (status != CST_OK) {
        cli_print_error(&err, status);
        code = cli_exit_code(status, CLI_STAGE_WRITE);
        goto done;
    }
    summary.write_seconds = cli_clock_seconds() - t_write;
    if (!a->quiet)
        cli_print_summary(output, &stats);
    if ((code = cli_report_passes(a, &passes, &stats, output, stop_signal)) >= 0)
        goto done;
    code = CLI_EXIT_INTERNAL;
    if (render_status != CST_OK) {
        cli_print_error(&render_err, render_status);
        fprintf(stderr, "caustic: %s was written for inspection only: the render failed\n", output);
        code = cli_exit_code(render_status, CLI_STAGE_RENDER);
        goto done;
    }
    if (stats.nonfinite > 0)
        fprintf(stderr, "caustic: warning: %" PRIu64 " NaN/Inf samples discarded "
                "(%.3g%% of %" PRIu64 "; counted, never added to the image)\n",
                stats.nonfinite,
                stats.samples ? 100.0 * (double)stats.nonfinite / (double)stats.samples : 0.0,
                stats.samples);
    code = CLI_EXIT_OK;
    if (json) {
        summary.output = output;
        summary.stats = stats;
        summary.total_seconds = cli_clock_seconds() - t_start;
        if (!cli_summary_write(json, &summary)) {
            fprintf(stderr, "caustic: error: writing the --json summary: %s\n", strerror(errno));
            code = CLI_EXIT_INTERNAL;
        }
    }

done:
    cli_passes_end(&passes, film, resume);
    cli_metadata_free(&meta);
    if (json && json != stdout)
        fclose(json);
    cst_film_destroy(film);
    cst_scene_destroy(scene);
    return code;
}

