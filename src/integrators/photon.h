/* Photon mapping (Jensen, "Realistic Image Synthesis Using Photon Mapping", 2001; Jensen &
 * Christensen, "Efficient Simulation of Light Transport in Scenes with Participating Media
 * Using Photon Maps", 1998, for the two-map split): a photon pass builds a global and a
 * caustic map once per render, then camera paths read them by density estimation. */
#ifndef CST_INTEGRATORS_PHOTON_H
#define CST_INTEGRATORS_PHOTON_H

#include <stdbool.h>
#include <stdint.h>

#include "camera/camera.h"
#include "integrators/photon_map.h"
#include "sampling/sampler.h"
#include "scene/scene.h"

enum {
    PHOTON_DEFAULT_COUNT = 200000, /* photons emitted when the settings say 0 */
    PHOTON_RADIUS_K = 50,          /* the automatic radius holds about this many photons */
    PHOTON_RADIUS_POINTS = 256,    /* camera hit points whose k-NN distance sets the radius */
    PHOTON_MAX_SPECULAR = 64,      /* delta bounces a camera or gather ray follows at most */
    PHOTON_SPECTRAL_SETS = 16,     /* spectral mode: photon sets, one set of wavelengths each */
    PHOTON_TIME_WINDOWS = 8        /* moving geometry: an estimate's time window is 1/8 of the shutter */
};

typedef struct PhotonParams {
    int photons;     /* emitted photon paths; 0 = PHOTON_DEFAULT_COUNT */
    float radius;    /* gather radius (scene units); 0 = automatic (photon_maps_build) */
    int max_depth;   /* bounces of a photon path; 0 = unbounded (Russian roulette only) */
    int rr_depth;    /* first bounce at which Russian roulette may stop a photon path */
    uint64_t seed;   /* the photon pass is a function of this seed only */
    /* Optional: called every PHOTON_PROGRESS_EVERY photon paths with the fraction of the
     * pass done; nonzero return stops the pass (CST_ERR_CANCELLED). */
    int (*progress)(void *user, double fraction);
    void *progress_user;
    bool spectral;   /* spectral mode: PHOTON_SPECTRAL_SETS sets of wavelengths (photon.c) */
    bool no_media;   /* trace as if the scene had no media: SPPM's automatic initial radius,
                      * which was chosen so before photon maps walked media (its images kept) */
    /* NULL, or the scene's emitting media as lights (media_lights.h): photon paths start in
     * them too, with probability p_media, as SPPM's (media_photon_walk). Not owned. */
    const struct MediaLights *media_lights;
} PhotonParams;
enum { PHOTON_PROGRESS_EVERY = 4096 };

/* A photon path's parameters: stream (seed, index, stream), emitted power scaled by
 * `scale` (1 / photons for the maps; SPPM divides later). */
typedef struct PhotonWalk {
    uint64_t seed, stream;
    float scale;
    int max_depth, rr_depth;
    const Wavelengths *wl; /* spectral mode (SPPM): the iteration's wavelengths; NULL: RGB */
    float time;            /* motion blur (SPPM): the iteration's instant, which every ray of
                            * the walk carries; 0 in static scenes */
    /* Motion blur (photon maps of scenes with moving instances): when not NULL, each path
     * draws its own time, uniform over this camera's shutter (camera_time), as the first
     * number of its stream, and `time` is ignored. */
    const Camera *shutter;
    const struct MediaLights *media_lights; /* NULL, or photons also start in the scene's
                                             * emitting media (media_photon_walk): SPPM's,
                                             * and photon maps' (PhotonParams.media_lights) */
} PhotonWalk;

/* The time of a photon path: its own, drawn from its stream (pw->shutter), or pw->time. */
static inline float photon_walk_time(const PhotonWalk *pw, Sampler *rng)
{
    return pw->shutter ? camera_time(pw->shutter, sampler_1d(rng)) : pw->time;
}

/* Called at every non-delta hit of a photon path with the photon there, its depth (1:
 * the first hit from the light) and whether every bounce before it was a delta lobe.
 * Returns false to stop (OOM). */
typedef bool (*PhotonVisit)(void *ctx, const Photon *ph, int depth, bool specular_only);

/* The photon path walk of photon maps and SPPM: the light tracer's and BDPT's light
 * subpath walk (subpath_walk_light: emission sampling, importance-mode BSDF sampling,
 * photons carry flux, Russian roulette), without lens samples. False if `visit` stopped it. */
bool photon_walk(const Scene *scene, const PhotonWalk *pw, uint64_t index, PhotonVisit visit, void *ctx,
                 uint64_t *rays);

/* The maps of one set of photon paths, all traced at the same wavelengths (spectral mode).
 * In scenes without media the volume map is empty. */
typedef struct PhotonSet {
    PhotonMap global;  /* every photon hit on a non-delta surface: paths L (S|D|V)* D */
    PhotonMap caustic; /* the subset whose path is L S+ D (no medium vertex) */
    PhotonMap volume;  /* photons scattered in media past the first vertex: L (S|D|V)+ V */
    Wavelengths wl;    /* spectral mode: the set's wavelengths; unused in RGB mode */
} PhotonSet;

/* The sets and the radii every estimate uses. RGB mode: one set of all the photons.
 * Spectral mode: PHOTON_SPECTRAL_SETS sets of emitted / sets photon paths each, set k at
 * wavelengths stratified over k (wavelengths_pass_u); a camera sample picks one set
 * uniformly and traces at its wavelengths (photon_maps_pick). A zeroed PhotonMaps is
 * valid and empty. */
typedef struct PhotonMaps {
    PhotonSet *sets;
    int num_sets;
    bool spectral;
    float radius;      /* resolved: the given one, or the automatic one */
    float vol_radius;  /* the volume estimate's ball: the given radius, or automatic */
    int emitted;       /* photon paths emitted per set (the power divisor) */
    /* Motion blur: the time window's half-width (scene time units; 0: no window, every
     * photon counts at every instant) and the shutter the photons' times are uniform
     * over. Set in scenes with moving instances (photon.c, TimeWindow). */
    float time_h, shutter_open, shutter_close;
    struct Recorder *rec; /* caustic explain's recorder (recorder.h); NULL in renders */
    bool media_emit;      /* built with PhotonParams.media_lights: the final gather adds the
                           * emission of media it passes (photon_li_media) */
} PhotonMaps;

/* Spectral mode: the set a camera sample of uniform u traces with (its wavelengths in
 * maps->sets[k].wl). 0 in RGB mode. */
int photon_maps_pick(const PhotonMaps *maps, float u);

/* Emits and traces the photons single-threaded, in index order, photon i drawing from the
 * stream (seed, i): the maps depend on the seed only, never on threads or timing. Then, if
 * pp->radius is 0, chooses the radius from camera rays (see photon.c). Adds the rays it
 * traces to *rays. Fails with CST_ERR_OOM (maps zeroed). Caller frees: photon_maps_free. */
CstStatus photon_maps_build(const Scene *scene, const Camera *cam, const PhotonParams *pp,
                            PhotonMaps *out, uint64_t *rays, CstError *err);
/* Accepts NULL and a zeroed struct. */
void photon_maps_free(PhotonMaps *maps);

/* photon_maps_build through a cache (CstRenderSettings.photon_cache; NULL: a plain build,
 * *borrowed false). With one, *out borrows the cache's maps (*borrowed true: not for
 * photon_maps_free) and only the radius is this render's: the given one, or the automatic
 * one from cam, exactly as photon_maps_build chooses it. The maps are rebuilt when scene,
 * photons, max_depth, rr_depth or seed differ from the cached build's. */
CstStatus photon_maps_build_cached(struct CstPhotonCache *cache, const Scene *scene, const Camera *cam,
                                   const PhotonParams *pp, PhotonMaps *out, bool *borrowed, uint64_t *rays,
                                   CstError *err);

/* Radiance arriving along `ray` (toward its origin): emission seen directly or through
 * delta bounces, NEE, the caustic map and one final-gather ray at the first non-delta hit;
 * in scenes with media, the first vertex may be in a medium (NEE and the volume map).
 * `set`: photon_maps_pick's; spectral mode traces at maps->sets[set].wl. No allocation;
 * safe from many threads on one committed scene and built maps. */
Color photon_li(const Scene *scene, const PhotonMaps *maps, int set, Ray ray, Sampler *rng, uint64_t *rays);

/* Shared with sppm.c, which builds its visible points the same way. */
struct Bsdf;
/* Follows delta lobes from `ray` (one sampled lobe per bounce, weights into *beta) to the
 * first non-delta hit *sh (its BSDF in *bsdf, the direction back in *wo_out), adding the
 * emission it passes to *le when le is not NULL. At a BSDF with both kinds of lobes it
 * stops with the probability of the non-delta ones (and *beta divided by it), and follows
 * a delta lobe otherwise: the caller then estimates only the non-delta part at *sh. False
 * if the ray leaves the scene, the chain dies or exceeds PHOTON_MAX_SPECULAR bounces.
 * rec: NULL, or sppm's explain recorder (recorder.h), which gets every hit, delta scatter
 * and emission added (photon_li records its chain in one event instead). */
bool photon_trace_to_diffuse(const Scene *s, Ray ray, Sampler *rng, const Wavelengths *wl, Color *beta, Color *le,
                             SurfaceHit *sh, struct Bsdf *bsdf, Vec3 *wo_out, uint64_t *rays, struct Recorder *rec);
/* Direct light at a non-delta point by one emitter sample, no MIS. */
Color photon_direct_light(const Scene *s, const struct Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo,
                        Sampler *rng, const Wavelengths *wl, uint64_t *rays);

#endif
