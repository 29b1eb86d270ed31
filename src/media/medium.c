/* Homogeneous media: coefficients at the path's wavelengths, transmittance, distance
 * sampling with the balance heuristic over colour channels (medium.h states the pdfs).
 * Heterogeneous media share the coefficients (at density 1); their tracking is in
 * hetero_medium.c. */
#include "media/medium.h"

#include <math.h>

MediumCoeffs medium_coeffs(const Medium *m, const Wavelengths *wl)
{
    MediumCoeffs c;
    const bool het = medium_is_hetero(m);
    const Color sa = het ? m->u.het.sigma_a : m->u.homog.sigma_a, ss = het ? m->u.het.sigma_s : m->u.homog.sigma_s;
    const Color le = het ? m->u.het.le : m->u.homog.le;
    c.emissive = !color_is_black(le);
    if (wl && m->spec.ready) { /* the same arithmetic as the conversions below, minus the lookup */
        c.sigma_a = spectrum_rgb_eval(&m->spec.sigma_a, wl);
        c.sigma_s = spectrum_rgb_eval(&m->spec.sigma_s, wl);
        c.le = c.emissive ? spectrum_rgb_eval_illuminant(&m->spec.le, wl) : color_s(0.0f);
    } else {
        c.sigma_a = wl ? spectrum_unbounded(sa, wl) : sa;
        c.sigma_s = wl ? spectrum_unbounded(ss, wl) : ss;
        c.le = c.emissive ? (wl ? spectrum_illuminant(le, wl) : le) : color_s(0.0f);
    }
    c.sigma_t = color_add(c.sigma_a, c.sigma_s);
    c.g = m->g;
    return c;
}

void medium_prepare_spectra(Medium *m)
{
    const bool het = medium_is_hetero(m);
    m->spec.sigma_a = spectrum_rgb_unbounded(het ? m->u.het.sigma_a : m->u.homog.sigma_a);
    m->spec.sigma_s = spectrum_rgb_unbounded(het ? m->u.het.sigma_s : m->u.homog.sigma_s);
    m->spec.le = spectrum_rgb_unbounded(het ? m->u.het.le : m->u.homog.le);
    m->spec.ready = true;
}

Color medium_transmittance(const MediumCoeffs *m, float d)
{
    Color tr;
    for (int i = 0; i < COLOR_LANES; i++) {
        /* d may be infinite: exp(-0 * inf) is a NaN that means "no attenuation". */
        float x = m->sigma_t.c[i] * d;
        tr.c[i] = m->sigma_t.c[i] > 0.0f ? expf(-x) : 1.0f;
    }
    return tr;
}

float medium_distance_pdf(const MediumCoeffs *m, float t)
{
    Color tr = medium_transmittance(m, t);
    float p = 0.0f;
    for (int i = 0; i < COLOR_LANES; i++) p += m->sigma_t.c[i] * tr.c[i];
    return p * (1.0f / (float)COLOR_LANES);
}

float medium_pass_prob(const MediumCoeffs *m, float t_max)
{
    Color tr = medium_transmittance(m, t_max);
    float p = 0.0f;
    for (int i = 0; i < COLOR_LANES; i++) p += tr.c[i];
    return p * (1.0f / (float)COLOR_LANES);
}

void medium_sample_distance(const MediumCoeffs *m, float t_max, float u_ch, float u, MediumSample *out)
{
    int c = (int)(u_ch * (float)COLOR_LANES);
    if (c > COLOR_LANES - 1) c = COLOR_LANES - 1;
    float st = m->sigma_t.c[c];
    /* -log(1 - u) / sigma_t: 1 - u in (0, 1], so t is finite and >= 0. */
    float t = st > 0.0f ? -log1pf(-u) / st : INFINITY;
    if (t < t_max) {
        Color tr = medium_transmittance(m, t);
        float pdf = medium_distance_pdf(m, t);
        out->t = t;
        out->scattered = true;
        out->tr_pdf = pdf > 0.0f ? color_scale(tr, 1.0f / pdf) : color_s(0.0f);
        out->weight = color_mul(out->tr_pdf, m->sigma_s);
        return;
    }
    Color tr = medium_transmittance(m, t_max);
    float p = medium_pass_prob(m, t_max);
    out->t = t_max;
    out->scattered = false;
    out->tr_pdf = color_s(0.0f);
    out->weight = p > 0.0f ? color_scale(tr, 1.0f / p) : color_s(0.0f);
}

void medium_release(Medium *m)
{
    if (m && medium_is_hetero(m)) hetero_medium_release(&m->u.het);
}
