/* The scene view of sss_walk.h: subsurface materials turned into medium interfaces, so that
 * light subpaths and camera subpaths random-walk the same media and agree. */
#include "integrators/sss_walk.h"

#include <stdlib.h>
#include <string.h>

#include "accel/instances.h"
#include "materials/bssrdf.h"

/* The view and the arrays it does not share with its scene, freed together. */
typedef struct SssWalkView {
    Scene view;              /* first: the pointer handed out */
    Medium *media;           /* one per subsurface material */
    MediumInterface *ifaces; /* one per subsurface material: inside its medium, outside vacuum */
    PrimInfo *info;          /* triangles', spheres' then shapes' PrimInfo, .medium set */
} SssWalkView;

/* The medium under subsurface material m, in RGB: the given coefficients, or those of its
 * diffuse reflectance and mean free path by the table's inversion (pbrt-v4
 * SubsurfaceFromDiffuse, as path_sss.c's sss_coeffs; in spectral mode path_sss.c inverts
 * per wavelength, while the medium's RGB coefficients are upsampled as unbounded spectra). */
static Medium sss_medium(const Material *m)
{
    Medium med = {.type = MEDIUM_HOMOGENEOUS, .g = m->g};
    if (!m->sss_from_reflectance) {
        med.u.homog.sigma_a = m->sss_sigma_a;
        med.u.homog.sigma_s = m->sss_sigma_s;
        medium_prepare_spectra(&med);
        return med;
    }
    Color r = m->sss_reflectance;
    for (int c = 0; c < COLOR_LANES; c++) r.c[c] = clampf(r.c[c], 0.0f, 1.0f);
    bssrdf_from_reflectance(m->bssrdf, r, m->sss_mfp, &med.u.homog.sigma_a, &med.u.homog.sigma_s);
    medium_prepare_spectra(&med);
    return med;
}

/* Whether an instance prototype's triangle or shape uses a subsurface material. */
static bool instances_use_subsurface(const Scene *s)
{
    if (!s->instances) return false;
    for (int p = 0; p < s->instances->num_protos; p++) {
        const InstProto *ip = &s->instances->protos[p];
        for (int t = 0; t < ip->num_triangles; t++)
            if (s->materials[ip->tri_material[t]].subsurface) return true;
        for (int k = 0; k < ip->num_shapes; k++)
            if (s->materials[ip->shape_material[k]].subsurface) return true;
    }
    return false;
}

CstStatus sss_walk_view_create(const Scene *s, const Scene **out, CstError *err)
{
    *out = NULL;
    for (int i = 0; i < s->num_materials; i++)
        if (s->materials[i].subsurface && s->materials[i].sss_from_reflectance &&
            s->materials[i].sss_reflectance_texture)
            return cst_fail(err, CST_ERR_UNSUPPORTED, "material %d: a subsurface material whose reflectance is a "
                            "texture is not a homogeneous medium, which light, bdpt, vcm and mmlt walk; use path, "
                            "path-nee or path-bsdf, or a constant reflectance", i);
    if (instances_use_subsurface(s))
        return cst_fail(err, CST_ERR_UNSUPPORTED, "an instanced object with a subsurface material: light, bdpt, vcm "
                        "and mmlt walk subsurface media of non-instanced shapes only; use path, path-nee or path-bsdf");
    const size_t prims = (size_t)s->num_triangles + (size_t)s->num_spheres + (size_t)s->num_shapes;
    SssWalkView *w = calloc(1, sizeof *w);
    int *medium_of = calloc((size_t)s->num_materials + 1, sizeof *medium_of); /* 1 + interface, 0 none */
    if (w) {
        w->media = calloc((size_t)s->num_subsurface + 1, sizeof *w->media);
        w->ifaces = calloc((size_t)s->num_subsurface + 1, sizeof *w->ifaces);
        w->info = malloc((prims + 1) * sizeof *w->info);
    }
    if (!w || !medium_of || !w->media || !w->ifaces || !w->info) {
        free(medium_of);
        sss_walk_view_destroy(w ? &w->view : NULL);
        return cst_fail(err, CST_ERR_OOM, "out of memory making the subsurface media");
    }
    int n = 0;
    for (int i = 0; i < s->num_materials && n < s->num_subsurface; i++) {
        if (!s->materials[i].subsurface) continue;
        w->media[n] = sss_medium(&s->materials[i]);
        w->ifaces[n] = (MediumInterface){.inside = n, .outside = -1, .boundary = 0};
        medium_of[i] = ++n;
    }
    /* (each array is NULL when its count is 0: memcpy may not be given NULL even then) */
    if (s->num_triangles) memcpy(w->info, s->tri_info, (size_t)s->num_triangles * sizeof *w->info);
    if (s->num_spheres) memcpy(w->info + s->num_triangles, s->sphere_info, (size_t)s->num_spheres * sizeof *w->info);
    if (s->num_shapes)
        memcpy(w->info + s->num_triangles + s->num_spheres, s->shape_info, (size_t)s->num_shapes * sizeof *w->info);
    for (size_t p = 0; p < prims; p++) w->info[p].medium = medium_of[w->info[p].material];
    free(medium_of);
    /* The shared scene, its media and interfaces (none: integrator_prepare refuses scenes
     * with both) and primitive attributes replaced; its capacities zeroed so that nothing
     * grows these arrays. */
    w->view = *s;
    w->view.media = w->media;
    w->view.num_media = n;
    w->view.cap_media = 0;
    w->view.medium_ifaces = w->ifaces;
    w->view.num_medium_ifaces = n;
    w->view.cap_medium_ifaces = 0;
    w->view.tri_info = w->info;
    w->view.sphere_info = w->info + s->num_triangles;
    w->view.shape_info = w->info + s->num_triangles + s->num_spheres;
    w->view.num_subsurface = 0;
    *out = &w->view;
    return CST_OK;
}

void sss_walk_view_destroy(const Scene *view)
{
    if (!view) return;
    SssWalkView *w = (SssWalkView *)(uintptr_t)view; /* view is the first member */
    free(w->media);
    free(w->ifaces);
    free(w->info);
    free(w);
}
