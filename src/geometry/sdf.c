/* Signed-distance CSG trees and their sphere tracing (J. C. Hart, "Sphere tracing: a
 * geometric method for the antialiased ray tracing of implicit surfaces", The Visual
 * Computer 12(10), 1996); the primitives' exact distances as I. Quilez tabulates them. */
#include "geometry/sdf.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>

/* Lipschitz bounds (Hart 1996 §3: a field f with |f(p) - f(q)| <= L |p - q| is sphere-traced
 * with steps |f| / L). Every primitive below is an exact Euclidean distance: L = 1. Union
 * (min), intersection (max) and difference (max(a, -b)) keep max(L_a, L_b) (Hart 1996
 * §3.3). The polynomial smooth minimum s = min(a, b) - k h^2 / 4, h = max(k - |a - b|, 0) / k
 * has ds/da = (k + |a - b|) / 2k and ds/db = (k - |a - b|) / 2k for a < b (symmetric
 * otherwise), both in [0, 1] and summing to 1: grad s is a convex combination of grad a and
 * grad b, so it keeps max(L_a, L_b) too (an exponential smooth minimum would not); it is no
 * longer a distance, only a bound, and lies at most k / 4 below min(a, b). A node with
 * transform x -> A x + t evaluates its subtree at A^-1 (p - t), which scales the Lipschitz
 * bound by ||A^-1||_2 = 1 / sigma_min(A); the node multiplies its value by sigma_min(A), so
 * its bound is its subtree's again: exact distances under rotations, translations and
 * uniform scales, and under a non-uniform scale a field that underestimates the distance by
 * up to sigma_min / sigma_max (more, shorter steps; never a step through the surface). The
 * tree records each node's bound as computed (SdfNode.lip), and the march divides by the
 * root's. */

typedef struct SdfNode {
    SdfKind kind;
    int a, b;
    bool has_xf;
    double prm[4], k;
    double l2p[3][4], p2l[3][4]; /* node -> parent, parent -> node (affine rows) */
    double scale;                /* sigma_min of l2p's linear part: the field's factor */
    double lip;                  /* the node's Lipschitz bound (in its parent's space) */
} SdfNode;

struct SdfTree {
    SdfNode *nodes;
    int n;
    double o2w[3][4], w2o[3][4], scale_w;
    double lip, eps;
    int max_steps;
    double lo[3], hi[3]; /* world box of the surface, padded by 2 eps: the march's clip */
    double centre[3];
    BBox bounds;
};

/* ------------------------------------------------------------ small double algebra */

static inline double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

static inline void map_pt(const double m[3][4], const double p[3], double out[3])
{
    for (int r = 0; r < 3; r++) out[r] = m[r][0] * p[0] + m[r][1] * p[1] + m[r][2] * p[2] + m[r][3];
}

/* Affine rows of a float Transform into double, and their inverse. False when singular or
 * not finite. */
static bool affine_from(const Transform *xf, double m[3][4], double inv[3][4])
{
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) {
            m[r][c] = (double)xf->m[r][c];
            if (!isfinite(m[r][c])) return false;
        }
    double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                 m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
    if (!(fabs(det) > 1e-30) || !isfinite(det)) return false;
    double a[3][3] = {
        {(m[1][1] * m[2][2] - m[1][2] * m[2][1]) / det, (m[0][2] * m[2][1] - m[0][1] * m[2][2]) / det, (m[0][1] * m[1][2] - m[0][2] * m[1][1]) / det},
        {(m[1][2] * m[2][0] - m[1][0] * m[2][2]) / det, (m[0][0] * m[2][2] - m[0][2] * m[2][0]) / det, (m[0][2] * m[1][0] - m[0][0] * m[1][2]) / det},
        {(m[1][0] * m[2][1] - m[1][1] * m[2][0]) / det, (m[0][1] * m[2][0] - m[0][0] * m[2][1]) / det, (m[0][0] * m[1][1] - m[0][1] * m[1][0]) / det}};
    for (int r = 0; r < 3; r++) {
        for (int c = 0; c < 3; c++) inv[r][c] = a[r][c];
        inv[r][3] = -(a[r][0] * m[0][3] + a[r][1] * m[1][3] + a[r][2] * m[2][3]);
        for (int c = 0; c < 4; c++)
            if (!isfinite(inv[r][c])) return false;
    }
    return true;
}

/* The extreme singular values of a 3x3 linear part: square roots of the extreme
 * eigenvalues of M^T M by the closed form for symmetric 3x3 matrices (O. K. Smith,
 * "Eigenvalues of a symmetric 3x3 matrix", CACM 4(4), 1961). */
static void singular_extremes(const double m[3][4], double *s_min, double *s_max)
{
    double g[3][3];
    for (int i = 0; i < 3; i++)
        for (int j = 0; j < 3; j++) g[i][j] = m[0][i] * m[0][j] + m[1][i] * m[1][j] + m[2][i] * m[2][j];
    const double p1 = g[0][1] * g[0][1] + g[0][2] * g[0][2] + g[1][2] * g[1][2];
    double e_lo, e_hi;
    if (p1 == 0.0) {
        e_lo = fmin(g[0][0], fmin(g[1][1], g[2][2]));
        e_hi = fmax(g[0][0], fmax(g[1][1], g[2][2]));
    } else {
        const double q = (g[0][0] + g[1][1] + g[2][2]) / 3.0;
        const double p2 = (g[0][0] - q) * (g[0][0] - q) + (g[1][1] - q) * (g[1][1] - q) + (g[2][2] - q) * (g[2][2] - q) + 2.0 * p1;
        const double p = sqrt(p2 / 6.0);
        double b[3][3];
        for (int i = 0; i < 3; i++)
            for (int j = 0; j < 3; j++) b[i][j] = (g[i][j] - (i == j ? q : 0.0)) / p;
        double r = 0.5 * (b[0][0] * (b[1][1] * b[2][2] - b[1][2] * b[2][1]) - b[0][1] * (b[1][0] * b[2][2] - b[1][2] * b[2][0]) +
                          b[0][2] * (b[1][0] * b[2][1] - b[1][1] * b[2][0]));
        r = fmax(-1.0, fmin(1.0, r));
        const double phi = acos(r) / 3.0;
        e_hi = q + 2.0 * p * cos(phi);
        e_lo = q + 2.0 * p * cos(phi + 2.0943951023931954923); /* + 2 pi / 3 */
    }
    *s_min = sqrt(fmax(e_lo, 0.0));
    *s_max = sqrt(fmax(e_hi, 0.0));
}

/* ------------------------------------------------------------ the field */

static inline double len2(double x, double y) { return sqrt(x * x + y * y); }

/* A box of half extents h (Quilez's sdBox): exact inside and out. */
static inline double box_dist(const double p[3], double hx, double hy, double hz)
{
    const double qx = fabs(p[0]) - hx, qy = fabs(p[1]) - hy, qz = fabs(p[2]) - hz;
    const double ox = fmax(qx, 0.0), oy = fmax(qy, 0.0), oz = fmax(qz, 0.0);
    return sqrt(ox * ox + oy * oy + oz * oz) + fmin(fmax(qx, fmax(qy, qz)), 0.0);
}

static double node_eval(const SdfNode *nodes, int i, const double pin[3])
{
    const SdfNode *n = &nodes[i];
    double p[3];
    if (n->has_xf) map_pt(n->p2l, pin, p);
    else p[0] = pin[0], p[1] = pin[1], p[2] = pin[2];
    const double *c = n->prm;
    double d;
    switch (n->kind) {
    case SDF_SPHERE: d = sqrt(dot3(p, p)) - c[0]; break;
    case SDF_BOX: d = box_dist(p, c[0], c[1], c[2]); break;
    case SDF_ROUND_BOX: /* the box shrunk by the rounding radius, then dilated by it */
        d = box_dist(p, c[0] - c[3], c[1] - c[3], c[2] - c[3]) - c[3];
        break;
    case SDF_TORUS: d = len2(len2(p[0], p[1]) - c[0], p[2]) - c[1]; break;
    case SDF_CAPSULE: {
        const double z = p[2] - fmax(-c[0], fmin(c[0], p[2]));
        d = sqrt(p[0] * p[0] + p[1] * p[1] + z * z) - c[1];
        break;
    }
    case SDF_CYLINDER: {
        const double dx = len2(p[0], p[1]) - c[0], dz = fabs(p[2]) - c[1];
        d = fmin(fmax(dx, dz), 0.0) + len2(fmax(dx, 0.0), fmax(dz, 0.0));
        break;
    }
    case SDF_UNION: d = fmin(node_eval(nodes, n->a, p), node_eval(nodes, n->b, p)); break;
    case SDF_INTERSECTION: d = fmax(node_eval(nodes, n->a, p), node_eval(nodes, n->b, p)); break;
    case SDF_DIFFERENCE: d = fmax(node_eval(nodes, n->a, p), -node_eval(nodes, n->b, p)); break;
    default: { /* SDF_SMOOTH_UNION: polynomial smooth minimum (Quilez, "smooth minimum") */
        const double a = node_eval(nodes, n->a, p), b = node_eval(nodes, n->b, p);
        const double h = fmax(n->k - fabs(a - b), 0.0) / n->k;
        d = fmin(a, b) - 0.25 * h * h * n->k;
        break;
    }
    }
    return n->has_xf ? d * n->scale : d;
}

double sdf_eval(const SdfTree *t, const double p[3])
{
    double q[3];
    map_pt(t->w2o, p, q);
    return t->scale_w * node_eval(t->nodes, t->n - 1, q);
}

double sdf_tree_lipschitz(const SdfTree *t) { return t->lip; }
double sdf_tree_epsilon(const SdfTree *t) { return t->eps; }
BBox sdf_tree_bounds(const SdfTree *t) { return t->bounds; }

/* ------------------------------------------------------------ bounds */

/* The box of the 8 corners of [lo, hi] under m. */
static void map_box(const double m[3][4], double lo[3], double hi[3])
{
    double nlo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, nhi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
    for (int c = 0; c < 8; c++) {
        const double p[3] = {(c & 1) ? hi[0] : lo[0], (c & 2) ? hi[1] : lo[1], (c & 4) ? hi[2] : lo[2]};
        double q[3];
        map_pt(m, p, q);
        for (int k = 0; k < 3; k++) nlo[k] = fmin(nlo[k], q[k]), nhi[k] = fmax(nhi[k], q[k]);
    }
    for (int k = 0; k < 3; k++) lo[k] = nlo[k], hi[k] = nhi[k];
}

/* A box, in the node's parent space, holding every point where the node's field is <= c
 * (c >= 0). Exact primitives: the solid's box grown by c. min: the union; max: the
 * intersection; a minus b: a's; the smooth union lies at most k / 4 below min(a, b): the
 * union at c + k / 4. A transformed node's field is scale x its subtree's: c / scale there. */
static void node_bounds(const SdfNode *nodes, int i, double c, double lo[3], double hi[3])
{
    const SdfNode *n = &nodes[i];
    const double cl = n->has_xf ? c / n->scale : c, *q = n->prm;
    double e[3];
    switch (n->kind) {
    case SDF_SPHERE: e[0] = e[1] = e[2] = q[0]; break;
    case SDF_BOX:
    case SDF_ROUND_BOX: e[0] = q[0], e[1] = q[1], e[2] = q[2]; break;
    case SDF_TORUS: e[0] = e[1] = q[0] + q[1], e[2] = q[1]; break;
    case SDF_CAPSULE: e[0] = e[1] = q[1], e[2] = q[0] + q[1]; break;
    case SDF_CYLINDER: e[0] = e[1] = q[0], e[2] = q[1]; break;
    default: {
        double lb[3], hb[3];
        const double cc = n->kind == SDF_SMOOTH_UNION ? cl + 0.25 * n->k : cl;
        node_bounds(nodes, n->a, cc, lo, hi);
        if (n->kind != SDF_DIFFERENCE) {
            node_bounds(nodes, n->b, cc, lb, hb);
            for (int k = 0; k < 3; k++) {
                if (n->kind == SDF_INTERSECTION) lo[k] = fmax(lo[k], lb[k]), hi[k] = fmin(hi[k], hb[k]);
                else lo[k] = fmin(lo[k], lb[k]), hi[k] = fmax(hi[k], hb[k]);
            }
        }
        if (n->has_xf) map_box(n->l2p, lo, hi);
        return;
    }
    }
    for (int k = 0; k < 3; k++) lo[k] = -(e[k] + cl), hi[k] = e[k] + cl;
    if (n->has_xf) map_box(n->l2p, lo, hi);
}

/* ------------------------------------------------------------ construction */

const char *sdf_error_string(SdfError e)
{
    switch (e) {
    case SDF_OK: return "no error";
    case SDF_ERR_EMPTY: return "the tree has no nodes, more than 256, or an empty surface";
    case SDF_ERR_KIND: return "not a known node kind";
    case SDF_ERR_PARAM: return "primitive lengths must be finite and > 0 (a rounded box's radius at most its smallest "
                               "half extent; a torus' minor radius below its major radius; a capsule's half length >= 0)";
    case SDF_ERR_BLEND: return "a smooth union's k must be finite and > 0";
    case SDF_ERR_OPERAND: return "an operand must be an earlier node";
    case SDF_ERR_SHARED: return "every node but the last (the root) must be the operand of exactly one operator";
    case SDF_ERR_DEPTH: return "the tree is deeper than 24 levels";
    case SDF_ERR_TRANSFORM: return "a transform is singular or not finite";
    case SDF_ERR_OPTIONS: return "epsilon must be finite and >= 0, max_steps in [0, 65536]";
    }
    return "unknown error";
}

static SdfError check_prim(const SdfNodeDesc *d)
{
    const double *c = d->prm;
    int need = d->kind == SDF_SPHERE ? 1 : d->kind == SDF_BOX ? 3 : d->kind == SDF_ROUND_BOX ? 4 : 2;
    for (int k = 0; k < need; k++)
        if (!(fabs(c[k]) <= 1e18)) return SDF_ERR_PARAM;
    switch (d->kind) {
    case SDF_SPHERE: return c[0] > 0.0 ? SDF_OK : SDF_ERR_PARAM;
    case SDF_BOX: return c[0] > 0.0 && c[1] > 0.0 && c[2] > 0.0 ? SDF_OK : SDF_ERR_PARAM;
    case SDF_ROUND_BOX:
        return c[0] > 0.0 && c[1] > 0.0 && c[2] > 0.0 && c[3] > 0.0 && c[3] <= fmin(c[0], fmin(c[1], c[2]))
                   ? SDF_OK : SDF_ERR_PARAM;
    case SDF_TORUS: return c[1] > 0.0 && c[1] < c[0] ? SDF_OK : SDF_ERR_PARAM;
    case SDF_CAPSULE: return c[0] >= 0.0 && c[1] > 0.0 ? SDF_OK : SDF_ERR_PARAM;
    default: return c[0] > 0.0 && c[1] > 0.0 ? SDF_OK : SDF_ERR_PARAM; /* SDF_CYLINDER */
    }
}

SdfError sdf_tree_create(const SdfNodeDesc *nodes, int n, const Transform *world_from_object,
                         const SdfOptions *opt, SdfTree **out, int *bad)
{
    *out = NULL;
    *bad = -1;
    if (!nodes || n < 1 || n > SDF_MAX_NODES) return SDF_ERR_EMPTY;
    const SdfOptions o = opt ? *opt : (SdfOptions){0};
    if (!(o.epsilon >= 0.0 && isfinite(o.epsilon)) || o.max_steps < 0 || o.max_steps > SDF_MAX_STEPS)
        return SDF_ERR_OPTIONS;
    SdfTree *t = calloc(1, sizeof *t);
    SdfNode *nd = calloc((size_t)n, sizeof *nd);
    int *uses = calloc((size_t)n, sizeof *uses), *depth = calloc((size_t)n, sizeof *depth);
    SdfError e = SDF_OK;
    if (!t || !nd || !uses || !depth) { e = SDF_ERR_EMPTY; goto fail; }
    t->nodes = nd;
    t->n = n;
    for (int i = 0; i < n; i++) {
        const SdfNodeDesc *d = &nodes[i];
        SdfNode *m = &nd[i];
        *bad = i;
        if ((unsigned)d->kind >= SDF_KIND_COUNT) { e = SDF_ERR_KIND; goto fail; }
        m->kind = d->kind;
        for (int k = 0; k < 4; k++) m->prm[k] = d->prm[k];
        if ((int)d->kind < (int)SDF_FIRST_OPERATOR) {
            if ((e = check_prim(d)) != SDF_OK) goto fail;
            m->lip = 1.0;
            depth[i] = 1;
        } else {
            if (d->a < 0 || d->a >= i || d->b < 0 || d->b >= i || d->a == d->b) { e = SDF_ERR_OPERAND; goto fail; }
            if (d->kind == SDF_SMOOTH_UNION && !(d->k > 0.0 && d->k <= 1e18)) { e = SDF_ERR_BLEND; goto fail; }
            m->a = d->a, m->b = d->b, m->k = d->k;
            uses[d->a]++, uses[d->b]++;
            m->lip = fmax(nd[d->a].lip, nd[d->b].lip);
            depth[i] = 1 + (depth[d->a] > depth[d->b] ? depth[d->a] : depth[d->b]);
            if (depth[i] > SDF_MAX_DEPTH) { e = SDF_ERR_DEPTH; goto fail; }
        }
        if (d->has_xf) {
            if (!affine_from(&d->parent_from_node, m->l2p, m->p2l)) { e = SDF_ERR_TRANSFORM; goto fail; }
            double s_min, s_max, i_min, i_max;
            singular_extremes(m->l2p, &s_min, &s_max);
            singular_extremes(m->p2l, &i_min, &i_max);
            if (!(s_min > 0.0)) { e = SDF_ERR_TRANSFORM; goto fail; }
            m->has_xf = true;
            m->scale = s_min;
            m->lip *= s_min * i_max; /* = 1 up to rounding: see the top of the file */
        }
    }
    for (int i = 0; i < n; i++) {
        *bad = i;
        if (uses[i] != (i == n - 1 ? 0 : 1)) { e = SDF_ERR_SHARED; goto fail; }
    }
    *bad = -1;
    {
        Transform id = transform_identity();
        if (!affine_from(world_from_object ? world_from_object : &id, t->o2w, t->w2o)) { e = SDF_ERR_TRANSFORM; goto fail; }
        double s_min, s_max, i_min, i_max;
        singular_extremes(t->o2w, &s_min, &s_max);
        singular_extremes(t->w2o, &i_min, &i_max);
        if (!(s_min > 0.0)) { e = SDF_ERR_TRANSFORM; goto fail; }
        t->scale_w = s_min;
        t->lip = nd[n - 1].lip * s_min * i_max;
    }
    node_bounds(nd, n - 1, 0.0, t->lo, t->hi);
    for (int k = 0; k < 3; k++)
        if (!(t->lo[k] <= t->hi[k])) { e = SDF_ERR_EMPTY; goto fail; } /* an intersection of disjoint boxes */
    map_box(t->o2w, t->lo, t->hi);
    double ext = 0.0, diag2 = 0.0;
    for (int k = 0; k < 3; k++) {
        ext = fmax(ext, fmax(fabs(t->lo[k]), fabs(t->hi[k])));
        diag2 += (t->hi[k] - t->lo[k]) * (t->hi[k] - t->lo[k]);
        t->centre[k] = 0.5 * (t->lo[k] + t->hi[k]);
    }
    if (!(ext <= 1e18)) { e = SDF_ERR_PARAM; goto fail; }
    /* Epsilon, the march's least step and the distance under which the side a ray starts on
     * is not yet decided: relative to the shape's world size and its distance from the
     * origin, so it stays far above float rounding of the hit points (2^-24 |p|) at any
     * scene scale. */
    t->eps = o.epsilon > 0.0 ? o.epsilon : SDF_EPS_RELATIVE * fmax(sqrt(diag2), ext);
    t->max_steps = o.max_steps > 0 ? o.max_steps : SDF_DEFAULT_STEPS;
    const double pad = 2.0 * t->eps;
    double fpad = 0.0;
    for (int k = 0; k < 3; k++) {
        t->lo[k] -= pad, t->hi[k] += pad;
        fpad = fmax(fpad, fmax(fabs(t->lo[k]), fabs(t->hi[k])));
    }
    fpad = fpad * 0x1p-20 + 1e-30; /* rounding the double box to float must not shrink it */
    t->bounds.min = v3((float)(t->lo[0] - fpad), (float)(t->lo[1] - fpad), (float)(t->lo[2] - fpad));
    t->bounds.max = v3((float)(t->hi[0] + fpad), (float)(t->hi[1] + fpad), (float)(t->hi[2] + fpad));
    if (!v3_is_finite(t->bounds.min) || !v3_is_finite(t->bounds.max)) { e = SDF_ERR_PARAM; goto fail; }
    free(uses);
    free(depth);
    *out = t;
    return SDF_OK;
fail:
    free(uses);
    free(depth);
    if (t) t->nodes = nd;
    else free(nd);
    sdf_tree_destroy(t);
    return e;
}

void sdf_tree_destroy(SdfTree *t)
{
    if (!t) return;
    free(t->nodes);
    free(t);
}

/* ------------------------------------------------------------ sphere tracing */

static inline double field_at(const SdfTree *t, const double o[3], const double d[3], double s)
{
    const double p[3] = {o[0] + s * d[0], o[1] + s * d[1], o[2] + s * d[2]};
    return sdf_eval(t, p);
}

/* March from the box entry (or t_min inside the box), steps of max(|f| / L, eps) (Hart 1996
 * eq. 4: the ball of radius |f| / L about the point holds no surface), until the sign of f
 * changes; then bisection on [previous, current] to half a float ulp of t. A march from
 * the box entry starts outside (the box holds every point with f <= 0); from inside the box
 * it starts on the side of the first point at least eps from the surface, so a ray leaving
 * a surface (its origin within rounding of it) ignores that surface, as the fixed-offset
 * spawn of the other shapes does. More than max_steps steps: a miss (a ray grazing the
 * surface within eps for that long). */
bool sdf_intersect(const SdfTree *t, const Ray *r, float *t_out)
{
    const double o[3] = {(double)r->o.x, (double)r->o.y, (double)r->o.z};
    const double d[3] = {(double)r->d.x, (double)r->d.y, (double)r->d.z};
    const double dl = sqrt(dot3(d, d));
    if (!(dl > 0.0) || !isfinite(dl)) return false;
    double t0 = (double)r->t_min, t1 = HUGE_VAL;
    for (int k = 0; k < 3; k++) {
        if (d[k] == 0.0) {
            if (o[k] < t->lo[k] || o[k] > t->hi[k]) return false;
            continue;
        }
        double ta = (t->lo[k] - o[k]) / d[k], tb = (t->hi[k] - o[k]) / d[k];
        if (ta > tb) { double tmp = ta; ta = tb; tb = tmp; }
        t0 = fmax(t0, ta);
        t1 = fmin(t1, tb);
    }
    if (!(t0 <= t1)) return false;
    const double tmax = (double)r->t_max, inv = 1.0 / (dl * t->lip), min_step = t->eps / dl;
    int side = t0 > (double)r->t_min ? 1 : 0;
    double tp = t0, tc = t0;
    for (int i = 0; i < t->max_steps; i++) {
        const double f = field_at(t, o, d, tc);
        const int s = f > 0.0 ? 1 : -1;
        if (side == 0) {
            if (fabs(f) >= t->eps * t->lip) side = s;
        } else if (s != side) {
            double a = tp, b = tc;
            for (int k = 0; k < 80 && b - a > 0x1p-25 * fabs(b); k++) {
                const double m = 0.5 * (a + b);
                if (!(m > a && m < b)) break;
                if ((field_at(t, o, d, m) > 0.0 ? 1 : -1) == side) a = m;
                else b = m;
            }
            const float tf = (float)(0.5 * (a + b));
            if (!(tf > r->t_min && tf < r->t_max)) return false;
            *t_out = tf;
            return true;
        }
        if (tc >= t1 || tc >= tmax) return false;
        tp = tc;
        tc = fmin(tc + fmax(fabs(f) * inv, min_step), t1);
    }
    return false;
}

/* The gradient by central differences with step eps (error O(eps^2) times the third
 * derivative on smooth parts). */
static void gradient(const SdfTree *t, const double p[3], double g[3])
{
    const double h = t->eps;
    for (int k = 0; k < 3; k++) {
        double a[3] = {p[0], p[1], p[2]}, b[3] = {p[0], p[1], p[2]};
        a[k] += h, b[k] -= h;
        g[k] = (sdf_eval(t, a) - sdf_eval(t, b)) / (2.0 * h);
    }
}

void sdf_surface(const SdfTree *t, const Ray *r, float t_hit, Vec3 *p_out, Vec3 *n_out, Vec2 *uv)
{
    const double s = (double)t_hit;
    double p[3] = {(double)r->o.x + s * (double)r->d.x, (double)r->o.y + s * (double)r->d.y,
                   (double)r->o.z + s * (double)r->d.z}, g[3];
    gradient(t, p, g);
    const double g2 = dot3(g, g);
    if (g2 > 0.0 && isfinite(g2)) {
        /* one Newton step onto f = 0 along the gradient */
        const double f = sdf_eval(t, p) / g2;
        for (int k = 0; k < 3; k++) p[k] -= f * g[k];
        const double gl = sqrt(g2);
        *n_out = v3((float)(g[0] / gl), (float)(g[1] / gl), (float)(g[2] / gl));
    } else {
        /* a flat spot of the field (the gradient cancels): face the ray */
        *n_out = v3_neg(v3_normalize(r->d));
    }
    *p_out = v3((float)p[0], (float)p[1], (float)p[2]);
    const double q[3] = {p[0] - t->centre[0], p[1] - t->centre[1], p[2] - t->centre[2]};
    const double ql = sqrt(dot3(q, q));
    double phi = atan2(q[1], q[0]);
    if (phi < 0.0) phi += 6.28318530717958647692;
    const double theta = ql > 0.0 ? acos(fmax(-1.0, fmin(1.0, q[2] / ql))) : 0.0;
    *uv = v2((float)(phi / 6.28318530717958647692), (float)(theta / 3.14159265358979323846));
}
