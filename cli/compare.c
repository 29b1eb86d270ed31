/* caustic compare A B: reads two images (and variances), prints the library's comparison
 * (cst_image_compare: means, RMSE, relMSE, block z-scores; cst_image_flip: FLIP) as a
 * table or one JSON object, and writes the FLIP map. Exit codes as in docs/cli.md. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include <jansson.h>

#include "cli.h"

static const char CLI_CMP_CHANNELS[3] = {'r', 'g', 'b'};

/* The images of one comparison; every pointer freed by cli_compare_free. */
typedef struct CompareInputs {
    float *a, *b, *va, *vb;
    int w, h;
    const char *va_from, *vb_from; /* where the variances came from (for the report) */
} CompareInputs;

static void cli_compare_free(CompareInputs *in)
{
    free(in->a);
    free(in->b);
    free(in->va);
    free(in->vb);
}

/* Reads an image; prints the error and returns its exit code (0 when read). */
static int cli_compare_read(const char *path, float **rgb, int *w, int *h)
{
    CstError err = {0};
    CstStatus st = cst_image_read(path, rgb, w, h, &err);
    if (st == CST_OK) return CLI_EXIT_OK;
    cli_print_error(&err, st);
    return cli_exit_code(st, CLI_STAGE_LOAD);
}

/* The variances of one image: the file given (its variance layer when it is an EXR that has
 * one, else its RGB), or else the image's own variance AOV when it has one. */
static int cli_compare_variance(const char *given, const char *image, const char *which, int w, int h,
                                float **out, const char **from)
{
    CstError err = {0};
    int vw = 0, vh = 0;
    *out = NULL;
    const char *path = given ? given : image;
    CstStatus st = cst_image_path_is_exr(path) ? cst_image_read_layer(path, "variance", out, &vw, &vh, &err)
                                               : CST_ERR_UNSUPPORTED;
    if (st == CST_OK) {
        *from = given ? "the variance AOV of the file given"
                      : strcmp(which, "a") == 0 ? "A's variance AOV" : "B's variance AOV";
    } else if (!given) {
        return CLI_EXIT_OK; /* no AOV: no variances, not an error */
    } else {
        st = cst_image_read(path, out, &vw, &vh, &err);
        if (st != CST_OK) {
            cli_print_error(&err, st);
            return cli_exit_code(st, CLI_STAGE_LOAD);
        }
        *from = "the image given";
    }
    if (vw != w || vh != h) {
        fprintf(stderr, "caustic: error: --variance-%s: %s is %dx%d, the images are %dx%d\n", which, path, vw,
                vh, w, h);
        free(*out);
        *out = NULL;
        return CLI_EXIT_USAGE;
    }
    return CLI_EXIT_OK;
}

static int cli_compare_load(const CompareArgs *c, CompareInputs *in)
{
    int wb = 0, hb = 0, code;
    if ((code = cli_compare_read(c->a, &in->a, &in->w, &in->h)) != CLI_EXIT_OK) return code;
    if ((code = cli_compare_read(c->b, &in->b, &wb, &hb)) != CLI_EXIT_OK) return code;
    if (wb != in->w || hb != in->h) {
        fprintf(stderr, "caustic: error: the images differ in size: %s is %dx%d, %s is %dx%d\n", c->a, in->w,
                in->h, c->b, wb, hb);
        return CLI_EXIT_USAGE;
    }
    if ((code = cli_compare_variance(c->var_a, c->a, "a", in->w, in->h, &in->va, &in->va_from)) != CLI_EXIT_OK)
        return code;
    return cli_compare_variance(c->var_b, c->b, "b", in->w, in->h, &in->vb, &in->vb_from);
}

/* The FLIP kind: --flip, else LDR for two PNGs (8-bit display images) and HDR otherwise. */
static CstFlipKind cli_compare_flip_kind(const CompareArgs *c)
{
    if (c->flip) return (CstFlipKind)c->flip;
    return cli_has_suffix(c->a, ".png") && cli_has_suffix(c->b, ".png") ? CST_FLIP_LDR : CST_FLIP_HDR;
}

static json_t *cli_cmp_real(double v)
{
    return isfinite(v) ? json_real(v) : json_null();
}

static bool cli_compare_json(const CompareArgs *c, const CompareInputs *in, const CstImageComparison *r,
                             const CstFlipResult *f)
{
    json_t *channels = json_array();
    for (int k = 0; channels && k < 3; k++)
        json_array_append_new(channels,
            json_pack("{s:s#, s:o, s:o, s:o, s:o, s:o, s:o}", "channel", &CLI_CMP_CHANNELS[k], (size_t)1,
                      "mean_a", cli_cmp_real(r->mean_a[k]), "mean_b", cli_cmp_real(r->mean_b[k]),
                      "diff", cli_cmp_real(r->diff[k]), "rel_diff", cli_cmp_real(r->rel_diff[k]),
                      "rmse", cli_cmp_real(r->rmse[k]), "relmse", cli_cmp_real(r->relmse[k])));
    json_t *flip = json_pack("{s:s, s:o, s:o, s:f}", "kind", f->kind == CST_FLIP_LDR ? "ldr" : "hdr", "mean",
                             cli_cmp_real(f->mean), "max", cli_cmp_real(f->max), "ppd", f->pixels_per_degree);
    if (flip && f->kind == CST_FLIP_HDR) {
        json_object_set_new(flip, "start_exposure", cli_cmp_real(f->start_exposure));
        json_object_set_new(flip, "stop_exposure", cli_cmp_real(f->stop_exposure));
        json_object_set_new(flip, "exposures", json_integer(f->exposures));
    }
    json_t *z = json_null();
    if (r->has_z)
        z = json_pack("{s:[o,o,o], s:i, s:i, s:o, s:o, s:[i,i], s:s#, s:f, s:i, s:o, s:s?, s:s?}", "z_mean",
                      cli_cmp_real(r->z_mean[0]), cli_cmp_real(r->z_mean[1]), cli_cmp_real(r->z_mean[2]),
                      "block", c->block, "blocks", r->blocks, "max_abs_z", cli_cmp_real(r->max_abs_z),
                      "worst_z", cli_cmp_real(r->worst_z), "worst_block", r->worst_bx, r->worst_by,
                      "worst_channel", &CLI_CMP_CHANNELS[r->worst_channel], (size_t)1, "threshold",
                      CST_COMPARE_Z_OUTLIER, "above", r->above, "frac_above", cli_cmp_real(r->frac_above),
                      "variance_a", in->va_from, "variance_b", in->vb_from);
    json_t *o = channels && flip && z
        ? json_pack("{s:s, s:s, s:i, s:i, s:o, s:o, s:o, s:f, s:I, s:o, s:o}", "a", c->a, "b", c->b, "width",
                    in->w, "height", in->h, "channels", channels, "rmse", cli_cmp_real(r->rmse_all), "relmse",
                    cli_cmp_real(r->relmse_all), "relmse_eps", CST_RELMSE_EPS, "nonfinite",
                    (json_int_t)r->nonfinite, "flip", flip, "z", z)
        : NULL;
    if (!o) {
        json_decref(channels);
        json_decref(flip);
        json_decref(z);
    }
    char *line = o ? json_dumps(o, JSON_COMPACT | JSON_PRESERVE_ORDER) : NULL;
    json_decref(o);
    if (!line) {
        fprintf(stderr, "caustic: error: out of memory for the JSON report\n");
        return false;
    }
    printf("%s\n", line);
    free(line);
    return true;
}

static void cli_compare_print(const CompareArgs *c, const CompareInputs *in, const CstImageComparison *r,
                              const CstFlipResult *f)
{
    printf("compare:  %s against the reference %s, %dx%d\n", c->a, c->b, in->w, in->h);
    printf("channel   mean A        mean B        A - B         (A - B)/B   RMSE          relMSE\n");
    for (int k = 0; k < 3; k++)
        printf("%c         %-13.6g %-13.6g %-+13.6g %-+10.4f  %-13.6g %-13.6g\n", CLI_CMP_CHANNELS[k],
               r->mean_a[k], r->mean_b[k], r->diff[k], r->rel_diff[k], r->rmse[k], r->relmse[k]);
    printf("all                                                             %-13.6g %-13.6g\n", r->rmse_all,
           r->relmse_all);
    printf("relMSE:   mean of (a - b)^2 / (b^2 + %g) over pixels and channels\n", CST_RELMSE_EPS);
    if (f->kind == CST_FLIP_LDR)
        printf("FLIP:     %.6f mean, %.6f max (LDR-FLIP of the images clamped to [0, 1], %.2f pixels per "
               "degree)\n", f->mean, f->max, f->pixels_per_degree);
    else
        printf("FLIP:     %.6f mean, %.6f max (HDR-FLIP: %d exposure%s from %+.4f to %+.4f stops, %.2f pixels "
               "per degree)\n", f->mean, f->max, f->exposures, f->exposures == 1 ? "" : "s", f->start_exposure,
               f->stop_exposure, f->pixels_per_degree);
    if (r->has_z) {
        printf("z:        variances of A: %s; of B: %s\n", in->va_from ? in->va_from : "none (exact)",
               in->vb_from ? in->vb_from : "none (exact)");
        printf("          image mean z  r %+.3f  g %+.3f  b %+.3f\n", r->z_mean[0], r->z_mean[1], r->z_mean[2]);
        printf("          %d blocks of %dx%d: max |z| %.3f (block %d,%d channel %c), %d of %d block tests "
               "(%.2f%%) with |z| > %g\n", r->blocks, c->block, c->block, r->max_abs_z, r->worst_bx,
               r->worst_by, CLI_CMP_CHANNELS[r->worst_channel], r->above, 3 * r->blocks, 100.0 * r->frac_above,
               CST_COMPARE_Z_OUTLIER);
    } else {
        printf("z:        no variances (--variance-a/-b, or an EXR with a variance AOV)\n");
    }
    if (r->nonfinite)
        printf("note:     %lld NaN or infinite values (pixel x channel) in A or B left out\n",
               (long long)r->nonfinite);
}

/* The FLIP error as grey: for PNG (sRGB-encoded by the writer) each byte is 255 x error,
 * so the value handed over is the sRGB decoding of the error (IEC 61966-2-1); EXR and PFM
 * hold the error itself. */
static int cli_compare_write_map(const char *path, const float *err_map, int w, int h)
{
    size_t n = (size_t)w * (size_t)h;
    float *rgb = malloc(3 * n * sizeof *rgb);
    if (!rgb) {
        fprintf(stderr, "caustic: error: out of memory for the %dx%d map\n", w, h);
        return CLI_EXIT_INTERNAL;
    }
    bool png = cli_has_suffix(path, ".png");
    for (size_t i = 0; i < n; i++) {
        double e = (double)err_map[i];
        double v = !png ? e : e <= 0.04045 ? e / 12.92 : pow((e + 0.055) / 1.055, 2.4);
        rgb[3 * i] = rgb[3 * i + 1] = rgb[3 * i + 2] = (float)v;
    }
    CstError err = {0};
    CstStatus st = cst_image_write(path, rgb, w, h, &err);
    free(rgb);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        return cli_exit_code(st, CLI_STAGE_WRITE);
    }
    return CLI_EXIT_OK;
}

int cli_compare(const CliArgs *args)
{
    const CompareArgs *c = &args->compare;
    if (c->map_path && !cli_check_output(c->map_path, "--map")) return CLI_EXIT_USAGE;
    CompareInputs in;
    memset(&in, 0, sizeof in);
    int code = cli_compare_load(c, &in);
    float *flip_map = NULL;
    if (code != CLI_EXIT_OK) goto done;
    code = CLI_EXIT_INTERNAL;
    flip_map = malloc((size_t)in.w * (size_t)in.h * sizeof *flip_map);
    if (!flip_map) {
        fprintf(stderr, "caustic: error: out of memory for a %dx%d image\n", in.w, in.h);
        goto done;
    }
    CstError err = {0};
    CstImageComparison r;
    CstStatus st = cst_image_compare(in.a, in.b, in.w, in.h, in.va, in.vb, c->block, &r, NULL, &err);
    CstFlipOptions fo = {0};
    fo.kind = cli_compare_flip_kind(c);
    fo.pixels_per_degree = c->ppd;
    CstFlipResult f;
    if (st == CST_OK) st = cst_image_flip(in.a, in.b, in.w, in.h, &fo, flip_map, &f, &err);
    if (st != CST_OK) {
        cli_print_error(&err, st);
        code = cli_exit_code(st, CLI_STAGE_RENDER);
        goto done;
    }
    if (c->json) {
        if (!cli_compare_json(c, &in, &r, &f)) goto done;
    } else {
        cli_compare_print(c, &in, &r, &f);
    }
    code = CLI_EXIT_OK;
    if (c->map_path) {
        fflush(stdout);
        code = cli_compare_write_map(c->map_path, flip_map, in.w, in.h);
        if (code == CLI_EXIT_OK && !args->quiet)
            fprintf(stderr, "caustic: compare: wrote the FLIP map to %s\n", c->map_path);
    }
done:
    free(flip_map);
    cli_compare_free(&in);
    return code;
}
