/* Command-line parsing for the caustic tool: argv -> CliArgs with strict number parsing,
 * and the help text. Never prints diagnostics or exits: cli/main.c decides what to do. */
#ifndef CST_CLI_ARGS_H
#define CST_CLI_ARGS_H

#include <stdbool.h>
#include <stddef.h>
#include <stdio.h>

#include "caustic/caustic.h"

/* Valid values, shared by the help text and the error messages. */
#define ARGS_INTEGRATOR_NAMES "path, path-nee, path-bsdf, light, whitted, photon, sppm, bdpt, vcm, pssmlt, mmlt"
#define ARGS_FILTER_NAMES     "box, tent, gaussian, mitchell"
#define ARGS_ACCEL_NAMES      "bvh, kdtree, grid, list, embree, octree"
/* bench rays also takes Embree in its robust mode as a back end of its own. */
#define ARGS_EMBREE_ROBUST     "embree-robust"
#define ARGS_BENCH_ACCEL_NAMES ARGS_ACCEL_NAMES ", " ARGS_EMBREE_ROBUST
#define ARGS_SAMPLER_NAMES    "independent, stratified, sobol, zsobol"
#define ARGS_AOV_NAMES        "albedo, normal, depth, variance"
#define ARGS_MAX_EXPOSURE     64
#define ARGS_OUTPUT_FORMATS   ".png, .exr, .pfm"
#define ARGS_MAX_DIMENSION    65536
#define ARGS_MAX_THREADS      1024

typedef enum ArgsCommand {
    ARGS_CMD_RENDER,      /* caustic render ... */
    ARGS_CMD_HELP,        /* caustic --help | -h | help [COMMAND] | COMMAND --help: help_for */
    ARGS_CMD_INFO,        /* caustic info [SCENE] [--accel NAME] */
    ARGS_CMD_VERSION,     /* caustic --version */
    ARGS_CMD_BENCH_RAYS,  /* caustic bench rays [MESH | --cornell] [--stadium] [--accel LIST] ... */
    ARGS_CMD_VERIFY,      /* caustic verify [SCENE] --integrators NAME,NAME[,...] ... */
    ARGS_CMD_LIST,        /* caustic list [KIND] */
    ARGS_CMD_COMPARE,     /* caustic compare A B [--map OUT] [--json] [--variance-a VA] ... */
    ARGS_CMD_VIEW,        /* caustic view [SCENE] [render options] [--script FILE] */
    ARGS_CMD_MERGE,       /* caustic merge STATE... -o IMAGE */
    ARGS_CMD_EXPLAIN      /* caustic explain [SCENE] --pixel X,Y [--sample I] [render options] */
} ArgsCommand;

#define ARGS_BENCH_MAX_ACCELS 7 /* each back end at most once */

/* `caustic bench rays`: what to trace and with what. */
typedef struct BenchArgs {
    const char *mesh_path; /* NULL = the built-in Cornell box (or, with --stadium alone,
                            * the built-in dense ball); points into argv */
    bool cornell;          /* --cornell given */
    bool stadium;          /* --stadium: the scene inside a huge sparse box */
    bool json;             /* --json: one JSON object per line on stdout */
    int threads;           /* --threads: the second thread count; 0 = one per core */
    /* --accel: back-end names (static strings) in the order given; 0 = all available */
    const char *accels[ARGS_BENCH_MAX_ACCELS];
    int num_accels;
} BenchArgs;

#define ARGS_VERIFY_MAX_INTEGRATORS 16
#define ARGS_VERIFY_DEFAULT_ALPHA   0.01
#define ARGS_VERIFY_DEFAULT_BLOCK   16
#define ARGS_VERIFY_DEFAULT_LEVELS  3  /* --convergence: work 1, 4, 16 times the base */
#define ARGS_VERIFY_MAX_LEVELS      6  /* 4^5 = 1024 times the base work at most */

/* `caustic verify`: which integrators to render and how to compare them. The scene, size,
 * spp, time, threads and seed are CliArgs' scene_path and settings (seed: the base seed). */
typedef struct VerifyArgs {
    CstIntegrator integrators[ARGS_VERIFY_MAX_INTEGRATORS]; /* in the order given */
    int num_integrators;
    double alpha;         /* family-wise significance, in (0, 1) */
    int block;            /* block side in pixels, >= 1 */
    const char *map_path; /* --map: NULL = no map; points into argv */
    bool json;            /* --json: one JSON object per pair on stdout */
    int levels;           /* --convergence: work levels of consistent integrators, 2..MAX */
} VerifyArgs;

#define ARGS_COMPARE_DEFAULT_BLOCK 16
#define ARGS_COMPARE_MAX_PPD      10000.0

/* `caustic compare A B`: two images, B the reference. */
typedef struct CompareArgs {
    const char *a, *b;        /* points into argv */
    const char *var_a, *var_b; /* --variance-a/-b: NULL = the EXR's variance AOV if it has one */
    const char *map_path;     /* --map: NULL = none */
    bool json;                /* --json: one JSON object on stdout */
    int block;                /* --block: z blocks' side, >= 1 */
    int flip;                 /* --flip: 0 auto (LDR for two PNGs, else HDR), CST_FLIP_LDR/_HDR */
    double ppd;               /* --ppd: pixels per degree, 0 = FLIP's default */
} CompareArgs;

/* `caustic merge`: state files (pointers into argv) and -o, the CliArgs' output_path. */
typedef struct MergeArgs {
    const char *const *paths;
    int count;
} MergeArgs;

typedef struct CliArgs {
    ArgsCommand command;
    const char *scene_path;  /* NULL = the built-in Cornell box; points into argv */
    const char *output_path; /* NULL = the scene's "output", else the default name */
    const char *accel;       /* NULL = the scene's choice (default bvh); points into argv */
    const char *light_sampler; /* NULL = the scene's choice (cst_scene_set_light_sampler) */
    const char *light_sampling; /* NULL = the scene's choice (cst_scene_set_light_sampling) */
    /* Only what the command line set; zero fields defer to the scene, then the library
     * default. progress and progress_user are left for main.c. */
    CstRenderSettings settings;
    bool quiet;
    /* render: --json (summary on stdout) or --json=FILE (json_path); --force (render even
     * when the images' memory estimate exceeds the memory available) */
    bool json;
    const char *json_path;
    bool force;
    /* render: --checkpoint FILE (state written between passes, every checkpoint_every
     * seconds, 0 = CLI_CHECKPOINT_EVERY, and at the end), --resume FILE; NULL = none */
    const char *checkpoint_path;
    double checkpoint_every;
    const char *resume_path;
    ArgsCommand help_for; /* ARGS_CMD_HELP: the command whose help (ARGS_CMD_HELP: all) */
    const char *list_kind; /* ARGS_CMD_LIST: NULL = every kind; points into argv */
    BenchArgs bench;   /* ARGS_CMD_BENCH_RAYS only */
    VerifyArgs verify; /* ARGS_CMD_VERIFY only */
    CompareArgs compare; /* ARGS_CMD_COMPARE only */
    MergeArgs merge;     /* ARGS_CMD_MERGE only */
    const char *script_path; /* view: --script FILE (NULL: $CAUSTIC_VIEW_SCRIPT, else none) */
    /* render, view: --display tev[:HOST:PORT] (cli/tev.h); display NULL = none */
    const char *display;
    char display_host[256];
    int display_port;
    /* explain: --pixel X,Y (pixel_set when given) and --sample I (default 0) */
    bool pixel_set;
    int pixel_x, pixel_y;
    int explain_sample;
    int explain_why;       /* explain: 1 --why-dark, 2 --why-bright (one summary line), 0 the full text */
} CliArgs;

typedef struct ArgsError {
    char msg[512]; /* without the "caustic: " prefix */
    bool hint;     /* append "see caustic --help": the command line itself was malformed */
} ArgsError;

/* The KINDs of `caustic list KIND`, NULL-terminated. */
extern const char *const ARGS_LIST_KINDS[];

/* Parses argv. Returns false on any usage error and fills *err; *out is then undefined. */
bool args_parse(int argc, char **argv, CliArgs *out, ArgsError *err);

/* Writes the usage text of one command (ARGS_CMD_RENDER, _INFO, _BENCH_RAYS, _VERIFY,
 * _LIST, _COMPARE: its options, exit codes and examples), or with ARGS_CMD_HELP every command's
 * (cli/help.c). */
void args_print_help(FILE *f, ArgsCommand command);

#endif
