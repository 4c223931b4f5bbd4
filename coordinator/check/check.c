/* `lahar check` evaluation (see check.h): load the run's output, run the reference's evaluator,
 * compare its values with the case's bounds, write OUT/check.json (cJSON) and the plot. */
#include "check.h"
#include <cjson/cJSON.h>
#include <errno.h>
#include <hdf5.h>
#include <inttypes.h>
#include <limits.h>
#include <math.h>
#include <spawn.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>
#include "case.h"
#include "geometry.h"
#include "output.h"
#include "vec.h"

extern char **environ;

/* ---------------------------------------------------------------- loading --------------- */

/* Read a whole dataset of exactly `count` elements into buf (a different size is an error, not
 * an overflow). */
static int check_read(hid_t loc, const char *name, hid_t type, hssize_t count, void *buf)
{
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0)
        return -1;
    hid_t sp = H5Dget_space(ds);
    herr_t rc = H5Sget_simple_extent_npoints(sp) == count ? H5Dread(ds, type, H5S_ALL, H5S_ALL, H5P_DEFAULT, buf) : -1;
    H5Sclose(sp);
    H5Dclose(ds);
    return rc < 0 ? -1 : 0;
}

static int check_read_attr(hid_t loc, const char *name, hid_t type, void *buf)
{
    if (H5Aexists(loc, name) <= 0)
        return -1;
    hid_t a = H5Aopen(loc, name, H5P_DEFAULT);
    herr_t rc = H5Aread(a, type, buf);
    H5Aclose(a);
    return rc < 0 ? -1 : 0;
}

/* The first n rows of the dataset `name` (n x ncol, or n x ncol/3 x 3 for the force rows): other
 * datasets of the force stream may be ahead of /t while a writer is appending. */
static int check_read_rows(hid_t loc, const char *name, hid_t type, hsize_t n, int ncol, void *buf)
{
    hid_t ds = H5Dopen2(loc, name, H5P_DEFAULT);
    if (ds < 0)
        return -1;
    hid_t fsp = H5Dget_space(ds);
    hsize_t dims[3] = {0, 0, 0}, off[3] = {0, 0, 0};
    int rank = H5Sget_simple_extent_ndims(fsp), rc = -1;
    if ((rank == 2 || rank == 3) && H5Sget_simple_extent_dims(fsp, dims, NULL) == rank && dims[0] >= n &&
        (rank == 2 ? dims[1] == (hsize_t)ncol : dims[1] * dims[2] == (hsize_t)ncol)) {
        hsize_t cnt[3] = {n, dims[1], dims[2]};
        hid_t msp = H5Screate_simple(rank, cnt, NULL);
        H5Sselect_hyperslab(fsp, H5S_SELECT_SET, off, NULL, cnt, NULL);
        rc = H5Dread(ds, type, msp, fsp, H5P_DEFAULT, buf) < 0 ? -1 : 0;
        H5Sclose(msp);
    }
    H5Sclose(fsp);
    H5Dclose(ds);
    return rc;
}

static int check_load_forces(const char *outdir, lahar_check_data *d)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/forces.h5", outdir);
    if (access(path, R_OK) != 0)
        return 0;
    hid_t f = lahar_h5_file_open(path, H5F_ACC_RDONLY | H5F_ACC_SWMR_READ, H5P_DEFAULT, 0);
    if (f < 0)
        return -1;
    int rc = -1;
    hid_t ds = H5Dopen2(f, "t", H5P_DEFAULT);
    if (ds >= 0) {
        hid_t sp = H5Dget_space(ds);
        hsize_t n = 0;
        H5Sget_simple_extent_dims(sp, &n, NULL);
        H5Sclose(sp);
        H5Dclose(ds);
        d->nrow = (int64_t)n;
        d->ft = malloc((n ? n : 1) * sizeof *d->ft);
        d->ncontacts = malloc((n ? n : 1) * (size_t)(d->nbody ? d->nbody : 1) * sizeof *d->ncontacts);
        d->force = malloc((n ? n : 1) * (size_t)(d->nbody ? d->nbody : 1) * 3 * sizeof *d->force);
        if (d->ft && d->ncontacts && d->force &&
            (n == 0 ||
             (!check_read(f, "t", H5T_NATIVE_DOUBLE, (hssize_t)n, d->ft) &&
              (d->nbody == 0 ||
               (!check_read_rows(f, "ncontacts", H5T_NATIVE_INT32, n, d->nbody, d->ncontacts) &&
                !check_read_rows(f, "force", H5T_NATIVE_DOUBLE, n, 3 * d->nbody, d->force))))))
            rc = 0;
    }
    H5Fclose(f);
    return rc;
}

/* OUT/particles.h5: header, snapshot times and counts; the file stays open for
 * lahar_check_particles_read. No file: d->particles stays NULL. */
static int check_load_particles(const char *outdir, lahar_check_data *d, char *err, size_t n)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/particles.h5", outdir);
    if (access(path, R_OK) != 0)
        return 0;
    lahar_check_particles *p = calloc(1, sizeof *p);
    if (!p) {
        snprintf(err, n, "out of memory");
        return -1;
    }
    d->particles = p;
    p->cur = -1;
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, 0, 1);
    hid_t f = lahar_h5_file_open(path, H5F_ACC_RDONLY, fapl, 0);
    H5Pclose(fapl);
    if (f < 0) {
        snprintf(err, n, "%s: not a readable HDF5 file", path);
        return -1;
    }
    p->file = (int64_t)f;
    int64_t dim = 0, fields = 0;
    hid_t h = H5Gopen2(f, "header", H5P_DEFAULT);
    hid_t g = H5Gopen2(f, "snapshots", H5P_DEFAULT);
    H5G_info_t info = {0};
    int rc = (h < 0 || g < 0 || check_read_attr(h, "dimensions", H5T_NATIVE_INT64, &dim) ||
              check_read_attr(h, "fields", H5T_NATIVE_INT64, &fields) ||
              check_read_attr(h, "dx", H5T_NATIVE_DOUBLE, &p->dx) ||
              check_read_attr(h, "rest_density", H5T_NATIVE_DOUBLE, &p->rest_density) || H5Gget_info(g, &info) < 0)
                 ? -1
                 : 0;
    if (h >= 0)
        H5Gclose(h);
    p->dim = (int)dim;
    p->fields = (unsigned)fields;
    size_t ns = info.nlinks ? info.nlinks : 1;
    p->t = malloc(ns * sizeof *p->t);
    p->n = malloc(ns * sizeof *p->n);
    if (!rc && (!p->t || !p->n))
        rc = -1;
    for (hsize_t k = 0; rc == 0 && k < info.nlinks; k++) {
        char name[32];
        snprintf(name, sizeof name, "%06" PRId64, (int64_t)k);
        if (H5Lexists(g, name, H5P_DEFAULT) <= 0)
            break;
        hid_t s = H5Gopen2(g, name, H5P_DEFAULT);
        if (s < 0 || check_read_attr(s, "time", H5T_NATIVE_DOUBLE, &p->t[k]) ||
            check_read_attr(s, "n", H5T_NATIVE_INT64, &p->n[k]) || p->n[k] < 0)
            rc = -1;
        if (s >= 0)
            H5Gclose(s);
        if (rc == 0) {
            p->nsnap = (int64_t)k + 1;
            if (p->n[k] > p->nmax)
                p->nmax = p->n[k];
        }
    }
    if (g >= 0)
        H5Gclose(g);
    if (rc) {
        snprintf(err, n, "%s: no /header or unreadable snapshot %" PRId64 " (not written by lahar?)", path, p->nsnap);
        return -1;
    }
    size_t nm = (size_t)(p->nmax ? p->nmax : 1) * sizeof(double);
    int vel = (p->fields & LAHAR_PFIELD_VELOCITY) != 0;
    p->x = malloc(nm), p->y = malloc(nm), p->z = malloc(nm);
    p->vx = vel ? malloc(nm) : NULL, p->vy = vel ? malloc(nm) : NULL, p->vz = vel ? malloc(nm) : NULL;
    p->density = (p->fields & LAHAR_PFIELD_DENSITY) ? malloc(nm) : NULL;
    p->pressure = (p->fields & LAHAR_PFIELD_PRESSURE) ? malloc(nm) : NULL;
    p->phase = (p->fields & LAHAR_PFIELD_PHASE) ? malloc((size_t)(p->nmax ? p->nmax : 1) * sizeof *p->phase) : NULL;
    p->stress = (p->fields & LAHAR_PFIELD_STRESS) ? malloc(nm * 6) : NULL;
    if (((p->fields & LAHAR_PFIELD_PHASE) && !p->phase) || ((p->fields & LAHAR_PFIELD_STRESS) && !p->stress)) {
        snprintf(err, n, "out of memory for %" PRId64 " particles", p->nmax);
        return -1;
    }
    if (!p->x || !p->y || !p->z || (vel && (!p->vx || !p->vy || !p->vz)) ||
        ((p->fields & LAHAR_PFIELD_DENSITY) && !p->density) || ((p->fields & LAHAR_PFIELD_PRESSURE) && !p->pressure)) {
        snprintf(err, n, "out of memory for %" PRId64 " particles", p->nmax);
        return -1;
    }
    return 0;
}

int lahar_check_particles_read(lahar_check_particles *p, int64_t k, char *err, size_t n)
{
    if (k == p->cur)
        return 0;
    if (k < 0 || k >= p->nsnap) {
        snprintf(err, n, "particles.h5: no snapshot %" PRId64 " (have %" PRId64 ")", k, p->nsnap);
        return -1;
    }
    char name[48];
    snprintf(name, sizeof name, "snapshots/%06" PRId64, k);
    hid_t s = H5Gopen2((hid_t)p->file, name, H5P_DEFAULT);
    if (s < 0) {
        snprintf(err, n, "particles.h5: cannot open %s", name);
        return -1;
    }
    hssize_t cnt = (hssize_t)p->n[k];
    const struct {
        const char *name;
        double *buf;
    } col[] = {{"x", p->x},   {"y", p->y},   {"z", p->z},       {"vx", p->vx},
               {"vy", p->vy}, {"vz", p->vz}, {"density", p->density}, {"pressure", p->pressure}};
    int rc = 0;
    for (size_t i = 0; i < sizeof col / sizeof col[0] && rc == 0; i++)
        if (col[i].buf && cnt > 0 && check_read(s, col[i].name, H5T_NATIVE_DOUBLE, cnt, col[i].buf)) {
            snprintf(err, n, "particles.h5: %s/%s missing or not %" PRId64 " values", name, col[i].name, p->n[k]);
            rc = -1;
        }
    if (rc == 0 && p->phase && cnt > 0 && check_read(s, "phase", H5T_NATIVE_INT32, cnt, p->phase)) {
        snprintf(err, n, "particles.h5: %s/phase missing or not %" PRId64 " values", name, p->n[k]);
        rc = -1;
    }
    if (rc == 0 && p->stress && cnt > 0 && check_read(s, "stress", H5T_NATIVE_DOUBLE, cnt * 6, p->stress)) {
        snprintf(err, n, "particles.h5: %s/stress missing or not %" PRId64 " x 6 values", name, p->n[k]);
        rc = -1;
    }
    H5Gclose(s);
    p->cur = rc ? -1 : k;
    p->cur_n = rc ? 0 : p->n[k];
    return rc;
}

int lahar_check_data_load(const char *outdir, lahar_check_data *d, char *err, size_t n)
{
    memset(d, 0, sizeof *d);
    char path[1200];
    snprintf(path, sizeof path, "%s/bodies.h5", outdir);
    if (access(path, R_OK) != 0) {
        char ppath[1200];
        snprintf(ppath, sizeof ppath, "%s/particles.h5", outdir);
        if (access(ppath, R_OK) == 0) /* a scene without bodies (and no DEM node) writes particles only */
            goto particles;
        snprintf(err, n, "%s: missing (%s); did the run write output?", path, strerror(errno));
        return -1;
    }
    hid_t fapl = H5Pcreate(H5P_FILE_ACCESS);
    H5Pset_file_locking(fapl, 0, 1);
    hid_t f = lahar_h5_file_open(path, H5F_ACC_RDONLY, fapl, 0);
    H5Pclose(fapl);
    if (f < 0) {
        snprintf(err, n, "%s: not a readable HDF5 file", path);
        return -1;
    }
    int64_t nbody = 0;
    hid_t h = H5Gopen2(f, "header", H5P_DEFAULT);
    hid_t g = H5Gopen2(f, "snapshots", H5P_DEFAULT);
    H5G_info_t info = {0};
    if (h < 0 || g < 0 || check_read_attr(h, "nbody", H5T_NATIVE_INT64, &nbody) || H5Gget_info(g, &info) < 0) {
        snprintf(err, n, "%s: no /header or /snapshots (not written by lahar?)", path);
        if (h >= 0)
            H5Gclose(h);
        if (g >= 0)
            H5Gclose(g);
        H5Fclose(f);
        return -1;
    }
    H5Gclose(h);
    d->nbody = (int)nbody;
    size_t ns = info.nlinks ? info.nlinks : 1, nb3 = (size_t)(nbody ? nbody : 1) * 3;
    d->t = malloc(ns * sizeof *d->t);
    d->step = malloc(ns * sizeof *d->step);
    d->x = malloc(ns * nb3 * sizeof *d->x);
    d->q = malloc(ns * nb3 / 3 * 4 * sizeof *d->q);
    d->v = malloc(ns * nb3 * sizeof *d->v);
    d->w = malloc(ns * nb3 * sizeof *d->w);
    int rc = (d->t && d->step && d->x && d->q && d->v && d->w) ? 0 : -1;
    for (hsize_t k = 0; rc == 0 && k < info.nlinks; k++) {
        char name[32];
        snprintf(name, sizeof name, "%06" PRId64, (int64_t)k);
        if (H5Lexists(g, name, H5P_DEFAULT) <= 0)
            break;
        hid_t s = H5Gopen2(g, name, H5P_DEFAULT);
        if (s < 0 || check_read_attr(s, "time", H5T_NATIVE_DOUBLE, &d->t[k]) ||
            check_read_attr(s, "step", H5T_NATIVE_INT64, &d->step[k]) ||
            (nbody > 0 && (check_read(s, "position", H5T_NATIVE_DOUBLE, (hssize_t)nb3, d->x + k * nb3) ||
                           check_read(s, "quaternion", H5T_NATIVE_DOUBLE, (hssize_t)(nb3 / 3 * 4),
                                      d->q + k * nb3 / 3 * 4) ||
                           check_read(s, "velocity", H5T_NATIVE_DOUBLE, (hssize_t)nb3, d->v + k * nb3) ||
                           check_read(s, "angular_velocity", H5T_NATIVE_DOUBLE, (hssize_t)nb3, d->w + k * nb3))))
            rc = -1;
        if (s >= 0)
            H5Gclose(s);
        if (rc == 0)
            d->nsnap = (int64_t)k + 1;
    }
    H5Gclose(g);
    H5Fclose(f);
    if (rc) {
        snprintf(err, n, "%s: cannot read snapshot %" PRId64, path, d->nsnap);
        lahar_check_data_free(d);
        return -1;
    }
particles:
    if (check_load_forces(outdir, d)) {
        snprintf(err, n, "%s/forces.h5: unreadable", outdir);
        lahar_check_data_free(d);
        return -1;
    }
    if (check_load_particles(outdir, d, err, n)) {
        lahar_check_data_free(d);
        return -1;
    }
    return 0;
}

static void check_particles_free(lahar_check_particles *p)
{
    if (!p)
        return;
    if (p->file > 0)
        H5Fclose((hid_t)p->file);
    free(p->t), free(p->n), free(p->x), free(p->y), free(p->z), free(p->vx), free(p->vy), free(p->vz);
    free(p->density), free(p->pressure), free(p->phase), free(p->stress);
    free(p);
}

void lahar_check_data_free(lahar_check_data *d)
{
    free(d->t), free(d->step), free(d->x), free(d->q), free(d->v), free(d->w), free(d->ft), free(d->ncontacts);
    free(d->force);
    check_particles_free(d->particles);
    geom_body_grids_free(&d->grids);
    memset(d, 0, sizeof *d);
}

/* ---------------------------------------------------------------- evaluator helpers ----- */

void lahar_check_value(lahar_check_result *r, const char *name, double v)
{
    if (r->nvalue >= LAHAR_CHECK_MAX_VALUES || strlen(name) >= sizeof r->value[0].name)
        return;
    snprintf(r->value[r->nvalue].name, sizeof r->value[0].name, "%s", name);
    r->value[r->nvalue].value = v;
    r->nvalue++;
}
#define check_value lahar_check_value

double lahar_check_late_from(const double *t, int64_t n, double fraction)
{
    double t0 = t[0], t1 = t[n - 1];
    return t1 - fraction * (t1 - t0);
}

int lahar_check_grow(void **buf, size_t *cap, size_t n, size_t sz)
{
    if (n <= *cap)
        return 0;
    size_t c = *cap ? 2 * *cap : 1024;
    while (c < n)
        c *= 2;
    void *t = realloc(*buf, c * sz);
    if (!t)
        return -1;
    *buf = t, *cap = c;
    return 0;
}

int lahar_check_gauge_line(double **phi, size_t *cap, double low, double top, double support, double step)
{
    const int npt = (int)ceil((top + support - low) / step) + 1;
    if (lahar_check_grow((void **)phi, cap, (size_t)npt, sizeof **phi))
        return -1;
    for (int i = 0; i < npt; i++)
        (*phi)[i] = 0.0;
    return npt;
}

int lahar_check_panel(lahar_check_result *r, const char *title, const char *xlabel, const char *ylabel)
{
    if (r->npanel >= LAHAR_CHECK_MAX_PANELS)
        return -1;
    snprintf(r->panel[r->npanel].title, sizeof r->panel[0].title, "%s", title);
    snprintf(r->panel[r->npanel].xlabel, sizeof r->panel[0].xlabel, "%s", xlabel);
    snprintf(r->panel[r->npanel].ylabel, sizeof r->panel[0].ylabel, "%s", ylabel);
    return r->npanel++;
}

int lahar_check_curve(lahar_check_result *r, int panel, int measured, const char *label)
{
    if (panel < 0 || panel >= r->npanel || r->ncurve >= LAHAR_CHECK_MAX_CURVES)
        return -1;
    r->curve[r->ncurve].panel = panel;
    r->curve[r->ncurve].measured = measured;
    snprintf(r->curve[r->ncurve].label, sizeof r->curve[0].label, "%s", label);
    r->curve[r->ncurve].start = r->npoint;
    r->curve[r->ncurve].n = 0;
    r->ncurve++;
    return 0;
}

void lahar_check_point(lahar_check_result *r, double x, double y)
{
    if (r->ncurve == 0 || r->npoint >= LAHAR_CHECK_MAX_POINTS || !r->px)
        return;
    r->px[r->npoint] = x;
    r->py[r->npoint] = y;
    r->npoint++;
    r->curve[r->ncurve - 1].n++;
}

/* ---------------------------------------------------------------- table + driver -------- */

static const lahar_check_reference check_references[] = {
    {"restitution", "sphere dropped on a fixed floor: rebound/impact speed vs the material's e",
     "restitution_rel_error", 0.01, lahar_check_restitution},
    {"incline_roll", "sphere/disc on a fixed incline: fitted acceleration vs rolling or sliding theory",
     "accel_rel_error", 0.01, lahar_check_incline_roll},
    {"poiseuille", "plane Poiseuille flow between fixed plates: velocity profiles vs the transient series, plate force",
     "steady_l2_rel_error", 0.01, lahar_check_poiseuille},
    {"cylinder_array", "periodic square array of cylinders: K = rho g L^2/(mu U_s) vs Sangani & Acrivos 1982",
     "K_rel_error", 0.05, lahar_check_cylinder_array},
    {"sphere_array", "periodic simple cubic array of spheres: K = rho g L^3/(6 pi mu a U_s) vs Zick & Homsy 1982",
     "K_rel_error", 0.05, lahar_check_sphere_array},
    {"hydrostatic", "water at rest in a tank: wall force vs rho g h^2/2, pressure vs rho g (h - y)",
     "wall_force_rel_error", 0.01, lahar_check_hydrostatic},
    {"floating_box", "box floating in water: draft vs Archimedes rho_b h/rho_f", "draft_rel_error", 0.02,
     lahar_check_floating_box},
    {"sinking_disc", "dense disc sinking onto the floor: no penetration, comes to rest", "floor_penetration", 0.0,
     lahar_check_sinking_disc},
    {"dam_break", "collapsing water column: particle count conserved, no particle escapes, front monotonic",
     "escaped_particles", 0.0, lahar_check_dam_break},
    {"lid_driven_cavity", "lid-driven square cavity at Re = 100: centreline velocities vs Ghia, Ghia & Shin 1982, "
     "total volume kept", "u_max_error", 0.05, lahar_check_lid_driven_cavity},
    {"taylor_green", "2D Taylor-Green vortex (periodic): kinetic-energy decay rate vs 16 pi^2 nu / L^2, velocity L2",
     "energy_decay_rel_error", 0.01, lahar_check_taylor_green},
    {"soil_geostatic", "soil column at rest under gravity: sigma_v vs rho g z, sigma_h vs K0 sigma_v, no creep",
     "sigma_v_rel_error", 0.05, lahar_check_soil_geostatic},
    {"soil_slide", "soil block on a fixed floor under tilted gravity: sliding acceleration vs g (sin - mu_phi cos)",
     "accel_rel_error", 0.05, lahar_check_soil_slide},
    {"granular_collapse", "soil column collapsing from a wall onto a floor: run-out, deposit profile, settled at or "
     "below the angle of repose", "escaped_particles", 0.0, lahar_check_granular_collapse},
    {"granular_impact", "soil flowing down a chute onto a fixed wall: impact force history and peak, first impact, "
     "momentum balance, nothing through the wall", "escaped_particles", 0.0, lahar_check_granular_impact},
    {"darcy", "water driven through a soil: seepage velocity vs Darcy's k_h i", "darcy_velocity_rel_error", 0.05,
     lahar_check_darcy},
    {"inflow", "open boundaries: discharge through the inlets vs the hydrographs, mass balance, outflow vs inflow, "
     "steady depth vs the inlet level", "discharge_rel_error", 0.02, lahar_check_inflow},
    {"landslide", "soil mass sliding down a terrain profile: nothing through the terrain, mass kept, deposit length "
     "and thickness against the field's (Yangbaodi)", "escaped_particles", 0.0, lahar_check_landslide},
};
#define CHECK_NREF (sizeof check_references / sizeof check_references[0])

const lahar_check_reference *lahar_check_find(const char *name)
{
    for (size_t k = 0; k < CHECK_NREF; k++)
        if (strcmp(check_references[k].name, name) == 0)
            return &check_references[k];
    return NULL;
}

const char *lahar_check_names(void)
{
    static char names[512];
    size_t pos = 0;
    for (size_t k = 0; k < CHECK_NREF && pos < sizeof names; k++)
        pos += (size_t)snprintf(names + pos, sizeof names - pos, "%s%s", k ? ", " : "", check_references[k].name);
    return names;
}

static int check_write_json(const char *path, cJSON *root)
{
    char *text = cJSON_Print(root);
    if (!text)
        return -1;
    FILE *f = fopen(path, "w");
    int rc = -1;
    if (f) {
        rc = fputs(text, f) < 0 ? -1 : 0;
        fputc('\n', f);
        if (fclose(f))
            rc = -1;
    }
    cJSON_free(text);
    return rc;
}

static int check_fail(const char *outdir, const char *reference, const char *msg)
{
    fprintf(stderr, "lahar check: %s\n", msg);
    char path[1200];
    snprintf(path, sizeof path, "%s/check.json", outdir);
    cJSON *root = cJSON_CreateObject();
    cJSON_AddBoolToObject(root, "pass", 0);
    cJSON_AddStringToObject(root, "reference", reference);
    cJSON_AddStringToObject(root, "error", msg);
    cJSON_AddObjectToObject(root, "metrics");
    struct stat st;
    if (stat(outdir, &st) == 0 && S_ISDIR(st.st_mode))
        check_write_json(path, root);
    cJSON_Delete(root);
    return 2;
}

/* python3 tools/plot_check.py OUT; a missing python3/matplotlib only costs the plot. */
static void check_plot(const char *outdir)
{
    const char *skip = getenv("LAHAR_CHECK_NO_PLOT");
    if (skip && *skip && strcmp(skip, "0") != 0)
        return;
    const char *py = getenv("LAHAR_PYTHON");
    if (!py || !*py)
        py = "python3";
    char script[1200];
    snprintf(script, sizeof script, "%s/plot_check.py", LAHAR_TOOLS_DIR);
    char *argv[] = {(char *)py, script, (char *)outdir, NULL};
    pid_t pid;
    int status = 0;
    if (posix_spawnp(&pid, py, NULL, NULL, argv, environ) != 0) {
        fprintf(stderr, "lahar check: no plot: cannot run %s (install python3, python3-matplotlib, python3-h5py); "
                        "check.json is written\n",
                py);
        return;
    }
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR)
        ;
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        fprintf(stderr, "lahar check: no plot (%s %s failed, see above); check.json is written\n", py, script);
}

/* What lahar_check_evaluate holds, step by step (the helpers below fill it in order). Every step
 * that fails returns check_fail's exit status (2, with check.json saying why) having freed what
 * it was given; 0 to go on. */
typedef struct {
    const lahar_check_reference *ref;
    lahar_check_data d;         /* the output, loaded; freed once the reference has evaluated it */
    lahar_check_result *r;      /* what the reference computed */
    double *series;             /* the storage behind r's series and curve points */
    cJSON *root, *metrics, *info;
    int all_pass;
    int used[LAHAR_CHECK_MAX_VALUES]; /* the value is a metric (the others go to info) */
    char msg[2048];
} evaluation;

/* The case's reference by name. */
static int evaluation_reference(const lahar_case *c, const char *outdir, evaluation *ev)
{
    if (!c->check.enabled)
        return check_fail(outdir, "", "the case has no check: section (add check: {reference: ..., metrics: ...})");
    ev->ref = lahar_check_find(c->check.reference);
    if (!ev->ref) {
        snprintf(ev->msg, sizeof ev->msg, "%s: check.reference '%s' is unknown; known references: %s", c->path,
                 c->check.reference, lahar_check_names());
        return check_fail(outdir, c->check.reference, ev->msg);
    }
    return 0;
}

/* The output in OUT, refused when it is not the case's (another body count or dimension), and
 * the bodies' grids the references measure distances with. */
static int evaluation_load(const lahar_case *c, const char *outdir, evaluation *ev)
{
    lahar_check_data *d = &ev->d;
    const char *name = ev->ref->name;
    if (lahar_check_data_load(outdir, d, ev->msg, sizeof ev->msg))
        return check_fail(outdir, name, ev->msg);
    if (d->nbody != c->nbody) {
        snprintf(ev->msg, sizeof ev->msg, "%s/bodies.h5 has %d bodies, the case %s has %d: output of another case?",
                 outdir, d->nbody, c->path, c->nbody);
        lahar_check_data_free(d);
        return check_fail(outdir, name, ev->msg);
    }
    if (d->particles && d->particles->dim != c->dim) {
        snprintf(ev->msg, sizeof ev->msg, "%s/particles.h5 is %dD, the case %s is %dD: output of another case?",
                 outdir, d->particles->dim, c->path, c->dim);
        lahar_check_data_free(d);
        return check_fail(outdir, name, ev->msg);
    }
    if (geom_body_grids_build(&d->grids, c->bodies, c->nbody)) {
        lahar_check_data_free(d);
        return check_fail(outdir, name, "out of memory");
    }
    return 0;
}

/* The result and one block behind its series and curve points (too large for the stack). */
static int evaluation_alloc(const char *outdir, evaluation *ev)
{
    ev->r = calloc(1, sizeof *ev->r);
    ev->series = malloc((3 * LAHAR_CHECK_MAX_SERIES + 2 * LAHAR_CHECK_MAX_POINTS) * sizeof *ev->series);
    if (!ev->r || !ev->series) {
        free(ev->r), free(ev->series);
        lahar_check_data_free(&ev->d);
        return check_fail(outdir, ev->ref->name, "out of memory");
    }
    lahar_check_result *r = ev->r;
    double *series = ev->series;
    r->series_t = series, r->series_measured = series + LAHAR_CHECK_MAX_SERIES;
    r->series_reference = series + 2 * LAHAR_CHECK_MAX_SERIES;
    r->px = series + 3 * LAHAR_CHECK_MAX_SERIES, r->py = r->px + LAHAR_CHECK_MAX_POINTS;
    return 0;
}

/* The reference's evaluation of the output; the output is freed after. */
static int evaluation_run(const lahar_case *c, const char *outdir, evaluation *ev)
{
    int rc = ev->ref->evaluate(c, &ev->d, ev->r);
    lahar_check_data_free(&ev->d);
    if (rc) {
        snprintf(ev->msg, sizeof ev->msg, "%s", ev->r->err);
        free(ev->r), free(ev->series);
        return check_fail(outdir, ev->ref->name, ev->msg);
    }
    return 0;
}

/* The case's metrics (or the reference's default) against the computed values, each printed as
 * it is judged; a metric the reference does not compute lists those it does. */
static int evaluation_metrics(const lahar_case *c, const char *outdir, evaluation *ev)
{
    const lahar_check_reference *ref = ev->ref;
    const lahar_check_result *r = ev->r;
    char *msg = ev->msg;
    int nmetric = c->check.nmetric > 0 ? c->check.nmetric : 1;
    ev->root = cJSON_CreateObject(), ev->metrics = cJSON_CreateObject(), ev->info = cJSON_CreateObject();
    ev->all_pass = 1;
    for (int k = 0; k < nmetric; k++) {
        const char *name = c->check.nmetric > 0 ? c->check.metric[k].name : ref->default_metric;
        double bound = c->check.nmetric > 0 ? c->check.metric[k].bound : ref->default_bound;
        int found = -1;
        for (int i = 0; i < r->nvalue; i++)
            if (strcmp(r->value[i].name, name) == 0)
                found = i;
        if (found < 0) {
            size_t pos = (size_t)snprintf(msg, sizeof ev->msg,
                                          "%s: check.metrics.%s is not a metric of reference %s; it has:", c->path,
                                          name, ref->name);
            for (int i = 0; i < r->nvalue && pos < sizeof ev->msg; i++)
                pos += (size_t)snprintf(msg + pos, sizeof ev->msg - pos, " %s", r->value[i].name);
            cJSON_Delete(ev->root), cJSON_Delete(ev->metrics), cJSON_Delete(ev->info);
            free(ev->r), free(ev->series);
            return check_fail(outdir, ref->name, msg);
        }
        ev->used[found] = 1;
        double v = r->value[found].value;
        int pass = v <= bound; /* NaN fails */
        ev->all_pass &= pass;
        cJSON *m = cJSON_AddObjectToObject(ev->metrics, name);
        cJSON_AddNumberToObject(m, "value", v);
        cJSON_AddNumberToObject(m, "bound", bound);
        cJSON_AddBoolToObject(m, "pass", pass);
        printf("lahar check %s: %s = %.6g (bound %.6g) %s\n", ref->name, name, v, bound, pass ? "pass" : "FAIL");
    }
    return 0;
}

/* The reference's panels of labelled curves under plot (none: no "panels" key). */
static void evaluation_json_panels(const lahar_check_result *r, cJSON *plot)
{
    if (r->npanel <= 0)
        return;
    cJSON *panels = cJSON_AddArrayToObject(plot, "panels");
    for (int p = 0; p < r->npanel; p++) {
        cJSON *pj = cJSON_CreateObject();
        cJSON_AddStringToObject(pj, "title", r->panel[p].title);
        cJSON_AddStringToObject(pj, "xlabel", r->panel[p].xlabel);
        cJSON_AddStringToObject(pj, "ylabel", r->panel[p].ylabel);
        cJSON_AddBoolToObject(pj, "ylog", r->panel[p].ylog);
        cJSON *curves = cJSON_AddArrayToObject(pj, "curves");
        for (int k = 0; k < r->ncurve; k++) {
            if (r->curve[k].panel != p)
                continue;
            cJSON *cj = cJSON_CreateObject();
            cJSON_AddStringToObject(cj, "label", r->curve[k].label);
            cJSON_AddStringToObject(cj, "kind", r->curve[k].measured ? "measured" : "reference");
            cJSON_AddItemToObject(cj, "x", cJSON_CreateDoubleArray(r->px + r->curve[k].start, r->curve[k].n));
            cJSON_AddItemToObject(cj, "y", cJSON_CreateDoubleArray(r->py + r->curve[k].start, r->curve[k].n));
            cJSON_AddItemToArray(curves, cj);
        }
        cJSON_AddItemToArray(panels, pj);
    }
}

/* check.json's document: the verdict, the metrics, the other values as information, and the plot
 * (the single series and the panels) that tools/plot_check.py draws. */
static void evaluation_json(const lahar_case *c, evaluation *ev)
{
    const lahar_check_result *r = ev->r;
    cJSON *root = ev->root;
    for (int i = 0; i < r->nvalue; i++)
        if (!ev->used[i])
            cJSON_AddNumberToObject(ev->info, r->value[i].name, r->value[i].value);
    cJSON_AddStringToObject(ev->info, "note", r->note);
    cJSON_AddBoolToObject(root, "pass", ev->all_pass);
    cJSON_AddStringToObject(root, "reference", ev->ref->name);
    char case_path[PATH_MAX];
    cJSON_AddStringToObject(root, "case", lahar_case_path_abs(c, case_path, sizeof case_path));
    if (r->convention[0])
        cJSON_AddStringToObject(root, "convention", r->convention);
    cJSON_AddItemToObject(root, "metrics", ev->metrics);
    cJSON_AddItemToObject(root, "info", ev->info);
    cJSON *plot = cJSON_AddObjectToObject(root, "plot");
    cJSON_AddStringToObject(plot, "title", r->title);
    cJSON_AddStringToObject(plot, "xlabel", r->xlabel);
    cJSON_AddStringToObject(plot, "ylabel", r->ylabel);
    cJSON_AddItemToObject(plot, "t", cJSON_CreateDoubleArray(r->series_t, r->nseries));
    cJSON_AddItemToObject(plot, "measured", cJSON_CreateDoubleArray(r->series_measured, r->nseries));
    cJSON_AddItemToObject(plot, "reference", cJSON_CreateDoubleArray(r->series_reference, r->nseries));
    evaluation_json_panels(r, plot);
}

/* OUT/check.json written, everything freed, the verdict printed and the plot drawn: 0 pass,
 * 1 fail, 2 when check.json cannot be written. */
static int evaluation_write(const char *outdir, evaluation *ev)
{
    char path[1200];
    snprintf(path, sizeof path, "%s/check.json", outdir);
    int wrc = check_write_json(path, ev->root);
    cJSON_Delete(ev->root);
    free(ev->r), free(ev->series);
    if (wrc) {
        fprintf(stderr, "lahar check: %s: cannot write\n", path);
        return 2;
    }
    printf("lahar check %s: %s; details in %s\n", ev->ref->name, ev->all_pass ? "PASS" : "FAIL", path);
    fflush(stdout);
    check_plot(outdir);
    return ev->all_pass ? 0 : 1;
}

int lahar_check_evaluate(const lahar_case *c, const char *outdir)
{
    evaluation ev = {0};
    int rc;
    if ((rc = evaluation_reference(c, outdir, &ev)) || (rc = evaluation_load(c, outdir, &ev)) ||
        (rc = evaluation_alloc(outdir, &ev)) || (rc = evaluation_run(c, outdir, &ev)) ||
        (rc = evaluation_metrics(c, outdir, &ev)))
        return rc;
    evaluation_json(c, &ev);
    return evaluation_write(outdir, &ev);
}
