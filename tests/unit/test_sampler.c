/* Samplers (sampling/sampler.c): the independent one is exactly the old PCG32 stream;
 * stratified, Sobol' and ZSobol' put exactly one of N samples in each of N strata (1D) and
 * cells (2D); ZSobol's 2x2 pixel blocks together are a net too (its Morton order); every sampler's 1D and 2D marginals, and pairs of different requests, are uniform
 * across pixels (chi-square at 0.01, Sidak-corrected). */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>
#include <cmocka.h>

#include "sampling/sampler.h"
#include "unit/chi2.h"

static const CstSampler TYPES[] = {CST_SAMPLER_INDEPENDENT, CST_SAMPLER_STRATIFIED, CST_SAMPLER_SOBOL,
                                   CST_SAMPLER_ZSOBOL};
#define NUM_TYPES (sizeof TYPES / sizeof TYPES[0])

/* One sample from a setup made for it alone, in *u (renders make one setup for all
 * samples). A zsobol Sampler reads its setup until its last draw (deeper blocks' hashes),
 * so *u must live as long as *s. */
static void sampler_start_for_test(Sampler *s, SamplerSetup *u, CstSampler type, uint64_t seed, uint64_t pixel,
                                   uint32_t index, uint32_t spp)
{
    *u = sampler_setup(type, seed, spp, 128, 128); /* pixels < 16384 */
    sampler_start(s, u, pixel, index);
}

static void test_independent_is_pcg32(void **state)
{
    (void)state;
    for (uint64_t pixel = 0; pixel < 50; pixel++) {
        for (uint32_t i = 0; i < 4; i++) {
            Sampler s;
            SamplerSetup su;
            Pcg32 r;
            sampler_start_for_test(&s, &su, CST_SAMPLER_INDEPENDENT, 42, pixel, i, 4);
            pcg32_seed_sample(&r, 42, pixel, i);
            for (int k = 0; k < 10; k++) {
                /* The order the renderer drew in before the Sampler existed (sampler.c). */
                float y = pcg32_float(&r), x = pcg32_float(&r), u = pcg32_float(&r);
                Vec2 v = sampler_2d(&s);
                assert_true(v.x == x && v.y == y);
                assert_true(sampler_1d(&s) == u);
            }
        }
    }
}

static void test_deterministic(void **state)
{
    (void)state;
    for (size_t t = 0; t < NUM_TYPES; t++) {
        Sampler a, b;
        SamplerSetup ua, ub;
        sampler_start_for_test(&a, &ua, TYPES[t], 7, 1234, 5, 16);
        sampler_start_for_test(&b, &ub, TYPES[t], 7, 1234, 5, 16);
        for (int k = 0; k < 20; k++) {
            assert_true(sampler_1d(&a) == sampler_1d(&b));
            Vec2 u = sampler_2d(&a), v = sampler_2d(&b);
            assert_true(u.x == v.x && u.y == v.y);
        }
    }
}

static void test_permutation(void **state)
{
    (void)state;
    const uint32_t ns[] = {1, 2, 3, 7, 16, 17, 100, 1000};
    for (size_t k = 0; k < sizeof ns / sizeof ns[0]; k++) {
        uint32_t n = ns[k];
        unsigned char seen[1000] = {0};
        for (uint32_t i = 0; i < n; i++) {
            uint32_t j = permute_index(i, n, 0x9e3779b9u * (k + 1));
            assert_true(j < n);
            assert_false(seen[j]);
            seen[j] = 1;
        }
    }
}

/* Sobol' dimension 1 from its recurrence (Joe & Kuo d = 2: s = 1, a = 0, m_1 = 1). */
static void test_sobol_directions(void **state)
{
    (void)state;
    uint32_t v = 0x80000000u;
    for (int b = 0; b < 32; b++) {
        assert_int_equal(sobol_sample(1u << b, 1), v);
        assert_int_equal(sobol_sample(1u << b, 0), 0x80000000u >> b);
        v ^= v >> 1;
    }
}

/* Each of n strata (1D) and each cell of the sampler's 2D grid gets exactly one of the
 * pixel's n samples, in every request. Sobol': n = 2^m and every elementary interval
 * 2^-a x 2^-(m-a) (a (0, m, 2)-net), also for the second block of n indices. */
static void check_strata(CstSampler type, uint32_t n, uint32_t first)
{
    enum { REQUESTS = 24 }; /* zsobol: its first 48 dimensions, three blocks */
    uint32_t nx = 1;
    for (uint32_t d = 1; d <= n / d; d++)
        if (n % d == 0) nx = d;
    for (uint64_t pixel = 0; pixel < 40; pixel++) {
        static float u1[REQUESTS][1024];
        static Vec2 u2[REQUESTS][1024];
        for (uint32_t i = 0; i < n; i++) {
            Sampler s;
            SamplerSetup su;
            sampler_start_for_test(&s, &su, type, 3, pixel, first + i, type == CST_SAMPLER_STRATIFIED ? n : 0);
            for (int r = 0; r < REQUESTS; r++) {
                if (r % 2) u2[r][i] = sampler_2d(&s);
                else u1[r][i] = sampler_1d(&s);
            }
        }
        for (int r = 0; r < REQUESTS; r++) {
            unsigned char hit[1024] = {0};
            if (r % 2 == 0) {
                for (uint32_t i = 0; i < n; i++) {
                    uint32_t c = (uint32_t)((double)u1[r][i] * n);
                    assert_true(c < n);
                    assert_false(hit[c]);
                    hit[c] = 1;
                }
                continue;
            }
            if (type == CST_SAMPLER_STRATIFIED) {
                uint32_t ny = n / nx;
                for (uint32_t i = 0; i < n; i++) {
                    uint32_t cx = (uint32_t)((double)u2[r][i].x * nx), cy = (uint32_t)((double)u2[r][i].y * ny);
                    assert_true(cx < nx && cy < ny);
                    assert_false(hit[cy * nx + cx]);
                    hit[cy * nx + cx] = 1;
                }
                continue;
            }
            int m = 0;
            while ((1u << m) < n) m++;
            for (int a = 0; a <= m; a++) {
                memset(hit, 0, sizeof hit);
                uint32_t bx = 1u << a, by = 1u << (m - a);
                for (uint32_t i = 0; i < n; i++) {
                    uint32_t cx = (uint32_t)(u2[r][i].x * (float)bx), cy = (uint32_t)(u2[r][i].y * (float)by);
                    assert_false(hit[cy * bx + cx]);
                    hit[cy * bx + cx] = 1;
                }
            }
        }
    }
}

static void test_stratified_strata(void **state)
{
    (void)state;
    check_strata(CST_SAMPLER_STRATIFIED, 16, 0);  /* 4 x 4 */
    check_strata(CST_SAMPLER_STRATIFIED, 12, 0);  /* 3 x 4 */
    check_strata(CST_SAMPLER_STRATIFIED, 7, 0);   /* 1 x 7 */
    check_strata(CST_SAMPLER_STRATIFIED, 256, 0); /* 16 x 16 */
}

static void test_sobol_strata(void **state)
{
    (void)state;
    check_strata(CST_SAMPLER_SOBOL, 16, 0);
    check_strata(CST_SAMPLER_SOBOL, 16, 16);
    check_strata(CST_SAMPLER_SOBOL, 256, 0);
    check_strata(CST_SAMPLER_SOBOL, 1024, 1024);
}

/* ZSobol': the first 2^k <= 256 samples of a pixel are a (0, k, 2)-net in each request,
 * also in the second block of 256 (indices 256..). The 24 requests are its first 48 Sobol'
 * dimensions, three blocks (a 2D request after a 1D one skips a dimension). */
static void test_zsobol_strata(void **state)
{
    (void)state;
    check_strata(CST_SAMPLER_ZSOBOL, 4, 0);
    check_strata(CST_SAMPLER_ZSOBOL, 16, 0);
    check_strata(CST_SAMPLER_ZSOBOL, 64, 0);
    check_strata(CST_SAMPLER_ZSOBOL, 256, 0);
    check_strata(CST_SAMPLER_ZSOBOL, 64, 256);
}

/* Each cell of a 2^a x 2^(m-a) grid, for every a, holds one of the n = 2^m points. */
static void assert_net(const Vec2 *u, uint32_t n)
{
    static unsigned char hit[4096];
    int m = 0;
    while ((1u << m) < n) m++;
    for (int a = 0; a <= m; a++) {
        memset(hit, 0, n);
        uint32_t bx = 1u << a, by = 1u << (m - a);
        for (uint32_t i = 0; i < n; i++) {
            uint32_t cx = (uint32_t)(u[i].x * (float)bx), cy = (uint32_t)(u[i].y * (float)by);
            assert_true(cx < bx && cy < by);
            assert_false(hit[cy * bx + cx]);
            hit[cy * bx + cx] = 1;
        }
    }
}

/* ZSobol's point (Ahmed & Wonka 2020): at 256 spp the samples of an aligned 2x2 block of
 * pixels, and of a 4x4 block, are one (0, 10, 2)- or (0, 12, 2)-net in each 2D request
 * (and each 1D request hits each of the 1024 or 4096 strata once): the neighbours' errors
 * compensate. Blocks at several places of a 128 x 96 image; the block count of 256 is
 * what ZSOBOL_LOG2_BLOCK fixes. */
static void test_zsobol_pixel_blocks(void **state)
{
    (void)state;
    static Vec2 u2[3][4096];
    static float u1[3][4096];
    static const int corner[][2] = {{0, 0}, {4, 0}, {0, 8}, {36, 52}, {124, 92}};
    SamplerSetup su = sampler_setup(CST_SAMPLER_ZSOBOL, 21, 256, 128, 96);
    for (int side = 2; side <= 4; side += 2) {
        for (size_t c = 0; c < sizeof corner / sizeof corner[0]; c++) {
            uint32_t n = 0;
            for (int y = corner[c][1]; y < corner[c][1] + side; y++) {
                for (int x = corner[c][0]; x < corner[c][0] + side; x++) {
                    for (uint32_t i = 0; i < 256; i++, n++) {
                        Sampler s;
                        sampler_start(&s, &su, (uint64_t)(y * 128 + x), i);
                        for (int r = 0; r < 3; r++) {
                            u1[r][n] = sampler_1d(&s);
                            u2[r][n] = sampler_2d(&s);
                        }
                    }
                }
            }
            for (int r = 0; r < 3; r++) {
                assert_net(u2[r], n);
                static unsigned char hit[4096];
                memset(hit, 0, n);
                for (uint32_t i = 0; i < n; i++) {
                    uint32_t k = (uint32_t)((double)u1[r][i] * n);
                    assert_true(k < n);
                    assert_false(hit[k]);
                    hit[k] = 1;
                }
            }
        }
    }
}

/* The bit-parallel Sobol' dimension 1 (Pascal's matrix by a superset transform) and bit
 * reversal against the matrix product of sobol_sample. */
static void test_zsobol_bit_tricks(void **state)
{
    (void)state;
    uint32_t i = 0;
    for (uint32_t k = 0; k < 100000; k++, i = i * 2891336453u + 0x9e3779b9u) {
        uint32_t j = k < 70000 ? k : i;
        assert_int_equal(sampler_rev32(sobol1_reversed(j)), sobol_sample(j, 1));
        assert_int_equal(sampler_rev32(j), sobol_sample(j, 0));
    }
}

/* ZSobol's index: (block of 256 | Morton code of (x, y) | index mod 256). */
static void test_zsobol_morton_index(void **state)
{
    (void)state;
    SamplerSetup u = sampler_setup(CST_SAMPLER_ZSOBOL, 1, 0, 100, 40); /* 128 x 128: 14 bits */
    assert_int_equal(u.morton_bits, 14);
    assert_true(zsobol_morton_index(&u, 0, 5) == 5u);
    assert_true(zsobol_morton_index(&u, 1, 0) == 1u << 8);             /* x = 1: bit 0 */
    assert_true(zsobol_morton_index(&u, 100, 0) == 2u << 8);           /* y = 1: bit 1 */
    assert_true(zsobol_morton_index(&u, 3 * 100 + 2, 7) == ((0xeu << 8) | 7u)); /* x 2, y 3 */
    assert_true(zsobol_morton_index(&u, 0, 256 + 3) == ((1ULL << (8 + 14)) | 3u));
    SamplerSetup big = sampler_setup(CST_SAMPLER_ZSOBOL, 1, 0, 65536, 65536);
    assert_int_equal(big.morton_bits, 32);
    assert_true(zsobol_morton_index(&big, 65536ull * 65536 - 1, 2147483647u) ==
                (((uint64_t)(2147483647u >> 8) << 40) | (0xffffffffULL << 8) | 255u));
}

/* zsobol computes its points a block at a time (SIMD lanes when the build has AVX2): the
 * same floats as zsobol_point, one point at a time, on the bit-reversed Morton index, for
 * pixels and indices of small and 65536-wide images, in every block of the first 96
 * dimensions (past ZSOBOL_TABLE points the hashes are computed when drawn). */
static void test_zsobol_points_match_scalar(void **state)
{
    (void)state;
    const int size[2][2] = {{100, 40}, {65536, 65536}};
    for (int k = 0; k < 2; k++) {
        SamplerSetup u = sampler_setup(CST_SAMPLER_ZSOBOL, 77 + (uint64_t)k, 0, size[k][0], size[k][1]);
        uint64_t h = 12345;
        for (int n = 0; n < 20000; n++) {
            h = mix64(h + 1);
            uint64_t npix = (uint64_t)size[k][0] * (uint64_t)size[k][1];
            uint64_t pixel = h % npix;
            uint32_t index = n < 10000 ? (uint32_t)(h >> 40) & 1023u : (uint32_t)(h >> 33);
            Sampler s;
            sampler_start(&s, &u, pixel, index);
            uint64_t m = zsobol_morton_index(&u, pixel, index);
            uint64_t rev = ((uint64_t)sampler_rev32((uint32_t)m) << 32) | sampler_rev32((uint32_t)(m >> 32));
            assert_true(s.zrev == rev);
            for (uint32_t d = 0; d < 48; d++) {
                float p[2];
                ZSobolDim zd = zsobol_dim(&u, d);
                zsobol_point(rev, &zd, p);
                /* Alternately a 2D request and two 1D ones: every dimension is drawn. */
                if (d % 2 == 0) {
                    Vec2 v = sampler_2d(&s);
                    assert_true(v.x == p[0] && v.y == p[1]);
                } else {
                    float x = sampler_1d(&s), y = sampler_1d(&s);
                    assert_true(x == p[0] && y == p[1]);
                }
            }
        }
    }
}

/* Chi-square of one histogram against the uniform expectation; returns the p-value. */
static double uniform_p(const double *obs, int cells, double total)
{
    double expd[256];
    for (int c = 0; c < cells; c++) expd[c] = total / cells;
    int dof;
    double stat, outside;
    return chi2_pvalue(obs, expd, cells, &dof, &stat, &outside);
}

/* Across 16384 pixels, for each sample index of a 16-spp pixel and each request: the
 * first request's 1D values (64 bins), the second's 2D values (16 x 16 bins), and the
 * pair (first request, third request) (16 x 16 bins; independence of requests). */
static void test_uniform_across_pixels(void **state)
{
    (void)state;
    enum { PIXELS = 16384, SPP = 16, TESTS = 3 * 4 * (int)NUM_TYPES };
    const uint32_t indices[4] = {0, 1, 7, 15};
    const double alpha = 1.0 - pow(1.0 - 0.01, 1.0 / TESTS); /* Sidak */
    for (size_t t = 0; t < NUM_TYPES; t++) {
        for (int k = 0; k < 4; k++) {
            static double h1[64], h2[256], hp[256];
            memset(h1, 0, sizeof h1);
            memset(h2, 0, sizeof h2);
            memset(hp, 0, sizeof hp);
            for (uint64_t p = 0; p < PIXELS; p++) {
                Sampler s;
                SamplerSetup su;
                sampler_start_for_test(&s, &su, TYPES[t], 11, p, indices[k], SPP);
                /* Sample index k odd: the requests after 70 dimensions (zsobol: past the
                 * points whose hashes the setup keeps). */
                for (int skip = 0; skip < 35 * (k & 1); skip++) (void)sampler_2d(&s);
                float a = sampler_1d(&s);
                Vec2 b = sampler_2d(&s);
                float c = sampler_1d(&s);
                h1[(int)(a * 64.0f)] += 1.0;
                h2[(int)(b.y * 16.0f) * 16 + (int)(b.x * 16.0f)] += 1.0;
                hp[(int)(c * 16.0f) * 16 + (int)(a * 16.0f)] += 1.0;
            }
            double p1 = uniform_p(h1, 64, PIXELS), p2 = uniform_p(h2, 256, PIXELS), pp = uniform_p(hp, 256, PIXELS);
            if (p1 < alpha || p2 < alpha || pp < alpha)
                fail_msg("%s, sample %u: p-values 1D %.3g, 2D %.3g, pair %.3g (alpha %.3g)",
                         cst_sampler_name(TYPES[t]), indices[k], p1, p2, pp, alpha);
        }
    }
}

/* The stratified grid is worked out once per setup (issue 25: it was searched for every
 * sample): the largest divisor of spp not above its square root. */
static void test_setup_strata(void **state)
{
    (void)state;
    static const uint32_t spp[][2] = {{0, 1}, {1, 1}, {16, 4}, {32, 4}, {36, 6}, {97, 1}, {1u << 30, 1u << 15},
                                      {2147483647u, 1}, {4294967295u, 65535}};
    for (size_t k = 0; k < sizeof spp / sizeof spp[0]; k++) {
        SamplerSetup u = sampler_setup(CST_SAMPLER_STRATIFIED, 5, spp[k][0], 64, 64);
        assert_int_equal(u.nx, spp[k][1]);
        assert_int_equal(u.spp, spp[k][0]);
        assert_int_equal(sampler_setup(CST_SAMPLER_SOBOL, 5, spp[k][0], 64, 64).nx, 1);
    }
    assert_int_equal(sampler_setup(CST_SAMPLER_DEFAULT, 5, 16, 64, 64).type, CST_SAMPLER_ZSOBOL);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_independent_is_pcg32),
        cmocka_unit_test(test_deterministic),
        cmocka_unit_test(test_permutation),
        cmocka_unit_test(test_sobol_directions),
        cmocka_unit_test(test_stratified_strata),
        cmocka_unit_test(test_sobol_strata),
        cmocka_unit_test(test_zsobol_strata),
        cmocka_unit_test(test_zsobol_pixel_blocks),
        cmocka_unit_test(test_zsobol_bit_tricks),
        cmocka_unit_test(test_zsobol_morton_index),
        cmocka_unit_test(test_zsobol_points_match_scalar),
        cmocka_unit_test(test_uniform_across_pixels),
        cmocka_unit_test(test_setup_strata),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
