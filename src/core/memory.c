/* memory_alloc_large(): aligned_alloc plus a huge-page hint. */
#define _DEFAULT_SOURCE /* madvise */
#include "core/memory.h"

#include <stdlib.h>
#include <sys/mman.h>

enum { HUGE_PAGE = 2u << 20, LINE = 64 };

void *memory_alloc_large(size_t bytes)
{
    if (bytes < HUGE_PAGE) return aligned_alloc(LINE, (bytes + LINE - 1u) & ~(size_t)(LINE - 1u));
    const size_t rounded = (bytes + HUGE_PAGE - 1u) & ~(size_t)(HUGE_PAGE - 1u);
    if (rounded < bytes) return NULL; /* overflow */
    void *p = aligned_alloc(HUGE_PAGE, rounded);
#ifdef MADV_HUGEPAGE
    /* Only a hint: where transparent huge pages are off (or not Linux) the pages stay 4 KiB,
     * and a refusal is no error. Embree gives its BVH the same hint. */
    if (p) (void)madvise(p, rounded, MADV_HUGEPAGE);
#endif
    return p;
}
