/* libFuzzer target for the .spd spectrum reader (io/spd.c), from memory: any bytes must give
 * CST_OK with increasing finite wavelengths and finite values, or a CST_ERR_PARSE located as
 * "fuzz.spd:LINE:COL:" with nothing returned; never a crash, a hang or a leak. The pairs
 * then go through sampled_spectrum_from_pairs and the RGB reductions the loader applies.
 * Built by -DCST_FUZZ=ON (tests/fuzz/CMakeLists.txt); run with scripts/fuzz.sh. */
#include <math.h>
#include <stddef.h>
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "io/spd.h"
#include "math/spectrum_sampled.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    float *l = NULL, *v = NULL;
    int n = -1;
    CstError err;
    err.msg[0] = '\0';
    CstStatus st = spd_read("fuzz.spd", (const char *)data, size, &l, &v, &n, &err);
    if (st != CST_OK) {
        if (l || v || n != 0) abort();
        if (st == CST_ERR_PARSE && strncmp(err.msg, "fuzz.spd:", 9) != 0) abort();
        if (st != CST_ERR_PARSE && st != CST_ERR_OOM) abort();
        return 0;
    }
    if (n < 1 || n > SPD_MAX_PAIRS || !l || !v) abort();
    for (int i = 0; i < n; i++) {
        if (!isfinite(l[i]) || !isfinite(v[i]) || !(l[i] > 0.0f)) abort();
        if (i > 0 && !(l[i] > l[i - 1])) abort();
    }
    static SampledSpectrum s;
    sampled_spectrum_from_pairs(l, v, n, &s);
    volatile float sink = sampled_spectrum_mean_y(&s);
    Color c = sampled_spectrum_rgb_unbounded(&s);
    sink += c.c[0];
    c = sampled_spectrum_rgb_illuminant(&s);
    sink += c.c[2];
    (void)sink;
    free(l);
    free(v);
    return 0;
}

#include "fuzz_replay.h"
