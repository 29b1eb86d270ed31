/* The thread pool (core/threadpool.h) and the growable array (core/array.h): every item
 * of a parallel-for runs exactly once, the workers survive between calls, cancellation
 * stops at item boundaries; array growth and its overflow rule. */
#include <setjmp.h>
#include <stdarg.h>
#include <stdatomic.h>
#include <stddef.h>
#include <stdint.h>
#include <cmocka.h>

#include "core/array.h"
#include "core/threadpool.h"

enum { ITEMS = 10000 };

typedef struct Counts {
    atomic_int runs[ITEMS];
    atomic_int workers_seen;
    int size;
} Counts;

static void count_item(void *ctx, int item, int worker)
{
    Counts *c = ctx;
    atomic_fetch_add(&c->runs[item], 1);
    if (worker < 0 || worker >= c->size) atomic_fetch_add(&c->workers_seen, 1000000);
}

static void test_every_item_once(void **state)
{
    (void)state;
    static Counts c;
    for (int threads = 1; threads <= 4; threads++) {
        ThreadPool *pool;
        assert_int_equal(threadpool_create(threads, &pool), CST_OK);
        c.size = threadpool_size(pool);
        assert_int_equal(c.size, threads);
        /* Several parallel-fors on the same workers, of sizes below and above the pool's. */
        const int sizes[] = {0, 1, 3, ITEMS};
        for (size_t k = 0; k < sizeof sizes / sizeof sizes[0]; k++) {
            for (int i = 0; i < ITEMS; i++) atomic_store(&c.runs[i], 0);
            threadpool_for(pool, sizes[k], count_item, &c);
            assert_int_equal(threadpool_done(pool), sizes[k]);
            for (int i = 0; i < ITEMS; i++) assert_int_equal(atomic_load(&c.runs[i]), i < sizes[k] ? 1 : 0);
        }
        assert_int_equal(atomic_load(&c.workers_seen), 0);
        threadpool_destroy(pool);
    }
    threadpool_destroy(NULL);
}

static void cancel_item(void *ctx, int item, int worker)
{
    (void)worker;
    ThreadPool **pool = ctx;
    if (item == 5) threadpool_cancel(*pool);
}

static void test_cancel(void **state)
{
    (void)state;
    ThreadPool *pool;
    assert_int_equal(threadpool_create(2, &pool), CST_OK);
    threadpool_begin(pool, ITEMS, cancel_item, &pool);
    assert_true(threadpool_wait(pool, -1.0));
    /* Item 5 and those already taken finish; no new one starts. */
    int done = threadpool_done(pool);
    assert_true(done >= 6 && done < ITEMS);
    /* The next parallel-for is not cancelled. */
    static Counts c;
    c.size = threadpool_size(pool);
    threadpool_for(pool, 100, count_item, &c);
    assert_int_equal(threadpool_done(pool), 100);
    threadpool_destroy(pool);
}

static void test_array(void **state)
{
    (void)state;
    ARRAY(int) a = {0};
    for (int i = 0; i < 1000; i++) assert_true(array_push(&a, i));
    assert_int_equal(a.n, 1000);
    assert_true(a.cap >= 1000);
    for (int i = 0; i < 1000; i++) assert_int_equal(a.v[i], i);
    /* A size whose byte count overflows size_t fails and leaves the array as it was. */
    int *before = a.v;
    assert_false(array_reserve(&a, SIZE_MAX / 2));
    assert_ptr_equal(a.v, before);
    assert_int_equal(a.n, 1000);
    array_free(&a);
    assert_null(a.v);
    assert_int_equal(a.cap, 0);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_every_item_once),
        cmocka_unit_test(test_cancel),
        cmocka_unit_test(test_array),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
