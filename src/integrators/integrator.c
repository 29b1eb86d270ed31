/* The integrator interface (integrator.h): the public names of the integrators. */
#include "integrators/integrator.h"

#include <string.h>

static const struct { const char *name; CstIntegrator id; } INTEGRATOR_NAMES[] = {
    {"path", CST_INTEGRATOR_PATH},       {"path-nee", CST_INTEGRATOR_PATH_NEE},
    {"path-bsdf", CST_INTEGRATOR_PATH_BSDF}, {"mis", CST_INTEGRATOR_PATH},
    {"nee", CST_INTEGRATOR_PATH_NEE},    {"bsdf", CST_INTEGRATOR_PATH_BSDF},
    {"light", CST_INTEGRATOR_LIGHT},     {"lighttracing", CST_INTEGRATOR_LIGHT},
    {"whitted", CST_INTEGRATOR_WHITTED}, {"photon", CST_INTEGRATOR_PHOTON},
    {"sppm", CST_INTEGRATOR_SPPM},       {"bdpt", CST_INTEGRATOR_BDPT},
    {"vcm", CST_INTEGRATOR_VCM},
};

CstIntegrator cst_integrator_from_name(const char *name)
{
    for (size_t i = 0; i < sizeof INTEGRATOR_NAMES / sizeof INTEGRATOR_NAMES[0]; i++)
        if (strcmp(name, INTEGRATOR_NAMES[i].name) == 0) return INTEGRATOR_NAMES[i].id;
    return CST_INTEGRATOR_DEFAULT;
}

const char *cst_integrator_name(CstIntegrator integrator)
{
    switch (integrator) {
    case CST_INTEGRATOR_PATH: return "path";
    case CST_INTEGRATOR_PATH_NEE: return "path-nee";
    case CST_INTEGRATOR_PATH_BSDF: return "path-bsdf";
    case CST_INTEGRATOR_LIGHT: return "light";
    case CST_INTEGRATOR_WHITTED: return "whitted";
    case CST_INTEGRATOR_PHOTON: return "photon";
    case CST_INTEGRATOR_SPPM: return "sppm";
    case CST_INTEGRATOR_BDPT: return "bdpt";
    case CST_INTEGRATOR_VCM: return "vcm";
    case CST_INTEGRATOR_DEFAULT: break;
    }
    return "default";
}
