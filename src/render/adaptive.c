/* Adaptive sampling by quality (adaptive.h): per-block relative standard errors from the
 * film's per-pixel sums and sums of squares, the rounds planned from them, the summary. */
#include "render/adaptive.h"

#include <limits.h>
#include <math.h>

/* Relative luminance of linear sRGB (Rec. ITU-R BT.709, the Y row of its RGB -> XYZ). */
static const double LUMA[3] = {0.2126, 0.7152, 0.0722};

/* A block's mean luminance is (1/P) sum_i Y_i over its P pixels, each Y_i the mean of the
 * pixel's n_i samples, so its variance is (1/P^2) sum_i Var(Y_i) and its relative standard
 * error sqrt(sum_i Var(Y_i)) / sum_i Y_i. The film keeps no R-G-B cross products, so
 * Var(Y_i) is bounded by its value for fully correlated channels, (sum_c w_c sd_c)^2
 * (Cauchy-Schwarz): exact when a pixel's noise scales all three channels together (light
 * sampling, geometry terms), an over-estimate for colour noise; the estimate errs on the
 * safe side. Each sd_c^2 is the unbiased sample variance over n_i, with n_i - 1 degrees of
 * freedom; the sum's are Satterthwaite's (1946): (sum v_i)^2 / sum v_i^2 / (n_i - 1). */
BlockNoise adaptive_block_noise(const Film *f, int x0, int y0, int x1, int y1)
{
    BlockNoise b = {0.0, (double)INFINITY, film_pixel_spp(f, (size_t)y0 * (size_t)f->width + (size_t)x0)};
    double mean = 0.0, var = 0.0, var2 = 0.0;
    for (int y = y0; y < y1; y++)
        for (int x = x0; x < x1; x++) {
            const size_t i = (size_t)y * (size_t)f->width + (size_t)x;
            const int spp = film_pixel_spp(f, i);
            if (spp < 2) {
                b.rel = (double)INFINITY;
                b.dof = 0.0;
                return b;
            }
            const double n = (double)spp;
            double y_mean = 0.0, sd = 0.0;
            for (int c = 0; c < 3; c++) {
                const double m = f->sum[3 * i + (size_t)c] / n;
                const double v = (f->sum_sq[3 * i + (size_t)c] - n * m * m) / (n - 1.0) / n;
                y_mean += LUMA[c] * m;
                sd += LUMA[c] * sqrt(v > 0.0 ? v : 0.0);
            }
            mean += y_mean;
            var += sd * sd;
            var2 += sd * sd * sd * sd / (n - 1.0);
        }
    if (var <= 0.0) return b; /* every sample alike (a black block): nothing to estimate */
    b.rel = mean > 0.0 ? sqrt(var) / mean : (double)INFINITY;
    b.dof = var2 > 0.0 ? var * var / var2 : (double)INFINITY;
    return b;
}

int adaptive_more(int n, double rel, double target, int cap)
{
    if (n >= cap) return 0;
    if (n <= 0) return ADAPTIVE_MIN_SPP < cap ? ADAPTIVE_MIN_SPP : cap;
    if (rel <= target) return 0;
    /* The error falls as 1/sqrt(n): n (rel/target)^2 samples are predicted to reach the
     * target. At most doubling, so a poor early variance estimate is corrected by the next
     * round's; at least a quarter more, so a block near the target does not take many tiny
     * rounds. */
    const double need = (double)n * (rel / target) * (rel / target);
    int more = need >= 2.0 * n ? n : (int)ceil(need) - n;
    if (more < (n + 3) / 4) more = (n + 3) / 4;
    if (more > n) more = n;
    return more < cap - n ? more : cap - n;
}

AdaptiveGrid adaptive_grid(const int crop[4])
{
    AdaptiveGrid g = {crop[0], crop[2], crop[1], crop[3], 0, 0};
    g.tiles_x = (g.x1 - g.x0 + INTEGRATOR_TILE - 1) / INTEGRATOR_TILE;
    g.tiles = g.tiles_x * ((g.y1 - g.y0 + INTEGRATOR_TILE - 1) / INTEGRATOR_TILE);
    return g;
}

/* The integrators' tiles (integrator.c, camera_tile). */
void adaptive_tile_rect(const AdaptiveGrid *g, int tile, int *x0, int *y0, int *x1, int *y1)
{
    *x0 = g->x0 + (tile % g->tiles_x) * INTEGRATOR_TILE;
    *y0 = g->y0 + (tile / g->tiles_x) * INTEGRATOR_TILE;
    *x1 = *x0 + INTEGRATOR_TILE < g->x1 ? *x0 + INTEGRATOR_TILE : g->x1;
    *y1 = *y0 + INTEGRATOR_TILE < g->y1 ? *y0 + INTEGRATOR_TILE : g->y1;
}

int adaptive_plan(const Film *f, const AdaptiveGrid *g, double target, int cap, IntegratorTileRun *runs,
                  uint64_t *samples)
{
    int n = 0;
    *samples = 0;
    for (int t = 0; t < g->tiles; t++) {
        int x0, y0, x1, y1;
        adaptive_tile_rect(g, t, &x0, &y0, &x1, &y1);
        const BlockNoise b = adaptive_block_noise(f, x0, y0, x1, y1);
        const int more = adaptive_more(b.spp, b.rel, target, cap);
        if (more <= 0) continue;
        runs[n++] = (IntegratorTileRun){t, b.spp, more};
        *samples += (uint64_t)more * (uint64_t)((x1 - x0) * (y1 - y0));
    }
    return n;
}

void adaptive_commit(Film *f, const AdaptiveGrid *g, const IntegratorTileRun *runs, int n)
{
    for (int k = 0; k < n; k++) {
        int x0, y0, x1, y1;
        adaptive_tile_rect(g, runs[k].tile, &x0, &y0, &x1, &y1);
        for (int y = y0; y < y1; y++)
            for (int x = x0; x < x1; x++) f->pixel_spp[(size_t)y * (size_t)f->width + (size_t)x] += runs[k].count;
        const int spp = runs[k].first + runs[k].count;
        if (spp > f->spp) f->spp = spp;
    }
}

int adaptive_plan_uniform(const Film *f, const AdaptiveGrid *g, double target, int cap)
{
    int want = 0;
    for (int t = 0; t < g->tiles; t++) {
        int x0, y0, x1, y1;
        adaptive_tile_rect(g, t, &x0, &y0, &x1, &y1);
        const BlockNoise b = adaptive_block_noise(f, x0, y0, x1, y1);
        const int more = adaptive_more(f->spp, b.rel, target, cap);
        if (more > want) want = more;
    }
    return want;
}

/* The p-quantile of chi-square with nu degrees of freedom, by Wilson and Hilferty's cube
 * root normal approximation (1931); z the standard normal's p-quantile. Good to a few
 * tenths of a percent for nu >= 10, and a block's nu is in the thousands. */
static double chi2_quantile(double nu, double z)
{
    const double a = 2.0 / (9.0 * nu), c = 1.0 - a + z * sqrt(a);
    return c > 0.0 ? nu * c * c * c : 0.0;
}

void adaptive_summary(const Film *f, const AdaptiveGrid *g, double target, CstRenderStats *stats)
{
    double sum2 = 0.0, sum4 = 0.0, worst = 0.0;
    int over = 0, spp_min = INT_MAX;
    for (int t = 0; t < g->tiles; t++) {
        int x0, y0, x1, y1;
        adaptive_tile_rect(g, t, &x0, &y0, &x1, &y1);
        const BlockNoise b = adaptive_block_noise(f, x0, y0, x1, y1);
        if (b.rel > target) over++;
        if (b.rel > worst) worst = b.rel;
        if (b.spp < spp_min) spp_min = b.spp;
        sum2 += b.rel * b.rel;
        if (b.rel > 0.0 && isfinite(b.rel)) sum4 += b.rel * b.rel * b.rel * b.rel / b.dof;
    }
    /* The mean of the blocks' squared errors, each an estimate spread as chi-square over
     * its dof, has Satterthwaite's dof (sum r^2)^2 / sum r^4 / dof; its 95% interval
     * [nu / chi2(0.975), nu / chi2(0.025)] times the estimate, square-rooted for the RMS. */
    const double rms = g->tiles > 0 ? sqrt(sum2 / g->tiles) : 0.0;
    stats->noise_rms = stats->noise_rms_lo = stats->noise_rms_hi = rms;
    if (sum4 > 0.0 && isfinite(rms)) {
        const double nu = sum2 * sum2 / sum4;
        stats->noise_rms_lo = rms * sqrt(nu / chi2_quantile(nu, 1.959964));
        const double q = chi2_quantile(nu, -1.959964);
        stats->noise_rms_hi = q > 0.0 ? rms * sqrt(nu / q) : (double)INFINITY;
    }
    stats->noise_max = worst;
    stats->noise_blocks = g->tiles;
    stats->noise_blocks_over = over;
    stats->spp_min = g->tiles > 0 ? spp_min : 0;
}
