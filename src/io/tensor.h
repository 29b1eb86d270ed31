/* The RGL tensor file (Dupuy & Jakob 2018's measured-BSDF ".bsdf" files, Mitsuba's
 * TensorFile, pbrt-v4's Tensor): named n-dimensional arrays of fixed-size numbers, read
 * from memory with every count, offset and size checked against the bytes. */
#ifndef CST_IO_TENSOR_H
#define CST_IO_TENSOR_H

#include <stddef.h>
#include <stdint.h>

#include "caustic/caustic.h"

/* Element types, with the file's codes (Mitsuba's Struct::Type of format version 1.0). */
typedef enum TensorDtype {
    TENSOR_U8 = 1, TENSOR_I8, TENSOR_U16, TENSOR_I16, TENSOR_U32, TENSOR_I32,
    TENSOR_U64, TENSOR_I64, TENSOR_F16, TENSOR_F32, TENSOR_F64
} TensorDtype;

enum { TENSOR_MAX_DIMS = 8, TENSOR_MAX_FIELDS = 256, TENSOR_MAX_NAME = 255 };

typedef struct TensorField {
    char name[TENSOR_MAX_NAME + 1];
    TensorDtype dtype;
    int ndim;
    uint64_t shape[TENSOR_MAX_DIMS];
    uint64_t count;      /* product of the shape (1 for ndim 0) */
    uint64_t offset;     /* of the first element, from the start of the file */
    const uint8_t *data; /* into the bytes given to tensor_read (little-endian, unaligned) */
} TensorField;

typedef struct TensorFile {
    int num_fields;
    TensorField *fields; /* owned: tensor_free */
} TensorFile;

/* Bytes per element of a type (0 for a code outside TensorDtype). */
size_t tensor_dtype_size(int dtype);
/* A type's name as the messages spell it ("uint8", "float32", ...). */
const char *tensor_dtype_name(int dtype);

/* Parses the tensor file held in data[0..len); the fields point into data, which must
 * outlive *out. Layout (little-endian): "tensor_file\0", version 1.0 (two bytes), the
 * field count (uint32), then per field its name length (uint16) and name, its dimension
 * count (uint16), type code (uint8), data offset (uint64) and sizes (uint64 each). Every
 * field's data must lie inside the bytes, names are unique and non-empty. Errors
 * (CST_ERR_PARSE) say "NAME: byte OFFSET: what was expected". */
CstStatus tensor_read(const char *name, const void *data, size_t len, TensorFile *out, CstError *err);
/* The field called name, or NULL. */
const TensorField *tensor_field(const TensorFile *t, const char *name);
/* Element i of a field as a double, any type (f16 included); i < count. */
double tensor_value(const TensorField *f, uint64_t i);
void tensor_free(TensorFile *t);

#endif
