/* Error reporting inside the library: fill a CstError and return its status. */
#ifndef CST_CORE_ERROR_H
#define CST_CORE_ERROR_H

#include <stddef.h>

#include "caustic/caustic.h"

/* Makes the NUL-terminated msg (in a buffer of cap bytes, at most 2048 used) safe to print:
 * control bytes other than '\n', DEL and bytes of invalid UTF-8 become \xHH; valid UTF-8
 * is kept except invisible or reordering code points (C1 controls, the byte order mark
 * U+FEFF, bidirectional controls), which become \uXXXX. Idempotent (backslashes are kept),
 * so a message wrapped into another is not escaped twice. Truncates at a character. */
void cst_escape_message(char *msg, size_t cap);

/* printf-style; err may be NULL. Returns status so callers can `return cst_fail(...)`.
 * The message is escaped by cst_escape_message: file content quoted in it cannot reach a
 * terminal as raw bytes. */
CstStatus cst_fail(CstError *err, CstStatus status, const char *fmt, ...)
    __attribute__((format(printf, 3, 4)));

static inline void cst_error_clear(CstError *err)
{
    if (err) { err->status = CST_OK; err->msg[0] = '\0'; }
}

#endif
