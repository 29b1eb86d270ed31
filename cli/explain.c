/* caustic explain (issue 30): one pixel sample replayed by the library (cst_explain) and
 * printed, as text or with --json as one JSON object: the path's vertices, decisions,
 * densities, MIS weights and contributions, and whether they add up to the film's value. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "cli.h"

static const char *kind_name(CstExplainKind k)
{
    switch (k) {
    case CST_EXPLAIN_VERTEX: return "vertex";
    case CST_EXPLAIN_ESCAPE: return "escape";
    case CST_EXPLAIN_EMISSION: return "emission";
    case CST_EXPLAIN_NEE: return "nee";
    case CST_EXPLAIN_CONNECT: return "connect";
    case CST_EXPLAIN_SPLAT: return "splat";
    case CST_EXPLAIN_SCATTER: return "scatter";
    case CST_EXPLAIN_ROULETTE: return "roulette";
    case CST_EXPLAIN_MERGE: return "merge";
    case CST_EXPLAIN_DISTANCE: return "distance";
    case CST_EXPLAIN_PHOTON: return "photon";
    case CST_EXPLAIN_ESTIMATE: return "estimate";
    case CST_EXPLAIN_MUTATION: return "mutation";
    }
    return "unknown";
}

/* bdpt and vcm: strategies (s, t), an iteration's light paths and their splats. */
static bool is_bdpt(const CstExplain *x)
{
    return x->integrator == CST_INTEGRATOR_BDPT || x->integrator == CST_INTEGRATOR_VCM;
}
static bool is_light(const CstExplain *x) { return x->integrator == CST_INTEGRATOR_LIGHT; }
static bool is_whitted(const CstExplain *x) { return x->integrator == CST_INTEGRATOR_WHITTED; }
static bool is_photon(const CstExplain *x) { return x->integrator == CST_INTEGRATOR_PHOTON; }
/* pssmlt, mmlt: the Metropolis steps' splats of one iteration. */
static bool is_mlt(const CstExplain *x)
{
    return x->integrator == CST_INTEGRATOR_PSSMLT || x->integrator == CST_INTEGRATOR_MMLT;
}

/* ------------------------------------------------------------------ text */

/* Whether any of the three lanes is nonzero. */
static bool has3(const float v[3]) { return v[0] != 0.0f || v[1] != 0.0f || v[2] != 0.0f; }

static void print3(FILE *f, const char *label, const float v[3])
{
    fprintf(f, "%s(%.9g, %.9g, %.9g)", label, (double)v[0], (double)v[1], (double)v[2]);
}

static void print_mis(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    if (is_bdpt(x)) {
        fprintf(f, "MIS w %.9g = 1/(w_light %.6g + 1 + w_camera %.6g)", (double)e->mis_weight,
                (double)e->pdf_other_w, (double)e->pdf_other2);
        if (e->mis_strategies > 0)
            fprintf(f, "; explicitly %.9g of %d strategies (weights sum %.9g)", (double)e->mis_explicit,
                    e->mis_strategies, (double)e->mis_sum);
    } else
        fprintf(f, "MIS w %.9g", (double)e->mis_weight);
}

static void print_value(FILE *f, const CstExplainEvent *e)
{
    fputs("\n      ", f);
    print3(f, "value ", e->value);
    print3(f, " x beta ", e->beta);
    print3(f, " = contribution ", e->contribution);
    /* Spectral bdpt/vcm: a dispersed subpath counts at the hero wavelength alone (the
     * values are the four wavelengths', before spectrum_to_rgb). */
    if (e->flags & (CST_EXPLAIN_HERO | CST_EXPLAIN_LIGHT_DISPERSED))
        fprintf(f, "; hero wavelength alone (%s dispersed)",
                (e->flags & CST_EXPLAIN_HERO) ? "the camera subpath" : "the light subpath");
    fputc('\n', f);
}

/* photon with moving instances: the photons' time window, whose factor s = shutter /
 * window the kernel includes (Cammarano & Jensen 2002; photon.c's time_window). */
static void print_window(FILE *f, const CstExplainEvent *e)
{
    if (e->time_window[1] > e->time_window[0] || e->time_scale != 1.0f)
        fprintf(f, " (photons of times [%.6g, %.6g] only, s = shutter / window = %.6g)", (double)e->time_window[0],
                (double)e->time_window[1], (double)e->time_scale);
}

/* photon: the specular chain's emission, a gathered photon, a density estimate. */
static void print_gather(FILE *f, const CstExplainEvent *e)
{
    if (e->kind == CST_EXPLAIN_PHOTON) {
        fprintf(f, "    photon at (%.6g, %.6g, %.6g) from wi (%.4f, %.4f, %.4f): ", (double)e->p[0],
                (double)e->p[1], (double)e->p[2], (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
        print3(f, "power ", e->value);
        print3(f, " x f ", e->beta);
        print3(f, " = ", e->contribution);
        fputc('\n', f);
        return;
    }
    if (e->kind == CST_EXPLAIN_ESTIMATE && (e->flags & CST_EXPLAIN_VOLUME)) {
        /* photon.c's volume_estimate: (1 / sigma_s) sum f_HG Phi / ((4/3) pi r^3), times beta. */
        fprintf(f, "  volume map's estimate over those %d photons: radius %.6g, ball kernel %s %.6g", e->path,
                (double)e->distance, e->time_scale != 1.0f ? "s/((4/3) pi r^3)" : "1/((4/3) pi r^3)", (double)e->pmf);
        print_window(f, e);
        fputs(", ", f);
        print3(f, "divided by sigma_s ", e->transmittance);
        fputs("\n      ", f);
        print3(f, "in-scattered radiance ", e->value);
        print3(f, " x beta ", e->beta);
        print3(f, " = contribution ", e->contribution);
        fputc('\n', f);
        return;
    }
    if (e->kind == CST_EXPLAIN_ESTIMATE) {
        fprintf(f, "  %s map's estimate over those %d photons: radius %.6g, box kernel %s %.6g",
                (e->flags & CST_EXPLAIN_CAUSTIC) ? "caustic" : "global (final gather)", e->path,
                (double)e->distance, e->time_scale != 1.0f ? "s/(pi r^2)" : "1/(pi r^2)", (double)e->pmf);
        print_window(f, e);
    } else if (e->kind == CST_EXPLAIN_ESCAPE)
        fputs("environment met by the camera ray through media and delta bounces (no MIS)", f);
    else if (e->s == 0) /* recorder_media_emission: emitting media on a walk (photon_li_media) */
        fputs("emission of media met on the flight (collision estimate, weight 1, throughput included)", f);
    else
        fputs("emission met by the camera ray and its specular chain (no MIS)", f);
    print_value(f, e);
}

/* pssmlt, mmlt: one splat of a Metropolis step and what it added to the pixel. */
static void print_mutation(FILE *f, const CstExplainEvent *e)
{
    fprintf(f, "chain %d", e->chain);
    if (e->path_length >= 0) fprintf(f, " (path length %d)", e->path_length);
    if (e->s >= 0) fprintf(f, " strategy (s=%d, t=%d)", e->s, e->t);
    fprintf(f, ", step %d (%s step, a %.9g, %s): the %s at film (%.4f, %.4f), I %.9g, weight %s %.9g\n      ",
            e->step, (e->flags & CST_EXPLAIN_LARGE_STEP) ? "large" : "small", (double)e->accept,
            (e->flags & CST_EXPLAIN_ACCEPTED) ? "accepted" : "rejected",
            (e->flags & CST_EXPLAIN_PROPOSAL) ? "proposal" : "current state", (double)e->wi[0], (double)e->wi[1],
            (double)e->importance, (e->flags & CST_EXPLAIN_PROPOSAL) ? "a/I" : "(1-a)/I", (double)e->weight);
    print3(f, "L ", e->value);
    fprintf(f, "; adds (%.9g, %.9g, %.9g) to the pixel\n", e->share[0], e->share[1], e->share[2]);
}

/* A free flight in a medium: where it stopped, its densities, its weight. */
static void print_distance(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    fprintf(f, "  distance in medium %d: %s %.6g", e->medium,
            (e->flags & CST_EXPLAIN_SCATTERED) ? "scatters after" : "passes the segment of", (double)e->distance);
    if (e->pdf_w > 0.0f)
        fprintf(f, " (%s %.6g, transmittance (%.6g, %.6g, %.6g))",
                (e->flags & CST_EXPLAIN_SCATTERED) ? "pdf per unit length" : "probability", (double)e->pdf_w,
                (double)e->transmittance[0], (double)e->transmittance[1], (double)e->transmittance[2]);
    if (e->chain_fwd > 0.0f || e->chain_rev > 0.0f) /* bdpt, vcm (subpath_media.c) */
        fprintf(f, " (sampling density %.6g, reverse %.6g)", (double)e->chain_fwd, (double)e->chain_rev);
    /* bdpt, vcm, photon (subpath_media.c's flights): the throughput after the flight. */
    const bool thr = is_bdpt(x) || is_photon(x);
    print3(f, thr ? ", throughput " : ", weight ", thr ? e->beta : e->value);
    fputc('\n', f);
}

/* NEE's MIS partner at the vertex the event belongs to (the last VERTEX before it): the
 * phase function in a medium, the exit's cosine sampling at a subsurface exit, else the BSDF. */
static const char *nee_partner(const CstExplain *x, const CstExplainEvent *e)
{
    for (const CstExplainEvent *v = e; v-- > x->events;) {
        if (v->kind != CST_EXPLAIN_VERTEX) continue;
        if (v->material_type && !strcmp(v->material_type, "medium")) return "phase";
        if (v->material_type && !strcmp(v->material_type, "subsurface exit")) return "exit cos/pi";
        break;
    }
    return "BSDF";
}

/* whitted_direct's one shadow ray: detail, not summed (the mean follows it). */
static void print_shadow_ray(FILE *f, const CstExplainEvent *e)
{
    fprintf(f, "%*sshadow ray to light %d at (%.6g, %.6g, %.6g): ", 2 * e->depth, "", e->light, (double)e->p[0],
            (double)e->p[1], (double)e->p[2]);
    if (e->flags & CST_EXPLAIN_DELTA)
        fprintf(f, "delta light, pmf %.6g; ", (double)e->pmf);
    else
        fprintf(f, "pmf %.6g, pdf_w %.6g, pdf_a %.6g, BSDF pdf_w %.6g (no MIS); ", (double)e->pmf, (double)e->pdf_w,
                (double)e->pdf_a, (double)e->pdf_other_w);
    if (e->flags & CST_EXPLAIN_OCCLUDED) fputs("occluded; ", f);
    print3(f, "its share of the mean ", e->value);
    fputs(" (not summed: the line below is the mean)\n", f);
}

/* A hit of a light subpath (depth -bounces: mmlt's replay, BDPT's and VCM's pixel light path). */
static void print_light_vertex(FILE *f, const CstExplainEvent *e)
{
    if (e->medium >= 0) {
        fprintf(f, "light vertex %d (bounces from the emitter): in medium %d at (%.6g, %.6g, %.6g)\n", -e->depth,
                e->medium, (double)e->p[0], (double)e->p[1], (double)e->p[2]);
        return;
    }
    fprintf(f, "light vertex %d (bounces from the emitter): surface at (%.6g, %.6g, %.6g), normal (%.4f, %.4f, %.4f), "
            "material #%d (%s)\n", -e->depth, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->n[0],
            (double)e->n[1], (double)e->n[2], e->material, e->material_type ? e->material_type : "none");
}

/* A scatter: the lobe, its density, the direction and the weight (whitted: a branch). */
static void print_scatter(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    if (is_whitted(x)) {
        fprintf(f, "%*sbranch: %s lobe of probability %.6g, wi (%.4f, %.4f, %.4f), ", 2 * e->depth, "",
                e->lobe ? e->lobe : "specular", (double)e->pmf, (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
        print3(f, "weight ", e->value);
        fputc('\n', f);
        return;
    }
    /* the lobe that drew wi; a non-delta weight is still the mixture's (one-sample MIS) */
    fprintf(f, "  scatter (%s): ", e->lobe ? e->lobe : "lobe unknown");
    if (e->flags & CST_EXPLAIN_DELTA)
        fprintf(f, "delta lobe, pmf %.6g", (double)e->pmf);
    else
        fprintf(f, "non-delta lobes, pdf_w %.6g", (double)e->pdf_w);
    /* a light subpath's: the reverse density its MIS ratios use */
    if (e->depth < 0) fprintf(f, ", reverse %s %.6g", (e->flags & CST_EXPLAIN_DELTA) ? "pmf" : "pdf_w",
                              (double)e->pdf_other_w);
    fprintf(f, ", wi (%.4f, %.4f, %.4f), ", (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
    print3(f, "weight f cos/pdf ", e->value);
    fputc('\n', f);
}

static void print_event(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    if (e->kind == CST_EXPLAIN_VERTEX && e->depth < 0) {
        print_light_vertex(f, e);
        return;
    }
    if (is_whitted(x) && (e->kind == CST_EXPLAIN_ESCAPE || e->kind == CST_EXPLAIN_EMISSION)) {
        /* the ray tree: no densities, no MIS */
        fprintf(f, "%*s%s at tree depth %d", 2 * e->depth, "", e->kind == CST_EXPLAIN_ESCAPE ? "environment"
                : "emission", e->depth);
        print_value(f, e);
        return;
    }
    switch (e->kind) {
    case CST_EXPLAIN_DISTANCE: print_distance(f, x, e); return;
    case CST_EXPLAIN_VERTEX:
        if (e->medium >= 0) {
            fprintf(f, "vertex %d: in medium %d at (%.6g, %.6g, %.6g)", e->depth, e->medium, (double)e->p[0],
                    (double)e->p[1], (double)e->p[2]);
            /* photon: the walk stops at its first medium vertex; the volume map's estimate
             * evaluates the phase function for each photon instead of sampling it. */
            if (is_photon(x))
                fprintf(f, ": the walk's first medium vertex, no phase sample (Henyey-Greenstein g %.4g, "
                        "evaluated per photon)", (double)e->q);
            fputc('\n', f);
            return;
        }
        if (e->material_type && strcmp(e->material_type, "subsurface exit") == 0) {
            /* path_sss.c's BSSRDF step: where the light leaves the material again. */
            fprintf(f, "  subsurface exit at (%.6g, %.6g, %.6g), normal (%.4f, %.4f, %.4f): one of %.0f probe hits, "
                    "pdf_a %.6g (the pick's 1/%.0f included); ", (double)e->p[0], (double)e->p[1], (double)e->p[2],
                    (double)e->n[0], (double)e->n[1], (double)e->n[2], e->pmf > 0.0f ? 1.0 / (double)e->pmf : 0.0,
                    (double)e->pdf_a, e->pmf > 0.0f ? 1.0 / (double)e->pmf : 0.0);
            print3(f, "throughput Sp/pdf ", e->beta);
            fputc('\n', f);
            return;
        }
        fprintf(f, "vertex %d: surface at (%.6g, %.6g, %.6g), normal (%.4f, %.4f, %.4f), material #%d (%s)",
                e->depth, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->n[0], (double)e->n[1],
                (double)e->n[2], e->material, e->material_type ? e->material_type : "none");
        if (e->mix_material >= 0) fprintf(f, ", the mix chose #%d (%s)", e->mix_material, e->mix_material_type);
        if (e->light >= 0) fprintf(f, ", emitter %d", e->light);
        fputc('\n', f);
        return;
    case CST_EXPLAIN_ESCAPE:
        if (!(e->flags & CST_EXPLAIN_ADDED)) {
            fputs("  the ray leaves the scene (nothing added)\n", f);
            return;
        }
        /* fall through */
    case CST_EXPLAIN_EMISSION:
        if (is_photon(x)) {
            print_gather(f, e);
            return;
        }
        fprintf(f, "  %s", e->kind == CST_EXPLAIN_ESCAPE ? "environment" : "emission");
        if (is_bdpt(x)) fprintf(f, " (s=0, t=%d)", e->t);
        if (e->light >= 0) fprintf(f, " of emitter %d", e->light);
        if (!is_bdpt(x))
            fprintf(f, ": BSDF pdf_w %.6g (pdf_a %.6g), NEE pdf_w %.6g; ", (double)e->pdf_w, (double)e->pdf_a,
                    (double)e->pdf_other_w);
        else
            fputs(": ", f);
        print_mis(f, x, e);
        print_value(f, e);
        return;
    case CST_EXPLAIN_NEE:
        if (is_whitted(x) && !(e->flags & CST_EXPLAIN_ADDED)) { print_shadow_ray(f, e); return; }
        if (is_whitted(x)) {
            fprintf(f, "%*sdirect light (the mean of the shadow rays' estimates)", 2 * e->depth, "");
            print_value(f, e);
            return;
        }
        if (e->light < 0 && e->mis_weight < 0.0f) {
            /* volpath.c's medium NEE and path_sss.c's at a subsurface exit: the sum alone. */
            fprintf(f, "  NEE (light sample not itemised)");
            print_value(f, e);
            return;
        }
        fprintf(f, "  NEE");
        if (is_bdpt(x)) fprintf(f, " (s=1, t=%d)", e->t);
        fprintf(f, ": light %d at (%.6g, %.6g, %.6g), ", e->light, (double)e->p[0], (double)e->p[1],
                (double)e->p[2]);
        if (is_bdpt(x))
            fprintf(f, "sampled with density %.6g%s, direct pdf_w %.6g; ", (double)e->pdf_w,
                    (e->flags & CST_EXPLAIN_DELTA) ? " (pmf, delta light)" : " (pdf_w)", (double)e->pdf_a);
        else if (e->flags & CST_EXPLAIN_DELTA)
            fprintf(f, "delta light, pmf %.6g; ", (double)e->pmf);
        else
            fprintf(f, "pmf %.6g, pdf_w %.6g, pdf_a %.6g, %s pdf_w %.6g; ", (double)e->pmf, (double)e->pdf_w,
                    (double)e->pdf_a, nee_partner(x, e), (double)e->pdf_other_w);
        print_mis(f, x, e);
        if (e->flags & CST_EXPLAIN_OCCLUDED) fputs(", occluded", f);
        else if (!is_bdpt(x) && has3(e->transmittance)) /* volpath: the shadow ray's */
            fprintf(f, ", transmittance (%.6g, %.6g, %.6g)", (double)e->transmittance[0], (double)e->transmittance[1],
                    (double)e->transmittance[2]);
        print_value(f, e);
        return;
    case CST_EXPLAIN_CONNECT:
        fprintf(f, "  connect (s=%d, t=%d) to light vertex at (%.6g, %.6g, %.6g): camera-side pdf_w %.6g, pdf_a "
                "%.6g; ", e->s, e->t, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->pdf_w,
                (double)e->pdf_a);
        print_mis(f, x, e);
        if (e->flags & CST_EXPLAIN_OCCLUDED) fputs(", occluded", f);
        print_value(f, e);
        return;
    case CST_EXPLAIN_MERGE:
        fprintf(f, "  merge (s=%d, t=%d) with the light vertex at (%.6g, %.6g, %.6g), density estimate's 1/(pi r^2 N) "
                "%.6g; ", e->s, e->t, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->pmf);
        print_mis(f, x, e);
        print_value(f, e);
        return;
    case CST_EXPLAIN_SPLAT:
        if (is_light(x)) {
            fprintf(f, "light path %d's connection to the camera at raster (%.4f, %.4f): ", e->path, (double)e->wi[0],
                    (double)e->wi[1]);
            print3(f, "value (per unit film) ", e->value);
            fprintf(f, "\n      adds (%.9g, %.9g, %.9g) to the pixel\n", e->share[0], e->share[1], e->share[2]);
            return;
        }
        fprintf(f, "splat (s=%d, t=1) of light path %d from a light vertex at (%.6g, %.6g, %.6g) to raster (%.4f, "
                "%.4f): camera pdf_a %.6g; MIS w %.9g = 1/(w_light %.6g + 1)", e->s, e->path, (double)e->p[0],
                (double)e->p[1], (double)e->p[2], (double)e->wi[0], (double)e->wi[1], (double)e->pdf_a,
                (double)e->mis_weight, (double)e->pdf_other_w);
        if (e->mis_strategies > 0)
            fprintf(f, "; explicitly %.9g of %d strategies (weights sum %.9g)", (double)e->mis_explicit,
                    e->mis_strategies, (double)e->mis_sum);
        print3(f, "\n      value (per unit film, before the filter) ", e->value);
        fprintf(f, "; adds (%.9g, %.9g, %.9g) to the pixel\n", e->share[0], e->share[1], e->share[2]);
        return;
    case CST_EXPLAIN_SCATTER: print_scatter(f, x, e); return;
    case CST_EXPLAIN_ROULETTE:
        fprintf(f, "  roulette: survival probability %.6g, %s\n", (double)e->q,
                (e->flags & CST_EXPLAIN_SURVIVED) ? "survived (beta / q)" : "stopped");
        return;
    case CST_EXPLAIN_PHOTON:
    case CST_EXPLAIN_ESTIMATE: print_gather(f, e); return;
    case CST_EXPLAIN_MUTATION: print_mutation(f, e); return;
    }
}

/* Luminance (Rec. 709 weights) of a linear RGB triple: "how much" for the summary line. */
static double luminance(const float c[3])
{
    return 0.2126 * (double)c[0] + 0.7152 * (double)c[1] + 0.0722 * (double)c[2];
}

/* The event carrying most of the sample's luminance, and its share; -1 if nothing added any.
 * Shared by the summary line and --why-bright. */
static int largest_event(const CstExplain *x, double *share)
{
    int best = -1;
    double total = 0.0, best_y = 0.0;
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        /* (MLT: a splatted sample's own path is not a part of the sum; its splat is.) */
        if (!(e->flags & CST_EXPLAIN_ADDED) || (e->flags & CST_EXPLAIN_IN_SPLAT)) continue;
        /* MLT's splats: what each added to the pixel (the filter's weight differs). */
        const float sh[3] = {(float)e->share[0], (float)e->share[1], (float)e->share[2]};
        double y = luminance(e->kind == CST_EXPLAIN_MUTATION ? sh : e->contribution);
        total += y;
        if (best < 0 || y > best_y) { best = i; best_y = y; }
    }
    *share = total > 0.0 ? best_y / total : 0.0;
    return total > 0.0 ? best : -1;
}

/* The one line a student asks for first: which strategy at which vertex carries most of
 * the camera sample (a firefly's cause), with its share of the sum's luminance. */
static void print_largest(FILE *f, const CstExplain *x)
{
    double share;
    const int best = largest_event(x, &share);
    if (best < 0) {
        fputs("nothing reached a light: the sample is black\n", f);
        return;
    }
    const CstExplainEvent *e = &x->events[best];
    if (e->kind == CST_EXPLAIN_MUTATION)
        fprintf(f, "largest contribution: the %s's splat of chain %d, step %d",
                (e->flags & CST_EXPLAIN_PROPOSAL) ? "proposal" : "current state", e->chain, e->step);
    else if (e->path >= 0 && !is_photon(x)) /* (photon: path counts an estimate's photons) */
        fprintf(f, "largest contribution: the splat of light path %d", e->path);
    else
        fprintf(f, "largest contribution: %s at vertex %d", kind_name(e->kind), e->depth);
    if (e->s >= 0) fprintf(f, " (s=%d, t=%d)", e->s, e->t);
    fprintf(f, ", %.1f%% of the %s's luminance\n", 100.0 * share,
            is_light(x) || is_mlt(x) ? "pixel" : "camera sample");
}

/* The light tracer: no camera path, only the splats that reached the pixel. */
static void print_text_light(FILE *f, const CstExplain *x)
{
    fprintf(f, "pixel (%d, %d), iteration %d, integrator light, %s: %d light path connection(s) reach the pixel\n",
            x->x, x->y, x->sample, x->spectral ? "spectral" : "RGB", x->num_events);
    for (int i = 0; i < x->num_events; i++) print_event(f, x, &x->events[i]);
    if (x->truncated) fputs("(more splats than explain keeps: the list is truncated and not checked)\n", f);
    print_largest(f, x);
    fprintf(f, "the film's value for the iteration (%.9g, %.9g, %.9g): %s\n", x->film_value[0], x->film_value[1],
            x->film_value[2], x->truncated ? "not checked" : x->exact ? "the splats sum to it, bit for bit" : "MISMATCH");
}

/* MLT: the splats that reached the pixel (the MUTATION events; the others are their
 * samples' paths). */
static int mlt_splats(const CstExplain *x)
{
    int n = 0;
    for (int i = 0; i < x->num_events; i++) n += x->events[i].kind == CST_EXPLAIN_MUTATION;
    return n;
}

/* A replayed sample's path (the events after its MUTATION event), printed as `path` (pssmlt)
 * or `bdpt` (mmlt: one strategy) print theirs, indented under the splat. */
static void print_mlt_path(FILE *f, const CstExplain *x, const CstExplainEvent *m, const CstExplainEvent *ev)
{
    CstExplain v = *x;
    v.integrator = x->integrator == CST_INTEGRATOR_MMLT ? CST_INTEGRATOR_BDPT : CST_INTEGRATOR_PATH;
    fprintf(f, "    its sample evaluated again from its primary sample vector: L (%.9g, %.9g, %.9g), %s\n",
            (double)m->replay_value[0], (double)m->replay_value[1], (double)m->replay_value[2],
            (m->flags & CST_EXPLAIN_REPLAY_EXACT) ? "the splatted L, bit for bit" : "NOT the splatted L (MISMATCH)");
    for (int k = 0; k < m->path_events; k++) {
        const CstExplainEvent *e = &ev[k];
        fputs("    | ", f);
        if (e->kind == CST_EXPLAIN_VERTEX && e->depth < 0) { /* mmlt: the light subpath's hits */
            print_light_vertex(f, e);
            continue;
        }
        /* Continuation lines of an event get the same bar. */
        char *buf = NULL;
        size_t len = 0;
        FILE *m2 = open_memstream(&buf, &len);
        if (!m2) {
            print_event(f, &v, e);
            continue;
        }
        print_event(m2, &v, e);
        fclose(m2);
        for (size_t i = 0; i < len; i++) {
            fputc(buf[i], f);
            if (buf[i] == '\n' && i + 1 < len) fputs("    | ", f);
        }
        free(buf);
    }
}

/* MLT: the steps of the iteration whose splats reached the pixel, in the film's order. */
static void print_text_mlt(FILE *f, const CstExplain *x)
{
    fprintf(f, "pixel (%d, %d), iteration %d, integrator %s, %s: %d Metropolis splat(s) of %d chain(s) reach the "
            "pixel\n", x->x, x->y, x->sample, cst_integrator_name(x->integrator), x->spectral ? "spectral" : "RGB",
            mlt_splats(x), x->mlt_chains);
    fprintf(f, "b (the bootstrap's normalisation) %.9g; a splat adds b / (W H) = %.9g times weight x L (times the "
            "filter)\n", x->mlt_b, x->mlt_scale);
    if (x->mlt_replayed)
        fprintf(f, "the first %d splat(s)' samples evaluated again with their paths (at most %d are): %d give the "
                "splatted L bit for bit\n", x->mlt_replayed, (int)CST_EXPLAIN_MLT_PATHS, x->mlt_replay_exact);
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        if (e->flags & CST_EXPLAIN_IN_SPLAT) continue;
        print_event(f, x, e);
        if (e->kind == CST_EXPLAIN_MUTATION && (e->flags & CST_EXPLAIN_REPLAYED))
            print_mlt_path(f, x, e, &x->events[i + 1]);
    }
    if (x->truncated) fputs("(more splats than explain keeps: the list is truncated and not checked)\n", f);
    print_largest(f, x);
    fprintf(f, "the iteration's value (%.9g, %.9g, %.9g); the film's sum before it (%.9g, %.9g, %.9g) and after (%.9g, "
            "%.9g, %.9g): %s\n", x->splat_value[0], x->splat_value[1], x->splat_value[2], x->camera_value[0],
            x->camera_value[1], x->camera_value[2], x->film_value[0], x->film_value[1], x->film_value[2],
            x->truncated ? "not checked" : x->exact ? "the splats sum to the iteration's value, bit for bit" : "MISMATCH");
}

static void print_text(FILE *f, const CstExplain *x)
{
    if (x->integrator == CST_INTEGRATOR_SPPM) {
        cli_explain_sppm_text(f, x);
        return;
    }
    if (is_light(x)) {
        print_text_light(f, x);
        return;
    }
    if (is_mlt(x)) {
        print_text_mlt(f, x);
        return;
    }
    fprintf(f, "pixel (%d, %d), %s %d, integrator %s, %s\n", x->x, x->y, is_bdpt(x) ? "iteration" : "sample",
            x->sample, cst_integrator_name(x->integrator), x->spectral ? "spectral" : "RGB");
    if (x->spectral && x->wavelengths[0] > 0.0f) {
        fprintf(f, "wavelengths (%.6g, %.6g, %.6g, %.6g) nm", (double)x->wavelengths[0], (double)x->wavelengths[1],
                (double)x->wavelengths[2], (double)x->wavelengths[3]);
        if (x->photon_set >= 0) fprintf(f, ", photon set %d (its maps traced at them)", x->photon_set);
        fputs(": every value, beta and contribution below is per wavelength (the first three); the sum is "
              "converted to RGB\n", f);
    }
    /* BDPT, VCM: the pixel's light subpath (its events have depth -bounces), then the camera
     * path; the light step ran before it, its splats follow. */
    int splats = 0, light = 0;
    for (int i = 0; i < x->num_events; i++) light += x->events[i].kind != CST_EXPLAIN_SPLAT && x->events[i].depth < 0;
    if (light) {
        fputs("the pixel's light subpath (the light step's path of the pixel's index; listed, not summed):\n", f);
        for (int i = 0; i < x->num_events; i++)
            if (x->events[i].kind != CST_EXPLAIN_SPLAT && x->events[i].depth < 0) print_event(f, x, &x->events[i]);
        fputs("the camera subpath:\n", f);
    }
    for (int i = 0; i < x->num_events; i++) {
        if (x->events[i].kind == CST_EXPLAIN_SPLAT) splats++;
        else if (x->events[i].depth >= 0) print_event(f, x, &x->events[i]);
    }
    if (x->truncated) fputs("(more events than explain keeps: the list is truncated and not checked)\n", f);
    print_largest(f, x);
    print3(f, "sum of contributions x filter weight: ", x->sum);
    fprintf(f, "\n  filter weight %.9g\n", (double)x->filter_weight);
    fprintf(f, "camera sample the render computed: (%.9g, %.9g, %.9g): %s\n", x->camera_value[0],
            x->camera_value[1], x->camera_value[2],
            x->truncated ? "not checked" : x->exact ? "equal, bit for bit" : "MISMATCH");
    if (x->mis_checked)
        fprintf(f, "MIS check: %d strategies' weights computed again from every strategy's pdfs: largest relative "
                "difference %.3g, largest |sum - 1| %.3g\n", x->mis_checked, x->mis_max_error, x->mis_max_sum_error);
    if (splats) fputs("light paths' t = 1 connections landing within the filter's reach of the pixel:\n", f);
    for (int i = 0; i < x->num_events; i++)
        if (x->events[i].kind == CST_EXPLAIN_SPLAT) {
            fputs("  ", f);
            print_event(f, x, &x->events[i]);
        }
    if (is_bdpt(x))
        fprintf(f, "light paths' splats added (%.9g, %.9g, %.9g); the film's value for the iteration (%.9g, %.9g, "
                "%.9g): %s\n", x->splat_value[0], x->splat_value[1], x->splat_value[2], x->film_value[0],
                x->film_value[1], x->film_value[2],
                x->splats_exact ? "the camera sample and the splats sum to it, bit for bit" : "MISMATCH");
}

void cli_explain_view(const CstScene *scene, const CstRenderSettings *s, int x, int y, int sample, const char *mode)
{
    CstExplain *ex = NULL;
    CstError err = {0};
    CstStatus st = mode ? cst_explain(scene, s, x, y, sample, &ex, &err) : CST_ERR_UNSUPPORTED;
    if (st != CST_OK)
        printf("view: explain (%d, %d) in mode %s: %s\n", x, y, mode ? mode : "preview",
               mode ? err.msg : "the preview has no paths (switch to whitted, path, light, bdpt or vcm)");
    else
        printf("view: explain (%d, %d), mode %s, sample %d:\n", x, y, mode, sample);
    if (ex) print_text(stdout, ex);
    cst_explain_destroy(ex);
    fflush(stdout);
}

/* ------------------------------------------------------------------ JSON */

static json_t *num(double v) { return isfinite(v) ? json_real(v) : json_null(); }

static json_t *arr3f(const float v[3])
{
    return json_pack("[ooo]", num((double)v[0]), num((double)v[1]), num((double)v[2]));
}

static json_t *arr3d(const double v[3]) { return json_pack("[ooo]", num(v[0]), num(v[1]), num(v[2])); }

static json_t *event_json(const CstExplain *x, const CstExplainEvent *e)
{
    json_t *o = json_object();
    json_object_set_new(o, "kind", json_string(kind_name(e->kind)));
    json_object_set_new(o, "depth", json_integer(e->depth));
    if (e->s >= 0) {
        json_object_set_new(o, "s", json_integer(e->s));
        json_object_set_new(o, "t", json_integer(e->t));
    }
    if (e->light >= 0) json_object_set_new(o, "light", json_integer(e->light));
    switch (e->kind) {
    case CST_EXPLAIN_DISTANCE:
        json_object_set_new(o, "medium", json_integer(e->medium));
        json_object_set_new(o, "distance", num((double)e->distance));
        json_object_set_new(o, "scattered", json_boolean(e->flags & CST_EXPLAIN_SCATTERED));
        json_object_set_new(o, "pdf", num((double)e->pdf_w));
        json_object_set_new(o, "transmittance", arr3f(e->transmittance));
        json_object_set_new(o, "weight", arr3f(e->value));
        if (is_bdpt(x) || is_photon(x)) {
            json_object_set_new(o, "chain_fwd", num((double)e->chain_fwd));
            json_object_set_new(o, "chain_rev", num((double)e->chain_rev));
            json_object_set_new(o, "beta", arr3f(e->beta));
        }
        return o;
    case CST_EXPLAIN_VERTEX:
        if (e->medium >= 0) json_object_set_new(o, "medium", json_integer(e->medium));
        if (e->medium >= 0 && is_photon(x)) json_object_set_new(o, "g", num((double)e->q));
        json_object_set_new(o, "p", arr3f(e->p));
        json_object_set_new(o, "n", arr3f(e->n));
        json_object_set_new(o, "ng", arr3f(e->ng));
        json_object_set_new(o, "material", json_integer(e->material));
        json_object_set_new(o, "material_type", json_string(e->material_type ? e->material_type : "none"));
        if (e->mix_material >= 0) {
            json_object_set_new(o, "mix_material", json_integer(e->mix_material));
            json_object_set_new(o, "mix_material_type", json_string(e->mix_material_type));
        }
        return o;
    case CST_EXPLAIN_ROULETTE:
        json_object_set_new(o, "q", num((double)e->q));
        json_object_set_new(o, "survived", json_boolean(e->flags & CST_EXPLAIN_SURVIVED));
        return o;
    case CST_EXPLAIN_PHOTON:
        json_object_set_new(o, "p", arr3f(e->p));
        json_object_set_new(o, "wi", arr3f(e->wi));
        json_object_set_new(o, "power", arr3f(e->value));
        json_object_set_new(o, "f", arr3f(e->beta));
        json_object_set_new(o, "contribution", arr3f(e->contribution));
        return o;
    case CST_EXPLAIN_ESTIMATE:
        json_object_set_new(o, "map", json_string((e->flags & CST_EXPLAIN_VOLUME)    ? "volume"
                                                  : (e->flags & CST_EXPLAIN_CAUSTIC) ? "caustic"
                                                                                     : "global"));
        if (e->flags & CST_EXPLAIN_VOLUME) json_object_set_new(o, "sigma_s", arr3f(e->transmittance));
        json_object_set_new(o, "radius", num((double)e->distance));
        json_object_set_new(o, "kernel", num((double)e->pmf));
        json_object_set_new(o, "time_window", json_pack("[oo]", num((double)e->time_window[0]),
                                                        num((double)e->time_window[1])));
        json_object_set_new(o, "time_scale", num((double)e->time_scale));
        json_object_set_new(o, "photons", json_integer(e->path));
        json_object_set_new(o, "beta", arr3f(e->beta));
        json_object_set_new(o, "value", arr3f(e->value));
        json_object_set_new(o, "contribution", arr3f(e->contribution));
        return o;
    case CST_EXPLAIN_MUTATION:
        json_object_set_new(o, "chain", json_integer(e->chain));
        json_object_set_new(o, "step", json_integer(e->step));
        if (e->path_length >= 0) json_object_set_new(o, "path_length", json_integer(e->path_length));
        json_object_set_new(o, "proposal", json_boolean(e->flags & CST_EXPLAIN_PROPOSAL));
        json_object_set_new(o, "large_step", json_boolean(e->flags & CST_EXPLAIN_LARGE_STEP));
        json_object_set_new(o, "accepted", json_boolean(e->flags & CST_EXPLAIN_ACCEPTED));
        json_object_set_new(o, "accept", num((double)e->accept));
        json_object_set_new(o, "importance", num((double)e->importance));
        json_object_set_new(o, "weight", num((double)e->weight));
        json_object_set_new(o, "film", json_pack("[oo]", num((double)e->wi[0]), num((double)e->wi[1])));
        json_object_set_new(o, "value", arr3f(e->value));
        json_object_set_new(o, "contribution", arr3f(e->contribution));
        json_object_set_new(o, "share", arr3d(e->share));
        if (e->flags & CST_EXPLAIN_REPLAYED) { /* print_json adds its `path` */
            json_object_set_new(o, "replay_value", arr3f(e->replay_value));
            json_object_set_new(o, "replay_exact", json_boolean(e->flags & CST_EXPLAIN_REPLAY_EXACT));
        }
        return o;
    case CST_EXPLAIN_SCATTER:
        json_object_set_new(o, "delta", json_boolean(e->flags & CST_EXPLAIN_DELTA));
        json_object_set_new(o, "lobe", e->lobe ? json_string(e->lobe) : json_null());
        json_object_set_new(o, "wi", arr3f(e->wi));
        json_object_set_new(o, "pdf_w", num((double)e->pdf_w));
        json_object_set_new(o, "pmf", num((double)e->pmf));
        if (e->depth < 0) json_object_set_new(o, "pdf_rev", num((double)e->pdf_other_w)); /* a light subpath's */
        json_object_set_new(o, "weight", arr3f(e->value));
        json_object_set_new(o, "beta", arr3f(e->beta));
        return o;
    default: break;
    }
    if (e->kind != CST_EXPLAIN_ESCAPE) json_object_set_new(o, "p", arr3f(e->p));
    if (e->path >= 0) {
        json_object_set_new(o, "path", json_integer(e->path));
        json_object_set_new(o, "share", arr3d(e->share));
    }
    if (e->kind == CST_EXPLAIN_SPLAT) json_object_set_new(o, "raster", json_pack("[oo]", num((double)e->wi[0]),
                                                                                   num((double)e->wi[1])));
    json_object_set_new(o, "pdf_w", num((double)e->pdf_w));
    json_object_set_new(o, "pdf_a", num((double)e->pdf_a));
    if (is_bdpt(x)) {
        json_object_set_new(o, "w_light", num((double)e->pdf_other_w));
        json_object_set_new(o, "w_camera", num((double)e->pdf_other2));
        if (e->chain_fwd > 0.0f || e->chain_rev > 0.0f) { /* a connection through media */
            json_object_set_new(o, "chain_fwd", num((double)e->chain_fwd));
            json_object_set_new(o, "chain_rev", num((double)e->chain_rev));
            if (e->kind != CST_EXPLAIN_SPLAT) json_object_set_new(o, "transmittance", arr3f(e->transmittance));
        }
    } else {
        json_object_set_new(o, "pdf_other_w", num((double)e->pdf_other_w));
        if (e->kind == CST_EXPLAIN_NEE) {
            json_object_set_new(o, "pmf", num((double)e->pmf));
            json_object_set_new(o, "partner", json_string(nee_partner(x, e))); /* whose pdf_other_w */
            /* volpath: the shadow ray's transmittance (0 when occluded) */
            if (has3(e->transmittance) || (e->flags & CST_EXPLAIN_OCCLUDED))
                json_object_set_new(o, "transmittance", arr3f(e->transmittance));
        }
    }
    json_object_set_new(o, "mis_weight", num((double)e->mis_weight));
    if (e->mis_strategies > 0) {
        json_object_set_new(o, "mis_explicit", num((double)e->mis_explicit));
        json_object_set_new(o, "mis_sum", num((double)e->mis_sum));
        json_object_set_new(o, "mis_strategies", json_integer(e->mis_strategies));
    }
    json_object_set_new(o, "delta", json_boolean(e->flags & CST_EXPLAIN_DELTA));
    json_object_set_new(o, "occluded", json_boolean(e->flags & CST_EXPLAIN_OCCLUDED));
    json_object_set_new(o, "added", json_boolean(e->flags & CST_EXPLAIN_ADDED));
    if (e->flags & CST_EXPLAIN_HERO) json_object_set_new(o, "hero", json_true());
    if (e->flags & CST_EXPLAIN_LIGHT_DISPERSED) json_object_set_new(o, "light_dispersed", json_true());
    json_object_set_new(o, "beta", arr3f(e->beta));
    json_object_set_new(o, "value", arr3f(e->value));
    json_object_set_new(o, "contribution", arr3f(e->contribution));
    return o;
}

static bool print_json(FILE *f, const CstExplain *x)
{
    json_t *events = json_array();
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        json_t *ej = event_json(x, e);
        if (e->kind == CST_EXPLAIN_MUTATION && (e->flags & CST_EXPLAIN_REPLAYED)) {
            /* The sample's path, its events as `path` (pssmlt) or `bdpt` (mmlt) gives them. */
            CstExplain v = *x;
            v.integrator = x->integrator == CST_INTEGRATOR_MMLT ? CST_INTEGRATOR_BDPT : CST_INTEGRATOR_PATH;
            json_t *path = json_array();
            for (int k = 1; k <= e->path_events && i + k < x->num_events; k++)
                json_array_append_new(path, event_json(&v, &x->events[i + k]));
            json_object_set_new(ej, "path", path);
            i += e->path_events;
        }
        json_array_append_new(events, ej);
    }
    json_t *o = json_object();
    json_object_set_new(o, "pixel", json_pack("[ii]", x->x, x->y));
    json_object_set_new(o, "sample", json_integer(x->sample));
    json_object_set_new(o, "integrator", json_string(cst_integrator_name(x->integrator)));
    json_object_set_new(o, "spectral", json_boolean(x->spectral));
    json_object_set_new(o, "events", events);
    json_object_set_new(o, "truncated", json_boolean(x->truncated));
    json_object_set_new(o, "sum", arr3f(x->sum));
    json_object_set_new(o, "filter_weight", num((double)x->filter_weight));
    json_object_set_new(o, "camera_value", arr3d(x->camera_value));
    json_object_set_new(o, "splat_value", arr3d(x->splat_value));
    json_object_set_new(o, "film_value", arr3d(x->film_value));
    json_object_set_new(o, "exact", json_boolean(x->exact));
    if (x->spectral && x->wavelengths[0] > 0.0f)
        json_object_set_new(o, "wavelengths", json_pack("[oooo]", num((double)x->wavelengths[0]),
                                                        num((double)x->wavelengths[1]), num((double)x->wavelengths[2]),
                                                        num((double)x->wavelengths[3])));
    if (x->photon_set >= 0) json_object_set_new(o, "photon_set", json_integer(x->photon_set));
    if (is_bdpt(x)) {
        json_object_set_new(o, "mis_checked", json_integer(x->mis_checked));
        json_object_set_new(o, "mis_max_error", num(x->mis_max_error));
        json_object_set_new(o, "mis_max_sum_error", num(x->mis_max_sum_error));
        json_object_set_new(o, "splats_exact", json_boolean(x->splats_exact));
    }
    if (x->integrator == CST_INTEGRATOR_SPPM) cli_explain_sppm_json(o, x);
    if (is_mlt(x)) {
        json_object_set_new(o, "mlt_b", num(x->mlt_b));
        json_object_set_new(o, "mlt_scale", num(x->mlt_scale));
        json_object_set_new(o, "mlt_chains", json_integer(x->mlt_chains));
        json_object_set_new(o, "mlt_replayed", json_integer(x->mlt_replayed));
        json_object_set_new(o, "mlt_replay_exact", json_integer(x->mlt_replay_exact));
    }
    /* 17 significant digits: every float and double reads back to the same bits. */
    int rc = json_dumpf(o, f, JSON_INDENT(1) | JSON_REAL_PRECISION(17));
    json_decref(o);
    fputc('\n', f);
    return rc == 0;
}

/* --why-bright / --why-dark: one line for a student. Bright: the event carrying most of the
 * value, with what made it large (its density, MIS weight, and the path's least likely
 * scatter before it: a firefly's cause). Dark: how the path ended and which light samples
 * were blocked. */
static void print_why_bright(FILE *f, const CstExplain *x)
{
    double share;
    int b = largest_event(x, &share);
    if (b < 0) {
        fputs("why bright: it is not: nothing reached a light (try --why-dark)\n", f);
        return;
    }
    const CstExplainEvent *e = &x->events[b];
    if (e->kind == CST_EXPLAIN_MUTATION) {
        fprintf(f, "why bright: the %s's splat of chain %d, step %d (a %.4g, I %.6g, weight %.6g) gives %.1f%% of "
                "the pixel's iteration value\n", (e->flags & CST_EXPLAIN_PROPOSAL) ? "proposal" : "current state",
                e->chain, e->step, (double)e->accept, (double)e->importance, (double)e->weight, 100.0 * share);
        return;
    }
    if (e->path >= 0 && !is_photon(x)) {
        fprintf(f, "why bright: light path %d's connection to the camera at raster (%.2f, %.2f) gives %.1f%% of the "
                "pixel (luminance %.6g)\n", e->path, (double)e->wi[0], (double)e->wi[1], 100.0 * share,
                luminance(e->contribution));
        return;
    }
    fprintf(f, "why bright: %s at vertex %d", kind_name(e->kind), e->depth);
    if (e->s >= 0) fprintf(f, " (s=%d, t=%d)", e->s, e->t);
    fprintf(f, " gives %.1f%% of the sample (luminance %.6g = value %.6g x throughput %.6g)", 100.0 * share,
            luminance(e->contribution), luminance(e->value), luminance(e->beta));
    if (e->mis_weight >= 0.0f) fprintf(f, ", MIS w %.4g", (double)e->mis_weight);
    if (e->pdf_w > 0.0f && !is_whitted(x)) fprintf(f, ", pdf_w %.4g", (double)e->pdf_w);
    /* The least likely non-delta scatter before it: a small pdf makes a large throughput. */
    int low = -1;
    for (int i = 0; i < b; i++) {
        const CstExplainEvent *c = &x->events[i];
        if (c->kind == CST_EXPLAIN_SCATTER && c->depth >= 0 && !(c->flags & CST_EXPLAIN_DELTA) && c->pdf_w > 0.0f &&
            (low < 0 || c->pdf_w < x->events[low].pdf_w))
            low = i;
    }
    if (low >= 0)
        fprintf(f, "; the least likely scatter before it: vertex %d, pdf_w %.4g, weight f cos/pdf %.4g", x->events[low].depth,
                (double)x->events[low].pdf_w, luminance(x->events[low].value));
    fputc('\n', f);
}

static void print_why_dark(FILE *f, const CstExplain *x)
{
    const double *v = x->integrator == CST_INTEGRATOR_LIGHT ? x->film_value : is_mlt(x) ? x->splat_value
                                                                                        : x->camera_value;
    fprintf(f, "why dark: value (%.6g, %.6g, %.6g)", v[0], v[1], v[2]);
    if (is_mlt(x)) {
        fprintf(f, "; %d Metropolis splat(s) reached the pixel this iteration (the chains visit pixels in "
                "proportion to their brightness)\n", mlt_splats(x));
        return;
    }
    if (is_light(x)) {
        fprintf(f, "; %d light path connection(s) reached the pixel this iteration\n", x->num_events);
        return;
    }
    int vertices = 0, lights = 0, blocked = 0, zero = 0, last = -1;
    char where[96] = "";
    size_t wl = 0;
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        if (e->kind == CST_EXPLAIN_VERTEX) vertices = e->depth > vertices ? e->depth : vertices;
        if (e->kind == CST_EXPLAIN_NEE || e->kind == CST_EXPLAIN_CONNECT) {
            lights++;
            if (e->flags & CST_EXPLAIN_OCCLUDED) {
                blocked++;
                if (wl + 8 < sizeof where) wl += (size_t)snprintf(where + wl, sizeof where - wl, "%s%d", blocked > 1 ? ", " : "", e->depth);
            } else if ((e->flags & CST_EXPLAIN_ADDED) && luminance(e->contribution) == 0.0) {
                zero++;
            }
        }
        if (e->kind != CST_EXPLAIN_SPLAT) last = i;
    }
    if (vertices == 0) fputs("; the camera ray hit nothing", f);
    else fprintf(f, "; the path has %d vertices", vertices);
    if (last >= 0) {
        const CstExplainEvent *e = &x->events[last];
        if (e->kind == CST_EXPLAIN_ROULETTE && !(e->flags & CST_EXPLAIN_SURVIVED))
            fprintf(f, ", Russian roulette stopped it at vertex %d (survival %.3g)", e->depth, (double)e->q);
        else if (e->kind == CST_EXPLAIN_ESCAPE)
            fprintf(f, ", then it left the scene%s", luminance(e->contribution) > 0.0 ? "" : " (no light from there)");
    }
    if (lights) {
        fprintf(f, "; %d of %d light connection(s) blocked", blocked, lights);
        if (blocked) fprintf(f, " (at vertices %s)", where);
        if (zero) fprintf(f, ", %d added nothing (the surface turns away from the light)", zero);
    }
    double share;
    int b = largest_event(x, &share);
    if (b >= 0) fprintf(f, "; most of what there is: %s at vertex %d (%.1f%%)", kind_name(x->events[b].kind),
                        x->events[b].depth, 100.0 * share);
    else fputs("; nothing reached a light", f);
    fputc('\n', f);
}

int cli_explain(const CliArgs *a)
{
    CstScene *scene = NULL;
    int code = cli_load_scene(a, &scene, NULL);
    if (code != CLI_EXIT_OK) return code;
    CstExplain *x = NULL;
    CstError err = {0};
    CstStatus st = cst_explain(scene, &a->settings, a->pixel_x, a->pixel_y, a->explain_sample, &x, &err);
    cst_scene_destroy(scene);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        return cli_exit_code(st, CLI_STAGE_LOAD);
    }
    FILE *f = stdout;
    if (a->json_path && !(f = fopen(a->json_path, "w"))) {
        fprintf(stderr, "caustic: error: cannot write '%s'\n", a->json_path);
        cst_explain_destroy(x);
        return CLI_EXIT_USAGE;
    }
    /* --why-*: the one line alone (the check still decides the exit code). */
    const bool sppm_why = x->integrator == CST_INTEGRATOR_SPPM && a->explain_why;
    bool ok = a->json ? print_json(f, x) : sppm_why ? (cli_explain_sppm_why(f, x, a->explain_why == 2), true)
            : a->explain_why == 1 ? (print_why_dark(f, x), true)
            : a->explain_why == 2 ? (print_why_bright(f, x), true) : (print_text(f, x), true);
    if (f != stdout && fclose(f) != 0) ok = false;
    if (!ok) fprintf(stderr, "caustic: error: writing the explanation failed\n");
    /* The check is the point of the command: a sum that is not the render's value is a bug. */
    if (!x->exact && !x->truncated)
        fprintf(stderr, "caustic: explain: the contributions do not sum to the render's value (MISMATCH)\n");
    /* bdpt, vcm: the camera sample plus the splats must be the film's value too. */
    const bool splats_bad = is_bdpt(x) && !x->splats_exact && !x->truncated;
    if (splats_bad)
        fprintf(stderr, "caustic: explain: the camera sample and the splats do not sum to the film's value "
                "(MISMATCH)\n");
    code = !ok ? CLI_EXIT_INTERNAL : ((!x->exact && !x->truncated) || splats_bad) ? CLI_EXIT_MISMATCH : CLI_EXIT_OK;
    cst_explain_destroy(x);
    return code;
}
