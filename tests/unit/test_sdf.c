/* Implicit surfaces (geometry/sdf.h, the torus of geometry/shape.h): the SDF sphere against
 * the analytic sphere and the SDF torus against the quartic torus on many rays (same hit or
 * miss away from grazing, t within 1e-5 relative, normals within 1e-5); closed-form hits of
 * every primitive and operator (smooth union, non-uniform scale); every accel back end
 * reporting the same hits bit for bit; bad trees rejected with located errors; the rendered
 * image of an SDF sphere against the analytic one, means within 4 standard errors. */
#include <setjmp.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdint.h>

#include <cmocka.h>

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "core/rng.h"
#include "geometry/sdf.h"
#include "geometry/shape.h"
#include "math/transform.h"
#include "scene/scene.h"

#define NAME "sdf.json"

/* Tolerances: sphere tracing stops on a sign change and bisects to half a float ulp of t,
 * so t agrees with the closed form to about 2^-24 relative; 1e-5 leaves room for the
 * double-precision analytic tests' own rounding. Normals: central differences with step
 * eps = 1e-5 of the size, error O(eps^2): 1e-5 in any component. */
#define T_TOL 1e-5
#define N_TOL 1e-5f

static SdfTree *tree1(SdfNodeDesc nd, const Transform *w)
{
    SdfTree *t = NULL;
    int bad = 0;
    assert_int_equal(sdf_tree_create(&nd, 1, w, NULL, &t, &bad), SDF_OK);
    return t;
}

static AnalyticShape sdf_shape(SdfTree *t)
{
    AnalyticShape s;
    shape_init_sdf(&s, t);
    return s;
}

static Vec3 rand_dir(Pcg32 *rng)
{
    float z = 1.0f - 2.0f * pcg32_float(rng), phi = 2.0f * CST_PI * pcg32_float(rng);
    float r = sqrtf(fmaxf(0.0f, 1.0f - z * z));
    return v3(r * cosf(phi), r * sinf(phi), z);
}

/* Rays from a shell of radius 4 around c toward points within 1.6 of c (or, every fourth,
 * from inside the radius-0.5 ball about c outward). */
static Ray rand_ray(Pcg32 *rng, Vec3 c, int k)
{
    Vec3 o, target = v3_add(c, v3_scale(rand_dir(rng), 1.6f * pcg32_float(rng)));
    if (k % 4 == 3) o = v3_add(c, v3_scale(rand_dir(rng), 0.5f * pcg32_float(rng)));
    else o = v3_add(c, v3_scale(rand_dir(rng), 4.0f));
    Vec3 d = v3_normalize(v3_sub(target, o));
    if (k % 4 == 3) d = rand_dir(rng);
    return ray_make(o, d, 0.0f, INFINITY);
}

static void check_pair(const AnalyticShape *a, const AnalyticShape *b, const Ray *r, int *compared)
{
    float ta, tb, u, v;
    bool ha = shape_intersect(a, r, &ta, &u, &v), hb = shape_intersect(b, r, &tb, &u, &v);
    if (ha != hb) fail_msg("hit %d vs %d", ha, hb);
    if (!ha) return;
    if (!(fabs((double)ta - (double)tb) <= T_TOL * fmax(1.0, (double)ta)))
        fail_msg("t %.9g vs %.9g", (double)ta, (double)tb);
    ShapeSurface sa, sb;
    shape_surface(a, r, ta, &sa);
    shape_surface(b, r, tb, &sb);
    if (!(fabsf(sa.n.x - sb.n.x) <= N_TOL && fabsf(sa.n.y - sb.n.y) <= N_TOL && fabsf(sa.n.z - sb.n.z) <= N_TOL))
        fail_msg("n (%g %g %g) vs (%g %g %g)", (double)sa.n.x, (double)sa.n.y, (double)sa.n.z, (double)sb.n.x,
                 (double)sb.n.y, (double)sb.n.z);
    (*compared)++;
}

/* The SDF sphere against the analytic sphere, with a translation and with a rotation and
 * uniform scale; rays grazing within 1e-4 r of the silhouette are left out. */
static void test_sphere_vs_analytic(void **state)
{
    (void)state;
    const Transform xfs[2] = {
        transform_translate(v3(0.5f, -0.2f, 0.3f)),
        transform_compose(transform_translate(v3(-1.0f, 2.0f, 0.5f)),
                          transform_compose(transform_rotate(v3(1.0f, 1.0f, 0.0f), 0.7f), transform_scale(v3s(1.7f))))};
    Pcg32 rng;
    pcg32_seed(&rng, 11, 3);
    for (int x = 0; x < 2; x++) {
        const float r = 1.3f;
        ShapeParams p = {SHAPE_TAG_SPHERE, r, -r, r, 0.0f, 0.0f, 2.0f * CST_PI, false, 0.0f};
        AnalyticShape ana;
        assert_true(shape_init(&ana, &p, &xfs[x]));
        SdfNodeDesc nd = {.kind = SDF_SPHERE, .prm = {(double)r}};
        AnalyticShape sdf = sdf_shape(tree1(nd, &xfs[x]));
        const Vec3 c = transform_point(&xfs[x], v3s(0.0f));
        const double rw = x ? 1.7 * (double)r : (double)r;
        int compared = 0, hits = 0;
        for (int k = 0; k < 3000; k++) {
            Ray ray = rand_ray(&rng, c, k);
            /* closest approach of the line to the centre */
            Vec3 oc = v3_sub(c, ray.o);
            double b = sqrt(fmax(0.0, (double)v3_dot(oc, oc) - pow((double)v3_dot(oc, ray.d), 2.0)));
            if (fabs(b - rw) < 1e-4 * rw) continue;
            float t, u, v;
            hits += shape_intersect(&ana, &ray, &t, &u, &v);
            check_pair(&ana, &sdf, &ray, &compared);
        }
        assert_true(compared > 1000 && hits > 1000);
        shape_release(&sdf);
    }
}

/* Over a dense sampling of the ray in its first 12 units, the least |distance| to a torus
 * (R, r) about z in object space (identity transform): whether the ray grazes it. */
static double torus_min_dist(const Ray *ray, double R, double rm)
{
    double best = HUGE_VAL;
    for (int i = 0; i <= 120000; i++) {
        double t = 12.0 * i / 120000.0;
        double x = (double)ray->o.x + t * (double)ray->d.x, y = (double)ray->o.y + t * (double)ray->d.y,
               z = (double)ray->o.z + t * (double)ray->d.z;
        double q = sqrt(x * x + y * y) - R;
        best = fmin(best, fabs(sqrt(q * q + z * z) - rm));
    }
    return best;
}

/* The quartic torus against closed forms and against the SDF torus. */
static void test_torus_vs_quartic(void **state)
{
    (void)state;
    const float R = 1.0f, rm = 0.3f;
    ShapeParams p = {SHAPE_TAG_TORUS, R, 0.0f, 0.0f, 0.0f, 0.0f, 2.0f * CST_PI, false, rm};
    Transform id = transform_identity();
    AnalyticShape q;
    assert_true(shape_init(&q, &p, &id));
    float t, u, v;
    /* along x through the centre: the four crossings x = -1.3, -0.7, 0.7, 1.3 */
    const float want[4] = {3.7f, 4.3f, 5.7f, 6.3f};
    float tmin = 0.0f;
    for (int i = 0; i < 4; i++) {
        Ray ray = ray_make(v3(-5.0f, 0.0f, 0.0f), v3(1.0f, 0.0f, 0.0f), tmin, INFINITY);
        assert_true(shape_intersect(&q, &ray, &t, &u, &v));
        assert_float_equal(t, want[i], 1e-6f);
        tmin = t + 1e-3f;
    }
    /* down the tube's centre circle at (1, 0): z = +-0.3, normal +-z */
    Ray down = ray_make(v3(1.0f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_true(shape_intersect(&q, &down, &t, &u, &v));
    assert_float_equal(t, 4.7f, 1e-6f);
    ShapeSurface sf;
    shape_surface(&q, &down, t, &sf);
    assert_float_equal(sf.n.z, 1.0f, 1e-6f);
    assert_float_equal(sf.p.x, 1.0f, 1e-6f);
    assert_float_equal(shape_area(&q), 4.0f * CST_PI * CST_PI * R * rm, 1e-4f);
    /* through the hole along z: a miss */
    Ray hole = ray_make(v3(0.0f, 0.0f, 5.0f), v3(0.0f, 0.0f, -1.0f), 0.0f, INFINITY);
    assert_false(shape_intersect(&q, &hole, &t, &u, &v));

    SdfNodeDesc nd = {.kind = SDF_TORUS, .prm = {(double)R, (double)rm}};
    AnalyticShape s = sdf_shape(tree1(nd, &id));
    Pcg32 rng;
    pcg32_seed(&rng, 5, 9);
    int compared = 0, grazing = 0;
    for (int k = 0; k < 3000; k++) {
        Ray ray = rand_ray(&rng, v3s(0.0f), k);
        float ta, tb;
        bool ha = shape_intersect(&q, &ray, &ta, &u, &v), hb = shape_intersect(&s, &ray, &tb, &u, &v);
        if (ha != hb || (ha && !(fabs((double)ta - (double)tb) <= T_TOL * fmax(1.0, (double)ta)))) {
            /* only a ray passing within 1e-4 of the surface may disagree (a tangent crossing
             * that one side sees as two roots and the other as none) */
            double md = torus_min_dist(&ray, (double)R, (double)rm);
            if (!(md < 1e-4)) fail_msg("ray %d: hit %d (t %g) vs %d (t %g), closest %g", k, ha, (double)ta, hb,
                                       (double)tb, md);
            grazing++;
            continue;
        }
        if (ha) check_pair(&q, &s, &ray, &compared);
    }
    assert_true(compared > 800);
    assert_true(grazing <= 3);
    shape_release(&s);
}

/* Closed-form hits of each primitive and operator, on axis rays from -5 along x, y or z. */
static float axis_hit(const SdfNodeDesc *nodes, int n, int axis)
{
    SdfTree *t = NULL;
    int bad = 0;
    assert_int_equal(sdf_tree_create(nodes, n, NULL, NULL, &t, &bad), SDF_OK);
    float oc[3] = {0}, dc[3] = {0};
    oc[axis] = -5.0f, dc[axis] = 1.0f;
    Vec3 o = v3(oc[0], oc[1], oc[2]), d = v3(dc[0], dc[1], dc[2]);
    Ray r = ray_make(o, d, 0.0f, INFINITY);
    float th = -1.0f;
    if (!sdf_intersect(t, &r, &th)) th = -1.0f;
    sdf_tree_destroy(t);
    return th;
}

static SdfNodeDesc prim(SdfKind k, double a, double b, double c, double d, Transform xf)
{
    SdfNodeDesc n = {.kind = k, .prm = {a, b, c, d}, .has_xf = !transform_is_identity(&xf), .parent_from_node = xf};
    return n;
}

static void test_csg_closed_forms(void **state)
{
    (void)state;
    const Transform I = transform_identity();
    const float tol = 2e-6f;
    SdfNodeDesc n[3];
    n[0] = prim(SDF_ROUND_BOX, 1.0, 0.8, 0.6, 0.2, I);
    assert_float_equal(axis_hit(n, 1, 0), 4.0f, tol);
    assert_float_equal(axis_hit(n, 1, 2), 4.4f, tol);
    n[0] = prim(SDF_CAPSULE, 1.0, 0.5, 0, 0, I);
    assert_float_equal(axis_hit(n, 1, 2), 3.5f, tol);
    assert_float_equal(axis_hit(n, 1, 0), 4.5f, tol);
    n[0] = prim(SDF_CYLINDER, 0.5, 1.0, 0, 0, I);
    assert_float_equal(axis_hit(n, 1, 0), 4.5f, tol);
    assert_float_equal(axis_hit(n, 1, 2), 4.0f, tol);
    n[0] = prim(SDF_BOX, 1.0, 2.0, 3.0, 0, I);
    assert_float_equal(axis_hit(n, 1, 1), 3.0f, tol);
    /* a non-uniform scale (2, 1, 1) of the unit sphere: an ellipsoid */
    n[0] = prim(SDF_SPHERE, 1.0, 0, 0, 0, transform_scale(v3(2.0f, 1.0f, 1.0f)));
    assert_float_equal(axis_hit(n, 1, 0), 3.0f, tol);
    assert_float_equal(axis_hit(n, 1, 1), 4.0f, tol);
    /* two unit spheres at x = -0.5 and 0.5 */
    n[0] = prim(SDF_SPHERE, 1.0, 0, 0, 0, transform_translate(v3(-0.5f, 0.0f, 0.0f)));
    n[1] = prim(SDF_SPHERE, 1.0, 0, 0, 0, transform_translate(v3(0.5f, 0.0f, 0.0f)));
    n[2] = (SdfNodeDesc){.kind = SDF_UNION, .a = 0, .b = 1};
    assert_float_equal(axis_hit(n, 3, 0), 3.5f, tol);
    n[2].kind = SDF_INTERSECTION; /* the lens from x = -0.5 to 0.5 */
    assert_float_equal(axis_hit(n, 3, 0), 4.5f, tol);
    n[2].kind = SDF_DIFFERENCE;
    assert_float_equal(axis_hit(n, 3, 0), 3.5f, tol);
    n[2] = (SdfNodeDesc){.kind = SDF_DIFFERENCE, .a = 1, .b = 0}; /* the right sphere minus the left: from x = 0.5 */
    assert_float_equal(axis_hit(n, 3, 0), 5.5f, tol);
    /* smooth union of unit spheres at x = +-1.5, k = 3: on the y axis a = b, h = 1, the
     * surface where sqrt(2.25 + y^2) - 1 - 3/4 = 0: y = sqrt(0.8125) */
    n[0] = prim(SDF_SPHERE, 1.0, 0, 0, 0, transform_translate(v3(-1.5f, 0.0f, 0.0f)));
    n[1] = prim(SDF_SPHERE, 1.0, 0, 0, 0, transform_translate(v3(1.5f, 0.0f, 0.0f)));
    n[2] = (SdfNodeDesc){.kind = SDF_SMOOTH_UNION, .a = 0, .b = 1, .k = 3.0};
    assert_float_equal(axis_hit(n, 3, 1), (float)(5.0 - sqrt(0.8125)), tol);
    n[2].kind = SDF_UNION;
    assert_float_equal(axis_hit(n, 3, 1), -1.0f, 0.0f); /* the plain union has a gap there */
}

/* The builder's checks, with the offending node. */
static void test_bad_trees_builder(void **state)
{
    (void)state;
    SdfTree *t = NULL;
    int bad = 0;
    const Transform I = transform_identity();
    SdfNodeDesc n[3] = {prim(SDF_SPHERE, 1, 0, 0, 0, I), prim(SDF_SPHERE, 1, 0, 0, 0, I)};
    n[2] = (SdfNodeDesc){.kind = SDF_UNION, .a = 0, .b = 0};
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_OPERAND);
    assert_int_equal(bad, 2);
    assert_int_equal(sdf_tree_create(n, 2, NULL, NULL, &t, &bad), SDF_ERR_SHARED); /* node 0 unused */
    n[2] = (SdfNodeDesc){.kind = SDF_UNION, .a = 0, .b = 3};
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_OPERAND);
    n[2] = (SdfNodeDesc){.kind = SDF_SMOOTH_UNION, .a = 0, .b = 1, .k = 0.0};
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_BLEND);
    n[1] = prim(SDF_TORUS, 1, 1.5, 0, 0, I);
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_PARAM);
    assert_int_equal(bad, 1);
    n[1] = prim(SDF_SPHERE, 1, 0, 0, 0, transform_scale(v3(1.0f, 0.0f, 1.0f)));
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_TRANSFORM);
    /* two disjoint spheres intersected: an empty surface */
    n[0] = prim(SDF_SPHERE, 1, 0, 0, 0, transform_translate(v3(-3.0f, 0.0f, 0.0f)));
    n[1] = prim(SDF_SPHERE, 1, 0, 0, 0, transform_translate(v3(3.0f, 0.0f, 0.0f)));
    n[2] = (SdfNodeDesc){.kind = SDF_INTERSECTION, .a = 0, .b = 1};
    assert_int_equal(sdf_tree_create(n, 3, NULL, NULL, &t, &bad), SDF_ERR_EMPTY);
    assert_null(t);
    /* the public builder names the node */
    CstScene *sc = NULL;
    CstError err = {0};
    assert_int_equal(cst_scene_create(&sc, &err), CST_OK);
    CstMaterialDesc md;
    cst_material_desc_init(&md, CST_MATERIAL_DIFFUSE);
    int mat = -1;
    assert_int_equal(cst_scene_add_material(sc, &md, &mat, &err), CST_OK);
    CstSdfNode cn[3] = {{.kind = CST_SDF_SPHERE, .params = {1}}, {.kind = CST_SDF_BOX, .params = {1, 1, -1}},
                        {.kind = CST_SDF_UNION, .a = 0, .b = 1}};
    CstShapeDesc sd = {.type = CST_SHAPE_SDF, .material = mat, .sdf_nodes = cn, .sdf_num_nodes = 3};
    assert_int_equal(cst_scene_add_shape(sc, &sd, &err), CST_ERR_INVALID_ARG);
    assert_non_null(strstr(err.msg, "sdf_nodes[1]"));
    cn[1].params[2] = 1.0f;
    sd.emission.radiance[0] = 1.0f;
    assert_int_equal(cst_scene_add_shape(sc, &sd, &err), CST_ERR_UNSUPPORTED);
    sd.emission.radiance[0] = 0.0f;
    assert_int_equal(cst_scene_add_shape(sc, &sd, &err), CST_OK);
    cst_scene_destroy(sc);
}

/* ------------------------------------------------------------ through the JSON loader */

static const char *const HEAD =
    "{\"camera\": {\"position\": [0, 0, -6], \"look_at\": [0, 0, 0], \"fov\": 40},\n"
    " \"materials\": {\"m\": {\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},\n"
    " \"shapes\": [\n";

static CstStatus load_shapes(const char *shapes, CstScene **out, CstError *err)
{
    char text[8192];
    snprintf(text, sizeof text, "%s%s]}\n", HEAD, shapes);
    return cst_scene_load_json_string(text, strlen(text), NAME, out, err);
}

/* Loads and expects a failure whose message has "sdf.json:LINE:" (the shapes start on line
 * 4) and `what`. */
static void expect_bad(const char *shapes, int line, const char *what)
{
    CstScene *s = NULL;
    CstError err = {0};
    CstStatus st = load_shapes(shapes, &s, &err);
    assert_null(s);
    if (st == CST_OK) fail_msg("loaded: %s", shapes);
    char loc[32];
    snprintf(loc, sizeof loc, NAME ":%d:", line);
    if (!strstr(err.msg, loc) || !strstr(err.msg, what)) fail_msg("got \"%s\"; expected %s and %s", err.msg, loc, what);
}

static void test_bad_trees_json(void **state)
{
    (void)state;
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\"}", 4, "\"root\"");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"cone\"}}", 5, "unknown SDF node type");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"union\", \"children\": [\n"
               "  {\"type\": \"sphere\", \"radius\": 1}]}}", 5, "at least 2");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"union\", \"children\": [\n"
               "  {\"type\": \"sphere\", \"radius\": 1},\n  {\"type\": \"sphere\", \"radius\": -1}]}}", 7, "radius");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"torus\", \"major_radius\": 1,\n"
               "  \"minor_radius\": 2}}", 6, "minor_radius");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"smooth_union\", \"children\": [\n"
               "  {\"type\": \"sphere\", \"radius\": 1}, {\"type\": \"box\", \"half_size\": [1, 1, 1]}]}}", 5, "\"k\"");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": {\"type\": \"box\", \"half_size\": [1, 1, 1],\n"
               "  \"radius\": 0.1}}", 6, "radius");
    expect_bad("{\"type\": \"sdf\", \"material\": \"m\", \"emission\": {\"radiance\": [1, 1, 1]},\n"
               " \"root\": {\"type\": \"sphere\", \"radius\": 1}}", 4, "emitting SDF");
    expect_bad("{\"type\": \"torus\", \"material\": \"m\", \"major_radius\": 1,\n \"minor_radius\": 1}", 5,
               "minor_radius");
    /* deeper than 24 levels */
    char deep[6000] = "{\"type\": \"sdf\", \"material\": \"m\",\n \"root\": ";
    for (int i = 0; i < 26; i++)
        strcat(deep, "{\"type\": \"union\", \"children\": [{\"type\": \"sphere\", \"radius\": 1}, ");
    strcat(deep, "{\"type\": \"sphere\", \"radius\": 1}");
    for (int i = 0; i < 26; i++) strcat(deep, "]}");
    strcat(deep, "}");
    expect_bad(deep, 5, "deeper than 24");
}

/* A scene of SDF and torus shapes beside a sphere and a quad: every back end of this
 * build gives the list's hits, t to the bit. */
static const char *const ACCEL_SHAPES =
    "{\"type\": \"quad\", \"material\": \"m\", \"vertices\": [[-3, -1, -3], [3, -1, -3], [3, -1, 3], [-3, -1, 3]]},\n"
    "{\"type\": \"sphere\", \"material\": \"m\", \"center\": [1.5, 0, 0.5], \"radius\": 0.5},\n"
    "{\"type\": \"torus\", \"material\": \"m\", \"major_radius\": 0.6, \"minor_radius\": 0.2,\n"
    " \"transform\": {\"rotate\": {\"axis\": [1, 0, 0], \"angle\": 70}, \"translate\": [0, 0.5, 0]}},\n"
    "{\"type\": \"sdf\", \"material\": \"m\", \"transform\": {\"translate\": [-1.2, -0.3, 0]},\n"
    " \"root\": {\"type\": \"smooth_union\", \"k\": 0.3, \"children\": [\n"
    "  {\"type\": \"round_box\", \"half_size\": [0.5, 0.4, 0.5], \"radius\": 0.1},\n"
    "  {\"type\": \"capsule\", \"half_length\": 0.4, \"radius\": 0.2, \"transform\": {\"translate\": [0, 0.6, 0]}}]}},\n"
    "{\"type\": \"sdf\", \"material\": \"m\", \"transform\": {\"translate\": [0.2, -0.5, -1], \"scale\": [1, 0.5, 1]},\n"
    " \"root\": {\"type\": \"difference\", \"children\": [\n"
    "  {\"type\": \"cylinder\", \"radius\": 0.5, \"half_height\": 0.3},\n"
    "  {\"type\": \"torus\", \"major_radius\": 0.5, \"minor_radius\": 0.2}]}}\n";

static void test_accels_agree(void **state)
{
    (void)state;
    static const char *const names[] = {"list", "bvh", "kdtree", "grid", "octree", "embree"};
    enum { N = 4000 };
    float *ref_t = calloc(N, sizeof *ref_t);
    uint32_t *ref_p = calloc(N, sizeof *ref_p);
    int sdf_hits = 0;
    for (int a = 0; a < 6; a++) {
        CstScene *s = NULL;
        CstError err = {0};
        assert_int_equal(load_shapes(ACCEL_SHAPES, &s, &err), CST_OK);
        CstStatus st = cst_scene_set_accel(s, names[a], &err);
        if (st != CST_OK) { /* a back end this build lacks */
            assert_int_equal(a, 5);
            cst_scene_destroy(s);
            continue;
        }
        const Scene *sc = (const Scene *)s;
        Pcg32 rng;
        pcg32_seed(&rng, 21, 4);
        for (int k = 0; k < N; k++) {
            Vec3 o = v3_scale(rand_dir(&rng), 4.0f);
            Vec3 tg = v3(3.0f * pcg32_float(&rng) - 1.5f, 2.0f * pcg32_float(&rng) - 1.0f, 3.0f * pcg32_float(&rng) - 1.5f);
            Ray r = ray_make(o, v3_normalize(v3_sub(tg, o)), 0.0f, INFINITY);
            SurfaceHit h;
            bool hit = scene_intersect(sc, &r, &h);
            float t = hit ? h.t : -1.0f;
            uint32_t prim = hit ? h.prim : UINT32_MAX;
            if (a == 0) {
                ref_t[k] = t, ref_p[k] = prim;
                sdf_hits += hit && prim >= 3; /* 2 triangles, 1 sphere, then the shapes */
            } else if (memcmp(&t, &ref_t[k], sizeof t) != 0 || prim != ref_p[k]) {
                fail_msg("%s ray %d: prim %u t %.9g; list: prim %u t %.9g", names[a], k, prim, (double)t, ref_p[k],
                         (double)ref_t[k]);
            }
        }
        cst_scene_destroy(s);
    }
    assert_true(sdf_hits > 500);
    free(ref_t);
    free(ref_p);
}

/* ------------------------------------------------------------ rendered images */

static void render_mean(const char *shape, uint64_t seed, double mean[3], double se2[3])
{
    char shapes[1024];
    snprintf(shapes, sizeof shapes,
             "{\"type\": \"quad\", \"material\": \"m\", \"vertices\": [[-3, -1, -3], [3, -1, -3], [3, -1, 3], [-3, -1, 3]]},\n"
             "%s", shape);
    char text[4096];
    snprintf(text, sizeof text, "%s%s],\n \"environment\": {\"radiance\": [1, 0.8, 0.6]}}\n", HEAD, shapes);
    CstScene *s = NULL;
    CstError err = {0};
    assert_int_equal(cst_scene_load_json_string(text, strlen(text), NAME, &s, &err), CST_OK);
    CstRenderSettings st;
    cst_render_settings_init(&st);
    st.width = 24, st.height = 24, st.spp = 16, st.max_depth = 4, st.seed = seed, st.seed_set = 1, st.threads = 2;
    st.integrator = CST_INTEGRATOR_PATH;
    st.sampler = CST_SAMPLER_INDEPENDENT; /* se2 sums per-pixel variances: independent samples
                                           * and pixels, not the default zsobol's */
    CstFilm *f = NULL;
    assert_int_equal(cst_render(s, &st, &f, NULL, &err), CST_OK);
    float px[24 * 24 * 3], var[24 * 24 * 3];
    cst_film_pixels(f, px);
    cst_film_variances(f, var);
    for (int c = 0; c < 3; c++) {
        mean[c] = se2[c] = 0.0;
        for (int i = 0; i < 24 * 24; i++) mean[c] += (double)px[3 * i + c], se2[c] += (double)var[3 * i + c];
        mean[c] /= 24.0 * 24.0;
        se2[c] /= (24.0 * 24.0) * (24.0 * 24.0); /* independent pixels */
    }
    cst_film_destroy(f);
    cst_scene_destroy(s);
}

static void test_render_sdf_sphere(void **state)
{
    (void)state;
    double ma[3], va[3], mb[3], vb[3];
    render_mean("{\"type\": \"sphere\", \"material\": \"m\", \"center\": [0, 0, 0], \"radius\": 1}", 1, ma, va);
    render_mean("{\"type\": \"sdf\", \"material\": \"m\", \"root\": {\"type\": \"sphere\", \"radius\": 1}}", 2, mb, vb);
    for (int c = 0; c < 3; c++) {
        const double z = fabs(ma[c] - mb[c]) / sqrt(va[c] + vb[c]);
        print_message("channel %d: analytic %.5f, SDF %.5f, %.2f standard errors\n", c, ma[c], mb[c], z);
        assert_true(z < 4.0);
    }
}

int main(void)
{
    const struct CMUnitTest tests[] = {
        cmocka_unit_test(test_sphere_vs_analytic), cmocka_unit_test(test_torus_vs_quartic),
        cmocka_unit_test(test_csg_closed_forms),   cmocka_unit_test(test_bad_trees_builder),
        cmocka_unit_test(test_bad_trees_json),     cmocka_unit_test(test_accels_agree),
        cmocka_unit_test(test_render_sdf_sphere),
    };
    return cmocka_run_group_tests(tests, NULL, NULL);
}
