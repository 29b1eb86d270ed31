/* The render driver: resolves settings, runs every integrator's passes on one thread
 * pool, reports progress, honours cancellation, and produces the film. Implements
 * cst_render (caustic.h). */
#ifndef CST_RENDER_RENDER_H
#define CST_RENDER_RENDER_H

#include "caustic/caustic.h"

#endif
