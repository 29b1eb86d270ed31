/* Typed parameter lists of the pbrt format ("float fov" [45]): parsing, type and count
 * checks, lookups with defaults, and warnings for parameters no directive used. */
#include "scene/pbrt/pbrt_params.h"

#include <float.h>
#include <limits.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>


static const char *const PTYPE_NAMES[] = {"integer", "float", "point2", "vector2", "point3",
                                          "vector3", "normal", "rgb", "spectrum", "blackbody",
                                          "bool", "string", "texture", "xyz"};

void pbrt_params_free(Params *ps)
{
    for (int i = 0; i < ps->n; i++) {
        Param *p = &ps->v[i];
        free(p->name);
        free(p->decl);
        free(p->nums);
        for (int k = 0; k < p->num_strs; k++)
            free(p->strs[k]);
        free(p->strs);
    }
    free(ps->v);
    memset(ps, 0, sizeof *ps);
}

static int ptype_from_name(const char *s, PType *out)
{
    for (int i = 0; i < (int)(sizeof PTYPE_NAMES / sizeof PTYPE_NAMES[0]); i++)
        if (strcmp(s, PTYPE_NAMES[i]) == 0) {
            *out = (PType)i;
            return 1;
        }
    /* pbrt-v3 spellings */
    static const struct { const char *name; PType t; } alias[] = {
        {"point", PT_POINT3}, {"vector", PT_VECTOR3}, {"normal3", PT_NORMAL}, {"color", PT_RGB}};
    for (int i = 0; i < 4; i++)
        if (strcmp(s, alias[i].name) == 0) {
            *out = alias[i].t;
            return 1;
        }
    return 0;
}

/* Splits "type name" (any whitespace around and between) into its two words. */
static int split_decl(const char *d, char *type, size_t type_cap, char *name, size_t name_cap)
{
    const char *p = d;
    size_t n;
    while (*p == ' ' || *p == '\t') p++;
    for (n = 0; p[n] && p[n] != ' ' && p[n] != '\t'; n++) {}
    if (n == 0 || n >= type_cap) return 0;
    memcpy(type, p, n);
    type[n] = '\0';
    p += n;
    while (*p == ' ' || *p == '\t') p++;
    for (n = 0; p[n] && p[n] != ' ' && p[n] != '\t'; n++) {}
    if (n == 0 || n >= name_cap) return 0;
    memcpy(name, p, n);
    name[n] = '\0';
    p += n;
    while (*p == ' ' || *p == '\t') p++;
    return *p == '\0';
}

static CstStatus param_add_num(Loader *ld, Param *p, int *cap, double v)
{
    if (!pbrt_grow((void **)&p->nums, cap, p->num_nums + 1, sizeof *p->nums))
        return pbrt_oom(ld);
    p->nums[p->num_nums++] = v;
    return CST_OK;
}

static CstStatus param_add_str(Loader *ld, Param *p, int *cap, const PbrtToken *t)
{
    if (!pbrt_grow((void **)&p->strs, cap, p->num_strs + 1, sizeof *p->strs))
        return pbrt_oom(ld);
    char *s = pbrt_token_string(t);
    if (!s)
        return pbrt_oom(ld);
    p->strs[p->num_strs++] = s;
    return CST_OK;
}

/* One value token into p: numbers, strings, and the bare words true/false for bools. */
static CstStatus param_value(Loader *ld, Param *p, int *cap_n, int *cap_s, const PbrtToken *t,
                             int *ok)
{
    *ok = 1;
    if (t->kind == PBRT_TOK_NUMBER)
        return param_add_num(ld, p, cap_n, t->number);
    if (t->kind == PBRT_TOK_STRING)
        return param_add_str(ld, p, cap_s, t);
    if (t->kind == PBRT_TOK_WORD && (pbrt_tok_is(t, "true") || pbrt_tok_is(t, "false")) && p->type == PT_BOOL)
        return param_add_str(ld, p, cap_s, t);
    *ok = 0;
    return CST_OK;
}

/* Checks values against the declared type once the list is complete. */
static CstStatus param_check(Loader *ld, Param *p)
{
    char nm[72];
    if (p->num_nums == 0 && p->num_strs == 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has no values; expected at least one",
                            pbrt_clip(p->decl, nm));
    if (p->num_nums > 0 && p->num_strs > 0)
        return pbrt_fail_at(ld, CST_ERR_PARSE, p->loc,
                            "parameter \"%s\" mixes numbers and strings; expected values of one kind",
                            pbrt_clip(p->decl, nm));
    int n = p->num_nums;
    switch (p->type) {
    case PT_STRING:
    case PT_TEXTURE:
        if (p->num_strs == 0)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has numbers; expected quoted strings",
                                pbrt_clip(p->decl, nm));
        return CST_OK;
    case PT_BOOL:
        if (p->num_strs == 0)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                                "parameter \"%s\" has numbers; expected true or false", pbrt_clip(p->decl, nm));
        for (int i = 0; i < p->num_strs; i++) {
            int v = strcmp(p->strs[i], "true") == 0 ? 1 : (strcmp(p->strs[i], "false") == 0 ? 0 : -1);
            char val[72];
            if (v < 0)
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                                    "parameter \"%s\" has the value \"%s\"; expected true or false",
                                    pbrt_clip(p->decl, nm), pbrt_clip(p->strs[i], val));
            int cap = p->num_nums;
            TRY(param_add_num(ld, p, &cap, v));
        }
        return CST_OK;
    case PT_SPECTRUM:
        if (p->num_strs > 1)
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                           "parameter \"%s\" has %d strings; expected one spectrum name or "
                                "(wavelength, value) pairs", pbrt_clip(p->decl, nm), p->num_strs);
        if (p->num_strs == 0 && (n % 2 != 0))
            return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                                "parameter \"%s\" has %d numbers; expected (wavelength, value) pairs",
                                pbrt_clip(p->decl, nm), n);
        return CST_OK;
    default: break;
    }
    if (p->num_strs > 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has strings; expected numbers",
                            pbrt_clip(p->decl, nm));
    int per = 1, exact = 0;
    switch (p->type) {
    case PT_POINT2: case PT_VECTOR2: per = 2; break;
    case PT_POINT3: case PT_VECTOR3: case PT_NORMAL: per = 3; break;
    case PT_RGB: case PT_XYZ: exact = 3; break;
    case PT_BLACKBODY: if (n > 2) exact = 1; break; /* v4: kelvin; v3: kelvin, scale */
    default: break;
    }
    if ((exact && n != exact) || n % per != 0)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "parameter \"%s\" has %d numbers; expected %s %d",
                            pbrt_clip(p->decl, nm), n, exact ? "exactly" : "a multiple of", exact ? exact : per);
    if (p->type == PT_INTEGER)
        for (int i = 0; i < n; i++)
            if (p->nums[i] != floor(p->nums[i]) || fabs(p->nums[i]) > (double)INT_MAX)
                return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                               "parameter \"%s\": value %g is not an integer; expected whole "
                                    "numbers within +-%d", pbrt_clip(p->decl, nm), p->nums[i], INT_MAX);
    return CST_OK;
}

/* Reads "type name" value pairs while the next token is a string. */
CstStatus pbrt_parse_params(Loader *ld, Lexer *lx, Params *ps)
{
    for (;;) {
        PbrtToken t;
        TRY(pbrt_lex_peek(ld, lx, &t));
        if (t.kind != PBRT_TOK_STRING)
            return CST_OK;
        TRY(pbrt_lex_next(ld, lx, &t));
        Loc loc = pbrt_tok_loc(lx, &t);
        char *decl = pbrt_token_string(&t);
        if (!decl)
            return pbrt_oom(ld);
        char tname[64], pname[256], nm[72];
        PType type;
        if (!split_decl(decl, tname, sizeof tname, pname, sizeof pname)) {
            CstStatus st = pbrt_fail_at(ld, CST_ERR_PARSE, loc,
                                   "\"%s\" is not a parameter declaration; expected \"type name\", "
                                        "as in \"float fov\"", pbrt_clip(decl, nm));
            free(decl);
            return st;
        }
        if (!ptype_from_name(tname, &type)) {
            CstStatus st = pbrt_fail_at(ld, CST_ERR_PARSE, loc,
                                   "unknown parameter type \"%s\"; expected one of: integer, "
                                   "float, point2, vector2, point3, vector3, normal, rgb, "
                                        "spectrum, blackbody, bool, string, texture", pbrt_clip(tname, nm));
            free(decl);
            return st;
        }
        for (int i = 0; i < ps->n; i++)
            if (strcmp(ps->v[i].name, pname) == 0) {
                /* pbrt-v4 takes the last one (its ParameterDictionary looks the list up
                 * from the end), silently; we say so. */
                Loc first = ps->v[i].loc;
                pbrt_warn_at(ld, CST_WARN_PARAMETER_IGNORED, loc, "parameter \"%s\" given twice: "
                             "this one is used, the one at %.200s:%d:%d is ignored (as pbrt-v4 "
                             "does)", pbrt_clip(pname, nm), first.file, first.line, first.col);
                Param *old = &ps->v[i];
                free(old->name);
                free(old->decl);
                free(old->nums);
                for (int k = 0; k < old->num_strs; k++) free(old->strs[k]);
                free(old->strs);
                memmove(old, old + 1, (size_t)(ps->n - i - 1) * sizeof *ps->v);
                ps->n--;
                break;
            }
        if (!GROW(ps->v, ps->cap, ps->n + 1)) {
            free(decl);
            return pbrt_oom(ld);
        }
        Param *p = &ps->v[ps->n++];
        memset(p, 0, sizeof *p);
        p->type = type;
        p->decl = decl;
        p->loc = loc;
        p->name = pbrt_dup_str(pname);
        if (!p->name)
            return pbrt_oom(ld);
        int cap_n = 0, cap_s = 0, ok = 0;
        TRY(pbrt_lex_next(ld, lx, &t));
        if (t.kind == PBRT_TOK_LBRACKET) {
            Loc open = pbrt_tok_loc(lx, &t);
            for (;;) {
                TRY(pbrt_lex_next(ld, lx, &t));
                if (t.kind == PBRT_TOK_RBRACKET)
                    break;
                TRY(param_value(ld, p, &cap_n, &cap_s, &t, &ok));
                if (!ok) {
                    char got[96];
                    pbrt_token_describe(&t, got, sizeof got);
                    if (t.kind == PBRT_TOK_EOF || t.kind == PBRT_TOK_WORD)
                        return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t),
                                       "got %s inside the values of \"%s\"; expected ']' to "
                                            "close the '[' at %.200s:%d:%d", got, pbrt_clip(decl, nm),
                                            open.file, open.line, open.col);
                    return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t),
                                   "got %s inside the values of \"%s\"; expected numbers, "
                                        "strings or ']'", got, pbrt_clip(decl, nm));
                }
            }
        } else {
            TRY(param_value(ld, p, &cap_n, &cap_s, &t, &ok));
            if (!ok) {
                char got[96];
                pbrt_token_describe(&t, got, sizeof got);
                return pbrt_fail_at(ld, CST_ERR_PARSE, pbrt_tok_loc(lx, &t),
                               "got %s after \"%s\"; expected its value: a number, a string "
                                    "or '[' values ']'", got, pbrt_clip(decl, nm));
            }
        }
        TRY(param_check(ld, p));
    }
}

/* Warns about every parameter no getter asked for. */
void pbrt_params_warn_unused(Loader *ld, const Params *ps, const char *directive)
{
    for (int i = 0; i < ps->n; i++)
        if (!ps->v[i].used) {
            char nm[72];
            pbrt_warn_at(ld, CST_WARN_PARAMETER_IGNORED, ps->v[i].loc,
                         "%s: parameter \"%s\" is not supported; ignored", directive,
                         pbrt_clip(ps->v[i].decl, nm));
        }
}

void pbrt_params_mark_all_used(Params *ps)
{
    for (int i = 0; i < ps->n; i++)
        ps->v[i].used = 1;
}

Param *pbrt_find_param(Params *ps, const char *name)
{
    for (int i = 0; i < ps->n; i++)
        if (strcmp(ps->v[i].name, name) == 0)
            return &ps->v[i];
    return NULL;
}

/* The parameter called name if it has one of the allowed types (a mask of 1 << PType);
 * a parameter of that name and another type is an error (pbrt would leave it unused). */
CstStatus pbrt_lookup(Loader *ld, Params *ps, const char *directive, const char *name,
                      unsigned allowed, const char *expected, Param **out)
{
    *out = NULL;
    Param *p = pbrt_find_param(ps, name);
    if (!p)
        return CST_OK;
    p->used = 1;
    if (!(allowed & (1u << p->type))) {
        char nm[72];
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc,
                            "%s: parameter \"%s\" has type %s; expected %s", directive,
                            pbrt_clip(p->decl, nm), PTYPE_NAMES[p->type], expected);
    }
    *out = p;
    return CST_OK;
}

CstStatus pbrt_one_value(Loader *ld, const Param *p, const char *directive)
{
    int n = p->num_strs ? p->num_strs : p->num_nums;
    if (p->type == PT_BOOL)
        n = p->num_strs;
    char nm[72];
    if (n != 1)
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: parameter \"%s\" has %d values; expected one",
                            directive, pbrt_clip(p->decl, nm), n);
    return CST_OK;
}

CstStatus pbrt_get_float(Loader *ld, Params *ps, const char *d, const char *name, float def,
                         float *out, int *found)
{
    Param *p;
    *out = def;
    if (found) *found = 0;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_FLOAT), "float", &p));
    if (!p) return CST_OK;
    TRY(pbrt_one_value(ld, p, d));
    if (!(fabs(p->nums[0]) <= (double)FLT_MAX)) {
        char nm[72];
        return pbrt_fail_at(ld, CST_ERR_INVALID_ARG, p->loc, "%s: \"%s\" %g does not fit a 32-bit float",
                            d, pbrt_clip(p->decl, nm), p->nums[0]);
    }
    *out = (float)p->nums[0];
    if (found) *found = 1;
    return CST_OK;
}

CstStatus pbrt_get_int(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out)
{
    Param *p;
    *out = def;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_INTEGER), "integer", &p));
    if (!p) return CST_OK;
    TRY(pbrt_one_value(ld, p, d));
    *out = (int)p->nums[0];
    return CST_OK;
}

CstStatus pbrt_get_bool(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out)
{
    Param *p;
    *out = def;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_BOOL), "bool", &p));
    if (!p) return CST_OK;
    TRY(pbrt_one_value(ld, p, d));
    *out = p->nums[0] != 0.0;
    return CST_OK;
}

CstStatus pbrt_get_string(Loader *ld, Params *ps, const char *d, const char *name,
                          const char **out, Loc *loc)
{
    Param *p;
    *out = NULL;
    TRY(pbrt_lookup(ld, ps, d, name, PT_MASK(PT_STRING), "string", &p));
    if (!p) return CST_OK;
    TRY(pbrt_one_value(ld, p, d));
    *out = p->strs[0];
    if (loc) *loc = p->loc;
    return CST_OK;
}
