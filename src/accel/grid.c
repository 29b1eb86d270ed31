/* Uniform grid: resolution heuristic, exact primitive-cell overlap, compressed cell lists
 * (build) and traversal: a 3D-DDA over bricks with jumps through empty space, the cells
 * crossed in each occupied brick at once, hashed mailboxing and SIMD triangle tests
 * (closest hit, occlusion).
 *
 * Exactness. Hits must be bit-identical to the list back end, so every primitive is
 * tested with the caller's own ray (triangle_intersect_watertight / sphere_intersect on the same
 * floats), and the grid only decides which primitives to test and when to stop. Each
 * primitive is stored in every cell that comes within `margin` of it (margin = 2^-16 of
 * the scene's coordinate scale: ~500 float ulps of the coordinates, a small fraction of
 * a cell). So a primitive absent from a cell lies at least `margin` (max norm) away from
 * it, and a ray leaving that cell at t_exit can only meet the primitive beyond
 * t_exit + margin / max|d_i|. Hence once the best hit so far has t <= t_exit of the
 * current cell, no later cell can hold a closer one: stop. The DDA runs in double, so
 * its cell boundaries are off by ~1e-16 relative, and neither the stepping nor the
 * brick jumps can skip a region a primitive occupies; the cells of a brick are found
 * from the same crossings, rounded to float only in the direction that adds cells. What
 * the grid does not promise are hits that Moller-Trumbore itself puts farther than
 * `margin` off their triangle (rays grazing a sliver's plane, where t is ill-conditioned):
 * such a hit may be skipped, as the BVH may skip hits off a node box. */
#include "accel/grid.h"

#include <float.h>
#include <immintrin.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/sphere.h"
#include "geometry/triangle_block.h"

enum {
    GRID_CELLS_PER_PRIM = 27,  /* #cells ~ 27 N: 3 cells per primitive along each axis */
    GRID_MAX_CELLS = 1 << 26,  /* 256 MB of cell offsets; reached only from N ~ 2.5M */
    GRID_MAX_AXIS = 1 << 16,   /* finer cells would be thinner than the margin */
    GRID_MIN_REF_BUDGET = 1 << 22,
    GRID_REFS_PER_PRIM = 64,   /* beyond max(4M, 64 N) references, coarsen the grid */
    /* Per-ray mailbox slots (a power of two). Direct-mapped on the low bits of the
     * grid-local index: those follow the Morton order, so neighbours rarely collide. */
    GRID_MAILBOX = 32,
    BRICK_SHIFT = 2 /* bricks of 4 x 4 x 4 cells (grid.h) */
};
#define GRID_MARGIN_REL 0x1p-16

/* Test hook: tests/unit/test_grid.c compiles a private copy of this file with this macro
 * counting primitive tests per ray, to check the mailbox. Nothing in the library. */
#ifndef GRID_COUNT_PRIM_TEST
#define GRID_COUNT_PRIM_TEST(slot) ((void)0)
#endif

static inline double min3d(double a, double b, double c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
static inline double max3d(double a, double b, double c) { return a > b ? (a > c ? a : c) : (b > c ? b : c); }

/* The number of brick (bx, by, bz), x fastest. */
static inline int grid_brick_index(const Grid *g, int bx, int by, int bz)
{
    return bx + g->brick_res[0] * (by + g->brick_res[1] * bz);
}

/* The number of cell (x, y, z) in the brick layout of grid.h. */
static inline int grid_cell_index(const Grid *g, int x, int y, int z)
{
    const int m = (1 << BRICK_SHIFT) - 1;
    int brick = grid_brick_index(g, x >> BRICK_SHIFT, y >> BRICK_SHIFT, z >> BRICK_SHIFT);
    return brick * 64 + (x & m) + ((y & m) << BRICK_SHIFT) + ((z & m) << (2 * BRICK_SHIFT));
}

/* ------------------------------------------------------------------ build */

/* Cells per axis: proportional to the extents (near-cubic cells), product ~ target. An
 * axis too thin for one cell at that density (a flat or nearly flat box) gets exactly
 * one, and the density is recomputed over the remaining axes. */
static void grid_resolution(const double ext[3], double target, int res[3])
{
    bool active[3];
    for (int a = 0; a < 3; a++) { res[a] = 1; active[a] = ext[a] > 0.0; }
    for (;;) {
        int k = 0;
        double vol = 1.0;
        for (int a = 0; a < 3; a++)
            if (active[a]) { k++; vol *= ext[a]; }
        if (k == 0) return;
        double per_unit = pow(target / vol, 1.0 / (double)k); /* cells per unit length */
        bool again = false;
        for (int a = 0; a < 3; a++)
            if (active[a] && !(ext[a] * per_unit >= 1.0)) { active[a] = false; again = true; }
        if (again) continue;
        for (int a = 0; a < 3; a++) {
            if (!active[a]) continue;
            double r = floor(ext[a] * per_unit + 0.5);
            res[a] = r < 1.0 ? 1 : (r > (double)GRID_MAX_AXIS ? GRID_MAX_AXIS : (int)r);
        }
        break;
    }
    /* Rounding can overshoot the cap a little. */
    while ((size_t)res[0] * (size_t)res[1] * (size_t)res[2] > (size_t)GRID_MAX_CELLS) {
        int a = res[0] >= res[1] && res[0] >= res[2] ? 0 : (res[1] >= res[2] ? 1 : 2);
        res[a] = res[a] * 7 / 8;
    }
}

/* Separating-axis test of a triangle against an axis-aligned box (Akenine-Moller, "Fast
 * 3D Triangle-Box Overlap Testing", JGT 6(1), 2001): the 3 box normals, the triangle
 * normal and the 9 cross products of the box normals with the triangle edges. Any axis
 * that separates proves disjointness, however it was rounded; only the projections'
 * rounding (~1e-16 of the coordinates, in double) matters, and the box has already been
 * grown by the margin. A degenerate triangle has zero cross products, which separate
 * nothing, so it stays wherever its bounding box overlaps: conservative. */
static bool tri_box_overlap(const double tv[3][3], const double center[3], const double half[3])
{
    double v[3][3];
    for (int i = 0; i < 3; i++)
        for (int a = 0; a < 3; a++) v[i][a] = tv[i][a] - center[a];
    for (int a = 0; a < 3; a++)
        if (min3d(v[0][a], v[1][a], v[2][a]) > half[a] || max3d(v[0][a], v[1][a], v[2][a]) < -half[a])
            return false;
    double e[3][3];
    for (int a = 0; a < 3; a++) {
        e[0][a] = v[1][a] - v[0][a];
        e[1][a] = v[2][a] - v[1][a];
        e[2][a] = v[0][a] - v[2][a];
    }
    static const int NEXT[3] = {1, 2, 0}, PREV[3] = {2, 0, 1};
    for (int a = 0; a < 3; a++) {
        int a1 = NEXT[a], a2 = PREV[a];
        for (int i = 0; i < 3; i++) {
            /* unit_a x e_i has components -e[a2] on axis a1 and e[a1] on axis a2. */
            double x1 = -e[i][a2], x2 = e[i][a1];
            double p0 = x1 * v[0][a1] + x2 * v[0][a2], p1 = x1 * v[1][a1] + x2 * v[1][a2],
                   p2 = x1 * v[2][a1] + x2 * v[2][a2];
            double r = half[a1] * fabs(x1) + half[a2] * fabs(x2);
            if (min3d(p0, p1, p2) > r || max3d(p0, p1, p2) < -r) return false;
        }
    }
    double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double dist = n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2];
    double r = half[0] * fabs(n[0]) + half[1] * fabs(n[1]) + half[2] * fabs(n[2]);
    return fabs(dist) <= r;
}

/* Whether a sphere's surface (the only part a ray can hit) meets the box: the box's
 * nearest point is within the radius and its farthest is not strictly inside (Arvo,
 * "A Simple Method for Box-Sphere Intersection Testing", Graphics Gems, 1990). */
static bool sphere_box_overlap(const double c[3], double radius, const double lo[3], const double hi[3])
{
    double near2 = 0.0, far2 = 0.0;
    for (int a = 0; a < 3; a++) {
        if (c[a] < lo[a]) near2 += (lo[a] - c[a]) * (lo[a] - c[a]);
        else if (c[a] > hi[a]) near2 += (c[a] - hi[a]) * (c[a] - hi[a]);
        double f = fabs(c[a] - lo[a]) > fabs(hi[a] - c[a]) ? fabs(c[a] - lo[a]) : fabs(hi[a] - c[a]);
        far2 += f * f;
    }
    double r2 = radius * radius;
    return near2 <= r2 && far2 >= r2;
}

/* Bounding box of scene primitive id; false if it has a non-finite coordinate (checked
 * per vertex: the min/max of a NaN and a number is the number). Such a primitive is left
 * out of the grid: its NaN or infinite terms fail the primitive tests' comparisons, so
 * the list back end never reports it either. */
static bool prim_bounds(const AccelGeometry *geom, int id, BBox *box)
{
    if (id < geom->num_tris) {
        const int32_t *k = &geom->tri_indices[3 * id];
        Vec3 a = geom->positions[k[0]], b = geom->positions[k[1]], c = geom->positions[k[2]];
        *box = bbox_add(bbox_add(bbox_add(bbox_empty(), a), b), c);
        return v3_is_finite(a) && v3_is_finite(b) && v3_is_finite(c);
    }
    if (id >= geom->num_tris + geom->num_spheres) {
        *box = geom->shapes[id - geom->num_tris - geom->num_spheres].bounds; /* padded (shape_init) */
        return v3_is_finite(box->min) && v3_is_finite(box->max);
    }
    const Sphere *s = &geom->spheres[id - geom->num_tris];
    Vec3 r = v3s(fabsf(s->radius)); /* sphere_intersect only uses radius^2 */
    box->min = v3_sub(s->center, r);
    box->max = v3_add(s->center, r);
    return v3_is_finite(box->min) && v3_is_finite(box->max);
}

/* Visits the cells scene primitive id overlaps (within the margin), storing grid-local
 * index `slot`. Count pass (slots == NULL): count[c]++; fill pass: slots[count[c]++] =
 * slot. Returns the number of cells. */
static size_t grid_insert(const Grid *g, const AccelGeometry *geom, int id, uint32_t slot, uint32_t *count,
                          uint32_t *slots)
{
    BBox box;
    if (!prim_bounds(geom, id, &box)) return 0;
    double m = (double)g->margin;
    double bmin[3] = {(double)box.min.x, (double)box.min.y, (double)box.min.z},
           bmax[3] = {(double)box.max.x, (double)box.max.y, (double)box.max.z};
    int lo[3], hi[3], spanning = 0;
    for (int a = 0; a < 3; a++) {
        double f0 = floor((bmin[a] - m - g->org[a]) * g->inv_cell_size[a]);
        double f1 = floor((bmax[a] + m - g->org[a]) * g->inv_cell_size[a]);
        lo[a] = f0 < 0.0 ? 0 : (f0 >= (double)g->res[a] ? g->res[a] - 1 : (int)f0);
        hi[a] = f1 < 0.0 ? 0 : (f1 >= (double)g->res[a] ? g->res[a] - 1 : (int)f1);
        spanning += hi[a] > lo[a];
    }
    /* When the box spans several cells along at most one axis, the primitive (a connected
     * set whose projection fills the box) crosses every cell of the range: no test. */
    bool exact = spanning >= 2;
    double tv[3][3], sc[3] = {0.0, 0.0, 0.0}, sr = 0.0;
    bool is_tri = id < geom->num_tris;
    if (id >= geom->num_tris + geom->num_spheres) exact = false; /* shapes: every cell of the box */
    if (is_tri) {
        for (int i = 0; i < 3; i++) {
            Vec3 p = geom->positions[geom->tri_indices[3 * id + i]];
            tv[i][0] = (double)p.x; tv[i][1] = (double)p.y; tv[i][2] = (double)p.z;
        }
    } else if (exact) {
        const Sphere *s = &geom->spheres[id - geom->num_tris];
        sc[0] = (double)s->center.x; sc[1] = (double)s->center.y; sc[2] = (double)s->center.z;
        sr = fabs((double)s->radius);
    }
    size_t n = 0;
    for (int z = lo[2]; z <= hi[2]; z++)
        for (int y = lo[1]; y <= hi[1]; y++)
            for (int x = lo[0]; x <= hi[0]; x++) {
                if (exact) {
                    /* The cell grown by the margin on every side. */
                    int c[3] = {x, y, z};
                    double clo[3], chi[3], center[3], half[3];
                    for (int a = 0; a < 3; a++) {
                        clo[a] = g->org[a] + (double)c[a] * g->cell_size[a] - m;
                        chi[a] = g->org[a] + (double)(c[a] + 1) * g->cell_size[a] + m;
                        center[a] = 0.5 * (clo[a] + chi[a]);
                        half[a] = 0.5 * (chi[a] - clo[a]);
                    }
                    if (is_tri ? !tri_box_overlap(tv, center, half) : !sphere_box_overlap(sc, sr, clo, chi))
                        continue;
                }
                int cell = grid_cell_index(g, x, y, z);
                if (slots) slots[count[cell]++] = slot;
                else count[cell]++;
                n++;
            }
    return n;
}

/* Sets the cell geometry for resolution res over the grid box [lo, lo + size] and the
 * bricks (grid.h). */
static void grid_set_cells(Grid *g, const double lo[3], const double size[3], const int res[3])
{
    for (int a = 0; a < 3; a++) {
        g->res[a] = res[a];
        g->org[a] = lo[a];
        g->cell_size[a] = size[a] / (double)res[a];
        g->inv_cell_size[a] = (double)res[a] / size[a];
    }
    for (int a = 0; a < 3; a++) g->brick_res[a] = ((res[a] - 1) >> BRICK_SHIFT) + 1;
    g->num_cells = 64 * g->brick_res[0] * g->brick_res[1] * g->brick_res[2];
}

/* One pass of the Chebyshev distance transform, along axis a: d[b] becomes the least
 * max(|i - j|, d[b']) over the bricks b' of b's line along a (index j, b's is i), capped
 * at GRID_BRICK_REACH. Passes along x, y and z in turn give, from 0 on occupied bricks and
 * the cap elsewhere, the distance in the largest coordinate difference to the nearest
 * occupied brick: min over b' of max(|dx|, |dy|, |dz|, ...) nests axis by axis. */
static void brick_distance_pass(const Grid *g, int a, const uint32_t *in, uint32_t *out)
{
    const int *r = g->brick_res;
    int stride = a == 0 ? 1 : (a == 1 ? r[0] : r[0] * r[1]);
    int n = r[a], nb = r[0] * r[1] * r[2];
    for (int b = 0; b < nb; b++) {
        int i = b / stride % n, line = b - i * stride;
        uint32_t best = GRID_BRICK_REACH;
        int lo = i - (GRID_BRICK_REACH - 1) > 0 ? i - (GRID_BRICK_REACH - 1) : 0;
        int hi = i + (GRID_BRICK_REACH - 1) < n - 1 ? i + (GRID_BRICK_REACH - 1) : n - 1;
        for (int j = lo; j <= hi && best > 0; j++) {
            uint32_t dist = (uint32_t)(j > i ? j - i : i - j), v = in[line + j * stride];
            if (v < dist) v = dist;
            if (v < best) best = v;
        }
        out[b] = best;
    }
}

/* brick_info of the empty bricks (grid.h); `tmp` has two entries per brick. */
static void grid_brick_distances(Grid *g, uint32_t *tmp)
{
    int nb = g->num_cells / 64;
    uint32_t *d0 = tmp, *d1 = tmp + nb;
    for (int b = 0; b < nb; b++) d0[b] = g->cell_bits[b] ? 0u : GRID_BRICK_REACH;
    brick_distance_pass(g, 0, d0, d1);
    brick_distance_pass(g, 1, d1, d0);
    brick_distance_pass(g, 2, d0, d1);
    for (int b = 0; b < nb; b++)
        if (!g->cell_bits[b]) g->brick_info[b] = d1[b];
}

/* Spreads the low 10 bits of x to every third bit (Morton code helper). */
static uint64_t morton_spread(uint32_t x)
{
    uint64_t v = x & 0x3ffu;
    v = (v | (v << 16)) & 0x030000ffu;
    v = (v | (v << 8)) & 0x0300f00fu;
    v = (v | (v << 4)) & 0x030c30c3u;
    v = (v | (v << 2)) & 0x09249249u;
    return v;
}

static int cmp_u64(const void *a, const void *b)
{
    uint64_t x = *(const uint64_t *)a, y = *(const uint64_t *)b;
    return (x > y) - (x < y);
}

/* Grid-local order: triangles, then spheres, each in Morton order of the box centre
 * (ties by id, so the order is deterministic), primitives that cannot be placed last.
 * order[i] = scene id of local index i. */
static bool grid_order(const AccelGeometry *geom, BBox raw, uint32_t *order)
{
    size_t n = (size_t)geom->num_tris + (size_t)geom->num_spheres + (size_t)geom->num_shapes;
    uint64_t *key = malloc(n * sizeof *key);
    if (!key) return false;
    Vec3 ext = v3_sub(raw.max, raw.min);
    float sx = ext.x > 0.0f ? 1023.0f / ext.x : 0.0f, sy = ext.y > 0.0f ? 1023.0f / ext.y : 0.0f,
          sz = ext.z > 0.0f ? 1023.0f / ext.z : 0.0f;
    for (size_t i = 0; i < n; i++) {
        BBox b;
        uint64_t code = 0x3fffffffu; /* unplaceable: last */
        if (prim_bounds(geom, (int)i, &b)) {
            Vec3 c = v3_sub(bbox_center(b), raw.min);
            code = morton_spread((uint32_t)clampf(c.x * sx, 0.0f, 1023.0f)) |
                   (morton_spread((uint32_t)clampf(c.y * sy, 0.0f, 1023.0f)) << 1) |
                   (morton_spread((uint32_t)clampf(c.z * sz, 0.0f, 1023.0f)) << 2);
        }
        uint64_t kind = (uint64_t)(i >= (size_t)geom->num_tris) + (uint64_t)(i >= accel_shape_base(geom));
        key[i] = (kind << 62) | (code << 32) | (uint64_t)i;
    }
    qsort(key, n, sizeof *key, cmp_u64);
    for (size_t i = 0; i < n; i++) order[i] = (uint32_t)key[i];
    free(key);
    return true;
}

CstStatus grid_build(Grid *g, const AccelGeometry *geom, CstError *err)
{
    memset(g, 0, sizeof *g);
    g->bounds = bbox_empty();
    int nt = geom->num_tris > 0 ? geom->num_tris : 0, ns = geom->num_spheres > 0 ? geom->num_spheres : 0;
    int nsh = geom->num_shapes > 0 ? geom->num_shapes : 0;
    AccelGeometry gm = *geom;
    gm.num_tris = nt;
    gm.num_spheres = ns;
    gm.num_shapes = nsh;
    size_t n = (size_t)nt + (size_t)ns + (size_t)nsh;
    if (n == 0) return CST_OK;
    if (n >= (size_t)INT32_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "grid: %zu primitives exceed the 32-bit id range", n);
    uint32_t *order = NULL;
    uint32_t *cell_start = NULL; /* during the build: num_cells + 1 offsets into slots */
    uint32_t *reach = NULL;      /* during the build: the brick distances of one pass */

    BBox raw = bbox_empty();
    size_t placed = 0;
    for (int i = 0; i < (int)n; i++) {
        BBox b;
        if (prim_bounds(&gm, i, &b)) { raw = bbox_union(raw, b); placed++; }
    }
    if (placed == 0) return CST_OK; /* nothing hittable: num_cells = 0, every ray misses */

    /* The grid's own copies of the primitives, in grid-local order. */
    order = malloc(n * sizeof *order);
    if (!order || !grid_order(&gm, raw, order)) goto oom;
    if (nt > 0 && !(g->tris = malloc((size_t)nt * sizeof *g->tris))) goto oom;
    if (ns > 0 && !(g->spheres = malloc((size_t)ns * sizeof *g->spheres))) goto oom;
    if (nsh > 0 && !(g->shape_ids = malloc((size_t)nsh * sizeof *g->shape_ids))) goto oom;
    g->num_tris = nt;
    g->num_spheres = ns;
    g->num_shapes = nsh;
    g->shapes = geom->shapes;
    g->shape_base = (uint32_t)(nt + ns);
    for (int j = 0; j < nsh; j++) g->shape_ids[j] = order[nt + ns + j];
    for (int i = 0; i < nt; i++) {
        const int32_t *k = &geom->tri_indices[3 * order[i]];
        Vec3 a = geom->positions[k[0]];
        g->tris[i].v0 = a;
        g->tris[i].v1 = geom->positions[k[1]];
        g->tris[i].v2 = geom->positions[k[2]];
        g->tris[i].id = order[i];
    }
    for (int j = 0; j < ns; j++) {
        const Sphere *s = &geom->spheres[order[nt + j] - (uint32_t)nt];
        g->spheres[j].center = s->center;
        g->spheres[j].radius = s->radius;
        g->spheres[j].id = order[nt + j];
    }

    /* Margin: 2^-16 of the coordinate scale (largest |coordinate| plus largest extent). */
    double ext[3] = {(double)raw.max.x - (double)raw.min.x, (double)raw.max.y - (double)raw.min.y,
                     (double)raw.max.z - (double)raw.min.z};
    double scale = fmax((double)v3_max_abs(raw.min), (double)v3_max_abs(raw.max)) + fmax(ext[0], fmax(ext[1], ext[2]));
    g->margin = (float)(GRID_MARGIN_REL * scale);
    if (!(g->margin > 0.0f)) g->margin = FLT_MIN; /* everything at the origin */
    double m = (double)g->margin;
    /* The grid box holds every primitive box grown by the margin, with another margin of
     * room so no primitive needs clamping into the outer cells. */
    double lo[3] = {(double)raw.min.x - 2.0 * m, (double)raw.min.y - 2.0 * m, (double)raw.min.z - 2.0 * m};
    double size[3] = {ext[0] + 4.0 * m, ext[1] + 4.0 * m, ext[2] + 4.0 * m};
    g->bounds.min = v3((float)lo[0], (float)lo[1], (float)lo[2]);
    g->bounds.max = v3((float)(lo[0] + size[0]), (float)(lo[1] + size[1]), (float)(lo[2] + size[2]));

    int res[3];
    grid_resolution(ext, fmin((double)GRID_CELLS_PER_PRIM * (double)placed, (double)GRID_MAX_CELLS), res);

    /* Count references per cell. Large primitives in a fine grid (a big triangle across a
     * sparse "stadium" around a dense mesh) can make this explode; past the budget, halve
     * the resolution on every axis and count again. */
    size_t budget = (size_t)GRID_REFS_PER_PRIM * placed;
    if (budget > ((size_t)1 << 31)) budget = (size_t)1 << 31;
    if (budget < (size_t)GRID_MIN_REF_BUDGET) budget = (size_t)GRID_MIN_REF_BUDGET;
    size_t refs;
    for (;;) {
        grid_set_cells(g, lo, size, res);
        free(cell_start);
        cell_start = calloc((size_t)g->num_cells + 1, sizeof *cell_start);
        if (!cell_start) goto oom;
        refs = 0;
        for (size_t i = 0; i < n && refs <= budget; i++)
            refs += grid_insert(g, &gm, (int)order[i], (uint32_t)i, cell_start, NULL);
        if (refs <= budget || (res[0] == 1 && res[1] == 1 && res[2] == 1)) break;
        for (int a = 0; a < 3; a++) res[a] = res[a] > 1 ? res[a] / 2 : 1;
    }

    /* Exclusive prefix sum: cell_start[c] = first slot of cell c. The fill pass advances
     * each cell's entry to its end, the next cell's start; then shift back by one. */
    uint32_t sum = 0;
    for (int c = 0; c < g->num_cells; c++) {
        uint32_t k = cell_start[c];
        cell_start[c] = sum;
        sum += k;
    }
    cell_start[g->num_cells] = sum;
    g->num_refs = refs;
    if (!(g->slots = malloc((refs > 0 ? refs : 1) * sizeof *g->slots))) goto oom;
    for (size_t i = 0; i < n; i++) grid_insert(g, &gm, (int)order[i], (uint32_t)i, cell_start, g->slots);
    memmove(cell_start + 1, cell_start, (size_t)g->num_cells * sizeof *cell_start);
    cell_start[0] = 0;

    /* The compact form: occupancy bits per brick, list offsets for occupied cells only. */
    int occupied = 0;
    for (int c = 0; c < g->num_cells; c++) occupied += cell_start[c + 1] > cell_start[c];
    g->cell_bits = calloc((size_t)g->num_cells / 64, sizeof *g->cell_bits);
    g->brick_info = calloc((size_t)g->num_cells / 64, sizeof *g->brick_info);
    g->list_start = malloc(((size_t)occupied + 1) * sizeof *g->list_start);
    if (!g->cell_bits || !g->brick_info || !g->list_start) goto oom;
    g->num_occupied = occupied;
    for (int c = 0, k = 0; c < g->num_cells; c++) {
        if ((c & 63) == 0) g->brick_info[c >> 6] = (uint32_t)k;
        if (cell_start[c + 1] == cell_start[c]) continue;
        g->cell_bits[c >> 6] |= (uint64_t)1 << (c & 63);
        g->list_start[k++] = cell_start[c];
    }
    g->list_start[occupied] = cell_start[g->num_cells];
    free(cell_start);
    cell_start = NULL;

    /* Each empty brick's distance to the nearest occupied one (grid.h). */
    int nb = g->num_cells / 64;
    if (!(reach = calloc(2 * (size_t)nb, sizeof *reach))) goto oom;
    grid_brick_distances(g, reach);
    free(reach);
    reach = NULL;
    free(order);
    return CST_OK;
oom:
    free(order);
    free(cell_start);
    free(reach);
    grid_free(g);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the grid over %zu primitives", n);
}

void grid_free(Grid *g)
{
    if (!g) return;
    free(g->cell_bits);
    free(g->brick_info);
    free(g->list_start);
    free(g->slots);
    free(g->tris);
    free(g->spheres);
    free(g->shape_ids);
    memset(g, 0, sizeof *g);
}

size_t grid_memory_bytes(const Grid *g)
{
    if (g->num_cells == 0) return (size_t)g->num_tris * sizeof *g->tris + (size_t)g->num_spheres * sizeof *g->spheres +
           (size_t)g->num_shapes * sizeof *g->shape_ids;
    return (size_t)g->num_cells / 64 * (sizeof *g->cell_bits + sizeof *g->brick_info) +
           ((size_t)g->num_occupied + 1) * sizeof *g->list_start +
           g->num_refs * sizeof *g->slots +
           (size_t)g->num_tris * sizeof *g->tris + (size_t)g->num_spheres * sizeof *g->spheres +
           (size_t)g->num_shapes * sizeof *g->shape_ids;
}

/* ------------------------------------------------------------------ traversal */

/* A two-level walk: a 3D-DDA over bricks (Amanatides & Woo 1987, one brick of 4 x 4 x 4
 * cells per step, or a cube of empty bricks where there is one), and in each occupied
 * brick the set of its cells that the ray passes through, computed at once rather than
 * stepped cell by cell: cell (x, y, z) is crossed iff its three slabs' t-intervals
 * overlap, and since intervals on a line that overlap pairwise have a common point
 * (Helly's theorem in one dimension), that is three pairwise tests, each a 4 x 4 table
 * (brick_cells). A cell-by-cell DDA spent most of its time in mispredicted branches on
 * which axis to step (docs/benchmarks.md).
 *
 * In double: the ray crosses boundary plane k of axis a (at org + k * cell_size) at
 * t = t_base[a] + k * t_cell[a]. An axis the ray does not move along has t_base = inf and
 * t_cell = 0, so its crossings are all inf. The walk ends at t_end: the ray's exit from
 * the grid box, or its t_max, or the closest hit so far (a hit no farther than the
 * current brick's exit is final: see the top of the file). */
typedef struct GridWalk {
    double t_base[3], t_cell[3];
    double tb[3];  /* where the ray leaves the current brick on each axis */
    double t_lo;   /* where the ray enters the grid, or its t_min inside it */
    double t_end;
    int b[3];      /* brick coordinates */
    int step[3];   /* -1, 0 or +1 */
    int up[3];     /* 1 if step is +1: the exit plane of cell i is i + up */
    int brick;     /* brick number */
    unsigned flip; /* the bits of a cell's number to complement to count in the ray's direction */
    double o[3], d[3];
    int fixed[3];  /* on an axis the ray does not move along: its cell's place in the brick */
    int brick_step[3]; /* the change of the brick number for one step along each axis */
} GridWalk;

/* Where the ray leaves brick b along axis a: the exit plane of its last cell in the ray's
 * direction, (b + up) * 4. */
static inline double brick_exit(const GridWalk *w, int a, int b)
{
    return w->t_base[a] + (double)((b + w->up[a]) * (1 << BRICK_SHIFT)) * w->t_cell[a]; /* b < 0 past the grid */
}

/* Clips the ray to the grid box and finds its first brick. A zero direction component
 * (either sign) constrains nothing when the origin lies in the slab, boundary included,
 * and never steps; an origin inside the box starts at t_min. False if the ray misses. */
static inline bool walk_begin(const Grid *g, const Ray *r, GridWalk *w)
{
    double t0 = (double)r->t_min, t1 = (double)r->t_max;
    double o[3] = {(double)r->o.x, (double)r->o.y, (double)r->o.z}, d[3] = {(double)r->d.x, (double)r->d.y, (double)r->d.z},
           inv[3];
    for (int a = 0; a < 3; a++) {
        double lo = g->org[a], hi = g->org[a] + (double)g->res[a] * g->cell_size[a];
        if (d[a] > 0.0 || d[a] < 0.0) {
            inv[a] = 1.0 / d[a];
            double ta = (lo - o[a]) * inv[a], tb = (hi - o[a]) * inv[a];
            if (ta > tb) { double t = ta; ta = tb; tb = t; }
            if (ta > t0) t0 = ta;
            if (tb < t1) t1 = tb;
        } else { /* zero or NaN */
            if (o[a] < lo || o[a] > hi) return false;
            inv[a] = 0.0;
        }
    }
    if (!(t0 <= t1)) return false; /* also NaN */
    /* Finite, so an axis that never steps (t_next = inf) is never stepped. */
    w->t_end = t1 < DBL_MAX ? t1 : DBL_MAX;
    w->t_lo = t0;
    for (int a = 0; a < 3; a++) { w->o[a] = o[a]; w->d[a] = d[a]; }
    for (int a = 0; a < 3; a++) {
        bool moves = inv[a] != 0.0;
        w->step[a] = moves ? (d[a] > 0.0 ? 1 : -1) : 0;
        w->up[a] = d[a] > 0.0;
        w->t_base[a] = moves ? (g->org[a] - o[a]) * inv[a] : HUGE_VAL;
        w->t_cell[a] = g->cell_size[a] * inv[a];
        double p = moves ? o[a] + t0 * d[a] : o[a];
        double f = (p - g->org[a]) * g->inv_cell_size[a];
        int i = !(f >= 0.0) ? 0 : (f >= (double)g->res[a] ? g->res[a] - 1 : (int)f);
        w->b[a] = i >> BRICK_SHIFT;
        w->tb[a] = brick_exit(w, a, w->b[a]); /* inf on an axis without steps */
        w->fixed[a] = i & ((1 << BRICK_SHIFT) - 1);
    }
    w->brick = grid_brick_index(g, w->b[0], w->b[1], w->b[2]);
    w->brick_step[0] = w->step[0];
    w->brick_step[1] = w->step[1] * g->brick_res[0];
    w->brick_step[2] = w->step[2] * g->brick_res[0] * g->brick_res[1];
    w->flip = (d[0] < 0.0 ? 3u : 0u) | (d[1] < 0.0 ? 12u : 0u) | (d[2] < 0.0 ? 48u : 0u);
    return true;
}

/* The crossings of planes k, k + 1, k + 2, k + 3 of axis a, computed as in brick_exit
 * and rounded to float. Rounding is monotonic, so it can merge an interval's end with
 * the next one's start but never order two crossings the other way: the overlap tests
 * below can only gain cells from it, never lose one. */
static inline __m128 plane_t4(const GridWalk *w, int a, int k)
{
#if defined(__AVX__)
    __m256d kd = _mm256_add_pd(_mm256_set1_pd((double)k), _mm256_setr_pd(0.0, 1.0, 2.0, 3.0));
    __m256d t = _mm256_add_pd(_mm256_set1_pd(w->t_base[a]), _mm256_mul_pd(kd, _mm256_set1_pd(w->t_cell[a])));
    return _mm256_cvtpd_ps(t);
#else
    const __m128d base = _mm_set1_pd(w->t_base[a]), cell = _mm_set1_pd(w->t_cell[a]), kk = _mm_set1_pd((double)k);
    __m128d lo = _mm_add_pd(base, _mm_mul_pd(_mm_add_pd(kk, _mm_setr_pd(0.0, 1.0)), cell));
    __m128d hi = _mm_add_pd(base, _mm_mul_pd(_mm_add_pd(kk, _mm_setr_pd(2.0, 3.0)), cell));
    return _mm_movelh_ps(_mm_cvtpd_ps(lo), _mm_cvtpd_ps(hi));
#endif
}

/* The t-intervals [lo, hi] of the current brick's four slabs along axis a, in cell
 * order, limited to [t_lo, t_end]: a slab the ray crosses outside it is NaN. */
static inline void brick_slabs(const GridWalk *w, int a, __m128 t_lo, __m128 t_hi, __m128 *lo, __m128 *hi)
{
    const __m128 nan = _mm_set1_ps(NAN);
    if (!w->step[a]) {
        /* Its one slab spans all t, the other three none (NaN fails every comparison). */
        __m128 here = _mm_cmpeq_ps(_mm_setr_ps(0.0f, 1.0f, 2.0f, 3.0f), _mm_set1_ps((float)w->fixed[a]));
        *lo = _mm_or_ps(_mm_and_ps(here, _mm_set1_ps(-INFINITY)), _mm_andnot_ps(here, nan));
        *hi = _mm_or_ps(_mm_and_ps(here, _mm_set1_ps(INFINITY)), _mm_andnot_ps(here, nan));
        return;
    }
    /* Cell i of the brick is entered at plane i + 1 - up and left at plane i + up. */
    int k = w->b[a] << BRICK_SHIFT;
    __m128 l = plane_t4(w, a, k + 1 - w->up[a]), h = plane_t4(w, a, k + w->up[a]);
    __m128 in = _mm_and_ps(_mm_cmpge_ps(h, t_lo), _mm_cmple_ps(l, t_hi));
    *lo = _mm_or_ps(_mm_and_ps(in, l), _mm_andnot_ps(in, nan));
    *hi = _mm_or_ps(_mm_and_ps(in, h), _mm_andnot_ps(in, nan));
}

/* Bit i + 4 j: slab i of one axis and slab j of another overlap. With AVX-512 the 16
 * pairs are one compare each way, slab i repeated along the lanes and slab j spread. */
#if defined(__AVX512F__) && defined(__AVX512VL__)
static inline __m512 slabs_i(__m128 v)
{
    const __m512i i = _mm512_setr_epi32(0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3, 0, 1, 2, 3);
    return _mm512_permutexvar_ps(i, _mm512_castps128_ps512(v));
}
static inline __m512 slabs_j(__m128 v)
{
    const __m512i j = _mm512_setr_epi32(0, 0, 0, 0, 1, 1, 1, 1, 2, 2, 2, 2, 3, 3, 3, 3);
    return _mm512_permutexvar_ps(j, _mm512_castps128_ps512(v));
}
static inline unsigned slab_pairs(__m128 lo_i, __m128 hi_i, __m128 lo_j, __m128 hi_j)
{
    __mmask16 m = _mm512_cmp_ps_mask(slabs_i(lo_i), slabs_j(hi_j), _CMP_LE_OQ);
    return _mm512_mask_cmp_ps_mask(m, slabs_j(lo_j), slabs_i(hi_i), _CMP_LE_OQ);
}
#else
static inline unsigned slab_pairs(__m128 lo_i, __m128 hi_i, __m128 lo_j, __m128 hi_j)
{
#define SLAB_PAIR(j)                                                                                 \
    ((unsigned)_mm_movemask_ps(_mm_and_ps(_mm_cmple_ps(lo_i, _mm_shuffle_ps(hi_j, hi_j, (j) * 0x55)), \
                                          _mm_cmple_ps(_mm_shuffle_ps(lo_j, lo_j, (j) * 0x55), hi_i))) \
     << (4 * (j)))
    return SLAB_PAIR(0) | SLAB_PAIR(1) | SLAB_PAIR(2) | SLAB_PAIR(3);
#undef SLAB_PAIR
}
#endif

/* Bit k of m to bit 4 k (16 bits); and nibble k of m to bits 16 k .. 16 k + 3. */
static inline uint64_t spread_bits16(unsigned m)
{
    uint64_t x = m;
    x = (x | x << 24) & 0x000000ff000000ffu;
    x = (x | x << 12) & 0x000f000f000f000fu;
    x = (x | x << 6) & 0x0303030303030303u;
    return (x | x << 3) & 0x1111111111111111u;
}
static inline uint64_t spread_nibbles16(unsigned m)
{
    uint64_t x = m;
    x = (x | x << 24) & 0x000000ff000000ffu;
    return (x | x << 12) & 0x000f000f000f000fu;
}

/* The cells of the current brick that the ray crosses within [t_lo, t_end], as bits of
 * the brick's occupancy word (cell x + 4 y + 16 z). Exact up to the float rounding of
 * plane_t4, which only adds cells: a superset of the cells a cell-by-cell DDA visits. */
static inline uint64_t brick_cells_exits(const GridWalk *w, float exits[3][4])
{
    const __m128 t_lo = _mm_set1_ps((float)w->t_lo), t_hi = _mm_set1_ps((float)w->t_end);
    __m128 lo[3], hi[3];
    for (int a = 0; a < 3; a++) brick_slabs(w, a, t_lo, t_hi, &lo[a], &hi[a]);
    if (exits)
        for (int a = 0; a < 3; a++) _mm_storeu_ps(exits[a], hi[a]);
    unsigned xy = slab_pairs(lo[0], hi[0], lo[1], hi[1]); /* bit x + 4 y */
    unsigned xz = slab_pairs(lo[0], hi[0], lo[2], hi[2]); /* bit x + 4 z */
    unsigned yz = slab_pairs(lo[1], hi[1], lo[2], hi[2]); /* bit y + 4 z */
    return (xy * 0x0001000100010001u) & (spread_nibbles16(xz) * 0x1111u) & (spread_bits16(yz) * 0xfu);
}
static inline uint64_t brick_cells(const GridWalk *w) { return brick_cells_exits(w, NULL); }

/* Renumbers a brick's cell bits from c to c ^ flip (w.flip): a cell's number then grows
 * with x, y and z in the ray's direction, and as the ray meets the z layers of the brick
 * in order, the y rows of a layer in order and the cells of a row in order, increasing
 * renumbered bits are the cells in the order the ray crosses them. */
static inline uint64_t flip_cells(uint64_t m, unsigned flip)
{
    if (flip & 3u) {
        m = ((m >> 1) & 0x5555555555555555u) | ((m & 0x5555555555555555u) << 1);
        m = ((m >> 2) & 0x3333333333333333u) | ((m & 0x3333333333333333u) << 2);
    }
    if (flip & 12u) {
        m = ((m >> 4) & 0x0f0f0f0f0f0f0f0fu) | ((m & 0x0f0f0f0f0f0f0f0fu) << 4);
        m = ((m >> 8) & 0x00ff00ff00ff00ffu) | ((m & 0x00ff00ff00ff00ffu) << 8);
    }
    if (flip & 48u) {
        m = ((m >> 16) & 0x0000ffff0000ffffu) | ((m & 0x0000ffff0000ffffu) << 16);
        m = (m >> 32) | (m << 32);
    }
    return m;
}

/* The next brick along the ray: one step of the brick DDA from an occupied brick or an
 * empty one next to one; from an empty brick at distance D > 1 from the occupied ones,
 * the brick where the ray leaves the cube of bricks within D - 1 of it, all empty
 * (grid.h). The exit axis moves one brick past the cube; the others go to the brick
 * holding the ray's point there, kept within the cube: rounding can put the point in a
 * neighbour of the right brick only when it lies within ~1e-16 of their common face,
 * where the build margin covers the difference (the top of the file). `bits` is the
 * current brick's occupancy. False once the ray has left the grid or passed t_end. */
static inline bool walk_next_brick(const Grid *g, GridWalk *w, uint64_t bits)
{
    uint32_t dist = bits ? 1u : g->brick_info[w->brick];
    if (dist <= 1u) {
        /* The axis of the nearest exit without a branch on the axes' order, which is
         * irregular (ties go to the lower axis), and the brick number by one add: bunny,
         * every ray set 5% faster (docs/benchmarks.md). */
        const int e01 = w->tb[1] < w->tb[0];
        const double m01 = e01 ? w->tb[1] : w->tb[0];
        const int e = w->tb[2] < m01 ? 2 : e01;
        const double te = w->tb[2] < m01 ? w->tb[2] : m01;
        if (!(te < w->t_end)) return false;
        int i = w->b[e] + w->step[e];
        if ((unsigned)i >= (unsigned)g->brick_res[e]) return false;
        w->b[e] = i;
        w->tb[e] = brick_exit(w, e, i);
        w->brick += w->brick_step[e];
        return true;
    }
    /* A jump over a cube of empty bricks: the exit of its last brick on each axis. */
    const int r = (int)dist - 1;
    int last[3], e = 0;
    double t_exit = HUGE_VAL;
    for (int a = 0; a < 3; a++) {
        last[a] = w->b[a] + w->step[a] * r;
        double t = brick_exit(w, a, last[a]); /* inf on an axis without steps */
        if (t < t_exit) { t_exit = t; e = a; }
    }
    if (!(t_exit < w->t_end)) return false;
    int i = last[e] + w->step[e];
    if ((unsigned)i >= (unsigned)g->brick_res[e]) return false;
    for (int a = 0; a < 3; a++) {
        if (a == e || !w->step[a]) continue;
        double f = (w->o[a] + t_exit * w->d[a] - g->org[a]) * g->inv_cell_size[a];
        int k = f >= 0.0 ? (f < (double)g->res[a] ? (int)f : g->res[a] - 1) >> BRICK_SHIFT : 0;
        int lo = w->step[a] > 0 ? w->b[a] : last[a], hi = w->step[a] > 0 ? last[a] : w->b[a];
        k = k < lo ? lo : (k > hi ? hi : k);
        w->b[a] = k;
        w->tb[a] = brick_exit(w, a, k);
    }
    w->b[e] = i;
    w->tb[e] = brick_exit(w, e, i);
    w->brick = grid_brick_index(g, w->b[0], w->b[1], w->b[2]);
    return true;
}

/* The slots of occupied cell `local` of a brick with occupancy `bits`: [*begin, *end). */
static inline void cell_list_in(const Grid *g, int brick, uint64_t bits, int local, uint32_t *begin, uint32_t *end)
{
    uint64_t before = bits & (((uint64_t)1 << local) - 1u);
    uint32_t k = g->brick_info[brick] + (uint32_t)__builtin_popcountll(before);
    *begin = g->list_start[k];
    *end = g->list_start[k + 1];
}

/* Hashed mailboxing (after Benthin, "Realtime Ray Tracing on Current CPU Architectures",
 * PhD thesis, 2006): the primitives this ray has tested, in a small direct-mapped table
 * on the stack. Nothing is written to the shared grid, so any number of threads can
 * traverse it, with no per-thread ray ids. A primitive evicted by a colliding index is
 * simply tested again, which gives the same result (same ray, t_max no larger): a miss
 * in the mailbox costs time, never a wrong answer. */
typedef struct Mailbox {
    uint32_t slot[GRID_MAILBOX];
} Mailbox;

static inline void mailbox_clear(Mailbox *mb) { memset(mb->slot, 0xff, sizeof mb->slot); }

/* True if the primitive was already tested; otherwise records it. */
static inline bool mailbox_seen(Mailbox *mb, uint32_t slot)
{
    uint32_t *e = &mb->slot[slot & (GRID_MAILBOX - 1)];
    if (*e == slot) return true;
    *e = slot;
    return false;
}

/* Collects the next (up to) TRI_BLOCK_WIDTH triangles of slots[*k .. end) that the ray
 * has not tested yet, in list order; stops at the first sphere (spheres follow the
 * triangles: their grid-local indices are larger). Returns how many. */
static inline int cell_next_tris(const Grid *g, uint32_t *k, uint32_t end, Mailbox *mb,
                                 const GridTri *tri[TRI_BLOCK_WIDTH])
{
    int n = 0;
    uint32_t num_tris = (uint32_t)g->num_tris;
    for (; *k < end && n < TRI_BLOCK_WIDTH; (*k)++) {
        uint32_t slot = g->slots[*k];
        if (slot >= num_tris) break;
        if (mailbox_seen(mb, slot)) continue;
        GRID_COUNT_PRIM_TEST(slot);
        tri[n++] = &g->tris[slot];
    }
    for (int i = n; i < TRI_BLOCK_WIDTH; i++) tri[i] = &TRI_VERTS_NAN;
    return n;
}

/* The closest hit among a cell's untested primitives, in list order with a strict <, as
 * a scalar loop would pick among equal t; shortens r->t_max on a hit. */
static inline bool cell_intersect(const Grid *g, uint32_t k, uint32_t end, Mailbox *mb, const TriangleRayBlock *q,
                                  Ray *r, Hit *hit)
{
    bool found = false;
    const TriLanes t_min = lanes_set1(r->t_min);
    const GridTri *tri[TRI_BLOCK_WIDTH];
    int n;
    while ((n = cell_next_tris(g, &k, end, mb, tri)) > 0) {
        TriLanes tl, ul, vl;
        int scalar_lanes;
        int mask = tri_batch_intersect(tri, n, q, t_min, lanes_set1(r->t_max), &tl, &ul, &vl, &scalar_lanes);
        if (!((mask | scalar_lanes) & ((1 << n) - 1))) continue;
        float t[TRI_BLOCK_WIDTH], u[TRI_BLOCK_WIDTH], v[TRI_BLOCK_WIDTH];
        lanes_store(t, tl); lanes_store(u, ul); lanes_store(v, vl);
        for (int i = 0; i < n; i++) {
            if (scalar_lanes & (1 << i)) {
                float ts, us, vs;
                if (triangle_intersect_watertight(&q->tr, r, tri[i]->v0, tri[i]->v1, tri[i]->v2, &ts, &us, &vs)) {
                    r->t_max = ts;
                    hit->t = ts; hit->u = us; hit->v = vs; hit->prim = tri[i]->id;
                    found = true;
                }
            } else if ((mask & (1 << i)) && t[i] < r->t_max) {
                r->t_max = t[i];
                hit->t = t[i]; hit->u = u[i]; hit->v = v[i]; hit->prim = tri[i]->id;
                found = true;
            }
        }
    }
    for (; k < end; k++) {
        uint32_t slot = g->slots[k];
        if (slot < (uint32_t)g->num_tris || mailbox_seen(mb, slot)) continue;
        GRID_COUNT_PRIM_TEST(slot);
        if (slot >= g->shape_base) {
            found |= shape_leaf_intersect(g->shapes, g->shape_base, &g->shape_ids[slot - g->shape_base], 1u, r, hit);
            continue;
        }
        const GridSphere *sp = &g->spheres[slot - (uint32_t)g->num_tris];
        float t;
        if (sphere_intersect(sp->center, sp->radius, r, &t)) {
            r->t_max = t;
            hit->t = t; hit->u = 0.0f; hit->v = 0.0f; hit->prim = sp->id;
            found = true;
        }
    }
    return found;
}

static inline bool cell_occluded(const Grid *g, uint32_t k, uint32_t end, Mailbox *mb, const TriangleRayBlock *q,
                                 const Ray *r)
{
    const TriLanes t_min = lanes_set1(r->t_min), t_max = lanes_set1(r->t_max);
    const GridTri *tri[TRI_BLOCK_WIDTH];
    int n;
    while ((n = cell_next_tris(g, &k, end, mb, tri)) > 0) {
        TriLanes tl, ul, vl;
        int scalar_lanes;
        if (tri_batch_intersect(tri, n, q, t_min, t_max, &tl, &ul, &vl, &scalar_lanes) & ((1 << n) - 1)) return true;
        for (int i = 0; i < n; i++) {
            float ts, us, vs;
            if ((scalar_lanes & (1 << i)) &&
                triangle_intersect_watertight(&q->tr, r, tri[i]->v0, tri[i]->v1, tri[i]->v2, &ts, &us, &vs))
                return true;
        }
    }
    for (; k < end; k++) {
        uint32_t slot = g->slots[k];
        if (slot < (uint32_t)g->num_tris || mailbox_seen(mb, slot)) continue;
        GRID_COUNT_PRIM_TEST(slot);
        if (slot >= g->shape_base) {
            if (shape_leaf_occluded(g->shapes, g->shape_base, &g->shape_ids[slot - g->shape_base], 1u, r)) return true;
            continue;
        }
        const GridSphere *sp = &g->spheres[slot - (uint32_t)g->num_tris];
        float t;
        if (sphere_intersect(sp->center, sp->radius, r, &t)) return true;
    }
    return false;
}

bool grid_intersect(const Grid *g, const Ray *ray, Hit *hit)
{
    GridWalk w;
    if (g->num_cells == 0 || !walk_begin(g, ray, &w)) return false;
    Ray r = *ray;
    TriangleRayBlock q = triangle_block_ray_setup(&r);
    Mailbox mb;
    mailbox_clear(&mb);
    bool found = false;
    for (;;) {
        uint64_t bits = g->cell_bits[w.brick];
        /* In the order the ray crosses them (flip_cells), so a hit no farther than the
         * exit of the cell being tested is final, as in a cell-by-cell walk: the cells
         * after it are entered where it is left. Exits are the slabs' float-rounded
         * exits, which can exceed the exact ones by an ulp of t, far less than the build
         * margin. */
        float exits[3][4];
        uint64_t m = bits ? flip_cells(brick_cells_exits(&w, exits) & bits, w.flip) : 0u;
        while (m) {
            int local = __builtin_ctzll(m) ^ (int)w.flip;
            m &= m - 1u;
            uint32_t begin, end;
            cell_list_in(g, w.brick, bits, local, &begin, &end);
            if (cell_intersect(g, begin, end, &mb, &q, &r, hit)) {
                found = true;
                float exit = fminf(fminf(exits[0][local & 3], exits[1][(local >> 2) & 3]), exits[2][local >> 4]);
                if (r.t_max <= exit) return true;
                if ((double)r.t_max < w.t_end) w.t_end = (double)r.t_max;
            }
        }
        if (!walk_next_brick(g, &w, bits)) return found;
    }
}

bool grid_occluded(const Grid *g, const Ray *r)
{
    GridWalk w;
    if (g->num_cells == 0 || !walk_begin(g, r, &w)) return false;
    TriangleRayBlock q = triangle_block_ray_setup(r);
    Mailbox mb;
    mailbox_clear(&mb);
    for (;;) {
        uint64_t bits = g->cell_bits[w.brick];
        for (uint64_t m = bits ? brick_cells(&w) & bits : 0u; m; m &= m - 1u) {
            uint32_t begin, end;
            cell_list_in(g, w.brick, bits, __builtin_ctzll(m), &begin, &end);
            if (cell_occluded(g, begin, end, &mb, &q, r)) return true;
        }
        if (!walk_next_brick(g, &w, bits)) return false;
    }
}
