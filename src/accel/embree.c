/* Intel Embree 3 as a comparison back end: one device and one scene per structure. Our
 * spheres are a user geometry whose callbacks run our own sphere_intersect(); our
 * triangles are either Embree's own triangle geometry (native: Embree's speed, its
 * arithmetic) or a user geometry running our watertight test, so that hits, and images,
 * agree with the other back ends bit for bit. Compiled against Embree only when CMake
 * defines CST_HAVE_EMBREE. */
#include "accel/embree.h"

#include "core/error.h"

#ifndef CST_HAVE_EMBREE

bool embree_available(void) { return false; }

CstStatus embree_build(EmbreeAccel **out, const AccelGeometry *geom, EmbreeMode mode, CstError *err)
{
    (void)geom;
    (void)mode;
    *out = NULL;
    return cst_fail(err, CST_ERR_UNSUPPORTED,
                    "this build has no Embree back end (configure with -DCST_EMBREE=ON and "
                    "Embree 3 installed, e.g. Debian's libembree-dev)");
}
void embree_free(EmbreeAccel *a) { (void)a; }
bool embree_intersect(const EmbreeAccel *a, const Ray *r, Hit *hit) { (void)a; (void)r; (void)hit; return false; }
bool embree_occluded(const EmbreeAccel *a, const Ray *r) { (void)a; (void)r; return false; }
size_t embree_memory_bytes(const EmbreeAccel *a) { (void)a; return 0; }

#else /* CST_HAVE_EMBREE */

#include <embree3/rtcore.h>
#include <math.h>
#include <stdatomic.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/sphere.h"
#include "geometry/triangle.h"
#include "math/bbox.h"

/* Fixed geometry ids, so a hit's geomID tells which primitive range primID is in. */
enum { EMBREE_GEOM_TRIANGLES = 0, EMBREE_GEOM_SPHERES = 1, EMBREE_GEOM_SHAPES = 2 };

struct EmbreeAccel {
    RTCDevice device;
    RTCScene scene;
    const Sphere *spheres; /* borrowed from the AccelGeometry, read by the callbacks */
    const Vec3 *positions; /* borrowed too, for the watertight triangle callbacks */
    const int32_t *tri_indices;
    uint32_t num_tris;     /* sphere j has scene primitive id num_tris + j */
    const AnalyticShape *shapes; /* borrowed too: shape k has id shape_base + k */
    uint32_t shape_base;
    /* Added to the user geometries' boxes, as the BVH widens its node boxes (bvh.c,
     * widen): a ray lying exactly in a box's face plane with a zero direction component
     * (an axis ray along a mesh's edge at coordinate 0, where two ulps are a denormal)
     * would otherwise miss the box and a hit every other back end finds. */
    float margin;
    /* Net bytes Embree allocated on this device (allocations minus frees) since the memory
     * monitor was installed. Embree builds with TBB threads: the callback runs
     * concurrently, hence the atomic. */
    _Atomic long long live_bytes;
    size_t memory_bytes; /* live_bytes after the commit */
    /* The first error Embree reported, with its message (the error callback's text is
     * the only place Embree gives one; rtcGetDeviceError returns the code alone). */
    enum RTCError error_code;
    char error_msg[200];
};

bool embree_available(void) { return true; }

static const char *embree_error_name(enum RTCError code)
{
    switch (code) {
    case RTC_ERROR_NONE: return "no error";
    case RTC_ERROR_UNKNOWN: return "unknown error";
    case RTC_ERROR_INVALID_ARGUMENT: return "invalid argument";
    case RTC_ERROR_INVALID_OPERATION: return "invalid operation";
    case RTC_ERROR_OUT_OF_MEMORY: return "out of memory";
    case RTC_ERROR_UNSUPPORTED_CPU: return "unsupported CPU";
    case RTC_ERROR_CANCELLED: return "cancelled";
    }
    return "unrecognised error code";
}

static void embree_on_error(void *user, enum RTCError code, const char *str)
{
    EmbreeAccel *a = user;
    if (a->error_code != RTC_ERROR_NONE) return; /* keep the first: later ones follow from it */
    a->error_code = code;
    snprintf(a->error_msg, sizeof a->error_msg, "%s", str ? str : "");
}

static bool embree_on_memory(void *user, ssize_t bytes, bool post)
{
    (void)post;
    EmbreeAccel *a = user;
    atomic_fetch_add_explicit(&a->live_bytes, (long long)bytes, memory_order_relaxed);
    return true; /* never veto an allocation */
}

/* Turns the device's pending error, if any, into a CstStatus with a message naming what
 * we were doing. */
static CstStatus embree_check(EmbreeAccel *a, const char *doing, CstError *err)
{
    enum RTCError code = rtcGetDeviceError(a->device);
    if (code == RTC_ERROR_NONE && a->error_code == RTC_ERROR_NONE) return CST_OK;
    if (code == RTC_ERROR_NONE) code = a->error_code;
    CstStatus st = code == RTC_ERROR_OUT_OF_MEMORY ? CST_ERR_OOM
                 : code == RTC_ERROR_UNSUPPORTED_CPU ? CST_ERR_UNSUPPORTED
                 : CST_ERR_INTERNAL;
    return cst_fail(err, st, "Embree: %s: %s%s%s", doing, embree_error_name(code),
                    a->error_msg[0] ? ": " : "", a->error_msg);
}

/* ------------------------------------------------------------ spheres as user geometry */

/* Embree passes packets of N rays in SoA layout (rtcore_ray.h: RTCRayN is 12 arrays of N
 * floats/uints, RTCHitN follows RTCRayN in an RTCRayHitN). Its C++ accessors are not
 * available in C, so index by hand. We only call rtcIntersect1/rtcOccluded1 (N = 1), but
 * the callbacks stay correct for any N. */
static inline float *embree_rayn_f(void *rayn, unsigned n, unsigned field, unsigned i)
{
    return &((float *)rayn)[field * n + i];
}
static inline unsigned *embree_rayn_u(void *rayn, unsigned n, unsigned field, unsigned i)
{
    return &((unsigned *)rayn)[field * n + i];
}
enum {
    RAYN_ORG_X = 0, RAYN_ORG_Y, RAYN_ORG_Z, RAYN_TNEAR, RAYN_DIR_X, RAYN_DIR_Y, RAYN_DIR_Z,
    RAYN_TIME, RAYN_TFAR, RAYN_MASK, RAYN_ID, RAYN_FLAGS, RAYN_FIELDS
};
enum { HITN_NG_X = 0, HITN_NG_Y, HITN_NG_Z, HITN_U, HITN_V, HITN_PRIM, HITN_GEOM, HITN_INST };

static Ray embree_rayn_load(void *rayn, unsigned n, unsigned i)
{
    return ray_make(v3(*embree_rayn_f(rayn, n, RAYN_ORG_X, i), *embree_rayn_f(rayn, n, RAYN_ORG_Y, i),
                       *embree_rayn_f(rayn, n, RAYN_ORG_Z, i)),
                    v3(*embree_rayn_f(rayn, n, RAYN_DIR_X, i), *embree_rayn_f(rayn, n, RAYN_DIR_Y, i),
                       *embree_rayn_f(rayn, n, RAYN_DIR_Z, i)),
                    *embree_rayn_f(rayn, n, RAYN_TNEAR, i), *embree_rayn_f(rayn, n, RAYN_TFAR, i));
}

/* The box must contain every point sphere_intersect can report; one ulp outward covers
 * the rounding of center +- radius. */
static void embree_sphere_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const Sphere *s = &a->spheres[args->primID];
    const float r = fabsf(s->radius); /* sphere_intersect squares the radius: its sign is moot */
    struct RTCBounds *b = args->bounds_o;
    b->lower_x = nextafterf(s->center.x - r, -INFINITY) - a->margin;
    b->lower_y = nextafterf(s->center.y - r, -INFINITY) - a->margin;
    b->lower_z = nextafterf(s->center.z - r, -INFINITY) - a->margin;
    b->upper_x = nextafterf(s->center.x + r, INFINITY) + a->margin;
    b->upper_y = nextafterf(s->center.y + r, INFINITY) + a->margin;
    b->upper_z = nextafterf(s->center.z + r, INFINITY) + a->margin;
}

/* Closest hit: accept a root in (tnear, tfar) — sphere_intersect's open interval, the same
 * as every other back end — and shrink tfar to it. */
static void embree_sphere_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const Sphere *s = &a->spheres[args->primID];
    unsigned n = args->N;
    void *rayn = args->rayhit;
    void *hitn = (float *)args->rayhit + RAYN_FIELDS * n;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(rayn, n, i);
        float t;
        if (!sphere_intersect(s->center, s->radius, &r, &t)) continue;
        Vec3 ng = v3_sub(ray_at(&r, t), s->center);
        *embree_rayn_f(rayn, n, RAYN_TFAR, i) = t;
        *embree_rayn_f(hitn, n, HITN_NG_X, i) = ng.x;
        *embree_rayn_f(hitn, n, HITN_NG_Y, i) = ng.y;
        *embree_rayn_f(hitn, n, HITN_NG_Z, i) = ng.z;
        *embree_rayn_f(hitn, n, HITN_U, i) = 0.0f;
        *embree_rayn_f(hitn, n, HITN_V, i) = 0.0f;
        *embree_rayn_u(hitn, n, HITN_PRIM, i) = args->primID;
        *embree_rayn_u(hitn, n, HITN_GEOM, i) = args->geomID;
        *embree_rayn_u(hitn, n, HITN_INST, i) = args->context->instID[0];
    }
}

/* ------------------------------------------------------------ analytic shapes, the same way */

static void embree_shape_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const BBox sb = a->shapes[args->primID].bounds; /* padded (shape_init) */
    struct RTCBounds *b = args->bounds_o;
    b->lower_x = sb.min.x - a->margin; b->lower_y = sb.min.y - a->margin; b->lower_z = sb.min.z - a->margin;
    b->upper_x = sb.max.x + a->margin; b->upper_y = sb.max.y + a->margin; b->upper_z = sb.max.z + a->margin;
}

static void embree_shape_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const AnalyticShape *s = &a->shapes[args->primID];
    unsigned n = args->N;
    void *rayn = args->rayhit;
    void *hitn = (float *)args->rayhit + RAYN_FIELDS * n;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(rayn, n, i);
        float t, u, v;
        if (!shape_intersect(s, &r, &t, &u, &v)) continue;
        *embree_rayn_f(rayn, n, RAYN_TFAR, i) = t;
        *embree_rayn_f(hitn, n, HITN_NG_X, i) = 0.0f; /* unused: the scene rebuilds the surface */
        *embree_rayn_f(hitn, n, HITN_NG_Y, i) = 0.0f;
        *embree_rayn_f(hitn, n, HITN_NG_Z, i) = 1.0f;
        *embree_rayn_f(hitn, n, HITN_U, i) = u;
        *embree_rayn_f(hitn, n, HITN_V, i) = v;
        *embree_rayn_u(hitn, n, HITN_PRIM, i) = args->primID;
        *embree_rayn_u(hitn, n, HITN_GEOM, i) = args->geomID;
        *embree_rayn_u(hitn, n, HITN_INST, i) = args->context->instID[0];
    }
}

static void embree_shape_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const AnalyticShape *s = &a->shapes[args->primID];
    unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(args->ray, n, i);
        float t, u, v;
        if (shape_intersect(s, &r, &t, &u, &v)) *embree_rayn_f(args->ray, n, RAYN_TFAR, i) = -INFINITY;
    }
}

/* Any hit: Embree's convention for "occluded" is tfar = -inf. */
static void embree_sphere_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const Sphere *s = &a->spheres[args->primID];
    unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(args->ray, n, i);
        float t;
        if (sphere_intersect(s->center, s->radius, &r, &t))
            *embree_rayn_f(args->ray, n, RAYN_TFAR, i) = -INFINITY;
    }
}

/* ------------------------------------------------------------ exact triangles */

/* Our watertight test reports points on the triangle, inside its vertices' box up to
 * rounding; two ulps outward cover that and the rounding of Embree's own box tests. */
static void embree_triangle_bounds(const struct RTCBoundsFunctionArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    const int32_t *t = &a->tri_indices[3 * (size_t)args->primID];
    BBox b = bbox_add(bbox_add(bbox_add(bbox_empty(), a->positions[t[0]]), a->positions[t[1]]), a->positions[t[2]]);
    struct RTCBounds *o = args->bounds_o;
    o->lower_x = nextafterf(nextafterf(b.min.x, -INFINITY), -INFINITY) - a->margin;
    o->lower_y = nextafterf(nextafterf(b.min.y, -INFINITY), -INFINITY) - a->margin;
    o->lower_z = nextafterf(nextafterf(b.min.z, -INFINITY), -INFINITY) - a->margin;
    o->upper_x = nextafterf(nextafterf(b.max.x, INFINITY), INFINITY) + a->margin;
    o->upper_y = nextafterf(nextafterf(b.max.y, INFINITY), INFINITY) + a->margin;
    o->upper_z = nextafterf(nextafterf(b.max.z, INFINITY), INFINITY) + a->margin;
}

static inline bool embree_triangle_test(const EmbreeAccel *a, unsigned prim, const Ray *r, float *t, float *u,
                                        float *v)
{
    const int32_t *i = &a->tri_indices[3 * (size_t)prim];
    TriangleRay tr = triangle_ray_setup(r->d);
    return triangle_intersect_watertight(&tr, r, a->positions[i[0]], a->positions[i[1]], a->positions[i[2]], t, u, v);
}

static void embree_triangle_intersect(const struct RTCIntersectFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    unsigned n = args->N;
    void *rayn = args->rayhit;
    void *hitn = (float *)args->rayhit + RAYN_FIELDS * n;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(rayn, n, i);
        float t, u, v;
        if (!embree_triangle_test(a, args->primID, &r, &t, &u, &v)) continue;
        *embree_rayn_f(rayn, n, RAYN_TFAR, i) = t;
        *embree_rayn_f(hitn, n, HITN_NG_X, i) = 0.0f; /* unused: the scene computes normals */
        *embree_rayn_f(hitn, n, HITN_NG_Y, i) = 0.0f;
        *embree_rayn_f(hitn, n, HITN_NG_Z, i) = 0.0f;
        *embree_rayn_f(hitn, n, HITN_U, i) = u;
        *embree_rayn_f(hitn, n, HITN_V, i) = v;
        *embree_rayn_u(hitn, n, HITN_PRIM, i) = args->primID;
        *embree_rayn_u(hitn, n, HITN_GEOM, i) = args->geomID;
        *embree_rayn_u(hitn, n, HITN_INST, i) = args->context->instID[0];
    }
}

static void embree_triangle_occluded(const struct RTCOccludedFunctionNArguments *args)
{
    const EmbreeAccel *a = args->geometryUserPtr;
    unsigned n = args->N;
    for (unsigned i = 0; i < n; i++) {
        if (!args->valid[i]) continue;
        Ray r = embree_rayn_load(args->ray, n, i);
        float t, u, v;
        if (embree_triangle_test(a, args->primID, &r, &t, &u, &v)) *embree_rayn_f(args->ray, n, RAYN_TFAR, i) = -INFINITY;
    }
}

/* ------------------------------------------------------------ build */

/* Triangles in an Embree-owned buffer: rtcSetNewGeometryBuffer pads the vertex buffer
 * for Embree's 16-byte vector loads, which sharing our tightly packed Vec3 array would
 * not guarantee. The copy costs memory (counted in memory_bytes) but no speed. */
static CstStatus embree_add_triangles(EmbreeAccel *a, const AccelGeometry *g, CstError *err)
{
    int32_t max_index = -1;
    for (int i = 0; i < 3 * g->num_tris; i++) {
        if (g->tri_indices[i] < 0)
            return cst_fail(err, CST_ERR_INVALID_ARG, "Embree: negative vertex index %d in triangle %d",
                            (int)g->tri_indices[i], i / 3);
        if (g->tri_indices[i] > max_index) max_index = g->tri_indices[i];
    }
    size_t num_vertices = (size_t)max_index + 1;

    RTCGeometry geom = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geom) return embree_check(a, "creating the triangle geometry", err);
    float *vb = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                        3 * sizeof(float), num_vertices);
    unsigned *ib = rtcSetNewGeometryBuffer(geom, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                           3 * sizeof(unsigned), (size_t)g->num_tris);
    if (!vb || !ib) {
        rtcReleaseGeometry(geom);
        return embree_check(a, "allocating the triangle buffers", err);
    }
    for (size_t i = 0; i < num_vertices; i++) {
        vb[3 * i + 0] = g->positions[i].x;
        vb[3 * i + 1] = g->positions[i].y;
        vb[3 * i + 2] = g->positions[i].z;
    }
    for (size_t i = 0; i < 3 * (size_t)g->num_tris; i++) ib[i] = (unsigned)g->tri_indices[i];
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(a->scene, geom, EMBREE_GEOM_TRIANGLES);
    rtcReleaseGeometry(geom); /* the scene holds its own reference */
    return embree_check(a, "adding the triangles", err);
}

/* Primitives Embree intersects through our callbacks (exact triangles, spheres, analytic
 * shapes): one user geometry of `count` primitives under geometry id `id`; `what` names
 * them in messages. */
static CstStatus embree_add_user(EmbreeAccel *a, int count, RTCBoundsFunction bounds,
                                 RTCIntersectFunctionN intersect, RTCOccludedFunctionN occluded,
                                 unsigned id, const char *what, CstError *err)
{
    char msg[64];
    RTCGeometry geom = rtcNewGeometry(a->device, RTC_GEOMETRY_TYPE_USER);
    snprintf(msg, sizeof msg, "creating the %s geometry", what);
    if (!geom) return embree_check(a, msg, err);
    rtcSetGeometryUserPrimitiveCount(geom, (unsigned)count);
    rtcSetGeometryUserData(geom, a);
    rtcSetGeometryBoundsFunction(geom, bounds, NULL);
    rtcSetGeometryIntersectFunction(geom, intersect);
    rtcSetGeometryOccludedFunction(geom, occluded);
    rtcCommitGeometry(geom);
    rtcAttachGeometryByID(a->scene, geom, id);
    rtcReleaseGeometry(geom); /* the scene holds its own reference */
    snprintf(msg, sizeof msg, "adding the %ss", what);
    return embree_check(a, msg, err);
}

CstStatus embree_build(EmbreeAccel **out, const AccelGeometry *geom, EmbreeMode mode, CstError *err)
{
    const bool native_triangles = mode != EMBREE_EXACT;
    *out = NULL;
    EmbreeAccel *a = calloc(1, sizeof *a);
    if (!a) return cst_fail(err, CST_ERR_OOM, "out of memory creating the Embree back end");
    atomic_init(&a->live_bytes, 0);
    a->spheres = geom->spheres;
    a->positions = geom->positions;
    a->tri_indices = geom->tri_indices;
    a->num_tris = (uint32_t)geom->num_tris;
    a->shapes = geom->shapes;
    a->shape_base = accel_shape_base(geom);
    /* The BVH's margin: a hair (1e-7) of the largest finite coordinate. */
    float extent = 0.0f;
    for (int i = 0; i < 3 * geom->num_tris; i++) {
        Vec3 p = geom->positions[geom->tri_indices[i]];
        const float c[3] = {fabsf(p.x), fabsf(p.y), fabsf(p.z)};
        for (int k = 0; k < 3; k++)
            if (isfinite(c[k]) && c[k] > extent) extent = c[k];
    }
    for (int i = 0; i < geom->num_spheres; i++) {
        Vec3 p = geom->spheres[i].center;
        const float c[3] = {fabsf(p.x), fabsf(p.y), fabsf(p.z)}, r = fabsf(geom->spheres[i].radius);
        for (int k = 0; k < 3; k++)
            if (isfinite(c[k] + r) && c[k] + r > extent) extent = c[k] + r;
    }
    for (int i = 0; i < geom->num_shapes; i++) {
        const BBox sb = geom->shapes[i].bounds;
        const float c = fmaxf(v3_max_abs(sb.min), v3_max_abs(sb.max));
        if (isfinite(c) && c > extent) extent = c;
    }
    /* Capped: boxes grown past Embree's range (FLT_LARGE, 1.8e18) lose hits near them. */
    a->margin = 1e-7f * fminf(extent, 1e18f) + 1e-30f;
    CstStatus st = CST_OK;

    /* Default configuration: all hardware threads build, best ISA the CPU supports. */
    a->device = rtcNewDevice(NULL);
    if (!a->device) {
        enum RTCError code = rtcGetDeviceError(NULL);
        st = cst_fail(err, code == RTC_ERROR_UNSUPPORTED_CPU ? CST_ERR_UNSUPPORTED : CST_ERR_INTERNAL,
                      "Embree: creating the device: %s", embree_error_name(code));
        goto fail;
    }
    rtcSetDeviceErrorFunction(a->device, embree_on_error, a);
    rtcSetDeviceMemoryMonitorFunction(a->device, embree_on_memory, a);

    a->scene = rtcNewScene(a->device);
    if (!a->scene) { st = embree_check(a, "creating the scene", err); goto fail; }
    /* Robust mode is EMBREE_NATIVE_ROBUST's definition, and exact mode needs it too:
     * Embree's default box test computes lower * rdir - org * rdir, which loses hits a few
     * ulps of the coordinates from the origin (where two walls meet, a bounce ray can cross
     * the other wall at t ~ 1e-5 in a box of size 500), hits our conservative BVH keeps. */
    rtcSetSceneFlags(a->scene, mode == EMBREE_NATIVE ? RTC_SCENE_FLAG_NONE : RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(a->scene, RTC_BUILD_QUALITY_MEDIUM); /* Embree's default */

    if (geom->num_tris > 0 && native_triangles) st = embree_add_triangles(a, geom, err);
    else if (geom->num_tris > 0)
        st = embree_add_user(a, geom->num_tris, embree_triangle_bounds, embree_triangle_intersect,
                             embree_triangle_occluded, EMBREE_GEOM_TRIANGLES, "triangle", err);
    if (st == CST_OK && geom->num_spheres > 0)
        st = embree_add_user(a, geom->num_spheres, embree_sphere_bounds, embree_sphere_intersect,
                             embree_sphere_occluded, EMBREE_GEOM_SPHERES, "sphere", err);
    if (st == CST_OK && geom->num_shapes > 0)
        st = embree_add_user(a, geom->num_shapes, embree_shape_bounds, embree_shape_intersect,
                             embree_shape_occluded, EMBREE_GEOM_SHAPES, "shape", err);
    if (st != CST_OK) goto fail;
    rtcCommitScene(a->scene);
    if ((st = embree_check(a, "building the BVH", err)) != CST_OK) goto fail;

    long long live = atomic_load(&a->live_bytes);
    a->memory_bytes = sizeof *a + (live > 0 ? (size_t)live : 0u);
    *out = a;
    return CST_OK;
fail:
    embree_free(a);
    return st;
}

void embree_free(EmbreeAccel *a)
{
    if (!a) return;
    if (a->scene) rtcReleaseScene(a->scene);
    if (a->device) rtcReleaseDevice(a->device);
    free(a);
}

/* ------------------------------------------------------------ queries */

/* Interval semantics: Embree 3.13's triangle test accepts tnear < t <= tfar, open at tnear
 * like ours but closed at tfar (its depth test is absDen * tnear < T <= absDen * tfar;
 * checked on an axis-aligned triangle at exactly t = 1: tnear = 1 misses in both, tfar = 1
 * hits in Embree only). Ours is t_min < t < t_max throughout, and the sphere and exact
 * triangle callbacks use our open test. The difference shows only for a t_max exactly equal to a hit
 * distance, which neither the renderer (shadow rays stop short of their target) nor the
 * benchmark (t_max = inf or 1e30) produces. */
static inline void embree_ray_set(struct RTCRay *er, const Ray *r)
{
    er->org_x = r->o.x; er->org_y = r->o.y; er->org_z = r->o.z;
    er->tnear = r->t_min;
    er->dir_x = r->d.x; er->dir_y = r->d.y; er->dir_z = r->d.z;
    er->time = 0.0f;
    er->tfar = r->t_max;
    er->mask = 0xFFFFFFFFu;
    er->id = 0;
    er->flags = 0;
}

bool embree_intersect(const EmbreeAccel *a, const Ray *r, Hit *hit)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRayHit rh;
    embree_ray_set(&rh.ray, r);
    rh.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rh.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(a->scene, &ctx, &rh);
    if (rh.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
    hit->t = rh.ray.tfar;
    hit->u = rh.hit.u; /* Embree's u, v weight v1 and v2: our convention */
    hit->v = rh.hit.v;
    hit->prim = rh.hit.geomID == EMBREE_GEOM_SPHERES ? a->num_tris + rh.hit.primID
              : rh.hit.geomID == EMBREE_GEOM_SHAPES  ? a->shape_base + rh.hit.primID
                                                     : rh.hit.primID;
    return true;
}

bool embree_occluded(const EmbreeAccel *a, const Ray *r)
{
    struct RTCIntersectContext ctx;
    rtcInitIntersectContext(&ctx);
    struct RTCRay er;
    embree_ray_set(&er, r);
    rtcOccluded1(a->scene, &ctx, &er);
    return er.tfar == -INFINITY;
}

size_t embree_memory_bytes(const EmbreeAccel *a) { return a ? a->memory_bytes : 0; }

#endif /* CST_HAVE_EMBREE */
