/* The one thread pool: worker threads started once and kept alive between parallel-for
 * calls (render passes, SPPM phases, the BVH build). The only pthread_create in src/. */
#ifndef CST_CORE_THREADPOOL_H
#define CST_CORE_THREADPOOL_H

#include <stdbool.h>

#include "core/error.h"

typedef struct ThreadPool ThreadPool;

/* One work item: `item` in [0, n) of the current parallel-for, run by worker `worker` in
 * [0, threadpool_size()). Determinism is the caller's contract, kept by every user: the
 * work is cut into items by the caller (never by the thread count), an item's results
 * depend only on the item, and `worker` may only select integer counters (rays, NaNs)
 * whose totals do not depend on the order they are summed in. Items are handed out
 * first come first served, so which worker runs which item is not fixed. */
typedef void (*ThreadPoolFn)(void *ctx, int item, int worker);

/* Starts `threads` workers (<= 0: one). Fails with CST_ERR_OOM, or CST_ERR_INTERNAL if
 * not even one thread could be started (fewer than asked is not an error: the pool runs
 * with what it has, and the results are the same). Caller owns it: threadpool_destroy(). */
CstStatus threadpool_create(int threads, ThreadPool **out);
/* Stops and joins the workers. Accepts NULL. Not during a parallel-for. */
void threadpool_destroy(ThreadPool *pool);
/* Workers actually running. */
int threadpool_size(const ThreadPool *pool);

/* Starts fn(ctx, i, worker) for every i in [0, n) and returns at once; the calling
 * thread does none of the work (it reports progress). One parallel-for at a time:
 * threadpool_wait() must have returned true before the next begins. */
void threadpool_begin(ThreadPool *pool, int n, ThreadPoolFn fn, void *ctx);
/* Waits up to `seconds` (< 0: without limit) for the parallel-for to end; true once it
 * has (every item done, or every worker stopped after threadpool_cancel), false on
 * timeout. */
bool threadpool_wait(ThreadPool *pool, double seconds);
/* Items finished so far in the current parallel-for (for progress). */
int threadpool_done(ThreadPool *pool);
/* Workers take no new item; items already running finish. threadpool_wait() still
 * has to be called. */
void threadpool_cancel(ThreadPool *pool);
/* threadpool_begin + threadpool_wait(-1). */
void threadpool_for(ThreadPool *pool, int n, ThreadPoolFn fn, void *ctx);

#endif
