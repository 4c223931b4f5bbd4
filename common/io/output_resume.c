/* The snapshots already on disk (output.h): their list, the XDMF sidecar of a resumed writer
 * rebuilt from them, `lahar resume` cutting every output file back to a checkpoint, the mark on
 * the last snapshot of a failed run, and a SWMR file released after its writer died. Separate from
 * the writers: this is what reads and edits output after (or before) a run, not what writes it. */
#include <hdf5.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>
#include "output_h5.h"

/* ---------------------------------------------------------------- snapshot lists -------- */

/* Read (step, time, n) of every snapshot group in OUT/<name>; returns the count or -1. A
 * missing file gives 0. */
int64_t out_read_snapshot_list(const char *path, out_snap_entry **list)
{
    *list = NULL;
    FILE *probe = fopen(path, "rb");
    if (!probe)
        return 0;
    fclose(probe);
    hid_t f = out_file_open(path, H5F_ACC_RDONLY, 0);
    if (f < 0)
        return -1;
    hid_t g = H5Gopen2(f, "snapshots", H5P_DEFAULT);
    H5G_info_t info;
    if (g < 0 || H5Gget_info(g, &info) < 0) {
        if (g >= 0)
            H5Gclose(g);
        H5Fclose(f);
        return -1;
    }
    int64_t cnt = 0;
    *list = malloc((size_t)(info.nlinks > 0 ? info.nlinks : 1) * sizeof **list);
    for (hsize_t k = 0; *list && k < info.nlinks; k++) {
        char name[32];
        snprintf(name, sizeof name, "%06" PRId64, (int64_t)k);
        if (H5Lexists(g, name, H5P_DEFAULT) <= 0)
            break;
        hid_t s = H5Gopen2(g, name, H5P_DEFAULT);
        out_snap_entry e = {0, (int64_t)k, 0, 0.0};
        hid_t a = H5Aopen(s, "time", H5P_DEFAULT);
        H5Aread(a, H5T_NATIVE_DOUBLE, &e.t);
        H5Aclose(a);
        a = H5Aopen(s, "step", H5P_DEFAULT);
        H5Aread(a, H5T_NATIVE_INT64, &e.step);
        H5Aclose(a);
        if (H5Aexists(s, "n") > 0) {
            a = H5Aopen(s, "n", H5P_DEFAULT);
            H5Aread(a, H5T_NATIVE_INT64, &e.n);
            H5Aclose(a);
        }
        H5Gclose(s);
        (*list)[cnt++] = e;
    }
    H5Gclose(g);
    H5Fclose(f);
    return cnt;
}

int out_resume_sidecar(const char *h5path, const char *xmfpath, lahar_xdmf_file *xmf,
                       const lahar_xdmf_bodies *bodies, const unsigned *fields, int64_t *nsnap, char *err,
                       size_t n)
{
    if (access(h5path, F_OK) != 0) {
        snprintf(err, n, "%s: missing; the run to resume has no such file", h5path);
        return -1;
    }
    out_snap_entry *list = NULL;
    int64_t cnt = out_read_snapshot_list(h5path, &list);
    char *xml = malloc(OUT_XML_CAP);
    if (cnt < 0 || !xml) {
        snprintf(err, n, "%s: cannot read its snapshots to continue it", h5path);
        free(list), free(xml);
        return -1;
    }
    int rc = lahar_xdmf_open(xmf, xmfpath, err, n);
    for (int64_t k = 0; k < cnt && !rc; k++) {
        size_t len = lahar_xdmf_step_begin(xml, OUT_XML_CAP, list[k].step, list[k].t);
        if (bodies) {
            if (len < OUT_XML_CAP)
                len += lahar_xdmf_bodies_grids(xml + len, OUT_XML_CAP - len, bodies, k);
        } else {
            lahar_xdmf_particles xp = {"particles.h5", *fields};
            if (len < OUT_XML_CAP)
                len += lahar_xdmf_particles_grid(xml + len, OUT_XML_CAP - len, &xp, k, list[k].n);
        }
        if (len < OUT_XML_CAP)
            len += lahar_xdmf_step_end(xml + len, OUT_XML_CAP - len);
        if (len >= OUT_XML_CAP || lahar_xdmf_append(xmf, xml, len, OUT_XML_CAP)) {
            snprintf(err, n, "%s: cannot rebuild it", xmfpath);
            rc = -1;
        }
    }
    *nsnap = cnt;
    free(list), free(xml);
    return rc;
}

/* ---------------------------------------------------------------- cutting back to a checkpoint -- */

/* Cut the snapshots of OUT/<file> (bodies.h5, particles.h5, contacts.h5) after the checkpoint:
 * groups whose step is > last (>= last when strict), and drop the marks of a stopped run from
 * the ones kept. 0 (also when the file does not exist) or -1. */
static int out_trim_snapshots(const char *path, int64_t last, int strict)
{
    if (access(path, F_OK) != 0)
        return 0;
    out_snap_entry *list = NULL;
    int64_t cnt = out_read_snapshot_list(path, &list);
    if (cnt < 0)
        return -1;
    hid_t f = out_file_open(path, H5F_ACC_RDWR, 0);
    int rc = f < 0 ? -1 : 0;
    for (int64_t k = cnt - 1; k >= 0 && !rc; k--) {
        char name[48];
        snprintf(name, sizeof name, "/snapshots/%06" PRId64, list[k].snap);
        if (list[k].step > last || (strict && list[k].step == last)) {
            if (H5Ldelete(f, name, H5P_DEFAULT) < 0)
                rc = -1;
            continue;
        }
        static const char *const marks[] = {"stopped", "instability"};
        for (int m = 0; m < 2; m++)
            if (H5Aexists_by_name(f, name, marks[m], H5P_DEFAULT) > 0 &&
                H5Adelete_by_name(f, name, marks[m], H5P_DEFAULT) < 0)
                rc = -1;
    }
    if (f >= 0 && H5Fclose(f) < 0)
        rc = -1;
    free(list);
    return rc;
}

/* Cut the 1-D or row-major datasets names[] of group loc to the rows whose `step` is <= last. */
static int out_trim_rows(hid_t loc, const char *const *names, int nnames, int64_t last)
{
    hid_t ds = H5Dopen2(loc, "step", H5P_DEFAULT);
    if (ds < 0)
        return -1;
    hid_t sp = H5Dget_space(ds);
    hsize_t rows = 0;
    H5Sget_simple_extent_dims(sp, &rows, NULL);
    H5Sclose(sp);
    int64_t *st = malloc((size_t)(rows > 0 ? rows : 1) * sizeof *st);
    int rc = st ? 0 : -1;
    if (!rc && rows > 0 && H5Dread(ds, H5T_NATIVE_INT64, H5S_ALL, H5S_ALL, H5P_DEFAULT, st) < 0)
        rc = -1;
    H5Dclose(ds);
    hsize_t keep = 0;
    while (!rc && keep < rows && st[keep] <= last)
        keep++;
    free(st);
    for (int k = 0; k < nnames && !rc; k++) {
        hid_t d = H5Dopen2(loc, names[k], H5P_DEFAULT);
        if (d < 0) {
            rc = -1;
            break;
        }
        hid_t dsp = H5Dget_space(d);
        hsize_t dims[3] = {0, 0, 0};
        H5Sget_simple_extent_dims(dsp, dims, NULL);
        H5Sclose(dsp);
        dims[0] = keep;
        if (H5Dset_extent(d, dims) < 0)
            rc = -1;
        H5Dclose(d);
    }
    return rc;
}

int lahar_output_resume_trim(const char *outdir, int64_t step, int snapshot_at_step, char *err, size_t n)
{
    char path[OUT_PATH_MAX + 32];
    static const char *const snapfiles[] = {"particles.h5", "bodies.h5"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/%s", outdir, snapfiles[i]);
        if (out_trim_snapshots(path, step, !snapshot_at_step) != 0) {
            snprintf(err, n, "%s: cannot cut it back to the checkpoint (step %" PRId64 ")", path, step);
            return -1;
        }
    }
    /* contacts.h5 holds the LOADS of the steps that start at an output time: step `step` is the
     * first one the resumed run takes, so its entry belongs after the checkpoint */
    snprintf(path, sizeof path, "%s/contacts.h5", outdir);
    if (out_trim_snapshots(path, step, 1) != 0) {
        snprintf(err, n, "%s: cannot cut it back to the checkpoint (step %" PRId64 ")", path, step);
        return -1;
    }
    static const char *const streams[] = {"forces.h5", "gauges.h5"};
    for (int i = 0; i < 2; i++) {
        snprintf(path, sizeof path, "%s/%s", outdir, streams[i]);
        if (access(path, F_OK) != 0)
            continue;
        if (lahar_output_release_swmr(path) < 0) {
            snprintf(err, n, "%s: cannot open it", path);
            return -1;
        }
        hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
        H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
        hid_t f = (hid_t)lahar_h5_file_open(path, H5F_ACC_RDWR, fapl, 0);
        H5Pclose(fapl);
        int rc = f < 0 ? -1 : 0;
        /* a SWMR writer killed after its last flush leaves chunks past the end of allocation the
         * superblock records (h5clear --increment does the same): take in what is on disk */
        if (!rc && H5Fincrement_filesize(f, 0) < 0)
            rc = -1;
        if (!rc && i == 0) {
            static const char *const names[] = {"t", "step", "force", "torque", "ncontacts", "energy"};
            rc = out_trim_rows(f, names, 6, step);
        } else if (!rc) {
            static const char *const groups[] = {"probes", "trackers", "control_volumes"};
            for (int gi = 0; gi < 3 && !rc; gi++) {
                if (H5Lexists(f, groups[gi], H5P_DEFAULT) <= 0)
                    continue;
                hid_t pg = H5Gopen2(f, groups[gi], H5P_DEFAULT);
                H5G_info_t info;
                if (pg < 0 || H5Gget_info(pg, &info) < 0)
                    rc = -1;
                for (hsize_t k = 0; !rc && k < info.nlinks; k++) {
                    char name[LAHAR_NAME_MAX + 8];
                    if (H5Lget_name_by_idx(pg, ".", H5_INDEX_NAME, H5_ITER_INC, k, name, sizeof name, H5P_DEFAULT) < 0) {
                        rc = -1;
                        break;
                    }
                    hid_t g = H5Gopen2(pg, name, H5P_DEFAULT);
                    /* every dataset of the gauge: t, step and its values */
                    H5G_info_t gi2;
                    char dn[LAHAR_PROBE_MAX_VALUES + 2][16];
                    const char *dnames[LAHAR_PROBE_MAX_VALUES + 2];
                    int nd = 0;
                    if (g < 0 || H5Gget_info(g, &gi2) < 0)
                        rc = -1;
                    for (hsize_t d = 0; !rc && d < gi2.nlinks && nd < LAHAR_PROBE_MAX_VALUES + 2; d++) {
                        if (H5Lget_name_by_idx(g, ".", H5_INDEX_NAME, H5_ITER_INC, d, dn[nd], sizeof dn[nd],
                                               H5P_DEFAULT) < 0)
                            rc = -1;
                        else
                            dnames[nd] = dn[nd], nd++;
                    }
                    if (!rc)
                        rc = out_trim_rows(g, dnames, nd, step);
                    if (g >= 0)
                        H5Gclose(g);
                }
                if (pg >= 0)
                    H5Gclose(pg);
            }
        }
        if (f >= 0 && H5Fclose(f) < 0)
            rc = -1;
        if (rc) {
            snprintf(err, n, "%s: cannot cut it back to the checkpoint (step %" PRId64 ")", path, step);
            return -1;
        }
    }
    return 0;
}


/* ---------------------------------------------------------------- final snapshot of a failed run -- */

/* The string attribute `name` on the last snapshot of the file at path, in place. 0 or -1. */
static int out_mark_last(const char *path, const char *name, const char *text)
{
    hid_t f = out_file_open(path, H5F_ACC_RDWR, 0);
    if (f < 0)
        return -1;
    int rc = -1;
    hid_t g = H5Gopen2(f, "snapshots", H5P_DEFAULT);
    H5G_info_t info;
    if (g >= 0 && H5Gget_info(g, &info) >= 0 && info.nlinks > 0) {
        char sname[32];
        snprintf(sname, sizeof sname, "%06" PRId64, (int64_t)info.nlinks - 1);
        hid_t s = H5Gopen2(g, sname, H5P_DEFAULT);
        if (s >= 0) {
            if (H5Aexists(s, name) > 0)
                H5Adelete(s, name);
            rc = out_attr_string(s, name, text);
            H5Gclose(s);
        }
    }
    if (g >= 0)
        H5Gclose(g);
    if (out_close(f) < 0)
        rc = -1;
    return rc;
}

int lahar_output_mark_last_snapshot(const char *outdir, const char *file, const char *name, const char *text)
{
    char path[OUT_PATH_MAX + 64], twin[OUT_PATH_MAX + 96];
    snprintf(path, sizeof path, "%s/%s", outdir, file);
    if (access(path, F_OK) != 0)
        return -1;
    double avail = lahar_output_free_bytes(outdir);
    if (avail >= 0.0 && avail < LAHAR_OUTPUT_RESERVE) {
        fprintf(stderr, "lahar: %s: the last snapshot is not marked (no space left on device: %.0f bytes free)\n",
                path, avail);
        return -1;
    }
    int rc = out_mark_last(path, name, text);
    if (rc)
        fprintf(stderr, "lahar: %s: cannot mark the last snapshot\n", path);
    /* the writer's twin (output_snapfile.c), which a later snapshot would publish, gets the mark too */
    if (out_snapfile_twin_path(path, twin, sizeof twin) == 0 && access(twin, F_OK) == 0)
        out_mark_last(twin, name, text);
    return rc;
}

int lahar_output_last_snapshot(const char *outdir, const char *file, char *group, size_t n, int64_t *step, double *t)
{
    char path[OUT_PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", outdir, file);
    out_snap_entry *list = NULL;
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int64_t cnt = out_read_snapshot_list(path, &list);
    H5Eset_auto2(H5E_DEFAULT, func, data);
    if (cnt > 0) {
        snprintf(group, n, "/snapshots/%06" PRId64, list[cnt - 1].snap);
        *step = list[cnt - 1].step;
        *t = list[cnt - 1].t;
    }
    free(list);
    return cnt > 0 ? 0 : -1;
}

int lahar_output_release_swmr(const char *path)
{
    if (access(path, F_OK) != 0)
        return 0;
    hid_t f = (hid_t)lahar_h5_file_open(path, H5F_ACC_RDONLY, H5P_DEFAULT, 0);
    if (f >= 0) {
        H5Fclose(f);
        return 0;
    }
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    hbool_t clear = 1;
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    herr_t set = H5Pset(fapl, "clear_status_flags", &clear);
    H5Eset_auto2(H5E_DEFAULT, func, data);
    f = set >= 0 ? (hid_t)lahar_h5_file_open(path, H5F_ACC_RDWR, fapl, 0) : -1;
    H5Pclose(fapl);
    if (f < 0)
        return -1;
    /* The SWMR writer flushes its datasets but not the superblock's end of allocation, so the
     * objects it added lie beyond it and a reader that is not a SWMR reader fails on them ("addr
     * overflow"): the EOA becomes max(EOA, EOF), as h5clear -i does. */
    herr_t inc = H5Fincrement_filesize(f, 0);
    if (H5Fclose(f) < 0 || inc < 0)
        return -1;
    return 1;
}
