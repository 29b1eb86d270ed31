/* Distributed rendering over MPI (issue 29): rank 0 hands out blocks of samples of one
 * render (CstRenderSettings.sample_block) to the ranks that ask, renders blocks itself in
 * between, and adds every block's sums to the film in block order, never in the order
 * they arrive, so the image is bit for bit a one-process render's whatever the number of
 * ranks or their speed. Only the CLI knows MPI: the library renders each block as an
 * ordinary cst_render of samples [first_sample, first_sample + spp). */
#include "cluster.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"

/* The library's cst_fail is not public: the same for the CLI's own errors. */
static CstStatus mpi_fail(CstError *err, CstStatus status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));
static CstStatus mpi_fail(CstError *err, CstStatus status, const char *fmt, ...)
{
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->msg, sizeof err->msg, fmt, ap);
    va_end(ap);
    err->status = status;
    return status;
}

#ifdef CLI_HAVE_MPI
#include <mpi.h>

/* The messages: an assignment (one int64, the block's index, -1 = no more), and a result
 * (a header of four int64: block, samples, rays, NaN/Inf discarded; then the block film's
 * sums, sums of squares and, if any, AOV sums as doubles). */
enum { TAG_ASSIGN = 1, TAG_HEADER, TAG_SUM, TAG_SQ, TAG_AOV };
/* Blocks handed to a rank ahead of the one it renders, so it never waits for rank 0, which
 * answers only between its own steps (about ten times a second). */
enum { CLUSTER_AHEAD = 2, QUEUE_CAP = 8 };

static int g_started;

int cli_mpi_start(int *rank)
{
    *rank = 0;
    /* Open MPI's mpirun, and the PMI of MPICH's and Slurm's launchers. */
    if (!getenv("OMPI_COMM_WORLD_SIZE") && !getenv("PMI_SIZE") && !getenv("PMIX_RANK")) return 0;
    int provided = 0, size = 0;
    /* Only the main thread calls MPI (the progress callbacks run on it). */
    if (MPI_Init_thread(NULL, NULL, MPI_THREAD_FUNNELED, &provided) != MPI_SUCCESS) return 0;
    g_started = 1;
    MPI_Comm_rank(MPI_COMM_WORLD, rank);
    MPI_Comm_size(MPI_COMM_WORLD, &size);
    return size;
}

void cli_mpi_stop(void)
{
    if (g_started) MPI_Finalize();
    g_started = 0;
}

bool cli_mpi_active(void) { return g_started != 0; }

/* One rank's view of the job. */
typedef struct Cluster {
    int rank, size;
    const CstScene *scene;
    CstRenderSettings st;     /* resolved, no callbacks */
    int first, end, B, k0, nb; /* samples [first, end), blocks k0 .. k0 + nb - 1 */
    int next;                  /* rank 0: the next block to hand out (0 .. nb) */
    int added;                 /* rank 0: blocks added to total */
    CstFilm **ready;           /* rank 0: blocks received or rendered, not yet added */
    CstFilm *total;
    int *stopped;              /* rank 0: the rank was told there is no more */
    struct Incoming *incoming; /* rank 0: per rank, the result being received */
    uint64_t samples, rays, nonfinite;
    /* worker: blocks handed to it, and its last result's sends in flight */
    int64_t queue[QUEUE_CAP];
    int qhead, qlen;
    MPI_Request req[4];
    int64_t header[4];
    CstFilm *sending;
} Cluster;

/* Block i's samples [*s0, *s0 + *n). */
static void block_range(const Cluster *c, int i, int *s0, int *n)
{
    const int64_t k = (int64_t)c->k0 + i;
    const int64_t lo = k * c->B > c->first ? k * c->B : c->first;
    const int64_t hi = (k + 1) * c->B < c->end ? (k + 1) * c->B : c->end;
    *s0 = (int)lo;
    *n = (int)(hi - lo);
}

static void assign(int to, int64_t block)
{
    MPI_Send(&block, 1, MPI_INT64_T, to, TAG_ASSIGN, MPI_COMM_WORLD);
}

/* Rank 0: the next block for rank `to`, or the word that there is none (once). */
static void assign_next(Cluster *c, int to)
{
    if (c->next < c->nb) assign(to, c->next++);
    else if (!c->stopped[to]) {
        assign(to, -1);
        c->stopped[to] = 1;
    }
}

/* Rank 0: adds the blocks that are next in order. */
static CstStatus add_ready(Cluster *c, CstError *err)
{
    while (c->added < c->nb && c->ready[c->added]) {
        CstStatus status = cst_film_add(c->total, c->ready[c->added], err);
        cst_film_destroy(c->ready[c->added]);
        c->ready[c->added++] = NULL;
        if (status != CST_OK) return status;
    }
    return CST_OK;
}

/* Rank 0: a result being received from one rank (a rank sends its next only when this
 * one is through: worker()'s wait_sends). */
typedef struct Incoming {
    CstFilm *film; /* NULL: none */
    int64_t block;
    MPI_Request req[3];
} Incoming;

/* Rank 0, never blocking: finishes the receptions that are through, starts one for every
 * result announced (and hands its sender the next block at once), and adds what is next
 * in order. The sums arrive by MPI_Irecv, tested here ~10 times a second, so rank 0 never
 * spins in MPI while its render threads work. */
static CstStatus serve(Cluster *c, CstError *err)
{
    for (int r = 1; r < c->size; r++) {
        Incoming *in = &c->incoming[r];
        int done = 0;
        if (!in->film) continue;
        MPI_Testall(3, in->req, &done, MPI_STATUSES_IGNORE);
        if (!done) continue;
        c->ready[in->block] = in->film;
        in->film = NULL;
    }
    for (;;) {
        int flag = 0;
        MPI_Status ms;
        MPI_Iprobe(MPI_ANY_SOURCE, TAG_HEADER, MPI_COMM_WORLD, &flag, &ms);
        if (!flag) break;
        const int from = ms.MPI_SOURCE;
        Incoming *in = &c->incoming[from];
        int64_t h[4];
        MPI_Recv(h, 4, MPI_INT64_T, from, TAG_HEADER, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (in->film) { /* the sender's previous result: through on its side, not yet seen here */
            MPI_Waitall(3, in->req, MPI_STATUSES_IGNORE);
            c->ready[in->block] = in->film;
            in->film = NULL;
        }
        if (h[0] < 0 || h[0] >= c->nb || c->ready[h[0]])
            return mpi_fail(err, CST_ERR_INTERNAL, "rank %d sent block %lld, which is not one it was given", from,
                            (long long)h[0]);
        CstStatus status = cst_film_create(c->scene, &c->st, &in->film, err);
        if (status != CST_OK) return status;
        CstFilmSums s;
        cst_film_sums(in->film, &s);
        in->block = h[0];
        MPI_Irecv(s.sum, (int)(3 * s.pixels), MPI_DOUBLE, from, TAG_SUM, MPI_COMM_WORLD, &in->req[0]);
        MPI_Irecv(s.sum_sq, (int)(3 * s.pixels), MPI_DOUBLE, from, TAG_SQ, MPI_COMM_WORLD, &in->req[1]);
        in->req[2] = MPI_REQUEST_NULL;
        if (s.aov) MPI_Irecv(s.aov, (int)(8 * s.pixels), MPI_DOUBLE, from, TAG_AOV, MPI_COMM_WORLD, &in->req[2]);
        int s0, n;
        block_range(c, (int)h[0], &s0, &n);
        *s.spp = n;
        c->samples += (uint64_t)h[1];
        c->rays += (uint64_t)h[2];
        c->nonfinite += (uint64_t)h[3];
        assign_next(c, from);
    }
    return add_ready(c, err);
}

/* Worker: takes the assignments that have arrived into the queue. */
static void take_assignments(Cluster *c, bool wait)
{
    int flag = 1;
    while (c->qlen < QUEUE_CAP) {
        if (!wait) MPI_Iprobe(0, TAG_ASSIGN, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
        if (!flag) break;
        MPI_Recv(&c->queue[(c->qhead + c->qlen) % QUEUE_CAP], 1, MPI_INT64_T, 0, TAG_ASSIGN, MPI_COMM_WORLD,
                 MPI_STATUS_IGNORE);
        c->qlen++;
        wait = false;
    }
}

/* The progress callback of every block: rank 0 serves the others; a worker moves its last
 * result's sends along and takes new assignments. Never cancels. */
static int block_progress(void *user, double fraction, double elapsed)
{
    (void)fraction, (void)elapsed;
    Cluster *c = user;
    if (c->rank == 0) {
        CstError e = {0};
        CstStatus status = serve(c, &e);
        if (status != CST_OK) {
            fprintf(stderr, "caustic: error: %s\n", e.msg);
            MPI_Abort(MPI_COMM_WORLD, cli_exit_code(status, CLI_STAGE_RENDER));
        }
    } else {
        int done = 0;
        if (c->sending) MPI_Testall(4, c->req, &done, MPI_STATUSES_IGNORE);
        take_assignments(c, false);
    }
    return 0;
}

/* Renders block i into *film. */
static CstStatus render_block(Cluster *c, int i, CstFilm **film, CstError *err)
{
    CstRenderSettings b = c->st;
    block_range(c, i, &b.first_sample, &b.spp);
    b.sample_block = 1; /* one block from zero: the same sums as in blocks of B */
    b.progress = block_progress;
    b.progress_user = c;
    CstRenderStats rs;
    CstStatus status = cst_render(c->scene, &b, film, &rs, err);
    if (status == CST_ERR_NONFINITE && *film) status = CST_OK; /* judged on the whole job */
    if (status != CST_OK) return status;
    c->header[0] = i;
    c->header[1] = (int64_t)rs.samples;
    c->header[2] = (int64_t)rs.rays;
    c->header[3] = (int64_t)rs.nonfinite;
    return CST_OK;
}

static void wait_sends(Cluster *c)
{
    if (!c->sending) return;
    MPI_Waitall(4, c->req, MPI_STATUSES_IGNORE);
    cst_film_destroy(c->sending);
    c->sending = NULL;
}

/* A rank other than 0: blocks until told there are no more. */
static CstStatus worker(Cluster *c, CstError *err)
{
    for (int k = 0; k < 4; k++) c->req[k] = MPI_REQUEST_NULL;
    for (;;) {
        if (c->qlen == 0) take_assignments(c, true);
        const int64_t i = c->queue[c->qhead];
        c->qhead = (c->qhead + 1) % QUEUE_CAP;
        c->qlen--;
        if (i < 0) break;
        CstFilm *film = NULL;
        CstStatus status = render_block(c, (int)i, &film, err);
        if (status != CST_OK) return status;
        wait_sends(c);
        CstFilmSums s;
        cst_film_sums(film, &s);
        c->sending = film;
        MPI_Isend(c->header, 4, MPI_INT64_T, 0, TAG_HEADER, MPI_COMM_WORLD, &c->req[0]);
        MPI_Isend(s.sum, (int)(3 * s.pixels), MPI_DOUBLE, 0, TAG_SUM, MPI_COMM_WORLD, &c->req[1]);
        MPI_Isend(s.sum_sq, (int)(3 * s.pixels), MPI_DOUBLE, 0, TAG_SQ, MPI_COMM_WORLD, &c->req[2]);
        if (s.aov) MPI_Isend(s.aov, (int)(8 * s.pixels), MPI_DOUBLE, 0, TAG_AOV, MPI_COMM_WORLD, &c->req[3]);
        else c->req[3] = MPI_REQUEST_NULL;
        take_assignments(c, false);
    }
    wait_sends(c);
    return CST_OK;
}

/* Rank 0: hands out the first blocks, renders blocks while any are left, then waits for
 * the others' and adds the rest in order. */
static CstStatus leader(Cluster *c, CstError *err)
{
    for (int r = 1; r < c->size; r++)
        for (int k = 0; k < CLUSTER_AHEAD && !c->stopped[r]; k++) assign_next(c, r);
    CstStatus status = CST_OK;
    while (status == CST_OK && c->next < c->nb) {
        const int i = c->next++;
        CstFilm *film = NULL;
        if ((status = render_block(c, i, &film, err)) != CST_OK) break;
        c->ready[i] = film;
        c->samples += (uint64_t)c->header[1];
        c->rays += (uint64_t)c->header[2];
        c->nonfinite += (uint64_t)c->header[3];
        status = serve(c, err);
    }
    /* The tail: the others' last blocks, polled gently rather than waited for in MPI. */
    while (status == CST_OK && c->added < c->nb && (status = serve(c, err)) == CST_OK && c->added < c->nb) {
        struct timespec ts = {0, 1000000};
        nanosleep(&ts, NULL);
    }
    for (int r = 1; r < c->size && status == CST_OK; r++) assign_next(c, r); /* no more */
    return status;
}

CstStatus cli_mpi_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                         CstRenderStats *stats, CstError *err)
{
    *out = NULL;
    Cluster c;
    memset(&c, 0, sizeof c);
    MPI_Comm_rank(MPI_COMM_WORLD, &c.rank);
    MPI_Comm_size(MPI_COMM_WORLD, &c.size);
    c.scene = scene;
    cst_render_settings_resolve(scene, settings, &c.st);
    if (c.st.time_limit > 0.0 || c.st.spp <= 0 || settings->resume || c.st.integrator == CST_INTEGRATOR_SPPM)
        return mpi_fail(err, CST_ERR_UNSUPPORTED,
                        "under mpirun: %s; expected a sample count (--spp) without --time, --resume or "
                        "--checkpoint, and an integrator other than sppm (its iterations depend on each other)",
                        c.st.integrator == CST_INTEGRATOR_SPPM ? "sppm cannot be split across ranks"
                        : settings->resume ? "--resume is not supported across ranks yet"
                                           : "a time limit cannot be split into fixed blocks");
    c.st.progress = NULL, c.st.progress_user = NULL, c.st.progress_phase = NULL;
    c.st.pass_done = NULL, c.st.pass_user = NULL, c.st.resume = NULL;
    c.first = c.st.first_sample;
    c.end = c.st.first_sample + c.st.spp;
    c.B = c.st.sample_block;
    c.k0 = c.first / c.B;
    c.nb = (int)(((int64_t)c.end + c.B - 1) / c.B - c.k0);
    const double t0 = cli_clock_seconds();
    CstStatus status;
    if (c.rank != 0) {
        status = worker(&c, err);
        if (status != CST_OK) {
            /* The others would wait for this rank's blocks: end the job with the reason. */
            fprintf(stderr, "caustic: error: rank %d: %s\n", c.rank, err->msg);
            MPI_Abort(MPI_COMM_WORLD, cli_exit_code(status, CLI_STAGE_RENDER));
        }
        return status;
    }
    c.ready = calloc((size_t)c.nb, sizeof *c.ready);
    c.stopped = calloc((size_t)c.size, sizeof *c.stopped);
    c.incoming = calloc((size_t)c.size, sizeof *c.incoming);
    if (!c.ready || !c.stopped || !c.incoming) status = mpi_fail(err, CST_ERR_OOM, "out of memory for %d blocks", c.nb);
    else status = cst_film_create(scene, &c.st, &c.total, err);
    if (status == CST_OK) status = leader(&c, err);
    if (status != CST_OK) {
        fprintf(stderr, "caustic: error: rank 0: %s\n", err->msg);
        MPI_Abort(MPI_COMM_WORLD, cli_exit_code(status, CLI_STAGE_RENDER));
    }
    for (int i = 0; i < c.nb; i++) cst_film_destroy(c.ready[i]);
    free(c.ready);
    free(c.stopped);
    free(c.incoming);
    memset(stats, 0, sizeof *stats);
    stats->seconds = cli_clock_seconds() - t0;
    stats->samples = c.samples;
    stats->rays = c.rays;
    stats->nonfinite = c.nonfinite;
    stats->spp = c.st.spp;
    stats->threads = c.st.threads;
    stats->width = cst_film_width(c.total);
    stats->height = cst_film_height(c.total);
    stats->integrator = c.st.integrator;
    stats->filter = c.st.filter;
    *out = c.total;
    return CST_OK;
}

#else /* !CLI_HAVE_MPI */

int cli_mpi_start(int *rank)
{
    *rank = 0;
    return 0;
}

void cli_mpi_stop(void) {}

bool cli_mpi_active(void) { return false; }

CstStatus cli_mpi_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                         CstRenderStats *stats, CstError *err)
{
    (void)scene, (void)settings, (void)stats;
    *out = NULL;
    return mpi_fail(err, CST_ERR_UNSUPPORTED, "this caustic was built without MPI");
}

#endif
