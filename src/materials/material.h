/* Material descriptions as stored in the scene. A Material is turned into a Bsdf at each
 * hit (materials/bsdf.h); keeping the two apart lets textures plug in later. */
#ifndef CST_MATERIALS_MATERIAL_H
#define CST_MATERIALS_MATERIAL_H

#include "math/rgb.h"

typedef enum MaterialType {
    MATERIAL_DIFFUSE, /* Lambertian: albedo = hemispherical reflectance */
    MATERIAL_MIRROR,  /* perfect specular reflection scaled by albedo */
    MATERIAL_GLASS    /* smooth dielectric: exact Fresnel, reflect or refract; albedo tints both */
} MaterialType;

typedef struct Material {
    MaterialType type;
    Rgb albedo;
    float ior; /* glass only: interior over exterior index of refraction, > 0 */
} Material;

#endif
