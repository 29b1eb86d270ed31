/* caustic: the command-line front end. Parses arguments (args.c), builds or loads the
 * scene, renders with progress on stderr and writes the image; `bench rays` traces the
 * acceleration benchmark's ray sets (bench/raysets.c). The only place in the
 * project that turns a CstStatus into an exit code (see docs/cli.md). */
#include <errno.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "caustic/caustic.h"
#include "cli.h"
#include "cluster.h"

/* ------------------------------------------------------------ caustic bench rays */

/* The benchmark runs in the library (cst_bench_rays); the table or JSON goes to stdout,
 * notes to stderr (build and tracing notes only on a terminal). */
static int cli_bench_rays(const CliArgs *a)
{
    const BenchArgs *b = &a->bench;
    CstBenchRaysOptions o;
    memset(&o, 0, sizeof o);
    o.mesh_path = b->mesh_path;
    o.cornell = b->cornell;
    o.stadium = b->stadium;
    o.json = b->json;
    o.threads = b->threads;
    for (int i = 0; i < b->num_accels; i++) o.accels[i] = b->accels[i];
    o.num_accels = b->num_accels;
    o.out = stdout;
    o.log = stderr;
    o.verbose = isatty(STDERR_FILENO) == 1;
    CstBenchRaysResult r;
    CstError err = {0};
    CstStatus st = cst_bench_rays(&o, &r, &err);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        return r.input_error ? cli_exit_code(st, CLI_STAGE_LOAD) : CLI_EXIT_INTERNAL;
    }
    if (r.mismatches)
        fprintf(stderr, "caustic: bench rays: %d of %d checks MISMATCH\n", r.mismatches, r.checks);
    return r.mismatches ? CLI_EXIT_MISMATCH : CLI_EXIT_OK;
}

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
        args_print_help(stdout, args.help_for);
        code = cli_finish_stdout();
        break;
    case ARGS_CMD_VERSION:
        cli_version();
        code = cli_finish_stdout();
        break;
    case ARGS_CMD_LIST:
        cli_list(&args);
        code = cli_finish_stdout();
        break;
    case ARGS_CMD_RENDER:
    case ARGS_CMD_INFO: {
        /* Under mpirun (cli/cluster.c) rank 0 alone reports and writes. */
        int rank = 0;
        if (args.command == ARGS_CMD_RENDER && cli_mpi_start(&rank) > 0 && rank != 0) {
            args.quiet = true;
            args.json = false;
        }
        code = cli_render(&args);
        cli_mpi_stop(code);
        break;
    }
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
    case ARGS_CMD_VIEW:
        code = cli_view(&args);
        if (code != CLI_EXIT_USAGE && cli_finish_stdout() != CLI_EXIT_OK)
            code = CLI_EXIT_INTERNAL;
        break;
    case ARGS_CMD_MERGE:
        code = cli_merge(&args);
        break;
    case ARGS_CMD_EXPLAIN:
        code = cli_explain(&args);
        if (code != CLI_EXIT_USAGE && cli_finish_stdout() != CLI_EXIT_OK)
            code = CLI_EXIT_INTERNAL;
        break;
    case ARGS_CMD_COMPARE:
        code = cli_compare(&args);
        if (code != CLI_EXIT_USAGE && cli_finish_stdout() != CLI_EXIT_OK)
            code = CLI_EXIT_INTERNAL;
        break;
    }
    exit(code);
}
