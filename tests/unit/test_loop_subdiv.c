/* Loop subdivision (geometry/loop_subdiv.c): limit points against closed forms and against
 * deeper refinement, limit normals, the boundary rules on an open grid, watertightness of
 * the refined closed mesh, and located errors on non-manifold input. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <cmocka.h>

#include "core/rng.h"
#include "geometry/loop_subdiv.h"
#include "geometry/ray.h"
#include "geometry/triangle.h"

/* The octahedron +-x, +-y, +-z, every face wound outward (valence 4 everywhere). */
static const Vec3 OCTA_P[6] = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
static const int OCTA_IDX[24] = {0, 2, 4, 2, 1, 4, 1, 3, 4, 3, 0, 4, 2, 0, 5, 1, 2, 5, 3, 1, 5, 0, 3, 5};

static LoopMesh subdivide_ok(const Vec3 *p, int nv, const int *idx, int nt, int levels)
{
    LoopMesh m;
    CstError err;
    if (loop_subdivide(p, nv, idx, nt, levels, &m, &err) != CST_OK) fail_msg("%s", err.msg);
    return m;
}

static void assert_near(Vec3 a, Vec3 b, float tol, const char *what, int i)
{
    if (!(fabsf(a.x - b.x) <= tol && fabsf(a.y - b.y) <= tol && fabsf(a.z - b.z) <= tol))
        fail_msg("%s %d: (%.7f, %.7f, %.7f); expected (%.7f, %.7f, %.7f) within %g", what, i, (double)a.x,
                 (double)a.y, (double)a.z, (double)b.x, (double)b.y, (double)b.z, (double)tol);
}

static void test_octahedron_closed_form(void **state)
{
    (void)state;
    /* valence 4: beta = 3/32, gamma = 1 / (4 + 3 / (8 beta)) = 1/8; the limit of vertex
     * (1, 0, 0) is (1 - 4/8) (1, 0, 0) + 1/8 (sum of its ring = 0) = (1/2, 0, 0), and its
     * normal by symmetry is -x (pbrt-v4's sign: against the outward winding). */
    for (int levels = 0; levels <= 6; levels++) {
        LoopMesh m = subdivide_ok(OCTA_P, 6, OCTA_IDX, 8, levels);
        assert_int_equal(m.nt, 8 << (2 * levels));
        for (int i = 0; i < 6; i++) {
            assert_near(m.p[i], v3_scale(OCTA_P[i], 0.5f), 2e-6f, "octahedron vertex", i);
            assert_near(m.n[i], v3_neg(OCTA_P[i]), 1e-5f, "octahedron normal", i);
        }
        loop_mesh_free(&m);
    }
}

/* The limit position of a vertex does not depend on how many levels come first: every
 * vertex of level k (same index at every later level) has the same limit point at level
 * k + 5. A wrong even, odd or limit weight breaks this at once. Checked on the irregular
 * icosahedron (valence 5) with one vertex pulled out, so nothing is symmetric. */
static void test_limit_invariant_across_levels(void **state)
{
    (void)state;
    const float g = 1.6180339887f;
    Vec3 p[12] = {{-1, g, 0}, {1, g, 0}, {-1, -g, 0}, {1, -g, 0}, {0, -1, g}, {0, 1, g},
                  {0, -1, -g}, {0, 1, -g}, {g, 0, -1}, {g, 0, 1}, {-g, 0, -1}, {-g, 0, 1}};
    p[3] = v3(1.7f, -2.4f, 0.3f);
    const int idx[60] = {0, 11, 5, 0, 5, 1, 0, 1, 7, 0, 7, 10, 0, 10, 11, 1, 5, 9, 5, 11, 4, 11, 10, 2,
                         10, 7, 6, 7, 1, 8, 3, 9, 4, 3, 4, 2, 3, 2, 6, 3, 6, 8, 3, 8, 9, 4, 9, 5,
                         2, 4, 11, 6, 2, 10, 8, 6, 7, 9, 8, 1};
    for (int k = 0; k <= 1; k++) {
        LoopMesh a = subdivide_ok(p, 12, idx, 20, k);
        LoopMesh b = subdivide_ok(p, 12, idx, 20, k + 5);
        for (int i = 0; i < a.nv; i++) {
            assert_near(b.p[i], a.p[i], 1e-5f, "limit point", i);
            /* the normals too: both are the limit surface's at the same point */
            if (!(v3_dot(a.n[i], b.n[i]) > 0.99999f))
                fail_msg("vertex %d: normals differ by %g degrees", i,
                         acos((double)v3_dot(a.n[i], b.n[i])) * 180.0 / 3.14159265358979);
        }
        loop_mesh_free(&a);
        loop_mesh_free(&b);
    }
}

/* Limit normals are the limit surface's: at level 5, at every regular vertex (valence 6)
 * the normal is within 1 degree of the (flipped) winding normals of the small triangles
 * around it (their mean; vertices within 0.05 of an extraordinary one left out). Near an
 * extraordinary vertex the triangles' normals converge more slowly
 * (the surface is only C1 there: the corner triangle at the octahedron's valence-4 vertex
 * tilts 32, 23, 16, 11, 7.3, 4.9, 3.3 degrees at levels 2 to 8, a factor ~0.67 a level
 * while its edges shrink by ~0.37): checked as a decreasing tilt towards the exact normal. */
static void test_normals_match_surface(void **state)
{
    (void)state;
    LoopMesh m = subdivide_ok(OCTA_P, 6, OCTA_IDX, 8, 5);
    int *faces = calloc((size_t)m.nv, sizeof *faces);
    Vec3 *around = calloc((size_t)m.nv, sizeof *around);
    assert_true(faces && around);
    for (int t = 0; t < m.nt; t++) {
        const int *v = &m.idx[3 * t];
        Vec3 ng = v3_normalize(v3_cross(v3_sub(m.p[v[1]], m.p[v[0]]), v3_sub(m.p[v[2]], m.p[v[0]])));
        for (int k = 0; k < 3; k++) {
            faces[v[k]]++;
            around[v[k]] = v3_sub(around[v[k]], ng);
        }
    }
    int checked = 0;
    for (int i = 0; i < m.nv; i++) {
        float d = INFINITY;
        for (int k = 0; k < 6; k++) d = fminf(d, v3_length(v3_sub(m.p[i], m.p[k])));
        if (faces[i] != 6 || d < 0.05f) continue;
        checked++;
        double c = (double)v3_dot(m.n[i], v3_normalize(around[i]));
        if (!(c > cos(1.0 * 3.14159265358979 / 180.0)))
            fail_msg("vertex %d: normal off its triangles' by %g degrees", i, acos(c) * 180.0 / 3.14159265358979);
    }
    assert_true(checked > m.nv / 2);
    free(faces);
    free(around);
    loop_mesh_free(&m);
    double last = 90.0;
    for (int levels = 2; levels <= 7; levels++) {
        m = subdivide_ok(OCTA_P, 6, OCTA_IDX, 8, levels);
        const int *v = m.idx; /* triangle 0 is the corner child at vertex 0 */
        Vec3 ng = v3_normalize(v3_cross(v3_sub(m.p[v[1]], m.p[v[0]]), v3_sub(m.p[v[2]], m.p[v[0]])));
        double tilt = acos((double)v3_dot(m.n[0], v3_neg(ng))) * 180.0 / 3.14159265358979;
        if (!(tilt < 0.75 * last)) fail_msg("level %d: tilt %g degrees after %g", levels, tilt, last);
        last = tilt;
        loop_mesh_free(&m);
    }
    assert_true(last < 5.0);
}

/* Every edge of the refined closed mesh is shared by exactly two triangles, and rays from
 * the inside never escape through a crack (brute force over every triangle). */
static void test_watertight(void **state)
{
    (void)state;
    LoopMesh m = subdivide_ok(OCTA_P, 6, OCTA_IDX, 8, 3);
    /* edge count: a closed mesh has 3 nt / 2 edges each met twice */
    int *count = calloc((size_t)m.nv * (size_t)m.nv, sizeof *count);
    assert_non_null(count);
    for (int t = 0; t < m.nt; t++)
        for (int k = 0; k < 3; k++) {
            int a = m.idx[3 * t + k], b = m.idx[3 * t + (k + 1) % 3];
            count[(a < b ? a : b) * m.nv + (a < b ? b : a)]++;
        }
    int edges = 0;
    for (int i = 0; i < m.nv * m.nv; i++) {
        if (count[i] != 0 && count[i] != 2) fail_msg("edge %d-%d met %d times", i / m.nv, i % m.nv, count[i]);
        edges += count[i] != 0;
    }
    assert_int_equal(edges, 3 * m.nt / 2);
    assert_int_equal(m.nv - edges + m.nt, 2); /* Euler: a sphere */
    free(count);
    Pcg32 rng;
    pcg32_seed(&rng, 7u, 3u);
    for (int i = 0; i < 2000; i++) {
        float z = 1.0f - 2.0f * pcg32_float(&rng), phi = 2.0f * CST_PI * pcg32_float(&rng);
        float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
        Vec3 o = v3(0.1f * (pcg32_float(&rng) - 0.5f), 0.1f * (pcg32_float(&rng) - 0.5f), 0.0f);
        Ray ray = ray_make(o, v3(r * cosf(phi), r * sinf(phi), z), 0.0f, INFINITY);
        TriangleRay tr = triangle_ray_setup(ray.d);
        int hit = 0;
        for (int t = 0; t < m.nt && !hit; t++) {
            const int *v = &m.idx[3 * t];
            float th, b1, b2;
            hit = triangle_intersect_watertight(&tr, &ray, m.p[v[0]], m.p[v[1]], m.p[v[2]], &th, &b1, &b2);
        }
        if (!hit) fail_msg("ray %d escaped", i);
    }
    loop_mesh_free(&m);
}

/* An open 4 x 4 grid of quads (two triangles each) in z = 0 with its interior vertices
 * lifted: the boundary follows pbrt-v4's boundary rules alone (even 3/4, 1/8, 1/8; odd
 * 1/2, 1/2; limit 3/5, 1/5, 1/5), so boundary vertices stay in z = 0 and on the boundary's
 * lines, and a boundary vertex's limit point is (b0 + 3 v + b1) / 5. */
static void test_open_grid_boundary(void **state)
{
    (void)state;
    Vec3 p[25];
    int idx[6 * 16];
    for (int j = 0; j < 5; j++)
        for (int i = 0; i < 5; i++) {
            int inner = i > 0 && i < 4 && j > 0 && j < 4;
            p[5 * j + i] = v3((float)i, (float)j, inner ? 0.3f * (float)(i * j % 3 + 1) : 0.0f);
        }
    int nt = 0;
    for (int j = 0; j < 4; j++)
        for (int i = 0; i < 4; i++) {
            int a = 5 * j + i, b = a + 1, c = a + 5, d = a + 6;
            idx[3 * nt] = a; idx[3 * nt + 1] = b; idx[3 * nt + 2] = d; nt++;
            idx[3 * nt] = a; idx[3 * nt + 1] = d; idx[3 * nt + 2] = c; nt++;
        }
    /* level 0: the limit of boundary vertex (2, 0) and of the corner (0, 0), closed form */
    LoopMesh m0 = subdivide_ok(p, 25, idx, nt, 0);
    assert_near(m0.p[2], v3(2.0f, 0.0f, 0.0f), 1e-6f, "boundary limit", 2);
    assert_near(m0.p[0], v3(0.2f, 0.2f, 0.0f), 1e-6f, "corner limit", 0); /* (3 (0,0) + (1,0) + (0,1)) / 5 */
    loop_mesh_free(&m0);
    for (int levels = 1; levels <= 4; levels++) {
        LoopMesh m = subdivide_ok(p, 25, idx, nt, levels);
        /* boundary vertices: on edges met once */
        int *count = calloc((size_t)m.nv * (size_t)m.nv, sizeof *count);
        assert_non_null(count);
        for (int t = 0; t < m.nt; t++)
            for (int k = 0; k < 3; k++) {
                int a = m.idx[3 * t + k], b = m.idx[3 * t + (k + 1) % 3];
                count[(a < b ? a : b) * m.nv + (a < b ? b : a)]++;
            }
        int boundary_edges = 0;
        for (int a = 0; a < m.nv; a++)
            for (int b = a + 1; b < m.nv; b++) {
                if (count[a * m.nv + b] != 1) continue;
                boundary_edges++;
                for (int k = 0; k < 2; k++) {
                    Vec3 q = m.p[k ? b : a];
                    if (q.z != 0.0f) fail_msg("level %d: boundary vertex %d lifted to z = %g", levels, k ? b : a, (double)q.z);
                    /* away from the corners' cut, the straight sides stay on their lines */
                    if (q.x > 0.5f && q.x < 3.5f && !(q.y == 0.0f || q.y == 4.0f) && q.y > 0.5f && q.y < 3.5f &&
                        !(q.x == 0.0f || q.x == 4.0f))
                        fail_msg("level %d: boundary vertex %d at (%g, %g) is off the grid's sides", levels,
                                 k ? b : a, (double)q.x, (double)q.y);
                }
            }
        assert_int_equal(boundary_edges, 16 << levels);
        free(count);
        /* the side vertex (2, 0): still (2, 0, 0), its normal vertical (the boundary
         * tangent is x, the cross-boundary tangent lies in the plane x = 2 ... z is what
         * the interior lifts; the normal is perpendicular to x) */
        assert_near(m.p[2], v3(2.0f, 0.0f, 0.0f), 1e-6f, "boundary vertex", 2);
        assert_true(fabsf(m.n[2].x) < 1e-6f);
        loop_mesh_free(&m);
    }
}

/* Non-manifold input fails with a message naming the problem, never crashes. */
static void test_non_manifold(void **state)
{
    (void)state;
    const Vec3 p[7] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {-1, 0, 0}, {0, 0, -1}};
    LoopMesh m;
    CstError err;
    /* three faces on the edge 0-1 */
    const int fin[9] = {0, 1, 2, 1, 0, 3, 0, 1, 4};
    assert_int_equal(loop_subdivide(p, 7, fin, 3, 2, &m, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "edge (0, 1) is shared by 3 faces (0, 1, 2)")) fail_msg("%s", err.msg);
    assert_null(m.p);
    /* a bow tie: two triangles meeting only at vertex 0 */
    const int bow[6] = {0, 1, 2, 0, 5, 3};
    assert_int_equal(loop_subdivide(p, 7, bow, 2, 2, &m, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "vertex 0: its 2 faces form more than one fan")) fail_msg("%s", err.msg);
    /* two closed fans at one vertex: two octahedra sharing vertex 0 (second one shifted) */
    Vec3 q[11];
    int qi[48];
    for (int i = 0; i < 6; i++) q[i] = OCTA_P[i];
    for (int i = 1; i < 6; i++) q[5 + i] = v3_add(OCTA_P[i], v3(2.0f, 0.0f, 0.0f)); /* its vertex 1 is (1,0,0) */
    memcpy(qi, OCTA_IDX, sizeof OCTA_IDX);
    for (int k = 0; k < 24; k++) {
        int v = OCTA_IDX[k];
        qi[24 + k] = v == 1 ? 0 : 5 + v; /* the second octahedron's -x vertex is vertex 0 */
    }
    assert_int_equal(loop_subdivide(q, 11, qi, 16, 1, &m, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "vertex 0: its 8 faces form more than one fan")) fail_msg("%s", err.msg);
    /* a repeated vertex */
    const int rep[3] = {0, 1, 1};
    assert_int_equal(loop_subdivide(p, 7, rep, 1, 1, &m, &err), CST_ERR_INVALID_ARG);
    if (!strstr(err.msg, "face 0 has vertex 1 twice")) fail_msg("%s", err.msg);
    /* an index out of range, and a count that overflows */
    const int bad[3] = {0, 1, 9};
    assert_int_equal(loop_subdivide(p, 7, bad, 1, 1, &m, &err), CST_ERR_INVALID_ARG);
    assert_int_equal(loop_subdivide(p, 7, OCTA_IDX, 8, 40, &m, &err), CST_ERR_UNSUPPORTED);
    /* inconsistent winding is accepted (one face flipped): same positions as the
     * consistent mesh, since the rules do not use orientation */
    int flipped[24];
    memcpy(flipped, OCTA_IDX, sizeof flipped);
    flipped[1] = OCTA_IDX[2];
    flipped[2] = OCTA_IDX[1];
    LoopMesh a = subdivide_ok(OCTA_P, 6, OCTA_IDX, 8, 2), b = subdivide_ok(OCTA_P, 6, flipped, 8, 2);
    assert_int_equal(a.nv, b.nv);
    for (int i = 0; i < 6; i++) assert_near(b.p[i], a.p[i], 1e-6f, "flipped face's mesh", i);
    loop_mesh_free(&a);
    loop_mesh_free(&b);
    /* unused vertices stay, with a zero normal; an empty mesh is fine */
    LoopMesh e = subdivide_ok(p, 7, fin, 1, 1);
    assert_near(e.p[6], p[6], 0.0f, "unused vertex", 6);
    assert_true(e.n[6].x == 0.0f && e.n[6].y == 0.0f && e.n[6].z == 0.0f);
    loop_mesh_free(&e);
    e = subdivide_ok(p, 7, NULL, 0, 3);
    assert_int_equal(e.nt, 0);
    loop_mesh_free(&e);
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_octahedron_closed_form),
        cmocka_unit_test(test_limit_invariant_across_levels),
        cmocka_unit_test(test_normals_match_surface),
        cmocka_unit_test(test_watertight),
        cmocka_unit_test(test_open_grid_boundary),
        cmocka_unit_test(test_non_manifold),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
