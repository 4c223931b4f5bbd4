/* Gauge output (output.h): OUT/gauges.h5, one SWMR stream per probe, level gauge, tracker and
 * control volume of the case, buffered and appended like the force stream. */
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include "output_h5.h"

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
    out_stream_cache(fapl, GAUGE_BUFFER_ROWS * sizeof(double));
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
