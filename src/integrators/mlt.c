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
    Ray ray = camera_generate_ray(cam, fp->x, fp->y, ul);
    Wavelengths wl, *wlp = NULL;
    if (m->p.spectral) {
        wl = wavelengths_sample(sampler_1d(&smp));
        wlp = &wl;
    }
    Color L = path_li(s, &m->p.path, ray, &smp, wlp, rays);
    if (wlp) L = spectrum_to_rgb(L, wlp);
    return L;
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
                       uint64_t *rays)
{
    Sampler smp = sampler_pss(pss);
    pss_start_stream(pss, 0);
    int n_strategies = 1, sl = 0; /* pbrt's s: light vertices, the one on the emitter included */
    if (depth > 0) {
        n_strategies = depth + 2;
        sl = (int)(sampler_1d(&smp) * (float)n_strategies);
        if (sl > n_strategies - 1) sl = n_strategies - 1;
    }
    const int tc = depth + 2 - sl; /* pbrt's t: camera vertices, the camera included */
    Vec2 uf = sampler_2d(&smp);
    Vec2 ul = sampler_2d(&smp);
    *fp = v2(uf.x * domain_w(m) - m->p.margin, uf.y * domain_h(m) - m->p.margin);
    Wavelengths wl, *wlp = NULL;
    if (m->p.spectral) {
        wl = wavelengths_sample(sampler_1d(&smp));
        wlp = &wl;
    }
    const SubpathParams *vp = &m->p.sub;
    const SubpathIteration *it = &m->p.it;
    Color L = color_s(0.0f);
    SubpathVertex y;
    Wavelengths walk_wl;
    if (tc == 1) {
        /* The light tracer's strategy: y, d bounces from the emitter, to a lens point. Its
         * splat is per unit film (one light path per pixel of the W x H film, as
         * subpath_trace_light's), the camera strategies' per unit of the chains' domain:
         * W H / domain area converts. */
        pss_start_stream(pss, 1);
        if (!subpath_light_vertex(s, vp, it, sl - 1, &smp, wlp, &y, &walk_wl, rays)) return L;
        pss_start_stream(pss, 2);
        Vec2 u_lens = sampler_2d(&smp);
        Color rgb;
        if (!subpath_connect_camera(s, cam, vp, it, &y, u_lens, wlp, wlp ? &walk_wl : NULL, fp, &rgb, rays)) return L;
        const double film = (double)m->p.width * (double)m->p.height;
        return color_scale(rgb, (float)((double)n_strategies * film / ((double)domain_w(m) * (double)domain_h(m))));
    }
    Ray ray = camera_generate_ray(cam, fp->x, fp->y, ul);
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
        if (subpath_light_vertex(s, vp, it, sl - 1, &smp, wlp, &y, &walk_wl, rays)) {
            L = subpath_connect_pair(s, it, &x, &y, wlp, rays);
            if (wlp && (x.dispersed || y.dispersed)) L = subpath_hero_only(L);
        }
    }
    if (wlp) L = spectrum_to_rgb(L, wlp);
    return color_scale(L, (float)n_strategies);
}

/* The state's estimate (pssmlt: the path tracer's; mmlt: one strategy of the chain's path
 * length) and its film position; a NaN/Inf estimate counts as a zero one. */
static Color mlt_eval(const Mlt *m, const Scene *s, const Camera *cam, PssSampler *pss, int depth, Vec2 *fp,
                      uint64_t *rays, uint64_t *nonfinite)
{
    Color L = m->p.depths > 0 ? mmlt_eval(m, s, cam, pss, depth, fp, rays) : path_eval(m, s, cam, pss, fp, rays);
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
        Color L = mlt_eval(m, s, cam, &pss, boot_depth(m, i), &fp, rays, nonfinite);
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
    ch->L = mlt_eval(m, s, cam, &ch->pss, ch->depth, &ch->fp, rays, nonfinite);
    ch->I = mlt_importance(ch->L);
    pss_accept(&ch->pss);
    /* Its mutations from a stream of its own: two chains that picked the same bootstrap
     * path then still move independently. */
    ch->pss.rng = chain_stream(m, c, 2);
}

void mlt_chain_run(Mlt *m, const Scene *s, const Camera *cam, int c, int mutations, SplatList *out,
                   const SplatFrame *fr, uint64_t *rays, uint64_t *nonfinite)
{
    MltChain *ch = &m->chains[c];
    if (!(ch->I > 0.0f)) return;
    for (int k = 0; k < mutations; k++) {
        pss_start_iteration(&ch->pss);
        Vec2 fp;
        Color L = mlt_eval(m, s, cam, &ch->pss, ch->depth, &fp, rays, nonfinite);
        float I = mlt_importance(L);
        /* Metropolis acceptance with a symmetric proposal (Kelemen et al. eq. 7). */
        float a = I >= ch->I ? 1.0f : I / ch->I;
        if (a > 0.0f) film_splat(out, fr, fp.x, fp.y, color_scale(L, a / I));
        if (a < 1.0f) film_splat(out, fr, ch->fp.x, ch->fp.y, color_scale(ch->L, (1.0f - a) / ch->I));
        if (pcg32_float(&ch->accept_rng) < a) {
            pss_accept(&ch->pss);
            ch->fp = fp;
            ch->L = L;
            ch->I = I;
        } else {
            pss_reject(&ch->pss);
        }
    }
    if (ch->pss.oom) out->oom = 1;
}
