/* LD_PRELOAD shim for tests/output_no_exchange.sh: renameat2 fails with EINVAL, as on a file
 * system that cannot swap two names (some network and overlay file systems), so that the snapshot
 * writers' fallback (common/io/output_snapfile.c) runs. */
#define _GNU_SOURCE
#include <errno.h>
#include <stdio.h>

int renameat2(int olddirfd, const char *oldpath, int newdirfd, const char *newpath, unsigned int flags)
{
    (void)olddirfd, (void)oldpath, (void)newdirfd, (void)newpath, (void)flags;
    errno = EINVAL;
    return -1;
}
