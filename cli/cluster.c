/* Distributed rendering over MPI (issue 29): rank 0 hands out blocks of samples of one
 * render (CstRenderSettings.sample_block) to the ranks that ask, renders blocks itself in
 * between, and adds every block's sums to the film in block order, never in the order
 * they arrive, so the image is bit for bit a one-process render's whatever the number of
 * ranks or their speed. Only the CLI knows MPI: the library renders each block as an
 * ordinary cst_render of samples [first_sample, first_sample + spp).
 * Checkpoints and resume: rank 0's film is, after every block it adds, the film a
 * one-process render holds at that block's end, so the CLI's pass callback writes it with
 * cst_film_state_write as it would a one-process render's; a resume starts the blocks at
 * the state's sample count. A stop (SIGINT/SIGTERM to any rank) ends the job with rank 0's
 * film of the blocks added so far; the others are ended by MPI_Abort once it is written. */
#include "cluster.h"

#include <signal.h>
#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "cli.h"
#include "signals.h"

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
enum { TAG_ASSIGN = 1, TAG_HEADER, TAG_SUM, TAG_SQ, TAG_AOV, TAG_STOP };
/* Blocks handed to a rank ahead of the one it renders, so it never waits for rank 0, which
 * answers only between its own steps (about ten times a second). */
enum { CLUSTER_AHEAD = 2, QUEUE_CAP = 8 };
/* The samples per pixel of a render under mpirun with --time and no --spp: the most it
 * may reach (a one-process render has no such cap). */
enum { CLUSTER_SPP_CAP = 1 << 20 };

static int g_started;
/* Rank 0 stopped before the last block (a signal, a failed checkpoint): the others may be
 * rendering or waiting, so the job ends by MPI_Abort, not MPI_Finalize (cli_mpi_stop). */
static int g_unfinished;

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

void cli_mpi_stop(int exit_code)
{
    if (g_started && g_unfinished) MPI_Abort(MPI_COMM_WORLD, exit_code ? exit_code : 1);
    if (g_started) MPI_Finalize();
    g_started = 0;
}

bool cli_mpi_active(void) { return g_started != 0; }

/* One rank's view of the job. */
typedef struct Cluster {
    int rank, size;
    const CstScene *scene;
    CstRenderSettings st;     /* resolved, no callbacks */
    const CstRenderSettings *user; /* the caller's: pass_done (checkpoints, stops) */
    double t0;                /* the job's start, for CstPassInfo.elapsed_seconds */
    bool stop;                /* rank 0: stop after the blocks added (pass_done or a signal) */
    bool stop_told;           /* pass_done has returned nonzero: it has seen the stop */
    bool last_told;           /* pass_done's last call said last */
    int stop_sent;            /* worker: its signal has been reported to rank 0 */
    int first, end, B, k0, nb; /* samples [first, end), blocks k0 .. k0 + nb - 1 */
    int next;                  /* rank 0: the next block to hand out (0 .. nb) */
    double time_limit;         /* rank 0: seconds after t0 past which no block is handed out; 0: none */
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

/* Rank 0: with a time limit, once it has passed, the blocks handed out are the last: nb
 * shrinks to them, and the job ends when they are added (a one-process render with that
 * many samples and the same sample_block, bit for bit). The blocks already handed out are
 * rendered: the job overruns the limit by at most CLUSTER_AHEAD + 1 blocks of a rank. */
static bool time_up(Cluster *c)
{
    if (c->time_limit > 0.0 && c->next < c->nb && cli_clock_seconds() - c->t0 >= c->time_limit) c->nb = c->next;
    return c->next >= c->nb;
}

/* Rank 0: the next block for rank `to`, or the word that there is none (once). */
static void assign_next(Cluster *c, int to)
{
    if (!time_up(c)) assign(to, c->next++);
    else if (!c->stopped[to]) {
        assign(to, -1);
        c->stopped[to] = 1;
    }
}

/* Rank 0: the caller's pass_done with the film as it stands (the resumed samples and the
 * blocks added): a one-process render's film at the same block end. A nonzero answer
 * stops the job there. */
static void report_pass(Cluster *c, bool last)
{
    if (!c->user->pass_done || c->stop_told) return;
    c->last_told = last;
    CstPassInfo info = {cst_film_spp(c->total), last, cli_clock_seconds() - c->t0};
    if (c->user->pass_done(c->user->pass_user, c->total, &info) != 0) c->stop = c->stop_told = true;
}

/* Rank 0: adds the blocks that are next in order (none once stopping: the film stays as
 * pass_done last saw it), then tells pass_done. */
static CstStatus add_ready(Cluster *c, CstError *err)
{
    const int before = c->added;
    while (!c->stop && c->added < c->nb && c->ready[c->added]) {
        CstStatus status = cst_film_add(c->total, c->ready[c->added], err);
        cst_film_destroy(c->ready[c->added]);
        c->ready[c->added++] = NULL;
        if (status != CST_OK) return status;
    }
    if (c->added > before) report_pass(c, c->added == c->nb);
    return CST_OK;
}

/* Rank 0: a worker's report that it was signalled (TAG_STOP) becomes rank 0's own stop
 * request (the CLI's handler, armed for the render), so the CLI writes the image and the
 * state and reports the signal as for a one-process render. */
static void take_stops(Cluster *c)
{
    for (;;) {
        int flag = 0, sig = 0;
        MPI_Status ms;
        MPI_Iprobe(MPI_ANY_SOURCE, TAG_STOP, MPI_COMM_WORLD, &flag, &ms);
        if (!flag) break;
        MPI_Recv(&sig, 1, MPI_INT, ms.MPI_SOURCE, TAG_STOP, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
        if (!cli_signals_stop_requested()) raise(sig == SIGTERM ? SIGTERM : SIGINT);
    }
    if (cli_signals_stop_requested()) c->stop = true;
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
    take_stops(c);
    if (c->stop) return CST_OK; /* nothing more is added or handed out */
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
 * result's sends along and takes new assignments. Cancels the block on a stop: rank 0's
 * (a signal, a worker's report, pass_done), or a worker's own signal, which it reports to
 * rank 0 once (mpirun signals every rank: SIGTERM after a SIGINT to it). */
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
        return c->stop;
    }
    int sig = cli_signals_stop_requested();
    if (sig) {
        if (!c->stop_sent) MPI_Send(&sig, 1, MPI_INT, 0, TAG_STOP, MPI_COMM_WORLD);
        c->stop_sent = 1;
        return 1;
    }
    int done = 0;
    if (c->sending) MPI_Testall(4, c->req, &done, MPI_STATUSES_IGNORE);
    take_assignments(c, false);
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
    if (status != CST_OK) return status; /* CST_ERR_CANCELLED: a stop, the caller's to handle */
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
        if (status == CST_ERR_CANCELLED) {
            /* Stopped by a signal, reported to rank 0, which writes what is done and ends
             * the job by MPI_Abort: wait for it (blocks still handed out are not rendered). */
            for (;;) take_assignments(c, true), c->qlen = 0;
        }
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

/* ------------------------------------------------------------ sppm: the photon pass split */

/* SPPM's iterations each depend on all before them, so one rank, 0, renders the whole
 * render (camera pass, gather, radii, checkpoints) and the others trace photons only: rank
 * r traces chunks [lo(r), lo(r + 1)) of every iteration (cst_sppm_trace_chunk) and sends
 * their hits to rank 0, whose render fetches them (CstPhotonSplit) and gathers every photon
 * in photon order: bit for bit a one-process render, whatever the number of ranks. A fixed
 * split: a photon's path does not depend on the iteration's state, so a tracer traces
 * iteration k + 1 while rank 0 gathers iteration k, and nothing is handed out. */
enum { TAG_HITS_N = 16, TAG_HITS };

/* Waits for requests by testing them every half millisecond: a blocking MPI call spins on
 * the CPU in Open MPI (over shared memory), which a tracer waiting for rank 0 to post its
 * receive, or rank 0 waiting for a tracer, would take from the ranks that work. */
static void wait_gently(int n, MPI_Request *req)
{
    for (;;) {
        int done = 0;
        MPI_Testall(n, req, &done, MPI_STATUSES_IGNORE);
        if (done) return;
        struct timespec ts = {0, 500000};
        nanosleep(&ts, NULL);
    }
}

static int chunk_lo(int chunks, int r, int size) { return (int)((int64_t)chunks * r / size); }

/* Rank 0's side of the split: per rank, the iteration whose hits it holds, their floats and
 * the offsets of its chunks in them. */
typedef struct PhotonInbox {
    Cluster *c;
    int chunks;
    int *iter;        /* per rank, -1 = none yet */
    float **buf;      /* per rank */
    size_t *cap;      /* per rank, floats */
    int64_t **off;    /* per rank: chunk offsets in floats, one more than its chunks */
} PhotonInbox;

/* Rank 0: waits (polling, so that its render threads keep the CPU) for rank r's hits of
 * iteration k: its chunk counts, then the floats. Reports of signalled ranks are taken in
 * the meantime. */
static int inbox_receive(PhotonInbox *in, int r, int k)
{
    const int n = chunk_lo(in->chunks, r + 1, in->c->size) - chunk_lo(in->chunks, r, in->c->size);
    for (;;) {
        int flag = 0;
        MPI_Iprobe(r, TAG_HITS_N, MPI_COMM_WORLD, &flag, MPI_STATUS_IGNORE);
        if (flag) break;
        take_stops(in->c);
        struct timespec ts = {0, 500000};
        nanosleep(&ts, NULL);
    }
    int64_t *off = in->off[r];
    off[0] = 0;
    MPI_Recv(off + 1, n, MPI_INT64_T, r, TAG_HITS_N, MPI_COMM_WORLD, MPI_STATUS_IGNORE);
    for (int i = 0; i < n; i++) off[i + 1] += off[i];
    const int64_t total = off[n];
    if (total > INT32_MAX) return 1;
    if ((size_t)total > in->cap[r]) {
        float *b = realloc(in->buf[r], (size_t)total * sizeof *b);
        if (!b) return 1;
        in->buf[r] = b;
        in->cap[r] = (size_t)total;
    }
    MPI_Request req;
    MPI_Irecv(in->buf[r], (int)total, MPI_FLOAT, r, TAG_HITS, MPI_COMM_WORLD, &req);
    wait_gently(1, &req);
    in->iter[r] = k;
    return 0;
}

/* CstPhotonSplit.fetch on rank 0: chunk `chunk` of iteration `k`, from its rank's message. */
static int inbox_fetch(void *user, int k, int chunk, const float **hits, size_t *count)
{
    PhotonInbox *in = user;
    int r = 1;
    while (r + 1 < in->c->size && chunk >= chunk_lo(in->chunks, r + 1, in->c->size)) r++;
    if (in->iter[r] != k && inbox_receive(in, r, k) != 0) return 1;
    const int i = chunk - chunk_lo(in->chunks, r, in->c->size);
    *hits = in->buf[r] + in->off[r][i];
    *count = (size_t)(in->off[r][i + 1] - in->off[r][i]);
    return 0;
}

/* A rank other than 0: its chunks of iterations [first, end), sent to rank 0. A signal is
 * reported to rank 0 (which stops at its pass end) and the tracing goes on, since rank 0
 * waits for these hits; the job is then ended by rank 0 (cli_mpi_stop). */
static CstStatus sppm_tracer(Cluster *c, int chunks, int first, int end, CstError *err)
{
    const int lo = chunk_lo(chunks, c->rank, c->size), hi = chunk_lo(chunks, c->rank + 1, c->size);
    int64_t *counts = calloc((size_t)(hi - lo) + 1, sizeof *counts);
    float *hits = NULL;
    size_t cap = 0;
    CstStatus status = counts ? CST_OK : mpi_fail(err, CST_ERR_OOM, "out of memory for %d chunks", hi - lo);
    for (int k = first; k < end && status == CST_OK; k++) {
        size_t count = 0;
        for (int ch = lo; ch < hi && status == CST_OK; ch++) {
            const size_t before = count;
            status = cst_sppm_trace_chunk(c->scene, &c->st, k, ch, &hits, &count, &cap, &c->rays, err);
            counts[ch - lo] = (int64_t)(count - before);
        }
        if (status == CST_OK && count > INT32_MAX)
            status = mpi_fail(err, CST_ERR_UNSUPPORTED, "%zu photon hit floats in one message: expected fewer "
                              "photons per rank (more ranks, or fewer photons)", count);
        if (status != CST_OK) break;
        const int sig = cli_signals_stop_requested();
        if (sig && !c->stop_sent) {
            MPI_Send(&sig, 1, MPI_INT, 0, TAG_STOP, MPI_COMM_WORLD);
            c->stop_sent = 1;
        }
        MPI_Request req[2];
        MPI_Isend(counts, hi - lo, MPI_INT64_T, 0, TAG_HITS_N, MPI_COMM_WORLD, &req[0]);
        MPI_Isend(hits, (int)count, MPI_FLOAT, 0, TAG_HITS, MPI_COMM_WORLD, &req[1]);
        wait_gently(2, req);
    }
    free(counts);
    free(hits);
    return status;
}

/* sppm under mpirun: rank 0 renders with the split, the others trace. Iterations resume
 * from the state's count (rank 0's cst_render restores the rest of SPPM's state). */
static CstStatus sppm_job(Cluster *c, CstFilm **out, CstRenderStats *stats, CstError *err)
{
    const int chunks = cst_sppm_photon_chunks(c->scene, &c->st);
    const int first = c->user->resume ? cst_film_spp(c->user->resume) : 0;
    if (c->rank != 0) {
        CstStatus status = sppm_tracer(c, chunks, first, c->st.spp, err);
        if (status != CST_OK) {
            fprintf(stderr, "caustic: error: rank %d: %s\n", c->rank, err->msg);
            MPI_Abort(MPI_COMM_WORLD, cli_exit_code(status, CLI_STAGE_RENDER));
        }
        return status;
    }
    PhotonInbox in = {c, chunks, NULL, NULL, NULL, NULL};
    const size_t size = (size_t)c->size;
    in.iter = malloc(size * sizeof *in.iter);
    in.buf = calloc(size, sizeof *in.buf);
    in.cap = calloc(size, sizeof *in.cap);
    in.off = calloc(size, sizeof *in.off);
    CstStatus status = in.iter && in.buf && in.cap && in.off ? CST_OK
                       : mpi_fail(err, CST_ERR_OOM, "out of memory for %d ranks", c->size);
    for (int r = 0; r < c->size && status == CST_OK; r++) {
        in.iter[r] = -1;
        const int n = chunk_lo(chunks, r + 1, c->size) - chunk_lo(chunks, r, c->size);
        if (!(in.off[r] = calloc((size_t)n + 1, sizeof *in.off[r])))
            status = mpi_fail(err, CST_ERR_OOM, "out of memory for %d chunks", n);
    }
    if (status == CST_OK) {
        const CstPhotonSplit split = {0, chunk_lo(chunks, 1, c->size), inbox_fetch, &in};
        CstRenderSettings s = *c->user;
        s.photon_split = &split;
        status = cst_render(c->scene, &s, out, stats, err);
    }
    /* Every tracer has sent every iteration only when the render ran to its end. */
    const bool complete = (status == CST_OK && !stats->stopped) || (status == CST_ERR_NONFINITE && *out);
    g_unfinished = c->size > 1 && !complete;
    for (int r = 0; in.buf && r < c->size; r++) free(in.buf[r]);
    for (int r = 0; in.off && r < c->size; r++) free(in.off[r]);
    free(in.iter);
    free(in.buf);
    free(in.cap);
    free(in.off);
    return status;
}

/* Rank 0: hands out the first blocks, renders blocks while any are left, then waits for
 * the others' and adds the rest in order. */
static CstStatus leader(Cluster *c, CstError *err)
{
    for (int r = 1; r < c->size; r++)
        for (int k = 0; k < CLUSTER_AHEAD && !c->stopped[r]; k++) assign_next(c, r);
    CstStatus status = CST_OK;
    if (c->nb == 0) report_pass(c, true); /* a resume with nothing left to render */
    while (status == CST_OK && !time_up(c) && !c->stop) {
        const int i = c->next++;
        CstFilm *film = NULL;
        if ((status = render_block(c, i, &film, err)) != CST_OK) {
            if (status == CST_ERR_CANCELLED && c->stop) status = CST_OK; /* the block is abandoned */
            break;
        }
        c->ready[i] = film;
        c->samples += (uint64_t)c->header[1];
        c->rays += (uint64_t)c->header[2];
        c->nonfinite += (uint64_t)c->header[3];
        status = serve(c, err);
    }
    /* The tail: the others' last blocks, polled gently rather than waited for in MPI. */
    while (status == CST_OK && !c->stop && c->added < c->nb && (status = serve(c, err)) == CST_OK &&
           c->added < c->nb && !c->stop) {
        struct timespec ts = {0, 1000000};
        nanosleep(&ts, NULL);
    }
    if (status == CST_OK && c->stop) {
        /* The film of the blocks added: pass_done sees the stop (and writes the state) if it
         * has not already; the others are ended when the CLI is through (cli_mpi_stop). */
        if (cst_film_spp(c->total) > 0) report_pass(c, false);
        g_unfinished = c->added < c->nb;
        return CST_OK;
    }
    /* A time limit that shrank nb after the last block was added: pass_done has not been
     * told that this film is the last. */
    if (status == CST_OK && !c->last_told) report_pass(c, true);
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
    c.user = settings;
    cst_render_settings_resolve(scene, settings, &c.st);
    if (c.st.integrator == CST_INTEGRATOR_SPPM) {
        if (c.st.time_limit > 0.0 || c.st.spp <= 0)
            return mpi_fail(err, CST_ERR_UNSUPPORTED, "sppm under mpirun: its photon chunks are split over the "
                            "ranks for a fixed number of iterations; expected --spp without --time");
        return sppm_job(&c, out, stats, err);
    }
    /* A time limit: blocks are handed out until it has passed (time_up), up to the sample
     * count if one is given, else up to CLUSTER_SPP_CAP samples (the blocks' table is
     * allocated for all of them). The blocks render without a limit of their own. */
    c.time_limit = c.st.time_limit > 0.0 ? c.st.time_limit : 0.0;
    if (c.st.spp <= 0) {
        if (!(c.time_limit > 0.0))
            return mpi_fail(err, CST_ERR_INVALID_ARG, "under mpirun: expected a sample count (--spp) or a time "
                            "limit (--time)");
        c.st.spp = CLUSTER_SPP_CAP - c.st.first_sample > 0 ? CLUSTER_SPP_CAP - c.st.first_sample : 1;
    }
    c.st.time_limit = 0.0;
    /* A resumed film's samples [first_sample, first_sample + done) are done: the blocks start
     * there, at a block end (a state is written only there), as cst_render's would. */
    const int done = settings->resume ? cst_film_spp(settings->resume) : 0;
    if (done > 0 && done < c.st.spp && (c.st.first_sample + done) % c.st.sample_block != 0)
        return mpi_fail(err, CST_ERR_INVALID_ARG, "resume: the film ends at sample %d, inside a block of %d; "
                        "expected a film of whole blocks (a state written at a block end)",
                        c.st.first_sample + done, c.st.sample_block);
    c.st.progress = NULL, c.st.progress_user = NULL, c.st.progress_phase = NULL;
    c.st.pass_done = NULL, c.st.pass_user = NULL, c.st.resume = NULL;
    c.first = c.st.first_sample + (done < c.st.spp ? done : c.st.spp);
    c.end = c.st.first_sample + c.st.spp;
    c.B = c.st.sample_block;
    c.k0 = c.first / c.B;
    c.nb = c.first < c.end ? (int)(((int64_t)c.end + c.B - 1) / c.B - c.k0) : 0;
    const double t0 = cli_clock_seconds();
    c.t0 = t0;
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
    c.ready = calloc((size_t)c.nb + 1, sizeof *c.ready);
    c.stopped = calloc((size_t)c.size, sizeof *c.stopped);
    c.incoming = calloc((size_t)c.size, sizeof *c.incoming);
    if (!c.ready || !c.stopped || !c.incoming) status = mpi_fail(err, CST_ERR_OOM, "out of memory for %d blocks", c.nb);
    else status = cst_film_create(scene, &c.st, &c.total, err);
    /* The resumed sums: 0 + x is x exactly (a sum is never -0), so the film holds the
     * state's bits, and the blocks add to them as cst_render's resume does. */
    if (status == CST_OK && settings->resume) status = cst_film_add(c.total, settings->resume, err);
    if (status == CST_OK) status = leader(&c, err);
    if (status != CST_OK) {
        fprintf(stderr, "caustic: error: rank 0: %s\n", err->msg);
        MPI_Abort(MPI_COMM_WORLD, cli_exit_code(status, CLI_STAGE_RENDER));
    }
    for (int i = 0; i < c.nb; i++) cst_film_destroy(c.ready[i]);
    /* After a stop, a result being received keeps its film: MPI may still write into it
     * until the job is ended (cli_mpi_stop). */
    free(c.ready);
    free(c.stopped);
    free(c.incoming);
    if (c.stop && cst_film_spp(c.total) == 0) {
        cst_film_destroy(c.total);
        return mpi_fail(err, CST_ERR_CANCELLED, "render stopped before its first block was complete");
    }
    memset(stats, 0, sizeof *stats);
    stats->seconds = cli_clock_seconds() - t0;
    stats->samples = c.samples;
    stats->rays = c.rays;
    stats->nonfinite = c.nonfinite;
    stats->spp = cst_film_spp(c.total);
    stats->first_spp = done < c.st.spp ? done : c.st.spp;
    stats->stopped = c.stop && c.added < c.nb;
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

void cli_mpi_stop(int exit_code) { (void)exit_code; }

bool cli_mpi_active(void) { return false; }

CstStatus cli_mpi_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                         CstRenderStats *stats, CstError *err)
{
    (void)scene, (void)settings, (void)stats;
    *out = NULL;
    return mpi_fail(err, CST_ERR_UNSUPPORTED, "this caustic was built without MPI");
}

#endif
