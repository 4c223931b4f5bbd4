/* Allocation counting for the no-allocation tests (test_sph_noalloc, test_dem_noalloc): a test
 * linked with -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free and alloc_count.c has
 * its malloc, calloc, realloc and free (and those of the libraries it links statically) counted
 * while alloc_counting is set. */
#ifndef LAHAR_TEST_ALLOC_COUNT_H
#define LAHAR_TEST_ALLOC_COUNT_H

/* volatile: the compiler knows malloc/free touch no program variable and would otherwise drop
 * the stores around them */
extern volatile int alloc_counting;
extern volatile long alloc_nalloc, alloc_nfree; /* calls counted: malloc + calloc + realloc; free of non-NULL */

#endif
