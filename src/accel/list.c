/* Brute-force intersection over all primitives, in primitive order. */
#include "accel/list.h"

#include "geometry/shape.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"

CstStatus list_build(ListAccel *l, const AccelGeometry *geom, CstError *err)
{
    (void)err;
    l->geom = *geom;
    return CST_OK;
}

void list_free(ListAccel *l) { (void)l; }

static inline bool list_prim(const AccelGeometry *g, const TriangleRay *tr, int i, const Ray *r,
                             float *t, float *u, float *v)
{
    if (i < g->num_tris) {
        const int32_t *k = &g->tri_indices[3 * i];
        return triangle_intersect_watertight(tr, r, g->positions[k[0]], g->positions[k[1]],
                                             g->positions[k[2]], t, u, v);
    }
    if (i < g->num_tris + g->num_spheres) {
        const Sphere *s = &g->spheres[i - g->num_tris];
        *u = *v = 0.0f;
        return sphere_intersect(s->center, s->radius, r, t);
    }
    return shape_intersect(&g->shapes[i - g->num_tris - g->num_spheres], r, t, u, v);
}

bool list_intersect(const ListAccel *l, const Ray *ray, Hit *hit)
{
    Ray r = *ray;
    TriangleRay tr = triangle_ray_setup(r.d);
    bool found = false;
    int n = l->geom.num_tris + l->geom.num_spheres + l->geom.num_shapes;
    for (int i = 0; i < n; i++) {
        float t, u, v;
        if (list_prim(&l->geom, &tr, i, &r, &t, &u, &v)) {
            r.t_max = t;
            hit->t = t; hit->u = u; hit->v = v; hit->prim = (uint32_t)i;
            found = true;
        }
    }
    return found;
}

bool list_occluded(const ListAccel *l, const Ray *r)
{
    TriangleRay tr = triangle_ray_setup(r->d);
    int n = l->geom.num_tris + l->geom.num_spheres + l->geom.num_shapes;
    for (int i = 0; i < n; i++) {
        float t, u, v;
        if (list_prim(&l->geom, &tr, i, r, &t, &u, &v)) return true;
    }
    return false;
}

size_t list_memory_bytes(const ListAccel *l) { (void)l; return sizeof *l; }
