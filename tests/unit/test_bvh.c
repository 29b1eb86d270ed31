/* The BVH's own invariants (accel/bvh.c): the 8-wide node and leaf-block layout, exact
 * bounds, every primitive stored once and bit for bit, depth within the traversal stack,
 * on the scenes of the acceleration conformance suite (unit/soup.h); the node test against
 * an exact one; and the large-page allocator the BVH's array comes from. Hits against brute
 * force, for every back end: test_accel_conformance. */
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

#include "accel/bvh.h"
#include "core/memory.h"
#include "core/rng.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

/* ------------------------------------------------------------------ scenes */

#include "unit/soup.h"

static void soup_build(const Soup *s, Bvh *bvh)
{
    CstError err = {0};
    AccelGeometry g = soup_geometry(s);
    CstStatus st = bvh_build(bvh, &g, &err);
    if (st != CST_OK) fail_msg("bvh_build: %s", err.msg);
}

/* ------------------------------------------------------------------ structure */

/* Box of one primitive by scene id, as the builder computes it. */
static BBox prim_box(const Soup *s, int id)
{
    if (id < s->num_tris) {
        BBox pb = bbox_empty();
        for (int k = 0; k < 3; k++) pb = bbox_add(pb, s->pos[s->idx[3 * id + k]]);
        return pb;
    }
    const Sphere *sp = &s->spheres[id - s->num_tris];
    float r = fabsf(sp->radius); /* the builder's box: sphere_intersect squares the radius */
    BBox pb = {v3_sub(sp->center, v3s(r)), v3_add(sp->center, v3s(r))};
    return pb;
}

static bool box_contains(BBox outer, BBox inner)
{
    return inner.min.x >= outer.min.x && inner.min.y >= outer.min.y && inner.min.z >= outer.min.z &&
           inner.max.x <= outer.max.x && inner.max.y <= outer.max.y && inner.max.z <= outer.max.z;
}

static BBox slot_box(const BvhNode *n, int i)
{
    BBox b = {v3(n->bounds[0][i], n->bounds[2][i], n->bounds[4][i]), v3(n->bounds[1][i], n->bounds[3][i], n->bounds[5][i])};
    return b;
}

/* Unused block lanes carry TRI_BLOCK_NO_PRIM. */
static bool lane_used(const TriangleBlock *b, int l) { return b->id[l] != TRI_BLOCK_NO_PRIM; }

/* Marks the n units from `first` as used by one node or block: every unit of the array
 * belongs to exactly one of them. */
static void cover_units(const Bvh *bvh, int *cover, size_t first, size_t n)
{
    assert_true(first + n <= bvh_num_units(bvh));
    for (size_t u = first; u < first + n; u++) {
        if (cover[u] != 0) fail_msg("unit %zu is used twice", u);
        cover[u] = 1;
    }
}

/* Checks one leaf reference against its slot box: every triangle lane and sphere is a
 * scene primitive stored exactly as the scalar tests would see it, inside the box, and
 * the leaf holds one kind only. Counts the ids seen, the spheres used (seen_items) and
 * the units of the blocks (cover). */
static void check_leaf(const Bvh *bvh, const Soup *s, uint32_t ref, BBox box, int *seen_ids, int *seen_items,
                       int *cover)
{
    uint32_t first = bvh_ref_index(ref), count = bvh_ref_count(ref);
    assert_true(count >= 1 && count <= 8);
    if (ref & BVH_SPHERES) {
        assert_true((int)(first + count) <= bvh->num_spheres);
        for (uint32_t si = first; si < first + count; si++) {
            const BvhSphere *sp = &bvh->spheres[si];
            int id = (int)sp->id;
            assert_true(id >= s->num_tris && id < s->num_tris + s->num_spheres);
            seen_ids[id]++;
            seen_items[si]++;
            const Sphere *src = &s->spheres[id - s->num_tris];
            assert_true(sp->center.x == src->center.x && sp->center.y == src->center.y &&
                        sp->center.z == src->center.z && sp->radius == src->radius);
            if (!box_contains(box, prim_box(s, id))) fail_msg("leaf %#x: sphere %d outside its box", ref, id);
        }
        return;
    }
    cover_units(bvh, cover, first, (size_t)count * (sizeof(TriangleBlock) / BVH_UNIT));
    for (uint32_t bi = 0; bi < count; bi++) {
        const TriangleBlock *b = bvh_blocks(bvh, first) + bi;
        assert_true(lane_used(b, 0));
        for (int l = 0; l < TRI_BLOCK_WIDTH; l++) {
            /* packed: only the leaf's last block has unused lanes, at its end */
            if (!lane_used(b, l)) {
                assert_true(bi == count - 1);
                for (int m = l; m < TRI_BLOCK_WIDTH; m++) assert_false(lane_used(b, m));
                break;
            }
            int id = (int)b->id[l];
            assert_true(id >= 0 && id < s->num_tris);
            seen_ids[id]++;
            for (int k = 0; k < 3; k++) {
                Vec3 p = s->pos[s->idx[3 * id + k]];
                assert_true(b->v[k][0][l] == p.x && b->v[k][1][l] == p.y && b->v[k][2][l] == p.z);
            }
            if (!box_contains(box, prim_box(s, id))) fail_msg("leaf %#x: triangle %d outside its box", ref, id);
        }
    }
}

/* Checks the 8-wide tree below wide node `node` (its reference: a byte offset), whose own
 * box (its slot in the parent) is `box`: every slot is empty (inverted infinite bounds),
 * a leaf or a later wide node,
 * and each slot's box lies in its parent's and holds its primitives. Returns the depth
 * below. This mirrors the layout in bvh.h and must follow it when it changes. */
static int check_node(const Bvh *bvh, const Soup *s, int node, BBox box, int depth, int *seen_ids, int *seen_items,
                      int *cover)
{
    assert_true(node >= 0 && node % (int)BVH_UNIT == 0);
    cover_units(bvh, cover, (size_t)node / BVH_UNIT, sizeof(BvhNode) / BVH_UNIT);
    const BvhNode *n = bvh_node(bvh, (uint32_t)node);
    assert_true(((uintptr_t)n & 31u) == 0u);
    int d = depth, used = 0;
    for (int i = 0; i < BVH_WIDTH; i++) {
        BBox sb = slot_box(n, i);
        if (n->child[i] == BVH_EMPTY) {
            assert_true(sb.min.x == INFINITY && sb.min.y == INFINITY && sb.min.z == INFINITY);
            assert_true(sb.max.x == -INFINITY && sb.max.y == -INFINITY && sb.max.z == -INFINITY);
            continue;
        }
        used++;
        if (!box_contains(box, sb)) fail_msg("node %d slot %d: box outside its parent's", node, i);
        if (bvh_ref_is_leaf(n->child[i])) {
            check_leaf(bvh, s, n->child[i], sb, seen_ids, seen_items, cover);
            d = depth + 1 > d ? depth + 1 : d;
        } else {
            assert_true((int)n->child[i] > node); /* children are laid out after their parent */
            int dk = check_node(bvh, s, (int)n->child[i], sb, depth + 1, seen_ids, seen_items, cover);
            d = dk > d ? dk : d;
        }
    }
    assert_true(used >= 1);
    return d;
}

static int check_structure(const Bvh *bvh, const Soup *s)
{
    int n = s->num_tris + s->num_spheres;
    assert_int_equal(bvh->num_prims, n);
    if (n == 0) { assert_int_equal(bvh->num_nodes, 0); return 0; }
    assert_true(bvh->num_nodes >= 1 && bvh->num_nodes <= n);
    assert_true(bvh->num_leaves >= 1 && bvh->num_leaves <= n);
    assert_int_equal(bvh->num_spheres, s->num_spheres);
    int *ids = calloc((size_t)n, sizeof *ids);
    int *items = calloc((size_t)bvh->num_spheres + 1u, sizeof *items);
    int *cover = calloc(bvh_num_units(bvh), sizeof *cover);
    assert_non_null(ids);
    assert_non_null(items);
    assert_non_null(cover);
    BBox all = bbox_empty();
    for (int i = 0; i < n; i++) all = bbox_union(all, prim_box(s, i));
    assert_true(box_contains(bvh->bounds, all) && box_contains(all, bvh->bounds)); /* bounds are exact */
    BBox everything = {v3s(-INFINITY), v3s(INFINITY)};
    int depth = check_node(bvh, s, 0, everything, 0, ids, items, cover);
    for (int i = 0; i < bvh->num_spheres; i++)
        if (items[i] != 1) fail_msg("sphere %d is referenced %d times", i, items[i]);
    for (size_t u = 0; u < bvh_num_units(bvh); u++)
        if (cover[u] != 1) fail_msg("unit %zu belongs to no node or block", u);
    for (int i = 0; i < n; i++)
        if (ids[i] != 1) fail_msg("scene primitive %d appears %d times", i, ids[i]);
    free(ids);
    free(items);
    free(cover);
    /* Traversal keeps at most 7 siblings per level on its stack (bvh.c's BVH_STACK). */
    assert_true(7 * depth + 1 < 7 * (60 + 33) + 1);
    return depth;
}

/* ------------------------------------------------------------------ tests */

/* Builds the BVH over s and checks its structure; prints the node count and depth. */
static void structure_of(const Soup *s, const char *what)
{
    Bvh bvh;
    soup_build(s, &bvh);
    int depth = check_structure(&bvh, s);
    print_message("  %-30s prims %5d nodes %5d leaves %5d depth %2d\n", what, bvh.num_prims, bvh.num_nodes,
                  bvh.num_leaves, depth);
    bvh_free(&bvh);
}



/* The BVH's array comes from memory_alloc_large: aligned for its 64-byte lines, and large
 * requests on whole 2 MiB pages (the huge-page hint covers all of them), every byte usable. */
static void test_memory_alloc_large(void **state)
{
    (void)state;
    const size_t huge = (size_t)2 << 20;
    const size_t sizes[] = {1, 64, 1000, huge - 1, huge, 5 * huge + 3};
    for (size_t i = 0; i < sizeof sizes / sizeof sizes[0]; i++) {
        unsigned char *p = memory_alloc_large(sizes[i]);
        assert_non_null(p);
        assert_int_equal((uintptr_t)p % (sizes[i] >= huge ? huge : 64), 0);
        memset(p, 0xa5, sizes[i]);
        assert_int_equal(p[0], 0xa5);
        assert_int_equal(p[sizes[i] - 1], 0xa5);
        free(p);
    }
    assert_null(memory_alloc_large(SIZE_MAX - 16)); /* rounding up would wrap */
}

static void test_bvh_empty(void **state)
{
    (void)state;
    Soup s = {0};
    structure_of(&s, "empty");
    bvh_free(NULL);
}

/* ------------------------------------------------------------------ node test */

/* Whether the ray o + t d, t in [t_min, t_max], meets the closed box [lo, hi], decided
 * exactly: every entry and exit distance is a fraction (plane - o) / d whose numerator
 * and denominator are exact in binary128, and two are compared by cross-multiplying
 * (products of 48 significant bits and fewer fit its 113). Direction components must be
 * non-zero. */
static bool exact_slab(const float o[3], const float d[3], const float lo[3], const float hi[3], float t_min,
                       float t_max)
{
    __float128 nn = (__float128)t_min, nd = 1, fn = (__float128)t_max, fd = 1; /* entry nn / nd, exit fn / fd */
    for (int a = 0; a < 3; a++) {
        __float128 den = (__float128)fabsf(d[a]), sign = d[a] > 0.0f ? 1 : -1;
        __float128 n0 = ((__float128)lo[a] - (__float128)o[a]) * sign, n1 = ((__float128)hi[a] - (__float128)o[a]) * sign;
        if (n0 > n1) { __float128 t = n0; n0 = n1; n1 = t; }
        if (n0 * nd > nn * den) { nn = n0; nd = den; }
        if (n1 * fd < fn * den) { fn = n1; fd = den; }
    }
    return nn * fd <= fn * nd;
}

static void node_set(BvhNode *n, int slot, const float lo[3], const float hi[3])
{
    for (int a = 0; a < 3; a++) { n->bounds[2 * a][slot] = lo[a]; n->bounds[2 * a + 1][slot] = hi[a]; }
    n->child[slot] = 0u;
}

/* The node test against an exact one, for both its forms: rays from random origins aimed
 * exactly at corners, edges and faces of random boxes (flat ones too), where entry and
 * exit distances meet and rounding decides. A box the exact test hits must be hit (no
 * leaks: the exit widening, and the FMA form's outward-rounded constants, cover the
 * rounding); a box missed with 1e-4 to spare (scene size 16) must be missed (the
 * conservatism stays tiny); an empty slot never. */
static void test_bvh_node_test_exact(void **state)
{
    (void)state;
    Soup s = {0};
    soup_reserve(&s, 2, 6, 0);
    soup_add_tri(&s, v3(-8.0f, -8.0f, -8.0f), v3(8.0f, 8.0f, 8.0f), v3(8.0f, -8.0f, 8.0f));
    soup_add_tri(&s, v3(-8.0f, 8.0f, -8.0f), v3(8.0f, 8.0f, -8.0f), v3(-8.0f, -8.0f, 8.0f));
    Bvh bvh;
    soup_build(&s, &bvh);
    BvhNode *n = memory_alloc_large(sizeof *n);
    assert_non_null(n);
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 3u);
    long exact_hits[2] = {0, 0}, clear_misses[2] = {0, 0};
    bool fma_tested = false;
    for (int i = 0; i < 200000; i++) {
        float lo[BVH_WIDTH][3], hi[BVH_WIDTH][3];
        const int used = 1 + (int)(pcg32_next(&rng) % BVH_WIDTH);
        for (int k = 0; k < BVH_WIDTH; k++) {
            for (int a = 0; a < 3; a++) {
                float x = (float)rnd(&rng, -8, 8), y = (float)rnd(&rng, -8, 8);
                if (pcg32_next(&rng) % 8u == 0u) y = x; /* flat, as an axis-aligned triangle's */
                lo[k][a] = fminf(x, y);
                hi[k][a] = fmaxf(x, y);
            }
            if (k < used) {
                node_set(n, k, lo[k], hi[k]);
            } else {
                const float inf[3] = {INFINITY, INFINITY, INFINITY}, ninf[3] = {-INFINITY, -INFINITY, -INFINITY};
                node_set(n, k, inf, ninf); /* empty, as the build leaves it */
            }
        }
        /* Aim at a corner, a point on an edge or on a face of one used slot; a third of
         * the targets are pushed 2e-4 outward on one axis instead. */
        const int k = (int)(pcg32_next(&rng) % (uint32_t)used);
        float p[3];
        for (int a = 0; a < 3; a++) p[a] = (pcg32_next(&rng) & 1u) ? hi[k][a] : lo[k][a];
        const int free_axes = (int)(pcg32_next(&rng) % 3u);
        for (int f = 0; f < free_axes; f++) {
            const int a = (int)(pcg32_next(&rng) % 3u);
            p[a] = (float)rnd(&rng, (double)lo[k][a], (double)hi[k][a]);
        }
        if (pcg32_next(&rng) % 3u == 0u) {
            const int a = (int)(pcg32_next(&rng) % 3u);
            p[a] = p[a] == hi[k][a] ? p[a] + 2e-4f : p[a] - 2e-4f;
        }
        float o[3], d[3];
        double dd[3], len = 0.0;
        for (int a = 0; a < 3; a++) {
            o[a] = (float)rnd(&rng, -30, 30);
            dd[a] = (double)p[a] - (double)o[a];
            len += dd[a] * dd[a];
        }
        len = sqrt(len);
        bool zero = false;
        for (int a = 0; a < 3; a++) {
            d[a] = (float)(dd[a] / len);
            zero |= d[a] == 0.0f;
        }
        if (zero) continue;
        Ray r = ray_make(v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f,
                         (pcg32_next(&rng) & 1u) ? INFINITY : (float)rnd(&rng, 1, 80));
        for (int form = 0; form < 2; form++) {
            unsigned mask;
            if (!bvh_node_test(&bvh, n, &r, form == 1, &mask)) {
                assert_int_equal(form, 1); /* the sub-mul form always answers */
                continue;
            }
            fma_tested |= form == 1;
            if (mask >> used)
                fail_msg("ray %d, %s form: an empty slot was hit (mask 0x%x)", i, form ? "FMA" : "sub-mul", mask);
            for (int j = 0; j < used; j++) {
                const bool hit = (mask >> j) & 1u;
                if (exact_slab(o, d, lo[j], hi[j], r.t_min, r.t_max)) {
                    exact_hits[form]++;
                    if (!hit)
                        fail_msg("ray %d, %s form: box %d [%.9g %.9g %.9g]-[%.9g %.9g %.9g] is met exactly but "
                                 "was missed (o %.9g %.9g %.9g, d %.9g %.9g %.9g)",
                                 i, form ? "FMA" : "sub-mul", j, (double)lo[j][0], (double)lo[j][1], (double)lo[j][2],
                                 (double)hi[j][0], (double)hi[j][1], (double)hi[j][2], (double)o[0], (double)o[1],
                                 (double)o[2], (double)d[0], (double)d[1], (double)d[2]);
                } else {
                    float glo[3], ghi[3];
                    for (int a = 0; a < 3; a++) { glo[a] = lo[j][a] - 1e-4f; ghi[a] = hi[j][a] + 1e-4f; }
                    if (!exact_slab(o, d, glo, ghi, r.t_min, r.t_max)) {
                        clear_misses[form]++;
                        if (hit) fail_msg("ray %d, %s form: box %d, missed by more than 1e-4, was hit", i,
                                          form ? "FMA" : "sub-mul", j);
                    }
                }
            }
        }
    }
    print_message("  exact hits %ld / %ld, clear misses %ld / %ld (sub-mul / FMA)\n", exact_hits[0], exact_hits[1],
                  clear_misses[0], clear_misses[1]);
    assert_true(exact_hits[0] > 100000 && clear_misses[0] > 100000);
    if (fma_tested)
        assert_true(exact_hits[1] == exact_hits[0] && clear_misses[1] == clear_misses[0]);
    else
        print_message("  note: the FMA form is not compiled in (no FMA in this build); only the sub-mul form tested\n");

    /* o * (1 / d) overflows only for an origin coordinate beyond about 3e18 with the
     * direction's component (near) zero, a ray that never reaches the scene: the FMA form
     * declines it, and the sub-mul form answers, a miss. */
    const float blo[3] = {-1.0f, -1.0f, -1.0f}, bhi[3] = {1.0f, 1.0f, 1.0f};
    for (int k = 0; k < BVH_WIDTH; k++) node_set(n, k, blo, bhi);
    Ray far = ray_make(v3(-5.0f, 1e19f, 0.0f), v3(1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
    unsigned mask = 1u;
    assert_false(bvh_node_test(&bvh, n, &far, true, &mask));
    assert_true(bvh_node_test(&bvh, n, &far, false, &mask));
    assert_int_equal(mask, 0u);
    far.o.y = 0.5f; /* the same ray in the box's slab: every slot hit, in both forms */
    for (int form = 0; form < 2; form++) {
        mask = 0u;
        if (bvh_node_test(&bvh, n, &far, form == 1, &mask)) assert_int_equal(mask, (1u << BVH_WIDTH) - 1u);
    }
    free(n);
    bvh_free(&bvh);
    soup_free(&s);
}

/* Random soups (slivers; then needles) and mixed triangles and spheres. */
static void test_bvh_structure_random(void **state)
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
            structure_of(&s, what);
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
            structure_of(&s, what);
            soup_free(&s);
        }
}

/* Identical triangles share a centroid, so binning cannot split them and the builder
 * falls back to splitting the range in the middle; triangles whose boxes share a centre;
 * triangles at exponentially growing distances, where every binned SAH split peels off one
 * primitive, driving the build to its depth limit and the median fallback below it. */
static void test_bvh_structure_degenerate_builds(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 1u);
    Soup s = {0};
    soup_coincident(&s, &rng);
    structure_of(&s, "1000 identical + 30");
    soup_free(&s);
    pcg32_seed(&rng, 78u, 1u);
    soup_same_centroid(&s, &rng, 500);
    structure_of(&s, "500 same-centroid");
    soup_free(&s);
    soup_exponential(&s, 150);
    structure_of(&s, "exponential spacing, 150");
    soup_free(&s);
    soup_exponential(&s, 250);
    structure_of(&s, "exponential spacing, 250");
    soup_free(&s);
}

/* Axis-aligned meshes (node boxes with faces on grid lines) and the closed meshes. */
static void test_bvh_structure_meshes(void **state)
{
    (void)state;
    for (int g = 4; g <= 6; g += 2) {
        Soup s = {0};
        soup_grid_cube(&s, g, 1.0f, v3(0.0f, 0.0f, 0.0f), true);
        structure_of(&s, g == 4 ? "grid cube 4x4" : "grid cube 6x6");
        soup_free(&s);
    }
    for (int k = 0; k < SOUP_CLOSED_MESHES; k++) {
        Soup s = {0};
        char name[64];
        soup_closed_mesh(&s, k, name, sizeof name);
        structure_of(&s, name);
        soup_free(&s);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_memory_alloc_large),
        cmocka_unit_test(test_bvh_empty),
        cmocka_unit_test(test_bvh_structure_random),
        cmocka_unit_test(test_bvh_structure_degenerate_builds),
        cmocka_unit_test(test_bvh_structure_meshes),
        cmocka_unit_test(test_bvh_node_test_exact),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
