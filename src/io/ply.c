/* The PLY reader: header, then each element's records in order (ASCII tokens or binary of
 * either byte order), keeping the vertex and face data pbrt-v4 uses and skipping the rest
 * by its declared types. Every count is checked against the bytes left before it is used. */
#include "io/ply.h"

#include <limits.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "core/array.h"
#include "core/error.h"
#include "io/gzip.h"

#define PLY_MAX_ELEMENTS 64
#define PLY_MAX_PROPS 512
#define PLY_MAX_NAME 64

typedef enum PlyType { PT_NONE, PT_I8, PT_U8, PT_I16, PT_U16, PT_I32, PT_U32, PT_F32, PT_F64 } PlyType;

/* What a property is for; ROLE_NONE is read (or jumped over) and dropped. */
typedef enum PlyRole {
    ROLE_NONE, ROLE_X, ROLE_Y, ROLE_Z, ROLE_NX, ROLE_NY, ROLE_NZ, ROLE_U, ROLE_V,
    ROLE_VERTEX_INDICES, ROLE_FACE_INDEX
} PlyRole;

typedef struct PlyProp {
    char name[PLY_MAX_NAME];
    PlyType type;       /* of the value, or of a list's items */
    PlyType count_type; /* PT_NONE for a scalar */
    PlyRole role;
} PlyProp;

typedef struct PlyElem {
    char name[PLY_MAX_NAME];
    uint64_t count;
    int first_prop, num_props;
} PlyElem;

enum { PLY_ASCII, PLY_LE, PLY_BE };

typedef ARRAY(int32_t) I32Array;

typedef struct PlyReader {
    const char *name;
    const unsigned char *d;
    size_t len, pos;
    int format, line; /* line: of the header, then of the ASCII data (1-based) */
    CstError *err;
    PlyElem elems[PLY_MAX_ELEMENTS];
    PlyProp props[PLY_MAX_PROPS];
    int num_elems, num_props;
    int vertex_elem, face_elem;
    /* the record being read, for messages */
    int cur_elem;
    uint64_t cur_record;
    size_t record_start;
    I32Array idx, fidx;
} PlyReader;

static const struct { const char *name; PlyType type; int size; } ply_types[] = {
    {"char", PT_I8, 1},    {"int8", PT_I8, 1},    {"uchar", PT_U8, 1},   {"uint8", PT_U8, 1},
    {"short", PT_I16, 2},  {"int16", PT_I16, 2},  {"ushort", PT_U16, 2}, {"uint16", PT_U16, 2},
    {"int", PT_I32, 4},    {"int32", PT_I32, 4},  {"uint", PT_U32, 4},   {"uint32", PT_U32, 4},
    {"float", PT_F32, 4},  {"float32", PT_F32, 4}, {"double", PT_F64, 8}, {"float64", PT_F64, 8},
};

static PlyType type_from_name(const char *s)
{
    for (size_t i = 0; i < sizeof ply_types / sizeof ply_types[0]; i++)
        if (strcmp(s, ply_types[i].name) == 0) return ply_types[i].type;
    return PT_NONE;
}

static int type_size(PlyType t)
{
    static const int sizes[] = {0, 1, 1, 2, 2, 4, 4, 4, 8};
    return sizes[t];
}

static int type_is_int(PlyType t) { return t != PT_F32 && t != PT_F64; }

/* ------------------------------------------------------------------ messages */

static CstStatus header_fail(PlyReader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static CstStatus header_fail(PlyReader *r, const char *fmt, ...)
{
    char what[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    return cst_fail(r->err, CST_ERR_PARSE, "%.300s:%d: malformed PLY header: %s", r->name, r->line, what);
}

/* An error in the data: ASCII at its line, binary at its byte offset; both name the
 * element and the record. */
static CstStatus data_fail(PlyReader *r, const char *fmt, ...) __attribute__((format(printf, 2, 3)));
static CstStatus data_fail(PlyReader *r, const char *fmt, ...)
{
    char what[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(what, sizeof what, fmt, ap);
    va_end(ap);
    const PlyElem *e = &r->elems[r->cur_elem];
    unsigned long long k = (unsigned long long)r->cur_record + 1, n = (unsigned long long)e->count;
    if (r->format == PLY_ASCII)
        return cst_fail(r->err, CST_ERR_PARSE, "%.300s:%d: malformed PLY data: %s %llu of %llu: %s",
                        r->name, r->line, e->name, k, n, what);
    return cst_fail(r->err, CST_ERR_PARSE, "%.300s: byte %zu: malformed PLY data: %s %llu of %llu "
                    "(starting at byte %zu): %s", r->name, r->pos, e->name, k, n, r->record_start, what);
}

/* ------------------------------------------------------------------ header */

/* Splits line (modified in place) into at most max words separated by blanks. */
static int split_words(char *line, char **w, int max)
{
    int n = 0;
    char *s = line;
    for (;;) {
        while (*s == ' ' || *s == '\t') s++;
        if (!*s) return n;
        if (n == max) return max + 1;
        w[n++] = s;
        while (*s && *s != ' ' && *s != '\t') s++;
        if (*s) *s++ = '\0';
    }
}

static int parse_count(const char *s, uint64_t *out)
{
    if (!*s) return 0;
    uint64_t v = 0;
    for (; *s; s++) {
        if (*s < '0' || *s > '9') return 0;
        if (v > (UINT64_MAX - 9) / 10) return 0;
        v = v * 10 + (uint64_t)(*s - '0');
    }
    *out = v;
    return 1;
}

static CstStatus header_property(PlyReader *r, char **w, int nw)
{
    if (r->num_elems == 0) return header_fail(r, "a property before any element; expected \"element NAME COUNT\" first");
    if (r->num_props == PLY_MAX_PROPS) return header_fail(r, "more than %d properties", PLY_MAX_PROPS);
    PlyProp *p = &r->props[r->num_props];
    memset(p, 0, sizeof *p);
    const char *pname;
    if (nw >= 2 && strcmp(w[1], "list") == 0) {
        if (nw != 5) return header_fail(r, "expected \"property list COUNT_TYPE ITEM_TYPE NAME\"");
        p->count_type = type_from_name(w[2]);
        p->type = type_from_name(w[3]);
        if (p->count_type == PT_NONE || !type_is_int(p->count_type))
            return header_fail(r, "list length type \"%.40s\"; expected an integer type (uchar, int, ...)", w[2]);
        if (p->type == PT_NONE) return header_fail(r, "unknown list item type \"%.40s\"", w[3]);
        pname = w[4];
    } else {
        if (nw != 3) return header_fail(r, "expected \"property TYPE NAME\" or \"property list COUNT_TYPE ITEM_TYPE NAME\"");
        p->type = type_from_name(w[1]);
        if (p->type == PT_NONE)
            return header_fail(r, "unknown property type \"%.40s\"; expected char, uchar, short, "
                               "ushort, int, uint, float, double (or int8 ... float64)", w[1]);
        pname = w[2];
    }
    if (strlen(pname) >= PLY_MAX_NAME) return header_fail(r, "property name longer than %d bytes", PLY_MAX_NAME - 1);
    PlyElem *e = &r->elems[r->num_elems - 1];
    for (int i = 0; i < e->num_props; i++)
        if (strcmp(r->props[e->first_prop + i].name, pname) == 0)
            return header_fail(r, "property \"%s\" declared twice in element \"%s\"", pname, e->name);
    strcpy(p->name, pname);
    e->num_props++;
    r->num_props++;
    return CST_OK;
}

/* One header line (NUL-terminated, without its line end). *done on end_header. */
static CstStatus header_line(PlyReader *r, char *text, int *have_format, int *done)
{
    char *w[8];
    int nw = split_words(text, w, 7);
    if (nw == 0) return CST_OK; /* blank lines: tolerated, as rply does */
    if (strcmp(w[0], "comment") == 0 || strcmp(w[0], "obj_info") == 0) return CST_OK;
    if (nw > 7) return header_fail(r, "too many words on a header line");
    if (strcmp(w[0], "format") == 0) {
        if (*have_format) return header_fail(r, "a second format line");
        if (nw != 3 || strcmp(w[2], "1.0") != 0)
            return header_fail(r, "expected \"format ascii|binary_little_endian|binary_big_endian 1.0\"");
        if (strcmp(w[1], "ascii") == 0) r->format = PLY_ASCII;
        else if (strcmp(w[1], "binary_little_endian") == 0) r->format = PLY_LE;
        else if (strcmp(w[1], "binary_big_endian") == 0) r->format = PLY_BE;
        else return header_fail(r, "unknown format \"%.40s\"; expected ascii, binary_little_endian or binary_big_endian", w[1]);
        *have_format = 1;
        return CST_OK;
    }
    if (!*have_format) return header_fail(r, "expected the format line before \"%.40s\"", w[0]);
    if (strcmp(w[0], "element") == 0) {
        if (nw != 3) return header_fail(r, "expected \"element NAME COUNT\"");
        if (r->num_elems == PLY_MAX_ELEMENTS) return header_fail(r, "more than %d elements", PLY_MAX_ELEMENTS);
        if (strlen(w[1]) >= PLY_MAX_NAME) return header_fail(r, "element name longer than %d bytes", PLY_MAX_NAME - 1);
        for (int i = 0; i < r->num_elems; i++)
            if (strcmp(r->elems[i].name, w[1]) == 0) return header_fail(r, "element \"%s\" declared twice", w[1]);
        PlyElem *e = &r->elems[r->num_elems];
        memset(e, 0, sizeof *e);
        if (!parse_count(w[2], &e->count))
            return header_fail(r, "element count \"%.40s\"; expected a non-negative integer", w[2]);
        strcpy(e->name, w[1]);
        e->first_prop = r->num_props;
        r->num_elems++;
        return CST_OK;
    }
    if (strcmp(w[0], "property") == 0) return header_property(r, w, nw);
    if (strcmp(w[0], "end_header") == 0) {
        if (nw != 1) return header_fail(r, "words after end_header");
        *done = 1;
        return CST_OK;
    }
    return header_fail(r, "unknown line starting \"%.40s\"; expected format, element, property, "
                       "comment or end_header", w[0]);
}

static CstStatus read_header(PlyReader *r)
{
    int have_format = 0, done = 0;
    r->line = 0;
    while (!done) {
        r->line++;
        const unsigned char *nl = r->pos < r->len ? memchr(r->d + r->pos, '\n', r->len - r->pos) : NULL;
        if (!nl) return header_fail(r, "the header has no end_header line");
        size_t n = (size_t)(nl - (r->d + r->pos));
        const unsigned char *s = r->d + r->pos;
        r->pos += n + 1;
        if (n > 0 && s[n - 1] == '\r') n--;
        if (memchr(s, '\0', n)) return header_fail(r, "a NUL byte in the header");
        int comment = (n >= 7 && memcmp(s, "comment", 7) == 0) || (n >= 8 && memcmp(s, "obj_info", 8) == 0);
        if (r->line == 1) {
            if (n != 3 || memcmp(s, "ply", 3) != 0) return header_fail(r, "expected \"ply\" alone on the first line");
            continue;
        }
        if (comment) continue; /* of any length */
        char text[1024];
        if (n >= sizeof text) return header_fail(r, "a header line longer than %zu bytes", sizeof text - 1);
        memcpy(text, s, n);
        text[n] = '\0';
        CstStatus st = header_line(r, text, &have_format, &done);
        if (st != CST_OK) return st;
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ roles */

static int find_prop(const PlyReader *r, int elem, const char *name)
{
    const PlyElem *e = &r->elems[elem];
    for (int i = 0; i < e->num_props; i++)
        if (strcmp(r->props[e->first_prop + i].name, name) == 0) return e->first_prop + i;
    return -1;
}

static int find_scalar(const PlyReader *r, int elem, const char *name)
{
    int p = find_prop(r, elem, name);
    return p >= 0 && r->props[p].count_type == PT_NONE ? p : -1;
}

/* Marks the properties we keep. Texture coordinates: the first of pbrt-v4's four name
 * pairs present with both members. Normals: only all three. */
static CstStatus assign_roles(PlyReader *r, PlyMesh *out)
{
    r->vertex_elem = r->face_elem = -1;
    for (int i = 0; i < r->num_elems; i++) {
        if (strcmp(r->elems[i].name, "vertex") == 0) r->vertex_elem = i;
        if (strcmp(r->elems[i].name, "face") == 0) r->face_elem = i;
    }
    if (r->vertex_elem < 0)
        return cst_fail(r->err, CST_ERR_PARSE, "%.300s: the PLY file has no \"vertex\" element", r->name);
    int ve = r->vertex_elem;
    const char *xyz[3] = {"x", "y", "z"};
    for (int k = 0; k < 3; k++) {
        int p = find_scalar(r, ve, xyz[k]);
        if (p < 0)
            return cst_fail(r->err, CST_ERR_PARSE, "%.300s: the PLY \"vertex\" element has no scalar "
                            "property \"%s\"; expected x, y and z", r->name, xyz[k]);
        r->props[p].role = (PlyRole)(ROLE_X + k);
    }
    int nx = find_scalar(r, ve, "nx"), ny = find_scalar(r, ve, "ny"), nz = find_scalar(r, ve, "nz");
    int has_n = nx >= 0 && ny >= 0 && nz >= 0;
    if (has_n) {
        r->props[nx].role = ROLE_NX;
        r->props[ny].role = ROLE_NY;
        r->props[nz].role = ROLE_NZ;
    }
    static const char *const uv_names[4][2] = {
        {"u", "v"}, {"s", "t"}, {"texture_u", "texture_v"}, {"texture_s", "texture_t"}};
    int has_uv = 0;
    for (int k = 0; k < 4 && !has_uv; k++) {
        int pu = find_scalar(r, ve, uv_names[k][0]), pv = find_scalar(r, ve, uv_names[k][1]);
        if (pu >= 0 && pv >= 0) {
            r->props[pu].role = ROLE_U;
            r->props[pv].role = ROLE_V;
            has_uv = 1;
        }
    }
    uint64_t nv = r->elems[ve].count;
    if (nv > INT_MAX)
        return cst_fail(r->err, CST_ERR_UNSUPPORTED, "%.300s: %llu vertices are too many; expected "
                        "at most %d", r->name, (unsigned long long)nv, INT_MAX);
    if (r->face_elem >= 0) {
        int fe = r->face_elem;
        int p = find_prop(r, fe, "vertex_indices");
        if (p < 0) p = find_prop(r, fe, "vertex_index");
        if (p < 0 || r->props[p].count_type == PT_NONE)
            return cst_fail(r->err, CST_ERR_PARSE, "%.300s: the PLY \"face\" element has no list "
                            "property \"vertex_indices\" (or \"vertex_index\")", r->name);
        r->props[p].role = ROLE_VERTEX_INDICES;
        int fi = find_scalar(r, fe, "face_indices");
        if (fi >= 0) r->props[fi].role = ROLE_FACE_INDEX;
    }
    /* The arrays are allocated by read_body once check_fits has found the records in the
     * data. */
    out->num_vertices = (int)nv;
    return CST_OK;
}

/* ------------------------------------------------------------------ values */

static double binary_value(const unsigned char *p, PlyType t, int big_endian)
{
    unsigned char b[8];
    int n = type_size(t);
    for (int i = 0; i < n; i++) b[i] = big_endian ? p[n - 1 - i] : p[i];
    switch (t) {
    case PT_I8: return (double)(int8_t)b[0];
    case PT_U8: return (double)b[0];
    case PT_I16: { int16_t v; memcpy(&v, b, 2); return (double)v; }
    case PT_U16: { uint16_t v; memcpy(&v, b, 2); return (double)v; }
    case PT_I32: { int32_t v; memcpy(&v, b, 4); return (double)v; }
    case PT_U32: { uint32_t v; memcpy(&v, b, 4); return (double)v; }
    case PT_F32: { float v; memcpy(&v, b, 4); return (double)v; }
    case PT_F64: { double v; memcpy(&v, b, 8); return v; }
    default: return 0.0;
    }
}

/* The next value of type t. ASCII: a whitespace-separated token, an integer for integer
 * types (strtoll, range-checked), any number for float types (strtod). */
static CstStatus next_value(PlyReader *r, PlyType t, double *v)
{
    if (r->format != PLY_ASCII) {
        size_t n = (size_t)type_size(t);
        if (r->len - r->pos < n)
            return data_fail(r, "the file ends inside the record (%zu bytes left, %zu needed); "
                             "the file is truncated or a count is wrong", r->len - r->pos, n);
        *v = binary_value(r->d + r->pos, t, r->format == PLY_BE);
        r->pos += n;
        return CST_OK;
    }
    while (r->pos < r->len) {
        unsigned char c = r->d[r->pos];
        if (c == '\n') r->line++;
        else if (c != ' ' && c != '\t' && c != '\r') break;
        r->pos++;
    }
    if (r->pos == r->len)
        return data_fail(r, "the file ends inside the record; the file is truncated or a count is wrong");
    size_t start = r->pos;
    while (r->pos < r->len && r->d[r->pos] > ' ') r->pos++;
    size_t n = r->pos - start;
    char tok[64];
    if (n >= sizeof tok) return data_fail(r, "a value of %zu characters; expected a number", n);
    memcpy(tok, r->d + start, n);
    tok[n] = '\0';
    char *end = NULL;
    if (type_is_int(t)) {
        long long x = strtoll(tok, &end, 10);
        static const long long lo[] = {0, -128, 0, -32768, 0, INT32_MIN, 0};
        static const long long hi[] = {0, 127, 255, 32767, 65535, INT32_MAX, UINT32_MAX};
        if (*end || end == tok || x < lo[t] || x > hi[t])
            return data_fail(r, "\"%s\"; expected an integer in [%lld, %lld]", tok, lo[t], hi[t]);
        *v = (double)x;
    } else {
        *v = strtod(tok, &end);
        if (*end || end == tok) return data_fail(r, "\"%s\"; expected a number", tok);
    }
    return CST_OK;
}

/* Jumps over n items of type t of a list nobody uses. */
static CstStatus skip_items(PlyReader *r, PlyType t, uint64_t n)
{
    if (r->format != PLY_ASCII) {
        r->pos += (size_t)n * (size_t)type_size(t); /* bounded by the caller's check */
        return CST_OK;
    }
    double v;
    for (uint64_t i = 0; i < n; i++) {
        CstStatus st = next_value(r, t, &v);
        if (st != CST_OK) return st;
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ elements */

/* Fails unless the element's declared records can fit in the bytes left: each binary record
 * is at least its scalars plus its list lengths, each ASCII value at least one byte. */
static CstStatus check_fits(PlyReader *r, int ei)
{
    const PlyElem *e = &r->elems[ei];
    uint64_t min = 0;
    for (int i = 0; i < e->num_props; i++) {
        const PlyProp *p = &r->props[e->first_prop + i];
        min += r->format == PLY_ASCII ? 1 : (uint64_t)type_size(p->count_type != PT_NONE ? p->count_type : p->type);
    }
    size_t left = r->len - r->pos;
    if (min > 0 && e->count > left / min)
        return cst_fail(r->err, CST_ERR_PARSE, "%.300s: byte %zu: malformed PLY data: element \"%s\" declares %llu "
                        "records of at least %llu bytes each, but only %zu bytes are left; the "
                        "file is truncated or the count is wrong", r->name, r->pos, e->name,
                        (unsigned long long)e->count, (unsigned long long)min, left);
    return CST_OK;
}

static CstStatus list_length(PlyReader *r, const PlyProp *p, uint64_t *n)
{
    double c;
    CstStatus st = next_value(r, p->count_type, &c);
    if (st != CST_OK) return st;
    size_t item = r->format == PLY_ASCII ? 1 : (size_t)type_size(p->type);
    size_t left = r->len - r->pos;
    if (c < 0.0 || c > (double)(left / item))
        return data_fail(r, "list \"%s\" of length %.0f, but %zu bytes are left; expected a length "
                         "from 0 to %zu", p->name, c, left, left / item);
    *n = (uint64_t)c;
    return CST_OK;
}

static CstStatus read_vertices(PlyReader *r, PlyMesh *out)
{
    const PlyElem *e = &r->elems[r->vertex_elem];
    for (uint64_t k = 0; k < e->count; k++) {
        r->cur_record = k;
        r->record_start = r->pos;
        float vals[ROLE_V + 1] = {0};
        for (int i = 0; i < e->num_props; i++) {
            const PlyProp *p = &r->props[e->first_prop + i];
            CstStatus st;
            if (p->count_type != PT_NONE) {
                uint64_t n = 0;
                st = list_length(r, p, &n);
                if (st == CST_OK) st = skip_items(r, p->type, n);
            } else {
                double v;
                st = next_value(r, p->type, &v);
                if (p->role != ROLE_NONE && p->role <= ROLE_V) vals[p->role] = (float)v;
            }
            if (st != CST_OK) return st;
        }
        out->positions[k] = v3(vals[ROLE_X], vals[ROLE_Y], vals[ROLE_Z]);
        if (out->normals) out->normals[k] = v3(vals[ROLE_NX], vals[ROLE_NY], vals[ROLE_NZ]);
        if (out->uvs) out->uvs[k] = v2(vals[ROLE_U], vals[ROLE_V]);
    }
    return CST_OK;
}

static CstStatus push_triangle(PlyReader *r, int32_t a, int32_t b, int32_t c, int has_fi, int32_t fi)
{
    if (r->idx.n / 3 >= INT_MAX)
        return cst_fail(r->err, CST_ERR_UNSUPPORTED, "%.300s: more than %d triangles; expected fewer",
                        r->name, INT_MAX);
    if (!array_reserve(&r->idx, r->idx.n + 3) || (has_fi && !array_reserve(&r->fidx, r->fidx.n + 1)))
        return cst_fail(r->err, CST_ERR_OOM, "%.300s: out of memory for %zu triangles", r->name, r->idx.n / 3 + 1);
    r->idx.v[r->idx.n++] = a;
    r->idx.v[r->idx.n++] = b;
    r->idx.v[r->idx.n++] = c;
    if (has_fi) r->fidx.v[r->fidx.n++] = fi;
    return CST_OK;
}

static CstStatus read_faces(PlyReader *r, PlyMesh *out)
{
    const PlyElem *e = &r->elems[r->face_elem];
    int has_fi = 0;
    for (int i = 0; i < e->num_props; i++) has_fi |= r->props[e->first_prop + i].role == ROLE_FACE_INDEX;
    uint64_t nv = (uint64_t)out->num_vertices;
    for (uint64_t k = 0; k < e->count; k++) {
        r->cur_record = k;
        r->record_start = r->pos;
        int32_t v[4] = {0};
        uint64_t nidx = 0;
        int32_t fi = 0;
        for (int i = 0; i < e->num_props; i++) {
            const PlyProp *p = &r->props[e->first_prop + i];
            CstStatus st;
            double x;
            if (p->count_type == PT_NONE) {
                st = next_value(r, p->type, &x);
                if (st == CST_OK && p->role == ROLE_FACE_INDEX) {
                    if (!(x >= INT32_MIN && x <= INT32_MAX && x == floor(x)))
                        return data_fail(r, "face_indices %g; expected an integer", x);
                    fi = (int32_t)x;
                }
            } else if (p->role != ROLE_VERTEX_INDICES) {
                uint64_t n = 0;
                st = list_length(r, p, &n);
                if (st == CST_OK) st = skip_items(r, p->type, n);
            } else {
                st = list_length(r, p, &nidx);
                if (st == CST_OK && nidx != 3 && nidx != 4) {
                    /* pbrt-v4 skips such faces with a warning: so do we (the caller warns) */
                    if (out->num_skipped_faces++ == 0) out->skipped_face_size = nidx > INT_MAX ? INT_MAX : (int)nidx;
                    st = skip_items(r, p->type, nidx);
                }
                for (uint64_t j = 0; st == CST_OK && (nidx == 3 || nidx == 4) && j < nidx; j++) {
                    st = next_value(r, p->type, &x);
                    if (st == CST_OK && !(x >= 0.0 && x < (double)nv && x == floor(x)))
                        return data_fail(r, "vertex index %g (number %llu of the face) is out of "
                                         "range; expected 0 to %llu (there are %llu vertices)", x,
                                         (unsigned long long)j, (unsigned long long)(nv ? nv - 1 : 0),
                                         (unsigned long long)nv);
                    if (st == CST_OK) v[j] = (int32_t)x;
                }
            }
            if (st != CST_OK) return st;
        }
        CstStatus st = CST_OK;
        if (nidx == 3) {
            st = push_triangle(r, v[0], v[1], v[2], has_fi, fi);
        } else if (nidx == 4) {
            /* pbrt-v4 makes the quad a bilinear patch (v0, v1, v3, v2) and, where it needs
             * triangles, splits it into (v0, v1, v2) and (v0, v2, v3): the same side. */
            st = push_triangle(r, v[0], v[1], v[2], has_fi, fi);
            if (st == CST_OK) st = push_triangle(r, v[0], v[2], v[3], has_fi, fi);
            out->num_quads++;
        }
        if (st != CST_OK) return st;
    }
    return CST_OK;
}

static CstStatus skip_element(PlyReader *r, int ei)
{
    const PlyElem *e = &r->elems[ei];
    if (e->num_props == 0) return CST_OK; /* records of no bytes */
    for (uint64_t k = 0; k < e->count; k++) {
        r->cur_record = k;
        r->record_start = r->pos;
        for (int i = 0; i < e->num_props; i++) {
            const PlyProp *p = &r->props[e->first_prop + i];
            uint64_t n = 1;
            CstStatus st = CST_OK;
            if (p->count_type != PT_NONE) st = list_length(r, p, &n);
            if (st == CST_OK && r->format != PLY_ASCII && r->len - r->pos < n * (uint64_t)type_size(p->type))
                st = data_fail(r, "the file ends inside the record; the file is truncated or a count is wrong");
            if (st == CST_OK) st = skip_items(r, p->type, n);
            if (st != CST_OK) return st;
        }
    }
    return CST_OK;
}

static CstStatus read_body(PlyReader *r, PlyMesh *out)
{
    r->line++; /* ASCII data starts on the line after end_header */
    for (int ei = 0; ei < r->num_elems; ei++) {
        r->cur_elem = ei;
        CstStatus st = check_fits(r, ei);
        if (st != CST_OK) return st;
        if (ei == r->vertex_elem) {
            size_t nv = (size_t)out->num_vertices;
            int has_n = 0, has_uv = 0;
            const PlyElem *e = &r->elems[ei];
            for (int i = 0; i < e->num_props; i++) {
                has_n |= r->props[e->first_prop + i].role == ROLE_NX;
                has_uv |= r->props[e->first_prop + i].role == ROLE_U;
            }
            out->positions = malloc((nv ? nv : 1) * sizeof *out->positions);
            if (has_n) out->normals = malloc((nv ? nv : 1) * sizeof *out->normals);
            if (has_uv) out->uvs = malloc((nv ? nv : 1) * sizeof *out->uvs);
            if (!out->positions || (has_n && !out->normals) || (has_uv && !out->uvs))
                return cst_fail(r->err, CST_ERR_OOM, "%.300s: out of memory for %zu vertices", r->name, nv);
            st = read_vertices(r, out);
        } else if (ei == r->face_elem) {
            st = read_faces(r, out);
        } else {
            st = skip_element(r, ei);
        }
        if (st != CST_OK) return st;
    }
    return CST_OK;
}

/* ------------------------------------------------------------------ entry points */

void ply_free(PlyMesh *mesh)
{
    if (!mesh) return;
    free(mesh->positions);
    free(mesh->normals);
    free(mesh->uvs);
    free(mesh->indices);
    free(mesh->face_indices);
    memset(mesh, 0, sizeof *mesh);
}

static CstStatus ply_read_plain(const char *name, const void *data, size_t len, PlyMesh *out, CstError *err)
{
    PlyReader *r = calloc(1, sizeof *r);
    if (!r) return cst_fail(err, CST_ERR_OOM, "%.300s: out of memory", name);
    r->name = name;
    r->d = data;
    r->len = len;
    r->err = err;
    CstStatus st = read_header(r);
    if (st == CST_OK) st = assign_roles(r, out);
    if (st == CST_OK) st = read_body(r, out);
    if (st == CST_OK) {
        out->num_triangles = (int)(r->idx.n / 3);
        out->indices = r->idx.v;
        out->face_indices = r->fidx.n ? r->fidx.v : NULL;
        if (!out->face_indices) array_free(&r->fidx);
        r->idx.v = NULL;
        r->fidx.v = NULL;
    } else {
        array_free(&r->idx);
        array_free(&r->fidx);
        ply_free(out);
    }
    free(r);
    return st;
}

CstStatus ply_read(const char *name, const void *data, size_t len, PlyMesh *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    if (!gzip_is_compressed(NULL, data, len)) return ply_read_plain(name, data, len, out, err);
    char *plain = NULL;
    size_t plain_len = 0;
    CstStatus st = gzip_inflate(name, data, len, GZIP_MAX_OUTPUT_BYTES, &plain, &plain_len, err);
    if (st == CST_OK) st = ply_read_plain(name, plain, plain_len, out, err);
    free(plain);
    return st;
}

CstStatus ply_read_file(const char *path, PlyMesh *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    char *data = NULL;
    size_t len = 0;
    CstStatus st = gzip_read_file(path, &data, &len, err);
    if (st == CST_OK) st = ply_read_plain(path, data, len, out, err);
    free(data);
    return st;
}

int ply_is_ply(const char *path, const void *data, size_t len)
{
    size_t n = path ? strlen(path) : 0;
    if (n >= 4 && strcasecmp(path + n - 4, ".ply") == 0) return 1;
    if (n >= 7 && strcasecmp(path + n - 7, ".ply.gz") == 0) return 1;
    const char *s = data;
    return len >= 4 && memcmp(s, "ply", 3) == 0 && (s[3] == '\n' || s[3] == '\r');
}
