/* Finds where a value sits in JSON text, for error messages: a bounded, non-recursive
 * scanner that skips strings, numbers, literals and containers without building anything. */
#include "scene/json/json_locate.h"

#include <limits.h>
#include <stdint.h>

/* Every helper takes the cursor by pointer and returns false at the end of the text or on
 * a byte that cannot start what was expected; no helper reads text[len] or beyond. */

static bool is_ws(unsigned char c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r';
}

static void skip_ws(const char *t, size_t len, size_t *p)
{
    while (*p < len && is_ws((unsigned char)t[*p]))
        (*p)++;
}

/* *p at the opening quote; leaves *p after the closing quote. */
static bool skip_string(const char *t, size_t len, size_t *p)
{
    size_t i = *p + 1;
    while (i < len) {
        char c = t[i];
        if (c == '"') {
            *p = i + 1;
            return true;
        }
        /* An escape covers the next byte, which may be a quote; \uXXXX needs no special
         * case because hex digits are never quotes or backslashes. */
        i += (c == '\\') ? 2 : 1;
    }
    return false;
}

/* *p at '{' or '['; leaves *p after the matching close. Counts depth only: brackets need not
 * pair by kind here, as the text was validated (or is garbage we just must not overrun). */
static bool skip_container(const char *t, size_t len, size_t *p)
{
    size_t i = *p, depth = 0;
    while (i < len) {
        char c = t[i];
        if (c == '"') {
            if (!skip_string(t, len, &i))
                return false;
            continue;
        }
        if (c == '{' || c == '[') {
            depth++;
        } else if (c == '}' || c == ']') {
            if (--depth == 0) {
                *p = i + 1;
                return true;
            }
        }
        i++;
    }
    return false;
}

static bool is_scalar_byte(unsigned char c)
{
    /* numbers (-0.5e+3) and the literals true, false, null */
    return (c >= '0' && c <= '9') || c == '-' || c == '+' || c == '.' || (c >= 'a' && c <= 'z') ||
           (c >= 'A' && c <= 'Z');
}

static bool skip_value(const char *t, size_t len, size_t *p)
{
    if (*p >= len)
        return false;
    char c = t[*p];
    if (c == '"')
        return skip_string(t, len, p);
    if (c == '{' || c == '[')
        return skip_container(t, len, p);
    size_t start = *p;
    while (*p < len && is_scalar_byte((unsigned char)t[*p]))
        (*p)++;
    return *p > start; /* nothing consumed: not a value, stop rather than loop */
}

static int hex_digit(char c)
{
    if (c >= '0' && c <= '9') return c - '0';
    if (c >= 'a' && c <= 'f') return c - 'a' + 10;
    if (c >= 'A' && c <= 'F') return c - 'A' + 10;
    return -1;
}

/* Reads XXXX of a \uXXXX escape starting at t[i]; -1 if malformed or truncated. */
static int32_t read_hex4(const char *t, size_t len, size_t i)
{
    if (i > len || len - i < 4)
        return -1;
    int32_t v = 0;
    for (int k = 0; k < 4; k++) {
        int d = hex_digit(t[i + (size_t)k]);
        if (d < 0)
            return -1;
        v = v * 16 + d;
    }
    return v;
}

static int utf8_encode(uint32_t cp, unsigned char out[4])
{
    if (cp < 0x80) { out[0] = (unsigned char)cp; return 1; }
    if (cp < 0x800) {
        out[0] = (unsigned char)(0xC0 | (cp >> 6));
        out[1] = (unsigned char)(0x80 | (cp & 0x3F));
        return 2;
    }
    if (cp < 0x10000) {
        out[0] = (unsigned char)(0xE0 | (cp >> 12));
        out[1] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
        out[2] = (unsigned char)(0x80 | (cp & 0x3F));
        return 3;
    }
    out[0] = (unsigned char)(0xF0 | (cp >> 18));
    out[1] = (unsigned char)(0x80 | ((cp >> 12) & 0x3F));
    out[2] = (unsigned char)(0x80 | ((cp >> 6) & 0x3F));
    out[3] = (unsigned char)(0x80 | (cp & 0x3F));
    return 4;
}

/* *p at the opening quote of a string; decodes it as it goes and compares with key.
 * Leaves *p after the closing quote. Sets *equal; returns false if the string is cut off.
 * Decoding matters: "\u0061lbedo" is the key albedo to jansson, so it must be to us. */
static bool match_string(const char *t, size_t len, size_t *p, const char *key, bool *equal)
{
    size_t i = *p + 1, k = 0;
    bool eq = true;
    while (i < len) {
        unsigned char bytes[4];
        int n = 1;
        char c = t[i];
        if (c == '"') {
            *equal = eq && key[k] == '\0';
            *p = i + 1;
            return true;
        }
        if (c != '\\') {
            bytes[0] = (unsigned char)c;
            i++;
        } else {
            if (i + 1 >= len)
                return false;
            char e = t[i + 1];
            i += 2;
            switch (e) {
            case 'b': bytes[0] = '\b'; break;
            case 'f': bytes[0] = '\f'; break;
            case 'n': bytes[0] = '\n'; break;
            case 'r': bytes[0] = '\r'; break;
            case 't': bytes[0] = '\t'; break;
            case 'u': {
                int32_t cp = read_hex4(t, len, i);
                if (cp < 0) {
                    eq = false; /* malformed: cannot equal anything; keep scanning */
                    continue;
                }
                i += 4;
                /* A UTF-16 surrogate pair spells one code point above U+FFFF. */
                if (cp >= 0xD800 && cp <= 0xDBFF && i + 1 < len && t[i] == '\\' &&
                    t[i + 1] == 'u') {
                    int32_t lo = read_hex4(t, len, i + 2);
                    if (lo >= 0xDC00 && lo <= 0xDFFF) {
                        cp = 0x10000 + ((cp - 0xD800) << 10) + (lo - 0xDC00);
                        i += 6;
                    }
                }
                n = utf8_encode((uint32_t)cp, bytes);
                break;
            }
            default: bytes[0] = (unsigned char)e; break; /* \" \\ \/ */
            }
        }
        /* Compare byte by byte; never step past key's terminator (a decoded NUL must not
         * "match" it and walk off the end). */
        for (int b = 0; b < n && eq; b++) {
            if (key[k] == '\0' || (unsigned char)key[k] != bytes[b])
                eq = false;
            else
                k++;
        }
    }
    return false;
}

/* *p at '{'. On success *p is at the member's value and *key_pos at its key's quote. */
static bool find_member(const char *t, size_t len, size_t *p, const char *key, size_t *key_pos)
{
    size_t i = *p + 1;
    for (;;) {
        skip_ws(t, len, &i);
        if (i >= len || t[i] != '"')
            return false; /* '}' (not found) or not JSON */
        size_t kpos = i;
        bool equal = false;
        if (!match_string(t, len, &i, key, &equal))
            return false;
        skip_ws(t, len, &i);
        if (i >= len || t[i] != ':')
            return false;
        i++;
        skip_ws(t, len, &i);
        if (equal) {
            *p = i;
            *key_pos = kpos;
            return true;
        }
        if (!skip_value(t, len, &i))
            return false;
        skip_ws(t, len, &i);
        if (i >= len || t[i] != ',')
            return false;
        i++;
    }
}

/* *p at '['. On success *p is at element `index`. */
static bool find_element(const char *t, size_t len, size_t *p, size_t index)
{
    size_t i = *p + 1;
    for (size_t n = 0;; n++) {
        skip_ws(t, len, &i);
        if (i >= len || t[i] == ']')
            return false;
        if (n == index) {
            *p = i;
            return true;
        }
        if (!skip_value(t, len, &i))
            return false;
        skip_ws(t, len, &i);
        if (i >= len || t[i] != ',')
            return false;
        i++;
    }
}

bool json_locate(const char *text, size_t len, const JsonPathStep *path, int depth,
                 JsonLocateTarget target, JsonLocation *out)
{
    if (!text || !out || depth < 0 || (depth > 0 && !path))
        return false;
    if (target == JSON_LOCATE_KEY && (depth == 0 || !path[depth - 1].key))
        return false;
    size_t p = 0, key_pos = 0;
    /* No byte-order-mark skipping: jansson rejects a BOM, so validated text never has one. */
    skip_ws(text, len, &p);
    for (int d = 0; d < depth; d++) {
        if (p >= len)
            return false;
        if (path[d].key) {
            if (text[p] != '{' || !find_member(text, len, &p, path[d].key, &key_pos))
                return false;
        } else {
            if (text[p] != '[' || !find_element(text, len, &p, path[d].index))
                return false;
        }
    }
    if (p >= len)
        return false;
    *out = json_offset_location(text, len, target == JSON_LOCATE_KEY ? key_pos : p);
    return true;
}

JsonLocation json_offset_location(const char *text, size_t len, size_t offset)
{
    JsonLocation loc = {1, 1};
    if (!text)
        return loc;
    if (offset > len)
        offset = len;
    for (size_t i = 0; i < offset; i++) {
        unsigned char c = (unsigned char)text[i];
        /* Saturate rather than overflow on multi-gigabyte text. */
        if (c == '\n') {
            if (loc.line < INT_MAX)
                loc.line++;
            loc.column = 1;
        } else if ((c & 0xC0) != 0x80 && loc.column < INT_MAX) {
            loc.column++; /* continuation bytes do not start a code point */
        }
    }
    return loc;
}
