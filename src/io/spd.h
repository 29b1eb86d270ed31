/* .spd spectrum files (pbrt-v4's "spectrum eta" "file.spd"): pairs of wavelength (nm) and
 * value, separated by white space; '#' starts a comment to the end of the line. caustic's
 * own reader; every error names the file, line and column. */
#ifndef CST_IO_SPD_H
#define CST_IO_SPD_H

#include <stddef.h>

#include "caustic/caustic.h"

/* At most this many pairs: far more than any measured spectrum (pbrt's have ~50-500). */
#define SPD_MAX_PAIRS 100000

/* Parses len bytes of text (name is used in messages only). On success *lambda and *value
 * are new malloc'd arrays of *n >= 1 floats (the caller frees both): wavelengths finite,
 * > 0 and strictly increasing, values finite. Errors: CST_ERR_PARSE "name:line:col: ..."
 * (not a number, an odd count, a wavelength that does not increase, no pairs, too many),
 * CST_ERR_OOM. Nothing to free on error. */
CstStatus spd_read(const char *name, const char *text, size_t len, float **lambda, float **value, int *n,
                   CstError *err);
/* The same for a file (read through file_read_all). */
CstStatus spd_read_file(const char *path, float **lambda, float **value, int *n, CstError *err);

#endif
