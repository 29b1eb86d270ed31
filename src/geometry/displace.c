/* True displacement of triangle meshes: tessellation by longest-edge bisection until every
 * edge is shorter than a length (pbrt-v4's TriQuadMesh::Refine), one shared midpoint per
 * split edge, displacement along the vertex normals and the normals recomputed. */
#include "geometry/displace.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/rng.h"

typedef ARRAY(Vec3) Vec3Array;
typedef ARRAY(Vec2) Vec2Array;
typedef ARRAY(int) IntArray;

/* A pending triangle of the refinement (pbrt-v4 recurses; an explicit stack bounds the
 * depth by memory instead of the C stack). */
typedef struct Pending {
    int v[3];
} Pending;
typedef ARRAY(Pending) PendingArray;

/* Split edges: the key (lo << 32 | hi) of an edge's two vertex indices, lo < hi, to the
 * index of its midpoint vertex. Open addressing with linear probing, at most half full. */
typedef struct EdgeMap {
    uint64_t *keys; /* EDGE_EMPTY where free */
    int *mid;
    size_t cap, n;
} EdgeMap;

#define EDGE_EMPTY UINT64_MAX

static bool edges_grow(EdgeMap *m)
{
    size_t cap = m->cap ? 2 * m->cap : 1024;
    uint64_t *keys = malloc(cap * sizeof *keys);
    int *mid = malloc(cap * sizeof *mid);
    if (!keys || !mid) {
        free(keys);
        free(mid);
        return false;
    }
    for (size_t i = 0; i < cap; i++) keys[i] = EDGE_EMPTY;
    for (size_t i = 0; i < m->cap; i++) {
        if (m->keys[i] == EDGE_EMPTY) continue;
        size_t h = mix64(m->keys[i]) & (cap - 1);
        while (keys[h] != EDGE_EMPTY) h = (h + 1) & (cap - 1);
        keys[h] = m->keys[i];
        mid[h] = m->mid[i];
    }
    free(m->keys);
    free(m->mid);
    m->keys = keys;
    m->mid = mid;
    m->cap = cap;
    return true;
}

/* The slot of key: where it is, or the free slot where it goes. */
static size_t edges_slot(const EdgeMap *m, uint64_t key)
{
    size_t h = mix64(key) & (m->cap - 1);
    while (m->keys[h] != EDGE_EMPTY && m->keys[h] != key) h = (h + 1) & (m->cap - 1);
    return h;
}

static void edges_free(EdgeMap *m)
{
    free(m->keys);
    free(m->mid);
    memset(m, 0, sizeof *m);
}

/* The growing mesh of the refinement: object-space and measured positions, normals, uvs. */
typedef struct Refiner {
    Vec3Array p, mp, n;
    Vec2Array uv;
    int has_uv;
    IntArray idx, parent;
    EdgeMap edges;
    const Transform *measure;
    float len;
} Refiner;

static Vec3 measured(const Refiner *r, Vec3 p) { return r->measure ? transform_point(r->measure, p) : p; }

/* pbrt-v4's Distance: the float length of the difference of the measured points. */
static float dist(const Refiner *r, int a, int b) { return v3_length(v3_sub(r->mp.v[a], r->mp.v[b])); }

/* The midpoint vertex of edge (a, b), made on the first request; -1 on OOM. Position, uv
 * and normal depend on the two end points alone (sums commute), so the edge's two
 * triangles would make the same vertex; the map makes it one. */
static int edge_midpoint(Refiner *r, int a, int b)
{
    uint64_t key = a < b ? ((uint64_t)a << 32 | (uint64_t)b) : ((uint64_t)b << 32 | (uint64_t)a);
    if (2 * (r->edges.n + 1) > r->edges.cap && !edges_grow(&r->edges)) return -1;
    size_t s = edges_slot(&r->edges, key);
    if (r->edges.keys[s] == key) return r->edges.mid[s];
    if (r->p.n >= (size_t)INT32_MAX) return -1;
    int m = (int)r->p.n;
    Vec3 p = v3_scale(v3_add(r->p.v[a], r->p.v[b]), 0.5f);
    Vec3 n = v3_add(r->n.v[a], r->n.v[b]);
    if (v3_length2(n) > 0.0f) n = v3_normalize(n);
    if (!array_push(&r->p, p) || !array_push(&r->mp, measured(r, p)) || !array_push(&r->n, n)) return -1;
    if (r->has_uv) {
        Vec2 uv = v2(0.5f * (r->uv.v[a].x + r->uv.v[b].x), 0.5f * (r->uv.v[a].y + r->uv.v[b].y));
        if (!array_push(&r->uv, uv)) return -1;
    }
    r->edges.keys[s] = key;
    r->edges.mid[s] = m;
    r->edges.n++;
    return m;
}

/* Refines input triangle t (vertices v0, v1, v2) as pbrt-v4's TriQuadMesh::Refine, its
 * children in the same order. Every triangle on the stack ends as at least one output
 * triangle, so out + stack > max_triangles fails early. */
static CstStatus refine(Refiner *r, PendingArray *stack, int t, const int *tri, int64_t max_tris, CstError *err)
{
    stack->n = 0;
    Pending first = {{tri[0], tri[1], tri[2]}};
    if (!array_push(stack, first)) return cst_fail(err, CST_ERR_OOM, "displacement: out of memory");
    while (stack->n > 0) {
        Pending q = stack->v[--stack->n];
        int v0 = q.v[0], v1 = q.v[1], v2 = q.v[2];
        float d01 = dist(r, v0, v1), d12 = dist(r, v1, v2), d20 = dist(r, v2, v0);
        if (d01 < r->len && d12 < r->len && d20 < r->len) {
            if (!array_push(&r->idx, v0) || !array_push(&r->idx, v1) || !array_push(&r->idx, v2) ||
                !array_push(&r->parent, t))
                return cst_fail(err, CST_ERR_OOM, "displacement: out of memory");
            continue;
        }
        /* the longest edge first (pbrt-v4's order, ties included), then the opposite vertex */
        int v[3];
        if (d01 > d12) {
            if (d01 > d20) v[0] = v0, v[1] = v1, v[2] = v2;
            else v[0] = v2, v[1] = v0, v[2] = v1;
        } else {
            if (d12 > d20) v[0] = v1, v[1] = v2, v[2] = v0;
            else v[0] = v2, v[1] = v0, v[2] = v1;
        }
        if ((int64_t)r->parent.n + (int64_t)stack->n + 2 > max_tris)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "displacement: the tessellation would exceed %lld "
                            "triangles (edge length %g); expected a larger edge length", (long long)max_tris,
                            (double)r->len);
        int m = edge_midpoint(r, v[0], v[1]);
        if (m < 0) return cst_fail(err, CST_ERR_OOM, "displacement: out of memory");
        Pending a = {{v[0], m, v[2]}}, b = {{m, v[1], v[2]}};
        if (!array_push(stack, b) || !array_push(stack, a)) /* a is refined first, as in pbrt-v4 */
            return cst_fail(err, CST_ERR_OOM, "displacement: out of memory");
    }
    return CST_OK;
}

void displace_vertex_normals(const Vec3 *p, int nv, const int *idx, int nt, Vec3 *n)
{
    for (int i = 0; i < nv; i++) n[i] = v3s(0.0f);
    for (int t = 0; t < nt; t++) {
        const int *v = &idx[3 * t];
        Vec3 fn = v3_cross(v3_sub(p[v[1]], p[v[0]]), v3_sub(p[v[2]], p[v[1]]));
        if (!(v3_length2(fn) > 0.0f)) continue;
        fn = v3_normalize(fn);
        for (int k = 0; k < 3; k++) n[v[k]] = v3_add(n[v[k]], fn);
    }
    for (int i = 0; i < nv; i++)
        if (v3_length2(n[i]) > 0.0f) n[i] = v3_normalize(n[i]);
}

static void refiner_free(Refiner *r)
{
    array_free(&r->p);
    array_free(&r->mp);
    array_free(&r->n);
    array_free(&r->uv);
    array_free(&r->idx);
    array_free(&r->parent);
    edges_free(&r->edges);
}

CstStatus displace_mesh(const DisplaceInput *in, DisplacedMesh *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    if (!(in->edge_length > 0.0f)) /* NaN too */
        return cst_fail(err, CST_ERR_INVALID_ARG, "displacement: edge length %g; expected a length > 0",
                        (double)in->edge_length);
    if (in->nv <= 0 || in->nt <= 0 || in->max_triangles < in->nt || in->max_triangles > INT32_MAX / 3)
        return cst_fail(err, CST_ERR_INVALID_ARG, "displacement: %d vertices, %d triangles, a limit of %lld "
                        "triangles; expected at least one of each, within the limit (at most %d)", in->nv,
                        in->nt, (long long)in->max_triangles, INT32_MAX / 3);
    Refiner r = {0};
    PendingArray stack = {0};
    CstStatus st = CST_OK;
    r.measure = in->measure;
    r.len = in->edge_length;
    r.has_uv = in->uv != NULL;
    size_t nv = (size_t)in->nv;
    if (!array_reserve(&r.p, nv) || !array_reserve(&r.mp, nv) || !array_reserve(&r.n, nv) ||
        (r.has_uv && !array_reserve(&r.uv, nv)) || !array_reserve(&r.idx, 3 * (size_t)in->nt) ||
        !array_reserve(&r.parent, (size_t)in->nt)) {
        st = cst_fail(err, CST_ERR_OOM, "displacement: out of memory for %d vertices", in->nv);
        goto done;
    }
    memcpy(r.p.v, in->p, nv * sizeof *r.p.v);
    r.p.n = r.mp.n = r.n.n = nv;
    for (size_t i = 0; i < nv; i++) r.mp.v[i] = measured(&r, in->p[i]);
    if (in->n) memcpy(r.n.v, in->n, nv * sizeof *r.n.v);
    else displace_vertex_normals(in->p, in->nv, in->idx, in->nt, r.n.v);
    if (r.has_uv) {
        memcpy(r.uv.v, in->uv, nv * sizeof *r.uv.v);
        r.uv.n = nv;
    }
    /* A lower bound first, so that a far too small edge length fails at once instead of at
     * the limit. Every output triangle has edges < len, so an area below the equilateral
     * triangle's, sqrt(3)/4 len^2, while the pieces cover the measured area; and an input
     * edge of length E ends in more than E / len pieces, each an edge of one of its
     * triangle's pieces, which hold at most 3 such (the bound that catches slivers). */
    double area = 0.0, perimeter = 0.0;
    for (int t = 0; t < in->nt; t++) {
        const int *v = &in->idx[3 * t];
        Vec3 a = r.mp.v[v[0]], b = r.mp.v[v[1]], c = r.mp.v[v[2]];
        double e1[3] = {(double)b.x - (double)a.x, (double)b.y - (double)a.y, (double)b.z - (double)a.z};
        double e2[3] = {(double)c.x - (double)a.x, (double)c.y - (double)a.y, (double)c.z - (double)a.z};
        double x = e1[1] * e2[2] - e1[2] * e2[1], y = e1[2] * e2[0] - e1[0] * e2[2], z = e1[0] * e2[1] - e1[1] * e2[0];
        area += 0.5 * sqrt(x * x + y * y + z * z);
        perimeter += (double)dist(&r, v[0], v[1]) + (double)dist(&r, v[1], v[2]) + (double)dist(&r, v[2], v[0]);
    }
    double len = (double)r.len;
    double least = fmax(area / (0.43301270189221932 * len * len), perimeter / (3.0 * len));
    if (least > (double)in->max_triangles) {
        st = cst_fail(err, CST_ERR_UNSUPPORTED, "displacement: the tessellation would exceed %lld triangles (edge "
                      "length %g; the mesh's area and edge lengths alone need at least %.3g); expected a larger "
                      "edge length", (long long)in->max_triangles, (double)r.len, least);
        goto done;
    }
    for (int t = 0; t < in->nt && st == CST_OK; t++) st = refine(&r, &stack, t, &in->idx[3 * t], in->max_triangles, err);
    if (st != CST_OK) goto done;
    /* Displace (the normals still interpolated), then the normals of the displaced surface. */
    for (size_t i = 0; i < r.p.n; i++) {
        Vec2 uv = r.has_uv ? r.uv.v[i] : v2(0.0f, 0.0f);
        float d = in->fn(in->user, r.p.v[i], r.n.v[i], uv);
        Vec3 q = v3_madd(r.p.v[i], r.n.v[i], d);
        if (!v3_is_finite(q)) {
            st = cst_fail(err, CST_ERR_INVALID_ARG, "displacement: vertex %zu moves from (%g, %g, %g) by %g to a "
                          "position that is not finite; expected a finite displacement", i, (double)r.p.v[i].x,
                          (double)r.p.v[i].y, (double)r.p.v[i].z, (double)d);
            goto done;
        }
        r.p.v[i] = q;
    }
    out->nt = (int)r.parent.n;
    out->nv = (int)r.p.n;
    displace_vertex_normals(r.p.v, out->nv, r.idx.v, out->nt, r.n.v);
    out->p = r.p.v, r.p.v = NULL;
    out->n = r.n.v, r.n.v = NULL;
    out->uv = r.uv.v, r.uv.v = NULL;
    out->idx = r.idx.v, r.idx.v = NULL;
    out->parent = r.parent.v, r.parent.v = NULL;
done:
    refiner_free(&r);
    array_free(&stack);
    return st;
}

void displaced_mesh_free(DisplacedMesh *m)
{
    free(m->p);
    free(m->n);
    free(m->uv);
    free(m->idx);
    free(m->parent);
    memset(m, 0, sizeof *m);
}
