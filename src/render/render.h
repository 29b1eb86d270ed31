/* The render driver: resolves settings, schedules tiles over worker threads, reports
 * progress, and produces the film. Implements cst_render (caustic.h). */
#ifndef CST_RENDER_RENDER_H
#define CST_RENDER_RENDER_H

#include "caustic/caustic.h"

enum { RENDER_TILE = 16 };

#endif
