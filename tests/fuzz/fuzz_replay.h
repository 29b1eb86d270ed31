/* The fuzz targets' replay main(): without libFuzzer (-DFUZZ_STANDALONE, e.g. gcc with
 * -fsanitize=address) a target is a program that feeds each file named on its command line
 * through LLVMFuzzerTestOneInput. Included once, at the end of each target. */
#ifndef CST_FUZZ_REPLAY_H
#define CST_FUZZ_REPLAY_H

#ifdef FUZZ_STANDALONE
#include <stdint.h>
#include <stdio.h>
#include <stdlib.h>

int main(int argc, char **argv)
{
    for (int i = 1; i < argc; i++) {
        FILE *f = fopen(argv[i], "rb");
        if (!f) {
            perror(argv[i]);
            return 1;
        }
        size_t cap = (size_t)1 << 20; /* inputs are small; longer files are truncated */
        uint8_t *buf = malloc(cap);
        if (!buf) {
            fclose(f);
            return 1;
        }
        size_t len = fread(buf, 1, cap, f);
        fclose(f);
        LLVMFuzzerTestOneInput(buf, len);
        free(buf);
    }
    return 0;
}
#endif

#endif
