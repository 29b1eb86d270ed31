/* The second half of caustic's public API, included by caustic/caustic.h (include that, not
 * this): comparing renders and images (`caustic verify`, `caustic compare`), the ray
 * benchmark (`caustic bench rays`) and explaining a pixel (`caustic explain`). Kept apart
 * only to keep each header readable. */
#ifndef CAUSTIC_CAUSTIC_COMPARE_H
#define CAUSTIC_CAUSTIC_COMPARE_H

#ifndef CAUSTIC_CAUSTIC_H
#error "include caustic/caustic.h, which includes this header"
#endif

/* ---------------------------------------------------------------- comparing renders
 * The statistics of `caustic verify` (docs/cli.md): two independent films of the same
 * scene agree when every z-score of their difference, of the image mean and of every
 * block of block x block pixels, per channel, is within a Sidak-corrected critical
 * value; consistent (biased) estimators are judged by whether their mean squared block
 * bias against an unbiased reference shrinks as their work grows 4x per level. */

/* The standard normal quantile Phi^-1(p), p in (0, 1). */
CST_API double cst_compare_normal_quantile(double p);
/* The per-test level 1 - (1 - alpha)^(1/m) of m tests at family-wise level alpha. */
CST_API double cst_compare_sidak_alpha(double alpha, double m);
/* The two-sided critical |z| of m tests at family-wise level alpha. */
CST_API double cst_compare_z_critical(double alpha, double m);
/* Blocks across and down a width x height image (the last ones may be partial). */
CST_API int cst_compare_blocks_x(int width, int block);
CST_API int cst_compare_blocks_y(int height, int block);
/* The tests cst_film_compare makes: 3 channels x (1 image mean + the blocks). */
CST_API int64_t cst_compare_tests_per_pair(int width, int height, int block);

typedef struct CstFilmComparison {
    /* z = (mean_a - mean_b) / sqrt(var_a + var_b) of the image mean, per channel; +-INFINITY
     * when both variances are zero and the means differ (an outright disagreement). */
    double z_mean[3];
    double max_abs_block_z;  /* largest |z| over blocks and channels (INFINITY as above) */
    double worst_z;          /* that z with its sign: > 0 where a is brighter */
    int worst_bx, worst_by;  /* the block where it was found (block column, row) */
    int worst_channel;       /* 0 r, 1 g, 2 b */
    int blocks;              /* blocks tested */
    int blocks_failing;      /* blocks with |z| > z_crit (or NaN) in any channel */
    int zero_variance_disagreements; /* tests (image or block, per channel) with zero variance
                                      * in both films and different means */
    int pass;                /* every image-mean and block |z| <= z_crit */
} CstFilmComparison;

/* Compares two films of the same size; block_abs_z (NULL, or one per block, row-major)
 * receives each block's largest |z| over the channels. */
CST_API CstStatus cst_film_compare(const CstFilm *a, const CstFilm *b, int block, double z_crit,
                           CstFilmComparison *out, double *block_abs_z, CstError *err);

typedef struct CstConvergenceLevel {
    double d2;           /* D = mean of t_b over blocks: the mean squared block bias (radiance^2) */
    double d2_se;        /* its standard error */
    double mean_diff[3]; /* image mean of (x1 + x2) / 2 minus the reference's */
    double mean_z[3];    /* mean_diff over its standard error */
    int blocks;
} CstConvergenceLevel;

/* One level of the convergence check: two independent films x1, x2 of the estimator at
 * that level against the reference; terms (one per block) keeps each block's t_b for
 * cst_compare_convergence_step. */
CST_API CstStatus cst_compare_convergence_level(const CstFilm *ref, const CstFilm *x1, const CstFilm *x2,
                                        int block, double *terms, CstConvergenceLevel *out,
                                        CstError *err);
/* The change of D between two levels' terms, and its standard error (paired by block). */
CST_API void cst_compare_convergence_step(const double *terms_a, const double *terms_b, int blocks,
                                  double *diff, double *se);

typedef enum CstConvergenceVerdict {
    CST_CONVERGENCE_WITHIN_NOISE, /* D at the last level is not significantly above 0 */
    CST_CONVERGENCE_SHRINKS,      /* D falls significantly at every step */
    CST_CONVERGENCE_FAILS         /* neither: a bias remains and it is not shown to shrink */
} CstConvergenceVerdict;

/* The verdict from `levels` levels and their levels - 1 steps; z: the one-sided critical
 * value of the steps and of D, z_mean: the two-sided one of the image means. */
CST_API CstConvergenceVerdict cst_compare_convergence_judge(const CstConvergenceLevel *lv,
                                                    const double *step_diff,
                                                    const double *step_se, int levels,
                                                    double z, double z_mean);
/* A map of block_abs_z (one per block) as width x height x 3 linear floats, one flat cell
 * per block: black at 0 ramping to blue at z_crit/2, to yellow at z_crit, red above. */
CST_API void cst_compare_map_image(const double *block_abs_z, int width, int height, int block,
                           double z_crit, float *rgb);

/* ---------------------------------------------------------------- comparing images
 * The numbers of `caustic compare A B` (docs/cli.md): B is the reference. Means, their
 * difference, RMSE and relMSE per channel; with per-pixel variances of A and/or B (the
 * variance AOV, cst_image_read_layer(..., "variance", ...)), z-scores of the block means;
 * and FLIP (cst_image_flip). */

/* relMSE = mean over pixels of (a - b)^2 / (b^2 + CST_RELMSE_EPS), the relative MSE of
 * Rousselle, Knaus and Zwicker 2011; the epsilon (our choice of value) keeps black
 * reference pixels from dominating. */
#define CST_RELMSE_EPS 0.01
/* A block "stands out" when |z| exceeds this (frac_above in CstImageComparison). */
#define CST_COMPARE_Z_OUTLIER 4.0

typedef struct CstImageComparison {
    double mean_a[3], mean_b[3]; /* per channel, over the pixels where both are finite */
    double diff[3];              /* mean_a - mean_b */
    double rel_diff[3];          /* diff / |mean_b|; NaN where mean_b is 0 */
    double rmse[3], rmse_all;    /* root mean square of a - b; _all over the 3 channels */
    double relmse[3], relmse_all;
    int64_t nonfinite;           /* values (pixel x channel) NaN or infinite in a or b: left out */
    /* With variances (var_a and/or var_b given; a missing one counts as exact): */
    int has_z;
    double z_mean[3];            /* the image mean's z per channel */
    int blocks;                  /* blocks tested (each in 3 channels) */
    double max_abs_z;            /* largest block |z| over blocks and channels */
    double worst_z;              /* that z with its sign: > 0 where a is brighter */
    int worst_bx, worst_by, worst_channel;
    int above;                   /* block tests (block x channel) with |z| > CST_COMPARE_Z_OUTLIER */
    double frac_above;           /* above / (3 blocks) */
} CstImageComparison;

/* Compares a with the reference b (width x height x 3 linear floats each, row 0 = top);
 * var_a, var_b: the variances of the pixel values (same layout) or NULL; block: the z
 * blocks' side in pixels (>= 1); block_abs_z (NULL, or one per block, row-major) receives
 * each block's largest |z| over the channels when variances are given. */
CST_API CstStatus cst_image_compare(const float *a, const float *b, int width, int height, const float *var_a,
                                    const float *var_b, int block, CstImageComparison *out,
                                    double *block_abs_z, CstError *err);

typedef enum CstFlipKind {
    CST_FLIP_LDR = 1, /* LDR-FLIP (HPG 2020) of the images clamped to [0, 1] */
    CST_FLIP_HDR = 2  /* HDR-FLIP (EG 2021): the maximum of LDR-FLIP over tone-mapped exposures */
} CstFlipKind;

/* Zero-initialised: HDR-FLIP at the papers' 67.02 pixels per degree, exposures automatic. */
typedef struct CstFlipOptions {
    CstFlipKind kind;           /* 0: HDR */
    double pixels_per_degree;   /* 0: the papers' default (0.7 m wide 4K monitor at 0.7 m) */
    int exposures;              /* HDR: 0 = the paper's automatic range; else start..stop */
    double start_exposure, stop_exposure;
} CstFlipOptions;

typedef struct CstFlipResult {
    CstFlipKind kind;
    double pixels_per_degree;
    double mean, max;           /* of the per-pixel FLIP error, in [0, 1] */
    double start_exposure, stop_exposure; /* HDR: the bracket used (stops) */
    int exposures;              /* HDR: how many; LDR: 0 */
} CstFlipResult;

/* FLIP of `test` against `reference` (width x height x 3 linear floats each); map (NULL,
 * or width x height floats) receives the per-pixel error. HDR-FLIP's automatic exposures
 * come from the reference. CST_ERR_OOM, CST_ERR_INVALID_ARG. */
CST_API CstStatus cst_image_flip(const float *test, const float *reference, int width, int height,
                                 const CstFlipOptions *options, float *map, CstFlipResult *out, CstError *err);

/* Reads the EXR channels "<layer>.R", "<layer>.G", "<layer>.B" (e.g. layer "variance":
 * the variance AOV of caustic render --aov variance) as an RGB image like cst_image_read.
 * CST_ERR_UNSUPPORTED when the file is not an EXR or has no such channels. */
CST_API CstStatus cst_image_read_layer(const char *path, const char *layer, float **rgb, int *width,
                                       int *height, CstError *err);

/* ---------------------------------------------------------------- ray benchmark */
#define CST_BENCH_MAX_ACCELS 7

/* `caustic bench rays` (docs/cli.md): zero-initialise, then set. */
typedef struct CstBenchRaysOptions {
    const char *mesh_path; /* a mesh file, or NULL: the built-in Cornell box (with stadium
                            * alone: the built-in dense ball) */
    int cornell;           /* the Cornell box even with stadium */
    int stadium;           /* the scene inside a huge sparse box */
    int json;              /* one JSON object per row instead of the table */
    int threads;           /* the second thread count; 0 = one per core */
    const char *accels[CST_BENCH_MAX_ACCELS]; /* back-end names ("bvh", ..., "embree",
                                               * "embree-robust") in order; none = all */
    int num_accels;
    FILE *out;             /* the table or the JSON lines */
    FILE *log;             /* notes (back ends skipped, built, tracing), or NULL */
    int verbose;           /* with log: also the build and tracing notes */
} CstBenchRaysOptions;

typedef struct CstBenchRaysResult {
    int checks;      /* rows checked */
    int mismatches;  /* rows whose hits or sum of t do not match */
    int input_error; /* on failure: 1 when the options or the mesh file were at fault */
} CstBenchRaysResult;

/* Runs the benchmark, writing to options->out. CST_OK also with mismatches (counted in
 * result); a failure leaves err's message and says in result->input_error whose it was. */
CST_API CstStatus cst_bench_rays(const CstBenchRaysOptions *options, CstBenchRaysResult *result,
                         CstError *err);

/* ---------------------------------------------------------------- explain (issue 30) */
/* One sample of one pixel replayed with the render's random numbers, and what its path
 * did: every vertex, every sampling decision, every strategy's contribution with its MIS
 * weight (docs/cli.md, "caustic explain"). Supported: path, path-nee, path-bsdf (media
 * and subsurface materials too), whitted, light (the splats that reached the pixel), bdpt and
 * vcm (RGB mode), sppm (an iteration: its camera chain, photons and progressive update),
 * pssmlt and mmlt (the Metropolis steps whose splats reached the pixel in one iteration);
 * CST_ERR_UNSUPPORTED for the rest. */
typedef enum CstExplainKind {
    CST_EXPLAIN_VERTEX = 1, /* a surface hit of the camera path: p, n, ng, material; or a
                             * subsurface exit (material_type "subsurface exit": pdf_a, pmf
                             * 1 / the probe's hits, beta Sp / pdf_a); depth -b: the hit after
                             * b bounces of a light subpath (bdpt, vcm: the pixel's; mmlt's
                             * replays), not summed, as that subpath's SCATTER (pdf_other_w its
                             * reverse pdf_w) and ROULETTE events of the same depth */
    CST_EXPLAIN_ESCAPE,     /* the camera path left the scene (environment, if any, in value) */
    CST_EXPLAIN_EMISSION,   /* an emitter reached by the camera path (bdpt: s = 0) */
    CST_EXPLAIN_NEE,        /* a light sampled from a vertex (bdpt: s = 1) */
    CST_EXPLAIN_CONNECT,    /* bdpt: camera vertex t joined to light vertex s - 1 (s >= 2) */
    CST_EXPLAIN_SPLAT,      /* bdpt, light: a light path's t = 1 connection landing near the pixel */
    CST_EXPLAIN_SCATTER,    /* the BSDF sample that continues the path */
    CST_EXPLAIN_ROULETTE,   /* Russian roulette: q the survival probability */
    CST_EXPLAIN_MERGE,      /* vcm: a light vertex merged at camera vertex t (value before the
                             * 1 / (pi r^2 N) normalisation, which pmf holds) */
    CST_EXPLAIN_DISTANCE,   /* path in media: free-flight distance sampled in a medium (distance,
                             * transmittance; flag SCATTERED when a medium vertex follows) */
    CST_EXPLAIN_PHOTON,     /* photon: a photon within the gather radius of the vertex (p its
                             * position, wi its incoming direction, value its power, beta the
                             * BSDF f without the cosine; contribution f * power); sppm: also
                             * path the photon path (of the iteration), s its hit's bounces
                             * from the light (2 = the first SPPM gathers), distance its
                             * distance from the visible point, pmf the box kernel
                             * 1 / (N_emitted pi r^2), share its part of the pixel's value */
    CST_EXPLAIN_ESTIMATE,   /* photon: the density estimate over the photons listed before it
                             * (flag CAUSTIC: the caustic map at the first diffuse vertex; flag
                             * VOLUME: the volume map at a medium vertex; else the global map
                             * at the final gather's vertex): distance the
                             * radius, pmf the box kernel 1 / (pi r^2), path the photons
                             * counted, value the estimate, beta the gather's throughput */
    CST_EXPLAIN_MUTATION    /* pssmlt, mmlt: a splat of a Metropolis step that reached the pixel
                             * (chain, step, path_length, accept, importance, weight below;
                             * flags PROPOSAL, LARGE_STEP, ACCEPTED): value the sample's radiance
                             * L, beta the weight, contribution weight * L, wi[0..1] its film
                             * position, share what it added to the pixel (the render's scale
                             * b / (W H) and the filter included) */
} CstExplainKind;

enum {
    CST_EXPLAIN_DELTA = 1,    /* a delta lobe or delta light (pmf, not pdf_w) */
    CST_EXPLAIN_OCCLUDED = 2, /* the connection's shadow ray was blocked (value 0); path in
                               * media: NEE's transmittance (in transmittance) was 0 */
    CST_EXPLAIN_SURVIVED = 4, /* roulette: the path went on */
    CST_EXPLAIN_ADDED = 8,    /* the event added contribution to the sample (value summed) */
    CST_EXPLAIN_SCATTERED = 16, /* DISTANCE: the sampled distance fell inside the segment */
    /* spectral bdpt/vcm: the camera subpath had refracted through a dispersive dielectric,
     * so the strategy's value counts at the hero wavelength alone (subpath_trace_camera's H) */
    CST_EXPLAIN_HERO = 32,
    /* spectral bdpt/vcm: a connection's or merge's light vertex lies on a dispersed light
     * subpath (hero wavelength alone too) */
    CST_EXPLAIN_LIGHT_DISPERSED = 64,
    CST_EXPLAIN_CAUSTIC = 128, /* ESTIMATE: over the caustic photon map */
    CST_EXPLAIN_PROPOSAL = 256,   /* MUTATION: the proposal's splat (weight a / I), else the
                                   * current state's (weight (1 - a) / I) */
    CST_EXPLAIN_LARGE_STEP = 512, /* MUTATION: the step was a large step (fresh uniforms) */
    CST_EXPLAIN_ACCEPTED = 1024,  /* MUTATION: the chain moved to the proposal */
    /* ESTIMATE (photon in media): the volume map's at a medium vertex: pmf the kernel
     * 1 / ((4/3) pi r^3) (0: the map is empty), transmittance holds sigma_s there (the
     * estimate divides by it), value the in-scattered radiance, contribution beta value */
    CST_EXPLAIN_VOLUME = 2048,
    /* MUTATION (pssmlt, mmlt): the splatted sample was evaluated again from its primary
     * sample vector with the recorder on (the first CST_EXPLAIN_MLT_PATHS splats that
     * reached the pixel); its path's events follow it (path_events of them, each flagged
     * IN_SPLAT), and replay_value holds the radiance the evaluation gave */
    CST_EXPLAIN_REPLAYED = 4096,
    /* MUTATION: ... and that radiance is the splatted L, bit for bit (every lane) */
    CST_EXPLAIN_REPLAY_EXACT = 8192,
    /* An event of the path of the splatted sample of the MUTATION event before it (pssmlt:
     * the path tracer's events; mmlt: the strategy's camera subpath, the light subpath's
     * hits as VERTEX events of depth -bounces, and the one (s, t) connection with its MIS
     * weight); not part of the pixel's sum (the MUTATION's share is) */
    CST_EXPLAIN_IN_SPLAT = 16384
};

/* pssmlt, mmlt: the splats (in the film's order) whose sample's path explain prints. */
enum { CST_EXPLAIN_MLT_PATHS = 16 };

typedef struct CstExplainEvent {
    CstExplainKind kind;
    int flags;        /* CST_EXPLAIN_* bits */
    int depth;        /* the camera vertex the event belongs to: 1 = the first hit */
    int s, t;         /* bdpt: the strategy (light and camera vertices); path: -1 */
    int light;        /* the emitter or light chosen (emitter index), -1 none */
    int material;     /* VERTEX: material index (scene order), -1 none */
    const char *material_type; /* VERTEX: "diffuse", "glass", ... (a static string) */
    /* VERTEX at a mix material: the material the mix chose at this hit (pbrt-v4's
     * MixMaterial, a hash of the hit: the one whose BSDF the path used there) and its type;
     * -1 and NULL at other vertices */
    int mix_material;
    const char *mix_material_type;
    /* SCATTER: the lobe that drew wi (a static string, never NULL on a SCATTER event):
     * "diffuse reflection", "glossy reflection", "specular reflection", the same three with
     * "transmission", "coat specular reflection", "coat glossy reflection", "base diffuse
     * reflection", "base glossy reflection", "base specular reflection" (plastic and the
     * coated materials: off the interface, or through it to the base and out), "hair R",
     * "hair TT", "hair TRT", "hair residual", "subsurface exit" (the cosine-weighted
     * direction leaving a subsurface exit point), "phase function" (a medium vertex),
     * "delta split" (the choice between a BSDF's delta and non-delta parts, whose own
     * SCATTER follows); NULL on other events */
    const char *lobe;
    float p[3], n[3], ng[3]; /* VERTEX: position, shading and geometric normal; SPLAT,
                              * CONNECT: the light vertex's position in p */
    float wi[3];      /* SCATTER, NEE: the sampled direction (unit, world) */
    float pdf_w;      /* the technique's density per unit solid angle (SCATTER: the BSDF's;
                       * NEE: the light sample's; EMISSION: the BSDF's that reached it) */
    float pdf_a;      /* the same per unit area at the reached vertex, where meaningful */
    float pdf_other_w; /* path MIS: the competing technique's pdf_w (NEE: the BSDF's,
                        * EMISSION: NEE's); bdpt: w_light, the ratios' sum light-ward */
    float pdf_other2;  /* bdpt: w_camera, the ratios' sum camera-ward; path: unused (0) */
    float pmf;        /* light selection (NEE) or delta lobe probability (SCATTER) */
    float mis_weight; /* the strategy's MIS weight; 1 when it has no partner; -1 n/a */
    float q;          /* ROULETTE: survival probability */
    float beta[3];    /* the path throughput the value is multiplied by */
    float value[3];   /* the weighted estimate before beta (what the integrator adds
                       * beta times); SCATTER: the BSDF weight f cos / pdf */
    float contribution[3]; /* beta * value: this event's share of the sample (RGB, or the
                            * first three wavelength lanes in spectral mode) */
    /* bdpt, vcm (EMISSION, NEE, CONNECT, MERGE, SPLAT at area lights): the strategy's MIS
     * weight computed explicitly from the densities of every strategy of the same whole
     * path (vcm: merges included), and those strategies' weights summed; -1 when not
     * computed (mis_strategies 0). */
    float mis_explicit, mis_sum;
    int mis_strategies;
    int path;         /* light, bdpt, vcm: the light path (of the iteration) whose splat this is; -1 */
    int medium;       /* VERTEX in a medium ("medium" material_type), DISTANCE: its index; -1 */
    float distance;   /* DISTANCE: the sampled distance, or the segment's length if it passed */
    float transmittance[3]; /* DISTANCE, homogeneous media: exp(-sigma_t distance) (RGB lanes);
                             * NEE of path in media: the shadow ray's (0: OCCLUDED) */
    /* bdpt, vcm through media: the distance-sampling densities of the segment (DISTANCE: the
     * flight that made the next vertex; NEE, CONNECT, SPLAT: the connection's): chain_fwd
     * the density with which a walk from the camera side's end (DISTANCE: the previous
     * vertex; SPLAT: the light vertex) makes the other end, chain_rev the reverse walk's;
     * per unit length at a medium vertex (majorant-based in grids), a pass probability at a
     * surface; 1 in vacuum. 0 when not applicable. */
    float chain_fwd, chain_rev;
    double share[3];  /* light, bdpt, vcm, MUTATION: what the splat added to the pixel (filter
                       * weight included) */
    /* MUTATION (pssmlt, mmlt): the chain, the step's index among the chain's mutations of the
     * iteration, the chain's path length (mmlt: bounces; pssmlt: -1), the acceptance
     * probability a = min(1, I(proposal) / I(current)), the splatted sample's scalar
     * contribution I (luminance of |L|) and the splat's weight (a / I or (1 - a) / I);
     * mmlt: s and t the sampled BDPT strategy of that length (s + t = path_length + 2). */
    int chain, step, path_length;
    float accept, importance, weight;
    /* MUTATION with CST_EXPLAIN_REPLAYED: the events of its sample's path that follow it,
     * and the radiance its evaluation again gave (first three lanes). */
    int path_events;
    float replay_value[3];
    /* ESTIMATE (photon with moving instances, Cammarano & Jensen 2002): the time window
     * [time_window[0], time_window[1]] of the photons counted (within the shutter) and the
     * factor shutter / window the estimate took, which pmf (the kernel) includes; 0, 0 and
     * 1 when nothing moves. */
    float time_window[2], time_scale;
} CstExplainEvent;

typedef struct CstExplain {
    int x, y, sample;
    CstIntegrator integrator;  /* resolved */
    int spectral;               /* 1: spectral mode */
    int num_events;
    int truncated;             /* more events than were kept (very long paths) */
    CstExplainEvent *events;
    float sum[3];              /* the ADDED events' values summed in the integrator's order
                                * (spectral: converted with the path's wavelengths), times
                                * the pixel filter weight: the camera sample's film value */
    float filter_weight;
    double camera_value[3];    /* what the render's camera step produced for this sample */
    double splat_value[3];     /* bdpt: what light paths' t = 1 splats added to the pixel */
    double film_value[3];      /* what the film accumulated: camera_value + splat_value */
    int exact;                 /* sum == camera_value, bit for bit */
    /* bdpt, vcm: strategies whose weight was also computed explicitly (mis_explicit), the
     * largest relative difference |mis_weight - mis_explicit| / mis_explicit among them and
     * the largest |mis_sum - 1|. */
    int mis_checked;
    double mis_max_error, mis_max_sum_error;
    /* bdpt, vcm: camera_value plus the iteration's splats on the pixel, re-added one by one
     * in the film's order (their shares in the SPLAT events' share), equals film_value bit
     * for bit. */
    int splats_exact;
    /* sppm: `sample` is the iteration; the pixel's progressive update in it (Hachisuka &
     * Jensen 2009 eqs. 6-7) and its value after it (film_value: a render of sample + 1
     * iterations holds it). */
    struct CstExplainSppm {
        int visible;              /* the camera chain reached a non-delta point */
        int volume;               /* ... in a participating medium: its ball (radius r, volume
                                   * 4/3 pi r^3) and statistic, the disc's untouched */
        int media;                /* the scene has media: the value adds the balls' estimate */
        long long photons;        /* photon paths per iteration */
        double emitted;           /* N_emitted: photons * (sample + 1) */
        float beta[3];            /* the visible point's throughput (filter weight included) */
        float direct[3];          /* this iteration's emission + NEE, added to ld (RGB) */
        double ld_before[3], ld_after[3]; /* sums of `direct` over the iterations */
        long long m;              /* M: photons gathered */
        double phi[3];            /* their sum of f Phi (RGB; spectral: converted) */
        double n_before, n_after; /* N -> N + alpha M */
        float r_before, r_after;  /* r -> r sqrt((N + alpha M) / (N + M)) (a ball: cbrt) */
        double tau_before[3], tau_after[3]; /* (tau + beta phi) r'^2 / r^2 (a ball: r'^3 / r^3) */
        double tau_other[3];      /* media: the other statistic's tau and radius (the ball's */
        float r_other;            /* for a surface point, the disc's for a point in a medium) */
        double value[3];          /* ld' / (sample + 1) + tau' / (N_emitted pi r'^2) (media: +
                                   * tau_vol / (N_emitted 4/3 pi r_vol^3)), recomputed */
        int state_exact;          /* the recomputed N', r', tau', ld' are the render's, bit for bit */
    } sppm;
    /* pssmlt, mmlt (`sample` is the iteration: W x H mutations over all chains): b, the
     * bootstrap's normalisation (mean I times the chains' film domain), and the factor from
     * a splat's weight * L to its share (b / (W H) before the filter); camera_value is then
     * the film's sum over iterations 0 .. sample - 1, splat_value the iteration's splats on
     * the pixel re-added in the film's order, film_value the film's sum after the
     * iteration; splats_exact (= exact): the re-added splats equal the value the render
     * merged for the iteration and camera_value + it = film_value, bit for bit. */
    double mlt_b, mlt_scale;
    int mlt_chains;
    /* pssmlt, mmlt: the splats whose sample was evaluated again (CST_EXPLAIN_REPLAYED), and
     * how many of them gave the splatted radiance bit for bit (REPLAY_EXACT; exact is 0
     * when one did not). */
    int mlt_replayed, mlt_replay_exact;
    /* Spectral mode (not sppm, pssmlt, mmlt, light): the camera path's four wavelengths in
     * nm as the recorder last saw them (lane order: every event's value, beta and
     * contribution show lanes 0-2); 0 in RGB mode. photon_set: spectral photon, the set the
     * sample picked (its maps were traced at these wavelengths); -1 otherwise (sppm: 0). */
    float wavelengths[4];
    int photon_set;
} CstExplain;

/* Replays sample `sample` (for bdpt, sppm, pssmlt and mmlt: iteration; sppm, pssmlt and mmlt
 * replay iterations 0..sample of the whole image) of pixel (x, y) under `settings` (as for
 * cst_render; spp, crop, threads and first_sample are ignored) and records its path.
 * *out: a new record, cst_explain_destroy. CST_ERR_INVALID_ARG for a pixel off the image
 * or a negative sample; CST_ERR_UNSUPPORTED for an integrator explain cannot follow. */
CST_API CstStatus cst_explain(const CstScene *scene, const CstRenderSettings *settings, int x, int y, int sample,
                              CstExplain **out, CstError *err);
CST_API void cst_explain_destroy(CstExplain *explain);
/* "path, path-nee, path-bsdf, whitted, light, photon, bdpt, vcm, sppm, pssmlt, mmlt": the integrators
 * cst_explain follows (in participating media and spectral mode too). */
CST_API const char *cst_explain_integrators(void);

#endif
