/* Ray sets of the acceleration benchmark, generated exactly as /work/shared/bench/RAYSETS.md
 * specifies: IEEE double arithmetic in the written order (this file is compiled with
 * -ffp-contract=off so no multiply-add is fused), rounded to float32 at the end. */
#include "raysets.h"

#include <math.h>
#include <pthread.h>
#include <stdatomic.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/clock.h"
#include "core/error.h"
#include "core/rng.h"
#include "scene/mesh_import.h"
#include "scene/scene.h"

/* The double nearest pi (M_PI is not in strict C17). */
#define RAYSET_PI 3.14159265358979323846

/* ------------------------------------------------------------ double vectors */

typedef struct D3 { double x, y, z; } D3;

static D3 d3(double x, double y, double z) { D3 r = {x, y, z}; return r; }
static D3 d3_of(Vec3 v) { return d3((double)v.x, (double)v.y, (double)v.z); }
static D3 d3_of_array(const double a[3]) { return d3(a[0], a[1], a[2]); }
static D3 d3_sub(D3 a, D3 b) { return d3(a.x - b.x, a.y - b.y, a.z - b.z); }
static double d3_dot(D3 a, D3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
/* cross(a,b) = (a.y b.z - a.z b.y, a.z b.x - a.x b.z, a.x b.y - a.y b.x) */
static D3 d3_cross(D3 a, D3 b)
{
    return d3(a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x);
}
/* Each component divided by sqrt(x x + y y + z z). */
static D3 d3_normalize(D3 v)
{
    double len = sqrt(v.x * v.x + v.y * v.y + v.z * v.z);
    return d3(v.x / len, v.y / len, v.z / len);
}
static Vec3 d3_to_float(D3 v) { return v3((float)v.x, (float)v.y, (float)v.z); }

/* ------------------------------------------------------------ scenes */

void rayset_scene_free(RaysetScene *s)
{
    if (!s) return;
    free(s->positions);
    free(s->tri_indices);
    memset(s, 0, sizeof *s);
}

static CstStatus rayset_scene_alloc(RaysetScene *s, int num_positions, int num_tris, CstError *err)
{
    s->positions = malloc((size_t)(num_positions > 0 ? num_positions : 1) * sizeof *s->positions);
    s->tri_indices = malloc((size_t)(num_tris > 0 ? num_tris : 1) * 3 * sizeof *s->tri_indices);
    if (!s->positions || !s->tri_indices) {
        rayset_scene_free(s);
        return cst_fail(err, CST_ERR_OOM, "out of memory for a %d-triangle ray-set scene", num_tris);
    }
    s->num_positions = num_positions;
    s->num_tris = num_tris;
    return CST_OK;
}

/* bbox over the triangles' vertices (for the meshes of RAYSETS.md the same as over all
 * vertices: see meshes/README.md) and diag = |max - min|, in double. */
static void rayset_scene_bbox(const RaysetScene *s, D3 *lo, D3 *hi, double *diag)
{
    *lo = d3(HUGE_VAL, HUGE_VAL, HUGE_VAL); /* double infinities: INFINITY is a float */
    *hi = d3(-HUGE_VAL, -HUGE_VAL, -HUGE_VAL);
    for (int i = 0; i < 3 * s->num_tris; i++) {
        D3 p = d3_of(s->positions[s->tri_indices[i]]);
        lo->x = fmin(lo->x, p.x); lo->y = fmin(lo->y, p.y); lo->z = fmin(lo->z, p.z);
        hi->x = fmax(hi->x, p.x); hi->y = fmax(hi->y, p.y); hi->z = fmax(hi->z, p.z);
    }
    D3 e = d3_sub(*hi, *lo);
    *diag = s->num_tris > 0 ? sqrt(e.x * e.x + e.y * e.y + e.z * e.z) : 0.0;
}

/* RAYSETS.md "Camera", meshes: look = bbox centre, eye = look + (0, 0, 1.25 diag),
 * up = +y, vfov 40 degrees, 1024 x 1024. */
static void rayset_scene_mesh_camera(RaysetScene *s)
{
    D3 lo, hi;
    rayset_scene_bbox(s, &lo, &hi, &s->diag);
    RaysetCamera *c = &s->camera;
    c->look[0] = (lo.x + hi.x) / 2.0;
    c->look[1] = (lo.y + hi.y) / 2.0;
    c->look[2] = (lo.z + hi.z) / 2.0;
    c->eye[0] = c->look[0] + 0.0;
    c->eye[1] = c->look[1] + 0.0;
    c->eye[2] = c->look[2] + 1.25 * s->diag;
    c->up[0] = 0.0; c->up[1] = 1.0; c->up[2] = 0.0;
    c->vfov_deg = 40.0;
    c->width = c->height = 1024;
}

CstStatus rayset_scene_cornell(RaysetScene *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    CstScene *scene;
    CstStatus st = cst_scene_create_cornell_box(&scene, err);
    if (st != CST_OK) return st;
    st = rayset_scene_alloc(out, scene->num_positions, scene->num_triangles, err);
    if (st == CST_OK) {
        memcpy(out->positions, scene->positions, (size_t)scene->num_positions * sizeof *out->positions);
        memcpy(out->tri_indices, scene->tri_indices, (size_t)scene->num_triangles * 3 * sizeof *out->tri_indices);
        snprintf(out->name, sizeof out->name, "cornell");
        D3 lo, hi;
        rayset_scene_bbox(out, &lo, &hi, &out->diag);
        /* RAYSETS.md "Camera", Cornell box: the published camera, not the scene's float copy. */
        RaysetCamera c = {{278.0, 273.0, -800.0}, {278.0, 273.0, 0.0}, {0.0, 1.0, 0.0}, 39.3077, 512, 512};
        out->camera = c;
    }
    cst_scene_destroy(scene);
    return st;
}

CstStatus rayset_scene_mesh(const char *path, RaysetScene *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    ImportedMesh m;
    memset(&m, 0, sizeof m);
    CstStatus st = mesh_import(path, &m, err);
    if (st != CST_OK) return st;
    if (m.num_triangles <= 0) {
        mesh_import_free(&m);
        return cst_fail(err, CST_ERR_INVALID_ARG, "%s: no triangles", path);
    }
    st = rayset_scene_alloc(out, m.num_vertices, m.num_triangles, err);
    if (st == CST_OK) {
        memcpy(out->positions, m.positions, (size_t)m.num_vertices * sizeof *out->positions);
        memcpy(out->tri_indices, m.indices, (size_t)m.num_triangles * 3 * sizeof *out->tri_indices);
        const char *base = strrchr(path, '/');
        base = base ? base + 1 : path;
        size_t stem = strcspn(base, ".");
        snprintf(out->name, sizeof out->name, "%.*s", (int)(stem < 63 ? stem : 63), base);
        rayset_scene_mesh_camera(out);
    }
    mesh_import_free(&m);
    return st;
}

/* Midpoint table of one subdivision level: open addressing on the unordered vertex pair. */
typedef struct MidTable {
    uint64_t *keys; /* (min << 32 | max) + 1; 0 = empty */
    int32_t *vals;
    size_t mask;
} MidTable;

static size_t mid_hash(uint64_t k) { return (size_t)mix64(k); }

CstStatus rayset_scene_bumpy_ball(int levels, RaysetScene *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    if (levels < 0 || levels > 9)
        return cst_fail(err, CST_ERR_INVALID_ARG, "bumpy ball: %d subdivision levels (0..9)", levels);
    int num_faces = 20 << (2 * levels);
    int num_verts = 10 * (1 << (2 * levels)) + 2;
    D3 *p = malloc((size_t)num_verts * sizeof *p);
    int32_t *fa = malloc((size_t)num_faces * 3 * sizeof *fa);
    int32_t *fb = malloc((size_t)num_faces * 3 * sizeof *fb);
    size_t cap = 1;
    while (cap < (size_t)num_faces * 4) cap <<= 1; /* edges of the last level: 1.5 x faces */
    MidTable mt = {calloc(cap, sizeof(uint64_t)), malloc(cap * sizeof(int32_t)), cap - 1};
    CstStatus st = CST_OK;
    if (!p || !fa || !fb || !mt.keys || !mt.vals) {
        st = cst_fail(err, CST_ERR_OOM, "out of memory for the bumpy ball");
        goto done;
    }
    /* 1. Base icosahedron, unit vectors. */
    const double t = (1.0 + sqrt(5.0)) / 2.0;
    const double base[12][3] = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                                {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
    const int32_t faces[20][3] = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                                  {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                                  {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                                  {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
    const double len = sqrt(1.0 + t * t);
    for (int i = 0; i < 12; i++) p[i] = d3(base[i][0] / len, base[i][1] / len, base[i][2] / len);
    memcpy(fa, faces, sizeof faces);
    int nv = 12, nf = 20;
    /* 2. Subdivide: midpoints requested ab, bc, ca; faces (a,ab,ca) (b,bc,ab) (c,ca,bc) (ab,bc,ca). */
    for (int level = 0; level < levels; level++) {
        memset(mt.keys, 0, cap * sizeof(uint64_t));
        for (int f = 0; f < nf; f++) {
            int32_t v[3] = {fa[3 * f], fa[3 * f + 1], fa[3 * f + 2]}, mid[3];
            for (int e = 0; e < 3; e++) {
                int32_t i = v[e], j = v[(e + 1) % 3];
                uint64_t key = (((uint64_t)(uint32_t)(i < j ? i : j) << 32) | (uint32_t)(i < j ? j : i)) + 1u;
                size_t h = mid_hash(key) & mt.mask;
                while (mt.keys[h] && mt.keys[h] != key) h = (h + 1) & mt.mask;
                if (!mt.keys[h]) {
                    D3 m = d3(p[i].x + p[j].x, p[i].y + p[j].y, p[i].z + p[j].z);
                    p[nv] = d3_normalize(m);
                    mt.keys[h] = key;
                    mt.vals[h] = nv++;
                }
                mid[e] = mt.vals[h];
            }
            int32_t ab = mid[0], bc = mid[1], ca = mid[2];
            int32_t nfs[12] = {v[0], ab, ca, v[1], bc, ab, v[2], ca, bc, ab, bc, ca};
            memcpy(&fb[12 * f], nfs, sizeof nfs);
        }
        nf *= 4;
        int32_t *tmp = fa; fa = fb; fb = tmp;
    }
    /* 3. Displacement: PCG32 (42, 54), one draw per vertex in index order. */
    if ((st = rayset_scene_alloc(out, nv, nf, err)) != CST_OK) goto done;
    Pcg32 rng;
    pcg32_seed(&rng, 42u, 54u);
    for (int i = 0; i < nv; i++) {
        double u = (double)(pcg32_next(&rng) >> 8) * 0x1p-24;
        double x = p[i].x, y = p[i].y, z = p[i].z;
        double radius = 1.0 + 0.15 * sin(7.0 * x) * sin(7.0 * y) * sin(7.0 * z) + 0.002 * (2.0 * u - 1.0);
        out->positions[i] = d3_to_float(d3(x * radius, y * radius, z * radius));
    }
    memcpy(out->tri_indices, fa, (size_t)nf * 3 * sizeof *fa);
    snprintf(out->name, sizeof out->name, "bumpyball%d", levels);
    rayset_scene_mesh_camera(out);
done:
    free(p);
    free(fa);
    free(fb);
    free(mt.keys);
    free(mt.vals);
    return st;
}

CstStatus rayset_scene_add_stadium(RaysetScene *s, CstError *err)
{
    D3 lo, hi;
    double diag;
    rayset_scene_bbox(s, &lo, &hi, &diag);
    D3 c = d3((lo.x + hi.x) / 2.0, (lo.y + hi.y) / 2.0, (lo.z + hi.z) / 2.0);
    double h = RAYSET_STADIUM_SCALE * diag;
    Vec3 *pos = realloc(s->positions, (size_t)(s->num_positions + 8) * sizeof *pos);
    if (!pos) return cst_fail(err, CST_ERR_OOM, "out of memory for the stadium");
    s->positions = pos;
    int32_t *idx = realloc(s->tri_indices, (size_t)(s->num_tris + 12) * 3 * sizeof *idx);
    if (!idx) return cst_fail(err, CST_ERR_OOM, "out of memory for the stadium");
    s->tri_indices = idx;
    /* Corner k has x = +h if bit 0, y if bit 1, z if bit 2. */
    int v0 = s->num_positions;
    for (int k = 0; k < 8; k++)
        pos[v0 + k] = d3_to_float(d3(c.x + ((k & 1) ? h : -h), c.y + ((k & 2) ? h : -h), c.z + ((k & 4) ? h : -h)));
    /* Six faces as quads of corner numbers, two triangles each (v0,v1,v2), (v0,v2,v3). */
    static const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                    {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    int32_t *t = &idx[3 * s->num_tris];
    for (int q = 0; q < 6; q++) {
        const int *k = quads[q];
        int32_t tri[6] = {v0 + k[0], v0 + k[1], v0 + k[2], v0 + k[0], v0 + k[2], v0 + k[3]};
        memcpy(&t[6 * q], tri, sizeof tri);
    }
    s->num_positions += 8;
    s->num_tris += 12;
    char name[64];
    snprintf(name, sizeof name, "stadium+%.50s", s->name);
    memcpy(s->name, name, sizeof name);
    return CST_OK;
}

/* ------------------------------------------------------------ ray generation */

Ray *rayset_primary(const RaysetScene *s, size_t *count)
{
    const RaysetCamera *c = &s->camera;
    size_t w = (size_t)c->width, h = (size_t)c->height;
    *count = 0;
    Ray *rays = malloc(w * h * sizeof *rays);
    if (!rays) return NULL;
    D3 eye = d3_of_array(c->eye), look = d3_of_array(c->look), up = d3_of_array(c->up);
    D3 f = d3_normalize(d3_sub(look, eye));
    D3 r = d3_normalize(d3_cross(f, up));
    D3 u = d3_cross(r, f);
    double th = tan(c->vfov_deg * RAYSET_PI / 360.0);
    double aspect = (double)c->width / (double)c->height;
    Vec3 o = d3_to_float(eye);
    for (size_t py = 0; py < h; py++) {
        double sy = (1.0 - 2.0 * ((double)py + 0.5) / (double)c->height) * th;
        for (size_t px = 0; px < w; px++) {
            double sx = (2.0 * ((double)px + 0.5) / (double)c->width - 1.0) * th * aspect;
            D3 d = d3(f.x + sx * r.x + sy * u.x, f.y + sx * r.y + sy * u.y, f.z + sx * r.z + sy * u.z);
            rays[py * w + px] = ray_make(o, d3_to_float(d3_normalize(d)), 0.0f, INFINITY);
        }
    }
    *count = w * h;
    return rays;
}

Ray *rayset_secondary(const RaysetScene *s, const Ray *primary, const RaysetResult *hits,
                      size_t num_primary, size_t *count)
{
    *count = 0;
    size_t n = 0;
    for (size_t i = 0; i < num_primary; i++) n += hits[i].prim != RAYSET_MISS;
    Ray *rays = malloc((n > 0 ? n : 1) * sizeof *rays);
    if (!rays) return NULL;
    const double offset = 1e-4 * s->diag;
    size_t k = 0;
    for (size_t i = 0; i < num_primary; i++) {
        if (hits[i].prim == RAYSET_MISS) continue;
        /* 1. Geometric normal of the hit triangle, facing the incoming ray. */
        const int32_t *tri = &s->tri_indices[3 * (size_t)hits[i].prim];
        D3 p0 = d3_of(s->positions[tri[0]]), p1 = d3_of(s->positions[tri[1]]), p2 = d3_of(s->positions[tri[2]]);
        D3 oi = d3_of(primary[i].o), di = d3_of(primary[i].d);
        D3 n_ = d3_normalize(d3_cross(d3_sub(p1, p0), d3_sub(p2, p0)));
        if (d3_dot(n_, di) > 0.0) n_ = d3(-n_.x, -n_.y, -n_.z);
        /* 2. Origin: the hit point pushed 1e-4 diag along n. */
        double t = (double)hits[i].t;
        D3 o = d3(oi.x + t * di.x + offset * n_.x, oi.y + t * di.y + offset * n_.y,
                  oi.z + t * di.z + offset * n_.z);
        /* 3. PCG32 seeded with (i, i). */
        Pcg32 rng;
        pcg32_seed(&rng, (uint64_t)i, (uint64_t)i);
        double u1 = (double)(pcg32_next(&rng) >> 8) * 0x1p-24;
        double u2 = (double)(pcg32_next(&rng) >> 8) * 0x1p-24;
        /* 4. Cosine-weighted direction in the local frame. */
        double rr = sqrt(u1), phi = 2.0 * RAYSET_PI * u2;
        double lx = rr * cos(phi), ly = rr * sin(phi), lz = sqrt(fmax(0.0, 1.0 - u1));
        /* 5. Orthonormal basis around n (Duff et al., "Building an Orthonormal Basis,
         * Revisited", JCGT 2017). */
        double sg = copysign(1.0, n_.z);
        double a = -1.0 / (sg + n_.z);
        double b = n_.x * n_.y * a;
        D3 t1 = d3(1.0 + sg * n_.x * n_.x * a, sg * b, -sg * n_.x);
        D3 t2 = d3(b, sg + n_.y * n_.y * a, -n_.y);
        /* 6. To world. */
        D3 d = d3(lx * t1.x + ly * t2.x + lz * n_.x, lx * t1.y + ly * t2.y + lz * n_.y,
                  lx * t1.z + ly * t2.z + lz * n_.z);
        rays[k++] = ray_make(d3_to_float(o), d3_to_float(d3_normalize(d)), 0.0f, INFINITY);
    }
    *count = n;
    return rays;
}

Ray *rayset_occlusion(const Ray *secondary, size_t count)
{
    Ray *rays = malloc((count > 0 ? count : 1) * sizeof *rays);
    if (!rays) return NULL;
    for (size_t i = 0; i < count; i++) {
        rays[i] = secondary[i];
        rays[i].t_max = 1e30f;
    }
    return rays;
}

/* ------------------------------------------------------------ tracing */

enum { RAYSET_CHUNK = 1024 }; /* rays per work item: small enough to balance two threads */

typedef struct TraceShared {
    const Accel *accel;
    const Ray *rays;
    size_t n;
    RaysetQuery query;
    RaysetResult *out;
    atomic_size_t next; /* first ray of the next chunk */
} TraceShared;

static void *rayset_trace_worker(void *arg)
{
    TraceShared *sh = arg;
    for (;;) {
        size_t begin = atomic_fetch_add_explicit(&sh->next, RAYSET_CHUNK, memory_order_relaxed);
        if (begin >= sh->n) break;
        size_t end = begin + RAYSET_CHUNK < sh->n ? begin + RAYSET_CHUNK : sh->n;
        if (sh->query == RAYSET_CLOSEST) {
            for (size_t i = begin; i < end; i++) {
                Hit h;
                if (accel_intersect(sh->accel, &sh->rays[i], &h)) {
                    sh->out[i].t = h.t;
                    sh->out[i].prim = h.prim;
                } else {
                    sh->out[i].t = 0.0f;
                    sh->out[i].prim = RAYSET_MISS;
                }
            }
        } else {
            for (size_t i = begin; i < end; i++) {
                sh->out[i].t = 0.0f;
                sh->out[i].prim = accel_occluded(sh->accel, &sh->rays[i]) ? 0u : RAYSET_MISS;
            }
        }
    }
    return NULL;
}

CstStatus rayset_trace(const Accel *a, const Ray *rays, size_t n, RaysetQuery query, int threads,
                       RaysetResult *out, RaysetStats *st, CstError *err)
{
    memset(st, 0, sizeof *st);
    if (threads < 1) return cst_fail(err, CST_ERR_INVALID_ARG, "ray tracing with %d threads", threads);
    RaysetResult *own = NULL;
    if (!out) {
        own = out = malloc((n > 0 ? n : 1) * sizeof *out);
        if (!out) return cst_fail(err, CST_ERR_OOM, "out of memory for %zu ray results", n);
    }
    TraceShared sh = {a, rays, n, query, out, 0};
    atomic_init(&sh.next, 0);
    pthread_t tid[RAYSET_MAX_THREADS];
    if (threads > RAYSET_MAX_THREADS) threads = RAYSET_MAX_THREADS;
    int started = 0;
    CstStatus status = CST_OK;

    double t0 = clock_seconds();
    for (int k = 1; k < threads; k++) {
        if (pthread_create(&tid[k], NULL, rayset_trace_worker, &sh) != 0) {
            status = cst_fail(err, CST_ERR_INTERNAL, "could not start tracing thread %d of %d", k + 1, threads);
            break;
        }
        started++;
    }
    rayset_trace_worker(&sh); /* the calling thread works too (and finishes the job alone
                               * if a thread failed to start, so joins cannot hang) */
    for (int k = 1; k <= started; k++) pthread_join(tid[k], NULL);
    st->seconds = clock_seconds() - t0;

    if (status == CST_OK) {
        /* Reduce in ray order: the sums do not depend on which thread traced what. */
        st->rays = n;
        for (size_t i = 0; i < n; i++) {
            if (out[i].prim == RAYSET_MISS) continue;
            st->hits++;
            if (query == RAYSET_CLOSEST) {
                st->sum_t += (double)out[i].t;
                st->sum_prim += out[i].prim;
                if (out[i].t > st->max_t) st->max_t = out[i].t;
            }
        }
    }
    free(own);
    return status;
}

/* ------------------------------------------------------------ reference checksums */

/* RAYSETS.md "Checksums" (computed with Embree 3.13, default BVH). */
static const RaysetReference RAYSET_REFERENCES[] = {
    {"bunny", 69451, 341825, 9.486407052e+04, 341825, 31748, 5.522044378e+02},
    {"dragon", 871414, 323176, 1.063657764e+05, 323176, 66548, 1.577498083e+03},
    {"bumpysphere", 1310720, 342641, 1.300850217e+06, 342641, 32548, 2.544053609e+03},
    {"cornell", 32, 244357, 2.718016793e+08, 244357, 177407, 5.251159230e+07},
};

const RaysetReference *rayset_reference(const RaysetScene *s)
{
    for (size_t i = 0; i < sizeof RAYSET_REFERENCES / sizeof RAYSET_REFERENCES[0]; i++)
        if (strcmp(s->name, RAYSET_REFERENCES[i].scene) == 0 && s->num_tris == RAYSET_REFERENCES[i].num_tris)
            return &RAYSET_REFERENCES[i];
    return NULL;
}

size_t rayset_rays_tolerance(size_t count)
{
    size_t rel = (size_t)(RAYSET_HITS_TOLERANCE_REL * (double)count);
    return rel > RAYSET_HITS_TOLERANCE_ABS ? rel : (size_t)RAYSET_HITS_TOLERANCE_ABS;
}

bool rayset_hits_match(size_t hits, size_t ref_hits)
{
    size_t d = hits > ref_hits ? hits - ref_hits : ref_hits - hits;
    return d <= rayset_rays_tolerance(ref_hits);
}

bool rayset_sum_t_match(double sum_t, double ref_sum_t, size_t hits, size_t ref_hits, double max_t)
{
    double dh = fabs((double)hits - (double)ref_hits);
    return fabs(sum_t - ref_sum_t) <= RAYSET_SUM_T_TOLERANCE * fabs(ref_sum_t) + dh * max_t;
}

size_t rayset_compare(const RaysetResult *a, const RaysetResult *b, size_t n, RaysetQuery query, double *dt_sum)
{
    size_t differ = 0;
    double dt = 0.0;
    for (size_t i = 0; i < n; i++) {
        bool ha = a[i].prim != RAYSET_MISS, hb = b[i].prim != RAYSET_MISS;
        if (ha != hb) {
            differ++;
            if (query == RAYSET_CLOSEST) dt += (double)(ha ? a[i].t : b[i].t);
        } else if (ha && query == RAYSET_CLOSEST) {
            double ta = (double)a[i].t, tb = (double)b[i].t;
            if (fabs(ta - tb) > RAYSET_T_TOLERANCE * fmax(fabs(ta), fabs(tb))) {
                differ++;
                dt += fabs(ta - tb);
            }
        }
    }
    *dt_sum = dt;
    return differ;
}

/* ------------------------------------------------------------ grazing ties */

static double d3_len(D3 a) { return sqrt(d3_dot(a, a)); }
static bool v3_same(Vec3 a, Vec3 b) { return a.x == b.x && a.y == b.y && a.z == b.z; }

/* Whether the edge (a, b) of triangle `tri` (a before b in its winding) is a silhouette for
 * direction d: no other triangle has it (a boundary), or one that has it faces d the other
 * way once both are wound consistently (the edge runs b -> a in the neighbour). Across a
 * non-silhouette edge both faces face d alike: a ray through it crosses the surface, and
 * must hit one of them (watertightness), so a miss there is no tie. Brute force over the
 * triangles: only run for the few rays two back ends disagree on. */
static bool rayset_edge_is_silhouette(const RaysetScene *s, int tri, int ea, int eb, D3 d)
{
    const int32_t *ti = &s->tri_indices[3 * tri];
    Vec3 a = s->positions[ti[ea]], b = s->positions[ti[eb]];
    D3 p0 = d3_of(s->positions[ti[0]]);
    double facing = d3_dot(d3_cross(d3_sub(d3_of(s->positions[ti[1]]), p0), d3_sub(d3_of(s->positions[ti[2]]), p0)), d);
    bool neighbour = false;
    for (int k = 0; k < s->num_tris; k++) {
        if (k == tri) continue;
        const int32_t *tk = &s->tri_indices[3 * k];
        int ia = -1, ib = -1;
        for (int v = 0; v < 3; v++) {
            if (v3_same(s->positions[tk[v]], a)) ia = v;
            else if (v3_same(s->positions[tk[v]], b)) ib = v;
        }
        if (ia < 0 || ib < 0) continue;
        neighbour = true;
        D3 q0 = d3_of(s->positions[tk[0]]);
        double nf = d3_dot(d3_cross(d3_sub(d3_of(s->positions[tk[1]]), q0), d3_sub(d3_of(s->positions[tk[2]]), q0)), d);
        if ((ib + 1) % 3 != ia) nf = -nf; /* a -> b in the neighbour too: opposite winding */
        if ((facing > 0.0) != (nf > 0.0)) return true;
    }
    return !neighbour;
}

/* Whether `ray` grazes triangle `tri`: it meets the triangle's plane within `eps` of a
 * silhouette edge, or runs within 1e-6 rad of parallel to the plane. */
static bool rayset_ray_grazes(const RaysetScene *s, const Ray *ray, uint32_t tri, double eps)
{
    if (tri >= (uint32_t)s->num_tris) return false;
    const int32_t *ti = &s->tri_indices[3 * tri];
    D3 p[3] = {d3_of(s->positions[ti[0]]), d3_of(s->positions[ti[1]]), d3_of(s->positions[ti[2]])};
    D3 o = d3_of(ray->o), d = d3_of(ray->d);
    D3 n = d3_cross(d3_sub(p[1], p[0]), d3_sub(p[2], p[0]));
    double nd = d3_dot(n, d), nl = d3_len(n), dl = d3_len(d);
    if (nl == 0.0 || dl == 0.0) return false;
    if (fabs(nd) <= 1e-6 * nl * dl) return true;
    double t = d3_dot(n, d3_sub(p[0], o)) / nd;
    D3 x = {o.x + t * d.x, o.y + t * d.y, o.z + t * d.z};
    for (int e = 0; e < 3; e++) {
        D3 a = p[e], ab = d3_sub(p[(e + 1) % 3], a);
        double len = d3_len(ab);
        if (len == 0.0) continue;
        double dist = d3_len(d3_cross(d3_sub(x, a), ab)) / len;
        if (dist <= eps && rayset_edge_is_silhouette(s, (int)tri, e, (e + 1) % 3, d)) return true;
    }
    return false;
}

size_t rayset_compare_ties(const RaysetScene *s, const Ray *rays, const RaysetResult *a, const RaysetResult *b,
                           size_t n, size_t *ties, double *dt_ties)
{
    size_t differ = 0, tie = 0, cap = rayset_rays_tolerance(n);
    double dt = 0.0, eps = RAYSET_EDGE_TOLERANCE * s->diag;
    for (size_t i = 0; i < n; i++) {
        bool ha = a[i].prim != RAYSET_MISS, hb = b[i].prim != RAYSET_MISS;
        double ta = ha ? (double)a[i].t : 0.0, tb = hb ? (double)b[i].t : 0.0;
        if (ha == hb && (!ha || fabs(ta - tb) <= RAYSET_T_TOLERANCE * fmax(fabs(ta), fabs(tb)))) continue;
        differ++;
        if (tie > cap) continue; /* past the tolerance the allowance is void anyway */
        /* The nearer hit is the one the other back end went past. */
        uint32_t near = !hb || (ha && ta <= tb) ? a[i].prim : b[i].prim;
        if (rayset_ray_grazes(s, &rays[i], near, eps)) {
            tie++;
            dt += fabs(ta - tb);
        }
    }
    *ties = tie;
    *dt_ties = dt;
    return differ;
}

bool rayset_sum_t_match_ties(double sum_t, double ref_sum_t, size_t hits, size_t ref_hits, double max_t,
                             size_t rays, size_t ties, double dt_ties)
{
    double allowance = ties <= rayset_rays_tolerance(rays) ? dt_ties : 0.0;
    double dh = fabs((double)hits - (double)ref_hits);
    return fabs(sum_t - ref_sum_t) <= RAYSET_SUM_T_TOLERANCE * fabs(ref_sum_t) + dh * max_t + allowance;
}
