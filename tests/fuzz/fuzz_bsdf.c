/* libFuzzer target for the measured material's .bsdf files (io/tensor.c, materials/
 * measured.c), from memory: any bytes must give CST_OK with tables of the sizes the
 * MeasuredData claims, or a message naming the file, never a crash, an overread, a leak or
 * an allocation the input cannot justify. Built by -DCST_FUZZ=ON (tests/fuzz/CMakeLists.txt);
 * run with scripts/fuzz.sh, see docs/fuzzing.md. */
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "caustic/caustic.h"
#include "materials/measured.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    MeasuredData m;
    CstError err = {0};
    CstStatus st = measured_read("fuzz.bsdf", data, size, &m, &err);
    if (st != CST_OK) {
        if (strncmp(err.msg, "fuzz.bsdf: ", 11) != 0 || m.ndf || m.spectra || m.rgb) abort();
        return 0;
    }
    /* Touch the last element of every table: ASan reports a table shorter than claimed. */
    const size_t grid = (size_t)m.n_phi * (size_t)m.n_theta * (size_t)m.res * (size_t)m.res;
    volatile float sink = m.ndf[(size_t)m.ndf_w * (size_t)m.ndf_h - 1] + m.sigma[(size_t)m.sigma_w * (size_t)m.sigma_h - 1] +
                          m.vndf[grid - 1] + m.luminance[grid - 1] + m.theta_i[m.n_theta - 1] + m.phi_i[m.n_phi - 1];
    if (m.n_lambda) sink += m.spectra[grid * (size_t)m.n_lambda - 1] + m.wavelengths[m.n_lambda - 1];
    else sink += m.rgb[grid * 3 - 1];
    (void)sink;
    measured_free(&m);
    return 0;
}

#include "fuzz_replay.h"
