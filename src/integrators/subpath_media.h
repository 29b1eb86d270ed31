/* Light tracing and BDPT in scenes with participating media (homogeneous): the light and
 * camera subpaths with vertices inside media, connections through media and boundary
 * shapes, and the MIS quantities of subpath.h extended to volume vertices. */
#ifndef CST_INTEGRATORS_SUBPATH_MEDIA_H
#define CST_INTEGRATORS_SUBPATH_MEDIA_H

#include "integrators/light.h"
#include "integrators/photon.h"
#include "integrators/subpath.h"

/* light_trace() for scenes with media (light.c hands them here). */
void media_light_trace(const Scene *s, const Camera *cam, const LightParams *lp, Sampler *rng, SplatList *out,
                       uint64_t *rays);

/* subpath_trace_light() and subpath_trace_camera() for scenes with media (subpath.c hands
 * them here). A light vertex in a medium is stored with ng = ns = 0 and material = -1 - its
 * medium's index. With `merge` (VCM; NULL: BDPT) a camera vertex merges the light vertices
 * of its own kind: surface ones on a surface, volume ones in a medium (UPBP's point-point
 * 3D estimator). time: the light subpath's (motion blur), cam placed at it; camera
 * subpaths carry their ray's time. */
void media_subpath_trace_light(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it,
                               Sampler *rng, float time, const Wavelengths *wl, SubpathVertexList *verts,
                               SplatList *splats, uint64_t *rays);
Color media_subpath_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                 const SubpathIteration *it, int path, Ray ray, Sampler *rng, const Wavelengths *wl,
                                 uint64_t *rays, const SubpathMerge *merge);

/* ---- Single strategies for multiplexed MLT (subpath.h's, mlt.c) in scenes with media:
 * the walks above cut at the one vertex a strategy needs, and their connections applied
 * to it alone, with the same MIS weights as media_subpath_trace_camera gives them. */

/* The last vertex of a camera subpath: on a surface (vol false: sh, bsdf) or in a medium
 * (vol true: HG asymmetry g). medium: the medium it is in, or on a surface the one arrived
 * through. */
typedef struct MediaCameraVertex {
    SurfaceHit sh;
    Bsdf bsdf;
    Vec3 p, wo;
    bool vol;
    float g;
    int medium;
    SubPath sp;     /* on arrival */
    bool dispersed; /* spectral: a dispersive refraction on the way */
    float time;     /* the camera ray's (motion blur), which the connections carry */
} MediaCameraVertex;

/* subpath_camera_vertex() through media (its hit number `hits` counts volume vertices).
 * With emission, *emitted also holds the emission of emitting media on the walk's last
 * segment (the one that reaches hit `hits`; below vp's depth limit), weight 1. */
bool media_subpath_camera_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                 const SubpathIteration *it, Ray ray, int hits, bool emission, Sampler *rng,
                                 const Wavelengths *wl, MediaCameraVertex *out, Color *emitted, uint64_t *rays);
/* subpath_light_vertex() through media (a vertex in a medium as media_subpath_trace_light
 * stores it). */
bool media_subpath_light_vertex(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                const SubpathIteration *it, int bounces, Sampler *rng, float time,
                                const Wavelengths *wl, SubpathVertex *out, Wavelengths *walk_wl, uint64_t *rays);
/* s = 1 and s >= 2, t >= 2: subpath_connect_light() and subpath_connect_pair() through media. */
Color media_subpath_connect_light(const Scene *s, const SubpathIteration *it, const MediaCameraVertex *x,
                                  Sampler *rng, const Wavelengths *wl, uint64_t *rays);
Color media_subpath_connect_pair(const Scene *s, const SubpathIteration *it, const MediaCameraVertex *x,
                                 const SubpathVertex *y, const Wavelengths *wl, uint64_t *rays);
/* t = 1 through media: walks the light subpath to its vertex `bounces` (>= 1) and connects
 * it to lens point u_lens, as subpath_light_vertex() then subpath_connect_camera() do (the
 * walk's vertex keeps pointers into the walk, so the two are one call here). */
bool media_subpath_connect_camera(const Scene *s, const Camera *cam, const SubpathParams *vp,
                                  const SubpathIteration *it, int bounces, Sampler *rng, float time, Vec2 u_lens,
                                  const Wavelengths *wl, Vec2 *raster, Color *rgb, uint64_t *rays);

/* ---- SPPM through media (sppm.c). */

/* A photon at a light-walk vertex: on a non-delta surface (n its geometric normal on wi's
 * side) or in a medium (n = 0); power the flux arriving (a volume vertex's includes the
 * sigma_s / sigma_t-type weight of the free-flight sample that made it); bounces 1 for the
 * first vertex after the emitter. */
typedef struct MediaPhoton {
    Vec3 p, wi, n;
    Color power;
    int bounces;
    bool specular_only; /* every vertex before it a delta surface bounce (photon.c's caustics) */
    float time;         /* the path's instant (PhotonWalk: its own or the iteration's) */
    const SurfaceHit *sh; /* the surface hit of a surface photon; NULL in a medium */
    bool medium_start;  /* the path started in an emitting medium (PhotonWalk.media_lights) */
    int medium;         /* the medium at p: a volume photon's own, a surface photon's arrival one */
} MediaPhoton;
typedef bool (*MediaPhotonVisit)(void *ctx, const MediaPhoton *ph);

/* photon_walk() through media: the light tracer's walk (hero-lane free flights, HG
 * scattering, roulette), starting in the medium the camera sees at the emitter (cam: its
 * origin). Every ray carries the path's time (PhotonWalk). With pw->media_lights, a path
 * starts in an emitting medium with probability p_media (media_lights.h), its walk one bounce
 * shorter (a volume vertex gathers the emission one bounce earlier than an emitter hit).
 * False if visit stopped it. */
bool media_photon_walk(const Scene *s, const Camera *cam, const PhotonWalk *pw, uint64_t index,
                       MediaPhotonVisit visit, void *ctx, uint64_t *rays);

/* SPPM's visible point through media: from the camera ray (in `medium`: the camera's, or
 * photon.c's final gather from a surface, the medium on its side),
 * free-flight sampling in media and delta lobes (photon_trace_to_diffuse's rules) to the
 * first vertex that is a medium scattering point (vol) or a non-delta surface; emission
 * passed on the way into *le (emitters, the environment, and emitting media by volpath.c's
 * estimators).
 * beta: the vertex's throughput from the camera, the hero lanes' balance included; at a
 * volume vertex it includes sigma_s(p) / sigma_t-type weight of its free flight. */
typedef struct MediaVisiblePoint {
    SurfaceHit sh; /* !vol */
    Bsdf bsdf;     /* !vol */
    Vec3 p, wo;
    bool vol;
    float g;       /* vol: HG asymmetry */
    int medium;    /* vol: the medium at p; else the medium arrived through */
    Color beta;
} MediaVisiblePoint;
bool media_visible_point(const Scene *s, Ray ray, int medium, Sampler *rng, const Wavelengths *wl, Color beta,
                         Color *le, MediaVisiblePoint *out, uint64_t *rays);
/* The same, recorded for `caustic explain` (rec NULL: the render's, identical draws): each
 * flight through a medium, each vertex (numbered on from rec->depth; a medium vertex's q the
 * HG asymmetry g), delta scatters and the emission added. le may be NULL: the emission met is
 * not wanted (photon.c's final gather without emitting media), and not recorded. With
 * le_media_only, *le gets the emission of media alone (photon.c's final gather in emitting
 * media: the emitters' and the environment's light there is NEE's or the caustic map's). */
struct Recorder;
bool media_visible_point_rec(const Scene *s, Ray ray, int medium, Sampler *rng, const Wavelengths *wl, Color beta,
                             Color *le, bool le_media_only, MediaVisiblePoint *out, uint64_t *rays,
                             struct Recorder *rec);

#endif
