/* kd-tree build and traversal. The build is the O(N log N) algorithm of Wald & Havran, "On
 * building fast kd-Trees for Ray Tracing, and on doing that in O(N log N)", IEEE Symposium
 * on Interactive Ray Tracing 2006: split candidates are the planes of the primitives'
 * bounds ("events"), sorted once per axis and then kept sorted by splitting the lists
 * (sec. 5.3), so every node is one linear SAH sweep (sec. 4.2, Alg. 4). Straddling
 * primitives go to both children and are clipped to each child's cell ("perfect splits",
 * sec. 4.3), which gives tighter event bounds than their boxes. Traversal is the
 * front-to-back stack traversal of pbrt-v3's KdTreeAccel (Havran's TA_rec_B); leaves are
 * tested TRI_BLOCK_WIDTH triangles at a time with the SIMD form of the watertight test. */
#include "accel/kdtree.h"

#include <float.h>
#include <immintrin.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

/* SAH constants (Wald & Havran eq. 2 and sec. 4.4): a traversal step and one block test
 * (TRI_BLOCK_WIDTH triangles at once, so a leaf of n triangles costs ceil(n / width) tests:
 * the "block SAH" of wide BVHs) in the same unit; cost * (1 - KD_EMPTY_BONUS) when one side
 * is empty, to cut off empty space. On the Stanford bunny (1 thread, bench rays), a block
 * cost of 0.5 ran ~5% faster on random rays than 0.25 or 1.0, and ~10% faster than 2.0;
 * per-triangle costs (the scalar tests' SAH) ran 10-20% slower on random rays; an empty
 * bonus of 0.1 or 0.3 instead of 0.2 within noise, 0.4 ~10% slower. */
static const float KD_COST_TRAVERSE = 1.0f;
static const float KD_COST_BLOCK = 0.5f;
static const float KD_EMPTY_BONUS = 0.2f;

static inline float leaf_blocks(int n) { return (float)((n + TRI_BLOCK_WIDTH - 1) / TRI_BLOCK_WIDTH); }

/* Traversal treats every split plane as a slab of half-width
 * w = KD_PLANE_MARGIN * (largest |coordinate| of the scene + largest |coordinate| of the
 * ray origin), visiting both children when the ray runs within it. A primitive test's hit
 * point can round to just outside the primitive (by a few ulps of the coordinates
 * involved), so it can lie in a cell that does not hold the primitive; with the margin
 * every cell counts as grown by w, and the primitive is still tested before the
 * traversal stops. 2^-20 is 8 ulps of those magnitudes. Rays lying in a split plane,
 * with a zero direction component of either sign, fall inside the slab: both sides. */
static const float KD_PLANE_MARGIN = 0x1p-20f;

enum {
    KD_STACK = KD_MAX_DEPTH + 4, /* each inner node on the current path pushes at most once */
    KD_NONE = -1,                /* descend(): no leaf to visit (as a uint32_t) */
    KD_MAX_NODES = 1 << 28       /* the child index has 28 bits */
};

/* ------------------------------------------------------------------ build: events */

/* Wald & Havran sec. 4.2: at equal positions, ends sort before planars before starts. */
enum { EV_END = 0, EV_PLANAR = 1, EV_START = 2 };

typedef struct KdEvent {
    float pos;
    uint32_t prim; /* scene id */
    uint32_t type;
} KdEvent;

static inline bool ev_less(const KdEvent *a, const KdEvent *b)
{
    return a->pos < b->pos || (a->pos == b->pos && a->type < b->type);
}

/* Quicksort (Hoare partition around the middle element, recursing into the smaller part)
 * with insertion sort below 16 elements. */
static void sort_events(KdEvent *e, size_t n)
{
    while (n > 16) {
        KdEvent piv = e[n / 2];
        size_t i = 0, j = n - 1;
        for (;;) {
            while (ev_less(&e[i], &piv)) i++;
            while (ev_less(&piv, &e[j])) j--;
            if (i >= j) break;
            KdEvent t = e[i]; e[i] = e[j]; e[j] = t;
            i++; j--;
        }
        size_t nl = j + 1; /* [0, j] and [j + 1, n), both non-empty */
        if (nl < n - nl) { sort_events(e, nl); e += nl; n -= nl; }
        else { sort_events(e + nl, n - nl); n = nl; }
    }
    for (size_t i = 1; i < n; i++) {
        KdEvent x = e[i];
        size_t j = i;
        while (j > 0 && ev_less(&x, &e[j - 1])) { e[j] = e[j - 1]; j--; }
        e[j] = x;
    }
}

/* Appends the events of primitive `id` with bounds b: a start and an end per axis, or one
 * planar event where the bounds are flat. */
static void push_events(KdEvent *out[3], int count[3], uint32_t id, BBox b)
{
    for (int a = 0; a < 3; a++) {
        float lo = v3_get(b.min, a), hi = v3_get(b.max, a);
        if (lo == hi) {
            out[a][count[a]++] = (KdEvent){lo, id, EV_PLANAR};
        } else {
            out[a][count[a]++] = (KdEvent){lo, id, EV_START};
            out[a][count[a]++] = (KdEvent){hi, id, EV_END};
        }
    }
}

/* ------------------------------------------------------------------ build: clipping */

static float round_down(double x)
{
    float f = (float)x;
    return (double)f > x ? nextafterf(f, -INFINITY) : f;
}

static float round_up(double x)
{
    float f = (float)x;
    return (double)f < x ? nextafterf(f, INFINITY) : f;
}

static BBox bbox_intersection(BBox a, BBox b)
{
    BBox r = {v3_max(a.min, b.min), v3_min(a.max, b.max)};
    return r;
}

static bool bbox_valid(BBox b) { return b.min.x <= b.max.x && b.min.y <= b.max.y && b.min.z <= b.max.z; }

/* Bounds of triangle (p0, p1, p2) within `cell`: the triangle is clipped against the six
 * planes of the cell (Sutherland-Hodgman, in double) and the box of the polygon rounded
 * outward to float. Returns false when nothing is left. */
static bool clip_triangle(Vec3 p0, Vec3 p1, Vec3 p2, BBox cell, BBox *out)
{
    double poly[2][9][3]; /* a triangle clipped by 6 planes has at most 9 vertices */
    const Vec3 in[3] = {p0, p1, p2};
    for (int i = 0; i < 3; i++) {
        poly[0][i][0] = (double)in[i].x; poly[0][i][1] = (double)in[i].y; poly[0][i][2] = (double)in[i].z;
    }
    int n = 3, cur = 0;
    for (int plane = 0; plane < 6 && n > 0; plane++) {
        int axis = plane >> 1;
        bool keep_above = (plane & 1) == 0; /* even planes: the cell's min, keep x >= min */
        double c = (double)v3_get(keep_above ? cell.min : cell.max, axis);
        double (*src)[3] = poly[cur], (*dst)[3] = poly[cur ^ 1];
        int m = 0;
        for (int i = 0; i < n; i++) {
            const double *a = src[i], *b = src[(i + 1) % n];
            bool ina = keep_above ? a[axis] >= c : a[axis] <= c;
            bool inb = keep_above ? b[axis] >= c : b[axis] <= c;
            if (ina) { memcpy(dst[m], a, sizeof dst[m]); m++; }
            if (ina != inb) {
                double t = (c - a[axis]) / (b[axis] - a[axis]);
                for (int k = 0; k < 3; k++) dst[m][k] = a[k] + t * (b[k] - a[k]);
                dst[m][axis] = c; /* exactly on the plane */
                m++;
            }
        }
        n = m;
        cur ^= 1;
    }
    if (n == 0) return false;
    double lo[3] = {HUGE_VAL, HUGE_VAL, HUGE_VAL}, hi[3] = {-HUGE_VAL, -HUGE_VAL, -HUGE_VAL};
    for (int i = 0; i < n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = fmin(lo[k], poly[cur][i][k]);
            hi[k] = fmax(hi[k], poly[cur][i][k]);
        }
    BBox b = {v3(round_down(lo[0]), round_down(lo[1]), round_down(lo[2])),
              v3(round_up(hi[0]), round_up(hi[1]), round_up(hi[2]))};
    b = bbox_intersection(b, cell);
    if (!bbox_valid(b)) return false;
    *out = b;
    return true;
}

/* ------------------------------------------------------------------ build: the tree */

/* Classification of a node's primitives against its split (Wald & Havran Alg. 5). */
enum { SIDE_BOTH = 0, SIDE_LEFT = 1, SIDE_RIGHT = 2 };

typedef struct Builder {
    const AccelGeometry *g;
    const BBox *prim_box; /* unclipped bounds by scene id */
    uint8_t *side;        /* by scene id; valid for the primitives of the node being split */
    KdTree *out;
    uint32_t *ids;        /* leaf lists (scene ids); a leaf node's `first` indexes it until store_leaves */
    int num_ids;
    size_t cap_nodes, cap_ids; /* core/array.h's growth rule */
    bool oom, too_big;
} Builder;

/* A node's events: three sorted lists (one per axis) in one allocation. */
typedef struct EventLists {
    KdEvent *block;
    KdEvent *ev[3];
    int n[3];
} EventLists;

typedef struct KdSplit {
    float cost, pos;
    int axis; /* -1: none */
    bool planar_left;
} KdSplit;

/* SAH cost of a split with hit probabilities pl, pr (child area / parent area). */
static inline float sah_cost(float pl, float pr, int nl, int nr)
{
    float c = KD_COST_TRAVERSE + KD_COST_BLOCK * (pl * leaf_blocks(nl) + pr * leaf_blocks(nr));
    return (nl == 0 || nr == 0) ? c * (1.0f - KD_EMPTY_BONUS) : c;
}

/* One sweep per axis over the sorted events (Wald & Havran Alg. 4). Only planes strictly
 * inside the cell are candidates: a plane on the cell's face would cut off an empty slice
 * of zero volume, which the empty bonus would make look attractive forever. */
static KdSplit find_split(const EventLists *E, int num_prims, BBox cell)
{
    KdSplit best = {INFINITY, 0.0f, -1, false};
    float area = bbox_area(cell);
    if (!(area > 0.0f)) return best;
    float inv_area = 1.0f / area;
    Vec3 ext = v3_sub(cell.max, cell.min);
    for (int k = 0; k < 3; k++) {
        float lo = v3_get(cell.min, k), hi = v3_get(cell.max, k);
        if (!(hi > lo)) continue;
        float e1 = v3_get(ext, (k + 1) % 3), e2 = v3_get(ext, (k + 2) % 3);
        float cross = e1 * e2, perim = e1 + e2;
        const KdEvent *ev = E->ev[k];
        int n = E->n[k];
        int nl = 0, nr = num_prims;
        for (int i = 0; i < n;) {
            float p = ev[i].pos;
            int ends = 0, planars = 0, starts = 0;
            while (i < n && ev[i].pos == p && ev[i].type == EV_END) { ends++; i++; }
            while (i < n && ev[i].pos == p && ev[i].type == EV_PLANAR) { planars++; i++; }
            while (i < n && ev[i].pos == p && ev[i].type == EV_START) { starts++; i++; }
            nr -= planars + ends;
            if (p > lo && p < hi) {
                float pl = 2.0f * (cross + (p - lo) * perim) * inv_area;
                float pr = 2.0f * (cross + (hi - p) * perim) * inv_area;
                float c_left = sah_cost(pl, pr, nl + planars, nr);
                float c_right = sah_cost(pl, pr, nl, nr + planars);
                if (c_left < best.cost) best = (KdSplit){c_left, p, k, true};
                if (c_right < best.cost) best = (KdSplit){c_right, p, k, false};
            }
            nl += starts + planars;
        }
    }
    return best;
}

static int new_node(Builder *b)
{
    KdTree *t = b->out;
    if (t->num_nodes >= KD_MAX_NODES) { b->too_big = true; return -1; }
    if (!array_grow(&t->nodes, &b->cap_nodes, (size_t)t->num_nodes + 1, sizeof *t->nodes)) {
        b->oom = true;
        return -1;
    }
    return t->num_nodes++;
}

static int cmp_u32(const void *a, const void *b)
{
    uint32_t x = *(const uint32_t *)a, y = *(const uint32_t *)b;
    return (x > y) - (x < y);
}

/* A leaf over the node's primitives, listed in ascending id order so that exact ties in t
 * within a leaf resolve to the lowest id, as in the brute-force loop. Until store_leaves,
 * the leaf's `first` indexes b->ids and flags >> 2 is its number of primitives. */
static void make_leaf(Builder *b, int node, const EventLists *E, int num_prims)
{
    KdNode *nd = &b->out->nodes[node];
    nd->flags = KD_LEAF | ((uint32_t)num_prims << 2);
    nd->first = (uint32_t)b->num_ids;
    if (num_prims == 0) return;
    if (num_prims >= (1 << 28) || b->num_ids > INT32_MAX - num_prims) { b->too_big = true; return; }
    if (!array_grow(&b->ids, &b->cap_ids, (size_t)b->num_ids + (size_t)num_prims, sizeof *b->ids)) {
        b->oom = true;
        return;
    }
    /* Every primitive has exactly one start or planar event on axis 0. */
    uint32_t *ids = &b->ids[b->num_ids];
    int m = 0;
    for (int i = 0; i < E->n[0]; i++)
        if (E->ev[0][i].type != EV_END) ids[m++] = E->ev[0][i].prim;
    qsort(ids, (size_t)m, sizeof *ids, cmp_u32);
    b->num_ids += m;
}

/* Bounds of primitive `id` clipped to `cell`. The caller knows the primitive overlaps the
 * cell; if clipping loses it to rounding, the box of the whole primitive cut to the cell
 * stands in (never empty then, and always conservative). */
static BBox prim_bounds_in(const Builder *b, uint32_t id, BBox cell)
{
    const AccelGeometry *g = b->g;
    BBox r;
    if ((int)id < g->num_tris) {
        const int32_t *k = &g->tri_indices[3 * id];
        if (clip_triangle(g->positions[k[0]], g->positions[k[1]], g->positions[k[2]], cell, &r)) return r;
    }
    return bbox_intersection(b->prim_box[id], cell);
}

/* Merges the sorted run dst[0, n1) with the sorted src[0, n2) into dst[0, n1 + n2). */
static void merge_events(KdEvent *dst, int n1, const KdEvent *src, int n2)
{
    int i = n1 - 1, j = n2 - 1, k = n1 + n2 - 1;
    while (j >= 0) {
        if (i >= 0 && ev_less(&src[j], &dst[i])) dst[k--] = dst[i--];
        else dst[k--] = src[j--];
    }
}

/* Builds the subtree over the events E (taking ownership of E->block) in `cell` and
 * returns its node index, or -1 on failure (b->oom or b->too_big). */
static int build_node(Builder *b, EventLists *E, int num_prims, BBox cell, int depth)
{
    int node = new_node(b);
    if (node < 0) { free(E->block); return -1; }
    KdSplit s = {INFINITY, 0.0f, -1, false};
    if (num_prims > 0 && depth < b->out->max_depth) s = find_split(E, num_prims, cell);
    if (s.axis < 0 || !(s.cost < KD_COST_BLOCK * leaf_blocks(num_prims))) {
        make_leaf(b, node, E, num_prims);
        free(E->block);
        return (b->oom || b->too_big) ? -1 : node;
    }

    /* Classify (Wald & Havran Alg. 5): everything straddles until an event says otherwise. */
    int k = s.axis;
    uint8_t *side = b->side;
    for (int i = 0; i < E->n[0]; i++) side[E->ev[0][i].prim] = SIDE_BOTH;
    for (int i = 0; i < E->n[k]; i++) {
        const KdEvent *e = &E->ev[k][i];
        if (e->type == EV_END && e->pos <= s.pos) side[e->prim] = SIDE_LEFT;
        else if (e->type == EV_START && e->pos >= s.pos) side[e->prim] = SIDE_RIGHT;
        else if (e->type == EV_PLANAR)
            side[e->prim] = e->pos < s.pos ? SIDE_LEFT
                          : e->pos > s.pos ? SIDE_RIGHT
                          : (s.planar_left ? SIDE_LEFT : SIDE_RIGHT);
    }
    int nb = 0, only_left = 0, only_right = 0;
    for (int i = 0; i < E->n[k]; i++) {
        const KdEvent *e = &E->ev[k][i];
        if (e->type == EV_END) continue;
        uint8_t sd = side[e->prim];
        nb += sd == SIDE_BOTH;
        only_left += sd == SIDE_LEFT;
        only_right += sd == SIDE_RIGHT;
    }

    /* Children's lists: the events of one-sided primitives, filtered in order (still
     * sorted), merged with the sorted events of the straddlers clipped to each child. */
    BBox cell_l = cell, cell_r = cell;
    if (k == 0) { cell_l.max.x = s.pos; cell_r.min.x = s.pos; }
    else if (k == 1) { cell_l.max.y = s.pos; cell_r.min.y = s.pos; }
    else { cell_l.max.z = s.pos; cell_r.min.z = s.pos; }
    size_t cap_l = 0, cap_r = 0;
    for (int a = 0; a < 3; a++) {
        cap_l += (size_t)E->n[a] + 2u * (size_t)nb;
        cap_r += (size_t)E->n[a] + 2u * (size_t)nb;
    }
    EventLists L = {0}, R = {0};
    KdEvent *fresh = malloc((size_t)(nb > 0 ? 12 * nb : 1) * sizeof *fresh);
    L.block = malloc(cap_l * sizeof *L.block);
    R.block = malloc(cap_r * sizeof *R.block);
    if (!fresh || !L.block || !R.block) {
        free(fresh); free(L.block); free(R.block); free(E->block);
        b->oom = true;
        return -1;
    }
    KdEvent *fl[3], *fr[3];
    int nfl[3] = {0, 0, 0}, nfr[3] = {0, 0, 0};
    for (int a = 0; a < 3; a++) {
        fl[a] = fresh + (size_t)(2 * a) * 2 * (size_t)nb;
        fr[a] = fresh + (size_t)(2 * a + 1) * 2 * (size_t)nb;
    }
    for (int i = 0; i < E->n[k]; i++) {
        const KdEvent *e = &E->ev[k][i];
        if (e->type != EV_START || side[e->prim] != SIDE_BOTH) continue;
        push_events(fl, nfl, e->prim, prim_bounds_in(b, e->prim, cell_l));
        push_events(fr, nfr, e->prim, prim_bounds_in(b, e->prim, cell_r));
    }
    size_t off_l = 0, off_r = 0;
    for (int a = 0; a < 3; a++) {
        L.ev[a] = L.block + off_l;
        R.ev[a] = R.block + off_r;
        int nl = 0, nr = 0;
        for (int i = 0; i < E->n[a]; i++) {
            const KdEvent *e = &E->ev[a][i];
            uint8_t sd = side[e->prim];
            if (sd == SIDE_LEFT) L.ev[a][nl++] = *e;
            else if (sd == SIDE_RIGHT) R.ev[a][nr++] = *e;
        }
        sort_events(fl[a], (size_t)nfl[a]);
        sort_events(fr[a], (size_t)nfr[a]);
        merge_events(L.ev[a], nl, fl[a], nfl[a]);
        merge_events(R.ev[a], nr, fr[a], nfr[a]);
        L.n[a] = nl + nfl[a];
        R.n[a] = nr + nfr[a];
        off_l += (size_t)E->n[a] + 2u * (size_t)nb;
        off_r += (size_t)E->n[a] + 2u * (size_t)nb;
    }
    free(fresh);
    free(E->block);

    /* Below the plane first: it is node + 1 in the depth-first layout. */
    if (build_node(b, &L, only_left + nb, cell_l, depth + 1) < 0) { free(R.block); return -1; }
    int above = build_node(b, &R, only_right + nb, cell_r, depth + 1);
    if (above < 0) return -1;
    KdNode *nd = &b->out->nodes[node];
    nd->split = s.pos;
    nd->flags = (uint32_t)k | ((uint32_t)above << 4);
    return node;
}

/* Turns the build's leaf lists into the final leaves: each leaf's triangles as
 * consecutive blocks of TRI_BLOCK_WIDTH (in the lists' ascending id order, lane by lane),
 * its spheres after them; leaves in node order, so a subtree's leaves are close in
 * memory. Returns false on OOM. */
static bool store_leaves(KdTree *t, const Builder *b)
{
    const AccelGeometry *g = b->g;
    uint32_t num_tris = (uint32_t)g->num_tris, shape_base = accel_shape_base(g);
    size_t blocks = 0, spheres = 0, sphere_leaves = 0, shapes = 0;
    for (int i = 0; i < t->num_nodes; i++) {
        const KdNode *nd = &t->nodes[i];
        if ((nd->flags & 3u) != KD_LEAF) continue;
        uint32_t count = nd->flags >> 2, nt = 0, ns = 0;
        const uint32_t *ids = &b->ids[nd->first];
        while (nt < count && ids[nt] < num_tris) nt++; /* ascending: triangles first */
        while (nt + ns < count && ids[nt + ns] < shape_base) ns++; /* then spheres, then shapes */
        blocks += (nt + TRI_BLOCK_WIDTH - 1) / TRI_BLOCK_WIDTH;
        spheres += ns;
        shapes += count - nt - ns;
        sphere_leaves += count > nt;
    }
    t->blocks = malloc((blocks > 0 ? blocks : 1) * sizeof *t->blocks);
    t->spheres = malloc((spheres > 0 ? spheres : 1) * sizeof *t->spheres);
    t->sphere_leaves = malloc((sphere_leaves > 0 ? sphere_leaves : 1) * sizeof *t->sphere_leaves);
    t->shape_ids = malloc((shapes > 0 ? shapes : 1) * sizeof *t->shape_ids);
    t->shapes = g->shapes;
    t->shape_base = shape_base;
    if (!t->blocks || !t->spheres || !t->sphere_leaves || !t->shape_ids) return false;
    for (int i = 0; i < t->num_nodes; i++) {
        KdNode *nd = &t->nodes[i];
        if ((nd->flags & 3u) != KD_LEAF) continue;
        uint32_t count = nd->flags >> 2, nt = 0;
        const uint32_t *ids = &b->ids[nd->first];
        while (nt < count && ids[nt] < num_tris) nt++;
        uint32_t first_block = (uint32_t)t->num_blocks, num_blocks = (nt + TRI_BLOCK_WIDTH - 1) / TRI_BLOCK_WIDTH;
        for (uint32_t k = 0; k < num_blocks; k++) {
            TriangleBlock *blk = &t->blocks[t->num_blocks++];
            for (int lane = 0; lane < TRI_BLOCK_WIDTH; lane++) {
                uint32_t j = TRI_BLOCK_WIDTH * k + (uint32_t)lane;
                if (j >= nt) {
                    /* NaN vertices fail every comparison of the test (t > t_min too). */
                    for (int v = 0; v < 3; v++)
                        for (int a = 0; a < 3; a++) blk->v[v][a][lane] = NAN;
                    blk->id[lane] = TRI_BLOCK_NO_PRIM;
                    continue;
                }
                const int32_t *vi = &g->tri_indices[3 * ids[j]];
                for (int v = 0; v < 3; v++) {
                    Vec3 p = g->positions[vi[v]]; /* the vertices list.c tests: bit-identical results */
                    blk->v[v][0][lane] = p.x;
                    blk->v[v][1][lane] = p.y;
                    blk->v[v][2][lane] = p.z;
                }
                blk->id[lane] = ids[j];
            }
        }
        if (count == nt) {
            nd->first = first_block;
            nd->flags = KD_LEAF | (num_blocks << 3);
            continue;
        }
        KdSphereLeaf *sl = &t->sphere_leaves[t->num_sphere_leaves];
        sl->first_block = first_block;
        sl->num_blocks = num_blocks;
        sl->first_sphere = (uint32_t)t->num_spheres;
        sl->first_shape = (uint32_t)t->num_shape_ids;
        for (uint32_t j = nt; j < count; j++) {
            if (ids[j] >= shape_base) { t->shape_ids[t->num_shape_ids++] = ids[j]; continue; }
            const Sphere *sp = &g->spheres[ids[j] - num_tris];
            t->spheres[t->num_spheres++] = (KdSphere){sp->center, sp->radius, ids[j]};
        }
        sl->num_spheres = (uint32_t)t->num_spheres - sl->first_sphere;
        sl->num_shapes = (uint32_t)t->num_shape_ids - sl->first_shape;
        nd->first = (uint32_t)t->num_sphere_leaves++;
        nd->flags = KD_LEAF | KD_LEAF_SPHERES;
    }
    return true;
}

/* Flags the children of inner nodes that are empty leaves and drops those leaves from the
 * node array (keeping the depth-first order): the traversal never descends into a child
 * flagged empty, so most of a tree built with the empty-space bonus (whose leaves are
 * mostly empty) costs neither node fetches nor cache space. Returns false on OOM. */
static bool drop_empty_leaves(KdTree *t)
{
    int n = t->num_nodes;
    uint32_t *new_index = malloc((size_t)n * sizeof *new_index);
    if (!new_index) return false;
    uint32_t kept = 0;
    for (int i = 0; i < n; i++) {
        new_index[i] = kept;
        /* The root is kept even when empty: the tree has at least one primitive. */
        if (i == 0 || t->nodes[i].flags != KD_LEAF) kept++;
    }
    for (int i = 0; i < n; i++) {
        KdNode nd = t->nodes[i];
        if (i > 0 && nd.flags == KD_LEAF) continue;
        if ((nd.flags & 3u) != KD_LEAF) {
            uint32_t above = nd.flags >> 4;
            uint32_t fl = nd.flags & 3u;
            if (t->nodes[i + 1].flags == KD_LEAF) fl |= KD_EMPTY_BELOW; /* no blocks, no spheres */
            if (t->nodes[above].flags == KD_LEAF) fl |= KD_EMPTY_ABOVE;
            nd.flags = fl | (new_index[above] << 4);
        }
        t->nodes[new_index[i]] = nd;
    }
    free(new_index);
    t->num_nodes = (int)kept;
    /* Give back the spare capacity (a failed shrink leaves the array as it was). */
    KdNode *nodes = realloc(t->nodes, (size_t)kept * sizeof *nodes);
    if (nodes) t->nodes = nodes;
    return true;
}

static bool vec_finite(Vec3 v) { return isfinite(v.x) && isfinite(v.y) && isfinite(v.z); }

/* Whether the triangle has zero area: (b - a) x (c - a) == 0, in double, where the
 * differences of floats and the products are exact for all but extreme exponent ranges.
 * Such a triangle has no surface; Moller-Trumbore's det is then zero only up to rounding,
 * and the t of a "hit" can put the point anywhere along the ray. */
static bool zero_area(Vec3 a, Vec3 b, Vec3 c)
{
    double ux = (double)b.x - (double)a.x, uy = (double)b.y - (double)a.y, uz = (double)b.z - (double)a.z;
    double vx = (double)c.x - (double)a.x, vy = (double)c.y - (double)a.y, vz = (double)c.z - (double)a.z;
    return uy * vz - uz * vy == 0.0 && uz * vx - ux * vz == 0.0 && ux * vy - uy * vx == 0.0;
}

CstStatus kdtree_build(KdTree *t, const AccelGeometry *geom, CstError *err)
{
    memset(t, 0, sizeof *t);
    t->bounds = bbox_empty();
    int nt = geom->num_tris, ns = geom->num_spheres, nsh = geom->num_shapes;
    int n = nt + ns + nsh;
    if (n == 0) return CST_OK;
    BBox *prim_box = malloc((size_t)n * sizeof *prim_box);
    uint8_t *side = malloc((size_t)n);
    EventLists E = {0};
    E.block = malloc((size_t)n * 6 * sizeof *E.block);
    Builder b = {geom, prim_box, side, t, NULL, 0, 0, 0, false, false};
    if (!prim_box || !side || !E.block) { free(E.block); goto oom; }

    /* The events of every primitive that is a surface: triangles of zero area (repeated
     * or collinear vertices) are never hit, by design; non-finite primitives neither
     * (their tests compare NaNs as false). */
    KdEvent *ev[3] = {E.block, E.block + 2 * (size_t)n, E.block + 4 * (size_t)n};
    int cnt[3] = {0, 0, 0}, used_tris = 0, used_spheres = 0;
    for (int i = 0; i < nt; i++) {
        const int32_t *k = &geom->tri_indices[3 * i];
        Vec3 a = geom->positions[k[0]], p1 = geom->positions[k[1]], p2 = geom->positions[k[2]];
        if (!vec_finite(a) || !vec_finite(p1) || !vec_finite(p2) || zero_area(a, p1, p2)) continue;
        prim_box[i] = bbox_add(bbox_add(bbox_add(bbox_empty(), a), p1), p2);
        push_events(ev, cnt, (uint32_t)i, prim_box[i]);
        t->bounds = bbox_union(t->bounds, prim_box[i]);
        used_tris++;
    }
    for (int j = 0; j < ns; j++) {
        const Sphere *sp = &geom->spheres[j];
        if (!vec_finite(sp->center) || !isfinite(sp->radius)) continue;
        /* c +- |r| rounded outward (the sphere test squares the radius: its sign is moot). */
        Vec3 c = sp->center;
        float r = fabsf(sp->radius);
        BBox box = {v3(nextafterf(c.x - r, -INFINITY), nextafterf(c.y - r, -INFINITY), nextafterf(c.z - r, -INFINITY)),
                    v3(nextafterf(c.x + r, INFINITY), nextafterf(c.y + r, INFINITY), nextafterf(c.z + r, INFINITY))};
        if (!vec_finite(box.min) || !vec_finite(box.max)) continue;
        prim_box[nt + j] = box;
        push_events(ev, cnt, (uint32_t)(nt + j), box);
        t->bounds = bbox_union(t->bounds, box);
        used_spheres++;
    }
    for (int j = 0; j < nsh; j++) { /* shapes by their padded boxes (shape_init) */
        BBox box = geom->shapes[j].bounds;
        if (!vec_finite(box.min) || !vec_finite(box.max)) continue;
        prim_box[nt + ns + j] = box;
        push_events(ev, cnt, (uint32_t)(nt + ns + j), box);
        t->bounds = bbox_union(t->bounds, box);
        used_spheres++;
    }
    int used = used_tris + used_spheres;
    if (used == 0) {
        free(E.block);
        free(prim_box);
        free(side);
        t->bounds = bbox_empty();
        return CST_OK; /* nothing can be hit: no nodes, every ray misses */
    }
    for (int a = 0; a < 3; a++) {
        E.ev[a] = ev[a];
        E.n[a] = cnt[a];
        sort_events(ev[a], (size_t)cnt[a]);
    }
    t->max_abs = maxf(v3_max_abs(t->bounds.min), v3_max_abs(t->bounds.max));
    /* pbrt's depth limit, 8 + 1.3 log2 N. */
    int depth = (int)lroundf(8.0f + 1.3f * log2f((float)used));
    t->max_depth = depth < KD_MAX_DEPTH ? depth : KD_MAX_DEPTH;
    b.cap_nodes = 2 * (size_t)used + 16;
    b.cap_ids = 2 * (size_t)used + 16;
    t->nodes = malloc((size_t)b.cap_nodes * sizeof *t->nodes);
    b.ids = malloc((size_t)b.cap_ids * sizeof *b.ids);
    if (!t->nodes || !b.ids) { free(E.block); goto oom; }

    build_node(&b, &E, used, t->bounds, 0); /* frees E.block */
    if (b.oom) goto oom;
    if (b.too_big) {
        free(prim_box);
        free(side);
        free(b.ids);
        kdtree_free(t);
        return cst_fail(err, CST_ERR_UNSUPPORTED, "kd-tree over %d primitives exceeds 2^28 nodes or 2^31 references",
                        n);
    }
    free(prim_box);
    free(side);
    prim_box = NULL;
    side = NULL;
    if (!store_leaves(t, &b) || !drop_empty_leaves(t)) goto oom;
    free(b.ids);
    return CST_OK;
oom:
    free(prim_box);
    free(side);
    free(b.ids);
    kdtree_free(t);
    return cst_fail(err, CST_ERR_OOM, "out of memory building the kd-tree over %d primitives", n);
}

void kdtree_free(KdTree *t)
{
    if (!t) return;
    free(t->nodes);
    free(t->blocks);
    free(t->spheres);
    free(t->sphere_leaves);
    free(t->shape_ids);
    memset(t, 0, sizeof *t);
}

size_t kdtree_memory_bytes(const KdTree *t)
{
    return (size_t)t->num_nodes * sizeof(KdNode) + (size_t)t->num_blocks * sizeof(TriangleBlock) +
           (size_t)t->num_spheres * sizeof(KdSphere) + (size_t)t->num_sphere_leaves * sizeof(KdSphereLeaf) +
           (size_t)t->num_shape_ids * sizeof(uint32_t);
}

/* ------------------------------------------------------------------ traversal */

/* Per-ray constants. With s the split, the ray leaves the near child's (margin-grown)
 * half-space at t = (s + near_off) * inv and enters the far child's at
 * (s + far_off) * inv. A zero direction component gives inv = +-inf and so t = +-inf on
 * the side of the slab the origin is on, or -inf/+inf (both children) inside it. */
typedef struct KdRay {
    float inv[3];
    float near_off[3], far_off[3];
    uint32_t near_above_mask[3]; /* all ones: the child above the plane comes first (d < 0 or -0) */
} KdRay;

typedef struct KdStackEntry {
    uint32_t node;
    float t0, t1;
} KdStackEntry;

/* Sets up q and clips the ray to the bounds grown by the margin. Returns false on a miss. */
static inline bool kd_ray_setup(const KdTree *t, const Ray *r, KdRay *q, float *t0, float *t1)
{
    const float o[3] = {r->o.x, r->o.y, r->o.z}, d[3] = {r->d.x, r->d.y, r->d.z};
    const float lo[3] = {t->bounds.min.x, t->bounds.min.y, t->bounds.min.z};
    const float hi[3] = {t->bounds.max.x, t->bounds.max.y, t->bounds.max.z};
    float w = KD_PLANE_MARGIN * (t->max_abs + v3_max_abs(r->o)) + FLT_MIN;
    float tn = r->t_min, tf = r->t_max;
    for (int a = 0; a < 3; a++) {
        float inv = 1.0f / d[a];
        uint32_t neg = signbit(d[a]) ? 1u : 0u;
        float sw = neg ? -w : w;
        q->inv[a] = inv;
        q->near_off[a] = sw - o[a];
        q->far_off[a] = -sw - o[a];
        q->near_above_mask[a] = 0u - neg;
        /* Slab test on the grown bounds, exact for zero components (as bbox_intersect). */
        float l = lo[a] - w, h = hi[a] + w;
        if (d[a] == 0.0f) {
            if (o[a] < l || o[a] > h) return false;
            continue;
        }
        float ta = (l - o[a]) * inv, tb = (h - o[a]) * inv;
        if (ta > tb) { float s = ta; ta = tb; tb = s; }
        tn = ta > tn ? ta : tn;
        tf = tb < tf ? tb : tf;
    }
    *t0 = tn;
    *t1 = tf + fabsf(tf) * (BBOX_EXIT_WIDEN - 1.0f); /* as bbox_intersect */
    return tn <= *t1;
}

/* The closest hit in a leaf; shortens r->t_max on a hit. */
static inline bool leaf_intersect(const KdTree *t, const KdNode *n, const TriangleRayBlock *q, Ray *r, Hit *hit)
{
    if (!(n->flags & KD_LEAF_SPHERES)) return triangle_blocks_intersect(&t->blocks[n->first], n->flags >> 3, q, r, hit);
    const KdSphereLeaf *l = &t->sphere_leaves[n->first];
    bool found = triangle_blocks_intersect(&t->blocks[l->first_block], l->num_blocks, q, r, hit);
    for (uint32_t i = 0; i < l->num_spheres; i++) {
        const KdSphere *sp = &t->spheres[l->first_sphere + i];
        float tt;
        if (!sphere_intersect(sp->center, sp->radius, r, &tt)) continue;
        r->t_max = tt;
        hit->t = tt; hit->u = 0.0f; hit->v = 0.0f; hit->prim = sp->id;
        found = true;
    }
    if (l->num_shapes)
        found |= shape_leaf_intersect(t->shapes, t->shape_base, &t->shape_ids[l->first_shape], l->num_shapes, r, hit);
    return found;
}

static inline bool leaf_occluded(const KdTree *t, const KdNode *n, const TriangleRayBlock *q, const Ray *r)
{
    if (!(n->flags & KD_LEAF_SPHERES)) return triangle_blocks_occluded(&t->blocks[n->first], n->flags >> 3, q, r);
    const KdSphereLeaf *l = &t->sphere_leaves[n->first];
    if (triangle_blocks_occluded(&t->blocks[l->first_block], l->num_blocks, q, r)) return true;
    for (uint32_t i = 0; i < l->num_spheres; i++) {
        const KdSphere *sp = &t->spheres[l->first_sphere + i];
        float tt;
        if (sphere_intersect(sp->center, sp->radius, r, &tt)) return true;
    }
    return l->num_shapes && shape_leaf_occluded(t->shapes, t->shape_base, &t->shape_ids[l->first_shape], l->num_shapes, r);
}

/* Descends from `node` with the ray interval [*t0, *t1] to the first non-empty leaf in
 * front-to-back order, pushing the far children that the interval also reaches (pbrt-v3's
 * KdTreeAccel::Intersect); returns KD_NONE when the interval meets only empty leaves below
 * `node`. Children flagged empty are never entered: where the near one is, the far one is
 * taken at once, unless it starts at or beyond `skip_from` (the caller's rule for popped
 * subtrees, which it would otherwise have been). The child above the plane is prefetched:
 * it is the next step or a later pop, and rarely in its parent's cache line. NaN plane
 * distances (0 * inf on a slab's face) compare false everywhere: both children. (Branch-
 * free variants of this loop ran primary rays 15-20% slower, random rays no faster, on the
 * bunny: the predicted branches keep the node fetches off the comparisons' latency.) */
static inline uint32_t descend(const KdTree *t, const KdRay *q, uint32_t node, float *t0, float *t1,
                               KdStackEntry *stack, int *sp, float skip_from)
{
    float tmin = *t0, tmax = *t1;
    for (;;) {
        const KdNode *n = &t->nodes[node];
        uint32_t f = n->flags, axis = f & 3u;
        if (axis == KD_LEAF) break;
        uint32_t below = node + 1, above = f >> 4;
        __builtin_prefetch(&t->nodes[above]);
        float s = n->split;
        float t_near_exit = (s + q->near_off[axis]) * q->inv[axis];
        float t_far_enter = (s + q->far_off[axis]) * q->inv[axis];
        uint32_t mask = q->near_above_mask[axis];
        uint32_t near = below ^ ((below ^ above) & mask);
        uint32_t far = near ^ below ^ above;
        bool near_empty = f & (KD_EMPTY_BELOW << (mask & 1u)), far_empty = f & (KD_EMPTY_ABOVE >> (mask & 1u));
        if (t_near_exit < tmin) { /* already past the near side */
            if (far_empty) return (uint32_t)KD_NONE;
            node = far;
            continue;
        }
        if (t_far_enter > tmax) { /* never reaches the far side */
            if (near_empty) return (uint32_t)KD_NONE;
            node = near;
            continue;
        }
        if (near_empty) {
            tmin = t_far_enter > tmin ? t_far_enter : tmin;
            if (tmin >= skip_from) return (uint32_t)KD_NONE;
            node = far;
            continue;
        }
        if (!far_empty) {
            stack[*sp].node = far;
            stack[*sp].t0 = t_far_enter > tmin ? t_far_enter : tmin;
            stack[*sp].t1 = tmax;
            (*sp)++;
        }
        node = near;
        tmax = t_near_exit < tmax ? t_near_exit : tmax;
    }
    *t0 = tmin;
    *t1 = tmax;
    return node;
}

/* Front to back; every hit shortens the ray, and a pending subtree is skipped when it
 * starts at or beyond the closest hit so far. A hit in a leaf is not cut at the leaf's
 * far end: a straddling primitive's hit beyond it is still a hit, and any closer one lies
 * in a cell that begins before it, which the traversal has not skipped. */
bool kdtree_intersect(const KdTree *t, const Ray *ray, Hit *hit)
{
    if (!t->nodes) return false;
    KdRay q;
    float t0, t1;
    if (!kd_ray_setup(t, ray, &q, &t0, &t1)) return false;
    TriangleRayBlock qt = triangle_block_ray_setup(ray);
    Ray r = *ray;
    KdStackEntry stack[KD_STACK];
    int sp = 0;
    uint32_t node = 0;
    bool found = false;
    for (;;) {
        node = descend(t, &q, node, &t0, &t1, stack, &sp, r.t_max);
        if (node != (uint32_t)KD_NONE) found |= leaf_intersect(t, &t->nodes[node], &qt, &r, hit);
        do {
            if (sp == 0) return found;
            sp--;
        } while (stack[sp].t0 >= r.t_max);
        node = stack[sp].node;
        t0 = stack[sp].t0;
        t1 = stack[sp].t1;
    }
}

bool kdtree_occluded(const KdTree *t, const Ray *ray)
{
    if (!t->nodes) return false;
    KdRay q;
    float t0, t1;
    if (!kd_ray_setup(t, ray, &q, &t0, &t1)) return false;
    TriangleRayBlock qt = triangle_block_ray_setup(ray);
    KdStackEntry stack[KD_STACK];
    int sp = 0;
    uint32_t node = 0;
    for (;;) {
        node = descend(t, &q, node, &t0, &t1, stack, &sp, INFINITY);
        if (node != (uint32_t)KD_NONE && leaf_occluded(t, &t->nodes[node], &qt, ray)) return true;
        if (sp == 0) return false;
        sp--;
        node = stack[sp].node;
        t0 = stack[sp].t0;
        t1 = stack[sp].t1;
    }
}
