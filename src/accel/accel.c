/* Back-end selection, build timing and bookkeeping for the acceleration interface. */
#include "accel/accel.h"

#include <string.h>

#include "core/clock.h"
#include "core/error.h"

static const char *const ACCEL_NAMES[ACCEL_TYPE_COUNT] = {"bvh", "kdtree", "grid", "list", "embree", "octree"};

const char *accel_type_name(AccelType type)
{
    return (unsigned)type < ACCEL_TYPE_COUNT ? ACCEL_NAMES[type] : "unknown";
}

bool accel_type_from_name(const char *name, AccelType *out)
{
    for (int i = 0; i < ACCEL_TYPE_COUNT; i++)
        if (strcmp(name, ACCEL_NAMES[i]) == 0) { *out = (AccelType)i; return true; }
    return false;
}

bool accel_type_available(AccelType type)
{
    return type == ACCEL_EMBREE ? embree_available() : (unsigned)type < ACCEL_TYPE_COUNT;
}

static BBox geometry_bounds(const AccelGeometry *g)
{
    BBox b = bbox_empty();
    for (int i = 0; i < 3 * g->num_tris; i++) b = bbox_add(b, g->positions[g->tri_indices[i]]);
    for (int i = 0; i < g->num_spheres; i++) {
        Vec3 r = v3s(g->spheres[i].radius);
        b = bbox_add(bbox_add(b, v3_sub(g->spheres[i].center, r)), v3_add(g->spheres[i].center, r));
    }
    for (int i = 0; i < g->num_shapes; i++) b = bbox_union(b, g->shapes[i].bounds);
    return b;
}

static CstStatus accel_build_mode(Accel *a, AccelType type, const AccelGeometry *geom, EmbreeMode mode, CstError *err)
{
    memset(a, 0, sizeof *a);
    a->type = type;
    double t0 = clock_seconds();
    CstStatus st;
    switch (type) {
    case ACCEL_BVH: st = bvh_build(&a->bvh, geom, err); break;
    case ACCEL_KDTREE: st = kdtree_build(&a->kdtree, geom, err); break;
    case ACCEL_GRID: st = grid_build(&a->grid, geom, err); break;
    case ACCEL_LIST: st = list_build(&a->list, geom, err); break;
    case ACCEL_EMBREE: st = embree_build(&a->embree, geom, mode, err); break;
    case ACCEL_OCTREE: st = octree_build(&a->octree, geom, err); break;
    default: return cst_fail(err, CST_ERR_INVALID_ARG, "unknown acceleration structure %d", (int)type);
    }
    if (st != CST_OK) {
        /* Leave a state accel_free() accepts: each back end cleans up after itself. */
        memset(a, 0, sizeof *a);
        return st;
    }
    a->build_seconds = clock_seconds() - t0;
    a->bounds = geometry_bounds(geom);
    return CST_OK;
}

CstStatus accel_build(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err)
{
    return accel_build_mode(a, type, geom, EMBREE_EXACT, err);
}

CstStatus accel_build_native(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err)
{
    return accel_build_mode(a, type, geom, EMBREE_NATIVE, err);
}

CstStatus accel_build_native_robust(Accel *a, AccelType type, const AccelGeometry *geom, CstError *err)
{
    return accel_build_mode(a, type, geom, EMBREE_NATIVE_ROBUST, err);
}

void accel_free(Accel *a)
{
    if (!a) return;
    switch (a->type) {
    case ACCEL_BVH: bvh_free(&a->bvh); break;
    case ACCEL_KDTREE: kdtree_free(&a->kdtree); break;
    case ACCEL_GRID: grid_free(&a->grid); break;
    case ACCEL_LIST: list_free(&a->list); break;
    case ACCEL_EMBREE: embree_free(a->embree); break;
    case ACCEL_OCTREE: octree_free(&a->octree); break;
    }
    memset(a, 0, sizeof *a);
}

size_t accel_memory_bytes(const Accel *a)
{
    switch (a->type) {
    case ACCEL_BVH: return bvh_memory_bytes(&a->bvh);
    case ACCEL_KDTREE: return kdtree_memory_bytes(&a->kdtree);
    case ACCEL_GRID: return grid_memory_bytes(&a->grid);
    case ACCEL_LIST: return list_memory_bytes(&a->list);
    case ACCEL_EMBREE: return embree_memory_bytes(a->embree);
    case ACCEL_OCTREE: return octree_memory_bytes(&a->octree);
    }
    return 0;
}
