/* Named scattering presets: the measured sigma_a and sigma_s that pbrt-v4's "preset"
 * parameter names (GetMediumScatteringProperties), for homogeneous and grid media. */
#ifndef CST_MEDIA_MEDIUM_PRESETS_H
#define CST_MEDIA_MEDIUM_PRESETS_H

#include <stdbool.h>
#include <stddef.h>

#include "math/color.h"

/* The preset called name (exact, case-sensitive, as pbrt-v4): sigma_a and sigma_s in linear
 * sRGB, per millimetre as measured (pbrt-v4 applies them per unit of the scene unchanged;
 * so does caustic). false when no preset has that name. */
bool medium_preset(const char *name, Color *sigma_a, Color *sigma_s);
/* A few of the names, for error messages. */
#define MEDIUM_PRESET_EXAMPLES "pbrt-v4's measured media (\"Skin1\", \"Marble\", \"Ketchup\", \"Regular Milk\", ...; " \
                               "docs/scene-format.md lists them)"

/* The number of presets and the i-th name (for listing them in error messages). */
int medium_preset_count(void);
const char *medium_preset_name(int i);

#endif
