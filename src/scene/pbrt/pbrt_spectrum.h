/* Spectra as linear sRGB: CIE 1931 matching functions, blackbodies, sampled and named
 * spectra (metals, glasses), and spectrum-valued parameters. */
#ifndef CST_SCENE_PBRT_PBRT_SPECTRUM_H
#define CST_SCENE_PBRT_PBRT_SPECTRUM_H

#include <stdbool.h>

#include "scene/pbrt/pbrt_loader.h"

typedef enum SpecKind { SPEC_REFLECTANCE, SPEC_UNBOUNDED, SPEC_ILLUMINANT } SpecKind;

/* A spectrum-valued parameter as linear sRGB: rgb, blackbody, spectrum (pairs or a named
 * spectrum), xyz (pbrt-v3), or with allow_tex a spectrum texture (its constant or average).
 * *found says whether the file gave it; out keeps its default otherwise. */
CstStatus pbrt_get_spectrum(Loader *ld, Params *ps, const char *d, const char *name,
                            SpecKind kind, int allow_tex, Color *out, int *found);

/* The same, and with spectrum_id (may be NULL) a spectrum kept for spectral mode: a named
 * spectrum (math/spectrum_sampled.h), (wavelength, value) pairs or a .spd file become a
 * scene spectrum (cst_scene_add_spectrum) and *spectrum_id its id; 0 for rgb, blackbody,
 * xyz, textures and the approximated illuminants. A string that is not a named spectrum
 * is read as a .spd file relative to the scene (pbrt-v4's rule): a missing or malformed
 * file is a located error. */
CstStatus pbrt_get_spectrum_id(Loader *ld, Params *ps, const char *d, const char *name, SpecKind kind,
                               int allow_tex, Color *out, int *found, int *spectrum_id);

/* Linear sRGB of a blackbody at kelvin, scaled to luminance Y = 1 (pbrt-v4 normalises
 * blackbody emitters to 1 nit before "scale"). */
Color pbrt_blackbody_rgb(double kelvin);
/* A sampled spectrum (lambda_nm, value pairs, piecewise linear, zero outside) as linear
 * sRGB. illuminant: scaled to luminance 1 as pbrt-v4 does for emitters; otherwise a
 * reflectance, normalised so that a constant spectrum c gives (c, c, c). */
Color pbrt_spectrum_rgb(const double *pairs, int num_pairs, bool illuminant);
/* RGB approximations of pbrt's named spectra "metal-<X>-eta" / "-k": false if unknown. */
bool pbrt_named_metal(const char *name, Color *out);
/* Normal-incidence Fresnel reflectance of a conductor, ((n-1)^2 + k^2) / ((n+1)^2 + k^2)
 * per channel. */
Color pbrt_conductor_r0(Color eta, Color k);

#endif
