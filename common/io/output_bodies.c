/* Body output (output.h): OUT/bodies.h5 with its header, display geometry and snapshots,
 * OUT/bodies.xmf, and the SWMR force stream OUT/forces.h5 the body snapshots flush. Everything a
 * snapshot or a force row needs is allocated at open; the per-step path only copies into those
 * buffers and calls HDF5. */
#include <hdf5.h>
#include <inttypes.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "output_h5.h"
#include "vec.h"

#define FORCES_BUFFER_BYTES (256 * 1024)

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
    int dim, nbody;
    lahar_display_mesh *mesh;  /* per body, body frame (fixed: world frame as given) */
    int *moving;               /* per body: 1 if not fixed */
    int64_t nmoving_vert, nmoving_cell, nfixed_vert, nfixed_cell;
    double *state;             /* nbody * 13: x, q, v, w laid out as four blocks */
    float *vert, *vvel;        /* moving display vertices and their velocities */
    int64_t nsnap;
    out_snapfile file;         /* bodies.h5 and its twin */
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
    out_stream_cache(fapl, (double)fs->cap * (fs->nbody > 0 ? fs->nbody : 1) * 3.0 * sizeof(double));
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

/* bodies.h5 and bodies.xmf of a resumed run: continued as the checkpoint left them
 * (lahar_output_resume_trim). 0, or -1 with the message in err. */
static int bodies_file_continue(lahar_body_output *o, const char *outdir, char *err, size_t n)
{
    char path[OUT_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/bodies.xmf", outdir);
    lahar_xdmf_bodies xb;
    out_xdmf_bodies_info(o, &xb);
    return out_resume_sidecar(o->file.path, path, &o->xmf, &xb, NULL, &o->nsnap, err, n) != 0 ? -1 : 0;
}

/* bodies.h5 of a new run (header, geometry, an empty snapshots group) and its bodies.xmf. 0, or -1
 * with the message in err. */
static int bodies_file_create(lahar_body_output *o, const lahar_case *c, const char *outdir, char *err, size_t n)
{
    hid_t f = out_file_open(o->file.path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file (does the directory exist?)", o->file.path);
        return -1;
    }
    int rc = out_write_header(f, c);
    rc |= out_write_geometry(f, o, c);
    rc |= out_snapshots_group(f);
    if (H5Fclose(f) < 0)
        rc = -1;
    if (rc) {
        snprintf(err, n, "%s: writing header/geometry failed", o->file.path);
        return -1;
    }
    char path[OUT_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/bodies.xmf", outdir);
    return lahar_xdmf_open(&o->xmf, path, err, n) ? -1 : 0;
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
    char h5path[OUT_PATH_MAX + 16];
    snprintf(h5path, sizeof h5path, "%s/bodies.h5", outdir);
    out_snapfile_init(&o->file, h5path, c->output_in_place);
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
    if ((c->resume ? bodies_file_continue(o, outdir, err, n) : bodies_file_create(o, c, outdir, err, n)) != 0) {
        lahar_body_output_close(o);
        return NULL;
    }
    char path[OUT_PATH_MAX + 16];
    snprintf(path, sizeof path, "%s/forces.h5", outdir);
    if (c->output_forces && c->nbody > 0 && forces_open(&o->fs, path, c, err, n)) {
        lahar_body_output_close(o);
        return NULL;
    }
    return o;
}

/* The datasets of a body snapshot from o's buffers (out_snapshot_fill). */
static int body_snapshot_fill(hid_t g, void *ctx)
{
    const lahar_body_output *o = ctx;
    int nb = o->nbody;
    const double *X = o->state, *Q = X + 3 * nb, *V = Q + 4 * nb, *W = V + 3 * nb;
    int rc = out_dataset(g, "position", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, X);
    rc |= out_dataset(g, "quaternion", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 4, Q);
    rc |= out_dataset(g, "velocity", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, V);
    rc |= out_dataset(g, "angular_velocity", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, (hsize_t)nb, 3, W);
    rc |= out_dataset(g, "vertices", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, 2, (hsize_t)o->nmoving_vert, 3, o->vert);
    rc |= out_dataset(g, "vertex_velocity", H5T_NATIVE_FLOAT, H5T_IEEE_F32LE, 2, (hsize_t)o->nmoving_vert, 3,
                      o->vvel);
    return rc;
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
    if (out_snapfile_append(&o->file, need, "a body snapshot", o->nsnap, step, t, body_snapshot_fill, o) != 0)
        return -1;
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
    out_snapfile_close(&o->file);
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

int lahar_body_output_sync(lahar_body_output *o)
{
    if (!o || o->fs.file < 0)
        return 0;
    int rc = forces_flush(&o->fs);
    return H5Fflush(o->fs.file, H5F_SCOPE_GLOBAL) < 0 ? -1 : rc;
}
