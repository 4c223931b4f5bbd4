/* HDF5 output of bodies, forces and particles with XDMF sidecars (layout in output.h and
 * tools/README.md). Everything a snapshot or a force row needs is allocated at open; the
 * per-step path only copies into those buffers and calls HDF5. */
#include "output.h"
#include <errno.h>
#include <hdf5.h>
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <stdatomic.h>
#include <string.h>
#include <sys/statvfs.h>
#include <time.h>
#include <unistd.h>
#include "vec.h"
#include "xdmf.h"

#define OUT_PATH_MAX 1200
#define OUT_XML_CAP 16384
#define FORCES_FLUSH_SECONDS 0.5
#define FORCES_BUFFER_BYTES (256 * 1024)

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
static int out_room(const char *path, double need, const char *what, int64_t step, double t)
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
static void out_write_failed(const char *path, const char *what, int64_t step, double t)
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
static int out_close(hid_t f)
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
static hid_t out_dcpl(void)
{
    hid_t p = H5Pcreate(H5P_DATASET_CREATE);
    H5Pset_obj_track_times(p, 0);
    return p;
}

static hid_t out_group(hid_t loc, const char *name)
{
    hid_t p = H5Pcreate(H5P_GROUP_CREATE);
    H5Pset_obj_track_times(p, 0);
    hid_t g = H5Gcreate2(loc, name, H5P_DEFAULT, p, H5P_DEFAULT);
    H5Pclose(p);
    return g;
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
static hid_t out_file_open(const char *path, unsigned flags, int create)
{
    hid_t fapl = out_fapl_unlocked();
    hid_t f = lahar_h5_file_open(path, flags, fapl, create);
    H5Pclose(fapl);
    return f;
}


static hid_t out_str_type(void)
{
    hid_t t = H5Tcopy(H5T_C_S1);
    H5Tset_size(t, H5T_VARIABLE);
    H5Tset_cset(t, H5T_CSET_UTF8);
    return t;
}

static int out_attr(hid_t loc, const char *name, hid_t type, int n, const void *data)
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
const char *const lahar_flow_names[LAHAR_FLOW_NVAL] = {
    "flow_entered", "flow_entered_mass", "flow_removed_water", "flow_removed_water_mass",
    "flow_removed_soil", "flow_removed_soil_mass", "flow_created", "flow_domain_mass"};

static int out_attr_double(hid_t loc, const char *name, double v) { return out_attr(loc, name, H5T_NATIVE_DOUBLE, 0, &v); }
static int out_attr_int64(hid_t loc, const char *name, int64_t v) { return out_attr(loc, name, H5T_NATIVE_INT64, 0, &v); }
static int out_attr_string(hid_t loc, const char *name, const char *s)
{
    hid_t t = out_str_type();
    int rc = out_attr(loc, name, t, 0, &s);
    H5Tclose(t);
    return rc;
}

/* The /header group every lahar file starts with: dimensions, units, version, case. Returns the
 * open group (the caller adds its own attributes and closes it), or -1. */
static hid_t out_header_group(hid_t f, const lahar_case *c)
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
static int out_dataset(hid_t loc, const char *name, hid_t memtype, hid_t filetype, int rank, hsize_t d0, hsize_t d1,
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

static int out_strings(hid_t loc, const char *name, int n, const char *const *s)
{
    hid_t t = out_str_type();
    int rc = out_dataset(loc, name, t, t, 1, (hsize_t)n, 0, s);
    H5Tclose(t);
    return rc;
}

/* Append `rows` rows at row `start` of an extendible dataset of rank 1 (rows), 2 (rows x nb) or 3
 * (rows x nb x 3) and flush it (SWMR readers see it). A rank > 1 dataset with nb = 0 is extended
 * only. 0, or -1 on any HDF5 failure. */
static int out_append_rows(hid_t id, hid_t mtype, int rank, hsize_t start, hsize_t rows, hsize_t nb, const void *buf)
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

/* A snapshot's start, the same for particles, bodies and contacts: room for `need` bytes (what:
 * for the message), the file reopened (*file), the group /snapshots/NNNNNN (nsnap) made with its
 * time and step. Returns the group; H5I_INVALID_HID with *file < 0 when nothing was opened (the
 * reason printed), H5I_INVALID_HID with *file open when the group or its attributes failed (the
 * group is closed then; the caller closes the file). */
static hid_t out_snapshot_open(const char *path, double need, const char *what, int64_t nsnap, int64_t step, double t,
                               hid_t *file)
{
    *file = H5I_INVALID_HID;
    if (out_room(path, need, what, step, t) != 0)
        return H5I_INVALID_HID;
    *file = out_file_open(path, H5F_ACC_RDWR, 0);
    if (*file < 0) {
        fprintf(stderr, "lahar: %s: cannot reopen for %s at step %" PRId64 "\n", path, what, step);
        return H5I_INVALID_HID;
    }
    char name[48];
    snprintf(name, sizeof name, "/snapshots/%06" PRId64, nsnap);
    hid_t g = out_group(*file, name);
    if (g >= 0 && (out_attr_double(g, "time", t) | out_attr_int64(g, "step", step)) != 0) {
        H5Gclose(g);
        g = H5I_INVALID_HID;
    }
    return g;
}

static double out_wall_seconds(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

/* A resumed run (lahar_case.resume): the snapshot count of an existing file and its XDMF sidecar
 * rebuilt from the snapshots on disk (below). */
static int out_resume_sidecar(const char *h5path, const char *xmfpath, lahar_xdmf_file *xmf,
                              const lahar_body_output *bodies, const unsigned *fields, int64_t *nsnap, char *err,
                              size_t n);

/* ---------------------------------------------------------------- bodies ---------------- */

typedef struct {
    hid_t file, t, step, force, torque, ncontacts, energy;
    char path[OUT_PATH_MAX + 16];
    int failed;           /* a flush failed: nothing more is written (the rows before stay readable) */
    int nbody;
    int64_t rows;         /* rows on disk */
    int cap, nbuf;        /* buffered rows */
    double *bt, *bforce, *btorque, *benergy;
    int64_t *bstep;
    int32_t *bncont;
    double last_flush;
    double interval;      /* s, 0 = every row */
    int64_t next_slot;    /* next multiple of interval to record */
} forces_stream;

struct lahar_body_output {
    char dir[OUT_PATH_MAX];
    char h5path[OUT_PATH_MAX];
    int dim, nbody;
    lahar_display_mesh *mesh;  /* per body, body frame (fixed: world frame as given) */
    int *moving;               /* per body: 1 if not fixed */
    int64_t nmoving_vert, nmoving_cell, nfixed_vert, nfixed_cell;
    double *state;             /* nbody * 13: x, q, v, w laid out as four blocks */
    float *vert, *vvel;        /* moving display vertices and their velocities */
    int64_t nsnap;
    lahar_xdmf_file xmf;
    char *xml;
    forces_stream fs;
};

/* Flattened display geometry of the bodies with the given motion filter (moving = 1: free and
 * prescribed bodies; 0: fixed ones), with world vertices from the case pose. */
static int out_write_mesh_set(hid_t g, const lahar_body_output *o, const lahar_case *c, int moving)
{
    int64_t nv = moving ? o->nmoving_vert : o->nfixed_vert, nc = moving ? o->nmoving_cell : o->nfixed_cell;
    int npc = o->dim == 2 ? 2 : 3;
    float *v = malloc((size_t)(nv > 0 ? nv : 1) * 3 * sizeof *v);
    int32_t *cell = malloc((size_t)(nc > 0 ? nc : 1) * (size_t)npc * sizeof *cell);
    int32_t *bid = malloc((size_t)(nc > 0 ? nc : 1) * sizeof *bid);
    int32_t *vbid = malloc((size_t)(nv > 0 ? nv : 1) * sizeof *vbid);
    if (!v || !cell || !bid || !vbid) {
        free(v), free(cell), free(bid), free(vbid);
        return -1;
    }
    int64_t iv = 0, ic = 0;
    for (int b = 0; b < o->nbody; b++) {
        if (o->moving[b] != moving)
            continue;
        const lahar_display_mesh *m = &o->mesh[b];
        quat q = q_load(c->bodies[b].q);
        vec3 x = v3_load(c->bodies[b].x);
        for (int k = 0; k < m->ncell; k++, ic++) {
            for (int j = 0; j < npc; j++)
                cell[ic * npc + j] = (int32_t)(iv + m->cell[k * npc + j]);
            bid[ic] = b;
        }
        for (int i = 0; i < m->nvert; i++, iv++) {
            vec3 p = v3_add(x, q_rotate(q, v3_load(m->v[i])));
            v[iv * 3 + 0] = (float)p.x, v[iv * 3 + 1] = (float)p.y, v[iv * 3 + 2] = (float)p.z;
            vbid[iv] = b;
        }
    }
    int rc = 0;
    if (!moving)
        rc |= out_dataset(g, "vertices", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, 2, (hsize_t)nv, 3, v);
    rc |= out_dataset(g, "cells", H5T_NATIVE_INT32, H5T_STD_I32LE, 2, (hsize_t)nc, (hsize_t)npc, cell);
    rc |= out_dataset(g, "body_id", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nc, 0, bid);
    rc |= out_dataset(g, "vertex_body_id", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nv, 0, vbid);
    free(v), free(cell), free(bid), free(vbid);
    return rc;
}

static int out_write_header(hid_t f, const lahar_case *c)
{
    int rc = 0, nb = c->nbody, nm = c->nmaterial;
    hid_t h = out_header_group(f, c);
    if (h < 0)
        return -1;
    rc |= out_attr_int64(h, "nbody", nb);
    rc |= out_attr(h, "gravity", H5T_NATIVE_DOUBLE, 3, c->gravity);
    rc |= out_attr_double(h, "t_end", c->t_end);
    rc |= out_attr_double(h, "output_interval", c->output_interval);
    rc |= out_attr_double(h, "forces_interval", c->forces_interval);
    rc |= out_attr_string(h, "motion_kinds", "0 free, 1 fixed, 2 prescribed");
    rc |= out_attr_string(h, "frames", "geometry in body frame (fixed bodies: world frame); "
                                       "quaternions (w,x,y,z) body->world; angular velocity in world frame");
    size_t nalloc = (size_t)(nb > nm ? nb : nm) + 1;
    const char **names = malloc(nalloc * sizeof *names);
    int32_t *iv = malloc(nalloc * sizeof *iv);
    double *dv = malloc(nalloc * 3 * sizeof *dv);
    if (!names || !iv || !dv) {
        free(names), free(iv), free(dv);
        H5Gclose(h);
        return -1;
    }
    for (int b = 0; b < nb; b++)
        names[b] = c->bodies[b].name;
    rc |= out_strings(h, "body_name", nb, names);
    for (int b = 0; b < nb; b++)
        iv[b] = b;
    rc |= out_dataset(h, "body_id", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nb, 0, iv);
    for (int b = 0; b < nb; b++)
        iv[b] = c->bodies[b].material;
    rc |= out_dataset(h, "material", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nb, 0, iv);
    for (int b = 0; b < nb; b++) {
        int m = c->bodies[b].material;
        names[b] = (m >= 0 && m < nm) ? c->materials[m].name : "";
    }
    rc |= out_strings(h, "material_name", nb, names);
    for (int b = 0; b < nb; b++)
        iv[b] = (int32_t)c->bodies[b].motion;
    rc |= out_dataset(h, "motion", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nb, 0, iv);
    for (int b = 0; b < nb; b++)
        dv[b] = c->bodies[b].mass;
    rc |= out_dataset(h, "mass", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 1, (hsize_t)nb, 0, dv);
    for (int b = 0; b < nb; b++)
        dv[b] = c->bodies[b].shape.radius;
    rc |= out_dataset(h, "sweep_radius", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 1, (hsize_t)nb, 0, dv);
    for (int b = 0; b < nb; b++)
        memcpy(dv + 3 * b, c->bodies[b].inertia, 3 * sizeof(double));
    rc |= out_dataset(h, "inertia", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, dv);

    /* material table: one dataset per property, indexed by /header/material */
    hid_t mg = out_group(h, "materials");
    if (mg < 0)
        rc = -1;
    else {
        for (int m = 0; m < nm; m++)
            names[m] = c->materials[m].name;
        rc |= out_strings(mg, "name", nm, names);
        static const struct {
            const char *name;
            size_t off;
        } prop[] = {{"density", offsetof(lahar_material, density)},
                    {"young", offsetof(lahar_material, young)},
                    {"poisson", offsetof(lahar_material, poisson)},
                    {"kn", offsetof(lahar_material, kn)},
                    {"kt_ratio", offsetof(lahar_material, kt_ratio)},
                    {"restitution", offsetof(lahar_material, restitution)},
                    {"friction", offsetof(lahar_material, friction)}};
        for (size_t p = 0; p < sizeof prop / sizeof prop[0]; p++) {
            for (int m = 0; m < nm; m++)
                memcpy(&dv[m], (const char *)&c->materials[m] + prop[p].off, sizeof(double));
            rc |= out_dataset(mg, prop[p].name, H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 1, (hsize_t)nm, 0, dv);
        }
        for (int m = 0; m < nm; m++)
            iv[m] = (int32_t)c->materials[m].model;
        rc |= out_dataset(mg, "model", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, (hsize_t)nm, 0, iv);
        rc |= out_attr_string(mg, "model_kinds", "0 linear, 1 hertz");
        H5Gclose(mg);
    }
    free(names), free(iv), free(dv);
    H5Gclose(h);
    return rc ? -1 : 0;
}

static int out_write_geometry(hid_t f, const lahar_body_output *o, const lahar_case *c)
{
    int rc = 0;
    hid_t g = out_group(f, "geometry");
    if (g < 0)
        return -1;
    rc |= out_attr_int64(g, "nodes_per_cell", o->dim == 2 ? 2 : 3);
    rc |= out_attr_int64(g, "moving_vertices", o->nmoving_vert);
    rc |= out_attr_int64(g, "moving_cells", o->nmoving_cell);
    rc |= out_attr_int64(g, "fixed_vertices", o->nfixed_vert);
    rc |= out_attr_int64(g, "fixed_cells", o->nfixed_cell);
    hid_t bg = out_group(g, "bodies");
    for (int b = 0; bg >= 0 && b < o->nbody; b++) {
        char name[32];
        snprintf(name, sizeof name, "%06d", b);
        hid_t one = out_group(bg, name);
        if (one < 0) {
            rc = -1;
            break;
        }
        const lahar_display_mesh *m = &o->mesh[b];
        rc |= out_attr_string(one, "name", c->bodies[b].name);
        rc |= out_attr_string(one, "frame", o->moving[b] ? "body" : "world");
        rc |= out_dataset(one, "vertices", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)m->nvert, 3, m->v);
        rc |= out_dataset(one, "cells", H5T_NATIVE_INT32, H5T_STD_I32LE, 2, (hsize_t)m->ncell,
                          (hsize_t)m->nodes_per_cell, m->cell);
        H5Gclose(one);
    }
    if (bg >= 0)
        H5Gclose(bg);
    else
        rc = -1;
    for (int moving = 0; moving < 2; moving++) {
        hid_t s = out_group(g, moving ? "moving" : "fixed");
        if (s < 0 || out_write_mesh_set(s, o, c, moving))
            rc = -1;
        if (s >= 0)
            H5Gclose(s);
    }
    H5Gclose(g);
    return rc ? -1 : 0;
}

/* The write buffers: as many rows as fit in FORCES_BUFFER_BYTES (1 to 1024). */
static int forces_buffers(forces_stream *fs)
{
    const int nb = fs->nbody;
    size_t row_bytes = (size_t)(nb > 0 ? nb : 1) * 76 + 16;
    fs->cap = (int)(FORCES_BUFFER_BYTES / row_bytes);
    if (fs->cap < 1)
        fs->cap = 1;
    if (fs->cap > 1024)
        fs->cap = 1024;
    size_t nrow = (size_t)fs->cap, nb3 = (size_t)(nb > 0 ? nb : 1) * 3;
    fs->bt = malloc(nrow * sizeof *fs->bt);
    fs->bstep = malloc(nrow * sizeof *fs->bstep);
    fs->bforce = malloc(nrow * nb3 * sizeof *fs->bforce);
    fs->btorque = malloc(nrow * nb3 * sizeof *fs->btorque);
    fs->benergy = malloc(nrow * nb3 * sizeof *fs->benergy);
    fs->bncont = malloc(nrow * (size_t)(nb > 0 ? nb : 1) * sizeof *fs->bncont);
    return fs->bt && fs->bstep && fs->bforce && fs->btorque && fs->bncont && fs->benergy ? 0 : -1;
}

/* A resumed run appends to the stream as lahar_output_resume_trim left it (cut at the checkpoint):
 * the rows on disk, and the next forces_interval slot after the last row. */
static int forces_reopen(forces_stream *fs, hid_t fapl, char *err, size_t n)
{
    const char *path = fs->path;
    fs->file = lahar_h5_file_open(path, H5F_ACC_RDWR, fapl, 0);
    if (fs->file < 0) {
        snprintf(err, n, "%s: cannot reopen the force stream to continue it", path);
        return -1;
    }
    hid_t *ids[] = {&fs->t, &fs->step, &fs->force, &fs->torque, &fs->ncontacts, &fs->energy};
    const char *names[] = {"t", "step", "force", "torque", "ncontacts", "energy"};
    for (int k = 0; k < 6; k++)
        if ((*ids[k] = H5Dopen2(fs->file, names[k], H5P_DEFAULT)) < 0) {
            snprintf(err, n, "%s: no dataset %s to continue", path, names[k]);
            return -1;
        }
    hid_t sp = H5Dget_space(fs->t);
    hsize_t rows = 0;
    H5Sget_simple_extent_dims(sp, &rows, NULL);
    H5Sclose(sp);
    fs->rows = (int64_t)rows;
    if (rows > 0 && fs->interval > 0.0) {
        double last = 0.0;
        hsize_t off = rows - 1, one = 1;
        hid_t fsp = H5Dget_space(fs->t), msp = H5Screate_simple(1, &one, NULL);
        H5Sselect_hyperslab(fsp, H5S_SELECT_SET, &off, NULL, &one, NULL);
        H5Dread(fs->t, H5T_NATIVE_DOUBLE, msp, fsp, H5P_DEFAULT, &last);
        H5Sclose(msp);
        H5Sclose(fsp);
        fs->next_slot = (int64_t)floor(last / fs->interval * (1.0 + 1e-12)) + 1;
    }
    if (H5Fstart_swmr_write(fs->file) < 0) {
        snprintf(err, n, "%s: cannot start SWMR writing", path);
        return -1;
    }
    return 0;
}

/* The description attribute of forces.h5. */
static const char forces_file_description[] =
    "contact + external force and torque (about the centre of mass) on each body, time "
    "average over the step; fixed bodies: the contact force they receive. energy: per body "
    "[E_P, E_K, E_R] at the end of the step: potential energy -m g . x (m g y_B for gravity "
    "along -y, Trujillo-Vela et al. 2020 eq. 37; 0 at the origin), translational kinetic "
    "energy m |v|^2 / 2 (eq. 38) and rotational kinetic energy w . I w / 2 (0 for fixed "
    "bodies)";

/* A new stream: its extendible datasets (chunks of the buffer's rows) and attributes. */
static int forces_create(forces_stream *fs, const lahar_case *c)
{
    const int nb = fs->nbody;
    hsize_t chunk_rows = (hsize_t)fs->cap;
    struct {
        hid_t *id;
        const char *name;
        hid_t type;
        int rank;
        const char *units;
    } ds[] = {{&fs->t, "t", H5T_IEEE_F64LE, 1, "s"},
              {&fs->step, "step", H5T_STD_I64LE, 1, ""},
              {&fs->force, "force", H5T_IEEE_F64LE, 3, c->dim == 2 ? "N/m" : "N"},
              {&fs->torque, "torque", H5T_IEEE_F64LE, 3, c->dim == 2 ? "N m/m" : "N m"},
              {&fs->ncontacts, "ncontacts", H5T_STD_I32LE, 2, ""},
              {&fs->energy, "energy", H5T_IEEE_F64LE, 3, c->dim == 2 ? "J/m" : "J"}};
    int rc = 0;
    for (size_t k = 0; k < sizeof ds / sizeof ds[0]; k++) {
        hsize_t dims[3] = {0, (hsize_t)nb, 3}, maxd[3] = {H5S_UNLIMITED, (hsize_t)nb, 3};
        hsize_t ch[3] = {chunk_rows, (hsize_t)(nb > 0 ? nb : 1), 3};
        hid_t sp = H5Screate_simple(ds[k].rank, dims, maxd);
        hid_t dcpl = out_dcpl();
        H5Pset_chunk(dcpl, ds[k].rank, ch);
        *ds[k].id = H5Dcreate2(fs->file, ds[k].name, ds[k].type, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        H5Pclose(dcpl);
        H5Sclose(sp);
        if (*ds[k].id < 0 || (ds[k].units[0] && out_attr_string(*ds[k].id, "units", ds[k].units)))
            rc = -1;
    }
    const char **names = malloc((size_t)(nb > 0 ? nb : 1) * sizeof *names);
    if (!names)
        rc = -1;
    else {
        for (int b = 0; b < nb; b++)
            names[b] = c->bodies[b].name;
        hid_t st = out_str_type();
        if (nb > 0)
            rc |= out_attr(fs->file, "body_names", st, nb, names);
        H5Tclose(st);
        free(names);
    }
    rc |= out_attr_string(fs->file, "units", "SI");
    rc |= out_attr_string(fs->file, "description", forces_file_description);
    rc |= out_attr_string(fs->file, "lahar_version", LAHAR_VERSION);
    return rc;
}

static int forces_open(forces_stream *fs, const char *path, const lahar_case *c, char *err, size_t n)
{
    memset(fs, 0, sizeof *fs);
    fs->file = fs->t = fs->step = fs->force = fs->torque = fs->ncontacts = fs->energy = H5I_INVALID_HID;
    fs->nbody = c->nbody;
    fs->interval = c->forces_interval > 0.0 ? c->forces_interval : 0.0;
    if (forces_buffers(fs) != 0) {
        snprintf(err, n, "out of memory for the force stream buffer");
        return -1;
    }
    /* SWMR needs the latest file format; datasets must all exist before SWMR writing starts. */
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
    snprintf(fs->path, sizeof fs->path, "%s", path);
    if (c->resume) {
        int rc = forces_reopen(fs, fapl, err, n);
        H5Pclose(fapl);
        if (rc != 0)
            return -1;
    } else {
        fs->file = lahar_h5_file_open(path, H5F_ACC_TRUNC, fapl, 1);
        H5Pclose(fapl);
        if (fs->file < 0) {
            snprintf(err, n, "%s: cannot create HDF5 file", path);
            return -1;
        }
        if (forces_create(fs, c) != 0 || H5Fstart_swmr_write(fs->file) < 0) {
            snprintf(err, n, "%s: cannot create the force datasets / start SWMR writing", path);
            return -1;
        }
    }
    fs->last_flush = out_wall_seconds();
    return 0;
}

static int forces_flush(forces_stream *fs)
{
    if (fs->file < 0 || fs->nbuf == 0)
        return 0;
    if (fs->failed)
        return -1;
    int64_t last_step = fs->bstep[fs->nbuf - 1];
    double last_t = fs->bt[fs->nbuf - 1];
    /* the rows, plus the chunks they may open (one per dataset, FORCES_BUFFER_BYTES in all) */
    double need = (double)fs->nbuf * (16.0 + 76.0 * fs->nbody) + FORCES_BUFFER_BYTES;
    if (out_room(fs->path, need, "the force rows", last_step, last_t) != 0) {
        fs->failed = 1;
        return -1;
    }
    hsize_t rows = (hsize_t)fs->nbuf, start = (hsize_t)fs->rows, nb = (hsize_t)fs->nbody;
    struct {
        hid_t id, mtype;
        int rank;
        const void *buf;
    } ds[] = {{fs->step, H5T_NATIVE_INT64, 1, fs->bstep},
              {fs->force, H5T_NATIVE_DOUBLE, 3, fs->bforce},
              {fs->torque, H5T_NATIVE_DOUBLE, 3, fs->btorque},
              {fs->ncontacts, H5T_NATIVE_INT32, 2, fs->bncont},
              {fs->energy, H5T_NATIVE_DOUBLE, 3, fs->benergy},
              {fs->t, H5T_NATIVE_DOUBLE, 1, fs->bt}};
    /* /t is extended, written and flushed last: a SWMR reader that sees n rows in /t finds
     * them in every other dataset */
    int rc = 0;
    for (size_t k = 0; k < sizeof ds / sizeof ds[0]; k++)
        if (out_append_rows(ds[k].id, ds[k].mtype, ds[k].rank, start, rows, nb, ds[k].buf) != 0)
            rc = -1;
    fs->rows += fs->nbuf;
    fs->nbuf = 0;
    fs->last_flush = out_wall_seconds();
    if (rc) {
        out_write_failed(fs->path, "the force rows", last_step, last_t);
        fs->failed = 1;
    }
    return rc;
}

static void forces_close(forces_stream *fs)
{
    if (fs->file >= 0) { /* forces_open set every id (invalid until created) */
        forces_flush(fs);
        hid_t ids[] = {fs->t, fs->step, fs->force, fs->torque, fs->ncontacts, fs->energy};
        for (size_t k = 0; k < sizeof ids / sizeof ids[0]; k++)
            if (ids[k] >= 0)
                H5Dclose(ids[k]);
        out_close(fs->file);
    }
    free(fs->bt), free(fs->bstep), free(fs->bforce), free(fs->btorque), free(fs->bncont), free(fs->benergy);
    memset(fs, 0, sizeof *fs);
    fs->file = H5I_INVALID_HID;
}

static void out_xdmf_bodies_info(const lahar_body_output *o, lahar_xdmf_bodies *x)
{
    x->h5name = "bodies.h5";
    x->nbody = o->nbody;
    x->nodes_per_cell = o->dim == 2 ? 2 : 3;
    x->moving_vertices = o->nmoving_vert;
    x->moving_cells = o->nmoving_cell;
    x->fixed_vertices = o->nfixed_vert;
    x->fixed_cells = o->nfixed_cell;
}

lahar_body_output *lahar_body_output_open(const char *outdir, const lahar_case *c, char *err, size_t n)
{
    lahar_body_output *o = calloc(1, sizeof *o);
    if (!o) {
        snprintf(err, n, "out of memory");
        return NULL;
    }
    o->xmf.fd = -1;
    o->fs.file = H5I_INVALID_HID;
    o->dim = c->dim;
    o->nbody = c->nbody;
    snprintf(o->dir, sizeof o->dir, "%s", outdir);
    snprintf(o->h5path, sizeof o->h5path, "%s/bodies.h5", outdir);
    size_t nb = (size_t)(c->nbody > 0 ? c->nbody : 1);
    o->mesh = calloc(nb, sizeof *o->mesh);
    o->moving = calloc(nb, sizeof *o->moving);
    o->state = calloc(nb * 13, sizeof *o->state);
    o->xml = malloc(OUT_XML_CAP);
    if (!o->mesh || !o->moving || !o->state || !o->xml) {
        snprintf(err, n, "out of memory");
        lahar_body_output_close(o);
        return NULL;
    }
    for (int b = 0; b < c->nbody; b++) {
        o->moving[b] = c->bodies[b].motion != LAHAR_MOTION_FIXED;
        if (lahar_display_mesh_build(&c->bodies[b].shape, c->dim, c->bodies[b].convex, &o->mesh[b])) {
            snprintf(err, n, "bodies[%d] (%s): cannot build its display mesh", b, c->bodies[b].name);
            lahar_body_output_close(o);
            return NULL;
        }
        if (o->moving[b])
            o->nmoving_vert += o->mesh[b].nvert, o->nmoving_cell += o->mesh[b].ncell;
        else
            o->nfixed_vert += o->mesh[b].nvert, o->nfixed_cell += o->mesh[b].ncell;
    }
    size_t nmv = (size_t)(o->nmoving_vert > 0 ? o->nmoving_vert : 1);
    o->vert = malloc(nmv * 3 * sizeof *o->vert);
    o->vvel = malloc(nmv * 3 * sizeof *o->vvel);
    if (!o->vert || !o->vvel) {
        snprintf(err, n, "out of memory");
        lahar_body_output_close(o);
        return NULL;
    }
    char stale[OUT_PATH_MAX + 16];
    snprintf(stale, sizeof stale, "%s/lahar.xmf", outdir); /* a previous run's, rebuilt at close */
    unlink(stale);
    if (c->resume) { /* continue bodies.h5 as the checkpoint left it (lahar_output_resume_trim) */
        char path[OUT_PATH_MAX + 16];
        snprintf(path, sizeof path, "%s/bodies.xmf", outdir);
        if (out_resume_sidecar(o->h5path, path, &o->xmf, o, NULL, &o->nsnap, err, n) != 0) {
            lahar_body_output_close(o);
            return NULL;
        }
        snprintf(path, sizeof path, "%s/forces.h5", outdir);
        if (c->output_forces && c->nbody > 0 && forces_open(&o->fs, path, c, err, n)) {
            lahar_body_output_close(o);
            return NULL;
        }
        return o;
    }
    hid_t f = out_file_open(o->h5path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file (does the directory exist?)", o->h5path);
        lahar_body_output_close(o);
        return NULL;
    }
    int rc = out_write_header(f, c);
    rc |= out_write_geometry(f, o, c);
    hid_t sg = out_group(f, "snapshots");
    if (sg < 0)
        rc = -1;
    else
        H5Gclose(sg);
    if (H5Fclose(f) < 0)
        rc = -1;
    if (rc) {
        snprintf(err, n, "%s: writing header/geometry failed", o->h5path);
        lahar_body_output_close(o);
        return NULL;
    }
    char path[OUT_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/bodies.xmf", outdir);
    if (lahar_xdmf_open(&o->xmf, path, err, n)) {
        lahar_body_output_close(o);
        return NULL;
    }
    snprintf(path, sizeof path, "%s/forces.h5", outdir);
    if (c->output_forces && c->nbody > 0 && forces_open(&o->fs, path, c, err, n)) {
        lahar_body_output_close(o);
        return NULL;
    }
    return o;
}

int lahar_body_output_snapshot(lahar_body_output *o, int64_t step, double t, const lahar_body_state *s)
{
    /* the force rows so far reach the disk with every snapshot too, even if the run then stalls */
    if (forces_flush(&o->fs))
        fprintf(stderr, "lahar: %s/forces.h5: flushing the force stream failed\n", o->dir);
    int nb = o->nbody;
    double *X = o->state, *Q = X + 3 * nb, *V = Q + 4 * nb, *W = V + 3 * nb;
    int64_t iv = 0;
    for (int b = 0; b < nb; b++) {
        memcpy(X + 3 * b, s[b].x, sizeof s[b].x);
        memcpy(Q + 4 * b, s[b].q, sizeof s[b].q);
        memcpy(V + 3 * b, s[b].v, sizeof s[b].v);
        memcpy(W + 3 * b, s[b].w, sizeof s[b].w);
        if (!o->moving[b])
            continue;
        vec3 x = v3_load(s[b].x), v = v3_load(s[b].v), w = v3_load(s[b].w);
        quat q = q_load(s[b].q);
        const lahar_display_mesh *m = &o->mesh[b];
        for (int i = 0; i < m->nvert; i++, iv++) {
            vec3 r = q_rotate(q, v3_load(m->v[i]));
            vec3 p = v3_add(x, r), u = v3_add(v, v3_cross(w, r)); /* rigid-body velocity of the point */
            o->vert[3 * iv + 0] = (float)p.x, o->vert[3 * iv + 1] = (float)p.y, o->vert[3 * iv + 2] = (float)p.z;
            o->vvel[3 * iv + 0] = (float)u.x, o->vvel[3 * iv + 1] = (float)u.y, o->vvel[3 * iv + 2] = (float)u.z;
        }
    }
    /* the snapshot's data, its object headers, and the XDMF text */
    double need = 8.0 * 13.0 * nb + 24.0 * (double)o->nmoving_vert + 6.0 * 1024.0 + OUT_XML_CAP;
    hid_t f, g = out_snapshot_open(o->h5path, need, "a body snapshot", o->nsnap, step, t, &f);
    if (g == H5I_INVALID_HID && f < 0)
        return -1;
    int rc = g < 0 ? -1 : 0;
    if (g >= 0) {
        rc |= out_dataset(g, "position", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, X);
        rc |= out_dataset(g, "quaternion", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 4, Q);
        rc |= out_dataset(g, "velocity", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, V);
        rc |= out_dataset(g, "angular_velocity", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, W);
        rc |= out_dataset(g, "vertices", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, 2, (hsize_t)o->nmoving_vert, 3, o->vert);
        rc |= out_dataset(g, "vertex_velocity", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, 2, (hsize_t)o->nmoving_vert, 3,
                          o->vvel);
        H5Gclose(g);
    }
    if (out_close(f) < 0)
        rc = -1;
    if (rc) {
        out_write_failed(o->h5path, "a body snapshot", step, t);
        return -1;
    }
    lahar_xdmf_bodies xb;
    out_xdmf_bodies_info(o, &xb);
    size_t len = lahar_xdmf_step_begin(o->xml, OUT_XML_CAP, step, t);
    if (len < OUT_XML_CAP)
        len += lahar_xdmf_bodies_grids(o->xml + len, OUT_XML_CAP - len, &xb, o->nsnap);
    if (len < OUT_XML_CAP)
        len += lahar_xdmf_step_end(o->xml + len, OUT_XML_CAP - len);
    o->nsnap++;
    if (len >= OUT_XML_CAP || lahar_xdmf_append(&o->xmf, o->xml, len, OUT_XML_CAP)) {
        fprintf(stderr, "lahar: %s/bodies.xmf: cannot append step %" PRId64 "\n", o->dir, step);
        return -1;
    }
    return 0;
}

int lahar_body_output_forces(lahar_body_output *o, int64_t step, double t, const lahar_body_report *r)
{
    forces_stream *fs = &o->fs;
    if (fs->file < 0)
        return 0; /* the case turned the force stream off (output: forces) */
    if (fs->interval > 0.0) {
        /* record the first row at or after each multiple of the interval (slot counted in
         * integers, relative tolerance for times that are multiples up to rounding) */
        if (t < (double)fs->next_slot * fs->interval * (1.0 - 1e-12) - 1e-300)
            return 0;
        fs->next_slot = (int64_t)floor(t / fs->interval * (1.0 + 1e-12)) + 1;
    }
    int nb = fs->nbody, i = fs->nbuf;
    fs->bt[i] = t;
    fs->bstep[i] = step;
    for (int b = 0; b < nb; b++) {
        memcpy(fs->bforce + ((size_t)i * nb + b) * 3, r[b].force, 3 * sizeof(double));
        memcpy(fs->btorque + ((size_t)i * nb + b) * 3, r[b].torque, 3 * sizeof(double));
        memcpy(fs->benergy + ((size_t)i * nb + b) * 3, r[b].energy, 3 * sizeof(double));
        fs->bncont[(size_t)i * nb + b] = r[b].ncontacts;
    }
    fs->nbuf++;
    if (fs->nbuf == fs->cap || out_wall_seconds() - fs->last_flush >= FORCES_FLUSH_SECONDS)
        return forces_flush(fs);
    return 0;
}

void lahar_body_output_close(lahar_body_output *o)
{
    if (!o)
        return;
    forces_close(&o->fs);
    lahar_xdmf_close(&o->xmf);
    if (o->mesh)
        for (int b = 0; b < o->nbody; b++)
            lahar_display_mesh_free(&o->mesh[b]);
    int had_snapshots = o->nsnap > 0;
    char dir[OUT_PATH_MAX];
    snprintf(dir, sizeof dir, "%s", o->dir);
    free(o->mesh), free(o->moving), free(o->state), free(o->vert), free(o->vvel), free(o->xml);
    free(o);
    if (had_snapshots) {
        /* best effort: the other writer (another process) may still be writing its file; the
         * coordinator rebuilds lahar.xmf once every node has finished */
        char err[256];
        lahar_output_xdmf_combine(dir, err, sizeof err);
    }
}

/* ---------------------------------------------------------------- particles ------------- */

struct lahar_particle_output {
    char dir[OUT_PATH_MAX];
    char h5path[OUT_PATH_MAX];
    unsigned fields;
    int64_t nsnap;
    lahar_xdmf_file xmf;
    char *xml;
};

lahar_particle_output *lahar_particle_output_open(const char *outdir, const lahar_case *c, unsigned fields,
                                                  char *err, size_t n)
{
    lahar_particle_output *o = calloc(1, sizeof *o);
    char *xml = malloc(OUT_XML_CAP);
    if (!o || !xml) {
        free(o), free(xml);
        snprintf(err, n, "out of memory");
        return NULL;
    }
    o->xml = xml;
    o->xmf.fd = -1;
    o->fields = fields & (LAHAR_PFIELD_ALL | LAHAR_PFIELD_STRESS);
    snprintf(o->dir, sizeof o->dir, "%s", outdir);
    snprintf(o->h5path, sizeof o->h5path, "%s/particles.h5", outdir);
    if (c->resume) { /* continue particles.h5 as the checkpoint left it (lahar_output_resume_trim) */
        char path[OUT_PATH_MAX + 16];
        snprintf(path, sizeof path, "%s/particles.xmf", outdir);
        if (out_resume_sidecar(o->h5path, path, &o->xmf, NULL, &o->fields, &o->nsnap, err, n) != 0) {
            lahar_particle_output_close(o);
            return NULL;
        }
        return o;
    }
    hid_t f = out_file_open(o->h5path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file", o->h5path);
        lahar_particle_output_close(o);
        return NULL;
    }
    int rc = 0;
    hid_t h = out_header_group(f, c);
    if (h < 0)
        rc = -1;
    else {
        rc |= out_attr_int64(h, "fields", o->fields);
        rc |= out_attr_string(h, "field_bits", "1 velocity (vx,vy,vz), 2 density, 4 pressure, 8 phase, 16 id, "
                                               "32 stress (n x 6: xx, xy, xz, yy, yz, zz)");
        rc |= out_attr_double(h, "dx", c->sph_dx);
        rc |= out_attr_double(h, "rest_density", c->sph_density);
        H5Gclose(h);
    }
    hid_t sg = out_group(f, "snapshots");
    if (sg < 0)
        rc = -1;
    else
        H5Gclose(sg);
    if (H5Fclose(f) < 0 || rc) {
        snprintf(err, n, "%s: writing the header failed", o->h5path);
        lahar_particle_output_close(o);
        return NULL;
    }
    char path[OUT_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/particles.xmf", outdir);
    if (lahar_xdmf_open(&o->xmf, path, err, n)) {
        lahar_particle_output_close(o);
        return NULL;
    }
    return o;
}

/* The soil stress as one n x 6 dataset (rows xx, xy, xz, yy, yz, zz), interleaved from the SoA
 * arrays of the view in a buffer that lives for this snapshot only. */
static int out_particle_stress(hid_t g, const lahar_particles_view *p)
{
    hsize_t n = (hsize_t)(p->n > 0 ? p->n : 0);
    for (int a = 0; a < 6; a++)
        if (!p->stress[a] && n > 0) {
            fprintf(stderr, "lahar: particle snapshot: field stress selected but not given\n");
            return -1;
        }
    double *buf = malloc((n > 0 ? n : 1) * 6 * sizeof *buf);
    if (!buf)
        return -1;
    for (hsize_t i = 0; i < n; i++)
        for (int a = 0; a < 6; a++)
            buf[i * 6 + (hsize_t)a] = p->stress[a][i];
    int rc = out_dataset(g, "stress", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, n, 6, buf);
    free(buf);
    return rc;
}

int lahar_particle_output_snapshot(lahar_particle_output *o, int64_t step, double t, const lahar_particles_view *p)
{
    /* at most 17 values of 8 bytes per particle (position, velocity, density, pressure, phase,
     * id, stress), the datasets' headers and the XDMF text */
    double need = 17.0 * 8.0 * (double)(p->n > 0 ? p->n : 0) + 16.0 * 1024.0 + OUT_XML_CAP;
    hid_t f, g = out_snapshot_open(o->h5path, need, "a particle snapshot", o->nsnap, step, t, &f);
    if (g == H5I_INVALID_HID && f < 0)
        return -1;
    int rc = g < 0 ? -1 : 0;
    hsize_t n = (hsize_t)(p->n > 0 ? p->n : 0);
    if (g >= 0) {
        rc |= out_attr_int64(g, "n", (int64_t)n);
        const struct {
            unsigned field;
            const char *name;
            hid_t mt, ft;
            const void *data;
        } col[] = {
            {0, "x", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->x},
            {0, "y", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->y},
            {0, "z", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->z},
            {LAHAR_PFIELD_VELOCITY, "vx", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->vx},
            {LAHAR_PFIELD_VELOCITY, "vy", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->vy},
            {LAHAR_PFIELD_VELOCITY, "vz", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->vz},
            {LAHAR_PFIELD_DENSITY, "density", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->density},
            {LAHAR_PFIELD_PRESSURE, "pressure", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, p->pressure},
            {LAHAR_PFIELD_PHASE, "phase", H5T_NATIVE_INT32, H5T_STD_I32LE, p->phase},
            {LAHAR_PFIELD_ID, "id", H5T_NATIVE_INT64, H5T_STD_I64LE, p->id},
        };
        for (size_t k = 0; k < sizeof col / sizeof col[0] && !rc; k++) {
            if (col[k].field && !(o->fields & col[k].field))
                continue;
            if (!col[k].data && n > 0) {
                if (col[k].field == 0 && col[k].name[0] == 'z') {
                    /* 2D: z is never written, the dataset's fill value (0) stands for it */
                    hid_t sp = H5Screate_simple(1, &n, NULL);
                    hid_t dcpl = out_dcpl();
                    hid_t ds = H5Dcreate2(g, "z", H5T_IEEE_F64LE, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
                    H5Pclose(dcpl);
                    if (ds < 0)
                        rc = -1;
                    else
                        H5Dclose(ds);
                    H5Sclose(sp);
                    continue;
                }
                fprintf(stderr, "lahar: particle snapshot: field %s selected but not given\n", col[k].name);
                rc = -1;
                break;
            }
            rc |= out_dataset(g, col[k].name, col[k].mt, col[k].ft, 1, n, 0, col[k].data);
        }
        if (!rc && (o->fields & LAHAR_PFIELD_STRESS))
            rc |= out_particle_stress(g, p);
        if (!rc && p->inlet)
            rc |= out_dataset(g, "inlet", H5T_NATIVE_INT32, H5T_STD_I32LE, 1, n, 0, p->inlet);
        for (int k = 0; p->flow && k < LAHAR_FLOW_NVAL && !rc; k++)
            rc |= out_attr_double(g, lahar_flow_names[k], p->flow[k]);
        H5Gclose(g);
    }
    if (out_close(f) < 0)
        rc = -1;
    if (rc) {
        out_write_failed(o->h5path, "a particle snapshot", step, t);
        return -1;
    }
    lahar_xdmf_particles xp = {"particles.h5", o->fields};
    size_t len = lahar_xdmf_step_begin(o->xml, OUT_XML_CAP, step, t);
    if (len < OUT_XML_CAP)
        len += lahar_xdmf_particles_grid(o->xml + len, OUT_XML_CAP - len, &xp, o->nsnap, (int64_t)n);
    if (len < OUT_XML_CAP)
        len += lahar_xdmf_step_end(o->xml + len, OUT_XML_CAP - len);
    o->nsnap++;
    if (len >= OUT_XML_CAP || lahar_xdmf_append(&o->xmf, o->xml, len, OUT_XML_CAP)) {
        fprintf(stderr, "lahar: %s/particles.xmf: cannot append step %" PRId64 "\n", o->dir, step);
        return -1;
    }
    return 0;
}

void lahar_particle_output_close(lahar_particle_output *o)
{
    if (!o)
        return;
    lahar_xdmf_close(&o->xmf);
    int had_snapshots = o->nsnap > 0;
    char dir[OUT_PATH_MAX];
    snprintf(dir, sizeof dir, "%s", o->dir);
    free(o->xml);
    free(o);
    if (had_snapshots) {
        /* best effort: the other writer (another process) may still be writing its file; the
         * coordinator rebuilds lahar.xmf once every node has finished */
        char err[256];
        lahar_output_xdmf_combine(dir, err, sizeof err);
    }
}

/* ---------------------------------------------------------------- combined XDMF --------- */

typedef struct {
    int64_t step, snap, n;
    double t;
} out_snap_entry;

/* Read (step, time, n) of every snapshot group in OUT/<name>; returns the count or -1. A
 * missing file gives 0. */
static int64_t out_read_snapshot_list(const char *path, out_snap_entry **list)
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

static int out_resume_sidecar(const char *h5path, const char *xmfpath, lahar_xdmf_file *xmf,
                              const lahar_body_output *bodies, const unsigned *fields, int64_t *nsnap, char *err,
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
            lahar_xdmf_bodies xb;
            out_xdmf_bodies_info(bodies, &xb);
            if (len < OUT_XML_CAP)
                len += lahar_xdmf_bodies_grids(xml + len, OUT_XML_CAP - len, &xb, k);
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

int lahar_body_output_sync(lahar_body_output *o)
{
    if (!o || o->fs.file < 0)
        return 0;
    int rc = forces_flush(&o->fs);
    return H5Fflush(o->fs.file, H5F_SCOPE_GLOBAL) < 0 ? -1 : rc;
}

static int out_read_attr_int64(hid_t loc, const char *obj, const char *name, int64_t *v)
{
    *v = 0;
    if (H5Aexists_by_name(loc, obj, name, H5P_DEFAULT) <= 0)
        return -1;
    hid_t a = H5Aopen_by_name(loc, obj, name, H5P_DEFAULT, H5P_DEFAULT);
    herr_t rc = H5Aread(a, H5T_NATIVE_INT64, v);
    H5Aclose(a);
    return rc < 0 ? -1 : 0;
}

static int out_xdmf_combine(const char *outdir, char *err, size_t n);

int lahar_output_xdmf_combine(const char *outdir, char *err, size_t n)
{
    /* files still being written may not open cleanly: one message, no HDF5 error stacks */
    H5E_auto2_t func;
    void *data;
    H5Eget_auto2(H5E_DEFAULT, &func, &data);
    H5Eset_auto2(H5E_DEFAULT, NULL, NULL);
    int rc = out_xdmf_combine(outdir, err, n);
    H5Eset_auto2(H5E_DEFAULT, func, data);
    return rc;
}

static int out_xdmf_combine(const char *outdir, char *err, size_t n)
{
    char bpath[OUT_PATH_MAX + 16], ppath[OUT_PATH_MAX + 16], xpath[OUT_PATH_MAX + 16], tpath[OUT_PATH_MAX + 32];
    snprintf(bpath, sizeof bpath, "%s/bodies.h5", outdir);
    snprintf(ppath, sizeof ppath, "%s/particles.h5", outdir);
    snprintf(xpath, sizeof xpath, "%s/lahar.xmf", outdir);
    snprintf(tpath, sizeof tpath, "%s/.lahar.xmf.%d.tmp", outdir, (int)getpid());
    out_snap_entry *bl = NULL, *pl = NULL;
    int64_t nbs = out_read_snapshot_list(bpath, &bl), nps = out_read_snapshot_list(ppath, &pl);
    if (nbs < 0 || nps < 0) {
        free(bl), free(pl);
        snprintf(err, n, "%s: cannot read the snapshot lists of bodies.h5/particles.h5", outdir);
        return -1;
    }
    lahar_xdmf_bodies xb = {"bodies.h5", 0, 3, 0, 0, 0, 0};
    lahar_xdmf_particles xp = {"particles.h5", 0};
    if (nbs > 0) {
        hid_t f = out_file_open(bpath, H5F_ACC_RDONLY, 0);
        int64_t v[6] = {0};
        if (f >= 0) {
            out_read_attr_int64(f, "header", "nbody", &v[0]);
            out_read_attr_int64(f, "geometry", "nodes_per_cell", &v[1]);
            out_read_attr_int64(f, "geometry", "moving_vertices", &v[2]);
            out_read_attr_int64(f, "geometry", "moving_cells", &v[3]);
            out_read_attr_int64(f, "geometry", "fixed_vertices", &v[4]);
            out_read_attr_int64(f, "geometry", "fixed_cells", &v[5]);
            H5Fclose(f);
        }
        xb.nbody = (int)v[0], xb.nodes_per_cell = (int)v[1], xb.moving_vertices = v[2], xb.moving_cells = v[3];
        xb.fixed_vertices = v[4], xb.fixed_cells = v[5];
    }
    if (nps > 0) {
        hid_t f = out_file_open(ppath, H5F_ACC_RDONLY, 0);
        int64_t v = 0;
        if (f >= 0) {
            out_read_attr_int64(f, "header", "fields", &v);
            H5Fclose(f);
        }
        xp.fields = (unsigned)v;
    }
    FILE *fp = fopen(tpath, "w");
    char *buf = malloc(OUT_XML_CAP);
    if (!fp || !buf) {
        if (fp)
            fclose(fp);
        free(buf), free(bl), free(pl);
        snprintf(err, n, "%s: cannot write (%s)", tpath, strerror(errno));
        return -1;
    }
    fputs("<?xml version=\"1.0\" ?>\n<!DOCTYPE Xdmf SYSTEM \"Xdmf.dtd\" []>\n<Xdmf Version=\"2.0\">\n <Domain>\n"
          "  <Grid Name=\"lahar\" GridType=\"Collection\" CollectionType=\"Temporal\">\n",
          fp);
    /* merge the two lists by step: a time step holds whatever was written at that step */
    int64_t i = 0, j = 0;
    while (i < nbs || j < nps) {
        int take_b = i < nbs && (j >= nps || bl[i].step <= pl[j].step);
        int take_p = j < nps && (i >= nbs || pl[j].step <= bl[i].step);
        const out_snap_entry *e = take_b ? &bl[i] : &pl[j];
        size_t len = lahar_xdmf_step_begin(buf, OUT_XML_CAP, e->step, e->t);
        if (take_b && len < OUT_XML_CAP)
            len += lahar_xdmf_bodies_grids(buf + len, OUT_XML_CAP - len, &xb, bl[i].snap);
        if (take_p && len < OUT_XML_CAP)
            len += lahar_xdmf_particles_grid(buf + len, OUT_XML_CAP - len, &xp, pl[j].snap, pl[j].n);
        if (len < OUT_XML_CAP)
            len += lahar_xdmf_step_end(buf + len, OUT_XML_CAP - len);
        if (len < OUT_XML_CAP)
            fwrite(buf, 1, len, fp);
        i += take_b;
        j += take_p;
    }
    fputs("  </Grid>\n </Domain>\n</Xdmf>\n", fp);
    int rc = ferror(fp) ? -1 : 0;
    if (fclose(fp))
        rc = -1;
    free(buf), free(bl), free(pl);
    if (rc || rename(tpath, xpath)) {
        remove(tpath);
        snprintf(err, n, "%s: cannot write (%s)", xpath, strerror(errno));
        return -1;
    }
    return 0;
}

/* ---------------------------------------------------------------- contact points -------- */

struct lahar_contact_output {
    char h5path[OUT_PATH_MAX];
    int nbody;         /* bodies of the case */
    int nmarked;
    int *marked;       /* body indices marked record_contacts */
    char (*group)[LAHAR_NAME_MAX + 16]; /* per marked body: its group name in a snapshot */
    int *slot;         /* per body of the case: index into the listed bodies of the current write, -1 */
    int64_t *offset;   /* per body of the case: first point in x/f of the current write */
    int64_t nsnap;
};

void lahar_contact_output_close(lahar_contact_output *o)
{
    if (!o)
        return;
    free(o->marked);
    free(o->group);
    free(o->slot);
    free(o->offset);
    free(o);
}

lahar_contact_output *lahar_contact_output_open(const char *outdir, const lahar_case *c, char *err, size_t n)
{
    err[0] = '\0';
    int nmarked = 0;
    for (int b = 0; b < c->nbody; b++)
        nmarked += c->bodies[b].record_contacts != 0;
    if (nmarked == 0)
        return NULL;
    lahar_contact_output *o = calloc(1, sizeof *o);
    if (o) {
        o->marked = calloc((size_t)nmarked, sizeof *o->marked);
        o->group = calloc((size_t)nmarked, sizeof *o->group);
        o->slot = calloc((size_t)c->nbody, sizeof *o->slot);
        o->offset = calloc((size_t)c->nbody, sizeof *o->offset);
    }
    if (!o || !o->marked || !o->group || !o->slot || !o->offset) {
        lahar_contact_output_close(o);
        snprintf(err, n, "out of memory");
        return NULL;
    }
    o->nbody = c->nbody;
    for (int b = 0; b < c->nbody; b++)
        if (c->bodies[b].record_contacts) {
            int m = o->nmarked++;
            o->marked[m] = b;
            const char *name = c->bodies[b].name;
            /* the body's name, unless HDF5 cannot take it as a link name */
            if (name[0] && !strchr(name, '/') && strcmp(name, ".") != 0)
                snprintf(o->group[m], sizeof o->group[m], "%s", name);
            else
                snprintf(o->group[m], sizeof o->group[m], "body_%d", b);
        }
    snprintf(o->h5path, sizeof o->h5path, "%s/contacts.h5", outdir);
    if (c->resume) { /* continue contacts.h5 as the checkpoint left it */
        out_snap_entry *list = NULL;
        int64_t cnt = out_read_snapshot_list(o->h5path, &list);
        free(list);
        if (cnt < 0) {
            snprintf(err, n, "%s: cannot read it to continue it", o->h5path);
            lahar_contact_output_close(o);
            return NULL;
        }
        o->nsnap = cnt;
        return o;
    }
    hid_t f = out_file_open(o->h5path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file", o->h5path);
        lahar_contact_output_close(o);
        return NULL;
    }
    int rc = 0;
    hid_t h = out_header_group(f, c);
    if (h < 0)
        rc = -1;
    else {
        rc |= out_attr_string(h, "contents",
                              "per snapshot and marked body: points (virtual particles on the surface, world frame, m) "
                              "and forces on the body at them (N, N/m in 2D); attributes force and torque (about the "
                              "centre of mass) are their resultants. Forces of the SPH node at the snapshot time.");
        const char **gn = malloc((size_t)o->nmarked * sizeof *gn);
        if (!gn)
            rc = -1;
        for (int m = 0; m < o->nmarked && gn; m++)
            gn[m] = o->group[m];
        if (!rc) {
            rc |= out_strings(h, "groups", o->nmarked, gn);
            rc |= out_dataset(h, "body_index", H5T_NATIVE_INT, H5T_STD_I32LE, 1, (hsize_t)o->nmarked, 0, o->marked);
        }
        free(gn);
        H5Gclose(h);
    }
    hid_t sg = out_group(f, "snapshots");
    if (sg < 0)
        rc = -1;
    else
        H5Gclose(sg);
    if (H5Fclose(f) < 0 || rc) {
        snprintf(err, n, "%s: writing the header failed", o->h5path);
        lahar_contact_output_close(o);
        return NULL;
    }
    return o;
}

int lahar_contact_output_write(lahar_contact_output *o, int64_t step, double t, int nlisted, const int32_t *body_id,
                               const int32_t *npoints, const double (*x)[3], const double (*f)[3],
                               const double (*force)[3], const double (*torque)[3])
{
    if (!o)
        return 0;
    for (int b = 0; b < o->nbody; b++)
        o->slot[b] = -1;
    int64_t off = 0;
    for (int i = 0; i < nlisted; i++) {
        int b = body_id[i];
        if (b >= 0 && b < o->nbody) {
            o->slot[b] = i;
            o->offset[b] = off;
        }
        off += npoints[i];
    }
    double need = 48.0 * (double)off + 4096.0 * (o->nmarked + 1);
    hid_t file, g = out_snapshot_open(o->h5path, need, "the contact points", o->nsnap, step, t, &file);
    if (g == H5I_INVALID_HID && file < 0)
        return -1;
    int rc = g < 0 ? -1 : 0;
    if (g >= 0) {
        for (int m = 0; m < o->nmarked && !rc; m++) {
            int b = o->marked[m], i = o->slot[b];
            hid_t bg = out_group(g, o->group[m]);
            if (bg < 0) {
                rc = -1;
                break;
            }
            static const double zero[3] = {0.0, 0.0, 0.0};
            hsize_t np = i >= 0 ? (hsize_t)npoints[i] : 0;
            const double *pts = np ? x[o->offset[b]] : zero, *fs = np ? f[o->offset[b]] : zero;
            rc |= out_attr_int64(bg, "n", (int64_t)np);
            rc |= out_attr(bg, "force", H5T_NATIVE_DOUBLE, 3, i >= 0 ? force[i] : zero);
            rc |= out_attr(bg, "torque", H5T_NATIVE_DOUBLE, 3, i >= 0 ? torque[i] : zero);
            rc |= out_dataset(bg, "points", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, np, 3, pts);
            rc |= out_dataset(bg, "forces", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, np, 3, fs);
            H5Gclose(bg);
        }
        H5Gclose(g);
    }
    if (out_close(file) < 0)
        rc = -1;
    if (rc) {
        out_write_failed(o->h5path, "the contact points", step, t);
        return -1;
    }
    o->nsnap++;
    return 0;
}

/* ---------------------------------------------------------------- final snapshot of a failed run -- */

int lahar_output_mark_last_snapshot(const char *outdir, const char *file, const char *name, const char *text)
{
    char path[OUT_PATH_MAX + 64];
    snprintf(path, sizeof path, "%s/%s", outdir, file);
    if (access(path, F_OK) != 0)
        return -1;
    double avail = lahar_output_free_bytes(outdir);
    if (avail >= 0.0 && avail < LAHAR_OUTPUT_RESERVE) {
        fprintf(stderr, "lahar: %s: the last snapshot is not marked (no space left on device: %.0f bytes free)\n",
                path, avail);
        return -1;
    }
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
    if (rc)
        fprintf(stderr, "lahar: %s: cannot mark the last snapshot\n", path);
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

const char *const lahar_output_run_files[] = {
    "summary.json", "check.json", "check.png",   "lahar.xmf", "bodies.h5", "bodies.xmf",
    "particles.h5", "particles.xmf", "forces.h5", "contacts.h5", "gauges.h5", NULL,
};

/* ---------------------------------------------------------------- gauges ---------------- */

#define GAUGE_BUFFER_ROWS 1024

typedef struct {
    hid_t t, step, v[LAHAR_PROBE_MAX_VALUES];
    int nv;                /* values per row (lahar_probe_nvalues) */
    int64_t rows;
    int nbuf;
    double *bt, *bp;       /* bp: value c of buffered row i at bp[c * GAUGE_BUFFER_ROWS + i] */
    int64_t *bstep;
} gauge_stream;

/* Where a gauge of this kind lives in gauges.h5, and its value datasets with their units. */
static const char *gauge_group(int kind)
{
    return kind == LAHAR_PROBE_TRACKER ? "trackers" : kind == LAHAR_PROBE_CONTROL_VOLUME ? "control_volumes" : "probes";
}

static const char *gauge_value_name(int kind, int c)
{
    static const char *const tr[] = {"x", "y", "z", "vx", "vy", "vz", "id"};
    static const char *const cv[] = {"ek", "ek_water", "ek_soil", "ek_bodies", "mass_water", "mass_soil",
                                     "flux_water", "flux_soil"};
    return kind == LAHAR_PROBE_TRACKER ? tr[c] : kind == LAHAR_PROBE_CONTROL_VOLUME ? cv[c]
                                                 : kind == LAHAR_PROBE_LEVEL ? "h" : "p";
}

static const char *gauge_value_units(int kind, int c, int dim)
{
    if (kind == LAHAR_PROBE_TRACKER)
        return c < 3 ? "m" : c < 6 ? "m/s" : "";
    if (kind == LAHAR_PROBE_CONTROL_VOLUME)
        return c < 4 ? (dim == 2 ? "J/m" : "J") : c < 6 ? (dim == 2 ? "kg/m" : "kg") : (dim == 2 ? "kg/(m s)" : "kg/s");
    return kind == LAHAR_PROBE_LEVEL ? "m" : "Pa";
}

struct lahar_gauge_output {
    hid_t file;
    char path[OUT_PATH_MAX + 16];
    int failed;
    int n;
    gauge_stream *g;
    double last_flush;
};

static int gauge_flush(lahar_gauge_output *o)
{
    if (o->failed)
        return -1;
    int rc = 0;
    double need = 0.0;
    int64_t last_step = 0;
    double last_t = 0.0;
    for (int k = 0; k < o->n; k++)
        if (o->g[k].nbuf > 0) {
            need += 8.0 * (2 + o->g[k].nv) * (o->g[k].nbuf + GAUGE_BUFFER_ROWS); /* rows, and the chunks they may open */
            last_step = o->g[k].bstep[o->g[k].nbuf - 1];
            last_t = o->g[k].bt[o->g[k].nbuf - 1];
        }
    if (need > 0.0 && out_room(o->path, need, "the gauge rows", last_step, last_t) != 0) {
        o->failed = 1;
        return -1;
    }
    for (int k = 0; k < o->n; k++) {
        gauge_stream *g = &o->g[k];
        if (g->nbuf == 0)
            continue;
        hsize_t rows = (hsize_t)g->nbuf, start = (hsize_t)g->rows;
        struct {
            hid_t id, mtype;
            const void *buf;
        } ds[LAHAR_PROBE_MAX_VALUES + 2];
        int nds = 0;
        ds[nds].id = g->step, ds[nds].mtype = H5T_NATIVE_INT64, ds[nds++].buf = g->bstep;
        for (int c = 0; c < g->nv; c++)
            ds[nds].id = g->v[c], ds[nds].mtype = H5T_NATIVE_DOUBLE, ds[nds++].buf = g->bp + (size_t)c * GAUGE_BUFFER_ROWS;
        ds[nds].id = g->t, ds[nds].mtype = H5T_NATIVE_DOUBLE, ds[nds++].buf = g->bt;
        /* t last: a SWMR reader that sees n rows of t finds them in step and the values */
        for (int d = 0; d < nds; d++)
            if (out_append_rows(ds[d].id, ds[d].mtype, 1, start, rows, 0, ds[d].buf) != 0)
                rc = -1;
        g->rows += g->nbuf;
        g->nbuf = 0;
    }
    o->last_flush = out_wall_seconds();
    if (rc) {
        out_write_failed(o->path, "the gauge rows", last_step, last_t);
        o->failed = 1;
    }
    return rc;
}

/* The description attribute of gauges.h5: what each kind of probe writes, and how. */
static const char gauge_file_description[] =
    "probes (case section probes:): per probe /probes/NAME/t (s), step and p (Pa, gauge: 0 at "
    "the free surface; kind pressure) or h (m; kind level). Fluid points: Shepard "
    "interpolation of the water particles' pressure (DualSPHysics MeasureTool, dry below sum "
    "V W = 0.5: 0). Points on a body: Adami, Hu & Adams 2012 eq. 27 at the surface point (dry "
    "below sum V W = 0.1: 0), averaged over the sensor's segment (2D) or disc (3D) of diameter "
    "size. Level gauges: the top of the water column on the floor along the vertical line from "
    "position (on the floor) up to top, the first point going up where sum V W (mirrored at "
    "the floor) falls to 0.5, above the floor (0: dry). trackers (case section trackers:): "
    "per tracker /trackers/NAME/t, step, x, y, z (m), vx, vy, vz (m/s) of the particle nearest "
    "its position at t = 0 and that particle's id. control volumes (control_volumes:): per "
    "box /control_volumes/NAME/t, step, ek (sum of m |v|^2 / 2 of the particles and bodies "
    "inside, Trujillo-Vela et al. 2020 eq. 39), ek_water, ek_soil, ek_bodies (its parts; a "
    "body counts when its centre is inside), mass_water, mass_soil (particle mass inside), "
    "flux_water, flux_soil (sum of m v_axis inside / the box's length along axis: the mean "
    "mass flow rate through its cross-section). 2D: per unit thickness";

/* The streams of every probe, with their write buffers; no file yet. */
static lahar_gauge_output *gauge_output_alloc(const lahar_case *c, char *err, size_t n)
{
    lahar_gauge_output *o = calloc(1, sizeof *o);
    if (!o || !(o->g = calloc((size_t)c->nprobe, sizeof *o->g))) {
        free(o);
        snprintf(err, n, "out of memory for the gauge stream");
        return NULL;
    }
    o->n = c->nprobe;
    o->file = H5I_INVALID_HID;
    for (int k = 0; k < o->n; k++) {
        gauge_stream *g = &o->g[k];
        g->t = g->step = H5I_INVALID_HID;
        g->nv = lahar_probe_nvalues(c->probes[k].kind);
        for (int v = 0; v < LAHAR_PROBE_MAX_VALUES; v++)
            g->v[v] = H5I_INVALID_HID;
        g->bt = malloc(GAUGE_BUFFER_ROWS * sizeof *g->bt);
        g->bp = malloc((size_t)g->nv * GAUGE_BUFFER_ROWS * sizeof *g->bp);
        g->bstep = malloc(GAUGE_BUFFER_ROWS * sizeof *g->bstep);
        if (!g->bt || !g->bp || !g->bstep) {
            snprintf(err, n, "out of memory for the gauge stream");
            lahar_gauge_output_close(o);
            return NULL;
        }
    }
    return o;
}

/* A resumed run: each probe's datasets as lahar_output_resume_trim left them, and their rows. */
static int gauge_output_reopen(lahar_gauge_output *o, const lahar_case *c, hid_t fapl)
{
    o->file = lahar_h5_file_open(o->path, H5F_ACC_RDWR, fapl, 0);
    int rc = o->file < 0 ? -1 : 0;
    for (int k = 0; k < o->n && !rc; k++) {
        gauge_stream *g = &o->g[k];
        char name[LAHAR_NAME_MAX + 48];
        const int kind = c->probes[k].kind;
        for (int d = -2; d < g->nv && !rc; d++) {
            hid_t *id = d == -2 ? &g->t : d == -1 ? &g->step : &g->v[d];
            snprintf(name, sizeof name, "%s/%s/%s", gauge_group(kind), c->probes[k].name,
                     d == -2 ? "t" : d == -1 ? "step" : gauge_value_name(kind, d));
            if ((*id = H5Dopen2(o->file, name, H5P_DEFAULT)) < 0)
                rc = -1;
        }
        if (!rc) {
            hid_t sp = H5Dget_space(g->t);
            hsize_t rows = 0;
            H5Sget_simple_extent_dims(sp, &rows, NULL);
            H5Sclose(sp);
            g->rows = (int64_t)rows;
        }
    }
    return rc;
}

/* The attributes of probe pr's group: its kind, where it is, its rate, and how it measures. */
static int gauge_probe_attrs(hid_t gg, const lahar_case *c, const lahar_probe *pr)
{
    int rc = 0;
    const int kind = pr->kind, level = kind == LAHAR_PROBE_LEVEL;
    if (kind == LAHAR_PROBE_TRACKER || kind == LAHAR_PROBE_CONTROL_VOLUME) {
        const int tr = kind == LAHAR_PROBE_TRACKER;
        rc |= out_attr_string(gg, "kind", tr ? "tracker" : "control_volume");
        rc |= out_attr(gg, tr ? "position" : "lo", H5T_NATIVE_DOUBLE, 3, pr->x);
        if (!tr) {
            rc |= out_attr(gg, "hi", H5T_NATIVE_DOUBLE, 3, pr->hi);
            rc |= out_attr_string(gg, "axis", pr->axis == 0 ? "x" : pr->axis == 1 ? "y" : "z");
        }
        rc |= out_attr_double(gg, "rate", pr->rate);
        return rc;
    }
    rc |= out_attr_string(gg, "kind", level ? "level" : "pressure");
    rc |= out_attr(gg, "position", H5T_NATIVE_DOUBLE, 3, pr->x);
    if (level) {
        rc |= out_attr_double(gg, "floor", pr->x[c->dim - 1]);
        rc |= out_attr_double(gg, "top", pr->top);
    }
    rc |= out_attr_string(gg, "body", pr->body >= 0 ? c->bodies[pr->body].name : "");
    if (pr->body >= 0)
        rc |= out_attr(gg, "normal", H5T_NATIVE_DOUBLE, 3, pr->n);
    rc |= out_attr_double(gg, "size", pr->size);
    rc |= out_attr_double(gg, "rate", pr->rate);
    rc |= out_attr_string(gg, "method", level ? "level: first z up from the floor with sum V W = 0.5"
                                        : pr->body >= 0 ? "wall: Adami, Hu & Adams 2012 eq. 27"
                                                        : "fluid: Shepard interpolation (DualSPHysics MeasureTool)");
    return rc;
}

/* A probe's extendible datasets (t, step and its values; chunks of the write buffer's rows). */
static int gauge_probe_datasets(hid_t gg, gauge_stream *g, int kind, int dim)
{
    struct {
        hid_t *id;
        const char *name, *units;
        hid_t type;
    } ds[LAHAR_PROBE_MAX_VALUES + 2] = {{&g->t, "t", "s", H5T_IEEE_F64LE}, {&g->step, "step", "", H5T_STD_I64LE}};
    for (int v = 0; v < g->nv; v++) {
        ds[2 + v].id = &g->v[v];
        ds[2 + v].name = gauge_value_name(kind, v);
        ds[2 + v].units = gauge_value_units(kind, v, dim);
        ds[2 + v].type = H5T_IEEE_F64LE;
    }
    int rc = 0;
    for (int d = 0; d < 2 + g->nv; d++) {
        hsize_t dim0 = 0, maxd = H5S_UNLIMITED, ch = GAUGE_BUFFER_ROWS;
        hid_t sp = H5Screate_simple(1, &dim0, &maxd), dcpl = out_dcpl();
        H5Pset_chunk(dcpl, 1, &ch);
        *ds[d].id = H5Dcreate2(gg, ds[d].name, ds[d].type, sp, H5P_DEFAULT, dcpl, H5P_DEFAULT);
        H5Pclose(dcpl);
        H5Sclose(sp);
        if (*ds[d].id < 0 || (ds[d].units[0] && out_attr_string(*ds[d].id, "units", ds[d].units)))
            rc = -1;
    }
    return rc;
}

/* Probe k's group under its kind's top group (created by the kind's first probe), its attributes
 * and datasets. */
static int gauge_probe_create(lahar_gauge_output *o, const lahar_case *c, int k)
{
    const lahar_probe *pr = &c->probes[k];
    const char *top = gauge_group(pr->kind);
    hid_t pg = H5Lexists(o->file, top, H5P_DEFAULT) > 0 ? H5Gopen2(o->file, top, H5P_DEFAULT) : out_group(o->file, top);
    if (pg < 0)
        return -1;
    hid_t gg = out_group(pg, pr->name);
    H5Gclose(pg);
    if (gg < 0)
        return -1;
    int rc = gauge_probe_attrs(gg, c, pr);
    rc |= gauge_probe_datasets(gg, &o->g[k], pr->kind, c->dim);
    H5Gclose(gg);
    return rc;
}

/* A new gauges.h5: the case's header, the file's attributes, every probe's group, and the names
 * of the pressure and level probes. */
static int gauge_output_create(lahar_gauge_output *o, const lahar_case *c)
{
    int rc = 0;
    hid_t h = out_header_group(o->file, c);
    if (h < 0)
        rc = -1;
    else
        H5Gclose(h);
    rc |= out_attr_string(o->file, "units", "SI");
    rc |= out_attr_string(o->file, "description", gauge_file_description);
    rc |= out_attr_string(o->file, "lahar_version", LAHAR_VERSION);
    for (int k = 0; k < o->n && !rc; k++)
        rc = gauge_probe_create(o, c, k);
    const char **names = malloc((size_t)o->n * sizeof *names);
    if (!names)
        return -1;
    int nnames = 0;
    for (int k = 0; k < o->n; k++)
        if (c->probes[k].kind <= LAHAR_PROBE_LEVEL)
            names[nnames++] = c->probes[k].name;
    hid_t st = out_str_type();
    if (nnames > 0)
        rc |= out_attr(o->file, "probe_names", st, nnames, names);
    H5Tclose(st);
    free(names);
    return rc;
}

lahar_gauge_output *lahar_gauge_output_open(const char *outdir, const lahar_case *c, char *err, size_t n)
{
    if (n)
        err[0] = '\0';
    if (c->nprobe <= 0)
        return NULL;
    lahar_gauge_output *o = gauge_output_alloc(c, err, n);
    if (!o)
        return NULL;
    snprintf(o->path, sizeof o->path, "%s/gauges.h5", outdir);
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_libver_bounds(fapl, H5F_LIBVER_LATEST, H5F_LIBVER_LATEST);
    if (c->resume) { /* continue the stream as lahar_output_resume_trim left it */
        int rc = gauge_output_reopen(o, c, fapl);
        H5Pclose(fapl);
        if (rc || H5Fstart_swmr_write(o->file) < 0) {
            snprintf(err, n, "%s: cannot reopen the probe streams to continue them", o->path);
            lahar_gauge_output_close(o);
            return NULL;
        }
    } else {
        o->file = lahar_h5_file_open(o->path, H5F_ACC_TRUNC, fapl, 1);
        H5Pclose(fapl);
        if (o->file < 0) {
            snprintf(err, n, "%s: cannot create HDF5 file", o->path);
            lahar_gauge_output_close(o);
            return NULL;
        }
        if (gauge_output_create(o, c) != 0 || H5Fstart_swmr_write(o->file) < 0) {
            snprintf(err, n, "%s: cannot create the gauge datasets / start SWMR writing", o->path);
            lahar_gauge_output_close(o);
            return NULL;
        }
    }
    o->last_flush = out_wall_seconds();
    return o;
}

int lahar_gauge_output_write(lahar_gauge_output *o, int64_t step, double t, const double *p, const int *due)
{
    if (!o)
        return 0;
    int full = 0, off = 0;
    for (int k = 0; k < o->n; k++) {
        gauge_stream *g = &o->g[k];
        off += g->nv;
        if (!due[k])
            continue;
        g->bt[g->nbuf] = t;
        g->bstep[g->nbuf] = step;
        for (int c = 0; c < g->nv; c++)
            g->bp[(size_t)c * GAUGE_BUFFER_ROWS + g->nbuf] = p[off - g->nv + c];
        full |= ++g->nbuf == GAUGE_BUFFER_ROWS;
    }
    if (full || out_wall_seconds() - o->last_flush >= FORCES_FLUSH_SECONDS)
        return gauge_flush(o);
    return 0;
}

int lahar_gauge_output_sync(lahar_gauge_output *o)
{
    if (!o || o->file < 0)
        return 0;
    int rc = gauge_flush(o);
    return H5Fflush(o->file, H5F_SCOPE_GLOBAL) < 0 ? -1 : rc;
}

void lahar_gauge_output_close(lahar_gauge_output *o)
{
    if (!o)
        return;
    if (o->file >= 0)
        gauge_flush(o);
    for (int k = 0; k < o->n; k++) {
        gauge_stream *g = &o->g[k];
        if (g->t >= 0)
            H5Dclose(g->t);
        if (g->step >= 0)
            H5Dclose(g->step);
        for (int v = 0; v < g->nv; v++)
            if (g->v[v] >= 0)
                H5Dclose(g->v[v]);
        free(g->bt), free(g->bp), free(g->bstep);
    }
    if (o->file >= 0)
        out_close(o->file);
    free(o->g);
    free(o);
}
