/* Error reporting: status names and the formatted-message helper. */
#include "core/error.h"

#include <stdarg.h>
#include <stdio.h>

CstStatus cst_fail(CstError *err, CstStatus status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        err->status = status;
    }
    return status;
}

const char *cst_status_name(CstStatus status)
{
    switch (status) {
    case CST_OK: return "CST_OK";
    case CST_ERR_INVALID_ARG: return "CST_ERR_INVALID_ARG";
    case CST_ERR_IO: return "CST_ERR_IO";
    case CST_ERR_PARSE: return "CST_ERR_PARSE";
    case CST_ERR_UNSUPPORTED: return "CST_ERR_UNSUPPORTED";
    case CST_ERR_OOM: return "CST_ERR_OOM";
    case CST_ERR_INTERNAL: return "CST_ERR_INTERNAL";
    case CST_ERR_CANCELLED: return "CST_ERR_CANCELLED";
    case CST_ERR_NONFINITE: return "CST_ERR_NONFINITE";
    }
    return "CST_ERR_UNKNOWN";
}
