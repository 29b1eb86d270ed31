/* The pbrt tokenizer: splits scene text into tokens and locates each one. Comments run
 * from '#' to the end of the line; strings may not span lines (pbrt rejects that too,
 * and it catches a missing closing quote at the line where it happened). */
#include "scene/pbrt/pbrt_tokenizer.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"

/* Longest number we accept: pbrt files print floats with at most ~20 characters; the bound
 * lets strtod work on a NUL-terminated copy on the stack. */
#define PBRT_MAX_NUMBER_LEN 64

void pbrt_tokenizer_init(PbrtTokenizer *tz, const char *text, size_t len, const char *name)
{
    tz->text = text ? text : "";
    tz->len = text ? len : 0;
    /* A UTF-8 byte order mark (some Windows editors write one) is skipped: pbrt-v4 would
     * read it as part of the first directive's name. Columns count from after it. */
    if (tz->len >= 3 && memcmp(tz->text, "\xEF\xBB\xBF", 3) == 0) {
        tz->text += 3;
        tz->len -= 3;
    }
    tz->pos = 0;
    tz->line = 1;
    tz->column = 1;
    tz->name = name ? name : "<string>";
}

/* Advances one byte, keeping line and code-point column. */
static void advance(PbrtTokenizer *tz)
{
    unsigned char c = (unsigned char)tz->text[tz->pos++];
    if (c == '\n') {
        tz->line++;
        tz->column = 1;
    } else if ((c & 0xC0) != 0x80) {
        tz->column++;
    }
}

static int is_word_start(int c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || c == '_'; }
static int is_word_char(int c) { return is_word_start(c) || (c >= '0' && c <= '9'); }
static int is_number_char(int c)
{
    return (c >= '0' && c <= '9') || c == '.' || c == '-' || c == '+' || c == 'e' || c == 'E';
}
static int is_delimiter(int c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v' || c == '[' ||
           c == ']' || c == '"' || c == '#';
}

static CstStatus lex_error(const PbrtTokenizer *tz, int line, int col, CstError *err,
                           const char *what)
{
    return cst_fail(err, CST_ERR_PARSE, "%.200s:%d:%d: %s", tz->name, line, col, what);
}

CstStatus pbrt_next_token(PbrtTokenizer *tz, PbrtToken *tok, CstError *err)
{
    memset(tok, 0, sizeof *tok);
    for (;;) {
        while (tz->pos < tz->len && strchr(" \t\n\r\f\v", tz->text[tz->pos]) && tz->text[tz->pos])
            advance(tz);
        if (tz->pos < tz->len && tz->text[tz->pos] == '#') {
            while (tz->pos < tz->len && tz->text[tz->pos] != '\n')
                advance(tz);
            continue;
        }
        break;
    }
    tok->line = tz->line;
    tok->column = tz->column;
    tok->file = tz->name;
    tok->text = tz->text + tz->pos;
    if (tz->pos >= tz->len) {
        tok->kind = PBRT_TOK_EOF;
        return CST_OK;
    }
    unsigned char c = (unsigned char)tz->text[tz->pos];
    if (tz->pos == 0 && tz->len >= 2 && (c == 0xFF || c == 0xFE) && (unsigned char)tz->text[1] == (c ^ 0x01))
        return lex_error(tz, 1, 1, err, "the file is UTF-16 (it starts with a UTF-16 byte order mark); "
                         "expected UTF-8 or ASCII (pbrt-v4 rejects UTF-16 too)");
    if (c == '[' || c == ']') {
        tok->kind = c == '[' ? PBRT_TOK_LBRACKET : PBRT_TOK_RBRACKET;
        tok->len = 1;
        advance(tz);
        return CST_OK;
    }
    if (c == '"') {
        advance(tz);
        size_t start = tz->pos;
        for (;;) {
            if (tz->pos >= tz->len || tz->text[tz->pos] == '\n')
                return lex_error(tz, tok->line, tok->column, err,
                                 "unterminated string; expected a closing '\"' on the same line");
            char s = tz->text[tz->pos];
            if (s == '\0')
                return lex_error(tz, tz->line, tz->column, err,
                                 "NUL byte in a string; expected text");
            if (s == '"')
                break;
            if (s == '\\') {
                int el = tz->line, ec = tz->column;
                advance(tz);
                if (tz->pos >= tz->len || !strchr("btnfr\\'\"", tz->text[tz->pos]) ||
                    tz->text[tz->pos] == '\0')
                    return lex_error(tz, el, ec, err,
                                     "unknown escape in a string; expected one of \\\" \\\\ \\' "
                                     "\\b \\f \\n \\r \\t");
            }
            advance(tz);
        }
        tok->kind = PBRT_TOK_STRING;
        tok->text = tz->text + start;
        tok->len = tz->pos - start;
        advance(tz); /* the closing quote */
        return CST_OK;
    }
    if (is_word_start(c)) {
        size_t start = tz->pos;
        while (tz->pos < tz->len && is_word_char((unsigned char)tz->text[tz->pos]))
            advance(tz);
        tok->kind = PBRT_TOK_WORD;
        tok->len = tz->pos - start;
        if (tz->pos < tz->len && !is_delimiter((unsigned char)tz->text[tz->pos]))
            return lex_error(tz, tz->line, tz->column, err,
                             "unexpected character after a word; expected a space, '[', ']' "
                             "or '\"'");
        return CST_OK;
    }
    if (is_number_char(c)) {
        size_t start = tz->pos;
        while (tz->pos < tz->len && !is_delimiter((unsigned char)tz->text[tz->pos]) &&
               tz->text[tz->pos] != '\0')
            advance(tz);
        size_t n = tz->pos - start;
        char buf[PBRT_MAX_NUMBER_LEN + 1];
        int ok = n <= PBRT_MAX_NUMBER_LEN;
        for (size_t i = 0; ok && i < n; i++)
            ok = is_number_char((unsigned char)tz->text[start + i]);
        if (ok) {
            memcpy(buf, tz->text + start, n);
            buf[n] = '\0';
            char *end = NULL;
            /* strtod after the character check: no "inf", "nan" or hex forms get through. */
            tok->number = strtod(buf, &end);
            ok = end == buf + n && n > 0;
            if (ok && !isfinite(tok->number))
                return lex_error(tz, tok->line, tok->column, err,
                                 "number out of range; expected a finite number");
        }
        if (!ok)
            return lex_error(tz, tok->line, tok->column, err,
                             "malformed number; expected digits with an optional sign, '.' "
                             "and exponent, as in -1.5e3");
        tok->kind = PBRT_TOK_NUMBER;
        tok->len = n;
        return CST_OK;
    }
    if (c == '\0')
        return lex_error(tz, tz->line, tz->column, err, "NUL byte; expected scene text");
    char what[160];
    if (c >= 0x20 && c < 0x7f)
        snprintf(what, sizeof what,
                 "unexpected character '%c'; expected a directive, a quoted string, a number, "
                 "'[' or ']'", c);
    else
        snprintf(what, sizeof what,
                 "unexpected byte 0x%02x; expected a directive, a quoted string, a number, "
                 "'[' or ']'", c);
    return lex_error(tz, tz->line, tz->column, err, what);
}

char *pbrt_token_string(const PbrtToken *tok)
{
    char *s = malloc(tok->len + 1);
    if (!s)
        return NULL;
    size_t o = 0;
    for (size_t i = 0; i < tok->len; i++) {
        char c = tok->text[i];
        if (c == '\\' && i + 1 < tok->len) {
            c = tok->text[++i];
            switch (c) {
            case 'b': c = '\b'; break;
            case 'f': c = '\f'; break;
            case 'n': c = '\n'; break;
            case 'r': c = '\r'; break;
            case 't': c = '\t'; break;
            default: break; /* \\ \' \" stand for themselves */
            }
        }
        s[o++] = c;
    }
    s[o] = '\0';
    return s;
}

void pbrt_token_describe(const PbrtToken *tok, char *buf, size_t cap)
{
    size_t n = tok->len > 40 ? 40 : tok->len;
    char clip[48];
    for (size_t i = 0; i < n; i++) {
        unsigned char c = (unsigned char)tok->text[i];
        clip[i] = c < 0x20 || c == 0x7f ? '?' : (char)c;
    }
    clip[n] = '\0';
    const char *more = tok->len > n ? "..." : "";
    switch (tok->kind) {
    case PBRT_TOK_EOF: snprintf(buf, cap, "the end of the file"); break;
    case PBRT_TOK_WORD: snprintf(buf, cap, "the word %s%s", clip, more); break;
    case PBRT_TOK_STRING: snprintf(buf, cap, "the string \"%s%s\"", clip, more); break;
    case PBRT_TOK_NUMBER: snprintf(buf, cap, "the number %s%s", clip, more); break;
    case PBRT_TOK_LBRACKET: snprintf(buf, cap, "'['"); break;
    case PBRT_TOK_RBRACKET: snprintf(buf, cap, "']'"); break;
    }
}
