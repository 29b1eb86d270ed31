/* Octree build (adaptive subdivision, exact primitive-cell overlap) and traversal
 * (front to back over the octants in the ray's octant order, hashed mailboxing, SIMD
 * triangle tests; closest hit and occlusion).
 *
 * Exactness. Hits must be bit-identical to the list back end's, so every primitive is
 * tested with the caller's own ray (the block form of triangle_intersect_watertight, and
 * sphere_intersect, on the same floats); the octree only decides which primitives to test
 * and in which order. As in the grid (grid.c), a cell holds every primitive that comes
 * within `margin` of it (2^-16 of the scene's coordinate scale, hundreds of float ulps),
 * and the traversal computes its plane crossings in double from exact cell boxes (halving
 * is exact), ~1e-16 relative: a hit point that lies on its primitive lies in a cell the
 * ray is found to cross, and that cell holds the primitive. A cell is entered unless the
 * ray enters it beyond the closest hit so far, so the closest hit's cell is always
 * entered. Like the grid, the octree does not promise hits that the watertight test
 * itself puts farther than half the margin off their triangle (rays grazing a sliver's
 * plane, where t is ill-conditioned).
 *
 * Octant order. With the axes flipped where the ray's direction is negative (octant
 * c ^ flip), the ray's coordinates only grow, so it can pass from octant i to octant j
 * only if j's bits include i's, hence j > i: visiting octants 0..7 of the flipped
 * numbering is front to back (the order of Revelles et al., "An efficient parametric
 * algorithm for octree traversal", WSCG 2000, sec. 3), with each child's entry and exit
 * from the crossings of its parent's three mid planes. */
#include "accel/octree.h"

#include <float.h>
#include <immintrin.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "geometry/sphere.h"
#include "geometry/triangle_block.h"

#define OCTREE_MARGIN_REL 0x1p-16

enum {
    /* A cell does not split when its children would hold more than this many references
     * per primitive of the cell: large primitives crossing all octants (or coincident
     * ones) would only multiply. */
    OCT_MAX_DUP = 4,
    /* No cell splits into children smaller than this many margins on every axis. */
    OCT_MIN_CELL = 8,
    /* Past max(4M, 64 N) references no cell splits any more (a sparse "stadium" of large
     * triangles around a dense mesh cannot blow up the build). */
    OCT_MIN_REF_BUDGET = 1 << 22,
    OCT_REFS_PER_PRIM = 64,
    /* Per-ray mailbox slots (a power of two), direct-mapped on the low bits of the index:
     * neighbouring primitives of a mesh rarely collide. */
    OCT_MAILBOX = 32,
    /* Each inner node on the current path leaves at most 7 siblings on the stack. */
    OCT_STACK = 7 * OCTREE_MAX_DEPTH + 2
};

/* ------------------------------------------------------------------ build: overlap */

static inline double min3d(double a, double b, double c) { return a < b ? (a < c ? a : c) : (b < c ? b : c); }
static inline double max3d(double a, double b, double c) { return a > b ? (a > c ? a : c) : (b > c ? b : c); }

/* Separating-axis test of a triangle against an axis-aligned box given by its centre and
 * half sizes (Akenine-Moller, "Fast 3D Triangle-Box Overlap Testing", JGT 6(1), 2001):
 * the 3 box normals, the 9 cross products of box normals and triangle edges, then the
 * triangle's plane. In double: projections err by ~1e-16 of the coordinates, far below
 * the margin the box has been grown by. A degenerate triangle has zero cross products,
 * which separate nothing: it stays where its bounding box overlaps, conservatively. */
static bool tri_box_overlap(const double tv[3][3], const double c[3], const double h[3])
{
    double v[3][3], e[3][3];
    for (int i = 0; i < 3; i++)
        for (int a = 0; a < 3; a++) v[i][a] = tv[i][a] - c[a];
    for (int a = 0; a < 3; a++) /* the box normals: the boxes overlap */
        if (min3d(v[0][a], v[1][a], v[2][a]) > h[a] || max3d(v[0][a], v[1][a], v[2][a]) < -h[a]) return false;
    for (int i = 0; i < 3; i++)
        for (int a = 0; a < 3; a++) e[i][a] = v[(i + 1) % 3][a] - v[i][a];
    for (int a = 0; a < 3; a++) {
        int a1 = (a + 1) % 3, a2 = (a + 2) % 3;
        for (int i = 0; i < 3; i++) {
            /* axis = unit_a x e_i = (.., -e_i[a2] on a1, e_i[a1] on a2) */
            double x1 = -e[i][a2], x2 = e[i][a1];
            double p0 = x1 * v[0][a1] + x2 * v[0][a2], p1 = x1 * v[1][a1] + x2 * v[1][a2];
            double p2 = x1 * v[2][a1] + x2 * v[2][a2];
            double r = h[a1] * fabs(x1) + h[a2] * fabs(x2);
            if (min3d(p0, p1, p2) > r || max3d(p0, p1, p2) < -r) return false;
        }
    }
    double n[3] = {e[0][1] * e[1][2] - e[0][2] * e[1][1], e[0][2] * e[1][0] - e[0][0] * e[1][2],
                   e[0][0] * e[1][1] - e[0][1] * e[1][0]};
    double dist = n[0] * v[0][0] + n[1] * v[0][1] + n[2] * v[0][2];
    return fabs(dist) <= h[0] * fabs(n[0]) + h[1] * fabs(n[1]) + h[2] * fabs(n[2]);
}

/* Whether a sphere's surface (all a ray can hit) meets the box: the box's nearest point is
 * within the radius and its farthest is not strictly inside (Arvo, "A Simple Method for
 * Box-Sphere Intersection Testing", Graphics Gems, 1990). */
static bool sphere_box_overlap(const double c[3], double radius, const double lo[3], const double hi[3])
{
    double near2 = 0.0, far2 = 0.0;
    for (int a = 0; a < 3; a++) {
        if (c[a] < lo[a]) near2 += (lo[a] - c[a]) * (lo[a] - c[a]);
        else if (c[a] > hi[a]) near2 += (c[a] - hi[a]) * (c[a] - hi[a]);
        double f = fmax(fabs(c[a] - lo[a]), fabs(hi[a] - c[a]));
        far2 += f * f;
    }
    double r2 = radius * radius;
    return near2 <= r2 && far2 >= r2;
}

/* ------------------------------------------------------------------ build: the tree */

/* During the build a primitive is a code: i < num_tris is tris[i], then spheres[i -
 * num_tris], then the shape of placed_shapes[i - num_tris - num_spheres]; lists are
 * ascending, so a cell's triangles come first, then its spheres, then its shapes. */
typedef struct OctBuilder {
    Octree *t;
    size_t cap_nodes, cap_slots;
    size_t budget;
    const uint32_t *placed_shapes; /* scene primitive ids of the shapes with finite bounds */
    bool oom;
} OctBuilder;

static const BBox *code_shape_bounds(const OctBuilder *b, uint32_t code)
{
    const Octree *t = b->t;
    uint32_t id = b->placed_shapes[code - (uint32_t)t->num_tris - (uint32_t)t->num_spheres];
    return &t->shapes[id - t->shape_base].bounds;
}

static bool code_overlaps(const OctBuilder *b, uint32_t code, const double lo[3], const double hi[3])
{
    const Octree *t = b->t;
    double m = (double)t->margin;
    double glo[3] = {lo[0] - m, lo[1] - m, lo[2] - m}, ghi[3] = {hi[0] + m, hi[1] + m, hi[2] + m};
    if (code < (uint32_t)t->num_tris) {
        const OctTri *tr = &t->tris[code];
        const double tv[3][3] = {{(double)tr->v0.x, (double)tr->v0.y, (double)tr->v0.z},
                                 {(double)tr->v1.x, (double)tr->v1.y, (double)tr->v1.z},
                                 {(double)tr->v2.x, (double)tr->v2.y, (double)tr->v2.z}};
        double c[3], h[3];
        for (int a = 0; a < 3; a++) {
            c[a] = 0.5 * (glo[a] + ghi[a]);
            h[a] = 0.5 * (ghi[a] - glo[a]);
        }
        return tri_box_overlap(tv, c, h);
    }
    if (code >= (uint32_t)t->num_tris + (uint32_t)t->num_spheres) { /* a shape: its bounds */
        const BBox *bb = code_shape_bounds(b, code);
        for (int a = 0; a < 3; a++)
            if ((double)v3_get(bb->min, a) > ghi[a] || (double)v3_get(bb->max, a) < glo[a]) return false;
        return true;
    }
    const OctSphere *sp = &t->spheres[code - (uint32_t)t->num_tris];
    const double c[3] = {(double)sp->center.x, (double)sp->center.y, (double)sp->center.z};
    return sphere_box_overlap(c, fabs((double)sp->radius), glo, ghi);
}

/* The box of a primitive, in double. */
static void code_bounds(const OctBuilder *b, uint32_t code, double lo[3], double hi[3])
{
    const Octree *t = b->t;
    if (code >= (uint32_t)t->num_tris + (uint32_t)t->num_spheres) {
        const BBox *bb = code_shape_bounds(b, code);
        for (int a = 0; a < 3; a++) {
            lo[a] = (double)v3_get(bb->min, a);
            hi[a] = (double)v3_get(bb->max, a);
        }
        return;
    }
    if (code < (uint32_t)t->num_tris) {
        const OctTri *tr = &t->tris[code];
        const Vec3 v[3] = {tr->v0, tr->v1, tr->v2};
        for (int a = 0; a < 3; a++) {
            double x0 = (double)v3_get(v[0], a), x1 = (double)v3_get(v[1], a), x2 = (double)v3_get(v[2], a);
            lo[a] = min3d(x0, x1, x2);
            hi[a] = max3d(x0, x1, x2);
        }
        return;
    }
    const OctSphere *sp = &t->spheres[code - (uint32_t)t->num_tris];
    double r = fabs((double)sp->radius);
    for (int a = 0; a < 3; a++) {
        lo[a] = (double)v3_get(sp->center, a) - r;
        hi[a] = (double)v3_get(sp->center, a) + r;
    }
}

static void make_leaf(OctBuilder *b, uint32_t node, const uint32_t *codes, size_t n)
{
    Octree *t = b->t;
    if (t->num_refs + n > b->cap_slots) {
        size_t cap = b->cap_slots * 2 > t->num_refs + n ? b->cap_slots * 2 : t->num_refs + n;
        uint32_t *s = realloc(t->slots, cap * sizeof *s);
        if (!s) { b->oom = true; return; }
        t->slots = s;
        b->cap_slots = cap;
    }
    const uint32_t shape0 = (uint32_t)t->num_tris + (uint32_t)t->num_spheres;
    uint32_t nt = 0, nts = 0;
    while (nt < n && codes[nt] < (uint32_t)t->num_tris) nt++;
    nts = nt;
    while (nts < n && codes[nts] < shape0) nts++;
    OctNode *nd = &t->nodes[node];
    nd->first = (uint32_t)t->num_refs;
    nd->num_tris = nt;
    nd->num_spheres = nts - nt;
    nd->num_shapes = (uint32_t)n - nts;
    for (size_t i = 0; i < n; i++)
        t->slots[t->num_refs++] = i < nt ? codes[i]
                                  : i < nts ? codes[i] - (uint32_t)t->num_tris
                                            : b->placed_shapes[codes[i] - shape0];
    if (n > 0) t->num_leaves++;
}

/* Builds node `node` (already allocated) over the cell at lo (size t->cell[depth]). */
static void build_node(OctBuilder *b, uint32_t node, const uint32_t *codes, size_t n, const double lo[3], int depth)
{
    Octree *t = b->t;
    if (depth > t->depth) t->depth = depth;
    if (n <= OCTREE_LEAF_PRIMS || depth >= OCTREE_MAX_DEPTH || t->num_refs > b->budget) {
        make_leaf(b, node, codes, n);
        return;
    }
    /* Children whose every side is under OCT_MIN_CELL margins cannot separate much: a
     * primitive is in every cell within a margin of it, so a point's primitives would
     * be copied into most of the cells around it. */
    const double *hs = t->cell[depth + 1];
    if (fmax(hs[0], fmax(hs[1], hs[2])) < OCT_MIN_CELL * (double)t->margin) {
        make_leaf(b, node, codes, n);
        return;
    }
    uint32_t *child = malloc(8 * n * sizeof *child);
    if (!child) { b->oom = true; return; }
    size_t count[8] = {0}, total = 0;
    double clo[8][3], chi[8][3];
    for (int c = 0; c < 8; c++)
        for (int a = 0; a < 3; a++) {
            clo[c][a] = (c >> a) & 1 ? lo[a] + hs[a] : lo[a];
            chi[c][a] = clo[c][a] + hs[a];
        }
    /* The octants whose grown boxes a primitive's box meets, per axis the lower half, the
     * upper or both; the exact test runs only when that leaves several. With one left, the
     * primitive's part near the cell (it comes within the margin of the cell) lies in its
     * box and so in that octant's grown box: the exact test would say yes. */
    static const unsigned UPPER[3] = {0xaau, 0xccu, 0xf0u}; /* octants with bit a set */
    const double m = (double)t->margin;
    for (size_t i = 0; i < n; i++) {
        double blo[3], bhi[3];
        code_bounds(b, codes[i], blo, bhi);
        unsigned cand = 0xffu;
        for (int a = 0; a < 3; a++) {
            double mid = lo[a] + hs[a];
            cand &= (blo[a] <= mid + m ? ~UPPER[a] & 0xffu : 0u) | (bhi[a] >= mid - m ? UPPER[a] : 0u);
        }
        bool one = (cand & (cand - 1u)) == 0u;
        for (unsigned bits = cand; bits; bits &= bits - 1u) {
            int c = __builtin_ctz(bits);
            if (one || code_overlaps(b, codes[i], clo[c], chi[c])) child[(size_t)c * n + count[c]++] = codes[i];
        }
    }
    for (int c = 0; c < 8; c++) total += count[c];
    if (total > (size_t)OCT_MAX_DUP * n) {
        free(child);
        make_leaf(b, node, codes, n);
        return;
    }
    if ((size_t)t->num_nodes + 8 > b->cap_nodes) {
        size_t cap = 2 * b->cap_nodes;
        OctNode *nodes = realloc(t->nodes, cap * sizeof *nodes);
        if (!nodes) { free(child); b->oom = true; return; }
        t->nodes = nodes;
        b->cap_nodes = cap;
    }
    uint32_t first = (uint32_t)t->num_nodes;
    t->num_nodes += 8;
    t->nodes[node] = (OctNode){first, (uint32_t)OCTREE_INNER, 0u, 0u};
    uint32_t occupied = 0u;
    for (int c = 0; c < 8 && !b->oom; c++) {
        t->nodes[first + (uint32_t)c] = (OctNode){0u, 0u, 0u, 0u};
        build_node(b, first + (uint32_t)c, child + (size_t)c * n, count[c], clo[c], depth + 1);
        if (count[c] > 0) occupied |= 1u << c;
    }
    t->nodes[node].num_spheres = occupied;
    free(child);
}

CstStatus octree_build(Octree *t, const AccelGeometry *geom, CstError *err)
{
    memset(t, 0, sizeof *t);
    t->bounds = bbox_empty();
    int nt = geom->num_tris > 0 ? geom->num_tris : 0, ns = geom->num_spheres > 0 ? geom->num_spheres : 0;
    int nsh = geom->num_shapes > 0 && geom->shapes ? geom->num_shapes : 0;
    size_t n = (size_t)nt + (size_t)ns + (size_t)nsh;
    if (n == 0) return CST_OK;
    if (n >= (size_t)INT32_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "octree: %zu primitives exceed the 32-bit id range", n);
    uint32_t *codes = NULL, *placed_shapes = NULL;
    OctBuilder b = {t, 0, 0, 0, NULL, false};

    /* The octree's own copies of the finite primitives (a non-finite one fails every
     * comparison of its test, so the list back end never reports it either). */
    if (nt > 0 && !(t->tris = malloc((size_t)nt * sizeof *t->tris))) goto oom;
    if (ns > 0 && !(t->spheres = malloc((size_t)ns * sizeof *t->spheres))) goto oom;
    BBox raw = bbox_empty();
    for (int i = 0; i < nt; i++) {
        const int32_t *k = &geom->tri_indices[3 * i];
        Vec3 a = geom->positions[k[0]], p1 = geom->positions[k[1]], p2 = geom->positions[k[2]];
        if (!v3_is_finite(a) || !v3_is_finite(p1) || !v3_is_finite(p2)) continue;
        t->tris[t->num_tris++] = (OctTri){a, p1, p2, (uint32_t)i};
        raw = bbox_add(bbox_add(bbox_add(raw, a), p1), p2);
    }
    for (int j = 0; j < ns; j++) {
        const Sphere *s = &geom->spheres[j];
        Vec3 r = v3s(fabsf(s->radius)); /* sphere_intersect only uses radius^2 */
        Vec3 lo = v3_sub(s->center, r), hi = v3_add(s->center, r);
        if (!v3_is_finite(lo) || !v3_is_finite(hi)) continue;
        t->spheres[t->num_spheres++] = (OctSphere){s->center, s->radius, (uint32_t)(nt + j)};
        raw = bbox_add(bbox_add(raw, lo), hi);
    }
    /* Shapes: the whole array copied (the leaf test indexes it by id - base), those with
     * finite bounds placed. */
    size_t placed_sh = 0;
    if (nsh > 0) {
        t->shape_base = accel_shape_base(geom);
        if (!(t->shapes = malloc((size_t)nsh * sizeof *t->shapes)) ||
            !(placed_shapes = malloc((size_t)nsh * sizeof *placed_shapes)))
            goto oom;
        memcpy(t->shapes, geom->shapes, (size_t)nsh * sizeof *t->shapes);
        t->num_shapes = nsh;
        for (int k = 0; k < nsh; k++) {
            const BBox *bb = &t->shapes[k].bounds;
            if (!v3_is_finite(bb->min) || !v3_is_finite(bb->max)) continue;
            placed_shapes[placed_sh++] = t->shape_base + (uint32_t)k;
            raw = bbox_union(raw, *bb);
        }
    }
    b.placed_shapes = placed_shapes;
    size_t placed = (size_t)t->num_tris + (size_t)t->num_spheres + placed_sh;
    if (placed == 0) {
        free(placed_shapes);
        octree_free(t);
        return CST_OK; /* nothing can be hit: no nodes, every ray misses */
    }

    /* Margin: 2^-16 of the coordinate scale (largest |coordinate| plus largest extent), as
     * the grid's. The root cell holds every primitive grown by it, with another margin of
     * room; its children are exact halves, down to cells as thin as the margin. */
    double ext[3] = {(double)raw.max.x - (double)raw.min.x, (double)raw.max.y - (double)raw.min.y,
                     (double)raw.max.z - (double)raw.min.z};
    double scale = fmax((double)v3_max_abs(raw.min), (double)v3_max_abs(raw.max)) + fmax(ext[0], fmax(ext[1], ext[2]));
    t->margin = (float)(OCTREE_MARGIN_REL * scale);
    if (!(t->margin > 0.0f)) t->margin = FLT_MIN; /* everything at the origin */
    double m = (double)t->margin;
    const double rmin[3] = {(double)raw.min.x, (double)raw.min.y, (double)raw.min.z};
    for (int a = 0; a < 3; a++) {
        t->org[a] = rmin[a] - 2.0 * m;
        t->size[a] = ext[a] + 4.0 * m;
        for (int d = 0; d <= OCTREE_MAX_DEPTH; d++) t->cell[d][a] = ldexp(t->size[a], -d);
    }
    t->bounds.min = v3(nextafterf((float)t->org[0], -INFINITY), nextafterf((float)t->org[1], -INFINITY),
                       nextafterf((float)t->org[2], -INFINITY));
    t->bounds.max = v3(nextafterf((float)(t->org[0] + t->size[0]), INFINITY),
                       nextafterf((float)(t->org[1] + t->size[1]), INFINITY),
                       nextafterf((float)(t->org[2] + t->size[2]), INFINITY));

    b.budget = (size_t)OCT_REFS_PER_PRIM * placed;
    if (b.budget > ((size_t)1 << 31)) b.budget = (size_t)1 << 31;
    if (b.budget < (size_t)OCT_MIN_REF_BUDGET) b.budget = (size_t)OCT_MIN_REF_BUDGET;
    b.cap_nodes = 64;
    b.cap_slots = 2 * placed + 16;
    t->nodes = malloc(b.cap_nodes * sizeof *t->nodes);
    t->slots = malloc(b.cap_slots * sizeof *t->slots);
    codes = malloc(placed * sizeof *codes);
    if (!t->nodes || !t->slots || !codes) goto oom;
    for (size_t i = 0; i < placed; i++) codes[i] = (uint32_t)i;
    t->num_nodes = 1;
    t->nodes[0] = (OctNode){0u, 0u, 0u, 0u};
    build_node(&b, 0u, codes, placed, t->org, 0);
    free(codes);
    codes = NULL;
    free(placed_shapes);
    placed_shapes = NULL;
    if (b.oom) goto oom;
    /* Give back the spare capacity (a failed shrink leaves the array as it was). */
    OctNode *nodes = realloc(t->nodes, (size_t)t->num_nodes * sizeof *nodes);
    if (nodes) t->nodes = nodes;
    if (t->num_refs > 0) {
        uint32_t *slots = realloc(t->slots, t->num_refs * sizeof *slots);
        if (slots) t->slots = slots;
    }
    return CST_OK;
oom:
    free(codes);
    free(placed_shapes);
    octree_free(t);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the octree over %zu primitives", n);
}

void octree_free(Octree *t)
{
    if (!t) return;
    free(t->nodes);
    free(t->slots);
    free(t->tris);
    free(t->spheres);
    free(t->shapes);
    memset(t, 0, sizeof *t);
}

size_t octree_memory_bytes(const Octree *t)
{
    return (size_t)t->num_nodes * sizeof *t->nodes + t->num_refs * sizeof *t->slots +
           (size_t)t->num_tris * sizeof *t->tris + (size_t)t->num_spheres * sizeof *t->spheres +
           (size_t)t->num_shapes * sizeof *t->shapes;
}

/* ------------------------------------------------------------------ traversal */

/* Per-ray constants, in double. An axis the ray does not move along (zero or NaN
 * component) has inv 0 and moves false. */
typedef struct OctRay {
    double o[3], inv[3];
    bool moves[3];
    unsigned flip; /* bit a: the ray runs toward -a (sign bit of d_a), so the upper half is near */
} OctRay;

/* A pending cell: node, depth and minimum corner, and where the ray enters it. */
typedef struct OctEntry {
    uint32_t node;
    int depth;
    double enter;
    double lo[3];
} OctEntry;

/* Clips [t_min, t_max] to the root cell (slab test; exact for an axis the ray does not
 * move along). False on a miss. */
static inline bool oct_ray_setup(const Octree *t, const Ray *r, OctRay *q, double *t0, double *t1)
{
    double tn = (double)r->t_min, tf = (double)r->t_max;
    const double o[3] = {(double)r->o.x, (double)r->o.y, (double)r->o.z};
    const double d[3] = {(double)r->d.x, (double)r->d.y, (double)r->d.z};
    q->flip = 0u;
    for (int a = 0; a < 3; a++) {
        double lo = t->org[a], hi = t->org[a] + t->size[a];
        q->o[a] = o[a];
        q->flip |= (signbit(d[a]) ? 1u : 0u) << a;
        q->moves[a] = d[a] > 0.0 || d[a] < 0.0;
        if (q->moves[a]) {
            q->inv[a] = 1.0 / d[a];
            double ta = (lo - o[a]) * q->inv[a], tb = (hi - o[a]) * q->inv[a];
            if (ta > tb) { double s = ta; ta = tb; tb = s; }
            if (ta > tn) tn = ta;
            if (tb < tf) tf = tb;
        } else {
            q->inv[a] = 0.0;
            if (o[a] < lo || o[a] > hi) return false;
        }
    }
    *t0 = tn;
    *t1 = tf;
    return tn <= tf; /* also false on NaN */
}

/* Pushes the non-empty children of inner node nd (cell at lo, depth) that the ray
 * crosses within [t_lo, t_hi], farthest first so they pop front to back. A child's entry
 * and exit on each axis are the crossings of the cell's lower plane, mid plane and upper
 * plane; an axis the ray does not move along admits the halves holding the origin (both
 * when it lies on the mid plane) over all t. NaN crossings constrain nothing. */
static inline void push_children(const Octree *t, const OctRay *q, const OctNode *nd, int depth, const double lo[3],
                                 double t_lo, double t_hi, OctEntry *stack, int *sp)
{
    double ne[3], nx[3], fe[3], fx[3]; /* near half's entry, exit; far half's entry, exit */
    const double *hs = t->cell[depth + 1];
    for (int a = 0; a < 3; a++) {
        double mid = lo[a] + hs[a];
        if (q->moves[a]) {
            double hi = mid + hs[a];
            double tl = (lo[a] - q->o[a]) * q->inv[a], tm = (mid - q->o[a]) * q->inv[a],
                   th = (hi - q->o[a]) * q->inv[a];
            bool neg = (q->flip >> a) & 1u;
            ne[a] = neg ? th : tl;
            nx[a] = tm;
            fe[a] = tm;
            fx[a] = neg ? tl : th;
        } else {
            bool lower = q->o[a] <= mid, upper = q->o[a] >= mid;
            bool near_ok = (q->flip >> a) & 1u ? upper : lower, far_ok = (q->flip >> a) & 1u ? lower : upper;
            ne[a] = near_ok ? -HUGE_VAL : HUGE_VAL;
            nx[a] = near_ok ? HUGE_VAL : -HUGE_VAL;
            fe[a] = far_ok ? -HUGE_VAL : HUGE_VAL;
            fx[a] = far_ok ? HUGE_VAL : -HUGE_VAL;
        }
    }
    for (int k = 7; k >= 0; k--) {
        unsigned c = (unsigned)k ^ q->flip;
        if (!((nd->num_spheres >> c) & 1u)) continue; /* an empty leaf */
        double enter = t_lo, exit = t_hi;
        for (int a = 0; a < 3; a++) {
            bool far = (k >> a) & 1;
            double e = far ? fe[a] : ne[a], x = far ? fx[a] : nx[a];
            if (e > enter) enter = e;
            if (x < exit) exit = x;
        }
        if (!(enter <= exit)) continue;
        OctEntry *en = &stack[(*sp)++];
        en->node = nd->first + c;
        en->depth = depth + 1;
        en->enter = enter;
        for (int a = 0; a < 3; a++) en->lo[a] = (c >> a) & 1u ? lo[a] + hs[a] : lo[a];
    }
}

/* Hashed mailboxing (Benthin, "Realtime Ray Tracing on Current CPU Architectures", PhD
 * thesis, 2006, as in grid.c): the primitives this ray has tested, in a small
 * direct-mapped table on the stack; nothing is written to the shared tree. A primitive
 * evicted by a colliding key is simply tested again, with the same result (same ray,
 * t_max no larger): a miss costs time, never a wrong answer. Keys: a triangle's index,
 * num_tris + a sphere's index. */
typedef struct OctMailbox {
    uint32_t key[OCT_MAILBOX];
} OctMailbox;

static inline bool mailbox_seen(OctMailbox *mb, uint32_t key)
{
    uint32_t *e = &mb->key[key & (OCT_MAILBOX - 1)];
    if (*e == key) return true;
    *e = key;
    return false;
}

/* Collects the next (up to) TRI_BLOCK_WIDTH triangles of slots[*k .. end) the ray has not
 * tested yet, in slot order, NaN-padded. Returns how many. */
static inline int next_tris(const Octree *t, uint32_t *k, uint32_t end, OctMailbox *mb,
                            const OctTri *tri[TRI_BLOCK_WIDTH])
{
    int n = 0;
    for (; *k < end && n < TRI_BLOCK_WIDTH; (*k)++) {
        uint32_t slot = t->slots[*k];
        if (!mailbox_seen(mb, slot)) tri[n++] = &t->tris[slot];
    }
    for (int i = n; i < TRI_BLOCK_WIDTH; i++) tri[i] = &TRI_VERTS_NAN;
    return n;
}

/* The closest hit among a leaf's untested triangles, batch lanes in slot order with a
 * strict <, as a scalar loop picks among equal t; shortens r->t_max on a hit. */
static inline bool leaf_tris_intersect(const Octree *t, const OctNode *nd, OctMailbox *mb, const TriangleRayBlock *q,
                                       Ray *r, Hit *hit)
{
    bool found = false;
    const TriLanes t_min = lanes_set1(r->t_min);
    const OctTri *tri[TRI_BLOCK_WIDTH];
    uint32_t k = nd->first, end = nd->first + nd->num_tris;
    int n;
    while ((n = next_tris(t, &k, end, mb, tri)) > 0) {
        TriLanes tl, ul, vl;
        int scalar_lanes;
        int mask = tri_batch_intersect(tri, n, q, t_min, lanes_set1(r->t_max), &tl, &ul, &vl, &scalar_lanes);
        if (!((mask | scalar_lanes) & ((1 << n) - 1))) continue;
        float tt[TRI_BLOCK_WIDTH], uu[TRI_BLOCK_WIDTH], vv[TRI_BLOCK_WIDTH];
        lanes_store(tt, tl); lanes_store(uu, ul); lanes_store(vv, vl);
        for (int i = 0; i < n; i++) {
            if (scalar_lanes & (1 << i)) {
                float ts, us, vs;
                if (triangle_intersect_watertight(&q->tr, r, tri[i]->v0, tri[i]->v1, tri[i]->v2, &ts, &us, &vs)) {
                    r->t_max = ts;
                    hit->t = ts; hit->u = us; hit->v = vs; hit->prim = tri[i]->id;
                    found = true;
                }
            } else if ((mask & (1 << i)) && tt[i] < r->t_max) {
                r->t_max = tt[i];
                hit->t = tt[i]; hit->u = uu[i]; hit->v = vv[i]; hit->prim = tri[i]->id;
                found = true;
            }
        }
    }
    return found;
}

static inline bool leaf_tris_occluded(const Octree *t, const OctNode *nd, OctMailbox *mb, const TriangleRayBlock *q,
                                      const Ray *r)
{
    const TriLanes t_min = lanes_set1(r->t_min), t_max = lanes_set1(r->t_max);
    const OctTri *tri[TRI_BLOCK_WIDTH];
    uint32_t k = nd->first, end = nd->first + nd->num_tris;
    int n;
    while ((n = next_tris(t, &k, end, mb, tri)) > 0) {
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
    return false;
}

/* The closest hit among a leaf's untested spheres; shortens r->t_max on a hit. */
static inline bool leaf_spheres_intersect(const Octree *t, const OctNode *nd, OctMailbox *mb, Ray *r, Hit *hit)
{
    bool found = false;
    uint32_t begin = nd->first + nd->num_tris, end = begin + nd->num_spheres;
    for (uint32_t k = begin; k < end; k++) {
        uint32_t slot = t->slots[k];
        if (mailbox_seen(mb, (uint32_t)t->num_tris + slot)) continue;
        const OctSphere *sp = &t->spheres[slot];
        float tt;
        if (sphere_intersect(sp->center, sp->radius, r, &tt)) {
            r->t_max = tt;
            hit->t = tt; hit->u = 0.0f; hit->v = 0.0f; hit->prim = sp->id;
            found = true;
        }
    }
    return found;
}

static inline bool leaf_spheres_occluded(const Octree *t, const OctNode *nd, OctMailbox *mb, const Ray *r)
{
    uint32_t begin = nd->first + nd->num_tris, end = begin + nd->num_spheres;
    for (uint32_t k = begin; k < end; k++) {
        uint32_t slot = t->slots[k];
        if (mailbox_seen(mb, (uint32_t)t->num_tris + slot)) continue;
        const OctSphere *sp = &t->spheres[slot];
        float tt;
        if (sphere_intersect(sp->center, sp->radius, r, &tt)) return true;
    }
    return false;
}

/* Front to back; every hit shortens the ray, and a pending cell is skipped when the ray
 * enters it beyond the closest hit so far. A hit is not cut at its leaf's exit: a
 * straddling primitive's hit beyond it is still a hit, and any closer one lies in a
 * cell entered before it, which has not been skipped. */
bool octree_intersect(const Octree *t, const Ray *ray, Hit *hit)
{
    OctRay q;
    double t0, t1;
    if (!t->nodes || !oct_ray_setup(t, ray, &q, &t0, &t1)) return false;
    Ray r = *ray;
    TriangleRayBlock qt = triangle_block_ray_setup(&r);
    OctMailbox mb;
    memset(mb.key, 0xff, sizeof mb.key);
    OctEntry stack[OCT_STACK];
    int sp = 1;
    stack[0] = (OctEntry){0u, 0, t0, {t->org[0], t->org[1], t->org[2]}};
    bool found = false;
    while (sp > 0) {
        const OctEntry e = stack[--sp];
        if (e.enter > (double)r.t_max) continue;
        const OctNode *nd = &t->nodes[e.node];
        if (nd->num_tris == (uint32_t)OCTREE_INNER) {
            push_children(t, &q, nd, e.depth, e.lo, e.enter, (double)r.t_max < t1 ? (double)r.t_max : t1, stack, &sp);
            continue;
        }
        if (nd->num_tris) found |= leaf_tris_intersect(t, nd, &mb, &qt, &r, hit);
        if (nd->num_spheres) found |= leaf_spheres_intersect(t, nd, &mb, &r, hit);
        /* Shapes unmailboxed: a shape tested again by a later cell of this ray gives the
         * same hit, which the open interval (t_min, t_max = that hit) then rejects. */
        if (nd->num_shapes)
            found |= shape_leaf_intersect(t->shapes, t->shape_base, &t->slots[nd->first + nd->num_tris + nd->num_spheres],
                                          nd->num_shapes, &r, hit);
    }
    return found;
}

bool octree_occluded(const Octree *t, const Ray *ray)
{
    OctRay q;
    double t0, t1;
    if (!t->nodes || !oct_ray_setup(t, ray, &q, &t0, &t1)) return false;
    TriangleRayBlock qt = triangle_block_ray_setup(ray);
    OctMailbox mb;
    memset(mb.key, 0xff, sizeof mb.key);
    OctEntry stack[OCT_STACK];
    int sp = 1;
    stack[0] = (OctEntry){0u, 0, t0, {t->org[0], t->org[1], t->org[2]}};
    while (sp > 0) {
        const OctEntry e = stack[--sp];
        const OctNode *nd = &t->nodes[e.node];
        if (nd->num_tris == (uint32_t)OCTREE_INNER) {
            push_children(t, &q, nd, e.depth, e.lo, e.enter, t1, stack, &sp);
            continue;
        }
        if (nd->num_tris && leaf_tris_occluded(t, nd, &mb, &qt, ray)) return true;
        if (nd->num_spheres && leaf_spheres_occluded(t, nd, &mb, ray)) return true;
        if (nd->num_shapes &&
            shape_leaf_occluded(t->shapes, t->shape_base, &t->slots[nd->first + nd->num_tris + nd->num_spheres],
                                nd->num_shapes, ray))
            return true;
    }
    return false;
}
