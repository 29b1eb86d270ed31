/* caustic: public C API of libcaustic, a physically based offline renderer.
 * Only opaque handles and plain option structs cross this boundary. Every function that
 * can fail returns a CstStatus and fills a CstError with a human-readable message;
 * the library never prints to stdout and never exits the process. */
#ifndef CAUSTIC_CAUSTIC_H
#define CAUSTIC_CAUSTIC_H

#include <stddef.h>
#include <stdint.h>
#include <stdio.h>

/* Marks the library's exported functions: libcaustic.so is built with hidden visibility
 * and exports these alone. */
#if defined(__GNUC__) || defined(__clang__)
#define CST_API __attribute__((visibility("default")))
#else
#define CST_API
#endif

#ifdef __cplusplus
extern "C" {
#endif

#define CST_VERSION_MAJOR 0
#define CST_VERSION_MINOR 1
#define CST_VERSION_PATCH 0
#define CST_VERSION_STRING "0.1.0"

typedef enum CstStatus {
    CST_OK = 0,
    CST_ERR_INVALID_ARG, /* a value out of range, an unknown name */
    CST_ERR_IO,          /* a file could not be opened, read or written */
    CST_ERR_PARSE,       /* malformed input text; the message names file:line:column */
    CST_ERR_UNSUPPORTED, /* a valid request this build cannot honour */
    CST_ERR_OOM,         /* allocation failed */
    CST_ERR_INTERNAL,    /* a bug or an unexpected library failure */
    CST_ERR_CANCELLED,   /* the caller asked to stop (CstProgressFn returned nonzero) */
    CST_ERR_NONFINITE    /* cst_render: more than CST_NONFINITE_LIMIT of the samples were NaN
                          * or infinite and were discarded; the film is still returned */
} CstStatus;

typedef struct CstError {
    CstStatus status;
    char msg[1024];
} CstError;

/* "CST_ERR_PARSE" etc. */
CST_API const char *cst_status_name(CstStatus status);

/* ---------------------------------------------------------------- scenes */
typedef struct CstScene CstScene;

/* The built-in Cornell box (original Cornell measured data, millimetres). */
CST_API CstStatus cst_scene_create_cornell_box(CstScene **out, CstError *err);
/* A scene in caustic's JSON format (docs/scene-format.md). Errors name path:line:column. */
CST_API CstStatus cst_scene_load_json(const char *path, CstScene **out, CstError *err);
/* The same from memory; `name` stands for the file name in messages. */
CST_API CstStatus cst_scene_load_json_string(const char *text, size_t len, const char *name,
                                     CstScene **out, CstError *err);

/* Diagnostics a loader reports without failing: something in the file that the render
 * ignores or approximates. Tests assert on the code; the message says
 * "file:line:column: directive: what was done". */
typedef enum CstWarningCode {
    CST_WARN_UNSUPPORTED = 1, /* a directive, type or feature skipped entirely */
    CST_WARN_APPROXIMATED,    /* mapped to the nearest thing caustic has (docs/pbrt-compat.md) */
    CST_WARN_PARAMETER_IGNORED, /* a parameter the mapping does not use */
    CST_WARN_GEOMETRY,        /* degenerate triangles dropped, unclosed blocks and the like */
    CST_WARN_MISSING_FILE     /* a file another file names is missing (an OBJ's .mtl):
                               * loaded with defaults instead */
} CstWarningCode;
typedef void (*CstWarningFn)(void *user, CstWarningCode code, const char *message);

/* Zero-initialise, then set what you want. */
typedef struct CstLoadOptions {
    CstWarningFn warning;   /* called once per warning, in file order; NULL drops them */
    void *warning_user;
    int no_file_access;     /* 1: Include, Import, plymesh and image textures fail instead
                             * of opening files (untrusted text, fuzzing) */
    size_t max_primitives;  /* 0: no limit. Else the pbrt loader fails, at the directive
                             * that passes it, once the scene holds more primitives
                             * (CstSceneInfo's triangles + spheres + shapes + instances;
                             * curve segments are shapes): a bound on the work untrusted text can ask for */
} CstLoadOptions;

/* A scene in pbrt-v4 format (pbrt-v3 syntax where it is the same); what is supported,
 * approximated or not is in docs/pbrt-compat.md. Relative file names (Include, plymesh,
 * imagemap) are resolved against the directory of `path`, as pbrt does. Errors name
 * file:line:column. options may be NULL. */
CST_API CstStatus cst_scene_load_pbrt(const char *path, const CstLoadOptions *options, CstScene **out,
                              CstError *err);
/* The same from memory; `name` stands for the file name in messages and its directory
 * for relative file names. */
CST_API CstStatus cst_scene_load_pbrt_string(const char *text, size_t len, const char *name,
                                     const CstLoadOptions *options, CstScene **out,
                                     CstError *err);
/* cst_scene_load_json with load options: the warning callback (a mesh file's missing
 * .mtl, ...); no_file_access is not honoured by the JSON loader. options may be NULL. */
CST_API CstStatus cst_scene_load_json_opt(const char *path, const CstLoadOptions *options,
                                          CstScene **out, CstError *err);
/* Accepts NULL. */
CST_API void cst_scene_destroy(CstScene *scene);
/* The output path named in the scene file, or NULL. Owned by the scene. */
CST_API const char *cst_scene_output_path(const CstScene *scene);

/* Rebuilds the scene's acceleration structure: "bvh" (default), "kdtree", "grid", "list"
 * (brute force) or "embree" (only in builds with Embree). On failure the old one stays.
 * Before cst_scene_commit: chooses the one commit builds. */
CST_API CstStatus cst_scene_set_accel(CstScene *scene, const char *name, CstError *err);

/* How next-event estimation picks a light (pbrt-v4's Integrator "lightsampler"): "power"
 * (by each light's power), "bvh" (a light BVH over the lights' bounds, power and
 * orientation: Conty Estevez & Kulla 2018, pbrt-v4's default) or "uniform". Scenes that name
 * none use the BVH when they have more than 64 lights with a position, power otherwise.
 * Light paths always start by power. Before cst_scene_commit: chooses what commit builds;
 * after: rebuilds it (not during a render). On failure the choice stays. */
CST_API CstStatus cst_scene_set_light_sampler(CstScene *scene, const char *name, CstError *err);

/* How next-event estimation samples a point on an emitting triangle: "area" (uniform by
 * area, the default) or "solid_angle" (uniform over the solid angle it subtends, Arvo
 * 1995, where that is between 3e-4 and 6.22 sr, by area otherwise: pbrt-v4's
 * Triangle::Sample; less noise from large, close lights). pbrt scenes use "solid_angle".
 * Before or after cst_scene_commit (not during a render). */
CST_API CstStatus cst_scene_set_light_sampling(CstScene *scene, const char *name, CstError *err);

typedef struct CstSceneInfo {
    int triangles, spheres, emitters, materials;
    const char *accel;          /* name of the acceleration structure in use */
    double accel_build_seconds; /* its last build */
    size_t accel_bytes;         /* memory it uses (not counting the scene's own arrays) */
    int instances;              /* object instances (pbrt ObjectInstance), not in `triangles` */
    int instanced_objects;      /* distinct objects they place */
    size_t instanced_triangles; /* triangles of those objects, each counted once */
    size_t instance_bytes;      /* the objects' geometry and BVHs, the instance records and
                                 * the top-level tree */
    int lights;                 /* every light source: emitting shapes, point, spot and
                                 * directional lights, the environment; 0 = the render is
                                 * black (callers warn) */
    const char *light_sampler;  /* next-event estimation's choice of light: "power", "bvh" or
                                 * "uniform" (after commit; static storage) */
    int shapes;                 /* analytic shapes (cst_scene_add_shape) */
    int emitting_media;         /* participating media with emission (Le): light sources too,
                                 * though not counted in `lights` (no NEE samples them) */
} CstSceneInfo;
/* Also before cst_scene_commit: the counts so far (the accel fields then describe no
 * structure yet). */
CST_API void cst_scene_info(const CstScene *scene, CstSceneInfo *info);

/* ---------------------------------------------------------------- building scenes
 * A scene built in code, the way a loader builds one: cst_scene_create, then textures,
 * materials, shapes, lights, an environment and a camera in any order (a thing must be
 * added before another refers to it by id), then cst_scene_commit, after which the scene
 * is read-only and can be rendered. Every call validates its input (non-finite numbers,
 * negative or zero sizes, ids and indices out of range, strides smaller than an element)
 * and fails with CST_ERR_INVALID_ARG and a message naming the bad value, leaving the scene
 * as it was before the call. Coordinates and lengths must lie within 1e18 in magnitude.
 * Ids are small integers handed out in order; texture ids start at 1, so that 0 means
 * "no texture" in a zero-initialised description. */

/* An empty scene with a default camera (at (0, 0, 5) looking at the origin, 40 degrees).
 * Caller owns it: cst_scene_destroy. */
CST_API CstStatus cst_scene_create(CstScene **out, CstError *err);

#include "caustic/caustic_textures.h"

typedef enum CstMaterialType {
    CST_MATERIAL_DIFFUSE = 1, /* Lambertian: albedo = hemispherical reflectance */
    CST_MATERIAL_MIRROR,      /* perfect specular reflection times albedo */
    CST_MATERIAL_GLASS,       /* smooth dielectric: exact Fresnel; albedo tints both lobes */
    CST_MATERIAL_CONDUCTOR,   /* metal: complex IOR (eta + i k, or a named metal), GGX if rough */
    CST_MATERIAL_DIELECTRIC,  /* glass that may be rough (GGX reflection + transmission) */
    CST_MATERIAL_PLASTIC,     /* dielectric coat (smooth or GGX) over Lambert */
    /* pbrt-v4's layered materials, by its stochastic random walk: a dielectric interface
     * (ior, roughness) over Lambert (albedo) or a conductor (metal or eta and k;
     * base_roughness), with a scattering layer between */
    CST_MATERIAL_COATED_DIFFUSE,
    CST_MATERIAL_COATED_CONDUCTOR,
    /* pbrt-v4's mix: at each hit one of two materials (mix_materials), the second with
     * probability amount (chosen by a hash of the hit) */
    CST_MATERIAL_MIX,
    /* pbrt-v4's diffusetransmission: Lambertian reflection (albedo, default 0.25) and
     * Lambertian transmission (transmittance, default 0.25) */
    CST_MATERIAL_DIFFUSE_TRANSMISSION,
    /* pbrt-v4's thindielectric: a thin slab of ior (default 1.5): mirror reflection and
     * undeviated transmission; albedo tints both */
    CST_MATERIAL_THIN_DIELECTRIC,
    /* pbrt-v4's measured: a tabulated BRDF from an RGL .bsdf file (measured_file) */
    CST_MATERIAL_MEASURED,
    /* pbrt-v4's hair: the fibre BSDF of Chiang et al. 2016 (ior: the fibre's, default
     * 1.55; beta_m, beta_n, hair_alpha; absorption by hair_absorption). The fibre runs
     * along the surface's dp/du and the offset across it is h = -1 + 2 v of the hit's uv */
    CST_MATERIAL_HAIR,
    /* pbrt-v4's subsurface: a dielectric boundary (ior, default 1.33; roughness) over a
     * homogeneous scattering medium, by the tabulated photon-beam-diffusion BSSRDF (sss_*
     * fields; the path integrator only) */
    CST_MATERIAL_SUBSURFACE
} CstMaterialType;

/* Where a hair's absorption comes from (CstMaterialDesc.hair_absorption). */
typedef enum CstHairAbsorption {
    CST_HAIR_MELANIN = 0, /* eumelanin, pheomelanin concentrations (default 1.3, 0) */
    CST_HAIR_SIGMA_A,     /* sigma_a, per fibre radius, >= 0 */
    CST_HAIR_COLOR        /* albedo (or albedo_texture): the colour the fibre is to have;
                           * sigma_a follows from it and beta_n (Chiang et al. eq. 9) */
} CstHairAbsorption;

/* Fill with cst_material_desc_init (the JSON format's defaults), then set what you want. */
typedef struct CstMaterialDesc {
    CstMaterialType type;
    float albedo[3];        /* reflectance in [0, 1] per channel (default 0.5 for diffuse and
                             * plastic, else 1) */
    int albedo_texture;     /* a texture id replacing albedo (values at most 1), or 0 */
    float ior;              /* glass, dielectric, plastic: interior over exterior, > 0
                             * (plastic: >= 1); default 1.5 */
    float roughness;        /* conductor, dielectric, plastic: perceptual, in [0, 1]; 0 = smooth */
    int roughness_texture;  /* a texture id replacing roughness (not for plastic), or 0 */
    const char *metal;      /* conductor: "gold", "silver", "copper", "aluminium", or NULL and */
    float eta[3], k[3];     /* conductor: complex IOR per channel, >= 0 */
    int two_sided;          /* diffuse, mirror, conductor, plastic: 1 (default) reflects on both
                             * sides, 0 leaves the back black; dielectrics ignore it */
    int displacement_texture; /* a texture id: bump mapping by its channel mean (scene units), or 0 */
    int normal_map_texture;   /* a texture id: a tangent-space normal map, (2 rgb - 1), or 0 */
    /* Coated materials (defaults: pbrt-v4's) */
    float base_roughness;   /* coated conductor: the conductor's perceptual roughness in [0, 1] */
    float thickness;        /* the layer's optical thickness, >= 0 (default 0.01) */
    float layer_albedo[3];  /* the layer's single-scattering albedo in [0, 1] (default 0) */
    float g;                /* the layer's Henyey-Greenstein asymmetry in (-1, 1) (default 0) */
    int max_depth;          /* random-walk steps per estimate, >= 1 (default 10) */
    int nsamples;           /* walks averaged per estimate, >= 1 (default 1) */
    /* Mix */
    int mix_materials[2];   /* two material ids of this scene (added before the mix) */
    float amount;           /* the probability of the second, in [0, 1] (default 0.5) */
    int amount_texture;     /* a texture id replacing amount (its channels' mean, clamped to
                             * [0, 1]), or 0 */
    float transmittance[3]; /* diffuse transmission: the transmitted share in [0, 1] per channel */
    /* Spectra (cst_scene_add_spectrum ids, 0 for none) replacing eta, k and ior: a
     * conductor's (or a coated conductor's base) eta and k, and the ior of glass,
     * dielectric, thin dielectric and the coated materials' interface. In spectral mode
     * they are evaluated at the path's wavelengths; an ior varying with wavelength
     * disperses (the path keeps its first wavelength after such a surface). RGB mode uses
     * their reductions: eta and k to RGB under D65, ior to its mean weighted by y-bar. */
    int eta_spectrum, k_spectrum, ior_spectrum;
    /* Anisotropic roughness (conductor, dielectric, coated diffuse and coated conductor;
     * pbrt-v4's uroughness and vroughness): with anisotropic = 1, roughness and
     * base_roughness are the perceptual roughness along the surface's dp/du (its texture
     * u direction) and roughness_v and base_roughness_v, in [0, 1], the one along the other
     * tangent (with a roughness_texture, which sets both widths, roughness_v must equal
     * roughness). 0 (default): isotropic, the _v fields unused. */
    int anisotropic;
    float roughness_v, base_roughness_v;
    /* With anisotropic = 1 and a roughness_texture: a texture id giving the perceptual
     * roughness along the other tangent (the roughness_texture then gives the one along
     * dp/du; pbrt-v4's uroughness and vroughness as two textures), or 0 */
    int roughness_v_texture;
    /* Conductor and coated conductor (its base): texture ids replacing eta and k per hit
     * (values >= 0; in spectral mode upsampled as unbounded spectra), or a reflectance
     * texture (values in [0, 1]) replacing both as pbrt-v4's "reflectance" does (eta = 1,
     * k = 2 sqrt(R) / sqrt(1 - R), per channel or per wavelength); 0 for none */
    int eta_texture, k_texture, reflectance_texture;
    /* Measured: the .bsdf file's path (read when the material is added, once per path;
     * a malformed file fails with CST_ERR_PARSE, "FILE: byte N: ...") */
    const char *measured_file;
    /* Hair (defaults: pbrt-v4's): longitudinal and azimuthal roughness in (0, 1] (0.3),
     * the cuticle scales' tilt in degrees, in [-90, 90] (2), and the absorption */
    float beta_m, beta_n, hair_alpha;
    int hair_absorption;          /* a CstHairAbsorption */
    float sigma_a[3];             /* CST_HAIR_SIGMA_A */
    float eumelanin, pheomelanin; /* CST_HAIR_MELANIN, >= 0 */
    /* Subsurface: the medium under the surface by sss_sigma_a and sss_sigma_s per unit
     * length of the scene (>= 0; defaults pbrt-v4's (.0011, .0024, .014) and (2.55, 3.21,
     * 3.77)), or, with sss_from_reflectance = 1, the medium whose diffuse reflectance is
     * albedo (or albedo_texture) at mean free path sss_mfp (> 0; default 1); g its
     * Henyey-Greenstein asymmetry in (-1, 1) (default 0) */
    int sss_from_reflectance;
    float sss_sigma_a[3], sss_sigma_s[3], sss_mfp[3];
} CstMaterialDesc;

CST_API void cst_material_desc_init(CstMaterialDesc *desc, CstMaterialType type);
/* A spectrum sampled at n >= 1 wavelengths (nm, finite, > 0, strictly increasing) with
 * finite values, linear between them and 0 outside them (pbrt-v4's piecewise-linear
 * spectrum; one sample is a constant); the scene keeps it at 1 nm over 360-830 nm.
 * *out_id (>= 1) names it in a CstMaterialDesc. */
CST_API CstStatus cst_scene_add_spectrum(CstScene *scene, const float *lambda_nm, const float *values, int n,
                                         int *out_id, CstError *err);
CST_API CstStatus cst_scene_add_material(CstScene *scene, const CstMaterialDesc *desc, int *out_id,
                                 CstError *err);

/* Light a surface sends out; zero-initialised = none. */
typedef struct CstEmission {
    float radiance[3];  /* linear RGB radiance, >= 0 (times the texture's value, if any) */
    int texture;        /* a texture id, or 0 */
    int two_sided;      /* 0: emits only on the side the geometric normal points to */
    int spectrum;       /* spectral mode: a spectrum id (cst_scene_add_spectrum) giving the emitted
                         * light's shape, at the luminance of radiance (times the texture);
                         * 0: radiance upsampled as an illuminant (RGB x D65). RGB mode ignores it */
} CstEmission;

/* An alpha cut-out (pbrt-v4's Shape "alpha"; leaves drawn on quads): where a shape's alpha
 * is 0 its surface does not exist (rays, shadow rays and light paths pass, an emitter does
 * not emit there), where it is 1 it is opaque, and in between a ray keeps the hit with
 * probability alpha (pbrt-v4's stochastic test, deterministic per ray). Zero-initialised:
 * opaque. */
typedef struct CstAlpha {
    int enabled;  /* 0: opaque (the rest ignored); 1: value or texture gives the alpha */
    float value;  /* in [0, 1], when texture is 0 */
    int texture;  /* a texture id whose scalar value (the mean of its channels; a pbrt float
                   * image texture, CstTextureDesc.pbrt_float, holds its one value in all
                   * three) is the alpha, or 0 */
} CstAlpha;

/* A triangle mesh read from the caller's arrays, Embree-style: each attribute is a pointer
 * to its first element and a stride in bytes between consecutive elements (0 = tightly
 * packed), so positions, normals and uvs may sit inside one interleaved vertex struct.
 * The data are copied; the caller's arrays can be freed after the call. Zero-initialise. */
typedef struct CstMeshDesc {
    const void *positions;   /* num_vertices x 3 floats */
    size_t position_stride;  /* bytes, 0 or >= 12 */
    int num_vertices;
    const void *normals;     /* optional: num_vertices x 3 floats, nonzero (normalised here);
                              * shading normals, interpolated over each triangle */
    size_t normal_stride;    /* 0 or >= 12 */
    const void *uvs;         /* optional: num_vertices x 2 floats, texture coordinates */
    size_t uv_stride;        /* 0 or >= 8 */
    const void *indices;     /* num_triangles x 3 uint32_t vertex indices, < num_vertices */
    size_t index_stride;     /* bytes between triangles, 0 or >= 12 */
    int num_triangles;
    int material;            /* a material id */
    CstEmission emission;    /* zero: not an emitter */
    int skip_degenerate;     /* 1: drop zero-area triangles (counted in *num_dropped) instead
                              * of failing */
    const int *triangle_materials; /* optional: num_triangles material ids, one per triangle,
                                    * used instead of material (mesh files with several) */
    int normals_unit;        /* 1: normals are already unit length, or zero where a vertex has
                              * none (its triangles shade with the geometric normal); stored
                              * as given instead of normalised */
    CstAlpha alpha;          /* an alpha cut-out over the mesh's uvs; zero: opaque */
    const CstAlpha *triangle_alphas; /* optional: num_triangles cut-outs, one per triangle, used
                                      * instead of alpha (an object gathering opaque shapes
                                      * and cut-out leaves) */
} CstMeshDesc;

/* num_dropped may be NULL. */
CST_API CstStatus cst_scene_add_mesh(CstScene *scene, const CstMeshDesc *desc, int *num_dropped,
                             CstError *err);

/* True displacement of meshes (cst_scene_displace_mesh): caustic_displace.h (part of this
 * API). */
#include "caustic/caustic_displace.h"

/* Instancing (Embree's instances, pbrt's ObjectInstance): an object is a mesh in its own
 * space, stored once with its own BVH; each instance places it with an affine transform.
 * Instances do not emit, so the object's desc must leave emission zero (else
 * CST_ERR_UNSUPPORTED); everything else, uvs and alpha cut-outs included, is read and
 * checked as by cst_scene_add_mesh (skip_degenerate drops zero-area triangles, counted in
 * *num_dropped, which may be NULL). *out_id (>= 0) names the object; an object whose
 * triangles were all dropped fails. */
CST_API CstStatus cst_scene_add_object(CstScene *scene, const CstMeshDesc *desc, int *out_id,
                                       int *num_dropped, CstError *err);
/* Places object `object` by world_from_object, a 3 x 4 row-major affine matrix (the rows
 * of the linear part, each followed by its translation: Embree's FLOAT3X4_ROW_MAJOR),
 * finite and invertible. */
CST_API CstStatus cst_scene_add_instance(CstScene *scene, int object,
                                         const float world_from_object[12], CstError *err);
/* A moving instance (motion blur): world_from_object at shutter open and
 * world_from_object_end at shutter close, both as for cst_scene_add_instance; in between
 * the placement is interpolated by decomposition (translation, rotation by quaternion
 * slerp, stretch; pbrt-v4's AnimatedTransform) at each path's time, uniform over the
 * shutter. Scenes with a moving instance render with every integrator but photon (it fails
 * with CST_ERR_UNSUPPORTED; docs/integrators.md), with or without participating media.
 * Equal matrices add a static instance. */
CST_API CstStatus cst_scene_add_instance_motion(CstScene *scene, int object, const float world_from_object[12],
                                                const float world_from_object_end[12], CstError *err);

/* emission may be NULL. */
CST_API CstStatus cst_scene_add_sphere(CstScene *scene, const float center[3], float radius,
                               int material, const CstEmission *emission, CstError *err);
/* cst_scene_add_sphere with an alpha cut-out over the sphere's uvs (alpha may be NULL:
 * opaque). */
CST_API CstStatus cst_scene_add_sphere_alpha(CstScene *scene, const float center[3], float radius,
                                             int material, const CstEmission *emission,
                                             const CstAlpha *alpha, CstError *err);

/* Analytic shapes (quadrics, tori, bilinear patches, curves, signed-distance trees) and
 * cst_scene_add_shape: caustic_shapes.h (part of this API). */
#include "caustic/caustic_shapes.h"

typedef enum CstLightType {
    CST_LIGHT_POINT = 1,  /* isotropic: intensity (W/sr) in every direction */
    CST_LIGHT_SPOT,       /* a point with a cone: intensity on the axis, smooth falloff */
    CST_LIGHT_DIRECTIONAL, /* parallel light from infinitely far: irradiance (W/m^2) */
    CST_LIGHT_GONIOMETRIC, /* a point whose intensity is scaled per direction by an image
                            * (pbrt-v4's "goniometric" light) */
    CST_LIGHT_PROJECTION   /* a point projecting an RGB image through a frustum (pbrt-v4's
                            * "projection" light) */
} CstLightType;

/* Zero-initialise, then set. */
typedef struct CstLightDesc {
    CstLightType type;
    float position[3];   /* point, spot */
    float direction[3];  /* spot: the axis; directional: the way the light travels; nonzero,
                          * any length */
    float intensity[3];  /* point, spot: W/sr; directional: irradiance; >= 0 */
    float cone_angle;    /* spot: half-angle of the cone in degrees, (0, 90] (pbrt: 30) */
    float cone_delta;    /* spot: degrees of falloff at the cone's edge, [0, cone_angle]
                          * (pbrt: 5) */
    /* goniometric: image_size^2 factors (finite, >= 0; copied) over the sphere in Clarberg's
     * equal-area octahedral layout, row 0 first (pbrt-v4's: square centre = light-space +z,
     * u = 1 edge +x, v = 1 edge +y); the intensity in world direction w (away from the
     * light) is intensity x the nearest factor at light_from_world w, a row-major 3 x 3
     * map (all zeros: the identity). */
    const float *image;
    int image_size;
    float light_from_world[9];
    /* projection: image is image_width x image_height RGB triples (linear, finite, >= 0;
     * copied), row 0 first; light space (light_from_world, its rows made orthonormal from
     * the third, all zeros: the identity) looks down +z; fov (degrees, (0, 180)) spans the
     * image's shorter side, the longer one in proportion; a light-space direction d lands
     * on screen point (d.x, d.y) / (d.z tan(fov / 2)) and takes the nearest pixel at
     * u = (x + sx) / 2 sx, v = (y + sy) / 2 sy of the window [-sx, sx] x [-sy, sy] (the
     * aspect on the longer side, 1 on the other), row v x height counted from row 0 as
     * pbrt-v4 does; intensity (W/sr) multiplies the pixel's RGB. */
    int image_width, image_height;
    float fov;
    /* spectral mode: a spectrum id (cst_scene_add_spectrum) giving the emitted light's
     * shape at the luminance of intensity (pbrt-v4 "I" or "L" given as a blackbody, named
     * or sampled spectrum); 0: intensity upsampled as an illuminant (RGB x D65). RGB mode
     * ignores it */
    int spectrum;
} CstLightDesc;

CST_API CstStatus cst_scene_add_light(CstScene *scene, const CstLightDesc *desc, CstError *err);
/* A constant environment: radiance from every direction (replaces one set before). */
CST_API CstStatus cst_scene_set_environment_constant(CstScene *scene, const float radiance[3],
                                             CstError *err);
/* Spectral mode: the environment's radiance in direction w becomes spectrum (an id of
 * cst_scene_add_spectrum) scaled to the luminance of its RGB radiance in w; 0 (the
 * default): the RGB upsampled as an illuminant. Kept when the environment is replaced;
 * RGB mode ignores it. */
CST_API CstStatus cst_scene_set_environment_spectrum(CstScene *scene, int spectrum, CstError *err);
/* An equirectangular environment image (EXR, PFM, PNG...) times scale (NULL = 1), sampled
 * by importance (replaces one set before). */
CST_API CstStatus cst_scene_set_environment_image(CstScene *scene, const char *path,
                                          const float scale[3], CstError *err);
/* An equirectangular environment from the caller's pixels (replaces one set before), in
 * caustic's convention: +y up, row 0 at theta = 0 (straight up), theta = acos(w.y) down
 * the rows, phi = atan2(w.z, w.x) in [0, 2 pi) across the columns. Strided, Embree-style:
 * pixel (x, y) is the 3 floats (R, G, B, linear, finite, >= 0) at rgb + y * row_stride +
 * x * pixel_stride bytes; pixel_stride 0 = 12, row_stride 0 = width * pixel_stride. The
 * pixels are copied; the caller keeps its buffer. scale: NULL = 1. world_from_map: NULL,
 * or a 3 x 3 row-major invertible linear map that turns the map's directions into world
 * directions (a rotation, typically); the image is then resampled once, by nearest
 * lookup, into a map of the same size in world space. */
/* A portal for the environment (pbrt-v4's infinite light "portal"): the four corners of a
 * rectangle, in order, xyz each, through which the environment lights the scene (a window).
 * Next-event estimation then samples only directions through it (by the environment's
 * radiance; Bitterli et al. 2015): less noise indoors; the radiance is unchanged, so a BSDF-
 * sampled ray still sees the environment in every direction. The environment seen from
 * behind the window (ax x ay side, ax = p3 - p0, ay = p1 - p0) is what it samples. Applied
 * at cst_scene_commit to the environment then set; CST_ERR_INVALID_ARG if the points are
 * not a rectangle. */
CST_API CstStatus cst_scene_set_environment_portal(CstScene *scene, const float corners[12], CstError *err);
CST_API CstStatus cst_scene_set_environment_pixels(CstScene *scene, const float *rgb, int width,
                                                   int height, size_t pixel_stride,
                                                   size_t row_stride, const float scale[3],
                                                   const float world_from_map[9], CstError *err);

typedef enum CstCameraType {
    CST_CAMERA_PERSPECTIVE = 1, /* a pinhole, or a thin lens when aperture_radius > 0 */
    CST_CAMERA_ORTHOGRAPHIC     /* parallel rays; fov and the lens are unused */
} CstCameraType;

/* Zero-initialise, then set. */
typedef struct CstCameraDesc {
    CstCameraType type;
    float position[3];
    float look_at[3];       /* a point on the view axis: finite, != position; only the
                             * direction counts, so it may lie beyond the 1e18 bound of
                             * coordinates (within about 1e19 of position) */
    float up[3];            /* not parallel to look_at - position; {0, 0, 0} = {0, 1, 0} */
    float fov;              /* perspective: vertical field of view, degrees, in (0, 180);
                             * orthographic: 0, or in (0, 180): not used by the rays, only
                             * by the film-area term of the bdpt and vcm integrators' MIS */
    float aperture_radius;  /* perspective: lens radius, >= 0; 0 = pinhole */
    float focus_distance;   /* perspective: distance to the plane in focus, > 0;
                             * 0 = |look_at - position| */
    float height;           /* orthographic: the view's height in scene units, > 0 */
    int mirror;             /* 0: image right = forward x up (right-handed); 1: up x forward,
                             * the image flipped left to right, as a left-handed frame (pbrt's
                             * LookAt) shows it */
} CstCameraDesc;

CST_API CstStatus cst_scene_set_camera(CstScene *scene, const CstCameraDesc *desc, CstError *err);
/* cst_scene_set_camera may also be called after cst_scene_commit (an interactive viewer
 * moving the view: `caustic view`), never during a render of the scene; the next render
 * uses the new camera. Texture footprints (MIP-filtered image textures) keep the view the
 * scene was committed with. */
/* The scene's camera as a description that cst_scene_set_camera accepts again: position,
 * look_at (the view axis's point at focus_distance when the scene gave none), up, fov,
 * lens (focus_distance as the render uses it), orthographic height, mirror. With a camera
 * motion (cst_scene_set_camera_motion) it is the camera in its own space. */
CST_API void cst_scene_camera(const CstScene *scene, CstCameraDesc *out);
/* Motion blur of the camera: the camera of cst_scene_set_camera, read as a camera in its
 * own space, is placed in the world by world_from_camera (3 x 4 row-major affine, finite,
 * invertible, as for cst_scene_add_instance) at time 0 and by world_from_camera_end at time
 * 1; in between by decomposition as a moving instance (the view axis and up vector placed,
 * then re-orthonormalised). Both mirror or neither. Both NULL: no placement (the camera is
 * in the world again). Kept across cst_scene_set_camera. Scenes with a moving camera render
 * with every integrator (photon: while no instance moves). */
CST_API CstStatus cst_scene_set_camera_motion(CstScene *scene, const float world_from_camera[12],
                                              const float world_from_camera_end[12], CstError *err);
/* The shutter: each camera path (and light path) draws its time uniformly in [open, close],
 * in the units where every motion (moving instances, the camera) has its start transform at
 * 0 and its end transform at 1 (before 0 and after 1 things stay at their ends); finite,
 * open <= close; [0, 1] by default. Only scenes that move draw a time. */
CST_API CstStatus cst_scene_set_shutter(CstScene *scene, float open, float close, CstError *err);
/* The file the scene asks its render to be written to (cst_scene_output_path reads it
 * back); a non-empty path, copied; replaces one set before. */
CST_API CstStatus cst_scene_set_output_path(CstScene *scene, const char *path, CstError *err);
/* A participating medium (pbrt-v4's "homogeneous", "uniformgrid", "cloud"): coefficients per unit
 * length of the scene, linear RGB (spectral mode upsamples sigma_a and sigma_s as
 * unbounded spectra, le as an illuminant). Initialise with cst_medium_desc_init (pbrt-v4's
 * defaults: sigma_a = sigma_s = 1, scale = 1, g = 0, no emission, le_scale = 1). */
typedef enum CstMediumType {
    CST_MEDIUM_HOMOGENEOUS = 0, /* pbrt-v4's "homogeneous" */
    CST_MEDIUM_UNIFORMGRID,     /* pbrt-v4's "uniformgrid": a density grid over a box */
    CST_MEDIUM_CLOUD            /* pbrt-v4's "cloud": procedural noise density over a box */
} CstMediumType;

typedef struct CstMediumDesc {
    float sigma_a[3], sigma_s[3]; /* absorption and scattering, finite, >= 0 */
    float scale;                  /* multiplies both, >= 0 */
    float g;                      /* Henyey–Greenstein asymmetry, in (-1, 1); > 0 forward */
    float le[3];                  /* emitted radiance (the medium adds sigma_a le per unit length) */
    float le_scale;               /* multiplies le, >= 0 */
    /* Added with heterogeneous media (cst_medium_desc_init sets every field below). */
    const char *preset;           /* a measured preset's name (pbrt-v4's "preset": "Skimmilk",
                                   * "Wholemilk", "Ketchup", ...) replacing sigma_a and sigma_s
                                   * (scale still applies); NULL for none; unknown: an error */
    CstMediumType type;           /* CST_MEDIUM_HOMOGENEOUS */
    /* Heterogeneous media: sigma(p) = density(p) x (sigma_a, sigma_s) x scale inside the
     * box p0 .. p1 of the medium's space, 0 outside; the box is placed by
     * world_from_medium (3 x 4 row-major affine, identity; pbrt's CTM at MakeNamedMedium). */
    float world_from_medium[12];
    float p0[3], p1[3];           /* (0, 0, 0), (1, 1, 1) */
    /* CST_MEDIUM_UNIFORMGRID: nx x ny x nz density samples >= 0 (x fastest), copied, looked
     * up trilinearly between cell centres as pbrt-v4's SampledGrid (falling to 0 within
     * half a sample spacing of the box's faces). Emission le x le_scale, or le times the
     * optional le_scale_grid (same shape) where given. */
    int nx, ny, nz;               /* 1, 1, 1 */
    const float *density;         /* NULL: required for a grid */
    const float *le_scale_grid;   /* NULL */
    /* CST_MEDIUM_CLOUD: pbrt-v4's parameters (density 1, wispiness 1, frequency 5). */
    float cloud_density, wispiness, frequency;
} CstMediumDesc;

CST_API void cst_medium_desc_init(CstMediumDesc *desc);
/* *out_id (>= 0) names the medium. Only the path integrators (path, path-nee,
 * path-bsdf) render scenes with media; the others fail with CST_ERR_UNSUPPORTED. */
CST_API CstStatus cst_scene_add_medium(CstScene *scene, const CstMediumDesc *desc, int *out_id, CstError *err);
/* The medium interface of every shape added after this call (pbrt-v4's MediumInterface):
 * inside (behind the shape's geometric normal) and outside medium ids, -1 = vacuum.
 * boundary = 1 makes those shapes pure medium boundaries (pbrt's "interface" material):
 * rays cross them without scattering, shadow rays pass them; their material is not used.
 * inside == outside with boundary 0 (the initial state) means no transition: rays keep
 * their medium. */
CST_API CstStatus cst_scene_set_medium_interface(CstScene *scene, int inside, int outside, int boundary,
                                                 CstError *err);
/* The medium the camera is in (pbrt-v4's CameraMedium), -1 = vacuum (the default). */
CST_API CstStatus cst_scene_set_camera_medium(CstScene *scene, int medium, CstError *err);
/* Builds the acceleration structure and the light distribution; after it the scene can
 * be rendered and accepts no more additions. */
CST_API CstStatus cst_scene_commit(CstScene *scene, CstError *err);

/* ---------------------------------------------------------------- rendering */
typedef enum CstIntegrator {
    CST_INTEGRATOR_DEFAULT = 0, /* the scene's choice, else CST_INTEGRATOR_PATH */
    CST_INTEGRATOR_PATH,        /* path tracing, NEE + BSDF sampling combined by MIS */
    CST_INTEGRATOR_PATH_NEE,    /* path tracing, emitters reached only by NEE (no MIS) */
    CST_INTEGRATOR_PATH_BSDF,   /* path tracing, BSDF sampling only (no NEE) */
    CST_INTEGRATOR_LIGHT,       /* light tracing: paths from emitters, every vertex splatted
                                 * to the camera; spp counts iterations of width x height
                                 * light paths (docs/integrators.md) */
    CST_INTEGRATOR_WHITTED,     /* Whitted ray tracing: specular recursion + direct light,
                                 * no diffuse interreflection (biased by design) */
    CST_INTEGRATOR_PHOTON,      /* photon mapping (Jensen): global + caustic maps built once
                                 * per render, NEE and one final-gather ray per camera
                                 * sample; consistent but biased (docs/integrators.md) */
    CST_INTEGRATOR_SPPM,        /* stochastic progressive photon mapping (Hachisuka & Jensen
                                 * 2009): spp counts iterations; photons = photon paths per
                                 * iteration; consistent; renders participating media (not
                                 * emitting ones) with volume photons (docs/integrators.md) */
    CST_INTEGRATOR_BDPT,        /* bidirectional path tracing, every connection strategy
                                 * combined by MIS; spp counts iterations of one light and
                                 * one camera path per pixel (docs/integrators.md) */
    CST_INTEGRATOR_VCM,         /* vertex connection and merging (Georgiev et al. 2012):
                                 * BDPT plus photon merging with a shrinking radius
                                 * (photon_radius = the first iteration's); consistent */
    CST_INTEGRATOR_PSSMLT,      /* primary-sample-space Metropolis light transport (Kelemen
                                 * et al. 2002) over the path tracer: spp counts mutations per
                                 * pixel; the mlt_* settings; consistent (docs/integrators.md) */
    CST_INTEGRATOR_MMLT         /* multiplexed MLT over BDPT (Hachisuka et al. 2014, pbrt-v4's
                                 * "mlt"): chains per path length up to max_depth (0 = 5);
                                 * spp counts mutations per pixel; the mlt_* settings
                                 * (mlt_bootstrap per path length); consistent */
} CstIntegrator;

typedef enum CstFilter {
    CST_FILTER_DEFAULT = 0, /* the scene's choice, else CST_FILTER_BOX */
    CST_FILTER_BOX,         /* uniform sampling inside the pixel */
    CST_FILTER_TENT,        /* tent of radius 1 pixel, by filter importance sampling */
    CST_FILTER_GAUSSIAN,    /* Gaussian, sigma 0.5 pixel, radius 1.5 (pbrt-v4's default) */
    CST_FILTER_MITCHELL     /* Mitchell-Netravali, B = C = 1/3, radius 2 (negative lobes) */
} CstFilter;

/* Where camera paths get their random numbers (docs/integrators.md, "Samplers"). Light
 * paths (light, photon, sppm, bdpt, vcm) always draw from independent PCG32 streams. */
typedef enum CstSampler {
    CST_SAMPLER_DEFAULT = 0,   /* the scene's choice, else CST_SAMPLER_ZSOBOL */
    CST_SAMPLER_INDEPENDENT,   /* one PCG32 stream per pixel sample */
    CST_SAMPLER_STRATIFIED,    /* jittered strata of spp (1D) and nx x ny = spp (2D) cells */
    CST_SAMPLER_SOBOL,         /* Sobol' with hash-based Owen scrambling (Burley 2020) */
    CST_SAMPLER_ZSOBOL         /* Sobol' over Morton-ordered (pixel, sample) indices (Ahmed &
                                * Wonka 2020; pbrt-v4's ZSobolSampler) */
} CstSampler;

/* Extra EXR channels (bit mask); see cst_film_write. */
enum {
    CST_AOV_ALBEDO = 1,   /* albedo.R/G/B: reflectance of the first surface hit */
    CST_AOV_NORMAL = 2,   /* N.X/Y/Z: its geometric normal, world space, facing the camera */
    CST_AOV_DEPTH = 4,    /* Z: its distance along the camera's view axis */
    CST_AOV_VARIANCE = 8  /* variance.R/G/B: the variance of each pixel mean */
};

/* How colour is transported (docs/integrators.md, "Spectral mode"). */
typedef enum CstColorMode {
    CST_COLOR_DEFAULT = 0, /* the scene's choice (pbrt-v4 scenes: spectral), else RGB */
    CST_COLOR_RGB,         /* linear sRGB per path: three channels */
    CST_COLOR_SPECTRAL     /* four sampled wavelengths per path, RGB inputs upsampled, the film
                            * integrating the CIE 1931 matching functions (pbrt-v4's model) */
} CstColorMode;

/* Parses "path", "path-nee", "path-bsdf", "light", "whitted", "photon", "sppm", "bdpt",
 * "vcm", "pssmlt", "mmlt" (aliases "mis", "nee", "bsdf", "lighttracing"). Returns CST_INTEGRATOR_DEFAULT for an unknown name. */
CST_API CstIntegrator cst_integrator_from_name(const char *name);
CST_API const char *cst_integrator_name(CstIntegrator integrator);
CST_API CstFilter cst_filter_from_name(const char *name);
CST_API const char *cst_filter_name(CstFilter filter);
/* "independent", "stratified", "sobol", "zsobol"; CST_SAMPLER_DEFAULT for an unknown name. */
CST_API CstSampler cst_sampler_from_name(const char *name);
CST_API const char *cst_sampler_name(CstSampler sampler);
/* "albedo", "normal", "depth", "variance" (one name) to its CST_AOV_ bit; 0 if unknown. */
CST_API int cst_aov_from_name(const char *name);

/* The names the library accepts, for listings (`caustic list`): each kind's table read
 * where the library keeps it. */
typedef enum CstNameKind {
    CST_NAMES_INTEGRATOR = 1, /* cst_integrator_from_name's names (not the aliases) */
    CST_NAMES_SAMPLER,        /* cst_sampler_from_name */
    CST_NAMES_FILTER,         /* cst_filter_from_name */
    CST_NAMES_ACCEL,          /* cst_scene_set_accel, only the back ends this build has */
    CST_NAMES_MATERIAL,       /* a JSON scene's material "type" */
    CST_NAMES_LIGHT,          /* a JSON scene's light "type" (area lights are shapes with
                               * "emission"; the environment is its own section) */
    CST_NAMES_OUTPUT_FORMAT,  /* extensions cst_film_write writes: "png", "exr", "pfm" */
    CST_NAMES_METAL           /* a conductor's "metal" presets */
} CstNameKind;
/* The index-th name (from 0) of a kind, or NULL past the last one (or for an unknown
 * kind). Static strings. */
CST_API const char *cst_list_names(CstNameKind kind, int index);

/* What this build of the library is: for `caustic --version` and bug reports. */
typedef struct CstBuildInfo {
    const char *version;    /* CST_VERSION_STRING of the library */
    const char *compiler;   /* e.g. "gcc 12.2.0" */
    const char *isa;        /* the widest vector ISA compiled for: "AVX-512", "AVX2",
                             * "AVX", "SSE4.2", "SSE2" or "generic" */
    const char *build_type; /* CMake's build type ("Release", ...), or "unknown" */
    int embree;             /* 1: the Embree back end is built in */
    int mpi, sdl2;          /* 1: built with MPI (distributed rendering), SDL2 (preview) */
    int sanitizers;         /* 1: built with -fsanitize */
} CstBuildInfo;
CST_API void cst_build_info(CstBuildInfo *info);

/* Returns 0 to go on; nonzero cancels the render: it stops at the next work-item
 * boundary (a tile, a chunk of light paths, an SPPM phase's unit), and cst_render
 * returns CST_ERR_CANCELLED without a film (*out stays NULL). */
typedef int (*CstProgressFn)(void *user, double fraction_done, double elapsed_seconds);

/* The phases a render reports through CstRenderSettings.progress_phase: CST_PHASE_PHOTONS,
 * the photon integrator's single-threaded photon pass (maps built before any camera
 * ray); CST_PHASE_RENDER, the passes of samples or iterations (every integrator). */
#define CST_PHASE_PHOTONS "photons"
#define CST_PHASE_RENDER  "render"
typedef void (*CstPhaseFn)(void *user, const char *phase);

struct CstFilm; /* typedef'd as CstFilm below, with the films' calls */

/* What CstRenderSettings.pass_done is told after each completed pass of samples. */
typedef struct CstPassInfo {
    int samples_done; /* every pixel holds samples [0, samples_done) (light, bdpt, vcm, sppm:
                       * iterations), a resumed state's included */
    int last;         /* 1: no pass follows (the sample count or the time limit is reached) */
    double elapsed_seconds;
} CstPassInfo;
/* Called from the calling thread between passes, with the render's film as it is then: the
 * whole width x height image (a crop's pixels outside it stay 0), cst_film_spp() =
 * samples_done, to be written with cst_film_state_write (SPPM's film holds its estimate
 * only at the end). Returns 0 to go on; nonzero stops the render here: cst_render then
 * finishes with the samples done as if they had been asked for, returns CST_OK and sets
 * CstRenderStats.stopped. With pass_done set, passes last about a second at most
 * (docs/cli.md, "Checkpoints"), whatever the sample count, so a stop comes soon; the image
 * does not depend on how the samples are cut into passes. */
typedef int (*CstPassFn)(void *user, const struct CstFilm *film, const CstPassInfo *info);

/* The value cst_render_settings_init gives every int and double field of
 * CstRenderSettings: "not set here: the scene's value, else the default". Compare with
 * == CST_UNSET (doubles hold it exactly). */
#define CST_UNSET (-2147483647 - 1)

/* Render settings, each either set or unset. Unset fields take the scene file's value,
 * else the default, so command-line values override scene-file values; a set field
 * overrides the scene even with 0 where 0 means something (max_depth 0 = unbounded
 * replaces a scene's max_depth 5; time_limit 0 = none; png_linear 0 = sRGB; aovs 0 =
 * none; an all-zero crop = the whole image; threads 0 = all cores).
 *
 *     CstRenderSettings s;
 *     cst_render_settings_init(&s);   every field unset
 *     s.spp = 64;                     the rest from the scene, else the defaults
 *
 * Compatibility: in a zero-initialised struct (the form before cst_render_settings_init)
 * the fields where 0 means nothing (width, height, spp, rr_depth, photons,
 * photon_radius, and the enums' *_DEFAULT) still read 0 as unset; the others read 0 as
 * the value 0. seed and exposure keep their own *_set flags. */
typedef struct CstRenderSettings {
    int width, height;        /* > 0; default 512 x 512 */
    int spp;                  /* samples per pixel (light tracing: iterations of width x height
                               * light paths), > 0; default 16 (or unlimited with time_limit) */
    double time_limit;        /* seconds; 0 = none (the default). With spp also set, stops at
                               * whichever comes first */
    int threads;              /* 0 = all cores (the default) */
    uint64_t seed;            /* used when seed_set != 0; default the scene's, else 0 */
    int seed_set;
    CstIntegrator integrator; /* CST_INTEGRATOR_DEFAULT = unset */
    CstFilter filter;         /* CST_FILTER_DEFAULT = unset */
    int max_depth;            /* maximum bounces (scattering vertices) of a path, light paths
                               * included; 0 = unbounded (the default) */
    int rr_depth;             /* Russian roulette starts at this depth, > 0; default 3 */
    int light_rr_depth;       /* bdpt and vcm: the same for their light subpaths (bounces
                               * from the emitter), > 0; default rr_depth */
    int photons;              /* photon integrator: photon paths emitted per render, > 0;
                               * default 200000 */
    double photon_radius;     /* photon integrator: gather radius in scene units, > 0; default
                               * automatic (about 50 photons at a typical visible point) */
    CstSampler sampler;       /* camera-path sampler (CST_SAMPLER_DEFAULT = unset); default
                               * zsobol */
    /* Output, applied when the film is written (cst_film_write), never to the stored means */
    double exposure;          /* used when exposure_set != 0: pixels times 2^exposure; default 0 */
    int exposure_set;
    int png_linear;           /* 1: PNG stores linear values (no sRGB curve); 0: sRGB (the
                               * default). EXR and PFM are always linear. */
    int aovs;                 /* CST_AOV_* bits: extra EXR channels; 0 = none (the default) */
    double white_balance;     /* kelvin: adapt the white of the CIE daylight illuminant of this
                               * temperature (a blackbody below 4000 K) to the output's D65 by
                               * von Kries in Bradford cone space (pbrt-v4's Film "whitebalance"
                               * for the cie1931 sensor); 0 = none (the default). The variance
                               * AOV stays that of the unbalanced mean */
    /* Crop: only the pixels [crop[0], crop[1]) x [crop[2], crop[3]) of the width x height
     * image (x0, x1, y0, y1; y = 0 the top row) are rendered, and the film holds just them.
     * Each holds exactly the value it has in a whole render with the same seed. All zero =
     * the whole image (the default); unset when crop[0] == CST_UNSET. */
    int crop[4];
    CstProgressFn progress;   /* called from the calling thread about 10 times a second;
                               * nonzero return: cancel (CST_ERR_CANCELLED) */
    void *progress_user;
    /* Optional, with progress: called (with progress_user) as each phase of the render
     * starts, and progress's fraction_done then counts within that phase. NULL: one
     * fraction over the whole render. */
    CstPhaseFn progress_phase;
    CstColorMode color_mode;  /* CST_COLOR_DEFAULT = unset */
    /* > 0: every camera sample's colour (and every light-path splat's) is scaled down, hue
     * kept, so that its largest CIE XYZ component times 2^exposure is at most this: pbrt-v4's
     * RGBFilm "maxcomponentvalue" (a biased clamp against fireflies). 0 = none (the default) */
    double max_component;
    /* 1: the path tracers (path, path-nee, path-bsdf) regularize every BSDF met after the
     * path's first non-delta bounce, as pbrt-v4's "regularize" does: each GGX width below 0.3
     * becomes 2 alpha clamped to [0.1, 0.3], smooth conductors and dielectrics included.
     * Biased (caustics through glass and mirrors blur), fewer fireflies. 0 = off (the default) */
    int regularize;
    /* 1: subsurface materials are rendered by a random walk of each material's homogeneous
     * medium under its dielectric surface, by the path tracers (path, path-nee, path-bsdf)
     * and by light, bdpt, vcm and mmlt alike (so that all agree); 0 (the default): the path
     * tracers use pbrt-v4's tabulated BSSRDF, a diffusion approximation, and light, bdpt,
     * vcm and mmlt refuse scenes with subsurface materials. Others ignore it. */
    int subsurface_walk;
    /* Checkpoint and resume (docs/state-format.md). resume: NULL, or a film read by
     * cst_film_state_read for this scene and these settings: the render continues with
     * sample cst_film_spp(resume) of every pixel (iteration, for light, bdpt and vcm), and
     * its film is bit for bit the one an uninterrupted render would have made (every
     * integrator: SPPM's and MLT's states travel in the film). The caller keeps it; cst_render only
     * reads it. pass_done, pass_user: see CstPassFn; NULL = no call. Neither belongs to a
     * scene (cst_scene_set_render_settings refuses them). */
    const struct CstFilm *resume;
    CstPassFn pass_done;
    void *pass_user;
    /* The index of the first sample (iteration) the render takes: it renders samples
     * [first_sample, first_sample + spp) of every pixel, each exactly as a render from 0
     * computes it (same seeds; light, BDPT and VCM iterations by their index, VCM's merge
     * radius included), so films of consecutive ranges add up, sum by sum, to one render of
     * the whole range: how `caustic view` refines its image pass by pass. >= 0; default 0
     * (unset reads 0). The stratified sampler's strata follow this render's spp. SPPM
     * carries state from iteration to iteration and refuses a first_sample > 0
     * (CST_ERR_UNSUPPORTED). Not a scene setting. */
    int first_sample;
    /* The photon integrator's maps kept from one render to the next (cst_photon_cache_create):
     * NULL = built for every render (the default). With a cache, a render of the same scene
     * with the same photons, max_depth, rr_depth and seed reuses the maps the cache holds
     * (the automatic radius is still chosen from this render's camera), so the image is bit
     * for bit the one without a cache: how `caustic view` refines its photon mode pass by
     * pass and across camera moves without tracing the photons again. Another scene or
     * other settings rebuild them. One render at a time per cache. Not a scene setting. */
    struct CstPhotonCache *photon_cache;
    /* Metropolis light transport (pssmlt and mmlt; docs/integrators.md). spp is the mutations per
     * pixel. mlt_large_step: the probability of a large step (a fresh path), in [0, 1];
     * default 0.3 (0 is a value: a zero-initialised struct asks for small steps only). mlt_sigma: the width of a small step in primary sample space, in
     * (0, 1]; default 0.01. mlt_bootstrap: the paths that estimate the normalisation b and
     * seed the chains, > 0; default 100000 (mmlt: per path length, at most 2^28 in all). mlt_chains: independent Markov chains, > 0;
     * default 1000 (fewer than the pixels: as many as the pixels). */
    double mlt_large_step, mlt_sigma;
    int mlt_bootstrap, mlt_chains;
    /* Samples (iterations) per block of the film's sums, > 0; unset or 1 = every sample
     * added to the pixel's sums in order (what a render always did). B > 1: the sums of
     * each block of samples [kB, (k+1)B) (k >= 0, cut at the render's range) are made
     * from zero, then added to the film in block order, so that films of whole blocks
     * rendered anywhere (other processes, other machines) add up bit for bit to one render
     * of their union: cst_film_add, cst_film_state_merge, MPI (docs/cli.md). With B > 1
     * the pass callback, the time limit and a stop act at block ends only. Not a scene
     * setting. */
    int sample_block;
    /* Adaptive sampling by quality (--noise; docs/cli.md, "Stopping by noise"): > 0, render in
     * rounds until every 16x16 block's estimated relative standard error (of the block's
     * mean luminance, from the pixels' variances of the mean) is at most this. Camera
     * integrators (path, path-nee, path-bsdf, whitted, photon) give more samples only to the
     * blocks above it; light, bdpt and vcm add iterations to the whole image until every
     * block is below it; sppm and pssmlt refuse it (CST_ERR_UNSUPPORTED). spp caps each
     * pixel's samples (spp 0 = CST_NOISE_SPP_CAP), time_limit the render. Every decision
     * depends on the completed rounds' sums alone: deterministic for any thread count, and
     * resumable (the state holds the per-pixel counts). Needs first_sample 0 and
     * sample_block 1. 0 or unset = off (the default). Not a scene setting. */
    double noise_target;
    /* sppm: its photon pass split across processes (CstPhotonSplit). NULL = none. */
    const struct CstPhotonSplit *photon_split;
} CstRenderSettings;

/* SPPM's photon pass split across processes (cli/cluster.c), bit for bit: an iteration's
 * photon paths are cst_sppm_photon_chunks() chunks of 1024; this render traces chunks
 * [chunk_lo, chunk_hi), and before each iteration's gather calls fetch (calling thread) for
 * every other chunk in chunk order, for the `count` floats cst_sppm_trace_chunk made of it
 * elsewhere, so photons are gathered in photon order as in one process. fetch: 0, or
 * nonzero to end the render (CST_ERR_CANCELLED). */
typedef struct CstPhotonSplit {
    int chunk_lo, chunk_hi;
    int (*fetch)(void *user, int iteration, int chunk, const float **hits, size_t *count);
    void *user;
} CstPhotonSplit;
CST_API int cst_sppm_photon_chunks(const CstScene *scene, const CstRenderSettings *settings);
/* Chunk `chunk` of iteration `iteration` traced on the calling thread as a render traces it,
 * its hits' floats appended to (*hits)[*count ..] (realloc'd, *cap floats; the caller frees
 * it); rays (or NULL) adds the rays traced. CST_ERR_OOM, CST_ERR_INVALID_ARG. */
CST_API CstStatus cst_sppm_trace_chunk(const CstScene *scene, const CstRenderSettings *settings, int iteration,
                                       int chunk, float **hits, size_t *count, size_t *cap, uint64_t *rays,
                                       CstError *err);

/* noise_target with spp 0 (unlimited): each pixel's samples are capped at this. */
#define CST_NOISE_SPP_CAP 65536

/* spp = CST_SPP_UNLIMITED: no sample cap, even over a scene's spp; with a time limit
 * (required), as many samples (iterations, passes) as fit in it. Resolves to spp 0. */
#define CST_SPP_UNLIMITED (-1)

/* Photon maps between renders (CstRenderSettings.photon_cache). A new, empty cache, or NULL
 * on OOM; cst_photon_cache_destroy frees it (and accepts NULL). Destroy it before the scene
 * its maps were built from (it remembers that scene by its address). */
typedef struct CstPhotonCache CstPhotonCache;
CST_API CstPhotonCache *cst_photon_cache_create(void);
CST_API void cst_photon_cache_destroy(CstPhotonCache *cache);
/* The positions (world space, x y z per photon) of the global map's photons (caustic 0:
 * every stored photon, paths L (S|D)* D) or the caustic map's (caustic 1: paths L S+ D),
 * at most max of them into xyz (may be NULL with max 0). Returns how many the map holds
 * (0 for an empty cache). */
CST_API size_t cst_photon_cache_positions(const CstPhotonCache *cache, int caustic, float *xyz, size_t max);
/* How many times the cache's maps were built (a render that reused them does not count). */
CST_API int cst_photon_cache_builds(const CstPhotonCache *cache);

/* Photon paths the photon integrator emits when the settings leave photons unset. */
#define CST_DEFAULT_PHOTONS 200000

/* Marks every field unset (CST_UNSET, the enums' *_DEFAULT, seed_set = exposure_set = 0,
 * no progress callback). */
CST_API void cst_render_settings_init(CstRenderSettings *settings);

/* The settings a render of `scene` would use, every field set: each unset field of `in`
 * (NULL = all unset) filled from the scene file, then from the defaults (threads: the
 * core count; crop: the whole image as [0, width) x [0, height)). */
CST_API void cst_render_settings_resolve(const CstScene *scene, const CstRenderSettings *in,
                                 CstRenderSettings *out);

/* The render settings the scene asks for, as a scene file's film and integrator sections
 * do: every set field of `settings` (the rules above) replaces the scene's value, unset
 * fields leave it, and cst_render_settings_resolve takes them for fields its caller leaves
 * unset. threads, progress and progress_user are not the scene's and must stay unset.
 * Before cst_scene_commit; fails on values out of range, leaving the scene as it was. */
CST_API CstStatus cst_scene_set_render_settings(CstScene *scene, const CstRenderSettings *settings,
                                                CstError *err);

typedef struct CstRenderStats {
    double seconds;           /* wall time of the render proper (not scene loading) */
    uint64_t samples;         /* camera samples = camera paths (light tracing: light paths) */
    uint64_t rays;            /* closest-hit + shadow rays traced */
    uint64_t nonfinite;       /* NaN/Inf samples (light tracing: splats) discarded (counted,
                               * never added to the film) */
    int spp, threads, width, height;
    CstIntegrator integrator;
    CstFilter filter;
    int first_spp;            /* samples (iterations) the render resumed from; 0 = a fresh one.
                               * spp counts them, samples and rays only this render's work */
    int stopped;              /* 1: CstRenderSettings.pass_done stopped it before its end */
    /* With noise_target (else all 0): the relative standard errors of the 16x16 blocks'
     * mean luminances as the film ends (render/adaptive.h): their root mean square over the
     * blocks with its 95% confidence interval (the variance estimates' chi-square spread,
     * Satterthwaite's degrees of freedom), the largest, the number of blocks and of those
     * still above the target (at the sample cap or the time limit), and the fewest samples
     * any pixel of the crop holds (spp: the most). */
    double noise_rms, noise_rms_lo, noise_rms_hi, noise_max;
    int noise_blocks, noise_blocks_over, spp_min;
} CstRenderStats;

typedef struct CstFilm CstFilm;

/* Bytes a render of `scene` with `settings` (resolved as cst_render resolves them) will
 * allocate for images: the film's sums (48 bytes per pixel), its AOVs, the crop's copy,
 * the light tracers' per-iteration image, and the float image cst_film_write makes. The
 * scene and acceleration structure are not included (cst_scene_info). For checking a size
 * against the memory available before a render starts. */
CST_API uint64_t cst_render_memory_estimate(const CstScene *scene, const CstRenderSettings *settings);

/* The fraction of a render's samples that may be discarded as NaN or infinite (counted,
 * never added to the film: CstRenderStats.nonfinite over .samples) before cst_render fails
 * with CST_ERR_NONFINITE. A lost sample counts as zero, so the image is biased low where
 * they fall; up to 1 in 10,000 (a few per million pixels-samples from rare degenerate
 * configurations) that bias stays below 8-bit quantisation and the noise of any practical
 * sample count, beyond it the losses are systematic (overflowing values, a broken
 * parameter) and the image is not what the scene describes. */
#define CST_NONFINITE_LIMIT 1e-4

/* Renders the scene. On success *out is a new film the caller owns (cst_film_destroy).
 * CST_ERR_NONFINITE (more than CST_NONFINITE_LIMIT of the samples discarded as NaN/Inf)
 * is the one failure that still sets *out and *stats: the caller owns that film too, so
 * that the image can be inspected; every other failure leaves *out NULL. */
CST_API CstStatus cst_render(const CstScene *scene, const CstRenderSettings *settings,
                     CstFilm **out, CstRenderStats *stats, CstError *err);

/* ---------------------------------------------------------------- films */
CST_API int cst_film_width(const CstFilm *film);
CST_API int cst_film_height(const CstFilm *film);
CST_API int cst_film_spp(const CstFilm *film);
/* Linear RGB mean of pixel (x, y); y = 0 is the top row. */
CST_API void cst_film_pixel(const CstFilm *film, int x, int y, double rgb[3]);
/* Estimated variance of that mean (sample variance / spp), per channel. */
CST_API void cst_film_pixel_variance(const CstFilm *film, int x, int y, double var[3]);
/* Every pixel at once, for copying a film out without a call per pixel: rgb_out receives
 * width * height * 3 floats, rows from the top, R, G, B per pixel: cst_film_pixel's means
 * rounded to float (the stored means; exposure applies only when the film is written). */
CST_API void cst_film_pixels(const CstFilm *film, float *rgb_out);
/* The same layout, as cst_film_write writes them to a float image (EXR, PFM): the means
 * scaled by the render's 2^exposure and white balanced, so a stream of the film (caustic
 * render --display tev) holds bit for bit the floats of the written EXR. */
CST_API void cst_film_output_pixels(const CstFilm *film, float *rgb_out);
/* The same layout for cst_film_pixel_variance's variances of the means. */
CST_API void cst_film_variances(const CstFilm *film, float *var_out);
/* One first-hit AOV of a film rendered with it (CstRenderSettings.aovs), every pixel, rows
 * from the top, as the EXR channels hold it: CST_AOV_ALBEDO 3 floats per pixel (mean
 * albedo), CST_AOV_NORMAL 3 (the mean normal renormalised; 0 where nothing was hit),
 * CST_AOV_DEPTH 1 (mean distance along the view axis over the samples that hit; INFINITY
 * where none did). CST_ERR_INVALID_ARG for another aov or one the film does not hold. */
CST_API CstStatus cst_film_aov_pixels(const CstFilm *film, int aov, float *out, CstError *err);
/* Writes the film; the format follows the extension: .png (8-bit sRGB, or linear when
 * the render's png_linear was set), .exr (float, linear), .pfm (float, linear), scaled
 * by the render's 2^exposure. A film rendered with AOVs writes them as extra EXR channels
 * and cannot be written to another format (CST_ERR_INVALID_ARG). Written to a temporary
 * file then renamed, so a failed write never leaves a partial image behind. */
CST_API CstStatus cst_film_write(const CstFilm *film, const char *path, CstError *err);
CST_API void cst_film_destroy(CstFilm *film);

/* ---------------------------------------------------------------- image write options
 * Metadata: text entries stored in the image, for reproducibility (the caustic CLI writes
 * caustic.version, caustic.command, caustic.scene_sha256, ... : docs/cli.md). PNG keeps
 * each as a tEXt chunk (an iTXt chunk, UTF-8, when the value is not printable ASCII), EXR
 * as a string attribute of the header. PFM has no place for metadata: a PFM write
 * ignores it. A key is 1 to 31 bytes of A-Z a-z 0-9 . _ - (EXR's short attribute names),
 * unique in the list and not one of EXR's own header attributes (channels, compression,
 * dataWindow, ...); a value is NUL-terminated valid UTF-8. Anything else fails the write
 * with CST_ERR_INVALID_ARG before a file is created. */
typedef struct CstImageMetadata {
    const char *key;
    const char *value;
} CstImageMetadata;

/* Every write goes to a temporary file in the output's directory, renamed into place when
 * complete (the name rule is in docs/cli.md). The callback is called with the temporary's
 * name before the file is created, and with NULL once no file of that name is left
 * (renamed, or removed after a failure), so a signal handler can unlink(2) the last name
 * it was given and never leave a partial file behind. The name is valid only until the
 * next call. It is called on the writing thread; it must not call back into caustic. */
typedef void (*CstTempFileFn)(void *user, const char *temp_path);

/* Zero-initialise, then set what you want: all zero = no metadata, no callback. */
typedef struct CstImageWriteOptions {
    const CstImageMetadata *metadata; /* metadata_count entries (at most 256), or NULL */
    int metadata_count;
    CstTempFileFn temp_file;          /* NULL = not told */
    void *temp_file_user;
} CstImageWriteOptions;

/* cst_film_write with options (NULL = none). Before writing, removes the temporaries of
 * `path` left behind by processes that no longer exist (docs/cli.md). */
CST_API CstStatus cst_film_write_opt(const CstFilm *film, const char *path,
                                     const CstImageWriteOptions *options, CstError *err);

/* ---------------------------------------------------------------- film state files
 * A render's film with what it is valid for (docs/state-format.md): per-pixel sums, sums of
 * squares, sample counts and AOV sums, the samples covered, and a key of every value that
 * changes the sums (library version, scene, size, crop, integrator, seed, sampler, depths,
 * photons and radius, colour mode, clamp, light sampler, acceleration structure, AOVs).
 * The sample count asked for is not in the key (a resume may extend it), except with the
 * stratified sampler, whose strata depend on it. scene_id: the caller's name for the
 * scene's content (the CLI: SHA-256 of the scene file), stored and compared as text; the
 * scene's counts (triangles, spheres, emitters, materials, lights) are added to the key. */

/* 1 when a render with this integrator can be checkpointed and resumed, else 0: 1 for every
 * integrator since SPPM's radii and photon statistics and MLT's chains went into the state
 * (kept for callers written when some could not). */
CST_API int cst_integrator_resumable(CstIntegrator integrator);
/* Writes film (the one CstPassFn is given, or a render's uncropped film) as a state file
 * for `scene` rendered with `settings` (resolved as cst_render resolves them), atomically
 * (temporary file renamed into place; options: only temp_file is used, may be NULL), so
 * an interrupted write leaves any previous state intact. CST_ERR_UNSUPPORTED for sppm,
 * CST_ERR_INVALID_ARG when the film is not the settings' width x height, CST_ERR_IO. */
CST_API CstStatus cst_film_state_write(const char *path, const CstFilm *film, const CstScene *scene,
                                       const CstRenderSettings *settings, const char *scene_id,
                                       const CstImageWriteOptions *options, CstError *err);
/* Reads a state file and checks it against `scene`, `settings` and scene_id as
 * cst_film_state_write would key them: a truncated, corrupted or foreign file is
 * CST_ERR_PARSE ("PATH: truncated ...", "... CRC-32 ..."), a state made for something else
 * CST_ERR_INVALID_ARG naming each value that differs ("seed: 7 in the state, 8 here"),
 * and one holding more samples than settings' spp asks for too. On success *out is the
 * film to pass as CstRenderSettings.resume (caller: cst_film_destroy). */
CST_API CstStatus cst_film_state_read(const char *path, const CstScene *scene, const CstRenderSettings *settings,
                                      const char *scene_id, CstFilm **out, CstError *err);

/* ---------------------------------------------------------------- combining films
 * Films of blocks of samples (CstRenderSettings.sample_block) rendered apart, combined bit
 * for bit as one render of their union combines them (docs/cli.md, "Distributed
 * rendering"): by `caustic merge` and by the CLI's MPI ranks. */

/* An empty film (zero sums, spp 0) as cst_render makes it for `scene` and `settings`: the
 * crop's size, AOV sums if the AOVs need them, the output settings. CST_ERR_OOM. */
CST_API CstStatus cst_film_create(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                                  CstError *err);
/* Adds src's sums to dst's, value by value, and src's spp to dst's: a render with
 * sample_block B adds each block's sums so. CST_ERR_INVALID_ARG when their sizes or AOV
 * sums differ. */
CST_API CstStatus cst_film_add(CstFilm *dst, const CstFilm *src, CstError *err);
/* The film's own arrays, to carry sums between processes: sum and sum_sq (3 doubles per
 * pixel, rows from the top), aov (8 per pixel, or NULL), and spp, all writable. */
typedef struct CstFilmSums {
    double *sum, *sum_sq, *aov;
    size_t pixels;
    int *spp;
} CstFilmSums;
CST_API void cst_film_sums(CstFilm *film, CstFilmSums *out);
/* Combines the state files paths[0..count) (cst_film_state_write's, each of a sample range
 * [first_sample, first_sample + spp)) into *out (caller: cst_film_destroy; the crop the
 * states were rendered with, the default output settings) whose sums are bit for bit those
 * of one render of the union of their ranges with the same settings, and *first_sample the
 * union's first sample. The ranges, in any order of paths, must be disjoint and leave no
 * gap; the state that starts the union may hold several blocks, every other one block
 * (blocks of the key's sample_block: their sums combine in block order). Refused, naming
 * what differs: CST_ERR_INVALID_ARG for states of different renders (any key entry but
 * first_sample), overlaps, gaps, several blocks, the stratified sampler (its strata
 * follow each render's spp); CST_ERR_PARSE and CST_ERR_IO as cst_film_state_read. */
CST_API CstStatus cst_film_state_merge(const char *const *paths, int count, CstFilm **out, int *first_sample,
                                       CstError *err);

/* ---------------------------------------------------------------- images */
/* Reads a PNG (sRGB decoded to linear), EXR, PFM or Radiance HDR as linear RGB floats: *rgb (width x
 * height x 3, row 0 = top) is the caller's to free(). */
CST_API CstStatus cst_image_read(const char *path, float **rgb, int *width, int *height, CstError *err);
/* Writes width x height x 3 linear floats (row 0 = top); the format follows the extension
 * (.png 8-bit sRGB, .exr, .pfm), atomically as cst_film_write does. */
CST_API CstStatus cst_image_write(const char *path, const float *rgb, int width, int height, CstError *err);
/* The same with options (NULL = none), as cst_film_write_opt. */
CST_API CstStatus cst_image_write_opt(const char *path, const float *rgb, int width, int height,
                                      const CstImageWriteOptions *options, CstError *err);
/* Whether a write to `path` can succeed, checked before a long render rather than after
 * it: a writable extension, not a directory, a name the file system accepts, and the
 * temporary file the write will use (same name rule) created and removed again. CST_OK,
 * or CST_ERR_INVALID_ARG (extension) or CST_ERR_IO with the reason. */
CST_API CstStatus cst_image_write_check(const char *path, CstError *err);
/* The one extension rule of every image the library writes or reads (case-insensitive):
 * 1 when `path` ends in an extension cst_image_write and cst_film_write can produce
 * (.png, .exr, .pfm), else 0; and 1 when it names an EXR (the only format with AOVs). */
CST_API int cst_image_path_writable(const char *path);
CST_API int cst_image_path_is_exr(const char *path);

/* Comparing renders and images, the ray benchmark, explaining a pixel: caustic_compare.h
 * (part of this API). */
#include "caustic/caustic_compare.h"

#ifdef __cplusplus
}
#endif
#endif
