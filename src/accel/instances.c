/* Two-level acceleration for instancing: per-prototype BVHs (bvh.c, via accel_build) and
 * a top-level binary BVH over instance bounds, split at the median centroid of the widest
 * axis; a moving instance's bound covers its whole motion and a ray meets it placed at the
 * ray's time. A ray enters an instance by the inverse transform; its direction is renormalised
 * there (the BVH and triangle tests expect unit directions) and t rescaled by that length
 * on the way in and out, so hits from different instances compare in world t. */
#include "accel/instances.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"

/* Depth of the top-level tree: median splits halve the count, so 64 covers any int count. */
#define INST_STACK 64

/* Room for one more element; counts stay int, so INT_MAX of them at most. */
static bool grow_one(void *arr, size_t *cap, int num, size_t size)
{
    return num < INT_MAX && array_grow(arr, cap, (size_t)num + 1, size);
}

CstStatus instances_add_proto(InstanceSet *set, const Vec3 *positions, const Vec3 *normals,
                              int num_positions, const int *indices, const int *tri_material,
                              int num_triangles, int *out_id, CstError *err)
{
    if (set->built) return cst_fail(err, CST_ERR_INVALID_ARG, "instances already built");
    if (!grow_one(&set->protos, &set->cap_protos, set->num_protos, sizeof *set->protos))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding an instanced object");
    InstProto *p = &set->protos[set->num_protos];
    memset(p, 0, sizeof *p);
    size_t nv = (size_t)(num_positions > 0 ? num_positions : 1), nt = (size_t)(num_triangles > 0 ? num_triangles : 1);
    p->positions = malloc(nv * sizeof *p->positions);
    p->tri_indices = malloc(3 * nt * sizeof *p->tri_indices);
    p->tri_material = malloc(nt * sizeof *p->tri_material);
    if (normals) p->normals = malloc(nv * sizeof *p->normals);
    if (!p->positions || !p->tri_indices || !p->tri_material || (normals && !p->normals)) {
        free(p->positions);
        free(p->normals);
        free(p->tri_indices);
        free(p->tri_material);
        return cst_fail(err, CST_ERR_OOM, "out of memory for an instanced object of %d triangles", num_triangles);
    }
    /* An object of analytic shapes only has no triangles (and NULL arrays: no memcpy). */
    if (num_positions > 0) memcpy(p->positions, positions, (size_t)num_positions * sizeof *positions);
    if (normals && num_positions > 0) memcpy(p->normals, normals, (size_t)num_positions * sizeof *normals);
    for (int i = 0; i < 3 * num_triangles; i++) p->tri_indices[i] = indices[i];
    for (int i = 0; i < num_triangles; i++) p->tri_material[i] = tri_material[i];
    p->num_positions = num_positions;
    p->num_triangles = num_triangles;
    *out_id = set->num_protos++;
    return CST_OK;
}

CstStatus instances_proto_set_surface(InstanceSet *set, int proto, const Vec2 *uvs, const int *tri_alpha,
                                      CstError *err)
{
    if (set->built) return cst_fail(err, CST_ERR_INVALID_ARG, "instances already built");
    if (proto < 0 || proto >= set->num_protos)
        return cst_fail(err, CST_ERR_INVALID_ARG, "instanced object %d out of range", proto);
    InstProto *p = &set->protos[proto];
    int any_alpha = 0;
    for (int t = 0; tri_alpha && t < p->num_triangles; t++) any_alpha |= tri_alpha[t] != 0;
    Vec2 *uv = uvs ? malloc((size_t)p->num_positions * sizeof *uv) : NULL;
    int32_t *al = any_alpha ? malloc((size_t)p->num_triangles * sizeof *al) : NULL;
    if ((uvs && !uv) || (any_alpha && !al)) {
        free(uv);
        free(al);
        return cst_fail(err, CST_ERR_OOM, "out of memory for an instanced object's uvs and cut-outs");
    }
    if (uv) memcpy(uv, uvs, (size_t)p->num_positions * sizeof *uv);
    for (int t = 0; al && t < p->num_triangles; t++) al[t] = tri_alpha[t];
    free(p->uvs);
    free(p->tri_alpha);
    p->uvs = uv;
    p->tri_alpha = al;
    return CST_OK;
}

CstStatus instances_proto_add_shape(InstanceSet *set, int proto, const AnalyticShape *shape, int material, int alpha,
                                    CstError *err)
{
    if (set->built) return cst_fail(err, CST_ERR_INVALID_ARG, "instances already built");
    if (proto < 0 || proto >= set->num_protos)
        return cst_fail(err, CST_ERR_INVALID_ARG, "instanced object %d out of range", proto);
    InstProto *p = &set->protos[proto];
    size_t cap = p->cap_shapes;
    if (p->num_shapes >= INT_MAX - p->num_triangles || !grow_one(&p->shapes, &cap, p->num_shapes, sizeof *p->shapes))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a shape to an instanced object");
    /* The per-shape ids grow with the shapes: their capacity is cap_shapes too. */
    int32_t *m = realloc(p->shape_material, cap * sizeof *m), *a = m ? realloc(p->shape_alpha, cap * sizeof *a) : NULL;
    if (m) p->shape_material = m;
    if (a) p->shape_alpha = a;
    if (!m || !a) return cst_fail(err, CST_ERR_OOM, "out of memory adding a shape to an instanced object");
    p->cap_shapes = cap;
    p->shapes[p->num_shapes] = *shape;
    p->shape_material[p->num_shapes] = material;
    p->shape_alpha[p->num_shapes] = alpha;
    p->num_shapes++;
    return CST_OK;
}

static void proto_free(InstProto *p)
{
    free(p->positions);
    free(p->normals);
    free(p->tri_indices);
    free(p->tri_material);
    free(p->uvs);
    free(p->tri_alpha);
    free(p->tri_normals);
    for (int k = 0; k < p->num_shapes; k++) shape_release(&p->shapes[k]);
    free(p->shapes);
    free(p->shape_material);
    free(p->shape_alpha);
    accel_free(&p->accel);
}

void instances_pop_proto(InstanceSet *set)
{
    if (set->built || set->num_protos == 0) return;
    proto_free(&set->protos[--set->num_protos]);
}

CstStatus instances_add(InstanceSet *set, int proto, const Transform *world_from_obj, CstError *err)
{
    if (set->built) return cst_fail(err, CST_ERR_INVALID_ARG, "instances already built");
    if (proto < 0 || proto >= set->num_protos)
        return cst_fail(err, CST_ERR_INVALID_ARG, "instanced object %d out of range", proto);
    Instance in;
    memset(&in, 0, sizeof in);
    in.world_from_obj = *world_from_obj;
    if (!transform_is_affine(world_from_obj) || !transform_invert(world_from_obj, &in.obj_from_world) ||
        !transform_normal_matrix(world_from_obj, &in.normal_matrix))
        return cst_fail(err, CST_ERR_INVALID_ARG, "instance transform is singular or not affine");
    in.proto = proto;
    in.motion = -1;
    if (!grow_one(&set->insts, &set->cap_insts, set->num_insts, sizeof *set->insts))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding an instance");
    set->insts[set->num_insts++] = in;
    return CST_OK;
}

CstStatus instances_add_moving(InstanceSet *set, int proto, const Transform *start, const Transform *end,
                               CstError *err)
{
    CstStatus st = instances_add(set, proto, start, err);
    if (st != CST_OK || memcmp(start->m, end->m, sizeof start->m) == 0) return st;
    Transform inv;
    MotionTransform mt;
    if (!transform_is_affine(end) || !transform_invert(end, &inv) || !motion_init(&mt, start, end)) {
        set->num_insts--;
        return cst_fail(err, CST_ERR_INVALID_ARG, "instance end transform is singular or not affine");
    }
    if (!grow_one(&set->motions, &set->cap_motions, set->num_motions, sizeof *set->motions)) {
        set->num_insts--;
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a moving instance");
    }
    set->motions[set->num_motions] = mt;
    set->insts[set->num_insts - 1].motion = set->num_motions++;
    return CST_OK;
}

/* The transforms of a moving instance at time: interpolated, then inverted and the normal
 * matrix made, per ray (no per-time cache: rays of a path share a time, but instances are
 * visited by rays of many paths). A singular interpolated transform (a stretch through
 * zero) places nothing: false. */
static bool placement_at(const InstanceSet *set, const Instance *in, float time, Transform *world_from_obj,
                         Transform *obj_from_world, Transform *normal_matrix)
{
    *world_from_obj = motion_at(&set->motions[in->motion], time);
    return transform_invert(world_from_obj, obj_from_world) &&
           (!normal_matrix || transform_normal_matrix(world_from_obj, normal_matrix));
}

void instances_placement(const InstanceSet *set, int inst, float time, Transform *world_from_obj,
                         Transform *normal_matrix)
{
    const Instance *in = &set->insts[inst];
    Transform inv;
    if (in->motion < 0 || !placement_at(set, in, time, world_from_obj, &inv, normal_matrix)) {
        *world_from_obj = in->world_from_obj;
        *normal_matrix = in->normal_matrix;
    }
}

bool instances_rest_frame(const InstanceSet *set, int inst, float time, Transform *rest_from_world,
                          Transform *world_from_rest, Transform *normal_matrix)
{
    const Instance *in = &set->insts[inst];
    if (in->motion < 0 || !set->motions[in->motion].moving) return false;
    Transform w, w_inv;
    if (!placement_at(set, in, time, &w, &w_inv, NULL)) return false;
    *rest_from_world = transform_compose(motion_at(&set->motions[in->motion], 0.0f), w_inv);
    return transform_invert(rest_from_world, world_from_rest) && transform_normal_matrix(rest_from_world, normal_matrix);
}

static float centroid(const InstanceSet *set, int32_t id, int axis)
{
    return v3_get(bbox_center(set->insts[id].bounds), axis);
}

/* Reorders a[lo, hi) so that a[nth] has the key it would have sorted, smaller keys before
 * it and larger after (quickselect with a three-way partition, so runs of equal keys end). */
static void select_nth(const InstanceSet *set, int32_t *a, int lo, int hi, int nth, int axis)
{
    while (hi - lo > 1) {
        float pv = centroid(set, a[lo + (hi - lo) / 2], axis);
        int lt = lo, i = lo, gt = hi;
        while (i < gt) {
            float k = centroid(set, a[i], axis);
            int32_t tmp;
            if (k < pv) {
                tmp = a[lt]; a[lt] = a[i]; a[i] = tmp;
                lt++;
                i++;
            } else if (k > pv) {
                gt--;
                tmp = a[gt]; a[gt] = a[i]; a[i] = tmp;
            } else {
                i++;
            }
        }
        if (nth < lt) hi = lt;
        else if (nth >= gt) lo = gt;
        else return;
    }
}

/* Builds the subtree of order[lo, hi) into nodes[at]. */
static void build_node(InstanceSet *set, int at, int lo, int hi)
{
    InstNode *n = &set->nodes[at];
    BBox b = bbox_empty(), c = bbox_empty();
    for (int i = lo; i < hi; i++) {
        const Instance *in = &set->insts[set->order[i]];
        b = bbox_union(b, in->bounds);
        c = bbox_add(c, bbox_center(in->bounds));
    }
    n->box = b;
    if (hi - lo <= 2) {
        n->first = lo;
        n->count = hi - lo;
        return;
    }
    Vec3 ext = v3_sub(c.max, c.min);
    int axis = ext.x >= ext.y && ext.x >= ext.z ? 0 : (ext.y >= ext.z ? 1 : 2);
    int mid = lo + (hi - lo) / 2;
    select_nth(set, set->order, lo, hi, mid, axis);
    int left = set->num_nodes;
    set->num_nodes += 2;
    n->first = left;
    n->count = 0;
    build_node(set, left, lo, mid);
    build_node(set, left + 1, mid, hi);
}

CstStatus instances_build(InstanceSet *set, CstError *err)
{
    if (set->built) return CST_OK;
    for (int i = 0; i < set->num_protos; i++) {
        InstProto *p = &set->protos[i];
        p->tri_normals = malloc((size_t)(p->num_triangles > 0 ? p->num_triangles : 1) * sizeof *p->tri_normals);
        if (!p->tri_normals) return cst_fail(err, CST_ERR_OOM, "out of memory for instance normals");
        for (int t = 0; t < p->num_triangles; t++) {
            const int32_t *v = &p->tri_indices[3 * t];
            Vec3 a = p->positions[v[0]];
            p->tri_normals[t] = v3_normalize(v3_cross(v3_sub(p->positions[v[1]], a), v3_sub(p->positions[v[2]], a)));
        }
        AccelGeometry g = {p->positions, p->tri_indices, p->num_triangles, NULL, 0, p->shapes, p->num_shapes};
        CstStatus st = accel_build(&p->accel, ACCEL_BVH, &g, err);
        if (st != CST_OK) return st;
    }
    for (int i = 0; i < set->num_insts; i++) {
        Instance *in = &set->insts[i];
        BBox ob = set->protos[in->proto].accel.bounds, wb = bbox_empty();
        if (in->motion >= 0) {
            wb = motion_bounds(&set->motions[in->motion], ob);
        } else {
            for (int k = 0; k < 8; k++) {
                Vec3 corner = v3(k & 1 ? ob.max.x : ob.min.x, k & 2 ? ob.max.y : ob.min.y, k & 4 ? ob.max.z : ob.min.z);
                wb = bbox_add(wb, transform_point(&in->world_from_obj, corner));
            }
        }
        /* Widened for the rounding of the transform (the boxes of the transformed triangles
         * are computed in double and rounded once; a relative 1e-5 is far above that). */
        Vec3 pad = v3_add(v3_scale(v3_sub(wb.max, wb.min), 1e-5f), v3s(1e-5f * v3_max_abs(wb.max) + 1e-30f));
        pad = v3_add(pad, v3s(1e-5f * v3_max_abs(wb.min)));
        in->bounds.min = v3_sub(wb.min, pad);
        in->bounds.max = v3_add(wb.max, pad);
    }
    int n = set->num_insts;
    set->order = malloc((size_t)(n > 0 ? n : 1) * sizeof *set->order);
    set->nodes = malloc((size_t)(n > 0 ? 2 * n : 1) * sizeof *set->nodes);
    if (!set->order || !set->nodes) return cst_fail(err, CST_ERR_OOM, "out of memory for %d instances", n);
    for (int i = 0; i < n; i++) set->order[i] = i;
    set->num_nodes = 1;
    if (n > 0) build_node(set, 0, 0, n);
    else set->num_nodes = 0;
    set->built = 1;
    return CST_OK;
}

void instances_free(InstanceSet *set)
{
    if (!set) return;
    for (int i = 0; i < set->num_protos; i++) proto_free(&set->protos[i]);
    free(set->protos);
    free(set->insts);
    free(set->nodes);
    free(set->order);
    free(set->motions);
    memset(set, 0, sizeof *set);
}

size_t instances_memory_bytes(const InstanceSet *set)
{
    size_t b = (size_t)set->num_insts * sizeof *set->insts + (size_t)set->num_nodes * sizeof *set->nodes +
               (size_t)set->num_insts * sizeof *set->order + (size_t)set->num_motions * sizeof *set->motions;
    for (int i = 0; i < set->num_protos; i++) {
        const InstProto *p = &set->protos[i];
        b += (size_t)p->num_positions * (sizeof *p->positions + (p->normals ? sizeof *p->normals : 0) +
                                         (p->uvs ? sizeof *p->uvs : 0)) +
             (size_t)p->num_triangles * (3 * sizeof *p->tri_indices + sizeof *p->tri_material + sizeof *p->tri_normals +
                                         (p->tri_alpha ? sizeof *p->tri_alpha : 0)) +
             (size_t)p->num_shapes * (sizeof *p->shapes + sizeof *p->shape_material + sizeof *p->shape_alpha) +
             accel_memory_bytes(&p->accel);
    }
    return b;
}

/* The world ray in object space with a unit direction; *scale = object t per world t
 * (0 when a moving instance has no placement at the ray's time: no hit). */
static Ray to_object(const InstanceSet *set, const Instance *in, const Ray *r, float *scale)
{
    const Transform *ofw = &in->obj_from_world;
    Transform moved_wfo, moved_ofw;
    if (in->motion >= 0) {
        if (!placement_at(set, in, r->time, &moved_wfo, &moved_ofw, NULL)) {
            *scale = 0.0f;
            return *r;
        }
        ofw = &moved_ofw;
    }
    Vec3 o = transform_point(ofw, r->o);
    Vec3 d = transform_vector(ofw, r->d);
    float len = v3_length(d);
    *scale = len;
    return ray_make(o, v3_scale(d, 1.0f / len), r->t_min * len, r->t_max * len);
}

Ray instances_object_ray(const InstanceSet *set, int inst, const Ray *ray, float *scale)
{
    return to_object(set, &set->insts[inst], ray, scale);
}

bool instances_intersect(const InstanceSet *set, const Ray *ray, InstHit *hit)
{
    if (set->num_nodes == 0) return false;
    int32_t stack[INST_STACK];
    int sp = 0;
    float best = ray->t_max;
    bool found = false;
    stack[sp++] = 0;
    while (sp > 0) {
        const InstNode *n = &set->nodes[stack[--sp]];
        float t_enter;
        if (!bbox_intersect(n->box, ray->o, ray->d, ray->t_min, best, &t_enter)) continue;
        if (n->count == 0) {
            const InstNode *a = &set->nodes[n->first], *b = &set->nodes[n->first + 1];
            float ta = 0.0f, tb = 0.0f;
            bool ha = bbox_intersect(a->box, ray->o, ray->d, ray->t_min, best, &ta);
            bool hb = bbox_intersect(b->box, ray->o, ray->d, ray->t_min, best, &tb);
            /* near child on top of the stack */
            if (ha && hb) {
                stack[sp++] = ta <= tb ? n->first + 1 : n->first;
                stack[sp++] = ta <= tb ? n->first : n->first + 1;
            } else if (ha) {
                stack[sp++] = n->first;
            } else if (hb) {
                stack[sp++] = n->first + 1;
            }
            continue;
        }
        for (int i = 0; i < n->count; i++) {
            int32_t id = set->order[n->first + i];
            const Instance *in = &set->insts[id];
            float scale;
            Ray local = *ray;
            local.t_max = best;
            Ray ro = to_object(set, in, &local, &scale);
            if (!(scale > 0.0f) || !isfinite(scale)) continue;
            Hit h;
            while (accel_intersect(&set->protos[in->proto].accel, &ro, &h)) {
                float t = h.t / scale;
                if (!(t > ray->t_min)) {
                    /* Beyond t_min in object space but not, after rounding, in world t (a
                     * query continued past a cut-away hit: t_min is that hit's world t):
                     * look further along, or this instance's farther surfaces are lost. */
                    ro.t_min = h.t;
                    continue;
                }
                if (t < best) {
                    best = t;
                    hit->t = t;
                    hit->t_obj = h.t;
                    hit->u = h.u;
                    hit->v = h.v;
                    hit->prim = h.prim;
                    hit->inst = id;
                    found = true;
                }
                break;
            }
        }
    }
    return found;
}

bool instances_occluded(const InstanceSet *set, const Ray *ray)
{
    if (set->num_nodes == 0) return false;
    int32_t stack[INST_STACK];
    int sp = 0;
    stack[sp++] = 0;
    while (sp > 0) {
        const InstNode *n = &set->nodes[stack[--sp]];
        float t_enter;
        if (!bbox_intersect(n->box, ray->o, ray->d, ray->t_min, ray->t_max, &t_enter)) continue;
        if (n->count == 0) {
            stack[sp++] = n->first + 1;
            stack[sp++] = n->first;
            continue;
        }
        for (int i = 0; i < n->count; i++) {
            const Instance *in = &set->insts[set->order[n->first + i]];
            float scale;
            Ray ro = to_object(set, in, ray, &scale);
            if (!(scale > 0.0f) || !isfinite(scale)) continue;
            if (accel_occluded(&set->protos[in->proto].accel, &ro)) return true;
        }
    }
    return false;
}
