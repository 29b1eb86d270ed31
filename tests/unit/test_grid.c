/* The uniform grid's own invariants (accel/grid.c), built through the acceleration
 * interface on the scenes of the acceleration conformance suite (unit/soup.h): the cell
 * lists themselves, resolution (about 27 N near-cubic cells, one across a flat axis), the
 * brick distances, memory on a teapot in a stadium; and the mailbox, seen through a private
 * copy of grid.c compiled with a counter of primitive tests. Hits against brute force, for
 * every back end: test_accel_conformance. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel.h"
#include "core/rng.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

/* A second copy of the grid code, its five entry points renamed counting_grid_*, with a
 * per-primitive counter of tests (the GRID_COUNT_PRIM_TEST hook of grid.c, empty in the
 * library). Everything else in this file uses the library's grid through accel.h. */
static uint32_t *tests_per_slot;
static long tests_total;
#define GRID_COUNT_PRIM_TEST(slot) (tests_per_slot[slot]++, tests_total++)
#define grid_build counting_grid_build
#define grid_free counting_grid_free
#define grid_intersect counting_grid_intersect
#define grid_occluded counting_grid_occluded
#define grid_memory_bytes counting_grid_memory_bytes
CstStatus grid_build(Grid *a, const AccelGeometry *geom, CstError *err);
void grid_free(Grid *a);
bool grid_intersect(const Grid *a, const Ray *r, Hit *hit);
bool grid_occluded(const Grid *a, const Ray *r);
size_t grid_memory_bytes(const Grid *a);
#include "accel/grid.c"
#undef grid_build
#undef grid_free
#undef grid_intersect
#undef grid_occluded
#undef grid_memory_bytes

/* ------------------------------------------------------------------ scenes */

#include "unit/soup.h"
static void build_grid(const Soup *s, Accel *a)
{
    CstError err = {0};
    AccelGeometry g = soup_geometry(s);
    if (accel_build(a, ACCEL_GRID, &g, &err) != CST_OK) fail_msg("grid build: %s", err.msg);
}

static BBox prim_box(const Soup *s, int id)
{
    if (id < s->num_tris) {
        BBox pb = bbox_empty();
        for (int k = 0; k < 3; k++) pb = bbox_add(pb, s->pos[s->idx[3 * id + k]]);
        return pb;
    }
    const Sphere *sp = &s->spheres[id - s->num_tris];
    float r = fabsf(sp->radius);
    BBox pb = {v3_sub(sp->center, v3s(r)), v3_add(sp->center, v3s(r))};
    return pb;
}

/* Distance in double from p to the segment [a, b] (a point if a == b). */
static uint32_t fbits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

/* ------------------------------------------------------------------ structure */

/* The slots of an occupied cell, by cell number: [*begin, *end). */
static void cell_list(const Grid *g, int cell, uint32_t *begin, uint32_t *end)
{
    cell_list_in(g, cell >> 6, g->cell_bits[cell >> 6], cell & 63, begin, end);
}

/* Every empty brick's brick_info against brute force: the largest coordinate difference
 * to the nearest occupied brick, capped at GRID_BRICK_REACH. */
static void check_brick_distances(const Grid *g)
{
    const int *r = g->brick_res;
    int nb = r[0] * r[1] * r[2], nocc = 0;
    int *occ = malloc((size_t)nb * 3 * sizeof *occ);
    assert_non_null(occ);
    for (int b = 0; b < nb; b++)
        if (g->cell_bits[b]) {
            occ[3 * nocc] = b % r[0];
            occ[3 * nocc + 1] = b / r[0] % r[1];
            occ[3 * nocc + 2] = b / r[0] / r[1];
            nocc++;
        }
    for (int b = 0; b < nb; b++) {
        if (g->cell_bits[b]) continue;
        int p[3] = {b % r[0], b / r[0] % r[1], b / r[0] / r[1]};
        int best = GRID_BRICK_REACH;
        for (int k = 0; k < nocc; k++) {
            int d = 0;
            for (int a = 0; a < 3; a++) d = abs(occ[3 * k + a] - p[a]) > d ? abs(occ[3 * k + a] - p[a]) : d;
            best = d < best ? d : best;
        }
        assert_int_equal((int)g->brick_info[b], best);
    }
    free(occ);
}

static bool cell_lists(const Grid *g, int cell, int id)
{
    if (!((g->cell_bits[cell >> 6] >> (cell & 63)) & 1u)) return false;
    uint32_t begin, end;
    cell_list(g, cell, &begin, &end);
    for (uint32_t k = begin; k < end; k++) {
        uint32_t slot = g->slots[k];
        uint32_t sid = slot < (uint32_t)g->num_tris ? g->tris[slot].id : g->spheres[slot - (uint32_t)g->num_tris].id;
        if ((int)sid == id) return true;
    }
    return false;
}

static int cell_of_point(const Grid *g, Vec3 p)
{
    int c[3];
    double q[3] = {(double)p.x, (double)p.y, (double)p.z};
    for (int a = 0; a < 3; a++) {
        double f = floor((q[a] - g->org[a]) * g->inv_cell_size[a]);
        c[a] = f < 0.0 ? 0 : (f >= (double)g->res[a] ? g->res[a] - 1 : (int)f);
    }
    return grid_cell_index(g, c[0], c[1], c[2]);
}

/* Checks the cell lists: one non-empty list per occupancy bit, offsets increasing and
 * complete, each brick's first list right after the previous bricks' lists, slots in
 * range and increasing within a cell, the grid's primitive copies exact (the list back
 * end's floats), every placed primitive referenced, and the cell containing each of a set
 * of points on each primitive (vertices, edge midpoints, centroid, random points; sphere
 * poles) listing it. Returns the number of references. */
static size_t check_structure(const Grid *g, const Soup *s, Pcg32 *rng)
{
    int n = s->num_tris + s->num_spheres;
    assert_int_equal(g->num_tris, s->num_tris);
    assert_int_equal(g->num_spheres, s->num_spheres);
    if (n <= 0) { assert_int_equal(g->num_cells, 0); return 0; }
    assert_int_equal(g->num_cells, 64 * g->brick_res[0] * g->brick_res[1] * g->brick_res[2]);
    for (int a = 0; a < 3; a++) assert_int_equal(g->brick_res[a], (g->res[a] + 3) / 4);
    assert_true(g->list_start[0] == 0u && g->list_start[g->num_occupied] == g->num_refs);
    for (int k = 0; k < g->num_occupied; k++) assert_true(g->list_start[k] < g->list_start[k + 1]);
    int *seen = calloc((size_t)n, sizeof *seen);
    assert_non_null(seen);
    for (int i = 0; i < s->num_tris; i++) {
        const GridTri *t = &g->tris[i];
        int id = (int)t->id;
        assert_true(id >= 0 && id < s->num_tris);
        seen[id]++;
        Vec3 a = s->pos[s->idx[3 * id]], b = s->pos[s->idx[3 * id + 1]], c = s->pos[s->idx[3 * id + 2]];
        assert_memory_equal(&t->v0, &a, sizeof a);
        assert_memory_equal(&t->v1, &b, sizeof b);
        assert_memory_equal(&t->v2, &c, sizeof c);
    }
    for (int j = 0; j < s->num_spheres; j++) {
        int id = (int)g->spheres[j].id;
        assert_true(id >= s->num_tris && id < n);
        seen[id]++;
        assert_true(g->spheres[j].radius == s->spheres[id - s->num_tris].radius);
    }
    for (int i = 0; i < n; i++) assert_int_equal(seen[i], 1); /* a permutation */
    memset(seen, 0, (size_t)n * sizeof *seen);
    int occupied = 0;
    for (int c = 0; c < g->num_cells; c++) {
        if ((c & 63) == 0 && g->cell_bits[c >> 6]) assert_int_equal((int)g->brick_info[c >> 6], occupied);
        bool bit = (g->cell_bits[c >> 6] >> (c & 63)) & 1u;
        uint32_t begin = 0, end = 0;
        if (bit) {
            cell_list(g, c, &begin, &end);
            assert_true(begin == g->list_start[occupied] && end == g->list_start[occupied + 1]);
            occupied++;
        }
        /* Decode the brick numbering of grid.h (4 x 4 x 4 bricks); padding cells past res
         * stay empty. */
        int brick = c >> 6, local = c & 63;
        int x = (brick % g->brick_res[0]) * 4 + (local & 3);
        int y = (brick / g->brick_res[0] % g->brick_res[1]) * 4 + ((local >> 2) & 3);
        int z = (brick / g->brick_res[0] / g->brick_res[1]) * 4 + (local >> 4);
        if (x >= g->res[0] || y >= g->res[1] || z >= g->res[2]) assert_false(bit);
        else assert_int_equal(grid_cell_index(g, x, y, z), c);
        for (uint32_t k = begin; k < end; k++) {
            assert_true(g->slots[k] < (uint32_t)n);
            if (k > begin) assert_true(g->slots[k] > g->slots[k - 1]);
            uint32_t slot = g->slots[k];
            seen[slot < (uint32_t)g->num_tris ? g->tris[slot].id : g->spheres[slot - (uint32_t)g->num_tris].id]++;
        }
    }
    assert_int_equal(occupied, g->num_occupied);
    /* Empty bricks: their distance to the nearest occupied brick (brute force on grids
     * small enough). */
    if (g->num_cells / 64 <= 20000) check_brick_distances(g);
    for (int id = 0; id < n; id++) {
        BBox b = prim_box(s, id);
        bool finite = v3_is_finite(b.min) && v3_is_finite(b.max);
        for (int k = 0; k < 3 && id < s->num_tris; k++) finite = finite && v3_is_finite(s->pos[s->idx[3 * id + k]]);
        if (finite && seen[id] == 0) fail_msg("primitive %d is in no cell", id);
        if (!finite) continue;
        Vec3 pts[16];
        int np = 0;
        if (id < s->num_tris) {
            Vec3 a = s->pos[s->idx[3 * id]], b1 = s->pos[s->idx[3 * id + 1]], c1 = s->pos[s->idx[3 * id + 2]];
            pts[np++] = a; pts[np++] = b1; pts[np++] = c1;
            pts[np++] = v3_scale(v3_add(a, b1), 0.5f);
            pts[np++] = v3_scale(v3_add(b1, c1), 0.5f);
            pts[np++] = v3_scale(v3_add(c1, a), 0.5f);
            pts[np++] = v3_scale(v3_add(a, v3_add(b1, c1)), 1.0f / 3.0f);
            for (int k = 0; k < 6; k++) {
                float bu = pcg32_float(rng), bv = pcg32_float(rng);
                if (bu + bv > 1.0f) { bu = 1.0f - bu; bv = 1.0f - bv; }
                pts[np++] = v3_add(a, v3_add(v3_scale(v3_sub(b1, a), bu), v3_scale(v3_sub(c1, a), bv)));
            }
        } else {
            const Sphere *sp = &s->spheres[id - s->num_tris];
            for (int k = 0; k < 8; k++) pts[np++] = v3_madd(sp->center, rnd_dir(rng), fabsf(sp->radius));
        }
        for (int k = 0; k < np; k++)
            if (!cell_lists(g, cell_of_point(g, pts[k]), id))
                fail_msg("the cell holding point %d of primitive %d does not list it", k, id);
    }
    free(seen);
    return g->num_refs;
}

/* ------------------------------------------------------------------ tests */

static void test_grid_empty(void **state)
{
    (void)state;
    Accel a;
    CstError err = {0};
    AccelGeometry none = {NULL, NULL, 0, NULL, 0, NULL, 0};
    assert_int_equal(accel_build(&a, ACCEL_GRID, &none, &err), CST_OK);
    assert_int_equal(a.grid.num_cells, 0);
    assert_int_equal(accel_memory_bytes(&a), 0);
    accel_free(&a);
    accel_free(&a); /* a freed accel frees again */
    grid_free(NULL);
}

/* Resolution: ~27 N cells, near-cubic, one cell across a flat axis. */
static void test_grid_resolution(void **state)
{
    (void)state;
    int res[3];
    double cube[3] = {1.0, 1.0, 1.0};
    grid_resolution(cube, 27.0 * 1000.0, res);
    assert_true(res[0] == 30 && res[1] == 30 && res[2] == 30);
    double slab[3] = {8.0, 2.0, 1.0};
    grid_resolution(slab, 27.0 * 1000.0, res);
    assert_true(abs(res[0] - 8 * res[2]) <= 8 && abs(res[1] - 2 * res[2]) <= 2);
    assert_true(abs(res[0] * res[1] * res[2] - 27000) < 27000 / 20);
    double flat[3] = {2.0, 1.0, 0.0};
    grid_resolution(flat, 27.0 * 1000.0, res);
    assert_int_equal(res[2], 1);
    assert_true(abs(res[0] - 2 * res[1]) <= 1 && abs(res[0] * res[1] - 27000) < 27000 / 20);
    double almost_flat[3] = {1.0, 1.0, 1e-6};
    grid_resolution(almost_flat, 27.0 * 1000.0, res);
    assert_true(res[2] == 1 && res[0] == res[1] && abs(res[0] * res[1] - 27000) < 27000 / 20);
    double line[3] = {0.0, 5.0, 0.0};
    grid_resolution(line, 27.0 * 100.0, res);
    assert_true(res[0] == 1 && res[1] == 2700 && res[2] == 1);
    double point[3] = {0.0, 0.0, 0.0};
    grid_resolution(point, 27.0 * 100.0, res);
    assert_true(res[0] == 1 && res[1] == 1 && res[2] == 1);
    double huge[3] = {1.0, 1.0, 1.0};
    grid_resolution(huge, (double)GRID_MAX_CELLS, res);
    assert_true((size_t)res[0] * (size_t)res[1] * (size_t)res[2] <= (size_t)GRID_MAX_CELLS);
}


/* Random soups with needles (about 27 N cells, up to rounding per axis) and mixed
 * triangles and spheres (one of negative radius). */
static void test_grid_structure_random(void **state)
{
    (void)state;
    const int sizes[] = {1, 2, 7, 100, 5000};
    for (int k = 0; k < 5; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 1000u + (uint64_t)k, 3u);
        soup_random_tris_needles(&s, &rng, sizes[k]);
        Accel a;
        build_grid(&s, &a);
        const Grid *g = &a.grid;
        size_t refs = check_structure(g, &s, &rng);
        int cells = g->res[0] * g->res[1] * g->res[2];
        print_message("  soup of %-5d with needles  cells %3dx%3dx%3d refs %7zu (%.1f/prim) %6.1f KB\n", sizes[k],
                      g->res[0], g->res[1], g->res[2], refs, (double)refs / sizes[k],
                      (double)accel_memory_bytes(&a) / 1024.0);
        assert_true(cells <= 2 * 27 * sizes[k] && cells >= 27 * sizes[k] / 4);
        accel_free(&a);
        soup_free(&s);
    }
    const int tris[] = {0, 1, 300, 2000}, spheres[] = {1, 5, 300, 500};
    for (int k = 0; k < 4; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 2000u + (uint64_t)k, 5u);
        soup_random_tris_needles(&s, &rng, tris[k]);
        soup_random_spheres(&s, &rng, spheres[k]);
        if (k == 3) s.spheres[0].radius = -s.spheres[0].radius; /* sphere_intersect squares it */
        Accel a;
        build_grid(&s, &a);
        size_t refs = check_structure(&a.grid, &s, &rng);
        print_message("  %d tris + %d spheres: refs %zu\n", tris[k], spheres[k], refs);
        accel_free(&a);
        soup_free(&s);
    }
}

/* The lattice cube of the cell-plane rays; zero-area, NaN and infinite triangles among
 * ordinary ones; triangles along one line (two flat axes: one cell across each); scenes
 * in one plane (one cell across it, about 27 N cells over the other two). */
static void test_grid_structure_degenerate_and_flat(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 3000u, 7u);
    Soup s = {0};
    Accel a;
    soup_grid_cube(&s, 4, 1.0f, v3(0.0f, 0.0f, 0.0f), false);
    build_grid(&s, &a);
    check_structure(&a.grid, &s, &rng);
    accel_free(&a);
    soup_free(&s);

    pcg32_seed(&rng, 4000u, 9u);
    soup_degenerate_mix(&s, &rng);
    build_grid(&s, &a);
    check_structure(&a.grid, &s, &rng);
    accel_free(&a);
    soup_free(&s);

    pcg32_seed(&rng, 4001u, 9u);
    soup_on_a_line(&s, &rng);
    build_grid(&s, &a);
    assert_true(a.grid.res[1] == 1 && a.grid.res[2] == 1 && a.grid.res[0] > 1);
    check_structure(&a.grid, &s, &rng);
    accel_free(&a);
    soup_free(&s);

    for (int variant = 0; variant < 2; variant++) {
        soup_flat(&s, &rng, variant);
        build_grid(&s, &a);
        const Grid *g = &a.grid;
        int flat_axis = variant == 0 ? 2 : 0;
        assert_int_equal(g->res[flat_axis], 1);
        int other = g->res[0] * g->res[1] * g->res[2];
        assert_true(other > 27 * s.num_tris / 3 && other < 2 * 27 * (s.num_tris + s.num_spheres));
        check_structure(g, &s, &rng);
        print_message("  flat in %c: cells %dx%dx%d\n", "zx"[variant], g->res[0], g->res[1], g->res[2]);
        accel_free(&a);
        soup_free(&s);
    }
}

/* Teapot in a stadium (soup_teapot_in_stadium): the grid, sized for the stadium, puts the
 * whole teapot in a handful of cells and is slow there (docs/benchmarks.md), but must stay
 * small: cells ~27 N, references dominated by the few huge triangles (exact overlap keeps
 * each to the cells its plane crosses). */
static void test_grid_teapot_in_stadium(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 5000u, 11u);
    Soup s = {0};
    soup_teapot_in_stadium(&s, &rng);
    Accel a;
    build_grid(&s, &a);
    const Grid *g = &a.grid;
    size_t refs = check_structure(g, &s, &rng);
    size_t bytes = accel_memory_bytes(&a);
    print_message("  teapot in stadium: %d tris, cells %dx%dx%d, refs %zu, %.1f MB\n", s.num_tris, g->res[0],
                  g->res[1], g->res[2], refs, (double)bytes / 1048576.0);
    assert_true(g->res[0] * g->res[1] * g->res[2] <= 2 * 27 * s.num_tris);
    assert_true(refs < (size_t)20 * (size_t)s.num_tris);
    assert_true(bytes < (size_t)16 << 20);
    accel_free(&a);
    soup_free(&s);
}


/* The brick distances on a long grid of bricks with three occupied ones, where most
 * distances reach the cap (the meshes of the other tests give grids too small for it). */
static void test_grid_brick_distances(void **state)
{
    (void)state;
    Grid g = {0};
    g.brick_res[0] = 3 * GRID_BRICK_REACH + 5;
    g.brick_res[1] = 3;
    g.brick_res[2] = 2;
    int nb = g.brick_res[0] * g.brick_res[1] * g.brick_res[2];
    g.num_cells = 64 * nb;
    g.cell_bits = calloc((size_t)nb, sizeof *g.cell_bits);
    g.brick_info = calloc((size_t)nb, sizeof *g.brick_info);
    uint32_t *tmp = calloc(2 * (size_t)nb, sizeof *tmp);
    assert_true(g.cell_bits && g.brick_info && tmp);
    g.cell_bits[0] = 1u;                                         /* brick (0, 0, 0) */
    g.cell_bits[GRID_BRICK_REACH + 3 + g.brick_res[0] * 4] = 8u; /* (reach + 3, 1, 1) */
    g.cell_bits[nb - 1] = (uint64_t)1 << 63;                     /* the last corner */
    grid_brick_distances(&g, tmp);
    check_brick_distances(&g);
    int capped = 0;
    for (int b = 0; b < nb; b++) capped += !g.cell_bits[b] && g.brick_info[b] == GRID_BRICK_REACH;
    assert_true(capped > 0);
    free(tmp);
    free(g.cell_bits);
    free(g.brick_info);
}

/* Builds the counting copy over s and runs ray r through it; returns the largest number
 * of tests of one primitive, and adds to the totals. */
static uint32_t counted_ray(const Grid *g, int n, const Ray *r, long *tests, long *distinct)
{
    memset(tests_per_slot, 0, (size_t)n * sizeof *tests_per_slot);
    tests_total = 0;
    Hit h;
    counting_grid_intersect(g, r, &h);
    uint32_t worst = 0;
    for (int i = 0; i < n; i++) {
        worst = tests_per_slot[i] > worst ? tests_per_slot[i] : worst;
        *distinct += tests_per_slot[i] > 0;
    }
    *tests += tests_total;
    return worst;
}

/* How many primitive references the ray's walk meets, i.e. the tests it would make
 * without the mailbox (the same walk as counting_grid_intersect). */
static long refs_on_walk(const Grid *g, const Ray *ray)
{
    GridWalk w;
    if (g->num_cells == 0 || !walk_begin(g, ray, &w)) return 0;
    Hit h;
    if (grid_intersect(g, ray, &h)) w.t_end = fmin(w.t_end, (double)h.t);
    long refs = 0;
    for (;;) {
        uint64_t bits = g->cell_bits[w.brick];
        for (uint64_t m = bits ? brick_cells(&w) & bits : 0u; m; m &= m - 1u) {
            uint32_t begin, end;
            cell_list_in(g, w.brick, bits, __builtin_ctzll(m), &begin, &end);
            refs += end - begin;
        }
        if (!walk_next_brick(g, &w, bits)) break;
    }
    return refs;
}

/* Mailboxing: with no more primitives than mailbox slots no primitive is ever tested
 * twice, though the rays cross many cells holding each (long thin triangles along the
 * rays); in a soup with needles, repeats (mailbox collisions) stay rare while the cells
 * hold several times more references than are tested. The counting copy returns the
 * same hits as the library's grid. */
static void test_grid_mailbox(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 6000u, 13u);
    Soup s = {0};
    soup_reserve(&s, GRID_MAILBOX, 3 * GRID_MAILBOX, 0);
    for (int i = 0; i < GRID_MAILBOX; i++) {
        /* Needles along the diagonal, fanned out a little. */
        Vec3 off = rnd_v3(&rng, -0.5, 0.5);
        soup_add_tri(&s, v3_add(v3(-10.0f, -10.0f, -10.0f), off), v3_add(v3(10.0f, 10.0f, 10.0f), off),
                     v3_add(v3(10.0f, 10.0f, 10.2f), off));
    }
    for (int scene = 0; scene < 2; scene++) {
        if (scene == 1) {
            soup_free(&s);
            soup_random_tris_needles(&s, &rng, 3000);
        }
        int n = s.num_tris;
        AccelGeometry geom = soup_geometry(&s);
        Grid g;
        CstError err = {0};
        assert_int_equal(counting_grid_build(&g, &geom, &err), CST_OK);
        tests_per_slot = calloc((size_t)n, sizeof *tests_per_slot);
        assert_non_null(tests_per_slot);
        Accel lib; /* the library's grid */
        build_grid(&s, &lib);
        long tests = 0, distinct = 0, refs = 0, rays = 0, repeated_rays = 0;
        uint32_t worst = 0;
        for (int i = 0; i < 4000; i++) {
            Vec3 o, d;
            if (scene == 0 || (i & 1)) { /* along the needles */
                o = v3_add(v3(-12.0f, -12.0f, -12.0f), rnd_v3(&rng, -0.6, 0.6));
                d = v3_normalize(v3_add(v3(1.0f, 1.0f, 1.0f), rnd_v3(&rng, -0.02, 0.02)));
            } else {
                o = rnd_v3(&rng, -15.0, 15.0);
                d = rnd_dir(&rng);
            }
            Ray r = ray_make(o, d, 0.0f, INFINITY);
            uint32_t wr = counted_ray(&g, n, &r, &tests, &distinct);
            worst = wr > worst ? wr : worst;
            repeated_rays += wr > 1;
            refs += refs_on_walk(&g, &r);
            rays++;
            Hit hc = {0}, hl = {0};
            bool c = counting_grid_intersect(&g, &r, &hc), l = accel_intersect(&lib, &r, &hl);
            assert_true(c == l && (!c || (hc.prim == hl.prim && fbits(hc.t) == fbits(hl.t))));
            assert_true(counting_grid_occluded(&g, &r) == accel_occluded(&lib, &r));
        }
        print_message("  mailbox (%d slots), %s: %ld rays meet %ld references, test %ld primitives (%ld distinct); "
                      "%ld rays repeat a test, at most %u times\n",
                      GRID_MAILBOX, scene == 0 ? "one needle per slot" : "3000-triangle soup", rays, refs, tests,
                      distinct, repeated_rays, worst);
        if (scene == 0) {
            assert_int_equal(worst, 1);
            assert_true(refs > 4 * tests); /* each needle sits in many cells along the ray */
        } else {
            assert_true(tests - distinct < distinct / 20); /* under 5% repeats */
            assert_true(refs > tests);
        }
        free(tests_per_slot);
        tests_per_slot = NULL;
        accel_free(&lib);
        counting_grid_free(&g);
    }
    soup_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_empty),
        cmocka_unit_test(test_grid_resolution),
        cmocka_unit_test(test_grid_structure_random),
        cmocka_unit_test(test_grid_structure_degenerate_and_flat),
        cmocka_unit_test(test_grid_teapot_in_stadium),
        cmocka_unit_test(test_grid_mailbox),
        cmocka_unit_test(test_grid_brick_distances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
