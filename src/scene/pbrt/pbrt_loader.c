/* The pbrt loader's shared state (Loader: the graphics state and its stack, named materials,
 * textures, coordinate systems and objects, the camera) and what every directive uses:
 * located errors and warnings, the lexer with one token of lookahead, file names. */
#include "scene/pbrt/pbrt_loader.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "core/array.h"
#include "core/error.h"
#include "io/path.h"
#include "scene/pbrt/pbrt_shape.h"

int pbrt_grow(void **arr, int *cap, int need, size_t size)
{
    /* core/array.h's growth rule; the parameter lists count with ints, so bounded below
     * INT_MAX / 2 as well. */
    if (need <= *cap)
        return 1;
    if (need > INT_MAX / 2)
        return 0;
    size_t c = (size_t)*cap;
    if (!array_grow(arr, &c, (size_t)need, size))
        return 0;
    *cap = c > INT_MAX ? INT_MAX : (int)c;
    return 1;
}

char *pbrt_dup_str(const char *s)
{
    size_t n = strlen(s) + 1;
    char *d = malloc(n);
    if (d)
        memcpy(d, s, n);
    return d;
}

/* A name from the file, printable and short enough to quote. */
const char *pbrt_clip(const char *s, char buf[72])
{
    size_t i = 0;
    for (; s[i] && i < 60; i++)
        buf[i] = ((unsigned char)s[i] < 0x20 || s[i] == 0x7f) ? '?' : s[i];
    buf[i] = '\0';
    if (s[i])
        memcpy(buf + i, "...", 4);
    return buf;
}

CstStatus pbrt_fail_at(Loader *ld, CstStatus st, Loc loc, const char *fmt, ...)
{
    char what[800];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return cst_fail(ld->err, st, "%.200s:%d:%d: %s", loc.file, loc.line, loc.col, what);
}

CstStatus pbrt_oom(Loader *ld) { return cst_fail(ld->err, CST_ERR_OOM, "out of memory loading the pbrt scene"); }

void pbrt_warn_at(Loader *ld, CstWarningCode code, Loc loc, const char *fmt, ...)
{
    if (!ld->opt.warning)
        return;
    char what[800], msg[1100];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    snprintf(msg, sizeof msg, "%.200s:%d:%d: %s", loc.file, loc.line, loc.col, what);
    cst_escape_message(msg, sizeof msg); /* as cst_fail does for errors */
    ld->opt.warning(ld->opt.warning_user, code, msg);
}

Loc pbrt_tok_loc(const Lexer *lx, const PbrtToken *t)
{
    Loc l = {t->file ? t->file : lx->tz.name, t->line, t->column};
    return l;
}

int pbrt_tok_is(const PbrtToken *t, const char *word)
{
    size_t n = strlen(word);
    return t->len == n && memcmp(t->text, word, n) == 0;
}

CstStatus pbrt_lex_push(Loader *ld, Lexer *lx, char *text, size_t len, const char *name)
{
    if (!GROW(lx->saved, lx->cap_saved, lx->num_saved + 1)) {
        free(text);
        return pbrt_oom(ld);
    }
    lx->saved[lx->num_saved++] = (LexSaved){lx->tz, lx->text};
    lx->text = text;
    pbrt_tokenizer_init(&lx->tz, text, len, name);
    lx->has_peek = 0; /* callers push between directives, with nothing peeked */
    return CST_OK;
}

void pbrt_lex_free(Lexer *lx)
{
    free(lx->text);
    for (int i = 0; i < lx->num_saved; i++) free(lx->saved[i].text);
    free(lx->saved);
    free(lx->retired);
    memset(lx, 0, sizeof *lx);
}

CstStatus pbrt_lex_peek(Loader *ld, Lexer *lx, PbrtToken *t)
{
    while (!lx->has_peek) {
        TRY(pbrt_next_token(&lx->tz, &lx->peek, ld->err));
        if (lx->peek.kind == PBRT_TOK_EOF && lx->num_saved > 0) {
            /* an included file ends: its includer goes on (pbrt-v4's parser pops its
             * file stack the same way, in the middle of a parameter list too) */
            free(lx->retired);
            lx->retired = lx->text;
            LexSaved sv = lx->saved[--lx->num_saved];
            lx->tz = sv.tz;
            lx->text = sv.text;
            continue;
        }
        lx->has_peek = 1;
    }
    *t = lx->peek;
    return CST_OK;
}

CstStatus pbrt_lex_next(Loader *ld, Lexer *lx, PbrtToken *t)
{
    TRY(pbrt_lex_peek(ld, lx, t));
    lx->has_peek = 0;
    return CST_OK;
}

CstStatus pbrt_expect_string(Loader *ld, Lexer *lx, const char *directive, const char *what,
                             char **out, Loc *loc)
{
    PbrtToken t;
    TRY(pbrt_lex_next(ld, lx, &t));
    if (loc)
        *loc = pbrt_tok_loc(lx, &t);
    if (t.kind != PBRT_TOK_STRING) {
        char got[96];
        pbrt_token_describe(&t, got, sizeof got);
        return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t), "%s: got %s; expected %s, a quoted string",
                            directive, got, what);
    }
    *out = pbrt_token_string(&t);
    return *out ? CST_OK : pbrt_oom(ld);
}

CstStatus pbrt_expect_numbers(Loader *ld, Lexer *lx, const char *directive, int n, double *out)
{
    for (int i = 0; i < n; i++) {
        PbrtToken t;
        TRY(pbrt_lex_next(ld, lx, &t));
        if (t.kind != PBRT_TOK_NUMBER) {
            char got[96];
            pbrt_token_describe(&t, got, sizeof got);
            return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t),
                                "%s: got %s; expected %d numbers (%d given)", directive, got, n, i);
        }
        out[i] = t.number;
    }
    return CST_OK;
}

/* n numbers in brackets; pbrt-v3 files sometimes leave the brackets out. */
CstStatus pbrt_expect_number_array(Loader *ld, Lexer *lx, const char *directive, int n, double *out)
{
    PbrtToken t;
    TRY(pbrt_lex_peek(ld, lx, &t));
    if (t.kind != PBRT_TOK_LBRACKET)
        return pbrt_expect_numbers(ld, lx, directive, n, out);
    Loc open = pbrt_tok_loc(lx, &t);
    TRY(pbrt_lex_next(ld, lx, &t));
    TRY(pbrt_expect_numbers(ld, lx, directive, n, out));
    TRY(pbrt_lex_next(ld, lx, &t));
    if (t.kind != PBRT_TOK_RBRACKET) {
        char got[96];
        pbrt_token_describe(&t, got, sizeof got);
        return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t),
                            "%s: got %s; expected ']' closing the '[' at %d:%d after %d numbers",
                            directive, got, open.line, open.col, n);
    }
    return CST_OK;
}

/* A failure of a library call (mesh import, image read): keep its text, add the location. */
CstStatus pbrt_fail_wrap(Loader *ld, CstStatus st, Loc loc, const char *d)
{
    char msg[sizeof ld->err->msg];
    memcpy(msg, ld->err->msg, sizeof msg);
    msg[sizeof msg - 1] = '\0';
    return pbrt_fail_at(ld, st, loc, "%s: %.700s", d, msg);
}

/* `file` relative to the main scene file's directory (pbrt's search directory). */
char *pbrt_resolve_path(Loader *ld, const char *file)
{
    return path_resolve(ld->base_dir, file);
}

CstStatus pbrt_check_file_access(Loader *ld, Loc loc, const char *d)
{
    if (ld->opt.no_file_access)
        return pbrt_fail_at(ld, CST_ERR_UNSUPPORTED, loc, "%s: file access is disabled for this load "
                            "(CstLoadOptions.no_file_access)", d);
    return CST_OK;
}

void pbrt_loader_free(Loader *ld)
{
    free(ld->env_rgb);
    for (int i = 0; i < ld->num_files; i++) free(ld->files[i]);
    free(ld->files);
    free(ld->stack);
    for (int i = 0; i < ld->num_mats; i++) {
        free(ld->mats[i].name);
        free((char *)(uintptr_t)ld->mats[i].m.measured_file); /* pbrt_material.c's path */
    }
    free(ld->mats);
    for (int i = 0; i < ld->num_meds; i++) free(ld->med_names[i]);
    free(ld->med_names);
    free(ld->med_ids);
    for (int i = 0; i < ld->num_texs; i++) free(ld->texs[i].name);
    free(ld->texs);
    for (int i = 0; i < ld->num_coords; i++) free(ld->coords[i].name);
    free(ld->coords);
    for (int i = 0; i < ld->num_objs; i++) {
        for (int k = 0; k < ld->objs[i].n; k++) pbrt_geom_free(&ld->objs[i].shapes[k].g);
        free(ld->objs[i].shapes);
        free(ld->objs[i].name);
    }
    free(ld->objs);
    free(ld->base_dir);
}
