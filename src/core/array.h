/* The one growable array: ARRAY(T) { T *v; size_t n, cap; } and its growth rule. One
 * overflow rule for all of them: a size that does not fit size_t fails like an OOM. */
#ifndef CST_CORE_ARRAY_H
#define CST_CORE_ARRAY_H

#include <stdbool.h>
#include <stddef.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

/* A zeroed ARRAY is valid and empty. Declare a named type with
 * typedef ARRAY(Foo) FooArray; */
#define ARRAY(T) struct { T *v; size_t n, cap; }

/* Makes the array at *data (a T * stored in the caller's struct, passed as its address)
 * hold at least `need` elements of `elem` bytes: the capacity doubles (from 16) until it
 * does, so pushes are amortised O(1). False, with the array unchanged, when `need * elem`
 * overflows size_t or realloc fails. The pointer is read and written through memcpy, so
 * any T * works without breaking aliasing rules. */
static inline bool array_grow(void *data, size_t *cap, size_t need, size_t elem)
{
    if (need <= *cap) return true;
    if (elem == 0 || need > SIZE_MAX / elem) return false;
    size_t c = *cap ? *cap : 16;
    while (c < need) c = c <= SIZE_MAX / 2 ? 2 * c : need;
    if (c > SIZE_MAX / elem) c = need; /* doubling past the limit: take just what is asked */
    void *old, *p;
    memcpy(&old, data, sizeof old);
    p = realloc(old, c * elem);
    if (!p) return false;
    memcpy(data, &p, sizeof p);
    *cap = c;
    return true;
}

/* Room for `need` elements in all. */
#define array_reserve(a, need) array_grow(&(a)->v, &(a)->cap, (need), sizeof *(a)->v)
/* Appends x; false (array unchanged) on overflow or OOM. */
#define array_push(a, x) (array_reserve((a), (a)->n + 1) ? ((a)->v[(a)->n++] = (x), true) : false)
/* Frees the elements; the array is empty and valid again. */
#define array_free(a) (free((a)->v), (a)->v = NULL, (a)->n = (a)->cap = 0)

#endif
