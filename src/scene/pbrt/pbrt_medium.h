/* pbrt's participating media: MakeNamedMedium ("homogeneous"), MediumInterface, and the
 * medium interface the shapes get (pbrt_medium_apply). */
#ifndef CST_SCENE_PBRT_PBRT_MEDIUM_H
#define CST_SCENE_PBRT_PBRT_MEDIUM_H

#include "scene/pbrt/pbrt_loader.h"

CstStatus pbrt_make_named_medium_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_medium_interface_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* Before a shape is added: hands the graphics state's medium interface to the scene
 * (boundary: the shape's material is "interface"). Nothing in scenes without media. */
CstStatus pbrt_medium_apply(Loader *ld, int boundary, Loc loc, const char *d);

/* Whether the graphics state's interface separates two different media. */
static inline int pbrt_medium_transition(const Loader *ld) { return ld->gs.med_in != ld->gs.med_out; }

#endif
