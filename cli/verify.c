/* caustic verify: renders a scene with several integrators and tests that the unbiased
 * ones agree (z-scores of the image and block means, Sidak-corrected) and that the
 * consistent ones converge to the first unbiased one (cst_compare_* in caustic.h). */
#include <inttypes.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <jansson.h>

#include "cli.h"

/* ------------------------------------------------------------ caustic verify */

/* How verify judges each integrator, by cst_integrator_name(); one line per integrator.
 * EXACT: unbiased, so any two must agree at any sample count (whitted too: it is biased by
 * design, and verify reports that it disagrees). CONVERGE_*: consistent but biased at every
 * finite sample count (density estimation), where a z-test would flag the bias, correctly
 * and uselessly; judged instead by the convergence check against the reference (the first
 * EXACT integrator listed), with the work that shrinks the bias growing by 4 per level:
 * iterations (--spp) or the photon count. A name not listed is judged EXACT. */
typedef enum VerifyJudge { VERIFY_EXACT, VERIFY_CONVERGE_SPP, VERIFY_CONVERGE_PHOTONS } VerifyJudge;

static const struct { const char *name; VerifyJudge judge; } CLI_VERIFY_JUDGES[] = {
    {"path", VERIFY_EXACT},
    {"path-nee", VERIFY_EXACT},
    {"path-bsdf", VERIFY_EXACT},
    {"light", VERIFY_EXACT},
    {"whitted", VERIFY_EXACT},
    {"photon", VERIFY_CONVERGE_PHOTONS},
    {"sppm", VERIFY_CONVERGE_SPP},
    {"bdpt", VERIFY_EXACT},
    {"vcm", VERIFY_CONVERGE_SPP}, /* --spp counts iterations; the merging radius shrinks over them */
    {"pssmlt", VERIFY_CONVERGE_SPP}, /* --spp counts mutations per pixel; start-up bias and b shrink with them */
    {"mmlt", VERIFY_CONVERGE_SPP},   /* as pssmlt */
};

static VerifyJudge cli_verify_judge(CstIntegrator id)
{
    const char *name = cst_integrator_name(id);
    for (size_t i = 0; i < sizeof CLI_VERIFY_JUDGES / sizeof CLI_VERIFY_JUDGES[0]; i++)
        if (strcmp(name, CLI_VERIFY_JUDGES[i].name) == 0) return CLI_VERIFY_JUDGES[i].judge;
    return VERIFY_EXACT;
}

/* Render k (0-based) of a verify run renders with output k+1 of SplitMix64 (Steele et al.
 * 2014) started at the base seed: independent streams for every render, so the images
 * compared are independent estimates, even of the same integrator. Integrator k of the
 * list is render k; render i of level l of the convergence check of integrator k is
 * render MAX_INTEGRATORS + 2 (k MAX_LEVELS + l) + i. */
/* SplitMix64's output function (Steele et al. 2014), the same finaliser core/rng.h's
 * mix64 is: verify's seeds must not change with the library's internals. */
static uint64_t cli_mix64(uint64_t x)
{
    x ^= x >> 30;
    x *= 0xbf58476d1ce4e5b9ULL;
    x ^= x >> 27;
    x *= 0x94d049bb133111ebULL;
    x ^= x >> 31;
    return x;
}

static uint64_t cli_verify_seed(uint64_t base, int k)
{
    return cli_mix64(base + (uint64_t)(k + 1) * 0x9e3779b97f4a7c15ULL);
}

static uint64_t cli_verify_level_seed(uint64_t base, int k, int level, int i)
{
    return cli_verify_seed(base, ARGS_VERIFY_MAX_INTEGRATORS + 2 * (k * ARGS_VERIFY_MAX_LEVELS + level) + i);
}

static const char CLI_CHANNELS[3] = {'r', 'g', 'b'};

/* Below this many samples per block and integrator the z of a heavy-tailed estimator is
 * itself skewed: a block that happened to miss the rare large samples has a low mean and
 * a low variance estimate at once. Measured on the Cornell box with path, path-nee and
 * path-bsdf at alpha 0.01 (runs with any false alarm; docs/cli.md): 64x64 in 16 blocks,
 * 4096 samples per block 22 of 100, 16384 2-3 of 100, 65536 0 of 100; 512x512, 16384
 * samples in each of 1024 blocks 4 of 4, 65536 in each of 256 blocks 0 of 6. */
#define CLI_VERIFY_MIN_BLOCK_SAMPLES 65536

/* jansson cannot represent infinities (zero-variance disagreements): null instead. */
static json_t *cli_json_real(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

typedef struct VerifyRender {
    CstIntegrator id;
    char label[40]; /* the integrator's name; "path#2" for its second occurrence */
    uint64_t seed;
    CstFilm *film;
    CstRenderStats stats;
} VerifyRender;

/* The convergence check of one consistent integrator (index k of --integrators). */
typedef struct VerifyConvergence {
    int k;
    VerifyJudge judge;
    char label[40];
    int work[ARGS_VERIFY_MAX_LEVELS];      /* iterations or photons */
    double radius[ARGS_VERIFY_MAX_LEVELS]; /* photon: the fixed radius, 0 = automatic */
    uint64_t seed[ARGS_VERIFY_MAX_LEVELS][2];
    double seconds[ARGS_VERIFY_MAX_LEVELS];  /* both renders */
    CstConvergenceLevel lv[ARGS_VERIFY_MAX_LEVELS];
    double step_diff[ARGS_VERIFY_MAX_LEVELS - 1], step_se[ARGS_VERIFY_MAX_LEVELS - 1];
    CstConvergenceVerdict verdict;
} VerifyConvergence;

typedef struct VerifyPlan {
    int width, height, block, nbx, nby, blocks;
    int pairs, checks, levels, reference; /* reference: index of the first EXACT integrator */
    int64_t tests; /* m: pairs x 3 channels x (1 + blocks) + checks x levels */
    double alpha, alpha_1, z_crit, z_conv; /* z_conv: one-sided, for the convergence tests */
} VerifyPlan;

static const char *cli_verify_verdict(CstConvergenceVerdict v)
{
    return v == CST_CONVERGENCE_WITHIN_NOISE ? "within-noise" : v == CST_CONVERGENCE_SHRINKS ? "shrinks" : "fails";
}

static void cli_verify_print_header(const CliArgs *a, const CstRenderSettings *rs,
                                    const VerifyPlan *p, const VerifyRender *r, int n)
{
    const char *scene = a->scene_path ? a->scene_path : "the built-in Cornell box";
    char work[96];
    if (rs->spp && rs->time_limit > 0.0)
        snprintf(work, sizeof work, "%d spp or %g s each, whichever first", rs->spp, rs->time_limit);
    else if (rs->time_limit > 0.0)
        snprintf(work, sizeof work, "%g s each (equal time)", rs->time_limit);
    else
        snprintf(work, sizeof work, "%d spp each", rs->spp);
    printf("scene:     %s, %dx%d, %s filter, %s\n", scene, p->width, p->height,
           cst_filter_name(rs->filter), work);
    printf("renders:   %-12s %-18s %6s %9s\n", "integrator", "seed", "spp", "seconds");
    for (int k = 0; k < n; k++)
        if (r[k].film)
            printf("           %-12s 0x%016" PRIx64 " %6d %9.2f\n", r[k].label, r[k].seed, r[k].stats.spp,
                   r[k].stats.seconds);
    bool partial = p->width % p->block || p->height % p->block;
    if (p->pairs > 0)
        printf("tests:     per pair and channel, z = (mean_a - mean_b) / sqrt(var_a + var_b) of the\n"
               "           image mean and of each of the %d blocks of %dx%d pixels (a %dx%d grid%s);\n"
               "           var of a mean = sum of its pixel-mean variances / n^2\n",
               p->blocks, p->block, p->block, p->nbx, p->nby, partial ? ", edge blocks partial" : "");
    if (p->checks > 0)
        printf("%s per consistent integrator X, %d levels of work (x1, x4, x16, ...), two renders\n"
               "           x1, x2 each, against the reference %s r: per block b, with block means,\n"
               "           t_b = sum over channels of ((x1+x2)/2 - r)^2 - (x1-x2)^2/4 - var(r);\n"
               "           D = mean of t_b over the %d blocks (the squared bias net of noise), se from\n"
               "           their spread; X converges if at the last level D <= z se and the image\n"
               "           mean's |z| <= z_crit per channel (within noise), or if D falls\n"
               "           significantly at every step (paired over blocks: dD > z se)\n",
               p->pairs > 0 ? "           and" : "tests:    ", p->levels, r[p->reference].label, p->blocks);
    char checks[64] = "";
    if (p->checks > 0)
        snprintf(checks, sizeof checks, " + %d check%s x (%d + 3)", p->checks, p->checks == 1 ? "" : "s",
                 p->levels);
    printf("threshold: m = %" PRId64 " tests (%d pair%s x 3 channels x (1 + %d)%s), family-wise alpha %g,\n"
           "           Sidak per-test alpha %.4g: a pair disagrees where |z| > z_crit = %.3f\n",
           p->tests, p->pairs, p->pairs == 1 ? "" : "s", p->blocks, checks, p->alpha, p->alpha_1, p->z_crit);
    if (p->checks > 0)
        printf("           (the image means of a convergence check too); D and its steps are\n"
               "           significant where z > %.3f (one-sided)\n", p->z_conv);
    printf("\n");
}

static void cli_verify_print_row(const VerifyRender *ra, const VerifyRender *rb, int width,
                                 const CstFilmComparison *c, const VerifyPlan *p)
{
    char pair[96], where[48], failing[48];
    snprintf(pair, sizeof pair, "%s vs %s", ra->label, rb->label);
    snprintf(where, sizeof where, "(%d, %d) %c", c->worst_bx * p->block, c->worst_by * p->block,
             CLI_CHANNELS[c->worst_channel]);
    snprintf(failing, sizeof failing, "%d of %d", c->blocks_failing, c->blocks);
    printf("%-*s  %+7.2f %+7.2f %+7.2f  %+13.2f  %-16s  %-14s  %s\n", width, pair, c->z_mean[0],
           c->z_mean[1], c->z_mean[2], c->worst_z, where, failing, c->pass ? "agree" : "DISAGREE");
    if (c->zero_variance_disagreements > 0)
        printf("%-*s  (%d test%s with zero variance in both images and different means)\n", width,
               "", c->zero_variance_disagreements, c->zero_variance_disagreements == 1 ? "" : "s");
}

static void cli_verify_print_convergence(const VerifyConvergence *cv, const VerifyRender *ref,
                                         const VerifyPlan *p)
{
    const bool photons = cv->judge == VERIFY_CONVERGE_PHOTONS;
    printf("convergence: %s against %s\n", cv->label, ref->label);
    printf("  %-5s %10s  %-37s %10s %9s %6s %8s  %s\n", "level", photons ? "photons" : "iterations",
           "seeds", "D", "se", "z(D)", "rms bias", "image-mean diff (z) r, g, b");
    for (int l = 0; l < p->levels; l++) {
        const CstConvergenceLevel *lv = &cv->lv[l];
        /* rms bias per channel of a block mean: sqrt(D / 3), 0 when noise exceeds it */
        printf("  %-5d %10d  0x%016" PRIx64 " 0x%016" PRIx64 " %+10.3e %9.2e %+6.2f %8.5f ", l, cv->work[l],
               cv->seed[l][0], cv->seed[l][1], lv->d2, lv->d2_se, lv->d2 / lv->d2_se,
               lv->d2 > 0.0 ? sqrt(lv->d2 / 3.0) : 0.0);
        for (int c = 0; c < 3; c++) printf(" %+.5f (%+.1f)", lv->mean_diff[c], lv->mean_z[c]);
        if (photons && cv->radius[l] > 0.0) printf("  (radius %g)", cv->radius[l]);
        printf("\n");
    }
    for (int l = 0; l + 1 < p->levels; l++)
        printf("  step %d->%d: D falls by %+.3e (se %.2e, z = %+.2f)\n", l, l + 1, cv->step_diff[l],
               cv->step_se[l], cv->step_diff[l] / cv->step_se[l]);
    if (cv->verdict == CST_CONVERGENCE_WITHIN_NOISE)
        printf("  result: converges (within noise at level %d: z(D) <= %.3f, |image-mean z| <= %.3f)\n",
               p->levels - 1, p->z_conv, p->z_crit);
    else if (cv->verdict == CST_CONVERGENCE_SHRINKS)
        printf("  result: converges (D falls significantly at every step: z > %.3f)\n", p->z_conv);
    else
        printf("  result: DISAGREE (a bias remains at level %d and D is not shown to fall at every step)\n",
               p->levels - 1);
}

/* One compact JSON line; false if jansson runs out of memory. */
static bool cli_print_json_line(json_t *o)
{
    char *line = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!line) return false;
    printf("%s\n", line);
    free(line);
    return true;
}

static bool cli_verify_print_json(const VerifyRender *ra, const VerifyRender *rb,
                                  const CstFilmComparison *c, const VerifyPlan *p)
{
    char seed_a[24], seed_b[24], ch[2] = {CLI_CHANNELS[c->worst_channel], '\0'};
    snprintf(seed_a, sizeof seed_a, "0x%016" PRIx64, ra->seed);
    snprintf(seed_b, sizeof seed_b, "0x%016" PRIx64, rb->seed);
    json_t *o = json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:[o,o,o], s:o, s:o, s:[i,i], s:s, s:i, s:i, "
                          "s:i, s:i, s:f, s:f, s:I, s:b, s:b}",
        "a", ra->label, "b", rb->label, "seed_a", seed_a, "seed_b", seed_b,
        "spp_a", ra->stats.spp, "spp_b", rb->stats.spp,
        "z_mean", cli_json_real(c->z_mean[0]), cli_json_real(c->z_mean[1]), cli_json_real(c->z_mean[2]),
        "max_abs_block_z", cli_json_real(c->max_abs_block_z), "worst_block_z", cli_json_real(c->worst_z),
        "worst_block", c->worst_bx * p->block, c->worst_by * p->block, "worst_channel", ch,
        "block", p->block, "blocks", c->blocks, "blocks_failing", c->blocks_failing,
        "zero_variance_disagreements", c->zero_variance_disagreements,
        "alpha", p->alpha, "z_crit", p->z_crit, "tests", (json_int_t)p->tests,
        "judged", 1, "pass", c->pass);
    return cli_print_json_line(o);
}

static bool cli_verify_print_json_convergence(const VerifyConvergence *cv, const VerifyRender *ref,
                                              const VerifyPlan *p)
{
    json_t *levels = json_array(), *steps = json_array();
    for (int l = 0; levels && l < p->levels; l++) {
        char s0[24], s1[24];
        snprintf(s0, sizeof s0, "0x%016" PRIx64, cv->seed[l][0]);
        snprintf(s1, sizeof s1, "0x%016" PRIx64, cv->seed[l][1]);
        const CstConvergenceLevel *lv = &cv->lv[l];
        json_array_append_new(levels, json_pack("{s:i, s:f, s:[s,s], s:o, s:o, s:[o,o,o], s:[o,o,o]}",
            "work", cv->work[l], "radius", cv->radius[l], "seeds", s0, s1,
            "d2", cli_json_real(lv->d2), "d2_se", cli_json_real(lv->d2_se),
            "mean_diff", cli_json_real(lv->mean_diff[0]), cli_json_real(lv->mean_diff[1]),
            cli_json_real(lv->mean_diff[2]),
            "mean_z", cli_json_real(lv->mean_z[0]), cli_json_real(lv->mean_z[1]), cli_json_real(lv->mean_z[2])));
    }
    for (int l = 0; steps && l + 1 < p->levels; l++)
        json_array_append_new(steps, json_pack("{s:o, s:o}", "diff", cli_json_real(cv->step_diff[l]),
                                               "se", cli_json_real(cv->step_se[l])));
    char seed_r[24];
    snprintf(seed_r, sizeof seed_r, "0x%016" PRIx64, ref->seed);
    /* "o" steals levels and steps, also when json_pack fails. */
    json_t *o = levels && steps
        ? json_pack("{s:s, s:s, s:s, s:s, s:i, s:i, s:o, s:o, s:f, s:f, s:f, s:I, s:s, s:b}",
            "convergence", cv->label, "reference", ref->label,
            "work", cv->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", "seed_reference", seed_r,
            "block", p->block, "blocks", p->blocks, "levels", levels, "steps", steps,
            "alpha", p->alpha, "z_conv", p->z_conv, "z_crit", p->z_crit, "tests", (json_int_t)p->tests,
            "verdict", cli_verify_verdict(cv->verdict), "pass", cv->verdict != CST_CONVERGENCE_FAILS)
        : NULL;
    if (!o && !(levels && steps)) {
        json_decref(levels);
        json_decref(steps);
    }
    return cli_print_json_line(o);
}

/* One render of verify, with a bar on a terminal (otherwise one line per render, not ten).
 * Returns an exit code; on success *film is the caller's. */
static int cli_verify_render(const CliArgs *a, CstScene *scene, CstRenderSettings settings, const char *what,
                             CstFilm **film, CstRenderStats *stats)
{
    CliProgress progress = {.tty = isatty(STDERR_FILENO) == 1};
    CstError err = {0};
    if (!a->quiet && progress.tty) {
        settings.progress = cli_progress_report;
        settings.progress_user = &progress;
        settings.progress_phase = cli_progress_phase;
    }
    CstStatus status = cst_render(scene, &settings, film, stats, &err);
    if (status != CST_OK) {
        if (settings.progress) cli_progress_abort(&progress);
        cli_print_error(&err, status);
        return cli_exit_code(status, CLI_STAGE_RENDER);
    }
    if (settings.progress) cli_progress_finish(&progress, stats->seconds);
    if (!a->quiet)
        fprintf(stderr, "caustic: verify: %s: %d spp in %.2f s\n", what, stats->spp, stats->seconds);
    if (stats->nonfinite > 0)
        fprintf(stderr, "caustic: warning: %s: %" PRIu64 " NaN/Inf samples discarded "
                "(counted as zero: the image is biased low there)\n", what, stats->nonfinite);
    return CLI_EXIT_OK;
}

/* The levels of one convergence check: render, compare with the reference, judge. terms
 * holds levels x blocks doubles. */
static int cli_verify_converge(const CliArgs *a, CstScene *scene, const CstRenderSettings *rs,
                               const VerifyPlan *p, const VerifyRender *ref, VerifyConvergence *cv,
                               double *terms)
{
    for (int l = 0; l < p->levels; l++) {
        CstFilm *x[2] = {NULL, NULL};
        for (int i = 0; i < 2; i++) {
            CstRenderSettings settings = a->settings;
            CstRenderStats stats;
            char what[96];
            settings.integrator = a->verify.integrators[cv->k];
            settings.seed = cv->seed[l][i];
            settings.seed_set = 1;
            if (cv->judge == VERIFY_CONVERGE_PHOTONS) {
                settings.photons = cv->work[l];
                settings.photon_radius = cv->radius[l];
                settings.spp = rs->spp;
            } else {
                settings.spp = cv->work[l];
            }
            snprintf(what, sizeof what, "%s level %d (%d %s) render %d", cv->label, l, cv->work[l],
                     cv->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", i + 1);
            int code = cli_verify_render(a, scene, settings, what, &x[i], &stats);
            if (code != CLI_EXIT_OK) {
                cst_film_destroy(x[0]);
                return code;
            }
            cv->seconds[l] += stats.seconds;
        }
        CstError err = {0};
        CstStatus status = cst_compare_convergence_level(ref->film, x[0], x[1], p->block,
                                                     &terms[(size_t)l * (size_t)p->blocks], &cv->lv[l], &err);
        cst_film_destroy(x[0]);
        cst_film_destroy(x[1]);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            return CLI_EXIT_USAGE; /* the only failures are the arguments' (block count) */
        }
    }
    for (int l = 0; l + 1 < p->levels; l++)
        cst_compare_convergence_step(&terms[(size_t)l * (size_t)p->blocks], &terms[(size_t)(l + 1) * (size_t)p->blocks],
                                 p->blocks, &cv->step_diff[l], &cv->step_se[l]);
    cv->verdict = cst_compare_convergence_judge(cv->lv, cv->step_diff, cv->step_se, p->levels, p->z_conv, p->z_crit);
    return CLI_EXIT_OK;
}

/* The plan's image-dependent part, once the settings are resolved: blocks, the number of
 * tests and the critical values, and each convergence check's levels (work, radius,
 * seeds). An exit code; usage errors are printed. */
static int cli_verify_plan(const VerifyArgs *v, const CstRenderSettings *rs, VerifyPlan *p, VerifyConvergence *cv)
{
    p->width = rs->width;
    p->height = rs->height;
    p->nbx = cst_compare_blocks_x(p->width, p->block);
    p->nby = cst_compare_blocks_y(p->height, p->block);
    p->blocks = p->nbx * p->nby;
    /* A check: D and the image mean per channel at the last level, and every step-> */
    p->tests = p->pairs * cst_compare_tests_per_pair(p->width, p->height, p->block) + (int64_t)p->checks * (p->levels + 3);
    p->alpha_1 = cst_compare_sidak_alpha(p->alpha, (double)p->tests);
    p->z_crit = cst_compare_z_critical(p->alpha, (double)p->tests);
    p->z_conv = -cst_compare_normal_quantile(p->alpha_1);
    if (p->checks > 0) {
        /* Levels are multiples of work; a time limit would make them depend on the machine. */
        if (rs->time_limit > 0.0) {
            fprintf(stderr, "caustic: error: verify: the convergence check of %s needs a sample count "
                    "(--spp), not a time limit: its levels are 1, 4, 16, ... times that work\n",
                    cst_integrator_name(v->integrators[cv[0].k]));
            return CLI_EXIT_USAGE;
        }
        if (p->blocks < 2) {
            fprintf(stderr, "caustic: error: verify: the convergence check needs at least 2 blocks "
                    "(%dx%d image, --block %d); its standard error comes from their spread\n",
                    p->width, p->height, p->block);
            return CLI_EXIT_USAGE;
        }
        const int64_t grow = (int64_t)1 << (2 * (p->levels - 1));
        for (int c = 0; c < p->checks; c++) {
            VerifyConvergence *x = &cv[c];
            int64_t base = x->judge == VERIFY_CONVERGE_PHOTONS
                               ? (rs->photons > 0 ? rs->photons : CST_DEFAULT_PHOTONS) : rs->spp;
            if (base * grow > INT32_MAX) {
                fprintf(stderr, "caustic: error: verify: %s: %" PRId64 " %s times 4^%d is too many "
                        "(at most %d); lower --spp or --convergence\n",
                        cst_integrator_name(v->integrators[x->k]), base,
                        x->judge == VERIFY_CONVERGE_PHOTONS ? "photons" : "iterations", p->levels - 1, INT32_MAX);
                return CLI_EXIT_USAGE;
            }
            for (int l = 0; l < p->levels; l++) {
                x->work[l] = (int)(base << (2 * l));
                /* A fixed radius would keep a fixed bias; halving it with 4x the photons
                 * keeps the photons per disc and halves the first-order bias. */
                x->radius[l] = x->judge == VERIFY_CONVERGE_PHOTONS ? rs->photon_radius / (double)(1 << l) : 0.0;
                for (int i = 0; i < 2; i++) x->seed[l][i] = cli_verify_level_seed(rs->seed, x->k, l, i);
            }
        }
    }
    return CLI_EXIT_OK;
}

/* The comparisons of the unbiased pairs, the tables or JSON lines on stdout, the z map
 * (--map) and the verdict: an exit code. */
static int cli_verify_report(const CliArgs *a, const CstRenderSettings *rs, const VerifyPlan *p, VerifyRender *r,
                             VerifyConvergence *cv, double *block_z, double *worst_z)
{
    const VerifyArgs *v = &a->verify;
    const int n = v->num_integrators;
    int code = CLI_EXIT_INTERNAL;
    CstError err = {0};
    CstStatus status;
    float *map = NULL;
    int width = 0;
    for (int k = 0; k < n; k++) {
        int len = (int)strlen(r[k].label);
        if (len > width) width = len;
    }
    width = 2 * width + 4;
    if (!v->json) {
        cli_verify_print_header(a, rs, p, r, n);
        if (p->pairs > 0)
            printf("%-*s  %-23s  %13s  %-16s  %-14s  %s\n", width, "pair", "image-mean z (r, g, b)",
                   "worst block z", "at (x, y) ch", "failing blocks", "result");
    }
    int disagree = 0, diverge = 0;
    for (int i = 0; i < n; i++)
        for (int j = i + 1; j < n; j++) {
            if (!r[i].film || !r[j].film) continue; /* a consistent integrator: its own check */
            CstFilmComparison c;
            status = cst_film_compare(r[i].film, r[j].film, p->block, p->z_crit, &c, block_z, &err);
            if (status != CST_OK) {
                cli_print_error(&err, status);
                goto done;
            }
            disagree += !c.pass;
            for (int b = 0; b < p->blocks; b++)
                if (block_z[b] > worst_z[b]) worst_z[b] = block_z[b];
            if (v->json) {
                if (!cli_verify_print_json(&r[i], &r[j], &c, p)) {
                    fprintf(stderr, "caustic: error: out of memory writing JSON\n");
                    goto done;
                }
            } else {
                cli_verify_print_row(&r[i], &r[j], width, &c, p);
            }
        }
    for (int c = 0; c < p->checks; c++) {
        diverge += cv[c].verdict == CST_CONVERGENCE_FAILS;
        if (v->json) {
            if (!cli_verify_print_json_convergence(&cv[c], &r[p->reference], p)) {
                fprintf(stderr, "caustic: error: out of memory writing JSON\n");
                goto done;
            }
        } else {
            if (c > 0 || p->pairs > 0) printf("\n");
            cli_verify_print_convergence(&cv[c], &r[p->reference], p);
        }
    }
    if (!v->json) {
        printf("\n");
        if (p->pairs > 0) {
            if (disagree)
                printf("result:    %d of %d pair%s DISAGREE\n", disagree, p->pairs, p->pairs == 1 ? "" : "s");
            else
                printf("result:    %s\n", p->pairs == 1 ? "the pair agrees" : "all pairs agree");
        }
        if (p->checks > 0) {
            if (diverge)
                printf("%s %d of %d consistent integrator%s not shown to converge (DISAGREE)\n",
                       p->pairs > 0 ? "          " : "result:   ", diverge, p->checks, p->checks == 1 ? "" : "s");
            else
                printf("%s %s\n", p->pairs > 0 ? "          " : "result:   ",
                       p->checks == 1 ? "the consistent integrator converges" : "every consistent integrator converges");
        }
    }

    if (v->map_path) {
        map = malloc((size_t)p->width * (size_t)p->height * 3u * sizeof *map);
        if (!map) {
            fprintf(stderr, "caustic: error: out of memory for the %dx%d map\n", p->width, p->height);
            goto done;
        }
        cst_compare_map_image(worst_z, p->width, p->height, p->block, p->z_crit, map);
        status = cst_image_write(v->map_path, map, p->width, p->height, &err);
        if (status != CST_OK) {
            cli_print_error(&err, status);
            code = cli_exit_code(status, CLI_STAGE_WRITE);
            goto done;
        }
        if (!a->quiet)
            fprintf(stderr, "caustic: verify: wrote the z map to %s\n", v->map_path);
    }
    if (disagree)
        fprintf(stderr, "caustic: verify: %d of %d pair%s disagree (|z| > %.3f)\n", disagree,
                p->pairs, p->pairs == 1 ? "" : "s", p->z_crit);
    if (diverge)
        fprintf(stderr, "caustic: verify: %d of %d consistent integrator%s not shown to converge\n", diverge,
                p->checks, p->checks == 1 ? "" : "s");
    code = disagree || diverge ? CLI_EXIT_DISAGREE : CLI_EXIT_OK;
done:
    free(map);
    return code;
}

int cli_verify(const CliArgs *a)
{
    const VerifyArgs *v = &a->verify;
    const int n = v->num_integrators;
    int code = CLI_EXIT_INTERNAL;
    CstScene *scene = NULL;
    VerifyRender r[ARGS_VERIFY_MAX_INTEGRATORS];
    VerifyConvergence cv[ARGS_VERIFY_MAX_INTEGRATORS];
    double *block_z = NULL, *worst_z = NULL, *terms = NULL;
    memset(r, 0, sizeof r);
    memset(cv, 0, sizeof cv);

    if (!cli_check_scene_path(a))
        return CLI_EXIT_USAGE;
    if (v->map_path && !cli_check_output(v->map_path, "--map"))
        return CLI_EXIT_USAGE;

    /* The plan, before rendering: pairs of EXACT integrators, convergence checks of the
     * others against the first EXACT one, how many tests, the critical values. */
    VerifyPlan p = {.block = v->block, .alpha = v->alpha, .levels = v->levels, .reference = -1};
    int exact = 0;
    for (int i = 0; i < n; i++) {
        if (cli_verify_judge(v->integrators[i]) == VERIFY_EXACT) {
            if (p.reference < 0) p.reference = i;
            exact++;
        } else {
            cv[p.checks].k = i;
            cv[p.checks].judge = cli_verify_judge(v->integrators[i]);
            p.checks++;
        }
    }
    p.pairs = exact * (exact - 1) / 2;
    if (p.checks > 0 && p.reference < 0) {
        fprintf(stderr, "caustic: error: verify: %s is judged by convergence against an unbiased "
                "reference; add one to --integrators (e.g. path,%s)\n",
                cst_integrator_name(v->integrators[cv[0].k]), cst_integrator_name(v->integrators[cv[0].k]));
        return CLI_EXIT_USAGE;
    }

    code = cli_load_scene(a, &scene, NULL);
    if (code != CLI_EXIT_OK)
        return code;
    code = CLI_EXIT_INTERNAL;

    CstRenderSettings rs;
    cst_render_settings_resolve(scene, &a->settings, &rs);
    code = cli_verify_plan(v, &rs, &p, cv);
    if (code != CLI_EXIT_OK) goto done;
    code = CLI_EXIT_INTERNAL;

    for (int k = 0; k < n; k++) {
        r[k].id = v->integrators[k];
        r[k].seed = cli_verify_seed(rs.seed, k);
        int seen = 1;
        for (int i = 0; i < k; i++) seen += r[i].id == r[k].id;
        if (seen > 1)
            snprintf(r[k].label, sizeof r[k].label, "%s#%d", cst_integrator_name(r[k].id), seen);
        else
            snprintf(r[k].label, sizeof r[k].label, "%s", cst_integrator_name(r[k].id));
    }
    for (int c = 0; c < p.checks; c++) memcpy(cv[c].label, r[cv[c].k].label, sizeof cv[c].label);

    if (!a->quiet) {
        char work[96];
        if (rs.spp && rs.time_limit > 0.0)
            snprintf(work, sizeof work, "%d spp or %g s each", rs.spp, rs.time_limit);
        else if (rs.time_limit > 0.0)
            snprintf(work, sizeof work, "%g s each", rs.time_limit);
        else
            snprintf(work, sizeof work, "%d spp each", rs.spp);
        fprintf(stderr, "caustic: verify: rendering %s (%dx%d, %s, %d thread%s) with",
                a->scene_path ? a->scene_path : "the built-in Cornell box", rs.width, rs.height,
                work, rs.threads, rs.threads == 1 ? "" : "s");
        for (int k = 0; k < n; k++) fprintf(stderr, "%s %s", k ? "," : "", r[k].label);
        if (p.checks > 0)
            fprintf(stderr, " (consistent ones: %d levels x 2 renders)", p.levels);
        fprintf(stderr, "\n");
    }
    int min_spp = INT32_MAX;
    for (int k = 0; k < n; k++) {
        if (cli_verify_judge(r[k].id) != VERIFY_EXACT) continue;
        CstRenderSettings settings = a->settings;
        settings.integrator = r[k].id;
        settings.seed = r[k].seed;
        settings.seed_set = 1;
        code = cli_verify_render(a, scene, settings, r[k].label, &r[k].film, &r[k].stats);
        if (code != CLI_EXIT_OK) goto done;
        code = CLI_EXIT_INTERNAL;
        if (r[k].stats.spp < 2) {
            fprintf(stderr, "caustic: error: verify: %s rendered %d sample per pixel; the "
                    "variance estimate needs at least 2 (use --spp 2 or more, or a longer --time)\n",
                    r[k].label, r[k].stats.spp);
            code = CLI_EXIT_USAGE;
            goto done;
        }
        if (r[k].stats.spp < min_spp) min_spp = r[k].stats.spp;
    }
    double block_samples = (double)(p.block < p.width ? p.block : p.width) *
                           (double)(p.block < p.height ? p.block : p.height) * min_spp;
    if (p.pairs > 0 && block_samples < CLI_VERIFY_MIN_BLOCK_SAMPLES)
        fprintf(stderr, "caustic: warning: verify: %.0f samples per block (%dx%d pixels x %d spp); "
                "with fewer than %d, heavy-tailed estimators (e.g. path-bsdf) give false alarms "
                "far above alpha: raise --spp or --block (see docs/cli.md)\n", block_samples,
                p.block, p.block, min_spp, CLI_VERIFY_MIN_BLOCK_SAMPLES);

    block_z = malloc((size_t)p.blocks * sizeof *block_z);
    worst_z = calloc((size_t)p.blocks, sizeof *worst_z);
    terms = malloc((size_t)p.levels * (size_t)p.blocks * sizeof *terms);
    if (!block_z || !worst_z || !terms) {
        fprintf(stderr, "caustic: error: out of memory for %d blocks\n", p.blocks);
        goto done;
    }
    for (int c = 0; c < p.checks; c++) {
        code = cli_verify_converge(a, scene, &rs, &p, &r[p.reference], &cv[c], terms);
        if (code != CLI_EXIT_OK) goto done;
        code = CLI_EXIT_INTERNAL;
    }

    code = cli_verify_report(a, &rs, &p, r, cv, block_z, worst_z);


done:
    free(terms);
    free(worst_z);
    free(block_z);
    for (int k = 0; k < n; k++) cst_film_destroy(r[k].film);
    cst_scene_destroy(scene);
    return code;
}

/* Help and version go to stdout; a failed write there (a closed pipe, a full disk) is an
 * error like any other. */
