/* The uniform grid (accel/grid.c) against the brute-force list back end, both built
 * through the acceleration interface: closest hits (same primitive, t bit for bit) and
 * occlusion on random soups with slivers and long needles, mixed triangles and spheres,
 * rays in cell boundary planes, degenerate and flat scenes, a teapot in a stadium and
 * empty geometry; the cell lists themselves; and the mailbox, seen through a private copy
 * of grid.c compiled with a counter of primitive tests. */
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

/* Random triangles of log-uniform size in [0.01, 5] around centres in [-10, 10]^3: a
 * third are slivers (the third vertex within 1e-4 of the size off the first edge), and
 * one in ten is a needle 5 to 25 long and 0.001 to 0.1 wide, which spans many cells. */
static void soup_random_tris_needles(Soup *s, Pcg32 *rng, int n)
{
    soup_reserve(s, s->num_tris + n, s->num_verts + 3 * n, s->num_spheres);
    for (int i = 0; i < n; i++) {
        Vec3 c = rnd_v3(rng, -10.0, 10.0);
        uint32_t kind = pcg32_next(rng) % 30u;
        if (kind < 3u) {
            /* Each length before its direction: GCC's order of the arguments this replaced. */
            float axis_len = (float)rnd(rng, 2.5, 12.5);
            Vec3 axis = v3_scale(rnd_dir(rng), axis_len);
            float side_len = (float)exp(rnd(rng, log(0.001), log(0.1)));
            Vec3 side = v3_scale(rnd_dir(rng), side_len);
            soup_add_tri(s, v3_sub(c, axis), v3_add(c, axis), v3_add(c, side));
            continue;
        }
        float size = (float)exp(rnd(rng, log(0.01), log(5.0)));
        Vec3 a = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        Vec3 b = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        Vec3 d;
        if (kind < 13u) {
            float t = (float)rnd(rng, 0.0, 1.0);
            d = v3_madd(v3_madd(a, v3_sub(b, a), t), rnd_v3(rng, -1.0, 1.0), 1e-4f * size);
        } else {
            d = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        }
        soup_add_tri(s, a, b, d);
    }
}

/* Indexed mesh of the cube [-1, 1]^3, each face an n x n grid of quads (two triangles),
 * coordinates exact in float, scaled by `scale` and moved by `offset`. */
static void soup_grid_cube(Soup *s, int n, float scale, Vec3 offset)
{
    int nv = 6 * (n + 1) * (n + 1), nt = 12 * n * n;
    soup_reserve(s, s->num_tris + nt, s->num_verts + nv, s->num_spheres);
    for (int axis = 0; axis < 3; axis++)
        for (int side = -1; side <= 1; side += 2) {
            int base = s->num_verts;
            for (int j = 0; j <= n; j++)
                for (int i = 0; i <= n; i++) {
                    float c[3];
                    c[axis] = (float)side;
                    c[(axis + 1) % 3] = -1.0f + 2.0f * (float)i / (float)n;
                    c[(axis + 2) % 3] = -1.0f + 2.0f * (float)j / (float)n;
                    s->pos[s->num_verts++] = v3_add(v3_scale(v3(c[0], c[1], c[2]), scale), offset);
                }
            for (int j = 0; j < n; j++)
                for (int i = 0; i < n; i++) {
                    int v00 = base + j * (n + 1) + i, v10 = v00 + 1, v01 = v00 + n + 1, v11 = v01 + 1;
                    int32_t *t = &s->idx[3 * s->num_tris];
                    t[0] = v00; t[1] = v10; t[2] = v11; t[3] = v00; t[4] = v11; t[5] = v01;
                    s->num_tris += 2;
                }
        }
}

/* Unit-sphere mesh from a latitude-longitude grid (poles as triangle fans), scaled and
 * moved: a dense closed mesh for the teapot-in-a-stadium scene. */
static void soup_uv_sphere(Soup *s, int rings, int segs, float radius, Vec3 centre)
{
    int nv = (rings - 1) * segs + 2, nt = 2 * segs * (rings - 1);
    soup_reserve(s, s->num_tris + nt, s->num_verts + nv, s->num_spheres);
    int base = s->num_verts;
    s->pos[s->num_verts++] = v3_add(centre, v3(0.0f, 0.0f, radius));
    for (int r = 1; r < rings; r++)
        for (int k = 0; k < segs; k++) {
            const double pi = 3.14159265358979323846;
            double th = pi * (double)r / (double)rings, ph = 2.0 * pi * (double)k / (double)segs;
            Vec3 p = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)cos(th));
            s->pos[s->num_verts++] = v3_madd(centre, p, radius);
        }
    int south = s->num_verts;
    s->pos[s->num_verts++] = v3_add(centre, v3(0.0f, 0.0f, -radius));
    for (int k = 0; k < segs; k++) {
        int k1 = (k + 1) % segs;
        int32_t *t = &s->idx[3 * s->num_tris];
        t[0] = base; t[1] = base + 1 + k; t[2] = base + 1 + k1;
        s->num_tris++;
        for (int r = 1; r < rings - 1; r++) {
            int a = base + 1 + (r - 1) * segs + k, b = base + 1 + (r - 1) * segs + k1;
            int c = a + segs, d = b + segs;
            t = &s->idx[3 * s->num_tris];
            t[0] = a; t[1] = c; t[2] = d; t[3] = a; t[4] = d; t[5] = b;
            s->num_tris += 2;
        }
        t = &s->idx[3 * s->num_tris];
        t[0] = base + 1 + (rings - 2) * segs + k; t[1] = south; t[2] = base + 1 + (rings - 2) * segs + k1;
        s->num_tris++;
    }
}

/* ------------------------------------------------------------------ comparison */

/* The grid and the list back end over one scene. */
typedef struct Pair {
    Accel grid, list;
    const Soup *s;
} Pair;

static void pair_build(Pair *p, const Soup *s)
{
    CstError err = {0};
    AccelGeometry g = soup_geometry(s);
    p->s = s;
    if (accel_build(&p->grid, ACCEL_GRID, &g, &err) != CST_OK) fail_msg("grid build: %s", err.msg);
    if (accel_build(&p->list, ACCEL_LIST, &g, &err) != CST_OK) fail_msg("list build: %s", err.msg);
}

static void pair_free(Pair *p)
{
    accel_free(&p->grid);
    accel_free(&p->list);
}

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
static double dist_segment(const double p[3], const double a[3], const double b[3])
{
    double ab[3], ap[3], l2 = 0.0, dot = 0.0;
    for (int k = 0; k < 3; k++) {
        ab[k] = b[k] - a[k];
        ap[k] = p[k] - a[k];
        l2 += ab[k] * ab[k];
        dot += ap[k] * ab[k];
    }
    double t = l2 > 0.0 ? fmin(fmax(dot / l2, 0.0), 1.0) : 0.0, d2 = 0.0;
    for (int k = 0; k < 3; k++) d2 += (ap[k] - t * ab[k]) * (ap[k] - t * ab[k]);
    return sqrt(d2);
}

/* Distance in double from p to primitive id: to the triangle (its plane inside, its
 * edges outside; only the edges for a degenerate one) or to the sphere's surface. */
static double dist_to_prim(const Soup *s, int id, const double p[3])
{
    if (id >= s->num_tris) {
        const Sphere *sp = &s->spheres[id - s->num_tris];
        double c[3] = {sp->center.x, sp->center.y, sp->center.z}, d2 = 0.0;
        for (int k = 0; k < 3; k++) d2 += (p[k] - c[k]) * (p[k] - c[k]);
        return fabs(sqrt(d2) - fabs((double)sp->radius));
    }
    double v[3][3];
    for (int i = 0; i < 3; i++) {
        Vec3 q = s->pos[s->idx[3 * id + i]];
        v[i][0] = q.x; v[i][1] = q.y; v[i][2] = q.z;
    }
    double e1[3], e2[3], w[3];
    for (int k = 0; k < 3; k++) { e1[k] = v[1][k] - v[0][k]; e2[k] = v[2][k] - v[0][k]; w[k] = p[k] - v[0][k]; }
    double n[3] = {e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2], e1[0] * e2[1] - e1[1] * e2[0]};
    double n2 = n[0] * n[0] + n[1] * n[1] + n[2] * n[2];
    if (n2 > 0.0) {
        /* Barycentrics of p's projection: (w x e2).n / n2 and (e1 x w).n / n2. */
        double c1[3] = {w[1] * e2[2] - w[2] * e2[1], w[2] * e2[0] - w[0] * e2[2], w[0] * e2[1] - w[1] * e2[0]};
        double c2[3] = {e1[1] * w[2] - e1[2] * w[1], e1[2] * w[0] - e1[0] * w[2], e1[0] * w[1] - e1[1] * w[0]};
        double bu = (c1[0] * n[0] + c1[1] * n[1] + c1[2] * n[2]) / n2;
        double bv = (c2[0] * n[0] + c2[1] * n[1] + c2[2] * n[2]) / n2;
        if (bu >= 0.0 && bv >= 0.0 && bu + bv <= 1.0)
            return fabs(w[0] * n[0] + w[1] * n[1] + w[2] * n[2]) / sqrt(n2);
    }
    return fmin(dist_segment(p, v[0], v[1]), fmin(dist_segment(p, v[1], v[2]), dist_segment(p, v[2], v[0])));
}

/* True if the hit point o + t d (in double) lies farther than tol from primitive id.
 * Moller-Trumbore's t is ill-conditioned for rays grazing a triangle's plane, worst on
 * slivers, and can put the point far off the triangle (though often inside its box). The
 * grid promises the hits within its margin of their primitive (grid.c): such off hits
 * may be skipped when the grid's exact triangle-cell overlap left the cells they fall in
 * out. */
static bool hit_off_prim(const Soup *s, int id, const Ray *r, float t, double tol)
{
    double p[3] = {(double)r->o.x + (double)t * (double)r->d.x, (double)r->o.y + (double)t * (double)r->d.y,
                   (double)r->o.z + (double)t * (double)r->d.z};
    return dist_to_prim(s, id, p) > tol;
}

/* Brute force's closest hit among hits within tol of their primitive. */
static bool list_intersect_near_prim(const Soup *s, const Ray *ray, double tol, Hit *hit)
{
    Ray r = *ray;
    bool found = false;
    for (int id = 0; id < s->num_tris + s->num_spheres; id++) {
        float t, u, v;
        if (prim_hit(s, id, &r, &t, &u, &v) && !hit_off_prim(s, id, &r, t, tol)) {
            r.t_max = t;
            hit->t = t; hit->u = u; hit->v = v; hit->prim = (uint32_t)id;
            found = true;
        }
    }
    return found;
}

static uint32_t fbits(float f)
{
    uint32_t b;
    memcpy(&b, &f, sizeof b);
    return b;
}

typedef struct Stats { long rays, hits, ties, occluded, off_prim; } Stats;

static void fail_ray(const char *what, long i, const Ray *r, const char *msg, bool g, const Hit *hg, bool l,
                     const Hit *hl)
{
    fail_msg("%s ray %ld: %s; grid %s prim %u t %.9g, list %s prim %u t %.9g; o = (%a, %a, %a), "
             "d = (%a, %a, %a), t in (%a, %a)",
             what, i, msg, g ? "hit" : "miss", g ? hg->prim : 0u, g ? (double)hg->t : 0.0, l ? "hit" : "miss",
             l ? hl->prim : 0u, l ? (double)hl->t : 0.0, (double)r->o.x, (double)r->o.y, (double)r->o.z,
             (double)r->d.x, (double)r->d.y, (double)r->d.z, (double)r->t_min, (double)r->t_max);
}

/* One ray through both back ends. The closest hits must be equal: same primitive, t, u
 * and v bit for bit; another primitive only for an exact tie (that primitive, tested
 * alone, gives the same t to the bit). Occlusion must be equal. The one exception: when
 * the list's hit lies farther than half the grid margin from its own primitive, the grid
 * may skip it, and must then still return a genuine hit no farther than every hit near
 * its primitive (and report occlusion when such a hit exists, and only when some hit
 * does). Such rays are counted in off_prim and the first few printed. */
static void check_ray(const Pair *p, const Ray *r, Stats *st, const char *what, long i)
{
    const Soup *s = p->s;
    Hit hg = {0}, hl = {0};
    bool g = accel_intersect(&p->grid, r, &hg);
    bool l = accel_intersect(&p->list, r, &hl);
    st->rays++;
    st->hits += l;
    bool same = g == l && (!l || fbits(hg.t) == fbits(hl.t));
    if (same && l && hg.prim != hl.prim) {
        float t, u, v;
        if (!prim_hit(s, (int)hg.prim, r, &t, &u, &v) || fbits(t) != fbits(hl.t))
            fail_ray(what, i, r, "different primitive, not a tie", g, &hg, l, &hl);
        st->ties++;
    } else if (same && l && (fbits(hg.u) != fbits(hl.u) || fbits(hg.v) != fbits(hl.v))) {
        fail_ray(what, i, r, "barycentrics differ", g, &hg, l, &hl);
    }
    bool og = accel_occluded(&p->grid, r), ol = accel_occluded(&p->list, r);
    st->occluded += ol;
    if (same && og == ol) return;

    double tol = 0.5 * (double)p->grid.grid.margin;
    if (!l || !hit_off_prim(s, (int)hl.prim, r, hl.t, tol))
        fail_ray(what, i, r, same ? "occlusion differs" : "closest hits differ", g, &hg, l, &hl);
    Hit hc = {0};
    bool c = list_intersect_near_prim(s, r, tol, &hc);
    if (g) {
        float t, u, v;
        if (!prim_hit(s, (int)hg.prim, r, &t, &u, &v) || fbits(t) != fbits(hg.t))
            fail_ray(what, i, r, "grid hit is not a hit of its primitive", g, &hg, l, &hl);
        if (c && hc.t < hg.t) fail_ray(what, i, r, "grid missed a closer near-primitive hit", g, &hg, l, &hl);
    } else if (c) {
        fail_ray(what, i, r, "grid missed a near-primitive hit", g, &hg, l, &hl);
    }
    if (og && !ol) fail_ray(what, i, r, "grid occluded without any hit", g, &hg, l, &hl);
    if (!og && c) fail_ray(what, i, r, "grid occlusion missed a near-primitive hit", g, &hg, l, &hl);
    if (st->off_prim++ < 3) {
        double q[3] = {(double)r->o.x + (double)hl.t * (double)r->d.x, (double)r->o.y + (double)hl.t * (double)r->d.y,
                       (double)r->o.z + (double)hl.t * (double)r->d.z};
        print_message("  note: %s ray %ld: the list's hit on prim %u at t = %.9g lies %.3g off the primitive "
                      "(grid margin %.3g); grid %s prim %u t %.9g\n",
                      what, i, hl.prim, (double)hl.t, dist_to_prim(s, (int)hl.prim, q), (double)p->grid.grid.margin,
                      g ? "hit" : "miss", g ? hg.prim : 0u, g ? (double)hg.t : 0.0);
    }
}

/* Random rays: origins in the bounds grown by half their size on each side (inside and
 * outside) or, for half the rays, aimed through a random point of a random primitive
 * from up to a diagonal away; directions uniform, axis-parallel (exact zeros of both
 * signs) or in a coordinate plane (one exact zero); t_min 0 or 1e-4, t_max infinite or a
 * finite segment end (so occlusion is tested on segments). */
static void check_random_rays(const Pair *p, Pcg32 *rng, int count, Stats *st, const char *what)
{
    const Soup *s = p->s;
    BBox b = p->grid.grid.bounds; /* finite even when a primitive is not */
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
            Vec3 r = rnd_dir(rng);
            float dd[3] = {r.x, r.y, r.z};
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
        check_ray(p, &r, st, what, i);
    }
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
    double q[3] = {p.x, p.y, p.z};
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
    AccelGeometry none = {NULL, NULL, 0, NULL, 0};
    assert_int_equal(accel_build(&a, ACCEL_GRID, &none, &err), CST_OK);
    assert_int_equal(a.grid.num_cells, 0);
    assert_int_equal(accel_memory_bytes(&a), 0);
    Pcg32 rng;
    pcg32_seed(&rng, 1u, 1u);
    for (int i = 0; i < 1000; i++) {
        Vec3 d = rnd_dir(&rng); /* the direction first: GCC's order of the arguments this replaced */
        Ray r = ray_make(rnd_v3(&rng, -10.0, 10.0), d, 0.0f, INFINITY);
        Hit h = {0};
        assert_false(accel_intersect(&a, &r, &h));
        assert_false(accel_occluded(&a, &r));
    }
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

static void test_grid_random_soups(void **state)
{
    (void)state;
    const int sizes[] = {1, 2, 7, 100, 5000};
    const int rays[] = {20000, 20000, 20000, 20000, 8000};
    for (int k = 0; k < 5; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 1000u + (uint64_t)k, 3u);
        soup_random_tris_needles(&s, &rng, sizes[k]);
        Pair p;
        pair_build(&p, &s);
        const Grid *g = &p.grid.grid;
        size_t refs = check_structure(g, &s, &rng);
        /* ~27 N cells, up to rounding per axis. */
        int cells = g->res[0] * g->res[1] * g->res[2];
        assert_true(cells <= 2 * 27 * sizes[k] && cells >= 27 * sizes[k] / 4);
        Stats st = {0};
        char what[64];
        snprintf(what, sizeof what, "soup of %d", sizes[k]);
        check_random_rays(&p, &rng, rays[k], &st, what);
        print_message("  %-22s cells %3dx%3dx%3d refs %7zu (%.1f/prim) %6.1f KB  rays %ld hits %ld ties %ld "
                      "occluded %ld off-prim %ld\n",
                      what, g->res[0], g->res[1], g->res[2], refs, (double)refs / sizes[k],
                      (double)accel_memory_bytes(&p.grid) / 1024.0, st.rays, st.hits, st.ties, st.occluded,
                      st.off_prim);
        assert_true(st.hits > st.rays / 100);
        pair_free(&p);
        soup_free(&s);
    }
}

static void test_grid_mixed_triangles_spheres(void **state)
{
    (void)state;
    const int tris[] = {0, 1, 300, 2000}, spheres[] = {1, 5, 300, 500};
    for (int k = 0; k < 4; k++) {
        Soup s = {0};
        Pcg32 rng;
        pcg32_seed(&rng, 2000u + (uint64_t)k, 5u);
        soup_random_tris_needles(&s, &rng, tris[k]);
        soup_random_spheres(&s, &rng, spheres[k]);
        if (k == 3) { /* a sphere with a negative radius: sphere_intersect squares it */
            s.spheres[0].radius = -s.spheres[0].radius;
        }
        Pair p;
        pair_build(&p, &s);
        size_t refs = check_structure(&p.grid.grid, &s, &rng);
        Stats st = {0};
        char what[64];
        snprintf(what, sizeof what, "%d tris + %d spheres", tris[k], spheres[k]);
        check_random_rays(&p, &rng, 10000, &st, what);
        /* Rays from inside spheres (they hit the far side). */
        for (int i = 0; i < 2000 && s.num_spheres > 0; i++) {
            const Sphere *sp = &s.spheres[pcg32_next(&rng) % (uint32_t)s.num_spheres];
            Vec3 d = rnd_dir(&rng); /* the direction first: GCC's order */
            Ray r = ray_make(v3_madd(sp->center, rnd_dir(&rng), 0.5f * sp->radius), d, 0.0f, INFINITY);
            check_ray(&p, &r, &st, "inside a sphere", i);
        }
        print_message("  %-22s refs %6zu  rays %ld hits %ld ties %ld occluded %ld off-prim %ld\n", what, refs, st.rays,
                      st.hits, st.ties, st.occluded, st.off_prim);
        assert_true(st.hits > st.rays / 100);
        pair_free(&p);
        soup_free(&s);
    }
}

/* Axis-parallel rays in the grid's own cell boundary planes (the float nearest each
 * plane and its two neighbours), with exact zeros of both signs in the other components,
 * through a soup; and rays along the lattice lines of a grid-aligned cube mesh, whose
 * triangles' edges lie in the rays' planes. */
static void test_grid_rays_in_cell_planes(void **state)
{
    (void)state;
    Soup s = {0};
    Pcg32 rng;
    pcg32_seed(&rng, 3000u, 7u);
    soup_random_tris_needles(&s, &rng, 400);
    soup_random_spheres(&s, &rng, 20);
    Pair p;
    pair_build(&p, &s);
    const Grid *g = &p.grid.grid;
    Stats st = {0};
    long i = 0;
    for (int axis = 0; axis < 3; axis++) {
        int a1 = (axis + 1) % 3, a2 = (axis + 2) % 3;
        for (int k = 0; k < 400; k++) {
            /* Plane indices on the two other axes, boundary planes included. */
            int i1 = (int)(pcg32_next(&rng) % (uint32_t)(g->res[a1] + 1));
            int i2 = (int)(pcg32_next(&rng) % (uint32_t)(g->res[a2] + 1));
            float c1 = (float)(g->org[a1] + (double)i1 * g->cell_size[a1]);
            float c2 = (float)(g->org[a2] + (double)i2 * g->cell_size[a2]);
            for (int nb = 0; nb < 3; nb++) {
                float o[3], d[3];
                o[a1] = nb == 0 ? c1 : nextafterf(c1, nb == 1 ? -INFINITY : INFINITY);
                o[a2] = nb == 0 ? c2 : nextafterf(c2, nb == 1 ? INFINITY : -INFINITY);
                /* From outside the grid, or from inside on a plane of the walking axis too. */
                bool down = pcg32_next(&rng) & 1u;
                double extent = (double)g->res[axis] * g->cell_size[axis];
                o[axis] = (float)(g->org[axis] + (down ? 1.2 : -0.2) * extent);
                if (pcg32_next(&rng) & 1u)
                    o[axis] = (float)(g->org[axis] + (double)(pcg32_next(&rng) % (uint32_t)(g->res[axis] + 1)) *
                                                         g->cell_size[axis]);
                float z = (pcg32_next(&rng) & 1u) ? -0.0f : 0.0f;
                d[a1] = z; d[a2] = (pcg32_next(&rng) & 1u) ? -0.0f : 0.0f;
                d[axis] = down ? -1.0f : 1.0f;
                Ray r = ray_make(v3(o[0], o[1], o[2]), v3(d[0], d[1], d[2]), 0.0f, INFINITY);
                check_ray(&p, &r, &st, "cell-plane ray", i++);
                /* The same line in a diagonal direction within the plane of a1. */
                float dd[3] = {d[0], d[1], d[2]};
                dd[a2] = (pcg32_next(&rng) & 1u) ? 0.6f : -0.6f;
                dd[axis] *= 0.8f;
                r.d = v3(dd[0], dd[1], dd[2]);
                check_ray(&p, &r, &st, "cell-plane ray, diagonal", i++);
            }
        }
    }
    print_message("  cell-plane rays (soup): %ld rays, %ld hits, %ld off-prim\n", st.rays, st.hits, st.off_prim);
    pair_free(&p);
    soup_free(&s);

    Soup c = {0};
    soup_grid_cube(&c, 4, 1.0f, v3(0.0f, 0.0f, 0.0f));
    pair_build(&p, &c);
    check_structure(&p.grid.grid, &c, &rng);
    Stats sc = {0};
    for (int axis = 0; axis < 3; axis++)
        for (int sgn = 0; sgn < 4; sgn++)
            for (int gi = 0; gi <= 8; gi++)
                for (int gj = 0; gj <= 8; gj++) {
                    float z0 = (sgn & 2) ? -0.0f : 0.0f;
                    float dd[3] = {z0, z0, z0}, oo[3];
                    dd[axis] = (sgn & 1) ? -1.0f : 1.0f;
                    oo[axis] = (sgn & 1) ? 3.0f : -3.0f;
                    oo[(axis + 1) % 3] = -1.0f + 0.25f * (float)gi;
                    oo[(axis + 2) % 3] = -1.0f + 0.25f * (float)gj;
                    Ray r = ray_make(v3(oo[0], oo[1], oo[2]), v3(dd[0], dd[1], dd[2]), 0.0f, INFINITY);
                    check_ray(&p, &r, &sc, "lattice ray", i++);
                    r.t_min = 2.5f; /* from just outside the near face */
                    check_ray(&p, &r, &sc, "lattice ray, t_min > 0", i++);
                    /* From the cube's middle plane, out along the lattice line. */
                    r.t_min = 0.0f;
                    float q[3] = {0.0f, 0.0f, 0.0f};
                    q[(axis + 1) % 3] = oo[(axis + 1) % 3];
                    q[(axis + 2) % 3] = oo[(axis + 2) % 3];
                    r.o = v3(q[0], q[1], q[2]);
                    check_ray(&p, &r, &sc, "lattice ray from inside", i++);
                }
    print_message("  lattice rays (cube mesh): %ld rays, %ld hits, %ld ties\n", sc.rays, sc.hits, sc.ties);
    assert_true(sc.hits > sc.rays / 2);
    pair_free(&p);
    soup_free(&c);
}

/* Zero-area triangles (repeated vertices, exactly collinear vertices), a NaN vertex,
 * infinite coordinates and coincident copies of one triangle (exact ties in t), next to
 * ordinary ones; a scene of only degenerate triangles along one line (two flat axes);
 * and scenes whose primitives all lie in one plane. */
static void test_grid_degenerate_and_flat(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 4000u, 9u);
    Soup s = {0};
    soup_random_tris_needles(&s, &rng, 200);
    soup_reserve(&s, s.num_tris + 60, s.num_verts + 180, 0);
    for (int i = 0; i < 20; i++) {
        Vec3 a = rnd_v3(&rng, -10.0, 10.0), b = rnd_v3(&rng, -10.0, 10.0);
        soup_add_tri(&s, a, a, b);                                     /* repeated vertex */
        soup_add_tri(&s, a, b, v3_scale(v3_add(a, b), 0.5f));          /* collinear (nearly, after rounding) */
        float x = (float)rnd(&rng, -10.0, 10.0);
        soup_add_tri(&s, v3(x, 1.0f, 2.0f), v3(x, 3.0f, 2.0f), v3(x, 7.0f, 2.0f)); /* exactly collinear */
    }
    soup_reserve(&s, s.num_tris + 52, s.num_verts + 156, 0);
    soup_add_tri(&s, v3(NAN, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), v3(0.0f, 1.0f, 0.0f));
    soup_add_tri(&s, v3(INFINITY, 0.0f, 0.0f), v3(1.0f, 2.0f, 0.0f), v3(0.0f, 1.0f, 3.0f));
    for (int i = 0; i < 50; i++) soup_add_tri(&s, v3(-4.0f, -3.0f, 1.0f), v3(6.0f, -2.0f, 2.0f), v3(0.5f, 7.0f, -1.0f));
    Pair p;
    pair_build(&p, &s);
    check_structure(&p.grid.grid, &s, &rng);
    Stats st = {0};
    check_random_rays(&p, &rng, 10000, &st, "with degenerates");
    for (int i = 0; i < 1000; i++) { /* at the coincident copies */
        Vec3 d = rnd_dir(&rng);
        float ty = (float)rnd(&rng, -1.0, 1.0), tx = 0.5f + (float)rnd(&rng, -1.0, 1.0); /* y first: GCC's order */
        Vec3 target = v3(tx, ty, 0.6f);
        Ray r = ray_make(v3_madd(target, d, -30.0f), d, 0.0f, INFINITY);
        check_ray(&p, &r, &st, "at the copies", i);
    }
    print_message("  %-22s rays %ld hits %ld ties %ld off-prim %ld\n", "with degenerates", st.rays, st.hits, st.ties,
                  st.off_prim);
    pair_free(&p);
    soup_free(&s);

    /* Degenerate triangles along the x axis only: both other extents are zero. */
    soup_reserve(&s, 50, 150, 0);
    for (int i = 0; i < 50; i++) {
        float x0 = (float)rnd(&rng, -5.0, 5.0), x1 = (float)rnd(&rng, -5.0, 5.0);
        soup_add_tri(&s, v3(x0, 1.0f, -2.0f), v3(x1, 1.0f, -2.0f), v3(0.5f * (x0 + x1), 1.0f, -2.0f));
    }
    pair_build(&p, &s);
    assert_true(p.grid.grid.res[1] == 1 && p.grid.grid.res[2] == 1 && p.grid.grid.res[0] > 1);
    check_structure(&p.grid.grid, &s, &rng);
    Stats sl = {0};
    check_random_rays(&p, &rng, 3000, &sl, "on one line");
    pair_free(&p);
    soup_free(&s);

    /* Everything in the plane z = 0.5, then in the plane x = -3 together with spheres of
     * radius 0 (points: placed like any primitive, never hit). */
    for (int variant = 0; variant < 2; variant++) {
        soup_reserve(&s, 3000, 9000, 10);
        for (int i = 0; i < 3000; i++) {
            Vec3 c = rnd_v3(&rng, -10.0, 10.0);
            float size = (float)exp(rnd(&rng, log(0.01), log(2.0)));
            Vec3 q[3];
            for (int k = 0; k < 3; k++) {
                q[k] = v3_madd(c, rnd_v3(&rng, -1.0, 1.0), size);
                if (variant == 0) q[k].z = 0.5f;
                else q[k].x = -3.0f;
            }
            soup_add_tri(&s, q[0], q[1], q[2]);
        }
        if (variant == 1)
            for (int i = 0; i < 10; i++) soup_add_sphere(&s, v3(-3.0f, (float)i, 1.0f), 0.0f);
        pair_build(&p, &s);
        const Grid *g = &p.grid.grid;
        int flat_axis = variant == 0 ? 2 : 0;
        assert_int_equal(g->res[flat_axis], 1);
        int other = g->res[0] * g->res[1] * g->res[2];
        assert_true(other > 27 * s.num_tris / 3 && other < 2 * 27 * (s.num_tris + s.num_spheres));
        check_structure(g, &s, &rng);
        Stats sf = {0};
        check_random_rays(&p, &rng, 8000, &sf, "flat");
        /* Rays nearly in the plane and exactly in it (never hit: det = 0). */
        for (int i = 0; i < 2000; i++) {
            Vec3 o = rnd_v3(&rng, -12.0, 12.0), d = rnd_dir(&rng);
            if (variant == 0) { o.z = 0.5f; d.z = (i & 1) ? 0.0f : 1e-3f * d.z; }
            else { o.x = -3.0f; d.x = (i & 1) ? -0.0f : 1e-3f * d.x; }
            Ray r = ray_make(o, v3_normalize(d), 0.0f, INFINITY);
            check_ray(&p, &r, &sf, "grazing the plane", i);
        }
        print_message("  flat in %c: cells %dx%dx%d  rays %ld hits %ld off-prim %ld\n", "zx"[variant], g->res[0],
                      g->res[1], g->res[2], sf.rays, sf.hits, sf.off_prim);
        assert_true(sf.hits > sf.rays / 100);
        pair_free(&p);
        soup_free(&s);
    }
}

/* Teapot in a stadium: a dense mesh of 0.02 across (a 40 x 64 uv sphere, 5k triangles)
 * inside a 2000-wide box of 12 triangles, plus a few huge slanted triangles across the
 * stadium. The grid, sized for the stadium, puts the whole teapot in a handful of cells
 * and is slow there, but must stay correct and small. */
static void test_grid_teapot_in_stadium(void **state)
{
    (void)state;
    Pcg32 rng;
    pcg32_seed(&rng, 5000u, 11u);
    Soup s = {0};
    soup_grid_cube(&s, 1, 1000.0f, v3(0.0f, 0.0f, 0.0f));
    soup_uv_sphere(&s, 40, 64, 0.01f, v3(3.0f, -2.0f, 1.0f));
    soup_reserve(&s, s.num_tris + 4, s.num_verts + 12, 0);
    for (int i = 0; i < 4; i++) {
        Vec3 c = rnd_v3(&rng, -990.0, 990.0), b = rnd_v3(&rng, -990.0, 990.0); /* last first: GCC's order */
        soup_add_tri(&s, rnd_v3(&rng, -990.0, 990.0), b, c);
    }
    Pair p;
    pair_build(&p, &s);
    const Grid *g = &p.grid.grid;
    size_t refs = check_structure(g, &s, &rng);
    size_t bytes = accel_memory_bytes(&p.grid);
    print_message("  teapot in stadium: %d tris, cells %dx%dx%d, refs %zu, %.1f MB\n", s.num_tris, g->res[0],
                  g->res[1], g->res[2], refs, (double)bytes / 1048576.0);
    /* Cells ~27 N, references dominated by the few huge triangles (exact overlap keeps
     * each to the cells its plane crosses): no blow-up. */
    assert_true(g->res[0] * g->res[1] * g->res[2] <= 2 * 27 * s.num_tris);
    assert_true(refs < (size_t)20 * (size_t)s.num_tris);
    assert_true(bytes < (size_t)16 << 20);
    Stats st = {0};
    /* Rays from the stadium at the teapot, and random ones in the stadium. */
    Vec3 teapot = v3(3.0f, -2.0f, 1.0f);
    for (int i = 0; i < 3000; i++) {
        Vec3 o = rnd_v3(&rng, -900.0, 900.0);
        float aim_r = (float)rnd(&rng, 0.0, 0.012); /* the distance first: GCC's order */
        Vec3 aim = v3_madd(teapot, rnd_dir(&rng), aim_r);
        Ray r = ray_make(o, v3_normalize(v3_sub(aim, o)), 0.0f, INFINITY);
        check_ray(&p, &r, &st, "at the teapot", i);
        float near_r = (float)rnd(&rng, 0.0, 0.02); /* the distance first: GCC's order */
        Vec3 near = v3_madd(teapot, rnd_dir(&rng), near_r);
        Ray q = ray_make(near, rnd_dir(&rng), 0.0f, (i & 1) ? INFINITY : 0.05f);
        check_ray(&p, &q, &st, "from the teapot", i);
    }
    check_random_rays(&p, &rng, 1000, &st, "in the stadium");
    print_message("  teapot in stadium: rays %ld hits %ld ties %ld off-prim %ld\n", st.rays, st.hits, st.ties,
                  st.off_prim);
    pair_free(&p);
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
        Pair p;
        pair_build(&p, &s);
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
            bool c = counting_grid_intersect(&g, &r, &hc), l = accel_intersect(&p.grid, &r, &hl);
            assert_true(c == l && (!c || (hc.prim == hl.prim && fbits(hc.t) == fbits(hl.t))));
            assert_true(counting_grid_occluded(&g, &r) == accel_occluded(&p.grid, &r));
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
        pair_free(&p);
        counting_grid_free(&g);
    }
    soup_free(&s);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_grid_empty),
        cmocka_unit_test(test_grid_resolution),
        cmocka_unit_test(test_grid_random_soups),
        cmocka_unit_test(test_grid_mixed_triangles_spheres),
        cmocka_unit_test(test_grid_rays_in_cell_planes),
        cmocka_unit_test(test_grid_degenerate_and_flat),
        cmocka_unit_test(test_grid_teapot_in_stadium),
        cmocka_unit_test(test_grid_mailbox),
        cmocka_unit_test(test_grid_brick_distances),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
