/* Arrays of a structure of arrays (particles, spheres), each placed at its own offset within a
 * 4 KiB page.
 *
 * Why: a loop over i that reads x[i], y[i], vx[i], rho[i], ... streams one cache line of each
 * array at a time. The L1 data cache picks a line's set from address bits 6-11, so arrays whose
 * starts are equal modulo 4096 put all those lines into one set (12 ways on the machines measured)
 * and evict each other; a store to one and a load from another also look alike to the CPU's
 * memory disambiguation ("4K aliasing"). glibc's malloc hands every array larger than its mmap
 * threshold its own pages at the same offset (16 bytes past a page boundary), so 17 particle
 * arrays allocated one by one all collide. Which arrays get pages of their own depends on what
 * the process freed before (glibc raises the threshold after a large free): measured on the
 * 24,844-particle boulder pool, the SPH node's own process ran its step 10-15 % slower than the
 * same code as a thread of the in-process run, whose earlier frees had moved the arrays onto the
 * heap. Here each array starts LAHAR_SOA_COLOURS cache lines apart from the previous one
 * (modulo the page), whatever the allocator's history. */
#ifndef LAHAR_SOA_ALLOC_H
#define LAHAR_SOA_ALLOC_H
#include <stddef.h>

#define LAHAR_SOA_COLOURS 63 /* distinct offsets: 64, 128, ..., 4032 bytes past a page boundary */

/* n elements of size bytes, zeroed, 64-byte aligned, at the next offset in the page; NULL when out
 * of memory or n * size overflows. Free with lahar_soa_free only. */
void *lahar_soa_calloc(size_t n, size_t size);
void lahar_soa_free(void *p);

#endif
