/* Names of the BSDF lobe codes (bsdf_lobe.h) for explain's SCATTER events. */
#include "materials/bsdf_lobe.h"

static const char *const lobe_names[BSDF_LOBE_COUNT] = {
    [BSDF_LOBE_NONE] = "none",
    [BSDF_LOBE_DIFFUSE_REFLECTION] = "diffuse reflection",
    [BSDF_LOBE_GLOSSY_REFLECTION] = "glossy reflection",
    [BSDF_LOBE_SPECULAR_REFLECTION] = "specular reflection",
    [BSDF_LOBE_DIFFUSE_TRANSMISSION] = "diffuse transmission",
    [BSDF_LOBE_GLOSSY_TRANSMISSION] = "glossy transmission",
    [BSDF_LOBE_SPECULAR_TRANSMISSION] = "specular transmission",
    [BSDF_LOBE_COAT_SPECULAR_REFLECTION] = "coat specular reflection",
    [BSDF_LOBE_COAT_GLOSSY_REFLECTION] = "coat glossy reflection",
    [BSDF_LOBE_BASE_DIFFUSE_REFLECTION] = "base diffuse reflection",
    [BSDF_LOBE_BASE_GLOSSY_REFLECTION] = "base glossy reflection",
    [BSDF_LOBE_BASE_SPECULAR_REFLECTION] = "base specular reflection",
    [BSDF_LOBE_HAIR_R] = "hair R",
    [BSDF_LOBE_HAIR_TT] = "hair TT",
    [BSDF_LOBE_HAIR_TRT] = "hair TRT",
    [BSDF_LOBE_HAIR_RESIDUAL] = "hair residual",
};

const char *bsdf_lobe_name(uint8_t lobe) { return lobe < BSDF_LOBE_COUNT ? lobe_names[lobe] : "unknown"; }

bool bsdf_lobe_is_transmission(uint8_t lobe)
{
    return lobe == BSDF_LOBE_DIFFUSE_TRANSMISSION || lobe == BSDF_LOBE_GLOSSY_TRANSMISSION ||
           lobe == BSDF_LOBE_SPECULAR_TRANSMISSION || lobe == BSDF_LOBE_HAIR_TT;
}
