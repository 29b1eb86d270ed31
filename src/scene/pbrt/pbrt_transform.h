/* Transforms with their inverses, the current transformation matrix, the graphics-state
 * stack and named coordinate systems, and the directives that change them. */
#ifndef CST_SCENE_PBRT_PBRT_TRANSFORM_H
#define CST_SCENE_PBRT_PBRT_TRANSFORM_H

#include "scene/pbrt/pbrt_loader.h"

/* The identity with its inverse. */
Xf pbrt_xf_identity(void);

/* a * b, inverses composed alongside. */
Xf pbrt_xf_compose(const Xf *a, const Xf *b);

/* The inverse transform: matrix and inverse exchanged. */
Xf pbrt_xf_swap(Xf x);

/* Names xf and xf_end, the start and end CTMs (CoordinateSystem, "camera", "world"),
 * replacing an earlier one of that name. */
CstStatus pbrt_set_named_xf(Loader *ld, const char *name, Xf xf, Xf xf_end);

/* Whether the start and end CTMs differ: what is declared now moves over the shutter. */
int pbrt_ctm_moving(const Loader *ld);

/* When the CTM moves: warns that d (a light, a medium, a sphere...) is rendered static at
 * its start-time transform, because `why` (pbrt-v4 does the same for lights and media). */
void pbrt_warn_static(Loader *ld, Loc loc, const char *d, const char *why);

/* Pushes the graphics state (AttributeBegin, ObjectBegin) or, transform_only, just the CTM
 * (TransformBegin). */
CstStatus pbrt_push_state(Loader *ld, Loc loc, int transform_only);

/* Pops what the matching push saved; a located error for an End without or against its
 * Begin. */
CstStatus pbrt_pop_state(Loader *ld, Loc loc, int transform_only, const char *d);

/* Directive handlers, called through the table in pbrt_scene.c; dname is the directive's
 * name (one handler serves Transform and ConcatTransform, AttributeBegin and TransformBegin...). */
CstStatus pbrt_translate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_scale_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_rotate_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_look_at_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* Transform replaces the CTM, ConcatTransform multiplies it. */
CstStatus pbrt_transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *d);

CstStatus pbrt_identity_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* CoordinateSystem names the CTM, CoordSysTransform makes a named one current. */
CstStatus pbrt_coordinate_system_directive(Loader *ld, Lexer *lx, Loc loc, const char *d);

CstStatus pbrt_active_transform_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* TransformTimes: only before WorldBegin, start < end (located errors otherwise). */
CstStatus pbrt_transform_times_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_reverse_orientation_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* AttributeBegin/End push and pop the whole graphics state, TransformBegin/End (pbrt-v3)
 * only the CTM. */
CstStatus pbrt_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

CstStatus pbrt_world_begin_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

/* pbrt-v3: the end of the file follows */
CstStatus pbrt_world_end_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
