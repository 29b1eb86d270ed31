/* The lobe a BSDF sample was drawn from (issue 30): a one-byte code every sampling routine
 * of src/materials/ sets, and its name for `caustic explain`. Renders never read it. */
#ifndef CST_MATERIALS_BSDF_LOBE_H
#define CST_MATERIALS_BSDF_LOBE_H

#include <stdbool.h>
#include <stdint.h>

/* Reflection lobes leave wi on wo's side of the surface, transmission lobes on the other.
 * Coat / base: the coated materials and plastic, whose sample either reflected off the
 * dielectric interface (coat) or went through it to the base and back out (base). Hair:
 * Marschner's p = 0 (R), 1 (TT), 2 (TRT) and the residual p >= 3. */
typedef enum BsdfLobe {
    BSDF_LOBE_NONE = 0,
    BSDF_LOBE_DIFFUSE_REFLECTION,
    BSDF_LOBE_GLOSSY_REFLECTION,
    BSDF_LOBE_SPECULAR_REFLECTION,
    BSDF_LOBE_DIFFUSE_TRANSMISSION,
    BSDF_LOBE_GLOSSY_TRANSMISSION,
    BSDF_LOBE_SPECULAR_TRANSMISSION,
    BSDF_LOBE_COAT_SPECULAR_REFLECTION,
    BSDF_LOBE_COAT_GLOSSY_REFLECTION,
    BSDF_LOBE_BASE_DIFFUSE_REFLECTION,
    BSDF_LOBE_BASE_GLOSSY_REFLECTION,
    BSDF_LOBE_BASE_SPECULAR_REFLECTION,
    BSDF_LOBE_HAIR_R,
    BSDF_LOBE_HAIR_TT,
    BSDF_LOBE_HAIR_TRT,
    BSDF_LOBE_HAIR_RESIDUAL,
    BSDF_LOBE_COUNT
} BsdfLobe;

/* A static string ("diffuse reflection", "coat specular reflection", "hair TT", ...);
 * "unknown" for a code out of range. */
const char *bsdf_lobe_name(uint8_t lobe);
/* Whether the lobe sends wi to the other side of the surface than wo (hair: TT only, in
 * the fibre's own sense; the residual lobe is neither). */
bool bsdf_lobe_is_transmission(uint8_t lobe);

#endif
