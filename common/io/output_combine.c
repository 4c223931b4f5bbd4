/* OUT/lahar.xmf (output.h lahar_output_xdmf_combine): bodies and particles in one XDMF temporal
 * collection, built from the snapshot lists of bodies.h5 and particles.h5 on disk, so that it is
 * right whichever writer finished last. */
#include <errno.h>
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>
#include "output_h5.h"

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
