/* Particle output (output.h): OUT/particles.h5 (structure-of-arrays datasets per snapshot, the
 * fields the case selects) and OUT/particles.xmf, and the names of the open-boundary counters a
 * snapshot carries. */
#include <hdf5.h>
#include <inttypes.h>
#include <stdio.h>
#include <stdlib.h>
#include "output_h5.h"

const char *const lahar_flow_names[LAHAR_FLOW_NVAL] = {
    "flow_entered", "flow_entered_mass", "flow_removed_water", "flow_removed_water_mass",
    "flow_removed_soil", "flow_removed_soil_mass", "flow_created", "flow_domain_mass"};

struct lahar_particle_output {
    char dir[OUT_PATH_MAX];
    unsigned fields;
    int64_t nsnap;
    out_snapfile file;  /* particles.h5 and its twin */
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
    char h5path[OUT_PATH_MAX + 16];
    snprintf(h5path, sizeof h5path, "%s/particles.h5", outdir);
    out_snapfile_init(&o->file, h5path, c->output_in_place);
    if (c->resume) { /* continue particles.h5 as the checkpoint left it (lahar_output_resume_trim) */
        char path[OUT_PATH_MAX + 16];
        snprintf(path, sizeof path, "%s/particles.xmf", outdir);
        if (out_resume_sidecar(o->file.path, path, &o->xmf, NULL, &o->fields, &o->nsnap, err, n) != 0) {
            lahar_particle_output_close(o);
            return NULL;
        }
        return o;
    }
    hid_t f = out_file_open(o->file.path, H5F_ACC_TRUNC, 1);
    if (f < 0) {
        snprintf(err, n, "%s: cannot create HDF5 file", o->file.path);
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
    rc |= out_snapshots_group(f);
    if (H5Fclose(f) < 0 || rc) {
        snprintf(err, n, "%s: writing the header failed", o->file.path);
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

/* What a particle snapshot's fill writes: the view and the output's field selection. */
typedef struct {
    const lahar_particle_output *o;
    const lahar_particles_view *p;
} particle_snapshot;

/* The datasets and counters of a particle snapshot (out_snapshot_fill). */
static int particle_snapshot_fill(hid_t g, void *ctx)
{
    const lahar_particle_output *o = ((const particle_snapshot *)ctx)->o;
    const lahar_particles_view *p = ((const particle_snapshot *)ctx)->p;
    hsize_t n = (hsize_t)(p->n > 0 ? p->n : 0);
    int rc = out_attr_int64(g, "n", (int64_t)n);
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
    return rc;
}

int lahar_particle_output_snapshot(lahar_particle_output *o, int64_t step, double t, const lahar_particles_view *p)
{
    /* at most 17 values of 8 bytes per particle (position, velocity, density, pressure, phase,
     * id, stress), the datasets' headers and the XDMF text */
    double need = 17.0 * 8.0 * (double)(p->n > 0 ? p->n : 0) + 16.0 * 1024.0 + OUT_XML_CAP;
    particle_snapshot snap = {o, p};
    if (out_snapfile_append(&o->file, need, "a particle snapshot", o->nsnap, step, t, particle_snapshot_fill, &snap))
        return -1;
    hsize_t n = (hsize_t)(p->n > 0 ? p->n : 0);
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
    out_snapfile_close(&o->file);
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
