/* The scene: geometry, materials, emitters, camera and the render settings a scene file
 * carries. Built with the scene_add_* calls, then frozen by scene_commit(), which builds
 * the BVH and the emitter distribution; after commit it is read-only and shared by all
 * render threads. */
#ifndef CST_SCENE_SCENE_H
#define CST_SCENE_SCENE_H

#include <stdbool.h>
#include <stdint.h>

#include "accel/accel.h"
#include "accel/instances.h"
#include "core/rng.h"
#include "camera/camera.h"
#include "caustic/caustic.h"
#include "geometry/shape.h"
#include "geometry/sphere.h"
#include "geometry/triangle.h"
#include "lights/light.h"
#include "materials/bsdf.h"
#include "materials/bsdf_spectral.h"
#include "materials/material.h"
#include "math/color.h"
#include "math/spectrum.h"
#include "math/cie_data.h"
#include "math/spectrum_sampled.h"
#include "math/vec3.h"
#include "media/medium.h"
#include "scene/footprint.h"
#include "scene/scene_build.h"
#include "textures/texture.h"

typedef struct Emission {
    Color radiance;  /* black = not an emitter */
    int two_sided; /* 0: emits only on the side its geometric normal points to */
    int texture;   /* 1 + texture index: radiance times the texture; 0 = none */
} Emission;

/* Primitive ids: triangles are [0, num_triangles), spheres follow. */
typedef struct PrimInfo {
    int32_t material; /* index into materials */
    int32_t emitter;  /* index into emitters, or -1 */
    int32_t alpha;    /* 1 + index into Scene.alphas; 0: opaque (no cut-out) */
    int32_t medium;   /* 1 + index into Scene.medium_ifaces; 0: no medium transition (a
                       * ray crossing it stays in its medium, as in pbrt-v4) */
} PrimInfo;

/* An alpha cut-out (pbrt-v4's Shape "alpha"): where the alpha a at a hit is 0 the surface
 * does not exist, where it is 1 it is opaque, and in between a ray keeps the hit with
 * probability a (a stochastic test, deterministic per ray: scene_alpha_cut()). */
typedef struct AlphaMask {
    float value; /* the alpha, when texture is 0 */
    int texture; /* 1 + index into the scene's textures (its scalar value), or 0 */
} AlphaMask;

typedef struct CstScene Scene;
struct CstScene {
    /* geometry */
    Vec3 *positions; int num_positions; size_t cap_positions;
    /* Per-position vertex attributes for shading, NULL until a mesh supplies them; then
     * positions of meshes without them hold zero fills (a zero normal means "none") and
     * the *_partial flag is set. */
    Vec3 *normals; size_t cap_normals; /* unit shading normals */
    Vec2 *uvs; size_t cap_uvs;      /* texture coordinates, channel 0 */
    int normals_partial, uvs_partial;
    /* Per triangle, whether it takes its uvs from `uvs` (else the default (0,0), (1,0),
     * (0,1) at its vertices): NULL until a mesh with uvs arrives. */
    unsigned char *tri_has_uv;
    int32_t *tri_indices; /* 3 per triangle */
    int num_triangles; size_t cap_triangles; /* of tri_indices */
    Sphere *spheres; int num_spheres; size_t cap_spheres;
    PrimInfo *tri_info;    /* num_triangles entries */
    Vec3 *tri_normals;     /* unit geometric normals, (v1-v0) x (v2-v0); made by commit */
    PrimInfo *sphere_info; /* num_spheres entries */
    /* Analytic shapes (geometry/shape.h): primitive ids after the spheres'. */
    AnalyticShape *shapes; int num_shapes; size_t cap_shapes;
    PrimInfo *shape_info;  /* num_shapes entries */
    /* appearance */
    Texture *textures; int num_textures; size_t cap_textures; /* referenced by index */
    bool needs_uv; /* hits need uvs without textures too (a hair material: its offset h) */
    Material *materials; int num_materials; size_t cap_materials;
    SampledSpectrum *spectra; int num_spectra; size_t cap_spectra; /* Material.*_spectrum */
    /* Per area emitter (emitter_sampler order), 1 + the index of its emitted spectrum or 0;
     * NULL when none has one; entries past num_emitter_spectrum are 0. */
    int *emitter_spectrum; int num_emitter_spectrum; size_t cap_emitter_spectrum;
    /* measured materials' tables, one per file, each allocated apart (materials point at them) */
    struct MeasuredBsdf **measured; int num_measured; size_t cap_measured;
    /* subsurface materials' BSSRDF profile tables, one per (g, eta), each allocated apart
     * (materials point at them); num_subsurface counts the subsurface materials, which
     * send path_li to path_sss_li (integrators/path_sss.c) */
    struct BssrdfTable **bssrdf_tables; int num_bssrdf_tables; size_t cap_bssrdf_tables;
    int num_subsurface;
    Emitter *emitters; int num_emitters; size_t cap_emitters;
    /* Alpha cut-outs, referred to by PrimInfo.alpha; num_alphas == 0 (every scene without
     * one) keeps the ray queries on their opaque path behind a single branch. */
    AlphaMask *alphas; int num_alphas; size_t cap_alphas;
    DeltaLight *delta_lights; int num_delta_lights; size_t cap_delta_lights; /* point, spot, directional */
    /* Per delta light, 1 + the index of its emitted spectrum or 0 (CstLightDesc.spectrum);
     * NULL when none has one; entries past num_delta_spectrum are 0. */
    int *delta_spectrum; int num_delta_spectrum; size_t cap_delta_spectrum;
    /* Participating media (media/medium.h) and the interfaces shapes carry (PrimInfo.medium);
     * num_media == 0 (every scene without media) keeps the path tracer on its surface-only
     * loop behind a single branch. cur_medium_iface: 1 + the interface given to shapes added
     * from now on (scene_set_medium_interface), 0 none. camera_medium: -1 vacuum. */
    Medium *media; int num_media; size_t cap_media;
    MediumInterface *medium_ifaces; int num_medium_ifaces; size_t cap_medium_ifaces;
    int cur_medium_iface;
    int camera_medium;
    EnvMap *env; /* the environment, or NULL */
    /* Spectral mode: 1 + the index of the spectrum giving the environment's radiance its
     * shape (at the luminance of its RGB), 0: the RGB upsampled (cst_scene_set_environment_spectrum) */
    int env_spectrum;
    /* after commit */
    AccelType accel_type; /* what scene_commit builds; ACCEL_BVH unless set */
    Accel accel;
    /* Instanced objects (pbrt ObjectInstance), NULL when there are none: a second,
     * two-level structure queried after `accel`. Instances do not emit. */
    InstanceSet *instances;
    /* While cst_scene_add_object_shape runs: 1 + the instanced object scene_add_shape and
     * scene_add_patch put their shape into (instead of the scene's arrays), 0 otherwise. */
    int shape_object;
    EmitterSampler emitter_sampler;
    int light_select; /* NEE's light sampler: 1 + LightSelect, 0 = by the rule (light.h) */
    int light_solid_angle; /* NEE samples triangles by solid angle (EmitterSampler.solid_angle) */
    int has_env_portal;    /* env_portal holds a portal's corners (applied by commit) */
    Vec3 env_portal[4];
    /* Spectral mode's lookups done once by commit (math/spectrum.h): per material, its
     * colours; per area emitter, its radiance (NULL before commit or on OOM: converted at
     * each use instead). */
    MaterialSpectra *material_spectra;
    SpectrumRgb *emitter_spectra;
    /* ray_offset_origin's offset near the origin: RAY_OFFSET_NEAR_MIN, or 4e-7 of the
     * scene's largest coordinate if that is more, so that a ray leaving a surface that
     * lies in a coordinate plane (a floor at y = 0) starts outside that surface's own
     * BVH box, which is widened by 1e-7 of that coordinate (bvh.c), instead of testing
     * the surface again on every bounce and shadow ray. Set by scene_commit. */
    float offset_near;
    /* Texture footprints at hits (scene/footprint.h), enabled by scene_commit when a texture
     * has a MIP filter; for the scene file's camera, resolution and samples per pixel. */
    Footprint footprint;
    int committed;
    /* view and settings */
    CameraDesc camera;
    int camera_set;
    int camera_mirror; /* render with camera_mirror_x (pbrt's left-handed LookAt) */
    /* Motion blur of the view (cst_scene_set_camera_motion, cst_scene_set_shutter): when
     * camera_placed, the camera above is in its own space, placed in the world by
     * camera_motion over [0, 1] (moving or not); the shutter interval of ray times ([0, 1]
     * from scene_create). */
    bool camera_placed;
    MotionTransform camera_motion;
    float shutter[2];
    CstRenderSettings settings; /* what the scene file asked for; unset (scene_create) = default */
    char *output_path;
};

/* Returns NULL on OOM. */
Scene *scene_create(void);
void scene_destroy(Scene *scene);

/* Takes ownership of t's image buffer, also on failure. A checkerboard's two textures
 * must already be in the scene. */
CstStatus scene_add_texture(Scene *scene, const Texture *t, int *out_id, CstError *err);
/* The material's textures must already be in the scene. */
CstStatus scene_add_material(Scene *scene, const Material *m, int *out_id, CstError *err);
/* Adds a copy of *sp; *out_id is its index (Material.*_spectrum = index + 1). */
CstStatus scene_add_spectrum(Scene *scene, const SampledSpectrum *sp, int *out_id, CstError *err);
/* Emitters first..num_emitters-1 (just added) emit spectrum (1 + index, 0 none) in spectral mode. */
CstStatus scene_set_emitter_spectrum(Scene *scene, int first, int spectrum, CstError *err);
/* The delta light just added emits spectrum (1 + index, 0 none) in spectral mode. */
CstStatus scene_set_delta_spectrum(Scene *scene, int spectrum, CstError *err);
/* Indices are 3 per triangle into positions; all must be in range and the triangles
 * non-degenerate (callers that know file locations check first for better messages).
 * emission may be NULL. */
CstStatus scene_add_mesh(Scene *scene, const Vec3 *positions, int num_vertices,
                         const int *indices, int num_triangles, int material,
                         const Emission *emission, CstError *err);
/* A triangle mesh for scene_add_mesh_ex: zero-initialise, then fill. */
typedef struct SceneMesh {
    const Vec3 *positions;
    int num_vertices;
    const Vec3 *normals; /* per vertex, unit (zero = none), or NULL */
    const Vec2 *uvs;     /* per vertex, or NULL */
    int normals_partial, uvs_partial; /* the arrays already hold zero fills */
    const int *indices;  /* 3 per triangle, into positions */
    int num_triangles;
    int material;            /* scene material id of every triangle, */
    const int *tri_material; /* unless this per-triangle array of ids is given */
    const Emission *emission; /* or NULL */
    int alpha;           /* 1 + index into Scene.alphas (scene_add_alpha), or 0: opaque, */
    const int *tri_alpha; /* unless this per-triangle array of such ids is given */
    int skip_degenerate; /* drop zero-area triangles instead of failing (mesh files) */
} SceneMesh;
/* scene_add_mesh with vertex attributes, per-triangle materials and optional skipping of
 * degenerate triangles; *num_dropped (may be NULL) gets how many were skipped. */
CstStatus scene_add_mesh_ex(Scene *scene, const SceneMesh *mesh, int *num_dropped, CstError *err);
/* Planar quad v0..v3 as triangles (v0,v1,v2), (v0,v2,v3); normal = (v1-v0) x (v2-v0);
 * texture coordinates (0,0), (1,0), (1,1), (0,1) at v0..v3. */
CstStatus scene_add_quad(Scene *scene, const Vec3 v[4], int material,
                         const Emission *emission, CstError *err);
/* An analytic shape (shape_init's parameters and transform); emission NULL or black for
 * none. An emitting one is an area light sampled uniformly by area and needs a similarity
 * transform (shape_uniform_area; CST_ERR_UNSUPPORTED otherwise). */
CstStatus scene_add_shape(Scene *scene, const ShapeParams *p, const Transform *object_to_world, int material,
                          const Emission *emission, int alpha, CstError *err);
/* A bilinear patch built by shape_init_bilinear (copied; it does not emit). */
CstStatus scene_add_patch(Scene *scene, const AnalyticShape *patch, int material, int alpha, CstError *err);
CstStatus scene_add_sphere(Scene *scene, Vec3 center, float radius, int material,
                           const Emission *emission, CstError *err);
/* An alpha cut-out for shapes added after it (SceneMesh.alpha, the last sphere's
 * sphere_info[].alpha): *out_id = 1 + its index. value in [0, 1]; texture 1 + a texture
 * index already in the scene, or 0. */
CstStatus scene_add_alpha(Scene *scene, float value, int texture, int *out_id, CstError *err);
/* A medium (its coefficients checked: finite, >= 0; |g| < 1); *out_id its index. */
CstStatus scene_add_medium(Scene *scene, const Medium *m, int *out_id, CstError *err);
/* The medium interface of shapes added from now on: inside and outside media indices
 * (-1 vacuum), boundary as MediumInterface.boundary. inside == outside and no boundary
 * means none (no transition). */
CstStatus scene_set_medium_interface(Scene *scene, int inside, int outside, int boundary, CstError *err);
/* The medium the camera sits in (-1 vacuum). */
CstStatus scene_set_camera_medium(Scene *scene, int medium, CstError *err);
/* Sets the environment (replacing one set before); the scene takes ownership of *env's
 * buffers (the struct is copied). */
CstStatus scene_set_environment(Scene *scene, const EnvMap *env, CstError *err);
/* A point, spot or directional light (unit dir; spot cosines with cos_outer < cos_inner). */
CstStatus scene_add_delta_light(Scene *scene, const DeltaLight *light, CstError *err);
void scene_set_camera(Scene *scene, const CameraDesc *camera);
CstStatus scene_set_output_path(Scene *scene, const char *path, CstError *err);
/* An object to instance: triangles in object space with a scene material id each, and
 * optional unit vertex normals for smooth shading (NULL, or zero for a vertex without). */
CstStatus scene_add_instance_proto(Scene *scene, const Vec3 *positions, const Vec3 *normals,
                                   int num_vertices, const int *indices, const int *tri_material,
                                   int num_triangles, int *out_id, CstError *err);
CstStatus scene_add_instance(Scene *scene, int proto, const Transform *world_from_obj,
                             CstError *err);
/* A moving instance: world_from_obj at shutter open (start) and close (end). */
CstStatus scene_add_instance_moving(Scene *scene, int proto, const Transform *start, const Transform *end,
                                    CstError *err);
CstStatus scene_commit(Scene *scene, CstError *err);
/* Rebuilds a committed scene's acceleration structure as `type`. */
CstStatus scene_set_accel(Scene *scene, AccelType type, CstError *err);
static inline AccelGeometry scene_accel_geometry(const Scene *s)
{
    AccelGeometry g = {s->positions, s->tri_indices, s->num_triangles, s->spheres, s->num_spheres, s->shapes, s->num_shapes};
    return g;
}

static inline const PrimInfo *scene_prim_info(const Scene *s, uint32_t prim)
{
    if ((int)prim < s->num_triangles) return &s->tri_info[prim];
    if ((int)prim < s->num_triangles + s->num_spheres) return &s->sphere_info[(int)prim - s->num_triangles];
    return &s->shape_info[(int)prim - s->num_triangles - s->num_spheres];
}

/* A surface point found by a closest-hit query. */
typedef struct SurfaceHit {
    Vec3 p;        /* position */
    Vec3 ng;       /* unit geometric normal: (v1-v0) x (v2-v0) for triangles, outward for spheres */
    /* Unit shading normal on ng's side (ns.ng >= 0): the vertex normals interpolated when
     * the triangle's three vertices have them, else ng (spheres, instances, flat meshes). */
    Vec3 ns;
    float t;
    uint32_t prim;
    int32_t material, emitter;
    /* Texture coordinates at p (triangle_uv(), sphere_uv()); computed only in scenes with
     * textures, the only readers, and (0, 0) elsewhere. */
    Vec2 uv;
    /* The time of the ray that found the hit (Ray.time): rays leaving the hit carry it on,
     * so a path sees one instant of a moving scene. */
    float time;
    /* A hit inside an instance (prim == UINT32_MAX) only, unset otherwise: the instance and
     * the prototype's triangle (what the alpha cut-out test looks up). */
    int32_t inst;
    uint32_t inst_prim;
} SurfaceHit;

/* The shading normal at barycentrics (u, v) of triangle t (3 indices into normals):
 * Phong's interpolation of the vertex normals (Phong 1975), renormalised and turned to
 * ng's side. ng is kept as it is, unlike pbrt-v4, which turns ng toward the shading
 * normal: here ng alone says what is inside a dielectric and which way an emitter faces.
 * ng when a vertex has no normal (zero) or the interpolation vanishes. */
static inline Vec3 scene_shading_normal(const Vec3 *normals, const int32_t *t, float u, float v, Vec3 ng)
{
    Vec3 n0 = normals[t[0]], n1 = normals[t[1]], n2 = normals[t[2]];
    if (v3_length2(n0) == 0.0f || v3_length2(n1) == 0.0f || v3_length2(n2) == 0.0f) return ng;
    Vec3 n = v3_add(v3_add(v3_scale(n0, 1.0f - u - v), v3_scale(n1, u)), v3_scale(n2, v));
    float l2 = v3_length2(n);
    if (!(l2 > 0.0f) || !isfinite(l2)) return ng;
    n = v3_scale(n, 1.0f / sqrtf(l2));
    return v3_dot(n, ng) < 0.0f ? v3_neg(n) : n;
}

/* A hit in an instance, closer than any in `accel`: filled in world space. */
static inline bool scene_intersect_instances(const Scene *s, const Ray *ray, SurfaceHit *sh)
{
    InstHit ih;
    if (!instances_intersect(s->instances, ray, &ih)) return false;
    const Instance *in = &s->instances->insts[ih.inst];
    const InstProto *pr = &s->instances->protos[in->proto];
    Transform moved_wfo, moved_nm;
    const Transform *wfo = &in->world_from_obj, *nm = &in->normal_matrix;
    if (in->motion >= 0) { /* a moving instance, placed at the ray's time */
        instances_placement(s->instances, ih.inst, ray->time, &moved_wfo, &moved_nm);
        wfo = &moved_wfo;
        nm = &moved_nm;
    }
    sh->t = ih.t;
    sh->prim = UINT32_MAX; /* not a scene primitive */
    sh->inst = ih.inst;
    sh->inst_prim = ih.prim;
    if ((int)ih.prim >= pr->num_triangles) {
        /* An analytic shape: its surface in object space at the object ray's t (reprojected
         * onto the shape in double, shape_surface), carried to the world as a triangle's. */
        const int k = (int)ih.prim - pr->num_triangles;
        float scale;
        Ray ro = instances_object_ray(s->instances, ih.inst, ray, &scale);
        ShapeSurface sf;
        shape_surface(&pr->shapes[k], &ro, ih.t_obj, &sf);
        sh->p = transform_point(wfo, sf.p);
        sh->ng = transform_normal(nm, sf.n);
        Vec3 ns = transform_normal(nm, sf.ns);
        sh->ns = v3_length2(ns) > 0.0f ? (v3_dot(ns, sh->ng) < 0.0f ? v3_neg(ns) : ns) : sh->ng;
        sh->uv = sf.uv;
        sh->material = pr->shape_material[k];
        sh->emitter = -1;
        return true;
    }
    const int32_t *t = &pr->tri_indices[3 * ih.prim];
    Vec3 a = pr->positions[t[0]], b = pr->positions[t[1]], c = pr->positions[t[2]];
    Vec3 p_obj = v3_add(v3_add(v3_scale(a, 1.0f - ih.u - ih.v), v3_scale(b, ih.u)), v3_scale(c, ih.v));
    sh->p = transform_point(wfo, p_obj);
    /* The normal matrix keeps the object's outside, also under mirroring transforms. */
    sh->ng = transform_normal(nm, pr->tri_normals[ih.prim]);
    sh->ns = sh->ng;
    if (pr->normals) { /* interpolated in object space, then carried like ng */
        Vec3 ns = scene_shading_normal(pr->normals, t, ih.u, ih.v, pr->tri_normals[ih.prim]);
        ns = transform_normal(nm, ns);
        if (v3_length2(ns) > 0.0f) sh->ns = v3_dot(ns, sh->ng) < 0.0f ? v3_neg(ns) : ns;
    }
    sh->material = pr->tri_material[ih.prim];
    sh->emitter = -1;
    sh->uv = v2(ih.u, ih.v); /* the triangle default (triangle_uv's), unless the object has uvs */
    if (pr->uvs) {
        Vec2 ua = pr->uvs[t[0]], ub = pr->uvs[t[1]], uc = pr->uvs[t[2]];
        float w = 1.0f - ih.u - ih.v;
        sh->uv = v2(w * ua.x + ih.u * ub.x + ih.v * uc.x, w * ua.y + ih.u * ub.y + ih.v * uc.y);
    }
    return true;
}

/* The closest hit in (t_min, t_max), alpha cut-outs not applied: scene_intersect(). */
static inline bool scene_intersect_first(const Scene *s, const Ray *ray, SurfaceHit *sh)
{
    Hit h;
    if (s->instances) {
        bool base = accel_intersect(&s->accel, ray, &h);
        Ray r = *ray;
        if (base) r.t_max = h.t;
        if (scene_intersect_instances(s, &r, sh)) return true;
        if (!base) return false;
    } else if (!accel_intersect(&s->accel, ray, &h)) {
        return false;
    }
    sh->t = h.t;
    sh->prim = h.prim;
    if ((int)h.prim < s->num_triangles) {
        const int32_t *t = &s->tri_indices[3 * h.prim];
        Vec3 a = s->positions[t[0]], b = s->positions[t[1]], c = s->positions[t[2]];
        sh->ng = s->tri_normals[h.prim];
        /* From barycentrics, not o + t d: accurate to a few ulps of the vertices,
         * which ray_offset_origin relies on (the ray form errs by ulps of |o| + t). */
        sh->p = v3_add(v3_add(v3_scale(a, 1.0f - h.u - h.v), v3_scale(b, h.u)), v3_scale(c, h.v));
        sh->uv = (s->num_textures || s->needs_uv) ? triangle_uv(s->uvs, s->tri_has_uv, s->tri_indices, h.prim, h.u, h.v)
                                 : v2(0.0f, 0.0f);
        /* Only scenes with vertex normals pay for the interpolation. */
        sh->ns = s->normals ? scene_shading_normal(s->normals, t, h.u, h.v, sh->ng) : sh->ng;
    } else if ((int)h.prim >= s->num_triangles + s->num_spheres) {
        /* Reprojected onto the shape in double (shape_surface): off it by the rounding only. */
        ShapeSurface sf;
        shape_surface(&s->shapes[(int)h.prim - s->num_triangles - s->num_spheres], ray, h.t, &sf);
        sh->p = sf.p;
        sh->ng = sf.n;
        sh->ns = sf.ns;
        sh->uv = sf.uv;
    } else {
        const Sphere *sp = &s->spheres[(int)h.prim - s->num_triangles];
        sh->ng = v3_normalize(v3_sub(ray_at(ray, h.t), sp->center));
        sh->p = v3_madd(sp->center, sh->ng, sp->radius); /* reprojected onto the surface */
        sh->uv = (s->num_textures || s->needs_uv) ? sphere_uv(sh->ng) : v2(0.0f, 0.0f);
        sh->ns = sh->ng;
    }
    const PrimInfo *pi = scene_prim_info(s, h.prim);
    sh->material = pi->material;
    sh->emitter = pi->emitter;
    return true;
}

/* scene_intersect's and scene_occluded's continuation in scenes with alpha cut-outs
 * (scene.c): hits on cut-away surface skipped, the ray continued beyond them. */
bool scene_intersect_alpha(const Scene *s, const Ray *ray, SurfaceHit *sh);
bool scene_occluded_alpha(const Scene *s, const Ray *ray);

/* The closest hit in (t_min, t_max) of a surface that exists there: every ray query of
 * every integrator goes through it and scene_occluded(), so alpha cut-outs hold for
 * camera, shadow and light paths and every accel back end alike. A scene without cut-outs
 * pays one branch. */
static inline bool scene_intersect(const Scene *s, const Ray *ray, SurfaceHit *sh)
{
    sh->time = ray->time;
    if (s->num_alphas) return scene_intersect_alpha(s, ray, sh);
    return scene_intersect_first(s, ray, sh);
}

/* Whether any geometry moves over the shutter (a moving instance): the light a point
 * receives then depends on the time (photon.c's time window). */
static inline bool scene_geometry_moves(const Scene *s)
{
    return s->instances && s->instances->num_motions > 0;
}

/* Whether anything in the scene (a moving instance, or the camera) moves over the shutter
 * interval: only then do camera paths draw a time (integrator.c), so static scenes keep their
 * random-number streams. */
static inline bool scene_has_motion(const Scene *s)
{
    return scene_geometry_moves(s) || (s->camera_placed && s->camera_motion.moving);
}

/* dp/du and dp/dv of the triangle p0 p1 p2 with texture coordinates uv0 uv1 uv2 (pbrt-v4
 * Triangle::InteractionFromIntersection); false when the uvs are degenerate. */
static inline bool scene_triangle_dpduv(Vec3 p0, Vec3 p1, Vec3 p2, Vec2 uv0, Vec2 uv1, Vec2 uv2, Vec3 *dpdu,
                                        Vec3 *dpdv)
{
    Vec2 d02 = v2(uv0.x - uv2.x, uv0.y - uv2.y), d12 = v2(uv1.x - uv2.x, uv1.y - uv2.y);
    Vec3 dp02 = v3_sub(p0, p2), dp12 = v3_sub(p1, p2);
    float det = d02.x * d12.y - d02.y * d12.x;
    if (!(fabsf(det) > 1e-9f)) return false; /* degenerate uvs: no footprint */
    float inv = 1.0f / det;
    *dpdu = v3_scale(v3_sub(v3_scale(dp02, d12.y), v3_scale(dp12, d02.y)), inv);
    *dpdv = v3_scale(v3_sub(v3_scale(dp12, d02.x), v3_scale(dp02, d12.x)), inv);
    return true;
}

/* The partial derivatives of the surface position with respect to the texture coordinates
 * at a hit (pbrt-v4 Triangle::InteractionFromIntersection, Sphere); inside an instance,
 * the prototype triangle's, in object space, carried to the world by the instance's
 * transform (dp/du is a tangent vector), so textures on instances are filtered as on
 * shapes placed directly. */
static inline bool scene_dpduv(const Scene *s, const SurfaceHit *sh, Vec3 *dpdu, Vec3 *dpdv)
{
    Vec2 uv0 = v2(0.0f, 0.0f), uv1 = v2(1.0f, 0.0f), uv2 = v2(0.0f, 1.0f); /* triangle_uv's default */
    if (sh->prim == UINT32_MAX) {
        const Instance *in = &s->instances->insts[sh->inst];
        const InstProto *pr = &s->instances->protos[in->proto];
        Vec3 du, dv;
        if ((int)sh->inst_prim >= pr->num_triangles) { /* a shape: pbrt-v4's dp/du, dp/dv at the hit's uv */
            ShapeSurface sf;
            shape_surface_at(&pr->shapes[(int)sh->inst_prim - pr->num_triangles], sh->uv, &sf);
            if (!(v3_length2(sf.dpdu) > 0.0f && v3_length2(sf.dpdv) > 0.0f)) return false;
            du = sf.dpdu;
            dv = sf.dpdv;
        } else {
            const int32_t *t = &pr->tri_indices[3 * sh->inst_prim];
            if (pr->uvs) uv0 = pr->uvs[t[0]], uv1 = pr->uvs[t[1]], uv2 = pr->uvs[t[2]];
            if (!scene_triangle_dpduv(pr->positions[t[0]], pr->positions[t[1]], pr->positions[t[2]], uv0, uv1, uv2,
                                      &du, &dv))
                return false;
        }
        Transform moved_wfo, moved_nm;
        const Transform *wfo = &in->world_from_obj;
        if (in->motion >= 0) { /* placed at the hit's time, as the hit itself */
            instances_placement(s->instances, sh->inst, sh->time, &moved_wfo, &moved_nm);
            wfo = &moved_wfo;
        }
        *dpdu = transform_vector(wfo, du);
        *dpdv = transform_vector(wfo, dv);
        return true;
    }
    if ((int)sh->prim < s->num_triangles) {
        const int32_t *t = &s->tri_indices[3 * sh->prim];
        if (s->tri_has_uv && s->tri_has_uv[sh->prim]) uv0 = s->uvs[t[0]], uv1 = s->uvs[t[1]], uv2 = s->uvs[t[2]];
        return scene_triangle_dpduv(s->positions[t[0]], s->positions[t[1]], s->positions[t[2]], uv0, uv1, uv2, dpdu,
                                    dpdv);
    }
    if ((int)sh->prim >= s->num_triangles + s->num_spheres) { /* pbrt-v4's dp/du, dp/dv at the hit's uv */
        ShapeSurface sf;
        shape_surface_at(&s->shapes[(int)sh->prim - s->num_triangles - s->num_spheres], sh->uv, &sf);
        *dpdu = sf.dpdu;
        *dpdv = sf.dpdv;
        return v3_length2(sf.dpdu) > 0.0f && v3_length2(sf.dpdv) > 0.0f;
    }
    /* sphere_uv: u = phi / 2pi, phi = atan2(d.x, d.z); v = theta / pi, theta = acos(-d.y). */
    const Sphere *sp = &s->spheres[(int)sh->prim - s->num_triangles];
    Vec3 d = sh->ng;
    float sin_t = sqrtf(d.x * d.x + d.z * d.z);
    if (!(sin_t > 1e-6f)) return false; /* the poles */
    *dpdu = v3_scale(v3(d.z, 0.0f, -d.x), 2.0f * CST_PI * sp->radius);
    *dpdv = v3_scale(v3(-d.y * d.x / sin_t, sin_t, -d.y * d.z / sin_t), CST_PI * sp->radius);
    return true;
}

/* A conductor's k for normal-incidence reflectance R (pbrt-v4 ConductorMaterial with
 * "reflectance": eta = 1, k = 2 sqrt(R) / sqrt(1 - R), R clamped to [0, 0.9999], whose
 * Fresnel reflectance k^2 / (4 + k^2) at normal incidence is R), per channel or lane. */
static inline Color scene_conductor_k_of_reflectance(Color r)
{
    Color k;
    for (int i = 0; i < COLOR_LANES; i++) {
        float c = clampf(r.c[i], 0.0f, 0.9999f);
        k.c[i] = 2.0f * sqrtf(c) / sqrtf(1.0f - c);
    }
    return k;
}

/* The texture context at a hit: with a footprint when the scene's textures filter with one. */
static inline TexCtx scene_tex_ctx(const Scene *s, const SurfaceHit *sh)
{
    TexCtx c = {.uv = sh->uv, .p = sh->p, .n = sh->ng};
    Vec3 dpdu, dpdv;
    if (s->footprint.enabled && scene_dpduv(s, sh, &dpdu, &dpdv))
        c = footprint_tex_ctx(&s->footprint, sh->p, sh->ng, sh->uv, dpdu, dpdv);
    return c;
}

/* A material's textures evaluated at the hit, over what bsdf_init took from the material's
 * constants; with a footprint when the scene's textures filter with one. */
static inline void scene_bsdf_textures(const Scene *s, const Material *m, const SurfaceHit *sh, Bsdf *b)
{
    TexCtx c = scene_tex_ctx(s, sh);
    if (m->albedo_texture) bsdf_set_albedo(b, texture_eval_ctx(s->textures, m->albedo_texture - 1, &c));
    if (m->roughness_v_texture) { /* anisotropic: a texture per width (pbrt-v4 uroughness, vroughness) */
        float ax, ay;
        material_bsdf_alpha2(clampf(texture_eval_scalar_ctx(s->textures, m->roughness_texture - 1, &c), 0.0f, 1.0f),
                             clampf(texture_eval_scalar_ctx(s->textures, m->roughness_v_texture - 1, &c), 0.0f, 1.0f),
                             &ax, &ay);
        bsdf_set_alpha2(b, ax, ay);
    } else if (m->roughness_texture) {
        bsdf_set_alpha(b, material_bsdf_alpha(clampf(texture_eval_scalar_ctx(s->textures, m->roughness_texture - 1, &c), 0.0f, 1.0f)));
    }
    if (m->reflectance_texture) { /* RGB mode's; spectral mode redoes k per wavelength */
        Color r = texture_eval_ctx(s->textures, m->reflectance_texture - 1, &c);
        bsdf_set_conductor_ior(b, color_s(1.0f), scene_conductor_k_of_reflectance(r));
    } else if (m->eta_texture | m->k_texture) {
        Color eta = m->eta_texture ? texture_eval_ctx(s->textures, m->eta_texture - 1, &c) : m->eta;
        Color k = m->k_texture ? texture_eval_ctx(s->textures, m->k_texture - 1, &c) : m->k;
        bsdf_set_conductor_ior(b, eta, k);
    }
}

/* The shading normal bent by the material's displacement (pbrt-v4 BumpMap: forward
 * differences of the displacement d over du, dv of half the footprint, or 0.0005, moving
 * dp/du by (d(u + du) - d(u)) / du n + d dn/du; PBR 4th ed. eq. 10.12) or normal map
 * (pbrt-v4 NormalMap: 2 rgb - 1 in the frame of dp/du and the shading normal), as
 * normalize(dp/du' x dp/dv') turned to the shading normal's side. dn/du is that of
 * spheres and analytic shapes (shape_dnduv); triangles' vertex-normal derivatives are
 * left out. The unbent normal where
 * the hit has no dp/du (instances) or the result is degenerate. */
static inline Vec3 scene_bump(const Scene *s, const Material *m, const SurfaceHit *sh)
{
    Vec3 dpdu, dpdv, n = sh->ns;
    if (!scene_dpduv(s, sh, &dpdu, &dpdv)) return n;
    TexCtx c = {.uv = sh->uv, .p = sh->p, .n = sh->ng};
    if (s->footprint.enabled) c = footprint_tex_ctx(&s->footprint, sh->p, sh->ng, sh->uv, dpdu, dpdv);
    Vec3 du_dir = dpdu, dv_dir = dpdv;
    if (m->displacement_texture) {
        int id = m->displacement_texture - 1;
        float du = 0.5f * (fabsf(c.dudx) + fabsf(c.dudy)), dv = 0.5f * (fabsf(c.dvdx) + fabsf(c.dvdy));
        if (!(du > 0.0f)) du = 0.0005f;
        if (!(dv > 0.0f)) dv = 0.0005f;
        TexCtx cu = c, cv = c;
        cu.p = v3_madd(c.p, dpdu, du), cu.uv = v2(c.uv.x + du, c.uv.y);
        cv.p = v3_madd(c.p, dpdv, dv), cv.uv = v2(c.uv.x, c.uv.y + dv);
        float d0 = texture_eval_scalar_ctx(s->textures, id, &c);
        float d_u = texture_eval_scalar_ctx(s->textures, id, &cu), d_v = texture_eval_scalar_ctx(s->textures, id, &cv);
        du_dir = v3_madd(dpdu, n, (d_u - d0) / du);
        dv_dir = v3_madd(dpdv, n, (d_v - d0) / dv);
        if ((int)sh->prim >= s->num_triangles && (int)sh->prim < s->num_triangles + s->num_spheres) {
            /* a sphere: dn/du = dp/du / r */
            float r = s->spheres[(int)sh->prim - s->num_triangles].radius;
            du_dir = v3_madd(du_dir, dpdu, d0 / r);
            dv_dir = v3_madd(dv_dir, dpdv, d0 / r);
        } else if ((int)sh->prim >= s->num_triangles + s->num_spheres) {
            /* analytic shapes: pbrt-v4's dn/du, dn/dv (quadrics and the torus; zero for
             * the others, as for triangles) */
            Vec3 dndu, dndv;
            shape_dnduv(&s->shapes[(int)sh->prim - s->num_triangles - s->num_spheres], sh->uv, &dndu, &dndv);
            du_dir = v3_madd(du_dir, dndu, d0);
            dv_dir = v3_madd(dv_dir, dndv, d0);
        }
    } else {
        TexCtx cn = {.uv = sh->uv, .p = sh->p, .n = sh->ng};
        Color rgb = texture_eval_ctx(s->textures, m->normal_map_texture - 1, &cn);
        Vec3 t = v3(2.0f * rgb.c[0] - 1.0f, 2.0f * rgb.c[1] - 1.0f, 2.0f * rgb.c[2] - 1.0f);
        float tl = v3_length(t);
        Vec3 x = v3_sub(dpdu, v3_scale(n, v3_dot(n, dpdu)));
        float xl = v3_length(x);
        if (!(tl > 0.0f) || !(xl > 0.0f)) return n;
        x = v3_scale(x, 1.0f / xl);
        Vec3 y = v3_cross(n, x);
        Vec3 nm = v3_scale(v3_add(v3_add(v3_scale(x, t.x), v3_scale(y, t.y)), v3_scale(n, t.z)), 1.0f / tl);
        float ulen = v3_length(dpdu), vlen = v3_length(dpdv);
        Vec3 gu = v3_sub(dpdu, v3_scale(nm, v3_dot(nm, dpdu)));
        float gl = v3_length(gu);
        if (!(gl > 0.0f)) return n;
        du_dir = v3_scale(gu, ulen / gl);
        dv_dir = v3_scale(v3_normalize(v3_cross(nm, du_dir)), vlen);
    }
    Vec3 nb = v3_cross(du_dir, dv_dir);
    float l2 = v3_length2(nb);
    if (!(l2 > 0.0f) || !isfinite(l2)) return n;
    nb = v3_scale(nb, 1.0f / sqrtf(l2));
    return v3_dot(nb, n) < 0.0f ? v3_neg(nb) : nb;
}

/* A 64-bit hash of a hit (its position's bits and its primitive): the stochastic choices
 * made per hit (a mix's material, a coated material's random numbers) are functions of it,
 * so every query at the same hit sees the same surface. */
static inline uint64_t scene_hit_hash(const SurfaceHit *sh)
{
    union { float f[3]; uint32_t u[3]; } b = {{sh->p.x, sh->p.y, sh->p.z}};
    uint64_t h = mix64(((uint64_t)b.u[0] << 32 | b.u[1]) + 0x9e3779b97f4a7c15ULL);
    return mix64(h ^ ((uint64_t)b.u[2] << 32 | sh->prim));
}

/* A mix material's choice at a hit (pbrt-v4 MixMaterial::ChooseMaterial): the second
 * material with probability amount, from a hash of the hit (pbrt-v4 hashes the point, wo
 * and the two materials; the hit alone suffices here, since every path reaching it
 * builds its BSDF through this function). Mixes of mixes choose again with another hash. */
static inline const Material *scene_mix_choose(const Scene *s, const Material *m, const SurfaceHit *sh)
{
    uint64_t h = scene_hit_hash(sh);
    while (m->type == MATERIAL_MIX) {
        /* with p and n: solid textures and non-uv mappings (texture_map_st) need them */
        TexCtx c = {.uv = sh->uv, .p = sh->p, .n = sh->ng};
        float amt = m->amount_texture ? texture_eval_scalar_ctx(s->textures, m->amount_texture - 1, &c) : m->amount;
        h = mix64(h + 0xd1b54a32d192ed03ULL);
        float u = (float)(h >> 40) * 0x1p-24f;
        m = &s->materials[m->mix[u < amt ? 1 : 0]];
    }
    return m;
}

/* Spectral mode: a material's spectra at wl over the values upsampled from its RGB-mode
 * reductions: a conductor's eta and k (a coated conductor's divided by the interface's
 * eta, as layered_init does), and with disperse the ior of a dispersive dielectric at the
 * hero wavelength wl->lambda[0] (pbrt-v4 DielectricMaterial: eta(lambda[0]), the other
 * wavelengths then terminated by the caller). */
static inline void scene_bsdf_spectra(const Scene *s, const Material *m, const Wavelengths *wl, bool disperse,
                                      Bsdf *b)
{
    if (disperse && m->ior_dispersive) {
        float eta = sampled_spectrum_at(&s->spectra[m->ior_spectrum - 1], wl->lambda[0]);
        if (material_is_layered(m->type)) {
            float old = b->lobe.layered.top_eta;
            b->lobe.layered.top_eta = eta;
            if (m->type == MATERIAL_COATED_CONDUCTOR && !(m->eta_spectrum | m->k_spectrum)) {
                b->lobe.layered.eta = color_scale(b->lobe.layered.eta, old / eta);
                b->lobe.layered.k = color_scale(b->lobe.layered.k, old / eta);
            }
        } else {
            b->lobe.dielectric.eta = eta;
        }
    }
    if (m->type == MATERIAL_CONDUCTOR) {
        if (m->eta_spectrum) b->lobe.conductor.eta = sampled_spectrum_eval(&s->spectra[m->eta_spectrum - 1], wl);
        if (m->k_spectrum) b->lobe.conductor.k = sampled_spectrum_eval(&s->spectra[m->k_spectrum - 1], wl);
    } else if (m->type == MATERIAL_COATED_CONDUCTOR) {
        float inv = 1.0f / b->lobe.layered.top_eta;
        if (m->eta_spectrum)
            b->lobe.layered.eta = color_scale(sampled_spectrum_eval(&s->spectra[m->eta_spectrum - 1], wl), inv);
        if (m->k_spectrum)
            b->lobe.layered.k = color_scale(sampled_spectrum_eval(&s->spectra[m->k_spectrum - 1], wl), inv);
    }
}

/* The BSDF at a hit: the one place where a hit's material, normals and texture
 * coordinates become a Bsdf, so every integrator sees the same surface. Spectral mode
 * (wl: the path's wavelengths; NULL in RGB mode): built in RGB, then its colours taken
 * at wl (bsdf_at_wavelengths) and its spectra applied (scene_bsdf_spectra). Returns the
 * material the BSDF was made from (a mix resolved). */
static inline const Material *scene_bsdf_material(const Scene *s, const SurfaceHit *sh, const Wavelengths *wl,
                                                  bool disperse, Bsdf *b)
{
    const Material *m = &s->materials[sh->material];
    if (m->type == MATERIAL_MIX) m = scene_mix_choose(s, m, sh);
    if (m->displacement_texture | m->normal_map_texture) {
        bsdf_init_shading(b, m, scene_bump(s, m, sh), sh->ng);
    } else {
        bsdf_init_shading(b, m, sh->ns, sh->ng);
    }
    if (m->albedo_texture | m->roughness_texture | m->eta_texture | m->k_texture | m->reflectance_texture)
        scene_bsdf_textures(s, m, sh, b);
    /* Anisotropic roughness lies along dp/du (pbrt-v4's BSDF frame); hits without one
     * (instances, degenerate uvs, a sphere's poles) keep frame_from_normal's tangent. */
    if (m->anisotropic && material_is_anisotropic(m)) {
        Vec3 dpdu, dpdv;
        if (scene_dpduv(s, sh, &dpdu, &dpdv)) bsdf_set_tangent(b, dpdu);
    }
    /* The coated materials' stochastic estimates draw their random numbers from a hash of
     * the hit (here) and of the directions (layered.c): the same query at the same hit
     * always gets the same number, different hits independent ones. */
    if (material_is_layered(m->type)) b->lobe.layered.seed = scene_hit_hash(sh);
    /* Hair: the fibre runs along dp/du (pbrt-v4's BSDF frame), and the offset across it
     * is h = -1 + 2 v (pbrt-v4's curves; other shapes take the same rule). */
    if (m->type == MATERIAL_HAIR) {
        Vec3 dpdu, dpdv;
        if (scene_dpduv(s, sh, &dpdu, &dpdv)) bsdf_set_tangent(b, dpdu);
        hair_set_offset(&b->lobe.hair, sh->uv.y);
    }
    if (wl) {
        const int mi = (int)(m - s->materials);
        if (!(m->albedo_texture | m->eta_texture | m->k_texture | m->reflectance_texture) && s->material_spectra)
            bsdf_at_wavelengths_prepared(b, &s->material_spectra[mi], wl);
        else bsdf_at_wavelengths(b, wl);
        if (m->reflectance_texture) { /* pbrt-v4: the reflectance as an albedo spectrum, k per wavelength */
            TexCtx c = scene_tex_ctx(s, sh);
            Color r = spectrum_albedo(texture_eval_ctx(s->textures, m->reflectance_texture - 1, &c), wl);
            bsdf_set_conductor_ior(b, color_s(1.0f), scene_conductor_k_of_reflectance(r));
        }
        if (m->eta_spectrum | m->k_spectrum | (disperse && m->ior_dispersive)) scene_bsdf_spectra(s, m, wl, disperse, b);
    }
    return m;
}

/* The BSDF at a hit for integrators that do not follow single wavelengths: a dispersive
 * dielectric takes its RGB-mode ior (the y-bar-weighted mean) at every wavelength. */
static inline void scene_bsdf(const Scene *s, const SurfaceHit *sh, const Wavelengths *wl, Bsdf *b)
{
    (void)scene_bsdf_material(s, sh, wl, false, b);
}

/* The BSDF at a hit for the integrators that disperse (path, light, bdpt, vcm): a dielectric whose
 * ior varies with wavelength refracts the hero wavelength wl->lambda[0] with its own ior
 * and terminates the other three (pbrt-v4 SampledWavelengths::TerminateSecondary: their
 * pdfs 0, the hero's divided by 4), at reflection and refraction alike, as pbrt-v4 does
 * when it builds such a BSDF. The path keeps wl for the rest of its vertices and its
 * film conversion. Identical to scene_bsdf in RGB mode (wl NULL). */
static inline void scene_bsdf_disperse(const Scene *s, const SurfaceHit *sh, Wavelengths *wl, Bsdf *b)
{
    const Material *m = scene_bsdf_material(s, sh, wl, wl != NULL, b);
    if (wl && m->ior_dispersive) wavelengths_terminate_secondary(wl);
}

/* Every emitted quantity (radiance, intensity, irradiance, a light path's flux) is an RGB
 * value times a scalar in the lights' module; in spectral mode this turns it into its
 * values at wl as an illuminant spectrum (math/spectrum.h), which commutes with the
 * scalar. The identity in RGB mode (wl NULL). */
static inline Color scene_light_color(Color rgb, const Wavelengths *wl)
{
    return wl ? spectrum_illuminant(rgb, wl) : rgb;
}

/* The spectrum (1 + index into spectra, 0 none) light `light` emits in spectral mode: an
 * area emitter's (CstEmission.spectrum), a delta light's (CstLightDesc.spectrum) or the
 * environment's (cst_scene_set_environment_spectrum), by the light index of light.h. */
static inline int scene_light_spectrum(const Scene *s, int light)
{
    const int n = s->emitter_sampler.count;
    if (light < 0) return 0;
    if (light < n) return s->emitter_spectrum && light < s->num_emitter_spectrum ? s->emitter_spectrum[light] : 0;
    if (light - n < s->emitter_sampler.num_delta)
        return light - n < s->num_delta_spectrum ? s->delta_spectrum[light - n] : 0;
    return light == light_env_index(&s->emitter_sampler) ? s->env_spectrum : 0;
}

/* Spectrum `spectrum` (1 + index) at wl scaled to the luminance of rgb (Y of linear sRGB):
 * pbrt-v4 divides every light's spectrum by its photometric value (SpectrumToPhotometric),
 * and the loaders' RGB of that light already carries the luminance and its scalars. */
static inline Color scene_spectrum_at_luminance(const Scene *s, int spectrum, Color rgb, const Wavelengths *wl)
{
    const SampledSpectrum *sp = &s->spectra[spectrum - 1];
    float y = cie_srgb_to_xyz[1][0] * rgb.c[0] + cie_srgb_to_xyz[1][1] * rgb.c[1] + cie_srgb_to_xyz[1][2] * rgb.c[2];
    return color_scale(sampled_spectrum_eval(sp, wl), y * sp->inv_y);
}

/* Spectral mode: light `emitter`'s value at wl if it has a spectrum of its own
 * (scene_light_spectrum): that spectrum at the luminance of rgb (its RGB value times any
 * scalar), true; false otherwise. */
static inline bool scene_emitter_spectral(const Scene *s, int emitter, Color rgb, const Wavelengths *wl, Color *out)
{
    int id = scene_light_spectrum(s, emitter);
    if (!id) return false;
    *out = scene_spectrum_at_luminance(s, id, rgb, wl);
    return true;
}

/* An emitted quantity of light `emitter` (an area emitter's index, or a delta light's
 * count + index) at wl: scene_emitter_spectral, else scene_light_color. */
static inline Color scene_emitter_color(const Scene *s, int emitter, Color rgb, const Wavelengths *wl)
{
    Color o;
    if (wl && scene_emitter_spectral(s, emitter, rgb, wl, &o)) return o;
    return scene_light_color(rgb, wl);
}

/* Radiance the hit's emitter sends toward w (unit, away from the surface); the hit must be
 * on an emitter (sh->emitter >= 0). */
static inline Color scene_emission(const Scene *s, const SurfaceHit *sh, Vec3 w, const Wavelengths *wl)
{
    const Emitter *e = &s->emitter_sampler.light[sh->emitter].u.area;
    Color le = emitter_radiance(e, s->textures, sh->ng, sh->uv, w);
    if (!wl) return le;
    Color o;
    if (scene_emitter_spectral(s, sh->emitter, le, wl, &o)) return o;
    if (!e->texture && s->emitter_spectra && !color_is_black(le))
        return spectrum_rgb_eval_illuminant(&s->emitter_spectra[sh->emitter], wl);
    return spectrum_illuminant(le, wl);
}

/* NEE's light value ls->li at wl (scene_light_color, from the emitter's prepared spectrum
 * when it is an untextured area light: li is then its radiance). */
/* Whether point p, sampled on area emitter `emitter` (an index < emitter_sampler.count),
 * lies on its shape's cut-away surface (scene.c): NEE and light-path starts then carry
 * no emission. Only called in scenes with cut-outs. */
bool scene_emitter_cut(const Scene *s, int emitter, Vec3 p);

static inline Color scene_light_li(const Scene *s, const LightLi *ls, const Wavelengths *wl)
{
    /* A light point on cut-away surface emits nothing (pbrt-v4 DiffuseAreaLight::
     * AlphaMasked): NEE samples the emitter's whole area, the cut part giving zero. */
    if (s->num_alphas && ls->light < s->emitter_sampler.count && scene_emitter_cut(s, ls->light, ls->p))
        return color_s(0.0f);
    if (!wl) return ls->li;
    Color o;
    if (scene_emitter_spectral(s, ls->light, ls->li, wl, &o)) return o;
    if (ls->light < s->emitter_sampler.count && s->emitter_spectra &&
        !s->emitter_sampler.light[ls->light].u.area.texture && !color_is_black(ls->li))
        return spectrum_rgb_eval_illuminant(&s->emitter_spectra[ls->light], wl);
    return spectrum_illuminant(ls->li, wl);
}

/* The environment's radiance arriving from direction w (black without one). */
static inline Color scene_env_radiance(const Scene *s, Vec3 w, const Wavelengths *wl)
{
    if (!s->emitter_sampler.env) return color_s(0.0f);
    Color le = light_env_radiance(&s->emitter_sampler, w);
    if (wl && s->env_spectrum) return scene_spectrum_at_luminance(s, s->env_spectrum, le, wl);
    return scene_light_color(le, wl);
}

/* What NEE and light-path starts need of the scene's geometry and textures. */
static inline EmitterGeometry scene_emitter_geometry(const Scene *s)
{
    EmitterGeometry g = {s->positions, s->tri_indices, s->num_triangles, s->spheres,
                         s->uvs, s->tri_has_uv, s->textures, s->num_spheres, s->shapes};
    return g;
}

/* Any hit in (r->t_min, r->t_max), instances included, alpha cut-outs applied. */
static inline bool scene_occluded(const Scene *s, const Ray *r)
{
    if (s->num_alphas) return scene_occluded_alpha(s, r);
    return accel_occluded(&s->accel, r) || (s->instances && instances_occluded(s->instances, r));
}

/* p moved off the surface with normal ng toward the side direction d points to. */
static inline Vec3 scene_offset(const Scene *s, Vec3 p, Vec3 ng, Vec3 d)
{
    return ray_offset_origin(p, v3_dot(ng, d) >= 0.0f ? ng : v3_neg(ng), s->offset_near);
}

/* Whether the segment between surface points p (normal n_p) and q (normal n_q) is
 * unoccluded. Both ends are pushed off their surfaces toward each other and the shadow
 * ray aims from one pushed end to the other: aiming from the pushed origin along the
 * unpushed direction would run parallel to the true segment and clip the target's own
 * surface at grazing angles (a measurable darkening of NEE near large emitters). */
static inline bool scene_visible_at(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, float time)
{
    Vec3 d = v3_sub(q, p);
    Vec3 o = scene_offset(s, p, n_p, d);
    Vec3 t = scene_offset(s, q, n_q, v3_neg(d));
    Vec3 od = v3_sub(t, o);
    float len = v3_length(od);
    if (!(len > 0.0f)) return true;
    Ray r = ray_make_at(o, v3_scale(od, 1.0f / len), 0.0f, len * (1.0f - 1e-5f), time);
    return !scene_occluded(s, &r);
}

/* scene_visible_at at time 0 (scenes without motion). */
static inline bool scene_visible(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q)
{
    return scene_visible_at(s, p, n_p, q, n_q, 0.0f);
}

/* Whether surface point p (normal ng) sees the point q in free space (a lens point: the
 * lens is not geometry, so only p's end is pushed off its surface, and the ray aims from
 * the pushed point). */
static inline bool scene_visible_point_at(const Scene *s, Vec3 p, Vec3 ng, Vec3 q, float time)
{
    Vec3 o = scene_offset(s, p, ng, v3_sub(q, p));
    Vec3 d = v3_sub(q, o);
    float len = v3_length(d);
    if (!(len > 0.0f)) return true;
    Ray r = ray_make_at(o, v3_scale(d, 1.0f / len), 0.0f, len, time);
    return !scene_occluded(s, &r);
}

/* scene_visible_point_at at time 0 (scenes without motion). */
static inline bool scene_visible_point(const Scene *s, Vec3 p, Vec3 ng, Vec3 q)
{
    return scene_visible_point_at(s, p, ng, q, 0.0f);
}

/* The medium interface of a hit's primitive, or NULL when it has none (no transition;
 * instances carry none). */
static inline const MediumInterface *scene_hit_medium_iface(const Scene *s, const SurfaceHit *sh)
{
    if (sh->prim == UINT32_MAX) return NULL;
    int m = scene_prim_info(s, sh->prim)->medium;
    return m ? &s->medium_ifaces[m - 1] : NULL;
}

/* The medium a ray enters when it leaves hit sh in direction d, coming from medium cur:
 * the interface's inside behind ng, its outside in front; cur when there is no transition. */
static inline int scene_medium_after(const Scene *s, const SurfaceHit *sh, Vec3 d, int cur)
{
    const MediumInterface *mi = scene_hit_medium_iface(s, sh);
    if (!mi) return cur;
    return v3_dot(d, sh->ng) < 0.0f ? mi->inside : mi->outside;
}

/* Scenes with media: the transmittance from p to q, p and q surface points with normals
 * n_p, n_q (pushed off as in scene_visible), or points in a medium (zero normal).
 * medium: the medium at p toward q (-1 vacuum). The shadow ray passes boundary shapes
 * (MediumInterface.boundary), changing medium at each and multiplying the transmittance
 * of every segment (Beer–Lambert per medium); any other surface between gives black.
 * wl: the path's wavelengths (NULL in RGB mode). time: the path's instant (Ray.time; moving
 * instances are placed at it). Adds the rays traced to *rays. */
Color scene_transmittance_at(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, int medium, float time,
                             const Wavelengths *wl, uint64_t *rays);

/* scene_transmittance_at at time 0 (scenes without motion). */
static inline Color scene_transmittance(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, int medium,
                                        const Wavelengths *wl, uint64_t *rays)
{
    return scene_transmittance_at(s, p, n_p, q, n_q, medium, 0.0f, wl, rays);
}

/* Defaults applied by the renderer to zero fields. */
#define CST_DEFAULT_WIDTH 512
#define CST_DEFAULT_HEIGHT 512
#define CST_DEFAULT_SPP 16
#define CST_DEFAULT_RR_DEPTH 3

#endif
