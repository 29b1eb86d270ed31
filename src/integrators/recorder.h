/* The path recorder of `caustic explain` (issue 30): what one camera sample's path did,
 * event by event, filled by the path tracers, Whitted, photon mapping, BDPT and VCM through
 * a pointer that renders leave NULL (one branch per hook, nothing else on the render path). */
#ifndef CST_INTEGRATORS_RECORDER_H
#define CST_INTEGRATORS_RECORDER_H

#include <stdbool.h>

#include "caustic/caustic.h"
#include "materials/bsdf.h"
#include "math/spectrum.h"
#include "media/medium.h"
#include "scene/scene.h"

/* The hits of a path kept for bdpt's explicit MIS check (bdpt_mis.h); longer paths are
 * not checked. */
enum { RECORDER_PATH_MAX = 64 };

/* BDPT: the camera subpath's and the pixel's light subpath's vertices, every one of them
 * (delta ones too), from which the check rebuilds each recorded strategy's whole path. */
struct Photon;

typedef struct RecorderPaths {
    Vec3 camera_o;                        /* the camera ray's origin (the lens point) */
    float camera_time;                    /* the camera ray's time (motion blur; where a
                                           * moving camera stood for this path) */
    SurfaceHit cam[RECORDER_PATH_MAX];    /* cam[d - 1]: the camera subpath's hit d */
    Vec3 cam_dir[RECORDER_PATH_MAX];      /* the unit direction of the ray that reached it */
    Vec3 next_dir;                        /* the last scatter's (or the camera ray's) */
    bool cam_delta[RECORDER_PATH_MAX];    /* a delta lobe continued the path there */
    int ncam;
    /* The light step starts subpaths 0, 1, ... in order on one thread in explain
     * (explain.c's run): the one numbered light_path (the pixel's) is kept. */
    int light_started, light_path;
    bool light_on, has_light;
    EmissionSample start;
    SurfaceHit light[RECORDER_PATH_MAX];  /* light[b - 1]: the hit after b - 1 bounces */
    Vec3 light_dir[RECORDER_PATH_MAX];    /* the unit direction of the ray that reached it */
    bool light_delta[RECORDER_PATH_MAX];
    /* The lens point of each kept light hit's t = 1 connection (a splat's path ends there). */
    Vec3 light_lens[RECORDER_PATH_MAX];
    int nlight;
    /* Through media (subpath_media.c): a vertex's medium (-1: a surface hit; a medium
     * vertex is kept as a SurfaceHit with its point alone), the distance-sampling densities
     * of the flight that reached it (fwd: from the previous vertex of its subpath; rev: back)
     * and that flight's length from the previous vertex (in its SurfaceHit's t). */
    bool media;
    int cam_medium[RECORDER_PATH_MAX], light_medium[RECORDER_PATH_MAX];
    float cam_fwd[RECORDER_PATH_MAX], cam_rev[RECORDER_PATH_MAX];
    float light_fwd[RECORDER_PATH_MAX], light_rev[RECORDER_PATH_MAX];
    float next_fwd, next_rev, next_len; /* the camera's flight, until its vertex is kept */
    bool next_flight;
} RecorderPaths;

/* MLT: one recorded splat's sample, kept so that explain can evaluate it again (mlt.h's
 * mlt_replay): its primary sample vector's values (off: their first in the recorder's pool,
 * n of them), its chain's path length, its radiance as splatted and its MUTATION event. */
typedef struct RecorderMltSample {
    int event;
    int depth;
    size_t off, n;
    Color L;
} RecorderMltSample;

typedef struct Recorder {
    CstExplainEvent *ev; /* cap events, owned by the caller */
    Color *beta, *value; /* per event: the exact (all-lane) throughput and value summed */
    int n, cap;
    int truncated;
    int depth;           /* the camera vertex being recorded (1 = first hit) */
    Wavelengths wl;      /* spectral mode: the path's wavelengths as of the last event
                          * (a dispersive dielectric terminates the secondary ones) */
    bool has_wl;
    /* BDPT's t = 1 splats are kept when they land within `radius` pixels of the centre of
     * pixel (px, py): the ones the film's filter can add to it. */
    int px, py;
    float radius;
    CstExplainEvent spare; /* where events go once ev is full */
    RecorderPaths paths;
    Color tree_beta[RECORDER_PATH_MAX + 2]; /* whitted: a node's throughput by depth */
    bool cam_dispersed; /* spectral BDPT: the camera subpath's wavelengths are terminated
                         * (its strategies get CST_EXPLAIN_HERO) */
    /* VCM in media: the per-lane normalisation of the merges at a volume camera vertex,
     * by depth (merge_vol[d] false: the scalar vm_norm of a surface vertex). */
    Color merge_norm[RECORDER_PATH_MAX + 2];
    bool merge_vol[RECORDER_PATH_MAX + 2];
    /* MLT (explain_mlt.c): the samples of the recorded splats (recorder_mlt_step), their
     * vectors' values in one pool; malloc'd, recorder_mlt_free. oom: one was not kept. */
    RecorderMltSample *mlt;
    size_t mlt_n, mlt_cap;
    double *mlt_pool;
    size_t mlt_pool_n, mlt_pool_cap;
    bool mlt_oom;
    /* mmlt's replay: the light subpath's hits are VERTEX events too (recorder_light_vertex). */
    bool light_vertices;
    /* BDPT/VCM explain: the pixel's light subpath (paths.light_on) as events, its hits as
     * VERTEX and its scatters and roulette as SCATTER and ROULETTE events of depth -bounces,
     * none of them summed (recorder_light_vertex, recorder_light_scatter). */
    bool light_events;
} Recorder;

/* A new event of kind k at the current depth (fields zero, s = t = light = -1,
 * mis_weight = -1), or the spare slot once the recorder is full (truncated set). */
CstExplainEvent *recorder_push(Recorder *r, CstExplainKind k);
/* Marks event e as an addition of beta * value to the sample, kept with all lanes. */
void recorder_added(Recorder *r, CstExplainEvent *e, Color beta, Color value);
void recorder_wavelengths(Recorder *r, const Wavelengths *wl);

/* ---- the path tracer (path.c) */
void recorder_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, int depth, const Wavelengths *wl);
/* An emitter hit (environment when sh is NULL) reached after a BSDF sample of density
 * pdf_bsdf (pmf for a delta lobe, 0 for the camera ray), NEE's density pdf_light of the
 * same direction; wo unit, from the hit back along the ray; w the MIS weight applied
 * (1 without a partner); value = le * w. */
void recorder_emission(Recorder *r, const SurfaceHit *sh, Vec3 wo, Color beta, Color value, float w,
                       float pdf_bsdf, float pdf_light);
/* NEE with the path tracer's draws (u_sel, u): the light sample is drawn again here (no
 * random number, no ray) to report the light, its densities and the MIS weight. */
void recorder_nee(Recorder *r, const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                  Vec2 u, bool mis, Color beta, Color value);
void recorder_scatter(Recorder *r, const BsdfSample *bs, Color beta);
/* volpath's NEE at a surface or medium vertex v (volpath.h) from the uniforms volpath_nee_u
 * took: the light sample's pdf_w and pdf_a, the pick's pmf, the partner's pdf_w (the BSDF's,
 * or the phase function's in a medium: pdf_other_w) and the power-heuristic weight; value
 * what the render added (beta times it). */
struct VolVertex;
void recorder_vol_nee(Recorder *r, const Scene *s, const struct VolVertex *v, float u_sel, Vec2 u, bool mis, Color beta,
                      Color value);
/* path_sss.c's NEE at a subsurface exit x, the same fields (the partner: Sw's cosine
 * sampling about x's shading normal, cos / pi). */
void recorder_sss_nee(Recorder *r, const Scene *s, const SurfaceHit *x, float u_sel, Vec2 u, bool mis, Color beta,
                      Color value);
/* Russian roulette with survival probability q (a draw was made). */
void recorder_roulette(Recorder *r, float q, bool survived);

/* ---- BDPT (subpath.c): Georgiev's recursive weights w = 1 / (w_light + 1 + w_camera) */
/* Strategy (s_light, t = depth + 1) at the current camera vertex: kind EMISSION (s = 0),
 * NEE (s = 1) or CONNECT; light: the emitter or light chosen; p: the light-side vertex;
 * value the MIS-weighted estimate the walk adds beta times (0 when occluded). */
void recorder_strategy(Recorder *r, CstExplainKind kind, int s_light, int light, Vec3 p, Color beta, Color value,
                       float w, float w_light, float w_camera, float pdf_w, float pdf_a, bool occluded);
/* VCM (vcm.c): light vertex at p merged at the current camera vertex of throughput beta;
 * value the MIS-weighted f beta_light the merge sums before its normalisation vm_norm. */
void recorder_merge(Recorder *r, Vec3 p, int light_bounces, Color beta, Color value, float vm_norm, float w,
                    float w_light, float w_camera, bool dispersed);
/* A light path's t = 1 connection from its light vertex p (s_light light vertices) to the
 * lens point `lens`, at raster position (x, y), kept when it lands within the filter's reach
 * of the recorded pixel (with the light path's index, for the MIS check); value already
 * MIS-weighted. */
void recorder_splat(Recorder *r, float x, float y, int s_light, Vec3 p, Vec3 lens, Color value, float w,
                    float w_light, float pdf_a);

/* ---- The path tracer's BSSRDF step (path_sss.c) */
/* The probe's exit point x, picked among `count` hits of the material along the probe, with
 * density pdf_a per unit area (the pick's 1 / count included); beta: the throughput after
 * Sp / pdf_a. */
void recorder_sss_exit(Recorder *r, const SurfaceHit *x, float pdf_a, int count, Color beta);
/* The Sw lobe's cosine sample at the exit: direction wi, density pdf_w, weight w (Sw cos
 * eta^2 / pdf_w), applied to beta. */
void recorder_sss_scatter(Recorder *r, Vec3 wi, float pdf_w, float w, Color beta);

/* ---- The path tracer in media (volpath.c) */
/* A free-flight distance sampled in medium `medium` (coefficients mc) along ray, up to
 * t_max (INFINITY: no surface behind). */
void recorder_distance(Recorder *r, int medium, const MediumCoeffs *mc, bool hetero, Ray ray, float t_max,
                       const MediumSample *ms);
/* A scattering vertex in a medium, the path's vertex `depth`. */
void recorder_medium_vertex(Recorder *r, Vec3 p, int medium, int depth);
/* An addition of beta * value of kind k (medium emission, NEE) with no more to say. */
void recorder_add(Recorder *r, CstExplainKind kind, Color beta, Color value);

/* ---- BDPT and VCM through media (subpath_media.c) */
/* recorder_strategy for a strategy through media: n the light-side vertex's normal (0 in a
 * medium; NEE's light point's, kept as recorder_nee_normal keeps it), tr the connection's
 * transmittance (ratio tracking in grids) or NULL when media_connect found it blocked
 * (value 0, w -1: no weight was computed). */
void recorder_media_strategy(Recorder *r, CstExplainKind kind, int s_light, int light, Vec3 p, Vec3 n, Color beta,
                             Color value, float w, float w_light, float w_camera, float pdf_w, float pdf_a,
                             const Color *tr, float chain_fwd, float chain_rev);
/* The free flight that made the camera subpath's next vertex at p (volume: in medium
 * `medium`), dist from the previous vertex: fwd its chain density (per unit length at a
 * volume vertex: the distance sampling's, majorant-based in grids; the pass probability at
 * a surface), rev the reverse walk's; beta the throughput after it. */
void recorder_media_flight(Recorder *r, Vec3 p, int medium, bool volume, float dist, float fwd, float rev, Color beta);
/* The Henyey-Greenstein sample that continues the camera subpath from a volume vertex:
 * direction wi, density pdf_w (weight 1: sampled exactly); beta the throughput after it. */
void recorder_phase(Recorder *r, Vec3 wi, float pdf_w, Color beta);
/* A hit of the light subpath walk through media (sh NULL: a medium vertex at p in
 * `medium`), reached along dir after a flight of length dist from the previous vertex
 * with chain densities fwd and rev (recorder_media_flight's). */
void recorder_media_light_hit(Recorder *r, const SurfaceHit *sh, Vec3 p, int medium, Vec3 dir, float dist, float fwd,
                              float rev);
/* The same hit (after `bounces` bounces) as a VERTEX event of depth -bounces, for mmlt's
 * replay (light_vertices) and BDPT/VCM's pixel light subpath (light_events); a medium
 * vertex's material_type "medium". */
void recorder_media_light_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, Vec3 p, int medium, int bounces);
/* The t = 1 connection of a light vertex through media (recorder_splat), with the
 * connection's chain densities fwd (light vertex to lens) and rev. */
void recorder_media_splat(Recorder *r, float x, float y, int s_light, Vec3 p, Vec3 lens, Color value, float w,
                          float w_light, float pdf_a, float fwd, float rev);
/* Emission of media gathered along the flight before camera vertex `depth` (s = 0, weight 1,
 * value already times the throughput). */
void recorder_media_emission(Recorder *r, int depth, Color value);
/* VCM's merges at a volume vertex: the per-lane normalisation 1 / ((4/3) pi r^3 N sigma_s)
 * that media_merge applies to their sum (the replay's, in place of vm_norm), and each merge
 * shown with it. */
void recorder_merge_norm(Recorder *r, Color norm);

/* ---- Whitted (whitted.c): a ray tree, its nodes' events in depth-first order; the
 * throughput of a node is the product of its branches' weights (kept per depth). */
/* An addition at the node of tree depth `depth` (1 = the camera ray's hit): kind EMISSION
 * (L_e), NEE (the direct light's mean) or ESCAPE (the environment, at a miss). */
void recorder_whitted(Recorder *r, CstExplainKind kind, int depth, Color value);
/* A specular branch of weight w (the lobe's probability times its f cos / pdf) from the
 * node at `depth` to a child at depth + 1. */
void recorder_whitted_branch(Recorder *r, const BsdfSample *bs, Color w, int depth);
/* whitted_direct's shadow ray from uniforms u_sel, u at the current vertex: a NEE event NOT
 * flagged ADDED (the sum event after them is what the tree adds) with the light, its pdf_w,
 * pdf_a, pmf, the BSDF's pdf_w and value its share of the mean (the estimate / n). */
void recorder_whitted_light(Recorder *r, const Scene *s, const Bsdf *bsdf, const SurfaceHit *sh, Vec3 wo, float u_sel,
                            Vec2 u, Color value);

/* ---- photon mapping (photon.c's photon_li) */
/* The camera ray's specular chain reached its diffuse vertex x, the last VERTEX recorded
 * (photon_trace_to_diffuse records the chain: its vertices, delta scatters, and the emission
 * it met, each added with its throughput): x's beta, the chain's throughput. */
void recorder_photon_chain(Recorder *r, Color beta);
/* The camera vertex being recorded (1 = the first hit). */
int recorder_depth(const Recorder *r);
/* A photon counted by a density estimate, with the BSDF value f (no cosine) it is weighted by. */
void recorder_photon(Recorder *r, const struct Photon *ph, Color f);
/* The density estimate over the photons recorded just before it (their count is kept):
 * radius, the gather throughput g it is multiplied by (1 at the caustic map's x), the
 * estimate est; window: the photons' time window [window[0], window[1]] and its factor
 * window[2] (shutter / window; 0, 0, 1 when nothing moves), which the kernel
 * window[2] / (pi r^2) includes, as photon.c's radiance_estimate computes it. */
void recorder_estimate(Recorder *r, bool caustic, float radius, Color g, Color est, const float window[3]);
/* The volume map's estimate at a medium vertex (Jensen & Christensen 1998 eq. 11) over the
 * photons recorded just before it: radius r, kernel 1 / ((4/3) pi r^3) (0: the map is empty,
 * nothing added), the vertex's throughput beta, sigma_s at the vertex per lane (the
 * replay's), the in-scattered radiance li (shown) and what was added, out = beta sum kernel /
 * sigma_s per lane. */
void recorder_volume_estimate(Recorder *r, float radius, float kernel, Color beta, Color sigma_s, Color li,
                              Color out, const float window[3]);

/* ---- SPPM (sppm.c; its camera chain by photon_trace_to_diffuse) */
/* At a BSDF with delta and non-delta lobes the chain stopped with the non-delta lobes'
 * probability `prob`: a SCATTER event of pmf prob and weight 1 / prob, beta before it. */
void recorder_mixed(Recorder *r, float prob, Color beta);
/* A photon hit deposited at the visible point: photon path `path` of the iteration, its hit
 * after `depth` bounces from the light, at distance `dist` from the point; f the BSDF (or
 * phase function) value it is weighted by, d = f * power the addition to phi (all lanes). */
void recorder_sppm_photon(Recorder *r, Vec3 p, Vec3 wi, Color power, Color f, Color d, int path, int depth,
                          float dist);

/* ---- BDPT's whole paths for the explicit MIS check (RecorderPaths) */
/* The camera subpath starts (ray origin, direction and time; wl its wavelengths in spectral
 * mode, NULL in RGB). */
void recorder_camera(Recorder *r, Vec3 origin, Vec3 dir, float time, const Wavelengths *wl);
/* Spectral BDPT: whether the camera subpath has been dispersed (its secondary wavelengths
 * terminated) as of the vertex being recorded. */
void recorder_cam_dispersed(Recorder *r, bool dispersed);
/* The connection just recorded used a light vertex of a dispersed light subpath. */
void recorder_light_dispersed(Recorder *r, bool dispersed);
/* The light point's normal of the NEE strategy just recorded (into its ng). */
void recorder_nee_normal(Recorder *r, Vec3 n);
/* A light subpath starts (subpath_trace_light, every path of the step, in order). */
void recorder_light_start(Recorder *r, const EmissionSample *es);
/* A hit of the light subpath walk, then the kind of the scatter that continues from it. */
void recorder_light_hit(Recorder *r, const SurfaceHit *sh, Vec3 dir);
/* mmlt's replay (light_vertices set): the light subpath's hit after `bounces` bounces as a
 * VERTEX event of depth -bounces (the light side, counted from the emitter). */
void recorder_light_vertex(Recorder *r, const Scene *s, const SurfaceHit *sh, int bounces);
/* The BSDF sample bs (importance transport) that continues the light subpath from its hit
 * after `bounces` bounces (b its BSDF, wo toward the previous vertex, beta the throughput
 * before it): kept for the MIS check, and with light_events a SCATTER event of depth
 * -bounces, not summed, whose pdf_other_w is the reverse density pdf_w(wi -> wo) BDPT's
 * weights use (the pmf for a delta lobe). */
void recorder_light_scatter(Recorder *r, const Bsdf *b, const BsdfSample *bs, Vec3 wo, Color beta, int bounces);
/* The light subpath's Henyey-Greenstein sample at its medium vertex after `bounces`
 * bounces (light_events): a SCATTER event of depth -bounces, lobe "phase function". */
void recorder_light_phase(Recorder *r, Vec3 wi, float pdf_w, Color beta, int bounces);
/* BDPT's Russian roulette on a subpath (subpath_scatter_rr): survival probability q; on
 * the light subpath (light) a ROULETTE event of depth -bounces with light_events, on the
 * camera subpath recorder_roulette's. */
void recorder_subpath_roulette(Recorder *r, bool light, int bounces, float q, bool survived);

/* ---- Metropolis light transport (mlt.c's mlt_chain_run) */
/* One splat of a step: the sample's film position, radiance, scalar contribution I, the
 * splat's weight and (mmlt) strategy; index: its place in the chain's splat list of the iteration (-1 when
 * no splat was made: weight 0, or off the film). */
typedef struct RecorderMltSplat {
    Vec2 fp;
    Color L;
    float I, weight;
    long index;
    int s; /* mmlt: the sample's strategy (light vertices); -1 for pssmlt or unknown */
} RecorderMltSplat;
/* Step `step` of chain `chain` (path length `length`, -1 for pssmlt): a large step or not,
 * accepted or not, acceptance probability a; sp[0] the proposal's splat, sp[1] the current
 * state's. Kept (a MUTATION event each, `path` its index in the list) when the splat lands
 * within `radius` pixels of the recorded pixel's centre, with its sample's vector from pss
 * (before the step's accept or reject: the proposal's values are the vector's, the current
 * state's the backups of the coordinates the proposal changed) in r->mlt. */
struct PssSampler;
void recorder_mlt_step(Recorder *r, int chain, int step, int length, bool large, bool accepted, float a,
                       const RecorderMltSplat sp[2], const struct PssSampler *pss);
/* Frees r's MLT samples (accepts none). */
void recorder_mlt_free(Recorder *r);

#endif
