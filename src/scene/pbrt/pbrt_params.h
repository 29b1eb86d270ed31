/* Typed parameter lists of the pbrt format ("float fov" [45]): parsing, type and count
 * checks, lookups with defaults, and warnings for parameters no directive used. */
#ifndef CST_SCENE_PBRT_PBRT_PARAMS_H
#define CST_SCENE_PBRT_PBRT_PARAMS_H

#include <stdbool.h>

#include "scene/pbrt/pbrt_loader.h"

/* Frees the parameters and their values; *ps may be reused. */
void pbrt_params_free(Params *ps);

/* Reads "type name" value pairs while the next token is a string. */
CstStatus pbrt_parse_params(Loader *ld, Lexer *lx, Params *ps);

/* Warns about every parameter no getter asked for. */
void pbrt_params_warn_unused(Loader *ld, const Params *ps, const char *directive);

/* For directives that ignore their parameters as a whole (already warned about). */
void pbrt_params_mark_all_used(Params *ps);

/* The parameter called name, or NULL; does not mark it used. */
Param *pbrt_find_param(Params *ps, const char *name);

/* The parameter called name if it has one of the allowed types (a mask of 1 << PType);
 * a parameter of that name and another type is an error (pbrt would leave it unused). */
CstStatus pbrt_lookup(Loader *ld, Params *ps, const char *directive, const char *name,
                      unsigned allowed, const char *expected, Param **out);

/* A located error unless p holds exactly one value. */
CstStatus pbrt_one_value(Loader *ld, const Param *p, const char *directive);

/* A set of parameter types, as pbrt_lookup takes them. */
#define PT_MASK(t) (1u << (t))

/* Typed getters: *out = the parameter's single value, or def when it is absent; *found
 * (when not NULL) says which. A wrong type or count is a located error. */
CstStatus pbrt_get_float(Loader *ld, Params *ps, const char *d, const char *name, float def,
                         float *out, int *found);

CstStatus pbrt_get_int(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out);

CstStatus pbrt_get_bool(Loader *ld, Params *ps, const char *d, const char *name, int def, int *out);

CstStatus pbrt_get_string(Loader *ld, Params *ps, const char *d, const char *name,
                          const char **out, Loc *loc);

#endif
