/* Photon map build and queries: a median-split kd-tree (Bentley, CACM 1975; Jensen 2001,
 * ch. 6) stored implicitly in array order, built by median selection, with bucket leaves
 * (Friedman, Bentley & Finkel, ACM TOMS 1977), queried by an iterative near-first descent
 * with an explicit stack. */
#include "integrators/photon_map.h"

#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

enum {
    /* Ranges halve at every level, so the depth is below log2(count) <= 30, and the
     * descent's stack holds at most one pending subtree per level (each pushed subtree is
     * a sibling of the path below it). */
    PM_STACK = 64,
    /* Below this many elements selection finishes with an insertion sort. */
    PM_SELECT_SMALL = 16
};

/* Why bucket leaves in array order rather than Jensen's heap-ordered tree with one photon
 * per node: the hot radius query (about 50 photons per density estimate) was bound by
 * memory latency on node visits. A leaf of <= 16 nodes is four contiguous cache lines
 * scanned without branching on the tree, replacing the bottom four levels of descent,
 * and the in-order layout keeps every subtree contiguous, where heap order (children
 * 2i+1, 2i+2) scatters the deep levels across the array. 1M uniform photons, radius
 * holding about 50, one thread, with a visitor summing power: heap order 0.1-0.16 M
 * queries/s on random points and 0.3-0.46 M/s along a coherent walk; this layout
 * 0.15-0.18 and 0.55-0.73 M/s (ranges: a shared, noisy 2-vCPU VM). Leaves of <= 8 or <= 32
 * were within that noise at 5, 50 and 200 photons per query. */
_Static_assert(PHOTON_MAP_LEAF_SIZE >= 1, "a leaf holds at least one photon");

/* ------------------------------------------------------------------ build */

static inline float key(const PhotonNode *e, int axis) { return e->p[axis]; }

static inline void swap_nodes(PhotonNode *a, PhotonNode *b)
{
    PhotonNode t = *a;
    *a = *b;
    *b = t;
}

/* nth_element: reorders a[0..n) so that a[k] is the element a sort by key would put there,
 * with keys <= a[k]'s before it and >= after. Hoare's FIND (CACM 1961) with a median-of-
 * three pivot, which is linear on sorted, reversed and constant input; Hoare partitioning
 * splits runs of equal keys down the middle, so many coincident photons cost O(n) rather
 * than the O(n^2) of a Lomuto partition. Expected O(n); no recursion. */
static void select_nth(PhotonNode *a, size_t n, size_t k, int axis)
{
    size_t lo = 0, hi = n - 1; /* inclusive; k stays in [lo, hi] */
    while (hi - lo >= PM_SELECT_SMALL) {
        size_t mid = lo + (hi - lo) / 2;
        if (key(&a[mid], axis) < key(&a[lo], axis)) swap_nodes(&a[mid], &a[lo]);
        if (key(&a[hi], axis) < key(&a[lo], axis)) swap_nodes(&a[hi], &a[lo]);
        if (key(&a[hi], axis) < key(&a[mid], axis)) swap_nodes(&a[hi], &a[mid]);
        /* a[lo] <= pivot <= a[hi]: both scans below stop inside [lo, hi] without bounds
         * checks, and the split point j ends in [lo, hi - 1], so both parts shrink. */
        float pivot = key(&a[mid], axis);
        size_t i = lo, j = hi;
        for (;;) {
            while (key(&a[i], axis) < pivot) i++;
            while (pivot < key(&a[j], axis)) j--;
            if (i >= j) break;
            swap_nodes(&a[i], &a[j]);
            i++;
            j--;
        }
        if (k <= j) hi = j;
        else lo = j + 1;
    }
    for (size_t i = lo + 1; i <= hi; i++) {
        PhotonNode x = a[i];
        size_t j = i;
        for (; j > lo && key(&x, axis) < key(&a[j - 1], axis); j--) a[j] = a[j - 1];
        a[j] = x;
    }
}

/* Arranges a[0..n) as a subtree (see PhotonMap). Each level costs O(n) (one bounds pass,
 * one selection) and there are log2(n / PHOTON_MAP_LEAF_SIZE) levels: O(n log n).
 * Recursion depth is the tree's depth, below 30. */
static void balance(PhotonNode *a, size_t n)
{
    if (n <= PHOTON_MAP_LEAF_SIZE) return;
    float lo[3] = {a[0].p[0], a[0].p[1], a[0].p[2]};
    float hi[3] = {lo[0], lo[1], lo[2]};
    for (size_t i = 1; i < n; i++)
        for (int k = 0; k < 3; k++) {
            lo[k] = minf(lo[k], a[i].p[k]);
            hi[k] = maxf(hi[k], a[i].p[k]);
        }
    /* Split the largest extent of this subset's bounds (Jensen 2001, ch. 6): the cells
     * stay close to cubes, which keeps the number of cells a query sphere overlaps low.
     * Equal extents (coincident or coplanar photons) take the lowest axis. */
    int axis = 0;
    for (int k = 1; k < 3; k++)
        if (hi[k] - lo[k] > hi[axis] - lo[axis]) axis = k;
    size_t m = n / 2;
    select_nth(a, n, m, axis);
    a[m].meta = (a[m].meta & ~3u) | (uint32_t)axis;
    balance(a, m);
    balance(a + m + 1, n - m - 1);
}

CstStatus photon_map_build(PhotonMap *map, const Photon *photons, size_t count, CstError *err)
{
    memset(map, 0, sizeof *map);
    if (count == 0) return CST_OK;
    if (!photons) return cst_fail(err, CST_ERR_INVALID_ARG, "photon map: %zu photons but no array", count);
    if (count > PHOTON_MAP_MAX_COUNT)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "photon map: %zu photons, at most %zu supported", count,
                        PHOTON_MAP_MAX_COUNT);
    map->nodes = malloc(count * sizeof *map->nodes);
    map->photons = malloc(count * sizeof *map->photons);
    if (!map->nodes || !map->photons) {
        photon_map_free(map);
        return cst_fail(err, CST_ERR_OOM, "photon map: out of memory for %zu photons (%zu bytes)", count,
                        count * (sizeof(PhotonNode) + sizeof(Photon)));
    }
    /* Selection moves the 16-byte nodes, which carry their input index; the 48-byte
     * photons are gathered once at the end. */
    for (size_t i = 0; i < count; i++) {
        map->nodes[i].p[0] = photons[i].pos.x;
        map->nodes[i].p[1] = photons[i].pos.y;
        map->nodes[i].p[2] = photons[i].pos.z;
        map->nodes[i].meta = (uint32_t)i << 2 | PHOTON_MAP_NO_SPLIT;
    }
    balance(map->nodes, count);
    for (size_t i = 0; i < count; i++) map->photons[i] = photons[map->nodes[i].meta >> 2];
    map->count = count;
    return CST_OK;
}

void photon_map_free(PhotonMap *map)
{
    if (!map) return;
    free(map->nodes);
    free(map->photons);
    memset(map, 0, sizeof *map);
}

size_t photon_map_count(const PhotonMap *map) { return map ? map->count : 0; }

size_t photon_map_index(const PhotonMap *map, const Photon *ph)
{
    return map->nodes[ph - map->photons].meta >> 2;
}

/* ------------------------------------------------------------------ queries */

static inline float node_dist2(const PhotonNode *nd, Vec3 x)
{
    return photon_dist2(x, v3(nd->p[0], nd->p[1], nd->p[2]));
}

/* Pruning a subtree by the squared distance to its splitting plane, delta^2 > r^2, is exact
 * in float, not just in real arithmetic: a photon q beyond the plane has |x_a - q_a| >=
 * |x_a - split| after rounding too (rounding is monotonic), and adding the other two
 * non-negative squares cannot make photon_dist2() smaller. So the queries find precisely
 * the photons a brute-force loop over photon_dist2() finds. */

size_t photon_map_radius(const PhotonMap *map, Vec3 x, float radius, PhotonVisitFn visit, void *ctx)
{
    if (!map || map->count == 0 || !(radius >= 0.0f)) return 0;
    const float r2 = radius * radius;
    const float q[3] = {x.x, x.y, x.z};
    const PhotonNode *nodes = map->nodes;
    const Photon *photons = map->photons;
    struct { size_t lo, hi; } stack[PM_STACK];
    int sp = 0;
    size_t lo = 0, hi = map->count, found = 0;
    for (;;) {
        if (hi - lo <= PHOTON_MAP_LEAF_SIZE) {
            for (size_t i = lo; i < hi; i++) {
                float d2 = node_dist2(&nodes[i], x);
                if (d2 <= r2) {
                    if (visit) visit(ctx, &photons[i], d2);
                    found++;
                }
            }
            if (sp == 0) break;
            sp--;
            lo = stack[sp].lo;
            hi = stack[sp].hi;
            continue;
        }
        size_t m = lo + (hi - lo) / 2;
        const PhotonNode *nd = &nodes[m];
        float d2 = node_dist2(nd, x);
        if (d2 <= r2) {
            if (visit) visit(ctx, &photons[m], d2);
            found++;
        }
        uint32_t axis = nd->meta & 3u;
        float delta = q[axis] - nd->p[axis];
        /* The side holding x is always searched: there is nothing to prune it by. */
        bool far_too = delta * delta <= r2;
        if (delta <= 0.0f) {
            if (far_too) { stack[sp].lo = m + 1; stack[sp].hi = hi; sp++; }
            hi = m;
        } else {
            if (far_too) { stack[sp].lo = lo; stack[sp].hi = m; sp++; }
            lo = m + 1;
        }
    }
    return found;
}

/* The query's total order, distance then input index, as one integer: squared distances
 * are non-negative and not NaN, and the bits of such floats order as unsigned integers do,
 * so the comparisons below are single integer compares without a lookup for the index. */
typedef struct KnnEntry {
    uint64_t key;  /* float bits of dist2 << 32 | input index: unique, no two entries tie */
    uint32_t slot; /* position in the map's arrays */
} KnnEntry;

static inline uint64_t knn_key(float d2, uint32_t meta)
{
    uint32_t bits;
    memcpy(&bits, &d2, sizeof bits);
    return (uint64_t)bits << 32 | (meta >> 2);
}

static inline float knn_key_dist2(uint64_t key)
{
    uint32_t bits = (uint32_t)(key >> 32);
    float d2;
    memcpy(&d2, &bits, sizeof d2);
    return d2;
}

/* Max-heap on key: heap[0] is the last of the k best so far, the one to evict. */
static void knn_sift_down(KnnEntry *heap, int size, int i)
{
    KnnEntry e = heap[i];
    for (;;) {
        int c = 2 * i + 1;
        if (c >= size) break;
        c += c + 1 < size && heap[c + 1].key > heap[c].key;
        if (heap[c].key <= e.key) break;
        heap[i] = heap[c];
        i = c;
    }
    heap[i] = e;
}

static void knn_sift_up(KnnEntry *heap, int i)
{
    KnnEntry e = heap[i];
    while (i > 0) {
        int parent = (i - 1) / 2;
        if (heap[parent].key >= e.key) break;
        heap[i] = heap[parent];
        i = parent;
    }
    heap[i] = e;
}

/* Offers photon `slot` at squared distance d2 to the k best; returns the new bound. */
static inline float knn_offer(const PhotonNode *nodes, KnnEntry *heap, int *size, int k, float bound, float d2,
                              size_t slot)
{
    if (!(d2 <= bound)) return bound;
    KnnEntry e = {knn_key(d2, nodes[slot].meta), (uint32_t)slot};
    if (*size < k) {
        heap[*size] = e;
        knn_sift_up(heap, (*size)++);
        return *size == k ? knn_key_dist2(heap[0].key) : bound;
    }
    if (e.key >= heap[0].key) return bound;
    heap[0] = e;
    knn_sift_down(heap, *size, 0);
    return knn_key_dist2(heap[0].key);
}

int photon_map_knn(const PhotonMap *map, Vec3 x, int k, float max_radius, const Photon **out,
                   float *dist2_out)
{
    if (k > PHOTON_MAP_MAX_K) return -1;
    if (k <= 0 || !map || map->count == 0 || !(max_radius >= 0.0f)) return 0;
    /* As locate_photons in Jensen 2001: the search radius starts at max_radius and
     * shrinks to the k-th best distance once k photons are held. */
    float bound = max_radius * max_radius;
    const float q[3] = {x.x, x.y, x.z};
    const PhotonNode *nodes = map->nodes;
    KnnEntry heap[PHOTON_MAP_MAX_K];
    int size = 0;
    struct {
        size_t lo, hi;
        float d2_plane; /* re-checked on pop: the bound may have shrunk since the push */
    } stack[PM_STACK];
    int sp = 0;
    size_t lo = 0, hi = map->count;
    for (;;) {
        if (hi - lo <= PHOTON_MAP_LEAF_SIZE) {
            for (size_t i = lo; i < hi; i++)
                bound = knn_offer(nodes, heap, &size, k, bound, node_dist2(&nodes[i], x), i);
            while (sp > 0 && stack[sp - 1].d2_plane > bound) sp--;
            if (sp == 0) break;
            sp--;
            lo = stack[sp].lo;
            hi = stack[sp].hi;
            continue;
        }
        size_t m = lo + (hi - lo) / 2;
        const PhotonNode *nd = &nodes[m];
        bound = knn_offer(nodes, heap, &size, k, bound, node_dist2(nd, x), m);
        uint32_t axis = nd->meta & 3u;
        float delta = q[axis] - nd->p[axis];
        float d2_plane = delta * delta;
        /* Not pruned at d2_plane == bound: a photon there at exactly the k-th distance with
         * a lower input index still belongs in the result. */
        bool far_too = d2_plane <= bound;
        if (far_too) {
            stack[sp].lo = delta <= 0.0f ? m + 1 : lo;
            stack[sp].hi = delta <= 0.0f ? hi : m;
            stack[sp].d2_plane = d2_plane;
            sp++;
        }
        if (delta <= 0.0f) hi = m;
        else lo = m + 1;
    }
    /* Heap sort: pop the last into the end of the output. */
    for (int n = size; n > 0; n--) {
        out[n - 1] = &map->photons[heap[0].slot];
        if (dist2_out) dist2_out[n - 1] = knn_key_dist2(heap[0].key);
        heap[0] = heap[n - 1];
        knn_sift_down(heap, n - 1, 0);
    }
    return size;
}
