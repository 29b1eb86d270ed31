/* Stochastic progressive photon mapping (Hachisuka & Jensen 2009; pbrt-v3 sec. 16.2).
 * Iteration k:
 *   camera pass: one camera sample per pixel, through delta lobes (one sampled lobe per
 *     bounce) to its first non-delta hit, the visible point x. Emission passed on the way
 *     and direct light at x by NEE go to the pixel's Ld (an unbiased sample of the L D and
 *     L S* E paths).
 *   photon pass: `photons` photon paths, traced as photon.c does. Every hit on a non-delta
 *     surface EXCEPT THE FIRST ONE FROM THE LIGHT (depth 1 = L D, which NEE already counts
 *     at x) adds f(wo, wi) Phi / |cos| to phi of every visible point within its radius, so
 *     the density estimate covers L (S|D)* (S|D) D exactly once next to NEE.
 *   update (HJ 2009 eqs. 6-7, pbrt-v3 eq. 16.10): with M photons found this iteration,
 *     N' = N + alpha M,  r' = r sqrt(N' / (N + M)),  tau' = (tau + beta phi) r'^2 / r^2.
 * Pixel: L = Ld_sum / k + tau / (N_emitted pi r^2), N_emitted the photon paths of all k
 * iterations (photon powers are not divided by the per-pass count).
 * Threads and determinism: every random number comes from a stream of (seed, pixel or
 * photon, iteration), so what a thread computes does not depend on which thread it is. The
 * camera pass runs over rows in parallel (a pixel's visible point is its own). Photons are
 * traced in parallel in fixed chunks, each recording its non-delta hits in its own list;
 * the hits are then counting-sorted by grid bucket (serial; each bucket keeps photon
 * order), and the pixels are split into ranges among the threads: each pixel gathers the
 * hits of the buckets its disc overlaps, merged back into photon order. So each pixel's
 * phi receives its photons in photon order, exactly the sums of a single-threaded loop
 * over photons, and the image does not depend on the thread count.
 * The grid is uniform and hashed (pbrt-v3's SPPMPixelListNode grid, its cells sized by the
 * largest disc, as flat counting-sort arrays), rebuilt each iteration. It holds the photon
 * hits, looked up from the pixels (as SmallVCM's PPM does), rather than the visible points
 * looked up from each photon: pixels in image order query neighbouring cells, so the
 * lookups stay in cache, where photons in photon order hit random cells (perf on
 * scenes/smallvcm-box.json: the deposit's cache misses were a third of the render). */
#include "integrators/sppm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "film/filter.h"
#include "integrators/photon.h"
#include "integrators/recorder.h"
#include "integrators/subpath_media.h"
#include "integrators/volpath.h"
#include "integrators/volume_ball.h"
#include "materials/bsdf.h"
#include "math/motion.h"
#include "media/phase.h"
#include "sampling/warp.h"

/* Photon path i of iteration k draws from (seed, i, SPPM_STREAM + k): disjoint from the
 * camera samples' (seed, pixel, k) for k < 2^62 and from photon.c's streams (2^62, 2^62 + 1)
 * which the automatic radius uses. */
#define SPPM_STREAM (((uint64_t)1 << 62) + 2u)

/* Spectral mode: the wavelengths of every camera and photon path of iteration `iter`. A
 * photon meets many visible points, so all paths of an iteration share one set: each
 * iteration is an unbiased estimate of the spectral integral (its flux converted to RGB
 * with that iteration's wavelengths before it joins tau), and the progressive average
 * converges to the spectral image; the iterations' wavelengths are stratified
 * (wavelengths_pass_u). From a stream of its own: no other draw moves. */
static Wavelengths sppm_wavelengths(const SppmParams *sp, int iter)
{
    Pcg32 r;
    pcg32_seed_sample(&r, sp->seed ^ 0x3c6ef372fe94f82bULL, UINT64_MAX, 0);
    return wavelengths_sample(wavelengths_pass_u((uint32_t)iter, pcg32_next(&r)));
}

typedef struct SppmPixel {
    /* the visible point of the current iteration */
    Vec3 p, wo, n;   /* n: geometric normal on wo's side; 0 in a medium */
    Bsdf bsdf;       /* on a surface */
    Color beta;        /* camera throughput to p (in a medium: divided by sigma_s(p)) */
    bool valid;
    bool vol;        /* in a medium (scenes with media): a ball of radius r_vol */
    float g;         /* vol: HG asymmetry at p */
    /* progressive state */
    double ld[3];    /* sum over iterations of emission + NEE */
    double tau[3];   /* accumulated flux (unnormalised photon powers) */
    double phi[4];   /* this iteration's sum of f Phi / |cos| (spectral mode: 4 lanes) */
    double n_photons; /* N */
    long m;          /* M: photons found this iteration */
    float r;
    /* the same for the visible points in media, a statistic of their own (see
     * progressive_update): tau, N and the ball's radius */
    double tau_vol[3];
    double n_vol;
    float r_vol;
} SppmPixel;

/* The radius of the pixel's current visible point: its disc's, or in a medium its ball's. */
static inline float vp_radius(const SppmPixel *v) { return v->vol ? v->r_vol : v->r; }

/* Scenes with participating media take sppm_media's walks (see the file comment). */
static inline bool scene_has_media(const Scene *s) { return s->num_media || s->num_medium_ifaces; }

/* What the deposit loop tests first, packed: most candidates fail the distance test, and
 * reading it from the 200-byte SppmPixel was a cache miss per candidate (perf: 40% of the
 * render on the Cornell spheres at 512 x 512). */
typedef struct SppmDisc {
    Vec3 p;
    float r2; /* r * r in float, as the test computed it before */
} SppmDisc;

/* A photon's arrival at a non-delta surface, kept until the deposit phase. */
typedef struct SppmHit {
    Vec3 p, wi, n;   /* n: geometric normal on wi's side */
    Color power;       /* unnormalised flux (see the file comment) */
    /* In a chunk's list: its grid bucket, SPPM_NO_BUCKET outside the box of every disc.
     * In the grid's sorted copy: its place in photon order. */
    uint32_t key;
} SppmHit;

#define SPPM_NO_BUCKET UINT32_MAX

/* Uniform grid over the box of the visible points' discs, hashed (Teschner et al. 2003)
 * into `buckets` slots; cell_start/hits is a counting sort of the iteration's photon hits
 * by bucket, photon order kept within a bucket: whole copies, so that a pixel's gather
 * reads them in sequence (fetching each deposited hit from its chunk's list was a cache
 * miss per photon, a fifth of the render). A disc overlaps at most 8 cells (the cell
 * edge is twice the largest radius). */
typedef struct SppmGrid {
    Vec3 lo, hi;     /* the box of every disc */
    float inv_cell;
    int res[3];
    uint32_t buckets;      /* power of two */
    uint32_t *cell_start;  /* buckets + 1 */
    SppmHit *hits;         /* the hits inside the box, bucket by bucket */
    size_t hits_cap;
    SppmDisc *discs;       /* per pixel, copied from the visible points at every build */
} SppmGrid;

static inline uint32_t sppm_grid_hash(const SppmGrid *g, int x, int y, int z)
{
    uint32_t h = ((uint32_t)x * 73856093u) ^ ((uint32_t)y * 19349663u) ^ ((uint32_t)z * 83492791u);
    return h & (g->buckets - 1u);
}

static inline int clampi(int v, int lo, int hi) { return v < lo ? lo : v > hi ? hi : v; }

static inline void sppm_grid_cell(const SppmGrid *g, Vec3 p, int c[3])
{
    float q[3] = {(p.x - g->lo.x) * g->inv_cell, (p.y - g->lo.y) * g->inv_cell, (p.z - g->lo.z) * g->inv_cell};
    for (int a = 0; a < 3; a++) c[a] = clampi((int)floorf(q[a]), 0, g->res[a] - 1);
}

/* The distinct buckets of the cells pixel `px`'s disc overlaps; returns how many (<= 8).
 * Distinct, so a hash collision between two of its own cells cannot count a photon twice. */
static int pixel_buckets(const SppmGrid *g, const SppmPixel *px, uint32_t out[8])
{
    int a[3], b[3], n = 0;
    const float rad = vp_radius(px);
    Vec3 r = v3(rad, rad, rad);
    sppm_grid_cell(g, v3_sub(px->p, r), a);
    sppm_grid_cell(g, v3_add(px->p, r), b);
    for (int z = a[2]; z <= b[2]; z++)
        for (int y = a[1]; y <= b[1]; y++)
            for (int x = a[0]; x <= b[0]; x++) {
                uint32_t h = sppm_grid_hash(g, x, y, z);
                bool seen = false;
                for (int i = 0; i < n; i++) seen |= out[i] == h;
                if (!seen && n < 8) out[n++] = h;
            }
    return n;
}

/* Sets the grid's box and cells from the valid visible points and copies their discs; the
 * hits are sorted in later (grid_sort_hits). No allocation (arrays sized once). */
static void sppm_grid_build(SppmGrid *g, const SppmPixel *px, size_t count)
{
    Vec3 lo = v3(INFINITY, INFINITY, INFINITY), hi = v3(-INFINITY, -INFINITY, -INFINITY);
    float rmax = 0.0f;
    for (size_t i = 0; i < count; i++) {
        if (!px[i].valid) continue;
        lo = v3_min(lo, px[i].p);
        hi = v3_max(hi, px[i].p);
        rmax = fmaxf(rmax, vp_radius(&px[i]));
    }
    if (!(rmax > 0.0f)) { g->res[0] = 0; return; }
    Vec3 rv = v3(rmax, rmax, rmax);
    g->lo = v3_sub(lo, rv);
    float cell = 2.0f * rmax;
    g->inv_cell = 1.0f / cell;
    g->hi = v3_add(hi, rv);
    Vec3 ext = v3_sub(g->hi, g->lo);
    float e[3] = {ext.x, ext.y, ext.z};
    /* Cell counts are capped so the integer cell coordinates stay small; a capped grid is
     * only coarser (the clamp in grid_cell keeps every point inside). */
    for (int a = 0; a < 3; a++) g->res[a] = clampi((int)(e[a] * g->inv_cell) + 1, 1, 1 << 20);
    for (size_t i = 0; i < count; i++)
        if (px[i].valid) g->discs[i] = (SppmDisc){px[i].p, vp_radius(&px[i]) * vp_radius(&px[i])};
}

/* The hits of one chunk of photon paths, in photon order then path order. Reused by every
 * iteration, so the array stops growing after the first ones. */
/* Explain only (SppmTrace): which photon path and bounce made a hit. */
typedef struct SppmHitOrigin {
    uint32_t path, depth;
} SppmHitOrigin;

typedef struct SppmHitList {
    SppmHit *v;
    size_t n, cap;
    bool oom;              /* a hit was lost for lack of memory: the render fails */
    /* Explain's iteration: origin[i] is hit i's (the render keeps track false). */
    bool track;
    uint32_t path;         /* the photon path being traced */
    ARRAY(SppmHitOrigin) origin;
} SppmHitList;

static void hit_list_push(SppmHitList *l, Vec3 p, Vec3 wi, Vec3 n, Color power, int depth)
{
    if (!array_push(l, ((SppmHit){p, wi, n, power, SPPM_NO_BUCKET}))) l->oom = true;
    if (l->track && !array_push(&l->origin, ((SppmHitOrigin){l->path, (uint32_t)depth}))) l->oom = true;
}

/* The bucket of a photon at pos, or SPPM_NO_BUCKET outside the box of every disc (no disc
 * can hold it). */
static uint32_t sppm_grid_bucket(const SppmGrid *g, Vec3 pos)
{
    if (g->res[0] == 0) return SPPM_NO_BUCKET;
    if (!(pos.x >= g->lo.x && pos.y >= g->lo.y && pos.z >= g->lo.z)) return SPPM_NO_BUCKET;
    if (!(pos.x <= g->hi.x && pos.y <= g->hi.y && pos.z <= g->hi.z)) return SPPM_NO_BUCKET;
    int c[3];
    sppm_grid_cell(g, pos, c);
    return sppm_grid_hash(g, c[0], c[1], c[2]);
}

/* Motion blur: the instant of every camera and photon path of iteration `iter`, for the
 * reason its wavelengths are shared (a photon lights the visible points of many pixels, and
 * a photon deposited at one instant on a surface that moves says nothing about that
 * surface at another). Each iteration is then SPPM at one uniform instant, its visible
 * points and photons in the same scene, and the progressive average over iterations
 * converges to the time-averaged image, as it converges over the pixel's area and the
 * lens (Hachisuka & Jensen 2009: the statistics of a pixel are shared by every sample of
 * its region). pbrt-v4's SPPM instead gives camera and photon paths times of their own
 * (a merge between instants: biased where the geometry moves, not only blurred). Mapped
 * through the scene's shutter as camera_time maps a camera sample's (the scene's shutter
 * is the camera's: integrator.c; [0, 1] keeps the instant bit for bit); camera_row places
 * a moving camera there. 0 in static scenes, without a draw. */
static float sppm_time(const Scene *s, const SppmParams *sp, int iter)
{
    if (!scene_has_motion(s)) return 0.0f;
    Pcg32 r;
    pcg32_seed_sample(&r, sp->seed ^ 0x9e3779b97f4a7c15ULL, UINT64_MAX, 0);
    const float u = motion_pass_time((uint32_t)iter, pcg32_float(&r));
    return s->shutter[0] + u * (s->shutter[1] - s->shutter[0]);
}

/* Adds a photon hit whose position is inside v's disc to v's phi (photon.c's
 * density_visit rules); true if it counted. f_out: NULL, or (explain) the f it was
 * weighted by (the phase function's value in a medium) and d_out the addition. */
static inline bool sppm_deposit(SppmPixel *v, const SppmHit *hit, Color *f_out, Color *d_out)
{
    /* A volume photon (n = 0) meets visible points in media only, and a surface photon
     * surface points only: each estimate is a density of its own measure. */
    const bool hit_vol = hit->n.x == 0.0f && hit->n.y == 0.0f && hit->n.z == 0.0f;
    if (hit_vol != v->vol) return false;
    if (hit_vol) {
        /* UPBP's point-point 3D estimator (Krivanek et al. 2014, table 1): the phase
         * function at p; the 1 / sigma_s(p) is in v->beta (camera_row_media). */
        const float f = phase_hg_eval(v->wo, hit->wi, v->g);
        for (int c = 0; c < COLOR_LANES; c++) v->phi[c] += (double)(f * hit->power.c[c]);
        v->m++;
        if (f_out) {
            *f_out = color_s(f);
            for (int c = 0; c < COLOR_LANES; c++) d_out->c[c] = f * hit->power.c[c];
        }
        return true;
    }
    /* A photon on the other side of a thin wall must not light this side, unless the
     * visible point's surface transmits (rough glass). */
    if (!(v3_dot(hit->n, v->n) > 0.0f) && !bsdf_has_transmission(&v->bsdf)) return false;
    float cos_i = fabsf(v3_dot(v->n, hit->wi));
    if (!(cos_i > 0.0f)) return false;
    /* bsdf_eval is f |cos theta_i|; the photon's flux already holds the projected area. */
    Color f = color_scale(bsdf_eval(&v->bsdf, v->wo, hit->wi), 1.0f / cos_i);
    Color d = color_mul(f, hit->power);
    v->phi[0] += (double)d.c[0];
    v->phi[1] += (double)d.c[1];
    v->phi[2] += (double)d.c[2];
    v->phi[3] += (double)d.c[3];
    v->m++;
    if (f_out) *f_out = f, *d_out = d;
    return true;
}

/* SPPM's photon store: every non-delta hit but the first one from the light (depth 1 =
 * L D, which NEE counts at the visible points) into the chunk's hit list. */
static bool store_hit(void *ctx, const Photon *ph, int depth, bool specular_only)
{
    (void)specular_only;
    if (depth > 1) hit_list_push(ctx, ph->pos, ph->wi, ph->n, ph->power, depth); /* sets oom, checked after the phase */
    return true;
}

/* store_hit through media: surface and volume photons alike (a volume one with n = 0),
 * but for the first vertex from an emitter, which NEE counts at the visible points
 * (through media, with transmittance). A path that starts in an emitting medium keeps its
 * first vertex too: NEE never samples the media's emission. */
static bool store_media_hit(void *ctx, const MediaPhoton *ph)
{
    if (ph->bounces > 1 || ph->medium_start) hit_list_push(ctx, ph->p, ph->wi, ph->n, ph->power, ph->bounces);
    return true;
}

/* Photon path `index` of iteration `iter`, by photon.c's walk (subpath_media.c's in scenes
 * with media), recording its hits in `out` instead of a map; power unnormalised (see the
 * file comment). */
static void trace_photon(const Scene *s, const SppmParams *sp, SppmHitList *out, uint64_t index, int iter,
                         uint64_t *rays)
{
    /* Powers unscaled: the estimate divides by the photons of all iterations. */
    out->path = (uint32_t)index;
    Wavelengths wl;
    if (sp->spectral) wl = sppm_wavelengths(sp, iter);
    const PhotonWalk pw = {sp->seed, SPPM_STREAM + (uint64_t)iter, 1.0f, sp->max_depth, sp->rr_depth,
                           sp->spectral ? &wl : NULL, sppm_time(s, sp, iter), NULL, sp->media_lights};
    if (scene_has_media(s)) media_photon_walk(s, sp->cam, &pw, index, store_media_hit, out, rays);
    else photon_walk(s, &pw, index, store_hit, out, rays);
}

/* A pixel's visible point in a scene with media, and the radiance its camera path
 * estimates without photons (emission passed, NEE at the point). The point is the camera
 * path's first non-delta vertex, on a surface or in a medium (media_visible_point): in a
 * medium, SPPM's estimate becomes a volume density estimate, UPBP's point-point 3D
 * estimator (Krivanek et al. 2014, table 1; Jensen & Christensen 1998 eq. 11's volume
 * radiance estimate): (1 / sigma_s(p)) sum_j f_p(wo, wi_j) Phi_j / ((4/3) pi r^3), over
 * the volume photons within a ball of radius r around p, each photon's flux holding the
 * sigma_s of its own free-flight sample and the camera's beta the sigma_s at p, so one
 * 1 / sigma_s(p) leaves the merged path with one scattering coefficient at p (as
 * subpath_media.c's media_merge). The ball's radius shrinks by its own rule
 * (progressive_update). */
static Color camera_media(const Scene *s, Ray ray, Sampler *rng, const Wavelengths *wl, Color beta, SppmPixel *v,
                          Recorder *rec, uint64_t *rays)
{
    Color L = color_s(0.0f);
    MediaVisiblePoint mv;
    v->valid = media_visible_point(s, ray, s->camera_medium, rng, wl, beta, &L, &mv, rays);
    /* explain: the chain through media is not itemised; its emission is one addition. */
    if (rec) recorder_add(rec, CST_EXPLAIN_EMISSION, color_s(1.0f), L);
    if (!v->valid) return L;
    if (rec && mv.vol) recorder_medium_vertex(rec, mv.p, mv.medium, 1);
    else if (rec) recorder_vertex(rec, s, &mv.sh, 1, wl);
    v->p = mv.p;
    v->wo = mv.wo;
    v->vol = mv.vol;
    VolVertex x = {mv.p, v3s(0.0f), v3s(0.0f), mv.wo, NULL, NULL, mv.g, mv.medium, ray.time};
    if (mv.vol) {
        v->g = mv.g;
        v->n = v3s(0.0f);
    } else {
        v->bsdf = mv.bsdf;
        v->n = v3_dot(mv.sh.ng, mv.wo) >= 0.0f ? mv.sh.ng : v3_neg(mv.sh.ng);
        x = (VolVertex){mv.sh.p, mv.sh.ns, mv.sh.ng, mv.wo, &mv.bsdf, &mv.sh, 0.0f, mv.medium, ray.time};
    }
    if (s->emitter_sampler.lights > 0) {
        const Color d = volpath_nee(s, &x, false, rng, wl, rays);
        if (rec) recorder_add(rec, CST_EXPLAIN_NEE, mv.beta, d);
        L = color_madd(L, mv.beta, d);
    }
    v->beta = mv.beta;
    if (mv.vol) {
        /* sigma_s(p): in a grid, the density at p times the medium's sigma_s. */
        const Medium *med = &s->media[mv.medium];
        const MediumCoeffs mc = medium_coeffs(med, wl);
        const float dens = medium_is_hetero(med) ? hetero_density_world(&med->u.het, mv.p) : 1.0f;
        for (int c = 0; c < COLOR_LANES; c++) {
            const float ss = mc.sigma_s.c[c] * dens;
            v->beta.c[c] = ss > 0.0f ? v->beta.c[c] / ss : 0.0f;
        }
        /* The ball's kernel over its part inside the medium (issue 27: photons exist only
         * there; volume_ball.c), at this iteration's radius, folded into beta like
         * 1 / sigma_s(p): the gather's phi is then the density over that part. */
        v->beta = color_scale(v->beta, 1.0f / volume_ball_fraction(s, mv.p, v->r_vol, ray.time, rays));
    }
    v->valid = color_is_finite(v->beta) && !color_is_black(v->beta);
    return L;
}

static SppmPixelState pixel_state(const SppmPixel *v)
{
    SppmPixelState o;
    for (int c = 0; c < 3; c++) o.ld[c] = v->ld[c], o.tau[c] = v->tau[c], o.tau_vol[c] = v->tau_vol[c];
    o.n_photons = v->n_photons;
    o.r = v->r;
    o.n_vol = v->n_vol;
    o.r_vol = v->r_vol;
    return o;
}

/* The visible points of row y for iteration `iter`; tr: NULL, or explain's trace of this
 * iteration (its pixel's camera chain recorded). */
static void camera_row(const Scene *s, const Camera *cam, const SppmParams *sp, const Filter *filter, SppmPixel *px,
                       int y, int iter, SppmTrace *tr, uint64_t *nonfinite, uint64_t *rays)
{
    Wavelengths wl;
    if (sp->spectral) wl = sppm_wavelengths(sp, iter);
    const Wavelengths *wlp = sp->spectral ? &wl : NULL;
    const float time = sppm_time(s, sp, iter);
    Camera placed;
    if (cam->moving) {
        placed = camera_at(cam, time);
        cam = &placed;
    }
    for (int x = 0; x < cam->width; x++) {
        int pixel = y * cam->width + x;
        SppmPixel *v = &px[pixel];
        Sampler rng;
        sampler_start_stream(&rng, sp->seed, (uint64_t)pixel, (uint64_t)iter);
        Vec2 uf = sampler_2d(&rng);
        Vec2 ul = sampler_2d(&rng);
        /* render.c's rule: the filter's weight h / pdf scales the sample, so both the
         * direct part and the visible point's throughput. */
        float fw;
        Vec2 fp = filter_film_position(filter, x, y, uf, &fw);
        Ray ray = camera_generate_ray(cam, fp.x, fp.y, ul);
        ray.time = time;
        Color L = color_s(0.0f), beta = color_s(fw);
        SurfaceHit sh;
        Recorder *rec = tr && pixel == tr->pixel ? tr->rec : NULL;
        if (rec) {
            tr->before = pixel_state(v);
            tr->fw = fw;
            if (wlp) tr->wl = *wlp, recorder_wavelengths(rec, wlp);
            rec->depth = 0;
        }
        if (scene_has_media(s)) {
            L = camera_media(s, ray, &rng, wlp, beta, v, rec, rays);
        } else {
            v->valid = photon_trace_to_diffuse(s, ray, &rng, wlp, &beta, &L, &sh, &v->bsdf, &v->wo, rays, rec);
        }
        if (v->valid && !scene_has_media(s)) {
            const Sampler peek = rng; /* explain: NEE's draws, read again by recorder_nee */
            const Color d = photon_direct_light(s, &v->bsdf, &sh, v->wo, &rng, wlp, rays);
            if (rec) {
                Sampler u = peek;
                const float u_sel = sampler_1d(&u);
                recorder_nee(rec, s, &v->bsdf, &sh, v->wo, u_sel, sampler_2d(&u), false, beta, d);
            }
            L = color_madd(L, beta, d);
            v->p = sh.p;
            v->n = v3_dot(sh.ng, v->wo) >= 0.0f ? sh.ng : v3_neg(sh.ng);
            v->beta = beta;
            v->valid = color_is_finite(beta) && !color_is_black(beta);
        }
        if (wlp) L = spectrum_to_rgb(L, wlp); /* the film's sensor */
        if (!color_is_finite(L)) {
            ++*nonfinite; /* dropped as a zero sample, as render.c does */
            L = color_s(0.0f);
        }
        v->ld[0] += (double)L.c[0];
        v->ld[1] += (double)L.c[1];
        v->ld[2] += (double)L.c[2];
        if (rec) tr->direct = L;
    }
}

/* HJ 2009 eqs. 6-7 (pbrt-v3 eq. 16.10): keep alpha of the new photons, shrink the disc so
 * the density stays, and rescale the flux to the smaller disc. */
static void progressive_update(SppmPixel *v, const Wavelengths *wl, uint64_t *nonfinite)
{
    if (v->valid && v->m > 0) {
        double b[3] = {(double)v->beta.c[0], (double)v->beta.c[1], (double)v->beta.c[2]};
        if (wl) {
            /* Spectral: beta phi at the iteration's wavelengths, to RGB by the film's
             * sensor; tau then accumulates RGB as in RGB mode (b = 1). */
            Color bp;
            for (int i = 0; i < COLOR_LANES; i++) bp.c[i] = (float)((double)v->beta.c[i] * v->phi[i]);
            Color rgb = spectrum_to_rgb(bp, wl);
            for (int c = 0; c < 3; c++) {
                v->phi[c] = (double)rgb.c[c];
                b[c] = 1.0;
            }
        }
        /* A visible point in a medium updates the volume statistic: the density estimate
         * in 3D keeps its density when r'^3 / r^3 = N' / (N + M) (the 3D form of HJ 2009
         * eq. 6, as progressive photon beams' and UPBP's point estimates shrink). */
        double *tau = v->vol ? v->tau_vol : v->tau, *np = v->vol ? &v->n_vol : &v->n_photons;
        float *r = v->vol ? &v->r_vol : &v->r;
        double n_new = *np + (double)SPPM_ALPHA * (double)v->m;
        double r_new, shrink;
        if (v->vol) {
            r_new = (double)*r * cbrt(n_new / (*np + (double)v->m));
            shrink = r_new * r_new * r_new / ((double)*r * (double)*r * (double)*r);
        } else {
            r_new = (double)*r * sqrt(n_new / (*np + (double)v->m));
            shrink = r_new * r_new / ((double)*r * (double)*r);
        }
        bool ok = true;
        for (int c = 0; c < 3; c++) ok &= isfinite(v->phi[c] * b[c]);
        if (ok) {
            for (int c = 0; c < 3; c++) tau[c] = (tau[c] + b[c] * v->phi[c]) * shrink;
            *np = n_new;
            *r = (float)r_new;
        } else {
            ++*nonfinite;
        }
    }
    v->m = 0;
    v->phi[0] = v->phi[1] = v->phi[2] = v->phi[3] = 0.0;
}

/* SPPM_PHOTON_CHUNK (sppm.h), photon paths per chunk: a chunk is the unit of work of the
 * photon phase. Any size gives the same image (the hit sort reads the chunks in order, so
 * photon order is kept); this one balances threads on small images and amortises the
 * bookkeeping. A split (SppmParams.split) hands whole chunks to other processes. */

/* The three parallel phases of an iteration. */
typedef enum SppmPhase { SPPM_PHASE_CAMERA, SPPM_PHASE_PHOTONS, SPPM_PHASE_DEPOSIT } SppmPhase;

typedef struct SppmWorker {
    uint64_t rays, nonfinite; /* integer totals: summed in any order */
    char pad[64];             /* bumped per ray: no cache line shared with the next worker's */
} SppmWorker;

/* The render's SPPM state (sppm.h): what every worker of a phase reads, and the
 * progressive pixels. */
struct Sppm {
    const Scene *s;
    const Camera *cam;
    SppmParams sp;
    Filter filter;        /* sp.filter's shape and tables */
    SppmPixel *px;
    size_t count;         /* pixels */
    SppmGrid g;
    SppmHitList *hits;    /* one per chunk */
    int chunks, photons;
    int ranges;           /* pixel ranges of the deposit phase */
    int iter;
    SppmPhase phase;
    SppmWorker *workers;  /* one per pool worker */
    int num_workers;
    float r0;             /* the initial radius */
    uint64_t prepare_rays; /* traced by the automatic radius */
    SppmTrace *trace;     /* explain (sppm_trace); NULL in renders */
    ARRAY(SppmHitOrigin) sorted_origin; /* explain: the origin of g.hits[k] by its key */
};

/* The trace, when iteration job->iter is the one explain records. */
static inline SppmTrace *traced(const struct Sppm *job)
{
    return job->trace && job->trace->iteration == job->iter ? job->trace : NULL;
}
typedef struct Sppm SppmJob;

/* Pixel range r of the deposit phase is [range_lo(r), range_lo(r + 1)). */
static inline uint32_t range_lo(const SppmJob *job, int r)
{
    return (uint32_t)(job->count * (size_t)r / (size_t)job->ranges);
}

/* Photon chunk u: its paths traced, then every hit's grid bucket (here, in parallel, so
 * that the serial sort only counts and copies). Out of line, as deposit_range, so that
 * profiles tell the photon pass from the gather. */
static __attribute__((noinline)) void photon_chunk(SppmJob *job, SppmWorker *w, int u)
{
    SppmHitList *l = &job->hits[u];
    l->n = 0;
    l->track = traced(job) != NULL;
    l->origin.n = 0;
    int first = u * SPPM_PHOTON_CHUNK;
    int last = first + SPPM_PHOTON_CHUNK < job->photons ? first + SPPM_PHOTON_CHUNK : job->photons;
    for (int i = first; i < last; i++) trace_photon(job->s, &job->sp, l, (uint64_t)i, job->iter, &w->rays);
    for (size_t i = 0; i < l->n; i++) l->v[i].key = sppm_grid_bucket(&job->g, l->v[i].p);
}

/* Serial, after the photon pass: the hits of every chunk counting-sorted by bucket into
 * g->hits, in chunk order and hit order, so that each bucket lists its hits in photon
 * order; each copy's key becomes its place in that order. False on OOM. */
static bool grid_sort_hits(SppmJob *job)
{
    SppmGrid *g = &job->g;
    memset(g->cell_start, 0, ((size_t)g->buckets + 1u) * sizeof *g->cell_start);
    size_t total = 0;
    for (int c = 0; c < job->chunks; c++) {
        const SppmHitList *l = &job->hits[c];
        for (size_t i = 0; i < l->n; i++)
            if (l->v[i].key != SPPM_NO_BUCKET) {
                g->cell_start[l->v[i].key + 1]++;
                total++;
            }
    }
    if (total >= UINT32_MAX || !array_grow(&g->hits, &g->hits_cap, total, sizeof *g->hits)) return false;
    job->sorted_origin.n = 0;
    for (uint32_t h = 0; h < g->buckets; h++) g->cell_start[h + 1] += g->cell_start[h];
    /* Fill using cell_start[h] as bucket h's cursor, then shift the starts back: the usual
     * in-place counting sort. */
    uint32_t seq = 0;
    for (int c = 0; c < job->chunks; c++) {
        const SppmHitList *l = &job->hits[c];
        for (size_t i = 0; i < l->n; i++) {
            uint32_t b = l->v[i].key;
            if (b == SPPM_NO_BUCKET) continue;
            SppmHit *h = &g->hits[g->cell_start[b]++];
            *h = l->v[i];
            if (l->track) {
                if (!array_push(&job->sorted_origin, l->origin.v[i])) return false;
            }
            h->key = seq++;
        }
    }
    for (uint32_t h = g->buckets; h > 0; h--) g->cell_start[h] = g->cell_start[h - 1];
    g->cell_start[0] = 0;
    return true;
}

/* Pixel i's gather: the hits of the (distinct) buckets its disc overlaps, each bucket in
 * photon order, merged into photon order, those inside its disc deposited. */
static void gather_pixel(SppmJob *job, uint32_t i)
{
    const SppmGrid *g = &job->g;
    SppmPixel *v = &job->px[i];
    const SppmDisc disc = g->discs[i];
    SppmTrace *tr = traced(job);
    Recorder *rec = tr && tr->pixel == (int)i ? tr->rec : NULL;
    uint32_t b[8], cur[8], end[8];
    int n = pixel_buckets(g, v, b);
    int live = 0;
    for (int k = 0; k < n; k++) {
        cur[live] = g->cell_start[b[k]];
        end[live] = g->cell_start[b[k] + 1];
        if (cur[live] < end[live]) live++;
    }
    while (live > 0) {
        int k = 0;
        for (int j = 1; j < live; j++)
            if (g->hits[cur[j]].key < g->hits[cur[k]].key) k = j;
        const SppmHit *hit = &g->hits[cur[k]];
        if (++cur[k] == end[k]) { /* bucket k done: the last live one takes its place */
            live--;
            cur[k] = cur[live];
            end[k] = end[live];
        }
        if (photon_dist2(hit->p, disc.p) > disc.r2) continue;
        if (rec) {
            Color f, d;
            const SppmHitOrigin o = job->sorted_origin.v[hit->key];
            if (sppm_deposit(v, hit, &f, &d))
                recorder_sppm_photon(rec, hit->p, hit->wi, hit->power, f, d, (int)o.path, (int)o.depth,
                                     sqrtf(photon_dist2(hit->p, disc.p)));
        } else {
            sppm_deposit(v, hit, NULL, NULL);
        }
    }
}

/* Deposit unit `r`: every valid pixel of range r gathers its photons, then the progressive
 * update of those pixels. */
static __attribute__((noinline)) void deposit_range(SppmJob *job, SppmWorker *w, int r)
{
    uint32_t lo = range_lo(job, r), hi = range_lo(job, r + 1);
    if (job->g.res[0] != 0)
        for (uint32_t i = lo; i < hi; i++)
            if (job->px[i].valid) gather_pixel(job, i);
    Wavelengths wl;
    if (job->sp.spectral) wl = sppm_wavelengths(&job->sp, job->iter);
    SppmTrace *tr = traced(job);
    for (uint32_t i = lo; i < hi; i++) {
        if (tr && tr->pixel == (int)i) {
            const SppmPixel *v = &job->px[i];
            tr->valid = v->valid;
            tr->vol = v->vol;
            tr->beta = v->beta;
            tr->m = v->m;
        }
        progressive_update(&job->px[i], job->sp.spectral ? &wl : NULL, &w->nonfinite);
        if (tr && tr->pixel == (int)i) tr->after = pixel_state(&job->px[i]);
    }
}

void sppm_trace(Sppm *job, SppmTrace *trace)
{
    job->trace = trace;
    if (trace) trace->photons = job->photons;
}

/* Unit u of the current phase (a row, a photon chunk, a pixel range) on pool worker
 * `worker`. */
void sppm_item(void *ctx, int u, int worker)
{
    SppmJob *job = ctx;
    SppmWorker *w = &job->workers[worker];
    if (job->phase == SPPM_PHASE_CAMERA) {
        camera_row(job->s, job->cam, &job->sp, &job->filter, job->px, u, job->iter, traced(job), &w->nonfinite,
                   &w->rays);
    } else if (job->phase == SPPM_PHASE_PHOTONS) {
        photon_chunk(job, w, u + (job->sp.split ? job->sp.split->chunk_lo : 0));
    } else {
        deposit_range(job, w, u);
    }
}

/* The automatic initial radius: photon.c's rule (the median distance to the 50th nearest
 * photon over 256 camera hit points) applied to one iteration's worth of photons, so the
 * first iteration's discs hold about 50 photons each. */
static CstStatus initial_radius(const Scene *s, const Camera *cam, const SppmParams *sp, int photons,
                                float *r, uint64_t *rays, CstError *err)
{
    if (sp->radius > 0.0f) { *r = sp->radius; return CST_OK; }
    PhotonParams pp = {photons, 0.0f, sp->max_depth, sp->rr_depth, sp->seed, NULL, NULL, false, true, NULL};
    PhotonMaps maps;
    CstStatus st = photon_maps_build(s, cam, &pp, &maps, rays, err);
    if (st != CST_OK) return st;
    *r = maps.radius;
    photon_maps_free(&maps);
    return CST_OK;
}

CstStatus sppm_create(const Scene *s, const Camera *cam, const SppmParams *sp, int workers, Sppm **out,
                      CstError *err)
{
    *out = NULL;
    const size_t count = (size_t)cam->width * (size_t)cam->height;
    /* The grid stores pixel indices and entry offsets (8 per pixel) as 32-bit integers. */
    if (count > (size_t)UINT32_MAX / 8u)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image of %zu pixels: too many for SPPM (at most %u)", count,
                        UINT32_MAX / 8u);
    Sppm *job = calloc(1, sizeof *job);
    if (!job) return cst_fail(err, CST_ERR_OOM, "out of memory for SPPM state");
    *out = job;
    job->s = s;
    job->cam = cam;
    job->sp = *sp;
    job->sp.cam = cam;
    job->count = count;
    job->photons = sp->photons > 0 ? sp->photons : (int)(count < (size_t)1 << 30 ? count : (size_t)1 << 30);
    const int threads = sp->threads > 0 ? sp->threads : 1;
    CstStatus st = initial_radius(s, cam, sp, job->photons, &job->r0, &job->prepare_rays, err);
    if (st != CST_OK) return st;
    SppmGrid *g = &job->g;
    g->buckets = 1;
    while (g->buckets < count && g->buckets < (1u << 30)) g->buckets <<= 1;
    filter_init(&job->filter, sp->filter);
    job->chunks = sppm_photon_chunks(job->photons, count);
    if (sp->split && !(0 <= sp->split->chunk_lo && sp->split->chunk_lo <= sp->split->chunk_hi &&
                       sp->split->chunk_hi <= job->chunks && sp->split->fetch))
        return cst_fail(err, CST_ERR_INVALID_ARG, "photon split: chunks [%d, %d) of %d, fetch %s: expected a range "
                        "of the iteration's chunks and a fetch function", sp->split->chunk_lo, sp->split->chunk_hi,
                        job->chunks, sp->split->fetch ? "set" : "NULL");
    /* Several pixel ranges per thread, so a range crowded with photons does not hold the
     * others up; one thread needs one range. */
    const int ranges = threads == 1 ? 1 : 8 * threads;
    job->ranges = count < (size_t)ranges ? (int)count : ranges;
    job->num_workers = workers;
    job->workers = calloc((size_t)workers, sizeof *job->workers);
    job->px = calloc(count, sizeof *job->px);
    job->hits = calloc((size_t)job->chunks, sizeof *job->hits);
    g->cell_start = malloc(((size_t)g->buckets + 1u) * sizeof *g->cell_start);
    g->discs = malloc(count * sizeof *g->discs);
    if (!job->workers || !job->px || !job->hits || !g->cell_start || !g->discs)
        return cst_fail(err, CST_ERR_OOM, "out of memory for SPPM state (%zu pixels)", count);
    for (size_t i = 0; i < count; i++) job->px[i].r = job->px[i].r_vol = job->r0;
    return CST_OK;
}

/* A split's other chunks, in chunk order, from its fetch (serial, before the deposit):
 * each hit unpacked as sppm_trace_chunk packed it and given its bucket as photon_chunk
 * gives it, so the deposit sees the lists a one-process photon phase makes, bit for bit.
 * 0, -1 on OOM, -2 when fetch fails. */
static int fetch_chunks(SppmJob *job)
{
    const CstPhotonSplit *sp = job->sp.split;
    for (int c = 0; c < job->chunks; c++) {
        if (c >= sp->chunk_lo && c < sp->chunk_hi) continue;
        SppmHitList *l = &job->hits[c];
        const float *f = NULL;
        size_t n = 0;
        l->n = 0;
        if (sp->fetch(sp->user, job->iter, c, &f, &n) != 0) return -2; /* n: floats */
        if ((n > 0 && !f) || n % SPPM_HIT_FLOATS != 0) return -2;
        for (size_t i = 0; i < n / SPPM_HIT_FLOATS; i++, f += SPPM_HIT_FLOATS) {
            Color power;
            for (int k = 0; k < COLOR_LANES; k++) power.c[k] = f[9 + k];
            hit_list_push(l, v3(f[0], f[1], f[2]), v3(f[3], f[4], f[5]), v3(f[6], f[7], f[8]), power, 0);
            if (l->oom) return -1;
            l->v[l->n - 1].key = sppm_grid_bucket(&job->g, l->v[l->n - 1].p);
        }
    }
    return 0;
}

int sppm_photon_chunks(int photons, size_t pixels)
{
    const int64_t n = photons > 0 ? photons : (int64_t)(pixels < (size_t)1 << 30 ? pixels : (size_t)1 << 30);
    return (int)((n + SPPM_PHOTON_CHUNK - 1) / SPPM_PHOTON_CHUNK);
}

bool sppm_trace_chunk(const Scene *s, const SppmParams *sp, int iter, int chunk, float **hits, size_t *count,
                      size_t *cap, uint64_t *rays)
{
    SppmHitList l = {0};
    const int first = chunk * SPPM_PHOTON_CHUNK;
    const int last = first + SPPM_PHOTON_CHUNK < sp->photons ? first + SPPM_PHOTON_CHUNK : sp->photons;
    if (s->emitter_sampler.lights > 0 || sp->media_lights)
        for (int i = first; i < last; i++) trace_photon(s, sp, &l, (uint64_t)i, iter, rays);
    bool ok = !l.oom && array_grow(hits, cap, *count + l.n * SPPM_HIT_FLOATS, sizeof **hits);
    for (size_t i = 0; ok && i < l.n; i++) {
        const SppmHit *h = &l.v[i];
        float *o = *hits + *count + i * SPPM_HIT_FLOATS;
        o[0] = h->p.x, o[1] = h->p.y, o[2] = h->p.z;
        o[3] = h->wi.x, o[4] = h->wi.y, o[5] = h->wi.z;
        o[6] = h->n.x, o[7] = h->n.y, o[8] = h->n.z;
        for (int k = 0; k < COLOR_LANES; k++) o[9 + k] = h->power.c[k];
    }
    if (ok) *count += l.n * SPPM_HIT_FLOATS;
    free(l.v);
    return ok;
}

int sppm_phase_begin(Sppm *job, int iter, int phase)
{
    job->iter = iter;
    job->phase = (SppmPhase)phase;
    switch (job->phase) {
    case SPPM_PHASE_CAMERA: return job->cam->height;
    case SPPM_PHASE_PHOTONS:
        /* Serial, and cheap next to the passes: a counting sort over the pixels. */
        sppm_grid_build(&job->g, job->px, job->count);
        if (job->s->emitter_sampler.lights > 0 || job->sp.media_lights)
            return job->sp.split ? job->sp.split->chunk_hi - job->sp.split->chunk_lo : job->chunks;
        for (int c = 0; c < job->chunks; c++) job->hits[c].n = 0;
        return 0;
    case SPPM_PHASE_DEPOSIT:
        if (job->sp.split) {
            int f = fetch_chunks(job);
            if (f < 0) return f;
        }
        for (int c = 0; c < job->chunks; c++)
            if (job->hits[c].oom) return -1;
        /* Serial, like the grid build: a counting sort over the hits. */
        if (!grid_sort_hits(job)) return -1;
        return job->ranges;
    }
    return 0;
}

void sppm_finish(const Sppm *job, Film *film, int iter)
{
    /* The final estimate as the film's single sample (see sppm.h). */
    const double n_emitted = (double)job->photons * (double)iter;
    for (size_t i = 0; i < job->count; i++) {
        const SppmPixel *v = &job->px[i];
        double area = (double)CST_PI * (double)v->r * (double)v->r;
        double L[3];
        for (int c = 0; c < 3; c++) L[c] = v->ld[c] / iter + (n_emitted > 0.0 ? v->tau[c] / (n_emitted * area) : 0.0);
        if (scene_has_media(job->s) && n_emitted > 0.0) { /* the balls of the visible points in media */
            double rv = (double)v->r_vol, volume = 4.0 / 3.0 * (double)CST_PI * rv * rv * rv;
            for (int c = 0; c < 3; c++) L[c] += v->tau_vol[c] / (n_emitted * volume);
        }
        film_accumulate(film, (int)i, L[0], L[1], L[2]);
    }
    film->spp = 1;
    /* The image, no longer a state: a checkpoint of it would pair one sample with the
     * state of `iter` iterations. */
    free(film->progressive);
    film->progressive = NULL;
}

/* Film.progressive per pixel: Ld sums (3), tau (3), N, r, then the volume statistic's tau
 * (3), N, r; every value exactly (r is a float, exact as a double), so a resumed render
 * continues the same arithmetic. */
bool sppm_export(const Sppm *job, Film *film)
{
    if (!film->progressive &&
        !(film->progressive = malloc(job->count * FILM_PROGRESSIVE_STRIDE * sizeof *film->progressive)))
        return false;
    for (size_t i = 0; i < job->count; i++) {
        const SppmPixel *v = &job->px[i];
        double *o = &film->progressive[FILM_PROGRESSIVE_STRIDE * i];
        for (int c = 0; c < 3; c++) o[c] = v->ld[c], o[3 + c] = v->tau[c];
        o[6] = v->n_photons;
        o[7] = (double)v->r;
        for (int c = 0; c < 3; c++) o[8 + c] = v->tau_vol[c];
        o[11] = v->n_vol;
        o[12] = (double)v->r_vol;
    }
    return true;
}

bool sppm_import(Sppm *job, const Film *film)
{
    if (!film->progressive || (size_t)film->width * (size_t)film->height != job->count) return false;
    for (size_t i = 0; i < job->count; i++) {
        SppmPixel *v = &job->px[i];
        const double *o = &film->progressive[FILM_PROGRESSIVE_STRIDE * i];
        /* A radius must be what a float held, positive and finite: the file's checksum
         * matched, but the values are checked before they are trusted anyway. */
        for (int k = 6; k <= 11; k += 5)
            if (!(o[k + 1] > 0.0) || !isfinite(o[k + 1]) || (double)(float)o[k + 1] != o[k + 1] || !(o[k] >= 0.0) ||
                !isfinite(o[k]))
                return false;
        for (int c = 0; c < 3; c++) v->ld[c] = o[c], v->tau[c] = o[3 + c], v->tau_vol[c] = o[8 + c];
        v->n_photons = o[6];
        v->r = (float)o[7];
        v->n_vol = o[11];
        v->r_vol = (float)o[12];
    }
    return true;
}

void sppm_counters(const Sppm *job, uint64_t *rays, uint64_t *nonfinite)
{
    *rays += job->prepare_rays;
    if (job->workers)
        for (int i = 0; i < job->num_workers; i++) {
            *rays += job->workers[i].rays;
            *nonfinite += job->workers[i].nonfinite;
        }
}

void sppm_destroy(Sppm *job)
{
    if (!job) return;
    if (job->hits)
        for (int c = 0; c < job->chunks; c++) free(job->hits[c].v), free(job->hits[c].origin.v);
    free(job->sorted_origin.v);
    free(job->hits);
    free(job->workers);
    free(job->px);
    free(job->g.cell_start);
    free(job->g.hits);
    free(job->g.discs);
    free(job);
}
