/* Rendering options (Film, Sampler, Integrator, PixelFilter, Accelerator, ColorSpace) mapped
 * onto caustic's settings, and the directives reported as unsupported (media, Attribute,
 * Option). */
#ifndef CST_SCENE_PBRT_PBRT_OPTIONS_H
#define CST_SCENE_PBRT_PBRT_OPTIONS_H

#include "scene/pbrt/pbrt_loader.h"

/* Directive handlers, called through the table in pbrt_scene.c. Film ... Attribute take a
 * type name and parameters (NamedCall), mapped to settings or reported; MediumInterface and
 * Option read their own arguments. */
CstStatus pbrt_film_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_sampler_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_integrator_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_pixel_filter_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_accelerator_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_color_space_directive(Loader *ld, NamedCall *call);

CstStatus pbrt_attribute_directive(Loader *ld, NamedCall *call);

/* Option "type name" value: a single parameter, no type name before it */
CstStatus pbrt_option_directive(Loader *ld, Lexer *lx, Loc loc, const char *dname);

#endif
