/* caustic explain --integrator sppm (issue 30): one iteration of one pixel printed, as text
 * or into explain.c's JSON object: the camera chain to the visible point, the direct light,
 * the photons gathered (the largest first), the progressive update and the pixel's value. */
#include <jansson.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "cli.h"

/* Photons listed by the text output, largest share first (all of them in --json). */
enum { SPPM_TOP_PHOTONS = 8 };

static double lum3(const double c[3]) { return 0.2126 * c[0] + 0.7152 * c[1] + 0.0722 * c[2]; }

static void p3f(FILE *f, const char *label, const float v[3])
{
    fprintf(f, "%s(%.9g, %.9g, %.9g)", label, (double)v[0], (double)v[1], (double)v[2]);
}

static void p3d(FILE *f, const char *label, const double v[3])
{
    fprintf(f, "%s(%.17g, %.17g, %.17g)", label, v[0], v[1], v[2]);
}

static void print_photon(FILE *f, const CstExplainEvent *e)
{
    fprintf(f, "  photon path %d, hit after %d bounces, at (%.6g, %.6g, %.6g), %.4g from the point, wi (%.4f, %.4f, "
            "%.4f)\n      ", e->path, e->s, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->distance,
            (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
    p3f(f, "power ", e->value);
    p3f(f, " x f ", e->beta);
    p3f(f, " = ", e->contribution);
    fprintf(f, "; box kernel %.6g; share of the pixel (%.6g, %.6g, %.6g)\n", (double)e->pmf, e->share[0],
            e->share[1], e->share[2]);
}

/* The chain: vertices, delta lobes, emission met, NEE at the visible point. */
static void print_chain(FILE *f, const CstExplain *x)
{
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        switch (e->kind) {
        case CST_EXPLAIN_VERTEX:
            if (e->medium >= 0) { /* a scene with media: the visible point alone */
                fprintf(f, "visible point in medium %d at (%.6g, %.6g, %.6g) (the chain through media is not "
                        "itemised)\n", e->medium, (double)e->p[0], (double)e->p[1], (double)e->p[2]);
                break;
            }
            fprintf(f, "vertex %d: surface at (%.6g, %.6g, %.6g), normal (%.4f, %.4f, %.4f), material #%d (%s)%s\n",
                    e->depth, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->n[0], (double)e->n[1],
                    (double)e->n[2], e->material, e->material_type ? e->material_type : "none",
                    e->light >= 0 ? ", an emitter" : "");
            break;
        case CST_EXPLAIN_SCATTER:
            if (e->flags & CST_EXPLAIN_DELTA)
                fprintf(f, "  %s: delta lobe, pmf %.6g, wi (%.4f, %.4f, %.4f), ", e->lobe ? e->lobe : "lobe unknown",
                        (double)e->pmf, (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
            else
                fprintf(f, "  the non-delta lobes taken (probability %.6g): the visible point, ", (double)e->pmf);
            p3f(f, "weight ", e->value);
            p3f(f, ", throughput before ", e->beta);
            fputc('\n', f);
            break;
        case CST_EXPLAIN_EMISSION:
        case CST_EXPLAIN_ESCAPE:
        case CST_EXPLAIN_NEE:
            if (!(e->flags & CST_EXPLAIN_ADDED)) break;
            if (e->kind == CST_EXPLAIN_NEE && e->light < 0)
                fputs("  direct light (NEE through media, one light sample, not itemised)\n    ", f);
            else if (e->kind == CST_EXPLAIN_NEE)
                fprintf(f, "  direct light (NEE, no MIS): light %d at (%.6g, %.6g, %.6g), pmf %.6g, pdf_w %.6g%s\n    ",
                        e->light, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->pmf,
                        (double)e->pdf_w, (e->flags & CST_EXPLAIN_OCCLUDED) ? ", occluded" : "");
            else
                fprintf(f, "  %s met by the chain\n    ", e->kind == CST_EXPLAIN_ESCAPE ? "environment" : "emission");
            p3f(f, "value ", e->value);
            p3f(f, " x beta ", e->beta);
            p3f(f, " = ", e->contribution);
            fputc('\n', f);
            break;
        default: break;
        }
    }
}

static int cmp_share(const void *a, const void *b)
{
    const CstExplainEvent *x = *(const CstExplainEvent *const *)a, *y = *(const CstExplainEvent *const *)b;
    const double lx = lum3(x->share), ly = lum3(y->share);
    return (lx < ly) - (lx > ly);
}

void cli_explain_sppm_text(FILE *f, const CstExplain *x)
{
    const struct CstExplainSppm *s = &x->sppm;
    fprintf(f, "pixel (%d, %d), iteration %d of sppm (%lld photon paths per iteration), %s\n", x->x, x->y, x->sample,
            s->photons, x->spectral ? "spectral" : "RGB");
    print_chain(f, x);
    if (!s->visible) fputs("no visible point this iteration (the chain left the scene or died)\n", f);
    else p3f(f, "visible point's throughput (filter weight included) ", s->beta), fputc('\n', f);
    p3f(f, "direct light of the iteration (emission + NEE) ", s->direct);
    p3d(f, "\n  sum over the iterations ", s->ld_before);
    p3d(f, " -> ", s->ld_after);
    fputc('\n', f);
    /* The photons, largest share of the pixel first. */
    int n = 0;
    const CstExplainEvent **ph = malloc(((size_t)x->num_events + 1) * sizeof *ph);
    for (int i = 0; ph && i < x->num_events; i++)
        if (x->events[i].kind == CST_EXPLAIN_PHOTON) ph[n++] = &x->events[i];
    fprintf(f, "photons gathered in the %s of radius %.9g: M = %lld\n", s->volume ? "ball" : "disc",
            (double)s->r_before, s->m);
    if (ph) {
        qsort(ph, (size_t)n, sizeof *ph, cmp_share);
        for (int i = 0; i < n && i < SPPM_TOP_PHOTONS; i++) print_photon(f, ph[i]);
        if (n > SPPM_TOP_PHOTONS) fprintf(f, "  ... and %d smaller ones (--json lists all)\n", n - SPPM_TOP_PHOTONS);
    }
    free(ph);
    p3d(f, "  their sum of f Phi: phi ", s->phi);
    fputc('\n', f);
    fprintf(f, "progressive update (Hachisuka & Jensen 2009 eqs. 6-7, alpha 2/3): N %.17g -> %.17g, r %.9g -> %.9g\n",
            s->n_before, s->n_after, (double)s->r_before, (double)s->r_after);
    p3d(f, "  tau ", s->tau_before);
    p3d(f, " -> ", s->tau_after);
    fprintf(f, "\n  state %s\n", s->state_exact ? "equal to the render's, bit for bit" : "MISMATCH with the render's");
    fprintf(f, "pixel value after iteration %d: ld / %d + tau / (N_emitted %.17g pi r^2)%s\n", x->sample,
            x->sample + 1, s->emitted, s->media ? " + tau_vol / (N_emitted 4/3 pi r_vol^3)" : "");
    if (s->media)
        fprintf(f, "  the %s's statistic, untouched: tau (%.9g, %.9g, %.9g), radius %.9g\n",
                s->volume ? "disc" : "ball", s->tau_other[0], s->tau_other[1], s->tau_other[2], (double)s->r_other);
    p3d(f, "  = ", s->value);
    fprintf(f, "\nthe film of a render with --spp %d (iterations 0..%d): ", x->sample + 1, x->sample);
    p3d(f, "", x->film_value);
    fprintf(f, ": %s\n",
            x->truncated ? "not checked (more photons than explain keeps)"
            : x->exact ? "equal, bit for bit" : "MISMATCH");
}

/* --why-bright: the iteration's largest share (a photon or the direct light); --why-dark:
 * what the iteration lacked. */
void cli_explain_sppm_why(FILE *f, const CstExplain *x, bool bright)
{
    const struct CstExplainSppm *s = &x->sppm;
    int best = -1;
    double total = 0.0;
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        if (e->kind != CST_EXPLAIN_PHOTON && !(e->flags & CST_EXPLAIN_ADDED)) continue;
        total += lum3(e->share);
        if (best < 0 || lum3(e->share) > lum3(x->events[best].share)) best = i;
    }
    if (!bright) {
        fprintf(f, "why dark: value (%.6g, %.6g, %.6g) after iteration %d; %s; %lld photons gathered in radius %.4g",
                s->value[0], s->value[1], s->value[2], x->sample,
                s->visible ? "the chain reached a visible point" : "no visible point this iteration (the chain "
                "left the scene or died)", s->m, (double)s->r_before);
        for (int i = 0; i < x->num_events; i++)
            if (x->events[i].kind == CST_EXPLAIN_NEE && (x->events[i].flags & CST_EXPLAIN_OCCLUDED))
                fputs("; its light sample was blocked", f);
        fputc('\n', f);
        return;
    }
    if (best < 0 || !(total > 0.0)) {
        fputs("why bright: it is not: iteration added nothing (try --why-dark)\n", f);
        return;
    }
    const CstExplainEvent *e = &x->events[best];
    const double part = 100.0 * lum3(e->share) / total;
    if (e->kind == CST_EXPLAIN_PHOTON)
        fprintf(f, "why bright: photon path %d (its hit after %d bounces, at (%.4g, %.4g, %.4g), f Phi luminance %.6g, "
                "kernel %.4g) gives %.1f%% of what iteration %d added to the pixel\n", e->path, e->s, (double)e->p[0],
                (double)e->p[1], (double)e->p[2], 0.2126 * (double)e->contribution[0] + 0.7152 *
                (double)e->contribution[1] + 0.0722 * (double)e->contribution[2], (double)e->pmf, part, x->sample);
    else
        fprintf(f, "why bright: the %s at vertex %d gives %.1f%% of what iteration %d added to the pixel\n",
                e->kind == CST_EXPLAIN_NEE ? "direct light (NEE)" : e->kind == CST_EXPLAIN_ESCAPE ? "environment"
                : "emission", e->depth, part, x->sample);
}

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }
static json_t *a3d(const double v[3]) { return json_pack("[ooo]", num(v[0]), num(v[1]), num(v[2])); }
static json_t *a3f(const float v[3])
{
    return json_pack("[ooo]", num((double)v[0]), num((double)v[1]), num((double)v[2]));
}

void cli_explain_sppm_json(json_t *o, const CstExplain *x)
{
    const struct CstExplainSppm *s = &x->sppm;
    /* The photon events get what sppm knows of them (explain.c's event_json wrote the rest). */
    json_t *events = json_object_get(o, "events");
    for (int i = 0; i < x->num_events && events; i++) {
        const CstExplainEvent *e = &x->events[i];
        json_t *ej = json_array_get(events, (size_t)i);
        if (e->kind != CST_EXPLAIN_PHOTON || !ej) continue;
        json_object_set_new(ej, "path", json_integer(e->path));
        json_object_set_new(ej, "bounces", json_integer(e->s));
        json_object_set_new(ej, "distance", num((double)e->distance));
        json_object_set_new(ej, "kernel", num((double)e->pmf));
        json_object_set_new(ej, "share", a3d(e->share));
    }
    json_t *p = json_object();
    json_object_set_new(p, "iteration", json_integer(x->sample));
    json_object_set_new(p, "visible", json_boolean(s->visible));
    json_object_set_new(p, "volume", json_boolean(s->volume));
    json_object_set_new(p, "media", json_boolean(s->media));
    json_object_set_new(p, "tau_other", a3d(s->tau_other));
    json_object_set_new(p, "radius_other", num((double)s->r_other));
    json_object_set_new(p, "photons_per_iteration", json_integer(s->photons));
    json_object_set_new(p, "photons_emitted", num(s->emitted));
    json_object_set_new(p, "beta", a3f(s->beta));
    json_object_set_new(p, "direct", a3f(s->direct));
    json_object_set_new(p, "ld", json_pack("[oo]", a3d(s->ld_before), a3d(s->ld_after)));
    json_object_set_new(p, "m", json_integer(s->m));
    json_object_set_new(p, "phi", a3d(s->phi));
    json_object_set_new(p, "n", json_pack("[oo]", num(s->n_before), num(s->n_after)));
    json_object_set_new(p, "radius", json_pack("[oo]", num((double)s->r_before), num((double)s->r_after)));
    json_object_set_new(p, "tau", json_pack("[oo]", a3d(s->tau_before), a3d(s->tau_after)));
    json_object_set_new(p, "value", a3d(s->value));
    json_object_set_new(p, "state_exact", json_boolean(s->state_exact));
    json_object_set_new(o, "sppm", p);
}
