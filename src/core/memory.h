/* Allocation of large, read-mostly arrays (acceleration structures): in transparent huge
 * pages where the system offers them, so traversal's scattered reads miss the TLB less. */
#ifndef CST_CORE_MEMORY_H
#define CST_CORE_MEMORY_H

#include <stddef.h>

/* At least `bytes` bytes, 64-byte aligned, uninitialised; NULL when out of memory.
 * Requests of 2 MiB or more are rounded up to whole 2 MiB pages and marked for huge pages
 * before anything touches them (the kernel backs a page by a huge one only at its first
 * fault). Release with free(). */
void *memory_alloc_large(size_t bytes);

#endif
