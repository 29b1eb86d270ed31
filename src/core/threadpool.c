/* The persistent worker pool (threadpool.h): workers sleep on a condition variable
 * between parallel-fors and take items from one atomic counter while one runs. */
#include "core/threadpool.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <time.h>

typedef struct PoolWorker {
    ThreadPool *pool;
    int index;
    pthread_t thread;
} PoolWorker;

struct ThreadPool {
    pthread_mutex_t lock;
    pthread_cond_t wake; /* a parallel-for began, or quit */
    pthread_cond_t idle; /* the last worker left the parallel-for */
    PoolWorker *workers;
    int size;
    /* The current parallel-for; written under `lock` while every worker is idle. */
    uint64_t generation; /* bumped by each begin: a worker runs each generation once */
    bool quit;
    ThreadPoolFn fn;
    void *ctx;
    int n;
    int active;          /* workers that have not yet left this parallel-for */
    atomic_int next;     /* the next item to hand out */
    atomic_int finished; /* items done */
    atomic_bool cancel;
};

static void *pool_worker_main(void *arg)
{
    PoolWorker *w = arg;
    ThreadPool *p = w->pool;
    uint64_t seen = 0;
    pthread_mutex_lock(&p->lock);
    for (;;) {
        while (!p->quit && p->generation == seen) pthread_cond_wait(&p->wake, &p->lock);
        if (p->quit) break;
        seen = p->generation;
        ThreadPoolFn fn = p->fn;
        void *ctx = p->ctx;
        const int n = p->n;
        pthread_mutex_unlock(&p->lock);
        while (!atomic_load_explicit(&p->cancel, memory_order_relaxed)) {
            int i = atomic_fetch_add(&p->next, 1);
            if (i >= n) break;
            fn(ctx, i, w->index);
            atomic_fetch_add(&p->finished, 1);
        }
        pthread_mutex_lock(&p->lock);
        /* The caller returns from threadpool_wait only when every worker is out, so the
         * next begin never races a worker still reading this one's fields. */
        if (--p->active == 0) pthread_cond_broadcast(&p->idle);
    }
    pthread_mutex_unlock(&p->lock);
    return NULL;
}

CstStatus threadpool_create(int threads, ThreadPool **out)
{
    *out = NULL;
    if (threads < 1) threads = 1;
    ThreadPool *p = calloc(1, sizeof *p);
    PoolWorker *w = calloc((size_t)threads, sizeof *w);
    if (!p || !w) { free(p); free(w); return CST_ERR_OOM; }
    pthread_mutex_init(&p->lock, NULL);
    pthread_cond_init(&p->wake, NULL);
    pthread_cond_init(&p->idle, NULL);
    atomic_init(&p->next, 0);
    atomic_init(&p->finished, 0);
    atomic_init(&p->cancel, false);
    p->workers = w;
    for (int i = 0; i < threads; i++) {
        w[i].pool = p;
        w[i].index = i;
        if (pthread_create(&w[i].thread, NULL, pool_worker_main, &w[i]) != 0) break;
        p->size++;
    }
    if (p->size == 0) {
        threadpool_destroy(p);
        return CST_ERR_INTERNAL;
    }
    *out = p;
    return CST_OK;
}

void threadpool_destroy(ThreadPool *p)
{
    if (!p) return;
    pthread_mutex_lock(&p->lock);
    p->quit = true;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
    for (int i = 0; i < p->size; i++) pthread_join(p->workers[i].thread, NULL);
    pthread_cond_destroy(&p->idle);
    pthread_cond_destroy(&p->wake);
    pthread_mutex_destroy(&p->lock);
    free(p->workers);
    free(p);
}

int threadpool_size(const ThreadPool *p) { return p->size; }

void threadpool_begin(ThreadPool *p, int n, ThreadPoolFn fn, void *ctx)
{
    pthread_mutex_lock(&p->lock);
    p->fn = fn;
    p->ctx = ctx;
    p->n = n;
    p->active = p->size;
    atomic_store(&p->next, 0);
    atomic_store(&p->finished, 0);
    atomic_store(&p->cancel, false);
    p->generation++;
    pthread_cond_broadcast(&p->wake);
    pthread_mutex_unlock(&p->lock);
}

bool threadpool_wait(ThreadPool *p, double seconds)
{
    struct timespec ts;
    if (seconds >= 0.0) {
        clock_gettime(CLOCK_REALTIME, &ts);
        long ns = ts.tv_nsec + (long)(seconds * 1e9);
        ts.tv_sec += ns / 1000000000L;
        ts.tv_nsec = ns % 1000000000L;
    }
    pthread_mutex_lock(&p->lock);
    while (p->active > 0) {
        if (seconds < 0.0) pthread_cond_wait(&p->idle, &p->lock);
        else if (pthread_cond_timedwait(&p->idle, &p->lock, &ts) != 0) break;
    }
    bool done = p->active == 0;
    pthread_mutex_unlock(&p->lock);
    return done;
}

int threadpool_done(ThreadPool *p) { return atomic_load(&p->finished); }

void threadpool_cancel(ThreadPool *p) { atomic_store(&p->cancel, true); }

void threadpool_for(ThreadPool *p, int n, ThreadPoolFn fn, void *ctx)
{
    threadpool_begin(p, n, fn, ctx);
    threadpool_wait(p, -1.0);
}
