/* Random triangle soups and spheres for the acceleration structures' tests (test_bvh,
 * test_kdtree, test_grid): one generator, so every back end is tested on the same kinds of
 * scenes. Include after cmocka.h. */
#ifndef CST_TESTS_UNIT_SOUP_H
#define CST_TESTS_UNIT_SOUP_H

#include <math.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "accel/accel_geometry.h"
#include "core/rng.h"
#include "geometry/sphere.h"
#include "math/vec3.h"

typedef struct Soup {
    Vec3 *pos;
    int32_t *idx;
    int num_tris, num_verts;
    Sphere *spheres;
    int num_spheres;
} Soup;

static inline void soup_free(Soup *s)
{
    free(s->pos);
    free(s->idx);
    free(s->spheres);
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
    AccelGeometry g = {s->pos, s->idx, s->num_tris, s->spheres, s->num_spheres};
    return g;
}

#endif
