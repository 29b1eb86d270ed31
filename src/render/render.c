/* Tiled multithreaded rendering. Determinism: each pixel sample draws from its own Sampler
 * (sampling/sampler.h) started from (seed, pixel, sample index), and each pixel is
 * accumulated by one thread in sample order, so images are bit-identical for any thread count.
 * Light tracing splats anywhere on the film instead; it runs in iterations of
 * width x height light paths, path i of iteration s seeded by (seed, i, s), cut into
 * fixed chunks whose splat lists are added in chunk order once the iteration is done, so
 * its images are bit-identical for any thread count too. BDPT and VCM run the same
 * iterations: a pass of light-path chunks (vertex lists and camera splats per chunk,
 * concatenated in chunk order), then a pass of tiles, one camera path per pixel, each
 * pixel written by one thread. SPPM (sppm.c) runs its own iterations and
 * threads. */
#include "render/render.h"

#include <pthread.h>
#include <stdatomic.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>
#include <time.h>
#include <unistd.h>

#include "camera/camera.h"
#include "core/clock.h"
#include "core/error.h"
#include "core/rng.h"
#include "film/film.h"
#include "film/filter.h"
#include "integrators/light.h"
#include "integrators/path.h"
#include "integrators/photon.h"
#include "integrators/sppm.h"
#include "integrators/vcm.h"
#include "integrators/whitted.h"
#include "sampling/sampler.h"
#include "sampling/warp.h"
#include "scene/scene.h"

static const struct { const char *name; CstIntegrator id; } INTEGRATOR_NAMES[] = {
    {"path", CST_INTEGRATOR_PATH},       {"path-nee", CST_INTEGRATOR_PATH_NEE},
    {"path-bsdf", CST_INTEGRATOR_PATH_BSDF}, {"mis", CST_INTEGRATOR_PATH},
    {"nee", CST_INTEGRATOR_PATH_NEE},    {"bsdf", CST_INTEGRATOR_PATH_BSDF},
    {"light", CST_INTEGRATOR_LIGHT},     {"lighttracing", CST_INTEGRATOR_LIGHT},
    {"whitted", CST_INTEGRATOR_WHITTED}, {"photon", CST_INTEGRATOR_PHOTON},
    {"sppm", CST_INTEGRATOR_SPPM},       {"bdpt", CST_INTEGRATOR_BDPT},
    {"vcm", CST_INTEGRATOR_VCM},
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
    case CST_INTEGRATOR_DEFAULT: break;
    }
    return "default";
}

CstFilter cst_filter_from_name(const char *name)
{
    if (strcmp(name, "box") == 0) return CST_FILTER_BOX;
    if (strcmp(name, "tent") == 0) return CST_FILTER_TENT;
    if (strcmp(name, "gaussian") == 0) return CST_FILTER_GAUSSIAN;
    if (strcmp(name, "mitchell") == 0) return CST_FILTER_MITCHELL;
    return CST_FILTER_DEFAULT;
}

const char *cst_filter_name(CstFilter filter)
{
    switch (filter) {
    case CST_FILTER_BOX: return "box";
    case CST_FILTER_TENT: return "tent";
    case CST_FILTER_GAUSSIAN: return "gaussian";
    case CST_FILTER_MITCHELL: return "mitchell";
    case CST_FILTER_DEFAULT: break;
    }
    return "default";
}

CstSampler cst_sampler_from_name(const char *name)
{
    if (strcmp(name, "independent") == 0) return CST_SAMPLER_INDEPENDENT;
    if (strcmp(name, "stratified") == 0) return CST_SAMPLER_STRATIFIED;
    if (strcmp(name, "sobol") == 0) return CST_SAMPLER_SOBOL;
    return CST_SAMPLER_DEFAULT;
}

const char *cst_sampler_name(CstSampler sampler)
{
    switch (sampler) {
    case CST_SAMPLER_INDEPENDENT: return "independent";
    case CST_SAMPLER_STRATIFIED: return "stratified";
    case CST_SAMPLER_SOBOL: return "sobol";
    case CST_SAMPLER_DEFAULT: break;
    }
    return "default";
}

int cst_aov_from_name(const char *name)
{
    if (strcmp(name, "albedo") == 0) return CST_AOV_ALBEDO;
    if (strcmp(name, "normal") == 0) return CST_AOV_NORMAL;
    if (strcmp(name, "depth") == 0) return CST_AOV_DEPTH;
    if (strcmp(name, "variance") == 0) return CST_AOV_VARIANCE;
    return 0;
}

/* Light paths per work unit: small enough to balance threads on small films, large
 * enough that a unit's splat list amortises its bookkeeping. Fixed, because chunk
 * boundaries decide the order in which splats are added. */
enum { LIGHT_CHUNK = 1024 };

/* What one light chunk writes: its splats and, for BDPT/VCM, its light vertices. Each on
 * cache lines of its own: the two threads trace neighbouring chunks and bump their lists'
 * counts on every splat and vertex, and with the lists packed in an array those counts
 * shared a line between cores (false sharing; docs/benchmarks.md has the figures). */
typedef struct ChunkOut {
    _Alignas(64) SplatList splats;
    VcmVertexList verts;
    Vec3 lo;      /* VCM: the lowest corner of the vertices' positions */
    size_t first; /* BDPT/VCM: where the vertices go in the iteration's array */
} ChunkOut;

/* Bucket ranges of the merging grid's parallel sort (vcm.h): a few per thread, for
 * balance; any number gives the same grid. */
enum { GRID_RANGES_MAX = 64 };

typedef struct RenderJob {
    const Scene *scene;
    Film *film;
    Camera camera;
    PathParams params;
    bool whitted; /* camera samples through whitted_li instead of path_li */
    bool photon;  /* camera samples through photon_li, reading photon_maps */
    PhotonMaps photon_maps; /* built once per render, before the first pass */
    WhittedParams whitted_params;
    CstFilter filter;
    Filter pixel_filter; /* its shape and sampling tables */
    uint64_t seed;
    CstSampler sampler;  /* camera paths' */
    uint32_t sampler_spp; /* the sample count strata divide; 0 = not known (time limit) */
    bool aov_hit;        /* albedo, normal or depth AOVs: trace the first hit for them */
    /* Work units: tiles, or chunks of LIGHT_CHUNK light paths. units is the pass's
     * count: num_tiles or num_chunks. */
    int tiles_x, tiles_y, num_tiles, num_chunks, units;
    int crop_x0, crop_x1, crop_y0, crop_y1; /* the pixels camera passes cover (settings crop) */
    /* What the pass's units are: camera tiles, light chunks, film bands of the splat merge,
     * and for BDPT/VCM between the light and the camera pass, chunks whose vertices are
     * gathered, then bucket ranges of the merging grid counted and filled. */
    enum { PASS_TILES, PASS_CHUNKS, PASS_MERGE, PASS_GATHER, PASS_GRID_COUNT, PASS_GRID_FILL } pass_kind;
    int merge_units;  /* row bands of a merge pass (SplatFrame) */
    /* light tracing, BDPT and VCM: iterations of width x height light paths */
    bool light;
    LightParams light_params;
    int iteration;     /* in progress */
    int light_paths;   /* per iteration: width x height */
    ChunkOut *chunks;  /* one per chunk, reused by every iteration */
    double *iteration_rgb; /* the iteration's image, width x height x 3 */
    double last_progress;  /* when progress was last reported: iterations can be short */
    /* BDPT / VCM only (with light = true) */
    bool vcm;
    VcmParams vcm_params;
    float vcm_radius;          /* the first iteration's merging radius */
    VcmIteration vcm_it;       /* the iteration in progress */
    uint32_t *vcm_path_count;  /* light_paths: vertices each path stored */
    uint32_t *vcm_path_start;  /* light_paths + 1 */
    VcmVertex *vcm_vertices;   /* the iteration's, concatenated */
    uint32_t *vcm_cell_of;     /* VCM: each vertex's grid bucket */
    size_t vcm_total;          /* vertices this iteration */
    int grid_ranges;
    uint32_t grid_base[GRID_RANGES_MAX + 1]; /* per range: its vertices, then the count below it */
    uint32_t *vcm_cell_start;
    VcmMergeVertex *vcm_cell_items;
    size_t vcm_cap;            /* capacity of vcm_vertices and vcm_cell_items */
    /* the pass in progress: samples [pass_first, pass_first + pass_spp) of every pixel */
    int pass_first, pass_spp;
    atomic_int next_tile;
    atomic_int tiles_done;
    /* Signalled when the last tile of a pass is done, so the reporting thread wakes at
     * once instead of at its next progress tick (which would inflate timings). */
    pthread_mutex_t lock;
    pthread_cond_t done;
} RenderJob;

/* Every ray bumps `rays`: the padding keeps the counters of neighbouring workers in the
 * array on different cache lines. Without it the two threads' increments bounced one line
 * between cores (false sharing), which cost the light tracer a third of its time
 * (docs/benchmarks.md). */
typedef struct Worker {
    RenderJob *job;
    pthread_t thread;
    uint64_t rays, nonfinite;
    char pad[64];
} Worker;

/* The AOVs of one camera sample (film.h): its first hit, traced again here so that no
 * integrator has to report it. */
static void render_aov(RenderJob *job, Worker *w, int pixel, Ray ray)
{
    SurfaceHit sh;
    ++w->rays;
    if (!scene_intersect(job->scene, &ray, &sh)) return;
    Bsdf bsdf;
    scene_bsdf(job->scene, &sh, &bsdf);
    Vec3 n = v3_dot(sh.ng, ray.d) > 0.0f ? v3_neg(sh.ng) : sh.ng;
    float z = v3_dot(v3_sub(sh.p, job->camera.origin), job->camera.forward);
    double *a = &job->film->aov[FILM_AOV_STRIDE * (size_t)pixel];
    a[0] += (double)bsdf.albedo.c[0]; a[1] += (double)bsdf.albedo.c[1]; a[2] += (double)bsdf.albedo.c[2];
    a[3] += (double)n.x; a[4] += (double)n.y; a[5] += (double)n.z;
    a[6] += (double)z;
    a[7] += 1.0;
}

static void render_tile(RenderJob *job, Worker *w, int tile)
{
    /* Tiles cover the crop; pixels keep their whole-image index (seeds, film). */
    const int W = job->film->width;
    int x0 = job->crop_x0 + (tile % job->tiles_x) * RENDER_TILE;
    int y0 = job->crop_y0 + (tile / job->tiles_x) * RENDER_TILE;
    int x1 = x0 + RENDER_TILE < job->crop_x1 ? x0 + RENDER_TILE : job->crop_x1;
    int y1 = y0 + RENDER_TILE < job->crop_y1 ? y0 + RENDER_TILE : job->crop_y1;
    for (int y = y0; y < y1; y++) {
        for (int x = x0; x < x1; x++) {
            int pixel = y * W + x;
            for (int s = job->pass_first; s < job->pass_first + job->pass_spp; s++) {
                Sampler smp;
                sampler_start(&smp, job->sampler, job->seed, (uint64_t)pixel, (uint32_t)s, job->sampler_spp);
                Vec2 uf = sampler_2d(&smp);
                Vec2 ul = sampler_2d(&smp);
                float fw;
                Vec2 fp = filter_film_position(&job->pixel_filter, x, y, uf, &fw);
                Ray ray = camera_generate_ray(&job->camera, fp.x, fp.y, ul);
                if (job->aov_hit) render_aov(job, w, pixel, ray);
                /* Photon mapping and BDPT/VCM continue from the sample's PCG32 stream. */
                Color L = job->vcm ? vcm_trace_camera(job->scene, &job->camera, &job->vcm_params,
                                                    &job->vcm_it, pixel, ray, &smp.rng, &w->rays)
                      : job->photon ? photon_li(job->scene, &job->photon_maps, ray, &smp.rng, &w->rays)
                      : job->whitted ? whitted_li(job->scene, &job->whitted_params, ray, &smp, &w->rays)
                                     : path_li(job->scene, &job->params, ray, &smp, &w->rays);
                if (!color_is_finite(L)) {
                    /* Counted and dropped as a zero sample: one NaN must not erase a pixel. */
                    w->nonfinite++;
                    L = color_s(0.0f);
                }
                if (fw != 1.0f) L = color_scale(L, fw);
                if (job->vcm) {
                    /* The iteration's image; light_merge adds the splats and files it. */
                    double *o = &job->iteration_rgb[3 * (size_t)pixel];
                    o[0] = L.c[0]; o[1] = L.c[1]; o[2] = L.c[2];
                } else {
                    film_accumulate(job->film, pixel, L.c[0], L.c[1], L.c[2]);
                }
            }
        }
    }
}

static void light_chunk(RenderJob *job, Worker *w, int chunk)
{
    SplatList *out = &job->chunks[chunk].splats;
    out->n = 0;
    int first = chunk * LIGHT_CHUNK;
    int last = first + LIGHT_CHUNK < job->light_paths ? first + LIGHT_CHUNK : job->light_paths;
    if (job->vcm) {
        VcmVertexList *verts = &job->chunks[chunk].verts;
        verts->n = 0;
        for (int i = first; i < last; i++) {
            Pcg32 rng;
            /* A stream apart from the camera path of pixel i, which uses (seed, i, iteration). */
            pcg32_seed_sample(&rng, job->seed ^ 0x6c8e9cf570932bd5ULL, (uint64_t)i, (uint64_t)job->iteration);
            size_t before = verts->n;
            vcm_trace_light(job->scene, &job->camera, &job->vcm_params, &job->vcm_it, &rng, verts, out,
                            &w->rays);
            job->vcm_path_count[i] = (uint32_t)(verts->n - before);
        }
        /* The grid's corner, reduced over the chunks by vcm_prepare (min is exact in any
         * order). */
        Vec3 lo = v3(INFINITY, INFINITY, INFINITY);
        if (job->vcm_params.merge)
            for (size_t k = 0; k < verts->n; k++) lo = v3_min(lo, verts->v[k].p);
        job->chunks[chunk].lo = lo;
    } else {
        for (int i = first; i < last; i++) {
            Pcg32 rng;
            pcg32_seed_sample(&rng, job->seed, (uint64_t)i, (uint64_t)job->iteration);
            light_trace(job->scene, &job->camera, &job->light_params, &rng, out, &w->rays);
        }
    }
    splat_list_bin(out, &job->light_params.frame); /* sets out->oom on failure, checked after the pass */
}

/* Between the light and the camera pass of a BDPT/VCM iteration: the chunks' vertex
 * lists are concatenated in chunk order (so path i's vertices are a run starting at
 * path_start[i]), and for VCM the merging grid is built over them. What is serial is
 * here: sizes, offsets and the grid's corner; the copying and sorting are passes
 * (vcm_gather_chunk, vcm_grid_range). Returns 0 on OOM. */
static int vcm_prepare(RenderJob *job, int threads)
{
    size_t total = 0;
    Vec3 lo = v3(INFINITY, INFINITY, INFINITY);
    for (int c = 0; c < job->num_chunks; c++) {
        if (job->chunks[c].verts.oom) return 0;
        job->chunks[c].first = total;
        total += job->chunks[c].verts.n;
        lo = v3_min(lo, job->chunks[c].lo);
    }
    if (total > UINT32_MAX - 1) return 0;
    if (total > job->vcm_cap) {
        size_t cap = total + total / 4;
        VcmVertex *v = realloc(job->vcm_vertices, cap * sizeof *v);
        if (!v) return 0;
        job->vcm_vertices = v;
        VcmMergeVertex *items = realloc(job->vcm_cell_items, cap * sizeof *items);
        if (!items) return 0;
        job->vcm_cell_items = items;
        uint32_t *starts = realloc(job->vcm_cell_start, (cap + 1) * sizeof *starts);
        if (!starts) return 0;
        job->vcm_cell_start = starts;
        uint32_t *cell_of = realloc(job->vcm_cell_of, cap * sizeof *cell_of);
        if (!cell_of) return 0;
        job->vcm_cell_of = cell_of;
        job->vcm_cap = cap;
    }
    job->vcm_total = total;
    uint32_t *ps = job->vcm_path_start;
    ps[0] = 0;
    for (int i = 0; i < job->light_paths; i++) ps[i + 1] = ps[i] + job->vcm_path_count[i];
    job->vcm_it.vertices = job->vcm_vertices;
    job->vcm_it.path_start = ps;
    job->vcm_it.cells = 0;
    job->grid_ranges = 0;
    if (job->vcm_params.merge && total > 0) {
        vcm_grid_init(&job->vcm_it, lo, (uint32_t)total, job->vcm_cell_start, job->vcm_cell_items);
        int ranges = 4 * threads;
        job->grid_ranges = ranges < 1 ? 1 : ranges > GRID_RANGES_MAX ? GRID_RANGES_MAX : ranges;
    }
    return 1;
}

static void vcm_gather_chunk(RenderJob *job, int chunk)
{
    const VcmVertexList *l = &job->chunks[chunk].verts;
    size_t first = job->chunks[chunk].first;
    if (l->n) memcpy(job->vcm_vertices + first, l->v, l->n * sizeof *l->v);
    if (job->grid_ranges)
        for (size_t k = 0; k < l->n; k++) job->vcm_cell_of[first + k] = vcm_grid_cell(&job->vcm_it, l->v[k].p);
}

/* Bucket range `range` of the merging grid: counted in a PASS_GRID_COUNT, sorted in a
 * PASS_GRID_FILL. */
static void vcm_grid_range(RenderJob *job, int range)
{
    if (job->pass_kind == PASS_GRID_COUNT)
        job->grid_base[range] = vcm_grid_count(&job->vcm_it, job->vcm_cell_of, job->vcm_total, range,
                                               job->grid_ranges, job->vcm_cell_start);
    else
        vcm_grid_fill(&job->vcm_it, job->vcm_cell_of, job->vcm_total, range, job->grid_ranges,
                      job->grid_base[range], job->vcm_cell_start, job->vcm_cell_items);
}

/* Adds the finished iteration to the film as one sample per pixel, for the rows of one
 * band (SplatFrame). The light tracer's pixel estimate is (W H / paths) times the sum of
 * its splats (splats are per unit film, camera.c), and W H / paths = 1 with one path per
 * pixel. Adding the iteration, not the splats, as the sample keeps the film's sum of
 * squares a per-pixel variance across iterations; splats are summed in chunk order and,
 * within a chunk, in the order they were made (splat_list_bin is stable), so the
 * floating-point sums depend neither on which thread traced which chunk nor on which
 * thread merged which band. */
static void light_merge_band(RenderJob *job, int unit)
{
    const SplatFrame *fr = &job->light_params.frame;
    const size_t pixels = (size_t)fr->width * (size_t)fr->height;
    const double scale = (double)pixels / (double)job->light_paths;
    size_t lo = (size_t)unit * (size_t)fr->band_rows * (size_t)fr->width;
    size_t hi = lo + (size_t)fr->band_rows * (size_t)fr->width;
    if (hi > pixels) hi = pixels;
    double *rgb = job->iteration_rgb;
    /* BDPT/VCM: the camera pass already wrote its pixel samples there. */
    if (!job->vcm) memset(rgb + 3 * lo, 0, 3 * (hi - lo) * sizeof *rgb);
    for (int c = 0; c < job->num_chunks; c++) film_add_splats_band(&job->chunks[c].splats, fr, rgb, scale, unit);
    for (size_t p = lo; p < hi; p++)
        film_accumulate(job->film, (int)p, rgb[3 * p], rgb[3 * p + 1], rgb[3 * p + 2]);
}

static void *worker_main(void *arg)
{
    Worker *w = arg;
    RenderJob *job = w->job;
    for (;;) {
        int tile = atomic_fetch_add(&job->next_tile, 1);
        if (tile >= job->units) break;
        if (job->pass_kind == PASS_CHUNKS) light_chunk(job, w, tile);
        else if (job->pass_kind == PASS_MERGE) light_merge_band(job, tile);
        else if (job->pass_kind == PASS_GATHER) vcm_gather_chunk(job, tile);
        else if (job->pass_kind == PASS_GRID_COUNT || job->pass_kind == PASS_GRID_FILL) vcm_grid_range(job, tile);
        else render_tile(job, w, tile);
        if (atomic_fetch_add(&job->tiles_done, 1) + 1 == job->units) {
            pthread_mutex_lock(&job->lock);
            pthread_cond_broadcast(&job->done);
            pthread_mutex_unlock(&job->lock);
        }
    }
    return NULL;
}

/* Waits until the pass is done or `seconds` have passed. */
static void wait_for_pass(RenderJob *job, double seconds)
{
    struct timespec ts;
    clock_gettime(CLOCK_REALTIME, &ts);
    long ns = ts.tv_nsec + (long)(seconds * 1e9);
    ts.tv_sec += ns / 1000000000L;
    ts.tv_nsec = ns % 1000000000L;
    pthread_mutex_lock(&job->lock);
    while (atomic_load(&job->tiles_done) < job->units)
        if (pthread_cond_timedwait(&job->done, &job->lock, &ts) != 0) break;
    pthread_mutex_unlock(&job->lock);
}

/* Runs one pass over all tiles with `threads` workers; the calling thread reports
 * progress. Returns 0 on thread-creation failure. */
static int run_pass(RenderJob *job, Worker *workers, int threads, const CstRenderSettings *st,
                    double t0, double done_before, double pass_fraction)
{
    atomic_store(&job->next_tile, 0);
    atomic_store(&job->tiles_done, 0);
    int started = 0;
    if (threads > job->units) threads = job->units; /* idle workers would only cost their creation */
    for (; started < threads; started++)
        if (pthread_create(&workers[started].thread, NULL, worker_main, &workers[started]) != 0) break;
    if (started == 0) return 0;
    while (atomic_load(&job->tiles_done) < job->units) {
        wait_for_pass(job, 0.1);
        /* Each light-tracing iteration is a pass of its own and may take far less than
         * 0.1 s: keep the reports about 10 a second. */
        if (st->progress && job->light && clock_seconds() - job->last_progress < 0.1) continue;
        if (st->progress) {
            job->last_progress = clock_seconds();
            double f = done_before + pass_fraction * atomic_load(&job->tiles_done) / job->units;
            if (st->time_limit > 0.0) {
                double ft = (clock_seconds() - t0) / st->time_limit;
                f = ft > f ? ft : f;
            }
            st->progress(st->progress_user, f > 1.0 ? 1.0 : f, clock_seconds() - t0);
        }
    }
    for (int i = 0; i < started; i++) pthread_join(workers[i].thread, NULL);
    return 1;
}

/* Samples [first, first + count) of every pixel: one pass over the tiles, or for light
 * tracing `count` iterations, each merged into the film before the next starts (the
 * iteration is the light tracer's pass unit for progress and time limits). */
static CstStatus run_samples(RenderJob *job, Worker *workers, int threads, const CstRenderSettings *st,
                             double t0, int first, int count, double done_before, double fraction)
{
    if (!job->light) {
        job->pass_first = first;
        job->pass_spp = count;
        job->units = job->num_tiles;
        job->pass_kind = PASS_TILES;
        return run_pass(job, workers, threads, st, t0, done_before, fraction) ? CST_OK : CST_ERR_INTERNAL;
    }
    for (int k = 0; k < count; k++) {
        job->iteration = first + k;
        double f0 = done_before + fraction * k / count, f1 = fraction / count;
        if (job->vcm)
            vcm_iteration_init(&job->vcm_it, &job->vcm_params, &job->camera, job->light_paths,
                               job->vcm_radius, job->iteration);
        job->units = job->num_chunks;
        job->pass_kind = PASS_CHUNKS;
        if (!run_pass(job, workers, threads, st, t0, f0, job->vcm ? 0.5 * f1 : f1))
            return CST_ERR_INTERNAL;
        for (int c = 0; c < job->num_chunks; c++)
            if (job->chunks[c].splats.oom) return CST_ERR_OOM;
        if (job->vcm) {
            if (!vcm_prepare(job, threads)) return CST_ERR_OOM;
            job->units = job->num_chunks;
            job->pass_kind = PASS_GATHER;
            if (!run_pass(job, workers, threads, st, t0, f0 + 0.5 * f1, 0.0)) return CST_ERR_INTERNAL;
            if (job->grid_ranges) {
                job->units = job->grid_ranges;
                job->pass_kind = PASS_GRID_COUNT;
                if (!run_pass(job, workers, threads, st, t0, f0 + 0.5 * f1, 0.0)) return CST_ERR_INTERNAL;
                vcm_grid_bases(job->grid_base, job->grid_ranges);
                job->pass_kind = PASS_GRID_FILL;
                if (!run_pass(job, workers, threads, st, t0, f0 + 0.5 * f1, 0.0)) return CST_ERR_INTERNAL;
            }
            /* One camera path per pixel: sample `iteration` of every pixel. */
            job->pass_first = job->iteration;
            job->pass_spp = 1;
            job->units = job->num_tiles;
            job->pass_kind = PASS_TILES;
            if (!run_pass(job, workers, threads, st, t0, f0 + 0.5 * f1, 0.5 * f1))
                return CST_ERR_INTERNAL;
        }
        job->units = job->merge_units;
        job->pass_kind = PASS_MERGE;
        if (!run_pass(job, workers, threads, st, t0, f0 + f1, 0.0)) return CST_ERR_INTERNAL;
    }
    return CST_OK;
}

static void light_free(RenderJob *job)
{
    if (job->chunks)
        for (int c = 0; c < job->num_chunks; c++) {
            splat_list_free(&job->chunks[c].splats);
            vcm_vertex_list_free(&job->chunks[c].verts);
        }
    free(job->chunks);
    free(job->iteration_rgb);
    free(job->vcm_path_count);
    free(job->vcm_path_start);
    free(job->vcm_vertices);
    free(job->vcm_cell_start);
    free(job->vcm_cell_of);
    free(job->vcm_cell_items);
    job->chunks = NULL;
    job->iteration_rgb = NULL;
    job->vcm_path_count = job->vcm_path_start = NULL;
    job->vcm_vertices = NULL;
    job->vcm_cell_start = NULL;
    job->vcm_cell_of = NULL;
    job->vcm_cell_items = NULL;
}

/* Per-render buffers of the light tracer: a splat list per chunk, sized for a few
 * connections per path (they grow if a scene needs more, then stay), and the iteration
 * image. Returns 0 on OOM. */
static int light_alloc(RenderJob *job)
{
    size_t pixels = (size_t)job->film->width * (size_t)job->film->height;
    /* Zeroed: BDPT/VCM camera passes over a crop never write the pixels outside it. */
    job->iteration_rgb = calloc(3 * pixels, sizeof *job->iteration_rgb);
    job->chunks = aligned_alloc(_Alignof(ChunkOut), (size_t)job->num_chunks * sizeof *job->chunks);
    if (!job->iteration_rgb || !job->chunks) return 0;
    memset(job->chunks, 0, (size_t)job->num_chunks * sizeof *job->chunks);
    for (int c = 0; c < job->num_chunks; c++)
        if (!splat_list_init(&job->chunks[c].splats, 4 * (size_t)LIGHT_CHUNK)) return 0;
    if (job->vcm) {
        job->vcm_path_count = calloc(pixels, sizeof *job->vcm_path_count);
        job->vcm_path_start = calloc(pixels + 1, sizeof *job->vcm_path_start);
        if (!job->vcm_path_count || !job->vcm_path_start) return 0;
    }
    return 1;
}

CstStatus cst_render(const CstScene *scene, const CstRenderSettings *settings, CstFilm **out,
                     CstRenderStats *stats, CstError *err)
{
    *out = NULL;
    CstRenderSettings st;
    cst_render_settings_resolve(scene, settings, &st);
    if (st.width <= 0 || st.height <= 0 || st.width > 65536 || st.height > 65536)
        return cst_fail(err, CST_ERR_INVALID_ARG, "image size %dx%d: expected 1..65536 in each dimension",
                        st.width, st.height);
    if (st.spp < 0 || st.time_limit < 0.0)
        return cst_fail(err, CST_ERR_INVALID_ARG, "spp and time limit must be positive");
    if (!scene->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene not committed");
    if (!(0 <= st.crop[0] && st.crop[0] < st.crop[1] && st.crop[1] <= st.width && 0 <= st.crop[2] &&
          st.crop[2] < st.crop[3] && st.crop[3] <= st.height))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "crop [%d, %d) x [%d, %d): expected 0 <= x0 < x1 <= %d and 0 <= y0 < y1 <= %d (the "
                        "image's width and height)",
                        st.crop[0], st.crop[1], st.crop[2], st.crop[3], st.width, st.height);

    if (st.integrator == CST_INTEGRATOR_LIGHT && scene->camera.ortho_height > 0.0f)
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "the light tracer cannot render through an orthographic camera (its rays are "
                        "parallel, so no light path can connect to it); expected a pinhole or thin-lens "
                        "camera, or another integrator");
    if ((st.aovs & FILM_AOV_FIRST_HIT) &&
        (st.integrator == CST_INTEGRATOR_LIGHT || st.integrator == CST_INTEGRATOR_SPPM))
        return cst_fail(err, CST_ERR_UNSUPPORTED,
                        "the albedo, normal and depth AOVs come from camera rays, which the %s integrator "
                        "does not trace; expected path, path-nee, path-bsdf, whitted, photon, bdpt or vcm "
                        "(the variance AOV works with every integrator)",
                        cst_integrator_name(st.integrator));
    Film *film = film_create(st.width, st.height);
    if (film && !film_set_output(film, st.aovs, st.exposure, st.png_linear)) {
        film_destroy(film);
        film = NULL;
    }
    Worker *workers = calloc((size_t)st.threads, sizeof *workers);
    RenderJob *job = calloc(1, sizeof *job);
    if (!film || !workers || !job) {
        film_destroy(film); free(workers); free(job);
        return cst_fail(err, CST_ERR_OOM, "out of memory for a %dx%d film", st.width, st.height);
    }
    pthread_mutex_init(&job->lock, NULL);
    pthread_cond_init(&job->done, NULL);
    job->scene = scene;
    job->film = film;
    camera_init(&job->camera, &scene->camera, st.width, st.height);
    if (scene->camera_mirror) camera_mirror_x(&job->camera);
    job->params.mode = st.integrator == CST_INTEGRATOR_PATH_NEE ? PATH_NEE
                     : st.integrator == CST_INTEGRATOR_PATH_BSDF ? PATH_BSDF : PATH_MIS;
    job->params.max_depth = st.max_depth;
    job->whitted = st.integrator == CST_INTEGRATOR_WHITTED;
    job->whitted_params.max_depth = st.max_depth;
    job->whitted_params.light_samples = 1;
    job->params.rr_depth = st.rr_depth;
    job->filter = st.filter;
    filter_init(&job->pixel_filter, st.filter);
    job->seed = st.seed;
    job->sampler = st.sampler;
    /* A time limit without a sample cap: the count is not known, strata cannot be laid out. */
    job->sampler_spp = (uint32_t)st.spp;
    job->aov_hit = (st.aovs & FILM_AOV_FIRST_HIT) != 0;
    job->crop_x0 = st.crop[0]; job->crop_x1 = st.crop[1];
    job->crop_y0 = st.crop[2]; job->crop_y1 = st.crop[3];
    job->tiles_x = (st.crop[1] - st.crop[0] + RENDER_TILE - 1) / RENDER_TILE;
    job->tiles_y = (st.crop[3] - st.crop[2] + RENDER_TILE - 1) / RENDER_TILE;
    job->num_tiles = job->tiles_x * job->tiles_y;
    for (int i = 0; i < st.threads; i++) workers[i].job = job;
    if (st.integrator == CST_INTEGRATOR_LIGHT || st.integrator == CST_INTEGRATOR_BDPT ||
        st.integrator == CST_INTEGRATOR_VCM) {
        job->light = true;
        if (st.integrator != CST_INTEGRATOR_LIGHT) {
            job->vcm = true;
            job->vcm_params.merge = st.integrator == CST_INTEGRATOR_VCM;
            job->vcm_params.max_depth = st.max_depth;
            job->vcm_params.rr_depth = st.rr_depth;
            job->vcm_radius = st.photon_radius > 0.0 ? (float)st.photon_radius : vcm_default_radius(scene);
            if (!(st.photon_radius >= 0.0) || !(job->vcm_radius > 0.0f) || !(job->vcm_radius < INFINITY)) {
                film_destroy(film); free(workers); free(job);
                return cst_fail(err, CST_ERR_INVALID_ARG, "merging radius %g: expected a positive value (0 = automatic)",
                                st.photon_radius);
            }
        }
        job->light_params.max_depth = st.max_depth;
        job->light_params.rr_depth = st.rr_depth;
        /* One light path per pixel per iteration; 65536^2 pixels would overflow int. */
        size_t pixels = (size_t)st.width * (size_t)st.height;
        if (pixels > (size_t)INT32_MAX - LIGHT_CHUNK) {
            film_destroy(film); free(workers); free(job);
            return cst_fail(err, CST_ERR_INVALID_ARG,
                            "image size %dx%d: too many pixels for the light tracer (at most %d)",
                            st.width, st.height, INT32_MAX - LIGHT_CHUNK);
        }
        job->light_paths = (int)pixels;
        job->num_chunks = (job->light_paths + LIGHT_CHUNK - 1) / LIGHT_CHUNK;
        job->light_params.frame = job->vcm_params.frame = splat_frame(st.width, st.height, st.filter);
        job->merge_units = job->light_params.frame.bands;
        if (!light_alloc(job)) {
            light_free(job);
            film_destroy(film); free(workers); free(job);
            return cst_fail(err, CST_ERR_OOM, "out of memory for light-tracing buffers (%dx%d)",
                            st.width, st.height);
        }
    }

    CstStatus status = CST_OK;
    double t0 = clock_seconds();
    uint64_t photon_rays = 0;
    if (st.integrator == CST_INTEGRATOR_PHOTON) {
        /* The photon pass is part of the render's time (and of a time limit's budget). It
         * runs single-threaded from the render seed, so the maps, and with them the image,
         * do not depend on the thread count. */
        PhotonParams pp = {st.photons, (float)st.photon_radius, st.max_depth, st.rr_depth, st.seed};
        job->photon = true;
        if (st.photons < 0 || !(st.photon_radius >= 0.0) || !((float)st.photon_radius < INFINITY)) {
            status = CST_ERR_INVALID_ARG;
            cst_fail(err, status, "photon count %d and radius %g: expected positive values (0 = default)",
                     st.photons, st.photon_radius);
        } else {
            status = photon_maps_build(scene, &job->camera, &pp, &job->photon_maps, &photon_rays, err);
        }
        if (status != CST_OK) {
            pthread_mutex_destroy(&job->lock);
            pthread_cond_destroy(&job->done);
            film_destroy(film); free(workers); free(job);
            return status;
        }
    }
    SppmResult sppm_res = {0};
    if (st.integrator == CST_INTEGRATOR_SPPM) {
        /* SPPM runs its own iterations and threads (sppm.c: photons reach each visible
         * point in photon order whatever the thread count); spp is the iteration count. */
        SppmParams sp = {st.spp, st.time_limit, st.photons, (float)st.photon_radius, st.max_depth,
                         st.rr_depth, st.filter, st.seed, st.progress, st.progress_user, st.threads};
        if (st.photons < 0 || !(st.photon_radius >= 0.0) || !((float)st.photon_radius < INFINITY))
            status = cst_fail(err, CST_ERR_INVALID_ARG,
                              "photon count %d and radius %g: expected positive values (0 = default)",
                              st.photons, st.photon_radius);
        else
            status = sppm_render(scene, &job->camera, &sp, film, &sppm_res, &photon_rays, err);
        if (status != CST_OK) {
            pthread_mutex_destroy(&job->lock);
            pthread_cond_destroy(&job->done);
            film_destroy(film); free(workers); free(job);
            return status;
        }
    } else if (st.time_limit <= 0.0) {
        /* Fixed sample count: one pass, so accumulation order is fixed. */
        status = run_samples(job, workers, st.threads, &st, t0, 0, st.spp, 0.0, 1.0);
        if (status == CST_OK) film->spp = st.spp;
    } else {
        /* Time budget: passes of growing size until the next one would not fit (or the
         * sample cap is reached). Every pixel always holds the same number of samples. */
        int pass = 1;
        while (status == CST_OK) {
            if (st.spp > 0 && film->spp + pass > st.spp) pass = st.spp - film->spp;
            if (pass <= 0) break;
            double pass_t0 = clock_seconds();
            double frac = st.spp > 0 ? (double)film->spp / st.spp : 0.0;
            status = run_samples(job, workers, st.threads, &st, t0, film->spp, pass, frac,
                                 st.spp > 0 ? (double)pass / st.spp : 0.0);
            if (status != CST_OK) break;
            film->spp += pass;
            double now = clock_seconds(), pass_time = now - pass_t0;
            double left = st.time_limit - (now - t0);
            if (left <= 0.0) break;
            /* Next pass: the largest of 2x, x, x/2, ... that is predicted to fit in the time left. */
            double per_spp = pass_time / pass;
            int next = pass * 2;
            while (next > 1 && per_spp * next > left) next /= 2;
            if (per_spp * next > left) break;
            pass = next;
        }
    }
    double seconds = clock_seconds() - t0;
    pthread_mutex_destroy(&job->lock);
    pthread_cond_destroy(&job->done);
    uint64_t splats_nonfinite = 0;
    if (job->light)
        for (int c = 0; c < job->num_chunks; c++) splats_nonfinite += job->chunks[c].splats.nonfinite;
    light_free(job);
    photon_maps_free(&job->photon_maps);
    if (status != CST_OK) {
        film_destroy(film);
        free(workers);
        free(job);
        if (status == CST_ERR_OOM)
            return cst_fail(err, status, "out of memory for light-tracing splats (%dx%d)", st.width, st.height);
        return cst_fail(err, status, "could not start render threads");
    }
    const int cw = st.crop[1] - st.crop[0], ch = st.crop[3] - st.crop[2];
    if (cw != st.width || ch != st.height) {
        /* Light paths were traced for the whole image (their splats land anywhere), camera
         * passes for the crop only: keep the crop. */
        Film *cropped = film_crop(film, st.crop[0], st.crop[2], cw, ch);
        film_destroy(film);
        film = cropped;
        if (!film) {
            free(workers);
            free(job);
            return cst_fail(err, CST_ERR_OOM, "out of memory for the %dx%d crop", cw, ch);
        }
    }
    if (st.progress) st.progress(st.progress_user, 1.0, seconds);
    if (stats) {
        memset(stats, 0, sizeof *stats);
        stats->seconds = seconds;
        /* SPPM: the film holds one final estimate per pixel; spp reports the iterations. */
        stats->spp = st.integrator == CST_INTEGRATOR_SPPM ? sppm_res.iterations : film->spp;
        stats->threads = st.threads;
        stats->width = cw;
        stats->height = ch;
        stats->integrator = st.integrator;
        stats->filter = st.filter;
        /* Light tracing traces width x height light paths per iteration, whatever the crop
         * (and BDPT/VCM as many light paths as there are pixels); camera passes cover the crop. */
        uint64_t per_spp = job->light || st.integrator == CST_INTEGRATOR_SPPM
                               ? (uint64_t)st.width * (uint64_t)st.height : (uint64_t)cw * (uint64_t)ch;
        stats->samples = (uint64_t)stats->spp * per_spp;
        stats->nonfinite = splats_nonfinite + sppm_res.nonfinite;
        stats->rays = photon_rays;
        for (int i = 0; i < st.threads; i++) {
            stats->rays += workers[i].rays;
            stats->nonfinite += workers[i].nonfinite;
        }
    }
    free(workers);
    free(job);
    *out = film;
    return CST_OK;
}
