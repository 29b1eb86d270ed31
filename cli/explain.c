/* caustic explain (issue 30): one pixel sample replayed by the library (cst_explain) and
 * printed, as text or with --json as one JSON object: the path's vertices, decisions,
 * densities, MIS weights and contributions, and whether they add up to the film's value. */
#include <math.h>
#include <stdio.h>
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
    }
    return "unknown";
}

static bool is_bdpt(const CstExplain *x) { return x->integrator == CST_INTEGRATOR_BDPT; }

/* ------------------------------------------------------------------ text */

static void print3(FILE *f, const char *label, const float v[3])
{
    fprintf(f, "%s(%.9g, %.9g, %.9g)", label, (double)v[0], (double)v[1], (double)v[2]);
}

static void print_mis(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    if (is_bdpt(x))
        fprintf(f, "MIS w %.9g = 1/(w_light %.6g + 1 + w_camera %.6g)", (double)e->mis_weight,
                (double)e->pdf_other_w, (double)e->pdf_other2);
    else
        fprintf(f, "MIS w %.9g", (double)e->mis_weight);
}

static void print_value(FILE *f, const CstExplainEvent *e)
{
    fputs("\n      ", f);
    print3(f, "value ", e->value);
    print3(f, " x beta ", e->beta);
    print3(f, " = contribution ", e->contribution);
    fputc('\n', f);
}

static void print_event(FILE *f, const CstExplain *x, const CstExplainEvent *e)
{
    switch (e->kind) {
    case CST_EXPLAIN_VERTEX:
        fprintf(f, "vertex %d: surface at (%.6g, %.6g, %.6g), normal (%.4f, %.4f, %.4f), material #%d (%s)",
                e->depth, (double)e->p[0], (double)e->p[1], (double)e->p[2], (double)e->n[0], (double)e->n[1],
                (double)e->n[2], e->material, e->material_type ? e->material_type : "none");
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
            fprintf(f, "pmf %.6g, pdf_w %.6g, pdf_a %.6g, BSDF pdf_w %.6g; ", (double)e->pmf, (double)e->pdf_w,
                    (double)e->pdf_a, (double)e->pdf_other_w);
        print_mis(f, x, e);
        if (e->flags & CST_EXPLAIN_OCCLUDED) fputs(", occluded", f);
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
    case CST_EXPLAIN_SPLAT:
        fprintf(f, "splat (s=%d, t=1) from a light vertex at (%.6g, %.6g, %.6g) to raster (%.4f, %.4f): camera "
                "pdf_a %.6g; MIS w %.9g = 1/(w_light %.6g + 1)\n      ", e->s, (double)e->p[0], (double)e->p[1],
                (double)e->p[2], (double)e->wi[0], (double)e->wi[1], (double)e->pdf_a, (double)e->mis_weight,
                (double)e->pdf_other_w);
        print3(f, "value (per unit film, before the filter) ", e->value);
        fputc('\n', f);
        return;
    case CST_EXPLAIN_SCATTER:
        if (e->flags & CST_EXPLAIN_DELTA)
            fprintf(f, "  scatter: delta lobe, pmf %.6g", (double)e->pmf);
        else
            fprintf(f, "  scatter: non-delta lobes, pdf_w %.6g", (double)e->pdf_w);
        fprintf(f, ", wi (%.4f, %.4f, %.4f), ", (double)e->wi[0], (double)e->wi[1], (double)e->wi[2]);
        print3(f, "weight f cos/pdf ", e->value);
        fputc('\n', f);
        return;
    case CST_EXPLAIN_ROULETTE:
        fprintf(f, "  roulette: survival probability %.6g, %s\n", (double)e->q,
                (e->flags & CST_EXPLAIN_SURVIVED) ? "survived (beta / q)" : "stopped");
        return;
    }
}

/* Luminance (Rec. 709 weights) of a linear RGB triple: "how much" for the summary line. */
static double luminance(const float c[3])
{
    return 0.2126 * (double)c[0] + 0.7152 * (double)c[1] + 0.0722 * (double)c[2];
}

/* The one line a student asks for first: which strategy at which vertex carries most of
 * the camera sample (a firefly's cause), with its share of the sum's luminance. */
static void print_largest(FILE *f, const CstExplain *x)
{
    int best = -1;
    double total = 0.0, best_y = 0.0;
    for (int i = 0; i < x->num_events; i++) {
        const CstExplainEvent *e = &x->events[i];
        if (!(e->flags & CST_EXPLAIN_ADDED)) continue;
        double y = luminance(e->contribution);
        total += y;
        if (best < 0 || y > best_y) { best = i; best_y = y; }
    }
    if (best < 0 || !(total > 0.0)) {
        fputs("nothing reached a light: the sample is black\n", f);
        return;
    }
    const CstExplainEvent *e = &x->events[best];
    fprintf(f, "largest contribution: %s at vertex %d", kind_name(e->kind), e->depth);
    if (e->s >= 0) fprintf(f, " (s=%d, t=%d)", e->s, e->t);
    fprintf(f, ", %.1f%% of the camera sample's luminance\n", 100.0 * best_y / total);
}

static void print_text(FILE *f, const CstExplain *x)
{
    fprintf(f, "pixel (%d, %d), %s %d, integrator %s, %s\n", x->x, x->y, is_bdpt(x) ? "iteration" : "sample",
            x->sample, cst_integrator_name(x->integrator), x->spectral ? "spectral" : "RGB");
    /* The camera path first; BDPT's light step ran before it, its splats follow. */
    int splats = 0;
    for (int i = 0; i < x->num_events; i++) {
        if (x->events[i].kind == CST_EXPLAIN_SPLAT) splats++;
        else print_event(f, x, &x->events[i]);
    }
    if (x->truncated) fputs("(more events than explain keeps: the list is truncated and not checked)\n", f);
    print_largest(f, x);
    print3(f, "sum of contributions x filter weight: ", x->sum);
    fprintf(f, "\n  filter weight %.9g\n", (double)x->filter_weight);
    fprintf(f, "camera sample the render computed: (%.9g, %.9g, %.9g): %s\n", x->camera_value[0],
            x->camera_value[1], x->camera_value[2],
            x->truncated ? "not checked" : x->exact ? "equal, bit for bit" : "MISMATCH");
    if (splats) fputs("light paths' t = 1 connections landing within the filter's reach of the pixel:\n", f);
    for (int i = 0; i < x->num_events; i++)
        if (x->events[i].kind == CST_EXPLAIN_SPLAT) {
            fputs("  ", f);
            print_event(f, x, &x->events[i]);
        }
    if (is_bdpt(x))
        fprintf(f, "light paths' splats added (%.9g, %.9g, %.9g); the film's value for the iteration (%.9g, %.9g, "
                "%.9g)\n", x->splat_value[0], x->splat_value[1], x->splat_value[2], x->film_value[0],
                x->film_value[1], x->film_value[2]);
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
    case CST_EXPLAIN_VERTEX:
        json_object_set_new(o, "p", arr3f(e->p));
        json_object_set_new(o, "n", arr3f(e->n));
        json_object_set_new(o, "ng", arr3f(e->ng));
        json_object_set_new(o, "material", json_integer(e->material));
        json_object_set_new(o, "material_type", json_string(e->material_type ? e->material_type : "none"));
        return o;
    case CST_EXPLAIN_ROULETTE:
        json_object_set_new(o, "q", num((double)e->q));
        json_object_set_new(o, "survived", json_boolean(e->flags & CST_EXPLAIN_SURVIVED));
        return o;
    case CST_EXPLAIN_SCATTER:
        json_object_set_new(o, "delta", json_boolean(e->flags & CST_EXPLAIN_DELTA));
        json_object_set_new(o, "wi", arr3f(e->wi));
        json_object_set_new(o, "pdf_w", num((double)e->pdf_w));
        json_object_set_new(o, "pmf", num((double)e->pmf));
        json_object_set_new(o, "weight", arr3f(e->value));
        json_object_set_new(o, "beta", arr3f(e->beta));
        return o;
    default: break;
    }
    if (e->kind != CST_EXPLAIN_ESCAPE) json_object_set_new(o, "p", arr3f(e->p));
    if (e->kind == CST_EXPLAIN_SPLAT) json_object_set_new(o, "raster", json_pack("[oo]", num((double)e->wi[0]),
                                                                                   num((double)e->wi[1])));
    json_object_set_new(o, "pdf_w", num((double)e->pdf_w));
    json_object_set_new(o, "pdf_a", num((double)e->pdf_a));
    if (is_bdpt(x)) {
        json_object_set_new(o, "w_light", num((double)e->pdf_other_w));
        json_object_set_new(o, "w_camera", num((double)e->pdf_other2));
    } else {
        json_object_set_new(o, "pdf_other_w", num((double)e->pdf_other_w));
        if (e->kind == CST_EXPLAIN_NEE) json_object_set_new(o, "pmf", num((double)e->pmf));
    }
    json_object_set_new(o, "mis_weight", num((double)e->mis_weight));
    json_object_set_new(o, "delta", json_boolean(e->flags & CST_EXPLAIN_DELTA));
    json_object_set_new(o, "occluded", json_boolean(e->flags & CST_EXPLAIN_OCCLUDED));
    json_object_set_new(o, "added", json_boolean(e->flags & CST_EXPLAIN_ADDED));
    json_object_set_new(o, "beta", arr3f(e->beta));
    json_object_set_new(o, "value", arr3f(e->value));
    json_object_set_new(o, "contribution", arr3f(e->contribution));
    return o;
}

static bool print_json(FILE *f, const CstExplain *x)
{
    json_t *events = json_array();
    for (int i = 0; i < x->num_events; i++) json_array_append_new(events, event_json(x, &x->events[i]));
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
    /* 17 significant digits: every float and double reads back to the same bits. */
    int rc = json_dumpf(o, f, JSON_INDENT(1) | JSON_REAL_PRECISION(17));
    json_decref(o);
    fputc('\n', f);
    return rc == 0;
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
    bool ok = a->json ? print_json(f, x) : (print_text(f, x), true);
    if (f != stdout && fclose(f) != 0) ok = false;
    if (!ok) fprintf(stderr, "caustic: error: writing the explanation failed\n");
    /* The check is the point of the command: a sum that is not the render's value is a bug. */
    if (!x->exact && !x->truncated)
        fprintf(stderr, "caustic: explain: the contributions do not sum to the render's value (MISMATCH)\n");
    code = !ok ? CLI_EXIT_INTERNAL : (!x->exact && !x->truncated) ? CLI_EXIT_MISMATCH : CLI_EXIT_OK;
    cst_explain_destroy(x);
    return code;
}
