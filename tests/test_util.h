/* The check macro the C tests share: a failed condition prints where and why and is counted;
 * a test returns non-zero when `failures` is not 0 at the end. Include once per test program. */
#ifndef LAHAR_TEST_UTIL_H
#define LAHAR_TEST_UTIL_H
#include <stdio.h>

static int failures;
#define CHECK(cond, ...)                                                                           \
    do {                                                                                           \
        if (!(cond)) {                                                                             \
            fprintf(stderr, "FAIL %s:%d: ", __FILE__, __LINE__);                                   \
            fprintf(stderr, __VA_ARGS__);                                                          \
            fputc('\n', stderr);                                                                   \
            failures++;                                                                            \
        }                                                                                          \
    } while (0)

#endif
