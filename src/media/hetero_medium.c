/* Heterogeneous media (hetero_medium.h): density lookups (pbrt-v4's SampledGrid and
 * CloudMedium::Density), the majorant grid, delta tracking with the balance heuristic over
 * colour lanes, ratio tracking. Random numbers past the sampler's two come from a PCG32
 * stream seeded by a hash of the segment and the sampler's number, as pbrt-v4's volpath
 * seeds its RNG from the ray and a sampler value: no state, no allocation per ray. */
#include "media/hetero_medium.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/rng.h"
#include "media/medium.h"
#include "textures/noise.h"

/* pbrt-v4's majorant grid resolution for GridMedium. */
enum { HETERO_MAJ_RES = 16 };

static inline float axis(Vec3 v, int a) { return a == 0 ? v.x : a == 1 ? v.y : v.z; }

static inline float grid_at(const float *v, const int n[3], int x, int y, int z)
{
    if (x < 0 || y < 0 || z < 0 || x >= n[0] || y >= n[1] || z >= n[2]) return 0.0f;
    return v[((size_t)z * (size_t)n[1] + (size_t)y) * (size_t)n[0] + (size_t)x];
}

static inline float lerpf(float t, float a, float b) { return (1.0f - t) * a + t * b; }

float hetero_grid_lookup(const float *v, const int n[3], Vec3 u)
{
    float ps[3] = {u.x * (float)n[0] - 0.5f, u.y * (float)n[1] - 0.5f, u.z * (float)n[2] - 0.5f};
    int i[3];
    float f[3];
    for (int a = 0; a < 3; a++) {
        /* Far outside (or NaN): every sample involved is outside, and the int conversion
         * below must not overflow. */
        if (!(ps[a] > -2.0f && ps[a] < (float)n[a] + 1.0f)) return 0.0f;
        float fl = floorf(ps[a]);
        i[a] = (int)fl;
        f[a] = ps[a] - fl;
    }
    const int x = i[0], y = i[1], z = i[2];
    float d00 = lerpf(f[0], grid_at(v, n, x, y, z), grid_at(v, n, x + 1, y, z));
    float d10 = lerpf(f[0], grid_at(v, n, x, y + 1, z), grid_at(v, n, x + 1, y + 1, z));
    float d01 = lerpf(f[0], grid_at(v, n, x, y, z + 1), grid_at(v, n, x + 1, y, z + 1));
    float d11 = lerpf(f[0], grid_at(v, n, x, y + 1, z + 1), grid_at(v, n, x + 1, y + 1, z + 1));
    return lerpf(f[2], lerpf(f[1], d00, d10), lerpf(f[1], d01, d11));
}

/* pbrt-v4's DNoise: the forward-difference gradient of the noise, step 0.01. */
static Vec3 dnoise(Vec3 p)
{
    const float delta = 0.01f;
    float n = noise3(p);
    return v3((noise3(v3(p.x + delta, p.y, p.z)) - n) / delta, (noise3(v3(p.x, p.y + delta, p.z)) - n) / delta,
              (noise3(v3(p.x, p.y, p.z + delta)) - n) / delta);
}

/* pbrt-v4's CloudMedium::Density: five octaves of noise at a point warped by two octaves
 * of the noise's gradient (wispiness), thinned with height y and filled below y = 0.5;
 * in [0, 1]. */
static float cloud_density(const HeteroMedium *h, Vec3 p)
{
    Vec3 pp = v3_scale(p, h->frequency);
    if (h->wispiness > 0.0f) {
        float vomega = 0.05f * h->wispiness, vlambda = 10.0f;
        for (int i = 0; i < 2; i++) {
            pp = v3_add(pp, v3_scale(dnoise(v3_scale(pp, vlambda)), vomega));
            vomega *= 0.5f;
            vlambda *= 1.99f;
        }
    }
    float d = 0.0f, omega = 0.5f, lambda = 1.0f;
    for (int i = 0; i < 5; i++) {
        d += omega * noise3(v3_scale(pp, lambda));
        omega *= 0.5f;
        lambda *= 1.99f;
    }
    d = fminf(fmaxf((1.0f - p.y) * 4.5f * h->cloud_density * d, 0.0f), 1.0f);
    d += 2.0f * fmaxf(0.0f, 0.5f - p.y);
    return fminf(fmaxf(d, 0.0f), 1.0f);
}

static inline Vec3 box_unit(const HeteroMedium *h, Vec3 p)
{
    return v3((p.x - h->p0.x) / (h->p1.x - h->p0.x), (p.y - h->p0.y) / (h->p1.y - h->p0.y),
              (p.z - h->p0.z) / (h->p1.z - h->p0.z));
}

float hetero_density(const HeteroMedium *h, Vec3 p)
{
    if (h->cloud) return cloud_density(h, p);
    return hetero_grid_lookup(h->density, h->n, box_unit(h, p));
}

static float le_scale_at(const HeteroMedium *h, Vec3 p)
{
    return h->le_scale ? hetero_grid_lookup(h->le_scale, h->n, box_unit(h, p)) : h->le_scale_1;
}

/* The largest sample that the trilinear lookup blends anywhere in [lo, hi] (unit cube):
 * pbrt-v4's SampledGrid::MaxValue. Interpolation never exceeds its samples, so this bounds
 * the density over the cell. */
static float grid_max(const float *v, const int n[3], Vec3 lo, Vec3 hi)
{
    int i0[3], i1[3];
    for (int a = 0; a < 3; a++) {
        int l = (int)floorf(axis(lo, a) * (float)n[a] - 0.5f);
        int h = (int)floorf(axis(hi, a) * (float)n[a] - 0.5f) + 1;
        i0[a] = l < 0 ? 0 : l;
        i1[a] = h > n[a] - 1 ? n[a] - 1 : h;
    }
    float m = 0.0f;
    for (int z = i0[2]; z <= i1[2]; z++)
        for (int y = i0[1]; y <= i1[1]; y++)
            for (int x = i0[0]; x <= i1[0]; x++) m = fmaxf(m, grid_at(v, n, x, y, z));
    return m;
}

bool hetero_medium_prepare(HeteroMedium *h)
{
    const int r = h->cloud ? 1 : HETERO_MAJ_RES;
    free(h->maj.max);
    h->maj.max = malloc((size_t)r * (size_t)r * (size_t)r * sizeof(float));
    if (!h->maj.max) return false;
    h->maj.res[0] = h->maj.res[1] = h->maj.res[2] = r;
    if (h->cloud) {
        h->maj.max[0] = 1.0f;
        return true;
    }
    const float inv = 1.0f / (float)r;
    for (int z = 0; z < r; z++)
        for (int y = 0; y < r; y++)
            for (int x = 0; x < r; x++) {
                Vec3 lo = v3((float)x * inv, (float)y * inv, (float)z * inv);
                Vec3 hi = v3((float)(x + 1) * inv, (float)(y + 1) * inv, (float)(z + 1) * inv);
                h->maj.max[(z * r + y) * r + x] = grid_max(h->density, h->n, lo, hi);
            }
    return true;
}

void hetero_medium_release(HeteroMedium *h)
{
    free(h->density);
    free(h->le_scale);
    free(h->maj.max);
    h->density = h->le_scale = h->maj.max = NULL;
}

/* ------------------------------------------------------------------ tracking */

static uint64_t hash_floats(const float *f, int n, uint64_t h)
{
    for (int i = 0; i < n; i++) {
        uint32_t b;
        memcpy(&b, &f[i], sizeof b);
        h = mix64(h ^ (b + 0x9e3779b97f4a7c15ULL + (h << 6) + (h >> 2)));
    }
    return h;
}

/* The segment in the grid's unit cube: false when the ray misses the medium's box. */
static bool to_grid(const HeteroMedium *h, Vec3 o, Vec3 d, float t_max, Vec3 *om, Vec3 *dm, Vec3 *og, Vec3 *dg,
                    float *ta, float *tb)
{
    *om = transform_point(&h->medium_from_world, o);
    *dm = transform_vector(&h->medium_from_world, d);
    if (!majorant_clip(*om, *dm, h->p0, h->p1, 0.0f, t_max, ta, tb)) return false;
    Vec3 ext = v3_sub(h->p1, h->p0);
    *og = v3((om->x - h->p0.x) / ext.x, (om->y - h->p0.y) / ext.y, (om->z - h->p0.z) / ext.z);
    *dg = v3(dm->x / ext.x, dm->y / ext.y, dm->z / ext.z);
    return true;
}

/* ln A_c per lane, A_c = sigma_t[c]^n exp(-sigma_t[c] tau): the part of the density of a
 * collision sequence (n tentative collisions in the optical depth tau of the majorant's
 * density bound) that depends on the lane; the rest is common to all lanes (the majorant
 * bounds and the real/null choices) and cancels in the balance heuristic. */
static void lane_logs(const Color *sigma_t, const double log_st[COLOR_LANES], int n, double tau,
                      double la[COLOR_LANES])
{
    for (int c = 0; c < COLOR_LANES; c++) /* log(0) = -inf: A_c = 0 after a collision */
        la[c] = (n > 0 ? (double)n * log_st[c] : 0.0) - (double)sigma_t->c[c] * tau;
}

/* One sigma_t factor more: ln(sigma_t[c] A_c), the lane's density of a tentative collision. */
static void add_log_sigma(const double log_st[COLOR_LANES], const double la[COLOR_LANES], double lb[COLOR_LANES])
{
    for (int c = 0; c < COLOR_LANES; c++) lb[c] = la[c] + log_st[c];
}

/* exp(a - b) for lane ratios, its exponent capped at 80 (e^80 < FLT_MAX) so that a hero
 * lane far less likely than another gives large but finite factors, never inf / inf. */
static inline float exp_ratio(double a, double b)
{
    double x = a - b;
    return x > -HUGE_VAL ? (float)exp(x < 80.0 ? x : 80.0) : 0.0f;
}

/* 1 / mean_c(r_path[c] r_seg[c]): the balance heuristic's normalisation over the lanes
 * for the path so far (r_path) and the segment's part (r_seg), both relative to the hero. */
static inline float mis_norm(Color r_path, Color r_seg)
{
    float m = 0.0f;
    for (int c = 0; c < COLOR_LANES; c++) m += r_path.c[c] * r_seg.c[c];
    return m > 0.0f ? (float)COLOR_LANES / m : 0.0f;
}

void hetero_sample_distance(const HeteroMedium *h, const MediumCoeffs *mc, Vec3 o, Vec3 d, float t_max, int hero,
                            Color r_path, float u, MediumSample *out)
{
    out->t = t_max;
    out->scattered = false;
    out->weight = color_s(1.0f);
    out->r = color_s(1.0f);
    out->tr_pdf = color_s(0.0f);
    out->le = color_s(0.0f);
    Vec3 om, dm, og, dg;
    float ta, tb;
    /* Missing the box: no collision in any lane, f = p = 1. */
    if (!to_grid(h, o, d, t_max, &om, &dm, &og, &dg, &ta, &tb)) return;
    const float sig_h = mc->sigma_t.c[hero];
    const float seed_in[7] = {u, o.x, o.y, o.z, d.x, d.y, d.z};
    Pcg32 rng;
    pcg32_seed(&rng, hash_floats(seed_in, 7, 0x6a09e667f3bcc909ULL), 0x3c6ef372fe94f82bULL);

    MajorantDda it;
    majorant_dda_init(&it, &h->maj, og, dg, ta, tb);
    int n = 0;        /* null collisions so far */
    double tau = 0.0; /* integral of the density bound over the walk so far */
    float e = -log1pf(-u); /* the unit-rate exponential budget left to the next collision */
    double la[COLOR_LANES], lb[COLOR_LANES], log_st[COLOR_LANES];
    for (int c = 0; c < COLOR_LANES; c++) log_st[c] = log((double)mc->sigma_t.c[c]);
    MajorantSeg seg;
    while (majorant_dda_next(&it, &seg)) {
        if (!(seg.maj > 0.0f)) continue;
        const float rate = sig_h * seg.maj; /* the hero lane's majorant, per unit length */
        float t = seg.t0;
        for (;;) {
            float step = rate > 0.0f ? e / rate : INFINITY;
            if (!(t + step < seg.t1)) { /* no collision left in this cell */
                float len = seg.t1 - t;
                e = fmaxf(e - rate * len, 0.0f);
                tau += (double)seg.maj * (double)len;
                break;
            }
            t += step;
            tau += (double)seg.maj * (double)step;
            Vec3 pm = v3_add(om, v3_scale(dm, t));
            const float dens = hetero_density(h, pm);
            lane_logs(&mc->sigma_t, log_st, n, tau, la);
            add_log_sigma(log_st, la, lb);
            /* Lane c's density of the collisions so far relative to the hero's: sigma_t[c]
             * A_c / (sigma_t[h] A_h). */
            Color r_seg;
            for (int c = 0; c < COLOR_LANES; c++) r_seg.c[c] = exp_ratio(lb[c], lb[hero]);
            if (mc->emissive && dens > 0.0f) {
                /* Emission at a tentative collision: sigma_a(x) Le(x) / majorant per lane,
                 * f / p_hero = A_c sigma_a Le dens / (sigma_t[h] A_h M), divided by the
                 * lanes' mean density ratio over the whole path (pbrt-v4's volpath adds
                 * beta sigma_a Le / sigma_maj with r_u the same way). */
                float k = dens * le_scale_at(h, pm) / seg.maj;
                if (k > 0.0f) {
                    Color x = color_scale(color_mul(mc->sigma_a, mc->le), k * mis_norm(r_path, r_seg));
                    for (int c = 0; c < COLOR_LANES; c++) x.c[c] *= exp_ratio(la[c], lb[hero]);
                    out->le = color_add(out->le, x);
                }
            }
            /* Real with probability density / bound, the same in every lane. */
            if (pcg32_float(&rng) * seg.maj < dens) {
                out->t = t;
                out->scattered = true;
                /* f_c / p_hero = sigma_s[c] A_c / (sigma_t[h] A_h): the albedo in the hero
                 * lane. */
                for (int c = 0; c < COLOR_LANES; c++)
                    out->weight.c[c] = mc->sigma_s.c[c] > 0.0f ? mc->sigma_s.c[c] * exp_ratio(la[c], lb[hero]) : 0.0f;
                out->r = r_seg;
                return;
            }
            n++;
            e = -log1pf(-pcg32_float(&rng));
        }
    }
    /* Passed: f_c = p_c = A_c times the common factors, so f / p_hero = r. */
    lane_logs(&mc->sigma_t, log_st, n, tau, la);
    for (int c = 0; c < COLOR_LANES; c++) out->weight.c[c] = out->r.c[c] = exp_ratio(la[c], la[hero]);
}

Color hetero_transmittance(const HeteroMedium *h, const MediumCoeffs *mc, Vec3 o, Vec3 d, float t_max, uint64_t seed)
{
    Color tr = color_s(1.0f);
    Vec3 om, dm, og, dg;
    float ta, tb;
    if (!to_grid(h, o, d, t_max, &om, &dm, &og, &dg, &ta, &tb)) return tr;
    const float smax = color_max(mc->sigma_t);
    if (!(smax > 0.0f)) return tr;
    Color ratio; /* sigma_t[c] / smax: each lane's share of the common majorant */
    for (int c = 0; c < COLOR_LANES; c++) ratio.c[c] = mc->sigma_t.c[c] / smax;
    Pcg32 rng;
    pcg32_seed(&rng, seed, 0xa54ff53a5f1d36f1ULL);
    MajorantDda it;
    majorant_dda_init(&it, &h->maj, og, dg, ta, tb);
    MajorantSeg seg;
    while (majorant_dda_next(&it, &seg)) {
        if (!(seg.maj > 0.0f)) continue;
        const float rate = smax * seg.maj;
        /* Exponential steps restart at each cell: the process is memoryless. */
        for (float t = seg.t0;;) {
            t += -log1pf(-pcg32_float(&rng)) / rate;
            if (!(t < seg.t1)) break;
            const float f = hetero_density(h, v3_add(om, v3_scale(dm, t))) / seg.maj;
            for (int c = 0; c < COLOR_LANES; c++) tr.c[c] *= fmaxf(0.0f, 1.0f - ratio.c[c] * f);
            /* Russian roulette on a faint estimate (pbrt-v4: below 0.05, survive 1/4). */
            if (color_max(tr) < 0.05f) {
                if (pcg32_float(&rng) < 0.75f) return color_s(0.0f);
                tr = color_scale(tr, 4.0f);
            }
        }
    }
    return tr;
}

float hetero_density_world(const HeteroMedium *h, Vec3 p_world)
{
    return hetero_density(h, transform_point(&h->medium_from_world, p_world));
}

float hetero_emission_world(const HeteroMedium *h, Vec3 p_world)
{
    const Vec3 p = transform_point(&h->medium_from_world, p_world);
    return hetero_density(h, p) * le_scale_at(h, p);
}

float hetero_majorant_depth(const HeteroMedium *h, Vec3 o, Vec3 d, float t_max)
{
    Vec3 om, dm, og, dg;
    float ta, tb;
    if (!to_grid(h, o, d, t_max, &om, &dm, &og, &dg, &ta, &tb)) return 0.0f;
    MajorantDda it;
    majorant_dda_init(&it, &h->maj, og, dg, ta, tb);
    MajorantSeg seg;
    double tau = 0.0;
    while (majorant_dda_next(&it, &seg)) tau += (double)seg.maj * (double)(seg.t1 - seg.t0);
    return (float)tau;
}

/* ------------------------------------------------------------------ validation, copies */

static bool finite_nonneg(Color c)
{
    for (int i = 0; i < COLOR_LANES; i++)
        if (!(c.c[i] >= 0.0f && c.c[i] <= FLT_MAX)) return false;
    return true;
}

const char *hetero_medium_invalid(const HeteroMedium *h)
{
    if (!finite_nonneg(h->sigma_a) || !finite_nonneg(h->sigma_s) || !finite_nonneg(h->le))
        return "sigma_a, sigma_s and Le must be finite and >= 0";
    if (!transform_is_affine(&h->medium_from_world)) return "the medium's transform must be affine and finite";
    const float b[6] = {h->p0.x, h->p0.y, h->p0.z, h->p1.x, h->p1.y, h->p1.z};
    for (int i = 0; i < 6; i++)
        if (!isfinite(b[i])) return "p0 and p1 must be finite";
    if (!(h->p0.x < h->p1.x && h->p0.y < h->p1.y && h->p0.z < h->p1.z))
        return "the box p0 .. p1 must have p0 < p1 on every axis";
    if (h->cloud) {
        if (!(isfinite(h->cloud_density) && isfinite(h->wispiness) && isfinite(h->frequency)))
            return "density, wispiness and frequency must be finite";
        return NULL;
    }
    if (!(h->le_scale_1 >= 0.0f && h->le_scale_1 <= FLT_MAX)) return "Lescale must be finite and >= 0";
    for (int a = 0; a < 3; a++)
        if (h->n[a] < 1 || h->n[a] > 4096) return "nx, ny and nz must be in 1 .. 4096";
    size_t count = (size_t)h->n[0] * (size_t)h->n[1] * (size_t)h->n[2];
    if (count > ((size_t)1 << 28)) return "the grid has more than 2^28 samples";
    if (!h->density) return "no density grid";
    for (size_t i = 0; i < count; i++)
        if (!(h->density[i] >= 0.0f && h->density[i] <= FLT_MAX)) return "a density is negative or not finite";
    if (h->le_scale)
        for (size_t i = 0; i < count; i++)
            if (!(h->le_scale[i] >= 0.0f && h->le_scale[i] <= FLT_MAX))
                return "an Lescale value is negative or not finite";
    return NULL;
}

bool hetero_medium_clone(HeteroMedium *dst, const HeteroMedium *src)
{
    *dst = *src;
    dst->density = dst->le_scale = dst->maj.max = NULL;
    if (!src->cloud) {
        size_t bytes = (size_t)src->n[0] * (size_t)src->n[1] * (size_t)src->n[2] * sizeof(float);
        if (!(dst->density = malloc(bytes))) goto fail;
        memcpy(dst->density, src->density, bytes);
        if (src->le_scale) {
            if (!(dst->le_scale = malloc(bytes))) goto fail;
            memcpy(dst->le_scale, src->le_scale, bytes);
        }
    }
    if (!hetero_medium_prepare(dst)) goto fail;
    return true;
fail:
    hetero_medium_release(dst);
    return false;
}
