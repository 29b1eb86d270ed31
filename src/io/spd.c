/* The .spd reader (spd.h): a hand-written scanner of numbers and comments with locations. */
#include "io/spd.h"

#include <errno.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "core/file.h"

static int is_space(char c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\v' || c == '\f'; }

CstStatus spd_read(const char *name, const char *text, size_t len, float **lambda, float **value, int *n,
                   CstError *err)
{
    *lambda = *value = NULL;
    *n = 0;
    size_t cap = 0, count = 0; /* numbers read */
    float *nums = NULL;
    int line = 1, col = 1, last_line = 1, last_col = 1;
    size_t i = 0;
    CstStatus st = CST_OK;
    while (i < len) {
        char c = text[i];
        if (c == '\n') {
            i++, line++, col = 1;
            continue;
        }
        if (is_space(c)) {
            i++, col++;
            continue;
        }
        if (c == '#') {
            while (i < len && text[i] != '\n') i++;
            continue;
        }
        /* A token: up to white space or a comment, copied so strtod stops at its end. */
        size_t j = i;
        while (j < len && !is_space(text[j]) && text[j] != '#') j++;
        char tok[64];
        size_t tl = j - i;
        char *end = NULL;
        double v = 0.0;
        if (tl < sizeof tok) {
            memcpy(tok, text + i, tl);
            tok[tl] = '\0';
            errno = 0;
            v = strtod(tok, &end);
        }
        if (tl >= sizeof tok || end != tok + tl || tl == 0 || !isfinite(v) || fabs(v) > 3.0e38) {
            int shown = tl > 24 ? 24 : (int)tl;
            st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: \"%.*s%s\" is not a number; expected (wavelength in nm, "
                          "value) pairs", name, line, col, shown, text + i, tl > 24 ? "..." : "");
            goto fail;
        }
        /* Kept as floats: a wavelength must stay positive as one (6e-62 rounds to 0). */
        if (count % 2 == 0 && !((float)v > 0.0f)) {
            st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: wavelength %g is not positive%s; expected (wavelength in "
                          "nm, value) pairs", name, line, col, v, v > 0.0 ? " as a 32-bit float" : "");
            goto fail;
        }
        if (count % 2 == 0 && count >= 2 && !((float)v > nums[count - 2])) {
            st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: wavelength %g does not increase (the previous is %g); "
                          "expected pairs in increasing wavelength", name, line, col, v, (double)nums[count - 2]);
            goto fail;
        }
        if (count >= 2 * (size_t)SPD_MAX_PAIRS) {
            st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: more than %d (wavelength, value) pairs", name, line, col,
                          SPD_MAX_PAIRS);
            goto fail;
        }
        if (count == cap) {
            size_t nc = cap ? 2 * cap : 128;
            float *nn = realloc(nums, nc * sizeof *nn);
            if (!nn) {
                st = cst_fail(err, CST_ERR_OOM, "%s: out of memory", name);
                goto fail;
            }
            nums = nn, cap = nc;
        }
        nums[count++] = (float)v;
        last_line = line, last_col = col;
        col += (int)tl;
        i = j;
    }
    if (count == 0) {
        st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: no (wavelength, value) pairs; expected at least one", name,
                      line, col);
        goto fail;
    }
    if (count % 2) {
        st = cst_fail(err, CST_ERR_PARSE, "%s:%d:%d: wavelength %g has no value; expected (wavelength in nm, "
                      "value) pairs", name, last_line, last_col, (double)nums[count - 1]);
        goto fail;
    }
    size_t np = count / 2;
    float *l = malloc(np * sizeof *l), *val = malloc(np * sizeof *val);
    if (!l || !val) {
        free(l), free(val);
        st = cst_fail(err, CST_ERR_OOM, "%s: out of memory", name);
        goto fail;
    }
    for (size_t k = 0; k < np; k++) l[k] = nums[2 * k], val[k] = nums[2 * k + 1];
    free(nums);
    *lambda = l, *value = val, *n = (int)np;
    return CST_OK;
fail:
    free(nums);
    return st;
}

CstStatus spd_read_file(const char *path, float **lambda, float **value, int *n, CstError *err)
{
    char *data = NULL;
    size_t len = 0;
    *lambda = *value = NULL;
    *n = 0;
    CstStatus st = file_read_all(path, &data, &len, err);
    if (st == CST_OK) st = spd_read(path, data, len, lambda, value, n, err);
    free(data);
    return st;
}
