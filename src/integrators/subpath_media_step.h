/* The steps of BDPT's, VCM's, the light tracer's and SPPM's subpaths through participating
 * media (subpath_media.c's walks use them): free flights to the next vertex, connections'
 * transmittance, and the distance-sampling densities both carry into the MIS quantities. */
#ifndef CST_INTEGRATORS_SUBPATH_MEDIA_STEP_H
#define CST_INTEGRATORS_SUBPATH_MEDIA_STEP_H

#include <math.h>

#include "camera/camera.h"
#include "integrators/subpath.h"

/* A connection from p (normal n_p; 0 in a medium) to q (n_q likewise; q_med: q is a
 * volume vertex, not a surface or the lens), leaving p in medium `medium`: its transmittance (black when a surface other than a boundary is in
 * the way) and its chain densities. */
typedef struct MediaSegment {
    Color tr;
    float fwd, rev; /* ChainPdf's, for q made from p and p from q */
} MediaSegment;

bool media_connect(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, bool q_med, int medium, float time,
                   const Wavelengths *wl, MediaSegment *out, uint64_t *rays);


/* The medium on the side of emission sample point p toward direction w: just off the
 * surface (further than medium_at's end tolerance), so that an emitter that is itself an
 * interface is crossed when the camera sits on its other side. */
int medium_at_emitter(const Scene *s, const Camera *cam, Vec3 p, Vec3 w, float time, uint64_t *rays);
/* The medium at point q (not on a surface) as a ray from the camera's origin sees it: the
 * camera's medium, switched at every interface shape between (media_lights.c's test that
 * a sampled point lies in the emitting medium). */
int medium_at_point(const Scene *s, const Camera *cam, Vec3 q, float time, uint64_t *rays);

/* The spectral MIS of delta tracking over the lanes (hetero_medium.h), for the light
 * tracer's walks through grid media: the hero lane (-1 until the first grid piece) and
 * p_c / p_hero over the grid pieces so far. */
typedef struct HeroMis {
    int hero;
    Color r_u;
    bool homogeneous; /* homogeneous media too (the light tracer): see hero_sample_homogeneous */
} HeroMis;

/* beta / mean(r_u): a contribution's throughput (volpath.c's mis_beta); beta itself on a
 * walk that met no grid. */
static inline Color hero_beta(const HeroMis *hm, Color beta)
{
    if (hm->hero < 0) return beta;
    float m = 0.0f;
    for (int c = 0; c < COLOR_LANES; c++) m += hm->r_u.c[c];
    return m > 0.0f && isfinite(m) ? color_scale(beta, (float)COLOR_LANES / m) : color_s(0.0f);
}

/* COLOR_LANES / sum(r_u), the factor hero_beta scales a throughput by (1 on a walk that met
 * no hero-sampled piece, 0 where hero_beta drops the path): Russian roulette's scale
 * (subpath_roulette), so that the survival probability follows the throughput the walk's
 * contributions carry, as volpath.c's roulette on mis_beta and pbrt-v4's on beta / r_u
 * (sec. 14.2). The raw per-lane scatter is T_c sigma_s,c / (T_h sigma_t,h) per flight
 * (h the hero lane): it can sit far below the contribution (q then too small, its survivors
 * up to COLOR_LANES times too heavy) or far above it (q at its cap on dim paths). */
static inline float hero_scale(const HeroMis *hm)
{
    if (hm->hero < 0) return 1.0f;
    float m = 0.0f;
    for (int c = 0; c < COLOR_LANES; c++) m += hm->r_u.c[c];
    return m > 0.0f && isfinite(m) ? (float)COLOR_LANES / m : 0.0f;
}

/* What a walk's ray met after free-flight sampling through the pieces of its way. */
typedef enum MediaHitKind { MEDIA_MISS, MEDIA_SURFACE, MEDIA_VOLUME } MediaHitKind;
typedef struct MediaHit {
    MediaHitKind kind;
    SurfaceHit sh; /* MEDIA_SURFACE */
    Vec3 p;        /* the vertex (surface or volume) */
    float dist;    /* |p - the previous vertex| */
    float fwd, rev; /* ChainPdf's: this vertex from the previous one, and back */
    Color le;       /* with `emit`: the media's emission along the way, times the throughput
                     * (hero-normalised), to be added as it is */
} MediaHit;

/* Follows ray (from vertex x_prev, a volume vertex when prev_med) through media and
 * boundaries, in *medium (updated at each boundary), to the next vertex: a free-flight
 * sample in each medium piece (two 1D numbers: the lane, the distance; medium.h), its
 * weight multiplied into sp's beta and scatter. Grid media are delta-tracked with the
 * walk's hero lane (hm), homogeneous ones too when hm->homogeneous. With emit, the
 * emission of every emissive piece is gathered into out->le (volpath.c's estimators:
 * sigma_a Le Tr / pdf at a homogeneous scattering point, hetero_sample_distance's at every
 * tentative collision of a grid). False when the path ends (black weight or a stack of
 * boundaries); a miss is returned as MEDIA_MISS. */
bool media_next(const Scene *s, Ray ray, Vec3 x_prev, bool prev_med, bool emit, int *medium, SubPath *sp,
                HeroMis *hm, Sampler *rng, const Wavelengths *wl, MediaHit *out, uint64_t *rays);

/* mis_arrive (subpath_walk.h) at a vertex reached through media: the area (or volume)
 * density of this vertex gains the distance sampling density fwd, and the reverse
 * density of the previous vertex, which d_vc and d_vm carry, gains rev (UPBP's
 * extension of tech. rep. eqs. 31-33; cos_in = 1 at a volume vertex). */
static inline void mis_arrive_media(SubPath *sp, float dist, float cos_in, float fwd, float rev)
{
    float inv = 1.0f / mis(cos_in * fwd);
    sp->d_vcm *= mis(dist * dist) * inv;
    sp->d_vc *= mis(rev) * inv;
    sp->d_vm *= mis(rev) * inv;
}

/* mis(eta) of merging at a vertex (tech. rep. eq. 12's eta_vcm): a disk's at a surface,
 * a ball's in a medium; 0 without merging (BDPT). */
static inline float eta_vm(const SubpathIteration *it, bool vol)
{
    return vol ? it->mis_vm_vol : it->mis_vm;
}

/* A phase-function scattering at a volume vertex: HG sampled exactly (weight 1), Russian
 * roulette (on scatter x rr_scale: subpath_roulette, hero_scale; with it->rec a ROULETTE
 * event of the light subpath when `light`, else of the camera subpath), the MIS quantities
 * (tech. rep. eqs. 34-36 with no cosine; HG is symmetric, so the reverse density is the
 * forward one) and the next ray, at *ray's time (the ray that reached p). */
bool media_scatter_phase(SubPath *sp, const SubpathIteration *it, bool light, Vec3 p, Vec3 wo, float g, int depth,
                         int rr_depth, float rr_scale, Sampler *rng, Ray *ray);


#endif
