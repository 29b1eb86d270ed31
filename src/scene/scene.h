/* The scene: geometry, materials, emitters, camera and the render settings a scene file
 * carries. Built with the scene_add_* calls, then frozen by scene_commit(), which builds
 * the BVH and the emitter distribution; after commit it is read-only and shared by all
 * render threads. */
#ifndef CST_SCENE_SCENE_H
#define CST_SCENE_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "accel/bvh.h"
#include "camera/camera.h"
#include "caustic/caustic.h"
#include "lights/light.h"
#include "materials/material.h"
#include "math/rgb.h"
#include "math/vec3.h"

typedef struct Emission {
    Rgb radiance;  /* black = not an emitter */
    int two_sided; /* 0: emits only on the side its geometric normal points to */
} Emission;

/* Primitive ids: triangles are [0, num_triangles), spheres follow. */
typedef struct PrimInfo {
    int32_t material; /* index into materials */
    int32_t emitter;  /* index into emitters, or -1 */
} PrimInfo;

typedef struct CstScene Scene;
struct CstScene {
    /* geometry */
    Vec3 *positions; int num_positions, cap_positions;
    int32_t *tri_indices; /* 3 per triangle */
    int num_triangles, cap_triangles;
    Sphere *spheres; int num_spheres, cap_spheres;
    PrimInfo *tri_info;    /* num_triangles entries */
    PrimInfo *sphere_info; /* num_spheres entries */
    /* appearance */
    Material *materials; int num_materials, cap_materials;
    Emitter *emitters; int num_emitters, cap_emitters;
    /* after commit */
    Bvh bvh;
    EmitterSampler emitter_sampler;
    float scene_scale; /* max |coordinate| of the scene bounds: sets ray offsets */
    int committed;
    /* view and settings */
    CameraDesc camera;
    int camera_set;
    CstRenderSettings settings; /* what the scene file asked for; zero = default */
    char *output_path;
};

/* Returns NULL on OOM. */
Scene *scene_create(void);
void scene_destroy(Scene *scene);

CstStatus scene_add_material(Scene *scene, const Material *m, int *out_id, CstError *err);
/* Indices are 3 per triangle into positions; all must be in range and the triangles
 * non-degenerate (callers that know file locations check first for better messages).
 * emission may be NULL. */
CstStatus scene_add_mesh(Scene *scene, const Vec3 *positions, int num_vertices,
                         const int *indices, int num_triangles, int material,
                         const Emission *emission, CstError *err);
/* Planar quad v0..v3 as triangles (v0,v1,v2), (v0,v2,v3); normal = (v1-v0) x (v2-v0). */
CstStatus scene_add_quad(Scene *scene, const Vec3 v[4], int material,
                         const Emission *emission, CstError *err);
CstStatus scene_add_sphere(Scene *scene, Vec3 center, float radius, int material,
                           const Emission *emission, CstError *err);
void scene_set_camera(Scene *scene, const CameraDesc *camera);
CstStatus scene_set_output_path(Scene *scene, const char *path, CstError *err);
CstStatus scene_commit(Scene *scene, CstError *err);

static inline const PrimInfo *scene_prim_info(const Scene *s, uint32_t prim)
{
    return (int)prim < s->num_triangles ? &s->tri_info[prim] : &s->sphere_info[(int)prim - s->num_triangles];
}

/* A surface point found by a closest-hit query. */
typedef struct SurfaceHit {
    Vec3 p;        /* position */
    Vec3 ng;       /* unit geometric normal: (v1-v0) x (v2-v0) for triangles, outward for spheres */
    float t;
    uint32_t prim;
    int32_t material, emitter;
} SurfaceHit;

static inline bool scene_intersect(const Scene *s, const Ray *ray, SurfaceHit *sh)
{
    Hit h;
    if (!bvh_intersect(&s->bvh, ray, &h)) return false;
    sh->t = h.t;
    sh->prim = h.prim;
    sh->p = ray_at(ray, h.t);
    if ((int)h.prim < s->num_triangles) {
        const int32_t *t = &s->tri_indices[3 * h.prim];
        Vec3 a = s->positions[t[0]];
        sh->ng = v3_normalize(v3_cross(v3_sub(s->positions[t[1]], a), v3_sub(s->positions[t[2]], a)));
    } else {
        sh->ng = v3_normalize(v3_sub(sh->p, s->spheres[(int)h.prim - s->num_triangles].center));
    }
    const PrimInfo *pi = scene_prim_info(s, h.prim);
    sh->material = pi->material;
    sh->emitter = pi->emitter;
    return true;
}

/* Ray origins are pushed off surfaces by this distance along the geometric normal, so
 * new rays cannot re-hit the surface they leave. It scales with the scene's extent
 * because float rounding of hit positions does (about 1e-7 relative). */
static inline float scene_ray_epsilon(const Scene *s) { return 5e-5f * (1.0f + s->scene_scale); }

/* p moved off the surface with normal ng toward the side direction d points to. */
static inline Vec3 scene_offset(const Scene *s, Vec3 p, Vec3 ng, Vec3 d)
{
    float eps = scene_ray_epsilon(s);
    return v3_madd(p, ng, v3_dot(ng, d) >= 0.0f ? eps : -eps);
}

/* Area of a triangle with nonzero normal; shared by loaders for validation. */
float triangle_area(Vec3 a, Vec3 b, Vec3 c);

/* Defaults applied by the renderer to zero fields. */
#define CST_DEFAULT_WIDTH 512
#define CST_DEFAULT_HEIGHT 512
#define CST_DEFAULT_SPP 16
#define CST_DEFAULT_RR_DEPTH 3

#endif
