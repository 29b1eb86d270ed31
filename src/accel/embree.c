/* PLACEHOLDER: the Embree back end is being written. */
#include "accel/embree.h"

#include "core/error.h"

bool embree_available(void) { return false; }
CstStatus embree_build(EmbreeAccel **out, const AccelGeometry *geom, CstError *err)
{
    (void)geom;
    *out = NULL;
    return cst_fail(err, CST_ERR_UNSUPPORTED, "this build has no Embree back end");
}
void embree_free(EmbreeAccel *a) { (void)a; }
bool embree_intersect(const EmbreeAccel *a, const Ray *r, Hit *hit) { (void)a; (void)r; (void)hit; return false; }
bool embree_occluded(const EmbreeAccel *a, const Ray *r) { (void)a; (void)r; return false; }
size_t embree_memory_bytes(const EmbreeAccel *a) { (void)a; return 0; }
