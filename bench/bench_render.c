/* Whole-render benchmark: the built-in Cornell box at 512x512 with MIS path tracing
 * (unbounded depth, Russian roulette), run with 1 thread and with all threads in the same
 * process, reporting camera paths/s, rays/s and the scaling ratio.
 * Usage: bench_render [SPP] [MAX_THREADS] [rgb|spectral]   (defaults: 256, all cores, rgb) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "caustic/caustic.h"

static int run(const CstScene *s, int spp, int threads, CstColorMode mode, CstRenderStats *st)
{
    CstRenderSettings rs = {0};
    rs.color_mode = mode;
    rs.spp = spp;
    rs.threads = threads;
    rs.integrator = CST_INTEGRATOR_PATH;
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &rs, &f, st, &err) != CST_OK) {
        fprintf(stderr, "bench_render: %s\n", err.msg);
        return 0;
    }
    cst_film_destroy(f);
    return 1;
}

int main(int argc, char **argv)
{
    int spp = argc > 1 ? atoi(argv[1]) : 256;
    int max_threads = argc > 2 ? atoi(argv[2]) : (int)sysconf(_SC_NPROCESSORS_ONLN);
    const char *mode_name = argc > 3 ? argv[3] : "rgb";
    CstColorMode mode = strcmp(mode_name, "rgb") == 0        ? CST_COLOR_RGB
                      : strcmp(mode_name, "spectral") == 0 ? CST_COLOR_SPECTRAL : CST_COLOR_DEFAULT;
    if (spp <= 0 || max_threads <= 0 || mode == CST_COLOR_DEFAULT) {
        fprintf(stderr, "usage: bench_render [SPP] [MAX_THREADS] [rgb|spectral]\n");
        return 2;
    }
    CstScene *s;
    CstError err;
    if (cst_scene_create_cornell_box(&s, &err) != CST_OK) {
        fprintf(stderr, "bench_render: %s\n", err.msg);
        return 1;
    }
    printf("Cornell box 512x512, path (MIS, RR from depth 3), %d spp, %s mode\n", spp, mode_name);
    printf("%8s %10s %14s %12s %10s\n", "threads", "seconds", "Mpaths/s", "Mrays/s", "vs 1 thr");
    double base = 0.0;
    int counts[2] = {1, max_threads};
    for (int i = 0; i < (max_threads > 1 ? 2 : 1); i++) {
        CstRenderStats st;
        if (!run(s, spp, counts[i], mode, &st)) return 1;
        double mpaths = (double)st.samples / st.seconds / 1e6;
        if (i == 0) base = mpaths;
        printf("%8d %10.2f %14.3f %12.2f %9.2fx\n", counts[i], st.seconds, mpaths,
               (double)st.rays / st.seconds / 1e6, mpaths / base);
    }
    cst_scene_destroy(s);
    return 0;
}
