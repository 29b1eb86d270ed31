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
/* MPI_Finalize, when cli_mpi_start started MPI; on rank 0 after a stop before the last
 * block (the others still busy), MPI_Abort with exit_code instead, which ends every rank. */
void cli_mpi_stop(int exit_code);
/* Whether cli_mpi_start started MPI: render goes through cli_mpi_render. */
bool cli_mpi_active(void);

/* cst_render across the ranks: every rank calls it with the same scene and settings; on
 * rank 0 *out is the film (bit for bit cst_render's with the same sample_block, whatever
 * the number of ranks) and *stats the whole job's; on the others *out is NULL. Rank 0 calls
 * settings->pass_done after the blocks it adds (the film of a one-process render at that
 * block end: checkpoints) and continues settings->resume's film; a stop (pass_done's, or
 * SIGINT/SIGTERM to any rank, with the CLI's stop armed) ends it with the blocks added,
 * stats->stopped set. sppm: rank 0 renders it all but the photons of the other ranks'
 * chunks (CstPhotonSplit), which they trace. Refuses (CST_ERR_UNSUPPORTED) a time limit. */
CstStatus cli_mpi_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                         CstRenderStats *stats, CstError *err);

#endif
