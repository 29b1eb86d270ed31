/* BDPT's and VCM's MIS weights from whole paths (bdpt_mis.h): Veach's thesis sec. 10.2, the
 * density p_s of a path sampled with s light vertices is the product of the light subpath's
 * area densities of x_0 .. x_{s-1} and the camera subpath's of x_s .. x_k; VCM's merge at
 * x_i samples x_i by both subpaths, so its density is eta_VCM p_L(x_0..x_i) p_C(x_i..x_k)
 * (Georgiev et al. 2012 eqs. 11-13: the connection's density times the acceptance pi r^2
 * p_L(x_i), counted N_light times); w = p^2 / sum_j p_j^2 (eq. 9.13). Computed in double,
 * vertex by vertex, independently of the recursive quantities (dVCM, dVC, dVM) of Georgiev's
 * technical report that subpath.c and vcm.c use. */
#include "integrators/bdpt_mis.h"

#include <math.h>

#include "media/phase.h"

/* |cos| at a vertex of normal n toward unit d. */
static double cosabs(Vec3 n, Vec3 d) { return fabs((double)v3_dot(n, d)); }

/* Whether x_i is a medium vertex (no cosine, a phase function). */
static bool is_vol(const BdptMisPath *x, int i) { return x->media && i >= 1 && i < x->k && x->medium[i] >= 0; }

/* The density per unit solid angle of scattering toward wi from wo at x_i (both pointing
 * away from x_i): its BSDF's, or in a medium Henyey-Greenstein's (symmetric). */
static double dir_pdf(const Scene *s, const BdptMisPath *x, const Bsdf *b, int i, Vec3 wo, Vec3 wi)
{
    if (is_vol(x, i)) return (double)phase_hg_eval(wo, wi, s->media[x->medium[i]].g);
    return (double)bsdf_pdf(b, wo, wi);
}

bool bdpt_mis_weight(const Scene *s, const Camera *cam, const SubpathIteration *it, const BdptMisPath *x,
                     int strategy, bool merge, double *weight, double *sum, int *strategies)
{
    const int k = x->k;
    *weight = 0.0;
    *sum = 0.0;
    *strategies = 0;
    if (k < 1 || k >= BDPT_MIS_MAX || x->emitter < 0 || x->emitter >= s->emitter_sampler.count) return false;
    Vec3 p[BDPT_MIS_MAX + 1], n[BDPT_MIS_MAX + 1];
    p[0] = x->p0;
    n[0] = x->n0;
    for (int i = 1; i < k; i++) {
        p[i] = x->hit[i]->p;
        n[i] = x->hit[i]->ng;
    }
    p[k] = x->lens;
    n[k] = cam->forward;
    /* nl[i]: the normal the light subpath arrived at x_i with (y's at a merged vertex). */
    Vec3 nl[BDPT_MIS_MAX + 1];
    for (int i = 0; i <= k; i++) nl[i] = n[i];
    if (x->merged > 0 && x->merged < k) nl[x->merged] = x->n_light;
    /* d[i]: unit x_i -> x_{i+1}; d2[i]: its squared length. */
    Vec3 d[BDPT_MIS_MAX];
    double d2[BDPT_MIS_MAX];
    for (int i = 0; i < k; i++) {
        Vec3 e = v3_sub(p[i + 1], p[i]);
        d2[i] = x->len[i] > 0.0f ? (double)x->len[i] * (double)x->len[i] : (double)v3_length2(e);
        if (!(d2[i] > 0.0)) return false;
        d[i] = x->len[i] > 0.0f ? x->dir[i] : v3_scale(e, 1.0f / sqrtf(v3_length2(e)));
    }
    Bsdf b[BDPT_MIS_MAX];
    for (int i = 1; i < k; i++)
        if (!is_vol(x, i)) scene_bsdf(s, x->hit[i], NULL, &b[i]);
    /* Through media: the cosine at x_i (1 at a medium vertex) and the distance sampling of
     * segment i either way (UPBP: a vertex's density includes the free flight that made it). */
    double cl[BDPT_MIS_MAX + 1], cc[BDPT_MIS_MAX + 1], cf[BDPT_MIS_MAX], cr[BDPT_MIS_MAX];
    for (int i = 0; i < k; i++) {
        cf[i] = x->media ? (double)x->chain_fwd[i] : 1.0;
        cr[i] = x->media ? (double)x->chain_rev[i] : 1.0;
    }
    /* pl[i]: the light subpath's density of x_i per unit area; pc[i]: the camera
     * subpath's. A delta lobe's density is a Dirac that every strategy sampling the
     * vertex shares (tech. rep. eqs. 53-55): 1 here, the cosine and distance kept. */
    double pl[BDPT_MIS_MAX], pc[BDPT_MIS_MAX];
    const Emitter *em = &s->emitter_sampler.light[x->emitter].u.area;
    pl[0] = (double)emitter_pdf_a(&s->emitter_sampler, x->emitter);
    for (int i = 1; i < k; i++) {
        double pw = i == 1 ? (double)emitter_emission_pdf_w(em, n[0], d[0])
                  : x->delta[i - 1] ? 1.0
                  : dir_pdf(s, x, &b[i - 1], i - 1, v3_neg(d[i - 2]), d[i - 1]);
        cl[i] = is_vol(x, i) ? 1.0 : cosabs(nl[i], d[i - 1]);
        pl[i] = pw * cl[i] * cf[i - 1] / d2[i - 1];
    }
    /* The camera's density of a direction at angle theta to its axis, per pixel sample:
     * 1 / (pixel area cos^3 theta) (subpath.c's camera_pdf_w). */
    double cos_theta = -(double)v3_dot(d[k - 1], cam->forward);
    if (!(cos_theta > 0.0)) return false;
    double cam_w = 1.0 / ((double)it->pixel_area * cos_theta * cos_theta * cos_theta);
    for (int i = 0; i < k; i++) cc[i] = is_vol(x, i) ? 1.0 : cosabs(n[i], d[i]);
    pc[k - 1] = cam_w * cc[k - 1] * cr[k - 1] / d2[k - 1];
    for (int i = k - 2; i >= 0; i--) {
        double pw = x->delta[i + 1] ? 1.0 : dir_pdf(s, x, &b[i + 1], i + 1, d[i + 1], v3_neg(d[i]));
        pc[i] = pw * cc[i] * cr[i] / d2[i];
    }
    const bool ortho = camera_is_orthographic(cam);
    /* ps[j]: connection strategy s = j; ps[k + 1 + i]: merging at x_i (0 when none). */
    double ps[2 * BDPT_MIS_MAX + 1];
    for (int j = 0; j <= k; j++) {
        /* Which strategies exist: the connection's two ends must not be delta vertices;
         * s = 0 needs the emitter hit; t = 1 a camera that can be connected to, and a
         * light vertex off the emitter (light points are not splatted); t = 0 none. */
        bool valid = j < k + 1;
        if (j >= 1) {
            bool a = j - 1 == 0 ? false : x->delta[j - 1];
            bool c = j == k ? ortho : x->delta[j];
            valid = !a && !c && !(j == k && j == 1);
        }
        double pr = 0.0;
        if (valid) {
            pr = 1.0;
            for (int i = 0; i < j; i++) pr *= pl[i];
            for (int i = j; i < k; i++) pr *= pc[i];
            if (j == k) pr *= (double)it->light_paths; /* N light paths per pixel sample */
            (*strategies)++;
        }
        ps[j] = pr;
    }
    /* Merges: at a non-delta vertex off the emitter and the lens (light vertices are stored
     * from the first bounce on, camera vertices merge from the first hit on). */
    for (int i = 0; i <= k; i++) {
        double pr = 0.0;
        if (x->eta > 0.0 && i >= 1 && i < k && !x->delta[i]) {
            pr = is_vol(x, i) ? x->eta_vol : x->eta;
            for (int j = 0; j <= i; j++) pr *= pl[j];
            for (int j = i; j < k; j++) pr *= pc[j];
            (*strategies)++;
        }
        ps[k + 1 + i] = pr;
    }
    const int m = 2 * k + 2, own = merge ? k + 1 + strategy : strategy;
    if (strategy < 0 || strategy > k || !(ps[own] > 0.0)) return false;
    /* Weights relative to the strategy's density, so that no square overflows. */
    double total = 0.0;
    for (int j = 0; j < m; j++) {
        double r = ps[j] / ps[own];
        total += r * r;
    }
    *weight = 1.0 / total;
    for (int j = 0; j < m; j++) {
        double r = ps[j] / ps[own];
        *sum += r * r / total;
    }
    return true;
}
