/* Error reporting inside the library: fill a CstError and return its status. */
#ifndef CST_CORE_ERROR_H
#define CST_CORE_ERROR_H

#include "caustic/caustic.h"

/* printf-style; err may be NULL. Returns status so callers can `return cst_fail(...)`. */
CstStatus cst_fail(CstError *err, CstStatus status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static inline void cst_error_clear(CstError *err)
{
    if (err) { err->status = CST_OK; err->msg[0] = '\0'; }
}

#endif
