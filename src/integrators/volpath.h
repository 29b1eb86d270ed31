/* The path tracer's loop for scenes with participating media (volpath.c): path_li runs it
 * when the scene has media or medium boundaries. */
#ifndef CST_INTEGRATORS_VOLPATH_H
#define CST_INTEGRATORS_VOLPATH_H

#include "integrators/path.h"

/* As path_li (same modes, depth and roulette rules; medium vertices count as bounces),
 * starting in the camera's medium. No allocation. */
Color volpath_li(const Scene *scene, const PathParams *params, Ray ray, Sampler *smp, Wavelengths *wl,
                 uint64_t *rays);

/* A scattering vertex for next-event estimation: on a surface (bsdf, normals) or in a
 * medium (bsdf NULL, zero normals, phase g). */
typedef struct VolVertex {
    Vec3 p, ns, ng, wo;
    const Bsdf *bsdf;
    const SurfaceHit *sh; /* the surface hit, or NULL in a medium */
    float g;
    int medium; /* the medium at p (for a surface: on the ray's side) */
    float time; /* the path's time (motion blur): the shadow ray's instant */
} VolVertex;

/* One light sample from vertex v: f x Tr x L_e / pdf, MIS-weighted against the
 * scattering density when mis (power heuristic; delta lights unweighted). Shared with
 * SPPM's visible points in media (sppm.c, mis false). */
Color volpath_nee(const Scene *s, const VolVertex *v, bool mis, Sampler *smp, const Wavelengths *wl, uint64_t *rays);
/* The same from the light pick's and the light point's uniforms u_sel, u (volpath_nee
 * draws them in that order), so explain can sample the same light point again. */
Color volpath_nee_u(const Scene *s, const VolVertex *v, bool mis, float u_sel, Vec2 u, const Wavelengths *wl,
                    uint64_t *rays);

#endif
