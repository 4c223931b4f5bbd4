/* Snapshot files (bodies.h5, particles.h5, contacts.h5) that a writer killed at any moment leaves
 * readable, with every snapshot it finished (declared in output_h5.h).
 *
 * HDF5 is not transactional: a snapshot adds a group and datasets and rewrites metadata in place
 * (the superblock's end of file, the snapshot group's B-tree and heap) as the file closes. A
 * SIGKILL inside that write leaves metadata that point past the end of the file or at a group
 * whose datasets were never written: the file no longer opens, or its last snapshot does not
 * read (tests/test_output_killed.c). So each file has a twin, OUT/.<name>.twin, holding the same
 * snapshots. A snapshot is written into the twin; the twin and the file then swap names in one
 * step (renameat2 RENAME_EXCHANGE); the former file, now the twin, receives the same snapshot and
 * is again equal to the published one, byte for byte (lahar writes no time stamps). The published
 * name always refers to a file HDF5 closed completely. The price: each snapshot is written twice,
 * and the file takes twice its size on the disk while the run writes (the twin is removed at
 * close). */
#define _GNU_SOURCE /* renameat2, copy_file_range */
#include <errno.h>
#include <fcntl.h>
#include <inttypes.h>
#include <stdio.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "output_h5.h"

int out_snapfile_twin_path(const char *path, char *twin, size_t n)
{
    const char *slash = strrchr(path, '/');
    int dirlen = slash ? (int)(slash - path + 1) : 0;
    return snprintf(twin, n, "%.*s.%s.twin", dirlen, path, path + dirlen) < (int)n ? 0 : -1;
}

void out_snapfile_init(out_snapfile *sf, const char *path, int in_place)
{
    snprintf(sf->path, sizeof sf->path, "%s", path);
    out_snapfile_twin_path(path, sf->twin, sizeof sf->twin);
    sf->twin_ok = 0;
    sf->in_place = in_place;
}

/* Copy file `from` to `to` (created or truncated, with from's permissions). 0 or -1 (errno set). */
static int out_copy_file(const char *from, const char *to)
{
    int in = open(from, O_RDONLY | O_CLOEXEC);
    if (in < 0)
        return -1;
    struct stat st;
    int out = fstat(in, &st) == 0 ? open(to, O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, st.st_mode & 0777) : -1;
    if (out < 0) {
        int e = errno;
        close(in);
        errno = e;
        return -1;
    }
    int rc = 0;
    off_t left = st.st_size;
    while (left > 0 && rc == 0) {
        ssize_t k = copy_file_range(in, NULL, out, NULL, (size_t)left, 0);
        if (k < 0 && (errno == EXDEV || errno == ENOSYS || errno == EINVAL || errno == EOPNOTSUPP)) {
            char buf[65536]; /* a file system without copy_file_range: copied through this buffer */
            k = read(in, buf, sizeof buf);
            for (ssize_t done = 0, w; k > 0 && done < k; done += w)
                if ((w = write(out, buf + done, (size_t)(k - done))) < 0)
                    k = -1;
        }
        if (k <= 0)
            rc = -1;
        else
            left -= k;
    }
    int e = errno;
    if (close(out) != 0)
        rc = -1;
    close(in);
    errno = e;
    return rc;
}

static double out_file_bytes(const char *path)
{
    struct stat st;
    return stat(path, &st) == 0 ? (double)st.st_size : 0.0;
}

/* One snapshot into the file at path: /snapshots/NNNNNN with its time and step, filled by fill,
 * the file closed. 0 or -1. */
static int out_snapshot_write(const char *path, int64_t nsnap, int64_t step, double t, out_snapshot_fill fill,
                              void *ctx)
{
    hid_t f = out_file_open(path, H5F_ACC_RDWR, 0);
    if (f < 0)
        return -1;
    char name[48];
    snprintf(name, sizeof name, "/snapshots/%06" PRId64, nsnap);
    hid_t g = out_group(f, name);
    int rc = g < 0 ? -1 : 0;
    if (g >= 0) {
        rc |= out_attr_double(g, "time", t) | out_attr_int64(g, "step", step);
        if (!rc)
            rc = fill(g, ctx);
        H5Gclose(g);
    }
    if (out_close(f) < 0)
        rc = -1;
    return rc;
}

int out_snapfile_append(out_snapfile *sf, double need, const char *what, int64_t nsnap, int64_t step, double t,
                        out_snapshot_fill fill, void *ctx)
{
    if (sf->in_place) {
        if (out_room(sf->path, need, what, step, t) != 0)
            return -1;
        if (out_snapshot_write(sf->path, nsnap, step, t, fill, ctx) != 0) {
            out_write_failed(sf->path, what, step, t);
            return -1;
        }
        return 0;
    }
    /* room for the snapshot twice, and for a new twin when the last one fell behind; the message
     * names the way out that needs half the room */
    double copy = sf->twin_ok ? 0.0 : out_file_bytes(sf->path);
    char both[256];
    snprintf(both, sizeof both, "%s and its twin (output: {twins: false} writes it once)", what);
    if (out_room(sf->path, 2.0 * need + copy, both, step, t) != 0)
        return -1;
    if (!sf->twin_ok && out_copy_file(sf->path, sf->twin) != 0) {
        out_write_failed(sf->twin, "a copy of the file", step, t);
        return -1;
    }
    sf->twin_ok = 0; /* until both hold the snapshot */
    if (out_snapshot_write(sf->twin, nsnap, step, t, fill, ctx) != 0) {
        out_write_failed(sf->path, what, step, t);
        return -1;
    }
    if (renameat2(AT_FDCWD, sf->twin, AT_FDCWD, sf->path, RENAME_EXCHANGE) != 0) {
        int e = errno;
        /* a file system that cannot swap two names (some network and overlay file systems):
         * the complete twin replaces the file, and later snapshots are written in place */
        if (rename(sf->twin, sf->path) != 0) {
            out_write_failed(sf->path, what, step, t);
            return -1;
        }
        sf->in_place = 1;
        fprintf(stderr,
                "lahar: %s: this file system cannot swap two files in one step (renameat2: %s): later snapshots "
                "are written in place, and a writer killed while writing one can leave the file unreadable\n",
                sf->path, strerror(e));
        return 0;
    }
    /* the former file, one snapshot behind, catches up; if it cannot, it is copied again before
     * the next snapshot (the published file is complete either way) */
    sf->twin_ok = out_snapshot_write(sf->twin, nsnap, step, t, fill, ctx) == 0;
    return 0;
}

void out_snapfile_close(out_snapfile *sf)
{
    if (sf->twin[0])
        unlink(sf->twin);
    sf->twin_ok = 0;
}

void lahar_output_remove_twins(const char *outdir)
{
    static const char *const names[] = {"bodies.h5", "particles.h5", "contacts.h5"};
    for (size_t i = 0; i < sizeof names / sizeof names[0]; i++) {
        char path[OUT_PATH_MAX + 32], twin[OUT_PATH_MAX + 64];
        snprintf(path, sizeof path, "%s/%s", outdir, names[i]);
        if (out_snapfile_twin_path(path, twin, sizeof twin) == 0)
            unlink(twin);
    }
}
