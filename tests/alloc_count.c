/* The linker's --wrap targets that count allocations (alloc_count.h). */
#include "alloc_count.h"
#include <stddef.h>

void *__real_malloc(size_t n);
void *__real_calloc(size_t n, size_t size);
void *__real_realloc(void *p, size_t n);
void __real_free(void *p);
void *__wrap_malloc(size_t n);
void *__wrap_calloc(size_t n, size_t size);
void *__wrap_realloc(void *p, size_t n);
void __wrap_free(void *p);

volatile int alloc_counting;
volatile long alloc_nalloc, alloc_nfree;

void *__wrap_malloc(size_t n)
{
    if (alloc_counting)
        alloc_nalloc++;
    return __real_malloc(n);
}

void *__wrap_calloc(size_t n, size_t size)
{
    if (alloc_counting)
        alloc_nalloc++;
    return __real_calloc(n, size);
}

void *__wrap_realloc(void *p, size_t n)
{
    if (alloc_counting)
        alloc_nalloc++;
    return __real_realloc(p, n);
}

void __wrap_free(void *p)
{
    if (alloc_counting && p)
        alloc_nfree++;
    __real_free(p);
}
