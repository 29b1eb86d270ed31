/* The SAH kd-tree's own invariants (accel/kdtree.c), built through the acceleration
 * interface on the scenes of the acceleration conformance suite (unit/soup.h): children
 * laid out depth-first, splits strictly inside their cells, depth within the limit, leaf
 * storage back to back with the list's vertices bit for bit, zero-area triangles left out,
 * every primitive meeting a leaf's cell listed in it, split planes on an axis-aligned mesh's
 * grid lines. Hits against brute force, for every back end: test_accel_conformance. */
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

/* ------------------------------------------------------------------ scenes */

#include "unit/soup.h"

static void build(const Soup *s, AccelType type, Accel *a)
{
    CstError err = {0};
    AccelGeometry g = soup_geometry(s);
    if (accel_build(a, type, &g, &err) != CST_OK) fail_msg("%s build: %s", accel_type_name(type), err.msg);
    assert_int_equal(a->type, type);
}

/* ------------------------------------------------------------------ structure */

/* Whether triangle abc meets the box (Sutherland-Hodgman in double, boundary included). */
static bool triangle_meets_box(Vec3 a, Vec3 b, Vec3 c, BBox box)
{
    double poly[2][12][3];
    Vec3 in[3] = {a, b, c};
    for (int i = 0; i < 3; i++) {
        poly[0][i][0] = (double)in[i].x; poly[0][i][1] = (double)in[i].y; poly[0][i][2] = (double)in[i].z;
    }
    int n = 3, cur = 0;
    for (int pl = 0; pl < 6 && n > 0; pl++) {
        int axis = pl >> 1;
        bool lower = (pl & 1) == 0;
        double cc = (double)v3_get(lower ? box.min : box.max, axis);
        int m = 0;
        for (int i = 0; i < n; i++) {
            double *p = poly[cur][i], *q = poly[cur][(i + 1) % n];
            bool ip = lower ? p[axis] >= cc : p[axis] <= cc, iq = lower ? q[axis] >= cc : q[axis] <= cc;
            if (ip) { memcpy(poly[cur ^ 1][m], p, sizeof poly[0][0]); m++; }
            if (ip != iq) {
                double t = (cc - p[axis]) / (q[axis] - p[axis]);
                for (int k = 0; k < 3; k++) poly[cur ^ 1][m][k] = p[k] + t * (q[k] - p[k]);
                poly[cur ^ 1][m][axis] = cc;
                m++;
            }
        }
        n = m;
        cur ^= 1;
    }
    return n > 0;
}

static bool sphere_meets_box(const Sphere *sp, BBox box)
{
    double d2 = 0.0;
    for (int a = 0; a < 3; a++) {
        double c = (double)v3_get(sp->center, a), lo = (double)v3_get(box.min, a), hi = (double)v3_get(box.max, a);
        double e = c < lo ? lo - c : (c > hi ? c - hi : 0.0);
        d2 += e * e;
    }
    return d2 <= (double)sp->radius * (double)sp->radius;
}

/* A triangle the tree leaves out: zero area, (b - a) x (c - a) == 0 in double. */
/* The cell shrunk by a relative hair, so that touching a face does not count as meeting. */
static BBox shrink(BBox b)
{
    Vec3 e = v3_scale(v3_sub(b.max, b.min), 1e-4f);
    return (BBox){v3_add(b.min, e), v3_sub(b.max, e)};
}

typedef struct TreeStats {
    int leaves, empty_leaves, max_depth, refs;
    int blocks, spheres, sphere_leaves; /* leaf storage met so far, in node order */
    int *seen;                          /* by scene id: leaves listing the primitive */
} TreeStats;

/* Checks that every primitive meeting the inside of `cell` is among ids[0..count). */
static void check_coverage(const Soup *s, BBox cell, const uint32_t *ids, uint32_t count, int node)
{
    BBox inner = shrink(cell);
    int np = s->num_tris + s->num_spheres;
    for (int id = 0; id < np; id++) {
        bool meets;
        if (id < s->num_tris) {
            if (soup_tri_zero_area(s, id)) continue;
            meets = triangle_meets_box(s->pos[s->idx[3 * id]], s->pos[s->idx[3 * id + 1]], s->pos[s->idx[3 * id + 2]],
                                       inner);
        } else {
            meets = sphere_meets_box(&s->spheres[id - s->num_tris], inner);
        }
        if (!meets) continue;
        bool listed = false;
        for (uint32_t i = 0; i < count && !listed; i++) listed = ids[i] == (uint32_t)id;
        if (!listed) fail_msg("leaf under node %d: primitive %d meets the cell but is not listed", node, id);
    }
}

/* An empty leaf: not stored, flagged in its parent `node`. */
static void check_empty_leaf(const Soup *s, int node, BBox cell, int depth, bool full, TreeStats *ts)
{
    if (depth > ts->max_depth) ts->max_depth = depth;
    ts->leaves++;
    ts->empty_leaves++;
    if (full) check_coverage(s, cell, NULL, 0, node);
}

/* Walks the subtree at `node` with cell `cell`: children laid out depth-first (below =
 * node + 1 unless flagged empty, above next after the below subtree), every split strictly
 * inside its cell, depth within the limit; leaves non-empty (empty ones are flags of their
 * parent), their blocks and spheres consecutive in node order, lanes filled from the
 * first with ascending scene ids and the list's vertices bit for bit (unused lanes NaN),
 * spheres after the triangles; and every primitive that meets the inside of a leaf's cell
 * listed in that leaf (checked when `full`). Returns the index after the subtree. */
static int check_node(const KdTree *t, const Soup *s, int node, BBox cell, int depth, bool full, TreeStats *ts)
{
    assert_true(node >= 0 && node < t->num_nodes);
    assert_true(depth <= t->max_depth && depth <= KD_MAX_DEPTH);
    if (depth > ts->max_depth) ts->max_depth = depth;
    const KdNode *n = &t->nodes[node];
    uint32_t axis = n->flags & 3u;
    if (axis != KD_LEAF) {
        float sp = n->split;
        float lo = v3_get(cell.min, (int)axis), hi = v3_get(cell.max, (int)axis);
        if (!(sp > lo && sp < hi)) fail_msg("node %d: split %g on axis %u outside its cell (%g, %g)", node, (double)sp, axis, (double)lo, (double)hi);
        BBox cl = cell, cr = cell;
        if (axis == 0) { cl.max.x = sp; cr.min.x = sp; }
        else if (axis == 1) { cl.max.y = sp; cr.min.y = sp; }
        else { cl.max.z = sp; cr.min.z = sp; }
        bool below_empty = n->flags & KD_EMPTY_BELOW, above_empty = n->flags & KD_EMPTY_ABOVE;
        assert_false(below_empty && above_empty); /* every primitive goes to a side */
        int next = node + 1;
        if (below_empty) check_empty_leaf(s, node, cl, depth + 1, full, ts);
        else next = check_node(t, s, node + 1, cl, depth + 1, full, ts);
        if (above_empty) {
            check_empty_leaf(s, node, cr, depth + 1, full, ts);
            return next;
        }
        assert_int_equal((int)(n->flags >> 4), next);
        return check_node(t, s, next, cr, depth + 1, full, ts);
    }
    ts->leaves++;
    uint32_t first_block, num_blocks, first_sphere = 0, num_spheres = 0;
    if (n->flags & KD_LEAF_SPHERES) {
        assert_int_equal((int)n->first, ts->sphere_leaves);
        assert_true(n->first < (uint32_t)t->num_sphere_leaves);
        const KdSphereLeaf *l = &t->sphere_leaves[n->first];
        ts->sphere_leaves++;
        first_block = l->first_block;
        num_blocks = l->num_blocks;
        first_sphere = l->first_sphere;
        num_spheres = l->num_spheres;
        assert_true(num_spheres > 0);
        assert_int_equal((int)first_sphere, ts->spheres);
        assert_true((size_t)first_sphere + num_spheres <= (size_t)t->num_spheres);
    } else {
        first_block = n->first;
        num_blocks = n->flags >> 3;
        assert_true(num_blocks > 0);
    }
    assert_int_equal((int)first_block, ts->blocks);
    assert_true((size_t)first_block + num_blocks <= (size_t)t->num_blocks);
    ts->blocks += (int)num_blocks;
    ts->spheres += (int)num_spheres;
    static uint32_t ids[8192]; /* scene ids of the leaf's primitives */
    uint32_t count = 0;
    for (uint32_t b = 0; b < num_blocks; b++) {
        const TriangleBlock *blk = &t->blocks[first_block + b];
        for (int lane = 0; lane < TRI_BLOCK_WIDTH; lane++) {
            uint32_t id = blk->id[lane];
            if (id == TRI_BLOCK_NO_PRIM) {
                assert_true(b == num_blocks - 1 && lane > 0); /* padding only ends the last block */
                for (int k = 0; k < 3; k++)
                    for (int a = 0; a < 3; a++) assert_true(isnan(blk->v[k][a][lane]));
                continue;
            }
            assert_true(b == 0 || lane == 0 || blk->id[lane - 1] != TRI_BLOCK_NO_PRIM);
            assert_true(id < (uint32_t)s->num_tris);
            assert_true(count < 8192);
            ids[count++] = id;
            const int32_t *vi = &s->idx[3 * id];
            for (int k = 0; k < 3; k++) {
                Vec3 p = s->pos[vi[k]]; /* list's own vertices: bit-identical hits */
                float got[3] = {blk->v[k][0][lane], blk->v[k][1][lane], blk->v[k][2][lane]};
                assert_memory_equal(got, &p, sizeof got);
            }
        }
    }
    for (uint32_t i = 0; i < num_spheres; i++) {
        const KdSphere *sp = &t->spheres[first_sphere + i];
        assert_true(sp->id >= (uint32_t)s->num_tris && sp->id < (uint32_t)(s->num_tris + s->num_spheres));
        const Sphere *ref = &s->spheres[sp->id - (uint32_t)s->num_tris];
        assert_memory_equal(&sp->center, &ref->center, sizeof ref->center);
        assert_memory_equal(&sp->radius, &ref->radius, sizeof ref->radius);
        assert_true(count < 8192);
        ids[count++] = sp->id;
    }
    assert_true(count > 0);
    ts->refs += (int)count;
    for (uint32_t i = 0; i < count; i++) {
        if (i > 0) assert_true(ids[i] > ids[i - 1]); /* ascending scene ids: list's tie order */
        ts->seen[ids[i]]++;
    }
    if (full) check_coverage(s, cell, ids, count, node);
    return node + 1;
}

/* Checks the whole tree; `full` adds the O(leaves x primitives) coverage check. */
static TreeStats check_structure(const Accel *a, const Soup *s, bool full)
{
    const KdTree *t = &a->kdtree;
    int np = s->num_tris + s->num_spheres;
    TreeStats ts = {0};
    ts.seen = calloc((size_t)(np > 0 ? np : 1), sizeof *ts.seen);
    assert_non_null(ts.seen);
    if (t->num_nodes == 0) {
        assert_null(t->nodes);
    } else {
        assert_int_equal(check_node(t, s, 0, t->bounds, 0, full, &ts), t->num_nodes);
        /* Leaf storage is exactly the leaves', back to back. */
        assert_int_equal(ts.blocks, t->num_blocks);
        assert_int_equal(ts.spheres, t->num_spheres);
        assert_int_equal(ts.sphere_leaves, t->num_sphere_leaves);
        /* A full binary tree over all leaves, of which the empty ones are not stored. */
        assert_int_equal(t->num_nodes, 2 * ts.leaves - 1 - ts.empty_leaves);
    }
    /* The stored primitives: exactly the non-degenerate ones (zero-area triangles are
     * left out by design). */
    for (int id = 0; id < np; id++) {
        bool skippable = id < s->num_tris && soup_tri_zero_area(s, id);
        if (skippable && ts.seen[id] != 0) fail_msg("zero-area triangle %d is in a leaf", id);
        if (!skippable && ts.seen[id] == 0) fail_msg("primitive %d is in no leaf", id);
    }
    size_t expect = (size_t)t->num_nodes * sizeof(KdNode) + (size_t)t->num_blocks * sizeof(TriangleBlock) +
                    (size_t)t->num_spheres * sizeof(KdSphere) + (size_t)t->num_sphere_leaves * sizeof(KdSphereLeaf);
    assert_true(accel_memory_bytes(a) == expect);
    free(ts.seen);
    ts.seen = NULL;
    return ts;
}


static void report(const char *what, const Accel *kd, const TreeStats *ts)
{
    print_message("  %-28s nodes %6d leaves %6d (empty %5d) refs %6d depth %2d/%2d\n", what, kd->kdtree.num_nodes,
                  ts->leaves, ts->empty_leaves, ts->refs, ts->max_depth, kd->kdtree.max_depth);
}

/* Builds the kd-tree over s and checks it (`full`: the coverage check too). */
static TreeStats structure_of(const Soup *s, bool full, const char *what, Accel *kd)
{
    build(s, ACCEL_KDTREE, kd);
    TreeStats ts = check_structure(kd, s, full);
    report(what, kd, &ts);
    return ts;
}

/* ------------------------------------------------------------------ tests */

static void test_kdtree_empty(void **state)
{
    (void)state;
    Soup s = {0};
    Accel kd;
    TreeStats ts = structure_of(&s, true, "empty", &kd);
    assert_int_equal(ts.leaves, 0);
    accel_free(&kd);
}

/* Random soups (slivers; then needles) and mixed triangles and spheres; the coverage
 * check on the smaller ones. */
static void test_kdtree_structure_random(void **state)
{
    (void)state;
    const int sizes[] = {1, 2, 7, 100, 5000};
    for (int needles = 0; needles < 2; needles++)
        for (int k = 0; k < 5; k++) {
            Soup s = {0};
            Pcg32 rng;
            pcg32_seed(&rng, 1000u + (uint64_t)k, 3u);
            if (needles) soup_random_tris_needles(&s, &rng, sizes[k]);
            else soup_random_tris(&s, &rng, sizes[k]);
            char what[64];
            snprintf(what, sizeof what, "soup of %d%s", sizes[k], needles ? " with needles" : "");
            Accel kd;
            structure_of(&s, sizes[k] <= 100, what, &kd);
            accel_free(&kd);
            soup_free(&s);
        }
    const int tris[] = {0, 1, 300, 2000}, spheres[] = {1, 5, 300, 500};
    for (int needles = 0; needles < 2; needles++)
        for (int k = 0; k < 4; k++) {
            Soup s = {0};
            Pcg32 rng;
            pcg32_seed(&rng, 2000u + (uint64_t)k, 5u);
            if (needles) soup_random_tris_needles(&s, &rng, tris[k]);
            else soup_random_tris(&s, &rng, tris[k]);
            soup_random_spheres(&s, &rng, spheres[k]);
            if (needles && k == 3) s.spheres[0].radius = -s.spheres[0].radius;
            char what[64];
            snprintf(what, sizeof what, "%d tris%s + %d spheres", tris[k], needles ? " (needles)" : "", spheres[k]);
            Accel kd;
            structure_of(&s, tris[k] + spheres[k] <= 600, what, &kd);
            accel_free(&kd);
            soup_free(&s);
        }
}

/* The grid cubes of the conformance suite's mesh-plane rays: there are split planes on
 * grid lines for those rays to lie in. */
static void test_kdtree_split_planes(void **state)
{
    (void)state;
    const int grids[] = {4, 6};
    for (int gk = 0; gk < 2; gk++) {
        int g = grids[gk];
        Soup s = {0};
        soup_grid_cube(&s, g, 1.0f, v3(0.0f, 0.0f, 0.0f), true);
        char what[64];
        snprintf(what, sizeof what, "grid cube %dx%d", g, g);
        Accel kd;
        structure_of(&s, true, what, &kd);
        int on_grid = 0, inner = 0;
        for (int i = 0; i < kd.kdtree.num_nodes; i++) {
            const KdNode *n = &kd.kdtree.nodes[i];
            if ((n->flags & 3u) == KD_LEAF) continue;
            inner++;
            for (int gi = 0; gi <= g; gi++) on_grid += n->split == -1.0f + 2.0f * (float)gi / (float)g;
        }
        print_message("  grid cube %dx%d: %d of %d split planes on grid lines\n", g, g, on_grid, inner);
        assert_true(on_grid > 0);
        accel_free(&kd);
        soup_free(&s);
    }
}

/* Zero-area triangles among ordinary ones are left out of the tree; a scene of nothing
 * but zero-area triangles builds an empty tree. */
static void test_kdtree_zero_area(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 123u, 7u);
    Soup s = {0};
    soup_zero_area(&s, &rng);
    Accel kd;
    structure_of(&s, true, "800 zero-area + 400", &kd);
    accel_free(&kd);
    soup_free(&s);

    Soup z = {0};
    soup_reserve(&z, 30, 90, 0);
    for (int i = 0; i < 30; i++) {
        Vec3 a = rnd_v3(&rng, -1.0, 1.0), e = rnd_v3(&rng, -1.0, 1.0);
        soup_add_tri(&z, a, (i & 1) ? a : e, e);
    }
    structure_of(&z, true, "only zero-area", &kd);
    assert_int_equal(kd.kdtree.num_nodes, 0);
    accel_free(&kd);
    soup_free(&z);
}

/* Many coincident triangles: no split separates them, so one leaf holds them all (lowest
 * id first, as in list); triangles at exponentially growing distances, where the SAH keeps
 * cutting off empty space and one leaf block at a time, so the build runs into its depth
 * limit; the shadow-segment scene (random triangles, spheres and a grid cube). */
static void test_kdtree_structure_degenerate_builds(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 1u);
    Soup s = {0};
    soup_coincident(&s, &rng);
    Accel kd;
    structure_of(&s, true, "1000 identical + 30", &kd);
    accel_free(&kd);
    soup_free(&s);

    soup_exponential(&s, 250);
    TreeStats ts = structure_of(&s, true, "exponential spacing, 250", &kd);
    assert_int_equal(ts.max_depth, kd.kdtree.max_depth);
    accel_free(&kd);
    soup_free(&s);

    pcg32_seed(&rng, 4242u, 9u);
    soup_random_tris(&s, &rng, 1500);
    soup_random_spheres(&s, &rng, 60);
    soup_grid_cube(&s, 5, 1.0f, v3(0.0f, 0.0f, 0.0f), true);
    structure_of(&s, false, "segments scene", &kd);
    accel_free(&kd);
    soup_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kdtree_empty),
        cmocka_unit_test(test_kdtree_structure_random),
        cmocka_unit_test(test_kdtree_split_planes),
        cmocka_unit_test(test_kdtree_zero_area),
        cmocka_unit_test(test_kdtree_structure_degenerate_builds),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
