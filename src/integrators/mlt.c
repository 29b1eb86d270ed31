/* Primary-sample-space MLT over the path tracer (mlt.h). Estimator (Kelemen et al. 2002;
 * Veach's thesis sec. 11.3): with I(x) the scalar contribution of the path tracer's sample
 * x and b = integral of I over the film domain, a chain distributed as I / b gives pixel
 * j the estimate (b / N) sum_i h_j(x_i) L(x_i) / I(x_i) over its N mutations; each step
 * adds both the proposal y (weight a) and the current state x (weight 1 - a), with the
 * acceptance a = min(1, I(y) / I(x)) (the PSS proposals are symmetric). b is estimated by
 * bootstrap paths drawn independently of the chains' mutations, as pbrt-v4 does. */
#include "integrators/mlt.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"

#include "integrators/recorder.h"
#include "integrators/subpath_media.h"
#include "sampling/sampler.h"

/* Streams of the render seed, apart from every other integrator's. */
#define MLT_BOOT_KEY 0x8f1bbcdc3c6ef372ULL
#define MLT_CHAIN_KEY 0xa54ff53a510e527fULL

Mlt *mlt_create(const MltParams *p)
{
    Mlt *m = calloc(1, sizeof *m);
    if (!m) return NULL;
    m->p = *p;
    m->boot_I = calloc((size_t)p->bootstrap, sizeof *m->boot_I);
    m->boot_cdf = calloc((size_t)p->bootstrap + 1, sizeof *m->boot_cdf);
    m->chains = aligned_alloc(_Alignof(MltChain), (size_t)p->chains * sizeof *m->chains);
    if (!m->boot_I || !m->boot_cdf || !m->chains) {
        mlt_destroy(m);
        return NULL;
    }
    for (int c = 0; c < p->chains; c++) m->chains[c] = (MltChain){0};
    return m;
}

void mlt_destroy(Mlt *m)
{
    if (!m) return;
    if (m->chains)
        for (int c = 0; c < m->p.chains; c++) pss_free(&m->chains[c].pss);
    free(m->chains);
    free(m->boot_I);
    free(m->boot_cdf);
    free(m);
}

/* The film domain the chains explore: the image and the margin its filter reaches. */
static float domain_w(const Mlt *m) { return (float)m->p.width + 2.0f * m->p.margin; }
static float domain_h(const Mlt *m) { return (float)m->p.height + 2.0f * m->p.margin; }

/* The path tracer's sample for the PSS state: film position, lens and (spectral) the
 * wavelengths from the first dimensions, as camera_tile draws them, then path_li reading
 * the rest through the same Sampler type. */
static Color path_eval(const Mlt *m, const Scene *s, const Camera *cam, PssSampler *pss, Vec2 *fp, uint64_t *rays)
{
    Sampler smp = sampler_pss(pss);
    pss_start_stream(pss, 0);
    Vec2 uf = sampler_2d(&smp);
    Vec2 ul = sampler_2d(&smp);
    *fp = v2(uf.x * domain_w(m) - m->p.margin, uf.y * domain_h(m) - m->p.margin);
    Wavelengths wl, *wlp = NULL;
    if (m->p.spectral) {
        wl = wavelengths_sample(sampler_1d(&smp));
        wlp = &wl;
    }
    /* Motion blur: the path's time, one more primary-sample dimension (mutated as the
     * others) mapped through the shutter, the camera placed there; drawn only in scenes
     * that move, so static ones keep their dimensions. */
    const float time = scene_has_motion(s) ? camera_time(cam, sampler_1d(&smp)) : 0.0f;
    Ray ray = camera_generate_ray_at(cam, fp->x, fp->y, ul, time);
    Color L = path_li(s, &m->p.path, ray, &smp, wlp, rays);
    if (wlp) L = spectrum_to_rgb(L, wlp);
    return L;
}

/* mmlt's strategy (below) in a scene with media: the same streams and weights through
 * subpath_media.c's single strategies, which cross media and boundaries as BDPT's
 * connections there do (transmittance on every connection, volume vertices on both
 * subpaths). smp reads pss; sl, n_strategies and the film position as mmlt_eval drew them. */
static Color mmlt_eval_media(const Mlt *m, const Scene *s, const Camera *cam, PssSampler *pss, Sampler *smp,
                             int depth, int sl, int n_strategies, Vec2 *fp, Vec2 ul, float time,
                             const Wavelengths *wlp, uint64_t *rays)
{
    const SubpathParams *vp = &m->p.sub;
    const SubpathIteration *it = &m->p.it;
    const int tc = depth + 2 - sl;
    Color L = color_s(0.0f);
    if (tc == 1) {
        /* The lens point first (its own stream: the order of streams changes no value). */
        pss_start_stream(pss, 2);
        Vec2 u_lens = sampler_2d(smp);
        pss_start_stream(pss, 1);
        Color rgb;
        if (!media_subpath_connect_camera(s, cam, vp, it, sl - 1, smp, time, u_lens, wlp, fp, &rgb, rays)) return L;
        const double film = (double)m->p.width * (double)m->p.height;
        return color_scale(rgb, (float)((double)n_strategies * film / ((double)domain_w(m) * (double)domain_h(m))));
    }
    Ray ray = camera_generate_ray(cam, fp->x, fp->y, ul);
    ray.time = time;
    MediaCameraVertex x;
    Color emitted;
    bool found = media_subpath_camera_vertex(s, cam, vp, it, ray, tc - 1, sl == 0, smp, wlp, &x, &emitted, rays);
    if (sl == 0) {
        L = emitted;
    } else if (found && sl == 1) {
        pss_start_stream(pss, 2);
        L = media_subpath_connect_light(s, it, &x, smp, wlp, rays);
        if (wlp && x.dispersed) L = subpath_hero_only(L);
    } else if (found) {
        pss_start_stream(pss, 1);
        SubpathVertex y;
        Wavelengths walk_wl;
        if (media_subpath_light_vertex(s, cam, vp, it, sl - 1, smp, time, wlp, &y, &walk_wl, rays)) {
            L = media_subpath_connect_pair(s, it, &x, &y, wlp, rays);
            if (wlp && (x.dispersed || y.dispersed)) L = subpath_hero_only(L);
        }
    }
    if (wlp) L = spectrum_to_rgb(L, wlp);
    return color_scale(L, (float)n_strategies);
}

/* mmlt: the state's one BDPT strategy of path length `depth` (Hachisuka et al. 2014 sec. 4,
 * pbrt-v4's MLTIntegrator::L), from three streams of the PSS vector: the camera stream
 * (the strategy, film position, lens, wavelengths, then the camera subpath), the light
 * stream (the light subpath) and the connection stream (NEE's or the lens point's
 * sample). A length of d bounces has d + 2 strategies (s = 0 .. d + 1 light vertices), one
 * at d = 0 (the emitter seen directly; s = 1, t = 1 is not a strategy, as in BDPT), picked
 * uniformly: the estimate is (d + 2) times that strategy's MIS-weighted contribution, its
 * expectation BDPT's estimate of the length. RGB (spectral: converted with the path's
 * wavelengths). */
static Color mmlt_eval(const Mlt *m, const Scene *s, const Camera *cam, PssSampler *pss, int depth, Vec2 *fp,
                       int *strategy, uint64_t *rays)
{
    Sampler smp = sampler_pss(pss);
    pss_start_stream(pss, 0);
    int n_strategies = 1, sl = 0; /* pbrt's s: light vertices, the one on the emitter included */
    if (depth > 0) {
        n_strategies = depth + 2;
        sl = (int)(sampler_1d(&smp) * (float)n_strategies);
        if (sl > n_strategies - 1) sl = n_strategies - 1;
    }
    *strategy = sl;
    const int tc = depth + 2 - sl; /* pbrt's t: camera vertices, the camera included */
    Vec2 uf = sampler_2d(&smp);
    Vec2 ul = sampler_2d(&smp);
    *fp = v2(uf.x * domain_w(m) - m->p.margin, uf.y * domain_h(m) - m->p.margin);
    Wavelengths wl, *wlp = NULL;
    if (m->p.spectral) {
        wl = wavelengths_sample(sampler_1d(&smp));
        wlp = &wl;
    }
    /* Motion blur: the path's one time, a dimension of the camera stream (mutated as the
     * others) mapped through the shutter, that both subpaths and every connection carry,
     * also for t = 1 where no camera ray is traced but the lens point, W_e and its pdf are
     * the camera's placed at that time; drawn only in scenes that move. */
    const float time = scene_has_motion(s) ? camera_time(cam, sampler_1d(&smp)) : 0.0f;
    Camera placed;
    if (cam->moving) {
        placed = camera_at(cam, time);
        cam = &placed;
    }
    const SubpathParams *vp = &m->p.sub;
    const SubpathIteration *it = &m->p.it;
    if (s->num_media | s->num_medium_ifaces)
        return mmlt_eval_media(m, s, cam, pss, &smp, depth, sl, n_strategies, fp, ul, time, wlp, rays);
    Color L = color_s(0.0f);
    SubpathVertex y;
    Wavelengths walk_wl;
    if (tc == 1) {
        /* The light tracer's strategy: y, d bounces from the emitter, to a lens point. Its
         * splat is per unit film (one light path per pixel of the W x H film, as
         * subpath_trace_light's), the camera strategies' per unit of the chains' domain:
         * W H / domain area converts. */
        pss_start_stream(pss, 1);
        if (!subpath_light_vertex(s, vp, it, sl - 1, &smp, time, wlp, &y, &walk_wl, rays)) return L;
        pss_start_stream(pss, 2);
        Vec2 u_lens = sampler_2d(&smp);
        Color rgb;
        if (!subpath_connect_camera(s, cam, vp, it, &y, u_lens, time, wlp, wlp ? &walk_wl : NULL, fp, &rgb, rays))
            return L;
        const double film = (double)m->p.width * (double)m->p.height;
        return color_scale(rgb, (float)((double)n_strategies * film / ((double)domain_w(m) * (double)domain_h(m))));
    }
    Ray ray = camera_generate_ray(cam, fp->x, fp->y, ul);
    ray.time = time;
    SubpathCameraVertex x;
    Color emitted;
    bool found = subpath_camera_vertex(s, cam, vp, it, ray, tc - 1, sl == 0, &smp, wlp, &x, &emitted, rays);
    if (sl == 0) {
        L = emitted;
    } else if (found && sl == 1) {
        pss_start_stream(pss, 2);
        L = subpath_connect_light(s, it, &x, &smp, wlp, rays);
        if (wlp && x.dispersed) L = subpath_hero_only(L);
    } else if (found) {
        pss_start_stream(pss, 1);
        if (subpath_light_vertex(s, vp, it, sl - 1, &smp, time, wlp, &y, &walk_wl, rays)) {
            L = subpath_connect_pair(s, it, &x, &y, wlp, rays);
            if (wlp && (x.dispersed || y.dispersed)) L = subpath_hero_only(L);
        }
    }
    if (wlp) L = spectrum_to_rgb(L, wlp);
    return color_scale(L, (float)n_strategies);
}

/* The state's estimate (pssmlt: the path tracer's; mmlt: one strategy of the chain's path
 * length, its light vertices s in *strategy, -1 for pssmlt) and its film position; a
 * NaN/Inf estimate counts as a zero one. */
static Color mlt_eval(const Mlt *m, const Scene *s, const Camera *cam, PssSampler *pss, int depth, Vec2 *fp,
                      int *strategy, uint64_t *rays, uint64_t *nonfinite)
{
    *strategy = -1;
    Color L = m->p.depths > 0 ? mmlt_eval(m, s, cam, pss, depth, fp, strategy, rays)
                              : path_eval(m, s, cam, pss, fp, rays);
    if (!color_is_finite(L) || !isfinite(mlt_importance(L))) {
        ++*nonfinite;
        return color_s(0.0f);
    }
    return L;
}

/* Streams interleaved in a state: mmlt's camera, light and connection; pssmlt's one. */
static int stream_count(const Mlt *m) { return m->p.depths > 0 ? 3 : 1; }

/* The path length of bootstrap path i (mmlt; 0 for pssmlt). */
static int boot_depth(const Mlt *m, int i) { return m->p.depths > 0 ? i % m->p.depths : 0; }

static Pcg32 boot_stream(const Mlt *m, int i)
{
    Pcg32 r;
    pcg32_seed_sample(&r, m->p.seed ^ MLT_BOOT_KEY, (uint64_t)i, 0);
    return r;
}

/* Stream k of chain c: 0 its start, 1 its acceptance draws, 2 its mutations. */
static Pcg32 chain_stream(const Mlt *m, int c, int k)
{
    Pcg32 r;
    pcg32_seed_sample(&r, m->p.seed ^ MLT_CHAIN_KEY, (uint64_t)c, (uint64_t)k);
    return r;
}

void mlt_bootstrap_item(Mlt *m, const Scene *s, const Camera *cam, int item, uint64_t *rays, uint64_t *nonfinite)
{
    int first = item * MLT_BOOTSTRAP_CHUNK;
    int last = first + MLT_BOOTSTRAP_CHUNK < m->p.bootstrap ? first + MLT_BOOTSTRAP_CHUNK : m->p.bootstrap;
    PssSampler pss;
    /* Large-step probability 1: every value of the path is a fresh uniform. */
    pss_init(&pss, boot_stream(m, first), m->p.sigma, 1.0f, stream_count(m));
    for (int i = first; i < last; i++) {
        pss_restart(&pss, boot_stream(m, i));
        pss_start_iteration(&pss);
        Vec2 fp;
        int strategy;
        Color L = mlt_eval(m, s, cam, &pss, boot_depth(m, i), &fp, &strategy, rays, nonfinite);
        m->boot_I[i] = pss.oom ? 0.0f : mlt_importance(L);
    }
    pss_free(&pss);
}

void mlt_bootstrap_finish(Mlt *m)
{
    double sum = 0.0;
    m->boot_cdf[0] = 0.0;
    for (int i = 0; i < m->p.bootstrap; i++) {
        sum += (double)m->boot_I[i];
        m->boot_cdf[i + 1] = sum;
    }
    /* b = area x mean I: the bootstrap paths are uniform over the film domain. mmlt: b is
     * the sum over path lengths of each length's mean, with bootstrap / depths paths each
     * (pbrt-v4's MLTIntegrator). */
    m->mean_I = sum / (double)m->p.bootstrap;
    if (m->p.depths > 0) m->mean_I *= (double)m->p.depths;
    /* Every mutation splats importance a + (1 - a) = 1 in all (mlt_chain_run), so with the
     * box filter the image's mean luminance is this b / (W H) exactly: the render's overall
     * brightness error is the bootstrap's alone (docs/integrators.md, mmlt); the chains
     * only spread it over the pixels. */
}

double mlt_splat_scale(const Mlt *m)
{
    return m->mean_I * (double)domain_w(m) * (double)domain_h(m) / ((double)m->p.width * (double)m->p.height);
}

void mlt_chain_start(Mlt *m, const Scene *s, const Camera *cam, int c, uint64_t *rays, uint64_t *nonfinite)
{
    MltChain *ch = &m->chains[c];
    pss_free(&ch->pss);
    *ch = (MltChain){0};
    ch->accept_rng = chain_stream(m, c, 1);
    const double total = m->boot_cdf[m->p.bootstrap];
    if (!(total > 0.0)) return; /* a black image: no chain runs (mlt_chain_run) */
    /* The bootstrap path with cdf[i] <= u total < cdf[i + 1]: picked with probability
     * I_i / total, never one with I_i = 0. */
    Pcg32 r = chain_stream(m, c, 0);
    double target = (double)pcg32_float(&r) * total;
    int lo = 0, hi = m->p.bootstrap - 1;
    while (lo < hi) {
        int mid = lo + (hi - lo) / 2;
        if (m->boot_cdf[mid + 1] <= target) lo = mid + 1;
        else hi = mid;
    }
    /* Rebuild that path's state from its stream: the same draws give the same path. */
    /* mmlt: the chain keeps that path's length; picking paths in proportion to I over
     * every length gives each length chains in proportion to its b_d (Hachisuka et al.
     * 2014, as pbrt-v4). */
    ch->depth = boot_depth(m, lo);
    pss_init(&ch->pss, boot_stream(m, lo), m->p.sigma, m->p.large_step_prob, stream_count(m));
    pss_start_iteration(&ch->pss);
    ch->pss.large_step = true;
    ch->L = mlt_eval(m, s, cam, &ch->pss, ch->depth, &ch->fp, &ch->strategy, rays, nonfinite);
    ch->I = mlt_importance(ch->L);
    pss_accept(&ch->pss);
    /* Its mutations from a stream of its own: two chains that picked the same bootstrap
     * path then still move independently. */
    ch->pss.rng = chain_stream(m, c, 2);
}

bool mlt_replay(const Mlt *m, const Scene *s, const Camera *cam, const double *v, size_t n, int depth,
                struct Recorder *rec, Color *L, int *strategy)
{
    PssSampler pss;
    if (!pss_replay_init(&pss, v, n, stream_count(m))) return false;
    /* The same parameters with the recorder on: the path tracer's (pssmlt) or the BDPT
     * strategies' (mmlt), whose hooks change no value. */
    Mlt r = *m;
    r.p.path.rec = rec;
    r.p.it.rec = rec;
    r.rec = NULL;
    Vec2 fp;
    uint64_t rays = 0, nonfinite = 0;
    *L = mlt_eval(&r, s, cam, &pss, depth < 0 ? 0 : depth, &fp, strategy, &rays, &nonfinite);
    pss_free(&pss);
    return true;
}

void mlt_chain_run(Mlt *m, const Scene *s, const Camera *cam, int c, int mutations, SplatList *out,
                   const SplatFrame *fr, uint64_t *rays, uint64_t *nonfinite)
{
    MltChain *ch = &m->chains[c];
    if (!(ch->I > 0.0f)) return;
    for (int k = 0; k < mutations; k++) {
        pss_start_iteration(&ch->pss);
        Vec2 fp;
        int strategy;
        Color L = mlt_eval(m, s, cam, &ch->pss, ch->depth, &fp, &strategy, rays, nonfinite);
        float I = mlt_importance(L);
        /* Metropolis acceptance with a symmetric proposal (Kelemen et al. eq. 7). */
        float a = I >= ch->I ? 1.0f : I / ch->I;
        const size_t n0 = out->n;
        if (a > 0.0f) film_splat(out, fr, fp.x, fp.y, color_scale(L, a / I));
        const size_t n1 = out->n;
        if (a < 1.0f) film_splat(out, fr, ch->fp.x, ch->fp.y, color_scale(ch->L, (1.0f - a) / ch->I));
        const bool accept = pcg32_float(&ch->accept_rng) < a;
        if (m->rec) {
            /* Each splat with its index in `out` (-1: none was added), the film's order. */
            const RecorderMltSplat sp[2] = {
                {fp, L, I, a > 0.0f ? a / I : 0.0f, n1 > n0 ? (long)n0 : -1, strategy},
                {ch->fp, ch->L, ch->I, (1.0f - a) / ch->I, out->n > n1 ? (long)n1 : -1, ch->strategy}};
            recorder_mlt_step(m->rec, c, k, m->p.depths > 0 ? ch->depth : -1, ch->pss.large_step, accept, a, sp,
                              &ch->pss);
        }
        if (accept) {
            pss_accept(&ch->pss);
            ch->fp = fp;
            ch->L = L;
            ch->I = I;
            ch->strategy = strategy;
        } else {
            pss_reject(&ch->pss);
        }
    }
    if (ch->pss.oom) out->oom = 1;
}

/* ---- Checkpoints: the chains as bytes (docs/state-format.md, version 4), little-endian.
 * Everything a chain carries from one iteration to the next: its PSS vector (every
 * coordinate's value and date, and the backups pss_reject restores from), its mutation
 * and acceptance streams, its current sample (film position, radiance, I) and path length;
 * and b (mean_I). The bootstrap's arrays are not needed once the chains have started. */

enum { MLT_STATE_HEAD = 16, MLT_STATE_CHAIN = 88, MLT_STATE_VALUE = 32 };

static unsigned char *put_u64(unsigned char *o, uint64_t v, int bytes)
{
    for (int k = 0; k < bytes; k++) o[k] = (unsigned char)(v >> (8 * k));
    return o + bytes;
}
static unsigned char *put_f64(unsigned char *o, double v)
{
    uint64_t b;
    memcpy(&b, &v, sizeof b);
    return put_u64(o, b, 8);
}
static unsigned char *put_f32(unsigned char *o, float v)
{
    uint32_t b;
    memcpy(&b, &v, sizeof b);
    return put_u64(o, b, 4);
}
static uint64_t get_u64(const unsigned char **p, int bytes)
{
    uint64_t v = 0;
    for (int k = 0; k < bytes; k++) v |= (uint64_t)(*p)[k] << (8 * k);
    *p += bytes;
    return v;
}
static double get_f64(const unsigned char **p)
{
    uint64_t b = get_u64(p, 8);
    double v;
    memcpy(&v, &b, sizeof v);
    return v;
}
static float get_f32(const unsigned char **p)
{
    uint32_t b = (uint32_t)get_u64(p, 4);
    float v;
    memcpy(&v, &b, sizeof v);
    return v;
}

size_t mlt_state_size(const Mlt *m)
{
    size_t n = MLT_STATE_HEAD;
    for (int c = 0; c < m->p.chains; c++) n += MLT_STATE_CHAIN + MLT_STATE_VALUE * m->chains[c].pss.n;
    return n;
}

bool mlt_state_write(const Mlt *m, unsigned char *out)
{
    if (!m->ready) return false;
    unsigned char *o = out;
    o = put_u64(o, (uint64_t)m->p.chains, 4);
    o = put_u64(o, (uint64_t)m->p.depths, 4);
    o = put_f64(o, m->mean_I);
    for (int c = 0; c < m->p.chains; c++) {
        const MltChain *ch = &m->chains[c];
        if (ch->pss.oom) return false; /* an invalid chain: no state rather than a wrong one */
        o = put_u64(o, (uint64_t)ch->depth, 4);
        o = put_u64(o, ch->accept_rng.state, 8);
        o = put_u64(o, ch->accept_rng.inc, 8);
        o = put_f32(o, ch->fp.x);
        o = put_f32(o, ch->fp.y);
        for (int k = 0; k < COLOR_LANES; k++) o = put_f32(o, ch->L.c[k]);
        o = put_f32(o, ch->I);
        o = put_u64(o, ch->pss.rng.state, 8);
        o = put_u64(o, ch->pss.rng.inc, 8);
        o = put_u64(o, (uint64_t)ch->pss.iteration, 8);
        o = put_u64(o, (uint64_t)ch->pss.last_large, 8);
        o = put_u64(o, (uint64_t)ch->pss.n, 8);
        for (size_t i = 0; i < ch->pss.n; i++) {
            const PssValue *v = &ch->pss.x[i];
            o = put_f64(o, v->value);
            o = put_f64(o, v->backup);
            o = put_u64(o, (uint64_t)v->modified, 8);
            o = put_u64(o, (uint64_t)v->modified_backup, 8);
        }
    }
    return (size_t)(o - out) == mlt_state_size(m);
}

/* A coordinate a chain can hold: in [0, 1], dated no later than the chain's iteration. */
static bool pss_value_ok(double v, int64_t modified, int64_t iteration)
{
    /* 1.0 itself: a small step's wrap (x - floor(x)) of a tiny negative x rounds to it. */
    return v >= 0.0 && v <= 1.0 && modified >= -1 && modified <= iteration;
}

bool mlt_state_read(Mlt *m, const unsigned char *in, size_t len)
{
    const unsigned char *p = in, *end = in + len;
    if (len < MLT_STATE_HEAD) return false;
    if (get_u64(&p, 4) != (uint64_t)m->p.chains || get_u64(&p, 4) != (uint64_t)m->p.depths) return false;
    const double mean_I = get_f64(&p);
    if (!(mean_I >= 0.0) || !isfinite(mean_I)) return false;
    const int lengths = m->p.depths > 0 ? m->p.depths : 1;
    for (int c = 0; c < m->p.chains; c++) {
        MltChain *ch = &m->chains[c];
        pss_free(&ch->pss);
        *ch = (MltChain){0};
        if ((size_t)(end - p) < MLT_STATE_CHAIN) return false;
        uint64_t depth = get_u64(&p, 4);
        if (depth >= (uint64_t)lengths) return false;
        ch->depth = (int)depth;
        ch->strategy = -1; /* not in the state: explain never resumes */
        ch->accept_rng.state = get_u64(&p, 8);
        ch->accept_rng.inc = get_u64(&p, 8);
        ch->fp.x = get_f32(&p);
        ch->fp.y = get_f32(&p);
        for (int k = 0; k < COLOR_LANES; k++) ch->L.c[k] = get_f32(&p);
        ch->I = get_f32(&p);
        Pcg32 rng;
        rng.state = get_u64(&p, 8);
        rng.inc = get_u64(&p, 8);
        pss_init(&ch->pss, rng, m->p.sigma, m->p.large_step_prob, stream_count(m));
        ch->pss.iteration = (int64_t)get_u64(&p, 8);
        ch->pss.last_large = (int64_t)get_u64(&p, 8);
        uint64_t n = get_u64(&p, 8);
        /* PCG's increments are odd (a chain with I = 0 never runs and has no mutation
         * stream); the sample finite, I its importance (mlt_chain_run divides by it); n
         * within what is left. */
        if (!(ch->accept_rng.inc & 1) || (ch->I > 0.0f && !(rng.inc & 1)) || !isfinite(ch->fp.x) ||
            !isfinite(ch->fp.y) || !color_is_finite(ch->L) || ch->I != mlt_importance(ch->L) || ch->pss.iteration < 0 ||
            ch->pss.last_large < 0 || ch->pss.last_large > ch->pss.iteration ||
            n > (uint64_t)(end - p) / MLT_STATE_VALUE)
            return false;
        if (n && !array_grow(&ch->pss.x, &ch->pss.cap, (size_t)n, sizeof *ch->pss.x)) return false;
        for (size_t i = 0; i < (size_t)n; i++) {
            PssValue *v = &ch->pss.x[i];
            v->value = get_f64(&p);
            v->backup = get_f64(&p);
            v->modified = (int64_t)get_u64(&p, 8);
            v->modified_backup = (int64_t)get_u64(&p, 8);
            if (!pss_value_ok(v->value, v->modified, ch->pss.iteration) ||
                !pss_value_ok(v->backup, v->modified_backup, ch->pss.iteration))
                return false;
        }
        ch->pss.n = (size_t)n;
    }
    if (p != end) return false;
    m->mean_I = mean_I;
    m->ready = true;
    return true;
}
