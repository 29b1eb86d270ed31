/* The tabulated photon-beam-diffusion BSSRDF (bssrdf.h): table construction, the Catmull-Rom
 * spline machinery over its two axes (albedo, optical radius), Sp, sampling and pdfs, Sw.
 * Written from pbrt 4th ed. sec. 11.4 (3rd ed. sec. 15.5) and Habel et al. 2013. */
#include "materials/bssrdf.h"

#include <math.h>

#include "materials/fresnel.h"

static const double PI_D = 3.14159265358979323846;

/* ------------------------------------------------------------------ Fresnel moments */

/* d'Eon & Irving 2011, "A quantized-diffusion model for rendering translucent materials",
 * the polynomial fits of the first two Fresnel moments (also pbrt-v3 sec. 11.4.1). */
float bssrdf_fresnel_moment1(float eta)
{
    float e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1.0f)
        return 0.45966f - 1.73965f * eta + 3.37668f * e2 - 3.904945f * e3 + 2.49277f * e4 - 0.68441f * e5;
    return -4.61686f + 11.1136f * eta - 10.4646f * e2 + 5.11455f * e3 - 1.27198f * e4 + 0.12746f * e5;
}

float bssrdf_fresnel_moment2(float eta)
{
    float e2 = eta * eta, e3 = e2 * eta, e4 = e3 * eta, e5 = e4 * eta;
    if (eta < 1.0f)
        return 0.27614f - 0.87350f * eta + 1.12077f * e2 - 0.65095f * e3 + 0.07883f * e4 + 0.04860f * e5;
    float r = 1.0f / eta, r2 = r * r, r3 = r2 * r;
    return -547.033f + 45.3087f * r3 - 218.725f * r2 + 458.843f * r + 404.557f * eta - 189.519f * e2 +
           54.9327f * e3 - 9.00603f * e4 + 0.63942f * e5;
}

/* ------------------------------------------------------------------ beam diffusion */

/* Henyey-Greenstein phase function of the angle between propagation directions. */
static double phase_hg(double cos_t, double g)
{
    double d = 1.0 + g * g + 2.0 * g * cos_t;
    return (1.0 - g * g) / (4.0 * PI_D * d * sqrt(d));
}

enum { BEAM_SAMPLES = 100 }; /* depths along the beam (pbrt's count) */

/* Multiple scattering: photon beam diffusion (Habel et al. 2013 eq. 8), the refracted beam
 * (depth z_r ~ sigma_t' e^{-sigma_t' z}, stratified) as a line of dipole sources. Each
 * depth's dipole: real source at z_r, virtual at z_v = -z_r + 2 z_e (extrapolated boundary
 * z_e from the Fresnel moments, d'Eon & Irving 2011 eq. 27), Grosjean's diffusion
 * coefficient D = (2 sigma_a + sigma_t') / (3 sigma_t'^2); the exitance is
 * c_phi phi + c_E E (d'Eon & Irving eq. 20-21), scaled by rho'^2 and the beam's
 * correction kappa = 1 - e^{-2 sigma_t' (d_r + z_r)} (Habel et al. eq. 10). */
float bssrdf_beam_ms(float sigma_s, float sigma_a, float g, float eta, float r)
{
    const double sps = (double)sigma_s * (1.0 - (double)g), spt = (double)sigma_a + sps, rhop = sps / spt;
    const double D = (2.0 * (double)sigma_a + spt) / (3.0 * spt * spt);
    const double str = sqrt(fmax((double)sigma_a / D, 0.0));
    const double fm1 = (double)bssrdf_fresnel_moment1(eta), fm2 = (double)bssrdf_fresnel_moment2(eta);
    const double ze = -2.0 * D * (1.0 + 3.0 * fm2) / (1.0 - 2.0 * fm1);
    const double c_phi = 0.25 * (1.0 - 2.0 * fm1), c_e = 0.5 * (1.0 - 3.0 * fm2);
    const double rr = (double)r;
    double ed = 0.0;
    for (int i = 0; i < BEAM_SAMPLES; i++) {
        double u = (i + 0.5) / BEAM_SAMPLES;
        double zr = -log(1.0 - u) / spt, zv = -zr + 2.0 * ze;
        double dr = sqrt(rr * rr + zr * zr), dv = sqrt(rr * rr + zv * zv);
        double er = exp(-str * dr), ev = exp(-str * dv);
        double phi = (er / dr - ev / dv) / (4.0 * PI_D * D);
        double edn = (zr * (1.0 + str * dr) * er / (dr * dr * dr) - zv * (1.0 + str * dv) * ev / (dv * dv * dv)) /
                     (4.0 * PI_D);
        double e = phi * c_phi + edn * c_e;
        double kappa = 1.0 - exp(-2.0 * spt * (dr + zr));
        ed += kappa * rhop * rhop * e;
    }
    return (float)(ed / BEAM_SAMPLES);
}

/* Single scattering along the refracted beam (Habel et al. eq. 9 with the normal-incidence
 * beam of pbrt): depths t >= t_crit = r sqrt(eta^2 - 1) (below it the exit direction is
 * totally reflected) sampled ~ sigma_t e^{-sigma_t (t - t_crit)}; each contributes
 * rho e^{-sigma_t (d + t_crit)} / d^2 p(cos) (1 - F) |cos| with cos = t / d. */
float bssrdf_beam_ss(float sigma_s, float sigma_a, float g, float eta, float r)
{
    const double st = (double)sigma_s + (double)sigma_a, rho = (double)sigma_s / st;
    const double rr = (double)r, tc = rr * sqrt(fmax((double)eta * (double)eta - 1.0, 0.0));
    double ess = 0.0;
    for (int i = 0; i < BEAM_SAMPLES; i++) {
        double u = (i + 0.5) / BEAM_SAMPLES;
        double ti = tc - log(1.0 - u) / st;
        double d = sqrt(rr * rr + ti * ti), cos_o = ti / d;
        double ft = 1.0 - (double)fresnel_dielectric((float)-cos_o, eta); /* leaving from inside */
        ess += rho * exp(-st * (d + tc)) / (d * d) * phase_hg(cos_o, (double)g) * ft * fabs(cos_o);
    }
    return (float)(ess / BEAM_SAMPLES);
}

/* ------------------------------------------------------------------ Catmull-Rom splines */

/* The last i in [0, n - 2] with x[i] <= v (x increasing). */
static int find_interval(const float *x, int n, float v)
{
    int lo = 0, hi = n - 2;
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (x[mid] <= v) lo = mid; else hi = mid - 1;
    }
    return lo;
}

/* Weights of the four nodes offset..offset+3 whose values give the Catmull-Rom spline at v
 * (the cubic Hermite segment [x_i, x_i+1] with finite-difference tangents, one-sided at
 * the ends). False outside [x_0, x_n-1]. A weight is 0 for a node outside the array. */
static bool catmull_rom_weights(const float *x, int n, float v, int *offset, float w[4])
{
    if (!(v >= x[0] && v <= x[n - 1])) return false;
    int i = find_interval(x, n, v);
    *offset = i - 1;
    float x0 = x[i], x1 = x[i + 1], width = x1 - x0;
    float t = (v - x0) / width, t2 = t * t, t3 = t2 * t;
    /* Hermite basis: f = h00 f_i + h01 f_i+1 + h10 d_i + h11 d_i+1 (tangents per unit t). */
    float h00 = 2.0f * t3 - 3.0f * t2 + 1.0f, h01 = -2.0f * t3 + 3.0f * t2;
    float h10 = t3 - 2.0f * t2 + t, h11 = t3 - t2;
    w[0] = 0.0f;
    w[1] = h00;
    w[2] = h01;
    w[3] = 0.0f;
    if (i > 0) { /* d_i = (f_i+1 - f_i-1) width / (x_i+1 - x_i-1) */
        float k = h10 * width / (x1 - x[i - 1]);
        w[0] = -k;
        w[2] += k;
    } else { /* d_i = f_i+1 - f_i */
        w[1] -= h10;
        w[2] += h10;
    }
    if (i + 2 < n) { /* d_i+1 = (f_i+2 - f_i) width / (x_i+2 - x_i) */
        float k = h11 * width / (x[i + 2] - x0);
        w[3] = k;
        w[1] -= k;
    } else {
        w[1] -= h11;
        w[2] += h11;
    }
    return true;
}

/* The spline's integral over each interval (pbrt IntegrateCatmullRom): cdf[0] = 0,
 * cdf[i + 1] = the integral up to x[i + 1]. Returns the whole integral. The Hermite
 * segment integrates to width ((f0 + f1) / 2 + (d0 - d1) / 12). */
static float integrate_catmull_rom(const float *x, const float *f, int n, float *cdf)
{
    double sum = 0.0;
    cdf[0] = 0.0f;
    for (int i = 0; i < n - 1; i++) {
        float x0 = x[i], x1 = x[i + 1], f0 = f[i], f1 = f[i + 1], width = x1 - x0;
        float d0 = i > 0 ? width * (f1 - f[i - 1]) / (x1 - x[i - 1]) : f1 - f0;
        float d1 = i + 2 < n ? width * (f[i + 2] - f0) / (x[i + 2] - x0) : f1 - f0;
        sum += (double)(((d0 - d1) * (1.0f / 12.0f) + (f0 + f1) * 0.5f) * width);
        cdf[i + 1] = (float)sum;
    }
    return (float)sum;
}

/* The Hermite segment F(t) = int_0^t f and f(t) for t in [0, 1] (per unit t). */
static void hermite_integral(float f0, float f1, float d0, float d1, float t, float *F, float *f)
{
    *F = t * (f0 + t * (0.5f * d0 + t * ((1.0f / 3.0f) * (-2.0f * d0 - d1) + f1 - f0 +
                                         t * (0.25f * (d0 + d1) + 0.5f * (f0 - f1)))));
    *f = f0 + t * (d0 + t * (-2.0f * d0 - d1 + 3.0f * (f1 - f0) + t * (d0 + d1 + 2.0f * (f0 - f1))));
}

/* Solves g(t) = target on [0, 1] for an increasing g by Newton steps kept inside a
 * shrinking bracket (bisection when a step leaves it). eval gives g and g'. */
typedef void (*SplineEval)(const float c[4], float t, float *g, float *dg);

static float newton_bisect(SplineEval eval, const float c[4], float target, float t)
{
    float a = 0.0f, b = 1.0f;
    for (int it = 0; it < 64; it++) {
        if (!(t >= a && t <= b)) t = 0.5f * (a + b);
        float g, dg;
        eval(c, t, &g, &dg);
        if (fabsf(g - target) < 1e-6f || b - a < 1e-6f) break;
        if (g - target < 0.0f) a = t; else b = t;
        t -= (g - target) / dg;
    }
    return t;
}

static void eval_integral(const float c[4], float t, float *g, float *dg)
{
    hermite_integral(c[0], c[1], c[2], c[3], t, g, dg);
}

static void eval_value(const float c[4], float t, float *g, float *dg)
{
    float f0 = c[0], f1 = c[1], d0 = c[2], d1 = c[3], t2 = t * t, t3 = t2 * t;
    *g = (2.0f * t3 - 3.0f * t2 + 1.0f) * f0 + (-2.0f * t3 + 3.0f * t2) * f1 + (t3 - 2.0f * t2 + t) * d0 +
         (t3 - t2) * d1;
    *dg = (6.0f * t2 - 6.0f * t) * f0 + (-6.0f * t2 + 6.0f * t) * f1 + (3.0f * t2 - 4.0f * t + 1.0f) * d0 +
          (3.0f * t2 - 2.0f * t) * d1;
}

/* ------------------------------------------------------------------ the table */

void bssrdf_table_build(BssrdfTable *t, float g, float eta)
{
    t->g = g;
    t->eta = eta;
    /* Radii: 0, then geometric from 2.5e-3 by 1.2 (to about 2e2 optical radii); albedos
     * crowded toward 1, where the profile changes fastest (pbrt's spacing). */
    t->radius[0] = 0.0f;
    t->radius[1] = 2.5e-3f;
    for (int j = 2; j < BSSRDF_NUM_RADIUS; j++) t->radius[j] = t->radius[j - 1] * 1.2f;
    for (int i = 0; i < BSSRDF_NUM_RHO; i++)
        t->rho[i] = (float)((1.0 - exp(-8.0 * i / (BSSRDF_NUM_RHO - 1.0))) / (1.0 - exp(-8.0)));
    for (int i = 0; i < BSSRDF_NUM_RHO; i++) {
        float rho = t->rho[i], *row = &t->profile[i * BSSRDF_NUM_RADIUS];
        for (int j = 0; j < BSSRDF_NUM_RADIUS; j++) {
            float r = t->radius[j];
            row[j] = 2.0f * CST_PI * r *
                     (bssrdf_beam_ss(rho, 1.0f - rho, g, eta, r) + bssrdf_beam_ms(rho, 1.0f - rho, g, eta, r));
        }
        t->rho_eff[i] = integrate_catmull_rom(t->radius, row, BSSRDF_NUM_RADIUS,
                                              &t->profile_cdf[i * BSSRDF_NUM_RADIUS]);
    }
}

float bssrdf_invert_rho_eff(const BssrdfTable *t, float target)
{
    const float *x = t->rho, *f = t->rho_eff;
    const int n = BSSRDF_NUM_RHO;
    if (!(target > f[0])) return x[0];
    if (!(target < f[n - 1])) return x[n - 1];
    int i = find_interval(f, n, target);
    float x0 = x[i], x1 = x[i + 1], width = x1 - x0;
    float c[4] = {f[i], f[i + 1], i > 0 ? width * (f[i + 1] - f[i - 1]) / (x1 - x[i - 1]) : f[i + 1] - f[i],
                  i + 2 < n ? width * (f[i + 2] - f[i]) / (x[i + 2] - x0) : f[i + 1] - f[i]};
    return x0 + width * newton_bisect(eval_value, c, target, 0.5f);
}

void bssrdf_from_reflectance(const BssrdfTable *t, Color r, Color mfp, Color *sigma_a, Color *sigma_s)
{
    for (int c = 0; c < COLOR_LANES; c++) {
        float rho = bssrdf_invert_rho_eff(t, r.c[c]);
        float inv = mfp.c[c] > 0.0f ? 1.0f / mfp.c[c] : 0.0f;
        sigma_s->c[c] = rho * inv;
        sigma_a->c[c] = (1.0f - rho) * inv;
    }
}

/* ------------------------------------------------------------------ per-hit BSSRDF */

void bssrdf_init(Bssrdf *b, const BssrdfTable *t, Color sigma_a, Color sigma_s, Vec3 po, Vec3 ns)
{
    b->table = t;
    b->eta = t->eta;
    for (int c = 0; c < COLOR_LANES; c++) {
        float sa = maxf(sigma_a.c[c], 0.0f), ss = maxf(sigma_s.c[c], 0.0f), st = sa + ss;
        b->sigma_t.c[c] = st;
        b->rho.c[c] = st > 0.0f ? ss / st : 0.0f;
    }
    b->po = po;
    b->frame = frame_from_normal(ns);
}

/* The 2D spline of the profile at (rho, r_opt), and rho_eff at rho: false outside the table. */
static bool profile_at(const BssrdfTable *t, float rho, float r_opt, float *sr, float *rho_eff)
{
    int ro, rr;
    float wr[4], wd[4];
    if (!catmull_rom_weights(t->rho, BSSRDF_NUM_RHO, rho, &ro, wr) ||
        !catmull_rom_weights(t->radius, BSSRDF_NUM_RADIUS, r_opt, &rr, wd))
        return false;
    float s = 0.0f, e = 0.0f;
    for (int i = 0; i < 4; i++) {
        if (wr[i] == 0.0f) continue;
        int ri = ro + i;
        e += wr[i] * t->rho_eff[ri];
        for (int j = 0; j < 4; j++)
            if (wd[j] != 0.0f) s += wr[i] * wd[j] * t->profile[ri * BSSRDF_NUM_RADIUS + rr + j];
    }
    /* the profile holds 2 pi r Sr: back to a density per unit area */
    if (r_opt != 0.0f) s /= 2.0f * CST_PI * r_opt;
    *sr = s;
    *rho_eff = e;
    return true;
}

Color bssrdf_sr(const Bssrdf *b, float r)
{
    Color out;
    for (int c = 0; c < COLOR_LANES; c++) {
        float st = b->sigma_t.c[c], sr = 0.0f, e;
        /* optical units -> scene units: an area scales by 1 / sigma_t^2 */
        if (st > 0.0f && profile_at(b->table, b->rho.c[c], r * st, &sr, &e)) sr *= st * st;
        out.c[c] = maxf(sr, 0.0f);
    }
    return out;
}

float bssrdf_pdf_sr(const Bssrdf *b, int c, float r)
{
    float st = b->sigma_t.c[c], sr, e;
    if (!(st > 0.0f) || !profile_at(b->table, b->rho.c[c], r * st, &sr, &e) || !(e > 0.0f)) return 0.0f;
    return maxf(sr * st * st / e, 0.0f);
}

/* Column j of a table's rows ro..ro+3 weighted by wr (the spline over rho). */
static float row_at(const float *arr, int ro, const float wr[4], int j)
{
    float v = 0.0f;
    for (int i = 0; i < 4; i++)
        if (wr[i] != 0.0f) v += wr[i] * arr[(ro + i) * BSSRDF_NUM_RADIUS + j];
    return v;
}

/* Inverse CDF of the profile spline in r at albedo rho (pbrt SampleCatmullRom2D): the CDF
 * rows are interpolated over rho like the values, the interval found by bisection of
 * the interpolated CDF, then the Hermite integral inverted inside it. */
float bssrdf_sample_sr(const Bssrdf *b, int c, float u)
{
    const BssrdfTable *t = b->table;
    float st = b->sigma_t.c[c];
    int ro;
    float wr[4];
    if (!(st > 0.0f) || !catmull_rom_weights(t->rho, BSSRDF_NUM_RHO, b->rho.c[c], &ro, wr)) return -1.0f;
#define ROW_AT(arr, j) row_at((arr), ro, wr, (j))
    const int n = BSSRDF_NUM_RADIUS;
    float total = ROW_AT(t->profile_cdf, n - 1);
    if (!(total > 0.0f)) return -1.0f;
    u *= total;
    int lo = 0, hi = n - 2; /* the last j with cdf(j) <= u */
    while (lo < hi) {
        int mid = (lo + hi + 1) / 2;
        if (ROW_AT(t->profile_cdf, mid) <= u) lo = mid; else hi = mid - 1;
    }
    const float *x = t->radius;
    int j = lo;
    float f0 = ROW_AT(t->profile, j), f1 = ROW_AT(t->profile, j + 1);
    float x0 = x[j], x1 = x[j + 1], width = x1 - x0;
    float d0 = j > 0 ? width * (f1 - ROW_AT(t->profile, j - 1)) / (x1 - x[j - 1]) : f1 - f0;
    float d1 = j + 2 < n ? width * (ROW_AT(t->profile, j + 2) - f0) / (x[j + 2] - x0) : f1 - f0;
    float target = (u - ROW_AT(t->profile_cdf, j)) / width;
#undef ROW_AT
    /* a first guess from the linear interpolant's inverse */
    float t0 = f0 != f1 ? (f0 - safe_sqrtf(f0 * f0 + 2.0f * target * (f1 - f0))) / (f0 - f1)
                        : (f0 > 0.0f ? target / f0 : 0.5f);
    float c4[4] = {f0, f1, d0, d1};
    float tt = newton_bisect(eval_integral, c4, target, t0);
    return (x0 + width * tt) / st;
}

bool bssrdf_sample_probe(const Bssrdf *b, float u1, Vec2 u2, Vec3 *p0, Vec3 *p1)
{
    Vec3 ax, ay, az; /* az: the probe's direction; ax, ay: the disc it is offset in */
    if (u1 < 0.25f) {
        az = b->frame.s; ax = b->frame.t; ay = b->frame.n;
        u1 *= 4.0f;
    } else if (u1 < 0.5f) {
        az = b->frame.t; ax = b->frame.n; ay = b->frame.s;
        u1 = (u1 - 0.25f) * 4.0f;
    } else {
        az = b->frame.n; ax = b->frame.s; ay = b->frame.t;
        u1 = (u1 - 0.5f) * 2.0f;
    }
    int c = (int)(u1 * (float)COLOR_LANES);
    if (c > COLOR_LANES - 1) c = COLOR_LANES - 1;
    float r = bssrdf_sample_sr(b, c, u2.x);
    if (r < 0.0f) return false;
    float r_max = bssrdf_sample_sr(b, c, 0.999f);
    if (!(r < r_max)) return false;
    float phi = 2.0f * CST_PI * u2.y, l = 2.0f * sqrtf(r_max * r_max - r * r);
    Vec3 off = v3_add(v3_scale(ax, r * cosf(phi)), v3_scale(ay, r * sinf(phi)));
    *p0 = v3_sub(v3_add(b->po, off), v3_scale(az, 0.5f * l));
    *p1 = v3_add(*p0, v3_scale(az, l));
    return true;
}

float bssrdf_pdf_sp(const Bssrdf *b, Vec3 pi, Vec3 ni)
{
    Vec3 d = frame_to_local(&b->frame, v3_sub(pi, b->po)), n = frame_to_local(&b->frame, ni);
    /* distances from the three axes (s, t, n) and the axis probabilities */
    const float r_proj[3] = {sqrtf(d.y * d.y + d.z * d.z), sqrtf(d.z * d.z + d.x * d.x), sqrtf(d.x * d.x + d.y * d.y)};
    const float n_abs[3] = {fabsf(n.x), fabsf(n.y), fabsf(n.z)};
    static const float axis_prob[3] = {0.25f, 0.25f, 0.5f};
    float pdf = 0.0f;
    for (int a = 0; a < 3; a++)
        for (int c = 0; c < COLOR_LANES; c++) pdf += bssrdf_pdf_sr(b, c, r_proj[a]) * n_abs[a] * axis_prob[a];
    return pdf * (1.0f / (float)COLOR_LANES);
}

float bssrdf_sw(float eta, float cos_i)
{
    if (!(cos_i > 0.0f)) return 0.0f;
    float c = 1.0f - 2.0f * bssrdf_fresnel_moment1(1.0f / eta);
    return (1.0f - fresnel_dielectric(cos_i, eta)) / (c * CST_PI);
}
