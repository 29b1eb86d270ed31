/* The photon map (integrators/photon_map.c) against brute force: radius and k-nearest
 * queries over uniform, clustered, coincident, coplanar and lattice photon sets of 0 to
 * 100,000 photons; the built tree's invariants; queries from two threads at once. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <pthread.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "integrators/photon_map.h"

_Static_assert(sizeof(Photon) <= 60, "Photon must stay within 60 bytes");
_Static_assert(sizeof(PhotonNode) == 16, "four nodes per cache line");

/* ------------------------------------------------------------------ photon sets */

typedef enum SetKind { SET_UNIFORM, SET_CLUSTERED, SET_IDENTICAL, SET_PLANE, SET_LATTICE } SetKind;
static const char *const SET_NAMES[] = {"uniform", "clustered", "identical", "plane", "lattice"};

typedef struct PhotonSet {
    Photon *ph;
    size_t n;
    SetKind kind;
    float scale; /* about the diameter of the set; radii are fractions of it */
} PhotonSet;

static float rndf(Pcg32 *rng, float lo, float hi) { return lo + (hi - lo) * pcg32_float(rng); }
static Vec3 rnd_v3(Pcg32 *rng, float lo, float hi)
{
    float x = rndf(rng, lo, hi), y = rndf(rng, lo, hi), z = rndf(rng, lo, hi);
    return v3(x, y, z);
}
static Vec3 rnd_dir(Pcg32 *rng)
{
    for (;;) {
        Vec3 d = rnd_v3(rng, -1.0f, 1.0f);
        float l = v3_length(d);
        if (l > 0.05f && l <= 1.0f) return v3_scale(d, 1.0f / l);
    }
}

/* Photons whose power.r is their index (exact below 2^24), so a copy can be traced back. */
static PhotonSet make_set(SetKind kind, size_t n, uint64_t seed)
{
    PhotonSet s = {NULL, n, kind, 2.0f};
    s.ph = malloc((n > 0 ? n : 1) * sizeof *s.ph);
    assert_non_null(s.ph);
    Pcg32 rng;
    pcg32_seed(&rng, seed, (uint64_t)kind);
    Vec3 centres[8];
    float sigma[8];
    for (int c = 0; c < 8; c++) {
        centres[c] = rnd_v3(&rng, -10.0f, 10.0f);
        sigma[c] = expf(rndf(&rng, logf(1e-4f), logf(0.1f)));
    }
    if (kind == SET_CLUSTERED) s.scale = 20.0f;
    if (kind == SET_LATTICE) s.scale = 4.0f;
    for (size_t i = 0; i < n; i++) {
        Vec3 p;
        switch (kind) {
        case SET_UNIFORM: p = v3_add(v3(3.0f, -2.0f, 7.0f), rnd_v3(&rng, -1.0f, 1.0f)); break;
        case SET_CLUSTERED: {
            if (pcg32_next(&rng) % 100u == 0u) { p = rnd_v3(&rng, -10.0f, 10.0f); break; }
            int c = (int)(pcg32_next(&rng) % 8u);
            /* Three draws in sequence (the order GCC evaluated the nested arguments in). */
            Vec3 g3 = rnd_v3(&rng, 0.0f, 1.0f), g2 = rnd_v3(&rng, 0.0f, 1.0f), g1 = rnd_v3(&rng, 0.0f, 1.0f);
            Vec3 g = v3_sub(v3_add(g1, v3_add(g2, g3)), v3s(1.5f));
            p = v3_madd(centres[c], g, sigma[c]);
            break;
        }
        case SET_IDENTICAL: p = v3(0.25f, -1.5f, 3.0f); break;
        case SET_PLANE: {
            float y = rndf(&rng, -1.0f, 1.0f), x = rndf(&rng, -1.0f, 1.0f); /* y first: GCC's order */
            p = v3(x, y, 2.0f);
            break;
        }
        default: { /* integer points of [0, 4]^3: duplicates and exactly equal distances */
            uint32_t pz = pcg32_next(&rng) % 5u, py = pcg32_next(&rng) % 5u, px = pcg32_next(&rng) % 5u;
            p = v3((float)px, (float)py, (float)pz);
            break;
        }
        }
        Vec3 wi = rnd_dir(&rng);
        s.ph[i].pos = p;
        s.ph[i].wi = wi;
        float pb = pcg32_float(&rng), pg = pcg32_float(&rng);
        s.ph[i].power = color_rgb((float)i, pg, pb);
        s.ph[i].n = v3_face_forward(rnd_dir(&rng), wi);
    }
    return s;
}

static void build_map(PhotonMap *map, const PhotonSet *s)
{
    CstError err = {0};
    if (photon_map_build(map, s->ph, s->n, &err) != CST_OK)
        fail_msg("%s n=%zu: build failed: %s", SET_NAMES[s->kind], s->n, err.msg);
    assert_int_equal(photon_map_count(map), s->n);
}

/* Query points: random in and around the set's bounds, exactly at photons, far outside,
 * and (lattice) on integer points, where many photons are at the same distance. */
static Vec3 query_point(const PhotonSet *s, Pcg32 *rng, int q)
{
    Vec3 lo = v3s(INFINITY), hi = v3s(-INFINITY);
    for (size_t i = 0; i < s->n && i < 64; i++) { lo = v3_min(lo, s->ph[i].pos); hi = v3_max(hi, s->ph[i].pos); }
    if (s->n == 0) { lo = v3s(-1.0f); hi = v3s(1.0f); }
    switch (q % 4) {
    case 0: {
        Vec3 c = v3_scale(v3_add(lo, hi), 0.5f), e = v3_add(v3_scale(v3_sub(hi, lo), 0.6f), v3s(0.05f));
        return v3_add(c, v3_mul(e, rnd_v3(rng, -1.0f, 1.0f)));
    }
    case 1: if (s->n > 0) return s->ph[pcg32_next(rng) % (uint32_t)s->n].pos; return v3s(0.0f);
    case 2: return v3_scale(rnd_dir(rng), 3.0f * s->scale + 30.0f); /* far outside */
    default:
        if (s->kind == SET_LATTICE)
            {
            uint32_t z = pcg32_next(rng) % 7u, y = pcg32_next(rng) % 7u, x = pcg32_next(rng) % 7u;
            return v3((float)x - 1.0f, (float)y - 1.0f, (float)z - 1.0f);
        }
        if (s->n > 0) { /* near a photon: the offset drawn before the photon (GCC's order) */
            Vec3 off = rnd_dir(rng);
            return v3_madd(s->ph[pcg32_next(rng) % (uint32_t)s->n].pos, off, 1e-3f * s->scale);
        }
        return v3s(0.5f);
    }
}

/* ------------------------------------------------------------------ tree invariants */

/* The range [lo, hi) of the implicit tree (see PhotonMap): leaves carry no split; an
 * inner range's median splits on the largest extent of the range's bounds (lowest axis on
 * ties), with everything before it <= and everything after it >= on that axis. */
static void check_range(const PhotonMap *map, size_t lo, size_t hi, int depth, int *max_depth)
{
    if (depth > *max_depth) *max_depth = depth;
    const PhotonNode *nd = map->nodes;
    if (hi - lo <= PHOTON_MAP_LEAF_SIZE) {
        for (size_t i = lo; i < hi; i++) assert_int_equal(nd[i].meta & 3u, PHOTON_MAP_NO_SPLIT);
        return;
    }
    float blo[3] = {INFINITY, INFINITY, INFINITY}, bhi[3] = {-INFINITY, -INFINITY, -INFINITY};
    for (size_t i = lo; i < hi; i++)
        for (int a = 0; a < 3; a++) { blo[a] = minf(blo[a], nd[i].p[a]); bhi[a] = maxf(bhi[a], nd[i].p[a]); }
    size_t m = lo + (hi - lo) / 2;
    uint32_t axis = nd[m].meta & 3u;
    int want = 0;
    for (int a = 1; a < 3; a++)
        if (bhi[a] - blo[a] > bhi[want] - blo[want]) want = a;
    if ((int)axis != want) fail_msg("range [%zu, %zu): split axis %u, largest extent is axis %d", lo, hi, axis, want);
    float split = nd[m].p[axis];
    for (size_t i = lo; i < m; i++)
        if (!(nd[i].p[axis] <= split)) fail_msg("range [%zu, %zu): node %zu at %g left of split %g", lo, hi, i, (double)nd[i].p[axis], (double)split);
    for (size_t i = m + 1; i < hi; i++)
        if (!(nd[i].p[axis] >= split)) fail_msg("range [%zu, %zu): node %zu at %g right of split %g", lo, hi, i, (double)nd[i].p[axis], (double)split);
    check_range(map, lo, m, depth + 1, max_depth);
    check_range(map, m + 1, hi, depth + 1, max_depth);
}

/* The split rule on every range, nodes and photons consistent, every input photon present
 * exactly once and copied verbatim, and the depth that of halving down to leaf size. */
static void check_tree(const PhotonMap *map, const PhotonSet *s)
{
    size_t n = map->count;
    if (n == 0) { assert_null(map->nodes); assert_null(map->photons); return; }
    bool *seen = calloc(n, 1);
    assert_non_null(seen);
    for (size_t i = 0; i < n; i++) {
        const PhotonNode *nd = &map->nodes[i];
        size_t idx = nd->meta >> 2;
        assert_true(idx < n);
        assert_false(seen[idx]);
        seen[idx] = true;
        assert_int_equal(photon_map_index(map, &map->photons[i]), idx);
        assert_memory_equal(&map->photons[i], &s->ph[idx], sizeof(Photon));
        assert_true(nd->p[0] == s->ph[idx].pos.x && nd->p[1] == s->ph[idx].pos.y && nd->p[2] == s->ph[idx].pos.z);
    }
    free(seen);
    int depth = 0, want = 0;
    check_range(map, 0, n, 0, &depth);
    for (size_t len = n; len > PHOTON_MAP_LEAF_SIZE; len /= 2) want++;
    assert_int_equal(depth, want);
}

/* ------------------------------------------------------------------ radius vs brute force */

/* The brute-force set is marked in `expected` with this query's stamp; the visitor checks
 * each photon it is given is marked, not given twice (`seen`), and comes with the right
 * squared distance. Equal counts then make the two sets equal, which is what comparing
 * sorted index lists would show, in O(n) per query. */
typedef struct RadiusCheck {
    const PhotonMap *map;
    const PhotonSet *set;
    Vec3 x;
    uint32_t stamp;
    uint32_t *expected, *seen;
    size_t visited;
    int errors;
    char first_error[160];
} RadiusCheck;

static void radius_visit(void *ctx, const Photon *ph, float dist2)
{
    RadiusCheck *c = ctx;
    size_t idx = photon_map_index(c->map, ph);
    c->visited++;
    const char *what = NULL;
    if (idx >= c->set->n) what = "index out of range";
    else if (c->expected[idx] != c->stamp) what = "not in the brute-force set";
    else if (c->seen[idx] == c->stamp) what = "visited twice";
    else if (dist2 != photon_dist2(c->x, c->set->ph[idx].pos)) what = "wrong dist2";
    else if (ph->power.c[0] != (float)idx) what = "photon record not the input's";
    if (what) {
        if (c->errors++ == 0) snprintf(c->first_error, sizeof c->first_error, "photon %zu: %s", idx, what);
        return;
    }
    c->seen[idx] = c->stamp;
}

typedef struct QueryStats {
    long queries, found, empty, all;
} QueryStats;

static void check_radius(const PhotonMap *map, const PhotonSet *s, Vec3 x, float radius, RadiusCheck *c,
                         QueryStats *st)
{
    c->stamp++;
    c->x = x;
    c->visited = 0;
    size_t want = 0;
    float r2 = radius * radius;
    for (size_t j = 0; j < s->n; j++)
        if (radius >= 0.0f && photon_dist2(x, s->ph[j].pos) <= r2) { c->expected[j] = c->stamp; want++; }
    size_t got = photon_map_radius(map, x, radius, radius_visit, c);
    if (c->errors || got != want || c->visited != want)
        fail_msg("%s n=%zu x=(%g %g %g) r=%g: returned %zu, visited %zu, brute force %zu; %s", SET_NAMES[s->kind], s->n,
                 (double)x.x, (double)x.y, (double)x.z, (double)radius, got, c->visited, want,
                 c->errors ? c->first_error : "");
    /* Counting only, no visitor. */
    assert_int_equal(photon_map_radius(map, x, radius, NULL, NULL), want);
    st->queries++;
    st->found += (long)want;
    st->empty += want == 0;
    st->all += s->n > 0 && want == s->n;
}

static void radius_suite(SetKind kind, size_t n, int queries, uint64_t seed)
{
    PhotonSet s = make_set(kind, n, seed);
    PhotonMap map;
    build_map(&map, &s);
    check_tree(&map, &s);
    RadiusCheck c = {&map, &s, v3s(0.0f), 0, calloc(n + 1, sizeof(uint32_t)), calloc(n + 1, sizeof(uint32_t)), 0, 0, ""};
    assert_true(c.expected && c.seen);
    /* Fractions of the set's size; the one from n gives about 50 photons in the uniform
     * set; 1e30 squares to infinity. */
    float r50 = 2.0f * cbrtf(50.0f / (float)(n > 0 ? n : 1) * 3.0f / (4.0f * CST_PI));
    const float radii[] = {0.0f, 1e-6f * s.scale, 1e-3f * s.scale, 0.02f * s.scale, r50, 0.1f * s.scale,
                           0.3f * s.scale, s.scale, 1.0f, 2.0f, 10.0f * s.scale, 1e30f, INFINITY, -1.0f, NAN};
    const int nr = (int)(sizeof radii / sizeof radii[0]);
    Pcg32 rng;
    pcg32_seed(&rng, seed + 99u, 3u);
    QueryStats st = {0};
    for (int q = 0; q < queries; q++) {
        Vec3 x = query_point(&s, &rng, q);
        for (int ri = 0; ri < nr; ri++) {
            /* Radii taking in most of a large set cost O(n) per query to check: fewer. */
            if (n >= 10000 && q % 8 != 0 && radii[ri] >= 0.3f * s.scale) continue;
            check_radius(&map, &s, x, radii[ri], &c, &st);
        }
        /* The exact distance to a photon: its own square may round either way, the rule
         * (dist2 <= r * r) decides, and the brute force applies the same rule. */
        if (n > 0) {
            float d = sqrtf(photon_dist2(x, s.ph[pcg32_next(&rng) % (uint32_t)n].pos));
            check_radius(&map, &s, x, d, &c, &st);
            check_radius(&map, &s, x, nextafterf(d, INFINITY), &c, &st);
            check_radius(&map, &s, x, nextafterf(d, 0.0f), &c, &st);
        }
    }
    print_message("  radius %-9s n=%-6zu %5ld queries, %9.1f photons on average, %ld empty, %ld all\n",
                  SET_NAMES[kind], n, st.queries, (double)st.found / (double)st.queries, st.empty, st.all);
    /* Both extremes occur, and (where the set allows) results in between. */
    if (n > 1) assert_true(st.empty > 0 && st.all > 0);
    if (n > 1 && kind != SET_IDENTICAL) assert_true(st.empty + st.all < st.queries);
    free(c.expected);
    free(c.seen);
    photon_map_free(&map);
    free(s.ph);
}

static void test_photon_map_radius_uniform(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 3, 17, 100, 1000, 100000};
    for (int i = 0; i < 7; i++) radius_suite(SET_UNIFORM, sizes[i], sizes[i] >= 100000 ? 48 : 400, 10u + (uint64_t)i);
}

static void test_photon_map_radius_degenerate_sets(void **state)
{
    (void)state;
    const SetKind kinds[] = {SET_CLUSTERED, SET_IDENTICAL, SET_PLANE, SET_LATTICE};
    const size_t sizes[] = {2, 40, 1000, 100000};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 4; i++) radius_suite(kinds[k], sizes[i], sizes[i] >= 100000 ? 32 : 300, 20u + (uint64_t)i);
}

/* ------------------------------------------------------------------ knn vs brute force */

/* The first k of all photons within max_radius in (dist2, input index) order: a sorted
 * buffer that a candidate enters only when it precedes the current last. */
static int brute_knn(const PhotonSet *s, Vec3 x, int k, float max_radius, size_t *idx, float *d2)
{
    if (k <= 0 || !(max_radius >= 0.0f)) return 0;
    float r2 = max_radius * max_radius;
    int m = 0;
    for (size_t j = 0; j < s->n; j++) {
        float d = photon_dist2(x, s->ph[j].pos);
        if (!(d <= r2)) continue;
        if (m == k && !(d < d2[m - 1])) continue; /* j is above every index held: ties lose */
        int p = m < k ? m++ : m - 1;
        for (; p > 0 && d < d2[p - 1]; p--) { d2[p] = d2[p - 1]; idx[p] = idx[p - 1]; }
        d2[p] = d;
        idx[p] = j;
    }
    return m;
}

static void check_knn(const PhotonMap *map, const PhotonSet *s, Vec3 x, int k, float max_radius, QueryStats *st)
{
    static const Photon *out[PHOTON_MAP_MAX_K];
    static float d2[PHOTON_MAP_MAX_K], bd2[PHOTON_MAP_MAX_K];
    static size_t bidx[PHOTON_MAP_MAX_K];
    int want = brute_knn(s, x, k, max_radius, bidx, bd2);
    int got = photon_map_knn(map, x, k, max_radius, out, d2);
    if (got != want)
        fail_msg("%s n=%zu x=(%g %g %g) k=%d r=%g: %d found, brute force %d", SET_NAMES[s->kind], s->n, (double)x.x,
                 (double)x.y, (double)x.z, k, (double)max_radius, got, want);
    float r2 = max_radius * max_radius;
    for (int i = 0; i < got; i++) {
        size_t idx = photon_map_index(map, out[i]);
        if (idx != bidx[i] || d2[i] != bd2[i])
            fail_msg("%s n=%zu x=(%g %g %g) k=%d r=%g: #%d is photon %zu at %.9g, brute force %zu at %.9g",
                     SET_NAMES[s->kind], s->n, (double)x.x, (double)x.y, (double)x.z, k, (double)max_radius, i, idx,
                     (double)d2[i], bidx[i], (double)bd2[i]);
        assert_true(d2[i] == photon_dist2(x, out[i]->pos));
        assert_true(d2[i] <= r2);
        if (i > 0) assert_true(d2[i - 1] <= d2[i]);
    }
    /* Without distances, the same photons. */
    static const Photon *out2[PHOTON_MAP_MAX_K];
    assert_int_equal(photon_map_knn(map, x, k, max_radius, out2, NULL), got);
    assert_memory_equal(out, out2, (size_t)(got > 0 ? got : 1) * sizeof *out);
    st->queries++;
    st->found += got;
    st->empty += got == 0;
    st->all += got > 0 && (size_t)got == s->n;
}

static void knn_suite(SetKind kind, size_t n, int queries, uint64_t seed)
{
    PhotonSet s = make_set(kind, n, seed);
    PhotonMap map;
    build_map(&map, &s);
    const int ks[] = {1, 2, 7, 50, 200, PHOTON_MAP_MAX_K, (int)n + 3};
    const float radii[] = {INFINITY, 0.3f * s.scale, 0.02f * s.scale, 1.0f, 0.0f};
    Pcg32 rng;
    pcg32_seed(&rng, seed + 7u, 11u);
    QueryStats st = {0};
    for (int q = 0; q < queries; q++) {
        Vec3 x = query_point(&s, &rng, q);
        for (int ki = 0; ki < 7; ki++) {
            if (ks[ki] > PHOTON_MAP_MAX_K) continue;
            for (int ri = 0; ri < 5; ri++) check_knn(&map, &s, x, ks[ki], radii[ri], &st);
        }
        /* The boundary again: max_radius exactly at some photon's distance. */
        if (n > 0) {
            float d = sqrtf(photon_dist2(x, s.ph[pcg32_next(&rng) % (uint32_t)n].pos));
            check_knn(&map, &s, x, 50, d, &st);
            check_knn(&map, &s, x, 50, nextafterf(d, 0.0f), &st);
        }
    }
    print_message("  knn    %-9s n=%-6zu %5ld queries, %9.1f photons on average, %ld empty, %ld all\n",
                  SET_NAMES[kind], n, st.queries, (double)st.found / (double)st.queries, st.empty, st.all);
    photon_map_free(&map);
    free(s.ph);
}

static void test_photon_map_knn_uniform(void **state)
{
    (void)state;
    const size_t sizes[] = {1, 2, 3, 17, 100, 1000, 100000};
    for (int i = 0; i < 7; i++) knn_suite(SET_UNIFORM, sizes[i], sizes[i] >= 100000 ? 12 : 100, 30u + (uint64_t)i);
}

static void test_photon_map_knn_degenerate_sets(void **state)
{
    (void)state;
    const SetKind kinds[] = {SET_CLUSTERED, SET_IDENTICAL, SET_PLANE, SET_LATTICE};
    const size_t sizes[] = {2, 40, 1000, 100000};
    for (int k = 0; k < 4; k++)
        for (int i = 0; i < 4; i++) knn_suite(kinds[k], sizes[i], sizes[i] >= 100000 ? 8 : 60, 40u + (uint64_t)i);
}

/* k outside [1, PHOTON_MAP_MAX_K], negative and NaN radii. */
static void test_photon_map_knn_arguments(void **state)
{
    (void)state;
    PhotonSet s = make_set(SET_UNIFORM, 500, 5u);
    PhotonMap map;
    build_map(&map, &s);
    const Photon *out[PHOTON_MAP_MAX_K];
    float d2[PHOTON_MAP_MAX_K];
    Vec3 x = v3(3.0f, -2.0f, 7.0f);
    assert_int_equal(photon_map_knn(&map, x, 0, INFINITY, out, d2), 0);
    assert_int_equal(photon_map_knn(&map, x, -5, INFINITY, out, d2), 0);
    assert_int_equal(photon_map_knn(&map, x, PHOTON_MAP_MAX_K + 1, INFINITY, out, d2), -1);
    assert_int_equal(photon_map_knn(&map, x, 10, -1.0f, out, d2), 0);
    assert_int_equal(photon_map_knn(&map, x, 10, NAN, out, d2), 0);
    assert_int_equal(photon_map_knn(&map, x, PHOTON_MAP_MAX_K, INFINITY, out, d2), 500);
    assert_int_equal(photon_map_knn(&map, x, 10, 1e30f, out, d2), 10);
    photon_map_free(&map);
    free(s.ph);
}

/* ------------------------------------------------------------------ build */

/* n = 0 is a valid empty map; so is a zeroed one; bad arguments fail with a status. */
static void test_photon_map_empty_and_errors(void **state)
{
    (void)state;
    PhotonMap map;
    CstError err = {0};
    assert_int_equal(photon_map_build(&map, NULL, 0, &err), CST_OK);
    assert_int_equal(photon_map_count(&map), 0);
    const Photon *out[4];
    float d2[4];
    assert_int_equal(photon_map_radius(&map, v3s(0.0f), INFINITY, radius_visit, NULL), 0);
    assert_int_equal(photon_map_knn(&map, v3s(0.0f), 4, INFINITY, out, d2), 0);
    photon_map_free(&map);
    photon_map_free(NULL);
    PhotonMap zero = {0};
    assert_int_equal(photon_map_count(&zero), 0);
    assert_int_equal(photon_map_radius(&zero, v3s(0.0f), 1.0f, NULL, NULL), 0);
    assert_int_equal(photon_map_knn(&zero, v3s(0.0f), 4, 1.0f, out, d2), 0);
    photon_map_free(&zero);

    assert_int_equal(photon_map_build(&map, NULL, 3, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(err.status, CST_ERR_INVALID_ARG);
    assert_null(map.nodes);
    assert_int_equal(map.count, 0);
    Photon one = {v3s(1.0f), v3(0.0f, 0.0f, 1.0f), color_s(1.0f), v3(0.0f, 0.0f, 1.0f), 0.0f, -1};
    /* Rejected before anything is read or allocated. */
    assert_int_equal(photon_map_build(&map, &one, PHOTON_MAP_MAX_COUNT + 1, &err), CST_ERR_UNSUPPORTED);
    assert_int_equal(err.status, CST_ERR_UNSUPPORTED);
    assert_int_equal(photon_map_build(&map, NULL, 3, NULL), CST_ERR_INVALID_ARG);
}

/* The map owns a copy: changing the input afterwards changes nothing; the build is a
 * function of the input alone (two builds are byte-identical). Tree invariants on every
 * set at small sizes, where shape edge cases live. */
static void test_photon_map_build_copies_and_invariants(void **state)
{
    (void)state;
    for (int kind = SET_UNIFORM; kind <= SET_LATTICE; kind++)
        for (size_t n = 1; n <= 80; n++) {
            PhotonSet s = make_set((SetKind)kind, n, 1000u + n);
            PhotonMap a, b;
            build_map(&a, &s);
            build_map(&b, &s);
            check_tree(&a, &s);
            assert_memory_equal(a.nodes, b.nodes, n * sizeof *a.nodes);
            assert_memory_equal(a.photons, b.photons, n * sizeof *a.photons);
            photon_map_free(&a);
            photon_map_free(&b);
            free(s.ph);
        }
    PhotonSet s = make_set(SET_UNIFORM, 2000, 77u);
    PhotonSet keep = s;
    keep.ph = malloc(s.n * sizeof *s.ph);
    assert_non_null(keep.ph);
    memcpy(keep.ph, s.ph, s.n * sizeof *s.ph);
    PhotonMap map;
    build_map(&map, &s);
    memset(s.ph, 0xff, s.n * sizeof *s.ph); /* NaN everywhere */
    free(s.ph);
    check_tree(&map, &keep);
    Pcg32 rng;
    pcg32_seed(&rng, 1u, 1u);
    RadiusCheck c = {&map, &keep, v3s(0.0f), 0, calloc(keep.n, sizeof(uint32_t)), calloc(keep.n, sizeof(uint32_t)), 0, 0, ""};
    assert_true(c.expected && c.seen);
    QueryStats st = {0};
    for (int q = 0; q < 200; q++) check_radius(&map, &keep, query_point(&keep, &rng, q), 0.3f, &c, &st);
    for (int q = 0; q < 200; q++) check_knn(&map, &keep, query_point(&keep, &rng, q), 20, INFINITY, &st);
    free(c.expected);
    free(c.seen);
    photon_map_free(&map);
    assert_null(map.nodes);
    free(keep.ph);
}

/* ------------------------------------------------------------------ threads */

enum { MT_QUERIES = 3000, MT_K = 40 };

typedef struct MtJob {
    const PhotonMap *map;
    const Vec3 *points;
    pthread_barrier_t *start;
    size_t counts[MT_QUERIES];
    uint64_t sums[MT_QUERIES];       /* order-independent digest of each radius result */
    uint32_t knn[MT_QUERIES][MT_K];  /* input indices of each knn result */
    int knn_n[MT_QUERIES];
} MtJob;

static void digest_visit(void *ctx, const Photon *ph, float dist2)
{
    (void)dist2;
    uint64_t *sum = ctx;
    *sum += mix64((uint64_t)ph->power.c[0] + 1u); /* power.r is the input index */
}

static void mt_run(MtJob *j)
{
    for (int q = 0; q < MT_QUERIES; q++) {
        j->sums[q] = 0;
        j->counts[q] = photon_map_radius(j->map, j->points[q], 0.15f, digest_visit, &j->sums[q]);
        const Photon *out[MT_K];
        j->knn_n[q] = photon_map_knn(j->map, j->points[q], MT_K, (q & 1) ? 0.2f : INFINITY, out, NULL);
        for (int i = 0; i < j->knn_n[q]; i++) j->knn[q][i] = (uint32_t)photon_map_index(j->map, out[i]);
    }
}

static void *mt_thread(void *arg)
{
    MtJob *j = arg;
    pthread_barrier_wait(j->start);
    mt_run(j);
    return NULL;
}

static bool mt_same(const MtJob *a, const MtJob *b)
{
    for (int q = 0; q < MT_QUERIES; q++) {
        if (a->counts[q] != b->counts[q] || a->sums[q] != b->sums[q] || a->knn_n[q] != b->knn_n[q]) return false;
        if (memcmp(a->knn[q], b->knn[q], (size_t)a->knn_n[q] * sizeof a->knn[q][0]) != 0) return false;
    }
    return true;
}

/* Two threads querying one map at once get what one thread alone gets: the queries keep
 * no state outside their own stack frame. */
static void test_photon_map_two_threads(void **state)
{
    (void)state;
    PhotonSet s = make_set(SET_UNIFORM, 50000, 321u);
    PhotonMap map;
    build_map(&map, &s);
    Vec3 *points = malloc(MT_QUERIES * sizeof *points);
    MtJob *jobs = calloc(3, sizeof *jobs);
    assert_true(points && jobs);
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 6u);
    for (int q = 0; q < MT_QUERIES; q++) points[q] = query_point(&s, &rng, q);
    pthread_barrier_t start;
    assert_int_equal(pthread_barrier_init(&start, NULL, 2), 0);
    for (int t = 0; t < 3; t++) { jobs[t].map = &map; jobs[t].points = points; jobs[t].start = &start; }
    mt_run(&jobs[0]);
    pthread_t th[2];
    for (int t = 0; t < 2; t++) assert_int_equal(pthread_create(&th[t], NULL, mt_thread, &jobs[1 + t]), 0);
    for (int t = 0; t < 2; t++) assert_int_equal(pthread_join(th[t], NULL), 0);
    pthread_barrier_destroy(&start);
    assert_true(mt_same(&jobs[0], &jobs[1]));
    assert_true(mt_same(&jobs[0], &jobs[2]));
    long found = 0;
    for (int q = 0; q < MT_QUERIES; q++) found += (long)jobs[0].counts[q];
    print_message("  %d queries per thread, %.1f photons per radius query on average\n", MT_QUERIES,
                  (double)found / MT_QUERIES);
    assert_true(found > MT_QUERIES); /* the results are not trivially empty */
    free(points);
    free(jobs);
    photon_map_free(&map);
    free(s.ph);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_photon_map_empty_and_errors),
        cmocka_unit_test(test_photon_map_build_copies_and_invariants),
        cmocka_unit_test(test_photon_map_radius_uniform),
        cmocka_unit_test(test_photon_map_radius_degenerate_sets),
        cmocka_unit_test(test_photon_map_knn_uniform),
        cmocka_unit_test(test_photon_map_knn_degenerate_sets),
        cmocka_unit_test(test_photon_map_knn_arguments),
        cmocka_unit_test(test_photon_map_two_threads),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
