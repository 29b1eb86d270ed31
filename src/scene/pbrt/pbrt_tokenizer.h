/* Tokens of the pbrt scene format (pbrt-v3 and pbrt-v4 share the lexical syntax): words,
 * quoted strings, numbers and brackets, each with its 1-based line and column. */
#ifndef CST_SCENE_PBRT_PBRT_TOKENIZER_H
#define CST_SCENE_PBRT_PBRT_TOKENIZER_H

#include <stddef.h>

#include "caustic/caustic.h"

typedef enum PbrtTokenKind {
    PBRT_TOK_EOF,
    PBRT_TOK_WORD,     /* a bare identifier: a directive, or true/false */
    PBRT_TOK_STRING,   /* "..." ; text/len exclude the quotes, escapes still raw */
    PBRT_TOK_NUMBER,   /* number holds the value */
    PBRT_TOK_LBRACKET, /* [ */
    PBRT_TOK_RBRACKET  /* ] */
} PbrtTokenKind;

typedef struct PbrtToken {
    PbrtTokenKind kind;
    const char *text; /* into the tokenizer's buffer; not NUL-terminated */
    size_t len;
    int line, column; /* of the token's first character, 1-based; columns count code points */
    const char *file; /* the tokenizer's name: the file the token is in */
    double number;
} PbrtToken;

/* Borrows text (len bytes, NUL bytes rejected as errors) and name for its lifetime. */
typedef struct PbrtTokenizer {
    const char *text;
    size_t len, pos;
    int line, column;
    const char *name; /* the file name in messages */
} PbrtTokenizer;

void pbrt_tokenizer_init(PbrtTokenizer *tz, const char *text, size_t len, const char *name);
/* The next token; at the end, PBRT_TOK_EOF forever. Lexical errors are CST_ERR_PARSE with
 * "name:line:column: what; expected what". */
CstStatus pbrt_next_token(PbrtTokenizer *tz, PbrtToken *tok, CstError *err);
/* A string token's value with escapes decoded, as a new NUL-terminated string (free());
 * NULL on OOM. The tokenizer has already checked the escapes. */
char *pbrt_token_string(const PbrtToken *tok);
/* Short, printable description of a token for messages ("the number 3", "\"Shape\""...). */
void pbrt_token_describe(const PbrtToken *tok, char *buf, size_t cap);

#endif
