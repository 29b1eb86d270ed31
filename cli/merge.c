/* caustic merge: state files of disjoint sample ranges of one render, added up in sample
 * order into the image of their union (cst_film_state_merge; docs/cli.md). */
#include <stdio.h>

#include "cli.h"
#include "signals.h"

int cli_merge(const CliArgs *a)
{
    if (!cli_check_output(a->output_path, "output")) return CLI_EXIT_USAGE;
    CstFilm *film = NULL;
    CstError err = {0};
    int first = 0;
    CstStatus status = cst_film_state_merge(a->merge.paths, a->merge.count, &film, &first, &err);
    if (status != CST_OK) {
        cli_print_error(&err, status);
        return cli_exit_code(status, CLI_STAGE_LOAD);
    }
    /* As every image write: atomic, no temporary left behind by a signal. */
    CstImageWriteOptions wo = {NULL, 0, cli_signals_temp_file, NULL};
    status = cst_film_write_opt(film, a->output_path, &wo, &err);
    if (status != CST_OK) {
        cli_print_error(&err, status);
        cst_film_destroy(film);
        return cli_exit_code(status, CLI_STAGE_WRITE);
    }
    if (!a->quiet)
        fprintf(stderr, "caustic: merged %d state%s, samples [%d, %d) of %dx%d pixels, into %s\n", a->merge.count,
                a->merge.count == 1 ? "" : "s", first, first + cst_film_spp(film), cst_film_width(film),
                cst_film_height(film), a->output_path);
    cst_film_destroy(film);
    return CLI_EXIT_OK;
}
