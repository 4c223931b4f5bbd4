/* lahar's error convention: a function that can fail on user input takes a caller-owned buffer
 * (err, errlen) and writes one line into it: what is wrong, where, and what to do. This is the one
 * formatter for such buffers (err may be NULL or errlen 0: nothing is written). */
#ifndef LAHAR_ERRMSG_H
#define LAHAR_ERRMSG_H
#include <errno.h>
#include <stdarg.h>
#include <stddef.h>
#include <stdio.h>
#include <sys/stat.h>

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

/* fopen for a file the user named as input (a case, STL, CSV, grid, HDF5 or key file): NULL with
 * errno = EISDIR for a directory, which fopen would open and whose reads then fail with messages
 * about the contents ("no rows", "0 vertices"); strerror(errno) says what is wrong. */
static inline FILE *lahar_fopen_input(const char *path, const char *mode)
{
    FILE *f = fopen(path, mode);
    struct stat st;
    if (f && fstat(fileno(f), &st) == 0 && S_ISDIR(st.st_mode)) {
        fclose(f);
        f = NULL;
        errno = EISDIR;
    }
    return f;
}

#endif
