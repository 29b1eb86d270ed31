/* VCM's merging grid (integrators/vcm.c): the bucket sort that render.c splits into
 * ranges over threads, against its definition (bucket c holds exactly the vertices whose
 * cell hashes to c, in vertex order), for partitions of 1 to 97 ranges, empty ranges
 * included; and the hash's spread of a wall's cells over the buckets. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "integrators/vcm.h"

typedef struct SortedGrid {
    uint32_t *cell_start;
    MergeVertex *items;
} SortedGrid;

/* Sorts it->vertices[0, n) into `cells` buckets with `ranges` ranges, counted then
 * filled, each step over the ranges in an order that is not the natural one (threads
 * finish in any). */
static SortedGrid sort_with_ranges(SubpathIteration *it, const uint32_t *cell_of, size_t n, uint32_t cells, int ranges)
{
    SortedGrid g = {malloc((cells + 1) * sizeof *g.cell_start), malloc((n ? n : 1) * sizeof *g.items)};
    assert_non_null(g.cell_start);
    assert_non_null(g.items);
    memset(g.cell_start, 0xab, (cells + 1) * sizeof *g.cell_start); /* no stale zeros to lean on */
    vcm_grid_init(it, it->grid_lo, cells, g.cell_start, g.items);
    uint32_t *base = calloc((size_t)ranges, sizeof *base);
    assert_non_null(base);
    for (int k = 0; k < ranges; k++) {
        int r = ranges - 1 - k;
        base[r] = vcm_grid_count(it, cell_of, n, r, ranges, g.cell_start);
    }
    assert_int_equal(vcm_grid_bases(base, ranges), n);
    for (int k = 0; k < ranges; k++) {
        int r = k % 2 ? k / 2 : ranges - 1 - k / 2; /* from both ends inward */
        vcm_grid_fill(it, cell_of, n, r, ranges, base[r], g.cell_start, g.items);
    }
    free(base);
    return g;
}

static void test_sort_against_definition(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 2026, 11);
    const size_t sizes[] = {0, 1, 5, 1000, 20000};
    const int partitions[] = {1, 2, 3, 7, 64, 97};
    for (size_t si = 0; si < sizeof sizes / sizeof *sizes; si++) {
        const size_t n = sizes[si];
        SubpathVertex *v = calloc(n ? n : 1, sizeof *v);
        uint32_t *cell_of = calloc(n ? n : 1, sizeof *cell_of);
        assert_non_null(v);
        assert_non_null(cell_of);
        /* Clustered positions, so that buckets hold from zero to many vertices. */
        for (size_t i = 0; i < n; i++) {
            float s = (i % 3 == 0) ? 1.0f : 20.0f;
            float pz = pcg32_float(&rng), py = pcg32_float(&rng), px = pcg32_float(&rng);
            v[i].p = v3(s * px, s * py, s * pz);
            v[i].w_prev = v3(0.0f, 0.0f, 1.0f);
            v[i].beta = color_s((float)i); /* identifies the vertex in the sorted copy */
            v[i].d_vcm = (float)i;
            v[i].bounces = (int32_t)(i % 5) + 1;
        }
        SubpathIteration it;
        memset(&it, 0, sizeof it);
        it.radius = 0.25f;
        it.grid_lo = v3(0.0f, 0.0f, 0.0f);
        it.vertices = v;
        /* More buckets than vertices, and fewer: ranges can then be empty or crowded. */
        const uint32_t bucket_counts[] = {(uint32_t)n + 1, (uint32_t)(n / 4) + 1};
        for (int bc = 0; bc < 2; bc++) {
            const uint32_t cells = bucket_counts[bc];
            SortedGrid first = {0};
            for (size_t pi = 0; pi < sizeof partitions / sizeof *partitions; pi++) {
                uint32_t start0;
                vcm_grid_init(&it, it.grid_lo, cells, &start0, NULL); /* the hash's parameters */
                for (size_t i = 0; i < n; i++) cell_of[i] = vcm_grid_cell(&it, v[i].p);
                SortedGrid g = sort_with_ranges(&it, cell_of, n, cells, partitions[pi]);
                /* The definition: bucket c, in vertex order, and every vertex once. */
                assert_int_equal(g.cell_start[0], 0);
                assert_int_equal(g.cell_start[cells], n);
                size_t k = 0;
                for (uint32_t c = 0; c < cells; c++) {
                    assert_true(g.cell_start[c] <= g.cell_start[c + 1]);
                    for (size_t i = 0; i < n; i++) {
                        if (cell_of[i] != c) continue;
                        assert_true(k < g.cell_start[c + 1]);
                        assert_true(k >= g.cell_start[c]);
                        assert_true(g.items[k].d_vcm == (float)i);
                        assert_true(g.items[k].bounces == v[i].bounces);
                        assert_true(g.items[k].p.x == v[i].p.x && g.items[k].p.y == v[i].p.y &&
                                    g.items[k].p.z == v[i].p.z);
                        k++;
                    }
                    assert_int_equal(k, g.cell_start[c + 1]);
                }
                assert_int_equal(k, n);
                /* Every partition gives the same bytes as the first. */
                if (pi == 0) {
                    first = g;
                } else {
                    assert_memory_equal(first.cell_start, g.cell_start, (cells + 1) * sizeof *g.cell_start);
                    if (n) assert_memory_equal(first.items, g.items, n * sizeof *g.items);
                    free(g.cell_start);
                    free(g.items);
                }
            }
            free(first.cell_start);
            free(first.items);
        }
        free(v);
        free(cell_of);
    }
}

/* The cells of a wall (a plane of 100 x 100 cells, offset from the origin) spread over the
 * buckets as random placement would: 10,000 cells placed at random in 16411 buckets (as
 * many as the vertices, as render.c sizes it) occupy 16411 (1 - e^(-10000 / 16411)),
 * about 7,490 distinct buckets; a hash that folded a coordinate away would use at most a
 * few hundred. */
static void test_buckets_spread(void **state)
{
    (void)state;
    SubpathIteration it;
    memset(&it, 0, sizeof it);
    it.radius = 0.5f; /* cells 1 wide */
    uint32_t start0;
    vcm_grid_init(&it, v3(0.0f, 0.0f, 0.0f), 16411, &start0, NULL);
    unsigned char *used = calloc(16411, 1);
    assert_non_null(used);
    const int axes[3][2] = {{0, 1}, {1, 2}, {0, 2}};
    for (int w = 0; w < 3; w++) {
        memset(used, 0, 16411);
        int distinct = 0;
        for (int i = 0; i < 100; i++)
            for (int j = 0; j < 100; j++) {
                float c[3] = {37.5f, 37.5f, 37.5f};
                c[axes[w][0]] = 500.5f + (float)i;
                c[axes[w][1]] = 20.5f + (float)j;
                uint32_t b = vcm_grid_cell(&it, v3(c[0], c[1], c[2]));
                assert_true(b < 16411);
                distinct += !used[b];
                used[b] = 1;
            }
        print_message("wall %d: 10000 cells in %d buckets\n", w, distinct);
        assert_true(distinct > 6500);
    }
    free(used);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sort_against_definition),
        cmocka_unit_test(test_buckets_spread),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
