/* Error reporting: status names, the formatted-message helper, and the escaping that keeps
 * bytes quoted from input files (terminal escape sequences, invalid UTF-8, invisible
 * characters) out of messages as raw bytes. */
#include "core/error.h"

#include <stdarg.h>
#include <stdint.h>
#include <stdio.h>
#include <string.h>

/* Length of the valid UTF-8 sequence at s[0, n) and its code point, or 0 when s does not
 * start one (a stray continuation byte, an overlong form, a surrogate, beyond U+10FFFF, or
 * cut short). */
static size_t utf8_sequence(const unsigned char *s, size_t n, uint32_t *cp)
{
    unsigned char c = s[0];
    size_t len = c >= 0xF0 ? 4 : c >= 0xE0 ? 3 : c >= 0xC0 ? 2 : 0;
    if (len == 0 || c >= 0xF5 || len > n) return 0;
    uint32_t v = c & (0x7Fu >> len);
    for (size_t i = 1; i < len; i++) {
        if ((s[i] & 0xC0) != 0x80) return 0;
        v = v << 6 | (s[i] & 0x3Fu);
    }
    static const uint32_t min[5] = {0, 0, 0x80, 0x800, 0x10000};
    if (v < min[len] || v > 0x10FFFF || (v >= 0xD800 && v <= 0xDFFF)) return 0;
    *cp = v;
    return len;
}

/* Code points that are valid but print as nothing or reorder the line: C1 controls, the
 * byte order mark, bidirectional controls, line and paragraph separators. */
static int invisible(uint32_t cp)
{
    return (cp >= 0x80 && cp <= 0x9F) || cp == 0xFEFF || cp == 0x200E || cp == 0x200F ||
           (cp >= 0x202A && cp <= 0x202E) || (cp >= 0x2066 && cp <= 0x2069) || cp == 0x2028 ||
           cp == 0x2029;
}

void cst_escape_message(char *msg, size_t cap)
{
    if (!msg || cap == 0) return;
    char out[2048];
    size_t limit = cap < sizeof out ? cap : sizeof out, o = 0, n = strnlen(msg, cap);
    const unsigned char *s = (const unsigned char *)msg;
    for (size_t i = 0; i < n;) {
        char esc[16];
        size_t len = 1, elen;
        uint32_t cp = 0;
        if (s[i] >= 0x20 && s[i] < 0x7F) {
            esc[0] = (char)s[i];
            elen = 1;
        } else if (s[i] == '\n') { /* the message's own line breaks */
            esc[0] = '\n';
            elen = 1;
        } else if (s[i] >= 0x80 && (len = utf8_sequence(s + i, n - i, &cp)) > 0 && !invisible(cp)) {
            memcpy(esc, s + i, len);
            elen = len;
        } else if (len > 0 && s[i] >= 0x80) {
            elen = (size_t)snprintf(esc, sizeof esc, "\\u%04X", (unsigned)cp);
        } else {
            len = 1; /* a control byte, DEL, or a byte of invalid UTF-8 */
            elen = (size_t)snprintf(esc, sizeof esc, "\\x%02X", s[i]);
        }
        if (o + elen >= limit) break; /* truncated, as vsnprintf would, at a character */
        memcpy(out + o, esc, elen);
        o += elen;
        i += len;
    }
    out[o] = '\0';
    memcpy(msg, out, o + 1);
}

CstStatus cst_fail(CstError *err, CstStatus status, const char *fmt, ...)
{
    if (err) {
        va_list ap;
        va_start(ap, fmt);
        vsnprintf(err->msg, sizeof err->msg, fmt, ap);
        va_end(ap);
        cst_escape_message(err->msg, sizeof err->msg);
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
