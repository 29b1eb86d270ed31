/* `caustic bench rays` as a library call (cst_bench_rays): builds every acceleration back
 * end over one of bench/raysets.c's scenes, times the primary, secondary and occlusion ray
 * sets, checks the results against RAYSETS.md's reference (or the first back end, ray by
 * ray) and writes the table or JSON lines to the caller's stream. */

#include <errno.h>
#include <math.h>
#include <stdbool.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>

#include <jansson.h>

#include "accel/accel.h"
#include "caustic/caustic.h"
#include "core/error.h"
#include "raysets.h"

/* The CLI's bound on --threads (cli/args.h). */
#define BENCH_MAX_THREADS 1024


/* Back ends run by default: brute force only where it finishes in seconds. */
#define BENCH_LIST_MAX_TRIS 1000
/* --stadium alone: a 20,480-triangle bumpy ball as the teapot. */
#define BENCH_BALL_LEVELS 5
/* Each figure is the best of up to this many runs, repeated while under a second in all. */
#define BENCH_MAX_REPEATS 5
#define BENCH_REPEAT_SECONDS 1.0

enum { BENCH_PRIMARY, BENCH_SECONDARY, BENCH_OCCLUSION, BENCH_NUM_SETS };
static const char *const BENCH_SET_NAMES[BENCH_NUM_SETS] = {"primary", "secondary", "occlusion"};

/* A back end of the benchmark: an acceleration structure, and for Embree which mode. */
typedef struct BenchBackend {
    AccelType type;
    bool robust; /* Embree in its robust mode (EMBREE_NATIVE_ROBUST) */
} BenchBackend;

static const char *bench_name(BenchBackend b)
{
    return b.type == ACCEL_EMBREE && b.robust ? "embree-robust" : accel_type_name(b.type);
}

static bool bench_same(BenchBackend a, BenchBackend b) { return a.type == b.type && a.robust == b.robust; }

typedef struct BenchRow {
    BenchBackend accel;
    double build_ms, bytes_per_tri;
    int set, threads;
    RaysetStats st; /* of the fastest run */
    int runs;
    bool checked, ok;   /* checked: there was something to compare with */
    const char *against; /* "reference", the back end compared with, or "1 thread" */
    double vs_embree;   /* M rays/s ratio to Embree's row; < 0 when there is none */
    double vs_robust;   /* the same against Embree's robust mode */
    /* Scenes without a reference, 1-thread rows of all but the first back end: the rays
     * whose result differs from the first back end's (rayset_compare). */
    bool compared;
    size_t rays_differing;
    double dt_sum;
    /* Scenes with a reference, in a build with Embree, 1-thread closest-hit rows: the
     * grazing ties against Embree's default mode on the same rays (rayset_compare_ties),
     * which rayset_sum_t_match_ties allows for. */
    bool tied;
    size_t ties;
    double dt_ties;
} BenchRow;

typedef struct BenchRays {
    const Ray *rays[BENCH_NUM_SETS];
    size_t count[BENCH_NUM_SETS];
} BenchRays;

static double bench_mrays(const RaysetStats *st)
{
    return st->seconds > 0.0 ? (double)st->rays / st->seconds / 1e6 : 0.0;
}

/* The expected (hits, sum t) of a set from RAYSETS.md's reference row. */
static void bench_expected(const RaysetReference *ref, int set, size_t *hits, double *sum_t)
{
    *hits = set == BENCH_PRIMARY ? ref->primary_hits : ref->secondary_hits;
    *sum_t = set == BENCH_PRIMARY ? ref->primary_sum_t : ref->secondary_sum_t;
}

/* Checks every row. With a reference row (RAYSETS.md): hits, ray counts and sum t against
 * it. Without: each back end's 1-thread rows against the first back end's, ray by ray (at
 * most a handful of rays may differ, and they must explain the sum-t difference). Every
 * N-thread row must equal the same back end's 1-thread row exactly. */
static void bench_check(BenchRow *rows, int n, const RaysetReference *ref, bool published_bounces)
{
    /* N-thread rows have the 1-thread row's per-ray results (checked below to be identical),
     * hence its grazing ties. */
    for (int i = 0; i < n; i++)
        for (int k = 0; k < n && rows[i].threads != 1; k++)
            if (bench_same(rows[k].accel, rows[i].accel) && rows[k].set == rows[i].set && rows[k].threads == 1) {
                rows[i].tied = rows[k].tied;
                rows[i].ties = rows[k].ties;
                rows[i].dt_ties = rows[k].dt_ties;
            }
    for (int i = 0; i < n; i++) {
        BenchRow *r = &rows[i];
        bool any = r->set == BENCH_OCCLUSION;
        r->ok = true;
        r->checked = false;
        if (ref) {
            size_t hits;
            double sum_t;
            bench_expected(ref, r->set, &hits, &sum_t);
            /* Bounce rays made from other hits than Embree's are not exactly the published
             * set (a few start on other surfaces): only their counts can be checked. */
            bool counts_only = r->set != BENCH_PRIMARY && !published_bounces;
            r->ok = rayset_hits_match(r->st.hits, hits) &&
                    (any || counts_only ||
                     rayset_sum_t_match_ties(r->st.sum_t, sum_t, r->st.hits, hits, (double)r->st.max_t,
                                             r->st.rays, r->tied ? r->ties : 0, r->tied ? r->dt_ties : 0.0));
            if (r->set != BENCH_PRIMARY) r->ok = r->ok && rayset_hits_match(r->st.rays, ref->secondary_rays);
            r->checked = true;
            r->against = counts_only && !any ? "reference (counts only)" : "reference";
        } else if (r->compared) {
            /* The first back end's 1-thread row of this set: rows[0..) are its rows. */
            const BenchRow *b = r;
            for (int k = 0; k < n; k++)
                if (bench_same(rows[k].accel, rows[0].accel) && rows[k].set == r->set && rows[k].threads == 1)
                    b = &rows[k];
            r->ok = r->rays_differing <= rayset_rays_tolerance(r->st.rays) &&
                    rayset_hits_match(r->st.hits, b->st.hits) &&
                    (any || fabs(r->st.sum_t - b->st.sum_t) <= RAYSET_SUM_T_TOLERANCE * fabs(b->st.sum_t) + r->dt_sum);
            r->checked = true;
            r->against = bench_name(b->accel);
        }
        if (r->threads != 1)
            for (int k = 0; k < i; k++) {
                const BenchRow *o = &rows[k];
                if (!bench_same(o->accel, r->accel) || o->set != r->set || o->threads != 1) continue;
                bool same = o->st.hits == r->st.hits && o->st.sum_t == r->st.sum_t &&
                            o->st.sum_prim == r->st.sum_prim;
                r->ok = r->ok && same && (!o->checked || o->ok);
                if (!r->checked) {
                    r->checked = true;
                    r->against = o->checked ? o->against : "1 thread";
                }
            }
        r->vs_embree = r->vs_robust = -1.0;
        for (int k = 0; k < n; k++)
            if (rows[k].accel.type == ACCEL_EMBREE && rows[k].set == r->set && rows[k].threads == r->threads &&
                bench_mrays(&rows[k].st) > 0.0)
                *(rows[k].accel.robust ? &r->vs_robust : &r->vs_embree) =
                    bench_mrays(&r->st) / bench_mrays(&rows[k].st);
    }
}

/* Three significant digits, without exponent down to 0.001 (slow back ends). */
static void bench_format3(double v, char *buf, size_t size)
{
    snprintf(buf, size, v >= 100.0 ? "%.0f" : v >= 10.0 ? "%.1f" : v >= 1.0 ? "%.2f" : v >= 0.001 ? "%.3f" : "%.2g",
             v);
}

/* "1.23x", or "-" for a ratio that is missing (< 0). */
static void bench_format_ratio(double v, char *buf, size_t size)
{
    if (v < 0.0) {
        snprintf(buf, size, "-");
        return;
    }
    bench_format3(v, buf, size - 1);
    strcat(buf, "x");
}

static void bench_print_table(FILE *out, const BenchRow *rows, int n)
{
    fprintf(out, "%-13s %9s %9s  %-9s %7s %9s %9s %9s %9s %9s %16s  %s\n", "accel", "build ms", "bytes/tri",
           "set", "threads", "rays", "Mrays/s", "vs embree", "vs robust", "hits", "sum_t", "check");
    for (int i = 0; i < n; i++) {
        const BenchRow *r = &rows[i];
        char ratio[32], ratio_robust[32], rate[32], sum[32], check[48];
        bench_format3(bench_mrays(&r->st), rate, sizeof rate);
        bench_format_ratio(r->vs_embree, ratio, sizeof ratio);
        bench_format_ratio(r->vs_robust, ratio_robust, sizeof ratio_robust);
        if (r->set == BENCH_OCCLUSION) snprintf(sum, sizeof sum, "-");
        else snprintf(sum, sizeof sum, "%.9e", r->st.sum_t);
        if (!r->checked) snprintf(check, sizeof check, "(basis)");
        else if (r->against && strcmp(r->against, "reference (counts only)") == 0)
            snprintf(check, sizeof check, "%s (counts only)", r->ok ? "OK" : "MISMATCH");
        else if (r->tied && r->ties > 0)
            snprintf(check, sizeof check, "%s (%zu grazing tie%s)", r->ok ? "OK" : "MISMATCH", r->ties,
                     r->ties == 1 ? "" : "s");
        else if (r->compared && r->rays_differing > 0)
            snprintf(check, sizeof check, "%s (%zu ray%s differ%s)", r->ok ? "OK" : "MISMATCH", r->rays_differing,
                     r->rays_differing == 1 ? "" : "s", r->rays_differing == 1 ? "s" : "");
        else snprintf(check, sizeof check, "%s", r->ok ? "OK" : "MISMATCH");
        fprintf(out, "%-13s %9.2f %9.1f  %-9s %7d %9zu %9s %9s %9s %9zu %16s  %s\n", bench_name(r->accel),
               r->build_ms, r->bytes_per_tri, BENCH_SET_NAMES[r->set], r->threads, r->st.rays, rate, ratio,
               ratio_robust, r->st.hits, sum, check);
    }
}

/* One compact JSON object per row; false if jansson runs out of memory. */
static bool bench_print_json(FILE *out, const BenchRow *rows, int n, const RaysetScene *scene)
{
    for (int i = 0; i < n; i++) {
        const BenchRow *r = &rows[i];
        bool closest = r->set != BENCH_OCCLUSION;
        json_t *o = json_pack("{s:s, s:i, s:s, s:i, s:s, s:I, s:f, s:i, s:f, s:I, s:o, s:o, s:f, s:f, s:o, s:o, s:o, s:o, s:o, s:o}",
            "scene", scene->name, "triangles", scene->num_tris,
            "accel", bench_name(r->accel), "threads", r->threads,
            "set", BENCH_SET_NAMES[r->set], "rays", (json_int_t)r->st.rays,
            "seconds", r->st.seconds, "runs", r->runs, "mrays_per_s", bench_mrays(&r->st),
            "hits", (json_int_t)r->st.hits,
            "sum_t", closest ? json_real(r->st.sum_t) : json_null(),
            "sum_prim", closest ? json_integer((json_int_t)r->st.sum_prim) : json_null(),
            "build_ms", r->build_ms, "bytes_per_tri", r->bytes_per_tri,
            "vs_embree", r->vs_embree >= 0.0 ? json_real(r->vs_embree) : json_null(),
            "vs_embree_robust", r->vs_robust >= 0.0 ? json_real(r->vs_robust) : json_null(),
            "check", r->checked ? json_string(r->ok ? "OK" : "MISMATCH") : json_null(),
            "checked_against", r->checked ? json_string(r->against) : json_null(),
            "rays_differing", r->compared ? json_integer((json_int_t)r->rays_differing) : json_null(),
            "grazing_ties", r->tied ? json_integer((json_int_t)r->ties) : json_null());
        char *line = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
        json_decref(o);
        if (!line) return false;
        fprintf(out, "%s\n", line);
        free(line);
    }
    return true;
}

/* Traces one set with one thread count through every built back end, in rounds: each
 * round runs each back end once, and each row keeps its fastest run. A back end leaves
 * the rounds once its runs add up to BENCH_REPEAT_SECONDS (the grid in the stadium
 * runs once). Interleaving puts the VM's slow spells, which last seconds, into every back
 * end's runs alike instead of into one back end's whole series, so they move the ratios
 * less. rows[i] is back end i's row. When `basis` is given (scenes without a
 * reference), the first run at 1 thread keeps its results there (back end 0) or compares
 * them with it ray by ray (the others, through `scratch`). When `embree` is given (scenes
 * with a reference, Embree's default-mode results of the closest-hit sets), every back
 * end's first 1-thread run of a closest-hit set counts its grazing ties against it. */
static CstStatus bench_set(const Accel *accels, int num_accels, const BenchRays *rays, int set, int threads,
                               RaysetResult *const *basis, const RaysetResult *const *embree,
                               const RaysetScene *scene, RaysetResult *scratch, BenchRow *const *rows, CstError *err)
{
    RaysetQuery q = set == BENCH_OCCLUSION ? RAYSET_ANY : RAYSET_CLOSEST;
    double spent[CST_BENCH_MAX_ACCELS] = {0.0};
    for (int rep = 0; rep < BENCH_MAX_REPEATS; rep++)
        for (int i = 0; i < num_accels; i++) {
            BenchRow *r = rows[i];
            if (rep > 0 && spent[i] >= BENCH_REPEAT_SECONDS) continue;
            bool tie_run = rep == 0 && embree && embree[set] && threads == 1;
            RaysetResult *out = rep == 0 && basis && threads == 1 ? (i == 0 ? basis[set] : scratch)
                                : tie_run ? scratch : NULL;
            RaysetStats run;
            CstStatus st = rayset_trace(&accels[i], rays->rays[set], rays->count[set], q, threads, out, &run, err);
            if (st != CST_OK) return st;
            spent[i] += run.seconds;
            if (rep == 0 || run.seconds < r->st.seconds) r->st = run;
            r->runs = rep + 1;
            if (out && basis && i > 0) {
                r->compared = true;
                r->rays_differing = rayset_compare(out, basis[set], rays->count[set], q, &r->dt_sum);
            }
            if (tie_run) {
                r->tied = true;
                rayset_compare_ties(scene, rays->rays[set], out, embree[set], rays->count[set], &r->ties,
                                    &r->dt_ties);
            }
        }
    return CST_OK;
}

/* The back ends named in the options, in order: an unknown name or one this build lacks
 * is the caller's error. */
static CstStatus bench_parse_accels(const CstBenchRaysOptions *b, BenchBackend *accels, int *num_accels,
                                    CstError *err)
{
    for (int i = 0; i < b->num_accels && i < CST_BENCH_MAX_ACCELS; i++) {
        BenchBackend be = {ACCEL_EMBREE, strcmp(b->accels[i], "embree-robust") == 0};
        if (!be.robust && !accel_type_from_name(b->accels[i], &be.type))
            return cst_fail(err, CST_ERR_INVALID_ARG, "unknown acceleration structure '%s'", b->accels[i]);
        if (!accel_type_available(be.type))
            return cst_fail(err, CST_ERR_UNSUPPORTED, "acceleration structure '%s' is not available in this build",
                            b->accels[i]);
        accels[(*num_accels)++] = be;
    }
    return CST_OK;
}

/* The benchmark's scene: the mesh file, the dense ball (stadium alone) or the Cornell
 * box, inside the stadium if asked. */
static CstStatus bench_load_scene(const CstBenchRaysOptions *b, RaysetScene *scene, CstError *err)
{
    CstStatus st;
    if (b->mesh_path) {
        struct stat sb;
        if (stat(b->mesh_path, &sb) != 0)
            return cst_fail(err, CST_ERR_IO, "cannot open mesh '%s': %s", b->mesh_path, strerror(errno));
        if (S_ISDIR(sb.st_mode))
            return cst_fail(err, CST_ERR_IO, "mesh '%s' is a directory", b->mesh_path);
        st = rayset_scene_mesh(b->mesh_path, scene, err);
    } else if (b->stadium && !b->cornell) {
        st = rayset_scene_bumpy_ball(BENCH_BALL_LEVELS, scene, err);
    } else {
        st = rayset_scene_cornell(scene, err);
    }
    if (st == CST_OK && b->stadium) st = rayset_scene_add_stadium(scene, err);
    return st;
}

/* The lines above the table: the scene, the ray sets, what the checks compare, timing. */
static void bench_print_header(FILE *out, const CstBenchRaysOptions *b, const RaysetScene *s,
                               const RaysetReference *ref, AccelType gen_type, size_t num_primary,
                               size_t num_secondary)
{
    const RaysetScene scene = *s;
    fprintf(out, "scene:   %s, %d triangles, bbox diagonal %.9g", scene.name, scene.num_tris, scene.diag);
    if (b->stadium)
        fprintf(out, " (the teapot's: camera and offsets are its own; stadium half-size %g x diagonal)",
               RAYSET_STADIUM_SCALE);
    fprintf(out, "\n");
    fprintf(out, "rays:    primary %zu (%dx%d), secondary %zu and occlusion %zu (bounces of %s's primary hits)\n",
           num_primary, scene.camera.width, scene.camera.height, num_secondary, num_secondary,
           accel_type_name(gen_type));
    if (ref)
        fprintf(out, "checks:  against RAYSETS.md's \"%s\" row: hits within max(%d, %g x count); sum_t within %g "
               "relative, plus |hits difference| x largest t%s%s\n", ref->scene, RAYSET_HITS_TOLERANCE_ABS,
               RAYSET_HITS_TOLERANCE_REL, RAYSET_SUM_T_TOLERANCE,
               gen_type == ACCEL_EMBREE ? ", plus |dt| of the rays grazing a silhouette where Embree's default "
                                          "mode hits another surface (at most as many rays as hits may differ)" : "",
               gen_type == ACCEL_EMBREE ? "" : "; secondary sum_t unchecked (bounces not made from Embree's hits)");
    else
        fprintf(out, "checks:  no reference checksums: every back end against the first, ray by ray: at most "
               "max(%d, %g x count) rays may differ (hit vs miss, or t off by more than %g relative); hits "
               "within the same; sum_t within %g relative plus what the differing rays explain\n",
               RAYSET_HITS_TOLERANCE_ABS, RAYSET_HITS_TOLERANCE_REL, RAYSET_T_TOLERANCE,
               RAYSET_SUM_T_TOLERANCE);
    fprintf(out, "timing:  Mrays/s of the fastest of up to %d runs (repeated while under %g s in all), the back "
           "ends taking turns on each set\n", BENCH_MAX_REPEATS, BENCH_REPEAT_SECONDS);
    fprintf(out, "\n");
    fflush(out);
}

CstStatus cst_bench_rays(const CstBenchRaysOptions *o, CstBenchRaysResult *result, CstError *err)
{
    const CstBenchRaysOptions *b = o;
    CstStatus st = CST_ERR_INTERNAL;
    cst_error_clear(err);
    memset(result, 0, sizeof *result);
    RaysetScene scene;
    Ray *primary = NULL, *secondary = NULL, *occlusion = NULL;
    RaysetResult *hits = NULL, *basis[BENCH_NUM_SETS] = {NULL, NULL, NULL}, *scratch = NULL;
    RaysetResult *embree_secondary = NULL;
    BenchRow *rows = NULL;
    Accel gen;
    memset(&gen, 0, sizeof gen);
    Accel built[CST_BENCH_MAX_ACCELS]; /* built[0 .. num_built) are freed at done */
    BenchBackend built_as[CST_BENCH_MAX_ACCELS];
    int num_built = 0;
    memset(&scene, 0, sizeof scene);

    /* The back ends, checked before any work: as listed (one this build lacks is a usage
     * error), else every one this build has, brute force only for tiny scenes. */
    BenchBackend accels[CST_BENCH_MAX_ACCELS];
    int num_accels = 0;
    bool explicit_accels = b->num_accels > 0;
    if (explicit_accels && (st = bench_parse_accels(b, accels, &num_accels, err)) != CST_OK) {
        result->input_error = 1;
        goto done;
    }

    st = bench_load_scene(b, &scene, err);
    if (st != CST_OK) {
        rayset_scene_free(&scene);
        result->input_error = b->mesh_path != NULL; /* the built-in scenes failing is not the user's doing */
        return st;
    }
    const RaysetReference *ref = b->stadium ? NULL : rayset_reference(&scene);

    if (!explicit_accels) {
        for (int t = 0; t < ACCEL_TYPE_COUNT; t++) {
            if (!accel_type_available((AccelType)t)) continue;
            if (t == ACCEL_LIST && scene.num_tris > BENCH_LIST_MAX_TRIS) {
                if (o->log) fprintf(o->log, "caustic: bench rays: skipping list (brute force over %d triangles; "
                        "name it with --accel to run it anyway)\n", scene.num_tris);
                continue;
            }
            accels[num_accels++] = (BenchBackend){(AccelType)t, false};
            if (t == ACCEL_EMBREE) accels[num_accels++] = (BenchBackend){ACCEL_EMBREE, true};
        }
    }

    int max_threads = b->threads;
    if (max_threads == 0) {
        long ncpu = sysconf(_SC_NPROCESSORS_ONLN);
        max_threads = ncpu > 0 ? (int)(ncpu < BENCH_MAX_THREADS ? ncpu : BENCH_MAX_THREADS) : 1;
    }
    int threads[2] = {1, max_threads};
    int num_threads = max_threads > 1 ? 2 : 1;

    /* The ray sets. Bounce rays come once from one back end's primary hits and are shared
     * by all: Embree's when this build has it (RAYSETS.md's references were made from
     * Embree's hits, so the secondary set is then the published one bit for bit), else
     * the BVH's. */
    size_t num_primary, num_secondary;
    primary = rayset_primary(&scene, &num_primary);
    hits = primary ? malloc(num_primary * sizeof *hits) : NULL;
    if (!primary || !hits) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for %d x %d primary rays", scene.camera.width,
                      scene.camera.height);
        goto done;
    }
    AccelType gen_type = accel_type_available(ACCEL_EMBREE) ? ACCEL_EMBREE : ACCEL_BVH;
    AccelGeometry geom = rayset_scene_geometry(&scene);
    RaysetStats gen_stats;
    /* Embree alone, its own hits: RAYSETS.md's bounces come from them. */
    if ((st = accel_build_native(&gen, gen_type, &geom, err)) != CST_OK ||
        (st = rayset_trace(&gen, primary, num_primary, RAYSET_CLOSEST, max_threads, hits, &gen_stats, err)) != CST_OK)
        goto done;
    secondary = rayset_secondary(&scene, primary, hits, num_primary, &num_secondary);
    occlusion = secondary ? rayset_occlusion(secondary, num_secondary) : NULL;
    /* With a reference and Embree: Embree's default-mode results of the closest-hit sets
     * (the primary ones are `hits`), the basis of the grazing ties that the sum-t check
     * allows for (rayset_sum_t_match_ties). Not timed. */
    const RaysetResult *embree[BENCH_NUM_SETS] = {NULL, NULL, NULL};
    if (ref && gen_type == ACCEL_EMBREE && secondary) {
        embree_secondary = malloc((num_secondary ? num_secondary : 1) * sizeof *embree_secondary);
        size_t most = num_primary > num_secondary ? num_primary : num_secondary;
        scratch = malloc((most ? most : 1) * sizeof *scratch);
        if (!embree_secondary || !scratch) {
            st = cst_fail(err, CST_ERR_OOM, "out of memory for the per-ray results");
            goto done;
        }
        RaysetStats es;
        st = rayset_trace(&gen, secondary, num_secondary, RAYSET_CLOSEST, max_threads, embree_secondary, &es, err);
        if (st != CST_OK) goto done;
        embree[BENCH_PRIMARY] = hits;
        embree[BENCH_SECONDARY] = embree_secondary;
    }
    accel_free(&gen);
    rows = calloc((size_t)CST_BENCH_MAX_ACCELS * BENCH_NUM_SETS * 2, sizeof *rows);
    if (!secondary || !occlusion || !rows) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for %zu secondary rays", num_primary);
        goto done;
    }
    BenchRays rays = {{primary, secondary, occlusion}, {num_primary, num_secondary, num_secondary}};
    if (!ref) { /* per-ray comparison with the first back end */
        for (int set = 0; set < BENCH_NUM_SETS; set++)
            if (!(basis[set] = malloc((rays.count[set] ? rays.count[set] : 1) * sizeof *basis[set]))) break;
        size_t most = num_primary > num_secondary ? num_primary : num_secondary;
        scratch = malloc((most ? most : 1) * sizeof *scratch);
        if (!basis[BENCH_NUM_SETS - 1] || !scratch) {
            st = cst_fail(err, CST_ERR_OOM, "out of memory for the per-ray results");
            goto done;
        }
    }

    if (!b->json) bench_print_header(o->out, b, &scene, ref, gen_type, num_primary, num_secondary);

    /* Every back end is built before any is timed, so that the rounds can interleave
     * them (bench_set). */
    for (int i = 0; i < num_accels; i++) {
        Accel *accel = &built[num_built];
        st = (accels[i].robust ? accel_build_native_robust : accel_build_native)(accel, accels[i].type, &geom, err);
        if (st == CST_ERR_UNSUPPORTED && !explicit_accels) {
            if (o->log) fprintf(o->log, "caustic: bench rays: skipping %s: %s\n", bench_name(accels[i]), err->msg);
            cst_error_clear(err);
            continue;
        }
        if (st != CST_OK) {
            result->input_error = st == CST_ERR_UNSUPPORTED; /* a back end named with --accel */
            goto done;
        }
        built_as[num_built++] = accels[i];
        if (o->log && o->verbose)
            if (o->log) fprintf(o->log, "caustic: bench rays: %s built in %.1f ms\n", bench_name(accels[i]),
                    accel->build_seconds * 1e3);
    }
    const int nb = num_built;
    if (nb == 0) {
        st = cst_fail(err, CST_ERR_INTERNAL, "no acceleration structure could be built");
        goto done;
    }
    if (o->log && o->verbose) if (o->log) fprintf(o->log, "caustic: bench rays: tracing...\n");

    /* Rows grouped by back end, then set, then thread count. */
    int n = nb * BENCH_NUM_SETS * num_threads;
    for (int i = 0; i < nb; i++) {
        double bpt = scene.num_tris > 0 ? (double)accel_memory_bytes(&built[i]) / scene.num_tris : 0.0;
        for (int set = 0; set < BENCH_NUM_SETS; set++)
            for (int k = 0; k < num_threads; k++) {
                BenchRow *r = &rows[(i * BENCH_NUM_SETS + set) * num_threads + k];
                r->accel = built_as[i];
                r->build_ms = built[i].build_seconds * 1e3;
                r->bytes_per_tri = bpt;
                r->set = set;
                r->threads = threads[k];
            }
    }
    for (int set = 0; set < BENCH_NUM_SETS; set++)
        for (int k = 0; k < num_threads; k++) {
            BenchRow *set_rows[CST_BENCH_MAX_ACCELS];
            for (int i = 0; i < nb; i++) set_rows[i] = &rows[(i * BENCH_NUM_SETS + set) * num_threads + k];
            st = bench_set(built, nb, &rays, set, threads[k], ref ? NULL : basis, ref ? embree : NULL, &scene,
                           scratch, set_rows, err);
            if (st != CST_OK) goto done;
        }

    bench_check(rows, n, ref, gen_type == ACCEL_EMBREE);
    if (b->json) {
        if (!bench_print_json(o->out, rows, n, &scene)) {
            st = cst_fail(err, CST_ERR_OOM, "out of memory writing JSON");
            goto done;
        }
    } else {
        bench_print_table(o->out, rows, n);
    }
    result->checks = n;
    for (int i = 0; i < n; i++) result->mismatches += rows[i].checked && !rows[i].ok;
    st = CST_OK;

done:
    accel_free(&gen);
    for (int i = 0; i < num_built; i++) accel_free(&built[i]);
    for (int set = 0; set < BENCH_NUM_SETS; set++) free(basis[set]);
    free(scratch);
    free(embree_secondary);
    free(rows);
    free(occlusion);
    free(secondary);
    free(hits);
    free(primary);
    rayset_scene_free(&scene);
    return st;
}

