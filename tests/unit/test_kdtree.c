/* The SAH kd-tree (accel/kdtree.c) against the brute-force `list` back end, both built
 * through the acceleration interface: closest hits and occlusion on random soups, mixed
 * triangles and spheres, rays lying in the planes of an axis-aligned mesh, degenerate and
 * coincident triangles, empty geometry, finite segments; and the built tree's invariants. */
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

/* ------------------------------------------------------------------ scenes */

#include "unit/soup.h"

/* The cube [-1, 1]^3 with each face an n x n grid of quads (two triangles each), grid
 * coordinates exact in float, vertices shared within a face. */
static void soup_grid_cube(Soup *s, int n)
{
    int verts = 6 * (n + 1) * (n + 1), tris = 12 * n * n;
    soup_reserve(s, s->num_tris + tris, s->num_verts + verts, s->num_spheres);
    for (int axis = 0; axis < 3; axis++)
        for (int side = -1; side <= 1; side += 2) {
            int base = s->num_verts;
            for (int j = 0; j <= n; j++)
                for (int i = 0; i <= n; i++) {
                    float c[3];
                    c[axis] = (float)side;
                    c[(axis + 1) % 3] = -1.0f + 2.0f * (float)i / (float)n;
                    c[(axis + 2) % 3] = -1.0f + 2.0f * (float)j / (float)n;
                    s->pos[s->num_verts++] = v3(c[0], c[1], c[2]);
                }
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    int v00 = base + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
                    int q[6] = {v00, v10, v11, v00, v11, v01};
                    if ((i + j) & 1) { q[2] = v01; q[3] = v10; q[4] = v11; q[5] = v01; }
                    for (int k = 0; k < 6; k++) s->idx[3 * s->num_tris + k] = q[k];
                    s->num_tris += 2;
                }
        }
}

static void build(const Soup *s, AccelType type, Accel *a)
{
    CstError err = {0};
    AccelGeometry g = soup_geometry(s);
    if (accel_build(a, type, &g, &err) != CST_OK) fail_msg("%s build: %s", accel_type_name(type), err.msg);
    assert_int_equal(a->type, type);
}

/* Builds kd-tree and list over s through the acceleration interface. */
static void build_both(const Soup *s, Accel *kd, Accel *list)
{
    build(s, ACCEL_KDTREE, kd);
    build(s, ACCEL_LIST, list);
}

/* ------------------------------------------------------------------ reference */

/* One primitive by id, as list.c tests it. */
static bool prim_hit(const Soup *s, int id, const Ray *r, float *t, float *u, float *v)
{
    if (id < s->num_tris) {
        Vec3 a = s->pos[s->idx[3 * id]], b = s->pos[s->idx[3 * id + 1]], c = s->pos[s->idx[3 * id + 2]];
        TriangleRay tr = triangle_ray_setup(r->d);
        return triangle_intersect_watertight(&tr, r, a, b, c, t, u, v);
    }
    const Sphere *sp = &s->spheres[id - s->num_tris];
    *u = *v = 0.0f;
    return sphere_intersect(sp->center, sp->radius, r, t);
}

static uint32_t fbits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

typedef struct D3 { double x, y, z; } D3;
static D3 d3(Vec3 v) { return (D3){(double)v.x, (double)v.y, (double)v.z}; }
static D3 d3_sub(D3 a, D3 b) { return (D3){a.x - b.x, a.y - b.y, a.z - b.z}; }
static D3 d3_madd(D3 a, D3 b, double s) { return (D3){a.x + b.x * s, a.y + b.y * s, a.z + b.z * s}; }
static double d3_dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }

/* Distance from p to triangle abc (Ericson, Real-Time Collision Detection, 5.1.5). */
static double point_triangle_distance(D3 p, D3 a, D3 b, D3 c)
{
    D3 ab = d3_sub(b, a), ac = d3_sub(c, a), ap = d3_sub(p, a), q;
    double d1 = d3_dot(ab, ap), d2 = d3_dot(ac, ap);
    if (d1 <= 0.0 && d2 <= 0.0) { q = a; goto done; }
    D3 bp = d3_sub(p, b);
    double d3v = d3_dot(ab, bp), d4 = d3_dot(ac, bp);
    if (d3v >= 0.0 && d4 <= d3v) { q = b; goto done; }
    double vc = d1 * d4 - d3v * d2;
    if (vc <= 0.0 && d1 >= 0.0 && d3v <= 0.0) { q = d3_madd(a, ab, d1 / (d1 - d3v)); goto done; }
    D3 cp = d3_sub(p, c);
    double d5 = d3_dot(ab, cp), d6 = d3_dot(ac, cp);
    if (d6 >= 0.0 && d5 <= d6) { q = c; goto done; }
    double vb = d5 * d2 - d1 * d6;
    if (vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0) { q = d3_madd(a, ac, d2 / (d2 - d6)); goto done; }
    double va = d3v * d6 - d5 * d4;
    if (va <= 0.0 && (d4 - d3v) >= 0.0 && (d5 - d6) >= 0.0) {
        q = d3_madd(b, d3_sub(c, b), (d4 - d3v) / ((d4 - d3v) + (d5 - d6)));
        goto done;
    }
    double den = va + vb + vc;
    if (!(den != 0.0)) { /* degenerate: nearest of the three edges' end points is enough here */
        double da = d3_dot(ap, ap), db = d3_dot(bp, bp), dc = d3_dot(cp, cp);
        return sqrt(fmin(da, fmin(db, dc)));
    }
    q = d3_madd(d3_madd(a, ab, vb / den), ac, vc / den);
done:;
    D3 e = d3_sub(p, q);
    return sqrt(d3_dot(e, e));
}

/* True if the point o + t d of primitive id's hit lies off the primitive's surface by more
 * than 4 ulps of its coordinates. Moller-Trumbore's t is ill-conditioned for rays grazing
 * a triangle's plane (det -> 0), worst on slivers, and can put the point well off the
 * triangle; the kd-tree, whose cells hold only the part of a triangle inside them
 * (perfect splits), may then never test the triangle in the cell where that point lies. */
static bool hit_off_prim(const Soup *s, int id, const Ray *r, float t)
{
    D3 p = d3_madd(d3(r->o), d3(r->d), (double)t);
    double mag = fmax(fabs(p.x), fmax(fabs(p.y), fabs(p.z)));
    double tol = 4.0 * 0x1p-23 * mag + 1e-30;
    if (id < s->num_tris) {
        D3 a = d3(s->pos[s->idx[3 * id]]), b = d3(s->pos[s->idx[3 * id + 1]]), c = d3(s->pos[s->idx[3 * id + 2]]);
        return point_triangle_distance(p, a, b, c) > tol;
    }
    const Sphere *sp = &s->spheres[id - s->num_tris];
    D3 e = d3_sub(p, d3(sp->center));
    return fabs(sqrt(d3_dot(e, e)) - fabs((double)sp->radius)) > tol;
}

/* Brute force's closest hit among the hits that lie on their primitive. */
static bool brute_intersect_on_prim(const Soup *s, const Ray *ray, Hit *hit)
{
    Ray r = *ray;
    bool found = false;
    for (int id = 0; id < s->num_tris + s->num_spheres; id++) {
        float t, u, v;
        if (prim_hit(s, id, &r, &t, &u, &v) && !hit_off_prim(s, id, &r, t)) {
            r.t_max = t;
            hit->t = t; hit->u = u; hit->v = v; hit->prim = (uint32_t)id;
            found = true;
        }
    }
    return found;
}

typedef struct Stats { long rays, hits, ties, occluded, off_prim; } Stats;

static void fail_ray(const char *what, int i, const Ray *r, const char *msg, bool k, const Hit *hk, bool l,
                     const Hit *hl)
{
    fail_msg("%s ray %d: %s; kdtree %s prim %u t %.9g, list %s prim %u t %.9g; o = (%a, %a, %a), "
             "d = (%a, %a, %a), t in (%a, %a)",
             what, i, msg, k ? "hit" : "miss", k ? hk->prim : 0u, k ? (double)hk->t : 0.0, l ? "hit" : "miss",
             l ? hl->prim : 0u, l ? (double)hl->t : 0.0, (double)r->o.x, (double)r->o.y, (double)r->o.z,
             (double)r->d.x, (double)r->d.y, (double)r->d.z, (double)r->t_min, (double)r->t_max);
}

/* Checks one ray. The kd-tree's closest hit must be list's bit for bit (t, u, v and
 * primitive); another primitive only for an exact tie (its own t, tested alone, is the
 * same float). Occlusion must equal list's. The one exception: list's closest hit lies
 * off its primitive (hit_off_prim); the kd-tree may skip it, and must then return a
 * genuine hit no farther than every on-primitive hit (and occlusion iff some hit is
 * left). Such rays are counted in st->off_prim and the first few printed. */
static void check_ray(const Accel *kd, const Accel *list, const Soup *s, const Ray *r, Stats *st,
                      const char *what, int i)
{
    Hit hk = {0}, hl = {0};
    bool k = accel_intersect(kd, r, &hk);
    bool l = accel_intersect(list, r, &hl);
    st->rays++;
    st->hits += l;
    bool same = k == l && (!l || fbits(hk.t) == fbits(hl.t));
    if (same && l && hk.prim != hl.prim) {
        float t, u, v;
        if (!prim_hit(s, (int)hk.prim, r, &t, &u, &v) || fbits(t) != fbits(hl.t))
            fail_ray(what, i, r, "different primitive, not a tie", k, &hk, l, &hl);
        st->ties++;
    } else if (same && l && (fbits(hk.u) != fbits(hl.u) || fbits(hk.v) != fbits(hl.v))) {
        fail_ray(what, i, r, "barycentrics differ", k, &hk, l, &hl);
    }
    bool ok = accel_occluded(kd, r), ol = accel_occluded(list, r);
    st->occluded += ok;
    if (same && ok == ol) return;

    if (!l || !hit_off_prim(s, (int)hl.prim, r, hl.t))
        fail_ray(what, i, r, same ? "occluded differs" : "closest hits differ", k, &hk, l, &hl);
    Hit hc = {0};
    bool c = brute_intersect_on_prim(s, r, &hc);
    if (k) {
        float t, u, v;
        if (!prim_hit(s, (int)hk.prim, r, &t, &u, &v) || fbits(t) != fbits(hk.t))
            fail_ray(what, i, r, "kdtree hit is not a hit of its primitive", k, &hk, l, &hl);
        if (c && hc.t < hk.t) fail_ray(what, i, r, "kdtree missed a closer on-primitive hit", k, &hk, l, &hl);
    } else if (c) {
        fail_ray(what, i, r, "kdtree missed an on-primitive hit", k, &hk, l, &hl);
    }
    if (ok && !ol) fail_ray(what, i, r, "kdtree occluded without any hit", k, &hk, l, &hl);
    if (!ok && c) fail_ray(what, i, r, "kdtree occluded missed an on-primitive hit", k, &hk, l, &hl);
    if (st->off_prim++ < 3)
        print_message("  note: %s ray %d: list's hit on prim %u at t = %.9g lies off the primitive; the kd-tree "
                      "skipped it: %s prim %u t %.9g\n",
                      what, i, hl.prim, (double)hl.t, k ? "hit" : "miss", k ? hk.prim : 0u, k ? (double)hk.t : 0.0);
}

/* Random rays against s (bounds b): origins in the bounds grown by half their size on
 * each side (inside and outside) or, for half the rays, placed to pass through a random
 * point of a random primitive; directions uniform, axis-parallel (exact zeros of either
 * sign) or in a coordinate plane (one exact zero); t intervals from 0 or 1e-4 to inf or a
 * finite segment end. */
static void check_random_rays(const Accel *kd, const Accel *list, const Soup *s, Pcg32 *rng, int count, Stats *st,
                              const char *what)
{
    BBox b = kd->bounds;
    if (!(b.min.x <= b.max.x)) b = (BBox){v3s(-1.0f), v3s(1.0f)};
    Vec3 ext = v3_sub(b.max, b.min);
    float diag = v3_length(ext);
    if (!(diag > 0.0f)) diag = 1.0f;
    int n = s->num_tris + s->num_spheres;
    for (int i = 0; i < count; i++) {
        float fx = (float)rnd(rng, -0.5, 1.5), fy = (float)rnd(rng, -0.5, 1.5), fz = (float)rnd(rng, -0.5, 1.5);
        Vec3 o = v3(b.min.x + ext.x * fx, b.min.y + ext.y * fy, b.min.z + ext.z * fz);
        Vec3 d;
        uint32_t kind = pcg32_next(rng) % 4u;
        if (kind == 0u) {
            float dd[3];
            uint32_t bits = pcg32_next(rng);
            for (int a = 0; a < 3; a++) dd[a] = (bits >> (3 + a)) & 1u ? -0.0f : 0.0f;
            dd[bits % 3u] = (bits >> 8) & 1u ? -1.0f : 1.0f;
            d = v3(dd[0], dd[1], dd[2]);
        } else if (kind == 1u) {
            Vec3 rd = rnd_dir(rng);
            float dd[3] = {rd.x, rd.y, rd.z};
            uint32_t bits = pcg32_next(rng);
            dd[bits % 3u] = (bits >> 4) & 1u ? -0.0f : 0.0f;
            d = v3_normalize(v3(dd[0], dd[1], dd[2]));
        } else {
            d = rnd_dir(rng);
        }
        if (n > 0 && (pcg32_next(rng) & 1u)) {
            int id = (int)(pcg32_next(rng) % (uint32_t)n);
            Vec3 target;
            if (id < s->num_tris) {
                Vec3 p0 = s->pos[s->idx[3 * id]], p1 = s->pos[s->idx[3 * id + 1]], p2 = s->pos[s->idx[3 * id + 2]];
                float bu = pcg32_float(rng), bv = pcg32_float(rng);
                if (bu + bv > 1.0f) { bu = 1.0f - bu; bv = 1.0f - bv; }
                target = v3_add(p0, v3_add(v3_scale(v3_sub(p1, p0), bu), v3_scale(v3_sub(p2, p0), bv)));
            } else {
                const Sphere *sp = &s->spheres[id - s->num_tris];
                target = v3_madd(sp->center, rnd_dir(rng), 0.9f * sp->radius);
            }
            o = v3_madd(target, d, -(float)rnd(rng, 0.0, 1.0) * diag);
        }
        float t_min = (pcg32_next(rng) & 1u) ? 0.0f : 1e-4f;
        float t_max = (pcg32_next(rng) & 1u) ? INFINITY : (float)rnd(rng, 0.0, 1.5) * diag;
        Ray r = ray_make(o, d, t_min, t_max);
        check_ray(kd, list, s, &r, st, what, i);
    }
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
static bool tri_zero_area(const Soup *s, int id)
{
    D3 a = d3(s->pos[s->idx[3 * id]]), b = d3(s->pos[s->idx[3 * id + 1]]), c = d3(s->pos[s->idx[3 * id + 2]]);
    D3 u = d3_sub(b, a), v = d3_sub(c, a);
    return u.y * v.z - u.z * v.y == 0.0 && u.z * v.x - u.x * v.z == 0.0 && u.x * v.y - u.y * v.x == 0.0;
}

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
            if (tri_zero_area(s, id)) continue;
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
        bool skippable = id < s->num_tris && tri_zero_area(s, id);
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

static void report(const char *what, const Accel *kd, const TreeStats *ts, const Stats *st)
{
    print_message("  %-26s nodes %6d leaves %6d (empty %5d) refs %6d depth %2d/%2d  rays %ld hits %ld ties %ld "
                  "occluded %ld off-prim %ld\n",
                  what, kd->kdtree.num_nodes, ts->leaves, ts->empty_leaves, ts->refs, ts->max_depth,
                  kd->kdtree.max_depth, st->rays, st->hits, st->ties, st->occluded, st->off_prim);
}

/* ------------------------------------------------------------------ tests */

static void test_kdtree_empty(void **state)
{
    (void)state;
    Soup s = {0};
    Accel kd, list;
    build_both(&s, &kd, &list);
    TreeStats ts = check_structure(&kd, &s, true);
    assert_int_equal(ts.leaves, 0);
    Pcg32 rng;
    pcg32_seed(&rng, 1u, 1u);
    for (int i = 0; i < 1000; i++) {
        Vec3 d = rnd_dir(&rng); /* the direction first: GCC's order of the arguments this replaced */
        Ray r = ray_make(rnd_v3(&rng, -10.0, 10.0), d, 0.0f, INFINITY);
        Hit h = {0};
        assert_false(accel_intersect(&kd, &r, &h));
        assert_false(accel_occluded(&kd, &r));
    }
    accel_free(&kd);
    accel_free(&list);
    accel_free(&kd); /* a freed Accel is accepted again */
}

static void test_kdtree_random_soups(void **state)
{
    (void)state;
    const int sizes[] = {1, 2, 7, 100, 5000};
    const int rays[] = {20000, 20000, 20000, 20000, 8000};
    for (int k = 0; k < 5; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 1000u + (uint64_t)k, 3u);
        soup_random_tris(&s, &rng, sizes[k]);
        Accel kd, list;
        build_both(&s, &kd, &list);
        TreeStats ts = check_structure(&kd, &s, sizes[k] <= 100);
        Stats st = {0};
        char what[64];
        snprintf(what, sizeof what, "soup of %d", sizes[k]);
        check_random_rays(&kd, &list, &s, &rng, rays[k], &st, what);
        report(what, &kd, &ts, &st);
        assert_true(st.hits > st.rays / 100); /* the rays do meet the geometry */
        assert_true(st.off_prim <= st.rays / 1000);
        accel_free(&kd);
        accel_free(&list);
        soup_free(&s);
    }
}

static void test_kdtree_mixed_triangles_spheres(void **state)
{
    (void)state;
    const int tris[] = {0, 1, 300, 2000}, spheres[] = {1, 5, 300, 500};
    for (int k = 0; k < 4; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 2000u + (uint64_t)k, 5u);
        soup_random_tris(&s, &rng, tris[k]);
        soup_random_spheres(&s, &rng, spheres[k]);
        Accel kd, list;
        build_both(&s, &kd, &list);
        TreeStats ts = check_structure(&kd, &s, tris[k] + spheres[k] <= 600);
        Stats st = {0};
        char what[64];
        snprintf(what, sizeof what, "%d tris + %d spheres", tris[k], spheres[k]);
        check_random_rays(&kd, &list, &s, &rng, 10000, &st, what);
        report(what, &kd, &ts, &st);
        assert_true(st.hits > st.rays / 100);
        accel_free(&kd);
        accel_free(&list);
        soup_free(&s);
    }
}

/* Rays lying exactly in the planes of an axis-aligned mesh, where the kd-tree's split
 * planes are: the grid cube's vertices are on multiples of 1/4 (or 1/3, rounded), origins
 * are on grid lines outside and inside the cube, directions axis-parallel with exact zero
 * components of both signs, or in a grid plane (one exact zero component). */
static void test_kdtree_rays_in_split_planes(void **state)
{
    (void)state;
    const int grids[] = {4, 6};
    for (int gk = 0; gk < 2; gk++) {
        int g = grids[gk];
        Soup s = {0};
        soup_grid_cube(&s, g);
        Accel kd, list;
        build_both(&s, &kd, &list);
        TreeStats ts = check_structure(&kd, &s, true);
        /* There are split planes on grid lines for the rays below to lie in. */
        int on_grid = 0, inner = 0;
        for (int i = 0; i < kd.kdtree.num_nodes; i++) {
            const KdNode *n = &kd.kdtree.nodes[i];
            if ((n->flags & 3u) == KD_LEAF) continue;
            inner++;
            for (int gi = 0; gi <= g; gi++) on_grid += n->split == -1.0f + 2.0f * (float)gi / (float)g;
        }
        print_message("  grid cube %dx%d: %d of %d split planes on grid lines\n", g, g, on_grid, inner);
        assert_true(on_grid > 0);
        Stats st = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 9u, (uint64_t)g);
        int i = 0;
        for (int axis = 0; axis < 3; axis++)
            for (int sgn = 0; sgn < 4; sgn++) /* direction sign x sign of the zero components */
                for (int gi = 0; gi <= g; gi++)
                    for (int gj = 0; gj <= g; gj++) {
                        float z0 = (sgn & 2) ? -0.0f : 0.0f;
                        float dd[3] = {z0, z0, z0}, oo[3];
                        dd[axis] = (sgn & 1) ? -1.0f : 1.0f;
                        oo[axis] = (sgn & 1) ? 3.0f : -3.0f;
                        oo[(axis + 1) % 3] = -1.0f + 2.0f * (float)gi / (float)g;
                        oo[(axis + 2) % 3] = -1.0f + 2.0f * (float)gj / (float)g;
                        Ray r = ray_make(v3(oo[0], oo[1], oo[2]), v3(dd[0], dd[1], dd[2]), 0.0f, INFINITY);
                        check_ray(&kd, &list, &s, &r, &st, "axis ray on grid lines", i++);
                        r.t_min = 2.5f; /* from inside the cube's slab */
                        check_ray(&kd, &list, &s, &r, &st, "axis ray on grid lines, t_min inside", i++);
                        oo[axis] = 0.0f; /* starting inside the cube, on grid lines */
                        r = ray_make(v3(oo[0], oo[1], oo[2]), v3(dd[0], dd[1], dd[2]), 0.0f, INFINITY);
                        check_ray(&kd, &list, &s, &r, &st, "axis ray from inside", i++);
                    }
        /* Rays in a grid plane: one coordinate on a grid line, that direction component +-0,
         * the other two random; origins inside and outside. */
        for (int j = 0; j < 6000; j++) {
            int axis = (int)(pcg32_next(&rng) % 3u);
            float c = -1.0f + 2.0f * (float)(pcg32_next(&rng) % (uint32_t)(g + 1)) / (float)g;
            Vec3 o = rnd_v3(&rng, (j & 1) ? -0.99 : -3.0, (j & 1) ? 0.99 : 3.0);
            Vec3 d = rnd_dir(&rng);
            float oo[3] = {o.x, o.y, o.z}, dd[3] = {d.x, d.y, d.z};
            oo[axis] = c;
            dd[axis] = (pcg32_next(&rng) & 1u) ? -0.0f : 0.0f;
            Vec3 dn = v3_normalize(v3(dd[0], dd[1], dd[2]));
            float dn3[3] = {dn.x, dn.y, dn.z};
            dn3[axis] = dd[axis]; /* keep the sign of the zero */
            Ray r = ray_make(v3(oo[0], oo[1], oo[2]), v3(dn3[0], dn3[1], dn3[2]), 0.0f,
                             (j % 3 == 0) ? (float)rnd(&rng, 0.5, 4.0) : INFINITY);
            check_ray(&kd, &list, &s, &r, &st, "ray in a grid plane", j);
        }
        char what[64];
        snprintf(what, sizeof what, "grid cube %dx%d", g, g);
        report(what, &kd, &ts, &st);
        assert_true(st.hits > st.rays / 4);
        assert_int_equal(st.off_prim, 0);
        accel_free(&kd);
        accel_free(&list);
        soup_free(&s);
    }
}

/* Zero-area triangles (repeated vertices, all three equal, collinear) among ordinary
 * ones: the build must cope, and they must never be hit. Moller-Trumbore does "hit" some of
 * them (det is zero only up to rounding when v1 == v2 or the vertices are collinear), so
 * the oracle is list over the same scene with each zero-area triangle collapsed to a point
 * (an exactly zero edge: det == 0 for every ray), which keeps the primitive ids. */
static void test_kdtree_degenerate_triangles(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 123u, 7u);
    Soup s = {0};
    soup_reserve(&s, 1200, 3600, 0);
    for (int i = 0; i < 800; i++) {
        Vec3 a = rnd_v3(&rng, -5.0, 5.0), b = v3_madd(a, rnd_v3(&rng, -1.0, 1.0), 1.0f);
        switch (i % 5) {
        case 0: soup_add_tri(&s, a, a, b); break;
        case 1: soup_add_tri(&s, a, b, a); break;
        case 2: soup_add_tri(&s, a, b, b); break;
        case 3: soup_add_tri(&s, a, a, a); break;
        default: { /* collinear, exactly: sixteenths, so every sum below is exact */
            Vec3 g = v3(floorf(16.0f * a.x) / 16.0f, floorf(16.0f * a.y) / 16.0f, floorf(16.0f * a.z) / 16.0f);
            float sy = (float)(int)(pcg32_next(&rng) % 17u) / 16.0f; /* y first: GCC's order */
            float sx = (float)(int)(pcg32_next(&rng) % 17u) / 16.0f;
            Vec3 step = v3(sx, sy, 1.0f / 16.0f);
            soup_add_tri(&s, g, v3_add(g, step), v3_madd(g, step, (i & 1) ? 2.0f : -1.0f));
            break;
        }
        }
    }
    int degenerate = s.num_tris;
    soup_random_tris(&s, &rng, 400);
    Soup c = {0}; /* the oracle's scene */
    soup_reserve(&c, s.num_tris, s.num_verts, 0);
    memcpy(c.pos, s.pos, (size_t)s.num_verts * sizeof *c.pos);
    memcpy(c.idx, s.idx, (size_t)(3 * s.num_tris) * sizeof *c.idx);
    c.num_tris = s.num_tris;
    c.num_verts = s.num_verts;
    int zero_area = 0;
    for (int id = 0; id < s.num_tris; id++)
        if (tri_zero_area(&s, id)) { c.idx[3 * id + 1] = c.idx[3 * id + 2] = c.idx[3 * id]; zero_area++; }
    assert_int_equal(zero_area, degenerate);
    Accel kd, list, list_raw;
    build(&s, ACCEL_KDTREE, &kd);
    build(&c, ACCEL_LIST, &list);
    build(&s, ACCEL_LIST, &list_raw);
    TreeStats ts = check_structure(&kd, &s, true);
    Stats st = {0};
    check_random_rays(&kd, &list, &c, &rng, 10000, &st, "degenerate");
    long raw_hits = 0, aimed = 0;
    for (int i = 0; i < 5000; i++) { /* rays aimed at the degenerate triangles */
        int id = (int)(pcg32_next(&rng) % (uint32_t)degenerate);
        Vec3 p = s.pos[s.idx[3 * id + (i % 3)]];
        Vec3 d = rnd_dir(&rng);
        Ray r = ray_make(v3_madd(p, d, -3.0f), d, 0.0f, INFINITY);
        check_ray(&kd, &list, &c, &r, &st, "at a degenerate triangle", i);
        Hit h = {0};
        if (accel_intersect(&kd, &r, &h) && tri_zero_area(&s, (int)h.prim))
            fail_msg("ray %d hit triangle %u, which has zero area", i, h.prim);
        raw_hits += accel_intersect(&list_raw, &r, &h) && tri_zero_area(&s, (int)h.prim);
        aimed++;
    }
    report("800 degenerate + 400", &kd, &ts, &st);
    print_message("  (list over the raw scene hits a zero-area triangle on %ld of %ld aimed rays)\n", raw_hits, aimed);
    accel_free(&kd);
    accel_free(&list);
    accel_free(&list_raw);
    soup_free(&s);
    soup_free(&c);

    /* Nothing but zero-area triangles: an empty tree, every ray misses. */
    Soup z = {0};
    soup_reserve(&z, 30, 90, 0);
    for (int i = 0; i < 30; i++) {
        Vec3 a = rnd_v3(&rng, -1.0, 1.0), b = rnd_v3(&rng, -1.0, 1.0);
        soup_add_tri(&z, a, (i & 1) ? a : b, b);
    }
    build(&z, ACCEL_KDTREE, &kd);
    check_structure(&kd, &z, true);
    assert_int_equal(kd.kdtree.num_nodes, 0);
    for (int i = 0; i < 2000; i++) {
        Vec3 p = z.pos[z.idx[3 * (i % 30)]];
        Vec3 d = rnd_dir(&rng);
        Ray r = ray_make(v3_madd(p, d, -3.0f), d, 0.0f, INFINITY);
        Hit h = {0};
        assert_false(accel_intersect(&kd, &r, &h));
        assert_false(accel_occluded(&kd, &r));
    }
    accel_free(&kd);
    soup_free(&z);
}

/* Many coincident triangles: no split separates them, so one leaf holds them all; hits on
 * the copies tie exactly and the lowest id in a leaf wins, as in list. */
static void test_kdtree_coincident_triangles(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 77u, 1u);
    Soup s = {0};
    soup_reserve(&s, 1030, 3090, 0);
    Vec3 a = v3(-1.0f, -1.0f, 0.3f), b = v3(1.5f, -0.5f, -0.2f), c = v3(0.1f, 1.2f, 0.1f);
    for (int i = 0; i < 1000; i++) soup_add_tri(&s, a, b, c);
    soup_random_tris(&s, &rng, 30);
    Accel kd, list;
    build_both(&s, &kd, &list);
    TreeStats ts = check_structure(&kd, &s, true);
    Stats st = {0};
    check_random_rays(&kd, &list, &s, &rng, 5000, &st, "1000 identical");
    for (int i = 0; i < 2000; i++) {
        float bu = (float)rnd(&rng, 0.05, 0.9), bv = (float)rnd(&rng, 0.05, 0.95 - (double)bu);
        Vec3 p = v3_add(a, v3_add(v3_scale(v3_sub(b, a), bu), v3_scale(v3_sub(c, a), bv)));
        Vec3 d = rnd_dir(&rng);
        Ray r = ray_make(v3_madd(p, d, -5.0f), d, 0.0f, INFINITY);
        check_ray(&kd, &list, &s, &r, &st, "at the identical triangles", i);
    }
    report("1000 identical + 30", &kd, &ts, &st);
    accel_free(&kd);
    accel_free(&list);
    soup_free(&s);
}

/* Triangles at exponentially growing distances: the SAH keeps cutting off empty space and
 * one leaf block of triangles at a time, so the build runs into its depth limit. */
static void test_kdtree_deep_build(void **state)
{
    (void)state;
    Soup s = {0};
    soup_reserve(&s, 250, 750, 0);
    for (int i = 0; i < 250; i++) {
        float x = powf(1.4f, (float)i);
        soup_add_tri(&s, v3(x, 0.0f, 0.0f), v3(x, 1.0f, 0.0f), v3(x, 0.0f, 1.0f));
    }
    Accel kd, list;
    build_both(&s, &kd, &list);
    TreeStats ts = check_structure(&kd, &s, true);
    Stats st = {0};
    Pcg32 rng;
    pcg32_seed(&rng, 5u, 5u);
    for (int i = 0; i < 2000; i++) {
        float y = (float)rnd(&rng, -0.2, 1.0), z = (float)rnd(&rng, -0.2, 1.0);
        float x0 = powf(1.4f, (float)rnd(&rng, 0.0, 250.0));
        Ray r = ray_make(v3(x0, y, z), v3((i & 1) ? 1.0f : -1.0f, 0.0f, 0.0f), 0.0f, INFINITY);
        check_ray(&kd, &list, &s, &r, &st, "deep, along x", i);
        Vec3 qd = rnd_dir(&rng); /* the direction first: GCC's order */
        Ray q = ray_make(rnd_v3(&rng, -3.0, 3.0), qd, 0.0f, INFINITY);
        check_ray(&kd, &list, &s, &q, &st, "deep, random", i);
    }
    report("exponential spacing", &kd, &ts, &st);
    assert_int_equal(ts.max_depth, kd.kdtree.max_depth);
    accel_free(&kd);
    accel_free(&list);
    soup_free(&s);
}

/* Shadow-ray-like finite segments between points on the geometry (and between random
 * points): occluded must equal list's any-hit on every one. */
static void test_kdtree_occlusion_segments(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 4242u, 9u);
    Soup s = {0};
    soup_random_tris(&s, &rng, 1500);
    soup_random_spheres(&s, &rng, 60);
    soup_grid_cube(&s, 5);
    Accel kd, list;
    build_both(&s, &kd, &list);
    check_structure(&kd, &s, false);
    int n = s.num_tris + s.num_spheres;
    long blocked = 0, segments = 0;
    for (int i = 0; i < 20000; i++) {
        Vec3 p[2];
        for (int e = 0; e < 2; e++) {
            if (i % 4 == 0) { p[e] = rnd_v3(&rng, -12.0, 12.0); continue; }
            int id = (int)(pcg32_next(&rng) % (uint32_t)n);
            if (id < s.num_tris) {
                Vec3 p0 = s.pos[s.idx[3 * id]], p1 = s.pos[s.idx[3 * id + 1]], p2 = s.pos[s.idx[3 * id + 2]];
                float bu = pcg32_float(&rng), bv = pcg32_float(&rng);
                if (bu + bv > 1.0f) { bu = 1.0f - bu; bv = 1.0f - bv; }
                p[e] = v3_add(p0, v3_add(v3_scale(v3_sub(p1, p0), bu), v3_scale(v3_sub(p2, p0), bv)));
            } else {
                const Sphere *sp = &s.spheres[id - s.num_tris];
                p[e] = v3_madd(sp->center, rnd_dir(&rng), sp->radius);
            }
        }
        Vec3 dv = v3_sub(p[1], p[0]);
        float dist = v3_length(dv);
        if (!(dist > 1e-3f)) continue;
        Ray r = ray_make(p[0], v3_scale(dv, 1.0f / dist), 1e-4f * dist, (1.0f - 1e-4f) * dist);
        bool ok = accel_occluded(&kd, &r), ol = accel_occluded(&list, &r);
        if (ok != ol) {
            Hit h = {0};
            bool l = accel_intersect(&list, &r, &h);
            if (!(l && hit_off_prim(&s, (int)h.prim, &r, h.t) && !brute_intersect_on_prim(&s, &r, &h)))
                fail_msg("segment %d: kdtree occluded %d, list %d", i, ok, ol);
        }
        blocked += ol;
        segments++;
    }
    print_message("  segments %ld, blocked %ld\n", segments, blocked);
    assert_true(blocked > segments / 10 && blocked < segments);
    accel_free(&kd);
    accel_free(&list);
    soup_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_kdtree_empty),
        cmocka_unit_test(test_kdtree_random_soups),
        cmocka_unit_test(test_kdtree_mixed_triangles_spheres),
        cmocka_unit_test(test_kdtree_rays_in_split_planes),
        cmocka_unit_test(test_kdtree_degenerate_triangles),
        cmocka_unit_test(test_kdtree_coincident_triangles),
        cmocka_unit_test(test_kdtree_deep_build),
        cmocka_unit_test(test_kdtree_occlusion_segments),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
