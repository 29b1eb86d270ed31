/* Equal-time comparison of the integrators: for each scene, a long reference render, then
 * every integrator with the same time budgets, reporting relMSE against the reference and
 * samples per second. Prints a markdown table (docs/benchmarks.md).
 * Usage: bench_integrators [--size N] [--threads T] [--times S,S,...] [--ref-time S]
 *                          [--ref NAME] [--integrators A,B,...] SCENE.json...
 * relMSE = mean over pixels and channels of (x - ref)^2 / (ref^2 + 0.01): the usual
 * relative MSE with a small floor so black pixels do not dominate. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"

static CstFilm *render(const CstScene *s, CstIntegrator integ, int size, int threads, double seconds,
                       uint64_t seed, CstRenderStats *stats)
{
    CstRenderSettings rs = {0};
    rs.width = rs.height = size;
    rs.threads = threads;
    rs.integrator = integ;
    rs.time_limit = seconds;
    rs.spp = 1 << 30; /* the time limit decides */
    rs.seed = seed;
    rs.seed_set = 1;
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &rs, &f, stats, &err) != CST_OK) {
        fprintf(stderr, "bench_integrators: %s\n", err.msg);
        return NULL;
    }
    return f;
}

static double rel_mse(const CstFilm *f, const CstFilm *ref)
{
    int w = cst_film_width(f), h = cst_film_height(f);
    double sum = 0.0;
    for (int y = 0; y < h; y++)
        for (int x = 0; x < w; x++) {
            double a[3], r[3];
            cst_film_pixel(f, x, y, a);
            cst_film_pixel(ref, x, y, r);
            for (int c = 0; c < 3; c++) sum += (a[c] - r[c]) * (a[c] - r[c]) / (r[c] * r[c] + 0.01);
        }
    return sum / (3.0 * w * h);
}

static int split(char *list, char **out, int max)
{
    int n = 0;
    for (char *t = strtok(list, ","); t && n < max; t = strtok(NULL, ",")) out[n++] = t;
    return n;
}

int main(int argc, char **argv)
{
    int size = 256, threads = 2;
    double ref_time = 120.0;
    char times_buf[64] = "10,60", integ_buf[128] = "path,light,bdpt,vcm,sppm", ref_name[32] = "vcm";
    const char *scenes[16];
    int nscenes = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--size") && v) { size = atoi(v); i++; }
        else if (!strcmp(a, "--threads") && v) { threads = atoi(v); i++; }
        else if (!strcmp(a, "--ref-time") && v) { ref_time = atof(v); i++; }
        else if (!strcmp(a, "--times") && v) { snprintf(times_buf, sizeof times_buf, "%s", v); i++; }
        else if (!strcmp(a, "--integrators") && v) { snprintf(integ_buf, sizeof integ_buf, "%s", v); i++; }
        else if (!strcmp(a, "--ref") && v) { snprintf(ref_name, sizeof ref_name, "%s", v); i++; }
        else if (a[0] != '-' && nscenes < 16) scenes[nscenes++] = a;
        else {
            fprintf(stderr, "usage: bench_integrators [--size N] [--threads T] [--times S,S] [--ref-time S] "
                            "[--ref NAME] [--integrators A,B] SCENE.json...\n");
            return 2;
        }
    }
    char *time_str[8], *integ_str[16];
    int ntimes = split(times_buf, time_str, 8), ninteg = split(integ_buf, integ_str, 16);
    CstIntegrator ref_integ = cst_integrator_from_name(ref_name);
    if (nscenes == 0 || size <= 0 || threads <= 0 || ntimes == 0 || ninteg == 0 ||
        ref_integ == CST_INTEGRATOR_DEFAULT) {
        fprintf(stderr, "bench_integrators: need scenes, a positive size and thread count, times, integrators\n");
        return 2;
    }
    printf("%dx%d, %d threads; reference: %s for %.0f s; relMSE = mean (x - ref)^2 / (ref^2 + 0.01)\n\n",
           size, size, threads, ref_name, ref_time);
    printf("| scene | integrator |");
    for (int t = 0; t < ntimes; t++) printf(" relMSE %s s | spp %s s |", time_str[t], time_str[t]);
    printf(" Msamples/s |\n|---|---|");
    for (int t = 0; t < ntimes; t++) printf("---|---|");
    printf("---|\n");
    fflush(stdout);
    for (int si = 0; si < nscenes; si++) {
        CstScene *s = NULL;
        CstError err;
        if (cst_scene_load_json(scenes[si], &s, &err) != CST_OK) {
            fprintf(stderr, "bench_integrators: %s\n", err.msg);
            return 1;
        }
        CstRenderStats rst;
        CstFilm *ref = render(s, ref_integ, size, threads, ref_time, 999, &rst);
        if (!ref) return 1;
        const char *base = strrchr(scenes[si], '/');
        base = base ? base + 1 : scenes[si];
        for (int k = 0; k < ninteg; k++) {
            CstIntegrator integ = cst_integrator_from_name(integ_str[k]);
            if (integ == CST_INTEGRATOR_DEFAULT) {
                fprintf(stderr, "bench_integrators: unknown integrator %s\n", integ_str[k]);
                return 2;
            }
            printf("| %s | %s |", base, integ_str[k]);
            double rate = 0.0;
            for (int t = 0; t < ntimes; t++) {
                CstRenderStats st;
                CstFilm *f = render(s, integ, size, threads, atof(time_str[t]), 1 + (uint64_t)k, &st);
                if (!f) return 1;
                printf(" %.4g | %d |", rel_mse(f, ref), st.spp);
                rate = (double)st.samples / st.seconds / 1e6;
                cst_film_destroy(f);
            }
            printf(" %.3f |\n", rate);
            fflush(stdout);
        }
        cst_film_destroy(ref);
        cst_scene_destroy(s);
    }
    return 0;
}
