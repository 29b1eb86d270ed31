/* Subsurface materials as the participating media that the light tracer, BDPT, VCM and
 * MMLT walk (subpath_media.c): a view of the scene in which they are medium interfaces. */
#ifndef CST_INTEGRATORS_SSS_WALK_H
#define CST_INTEGRATORS_SSS_WALK_H

#include "core/error.h"
#include "scene/scene.h"

/* A scene s with subsurface materials (and no media) as the bidirectional integrators see
 * it: every primitive of a subsurface material separates that material's homogeneous medium
 * (inside, behind ng: sigma_a, sigma_s as path_sss.c computes them in RGB, the material's
 * g) from vacuum (outside), its dielectric surface unchanged, so a path refracting in
 * random-walks the medium (no diffusion approximation) and leaves through the same
 * dielectric. num_subsurface is 0 in the view. Everything else is s's, shared: the view is
 * valid while s lives and must not be committed, edited or scene_destroy()ed.
 * Fails with CST_ERR_UNSUPPORTED when a subsurface material takes its reflectance from a
 * texture (not a homogeneous medium) or an instance uses one (instances carry no medium
 * interface), CST_ERR_OOM; message set. Caller frees with sss_walk_view_destroy. */
CstStatus sss_walk_view_create(const Scene *s, const Scene **out, CstError *err);
/* Accepts NULL. */
void sss_walk_view_destroy(const Scene *view);

#endif
