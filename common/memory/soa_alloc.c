/* Page-staggered arrays (soa_alloc.h). */
#include "soa_alloc.h"
#include <stdatomic.h>
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#define SOA_PAGE 4096u
#define SOA_LINE 64u

/* The offset of the next array; a process-wide count, so arrays allocated one after the other
 * (the usual case: a set's arrays at its creation) land on different sets. */
static atomic_uint soa_next_colour;

void *lahar_soa_calloc(size_t n, size_t size)
{
    if (size && n > (SIZE_MAX - 2 * SOA_PAGE) / size)
        return NULL;
    const size_t bytes = n * size;
    /* one page more than the data: the offset (>= one line, room for the block's address just
     * before the array) stays inside the block */
    const size_t total = (bytes + 2 * SOA_PAGE - 1) / SOA_PAGE * SOA_PAGE;
    unsigned char *base = aligned_alloc(SOA_PAGE, total);
    if (!base)
        return NULL;
    const unsigned colour = atomic_fetch_add(&soa_next_colour, 1u) % LAHAR_SOA_COLOURS;
    unsigned char *p = base + SOA_LINE * (1u + colour);
    memcpy(p - sizeof base, &base, sizeof base);
    memset(p, 0, bytes);
    return p;
}

void lahar_soa_free(void *p)
{
    if (!p)
        return;
    unsigned char *base;
    memcpy(&base, (unsigned char *)p - sizeof base, sizeof base);
    free(base);
}
