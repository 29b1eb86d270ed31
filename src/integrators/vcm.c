/* Vertex connection and merging (Georgiev et al., "Light Transport Simulation with Vertex
 * Connection and Merging", SIGGRAPH Asia 2012): BDPT's subpaths (subpath.c) plus merging,
 * the photon-mapping strategy, through a hashed grid over each iteration's light vertices
 * whose radius shrinks with the iterations; "tech. rep." is Georgiev's "Implementing
 * Vertex Connection and Merging" (2012). */
#include "integrators/vcm.h"

#include <math.h>
#include <string.h>

#include "integrators/recorder.h"

float vcm_default_radius(const Scene *s)
{
    /* SmallVCM's default: 0.003 times the radius of the scene's bounding sphere. */
    BBox b = s->accel.bounds;
    Vec3 ext = v3_sub(b.max, b.min);
    float r = 0.5f * v3_length(ext);
    return isfinite(r) && r > 0.0f ? 0.003f * r : 1e-3f;
}

void vcm_iteration_init(SubpathIteration *it, const SubpathParams *vp, const Camera *cam, int light_paths,
                        float base_radius, int index)
{
    memset(it, 0, sizeof *it);
    it->light_paths = light_paths;
    const float alpha = 0.75f;
    it->radius = base_radius * powf((float)index + 1.0f, 0.5f * (alpha - 1.0f));
    float eta = CST_PI * it->radius * it->radius * (float)light_paths; /* tech. rep. eq. 12 */
    it->mis_vm = vp->merge ? mis(eta) : 0.0f;
    it->mis_vc = vp->merge ? mis(1.0f / eta) : 0.0f;
    it->vm_norm = 1.0f / eta;
    /* Media: the ball's volume for the disk's area (UPBP's P-P3D estimator). */
    float eta_vol = (4.0f / 3.0f) * CST_PI * it->radius * it->radius * it->radius * (float)light_paths;
    it->mis_vm_vol = vp->merge ? mis(eta_vol) : 0.0f;
    it->mis_vc_vol = vp->merge ? mis(1.0f / eta_vol) : 0.0f;
    it->vm_norm_vol = 1.0f / eta_vol;
    float film_area = 4.0f * cam->tan_half_vfov * cam->tan_half_vfov * cam->aspect;
    it->pixel_area = film_area / ((float)cam->width * (float)cam->height);
}


/* A hashed grid cell index of integer cell coordinates (Teschner et al. 2003 primes). */
static inline uint32_t cell_hash(const SubpathIteration *it, int x, int y, int z)
{
    uint32_t h = ((uint32_t)x * 73856093u) ^ ((uint32_t)y * 19349663u) ^ ((uint32_t)z * 83492791u);
    return h % it->cells;
}

static inline int cell_coord(float p, float lo, float inv_cell)
{
    return (int)floorf((p - lo) * inv_cell);
}

void vcm_grid_init(SubpathIteration *it, Vec3 lo, uint32_t cells, uint32_t *cell_start, MergeVertex *cell_vertices)
{
    it->cells = cells;
    it->cell_start = cell_start;
    it->cell_vertices = cell_vertices;
    it->grid_lo = lo;
    it->inv_cell = 1.0f / (2.0f * it->radius);
    cell_start[0] = 0;
}

uint32_t vcm_grid_cell(const SubpathIteration *it, Vec3 p)
{
    const Vec3 lo = it->grid_lo;
    return cell_hash(it, cell_coord(p.x, lo.x, it->inv_cell), cell_coord(p.y, lo.y, it->inv_cell),
                     cell_coord(p.z, lo.z, it->inv_cell));
}

/* The sort is a counting sort by bucket, stable in vertex order: the order in which merges
 * are summed is then a function of the iteration alone. Range r of n owns the buckets
 * [c0, c1) below and cell_start[c0 + 1 .. c1] (the ends of its buckets; entry 0 is
 * vcm_grid_init's), so ranges never write each other's entries. */
static void range_buckets(const SubpathIteration *it, int range, int ranges, uint32_t *c0, uint32_t *c1)
{
    *c0 = (uint32_t)((uint64_t)it->cells * (uint64_t)range / (uint64_t)ranges);
    *c1 = (uint32_t)((uint64_t)it->cells * (uint64_t)(range + 1) / (uint64_t)ranges);
}

uint32_t vcm_grid_count(const SubpathIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges,
                        uint32_t *cell_start)
{
    uint32_t c0, c1;
    range_buckets(it, range, ranges, &c0, &c1);
    memset(cell_start + c0 + 1, 0, (size_t)(c1 - c0) * sizeof *cell_start);
    const uint32_t width = c1 - c0;
    for (size_t i = 0; i < n; i++)
        if (cell_of[i] - c0 < width) cell_start[cell_of[i] + 1]++;
    uint32_t sum = 0;
    for (uint32_t c = c0 + 1; c <= c1; c++) sum = cell_start[c] += sum;
    return sum;
}

uint32_t vcm_grid_bases(uint32_t *per_range, int ranges)
{
    uint32_t below = 0;
    for (int r = 0; r < ranges; r++) {
        uint32_t n = per_range[r];
        per_range[r] = below;
        below += n;
    }
    return below;
}

void vcm_grid_fill(const SubpathIteration *it, const uint32_t *cell_of, size_t n, int range, int ranges, uint32_t base,
                   uint32_t *cell_start, MergeVertex *cell_vertices)
{
    uint32_t c0, c1;
    range_buckets(it, range, ranges, &c0, &c1);
    /* cell_start[c + 1] becomes bucket c's fill cursor (its global start), and ends as its
     * end, the final value: no pass restores anything. */
    for (uint32_t c = c1; c > c0 + 1; c--) cell_start[c] = base + cell_start[c - 1];
    if (c1 > c0) cell_start[c0 + 1] = base;
    const uint32_t width = c1 - c0;
    for (size_t i = 0; i < n; i++) {
        uint32_t c = cell_of[i];
        if (c - c0 >= width) continue;
        const SubpathVertex *v = &it->vertices[i];
        cell_vertices[cell_start[c + 1]++] = (MergeVertex){
            .p = v->p, .w_prev = v->w_prev, .beta = v->beta, .d_vcm = v->d_vcm, .d_vm = v->d_vm, .bounces = v->bounces,
            .dispersed = v->dispersed | (v->ng.x == 0.0f && v->ng.y == 0.0f && v->ng.z == 0.0f ? MERGE_VOLUME : 0)};
    }
}


/* Step 1: the buckets of the cells the ball of radius r around p overlaps. At most 2 x 2
 * x 2 cells (cells are 2r wide); distinct cells can hash to the same bucket, which must
 * be visited once. Their bounds are prefetched together: the lookups are independent
 * cache misses, and issuing them at once overlaps their latency (docs/benchmarks.md). */
static void merge_plan(const SubpathIteration *it, Vec3 p, MergeQuery *q)
{
    const float r = it->radius;
    int lo[3], hi[3];
    const float pc[3] = {p.x, p.y, p.z}, gl[3] = {it->grid_lo.x, it->grid_lo.y, it->grid_lo.z};
    for (int a = 0; a < 3; a++) {
        lo[a] = cell_coord(pc[a] - r, gl[a], it->inv_cell);
        hi[a] = cell_coord(pc[a] + r, gl[a], it->inv_cell);
    }
    q->nb = 0;
    /* One bit per bucket's low six bits: a bucket whose bit is clear is certainly new,
     * and only the rare others are compared with the list. */
    uint64_t seen = 0;
    for (int cz = lo[2]; cz <= hi[2]; cz++)
        for (int cy = lo[1]; cy <= hi[1]; cy++)
            for (int cx = lo[0]; cx <= hi[0]; cx++) {
                uint32_t c = cell_hash(it, cx, cy, cz);
                const uint64_t bit = (uint64_t)1 << (c & 63u);
                if (seen & bit) {
                    bool dup = false;
                    for (int k = 0; k < q->nb; k++) dup |= q->bucket[k] == c;
                    if (dup) continue;
                }
                if (q->nb == 8) continue;
                seen |= bit;
                q->bucket[q->nb++] = c;
                __builtin_prefetch(&it->cell_start[c]);
            }
}

/* Step 2: where each bucket's run lies, and the run prefetched (up to eight lines; a run
 * is a few vertices). */
static void merge_fetch(const SubpathIteration *it, MergeQuery *q)
{
    for (int b = 0; b < q->nb; b++) {
        q->first[b] = it->cell_start[q->bucket[b]];
        q->last[b] = it->cell_start[q->bucket[b] + 1];
    }
    for (int b = 0; b < q->nb; b++) {
        if (q->first[b] == q->last[b]) continue;
        const char *p = (const char *)&it->cell_vertices[q->first[b]];
        const char *end = (const char *)&it->cell_vertices[q->last[b]];
        /* Most runs are one or two vertices: their first and last lines; longer runs
         * also the lines between, up to eight in all. */
        __builtin_prefetch(p);
        __builtin_prefetch(end - 1);
        for (int line = 2; line < 8 && end - p > 128; line++) __builtin_prefetch(p += 64);
    }
}

/* Step 3, merging at camera vertex x: the density estimate over every light vertex within
 * the radius, each MIS-weighted (tech. rep. eqs. 42-43), scaled by 1 / (pi r^2 N). */
static Color merge(const SubpathParams *vp, const SubpathIteration *it, const MergeQuery *q, const SubPath *sp,
                 const Bsdf *bx, const SurfaceHit *x, Vec3 wo, int bounces, Color *hero)
{
    const float r = it->radius, r2 = r * r;
    Color acc = color_s(0.0f), acc_hero = color_s(0.0f);
    for (int b = 0; b < q->nb; b++)
        for (uint32_t k = q->first[b]; k < q->last[b]; k++) {
            const MergeVertex *y = &it->cell_vertices[k];
            Vec3 dv = v3_sub(y->p, x->p);
            if (v3_dot(dv, dv) > r2) continue;
            /* The merged path has the camera vertices and y's, sharing one. */
            if (vp->max_depth > 0 && bounces + y->bounces - 1 > vp->max_depth) continue;
            float cos_w = fabsf(v3_dot(x->ng, y->w_prev));
            if (!(cos_w > 0.0f)) continue;
            /* A photon from the far side of a thin wall gets f = 0 here. */
            float x_fwd, x_rev;
            Color f = bsdf_eval_pdfs(bx, wo, y->w_prev, &x_fwd, &x_rev);
            if (color_is_black(f)) continue;
            f = color_scale(f, 1.0f / cos_w); /* merging wants f without the cosine */
            float w_light = y->d_vcm * it->mis_vc + y->d_vm * mis(x_fwd);
            float w_camera = sp->d_vcm * it->mis_vc + sp->d_vm * mis(x_rev);
            float weight = 1.0f / (w_light + 1.0f + w_camera);
            if (y->dispersed) acc_hero = color_add(acc_hero, color_scale(color_mul(f, y->beta), weight));
            else acc = color_add(acc, color_scale(color_mul(f, y->beta), weight));
            if (it->rec) recorder_merge(it->rec, y->p, y->bounces, sp->beta, color_scale(color_mul(f, y->beta), weight),
                                        it->vm_norm, weight, w_light, w_camera, y->dispersed);
        }
    *hero = color_scale(acc_hero, it->vm_norm);
    return color_scale(acc, it->vm_norm);
}


static const SubpathMerge VCM_MERGE = {merge_plan, merge_fetch, merge};

Color vcm_trace_camera(const Scene *s, const Camera *cam, const SubpathParams *vp, const SubpathIteration *it, int path,
                       Ray ray, Sampler *rng, const Wavelengths *wl, uint64_t *rays)
{
    return subpath_trace_camera(s, cam, vp, it, path, ray, rng, wl, rays, &VCM_MERGE);
}
