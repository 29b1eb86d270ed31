/* Uniform grid: resolution heuristic, exact primitive-cell overlap, compressed cell lists
 * (build) and 3D-DDA traversal with empty-brick skipping and hashed mailboxing (closest
 * hit, occlusion).
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
 * brick jumps can skip a region a primitive occupies. What the grid does not promise are
 * hits that Moller-Trumbore itself puts farther than `margin` off their triangle (rays
 * grazing a sliver's plane, where t is ill-conditioned): such a hit may be skipped, as
 * the BVH may skip hits off a node box. */
#include "accel/grid.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

enum {
    GRID_CELLS_PER_PRIM = 27,  /* #cells ~ 27 N: 3 cells per primitive along each axis */
    GRID_MAX_CELLS = 1 << 26,  /* 256 MB of cell offsets; reached only from N ~ 2.5M */
    GRID_MAX_AXIS = 1 << 16,   /* finer cells would be thinner than the margin */
    GRID_MIN_REF_BUDGET = 1 << 22,
    GRID_REFS_PER_PRIM = 64,   /* beyond max(4M, 64 N) references, coarsen the grid */
    /* Per-ray mailbox slots (a power of two). Direct-mapped on the low bits of the
     * grid-local index: those follow the Morton order, so neighbours rarely collide. */
    GRID_MAILBOX = 32
};
#define GRID_MARGIN_REL 0x1p-16

/* Test hook: tests/unit/test_grid.c compiles a private copy of this file with this macro
 * counting primitive tests per ray, to check the mailbox. Nothing in the library. */
#ifndef GRID_COUNT_PRIM_TEST
#define GRID_COUNT_PRIM_TEST(slot) ((void)0)
#endif

static inline double min3d(double a, double b, double c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
static inline double max3d(double a, double b, double c) { return a > b ? (a > c ? a : c) : (b > c ? b : c); }

/* The part of the number of cell (x, y, z) in the brick layout of grid.h contributed by
 * coordinate i on axis a; the cell number is the sum over the axes. */
static int grid_axis_cell(const Grid *g, int a, int i)
{
    const int *sh = g->brick_shift;
    int brick_stride = a == 0 ? 1 : (a == 1 ? g->brick_res[0] : g->brick_res[0] * g->brick_res[1]);
    int local_shift = a == 0 ? 0 : (a == 1 ? sh[0] : sh[0] + sh[1]);
    return ((i >> sh[a]) * brick_stride << 6) + ((i & ((1 << sh[a]) - 1)) << local_shift);
}

/* The number of cell (x, y, z). */
static inline int grid_cell_index(const Grid *g, int x, int y, int z)
{
    const int32_t *t = g->axis_cells;
    return t[x] + t[g->res[0] + y] + t[g->res[0] + g->res[1] + z];
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
    double bmin[3] = {box.min.x, box.min.y, box.min.z}, bmax[3] = {box.max.x, box.max.y, box.max.z};
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
    if (is_tri) {
        for (int i = 0; i < 3; i++) {
            Vec3 p = geom->positions[geom->tri_indices[3 * id + i]];
            tv[i][0] = p.x; tv[i][1] = p.y; tv[i][2] = p.z;
        }
    } else {
        const Sphere *s = &geom->spheres[id - geom->num_tris];
        sc[0] = s->center.x; sc[1] = s->center.y; sc[2] = s->center.z;
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

/* Splits 64 = 2^6 units over the axes: each bit goes to the axis with the most units
 * left, so the shape follows the proportions of n and a flat axis gets none. */
static void grid_split64(const int n[3], int shift[3])
{
    shift[0] = shift[1] = shift[2] = 0;
    for (int bit = 0; bit < 6; bit++) {
        int best = 0;
        for (int a = 1; a < 3; a++)
            if ((n[a] >> shift[a]) > (n[best] >> shift[best])) best = a;
        shift[best]++;
    }
}

/* Sets the cell geometry for resolution res over the grid box [lo, lo + size] and the
 * brick and superbrick shapes (grid.h). */
static void grid_set_cells(Grid *g, const double lo[3], const double size[3], const int res[3])
{
    for (int a = 0; a < 3; a++) {
        g->res[a] = res[a];
        g->org[a] = lo[a];
        g->cell_size[a] = size[a] / (double)res[a];
        g->inv_cell_size[a] = (double)res[a] / size[a];
    }
    grid_split64(res, g->brick_shift);
    for (int a = 0; a < 3; a++) g->brick_res[a] = ((res[a] - 1) >> g->brick_shift[a]) + 1;
    grid_split64(g->brick_res, g->super_shift);
    for (int a = 0; a < 3; a++) g->super_res[a] = ((g->brick_res[a] - 1) >> g->super_shift[a]) + 1;
    g->num_cells = 64 * g->brick_res[0] * g->brick_res[1] * g->brick_res[2];
    for (int a = 0, k = 0; a < 3; a++)
        for (int i = 0; i < res[a]; i++) g->axis_cells[k++] = grid_axis_cell(g, a, i);
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
    size_t n = (size_t)geom->num_tris + (size_t)geom->num_spheres;
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
        uint64_t sphere = i >= (size_t)geom->num_tris;
        key[i] = (sphere << 62) | (code << 32) | (uint64_t)i;
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
    AccelGeometry gm = *geom;
    gm.num_tris = nt;
    gm.num_spheres = ns;
    size_t n = (size_t)nt + (size_t)ns;
    if (n == 0) return CST_OK;
    if (n >= (size_t)INT32_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "grid: %zu primitives exceed the 32-bit id range", n);
    uint32_t *order = NULL;

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
    g->num_tris = nt;
    g->num_spheres = ns;
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
        free(g->axis_cells);
        if (!(g->axis_cells = malloc((size_t)(res[0] + res[1] + res[2]) * sizeof *g->axis_cells))) goto oom;
        grid_set_cells(g, lo, size, res);
        free(g->cell_start);
        g->cell_start = calloc((size_t)g->num_cells + 1, sizeof *g->cell_start);
        if (!g->cell_start) goto oom;
        refs = 0;
        for (size_t i = 0; i < n && refs <= budget; i++)
            refs += grid_insert(g, &gm, (int)order[i], (uint32_t)i, g->cell_start, NULL);
        if (refs <= budget || (res[0] == 1 && res[1] == 1 && res[2] == 1)) break;
        for (int a = 0; a < 3; a++) res[a] = res[a] > 1 ? res[a] / 2 : 1;
    }

    /* Exclusive prefix sum: cell_start[c] = first slot of cell c. The fill pass advances
     * each cell's entry to its end, the next cell's start; then shift back by one. */
    uint32_t sum = 0;
    for (int c = 0; c < g->num_cells; c++) {
        uint32_t k = g->cell_start[c];
        g->cell_start[c] = sum;
        sum += k;
    }
    g->cell_start[g->num_cells] = sum;
    g->num_refs = refs;
    if (!(g->slots = malloc((refs > 0 ? refs : 1) * sizeof *g->slots))) goto oom;
    for (size_t i = 0; i < n; i++) grid_insert(g, &gm, (int)order[i], (uint32_t)i, g->cell_start, g->slots);
    memmove(g->cell_start + 1, g->cell_start, (size_t)g->num_cells * sizeof *g->cell_start);
    g->cell_start[0] = 0;

    size_t num_super = (size_t)g->super_res[0] * (size_t)g->super_res[1] * (size_t)g->super_res[2];
    g->cell_bits = calloc((size_t)g->num_cells / 64, sizeof *g->cell_bits);
    g->super_bits = calloc(num_super, sizeof *g->super_bits);
    if (!g->cell_bits || !g->super_bits) goto oom;
    for (int c = 0; c < g->num_cells; c++)
        if (g->cell_start[c + 1] > g->cell_start[c]) g->cell_bits[c >> 6] |= (uint64_t)1 << (c & 63);
    for (int bz = 0, b = 0; bz < g->brick_res[2]; bz++)
        for (int by = 0; by < g->brick_res[1]; by++)
            for (int bx = 0; bx < g->brick_res[0]; bx++, b++) {
                if (!g->cell_bits[b]) continue;
                const int *ss = g->super_shift;
                int sb = (bx >> ss[0]) + g->super_res[0] * ((by >> ss[1]) + g->super_res[1] * (bz >> ss[2]));
                int local = (bx & ((1 << ss[0]) - 1)) | ((by & ((1 << ss[1]) - 1)) << ss[0]) |
                            ((bz & ((1 << ss[2]) - 1)) << (ss[0] + ss[1]));
                g->super_bits[sb] |= (uint64_t)1 << local;
            }
    free(order);
    return CST_OK;
oom:
    free(order);
    grid_free(g);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the grid over %zu primitives", n);
}

void grid_free(Grid *g)
{
    if (!g) return;
    free(g->cell_start);
    free(g->slots);
    free(g->cell_bits);
    free(g->super_bits);
    free(g->axis_cells);
    free(g->tris);
    free(g->spheres);
    memset(g, 0, sizeof *g);
}

size_t grid_memory_bytes(const Grid *g)
{
    if (g->num_cells == 0) return (size_t)g->num_tris * sizeof *g->tris + (size_t)g->num_spheres * sizeof *g->spheres;
    return ((size_t)g->num_cells + 1) * sizeof *g->cell_start + g->num_refs * sizeof *g->slots +
           (size_t)g->num_cells / 64 * sizeof *g->cell_bits +
           (size_t)g->super_res[0] * (size_t)g->super_res[1] * (size_t)g->super_res[2] * sizeof *g->super_bits +
           (size_t)(g->res[0] + g->res[1] + g->res[2]) * sizeof *g->axis_cells +
           (size_t)g->num_tris * sizeof *g->tris + (size_t)g->num_spheres * sizeof *g->spheres;
}

/* ------------------------------------------------------------------ traversal */

/* 3D-DDA state (Amanatides & Woo 1987), in double. The ray crosses boundary plane k of
 * axis a (at org + k * cell_size) at t = t_base[a] + k * t_cell[a]; t_next[a] is the
 * crossing that leaves the current cell on axis a. An axis the ray does not move along
 * has t_base = inf and t_cell = 0, so its crossings are all inf. The walk ends at t_end:
 * the ray's exit from the grid box, or its t_max, or the closest hit so far (a hit no
 * farther than the current cell's exit is final: see the top of the file). */
typedef struct GridWalk {
    double t_next[3], t_base[3], t_cell[3];
    double t_end;
    int idx[3];  /* cell coordinates */
    int step[3]; /* -1, 0 or +1 */
    int up[3];   /* 1 if step is +1: the exit plane of cell i is i + up */
    const int32_t *axis_cells[3]; /* the grid's per-axis cell number parts */
    int part[3]; /* axis_cells[a][idx[a]] */
    int cell;    /* cell number (grid.h): the sum of the parts */
} GridWalk;

/* Where the ray leaves cell i along axis a. */
static inline double walk_crossing(const GridWalk *w, int a, int i)
{
    return w->t_base[a] + (double)(i + w->up[a]) * w->t_cell[a];
}

/* Moves to coordinate i on axis a and updates the cell number. */
static inline void walk_set(GridWalk *w, int a, int i)
{
    w->idx[a] = i;
    w->t_next[a] = walk_crossing(w, a, i);
    w->cell += w->axis_cells[a][i] - w->part[a];
    w->part[a] = w->axis_cells[a][i];
}

/* Clips the ray to the grid box and finds its first cell. A zero direction component
 * (either sign) constrains nothing when the origin lies in the slab, boundary included,
 * and never steps; an origin inside the box starts at t_min. False if the ray misses. */
static inline bool walk_begin(const Grid *g, const Ray *r, GridWalk *w)
{
    double t0 = (double)r->t_min, t1 = (double)r->t_max;
    double o[3] = {r->o.x, r->o.y, r->o.z}, d[3] = {r->d.x, r->d.y, r->d.z}, inv[3];
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
    w->axis_cells[0] = g->axis_cells;
    w->axis_cells[1] = g->axis_cells + g->res[0];
    w->axis_cells[2] = g->axis_cells + g->res[0] + g->res[1];
    w->cell = 0;
    for (int a = 0; a < 3; a++) {
        bool moves = inv[a] != 0.0;
        w->step[a] = moves ? (d[a] > 0.0 ? 1 : -1) : 0;
        w->up[a] = d[a] > 0.0;
        w->t_base[a] = moves ? (g->org[a] - o[a]) * inv[a] : HUGE_VAL;
        w->t_cell[a] = g->cell_size[a] * inv[a];
        double p = moves ? o[a] + t0 * d[a] : o[a];
        double f = (p - g->org[a]) * g->inv_cell_size[a];
        int i = !(f >= 0.0) ? 0 : (f >= (double)g->res[a] ? g->res[a] - 1 : (int)f);
        w->part[a] = 0;
        walk_set(w, a, i);
    }
    return true;
}

/* One DDA step into the next cell; false once the ray has left the grid or passed
 * t_end. */
static inline bool walk_step(const Grid *g, GridWalk *w)
{
    const double *t = w->t_next;
    int a = t[0] < t[1] ? (t[0] < t[2] ? 0 : 2) : (t[1] < t[2] ? 1 : 2);
    if (!(t[a] < w->t_end)) return false;
    int i = w->idx[a] + w->step[a];
    if ((unsigned)i >= (unsigned)g->res[a]) return false;
    walk_set(w, a, i);
    return true;
}

static inline bool cell_occupied(const Grid *g, int cell)
{
    return (g->cell_bits[cell >> 6] >> (cell & 63)) & 1u;
}

static inline bool brick_occupied(const Grid *g, int cell) { return g->cell_bits[cell >> 6] != 0u; }

static inline bool super_occupied(const Grid *g, const GridWalk *w)
{
    const int *bs = g->brick_shift, *ss = g->super_shift;
    int sb = (w->idx[0] >> (bs[0] + ss[0])) +
             g->super_res[0] * ((w->idx[1] >> (bs[1] + ss[1])) + g->super_res[1] * (w->idx[2] >> (bs[2] + ss[2])));
    return g->super_bits[sb] != 0u;
}

/* Jumps over the empty block (brick or superbrick: 2^shift[a] cells along axis a)
 * holding the current cell, to the cell where the ray leaves it: the exit axis moves
 * into the neighbouring block; each other axis advances, within the block, past the
 * crossings before the exit. False once the ray has left the grid or passed t_end. */
static inline bool walk_skip(const Grid *g, GridWalk *w, int shift0, int shift1, int shift2)
{
    double t_exit = INFINITY;
    int exit_axis = 0;
    int mask[3] = {(1 << shift0) - 1, (1 << shift1) - 1, (1 << shift2) - 1}; /* block size - 1 */
    for (int a = 0; a < 3; a++) {
        int last = w->step[a] > 0 ? w->idx[a] | mask[a] : w->idx[a] & ~mask[a];
        double t = walk_crossing(w, a, last); /* inf on an axis without steps */
        if (t < t_exit) { t_exit = t; exit_axis = a; }
    }
    if (!(t_exit < w->t_end)) return false;
    for (int a = 0; a < 3; a++) {
        if (a == exit_axis) {
            int i = w->step[a] > 0 ? (w->idx[a] | mask[a]) + 1 : (w->idx[a] & ~mask[a]) - 1;
            if ((unsigned)i >= (unsigned)g->res[a]) return false;
            walk_set(w, a, i);
            continue;
        }
        /* Usually no step or one (at most the block's size); a crossing equal to the exit
         * (the ray leaves through an edge) can stay for walk_step. */
        while (w->t_next[a] < t_exit) {
            int i = w->idx[a] + w->step[a];
            if ((i & ~mask[a]) != (w->idx[a] & ~mask[a]) || i >= g->res[a]) break;
            walk_set(w, a, i);
        }
    }
    return true;
}

/* From an empty brick: skips its superbrick if that is empty too, else the brick. */
static inline bool walk_skip_empty(const Grid *g, GridWalk *w)
{
    const int *bs = g->brick_shift, *ss = g->super_shift;
    if (!super_occupied(g, w)) return walk_skip(g, w, bs[0] + ss[0], bs[1] + ss[1], bs[2] + ss[2]);
    return walk_skip(g, w, bs[0], bs[1], bs[2]);
}

static inline bool grid_prim_hit(const Grid *g, uint32_t slot, const TriangleRay *tr, const Ray *r,
                                 float *t, float *u, float *v, uint32_t *id)
{
    GRID_COUNT_PRIM_TEST(slot);
    if (slot < (uint32_t)g->num_tris) {
        const GridTri *tri = &g->tris[slot];
        *id = tri->id;
        return triangle_intersect_watertight(tr, r, tri->v0, tri->v1, tri->v2, t, u, v);
    }
    const GridSphere *s = &g->spheres[slot - (uint32_t)g->num_tris];
    *id = s->id;
    *u = *v = 0.0f;
    return sphere_intersect(s->center, s->radius, r, t);
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

bool grid_intersect(const Grid *g, const Ray *ray, Hit *hit)
{
    GridWalk w;
    if (g->num_cells == 0 || !walk_begin(g, ray, &w)) return false;
    Ray r = *ray;
    TriangleRay tr = triangle_ray_setup(r.d);
    Mailbox mb;
    mailbox_clear(&mb);
    bool found = false;
    for (;;) {
        if (cell_occupied(g, w.cell)) {
            for (uint32_t k = g->cell_start[w.cell], end = g->cell_start[w.cell + 1]; k < end; k++) {
                uint32_t slot = g->slots[k], id;
                if (mailbox_seen(&mb, slot)) continue;
                float t, u, v;
                if (grid_prim_hit(g, slot, &tr, &r, &t, &u, &v, &id)) {
                    r.t_max = t;
                    hit->t = t; hit->u = u; hit->v = v; hit->prim = id;
                    found = true;
                }
            }
            if (found && (double)r.t_max < w.t_end) w.t_end = (double)r.t_max;
        } else if (!brick_occupied(g, w.cell)) {
            if (!walk_skip_empty(g, &w)) break;
            continue;
        }
        if (!walk_step(g, &w)) break;
    }
    return found;
}

bool grid_occluded(const Grid *g, const Ray *r)
{
    GridWalk w;
    if (g->num_cells == 0 || !walk_begin(g, r, &w)) return false;
    TriangleRay tr = triangle_ray_setup(r->d);
    Mailbox mb;
    mailbox_clear(&mb);
    for (;;) {
        if (cell_occupied(g, w.cell)) {
            for (uint32_t k = g->cell_start[w.cell], end = g->cell_start[w.cell + 1]; k < end; k++) {
                uint32_t slot = g->slots[k], id;
                if (mailbox_seen(&mb, slot)) continue;
                float t, u, v;
                if (grid_prim_hit(g, slot, &tr, r, &t, &u, &v, &id)) return true;
            }
        } else if (!brick_occupied(g, w.cell)) {
            if (!walk_skip_empty(g, &w)) break;
            continue;
        }
        if (!walk_step(g, &w)) break;
    }
    return false;
}
