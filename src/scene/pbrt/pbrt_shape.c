/* Shapes: spheres, disks, triangle meshes and PLY files placed by the CTM with pbrt's
 * orientation rules; ObjectBegin/End definitions and their instances. */
#include "scene/pbrt/pbrt_shape.h"

#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "geometry/loop_subdiv.h"
#include "geometry/shape.h"
#include "geometry/triangle.h"
#include "scene/mesh_import.h"
#include "scene/pbrt/pbrt_curve.h"
#include "scene/pbrt/pbrt_displace.h"
#include "scene/pbrt/pbrt_material.h"
#include "scene/pbrt/pbrt_medium.h"
#include "scene/pbrt/pbrt_params.h"
#include "scene/pbrt/pbrt_texture.h"
#include "scene/pbrt/pbrt_transform.h"

/* Segments of a tessellated disk and rings/segments of a tessellated sphere. */
#define PBRT_DISK_SEGMENTS 128

#define PBRT_SPHERE_SEGMENTS 64

#define PBRT_SPHERE_RINGS 32

/* The most triangles one loopsubdiv shape is refined to (2^24). */
#define PBRT_LOOP_MAX_TRIANGLES (1 << 24)

void pbrt_geom_free(ShapeGeom *g)
{
    free(g->p);
    free(g->n);
    free(g->uv);
    free(g->idx);
    memset(g, 0, sizeof *g);
}


/* An area light's emission while the loader works it out (scaled by power per shape). */
typedef struct ShapeEmission {
    Color radiance;
    int two_sided;
    int texture;
    int spectrum; /* the area light's spectrum id (cst_scene_add_spectrum), or 0 */
} ShapeEmission;

/* The loader's emission as the public builder's (exact: three floats per colour). */
static CstEmission emission_desc(const ShapeEmission *em)
{
    CstEmission e = {{0.0f, 0.0f, 0.0f}, em->texture, em->two_sided, em->spectrum};
    for (int k = 0; k < 3; k++) e.radiance[k] = color_channel(em->radiance, k);
    return e;
}
static CstStatus geom_alloc(Loader *ld, ShapeGeom *g, int nv, int nt, int normals, int uvs)
{
    memset(g, 0, sizeof *g);
    g->p = malloc((size_t)(nv ? nv : 1) * sizeof *g->p);
    g->idx = malloc((size_t)(nt ? nt : 1) * 3 * sizeof *g->idx);
    if (normals) g->n = malloc((size_t)(nv ? nv : 1) * sizeof *g->n);
    if (uvs) g->uv = malloc((size_t)(nv ? nv : 1) * sizeof *g->uv);
    if (!g->p || !g->idx || (normals && !g->n) || (uvs && !g->uv)) {
        pbrt_geom_free(g);
        return pbrt_oom(ld);
    }
    g->nv = nv;
    g->nt = nt;
    return CST_OK;
}

/* A UV sphere, outward-facing, for spheres under transforms that are not similarities. */
static CstStatus sphere_mesh(Loader *ld, float radius, ShapeGeom *g)
{
    const int S = PBRT_SPHERE_SEGMENTS, R = PBRT_SPHERE_RINGS;
    int nv = (R - 1) * S + 2, nt = 2 * S * (R - 1);
    TRY(geom_alloc(ld, g, nv, nt, 1, 0));
    int v = 0, t = 0;
    g->n[v] = v3(0.0f, 0.0f, -1.0f);
    g->p[v++] = v3(0.0f, 0.0f, -radius);
    for (int r = 1; r < R; r++) {
        double th = PBRT_PI * (double)r / R;
        for (int s = 0; s < S; s++) {
            double ph = 2.0 * PBRT_PI * (double)s / S;
            Vec3 n = v3((float)(sin(th) * cos(ph)), (float)(sin(th) * sin(ph)), (float)-cos(th));
            g->n[v] = n;
            g->p[v++] = v3_scale(n, radius);
        }
    }
    g->n[v] = v3(0.0f, 0.0f, 1.0f);
    g->p[v++] = v3(0.0f, 0.0f, radius);
    for (int s = 0; s < S; s++) { /* bottom cap: counter-clockwise seen from outside */
        int a = 1 + s, b = 1 + (s + 1) % S;
        g->idx[3 * t] = 0; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = a; t++;
    }
    for (int r = 0; r < R - 2; r++)
        for (int s = 0; s < S; s++) {
            int a = 1 + r * S + s, b = 1 + r * S + (s + 1) % S;
            int c = a + S, e = b + S;
            g->idx[3 * t] = a; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = e; t++;
            g->idx[3 * t] = a; g->idx[3 * t + 1] = e; g->idx[3 * t + 2] = c; t++;
        }
    int top = nv - 1, base = 1 + (R - 2) * S;
    for (int s = 0; s < S; s++) {
        int a = base + s, b = base + (s + 1) % S;
        g->idx[3 * t] = a; g->idx[3 * t + 1] = b; g->idx[3 * t + 2] = top; t++;
    }
    g->nt = t;
    return CST_OK;
}

/* An annulus (inner may be 0) or sector at z = height facing +z, as a polygon whose
 * radii are scaled so that its area equals the true disk's: an emitting disk keeps its
 * power. */
static CstStatus disk_mesh(Loader *ld, float height, float radius, float inner, float phimax_deg,
                           ShapeGeom *g)
{
    double phimax = (double)clampf(phimax_deg, 0.0f, 360.0f) * PBRT_PI / 180.0;
    int segs = (int)ceil(PBRT_DISK_SEGMENTS * phimax / (2.0 * PBRT_PI));
    if (segs < 1) segs = 1;
    double step = phimax / segs;
    double k = sqrt(step / sin(step)); /* polygon area (segs/2) r^2 sin(step) -> (phimax/2) r^2 */
    int full = phimax >= 2.0 * PBRT_PI - 1e-9;
    int ring = full ? segs : segs + 1;
    int annulus = inner > 0.0f;
    int nv = annulus ? 2 * ring : ring + 1, nt = annulus ? 2 * segs : segs;
    TRY(geom_alloc(ld, g, nv, nt, 0, 0));
    for (int i = 0; i < ring; i++) {
        double ph = step * i;
        g->p[i] = v3((float)(k * (double)radius * cos(ph)), (float)(k * (double)radius * sin(ph)), height);
        if (annulus) g->p[ring + i] = v3((float)(k * (double)inner * cos(ph)), (float)(k * (double)inner * sin(ph)), height);
    }
    if (!annulus) g->p[ring] = v3(0.0f, 0.0f, height);
    for (int i = 0; i < segs; i++) {
        int a = i, b = (i + 1) % ring;
        if (!annulus) {
            g->idx[3 * i] = ring; g->idx[3 * i + 1] = a; g->idx[3 * i + 2] = b;
        } else {
            int *t = &g->idx[6 * i];
            t[0] = ring + a; t[1] = a; t[2] = b;
            t[3] = ring + a; t[4] = b; t[5] = ring + b;
        }
    }
    return CST_OK;
}

/* Linear part of m is a rotation times a uniform scale (to 1e-5): spheres stay spheres. */
static int is_similarity(const Transform *m, float *scale)
{
    Vec3 c[3];
    for (int k = 0; k < 3; k++) c[k] = v3(m->m[0][k], m->m[1][k], m->m[2][k]);
    float l0 = v3_length(c[0]), l1 = v3_length(c[1]), l2 = v3_length(c[2]);
    if (!(l0 > 0.0f)) return 0;
    float tol = 1e-5f * l0;
    if (fabsf(l1 - l0) > tol || fabsf(l2 - l0) > tol) return 0;
    if (fabsf(v3_dot(c[0], c[1])) > tol * l0 || fabsf(v3_dot(c[0], c[2])) > tol * l0 ||
        fabsf(v3_dot(c[1], c[2])) > tol * l0)
        return 0;
    *scale = l0;
    return 1;
}

/* The area of triangles [t, t + n) of a mesh: one pbrt shape's, for its power (a single
 * triangle's exactly as triangle_area gives it). */
static float group_area(const Vec3 *p, const int *idx, int t, int n)
{
    if (n == 1) return triangle_area(p[idx[3 * t]], p[idx[3 * t + 1]], p[idx[3 * t + 2]]);
    double sum = 0.0;
    for (int k = t; k < t + n; k++) sum += (double)triangle_area(p[idx[3 * k]], p[idx[3 * k + 1]], p[idx[3 * k + 2]]);
    return (float)sum;
}

int pbrt_coords_ok(Vec3 p) { return v3_is_finite(p) && (double)v3_max_abs(p) <= PBRT_MAX_LENGTH; }

/* The world-space triangles' indices in idx, wound as pbrt's orientation rule says: swapped
 * when `swap` (ReverseOrientation against a mirroring transform), or, with vertex normals
 * n, so that the geometric normal agrees with their sum. */
static void orient_triangles(const ShapeGeom *g, const Vec3 *p, const Vec3 *n, int swap, int *idx)
{
    for (int t = 0; t < g->nt; t++) {
        int a = g->idx[3 * t], b = g->idx[3 * t + 1], c = g->idx[3 * t + 2];
        int sw = swap;
        if (n) {
            Vec3 ng = v3_cross(v3_sub(p[b], p[a]), v3_sub(p[c], p[a]));
            Vec3 ns = v3_add(v3_add(n[a], n[b]), n[c]);
            sw = v3_dot(ng, ns) < 0.0f;
        }
        idx[3 * t] = a;
        idx[3 * t + 1] = sw ? c : b;
        idx[3 * t + 2] = sw ? b : c;
    }
}

/* Places an object-space shape with xf into the scene with the given material and area
 * light. Winding follows pbrt's orientation rule: the geometric normal (v1-v0) x (v2-v0)
 * is flipped when ReverseOrientation differs from whether xf mirrors, or, for meshes
 * with normals, made to face the (possibly reversed) shading normals. */
static CstStatus emit_shape(Loader *ld, const ShapeGeom *g, const Xf *xf, int reverse,
                            int material, const AreaLight *al, const CstAlpha *alpha, Loc loc, const char *d)
{
    int mat = 0;
    float s = 1.0f;
    TRY(pbrt_material_scene_id(ld, material, &mat));
    if (g->is_sphere && transform_is_affine(&xf->m) && is_similarity(&xf->m, &s)) {
        Vec3 c = transform_point(&xf->m, v3s(0.0f));
        float r = g->radius * s;
        if (!pbrt_coords_ok(c) || !(r > 1e-18f) || !((double)r <= PBRT_MAX_LENGTH))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: sphere at (%g, %g, %g) radius %g is "
                                "beyond the scene limits (coordinates within 1e18, radius above 1e-18)",
                                d, (double)c.x, (double)c.y, (double)c.z, (double)r);
        ShapeEmission em = {color_s(0.0f), 0, 0, 0};
        if (al && al->active) {
            em.radiance = color_scale(al->L, al->scale);
            em.two_sided = al->two_sided;
            em.texture = al->texture;
            em.spectrum = al->spectrum;
            if (al->power > 0.0f) {
                double k_e = (al->two_sided ? 2.0 : 1.0) * 4.0 * PBRT_PI * (double)r * (double)r * PBRT_PI *
                             (al->texture ? (double)al->image_lum : 1.0);
                em.radiance = color_scale(em.radiance, (float)((double)al->power / k_e));
            }
            if (reverse && !al->two_sided)
                pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: ReverseOrientation on an emitting sphere "
                             "is ignored: it emits outward", d);
        }
        if (ld->num_spheres >= INT_MAX - 1)
            return pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: too many spheres", d);
        float cf[3] = {c.x, c.y, c.z};
        CstEmission e = emission_desc(&em);
        CstStatus st = cst_scene_add_sphere_alpha(ld->scene, cf, r, mat, &e, alpha, ld->err);
        if (st) return pbrt_fail_wrap(ld, st, loc, d);
        ld->num_spheres++;
        return CST_OK;
    }
    ShapeGeom tess = {0};
    if (g->is_sphere) {
        TRY(sphere_mesh(ld, g->radius, &tess));
        tess.power_group = tess.nt; /* one sphere: its power over all its triangles */
        g = &tess;
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: sphere under a non-uniform transform "
                     "tessellated into %d triangles", d, tess.nt);
    }
    CstStatus st = CST_OK;
    Vec3 *p = malloc((size_t)(g->nv ? g->nv : 1) * sizeof *p);
    Vec3 *n = g->n ? malloc((size_t)g->nv * sizeof *n) : NULL;
    int *idx = malloc((size_t)(g->nt ? g->nt : 1) * 3 * sizeof *idx);
    if (!p || !idx || (g->n && !n)) { st = pbrt_oom(ld); goto done; }
    if (g->nt > PBRT_MAX_TRIANGLES - ld->num_triangles) {
        st = pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: the scene would exceed %d triangles", d,
                          PBRT_MAX_TRIANGLES);
        goto done;
    }
    int swap = (transform_det(&xf->m) < 0.0) != (reverse != 0);
    Transform nm = transform_identity();
    transform_normal_matrix(&xf->m, &nm);
    int projective = !transform_is_affine(&xf->m);
    for (int i = 0; i < g->nv; i++) {
        p[i] = transform_is_identity(&xf->m) ? g->p[i] : transform_point(&xf->m, g->p[i]);
        if (projective) { /* pbrt-v4's point transform: divided by w where w != 1 */
            const float *r3 = xf->m.m[3];
            double w = (double)r3[0] * (double)g->p[i].x + (double)r3[1] * (double)g->p[i].y +
                       (double)r3[2] * (double)g->p[i].z + (double)r3[3];
            if (w != 1.0)
                p[i] = v3((float)((double)p[i].x / w), (float)((double)p[i].y / w), (float)((double)p[i].z / w));
        }
        if (!pbrt_coords_ok(p[i])) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: vertex %d is at (%g, %g, %g), beyond the "
                              "scene limit; expected coordinates of magnitude at most %g", d, i,
                              (double)p[i].x, (double)p[i].y, (double)p[i].z, PBRT_MAX_LENGTH);
            goto done;
        }
        if (n) {
            n[i] = transform_normal(&nm, g->n[i]);
            if (reverse) n[i] = v3_neg(n[i]);
        }
    }
    orient_triangles(g, p, n, swap, idx);
    /* Normals come from transform_normal: unit, or zero where it degenerates. The indices
     * are non-negative ints, read by the builder as uint32_t (the same bytes). */
    CstMeshDesc sm = {0};
    sm.positions = p;
    sm.position_stride = sizeof *p;
    sm.num_vertices = g->nv;
    sm.normals = n;
    sm.normal_stride = sizeof(Vec3);
    sm.normals_unit = 1;
    sm.uvs = g->uv;
    sm.uv_stride = sizeof(Vec2);
    sm.indices = idx;
    sm.index_stride = 3 * sizeof *idx;
    sm.num_triangles = g->nt;
    sm.material = mat;
    sm.skip_degenerate = 1;
    if (alpha) sm.alpha = *alpha;
    ShapeEmission em = {color_s(0.0f), 0, 0, 0};
    if (al && al->active) {
        em.radiance = color_scale(al->L, al->scale);
        em.two_sided = al->two_sided;
        em.texture = al->texture;
        em.spectrum = al->spectrum;
    }
    sm.emission = emission_desc(&em);
    int dropped = 0;
    if (g->nt == 0) goto done; /* "indices" []: nothing to add (the builder wants a triangle) */
    if (al && al->active && al->power > 0.0f) {
        /* pbrt-v4 makes one light per shape and normalises each to `power` by its own
         * area: L = power / (pi A sides) times the spectrum (DiffuseAreaLight::Create). A
         * triangle mesh's shapes are its triangles; a bilinear patch is two triangles
         * here and a disk or a tessellated sphere all of theirs (power_group), which
         * share the area of their group. */
        const int grp = g->power_group > 1 ? g->power_group : 1;
        float area = 0.0f;
        for (int t = 0; t < g->nt && !st; t++) {
            if (t % grp == 0) area = group_area(p, idx, t, grp < g->nt - t ? grp : g->nt - t);
            ShapeEmission et = em;
            if (area > 0.0f)
                et.radiance = color_scale(em.radiance, (float)((double)al->power /
                                       (PBRT_PI * (double)area * (al->two_sided ? 2.0 : 1.0) *
                                        (al->texture ? (double)al->image_lum : 1.0))));
            CstMeshDesc one = sm;
            one.indices = &idx[3 * t];
            one.num_triangles = 1;
            one.emission = emission_desc(&et);
            int dr = 0;
            st = cst_scene_add_mesh(ld->scene, &one, &dr, ld->err);
            dropped += dr;
        }
    } else {
        st = cst_scene_add_mesh(ld->scene, &sm, &dropped, ld->err);
    }
    if (st) {
        st = pbrt_fail_wrap(ld, st, loc, d);
        goto done;
    }
    ld->num_triangles += g->nt - dropped;
    if (dropped)
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: %d of %d triangles are degenerate (zero area) "
                     "and were dropped", d, dropped, g->nt);
done:
    free(p);
    free(n);
    free(idx);
    pbrt_geom_free(&tess);
    return st;
}

/* Fills g from "point3 P", "integer indices" (optional for a single triangle), "normal N",
 * "point2 uv". */
static CstStatus read_mesh_params(Loader *ld, Params *ps, const char *d, Loc loc, int per_face,
                                  ShapeGeom *g)
{
    Param *pp, *pi, *pn, *puv;
    char nm[72];
    TRY(pbrt_lookup(ld, ps, d, "P", PT_MASK(PT_POINT3), "point3", &pp));
    TRY(pbrt_lookup(ld, ps, d, "indices", PT_MASK(PT_INTEGER), "integer", &pi));
    TRY(pbrt_lookup(ld, ps, d, "N", PT_MASK(PT_NORMAL), "normal", &pn));
    TRY(pbrt_lookup(ld, ps, d, "uv", PT_MASK(PT_POINT2) | PT_MASK(PT_FLOAT), "point2", &puv));
    if (!puv) TRY(pbrt_lookup(ld, ps, d, "st", PT_MASK(PT_POINT2) | PT_MASK(PT_FLOAT), "point2", &puv));
    if (!pp)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"point3 P\"; expected the vertex positions", d);
    int nv = pp->num_nums / 3;
    if (!pi && nv != per_face)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"integer indices\"; expected "
                            "indices unless there are exactly %d vertices", d, per_face);
    int ni = pi ? pi->num_nums : per_face;
    if (ni % per_face != 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pi->loc, "%s: %d indices; expected a multiple of %d",
                            d, ni, per_face);
    if (pn && pn->num_nums != pp->num_nums)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pn->loc, "%s: %d normals for %d vertices; expected "
                            "one per vertex", d, pn->num_nums / 3, nv);
    if (puv && puv->num_nums != 2 * nv)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, puv->loc, "%s: \"%s\" has %d values for %d vertices; "
                            "expected 2 per vertex", d, pbrt_clip(puv->decl, nm), puv->num_nums, nv);
    int nfaces = ni / per_face, nt = per_face == 4 ? 2 * nfaces : nfaces;
    TRY(geom_alloc(ld, g, nv, nt, pn != NULL, puv != NULL));
    for (int i = 0; i < nv; i++) {
        g->p[i] = v3((float)pp->nums[3 * i], (float)pp->nums[3 * i + 1], (float)pp->nums[3 * i + 2]);
        if (!pbrt_coords_ok(g->p[i]))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pp->loc, "%s: vertex %d is beyond the scene limit; "
                                "expected coordinates of magnitude at most %g", d, i, PBRT_MAX_LENGTH);
        if (pn) {
            Vec3 v = v3((float)pn->nums[3 * i], (float)pn->nums[3 * i + 1], (float)pn->nums[3 * i + 2]);
            float l = v3_length(v);
            g->n[i] = l > 0.0f && isfinite(l) ? v3_scale(v, 1.0f / l) : v3s(0.0f);
        }
        if (puv) g->uv[i] = v2((float)puv->nums[2 * i], (float)puv->nums[2 * i + 1]);
    }
    for (int i = 0; i < ni; i++) {
        double v = pi ? pi->nums[i] : (double)i;
        if (v < 0 || v >= nv)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, pi->loc, "%s: index %g (number %d) is out of "
                                "range; expected 0 to %d (there are %d vertices)", d, v, i, nv - 1, nv);
    }
    for (int f = 0; f < nfaces; f++) {
        const double *q = pi ? &pi->nums[per_face * f] : NULL;
        int v[4];
        for (int k = 0; k < per_face; k++) v[k] = q ? (int)q[k] : per_face * f + k;
        if (per_face == 3) {
            for (int k = 0; k < 3; k++) g->idx[3 * f + k] = v[k];
        } else {
            /* bilinear patch p00 p10 p01 p11: (p00, p10, p11), (p00, p11, p01), the same
             * side as pbrt's dp/du x dp/dv */
            int *t = &g->idx[6 * f];
            t[0] = v[0]; t[1] = v[1]; t[2] = v[3];
            t[3] = v[0]; t[4] = v[3]; t[5] = v[2];
        }
    }
    return CST_OK;
}

static CstStatus plymesh(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g)
{
    const char *file = NULL;
    Loc fl = loc;
    TRY(pbrt_get_string(ld, ps, d, "filename", &file, &fl));
    if (!file || !file[0])
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: missing \"string filename\"; expected the PLY file", d);
    TRY(pbrt_check_file_access(ld, fl, d));
    char *path = pbrt_resolve_path(ld, file);
    if (!path) return pbrt_oom(ld);
    ImportedMesh im = {0};
    CstStatus st = mesh_import(path, &im, ld->err);
    free(path);
    if (st) return pbrt_fail_wrap(ld, st, fl, d);
    st = geom_alloc(ld, g, im.num_vertices, im.num_triangles, im.normals != NULL, im.uvs != NULL);
    if (!st) {
        memcpy(g->p, im.positions, (size_t)im.num_vertices * sizeof *g->p);
        for (int i = 0; i < 3 * im.num_triangles; i++) g->idx[i] = im.indices[i];
        if (im.normals) memcpy(g->n, im.normals, (size_t)im.num_vertices * sizeof *g->n);
        if (im.uvs) memcpy(g->uv, im.uvs, (size_t)im.num_vertices * sizeof *g->uv);
    }
    if (!st && im.num_skipped_primitives)
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, fl, "%s: \"%s\": %d faces of other than 3 or 4 vertices "
                     "skipped (the first has %d), as pbrt-v4 skips them", d, file,
                     im.num_skipped_primitives, im.skipped_face_size);
    if (!st && im.num_quads)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, fl, "%s: \"%s\": %d quads each split into two "
                     "triangles (pbrt-v4 renders them as bilinear patches; exact for planar quads)",
                     d, file, im.num_quads);
    mesh_import_free(&im);
    return st;
}

/* pbrt-v4's "loopsubdiv": "point3 P" and "integer indices" refined "integer levels" (3)
 * times and pushed to the limit surface, with the limit normals and no uvs, as pbrt-v4
 * (geometry/loop_subdiv.c). A control mesh that is not manifold, which pbrt-v4 does not
 * handle, renders as itself with a warning naming the first problem. */
static CstStatus loop_shape(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g)
{
    int levels = 3;
    ShapeGeom ctl = {0};
    TRY(pbrt_get_int(ld, ps, d, "levels", 3, &levels));
    CstStatus st = read_mesh_params(ld, ps, d, loc, 3, &ctl);
    if (st) {
        pbrt_geom_free(&ctl);
        return st;
    }
    if (ctl.n || ctl.uv)
        pbrt_warn_at(ld, CST_WARN_PARAMETER_IGNORED, loc, "%s: \"N\" and \"uv\" are ignored: the limit "
                     "surface has its own normals and, as in pbrt-v4, no uvs", d);
    /* Each level multiplies the triangles by 4: a large "levels" (a typo, or fuzzed input)
     * would ask for gigabytes, so the refinement stops at PBRT_LOOP_MAX_TRIANGLES per shape
     * (16.8 M; about 2 GB at the peak of the last level) and within the scene's limit. */
    int lv = levels < 0 ? 0 : levels;
    int64_t cap = (int64_t)PBRT_MAX_TRIANGLES - ld->num_triangles;
    if (cap > PBRT_LOOP_MAX_TRIANGLES) cap = PBRT_LOOP_MAX_TRIANGLES;
    while (lv > 0 && (loop_triangle_count(ctl.nt, lv) < 0 || loop_triangle_count(ctl.nt, lv) > cap)) lv--;
    if (lv < levels)
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: %d levels would make more than %lld triangles; "
                     "refined %d times", d, levels, (long long)cap, lv);
    LoopMesh m;
    CstError sub;
    st = loop_subdivide(ctl.p, ctl.nv, ctl.idx, ctl.nt, lv, &m, &sub);
    if (st == CST_ERR_OOM) {
        pbrt_geom_free(&ctl);
        return pbrt_oom(ld);
    }
    if (st) {
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: %s; rendered as its control mesh, without "
                     "subdivision", d, sub.msg);
        free(ctl.n);
        free(ctl.uv);
        ctl.n = NULL;
        ctl.uv = NULL;
        *g = ctl;
        return CST_OK;
    }
    pbrt_geom_free(&ctl);
    memset(g, 0, sizeof *g);
    g->p = m.p;
    g->n = m.n;
    g->nv = m.nv;
    g->idx = m.idx;
    g->nt = m.nt;
    return CST_OK;
}

/* pbrt-v4's Shape "alpha" (every shape takes it): "float alpha" or "texture alpha" naming a
 * float texture; a constant 1 (the default) leaves the shape opaque. */
CstStatus pbrt_shape_alpha(Loader *ld, Params *ps, const char *d, CstAlpha *out)
{
    int tex = 0, found = 0;
    Color val = color_s(1.0f);
    float a = 1.0f;
    memset(out, 0, sizeof *out);
    TRY(pbrt_tex_param(ld, ps, d, "alpha", 1, &tex, &val, NULL));
    if (tex) {
        out->enabled = 1;
        out->texture = tex;
        return CST_OK;
    }
    Param *p = pbrt_find_param(ps, "alpha");
    if (p && p->type == PT_TEXTURE) {
        a = color_channel(val, 0); /* a constant texture */
        found = 1;
    } else {
        TRY(pbrt_get_float(ld, ps, d, "alpha", 1.0f, &a, &found));
    }
    if (!found || a >= 1.0f) return CST_OK;
    out->enabled = 1;
    out->value = a > 0.0f ? a : 0.0f;
    return CST_OK;
}

/* Whether a quadric can be an analytic shape here: not inside an object (instances hold
 * triangles), not a medium boundary (left out as every "interface" shape), and, when it
 * emits, placed by a similarity (area lights sample analytic shapes uniformly by area,
 * which a non-uniform scale would skew). Otherwise the caller falls back to the
 * tessellation (disk, sphere) or the skip (cylinder). */
static int moving_analytic(const Loader *ld)
{
    return pbrt_ctm_moving(ld) && !ld->gs.area.active && !pbrt_medium_transition(ld);
}

static int analytic_ok(const Loader *ld)
{
    float scale;
    if (ld->cur_obj >= 0 || ld->mats[ld->gs.material].interface) return 0;
    if (moving_analytic(ld)) return 1; /* an object of its own under a moving instance (add_analytic) */
    return !ld->gs.area.active || (transform_is_affine(&ld->gs.ctm.m) && is_similarity(&ld->gs.ctm.m, &scale));
}

/* Whether a full sphere must keep pbrt-v4's parametrization (u = phi / 2pi about the
 * object's +z from +x, v from the -z pole, dp/du along phi): caustic's own spheres are a
 * centre and a radius with their own uv about world +y (geometry/sphere.h), which a
 * texture, a bump or normal map, anisotropic roughness, hair or an alpha texture would see
 * (a normal-mapped sphere rendered +22 % off pbrt-v4). Emitting spheres stay caustic's
 * (sampled by the cone they subtend). A mix may hold any of these: kept exact too. */
static int sphere_needs_uv(const Loader *ld, Params *ps)
{
    const Material *m = &ld->mats[ld->gs.material].m;
    Param *a = pbrt_find_param(ps, "alpha");
    if (ld->gs.area.active) return 0;
    return m->albedo_texture || m->roughness_texture || m->displacement_texture || m->normal_map_texture ||
           m->eta_texture || m->k_texture || m->reflectance_texture ||
           m->anisotropic || m->type == MATERIAL_HAIR || m->type == MATERIAL_MIX || (a && a->type == PT_TEXTURE);
}

/* pbrt-v4's Area() of a quadric in object space (Cylinder, Disk, Sphere::Area). */
static double quadric_object_area(const CstShapeDesc *sd)
{
    const double phi = (double)sd->phi_max_degrees * (PBRT_PI / 180.0), r = (double)sd->radius;
    switch (sd->type) {
    case CST_SHAPE_CYLINDER: return phi * r * ((double)sd->z_max - (double)sd->z_min);
    case CST_SHAPE_DISK: return 0.5 * phi * (r * r - (double)sd->inner_radius * (double)sd->inner_radius);
    default: return phi * r * (fmin((double)sd->z_max, r) - fmax((double)sd->z_min, -r));
    }
}

/* The area light of the graphics state on an analytic shape: L x scale, or normalised to
 * `power` by the shape's world area as pbrt-v4's DiffuseAreaLight::Create does (pbrt-v4
 * takes the quadric's object-space Area(); the world area is used here, as for spheres,
 * the same under the rigid transforms of the scenes). */
static void analytic_emission(const Loader *ld, CstShapeDesc *sd)
{
    const AreaLight *al = &ld->gs.area;
    if (!al->active) return;
    ShapeEmission em = {color_scale(al->L, al->scale), al->two_sided, al->texture, al->spectrum};
    if (al->power > 0.0f) {
        float scale = 1.0f;
        (void)is_similarity(&ld->gs.ctm.m, &scale); /* analytic_ok held */
        double area = quadric_object_area(sd) * (double)scale * (double)scale;
        double k_e = (al->two_sided ? 2.0 : 1.0) * area * PBRT_PI * (al->texture ? (double)al->image_lum : 1.0);
        if (k_e > 0.0) em.radiance = color_scale(em.radiance, (float)((double)al->power / k_e));
    }
    sd->emission = emission_desc(&em);
}

static CstStatus add_moving_instance(Loader *ld, int proto, Loc loc, const char *d);

/* Under a moving CTM (moving_analytic): the shape sd, in object space (its
 * world_from_object the identity), into object *obj (-1: a new one, its id returned), as
 * pbrt-v4 makes an AnimatedPrimitive over the shape built with identity transforms. */
static CstStatus add_object_shape(Loader *ld, CstShapeDesc *sd, int *obj, Loc loc, const char *d)
{
    memset(sd->world_from_object, 0, sizeof sd->world_from_object);
    CstStatus st = cst_scene_add_object_shape(ld->scene, *obj, sd, obj, ld->err);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

/* A cylinder, disk or partial sphere placed by the CTM as an analytic shape (pbrt-v4's
 * quadrics: exact hits, uv and dp/du, normals flipped by ReverseOrientation and by a
 * mirroring CTM as pbrt does); under a moving CTM, an object of its own placed by a moving
 * instance (emitting shapes and shapes between two media: static, with a warning). */
static CstStatus add_analytic(Loader *ld, Params *ps, const char *d, Loc loc, CstShapeDesc *sd)
{
    CstAlpha alpha = {0};
    TRY(pbrt_shape_alpha(ld, ps, d, &alpha));
    pbrt_params_warn_unused(ld, ps, d);
    if (alpha.enabled && !alpha.texture && alpha.value == 0.0f) return CST_OK; /* as emit_shape's callers */
    TRY(pbrt_material_scene_id(ld, ld->gs.material, &sd->material));
    if (moving_analytic(ld)) {
        int obj = -1;
        sd->reverse_orientation = ld->gs.reverse != 0;
        sd->alpha = alpha;
        TRY(add_object_shape(ld, sd, &obj, loc, d));
        return add_moving_instance(ld, obj, loc, d);
    }
    pbrt_warn_static(ld, loc, d, ld->gs.area.active ? "emitting shapes do not move in caustic (moving instances do "
                     "not emit)" : "shapes between two media do not move in caustic");
    const Transform *m = &ld->gs.ctm.m;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) sd->world_from_object[4 * r + c] = m->m[r][c];
    if (transform_is_identity(m)) memset(sd->world_from_object, 0, sizeof sd->world_from_object);
    sd->reverse_orientation = ld->gs.reverse != 0;
    sd->alpha = alpha;
    analytic_emission(ld, sd);
    TRY(pbrt_medium_apply(ld, 0, loc, d)); /* its own MediumInterface, as emit_world_shape's */
    CstStatus st = cst_scene_add_shape(ld->scene, sd, ld->err);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

/* A "bilinearmesh" as exact bilinear patches (pbrt-v4's BilinearPatch: Reshetov 2019), one
 * analytic shape per patch, placed by the CTM; the patches g holds as triangle pairs
 * (read_mesh_params: (p00, p10, p11), (p00, p11, p01)). Patches without area (corners on
 * one line) are left out with a warning, as degenerate triangles are. */
static CstStatus bilinear_patches(Loader *ld, Params *ps, const char *d, Loc loc, const ShapeGeom *g)
{
    CstAlpha alpha = {0};
    TRY(pbrt_shape_alpha(ld, ps, d, &alpha));
    pbrt_params_warn_unused(ld, ps, d);
    if (alpha.enabled && !alpha.texture && alpha.value == 0.0f) return CST_OK; /* as emit_shape's callers */
    CstShapeDesc sd = {0};
    sd.type = CST_SHAPE_BILINEAR;
    TRY(pbrt_material_scene_id(ld, ld->gs.material, &sd.material));
    const Transform *m = &ld->gs.ctm.m;
    for (int r = 0; r < 3; r++)
        for (int c = 0; c < 4; c++) sd.world_from_object[4 * r + c] = m->m[r][c];
    if (transform_is_identity(m)) memset(sd.world_from_object, 0, sizeof sd.world_from_object);
    sd.reverse_orientation = ld->gs.reverse != 0;
    sd.alpha = alpha;
    sd.patch_has_normals = g->n != NULL;
    sd.patch_has_uvs = g->uv != NULL;
    int skipped = 0, obj = -1;
    const int moving = moving_analytic(ld);
    if (!moving) TRY(pbrt_medium_apply(ld, 0, loc, d)); /* its own MediumInterface */
    for (int f = 0; 2 * f < g->nt; f++) {
        const int *t = &g->idx[6 * f];
        const int v[4] = {t[0], t[1], t[5], t[2]}; /* p00, p10, p01, p11 */
        Vec3 corner[4];
        for (int k = 0; k < 4; k++) {
            corner[k] = g->p[v[k]];
            for (int c = 0; c < 3; c++) sd.patch[k][c] = v3_get(corner[k], c);
            if (g->n)
                for (int c = 0; c < 3; c++) sd.patch_normals[k][c] = v3_get(g->n[v[k]], c);
            if (g->uv) { sd.patch_uvs[k][0] = g->uv[v[k]].x; sd.patch_uvs[k][1] = g->uv[v[k]].y; }
        }
        AnalyticShape probe; /* area is kept by the invertible CTM: test in object space */
        if (!shape_init_bilinear(&probe, corner, NULL, NULL, false)) { skipped++; continue; }
        if (moving) { /* every patch in one object, placed by one moving instance */
            TRY(add_object_shape(ld, &sd, &obj, loc, d));
            continue;
        }
        CstStatus st = cst_scene_add_shape(ld->scene, &sd, ld->err);
        if (st) return pbrt_fail_wrap(ld, st, loc, d);
    }
    if (obj >= 0) TRY(add_moving_instance(ld, obj, loc, d));
    if (skipped)
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: %d bilinear patch%s without area left out", d, skipped,
                     skipped > 1 ? "es" : "");
    return CST_OK;
}

/* "bilinearmesh": exact patches (*exact set: added) where analytic_ok and not emitting,
 * else g as two triangles per patch (power_group 2), with a warning. */
static CstStatus bilinear_mesh(Loader *ld, Params *ps, const char *d, Loc loc, ShapeGeom *g, int *exact)
{
    TRY(read_mesh_params(ld, ps, d, loc, 4, g));
    if (analytic_ok(ld) && !ld->gs.area.active && transform_is_affine(&ld->gs.ctm.m)) {
        *exact = 1;
        return bilinear_patches(ld, ps, d, loc, g);
    }
    g->power_group = 2;
    pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: each bilinear patch split into two triangles, exact for "
                 "planar patches (emitting, in an object, or an interface)", d);
    return CST_OK;
}

/* pbrt-v4's Cylinder: radius 1, z from -1 to 1 (either order), phimax 360. */
static CstStatus cylinder_shape(Loader *ld, Params *ps, const char *d, Loc loc)
{
    float r = 1.0f, zmin = -1.0f, zmax = 1.0f, phimax = 360.0f;
    TRY(pbrt_get_float(ld, ps, d, "radius", 1.0f, &r, NULL));
    TRY(pbrt_get_float(ld, ps, d, "zmin", -1.0f, &zmin, NULL));
    TRY(pbrt_get_float(ld, ps, d, "zmax", 1.0f, &zmax, NULL));
    TRY(pbrt_get_float(ld, ps, d, "phimax", 360.0f, &phimax, NULL));
    float z0 = minf(zmin, zmax), z1 = maxf(zmin, zmax);
    if (!(r > 0.0f) || !(z0 < z1) || !(phimax > 0.0f) || !pbrt_coords_ok(v3(r, z0, z1)))
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g, zmin %g, zmax %g, phimax %g; expected "
                            "radius > 0, zmin != zmax and phimax > 0", d, (double)r, (double)zmin, (double)zmax,
                            (double)phimax);
    CstShapeDesc sd = {.type = CST_SHAPE_CYLINDER, .radius = r, .z_min = z0, .z_max = z1,
                       .phi_max_degrees = clampf(phimax, 0.0f, 360.0f)};
    return add_analytic(ld, ps, d, loc, &sd);
}

static CstStatus emit_moving_shape(Loader *ld, const ShapeGeom *g, const CstAlpha *alpha, Loc loc, const char *d);

/* A shape of the world (not in an object, not an interface): a moving instance when the CTM
 * moves and instances can hold it (triangles, with their uvs and alpha: the prototype's
 * per-triangle cut-out), else placed by the start CTM. */
static CstStatus emit_world_shape(Loader *ld, const ShapeGeom *g, const CstAlpha *alpha, Loc loc, const char *d)
{
    /* A constant alpha of 0 (sportscar's hidden area lights): no ray ever meets the shape
     * and it emits nowhere, so leaving it out renders exactly what pbrt-v4 does, without the
     * light sampler picking a light that gives nothing. */
    if (alpha->enabled && !alpha->texture && alpha->value == 0.0f) return CST_OK;
    if (pbrt_ctm_moving(ld) && !g->is_sphere && !ld->gs.area.active && !pbrt_medium_transition(ld))
        return emit_moving_shape(ld, g, alpha, loc, d);
    TRY(pbrt_medium_apply(ld, 0, loc, d));
    pbrt_warn_static(ld, loc, d, ld->gs.area.active ? "emitting shapes do not move in caustic (moving instances do not emit)"
                                 : "shapes between two media do not move in caustic");
    return emit_shape(ld, g, &ld->gs.ctm, ld->gs.reverse, ld->gs.material, &ld->gs.area, alpha, loc, d);
}

CstStatus pbrt_shape_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *type = NULL, nm[72], d[96];
    Params ps = {0};
    ShapeGeom g = {0};
    Loc tl;
    CstStatus st = pbrt_expect_string(ld, lx, "Shape", "the shape type, as in \"trianglemesh\"", &type, &tl);
    if (!st) st = pbrt_parse_params(ld, lx, &ps);
    if (st) goto done;
    snprintf(d, sizeof d, "Shape \"%s\"", pbrt_clip(type, nm));
    if (!ld->in_world) {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "Shape before WorldBegin; expected shapes in the world block");
        goto done;
    }
    int skip = 0;
    if (strcmp(type, "trianglemesh") == 0) {
        st = read_mesh_params(ld, &ps, d, loc, 3, &g);
    } else if (strcmp(type, "bilinearmesh") == 0) {
        int exact = 0;
        st = bilinear_mesh(ld, &ps, d, loc, &g, &exact);
        if (exact) goto done;
    } else if (strcmp(type, "loopsubdiv") == 0) {
        st = loop_shape(ld, &ps, d, loc, &g);
    } else if (strcmp(type, "plymesh") == 0) {
        st = plymesh(ld, &ps, d, loc, &g);
        if (!st) st = pbrt_displace_shape(ld, &ps, d, loc, &g);
    } else if (strcmp(type, "sphere") == 0) {
        float r = 1.0f, zmin = 0, zmax = 0, phimax = 360.0f;
        int hz0 = 0, hz1 = 0, hp = 0;
        st = pbrt_get_float(ld, &ps, d, "radius", 1.0f, &r, NULL);
        if (!st) st = pbrt_get_float(ld, &ps, d, "zmin", -r, &zmin, &hz0);
        if (!st) st = pbrt_get_float(ld, &ps, d, "zmax", r, &zmax, &hz1);
        if (!st) st = pbrt_get_float(ld, &ps, d, "phimax", 360.0f, &phimax, &hp);
        if (st) goto done;
        if (!(r > 0.0f)) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g; expected a radius > 0", d, (double)r);
            goto done;
        }
        int partial = (hz0 && zmin > -r) || (hz1 && zmax < r) || (hp && phimax < 360.0f);
        if ((partial || sphere_needs_uv(ld, &ps) || moving_analytic(ld)) && analytic_ok(ld)) {
            if (!(zmin < zmax) || !(phimax > 0.0f)) {
                st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: zmin %g, zmax %g, phimax %g; expected "
                                  "zmin < zmax and phimax > 0", d, (double)zmin, (double)zmax, (double)phimax);
                goto done;
            }
            CstShapeDesc sd = {.type = CST_SHAPE_SPHERE, .radius = r, .z_min = zmin, .z_max = zmax,
                               .phi_max_degrees = clampf(phimax, 0.0f, 360.0f)};
            st = add_analytic(ld, &ps, d, loc, &sd);
            goto done;
        }
        if (partial)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: partial sphere (zmin, zmax, phimax) "
                         "rendered as the full sphere (in an object, or emitting under a non-uniform scale)", d);
        g.is_sphere = 1;
        g.radius = r;
    } else if (strcmp(type, "disk") == 0) {
        float h = 0.0f, r = 1.0f, ri = 0.0f, phimax = 360.0f;
        st = pbrt_get_float(ld, &ps, d, "height", 0.0f, &h, NULL);
        if (!st) st = pbrt_get_float(ld, &ps, d, "radius", 1.0f, &r, NULL);
        if (!st) st = pbrt_get_float(ld, &ps, d, "innerradius", 0.0f, &ri, NULL);
        if (!st) st = pbrt_get_float(ld, &ps, d, "phimax", 360.0f, &phimax, NULL);
        if (st) goto done;
        if (!(r > 0.0f) || !(ri >= 0.0f) || !(ri < r) || !(phimax > 0.0f) || !pbrt_coords_ok(v3(r, h, 0.0f))) {
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "%s: radius %g, innerradius %g, phimax %g; "
                              "expected 0 <= innerradius < radius and phimax > 0", d, (double)r,
                              (double)ri, (double)phimax);
            goto done;
        }
        if (analytic_ok(ld)) {
            CstShapeDesc sd = {.type = CST_SHAPE_DISK, .radius = r, .height = h, .inner_radius = ri,
                               .phi_max_degrees = clampf(phimax, 0.0f, 360.0f)};
            st = add_analytic(ld, &ps, d, loc, &sd);
            goto done;
        }
        st = disk_mesh(ld, h, r, ri, phimax, &g);
        g.power_group = g.nt; /* one disk: its power over all its triangles */
        if (!st)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s (in an object, or emitting under a non-uniform scale) tessellated into %d "
                         "triangles of the same total area", d, g.nt);
    } else if (strcmp(type, "curve") == 0) {
        st = pbrt_curve_shape(ld, &ps, d, loc);
        goto done;
    } else if (strcmp(type, "cylinder") == 0 && analytic_ok(ld)) {
        st = cylinder_shape(ld, &ps, d, loc);
        goto done;
    } else if (strcmp(type, "cylinder") == 0 || strcmp(type, "cone") == 0 ||
               strcmp(type, "paraboloid") == 0 || strcmp(type, "hyperboloid") == 0 ||
               strcmp(type, "nurbs") == 0 ||
               strcmp(type, "heightfield") == 0) {
        skip = 1;
        pbrt_params_mark_all_used(&ps);
        pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s is not supported%s; skipped", d,
                     strcmp(type, "cylinder") == 0 ? " (in an object, an interface, or emitting under a non-uniform "
                                                     "scale)" : "");
    } else {
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, tl, "unknown shape \"%s\"; expected one of: "
                     "trianglemesh, plymesh, bilinearmesh, loopsubdiv, sphere, disk, curve (or the "
                          "unsupported cylinder, cone, paraboloid, hyperboloid)", pbrt_clip(type, nm));
    }
    if (st || skip) goto done;
    CstAlpha alpha = {0};
    if ((st = pbrt_shape_alpha(ld, &ps, d, &alpha)) != CST_OK) goto done;
    pbrt_params_warn_unused(ld, &ps, d);
    if (ld->mats[ld->gs.material].interface && ld->cur_obj < 0 && !ld->gs.area.active &&
        pbrt_medium_transition(ld)) {
        /* A boundary between two media: kept, invisible but for the change of medium. */
        if ((st = pbrt_medium_apply(ld, 1, loc, d)) == CST_OK)
            st = emit_shape(ld, &g, &ld->gs.ctm, ld->gs.reverse, ld->gs.material, &ld->gs.area, &alpha, loc, d);
    } else if (ld->mats[ld->gs.material].interface && !(ld->cur_obj < 0 && ld->gs.area.active)) {
        /* An "interface" shape that separates no two media caustic renders (equal sides,
         * or a medium type read as vacuum) scatters nothing and changes no medium, so
         * leaving it out is exact for every ray, shadow rays included. An emitting one
         * stays, as glass of eta 1 (it would block shadow rays). */
        if (ld->num_interface_shapes++ == 0)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: shapes with material \"interface\" (medium "
                         "boundaries) that separate no two rendered media are left out", d);
    } else if (ld->gs.area.active && ld->mats[ld->gs.material].interface && ld->cur_obj < 0) {
        pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: an emitting shape with material \"interface\" "
                     "is kept as glass of eta 1: paths pass through it, shadow rays are blocked", d);
        if ((st = pbrt_medium_apply(ld, 0, loc, d)) == CST_OK)
            st = emit_shape(ld, &g, &ld->gs.ctm, ld->gs.reverse, ld->gs.material, &ld->gs.area, &alpha, loc, d);
    } else if (ld->cur_obj >= 0 && alpha.enabled && !alpha.texture && alpha.value == 0.0f) {
        /* a constant alpha of 0 in an object: left out, as below */
    } else if (ld->cur_obj >= 0) {
        Object *o = &ld->objs[ld->cur_obj];
        if (ld->gs.area.active)
            pbrt_warn_at(ld, CST_WARN_UNSUPPORTED, loc, "%s: area lights inside ObjectBegin are not "
                         "supported (as in pbrt-v4); the shape does not emit", d);
        pbrt_warn_static(ld, loc, d, "shapes inside ObjectBegin do not move in caustic (instances of them do)");
        if (!GROW(o->shapes, o->cap, o->n + 1)) { st = pbrt_oom(ld); goto done; }
        ObjShape *os = &o->shapes[o->n++];
        os->g = g;
        os->xf = ld->gs.ctm;
        os->reverse = ld->gs.reverse;
        os->material = ld->gs.material;
        os->alpha = alpha;
        os->loc = loc;
        memset(&g, 0, sizeof g);
    } else {
        st = emit_world_shape(ld, &g, &alpha, loc, d);
    }
done:
    pbrt_geom_free(&g);
    free(type);
    pbrt_params_free(&ps);
    return st;
}

/* The object's triangles, placed by their definition transforms with pbrt's orientation
 * rule (as emit_shape does), as one instanced object of the scene, with their uvs and
 * each shape's alpha cut-out. Degenerate triangles are dropped; an object without
 * triangles gets no prototype. When some shapes have uvs and others not, the latter's
 * triangles get vertices of their own with the default uvs (0,0), (1,0), (0,1) of their
 * corners (triangle_uv's, as the same shape outside an object). */
static CstStatus make_proto(Loader *ld, Object *obj, const char *d)
{
    int nv = 0, nt = 0, any_n = 0, any_uv = 0, any_alpha = 0;
    for (int i = 0; i < obj->n; i++) {
        const ShapeGeom *g = &obj->shapes[i].g;
        if (g->is_sphere) continue;
        any_n |= g->n != NULL; /* vertex normals (N) on some shape: shading normals, zero where none */
        any_uv |= g->uv != NULL;
        any_alpha |= obj->shapes[i].alpha.enabled;
    }
    for (int i = 0; i < obj->n; i++) {
        const ShapeGeom *g = &obj->shapes[i].g;
        if (g->is_sphere) continue;
        int gv = any_uv && !g->uv ? (g->nt > INT_MAX / 3 ? INT_MAX : 3 * g->nt) : g->nv;
        if (gv > INT_MAX - nv || g->nt > PBRT_MAX_TRIANGLES - nt)
            return pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, obj->loc, "%s: the object has too many triangles", d);
        nv += gv;
        nt += g->nt;
    }
    if (nt == 0) return CST_OK;
    CstStatus st = CST_OK;
    /* zeroed: the corners of dropped triangles stay defined */
    Vec3 *p = calloc((size_t)nv, sizeof *p), *n = any_n ? calloc((size_t)nv, sizeof *n) : NULL;
    Vec2 *uv = any_uv ? calloc((size_t)nv, sizeof *uv) : NULL;
    CstAlpha *al = any_alpha ? malloc((size_t)nt * sizeof *al) : NULL;
    int *idx = malloc((size_t)nt * 3 * sizeof *idx), *mat = malloc((size_t)nt * sizeof *mat);
    int vbase = 0, t_out = 0, dropped = 0;
    if (!p || !idx || !mat || (any_n && !n) || (any_uv && !uv) || (any_alpha && !al)) {
        st = pbrt_oom(ld);
        goto done;
    }
    for (int i = 0; i < obj->n && !st; i++) {
        const ObjShape *os = &obj->shapes[i];
        const ShapeGeom *g = &os->g;
        if (g->is_sphere) continue;
        int m = 0;
        if ((st = pbrt_material_scene_id(ld, os->material, &m))) goto done;
        int swap = (transform_det(&os->xf.m) < 0.0) != (os->reverse != 0);
        const int unshared = any_uv && !g->uv; /* vertices per triangle corner */
        Transform nm = transform_identity();
        transform_normal_matrix(&os->xf.m, &nm);
        for (int v = 0; v < g->nv; v++) {
            Vec3 pv = transform_point(&os->xf.m, g->p[v]);
            if (!pbrt_coords_ok(pv)) {
                st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, os->loc, "%s: vertex %d of the object is beyond "
                                  "the scene limit", d, v);
                goto done;
            }
            if (unshared) continue;
            p[vbase + v] = pv;
            if (g->n) n[vbase + v] = transform_normal(&nm, g->n[v]);
            if (g->uv) uv[vbase + v] = g->uv[v];
        }
        for (int t = 0; t < g->nt; t++) {
            int c[3] = {g->idx[3 * t], g->idx[3 * t + 1], g->idx[3 * t + 2]};
            Vec3 pc[3];
            for (int k = 0; k < 3; k++) pc[k] = transform_point(&os->xf.m, g->p[c[k]]);
            int sw = swap;
            if (g->n) {
                Vec3 ns = v3_add(v3_add(transform_normal(&nm, g->n[c[0]]), transform_normal(&nm, g->n[c[1]])),
                                 transform_normal(&nm, g->n[c[2]]));
                if (os->reverse) ns = v3_neg(ns);
                sw = v3_dot(v3_cross(v3_sub(pc[1], pc[0]), v3_sub(pc[2], pc[0])), ns) < 0.0f;
            }
            if (!(triangle_area(pc[0], pc[1], pc[2]) > 0.0f)) {
                dropped++;
                continue;
            }
            const int order[3] = {0, sw ? 2 : 1, sw ? 1 : 2};
            for (int k = 0; k < 3; k++) {
                int v = c[order[k]];
                if (unshared) { /* corner k of the stored triangle: triangle_uv's default */
                    int u = vbase + 3 * t + k;
                    p[u] = pc[order[k]];
                    if (g->n) n[u] = transform_normal(&nm, g->n[v]);
                    uv[u] = v2(k == 1 ? 1.0f : 0.0f, k == 2 ? 1.0f : 0.0f);
                    v = 3 * t + k;
                }
                idx[3 * t_out + k] = vbase + v;
            }
            if (al) al[t_out] = os->alpha;
            mat[t_out++] = m;
        }
        vbase += unshared ? 3 * g->nt : g->nv;
    }
    if (dropped)
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, obj->loc, "ObjectBegin \"%s\": %d degenerate triangles dropped",
                     obj->name, dropped);
    if (t_out > 0) {
        /* Normals as emit_shape passes them: unit from transform_normal, zero where none. */
        CstMeshDesc od = {0};
        od.positions = p;
        od.position_stride = sizeof *p;
        od.num_vertices = nv;
        od.normals = n;
        od.normal_stride = sizeof(Vec3);
        od.normals_unit = 1;
        od.uvs = uv;
        od.uv_stride = sizeof(Vec2);
        od.indices = idx;
        od.index_stride = 3 * sizeof *idx;
        od.num_triangles = t_out;
        od.triangle_materials = mat;
        od.triangle_alphas = al;
        st = cst_scene_add_object(ld->scene, &od, &obj->proto, NULL, ld->err);
        if (st) st = pbrt_fail_wrap(ld, st, obj->loc, d);
    }
done:
    free(p);
    free(n);
    free(uv);
    free(al);
    free(idx);
    free(mat);
    return st;
}

/* Object id `proto` placed by the moving CTM (ctm at time 0, ctm_end at 1): a moving
 * instance, pbrt-v4's AnimatedPrimitive. Its affine parts, as static instances; a singular
 * end is skipped with a warning, as a static instance's. */
static CstStatus add_moving_instance(Loader *ld, int proto, Loc loc, const char *d)
{
    const Transform *m0 = &ld->gs.ctm.m, *m1 = &ld->gs.ctm_end.m;
    Transform inv;
    if (!transform_invert(m0, &inv) || !transform_invert(m1, &inv)) {
        pbrt_warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: the transform at the start or end time is singular; skipped", d);
        return CST_OK;
    }
    float r0[12], r1[12];
    for (int r = 0; r < 3; r++) {
        memcpy(&r0[4 * r], m0->m[r], sizeof m0->m[r]);
        memcpy(&r1[4 * r], m1->m[r], sizeof m1->m[r]);
    }
    CstStatus st = cst_scene_add_instance_motion(ld->scene, proto, r0, r1, ld->err);
    return st ? pbrt_fail_wrap(ld, st, loc, d) : CST_OK;
}

/* A triangle shape under a moving CTM: its triangles in object space as an object of its
 * own (make_proto's orientation rule), placed by a moving instance (as the JSON loader's
 * moving meshes). pbrt-v4 makes the same: the shape in object space under an
 * AnimatedPrimitive. The prototype keeps the shape's uvs and its alpha (constant or a
 * texture) as every triangle's cut-out, tested at the ray's time like a static shape's. */
static CstStatus emit_moving_shape(Loader *ld, const ShapeGeom *g, const CstAlpha *alpha, Loc loc, const char *d)
{
    ObjShape os = {.g = *g, .xf = pbrt_xf_identity(), .reverse = ld->gs.reverse, .material = ld->gs.material,
                   .alpha = *alpha, .loc = loc};
    char name[] = "(a moving shape)";
    Object tmp = {.name = name, .shapes = &os, .n = 1, .cap = 1, .loc = loc, .proto = -1};
    TRY(make_proto(ld, &tmp, d));
    return tmp.proto >= 0 ? add_moving_instance(ld, tmp.proto, loc, d) : CST_OK;
}

CstStatus pbrt_object_instance_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)dname;
    char *name = NULL, nm[72];
    Loc nl;
    TRY(pbrt_expect_string(ld, lx, "ObjectInstance", "the object's name", &name, &nl));
    CstStatus st = CST_OK;
    int o = -1;
    for (int i = 0; i < ld->num_objs; i++)
        if (strcmp(ld->objs[i].name, name) == 0) o = i;
    if (!ld->in_world)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectInstance before WorldBegin; expected it in the world block");
    else if (ld->cur_obj >= 0)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectInstance inside ObjectBegin \"%s\"; "
                          "expected instances outside object definitions", pbrt_clip(ld->objs[ld->cur_obj].name, nm));
    else if (o < 0)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, nl, "ObjectInstance: object \"%s\" is not defined; "
                          "expected a name given to ObjectBegin before", pbrt_clip(name, nm));
    if (st) {
        free(name);
        return st;
    }
    char d[96];
    snprintf(d, sizeof d, "ObjectInstance \"%s\"", pbrt_clip(name, nm));
    free(name);
    Object *obj = &ld->objs[o];
    if (obj->proto < 0) {
        st = make_proto(ld, obj, d);
        if (st) return st;
    }
    if (obj->proto >= 0 && pbrt_ctm_moving(ld)) {
        st = add_moving_instance(ld, obj->proto, loc, d);
        if (st) return st;
    } else if (obj->proto >= 0) {
        Xf xf = ld->gs.ctm;
        Transform inv;
        if (!transform_invert(&xf.m, &inv)) {
            /* flat (Scale 0) or not finite when inverted: nothing a ray could hit */
            pbrt_warn_at(ld, CST_WARN_GEOMETRY, loc, "%s: the instance transform is singular; skipped", d);
        } else {
            /* a projective instance transform (warned at its ConcatTransform/Transform):
             * its affine part, the instance BVH being affine */
            float rows[12];
            for (int r = 0; r < 3; r++) memcpy(&rows[4 * r], xf.m.m[r], sizeof xf.m.m[r]);
            st = cst_scene_add_instance(ld->scene, obj->proto, rows, ld->err);
            if (st) return pbrt_fail_wrap(ld, st, loc, d);
        }
    }
    /* Spheres are not instanced (the prototypes hold triangles): they are placed as copies. */
    for (int i = 0; i < obj->n && !st; i++) {
        const ObjShape *os = &obj->shapes[i];
        if (!os->g.is_sphere) continue;
        if (ld->num_instances_expanded++ == 0)
            pbrt_warn_at(ld, CST_WARN_APPROXIMATED, loc, "%s: spheres in instanced objects are placed "
                         "as copies (only triangles are instanced)", d);
        pbrt_warn_static(ld, loc, d, "its spheres are copies, which do not move");
        Xf xf = pbrt_xf_compose(&ld->gs.ctm, &os->xf);
        st = emit_shape(ld, &os->g, &xf, os->reverse, os->material, NULL, &os->alpha, loc, d);
    }
    return st;
}

CstStatus pbrt_object_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    char *s = NULL, nm[72];
    CstStatus st = CST_OK;
    Loc nl;
    TRY(pbrt_expect_string(ld, lx, dname, "the object's name", &s, &nl));
    if (!ld->in_world) st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectBegin before WorldBegin; expected it in the world block");
    else if (ld->cur_obj >= 0)
        st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectBegin inside ObjectBegin \"%s\"; "
                          "expected ObjectEnd first", pbrt_clip(ld->objs[ld->cur_obj].name, nm));
    for (int i = 0; !st && i < ld->num_objs; i++)
        if (strcmp(ld->objs[i].name, s) == 0)
            st = pbrt_fail_at(ld, CST_ERR_INVALID_ARG, nl, "ObjectBegin: \"%s\" is already defined "
                              "(line %d); expected each name once", pbrt_clip(s, nm), ld->objs[i].loc.line);
    if (!st) st = pbrt_push_state(ld, loc, 0);
    if (!st && !GROW(ld->objs, ld->cap_objs, ld->num_objs + 1)) st = pbrt_oom(ld);
    if (st) {
        free(s);
        return st;
    }
    Object *o = &ld->objs[ld->num_objs];
    memset(o, 0, sizeof *o);
    o->name = s;
    o->loc = loc;
    o->proto = -1;
    ld->cur_obj = ld->num_objs++;
    return CST_OK;
}

CstStatus pbrt_object_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname)
{
    (void)lx;
    if (ld->cur_obj < 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, loc, "ObjectEnd without ObjectBegin; expected it "
                            "only to close an object definition");
    ld->cur_obj = -1;
    return pbrt_pop_state(ld, loc, 0, dname);
}
