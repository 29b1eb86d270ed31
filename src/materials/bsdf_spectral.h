/* The spectral mode's conversion of a BSDF: its RGB parameters at a path's four
 * wavelengths (math/spectrum.h). */
#ifndef CST_MATERIALS_BSDF_SPECTRAL_H
#define CST_MATERIALS_BSDF_SPECTRAL_H

#include "materials/bsdf.h"
#include "math/spectrum.h"

/* Replaces every Color field of b's lobe, built in RGB by bsdf_init_shading (and the
 * texture overrides), by its values at wl: reflectances and tints as bounded reflectance
 * spectra (pbrt-v4 RGBAlbedoSpectrum), a conductor's eta and k as unbounded spectra
 * (RGBUnboundedSpectrum). Scalars (roughness, a dielectric's eta) are unchanged.
 * New lobes' Color fields must be added here. */
void bsdf_at_wavelengths(Bsdf *b, const Wavelengths *wl);

/* A material's colours looked up once (scene_commit): its albedo (reflectance or tint)
 * and a conductor's eta and k. */
typedef struct MaterialSpectra {
    SpectrumRgb albedo, eta, k;
} MaterialSpectra;
MaterialSpectra material_spectra(const Material *m);
/* bsdf_at_wavelengths for a BSDF made from m's constants alone (no texture override),
 * from ms = material_spectra(m): the same values without the table lookups. */
void bsdf_at_wavelengths_prepared(Bsdf *b, const MaterialSpectra *ms, const Wavelengths *wl);

#endif
