/* caustic: public C API of libcaustic, a physically based offline renderer.
 * Only opaque handles and plain option structs cross this boundary. Every function that
 * can fail returns a CstStatus and fills a CstError with a human-readable message;
 * the library never prints to stdout and never exits the process. */
#ifndef CAUSTIC_CAUSTIC_H
#define CAUSTIC_CAUSTIC_H

#include <stddef.h>
#include <stdint.h>

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
    CST_ERR_CANCELLED    /* the caller asked to stop (CstProgressFn returned nonzero) */
} CstStatus;

typedef struct CstError {
    CstStatus status;
    char msg[1024];
} CstError;

/* "CST_ERR_PARSE" etc. */
const char *cst_status_name(CstStatus status);

/* ---------------------------------------------------------------- scenes */
typedef struct CstScene CstScene;

/* The built-in Cornell box (original Cornell measured data, millimetres). */
CstStatus cst_scene_create_cornell_box(CstScene **out, CstError *err);
/* A scene in caustic's JSON format (docs/scene-format.md). Errors name path:line:column. */
CstStatus cst_scene_load_json(const char *path, CstScene **out, CstError *err);
/* The same from memory; `name` stands for the file name in messages. */
CstStatus cst_scene_load_json_string(const char *text, size_t len, const char *name,
                                     CstScene **out, CstError *err);

/* Diagnostics a loader reports without failing: something in the file that the render
 * ignores or approximates. Tests assert on the code; the message says
 * "file:line:column: directive: what was done". */
typedef enum CstWarningCode {
    CST_WARN_UNSUPPORTED = 1, /* a directive, type or feature skipped entirely */
    CST_WARN_APPROXIMATED,    /* mapped to the nearest thing caustic has (docs/pbrt-compat.md) */
    CST_WARN_PARAMETER_IGNORED, /* a parameter the mapping does not use */
    CST_WARN_GEOMETRY         /* degenerate triangles dropped, unclosed blocks and the like */
} CstWarningCode;
typedef void (*CstWarningFn)(void *user, CstWarningCode code, const char *message);

/* Zero-initialise, then set what you want. */
typedef struct CstLoadOptions {
    CstWarningFn warning;   /* called once per warning, in file order; NULL drops them */
    void *warning_user;
    int no_file_access;     /* 1: Include, Import, plymesh and image textures fail instead
                             * of opening files (untrusted text, fuzzing) */
} CstLoadOptions;

/* A scene in pbrt-v4 format (pbrt-v3 syntax where it is the same); what is supported,
 * approximated or not is in docs/pbrt-compat.md. Relative file names (Include, plymesh,
 * imagemap) are resolved against the directory of `path`, as pbrt does. Errors name
 * file:line:column. options may be NULL. */
CstStatus cst_scene_load_pbrt(const char *path, const CstLoadOptions *options, CstScene **out,
                              CstError *err);
/* The same from memory; `name` stands for the file name in messages and its directory
 * for relative file names. */
CstStatus cst_scene_load_pbrt_string(const char *text, size_t len, const char *name,
                                     const CstLoadOptions *options, CstScene **out,
                                     CstError *err);
/* Accepts NULL. */
void cst_scene_destroy(CstScene *scene);
/* The output path named in the scene file, or NULL. Owned by the scene. */
const char *cst_scene_output_path(const CstScene *scene);

/* Rebuilds the scene's acceleration structure: "bvh" (default), "kdtree", "grid", "list"
 * (brute force) or "embree" (only in builds with Embree). On failure the old one stays. */
CstStatus cst_scene_set_accel(CstScene *scene, const char *name, CstError *err);

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
} CstSceneInfo;
void cst_scene_info(const CstScene *scene, CstSceneInfo *info);

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
                                 * iteration; single-threaded; consistent (docs/integrators.md) */
    CST_INTEGRATOR_BDPT,        /* bidirectional path tracing, every connection strategy
                                 * combined by MIS; spp counts iterations of one light and
                                 * one camera path per pixel (docs/integrators.md) */
    CST_INTEGRATOR_VCM          /* vertex connection and merging (Georgiev et al. 2012):
                                 * BDPT plus photon merging with a shrinking radius
                                 * (photon_radius = the first iteration's); consistent */
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
    CST_SAMPLER_DEFAULT = 0,   /* the scene's choice, else CST_SAMPLER_INDEPENDENT */
    CST_SAMPLER_INDEPENDENT,   /* one PCG32 stream per pixel sample */
    CST_SAMPLER_STRATIFIED,    /* jittered strata of spp (1D) and nx x ny = spp (2D) cells */
    CST_SAMPLER_SOBOL          /* Sobol' with hash-based Owen scrambling (Burley 2020) */
} CstSampler;

/* Extra EXR channels (bit mask); see cst_film_write. */
enum {
    CST_AOV_ALBEDO = 1,   /* albedo.R/G/B: reflectance of the first surface hit */
    CST_AOV_NORMAL = 2,   /* N.X/Y/Z: its geometric normal, world space, facing the camera */
    CST_AOV_DEPTH = 4,    /* Z: its distance along the camera's view axis */
    CST_AOV_VARIANCE = 8  /* variance.R/G/B: the variance of each pixel mean */
};

/* Parses "path", "path-nee", "path-bsdf", "light", "whitted", "photon", "sppm", "bdpt",
 * "vcm" (aliases "mis", "nee", "bsdf", "lighttracing"). Returns CST_INTEGRATOR_DEFAULT for an unknown name. */
CstIntegrator cst_integrator_from_name(const char *name);
const char *cst_integrator_name(CstIntegrator integrator);
CstFilter cst_filter_from_name(const char *name);
const char *cst_filter_name(CstFilter filter);
/* "independent", "stratified", "sobol"; CST_SAMPLER_DEFAULT for an unknown name. */
CstSampler cst_sampler_from_name(const char *name);
const char *cst_sampler_name(CstSampler sampler);
/* "albedo", "normal", "depth", "variance" (one name) to its CST_AOV_ bit; 0 if unknown. */
int cst_aov_from_name(const char *name);

/* Returns 0 to go on; nonzero cancels the render: it stops at the next work-item
 * boundary (a tile, a chunk of light paths, an SPPM phase's unit), and cst_render
 * returns CST_ERR_CANCELLED without a film (*out stays NULL). */
typedef int (*CstProgressFn)(void *user, double fraction_done, double elapsed_seconds);

/* Zero-initialise, then set what you want: a zero field means "the scene's value, else
 * the default". Command-line values override scene-file values this way. */
typedef struct CstRenderSettings {
    int width, height;        /* default 512 x 512 */
    int spp;                  /* samples per pixel (light tracing: iterations of width x height
                               * light paths); default 16 (or unlimited with time_limit) */
    double time_limit;        /* seconds; 0 = none. With spp also set, stops at whichever comes first */
    int threads;              /* 0 = all cores */
    uint64_t seed;            /* used when seed_set != 0; default 0 */
    int seed_set;
    CstIntegrator integrator;
    CstFilter filter;
    int max_depth;            /* maximum bounces (scattering vertices) of a path, light paths
                               * included; 0 = unbounded */
    int rr_depth;             /* Russian roulette starts at this depth; 0 = default 3 */
    int photons;              /* photon integrator: photon paths emitted per render;
                               * 0 = default 200000 */
    double photon_radius;     /* photon integrator: gather radius in scene units; 0 = automatic
                               * (about 50 photons at a typical visible point) */
    CstSampler sampler;       /* camera-path sampler; default independent */
    /* Output, applied when the film is written (cst_film_write), never to the stored means */
    double exposure;          /* used when exposure_set != 0: pixels times 2^exposure; default 0 */
    int exposure_set;
    int png_linear;           /* 1: PNG stores linear values (no sRGB curve); 0 = the scene's,
                               * else sRGB. EXR and PFM are always linear. */
    int aovs;                 /* CST_AOV_* bits: extra EXR channels; 0 = the scene's, else none */
    /* Crop: only the pixels [crop[0], crop[1]) x [crop[2], crop[3]) of the width x height
     * image (x0, x1, y0, y1; y = 0 the top row) are rendered, and the film holds just them.
     * Each holds exactly the value it has in a whole render with the same seed. All zero =
     * the scene's crop, else the whole image. */
    int crop[4];
    CstProgressFn progress;   /* called from the calling thread about 10 times a second;
                               * nonzero return: cancel (CST_ERR_CANCELLED) */
    void *progress_user;
} CstRenderSettings;

/* The settings a render of `scene` would use: every zero field of `in` (which may be
 * NULL) filled from the scene file, then from the defaults (threads: the core count). */
void cst_render_settings_resolve(const CstScene *scene, const CstRenderSettings *in,
                                 CstRenderSettings *out);

typedef struct CstRenderStats {
    double seconds;           /* wall time of the render proper (not scene loading) */
    uint64_t samples;         /* camera samples = camera paths (light tracing: light paths) */
    uint64_t rays;            /* closest-hit + shadow rays traced */
    uint64_t nonfinite;       /* NaN/Inf samples (light tracing: splats) discarded (counted,
                               * never added to the film) */
    int spp, threads, width, height;
    CstIntegrator integrator;
    CstFilter filter;
} CstRenderStats;

typedef struct CstFilm CstFilm;

/* Renders the scene. On success *out is a new film the caller owns (cst_film_destroy). */
CstStatus cst_render(const CstScene *scene, const CstRenderSettings *settings,
                     CstFilm **out, CstRenderStats *stats, CstError *err);

/* ---------------------------------------------------------------- films */
int cst_film_width(const CstFilm *film);
int cst_film_height(const CstFilm *film);
int cst_film_spp(const CstFilm *film);
/* Linear RGB mean of pixel (x, y); y = 0 is the top row. */
void cst_film_pixel(const CstFilm *film, int x, int y, double rgb[3]);
/* Estimated variance of that mean (sample variance / spp), per channel. */
void cst_film_pixel_variance(const CstFilm *film, int x, int y, double var[3]);
/* Writes the film; the format follows the extension: .png (8-bit sRGB, or linear when
 * the render's png_linear was set), .exr (float, linear), .pfm (float, linear), scaled
 * by the render's 2^exposure. A film rendered with AOVs writes them as extra EXR channels
 * and cannot be written to another format (CST_ERR_INVALID_ARG). Written to a temporary
 * file then renamed, so a failed write never leaves a partial image behind. */
CstStatus cst_film_write(const CstFilm *film, const char *path, CstError *err);
void cst_film_destroy(CstFilm *film);

#ifdef __cplusplus
}
#endif
#endif
