/* What the CLI's files share: exit codes, error printing, output and scene path checks,
 * scene loading (common.c) and the progress display. Every file of the CLI reaches the
 * library through include/caustic/caustic.h only. */
#ifndef CST_CLI_CLI_H
#define CST_CLI_CLI_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

#include "args.h"
#include "caustic/caustic.h"

/* Exit codes: the contract with scripts, documented in --help and docs/cli.md. */
#define CLI_EXIT_OK       0
#define CLI_EXIT_INTERNAL 1 /* not the user's fault: OOM, library failure, I/O while writing */
#define CLI_EXIT_USAGE    2 /* bad command line, bad scene file, unusable output path */
#define CLI_EXIT_MISMATCH 1 /* bench rays: a checksum did not match */
#define CLI_EXIT_DISAGREE 1 /* verify: a pair of integrators disagrees */

#define CLI_BUILTIN_OUTPUT "cornell-box.png"

/* Where a library call failed; an I/O error means a different thing at each stage. */
typedef enum CliStage { CLI_STAGE_LOAD, CLI_STAGE_RENDER, CLI_STAGE_WRITE } CliStage;


/* Maps a library status to an exit code (common.c explains the I/O rule). */
int cli_exit_code(CstStatus status, CliStage stage);
/* "caustic: error: <message>" on stderr. */
void cli_print_error(const CstError *err, CstStatus status);
bool cli_has_suffix(const char *s, const char *suffix);
bool cli_is_pbrt_path(const char *s);
/* Whether `path` (named `origin` in messages) can take an image: a known extension and a
 * writable directory; prints the error and returns false if not. */
bool cli_check_output(const char *path, const char *origin);
bool cli_check_scene_path(const CliArgs *a);
int cli_load_scene(const CliArgs *a, CstScene **out, double *read_seconds);
/* Seconds on the monotonic clock (CLOCK_MONOTONIC): only differences mean anything. */
double cli_clock_seconds(void);

/* The progress display (progress.c). Zero-initialise, then set tty. */
typedef struct CliProgress {
    bool tty;      /* redraw a bar in place; otherwise one line per 10% */
    int last_step; /* plain mode: the last 10% step printed, 0..10 */
    int last_len;  /* bar mode: characters of the last line drawn, to blank leftovers */
    bool drawn;    /* bar mode: a bar is on screen without its newline */
    char phase[32];      /* the current phase (CST_PHASE_*), "" before the first */
    double phase_start;  /* the render's elapsed seconds when it began: its ETA's origin */
    double last_elapsed; /* the last elapsed time reported */
} CliProgress;

/* A CstProgressFn and a CstPhaseFn: user is a CliProgress. */
int cli_progress_report(void *user, double fraction, double elapsed);
void cli_progress_phase(void *user, const char *phase);
void cli_progress_finish(CliProgress *p, double seconds);
void cli_progress_abort(CliProgress *p);

/* summary.c: the memory check before a render and the --json summary after it. */
typedef struct CliSummary {
    const char *scene;   /* NULL: the built-in Cornell box */
    const char *output;
    double load_seconds, accel_seconds, write_seconds, total_seconds;
    CstRenderStats stats; /* its seconds: the render's */
    uint64_t memory_estimate;
} CliSummary;
uint64_t cli_available_memory(void);
/* Whether the images' estimated memory (*estimate) fits in the memory available; prints
 * the error (or, with force, a warning) when not. */
bool cli_check_memory(const CstScene *scene, const CstRenderSettings *settings, bool force,
                      uint64_t *estimate);
FILE *cli_summary_open(const char *path);
bool cli_summary_write(FILE *f, const CliSummary *s);

int cli_render(const CliArgs *a);
int cli_verify(const CliArgs *a);
/* caustic compare A B (compare.c): the numbers on stdout, the FLIP map to --map. */
int cli_compare(const CliArgs *a);
/* caustic explain (explain.c): one pixel sample's path, text or --json, on stdout. */
int cli_explain(const CliArgs *a);
/* explain_sppm.c: sppm's iteration (chain, photons, update) as text, a --why-* line, or
 * added to explain.c's JSON object o (a json_t). */
struct json_t;
void cli_explain_sppm_text(FILE *f, const CstExplain *x);
void cli_explain_sppm_why(FILE *f, const CstExplain *x, bool bright);
void cli_explain_sppm_json(struct json_t *o, const CstExplain *x);
/* caustic view's click-to-explain: explain's text for pixel (x, y) at `sample` under s (the
 * current mode's settings; mode its name, NULL for the preview, which has no paths) on stdout. */
void cli_explain_view(const CstScene *scene, const CstRenderSettings *s, int x, int y, int sample, const char *mode);
/* caustic merge (merge.c) */
int cli_merge(const CliArgs *a);
/* caustic list [KIND] and caustic --version (list.c), on stdout. */
int cli_list(const CliArgs *a);
int cli_version(void);
/* caustic view [SCENE] (view.c): the interactive window; without SDL2 in the build, a
 * message and CLI_EXIT_USAGE. cli_view_available: whether this build has it. */
int cli_view(const CliArgs *a);
bool cli_view_available(void);

#endif
