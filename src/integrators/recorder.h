/* The path recorder of `caustic explain` (issue 30): what one camera sample's path did,
 * event by event, filled by the path tracer and BDPT through a pointer that renders leave
 * NULL (one branch per hook, nothing else on the render path). */
#ifndef CST_INTEGRATORS_RECORDER_H
#define CST_INTEGRATORS_RECORDER_H

#include <stdbool.h>

#include "caustic/caustic.h"
#include "materials/bsdf.h"
#include "math/spectrum.h"
#include "scene/scene.h"

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
/* Russian roulette with survival probability q (a draw was made). */
void recorder_roulette(Recorder *r, float q, bool survived);

/* ---- BDPT (subpath.c): Georgiev's recursive weights w = 1 / (w_light + 1 + w_camera) */
/* Strategy (s_light, t = depth + 1) at the current camera vertex: kind EMISSION (s = 0),
 * NEE (s = 1) or CONNECT; light: the emitter or light chosen; p: the light-side vertex;
 * value the MIS-weighted estimate the walk adds beta times (0 when occluded). */
void recorder_strategy(Recorder *r, CstExplainKind kind, int s_light, int light, Vec3 p, Color beta, Color value,
                       float w, float w_light, float w_camera, float pdf_w, float pdf_a, bool occluded);
/* A light path's t = 1 connection to the camera at raster position (x, y), kept when it
 * lands within the filter's reach of the recorded pixel; value already MIS-weighted. */
void recorder_splat(Recorder *r, float x, float y, int s_light, Vec3 p, Color value, float w, float w_light,
                    float pdf_a);

#endif
