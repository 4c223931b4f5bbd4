/* lahar's error convention: a function that can fail on user input takes a caller-owned buffer
 * (err, errlen) and writes one line into it: what is wrong, where, and what to do. This is the one
 * formatter for such buffers (err may be NULL or errlen 0: nothing is written). */
#ifndef LAHAR_ERRMSG_H
#define LAHAR_ERRMSG_H
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>

static inline void lahar_errf(char *err, size_t errlen, const char *fmt, ...) __attribute__((format(printf, 3, 4)));
static inline void lahar_errf(char *err, size_t errlen, const char *fmt, ...)
{
    if (!err || errlen == 0)
        return;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err, errlen, fmt, ap);
    va_end(ap);
}

#endif
