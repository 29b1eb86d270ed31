/* The RGL tensor file reader: a cursor over the header that checks each read against the
 * bytes left, then each field's data range against the file's size. */
#include "io/tensor.h"

#include <math.h>
#include <stdbool.h>
#include <stdlib.h>
#include <string.h>

#include "core/error.h"
#include "math/half.h"

size_t tensor_dtype_size(int dtype)
{
    static const size_t sizes[] = {0, 1, 1, 2, 2, 4, 4, 8, 8, 2, 4, 8};
    return dtype >= TENSOR_U8 && dtype <= TENSOR_F64 ? sizes[dtype] : 0;
}

const char *tensor_dtype_name(int dtype)
{
    static const char *const names[] = {"invalid", "uint8", "int8", "uint16", "int16", "uint32", "int32",
                                        "uint64", "int64", "float16", "float32", "float64"};
    return dtype >= TENSOR_U8 && dtype <= TENSOR_F64 ? names[dtype] : "invalid";
}

typedef struct Cursor {
    const uint8_t *p;
    size_t len, pos;
    const char *name;
    CstError *err;
} Cursor;

/* Little-endian unsigned integer of n bytes at the cursor, or a located error. */
static CstStatus take(Cursor *c, int n, const char *what, uint64_t *out)
{
    if (c->len - c->pos < (size_t)n)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: the file ends (%zu bytes) inside the header; "
                        "expected %s (%d bytes)", c->name, c->pos, c->len, what, n);
    uint64_t v = 0;
    for (int i = n - 1; i >= 0; i--) v = v << 8 | c->p[c->pos + (size_t)i];
    c->pos += (size_t)n;
    *out = v;
    return CST_OK;
}

#define TAKE(c, n, what, out)                               \
    do {                                                    \
        CstStatus st_ = take((c), (n), (what), (out));      \
        if (st_ != CST_OK) return st_;                      \
    } while (0)

static CstStatus read_field(Cursor *c, int index, TensorField *f)
{
    uint64_t v = 0;
    size_t at = c->pos;
    TAKE(c, 2, "a field name's length (uint16)", &v);
    if (v == 0 || v > TENSOR_MAX_NAME)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field %d has a name of %llu bytes; expected 1 to %d",
                        c->name, at, index, (unsigned long long)v, TENSOR_MAX_NAME);
    if (c->len - c->pos < v)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: the file ends (%zu bytes) inside field %d's name of "
                        "%llu bytes", c->name, c->pos, c->len, index, (unsigned long long)v);
    memcpy(f->name, c->p + c->pos, (size_t)v);
    f->name[v] = '\0';
    if (strlen(f->name) != (size_t)v)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field %d's name contains a NUL byte; expected "
                        "a name of printable characters", c->name, c->pos, index);
    c->pos += (size_t)v;
    at = c->pos;
    TAKE(c, 2, "a dimension count (uint16)", &v);
    if (v > TENSOR_MAX_DIMS)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field \"%s\" has %llu dimensions; expected at most %d",
                        c->name, at, f->name, (unsigned long long)v, TENSOR_MAX_DIMS);
    f->ndim = (int)v;
    at = c->pos;
    TAKE(c, 1, "a type code (uint8)", &v);
    if (tensor_dtype_size((int)v) == 0)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field \"%s\" has type code %llu; expected 1 (uint8) to "
                        "11 (float64)", c->name, at, f->name, (unsigned long long)v);
    f->dtype = (TensorDtype)v;
    size_t off_at = c->pos;
    TAKE(c, 8, "a data offset (uint64)", &f->offset);
    /* The product of the sizes, without wrapping, then bounded by the file's size. */
    uint64_t count = 1, esize = tensor_dtype_size(f->dtype);
    bool wrapped = false;
    for (int d = 0; d < f->ndim; d++) {
        TAKE(c, 8, "a dimension's size (uint64)", &f->shape[d]);
        wrapped |= __builtin_mul_overflow(count, f->shape[d], &count);
    }
    if (wrapped || count > (uint64_t)c->len / esize)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field \"%s\" has more %s values than the file (%zu "
                        "bytes) can hold", c->name, off_at + 8, f->name, tensor_dtype_name(f->dtype), c->len);
    f->count = count;
    uint64_t bytes = count * esize;
    if (f->offset > (uint64_t)c->len - bytes)
        return cst_fail(c->err, CST_ERR_PARSE, "%s: byte %zu: field \"%s\" (%llu %s values, %llu bytes) at offset %llu "
                        "runs past the end of the file (%zu bytes); expected its data inside the file",
                        c->name, off_at, f->name, (unsigned long long)count, tensor_dtype_name(f->dtype),
                        (unsigned long long)bytes, (unsigned long long)f->offset, c->len);
    f->data = c->p + f->offset;
    return CST_OK;
}

CstStatus tensor_read(const char *name, const void *data, size_t len, TensorFile *out, CstError *err)
{
    memset(out, 0, sizeof *out);
    Cursor c = {.p = data, .len = len, .pos = 0, .name = name, .err = err};
    static const char magic[12] = "tensor_file";
    if (len < 12 || memcmp(data, magic, 12) != 0)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte 0: not a tensor file; expected it to start with "
                        "\"tensor_file\" and a NUL byte (the RGL .bsdf format)", name);
    c.pos = 12;
    uint64_t major = 0, minor = 0, n = 0;
    TAKE(&c, 1, "the major version", &major);
    TAKE(&c, 1, "the minor version", &minor);
    if (major != 1 || minor != 0)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte 12: tensor file version %llu.%llu; expected 1.0", name,
                        (unsigned long long)major, (unsigned long long)minor);
    TAKE(&c, 4, "the field count (uint32)", &n);
    if (n == 0 || n > TENSOR_MAX_FIELDS)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte 14: %llu fields; expected 1 to %d", name,
                        (unsigned long long)n, TENSOR_MAX_FIELDS);
    /* Each field's header takes at least 14 bytes: no allocation the bytes cannot back. */
    if (n > (len - c.pos) / 14)
        return cst_fail(err, CST_ERR_PARSE, "%s: byte 14: %llu fields cannot fit in the file (%zu bytes)", name,
                        (unsigned long long)n, len);
    out->fields = calloc((size_t)n, sizeof *out->fields);
    if (!out->fields) return cst_fail(err, CST_ERR_OOM, "%s: out of memory for %llu fields", name, (unsigned long long)n);
    for (int i = 0; i < (int)n; i++) {
        size_t at = c.pos;
        CstStatus st = read_field(&c, i, &out->fields[i]);
        if (st == CST_OK && tensor_field(out, out->fields[i].name))
            st = cst_fail(err, CST_ERR_PARSE, "%s: byte %zu: a second field \"%s\"; expected unique names", name, at,
                          out->fields[i].name);
        if (st != CST_OK) {
            tensor_free(out);
            return st;
        }
        out->num_fields = i + 1;
    }
    return CST_OK;
}

const TensorField *tensor_field(const TensorFile *t, const char *name)
{
    for (int i = 0; i < t->num_fields; i++)
        if (strcmp(t->fields[i].name, name) == 0) return &t->fields[i];
    return NULL;
}

double tensor_value(const TensorField *f, uint64_t i)
{
    size_t n = tensor_dtype_size(f->dtype);
    uint64_t u = 0;
    for (int b = (int)n - 1; b >= 0; b--) u = u << 8 | f->data[i * n + (size_t)b];
    switch (f->dtype) {
    case TENSOR_U8: case TENSOR_U16: case TENSOR_U32: case TENSOR_U64: return (double)u;
    case TENSOR_I8: return (double)(int8_t)u;
    case TENSOR_I16: return (double)(int16_t)u;
    case TENSOR_I32: return (double)(int32_t)u;
    case TENSOR_I64: return (double)(int64_t)u;
    case TENSOR_F16: return (double)half_to_float((uint16_t)u); /* exact */
    case TENSOR_F32: {
        uint32_t w = (uint32_t)u;
        float x;
        memcpy(&x, &w, sizeof x);
        return (double)x;
    }
    case TENSOR_F64: {
        double x;
        memcpy(&x, &u, sizeof x);
        return x;
    }
    }
    return 0.0;
}

void tensor_free(TensorFile *t)
{
    if (!t) return;
    free(t->fields);
    t->fields = NULL;
    t->num_fields = 0;
}
