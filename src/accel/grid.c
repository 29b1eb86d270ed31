/* PLACEHOLDER: the grid back end is being written. */
#include "accel/grid.h"

#include "core/error.h"

CstStatus grid_build(Grid *a, const AccelGeometry *geom, CstError *err)
{
    (void)a; (void)geom;
    return cst_fail(err, CST_ERR_UNSUPPORTED, "the grid back end is not built yet");
}
void grid_free(Grid *a) { (void)a; }
bool grid_intersect(const Grid *a, const Ray *r, Hit *hit) { (void)a; (void)r; (void)hit; return false; }
bool grid_occluded(const Grid *a, const Ray *r) { (void)a; (void)r; return false; }
size_t grid_memory_bytes(const Grid *a) { (void)a; return 0; }
