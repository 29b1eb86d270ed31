/* Scene construction (growable arrays) and commit (BVH + emitter distribution). */
#include "scene/scene.h"

#include <limits.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "materials/bssrdf.h"
#include "materials/measured.h"

/* Room for `need` elements of `size` bytes in the array at *arr (core/array.h's rule).
 * Counts are int: `need`, computed by the caller in 64 bits, above INT_MAX fails like an
 * OOM, so no count can overflow. */
static bool grow(void *arr, size_t *cap, long long need, size_t size)
{
    return need >= 0 && need <= INT_MAX && array_grow(arr, cap, (size_t)need, size);
}
#define GROW(arr, cap, need) grow(&(arr), &(cap), (need), sizeof *(arr))

Scene *scene_create(void)
{
    Scene *s = calloc(1, sizeof *s);
    if (!s) return NULL;
    /* A usable default view: the scene loaders always set their own. */
    s->camera.position = v3(0.0f, 0.0f, 5.0f);
    s->camera.look_at = v3(0.0f, 0.0f, 0.0f);
    s->camera.up = v3(0.0f, 1.0f, 0.0f);
    s->camera.vfov_deg = 40.0f;
    s->camera.focus_distance = 5.0f;
    /* Nothing asked for until a loader reads it: resolve then takes the defaults. The
     * fields where 0 also reads as unset stay 0, the form the loaders test ("film width
     * given" is `rs->width != 0` in scene_json.c's crop check), and so do the AOVs, which
     * scene_json.c ORs bits into: a scene's 0 ("none") resolves as the unset default does. */
    cst_render_settings_init(&s->settings);
    s->settings.width = s->settings.height = s->settings.spp = 0;
    s->settings.rr_depth = s->settings.photons = 0;
    s->settings.photon_radius = 0.0;
    s->settings.aovs = 0;
    s->camera_medium = -1;
    s->shutter[1] = 1.0f; /* [0, 1]: the whole motion of every moving thing */
    return s;
}

void scene_destroy(Scene *s)
{
    if (!s) return;
    free(s->positions);
    free(s->normals);
    free(s->uvs);
    free(s->tri_has_uv);
    free(s->tri_indices);
    free(s->tri_info);
    free(s->tri_normals);
    free(s->spheres);
    free(s->sphere_info);
    for (int i = 0; i < s->num_shapes; i++) shape_release(&s->shapes[i]);
    free(s->shapes);
    free(s->shape_info);
    free(s->materials);
    free(s->spectra);
    free(s->emitter_spectrum);
    free(s->delta_spectrum);
    for (int i = 0; i < s->num_measured; i++) {
        measured_bsdf_free(s->measured[i]);
        free(s->measured[i]);
    }
    free(s->measured);
    for (int i = 0; i < s->num_bssrdf_tables; i++) free(s->bssrdf_tables[i]);
    free(s->bssrdf_tables);
    for (int i = 0; i < s->num_textures; i++) texture_free(&s->textures[i]);
    free(s->textures);
    free(s->emitters);
    free(s->alphas);
    for (int i = 0; i < s->num_media; i++) medium_release(&s->media[i]);
    free(s->media);
    free(s->medium_ifaces);
    for (int i = 0; i < s->num_delta_lights; i++)
        if (s->delta_lights[i].type == DELTA_GONIO) free((void *)(uintptr_t)s->delta_lights[i].gonio.factor);
        else if (s->delta_lights[i].type == DELTA_PROJECTION) free((void *)(uintptr_t)s->delta_lights[i].proj.rgb);
    free(s->material_spectra);
    free(s->emitter_spectra);
    free(s->delta_lights);
    if (s->env) envmap_free(s->env);
    free(s->env);
    free(s->output_path);
    accel_free(&s->accel);
    instances_free(s->instances);
    free(s->instances);
    emitter_sampler_free(&s->emitter_sampler);
    free(s);
}

void cst_scene_destroy(CstScene *scene) { scene_destroy(scene); }

const char *cst_scene_output_path(const CstScene *scene) { return scene->output_path; }

CstStatus scene_add_texture(Scene *s, const Texture *t, int *out_id, CstError *err)
{
    Texture copy = *t;
    if (t->type == TEXTURE_CHECKERBOARD &&
        (t->checker.even < 0 || t->checker.even >= s->num_textures || t->checker.odd < 0 ||
         t->checker.odd >= s->num_textures)) {
        texture_free(&copy);
        return cst_fail(err, CST_ERR_INVALID_ARG, "checkerboard texture refers to textures %d and %d; "
                        "expected indices of textures already added (0 to %d)",
                        t->checker.even, t->checker.odd, s->num_textures - 1);
    }
    if (!GROW(s->textures, s->cap_textures, s->num_textures + 1LL)) {
        texture_free(&copy);
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a texture");
    }
    s->textures[s->num_textures] = copy;
    *out_id = s->num_textures++;
    return CST_OK;
}

CstStatus scene_add_spectrum(Scene *s, const SampledSpectrum *sp, int *out_id, CstError *err)
{
    if (!GROW(s->spectra, s->cap_spectra, s->num_spectra + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a spectrum");
    s->spectra[s->num_spectra] = *sp;
    double y = sampled_spectrum_y(sp);
    s->spectra[s->num_spectra].inv_y = y > 0.0 ? (float)(1.0 / y) : 0.0f;
    *out_id = s->num_spectra++;
    return CST_OK;
}

CstStatus scene_set_emitter_spectrum(Scene *s, int first, int spectrum, CstError *err)
{
    if (spectrum < 0 || spectrum > s->num_spectra || first < 0 || first > s->num_emitters)
        return cst_fail(err, CST_ERR_INVALID_ARG, "emitter spectrum %d (emitters from %d) out of range", spectrum, first);
    if (!spectrum && !s->emitter_spectrum) return CST_OK; /* none so far, none here */
    if (!GROW(s->emitter_spectrum, s->cap_emitter_spectrum, s->num_emitters + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding an emitter's spectrum");
    for (int i = s->num_emitter_spectrum; i < first; i++) s->emitter_spectrum[i] = 0;
    for (int i = first; i < s->num_emitters; i++) s->emitter_spectrum[i] = spectrum;
    s->num_emitter_spectrum = s->num_emitters;
    return CST_OK;
}

CstStatus scene_set_delta_spectrum(Scene *s, int spectrum, CstError *err)
{
    if (spectrum < 0 || spectrum > s->num_spectra || s->num_delta_lights < 1)
        return cst_fail(err, CST_ERR_INVALID_ARG, "delta light spectrum %d out of range", spectrum);
    if (!spectrum && !s->delta_spectrum) return CST_OK; /* none so far, none here */
    if (!GROW(s->delta_spectrum, s->cap_delta_spectrum, (long long)s->num_delta_lights))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a light's spectrum");
    for (int i = s->num_delta_spectrum; i < s->num_delta_lights - 1; i++) s->delta_spectrum[i] = 0;
    s->delta_spectrum[s->num_delta_lights - 1] = spectrum;
    s->num_delta_spectrum = s->num_delta_lights;
    return CST_OK;
}

/* A measured material's tables from path, read once per file (pbrt-v4 caches them by
 * name too) and kept by the scene. */
static CstStatus scene_measured_load(Scene *s, const char *path, const MeasuredBsdf **out, CstError *err)
{
    if (!path) return cst_fail(err, CST_ERR_INVALID_ARG, "measured material without a file; expected a .bsdf file");
    for (int i = 0; i < s->num_measured; i++)
        if (strcmp(s->measured[i]->path, path) == 0) {
            *out = s->measured[i];
            return CST_OK;
        }
    if (!GROW(s->measured, s->cap_measured, s->num_measured + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a measured material");
    MeasuredBsdf *b = malloc(sizeof *b);
    if (!b) return cst_fail(err, CST_ERR_OOM, "out of memory adding a measured material");
    CstStatus st = measured_bsdf_read_file(b, path, err);
    if (st != CST_OK) {
        free(b);
        return st;
    }
    s->measured[s->num_measured++] = b;
    *out = b;
    return CST_OK;
}

/* A subsurface material's profile table for (g, eta), made once per pair (about 40 ms). */
static CstStatus scene_bssrdf_table(Scene *s, float g, float eta, const BssrdfTable **out, CstError *err)
{
    for (int i = 0; i < s->num_bssrdf_tables; i++)
        if (s->bssrdf_tables[i]->g == g && s->bssrdf_tables[i]->eta == eta) {
            *out = s->bssrdf_tables[i];
            return CST_OK;
        }
    if (!GROW(s->bssrdf_tables, s->cap_bssrdf_tables, s->num_bssrdf_tables + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a subsurface material");
    BssrdfTable *t = malloc(sizeof *t);
    if (!t) return cst_fail(err, CST_ERR_OOM, "out of memory adding a subsurface material");
    bssrdf_table_build(t, g, eta);
    s->bssrdf_tables[s->num_bssrdf_tables++] = t;
    *out = t;
    return CST_OK;
}

CstStatus scene_add_material(Scene *s, const Material *m, int *out_id, CstError *err)
{
    if (m->albedo_texture < 0 || m->albedo_texture > s->num_textures || m->roughness_texture < 0 ||
        m->roughness_texture > s->num_textures || m->roughness_v_texture < 0 ||
        m->roughness_v_texture > s->num_textures || m->eta_texture < 0 || m->eta_texture > s->num_textures ||
        m->k_texture < 0 || m->k_texture > s->num_textures || m->reflectance_texture < 0 ||
        m->reflectance_texture > s->num_textures)
        return cst_fail(err, CST_ERR_INVALID_ARG, "material texture index out of range");
    /* The rough plastic's coat albedo table (material_prepare) is made for one roughness. */
    if (m->eta_spectrum < 0 || m->eta_spectrum > s->num_spectra || m->k_spectrum < 0 ||
        m->k_spectrum > s->num_spectra || m->ior_spectrum < 0 || m->ior_spectrum > s->num_spectra)
        return cst_fail(err, CST_ERR_INVALID_ARG, "material spectrum index out of range");
    if (m->type == MATERIAL_PLASTIC && m->roughness_texture)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "a plastic's roughness cannot be a texture "
                        "(its coat albedo table is computed for one roughness); expected a number");
    /* A mix refers to materials added before it, so a chain of mixes always ends. */
    if (m->type == MATERIAL_MIX &&
        (m->mix[0] < 0 || m->mix[0] >= s->num_materials || m->mix[1] < 0 || m->mix[1] >= s->num_materials ||
         m->amount_texture < 0 || m->amount_texture > s->num_textures))
        return cst_fail(err, CST_ERR_INVALID_ARG, "mix material: materials %d and %d (or its amount texture) "
                        "out of range; expected materials added before it", m->mix[0], m->mix[1]);
    const MeasuredBsdf *table = m->measured;
    if (m->type == MATERIAL_MEASURED && !table) {
        CstStatus st = scene_measured_load(s, m->measured_file, &table, err);
        if (st != CST_OK) return st;
    }
    const BssrdfTable *bt = m->bssrdf;
    if (m->subsurface && (m->type != MATERIAL_DIELECTRIC || m->sss_reflectance_texture < 0 ||
                          m->sss_reflectance_texture > s->num_textures))
        return cst_fail(err, CST_ERR_INVALID_ARG, "subsurface material: not a dielectric surface, or its "
                        "reflectance texture out of range");
    if (m->subsurface && !bt) {
        CstStatus st = scene_bssrdf_table(s, m->g, m->ior, &bt, err);
        if (st != CST_OK) return st;
    }
    if (!GROW(s->materials, s->cap_materials, s->num_materials + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a material");
    s->materials[s->num_materials] = *m;
    s->materials[s->num_materials].bssrdf = m->subsurface ? bt : NULL;
    if (m->subsurface) s->num_subsurface++;
    s->materials[s->num_materials].measured = table;
    s->materials[s->num_materials].measured_file = NULL; /* the caller's string */
    /* Derived data (the rough plastic's coat table) is computed once here, not per hit. */
    material_prepare(&s->materials[s->num_materials]);
    if (m->type == MATERIAL_HAIR) s->needs_uv = true;
    *out_id = s->num_materials++;
    return CST_OK;
}

CstStatus scene_set_environment(Scene *s, const EnvMap *env, CstError *err)
{
    if (s->env) {
        envmap_free(s->env);
    } else if (!(s->env = malloc(sizeof *s->env))) {
        EnvMap tmp = *env;
        envmap_free(&tmp);
        return cst_fail(err, CST_ERR_OOM, "out of memory for the environment");
    }
    *s->env = *env;
    return CST_OK;
}

CstStatus scene_add_delta_light(Scene *s, const DeltaLight *l, CstError *err)
{
    if (!GROW(s->delta_lights, s->cap_delta_lights, s->num_delta_lights + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a light");
    s->delta_lights[s->num_delta_lights++] = *l;
    return CST_OK;
}

static CstStatus add_emitter(Scene *s, uint32_t prim, const Emission *em, float area,
                             int32_t *out, CstError *err)
{
    *out = -1;
    if (!em || color_is_black(em->radiance)) return CST_OK;
    if (!GROW(s->emitters, s->cap_emitters, s->num_emitters + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding an emitter");
    Emitter *e = &s->emitters[s->num_emitters];
    if (em->texture < 0 || em->texture > s->num_textures)
        return cst_fail(err, CST_ERR_INVALID_ARG, "emission texture index out of range");
    e->prim = prim;
    e->radiance = em->radiance;
    e->texture = em->texture;
    e->average = em->texture ? color_mul(em->radiance, s->textures[em->texture - 1].average) : em->radiance;
    e->two_sided = em->two_sided;
    e->area = area;
    e->is_sphere = 0;
    e->is_shape = 0;
    *out = s->num_emitters++;
    return CST_OK;
}

/* Makes room for an attribute array of elem bytes per position, in step with positions:
 * created on first use with zero fills for the positions before `base` (which count as
 * partial), then filled from src for the new vertices, or zeroed when src is NULL. */
static int add_attribute(void **arr, size_t *cap, size_t elem, int base, int n, const void *src,
                         int src_partial, int *partial)
{
    if (!src && !*arr) return 1;
    int fresh = *arr == NULL;
    if (!grow(arr, cap, (long long)base + n, elem)) return 0;
    char *a = *arr;
    if (fresh && base > 0) {
        memset(a, 0, (size_t)base * elem);
        *partial = 1;
    }
    if (src)
        memcpy(a + (size_t)base * elem, src, (size_t)n * elem);
    else
        memset(a + (size_t)base * elem, 0, (size_t)n * elem);
    if (!src || src_partial) *partial = 1;
    return 1;
}

CstStatus scene_add_mesh_ex(Scene *s, const SceneMesh *m, int *num_dropped, CstError *err)
{
    if (num_dropped) *num_dropped = 0;
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    int num_vertices = m->num_vertices, num_triangles = m->num_triangles;
    const int *indices = m->indices;
    const Vec3 *positions = m->positions;
    if (!m->tri_material && (m->material < 0 || m->material >= s->num_materials))
        return cst_fail(err, CST_ERR_INVALID_ARG, "material index %d out of range", m->material);
    if (m->tri_material)
        for (int t = 0; t < num_triangles; t++)
            if (m->tri_material[t] < 0 || m->tri_material[t] >= s->num_materials)
                return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d: material index %d out of range",
                                t, m->tri_material[t]);
    for (int i = 0; i < 3 * num_triangles; i++)
        if (indices[i] < 0 || indices[i] >= num_vertices)
            return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d: vertex index %d out of range [0, %d)",
                            i / 3, indices[i], num_vertices);
    for (int i = 0; i < num_vertices; i++)
        if (!v3_is_finite(positions[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "vertex %d is not finite", i);
    for (int i = 0; m->normals && i < num_vertices; i++)
        if (!v3_is_finite(m->normals[i]))
            return cst_fail(err, CST_ERR_INVALID_ARG, "normal of vertex %d is not finite", i);
    for (int i = 0; m->uvs && i < num_vertices; i++)
        if (!isfinite(m->uvs[i].x) || !isfinite(m->uvs[i].y))
            return cst_fail(err, CST_ERR_INVALID_ARG, "uv of vertex %d is not finite", i);
    int base = s->num_positions;
    /* 3 * triangles within INT_MAX: the per-triangle sizes below cannot overflow. */
    if (!GROW(s->positions, s->cap_positions, (long long)base + num_vertices) ||
        !GROW(s->tri_indices, s->cap_triangles, 3LL * ((long long)s->num_triangles + num_triangles)))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding %d triangles", num_triangles);
    if (!add_attribute((void **)&s->normals, &s->cap_normals, sizeof *s->normals, base,
                       num_vertices, m->normals, m->normals_partial, &s->normals_partial) ||
        !add_attribute((void **)&s->uvs, &s->cap_uvs, sizeof *s->uvs, base, num_vertices, m->uvs,
                       m->uvs_partial, &s->uvs_partial))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding %d vertices", num_vertices);
    /* tri_info shares the triangle capacity logic but has one entry per triangle. */
    PrimInfo *info = realloc(s->tri_info, (size_t)(s->num_triangles + num_triangles) * sizeof *info);
    if (!info) return cst_fail(err, CST_ERR_OOM, "out of memory adding %d triangles", num_triangles);
    s->tri_info = info;
    /* Which triangles take their uvs from the array: made on the first mesh with uvs,
     * zero (the default mapping) for the triangles before it. */
    if (m->uvs || s->tri_has_uv) {
        unsigned char *hu = realloc(s->tri_has_uv, (size_t)(s->num_triangles + num_triangles));
        if (!hu) return cst_fail(err, CST_ERR_OOM, "out of memory adding %d triangles", num_triangles);
        if (!s->tri_has_uv) memset(hu, 0, (size_t)s->num_triangles);
        s->tri_has_uv = hu;
    }
    memcpy(s->positions + base, positions, (size_t)num_vertices * sizeof *positions);
    s->num_positions += num_vertices;
    for (int t = 0; t < num_triangles; t++) {
        int id = s->num_triangles;
        Vec3 a = positions[indices[3 * t]], b = positions[indices[3 * t + 1]], c = positions[indices[3 * t + 2]];
        float area = triangle_area(a, b, c);
        if (!(area > 0.0f)) {
            if (m->skip_degenerate) {
                if (num_dropped) (*num_dropped)++;
                continue;
            }
            return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d is degenerate (zero area)", t);
        }
        for (int k = 0; k < 3; k++) s->tri_indices[3 * id + k] = base + indices[3 * t + k];
        s->tri_info[id].material = m->tri_material ? m->tri_material[t] : m->material;
        s->tri_info[id].alpha = m->tri_alpha ? m->tri_alpha[t] : m->alpha;
        s->tri_info[id].medium = s->cur_medium_iface;
        if (s->tri_has_uv) s->tri_has_uv[id] = m->uvs != NULL;
        CstStatus st = add_emitter(s, (uint32_t)id, m->emission, area, &s->tri_info[id].emitter, err);
        if (st != CST_OK) return st;
        s->num_triangles = id + 1; /* keep counts consistent if a later triangle fails */
    }
    return CST_OK;
}

CstStatus scene_add_mesh(Scene *s, const Vec3 *positions, int num_vertices, const int *indices,
                         int num_triangles, int material, const Emission *emission, CstError *err)
{
    SceneMesh m = {0};
    m.positions = positions;
    m.num_vertices = num_vertices;
    m.indices = indices;
    m.num_triangles = num_triangles;
    m.material = material;
    m.emission = emission;
    return scene_add_mesh_ex(s, &m, NULL, err);
}

CstStatus scene_add_quad(Scene *s, const Vec3 v[4], int material, const Emission *emission, CstError *err)
{
    static const int idx[6] = {0, 1, 2, 0, 2, 3};
    static const Vec2 uv[4] = {{0.0f, 0.0f}, {1.0f, 0.0f}, {1.0f, 1.0f}, {0.0f, 1.0f}};
    SceneMesh m = {0};
    m.positions = v;
    m.num_vertices = 4;
    m.uvs = uv;
    m.indices = idx;
    m.num_triangles = 2;
    m.material = material;
    m.emission = emission;
    return scene_add_mesh_ex(s, &m, NULL, err);
}

CstStatus scene_add_shape(Scene *s, const ShapeParams *p, const Transform *object_to_world, int material,
                          const Emission *emission, int alpha, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (material < 0 || material >= s->num_materials)
        return cst_fail(err, CST_ERR_INVALID_ARG, "material index %d out of range", material);
    if (s->shape_object) { /* into an instanced object (cst_scene_add_object_shape): it does not emit */
        AnalyticShape sh;
        if (!shape_init(&sh, p, object_to_world))
            return cst_fail(err, CST_ERR_INVALID_ARG, "shape parameters out of range or a singular transform");
        return instances_proto_add_shape(s->instances, s->shape_object - 1, &sh, material, alpha, err);
    }
    if (!GROW(s->shapes, s->cap_shapes, s->num_shapes + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a shape");
    PrimInfo *info = realloc(s->shape_info, (size_t)(s->num_shapes + 1) * sizeof *info);
    if (!info) return cst_fail(err, CST_ERR_OOM, "out of memory adding a shape");
    s->shape_info = info;
    if (!shape_init(&s->shapes[s->num_shapes], p, object_to_world))
        return cst_fail(err, CST_ERR_INVALID_ARG, "shape parameters out of range or a singular transform");
    const AnalyticShape *sh = &s->shapes[s->num_shapes];
    const bool emits = emission && !color_is_black(emission->radiance);
    if (emits && !shape_uniform_area(sh))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "an emitting analytic shape needs a similarity transform "
                        "(rotation, mirror, uniform scale) so that it is sampled uniformly by area");
    s->shape_info[s->num_shapes] = (PrimInfo){material, -1, alpha, s->cur_medium_iface};
    /* Shape prim ids follow the triangles and spheres, known at commit: until then the
     * emitter holds the shape index, flagged by is_shape (as spheres do). */
    int i = s->num_shapes++;
    CstStatus st = add_emitter(s, (uint32_t)i, emission, shape_area(sh), &s->shape_info[i].emitter, err);
    if (st == CST_OK && s->shape_info[i].emitter >= 0) s->emitters[s->shape_info[i].emitter].is_shape = 1;
    return st;
}

CstStatus scene_add_patch(Scene *s, const AnalyticShape *patch, int material, int alpha, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (material < 0 || material >= s->num_materials)
        return cst_fail(err, CST_ERR_INVALID_ARG, "material index %d out of range", material);
    if (s->shape_object) return instances_proto_add_shape(s->instances, s->shape_object - 1, patch, material, alpha, err);
    if (!GROW(s->shapes, s->cap_shapes, s->num_shapes + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a bilinear patch");
    PrimInfo *info = realloc(s->shape_info, (size_t)(s->num_shapes + 1) * sizeof *info);
    if (!info) return cst_fail(err, CST_ERR_OOM, "out of memory adding a bilinear patch");
    s->shape_info = info;
    s->shapes[s->num_shapes] = *patch;
    s->shape_info[s->num_shapes] = (PrimInfo){material, -1, alpha, s->cur_medium_iface};
    s->num_shapes++;
    return CST_OK;
}

CstStatus scene_add_sphere(Scene *s, Vec3 center, float radius, int material,
                           const Emission *emission, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (!(radius > 0.0f) || !isfinite(radius) || !v3_is_finite(center))
        return cst_fail(err, CST_ERR_INVALID_ARG, "sphere radius must be a positive finite number");
    if (material < 0 || material >= s->num_materials)
        return cst_fail(err, CST_ERR_INVALID_ARG, "material index %d out of range", material);
    if (!GROW(s->spheres, s->cap_spheres, s->num_spheres + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a sphere");
    PrimInfo *info = realloc(s->sphere_info, (size_t)(s->num_spheres + 1) * sizeof *info);
    if (!info) return cst_fail(err, CST_ERR_OOM, "out of memory adding a sphere");
    s->sphere_info = info;
    int i = s->num_spheres;
    s->spheres[i].center = center;
    s->spheres[i].radius = radius;
    s->sphere_info[i].material = material;
    s->sphere_info[i].alpha = 0;
    s->sphere_info[i].medium = s->cur_medium_iface;
    s->num_spheres = i + 1;
    /* Sphere prim ids follow all triangles, so they are only known at commit: until
     * then the emitter holds the sphere index, flagged by is_sphere. */
    CstStatus st = add_emitter(s, (uint32_t)i, emission, 4.0f * CST_PI * radius * radius,
                               &s->sphere_info[i].emitter, err);
    if (st == CST_OK && s->sphere_info[i].emitter >= 0) s->emitters[s->sphere_info[i].emitter].is_sphere = 1;
    return st;
}

CstStatus scene_add_alpha(Scene *s, float value, int texture, int *out_id, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (!(value >= 0.0f && value <= 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "alpha %g; expected a value in [0, 1]", (double)value);
    if (texture < 0 || texture > s->num_textures)
        return cst_fail(err, CST_ERR_INVALID_ARG, "alpha texture %d out of range", texture);
    if (!GROW(s->alphas, s->cap_alphas, s->num_alphas + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding an alpha cut-out");
    s->alphas[s->num_alphas] = (AlphaMask){value, texture};
    *out_id = ++s->num_alphas;
    return CST_OK;
}

/* ------------------------------------------------------------------ media */

static bool coeff_ok(Color c)
{
    for (int i = 0; i < COLOR_LANES; i++)
        if (!(c.c[i] >= 0.0f) || !isfinite(c.c[i])) return false;
    return true;
}

CstStatus scene_add_medium(Scene *s, const Medium *m, int *out_id, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (m->type != MEDIUM_HOMOGENEOUS && m->type != MEDIUM_GRID && m->type != MEDIUM_CLOUD)
        return cst_fail(err, CST_ERR_UNSUPPORTED, "medium type %d; expected homogeneous, grid or cloud", (int)m->type);
    if (medium_is_hetero(m)) {
        const char *why = hetero_medium_invalid(&m->u.het);
        if (why) return cst_fail(err, CST_ERR_INVALID_ARG, "medium: %s", why);
        if ((m->type == MEDIUM_CLOUD) != m->u.het.cloud)
            return cst_fail(err, CST_ERR_INVALID_ARG, "medium: type and HeteroMedium.cloud disagree");
    } else if (!coeff_ok(m->u.homog.sigma_a) || !coeff_ok(m->u.homog.sigma_s) || !coeff_ok(m->u.homog.le))
        return cst_fail(err, CST_ERR_INVALID_ARG, "medium: sigma_a, sigma_s and Le must be finite and >= 0");
    if (!(fabsf(m->g) < 1.0f))
        return cst_fail(err, CST_ERR_INVALID_ARG, "medium: g = %g; expected a value in (-1, 1)", (double)m->g);
    if (!GROW(s->media, s->cap_media, s->num_media + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a medium");
    s->media[s->num_media] = *m;
    medium_prepare_spectra(&s->media[s->num_media]);
    /* The scene keeps its own copies of a grid's arrays, and builds its majorants. */
    if (medium_is_hetero(m) && !hetero_medium_clone(&s->media[s->num_media].u.het, &m->u.het))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a grid medium");
    *out_id = s->num_media++;
    return CST_OK;
}

CstStatus scene_set_medium_interface(Scene *s, int inside, int outside, int boundary, CstError *err)
{
    if (inside < -1 || inside >= s->num_media || outside < -1 || outside >= s->num_media)
        return cst_fail(err, CST_ERR_INVALID_ARG, "medium interface (%d, %d): expected media indices "
                        "from -1 (vacuum) to %d", inside, outside, s->num_media - 1);
    if (inside == outside && !boundary) {
        s->cur_medium_iface = 0;
        return CST_OK;
    }
    /* Shapes added in a row usually share one interface: reuse the last. */
    if (s->num_medium_ifaces) {
        const MediumInterface *l = &s->medium_ifaces[s->num_medium_ifaces - 1];
        if (l->inside == inside && l->outside == outside && l->boundary == (boundary != 0)) {
            s->cur_medium_iface = s->num_medium_ifaces;
            return CST_OK;
        }
    }
    if (!GROW(s->medium_ifaces, s->cap_medium_ifaces, s->num_medium_ifaces + 1LL))
        return cst_fail(err, CST_ERR_OOM, "out of memory adding a medium interface");
    s->medium_ifaces[s->num_medium_ifaces] = (MediumInterface){inside, outside, boundary != 0};
    s->cur_medium_iface = ++s->num_medium_ifaces;
    return CST_OK;
}

CstStatus scene_set_camera_medium(Scene *s, int medium, CstError *err)
{
    if (medium < -1 || medium >= s->num_media)
        return cst_fail(err, CST_ERR_INVALID_ARG, "camera medium %d: expected a medium index from -1 (vacuum) "
                        "to %d", medium, s->num_media - 1);
    s->camera_medium = medium;
    return CST_OK;
}

Color scene_transmittance_at(const Scene *s, Vec3 p, Vec3 n_p, Vec3 q, Vec3 n_q, int medium, float time,
                             const Wavelengths *wl, uint64_t *rays)
{
    Vec3 d = v3_sub(q, p);
    Vec3 o = scene_offset(s, p, n_p, d); /* a zero normal leaves the point where it is */
    const Vec3 end = scene_offset(s, q, n_q, v3_neg(d));
    Color tr = color_s(1.0f);
    /* Each step crosses one boundary; a bound on them keeps a degenerate stack of
     * coincident boundaries from looping (then the light counts as blocked). */
    for (int step = 0; step < 256; step++) {
        Vec3 od = v3_sub(end, o);
        float len = v3_length(od);
        if (!(len > 0.0f)) return tr;
        Vec3 dir = v3_scale(od, 1.0f / len);
        Ray r = ray_make_at(o, dir, 0.0f, len * (1.0f - 1e-5f), time);
        SurfaceHit sh;
        ++*rays;
        bool hit = scene_intersect(s, &r, &sh);
        if (medium >= 0) {
            const Medium *m = &s->media[medium];
            MediumCoeffs mc = medium_coeffs(m, wl);
            if (medium_is_hetero(m)) {
                /* Ratio tracking, its random stream a hash of the segment (the shadow ray's
                 * end points are themselves random; no sampler dimension is spent). */
                const float seg[6] = {o.x, o.y, o.z, end.x, end.y, end.z};
                uint64_t seed = 0x8f1bbcdcca62c1d6ULL + (uint64_t)step;
                for (int i = 0; i < 6; i++) {
                    union { float f; uint32_t u; } b = {seg[i]};
                    seed = mix64(seed ^ b.u);
                }
                tr = color_mul(tr, hetero_transmittance(&m->u.het, &mc, o, dir, hit ? sh.t : len, seed));
            } else {
                tr = color_mul(tr, medium_transmittance(&mc, hit ? sh.t : len));
            }
        }
        if (!hit) return tr;
        const MediumInterface *mi = scene_hit_medium_iface(s, &sh);
        if (!mi || !mi->boundary || color_is_black(tr)) return color_s(0.0f);
        medium = v3_dot(dir, sh.ng) < 0.0f ? mi->inside : mi->outside;
        o = scene_offset(s, sh.p, sh.ng, dir);
    }
    return color_s(0.0f);
}

/* ------------------------------------------------------------------ alpha cut-outs */

/* The alpha at a surface point with texture coordinates uv: the texture's scalar value
 * without a footprint (pbrt-v4 evaluates alpha in GeometricPrimitive::Intersect, before
 * the hit has its screen-space differentials: the finest MIP level). */
static float alpha_value(const Scene *s, const AlphaMask *am, Vec2 uv, Vec3 p, Vec3 n)
{
    if (!am->texture) return am->value;
    TexCtx c = {.uv = uv, .p = p, .n = n};
    return texture_eval_scalar_ctx(s->textures, am->texture - 1, &c);
}

/* pbrt-v4's test (GeometricPrimitive::Intersect): a >= 1 keeps the surface, a <= 0 (or
 * NaN) cuts it, else it is cut when a uniform number u from hash h exceeds a, so it is
 * present with probability a. */
static bool alpha_cut(float a, uint64_t h)
{
    if (a >= 1.0f) return false;
    if (!(a > 0.0f)) return true;
    return (float)(h >> 40) * 0x1p-24f > a;
}

static uint64_t hash_vec3(Vec3 v, uint64_t seed)
{
    union { float f[3]; uint32_t u[3]; } b = {{v.x, v.y, v.z}};
    uint64_t h = mix64(seed ^ ((uint64_t)b.u[0] << 32 | b.u[1]));
    return mix64(h + ((uint64_t)b.u[2] << 17) + 0x9e3779b97f4a7c15ULL);
}

/* Whether the hit sh of ray is on cut-away surface. The stochastic test's number is a
 * hash of the ray's origin and direction (as pbrt-v4's HashFloat(r.o, r.d)), of the
 * primitive and of the hit's distance: the same ray always makes the same choice, and,
 * since the ray is continued with the same origin, every surface further along it chooses
 * independently, the far side of a sphere too (pbrt-v4 spawns a new ray at each cut hit,
 * whose new origin gives it a new number). A hit inside an instance takes its cut-out
 * from the prototype's triangle and hashes that triangle's index in place of the
 * primitive's, with the world ray and world t: the same rule as for shapes placed
 * directly (the choices differ only where the transform's rounding moves t by ulps). */
static bool hit_cut(const Scene *s, const Ray *ray, const SurfaceHit *sh)
{
    int a;
    uint32_t prim = sh->prim;
    if (prim == UINT32_MAX) {
        const InstProto *pr = &s->instances->protos[s->instances->insts[sh->inst].proto];
        if ((int)sh->inst_prim >= pr->num_triangles) a = pr->shape_alpha[(int)sh->inst_prim - pr->num_triangles];
        else if (!pr->tri_alpha) return false;
        else a = pr->tri_alpha[sh->inst_prim];
        prim = sh->inst_prim;
    } else {
        a = scene_prim_info(s, prim)->alpha;
    }
    if (!a) return false;
    const AlphaMask *am = &s->alphas[a - 1];
    float v = alpha_value(s, am, sh->uv, sh->p, sh->ng);
    if (v >= 1.0f || !(v > 0.0f)) return alpha_cut(v, 0);
    union { float f; uint32_t u; } t = {sh->t};
    return alpha_cut(v, hash_vec3(ray->d, hash_vec3(ray->o, (uint64_t)t.u << 32 | prim)));
}

/* A closest-hit filter: a hit on cut-away surface moves t_min to it and the query runs
 * again (every back end's interval is open at t_min, so the same surface is not found
 * twice and each step makes progress). Costs one query per cut surface crossed. */
bool scene_intersect_alpha(const Scene *s, const Ray *ray, SurfaceHit *sh)
{
    Ray r = *ray;
    while (scene_intersect_first(s, &r, sh)) {
        if (!hit_cut(s, ray, sh)) return true;
        r.t_min = sh->t;
    }
    return false;
}

/* Any-hit with cut-outs: the plain occlusion query first (a free segment stays free),
 * then the filtered closest-hit walk decides. */
bool scene_occluded_alpha(const Scene *s, const Ray *ray)
{
    if (!accel_occluded(&s->accel, ray) && !(s->instances && instances_occluded(s->instances, ray))) return false;
    SurfaceHit sh;
    return scene_intersect_alpha(s, ray, &sh);
}

/* Whether point p, sampled on area emitter `emitter`, is on cut-away surface (pbrt-v4
 * DiffuseAreaLight::AlphaMasked: the test's number hashes the point). Triangles find p's
 * barycentrics from the two edge vectors (least squares in the triangle's plane). */
bool scene_emitter_cut(const Scene *s, int emitter, Vec3 p)
{
    const Emitter *e = &s->emitter_sampler.light[emitter].u.area;
    int a = scene_prim_info(s, e->prim)->alpha;
    if (!a) return false;
    const AlphaMask *am = &s->alphas[a - 1];
    Vec2 uv = v2(0.0f, 0.0f);
    Vec3 n;
    if ((int)e->prim < s->num_triangles) {
        const int32_t *t = &s->tri_indices[3 * e->prim];
        Vec3 p0 = s->positions[t[0]];
        Vec3 e1 = v3_sub(s->positions[t[1]], p0), e2 = v3_sub(s->positions[t[2]], p0), q = v3_sub(p, p0);
        float d11 = v3_dot(e1, e1), d12 = v3_dot(e1, e2), d22 = v3_dot(e2, e2);
        float q1 = v3_dot(q, e1), q2 = v3_dot(q, e2), det = d11 * d22 - d12 * d12;
        float u = det != 0.0f ? (d22 * q1 - d12 * q2) / det : 0.0f;
        float v = det != 0.0f ? (d11 * q2 - d12 * q1) / det : 0.0f;
        n = s->tri_normals[e->prim];
        if (am->texture) uv = triangle_uv(s->uvs, s->tri_has_uv, s->tri_indices, e->prim, u, v);
    } else if ((int)e->prim < s->num_triangles + s->num_spheres) {
        const Sphere *sp = &s->spheres[(int)e->prim - s->num_triangles];
        n = v3_normalize(v3_sub(p, sp->center));
        uv = sphere_uv(n);
    } else {
        /* shape_surface reprojects o + t d: with d = 0 and t = 0, the point p itself */
        const Ray r = {.o = p, .t_min = 0.0f, .d = v3s(0.0f), .t_max = 0.0f};
        ShapeSurface sf;
        shape_surface(&s->shapes[(int)e->prim - s->num_triangles - s->num_spheres], &r, 0.0f, &sf);
        n = sf.n;
        uv = sf.uv;
    }
    return alpha_cut(alpha_value(s, am, uv, p, n), hash_vec3(p, 0x5bd1e995u));
}

void scene_set_camera(Scene *s, const CameraDesc *camera)
{
    s->camera = *camera;
    s->camera_set = 1;
}

CstStatus scene_set_output_path(Scene *s, const char *path, CstError *err)
{
    char *p = strdup(path);
    if (!p) return cst_fail(err, CST_ERR_OOM, "out of memory");
    free(s->output_path);
    s->output_path = p;
    return CST_OK;
}

static CstStatus ensure_instances(Scene *s, CstError *err)
{
    if (s->committed) return cst_fail(err, CST_ERR_INVALID_ARG, "scene already committed");
    if (!s->instances && !(s->instances = calloc(1, sizeof *s->instances)))
        return cst_fail(err, CST_ERR_OOM, "out of memory for instances");
    return CST_OK;
}

CstStatus scene_add_instance_proto(Scene *s, const Vec3 *positions, const Vec3 *normals,
                                   int num_vertices, const int *indices, const int *tri_material,
                                   int num_triangles, int *out_id, CstError *err)
{
    CstStatus st = ensure_instances(s, err);
    if (st != CST_OK) return st;
    for (int t = 0; t < num_triangles; t++) {
        if (tri_material[t] < 0 || tri_material[t] >= s->num_materials)
            return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d: material index %d out of range", t, tri_material[t]);
        for (int k = 0; k < 3; k++)
            if (indices[3 * t + k] < 0 || indices[3 * t + k] >= num_vertices)
                return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d: vertex index out of range", t);
        Vec3 a = positions[indices[3 * t]], b = positions[indices[3 * t + 1]], c = positions[indices[3 * t + 2]];
        if (!(triangle_area(a, b, c) > 0.0f))
            return cst_fail(err, CST_ERR_INVALID_ARG, "triangle %d is degenerate (zero area)", t);
    }
    for (int i = 0; i < num_vertices; i++)
        if (!v3_is_finite(positions[i]) || (normals && !v3_is_finite(normals[i])))
            return cst_fail(err, CST_ERR_INVALID_ARG, "vertex %d is not finite", i);
    return instances_add_proto(s->instances, positions, normals, num_vertices, indices, tri_material,
                               num_triangles, out_id, err);
}

CstStatus scene_add_instance(Scene *s, int proto, const Transform *world_from_obj, CstError *err)
{
    CstStatus st = ensure_instances(s, err);
    if (st != CST_OK) return st;
    return instances_add(s->instances, proto, world_from_obj, err);
}

CstStatus scene_add_instance_moving(Scene *s, int proto, const Transform *start, const Transform *end, CstError *err)
{
    CstStatus st = ensure_instances(s, err);
    if (st != CST_OK) return st;
    return instances_add_moving(s->instances, proto, start, end, err);
}

CstStatus scene_commit(Scene *s, CstError *err)
{
    if (s->committed) return CST_OK;
    for (int i = 0; i < s->num_emitters; i++)
        if (s->emitters[i].is_sphere) {
            s->emitters[i].prim += (uint32_t)s->num_triangles;
            s->emitters[i].is_sphere = 0;
        } else if (s->emitters[i].is_shape) {
            s->emitters[i].prim += (uint32_t)(s->num_triangles + s->num_spheres);
            s->emitters[i].is_shape = 0;
        }
    s->tri_normals = malloc((size_t)(s->num_triangles > 0 ? s->num_triangles : 1) * sizeof *s->tri_normals);
    if (!s->tri_normals) return cst_fail(err, CST_ERR_OOM, "out of memory for %d normals", s->num_triangles);
    for (int i = 0; i < s->num_triangles; i++) {
        const int32_t *t = &s->tri_indices[3 * i];
        Vec3 a = s->positions[t[0]];
        s->tri_normals[i] = v3_normalize(v3_cross(v3_sub(s->positions[t[1]], a), v3_sub(s->positions[t[2]], a)));
    }
    for (int i = 0; i < s->num_emitters; i++)
        if ((int)s->emitters[i].prim < s->num_triangles) s->emitters[i].n = s->tri_normals[s->emitters[i].prim];
    AccelGeometry geom = scene_accel_geometry(s);
    CstStatus st = accel_build(&s->accel, s->accel_type, &geom, err);
    if (st != CST_OK) return st;
    BBox bounds = s->accel.bounds;
    if (s->instances) {
        if ((st = instances_build(s->instances, err)) != CST_OK) return st;
        /* directional lights are sampled over the bounds of everything they can light */
        if (s->instances->num_nodes > 0) bounds = bbox_union(bounds, s->instances->nodes[0].box);
    }
    /* An empty scene: a point at the origin, not the empty box (its centre would be NaN). */
    if (!(bounds.min.x <= bounds.max.x)) bounds.min = bounds.max = v3s(0.0f);
    if (s->env && s->has_env_portal && (st = envmap_set_portal(s->env, s->env_portal, err)) != CST_OK) return st;
    st = emitter_sampler_init(&s->emitter_sampler, s->emitters, s->num_emitters, s->delta_lights,
                              s->num_delta_lights, s->env, bounds.min, bounds.max, err);
    if (st != CST_OK) return st;
    s->emitter_sampler.solid_angle = s->light_solid_angle != 0;
    {
        EmitterGeometry g = scene_emitter_geometry(s);
        LightSelect sel = s->light_select > 0 ? (LightSelect)(s->light_select - 1)
                                              : emitter_sampler_auto_nee(&s->emitter_sampler);
        if ((st = emitter_sampler_set_nee(&s->emitter_sampler, &g, sel, err)) != CST_OK) return st;
    }
    /* The spectral mode's table lookups of constant colours, once (scene.h); optional:
     * without them each use converts. Emitters are in emitter_sampler order (area lights
     * first, an emitter's index is its light index). */
    s->material_spectra = malloc((size_t)(s->num_materials > 0 ? s->num_materials : 1) * sizeof *s->material_spectra);
    if (s->material_spectra)
        for (int i = 0; i < s->num_materials; i++) s->material_spectra[i] = material_spectra(&s->materials[i]);
    s->emitter_spectra = malloc((size_t)(s->emitter_sampler.count > 0 ? s->emitter_sampler.count : 1) * sizeof *s->emitter_spectra);
    if (s->emitter_spectra)
        for (int i = 0; i < s->emitter_sampler.count; i++)
            s->emitter_spectra[i] = spectrum_rgb_unbounded(s->emitter_sampler.light[i].u.area.radiance);
    /* From the geometry, not from `bounds` (the back end's): every back end must offset
     * rays alike for their images to agree bit for bit. */
    float extent = 0.0f;
    for (int i = 0; i < s->num_positions; i++) extent = maxf(extent, v3_max_abs(s->positions[i]));
    for (int i = 0; i < s->num_spheres; i++)
        extent = maxf(extent, v3_max_abs(s->spheres[i].center) + s->spheres[i].radius);
    for (int i = 0; i < s->num_shapes; i++)
        extent = maxf(extent, maxf(v3_max_abs(s->shapes[i].bounds.min), v3_max_abs(s->shapes[i].bounds.max)));
    if (s->instances && s->instances->num_nodes > 0)
        extent = maxf(extent, maxf(v3_max_abs(s->instances->nodes[0].box.min),
                                   v3_max_abs(s->instances->nodes[0].box.max)));
    s->offset_near = maxf(RAY_OFFSET_NEAR_MIN, isfinite(extent) ? 4e-7f * extent : 0.0f);
    /* Footprints for MIP-filtered textures, from the scene file's view (a render at another
     * resolution or sample count keeps these: pbrt-v4 takes them from its film). */
    for (int i = 0; i < s->num_textures; i++)
        if (texture_needs_footprint(&s->textures[i])) {
            const CstRenderSettings *rs = &s->settings;
            CameraDesc view = s->camera;
            if (s->camera_placed) { /* a moving camera: its view in the middle of its motion */
                Transform w = motion_at(&s->camera_motion, 0.5f);
                view.position = transform_point(&w, view.position);
                view.look_at = transform_point(&w, view.look_at);
                view.up = transform_vector(&w, view.up);
            }
            footprint_init(&s->footprint, &view, s->camera_mirror != 0,
                           rs->width > 0 ? rs->width : CST_DEFAULT_WIDTH, rs->height > 0 ? rs->height : CST_DEFAULT_HEIGHT,
                           rs->spp > 0 ? rs->spp : CST_DEFAULT_SPP);
            s->footprint.enabled = true;
            break;
        }
    s->committed = 1;
    return CST_OK;
}

CstStatus scene_set_accel(Scene *s, AccelType type, CstError *err)
{
    if (!s->committed) {
        s->accel_type = type;
        return CST_OK;
    }
    Accel fresh;
    AccelGeometry geom = scene_accel_geometry(s);
    CstStatus st = accel_build(&fresh, type, &geom, err);
    if (st != CST_OK) return st; /* the old structure stays usable */
    accel_free(&s->accel);
    s->accel = fresh;
    s->accel_type = type;
    return CST_OK;
}

CstStatus cst_scene_set_accel(CstScene *scene, const char *name, CstError *err)
{
    AccelType type;
    if (!accel_type_from_name(name, &type))
        return cst_fail(err, CST_ERR_INVALID_ARG,
                        "unknown acceleration structure '%s'; expected bvh, kdtree, grid, list, embree or octree", name);
    if (!accel_type_available(type))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "acceleration structure '%s' is not available in this build", name);
    return scene_set_accel(scene, type, err);
}

void cst_scene_info(const CstScene *s, CstSceneInfo *info)
{
    memset(info, 0, sizeof *info);
    info->triangles = s->num_triangles;
    info->spheres = s->num_spheres;
    info->shapes = s->num_shapes;
    info->emitters = s->num_emitters;
    info->materials = s->num_materials;
    info->lights = s->emitter_sampler.lights; /* set by commit */
    for (int i = 0; i < s->num_media; i++) {
        const Medium *m = &s->media[i];
        if (!color_is_black(medium_is_hetero(m) ? m->u.het.le : m->u.homog.le)) info->emitting_media++;
    }
    info->light_sampler = s->emitter_sampler.nee == LIGHT_SELECT_BVH       ? "bvh"
                          : s->emitter_sampler.nee == LIGHT_SELECT_UNIFORM ? "uniform"
                                                                           : "power";
    info->accel = accel_type_name(s->accel.type);
    info->accel_build_seconds = s->accel.build_seconds;
    info->accel_bytes = accel_memory_bytes(&s->accel);
    if (s->instances) {
        info->instances = s->instances->num_insts;
        info->instanced_objects = s->instances->num_protos;
        info->instance_bytes = instances_memory_bytes(s->instances);
        for (int i = 0; i < s->instances->num_protos; i++)
            info->instanced_triangles += (size_t)s->instances->protos[i].num_triangles;
    }
}
