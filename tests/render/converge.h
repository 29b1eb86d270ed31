/* The convergence tests of the consistent estimators (test_photon, test_photon_spectral,
 * test_sppm): the path tracer's whole-image reference, a whole-image mean from independent
 * renders, and photon mapping's Richardson check against the reference. Include after
 * cmocka.h. */
#ifndef CST_TESTS_CONVERGE_H
#define CST_TESTS_CONVERGE_H

#include <math.h>
#include <stdbool.h>

#include "render/render_util.h"

/* The whole size x size image's mean of the MIS path tracer (spp samples, seed 1, colour
 * mode `mode`), its standard errors from the film's per-pixel variances. */
static inline RegionStat converge_path_reference(const CstScene *s, int size, int spp, CstColorMode mode)
{
    CstRenderSettings st = {0};
    st.width = st.height = size;
    st.spp = spp;
    st.integrator = CST_INTEGRATOR_PATH;
    st.color_mode = mode;
    st.seed = 1;
    st.seed_set = 1;
    st.sampler = CST_SAMPLER_INDEPENDENT; /* region_stat's per-pixel variances assume it */
    CstFilm *f = NULL;
    CstError err;
    if (cst_render(s, &st, &f, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    RegionStat ref = region_stat(f, 0, 0, size, size);
    cst_film_destroy(f);
    return ref;
}

/* The whole image's mean over `renders` independent renders of st (seeds seed, seed + 1,
 * ...): each render builds its own photon maps, so the spread of the per-render means holds
 * the maps' noise as well as the gather noise, which per-pixel variances would miss (one
 * map serves every pixel). */
static inline RegionStat converge_mean_by_render(const CstScene *s, const CstRenderSettings *st, int renders,
                                                 uint64_t seed)
{
    const int whole[1][4] = {{0, 0, st->width, st->height}};
    RegionStat r;
    CstError err;
    if (region_stats_by_render(s, st, renders, seed, 1, whole, &r, NULL, &err) != CST_OK) fail_msg("%s", err.msg);
    return r;
}

/* Photon mapping's fixed-radius bias is first order in r, so the Richardson extrapolation
 * 2 m(r/2) - m(r) of coarse (N photons, r) and fine (4N, r/2) removes it: per channel it must
 * agree with the path tracer's ref within Z_LIMIT standard errors, and (check_shrink) the
 * bias at fine must be smaller than at coarse. Prints each channel's figures (labelled as
 * both tests run them: 10k photons at r = 40 mm, 40k at 20 mm). */
static inline void converge_richardson_check(RegionStat ref, RegionStat coarse, RegionStat fine, bool check_shrink,
                                             const char *what)
{
    for (int c = 0; c < 3; c++) {
        double d_coarse = coarse.mean[c] - ref.mean[c], d_fine = fine.mean[c] - ref.mean[c];
        double rich = 2.0 * fine.mean[c] - coarse.mean[c];
        double rich_se = sqrt(4.0 * fine.se[c] * fine.se[c] + coarse.se[c] * coarse.se[c]);
        double z = z_score(rich, rich_se, ref.mean[c], ref.se[c]);
        print_message("channel %d: path %.6f +- %.6f; photon (10k, 40) %+.6f +- %.6f, "
                      "(40k, 20) %+.6f +- %.6f; extrapolated %.6f, z = %.2f\n",
                      c, ref.mean[c], ref.se[c], d_coarse, coarse.se[c], d_fine, fine.se[c], rich, z);
        if (check_shrink && !(fabs(d_fine) < fabs(d_coarse)))
            fail_msg("channel %d: the bias did not shrink: %+.6f at (10k, r = 40), %+.6f at (40k, r = 20)",
                     c, d_coarse, d_fine);
        if (!(fabs(z) <= Z_LIMIT))
            fail_msg("channel %d: extrapolated %s mean %.6f vs path %.6f, z = %.2f", c, what, rich, ref.mean[c], z);
    }
}

#endif
