/* Contact output (output.h): OUT/contacts.h5, the points where the fluid pushes on the bodies a
 * case marks record_contacts and the forces there, one group per snapshot and marked body. */
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include "output_h5.h"

struct lahar_contact_output {
    int nbody;         /* bodies of the case */
    int nmarked;
    int *marked;       /* body indices marked record_contacts */
    char (*group)[LAHAR_NAME_MAX + 16]; /* per marked body: its group name in a snapshot */
    int *slot;         /* per body of the case: index into the listed bodies of the current write, -1 */
    int64_t *offset;   /* per body of the case: first point in x/f of the current write */
    int64_t nsnap;
    out_snapfile file;  /* contacts.h5 and its twin */
};

/* What a contact snapshot's fill writes: the output and the loads of this write. */
typedef struct {
    const lahar_contact_output *o;
    const int32_t *npoints;
    const double (*x)[3], (*f)[3], (*force)[3], (*torque)[3];
} contact_snapshot;

void lahar_contact_output_close(lahar_contact_output *o)
{
    if (!o)
        return;
    out_snapfile_close(&o->file);
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
    char h5path[OUT_PATH_MAX + 16];
    snprintf(h5path, sizeof h5path, "%s/contacts.h5", outdir);
    out_snapfile_init(&o->file, h5path, c->output_in_place);
    if (c->resume) { /* continue contacts.h5 as the checkpoint left it */
        out_snap_entry *list = NULL;
        int64_t cnt = out_read_snapshot_list(o->file.path, &list);
        free(list);
        if (cnt < 0) {
            snprintf(err, n, "%s: cannot read it to continue it", o->file.path);
            lahar_contact_output_close(o);
            return NULL;
        }
        o->nsnap = cnt;
        return o;
    }
    hid_t f = out_file_open(o->file.path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file", o->file.path);
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
    rc |= out_snapshots_group(f);
    if (H5Fclose(f) < 0 || rc) {
        snprintf(err, n, "%s: writing the header failed", o->file.path);
        lahar_contact_output_close(o);
        return NULL;
    }
    return o;
}

/* A group per marked body with its points, forces and resultants (out_snapshot_fill); bodies not
 * listed in this write get an empty group. */
static int contact_snapshot_fill(hid_t g, void *ctx)
{
    const contact_snapshot *w = ctx;
    const lahar_contact_output *o = w->o;
    int rc = 0;
    for (int m = 0; m < o->nmarked && !rc; m++) {
        int b = o->marked[m], i = o->slot[b];
        hid_t bg = out_group(g, o->group[m]);
        if (bg < 0)
            return -1;
        static const double zero[3] = {0.0, 0.0, 0.0};
        hsize_t np = i >= 0 ? (hsize_t)w->npoints[i] : 0;
        const double *pts = np ? w->x[o->offset[b]] : zero, *fs = np ? w->f[o->offset[b]] : zero;
        rc |= out_attr_int64(bg, "n", (int64_t)np);
        rc |= out_attr(bg, "force", H5T_NATIVE_DOUBLE, 3, i >= 0 ? w->force[i] : zero);
        rc |= out_attr(bg, "torque", H5T_NATIVE_DOUBLE, 3, i >= 0 ? w->torque[i] : zero);
        rc |= out_dataset(bg, "points", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, np, 3, pts);
        rc |= out_dataset(bg, "forces", H5T_NATIVE_DOUBLE, H5T_IEEE_F64LE, 2, np, 3, fs);
        H5Gclose(bg);
    }
    return rc;
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
    contact_snapshot w = {o, npoints, x, f, force, torque};
    if (out_snapfile_append(&o->file, need, "the contact points", o->nsnap, step, t, contact_snapshot_fill, &w) != 0)
        return -1;
    o->nsnap++;
    return 0;
}
