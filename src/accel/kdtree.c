/* PLACEHOLDER: the kdtree back end is being written. */
#include "accel/kdtree.h"

#include "core/error.h"

CstStatus kdtree_build(KdTree *a, const AccelGeometry *geom, CstError *err)
{
    (void)a; (void)geom;
    return cst_fail(err, CST_ERR_UNSUPPORTED, "the kdtree back end is not built yet");
}
void kdtree_free(KdTree *a) { (void)a; }
bool kdtree_intersect(const KdTree *a, const Ray *r, Hit *hit) { (void)a; (void)r; (void)hit; return false; }
bool kdtree_occluded(const KdTree *a, const Ray *r) { (void)a; (void)r; return false; }
size_t kdtree_memory_bytes(const KdTree *a) { (void)a; return 0; }
