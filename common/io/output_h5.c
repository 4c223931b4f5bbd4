/* What every writer of output.h shares (declared in output_h5.h): room on the disk and the last
 * error of a writer, HDF5 files without locks, attributes, datasets, the /header group, SWMR row
 * appends, and the list of a run's files. Separate from the writers so that a change to how
 * lahar writes HDF5 is made in one place for all of them. */
#include "output_h5.h"
#include <errno.h>
#include <inttypes.h>
#include <stdatomic.h>
#include <stdio.h>
#include <string.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>

/* ---------------------------------------------------------------- room on the disk ----- */

/* A full disk must not cost what was written before it. HDF5 that runs out of space in the
 * middle of a snapshot may leave its metadata half-written (a file that no longer opens) and an
 * identifier that crashes the library's clean-up at exit, so every write first checks that the
 * file system has room for it with a margin (LAHAR_OUTPUT_RESERVE: the other node may be
 * writing at the same time) and refuses otherwise, leaving the file as it was. */
static _Thread_local char out_err[OUT_PATH_MAX + 512];
static atomic_int out_hdf5_failed;

const char *lahar_output_error(void) { return out_err; }
int lahar_output_failed(void) { return atomic_load(&out_hdf5_failed); }

int lahar_output_exit(int status)
{
    if (lahar_output_failed()) {
        fflush(NULL);
        _exit(status);
    }
    return status;
}
void lahar_output_explain(char *err, size_t n)
{
    if (out_err[0] && n > 0)
        snprintf(err, n, "%s", out_err);
}

/* Bytes an unprivileged writer may still use on the file system of directory dir (-1 unknown). */
double lahar_output_free_bytes(const char *dir)
{
    struct statvfs v;
    if (statvfs(dir, &v) != 0)
        return -1.0;
    return (double)v.f_bavail * (double)v.f_frsize;
}

static void out_dir_of(const char *path, char *dir, size_t n)
{
    snprintf(dir, n, "%s", path);
    char *slash = strrchr(dir, '/');
    if (slash && slash != dir)
        *slash = '\0';
    else if (!slash)
        snprintf(dir, n, ".");
}

/* 0 when the file system of `path` has room for `need` bytes (with the margin); else -1 and the
 * message (which file, how much, what was being written at which step and time) in out_err and
 * on stderr. */
int out_room(const char *path, double need, const char *what, int64_t step, double t)
{
    char dir[OUT_PATH_MAX];
    out_dir_of(path, dir, sizeof dir);
    double avail = lahar_output_free_bytes(dir);
    if (avail < 0.0 || avail >= 1.5 * need + LAHAR_OUTPUT_RESERVE)
        return 0;
    snprintf(out_err, sizeof out_err,
             "%s: no space left on device (%.0f bytes free): %s at step %" PRId64 " (t = %.9g s) needs about %.0f "
             "bytes; not written, the file keeps what was written before; free space there or choose another -o",
             path, avail, what, step, t, 1.5 * need + LAHAR_OUTPUT_RESERVE);
    fprintf(stderr, "lahar: %s\n", out_err);
    return -1;
}

/* A write to `path` failed after its room was checked (another writer took the space, or an I/O
 * error): the message in out_err, naming a full disk when it is one. */
void out_write_failed(const char *path, const char *what, int64_t step, double t)
{
    int e = errno;
    char dir[OUT_PATH_MAX];
    out_dir_of(path, dir, sizeof dir);
    double avail = lahar_output_free_bytes(dir);
    const char *why = (e == ENOSPC || (avail >= 0.0 && avail < LAHAR_OUTPUT_RESERVE)) ? "no space left on device"
                      : e ? strerror(e) : "HDF5 error";
    snprintf(out_err, sizeof out_err, "%s: writing %s at step %" PRId64 " (t = %.9g s) failed: %s (%.0f bytes free)",
             path, what, step, t, why, avail);
    fprintf(stderr, "lahar: %s\n", out_err);
}

/* H5Fclose that failed leaves HDF5 an identifier its clean-up at exit crashes on (HDF5 1.10):
 * remembered, so that a program can leave with _exit (lahar_output_failed). */
int out_close(hid_t f)
{
    if (H5Fclose(f) >= 0)
        return 0;
    atomic_store(&out_hdf5_failed, 1);
    return -1;
}

/* ---------------------------------------------------------------- small HDF5 helpers ---- */

/* H5Fcreate/H5Fopen without HDF5's error-stack dump on failure: callers report one message of
 * their own (a missing output directory is a user error, not a library trace). */
int64_t lahar_h5_file_open(const char *path, unsigned flags, int64_t fapl, int create)
{
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    hid_t fcpl = H5Pcreate(H5P_FILE_CREATE);
    H5Pset_obj_track_times(fcpl, 0); /* the root group too: same run, same bytes */
    hid_t f = create ? H5Fcreate(path, flags, fcpl, (hid_t)fapl) : H5Fopen(path, flags, (hid_t)fapl);
    H5Pclose(fcpl);
    H5Eset_auto2(H5E_DEFAULT, func, data);
    return f;
}

/* Creation property lists without object modification times, so that the same run writes
 * byte-identical files (HDF5 stamps every object header with a time by default). */
hid_t out_dcpl(void)
{
    hid_t p = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(p, 0);
    return p;
}

hid_t out_group(hid_t loc, const char *name)
{
    hid_t p = H5Pcreate(H5P_GROUP_CREATE);
    H5Pset_obj_track_times(p, 0);
    hid_t g = H5Gcreate2(loc, name, H5P_DEFAULT, p, H5P_DEFAULT);
    H5Pclose(p);
    return g;
}

/* The empty "snapshots" group of a new snapshot file (bodies.h5, particles.h5, contacts.h5). 0 or -1. */
int out_snapshots_group(hid_t f)
{
    hid_t g = out_group(f, "snapshots");
    if (g < 0)
        return -1;
    H5Gclose(g);
    return 0;
}

/* Files that are closed between snapshots are opened without HDF5's file lock so that a viewer
 * holding the file open (ParaView) never makes the next snapshot fail. */
static hid_t out_fapl_unlocked(void)
{
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, 0, 1);
    return fapl;
}

/* Open (or create) one of lahar's HDF5 files without HDF5's file locking (see above). */
hid_t out_file_open(const char *path, unsigned flags, int create)
{
    hid_t fapl = out_fapl_unlocked();
    hid_t f = lahar_h5_file_open(path, flags, fapl, create);
    H5Pclose(fapl);
    return f;
}


hid_t out_str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

int out_attr(hid_t loc, const char *name, hid_t type, int n, const void *data)
{
    hsize_t d = (hsize_t)n;
    hid_t sp = n == 0 ? H5Screate(H5S_SCALAR) : H5Screate_simple(1, &d, NULL);
    hid_t a = H5Acreate2(loc, name, type, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, type, data);
    if (a >= 0)
        H5Aclose(a);
    H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

int out_attr_double(hid_t loc, const char *name, double v) { return out_attr(loc, name, H5T_NATIVE_DOUBLE, 0, &v); }
int out_attr_int64(hid_t loc, const char *name, int64_t v) { return out_attr(loc, name, H5T_NATIVE_INT64, 0, &v); }
int out_attr_string(hid_t loc, const char *name, const char *s)
{
    hid_t t = out_str_type();
    int rc = out_attr(loc, name, t, 0, &s);
    H5Tclose(t);
    return rc;
}

/* The /header group every lahar file starts with: dimensions, units, version, case. Returns the
 * open group (the caller adds its own attributes and closes it), or -1. */
hid_t out_header_group(hid_t f, const lahar_case *c)
{
    hid_t h = out_group(f, "header");
    if (h < 0)
        return -1;
    int rc = out_attr_int64(h, "dimensions", c->dim);
    rc |= out_attr_string(h, "units", "SI");
    rc |= out_attr_string(h, "lahar_version", LAHAR_VERSION);
    rc |= out_attr_string(h, "case_path", c->path);
    if (rc) {
        H5Gclose(h);
        return -1;
    }
    return h;
}

/* Write a whole dataset (rank 1 or 2); file type = memory type except float32 display data. */
int out_dataset(hid_t loc, const char *name, hid_t memtype, hid_t filetype, int rank, hsize_t d0, hsize_t d1,
                const void *data)
{
    hsize_t dims[2] = {d0, d1};
    hid_t sp = H5Screate_simple(rank, dims, NULL);
    hid_t dcpl = out_dcpl();
    hid_t ds = H5Dcreate2(loc, name, filetype, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
    H5Pclose(dcpl);
    herr_t rc = ds < 0 ? -1 : 0;
    if (ds >= 0 && d0 * (rank == 2 ? d1 : 1) > 0)
        rc = H5Dwrite(ds, memtype, H5S_ALL, H5S_ALL, H5P_DEFAULT, data);
    if (ds >= 0)
        H5Dclose(ds);
    H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

int out_strings(hid_t loc, const char *name, int n, const char *const *s)
{
    hid_t t = out_str_type();
    int rc = out_dataset(loc, name, t, t, 1, (hsize_t)n, 0, s);
    H5Tclose(t);
    return rc;
}

/* Append `rows` rows at row `start` of an extendible dataset of rank 1 (rows), 2 (rows x nb) or 3
 * (rows x nb x 3) and flush it (SWMR readers see it). A rank > 1 dataset with nb = 0 is extended
 * only. 0, or -1 on any HDF5 failure. */
int out_append_rows(hid_t id, hid_t mtype, int rank, hsize_t start, hsize_t rows, hsize_t nb, const void *buf)
{
    hsize_t newd[3] = {start + rows, nb, 3}, off[3] = {start, 0, 0}, cnt[3] = {rows, nb, 3};
    if (H5Dset_extent(id, newd) < 0)
        return -1;
    if (nb == 0 && rank > 1)
        return 0;
    int rc = 0;
    hid_t fsp = H5Dget_space(id), msp = H5Screate_simple(rank, cnt, NULL);
    H5Sselect_hyperslab(fsp, H5S_SELECT_SET, off, NULL, cnt, NULL);
    if (H5Dwrite(id, mtype, msp, fsp, H5P_DEFAULT, buf) < 0)
        rc = -1;
    H5Sclose(msp);
    H5Sclose(fsp);
    if (H5Dflush(id) < 0)
        rc = -1;
    return rc;
}

double out_wall_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* The chunk cache of an append-only SWMR stream (forces.h5, gauges.h5), set on its file access
 * list. HDF5 keeps up to 1 MiB of chunks per dataset by default and evicts only beyond that, so
 * every dataset of a long run grows the writer by up to 1 MiB although it never reads a chunk
 * back (gauges.h5 of 30 probes written every step: +30 MB in 40,000 steps, docs/bench/liveness.md).
 * Room for two of the largest chunk: the one being filled and the one before it. */
void out_stream_cache(hid_t fapl, double chunk_bytes)
{
    H5Pset_cache(fapl, 0, 101, (size_t)(2.0 * chunk_bytes), 1.0);
}

/* ---------------------------------------------------------------- files of a run -------- */

const char *const lahar_output_run_files[] = {
    "summary.json", "check.json", "check.png",   "lahar.xmf", "bodies.h5", "bodies.xmf",
    "particles.h5", "particles.xmf", "forces.h5", "contacts.h5", "gauges.h5",
    /* the twins of the snapshot files (output_snapfile.c), left behind by a writer that was killed */
    ".bodies.h5.twin", ".particles.h5.twin", ".contacts.h5.twin", NULL,
};
