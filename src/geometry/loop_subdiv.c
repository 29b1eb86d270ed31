/* Loop subdivision (Loop 1987) on an indexed triangle mesh: edge topology by sorting, the
 * even and odd vertex rules with pbrt-v4's boundary rules, the limit positions and the limit
 * normals from the tangent masks. */
#include "geometry/loop_subdiv.h"

#include <stdlib.h>
#include <string.h>

/* Edges of one level. Face-edge (half-edge) h = 3 f + k runs from idx[h] to
 * idx[3 f + (k + 1) % 3]; edge_of[h] is its edge. Edge e joins edge_v[2e] < edge_v[2e+1]
 * and has the half-edges edge_he[2e] and edge_he[2e+1] (-1: e is on the boundary). Edge
 * ids follow the first half-edge that meets them, in face order (as pbrt-v4 numbers its
 * new vertices). */
typedef struct Topo {
    int ne;
    int *edge_of;
    int *edge_v;
    int *edge_he;
} Topo;

typedef struct HalfKey {
    int lo, hi, he;
} HalfKey;

static int half_key_cmp(const void *pa, const void *pb)
{
    const HalfKey *a = pa, *b = pb;
    if (a->lo != b->lo) return a->lo < b->lo ? -1 : 1;
    if (a->hi != b->hi) return a->hi < b->hi ? -1 : 1;
    return (a->he > b->he) - (a->he < b->he);
}

static int next3(int k) { return k == 2 ? 0 : k + 1; }

static void topo_free(Topo *t)
{
    free(t->edge_of);
    free(t->edge_v);
    free(t->edge_he);
    memset(t, 0, sizeof *t);
}

static CstStatus topo_build(const int *idx, int nt, Topo *t, CstError *err)
{
    memset(t, 0, sizeof *t);
    size_t nh = 3 * (size_t)nt;
    HalfKey *keys = malloc((nh ? nh : 1) * sizeof *keys);
    int *run_of_first = malloc((nh ? nh : 1) * sizeof *run_of_first); /* run + 1 at a run's first half-edge */
    t->edge_of = malloc((nh ? nh : 1) * sizeof *t->edge_of);
    CstStatus st = CST_OK;
    if (!keys || !run_of_first || !t->edge_of) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for the edges of %d triangles", nt);
        goto done;
    }
    for (int f = 0; f < nt; f++)
        for (int k = 0; k < 3; k++) {
            int a = idx[3 * f + k], b = idx[3 * f + next3(k)];
            if (a == b) {
                st = cst_fail(err, CST_ERR_INVALID_ARG, "face %d has vertex %d twice; expected three "
                              "distinct vertices", f, a);
                goto done;
            }
            keys[3 * f + k] = (HalfKey){a < b ? a : b, a < b ? b : a, 3 * f + k};
        }
    qsort(keys, nh, sizeof *keys, half_key_cmp);
    /* runs of equal (lo, hi): one edge each, its first half-edge the run's smallest */
    memset(run_of_first, 0, nh * sizeof *run_of_first);
    size_t runs = 0;
    for (size_t i = 0; i < nh;) {
        size_t j = i + 1;
        while (j < nh && keys[j].lo == keys[i].lo && keys[j].hi == keys[i].hi) j++;
        if (j - i > 2) {
            st = cst_fail(err, CST_ERR_INVALID_ARG, "edge (%d, %d) is shared by %zu faces (%d, %d, %d%s); "
                          "expected at most two (a manifold mesh)", keys[i].lo, keys[i].hi, j - i,
                          keys[i].he / 3, keys[i + 1].he / 3, keys[i + 2].he / 3, j - i > 3 ? ", ..." : "");
            goto done;
        }
        run_of_first[keys[i].he] = (int)i + 1; /* the run's start in keys, + 1 */
        runs++;
        i = j;
    }
    t->edge_v = malloc(2 * (runs ? runs : 1) * sizeof *t->edge_v);
    t->edge_he = malloc(2 * (runs ? runs : 1) * sizeof *t->edge_he);
    if (!t->edge_v || !t->edge_he) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for the %zu edges of %d triangles", runs, nt);
        goto done;
    }
    t->ne = 0;
    for (size_t h = 0; h < nh; h++) {
        if (!run_of_first[h]) continue;
        size_t i = (size_t)run_of_first[h] - 1;
        int e = t->ne++;
        t->edge_v[2 * e] = keys[i].lo;
        t->edge_v[2 * e + 1] = keys[i].hi;
        t->edge_he[2 * e] = keys[i].he;
        int two = i + 1 < nh && keys[i + 1].lo == keys[i].lo && keys[i + 1].hi == keys[i].hi;
        t->edge_he[2 * e + 1] = two ? keys[i + 1].he : -1;
        t->edge_of[keys[i].he] = e;
        if (two) t->edge_of[keys[i + 1].he] = e;
    }
done:
    free(keys);
    free(run_of_first);
    if (st) topo_free(t);
    return st;
}

/* beta(n) of the interior even rule: Warren's simplification of Loop's weights (3/16 for
 * valence 3, 3 / (8 n) otherwise, Loop's own value 1/16 for the regular valence 6), as
 * pbrt-v4 uses. */
static float loop_beta(int n) { return n == 3 ? 3.0f / 16.0f : 3.0f / (8.0f * (float)n); }

/* The limit mask's weight of each ring vertex for that beta: gamma = 1 / (n + 3 / (8 beta))
 * (the left eigenvector of the subdivision matrix for eigenvalue 1). */
static float loop_gamma(int n) { return 1.0f / ((float)n + 3.0f / (8.0f * loop_beta(n))); }

/* Per vertex: valence (number of edges), the sum of its neighbours and the two neighbours
 * along boundary edges (nb counts them: 0 interior, 2 on the boundary). */
typedef struct Ring {
    int valence, nb;
    int b[2];
    Vec3 sum;
} Ring;

static CstStatus rings_from_edges(const Vec3 *p, int nv, const Topo *t, Ring *r, CstError *err)
{
    memset(r, 0, (size_t)nv * sizeof *r);
    for (int e = 0; e < t->ne; e++) {
        int a = t->edge_v[2 * e], b = t->edge_v[2 * e + 1];
        r[a].valence++;
        r[b].valence++;
        r[a].sum = v3_add(r[a].sum, p[b]);
        r[b].sum = v3_add(r[b].sum, p[a]);
        if (t->edge_he[2 * e + 1] < 0) {
            if (r[a].nb < 2) r[a].b[r[a].nb] = b;
            if (r[b].nb < 2) r[b].b[r[b].nb] = a;
            r[a].nb++;
            r[b].nb++;
        }
    }
    for (int v = 0; v < nv; v++)
        if (r[v].nb != 0 && r[v].nb != 2)
            return cst_fail(err, CST_ERR_INVALID_ARG, "vertex %d is on %d boundary edges; expected 2 "
                            "(its faces form more than one fan: not a manifold mesh)", v, r[v].nb);
    return CST_OK;
}

/* One level: even vertices (the old ones, same indices) by the one-ring rule
 * (1 - n beta) v + beta sum, or on the boundary 3/4 v + 1/8 (b0 + b1); odd vertices
 * nv + e, one per edge, 3/8 (a + b) + 1/8 (c + d), or on the boundary (a + b) / 2; each
 * face (a, b, c) with edge vertices m0 (a-b), m1 (b-c), m2 (c-a) becomes (a, m0, m2),
 * (m0, b, m1), (m2, m1, c), (m0, m1, m2), pbrt-v4's order. */
static void refine(const Vec3 *p, int nv, const int *idx, int nt, const Topo *t, const Ring *r, Vec3 *np,
                   int *nidx)
{
    for (int v = 0; v < nv; v++) {
        if (r[v].valence == 0) {
            np[v] = p[v];
        } else if (r[v].nb == 2) {
            np[v] = v3_add(v3_scale(p[v], 0.75f), v3_scale(v3_add(p[r[v].b[0]], p[r[v].b[1]]), 0.125f));
        } else {
            float beta = loop_beta(r[v].valence);
            np[v] = v3_add(v3_scale(p[v], 1.0f - (float)r[v].valence * beta), v3_scale(r[v].sum, beta));
        }
    }
    for (int e = 0; e < t->ne; e++) {
        Vec3 a = p[t->edge_v[2 * e]], b = p[t->edge_v[2 * e + 1]];
        int h0 = t->edge_he[2 * e], h1 = t->edge_he[2 * e + 1];
        if (h1 < 0) {
            np[nv + e] = v3_scale(v3_add(a, b), 0.5f);
        } else {
            /* the vertex opposite half-edge h = 3 f + k is idx[3 f + (k + 2) % 3] */
            Vec3 c = p[idx[3 * (h0 / 3) + next3(next3(h0 % 3))]];
            Vec3 d = p[idx[3 * (h1 / 3) + next3(next3(h1 % 3))]];
            np[nv + e] = v3_add(v3_scale(v3_add(a, b), 0.375f), v3_scale(v3_add(c, d), 0.125f));
        }
    }
    for (int f = 0; f < nt; f++) {
        int a = idx[3 * f], b = idx[3 * f + 1], c = idx[3 * f + 2];
        int m0 = nv + t->edge_of[3 * f], m1 = nv + t->edge_of[3 * f + 1], m2 = nv + t->edge_of[3 * f + 2];
        int *o = &nidx[12 * (size_t)f];
        o[0] = a;  o[1] = m0;  o[2] = m2;
        o[3] = m0; o[4] = b;   o[5] = m1;
        o[6] = m2; o[7] = m1;  o[8] = c;
        o[9] = m0; o[10] = m1; o[11] = m2;
    }
}

/* The vertex of face f that is neither v nor x. */
static int other_vertex(const int *idx, int f, int v, int x)
{
    for (int k = 0; k < 2; k++)
        if (idx[3 * f + k] != v && idx[3 * f + k] != x) return idx[3 * f + k];
    return idx[3 * f + 2];
}

/* The face across the edge (v, y) of face f, or -1 where that edge is on the boundary. */
static int face_across(const int *idx, const Topo *t, int f, int v, int y)
{
    int e = 0;
    for (int k = 0; k < 3; k++) {
        int p0 = idx[3 * f + k], p1 = idx[3 * f + next3(k)];
        if ((p0 == v && p1 == y) || (p1 == v && p0 == y)) e = t->edge_of[3 * f + k];
    }
    int h0 = t->edge_he[2 * e], h1 = t->edge_he[2 * e + 1];
    return h1 < 0 ? -1 : (h0 / 3 == f ? h1 / 3 : h0 / 3);
}

/* The one-ring of v in order around it: the walk from face to face across the edges at v
 * (entering a face through one ring vertex x, leaving through the other, y), which needs
 * no consistent orientation. corners[first..last) are the half-edges 3 f + k with
 * idx[3 f + k] = v. On the boundary the ring starts and ends at the two boundary
 * neighbours (valence = faces + 1), inside it closes (valence = faces). Returns the ring's
 * length, or -1 when the walk does not reach every face at v (more than one fan). ring has
 * room for faces + 1 entries. */
static int ordered_ring(const int *idx, const Topo *t, const int *corners, int first, int last, int v,
                        int *ring)
{
    const int m = last - first;
    const int f0 = corners[first] / 3;
    const int a0 = idx[3 * f0 + next3(corners[first] % 3)];
    /* backwards from f0 (leaving through a0) to a boundary face, if there is one */
    int f = f0, x = other_vertex(idx, f0, v, a0), start_f = f0, start_x = a0, boundary = 0;
    for (int steps = 0; steps <= m; steps++) {
        int y = other_vertex(idx, f, v, x), g = face_across(idx, t, f, v, y);
        if (g < 0) { /* f is an end face: the ring starts at y */
            start_f = f;
            start_x = y;
            boundary = 1;
            break;
        }
        if (g == f0) break; /* closed: an interior vertex */
        f = g;
        x = y;
    }
    /* forwards from start_f, entering through start_x */
    int len = 0, visited = 0;
    f = start_f;
    x = start_x;
    ring[len++] = x;
    for (;;) {
        int y = other_vertex(idx, f, v, x), g = face_across(idx, t, f, v, y);
        visited++;
        if (g < 0) {
            ring[len++] = y;
            break;
        }
        if (g == start_f || visited >= m) break;
        ring[len++] = y;
        f = g;
        x = y;
    }
    if (visited != m || (!boundary && len != m)) return -1;
    return len;
}

/* Vertex-to-corner lists (CSR): corners[start[v] .. start[v + 1]). */
static CstStatus corner_lists(const int *idx, int nv, int nt, int **start_out, int **corners_out, CstError *err)
{
    int *start = calloc((size_t)nv + 1, sizeof *start);
    int *corners = malloc((nt > 0 ? 3 * (size_t)nt : 1) * sizeof *corners);
    if (!start || !corners) {
        free(start);
        free(corners);
        return cst_fail(err, CST_ERR_OOM, "out of memory for the corners of %d triangles", nt);
    }
    for (int h = 0; h < 3 * nt; h++) start[idx[h] + 1]++;
    for (int v = 0; v < nv; v++) start[v + 1] += start[v];
    int *fill = malloc(((size_t)nv ? (size_t)nv : 1) * sizeof *fill);
    if (!fill) {
        free(start);
        free(corners);
        return cst_fail(err, CST_ERR_OOM, "out of memory for the corners of %d triangles", nt);
    }
    memcpy(fill, start, (size_t)nv * sizeof *fill);
    for (int h = 0; h < 3 * nt; h++) corners[fill[idx[h]]++] = h;
    free(fill);
    *start_out = start;
    *corners_out = corners;
    return CST_OK;
}

/* Every vertex's faces must form one fan (checked on the control mesh: refinement keeps
 * the property, its new vertices being regular). */
static CstStatus check_fans(const int *idx, int nv, int nt, const Topo *t, CstError *err)
{
    int *start = NULL, *corners = NULL;
    CstStatus st = corner_lists(idx, nv, nt, &start, &corners, err);
    if (st) return st;
    int maxc = 0;
    for (int v = 0; v < nv; v++) maxc = start[v + 1] - start[v] > maxc ? start[v + 1] - start[v] : maxc;
    int *ring = malloc(((size_t)maxc + 2) * sizeof *ring);
    if (!ring) st = cst_fail(err, CST_ERR_OOM, "out of memory for a vertex ring of %d faces", maxc);
    for (int v = 0; v < nv && !st; v++)
        if (start[v + 1] > start[v] && ordered_ring(idx, t, corners, start[v], start[v + 1], v, ring) < 0)
            st = cst_fail(err, CST_ERR_INVALID_ARG, "vertex %d: its %d faces form more than one fan; "
                          "expected a manifold mesh", v, start[v + 1] - start[v]);
    free(ring);
    free(start);
    free(corners);
    return st;
}

/* The limit normal from the tangent masks of Loop's thesis applied to the ring (pbrt-v4's
 * masks): inside, S = sum cos(2 pi j / n) r_j and T = sum sin(2 pi j / n) r_j; on the
 * boundary S = r_last - r_0 and T by valence (2: r0 + r1 - 2 v; 3: r1 - v; 4:
 * -r0 + 2 r1 + 2 r2 - r3 - 2 v; else with theta = pi / (n - 1): -(sin theta (r0 + r_last)
 * + sum_k (2 cos theta - 2) sin(k theta) r_k)). The masks are applied to the last level's
 * control points (pbrt-v4 applies them to the ring's limit points, a difference of the
 * order of the level's edge length squared). */
static Vec3 limit_normal(const Vec3 *p, Vec3 pv, const int *ring, int n, int boundary)
{
    Vec3 s = v3s(0.0f), tg = v3s(0.0f);
    if (!boundary) {
        for (int j = 0; j < n; j++) {
            float ang = 2.0f * CST_PI * (float)j / (float)n;
            s = v3_madd(s, p[ring[j]], cosf(ang));
            tg = v3_madd(tg, p[ring[j]], sinf(ang));
        }
    } else {
        s = v3_sub(p[ring[n - 1]], p[ring[0]]);
        if (n == 2) {
            tg = v3_sub(v3_add(p[ring[0]], p[ring[1]]), v3_scale(pv, 2.0f));
        } else if (n == 3) {
            tg = v3_sub(p[ring[1]], pv);
        } else if (n == 4) {
            tg = v3_sub(v3_scale(v3_add(p[ring[1]], p[ring[2]]), 2.0f),
                        v3_add(v3_add(p[ring[0]], p[ring[3]]), v3_scale(pv, 2.0f)));
        } else {
            float th = CST_PI / (float)(n - 1);
            tg = v3_scale(v3_add(p[ring[0]], p[ring[n - 1]]), sinf(th));
            for (int k = 1; k < n - 1; k++)
                tg = v3_madd(tg, p[ring[k]], (2.0f * cosf(th) - 2.0f) * sinf((float)k * th));
            tg = v3_neg(tg);
        }
    }
    return v3_cross(s, tg);
}

/* Pushes the last level to the limit: positions (1 - n gamma) v + gamma sum inside,
 * 3/5 v + 1/5 (b0 + b1) on the boundary; normals from limit_normal, unit, turned against
 * the sum of the faces' winding normals at the vertex (pbrt-v4's ring runs clockwise seen
 * from the winding's side, so its cross(S, T) points that way). */
static CstStatus push_to_limit(const Vec3 *p, int nv, const int *idx, int nt, const Topo *t, const Ring *r,
                               Vec3 *lp, Vec3 *ln, CstError *err)
{
    int *start = NULL, *corners = NULL;
    CstStatus st = corner_lists(idx, nv, nt, &start, &corners, err);
    if (st) return st;
    int maxc = 0;
    for (int v = 0; v < nv; v++) maxc = start[v + 1] - start[v] > maxc ? start[v + 1] - start[v] : maxc;
    int *ring = malloc(((size_t)maxc + 2) * sizeof *ring);
    if (!ring) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for a vertex ring of %d faces", maxc);
        goto done;
    }
    for (int v = 0; v < nv; v++) {
        ln[v] = v3s(0.0f);
        if (r[v].valence == 0) {
            lp[v] = p[v];
            continue;
        }
        if (r[v].nb == 2) {
            lp[v] = v3_add(v3_scale(p[v], 0.6f), v3_scale(v3_add(p[r[v].b[0]], p[r[v].b[1]]), 0.2f));
        } else {
            float g = loop_gamma(r[v].valence);
            lp[v] = v3_add(v3_scale(p[v], 1.0f - (float)r[v].valence * g), v3_scale(r[v].sum, g));
        }
        int n = ordered_ring(idx, t, corners, start[v], start[v + 1], v, ring);
        if (n < 2) continue; /* cannot happen after check_fans; a zero normal */
        Vec3 nn = limit_normal(p, p[v], ring, n, r[v].nb == 2);
        Vec3 wind = v3s(0.0f);
        for (int c = start[v]; c < start[v + 1]; c++) {
            const int *tri = &idx[3 * (corners[c] / 3)];
            wind = v3_add(wind, v3_cross(v3_sub(p[tri[1]], p[tri[0]]), v3_sub(p[tri[2]], p[tri[0]])));
        }
        if (v3_dot(nn, wind) > 0.0f) nn = v3_neg(nn);
        float len = v3_length(nn);
        ln[v] = len > 0.0f && isfinite(len) ? v3_scale(nn, 1.0f / len) : v3s(0.0f);
    }
done:
    free(ring);
    free(start);
    free(corners);
    return st;
}

int64_t loop_triangle_count(int nt, int levels)
{
    int64_t n = nt;
    for (int i = 0; i < levels; i++) {
        n *= 4;
        if (n > INT32_MAX / 3) return -1;
    }
    return n;
}

void loop_mesh_free(LoopMesh *m)
{
    if (!m) return;
    free(m->p);
    free(m->n);
    free(m->idx);
    memset(m, 0, sizeof *m);
}

CstStatus loop_subdivide(const Vec3 *p0, int nv0, const int *idx0, int nt0, int levels, LoopMesh *out,
                         CstError *err)
{
    memset(out, 0, sizeof *out);
    if (levels < 0) levels = 0;
    if (nv0 < 0 || nt0 < 0 || loop_triangle_count(nt0, levels) < 0)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "%d triangles refined %d times would exceed %d triangles",
                        nt0, levels, INT32_MAX / 3);
    for (int h = 0; h < 3 * nt0; h++)
        if (idx0[h] < 0 || idx0[h] >= nv0)
            return cst_fail(err, CST_ERR_INVALID_ARG, "face %d: vertex index %d is out of range; expected "
                            "0 to %d", h / 3, idx0[h], nv0 - 1);
    Vec3 *p = malloc(((size_t)nv0 ? (size_t)nv0 : 1) * sizeof *p);
    int *idx = malloc((nt0 > 0 ? 3 * (size_t)nt0 : 1) * sizeof *idx);
    Ring *r = NULL;
    Topo t = {0};
    CstStatus st = CST_OK;
    if (!p || !idx) { st = cst_fail(err, CST_ERR_OOM, "out of memory for a subdivision mesh"); goto fail; }
    if (nv0 > 0) memcpy(p, p0, (size_t)nv0 * sizeof *p); /* an empty mesh may pass NULLs */
    if (nt0 > 0) memcpy(idx, idx0, 3 * (size_t)nt0 * sizeof *idx);
    int nv = nv0, nt = nt0;
    if ((st = topo_build(idx, nt, &t, err))) goto fail;
    if ((st = check_fans(idx, nv, nt, &t, err))) goto fail;
    for (int level = 0;; level++) {
        free(r);
        r = malloc(((size_t)nv ? (size_t)nv : 1) * sizeof *r);
        if (!r) { st = cst_fail(err, CST_ERR_OOM, "out of memory for %d vertex rings", nv); goto fail; }
        if ((st = rings_from_edges(p, nv, &t, r, err))) goto fail;
        if (level == levels) break;
        size_t nnv = (size_t)nv + (size_t)t.ne;
        if (nnv > INT32_MAX) {
            st = cst_fail(err, CST_ERR_UNSUPPORTED, "the subdivision mesh would exceed %d vertices", INT32_MAX);
            goto fail;
        }
        Vec3 *np = malloc(nnv * sizeof *np);
        int *nidx = malloc(12 * ((size_t)nt ? (size_t)nt : 1) * sizeof *nidx);
        if (!np || !nidx) {
            free(np);
            free(nidx);
            st = cst_fail(err, CST_ERR_OOM, "out of memory for subdivision level %d", level + 1);
            goto fail;
        }
        refine(p, nv, idx, nt, &t, r, np, nidx);
        free(p);
        free(idx);
        p = np;
        idx = nidx;
        nv = (int)nnv;
        nt *= 4;
        topo_free(&t);
        if ((st = topo_build(idx, nt, &t, err))) goto fail;
    }
    out->p = malloc(((size_t)nv ? (size_t)nv : 1) * sizeof *out->p);
    out->n = malloc(((size_t)nv ? (size_t)nv : 1) * sizeof *out->n);
    if (!out->p || !out->n) { st = cst_fail(err, CST_ERR_OOM, "out of memory for %d limit points", nv); goto fail; }
    if ((st = push_to_limit(p, nv, idx, nt, &t, r, out->p, out->n, err))) goto fail;
    out->nv = nv;
    out->idx = idx;
    out->nt = nt;
    free(p);
    free(r);
    topo_free(&t);
    return CST_OK;
fail:
    free(p);
    free(idx);
    free(r);
    topo_free(&t);
    loop_mesh_free(out);
    return st;
}
