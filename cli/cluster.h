/* Distributed rendering over MPI (cli/cluster.c, built when CMake finds MPI: CLI_HAVE_MPI):
 * under mpirun, `caustic render` splits its samples into blocks that rank 0 hands out on
 * request, and rank 0 adds the blocks' sums in block order and writes the image. The
 * library knows nothing of MPI; without it these are no-ops. */
#ifndef CST_CLI_CLUSTER_H
#define CST_CLI_CLUSTER_H

#include <stdbool.h>

#include "caustic/caustic.h"

/* Starts MPI when the process was launched by mpirun (its environment says so) and this
 * build has MPI. Returns the number of ranks, 0 when MPI is not in use; *rank: this one's. */
int cli_mpi_start(int *rank);
/* MPI_Finalize, when cli_mpi_start started MPI. */
void cli_mpi_stop(void);
/* Whether cli_mpi_start started MPI: render goes through cli_mpi_render. */
bool cli_mpi_active(void);

/* cst_render across the ranks: every rank calls it with the same scene and settings; on
 * rank 0 *out is the film (bit for bit cst_render's with the same sample_block, whatever
 * the number of ranks) and *stats the whole job's; on the others *out is NULL. Refuses
 * (CST_ERR_UNSUPPORTED) what needs a film between blocks on every rank: a time limit,
 * --checkpoint, --resume, and sppm. */
CstStatus cli_mpi_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                         CstRenderStats *stats, CstError *err);

#endif
