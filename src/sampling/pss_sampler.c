/* The primary-sample-space sampler (pss_sampler.h): Kelemen, Szirmay-Kalos, Antal &
 * Csonka 2002, "A simple and robust mutation strategy for the Metropolis light transport
 * algorithm", with the lazy update and the stream interleaving of pbrt-v4's MLTSampler. */
#include "sampling/pss_sampler.h"

#include <math.h>
#include <stdlib.h>

#include "core/array.h"

void pss_init(PssSampler *s, Pcg32 rng, double sigma, float large_step_prob, int stream_count)
{
    *s = (PssSampler){0};
    s->rng = rng;
    s->sigma = sigma;
    s->large_step_prob = large_step_prob;
    s->stream_count = stream_count > 0 ? stream_count : 1;
}

void pss_restart(PssSampler *s, Pcg32 rng)
{
    s->rng = rng;
    s->stream = s->stream_next = 0;
    s->large_step = s->oom = false;
    s->iteration = s->last_large = 0;
    s->n = 0;
}

void pss_free(PssSampler *s)
{
    free(s->x);
    s->x = NULL;
    s->n = s->cap = 0;
}

void pss_start_iteration(PssSampler *s)
{
    s->iteration++;
    s->large_step = pcg32_float(&s->rng) < s->large_step_prob;
    s->stream = 0;
    s->stream_next = 0;
}

void pss_start_stream(PssSampler *s, int index)
{
    s->stream = index;
    s->stream_next = 0;
}

/* A standard normal by Box-Muller from two draws of the chain's stream (exact, unlike a
 * polynomial inverse of erf); 1 - u keeps the logarithm finite. */
static double normal_draw(Pcg32 *r)
{
    double u1 = 1.0 - (double)pcg32_float(r);
    double u2 = (double)pcg32_float(r);
    return sqrt(-2.0 * log(u1)) * cos(6.283185307179586 * u2);
}

/* The state's value as a float in [0, 1): a double just below 1 rounds up to 1.0f. */
static float to_unit_float(double v)
{
    float f = (float)v;
    return f < 1.0f ? f : 0x1.fffffep-1f;
}

float pss_next(PssSampler *s)
{
    size_t i = (size_t)s->stream + (size_t)s->stream_count * (size_t)s->stream_next++;
    if (i >= s->n) {
        /* New coordinates enter as if drawn at the last accepted large step (they were
         * never read, so any value is as likely as any other): a uniform, dated then. */
        if (!array_grow(&s->x, &s->cap, i + 1, sizeof *s->x)) {
            s->oom = true;
            return pcg32_float(&s->rng);
        }
        for (; s->n <= i; s->n++) s->x[s->n] = (PssValue){0.0, 0.0, -1, -1};
    }
    PssValue *x = &s->x[i];
    /* Not touched since before the last accepted large step: that step replaced it. */
    if (x->modified < s->last_large) {
        x->value = (double)pcg32_float(&s->rng);
        x->modified = s->last_large;
    }
    x->backup = x->value;
    x->modified_backup = x->modified;
    if (s->large_step) {
        x->value = (double)pcg32_float(&s->rng);
    } else {
        /* The small steps missed since `modified`, as one normal step (their sum). */
        double steps = (double)(s->iteration - x->modified);
        x->value += normal_draw(&s->rng) * s->sigma * sqrt(steps);
        x->value -= floor(x->value);
    }
    x->modified = s->iteration;
    return to_unit_float(x->value);
}

void pss_accept(PssSampler *s)
{
    if (s->large_step) s->last_large = s->iteration;
}

void pss_reject(PssSampler *s)
{
    for (size_t i = 0; i < s->n; i++)
        if (s->x[i].modified == s->iteration) {
            s->x[i].value = s->x[i].backup;
            s->x[i].modified = s->x[i].modified_backup;
        }
    s->iteration--;
}

bool pss_replay_init(PssSampler *s, const double *v, size_t n, int stream_count)
{
    /* No large step and sigma 0: pss_next adds a normal draw times 0 (finite, so +-0) to
     * each value and wraps it, which leaves a value in [0, 1) as it is; dated at the
     * iteration and after the last large step, so no value is drawn afresh. A value of
     * exactly 1 (a wrap's rounding) would wrap to 0: the double below 1 reads back as the
     * same float (to_unit_float clamps both). */
    pss_init(s, (Pcg32){0x853c49e6748fea9bULL, 0xda3e39cb94b95bdbULL}, 0.0, 0.0f, stream_count);
    s->iteration = 1;
    if (n && !array_grow(&s->x, &s->cap, n, sizeof *s->x)) return false;
    for (size_t i = 0; i < n; i++) {
        const double x = v[i] < 1.0 ? v[i] : 0x1.fffffffffffffp-1;
        s->x[i] = (PssValue){x, x, 1, 1};
    }
    s->n = n;
    return true;
}

double pss_small_step_pdf(double x, double y, double w)
{
    /* The wrapped normal's images beyond 8 widths (and 2 periods) add nothing in double. */
    double d = y - x, sum = 0.0;
    int kmax = (int)ceil(8.0 * w) + 2;
    for (int k = -kmax; k <= kmax; k++) {
        double z = (d + (double)k) / w;
        sum += exp(-0.5 * z * z);
    }
    return sum / (w * 2.5066282746310002);
}
