/* Checkpoint files (checkpoint.h). */
#include "checkpoint.h"
#include <errno.h>
#include <fcntl.h>
#include <hdf5.h>
#include <inttypes.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <unistd.h>
#include "output.h"

static void ckpt_fail(lahar_ckpt_file *f, const char *fmt, ...)
{
    if (f->failed)
        return;
    f->failed = 1;
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(f->err, sizeof f->err, fmt, ap);
    va_end(ap);
}

static int ckpt_attr_write(hid_t loc, const char *name, hid_t type, const void *v)
{
    hid_t sp = H5Screate(H5S_SCALAR);
    hid_t a = H5Acreate2(loc, name, type, sp, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = a < 0 ? -1 : H5Awrite(a, type, v);
    if (a >= 0)
        H5Aclose(a);
    H5Sclose(sp);
    return rc < 0 ? -1 : 0;
}

int lahar_ckpt_create(lahar_ckpt_file *f, const char *path, const char *role)
{
    memset(f, 0, sizeof *f);
    f->writing = 1;
    snprintf(f->path, sizeof f->path, "%s", path);
    f->file = lahar_h5_file_open(path, H5F_ACC_TRUNC, H5P_DEFAULT, 1);
    if (f->file < 0) {
        ckpt_fail(f, "%s: cannot create the checkpoint file", path);
        return -1;
    }
    int64_t format = LAHAR_CKPT_FORMAT;
    hid_t st = H5Tcopy(H5T_C_S1);
    H5Tset_size(st, H5T_VARIABLE);
    const char *version = LAHAR_VERSION;
    int rc = ckpt_attr_write((hid_t)f->file, "format", H5T_NATIVE_INT64, &format);
    rc |= ckpt_attr_write((hid_t)f->file, "lahar_version", st, &version);
    rc |= ckpt_attr_write((hid_t)f->file, "role", st, &role);
    H5Tclose(st);
    if (rc)
        ckpt_fail(f, "%s: cannot write the checkpoint header", path);
    return f->failed ? -1 : 0;
}

int lahar_ckpt_open(lahar_ckpt_file *f, const char *path, const char *role)
{
    memset(f, 0, sizeof *f);
    f->file = lahar_h5_file_open(path, H5F_ACC_RDONLY, H5P_DEFAULT, 0);
    if (f->file < 0) {
        ckpt_fail(f, "%s: cannot open the checkpoint file (missing or not HDF5)", path);
        return -1;
    }
    int64_t format = -1;
    char *version = NULL, *frole = NULL;
    hid_t st = H5Tcopy(H5T_C_S1);
    H5Tset_size(st, H5T_VARIABLE);
    hid_t a;
    if (H5Aexists((hid_t)f->file, "format") > 0 && (a = H5Aopen((hid_t)f->file, "format", H5P_DEFAULT)) >= 0) {
        H5Aread(a, H5T_NATIVE_INT64, &format);
        H5Aclose(a);
    }
    if (H5Aexists((hid_t)f->file, "lahar_version") > 0 &&
        (a = H5Aopen((hid_t)f->file, "lahar_version", H5P_DEFAULT)) >= 0) {
        H5Aread(a, st, &version);
        H5Aclose(a);
    }
    if (H5Aexists((hid_t)f->file, "role") > 0 && (a = H5Aopen((hid_t)f->file, "role", H5P_DEFAULT)) >= 0) {
        H5Aread(a, st, &frole);
        H5Aclose(a);
    }
    H5Tclose(st);
    if (format != LAHAR_CKPT_FORMAT || !version || strcmp(version, LAHAR_VERSION) != 0)
        ckpt_fail(f, "%s: checkpoint of format %" PRId64 " written by lahar %s; this lahar %s reads format %d only: "
                  "resume it with the build that wrote it, or start the run again (lahar run --overwrite)",
                  path, format, version ? version : "?", LAHAR_VERSION, LAHAR_CKPT_FORMAT);
    else if (!frole || strcmp(frole, role) != 0)
        ckpt_fail(f, "%s: not a checkpoint of the %s (it says '%s')", path, role, frole ? frole : "?");
    H5free_memory(version);
    H5free_memory(frole);
    return f->failed ? -1 : 0;
}

int lahar_ckpt_close(lahar_ckpt_file *f)
{
    if (f->file >= 0) {
        char path[1200] = "";
        H5Fget_name((hid_t)f->file, path, sizeof path);
        if (f->writing && H5Fflush((hid_t)f->file, H5F_SCOPE_GLOBAL) < 0)
            ckpt_fail(f, "%s: cannot flush the checkpoint file", path);
        if (H5Fclose((hid_t)f->file) < 0)
            ckpt_fail(f, "%s: cannot close the checkpoint file", path);
        f->file = -1;
        if (f->writing && !f->failed && lahar_ckpt_fsync_path(path) != 0)
            ckpt_fail(f, "%s: fsync: %s", path, strerror(errno));
    }
    return f->failed ? -1 : 0;
}

/* Store or load one 1-D dataset of n elements of type mt (file type ft). */
static void ckpt_array(lahar_ckpt_file *f, const char *name, hid_t mt, hid_t ft, void *data, int64_t n)
{
    if (f->failed || f->file < 0)
        return;
    hid_t file = (hid_t)f->file;
    if (f->writing) {
        /* room first, as every output writer (output.h, LAHAR_OUTPUT_RESERVE): HDF5 that runs
         * out of space says only that a write failed */
        double need = 1.5 * (double)(n > 0 ? n : 0) * (double)H5Tget_size(ft) + LAHAR_OUTPUT_RESERVE;
        char dir[sizeof f->path];
        snprintf(dir, sizeof dir, "%s", f->path);
        char *slash = strrchr(dir, '/');
        if (slash)
            *slash = '\0';
        double avail = lahar_output_free_bytes(slash ? dir : ".");
        if (avail >= 0.0 && avail < need) {
            ckpt_fail(f, "%s: no space left on device (%.0f bytes free): the checkpoint's '%s' (%" PRId64 " values) "
                      "needs about %.0f bytes; this checkpoint is not written (the previous one is kept); free space "
                      "there and `lahar resume` the run",
                      f->path, avail, name, n, need);
            return;
        }
        hsize_t d = (hsize_t)(n > 0 ? n : 0);
        hid_t sp = H5Screate_simple(1, &d, NULL);
        hid_t ds = H5Dcreate2(file, name, ft, sp, H5P_DEFAULT, H5P_DEFAULT, H5P_DEFAULT);
        if (ds < 0 || (n > 0 && H5Dwrite(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0))
            ckpt_fail(f, "cannot write '%s' (%" PRId64 " values) into the checkpoint", name, n);
        if (ds >= 0)
            H5Dclose(ds);
        H5Sclose(sp);
        return;
    }
    int64_t len = lahar_ckpt_length(f, name);
    if (len != n) {
        ckpt_fail(f, "the checkpoint's '%s' has %" PRId64 " values, this run needs %" PRId64
                  " (a checkpoint of another case or build)", name, len, n);
        return;
    }
    if (n == 0)
        return;
    hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
    if (ds < 0 || H5Dread(ds, mt, H5S_ALL, H5S_ALL, H5P_DEFAULT, data) < 0)
        ckpt_fail(f, "cannot read '%s' from the checkpoint", name);
    if (ds >= 0)
        H5Dclose(ds);
}

int64_t lahar_ckpt_length(lahar_ckpt_file *f, const char *name)
{
    hid_t file = (hid_t)f->file;
    H5E_auto2_t func;
    void *cd;
    H5Eget_auto2(H5E_DEFAULT, &func, &cd);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int64_t len = -1;
    if (H5Lexists(file, name, H5P_DEFAULT) > 0) {
        hid_t ds = H5Dopen2(file, name, H5P_DEFAULT);
        if (ds >= 0) {
            hid_t sp = H5Dget_space(ds);
            hsize_t d = 0;
            if (H5Sget_simple_extent_ndims(sp) == 1 && H5Sget_simple_extent_dims(sp, &d, NULL) == 1)
                len = (int64_t)d;
            H5Sclose(sp);
            H5Dclose(ds);
        }
    }
    H5Eset_auto2(H5E_DEFAULT, func, cd);
    return len;
}

void lahar_ckpt_f64(lahar_ckpt_file *f, const char *name, double *data, int64_t n)
{
    ckpt_array(f, name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, data, n);
}
void lahar_ckpt_i64(lahar_ckpt_file *f, const char *name, int64_t *data, int64_t n)
{
    ckpt_array(f, name, H5T_NATIVE_INT64, H5T_STD_I64LE, data, n);
}
void lahar_ckpt_i32(lahar_ckpt_file *f, const char *name, int32_t *data, int64_t n)
{
    ckpt_array(f, name, H5T_NATIVE_INT32, H5T_STD_I32LE, data, n);
}
void lahar_ckpt_u8(lahar_ckpt_file *f, const char *name, uint8_t *data, int64_t n)
{
    ckpt_array(f, name, H5T_NATIVE_UINT8, H5T_STD_U8LE, data, n);
}

void lahar_ckpt_int(lahar_ckpt_file *f, const char *name, int *v)
{
    int64_t x = *v;
    lahar_ckpt_i64(f, name, &x, 1);
    if (!f->writing && !f->failed)
        *v = (int)x;
}

void lahar_ckpt_blob(lahar_ckpt_file *f, const char *name, void **data, size_t *n)
{
    if (f->writing) {
        lahar_ckpt_u8(f, name, *data, (int64_t)*n);
        return;
    }
    *data = NULL;
    *n = 0;
    if (f->failed)
        return;
    int64_t len = lahar_ckpt_length(f, name);
    if (len < 0) {
        ckpt_fail(f, "the checkpoint has no '%s'", name);
        return;
    }
    *data = malloc((size_t)(len > 0 ? len : 1));
    if (!*data) {
        ckpt_fail(f, "out of memory for '%s' (%" PRId64 " bytes)", name, len);
        return;
    }
    *n = (size_t)len;
    lahar_ckpt_u8(f, name, *data, len);
}

void lahar_ckpt_dir(char *buf, size_t n, const char *outdir, int64_t step, int tmp)
{
    snprintf(buf, n, "%s/" LAHAR_CKPT_DIR "/%06" PRId64 "%s", outdir, step, tmp ? ".tmp" : "");
}

int lahar_mkdir_p(const char *path)
{
    char tmp[4200];
    size_t len = strlen(path);
    if (len >= sizeof tmp) {
        errno = ENAMETOOLONG;
        return -1;
    }
    memcpy(tmp, path, len + 1);
    for (char *p = tmp + 1; *p; p++)
        if (*p == '/') {
            *p = '\0';
            if (mkdir(tmp, 0777) != 0 && errno != EEXIST)
                return -1;
            *p = '/';
        }
    return (mkdir(tmp, 0777) != 0 && errno != EEXIST) ? -1 : 0;
}

int lahar_ckpt_fsync_path(const char *path)
{
    int fd = open(path, O_RDONLY | O_CLOEXEC);
    if (fd < 0)
        return -1;
    int rc = fsync(fd);
    int e = errno;
    close(fd);
    errno = e;
    return rc;
}
