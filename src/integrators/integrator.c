/* The integrator interface (integrator.h): every integrator's state behind one tagged
 * union, the work items render.c runs for them (camera tiles, light-path chunks, the
 * splat merge, BDPT/VCM's vertex gather and merging grid, SPPM's phases), the order of
 * those steps within a pass, and the public name table.
 * Determinism: each camera sample draws from its own Sampler started from (seed, pixel,
 * sample index), and each pixel is accumulated by one thread in sample order. Light
 * tracing splats anywhere on the film instead; it runs in iterations of width x height
 * light paths, path i of iteration s seeded by (seed, i, s), cut into fixed chunks whose
 * splat lists are added in chunk order once the iteration is done. BDPT and VCM run the
 * same iterations: light-path chunks (vertex lists and camera splats per chunk,
 * concatenated in chunk order), then one camera path per pixel, each pixel written by one
 * thread. SPPM's phases keep photon order (sppm.c). So images are bit-identical for any
 * thread count. */
#include "integrators/integrator.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "core/memory.h"
#include "integrators/media_lights.h"
#include "integrators/sss_walk.h"
#include "math/motion.h"
#include "materials/bsdf.h"

/* Light paths per work item: small enough to balance threads on small films, large
 * enough that an item's splat list amortises its bookkeeping. Fixed, because chunk
 * boundaries decide the order in which splats are added. */
enum { LIGHT_CHUNK = 1024 };
/* Entries per light path a chunk's vertex and splat lists first make room for (light_chunk);
 * a guess of the order of a path's stores in an enclosed diffuse scene (lists still grow
 * past it, and a smaller need costs only untouched address space). */
enum { LIGHT_RESERVE = 4 };

/* ------------------------------------------------------------------ camera tiles */

/* The AOVs of one camera sample (film.h): its first hit, traced again here so that no
 * integrator has to report it. */
static void camera_aov(Integrator *it, const Camera *cam, IntegratorWorker *w, int pixel, Ray ray)
{
    SurfaceHit sh;
    ++w->rays;
    if (!scene_intersect(it->scene, &ray, &sh)) return;
    Bsdf bsdf;
    scene_bsdf(it->scene, &sh, NULL, &bsdf);
    Vec3 n = v3_dot(sh.ng, ray.d) > 0.0f ? v3_neg(sh.ng) : sh.ng;
    float z = v3_dot(v3_sub(sh.p, cam->origin), cam->forward);
    double *a = &it->film->aov[FILM_AOV_STRIDE * (size_t)pixel];
    const Color albedo = bsdf_albedo(&bsdf);
    a[0] += (double)color_channel(albedo, 0);
    a[1] += (double)color_channel(albedo, 1);
    a[2] += (double)color_channel(albedo, 2);
    a[3] += (double)n.x; a[4] += (double)n.y; a[5] += (double)n.z;
    a[6] += (double)z;
    a[7] += 1.0;
}

/* Spectral mode, BDPT and VCM: the wavelengths of light path `path` of iteration
 * `iteration`, which BDPT's camera path of pixel `path` shares (the connections join
 * the two, so both must carry the same wavelengths); VCM merges every camera path with
 * every light path of the iteration, so all its paths share one set (path ignored): each
 * iteration is then an unbiased estimate of the spectral integral, and their average
 * converges. From a stream of their own, so no other draw moves. */
static Wavelengths bidir_wavelengths(const Integrator *it, uint64_t path, int iteration)
{
    Pcg32 r;
    if (it->light.vcm_params.merge) { /* stratified over iterations (wavelengths_pass_u) */
        pcg32_seed_sample(&r, it->seed ^ 0x3c6ef372fe94f82bULL, 0, 0);
        return wavelengths_sample(wavelengths_pass_u((uint32_t)iteration, pcg32_next(&r)));
    }
    pcg32_seed_sample(&r, it->seed ^ 0x3c6ef372fe94f82bULL, path + 1, (uint64_t)iteration);
    return wavelengths_sample(pcg32_float(&r));
}

/* Motion blur, BDPT and VCM: the instant of light path `path` of iteration `iteration`,
 * which the camera paths it is joined with must share (a connection or merge between
 * subpaths at two instants would join two different scenes).
 * BDPT joins light path i with the camera path of pixel i alone: the time is that camera
 * sample's own time dimension (camera_tile's draw after film and lens, redrawn here from
 * the same sampler state), so each path sample has one time, stratified as the sampler
 * stratifies it. VCM merges every camera path with every light path of the iteration, so
 * all paths of an iteration share one instant (path ignored), as its wavelengths are
 * shared: each iteration is then an unbiased estimate of the image at a uniform instant
 * (merging keeps its usual, vanishing, radius bias), so the average over iterations
 * converges to the time-averaged image; pixels of one iteration are correlated (the blur
 * shows as few sharp copies at low sample counts). The iterations' instants are spread
 * over the shutter by motion_pass_time. Either is mapped through the shutter (camera_time:
 * [0, 1] keeps u bit for bit). */
static float bidir_time(const Integrator *it, uint64_t path, int iteration)
{
    if (it->light.vcm_params.merge) {
        Pcg32 r;
        pcg32_seed_sample(&r, it->seed ^ 0x9e3779b97f4a7c15ULL, 0, 0);
        return camera_time(&it->camera, motion_pass_time((uint32_t)iteration, pcg32_float(&r)));
    }
    Sampler smp;
    sampler_start(&smp, &it->sampler, path, (uint32_t)iteration);
    (void)sampler_2d(&smp); /* film */
    (void)sampler_2d(&smp); /* lens */
    return camera_time(&it->camera, sampler_1d(&smp));
}

/* The camera at a path's time: *buf placed there when the camera moves, else the camera
 * itself (no copy). BDPT/VCM's light subpaths connect to it (t = 1: the lens point, W_e and
 * its pdf) where their own instant places it, as the light tracer does (light.c). */
static const Camera *camera_placed(const Camera *cam, float time, Camera *buf)
{
    if (!cam->moving) return cam;
    *buf = camera_at(cam, time);
    return buf;
}

/* One camera sample's radiance, by the integrator's estimator (spectral mode: at wl's
 * wavelengths; wl NULL in RGB mode). */
static inline Color camera_li(Integrator *it, const Camera *cam, IntegratorWorker *w, int pixel, Ray ray,
                              Sampler *smp, Wavelengths *wl, int photon_set)
{
    Sampler cont;
    switch (it->kind) {
    case INTEGRATOR_PATH: return path_li(it->scene, &it->path, ray, smp, wl, &w->rays);
    case INTEGRATOR_WHITTED: return whitted_li(it->scene, &it->whitted, ray, smp, wl, &w->rays);
    case INTEGRATOR_PHOTON:
        /* Photon mapping and BDPT/VCM continue from the sample's PCG32 stream. */
        cont = sampler_continue_sample(smp);
        return photon_li(it->scene, &it->photon, photon_set, ray, &cont, &w->rays);
    case INTEGRATOR_BIDIR:
        cont = sampler_continue_sample(smp);
        if (it->light.vcm_params.merge)
            return vcm_trace_camera(it->scene, cam, &it->light.vcm_params, &it->light.vcm_it, pixel, ray,
                                    &cont, wl, &w->rays);
        return bdpt_trace_camera(it->scene, cam, &it->light.vcm_params, &it->light.vcm_it, pixel, ray,
                                 &cont, wl, &w->rays);
    case INTEGRATOR_LIGHT:
    case INTEGRATOR_SPPM:
    case INTEGRATOR_PSSMLT: break;
    }
    return color_s(0.0f);
}

static void camera_tile(void *ctx, int tile, int worker)
{
    Integrator *it = ctx;
    IntegratorWorker *w = &it->workers[worker];
    int first = it->tile_first, count = it->tile_spp;
    if (it->tile_runs) {
        const IntegratorTileRun *run = &it->tile_runs[tile];
        tile = run->tile;
        first = run->first;
        count = run->count;
    }
    /* Tiles cover the crop; pixels keep their whole-image index (seeds, film). */
    const int W = it->film->width;
    int x0 = it->crop_x0 + (tile % it->tiles_x) * INTEGRATOR_TILE;
    int y0 = it->crop_y0 + (tile / it->tiles_x) * INTEGRATOR_TILE;
    int x1 = x0 + INTEGRATOR_TILE < it->crop_x1 ? x0 + INTEGRATOR_TILE : it->crop_x1;
    int y1 = y0 + INTEGRATOR_TILE < it->crop_y1 ? y0 + INTEGRATOR_TILE : it->crop_y1;
    for (int y = y0; y < y1; y++) {
        for (int x = x0; x < x1; x++) {
            int pixel = y * W + x;
            for (int s = first; s < first + count; s++) {
                Sampler smp;
                sampler_start(&smp, &it->sampler, (uint64_t)pixel, (uint32_t)s);
                Vec2 uf = sampler_2d(&smp);
                Vec2 ul = sampler_2d(&smp);
                float fw;
                Vec2 fp = filter_film_position(&it->pixel_filter, x, y, uf, &fw);
                /* Motion blur: the path's time, uniform over the shutter interval, from the
                 * dimension after the film and lens ones; drawn only in scenes that move, so
                 * static scenes keep their streams (and their images) bit for bit. BDPT's
                 * light pass redraws this dimension (bidir_time): keep the two in step; VCM
                 * takes the iteration's one instant instead. A moving camera is placed at
                 * that time first; the camera path's estimator sees it placed (BDPT/VCM's
                 * camera pdf at the primary vertex). */
                float time = 0.0f;
                if (it->motion) {
                    time = camera_time(&it->camera, sampler_1d(&smp));
                    if (it->kind == INTEGRATOR_BIDIR && it->light.vcm_params.merge)
                        time = bidir_time(it, (uint64_t)pixel, s);
                }
                Camera placed;
                const Camera *cam = camera_placed(&it->camera, time, &placed);
                Ray ray = camera_generate_ray(cam, fp.x, fp.y, ul);
                ray.time = time;
                if (it->aov_hit) camera_aov(it, cam, w, pixel, ray);
                /* Spectral mode: the path's wavelengths, from the dimension after the
                 * film and lens ones (BDPT/VCM: shared with light paths, above). */
                Wavelengths wl, *wlp = NULL;
                int photon_set = 0; /* photon: the photon set whose wavelengths the path takes */
                if (it->spectral && it->kind == INTEGRATOR_PHOTON) {
                    photon_set = photon_maps_pick(&it->photon, sampler_1d(&smp));
                    wl = it->photon.sets[photon_set].wl;
                    wlp = &wl;
                } else if (it->spectral) {
                    wl = it->kind == INTEGRATOR_BIDIR ? bidir_wavelengths(it, (uint64_t)pixel, s)
                                                      : wavelengths_sample(sampler_1d(&smp));
                    wlp = &wl;
                }
                Color L = camera_li(it, cam, w, pixel, ray, &smp, wlp, photon_set);
                /* The film's sensor: the path's four spectral values to linear sRGB. */
                if (wlp) L = spectrum_to_rgb(L, wlp);
                if (!color_is_finite(L)) {
                    /* Counted and dropped as a zero sample: one NaN must not erase a pixel. */
                    w->nonfinite++;
                    L = color_s(0.0f);
                } else if (it->clamp > 0.0f) {
                    L = color_clamp_xyz_max(L, it->clamp);
                }
                if (fw != 1.0f) L = color_scale(L, fw);
                if (it->kind == INTEGRATOR_BIDIR) {
                    /* The iteration's image; light_merge_band adds the splats and files it. */
                    double *o = &it->light.iteration_rgb[3 * (size_t)pixel];
                    o[0] = (double)L.c[0]; o[1] = (double)L.c[1]; o[2] = (double)L.c[2];
                } else {
                    film_accumulate(it->film, pixel, (double)L.c[0], (double)L.c[1], (double)L.c[2]);
                }
            }
        }
    }
}

/* --------------------------------------------------- light tracing, BDPT and VCM */

/* BDPT/VCM's light subpath i of the iteration: a stream apart from the camera path of pixel
 * i, which uses (seed, i, iteration). */
static void bidir_light_stream(const Integrator *it, int iteration, int i, Sampler *rng)
{
    sampler_start_stream(rng, it->seed ^ 0x6c8e9cf570932bd5ULL, (uint64_t)i, (uint64_t)iteration);
}

static void light_chunk(void *ctx, int chunk, int worker)
{
    Integrator *it = ctx;
    LightIterations *L = &it->light;
    IntegratorWorker *w = &it->workers[worker];
    SplatList *out = &L->chunks[chunk].splats;
    out->n = 0;
    int first = chunk * LIGHT_CHUNK;
    int last = first + LIGHT_CHUNK < L->light_paths ? first + LIGHT_CHUNK : L->light_paths;
    /* The first iteration's lists start with room for LIGHT_RESERVE entries per path
     * instead of doubling from 16: each doubling of a block below malloc's mmap threshold
     * copies it: on SmallVCM's box memmove was 7.7% of a 4-iteration bdpt render's CPU
     * time, nearly all of it in the first iteration (perf; docs/benchmarks-history.md,
     * issue 32). Capacity only: the lists' contents, and so the images, are unchanged. */
    const size_t reserve = (size_t)(last - first) * LIGHT_RESERVE;
    if (!array_reserve(out, reserve)) out->oom = 1;
    if (it->kind == INTEGRATOR_BIDIR) {
        SubpathVertexList *verts = &L->chunks[chunk].verts;
        verts->n = 0;
        if (!array_reserve(verts, reserve)) verts->oom = 1;
        for (int i = first; i < last; i++) {
            Sampler rng;
            bidir_light_stream(it, it->iteration, i, &rng);
            size_t before = verts->n;
            Wavelengths wl;
            if (it->spectral) wl = bidir_wavelengths(it, (uint64_t)i, it->iteration);
            const float time = it->motion ? bidir_time(it, (uint64_t)i, it->iteration) : 0.0f;
            Camera placed;
            const Camera *cam = camera_placed(&it->camera, time, &placed);
            subpath_trace_light(it->scene, cam, &L->vcm_params, &L->vcm_it, &rng, time,
                                it->spectral ? &wl : NULL, verts, out, &w->rays);
            L->path_count[i] = (uint32_t)(verts->n - before);
        }
        /* The grid's corner, reduced over the chunks by bidir_prepare (min is exact in any
         * order). */
        Vec3 lo = v3(INFINITY, INFINITY, INFINITY);
        if (L->vcm_params.merge)
            for (size_t k = 0; k < verts->n; k++) lo = v3_min(lo, verts->v[k].p);
        L->chunks[chunk].lo = lo;
    } else {
        for (int i = first; i < last; i++) {
            Sampler rng;
            sampler_start_stream(&rng, it->seed, (uint64_t)i, (uint64_t)it->iteration);
            light_trace(it->scene, &it->camera, &L->params, &rng, out, &w->rays);
        }
    }
    splat_list_bin(out, &L->params.frame); /* sets out->oom on failure, checked after the step */
}

void integrator_light_path(const Integrator *it, int iteration, int path, SplatList *out, uint64_t *rays)
{
    Sampler rng;
    sampler_start_stream(&rng, it->seed, (uint64_t)path, (uint64_t)iteration); /* as light_chunk */
    light_trace(it->scene, &it->camera, &it->light.params, &rng, out, rays);
}

void integrator_bidir_light_path(const Integrator *it, int iteration, int path, struct Recorder *rec,
                                 SubpathVertexList *verts, SplatList *splats, uint64_t *rays)
{
    const LightIterations *L = &it->light;
    SubpathIteration vi = L->vcm_it;
    vi.rec = rec;
    Sampler rng;
    bidir_light_stream(it, iteration, path, &rng);
    Wavelengths wl; /* as light_chunk */
    if (it->spectral) wl = bidir_wavelengths(it, (uint64_t)path, iteration);
    const float time = it->motion ? bidir_time(it, (uint64_t)path, iteration) : 0.0f;
    Camera placed;
    const Camera *cam = camera_placed(&it->camera, time, &placed);
    subpath_trace_light(it->scene, cam, &L->vcm_params, &vi, &rng, time, it->spectral ? &wl : NULL, verts,
                        splats, rays);
}

/* Between the light and the camera step of a BDPT/VCM iteration: the chunks' vertex
 * lists are concatenated in chunk order (so path i's vertices are a run starting at
 * path_start[i]), and for VCM the merging grid is built over them. What is serial is
 * here: sizes, offsets and the grid's corner; the copying and sorting are steps
 * (bidir_gather_chunk, bidir_grid_range). Returns 0 on OOM. */
/* Room for `need` elements of `elem` bytes at *data (capacity *cap) without keeping the
 * contents, for the iteration-wide arrays that every iteration rewrites whole: a quarter
 * more than asked (the totals vary a little between iterations), in huge pages where the
 * system offers them (memory_alloc_large). Merging reads the light vertices and the grid's
 * bucket bounds at random over tens of megabytes, and with 4 KiB pages nearly each read
 * was a TLB miss; the first iteration also faulted every 4 KiB page in (perf: the kernel's
 * page faults 8% of a 4-iteration bdpt render; docs/benchmarks-history.md, issue 32).
 * False on overflow or OOM, with *data NULL and *cap 0 (light_free frees it). */
static bool scratch_grow(void *data, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return true;
    const size_t want = need + need / 4;
    void *old;
    memcpy(&old, data, sizeof old);
    free(old);
    void *p = want >= need && want <= SIZE_MAX / elem ? memory_alloc_large(want * elem) : NULL;
    memcpy(data, &p, sizeof p);
    *cap = p ? want : 0;
    return p != NULL;
}

static int bidir_prepare(LightIterations *L, int threads)
{
    size_t total = 0;
    Vec3 lo = v3(INFINITY, INFINITY, INFINITY);
    for (int c = 0; c < L->num_chunks; c++) {
        if (L->chunks[c].verts.oom) return 0;
        L->chunks[c].first = total;
        total += L->chunks[c].verts.n;
        lo = v3_min(lo, L->chunks[c].lo);
    }
    if (total > UINT32_MAX - 1) return 0;
    if (!scratch_grow(&L->vertices, &L->cap[0], total, sizeof *L->vertices) ||
        !scratch_grow(&L->cell_items, &L->cap[1], total, sizeof *L->cell_items) ||
        !scratch_grow(&L->cell_start, &L->cap[2], total + 1, sizeof *L->cell_start) ||
        !scratch_grow(&L->cell_of, &L->cap[3], total, sizeof *L->cell_of))
        return 0;
    L->total = total;
    uint32_t *ps = L->path_start;
    ps[0] = 0;
    for (int i = 0; i < L->light_paths; i++) ps[i + 1] = ps[i] + L->path_count[i];
    L->vcm_it.vertices = L->vertices;
    L->vcm_it.path_start = ps;
    L->vcm_it.cells = 0;
    L->grid_ranges = 0;
    if (L->vcm_params.merge && total > 0) {
        vcm_grid_init(&L->vcm_it, lo, (uint32_t)total, L->cell_start, L->cell_items);
        int ranges = 4 * threads;
        L->grid_ranges = ranges < 1 ? 1 : ranges > GRID_RANGES_MAX ? GRID_RANGES_MAX : ranges;
    }
    return 1;
}

static void bidir_gather_chunk(void *ctx, int chunk, int worker)
{
    (void)worker;
    LightIterations *L = &((Integrator *)ctx)->light;
    const SubpathVertexList *l = &L->chunks[chunk].verts;
    size_t first = L->chunks[chunk].first;
    if (l->n) memcpy(L->vertices + first, l->v, l->n * sizeof *l->v);
    if (L->grid_ranges)
        for (size_t k = 0; k < l->n; k++) L->cell_of[first + k] = vcm_grid_cell(&L->vcm_it, l->v[k].p);
}

/* Bucket range `range` of the merging grid: counted, or once all are counted, sorted. */
static void bidir_grid_range(void *ctx, int range, int worker)
{
    (void)worker;
    LightIterations *L = &((Integrator *)ctx)->light;
    if (!L->grid_fill)
        L->grid_base[range] = vcm_grid_count(&L->vcm_it, L->cell_of, L->total, range, L->grid_ranges,
                                             L->cell_start);
    else
        vcm_grid_fill(&L->vcm_it, L->cell_of, L->total, range, L->grid_ranges, L->grid_base[range],
                      L->cell_start, L->cell_items);
}

/* Adds the finished iteration to the film as one sample per pixel, for the rows of one
 * band (SplatFrame). The light tracer's pixel estimate is (W H / paths) times the sum of
 * its splats (splats are per unit film, camera.c), and W H / paths = 1 with one path per
 * pixel. Adding the iteration, not the splats, as the sample keeps the film's sum of
 * squares a per-pixel variance across iterations; splats are summed in chunk order and,
 * within a chunk, in the order they were made (splat_list_bin is stable), so the
 * floating-point sums depend neither on which thread traced which chunk nor on which
 * thread merged which band. */
static void light_merge_band(void *ctx, int unit, int worker)
{
    (void)worker;
    Integrator *it = ctx;
    LightIterations *L = &it->light;
    const SplatFrame *fr = &L->params.frame;
    const size_t pixels = (size_t)fr->width * (size_t)fr->height;
    const double scale = it->kind == INTEGRATOR_PSSMLT ? mlt_splat_scale(it->mlt)
                                                       : (double)pixels / (double)L->light_paths;
    size_t lo = (size_t)unit * (size_t)fr->band_rows * (size_t)fr->width;
    size_t hi = lo + (size_t)fr->band_rows * (size_t)fr->width;
    if (hi > pixels) hi = pixels;
    double *rgb = L->iteration_rgb;
    /* BDPT/VCM: the camera step already wrote its pixel samples there. */
    if (it->kind != INTEGRATOR_BIDIR) memset(rgb + 3 * lo, 0, 3 * (hi - lo) * sizeof *rgb);
    for (int c = 0; c < L->num_chunks; c++) film_add_splats_band(&L->chunks[c].splats, fr, rgb, scale, unit);
    for (size_t p = lo; p < hi; p++)
        film_accumulate(it->film, (int)p, rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]);
}

/* Per-render buffers of the light iterations: a splat list per chunk, sized for a few
 * connections per path (they grow if a scene needs more, then stay), the iteration image,
 * and for BDPT/VCM the per-path vertex counts. Returns 0 on OOM. */
static int light_alloc(Integrator *it, size_t splat_cap)
{
    LightIterations *L = &it->light;
    size_t pixels = (size_t)it->film->width * (size_t)it->film->height;
    /* Zeroed: BDPT/VCM camera steps over a crop never write the pixels outside it. */
    L->iteration_rgb = calloc(3 * pixels, sizeof *L->iteration_rgb);
    L->chunks = aligned_alloc(_Alignof(LightChunk), (size_t)L->num_chunks * sizeof *L->chunks);
    if (!L->iteration_rgb || !L->chunks) return 0;
    memset(L->chunks, 0, (size_t)L->num_chunks * sizeof *L->chunks);
    for (int c = 0; c < L->num_chunks; c++)
        if (!splat_list_init(&L->chunks[c].splats, splat_cap)) return 0;
    if (it->kind == INTEGRATOR_BIDIR) {
        L->path_count = calloc(pixels, sizeof *L->path_count);
        L->path_start = calloc(pixels + 1, sizeof *L->path_start);
        if (!L->path_count || !L->path_start) return 0;
    }
    return 1;
}

static void light_free(LightIterations *L)
{
    if (L->chunks)
        for (int c = 0; c < L->num_chunks; c++) {
            splat_list_free(&L->chunks[c].splats);
            subpath_vertex_list_free(&L->chunks[c].verts);
        }
    free(L->chunks);
    free(L->iteration_rgb);
    free(L->path_count);
    free(L->path_start);
    free(L->vertices);
    free(L->cell_start);
    free(L->cell_of);
    free(L->cell_items);
    memset(L, 0, sizeof *L);
}

/* A photon gather or VCM merging radius given by the settings (issue 25: 1e-30 was accepted
 * and most samples came out NaN). The density estimates divide by pi r^2 N in float
 * (photon.c, sppm.c; VCM's eta = pi r^2 N, tech. rep. eq. 12): r^2 underflowed to 0 and
 * 0 x inf gave NaN. A photon's flux grows with the scene's area, so an estimate scales as
 * (scene diagonal / r)^2: from RADIUS_MIN_REL of the diagonal that factor stays within 1e12,
 * far inside float's range for any sensible radiance (and such a radius gathers no photon
 * anyway: the automatic one is about 3e-3 of the diagonal). RADIUS_MIN_ABS keeps r^2 a
 * normal float in tiny scenes, as the builder's smallest sphere radius does; RADIUS_MAX is
 * the loaders' bound on lengths, whose square stays finite. Out-of-range values are
 * refused, not clamped: a radius the user chose should not change silently. */
#define RADIUS_MIN_REL 1e-6
#define RADIUS_MIN_ABS 1e-18
#define RADIUS_MAX 1e18
static CstStatus check_radius(const Scene *s, double r, const char *what, CstError *err)
{
    double diag = 2.0 * (double)s->emitter_sampler.radius; /* the scene's bounding-box diagonal */
    double lo = RADIUS_MIN_REL * diag > RADIUS_MIN_ABS ? RADIUS_MIN_REL * diag : RADIUS_MIN_ABS;
    if (r >= lo && r <= RADIUS_MAX) return CST_OK;
    return cst_fail(err, CST_ERR_INVALID_ARG,
                    "%s radius %g: expected %g to %g (at least 1e-6 of the scene's bounding-box diagonal, %g, "
                    "and 1e-18; at most 1e18), or 0 / no radius for the automatic one",
                    what, r, lo, RADIUS_MAX, diag);
}

static CstStatus light_prepare(Integrator *it, const CstRenderSettings *st, CstError *err)
{
    LightIterations *L = &it->light;
    if (it->kind == INTEGRATOR_BIDIR) {
        L->vcm_params.merge = st->integrator == CST_INTEGRATOR_VCM;
        L->vcm_params.max_depth = st->max_depth;
        L->vcm_params.rr_depth = st->rr_depth;
        L->vcm_params.light_rr_depth = st->light_rr_depth;
        L->vcm_radius = st->photon_radius > 0.0 ? (float)st->photon_radius : vcm_default_radius(it->scene);
        if (!(st->photon_radius >= 0.0) || !(L->vcm_radius > 0.0f) || !(L->vcm_radius < INFINITY))
            return cst_fail(err, CST_ERR_INVALID_ARG, "merging radius %g: expected a positive value (0 = automatic)",
                            st->photon_radius);
        CstStatus rs = L->vcm_params.merge && st->photon_radius > 0.0
                           ? check_radius(it->scene, st->photon_radius, "merging", err) : CST_OK;
        if (rs != CST_OK) return rs;
    }
    L->params.max_depth = st->max_depth;
    L->params.rr_depth = st->rr_depth;
    L->params.spectral = it->spectral;
    /* One light path per pixel per iteration; 65536^2 pixels would overflow int. */
    size_t pixels = (size_t)st->width * (size_t)st->height;
    if (pixels > (size_t)INT32_MAX - LIGHT_CHUNK)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image size %dx%d: too many pixels for the light tracer (at most %d)",
                        st->width, st->height, INT32_MAX - LIGHT_CHUNK);
    L->light_paths = (int)pixels;
    L->num_chunks = (L->light_paths + LIGHT_CHUNK - 1) / LIGHT_CHUNK;
    L->params.frame = L->vcm_params.frame = splat_frame(st->width, st->height, st->filter);
    L->params.frame.clamp = L->vcm_params.frame.clamp = it->clamp;
    if (!light_alloc(it, 4 * (size_t)LIGHT_CHUNK))
        return cst_fail(err, CST_ERR_OOM, "out of memory for light-tracing buffers (%dx%d)", st->width, st->height);
    return CST_OK;
}

/* Metropolis light transport (mlt.h) on the light tracer's splat machinery: one chunk per
 * chain, so the splats are merged in chain order, whatever thread ran which chain. */
static CstStatus mlt_prepare(Integrator *it, const CstRenderSettings *st, CstError *err)
{
    LightIterations *L = &it->light;
    if (!(st->mlt_large_step >= 0.0 && st->mlt_large_step <= 1.0) || !(st->mlt_sigma > 0.0 && st->mlt_sigma <= 1.0) ||
        st->mlt_bootstrap < 1 || st->mlt_chains < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "MLT settings: large step probability %g (expected [0, 1]), sigma %g "
                        "(expected (0, 1]), bootstrap %d and chains %d (expected > 0)", st->mlt_large_step,
                        st->mlt_sigma, st->mlt_bootstrap, st->mlt_chains);
    size_t pixels = (size_t)st->width * (size_t)st->height;
    if (pixels > (size_t)INT32_MAX)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image size %dx%d: too many pixels for MLT", st->width, st->height);
    MltParams p = {0};
    if (st->integrator == CST_INTEGRATOR_MMLT) {
        /* Multiplexed MLT needs a finite path length: pbrt-v4's default maxdepth, 5, for 0
         * (unbounded). Bootstrap paths: mlt_bootstrap per length, as pbrt-v4. */
        const int depth = st->max_depth > 0 ? st->max_depth : MMLT_DEFAULT_DEPTH;
        if (depth >= (1 << 16) || (int64_t)st->mlt_bootstrap * (depth + 1) > (int64_t)1 << 28)
            return cst_fail(err, CST_ERR_INVALID_ARG, "mmlt: max_depth %d with %d bootstrap paths per path length: "
                            "expected at most 2^28 bootstrap paths in all (bootstrap x (max_depth + 1))", depth,
                            st->mlt_bootstrap);
        p.depths = depth + 1;
        p.sub.merge = false;
        p.sub.max_depth = depth;
        p.sub.rr_depth = st->rr_depth;
        p.sub.light_rr_depth = st->rr_depth; /* MMLT's light subpaths: rr_depth, as always */
        p.sub.frame = splat_frame(st->width, st->height, st->filter);
        vcm_iteration_init(&p.it, &p.sub, &it->camera, (int)pixels, 0.0f, 0);
    }
    p.path.mode = PATH_MIS;
    p.path.max_depth = st->max_depth;
    p.path.rr_depth = st->rr_depth;
    p.path.regularize = st->regularize == 1;
    p.width = st->width;
    p.height = st->height;
    p.margin = filter_radius(st->filter) - 0.5f;
    p.large_step_prob = (float)st->mlt_large_step;
    p.sigma = st->mlt_sigma;
    p.bootstrap = st->mlt_bootstrap * (p.depths > 0 ? p.depths : 1);
    /* At least one mutation per chain per iteration. */
    p.chains = (size_t)st->mlt_chains < pixels ? st->mlt_chains : (int)pixels;
    p.seed = st->seed;
    p.spectral = it->spectral;
    if (!(it->mlt = mlt_create(&p)))
        return cst_fail(err, CST_ERR_OOM, "out of memory for %d MLT chains and %d bootstrap paths", p.chains,
                        p.bootstrap);
    L->light_paths = (int)pixels;
    L->num_chunks = p.chains;
    L->params.frame = splat_frame(st->width, st->height, st->filter);
    L->params.frame.clamp = it->clamp;
    /* A proposal and a current-state splat per mutation. */
    if (!light_alloc(it, 2 * (size_t)mlt_chain_mutations(it->mlt, 0) + 16))
        return cst_fail(err, CST_ERR_OOM, "out of memory for MLT buffers (%dx%d)", st->width, st->height);
    return CST_OK;
}

static void mlt_boot_step(void *ctx, int item, int worker)
{
    Integrator *it = ctx;
    IntegratorWorker *w = &it->workers[worker];
    mlt_bootstrap_item(it->mlt, it->scene, &it->camera, item, &w->rays, &w->nonfinite);
}

static void mlt_start_step(void *ctx, int chain, int worker)
{
    Integrator *it = ctx;
    IntegratorWorker *w = &it->workers[worker];
    mlt_chain_start(it->mlt, it->scene, &it->camera, chain, &w->rays, &w->nonfinite);
}

static void mlt_chain_step(void *ctx, int chain, int worker)
{
    Integrator *it = ctx;
    IntegratorWorker *w = &it->workers[worker];
    SplatList *out = &it->light.chunks[chain].splats;
    out->n = 0;
    mlt_chain_run(it->mlt, it->scene, &it->camera, chain, mlt_chain_mutations(it->mlt, chain), out,
                  &it->light.params.frame, &w->rays, &w->nonfinite);
    splat_list_bin(out, &it->light.params.frame); /* sets out->oom on failure, checked after the step */
}

/* ------------------------------------------------------------------------ steps */

static void set_step(IntegratorStep *step, int items, ThreadPoolFn fn, void *ctx, double lo, double hi,
                     bool throttle)
{
    *step = (IntegratorStep){items, fn, ctx, lo, hi, throttle};
}

static CstStatus splats_lost(const Integrator *it, CstError *err)
{
    for (int c = 0; c < it->light.num_chunks; c++)
        if (it->light.chunks[c].splats.oom)
            return cst_fail(err, CST_ERR_OOM, "out of memory for light-tracing splats (%dx%d)", it->film->width,
                            it->film->height);
    return CST_OK;
}

/* Step it->step of the current iteration into *step (items 0: the iteration is done).
 * [lo, hi]: the iteration's share of the pass's progress. */
static CstStatus iteration_step(Integrator *it, IntegratorStep *step, double lo, double hi, CstError *err)
{
    LightIterations *L = &it->light;
    const double mid = it->kind == INTEGRATOR_BIDIR ? lo + 0.5 * (hi - lo) : hi;
    CstStatus st;
    switch (it->kind) {
    case INTEGRATOR_PATH:
    case INTEGRATOR_WHITTED:
    case INTEGRATOR_PHOTON:
        /* One step for the whole pass: every sample of a pixel in one tile item, so the
         * pixel's accumulation order is fixed. */
        if (it->step++ > 0) return CST_OK;
        it->tile_first = it->pass_first;
        it->tile_spp = it->pass_count;
        it->iteration = it->pass_first + it->pass_count - 1;
        set_step(step, it->tile_runs ? it->num_tile_runs : it->num_tiles, camera_tile, it, 0.0, 1.0, false);
        return CST_OK;
    case INTEGRATOR_LIGHT:
    case INTEGRATOR_BIDIR:
        for (;;) {
            switch (it->step++) {
            case 0:
                if (it->kind == INTEGRATOR_BIDIR)
                    vcm_iteration_init(&L->vcm_it, &L->vcm_params, &it->camera, L->light_paths, L->vcm_radius,
                                       it->iteration);
                set_step(step, L->num_chunks, light_chunk, it, lo, mid, true);
                return CST_OK;
            case 1:
                if ((st = splats_lost(it, err)) != CST_OK) return st;
                if (it->kind == INTEGRATOR_LIGHT) { it->step = 5; continue; }
                if (!bidir_prepare(L, it->threads))
                    return cst_fail(err, CST_ERR_OOM, "out of memory for the light vertices of an iteration");
                set_step(step, L->num_chunks, bidir_gather_chunk, it, mid, mid, true);
                return CST_OK;
            case 2:
                if (!L->grid_ranges) { it->step = 4; continue; }
                L->grid_fill = false;
                set_step(step, L->grid_ranges, bidir_grid_range, it, mid, mid, true);
                return CST_OK;
            case 3:
                vcm_grid_bases(L->grid_base, L->grid_ranges);
                L->grid_fill = true;
                set_step(step, L->grid_ranges, bidir_grid_range, it, mid, mid, true);
                return CST_OK;
            case 4:
                /* One camera path per pixel: sample `iteration` of every pixel. */
                it->tile_first = it->iteration;
                it->tile_spp = 1;
                set_step(step, it->num_tiles, camera_tile, it, mid, hi, true);
                return CST_OK;
            case 5:
                set_step(step, L->params.frame.bands, light_merge_band, it, hi, hi, true);
                return CST_OK;
            default: return CST_OK;
            }
        }
    case INTEGRATOR_PSSMLT:
        for (;;) {
            switch (it->step++) {
            case 0: /* once per render, before the first iteration: the bootstrap */
                if (it->mlt->ready) continue;
                set_step(step, (it->mlt->p.bootstrap + MLT_BOOTSTRAP_CHUNK - 1) / MLT_BOOTSTRAP_CHUNK, mlt_boot_step,
                         it, lo, lo, true);
                return CST_OK;
            case 1: /* and the chains' starts */
                if (it->mlt->ready) continue;
                mlt_bootstrap_finish(it->mlt);
                it->mlt->ready = true;
                set_step(step, it->mlt->p.chains, mlt_start_step, it, lo, lo, true);
                return CST_OK;
            case 2:
                set_step(step, it->mlt->p.chains, mlt_chain_step, it, lo, hi, true);
                return CST_OK;
            case 3:
                if ((st = splats_lost(it, err)) != CST_OK) return st;
                set_step(step, L->params.frame.bands, light_merge_band, it, hi, hi, true);
                return CST_OK;
            default: return CST_OK;
            }
        }
    case INTEGRATOR_SPPM:
        while (it->step < SPPM_PHASES) {
            int p = it->step++;
            int n = sppm_phase_begin(it->sppm, it->iteration, p);
            if (n == -2)
                return cst_fail(err, CST_ERR_CANCELLED, "SPPM iteration %d: the photon hits of another process "
                                "did not arrive (CstPhotonSplit.fetch failed)", it->iteration);
            if (n < 0) return cst_fail(err, CST_ERR_OOM, "out of memory for SPPM photon hits");
            if (n == 0) continue;
            set_step(step, n, sppm_item, it->sppm, lo + (hi - lo) * p / SPPM_PHASES,
                     lo + (hi - lo) * (p + 1) / SPPM_PHASES, false);
            return CST_OK;
        }
        return CST_OK;
    }
    return CST_OK;
}

void integrator_pass_begin(Integrator *it, int first, int count)
{
    it->pass_first = first;
    it->pass_count = count;
    it->iteration = first;
    it->step = 0;
}

CstStatus integrator_next_step(Integrator *it, IntegratorStep *step, CstError *err)
{
    for (;;) {
        const int k = it->iteration - it->pass_first;
        set_step(step, 0, NULL, it, 1.0, 1.0, false);
        if (k >= it->pass_count) return CST_OK;
        CstStatus st = iteration_step(it, step, (double)k / it->pass_count, (double)(k + 1) / it->pass_count, err);
        if (st != CST_OK || step->items > 0) return st;
        it->iteration++;
        it->step = 0;
    }
}

/* ---------------------------------------------------------------------- lifetime */

/* Subsurface materials: the path tracers take pbrt-v4's BSSRDF step (path_sss.c) by
 * default. With subsurface_walk, the path tracers (through volpath.c), the light tracer,
 * BDPT, VCM and MMLT random-walk the materials' media instead, in a view of the scene where
 * they are medium interfaces (sss_walk.h), so that light and camera subpaths meet in the
 * same media. The two estimands differ by the BSSRDF's diffusion approximation (about 10 %
 * on tests/render/subsurface/sss-walk.pbrt), so the light-path integrators refuse the
 * default rather than render another image than path does: every integrator a setting
 * accepts converges to the same answer. On return *scene (and it->scene) is the view,
 * media and all, when one is made. */
static CstStatus prepare_subsurface(Integrator *it, const Scene **scene, const CstRenderSettings *st, CstError *err)
{
    const Scene *s = *scene;
    if (!s->num_subsurface) return CST_OK;
    if (s->num_media | s->num_medium_ifaces)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "subsurface materials in a scene with participating media are "
                        "not rendered yet; expected one or the other");
    const bool walker = it->kind == INTEGRATOR_PATH || it->kind == INTEGRATOR_LIGHT ||
                        it->kind == INTEGRATOR_BIDIR || st->integrator == CST_INTEGRATOR_MMLT;
    if (!walker)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "integrator %s does not render subsurface materials yet: "
                        "use path, path-nee, path-bsdf, or light, bdpt, vcm or mmlt with --subsurface walk",
                        cst_integrator_name(st->integrator));
    const bool walk = st->subsurface_walk == 1;
    if (it->kind != INTEGRATOR_PATH && !walk)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "integrator %s renders subsurface materials only as a random walk "
                        "of their media (--subsurface walk, CstRenderSettings.subsurface_walk), which the path "
                        "tracers then render too; without it the path tracers use pbrt-v4's BSSRDF, which has no "
                        "light-path form", cst_integrator_name(st->integrator));
    if (!walk) return CST_OK;
    CstStatus ss = sss_walk_view_create(s, &it->sss_view, err);
    if (ss != CST_OK) return ss;
    it->scene = *scene = it->sss_view;
    return CST_OK;
}

CstStatus integrator_prepare(Integrator *it, const Scene *scene, const CstRenderSettings *st, Film *film,
                             IntegratorWorker *workers, uint64_t *rays, int (*progress)(void *, double),
                             void *progress_user, CstError *err)
{
    memset(it, 0, sizeof *it);
    switch (st->integrator) {
    case CST_INTEGRATOR_WHITTED: it->kind = INTEGRATOR_WHITTED; break;
    case CST_INTEGRATOR_PHOTON: it->kind = INTEGRATOR_PHOTON; break;
    case CST_INTEGRATOR_LIGHT: it->kind = INTEGRATOR_LIGHT; break;
    case CST_INTEGRATOR_BDPT:
    case CST_INTEGRATOR_VCM: it->kind = INTEGRATOR_BIDIR; break;
    case CST_INTEGRATOR_SPPM: it->kind = INTEGRATOR_SPPM; break;
    case CST_INTEGRATOR_PSSMLT:
    case CST_INTEGRATOR_MMLT: it->kind = INTEGRATOR_PSSMLT; break;
    case CST_INTEGRATOR_PATH:
    case CST_INTEGRATOR_PATH_NEE:
    case CST_INTEGRATOR_PATH_BSDF:
    case CST_INTEGRATOR_DEFAULT: it->kind = INTEGRATOR_PATH; break;
    }
    it->scene = scene;
    it->film = film;
    it->workers = workers;
    it->threads = st->threads;
    it->seed = st->seed;
    camera_init(&it->camera, &scene->camera, st->width, st->height);
    if (scene->camera_mirror) camera_mirror_x(&it->camera);
    camera_set_motion(&it->camera, scene->camera_placed ? &scene->camera_motion : NULL, scene->shutter[0],
                      scene->shutter[1]);
    filter_init(&it->pixel_filter, st->filter);
    /* A time limit without a sample cap: the count is not known, strata cannot be laid out. */
    it->sampler = sampler_setup(st->sampler, st->seed, (uint32_t)st->spp, st->width, st->height);
    it->aov_hit = (st->aovs & FILM_AOV_FIRST_HIT) != 0;
    it->spectral = st->color_mode == CST_COLOR_SPECTRAL;
    /* max_component bounds what the written image shows (after 2^exposure, which holds the
     * pbrt sensor's iso / 100), as pbrt-v4 bounds its sensor values after that ratio. */
    it->clamp = st->max_component > 0.0 ? (float)(st->max_component / exp2(st->exposure)) : 0.0f;
    CstStatus ss = prepare_subsurface(it, &scene, st, err);
    if (ss != CST_OK) return ss;
    /* pssmlt's target is path_li's estimate, media included (volpath_li reads the same
     * Sampler); mmlt's is BDPT's strategies, media included (subpath_media.c's single
     * strategies). light, bdpt, vcm, mmlt and sppm walk homogeneous, grid and cloud media
     * (subpath_media.c); vcm merges volume vertices by UPBP's point-point 3D estimator,
     * and sppm gathers volume photons at its visible points in media by the same (sppm.c).
     * Emission of media is gathered by the camera walks of bdpt, vcm and mmlt (its s = 0
     * strategy); light and sppm start light paths (photons) in the emitting media too
     * (media_lights.h; sppm's camera walk gathers the emission on its way as well), which
     * needs each such medium bounded (media_lights_create refuses the others); photon's
     * photons start in them as sppm's do, and its camera and final-gather walks gather the
     * emission they pass (photon.c, photon_li_media). */
    const bool bidir_media = it->kind == INTEGRATOR_LIGHT || it->kind == INTEGRATOR_BIDIR ||
                             st->integrator == CST_INTEGRATOR_MMLT || it->kind == INTEGRATOR_SPPM ||
                             it->kind == INTEGRATOR_PHOTON; /* photon: a volume photon map (photon.c) */
    if ((scene->num_media | scene->num_medium_ifaces) && it->kind != INTEGRATOR_PATH &&
        (it->kind != INTEGRATOR_PSSMLT || st->integrator == CST_INTEGRATOR_MMLT) && !bidir_media)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "integrator %s does not render participating media yet: "
                        "use path, path-nee, path-bsdf, light, photon, bdpt, vcm, pssmlt, mmlt or sppm",
                        cst_integrator_name(st->integrator));
    if (it->kind == INTEGRATOR_LIGHT || it->kind == INTEGRATOR_SPPM || it->kind == INTEGRATOR_PHOTON) {
        CstStatus ms = media_lights_create(scene, cst_integrator_name(st->integrator), &it->media_lights, err);
        if (ms != CST_OK) return ms;
    }
    /* Motion blur: every path carries one time to all its rays (Ray.time), drawn over the
     * shutter (camera_time), with a moving camera placed at it (camera_at) for its camera
     * ray and for every t = 1 connection to the lens. The path tracers (volpath and path_sss
     * too), Whitted and pssmlt take the camera sample's; the light tracer each light path's
     * own; BDPT and VCM share one between the subpaths they join (bidir_time); mmlt draws it
     * in the camera stream for both subpaths; SPPM shares one per iteration (sppm.c). The
     * photon integrator builds its maps once, before any camera path: at time 0 while only
     * the camera moves; where instances move, each photon path at a time of its own and
     * every estimate over a time window around its camera path's (photon.c, TimeWindow).
     * subpath_media.c's walks (light, bdpt, vcm and mmlt in
     * media) carry the time as subpath.c's do. */
    /* SPPM's walks through media carry the iteration's time too (media_photon_walk,
     * media_visible_point; test_motion_shapes compares them with path in fog). */
    it->motion = scene_has_motion(scene);
    it->crop_x0 = st->crop[0]; it->crop_x1 = st->crop[1];
    it->crop_y0 = st->crop[2]; it->crop_y1 = st->crop[3];
    it->tiles_x = (st->crop[1] - st->crop[0] + INTEGRATOR_TILE - 1) / INTEGRATOR_TILE;
    int tiles_y = (st->crop[3] - st->crop[2] + INTEGRATOR_TILE - 1) / INTEGRATOR_TILE;
    it->num_tiles = it->tiles_x * tiles_y;
    const bool photons_ok = st->photons >= 0 && st->photon_radius >= 0.0 && (float)st->photon_radius < INFINITY;
    switch (it->kind) {
    case INTEGRATOR_PATH:
        it->path.mode = st->integrator == CST_INTEGRATOR_PATH_NEE ? PATH_NEE
                      : st->integrator == CST_INTEGRATOR_PATH_BSDF ? PATH_BSDF : PATH_MIS;
        it->path.max_depth = st->max_depth;
        it->path.rr_depth = st->rr_depth;
        it->path.regularize = st->regularize == 1;
        return CST_OK;
    case INTEGRATOR_WHITTED:
        it->whitted.max_depth = st->max_depth;
        it->whitted.light_samples = 1;
        return CST_OK;
    case INTEGRATOR_PHOTON: {
        /* The photon pass is part of the render's time (and of a time limit's budget). It
         * runs single-threaded from the render seed, so the maps, and with them the image,
         * do not depend on the thread count. */
        if (!photons_ok) break;
        CstStatus rs = st->photon_radius > 0.0 ? check_radius(scene, st->photon_radius, "photon gather", err) : CST_OK;
        if (rs != CST_OK) return rs;
        PhotonParams pp = {st->photons, (float)st->photon_radius, st->max_depth, st->rr_depth, st->seed,
                           progress, progress_user, it->spectral, false, it->media_lights};
        return photon_maps_build_cached(st->photon_cache, scene, &it->camera, &pp, &it->photon,
                                        &it->photon_borrowed, rays, err);
    }
    case INTEGRATOR_LIGHT:
    case INTEGRATOR_BIDIR: {
        CstStatus ls = light_prepare(it, st, err);
        it->light.params.media_lights = it->media_lights; /* NULL but for light */
        return ls;
    }
    case INTEGRATOR_PSSMLT: return mlt_prepare(it, st, err);
    case INTEGRATOR_SPPM: {
        /* spp is the iteration count; photons reach each visible point in photon order
         * whatever the thread count (sppm.c). */
        if (!photons_ok) break;
        CstStatus rs = st->photon_radius > 0.0 ? check_radius(scene, st->photon_radius, "SPPM initial", err) : CST_OK;
        if (rs != CST_OK) return rs;
        SppmParams sp = {st->photons, (float)st->photon_radius, st->max_depth, st->rr_depth, st->filter, st->seed,
                         st->threads, it->spectral, st->photon_split, &it->camera, it->media_lights};
        return sppm_create(scene, &it->camera, &sp, st->threads, &it->sppm, err);
    }
    }
    return cst_fail(err, CST_ERR_INVALID_ARG, "photon count %d and radius %g: expected positive values (0 = default)",
                    st->photons, st->photon_radius);
}

void integrator_finish(Integrator *it, int samples)
{
    if (it->kind == INTEGRATOR_SPPM) sppm_finish(it->sppm, it->film, samples);
    else it->film->spp = samples;
    if (it->kind == INTEGRATOR_PSSMLT) { /* the image is made: the chains are no state of it (as SPPM's) */
        free(it->film->chains);
        it->film->chains = NULL;
        it->film->chains_len = 0;
    }
}

bool integrator_export_progressive(Integrator *it, int done)
{
    if (it->kind == INTEGRATOR_PSSMLT) {
        /* MLT: its chains as bytes (mlt.h), replacing the previous pass's. */
        Film *f = it->film;
        free(f->chains);
        f->chains = NULL;
        f->chains_len = 0;
        const size_t n = mlt_state_size(it->mlt);
        unsigned char *b = malloc(n);
        if (!b || !mlt_state_write(it->mlt, b)) {
            free(b);
            return false;
        }
        f->chains = b;
        f->chains_len = n;
        return true;
    }
    if (it->kind != INTEGRATOR_SPPM) return true;
    it->film->spp = done;
    return sppm_export(it->sppm, it->film);
}

bool integrator_import_progressive(Integrator *it, const Film *resume)
{
    if (it->kind == INTEGRATOR_PSSMLT)
        return resume->chains && mlt_state_read(it->mlt, resume->chains, resume->chains_len);
    return it->kind != INTEGRATOR_SPPM || sppm_import(it->sppm, resume);
}

void integrator_counters(const Integrator *it, uint64_t *rays, uint64_t *nonfinite)
{
    if (it->kind == INTEGRATOR_SPPM && it->sppm) sppm_counters(it->sppm, rays, nonfinite);
    if ((it->kind == INTEGRATOR_LIGHT || it->kind == INTEGRATOR_BIDIR || it->kind == INTEGRATOR_PSSMLT) &&
        it->light.chunks)
        for (int c = 0; c < it->light.num_chunks; c++) *nonfinite += it->light.chunks[c].splats.nonfinite;
}

void integrator_destroy(Integrator *it)
{
    sss_walk_view_destroy(it->sss_view);
    it->sss_view = NULL;
    media_lights_destroy(it->media_lights);
    it->media_lights = NULL;
    switch (it->kind) {
    case INTEGRATOR_PHOTON:
        if (!it->photon_borrowed) photon_maps_free(&it->photon);
        break;
    case INTEGRATOR_LIGHT:
    case INTEGRATOR_BIDIR: light_free(&it->light); break;
    case INTEGRATOR_SPPM: sppm_destroy(it->sppm); it->sppm = NULL; break;
    case INTEGRATOR_PSSMLT:
        light_free(&it->light);
        mlt_destroy(it->mlt);
        it->mlt = NULL;
        break;
    case INTEGRATOR_PATH:
    case INTEGRATOR_WHITTED: break;
    }
}

/* ------------------------------------------------------------------- name table */

static const struct { const char *name; CstIntegrator id; } INTEGRATOR_NAMES[] = {
    {"path", CST_INTEGRATOR_PATH},       {"path-nee", CST_INTEGRATOR_PATH_NEE},
    {"path-bsdf", CST_INTEGRATOR_PATH_BSDF}, {"mis", CST_INTEGRATOR_PATH},
    {"nee", CST_INTEGRATOR_PATH_NEE},    {"bsdf", CST_INTEGRATOR_PATH_BSDF},
    {"light", CST_INTEGRATOR_LIGHT},     {"lighttracing", CST_INTEGRATOR_LIGHT},
    {"whitted", CST_INTEGRATOR_WHITTED}, {"photon", CST_INTEGRATOR_PHOTON},
    {"sppm", CST_INTEGRATOR_SPPM},       {"bdpt", CST_INTEGRATOR_BDPT},
    {"vcm", CST_INTEGRATOR_VCM},         {"pssmlt", CST_INTEGRATOR_PSSMLT},
    {"mmlt", CST_INTEGRATOR_MMLT},
};

CstIntegrator cst_integrator_from_name(const char *name)
{
    for (size_t i = 0; i < sizeof INTEGRATOR_NAMES / sizeof INTEGRATOR_NAMES[0]; i++)
        if (strcmp(name, INTEGRATOR_NAMES[i].name) == 0) return INTEGRATOR_NAMES[i].id;
    return CST_INTEGRATOR_DEFAULT;
}

const char *cst_integrator_name(CstIntegrator integrator)
{
    switch (integrator) {
    case CST_INTEGRATOR_PATH: return "path";
    case CST_INTEGRATOR_PATH_NEE: return "path-nee";
    case CST_INTEGRATOR_PATH_BSDF: return "path-bsdf";
    case CST_INTEGRATOR_LIGHT: return "light";
    case CST_INTEGRATOR_WHITTED: return "whitted";
    case CST_INTEGRATOR_PHOTON: return "photon";
    case CST_INTEGRATOR_SPPM: return "sppm";
    case CST_INTEGRATOR_BDPT: return "bdpt";
    case CST_INTEGRATOR_VCM: return "vcm";
    case CST_INTEGRATOR_PSSMLT: return "pssmlt";
    case CST_INTEGRATOR_MMLT: return "mmlt";
    case CST_INTEGRATOR_DEFAULT: break;
    }
    return "default";
}
