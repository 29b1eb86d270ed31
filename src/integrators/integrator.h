/* The integrator interface: which light-transport algorithm renders, by its public
 * CstIntegrator id, and the public name table of the integrators. */
#ifndef CST_INTEGRATORS_INTEGRATOR_H
#define CST_INTEGRATORS_INTEGRATOR_H

#include "caustic/caustic.h"

#endif
