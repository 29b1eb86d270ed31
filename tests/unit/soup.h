/* The scenes of the acceleration structures' tests (test_accel_conformance over every back
 * end; test_bvh, test_kdtree, test_grid check their structures' invariants on the same
 * scenes): random soups and spheres, closed and axis-aligned meshes, degenerate cases. One
 * generator per kind, so every back end is tested on the same scenes. Include after cmocka.h. */
#ifndef CST_TESTS_UNIT_SOUP_H
#define CST_TESTS_UNIT_SOUP_H

#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel_geometry.h"
#include "core/rng.h"
#include "geometry/shape.h"
#include "geometry/sphere.h"
#include "math/transform.h"
#include "math/vec3.h"

typedef struct Soup {
    Vec3 *pos;
    int32_t *idx;
    int num_tris, num_verts;
    Sphere *spheres;
    int num_spheres;
    AnalyticShape *shapes; /* ids after the spheres' */
    int num_shapes;
} Soup;

static inline int soup_num_prims(const Soup *s) { return s->num_tris + s->num_spheres + s->num_shapes; }

static inline void soup_free(Soup *s)
{
    free(s->pos);
    free(s->idx);
    free(s->spheres);
    free(s->shapes);
    memset(s, 0, sizeof *s);
}

static inline void soup_reserve(Soup *s, int tris, int verts, int spheres)
{
    s->pos = realloc(s->pos, (size_t)(verts > 0 ? verts : 1) * sizeof *s->pos);
    s->idx = realloc(s->idx, (size_t)(tris > 0 ? 3 * tris : 1) * sizeof *s->idx);
    s->spheres = realloc(s->spheres, (size_t)(spheres > 0 ? spheres : 1) * sizeof *s->spheres);
    assert_non_null(s->pos);
    assert_non_null(s->idx);
    assert_non_null(s->spheres);
}

/* Appends an unshared triangle (its own three vertices). */
static inline void soup_add_tri(Soup *s, Vec3 a, Vec3 b, Vec3 c)
{
    int v = s->num_verts;
    s->pos[v] = a; s->pos[v + 1] = b; s->pos[v + 2] = c;
    s->idx[3 * s->num_tris] = v; s->idx[3 * s->num_tris + 1] = v + 1; s->idx[3 * s->num_tris + 2] = v + 2;
    s->num_verts += 3;
    s->num_tris++;
}

static inline double rnd(Pcg32 *rng, double lo, double hi) { return lo + (hi - lo) * (double)pcg32_float(rng); }
static inline Vec3 rnd_v3(Pcg32 *rng, double lo, double hi)
{
    float x = (float)rnd(rng, lo, hi);
    float y = (float)rnd(rng, lo, hi);
    float z = (float)rnd(rng, lo, hi);
    return v3(x, y, z);
}
static inline Vec3 rnd_dir(Pcg32 *rng)
{
    for (;;) {
        Vec3 d = rnd_v3(rng, -1.0, 1.0);
        float l = v3_length(d);
        if (l > 0.05f && l <= 1.0f) return v3_scale(d, 1.0f / l);
    }
}
/* Random bilinear patches appended to the shapes: centres in [-10, 10]^3, log-uniform
 * size in [0.01, 4], corners displaced at random (curved, twisted), one in four planar
 * (p11 = p10 + p01 - p00: a parallelogram), one in ten reverse-oriented. */
static inline void soup_random_patches(Soup *s, Pcg32 *rng, int n)
{
    s->shapes = realloc(s->shapes, (size_t)(s->num_shapes + n > 0 ? s->num_shapes + n : 1) * sizeof *s->shapes);
    assert_non_null(s->shapes);
    for (int i = 0; i < n; i++) {
        Vec3 c = rnd_v3(rng, -10.0, 10.0);
        float size = (float)exp(rnd(rng, log(0.01), log(4.0)));
        Vec3 p[4];
        for (int k = 0; k < 4; k++) p[k] = v3_add(c, v3_scale(rnd_v3(rng, -1.0, 1.0), size));
        if (pcg32_next(rng) % 4u == 0u) p[3] = v3_sub(v3_add(p[1], p[2]), p[0]);
        bool flip = pcg32_next(rng) % 10u == 0u;
        assert_true(shape_init_bilinear(&s->shapes[s->num_shapes], p, NULL, NULL, flip));
        s->num_shapes++;
    }
}

/* Random triangles of log-uniform size in [0.01, 5] around centres in [-10, 10]^3, a
 * third of them slivers (the third vertex within 1e-4 of the size off the first edge). */
static inline void soup_random_tris(Soup *s, Pcg32 *rng, int n)
{
    soup_reserve(s, s->num_tris + n, s->num_verts + 3 * n, s->num_spheres);
    for (int i = 0; i < n; i++) {
        Vec3 c = rnd_v3(rng, -10.0, 10.0);
        float size = (float)exp(rnd(rng, log(0.01), log(5.0)));
        Vec3 a = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        Vec3 b = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        Vec3 d;
        if (pcg32_next(rng) % 3u == 0u) {
            float t = (float)rnd(rng, 0.0, 1.0);
            d = v3_madd(v3_madd(a, v3_sub(b, a), t), rnd_v3(rng, -1.0, 1.0), 1e-4f * size);
        } else {
            d = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
        }
        soup_add_tri(s, a, b, d);
    }
}

static inline void soup_add_sphere(Soup *s, Vec3 c, float r)
{
    s->spheres[s->num_spheres].center = c;
    s->spheres[s->num_spheres].radius = r;
    s->num_spheres++;
}

static inline void soup_random_spheres(Soup *s, Pcg32 *rng, int n)
{
    soup_reserve(s, s->num_tris, s->num_verts, s->num_spheres + n);
    for (int i = 0; i < n; i++) {
        float r = (float)exp(rnd(rng, log(0.01), log(3.0))); /* radius first: GCC's order */
        soup_add_sphere(s, rnd_v3(rng, -10.0, 10.0), r);
    }
}

static inline AccelGeometry soup_geometry(const Soup *s)
{
    AccelGeometry g = {s->pos, s->idx, s->num_tris, s->spheres, s->num_spheres, s->shapes, s->num_shapes};
    return g;
}

/* Random analytic shapes (cylinders, disks with and without a hole, partial spheres, each
 * clipped in phi half the time) of log-uniform radius in [0.01, 3] around centres in
 * [-10, 10]^3, randomly rotated, a quarter of them scaled non-uniformly, a quarter
 * mirrored, a fifth with reversed orientation. */
static inline void soup_random_shapes(Soup *s, Pcg32 *rng, int n)
{
    s->shapes = realloc(s->shapes, (size_t)(s->num_shapes + n > 0 ? s->num_shapes + n : 1) * sizeof *s->shapes);
    assert_non_null(s->shapes);
    for (int i = 0; i < n; i++) {
        ShapeParams p = {0};
        p.type = (ShapeTag)(pcg32_next(rng) % 3u);
        p.radius = (float)exp(rnd(rng, log(0.01), log(3.0)));
        float z0 = (float)rnd(rng, -1.5, 1.0) * p.radius, z1 = (float)rnd(rng, 0.1, 1.5) * p.radius;
        p.z_min = z0; p.z_max = z0 + z1;
        p.height = (float)rnd(rng, -1.0, 1.0) * p.radius;
        p.inner_radius = pcg32_next(rng) % 2u ? (float)rnd(rng, 0.0, 0.9) * p.radius : 0.0f;
        p.phi_max = pcg32_next(rng) % 2u ? (float)rnd(rng, 0.2, 6.28) : 2.0f * CST_PI;
        p.reverse_orientation = pcg32_next(rng) % 5u == 0u;
        Vec3 axis = rnd_dir(rng);
        float angle = (float)rnd(rng, 0.0, 6.28);
        Transform m = transform_rotate(axis, angle);
        uint32_t kind = pcg32_next(rng) % 4u;
        if (kind == 0u) m = transform_compose(m, transform_scale(rnd_v3(rng, 0.3, 2.0)));
        if (kind == 1u) m = transform_compose(m, transform_scale(v3(-1.0f, 1.0f, 1.0f)));
        m = transform_compose(transform_translate(rnd_v3(rng, -10.0, 10.0)), m);
        if (p.type == SHAPE_TAG_SPHERE) { /* a non-empty zone of the sphere */
            p.z_min = clampf(p.z_min, -p.radius, 0.8f * p.radius);
            p.z_max = maxf(p.z_max, p.z_min + 0.2f * p.radius);
        }
        assert_true(shape_init(&s->shapes[s->num_shapes], &p, &m));
        s->num_shapes++;
    }
}


/* Random triangles of log-uniform size in [0.01, 5] around centres in [-10, 10]^3: a
 * third are slivers (the third vertex within 1e-4 of the size off the first edge), and
 * one in ten is a needle 5 to 25 long and 0.001 to 0.1 wide, which spans many grid cells. */
static inline void soup_random_tris_needles(Soup *s, Pcg32 *rng, int n)
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

/* The cube [-1, 1]^3 with each face an n x n grid of quads (two triangles each), grid
 * coordinates exact in float, vertices shared within a face, scaled by `scale` and moved
 * by `offset`. `alternate` flips the diagonal of every other quad, so vertices have
 * different valences. */
static inline void soup_grid_cube(Soup *s, int n, float scale, Vec3 offset, bool alternate)
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
                    int q[6] = {v00, v10, v11, v00, v11, v01};
                    if (alternate && ((i + j) & 1)) { q[2] = v01; q[3] = v10; q[4] = v11; q[5] = v01; }
                    for (int k = 0; k < 6; k++) s->idx[3 * s->num_tris + k] = q[k];
                    s->num_tris += 2;
                }
        }
}

/* Unit-sphere mesh from a latitude-longitude grid (poles as triangle fans), scaled and
 * moved: a dense closed mesh (the teapot of the teapot-in-a-stadium scene). */
static inline void soup_uv_sphere(Soup *s, int rings, int segs, float radius, Vec3 centre)
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

/* Midpoint of edge (a, b) projected on the unit sphere, created once per edge. */
static inline int soup_edge_midpoint(Soup *s, int a, int b, int *cache_a, int *cache_b, int *cache_m, int *ncache)
{
    int lo = a < b ? a : b, hi = a < b ? b : a;
    for (int i = 0; i < *ncache; i++)
        if (cache_a[i] == lo && cache_b[i] == hi) return cache_m[i];
    s->pos[s->num_verts] = v3_normalize(v3_scale(v3_add(s->pos[a], s->pos[b]), 0.5f));
    cache_a[*ncache] = lo; cache_b[*ncache] = hi; cache_m[*ncache] = s->num_verts;
    (*ncache)++;
    return s->num_verts++;
}

/* Icosahedron (vertices (0, +-1, +-phi) and cyclic permutations, normalised: several
 * have exact zero components) subdivided `level` times onto the unit sphere; the scene
 * must be empty. A closed mesh with shared vertices. */
static inline void soup_icosphere(Soup *s, int level)
{
    const float p = 1.61803398874989484820f;
    const float raw[12][3] = {{-1, p, 0}, {1, p, 0}, {-1, -p, 0}, {1, -p, 0}, {0, -1, p}, {0, 1, p},
                              {0, -1, -p}, {0, 1, -p}, {p, 0, -1}, {p, 0, 1}, {-p, 0, -1}, {-p, 0, 1}};
    const int faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11}, {1, 5, 9}, {5, 11, 4},
                              {11, 10, 2}, {10, 7, 6}, {7, 1, 8}, {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8},
                              {3, 8, 9}, {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    int tris = 20, verts = 12;
    for (int l = 0; l < level; l++) { verts += 3 * tris / 2; tris *= 4; }
    assert_int_equal(s->num_tris + s->num_verts, 0);
    soup_reserve(s, tris, verts, 0);
    for (int i = 0; i < 12; i++) s->pos[s->num_verts++] = v3_normalize(v3(raw[i][0], raw[i][1], raw[i][2]));
    for (int i = 0; i < 20; i++)
        for (int k = 0; k < 3; k++) s->idx[3 * i + k] = faces[i][k];
    s->num_tris = 20;
    for (int l = 0; l < level; l++) {
        int nt = s->num_tris;
        int32_t *old = malloc((size_t)(3 * nt) * sizeof *old);
        int *ca = malloc((size_t)(3 * nt) * sizeof *ca), *cb = malloc((size_t)(3 * nt) * sizeof *cb),
            *cm = malloc((size_t)(3 * nt) * sizeof *cm);
        assert_true(old && ca && cb && cm);
        memcpy(old, s->idx, (size_t)(3 * nt) * sizeof *old);
        int nc = 0;
        s->num_tris = 0;
        for (int t = 0; t < nt; t++) {
            int a = old[3 * t], b = old[3 * t + 1], c = old[3 * t + 2];
            int ab = soup_edge_midpoint(s, a, b, ca, cb, cm, &nc), bc = soup_edge_midpoint(s, b, c, ca, cb, cm, &nc),
                ca_ = soup_edge_midpoint(s, c, a, ca, cb, cm, &nc);
            const int q[4][3] = {{a, ab, ca_}, {b, bc, ab}, {c, ca_, bc}, {ab, bc, ca_}};
            for (int k = 0; k < 4; k++, s->num_tris++)
                for (int e = 0; e < 3; e++) s->idx[3 * s->num_tris + e] = q[k][e];
        }
        free(old); free(ca); free(cb); free(cm);
    }
    assert_int_equal(s->num_verts, verts);
}

/* The closed meshes of the watertightness checks: icospheres of levels 0-3 and grid cubes
 * of 1, 2, 5 and 8 quads per face side. */
enum { SOUP_CLOSED_MESHES = 8 };
static inline void soup_closed_mesh(Soup *s, int k, char *name, size_t name_size)
{
    static const int grids[4] = {1, 2, 5, 8};
    if (k < 4) {
        soup_icosphere(s, k);
        snprintf(name, name_size, "icosphere level %d (%d tris)", k, s->num_tris);
    } else {
        soup_grid_cube(s, grids[k - 4], 1.0f, v3(0.0f, 0.0f, 0.0f), true);
        snprintf(name, name_size, "cube %dx%d per face (%d tris)", grids[k - 4], grids[k - 4], s->num_tris);
    }
}

/* 1000 copies of one triangle (corners s->pos[0..2]) plus 30 random ones: the copies share
 * a centroid, so no split separates them, and hits on them tie exactly. */
static inline void soup_coincident(Soup *s, Pcg32 *rng)
{
    soup_reserve(s, 1030, 3090, 0);
    Vec3 a = v3(-1.0f, -1.0f, 0.3f), b = v3(1.5f, -0.5f, -0.2f), c = v3(0.1f, 1.2f, 0.1f);
    for (int i = 0; i < 1000; i++) soup_add_tri(s, a, b, c);
    soup_random_tris(s, rng, 30);
}

/* n different triangles whose bounding boxes all have the same centre: each is
 * (m + e, m - e, m + f) with |f_i| < |e_i|, so its box is m +- |e|. */
static inline void soup_same_centroid(Soup *s, Pcg32 *rng, int n)
{
    soup_reserve(s, n, 3 * n, 0);
    Vec3 m = v3(2.0f, -1.0f, 0.5f);
    for (int i = 0; i < n; i++) {
        float e[3], f[3];
        for (int k = 0; k < 3; k++) {
            float len = (float)rnd(rng, 0.5, 3.0); /* then the sign: the operands in sequence */
            e[k] = len * ((pcg32_next(rng) & 1u) ? 1.0f : -1.0f);
            f[k] = e[k] * (float)rnd(rng, -0.99, 0.99);
        }
        Vec3 ev = v3(e[0], e[1], e[2]), fv = v3(f[0], f[1], f[2]);
        soup_add_tri(s, v3_add(m, ev), v3_sub(m, ev), v3_add(m, fv));
    }
}

/* n triangles at x = 1.4^i: every SAH split peels off one primitive (or one leaf's worth),
 * driving a tree to its depth limit. */
static inline void soup_exponential(Soup *s, int n)
{
    soup_reserve(s, n, 3 * n, 0);
    for (int i = 0; i < n; i++) {
        float x = powf(1.4f, (float)i);
        soup_add_tri(s, v3(x, 0.0f, 0.0f), v3(x, 1.0f, 0.0f), v3(x, 0.0f, 1.0f));
    }
}

/* Zero area in double: (b - a) x (c - a) == 0. The kd-tree leaves such triangles out. */
static inline bool soup_tri_zero_area(const Soup *s, int id)
{
    double p[3][3];
    for (int k = 0; k < 3; k++) {
        Vec3 q = s->pos[s->idx[3 * id + k]];
        p[k][0] = (double)q.x; p[k][1] = (double)q.y; p[k][2] = (double)q.z;
    }
    double u[3], v[3];
    for (int a = 0; a < 3; a++) { u[a] = p[1][a] - p[0][a]; v[a] = p[2][a] - p[0][a]; }
    return u[1] * v[2] - u[2] * v[1] == 0.0 && u[2] * v[0] - u[0] * v[2] == 0.0 && u[0] * v[1] - u[1] * v[0] == 0.0;
}

/* 800 zero-area triangles (repeated vertices, all three equal, exactly collinear on
 * sixteenths) followed by 400 random ones. Returns the number of degenerate ones. */
static inline int soup_zero_area(Soup *s, Pcg32 *rng)
{
    soup_reserve(s, 1200, 3600, 0);
    for (int i = 0; i < 800; i++) {
        Vec3 a = rnd_v3(rng, -5.0, 5.0), b = v3_madd(a, rnd_v3(rng, -1.0, 1.0), 1.0f);
        switch (i % 5) {
        case 0: soup_add_tri(s, a, a, b); break;
        case 1: soup_add_tri(s, a, b, a); break;
        case 2: soup_add_tri(s, a, b, b); break;
        case 3: soup_add_tri(s, a, a, a); break;
        default: { /* collinear, exactly: sixteenths, so every sum below is exact */
            Vec3 g = v3(floorf(16.0f * a.x) / 16.0f, floorf(16.0f * a.y) / 16.0f, floorf(16.0f * a.z) / 16.0f);
            float sy = (float)(int)(pcg32_next(rng) % 17u) / 16.0f; /* y first: GCC's order */
            float sx = (float)(int)(pcg32_next(rng) % 17u) / 16.0f;
            Vec3 step = v3(sx, sy, 1.0f / 16.0f);
            soup_add_tri(s, g, v3_add(g, step), v3_madd(g, step, (i & 1) ? 2.0f : -1.0f));
            break;
        }
        }
    }
    int degenerate = s->num_tris;
    soup_random_tris(s, rng, 400);
    return degenerate;
}

/* A copy of s with every zero-area triangle collapsed to a point (an exactly zero edge:
 * det == 0 for every ray), keeping the primitive ids: what a back end that leaves such
 * triangles out must agree with. Returns their number. */
static inline int soup_collapse_zero_area(const Soup *s, Soup *c)
{
    soup_reserve(c, s->num_tris, s->num_verts, s->num_spheres);
    memcpy(c->pos, s->pos, (size_t)s->num_verts * sizeof *c->pos);
    memcpy(c->idx, s->idx, (size_t)(3 * s->num_tris) * sizeof *c->idx);
    memcpy(c->spheres, s->spheres, (size_t)s->num_spheres * sizeof *c->spheres);
    c->num_tris = s->num_tris;
    c->num_verts = s->num_verts;
    c->num_spheres = s->num_spheres;
    int zero_area = 0;
    for (int id = 0; id < s->num_tris; id++)
        if (soup_tri_zero_area(s, id)) { c->idx[3 * id + 1] = c->idx[3 * id + 2] = c->idx[3 * id]; zero_area++; }
    return zero_area;
}

/* 200 random triangles with needles, then zero-area triangles (repeated vertices, nearly
 * and exactly collinear), a NaN vertex, an infinite coordinate and 50 coincident copies of
 * one triangle (exact ties in t). */
static inline void soup_degenerate_mix(Soup *s, Pcg32 *rng)
{
    soup_random_tris_needles(s, rng, 200);
    soup_reserve(s, s->num_tris + 60, s->num_verts + 180, 0);
    for (int i = 0; i < 20; i++) {
        Vec3 a = rnd_v3(rng, -10.0, 10.0), b = rnd_v3(rng, -10.0, 10.0);
        soup_add_tri(s, a, a, b);                            /* repeated vertex */
        soup_add_tri(s, a, b, v3_scale(v3_add(a, b), 0.5f)); /* collinear (nearly, after rounding) */
        float x = (float)rnd(rng, -10.0, 10.0);
        soup_add_tri(s, v3(x, 1.0f, 2.0f), v3(x, 3.0f, 2.0f), v3(x, 7.0f, 2.0f)); /* exactly collinear */
    }
    soup_reserve(s, s->num_tris + 52, s->num_verts + 156, 0);
    soup_add_tri(s, v3(NAN, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), v3(0.0f, 1.0f, 0.0f));
    soup_add_tri(s, v3(INFINITY, 0.0f, 0.0f), v3(1.0f, 2.0f, 0.0f), v3(0.0f, 1.0f, 3.0f));
    for (int i = 0; i < 50; i++) soup_add_tri(s, v3(-4.0f, -3.0f, 1.0f), v3(6.0f, -2.0f, 2.0f), v3(0.5f, 7.0f, -1.0f));
}

/* 50 degenerate triangles along the line y = 1, z = -2: two flat axes. */
static inline void soup_on_a_line(Soup *s, Pcg32 *rng)
{
    soup_reserve(s, 50, 150, 0);
    for (int i = 0; i < 50; i++) {
        float x0 = (float)rnd(rng, -5.0, 5.0), x1 = (float)rnd(rng, -5.0, 5.0);
        soup_add_tri(s, v3(x0, 1.0f, -2.0f), v3(x1, 1.0f, -2.0f), v3(0.5f * (x0 + x1), 1.0f, -2.0f));
    }
}

/* 3000 triangles in one plane: z = 0.5 (variant 0), or x = -3 with 10 spheres of radius 0
 * (variant 1: points, placed like any primitive, never hit). */
static inline void soup_flat(Soup *s, Pcg32 *rng, int variant)
{
    soup_reserve(s, 3000, 9000, 10);
    for (int i = 0; i < 3000; i++) {
        Vec3 c = rnd_v3(rng, -10.0, 10.0);
        float size = (float)exp(rnd(rng, log(0.01), log(2.0)));
        Vec3 q[3];
        for (int k = 0; k < 3; k++) {
            q[k] = v3_madd(c, rnd_v3(rng, -1.0, 1.0), size);
            if (variant == 0) q[k].z = 0.5f;
            else q[k].x = -3.0f;
        }
        soup_add_tri(s, q[0], q[1], q[2]);
    }
    if (variant == 1)
        for (int i = 0; i < 10; i++) soup_add_sphere(s, v3(-3.0f, (float)i, 1.0f), 0.0f);
}

/* Teapot in a stadium: a dense mesh 0.02 across (a 40 x 64 uv sphere, 5k triangles, centred
 * at SOUP_TEAPOT) inside a 2000-wide box of 12 triangles, plus 4 huge slanted triangles. */
#define SOUP_TEAPOT v3(3.0f, -2.0f, 1.0f)
static inline void soup_teapot_in_stadium(Soup *s, Pcg32 *rng)
{
    soup_grid_cube(s, 1, 1000.0f, v3(0.0f, 0.0f, 0.0f), false);
    soup_uv_sphere(s, 40, 64, 0.01f, SOUP_TEAPOT);
    soup_reserve(s, s->num_tris + 4, s->num_verts + 12, 0);
    for (int i = 0; i < 4; i++) {
        Vec3 c = rnd_v3(rng, -990.0, 990.0), b = rnd_v3(rng, -990.0, 990.0); /* last first: GCC's order */
        soup_add_tri(s, rnd_v3(rng, -990.0, 990.0), b, c);
    }
}

#endif
