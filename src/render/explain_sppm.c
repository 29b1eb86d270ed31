/* cst_explain for sppm (issue 30): the render's iterations 0..I replayed (the whole image:
 * every pixel's visible point bounds the photon grid, and the photon pass is the image's),
 * iteration I of one pixel recorded (integrators/sppm.h, SppmTrace), then its value summed
 * again from the recorded events alone: the camera chain's emission and NEE, each gathered
 * photon's f Phi in the order the deposit added it, and Hachisuka & Jensen 2009's update
 * (eqs. 6-7, pbrt-v3 eq. 16.10), checked bit for bit against the film of I + 1 iterations. */
#include "render/explain_sppm.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "film/film.h"
#include "integrators/integrator.h"
#include "integrators/recorder.h"
#include "integrators/sppm.h"
#include "render/explain.h"

/* Events kept: the chain (at most PHOTON_MAX_SPECULAR vertices) and the photons of one
 * disc; a caustic's disc can hold more, then the record is truncated (and not checked). */
enum { EXPLAIN_SPPM_EVENTS = 1 << 16 };

/* The pixel's value summed again from r's events and the state before the iteration, as
 * camera_row, progressive_update and sppm_finish compute it; ex->sppm filled. */
static void replay(const Integrator *it, const Recorder *r, const SppmTrace *tr, int iteration, CstExplain *ex)
{
    struct CstExplainSppm *o = &ex->sppm;
    Color L = color_s(0.0f);
    double phi[COLOR_LANES] = {0.0};
    long m = 0;
    for (int i = 0; i < r->n; i++) {
        const CstExplainEvent *e = &r->ev[i];
        if (e->kind == CST_EXPLAIN_PHOTON) {
            for (int c = 0; c < COLOR_LANES; c++) phi[c] += (double)r->value[i].c[c];
            m++;
        } else if (e->flags & CST_EXPLAIN_ADDED) {
            L = color_madd(L, r->beta[i], r->value[i]); /* the chain's emission, NEE at x */
        }
    }
    if (it->spectral) L = spectrum_to_rgb(L, &tr->wl);
    if (!color_is_finite(L)) L = color_s(0.0f);
    /* The statistic the visible point updates: its disc's, or in a medium its ball's. */
    const SppmPixelState *b = &tr->before;
    const bool vol = tr->valid && tr->vol;
    const double *tau_b = vol ? b->tau_vol : b->tau, n_b = vol ? b->n_vol : b->n_photons;
    double tau[3], n = n_b, ld[3];
    float rad = vol ? b->r_vol : b->r;
    for (int c = 0; c < 3; c++) {
        ld[c] = b->ld[c] + (double)L.c[c];
        tau[c] = tau_b[c];
    }
    double w[3] = {(double)tr->beta.c[0], (double)tr->beta.c[1], (double)tr->beta.c[2]};
    if (tr->valid && m > 0) {
        if (it->spectral) { /* beta phi at the iteration's wavelengths, to RGB */
            Color bp;
            for (int c = 0; c < COLOR_LANES; c++) bp.c[c] = (float)((double)tr->beta.c[c] * phi[c]);
            const Color rgb = spectrum_to_rgb(bp, &tr->wl);
            for (int c = 0; c < 3; c++) phi[c] = (double)rgb.c[c], w[c] = 1.0;
        }
        /* HJ 2009 eq. 6, in 3D for a ball (progressive_update) */
        const double n_new = n + (double)SPPM_ALPHA * (double)m;
        double r_new, shrink;
        if (vol) {
            r_new = (double)rad * cbrt(n_new / (n + (double)m));
            shrink = r_new * r_new * r_new / ((double)rad * (double)rad * (double)rad);
        } else {
            r_new = (double)rad * sqrt(n_new / (n + (double)m));
            shrink = r_new * r_new / ((double)rad * (double)rad);
        }
        bool ok = true;
        for (int c = 0; c < 3; c++) ok &= isfinite(phi[c] * w[c]);
        if (ok) {
            for (int c = 0; c < 3; c++) tau[c] = (tau[c] + w[c] * phi[c]) * shrink;
            n = n_new;
            rad = (float)r_new;
        }
    }
    /* sppm_finish: the disc's estimate, and in scenes with media the ball's */
    const int iters = iteration + 1;
    o->emitted = (double)tr->photons * (double)iters;
    o->media = it->scene->num_media || it->scene->num_medium_ifaces;
    const double *tau_s = vol ? b->tau : tau, *tau_v = vol ? tau : b->tau_vol;
    const float r_s = vol ? b->r : rad, r_v = vol ? rad : b->r_vol;
    const double area = (double)CST_PI * (double)r_s * (double)r_s;
    const double rv = (double)r_v, volume = 4.0 / 3.0 * (double)CST_PI * rv * rv * rv;
    for (int c = 0; c < 3; c++) {
        o->value[c] = ld[c] / iters + (o->emitted > 0.0 ? tau_s[c] / (o->emitted * area) : 0.0);
        if (o->media && o->emitted > 0.0) o->value[c] += tau_v[c] / (o->emitted * volume);
        o->tau_other[c] = vol ? b->tau[c] : b->tau_vol[c];
        o->direct[c] = L.c[c];
        o->ld_before[c] = b->ld[c];
        o->ld_after[c] = ld[c];
        o->phi[c] = phi[c];
        o->tau_before[c] = tau_b[c];
        o->tau_after[c] = tau[c];
        o->beta[c] = tr->beta.c[c];
    }
    o->visible = tr->valid;
    o->volume = vol;
    o->r_other = vol ? b->r : b->r_vol;
    o->photons = tr->photons;
    o->m = m;
    o->n_before = n_b;
    o->n_after = n;
    o->r_before = vol ? b->r_vol : b->r;
    o->r_after = rad;
    const SppmPixelState *a = &tr->after;
    o->state_exact = m == tr->m && memcmp(&n, vol ? &a->n_vol : &a->n_photons, sizeof n) == 0 &&
                     rad == (vol ? a->r_vol : a->r) && memcmp(tau, vol ? a->tau_vol : a->tau, sizeof tau) == 0 &&
                     memcmp(ld, a->ld, sizeof ld) == 0;
}

/* Each event's share of the pixel's value: a photon's beta f Phi times the box kernel
 * 1 / (N_emitted pi r^2) of the radius it was gathered with (tau' / (N_e pi r'^2) holds
 * (tau + beta phi) / (N_e pi r^2)); the chain's emission and NEE over the I + 1 iterations
 * the direct sums are averaged over. Spectral: through the iteration's sensor conversion. */
static void shares(const Integrator *it, const Recorder *r, const SppmTrace *tr, int iteration, CstExplain *ex)
{
    /* box kernel of the disc 1 / (N_e pi r^2), or of the ball 1 / (N_e 4/3 pi r^3) */
    const double rad = (double)ex->sppm.r_before;
    const double kernel = !(ex->sppm.emitted > 0.0) ? 0.0
                          : ex->sppm.volume ? 1.0 / (ex->sppm.emitted * (4.0 / 3.0 * (double)CST_PI * rad * rad * rad))
                          : 1.0 / (ex->sppm.emitted * (double)CST_PI * rad * rad);
    for (int i = 0; i < r->n; i++) {
        CstExplainEvent *e = &r->ev[i];
        const bool photon = e->kind == CST_EXPLAIN_PHOTON;
        if (!photon && !(e->flags & CST_EXPLAIN_ADDED)) continue;
        Color v = photon ? color_mul(tr->beta, r->value[i]) : color_mul(r->beta[i], r->value[i]);
        if (it->spectral) v = spectrum_to_rgb(v, &tr->wl);
        const double k = photon ? kernel : 1.0 / (double)(iteration + 1);
        if (photon) e->pmf = (float)kernel;
        for (int c = 0; c < 3; c++) e->share[c] = (double)v.c[c] * k;
    }
}

CstStatus explain_sppm(const Scene *scene, const CstRenderSettings *settings, int x, int y, int iteration,
                       CstExplain **out, CstError *err)
{
    *out = NULL;
    CstRenderSettings st = *settings;
    /* The render of iteration + 1 iterations, whole, on one thread (the image does not
     * depend on the thread count, sppm.c). */
    st.threads = 1;
    st.first_sample = 0;
    st.spp = iteration + 1;
    st.crop[0] = 0; st.crop[1] = st.width; st.crop[2] = 0; st.crop[3] = st.height;
    st.aovs = 0;
    st.time_limit = 0.0;
    st.resume = NULL;
    st.pass_done = NULL;
    st.progress = NULL;
    st.photon_split = NULL;

    ExplainRun xr;
    CstStatus status = explain_begin(&xr, scene, &st, x, y, iteration, EXPLAIN_SPPM_EVENTS, err);
    if (status != CST_OK) return explain_finish(&xr, status, out);
    CstExplain *ex = xr.ex;
    Film *film = xr.film;
    Integrator *it = xr.it;
    Recorder *rec = &xr.rec;
    const int pixel = y * st.width + x;
    SppmTrace tr;
    memset(&tr, 0, sizeof tr);
    tr.rec = rec;
    tr.pixel = pixel;
    tr.iteration = iteration;
    sppm_trace(it->sppm, &tr);
    integrator_pass_begin(it, 0, iteration + 1);
    for (;;) {
        IntegratorStep step;
        if ((status = integrator_next_step(it, &step, err)) != CST_OK) goto done;
        if (step.items == 0) break;
        for (int i = 0; i < step.items; i++) step.fn(step.ctx, i, 0);
    }
    integrator_finish(it, iteration + 1);
    sppm_trace(it->sppm, NULL);

    ex->truncated = rec->truncated;
    ex->filter_weight = tr.fw;
    replay(it, rec, &tr, iteration, ex);
    shares(it, rec, &tr, iteration, ex);
    ex->exact = !rec->truncated && ex->sppm.state_exact;
    for (int c = 0; c < 3; c++) {
        ex->sum[c] = (float)ex->sppm.value[c];
        ex->camera_value[c] = ex->sppm.value[c];
        ex->film_value[c] = film->sum[3 * (size_t)pixel + (size_t)c];
        /* Added to a zeroed sum, as sppm_finish adds it: a -0 leaves +0 there. */
        const double v = 0.0 + ex->sppm.value[c];
        if (memcmp(&v, &ex->film_value[c], sizeof v) != 0) ex->exact = 0;
    }
done:
    return explain_finish(&xr, status, out);
}
